//! `shadelab fit observer`: the observer model fitted to bump/dimple responses (the work is
//! [`shadelab::pipeline::fit`]).

use super::destination;
use super::output::Output;
use super::progress::Bar;
use super::{CliResult, Global};
use shadelab::pipeline::fit::FitOptions;
use shadelab::pipeline::fit::{self as pipeline, Config, KeyMap, Report as FitReport};
use shadelab::CommandReport;
use std::path::PathBuf;
use std::time::Instant;

/// The subcommands of `fit`.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Fit the observer model P(convex | θ) (von Mises light prior μ, κ; convexity prior π;
    /// lapse λ) to a responses CSV by maximum likelihood, with profile-likelihood 95% intervals (and parametric-bootstrap ones beside them).
    Observer(ObserverArgs),
}

/// Arguments of `fit observer`.
#[derive(Debug, clap::Args)]
pub struct ObserverArgs {
    /// The data: jsPsych's CSV or JSON as the `shadelab experiment` study saves it, a plain
    /// responses CSV (columns rotation_deg and response: convex/concave or 1/0), or a folder of
    /// such files (one or more participants each; a design.json in it is read as --design).
    /// Rows without a rotation are skipped in jsPsych data, practice rows always, trials without
    /// a response (timed out) and simulated rows are counted and left out; each participant
    /// (the participant column, else the file's name) is fitted beside the pooled fit. A folder
    /// is read as a lab's data arrive: JATOS's results export (a result per line), semicolon-
    /// separated CSV, the same rows in two files counted once (with a warning), files of two
    /// designs refused.
    responses: PathBuf,
    /// The keys for bump and dimple, when `response` holds the key pressed and the rows do not
    /// say (e.g. fj, or arrowleft,arrowright).
    #[arg(long, value_name = "BUMP,DIMPLE")]
    keys: Option<String>,
    /// Fit the rows whose `simulated` column is set too (a pilot's, answered by the observer
    /// model; without it they are counted and left out). The Methods paragraph says they were
    /// simulated.
    #[arg(long)]
    include_simulated: bool,
    /// Pool data files of different designs (another `design_hash`), which are refused
    /// otherwise.
    #[arg(long)]
    mixed_designs: bool,
    /// The experiment's design.json, for the Methods paragraph's stimulus and apparatus.
    #[arg(long, value_name = "FILE")]
    design: Option<PathBuf>,
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file): fit.json, fit.png, fit.svg, methods.md (and participants.png, .svg with several participants).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Parametric-bootstrap replicates for the percentile intervals given beside the profile-likelihood ones, and for the non-parametric prior's (0: none).
    #[arg(long, value_name = "N", default_value_t = FitOptions::default().bootstrap)]
    bootstrap: usize,
    /// The bootstrap's random seed.
    #[arg(long, value_name = "S", default_value_t = FitOptions::default().seed)]
    seed: u64,
    /// Also fit a smooth, non-parametric prior over light tilt (24 directions).
    #[arg(long)]
    nonparametric: bool,
    /// Fix the lapse rate at this value instead of estimating it.
    #[arg(long, value_name = "FIXED", allow_hyphen_values = true)]
    lapse: Option<f64>,
}

/// Runs `fit`.
pub fn run(command: Command, global: &Global) -> CliResult {
    match command {
        Command::Observer(a) => observer(a, global),
    }
}

fn observer(args: ObserverArgs, global: &Global) -> CliResult {
    let started = Instant::now();
    let mut config = Config::new(&args.responses);
    if let Some(k) = &args.keys {
        config.reading.keys = Some(KeyMap::parse(k).map_err(|e| super::flags::usage("--keys", e))?);
    }
    config.reading.include_simulated = args.include_simulated;
    config.reading.mixed_designs = args.mixed_designs;
    config.design = args.design.clone();
    config.options = FitOptions {
        lapse: args.lapse,
        nonparametric: args.nonparametric,
        bootstrap: args.bootstrap,
        seed: args.seed,
    };
    // Each value alone, so that the error names its own flag.
    let d = FitOptions::default();
    let alone = |o: FitOptions, flag: &str| o.validate().map_err(|e| super::flags::usage(flag, e));
    alone(
        FitOptions {
            lapse: args.lapse,
            ..d
        },
        "--lapse",
    )?;
    alone(
        FitOptions {
            bootstrap: args.bootstrap,
            ..d
        },
        "--bootstrap",
    )?;
    let dest = destination::<FitReport>(&args.out, global, vec![config.responses.clone()])?;
    let report = pipeline::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    for w in &report.warnings {
        out.warn(w);
    }
    out.wrote(&target, started.elapsed().as_secs_f64());
    let f = &report.pooled;
    let ci = |c: Option<[f64; 2]>| match c {
        Some([lo, hi]) => format!(" [{lo:.3}, {hi:.3}]"),
        None => String::new(),
    };
    let mut text = format!(
        "{} trials at {} rotations, {} participant(s)\n",
        report.design.trials,
        report.design.rotations_deg.len(),
        report.design.participants
    );
    for (name, e) in [
        ("prior tilt (deg)", f.prior_tilt_deg),
        ("prior kappa", f.prior_kappa),
        ("convexity prior", f.convexity_prior),
        ("lapse", f.lapse),
    ] {
        text += &format!("{name}: {:.3}{}\n", e.value, ci(e.ci95));
    }
    text += &format!(
        "log-likelihood {:.2}; delta AIC {:.2}, delta BIC {:.2} against no convexity prior\n",
        f.log_likelihood, f.delta_aic, f.delta_bic
    );
    out.results(&text, &report)
}
