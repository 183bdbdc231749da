//! Light directions: unit vectors toward a distant light, and the tilt/slant angles of the
//! vision-science literature.
//!
//! Tilt is the image-plane direction the light comes from, in degrees: 0 = from above, +90 = from
//! the left (counter-clockwise), 180 = from below, −90 = from the right. Slant is the angle from
//! the viewing direction (0 = frontal). The unit vector is
//! s = (−sin(tilt)·sin(slant), cos(tilt)·sin(slant), cos(slant)).

use crate::error::{Error, Result};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// The slant used by the named lights (`above`, `left`, …) when none is given.
pub const DEFAULT_NAMED_SLANT_DEG: f64 = 45.0;

/// The named lights and their tilts in degrees.
pub const NAMED_LIGHTS: &[(&str, f64)] = &[
    ("above", 0.0),
    ("above-left", 45.0),
    ("left", 90.0),
    ("below", 180.0),
    ("right", -90.0),
    ("above-right", -45.0),
];

/// A distant light: a unit vector from the surface toward the light, never below the horizon
/// (z ≥ 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "[f64; 3]", into = "[f64; 3]")]
pub struct Light {
    dir: Vector3<f64>,
}

impl Light {
    /// The frontal light (0, 0, 1), from the viewer's direction.
    pub const FRONT: Light = Light {
        dir: Vector3::new(0.0, 0.0, 1.0),
    };

    /// A light toward `(x, y, z)`, normalised. Fails for a zero, non-finite or below-horizon
    /// (z < 0) direction.
    pub fn from_vector(x: f64, y: f64, z: f64) -> Result<Self> {
        // Scaled by its largest component first, so that a finite vector as long as 1e308 has
        // a direction too (its norm would overflow).
        let largest = x.abs().max(y.abs()).max(z.abs());
        let v = Vector3::new(x, y, z) / largest;
        let norm = v.norm();
        if !(largest.is_finite() && largest > 0.0 && norm.is_finite()) {
            return Err(Error::invalid(format!(
                "light ({x}, {y}, {z}) is not a direction (it must be a non-zero finite vector)"
            )));
        }
        if z < 0.0 {
            return Err(Error::invalid(format!(
                "light ({x}, {y}, {z}) is below the horizon (z must be ≥ 0: the light must face the viewer's side)"
            )));
        }
        Ok(Light { dir: v / norm })
    }

    /// A light from `tilt_deg` and `slant_deg` (0 ≤ slant ≤ 90).
    pub fn from_tilt_slant(tilt_deg: f64, slant_deg: f64) -> Result<Self> {
        if !tilt_deg.is_finite() || !slant_deg.is_finite() {
            return Err(Error::invalid(
                "light tilt and slant must be finite numbers",
            ));
        }
        if !(0.0..=90.0).contains(&slant_deg) {
            return Err(Error::invalid(format!(
                "light slant {slant_deg}° is outside 0..90 (90 is grazing; more is below the horizon)"
            )));
        }
        let (sin_t, cos_t) = sin_cos_deg(tilt_deg);
        let (sin_s, cos_s) = sin_cos_deg(slant_deg);
        Light::from_vector(-sin_t * sin_s, cos_t * sin_s, cos_s.max(0.0))
    }

    /// The unit vector toward the light.
    pub fn direction(&self) -> Vector3<f64> {
        self.dir
    }

    /// Tilt in degrees, in (−180, 180]; 0 for the frontal light, whose tilt is undefined.
    pub fn tilt_deg(&self) -> f64 {
        if self.dir.x.hypot(self.dir.y) < 1e-12 {
            return 0.0;
        }
        // `+ 0.0` turns the −0 of a light straight above (x = −0) into 0.
        let t = (-self.dir.x).atan2(self.dir.y).to_degrees() + 0.0;
        if t <= -180.0 {
            t + 360.0
        } else {
            t
        }
    }

    /// Slant in degrees, 0..90.
    pub fn slant_deg(&self) -> f64 {
        self.dir.z.clamp(-1.0, 1.0).acos().to_degrees()
    }

    /// The light with its image-plane part turned by 180° (tilt + 180°, same slant): the light
    /// under which the depth-negated surface gives the same image.
    pub fn opposite_tilt(&self) -> Light {
        Light {
            dir: Vector3::new(-self.dir.x, -self.dir.y, self.dir.z),
        }
    }
}

impl TryFrom<[f64; 3]> for Light {
    type Error = Error;
    fn try_from(v: [f64; 3]) -> Result<Self> {
        Light::from_vector(v[0], v[1], v[2])
    }
}

impl From<Light> for [f64; 3] {
    fn from(l: Light) -> Self {
        [l.dir.x, l.dir.y, l.dir.z]
    }
}

impl fmt::Display for Light {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "tilt={},slant={}",
            round6(self.tilt_deg()),
            round6(self.slant_deg())
        )
    }
}

/// sin and cos of an angle in degrees, reduced to the first quadrant and turned by whole
/// quadrants exactly: multiples of 90° are exact, and angles 180° apart give exactly negated
/// values, so lights 180° apart in tilt are exact mirror images (which the convex/concave
/// ambiguity relies on: the depth-negated surface under the turned light renders bit for bit).
pub fn sin_cos_deg(degrees: f64) -> (f64, f64) {
    let r = degrees.rem_euclid(360.0);
    let quadrant = (r / 90.0).floor();
    let (s, c) = (r - 90.0 * quadrant).to_radians().sin_cos();
    // A tiny negative angle wraps to 360 − ε, which rounds to exactly 360: quadrant 4, which is
    // quadrant 0 (it once turned a tilt of −1e-17° into 270°).
    match quadrant as i64 % 4 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

fn round6(v: f64) -> f64 {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

impl FromStr for Light {
    type Err = Error;

    /// Parses `x,y,z`, `tilt=T,slant=S` (either may be omitted: tilt 0, slant 45), or a name
    /// (`front`, `above`, `below`, `left`, `right`, `above-left`, `above-right`, optionally
    /// followed by `,slant=S`).
    fn from_str(text: &str) -> Result<Self> {
        let text = text.trim();
        let bad = || {
            Error::invalid(format!(
                "light '{text}' is not a direction: use x,y,z or tilt=T,slant=S or one of front, {}",
                NAMED_LIGHTS.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", ")
            ))
        };
        let parts: Vec<&str> = text.split(',').map(str::trim).collect();
        if parts.len() == 3 && parts.iter().all(|p| !p.contains('=')) {
            let v: Vec<f64> = parts
                .iter()
                .map(|p| p.parse::<f64>().map_err(|_| bad()))
                .collect::<Result<_>>()?;
            return Light::from_vector(v[0], v[1], v[2]);
        }
        let mut tilt = None;
        let mut slant = None;
        let mut named = false;
        for (i, part) in parts.iter().enumerate() {
            if let Some((key, value)) = part.split_once('=') {
                let value: f64 = value.trim().parse().map_err(|_| bad())?;
                match key.trim() {
                    "tilt" if tilt.is_none() => tilt = Some(value),
                    "slant" if slant.is_none() => slant = Some(value),
                    _ => return Err(bad()),
                }
            } else if i == 0 {
                if *part == "front" {
                    named = true;
                    tilt = Some(0.0);
                    slant = Some(0.0);
                } else if let Some((_, t)) = NAMED_LIGHTS.iter().find(|(n, _)| n == part) {
                    named = true;
                    tilt = Some(*t);
                } else {
                    return Err(bad());
                }
            } else {
                return Err(bad());
            }
        }
        if !named && tilt.is_none() && slant.is_none() {
            return Err(bad());
        }
        Light::from_tilt_slant(
            tilt.unwrap_or(0.0),
            slant.unwrap_or(DEFAULT_NAMED_SLANT_DEG),
        )
    }
}

/// A light strictly in front of the surface (z > 0): the only light shape from shading can
/// use, since a grazing or rear light leaves the shading without an answer. It is made once,
/// where a light for a solve is parsed, given or estimated ([`FrontLight::new`], `FromStr`);
/// what takes one checks nothing again. Everything of a [`Light`] is there by `Deref`.
///
/// ```
/// use shadelab::{FrontLight, Light};
/// let light: FrontLight = "tilt=30,slant=40".parse()?;
/// assert_eq!(light.tilt_deg().round(), 30.0);
/// let grazing: Light = "above,slant=90".parse()?; // renders, but cannot be solved under
/// assert!(FrontLight::new(grazing).is_err());
/// assert!("above,slant=90".parse::<FrontLight>().is_err());
/// # Ok::<(), shadelab::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Light", into = "Light")]
pub struct FrontLight(Light);

impl FrontLight {
    /// The frontal light (0, 0, 1).
    pub const FRONT: FrontLight = FrontLight(Light::FRONT);

    /// `light`, which must be strictly in front of the surface (z > 0).
    pub fn new(light: Light) -> Result<FrontLight> {
        let d = light.direction();
        if d.z > 0.0 {
            Ok(FrontLight(light))
        } else {
            Err(Error::invalid(format!(
                "the light ({:.4}, {:.4}, {:.4}) must have z > 0, a slant below 90° (a grazing or \
                 rear light leaves the shading without an answer)",
                d.x, d.y, d.z
            )))
        }
    }

    /// The light.
    pub fn light(self) -> Light {
        self.0
    }
}

impl std::ops::Deref for FrontLight {
    type Target = Light;
    fn deref(&self) -> &Light {
        &self.0
    }
}

impl TryFrom<Light> for FrontLight {
    type Error = Error;
    fn try_from(light: Light) -> Result<FrontLight> {
        FrontLight::new(light)
    }
}

impl From<FrontLight> for Light {
    fn from(light: FrontLight) -> Light {
        light.0
    }
}

impl FromStr for FrontLight {
    type Err = Error;

    /// A [`Light`]'s syntax, for a light in front of the surface.
    fn from_str(text: &str) -> Result<FrontLight> {
        FrontLight::new(text.parse()?)
    }
}

impl fmt::Display for FrontLight {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tilt_conventions() {
        let above = Light::from_tilt_slant(0.0, 90.0).unwrap().direction();
        assert!((above - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        let left = Light::from_tilt_slant(90.0, 90.0).unwrap().direction();
        assert!((left - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12);
        let right = Light::from_tilt_slant(-90.0, 30.0).unwrap();
        assert!(right.direction().x > 0.0);
        assert!((right.tilt_deg() + 90.0).abs() < 1e-9);
        assert!((right.slant_deg() - 30.0).abs() < 1e-9);
        // A light straight above with x = −0 reads tilt 0, never "-0" in a report.
        let above = Light::from_vector(-0.0, 0.7, 0.7).unwrap();
        assert!(above.tilt_deg().is_sign_positive());
        assert_eq!(format!("{:.1}", above.tilt_deg()), "0.0");
    }

    #[test]
    fn quadrant_angles_are_exact_and_opposite_tilts_mirror() {
        assert_eq!(sin_cos_deg(90.0), (1.0, 0.0));
        assert_eq!(sin_cos_deg(-90.0), (-1.0, 0.0));
        assert_eq!(sin_cos_deg(180.0), (0.0, -1.0));
        assert!((sin_cos_deg(123.0).0 - 123f64.to_radians().sin()).abs() < 1e-15);
        // −1e-17 wraps to 360 − 1e-17, which is exactly 360.0 in f64: still the top.
        for tiny in [-1e-17, -1.1134687610987288e-17, -1e-14, -0.0] {
            let (s, c) = sin_cos_deg(tiny);
            assert!(s.abs() < 1e-15 && c == 1.0, "{tiny}: ({s}, {c})");
        }
        assert_eq!(sin_cos_deg(360.0), (0.0, 1.0));
        for tilt in [0.0, 26.0, 45.0, 90.0, 137.5] {
            let a = Light::from_tilt_slant(tilt, 45.0).unwrap().direction();
            let b = Light::from_tilt_slant(tilt + 180.0, 45.0)
                .unwrap()
                .direction();
            assert_eq!((a.x, a.y, a.z), (-b.x, -b.y, b.z), "tilt {tilt}");
        }
        let above = Light::from_tilt_slant(0.0, 45.0).unwrap().direction();
        assert_eq!(above.x, 0.0);
    }

    #[test]
    fn parses_all_forms() {
        let a: Light = "above".parse().unwrap();
        assert!((a.slant_deg() - 45.0).abs() < 1e-9 && a.tilt_deg().abs() < 1e-9);
        let b: Light = "left,slant=30".parse().unwrap();
        assert!((b.tilt_deg() - 90.0).abs() < 1e-9 && (b.slant_deg() - 30.0).abs() < 1e-9);
        let c: Light = "1,0,1".parse().unwrap();
        assert!((c.tilt_deg() + 90.0).abs() < 1e-9 && (c.slant_deg() - 45.0).abs() < 1e-9);
        let d: Light = "tilt=180,slant=10".parse().unwrap();
        assert!((d.tilt_deg() - 180.0).abs() < 1e-9);
        assert_eq!("front".parse::<Light>().unwrap(), Light::FRONT);
        for bad in [
            "",
            "0,0,0",
            "0,0,-1",
            "up",
            "1,2",
            "tilt=x",
            "slant=120",
            "nan,0,1",
        ] {
            assert!(bad.parse::<Light>().is_err(), "{bad} should fail");
        }
    }

    #[test]
    fn display_round_trips() {
        let l = Light::from_tilt_slant(-135.0, 60.0).unwrap();
        let back: Light = l.to_string().parse().unwrap();
        assert!((back.direction() - l.direction()).norm() < 1e-9);
    }
}
