//! Writing the experiment folder: the page, its scripts and styles, the images, `design.json`
//! and a README that says how to run it, whole or not at all.

use super::{
    package_json, Design, Report, DATA_COLUMNS, JSPSYCH_PACKAGES, MARKER, MODEL, PAGE_HTML,
    RUNNER_CSS, RUNNER_JS, TIMELINE_JS,
};
use crate::error::{Error, Result};
use crate::io::{self, BitDepth};
use crate::parallel::prelude::*;
use crate::stimulus::{self, ExportOptions};
use std::path::{Path, PathBuf};

impl Report {
    /// Writes the experiment folder whole (or not at all) and returns its path: `index.html`,
    /// `experiment.js`, `experiment.css`, `design.json`, `README.md` and `images/` (per rotation
    /// a PNG, its sidecar and its target mask).
    ///
    /// A folder that holds files an earlier run did not write (responses saved beside the design)
    /// is refused unless [`Output::force`](crate::pipeline::Output::force); with it they are kept, as every file shadelab did not
    /// write always is, and [`Written::kept`] lists them. npm's `node_modules/` and
    /// `package-lock.json` are the lab's: always kept, never listed; `package.json` keeps the
    /// lab's own dependencies, with shadelab's pins set in it. `npm install` (with
    /// [`Config::install`](super::Config::install)) runs in the folder once it is in place.
    pub fn write(&self, out: &crate::pipeline::Output) -> Result<Written> {
        let report = self;
        let dir = out
            .folder(MARKER)?
            .refusing_collected("the experiment's design")
            .leaves_to(NPM_FILES);
        // The lab's package.json (its own plugins beside shadelab's pins), read before any work.
        let package = package_json_over(&dir.target().join("package.json"))?;
        let images = dir.path().join("images");
        std::fs::create_dir(&images).map_err(|e| Error::io(&images, e))?;
        let options = ExportOptions {
            bit_depth: BitDepth::Eight,
            gamma: report.design.display.gamma,
            ..ExportOptions::default()
        };
        let design = &report.design;
        report
            .images
            .par_iter()
            .zip(design.images.par_iter())
            .map(|(r, entry)| {
                stimulus::write_output(
                    &design.stimulus,
                    &r.request,
                    &r.output,
                    &dir.path().join(&entry.file),
                    &options,
                    // Into the run's own fresh folder.
                    true,
                    None,
                )
                .map(|_| ())
            })
            .collect::<Result<Vec<()>>>()?;
        let json = serde_json::to_value(design)
            .map_err(|e| Error::Compute(format!("cannot serialise the design: {e}")))?;
        io::write_json(&dir.path().join(MARKER), &json)?;
        // The page carries the design itself, so it also runs when opened as a file; `<` is
        // escaped so that no text of the design can close the script element.
        let embedded = serde_json::to_string(&json)
            .map_err(|e| Error::Compute(format!("cannot serialise the design: {e}")))?
            .replace('<', "\\u003c");
        let scripts: String = JSPSYCH_PACKAGES
            .iter()
            .map(|(_, _, script)| format!("<script src=\"node_modules/{script}\"></script>\n"))
            .collect();
        let page = |jatos: &str| {
            PAGE_HTML
                .replace("{{BACKGROUND}}", &design.display.background)
                .replace("{{SCRIPTS}}", scripts.trim_end())
                .replace("{{JATOS}}", jatos)
                .replace("{{DESIGN}}", &embedded)
        };
        io::write_text(&dir.path().join("experiment.js"), RUNNER_JS)?;
        io::write_text(&dir.path().join("shadelab-timeline.js"), TIMELINE_JS)?;
        io::write_text(&dir.path().join("experiment.css"), RUNNER_CSS)?;
        io::write_text(&dir.path().join("package.json"), &package)?;
        io::write_text(&dir.path().join("README.md"), &readme(design))?;
        io::write_text(&dir.path().join("index.html"), &page(""))?;
        // JATOS serves its jatos.js beside the study's files; a static host has none, so the
        // JATOS page is a file of its own rather than a failing script in index.html.
        io::write_text(
            &dir.path().join("jatos.html"),
            &page("<script src=\"jatos.js\"></script>\n"),
        )?;
        let (folder, kept) = dir.commit_keeping()?;
        // In the folder as committed, where the lab's node_modules/ and package-lock.json were
        // carried over: npm updates shadelab's pins and keeps the lab's packages.
        let install = if report.install {
            npm_install(&folder)
        } else {
            Install::NotAsked
        };
        Ok(Written {
            folder,
            kept,
            install,
        })
    }
}

/// The entries of a study folder that are npm's, not shadelab's: a rerun keeps them as they
/// are (with the lab's own plugins), and `npm install` updates them.
const NPM_FILES: &[&str] = &["node_modules", "package-lock.json"];

/// The package.json to write over `existing` (the folder's, if any): the lab's file as it is,
/// with shadelab's pins ([`JSPSYCH_PACKAGES`]) set in its `dependencies`; a new one when there
/// is none. A file that is not a JSON object with an object of `dependencies` is refused,
/// naming it, rather than replaced with the lab's packages lost.
fn package_json_over(existing: &Path) -> Result<String> {
    let Ok(text) = std::fs::read_to_string(existing) else {
        return Ok(package_json());
    };
    let bad = |why: &str| {
        Error::format(
            existing,
            format!("{why}, so shadelab cannot set its jsPsych versions in it (fix or remove it)"),
        )
    };
    let mut json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| bad(&format!("is not JSON ({e})")))?;
    let object = json
        .as_object_mut()
        .ok_or_else(|| bad("is not a JSON object"))?;
    let deps = object
        .entry("dependencies")
        .or_insert_with(|| serde_json::Value::Object(serde_json::Map::new()))
        .as_object_mut()
        .ok_or_else(|| bad("has `dependencies` that are not an object"))?;
    for (name, version, _) in JSPSYCH_PACKAGES {
        deps.insert(name.to_string(), serde_json::Value::from(*version));
    }
    Ok(serde_json::to_string_pretty(&json).unwrap_or_default() + "\n")
}

/// Whether jsPsych was installed into the folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Install {
    /// `npm install` ran: `node_modules/` holds jsPsych and its plugins.
    Installed,
    /// Not asked for ([`Config::install`](super::Config::install) false).
    NotAsked,
    /// Asked for, but it could not be done: why (npm missing, no network); the README says the
    /// one command to run.
    Failed(String),
}

/// Runs `npm install` in `folder` (quietly, without audit), so that `node_modules/` holds the
/// packages of its `package.json`.
fn npm_install(folder: &Path) -> Install {
    let out = std::process::Command::new("npm")
        .args([
            "install",
            "--no-audit",
            "--no-fund",
            "--loglevel=error",
            "--fetch-retries=1",
        ])
        .current_dir(folder)
        .stdin(std::process::Stdio::null())
        .output();
    match out {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Install::Failed("npm is not on PATH".into())
        }
        Err(e) => Install::Failed(format!("npm could not start: {e}")),
        Ok(o) if o.status.success() && folder.join("node_modules/jspsych").is_dir() => {
            Install::Installed
        }
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stderr);
            let line = text
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("no message");
            Install::Failed(format!("npm install failed ({}): {line}", o.status))
        }
    }
}

/// What [`Report::write`] did.
#[derive(Debug, Clone)]
pub struct Written {
    /// The experiment folder.
    pub folder: PathBuf,
    /// The files of the folder that shadelab did not write and kept (paths inside it).
    pub kept: Vec<PathBuf>,
    /// Whether jsPsych was installed into it.
    pub install: Install,
}

/// The lab's README for one experiment folder.
fn readme(d: &Design) -> String {
    let rotations: Vec<String> = d.rotations_deg.iter().map(|r| format!("{r}")).collect();
    let packages: Vec<String> = d.jspsych.iter().map(|(n, v)| format!("{n} {v}")).collect();
    format!(
        "# A shadelab experiment: bump or dimple?\n\n\
Written by shadelab {version}. Each trial shows one shaded `{stimulus}` (lit at slant \
{slant}°) turned so that its bright side faces θ (0 = up, +90 = left); the participant presses \
**{convex}** for a bump (convex) and **{concave}** for a dimple (concave). {practice} practice \
trials, then {test} test trials: the rotations {rotations} degrees, {repeats} times each{breaks}. \
Each participant sees them in their own order, shuffled with a seed made of the design's seed \
({seed}) and the participant id; the same id always gets the same order.\n\n\
## Installing jsPsych (once)\n\n\
The study runs on jsPsych 8 ({packages}), pinned in `package.json`. In this folder:\n\n\
    npm install\n\n\
(`shadelab experiment` runs it when npm is on PATH.) Then the folder is a static site that runs \
offline: `node_modules/` holds everything the pages load. Packages you add yourself (`npm install \
@jspsych/plugin-survey`) stay: running `shadelab experiment` on this folder again keeps \
`node_modules/`, `package-lock.json` and your dependencies in `package.json`, and sets only \
shadelab's own versions there.\n\n\
## Running it\n\n\
- Locally: `python3 -m http.server 8000` in this folder, then open http://localhost:8000/.\n\
- Any static host (a lab server, GitHub Pages, Pavlovia, Cognition.run): upload the folder \
with `node_modules/`.\n\
- JATOS: zip the folder (with `node_modules/`), import it as a study's assets and make \
`jatos.html` the component's HTML file; the data go to JATOS (`jatos.submitResultData`) and \
the study ends with `jatos.endStudy`.\n\
- Prolific: give Prolific the study link with \
`?PROLIFIC_PID={{{{%PROLIFIC_PID%}}}}&STUDY_ID={{{{%STUDY_ID%}}}}&SESSION_ID={{{{%SESSION_ID%}}}}`; the three ids are \
saved in every row, and the participant id is PROLIFIC_PID. {completion}\n\n\
URL parameters: `participant=ID` (the id, else PROLIFIC_PID, else one drawn by the page), \
`save_url=URL` (POST the data there{save}), `save_format=json|csv`, `calibration=none` (no \
card calibration: each image pixel is one CSS pixel, {ppd} pixels per degree), `fullscreen=0`.\n\n\
The page checks the browser (phones and touch-only tablets are refused), asks for consent, \
goes fullscreen, calibrates the screen with jsPsych's virtual chinrest (a credit card held to \
the screen gives pixels per cm; with the viewing distance of {distance} cm, pixels per degree, \
so the images are {h}° × {w}°), then runs the instructions, the practice and the test with a \
fixation cross ({fixation} ms) before each image. At the end the data go to JATOS or to the \
save URL (tried three times; if that fails the participant is told and downloads the file), \
or else the participant downloads them.\n\n\
## Embedding the trials in your own jsPsych study\n\n\
`shadelab-timeline.js` defines `shadelabTimeline(design, options)`, which returns the \
instructions, practice, test and breaks as a jsPsych timeline to put between your own trials \
(see the comment at its top for the options):\n\n\
    const design = await (await fetch('design.json')).json();\n\
    jsPsych.run([consent, shadelabTimeline(design, {{ jsPsych }}), questionnaire]);\n\n\
## Checking the design first (pilot mode)\n\n\
`index.html?simulate=tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1` runs the study in jsPsych's \
simulation mode, every trial answered from the observer model below (prior light tilt 26° \
left, concentration 2, convexity prior 0.7, lapse rate 0.02, random seed 1), and shows the \
data. `tilt` and `kappa` are required; `convex` defaults to 0.5, `lapse` to 0, `seed` to 1. \
It works with the other parameters (e.g. `save_url`). Fit it with `shadelab fit observer` to \
see how well this design recovers a prior.\n\n\
## The data\n\n\
jsPsych's own CSV or JSON, one row per screen. The trial rows carry `shadelab = trial` and \
the columns {columns}; `response` is the key pressed, `judgement` convex or concave, `rt` \
the reaction time from the image's onset (ms). `shadelab fit observer` reads the file (or a \
folder of them) as it is.\n\n\
## The model\n\n\
{model}\n\n\
with θ = rotation_deg, vM a von Mises density, μ the prior's light tilt, κ its concentration, \
π the convexity prior and λ the lapse rate.\n\n\
## Files\n\n\
- `index.html` (the study), `jatos.html` (the same under JATOS), `experiment.js` (the study \
around the trials), `shadelab-timeline.js` (the trials), `experiment.css`, `package.json`\n\
- `design.json`: every trial, the seed, the display, the keys and this convention\n\
- `images/theta-DDD.png`: one image per rotation (8-bit, display gamma {gamma}), with its \
shadelab sidecar (`.json`, every parameter: `shadelab render --spec` reproduces it) and target \
mask (`_mask.png`)\n",
        version = d.version,
        stimulus = d.stimulus,
        slant = d.light_slant_deg,
        convex = d.keys.convex.to_ascii_uppercase(),
        concave = d.keys.concave.to_ascii_uppercase(),
        practice = d.practice_trials,
        test = d.test_trials,
        rotations = rotations.join(", "),
        repeats = d.repeats,
        breaks = if d.break_every > 0 && d.break_every < d.test_trials {
            format!(", with a break every {} trials", d.break_every)
        } else {
            String::new()
        },
        seed = d.seed,
        packages = packages.join(", "),
        completion = match &d.completion_url {
            Some(url) => format!("Once the data are saved the page goes to {url}."),
            None => "Give `shadelab experiment --prolific-code CODE` to send participants back \
                     to Prolific once their data are saved."
                .into(),
        },
        save = match &d.save_url {
            Some(url) => format!("; this design's own: {url}"),
            None => String::new(),
        },
        distance = d.display.viewing_distance_cm,
        h = d.display.visual_size.0,
        w = d.display.visual_size.1,
        ppd = d.display.ppd,
        fixation = d.timing.fixation_ms,
        columns = DATA_COLUMNS,
        model = MODEL,
        gamma = d
            .display
            .gamma
            .map_or_else(|| "none (linear)".to_string(), |g| g.to_string()),
    )
}
