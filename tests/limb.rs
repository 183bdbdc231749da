//! The limb boundary ([`Boundary::Limb`]): the occluding condition only where the shading
//! allows a limb. A sphere cut by a plane has an outline that is partly a limb and partly a
//! cut; the cut's rim pixels must be found and held at the slant their brightness gives, the
//! limb's left as the occluding condition has them, and the solve must come out closer to the
//! truth than with the plain occluding condition. On a whole sphere nothing may change.

use crate::cli::{scratch, shadelab};
use nalgebra::Vector3;
use shadelab::angular_error;
use shadelab::{Grid, Light};
use shadelab::{Lambertian, ReflectanceMap};
use shadelab_core::gradient_space::{angle_deg, normal_from_fg};
use shadelab_engine::boundary::{
    boundary_conditions, dark_level, limb_conditions, limb_count, Boundary, Role, BOUNDARY_NAMES,
    LIMB_MAX_NZ,
};
use shadelab_engine::render::{render, RenderOptions};
use shadelab_engine::solver::{SolveOptions, Solver};
use shadelab_engine::surface::{sphere, Surface};
use shadelab_io as io;

/// Side of the test images.
const SIDE: usize = 96;
/// Radius of the sphere.
const RADIUS: f64 = 40.0;
/// Where the plane x = CUT cuts the sphere: everything right of it is gone.
const CUT: f64 = 20.0;

/// A sphere of radius [`RADIUS`] cut by the plane x = [`CUT`]: its outline is the limb on the
/// left and a straight cut on the right, where the surface faces the viewer (n_z up to 0.87).
fn cut_sphere() -> Surface {
    Surface::from_fn(SIDE, SIDE, |x, y| {
        let r2 = x * x + y * y;
        (r2 < RADIUS * RADIUS && x <= CUT).then(|| {
            let z = (RADIUS * RADIUS - r2).sqrt();
            (z, Vector3::new(x, y, z) / RADIUS)
        })
    })
}

fn image_of(surface: &Surface, map: &Lambertian) -> Grid<f64> {
    render(surface, map, &RenderOptions::default()).image
}

/// The mean normal error of a multigrid solve of `surface` under `light` with `boundary`.
fn solve_error(surface: &Surface, light: Light, boundary: &Boundary) -> f64 {
    let map = Lambertian::unit(light);
    let image = image_of(surface, &map);
    let mut solver = Solver::new(SIDE, SIDE).unwrap();
    let solution = solver
        .solve(
            &image,
            &surface.mask,
            boundary,
            &map,
            &SolveOptions::default(),
        )
        .unwrap();
    assert!(solution.converged);
    angular_error(&solution.normals(), &surface.normals, &surface.mask)
        .unwrap()
        .mean_deg
}

#[test]
fn the_cut_is_held_at_its_shading_slant_and_the_limb_is_left_alone() {
    let s = cut_sphere();
    let cut_col = (0..SIDE)
        .filter(|&c| (0..SIDE).any(|r| *s.mask.get(c, r)))
        .max()
        .unwrap();
    let occluding = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    for light in [Light::FRONT, Light::from_tilt_slant(90.0, 30.0).unwrap()] {
        let map = Lambertian::unit(light);
        let image = image_of(&s, &map);
        let limb = limb_conditions(&occluding, &image, &map, None);
        let (mut changed, mut cut_bright, mut limb_kept) = (0, 0, 0);
        for &(index, fg) in occluding.fixed_values() {
            let (col, row) = (index % SIDE, index / SIDE);
            let truth = s.normals.get(col, row);
            // Without clipping no pixel is freed: every one stays fixed.
            assert_eq!(limb.conditions.roles.get(col, row), &Role::Fixed);
            let [f, g] = limb.conditions.fixed_value(col, row).unwrap();
            let (now, pin) = (normal_from_fg(f, g), normal_from_fg(fg[0], fg[1]));
            if now != pin {
                changed += 1;
                // Only on the cut or at its corners.
                assert!(col + 3 >= cut_col, "({col}, {row}) under {light}");
                // The contour's azimuth (the occluding value's) at the slant that gives the
                // pixel's brightness, closer to the truth than the occluding value.
                let azimuth = |n: &shadelab::Normal| n.y.atan2(n.x);
                assert!(
                    (azimuth(&now) - azimuth(&pin)).abs() < 1e-9,
                    "{now:?} {pin:?}"
                );
                assert!((map.radiance(&now) - image.get(col, row)).abs() < 1e-6);
                assert!(angle_deg(&now, truth) < angle_deg(&pin, truth));
            }
            if col == cut_col && truth.z > LIMB_MAX_NZ + 0.1 {
                // Too bright for a limb under either light.
                assert_ne!(now, pin, "({col}, {row}) under {light}");
                cut_bright += 1;
            } else if col + 3 < cut_col {
                // The limb, away from the cut's corners: the occluding value, exactly.
                assert_eq!(now, pin, "({col}, {row}) under {light}");
                limb_kept += 1;
            }
        }
        assert!(
            cut_bright >= 30,
            "{cut_bright} bright cut pixels under {light}"
        );
        assert!(limb_kept > 100, "{limb_kept}");
        assert_eq!(limb.test.not_limb, changed);
        assert_eq!(limb_count(&s.mask, &image, &map, None).unwrap(), changed);
    }
}

/// `image` as a photograph reads it where no light falls: every pixel of `mask` at exactly 0
/// raised by `offset` (a camera's black level) plus a uniform `noise` in [0, noise) from a
/// fixed sequence.
fn dark_offset(image: &Grid<f64>, mask: &shadelab::Mask, offset: f64, noise: f64) -> Grid<f64> {
    let mut dark = image.clone();
    let mut state = 0x5EED_u64;
    for (value, inside) in dark.data_mut().iter_mut().zip(mask.data()) {
        if *inside && *value == 0.0 {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            *value = offset + noise * (state >> 11) as f64 / (1u64 << 53) as f64;
        }
    }
    dark
}

/// A limb in attached shadow reads a photograph's dark level, not 0: the test allows for the
/// image's own (the median reading of the rim where a limb would be dark), so a sphere whose
/// shadow reads 0.01 is still a limb all round, while an exact render's dark level is 0; and a
/// lit cut is still found above that allowance.
#[test]
fn a_shadowed_limb_at_a_photographs_dark_level_is_still_a_limb() {
    let light = Light::from_tilt_slant(90.0, 60.0).unwrap();
    let map = Lambertian::unit(light);
    let ball = sphere(SIDE, SIDE, RADIUS).unwrap();
    let occluding = boundary_conditions(&ball.mask, &Boundary::Occluding).unwrap();
    let render = image_of(&ball, &map);
    let exact = limb_conditions(&occluding, &render, &map, None);
    assert_eq!((exact.test.not_limb, exact.test.dark_level), (0, 0.0));
    // A constant black level: the shadowed limb reads it, and is a limb.
    let photo = dark_offset(&render, &ball.mask, 0.01, 0.0);
    let limb = limb_conditions(&occluding, &photo, &map, None);
    assert_eq!(limb.test.dark_level, 0.01);
    assert_eq!((limb.test.not_limb, &limb.conditions), (0, &occluding));
    // Without the allowance those pixels would be held past the terminator.
    let shadowed = (occluding.fixed_values().iter())
        .filter(|(index, _)| photo.data()[*index] > 0.0 && render.data()[*index] == 0.0)
        .count();
    assert!(shadowed >= 40, "{shadowed} rim pixels in shadow");
    // Noise about the black level: those at or below the level read keep the occluding value.
    let noisy = dark_offset(&render, &ball.mask, 0.01, 0.004);
    let limb = limb_conditions(&occluding, &noisy, &map, None);
    assert!(
        limb.test.dark_level > 0.01 && limb.test.dark_level < 0.014,
        "{}",
        limb.test.dark_level
    );
    for &(index, fg) in occluding.fixed_values() {
        if noisy.data()[index] <= limb.test.dark_level {
            let (col, row) = (index % SIDE, index / SIDE);
            assert_eq!(limb.conditions.fixed_value(col, row), Some(fg));
        }
    }
    assert!(
        limb.test.not_limb <= shadowed / 2 + 1,
        "{} of {shadowed}",
        limb.test.not_limb
    );
    assert_eq!(dark_level(&[0.01; 40]), 0.01);

    // The cut sphere lit from above, its lower limb in shadow at 0.01: the cut's upper half,
    // brighter than a limb facing right could be, is found as in the exact render.
    let light = Light::from_tilt_slant(0.0, 60.0).unwrap();
    let map = Lambertian::unit(light);
    let s = cut_sphere();
    let occluding = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    let render = image_of(&s, &map);
    let exact = limb_conditions(&occluding, &render, &map, None);
    let photo = limb_conditions(
        &occluding,
        &dark_offset(&render, &s.mask, 0.01, 0.0),
        &map,
        None,
    );
    assert_eq!(photo.test.dark_level, 0.01);
    assert!(exact.test.not_limb >= 20, "{}", exact.test.not_limb);
    assert_eq!(photo.test.not_limb, exact.test.not_limb);
}

/// The occluding condition pins the cut's rim edge-on, 30–60° from the truth near the cut's
/// middle; held at its shading slant instead the whole solve comes out about 1° closer (5.66°
/// → 4.79° under the frontal light, 6.79° → 5.80° under the oblique one when written).
#[test]
fn the_limb_condition_solves_a_cut_sphere_better_than_the_occluding_one() {
    let s = cut_sphere();
    for light in [Light::FRONT, Light::from_tilt_slant(90.0, 30.0).unwrap()] {
        let occluding = solve_error(&s, light, &Boundary::Occluding);
        let limb = solve_error(&s, light, &Boundary::Limb);
        assert!(
            limb + 0.7 < occluding,
            "under {light}: limb {limb:.2}° against occluding {occluding:.2}°"
        );
    }
}

#[test]
fn a_whole_sphere_is_a_limb_everywhere_and_nothing_changes() {
    let s = sphere(SIDE, SIDE, RADIUS).unwrap();
    let occluding = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    for (tilt, slant) in [(0.0, 0.0), (30.0, 30.0), (-90.0, 45.0), (135.0, 60.0)] {
        let light = Light::from_tilt_slant(tilt, slant).unwrap();
        let map = Lambertian::unit(light);
        let image = image_of(&s, &map);
        let limb = limb_conditions(&occluding, &image, &map, None);
        assert_eq!(limb.test.not_limb, 0, "under {light}");
        assert_eq!(limb.conditions, occluding, "under {light}");
        let mut solver = Solver::new(SIDE, SIDE).unwrap();
        let options = SolveOptions::default();
        let a = solver
            .solve(&image, &s.mask, &Boundary::Occluding, &map, &options)
            .unwrap();
        let b = solver
            .solve(&image, &s.mask, &Boundary::Limb, &map, &options)
            .unwrap();
        assert_eq!((a.f, a.g), (b.f, b.g), "under {light}");
    }
}

#[test]
fn clipped_rim_pixels_that_rule_out_a_limb_are_left_free() {
    let s = cut_sphere();
    let map = Lambertian::unit(Light::FRONT);
    let image = image_of(&s, &map);
    let occluding = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    let plain = limb_conditions(&occluding, &image, &map, None);
    // Clipped at 0.8: the cut's pixels above it carry no slant and become unknowns.
    let limb = limb_conditions(&occluding, &image, &map, Some(0.8));
    assert_eq!(limb.test.not_limb, plain.test.not_limb);
    let freed: Vec<usize> = (0..SIDE * SIDE)
        .filter(|&i| {
            occluding.roles.data()[i] == Role::Fixed
                && limb.conditions.roles.data()[i] == Role::Unknown
        })
        .collect();
    let clipped: Vec<usize> = occluding
        .fixed_values()
        .iter()
        .map(|&(i, _)| i)
        .filter(|&i| image.data()[i] >= 0.8)
        .collect();
    assert!(!clipped.is_empty());
    assert_eq!(freed, clipped);
    assert_eq!(
        limb.conditions.fixed_count() + freed.len(),
        occluding.fixed_count()
    );
}

#[test]
fn the_limb_boundary_is_named_and_needs_the_image() {
    assert!(BOUNDARY_NAMES.contains(&"limb"));
    let limb = Boundary::named("limb").unwrap();
    assert_eq!((limb.clone(), limb.name()), (Boundary::Limb, "limb"));
    let mask = cut_sphere().mask;
    let message = boundary_conditions(&mask, &Boundary::Limb)
        .unwrap_err()
        .to_string();
    assert!(message.contains("limb_conditions"), "{message}");
    assert!(!message.contains('\n'));
    // The count needs an image the mask's size.
    let map = Lambertian::unit(Light::FRONT);
    let small = Grid::new(SIDE - 1, SIDE, 0.5);
    let message = limb_count(&mask, &small, &map, None)
        .unwrap_err()
        .to_string();
    assert_eq!(
        message,
        "image is 96 px high × 95 px wide but the mask is 96 px high × 96 px wide"
    );
}

/// `shadelab solve image.npy --mask mask.png` in `dir` under `light` with `boundary`, into the
/// folder named after the boundary; its report.json.
fn solve_report(dir: &std::path::Path, light: &str, boundary: &str) -> serde_json::Value {
    let args = [
        "solve",
        "image.npy",
        "--light",
        light,
        "--mask",
        "mask.png",
        "--boundary",
        boundary,
        "--out",
        boundary,
    ];
    let out = shadelab(dir, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join(boundary).join("report.json")).unwrap(),
    )
    .unwrap();
    // The summary on stdout names what the limb test found, and only for the limb boundary.
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().find(|l| l.starts_with("limb test: "));
    match report["boundary"]["not_limb"].as_u64() {
        Some(held) => {
            let line = line.unwrap_or_else(|| panic!("no limb line in {stdout}"));
            let dark = report["boundary"]["dark_level"].as_f64().unwrap();
            assert!(line.contains(&format!("{held} rim pixels")), "{line}");
            assert!(line.ends_with(&format!("dark level {dark:.4}")), "{line}");
        }
        None => assert_eq!(line, None),
    }
    report
}

#[test]
fn solve_reports_the_rim_pixels_that_are_not_a_limb() {
    let d = scratch("solve-limb");
    let s = cut_sphere();
    let map = Lambertian::unit(Light::FRONT);
    let image = image_of(&s, &map);
    io::write_image(&d.join("image.npy"), &image).unwrap();
    io::write_mask(&d.join("mask.png"), &s.mask).unwrap();
    let expected = limb_count(&s.mask, &image, &map, None).unwrap();
    assert!(expected > 0);
    for (boundary, not_limb) in [("limb", Some(expected)), ("occluding", None)] {
        let report = solve_report(&d, "front", boundary);
        assert_eq!(report["boundary"]["kind"], boundary);
        assert_eq!(
            report["boundary"]["not_limb"].as_u64().map(|n| n as usize),
            not_limb
        );
        // An exact render reads 0 where no light falls; no dark level without the limb test.
        let dark_level = not_limb.map(|_| 0.0);
        assert_eq!(report["boundary"]["dark_level"].as_f64(), dark_level);
    }
}

/// A photograph's black: the report gives the dark level the limb test allowed for, the
/// offset added to the render where no light falls, and the count it found with it.
#[test]
fn solve_reports_the_dark_level_of_the_limb_test() {
    let d = scratch("solve-dark-level");
    let light = Light::from_tilt_slant(0.0, 60.0).unwrap();
    let map = Lambertian::unit(light);
    let s = cut_sphere();
    let photo = dark_offset(&image_of(&s, &map), &s.mask, 0.01, 0.0);
    io::write_image(&d.join("image.npy"), &photo).unwrap();
    io::write_mask(&d.join("mask.png"), &s.mask).unwrap();
    // The solve reads the file's 32-bit values.
    let photo = io::read_image(&d.join("image.npy"), 1 << 20).unwrap();
    let occluding = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    let expected = limb_conditions(&occluding, &photo, &map, None);
    assert_eq!(expected.test.dark_level, 0.01_f32 as f64);
    let report = solve_report(&d, "tilt=0,slant=60", "limb");
    assert_eq!(
        report["boundary"]["dark_level"].as_f64(),
        Some(expected.test.dark_level)
    );
    assert_eq!(
        report["boundary"]["not_limb"].as_u64(),
        Some(expected.test.not_limb as u64)
    );
}

/// With the limb condition the light is estimated from the outline as with the occluding one
/// (the limb band fit on a sphere, within a degree), not from the interior statistics alone,
/// and the analyses take it: their domain is the occluding one.
#[test]
fn the_limb_boundary_estimates_the_light_at_the_outline_and_serves_the_analyses() {
    use shadelab::EstimateMethod;
    use shadelab::LightAndAlbedo as Lighting;
    use shadelab_engine::boundary::domain_roles;
    let s = sphere(SIDE, SIDE, RADIUS).unwrap();
    let truth = Light::from_tilt_slant(90.0, 45.0).unwrap();
    let image = image_of(&s, &Lambertian::unit(truth));
    let mut estimates = Vec::new();
    for boundary in [Boundary::Occluding, Boundary::Limb, Boundary::Free] {
        let lighting = Lighting::resolve(None, None, &image, &s.mask, &boundary).unwrap();
        estimates.push(lighting.estimate.unwrap());
    }
    let [occluding, limb, free] = [estimates[0], estimates[1], estimates[2]];
    assert_eq!(limb.method, EstimateMethod::LimbBand);
    assert_eq!(
        (limb.tilt_deg, limb.slant_deg),
        (occluding.tilt_deg, occluding.slant_deg)
    );
    assert!(
        (limb.tilt_deg - 90.0).abs() < 1.0 && (limb.slant_deg - 45.0).abs() < 1.0,
        "{limb:?}"
    );
    assert_eq!(free.method, EstimateMethod::Moments);
    assert_eq!(
        domain_roles(&s.mask, &Boundary::Limb).unwrap(),
        boundary_conditions(&s.mask, &Boundary::Occluding)
            .unwrap()
            .roles
    );

    let d = scratch("prior-sweep-limb");
    let out = shadelab(
        &d,
        &[
            "analyze",
            "prior-sweep",
            "--stimulus",
            "bumps",
            "--boundary",
            "limb",
            "--out",
            "sweep",
            "--quiet",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join("sweep").join("sweep.csv").is_file());
}
