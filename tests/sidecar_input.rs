//! Analyses read the render they are given (its sidecar's mask, names, ppd, albedo, ambient,
//! gamma and light), and every command prints its results on stdout, chatter on stderr.

use crate::cli::{assert_error, scratch, shadelab};
use serde_json::Value;
use shadelab::pipeline::PictureSource;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};

fn ok(out: &std::process::Output) -> (String, String) {
    let (o, e) = (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    );
    assert!(out.status.success(), "stdout: {o}\nstderr: {e}");
    assert!(!e.contains("panicked"), "{e}");
    (o, e)
}

fn json(out: &std::process::Output) -> Value {
    let (o, _) = ok(out);
    serde_json::from_str(&o).unwrap_or_else(|e| panic!("stdout is not one JSON document: {e}\n{o}"))
}

fn token_names(report: &Value) -> Vec<String> {
    report["tokens"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["name"].as_str().unwrap().to_string())
        .collect()
}

#[test]
fn prior_sweep_of_a_render_matches_the_stimulus_itself() {
    let d = scratch("sidecar-sweep");
    ok(&shadelab(&d, &["render", "crater", "--out", "crater.png"]));
    // The same sweep of one picture, named as `picture`, into the folder `out`.
    let sweep = |picture: &[&str], out: &str| {
        let args = [
            &["analyze", "prior-sweep"][..],
            picture,
            &["--tilts", "0:360:45", "--json", "--out", out],
        ]
        .concat();
        shadelab(&d, &args)
    };
    let from_file = sweep(&["crater.png"], "a");
    let err = String::from_utf8_lossy(&from_file.stderr).into_owned();
    assert!(
        err.contains("read crater.json: mask crater_mask.png, 2 targets (crater, mound), ppd 40, albedo 0.566, ambient 0.1, light tilt 0 slant 45"),
        "{err}"
    );
    let a = json(&from_file);
    let b = json(&sweep(&["--stimulus", "crater"], "b"));
    assert_eq!(token_names(&a), ["crater", "mound"]);
    assert_eq!(token_names(&a), token_names(&b));
    let (pa, pb) = (&a["parameters"], &b["parameters"]);
    for key in ["albedo", "ambient", "slant_deg"] {
        let (x, y) = (pa[key].as_f64().unwrap(), pb[key].as_f64().unwrap());
        assert!((x - y).abs() < 1e-6, "{key}: {x} vs {y}");
    }
    assert!((pa["ambient"].as_f64().unwrap() - 0.1).abs() < 1e-12);
    // The true light, beside the assumed ones, from the sidecar as from the stimulus.
    assert_eq!(a["true_light"], b["true_light"]);
    assert!((a["true_light"]["slant_deg"].as_f64().unwrap() - 45.0).abs() < 1e-9);
    // The same numbers up to the PNG's 16-bit quantisation.
    for (ta, tb) in a["tokens"]
        .as_array()
        .unwrap()
        .iter()
        .zip(b["tokens"].as_array().unwrap())
    {
        let flips = |t: &Value| -> Vec<f64> {
            t["flips_deg"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| f.as_f64().unwrap())
                .collect()
        };
        let (fa, fb) = (flips(ta), flips(tb));
        assert_eq!(fa.len(), fb.len(), "{fa:?} vs {fb:?}");
        assert!(
            fa.iter().zip(&fb).all(|(x, y)| (x - y).abs() < 0.5),
            "{fa:?} vs {fb:?}"
        );
    }
    // The CSV names the targets.
    let csv = std::fs::read_to_string(d.join("a/sweep.csv")).unwrap();
    assert!(csv.contains("crater") && csv.contains("mound"), "{csv}");
    // --spec SIDECAR renders it in memory: the stimulus's own numbers.
    let c = json(&sweep(&["--spec", "crater.json"], "c"));
    assert_eq!(c["tokens"], b["tokens"]);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn lightness_of_a_render_takes_its_ppd_and_names() {
    let d = scratch("sidecar-lightness");
    ok(&shadelab(
        &d,
        &["render", "checker-shadow", "--out", "cs.png"],
    ));
    let (out, err) = ok(&shadelab(
        &d,
        &[
            "analyze",
            "lightness",
            "cs.png",
            "--model",
            "odog",
            "--out",
            "o",
        ],
    ));
    assert!(
        err.contains("read cs.json:") && err.contains("ppd"),
        "{err}"
    );
    assert!(out.contains("odog: A (label 1)"), "{out}");
    assert!(
        out.contains("checker-shadow: A and B pixels identical: true"),
        "{out}"
    );
    // An explicit flag wins, and says so.
    let (_, err) = ok(&shadelab(
        &d,
        &[
            "analyze",
            "lightness",
            "cs.png",
            "--model",
            "odog",
            "--ppd",
            "20",
            "--out",
            "p",
        ],
    ));
    assert!(err.contains("--ppd 20 replaces the sidecar's"), "{err}");
    // Without the sidecar the resolution is asked for, as before.
    std::fs::rename(d.join("cs.json"), d.join("moved.json")).unwrap();
    assert_error(
        &shadelab(
            &d,
            &[
                "analyze",
                "lightness",
                "cs.png",
                "--model",
                "odog",
                "--out",
                "q",
            ],
        ),
        2,
        "--ppd",
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_recorded_gamma_is_undone() {
    let d = scratch("sidecar-gamma");
    ok(&shadelab(
        &d,
        &["render", "sphere", "--size", "64", "--out", "lin.png"],
    ));
    ok(&shadelab(
        &d,
        &[
            "render", "sphere", "--size", "64", "--gamma", "2.2", "--out", "gam.png",
        ],
    ));
    let load = |name: &str| {
        PictureSource {
            image: Some(d.join(name)),
            max_pixels: 1 << 24,
            ..PictureSource::default()
        }
        .load(false)
        .unwrap()
        .luminance()
    };
    let (lin, gam) = (load("lin.png"), load("gam.png"));
    let worst = lin
        .data()
        .iter()
        .zip(gam.data())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    // 16-bit codes of v^(1/2.2) decoded back: within a few codes of the linear render.
    assert!(worst < 2e-3, "largest difference {worst}");
    let worst_against_lin = |img: &shadelab::Image| {
        lin.data()
            .iter()
            .zip(img.data())
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    // The PNG alone says its gamma (gAMA 1/2.2): read without its sidecar, it is linear too.
    let alone = shadelab_io::read_gray(&d.join("gam.png"), 1 << 24)
        .unwrap()
        .0;
    assert!(worst_against_lin(&alone) < 2e-3);
    // A file from before the gAMA chunk (the same bytes without it): the sidecar's gamma is
    // undone instead, once; read alone, the gamma-encoded mid-grey is far off.
    let bytes = std::fs::read(d.join("gam.png")).unwrap();
    let mut old = bytes[..8].to_vec();
    let mut at = 8;
    while at < bytes.len() {
        let len = u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        if &bytes[at + 4..at + 8] != b"gAMA" {
            old.extend(&bytes[at..at + 12 + len]);
        }
        at += 12 + len;
    }
    assert_eq!(
        old.len(),
        bytes.len() - 16,
        "one gAMA chunk (4 bytes of data) taken out"
    );
    std::fs::write(d.join("old.png"), &old).unwrap();
    std::fs::copy(d.join("gam.json"), d.join("old.json")).unwrap();
    assert!(worst_against_lin(&load("old.png")) < 2e-3);
    let raw = shadelab_io::read_gray(&d.join("old.png"), 1 << 24)
        .unwrap()
        .0;
    let raw_worst = worst_against_lin(&raw);
    assert!(raw_worst > 0.1, "{raw_worst}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Renders a small crater as `c.png` (and its sidecar) in `d`; returns the arguments of a
/// prior sweep of it, all but the output folder.
fn small_crater(d: &Path) -> [&'static str; 6] {
    ok(&shadelab(
        d,
        &["render", "crater", "--size", "64", "--out", "c.png"],
    ));
    [
        "analyze",
        "prior-sweep",
        "c.png",
        "--tilts",
        "0,180",
        "--out",
    ]
}

#[test]
fn foreign_and_malformed_sidecars() {
    let d = scratch("sidecar-bad");
    let args = [&small_crater(&d)[..], &["o"]].concat();
    // Another program's JSON: ignored, with a note.
    std::fs::write(d.join("c.json"), r#"{"program": "elsewhere"}"#).unwrap();
    let (out, err) = ok(&shadelab(&d, &args));
    assert!(
        err.contains("c.json is not a shadelab sidecar") && err.contains("ignored"),
        "{err}"
    );
    assert!(out.contains("image: convexity"), "{out}");
    // Not JSON at all, or shadelab's with a bad field: one line naming the file.
    std::fs::write(d.join("c.json"), "{not json").unwrap();
    assert_error(&shadelab(&d, &args), 1, "c.json");
    std::fs::write(
        d.join("c.json"),
        r#"{"program": "shadelab", "ppd": "forty"}"#,
    )
    .unwrap();
    assert_error(&shadelab(&d, &args), 1, "c.json");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn results_on_stdout_chatter_on_stderr() {
    let d = scratch("stdout");
    let args = small_crater(&d);
    let (out, err) = ok(&shadelab(&d, &[&args[..], &["a"]].concat()));
    assert!(out.contains("crater: convexity changes sign"), "{out}");
    assert!(err.contains("wrote ") && !out.contains("wrote "), "{err}");
    // --quiet silences the chatter, never the results.
    let (out, err) = ok(&shadelab(&d, &[&args[..], &["b", "--quiet"]].concat()));
    assert!(out.contains("crater: convexity changes sign"), "{out}");
    assert!(err.is_empty(), "{err}");
    // --json: the report, one document.
    let report = json(&shadelab(
        &d,
        &[&args[..], &["c", "--json", "--quiet"]].concat(),
    ));
    assert_eq!(report["command"], "analyze prior-sweep");
    let (out, _) = ok(&shadelab(&d, &["list", "--json"]));
    let list: Value = serde_json::from_str(&out).unwrap();
    assert!(list
        .as_array()
        .unwrap()
        .iter()
        .any(|s| s["name"] == "crater"));
    let _ = std::fs::remove_dir_all(&d);
}

/// Runs the binary with its stdout a pipe whose reading end is closed at once.
fn closed_stdout(args: &[&str]) -> std::process::Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    std::process::Output {
        status,
        stdout: Vec::new(),
        stderr: err.into_bytes(),
    }
}

#[test]
fn a_closed_or_full_stdout_is_no_panic() {
    for args in [&["list"][..], &["describe", "sphere"], &["list", "--json"]] {
        let out = closed_stdout(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    }
    if !Path::new("/dev/full").exists() {
        eprintln!("skipped the /dev/full half: no /dev/full here");
        return;
    }
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(["describe", "sphere"])
        .stdout(Stdio::from(full))
        .output()
        .unwrap();
    assert_error(&out, 1, "standard output");
}

#[test]
fn solve_takes_a_silhouette_as_its_mask_and_solves_regions_whole() {
    let d = scratch("sidecar-solve-mask");
    // A rendered surface: its target is the object's silhouette, so the solve stays inside it.
    ok(&shadelab(
        &d,
        &["render", "sphere", "--size", "64x64", "--out", "s.png"],
    ));
    let (o, e) = ok(&shadelab(
        &d,
        &["solve", "s.png", "--light", "0,0,1", "--out", "s"],
    ));
    assert!(o.ends_with('\n') && o.contains("pixels solved"), "{o}");
    assert!(!e.contains("whole picture"), "{e}");
    let report: Value =
        serde_json::from_slice(&std::fs::read(d.join("s/report.json")).unwrap()).unwrap();
    let mask = io_mask(&d.join("s_mask.png"));
    assert_eq!(report["input"]["mask"], "s_mask.png");
    assert_eq!(report["input"]["mask_pixels"], mask);
    assert!(mask < 64 * 64);
    // Bumps: regions of one surface that goes on around them, so the whole picture is solved.
    ok(&shadelab(
        &d,
        &["render", "bumps", "--size", "96x64", "--out", "b.png"],
    ));
    let (_, e) = ok(&shadelab(
        &d,
        &["solve", "b.png", "--light", "0,0,1", "--out", "b"],
    ));
    assert!(
        e.contains("the whole picture is solved (give --mask"),
        "{e}"
    );
    let report: Value =
        serde_json::from_slice(&std::fs::read(d.join("b/report.json")).unwrap()).unwrap();
    assert_eq!(report["input"]["mask"], Value::Null);
    assert_eq!(report["input"]["mask_pixels"], 96 * 64);
}

/// The number of nonzero pixels of a mask PNG.
fn io_mask(path: &Path) -> u64 {
    let labels = shadelab_io::read_labels(path, 1 << 24).unwrap();
    labels.data().iter().filter(|&&l| l > 0).count() as u64
}
