//! The Python package (`python/`, docs/python.md): builds its wheel with maturin and runs its
//! pytest suite (`python/tests`) inside `cargo test --release`, so the README's one test
//! command covers it.
//!
//! A virtual environment (`target/python/venv/`, with maturin, NumPy and pytest installed by
//! pip) and the wheel (`target/python/wheels/`), built from the sdist as pip builds it: `maturin
//! sdist`, unpacked into `target/python/sdist/tree/` (only the files that changed are written, so
//! cargo rebuilds no more than it would from python/), and `maturin build` there; a file the
//! sdist lacks fails the build here, not in a user's `pip install`. The wheel is compiled in the
//! root's own target directory: the binding is a member of the root workspace, with its one lock
//! file, so the dependencies are compiled once for both;
//! `cargo test` releases the directory's lock before it runs the tests. The suite runs twice:
//! from python/tests (beside `../shared`'s data) in that venv, and from the sdist's own tests
//! in a clean venv without Rust (below). Where Python ≥ 3.9, its `venv` module or pip's packages
//! cannot be had (no network), the test says why on stderr and passes; with
//! `SHADELAB_REQUIRE_PYTHON=1` (set by `.ci/run` once it has installed them) it fails instead.
//! `SHADELAB_PYTHON` names the interpreter (default `python3`).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The repository root.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The root build's target directory (`CARGO_TARGET_DIR` where set, as cargo reads it).
fn cargo_target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) if !dir.is_empty() => root().join(dir),
        _ => root().join("target"),
    }
}

/// Skips with `why` (stderr), or fails when Python is required.
fn skip(why: &str) {
    if std::env::var("SHADELAB_REQUIRE_PYTHON").is_ok_and(|v| v == "1") {
        panic!("python test cannot run, and SHADELAB_REQUIRE_PYTHON=1: {why}");
    }
    eprintln!("python test SKIPPED: {why}");
}

/// Runs `cmd`, returning its output, or `None` when it cannot be started.
fn run(cmd: &mut Command) -> Option<Output> {
    cmd.output().ok()
}

fn text(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

/// The venv's interpreter.
fn venv_python(venv: &Path) -> PathBuf {
    if cfg!(windows) {
        venv.join("Scripts").join("python.exe")
    } else {
        venv.join("bin").join("python")
    }
}

#[test]
fn the_python_package_builds_and_its_pytest_suite_passes() {
    let root = root();
    let dir = root.join("target").join("python");
    let python = std::env::var("SHADELAB_PYTHON").unwrap_or_else(|_| "python3".into());
    let version =
        run(Command::new(&python).args(["-c", "import sys; print(sys.version_info >= (3, 9))"]));
    match &version {
        Some(out) if out.status.success() && text(out).trim() == "True" => {}
        Some(out) if out.status.success() => {
            return skip(&format!("{python} is older than Python 3.9"));
        }
        _ => return skip(&format!("no Python interpreter '{python}' on PATH")),
    }

    // The environment: created once, then reused (pip answers from what is installed).
    let venv = dir.join("venv");
    let py = venv_python(&venv);
    if !py.exists() {
        let made = run(Command::new(&python).arg("-m").arg("venv").arg(&venv));
        if !made.as_ref().is_some_and(|o| o.status.success()) {
            let why = made.as_ref().map(text).unwrap_or_default();
            let _ = std::fs::remove_dir_all(&venv);
            return skip(&format!(
                "'{python} -m venv' failed (Debian: apt-get install python3-venv): {}",
                why.trim()
            ));
        }
    }
    // nbclient, nbformat and ipykernel run the tutorial notebook (python/examples/).
    let have = run(Command::new(&py).args([
        "-c",
        "import maturin, numpy, pytest, nbclient, nbformat, ipykernel",
    ]));
    if !have.is_some_and(|o| o.status.success()) {
        let pip = run(Command::new(&py).args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "maturin>=1.14,<2",
            "numpy",
            "pytest",
            "nbclient",
            "nbformat",
            "ipykernel",
        ]));
        if !pip.as_ref().is_some_and(|o| o.status.success()) {
            let why = pip.as_ref().map(text).unwrap_or_default();
            return skip(&format!(
                "pip could not install maturin, numpy, pytest, nbclient and ipykernel into {} (no network?): {}",
                venv.display(),
                why.trim().lines().last().unwrap_or("")
            ));
        }
    }

    // The wheel, built from the sdist incrementally beside the root crate's release build.
    let tree = sdist_tree(&py, &dir);
    let wheels = dir.join("wheels");
    let _ = std::fs::remove_dir_all(&wheels);
    let build = Command::new(&py)
        .args(["-m", "maturin", "build", "--release", "--quiet", "--out"])
        .arg(&wheels)
        .current_dir(&tree)
        .env("CARGO_TARGET_DIR", cargo_target_dir())
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .output()
        .expect("maturin runs");
    assert!(
        build.status.success(),
        "maturin could not build the wheel from the sdist ({}):\n{}",
        tree.display(),
        text(&build)
    );
    let wheel = written(&wheels, ".whl");
    let install = pip_install(&py, &["--no-deps", "--force-reinstall"], &wheel)
        .output()
        .expect("pip runs");
    assert!(
        install.status.success(),
        "pip could not install {}:\n{}",
        wheel.display(),
        text(&install)
    );

    let summary = pytest_suite(&py, &dir, &root.join("python").join("tests"), &mut |_| {});
    eprintln!("python: {summary}");

    the_wheel_installs_and_passes_without_rust(&python, &dir, &wheel, &tree);
}

/// The file whose name ends with `suffix` that maturin wrote into `folder`.
fn written(folder: &Path, suffix: &str) -> PathBuf {
    std::fs::read_dir(folder)
        .unwrap_or_else(|e| panic!("{}: {e}", folder.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.to_string_lossy().ends_with(suffix))
        .unwrap_or_else(|| panic!("maturin wrote no {suffix} into {}", folder.display()))
}

/// Unpacks the sdist into `tree` as pip would, but writing only the files whose bytes changed
/// and removing those the sdist no longer has, so that cargo (which compares modification
/// times) rebuilds from `tree` exactly what changed. Fails on a link or any entry that is not a
/// plain file: pip on another system gets the sdist's bytes, not a link into this checkout.
const UNPACK: &str = r#"
import os, sys, tarfile
archive, tree = sys.argv[1], os.path.abspath(sys.argv[2])
kept = set()
with tarfile.open(archive) as tar:
    for m in tar.getmembers():
        if m.isdir():
            continue
        if not m.isfile():
            sys.exit(f"{archive}: {m.name} is a link or a special file, not a file")
        rel = m.name.split("/", 1)[1]
        path = os.path.normpath(os.path.join(tree, rel))
        if not path.startswith(tree + os.sep):
            sys.exit(f"{archive}: {m.name} lies outside the sdist's folder")
        data = tar.extractfile(m).read()
        kept.add(path)
        if os.path.isfile(path):
            with open(path, "rb") as f:
                if f.read() == data:
                    continue
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as f:
            f.write(data)
for folder, _, files in os.walk(tree):
    for name in files:
        if os.path.join(folder, name) not in kept:
            os.remove(os.path.join(folder, name))
print(len(kept))
"#;

/// `maturin sdist` of python/ into `dir/sdist/`, unpacked into `dir/sdist/tree/` ([`UNPACK`]);
/// returns the tree, whose root holds the sdist's pyproject.toml.
fn sdist_tree(py: &Path, dir: &Path) -> PathBuf {
    let out = dir.join("sdist");
    let archives = out.join("dist");
    let _ = std::fs::remove_dir_all(&archives);
    let sdist = Command::new(py)
        .args(["-m", "maturin", "sdist", "--out"])
        .arg(&archives)
        .current_dir(root().join("python"))
        .output()
        .expect("maturin runs");
    assert!(
        sdist.status.success(),
        "maturin could not build the sdist:\n{}",
        text(&sdist)
    );
    let archive = written(&archives, ".tar.gz");
    let tree = out.join("tree");
    let unpack = Command::new(py)
        .args(["-c", UNPACK])
        .arg(&archive)
        .arg(&tree)
        .output()
        .expect("python runs");
    assert!(unpack.status.success(), "{}", text(&unpack));
    eprintln!(
        "python: {} ({} bytes, {} files)",
        archive.display(),
        std::fs::metadata(&archive).expect("the sdist").len(),
        String::from_utf8_lossy(&unpack.stdout).trim()
    );
    tree
}

/// The largest wheel users are asked to download (issue 40: 10 MB).
const MAX_WHEEL_BYTES: u64 = 10 * 1000 * 1000;

/// PATH without any folder holding a Rust toolchain (cargo, rustc, rustup).
fn path_without_rust() -> std::ffi::OsString {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let kept: Vec<PathBuf> = std::env::split_paths(&path)
        .filter(|d| {
            !["cargo", "rustc", "rustup"]
                .iter()
                .any(|t| d.join(t).exists())
        })
        .collect();
    std::env::join_paths(kept).expect("PATH entries join")
}

/// The wheel as a user gets it: a fresh venv with only NumPy and pytest, no Rust toolchain on
/// PATH (so nothing can compile), the wheel installed by pip, and the sdist's own pytest suite
/// (`tree`, where the tests find the pages they read as a lab unpacking the sdist does) run
/// against it. Also the wheel's size (at most [`MAX_WHEEL_BYTES`]) and its metadata, the
/// description python/README.md's.
fn the_wheel_installs_and_passes_without_rust(python: &str, dir: &Path, wheel: &Path, tree: &Path) {
    let bytes = std::fs::metadata(wheel).expect("the wheel").len();
    assert!(
        bytes <= MAX_WHEEL_BYTES,
        "{} is {bytes} bytes; a wheel is at most {MAX_WHEEL_BYTES}",
        wheel.display()
    );
    let name = wheel.file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        name.contains("-cp39-abi3-"),
        "one wheel for CPython >= 3.9: {name}"
    );
    let path = path_without_rust();
    let clean = dir.join("clean-venv");
    let _ = std::fs::remove_dir_all(&clean);
    let made = Command::new(python)
        .args(["-m", "venv"])
        .arg(&clean)
        .env("PATH", &path)
        .output()
        .expect("venv runs");
    assert!(made.status.success(), "{}", text(&made));
    let py = venv_python(&clean);
    let pip = pip_install(&py, &["numpy"], Path::new("pytest"))
        .env("PATH", &path)
        .output()
        .expect("pip runs");
    if !pip.status.success() {
        return skip(&format!(
            "pip could not install numpy and pytest into a clean venv (no network?): {}",
            text(&pip).trim().lines().last().unwrap_or("")
        ));
    }
    let install = pip_install(&py, &["--only-binary", ":all:"], wheel)
        .env("PATH", &path)
        .env_remove("CARGO_HOME")
        .env_remove("RUSTUP_HOME")
        .output()
        .expect("pip runs");
    assert!(
        install.status.success(),
        "the wheel did not install:\n{}",
        text(&install)
    );
    // No toolchain could have been used, and the package's metadata is what an index shows.
    let probe = Command::new(&py)
        .args([
            "-c",
            "import sys, shutil, time, importlib.metadata as m; \
             assert shutil.which('cargo') is None and shutil.which('rustc') is None; \
             t = time.perf_counter(); import shadelab; t = time.perf_counter() - t; \
             md = m.metadata('shadelab'); \
             print(f'import {t * 1000:.0f} ms'); \
             print(md['License-Expression'] or md['License']); \
             text = (md.get_payload() or md['Description'] or '').strip(); \
             readme = open(sys.argv[1], encoding='utf-8').read().strip(); \
             print(len(md.get_all('Classifier') or []), len(md.get_all('Project-URL') or []), \
                   len(text), int(text == readme))",
        ])
        .arg(root().join("python").join("README.md"))
        .env("PATH", &path)
        .current_dir(dir)
        .output()
        .expect("python runs");
    let said = text(&probe);
    assert!(probe.status.success(), "{said}");
    let lines: Vec<&str> = said.lines().collect();
    let counts: Vec<usize> = lines[2].split(' ').map(|n| n.parse().unwrap()).collect();
    assert!(
        // Classifiers and python/README.md as the long description (not the crate's README.md,
        // which sits at the sdist's root beside pyproject.toml); no project URLs until there is
        // a public home (README.md says a release sets them).
        counts[0] >= 5 && counts[2] > 1000 && counts[3] == 1,
        "metadata (classifiers, project URLs, description's length, whether it is python/README.md): {said}"
    );
    let summary = pytest_suite(&py, dir, &tree.join("python").join("tests"), &mut |cmd| {
        // PsychoPy and stimupy live in the build venv only; here their tests say why they skip.
        cmd.env("PATH", &path)
            .env_remove("SHADELAB_REQUIRE_PSYCHOPY")
            .env_remove("SHADELAB_REQUIRE_STIMUPY");
    });
    eprintln!(
        "python, clean venv without Rust: {bytes} bytes wheel, {}; {summary}",
        lines[0]
    );
}

/// `py -m pip install --quiet` with `options` and then `what` (a wheel or a package name).
fn pip_install(py: &Path, options: &[&str], what: &Path) -> Command {
    let mut cmd = Command::new(py);
    cmd.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
    ])
    .args(options)
    .arg(what);
    cmd
}

/// Runs the pytest suite `tests` with `py` from `dir` (outside python/ and the sdist's tree, so
/// that `import shadelab` is the installed wheel), `adjust` setting its environment; fails with
/// pytest's report unless it passes, and returns pytest's summary line.
fn pytest_suite(
    py: &Path,
    dir: &Path,
    tests: &Path,
    adjust: &mut dyn FnMut(&mut Command),
) -> String {
    // PsychoPy keeps its preferences, fonts and monitors under the home folder (~/.psychopy3),
    // matplotlib its caches: the suite runs with a home of its own, so that testing writes
    // nothing into the user's.
    let home = dir.join("home");
    let _ = std::fs::remove_dir_all(&home);
    std::fs::create_dir_all(&home).expect("a scratch home folder");
    let mut cmd = Command::new(py);
    cmd.args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(tests)
        .current_dir(dir)
        .env("HOME", &home)
        .env("PSYCHOPY_USERDIR", home.join(".psychopy3"))
        // `shadelab.save` is compared byte for byte with the command line's `render`.
        .env("SHADELAB_BIN", env!("CARGO_BIN_EXE_shadelab"));
    adjust(&mut cmd);
    // What the suite sees of SHADELAB_REQUIRE_PSYCHOPY: set or removed here, else inherited.
    let required = match cmd
        .get_envs()
        .find(|(k, _)| *k == "SHADELAB_REQUIRE_PSYCHOPY")
    {
        Some((_, v)) => v.is_some_and(|v| v == "1"),
        None => std::env::var("SHADELAB_REQUIRE_PSYCHOPY").as_deref() == Ok("1"),
    };
    let pytest = cmd.output().expect("pytest runs");
    let report = text(&pytest);
    assert!(
        pytest.status.success(),
        "the pytest suite failed with {}:\n{report}",
        py.display()
    );
    if required {
        // The window test ran (it fails rather than skips when PsychoPy is required): its
        // preferences went to the scratch home.
        assert!(
            home.join(".psychopy3").is_dir(),
            "PsychoPy ran but wrote no ~/.psychopy3 under the suite's home {}: where did it write?",
            home.display()
        );
    }
    let summary = report.lines().rev().find(|l| l.contains("passed"));
    summary.unwrap_or("pytest passed").to_string()
}
