//! Studies: a grid of stimuli × parameters × slants × priors, run whole or in shards, merged
//! into exactly the files a single run writes.
//!
//! A *grid point* is one picture at one assumed slant: a stimulus with one value for each of
//! its varied parameters. Each point costs one prior sweep; the priors and rotations that the
//! observer then applies to that sweep are cheap and are rows of the same point. Points are
//! numbered in the spec's order (stimuli in order, then their parameters, keys in alphabetical
//! order with the last varying fastest, then the slants), and shard i of n runs the points
//! with number ≡ i (mod n), which spreads expensive stimuli over the shards. Every row starts
//! with its point's number and every computation is deterministic, so the merge, a stable sort
//! of the shards' rows by point, is byte-identical to the unsharded run.
//!
//! The spec is JSON (unknown keys are refused):
//!
//! ```json
//! {
//!   "stimuli": [
//!     {"stimulus": "bumps", "params": {"pattern": ["bumps", "dimples"], "rows": 1, "columns": 1},
//!      "shape": [64, 64], "seed": 0}
//!   ],
//!   "tilts": "0:360:15",
//!   "slants": [45],
//!   "priors": {"tilt": [26], "kappa": [1, 2], "convexity_bias": [0]},
//!   "rotations": "0:360:45",
//!   "noise": 0.05,
//!   "boundary": "flat",
//!   "domain": "image"
//! }
//! ```
//!
//! A parameter given as a list is a grid axis; anything else is held fixed.

use super::interpretation::{analysis_solve_options, Scene};
use super::observer::{observe, LightPrior, ObserverOptions};
use super::parse_angles;
use super::picture::{Domain, Picture};
use super::prior_sweep::sweep;
use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::io;
use crate::visual_size::SizeRequest;
use md5::{Digest, Md5};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

/// The file that holds a study folder's report (and marks it as shadelab's).
pub const REPORT: &str = "study.json";
/// The observer's results: one row per point × prior × rotation × token.
pub const RESULTS: &str = "results.csv";
/// The raw sweeps: one row per point × assumed tilt × token.
pub const SWEEP: &str = "sweep.csv";

/// The most grid points a study may have.
pub const MAX_POINTS: usize = 1_000_000;

/// A study spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// The stimuli, each with fixed and varied parameters.
    pub stimuli: Vec<StimulusEntry>,
    /// Assumed light tilts of each sweep (`START:STOP:STEP` or a list; they must cover the
    /// circle in equal steps for the observer).
    #[serde(default = "default_tilts")]
    pub tilts: String,
    /// Assumed light slants, degrees; each is a grid axis.
    #[serde(default = "default_slants")]
    pub slants: Vec<f64>,
    /// The observer's priors (every combination).
    #[serde(default)]
    pub priors: PriorGrid,
    /// Picture rotations the observer judges (degrees counter-clockwise).
    #[serde(default = "default_rotations")]
    pub rotations: String,
    /// Image noise σ of the observer's likelihood.
    #[serde(default = "default_noise")]
    pub noise: f64,
    /// Boundary condition: `flat`, `free` or `occluding`.
    #[serde(default = "default_boundary")]
    pub boundary: String,
    /// Solve domain: `image` or `tokens`.
    #[serde(default = "default_domain")]
    pub domain: String,
}

fn default_tilts() -> String {
    "0:360:15".into()
}
fn default_slants() -> Vec<f64> {
    vec![45.0]
}
fn default_rotations() -> String {
    "0".into()
}
fn default_noise() -> f64 {
    super::observer::DEFAULT_NOISE
}
fn default_boundary() -> String {
    "flat".into()
}
fn default_domain() -> String {
    "image".into()
}

/// One stimulus of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StimulusEntry {
    /// The stimulus name.
    pub stimulus: String,
    /// Parameters: a list is a grid axis, anything else a fixed value.
    #[serde(default)]
    pub params: Map<String, Value>,
    /// Visual size (width, height) in degrees.
    #[serde(default)]
    pub visual_size: Option<(f64, f64)>,
    /// Pixels per degree.
    #[serde(default)]
    pub ppd: Option<f64>,
    /// Size (width, height) in pixels.
    #[serde(default)]
    pub shape: Option<(usize, usize)>,
    /// Random seed.
    #[serde(default)]
    pub seed: u64,
}

/// The observer priors of a study: every combination is applied to every point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorGrid {
    /// Prior mean tilts, degrees.
    #[serde(default = "default_prior_tilt")]
    pub tilt: Vec<f64>,
    /// Prior concentrations κ.
    #[serde(default = "default_prior_kappa")]
    pub kappa: Vec<f64>,
    /// Convexity biases B (log odds).
    #[serde(default = "default_bias")]
    pub convexity_bias: Vec<f64>,
}

fn default_prior_tilt() -> Vec<f64> {
    vec![super::observer::DEFAULT_PRIOR_TILT_DEG]
}
fn default_prior_kappa() -> Vec<f64> {
    vec![super::observer::DEFAULT_PRIOR_KAPPA]
}
fn default_bias() -> Vec<f64> {
    vec![0.0]
}

impl Default for PriorGrid {
    fn default() -> Self {
        PriorGrid {
            tilt: default_prior_tilt(),
            kappa: default_prior_kappa(),
            convexity_bias: default_bias(),
        }
    }
}

/// One grid point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Its number in the study.
    pub index: usize,
    /// Which stimulus entry it comes from.
    pub entry: usize,
    /// The stimulus parameters at this point.
    pub params: Map<String, Value>,
    /// The assumed slant.
    pub slant_deg: f64,
}

/// Which part of a study to run: shard `index` of `count` (0 ≤ index < count).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Shard {
    /// This shard, from 0.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl Shard {
    /// The whole study.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `I/N` (e.g. `$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT`).
    pub fn parse(text: &str) -> Result<Shard> {
        let bad = |why: &str| {
            Error::invalid(format!(
                "--shard '{text}': {why} (give I/N with 0 ≤ I < N, e.g. 0/4)"
            ))
        };
        let (i, n) = text.trim().split_once('/').ok_or_else(|| bad("no '/'"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| bad("I is not a whole number"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if count == 0 {
            return Err(bad("N must be at least 1"));
        }
        if index >= count {
            return Err(bad(&format!("shard {index} does not exist among {count}")));
        }
        Ok(Shard { index, count })
    }

    /// Whether this shard runs point `index`.
    pub fn runs(&self, index: usize) -> bool {
        index % self.count == self.index
    }
}

/// A checked spec with its expanded grid.
#[derive(Debug, Clone)]
pub struct Study {
    /// The spec as given.
    pub spec: StudySpec,
    /// The md5 of the spec's canonical JSON: shards of one study share it.
    pub spec_md5: String,
    /// The assumed tilts.
    pub tilts: Vec<f64>,
    /// The rotations.
    pub rotations: Vec<f64>,
    /// The boundary condition.
    pub boundary: Boundary,
    /// The domain.
    pub domain: Domain,
    /// Every grid point, in order.
    pub points: Vec<Point>,
    /// The largest picture a point may make, in pixels (`--max-pixels`).
    pub max_pixels: usize,
}

impl Study {
    /// Reads and checks a spec file, with pictures of at most the default number of pixels.
    pub fn load(path: &Path) -> Result<Study> {
        Study::load_with_max_pixels(path, crate::grid::DEFAULT_MAX_PIXELS)
    }

    /// Reads and checks a spec file whose pictures may have up to `max_pixels` pixels.
    pub fn load_with_max_pixels(path: &Path, max_pixels: usize) -> Result<Study> {
        let bytes = io::read_bytes(path)?;
        let spec: StudySpec = serde_json::from_slice(&bytes)
            .map_err(|e| Error::format(path, format!("bad study spec: {e}")))?;
        Study::new_with_max_pixels(spec, max_pixels).map_err(|e| match e {
            Error::Invalid(m) => Error::format(path, m),
            Error::Unknown { kind, name, valid } => {
                Error::format(path, format!("unknown {kind} '{name}' (valid: {valid})"))
            }
            other => other,
        })
    }

    /// Checks a spec and expands its grid. Every stimulus is checked by name and parameters
    /// here, so a bad spec fails before any work.
    pub fn new(spec: StudySpec) -> Result<Study> {
        Study::new_with_max_pixels(spec, crate::grid::DEFAULT_MAX_PIXELS)
    }

    /// [`Study::new`] with pictures of up to `max_pixels` pixels; each stimulus's size is
    /// resolved here too, so that an impossible size fails before any work.
    pub fn new_with_max_pixels(spec: StudySpec, max_pixels: usize) -> Result<Study> {
        if spec.stimuli.is_empty() {
            return Err(Error::invalid("the study has no stimuli"));
        }
        let tilts = parse_angles(&spec.tilts, "tilts")?;
        if super::prior_sweep::circle_step(&tilts).is_none() {
            return Err(Error::invalid(format!(
                "tilts '{}' must cover the circle in equal steps for the observer (e.g. 0:360:15)",
                spec.tilts
            )));
        }
        let rotations = parse_angles(&spec.rotations, "rotations")?;
        if spec.slants.is_empty() {
            return Err(Error::invalid("slants is empty: give at least one"));
        }
        for &s in &spec.slants {
            if !(s.is_finite() && (0.0..90.0).contains(&s)) {
                return Err(Error::invalid(format!("slant {s} must be in 0..90")));
            }
        }
        let p = &spec.priors;
        if p.tilt.is_empty() || p.kappa.is_empty() || p.convexity_bias.is_empty() {
            return Err(Error::invalid(
                "priors: tilt, kappa and convexity_bias each need at least one value",
            ));
        }
        for prior in prior_combinations(p) {
            ObserverOptions {
                prior,
                noise: spec.noise,
            }
            .validate()?;
        }
        let boundary = match spec.boundary.as_str() {
            "flat" | "free" | "occluding" => Boundary::named(&spec.boundary)?,
            other => {
                return Err(Error::unknown(
                    "boundary",
                    other,
                    &["flat", "free", "occluding"],
                ))
            }
        };
        let domain: Domain = spec.domain.parse()?;
        let mut points = Vec::new();
        for (entry_index, entry) in spec.stimuli.iter().enumerate() {
            let info = crate::stimulus::find(&entry.stimulus)?.info();
            let combos = param_combinations(&entry.params)?;
            for combo in combos {
                // Checked now against the stimulus's declarations, so typos fail at once.
                crate::params::Params::resolve(&info.params, &combo)
                    .map_err(|e| Error::invalid(format!("{}: {e}", entry.stimulus)))?;
                let size = SizeRequest {
                    visual_size: entry.visual_size,
                    ppd: entry.ppd,
                    shape: entry.shape,
                };
                crate::stimulus::prepare(&entry.stimulus, &combo, &size, entry.seed, max_pixels)
                    .map_err(|e| match e {
                        Error::Invalid(m) => Error::invalid(format!("{}: {m}", entry.stimulus)),
                        other => other,
                    })?;
                for &slant in &spec.slants {
                    if points.len() >= MAX_POINTS {
                        return Err(Error::invalid(format!(
                            "the study has more than {MAX_POINTS} grid points"
                        )));
                    }
                    points.push(Point {
                        index: points.len(),
                        entry: entry_index,
                        params: combo.clone(),
                        slant_deg: slant,
                    });
                }
            }
        }
        let canonical = serde_json::to_string(&spec)
            .map_err(|e| Error::Compute(format!("cannot serialise the spec: {e}")))?;
        let spec_md5 = Md5::digest(canonical.as_bytes())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(Study {
            spec,
            spec_md5,
            tilts,
            rotations,
            boundary,
            domain,
            points,
            max_pixels,
        })
    }

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
        let size = SizeRequest {
            visual_size: entry.visual_size,
            ppd: entry.ppd,
            shape: entry.shape,
        };
        let (request, output) = crate::stimulus::generate(
            &entry.stimulus,
            &point.params,
            &size,
            entry.seed,
            self.max_pixels,
        )?;
        let picture = Picture::from_stimulus(&request, &output)?;
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

    /// The report of a run of `shard`.
    pub fn report(&self, shard: Shard, output: &StudyOutput, seconds: f64) -> Value {
        json!({
            "program": "shadelab",
            "version": io::PROGRAM_VERSION,
            "command": "study run",
            "spec": self.spec,
            "spec_md5": self.spec_md5,
            "shard": shard,
            "point_count": self.points.len(),
            "points": output.points,
            "files": {
                RESULTS: "observer: P(convex) per point × prior × rotation × token",
                SWEEP: "prior sweep: convexity, residual e_R, smoothness e_S per point × assumed tilt × token",
            },
            "seconds": seconds,
        })
    }
}

/// The header of `results.csv`.
pub const RESULTS_HEADER: &str = "point,stimulus,params,slant_deg,prior_tilt_deg,prior_kappa,convexity_bias,rotation_deg,token,p_convex,map_tilt_deg\n";
/// The header of `sweep.csv`.
pub const SWEEP_HEADER: &str =
    "point,stimulus,params,slant_deg,tilt_deg,token,convexity,residual,smoothness,surface_residual,converged\n";

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

/// Every combination of the priors, tilt slowest and bias fastest.
fn prior_combinations(p: &PriorGrid) -> Vec<LightPrior> {
    let mut out = Vec::new();
    for &mean_tilt_deg in &p.tilt {
        for &kappa in &p.kappa {
            for &convexity_bias in &p.convexity_bias {
                out.push(LightPrior {
                    mean_tilt_deg,
                    kappa,
                    convexity_bias,
                });
            }
        }
    }
    out
}

/// Every combination of the parameters: lists are axes (keys in alphabetical order, the last
/// varying fastest), other values fixed.
fn param_combinations(params: &Map<String, Value>) -> Result<Vec<Map<String, Value>>> {
    let mut combos = vec![Map::new()];
    let mut keys: Vec<&String> = params.keys().collect();
    keys.sort();
    for key in keys {
        let values = match &params[key.as_str()] {
            Value::Array(v) if v.is_empty() => {
                return Err(Error::invalid(format!(
                    "parameter {key}: an empty list gives no grid points"
                )))
            }
            Value::Array(v) => v.clone(),
            other => vec![other.clone()],
        };
        let mut next = Vec::with_capacity(combos.len() * values.len());
        for c in &combos {
            for v in &values {
                let mut m = c.clone();
                m.insert(key.clone(), v.clone());
                next.push(m);
            }
        }
        if next.len() > MAX_POINTS {
            return Err(Error::invalid(format!(
                "the study has more than {MAX_POINTS} grid points"
            )));
        }
        combos = next;
    }
    Ok(combos)
}

/// Parameters as `key=value;key=value` (strings unquoted).
fn params_text(params: &Map<String, Value>) -> String {
    let mut keys: Vec<&String> = params.keys().collect();
    keys.sort();
    keys.iter()
        .map(|k| match &params[k.as_str()] {
            Value::String(s) => format!("{k}={s}"),
            v => format!("{k}={v}"),
        })
        .collect::<Vec<_>>()
        .join(";")
}

/// A CSV field, quoted when it holds a comma, quote or line break (RFC 4180).
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// What a merge produces.
#[derive(Debug, Clone, PartialEq)]
pub struct Merged {
    /// `results.csv`, byte-identical to an unsharded run's.
    pub results: String,
    /// `sweep.csv`, byte-identical to an unsharded run's.
    pub sweep: String,
    /// The merge report.
    pub report: Value,
}

/// Merges the output folders of every shard of one study.
///
/// Fails, naming the folder, when one is not a study output, when they come from different
/// specs or shard counts, or when a shard is missing or given twice.
pub fn merge(dirs: &[PathBuf]) -> Result<Merged> {
    if dirs.is_empty() {
        return Err(Error::invalid("give the shard folders to merge"));
    }
    let mut shards: Vec<(Shard, &PathBuf)> = Vec::new();
    let mut spec: Option<(String, Value, usize)> = None;
    for dir in dirs {
        let path = dir.join(REPORT);
        if !path.exists() {
            return Err(Error::format(
                dir,
                format!("not a study output folder (no {REPORT} in it)"),
            ));
        }
        let report: Value = serde_json::from_slice(&io::read_bytes(&path)?)
            .map_err(|e| Error::format(&path, format!("bad study report: {e}")))?;
        let md5 = report["spec_md5"].as_str().unwrap_or_default().to_string();
        let index = report["shard"]["index"].as_u64();
        let count = report["shard"]["count"].as_u64();
        let points = report["point_count"].as_u64();
        let (Some(index), Some(count), Some(points), false) =
            (index, count, points, md5.is_empty())
        else {
            return Err(Error::format(
                &path,
                "bad study report: no spec_md5, shard or point_count",
            ));
        };
        let shard = Shard {
            index: index as usize,
            count: count as usize,
        };
        match &spec {
            None => spec = Some((md5, report["spec"].clone(), points as usize)),
            Some((m, _, _)) if *m != md5 => {
                return Err(Error::format(
                    dir,
                    format!(
                        "comes from a different study spec than {} (spec md5 {md5} vs {m})",
                        dirs[0].display()
                    ),
                ))
            }
            Some(_) => {}
        }
        if let Some((first, _)) = shards.first() {
            if first.count != shard.count {
                return Err(Error::format(
                    dir,
                    format!(
                        "is shard {}/{} but {} is one of {}",
                        shard.index,
                        shard.count,
                        dirs[0].display(),
                        first.count
                    ),
                ));
            }
        }
        if let Some((_, other)) = shards.iter().find(|(s, _)| s.index == shard.index) {
            return Err(Error::format(
                dir,
                format!(
                    "is shard {}/{}, as is {}",
                    shard.index,
                    shard.count,
                    other.display()
                ),
            ));
        }
        shards.push((shard, dir));
    }
    let count = shards[0].0.count;
    let missing: Vec<String> = (0..count)
        .filter(|i| !shards.iter().any(|(s, _)| s.index == *i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!(
            "cannot merge: shard{} {} missing",
            if missing.len() > 1 { "s" } else { "" },
            missing.join(", ")
        )));
    }
    shards.sort_by_key(|(s, _)| s.index);
    let join = |file: &str, header: &str| -> Result<String> {
        let mut rows: Vec<(usize, String)> = Vec::new();
        for (_, dir) in &shards {
            let path = dir.join(file);
            let text = String::from_utf8(io::read_bytes(&path)?)
                .map_err(|_| Error::format(&path, "not UTF-8 text"))?;
            let mut lines = text.split_inclusive('\n');
            if lines.next() != Some(header) {
                return Err(Error::format(
                    &path,
                    "unexpected header: not a study CSV of this version",
                ));
            }
            for line in lines {
                let point = line
                    .split(',')
                    .next()
                    .and_then(|p| p.parse::<usize>().ok())
                    .ok_or_else(|| {
                        Error::format(
                            &path,
                            format!("row without a point number: {}", line.trim_end()),
                        )
                    })?;
                rows.push((point, line.to_string()));
            }
        }
        // Stable: rows of one point keep their order (they all come from one shard).
        rows.sort_by_key(|(p, _)| *p);
        let mut out = String::from(header);
        for (_, line) in rows {
            out.push_str(&line);
        }
        Ok(out)
    };
    let results = join(RESULTS, RESULTS_HEADER)?;
    let sweep_csv = join(SWEEP, SWEEP_HEADER)?;
    let (md5, spec_value, point_count) = spec.unwrap_or_default();
    Ok(Merged {
        results,
        sweep: sweep_csv,
        report: json!({
            "program": "shadelab",
            "version": io::PROGRAM_VERSION,
            "command": "study merge",
            "spec": spec_value,
            "spec_md5": md5,
            "shard": Shard::WHOLE,
            "point_count": point_count,
            "merged_from": shards.iter().map(|(s, d)| json!({
                "folder": d.display().to_string(),
                "shard": s,
            })).collect::<Vec<_>>(),
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> Result<Study> {
        let spec: StudySpec = serde_json::from_str(text)
            .map_err(|e| Error::invalid(format!("bad study spec: {e}")))?;
        Study::new(spec)
    }

    #[test]
    fn shards_parse_and_partition() {
        assert_eq!(Shard::parse("2/4").unwrap(), Shard { index: 2, count: 4 });
        for bad in ["3/2", "2/2", "0/0", "1", "a/b", "-1/3", "1/x"] {
            let e = Shard::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--shard") && e.contains(bad), "{e}");
        }
        let shards: Vec<Shard> = (0..3).map(|i| Shard { index: i, count: 3 }).collect();
        for p in 0..10 {
            assert_eq!(shards.iter().filter(|s| s.runs(p)).count(), 1);
        }
    }

    #[test]
    fn the_grid_expands_in_order_and_bad_specs_fail() {
        let s = spec(
            r#"{"stimuli":[{"stimulus":"bumps","params":{"rows":1,"columns":1,
               "pattern":["bumps","dimples"],"height":[0.5,1]}}],"slants":[30,45]}"#,
        )
        .unwrap();
        assert_eq!(s.points.len(), 8);
        // Keys alphabetical (height before pattern), last fastest, then slants.
        assert_eq!(s.points[0].params["height"], json!(0.5));
        assert_eq!(s.points[0].slant_deg, 30.0);
        assert_eq!(s.points[1].slant_deg, 45.0);
        assert_eq!(s.points[2].params["pattern"], json!("dimples"));
        assert_eq!(s.points[4].params["height"], json!(1));
        assert_eq!(
            params_text(&s.points[0].params),
            "columns=1;height=0.5;pattern=bumps;rows=1"
        );
        for (bad, needle) in [
            (
                r#"{"stimuli":[{"stimulus":"bumps"}],"colour":1}"#,
                "unknown field",
            ),
            (r#"{"stimuli":[{"stimulus":"teapot"}]}"#, "teapot"),
            (
                r#"{"stimuli":[{"stimulus":"bumps","params":{"radius":[]}}]}"#,
                "empty list",
            ),
            (
                r#"{"stimuli":[{"stimulus":"bumps","params":{"hue":1}}]}"#,
                "hue",
            ),
            (
                r#"{"stimuli":[{"stimulus":"bumps"}],"tilts":"0:180:15"}"#,
                "cover the circle",
            ),
            (r#"{"stimuli":[]}"#, "no stimuli"),
            (r#"{"stimuli":[{"stimulus":"bumps"}],"noise":0}"#, "noise"),
        ] {
            let e = spec(bad).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }

    #[test]
    fn csv_fields_are_quoted_when_needed() {
        assert_eq!(csv_field("bump r1c1"), "bump r1c1");
        assert_eq!(
            csv_field("light=tilt=0,slant=45"),
            "\"light=tilt=0,slant=45\""
        );
        assert_eq!(csv_field("a\"b"), "\"a\"\"b\"");
    }
}
