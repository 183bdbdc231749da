//! Command-line parsing and dispatch. Each subcommand lives in its own file; none holds an
//! algorithm. Errors print as one line, `error: …` with the cause chain, and exit with 2 for
//! usage errors and 1 for everything else (never a panic or a backtrace).

mod analyze;
mod bench;
mod benchmark;
mod describe;
mod error;
mod eval;
mod experiment;
mod fit;
mod flags;
mod gallery;
mod output;
mod progress;
mod render;
mod solve;
mod study;

use clap::{Parser, Subcommand};
use error::{cancelled, hint, one_line, INTERRUPTED};
pub use error::{CliError, CliResult};
use std::process::ExitCode;

/// Options every subcommand accepts.
#[derive(Debug, Clone, clap::Args)]
pub struct Global {
    /// No progress bars or chatter on stderr (results still print on stdout).
    #[arg(long, global = true)]
    pub quiet: bool,
    /// Print the results on stdout as one JSON document (the command's report) instead of a
    /// table.
    #[arg(long, global = true)]
    pub json: bool,
    /// Worker threads (default: all cores). Outputs are identical for any count.
    #[arg(long, global = true, value_name = "N", allow_hyphen_values = true)]
    pub threads: Option<usize>,
    /// Largest image accepted or made, in pixels.
    #[arg(long, global = true, value_name = "N", default_value_t = shadelab::DEFAULT_MAX_PIXELS,
        allow_hyphen_values = true
    )]
    pub max_pixels: usize,
    /// Write into a folder that shadelab did not write (every other file in it stays), or
    /// replace a file that it did not write.
    #[arg(long, global = true)]
    pub force: bool,
}

#[derive(Debug, Parser)]
#[command(
    name = "shadelab",
    version,
    about = "Shape-from-shading stimuli and analyses for vision science"
)]
struct Cli {
    #[command(flatten)]
    global: Global,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Render a stimulus or surface to PNG/.npy with a JSON sidecar.
    Render(render::Args),
    /// List everything that can be rendered, one line each.
    List,
    /// Show a stimulus's parameters with defaults and ranges.
    Describe(describe::Args),
    /// Render every preset of stimuli/ into a folder with thumbnails and an index.html.
    Gallery(gallery::Args),
    /// Recover surface normals and depth from one shaded image (shape from shading).
    Solve(solve::Args),
    /// Analyses of an image or stimulus (lightness models, the fading disk).
    #[command(subcommand)]
    Analyze(analyze::Command),
    /// Time the shape-from-shading solvers (multigrid, Jacobi, the NumPy reference) as a table.
    Bench(bench::Args),
    /// Score the lightness models against people: stimupy's RHS2007 and murray2020 stimuli with their human data.
    Benchmark(benchmark::Args),
    /// Run a grid of stimuli × parameters × priors (whole or one shard), or merge shards.
    #[command(subcommand)]
    Study(study::Command),
    /// Measure the shape-from-shading engine on real data (bunny, Mozart, DiLiGenT, Beethoven).
    Eval(eval::Args),
    /// Write a jsPsych 8 study (bump or dimple?) with a pilot mode, saving to JATOS, a server or a download.
    Experiment(experiment::Args),
    /// Fit models to responses: `fit observer` estimates a light prior, a convexity prior and
    /// a lapse rate from bump/dimple judgements.
    #[command(subcommand)]
    Fit(fit::Command),
}

/// Parses the command line, runs the subcommand and turns the outcome into an exit code.
pub fn main() -> ExitCode {
    // Ctrl-C, SIGTERM or SIGHUP: ask the library to stop (`shadelab::cancel`). Workers stop at
    // the flag; the main thread gets `Error::Cancelled`, drops the temporaries of its unfinished
    // outputs (their final names are never touched) and exits with 130. A second signal stops
    // at once: what it leaves is hidden temporaries that the next run on the same output
    // recognises (process id and start time in their names) and removes.
    let _ = ctrlc::set_handler(|| {
        if shadelab::cancel::requested() {
            output::stderr_line("error: interrupted twice; stopped at once");
            std::process::exit(i32::from(INTERRUPTED));
        }
        shadelab::cancel::request();
    });
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                let _ = e.print();
                return if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                    ExitCode::from(2)
                } else {
                    ExitCode::SUCCESS
                };
            }
            // clap's message is several lines (tips, usage); keep the first, as one line, with
            // the indented lines that complete it (the names of missing arguments).
            let text = e.render().to_string();
            let mut lines = text.lines();
            let mut first = lines
                .next()
                .unwrap_or("invalid arguments")
                .trim_start_matches("error: ")
                .to_string();
            if first.ends_with(':') {
                let names: Vec<&str> = lines
                    .take_while(|l| l.starts_with("  "))
                    .map(str::trim)
                    .collect();
                first = format!("{} {}", first, names.join(", "));
            }
            output::stderr_line(&format!("error: {first} (see shadelab --help)"));
            return ExitCode::from(2);
        }
    };
    let result = configure_threads(&cli.global).and_then(|_| run(cli.command, &cli.global));
    let interrupted = shadelab::cancel::requested();
    match result {
        Ok(()) if !interrupted => ExitCode::SUCCESS,
        // The signal came after the last output was committed: it is whole and in place, but a
        // stopped run never reports success.
        Ok(()) => {
            output::stderr_line("error: interrupted after the output was complete");
            ExitCode::from(INTERRUPTED)
        }
        Err(e) if interrupted || cancelled(&e.error) => {
            output::stderr_line("error: interrupted; the unfinished output was removed");
            ExitCode::from(INTERRUPTED)
        }
        Err(e) => {
            output::stderr_line(&format!("error: {}{}", one_line(&e.error), hint(&e.error)));
            ExitCode::from(if e.usage { 2 } else { 1 })
        }
    }
}

/// Where a command writes `path`, with `--force`, never replacing `inputs`.
pub(crate) fn output_to(
    path: &std::path::Path,
    global: &Global,
    inputs: Vec<std::path::PathBuf>,
) -> shadelab::Output {
    shadelab::Output::new(path)
        .force(global.force)
        .reads(inputs)
}

/// [`output_to`], claimed now for a folder marked by `marker`, so that a folder that may not be
/// written fails before the work.
pub(crate) fn destination_marked(
    path: &std::path::Path,
    global: &Global,
    inputs: Vec<std::path::PathBuf>,
    marker: &str,
) -> Result<shadelab::Output, CliError> {
    let out = output_to(path, global, inputs);
    out.check(marker)?;
    Ok(out)
}

/// [`destination_marked`] for a command's report `R`.
pub(crate) fn destination<R: shadelab::CommandReport>(
    path: &std::path::Path,
    global: &Global,
    inputs: Vec<std::path::PathBuf>,
) -> Result<shadelab::Output, CliError> {
    destination_marked(path, global, inputs, R::MARKER)
}

fn configure_threads(global: &Global) -> CliResult {
    if let Some(n) = global.threads {
        if n == 0 {
            return Err(CliError::usage("--threads must be at least 1"));
        }
        let (n, capped) = shadelab_core::parallel::capped_threads(n);
        if capped {
            output::Output::new(global).warn(format!(
                "--threads {} is more than {n} (4 per core of this machine): using {n}",
                global.threads.unwrap_or(n)
            ));
        }
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| CliError::usage(format!("cannot set --threads {n}: {e}")))?;
    }
    Ok(())
}

fn run(command: Command, global: &Global) -> CliResult {
    match command {
        Command::Render(args) => render::run(args, global),
        Command::List => describe::list(global),
        Command::Describe(args) => describe::run(args, global),
        Command::Gallery(args) => gallery::run(args, global),
        Command::Solve(args) => solve::run(args, global),
        Command::Analyze(args) => analyze::run(args, global),
        Command::Bench(args) => bench::run(args, global),
        Command::Benchmark(args) => benchmark::run(args, global),
        Command::Study(args) => study::run(args, global),
        Command::Eval(args) => eval::run(args, global),
        Command::Experiment(args) => experiment::run(args, global),
        Command::Fit(args) => fit::run(args, global),
    }
}
