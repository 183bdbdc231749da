//! Perception analyses: the shape-from-shading engine run as an observer would run it.
//!
//! One shaded picture is consistent with many surfaces; which one is seen depends on what is
//! assumed about the light. These modules make that measurable:
//!
//! - [`convexity`]: the picture's tokens (discs, strips, a face) and a signed convexity of a
//!   recovered depth map on each, exactly negated when the depth is negated.
//! - [`interpretation`]: one interpretation, the solve under one assumed light, with its
//!   irradiance residual e_R, smoothness e_S and per-token convexity.
//! - [`prior_sweep`]: interpretations over a range of assumed light tilts, and the tilts where
//!   each token flips between convex and concave.
//! - [`observer`]: a Bayesian observer, a von Mises prior over the light's tilt, an optional
//!   convexity prior and a likelihood from the residuals, giving P(convex) against the
//!   picture's rotation.
//! - [`observer_model`]: the observer model P(convex | θ) that [`fit`] estimates from
//!   bump/dimple responses (maximum likelihood, bootstrap intervals) and the observer predicts
//!   with.
//! - [`binding`]: one light for the whole scene versus a light per token (Ramachandran's arrays).
//! - [`outline`]: where curvature concentrates in shapes recovered inside an outline (the
//!   boundary-strips demonstration).
//! - [`picture`]: a picture with its tokens and the lighting to assume for it.
//! - [`rotation`]: quarter-turn rotation of grids, for checking that rotating a picture is the
//!   same as turning the assumed light.
//! - [`study`]: grids of stimuli × parameters × priors, run in shards and merged.
//!
//! Their figures are drawn by [`crate::plot`].
//!
//! The exact ambiguity behind all of them: a Lambertian image under light s = (s_x, s_y, s_z) is
//! reproduced exactly by the depth-negated surface, whose normals are (−n_x, −n_y, n_z), under
//! (−s_x, −s_y, s_z), the light with its tilt turned by 180°. Residuals cannot tell the two
//! apart; only a prior can.

pub mod binding;
pub mod convexity;
pub mod fit;
pub mod interpretation;
pub mod observer;
pub mod observer_model;
pub mod outline;
pub mod picture;
pub mod prior_sweep;
pub mod rotation;
pub mod study;

pub use convexity::Token;
pub use interpretation::{Interpretation, Interpreter, Lighting, Scene, TokenReading};
pub use observer::{observe, LightPrior, ObserverOptions, Percept};
pub use picture::{Domain, TokenPicture};
pub use prior_sweep::{sweep, Sweep};

use crate::error::{Error, Result};

/// The most angles a range may expand to.
pub const MAX_ANGLES: usize = 100_000;

/// Parses a list of angles in degrees: `START:STOP:STEP` (STOP excluded, as in Python's
/// `range`: `0:360:15` is 0, 15, …, 345), a comma-separated list (`0,90,180`), or one number.
/// `what` names the option in errors. Fails on an empty range, a step that is not positive,
/// anything not a finite number, or more than [`MAX_ANGLES`] angles.
pub fn parse_angles(text: &str, what: &str) -> Result<Vec<f64>> {
    let text = text.trim();
    let number = |s: &str| -> Result<f64> {
        let v: f64 = s.trim().parse().map_err(|_| {
            Error::invalid(format!(
                "{what} '{text}': '{}' is not a number (give START:STOP:STEP, e.g. 0:360:15, or a comma-separated list)",
                s.trim()
            ))
        })?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::invalid(format!(
                "{what} '{text}': '{}' is not a finite number",
                s.trim()
            )))
        }
    };
    if text.contains(':') {
        let parts: Vec<&str> = text.split(':').collect();
        if parts.len() != 3 {
            return Err(Error::invalid(format!(
                "{what} '{text}' must be START:STOP:STEP, e.g. 0:360:15"
            )));
        }
        let (start, stop, step) = (number(parts[0])?, number(parts[1])?, number(parts[2])?);
        if step <= 0.0 {
            return Err(Error::invalid(format!(
                "{what} '{text}': the step {step} must be positive"
            )));
        }
        // Each angle is start + k·step (no accumulated rounding); a hair below STOP is STOP.
        let count = ((stop - start) / step - 1e-9).ceil();
        if count < 1.0 {
            return Err(Error::invalid(format!(
                "{what} '{text}' is empty: STOP must be above START"
            )));
        }
        if count > MAX_ANGLES as f64 {
            return Err(Error::invalid(format!(
                "{what} '{text}' gives {count} angles; at most {MAX_ANGLES}"
            )));
        }
        return Ok((0..count as usize)
            .map(|k| start + k as f64 * step)
            .collect());
    }
    if text.is_empty() {
        return Err(Error::invalid(format!(
            "{what} is empty: give START:STOP:STEP, e.g. 0:360:15, or a comma-separated list"
        )));
    }
    let angles = text.split(',').map(number).collect::<Result<Vec<f64>>>()?;
    if angles.len() > MAX_ANGLES {
        return Err(Error::invalid(format!(
            "{what} gives {} angles; at most {MAX_ANGLES}",
            angles.len()
        )));
    }
    Ok(angles)
}

/// `angle` in degrees wrapped into [0, 360).
pub fn wrap_360(angle: f64) -> f64 {
    let a = angle.rem_euclid(360.0);
    // rem_euclid can return 360 for a tiny negative input.
    if a >= 360.0 {
        0.0
    } else {
        a
    }
}

/// `angle` in degrees wrapped into (−180, 180].
pub fn wrap_180(angle: f64) -> f64 {
    let a = wrap_360(angle);
    if a > 180.0 {
        a - 360.0
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_lists_and_single_angles() {
        assert_eq!(
            parse_angles("0:360:90", "--tilts").unwrap(),
            [0.0, 90.0, 180.0, 270.0]
        );
        assert_eq!(parse_angles("0:1:0.25", "x").unwrap().len(), 4);
        assert_eq!(parse_angles("-90:91:90", "x").unwrap(), [-90.0, 0.0, 90.0]);
        assert_eq!(
            parse_angles(" 10, 20 ,30", "x").unwrap(),
            [10.0, 20.0, 30.0]
        );
        assert_eq!(parse_angles("45", "x").unwrap(), [45.0]);
        // 0.1 steps must not lose the last angle to rounding, nor gain STOP.
        let v = parse_angles("0:1:0.1", "x").unwrap();
        assert_eq!(v.len(), 10);
        assert!((v[9] - 0.9).abs() < 1e-12);
    }

    #[test]
    fn bad_ranges_name_the_option() {
        for bad in [
            "0:0:15", "10:0:15", "0:360:0", "0:360:-5", "a:b:c", "0:360", "", "1,x", "nan",
        ] {
            let e = parse_angles(bad, "--tilts").unwrap_err().to_string();
            assert!(e.contains("--tilts"), "{bad}: {e}");
            assert!(!e.contains('\n'));
        }
        assert!(parse_angles("0:1e9:1", "--tilts").is_err());
    }

    #[test]
    fn wrapping() {
        assert_eq!(wrap_360(-90.0), 270.0);
        assert_eq!(wrap_360(720.0), 0.0);
        assert_eq!(wrap_180(270.0), -90.0);
        assert_eq!(wrap_180(180.0), 180.0);
        assert_eq!(wrap_180(-180.0), 180.0);
    }
}
