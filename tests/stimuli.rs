//! The stimulus generator as a vision scientist uses it: golden images of every stimulus, the
//! exact facts the illusions rest on, every output format, the gallery, and bad input.
//!
//! Golden images live in `tests/images/` (16-bit PNG of the picture and its target mask at a
//! reduced size). On a mismatch the test writes the actual image and an amplified difference
//! image under the target's temporary folder; `SHADELAB_BLESS=1 cargo test --test tests
//! stimuli` rewrites the golden files.

use crate::cli::{assert_error, scratch, shadelab};
use serde_json::{Map, Value};
use shadelab::io::{self, BitDepth};
use shadelab::stimulus::{self, mat, ExportOptions, Output, Pixels};
use shadelab::visual_size::SizeRequest;
use shadelab::{Grid, Image};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const MAX: usize = 1 << 24;

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/images")
}

/// Renders `name` with its defaults at a ppd that keeps the longer side near 128 pixels.
fn small(name: &str) -> shadelab::Result<(stimulus::Request, Output)> {
    let info = stimulus::find(name)?.info();
    let (w, h) = info.default_visual_size;
    let ppd = (128.0 / w.max(h)).min(info.default_ppd);
    let size = SizeRequest {
        visual_size: Some(info.default_visual_size),
        ppd: Some(ppd),
        shape: None,
    };
    stimulus::generate(name, &Map::new(), &size, 0, MAX)
}

fn codes(v: f64) -> i64 {
    (v.clamp(0.0, 1.0) * 65535.0).round() as i64
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
    let given =
        shadelab::params::Params::parse_pairs(&["layout=random", "odd_one_out=true"]).unwrap();
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

fn labels_and_values(img: &Image, labels: &shadelab::Labels, label: u16) -> Vec<f64> {
    img.data()
        .iter()
        .zip(labels.data())
        .filter(|(_, &l)| l == label)
        .map(|(&v, _)| v)
        .collect()
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

#[test]
fn checker_shadow_squares_a_and_b_share_one_value_in_the_file() {
    let d = scratch("stim-checker");
    ok(&shadelab(
        &d,
        &["render", "checker-shadow", "--out", "c.png"],
    ));
    let (img, info) = io::read_gray(&d.join("c.png"), MAX).unwrap();
    assert_eq!(info.bit_depth, 16);
    let labels = io::read_labels(&d.join("c_mask.png"), MAX).unwrap();
    let meta = sidecar(&d.join("c.json"));
    assert_eq!(meta["targets"][0]["name"], "A");
    assert_eq!(meta["targets"][1]["name"], "B");
    let (a, b) = (
        labels_and_values(&img, &labels, 1),
        labels_and_values(&img, &labels, 2),
    );
    assert!(a.len() > 300 && b.len() > 300);
    let first = a[0];
    assert!(a.iter().chain(&b).all(|&v| v == first), "A and B differ");
    assert_eq!(
        codes(meta["notes"]["a_and_b_value"].as_f64().unwrap()),
        codes(first)
    );
}

#[test]
fn crater_rotation_180_is_the_exact_pixel_rotation() {
    let d = scratch("stim-crater");
    ok(&shadelab(&d, &["render", "crater", "--out", "up.npy"]));
    ok(&shadelab(
        &d,
        &[
            "render",
            "crater",
            "--set",
            "rotation=180",
            "--out",
            "down.npy",
        ],
    ));
    let up = io::read_image(&d.join("up.npy"), MAX).unwrap();
    let down = io::read_image(&d.join("down.npy"), MAX).unwrap();
    assert_eq!(up.rotated_180(), down);
    assert_ne!(up, down);
    let (mu, md) = (
        io::read_labels(&d.join("up_mask.png"), MAX).unwrap(),
        io::read_labels(&d.join("down_mask.png"), MAX).unwrap(),
    );
    let mut rotated = mu.data().to_vec();
    rotated.reverse();
    assert_eq!(rotated, md.data());
}

#[test]
fn bumps_lit_from_above_are_brighter_on_top_and_dimples_below() {
    let d = scratch("stim-bumps");
    ok(&shadelab(
        &d,
        &[
            "render",
            "bumps",
            "--set",
            "pattern=alternate",
            "--out",
            "b.npy",
        ],
    ));
    let img = io::read_image(&d.join("b.npy"), MAX).unwrap();
    let labels = io::read_labels(&d.join("b_mask.png"), MAX).unwrap();
    let meta = sidecar(&d.join("b.json"));
    let targets = meta["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 12);
    for t in targets {
        let label = t["label"].as_u64().unwrap() as u16;
        let rows: Vec<usize> = (0..img.height())
            .filter(|&r| (0..img.width()).any(|c| *labels.get(c, r) == label))
            .collect();
        let mid = (rows[0] + rows[rows.len() - 1]).div_ceil(2);
        let (mut top, mut bottom) = (0.0, 0.0);
        for &r in &rows {
            for c in 0..img.width() {
                if *labels.get(c, r) == label {
                    if r < mid {
                        top += img.get(c, r);
                    } else {
                        bottom += img.get(c, r);
                    }
                }
            }
        }
        let name = t["name"].as_str().unwrap();
        if name.starts_with("bump") {
            assert!(top > 1.5 * bottom, "{name}");
        } else {
            assert!(bottom > 1.5 * top, "{name}");
        }
    }
}

#[test]
fn binary_circles_have_exactly_two_levels_inside() {
    let d = scratch("stim-binary");
    ok(&shadelab(
        &d,
        &[
            "render",
            "circles-binary",
            "--set",
            "layout=random",
            "--seed",
            "5",
            "--out",
            "c.npy",
        ],
    ));
    let img = io::read_image(&d.join("c.npy"), MAX).unwrap();
    let labels = io::read_labels(&d.join("c_mask.png"), MAX).unwrap();
    let n = labels.data().iter().copied().max().unwrap();
    assert!(n >= 10);
    let mut levels = BTreeSet::new();
    for label in 1..=n {
        let v = labels_and_values(&img, &labels, label);
        let inside: BTreeSet<u64> = v.iter().map(|x| x.to_bits()).collect();
        let high = v.iter().filter(|&&x| x > 0.5).count();
        assert_eq!(inside.len(), 2, "circle {label}");
        assert_eq!(2 * high, v.len(), "circle {label}: halves");
        levels.extend(inside);
    }
    assert_eq!(levels.len(), 2, "the same two levels in every circle");
}

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
    assert_eq!(meta["visual_size_deg"]["width"], 12.0);
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
    for ext in ["png", "npy", "mat", "svg"] {
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
            shape: Some((40, 30)),
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
    assert_eq!(a.name, "stimulus");
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
        stimulus::write_output(name, &request, &out, &path, &ExportOptions::default()).unwrap();
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
fn hollow_face_lit_from_above_is_the_convex_face_lit_from_below() {
    let d = scratch("stim-hollow");
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=hollow",
            "--set",
            "light=above",
            "--out",
            "h.npy",
        ],
    ));
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=convex",
            "--set",
            "light=below",
            "--out",
            "c.npy",
        ],
    ));
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=convex",
            "--set",
            "light=above",
            "--layers",
            "--out",
            "a.npy",
        ],
    ));
    let h = io::read_image(&d.join("h.npy"), MAX).unwrap();
    let c = io::read_image(&d.join("c.npy"), MAX).unwrap();
    let a = io::read_image(&d.join("a.npy"), MAX).unwrap();
    assert_eq!(h, c);
    assert_ne!(h, a);
    for layer in [
        "a_depth.npy",
        "a_normals.npy",
        "a_shading.npy",
        "a_mask.png",
    ] {
        assert!(d.join(layer).exists(), "{layer}");
    }
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

#[test]
fn bad_input_is_one_line_nonzero_and_writes_nothing() {
    let d = scratch("stim-bad");
    std::fs::write(
        d.join("extra.json"),
        r#"{"stimulus": "bumps", "params": {}, "colour": "red"}"#,
    )
    .unwrap();
    std::fs::write(
        d.join("badparam.json"),
        r#"{"stimulus": "strips", "params": {"width": 2}}"#,
    )
    .unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["render", "bumpz", "--out", "x.png"], 2, "checker-shadow"),
        (
            &["render", "bumps", "--set", "colour=red", "--out", "x.png"],
            2,
            "valid: profile, radius",
        ),
        (
            &["render", "bumps", "--set", "radius=-1", "--out", "x.png"],
            2,
            "radius",
        ),
        (
            &["render", "bumps", "--set", "radius=0", "--out", "x.png"],
            2,
            "radius",
        ),
        (
            &[
                "render",
                "strips",
                "--set",
                "contrast=1.5",
                "--out",
                "x.png",
            ],
            2,
            "contrast",
        ),
        (
            &[
                "render",
                "circles-binary",
                "--set",
                "contrast=-0.1",
                "--out",
                "x.png",
            ],
            2,
            "contrast",
        ),
        (
            &["render", "checker-shadow", "--ppd", "0", "--out", "x.png"],
            2,
            "ppd",
        ),
        (
            &[
                "render",
                "checker-shadow",
                "--visual-size=-3",
                "--out",
                "x.png",
            ],
            2,
            "positive",
        ),
        (
            &["render", "disc", "--visual-size", "0x4", "--out", "x.png"],
            2,
            "positive",
        ),
        (
            &["render", "fading-disk", "--size", "0x10", "--out", "x.png"],
            2,
            "empty",
        ),
        (
            &[
                "render",
                "crater",
                "--visual-size",
                "8",
                "--ppd",
                "32",
                "--size",
                "300",
                "--out",
                "x.png",
            ],
            2,
            "inconsistent",
        ),
        (
            &["render", "--spec", "extra.json", "--out", "x.png"],
            1,
            "unknown field `colour`",
        ),
        (
            &["render", "--spec", "badparam.json", "--out", "x.png"],
            2,
            "unknown parameter 'width'",
        ),
        (
            &[
                "render",
                "boundary-strips",
                "--set",
                "boundary=wavy",
                "--out",
                "x.png",
            ],
            2,
            "'wavy'",
        ),
        (
            &[
                "render",
                "fading-disk",
                "--set",
                "disk_colour=blue",
                "--out",
                "x.png",
            ],
            2,
            "disk_colour",
        ),
        (
            &["render", "bumps", "--set", "rows=30", "--out", "x.png"],
            2,
            "enlarge",
        ),
        (
            &["render", "strips", "--range", "psychopy", "--out", "x.svg"],
            2,
            "psychopy",
        ),
        (
            &["render", "strips", "--gamma", "2.2", "--out", "x.mat"],
            2,
            "gamma",
        ),
        (
            &["gallery", "--presets", "missing", "--out", "g"],
            1,
            "missing",
        ),
    ];
    for (args, code, needle) in cases {
        let out = shadelab(&d, args);
        assert_error(&out, *code, needle);
    }
    let mut left: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["badparam.json", "extra.json"],
        "nothing else written"
    );
}

#[test]
fn the_gallery_renders_every_preset_with_captions_and_files() {
    let d = scratch("stim-gallery");
    let out = shadelab(&d, &["gallery", "--out", "g"]);
    ok(&out);
    let g = d.join("g");
    let html = std::fs::read_to_string(g.join("index.html")).unwrap();
    let presets = shadelab::gallery::builtin_presets().unwrap();
    // Every spec in stimuli/ is a built-in preset.
    let on_disk: BTreeSet<String> =
        std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
            .collect();
    let built_in: BTreeSet<String> = presets.iter().map(|p| p.name.clone()).collect();
    assert_eq!(on_disk, built_in);
    for p in &presets {
        let title = p.spec.title.as_deref().unwrap();
        assert!(
            html.contains(&title.replace('&', "&amp;")),
            "{title} not in index.html"
        );
        for f in [
            format!("{}.png", p.name),
            format!("{}.json", p.name),
            format!("thumbs/{}.png", p.name),
        ] {
            assert!(g.join(&f).exists(), "{f}");
        }
        let meta = sidecar(&g.join(format!("{}.json", p.name)));
        assert_eq!(meta["stimulus"], p.spec.stimulus.as_str());
    }
    assert!(g.join("gallery.png").exists());
    // A second run replaces its own folder and gives the same files.
    let first = std::fs::read(g.join("checker-shadow.png")).unwrap();
    let first_html = html.clone();
    ok(&shadelab(&d, &["gallery", "--out", "g"]));
    assert_eq!(first, std::fs::read(g.join("checker-shadow.png")).unwrap());
    assert_eq!(
        first_html,
        std::fs::read_to_string(g.join("index.html")).unwrap()
    );
    // A folder of someone else's is not replaced.
    std::fs::create_dir(d.join("photos")).unwrap();
    std::fs::write(d.join("photos/holiday.jpg"), "x").unwrap();
    assert_error(&shadelab(&d, &["gallery", "--out", "photos"]), 1, "--force");
    // A custom preset folder works too.
    std::fs::create_dir(d.join("mine")).unwrap();
    std::fs::write(
        d.join("mine/a.json"),
        r#"{"stimulus": "disc", "shape": [32, 32]}"#,
    )
    .unwrap();
    ok(&shadelab(
        &d,
        &["gallery", "--presets", "mine", "--out", "m"],
    ));
    assert!(d.join("m/a.png").exists() && d.join("m/index.html").exists());
}
