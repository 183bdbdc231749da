//! Outputs of several files and output folders appear whole or not at all: under Ctrl-C at any
//! moment, SIGKILL, two runs writing the same output, and closed or full stdout/stderr.
//! Interrupt and concurrency tests repeat at varied delays to catch races (trial counts below
//! and in docs/reliability.md).

use crate::cli::{assert_error, files_in, scratch, shadelab};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Trials of each interrupt and concurrency test.
const TRIALS: u64 = 20;

/// Spread delays in `lo..hi` ms, the same each run (SplitMix64 of the trial number).
fn delay_ms(trial: u64, lo: u64, hi: u64) -> u64 {
    let mut z = trial.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    lo + z % (hi - lo)
}

fn spawn(dir: &Path, args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Starts `args` in `dir`, sends it SIGINT after `ms` milliseconds and waits for it. (The
/// process may have ended already; kill then fails, which is fine.)
fn interrupt_after(dir: &Path, args: &[&str], ms: u64) -> Output {
    let child = spawn(dir, args);
    std::thread::sleep(Duration::from_millis(ms));
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .stderr(Stdio::null())
        .status();
    child.wait_with_output().unwrap()
}

/// Every file under `dir` (relative path → bytes).
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    if dir.exists() {
        walk(dir, dir, &mut out);
    }
    out
}

/// The names in `dir` that start with a dot (temporaries, locks, backups).
fn hidden(dir: &Path) -> Vec<String> {
    files_in(dir)
        .into_iter()
        .filter(|n| n.starts_with('.'))
        .collect()
}

/// An interrupted run ends with 130 and its one line; a run the signal missed (it had ended)
/// with 0. Never anything else: no exit 0 after the signal reached it, no panic.
fn assert_interrupted_or_done(out: &Output, what: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{what}: {err}");
    match out.status.code() {
        Some(0) => assert!(err.is_empty(), "{what}: {err}"),
        Some(130) => {
            assert_eq!(err.lines().count(), 1, "{what}: {err}");
            assert!(err.starts_with("error: interrupted"), "{what}: {err}");
        }
        // A signal that came before the handler was installed (a loaded machine starts a
        // process slowly) ends it at once, before it wrote anything.
        None if std::os::unix::process::ExitStatusExt::signal(&out.status) == Some(2) => {}
        other => panic!("{what}: exit {other:?}: {err}"),
    }
}

/// A small gallery: eight presets of the built-in ones.
fn small_presets(d: &Path) -> PathBuf {
    let presets = d.join("presets");
    std::fs::create_dir(&presets).unwrap();
    let stimuli = Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli");
    for name in [
        "boundary-strips",
        "boundary-strips-ramp",
        "bumps",
        "bumps-gradient",
        "checker-shadow",
        "circles-binary",
        "circles-gradient",
        "circles-odd-one-out",
    ] {
        let file = format!("{name}.json");
        std::fs::copy(stimuli.join(&file), presets.join(&file)).unwrap();
    }
    presets
}

#[test]
fn an_interrupted_gallery_leaves_the_old_folder_whole_and_never_exits_0() {
    let d = scratch("sets-gallery");
    small_presets(&d);
    let args = [
        "--threads",
        "2",
        "--quiet",
        "gallery",
        "--presets",
        "presets",
        "--out",
        "g",
    ];
    let out = shadelab(&d, &args);
    assert!(out.status.success(), "{out:?}");
    let whole = tree(&d.join("g"));
    assert!(whole.len() > 20, "{}", whole.len());
    let (mut interrupted, mut finished) = (0, 0);
    for trial in 0..TRIALS {
        let out = interrupt_after(&d, &args, delay_ms(trial, 5, 700));
        let what = format!("trial {trial}");
        assert_interrupted_or_done(&out, &what);
        if out.status.code() != Some(0) {
            interrupted += 1;
        } else {
            finished += 1;
        }
        // The folder under its final name is complete (old or new: the same bytes), and no
        // temporary folder, lock or backup is left beside it.
        assert!(
            tree(&d.join("g")) == whole,
            "{what}: the folder is not whole"
        );
        assert_eq!(hidden(&d), Vec::<String>::new(), "{what}");
    }
    eprintln!("gallery: {interrupted} of {TRIALS} runs interrupted, {finished} finished");
    assert!(interrupted > 0, "no trial was interrupted in time");
}

/// A render of `light` whose set is large enough to be stopped while it is written.
fn big_render(light: &str) -> Vec<String> {
    [
        "--threads",
        "2",
        "--quiet",
        "render",
        "sphere",
        "--size",
        "1536",
        "--layers",
        "--light",
        light,
        "--out",
        "s.png",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect()
}

fn run_args(d: &Path, args: &[String]) -> Output {
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    shadelab(d, &args)
}

/// The complete set that a render of `args` writes (made in a folder of its own).
fn reference_set(d: &Path, name: &str, args: &[String]) -> BTreeMap<PathBuf, Vec<u8>> {
    let folder = d.join(name);
    std::fs::create_dir(&folder).unwrap();
    assert!(run_args(&folder, args).status.success());
    tree(&folder)
}

#[test]
fn an_interrupted_render_leaves_the_old_set_or_the_new_set_whole() {
    let d = scratch("sets-render");
    let (old_args, new_args) = (big_render("left"), big_render("right"));
    let old = reference_set(&d, "old", &old_args);
    let new = reference_set(&d, "new", &new_args);
    assert_eq!(old.len(), 6, "{:?}", old.keys());
    assert_ne!(old, new);
    let out_dir = d.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let (mut kept, mut replaced) = (0, 0);
    for trial in 0..TRIALS {
        assert!(run_args(&out_dir, &old_args).status.success());
        let args: Vec<&str> = new_args.iter().map(String::as_str).collect();
        let out = interrupt_after(&out_dir, &args, delay_ms(trial, 5, 300));
        let what = format!("trial {trial}");
        assert_interrupted_or_done(&out, &what);
        let now = tree(&out_dir);
        if now == old {
            kept += 1;
            assert_eq!(
                out.status.code(),
                Some(130),
                "{what}: exit 0 but the old set"
            );
        } else {
            assert!(now == new, "{what}: a mixed set: {:?}", now.keys());
            replaced += 1;
        }
        assert_eq!(hidden(&out_dir), Vec::<String>::new(), "{what}");
    }
    eprintln!(
        "render: {kept} of {TRIALS} interrupted renders kept the old set, {replaced} the new"
    );
    assert!(kept > 0, "no trial was interrupted in time");
}

#[test]
fn two_renders_to_one_output_one_wins_whole_the_other_fails_clearly() {
    let d = scratch("sets-concurrent");
    let (a_args, b_args) = (big_render("left"), big_render("right"));
    let a = reference_set(&d, "a", &a_args);
    let b = reference_set(&d, "b", &b_args);
    let out_dir = d.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let mut refused = 0;
    for trial in 0..TRIALS {
        for f in files_in(&out_dir) {
            std::fs::remove_file(out_dir.join(f)).unwrap();
        }
        let first: Vec<&str> = a_args.iter().map(String::as_str).collect();
        let second: Vec<&str> = b_args.iter().map(String::as_str).collect();
        let one = spawn(&out_dir, &first);
        std::thread::sleep(Duration::from_millis(delay_ms(trial, 0, 50)));
        let two = spawn(&out_dir, &second);
        let (one, two) = (
            one.wait_with_output().unwrap(),
            two.wait_with_output().unwrap(),
        );
        let what = format!("trial {trial}");
        for out in [&one, &two] {
            if !out.status.success() {
                assert_error(out, 1, "another shadelab run (process ");
                refused += 1;
            }
        }
        assert!(one.status.success() || two.status.success(), "{what}");
        let now = tree(&out_dir);
        if two.status.success() && !one.status.success() {
            assert!(now == b, "{what}");
        } else if one.status.success() && !two.status.success() {
            assert!(now == a, "{what}");
        } else {
            // Both ran, one after the other: the set of either, whole.
            assert!(now == a || now == b, "{what}: a mixed set");
        }
        assert_eq!(hidden(&out_dir), Vec::<String>::new(), "{what}");
    }
    eprintln!("concurrent renders: {refused} of {TRIALS} pairs had one run refused");
}

#[test]
fn a_render_killed_with_sigkill_is_cleaned_up_by_the_next_run() {
    let d = scratch("sets-sigkill");
    let (old_args, new_args) = (big_render("left"), big_render("right"));
    let new = reference_set(&d, "new", &new_args);
    let out_dir = d.join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let mut left_behind = 0;
    for trial in 0..TRIALS / 2 {
        assert!(run_args(&out_dir, &old_args).status.success());
        let args: Vec<&str> = new_args.iter().map(String::as_str).collect();
        let mut child = spawn(&out_dir, &args);
        // Kill it once it is writing (a temporary or its lock has appeared), a little later
        // in each trial.
        let started = Instant::now();
        while hidden(&out_dir).is_empty() && started.elapsed() < Duration::from_secs(20) {
            std::thread::sleep(Duration::from_millis(1));
        }
        std::thread::sleep(Duration::from_millis(delay_ms(trial, 0, 120)));
        child.kill().unwrap();
        child.wait().unwrap();
        if !hidden(&out_dir).is_empty() {
            left_behind += 1;
        }
        // The next run on the same output removes what the killed one left and writes a whole
        // set.
        let out = run_args(&out_dir, &new_args);
        assert!(out.status.success(), "trial {trial}: {out:?}");
        assert!(tree(&out_dir) == new, "trial {trial}");
        assert_eq!(hidden(&out_dir), Vec::<String>::new(), "trial {trial}");
    }
    eprintln!(
        "sigkill: {left_behind} of {} killed renders left temporaries",
        TRIALS / 2
    );
    assert!(
        left_behind > 0,
        "no kill landed while the render was writing"
    );
}

/// Runs `args` with stdout (or stderr) a pipe whose reader is closed as soon as the process is
/// started (long before it prints anything).
fn with_closed(d: &Path, args: &[&str], close_stdout: bool) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .current_dir(d)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    if close_stdout {
        drop(child.stdout.take());
    } else {
        drop(child.stderr.take());
    }
    child.wait_with_output().unwrap()
}

#[test]
fn closed_or_full_stdout_and_stderr_never_panic() {
    let d = scratch("sets-pipes");
    // stdout read by `head -c1`: the rest ends quietly, with success.
    for args in [
        &["list"][..],
        &["describe", "sphere"],
        &["--json", "describe", "sphere"],
        &["bench", "--sizes", "16", "--repeat", "1"],
        &[
            "--json", "render", "sphere", "--size", "32", "--out", "p.png",
        ],
    ] {
        let out = with_closed(&d, args, true);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
    }
    assert!(d.join("p.json").exists());
    // stderr closed: the outputs are still written, errors still end with their status.
    let out = with_closed(
        &d,
        &["render", "sphere", "--size", "48", "--out", "s.png"],
        false,
    );
    assert_eq!(out.status.code(), Some(0));
    let out = with_closed(
        &d,
        &["solve", "s.png", "--light", "front", "--out", "res"],
        false,
    );
    assert_eq!(out.status.code(), Some(0));
    assert!(d.join("res/report.json").exists());
    let out = with_closed(&d, &["render", "teapot", "--out", "t.png"], false);
    assert_eq!(out.status.code(), Some(2));
    let out = with_closed(&d, &["--threads", "100000", "list"], false);
    assert_eq!(out.status.code(), Some(0));
    // A full stdout is an error worth one line (the results were not delivered).
    let full = std::fs::OpenOptions::new().write(true).open("/dev/full");
    match full {
        Ok(full) => {
            let out = Command::new(env!("CARGO_BIN_EXE_shadelab"))
                .args(["describe", "sphere"])
                .stdout(full)
                .output()
                .unwrap();
            assert_error(&out, 1, "standard output: No space left on device");
        }
        Err(e) => eprintln!("skipped /dev/full: {e}"),
    }
}

#[test]
fn a_set_replaced_by_a_smaller_one_takes_its_extra_files_with_it() {
    let d = scratch("sets-shrink");
    let render = |extra: &[&str]| {
        let mut args = vec![
            "--quiet", "render", "vase", "--size", "24", "--out", "v.png",
        ];
        args.extend_from_slice(extra);
        let out = shadelab(&d, &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    render(&["--layers"]);
    assert_eq!(
        files_in(&d),
        [
            "v.json",
            "v.png",
            "v_depth.npy",
            "v_mask.png",
            "v_normals.npy",
            "v_shading.npy"
        ]
    );
    // Without layers, the old set's layers would lie beside a picture they do not belong to.
    render(&[]);
    assert_eq!(files_in(&d), ["v.json", "v.png", "v_mask.png"]);
    // Only files the old sidecar listed go, and only names a render writes: a layer file of the
    // user's, and whatever a hand-edited sidecar names, stay.
    render(&["--layers"]);
    let sidecar = d.join("v.json");
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sidecar).unwrap()).unwrap();
    json["files"]["depth"] = "notes.txt".into();
    json["files"]["extra"] = "../outside.txt".into();
    std::fs::write(&sidecar, json.to_string()).unwrap();
    std::fs::write(d.join("notes.txt"), "mine").unwrap();
    std::fs::write(d.join("../outside.txt"), "mine").unwrap();
    render(&[]);
    assert_eq!(
        files_in(&d),
        ["notes.txt", "v.json", "v.png", "v_depth.npy", "v_mask.png"]
    );
    assert!(d.join("../outside.txt").exists());
    let _ = std::fs::remove_file(d.join("../outside.txt"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn two_pictures_of_one_name_never_share_a_sidecar_or_mask() {
    // `a.npy` and then `a.png`: both would be recorded in a.json with a_mask.png beside them,
    // and `a.png → a.json` is how every analysis finds a picture's record. The second is
    // refused, naming the first; the first set stays as it was.
    let d = scratch("sets-one-name");
    let render = |stimulus: &str, out: &str| {
        shadelab(
            &d,
            &["--quiet", "render", stimulus, "--size", "24", "--out", out],
        )
    };
    assert!(render("bumps", "a.npy").status.success());
    let before = tree(&d);
    for forced in [false, true] {
        let mut args = vec![
            "--quiet", "render", "crater", "--size", "24", "--out", "a.png",
        ];
        if forced {
            args.push("--force");
        }
        let out = shadelab(&d, &args);
        assert_error(
            &out,
            1,
            "a.json beside it is the record of a.npy, another picture",
        );
        assert_eq!(tree(&d), before, "forced: {forced}");
    }
    // The same picture again replaces its own set, and once a.npy is gone its record is a
    // stale one that a new picture may take.
    assert!(render("bumps", "a.npy").status.success());
    std::fs::remove_file(d.join("a.npy")).unwrap();
    assert!(render("crater", "a.png").status.success());
    assert_eq!(files_in(&d), ["a.json", "a.png", "a_mask.png"]);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("a.json")).unwrap()).unwrap();
    assert_eq!(json["stimulus"], "crater");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_edited_picture_says_so_and_its_sidecar_is_not_rendered_again() {
    use shadelab::pipeline::render::{run, RenderConfig};
    use shadelab::stimulus::{Pixels, Range};
    let d = scratch("sets-edited");
    let mut config = RenderConfig::new("bumps");
    config.size.set_shape((24, 32));
    let report = run(&config, &shadelab::NoProgress).unwrap();
    let Pixels::Gray(img) = &report.output.pixels else {
        panic!("bumps is gray")
    };
    let rendered_md5 = shadelab::stimulus::pixels_md5(&report.output.pixels);
    let edited = Pixels::Gray(img.map(|v| v * 0.5 + 0.25));
    let edited_md5 = shadelab::stimulus::pixels_md5(&edited);
    let edited = report
        .clone()
        .with_picture(edited, Range::Unit, "img")
        .unwrap();
    edited
        .write(&shadelab::Output::new(d.join("e.npy")))
        .unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("e.json")).unwrap()).unwrap();
    assert_eq!(json["md5_float64_rounded8"], edited_md5.as_str());
    assert_eq!(
        json["edited"]["rendered_md5_float64_rounded8"],
        rendered_md5.as_str()
    );
    assert_ne!(edited_md5, rendered_md5);
    // The .npy holds the edited values exactly (float32 of them).
    let written = shadelab_io::read_array(&d.join("e.npy"), 1 << 20).unwrap();
    let Pixels::Gray(want) = &edited.output.pixels else {
        unreachable!()
    };
    assert_eq!(written.shape, [24, 32]);
    for (a, b) in written.data.iter().zip(want.data()) {
        assert_eq!(*a, f64::from(*b as f32));
    }
    // render --spec of its sidecar refuses to claim it reproduces the picture, in one line.
    std::fs::create_dir(d.join("again")).unwrap();
    let out = shadelab(&d, &["render", "--spec", "e.json", "--out", "again/e.npy"]);
    assert_error(&out, 1, "e.json: records a picture edited after rendering");
    assert!(files_in(&d.join("again")).is_empty());
    let _ = std::fs::remove_dir_all(&d);
}
