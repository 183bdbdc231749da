//! The command line as a user meets it: outputs, sidecars and one-line errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the shadelab binary with `args` in `dir`.
pub fn shadelab(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the shadelab binary runs")
}

/// A fresh scratch folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shadelab-it-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Asserts that a run failed with exit `code`, one `error:` line mentioning `needle`, no panic.
pub fn assert_error(out: &Output, code: i32, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(code), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(lines.len(), 1, "one line expected: {err}");
    assert!(lines[0].starts_with("error: "), "{err}");
    assert!(lines[0].contains(needle), "'{needle}' not in: {err}");
}

/// The names in `dir`, sorted (hidden ones included).
pub fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn render_writes_image_sidecar_mask_and_layers() {
    let d = scratch("render");
    let out = shadelab(
        &d,
        &[
            "render", "sphere", "--light", "above", "--size", "64", "--layers", "--out", "s.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        files_in(&d),
        [
            "s.json",
            "s.png",
            "s_depth.npy",
            "s_mask.png",
            "s_normals.npy",
            "s_shading.npy"
        ]
    );
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("s.json")).unwrap()).unwrap();
    assert_eq!(sidecar["stimulus"], "sphere");
    assert_eq!(sidecar["parameters"]["light"], "tilt=0,slant=45");
    assert_eq!(sidecar["parameters"]["radius"], 0.45);
    assert_eq!(sidecar["shape"], serde_json::json!([64, 64]));
    assert_eq!(sidecar["version"], env!("CARGO_PKG_VERSION"));
    // The PNG is 16-bit and equals the library's render to the last code.
    let (img, info) = shadelab_io::read_gray(&d.join("s.png"), 1 << 20).unwrap();
    assert_eq!(info.bit_depth, 16);
    let light: shadelab::Light = "above".parse().unwrap();
    let s = shadelab_engine::surface::sphere(64, 64, 0.45 * 64.0).unwrap();
    for (i, n) in s.normals.data().iter().enumerate() {
        let expect = if s.mask.data()[i] {
            n.dot(&light.direction()).max(0.0)
        } else {
            0.0
        };
        assert!((img.data()[i] - expect).abs() <= 0.5 / 65535.0 + 1e-12);
    }
    let normals = shadelab_io::read_normals(&d.join("s_normals.npy"), 1 << 20).unwrap();
    assert!(
        (normals.get(32, 5).y) > 0.5,
        "top of the sphere faces up (y up)"
    );
    let mask = shadelab_io::read_mask(&d.join("s_mask.png"), 1 << 20).unwrap();
    assert_eq!(&mask, &s.mask);
}

#[test]
fn lit_from_above_is_brighter_on_top_and_from_the_left_on_the_left() {
    let d = scratch("halves");
    for (light, file) in [("tilt=0,slant=45", "a.npy"), ("tilt=90,slant=45", "l.npy")] {
        let out = shadelab(
            &d,
            &[
                "render", "sphere", "--light", light, "--size", "64", "--out", file,
            ],
        );
        assert!(out.status.success());
    }
    let a = shadelab_io::read_image(&d.join("a.npy"), 1 << 20).unwrap();
    let l = shadelab_io::read_image(&d.join("l.npy"), 1 << 20).unwrap();
    let half_sum = |img: &shadelab::Image, f: &dyn Fn(usize, usize) -> bool| -> f64 {
        let mut s = 0.0;
        for r in 0..64 {
            for c in 0..64 {
                if f(c, r) {
                    s += img.get(c, r);
                }
            }
        }
        s
    };
    assert!(half_sum(&a, &|_, r| r < 32) > 1.5 * half_sum(&a, &|_, r| r >= 32));
    assert!(half_sum(&l, &|c, _| c < 32) > 1.5 * half_sum(&l, &|c, _| c >= 32));
}

#[test]
fn rerender_is_bit_identical_and_own_output_may_be_replaced() {
    let d = scratch("identical");
    let args = [
        "render", "vase", "--light", "1,1,2", "--size", "48x64", "--out", "v.png",
    ];
    assert!(shadelab(&d, &args).status.success());
    let first = std::fs::read(d.join("v.png")).unwrap();
    assert!(shadelab(&d, &args).status.success());
    assert_eq!(first, std::fs::read(d.join("v.png")).unwrap());
}

#[test]
fn bad_input_gets_one_line_and_nothing_written() {
    let d = scratch("bad");
    let cases: &[(&[&str], i32, &str)] = &[
        (
            &["render", "teapot", "--out", "x.png"],
            2,
            "unknown stimulus 'teapot'",
        ),
        (
            &["render", "sphere", "--set", "colour=red", "--out", "x.png"],
            2,
            "unknown parameter 'colour'",
        ),
        (
            &["render", "sphere", "--size", "0", "--out", "x.png"],
            2,
            "--size '0': both sides must be positive",
        ),
        (
            &["render", "sphere", "--light", "0,0,0", "--out", "x.png"],
            2,
            "not a direction",
        ),
        (
            &["render", "sphere", "--light", "0,0,-1", "--out", "x.png"],
            2,
            "below the horizon",
        ),
        (
            &["render", "sphere", "--light", "sideways", "--out", "x.png"],
            2,
            "not a direction",
        ),
        (
            &["render", "sphere", "--out", "x.tiff"],
            2,
            "unknown output format",
        ),
        (
            &[
                "render",
                "sphere",
                "--visual-size",
                "10",
                "--ppd",
                "32",
                "--size",
                "100",
                "--out",
                "x.png",
            ],
            2,
            "inconsistent",
        ),
        (
            &["render", "sphere", "--ppd", "0", "--out", "x.png"],
            2,
            "ppd",
        ),
        (
            &[
                "render",
                "heightfield",
                "--set",
                "path=missing.npy",
                "--out",
                "x.png",
            ],
            1,
            "missing.npy",
        ),
        (
            &["render", "sphere", "--out", "no/such/dir/x.png"],
            1,
            "does not exist",
        ),
        (&["render", "sphere", "--frobnicate"], 2, "--frobnicate"),
        (
            &["render", "mesh", "--out", "x.png"],
            2,
            "give the mesh file",
        ),
        (
            &[
                "render",
                "mesh",
                "--set",
                "path=nothing.ply",
                "--out",
                "x.png",
            ],
            1,
            "nothing.ply",
        ),
        (
            &["render", "bunny", "--set", "fill=0", "--out", "x.png"],
            2,
            "fill",
        ),
        (&["describe", "teapot"], 2, "teapot"),
    ];
    for (args, code, needle) in cases {
        let out = shadelab(&d, args);
        assert_error(&out, *code, needle);
    }
    assert!(files_in(&d).is_empty(), "left behind: {:?}", files_in(&d));
}

#[test]
fn a_foreign_file_is_not_overwritten_without_force() {
    let d = scratch("foreign");
    std::fs::write(d.join("photo.png"), b"precious").unwrap();
    let out = shadelab(
        &d,
        &["render", "sphere", "--size", "16", "--out", "photo.png"],
    );
    assert_error(&out, 1, "--force");
    assert_eq!(std::fs::read(d.join("photo.png")).unwrap(), b"precious");
    let out = shadelab(
        &d,
        &[
            "render",
            "sphere",
            "--size",
            "16",
            "--force",
            "--out",
            "photo.png",
        ],
    );
    assert!(out.status.success());
}

#[test]
fn heightfield_from_npy_renders_at_its_own_size() {
    let d = scratch("heightfield");
    let depth = shadelab::Grid::from_fn(30, 20, |c, _| if c > 5 { c as f64 * 0.5 } else { 0.0 });
    shadelab_io::write_image(&d.join("depth.npy"), &depth).unwrap();
    let out = shadelab(
        &d,
        &[
            "render",
            "heightfield",
            "--set",
            "path=depth.npy",
            "--light",
            "right",
            "--out",
            "h.npy",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = shadelab_io::read_image(&d.join("h.npy"), 1 << 20).unwrap();
    assert_eq!((img.width(), img.height()), (30, 20));
    // z rises to the right, so the surface faces left: light from the right grazes it less.
    let n = shadelab_core::gradient_space::normal_from_pq(-0.5, 0.0);
    let s: shadelab::Light = "right".parse().unwrap();
    assert!((img.get(15, 10) - n.dot(&s.direction()).max(0.0)).abs() < 1e-6);
    assert_eq!(*img.get(2, 10), 0.0);
}

#[test]
fn list_and_describe() {
    let d = scratch("list");
    let out = shadelab(&d, &["list"]);
    let text = String::from_utf8_lossy(&out.stdout);
    for name in ["sphere", "vase", "gaussian", "heightfield"] {
        assert!(
            text.lines().any(|l| l.starts_with(name)),
            "{name} missing from list"
        );
    }
    let out = shadelab(&d, &["describe", "sphere"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("radius") && text.contains("0.01..5"));
}

#[test]
fn the_built_in_bunny_renders_upright() {
    let d = scratch("bunny");
    let out = shadelab(
        &d,
        &[
            "render", "bunny", "--light", "above", "--size", "96", "--layers", "--out", "b.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mask = shadelab_io::read_mask(&d.join("b_mask.png"), 1 << 20).unwrap();
    let frac = mask.count() as f64 / mask.len() as f64;
    assert!(
        (0.25..0.6).contains(&frac),
        "bunny covers {frac} of the frame"
    );
    let normals = shadelab_io::read_normals(&d.join("b_normals.npy"), 1 << 20).unwrap();
    // Ears up: the topmost object row lies in the top fifth of the frame, and the normals along
    // the top of the silhouette point up.
    let top = (0..96).find(|&r| (0..96).any(|c| *mask.get(c, r))).unwrap();
    assert!(top < 20, "top row {top}");
    let mut up = 0;
    let mut n = 0;
    for c in 0..96 {
        if let Some(r) = (0..96).find(|&r| *mask.get(c, r)) {
            n += 1;
            if normals.get(c, r).y > 0.0 {
                up += 1;
            }
        }
    }
    assert!(up * 10 >= n * 8, "{up} of {n} top-edge normals point up");
}

/// Every flag that takes numbers or lists takes a negative value as written (`--light -1,0,1`,
/// `--tilts -90:90:30`): the same outputs as the `--flag=value` form, never "unexpected
/// argument".
#[test]
fn negative_values_are_values_not_flags() {
    let dir = scratch("negative-values");
    let run = |args: &[&str]| {
        let mut full = vec!["--quiet"];
        full.extend_from_slice(args);
        let out = shadelab(&dir, &full);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let read = |name: &str| std::fs::read(dir.join(name)).unwrap();
    // render --light: the light from the left (x < 0) makes the left half brighter.
    run(&[
        "render", "sphere", "--size", "32", "--light", "-1,0,1", "--out", "a.png",
    ]);
    run(&[
        "render",
        "sphere",
        "--size",
        "32",
        "--light=-1,0,1",
        "--out",
        "b.png",
    ]);
    assert_eq!(read("a.png"), read("b.png"));
    let (image, _) = shadelab_io::read_gray(&dir.join("a.png"), 1 << 20).unwrap();
    assert!(image.get(8, 16) > image.get(23, 16));
    // solve --light.
    run(&[
        "solve",
        "a.png",
        "--mask",
        "a_mask.png",
        "--light",
        "-1,0,1",
        "--out",
        "s1",
    ]);
    run(&[
        "solve",
        "a.png",
        "--mask",
        "a_mask.png",
        "--light=-1,0,1",
        "--out",
        "s2",
    ]);
    assert_eq!(read("s1/depth.npy"), read("s2/depth.npy"));
    // bench --light.
    let out = run(&[
        "bench", "--sizes", "8", "--repeat", "1", "--light", "-1,0,1",
    ]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("light (-0.707, 0.000, 0.707)"));
    // prior-sweep --tilts and observer --rotations/--tilts.
    let picture = [
        "--stimulus",
        "bumps",
        "--set",
        "rows=1",
        "--set",
        "columns=1",
        "--ppd",
        "8",
    ];
    for (tilts, out) in [("-90:90:30", "p1"), ("=-90:90:30", "p2")] {
        let flag = format!("--tilts{}", if tilts.starts_with('=') { tilts } else { "" });
        let mut args = vec!["analyze", "prior-sweep"];
        args.extend_from_slice(&picture);
        args.push(&flag);
        if !tilts.starts_with('=') {
            args.push(tilts);
        }
        args.extend_from_slice(&["--out", out]);
        run(&args);
    }
    assert_eq!(read("p1/sweep.csv"), read("p2/sweep.csv"));
    let mut args = vec!["analyze", "observer"];
    args.extend_from_slice(&picture);
    args.extend_from_slice(&["--rotations", "-180:180:90", "--tilts", "-180:180:45"]);
    args.extend_from_slice(&["--out", "obs"]);
    run(&args);
    let csv = String::from_utf8(read("obs/observer.csv")).unwrap();
    let rotation = csv.lines().nth(1).unwrap().split(',').nth(1);
    assert_eq!(rotation, Some("-180"), "{csv}");
    // Values that are negative and wrong are refused for what they are.
    let out = shadelab(&dir, &["--threads", "-1", "list"]);
    assert_error(&out, 2, "invalid value '-1' for '--threads");
    let out = shadelab(
        &dir,
        &["eval", "--data", "nowhere", "--diligent-light", "-1,0,1"],
    );
    assert_error(&out, 1, "nowhere: evaluation data folder not found");
    let out = shadelab(
        &dir,
        &["study", "run", "x.json", "--shard", "-1/2", "--out", "st"],
    );
    assert_error(&out, 2, "--shard '-1/2'");
}

#[test]
fn a_huge_thread_count_is_capped_with_a_warning() {
    let d = scratch("threads-cap");
    let out = shadelab(&d, &["--threads", "100000", "describe", "disc"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let cap = shadelab_core::parallel::thread_cap();
    assert!(
        err.contains(&format!("--threads 100000 is more than {cap}")),
        "{err}"
    );
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("disc"));
    // A count within the cap says nothing.
    let out = shadelab(&d, &["--threads", "2", "describe", "disc"]);
    assert!(out.status.success() && out.stderr.is_empty());
    let _ = std::fs::remove_dir_all(&d);
}
