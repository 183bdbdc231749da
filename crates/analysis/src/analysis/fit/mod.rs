//! Maximum-likelihood fits of the observer model ([`crate::analysis::observer_model`]) to
//! bump/dimple responses, with parametric-bootstrap confidence intervals.
//!
//! **Parametrisation.** The log odds of convex before lapses are linear in the harmonics of θ:
//! η(θ) = β₀ + Σₕ (β_{c,h} cos hθ + β_{s,h} sin hθ), h odd. For the von Mises prior only h = 1
//! is present, with β₀ = logit π, β_{c,1} = 2κ cos μ and β_{s,1} = 2κ sin μ: μ is circular by
//! construction, κ = |β₁|/2 ≥ 0 and π in (0, 1). The lapse is λ = λ_max·σ(u) with
//! λ_max = [`LAPSE_MAX`] (or fixed). The fit maximises
//! Σ kᵢ ln P(θᵢ) + (nᵢ − kᵢ) ln(1 − P(θᵢ)) over the counts kᵢ of convex among nᵢ trials at
//! each rotation θᵢ, P = λ/2 + (1 − λ)σ(η).
//!
//! **Non-parametric prior.** With [`FitOptions::nonparametric`] the log-density of the light
//! prior gets the odd harmonics 3 and 5 as well, with a roughness penalty
//! ρ Σₕ h⁴ (a_h² + b_h²) on them (ρ = [`ROUGHNESS`]) so that the estimate shrinks toward the
//! von Mises; the prior is reported as a density over [`PRIOR_DIRECTIONS`] directions. Only
//! the odd part of a log prior reaches the responses (a disc at θ weighs p(θ) against
//! p(θ + 180°)), so the even harmonics are set to 0: the reported density is the smoothest one
//! consistent with the data, and this is stated in the report.
//!
//! **Optimiser.** Starting values on a grid over μ (every 45°) and κ (0.5, 2), the best of
//! which starts a Nelder–Mead simplex, restarted once from its result. Deterministic: no
//! random starts.
//!
//! **Intervals.** Each estimate's `ci95` is its 95 % profile-likelihood interval
//! ([`profile`]): the values whose likelihood, maximised over the other parameters, is within
//! χ²₁(0.95)/2 of the maximum. Beside it, `ci95_bootstrap` is a parametric bootstrap's: `B`
//! data sets simulated from the fitted model at the same rotations and trial counts, each
//! refitted; 95 % percentile intervals (for μ, of the replicates' circular differences from the
//! estimate, so an interval may run past 0° or 360°). The percentile interval of a skewed,
//! bounded estimate (κ of a weak prior, and π beside it) covers the truth too rarely (down to
//! 87 % in the recovery study of docs/experiments.md); the profile interval keeps 95 %. The
//! non-parametric prior's density has bootstrap intervals only. Replicate b draws from its own
//! SplitMix64 generator whose seed is the b-th output of one seeded from `seed`, so the
//! intervals are the same bits for any number of threads.

pub mod profile;

use super::observer_model::{convexity_bias, sigmoid, ModelParams};
use crate::error::{Error, Result};
use crate::parallel::prelude::*;
use crate::random::SplitMix64;
use profile::Parameter;
use serde::Serialize;

/// The largest lapse rate the fit considers (a lapse answers at random, so λ = 1 is pure
/// guessing; more than half the trials lapsed is not an observer worth fitting).
pub const LAPSE_MAX: f64 = 0.5;

/// The largest prior concentration κ the fit considers; an estimate there is reported as at
/// its bound (the responses are a step, and κ is only bounded below).
pub const KAPPA_MAX: f64 = 50.0;

/// The largest |logit π| the fit considers (π within about 10⁻⁹ of 0 or 1).
pub const BIAS_MAX: f64 = 20.0;

/// The number of directions over which the non-parametric prior is reported (every 15°).
pub const PRIOR_DIRECTIONS: usize = 24;

/// The weight ρ of the non-parametric prior's roughness penalty.
pub const ROUGHNESS: f64 = 0.01;

/// The odd harmonics of the non-parametric prior's log-density.
const NONPARAMETRIC_HARMONICS: [u32; 3] = [1, 3, 5];

/// The fewest trials a data set needs before it is fitted.
pub const MIN_TRIALS: usize = 20;

/// The trials at one rotation: how many, and how many were answered convex.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bin {
    /// The rotation θ (direction of the bright side), degrees in [0, 360).
    pub rotation_deg: f64,
    /// Trials at this rotation.
    pub trials: usize,
    /// Of which answered convex.
    pub convex: usize,
}

impl Bin {
    /// The proportion answered convex.
    pub fn proportion(&self) -> f64 {
        self.convex as f64 / self.trials as f64
    }

    /// The Wilson score interval of the proportion at 95 %.
    ///
    /// ```
    /// use shadelab_analysis::analysis::fit::Bin;
    /// let b = Bin { rotation_deg: 0.0, trials: 20, convex: 20 };
    /// let [lo, hi] = b.wilson95();
    /// assert!((lo - 0.8389).abs() < 1e-4 && hi == 1.0);
    /// ```
    pub fn wilson95(&self) -> [f64; 2] {
        let z = 1.959_963_984_540_054_f64;
        let n = self.trials as f64;
        let p = self.proportion();
        let denom = 1.0 + z * z / n;
        let centre = (p + z * z / (2.0 * n)) / denom;
        let half = z / denom * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
        [(centre - half).max(0.0), (centre + half).min(1.0)]
    }
}

/// Counts trials by rotation: one [`Bin`] per distinct rotation (wrapped to [0, 360)), in
/// increasing order. `trials` holds (rotation in degrees, answered convex).
pub fn bins(trials: &[(f64, bool)]) -> Vec<Bin> {
    let mut out: Vec<Bin> = Vec::new();
    let mut sorted: Vec<(f64, bool)> = trials
        .iter()
        .map(|&(r, c)| (super::wrap_360(r), c))
        .collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (r, c) in sorted {
        match out.last_mut() {
            Some(b) if b.rotation_deg == r => {
                b.trials += 1;
                b.convex += usize::from(c);
            }
            _ => out.push(Bin {
                rotation_deg: r,
                trials: 1,
                convex: usize::from(c),
            }),
        }
    }
    out
}

/// How to fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitOptions {
    /// A fixed lapse rate, or `None` to estimate it (in 0..[`LAPSE_MAX`]).
    pub lapse: Option<f64>,
    /// Estimate a non-parametric (smooth) prior over light tilt as well.
    pub nonparametric: bool,
    /// Parametric-bootstrap replicates for the intervals (0: none).
    pub bootstrap: usize,
    /// The bootstrap's seed.
    pub seed: u64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            lapse: None,
            nonparametric: false,
            bootstrap: 1000,
            seed: 0,
        }
    }
}

impl FitOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        if let Some(l) = self.lapse {
            if !(0.0..=LAPSE_MAX).contains(&l) {
                return Err(Error::invalid(format!(
                    "fixed lapse {l} must be in 0..{LAPSE_MAX}"
                )));
            }
        }
        if self.bootstrap > 100_000 {
            return Err(Error::invalid(format!(
                "{} bootstrap replicates is more than the 100000 allowed",
                self.bootstrap
            )));
        }
        Ok(())
    }
}

/// A model's structure: which harmonics, whether π and λ are free.
#[derive(Debug, Clone, Copy)]
struct Structure {
    harmonics: &'static [u32],
    free_bias: bool,
    lapse: Option<f64>,
}

impl Structure {
    fn dims(&self) -> usize {
        usize::from(self.free_bias) + 2 * self.harmonics.len() + usize::from(self.lapse.is_none())
    }

    /// The free parameters of the model (for AIC/BIC): the harmonics' coefficients, π and λ.
    fn parameters(&self) -> usize {
        self.dims()
    }

    fn split<'z>(&self, z: &'z [f64]) -> (f64, &'z [f64], f64) {
        let mut i = 0;
        let b0 = if self.free_bias {
            i = 1;
            z[0]
        } else {
            0.0
        };
        let h = &z[i..i + 2 * self.harmonics.len()];
        let lapse = match self.lapse {
            Some(l) => l,
            None => LAPSE_MAX * sigmoid(z[i + 2 * self.harmonics.len()]),
        };
        (b0, h, lapse)
    }

    fn eta(&self, b0: f64, h: &[f64], theta: f64) -> f64 {
        let t = theta.to_radians();
        let mut eta = b0;
        for (j, &k) in self.harmonics.iter().enumerate() {
            let a = k as f64 * t;
            eta += h[2 * j] * a.cos() + h[2 * j + 1] * a.sin();
        }
        eta
    }

    /// The negative penalised log-likelihood, +∞ outside the bounds.
    fn objective(&self, z: &[f64], data: &[Bin]) -> f64 {
        let (b0, h, lapse) = self.split(z);
        if b0.abs() > BIAS_MAX || h[0].hypot(h[1]) > 2.0 * KAPPA_MAX {
            return f64::INFINITY;
        }
        if self.lapse.is_none() && z[z.len() - 1].abs() > 30.0 {
            return f64::INFINITY;
        }
        let mut penalty = 0.0;
        for (j, &k) in self.harmonics.iter().enumerate().skip(1) {
            // h holds 2a and 2b of log p; the penalty is on a and b.
            penalty +=
                ROUGHNESS * (k as f64).powi(4) * (h[2 * j].powi(2) + h[2 * j + 1].powi(2)) / 4.0;
        }
        -log_likelihood_eta(data, lapse, |theta| self.eta(b0, h, theta)) + penalty
    }
}

/// Σ k ln P + (n − k) ln(1 − P) with P = λ/2 + (1 − λ)σ(η(θ)), computed without log(0).
fn log_likelihood_eta(data: &[Bin], lapse: f64, eta: impl Fn(f64) -> f64) -> f64 {
    data.iter()
        .map(|b| {
            let e = eta(b.rotation_deg);
            let (lp, lq) = if lapse == 0.0 {
                (-softplus(-e), -softplus(e))
            } else {
                (
                    (0.5 * lapse + (1.0 - lapse) * sigmoid(e)).ln(),
                    (0.5 * lapse + (1.0 - lapse) * sigmoid(-e)).ln(),
                )
            };
            let k = b.convex as f64;
            let n = b.trials as f64;
            let mut ll = 0.0;
            if b.convex > 0 {
                ll += k * lp;
            }
            if b.convex < b.trials {
                ll += (n - k) * lq;
            }
            ll
        })
        .sum()
}

/// ln(1 + eˣ) without overflow.
fn softplus(x: f64) -> f64 {
    if x > 0.0 {
        x + (-x).exp().ln_1p()
    } else {
        x.exp().ln_1p()
    }
}

/// The log-likelihood of `model` on the counts `data`.
///
/// ```
/// use shadelab_analysis::analysis::fit::{log_likelihood, Bin};
/// use shadelab_analysis::analysis::observer_model::ModelParams;
/// let m = ModelParams { tilt_deg: 0.0, kappa: 0.0, convexity_prior: 0.5, lapse: 0.0 };
/// let data = [Bin { rotation_deg: 0.0, trials: 10, convex: 3 }];
/// assert!((log_likelihood(&m, &data) - 10.0 * 0.5f64.ln()).abs() < 1e-12);
/// ```
pub fn log_likelihood(model: &ModelParams, data: &[Bin]) -> f64 {
    let b0 = convexity_bias(model.convexity_prior);
    let t = model.tilt_deg.to_radians();
    let (c, s) = (2.0 * model.kappa * t.cos(), 2.0 * model.kappa * t.sin());
    log_likelihood_eta(data, model.lapse, |theta| {
        let r = theta.to_radians();
        b0 + c * r.cos() + s * r.sin()
    })
}

/// Minimises `f` from `start` with the Nelder–Mead simplex (reflection 1, expansion 2,
/// contraction ½, shrink ½), initial steps `step`, until the values at the simplex's vertices
/// agree to `1e-10` (relative) or after `max_evals` evaluations. Returns the best point and its
/// value. Deterministic.
///
/// ```
/// use shadelab_analysis::analysis::fit::nelder_mead;
/// let rosenbrock = |z: &[f64]| (1.0 - z[0]).powi(2) + 100.0 * (z[1] - z[0] * z[0]).powi(2);
/// let (z, v) = nelder_mead(&rosenbrock, &[-1.2, 1.0], 0.5, 20_000);
/// assert!((z[0] - 1.0).abs() < 1e-4 && (z[1] - 1.0).abs() < 1e-4 && v < 1e-8);
/// ```
pub fn nelder_mead(
    f: &dyn Fn(&[f64]) -> f64,
    start: &[f64],
    step: f64,
    max_evals: usize,
) -> (Vec<f64>, f64) {
    let n = start.len();
    let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
    simplex.push((start.to_vec(), f(start)));
    for i in 0..n {
        let mut p = start.to_vec();
        p[i] += step;
        let v = f(&p);
        simplex.push((p, v));
    }
    let mut evals = n + 1;
    let order = |s: &mut Vec<(Vec<f64>, f64)>| s.sort_by(|a, b| a.1.total_cmp(&b.1));
    order(&mut simplex);
    while evals < max_evals {
        let (best, worst) = (simplex[0].1, simplex[n].1);
        let spread = (worst - best).abs();
        if spread.is_finite() && spread <= 1e-10 * (best.abs() + 1e-10) {
            break;
        }
        let mut centroid = vec![0.0; n];
        for (p, _) in &simplex[..n] {
            for (c, x) in centroid.iter_mut().zip(p) {
                *c += x / n as f64;
            }
        }
        let along = |t: f64| -> Vec<f64> {
            centroid
                .iter()
                .zip(&simplex[n].0)
                .map(|(c, w)| c + t * (w - c))
                .collect()
        };
        let reflected = along(-1.0);
        let fr = f(&reflected);
        evals += 1;
        if fr < simplex[0].1 {
            let expanded = along(-2.0);
            let fe = f(&expanded);
            evals += 1;
            simplex[n] = if fe < fr {
                (expanded, fe)
            } else {
                (reflected, fr)
            };
        } else if fr < simplex[n - 1].1 {
            simplex[n] = (reflected, fr);
        } else {
            let (contracted, fc) = if fr < simplex[n].1 {
                let c = along(-0.5);
                let v = f(&c);
                (c, v)
            } else {
                let c = along(0.5);
                let v = f(&c);
                (c, v)
            };
            evals += 1;
            if fc < simplex[n].1.min(fr) {
                simplex[n] = (contracted, fc);
            } else {
                let first = simplex[0].0.clone();
                for (p, v) in simplex.iter_mut().skip(1) {
                    for (x, b) in p.iter_mut().zip(&first) {
                        *x = b + 0.5 * (*x - b);
                    }
                    *v = f(p);
                }
                evals += n;
            }
        }
        order(&mut simplex);
    }
    let (p, v) = simplex.swap_remove(0);
    (p, v)
}

/// One maximum-likelihood fit, without intervals.
#[derive(Debug, Clone, PartialEq)]
pub struct PointFit {
    /// The von Mises model's parameters (for the non-parametric fit: the first harmonic as
    /// μ and κ).
    pub params: ModelParams,
    /// The maximised log-likelihood (without the penalty).
    pub log_likelihood: f64,
    /// The non-parametric prior's density over [`PRIOR_DIRECTIONS`] directions (per radian),
    /// when fitted.
    pub prior_density: Option<Vec<f64>>,
    /// Which estimates lie at a bound of the search (e.g. "prior_kappa").
    pub at_bounds: Vec<&'static str>,
    /// The number of free parameters.
    pub parameters: usize,
}

fn fit_structure(data: &[Bin], s: Structure) -> PointFit {
    let total: usize = data.iter().map(|b| b.trials).sum();
    let convex: usize = data.iter().map(|b| b.convex).sum();
    let p = (convex as f64 + 0.5) / (total as f64 + 1.0);
    let b0 = (p / (1.0 - p)).ln();
    let u0 = (0.05 / (LAPSE_MAX - 0.05)).ln();
    let objective = |z: &[f64]| s.objective(z, data);
    let mut best: Option<(Vec<f64>, f64)> = None;
    for kappa in [0.5, 2.0] {
        for step in 0..8 {
            let mu = (45.0 * step as f64).to_radians();
            let mut z = Vec::with_capacity(s.dims());
            if s.free_bias {
                z.push(b0);
            }
            z.push(2.0 * kappa * mu.cos());
            z.push(2.0 * kappa * mu.sin());
            z.extend(std::iter::repeat(0.0).take(2 * (s.harmonics.len() - 1)));
            if s.lapse.is_none() {
                z.push(u0);
            }
            let v = objective(&z);
            if best.as_ref().map_or(true, |b| v < b.1) {
                best = Some((z, v));
            }
        }
    }
    let (start, _) = best.unwrap_or_default();
    let (z, _) = nelder_mead(&objective, &start, 0.5, 4000);
    let (z, _) = nelder_mead(&objective, &z, 0.1, 4000);
    let (b0, h, lapse) = s.split(&z);
    let kappa = h[0].hypot(h[1]) / 2.0;
    let tilt = super::wrap_180(h[1].atan2(h[0]).to_degrees());
    let params = ModelParams {
        tilt_deg: tilt,
        kappa,
        convexity_prior: if s.free_bias { sigmoid(b0) } else { 0.5 },
        lapse,
    };
    let mut at_bounds = Vec::new();
    if kappa > 0.999 * KAPPA_MAX {
        at_bounds.push("prior_kappa");
    }
    if s.free_bias && b0.abs() > 0.999 * BIAS_MAX {
        at_bounds.push("convexity_prior");
    }
    let prior_density = (s.harmonics.len() > 1).then(|| {
        let logs: Vec<f64> = (0..PRIOR_DIRECTIONS)
            .map(|i| 0.5 * (s.eta(0.0, h, 360.0 * i as f64 / PRIOR_DIRECTIONS as f64)))
            .collect();
        let top = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let w: Vec<f64> = logs.iter().map(|l| (l - top).exp()).collect();
        let total: f64 = w.iter().sum();
        let per_radian = PRIOR_DIRECTIONS as f64 / std::f64::consts::TAU;
        w.iter().map(|v| v / total * per_radian).collect()
    });
    PointFit {
        params,
        log_likelihood: log_likelihood_eta(data, lapse, |t| s.eta(b0, h, t)),
        prior_density,
        at_bounds,
        parameters: s.parameters(),
    }
}

/// The maximum-likelihood fit of the von Mises model (and, with `nonparametric`, of the
/// smooth prior instead) to `data`, without intervals; `lapse` fixes λ when given.
pub fn fit_point(data: &[Bin], lapse: Option<f64>, nonparametric: bool) -> PointFit {
    fit_structure(
        data,
        Structure {
            harmonics: if nonparametric {
                &NONPARAMETRIC_HARMONICS
            } else {
                &NONPARAMETRIC_HARMONICS[..1]
            },
            free_bias: true,
            lapse,
        },
    )
}

/// An estimate with its intervals.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Estimate {
    /// The maximum-likelihood value.
    pub value: f64,
    /// The 95 % profile-likelihood interval ([`profile`]; `null` for a value that was fixed;
    /// for the non-parametric prior's density, the bootstrap interval).
    pub ci95: Option<[f64; 2]>,
    /// The 95 % parametric-bootstrap percentile interval (`null` without a bootstrap, or for
    /// a value that was fixed).
    pub ci95_bootstrap: Option<[f64; 2]>,
}

/// A model compared by information criteria.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Criteria {
    /// The model, in words.
    pub model: String,
    /// Free parameters.
    pub parameters: usize,
    /// The maximised log-likelihood.
    pub log_likelihood: f64,
    /// Akaike's criterion, 2k − 2 ln L.
    pub aic: f64,
    /// The Bayesian (Schwarz) criterion, k ln n − 2 ln L.
    pub bic: f64,
}

impl Criteria {
    fn new(model: &str, parameters: usize, log_likelihood: f64, trials: usize) -> Criteria {
        let k = parameters as f64;
        Criteria {
            model: model.into(),
            parameters,
            log_likelihood,
            aic: 2.0 * k - 2.0 * log_likelihood,
            bic: k * (trials as f64).ln() - 2.0 * log_likelihood,
        }
    }
}

/// The non-parametric prior: a smooth density over [`PRIOR_DIRECTIONS`] directions.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SmoothPrior {
    /// The directions, degrees (0 = above, +90 = left).
    pub tilt_deg: Vec<f64>,
    /// The density at each, per radian, with its bootstrap interval.
    pub density: Vec<Estimate>,
    /// The model's fit.
    pub criteria: Criteria,
    /// What the data can and cannot say about it.
    pub note: &'static str,
}

/// A full fit: estimates with intervals, the criteria against the model without a convexity
/// prior, and the data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObserverFit {
    /// Trials fitted.
    pub n_trials: usize,
    /// μ, degrees in (−180, 180] (0 = above, +90 = left).
    pub prior_tilt_deg: Estimate,
    /// κ.
    pub prior_kappa: Estimate,
    /// π.
    pub convexity_prior: Estimate,
    /// λ.
    pub lapse: Estimate,
    /// logit π, the convexity bias B of `analyze observer`.
    pub convexity_bias: f64,
    /// The fitted model's log-likelihood.
    pub log_likelihood: f64,
    /// The fitted model and the one without a convexity prior (π = 0.5), by AIC and BIC.
    pub models: [Criteria; 2],
    /// AIC of the model without a convexity prior minus the full model's (> 0 favours a
    /// convexity prior).
    pub delta_aic: f64,
    /// The same for BIC.
    pub delta_bic: f64,
    /// Estimates at a bound of the search.
    pub at_bounds: Vec<&'static str>,
    /// The smooth, non-parametric prior, when asked for.
    pub nonparametric_prior: Option<SmoothPrior>,
    /// The counts per rotation, with Wilson intervals.
    pub bins: Vec<BinSummary>,
    /// Bootstrap replicates used (replicates whose data were all one answer are kept: they are
    /// what the fitted model produces).
    pub bootstrap: usize,
}

/// A rotation's counts as reported.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BinSummary {
    /// The rotation, degrees.
    pub rotation_deg: f64,
    /// Trials.
    pub trials: usize,
    /// Answered convex.
    pub convex: usize,
    /// The proportion convex.
    pub proportion: f64,
    /// Its 95 % Wilson interval.
    pub ci95: [f64; 2],
}

impl ObserverFit {
    /// The fitted model's parameters.
    pub fn params(&self) -> ModelParams {
        ModelParams {
            tilt_deg: self.prior_tilt_deg.value,
            kappa: self.prior_kappa.value,
            convexity_prior: self.convexity_prior.value,
            lapse: self.lapse.value,
        }
    }
}

/// Checks that `data` can identify the model: enough trials, both answers, and rotations
/// that are not all on one axis. `what` names the data set in messages.
pub fn check_identifiable(data: &[Bin], options: &FitOptions, what: &str) -> Result<()> {
    let n: usize = data.iter().map(|b| b.trials).sum();
    let convex: usize = data.iter().map(|b| b.convex).sum();
    if n < MIN_TRIALS {
        return Err(Error::invalid(format!(
            "{what}: {n} trials is too few to fit the observer (at least {MIN_TRIALS})"
        )));
    }
    if convex == 0 || convex == n {
        let answer = if convex == 0 { "concave" } else { "convex" };
        return Err(Error::invalid(format!(
            "{what}: all {n} responses are '{answer}', so the priors cannot be estimated (the estimates would run off to their bounds)"
        )));
    }
    if data.len() == 1 {
        return Err(Error::invalid(format!(
            "{what}: every trial is at rotation {}°, so the light prior is not identifiable (it needs rotations around the circle)",
            data[0].rotation_deg
        )));
    }
    let axis = data[0].rotation_deg.rem_euclid(180.0);
    if data
        .iter()
        .all(|b| (b.rotation_deg.rem_euclid(180.0) - axis).abs() < 1e-9)
    {
        return Err(Error::invalid(format!(
            "{what}: every rotation lies on the axis {axis}°–{}°, so the light prior's direction is not identifiable",
            axis + 180.0
        )));
    }
    let free = 3 + usize::from(options.lapse.is_none());
    let need = if options.nonparametric {
        free + 4
    } else {
        free
    };
    if data.len() < need {
        return Err(Error::invalid(format!(
            "{what}: {} distinct rotations cannot identify {need} parameters (give at least {need})",
            data.len()
        )));
    }
    Ok(())
}

/// Fits the observer model to `data` with intervals from a parametric bootstrap. Fails on data
/// that cannot identify it ([`check_identifiable`]).
///
/// ```
/// use shadelab_analysis::analysis::fit::{fit, simulate, FitOptions};
/// use shadelab_analysis::analysis::observer_model::ModelParams;
/// let truth = ModelParams { tilt_deg: 26.0, kappa: 1.5, convexity_prior: 0.6, lapse: 0.04 };
/// let rotations: Vec<f64> = (0..24).map(|i| 15.0 * i as f64).collect();
/// let data = simulate(&truth, &rotations, 40, 1);
/// let options = FitOptions { bootstrap: 50, ..FitOptions::default() };
/// let f = fit(&data, &options, "example").unwrap();
/// assert!((f.prior_tilt_deg.value - 26.0).abs() < 15.0);
/// let [lo, hi] = f.prior_kappa.ci95.unwrap();
/// assert!(lo < f.prior_kappa.value && f.prior_kappa.value < hi);
/// ```
pub fn fit(data: &[Bin], options: &FitOptions, what: &str) -> Result<ObserverFit> {
    options.validate()?;
    check_identifiable(data, options, what)?;
    let n: usize = data.iter().map(|b| b.trials).sum();
    let vm = fit_point(data, options.lapse, false);
    let null = fit_structure(
        data,
        Structure {
            harmonics: &NONPARAMETRIC_HARMONICS[..1],
            free_bias: false,
            lapse: options.lapse,
        },
    );
    let np = options
        .nonparametric
        .then(|| fit_point(data, options.lapse, true));
    // The bootstrap: replicate b from the b-th seed of one generator.
    let mut master = SplitMix64::new(options.seed);
    let seeds: Vec<u64> = (0..options.bootstrap).map(|_| master.next_u64()).collect();
    let replicates: Vec<(PointFit, Option<PointFit>)> = seeds
        .par_iter()
        .map(|&seed| {
            let mut rng = SplitMix64::new(seed);
            let sim = simulate_counts(&vm.params, data, &mut rng);
            let v = fit_point(&sim, options.lapse, false);
            let p = np.as_ref().map(|np| {
                let sim = simulate_counts_np(np, data, &mut rng);
                fit_point(&sim, options.lapse, true)
            });
            (v, p)
        })
        .collect();
    let pick =
        |f: &dyn Fn(&PointFit) -> f64| -> Vec<f64> { replicates.iter().map(|r| f(&r.0)).collect() };
    let boot = options.bootstrap > 0;
    let p = vm.params;
    // The profile-likelihood intervals, one parameter per task.
    let mut which = vec![Parameter::Tilt, Parameter::Kappa, Parameter::Convexity];
    if options.lapse.is_none() {
        which.push(Parameter::Lapse);
    }
    let profiled: Vec<[f64; 2]> = which
        .par_iter()
        .map(|&w| profile::interval(data, options.lapse, &p, w))
        .collect();
    let estimate = |value: f64, k: usize, samples: Vec<f64>| Estimate {
        value,
        ci95: Some(profiled[k]),
        ci95_bootstrap: boot.then(|| percentile_interval(samples)),
    };
    let tilt = Estimate {
        value: p.tilt_deg,
        ci95: Some(profiled[0]),
        ci95_bootstrap: boot.then(|| {
            let d = pick(&|r| super::wrap_180(r.params.tilt_deg - p.tilt_deg));
            let [lo, hi] = percentile_interval(d);
            [p.tilt_deg + lo, p.tilt_deg + hi]
        }),
    };
    let lapse = match options.lapse {
        Some(l) => Estimate {
            value: l,
            ci95: None,
            ci95_bootstrap: None,
        },
        None => estimate(p.lapse, 3, pick(&|r| r.params.lapse)),
    };
    let full = Criteria::new(
        "von Mises light prior, convexity prior, lapse",
        vm.parameters,
        vm.log_likelihood,
        n,
    );
    let without = Criteria::new(
        "von Mises light prior, lapse, no convexity prior (π = 0.5)",
        null.parameters,
        null.log_likelihood,
        n,
    );
    let nonparametric_prior = np.as_ref().map(|np| {
        let density = np.prior_density.clone().unwrap_or_default();
        SmoothPrior {
            tilt_deg: (0..PRIOR_DIRECTIONS)
                .map(|i| 360.0 * i as f64 / PRIOR_DIRECTIONS as f64)
                .collect(),
            density: density
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    let samples = replicates
                        .iter()
                        .filter_map(|r| r.1.as_ref())
                        .filter_map(|f| f.prior_density.as_ref().map(|d| d[i]))
                        .collect();
                    let ci = boot.then(|| percentile_interval(samples));
                    Estimate {
                        value: v,
                        ci95: ci,
                        ci95_bootstrap: ci,
                    }
                })
                .collect(),
            criteria: Criteria::new(
                "smooth light prior (odd harmonics 1, 3, 5 of the log-density, penalised), convexity prior, lapse",
                np.parameters,
                np.log_likelihood,
                n,
            ),
            note: "bump/dimple judgements weigh p(θ) against p(θ + 180°), so only the odd part of the log-density is estimated; its even part is set to the smoothest choice (zero)",
        }
    });
    let mut at_bounds = vm.at_bounds.clone();
    if options.lapse.is_none() && p.lapse > 0.999 * LAPSE_MAX {
        at_bounds.push("lapse");
    }
    Ok(ObserverFit {
        n_trials: n,
        prior_tilt_deg: tilt,
        prior_kappa: estimate(p.kappa, 1, pick(&|r| r.params.kappa)),
        convexity_prior: estimate(p.convexity_prior, 2, pick(&|r| r.params.convexity_prior)),
        lapse,
        convexity_bias: convexity_bias(p.convexity_prior),
        log_likelihood: vm.log_likelihood,
        delta_aic: without.aic - full.aic,
        delta_bic: without.bic - full.bic,
        models: [full, without],
        at_bounds,
        nonparametric_prior,
        bins: data
            .iter()
            .map(|b| BinSummary {
                rotation_deg: b.rotation_deg,
                trials: b.trials,
                convex: b.convex,
                proportion: b.proportion(),
                ci95: b.wilson95(),
            })
            .collect(),
        bootstrap: options.bootstrap,
    })
}

/// The 2.5 % and 97.5 % percentiles (linear interpolation between order statistics).
fn percentile_interval(mut samples: Vec<f64>) -> [f64; 2] {
    samples.retain(|v| v.is_finite());
    if samples.is_empty() {
        return [f64::NAN, f64::NAN];
    }
    samples.sort_by(f64::total_cmp);
    let at = |q: f64| {
        let x = q * (samples.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x - x.floor());
        let j = (i + 1).min(samples.len() - 1);
        samples[i] + f * (samples[j] - samples[i])
    };
    [at(0.025), at(0.975)]
}

/// `like`'s rotations and trial counts with answers drawn from `rng`: convex with probability
/// `p(θ)`.
fn draw_counts(like: &[Bin], rng: &mut SplitMix64, p: impl Fn(f64) -> f64) -> Vec<Bin> {
    like.iter()
        .map(|b| {
            let p = p(b.rotation_deg);
            Bin {
                convex: (0..b.trials).filter(|_| rng.next_f64() < p).count(),
                ..*b
            }
        })
        .collect()
}

fn simulate_counts(model: &ModelParams, like: &[Bin], rng: &mut SplitMix64) -> Vec<Bin> {
    draw_counts(like, rng, |theta| model.p_convex(theta))
}

fn simulate_counts_np(np: &PointFit, like: &[Bin], rng: &mut SplitMix64) -> Vec<Bin> {
    // The smooth prior's P(convex) at θ: its log odds from the density at θ and θ + 180°.
    let density = np.prior_density.as_deref().unwrap_or(&[]);
    let b0 = convexity_bias(np.params.convexity_prior);
    draw_counts(like, rng, |theta| match direction_index(theta) {
        Some(i) if density.len() == PRIOR_DIRECTIONS => {
            let j = (i + PRIOR_DIRECTIONS / 2) % PRIOR_DIRECTIONS;
            let eta = b0 + (density[i] / density[j]).ln();
            super::observer_model::with_lapse(np.params.lapse, sigmoid(eta))
        }
        _ => np.params.p_convex(theta),
    })
}

/// The index of `rotation_deg` among the [`PRIOR_DIRECTIONS`] directions, if it is one.
fn direction_index(rotation_deg: f64) -> Option<usize> {
    let step = 360.0 / PRIOR_DIRECTIONS as f64;
    let x = super::wrap_360(rotation_deg) / step;
    ((x - x.round()).abs() < 1e-9).then(|| x.round() as usize % PRIOR_DIRECTIONS)
}

/// Simulated responses of `model`: `repeats` trials at each of `rotations`, from a generator
/// seeded with `seed`, as counts per rotation.
pub fn simulate(model: &ModelParams, rotations: &[f64], repeats: usize, seed: u64) -> Vec<Bin> {
    let mut rng = SplitMix64::new(seed);
    let like: Vec<Bin> = rotations
        .iter()
        .map(|&r| Bin {
            rotation_deg: super::wrap_360(r),
            trials: repeats,
            convex: 0,
        })
        .collect();
    simulate_counts(model, &like, &mut rng)
}

#[cfg(test)]
mod tests;
