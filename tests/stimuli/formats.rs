//! Sizes and every output format: PNG, .npy, .mat, .svg, sidecars and surface layers.

use super::*;
use crate::cli::{assert_error, scratch, shadelab};
use serde_json::Map;
use shadelab::stimulus::{self, ExportOptions, Pixels};
use shadelab::SizeRequest;
use shadelab_io as io;
use shadelab_stimuli::mat;
use std::collections::BTreeSet;
use std::path::Path;

#[test]
fn degrees_times_ppd_is_pixels() {
    let d = scratch("stim-degrees");
    ok(&shadelab(
        &d,
        &[
            "render",
            "circles-gradient",
            "--visual-size",
            "12x8",
            "--ppd",
            "25",
            "--set",
            "radius=1",
            "--set",
            "spacing=3",
            "--set",
            "rows=2",
            "--set",
            "columns=3",
            "--out",
            "c.png",
        ],
    ));
    let (img, _) = io::read_gray(&d.join("c.png"), MAX).unwrap();
    assert_eq!((img.width(), img.height()), (300, 200));
    let meta = sidecar(&d.join("c.json"));
    // stimupy's order: [height, width].
    assert_eq!(meta["visual_size"], serde_json::json!([8.0, 12.0]));
    assert_eq!(meta["shape"], serde_json::json!([200, 300]));
    assert_eq!(meta["ppd"], 25.0);
    let centres = meta["notes"]["centres_px"].as_array().unwrap();
    let x = |i: usize| centres[i][0].as_f64().unwrap();
    let y = |i: usize| centres[i][1].as_f64().unwrap();
    // 3° × 25 ppd = 75 px apart, to within the half pixel of snapping to the lattice.
    assert!((x(1) - x(0) - 75.0).abs() <= 1.0 && (y(3) - y(0) - 75.0).abs() <= 1.0);
    // Each circle covers π (1° × 25)² pixels.
    let labels = io::read_labels(&d.join("c_mask.png"), MAX).unwrap();
    let area = labels.data().iter().filter(|&&l| l == 1).count() as f64;
    let expect = std::f64::consts::PI * 25.0 * 25.0;
    assert!((area - expect).abs() / expect < 0.01, "{area} vs {expect}");
    // Checks of 0.5° at 30 ppd are 15 px.
    ok(&shadelab(
        &d,
        &[
            "render",
            "checkerboard",
            "--set",
            "check=0.5",
            "--ppd",
            "30",
            "--visual-size",
            "6",
            "--out",
            "k.png",
        ],
    ));
    let (k, _) = io::read_gray(&d.join("k.png"), MAX).unwrap();
    assert_eq!(k.width(), 180);
    let changes = (1..180)
        .filter(|&c| k.get(c, 0) != k.get(c - 1, 0))
        .collect::<Vec<_>>();
    assert_eq!(changes, (1..12).map(|i| i * 15).collect::<Vec<_>>());
}

#[test]
fn every_format_is_bit_identical_on_rerun() {
    let d = scratch("stim-rerun");
    for ext in ["png", "npy", "mat", "npz", "svg"] {
        let render = |seed: &str, file: &str| {
            let args = [
                "render",
                "circles-binary",
                "--set",
                "layout=random",
                "--seed",
                seed,
                "--out",
                file,
            ];
            ok(&shadelab(&d, &args));
            (
                std::fs::read(d.join(file)).unwrap(),
                std::fs::read(io::sibling(&d.join(file), "", "json")).unwrap(),
            )
        };
        let first = render("12", &format!("r.{ext}"));
        assert_eq!(first, render("12", &format!("r.{ext}")), "{ext}");
        let other = render("13", &format!("o.{ext}"));
        assert_ne!(first.0, other.0, "{ext}: the seed matters");
    }
}

#[test]
fn mat_files_hold_the_image_as_doubles_column_major() {
    let d = scratch("stim-mat");
    ok(&shadelab(
        &d,
        &[
            "render", "strips", "--size", "40x30", "--ppd", "4", "--out", "s.mat",
        ],
    ));
    ok(&shadelab(
        &d,
        &[
            "render", "strips", "--size", "40x30", "--ppd", "4", "--range", "psychopy", "--out",
            "p.mat",
        ],
    ));
    ok(&shadelab(
        &d,
        &["render", "fading-disk", "--size", "20x10", "--out", "f.mat"],
    ));
    let (_, out) = stimulus::generate(
        "strips",
        &Map::new(),
        &SizeRequest {
            shape: Some((30, 40)),
            ppd: Some(4.0),
            ..Default::default()
        },
        0,
        MAX,
    )
    .unwrap();
    let Pixels::Gray(img) = out.pixels else {
        panic!()
    };
    let a = mat::decode(&std::fs::read(d.join("s.mat")).unwrap()).unwrap();
    assert_eq!(
        a.name, "img",
        "stimupy's name for the picture, the bundle's first field"
    );
    assert_eq!(a.dims, [30, 40]);
    for r in 0..30 {
        for c in 0..40 {
            assert_eq!(a.data[r + 30 * c], *img.get(c, r));
        }
    }
    let p = mat::decode(&std::fs::read(d.join("p.mat")).unwrap()).unwrap();
    assert!(p.data.iter().zip(&a.data).all(|(p, a)| *p == a * 2.0 - 1.0));
    assert_eq!(sidecar(&d.join("p.json"))["range"], "-1..1");
    let f = mat::decode(&std::fs::read(d.join("f.mat")).unwrap()).unwrap();
    assert_eq!(f.dims, [10, 20, 3]);
}

/// Counts the elements of each tag name in an SVG document, via the svg crate's parser.
fn svg_tags(path: &Path) -> std::collections::BTreeMap<String, usize> {
    let mut content = String::new();
    let mut counts = std::collections::BTreeMap::new();
    for event in svg::open(path, &mut content).unwrap() {
        match event {
            svg::parser::Event::Tag(name, kind, _)
                if kind != svg::node::element::tag::Type::End =>
            {
                *counts.entry(name.to_string()).or_insert(0) += 1;
            }
            svg::parser::Event::Error(e) => panic!("{}: {e:?}", path.display()),
            _ => {}
        }
    }
    counts
}

#[test]
fn svg_output_parses_back_with_the_expected_elements() {
    let d = scratch("stim-svg");
    let run = |args: &[&str]| ok(&shadelab(&d, args));
    run(&[
        "render",
        "circles-binary",
        "--set",
        "rows=3",
        "--set",
        "columns=5",
        "--out",
        "b.svg",
    ]);
    run(&[
        "render",
        "circles-gradient",
        "--set",
        "rows=2",
        "--set",
        "columns=3",
        "--out",
        "g.svg",
    ]);
    run(&["render", "strips", "--set", "strips=4", "--out", "s.svg"]);
    run(&[
        "render",
        "boundary-strips",
        "--set",
        "boundary=sawtooth,arched",
        "--out",
        "bs.svg",
    ]);
    run(&[
        "render",
        "checkerboard",
        "--set",
        "check=2",
        "--out",
        "k.svg",
    ]);
    run(&["render", "disc", "--out", "d.svg"]);
    let b = svg_tags(&d.join("b.svg"));
    assert_eq!(b["svg"], 1);
    assert_eq!(b["path"], 2 * 15, "two half discs per circle");
    let g = svg_tags(&d.join("g.svg"));
    assert_eq!((g["circle"], g["linearGradient"]), (6, 2));
    let s = svg_tags(&d.join("s.svg"));
    assert_eq!(s["rect"], 1 + 4, "background and four strips");
    let bs = svg_tags(&d.join("bs.svg"));
    assert_eq!(bs["path"], 2);
    let k = svg_tags(&d.join("k.svg"));
    assert_eq!(
        k["rect"],
        1 + 8,
        "background and the 8 second-colour checks of a 4x4 board"
    );
    assert_eq!(svg_tags(&d.join("d.svg"))["circle"], 1);
    // The document's size is the raster's.
    let text = std::fs::read_to_string(d.join("d.svg")).unwrap();
    assert!(text.contains("width=\"256\"") && text.contains("viewBox=\"0 0 256 256\""));
    // A stimulus that is not vector by nature refuses .svg, and writes nothing.
    let out = shadelab(&d, &["render", "hollow-mask", "--out", "h.svg"]);
    assert_error(&out, 2, "no vector form");
    assert!(
        !d.join("h.svg").exists() && !d.join("h.json").exists() && !d.join("h_mask.png").exists()
    );
}

#[test]
fn the_sidecar_holds_every_parameter_of_every_stimulus() {
    let d = scratch("stim-sidecar");
    for name in stimulus::names() {
        let Ok((request, out)) = small(name) else {
            continue;
        };
        let path = d.join(format!("{name}.npy"));
        stimulus::write_output(
            name,
            &request,
            &out,
            &path,
            &ExportOptions::default(),
            false,
            None,
        )
        .unwrap();
        let meta = sidecar(&d.join(format!("{name}.json")));
        let info = stimulus::find(name).unwrap().info();
        let keys: BTreeSet<&str> = meta["parameters"]
            .as_object()
            .unwrap()
            .keys()
            .map(|k| k.as_str())
            .collect();
        let declared: BTreeSet<&str> = info.params.iter().map(|p| p.name).collect();
        assert_eq!(keys, declared, "{name}");
        assert_eq!(meta["stimulus"], name);
        assert_eq!(meta["seed"], 0);
        assert_eq!(meta["md5_float64_rounded8"].as_str().unwrap().len(), 32);
        if let Some(t) = &out.targets {
            assert_eq!(
                meta["targets"].as_array().unwrap().len(),
                t.names.len(),
                "{name}"
            );
        }
    }
    // A set value is recorded as given.
    ok(&shadelab(
        &d,
        &[
            "render",
            "bumps",
            "--set",
            "radius=0.9",
            "--set",
            "pattern=rows",
            "--out",
            "b.png",
        ],
    ));
    let meta = sidecar(&d.join("b.json"));
    assert_eq!(meta["parameters"]["radius"], 0.9);
    assert_eq!(meta["parameters"]["pattern"], "rows");
    assert_eq!(meta["parameters"]["light"], "tilt=0,slant=45");
}

#[test]
fn stimuli_that_render_a_surface_write_their_layers() {
    let d = scratch("stim-layers");
    for name in ["bumps", "crater", "sideways", "hollow-mask"] {
        ok(&shadelab(
            &d,
            &[
                "render",
                name,
                "--ppd",
                "10",
                "--layers",
                "--out",
                &format!("{name}.png"),
            ],
        ));
        let depth = io::read_image(&d.join(format!("{name}_depth.npy")), MAX).unwrap();
        let normals = io::read_normals(&d.join(format!("{name}_normals.npy")), MAX).unwrap();
        assert!(
            depth.min_max().unwrap().1 > 0.0 || depth.min_max().unwrap().0 < 0.0,
            "{name}"
        );
        assert!(
            normals
                .data()
                .iter()
                .all(|n| (n.norm() - 1.0).abs() < 1e-5 && n.z > 0.0),
            "{name}"
        );
        assert!(d.join(format!("{name}_shading.npy")).exists());
    }
}
