//! The multigrid solver (`Method::Multigrid`) against the stable Jacobi iteration it must agree
//! with: the same fixed point on the sphere and the vase at 128² and 256² under frontal and
//! oblique light, on flat and free boundaries, bit-identical results for any thread count,
//! buffers reused without carry-over, and an honest report when it stops early.
//!
//! The 256² Jacobi references take 7,000–18,000 sweeps each, so they are computed once and kept
//! in Cargo's scratch folder for integration tests, under a key made of the case and the source
//! of everything that shapes Jacobi's answer (any change there recomputes them).

use md5::{Digest, Md5};
use shadelab::Lambertian;
use shadelab::{Grid, Image, Light, Mask};
use shadelab_core::gradient_space::{angle_deg, normal_from_fg};
use shadelab_engine::boundary::{boundary_conditions, Boundary, Role};
use shadelab_engine::render::{render, RenderOptions};
use shadelab_engine::solver::{Method, Solution, SolveOptions, Solver};
use shadelab_engine::surface::{gaussian, sphere, vase, Surface};
use std::path::PathBuf;

/// The sources whose change can change Jacobi's answer.
const JACOBI_SOURCES: &[&str] = &[
    include_str!("../crates/engine/src/solver/mod.rs"),
    include_str!("../crates/engine/src/boundary.rs"),
    include_str!("../crates/engine/src/reflectance.rs"),
    include_str!("../crates/core/src/gradient_space.rs"),
    include_str!("../crates/engine/src/render.rs"),
    include_str!("../crates/engine/src/surface/shapes.rs"),
];

/// One test problem.
struct Case {
    name: String,
    surface: Surface,
    image: Image,
    map: Lambertian,
    boundary: Boundary,
}

fn case(shape: &str, size: usize, light: [f64; 3], boundary: Boundary) -> Case {
    let surface = match shape {
        "sphere" => sphere(size, size, 0.45 * size as f64).unwrap(),
        "vase" => vase(size, size).unwrap(),
        "bump" => gaussian(size, size, 0.12 * size as f64, 0.12 * size as f64, 0.0, 0.0).unwrap(),
        other => panic!("no shape {other}"),
    };
    let map = Lambertian {
        light: Light::from_vector(light[0], light[1], light[2]).unwrap(),
        albedo: 1.0,
        ambient: 0.0,
    };
    let image = render(&surface, &map, &RenderOptions::default()).image;
    Case {
        name: format!("{shape}-{size}-{light:?}-{}", boundary.name()),
        surface,
        image,
        map,
        boundary,
    }
}

fn options(method: Method) -> SolveOptions {
    SolveOptions {
        method,
        ..SolveOptions::for_method(method)
    }
}

fn solve(c: &Case, options: &SolveOptions) -> Solution {
    let mut solver = Solver::new(c.image.width(), c.image.height()).unwrap();
    solver
        .solve(&c.image, &c.surface.mask, &c.boundary, &c.map, options)
        .unwrap()
}

/// Jacobi's normals for `c` at the default options, from the cache when it has them.
fn jacobi_normals(c: &Case) -> Grid<nalgebra::Vector3<f64>> {
    let options = options(Method::Jacobi);
    let mut hash = Md5::new();
    hash.update(format!("{}|{:?}", c.name, options));
    for source in JACOBI_SOURCES {
        hash.update(source.as_bytes());
    }
    let key: String = hash.finalize().iter().map(|b| format!("{b:02x}")).collect();
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("jacobi-references");
    let path = dir.join(format!("{key}.f64"));
    let (w, h) = (c.image.width(), c.image.height());
    let (f, g) = match std::fs::read(&path) {
        Ok(bytes) if bytes.len() == 16 * w * h => {
            let values: Vec<f64> = bytes
                .chunks_exact(8)
                .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
                .collect();
            let (f, g) = values.split_at(w * h);
            (f.to_vec(), g.to_vec())
        }
        _ => {
            let sol = solve(c, &options);
            assert!(sol.converged, "{}: Jacobi did not converge", c.name);
            let mut bytes = Vec::with_capacity(16 * w * h);
            for v in sol.f.data().iter().chain(sol.g.data()) {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
            std::fs::create_dir_all(&dir).unwrap();
            let tmp = dir.join(format!("{key}.{}.tmp", std::process::id()));
            std::fs::write(&tmp, &bytes).unwrap();
            std::fs::rename(&tmp, &path).unwrap();
            (sol.f.data().to_vec(), sol.g.data().to_vec())
        }
    };
    Grid::from_fn(w, h, |col, row| {
        let i = row * w + col;
        if *c.surface.mask.get(col, row) {
            normal_from_fg(f[i], g[i])
        } else {
            nalgebra::Vector3::z()
        }
    })
}

/// Mean angle (degrees) between two normal fields over the unknowns of `c`.
fn mean_difference(
    c: &Case,
    a: &Grid<nalgebra::Vector3<f64>>,
    b: &Grid<nalgebra::Vector3<f64>>,
) -> f64 {
    let bc = boundary_conditions(&c.surface.mask, &c.boundary).unwrap();
    let (mut sum, mut n) = (0.0, 0);
    for (i, role) in bc.roles.data().iter().enumerate() {
        if *role == Role::Unknown {
            sum += angle_deg(&a.data()[i], &b.data()[i]);
            n += 1;
        }
    }
    sum / n as f64
}

/// Multigrid reaches Jacobi's answer on `c` to within `limit_deg` on average, and converges.
fn agrees_with_jacobi(c: &Case, limit_deg: f64) {
    let mg = solve(c, &options(Method::Multigrid));
    assert!(mg.converged && !mg.diverged, "{}: {mg:?}", c.name);
    assert!(mg.last_update < SolveOptions::default().tol);
    // A handful of cycles, not thousands of sweeps.
    assert!(mg.iterations <= 30, "{}: {} cycles", c.name, mg.iterations);
    let reference = jacobi_normals(c);
    let diff = mean_difference(c, &mg.normals(), &reference);
    eprintln!(
        "{}: {} cycles, {diff:.5}° from Jacobi",
        c.name, mg.iterations
    );
    assert!(
        diff <= limit_deg,
        "{}: mean difference from Jacobi {diff:.4}° > {limit_deg}°",
        c.name
    );
}

const FRONT: [f64; 3] = [0.0, 0.0, 1.0];
const OBLIQUE: [f64; 3] = [1.0, 0.0, 1.0];

#[test]
fn sphere_128_frontal_and_oblique_match_jacobi() {
    for light in [FRONT, OBLIQUE] {
        agrees_with_jacobi(&case("sphere", 128, light, Boundary::Occluding), 0.1);
    }
}

#[test]
fn vase_128_frontal_and_oblique_match_jacobi() {
    for light in [FRONT, OBLIQUE] {
        agrees_with_jacobi(&case("vase", 128, light, Boundary::Occluding), 0.1);
    }
}

#[test]
fn sphere_256_frontal_matches_jacobi() {
    agrees_with_jacobi(&case("sphere", 256, FRONT, Boundary::Occluding), 0.1);
}

#[test]
fn sphere_256_oblique_matches_jacobi() {
    agrees_with_jacobi(&case("sphere", 256, OBLIQUE, Boundary::Occluding), 0.1);
}

#[test]
fn vase_256_frontal_matches_jacobi() {
    agrees_with_jacobi(&case("vase", 256, FRONT, Boundary::Occluding), 0.1);
}

#[test]
fn vase_256_oblique_matches_jacobi() {
    agrees_with_jacobi(&case("vase", 256, OBLIQUE, Boundary::Occluding), 0.1);
}

#[test]
fn flat_and_free_boundaries_match_jacobi() {
    // The flat rim fixes the whole image border; the free boundary fixes nothing, so every
    // coarse cell at the edge of the domain has a natural boundary.
    agrees_with_jacobi(&case("bump", 96, [0.0, 1.0, 1.0], Boundary::Flat), 0.1);
    agrees_with_jacobi(&case("vase", 64, [0.3, 0.2, 1.0], Boundary::Free), 0.1);
}

#[test]
fn tiny_and_ragged_domains_match_jacobi() {
    // A mask too small to coarsen, with an isolated pixel (free boundary: it has no domain
    // neighbour and is not fixed), and an odd-sized image whose coarse cells straddle the frame.
    let light = Light::from_vector(0.2, -0.3, 1.0).unwrap();
    let map = Lambertian {
        light,
        albedo: 1.0,
        ambient: 0.0,
    };
    for (w, h) in [(9, 7), (37, 23)] {
        let s = sphere(w, h, 0.4 * w.min(h) as f64).unwrap();
        let mut mask: Mask = s.mask.clone();
        *mask.get_mut(0, 0) = true;
        let image = render(&s, &map, &RenderOptions::default()).image;
        let c = Case {
            name: format!("ragged {w}x{h}"),
            surface: Surface { mask, ..s },
            image,
            map,
            boundary: Boundary::Free,
        };
        let mg = solve(&c, &options(Method::Multigrid));
        let jac = solve(&c, &options(Method::Jacobi));
        assert!(mg.converged);
        assert_eq!(mg.unknowns, jac.unknowns);
        // The isolated pixel stays facing the viewer, as in Jacobi.
        assert_eq!(*mg.f.get(0, 0), 0.0);
        assert_eq!(mg.normal(0, 0), jac.normal(0, 0));
        let diff = mean_difference(&c, &mg.normals(), &jac.normals());
        assert!(diff <= 0.01, "{}: {diff}°", c.name);
    }
}

#[test]
fn results_do_not_depend_on_threads_and_buffers_carry_nothing_over() {
    // 256² has enough unknowns for the parallel sweeps; the oblique light adds a shadow.
    let c = case("sphere", 256, OBLIQUE, Boundary::Occluding);
    let opts = options(Method::Multigrid);
    let run = |threads: usize, solver: &mut Solver, c: &Case| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                solver
                    .solve(&c.image, &c.surface.mask, &c.boundary, &c.map, &opts)
                    .unwrap()
            })
    };
    let mut solver = Solver::new(256, 256).unwrap();
    let one = run(1, &mut solver, &c);
    // The same solver on another problem, then on the first one again with two threads.
    let other = case("vase", 256, FRONT, Boundary::Occluding);
    let between = run(2, &mut solver, &other);
    assert!(between.converged);
    let two = run(2, &mut solver, &c);
    assert_eq!(one, two);
    assert!(one
        .f
        .data()
        .iter()
        .zip(two.f.data())
        .all(|(a, b)| a.to_bits() == b.to_bits()));
}

#[test]
fn stopping_early_is_reported() {
    let c = case("sphere", 128, FRONT, Boundary::Occluding);
    let mut seen = Vec::new();
    let mut solver = Solver::new(128, 128).unwrap();
    let opts = SolveOptions {
        max_iter: 2,
        ..options(Method::Multigrid)
    };
    let sol = solver
        .solve_with_progress(
            &c.image,
            &c.surface.mask,
            &c.boundary,
            &c.map,
            &opts,
            &mut |p| seen.push(*p),
        )
        .unwrap();
    assert!(!sol.converged && !sol.diverged);
    assert_eq!(sol.iterations, 2);
    assert!(sol.last_update >= opts.tol);
    assert_eq!(seen.len(), 2);
    assert_eq!(seen[1].iteration, 2);
    // A looser tolerance is met sooner, a tighter one later: the test is on the residual.
    let loose = solve(
        &c,
        &SolveOptions {
            tol: 1e-3,
            ..options(Method::Multigrid)
        },
    );
    let tight = solve(
        &c,
        &SolveOptions {
            tol: 1e-10,
            ..options(Method::Multigrid)
        },
    );
    assert!(loose.converged && tight.converged);
    assert!(loose.iterations < tight.iterations);
    assert!(tight.last_update < 1e-10);
}

#[test]
fn bad_input_is_rejected_as_for_jacobi() {
    let c = case("sphere", 16, FRONT, Boundary::Occluding);
    let mut solver = Solver::new(16, 16).unwrap();
    let mg = options(Method::Multigrid);
    let jac = options(Method::Jacobi);
    let message = |solver: &mut Solver, image: &Image, mask: &Mask, o: &SolveOptions| {
        solver
            .solve(image, mask, &c.boundary, &c.map, o)
            .unwrap_err()
            .to_string()
    };
    let mut nan = c.image.clone();
    *nan.get_mut(3, 5) = f64::NAN;
    let small = Grid::new(16, 15, 0.5);
    let empty = Grid::new(16, 16, false);
    for (image, mask) in [
        (&nan, &c.surface.mask),
        (&small, &c.surface.mask),
        (&c.image, &empty),
    ] {
        assert_eq!(
            message(&mut solver, image, mask, &mg),
            message(&mut solver, image, mask, &jac)
        );
    }
    for bad in [
        SolveOptions { lambda: 0.0, ..mg },
        SolveOptions { tol: 0.0, ..mg },
        SolveOptions { max_iter: 0, ..mg },
    ] {
        assert!(solver
            .solve(&c.image, &c.surface.mask, &c.boundary, &c.map, &bad)
            .is_err());
    }
    assert_eq!("multigrid".parse::<Method>().unwrap(), Method::Multigrid);
    assert_eq!(Method::Multigrid.to_string(), "multigrid");
}

#[test]
fn solve_command_uses_multigrid_and_reports_non_convergence() {
    use crate::cli::{scratch, shadelab};
    use shadelab_io as io;
    let d = scratch("fast-solver-cli");
    let c = case("sphere", 64, FRONT, Boundary::Occluding);
    io::write_image(&d.join("image.npy"), &c.image).unwrap();
    io::write_mask(&d.join("mask.png"), &c.surface.mask).unwrap();
    let base = [
        "solve",
        "image.npy",
        "--light",
        "front",
        "--mask",
        "mask.png",
    ];
    let report = |dir: &str| -> serde_json::Value {
        let text = std::fs::read_to_string(d.join(dir).join("report.json")).unwrap();
        serde_json::from_str(&text).unwrap()
    };
    // Multigrid (the fast choice) converges and says so quietly.
    let multigrid = ["--method", "multigrid"];
    let args = [&base[..], &multigrid, &["--out", "ok", "--quiet"]].concat();
    let out = shadelab(&d, &args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r = report("ok");
    assert_eq!(r["parameters"]["method"], "multigrid");
    assert_eq!(r["solver"]["converged"], true);
    assert!(r["solver"]["warning"].is_null());
    // One cycle is not enough: still a success, but never a silent one, even with --quiet.
    let args = [
        &base[..],
        &multigrid,
        &["--out", "short", "--max-iter", "1", "--quiet"],
    ]
    .concat();
    let out = shadelab(&d, &args);
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with("warning: the multigrid solve did not converge within --max-iter 1"),
        "{stderr}"
    );
    let r = report("short");
    assert_eq!(r["solver"]["converged"], false);
    assert_eq!(r["solver"]["iterations"], 1);
    assert!(r["solver"]["warning"]
        .as_str()
        .is_some_and(|w| w.contains("did not converge")));
    // Jacobi stays selectable, and counts sweeps.
    let args = [
        &base[..],
        &["--out", "jac", "--method", "jacobi", "--max-iter", "3"],
    ]
    .concat();
    let out = shadelab(&d, &args);
    assert!(out.status.success());
    let r = report("jac");
    assert_eq!(r["solver"]["iteration_unit"], "sweeps");
    assert_eq!(r["solver"]["iterations"], 3);
    // Without --max-iter, Jacobi's cap is in sweeps.
    let args = [
        &base[..],
        &[
            "--out",
            "jac-default",
            "--method",
            "jacobi",
            "--tol",
            "1e-2",
        ],
    ]
    .concat();
    assert!(shadelab(&d, &args).status.success());
    assert_eq!(report("jac-default")["parameters"]["max_iter"], 100_000);
}
