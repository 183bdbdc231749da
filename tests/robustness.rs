//! Issue 20, parts 1–2 on the evaluation's own photographs (skipped, saying why, when the
//! shared data is absent): `--albedo estimate` gives the evaluation's errors whatever
//! percentile the user normalised the photograph by.

use shadelab::albedo::brightness_quantile;
use shadelab::evaluation::crop::Crop;
use shadelab::evaluation::datasets::ball;
use shadelab::evaluation::metrics::angular_error;
use shadelab::pipeline::solve::{run_image, LightChoice, SolveConfig};
use shadelab::progress::NoProgress;
use std::path::PathBuf;

/// The shared data: `SHADELAB_EVAL_DATA`, else `../shared/data` beside the repository.
fn data() -> Option<PathBuf> {
    let dir = std::env::var_os("SHADELAB_EVAL_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    if dir.join("diligent_ball/mask.png").is_file() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: the DiLiGenT ball is not under {} (set SHADELAB_EVAL_DATA)",
            dir.display()
        );
        None
    }
}

/// Ball photographs 052 (4°) and 041 (43°), normalised so that their 95th, 99th or 99.9th
/// percentile or their maximum is 1 and clipped to 0..1 as a picture file stores them, solved
/// with the albedo estimate: the same albedo in their units (within 0.1 %) and the normal
/// error of the photograph as the evaluation solves it within 0.5°; normalised by the 90th
/// percentile (10 % of the ball clipped), the same albedo and within 1° (the clipped
/// shading is lost to the solve whatever the albedo).
#[test]
fn the_albedo_estimate_does_not_care_how_a_photograph_was_normalised() {
    let Some(data) = data() else { return };
    let set = ball(&data, &["052".to_string(), "041".to_string()]).unwrap();
    let crop = Crop::around(&set.truth.mask, 2).unwrap();
    let (mask, truth) = (crop.apply(&set.truth.mask), crop.apply(&set.truth.normals));
    for photo in &set.photos {
        let image = crop.apply(&photo.image);
        let solve = |q: f64| {
            let top = brightness_quantile(&image, &mask, q).unwrap();
            let picture = image.map(|v| (v / top).min(1.0));
            let mut config = SolveConfig::new("ball", LightChoice::Given(photo.light));
            config.albedo_estimate = true;
            let run = run_image(&config, picture, Some(mask.clone()), &NoProgress).unwrap();
            let error = angular_error(&run.shape.solution.normals(), &truth, &mask).unwrap();
            let albedo = run.report.parameters.albedo_estimate.unwrap().value * top;
            (error.mean_deg, albedo)
        };
        let (reference, albedo) = solve(1.0);
        for q in [0.9, 0.95, 0.99, 0.999] {
            let (error, a) = solve(q);
            let what = format!(
                "{} at the {q} quantile: {error:.2}° ({reference:.2}°)",
                photo.name
            );
            assert!(
                (a / albedo - 1.0).abs() < 1e-3,
                "{what}: albedo {a} ({albedo})"
            );
            let allowed = if q < 0.95 { 1.0 } else { 0.5 };
            assert!((error - reference).abs() < allowed, "{what}");
            eprintln!("{what}");
        }
    }
}
