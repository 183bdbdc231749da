//! stimupy's conventions: sizes are (height, width) in specs and sidecars, and one rule for a
//! size in pixels — the whole stimulus scales to fill it.

use super::*;
use crate::cli::{scratch, shadelab};
use shadelab::stimulus::Pixels;
use shadelab::Grid;

#[test]
fn a_spec_gives_stimupys_shape_in_height_width_order() {
    // stimupy: checkerboard(visual_size=(4, 8), ppd=32, check_visual_size=(1, 1)) is 128 × 256.
    let d = scratch("conv-spec");
    std::fs::write(
        d.join("spec.json"),
        r#"{"stimulus": "checkerboard", "params": {"check": 1}, "visual_size": [4, 8], "ppd": 32}"#,
    )
    .unwrap();
    ok(&shadelab(
        &d,
        &["render", "--spec", "spec.json", "--out", "c.png"],
    ));
    let (img, _) = shadelab_io::read_gray(&d.join("c.png"), MAX).unwrap();
    assert_eq!((img.height(), img.width()), (128, 256));
    // 1° checks at 32 ppd: 4 rows and 8 columns of checks.
    let changes = |values: Vec<f64>| values.windows(2).filter(|pair| pair[0] != pair[1]).count();
    assert_eq!(changes((0..256).map(|c| *img.get(c, 5)).collect()), 7);
    assert_eq!(changes((0..128).map(|r| *img.get(5, r)).collect()), 3);
    let meta = sidecar(&d.join("c.json"));
    assert_eq!(meta["visual_size"], serde_json::json!([4.0, 8.0]));
    assert_eq!(meta["shape"], serde_json::json!([128, 256]));
    assert_eq!(meta["ppd"], 32.0);
    // A spec's "shape" is (height, width) too, and the CLI's --size is WxH, width first.
    std::fs::write(
        d.join("shape.json"),
        r#"{"stimulus": "sphere", "shape": [30, 50]}"#,
    )
    .unwrap();
    ok(&shadelab(
        &d,
        &["render", "--spec", "shape.json", "--out", "s.png"],
    ));
    ok(&shadelab(
        &d,
        &["render", "sphere", "--size", "50x30", "--out", "t.png"],
    ));
    for f in ["s.png", "t.png"] {
        let (img, _) = shadelab_io::read_gray(&d.join(f), MAX).unwrap();
        assert_eq!((img.height(), img.width()), (30, 50), "{f}");
    }
}

/// The picture as grey values (the mean of the channels of a colour one).
fn gray(pixels: &Pixels) -> Grid<f64> {
    match pixels {
        Pixels::Gray(img) => img.clone(),
        Pixels::Rgb(img) => img.map(|p| (p[0] + p[1] + p[2]) / 3.0),
    }
}

/// Renders `name` with its defaults at `shape` (height, width) and nothing else: the rule of
/// `--size`.
fn at_shape(name: &str, shape: (usize, usize)) -> shadelab::Result<(stimulus::Request, Output)> {
    let size = SizeRequest {
        shape: Some(shape),
        ..Default::default()
    };
    stimulus::generate(name, &Map::new(), &size, 0, MAX)
}

/// Pixel count and bounding box (left, top, right, bottom; inclusive) of each label 1..=n.
fn label_boxes(labels: &Grid<u16>, n: usize) -> Vec<(usize, [usize; 4])> {
    let mut out = vec![(0, [usize::MAX, usize::MAX, 0, 0]); n];
    for r in 0..labels.height() {
        for c in 0..labels.width() {
            let l = *labels.get(c, r) as usize;
            if (1..=n).contains(&l) {
                let (count, b) = &mut out[l - 1];
                *count += 1;
                *b = [b[0].min(c), b[1].min(r), b[2].max(c), b[3].max(r)];
            }
        }
    }
    out
}

#[test]
fn a_size_in_pixels_scales_every_stimulus_to_fill_it() {
    let (mut checked, mut skipped) = (0, 0);
    for s in shadelab::pipeline::render::list() {
        let info = stimulus::find(s.name).unwrap().info();
        let (h_deg, w_deg) = info.default_visual_size;
        let small_shape = (
            (h_deg * 8.0).round() as usize,
            (w_deg * 8.0).round() as usize,
        );
        let large_shape = (small_shape.0 * 2, small_shape.1 * 2);
        let (Ok((r1, o1)), Ok((r2, o2))) =
            (at_shape(s.name, small_shape), at_shape(s.name, large_shape))
        else {
            // A stimulus that needs a parameter (a mesh or depth-map file) to render at all.
            assert!(
                at_shape(s.name, small_shape).is_err()
                    && stimulus::generate(s.name, &Map::new(), &SizeRequest::default(), 0, MAX)
                        .is_err(),
                "{}: renders by default but not at a shape",
                s.name
            );
            println!(
                "{}: skipped, it renders nothing without a file parameter",
                s.name
            );
            skipped += 1;
            continue;
        };
        let (g1, g2) = (r1.geometry, r2.geometry);
        assert_eq!((g1.height, g1.width), small_shape, "{}", s.name);
        assert_eq!((g2.height, g2.width), large_shape, "{}", s.name);
        // The same degrees at twice the ppd.
        assert!(
            (g2.ppd / g1.ppd - 2.0).abs() < 1e-9,
            "{}: {} vs {}",
            s.name,
            g1.ppd,
            g2.ppd
        );
        assert!((g1.ppd - 8.0).abs() < 0.1, "{}: ppd {}", s.name, g1.ppd);
        // The same picture: the large one averaged over 2 × 2 blocks is the small one, up to
        // edges and antialiasing (the mean difference is small, where a padded picture, a
        // quarter of the frame, differs by a large fraction of its contrast).
        let (a, b) = (gray(&o1.pixels), gray(&o2.pixels));
        let mut diff = 0.0;
        for r in 0..a.height() {
            for c in 0..a.width() {
                let block = (b.get(2 * c, 2 * r)
                    + b.get(2 * c + 1, 2 * r)
                    + b.get(2 * c, 2 * r + 1)
                    + b.get(2 * c + 1, 2 * r + 1))
                    / 4.0;
                diff += (block - a.get(c, r)).abs();
            }
        }
        let mean = diff / (a.width() * a.height()) as f64;
        let (lo, hi) = a.min_max().unwrap();
        assert!(
            mean < 0.08 * (hi - lo).max(0.1),
            "{}: mean difference {mean:.4} (range {lo:.3}..{hi:.3})",
            s.name
        );
        // Each target covers four times the pixels, and its box scales by two.
        if let (Some(t1), Some(t2)) = (&o1.targets, &o2.targets) {
            assert_eq!(t1.names, t2.names, "{}", s.name);
            let n = t1.names.len();
            for (i, ((n1, b1), (n2, b2))) in label_boxes(&t1.labels, n)
                .into_iter()
                .zip(label_boxes(&t2.labels, n))
                .enumerate()
            {
                if n1 < 12 {
                    continue; // too small at 8 ppd to measure
                }
                let ratio = n2 as f64 / n1 as f64;
                assert!(
                    (ratio - 4.0).abs() < 0.6,
                    "{} target {}: {n1} px then {n2} px",
                    s.name,
                    t1.names[i]
                );
                for k in 0..4 {
                    let expect = 2.0 * b1[k] as f64 + if k >= 2 { 1.0 } else { 0.0 };
                    assert!(
                        (b2[k] as f64 - expect).abs() <= 3.0,
                        "{} target {}: box {b1:?} then {b2:?}",
                        s.name,
                        t1.names[i]
                    );
                }
            }
        }
        checked += 1;
    }
    assert!(
        skipped <= 2 && checked >= 18,
        "{checked} stimuli checked, {skipped} skipped"
    );
}

#[test]
fn another_aspect_fits_the_stimulus_and_centres_it() {
    // bumps is 14° × 10° (width × height) by default; a square of 140 pixels fits the width
    // at 10 ppd and adds 2° of field above and below.
    let (request, out) = at_shape("bumps", (140, 140)).unwrap();
    assert_eq!(request.geometry.ppd, 10.0);
    let (fitted, scaled) = (
        gray(&out.pixels),
        gray(&at_shape("bumps", (100, 140)).unwrap().1.pixels),
    );
    let mut diff = 0.0;
    for r in 0..100 {
        for c in 0..140 {
            diff += (fitted.get(c, r + 20) - scaled.get(c, r)).abs();
        }
    }
    assert!(
        diff / (140.0 * 100.0) < 0.01,
        "mean difference {}",
        diff / 14000.0
    );
    // With a ppd given, a size in pixels is more field at that scale instead.
    let size = SizeRequest {
        ppd: Some(5.0),
        shape: Some((140, 140)),
        ..Default::default()
    };
    let (request, _) = stimulus::generate("bumps", &Map::new(), &size, 0, MAX).unwrap();
    assert_eq!(
        (request.geometry.height_deg(), request.geometry.width_deg()),
        (28.0, 28.0)
    );
}

#[test]
fn a_sidecar_in_the_old_form_still_renders_and_size_rescales_a_sidecar() {
    let d = scratch("conv-old-sidecar");
    ok(&shadelab(
        &d,
        &["--quiet", "render", "bumps", "--ppd", "6", "--out", "b.png"],
    ));
    let mut old = sidecar(&d.join("b.json"));
    let shape = old["shape"].clone();
    let map = old.as_object_mut().unwrap();
    map.remove("shape");
    map.remove("visual_size");
    map.insert(
        "shape_px".into(),
        serde_json::json!({"width": shape[1], "height": shape[0]}),
    );
    std::fs::create_dir_all(d.join("old")).unwrap();
    std::fs::write(d.join("old/b.json"), old.to_string()).unwrap();
    ok(&shadelab(
        &d,
        &[
            "--quiet",
            "render",
            "--spec",
            "old/b.json",
            "--out",
            "again.png",
        ],
    ));
    assert_eq!(
        std::fs::read(d.join("b.png")).unwrap(),
        std::fs::read(d.join("again.png")).unwrap()
    );
    // --size beside a sidecar scales what it recorded: twice the pixels, twice the ppd.
    ok(&shadelab(
        &d,
        &[
            "--quiet", "render", "--spec", "b.json", "--size", "168x120", "--out", "big.png",
        ],
    ));
    let big = sidecar(&d.join("big.json"));
    assert_eq!(big["ppd"], 12.0);
    assert_eq!(big["shape"], serde_json::json!([120, 168]));
}

#[test]
fn a_visual_size_is_rounded_down_to_whole_pixels_as_stimupy_and_said() {
    // stimupy 1.2: 3.3° × 31.7 ppd = 104.61 px → 104, 5.1° → 161.67 → 161; the visual size
    // becomes 104 / 31.7 = 3.281°, with a warning.
    let d = scratch("conv-rounding");
    let out = shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--visual-size",
            "5.1x3.3",
            "--ppd",
            "31.7",
            "--out",
            "c.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("warning: checkerboard: visual size 3.3° high × 5.1° wide at 31.7 ppd is 104 px high × 161 px wide, rounded down"),
        "{err}"
    );
    let side: Value = serde_json::from_slice(&std::fs::read(d.join("c.json")).unwrap()).unwrap();
    assert_eq!(side["shape"], serde_json::json!([104, 161]));
    assert_eq!(
        side["notes"]["visual_size_rounded"]["asked_visual_size"],
        serde_json::json!([3.3, 5.1])
    );
    // A whole number of pixels: no warning, no note.
    let out = shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--visual-size",
            "6x4",
            "--ppd",
            "10",
            "--out",
            "w.png",
        ],
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let side: Value = serde_json::from_slice(&std::fs::read(d.join("w.json")).unwrap()).unwrap();
    assert!(side["notes"].get("visual_size_rounded").is_none());
    // 0.29° × 100 ppd is 29 px (28.999999999999996 before the product is rounded to 10 decimals).
    assert_eq!(shadelab_core::visual_size::whole_pixels(0.29, 100.0), 29.0);
    assert_eq!(shadelab_core::visual_size::whole_pixels(3.3, 31.7), 104.0);
}

#[test]
fn sizes_in_messages_name_their_axes_and_a_visual_size_stays_under_180_degrees() {
    let d = scratch("conv-size-words");
    // --visual-size is width first: 10° wide, 14° high; the 3 × 4 discs need 11° across.
    let out = shadelab(
        &d,
        &[
            "render",
            "bumps",
            "--visual-size",
            "10x14",
            "--out",
            "b.png",
        ],
    );
    crate::cli::assert_error(
        &out,
        2,
        "bumps: 3 rows × 4 columns of discs need 8.0° high × 11.0° wide but the frame is 14.0° high × 10.0° wide",
    );
    // 100000 × 1 pixels fitted to the default 8° × 8° would be 800,000° wide.
    let out = shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--size",
            "100000x1",
            "--out",
            "c.png",
        ],
    );
    crate::cli::assert_error(
        &out,
        2,
        "1 px high × 100000 px wide at 0.125 ppd (the ppd that fits the stimulus's default visual size to the shape) is 8.0° high × 800000.0° wide: over 180°",
    );
    assert!(crate::cli::files_in(&d).is_empty());
}

#[test]
fn a_check_that_is_no_whole_number_of_pixels_is_rounded_as_stimupy_rounds_it() {
    // stimupy 1.2: 0.75° at 10 ppd is round(7.5) = 8 px (half to even), 0.8°, with a warning.
    let d = scratch("conv-check-rounding");
    let out = shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--visual-size",
            "6x4",
            "--ppd",
            "10",
            "--set",
            "check=0.75",
            "--out",
            "c.png",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("warning: checkerboard: check 0.75° at 10 ppd is 8 px, rounded to whole pixels as stimupy does: 0.8000°"),
        "{err}"
    );
    let side: Value = serde_json::from_slice(&std::fs::read(d.join("c.json")).unwrap()).unwrap();
    assert_eq!(side["notes"]["check_rounded"]["check_px"], 8.0);
    let (img, _) = shadelab_io::read_gray(&d.join("c.png"), 1 << 20).unwrap();
    // Row 0: 8 dark columns, 8 light, 8 dark … (not 7.5).
    let top: Vec<f64> = (0..60).map(|c| *img.get(c, 0)).collect();
    for (c, v) in top.iter().enumerate() {
        let expect = if (c / 8) % 2 == 0 { 0.0 } else { 1.0 };
        assert_eq!(*v, expect, "column {c}");
    }
    // A whole number of pixels: no warning, no note.
    let out = shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--visual-size",
            "6x4",
            "--ppd",
            "10",
            "--set",
            "check=0.8",
            "--out",
            "w.png",
        ],
    );
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    let side: Value = serde_json::from_slice(&std::fs::read(d.join("w.json")).unwrap()).unwrap();
    assert!(side["notes"].get("check_rounded").is_none());
}
