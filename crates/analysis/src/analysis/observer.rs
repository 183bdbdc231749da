//! A Bayesian observer over light tilt and shape.
//!
//! The hypotheses are the interpretations of a prior sweep: under assumed tilt t the engine
//! recovers one surface, with irradiance residual e_R(t) and a convexity c_k(t) for each token
//! k. The observer weighs them by
//!
//! - a von Mises prior over the light's tilt, p(t) ∝ exp(κ·cos(t − μ)), by default centred
//!   26° to the left of vertical (μ = +26°; tilt +90° is from the left), the average preference
//!   Mamassian & Goutcher (2001) measured; κ sets how firmly light is assumed to come from
//!   there;
//! - an optional convexity prior: each token read as convex multiplies the weight by e^B
//!   (B = `convexity_bias`, the log prior odds of convex over concave; 0 = none; B > 0 is
//!   the preference for convex, familiar shapes that makes a hollow mask look convex);
//! - a likelihood from the residual: exp(−(e_R(t) − min e_R) / (2σ²)), as for Gaussian image
//!   noise of standard deviation σ (`noise`, in luminance units) on every pixel.
//!
//! One scene, one light: the likelihood is the residual of the whole solve, and the posterior
//! over t gives each token's P(convex) = Σ_t post(t)·[c_k(t) > 0] (½ where c_k(t) is 0). The
//! answer adds a lapse λ (`lapse`): with probability λ the observer answers at random, so the
//! reported P(convex) is λ/2 + (1 − λ)·Σ_t post(t)·[c_k(t) > 0].
//!
//! **One model family.** This is the observer model of [`super::observer_model`] computed
//! from the picture: for one disc whose bright side faces θ, the two interpretations that
//! render it exactly are a bump lit from θ and a dimple lit from θ + 180°, and as σ → 0 the
//! likelihood keeps only those two, so P(convex) tends to
//! λ/2 + (1 − λ)·π·vM(θ; μ, κ)/(π·vM(θ; μ, κ) + (1 − π)·vM(θ + 180°; μ, κ)) with π = e^B/(1 + e^B):
//! the formula `fit observer` estimates. A fit's (μ, κ, π, λ) therefore give this observer's
//! prior directly ([`ObserverOptions::from_model`]); a finite σ also counts the interpretations
//! near those two, which matters for pictures with more than one token or no exact
//! interpretation.
//!
//! Rotating the picture by θ (counter-clockwise) turns every interpretation with it: the picture
//! turned by θ under tilt t gives the turned solution of the upright picture under t − θ, with
//! the same residual and, since the token turns too, the same convexity. So one sweep of the
//! upright picture serves every rotation: the hypothesis t of the turned picture is the
//! hypothesis t − θ of the sweep, and only the prior moves. This needs tilts that cover the
//! circle in equal steps, so that the sum over t is a fair integral.

use super::convexity::CONVEXITY_ZERO;
use super::observer_model::{
    check_lapse, check_tilt_prior, convexity_bias, with_lapse, ModelParams,
};
use super::prior_sweep::Sweep;
use crate::error::{Error, Result};
use crate::io::csv_field;
use crate::plot::circle_step;
use crate::plot::{span, LinePlot, Marker, Series};
use serde::Serialize;

/// The default prior tilt: 26° to the left of vertical, the average Mamassian & Goutcher
/// (2001, *Cognition* 81:B1) measured. Other published values differ with the task (McManus,
/// Buckman & Woolley 2004: 0.5° right for a single bubble, 14° left in a 16-bubble pop-out,
/// 9° combined); docs/priors.md tabulates them.
pub const DEFAULT_PRIOR_TILT_DEG: f64 = 26.0;

/// The default concentration κ of the tilt prior (a circular standard deviation of about 49°).
pub const DEFAULT_PRIOR_KAPPA: f64 = 2.0;

/// The default image noise σ of the likelihood, in luminance units.
pub const DEFAULT_NOISE: f64 = 0.05;

/// The largest image noise σ accepted: the whole luminance range.
pub const MAX_NOISE: f64 = 1.0;

/// The observer's prior.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LightPrior {
    /// Mean μ of the tilt prior, degrees (0 = above, +90 = left).
    pub mean_tilt_deg: f64,
    /// Concentration κ ≥ 0 of the tilt prior (0 = no preference).
    pub kappa: f64,
    /// Log prior odds B of convex over concave, per token (0 = no preference).
    pub convexity_bias: f64,
}

impl Default for LightPrior {
    fn default() -> Self {
        LightPrior {
            mean_tilt_deg: DEFAULT_PRIOR_TILT_DEG,
            kappa: DEFAULT_PRIOR_KAPPA,
            convexity_bias: 0.0,
        }
    }
}

/// Everything the observer assumes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ObserverOptions {
    /// The prior.
    pub prior: LightPrior,
    /// Image noise σ of the likelihood (> 0), luminance units.
    pub noise: f64,
    /// The lapse rate λ in 0..1: how often the observer answers at random (0 = never).
    pub lapse: f64,
}

impl Default for ObserverOptions {
    fn default() -> Self {
        ObserverOptions {
            prior: LightPrior::default(),
            noise: DEFAULT_NOISE,
            lapse: 0.0,
        }
    }
}

impl ObserverOptions {
    /// The observer whose prior and lapse are the observer model's `model` (a fit's
    /// estimates): tilt prior vM(μ, κ), convexity bias B = logit π, lapse λ; with image noise
    /// `noise`. Fails on a convexity prior of exactly 0 or 1 (an infinite bias).
    ///
    /// ```
    /// use shadelab_analysis::analysis::observer::ObserverOptions;
    /// use shadelab_analysis::analysis::observer_model::ModelParams;
    /// let m = ModelParams { tilt_deg: 26.0, kappa: 1.5, convexity_prior: 0.75, lapse: 0.04 };
    /// let o = ObserverOptions::from_model(&m, 0.01).unwrap();
    /// assert_eq!(o.prior.mean_tilt_deg, 26.0);
    /// assert!((o.prior.convexity_bias - 3f64.ln()).abs() < 1e-12);
    /// assert_eq!(o.lapse, 0.04);
    /// ```
    pub fn from_model(model: &ModelParams, noise: f64) -> Result<ObserverOptions> {
        model.validate()?;
        let options = ObserverOptions {
            prior: LightPrior {
                mean_tilt_deg: model.tilt_deg,
                kappa: model.kappa,
                convexity_bias: convexity_bias(model.convexity_prior),
            },
            noise,
            lapse: model.lapse,
        };
        options.validate()?;
        Ok(options)
    }

    /// Checks every value, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        let p = &self.prior;
        check_tilt_prior(p.mean_tilt_deg, p.kappa)?;
        if !p.convexity_bias.is_finite() {
            return Err(Error::invalid(format!(
                "convexity bias {} must be a finite number",
                p.convexity_bias
            )));
        }
        if !(self.noise > 0.0 && self.noise <= MAX_NOISE) {
            return Err(Error::invalid(format!(
                "noise {:e} is outside 0..{MAX_NOISE} (σ in luminance units, which run 0..1)",
                self.noise
            )));
        }
        check_lapse(self.lapse)
    }
}

/// What the observer concludes for one rotation of the picture.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Percept {
    /// The picture's rotation, degrees counter-clockwise.
    pub rotation_deg: f64,
    /// P(convex) for each token, in the sweep's token order.
    pub p_convex: Vec<f64>,
    /// The tilt of the most probable light, in the turned picture's frame, in [0, 360).
    pub map_tilt_deg: f64,
    /// The posterior probability that the light comes from the upper half (|tilt| < 90°).
    pub p_light_above: f64,
}

/// The posterior over the sweep's interpretations for the picture turned by `rotation_deg`:
/// one normalised weight per interpretation, in sweep order.
pub fn posterior(sweep: &Sweep, options: &ObserverOptions, rotation_deg: f64) -> Result<Vec<f64>> {
    options.validate()?;
    if !rotation_deg.is_finite() {
        return Err(Error::invalid(format!(
            "rotation {rotation_deg} is not a finite number"
        )));
    }
    check_circle(&sweep.tilts())?;
    let p = &options.prior;
    let e_min = sweep
        .interpretations
        .iter()
        .map(|i| i.surface_residual)
        .fold(f64::INFINITY, f64::min);
    let two_var = 2.0 * options.noise * options.noise;
    let log_weights: Vec<f64> = sweep
        .interpretations
        .iter()
        .map(|i| {
            // The turned picture's light for this hypothesis is at tilt + rotation.
            let t = (i.tilt_deg + rotation_deg - p.mean_tilt_deg).to_radians();
            let convex = i
                .tokens
                .iter()
                .map(|r| p.convexity_bias * verdict(r.convexity))
                .sum::<f64>();
            // The residual's excess over the best, in units of 2σ²: 0 for the best
            // interpretation even when 2σ² underflows to 0 (a tiny σ keeps only the best).
            let excess = i.surface_residual - e_min;
            let misfit = if excess > 0.0 { excess / two_var } else { 0.0 };
            p.kappa * t.cos() - misfit + convex
        })
        .collect();
    let top = log_weights
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let weights: Vec<f64> = log_weights.iter().map(|l| (l - top).exp()).collect();
    let total: f64 = weights.iter().sum();
    Ok(weights.iter().map(|w| w / total).collect())
}

/// Checks that `tilts` cover the circle in equal steps, as the observer needs.
///
/// ```
/// use shadelab_analysis::analysis::observer::check_circle;
/// assert!(check_circle(&[0.0, 90.0, 180.0, 270.0]).is_ok());
/// assert!(check_circle(&[0.0, 90.0, 180.0]).is_err());
/// ```
pub fn check_circle(tilts: &[f64]) -> Result<()> {
    if circle_step(tilts).is_none() {
        return Err(Error::invalid(format!(
            "the observer needs assumed tilts that cover the circle in equal steps (e.g. 0:360:5); got {} tilts from {} to {}",
            tilts.len(),
            tilts.first().copied().unwrap_or(f64::NAN),
            tilts.last().copied().unwrap_or(f64::NAN)
        )));
    }
    Ok(())
}

/// Parses concentrations κ of the tilt prior: one number ≥ 0 or a comma-separated list.
///
/// ```
/// use shadelab_analysis::analysis::observer::parse_kappas;
/// assert_eq!(parse_kappas("0, 2").unwrap(), [0.0, 2.0]);
/// assert!(parse_kappas("-1").is_err());
/// assert!(parse_kappas("nan").is_err());
/// ```
pub fn parse_kappas(text: &str) -> Result<Vec<f64>> {
    let bad = || {
        Error::invalid(format!(
            "prior kappa '{text}' must be a number ≥ 0 or a comma-separated list of them"
        ))
    };
    let kappas = text
        .split(',')
        .map(|k| k.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<Vec<_>>>()?;
    if kappas.iter().any(|k| !(k.is_finite() && *k >= 0.0)) {
        return Err(bad());
    }
    Ok(kappas)
}

/// The percepts under one set of observer options, over the rotations; serialised as the
/// prior's κ and the percepts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Curve {
    /// The observer's options.
    #[serde(rename = "prior_kappa", serialize_with = "kappa_of")]
    pub options: ObserverOptions,
    /// One percept per rotation.
    pub percepts: Vec<Percept>,
}

fn kappa_of<S: serde::Serializer>(o: &ObserverOptions, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(o.prior.kappa)
}

/// One row per curve (prior κ), rotation and token: P(convex), the most probable light tilt
/// and P(light from above).
pub fn curves_csv(sweep: &Sweep, curves: &[Curve]) -> String {
    let mut csv =
        String::from("prior_kappa,rotation_deg,token,label,p_convex,map_tilt_deg,p_light_above\n");
    for c in curves {
        for p in &c.percepts {
            for (k, v) in p.p_convex.iter().enumerate() {
                let (label, name) = &sweep.tokens[k];
                csv.push_str(&format!(
                    "{},{},{},{label},{v},{},{}\n",
                    c.options.prior.kappa,
                    p.rotation_deg,
                    csv_field(name),
                    p.map_tilt_deg,
                    p.p_light_above
                ));
            }
        }
    }
    csv
}

/// P(convex) against rotation, one curve per token (and per κ when there are several), the
/// prior's mean tilt marked. The curves share the prior's mean tilt and convexity bias (the
/// first curve's are named in the title). Fails on no curves.
pub fn p_convex_plot(sweep: &Sweep, curves: &[Curve]) -> Result<LinePlot> {
    let first = curves
        .first()
        .ok_or_else(|| Error::invalid("no observer curves to plot"))?;
    let rs: Vec<f64> = first.percepts.iter().map(|p| p.rotation_deg).collect();
    let (lo, hi) = span(&rs);
    let prior = first.options.prior;
    let kappa_text = format!(
        "κ = {}",
        curves
            .iter()
            .map(|c| c.options.prior.kappa.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut plot = LinePlot::new(
        &format!(
            "P(convex) against rotation (prior tilt {}°, {kappa_text}, convexity bias {})",
            prior.mean_tilt_deg, prior.convexity_bias
        ),
        "rotation of the picture (°, counter-clockwise)",
        "P(convex) (probability)",
        (lo, hi),
    );
    plot.y_range = Some((-0.02, 1.02));
    plot.reference_y = Some(0.5);
    let mean = prior.mean_tilt_deg;
    if mean >= lo && mean <= hi {
        plot.markers.push(Marker {
            x: mean,
            label: format!("prior {mean}°"),
        });
    }
    for c in curves {
        for (k, (_, name)) in sweep.tokens.iter().enumerate() {
            plot.series.push(Series {
                name: if curves.len() == 1 {
                    name.clone()
                } else {
                    format!("{name}, κ = {}", c.options.prior.kappa)
                },
                points: c
                    .percepts
                    .iter()
                    .map(|p| (p.rotation_deg, p.p_convex[k]))
                    .collect(),
            });
        }
    }
    if plot.close_circle() {
        let (lo, hi) = plot.x_range;
        plot.markers.retain(|m| m.x >= lo && m.x <= hi);
    }
    Ok(plot)
}

/// 1 for convex, 0 for concave, ½ for no verdict.
fn verdict(convexity: f64) -> f64 {
    if convexity.abs() <= CONVEXITY_ZERO {
        0.5
    } else if convexity > 0.0 {
        1.0
    } else {
        0.0
    }
}

/// The observer's percept of the picture turned by each of `rotations` (degrees,
/// counter-clockwise), from one sweep of the upright picture.
pub fn observe(
    sweep: &Sweep,
    options: &ObserverOptions,
    rotations: &[f64],
) -> Result<Vec<Percept>> {
    rotations
        .iter()
        .map(|&rotation| {
            let post = posterior(sweep, options, rotation)?;
            let p_convex = (0..sweep.tokens.len())
                .map(|k| {
                    let p = sweep
                        .interpretations
                        .iter()
                        .zip(&post)
                        .map(|(i, w)| w * verdict(i.tokens[k].convexity))
                        .sum();
                    with_lapse(options.lapse, p)
                })
                .collect();
            let best = post
                .iter()
                .enumerate()
                .fold(0, |b, (i, &w)| if w > post[b] { i } else { b });
            let map_tilt_deg = super::wrap_360(sweep.interpretations[best].tilt_deg + rotation);
            let p_light_above = sweep
                .interpretations
                .iter()
                .zip(&post)
                .filter(|(i, _)| (i.tilt_deg + rotation).to_radians().cos() > 0.0)
                .map(|(_, w)| w)
                .sum();
            Ok(Percept {
                rotation_deg: rotation,
                p_convex,
                map_tilt_deg,
                p_light_above,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::interpretation::{Interpretation, Lighting, TokenReading};

    /// A sweep with an ideal engine: a bump lit from above, convex under tilts within 90° of
    /// above, residual rising with the distance from the true axis.
    fn ideal_sweep(step: f64) -> Sweep {
        let n = (360.0 / step) as usize;
        Sweep {
            lighting: Lighting {
                slant_deg: 45.0,
                albedo: 1.0,
                ambient: 0.0,
            },
            tokens: vec![(1, "disc".into())],
            interpretations: (0..n)
                .map(|i| {
                    let t = (i as f64 * step).to_radians();
                    Interpretation {
                        tilt_deg: i as f64 * step,
                        residual: 0.0,
                        smoothness: 0.0,
                        surface_residual: 0.01 * t.sin().powi(2),
                        converged: true,
                        iterations: 1,
                        method: crate::solver::Method::Multigrid,
                        tokens: vec![TokenReading {
                            convexity: t.cos(),
                            residual: 0.0,
                            smoothness: 0.0,
                            surface_residual: 0.0,
                        }],
                        depth: None,
                        f: None,
                        g: None,
                    }
                })
                .collect(),
        }
    }

    #[test]
    fn the_curve_peaks_at_the_prior_and_sharpens_with_kappa() {
        let sweep = ideal_sweep(5.0);
        let rotations: Vec<f64> = (0..360).map(f64::from).collect();
        let curve = |kappa: f64| -> Vec<f64> {
            let o = ObserverOptions {
                prior: LightPrior {
                    kappa,
                    ..LightPrior::default()
                },
                noise: 0.05,
                lapse: 0.0,
            };
            observe(&sweep, &o, &rotations)
                .unwrap()
                .iter()
                .map(|p| p.p_convex[0])
                .collect()
        };
        let (a, b) = (curve(2.0), curve(4.0));
        let peak = |c: &[f64]| (0..360).fold(0, |b, i| if c[i] > c[b] { i } else { b });
        assert_eq!(peak(&a), 26);
        assert_eq!(peak(&b), 26);
        assert!(b[26] > a[26]);
        // Half a turn away from any rotation, convex and concave trade places exactly.
        for i in 0..180 {
            assert!((a[i] + a[i + 180] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_tilts_must_cover_the_circle() {
        let mut sweep = ideal_sweep(90.0);
        sweep.interpretations.pop();
        let e = observe(&sweep, &ObserverOptions::default(), &[0.0]).unwrap_err();
        assert!(e.to_string().contains("cover the circle"), "{e}");
        let bad = ObserverOptions {
            noise: 0.0,
            ..ObserverOptions::default()
        };
        assert!(observe(&ideal_sweep(90.0), &bad, &[0.0]).is_err());
    }

    /// The image observer on one disc is the fitted formula: with a small image noise, at
    /// every rotation θ of the sweep's grid, its P(convex) is the observer model's
    /// P(convex | θ) for the same (μ, κ, π, λ).
    #[test]
    fn on_one_disc_the_observer_is_the_formula() {
        let sweep = ideal_sweep(5.0);
        let model = ModelParams {
            tilt_deg: 26.0,
            kappa: 1.3,
            convexity_prior: 0.7,
            lapse: 0.06,
        };
        let o = ObserverOptions::from_model(&model, 1e-3).unwrap();
        let rotations: Vec<f64> = (0..72).map(|i| 5.0 * i as f64).collect();
        for p in observe(&sweep, &o, &rotations).unwrap() {
            let want = model.p_convex(p.rotation_deg);
            assert!(
                (p.p_convex[0] - want).abs() < 1e-9,
                "{}: {} vs {want}",
                p.rotation_deg,
                p.p_convex[0]
            );
        }
    }

    /// A noise so small that 2σ² underflows keeps the best interpretations and never gives NaN.
    #[test]
    fn a_tiny_noise_gives_numbers_not_nan() {
        let sweep = ideal_sweep(15.0);
        let o = ObserverOptions {
            noise: 1e-200,
            ..ObserverOptions::default()
        };
        let rotations: Vec<f64> = (0..24).map(|i| 15.0 * i as f64).collect();
        for p in observe(&sweep, &o, &rotations).unwrap() {
            assert!(
                p.p_convex[0].is_finite() && p.p_light_above.is_finite(),
                "{p:?}"
            );
        }
        let csv = curves_csv(
            &sweep,
            &[Curve {
                options: o,
                percepts: observe(&sweep, &o, &rotations).unwrap(),
            }],
        );
        assert!(!csv.to_lowercase().contains("nan"), "{csv}");
    }
}
