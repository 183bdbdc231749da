//! `shadelab benchmark`: every lightness model on the stimuli of stimupy's RHS2007 and
//! murray2020 that have human data, scored against the people (direction of effect, Spearman
//! ρ). The stimuli and data come from stimupy, exported by Python into a temporary folder.

use super::output::Output;
use super::progress::Bar;
use super::{CliResult, Global};
use shadelab::pipeline::benchmark::{self as pipeline, BenchmarkConfig, BenchmarkReport};
use shadelab::CommandReport;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `benchmark`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file): benchmark.csv, scores.csv, benchmark.md, benchmark.png, benchmark.json.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// The models, comma separated, or all.
    #[arg(
        long,
        value_name = "odog,lodog,flodog,retinex,highpass|all",
        default_value = "all"
    )]
    models: String,
    /// Only these stimuli, comma separated (NAME or SET/NAME, e.g. WE_thick,murray2020/white); all with human data when not given.
    #[arg(long, value_name = "NAME,…", value_delimiter = ',')]
    stimuli: Vec<String>,
    /// The Python interpreter that has stimupy (pip install stimupy==1.2.0).
    #[arg(long, value_name = "PY", default_value = "python3")]
    python: String,
}

/// Runs `benchmark`: stimupy's export → [`BenchmarkConfig`] → [`pipeline::run`] → the table.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let models = BenchmarkConfig::parse_models(&args.models)
        .map_err(|e| super::CliError::usage(format!("--models: {e}")))?;
    // Claimed before the work, so that a folder that may not be replaced fails at once.
    let dest = match &args.out {
        Some(out) => Some(super::destination::<BenchmarkReport>(
            out,
            global,
            Vec::new(),
        )?),
        None => None,
    };
    let config = BenchmarkConfig::from_stimupy(&args.python, models, &args.stimuli)?;
    let report = pipeline::run(&config, &Bar::new(global.quiet))?;
    let out = Output::new(global);
    if let Some(dest) = dest {
        let target = report.write(&dest)?;
        out.wrote(&target, started.elapsed().as_secs_f64());
    }
    out.results(&report.markdown(), &report)
}
