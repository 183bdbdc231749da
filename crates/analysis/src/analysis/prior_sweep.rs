//! The prior sweep: one picture interpreted under each of a range of assumed light tilts.
//!
//! Under a flat or free boundary one solve serves every tilt: turning the light about the line
//! of sight turns the solution with it ([`Interpreter::turns_with_light`]), so the sweep solves
//! under the first tilt and turns that solution to each of the others; otherwise every tilt is
//! an independent solve. Either way the per-tilt work runs in parallel (rayon), each worker
//! with its own [`Interpreter`], and the results are collected in tilt order: the output does
//! not depend on the number of threads. For each token the sweep reports where its convexity
//! changes sign: the assumed tilts at which a bump becomes a dimple.

use super::convexity::CONVEXITY_ZERO;
use super::interpretation::{check_scene, Interpretation, Interpreter, Lighting, Scene};
use crate::error::{Error, Result};
use crate::io::csv_field;
use crate::parallel::prelude::*;
use crate::plot::{circle_step, span, Figure, LinePlot, Marker, Series};
use crate::solver::SolveOptions;
use serde::Serialize;

/// A finished sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Sweep {
    /// What was assumed besides the tilt.
    pub lighting: Lighting,
    /// The tokens' labels and names, in reading order.
    pub tokens: Vec<(u16, String)>,
    /// One interpretation per assumed tilt, in the order the tilts were given.
    pub interpretations: Vec<Interpretation>,
}

impl Sweep {
    /// The tilts, in order.
    pub fn tilts(&self) -> Vec<f64> {
        self.interpretations.iter().map(|i| i.tilt_deg).collect()
    }

    /// Token `k`'s convexity at every tilt.
    pub fn convexities(&self, k: usize) -> Vec<f64> {
        self.interpretations
            .iter()
            .map(|i| i.tokens[k].convexity)
            .collect()
    }

    /// Whether the tilts are equally spaced and cover the circle exactly once (step s, n·s =
    /// 360), so that the last tilt is followed by the first.
    pub fn covers_circle(&self) -> bool {
        circle_step(&self.tilts()).is_some()
    }

    /// The assumed tilts at which token `k`'s convexity changes sign, by linear interpolation
    /// between neighbouring tilts (and across the wrap from the last tilt to the first when the
    /// sweep covers the circle); angles are wrapped into [0, 360).
    pub fn flips(&self, k: usize) -> Vec<f64> {
        sign_changes(&self.tilts(), &self.convexities(k), self.covers_circle())
    }

    /// The tilts at which token `k`'s convexity passes `keep` (e.g. `|c| c > 0.0`: convex).
    pub fn tilts_where(&self, k: usize, keep: impl Fn(f64) -> bool) -> Vec<f64> {
        self.interpretations
            .iter()
            .filter(|i| keep(i.tokens[k].convexity))
            .map(|i| i.tilt_deg)
            .collect()
    }

    /// How many solves did not converge.
    pub fn unconverged(&self) -> usize {
        self.interpretations.iter().filter(|i| !i.converged).count()
    }

    /// The sweep as CSV: one row per assumed tilt and token, with its convexity, residual,
    /// smoothness and surface residual over the token, and whether the solve converged.
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "tilt_deg,token,label,convexity,residual,smoothness,surface_residual,converged\n",
        );
        for i in &self.interpretations {
            for (k, r) in i.tokens.iter().enumerate() {
                let (label, name) = &self.tokens[k];
                csv.push_str(&format!(
                    "{},{},{label},{},{},{},{},{}\n",
                    i.tilt_deg,
                    csv_field(name),
                    r.convexity,
                    r.residual,
                    r.smoothness,
                    r.surface_residual,
                    i.converged
                ));
            }
        }
        csv
    }

    /// Convexity (top; with one token, its flips marked) and surface residual (bottom) against
    /// assumed tilt, one curve per token (grouped by class when there are many); a sweep that
    /// covers the circle is shown over the full 0–360° with each curve closed.
    pub fn figure(&self) -> Figure {
        let tilts = self.tilts();
        let (lo, hi) = span(&tilts);
        let x_label = "assumed light tilt (°; 0 = above, 90 = left, 180 = below)";
        let mut convexity = LinePlot::new(
            "Convexity of each token under each assumed light",
            x_label,
            "convexity (relief / half-width, no unit; > 0 convex)",
            (lo, hi),
        );
        convexity.reference_y = Some(0.0);
        let mut fit = LinePlot::new(
            "How well the recovered surface reproduces the picture",
            x_label,
            "surface residual e_Z (Σ squared error, luminance²)",
            (lo, hi),
        );
        for (k, (_, name)) in self.tokens.iter().enumerate() {
            convexity.series.push(Series {
                name: name.clone(),
                points: tilts.iter().copied().zip(self.convexities(k)).collect(),
            });
            fit.series.push(Series {
                name: name.clone(),
                points: self
                    .interpretations
                    .iter()
                    .map(|i| (i.tilt_deg, i.tokens[k].surface_residual))
                    .collect(),
            });
        }
        convexity.close_circle();
        fit.close_circle();
        let (lo, hi) = convexity.x_range;
        if self.tokens.len() == 1 {
            for f in self.flips(0) {
                if f >= lo && f <= hi {
                    convexity.markers.push(Marker {
                        x: f,
                        label: format!("flip {f:.0}°"),
                    });
                }
            }
        }
        Figure {
            panels: vec![convexity, fit],
            size: (900, 900),
        }
    }
}

/// Where `values` (sampled at `angles`) change sign: linear interpolation between neighbours,
/// stepping over values within [`CONVEXITY_ZERO`] of zero; `cyclic` also checks the wrap from
/// the last sample back to the first. Angles are wrapped into [0, 360).
pub fn sign_changes(angles: &[f64], values: &[f64], cyclic: bool) -> Vec<f64> {
    let n = angles.len().min(values.len());
    // The samples with a verdict, as (angle, value), unwrapped along the sweep.
    let signed: Vec<(f64, f64)> = (0..n)
        .filter(|&i| values[i].abs() > CONVEXITY_ZERO)
        .map(|i| (angles[i], values[i]))
        .collect();
    let mut pairs: Vec<((f64, f64), (f64, f64))> =
        signed.windows(2).map(|w| (w[0], w[1])).collect();
    if cyclic && signed.len() >= 2 {
        let (first, last) = (signed[0], signed[signed.len() - 1]);
        pairs.push((last, (first.0 + 360.0, first.1)));
    }
    pairs
        .into_iter()
        .filter(|((_, a), (_, b))| a.signum() != b.signum())
        .map(|((ta, a), (tb, b))| super::wrap_360(ta + (tb - ta) * a / (a - b)))
        .collect()
}

/// Interprets `scene` under the light of each tilt in `tilts` with `lighting`, in parallel.
/// `progress` is called once per finished tilt (from any thread).
///
/// Fails on no tilts, a bad scene or lighting, or a solve that diverges.
pub fn sweep(
    scene: &Scene,
    tilts: &[f64],
    lighting: &Lighting,
    options: &SolveOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<Sweep> {
    if tilts.is_empty() {
        return Err(Error::invalid("the sweep has no tilts"));
    }
    if let Some(t) = tilts.iter().find(|t| !t.is_finite()) {
        return Err(Error::invalid(format!("tilt {t} is not a finite number")));
    }
    lighting.validate()?;
    check_scene(scene)?;
    // Plan once here so that a bad scene fails before any work, then one per worker.
    let mut first = Interpreter::new(scene, options)?;
    let plan = || Interpreter::new(scene, options);
    let planned = |e: &Error| Error::Compute(format!("cannot plan the solve: {e}"));
    let interpretations = if Interpreter::turns_with_light(scene) {
        // One solve serves every tilt: turned, it is the solve under each of them, to the
        // solver's tolerance (see `Interpreter::turns_with_light` and `interpret_turned`).
        // What is left per tilt, the integration and the readings, runs in parallel.
        let shape = first.solve(scene, tilts[0], lighting)?;
        drop(first);
        tilts
            .par_iter()
            .map_init(plan, |interpreter, &tilt| {
                let result = match interpreter {
                    Ok(it) => it.interpret_turned(scene, &shape, tilts[0], tilt, lighting),
                    Err(e) => Err(planned(e)),
                };
                progress();
                result
            })
            .collect::<Result<Vec<_>>>()?
    } else {
        drop(first);
        tilts
            .par_iter()
            .map_init(plan, |interpreter, &tilt| {
                let result = match interpreter {
                    Ok(it) => it.interpret(scene, tilt, lighting),
                    Err(e) => Err(planned(e)),
                };
                progress();
                result
            })
            .collect::<Result<Vec<_>>>()?
    };
    Ok(Sweep {
        lighting: *lighting,
        tokens: scene
            .tokens
            .iter()
            .map(|t| (t.label, t.name.clone()))
            .collect(),
        interpretations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sign_changes_interpolate_and_wrap() {
        let angles = [0.0, 90.0, 180.0, 270.0];
        // cos-like: flips at 45 (between 0 and 90: 1 → −1) and the wrap.
        let v = [1.0, -1.0, -1.0, 1.0];
        assert_eq!(sign_changes(&angles, &v, false), [45.0, 225.0]);
        let v = [1.0, 1.0, -1.0, -1.0];
        assert_eq!(sign_changes(&angles, &v, true), [135.0, 315.0]);
        // A zero sample is stepped over: one flip, at the zero.
        let v = [1.0, 0.0, -1.0, -1.0];
        assert_eq!(sign_changes(&angles, &v, false), [90.0]);
        assert!(sign_changes(&angles, &[1.0; 4], true).is_empty());
        assert_eq!(circle_step(&[0.0, 90.0, 180.0, 270.0]), Some(90.0));
        assert_eq!(circle_step(&[-180.0, -60.0, 60.0]), Some(120.0));
        assert_eq!(circle_step(&[0.0, 90.0, 180.0]), None);
    }
}
