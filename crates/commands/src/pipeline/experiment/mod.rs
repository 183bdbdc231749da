//! `experiment` as a pipeline: a jsPsych 8 study that measures a person's light-from-above and
//! convexity priors. One shaded bump per trial, its light turned to each rotation θ (the
//! direction its bright side faces; tilt convention, 0 = up, +90 = left), a "bump or dimple?"
//! key response, and jsPsych's own data (CSV or JSON, every row with the participant, the order
//! seed, the display and the design's hash) that `shadelab fit observer` reads.
//!
//! [`run`] renders one image per rotation (with the render pipeline, so every image has its
//! sidecar) and lists the trials; [`Report::write`] lands the folder whole: `index.html` (the design
//! embedded) and `jatos.html` (the same study for JATOS), `experiment.js` (the study around the
//! trials: browser check, consent, fullscreen, calibration, saving to JATOS, to a server by POST
//! or as a download, the Prolific completion), `shadelab-timeline.js` (the trials as a jsPsych
//! timeline, `shadelabTimeline(design, options)`, which a lab can embed in its own study),
//! `experiment.css`, `package.json` (jsPsych and its plugins at pinned versions, see
//! [`JSPSYCH_PACKAGES`]), `design.json`, `README.md` and `images/`. With [`Config::install`] it
//! runs `npm install` in the folder, so that it runs offline as a static site.
//!
//! Each participant gets their own order: the page shuffles the design's practice and test
//! trials with a seed made of the design's seed and the participant id (`design.json`'s
//! `trials` lists them in the order of the design's seed alone).
//!
//! ```
//! use shadelab::pipeline::experiment::{run, Config};
//! use shadelab::{NoProgress, Output};
//!
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-experiment-{}", std::process::id()));
//! let mut config = Config::new();
//! config.rotations = vec![0.0, 90.0, 180.0, 270.0];
//! config.repeats = 2;
//! config.practice = 1;
//! config.validate()?;
//! let report = run(&config, &NoProgress)?;
//! assert_eq!(report.design.trials.len(), 4 * 2 + 1);
//! let folder = report.write(&Output::new(&dir))?.folder;
//! assert!(folder.join("index.html").exists() && folder.join("design.json").exists());
//! assert!(folder.join("images/theta-090.png").exists());
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod folder;
mod pilot_mode;

pub use folder::{Install, Written};
pub use pilot_mode::{
    csv_cell, order_seed, pilot, run_pilot, Participant, PilotConfig, PilotReport, Simulate,
    PILOT_COLUMNS, PILOT_PPD_METHOD,
};

use super::perception::{field, BadSetting};
use crate::analysis::convexity;
use crate::error::{Error, Result};
use crate::io;
use crate::parallel::prelude::*;
use crate::progress::Progress;
use crate::random::SplitMix64;
use crate::stimulus::{self, Output, Pixels, Request};
use crate::visual_size::{Geometry, SizeRequest};
use serde::Serialize;
use serde_json::{Map, Value};
use std::collections::BTreeMap;
use std::str::FromStr;

/// The file that marks a folder as a shadelab experiment (its `program` is `shadelab`).
pub const MARKER: &str = "design.json";

/// The header of the responses CSV the page writes (and `fit observer` reads).
pub const CSV_HEADER: &str =
    "participant,trial,block,stimulus,rotation_deg,response,rt_ms,key,image,design_hash,simulated";

/// The observer model the pilot mode simulates and `fit observer` estimates.
pub const MODEL: &str =
    "P(convex | θ) = λ/2 + (1 − λ) · π·vM(θ; μ, κ) / (π·vM(θ; μ, κ) + (1 − π)·vM(θ + 180°; μ, κ))";

/// What θ means in the design, the CSV and the model.
pub const CONVENTION: &str = "rotation_deg = θ = the direction the stimulus's bright side faces \
     (its light's tilt): 0 = up, +90 = left (counter-clockwise), in [0, 360)";

/// Default repeats of each rotation: with 24 rotations, enough for a 95 % interval of about
/// ±10° on the prior's direction at κ = 1 (docs/experiments.md gives the argument).
pub const DEFAULT_REPEATS: usize = 16;

/// Most repeats of each rotation accepted.
pub const MAX_REPEATS: usize = 1000;

/// Most practice trials accepted.
pub const MAX_PRACTICE: usize = 100;

/// The largest design seed: 2⁵³ − 1, JavaScript's largest exact whole number (the page reads
/// the seed from `design.json` as a number and makes each participant's order seed of it).
pub const MAX_PAGE_SEED: u64 = (1 << 53) - 1;

/// The runner and its style sheet, copied into every experiment folder.
const RUNNER_JS: &str = include_str!("../../../assets/experiment/experiment.js");
const TIMELINE_JS: &str = include_str!("../../../assets/experiment/shadelab-timeline.js");
const RUNNER_CSS: &str = include_str!("../../../assets/experiment/experiment.css");
const PAGE_HTML: &str = include_str!("../../../assets/experiment/index.html");

/// Default test trials between two breaks.
pub const DEFAULT_BREAK_EVERY: usize = 96;

/// The npm packages of the study, at the versions `package.json` pins, with the script each
/// page loads (relative to `node_modules/`). jsPsych 8 and its plugins; never copied into
/// shadelab's repository, installed into the study folder by `npm install`.
pub const JSPSYCH_PACKAGES: &[(&str, &str, &str)] = &[
    ("jspsych", "8.3.0", "jspsych/dist/index.browser.min.js"),
    (
        "@jspsych/plugin-preload",
        "2.1.0",
        "@jspsych/plugin-preload/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-browser-check",
        "2.1.0",
        "@jspsych/plugin-browser-check/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-html-button-response",
        "2.1.0",
        "@jspsych/plugin-html-button-response/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-html-keyboard-response",
        "2.2.0",
        "@jspsych/plugin-html-keyboard-response/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-image-keyboard-response",
        "2.2.0",
        "@jspsych/plugin-image-keyboard-response/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-fullscreen",
        "2.1.0",
        "@jspsych/plugin-fullscreen/dist/index.browser.min.js",
    ),
    (
        "@jspsych/plugin-virtual-chinrest",
        "3.1.0",
        "@jspsych/plugin-virtual-chinrest/dist/index.browser.min.js",
    ),
];

/// The columns shadelab adds to jsPsych's rows of a trial (beside jsPsych's own `response`,
/// `rt`, `stimulus`, `trial_type`, `trial_index`, `time_elapsed`).
pub const DATA_COLUMNS: &str = "shadelab,block,practice,break,shadelab_trial,rotation_deg,image,\
     key_convex,key_concave,judgement,participant,order_seed,design_hash,stimulus_name,ppd,\
     ppd_method,fullscreen,window_width,window_height,viewing_distance_cm,user_agent,\
     screen_width,screen_height,prolific_pid,study_id,session_id,shadelab_version,simulated";

/// The package.json of a study folder: jsPsych and its plugins at pinned versions.
pub fn package_json() -> String {
    let deps: Map<String, Value> = JSPSYCH_PACKAGES
        .iter()
        .map(|(name, version, _)| (name.to_string(), Value::from(*version)))
        .collect();
    let json = serde_json::json!({
        "name": "shadelab-experiment",
        "private": true,
        "description": "A shadelab experiment (bump or dimple?) run by jsPsych 8",
        "dependencies": deps,
    });
    serde_json::to_string_pretty(&json).unwrap_or_default() + "\n"
}

/// Prolific's completion URL for a completion `code` (letters and digits).
pub fn prolific_completion_url(code: &str) -> Result<String> {
    if code.is_empty() || code.len() > 64 || !code.chars().all(|c| c.is_ascii_alphanumeric()) {
        return Err(Error::invalid(format!(
            "the Prolific completion code '{code}' must be 1 to 64 letters or digits"
        )));
    }
    Ok(format!(
        "https://app.prolific.com/submissions/complete?cc={code}"
    ))
}

/// How the page sends its data to a save URL.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum SaveFormat {
    /// jsPsych's JSON (an array of rows), `Content-Type: application/json`.
    #[default]
    Json,
    /// jsPsych's CSV, `Content-Type: text/csv`.
    Csv,
}

/// The response keys (lower-case letters or digits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Keys {
    /// The key for "bump" (convex).
    pub convex: char,
    /// The key for "dimple" (concave).
    pub concave: char,
}

impl Default for Keys {
    fn default() -> Self {
        Keys {
            convex: 'f',
            concave: 'j',
        }
    }
}

impl FromStr for SaveFormat {
    type Err = Error;

    /// `json` or `csv`; the message begins with the text given, for the caller to prefix with
    /// its flag or keyword.
    fn from_str(text: &str) -> Result<Self> {
        match text {
            "json" => Ok(SaveFormat::Json),
            "csv" => Ok(SaveFormat::Csv),
            _ => Err(Error::invalid(format!("'{text}' must be json or csv"))),
        }
    }
}

impl FromStr for Keys {
    type Err = Error;

    /// Two keys, bump then dimple, with or without a comma between (`fj`, `f,j`), lower-cased;
    /// whether they may be used is [`Config::check`]'s. The message begins with the text
    /// given, for the caller to prefix with its flag or keyword.
    ///
    /// ```
    /// use shadelab::pipeline::experiment::Keys;
    /// let keys: Keys = "F,J".parse().unwrap();
    /// assert_eq!((keys.convex, keys.concave), ('f', 'j'));
    /// assert!("fjk".parse::<Keys>().is_err());
    /// ```
    fn from_str(text: &str) -> Result<Self> {
        let chars: Vec<char> = text.chars().filter(|c| *c != ',').collect();
        let [convex, concave] = chars[..] else {
            return Err(Error::invalid(format!(
                "'{text}' must be two keys, bump then dimple (e.g. fj)"
            )));
        };
        Ok(Keys {
            convex: convex.to_ascii_lowercase(),
            concave: concave.to_ascii_lowercase(),
        })
    }
}

/// How long the screens between responses last, in milliseconds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// The fixation cross before each stimulus.
    pub fixation_ms: u32,
    /// The blank screen after each response.
    pub blank_ms: u32,
}

impl Default for Timing {
    fn default() -> Self {
        Timing {
            fixation_ms: 500,
            blank_ms: 300,
        }
    }
}

/// An experiment to make: the stimulus, the design and the display.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// The stimulus (any shadelab stimulus with a `light` parameter and one target).
    pub stimulus: String,
    /// Its parameters (not `light`: each trial's rotation sets it); missing ones take their
    /// defaults.
    pub params: Map<String, Value>,
    /// The slant of the light, degrees from the line of sight (0 < slant < 90).
    pub slant_deg: f64,
    /// The rotations θ in degrees (normalised to [0, 360)); each is shown `repeats` times.
    pub rotations: Vec<f64>,
    /// How many times each rotation is shown in the test block.
    pub repeats: usize,
    /// Practice trials before the test (rotations drawn with the seed; not for analysis).
    pub practice: usize,
    /// Pixels per degree of the rendered images (and of the display when the page is not
    /// calibrated: one image pixel per CSS pixel).
    pub ppd: f64,
    /// The viewing distance the calibration step assumes, in centimetres.
    pub viewing_distance_cm: f64,
    /// The size of each image in degrees, (height, width).
    pub visual_size: (f64, f64),
    /// Seed of the trial order (and of the stimulus's own random layout, if any).
    pub seed: u64,
    /// The response keys.
    pub keys: Keys,
    /// Fixation and blank durations.
    pub timing: Timing,
    /// Display gamma of the images (8-bit PNGs for the browser; `None` writes linear values).
    pub gamma: Option<f64>,
    /// The largest image made, in pixels.
    pub max_pixels: usize,
    /// A break after every this many test trials (0: none).
    pub break_every: usize,
    /// Swap the two keys for half of the participants (chosen by their order seed).
    pub counterbalance_keys: bool,
    /// Where the page POSTs the data (`http(s)://…` or a path on the same host); the URL
    /// parameter `save_url` overrides it. `None`: the participant downloads them.
    pub save_url: Option<String>,
    /// The body of that POST.
    pub save_format: SaveFormat,
    /// Where the page sends the participant once the data are saved (e.g. Prolific's, see
    /// [`prolific_completion_url`]).
    pub completion_url: Option<String>,
    /// Run `npm install` in the written folder (when npm is on PATH) so that it runs as it is.
    pub install: bool,
}

impl Default for Config {
    fn default() -> Config {
        Config::new()
    }
}

impl Config {
    /// The default experiment: one hemispherical bump (shadelab's `bumps` with one
    /// disc), 4° × 4° at 32 ppd, lit at slant 45°, rotations every 15° (24), 16 repeats, 8
    /// practice trials, 57 cm viewing distance, keys F = bump and J = dimple, seed 1.
    pub fn new() -> Config {
        Config {
            stimulus: "bumps".into(),
            params: default_params("bumps"),
            slant_deg: 45.0,
            rotations: (0..24).map(|i| f64::from(i) * 15.0).collect(),
            repeats: DEFAULT_REPEATS,
            practice: 8,
            ppd: 32.0,
            viewing_distance_cm: 57.0,
            visual_size: (4.0, 4.0),
            seed: 1,
            keys: Keys::default(),
            timing: Timing::default(),
            gamma: Some(2.2),
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            break_every: DEFAULT_BREAK_EVERY,
            counterbalance_keys: false,
            save_url: None,
            save_format: SaveFormat::Json,
            completion_url: None,
            install: false,
        }
    }

    /// Shows `name` instead, with the parameters that make it one target (for `bumps`: one
    /// bump; for the others, their defaults).
    pub fn set_stimulus(&mut self, name: &str) -> Result<()> {
        stimulus::find(name)?;
        self.stimulus = name.to_string();
        self.params = default_params(name);
        Ok(())
    }

    /// Checks everything that needs no rendering; each problem is one line.
    pub fn validate(&self) -> Result<()> {
        self.check().map_err(Error::from)
    }

    /// [`Config::validate`], naming the field that failed (the command line names its flag).
    pub fn check(&self) -> std::result::Result<(), BadSetting> {
        field("stimulus", self.check_stimulus())?;
        if !(self.slant_deg.is_finite() && self.slant_deg > 0.0 && self.slant_deg < 90.0) {
            return Err(BadSetting {
                field: "slant_deg",
                error: Error::invalid(format!(
                    "the light's slant {} must be above 0 and below 90 degrees",
                    self.slant_deg
                )),
            });
        }
        field("rotations", rotations(&self.rotations).map(|_| ()))?;
        if self.seed > MAX_PAGE_SEED {
            return Err(BadSetting {
                field: "seed",
                error: Error::invalid(format!(
                    "seed {} must be at most {MAX_PAGE_SEED} (2^53 − 1: the page's JavaScript \
                     holds it as a number, and a larger one would give the participants other \
                     orders than design.json and `experiment pilot` say)",
                    self.seed
                )),
            });
        }
        if self.repeats == 0 || self.repeats > MAX_REPEATS {
            return Err(BadSetting {
                field: "repeats",
                error: Error::invalid(format!(
                    "repeats {} must be 1 to {MAX_REPEATS}",
                    self.repeats
                )),
            });
        }
        if self.practice > MAX_PRACTICE {
            return Err(BadSetting {
                field: "practice",
                error: Error::invalid(format!(
                    "practice trials {} must be at most {MAX_PRACTICE}",
                    self.practice
                )),
            });
        }
        if !(self.ppd.is_finite() && self.ppd > 0.0 && self.ppd <= 1000.0) {
            return Err(BadSetting {
                field: "ppd",
                error: Error::invalid(format!(
                    "pixels per degree {} must be above 0 and at most 1000",
                    self.ppd
                )),
            });
        }
        if !(self.viewing_distance_cm.is_finite()
            && (10.0..=1000.0).contains(&self.viewing_distance_cm))
        {
            return Err(BadSetting {
                field: "viewing_distance_cm",
                error: Error::invalid(format!(
                    "the viewing distance {} cm must be 10 to 1000 cm",
                    self.viewing_distance_cm
                )),
            });
        }
        let (h, w) = self.visual_size;
        let most = crate::visual_size::MAX_VISUAL_DEGREES;
        if !(h.is_finite() && w.is_finite() && h > 0.0 && w > 0.0 && h <= most && w <= most) {
            return Err(BadSetting {
                field: "visual_size",
                error: Error::invalid(format!(
                    "the visual size {} must be above 0 and at most {most}° each way",
                    crate::message::SizeText::Degrees(h, w)
                )),
            });
        }
        let key_ok = |k: char| k.is_ascii_lowercase() || k.is_ascii_digit();
        if !key_ok(self.keys.convex) || !key_ok(self.keys.concave) {
            return Err(BadSetting {
                field: "keys",
                error: Error::invalid(format!(
                    "the response keys '{}' and '{}' must be lower-case letters or digits",
                    self.keys.convex, self.keys.concave
                )),
            });
        }
        if self.keys.convex == self.keys.concave {
            return Err(BadSetting {
                field: "keys",
                error: Error::invalid(format!(
                    "the two response keys are both '{}'",
                    self.keys.convex
                )),
            });
        }
        if self.timing.fixation_ms > 10_000 || self.timing.blank_ms > 10_000 {
            return Err(BadSetting {
                field: "timing",
                error: Error::invalid(
                    "the fixation and blank screens must each last at most 10000 ms",
                ),
            });
        }
        if let Some(g) = self.gamma {
            if !(g.is_finite() && (0.1..=10.0).contains(&g)) {
                return Err(BadSetting {
                    field: "gamma",
                    error: Error::invalid(format!("the display gamma {g} must be 0.1 to 10")),
                });
            }
        }
        if self.break_every > MAX_REPEATS * 360 {
            return Err(BadSetting {
                field: "break_every",
                error: Error::invalid(format!(
                    "a break every {} trials is more than the experiment can have",
                    self.break_every
                )),
            });
        }
        if let Some(url) = &self.save_url {
            field("save_url", check_url(url, "the save URL", true))?;
        }
        if let Some(url) = &self.completion_url {
            field(
                "completion_url",
                check_url(url, "the completion URL", false),
            )?;
        }
        Ok(())
    }

    /// The stimulus has a light to turn, and the light is left to the trials.
    fn check_stimulus(&self) -> Result<()> {
        let info = stimulus::find(&self.stimulus)?.info();
        if !info.params.iter().any(|p| p.name == "light") {
            return Err(Error::invalid(format!(
                "'{}' has no light to turn: the experiment rotates the shading by turning the light (use a shaded stimulus such as bumps, gaussian or sphere)",
                self.stimulus
            )));
        }
        if self.params.contains_key("light") {
            return Err(Error::invalid(
                "the light is set by each trial's rotation; give its slant instead of a light parameter",
            ));
        }
        Ok(())
    }
}

/// An absolute `http(s)://` URL (or, with `path_ok`, a path on the page's host) without
/// spaces or quotes.
fn check_url(url: &str, what: &str, path_ok: bool) -> Result<()> {
    let absolute = url.starts_with("https://") || url.starts_with("http://");
    let path = path_ok && url.starts_with('/') && !url.starts_with("//");
    let clean = url.len() <= 2000
        && url
            .chars()
            .all(|c| c.is_ascii_graphic() && !matches!(c, '"' | '\'' | '<' | '>' | '\\'));
    if !(absolute || path) || !clean {
        return Err(Error::invalid(format!(
            "{what} '{url}' must be an http:// or https:// address{} without spaces or quotes",
            if path_ok {
                " (or a path on the page's host, /...)"
            } else {
                ""
            }
        )));
    }
    Ok(())
}

/// The parameters that make `name` one target: `bumps` with one bump, the others as they are.
fn default_params(name: &str) -> Map<String, Value> {
    let mut params = Map::new();
    if name == "bumps" {
        params.insert("rows".into(), 1.into());
        params.insert("columns".into(), 1.into());
        params.insert("pattern".into(), "bumps".into());
    }
    params
}

/// The rotations normalised to [0, 360), refused when empty, not finite or repeated.
fn rotations(given: &[f64]) -> Result<Vec<f64>> {
    if given.is_empty() {
        return Err(Error::invalid("the experiment needs at least one rotation"));
    }
    if given.len() > 360 {
        return Err(Error::invalid(format!(
            "{} rotations are too many (at most 360)",
            given.len()
        )));
    }
    let mut out: Vec<f64> = Vec::with_capacity(given.len());
    for &r in given {
        if !r.is_finite() {
            return Err(Error::invalid(format!("the rotation {r} is not a number")));
        }
        let n = r.rem_euclid(360.0);
        // 359.9999999 and 0 are the same direction on screen.
        let n = if (360.0 - n) < 1e-9 { 0.0 } else { n };
        if out.iter().any(|o| (o - n).abs() < 1e-9) {
            return Err(Error::invalid(format!(
                "the rotation {r} is given twice (rotations are taken modulo 360)"
            )));
        }
        out.push(n);
    }
    Ok(out)
}

/// The display the images were made for.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Display {
    /// Pixels per degree of the images.
    pub ppd: f64,
    /// The viewing distance the calibration assumes, centimetres.
    pub viewing_distance_cm: f64,
    /// Each image's size in degrees, (height, width).
    pub visual_size: (f64, f64),
    /// Each image's size in pixels, (height, width).
    pub shape: (usize, usize),
    /// The display gamma of the images, if any.
    pub gamma: Option<f64>,
    /// The page's background, the images' own background colour (`#rrggbb`), so their edges
    /// do not show.
    pub background: String,
}

/// One stimulus image of the folder.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImageEntry {
    /// The rotation θ it shows, degrees.
    pub rotation_deg: f64,
    /// Its path in the folder (`images/theta-015.png`); its sidecar and mask lie beside it.
    pub file: String,
    /// The light it was rendered under.
    pub light: String,
    /// Where its bright side faces, measured on the pixels (tilt convention, degrees): the
    /// direction of the luminance-weighted centroid of the target (to 0.01°), which must lie
    /// within 45° of the rotation.
    pub bright_side_deg: f64,
}

/// One trial, in presentation order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    /// Its number, from 1, over practice and test.
    pub trial: usize,
    /// `practice` or `test`.
    pub block: &'static str,
    /// The rotation θ shown, degrees.
    pub rotation_deg: f64,
    /// The image shown.
    pub image: String,
}

/// The model and conventions the design and its responses follow.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelNote {
    /// What θ is.
    pub convention: &'static str,
    /// The observer model.
    pub formula: &'static str,
    /// The header of the plain responses CSV `fit observer` also reads.
    pub responses_csv: &'static str,
    /// The columns shadelab adds to jsPsych's data rows ([`DATA_COLUMNS`]).
    pub data_columns: &'static str,
}

/// Everything the page runs: `design.json`, also embedded in `index.html`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Design {
    /// Always `shadelab`.
    pub program: &'static str,
    /// The version that wrote it.
    pub version: &'static str,
    /// The stimulus.
    pub stimulus: String,
    /// Its parameters, defaults filled in (without the light, which each image's entry gives).
    pub parameters: Value,
    /// The light's slant, degrees.
    pub light_slant_deg: f64,
    /// The seed of the trial order.
    pub seed: u64,
    /// The rotations, degrees in [0, 360).
    pub rotations_deg: Vec<f64>,
    /// Test trials per rotation.
    pub repeats: usize,
    /// Practice trials.
    pub practice_trials: usize,
    /// Test trials.
    pub test_trials: usize,
    /// The display.
    pub display: Display,
    /// The response keys.
    pub keys: Keys,
    /// Fixation and blank durations.
    pub timing: Timing,
    /// θ's convention, the model, the CSV.
    pub model: ModelNote,
    /// One image per rotation.
    pub images: Vec<ImageEntry>,
    /// Every trial: the practice trials, then the test trials, in the order of the design's
    /// seed; the page shows each participant these in their own order (a seed made of the
    /// design's seed and the participant id).
    pub trials: Vec<Trial>,
    /// A break after every this many test trials (0: none).
    pub break_every: usize,
    /// Whether the keys are swapped for half of the participants.
    pub counterbalance_keys: bool,
    /// Where the page POSTs the data, if anywhere.
    pub save_url: Option<String>,
    /// The POST's body.
    pub save_format: SaveFormat,
    /// Where the participant goes once the data are saved.
    pub completion_url: Option<String>,
    /// The npm packages the page runs on, name to pinned version.
    pub jspsych: BTreeMap<&'static str, &'static str>,
    /// The first 16 hex digits of the MD5 of this design as JSON (with this field empty):
    /// every response row carries it, so that responses collected under an earlier design in
    /// the same folder are told apart from the current design's.
    pub design_hash: String,
}

impl Design {
    /// The hash [`Design::design_hash`] holds.
    fn hash(&self) -> Result<String> {
        use md5::{Digest, Md5};
        let unhashed = Design {
            design_hash: String::new(),
            ..self.clone()
        };
        let bytes = serde_json::to_vec(&unhashed)
            .map_err(|e| Error::Compute(format!("cannot serialise the design: {e}")))?;
        Ok(Md5::digest(&bytes)
            .iter()
            .take(8)
            .map(|b| format!("{b:02x}"))
            .collect())
    }
}

/// One rendered image, kept for the writer.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The resolved request (parameters, size, seed).
    pub request: Request,
    /// The picture and its target.
    pub output: Output,
}

/// What [`run`] made: the design, and the images to write.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The design (what `design.json` holds).
    pub design: Design,
    /// The images, in the order of `design.images`.
    #[serde(skip)]
    pub images: Vec<Rendered>,
    /// Whether [`Report::write`] runs `npm install` in the folder ([`Config::install`]).
    #[serde(skip)]
    pub install: bool,
}

/// The file name of the image for rotation `deg`: `theta-015`, or `theta-007.5` for a
/// fractional one.
fn image_stem(deg: f64) -> String {
    if deg.fract() == 0.0 {
        format!("theta-{deg:03.0}")
    } else {
        let text = format!("{deg:.6}");
        let text = text.trim_end_matches('0');
        let (whole, frac) = text.split_once('.').unwrap_or((text, ""));
        format!("theta-{whole:0>3}.{frac}")
    }
}

/// Where the bright side of the target faces (tilt convention, degrees in [0, 360)): see
/// [`bright_side`]; `None` for a colour picture, one without a target, or a flat target.
pub fn bright_side_deg(output: &Output) -> Option<f64> {
    let Pixels::Gray(image) = &output.pixels else {
        return None;
    };
    let labels = &output.targets.as_ref()?.labels;
    bright_side(image, &|c, r| *labels.get(c, r) != 0)
}

/// Where the bright side of the pixels `inside` faces (tilt convention: 0 = up, +90 = left;
/// degrees in [0, 360)): the direction of Σ (v − v̄)·(x, y) over those pixels, their
/// luminance-weighted centroid seen from their plain centroid; `None` when it is zero (a flat
/// region). Used on every image of an experiment, and by the tests on screenshots of the page.
pub fn bright_side(
    image: &crate::grid::Image,
    inside: &dyn Fn(usize, usize) -> bool,
) -> Option<f64> {
    let w = image.width();
    let pixels: Vec<usize> = (0..image.height() * w)
        .filter(|&p| inside(p % w, p / w))
        .collect();
    let (dx, dy, _) = convexity::luminance_moment(image, &pixels);
    (dx.hypot(dy) >= 1e-9).then(|| convexity::moment_tilt(dx, dy))
}

/// The signed difference a − b of two directions, in (−180, 180].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    if d > 180.0 {
        d - 360.0
    } else {
        d
    }
}

/// Renders one image per rotation and draws the trial order (nothing is written; see
/// [`Report::write`]). Refuses a stimulus that does not show one target, or whose bright side does not
/// face its light (a dimple), since θ would then mean something else.
pub fn run(config: &Config, progress: &dyn Progress) -> Result<Report> {
    config.validate()?;
    let rotations = rotations(&config.rotations)?;
    let size = SizeRequest {
        visual_size: Some(config.visual_size),
        ppd: Some(config.ppd),
        shape: None,
    };
    let light = |deg: f64| format!("tilt={deg},slant={}", config.slant_deg);
    progress.start(rotations.len() as u64, "experiment");
    let rendered: Vec<Rendered> = rotations
        .par_iter()
        .map(|&deg| {
            let mut params = config.params.clone();
            params.insert("light".into(), Value::from(light(deg)));
            let (request, output) = stimulus::generate(
                &config.stimulus,
                &params,
                &size,
                config.seed,
                config.max_pixels,
            )?;
            progress.advance(1);
            Ok(Rendered { request, output })
        })
        .collect::<Result<_>>()?;
    progress.finish();
    let mut images = Vec::with_capacity(rendered.len());
    for (&deg, r) in rotations.iter().zip(&rendered) {
        let targets = r.output.targets.as_ref().map_or(0, |t| t.names.len());
        if targets != 1 {
            return Err(Error::invalid(format!(
                "'{}' with these parameters shows {targets} targets; the experiment shows one per trial",
                config.stimulus
            )));
        }
        let bright = bright_side_deg(&r.output).ok_or_else(|| {
            Error::invalid(format!(
                "'{}' lit from {deg} degrees has no bright side (its target is flat)",
                config.stimulus
            ))
        })?;
        if angle_between(bright, deg).abs() > 45.0 {
            return Err(Error::invalid(format!(
                "the bright side of '{}' lit from {deg} degrees faces {bright:.0} degrees; the experiment needs a stimulus whose bright side faces its light (a bump, not a dimple)",
                config.stimulus
            )));
        }
        images.push(ImageEntry {
            rotation_deg: deg,
            file: format!("images/{}.png", image_stem(deg)),
            light: light(deg),
            bright_side_deg: ((bright * 100.0).round() / 100.0).rem_euclid(360.0),
        });
    }
    let first = rendered
        .first()
        .ok_or_else(|| Error::Compute("internal: no image rendered".into()))?;
    let geometry: Geometry = first.request.geometry;
    let trials = trial_order(&images, config.repeats, config.practice, config.seed);
    let mut parameters = first.request.params.to_json();
    if let Value::Object(map) = &mut parameters {
        map.remove("light");
    }
    let design = Design {
        program: "shadelab",
        version: io::PROGRAM_VERSION,
        stimulus: config.stimulus.clone(),
        parameters,
        light_slant_deg: config.slant_deg,
        seed: config.seed,
        rotations_deg: rotations,
        repeats: config.repeats,
        practice_trials: config.practice,
        test_trials: images.len() * config.repeats,
        display: Display {
            ppd: geometry.ppd,
            viewing_distance_cm: config.viewing_distance_cm,
            visual_size: (geometry.height_deg(), geometry.width_deg()),
            shape: (geometry.height, geometry.width),
            gamma: config.gamma,
            background: background_css(&first.output, config.gamma),
        },
        keys: config.keys,
        timing: config.timing,
        model: ModelNote {
            convention: CONVENTION,
            formula: MODEL,
            responses_csv: CSV_HEADER,
            data_columns: DATA_COLUMNS,
        },
        images,
        trials,
        break_every: config.break_every,
        counterbalance_keys: config.counterbalance_keys,
        save_url: config.save_url.clone(),
        save_format: config.save_format,
        completion_url: config.completion_url.clone(),
        jspsych: JSPSYCH_PACKAGES.iter().map(|(n, v, _)| (*n, *v)).collect(),
        design_hash: String::new(),
    };
    let design = Design {
        design_hash: design.hash()?,
        ..design
    };
    Ok(Report {
        design,
        images: rendered,
        install: config.install,
    })
}

/// The practice trials (rotations drawn with the seed), then every rotation `repeats` times in
/// a seeded shuffle (Fisher–Yates with SplitMix64).
fn trial_order(images: &[ImageEntry], repeats: usize, practice: usize, seed: u64) -> Vec<Trial> {
    let mut rng = SplitMix64::new(seed);
    let trial = |block: &'static str, image: &ImageEntry| Trial {
        trial: 0,
        block,
        rotation_deg: image.rotation_deg,
        image: image.file.clone(),
    };
    let mut trials: Vec<Trial> = (0..practice)
        .map(|_| trial("practice", &images[rng.below(images.len())]))
        .collect();
    let mut test: Vec<Trial> = (0..repeats)
        .flat_map(|_| images.iter().map(|i| trial("test", i)))
        .collect();
    for i in (1..test.len()).rev() {
        test.swap(i, rng.below(i + 1));
    }
    trials.extend(test);
    for (n, t) in trials.iter_mut().enumerate() {
        t.trial = n + 1;
    }
    trials
}

/// The colour of the image's top-left pixel (its background) as CSS `#rrggbb`.
fn background_css(output: &Output, gamma: Option<f64>) -> String {
    let v = match &output.pixels {
        Pixels::Gray(g) => [*g.get(0, 0); 3],
        Pixels::Rgb(c) => *c.get(0, 0),
    };
    let [r, g, b] = v.map(|v| crate::plot::encode(v, gamma));
    format!("#{r:02x}{g:02x}{b:02x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn image_names_sort_by_rotation_and_keep_fractions() {
        assert_eq!(image_stem(0.0), "theta-000");
        assert_eq!(image_stem(15.0), "theta-015");
        assert_eq!(image_stem(345.0), "theta-345");
        assert_eq!(image_stem(7.5), "theta-007.5");
        assert_eq!(image_stem(112.25), "theta-112.25");
    }

    #[test]
    fn rotations_are_normalised_and_twins_refused() {
        assert_eq!(
            rotations(&[-90.0, 360.0, 45.0]).unwrap(),
            vec![270.0, 0.0, 45.0]
        );
        assert!(rotations(&[0.0, 360.0]).is_err());
        assert!(rotations(&[]).is_err());
        assert!(rotations(&[f64::NAN]).is_err());
        assert_eq!(angle_between(10.0, 350.0), 20.0);
        assert_eq!(angle_between(350.0, 10.0), -20.0);
    }
}
