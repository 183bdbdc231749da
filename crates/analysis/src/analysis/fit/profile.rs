//! Profile-likelihood intervals for the observer model's parameters.
//!
//! The 95 % interval of one parameter θ is the set of values whose profile likelihood (the
//! likelihood maximised over the other parameters with θ held fixed) lies within
//! χ²₁(0.95)/2 = 1.92 log-units of the maximum: {θ : 2 (ℓ̂ − ℓₚ(θ)) ≤ 3.84}. Unlike a
//! percentile interval of bootstrap estimates, it does not assume the estimate's sampling
//! distribution is centred on the truth, and it is the same whatever scale the parameter is
//! written on (κ or ln κ, π or logit π), so it keeps its coverage where an estimate is skewed
//! and bounded (κ of a weak prior, π beside it). Where the profile does not fall that far
//! before a bound of the search (κ = 0, λ = 0, λ = [`LAPSE_MAX`]), the bound is the endpoint.
//!
//! Each endpoint is bracketed by steps that double outward from the estimate, then bisected;
//! every profile point is a Nelder–Mead maximisation warm-started from its neighbour's
//! solution. Deterministic.

use super::{nelder_mead, Bin, Structure, BIAS_MAX, KAPPA_MAX, LAPSE_MAX, NONPARAMETRIC_HARMONICS};
use crate::analysis::observer_model::{convexity_bias as logit, ModelParams};

/// The deviance 2 (ℓ̂ − ℓₚ) at the edge of a 95 % interval: the 95th percentile of χ² with one
/// degree of freedom.
pub const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// Bisection steps per endpoint (the bracket shrinks by 2⁻²⁴).
const BISECTIONS: usize = 24;

/// One of the model's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Parameter {
    /// μ, degrees.
    Tilt,
    /// κ.
    Kappa,
    /// π.
    Convexity,
    /// λ.
    Lapse,
}

impl Parameter {
    /// The parameter's value in `p` on the scale its profile is searched on: degrees for μ,
    /// logit π (within the search's bound) for π, κ and λ as they are.
    fn searched(self, p: &ModelParams) -> f64 {
        match self {
            Parameter::Tilt => p.tilt_deg,
            Parameter::Kappa => p.kappa,
            Parameter::Convexity => logit(p.convexity_prior).clamp(-BIAS_MAX, BIAS_MAX),
            Parameter::Lapse => p.lapse,
        }
    }
}

/// The von Mises model's negative log-likelihood as a function of the parameters other than
/// one held fixed.
struct Profile<'a> {
    data: &'a [Bin],
    lapse: Option<f64>,
    which: Parameter,
}

impl Profile<'_> {
    fn structure(&self, lapse: Option<f64>) -> Structure {
        Structure {
            harmonics: &NONPARAMETRIC_HARMONICS[..1],
            free_bias: true,
            lapse,
        }
    }

    /// The free coordinates at `params` (the fixed parameter left out).
    fn free_of(&self, p: &ModelParams) -> Vec<f64> {
        let mu = p.tilt_deg.to_radians();
        let b0 = Parameter::Convexity.searched(p);
        let u = self
            .lapse
            .is_none()
            .then(|| logit((p.lapse / LAPSE_MAX).clamp(1e-12, 1.0 - 1e-12)).clamp(-29.0, 29.0));
        let (h1, h2) = (2.0 * p.kappa * mu.cos(), 2.0 * p.kappa * mu.sin());
        let mut z = match self.which {
            Parameter::Tilt => vec![b0, p.kappa],
            Parameter::Kappa => vec![b0, mu],
            Parameter::Convexity => vec![h1, h2],
            Parameter::Lapse => vec![b0, h1, h2],
        };
        if self.which != Parameter::Lapse {
            z.extend(u);
        }
        z
    }

    /// The negative log-likelihood with the fixed parameter at `value` (degrees for μ, logit π
    /// for π) and the others at `free`; +∞ outside the search's bounds.
    fn objective(&self, value: f64, free: &[f64]) -> f64 {
        let (z, lapse) = match self.which {
            Parameter::Tilt => {
                if free[1] < 0.0 {
                    return f64::INFINITY;
                }
                let mu = value.to_radians();
                let mut z = vec![free[0], 2.0 * free[1] * mu.cos(), 2.0 * free[1] * mu.sin()];
                z.extend_from_slice(&free[2..]);
                (z, self.lapse)
            }
            Parameter::Kappa => {
                let mut z = vec![
                    free[0],
                    2.0 * value * free[1].cos(),
                    2.0 * value * free[1].sin(),
                ];
                z.extend_from_slice(&free[2..]);
                (z, self.lapse)
            }
            Parameter::Convexity => {
                let mut z = vec![value];
                z.extend_from_slice(free);
                (z, self.lapse)
            }
            Parameter::Lapse => (free.to_vec(), Some(value)),
        };
        self.structure(lapse).objective(&z, self.data)
    }

    /// The profile's minimum at `value`, from `start`, with the free coordinates there.
    fn minimise(&self, value: f64, start: &[f64]) -> (Vec<f64>, f64) {
        let f = |z: &[f64]| self.objective(value, z);
        let (z, _) = nelder_mead(&f, start, 0.3, 3000);
        let mut best = nelder_mead(&f, &z, 0.05, 3000);
        // The lapse's coordinate is flat near λ = 0 (logit far below 0), where a simplex cannot
        // climb back out: start again from a lapse of 5 %.
        if self.which != Parameter::Lapse && self.lapse.is_none() {
            let mut s = start.to_vec();
            if let Some(u) = s.last_mut() {
                *u = logit(0.05 / LAPSE_MAX);
            }
            let (z, _) = nelder_mead(&f, &s, 0.3, 3000);
            let again = nelder_mead(&f, &z, 0.05, 3000);
            if again.1 < best.1 {
                best = again;
            }
        }
        best
    }
}

/// The 95 % profile-likelihood interval of `which` for the fit `fitted` of `data` (`lapse`
/// fixes λ when given, as in the fit). μ's interval is in degrees about the estimate (it may
/// run past ±180°); π's and λ's lie within their bounds.
pub(super) fn interval(
    data: &[Bin],
    lapse: Option<f64>,
    fitted: &ModelParams,
    which: Parameter,
) -> [f64; 2] {
    let profile = Profile { data, lapse, which };
    // The parameter on the scale it is searched on, with its bounds.
    let centre = which.searched(fitted);
    let (lo_bound, hi_bound, first_step) = match which {
        Parameter::Tilt => (centre - 180.0, centre + 180.0, 5.0),
        Parameter::Kappa => (0.0, KAPPA_MAX, 0.1_f64.max(0.1 * centre)),
        Parameter::Convexity => (-BIAS_MAX, BIAS_MAX, 0.1),
        Parameter::Lapse => (0.0, LAPSE_MAX, 0.01),
    };
    let start = profile.free_of(fitted);
    let (start, mut best) = profile.minimise(centre, &start);
    let mut endpoint = |direction: f64| -> f64 {
        let bound = if direction < 0.0 { lo_bound } else { hi_bound };
        // Walk out until the deviance passes the threshold or the bound is reached.
        let (mut inside, mut inside_z) = (centre, start.clone());
        let mut step = first_step;
        let mut outside = None;
        loop {
            let v = centre + direction * step;
            let v = if (v - bound) * direction >= 0.0 {
                bound
            } else {
                v
            };
            let (z, nll) = profile.minimise(v, &inside_z);
            // A lower minimum than the fit's: the fit stopped short; measure from this one.
            best = best.min(nll);
            if 2.0 * (nll - best) > CHI2_1_95 {
                outside = Some(v);
                break;
            }
            inside = v;
            inside_z = z;
            if v == bound {
                break;
            }
            step *= 2.0;
        }
        let Some(mut out) = outside else {
            return bound;
        };
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (inside + out);
            let (z, nll) = profile.minimise(mid, &inside_z);
            best = best.min(nll);
            if 2.0 * (nll - best) > CHI2_1_95 {
                out = mid;
            } else {
                inside = mid;
                inside_z = z;
            }
        }
        0.5 * (inside + out)
    };
    let (lo, hi) = (endpoint(-1.0), endpoint(1.0));
    match which {
        Parameter::Convexity => [super::sigmoid(lo), super::sigmoid(hi)],
        _ => [lo, hi],
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{design, interval_truth};
    use super::super::{fit_point, simulate};
    use super::*;

    /// The deviance 2 (ℓ̂ − ℓₚ(v)) found by a many-start search over the other parameters,
    /// independent of the interval's warm-started walk.
    fn deviance(data: &[Bin], fitted: &ModelParams, which: Parameter, v: f64) -> f64 {
        let profile = Profile {
            data,
            lapse: None,
            which,
        };
        let ll_hat = -profile
            .minimise(which.searched(fitted), &profile.free_of(fitted))
            .1;
        let mut best = f64::INFINITY;
        for k in 0..8 {
            let angle = (45.0 * k as f64).to_radians();
            for lapse in [0.01, 0.1] {
                let start = ModelParams {
                    tilt_deg: angle.to_degrees(),
                    kappa: 0.5 + k as f64 * 0.3,
                    convexity_prior: 0.5,
                    lapse,
                };
                best = best.min(profile.minimise(v, &profile.free_of(&start)).1);
            }
        }
        2.0 * (best + ll_hat)
    }

    #[test]
    fn each_endpoint_lies_where_the_profile_deviance_reaches_the_chi2_quantile() {
        let truth = interval_truth();
        let data = simulate(&truth, &design(), 20, 11);
        let fitted = fit_point(&data, None, false).params;
        for (which, value) in [
            (Parameter::Tilt, fitted.tilt_deg),
            (Parameter::Kappa, fitted.kappa),
            (Parameter::Convexity, fitted.convexity_prior),
            (Parameter::Lapse, fitted.lapse),
        ] {
            let [lo, hi] = interval(&data, None, &fitted, which);
            assert!(lo < value && value < hi, "{which:?}: {lo} {value} {hi}");
            for end in [lo, hi] {
                // On the scale the profile is searched on (logit π for π).
                let v = if which == Parameter::Convexity {
                    logit(end)
                } else {
                    end
                };
                if which == Parameter::Lapse && end == 0.0 {
                    // At the bound: the deviance there is still below the quantile.
                    assert!(deviance(&data, &fitted, which, v) <= CHI2_1_95);
                    continue;
                }
                let d = deviance(&data, &fitted, which, v);
                assert!(
                    (d - CHI2_1_95).abs() < 2e-3,
                    "{which:?} at {end}: deviance {d}"
                );
            }
        }
    }

    #[test]
    fn kappa_interval_starts_at_zero_exactly_when_no_prior_is_within_the_quantile() {
        // Answers that do not depend on the rotation: κ̂ is small, and κ = 0 is inside the
        // interval unless the sample happens to lean one way by chance. (With π = 0.5: a
        // flat proportion other than one half is also matched by a steep prior at the
        // convexity bound plus lapses, which leaves κ's upper end far out.)
        let flat = ModelParams {
            tilt_deg: 0.0,
            kappa: 0.0,
            convexity_prior: 0.5,
            lapse: 0.0,
        };
        let mut from_zero = 0;
        for seed in 1..=6 {
            let data = simulate(&flat, &design(), 20, seed);
            let fitted = fit_point(&data, None, false).params;
            let [lo, hi] = interval(&data, None, &fitted, Parameter::Kappa);
            assert!(
                hi > fitted.kappa && hi < 1.5,
                "[{lo}, {hi}] around {}",
                fitted.kappa
            );
            if deviance(&data, &fitted, Parameter::Kappa, 0.0) <= CHI2_1_95 {
                assert_eq!(lo, 0.0, "seed {seed}");
                from_zero += 1;
            } else {
                let d = deviance(&data, &fitted, Parameter::Kappa, lo);
                assert!(
                    (d - CHI2_1_95).abs() < 2e-3,
                    "seed {seed}: deviance {d} at {lo}"
                );
            }
        }
        assert!(from_zero >= 3, "{from_zero} of 6 intervals start at 0");
    }
}
