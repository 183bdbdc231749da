//! Issue 20, part 2: `--albedo estimate` gives the evaluation's errors whatever percentile the
//! user normalised the photograph by, on the evaluation's own photographs (skipped, saying why,
//! when the shared data is absent) and on a rendered sphere clipped at its 90th percentile,
//! whose clipped plateau the solve leaves out of the data term.

use shadelab::angular_error;
use shadelab::pipeline::solve::{run_image, LightChoice, SolveConfig};
use shadelab::Light;
use shadelab::NoProgress;
use shadelab::{Lambertian, ReflectanceMap};
use shadelab_analysis::evaluation::crop::Crop;
use shadelab_analysis::evaluation::datasets::ball;
use shadelab_engine::albedo::{brightness_quantile, Saturation};
use shadelab_engine::surface::sphere;
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

/// Ball photographs 052 (4°) and 041 (43°), normalised so that their 90th, 95th, 99th or
/// 99.9th percentile or their maximum is 1 and clipped to 0..1 as a picture file stores them,
/// solved with the albedo estimate: the same albedo in their units (within 0.1 %) and the
/// normal error of the photograph as the evaluation solves it within 0.5° (issue 20's goal;
/// measured: within 0.2°). At the 90th percentile 10 % of the ball is one clipped plateau,
/// left out of the data term (the report counts it); with it in (`Saturation::None`) 041 was
/// 0.7° off.
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
            let mut config = SolveConfig::new(
                "ball",
                LightChoice::Given(shadelab::FrontLight::new(photo.light).unwrap()),
            );
            config.albedo_estimate = true;
            config.options = multigrid();
            let run = run_image(&config, picture, Some(mask.clone()), &NoProgress).unwrap();
            let error = angular_error(&run.shape.solution.normals(), &truth, &mask).unwrap();
            let albedo = run.report.parameters.albedo_estimate.unwrap().value * top;
            let clipped = run.report.solver.clipped.map_or(0, |c| c.pixels);
            (error.mean_deg, albedo, clipped)
        };
        let (reference, albedo, _) = solve(1.0);
        for q in [0.9, 0.95, 0.99, 0.999] {
            let (error, a, clipped) = solve(q);
            let what = format!(
                "{} at the {q} quantile: {error:.2}° ({reference:.2}°)",
                photo.name
            );
            assert!(
                (a / albedo - 1.0).abs() < 1e-3,
                "{what}: albedo {a} ({albedo})"
            );
            assert!((error - reference).abs() < 0.5, "{what}");
            if q == 0.9 {
                let share = clipped as f64 / mask.count() as f64;
                assert!(
                    (0.09..0.12).contains(&share),
                    "{what}: {clipped} px clipped"
                );
            }
            eprintln!("{what}, {clipped} px clipped");
        }
    }
}

/// A matte sphere (radius 40 px, albedo 0.7) under a light at tilt 30°, slant 35°, divided by
/// its 90th percentile and clipped at 1 (10 % of the disc one plateau), solved with the albedo
/// estimate: the plateau is found and left out of the data term (the report counts exactly
/// the pixels at 1), the error within 0.5° of the unclipped image's (measured: 0.38°; the
/// plateau's shading is lost, its normals interpolated by smoothness); with every pixel in the
/// data term (`Saturation::None`) the plateau's normals are pulled toward one orientation and
/// the error is larger by more than 0.2° (measured: 0.41°). A level given by the user leaves
/// out the same pixels.
#[test]
fn a_sphere_clipped_at_its_90th_percentile_is_solved_as_the_unclipped_one() {
    let s = sphere(96, 96, 40.0).unwrap();
    let light = Light::from_tilt_slant(30.0, 35.0).unwrap();
    let map = Lambertian {
        light,
        albedo: 0.7,
        ambient: 0.0,
    };
    let image = s.normals.map(|n| map.radiance(n));
    let top = brightness_quantile(&image, &s.mask, 0.9).unwrap();
    let clipped = image.map(|v| (v / top).min(1.0));
    let at_one = clipped
        .data()
        .iter()
        .zip(s.mask.data())
        .filter(|(v, &m)| m && **v == 1.0)
        .count();
    let share = at_one as f64 / s.mask.count() as f64;
    assert!((0.09..0.11).contains(&share), "{share}");
    let solve = |picture: &shadelab::Image, saturation: Saturation| {
        let mut config = SolveConfig::new(
            "sphere",
            LightChoice::Given(shadelab::FrontLight::new(light).unwrap()),
        );
        config.albedo_estimate = true;
        config.options = multigrid();
        config.saturation = saturation;
        let run = run_image(&config, picture.clone(), Some(s.mask.clone()), &NoProgress).unwrap();
        assert!(run.report.solver.converged);
        let error = angular_error(&run.shape.solution.normals(), &s.normals, &s.mask).unwrap();
        (error.mean_deg, run.report.solver.clipped.map(|c| c.pixels))
    };
    let (unclipped, none) = solve(&image, Saturation::Auto);
    assert_eq!(none, None, "no plateau in the unclipped image");
    let (left_out, pixels) = solve(&clipped, Saturation::Auto);
    assert_eq!(pixels, Some(at_one));
    let (kept_in, none) = solve(&clipped, Saturation::None);
    assert_eq!(none, None);
    let (given, pixels) = solve(&clipped, Saturation::Level(1.0));
    assert_eq!(pixels, Some(at_one));
    assert_eq!(given, left_out);
    eprintln!(
        "unclipped {unclipped:.3}°, clipped: plateau left out {left_out:.3}°, kept in {kept_in:.3}°"
    );
    assert!(
        (left_out - unclipped).abs() < 0.5,
        "{left_out} against {unclipped}"
    );
    assert!(kept_in > left_out + 0.2, "{kept_in} against {left_out}");
}

/// The multigrid solve's options: the saturation rule and the albedo estimate were measured
/// with it (the default, nested-lm, loses more on a clipped plateau: the clipped sphere's
/// 4.75° against its unclipped 2.33°; issue 62).
fn multigrid() -> shadelab::ReconstructOptions {
    shadelab::ReconstructOptions::from_solve(
        &shadelab::SolveOptions::for_method(shadelab::Method::Multigrid),
        shadelab::NonConvergence::Report,
    )
}
