//! Never a user's file lost (issue 38): every command that writes an output folder replaces
//! only the files shadelab writes there and keeps every other file byte for byte, with and
//! without `--force`; an input inside the output folder survives or is refused before any
//! work; an experiment with collected responses is refused unless forced (and the responses
//! kept); a link to a folder is followed; numbers out of range and diverging runs write
//! nothing.

use crate::cli::{assert_error, scratch, shadelab};
use std::path::Path;
use std::process::Output;

fn ok(out: &Output, what: &str) {
    assert!(
        out.status.success(),
        "{what}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The user's own files: one at the top, one in a folder of theirs, one in a folder
/// shadelab may write too (a name no command uses), with bytes no output has.
const USER_FILES: [(&str, &[u8]); 2] = [
    ("my_notes.txt", b"the lab's notes\n\x00\xff"),
    ("participants/p01.csv", b"rotation_deg,response\n0,convex\n"),
];

/// Runs `args` quietly in `d`, with `--force` when `force`.
fn quiet(d: &Path, force: bool, args: &[&str]) -> Output {
    let mut all = vec!["--quiet"];
    if force {
        all.push("--force");
    }
    all.extend_from_slice(args);
    shadelab(d, &all)
}

fn put_user_files(out: &Path) {
    for (name, bytes) in USER_FILES {
        let path = out.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
}

fn assert_user_files(out: &Path, what: &str) {
    for (name, bytes) in USER_FILES {
        let got = std::fs::read(out.join(name))
            .unwrap_or_else(|e| panic!("{what}: {name} is gone ({e})"));
        assert_eq!(got, bytes, "{what}: {name} changed");
    }
    // The manifest lists what shadelab wrote, never the user's files.
    let manifest = std::fs::read_to_string(out.join(shadelab_io::MANIFEST)).unwrap();
    let listed: serde_json::Value = serde_json::from_str(&manifest).unwrap();
    let files = listed["files"].as_array().unwrap();
    assert!(!files.is_empty(), "{what}: {manifest}");
    for (name, _) in USER_FILES {
        assert!(!files.iter().any(|f| f == name), "{what}: {name} listed");
    }
}

/// Runs `args` (whose `--out` is `out`) three times: once into a fresh folder, then with the
/// user's files in it, without and with `--force`; the files stay each time.
fn keeps_user_files(d: &Path, out: &str, args: &[&str]) {
    ok(&shadelab(d, args), out);
    put_user_files(&d.join(out));
    ok(&shadelab(d, args), out);
    assert_user_files(&d.join(out), &format!("{out}, second run"));
    ok(&shadelab(d, &[&["--force"][..], args].concat()), out);
    assert_user_files(&d.join(out), &format!("{out}, --force"));
}

fn render_sphere(d: &Path) {
    ok(
        &quiet(
            d,
            false,
            &[
                "render", "sphere", "--size", "32", "--light", "front", "--out", "s.png",
            ],
        ),
        "render",
    );
}

#[test]
fn solve_keeps_the_users_files_and_its_inputs() {
    let d = scratch("keep-solve");
    render_sphere(&d);
    let solve = |image: &str, mask: &str, force: bool| {
        let args = [
            "solve", image, "--mask", mask, "--light", "front", "--out", "sfs",
        ];
        quiet(&d, force, &args)
    };
    keeps_user_files(
        &d,
        "sfs",
        &[
            "--quiet",
            "solve",
            "s.png",
            "--mask",
            "s_mask.png",
            "--light",
            "front",
            "--out",
            "sfs",
        ],
    );
    // The picture and its mask put into the output folder and solved from there: read, kept.
    for f in ["s.png", "s_mask.png", "s.json"] {
        std::fs::copy(d.join(f), d.join("sfs").join(f)).unwrap();
    }
    let before = std::fs::read(d.join("sfs/s.png")).unwrap();
    for force in [false, true] {
        ok(
            &solve("sfs/s.png", "sfs/s_mask.png", force),
            "solve from inside",
        );
        assert_eq!(std::fs::read(d.join("sfs/s.png")).unwrap(), before);
        assert!(d.join("sfs/s_mask.png").exists() && d.join("sfs/s.json").exists());
        assert_user_files(&d.join("sfs"), "solve from inside");
    }
    // An input that the previous run wrote (its depth picture) would be replaced: refused
    // before any work, naming both, and nothing changes.
    let depth = std::fs::read(d.join("sfs/depth.png")).unwrap();
    let report = std::fs::read(d.join("sfs/report.json")).unwrap();
    let out = solve("sfs/depth.png", "s_mask.png", false);
    assert_error(&out, 1, "sfs/depth.png");
    assert!(String::from_utf8_lossy(&out.stderr).contains("output folder sfs"));
    assert_eq!(std::fs::read(d.join("sfs/depth.png")).unwrap(), depth);
    assert_eq!(std::fs::read(d.join("sfs/report.json")).unwrap(), report);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_analyses_keep_the_users_files() {
    let d = scratch("keep-analyses");
    for (out, args) in [
        (
            "sweep",
            vec![
                "analyze",
                "prior-sweep",
                "--stimulus",
                "bumps",
                "--size",
                "32",
                "--tilts",
                "0:360:90",
            ],
        ),
        (
            "obs",
            vec![
                "analyze",
                "observer",
                "--stimulus",
                "bumps",
                "--size",
                "32",
                "--rotations",
                "0,180",
            ],
        ),
        (
            "outline",
            vec![
                "analyze",
                "outline",
                "--stimulus",
                "boundary-strips",
                "--size",
                "64x32",
            ],
        ),
        (
            "lightness",
            vec![
                "analyze",
                "lightness",
                "--stimulus",
                "checker-shadow",
                "--ppd",
                "6",
                "--model",
                "retinex",
            ],
        ),
        (
            "fading",
            vec![
                "analyze",
                "fading",
                "--stimulus",
                "fading-disk",
                "--ppd",
                "8",
                "--duration",
                "1",
            ],
        ),
    ] {
        let with_out: Vec<&str> = [&["--quiet"][..], &args[..], &["--out", out]].concat();
        keeps_user_files(&d, out, &with_out);
        // The same stimulus rendered into the output folder and analysed from there: the
        // picture, its sidecar and its mask are read, and kept.
        let at = args.iter().position(|a| *a == "--stimulus").unwrap();
        let name = args[at + 1];
        let picture = format!("{out}/pic.png");
        let mut render = vec!["--quiet", "render", name, "--out", &picture];
        let mut from_file = vec!["--quiet", args[0], args[1], &picture];
        let mut rest = args[2..].iter();
        while let Some(&flag) = rest.next() {
            match flag {
                "--stimulus" => {
                    rest.next();
                }
                "--size" | "--ppd" => {
                    let value = rest.next().unwrap();
                    render.extend([flag, value]);
                    if flag == "--ppd" {
                        from_file.extend([flag, value]);
                    }
                }
                other => from_file.push(other),
            }
        }
        from_file.extend(["--out", out]);
        ok(&shadelab(&d, &render), &format!("render into {out}"));
        let bytes = std::fs::read(d.join(&picture)).unwrap();
        // (A rendered fading disk is the blurred disk; its sharp twin is rendered from its
        // record.)
        ok(&shadelab(&d, &from_file), &format!("{out} from inside"));
        assert_eq!(std::fs::read(d.join(&picture)).unwrap(), bytes, "{out}");
        assert!(d.join(out).join("pic.json").exists() && d.join(out).join("pic_mask.png").exists());
        assert_user_files(&d.join(out), &format!("{out} from inside"));
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn fit_study_gallery_and_eval_keep_the_users_files() {
    let d = scratch("keep-fit-study");
    // fit: the responses CSV lies in the output folder of an earlier fit (issue 38's case).
    let m = shadelab::pipeline::fit::ModelParams {
        tilt_deg: 26.0,
        kappa: 2.0,
        convexity_prior: 0.5,
        lapse: 0.02,
    };
    let rotations: Vec<f64> = (0..8).map(|k| k as f64 * 45.0).collect();
    let csv = shadelab::pipeline::fit::simulated_responses(&m, &rotations, 10, 1, "p01");
    std::fs::write(d.join("r.csv"), &csv).unwrap();
    keeps_user_files(
        &d,
        "fit2",
        &[
            "--quiet",
            "fit",
            "observer",
            "r.csv",
            "--include-simulated",
            "--out",
            "fit2",
        ],
    );
    std::fs::write(d.join("fit2/p01.csv"), &csv).unwrap();
    for force in [false, true] {
        let args = [
            "fit",
            "observer",
            "fit2/p01.csv",
            "--include-simulated",
            "--out",
            "fit2",
        ];
        ok(&quiet(&d, force, &args), "fit from inside");
        assert_eq!(
            std::fs::read_to_string(d.join("fit2/p01.csv")).unwrap(),
            csv
        );
        assert!(d.join("fit2/fit.json").exists());
    }

    // study run and merge.
    let spec = r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": 1},
        "shape": [24, 24], "ppd": 12}], "tilts": "0:360:90", "slants": [45],
        "priors": {"kappa": [2]}, "rotations": "0"}"#;
    std::fs::write(d.join("spec.json"), spec).unwrap();
    keeps_user_files(
        &d,
        "st",
        &["--quiet", "study", "run", "spec.json", "--out", "st"],
    );
    std::fs::copy(d.join("spec.json"), d.join("st/spec.json")).unwrap();
    ok(
        &quiet(&d, false, &["study", "run", "st/spec.json", "--out", "st"]),
        "study from inside",
    );
    assert_eq!(
        std::fs::read_to_string(d.join("st/spec.json")).unwrap(),
        spec
    );
    for i in 0..2 {
        ok(
            &quiet(
                &d,
                false,
                &[
                    "study",
                    "run",
                    "spec.json",
                    "--shard",
                    &format!("{i}/2"),
                    "--out",
                    &format!("shard{i}"),
                ],
            ),
            "shard",
        );
    }
    keeps_user_files(
        &d,
        "merged",
        &[
            "--quiet", "study", "merge", "shard0", "shard1", "--out", "merged",
        ],
    );
    // A shard folder is never the merge's output.
    let out = shadelab(
        &d,
        &["study", "merge", "shard0", "shard1", "--out", "shard0"],
    );
    assert_error(&out, 2, "shard0");
    assert!(d.join("shard0/results.csv").exists());

    // gallery, on two presets.
    let presets = d.join("presets");
    std::fs::create_dir(&presets).unwrap();
    for name in ["bumps", "crater"] {
        let stimuli = Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli");
        std::fs::copy(
            stimuli.join(format!("{name}.json")),
            presets.join(format!("{name}.json")),
        )
        .unwrap();
    }
    keeps_user_files(
        &d,
        "g",
        &["--quiet", "gallery", "--presets", "presets", "--out", "g"],
    );
    // Presets kept in a folder of the user's inside the gallery: read, and kept.
    std::fs::create_dir(d.join("g/mine")).unwrap();
    std::fs::copy(presets.join("bumps.json"), d.join("g/mine/bumps.json")).unwrap();
    let mine = std::fs::read(d.join("g/mine/bumps.json")).unwrap();
    ok(
        &quiet(&d, false, &["gallery", "--presets", "g/mine", "--out", "g"]),
        "gallery from inside",
    );
    assert_eq!(std::fs::read(d.join("g/mine/bumps.json")).unwrap(), mine);
    assert!(d.join("g/bumps.json").exists() && !d.join("g/crater.json").exists());
    assert_user_files(&d.join("g"), "gallery from inside");

    // eval, on a bunny folder made from the test mesh (its data read from inside the output
    // folder the second time).
    let bunny = d.join("ev/data/bunny");
    std::fs::create_dir_all(&bunny).unwrap();
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bun_zipper_res3.ply");
    std::fs::copy(&mesh, bunny.join("bun_zipper_res2.ply")).unwrap();
    let eval = [
        "--quiet",
        "eval",
        "--data",
        "ev/data",
        "--only",
        "bunny",
        "--bunny-size",
        "24",
        "--method",
        "multigrid",
        "--boundary",
        "occluding",
        "--out",
        "ev",
    ];
    // The folder holds the data (not shadelab's): the first run needs --force.
    let first = shadelab(&d, &eval);
    assert_error(&first, 1, "was not written by shadelab");
    let forced: Vec<&str> = [&["--force"][..], &eval[..]].concat();
    ok(&shadelab(&d, &forced), "eval forced");
    put_user_files(&d.join("ev"));
    ok(&shadelab(&d, &eval), "eval again");
    assert_user_files(&d.join("ev"), "eval");
    assert_eq!(
        std::fs::read(bunny.join("bun_zipper_res2.ply")).unwrap(),
        std::fs::read(&mesh).unwrap()
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn an_experiment_with_collected_responses_is_refused_unless_forced_and_they_stay() {
    let d = scratch("keep-experiment");
    let args = [
        "--quiet",
        "experiment",
        "--rotations",
        "0,90,180,270",
        "--repeats",
        "1",
        "--practice",
        "0",
        "--out",
        "exp",
        "--no-install",
    ];
    ok(&shadelab(&d, &args), "experiment");
    let design: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("exp/design.json")).unwrap()).unwrap();
    let hash = design["design_hash"].as_str().unwrap().to_string();
    assert_eq!(hash.len(), 16, "{hash}");
    assert!(design["model"]["responses_csv"]
        .as_str()
        .unwrap()
        .ends_with(",design_hash,simulated"));
    // The runner writes each row's design hash from the design (the header and the field).
    let js = std::fs::read_to_string(d.join("exp/shadelab-timeline.js")).unwrap();
    assert!(js.contains("design_hash: design.design_hash"), "{js}");
    // Written again with nothing collected: fine.
    ok(&shadelab(&d, &args), "experiment again");
    // A participant's responses saved into the folder.
    let responses = format!(
        "participant,trial,block,stimulus,rotation_deg,response,rt_ms,key,image,design_hash\n\
         p01,1,test,bumps,0,convex,512,f,images/theta-000.png,{hash}\n"
    );
    std::fs::write(d.join("exp/responses.csv"), &responses).unwrap();
    std::fs::create_dir(d.join("exp/data")).unwrap();
    std::fs::write(d.join("exp/data/p02.csv"), "x").unwrap();
    let before = std::fs::read(d.join("exp/design.json")).unwrap();
    // A changed design beside them: refused, naming how many and which, nothing written.
    let mut changed = args.to_vec();
    changed[3] = "0,180";
    let out = shadelab(&d, &changed);
    assert_error(&out, 1, "holds 2 files");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("responses.csv") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(std::fs::read(d.join("exp/design.json")).unwrap(), before);
    // Forced: the new design, and the responses kept byte for byte; the message says where.
    let forced: Vec<&str> = [&["--quiet", "--force"][..], &changed[1..]].concat();
    let out = shadelab(&d, &forced);
    ok(&out, "forced");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("kept 2 file(s) in exp") && err.contains("data/p02.csv"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(d.join("exp/responses.csv")).unwrap(),
        responses
    );
    assert_eq!(
        std::fs::read_to_string(d.join("exp/data/p02.csv")).unwrap(),
        "x"
    );
    let design: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("exp/design.json")).unwrap()).unwrap();
    assert_ne!(design["design_hash"].as_str().unwrap(), hash);
    assert_eq!(design["rotations_deg"].as_array().unwrap().len(), 2);
    // The old design's images that the new one does not use are gone (they were shadelab's).
    assert!(!d.join("exp/images/theta-090.png").exists());
    assert!(d.join("exp/images/theta-180.png").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[cfg(unix)]
#[test]
fn a_link_to_a_folder_is_followed_and_a_broken_link_is_named() {
    let d = scratch("keep-link");
    render_sphere(&d);
    std::fs::create_dir(d.join("real")).unwrap();
    std::os::unix::fs::symlink("real", d.join("plink")).unwrap();
    std::fs::write(d.join("real/mine.txt"), "mine").unwrap();
    for force in [true, false] {
        // Forced the first time: the folder is not shadelab's yet.
        let args = ["solve", "s.png", "--light", "front", "--out", "plink"];
        ok(&quiet(&d, force, &args), "solve into a link");
        assert!(d.join("real/report.json").exists());
        assert!(std::fs::symlink_metadata(d.join("plink"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(
            std::fs::read_to_string(d.join("real/mine.txt")).unwrap(),
            "mine"
        );
    }
    std::os::unix::fs::symlink("nowhere", d.join("broken")).unwrap();
    let out = quiet(
        &d,
        false,
        &["solve", "s.png", "--light", "front", "--out", "broken"],
    );
    assert_error(
        &out,
        1,
        "broken: is a link to nowhere, which does not exist",
    );
    std::fs::write(d.join("file.txt"), "x").unwrap();
    std::os::unix::fs::symlink("file.txt", d.join("flink")).unwrap();
    let out = quiet(
        &d,
        false,
        &["solve", "s.png", "--light", "front", "--out", "flink"],
    );
    assert_error(&out, 1, "which is not a folder");
    assert_eq!(std::fs::read_to_string(d.join("file.txt")).unwrap(), "x");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn numbers_out_of_range_and_diverging_runs_write_nothing() {
    let d = scratch("keep-ranges");
    render_sphere(&d);
    let solve = |extra: &[&str]| {
        let mut args = vec![
            "--quiet", "solve", "s.png", "--light", "front", "--out", "o",
        ];
        args.extend_from_slice(extra);
        shadelab(&d, &args)
    };
    for (extra, needle) in [
        (
            &["--lambda", "1e300"][..],
            "--lambda: lambda = 1e300 is outside 1e-3..1e3",
        ),
        (&["--lambda", "1e-4"], "--lambda: lambda = 1e-4 is outside"),
        (&["--lambda", "nan"], "--lambda"),
        (&["--tol", "1"], "--tol: tol = 1e0 is outside 1e-12..1e-1"),
        (
            &["--max-iter", "0"],
            "--max-iter: max_iter = 0 is outside 1..10000000",
        ),
    ] {
        assert_error(&solve(extra), 2, needle);
        assert!(!d.join("o").exists(), "{extra:?}");
    }
    // λ at both ends of the range converges (multigrid, the default) on the sphere and the
    // vase under an oblique light, with their masks.
    for object in ["sphere", "vase"] {
        let light = "tilt=30,slant=40";
        let picture = format!("{object}.png");
        let render = [
            "--quiet", "render", object, "--size", "64", "--light", light, "--out", &picture,
        ];
        ok(&shadelab(&d, &render), object);
        let mask = format!("{object}_mask.png");
        for lambda in ["1e-3", "1e3"] {
            let out_dir = format!("{object}-{lambda}");
            let args = [
                "--quiet", "solve", &picture, "--mask", &mask, "--light", light, "--lambda",
                lambda, "--out", &out_dir,
            ];
            let out = shadelab(&d, &args);
            ok(&out, &out_dir);
            let stdout = String::from_utf8_lossy(&out.stdout);
            assert!(stdout.starts_with("converged"), "{out_dir}: {stdout}");
        }
    }
    // Jacobi sweeps diverge at a λ multigrid takes: exit 1, the flag to change, nothing written.
    let out = solve(&["--method", "jacobi", "--lambda", "30"]);
    assert_error(&out, 1, "the jacobi iteration diverged");
    assert!(String::from_utf8_lossy(&out.stderr).contains("(--lambda)"));
    assert!(!d.join("o").exists());
    // Other flags name themselves.
    for (args, needle) in [
        (
            vec![
                "analyze",
                "observer",
                "--stimulus",
                "bumps",
                "--noise",
                "1e300",
                "--out",
                "o",
            ],
            "--noise: noise 1e300 is outside 0..1",
        ),
        (
            vec![
                "analyze",
                "outline",
                "--stimulus",
                "boundary-strips",
                "--lambda",
                "1e9",
                "--out",
                "o",
            ],
            "--lambda: lambda = 1e9 is outside 0..1e3",
        ),
        (
            vec!["render", "sphere", "--size", "0", "--out", "o.png"],
            "--size '0': both sides must be positive",
        ),
        (
            vec!["render", "sphere", "--visual-size", "-2", "--out", "o.png"],
            "--visual-size",
        ),
        (
            vec!["render", "sphere", "--range", "psychopy", "--out", "o.png"],
            "--range: range psychopy",
        ),
        (
            vec!["render", "sphere", "--gamma", "2.2", "--out", "o.npy"],
            "--gamma: a display gamma",
        ),
        (
            vec!["experiment", "--repeats", "0", "--out", "o"],
            "--repeats: repeats 0",
        ),
        (
            vec!["experiment", "--ppd", "0", "--out", "o"],
            "--ppd: pixels per degree 0",
        ),
    ] {
        assert_error(&shadelab(&d, &args), 2, needle);
        assert!(
            !d.join("o").exists() && !d.join("o.png").exists(),
            "{args:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn rim_normals_facing_away_are_refused_naming_the_file() {
    let d = scratch("keep-normals");
    render_sphere(&d);
    // Normals facing away from the viewer everywhere: (0, 0, -1).
    let normals = shadelab::Grid::new(32, 32, nalgebra::Vector3::new(0.0, 0.0, -1.0));
    shadelab_io::write_normals(&d.join("back_normals.npy"), &normals).unwrap();
    let out = quiet(
        &d,
        false,
        &[
            "solve",
            "s.png",
            "--mask",
            "s_mask.png",
            "--light",
            "front",
            "--boundary",
            "back_normals.npy",
            "--out",
            "o",
        ],
    );
    assert_error(&out, 1, "back_normals.npy: boundary normal at column");
    assert!(String::from_utf8_lossy(&out.stderr).contains("faces away from the viewer"));
    assert!(!d.join("o").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_render_never_replaces_the_spec_it_reads() {
    let d = scratch("keep-spec");
    let preset = Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli/bumps.json");
    std::fs::copy(&preset, d.join("my.json")).unwrap();
    let spec = std::fs::read(d.join("my.json")).unwrap();
    for force in [false, true] {
        let args = ["render", "--spec", "my.json", "--out", "my.png"];
        let out = quiet(&d, force, &args);
        assert_error(&out, 1, "my.json: is the spec this render reads");
        assert_eq!(std::fs::read(d.join("my.json")).unwrap(), spec);
        assert!(!d.join("my.png").exists());
    }
    // Under another name it renders, and its own sidecar re-renders the same set.
    ok(
        &quiet(
            &d,
            false,
            &["render", "--spec", "my.json", "--out", "b.png"],
        ),
        "spec",
    );
    let png = std::fs::read(d.join("b.png")).unwrap();
    ok(
        &quiet(&d, false, &["render", "--spec", "b.json", "--out", "b.png"]),
        "sidecar",
    );
    assert_eq!(std::fs::read(d.join("b.png")).unwrap(), png);
    let _ = std::fs::remove_dir_all(&d);
}
