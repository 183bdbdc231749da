//! `shadelab experiment --out DIR`: a jsPsych 8 study ("bump or dimple?"); `shadelab experiment
//! pilot STUDY --simulate …`: its simulated participant's data without a browser.

use super::progress::Bar;
use super::{CliError, CliResult, Global};
use shadelab::parse_size;
use shadelab::pipeline::experiment::{
    prolific_completion_url, run as build, run_pilot, Config, Install, PilotConfig,
};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `experiment`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    /// `pilot`: the simulated participant's data without a browser.
    #[command(subcommand)]
    pub command: Option<Sub>,
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file, npm's node_modules/ and package-lock.json and the lab's own dependencies in package.json too): index.html, jatos.html, experiment.js, shadelab-timeline.js, experiment.css, package.json, design.json, README.md and images/.
    #[arg(long, value_name = "DIR", required = true)]
    pub out: Option<PathBuf>,
    /// The stimulus shown (any with a light and one target, e.g. bumps, gaussian, sphere) [default: bumps, one bump].
    #[arg(long, value_name = "NAME")]
    pub stimulus: Option<String>,
    /// Set a stimulus parameter (repeatable); `shadelab describe NAME` lists them. Not the light: each trial's rotation sets it.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = super::render::utf8_text())]
    pub set: Vec<String>,
    /// The rotations θ (the direction the bright side faces; 0 = up, +90 = left), degrees: START:STOP:STEP or a list [default: 0:360:15].
    #[arg(long, value_name = "LIST", allow_hyphen_values = true)]
    pub rotations: Option<String>,
    /// Test trials per rotation [default: 16].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub repeats: Option<usize>,
    /// Practice trials before the test [default: 8].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub practice: Option<usize>,
    /// The light's slant, degrees from the line of sight [default: 45].
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub slant: Option<f64>,
    /// Size of each image in degrees: D (square) or WxH (width first; design.json writes [h, w]) [default: 4].
    #[arg(long, value_name = "DEG|WxH", allow_hyphen_values = true)]
    pub visual_size: Option<String>,
    /// Pixels per degree of the images (and of the display when the page is not calibrated) [default: 32].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub ppd: Option<f64>,
    /// Viewing distance in cm, for the page's credit-card calibration [default: 57].
    #[arg(long, value_name = "CM", allow_hyphen_values = true)]
    pub viewing_distance: Option<f64>,
    /// Seed of the trial order [default: 1].
    #[arg(long, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// The two response keys, bump then dimple, e.g. fj [default: fj].
    #[arg(long, value_name = "BUMP,DIMPLE")]
    pub keys: Option<String>,
    /// A break after every N test trials (0: none) [default: 96].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub break_every: Option<usize>,
    /// Swap the two keys for half of the participants (by their order seed).
    #[arg(long)]
    pub counterbalance_keys: bool,
    /// POST the data to this URL at the end (the page's save_url parameter overrides it); if that fails, the participant downloads them.
    #[arg(long, value_name = "URL")]
    pub save_url: Option<String>,
    /// The POST's body: json (jsPsych's JSON) or csv [default: json].
    #[arg(long, value_name = "FORMAT")]
    pub save_format: Option<String>,
    /// Send participants back to Prolific with this completion code once their data are saved.
    #[arg(long, value_name = "CODE", conflicts_with = "completion_url")]
    pub prolific_code: Option<String>,
    /// Send participants to this URL once their data are saved.
    #[arg(long, value_name = "URL")]
    pub completion_url: Option<String>,
    /// Do not run `npm install` in the folder (the README says the command).
    #[arg(long)]
    pub no_install: bool,
}

/// The subcommands of `experiment`.
#[derive(Debug, clap::Subcommand)]
pub enum Sub {
    /// The study's simulated participant without a browser: the trial rows its page writes in pilot mode (index.html?simulate=…) for the same observer, seed and participant, as CSV.
    Pilot(PilotArgs),
}

/// Arguments of `experiment pilot`.
#[derive(Debug, clap::Args)]
pub struct PilotArgs {
    /// The study folder `shadelab experiment` wrote (or its design.json).
    #[arg(value_name = "STUDY")]
    pub study: PathBuf,
    /// The observer, as the page's simulate parameter: tilt:T,kappa:K[,convex:C][,lapse:L][,seed:S] (convex 0.5, lapse 0, seed 1 by default).
    #[arg(long, value_name = "MODEL")]
    pub simulate: String,
    /// The participant id (the page's participant parameter) [default: simulated-seedS].
    #[arg(long, value_name = "ID")]
    pub participant: Option<String>,
    /// The CSV file to write (replaced only with --force).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Runs `experiment pilot`.
fn pilot(args: PilotArgs, global: &Global) -> CliResult {
    let started = Instant::now();
    let config = PilotConfig {
        study: args.study,
        simulate: args
            .simulate
            .parse()
            .map_err(|e| CliError::usage(format!("--simulate {e}")))?,
        participant: args
            .participant
            .map(|p| p.parse())
            .transpose()
            .map_err(|e| CliError::usage(format!("--participant {e}")))?,
    };
    let report = run_pilot(&config)?;
    report.write(&args.out, &config.design_path(), global.force)?;
    let out = super::output::Output::new(global);
    out.wrote(&args.out, started.elapsed().as_secs_f64());
    out.results(
        &format!(
            "{} trials of participant {} (order seed {}) answered by {}; fit them with `shadelab fit observer {} --include-simulated`",
            report.rows.len(),
            report.participant,
            report.order_seed,
            report.simulate.text(),
            args.out.display()
        ),
        &report,
    )
}

/// Runs `experiment`.
pub fn run(args: Args, global: &Global) -> CliResult {
    if let Some(Sub::Pilot(p)) = args.command {
        return pilot(p, global);
    }
    let Some(out_folder) = args.out.clone() else {
        return Err(CliError::usage("experiment needs --out DIR"));
    };
    let started = Instant::now();
    let mut config = Config::new();
    if let Some(name) = &args.stimulus {
        config.set_stimulus(name)?;
    }
    config
        .params
        .extend(shadelab::Params::parse_pairs(&args.set)?);
    if let Some(text) = &args.rotations {
        config.rotations = super::flags::angles(text, "--rotations")?;
    }
    if let Some(n) = args.repeats {
        config.repeats = n;
    }
    if let Some(n) = args.practice {
        config.practice = n;
    }
    if let Some(s) = args.slant {
        config.slant_deg = s;
    }
    if let Some(v) = &args.visual_size {
        config.visual_size = parse_size::<f64>(v, "--visual-size")?;
    }
    if let Some(p) = args.ppd {
        config.ppd = p;
    }
    if let Some(d) = args.viewing_distance {
        config.viewing_distance_cm = d;
    }
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    if let Some(keys) = &args.keys {
        config.keys = keys
            .parse()
            .map_err(|e| CliError::usage(format!("--keys {e}")))?;
    }
    if let Some(n) = args.break_every {
        config.break_every = n;
    }
    config.counterbalance_keys = args.counterbalance_keys;
    config.save_url = args.save_url.clone();
    if let Some(f) = &args.save_format {
        config.save_format = f
            .parse()
            .map_err(|e| CliError::usage(format!("--save-format {e}")))?;
    }
    if let Some(code) = &args.prolific_code {
        config.completion_url = Some(
            prolific_completion_url(code).map_err(|e| super::flags::usage("--prolific-code", e))?,
        );
    }
    if let Some(url) = &args.completion_url {
        config.completion_url = Some(url.clone());
    }
    config.install = !args.no_install;
    config.max_pixels = global.max_pixels;
    config.check().map_err(super::flags::setting)?;
    // Claimed before the work, so that a folder that may not be written fails at once.
    let dest = super::destination_marked(
        &out_folder,
        global,
        Vec::new(),
        shadelab::pipeline::experiment::MARKER,
    )?;
    let report = build(&config, &Bar::new(global.quiet))?;
    let written = report.write(&dest)?;
    let folder = written.folder;
    let out = super::output::Output::new(global);
    if !written.kept.is_empty() {
        out.warn(format!(
            "kept {} file(s) in {} that the design did not write ({}); response rows carry \
             the design's hash (design_hash {}) to tell the designs apart",
            written.kept.len(),
            folder.display(),
            written
                .kept
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            report.design.design_hash
        ));
    }
    if let Install::Failed(why) = &written.install {
        out.warn(format!(
            "jsPsych is not installed ({why}): run `npm install` in {} before opening the study",
            folder.display()
        ));
    }
    out.wrote(&folder, started.elapsed().as_secs_f64());
    let d = &report.design;
    out.results(
        &format!(
            "{} trials ({} practice, {} rotations x {} repeats); open {}/index.html from a web server (python3 -m http.server; jatos.html under JATOS), or pilot it with index.html?simulate=tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1 (without a browser: shadelab experiment pilot {} --simulate tilt:26,kappa:2 --out pilot.csv)",
            d.trials.len(),
            d.practice_trials,
            d.rotations_deg.len(),
            d.repeats,
            folder.display(),
            folder.display()
        ),
        &report,
    )
}
