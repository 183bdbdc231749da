//! Benchmarks of the stimulus generator: the 1024² checkerboard and disc compared with stimupy
//! (`benches/stimupy_compare.py` times stimupy on the same stimuli), every gallery preset, and
//! the whole gallery as `shadelab gallery` builds it (files, thumbnails, sheet and page).
//!
//! `cargo bench --bench stimuli` runs criterion. The figures are recorded in
//! docs/performance.md under "Stimuli".

use criterion::{criterion_group, criterion_main, Criterion};
use serde_json::{Map, Value};
use shadelab::stimulus;
use shadelab::SizeRequest;
use std::hint::black_box;
use std::time::Duration;

const MAX: usize = 1 << 26;

fn size(visual: f64, ppd: f64) -> SizeRequest {
    SizeRequest {
        visual_size: Some((visual, visual)),
        ppd: Some(ppd),
        shape: None,
    }
}

fn params(pairs: &[(&str, f64)]) -> Map<String, Value> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), Value::from(*v)))
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("stimupy_1024");
    group.measurement_time(Duration::from_secs(5));
    // stimupy.stimuli.checkerboards.checkerboard(visual_size=32, ppd=32, check_visual_size=1)
    let checks = params(&[("check", 1.0)]);
    group.bench_function("checkerboard", |b| {
        b.iter(|| {
            stimulus::generate(
                "checkerboard",
                black_box(&checks),
                &size(32.0, 32.0),
                0,
                MAX,
            )
        })
    });
    // stimupy.components.shapes.disc(visual_size=16, ppd=64, radius=4)
    let disc = params(&[("radius", 4.0)]);
    group.bench_function("disc", |b| {
        b.iter(|| stimulus::generate("disc", black_box(&disc), &size(16.0, 64.0), 0, MAX))
    });
    group.finish();

    let mut group = c.benchmark_group("presets");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(2));
    for preset in shadelab_stimuli::gallery::builtin_presets().unwrap_or_default() {
        let spec = preset.spec;
        group.bench_function(preset.name.as_str(), |b| {
            b.iter(|| {
                stimulus::generate(
                    &spec.stimulus,
                    &spec.params,
                    &spec.size(),
                    spec.seed.unwrap_or(0),
                    MAX,
                )
            })
        });
    }
    group.finish();

    // The whole gallery into one folder, replaced each time (README: "about a second").
    let mut group = c.benchmark_group("gallery");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    let presets = shadelab_stimuli::gallery::builtin_presets().expect("the built-in presets");
    let out = std::env::temp_dir().join(format!("shadelab-bench-gallery-{}", std::process::id()));
    let config = shadelab::GalleryConfig {
        presets,
        options: shadelab::pipeline::gallery::Options::default(),
        source: None,
    };
    let dest = shadelab::Output::new(&out);
    group.bench_function("build", |b| {
        b.iter(|| {
            use shadelab::CommandReport;
            shadelab::gallery(black_box(&config), &shadelab::NoProgress)
                .and_then(|report| report.write(&dest))
        })
    });
    group.finish();
    let _ = std::fs::remove_dir_all(&out);
}

// No plots: the plotting backend needs fonts that a bare machine may not have.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
