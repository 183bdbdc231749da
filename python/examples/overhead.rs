//! The library calls that `shadelab.render` and `shadelab.solve` make, timed in Rust alone, for
//! the Python overhead figures of docs/performance.md (`python/benches/overhead.py` runs this
//! and the same calls from Python, and prints both).
//!
//! `CARGO_TARGET_DIR=../target/python cargo run --release --example overhead` in `python/`
//! prints `render_ms <median>` and `solve_ms <median>`.

use shadelab::pipeline::{render, solve};
use shadelab::{NoProgress, Pixels};
use std::time::Instant;

fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    f(); // warm up
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

fn main() -> Result<(), shadelab::Error> {
    let runs: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(21);
    let mut board = render::RenderConfig::new("checkerboard", "<array>");
    board.size.shape = Some((1024, 1024));
    board.size.ppd = Some(32.0);
    let ms = median_ms(runs, || {
        std::hint::black_box(render::run(&board, &NoProgress).expect("renders"));
    });
    println!("render_ms {ms:.4}");

    let mut sphere = render::RenderConfig::new("sphere", "<array>");
    sphere.size.shape = Some((256, 256));
    sphere.params.insert("light".into(), "0.3,0.4,0.866".into());
    let out = render::run(&sphere, &NoProgress)?.output;
    let (Pixels::Gray(image), Some(truth)) = (out.pixels, out.surface) else {
        return Err(shadelab::Error::invalid(
            "the sphere is a gray rendered surface",
        ));
    };
    let config = solve::SolveConfig::new("<array>", "0.3,0.4,0.866".parse()?);
    let ms = median_ms(runs, || {
        let run = solve::run_image(
            &config,
            image.clone(),
            Some(truth.mask.clone()),
            &NoProgress,
        )
        .expect("solves");
        std::hint::black_box(run);
    });
    println!("solve_ms {ms:.4}");
    Ok(())
}
