//! `shadelab analyze outline`: for each target (a strip cut by an outline), the shape its
//! outline implies, the shading that shape predicts, and the split of the picture into what
//! the shape explains and what is left as paint (the work is [`shadelab::pipeline::outline`]).

use super::{CliResult, Global, RenderSize, Source};
use crate::cli::destination;
use crate::cli::flags::{usage, OutFolder};
use crate::cli::output::Output;
use crate::cli::progress::Bar;
use shadelab::pipeline::outline::{self, OutlineConfig, OutlineReport};
use shadelab::CommandReport;
use std::time::Instant;

/// Arguments of `analyze outline`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub source: Source,
    #[command(flatten)]
    size: RenderSize,
    /// The light: x,y,z or tilt=T,slant=S or a name, with z > 0 (default: fitted per target
    /// in the plane of its outline's profile).
    #[arg(long, value_name = "L", allow_hyphen_values = true)]
    light: Option<String>,
    /// Depth per pixel of outline height: 1 reads the cut's profile at its own scale.
    #[arg(
        long,
        value_name = "X",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    depth_scale: f64,
    /// Weight λ of the brightness term in the reconstructions.
    #[arg(
        long,
        value_name = "X",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    lambda: f64,
    #[command(flatten)]
    output: OutFolder,
}

/// Runs `analyze outline`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let mut config = OutlineConfig::new(args.source.to_library(global)?);
    config.size = args.size.get()?;
    if let Some(text) = &args.light {
        config.light = Some(text.parse().map_err(|e| usage("--light", e))?);
    }
    config.profile.depth_scale = args.depth_scale;
    config.crease.lambda = args.lambda;
    config
        .profile
        .validate()
        .map_err(|e| usage("--depth-scale", e))?;
    config.crease.validate().map_err(|e| usage("--lambda", e))?;
    let dest = destination::<OutlineReport>(&args.output.out, global, config.source.files())?;
    let report = outline::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.wrote(&target, started.elapsed().as_secs_f64());
    let mut text = String::new();
    for t in &report.targets {
        text += &format!(
            "{}: shape explains {:.3} of the shading (light tilt {:.1}° slant {:.1}°), bend concentration {:.2} (Horn's smoothness: {:.2})\n",
            t.name,
            t.shape_explained,
            t.light_tilt_deg,
            t.light_slant_deg,
            t.bend_concentration,
            t.bend_concentration_quadratic
        );
        if !(t.converged && t.converged_quadratic) {
            out.warn(format!("{}: a reconstruction did not converge", t.name));
        }
    }
    out.results(&text, &report)
}
