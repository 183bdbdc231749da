//! Figures a reviewer accepts: grouped legends beside the data, full 0–360° tilt axes, units,
//! colour bars, target outlines with names, the fading time course, the labelled reflectance
//! map and the captioned gallery sheet (issue 14, item 6). Pixel facts where the figure is a
//! PNG, text facts where it is an SVG.
#![cfg(feature = "plots")]

use crate::cli::{scratch, shadelab};
use std::path::Path;

fn ok(dir: &Path, args: &[&str]) {
    let out = shadelab(dir, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn rgb(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}

#[test]
fn a_sweep_over_the_circle_runs_0_to_360_with_units_and_a_grouped_legend() {
    let d = scratch("fig-sweep");
    ok(
        &d,
        &[
            "analyze",
            "prior-sweep",
            "--stimulus",
            "bumps",
            "--set",
            "rows=3",
            "--set",
            "columns=4",
            "--ppd",
            "8",
            "--tilts",
            "0:360:90",
            "--out",
            "sweep",
        ],
    );
    let svg = std::fs::read_to_string(d.join("sweep/sweep.svg")).unwrap();
    // Twelve tokens: one legend entry per class with its count, not twelve names (or none).
    let csv = std::fs::read_to_string(d.join("sweep/sweep.csv")).unwrap();
    let count = |class: &str| {
        let names: std::collections::BTreeSet<&str> = csv
            .lines()
            .skip(1)
            .filter_map(|l| l.split(',').nth(1))
            .filter(|n| n.starts_with(class))
            .collect();
        names.len()
    };
    assert_eq!(count("bump") + count("dimple"), 12);
    assert!(
        svg.contains(&format!("bumps (n={})", count("bump"))),
        "grouped legend"
    );
    assert!(
        svg.contains(&format!("dimples (n={})", count("dimple"))),
        "grouped legend"
    );
    assert!(
        !svg.contains("bump r1c1"),
        "tokens are grouped, not named one by one"
    );
    // The tilt axis closes the circle and says its unit; the residual axis has one.
    assert!(
        svg.contains(">\n360\n<") && svg.contains(">\n270\n<"),
        "ticks to 360"
    );
    assert!(svg.contains("assumed light tilt (°"));
    assert!(svg.contains("surface residual e_Z (Σ squared error, luminance²)"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn fading_writes_a_time_course_plot_in_seconds() {
    let d = scratch("fig-fading");
    ok(
        &d,
        &[
            "analyze",
            "fading",
            "--stimulus",
            "fading-disk",
            "--ppd",
            "12",
            "--duration",
            "2",
            "--out",
            "fading",
        ],
    );
    let csv = std::fs::read_to_string(d.join("fading/time_course.csv")).unwrap();
    assert!(csv.starts_with("time_s,blurred,sharp"), "time column first");
    let png = rgb(&d.join("fading/time_course.png"));
    assert_eq!(png.dimensions(), (900, 540));
    // Both disks' curves are drawn in their colours.
    let count = |c: [u8; 3]| png.pixels().filter(|p| p.0 == c).count();
    assert!(count([0, 114, 178]) > 200 && count([213, 94, 0]) > 200);
    let svg = std::fs::read_to_string(d.join("fading/time_course.svg")).unwrap();
    assert!(svg.contains("time since stimulus onset (s)"));
    assert!(svg.contains("blurred disk") && svg.contains("sharp disk"));
    assert!(svg.contains(">\n2.0\n<"), "ticks reach the 2 s end");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_lightness_figure_has_a_colour_bar_and_outlines_a_and_b() {
    let d = scratch("fig-lightness");
    ok(
        &d,
        &[
            "analyze",
            "lightness",
            "--stimulus",
            "checker-shadow",
            "--ppd",
            "12",
            "--model",
            "retinex",
            "--out",
            "light",
        ],
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("light/lightness.json")).unwrap()).unwrap();
    assert_eq!(report["outputs"][0]["figure"], "lightness_figure.png");
    let png = rgb(&d.join("light/lightness_figure.png"));
    assert_eq!(png.dimensions(), (900, 720));
    // The outlines of A and B in red.
    let red = png.pixels().filter(|p| p.0 == [255, 40, 40]).count();
    assert!(red > 100, "outlines drawn: {red}");
    // A gray colour bar: a column whose top is white and bottom black, grays between.
    let (w, h) = png.dimensions();
    let bar = (w / 2..w).find(|&x| {
        (0..h).any(|y| png.get_pixel(x, y).0 == [255; 3])
            && (0..h).any(|y| png.get_pixel(x, y).0 == [0; 3])
            && (0..h)
                .filter(|&y| {
                    let p = png.get_pixel(x, y).0;
                    p[0] == p[1] && p[1] == p[2] && (100..156).contains(&p[0])
                })
                .count()
                > 20
    });
    assert!(
        bar.is_some(),
        "a black-to-white colour bar right of the map"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_reflectance_map_figure_has_axes_and_a_colour_bar_at_the_requested_size() {
    let d = scratch("fig-rmap");
    ok(
        &d,
        &[
            "render",
            "reflectance-map",
            "--size",
            "800x600",
            "--set",
            "figure=true",
            "--bit-depth",
            "8",
            "--out",
            "rm.png",
        ],
    );
    ok(
        &d,
        &[
            "render",
            "reflectance-map",
            "--size",
            "800x600",
            "--bit-depth",
            "8",
            "--out",
            "plain.png",
        ],
    );
    let fig = rgb(&d.join("rm.png"));
    assert_eq!(fig.dimensions(), (800, 600));
    // White margins around the map (the plain map fills the picture), dark axis text, and the
    // bar's top: viridis's yellow end as sRGB (253, 231, 37).
    assert_eq!(fig.get_pixel(2, 2).0, [255; 3]);
    let dark = fig.pixels().filter(|p| p.0.iter().all(|&v| v < 60)).count();
    assert!(dark > 500, "text and axes: {dark}");
    let yellow = fig
        .pixels()
        .filter(|p| p.0[0] > 245 && p.0[1] > 220 && p.0[2] < 60)
        .count();
    assert!(yellow >= 20, "the colour bar's top: {yellow}");
    let plain = rgb(&d.join("plain.png"));
    assert_ne!(
        plain.get_pixel(2, 2).0,
        [255; 3],
        "the plain map fills its picture"
    );
    let sidecar = std::fs::read_to_string(d.join("rm.json")).unwrap();
    assert!(sidecar.contains("\"figure\""));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_gallery_sheet_has_a_caption_under_each_stimulus() {
    let d = scratch("fig-gallery");
    ok(&d, &["gallery", "--out", "g"]);
    let sheet = rgb(&d.join("g/gallery.png"));
    let presets = shadelab_stimuli::gallery::builtin_presets().unwrap();
    let (thumb, gap, caption) = (shadelab_stimuli::gallery::THUMBNAIL as u32, 12, 44);
    let rows = presets.len().div_ceil(4) as u32;
    assert_eq!(sheet.height(), rows * (thumb + caption + gap) + gap);
    // Under every thumbnail, in its caption band, dark text.
    for i in 0..presets.len() as u32 {
        let x0 = gap + (i % 4) * (thumb + gap);
        let y0 = gap + (i / 4) * (thumb + caption + gap) + thumb + 2;
        let dark = (y0..y0 + caption)
            .flat_map(|y| (x0..x0 + thumb).map(move |x| (x, y)))
            .filter(|&(x, y)| sheet.get_pixel(x, y).0.iter().all(|&v| v < 90))
            .count();
        assert!(dark > 40, "caption of {}: {dark}", presets[i as usize].name);
    }
    let _ = std::fs::remove_dir_all(&d);
}
