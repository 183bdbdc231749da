use super::*;
use crate::surface::{sphere, vase, world_xy, Surface};
use realfft::num_complex::Complex;
use std::f64::consts::PI;

/// Frankot–Chellappa by a naive 2-D DFT (O(N²) per coefficient): obviously correct, slow.
/// Same conventions as the fast path: signed frequencies, Nyquist coefficients and the mean
/// set to 0.
fn frankot_chellappa_reference(dz_dx: &Image, dz_dy: &Image) -> Image {
    let (w, h) = (dz_dx.width(), dz_dx.height());
    let dft = |field: &Image, sign: f64| -> Vec<Complex<f64>> {
        let mut out = vec![Complex::new(0.0, 0.0); w * h];
        for kr in 0..h {
            for kc in 0..w {
                let mut acc = Complex::new(0.0, 0.0);
                for r in 0..h {
                    for c in 0..w {
                        let phase =
                            -2.0 * PI * ((kc * c) as f64 / w as f64 + (kr * r) as f64 / h as f64);
                        acc += Complex::from_polar(sign * field.get(c, r), phase);
                    }
                }
                out[kr * w + kc] = acc;
            }
        }
        out
    };
    let a = dft(dz_dx, 1.0);
    let b = dft(dz_dy, -1.0);
    let signed = |k: usize, n: usize| {
        if k <= n / 2 {
            k as f64
        } else {
            k as f64 - n as f64
        }
    };
    let mut z = vec![Complex::new(0.0, 0.0); w * h];
    for kr in 0..h {
        for kc in 0..w {
            let nyquist = (w % 2 == 0 && kc == w / 2) || (h % 2 == 0 && kr == h / 2);
            let (wc, wr) = (
                2.0 * PI * signed(kc, w) / w as f64,
                2.0 * PI * signed(kr, h) / h as f64,
            );
            let d = wc * wc + wr * wr;
            if d > 0.0 && !nyquist {
                let i = kr * w + kc;
                z[i] = (a[i] * wc + b[i] * wr) * Complex::new(0.0, -1.0) / d;
            }
        }
    }
    Grid::from_fn(w, h, |c, r| {
        let mut acc = Complex::new(0.0, 0.0);
        for kr in 0..h {
            for kc in 0..w {
                let phase = 2.0 * PI * ((kc * c) as f64 / w as f64 + (kr * r) as f64 / h as f64);
                acc += z[kr * w + kc] * Complex::from_polar(1.0, phase);
            }
        }
        acc.re / (w * h) as f64
    })
}

/// A deterministic pseudo-random field in −1..1.
fn noise(w: usize, h: usize, seed: u64) -> Image {
    let mut state = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    Grid::from_fn(w, h, |_, _| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    })
}

/// z = cos(2π·2c/W) + 0.5·sin(2π·3r/H) with its exact world-axis slopes.
fn periodic_surface(w: usize, h: usize) -> (Image, Image, Image) {
    let (kx, ky) = (2.0 * PI * 2.0 / w as f64, 2.0 * PI * 3.0 / h as f64);
    let z = Grid::from_fn(w, h, |c, r| {
        (kx * c as f64).cos() + 0.5 * (ky * r as f64).sin()
    });
    let dz_dx = Grid::from_fn(w, h, |c, _| -kx * (kx * c as f64).sin());
    // ∂z/∂y = −∂z/∂row.
    let dz_dy = Grid::from_fn(w, h, |_, r| -0.5 * ky * (ky * r as f64).cos());
    (z, dz_dx, dz_dy)
}

#[test]
fn the_reference_recovers_a_periodic_surface() {
    let (z, dx, dy) = periodic_surface(12, 10);
    let got = frankot_chellappa_reference(&dx, &dy);
    let mean = z.data().iter().sum::<f64>() / z.len() as f64;
    for (a, b) in got.data().iter().zip(z.data()) {
        assert!((a - (b - mean)).abs() < 1e-12, "{a} vs {}", b - mean);
    }
}

#[test]
fn the_fft_path_agrees_with_the_naive_dft() {
    for (w, h, seed) in [
        (12, 10, 1),
        (9, 7, 2),
        (16, 16, 3),
        (1, 8, 4),
        (5, 1, 5),
        (8, 6, 6),
    ] {
        let (dx, dy) = (noise(w, h, seed), noise(w, h, seed + 100));
        let want = frankot_chellappa_reference(&dx, &dy);
        let mut fc = FrankotChellappa::new(w, h).unwrap();
        // Twice, to check that reused buffers carry nothing over.
        for _ in 0..2 {
            let got = fc.integrate(&dx, &dy).unwrap();
            for (a, b) in got.data().iter().zip(want.data()) {
                assert!((a - b).abs() < 1e-10, "{w}x{h}: {a} vs {b}");
            }
        }
    }
    let (z, dx, dy) = periodic_surface(64, 48);
    let got = FrankotChellappa::new(64, 48)
        .unwrap()
        .integrate(&dx, &dy)
        .unwrap();
    for (a, b) in got.data().iter().zip(z.data()) {
        assert!((a - b).abs() < 1e-9);
    }
}

#[test]
fn frankot_chellappa_rejects_bad_fields() {
    let mut fc = FrankotChellappa::new(8, 8).unwrap();
    let ok = Grid::new(8, 8, 0.0);
    assert!(fc
        .integrate(&Grid::new(8, 7, 0.0), &Grid::new(8, 7, 0.0))
        .is_err());
    assert!(fc.integrate(&ok, &Grid::new(7, 8, 0.0)).is_err());
    let mut nan = ok.clone();
    *nan.get_mut(3, 4) = f64::NAN;
    let e = fc.integrate(&ok, &nan).unwrap_err().to_string();
    assert!(e.contains("column 3, row 4"), "{e}");
}

/// Depth RMSE after a scale and offset fit, from the exact normals of `s`.
fn rmse_from_exact_normals(s: &Surface) -> f64 {
    let (dx, dy) = gradients_from_normals(&s.normals, &s.mask, DEFAULT_MIN_NZ).unwrap();
    let out = integrate_gradients(&dx, &dy, &s.mask, &PoissonOptions::default()).unwrap();
    assert!(out.converged, "CG stopped at {}", out.relative_residual);
    let fit = fit_scale_offset(&out.depth, &s.depth, &s.mask).unwrap();
    assert!((fit.scale - 1.0).abs() < 0.05, "scale {}", fit.scale);
    fit.rmse
}

#[test]
fn poisson_integration_of_the_sphere_and_vase_is_within_half_a_pixel() {
    let sphere_rmse = rmse_from_exact_normals(&sphere(128, 128, 57.6).unwrap());
    assert!(sphere_rmse <= 0.5, "sphere depth RMSE {sphere_rmse} px");
    let vase_rmse = rmse_from_exact_normals(&vase(128, 128).unwrap());
    assert!(vase_rmse <= 0.5, "vase depth RMSE {vase_rmse} px");
}

#[test]
fn slopes_from_fg_in_place_equal_slopes_from_normals_and_integrate_bit_for_bit() {
    // The vase's (f, g).
    let s = vase(96, 96).unwrap();
    let fg = s.normals.map(crate::gradient_space::fg_from_normal);
    let f = fg.map(|v| v.0);
    let g = fg.map(|v| v.1);
    let normals = Grid::from_fn(96, 96, |c, r| {
        if *s.mask.get(c, r) {
            normal_from_fg(*f.get(c, r), *g.get(c, r))
        } else {
            Normal::z()
        }
    });
    let (dx, dy) = gradients_from_normals(&normals, &s.mask, DEFAULT_MIN_NZ).unwrap();
    let (ix, iy) = gradients_from_fg(f, g, &s.mask, DEFAULT_MIN_NZ).unwrap();
    assert_eq!(dx, ix);
    assert_eq!(dy, iy);
    let options = PoissonOptions::default();
    let borrowed = integrate_gradients(&dx, &dy, &s.mask, &options).unwrap();
    let owned = integrate_owned_gradients(ix, iy, &s.mask, &options).unwrap();
    assert_eq!(borrowed.depth, owned.depth);
    assert_eq!(borrowed.iterations, owned.iterations);
    let wrong = Grid::new(5, 5, 0.0);
    let e = gradients_from_fg(wrong.clone(), wrong, &s.mask, DEFAULT_MIN_NZ).unwrap_err();
    assert!(e.to_string().contains("one size"), "{e}");
}

#[test]
fn rest_on_zero_lifts_the_masked_minimum_to_zero_and_clears_the_outside() {
    let mut depth = Grid::from_vec(3, 2, vec![5.0, -2.0, 7.0, 9.0, 1.0, -8.0]).unwrap();
    let mask = Grid::from_vec(3, 2, vec![true, true, false, false, true, false]).unwrap();
    let highest = rest_on_zero(&mut depth, &mask).unwrap();
    assert_eq!(depth.data(), &[7.0, 0.0, 0.0, 0.0, 3.0, 0.0]);
    assert_eq!(highest, 7.0);
    let mut flat = Grid::new(2, 2, 4.0);
    assert_eq!(
        rest_on_zero(&mut flat, &Grid::new(2, 2, false)).unwrap(),
        0.0
    );
    assert_eq!(flat.data(), &[0.0; 4]);
    let e = rest_on_zero(&mut flat, &Grid::new(3, 2, true)).unwrap_err();
    assert!(
        e.to_string().contains("depth is 2 px high × 2 px wide"),
        "{e}"
    );
}

#[test]
fn consistent_differences_are_integrated_exactly_on_any_mask() {
    // A quadratic on an annulus with a hole and a notch: exact differences give it back.
    let (w, h) = (40, 30);
    let truth = |c: usize, r: usize| {
        let (x, y) = world_xy(c, r, w, h);
        0.3 * x - 0.2 * y + 0.01 * x * y
    };
    let mask = Grid::from_fn(w, h, |c, r| {
        let (x, y) = world_xy(c, r, w, h);
        let d = x.hypot(y);
        (5.0..14.0).contains(&d) && !(x > 0.0 && y.abs() < 1.0)
    });
    let right = Grid::from_fn(w, h, |c, r| {
        if c + 1 < w {
            truth(c + 1, r) - truth(c, r)
        } else {
            0.0
        }
    });
    let down = Grid::from_fn(w, h, |c, r| {
        if r + 1 < h {
            truth(c, r + 1) - truth(c, r)
        } else {
            0.0
        }
    });
    // Converged far beyond the default tolerance, so that the answer must be exact.
    let tight = PoissonOptions {
        tol: 1e-12,
        ..PoissonOptions::default()
    };
    let out = integrate_differences(&right, &down, &mask, &tight).unwrap();
    let z = Grid::from_fn(w, h, |c, r| if *mask.get(c, r) { truth(c, r) } else { 0.0 });
    let fit = fit_scale_offset(&out.depth, &z, &mask).unwrap();
    assert!(fit.rmse < 1e-7 && (fit.scale - 1.0).abs() < 1e-9, "{fit:?}");
    let mean = out.depth.masked_mean(&mask).unwrap();
    assert!(mean.abs() < 1e-9);
    for (d, m) in out.depth.data().iter().zip(mask.data()) {
        if !m {
            assert_eq!(*d, 0.0);
        }
    }
}

#[test]
fn separate_parts_each_have_zero_mean() {
    // Two blocks and a lone pixel, with a constant slope along x.
    let mask = Grid::from_fn(20, 6, |c, r| {
        (1..6).contains(&c) || (10..18).contains(&c) && r > 1 || (c, r) == (8, 0)
    });
    let right = Grid::new(20, 6, 1.0);
    let down = Grid::new(20, 6, 0.0);
    let tight = PoissonOptions {
        tol: 1e-12,
        ..PoissonOptions::default()
    };
    let out = integrate_differences(&right, &down, &mask, &tight).unwrap();
    for cols in [1..6, 10..18] {
        let part = Grid::from_fn(20, 6, |c, r| *mask.get(c, r) && cols.contains(&c));
        assert!(out.depth.masked_mean(&part).unwrap().abs() < 1e-9);
        // The slope along x is exact within each part.
        let row = 3;
        let first = cols.start;
        assert!((out.depth.get(first + 1, row) - out.depth.get(first, row) - 1.0).abs() < 1e-8);
    }
    assert_eq!(*out.depth.get(8, 0), 0.0);
}

#[test]
fn integration_rejects_bad_input() {
    let mask = Grid::new(6, 5, true);
    let z = Grid::new(6, 5, 0.0);
    let o = PoissonOptions::default();
    assert!(integrate_gradients(&z, &z, &Grid::new(5, 5, true), &o).is_err());
    assert!(integrate_gradients(&z, &z, &Grid::new(6, 5, false), &o).is_err());
    let mut inf = z.clone();
    *inf.get_mut(0, 0) = f64::INFINITY;
    assert!(integrate_differences(&inf, &z, &mask, &o).is_err());
    let bad = PoissonOptions { tol: 0.0, ..o };
    assert!(integrate_gradients(&z, &z, &mask, &bad).is_err());
}

#[test]
fn slopes_from_normals_follow_the_conventions_and_are_capped() {
    // A plane z = 0.5x − 0.25y has p = −0.5, q = 0.25, n ∝ (p, q, 1).
    let n = crate::gradient_space::normal_from_pq(-0.5, 0.25);
    let mut normals = Grid::new(3, 2, n);
    *normals.get_mut(2, 1) = nalgebra::Vector3::new(1.0, 0.0, 0.0);
    let mut mask = Grid::new(3, 2, true);
    *mask.get_mut(0, 1) = false;
    let (dx, dy) = gradients_from_normals(&normals, &mask, DEFAULT_MIN_NZ).unwrap();
    assert!((dx.get(0, 0) - 0.5).abs() < 1e-12 && (dy.get(0, 0) + 0.25).abs() < 1e-12);
    assert_eq!((*dx.get(0, 1), *dy.get(0, 1)), (0.0, 0.0));
    assert!(
        (dx.get(2, 1) + 20.0).abs() < 1e-9,
        "limb slope capped at 1/0.05"
    );
    assert!(gradients_from_normals(&normals, &mask, 0.0).is_err());
}

#[test]
fn scale_offset_fit_finds_an_affine_map() {
    let est = Grid::from_fn(5, 4, |c, r| (c * 3 + r) as f64);
    let truth = est.map(|v| 2.5 * v - 1.0);
    let fit = fit_scale_offset(&est, &truth, &Grid::new(5, 4, true)).unwrap();
    assert!((fit.scale - 2.5).abs() < 1e-12 && (fit.offset + 1.0).abs() < 1e-12);
    assert!(fit.rmse < 1e-12);
}
