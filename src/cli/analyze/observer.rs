//! `shadelab analyze observer`: a Bayesian observer's P(convex) for each token against the
//! picture's rotation, from one fine sweep of the upright picture (the work is
//! [`shadelab::pipeline::observer`]).

use super::perception::{true_light_line, PictureArgs};
use super::{CliResult, Global};
use crate::cli::destination;
use crate::cli::flags::{self, usage, OutFolder};
use crate::cli::output::Output;
use crate::cli::progress::Bar;
use shadelab::pipeline::observer::{self, Config, DEFAULT_ROTATIONS, DEFAULT_TILTS};
use shadelab::pipeline::observer::{
    parse_kappas, LightPrior, DEFAULT_NOISE, DEFAULT_PRIOR_KAPPA, DEFAULT_PRIOR_TILT_DEG,
};
use shadelab::{CommandReport, ObserverReport};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `analyze observer`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub picture: PictureArgs,
    /// Mean of the von Mises prior over light tilt, degrees (+26 = 26° left of vertical).
    #[arg(long, value_name = "DEG", default_value_t = DEFAULT_PRIOR_TILT_DEG, allow_hyphen_values = true)]
    prior_tilt: f64,
    /// Concentration κ of the tilt prior (0 = no preference; larger = firmer); a
    /// comma-separated list draws one curve per value.
    #[arg(long, value_name = "K[,K...]", default_value_t = DEFAULT_PRIOR_KAPPA.to_string(), allow_hyphen_values = true)]
    prior_kappa: String,
    /// Log prior odds of convex over concave for each token (0 = none).
    #[arg(long, value_name = "B", default_value_t = LightPrior::default().convexity_bias, allow_hyphen_values = true)]
    convexity_bias: f64,
    /// Image noise σ of the likelihood, luminance units.
    #[arg(long, value_name = "SIGMA", default_value_t = DEFAULT_NOISE, allow_hyphen_values = true)]
    noise: f64,
    /// Lapse rate λ: how often the observer answers at random (0..1).
    #[arg(
        long,
        value_name = "L",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    lapse: f64,
    /// Take the prior tilt, kappa, convexity prior (as its log odds) and lapse from a
    /// fit.json written by `shadelab fit observer`.
    #[arg(long, value_name = "FIT_JSON",
        conflicts_with_all = ["prior_tilt", "prior_kappa", "convexity_bias", "lapse"]
    )]
    prior: Option<PathBuf>,
    /// Rotations of the picture to judge, degrees counter-clockwise: START:STOP:STEP or a list.
    #[arg(long, value_name = "START:STOP:STEP", default_value = DEFAULT_ROTATIONS,
        allow_hyphen_values = true
    )]
    rotations: String,
    /// Assumed light tilts of the sweep behind the observer; they must cover the circle in
    /// equal steps.
    #[arg(long, value_name = "START:STOP:STEP", default_value = DEFAULT_TILTS,
        allow_hyphen_values = true
    )]
    tilts: String,
    #[command(flatten)]
    output: OutFolder,
}

/// Runs `analyze observer`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let mut config = Config {
        tilts: flags::angles(&args.tilts, "--tilts")?,
        rotations: flags::angles(&args.rotations, "--rotations")?,
        kappas: parse_kappas(&args.prior_kappa).map_err(|e| usage("--prior-kappa", e))?,
        prior_tilt_deg: args.prior_tilt,
        convexity_bias: args.convexity_bias,
        noise: args.noise,
        lapse: args.lapse,
        ..Config::new(args.picture.config(global)?)?
    };
    if let Some(path) = &args.prior {
        config.use_fit(path).map_err(|e| usage("--prior", e))?;
    }
    config.check().map_err(flags::setting)?;
    let mut inputs = config.picture.source.files();
    inputs.extend(args.prior.clone());
    let dest = destination::<ObserverReport>(&args.output.out, global, inputs)?;
    let report = observer::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.wrote(&target, started.elapsed().as_secs_f64());
    let mut text = true_light_line(&report.header);
    for curve in &report.percepts {
        for (k, (_, name)) in report.sweep.tokens.iter().enumerate() {
            let best = curve.percepts.iter().fold(&curve.percepts[0], |b, p| {
                if p.p_convex[k] > b.p_convex[k] {
                    p
                } else {
                    b
                }
            });
            text += &format!(
                "{name} (kappa {}): P(convex) is highest, {:.3}, at rotation {}°\n",
                curve.options.prior.kappa, best.p_convex[k], best.rotation_deg
            );
        }
    }
    out.results(&text, &report)
}
