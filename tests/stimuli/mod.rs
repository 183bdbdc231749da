//! The stimulus generator as a vision scientist uses it: golden images of every stimulus, the
//! exact facts the illusions rest on, every output format, the gallery, and bad input.
//!
//! Golden images live in `tests/images/` (16-bit PNG of the picture and its target mask at a
//! reduced size). On a mismatch the test writes the actual image and an amplified difference
//! image under the target's temporary folder; `SHADELAB_BLESS=1 cargo test --test tests
//! stimuli` rewrites the golden files.

mod bad_input;
mod bundles;
mod conventions;
mod display;
mod display_model;
mod face;
mod figures;
mod formats;
mod gallery;
mod golden;
mod illusions;
mod sidecar;

use serde_json::{Map, Value};
use shadelab::stimulus::{self, Output};
use shadelab::SizeRequest;
use std::path::Path;

/// The largest picture the tests make.
const MAX: usize = 1 << 24;

/// Renders `name` with its defaults at a ppd that keeps the longer side near 128 pixels.
fn small(name: &str) -> shadelab::Result<(stimulus::Request, Output)> {
    let info = stimulus::find(name)?.info();
    let (h, w) = info.default_visual_size;
    let ppd = (128.0 / w.max(h)).min(info.default_ppd);
    let size = SizeRequest {
        visual_size: Some((h, w)),
        ppd: Some(ppd),
        shape: None,
    };
    stimulus::generate(name, &Map::new(), &size, 0, MAX)
}
fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn sidecar(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// A value as a 16-bit code.
fn codes(v: f64) -> i64 {
    (v.clamp(0.0, 1.0) * 65535.0).round() as i64
}
