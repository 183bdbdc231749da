//! `shadelab analyze prior-sweep`: the picture interpreted under each assumed light tilt, with
//! each token's convexity, residual and smoothness, and the tilts where it flips (the work is
//! [`shadelab::pipeline::prior_sweep`]).

use super::perception::{true_light_line, PictureArgs};
use super::{CliResult, Global};
use crate::cli::destination;
use crate::cli::flags::{self, usage, OutFolder};
use crate::cli::output::Output;
use crate::cli::progress::Bar;
use shadelab::pipeline::prior_sweep::{self, parse_global_light, Config, DEFAULT_TILTS};
use shadelab::{CommandReport, PriorSweepReport};
use std::time::Instant;

/// Arguments of `analyze prior-sweep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub picture: PictureArgs,
    /// Assumed light tilts, degrees: START:STOP:STEP (STOP excluded) or a list; 0 = from
    /// above, +90 = from the left.
    #[arg(long, value_name = "START:STOP:STEP", default_value = DEFAULT_TILTS, allow_hyphen_values = true)]
    tilts: String,
    /// Also read the tokens under one global light (estimate, or a tilt in degrees) and under
    /// a light estimated from each token alone.
    #[arg(long, value_name = "estimate|TILT", allow_hyphen_values = true)]
    binding: Option<String>,
    #[command(flatten)]
    output: OutFolder,
}

/// Runs `analyze prior-sweep`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let tilts = flags::angles(&args.tilts, "--tilts")?;
    let binding = match &args.binding {
        Some(text) => Some(parse_global_light(text).map_err(|e| usage("--binding", e))?),
        None => None,
    };
    let config = Config {
        tilts,
        binding,
        ..Config::new(args.picture.config(global)?)?
    };
    config.check().map_err(flags::setting)?;
    let dest =
        destination::<PriorSweepReport>(&args.output.out, global, config.picture.source.files())?;
    let report = prior_sweep::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    if report.unconverged_solves > 0 {
        out.warn(format!(
            "{} of {} solves did not converge within --max-iter {}",
            report.unconverged_solves,
            report.tilts_deg.len(),
            report.header.parameters.max_iter
        ));
    }
    out.wrote(&target, started.elapsed().as_secs_f64());
    let mut text = true_light_line(&report.header);
    for t in &report.tokens {
        let flips: Vec<String> = t.flips_deg.iter().map(|f| format!("{f:.1}")).collect();
        text += &format!(
            "{}: convexity changes sign at assumed tilt {}\n",
            t.name,
            if flips.is_empty() {
                "none".into()
            } else {
                flips.join(", ") + "°"
            }
        );
    }
    if let Some(b) = &report.binding {
        let signs = |v: &[f64]| -> String {
            v.iter()
                .map(|&c| match c {
                    c if c > 0.0 => '+',
                    c if c < 0.0 => '-',
                    _ => '0',
                })
                .collect()
        };
        text += &format!(
            "one light (tilt {:.1}°): {}; a light per token: {}\n",
            b.global_light.tilt_deg,
            signs(&b.global),
            signs(&b.per_token)
        );
    }
    out.results(&text, &report)
}
