//! The observer fit as a pipeline (`shadelab fit observer`): read a responses CSV, fit the
//! observer model ([`crate::analysis::observer_model`]) pooled and per participant
//! ([`crate::analysis::fit`]), and write `fit.json`, a figure and a Methods paragraph.
//!
//! The responses CSV is what `shadelab experiment` writes: a header, then one row per trial.
//! Only `rotation_deg` (θ, the direction of the stimulus's bright side, degrees; 0 = up,
//! +90 = left) and `response` (`convex` | `concave`, or 1 | 0) are needed; a `block` column
//! keeps the `test` rows (and drops `practice`); a `participant` column gives one fit per
//! participant beside the pooled fit; other columns are ignored.
//!
//! ```
//! use shadelab::pipeline::fit::parse_responses;
//! let csv = "participant,rotation_deg,response\np1,0,convex\np1,180,concave\n";
//! let r = parse_responses(csv, std::path::Path::new("r.csv")).unwrap();
//! assert_eq!(r.participants, vec![("p1".to_string(), vec![(0.0, true), (180.0, false)])]);
//! ```

use crate::analysis::fit::{bins, fit, FitOptions, ObserverFit};
use crate::analysis::observer_model::ModelParams;
use crate::analysis::plot::{IntervalSeries, LineAndPolar, LinePlot, Marker, PolarPlot, Series};
use crate::error::{Error, Result};
use crate::io;
use crate::progress::Progress;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The report's file name, which marks an output folder as a fit's.
pub const REPORT_FILE: &str = "fit.json";

/// What to fit, as plain values.
#[derive(Debug, Clone)]
pub struct Config {
    /// The responses CSV.
    pub responses: PathBuf,
    /// How to fit.
    pub options: FitOptions,
}

impl Config {
    /// The defaults ([`FitOptions::default`]) for `responses`.
    pub fn new(responses: &Path) -> Config {
        Config {
            responses: responses.to_path_buf(),
            options: FitOptions::default(),
        }
    }
}

/// The trials read from a responses CSV.
#[derive(Debug, Clone, PartialEq)]
pub struct Responses {
    /// Each participant's trials as (rotation in degrees, answered convex), in file order;
    /// participants in order of first appearance (one unnamed participant, "", without a
    /// `participant` column).
    pub participants: Vec<(String, Vec<(f64, bool)>)>,
    /// Practice rows left out.
    pub practice_rows: usize,
    /// The file's columns.
    pub columns: Vec<String>,
}

/// Reads a responses CSV (at most [`io::MAX_TEXT_BYTES`], about a million trials).
pub fn read_responses(path: &Path) -> Result<Responses> {
    let bytes = io::read_bytes(path)?;
    let text = String::from_utf8(bytes).map_err(|_| Error::format(path, "not UTF-8 text"))?;
    parse_responses(&text, path)
}

/// Parses the text of a responses CSV; `path` names it in errors, which give the line.
pub fn parse_responses(text: &str, path: &Path) -> Result<Responses> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let rows = io::parse_csv(text).map_err(|m| Error::format(path, m))?;
    let Some(((_, header), rows)) = rows.split_first() else {
        return Err(Error::format(path, "empty: no header and no trials"));
    };
    let columns: Vec<String> = header.iter().map(|h| h.trim().to_string()).collect();
    let find = |name: &str| columns.iter().position(|c| c.eq_ignore_ascii_case(name));
    let need = |name: &str| {
        find(name).ok_or_else(|| {
            Error::format(
                path,
                format!("line 1: no '{name}' column (the header needs rotation_deg and response)"),
            )
        })
    };
    let (rotation, response) = (need("rotation_deg")?, need("response")?);
    let (block, participant) = (find("block"), find("participant"));
    let mut participants: Vec<(String, Vec<(f64, bool)>)> = Vec::new();
    let mut practice_rows = 0;
    for (line, row) in rows {
        if row.len() != columns.len() {
            return Err(Error::format(
                path,
                format!(
                    "line {line}: {} fields where the header has {}",
                    row.len(),
                    columns.len()
                ),
            ));
        }
        if let Some(b) = block {
            match row[b].trim().to_ascii_lowercase().as_str() {
                "test" => {}
                "practice" => {
                    practice_rows += 1;
                    continue;
                }
                other => {
                    return Err(Error::format(
                        path,
                        format!("line {line}: block '{other}' is not 'test' or 'practice'"),
                    ))
                }
            }
        }
        let theta: f64 = row[rotation]
            .trim()
            .parse()
            .ok()
            .filter(|t: &f64| t.is_finite())
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!(
                        "line {line}: rotation_deg '{}' is not a finite number of degrees",
                        row[rotation]
                    ),
                )
            })?;
        let convex = match row[response].trim().to_ascii_lowercase().as_str() {
            "convex" | "1" => true,
            "concave" | "0" => false,
            other => {
                return Err(Error::format(
                    path,
                    format!(
                        "line {line}: unknown response '{other}' (valid: convex, concave, 1, 0)"
                    ),
                ))
            }
        };
        let who = participant
            .map(|p| row[p].trim().to_string())
            .unwrap_or_default();
        match participants.iter_mut().find(|(p, _)| *p == who) {
            Some((_, trials)) => trials.push((theta, convex)),
            None => participants.push((who, vec![(theta, convex)])),
        }
    }
    if participants.is_empty() {
        return Err(Error::format(
            path,
            if practice_rows > 0 {
                "no test trials (only practice rows)"
            } else {
                "no trials after the header"
            },
        ));
    }
    Ok(Responses {
        participants,
        practice_rows,
        columns,
    })
}

/// The design as read from the data.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Design {
    /// Test trials fitted (all participants).
    pub trials: usize,
    /// Participants (1 without a `participant` column).
    pub participants: usize,
    /// The distinct rotations, degrees in [0, 360).
    pub rotations_deg: Vec<f64>,
    /// The fewest and most trials at one rotation (pooled).
    pub trials_per_rotation: [usize; 2],
    /// Practice rows left out.
    pub practice_rows: usize,
}

/// One participant's fit.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParticipantFit {
    /// The participant's id.
    pub participant: String,
    /// The fit.
    #[serde(flatten)]
    pub fit: ObserverFit,
}

/// What the fit found; serialised, it is `fit.json`. Its top level holds the pooled fit (all
/// trials, or the only participant's), with `participants` beside it.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// "shadelab".
    pub program: &'static str,
    /// The program's version.
    pub version: &'static str,
    /// "fit observer".
    pub command: &'static str,
    /// The responses file.
    pub responses: String,
    /// The model, in words.
    pub model: &'static str,
    /// The design read from the data.
    pub design: Design,
    /// How it was fitted.
    pub settings: FitOptions,
    /// The pooled fit.
    #[serde(flatten)]
    pub pooled: ObserverFit,
    /// One fit per participant (when there are several).
    pub participants: Vec<ParticipantFit>,
    /// The pooled fit as a study spec's observer settings (`priors` and `lapse`), to copy into
    /// a spec so that the study predicts with the fitted model.
    pub study: serde_json::Value,
    /// What was not fitted, and why; other cautions.
    pub warnings: Vec<String>,
    /// The files written and what they hold.
    pub outputs: BTreeMap<&'static str, &'static str>,
    /// Seconds the run took.
    pub seconds: f64,
}

/// The model as the report states it.
pub const MODEL: &str = "P(convex | theta) = lapse/2 + (1 - lapse) * pi * vM(theta; mu, kappa) / (pi * vM(theta; mu, kappa) + (1 - pi) * vM(theta + 180; mu, kappa)); theta = direction of the bright side (0 = up, +90 = left); maximum likelihood, 95% profile-likelihood intervals (parametric-bootstrap percentile intervals beside them)";

/// Reads the responses and fits them: pooled, and per participant when there are several
/// (one progress step per fit). A participant whose data cannot identify the model is left
/// out with a warning; the pooled data must identify it.
pub fn run(config: &Config, progress: &dyn Progress) -> Result<Report> {
    let started = Instant::now();
    config.options.validate()?;
    let responses = read_responses(&config.responses)?;
    let all: Vec<(f64, bool)> = responses
        .participants
        .iter()
        .flat_map(|(_, t)| t.iter().copied())
        .collect();
    let pooled_bins = bins(&all);
    let name = config.responses.display().to_string();
    let several = responses.participants.len() > 1;
    progress.start(
        1 + if several {
            responses.participants.len() as u64
        } else {
            0
        },
        "fit",
    );
    let pooled = fit(&pooled_bins, &config.options, &name)?;
    progress.advance(1);
    let mut warnings = Vec::new();
    let mut participants = Vec::new();
    if several {
        for (i, (who, trials)) in responses.participants.iter().enumerate() {
            let data = bins(trials);
            let what = format!("participant '{who}'");
            // Each participant's bootstrap has its own seed, derived from the one given.
            let options = FitOptions {
                seed: config.options.seed.wrapping_add(1 + i as u64),
                ..config.options
            };
            match fit(&data, &options, &what) {
                Ok(fit) => participants.push(ParticipantFit {
                    participant: who.clone(),
                    fit,
                }),
                Err(e) => warnings.push(format!(
                    "{e}: left out of the per-participant fits (kept in the pooled fit)"
                )),
            }
            progress.advance(1);
        }
    }
    progress.finish();
    for b in &pooled.at_bounds {
        warnings.push(format!(
            "the pooled estimate of {b} lies at the bound of the search"
        ));
    }
    let per = pooled_bins.iter().map(|b| b.trials);
    let m = pooled.params();
    let study = serde_json::json!({
        "priors": {
            "tilt": [m.tilt_deg],
            "kappa": [m.kappa],
            "convexity_bias": [pooled.convexity_bias],
        },
        "lapse": m.lapse,
    });
    Ok(Report {
        program: "shadelab",
        version: io::PROGRAM_VERSION,
        command: "fit observer",
        responses: name,
        model: MODEL,
        design: Design {
            trials: all.len(),
            participants: responses.participants.len(),
            rotations_deg: pooled_bins.iter().map(|b| b.rotation_deg).collect(),
            trials_per_rotation: [per.clone().min().unwrap_or(0), per.max().unwrap_or(0)],
            practice_rows: responses.practice_rows,
        },
        settings: config.options,
        pooled,
        participants,
        study,
        warnings,
        outputs: BTreeMap::from([
            ("fit.json", "the estimates with 95% intervals, log-likelihood, AIC/BIC against the model without a convexity prior, counts per rotation, per-participant fits"),
            ("fit.png", "proportion convex per rotation (95% Wilson intervals), the fitted curve, and the fitted prior over light tilt on a polar plot (also .svg)"),
            ("methods.md", "a Methods paragraph: design, model, estimates, citations"),
        ]),
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The header of a responses CSV, as `shadelab experiment` writes it.
pub const RESPONSES_HEADER: &str = super::experiment::CSV_HEADER;

/// A simulated responses CSV (the format [`parse_responses`] reads): `repeats` test trials at
/// each of `rotations` answered by the observer model `model` with draws from a generator
/// seeded with `seed`, in a seeded random order; `rt_ms` is 0 and `key`, `image` and `design_hash` are empty
/// (nothing was shown).
///
/// ```
/// use shadelab::analysis::observer_model::ModelParams;
/// use shadelab::pipeline::fit::{parse_responses, simulated_responses};
/// let m = ModelParams { tilt_deg: 26.0, kappa: 2.0, convexity_prior: 0.5, lapse: 0.02 };
/// let csv = simulated_responses(&m, &[0.0, 90.0, 180.0, 270.0], 5, 1, "sim");
/// let r = parse_responses(&csv, std::path::Path::new("sim.csv")).unwrap();
/// assert_eq!(r.participants[0].1.len(), 20);
/// ```
pub fn simulated_responses(
    model: &ModelParams,
    rotations: &[f64],
    repeats: usize,
    seed: u64,
    participant: &str,
) -> String {
    let mut rng = crate::random::SplitMix64::new(seed);
    let mut order: Vec<f64> = rotations
        .iter()
        .flat_map(|&r| std::iter::repeat(r).take(repeats))
        .collect();
    // Fisher–Yates.
    for i in (1..order.len()).rev() {
        let j = rng.below(i + 1);
        order.swap(i, j);
    }
    let mut csv = format!("{RESPONSES_HEADER}\n");
    for (i, &r) in order.iter().enumerate() {
        let convex = rng.next_f64() < model.p_convex(r);
        csv.push_str(&format!(
            "{},{},test,simulated,{r},{},0,,,\n",
            io::csv_field(participant),
            i + 1,
            if convex { "convex" } else { "concave" }
        ));
    }
    csv
}

/// Reads the fitted model from a `fit.json` (its pooled estimates), to predict with.
///
/// ```no_run
/// let m = shadelab::pipeline::fit::read_fit(std::path::Path::new("fit/fit.json")).unwrap();
/// println!("prior tilt {}°", m.tilt_deg);
/// ```
pub fn read_fit(path: &Path) -> Result<ModelParams> {
    let bytes = io::read_bytes(path)?;
    let v: serde_json::Value = serde_json::from_slice(&bytes)
        .map_err(|e| Error::format(path, format!("not JSON: {e}")))?;
    let value = |key: &str| -> Result<f64> {
        v.get(key)
            .and_then(|e| e.get("value"))
            .and_then(|x| x.as_f64())
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!("no {key}.value: not a fit.json written by shadelab fit observer"),
                )
            })
    };
    let model = ModelParams {
        tilt_deg: value("prior_tilt_deg")?,
        kappa: value("prior_kappa")?,
        convexity_prior: value("convexity_prior")?,
        lapse: value("lapse")?,
    };
    model
        .validate()
        .map_err(|e| Error::format(path, e.to_string()))?;
    Ok(model)
}

/// `[lo, hi]` as text, or "not estimated".
fn interval(ci: Option<[f64; 2]>, decimals: usize) -> String {
    match ci {
        Some([lo, hi]) => format!("95% CI {lo:.decimals$} to {hi:.decimals$}"),
        None => "fixed".into(),
    }
}

impl Report {
    /// The figure: proportions convex with Wilson intervals and the fitted curve against θ
    /// (0–360°), and the fitted prior over light tilt (and the smooth prior, when fitted) on a
    /// polar plot.
    pub fn figure(&self) -> LineAndPolar {
        let f = &self.pooled;
        let m = f.params();
        let mut line = LinePlot::new(
            "Proportion 'convex' against the direction of the bright side",
            "direction of the bright side θ (°, 0 = up, 90 = left)",
            "P(convex) (proportion)",
            (0.0, 360.0),
        );
        line.y_range = Some((-0.02, 1.02));
        line.reference_y = Some(0.5);
        line.x_ticks = crate::analysis::plot::Ticks::Degrees;
        line.series.push(Series {
            name: format!(
                "fit: μ = {:.0}°, κ = {:.2}, π = {:.2}, λ = {:.3}",
                m.tilt_deg, m.kappa, m.convexity_prior, m.lapse
            ),
            points: (0..=360)
                .map(|d| (d as f64, m.p_convex(d as f64)))
                .collect(),
        });
        line.intervals.push(IntervalSeries {
            name: format!("data ({} trials), 95% Wilson intervals", f.n_trials),
            points: f
                .bins
                .iter()
                .map(|b| (b.rotation_deg, b.proportion, b.ci95[0], b.ci95[1]))
                .collect(),
        });
        let mu = crate::analysis::wrap_360(m.tilt_deg);
        line.markers.push(Marker {
            x: mu,
            label: format!("μ = {:.0}°", m.tilt_deg),
        });
        let mut polar = PolarPlot {
            title: "Fitted prior over light tilt".into(),
            radius_label: "density (per radian)".into(),
            series: vec![Series {
                name: format!("von Mises, μ = {:.0}°, κ = {:.2}", m.tilt_deg, m.kappa),
                points: (0..360)
                    .map(|d| (d as f64, m.prior_density(d as f64)))
                    .collect(),
            }],
            markers: vec![Marker {
                x: m.tilt_deg,
                label: format!("μ = {:.0}°", m.tilt_deg),
            }],
            // The von Mises in the fitted curve's colour, the smooth prior in a third one
            // (the second is the data's).
            colours: vec![0, 2],
        };
        if let Some(np) = &f.nonparametric_prior {
            polar.series.push(Series {
                name: "smooth prior (24 directions)".into(),
                points: np
                    .tilt_deg
                    .iter()
                    .zip(&np.density)
                    .map(|(&t, d)| (t, d.value))
                    .collect(),
            });
        }
        LineAndPolar {
            line,
            polar,
            size: (1500, 620),
        }
    }

    /// The Methods paragraph (Markdown).
    pub fn methods(&self) -> String {
        let f = &self.pooled;
        let d = &self.design;
        let step = if d.rotations_deg.len() > 1 {
            d.rotations_deg[1] - d.rotations_deg[0]
        } else {
            0.0
        };
        let even = d
            .rotations_deg
            .windows(2)
            .all(|w| ((w[1] - w[0]) - step).abs() < 1e-9);
        let rotations = if even && d.rotations_deg.len() > 2 {
            format!(
                "{} directions of the bright side, every {step}° from {}°",
                d.rotations_deg.len(),
                d.rotations_deg[0]
            )
        } else {
            format!(
                "{} directions of the bright side ({}°)",
                d.rotations_deg.len(),
                d.rotations_deg
                    .iter()
                    .map(|r| r.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        let repeats = if d.trials_per_rotation[0] == d.trials_per_rotation[1] {
            format!("{} trials each", d.trials_per_rotation[0])
        } else {
            format!(
                "{} to {} trials each",
                d.trials_per_rotation[0], d.trials_per_rotation[1]
            )
        };
        let who = if d.participants > 1 {
            format!(
                "{} participants ({} fitted individually)",
                d.participants,
                self.participants.len()
            )
        } else {
            "One participant".into()
        };
        let lapse = match self.settings.lapse {
            Some(l) => format!("a lapse rate fixed at λ = {l}"),
            None => format!(
                "a lapse rate λ ≤ {} (a lapse answers at random)",
                crate::analysis::fit::LAPSE_MAX
            ),
        };
        let mut text = format!(
            "## Methods\n\n\
            **Design.** {who} judged whether a shaded disc was a bump (convex) or a dimple \
            (concave) in {} test trials{}: {rotations}, {repeats}{}. The direction θ of the bright \
            side is given in the tilt convention (0° = up, +90° = left).\n\n\
            **Model.** Responses were fitted with an ideal-observer model in which the disc is \
            either a bump lit from θ or a dimple lit from θ + 180°, a von Mises prior over the \
            light's tilt (mean μ, concentration κ) weighs the two lights, a convexity prior π \
            weighs the two shapes, and {lapse}: P(convex | θ) = λ/2 + (1 − λ)·π·vM(θ; μ, κ) / \
            (π·vM(θ; μ, κ) + (1 − π)·vM(θ + 180°; μ, κ)) (after Mamassian & Goutcher, 2001; \
            Sun & Perona, 1998). Parameters were estimated by maximum likelihood (shadelab {}, \
            `fit observer`), with 95% profile-likelihood confidence intervals (the values whose \
            likelihood, maximised over the other parameters, lies within χ²₁(0.95)/2 of the \
            maximum){}.\n\n\
            **Results.** The light prior pointed at μ = {:.1}° ({}; positive = left of \
            vertical) with concentration κ = {:.2} ({}); the convexity prior was π = {:.3} ({}) \
            and the lapse rate λ = {:.3} ({}). The log-likelihood was {:.2}; against the model \
            without a convexity prior (π = 0.5), ΔAIC = {:.2} and ΔBIC = {:.2} (positive values \
            favour a convexity prior).\n",
            d.trials,
            if d.participants > 1 { " in all" } else { "" },
            if d.practice_rows > 0 {
                format!(" ({} practice trials were not analysed)", d.practice_rows)
            } else {
                String::new()
            },
            io::PROGRAM_VERSION,
            if f.bootstrap > 0 {
                format!(
                    "; parametric-bootstrap percentile intervals from {} simulated data sets \
                    (seed {}) are given beside them in fit.json",
                    f.bootstrap, self.settings.seed
                )
            } else {
                String::new()
            },
            f.prior_tilt_deg.value,
            interval(f.prior_tilt_deg.ci95, 1).replace(" to ", "° to ") + "°",
            f.prior_kappa.value,
            interval(f.prior_kappa.ci95, 2),
            f.convexity_prior.value,
            interval(f.convexity_prior.ci95, 3),
            f.lapse.value,
            interval(f.lapse.ci95, 3),
            f.log_likelihood,
            f.delta_aic,
            f.delta_bic,
        );
        if f.nonparametric_prior.is_some() {
            text += "\nA smooth, non-parametric prior over light tilt (the odd harmonics 1, 3 and 5 of its log-density, with a roughness penalty, reported over 24 directions) was fitted as well, in the spirit of Stone, Kerrigan & Porrill (2009); bump/dimple judgements constrain only the odd part of the log-density (p(θ) against p(θ + 180°)), so its even part is not estimated.\n";
        }
        if !self.warnings.is_empty() {
            text += "\nNotes: ";
            text += &self.warnings.join("; ");
            text += ".\n";
        }
        text += "\n**References.** Adams, W. J., Graf, E. W., & Ernst, M. O. (2004). Experience can change the 'light-from-above' prior. *Nature Neuroscience*, 7, 1057–1058. \
            Mamassian, P., & Goutcher, R. (2001). Prior knowledge on the illumination position. *Cognition*, 81, B1–B9. \
            Stone, J. V., Kerrigan, I. S., & Porrill, J. (2009). Where is the light? Bayesian perceptual priors for lighting direction. *Proceedings of the Royal Society B*, 276, 1797–1804. \
            Sun, J., & Perona, P. (1998). Where is the sun? *Nature Neuroscience*, 1, 183–184.\n";
        text
    }

    /// Writes `fit.json` (the report, [`REPORT_FILE`]), `fit.png`, `fit.svg` and
    /// `methods.md` into the folder `dir` (which must exist).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let figure = self.figure();
        figure.write_png(&dir.join("fit.png"))?;
        figure.write_svg(&dir.join("fit.svg"))?;
        io::write_text(&dir.join("methods.md"), &self.methods())?;
        let value = serde_json::to_value(self)
            .map_err(|e| Error::Compute(format!("cannot serialise the fit: {e}")))?;
        io::write_json(&dir.join(REPORT_FILE), &value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_responses_name_their_line() {
        let p = Path::new("r.csv");
        for (csv, needle) in [
            ("", "empty"),
            ("rotation,response\n0,convex\n", "no 'rotation_deg' column"),
            (
                "rotation_deg,response\n0,yes\n",
                "line 2: unknown response 'yes'",
            ),
            (
                "rotation_deg,response\n0,convex\nx,concave\n",
                "line 3: rotation_deg 'x'",
            ),
            ("rotation_deg,response\n0,convex,9\n", "line 2: 3 fields"),
            ("rotation_deg,response\n\"0,convex\n", "never closed"),
            (
                "block,rotation_deg,response\npractice,0,convex\n",
                "only practice",
            ),
            (
                "block,rotation_deg,response\nwarmup,0,convex\n",
                "block 'warmup'",
            ),
            ("rotation_deg,response\nnan,convex\n", "not a finite number"),
        ] {
            let e = parse_responses(csv, p).unwrap_err().to_string();
            assert!(e.contains(needle), "{csv:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let ok = "participant,trial,block,stimulus,rotation_deg,response,rt_ms,key,image\n\
                  a,1,practice,disc,0,convex,500,f,img/0.png\n\
                  a,2,test,disc,15,1,512,f,\"img/a,b.png\"\n\
                  b,1,test,disc,30,Concave,400,j,img/1.png\n";
        let r = parse_responses(ok, p).unwrap();
        assert_eq!(r.practice_rows, 1);
        assert_eq!(
            r.participants,
            vec![
                ("a".into(), vec![(15.0, true)]),
                ("b".into(), vec![(30.0, false)])
            ]
        );
    }
}
