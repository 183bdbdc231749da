//! The observer fit as a pipeline (`shadelab fit observer`): read a responses CSV, fit the
//! observer model ([`crate::analysis::observer_model`]) pooled and per participant
//! ([`crate::analysis::fit`]), and write `fit.json`, a figure and a Methods paragraph.
//!
//! The responses CSV is what `shadelab experiment` writes: a header, then one row per trial.
//! Only `rotation_deg` (θ, the direction of the stimulus's bright side, degrees; 0 = up,
//! +90 = left) and `response` (`convex` | `concave`, or 1 | 0) are needed; a `block` column
//! keeps the `test` rows (and drops `practice`); a `participant` column gives one fit per
//! participant beside the pooled fit; a `simulated` column marks a pilot's rows, which are
//! left out unless [`Reading::include_simulated`]; a `design_hash` column tells designs
//! apart; other columns are ignored. What the reader left out, and why, is in the report's
//! [`Design`].
//!
//! ```
//! use shadelab::pipeline::fit::parse_responses;
//! let csv = "participant,rotation_deg,response\np1,0,convex\np1,180,concave\n";
//! let r = parse_responses(csv, std::path::Path::new("r.csv")).unwrap();
//! assert_eq!(r.participants, vec![("p1".to_string(), vec![(0.0, true), (180.0, false)])]);
//! ```

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::fit::{
    fit, simulate, Bin, BinSummary, Criteria, Estimate, FitOptions, ObserverFit, SmoothPrior,
};
pub use crate::analysis::observer_model::ModelParams;
// The fit's angles are reported in (−180°, 180°], the one wrapping rule.
pub use crate::analysis::wrap_180;

mod responses;

use responses::is_design;

pub use responses::{
    parse_data, parse_responses, read_responses, read_responses_with, DesignFiles, Duplicate,
    KeyMap, Reading, Responses, DATA_EXTENSIONS,
};

use super::CommandReport;
use crate::analysis::fit::bins;
use crate::error::{Error, Result};
use crate::io::{self, Stamp};
use crate::plot::{IntervalSeries, LineAndPolar, LinePlot, Marker, PolarPlot, Series};
use crate::progress::Progress;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What to fit, as plain values.
#[derive(Debug, Clone)]
pub struct Config {
    /// The responses: a CSV or JSON file (shadelab's responses CSV, or jsPsych's data as CSV
    /// or JSON), or a folder of them (one or more participants each).
    pub responses: PathBuf,
    /// How to fit.
    pub options: FitOptions,
    /// How to read the data: the key mapping, and whether simulated rows and several designs
    /// are taken.
    pub reading: Reading,
    /// The experiment's `design.json`, which the Methods paragraph describes (stimulus,
    /// apparatus, order); `None`: a `design.json` in the responses folder, if any.
    pub design: Option<PathBuf>,
    /// The responses' text itself (CSV or jsPsych JSON, as a file would hold it), read by the
    /// same parser instead of the file `responses`, which then only names the data in errors
    /// and the report (e.g. a table handed over from Python).
    pub text: Option<String>,
}

impl Config {
    /// The defaults ([`FitOptions::default`]) for `responses`.
    pub fn new(responses: &Path) -> Config {
        Config {
            responses: responses.to_path_buf(),
            options: FitOptions::default(),
            reading: Reading::default(),
            design: None,
            text: None,
        }
    }
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
    /// jsPsych rows that are not trials (instructions, fixation, breaks, a lab's own), left out.
    pub other_rows: usize,
    /// Test trials without a response (timed out: `response` null or empty), left out.
    pub no_response_rows: usize,
    /// Simulated test trials (a pilot's: their `simulated` column set) left out.
    pub simulated_rows_left_out: usize,
    /// Simulated test trials fitted (with [`Reading::include_simulated`]), among `trials`.
    pub simulated_trials: usize,
    /// Participants with simulated trials fitted, among `participants`.
    pub simulated_participants: usize,
    /// Rows read twice (the same rows in two files) and counted once.
    pub duplicates: Vec<Duplicate>,
    /// The designs of the trials (their `design_hash`), each with its files: one, or several
    /// pooled with [`Reading::mixed_designs`]; none where the data carry no hash.
    pub designs: Vec<DesignFiles>,
    /// The data files read.
    pub files: Vec<String>,
}

impl Design {
    /// What was read but not analysed, in the order the Methods name it: the one wording of
    /// the fit's warnings and of its Methods paragraph.
    fn left_out(&self) -> Vec<LeftOut> {
        [
            LeftOut::Practice(self.practice_rows),
            LeftOut::NoResponse(self.no_response_rows),
            LeftOut::Simulated(self.simulated_rows_left_out),
            LeftOut::Repeated(self.duplicates.iter().map(|r| r.rows).sum()),
        ]
        .into_iter()
        .filter(|l| l.count() > 0)
        .collect()
    }
}

/// Rows of the data that the fit read and left out, with their count.
#[derive(Debug, Clone, Copy)]
enum LeftOut {
    /// Practice trials (never analysed).
    Practice(usize),
    /// Test trials without a response.
    NoResponse(usize),
    /// Simulated test trials (without [`Reading::include_simulated`]).
    Simulated(usize),
    /// Rows a second copy of the same data repeated (each duplicate also has its own warning).
    Repeated(usize),
}

impl LeftOut {
    fn count(&self) -> usize {
        match *self {
            LeftOut::Practice(n)
            | LeftOut::NoResponse(n)
            | LeftOut::Simulated(n)
            | LeftOut::Repeated(n) => n,
        }
    }

    /// Whether leaving these out is worth a warning: practice rows are meant to be left out,
    /// and each repeated file has a warning of its own.
    fn warned(&self) -> bool {
        matches!(self, LeftOut::NoResponse(_) | LeftOut::Simulated(_))
    }
}

impl std::fmt::Display for LeftOut {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            LeftOut::Practice(n) => write!(f, "{n} practice trials"),
            LeftOut::NoResponse(n) => write!(f, "{n} trials without a response (timed out)"),
            LeftOut::Simulated(n) => write!(f, "{n} simulated trials (a pilot's)"),
            LeftOut::Repeated(n) => {
                write!(f, "{n} rows that a second copy of the same data repeated")
            }
        }
    }
}

/// The spread of the per-participant fits: a two-stage (summary-statistics) random-effects
/// description of the group, beside the pooled fit (which treats every trial as one observer's).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GroupSummary {
    /// Participants fitted individually.
    pub participants: usize,
    /// The circular mean of their μ, degrees in (−180, 180].
    pub prior_tilt_mean_deg: f64,
    /// The circular standard deviation of their μ, √(−2 ln R̄), degrees.
    pub prior_tilt_sd_deg: f64,
    /// A 95% interval for the group's mean μ: mean ± t(n−1) · sd / √n (degrees; `None` with
    /// fewer than two participants).
    pub prior_tilt_mean_ci95: Option<[f64; 2]>,
    /// The mean of their κ.
    pub prior_kappa_mean: f64,
    /// The standard deviation of their κ (0 for one participant).
    pub prior_kappa_sd: f64,
    /// The median of their κ.
    pub prior_kappa_median: f64,
    /// The mean of their convexity priors π.
    pub convexity_prior_mean: f64,
    /// The standard deviation of their π.
    pub convexity_prior_sd: f64,
}

/// The 0.975 quantile of Student's t with `df` degrees of freedom (1.96 beyond 30).
fn t975(df: usize) -> f64 {
    const T: [f64; 30] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160,
        2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056,
        2.052, 2.048, 2.045, 2.042,
    ];
    T.get(df.wrapping_sub(1)).copied().unwrap_or(1.96)
}

/// The group's spread from the per-participant fits (`None` without any).
pub fn group_summary(fits: &[ParticipantFit]) -> Option<GroupSummary> {
    let n = fits.len();
    if n == 0 {
        return None;
    }
    let nf = n as f64;
    let (mut c, mut s) = (0.0, 0.0);
    for f in fits {
        let t = f.fit.prior_tilt_deg.value.to_radians();
        c += t.cos();
        s += t.sin();
    }
    let (c, s) = (c / nf, s / nf);
    let r = c.hypot(s).clamp(1e-12, 1.0);
    let mean = s.atan2(c).to_degrees();
    let sd = (-2.0 * r.ln()).max(0.0).sqrt().to_degrees();
    let stats = |values: Vec<f64>| {
        let m = values.iter().sum::<f64>() / nf;
        let var = if n > 1 {
            values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (nf - 1.0)
        } else {
            0.0
        };
        (m, var.sqrt(), values)
    };
    let (k_mean, k_sd, mut kappas) = stats(fits.iter().map(|f| f.fit.prior_kappa.value).collect());
    kappas.sort_by(f64::total_cmp);
    let k_median = if n % 2 == 1 {
        kappas[n / 2]
    } else {
        (kappas[n / 2 - 1] + kappas[n / 2]) / 2.0
    };
    let (p_mean, p_sd, _) = stats(fits.iter().map(|f| f.fit.convexity_prior.value).collect());
    let half = t975(n.saturating_sub(1)) * sd / nf.sqrt();
    Some(GroupSummary {
        participants: n,
        prior_tilt_mean_deg: mean,
        prior_tilt_sd_deg: sd,
        prior_tilt_mean_ci95: (n > 1).then_some([mean - half, mean + half]),
        prior_kappa_mean: k_mean,
        prior_kappa_sd: k_sd,
        prior_kappa_median: k_median,
        convexity_prior_mean: p_mean,
        convexity_prior_sd: p_sd,
    })
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
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The responses file.
    pub responses: String,
    /// The model, in words.
    pub model: &'static str,
    /// The design read from the data.
    pub design: Design,
    /// How the data were read.
    pub reading: Reading,
    /// How it was fitted.
    pub settings: FitOptions,
    /// The pooled fit.
    #[serde(flatten)]
    pub pooled: ObserverFit,
    /// One fit per participant (when there are several).
    pub participants: Vec<ParticipantFit>,
    /// The spread of the per-participant fits (when there are several).
    pub group: Option<GroupSummary>,
    /// The experiment's design (`design.json`), when given or found beside the data: what the
    /// Methods paragraph describes.
    pub experiment: Option<serde_json::Value>,
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
    let responses = match &config.text {
        Some(text) => parse_data(text, &config.responses, &config.reading, "")?,
        None => read_responses_with(&config.responses, &config.reading)?,
    };
    let design_file = config.design.clone().or_else(|| {
        let beside = config.responses.join(super::experiment::MARKER);
        (config.responses.is_dir() && is_design(&beside)).then_some(beside)
    });
    let experiment = match &design_file {
        Some(path) => {
            let v: serde_json::Value = serde_json::from_slice(&io::read_bytes(path)?)
                .map_err(|e| Error::format(path, format!("not JSON: {e}")))?;
            if v["program"] != "shadelab" || !v["trials"].is_array() {
                return Err(Error::format(
                    path,
                    "not a shadelab experiment's design.json",
                ));
            }
            Some(v)
        }
        None => None,
    };
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
    for d in &responses.duplicates {
        warnings.push(format!(
            "participant '{}': the same {} rows are in {} and in {}; counted once (from {})",
            d.participant, d.rows, d.kept, d.left_out, d.kept
        ));
    }
    if responses.designs.len() > 1 {
        warnings.push(format!(
            "{} designs pooled (another design_hash): {}",
            responses.designs.len(),
            responses
                .designs
                .iter()
                .map(DesignFiles::to_string)
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    if responses.simulated_fitted > 0 {
        warnings.push(format!(
            "{} of the {} trials fitted are simulated (a pilot's), not people's",
            responses.simulated_fitted,
            all.len()
        ));
    }
    let per = pooled_bins.iter().map(|b| b.trials);
    let design = Design {
        trials: all.len(),
        participants: responses.participants.len(),
        rotations_deg: pooled_bins.iter().map(|b| b.rotation_deg).collect(),
        trials_per_rotation: [per.clone().min().unwrap_or(0), per.max().unwrap_or(0)],
        practice_rows: responses.practice_rows,
        other_rows: responses.other_rows,
        no_response_rows: responses.no_response,
        simulated_rows_left_out: responses.simulated_left_out,
        simulated_trials: responses.simulated_fitted,
        simulated_participants: responses.simulated_participants,
        duplicates: responses.duplicates.clone(),
        designs: responses.designs.clone(),
        files: responses
            .files
            .iter()
            .map(|f| f.display().to_string())
            .collect(),
    };
    warnings.extend(
        design
            .left_out()
            .into_iter()
            .filter(LeftOut::warned)
            .map(|l| format!("{l} left out")),
    );
    for b in &pooled.at_bounds {
        warnings.push(format!(
            "the pooled estimate of {b} lies at the bound of the search"
        ));
    }
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
        stamp: Stamp::of("fit observer"),
        responses: name,
        model: MODEL,
        design,
        reading: config.reading.clone(),
        settings: config.options,
        pooled,
        group: if several {
            group_summary(&participants)
        } else {
            None
        },
        participants,
        experiment,
        study,
        warnings,
        outputs: BTreeMap::from([
            ("fit.json", "the estimates with 95% intervals, log-likelihood, AIC/BIC against the model without a convexity prior, counts per rotation, per-participant fits"),
            ("fit.png", "proportion convex per rotation (95% Wilson intervals), the fitted curve, and the fitted prior over light tilt on a polar plot (also .svg)"),
            ("participants.png", "with several participants: each participant's fitted curve beside the pooled one (also .svg)"),
            ("methods.md", "a Methods paragraph: design, model, estimates, citations"),
        ]),
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The header of a responses CSV, as `shadelab experiment` writes it.
pub const RESPONSES_HEADER: &str = super::experiment::CSV_HEADER;

/// A simulated responses CSV (the format [`parse_responses`] reads): `repeats` test trials at
/// each of `rotations` answered by the observer model `model` with draws from a generator
/// seeded with `seed`, in a seeded random order; `rt_ms` is 0 and `key`, `image` and
/// `design_hash` are empty (nothing was shown), and every row's `simulated` says so, as the
/// study's pilot mode does (`tilt:26,kappa:2,convex:0.5,lapse:0.02,seed:1`): the fit leaves
/// the rows out unless [`Reading::include_simulated`].
///
/// ```
/// use shadelab_analysis::analysis::observer_model::ModelParams;
/// use shadelab::pipeline::fit::{parse_data, parse_responses, simulated_responses, Reading};
/// let m = ModelParams { tilt_deg: 26.0, kappa: 2.0, convexity_prior: 0.5, lapse: 0.02 };
/// let csv = simulated_responses(&m, &[0.0, 90.0, 180.0, 270.0], 5, 1, "sim");
/// let path = std::path::Path::new("sim.csv");
/// assert!(parse_responses(&csv, path).is_err(), "a pilot's rows only");
/// let pilot = Reading { include_simulated: true, ..Reading::default() };
/// let r = parse_data(&csv, path, &pilot, "").unwrap();
/// assert_eq!((r.participants[0].1.len(), r.simulated_fitted), (20, 20));
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
    // Said as the study page's pilot mode says it (its `simulate` URL parameter).
    let simulated = io::csv_field(&format!(
        "tilt:{},kappa:{},convex:{},lapse:{},seed:{seed}",
        model.tilt_deg, model.kappa, model.convexity_prior, model.lapse
    ));
    for (i, &r) in order.iter().enumerate() {
        let convex = rng.next_f64() < model.p_convex(r);
        csv.push_str(&format!(
            "{},{},test,simulated,{r},{},0,,,,{simulated}\n",
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

/// The stimulus and apparatus paragraph, from an experiment's design.json.
fn apparatus(e: &serde_json::Value) -> String {
    let num = |v: &serde_json::Value| v.as_f64().map_or("?".to_string(), |x| format!("{x}"));
    let d = &e["display"];
    let keys = &e["keys"];
    let key = |k: &str| keys[k].as_str().unwrap_or("?").to_uppercase();
    let breaks = e["break_every"].as_u64().unwrap_or(0);
    format!(
        "\n**Stimulus and apparatus.** Each trial showed one shaded `{}` (shadelab {}), \
        {} × {} degrees of visual angle (height × width; {} pixels per degree at a viewing \
        distance of {} cm, set for each participant by a credit-card calibration, jsPsych's \
        virtual chinrest, where they made one), lit at a slant of {}° from the line of sight and \
        turned so that its bright side faced θ, on a uniform background of the images' own grey \
        ({}); the 8-bit images were encoded for a display gamma of {} and the luminance of the \
        participants' screens was not calibrated. After a fixation cross ({} ms) the image \
        stayed until the participant pressed {} (bump) or {} (dimple){}. The study ran in the \
        browser on jsPsych {} ({} practice and {} test trials{}; each rotation shown {} \
        time(s)), \
        the practice and the test trials each in the participant's own random order, drawn \
        from a seed made of the design's seed ({}) and the participant's id.\n",
        e["stimulus"].as_str().unwrap_or("?"),
        e["version"].as_str().unwrap_or("?"),
        num(&d["visual_size"][0]),
        num(&d["visual_size"][1]),
        num(&d["ppd"]),
        num(&d["viewing_distance_cm"]),
        num(&e["light_slant_deg"]),
        d["background"].as_str().unwrap_or("?"),
        d["gamma"]
            .as_f64()
            .map_or("none (linear values)".to_string(), |g| g.to_string()),
        num(&e["timing"]["fixation_ms"]),
        key("convex"),
        key("concave"),
        if e["counterbalance_keys"] == true {
            " (the keys swapped for half of the participants)"
        } else {
            ""
        },
        e["jspsych"]["jspsych"].as_str().unwrap_or("8"),
        num(&e["practice_trials"]),
        num(&e["test_trials"]),
        if breaks > 0 && (breaks as f64) < e["test_trials"].as_f64().unwrap_or(0.0) {
            format!(", a break after every {breaks}")
        } else {
            String::new()
        },
        num(&e["repeats"]),
        num(&e["seed"]),
    )
}

/// `[lo, hi]` as text, or "not estimated".
fn interval(ci: Option<[f64; 2]>, decimals: usize) -> String {
    match ci {
        Some([lo, hi]) => format!("95% CI {lo:.decimals$} to {hi:.decimals$}"),
        None => "fixed".into(),
    }
}

/// Empty axes of P(convex) against the direction of the bright side θ, 0..360°.
fn p_convex_axes(title: &str) -> LinePlot {
    let mut line = LinePlot::new(
        title,
        "direction of the bright side θ (°, 0 = up, 90 = left)",
        "P(convex) (proportion)",
        (0.0, 360.0),
    );
    line.y_range = Some((-0.02, 1.02));
    line.reference_y = Some(0.5);
    line.x_ticks = crate::plot::Ticks::Degrees;
    line
}

impl Report {
    /// The figure: proportions convex with Wilson intervals and the fitted curve against θ
    /// (0–360°), and the fitted prior over light tilt (and the smooth prior, when fitted) on a
    /// polar plot.
    pub(crate) fn figure(&self) -> LineAndPolar {
        let f = &self.pooled;
        let m = f.params();
        let mut line =
            p_convex_axes("Proportion 'convex' against the direction of the bright side");
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

    /// Every participant's fitted curve beside the pooled one (`None` with one participant).
    pub(crate) fn participants_figure(&self) -> Option<LinePlot> {
        if self.participants.is_empty() {
            return None;
        }
        let curve = |m: &ModelParams| {
            (0..=360)
                .map(|d| (d as f64, m.p_convex(d as f64)))
                .collect()
        };
        let mut line = p_convex_axes("Each participant's fitted P(convex)");
        let m = self.pooled.params();
        line.series.push(Series {
            name: format!("pooled fit: μ = {:.0}°, κ = {:.2}", m.tilt_deg, m.kappa),
            points: curve(&m),
        });
        for p in &self.participants {
            let m = p.fit.params();
            line.series.push(Series {
                name: format!(
                    "participant {}: μ = {:.0}°, κ = {:.2}",
                    p.participant, m.tilt_deg, m.kappa
                ),
                points: curve(&m),
            });
        }
        Some(line)
    }

    /// The Methods paragraph (Markdown). The fitted μ is set beside the published values it
    /// compares with (docs/priors.md's table): Mamassian & Goutcher (2001), 26° left on
    /// average, and McManus, Buckman & Woolley (2004), 9° left combined.
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
        // Simulated responses are never described as people's judgements.
        let all_simulated = d.simulated_trials == d.trials;
        let (one, many) = if all_simulated {
            ("a simulated observer", "simulated observers")
        } else {
            ("One participant", "participants")
        };
        let some_simulated = d.simulated_participants > 0 && !all_simulated;
        let people = if some_simulated {
            let k = d.simulated_participants;
            format!(
                "{} {} and {k} simulated observer{}",
                d.participants - k,
                if d.participants - k == 1 {
                    "participant"
                } else {
                    "participants"
                },
                if k == 1 { "" } else { "s" }
            )
        } else {
            format!("{} {many}", d.participants)
        };
        let who = if d.participants > 1 {
            format!("{people} ({} fitted individually)", self.participants.len())
        } else {
            one.into()
        };
        let (opening, judged) = if all_simulated {
            (
                "These responses were simulated, not given by people: ",
                " (the observer model of shadelab's pilot mode) answered",
            )
        } else if some_simulated {
            ("", " answered")
        } else {
            ("", " judged")
        };
        let simulated = if d.simulated_trials > 0 && !all_simulated {
            format!(
                " {} of these trials were simulated (a pilot's rows, answered by the observer \
                 model), not judged by people.",
                d.simulated_trials
            )
        } else {
            String::new()
        };
        let mut left_out: Vec<String> = d.left_out().iter().map(LeftOut::to_string).collect();
        let left_out = match left_out.len() {
            0 => String::new(),
            1 => format!(" ({} were not analysed)", left_out[0]),
            _ => {
                let last = left_out.pop().unwrap_or_default();
                format!(" ({} and {last} were not analysed)", left_out.join(", "))
            }
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
            **Design.** {opening}{who}{judged} whether a shaded disc was a bump (convex) or a \
            dimple (concave) in {} test trials{}: {rotations}, {repeats}{left_out}.{simulated} The \
            direction θ of the bright side is given in the tilt convention (0° = up, +90° = \
            left).\n\n\
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
            vertical; compare: Mamassian & Goutcher 2001, 26° left on average; McManus, \
            Buckman & Woolley 2004, 9° left over a single bubble and a 16-bubble pop-out \
            combined) with concentration κ = {:.2} ({}); the convexity prior was π = {:.3} ({}) \
            and the lapse rate λ = {:.3} ({}). The log-likelihood was {:.2}; against the model \
            without a convexity prior (π = 0.5), ΔAIC = {:.2} and ΔBIC = {:.2} (positive values \
            favour a convexity prior).\n",
            d.trials,
            if d.participants > 1 { " in all" } else { "" },
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
        if let Some(g) = &self.group {
            text += &format!(
                "\n**Group.** Across the {} participants fitted individually, the light prior's \
                direction had a circular mean of {:.1}°{} and a circular standard deviation of \
                {:.1}°; κ had a mean of {:.2} (SD {:.2}, median {:.2}) and the convexity prior a \
                mean of {:.3} (SD {:.3}). (A two-stage summary of the individual fits; the pooled \
                fit above treats all trials as one observer's.)\n",
                g.participants,
                g.prior_tilt_mean_deg,
                g.prior_tilt_mean_ci95
                    .map(|[lo, hi]| format!(" (95% CI {lo:.1}° to {hi:.1}°)"))
                    .unwrap_or_default(),
                g.prior_tilt_sd_deg,
                g.prior_kappa_mean,
                g.prior_kappa_sd,
                g.prior_kappa_median,
                g.convexity_prior_mean,
                g.convexity_prior_sd,
            );
        }
        if let Some(e) = &self.experiment {
            text += &apparatus(e);
        }
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
}

impl CommandReport for Report {
    /// The report, `fit.json`.
    const MARKER: &'static str = "fit.json";

    /// Writes `fit.json` (the report, [`Report::MARKER`]), `fit.png`, `fit.svg` and
    /// `methods.md` (and `participants.png`/`.svg` for a folder of participants).
    fn write_into(&self, dir: &Path) -> Result<()> {
        let figure = self.figure();
        figure.write_png(&dir.join("fit.png"))?;
        figure.write_svg(&dir.join("fit.svg"))?;
        if let Some(each) = self.participants_figure() {
            each.write_png(&dir.join("participants.png"))?;
            each.write_svg(&dir.join("participants.svg"))?;
        }
        io::write_text(&dir.join("methods.md"), &self.methods())?;
        let value = serde_json::to_value(self)
            .map_err(|e| Error::Compute(format!("cannot serialise the fit: {e}")))?;
        io::write_json(&dir.join(Self::MARKER), &value)
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

    #[test]
    fn jspsych_data_are_read_with_their_key_mapping() {
        let p = Path::new("d.csv");
        // jsPsych's CSV (every field quoted, CRLF, "null" for missing values): the rows
        // without a rotation are other screens; keys from the rows.
        let csv = "\"trial_type\",\"shadelab\",\"block\",\"rotation_deg\",\"response\",\"key_convex\",\"key_concave\",\"participant\"\r\n\
                   \"html-button-response\",\"consent\",\"\",\"\",\"0\",\"\",\"\",\"A\"\r\n\
                   \"html-keyboard-response\",\"fixation\",\"\",\"null\",\"null\",\"\",\"\",\"A\"\r\n\
                   \"image-keyboard-response\",\"trial\",\"practice\",\"90\",\"f\",\"f\",\"j\",\"A\"\r\n\
                   \"image-keyboard-response\",\"trial\",\"test\",\"0\",\"f\",\"f\",\"j\",\"A\"\r\n\
                   \"image-keyboard-response\",\"trial\",\"test\",\"180\",\"j\",\"f\",\"j\",\"A\"\r\n\
                   \"image-keyboard-response\",\"trial\",\"test\",\"90\",\"j\",\"j\",\"f\",\"A\"\r\n";
        let r = parse_data(csv, p, &Reading::default(), "").unwrap();
        assert_eq!(
            r.participants,
            vec![("A".into(), vec![(0.0, true), (180.0, false), (90.0, true)])]
        );
        assert_eq!((r.practice_rows, r.other_rows), (1, 2));
        // The same as jsPsych's JSON; a participant named by the file when no column says.
        let json = r#"[{"trial_type":"html-button-response","response":0},
            {"trial_type":"image-keyboard-response","block":"test","rotation_deg":0,"response":"a"},
            {"trial_type":"image-keyboard-response","block":"test","rotation_deg":180,"response":"L"}]"#;
        let e = parse_data(json, p, &Reading::default(), "p7")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("row 2: unknown response 'a'") && e.contains("give the keys"),
            "{e}"
        );
        let keys = Reading {
            keys: Some(KeyMap::parse("a,l").unwrap()),
            ..Reading::default()
        };
        let r = parse_data(json, p, &keys, "p7").unwrap();
        assert_eq!(
            r.participants,
            vec![("p7".into(), vec![(0.0, true), (180.0, false)])]
        );
        // A press that is neither key is named.
        let fj = Reading {
            keys: Some(KeyMap::parse("fj").unwrap()),
            ..Reading::default()
        };
        let e = parse_data(json, p, &fj, "").unwrap_err().to_string();
        assert!(e.contains("row 2: response 'a' is neither"), "{e}");
        assert!(KeyMap::parse("ff").is_err() && KeyMap::parse("fjk").is_err());
        assert!(parse_data("[1]", p, &Reading::default(), "")
            .unwrap_err()
            .to_string()
            .contains("row 1"));
        assert!(parse_data("{\"x\": 1}", p, &Reading::default(), "").is_err());
    }

    #[test]
    fn the_group_summary_is_circular_for_the_direction() {
        // One fitted participant (bump seen when lit from above), its estimates then set.
        let trials: Vec<(f64, bool)> = (0..240)
            .map(|i| {
                (
                    (i % 24) as f64 * 15.0,
                    (i % 24) < 7 || (i % 24) > 19 || i % 7 == 0,
                )
            })
            .collect();
        let options = FitOptions {
            bootstrap: 0,
            ..FitOptions::default()
        };
        let carrier = fit(&bins(&trials), &options, "x").unwrap();
        let fit = |tilt: f64, kappa: f64| {
            let f = carrier.clone();
            let mut f = f;
            f.prior_tilt_deg.value = tilt;
            f.prior_kappa.value = kappa;
            ParticipantFit {
                participant: format!("{tilt}"),
                fit: f,
            }
        };
        let g = group_summary(&[fit(350.0, 1.0), fit(10.0, 3.0)]).unwrap();
        assert!(g.prior_tilt_mean_deg.abs() < 1e-9, "{g:?}");
        assert!((g.prior_tilt_sd_deg - 10.0).abs() < 0.2, "{g:?}");
        assert_eq!((g.prior_kappa_mean, g.prior_kappa_median), (2.0, 2.0));
        let [lo, hi] = g.prior_tilt_mean_ci95.unwrap();
        assert!(lo < 0.0 && hi > 0.0);
        assert!(group_summary(&[]).is_none());
    }
}
