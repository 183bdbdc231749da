//! `experiment pilot`: the study's simulated participant without a browser. The page's pilot
//! mode (`index.html?simulate=…`) answers every trial from the observer model; [`pilot`] draws
//! the same participant's order and answers here, with the same generators as
//! `shadelab-timeline.js` (FNV-1a of `seed:participant` for the order, mulberry32 for the
//! shuffles and the answers, Fisher–Yates) and the one observer model,
//! [`ModelParams::p_convex`], and returns the trial rows the page writes for them, in its
//! column names, as CSV ([`PilotReport::csv`]). The columns that depend on the browser (the
//! user agent, the screen and window, jsPsych's `time_elapsed` and `trial_index`) are left out.
//!
//! ```
//! use shadelab::pipeline::experiment::{pilot, run, Config, Simulate};
//! use shadelab::{NoProgress, Output};
//!
//! let mut config = Config::new();
//! config.rotations = vec![0.0, 90.0, 180.0, 270.0];
//! config.repeats = 2;
//! config.practice = 1;
//! let design = run(&config, &NoProgress)?.design;
//! let model: Simulate = "tilt:26,kappa:2,seed:3".parse()?;
//! let report = pilot(&serde_json::to_value(&design)?, &model, None)?;
//! assert_eq!(report.rows.len(), 9);
//! assert!(report.csv().starts_with("shadelab,block,practice,"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::analysis::observer_model::ModelParams;
use crate::error::{Error, Result};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A pilot to run: the study, the observer, the participant. Its parts are each valid by
/// their type ([`Simulate`] and [`Participant`] are made by parsing the page's text), so there
/// is nothing left to check.
#[derive(Debug, Clone, PartialEq)]
pub struct PilotConfig {
    /// The study folder `shadelab experiment` wrote (or its `design.json`).
    pub study: PathBuf,
    /// The simulated observer.
    pub simulate: Simulate,
    /// The participant id (the page's `participant` parameter); `None`: `simulated-seedS`.
    pub participant: Option<Participant>,
}

/// A participant id as the page takes it: letters, digits, `-`, `_`, `.` or `@`, at most 128.
///
/// ```
/// use shadelab::pipeline::experiment::Participant;
/// let p: Participant = "p-01@lab".parse()?;
/// assert_eq!(p.as_str(), "p-01@lab");
/// assert!("p 01".parse::<Participant>().is_err());
/// # Ok::<(), shadelab::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Participant(String);

impl Participant {
    /// The id.
    pub fn as_str(&self) -> &str {
        &self.0
    }
}

impl FromStr for Participant {
    type Err = Error;

    /// The message names the id, for the caller to prefix with its flag or keyword.
    fn from_str(p: &str) -> Result<Self> {
        let ok = (1..=128).contains(&p.len())
            && p.chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '@' | '-'));
        if ok {
            Ok(Participant(p.to_string()))
        } else {
            Err(Error::invalid(format!(
                "'{p}': use letters, digits, '-', '_', '.' or '@' (at most 128)"
            )))
        }
    }
}

impl PilotConfig {
    /// The design file: `study/design.json`, or `study` itself when it is a file.
    pub fn design_path(&self) -> PathBuf {
        if self.study.is_dir() {
            self.study.join(super::MARKER)
        } else {
            self.study.clone()
        }
    }
}

/// Reads the study's design and runs [`pilot`] on it.
pub fn run_pilot(config: &PilotConfig) -> Result<PilotReport> {
    let path = config.design_path();
    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
    let design: Value = serde_json::from_str(&text)
        .map_err(|e| Error::format(&path, format!("is not JSON ({e})")))?;
    pilot(&design, &config.simulate, config.participant.as_ref())
        .map_err(|e| Error::format(&path, e.to_string()))
}

/// The pilot's observer: the model and the seed of its answers, as the page's `simulate`
/// parameter gives them (`tilt:T,kappa:K,convex:C,lapse:L,seed:S`). Made only by parsing that
/// text, with the page's ranges, so a `Simulate` is always a valid observer.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Simulate {
    model: ModelParams,
    seed: u32,
}

impl Simulate {
    /// The observer model (π defaults to 0.5, λ to 0).
    pub fn model(&self) -> &ModelParams {
        &self.model
    }

    /// The seed of the answers' generator (default 1).
    pub fn seed(&self) -> u32 {
        self.seed
    }

    /// The model as the rows' `simulated` column writes it:
    /// `tilt:T,kappa:K,convex:C,lapse:L,seed:S`.
    pub fn text(&self) -> String {
        let m = &self.model;
        format!(
            "tilt:{},kappa:{},convex:{},lapse:{},seed:{}",
            m.tilt_deg, m.kappa, m.convexity_prior, m.lapse, self.seed
        )
    }
}

impl FromStr for Simulate {
    type Err = Error;

    /// `tilt:T,kappa:K[,convex:C][,lapse:L][,seed:S]`, with the page's ranges (tilt −360 to
    /// 360, kappa 0 to 100, convex and lapse 0 to 1, seed a whole number below 2³²); the
    /// message names the part that is wrong, for the caller to prefix with its flag.
    fn from_str(text: &str) -> Result<Self> {
        let mut sim = Simulate {
            model: ModelParams {
                tilt_deg: f64::NAN,
                kappa: f64::NAN,
                convexity_prior: 0.5,
                lapse: 0.0,
            },
            seed: 1,
        };
        let mut given: Vec<&str> = Vec::new();
        for part in text.split(',') {
            let (name, value) = part
                .split_once(':')
                .map(|(n, v)| (n.trim(), v.trim()))
                .ok_or_else(|| {
                    Error::invalid(format!("'{part}' is not NAME:VALUE (e.g. tilt:26)"))
                })?;
            if given.contains(&name) {
                return Err(Error::invalid(format!("'{name}' is given twice")));
            }
            let (lo, hi, what) = match name {
                "tilt" => (-360.0, 360.0, "a number of degrees from -360 to 360"),
                "kappa" => (0.0, 100.0, "a number from 0 to 100"),
                "convex" | "lapse" => (0.0, 1.0, "a probability from 0 to 1"),
                "seed" => (
                    0.0,
                    f64::from(u32::MAX),
                    "a whole number from 0 to 4294967295",
                ),
                _ => {
                    return Err(Error::invalid(format!(
                        "unknown parameter '{name}' (use tilt, kappa, convex, lapse, seed)"
                    )))
                }
            };
            let v: f64 = value
                .parse()
                .ok()
                .filter(|v: &f64| (lo..=hi).contains(v) && (name != "seed" || v.fract() == 0.0))
                .ok_or_else(|| Error::invalid(format!("{name} '{value}' must be {what}")))?;
            match name {
                "tilt" => sim.model.tilt_deg = v,
                "kappa" => sim.model.kappa = v,
                "convex" => sim.model.convexity_prior = v,
                "lapse" => sim.model.lapse = v,
                _ => sim.seed = v as u32,
            }
            given.push(name);
        }
        for needed in ["tilt", "kappa"] {
            if !given.contains(&needed) {
                return Err(Error::invalid(format!(
                    "give {needed} (e.g. tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1)"
                )));
            }
        }
        Ok(sim)
    }
}

/// FNV-1a (32 bits) of `text`'s UTF-8 bytes: the participant's order seed, as the page's.
pub fn order_seed(text: &str) -> u32 {
    text.bytes().fold(0x811c_9dc5_u32, |h, b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    })
}

/// mulberry32 (Tommy Ettinger's 32-bit generator), as the page draws with it: uniforms in
/// [0, 1) that are k / 2³².
#[derive(Debug, Clone)]
struct Mulberry32(u32);

impl Mulberry32 {
    fn draw(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x6d2b_79f5);
        let mut t = self.0;
        t = (t ^ (t >> 15)).wrapping_mul(t | 1);
        t ^= t.wrapping_add((t ^ (t >> 7)).wrapping_mul(t | 61));
        f64::from(t ^ (t >> 14)) / 4_294_967_296.0
    }
}

/// Fisher–Yates in place, as the page's `shuffle`.
fn shuffle<T>(items: &mut [T], random: &mut Mulberry32) {
    for i in (1..items.len()).rev() {
        let j = (random.draw() * (i + 1) as f64).floor() as usize;
        items.swap(i, j);
    }
}

/// The pixels-per-degree method the page's pilot writes: the calibration is skipped.
pub const PILOT_PPD_METHOD: &str = "none (simulated): one image pixel per CSS pixel";

/// The columns of the pilot's rows, in order: the page's names for them.
pub const PILOT_COLUMNS: &[&str] = &[
    "shadelab",
    "block",
    "practice",
    "break",
    "shadelab_trial",
    "rotation_deg",
    "image",
    "stimulus",
    "key_convex",
    "key_concave",
    "response",
    "rt",
    "judgement",
    "participant",
    "order_seed",
    "design_hash",
    "stimulus_name",
    "ppd",
    "ppd_method",
    "viewing_distance_cm",
    "shadelab_version",
    "simulated",
];

/// The simulated participant's trial rows ([`PILOT_COLUMNS`], each as the page's CSV writes it).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PilotReport {
    /// The participant id (the page's default for a pilot: `simulated-seedS`).
    pub participant: String,
    /// Their order seed.
    pub order_seed: u32,
    /// The observer.
    pub simulate: Simulate,
    /// One row per trial, in the order shown; the cells of [`PILOT_COLUMNS`].
    #[serde(skip)]
    pub rows: Vec<Vec<String>>,
}

impl PilotReport {
    /// The rows as CSV: a header of [`PILOT_COLUMNS`], then one line per trial (a cell with a
    /// comma or a quote is quoted).
    pub fn csv(&self) -> String {
        let mut out = csv_line(PILOT_COLUMNS.iter().copied());
        for row in &self.rows {
            out += &csv_line(row.iter().map(String::as_str));
        }
        out
    }
}

impl PilotReport {
    /// Writes [`PilotReport::csv`] to `path` (atomically). An existing file is replaced only
    /// with `force`; `design`, the run's input, never.
    pub fn write(&self, path: &Path, design: &Path, force: bool) -> Result<()> {
        let same = |a: &Path, b: &Path| {
            std::fs::canonicalize(a)
                .ok()
                .is_some_and(|a| Some(a) == std::fs::canonicalize(b).ok())
        };
        if same(path, design) {
            return Err(Error::format(
                path,
                "is the study's design, the pilot's input: choose another file",
            ));
        }
        if path.exists() && !force {
            return Err(Error::NotOurs {
                path: path.to_path_buf(),
                message: "exists; the pilot replaces a file only when forced".into(),
            });
        }
        crate::io::write_text(path, &self.csv())
    }
}

/// One CSV line of `cells`, ended by a line break.
fn csv_line<'a>(cells: impl Iterator<Item = &'a str>) -> String {
    cells.map(csv_cell).collect::<Vec<_>>().join(",") + "\n"
}

/// One CSV cell: quoted (quotes doubled) when it holds a comma, a quote or a line break.
pub fn csv_cell(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// A number as JavaScript writes it (`32`, `7.5`): Rust's shortest form, which is the same for
/// the numbers of a design.
fn js_number(v: &Value) -> String {
    match v.as_f64() {
        Some(x) if x == x.trunc() && x.abs() < 1e15 => format!("{}", x as i64),
        Some(x) => format!("{x}"),
        None => String::new(),
    }
}

/// The simulated participant of `design` (a study's `design.json`) answering as `simulate`:
/// the page's pilot for that participant (`participant`, else `simulated-seedS` as the page's
/// default), with every trial row it writes.
pub fn pilot(
    design: &Value,
    simulate: &Simulate,
    participant: Option<&Participant>,
) -> Result<PilotReport> {
    let bad = |what: &str| {
        Error::invalid(format!(
            "the design has no {what}: is it a shadelab experiment's design.json?"
        ))
    };
    if design["program"] != "shadelab" {
        return Err(bad("`program: shadelab`"));
    }
    let trials = design["trials"].as_array().ok_or_else(|| bad("trials"))?;
    let seed = design["seed"].as_u64().ok_or_else(|| bad("seed"))?;
    let text = |v: &Value, what: &str| -> Result<String> {
        v.as_str().map(str::to_string).ok_or_else(|| bad(what))
    };
    let participant = participant
        .map(|p| p.as_str().to_string())
        .unwrap_or_else(|| format!("simulated-seed{}", simulate.seed));
    let order_seed = order_seed(&format!("{seed}:{participant}"));
    let mut random = Mulberry32(order_seed);
    let (mut convex, mut concave) = (
        text(&design["keys"]["convex"], "keys")?,
        text(&design["keys"]["concave"], "keys")?,
    );
    if design["counterbalance_keys"] == true && order_seed & 1 == 1 {
        std::mem::swap(&mut convex, &mut concave);
    }
    let block =
        |name: &str| -> Vec<&Value> { trials.iter().filter(|t| t["block"] == name).collect() };
    let mut practice = block("practice");
    shuffle(&mut practice, &mut random);
    let mut test = block("test");
    shuffle(&mut test, &mut random);
    let mut answers = Mulberry32(simulate.seed);
    let common = [
        text(&design["design_hash"], "design_hash")?,
        text(&design["stimulus"], "stimulus")?,
        js_number(&design["display"]["ppd"]),
        PILOT_PPD_METHOD.to_string(),
        js_number(&design["display"]["viewing_distance_cm"]),
        text(&design["version"], "version")?,
        simulate.text(),
    ];
    let mut rows = Vec::with_capacity(trials.len());
    for (n, t) in practice.iter().chain(&test).enumerate() {
        let rotation = t["rotation_deg"]
            .as_f64()
            .ok_or_else(|| bad("rotation_deg in its trials"))?;
        let image = text(&t["image"], "image in its trials")?;
        let says_convex = answers.draw() < simulate.model.p_convex(rotation);
        let rt = (400.0 + 400.0 * answers.draw()).round();
        let block = text(&t["block"], "block in its trials")?;
        let mut row = vec![
            "trial".to_string(),
            block.clone(),
            (block == "practice").to_string(),
            "false".to_string(),
            (n + 1).to_string(),
            js_number(&t["rotation_deg"]),
            image.clone(),
            image,
            convex.clone(),
            concave.clone(),
            if says_convex { &convex } else { &concave }.clone(),
            format!("{rt}"),
            if says_convex { "convex" } else { "concave" }.to_string(),
            participant.clone(),
            order_seed.to_string(),
        ];
        row.extend(common.iter().cloned());
        rows.push(row);
    }
    Ok(PilotReport {
        participant,
        order_seed,
        simulate: *simulate,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_generators_are_the_pages() {
        // FNV-1a's published test vectors.
        assert_eq!(order_seed(""), 0x811c_9dc5);
        assert_eq!(order_seed("a"), 0xe40c_292c);
        assert_eq!(order_seed("foobar"), 0xbf9c_f968);
        // mulberry32(1)'s first draws, as JavaScript's reference implementation gives them.
        let mut m = Mulberry32(1);
        let first: Vec<u64> = (0..3)
            .map(|_| (m.draw() * 4_294_967_296.0) as u64)
            .collect();
        assert_eq!(first, [2_693_262_067, 11_749_833, 2_265_367_787]);
    }

    #[test]
    fn the_simulate_text_is_parsed_as_the_page_parses_it() {
        let s: Simulate = "tilt:26, kappa:2,convex:0.7,lapse:0.02,seed:1"
            .parse()
            .unwrap();
        assert_eq!(s.text(), "tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1");
        let d: Simulate = "kappa:2,tilt:-10".parse().unwrap();
        assert_eq!(d.text(), "tilt:-10,kappa:2,convex:0.5,lapse:0,seed:1");
        for (bad, needle) in [
            ("tilt:26", "give kappa"),
            ("tilt:26,kappa:2,seed:1.5", "seed '1.5'"),
            ("tilt:26,kappa:200", "kappa '200'"),
            ("tilt:26,kappa:2,tilt:3", "given twice"),
            ("tilt:26,kappa:2,gamma:1", "unknown parameter 'gamma'"),
            ("tilt=26", "NAME:VALUE"),
        ] {
            let e = bad.parse::<Simulate>().unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }
}
