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
use crate::lightness::benchmark::{direction_agreement, effect, spearman};
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

    /// The human direction: +1 when the expected-lighter target was seen lighter, −1 when the
    /// other was, 0 when there is no effect (an effect strength of 0, or a proportion whose
    /// 95 % interval holds ½).
    pub fn direction(&self) -> i8 {
        let (v, half) = match *self {
            Human::EffectStrength { value } => (value, 0.0),
            Human::ProportionExpected { value, ci95 } => (value - 0.5, ci95.abs()),
        };
        if v.abs() <= half || v == 0.0 {
            0
        } else if v > 0.0 {
            1
        } else {
            -1
        }
    }
}

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
    /// The label of the target that is expected to look lighter.
    pub lighter: u16,
    /// The label of the other target.
    pub darker: u16,
    /// How `lighter` was chosen: the published rule applied to the stimulus's pixels (e.g.
    /// `contrast`, `white`), or a note that it is the stimulus set's order, not checked.
    pub convention: String,
    /// Whether a published rule on the pixels chose `lighter` (`false`: the set's order).
    pub convention_checked: bool,
    /// What people reported.
    pub human: Human,
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
            // Older exports carry no convention: the set's order, not checked.
            let convention = entry["convention"]
                .as_str()
                .unwrap_or("not recorded by the exporter")
                .to_string();
            let convention_checked = entry["convention_checked"].as_bool().unwrap_or(false);
            stimuli.push(BenchmarkStimulus {
                set,
                name,
                image,
                targets,
                ppd: number("ppd")?,
                lighter: target("lighter_target")?,
                darker: target("darker_target")?,
                convention,
                convention_checked,
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
pub const EXPORTER: &str = include_str!("../../assets/benchmark/_benchmark_data.py");

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

/// One model on one stimulus.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BenchmarkRow {
    /// The stimulus set.
    pub set: String,
    /// The stimulus.
    pub stimulus: String,
    /// The model.
    pub model: String,
    /// The human value (RHS2007: effect strength; murray2020: proportion expected).
    pub human: f64,
    /// Half the 95 % interval of the human value, when the data give one.
    pub human_ci95: Option<f64>,
    /// The human direction (+1, −1, or 0 for no effect).
    pub human_direction: i8,
    /// The model's effect: mean output over the expected-lighter target minus the other.
    pub effect: f64,
    /// Whether the model's effect has the human sign (`None` where people saw no effect).
    pub agrees: Option<bool>,
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
    /// Stimuli with a human direction (those with no effect are left out).
    pub direction_counted: usize,
    /// Spearman's ρ between the model's effects and the human values, over every stimulus
    /// of the set.
    pub spearman: Option<f64>,
    /// Stimuli in the set.
    pub stimuli: usize,
}

/// Which target of a stimulus people see as lighter, and how that was established.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchmarkConvention {
    /// The stimulus set.
    pub set: String,
    /// The stimulus.
    pub stimulus: String,
    /// The label of the target people see as lighter.
    pub lighter_target: u16,
    /// The label of the other target.
    pub darker_target: u16,
    /// The published rule applied to the pixels, or a note that it is the set's order.
    pub convention: String,
    /// Whether a published rule chose the lighter target.
    pub checked: bool,
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
    /// The same scores over only the stimuli whose lighter-looking target a published rule
    /// chose from the pixels ([`BenchmarkConvention::checked`]).
    pub checked_scores: Vec<BenchmarkScore>,
    /// Per stimulus, which target people see as lighter and how that was established.
    pub conventions: Vec<BenchmarkConvention>,
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
        for model in &config.models {
            let out = model.predict(&s.image, Some(s.ppd))?;
            let e = effect(&out, &s.targets, s.lighter, s.darker)?.ok_or_else(|| {
                Error::invalid(format!("stimulus {}/{}: a target is empty", s.set, s.name))
            })?;
            let direction = s.human.direction();
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
                effect: e,
                agrees: (direction != 0).then_some(e != 0.0 && e.signum() == f64::from(direction)),
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
        checked_scores: scores(
            &rows
                .iter()
                .filter(|r| {
                    config
                        .stimuli
                        .iter()
                        .any(|s| s.set == r.set && s.name == r.stimulus && s.convention_checked)
                })
                .cloned()
                .collect::<Vec<_>>(),
        ),
        conventions: config
            .stimuli
            .iter()
            .map(|s| BenchmarkConvention {
                set: s.set.clone(),
                stimulus: s.name.clone(),
                lighter_target: s.lighter,
                darker_target: s.darker,
                convention: s.convention.clone(),
                checked: s.convention_checked,
            })
            .collect(),
        rows,
        seconds: started.elapsed().as_secs_f64(),
    })
}

const DEFINITIONS: [&str; 4] = [
    "effect: mean model output over the target people see as lighter minus the mean over the \
     other target; which target that is, is stated per stimulus by the exporter (conventions): \
     a published rule on the illusion's direction applied to stimupy's pixels where one was \
     verified (checked), else stimupy's order (RHS2007: target 1; murray2020: target 2)",
    "direction: the model agrees when its effect is positive where people saw the \
     expected-lighter target lighter (negative where they saw the reverse); stimuli with no \
     human effect (effect strength 0, or a proportion whose 95 % interval holds 0.5) are not \
     counted",
    "spearman: rank correlation of the model's effects with RHS2007's effect strengths or \
     murray2020's proportions expected, over every stimulus of the set",
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
            let pairs: Vec<(f64, f64)> = mine
                .iter()
                .map(|r| (f64::from(r.human_direction), r.effect))
                .collect();
            let (direction_agrees, direction_counted) = direction_agreement(&pairs);
            let human: Vec<f64> = mine.iter().map(|r| r.human).collect();
            let model_effects: Vec<f64> = mine.iter().map(|r| r.effect).collect();
            BenchmarkScore {
                spearman: spearman(&human, &model_effects),
                stimuli: mine.len(),
                set,
                model,
                direction_agrees,
                direction_counted,
            }
        })
        .collect()
}

/// The columns of `benchmark.csv`.
pub const CSV_HEADER: &str = "set,stimulus,model,human,human_ci95,human_direction,effect,agrees";

/// The rows as CSV (numbers written so that they read back exactly).
pub fn rows_csv(rows: &[BenchmarkRow]) -> String {
    let mut csv = format!("{CSV_HEADER}\n");
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{}\n",
            r.set,
            r.stimulus,
            r.model,
            r.human,
            r.human_ci95.map(|v| v.to_string()).unwrap_or_default(),
            r.human_direction,
            r.effect,
            r.agrees.map(|a| a.to_string()).unwrap_or_default()
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
            if f.len() != 8 {
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
                effect: num(f[6])?,
                agrees: if f[7].is_empty() {
                    None
                } else {
                    Some(f[7] == "true")
                },
            })
        })
        .collect()
}

impl BenchmarkReport {
    /// The scores and the per-stimulus table as Markdown (the table docs/lightness.md shows).
    pub fn markdown(&self) -> String {
        let mut md = format!(
            "Scores (shadelab {}, stimupy {}): direction = stimuli where the model's effect \
             has the human sign / stimuli with a human effect; ρ = Spearman rank correlation \
             with the human values.\n\n| model | RHS2007 direction | RHS2007 ρ | murray2020 \
             direction | murray2020 ρ |\n|---|---|---|---|---|\n",
            self.stamp.version, self.stimupy_version
        );
        let cell = |scores: &[BenchmarkScore], set: &str, model: &str| -> (String, String) {
            match scores.iter().find(|s| s.set == set && s.model == model) {
                Some(s) => (
                    format!("{} / {}", s.direction_agrees, s.direction_counted),
                    s.spearman
                        .map(|r| format!("{r:.2}"))
                        .unwrap_or_else(|| "–".into()),
                ),
                None => ("–".into(), "–".into()),
            }
        };
        for m in &self.models {
            let (rd, rr) = cell(&self.scores, "RHS2007", m);
            let (md_, mr) = cell(&self.scores, "murray2020", m);
            md.push_str(&format!("| {m} | {rd} | {rr} | {md_} | {mr} |\n"));
        }
        let checked = self.conventions.iter().filter(|c| c.checked).count();
        md.push_str(&format!(
            "\nThe same scores over only the {checked} of {} stimuli whose lighter-looking target \
             a published rule chose from the pixels (column *lighter* below):\n\n| model | \
             RHS2007 direction | RHS2007 ρ | murray2020 direction | murray2020 ρ |\n\
             |---|---|---|---|---|\n",
            self.conventions.len()
        ));
        for m in &self.models {
            let (rd, rr) = cell(&self.checked_scores, "RHS2007", m);
            let (md_, mr) = cell(&self.checked_scores, "murray2020", m);
            md.push_str(&format!("| {m} | {rd} | {rr} | {md_} | {mr} |\n"));
        }
        md.push_str("\nEach model's effect per stimulus (✓ = human direction, ✗ = opposite, · = no human effect; *lighter* = the target people see as lighter, with the published rule that chose it, or *order* where it is the set's order, not checked):\n\n| # | set | stimulus | human | lighter |");
        for m in &self.models {
            md.push_str(&format!(" {m} |"));
        }
        md.push_str("\n|---|---|---|---|---|");
        md.push_str(&"---|".repeat(self.models.len()));
        md.push('\n');
        for (i, (set, name)) in self.stimulus_order().iter().enumerate() {
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
            let lighter = self
                .conventions
                .iter()
                .find(|c| &c.set == set && &c.stimulus == name)
                .map(|c| {
                    if c.checked {
                        format!("{} ({})", c.lighter_target, c.convention)
                    } else {
                        format!("{} (order)", c.lighter_target)
                    }
                })
                .unwrap_or_else(|| "–".into());
            md.push_str(&format!(
                "| {} | {set} | {name} | {human} | {lighter} |",
                i + 1
            ));
            for m in &self.models {
                let cell = self
                    .rows
                    .iter()
                    .find(|r| &r.set == set && &r.stimulus == name && &r.model == m)
                    .map(|r| {
                        let mark = match r.agrees {
                            Some(true) => "✓",
                            Some(false) => "✗",
                            None => "·",
                        };
                        format!("{:+.3} {mark}", r.effect)
                    })
                    .unwrap_or_default();
                md.push_str(&format!(" {cell} |"));
            }
            md.push('\n');
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
            String::from("set,model,direction_agrees,direction_counted,spearman,stimuli\n");
        for s in &self.scores {
            scores.push_str(&format!(
                "{},{},{},{},{},{}\n",
                s.set,
                s.model,
                s.direction_agrees,
                s.direction_counted,
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
        convention: "contrast".into(),
        convention_checked: true,
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
        let mut wrong = s;
        wrong.darker = 7;
        let e = BenchmarkConfig::new(vec![wrong], vec![Model::Retinex], "x".into()).unwrap_err();
        assert!(e.to_string().contains("label 7"), "{e}");
    }

    #[test]
    fn an_exports_conventions_are_read_and_bad_target_labels_are_one_line_errors() {
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
        let c =
            write(r#", "lighter_target": 1, "convention": "contrast", "convention_checked": true"#)
                .unwrap();
        let st = &c.stimuli[0];
        assert_eq!((st.lighter, st.darker), (1, 2));
        assert!(st.convention_checked && st.convention == "contrast");
        let report = run(&c, &NoProgress).unwrap();
        assert_eq!(report.conventions[0].lighter_target, 1);
        assert_eq!(report.checked_scores, report.scores);
        // An export from before the conventions: the set's order, not checked.
        let c = write(r#", "lighter_target": 1"#).unwrap();
        assert!(!c.stimuli[0].convention_checked);
        let report = run(&c, &NoProgress).unwrap();
        assert!(report.checked_scores.is_empty());
        assert!(report.markdown().contains("only the 0 of 1 stimuli"));
        for (bad, says) in [
            (r#", "lighter_target": 0"#, "target label from 1"),
            (r#", "lighter_target": 1.5"#, "target label from 1"),
            (r#", "lighter_target": 2"#, "both label 2"),
            ("", "no number lighter_target"),
        ] {
            let e = write(bad).unwrap_err().to_string();
            assert!(e.contains(says) && !e.contains('\n'), "{bad}: {e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_high_pass_model_predicts_simultaneous_contrast() {
        let s = contrast_stimulus("sbc", 64, 8.0, Human::EffectStrength { value: 1.0 });
        let config = BenchmarkConfig::new(vec![s], vec![Model::HighPass], "x".into()).unwrap();
        let report = run(&config, &NoProgress).unwrap();
        assert!(report.rows[0].effect > 0.0 && report.rows[0].agrees == Some(true));
    }
}
