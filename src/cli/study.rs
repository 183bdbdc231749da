//! `shadelab study run` and `shadelab study merge`: a grid of stimuli × parameters × priors,
//! in parallel on one machine or in shards on many (see docs/studies.md), merged into the
//! files a single run writes.

use super::{progress, CliError, CliResult, Global};
use shadelab::analysis::study::{merge, Shard, Study, REPORT, RESULTS, SWEEP};
use shadelab::io::{self, write_text, AtomicDir};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `study`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, clap::Subcommand)]
enum Command {
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
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Output folder (written whole or not at all): results.csv, sweep.csv, study.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Arguments of `study merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// The shard output folders (every shard of one study, any order).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output folder for the merged results.csv, sweep.csv and study.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Runs `study`.
pub fn run(args: Args, global: &Global) -> CliResult {
    match args.command {
        Command::Run(a) => run_study(a, global),
        Command::Merge(a) => merge_shards(a, global),
    }
}

fn run_study(args: RunArgs, global: &Global) -> CliResult {
    let started = Instant::now();
    let shard = match &args.shard {
        Some(text) => Shard::parse(text)?,
        None => Shard::WHOLE,
    };
    let study = Study::load_with_max_pixels(&args.spec, global.max_pixels)?;
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;
    let count = study.shard_points(shard).len();
    let bar = progress::bar(count as u64, "study", global.quiet);
    let output = study.run(shard, &|| bar.inc(1))?;
    bar.finish_and_clear();
    let dir = folder.path().to_path_buf();
    write_text(&dir.join(RESULTS), &output.results)?;
    write_text(&dir.join(SWEEP), &output.sweep)?;
    let report = study.report(shard, &output, started.elapsed().as_secs_f64());
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if !global.quiet {
        eprintln!(
            "{}: {count} of {} grid points (shard {}/{}) in {:.2} s",
            target.display(),
            study.points.len(),
            shard.index,
            shard.count,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn merge_shards(args: MergeArgs, global: &Global) -> CliResult {
    // Replacing one of its own inputs would lose that shard if anything went wrong later.
    let out = std::fs::canonicalize(&args.out).ok();
    if let Some(dir) = args
        .dirs
        .iter()
        .find(|d| out.is_some() && std::fs::canonicalize(d).ok() == out)
    {
        return Err(CliError::usage(format!(
            "--out {} is one of the shard folders being merged ({}); choose another folder",
            args.out.display(),
            dir.display()
        )));
    }
    let merged = merge(&args.dirs)?;
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;
    let dir = folder.path().to_path_buf();
    write_text(&dir.join(RESULTS), &merged.results)?;
    write_text(&dir.join(SWEEP), &merged.sweep)?;
    io::write_json(&dir.join(REPORT), &merged.report)?;
    let target = folder.commit()?;
    if !global.quiet {
        eprintln!(
            "{}: merged {} shard folders",
            target.display(),
            args.dirs.len()
        );
    }
    Ok(())
}
