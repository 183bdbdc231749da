//! `shadelab eval`: the engine on the evaluation data, as a table (and a folder of results).

use super::output::Output;
use super::{flags::SolverFlags, progress::Bar, CliResult, Global};
use shadelab::pipeline::evaluation::{self, Config, Set};
use shadelab::Boundary;
use shadelab::Method;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `eval`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The evaluation data folder (bunny/, mozart/, diligent_normals/, diligent_ball/,
    /// beethoven/ as in ../shared/data).
    #[arg(long, value_name = "DIR")]
    pub data: PathBuf,
    /// Output folder for evaluation.md, evaluation.json and one picture per case (written whole or not at all; it replaces only the files shadelab writes and keeps every other file); default: only print the table.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Run only these sets (comma separated): bunny, mozart, diligent, ball, beethoven.
    #[arg(long, value_name = "SETS", value_delimiter = ',')]
    pub only: Vec<String>,
    /// The DiLiGenT objects to run (comma separated; default all nine).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub objects: Vec<String>,
    /// The light the DiLiGenT normals are rendered under.
    #[arg(
        long,
        value_name = "L",
        default_value = "tilt=0,slant=30",
        allow_hyphen_values = true
    )]
    pub diligent_light: String,
    /// The ball photographs to run (comma separated; default 052,076,008,029,049,041).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub ball_images: Vec<String>,
    /// One boundary condition for every case (occluding, flat, free, limb); default:
    /// occluding, and occluding, free and limb (a row each) for Mozart and the ball.
    #[arg(long, value_name = "occluding|flat|free|limb")]
    pub boundary: Option<String>,
    /// A photograph's albedo: at the default, the library's rule (`solve --albedo estimate`:
    /// the bright tail below this quantile extrapolated); any other value takes this quantile
    /// of its brightness on its mask (a comparison).
    #[arg(long, value_name = "Q", default_value_t = evaluation::BRIGHT_QUANTILE,
        allow_hyphen_values = true
    )]
    pub albedo_quantile: f64,
    /// Divide the ball photographs by the albedo their true normals give (a reference for
    /// what the albedo estimate costs; not available for real use).
    #[arg(long)]
    pub ball_albedo_from_truth: bool,
    /// Side of the square frame the bunny is rasterised into, in pixels.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 256,
        allow_hyphen_values = true
    )]
    pub bunny_size: usize,
    #[command(flatten)]
    pub solver: SolverFlags,
    #[arg(long, value_name = "METHODS", value_delimiter = ',', help = methods_help())]
    pub method: Option<Vec<String>>,
    /// The commit to record in the report; default: `git rev-parse --short HEAD` in the
    /// current folder (with `-dirty` when tracked files are modified), or "unknown".
    #[arg(long, value_name = "ID")]
    pub commit: Option<String>,
}

/// The `--method` help, with the library's default (`shadelab solve`'s method).
fn methods_help() -> String {
    format!(
        "The methods each case is solved with, a row each (comma separated): multigrid \
         (Ikeuchi–Horn), integrable (depth and gradients together, from the multigrid \
         solution), integrable-lm (the integrable method's energy minimised by \
         Levenberg–Marquardt; slower), nested-lm (the same energy, solved coarse to fine; \
         integrable-lm's accuracy in fewer steps), jacobi (Ikeuchi–Horn's fixed point, slowly; for \
         comparison) [default: {}, the method of `shadelab solve`; multigrid is the fast \
         choice]",
        Method::SOLVE_DEFAULT
    )
}

/// Runs `eval`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let mut config = Config::new(&args.data)?;
    if !args.only.is_empty() {
        config.sets = args
            .only
            .iter()
            .map(|s| s.trim().parse::<Set>())
            .collect::<Result<_, _>>()?;
    }
    if !args.objects.is_empty() {
        config.diligent_objects = args.objects.iter().map(|s| s.trim().to_string()).collect();
    }
    if !args.ball_images.is_empty() {
        config.ball_images = args
            .ball_images
            .iter()
            .map(|s| s.trim().trim_end_matches(".png").to_string())
            .collect();
    }
    config.diligent_light = args
        .diligent_light
        .parse()
        .map_err(|e| super::flags::usage("--diligent-light", e))?;
    config.boundary = args.boundary.as_deref().map(Boundary::named).transpose()?;
    config.bunny_size = args.bunny_size;
    config.albedo_quantile = args.albedo_quantile;
    config.ball_albedo_from_truth = args.ball_albedo_from_truth;
    if let Some(methods) = &args.method {
        config.methods = methods
            .iter()
            .map(|m| m.trim().parse::<Method>())
            .collect::<Result<_, _>>()?;
        config.method_source = shadelab::MethodSource::Asked;
    }
    args.solver.apply(&mut config.options)?;
    config.tol = args.solver.tol;
    config.max_iter = args.solver.max_iter;
    config.validate()?;
    let commit = match &args.commit {
        Some(c) => c.clone(),
        None => git_commit().unwrap_or_else(|| "unknown".into()),
    };

    let record = evaluation::Record {
        out: args
            .out
            .as_ref()
            .map(|o| super::output_to(o, global, Vec::new())),
        commit,
        command: std::env::args().collect(),
    };
    let (results, written) = evaluation::run_into(&config, &record, &Bar::new(global.quiet))?;
    let out = Output::new(global);
    if let Some(target) = written {
        out.note(format!(
            "wrote {}: {} cases, {:.1} s",
            target.display(),
            results.len(),
            started.elapsed().as_secs_f64()
        ));
    }
    out.results(&evaluation::markdown_table(&results), &results)
}

/// The short commit of the git checkout in the current folder, `-dirty` when tracked files
/// differ from it; `None` outside a checkout or without git.
fn git_commit() -> Option<String> {
    let run = |args: &[&str]| -> Option<String> {
        let out = std::process::Command::new("git").args(args).output().ok()?;
        out.status
            .success()
            .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
    };
    let head = run(&["rev-parse", "--short", "HEAD"]).filter(|s| !s.is_empty())?;
    let dirty =
        run(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    Some(if dirty { format!("{head}-dirty") } else { head })
}
