//! Benchmarks of the shape-from-shading solvers on the sphere (radius 0.45 of the side, frontal
//! light, occluding boundary, λ = 1, tol 1e-6): multigrid from 128² to 1024², plain Jacobi at
//! 128² for the ratio. `shadelab bench` prints the same comparison as a table, with the NumPy
//! reference beside it.
//!
//! `cargo bench --bench solver` runs criterion. For a memory figure, run the bench binary once
//! under `/usr/bin/time -v` with `SHADELAB_SOLVER_ONCE=1024` (any size): it solves that sphere
//! once with multigrid, prints the time and exits.

use criterion::{criterion_group, BenchmarkId, Criterion};
use shadelab::Boundary;
use shadelab::Lambertian;
use shadelab::{Image, Light};
use shadelab_engine::render::{render, RenderOptions};
use shadelab_engine::solver::{Method, SolveOptions, Solver};
use shadelab_engine::surface::{sphere, Surface};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// The benchmark problem at `size`².
fn problem(size: usize) -> (Surface, Image, Lambertian) {
    let surface = sphere(size, size, 0.45 * size as f64).expect("a valid sphere");
    let map = Lambertian {
        light: Light::FRONT,
        albedo: 1.0,
        ambient: 0.0,
    };
    let image = render(&surface, &map, &RenderOptions::default()).image;
    (surface, image, map)
}

fn options(method: Method) -> SolveOptions {
    SolveOptions {
        method,
        ..SolveOptions::for_method(method)
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("solve_sphere_frontal");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for size in [128, 256, 512, 1024] {
        let (surface, image, map) = problem(size);
        // One solver per size, as a sweep over lights would use it: planned once, reused.
        let mut solver = Solver::new(size, size).expect("a valid size");
        let opts = options(Method::Multigrid);
        group.bench_with_input(BenchmarkId::new("multigrid", size), &size, |b, _| {
            b.iter(|| {
                let s = solver
                    .solve(&image, &surface.mask, &Boundary::Occluding, &map, &opts)
                    .expect("solvable");
                assert!(s.converged);
                black_box(s)
            })
        });
    }
    let size = 128;
    let (surface, image, map) = problem(size);
    let mut solver = Solver::new(size, size).expect("a valid size");
    let opts = options(Method::Jacobi);
    group.measurement_time(Duration::from_secs(20));
    group.bench_with_input(BenchmarkId::new("jacobi", size), &size, |b, _| {
        b.iter(|| {
            black_box(
                solver
                    .solve(&image, &surface.mask, &Boundary::Occluding, &map, &opts)
                    .expect("solvable"),
            )
        })
    });
    group.finish();
}

// No plots: the plotting backend needs fonts that a bare machine may not have.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}

fn main() {
    if let Ok(size) = std::env::var("SHADELAB_SOLVER_ONCE") {
        let size: usize = size.parse().expect("SHADELAB_SOLVER_ONCE must be a size");
        let (surface, image, map) = problem(size);
        let started = Instant::now();
        let mut solver = Solver::new(size, size).expect("a valid size");
        let s = solver
            .solve(
                &image,
                &surface.mask,
                &Boundary::Occluding,
                &map,
                &options(Method::Multigrid),
            )
            .expect("solvable");
        println!(
            "multigrid {size}²: {} cycles, converged {}, {:.3} s",
            s.iterations,
            s.converged,
            started.elapsed().as_secs_f64()
        );
        return;
    }
    benches();
    Criterion::default()
        .without_plots()
        .configure_from_args()
        .final_summary();
}
