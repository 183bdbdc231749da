//! `shadelab analyze fading`: the fading (Troxler) disk. Border band-pass energy of a blurred
//! and a sharp disk, the perceived-contrast time course of a first-order adaptation model with
//! fixational jitter, and an animation in which the blurred disk fades.

use super::{CliError, CliResult, Global, Input, Source};
use serde_json::{json, Map, Value};
use shadelab::grid::{Image, Mask, RgbImage};
use shadelab::io::{self, AtomicDir};
use shadelab::lightness::fading::{
    adaptation_time_course, border_energy, perceived_frames, shrink, side_by_side, write_gif,
    AdaptationOptions, Disk, DogBand,
};
use shadelab::stimulus::Pixels;
use std::time::Instant;

/// The file that marks an output folder as written by `analyze fading`.
const REPORT: &str = "fading.json";
/// The animation's frame rate and largest side in pixels.
const FPS: f64 = 10.0;
const GIF_SIDE: usize = 480;

/// Arguments of `analyze fading`.
///
/// The two disks come from a label mask (--mask: label 1 = the blurred disk, 2 = the sharp
/// disk, in one picture), or with --stimulus fading-disk from two renders of it: as given
/// (blurred) and with blur=0 (sharp), each with its own disk target.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    source: Source,
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
    /// Output folder (written whole or not at all).
    #[arg(long, value_name = "DIR")]
    out: std::path::PathBuf,
}

/// One disk: its picture (RGB for the animation, channels for the analysis) and mask.
struct Scene {
    picture: RgbImage,
    channels: Vec<Image>,
    mask: Mask,
}

/// Runs `analyze fading`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let band = DogBand {
        centre_sigma_deg: args.dog_sigma,
        surround_ratio: 2.0,
        border_half_width_deg: args.border,
    };
    let options = AdaptationOptions {
        tau_s: args.tau,
        duration_s: args.duration,
        dt_s: args.dt,
        jitter_deg: args.jitter,
        jitter_tau_s: AdaptationOptions::default().jitter_tau_s,
        seed: args.jitter_seed,
    };
    args.source.check()?;
    if args.source.image.is_some() {
        if args.source.ppd.is_none() {
            return Err(CliError::usage(
                "the fading analysis works in degrees of visual angle: give the image's \
                 resolution with --ppd N (pixels per degree)",
            ));
        }
        if args.source.mask.is_none() {
            return Err(CliError::usage(
                "an image needs --mask LABELS.png with label 1 = the blurred disk and 2 = the \
                 sharp disk",
            ));
        }
    }
    let (blurred, sharp, ppd, origin) = scenes(&args.source, global)?;
    let (b, s) = (
        Disk {
            channels: &blurred.channels,
            mask: &blurred.mask,
        },
        Disk {
            channels: &sharp.channels,
            mask: &sharp.mask,
        },
    );
    let energy = border_energy(b, s, ppd, &band)?;
    let course = adaptation_time_course(b, s, ppd, &band, &options)?;

    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;
    let dir = folder.path().to_path_buf();
    let mut csv = String::from("time_s,blurred,sharp,eye_x_deg,eye_y_deg\n");
    for i in 0..course.times.len() {
        csv.push_str(&format!(
            "{},{},{},{},{}\n",
            course.times[i], course.blurred[i], course.sharp[i], course.eye[i].0, course.eye[i].1
        ));
    }
    let csv_path = dir.join("time_course.csv");
    io::write_text(&csv_path, &csv)?;

    let every = ((1.0 / FPS) / options.dt_s).round().max(1.0) as usize;
    let same_picture = blurred.picture == sharp.picture;
    let frames = if same_picture {
        let regions: [(&Mask, &[f64]); 2] = [
            (&blurred.mask, &course.blurred),
            (&sharp.mask, &course.sharp),
        ];
        perceived_frames(&blurred.picture, &regions, ppd, &band, every)?
    } else {
        let left = perceived_frames(
            &blurred.picture,
            &[(&blurred.mask, &course.blurred)],
            ppd,
            &band,
            every,
        )?;
        let right = perceived_frames(
            &sharp.picture,
            &[(&sharp.mask, &course.sharp)],
            ppd,
            &band,
            every,
        )?;
        left.iter()
            .zip(&right)
            .map(|(l, r)| side_by_side(l, r, (0.25 * ppd).ceil() as usize, [0.0; 3]))
            .collect()
    };
    let side = frames
        .first()
        .map(|f| f.width().max(f.height()))
        .unwrap_or(1);
    let factor = side.div_ceil(GIF_SIDE);
    let frames: Vec<RgbImage> = frames.iter().map(|f| shrink(f, factor)).collect();
    let delay_ms = (every as f64 * options.dt_s * 1000.0).round() as u32;
    write_gif(&dir.join("fading.gif"), &frames, delay_ms)?;

    let last = course.times.len() - 1;
    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "command": "analyze fading",
        "input": origin,
        "ppd": ppd,
        "band_pass": band,
        "border_energy": energy,
        "adaptation": options,
        "final_contrast": { "blurred": course.blurred[last], "sharp": course.sharp[last] },
        "time_course": "time_course.csv: relative perceived contrast (RMS adapted band-pass response in the border band over its value at onset) and eye position",
        "animation": {
            "file": "fading.gif",
            "frames": frames.len(),
            "delay_ms": delay_ms,
            "reduced_by": factor,
            "rule": "inside each disk's region the picture is its surround colour plus the disk's relative contrast times the difference; values written as 8-bit codes without gamma",
            "layout": if same_picture { "one picture" } else { "blurred disk left, sharp disk right" },
        },
        "seconds": started.elapsed().as_secs_f64(),
    });
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if !global.quiet {
        eprintln!(
            "border band-pass energy: blurred {:.3e}, sharp {:.3e}, ratio {:.4}",
            energy.blurred, energy.sharp, energy.ratio
        );
        eprintln!(
            "perceived contrast after {} s: blurred {:.3}, sharp {:.3}",
            course.times[last], course.blurred[last], course.sharp[last]
        );
        eprintln!("wrote {}", target.display());
    }
    Ok(())
}

/// The blurred and the sharp disk, the resolution, and where they came from.
fn scenes(source: &Source, global: &Global) -> Result<(Scene, Scene, f64, Value), CliError> {
    if source.image.is_some() {
        let input = source.load(true, global)?;
        let ppd = input.ppd.unwrap_or_default();
        let (labels, _) = input
            .labels
            .as_ref()
            .ok_or_else(|| CliError::usage("--mask is needed with an image"))?;
        let mask = |l: u16, what: &str| -> Result<Mask, CliError> {
            let m = labels.map(|&v| v == l);
            if m.count() == 0 {
                return Err(CliError::usage(format!(
                    "the mask has no pixel labelled {l} (the {what} disk)"
                )));
            }
            Ok(m)
        };
        let (mb, ms) = (mask(1, "blurred")?, mask(2, "sharp")?);
        let picture = rgb(&input);
        let channels = channels(&input.pixels);
        let blurred = Scene {
            picture: picture.clone(),
            channels: channels.clone(),
            mask: mb,
        };
        let sharp = Scene {
            picture,
            channels,
            mask: ms,
        };
        return Ok((blurred, sharp, ppd, input.origin));
    }
    // A stimulus: as given for the blurred disk, with blur = 0 for the sharp one.
    let blurred_input = source.load(true, global)?;
    let mut sharp_source = Source {
        image: None,
        stimulus: source.stimulus.clone(),
        set: source.set.clone(),
        seed: source.seed,
        ppd: source.ppd,
        mask: source.mask.clone(),
    };
    sharp_source.set.push("blur=0".into());
    let sharp_input = sharp_source.load(true, global)?;
    let ppd = blurred_input.ppd.unwrap_or_default();
    let disk = |input: &Input, what: &str| -> Result<Scene, CliError> {
        let (labels, names) = input.labels.as_ref().ok_or_else(|| {
            CliError::usage(format!(
                "the stimulus has no target mask to find the {what} disk in; give --mask"
            ))
        })?;
        let label = names
            .iter()
            .position(|n| n == "disk")
            .map(|i| i as u16 + 1)
            .unwrap_or(1);
        let mask = labels.map(|&v| v == label);
        if mask.count() == 0 {
            return Err(CliError::usage(format!(
                "the {what} render has no disk target (label {label})"
            )));
        }
        Ok(Scene {
            picture: rgb(input),
            channels: channels(&input.pixels),
            mask,
        })
    };
    let blurred = disk(&blurred_input, "blurred")?;
    let sharp = disk(&sharp_input, "sharp")?;
    let mut origin = Map::new();
    origin.insert("blurred".into(), blurred_input.origin);
    origin.insert("sharp".into(), sharp_input.origin);
    Ok((blurred, sharp, ppd, Value::Object(origin)))
}

fn rgb(input: &Input) -> RgbImage {
    match &input.pixels {
        Pixels::Rgb(i) => i.clone(),
        Pixels::Gray(i) => i.map(|&v| [v, v, v]),
    }
}

fn channels(pixels: &Pixels) -> Vec<Image> {
    match pixels {
        Pixels::Gray(i) => vec![i.clone()],
        Pixels::Rgb(i) => (0..3).map(|k| i.map(|p| p[k])).collect(),
    }
}
