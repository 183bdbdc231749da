//! `shadelab bench`: times the shape-from-shading solvers on a synthetic shape and prints a
//! table, with the NumPy reference solver beside them when python3 with numpy and the reference
//! folder are there.

use super::flags::usage;
use super::{progress::Bar, CliError, CliResult, Global};
use shadelab::pipeline::bench::{self, BenchConfig};
use shadelab::{FrontLight, Method};
use std::path::PathBuf;

/// Arguments of `bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Image sides to time, comma separated.
    #[arg(
        long,
        value_name = "N,N,…",
        default_value = "128,256,512,1024",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub sizes: Vec<usize>,
    /// The methods to time, comma separated, in the table's order: multigrid (always timed:
    /// every ratio is to it), jacobi, integrable, integrable-lm, nested-lm.
    #[arg(
        long,
        value_name = "M,M,…",
        default_value = "multigrid,nested-lm,jacobi",
        value_delimiter = ','
    )]
    pub methods: Vec<String>,
    /// Weight λ of the brightness term (0.001 to 1000).
    #[arg(
        long,
        value_name = "L",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub lambda: f64,
    /// The shape: sphere (radius 0.45 of the side) or vase.
    #[arg(long, value_name = "sphere|vase", default_value = "sphere")]
    pub shape: String,
    /// The light (x,y,z, tilt=T,slant=S or a name), z > 0.
    #[arg(
        long,
        value_name = "L",
        default_value = "0,0,1",
        allow_hyphen_values = true
    )]
    pub light: String,
    /// Time plain Jacobi up to this side (it needs thousands of sweeps: 256² takes seconds,
    /// 1024² would take many minutes).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 256,
        allow_hyphen_values = true
    )]
    pub jacobi_up_to: usize,
    /// Time the integrable methods (integrable, integrable-lm, nested-lm) up to this side
    /// (at 1024² nested-lm takes minutes on two cores, integrable-lm far longer).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 512,
        allow_hyphen_values = true
    )]
    pub integrable_up_to: usize,
    /// The folder of the NumPy reference (`run_reference.py`).
    #[arg(long, value_name = "PATH", default_value = "../shared/reference")]
    pub reference: PathBuf,
    /// Run the NumPy reference (red-black SOR) up to this side (512² takes minutes there).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 256,
        allow_hyphen_values = true
    )]
    pub reference_up_to: usize,
    /// Time multigrid this many times per size and keep the fastest.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 3,
        allow_hyphen_values = true
    )]
    pub repeat: usize,
}

/// Runs `bench`: flags → [`BenchConfig`] → [`bench::run`] → the table on stdout.
pub fn run(args: Args, global: &Global) -> CliResult {
    if args.sizes.is_empty() || args.sizes.iter().any(|&n| n < 8) {
        return Err(CliError::usage(
            "--sizes must list sides of at least 8 pixels",
        ));
    }
    if args.repeat == 0 {
        return Err(CliError::usage("--repeat must be at least 1"));
    }
    let methods = args
        .methods
        .iter()
        .map(|m| m.parse::<Method>().map_err(|e| usage("--methods", e)))
        .collect::<Result<Vec<_>, _>>()?;
    let light: FrontLight = args.light.parse().map_err(|e| usage("--light", e))?;
    if let Some(&n) = args
        .sizes
        .iter()
        .find(|&&n| !matches!(n.checked_mul(n), Some(a) if a <= global.max_pixels))
    {
        return Err(CliError::usage(format!(
            "--sizes {n} exceeds --max-pixels {}",
            global.max_pixels
        )));
    }
    let config = BenchConfig {
        sizes: args.sizes,
        methods,
        lambda: args.lambda,
        integrable_up_to: args.integrable_up_to,
        shape: args.shape,
        light,
        jacobi_up_to: args.jacobi_up_to,
        reference: args.reference,
        reference_up_to: args.reference_up_to,
        repeat: args.repeat,
        max_pixels: global.max_pixels,
    };
    config
        .validate()
        .map_err(|e| CliError::usage(e.to_string()))?;
    let report = bench::run(&config, &Bar::new(global.quiet))?;
    super::output::Output::new(global).results(&report.table(), &report)
}
