//! The library calls that `shadelab.render` and `shadelab.solve` make, timed in Rust alone, for
//! the Python overhead figures of docs/performance.md (`python/benches/overhead.py` runs this
//! and the same calls from Python, and prints both).
//!
//! `CARGO_TARGET_DIR=../target/python cargo run --release --example overhead` in `python/`
//! prints `render_ms t1,t2,…` and `solve_ms t1,t2,…` (milliseconds per call).

use shadelab::pipeline::{render, solve};
use shadelab::{NoProgress, Pixels};
use std::time::Instant;

/// Every call's time in milliseconds, comma separated, after one call to warm up.
fn times_ms(runs: usize, mut f: impl FnMut()) -> String {
    f();
    let t: Vec<String> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            format!("{:.4}", s.elapsed().as_secs_f64() * 1e3)
        })
        .collect();
    t.join(",")
}

fn main() -> Result<(), shadelab::Error> {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(21);
    let mut board = render::RenderConfig::new("checkerboard");
    board.size.shape = Some((1024, 1024));
    board.size.ppd = Some(32.0);
    let ms = times_ms(runs, || {
        std::hint::black_box(render::run(&board, &NoProgress).expect("renders"));
    });
    println!("render_ms {ms}");

    let mut sphere = render::RenderConfig::new("sphere");
    sphere.size.shape = Some((256, 256));
    sphere.params.insert("light".into(), "0.3,0.4,0.866".into());
    let out = render::run(&sphere, &NoProgress)?.output;
    let (Pixels::Gray(image), Some(truth)) = (out.pixels, out.surface) else {
        return Err(shadelab::Error::invalid(
            "the sphere is a gray rendered surface",
        ));
    };
    let config = solve::SolveConfig::new("<array>", "0.3,0.4,0.866".parse()?);
    let ms = times_ms(runs, || {
        let run = solve::run_image(
            &config,
            image.clone(),
            Some(truth.mask.clone()),
            &NoProgress,
        )
        .expect("solves");
        std::hint::black_box(run);
    });
    println!("solve_ms {ms}");
    Ok(())
}
