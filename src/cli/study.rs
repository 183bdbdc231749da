//! `shadelab study run` and `shadelab study merge`: a grid of stimuli × parameters × priors,
//! in parallel on one machine or in shards on many (see docs/studies.md), merged into the
//! files a single run writes.

use super::destination;
use super::output::Output;
use super::progress::Bar;
use super::{CliError, CliResult, Global};
use shadelab::pipeline::study::Shard;
use shadelab::pipeline::study::{self as pipeline, StudyMergeConfig, StudyRunConfig};
use shadelab::{CommandReport, StudyMergeReport, StudyRunReport};
use std::path::PathBuf;
use std::time::Instant;

/// The subcommands of `study`.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// Run a study spec (or one shard of it) into an output folder.
    Run(RunArgs),
    /// Join the output folders of every shard into one, identical to an unsharded run.
    Merge(MergeArgs),
}

/// Arguments of `study run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The study spec (JSON; see docs/studies.md).
    spec: PathBuf,
    /// Run only shard I of N (0 ≤ I < N): the grid points whose number is I modulo N.
    #[arg(long, value_name = "I/N", allow_hyphen_values = true)]
    shard: Option<String>,
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file): results.csv, sweep.csv, study.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Arguments of `study merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The shard output folders (every shard of one study, any order).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder for the merged results.csv, sweep.csv and study.json (written whole or not at all; it replaces only the files shadelab writes and keeps every other file).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Runs `study`.
pub fn run(command: Command, global: &Global) -> CliResult {
    match command {
        Command::Run(a) => run_study(a, global),
        Command::Merge(a) => merge_shards(a, global),
    }
}

fn run_study(args: RunArgs, global: &Global) -> CliResult {
    let started = Instant::now();
    let shard = match &args.shard {
        // The library's message begins "shard 'I/N': …"; here it is the flag's.
        Some(text) => Shard::parse(text).map_err(|e| CliError::usage(format!("--{e}")))?,
        None => Shard::WHOLE,
    };
    let config = StudyRunConfig::load(&args.spec, shard, global.max_pixels)?;
    let dest = destination::<StudyRunReport>(&args.out, global, vec![args.spec.clone()])?;
    let report = pipeline::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.wrote(&target, started.elapsed().as_secs_f64());
    let text = format!(
        "{} of {} grid points (shard {}/{})\n",
        report.points.len(),
        report.point_count,
        shard.index,
        shard.count
    );
    out.results(&text, &report)
}

fn merge_shards(args: MergeArgs, global: &Global) -> CliResult {
    let config = StudyMergeConfig::new(args.dirs, &args.out)
        .map_err(|e| CliError::usage(format!("--out {e}")))?;
    let dest = destination::<StudyMergeReport>(&args.out, global, config.dirs.clone())?;
    let report = pipeline::merge(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.note(format!("wrote {}", target.display()));
    let text = format!("merged {} shard folders\n", config.dirs.len());
    out.results(&text, &report)
}
