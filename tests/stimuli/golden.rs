//! Golden images of every stimulus, and rendering that repeats exactly.

use super::*;
use shadelab::stimulus::{self, Output, Pixels};
use shadelab::Grid;
use shadelab::SizeRequest;
use shadelab_io::{self as io, BitDepth};
use std::path::{Path, PathBuf};

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/images")
}

/// The picture as channels of 16-bit codes (1 or 3 per pixel).
fn picture_codes(p: &Pixels) -> (usize, usize, Vec<i64>) {
    match p {
        Pixels::Gray(g) => (
            g.width(),
            g.height(),
            g.data().iter().map(|&v| codes(v)).collect(),
        ),
        Pixels::Rgb(c) => (
            c.width(),
            c.height(),
            c.data().iter().flat_map(|px| px.map(codes)).collect(),
        ),
    }
}

fn write_picture(path: &Path, p: &Pixels) {
    match p {
        Pixels::Gray(g) => io::write_gray(path, g, BitDepth::Sixteen, None).unwrap(),
        Pixels::Rgb(c) => io::write_rgb(path, c, BitDepth::Sixteen, None).unwrap(),
    }
}

/// Compares one stimulus with its golden files; returns a description of any mismatch.
fn check_golden(name: &str, out: &Output, bless: bool) -> Option<String> {
    let dir = golden_dir();
    let image_path = dir.join(format!("{name}.png"));
    let mask_path = dir.join(format!("{name}_mask.png"));
    if bless {
        std::fs::create_dir_all(&dir).unwrap();
        write_picture(&image_path, &out.pixels);
        match &out.targets {
            Some(t) => io::write_labels(&mask_path, &t.labels).unwrap(),
            None => {
                let _ = std::fs::remove_file(&mask_path);
            }
        }
        return None;
    }
    if !image_path.exists() {
        return Some(format!(
            "{name}: no golden image {} (run with SHADELAB_BLESS=1 to create it)",
            image_path.display()
        ));
    }
    let (w, h, actual) = picture_codes(&out.pixels);
    let expected: Vec<i64> = match &out.pixels {
        Pixels::Gray(_) => io::read_gray(&image_path, MAX)
            .unwrap()
            .0
            .data()
            .iter()
            .map(|&v| codes(v))
            .collect(),
        Pixels::Rgb(_) => io::read_rgb(&image_path, MAX)
            .unwrap()
            .data()
            .iter()
            .flat_map(|px| px.map(codes))
            .collect(),
    };
    let mut problems = Vec::new();
    if expected.len() != actual.len() {
        problems.push(format!("size differs from the golden image ({w}x{h} now)"));
    } else {
        // One code (1/65535) of slack absorbs last-bit differences of libm across platforms.
        let worst = actual
            .iter()
            .zip(&expected)
            .map(|(a, b)| (a - b).abs())
            .max()
            .unwrap_or(0);
        if worst > 1 {
            let channels = actual.len() / (w * h);
            let diff = Grid::from_fn(w, h, |c, r| {
                let i = (r * w + c) * channels;
                let d = (0..channels)
                    .map(|k| (actual[i + k] - expected[i + k]).abs())
                    .max()
                    .unwrap_or(0);
                (d as f64 / 65535.0 * 50.0).min(1.0)
            });
            let tmp = Path::new(env!("CARGO_TARGET_TMPDIR")).join("golden");
            std::fs::create_dir_all(&tmp).unwrap();
            write_picture(&tmp.join(format!("{name}_actual.png")), &out.pixels);
            io::write_gray(
                &tmp.join(format!("{name}_diff.png")),
                &diff,
                BitDepth::Eight,
                None,
            )
            .unwrap();
            problems.push(format!(
                "pixels differ by up to {worst} codes; see {}",
                tmp.join(format!("{name}_diff.png")).display()
            ));
        }
    }
    match (&out.targets, mask_path.exists()) {
        (Some(t), true) => {
            if io::read_labels(&mask_path, MAX).unwrap() != t.labels {
                problems.push("target mask differs".into());
            }
        }
        (Some(_), false) => problems.push("no golden mask".into()),
        (None, true) => problems.push("golden mask exists but the stimulus has no targets".into()),
        (None, false) => {}
    }
    (!problems.is_empty()).then(|| format!("{name}: {}", problems.join("; ")))
}

#[test]
fn every_stimulus_matches_its_golden_image() {
    let bless = std::env::var("SHADELAB_BLESS").is_ok_and(|v| v == "1");
    let mut failures = Vec::new();
    let mut checked = Vec::new();
    for name in stimulus::names() {
        // Stimuli that need a file (a depth map, a mesh) have no defaults to render.
        let Ok((_, out)) = small(name) else {
            eprintln!("golden: {name} does not render from defaults alone; skipped");
            continue;
        };
        checked.push(name);
        failures.extend(check_golden(name, &out, bless));
    }
    for must in [
        "bumps",
        "crater",
        "sideways",
        "strips",
        "circles-binary",
        "circles-gradient",
        "boundary-strips",
        "hollow-mask",
        "checker-shadow",
        "fading-disk",
        "checkerboard",
        "disc",
        "sphere",
        "vase",
    ] {
        assert!(checked.contains(&must), "{must} was not checked");
    }
    assert!(
        failures.is_empty(),
        "golden images:\n{}",
        failures.join("\n")
    );
}

#[test]
fn rendering_twice_gives_the_same_output_and_the_seed_matters() {
    let given = shadelab::Params::parse_pairs(&["layout=random", "odd_one_out=true"]).unwrap();
    let size = SizeRequest::default();
    let a = stimulus::generate("circles-gradient", &given, &size, 9, MAX)
        .unwrap()
        .1;
    let b = stimulus::generate("circles-gradient", &given, &size, 9, MAX)
        .unwrap()
        .1;
    let c = stimulus::generate("circles-gradient", &given, &size, 10, MAX)
        .unwrap()
        .1;
    assert_eq!(a, b);
    assert_ne!(a.pixels, c.pixels);
}
