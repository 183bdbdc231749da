//! The multigrid-preconditioned solver against the original CG (the reference).

use super::reference::solve_reference;
use super::{differences_rhs, integrate_differences, integrate_gradients, PoissonOptions};
use crate::grid::{Grid, Image, Mask};
use crate::integrate::{gradients_from_normals, DEFAULT_MIN_NZ};
use crate::surface::{sphere, vase, world_xy};

/// The difference fields that `integrate_gradients` builds from slopes.
fn differences(dz_dx: &Image, dz_dy: &Image) -> (Image, Image) {
    let (w, h) = (dz_dx.width(), dz_dx.height());
    let right = Grid::from_fn(w, h, |c, r| {
        if c + 1 < w {
            0.5 * (dz_dx.get(c, r) + dz_dx.get(c + 1, r))
        } else {
            0.0
        }
    });
    let down = Grid::from_fn(w, h, |c, r| {
        if r + 1 < h {
            -0.5 * (dz_dy.get(c, r) + dz_dy.get(c, r + 1))
        } else {
            0.0
        }
    });
    (right, down)
}

/// Largest |new − reference| over the mask relative to the reference's depth range, and the
/// largest absolute difference outside the mask.
fn compare(right: &Image, down: &Image, mask: &Mask) -> (f64, f64, usize, usize) {
    // Both converged far beyond the default tolerance, so that they must agree closely.
    let options = PoissonOptions {
        tol: 1e-10,
        ..PoissonOptions::default()
    };
    let new = integrate_differences(right, down, mask, &options).unwrap();
    let old = solve_reference(mask, &differences_rhs(right, down, mask), &options).unwrap();
    assert!(new.converged && old.converged);
    assert!(new.relative_residual <= options.tol);
    let (lo, hi) = old.depth.min_max().unwrap();
    let mut inside = 0.0f64;
    let mut outside = 0.0f64;
    for ((a, b), &m) in new
        .depth
        .data()
        .iter()
        .zip(old.depth.data())
        .zip(mask.data())
    {
        if m {
            inside = inside.max((a - b).abs());
        } else {
            outside = outside.max(a.abs());
        }
    }
    (inside / (hi - lo), outside, new.iterations, old.iterations)
}

#[test]
fn multigrid_cg_agrees_with_the_reference_on_the_sphere_and_vase() {
    for (name, s) in [
        ("sphere", sphere(128, 128, 57.6).unwrap()),
        ("vase", vase(128, 96).unwrap()),
    ] {
        let (dx, dy) = gradients_from_normals(&s.normals, &s.mask, DEFAULT_MIN_NZ).unwrap();
        let (right, down) = differences(&dx, &dy);
        let (rel, outside, new_it, old_it) = compare(&right, &down, &s.mask);
        assert!(rel < 1e-7, "{name}: relative difference {rel:e}");
        assert_eq!(outside, 0.0, "{name}: nonzero depth outside the mask");
        // The point of the preconditioner: far fewer iterations than the reference.
        assert!(
            new_it * 5 < old_it,
            "{name}: {new_it} vs {old_it} iterations"
        );
        // integrate_gradients (which forms the differences on the fly) gives the same.
        let via = integrate_gradients(&dx, &dy, &s.mask, &PoissonOptions::default()).unwrap();
        let direct =
            integrate_differences(&right, &down, &s.mask, &PoissonOptions::default()).unwrap();
        assert_eq!(via, direct, "{name}");
    }
}

#[test]
fn multigrid_cg_agrees_with_the_reference_on_two_parts_and_a_lone_pixel() {
    // Two discs of different sizes, a lone pixel, and inconsistent (noisy) differences, so the
    // least-squares residual is not zero.
    let (w, h) = (90, 61);
    let mask = Grid::from_fn(w, h, |c, r| {
        let (x, y) = world_xy(c, r, w, h);
        (x + 20.0).hypot(y) < 18.0 || (x - 25.0).hypot(y - 5.0) < 11.0 || (c, r) == (45, 2)
    });
    let wiggle = |c: usize, r: usize, k: f64| ((c as f64 * 0.37 + r as f64 * 0.11) * k).sin();
    let right = Grid::from_fn(w, h, |c, r| 0.3 + 0.2 * wiggle(c, r, 1.3));
    let down = Grid::from_fn(w, h, |c, r| -0.1 + 0.2 * wiggle(c, r, 2.9));
    let (rel, outside, _, _) = compare(&right, &down, &mask);
    assert!(rel < 1e-7, "relative difference {rel:e}");
    assert_eq!(outside, 0.0);
    let out = integrate_differences(&right, &down, &mask, &PoissonOptions::default()).unwrap();
    assert_eq!(*out.depth.get(45, 2), 0.0);
    for left in [true, false] {
        let part = Grid::from_fn(w, h, |c, r| *mask.get(c, r) && (c < 45) == left);
        assert!(out.depth.masked_mean(&part).unwrap().abs() < 1e-12);
    }
}

#[test]
fn multigrid_cg_agrees_with_the_reference_on_thin_and_tiny_domains() {
    for (w, h) in [(1, 37), (37, 1), (3, 3), (2, 1), (5, 130)] {
        let mask = Grid::from_fn(w, h, |c, r| (c + 2 * r) % 11 != 4);
        let right = Grid::from_fn(w, h, |c, r| ((c * 7 + r * 3) % 5) as f64 * 0.1 - 0.2);
        let down = Grid::from_fn(w, h, |c, r| ((c * 2 + r * 5) % 7) as f64 * 0.1 - 0.3);
        let (rel, outside, _, _) = compare(&right, &down, &mask);
        assert!(rel < 1e-7, "{w}x{h}: relative difference {rel:e}");
        assert_eq!(outside, 0.0, "{w}x{h}");
    }
}

#[test]
fn the_default_tolerance_is_far_below_a_depth_maps_precision() {
    // The solver's own normals of a sphere at 256² (slopes capped at the limb, so not exactly
    // integrable): at the default tolerance the depth is within 1e-6 of its range of the
    // depth converged to 1e-12.
    let s = sphere(256, 256, 115.2).unwrap();
    let (dx, dy) = gradients_from_normals(&s.normals, &s.mask, DEFAULT_MIN_NZ).unwrap();
    let default = integrate_gradients(&dx, &dy, &s.mask, &PoissonOptions::default()).unwrap();
    let tight = PoissonOptions {
        tol: 1e-12,
        ..PoissonOptions::default()
    };
    let exact = integrate_gradients(&dx, &dy, &s.mask, &tight).unwrap();
    assert!(default.iterations < exact.iterations);
    let (lo, hi) = exact.depth.min_max().unwrap();
    let worst = default
        .depth
        .data()
        .iter()
        .zip(exact.depth.data())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6 * (hi - lo), "{worst:e} of a range {}", hi - lo);
}

/// The same bytes on one worker thread as on several (the colour sweeps and the sums are
/// split among threads in a fixed way).
#[cfg(feature = "parallel")]
#[test]
fn the_depth_does_not_depend_on_the_thread_count() {
    // Large enough (≥ 2^15 cells) for the parallel loops, with an odd width and height and
    // separate parts.
    let (w, h) = (301, 203);
    let mask = Grid::from_fn(w, h, |c, r| {
        let (x, y) = world_xy(c, r, w, h);
        x.hypot(y) < 95.0 && (x - 30.0).hypot(y) > 12.0 || (x - 130.0).abs() < 15.0
    });
    let wiggle = |c: usize, r: usize, k: f64| ((c as f64 * 0.37 + r as f64 * 0.11) * k).sin();
    let right = Grid::from_fn(w, h, |c, r| 0.3 + 0.2 * wiggle(c, r, 1.3));
    let down = Grid::from_fn(w, h, |c, r| -0.1 + 0.2 * wiggle(c, r, 2.9));
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                integrate_differences(&right, &down, &mask, &PoissonOptions::default()).unwrap()
            })
    };
    let one = on(1);
    assert!(one.converged && one.iterations > 3);
    for threads in [2, 3, 8] {
        let many = on(threads);
        assert_eq!(one, many, "{threads} threads");
    }
}
