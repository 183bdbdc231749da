//! The lightness benchmark as a pipeline: every lightness model on every stimulus of a set of
//! published stimuli with human data (stimupy's `papers.RHS2007` and `papers.murray2020`),
//! scored against the people's reports (see [`crate::lightness::benchmark`] for the scores and
//! docs/lightness.md for the results).
//!
//! shadelab holds no human value: the stimuli and the data come from stimupy through an
//! export folder (`stimuli.json` with `.npy` images and target masks) that the Python package
//! writes (`python3 -m shadelab._benchmark_data DIR`, also run by the `benchmark` command).

use super::CommandReport;
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Labels};
use crate::io::{self, Stamp};
use crate::lightness::benchmark::{effect, spearman};
use crate::lightness::Model;
use crate::plot::{Figure, IntervalSeries, LinePlot, Series, Ticks};
use crate::progress::Progress;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;
use std::time::Instant;

/// The file that marks an output folder as written by the benchmark.
pub const MARKER: &str = "benchmark.json";

/// The export folder's index, written by `shadelab._benchmark_data`.
pub const EXPORT_INDEX: &str = "stimuli.json";

/// What people reported for one stimulus.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Human {
    /// RHS2007's effect strength: how much lighter the lighter target was matched than the
    /// darker one (0 = no effect).
    EffectStrength {
        /// The effect strength.
        value: f64,
    },
    /// murray2020's mean proportion of judgements in the expected direction, with the half
    /// width of its 95 % confidence interval.
    ProportionExpected {
        /// The mean proportion (0..1).
        value: f64,
        /// Half the width of the 95 % confidence interval.
        ci95: f64,
    },
}

impl Human {
    /// The reported value (effect strength or proportion).
    pub fn value(&self) -> f64 {
        match *self {
            Human::EffectStrength { value } | Human::ProportionExpected { value, .. } => value,
        }
    }

    /// The direction the data show: +1 when the expected-lighter target was seen lighter, −1
    /// when the other was, 0 when there is no effect (an effect strength of 0, or a proportion
    /// whose 95 % interval holds ½; within [`NO_HUMAN_EFFECT`], not by exact equality).
    pub fn direction(&self) -> i8 {
        let (v, half) = match *self {
            Human::EffectStrength { value } => (value, 0.0),
            Human::ProportionExpected { value, ci95 } => (value - 0.5, ci95.abs()),
        };
        if v.abs() <= half + NO_HUMAN_EFFECT {
            0
        } else if v > 0.0 {
            1
        } else {
            -1
        }
    }

    /// Why the data show no direction, when they show none.
    fn why_no_direction(&self) -> Option<&'static str> {
        (self.direction() == 0).then_some(match self {
            Human::EffectStrength { .. } => "the human effect strength is 0",
            Human::ProportionExpected { .. } => "the proportion's 95 % interval holds 0.5",
        })
    }
}

/// A human effect strength or proportion difference this close to none is none.
pub const NO_HUMAN_EFFECT: f64 = 1e-12;

/// One stimulus with its human data.
#[derive(Debug, Clone)]
pub struct BenchmarkStimulus {
    /// The stimulus set (e.g. `RHS2007`).
    pub set: String,
    /// The stimulus's name in its set (e.g. `WE_thick`).
    pub name: String,
    /// The image, linear luminance 0..1.
    pub image: Image,
    /// The target mask (0 = no target).
    pub targets: Labels,
    /// Pixels per degree.
    pub ppd: f64,
    /// The label of the target the data's source expects people to see as lighter (RHS2007:
    /// the authors' `region.hi`; murray2020: the paper's expected target). The effect is
    /// measured from it, and the human value is stated for it.
    pub lighter: u16,
    /// The label of the other target.
    pub darker: u16,
    /// Where `lighter` was read: repository, commit and file, or the paper, page and figure
    /// (one line without commas: it is a CSV field).
    pub direction_source: String,
    /// Where the source's lighter region lies in the picture, in degrees from the picture's
    /// centre (x right, y up), when the exporter recorded it.
    pub source_position: Option<[f64; 2]>,
    /// Why the source itself calls the stimulus's direction unreliable (a control figure it
    /// calls ineffective), or `None`.
    pub no_direction: Option<String>,
    /// What people reported.
    pub human: Human,
}

impl BenchmarkStimulus {
    /// The target people saw as lighter: the expected one where the data show the expected
    /// effect, the other where they show the reverse, `None` where there is no reliable
    /// direction ([`BenchmarkStimulus::why_no_direction`]).
    pub fn human_lighter(&self) -> Option<u16> {
        if self.no_direction.is_some() {
            return None;
        }
        match self.human.direction() {
            1 => Some(self.lighter),
            -1 => Some(self.darker),
            _ => None,
        }
    }

    /// The human direction relative to the expected-lighter target: +1 (as expected), −1
    /// (reversed) or 0 (none).
    pub fn human_direction(&self) -> i8 {
        match self.human_lighter() {
            Some(l) if l == self.lighter => 1,
            Some(_) => -1,
            None => 0,
        }
    }

    /// Why there is no human direction: the source's reason, or the data's (an effect
    /// strength of 0, a proportion whose interval holds ½); `None` when there is one.
    pub fn why_no_direction(&self) -> Option<String> {
        self.no_direction
            .clone()
            .or_else(|| self.human.why_no_direction().map(str::to_string))
    }
}

/// What to run: stimuli, models and where the data came from.
#[derive(Debug, Clone)]
pub struct BenchmarkConfig {
    /// The stimuli, in order.
    pub stimuli: Vec<BenchmarkStimulus>,
    /// The models, in order.
    pub models: Vec<Model>,
    /// The stimupy version the stimuli and data came from.
    pub stimupy_version: String,
}

impl BenchmarkConfig {
    /// A checked configuration.
    pub fn new(
        stimuli: Vec<BenchmarkStimulus>,
        models: Vec<Model>,
        stimupy_version: String,
    ) -> Result<Self> {
        let config = BenchmarkConfig {
            stimuli,
            models,
            stimupy_version,
        };
        config.validate()?;
        Ok(config)
    }

    /// The models named in `text`, comma separated (`all` for every model).
    ///
    /// ```
    /// use shadelab::pipeline::benchmark::BenchmarkConfig;
    /// assert_eq!(BenchmarkConfig::parse_models("all").unwrap().len(), 5);
    /// assert_eq!(BenchmarkConfig::parse_models("odog,highpass").unwrap().len(), 2);
    /// assert!(BenchmarkConfig::parse_models("odog,nope").is_err());
    /// ```
    pub fn parse_models(text: &str) -> Result<Vec<Model>> {
        if text.trim().eq_ignore_ascii_case("all") {
            return Model::NAMES.iter().map(|n| n.parse()).collect();
        }
        text.split(',').map(|n| n.trim().parse()).collect()
    }

    /// Checks the models, the stimuli's sizes, resolutions and target labels.
    pub fn validate(&self) -> Result<()> {
        if self.models.is_empty() {
            return Err(Error::invalid("models: no lightness model to run"));
        }
        if self.stimuli.is_empty() {
            return Err(Error::invalid("stimuli: no stimulus to run"));
        }
        for s in &self.stimuli {
            let what = format!("stimulus {}/{}", s.set, s.name);
            s.targets.check_same_size(
                &format!("{what}: the target mask is"),
                &s.image,
                "the image is",
            )?;
            if !(s.ppd.is_finite() && s.ppd > 0.0) {
                return Err(Error::invalid(format!(
                    "{what}: ppd must be positive, not {}",
                    s.ppd
                )));
            }
            if s.lighter == s.darker {
                return Err(Error::invalid(format!(
                    "{what}: the lighter and the darker target are both label {}",
                    s.lighter
                )));
            }
            for l in [s.lighter, s.darker] {
                if l == 0 || !s.targets.data().contains(&l) {
                    return Err(Error::invalid(format!(
                        "{what}: no pixel has target label {l}"
                    )));
                }
            }
            if !s.human.value().is_finite() {
                return Err(Error::invalid(format!(
                    "{what}: the human value is not finite"
                )));
            }
            if s.direction_source.trim().is_empty()
                || s.direction_source.contains([',', '"', '\n', '\r'])
            {
                return Err(Error::invalid(format!(
                    "{what}: direction_source must be one line without commas or quotes, not {:?}",
                    s.direction_source
                )));
            }
            if s.source_position
                .is_some_and(|p| !p.iter().all(|v| v.is_finite()))
            {
                return Err(Error::invalid(format!(
                    "{what}: source_position must be two finite numbers"
                )));
            }
        }
        Ok(())
    }

    /// The stimuli and human data stimupy exports (run by `python`, which must have stimupy;
    /// see [`export_with_python`]), read into memory from a scratch folder that is removed
    /// afterwards, whatever happens; `only` as [`BenchmarkConfig::from_export`].
    pub fn from_stimupy(python: &str, models: Vec<Model>, only: &[String]) -> Result<Self> {
        let scratch = Scratch::new();
        export_with_python(python, &scratch.0, only)?;
        BenchmarkConfig::from_export(&scratch.0, models, only)
    }

    /// Reads an export folder (`stimuli.json` and its `.npy` files), keeping the stimuli
    /// named in `only` (`NAME` or `SET/NAME`; empty keeps all).
    pub fn from_export(dir: &Path, models: Vec<Model>, only: &[String]) -> Result<Self> {
        let index_path = dir.join(EXPORT_INDEX);
        let text = std::fs::read_to_string(&index_path).map_err(|e| Error::io(&index_path, e))?;
        let index: Value = serde_json::from_str(&text)
            .map_err(|e| Error::format(&index_path, format!("not JSON: {e}")))?;
        let bad = |m: &str| Error::format(&index_path, m.to_string());
        let version = index["stimupy_version"]
            .as_str()
            .ok_or_else(|| bad("no stimupy_version"))?
            .to_string();
        let list = index["stimuli"]
            .as_array()
            .ok_or_else(|| bad("no stimuli list"))?;
        let mut stimuli = Vec::new();
        for entry in list {
            let field = |k: &str| {
                entry[k]
                    .as_str()
                    .map(str::to_string)
                    .ok_or_else(|| bad(&format!("a stimulus has no {k}")))
            };
            let (set, name) = (field("set")?, field("name")?);
            let full = format!("{set}/{name}");
            if !only.is_empty() && !only.iter().any(|o| *o == name || *o == full) {
                continue;
            }
            let image =
                io::read_image(&dir.join(field("image")?), crate::grid::DEFAULT_MAX_PIXELS)?;
            let mask = io::read_image(&dir.join(field("mask")?), crate::grid::DEFAULT_MAX_PIXELS)?;
            let targets: Labels = mask.map(|v| v.round().clamp(0.0, 65535.0) as u16);
            let number = |k: &str| {
                entry[k]
                    .as_f64()
                    .ok_or_else(|| bad(&format!("{full}: no number {k}")))
            };
            let human: Human = serde_json::from_value(entry["human"].clone())
                .map_err(|e| bad(&format!("{full}: human data: {e}")))?;
            let target = |k: &str| -> Result<u16> {
                let v = number(k)?;
                if v.fract() != 0.0 || !(1.0..=65535.0).contains(&v) {
                    return Err(bad(&format!(
                        "{full}: {k} must be a target label from 1, not {v}"
                    )));
                }
                Ok(v as u16)
            };
            let source_position = match &entry["source_position"] {
                Value::Null => None,
                v => Some(serde_json::from_value::<[f64; 2]>(v.clone()).map_err(|_| {
                    bad(&format!(
                        "{full}: source_position must be [x, y] in degrees"
                    ))
                })?),
            };
            let no_direction = match &entry["no_direction"] {
                Value::Null => None,
                Value::String(why) => Some(why.clone()),
                _ => {
                    return Err(bad(&format!(
                        "{full}: no_direction must be a string or null"
                    )))
                }
            };
            stimuli.push(BenchmarkStimulus {
                set,
                name,
                image,
                targets,
                ppd: number("ppd")?,
                lighter: target("lighter_target")?,
                darker: target("darker_target")?,
                direction_source: field("direction_source")?,
                source_position,
                no_direction,
                human,
            });
        }
        if let Some(o) = only.iter().find(|o| {
            !stimuli
                .iter()
                .any(|s| s.name == **o || format!("{}/{}", s.set, s.name) == **o)
        }) {
            return Err(Error::unknown(
                "stimulus",
                o,
                &list
                    .iter()
                    .filter_map(|e| e["name"].as_str())
                    .collect::<Vec<_>>(),
            ));
        }
        BenchmarkConfig::new(stimuli, models, version)
    }
}

/// The exporter (`python/shadelab/_benchmark_data.py`), carried by the program so that the
/// command line needs only Python with stimupy and NumPy, not the shadelab package.
pub const EXPORTER: &str = include_str!("../../assets/_benchmark_data.py");

/// A scratch folder for one export, removed when dropped.
struct Scratch(std::path::PathBuf);

impl Scratch {
    fn new() -> Scratch {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        Scratch(std::env::temp_dir().join(format!(
            "shadelab-benchmark-{}-{nanos}-{n}",
            std::process::id()
        )))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs the exporter with the interpreter `python` into the folder `dir` (created), keeping
/// the stimuli named in `only`. Fails with one line saying how to install stimupy when the
/// interpreter or stimupy is missing.
pub fn export_with_python(python: &str, dir: &Path, only: &[String]) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let script = dir.join("benchmark_data.py");
    io::write_text(&script, EXPORTER)?;
    let out = std::process::Command::new(python)
        .arg(&script)
        .arg(dir)
        .args(only)
        .output()
        .map_err(|e| {
            Error::invalid(format!(
                "cannot run {python} ({e}): the benchmark needs Python 3 with stimupy \
                 (pip install stimupy==1.2.0)"
            ))
        })?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let last = stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no message")
            .trim();
        let last = last.strip_prefix("error: ").unwrap_or(last);
        return Err(Error::invalid(format!(
            "the stimupy exporter ({python}) failed: {last}"
        )));
    }
    Ok(())
}

/// Whether `python` can import stimupy (for tests and the command line's checks).
pub fn stimupy_available(python: &str) -> bool {
    std::process::Command::new(python)
        .args(["-c", "import stimupy, numpy"])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// How a model's effect on one stimulus compares with what people saw.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The effect has the human sign.
    Agrees,
    /// The effect has the opposite sign.
    Opposite,
    /// The effect is zero (within [`NO_MODEL_EFFECT`] of the output's range): the model
    /// predicts no difference, which is counted neither as agreeing nor as wrong.
    NoPrediction,
    /// People saw no reliable direction: not counted.
    NotCounted,
}

impl Verdict {
    /// The verdict on a model's `effect` where people saw the human direction `direction`
    /// (+1, −1, 0); `scale` is the range of the model's output on the stimulus.
    pub fn of(direction: i8, effect: f64, scale: f64) -> Verdict {
        if direction == 0 {
            Verdict::NotCounted
        } else if effect.abs() <= NO_MODEL_EFFECT * scale {
            Verdict::NoPrediction
        } else if effect.signum() == f64::from(direction) {
            Verdict::Agrees
        } else {
            Verdict::Opposite
        }
    }

    /// The name in the CSV and the JSON.
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Opposite => "opposite",
            Verdict::NoPrediction => "no_prediction",
            Verdict::NotCounted => "not_counted",
        }
    }

    /// The verdict named `name` (as [`Verdict::name`] writes it).
    pub fn from_name(name: &str) -> Option<Verdict> {
        [
            Verdict::Agrees,
            Verdict::Opposite,
            Verdict::NoPrediction,
            Verdict::NotCounted,
        ]
        .into_iter()
        .find(|v| v.name() == name)
    }
}

/// A model effect within this fraction of the range of the model's output on the stimulus is
/// no prediction (Retinex, for one, gives equal-luminance targets on flat surrounds exactly
/// or almost exactly the same value): a decision never rests on exact float equality.
pub const NO_MODEL_EFFECT: f64 = 1e-9;

/// One model on one stimulus.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchmarkRow {
    /// The stimulus set.
    pub set: String,
    /// The stimulus.
    pub stimulus: String,
    /// The model.
    pub model: String,
    /// The human value (RHS2007: effect strength; murray2020: proportion expected), stated
    /// for the expected-lighter target.
    pub human: f64,
    /// Half the 95 % interval of the human value, when the data give one.
    pub human_ci95: Option<f64>,
    /// The human direction relative to the expected-lighter target (+1, −1, or 0 for none).
    pub human_direction: i8,
    /// The target people saw as lighter (`None`: no reliable direction).
    pub human_lighter_target: Option<u16>,
    /// Where the expected-lighter target was read (repository, commit, file; or the paper's
    /// page and figure).
    pub direction_source: String,
    /// The model's effect: mean output over the expected-lighter target minus the other.
    pub effect: f64,
    /// How the effect compares with what people saw.
    pub verdict: Verdict,
}

/// One model's scores on one stimulus set.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchmarkScore {
    /// The stimulus set.
    pub set: String,
    /// The model.
    pub model: String,
    /// Stimuli on which the model's effect has the human sign.
    pub direction_agrees: usize,
    /// Stimuli with a human direction (those with none are left out).
    pub direction_counted: usize,
    /// Of those, the stimuli on which the model predicts no difference (effect zero): neither
    /// agreeing nor wrong.
    pub direction_no_prediction: usize,
    /// Spearman's ρ between the model's effects and the human values, over every stimulus
    /// of the set (those without a human direction too).
    pub spearman: Option<f64>,
    /// Stimuli in the set.
    pub stimuli: usize,
}

/// Which target of a stimulus people see as lighter, and where that was read.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchmarkDirection {
    /// The stimulus set.
    pub set: String,
    /// The stimulus.
    pub stimulus: String,
    /// The label of the target the source expects to look lighter.
    pub expected_lighter: u16,
    /// The label of the other target.
    pub expected_darker: u16,
    /// The target people saw as lighter (`None`: no reliable direction).
    pub human_lighter_target: Option<u16>,
    /// Why there is no reliable direction, when there is none.
    pub no_direction: Option<String>,
    /// Where the expected-lighter target was read.
    pub direction_source: String,
    /// Where the source's lighter region lies in the picture (degrees from its centre, x
    /// right, y up).
    pub source_position: Option<[f64; 2]>,
}

/// What the benchmark found; [`BenchmarkReport::write_into`] writes it.
#[derive(Debug, Clone, Serialize)]
pub struct BenchmarkReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The stimupy version the stimuli and human data came from.
    pub stimupy_version: String,
    /// The models, in order.
    pub models: Vec<String>,
    /// How the effect and the scores are defined.
    pub definitions: Vec<String>,
    /// Each model's scores per stimulus set.
    pub scores: Vec<BenchmarkScore>,
    /// Per stimulus, which target people see as lighter and where that was read.
    pub directions: Vec<BenchmarkDirection>,
    /// Every model on every stimulus.
    pub rows: Vec<BenchmarkRow>,
    /// Seconds taken in all.
    pub seconds: f64,
}

/// Runs every model on every stimulus and scores them.
pub fn run(config: &BenchmarkConfig, progress: &dyn Progress) -> Result<BenchmarkReport> {
    let started = Instant::now();
    config.validate()?;
    progress.start(
        (config.stimuli.len() * config.models.len()) as u64,
        "models × stimuli",
    );
    let mut rows = Vec::new();
    for s in &config.stimuli {
        let direction = s.human_direction();
        for model in &config.models {
            let out = model.predict(&s.image, Some(s.ppd))?;
            let e = effect(&out, &s.targets, s.lighter, s.darker)?.ok_or_else(|| {
                Error::invalid(format!("stimulus {}/{}: a target is empty", s.set, s.name))
            })?;
            rows.push(BenchmarkRow {
                set: s.set.clone(),
                stimulus: s.name.clone(),
                model: model.name().into(),
                human: s.human.value(),
                human_ci95: match s.human {
                    Human::ProportionExpected { ci95, .. } => Some(ci95),
                    Human::EffectStrength { .. } => None,
                },
                human_direction: direction,
                human_lighter_target: s.human_lighter(),
                direction_source: s.direction_source.clone(),
                effect: e,
                verdict: Verdict::of(direction, e, range(&out)),
            });
            progress.advance(1);
        }
    }
    progress.finish();
    Ok(BenchmarkReport {
        stamp: Stamp::of("benchmark"),
        stimupy_version: config.stimupy_version.clone(),
        models: config.models.iter().map(|m| m.name().into()).collect(),
        definitions: DEFINITIONS.iter().map(|s| s.to_string()).collect(),
        scores: scores(&rows),
        directions: config
            .stimuli
            .iter()
            .map(|s| BenchmarkDirection {
                set: s.set.clone(),
                stimulus: s.name.clone(),
                expected_lighter: s.lighter,
                expected_darker: s.darker,
                human_lighter_target: s.human_lighter(),
                no_direction: s.why_no_direction(),
                direction_source: s.direction_source.clone(),
                source_position: s.source_position,
            })
            .collect(),
        rows,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The range (largest minus smallest finite value) of a model's output.
fn range(out: &Image) -> f64 {
    let (lo, hi) = out
        .data()
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    if hi >= lo {
        hi - lo
    } else {
        0.0
    }
}

const DEFINITIONS: [&str; 5] = [
    "effect: mean model output over the target the data's source expects people to see as \
     lighter minus the mean over the other target; the exporter states that target per \
     stimulus with its source (directions): RHS2007 the authors' MATLAB code (region.hi in \
     srhande/flodog-models testpatterns/make_*.m), murray2020 Murray (2020) p. 6 and Figure 1",
    "human_lighter_target: the expected target where the data show the expected effect, the \
     other where they show the reverse, none where there is no reliable direction (an effect \
     strength of 0, a proportion whose 95 % interval holds 0.5, or a control figure the paper \
     calls ineffective)",
    "direction: the model agrees when its effect has the human sign; stimuli with no human \
     direction are not counted; an effect within 1e-9 of the range of the model's output is \
     no prediction, counted neither as agreeing nor as wrong",
    "spearman: rank correlation of the model's effects with RHS2007's effect strengths or \
     murray2020's proportions expected, over every stimulus of the set (those without a \
     human direction too)",
    "murray2020 stimuli are stimupy's at 16 pixels per degree (its 2 ppd pixels repeated)",
];

/// Each model's scores per set, sets and models in the order of `rows`.
pub fn scores(rows: &[BenchmarkRow]) -> Vec<BenchmarkScore> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.set.clone(), r.model.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(set, model)| {
            let mine: Vec<&BenchmarkRow> = rows
                .iter()
                .filter(|r| r.set == set && r.model == model)
                .collect();
            let count = |v: Verdict| mine.iter().filter(|r| r.verdict == v).count();
            let human: Vec<f64> = mine.iter().map(|r| r.human).collect();
            let model_effects: Vec<f64> = mine.iter().map(|r| r.effect).collect();
            BenchmarkScore {
                spearman: spearman(&human, &model_effects),
                stimuli: mine.len(),
                direction_agrees: count(Verdict::Agrees),
                direction_counted: mine.len() - count(Verdict::NotCounted),
                direction_no_prediction: count(Verdict::NoPrediction),
                set,
                model,
            }
        })
        .collect()
}

/// The columns of `benchmark.csv`.
pub const CSV_HEADER: &str = "set,stimulus,model,human,human_ci95,human_direction,\
                              human_lighter_target,direction_source,effect,verdict";

/// The rows as CSV (numbers written so that they read back exactly; `none` where people saw
/// no reliable direction).
pub fn rows_csv(rows: &[BenchmarkRow]) -> String {
    let mut csv = format!("{CSV_HEADER}\n");
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{}\n",
            r.set,
            r.stimulus,
            r.model,
            r.human,
            r.human_ci95.map(|v| v.to_string()).unwrap_or_default(),
            r.human_direction,
            r.human_lighter_target
                .map_or_else(|| "none".to_string(), |t| t.to_string()),
            r.direction_source,
            r.effect,
            r.verdict.name()
        ));
    }
    csv
}

/// Reads `benchmark.csv` back (`path` names it in errors).
pub fn parse_rows_csv(text: &str, path: &Path) -> Result<Vec<BenchmarkRow>> {
    let mut lines = text.lines();
    if lines.next() != Some(CSV_HEADER) {
        return Err(Error::format(
            path,
            format!("the header is not {CSV_HEADER}"),
        ));
    }
    lines
        .enumerate()
        .map(|(i, line)| {
            let f: Vec<&str> = line.split(',').collect();
            let bad = || Error::format(path, format!("line {}: cannot read {line:?}", i + 2));
            if f.len() != 10 {
                return Err(bad());
            }
            let num = |s: &str| s.parse::<f64>().map_err(|_| bad());
            Ok(BenchmarkRow {
                set: f[0].into(),
                stimulus: f[1].into(),
                model: f[2].into(),
                human: num(f[3])?,
                human_ci95: if f[4].is_empty() {
                    None
                } else {
                    Some(num(f[4])?)
                },
                human_direction: f[5].parse().map_err(|_| bad())?,
                human_lighter_target: if f[6] == "none" {
                    None
                } else {
                    Some(f[6].parse().map_err(|_| bad())?)
                },
                direction_source: f[7].into(),
                effect: num(f[8])?,
                verdict: Verdict::from_name(f[9]).ok_or_else(bad)?,
            })
        })
        .collect()
}

impl BenchmarkReport {
    /// The scores and the per-stimulus table as Markdown (the table docs/lightness.md shows).
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "Scores (shadelab {}, stimupy {}): direction = stimuli where the model's effect \
             has the human sign / stimuli with a human direction (in brackets: of those, the \
             ones where the model predicts no difference, counted neither way); ρ = Spearman \
             rank correlation with the human values over every stimulus of the set.\n\n\
             | model | RHS2007 direction | RHS2007 ρ | murray2020 direction | murray2020 ρ |\n\
             |---|---|---|---|---|\n",
            self.stamp.version, self.stimupy_version
        );
        let cell = |set: &str, model: &str| -> (String, String) {
            match self
                .scores
                .iter()
                .find(|s| s.set == set && s.model == model)
            {
                Some(s) => (
                    format!(
                        "{} / {}{}",
                        s.direction_agrees,
                        s.direction_counted,
                        if s.direction_no_prediction > 0 {
                            format!(" ({} no prediction)", s.direction_no_prediction)
                        } else {
                            String::new()
                        }
                    ),
                    s.spearman
                        .map(|r| format!("{r:.2}"))
                        .unwrap_or_else(|| "–".into()),
                ),
                None => ("–".into(), "–".into()),
            }
        };
        for m in &self.models {
            let (rd, rr) = cell("RHS2007", m);
            let (md_, mr) = cell("murray2020", m);
            md.push_str(&format!("| {m} | {rd} | {rr} | {md_} | {mr} |\n"));
        }
        md.push_str(
            "\nEach model's effect per stimulus, measured from the target the source expects to \
             look lighter (*expected*; ✓ = human direction, ✗ = opposite, 0 = no prediction, · = \
             no human direction); *seen lighter* = the target people saw as lighter (`none`: no \
             reliable direction); the sources are listed below the table:\n\n\
             | # | set | stimulus | human | expected | seen lighter |",
        );
        for m in &self.models {
            md.push_str(&format!(" {m} |"));
        }
        md.push_str("\n|---|---|---|---|---|---|");
        md.push_str(&"---|".repeat(self.models.len()));
        md.push('\n');
        let order = self.stimulus_order();
        for (i, (set, name)) in order.iter().enumerate() {
            let Some(first) = self
                .rows
                .iter()
                .find(|r| &r.set == set && &r.stimulus == name)
            else {
                continue;
            };
            let human = match first.human_ci95 {
                Some(ci) => format!("{:.3} ± {:.3}", first.human, ci),
                None => format!("{}", first.human),
            };
            let direction = self
                .directions
                .iter()
                .find(|d| &d.set == set && &d.stimulus == name);
            let expected = direction.map_or_else(|| "–".into(), |d| d.expected_lighter.to_string());
            let seen = first
                .human_lighter_target
                .map_or_else(|| "none".to_string(), |t| t.to_string());
            md.push_str(&format!(
                "| {} | {set} | {name} | {human} | {expected} | {seen} |",
                i + 1
            ));
            for m in &self.models {
                let cell = self
                    .rows
                    .iter()
                    .find(|r| &r.set == set && &r.stimulus == name && &r.model == m)
                    .map(|r| {
                        let mark = match r.verdict {
                            Verdict::Agrees => "✓",
                            Verdict::Opposite => "✗",
                            Verdict::NoPrediction => "0",
                            Verdict::NotCounted => "·",
                        };
                        format!("{:+.3} {mark}", r.effect)
                    })
                    .unwrap_or_default();
                md.push_str(&format!(" {cell} |"));
            }
            md.push('\n');
        }
        md.push_str("\nWhere each expected target was read, and why a stimulus has no human direction:\n\n| # | stimulus | source | no direction because |\n|---|---|---|---|\n");
        for (i, (set, name)) in order.iter().enumerate() {
            if let Some(d) = self
                .directions
                .iter()
                .find(|d| &d.set == set && &d.stimulus == name)
            {
                md.push_str(&format!(
                    "| {} | {set}/{name} | {} | {} |\n",
                    i + 1,
                    d.direction_source,
                    d.no_direction.as_deref().unwrap_or("")
                ));
            }
        }
        md
    }

    /// The stimuli in the order of the rows, each once.
    pub fn stimulus_order(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = Vec::new();
        for r in &self.rows {
            let k = (r.set.clone(), r.stimulus.clone());
            if !out.contains(&k) {
                out.push(k);
            }
        }
        out
    }

    /// The figure: one panel per stimulus set, the stimuli numbered as in the Markdown table
    /// along x, and the human values and each model's effects scaled to their largest
    /// magnitude in the set (so that the shapes compare; the signs are the data's).
    pub(crate) fn figure(&self) -> Figure {
        let order = self.stimulus_order();
        let mut panels = Vec::new();
        let mut sets: Vec<&str> = Vec::new();
        for (s, _) in &order {
            if !sets.contains(&s.as_str()) {
                sets.push(s);
            }
        }
        for set in sets {
            let numbered: Vec<(usize, &String)> = order
                .iter()
                .enumerate()
                .filter(|(_, (s, _))| s == set)
                .map(|(i, (_, n))| (i + 1, n))
                .collect();
            let (lo, hi) = (numbered[0].0 as f64, numbered[numbered.len() - 1].0 as f64);
            let human_label = if set == "murray2020" {
                "proportion expected − 0.5 (95 % CI)"
            } else {
                "effect strength"
            };
            let mut plot = LinePlot::new(
                &format!(
                    "{set}: human {human_label} and model effects, each scaled to its largest"
                ),
                "stimulus (numbered as in the table)",
                "effect / largest effect in the set",
                (lo - 0.5, hi + 0.5),
            );
            plot.x_ticks = Ticks::Integer;
            plot.reference_y = Some(0.0);
            plot.reference_label = "no effect".into();
            plot.y_range = Some((-1.6, 1.6));
            let rows_of = |model: &str| -> Vec<&BenchmarkRow> {
                self.rows
                    .iter()
                    .filter(|r| r.set == set && r.model == model)
                    .collect()
            };
            let first_model = &self.models[0];
            let human_rows = rows_of(first_model);
            let offset = if set == "murray2020" { 0.5 } else { 0.0 };
            let hmax = human_rows
                .iter()
                .map(|r| (r.human - offset).abs() + r.human_ci95.unwrap_or(0.0))
                .fold(0.0f64, f64::max)
                .max(1e-12);
            for m in &self.models {
                let rows = rows_of(m);
                let emax = rows
                    .iter()
                    .map(|r| r.effect.abs())
                    .fold(0.0f64, f64::max)
                    .max(1e-300);
                plot.series.push(Series {
                    name: m.clone(),
                    points: rows
                        .iter()
                        .map(|r| (number_of(&order, r) as f64, r.effect / emax))
                        .collect(),
                });
            }
            plot.intervals.push(IntervalSeries {
                name: "human".into(),
                points: human_rows
                    .iter()
                    .map(|r| {
                        let y = (r.human - offset) / hmax;
                        let ci = r.human_ci95.unwrap_or(0.0) / hmax;
                        (number_of(&order, r) as f64, y, y - ci, y + ci)
                    })
                    .collect(),
            });
            plot.size = (1100, 520);
            panels.push(plot);
        }
        Figure {
            size: (1100, 520 * panels.len() as u32),
            panels,
        }
    }
}

impl CommandReport for BenchmarkReport {
    const MARKER: &'static str = MARKER;

    /// Writes `benchmark.json`, `benchmark.csv` (every model on every stimulus),
    /// `scores.csv`, `benchmark.md` and, in builds with plots, `benchmark.png` into `dir`, a
    /// folder already prepared (see [`crate::io::AtomicDir`]).
    fn write_into(&self, dir: &Path) -> Result<()> {
        io::write_text(&dir.join("benchmark.csv"), &rows_csv(&self.rows))?;
        let mut scores =
            String::from("set,model,direction_agrees,direction_counted,direction_no_prediction,spearman,stimuli\n");
        for s in &self.scores {
            scores.push_str(&format!(
                "{},{},{},{},{},{},{}\n",
                s.set,
                s.model,
                s.direction_agrees,
                s.direction_counted,
                s.direction_no_prediction,
                s.spearman.map(|r| r.to_string()).unwrap_or_default(),
                s.stimuli
            ));
        }
        io::write_text(&dir.join("scores.csv"), &scores)?;
        io::write_text(&dir.join("benchmark.md"), &self.markdown())?;
        if cfg!(feature = "plots") {
            self.figure().write_png(&dir.join("benchmark.png"))?;
        }
        let json = serde_json::to_value(self)
            .map_err(|e| Error::Compute(format!("cannot serialise the report: {e}")))?;
        io::write_json(&dir.join(MARKER), &json)
    }
}

fn number_of(order: &[(String, String)], row: &BenchmarkRow) -> usize {
    order
        .iter()
        .position(|(s, n)| *s == row.set && *n == row.stimulus)
        .map_or(0, |i| i + 1)
}

/// A synthetic stimulus for tests and examples: two grey targets, one on black and one on
/// white (simultaneous contrast; the one on black looks lighter), `size` pixels square.
pub fn contrast_stimulus(name: &str, size: usize, ppd: f64, human: Human) -> BenchmarkStimulus {
    let (q, h) = (size / 4, size / 2);
    let inside = |c: usize, r: usize, x0: usize| {
        (x0..x0 + q / 2).contains(&c) && (h - q / 4..h + q / 4).contains(&r)
    };
    let image = Grid::from_fn(size, size, |c, r| {
        if inside(c, r, q - q / 4) || inside(c, r, h + q - q / 4) {
            0.5
        } else if c < h {
            0.0
        } else {
            1.0
        }
    });
    let targets = Grid::from_fn(size, size, |c, r| {
        if inside(c, r, q - q / 4) {
            1
        } else if inside(c, r, h + q - q / 4) {
            2
        } else {
            0
        }
    });
    BenchmarkStimulus {
        set: "synthetic".into(),
        name: name.into(),
        image,
        targets,
        ppd,
        lighter: 1,
        darker: 2,
        direction_source: "simultaneous contrast (synthetic)".into(),
        source_position: None,
        no_direction: None,
        human,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn human_directions_and_bad_configs() {
        assert_eq!(Human::EffectStrength { value: 4.2 }.direction(), 1);
        assert_eq!(Human::EffectStrength { value: 0.0 }.direction(), 0);
        assert_eq!(Human::EffectStrength { value: 1e-15 }.direction(), 0);
        let p = |value, ci95| Human::ProportionExpected { value, ci95 }.direction();
        assert_eq!(
            (p(0.95, 0.07), p(0.4875, 0.15), p(0.35, 0.1478)),
            (1, 0, -1)
        );
        let s = contrast_stimulus("sbc", 32, 8.0, Human::EffectStrength { value: 1.0 });
        let e = BenchmarkConfig::new(vec![s.clone()], vec![], "x".into()).unwrap_err();
        assert!(e.to_string().starts_with("models:"), "{e}");
        let mut same = s.clone();
        same.darker = same.lighter;
        let e = BenchmarkConfig::new(vec![same], vec![Model::Retinex], "x".into()).unwrap_err();
        assert!(e.to_string().contains("both label 1"), "{e}");
        let mut wrong = s.clone();
        wrong.darker = 7;
        let e = BenchmarkConfig::new(vec![wrong], vec![Model::Retinex], "x".into()).unwrap_err();
        assert!(e.to_string().contains("label 7"), "{e}");
        let mut comma = s;
        comma.direction_source = "a, b".into();
        let e = BenchmarkConfig::new(vec![comma], vec![Model::Retinex], "x".into()).unwrap_err();
        assert!(e.to_string().contains("direction_source"), "{e}");
    }

    #[test]
    fn the_seen_lighter_target_follows_the_data_and_the_sources_reason() {
        let mut s = contrast_stimulus("sbc", 32, 8.0, Human::EffectStrength { value: 1.0 });
        assert_eq!((s.human_lighter(), s.human_direction()), (Some(1), 1));
        assert_eq!(s.why_no_direction(), None);
        s.human = Human::ProportionExpected {
            value: 0.35,
            ci95: 0.1,
        };
        // Significantly below ½: people chose the other target.
        assert_eq!((s.human_lighter(), s.human_direction()), (Some(2), -1));
        s.no_direction = Some("a control the paper calls ineffective".into());
        assert_eq!((s.human_lighter(), s.human_direction()), (None, 0));
        assert_eq!(
            s.why_no_direction().unwrap(),
            "a control the paper calls ineffective"
        );
        s.no_direction = None;
        s.human = Human::EffectStrength { value: 0.0 };
        assert_eq!(s.human_lighter(), None);
        assert!(s.why_no_direction().unwrap().contains("is 0"));
    }

    #[test]
    fn a_zero_effect_is_no_prediction_not_a_wrong_one() {
        assert_eq!(Verdict::of(1, 0.0, 2.0), Verdict::NoPrediction);
        assert_eq!(Verdict::of(-1, 1e-12, 2.0), Verdict::NoPrediction);
        assert_eq!(Verdict::of(1, 1e-6, 2.0), Verdict::Agrees);
        assert_eq!(Verdict::of(-1, 1e-6, 2.0), Verdict::Opposite);
        assert_eq!(Verdict::of(-1, -0.3, 2.0), Verdict::Agrees);
        assert_eq!(Verdict::of(0, 0.5, 2.0), Verdict::NotCounted);
        // A constant output predicts nothing whatever its effect's rounding.
        assert_eq!(Verdict::of(1, 0.0, 0.0), Verdict::NoPrediction);
        for v in [
            Verdict::Agrees,
            Verdict::Opposite,
            Verdict::NoPrediction,
            Verdict::NotCounted,
        ] {
            assert_eq!(Verdict::from_name(v.name()), Some(v));
            assert_eq!(
                serde_json::to_value(v).unwrap(),
                serde_json::Value::from(v.name())
            );
        }
        // A flat picture: every model's output is flat, so no model predicts anything.
        let mut s = contrast_stimulus("flat", 32, 8.0, Human::EffectStrength { value: 1.0 });
        s.image = s.image.map(|_| 0.5);
        s.set = "RHS2007".into();
        let config = BenchmarkConfig::new(vec![s], vec![Model::HighPass], "x".into()).unwrap();
        let report = run(&config, &NoProgress).unwrap();
        assert_eq!(report.rows[0].verdict, Verdict::NoPrediction);
        let score = &report.scores[0];
        assert_eq!(
            (
                score.direction_agrees,
                score.direction_counted,
                score.direction_no_prediction
            ),
            (0, 1, 1)
        );
        assert!(report.markdown().contains("0 / 1 (1 no prediction)"));
    }

    #[test]
    fn an_exports_directions_are_read_and_bad_fields_are_one_line_errors() {
        let dir = std::env::temp_dir().join(format!("shadelab-bm-export-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let s = contrast_stimulus("sbc", 32, 8.0, Human::EffectStrength { value: 1.0 });
        io::write_image(&dir.join("img.npy"), &s.image).unwrap();
        io::write_image(&dir.join("mask.npy"), &s.targets.map(|&l| f64::from(l))).unwrap();
        let write = |extra: &str| {
            let index = format!(
                r#"{{"stimupy_version": "1.2.0", "stimuli": [{{"set": "RHS2007", "name": "sbc",
                "image": "img.npy", "mask": "mask.npy", "ppd": 8, "darker_target": 2,
                "human": {{"kind": "effect_strength", "value": 1.0}}{extra}}}]}}"#
            );
            std::fs::write(dir.join(EXPORT_INDEX), index).unwrap();
            BenchmarkConfig::from_export(&dir, vec![Model::HighPass], &[])
        };
        let source = r#", "direction_source": "make_sbc_small.m region.hi=3""#;
        let c = write(&format!(
            r#", "lighter_target": 1{source}, "source_position": [-7.5, 0.0], "no_direction": null"#
        ))
        .unwrap();
        let st = &c.stimuli[0];
        assert_eq!((st.lighter, st.darker), (1, 2));
        assert_eq!(st.source_position, Some([-7.5, 0.0]));
        let report = run(&c, &NoProgress).unwrap();
        let d = &report.directions[0];
        assert_eq!((d.expected_lighter, d.human_lighter_target), (1, Some(1)));
        assert_eq!(d.direction_source, "make_sbc_small.m region.hi=3");
        assert!(report.markdown().contains("make_sbc_small.m region.hi=3"));
        // The source's reason for no direction leaves the stimulus out of the direction score.
        let c = write(&format!(
            r#", "lighter_target": 1{source}, "no_direction": "a control""#
        ))
        .unwrap();
        let report = run(&c, &NoProgress).unwrap();
        assert_eq!(report.rows[0].verdict, Verdict::NotCounted);
        assert_eq!(
            report.directions[0].no_direction.as_deref(),
            Some("a control")
        );
        assert!(report.markdown().contains("| none |"));
        for (bad, says) in [
            (
                format!(r#", "lighter_target": 0{source}"#),
                "target label from 1",
            ),
            (
                format!(r#", "lighter_target": 1.5{source}"#),
                "target label from 1",
            ),
            (format!(r#", "lighter_target": 2{source}"#), "both label 2"),
            (source.to_string(), "no number lighter_target"),
            (
                r#", "lighter_target": 1"#.to_string(),
                "no direction_source",
            ),
            (
                format!(r#", "lighter_target": 1{source}, "source_position": [1]"#),
                "source_position",
            ),
            (
                format!(r#", "lighter_target": 1{source}, "no_direction": 3"#),
                "no_direction",
            ),
        ] {
            let e = write(&bad).unwrap_err().to_string();
            assert!(e.contains(says) && !e.contains('\n'), "{bad}: {e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_high_pass_model_predicts_simultaneous_contrast() {
        let s = contrast_stimulus("sbc", 64, 8.0, Human::EffectStrength { value: 1.0 });
        let config = BenchmarkConfig::new(vec![s], vec![Model::HighPass], "x".into()).unwrap();
        let report = run(&config, &NoProgress).unwrap();
        assert!(report.rows[0].effect > 0.0 && report.rows[0].verdict == Verdict::Agrees);
    }
}
