//! How `solve --albedo estimate` does on the DiLiGenT ball photographs whatever the user
//! normalised them by: each photograph pre-scaled so that its 90th, 95th, 99th or 99.9th
//! percentile, or its maximum, is 1 (clipped at 1 and rounded to 16 bits, as a PNG stores it),
//! solved by the solve pipeline with the estimate, and compared with the truth and with the
//! photograph solved unscaled; each pre-scaled photograph solved twice: with its clipped
//! plateau left out of the data term (the default, `Saturation::Auto`) and with every pixel in
//! it (`Saturation::None`, the solve before issue 20's part 2).
//! `cargo run --release --example albedo_estimate -- ../shared/data` (prints the tables of
//! docs/evaluation.md's "Albedo estimate" section; says why and stops when the data is absent).

use shadelab::angular_error;
use shadelab::pipeline::solve::{run_image, LightChoice, SolveConfig};
use shadelab::{FrontLight, Light, NoProgress};
use shadelab::{Image, Mask};
use shadelab_analysis::evaluation::crop::Crop;
use shadelab_analysis::evaluation::datasets::{ball, BALL_IMAGES};
use shadelab_engine::albedo::{albedo_with_normals, brightness_quantile, Saturation};
use std::path::PathBuf;

/// The pre-scalings: the quantile of the brightness on the mask made 1.
const SCALINGS: [(&str, f64); 5] = [
    ("90th", 0.90),
    ("95th", 0.95),
    ("99th", 0.99),
    ("99.9th", 0.999),
    ("max", 1.0),
];

/// `image` divided by its `q`-quantile on `mask`, clipped at 1 and rounded to 16 bits.
fn prescaled(image: &Image, mask: &Mask, q: f64) -> shadelab::Result<Image> {
    let top = brightness_quantile(image, mask, q)?;
    Ok(image.map(|v| ((v / top).clamp(0.0, 1.0) * 65535.0).round() / 65535.0))
}

/// Mean normal error (degrees) of `image` solved with the albedo estimate and `saturation`,
/// the albedo found, and the pixels left out as clipped.
fn solve(
    image: &Image,
    mask: &Mask,
    light: Light,
    truth: &shadelab::Grid<shadelab::Normal>,
    saturation: Saturation,
) -> shadelab::Result<(f64, f64, usize)> {
    let mut config = SolveConfig::new("ball", LightChoice::Given(FrontLight::new(light)?));
    config.albedo_estimate = true;
    config.saturation = saturation;
    let run = run_image(&config, image.clone(), Some(mask.clone()), &NoProgress)?;
    let error = angular_error(&run.shape.solution.normals(), truth, mask)?;
    let albedo = run
        .report
        .parameters
        .albedo_estimate
        .map_or(f64::NAN, |e| e.value);
    let clipped = run.report.solver.clipped.map_or(0, |c| c.pixels);
    Ok((error.mean_deg, albedo, clipped))
}

fn main() -> shadelab::Result<()> {
    let data = PathBuf::from(std::env::args().nth(1).unwrap_or("../shared/data".into()));
    if !data.join("diligent_ball").is_dir() {
        println!(
            "skipped: no DiLiGenT ball under {} (give the data folder)",
            data.display()
        );
        return Ok(());
    }
    let names: Vec<String> = BALL_IMAGES.iter().map(|s| s.to_string()).collect();
    let set = ball(&data, &names)?;
    let crop = Crop::around(&set.truth.mask, 2)?;
    let mask = crop.apply(&set.truth.mask);
    let truth = crop.apply(&set.truth.normals);
    println!(
        "Each cell: clipped plateau left out (auto) / every pixel in (none), albedo error, \
         pixels left out (of {} in the mask)",
        mask.count()
    );
    print!("| photograph | albedo with true normals | as the eval solves it |");
    for (name, _) in SCALINGS {
        print!(" {name} = 1 |");
    }
    println!(" largest difference |");
    println!("|---|---:|---:|{}---:|", "---:|".repeat(SCALINGS.len()));
    for photo in &set.photos {
        let image = crop.apply(&photo.image);
        let reference =
            albedo_with_normals(&image, &truth, &mask, &photo.light).unwrap_or(f64::NAN);
        // Unscaled, as the evaluation solves it (divided by its maximum to be a picture in
        // 0..1: the rule scales with the image, so this is the evaluation's row).
        let top = brightness_quantile(&image, &mask, 1.0)?;
        let unit = image.map(|v| v / top);
        let (base, albedo, _) = solve(&unit, &mask, photo.light, &truth, Saturation::Auto)?;
        let albedo = albedo * top;
        print!(
            "| {} (slant {:.0}°) | {:.4} | {base:.2}° (albedo {:+.1} %) |",
            photo.name,
            photo.light.slant_deg(),
            reference,
            100.0 * (albedo / reference - 1.0)
        );
        let (mut worst, mut worst_before): (f64, f64) = (0.0, 0.0);
        for (_, q) in SCALINGS {
            let scaled = prescaled(&image, &mask, q)?;
            let top = brightness_quantile(&image, &mask, q)?;
            let (err, albedo, clipped) =
                solve(&scaled, &mask, photo.light, &truth, Saturation::Auto)?;
            let (before, _, _) = solve(&scaled, &mask, photo.light, &truth, Saturation::None)?;
            worst = worst.max((err - base).abs());
            worst_before = worst_before.max((before - base).abs());
            print!(
                " **{err:.2}°** / {before:.2}° ({:+.1} %, {clipped} px clipped) |",
                100.0 * (albedo * top / reference - 1.0)
            );
        }
        println!(" **{worst:.2}°** / {worst_before:.2}° |");
    }
    Ok(())
}
