//! Running a study, or one shard of it: a prior sweep per point, the observer per prior.

use super::grid::{params_text, prior_combinations, Point};
use super::{Shard, Study, RESULTS_HEADER, SWEEP_HEADER};
use crate::analysis::interpretation::{analysis_solve_options, Scene};
use crate::analysis::observer::{observe, ObserverOptions};
use crate::analysis::picture::TokenPicture;
use crate::analysis::prior_sweep::sweep;
use crate::error::{Error, Result};
use crate::io::csv_field;
use crate::parallel::prelude::*;

impl Study {
    /// The points shard `shard` runs.
    pub fn shard_points(&self, shard: Shard) -> Vec<&Point> {
        self.points.iter().filter(|p| shard.runs(p.index)).collect()
    }

    /// Runs the points of `shard` in parallel (rayon), calling `progress` as each finishes,
    /// and returns the CSV text of the results and the sweeps (headers included), rows in point
    /// order.
    pub fn run(&self, shard: Shard, progress: &(dyn Fn() + Sync)) -> Result<StudyOutput> {
        let points = self.shard_points(shard);
        let rows = points
            .par_iter()
            .map(|p| {
                let r = self.run_point(p).map_err(|e| {
                    let params = params_text(&p.params);
                    let sep = if params.is_empty() { "" } else { " " };
                    let name = &self.spec.stimuli[p.entry].stimulus;
                    let at = format!("study point {} ({name}{sep}{params})", p.index);
                    match e {
                        Error::Cancelled => Error::Cancelled,
                        Error::Invalid(m) => Error::Invalid(format!("{at}: {m}")),
                        Error::Compute(m) => Error::Compute(format!("{at}: {m}")),
                        other => Error::Compute(format!("{at}: {other}")),
                    }
                });
                progress();
                r
            })
            .collect::<Result<Vec<_>>>()?;
        let mut results = String::from(RESULTS_HEADER);
        let mut sweep_csv = String::from(SWEEP_HEADER);
        for (r, s) in rows {
            results.push_str(&r);
            sweep_csv.push_str(&s);
        }
        Ok(StudyOutput {
            results,
            sweep: sweep_csv,
            points: points.iter().map(|p| p.index).collect(),
        })
    }

    /// One point's result rows and sweep rows.
    fn run_point(&self, point: &Point) -> Result<(String, String)> {
        let entry = &self.spec.stimuli[point.entry];
        let size = entry.size();
        let (request, output) = crate::stimulus::generate(
            &entry.stimulus,
            &point.params,
            &size,
            entry.seed,
            self.max_pixels,
        )?;
        let picture = TokenPicture::from_stimulus(&request, &output)?;
        let domain = picture.domain(self.domain);
        let lighting = picture.lighting(&domain, point.slant_deg, None, None)?;
        let scene = Scene {
            image: &picture.image,
            domain: &domain,
            boundary: &self.boundary,
            tokens: &picture.tokens,
        };
        let result = sweep(
            &scene,
            &self.tilts,
            &lighting,
            &analysis_solve_options(),
            &|| {},
        )?;
        let lead = format!(
            "{},{},{},{}",
            point.index,
            csv_field(&entry.stimulus),
            csv_field(&params_text(&point.params)),
            point.slant_deg
        );
        let mut sweep_rows = String::new();
        for i in &result.interpretations {
            for (k, r) in i.tokens.iter().enumerate() {
                sweep_rows.push_str(&format!(
                    "{lead},{},{},{},{},{},{},{}\n",
                    i.tilt_deg,
                    csv_field(&result.tokens[k].1),
                    r.convexity,
                    r.residual,
                    r.smoothness,
                    r.surface_residual,
                    i.converged
                ));
            }
        }
        let mut result_rows = String::new();
        for prior in prior_combinations(&self.spec.priors) {
            let options = ObserverOptions {
                prior,
                noise: self.spec.noise,
                lapse: self.spec.lapse,
            };
            for percept in observe(&result, &options, &self.rotations)? {
                for (k, p) in percept.p_convex.iter().enumerate() {
                    result_rows.push_str(&format!(
                        "{lead},{},{},{},{},{},{},{}\n",
                        prior.mean_tilt_deg,
                        prior.kappa,
                        prior.convexity_bias,
                        percept.rotation_deg,
                        csv_field(&result.tokens[k].1),
                        p,
                        percept.map_tilt_deg
                    ));
                }
            }
        }
        Ok((result_rows, sweep_rows))
    }
}

/// What a run produces.
#[derive(Debug, Clone, PartialEq)]
pub struct StudyOutput {
    /// `results.csv`.
    pub results: String,
    /// `sweep.csv`.
    pub sweep: String,
    /// The points run.
    pub points: Vec<usize>,
}
