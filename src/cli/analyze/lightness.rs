//! `shadelab analyze lightness`: a lightness model's output for an image or stimulus, the mean
//! output per target, and for the checker-shadow (targets named A and B) the pixel facts and
//! each model's verdict.

use super::{CliResult, Global, Source};
use crate::cli::destination;
use crate::cli::flags::OutFolder;
use crate::cli::output::Output;
use crate::cli::progress::Bar;
use shadelab::pipeline::lightness::{self, LightnessConfig};
use shadelab::{CommandReport, LightnessReport};

/// Arguments of `analyze lightness`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub source: Source,
    /// The model: odog, lodog, flodog, retinex, highpass, or all (each in turn).
    #[arg(long, value_name = "odog|lodog|flodog|retinex|highpass|all")]
    model: String,
    #[command(flatten)]
    output: OutFolder,
}

/// Runs `analyze lightness`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let models = LightnessConfig::parse_models(&args.model)?;
    args.source.check()?;
    let config = LightnessConfig::new(args.source.to_library(global)?, models)?;
    let dest = destination::<LightnessReport>(&args.output.out, global, config.source.files())?;
    let report = lightness::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.wrote(&target, report.seconds.total);
    let mut text = String::new();
    for t in &report.targets {
        for m in &t.targets {
            text += &format!(
                "{}: {} (label {}): luminance {:.4}, output {:.4}\n",
                t.model, m.name, m.label, m.luminance, m.output
            );
        }
    }
    if let Some(c) = &report.checker_shadow {
        text += &format!(
            "checker-shadow: A and B pixels identical: {}\n",
            c.identical_pixels
        );
    }
    out.results(&text, &report)
}
