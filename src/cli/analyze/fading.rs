//! `shadelab analyze fading`: the fading (Troxler) disk. Border band-pass energy of a blurred
//! and a sharp disk, the perceived-contrast time course of a first-order adaptation model with
//! fixational jitter, and an animation in which the blurred disk fades.

use super::{CliResult, Global, Source};
use crate::cli::destination;
use crate::cli::flags::OutFolder;
use crate::cli::output::Output;
use crate::cli::progress::Bar;
use shadelab::pipeline::fading::{self, FadingConfig};
use shadelab::pipeline::fading::{AdaptationOptions, DogBand};
use shadelab::{CommandReport, FadingReport};

/// Arguments of `analyze fading`.
///
/// The two disks come from a label mask (--mask: label 1 = the blurred disk, 2 = the sharp
/// disk, in one picture), or with --stimulus fading-disk from two renders of it: as given
/// (blurred) and with blur=0 (sharp), each with its own disk target.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub source: Source,
    /// Adaptation time constant τ in seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 2.0,
        allow_hyphen_values = true
    )]
    tau: f64,
    /// Fixation time to simulate, seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 10.0,
        allow_hyphen_values = true
    )]
    duration: f64,
    /// Time step, seconds.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.05,
        allow_hyphen_values = true
    )]
    dt: f64,
    /// RMS fixational jitter per axis in degrees (0 = a perfectly steady eye).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.05,
        allow_hyphen_values = true
    )]
    jitter: f64,
    /// Seed of the jitter.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_hyphen_values = true
    )]
    jitter_seed: u64,
    /// Centre σ of the difference-of-Gaussians band-pass filter, degrees (surround 2σ).
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.05,
        allow_hyphen_values = true
    )]
    dog_sigma: f64,
    /// Half-width of the band around each disk's outline where energy is measured, degrees.
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.5,
        allow_hyphen_values = true
    )]
    border: f64,
    #[command(flatten)]
    output: OutFolder,
}

/// Runs `analyze fading`.
pub fn run(args: Args, global: &Global) -> CliResult {
    args.source.check()?;
    let band = DogBand {
        centre_sigma_deg: args.dog_sigma,
        border_half_width_deg: args.border,
        ..DogBand::default()
    };
    let adaptation = AdaptationOptions {
        tau_s: args.tau,
        duration_s: args.duration,
        dt_s: args.dt,
        jitter_deg: args.jitter,
        seed: args.jitter_seed,
        ..AdaptationOptions::default()
    };
    let config = FadingConfig::new(args.source.to_library(global)?, band, adaptation)?;
    let dest = destination::<FadingReport>(&args.output.out, global, config.source.files())?;
    let report = fading::run(&config, &Bar::new(global.quiet))?;
    let target = report.write(&dest)?;
    let out = Output::new(global);
    out.note(format!("wrote {}", target.display()));
    let (energy, last) = (&report.border_energy, &report.final_contrast);
    let text = format!(
        "border band-pass energy: blurred {:.3e}, sharp {:.3e}, ratio {:.4}\n\
         perceived contrast after {} s: blurred {:.3}, sharp {:.3}\n",
        energy.blurred,
        energy.sharp,
        energy.ratio,
        report.course.times.last().copied().unwrap_or_default(),
        last.blurred,
        last.sharp
    );
    out.results(&text, &report)
}
