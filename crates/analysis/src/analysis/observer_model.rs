//! The observer model that `fit observer` estimates, `analyze observer` and `study` predict
//! with, and the browser experiment's pilot mode simulates:
//!
//! P(convex | θ) = λ/2 + (1 − λ) · π·vM(θ; μ, κ) / (π·vM(θ; μ, κ) + (1 − π)·vM(θ + 180°; μ, κ)),
//!
//! with θ the direction toward which the stimulus's bright side faces (tilt convention: 0 = up,
//! +90 = left), vM a von Mises density, μ the prior's mean light tilt, κ its concentration, π
//! the convexity prior and λ the lapse rate (a lapse answers at random).
//!
//! A disc whose bright side faces θ has exactly two interpretations: a bump lit from θ or a
//! dimple lit from θ + 180°. The von Mises normaliser cancels in the ratio, so
//! vM(θ)/vM(θ + 180°) = exp(2κ·cos(θ − μ)) and, before lapses, the log odds of convex are
//! linear in (1, cos θ, sin θ):
//!
//! logit P = logit π + 2κ·cos(θ − μ) = B + 2κ cos μ · cos θ + 2κ sin μ · sin θ,
//!
//! where B = logit π is the convexity bias (the log prior odds of convex) of the image-based
//! observer ([`crate::analysis::observer`]). That observer *is* this model for one disc: its
//! prior over light tilt is vM(μ, κ), its convexity prior is π (as B), its decision adds the
//! lapse λ, and as its image noise σ goes to 0 its likelihood keeps only the two
//! interpretations that render the disc exactly. A general prior over light tilt, log p(t),
//! enters the same way: only its odd part, log p(θ) − log p(θ + 180°), reaches the responses,
//! so the even part of a non-parametric prior cannot be estimated from bump/dimple judgements.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The parameters of the observer model.
///
/// ```
/// use shadelab_analysis::analysis::observer_model::ModelParams;
/// let m = ModelParams { tilt_deg: 26.0, kappa: 2.0, convexity_prior: 0.5, lapse: 0.0 };
/// // Bright side toward the prior's mean: mostly convex; the opposite way: mostly concave.
/// assert!(m.p_convex(26.0) > 0.95);
/// assert!((m.p_convex(26.0) + m.p_convex(206.0) - 1.0).abs() < 1e-12);
/// // A lapse pulls every answer toward ½.
/// let l = ModelParams { lapse: 0.2, ..m };
/// assert!((l.p_convex(26.0) - (0.1 + 0.8 * m.p_convex(26.0))).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModelParams {
    /// μ: the prior's mean light tilt, degrees (0 = above, +90 = left).
    pub tilt_deg: f64,
    /// κ ≥ 0: the prior's concentration (0 = no preferred light direction).
    pub kappa: f64,
    /// π in [0, 1]: the prior probability of convex (0.5 = no preference).
    pub convexity_prior: f64,
    /// λ in [0, 1]: the lapse rate (a lapse answers convex or concave at random).
    pub lapse: f64,
}

impl ModelParams {
    /// Checks every value, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        check_tilt_prior(self.tilt_deg, self.kappa)?;
        if !(0.0..=1.0).contains(&self.convexity_prior) {
            return Err(Error::invalid(format!(
                "convexity prior {} must be a probability in 0..1",
                self.convexity_prior
            )));
        }
        check_lapse(self.lapse)
    }

    /// P(convex | θ) for the bright side facing `theta_deg` (computed from the log odds, so
    /// that large κ neither overflows nor gives NaN).
    pub fn p_convex(&self, theta_deg: f64) -> f64 {
        let b = convexity_bias(self.convexity_prior);
        let odds = 2.0 * self.kappa * (theta_deg - self.tilt_deg).to_radians().cos();
        with_lapse(self.lapse, sigmoid(b + odds))
    }

    /// The von Mises density of the light prior at tilt `t_deg`, per radian.
    pub fn prior_density(&self, t_deg: f64) -> f64 {
        von_mises(t_deg - self.tilt_deg, self.kappa)
    }
}

/// Checks a von Mises prior over light tilt: a finite mean (degrees) and a concentration ≥ 0.
pub fn check_tilt_prior(mean_tilt_deg: f64, kappa: f64) -> Result<()> {
    if !mean_tilt_deg.is_finite() {
        return Err(Error::invalid(format!(
            "prior tilt {mean_tilt_deg} must be a finite number of degrees"
        )));
    }
    if !(kappa.is_finite() && kappa >= 0.0) {
        return Err(Error::invalid(format!(
            "prior kappa {kappa} must be a number ≥ 0"
        )));
    }
    Ok(())
}

/// Checks a lapse rate: a probability in 0..1.
pub fn check_lapse(lapse: f64) -> Result<()> {
    if (0.0..=1.0).contains(&lapse) {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "lapse {lapse} must be a probability in 0..1"
        )))
    }
}

/// The answer of an observer who lapses with probability `lapse` (and then answers at random)
/// and otherwise answers convex with probability `p`: λ/2 + (1 − λ)·p. With λ = 0 it is `p`,
/// bit for bit.
pub fn with_lapse(lapse: f64, p: f64) -> f64 {
    if lapse == 0.0 {
        p
    } else {
        0.5 * lapse + (1.0 - lapse) * p
    }
}

/// The convexity bias B = logit π = ln(π / (1 − π)): the log prior odds of convex (±∞ at 1
/// and 0).
///
/// ```
/// use shadelab_analysis::analysis::observer_model::{convexity_bias, convexity_prior};
/// assert_eq!(convexity_bias(0.5), 0.0);
/// assert!((convexity_prior(convexity_bias(0.8)) - 0.8).abs() < 1e-12);
/// ```
pub fn convexity_bias(prior: f64) -> f64 {
    (prior / (1.0 - prior)).ln()
}

/// The convexity prior π = 1 / (1 + e^−B) of a convexity bias B.
pub fn convexity_prior(bias: f64) -> f64 {
    sigmoid(bias)
}

/// The logistic function 1 / (1 + e^−x), without overflow for any x.
pub fn sigmoid(x: f64) -> f64 {
    if x >= 0.0 {
        1.0 / (1.0 + (-x).exp())
    } else {
        let e = x.exp();
        e / (1.0 + e)
    }
}

/// The von Mises density at angle `d_deg` from its mean, per radian: e^{κ cos d} / (2π I₀(κ)).
pub fn von_mises(d_deg: f64, kappa: f64) -> f64 {
    // e^{κ(cos d − 1)} / (2π e^{−κ} I₀(κ)), stable for large κ.
    (kappa * (d_deg.to_radians().cos() - 1.0)).exp()
        / (std::f64::consts::TAU * bessel_i0_scaled(kappa))
}

/// e^{−x}·I₀(x) for x ≥ 0 (Abramowitz & Stegun 9.8.1–9.8.2; relative error below 2·10⁻⁷).
pub fn bessel_i0_scaled(x: f64) -> f64 {
    let x = x.abs();
    if x < 3.75 {
        let t = (x / 3.75).powi(2);
        let i0 = 1.0
            + t * (3.5156229
                + t * (3.0899424
                    + t * (1.2067492 + t * (0.2659732 + t * (0.0360768 + t * 0.0045813)))));
        i0 * (-x).exp()
    } else {
        let t = 3.75 / x;
        (0.39894228
            + t * (0.01328592
                + t * (0.00225319
                    + t * (-0.00157565
                        + t * (0.00916281
                            + t * (-0.02057706
                                + t * (0.02635537 + t * (-0.01647633 + t * 0.00392377))))))))
            / x.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_formula_matches_its_definition() {
        let m = ModelParams {
            tilt_deg: 26.0,
            kappa: 1.7,
            convexity_prior: 0.7,
            lapse: 0.06,
        };
        for theta in (0..360).step_by(15) {
            let t = theta as f64;
            let (a, b) = (m.prior_density(t), m.prior_density(t + 180.0));
            let direct = 0.03 + 0.94 * 0.7 * a / (0.7 * a + 0.3 * b);
            assert!((m.p_convex(t) - direct).abs() < 1e-12, "{t}");
        }
        // The density integrates to 1 over the circle.
        let sum: f64 = (0..3600)
            .map(|i| m.prior_density(i as f64 / 10.0) * (0.1f64).to_radians())
            .sum();
        assert!((sum - 1.0).abs() < 1e-6, "{sum}");
        // Huge κ: no overflow, a step at ±90° from μ.
        let sharp = ModelParams {
            kappa: 1e6,
            lapse: 0.0,
            ..m
        };
        assert_eq!(sharp.p_convex(26.0), 1.0);
        assert_eq!(sharp.p_convex(206.0), 0.0);
        assert!(sharp.prior_density(26.0).is_finite());
        assert!(ModelParams { lapse: 1.5, ..m }.validate().is_err());
        assert!(ModelParams {
            convexity_prior: -0.1,
            ..m
        }
        .validate()
        .is_err());
    }
}
