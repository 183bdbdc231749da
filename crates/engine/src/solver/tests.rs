use super::*;
use crate::gradient_space::angle_deg;
use crate::integrate::{gradients_from_normals, integrate_gradients, PoissonOptions};
use crate::light::Light;
use crate::reflectance::Lambertian;
use crate::render::{render, RenderOptions};
use crate::surface::{gaussian, sphere, vase, Mesh, Surface};

/// The image of `surface` under a Lambertian surface of albedo 1 lit from `light`.
pub(super) fn picture(surface: &Surface, light: Light) -> (Image, Lambertian) {
    let map = Lambertian::unit(light);
    let image = render(surface, &map, &RenderOptions::default()).image;
    (image, map)
}

/// Eight iterations (finest steps, cycles) of `method` on a 200² picture of `b`, on one thread
/// and on three, give the same solution, which the parallel loops handle (returned for the
/// caller's own checks).
#[cfg(feature = "parallel")]
pub(super) fn same_for_any_thread_count(
    b: &Surface,
    image: &Image,
    map: &Lambertian,
    method: Method,
) -> Solution {
    let options = SolveOptions {
        max_iter: 8,
        ..SolveOptions::for_method(method)
    };
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let mut solver = Solver::new(200, 200).unwrap();
                solver
                    .solve(image, &b.mask, &Boundary::Flat, map, &options)
                    .unwrap()
            })
    };
    let one = run(1);
    assert!(one.unknowns >= PARALLEL_MIN, "{method}");
    assert_eq!(one, run(3), "{method}");
    one
}

/// The built-in Stanford bunny (`bun_zipper_res3`) rasterised into a `size`² frame.
pub(super) fn bunny(size: usize) -> Surface {
    let ply = include_bytes!("../../../../tests/data/bun_zipper_res3.ply");
    let mesh = Mesh::from_ply(ply, std::path::Path::new("bun_zipper_res3.ply")).unwrap();
    mesh.rasterize(size, size, &nalgebra::Rotation3::identity(), 0.85)
        .unwrap()
}

/// Mean angle (degrees) between the solution's normals and the truth over the unknowns.
fn mean_error(solution: &Solution, truth: &Surface, boundary: &Boundary) -> f64 {
    let bc = boundary_conditions(&truth.mask, boundary).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for (i, role) in bc.roles.data().iter().enumerate() {
        if *role == Role::Unknown {
            sum += angle_deg(&solution.normals().data()[i], &truth.normals.data()[i]);
            n += 1;
        }
    }
    assert_eq!(n, solution.unknowns);
    sum / n as f64
}

/// Solves the image of `surface` under `light`, assuming `assumed` (λ = 1 and the defaults).
fn solve(surface: &Surface, light: Light, assumed: Light, boundary: &Boundary) -> Solution {
    let (image, _) = picture(surface, light);
    let (_, map) = picture(surface, assumed);
    let mut solver = Solver::new(surface.width(), surface.height()).unwrap();
    solver
        .solve(
            &image,
            &surface.mask,
            boundary,
            &map,
            &SolveOptions::default(),
        )
        .unwrap()
}

/// Depth from the solution's normals by least squares on the mask.
fn depth(solution: &Solution, mask: &Mask) -> Image {
    let (dx, dy) = gradients_from_normals(&solution.normals(), mask, 0.05).unwrap();
    integrate_gradients(&dx, &dy, mask, &PoissonOptions::default())
        .unwrap()
        .depth
}

fn bump() -> Surface {
    gaussian(128, 128, 0.12 * 128.0, 0.12 * 128.0, 0.0, 0.0).unwrap()
}

#[test]
fn sphere_with_frontal_light_is_within_a_quarter_degree() {
    let s = sphere(128, 128, 57.6).unwrap();
    let sol = solve(&s, Light::FRONT, Light::FRONT, &Boundary::Occluding);
    assert!(sol.converged && !sol.diverged && sol.last_update < 1e-6);
    let err = mean_error(&sol, &s, &Boundary::Occluding);
    assert!(
        err <= 0.25,
        "mean normal error {err}° after {} sweeps",
        sol.iterations
    );
    // Normals are unit, and face the viewer outside the mask.
    for (n, m) in sol.normals().data().iter().zip(s.mask.data()) {
        assert!((n.norm() - 1.0).abs() < 1e-12);
        if !m {
            assert_eq!(*n, nalgebra::Vector3::z());
        }
    }
}

#[test]
fn vase_with_frontal_light_is_within_three_and_a_half_degrees() {
    let v = vase(128, 128).unwrap();
    let sol = solve(&v, Light::FRONT, Light::FRONT, &Boundary::Occluding);
    assert!(sol.converged);
    let err = mean_error(&sol, &v, &Boundary::Occluding);
    assert!(
        err <= 3.5,
        "mean normal error {err}° after {} sweeps",
        sol.iterations
    );
}

#[test]
fn sphere_with_oblique_light_is_within_eleven_degrees() {
    let s = sphere(128, 128, 57.6).unwrap();
    let light = Light::from_vector(1.0, 0.0, 1.0).unwrap();
    let sol = solve(&s, light, light, &Boundary::Occluding);
    assert!(sol.converged);
    let err = mean_error(&sol, &s, &Boundary::Occluding);
    assert!(
        err <= 11.0,
        "mean normal error {err}° after {} sweeps",
        sol.iterations
    );
}

#[test]
fn bump_on_a_plane_is_recovered_and_flips_with_the_light() {
    let b = bump();
    let light = Light::from_tilt_slant(0.0, 45.0).unwrap();
    let sol = solve(&b, light, light, &Boundary::Flat);
    assert!(sol.converged);
    let err = mean_error(&sol, &b, &Boundary::Flat);
    assert!(err <= 5.0, "mean normal error {err}°");
    let z = depth(&sol, &b.mask);
    let rim: Vec<f64> = (0..128)
        .flat_map(|i| [(i, 0), (i, 127), (0, i), (127, i)])
        .map(|(c, r)| *z.get(c, r))
        .collect();
    let rim_mean = rim.iter().sum::<f64>() / rim.len() as f64;
    let centre = (z.get(63, 63) + z.get(64, 64) + z.get(63, 64) + z.get(64, 63)) / 4.0;
    assert!(centre > rim_mean + 5.0, "centre {centre} vs rim {rim_mean}");
    // Assuming the light from below, the same image is a dimple: the depth negated.
    let below = solve(&b, light, light.opposite_tilt(), &Boundary::Flat);
    let z2 = depth(&below, &b.mask);
    let scale = z.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (a, b) in z.data().iter().zip(z2.data()) {
        assert!((a + b).abs() <= 1e-6 * scale, "{a} vs {b}");
    }
    assert_eq!(below.iterations, sol.iterations);
}

#[test]
fn the_literal_update_diverges_where_jacobi_converges() {
    let s = sphere(64, 64, 28.8).unwrap();
    let (image, map) = picture(&s, Light::FRONT);
    let mut solver = Solver::new(64, 64).unwrap();
    let mut options = SolveOptions {
        max_iter: 5000,
        ..SolveOptions::default()
    };
    let stable = solver
        .solve(&image, &s.mask, &Boundary::Occluding, &map, &options)
        .unwrap();
    assert!(stable.converged && !stable.diverged);
    assert!(mean_error(&stable, &s, &Boundary::Occluding) < 1.0);
    options.method = Method::Literal;
    let literal = solver
        .solve(&image, &s.mask, &Boundary::Occluding, &map, &options)
        .unwrap();
    assert!(literal.diverged && !literal.converged, "{literal:?}");
    assert!(
        literal.iterations < 2000,
        "took {} sweeps",
        literal.iterations
    );
    assert!(literal.last_update > DIVERGENCE_UPDATE);
}

#[test]
fn shadowed_pixels_carry_smoothness_only() {
    // A sphere lit from the side at a steep slant: its far side is in attached shadow.
    let s = sphere(64, 64, 28.8).unwrap();
    let light = Light::from_tilt_slant(90.0, 70.0).unwrap();
    let (image, map) = picture(&s, light);
    let mut solver = Solver::new(64, 64).unwrap();
    let options = SolveOptions {
        tol: 1e-9,
        ..SolveOptions::default()
    };
    let sol = solver
        .solve(&image, &s.mask, &Boundary::Occluding, &map, &options)
        .unwrap();
    assert!(sol.converged);
    let bc = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
    let mut shadowed = 0;
    for r in 1..63 {
        for c in 1..63 {
            if *bc.roles.get(c, r) != Role::Unknown || *image.get(c, r) > 0.0 {
                continue;
            }
            shadowed += 1;
            // At the fixed point a shadowed pixel is the mean of its neighbours: no data pull.
            let f_bar = (sol.f.get(c - 1, r)
                + sol.f.get(c + 1, r)
                + sol.f.get(c, r - 1)
                + sol.f.get(c, r + 1))
                / 4.0;
            assert!((sol.f.get(c, r) - f_bar).abs() < 1e-8);
        }
    }
    assert!(shadowed > 50, "{shadowed} shadowed unknowns");
}

#[test]
fn a_plane_facing_the_viewer_is_a_fixed_point_with_zero_energy() {
    let light = Light::from_tilt_slant(30.0, 40.0).unwrap();
    let map = Lambertian::unit(light);
    let image = Grid::new(20, 16, light.direction().z);
    let mut solver = Solver::new(20, 16).unwrap();
    let sol = solver
        .solve(
            &image,
            &Grid::new(20, 16, true),
            &Boundary::Flat,
            &map,
            &SolveOptions::default(),
        )
        .unwrap();
    assert_eq!(sol.iterations, 1);
    assert!(sol.converged && sol.last_update == 0.0);
    assert_eq!(sol.smoothness_energy, 0.0);
    assert!(sol.brightness_energy < 1e-28);
    assert_eq!(sol.unknowns, 18 * 14);
}

/// Solves the picture of `surface` under `light` with `options` (the occluding boundary),
/// keeping every progress report.
pub(super) fn solve_reporting(
    surface: &Surface,
    light: Light,
    options: &SolveOptions,
) -> (Solution, Vec<Progress>) {
    let (image, map) = picture(surface, light);
    let mut solver = Solver::new(surface.width(), surface.height()).unwrap();
    let mut seen = Vec::new();
    let sol = solver
        .solve_with_progress(
            &image,
            &surface.mask,
            &Boundary::Occluding,
            &map,
            options,
            &mut |p| seen.push(*p),
        )
        .unwrap();
    (sol, seen)
}

#[test]
fn progress_is_reported_every_sweep() {
    let s = sphere(32, 32, 14.0).unwrap();
    let (sol, seen) = solve_reporting(&s, Light::FRONT, &SolveOptions::default());
    assert_eq!(seen.len(), sol.iterations);
    for (i, p) in seen.iter().enumerate() {
        assert_eq!(p.iteration, i + 1);
        assert_eq!(p.max_iter, MULTIGRID_MAX_CYCLES);
    }
    assert_eq!(seen.last().map(|p| p.last_update), Some(sol.last_update));
}

#[cfg(feature = "parallel")]
#[test]
fn reused_buffers_carry_nothing_over_and_results_do_not_depend_on_threads() {
    // Big enough for the parallel sweep; a few sweeps suffice to compare bits.
    let b = gaussian(200, 200, 20.0, 20.0, 0.0, 0.0).unwrap();
    let light = Light::from_tilt_slant(20.0, 40.0).unwrap();
    let (image, map) = picture(&b, light);
    let options = SolveOptions {
        max_iter: 30,
        ..SolveOptions::default()
    };
    let run = |threads: usize, solver: &mut Solver| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                solver
                    .solve(&image, &b.mask, &Boundary::Flat, &map, &options)
                    .unwrap()
            })
    };
    let mut solver = Solver::new(200, 200).unwrap();
    let one = run(1, &mut solver);
    assert!(one.unknowns >= PARALLEL_MIN);
    // The same solver, used first on another problem, then again.
    let s = sphere(200, 200, 90.0).unwrap();
    let (other, _) = picture(&s, Light::FRONT);
    solver
        .solve(&other, &s.mask, &Boundary::Occluding, &map, &options)
        .unwrap();
    let three = run(3, &mut solver);
    assert_eq!(one, three);
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let s = sphere(16, 16, 6.0).unwrap();
    let (image, map) = picture(&s, Light::FRONT);
    let mut solver = Solver::new(16, 16).unwrap();
    let ok = SolveOptions::default();
    let occ = Boundary::Occluding;
    let e = solver
        .solve(&Grid::new(16, 15, 0.5), &s.mask, &occ, &map, &ok)
        .unwrap_err();
    assert!(e.to_string().contains("15 px high × 16 px wide"), "{e}");
    assert!(solver
        .solve(&image, &Grid::new(15, 16, true), &occ, &map, &ok)
        .is_err());
    let mut nan = image.clone();
    *nan.get_mut(3, 5) = f64::NAN;
    let e = solver.solve(&nan, &s.mask, &occ, &map, &ok).unwrap_err();
    assert!(e.to_string().contains("column 3, row 5"), "{e}");
    let empty = solver
        .solve(&image, &Grid::new(16, 16, false), &occ, &map, &ok)
        .unwrap_err();
    assert!(empty.to_string().contains("empty"), "{empty}");
    for bad in [
        SolveOptions { lambda: 0.0, ..ok },
        SolveOptions { lambda: -1.0, ..ok },
        SolveOptions {
            lambda: f64::NAN,
            ..ok
        },
        SolveOptions { tol: 0.0, ..ok },
        SolveOptions { max_iter: 0, ..ok },
    ] {
        assert!(solver.solve(&image, &s.mask, &occ, &map, &bad).is_err());
    }
    // A grazing light is refused where a light for a solve is made (a FrontLight); the engine
    // itself computes under any light, without a panic.
    let grazing = Light::from_vector(1.0, 0.0, 0.0).unwrap();
    let e = crate::light::FrontLight::new(grazing).unwrap_err();
    assert!(e.to_string().contains("z > 0"), "{e}");
    let _ = solver.solve(&image, &s.mask, &occ, &Lambertian::unit(grazing), &ok);
    assert!("multigridx".parse::<Method>().is_err());
    assert_eq!("literal".parse::<Method>().unwrap(), Method::Literal);
    assert_eq!(Method::Jacobi.to_string(), "jacobi");
}

/// Clipped pixels (at or above `SolveOptions::saturation`) carry smoothness only, in every
/// method: Jacobi ignores their values exactly (any value above the level gives the same
/// bits, the same brightness energy), so do multigrid and the integrable method (up to the
/// nested start, which averages the image), and without the level the same image solves
/// differently, its clipped pixels in the brightness energy.
#[test]
fn clipped_pixels_carry_smoothness_only() {
    let s = sphere(48, 48, 20.0).unwrap();
    let light = Light::from_tilt_slant(30.0, 30.0).unwrap();
    let (image, map) = picture(&s, light);
    let level = 0.95;
    let clipped = image.map(|v| v.min(level));
    let brighter = image.map(|v| if *v >= level { 5.0 } else { *v });
    let n_clipped = clipped_pixels(&clipped, &s.mask, Some(level));
    assert!(n_clipped > 20, "{n_clipped}");
    assert_eq!(clipped_pixels(&clipped, &s.mask, None), 0);
    let mut solver = Solver::new(48, 48).unwrap();
    let mut solve = |image: &Image, method: Method, saturation: Option<f64>| {
        let options = SolveOptions {
            tol: 1e-9,
            saturation,
            ..SolveOptions::for_method(method)
        };
        let sol = solver
            .solve(image, &s.mask, &Boundary::Occluding, &map, &options)
            .unwrap();
        // The integrable methods stop at their caps of 200 short of 1e-9.
        assert!(
            sol.converged || matches!(method, Method::Integrable | Method::IntegrableLm),
            "{method}"
        );
        sol
    };
    let largest_difference = |a: &Solution, b: &Solution| {
        let d = |x: &Image, y: &Image| {
            x.data()
                .iter()
                .zip(y.data())
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max)
        };
        d(&a.f, &b.f).max(d(&a.g, &b.g))
    };
    let jacobi = solve(&clipped, Method::Jacobi, Some(level));
    let other = solve(&brighter, Method::Jacobi, Some(level));
    assert_eq!(jacobi.f, other.f);
    assert_eq!(jacobi.g, other.g);
    assert_eq!(jacobi.brightness_energy, other.brightness_energy);
    let kept_in = solve(&clipped, Method::Jacobi, None);
    assert!(largest_difference(&kept_in, &jacobi) > 1e-2);
    assert!(kept_in.brightness_energy > jacobi.brightness_energy);
    for method in [Method::Multigrid, Method::Integrable, Method::IntegrableLm] {
        let a = solve(&clipped, method, Some(level));
        let b = solve(&brighter, method, Some(level));
        let kept_in = solve(&clipped, method, None);
        assert!(largest_difference(&a, &b) < 1e-5, "{method}");
        assert!(largest_difference(&a, &kept_in) > 1e-2, "{method}");
    }
    // A level that is not a positive number is refused.
    for bad in [0.0, -1.0, f64::NAN] {
        let options = SolveOptions {
            saturation: Some(bad),
            ..SolveOptions::default()
        };
        assert!(options.validate().is_err(), "{bad}");
    }
}

/// `grid` mirrored left to right, or top to bottom when `vertical`.
fn mirrored<T: Clone>(grid: &Grid<T>, vertical: bool) -> Grid<T> {
    let (w, h) = (grid.width(), grid.height());
    Grid::from_fn(w, h, |c, r| {
        let (c, r) = if vertical {
            (c, h - 1 - r)
        } else {
            (w - 1 - c, r)
        };
        grid.get(c, r).clone()
    })
}

/// The Ikeuchi–Horn solve does not prefer a side: the picture mirrored left to right and solved
/// under the light's mirror (tilt −θ) gives the solution mirrored (f negated), and top to
/// bottom (tilt 180° − θ) the same with g negated, with every boundary, on the bunny (no
/// symmetry of its own) lit obliquely. An update order or stencil that leaned one way, or a
/// boundary normal fitted one-sidedly, would show here (a light 1° off the mirror: 0.015).
///
/// Measured: at 80², at most 5e-5 everywhere. At 101² (an odd size: its coarse grids are not
/// mirror images, the last coarse row or column having one child) the top–bottom mirror
/// differs by up to 0.16 at the edge of the attached shadow, 1e-3 three pixels from it and
/// 3e-4 six pixels from it (the occluding boundary; 3e-7 with the others); a sphere at 96²
/// differs by 0.018 inside its shadow. There the brightness term only asks n·l ≤ 0, a region
/// of the f–g plane outside a circle, not convex, so the smoothest field need not be unique,
/// and the update order picks one. Hence the comparison six pixels or more from the shadow
/// (pixels of the object darker than 0.02). The Levenberg–Marquardt methods are not held to
/// it (see `integrable/newton/mod.rs`).
#[test]
fn mirrored_pictures_give_mirrored_solutions() {
    let options = SolveOptions::for_method(Method::Multigrid);
    for size in [80, 101] {
        let surface = bunny(size);
        let (image, map) = picture(&surface, Light::from_tilt_slant(30.0, 40.0).unwrap());
        // At least six pixels (in rows and columns) from any pixel of the object darker than
        // 0.02.
        let far = |c: usize, r: usize| {
            let near = |a: usize| a.saturating_sub(6)..(a + 7).min(size);
            near(r).all(|rr| {
                near(c).all(|cc| !*surface.mask.get(cc, rr) || *image.get(cc, rr) >= 0.02)
            })
        };
        for vertical in [false, true] {
            let tilt = if vertical { 150.0 } else { -30.0 };
            let mirror_map = Lambertian::unit(Light::from_tilt_slant(tilt, 40.0).unwrap());
            let mirror_image = mirrored(&image, vertical);
            let mirror_mask = mirrored(&surface.mask, vertical);
            let (sf, sg) = if vertical { (1.0, -1.0) } else { (-1.0, 1.0) };
            for boundary in [Boundary::Occluding, Boundary::Flat, Boundary::Free] {
                let solve = |image: &Image, mask: &Mask, map: &Lambertian| {
                    let mut solver = Solver::new(size, size).unwrap();
                    let s = solver.solve(image, mask, &boundary, map, &options).unwrap();
                    assert!(s.converged, "{size} {boundary:?}");
                    s
                };
                let a = solve(&image, &surface.mask, &map);
                let b = solve(&mirror_image, &mirror_mask, &mirror_map);
                let (bf, bg) = (mirrored(&b.f, vertical), mirrored(&b.g, vertical));
                let mut worst: f64 = 0.0;
                for r in 0..size {
                    for c in (0..size).filter(|&c| far(c, r)) {
                        let df = a.f.get(c, r) - sf * bf.get(c, r);
                        let dg = a.g.get(c, r) - sg * bg.get(c, r);
                        worst = worst.max(df.abs()).max(dg.abs());
                    }
                }
                let bound = if size % 2 == 0 { 1e-4 } else { 1e-3 };
                assert!(
                    worst < bound,
                    "{size} {boundary:?} vertical {vertical}: {worst:e}"
                );
            }
        }
    }
}
