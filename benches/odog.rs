//! Benchmarks of the ODOG family on a 1024² White's-illusion-like image at 32 ppd (32°), the
//! size of multyscale's reference run (33 s for ODOG, 62 s for LODOG there).
//!
//! `cargo bench --bench odog` runs criterion. For a memory figure, run the bench binary once
//! under `/usr/bin/time -v` with `SHADELAB_ODOG_ONCE=odog` (or lodog, flodog): it plans the
//! model, applies it once, prints the timings and exits.

use criterion::{criterion_group, Criterion};
use shadelab::Grid;
use shadelab::Image;
use shadelab_analysis::lightness::{Odog, Variant};
use std::hint::black_box;
use std::time::{Duration, Instant};

const SIZE: usize = 1024;
const PPD: f64 = 32.0;

/// Vertical square-wave bars of 2° with two mid-grey targets, like the reference stimulus.
fn whites_illusion() -> Image {
    Grid::from_fn(SIZE, SIZE, |c, r| {
        let bar = (c / 64) % 2;
        let target =
            (448..576).contains(&r) && ((128..192).contains(&c) || (832..896).contains(&c));
        if target {
            0.5
        } else if bar == 0 {
            1.0
        } else {
            0.0
        }
    })
}

fn bench(c: &mut Criterion) {
    let image = whites_illusion();
    let mut group = c.benchmark_group("odog_1024");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.bench_function("plan_odog", |b| {
        b.iter(|| Odog::new(SIZE, SIZE, PPD, Variant::Odog).unwrap())
    });
    for variant in Variant::ALL {
        let model = Odog::new(SIZE, SIZE, PPD, variant).unwrap();
        group.bench_function(format!("apply_{variant}"), |b| {
            b.iter(|| model.apply(black_box(&image)).unwrap())
        });
    }
    group.finish();
}

// No plots: the plotting backend needs fonts that a bare machine may not have.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}

fn main() {
    if let Ok(name) = std::env::var("SHADELAB_ODOG_ONCE") {
        let variant: Variant = name.parse().expect("odog, lodog or flodog");
        let image = whites_illusion();
        let t = Instant::now();
        let model = Odog::new(SIZE, SIZE, PPD, variant).unwrap();
        let planned = t.elapsed();
        let t = Instant::now();
        let out = model.apply(&image).unwrap();
        let applied = t.elapsed();
        println!(
            "{variant} {SIZE}x{SIZE}: plan {:.3} s, apply {:.3} s, output[512,160] = {:.4}",
            planned.as_secs_f64(),
            applied.as_secs_f64(),
            out.get(160, 512)
        );
        return;
    }
    benches();
    Criterion::default()
        .without_plots()
        .configure_from_args()
        .final_summary();
}
