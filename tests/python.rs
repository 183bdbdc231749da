//! The Python package (`python/`, docs/python.md): builds its wheel with maturin and runs its
//! pytest suite (`python/tests`) inside `cargo test --release`, so the README's one test
//! command covers it.
//!
//! A virtual environment (`target/python/venv/`, with maturin, NumPy and pytest installed by
//! pip) and the wheel (`target/python/wheels/`). The wheel is compiled in the root's own target
//! directory: its dependencies are the root crate's, at the versions of the root's lock file
//! (python/Cargo.lock keeps them equal), so they are compiled once for both; `cargo test`
//! releases the directory's lock before it runs the tests. Where Python ≥ 3.9, its `venv` module or pip's packages
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
    let have = run(Command::new(&py).args(["-c", "import maturin, numpy, pytest"]));
    if !have.is_some_and(|o| o.status.success()) {
        let pip = run(Command::new(&py).args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "maturin>=1.5,<2",
            "numpy",
            "pytest",
        ]));
        if !pip.as_ref().is_some_and(|o| o.status.success()) {
            let why = pip.as_ref().map(text).unwrap_or_default();
            return skip(&format!(
                "pip could not install maturin, numpy and pytest into {} (no network?): {}",
                venv.display(),
                why.trim().lines().last().unwrap_or("")
            ));
        }
    }

    // The wheel, built incrementally beside the root crate's release build.
    let wheels = dir.join("wheels");
    let _ = std::fs::remove_dir_all(&wheels);
    let build = Command::new(&py)
        .args(["-m", "maturin", "build", "--release", "--quiet", "--out"])
        .arg(&wheels)
        .current_dir(root.join("python"))
        .env("CARGO_TARGET_DIR", cargo_target_dir())
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .output()
        .expect("maturin runs");
    assert!(
        build.status.success(),
        "maturin could not build the wheel:\n{}",
        text(&build)
    );
    let wheel = std::fs::read_dir(&wheels)
        .expect("the wheels folder")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|e| e == "whl"))
        .expect("maturin wrote a wheel");
    let install = Command::new(&py)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "--no-deps",
            "--force-reinstall",
        ])
        .arg(&wheel)
        .output()
        .expect("pip runs");
    assert!(
        install.status.success(),
        "pip could not install {}:\n{}",
        wheel.display(),
        text(&install)
    );

    // The suite, from outside python/ so that `import shadelab` is the installed wheel.
    let pytest = Command::new(&py)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root.join("python").join("tests"))
        .current_dir(&dir)
        // `shadelab.save` is compared byte for byte with the command line's `render`.
        .env("SHADELAB_BIN", env!("CARGO_BIN_EXE_shadelab"))
        .output()
        .expect("pytest runs");
    let report = text(&pytest);
    assert!(
        pytest.status.success(),
        "the pytest suite failed:\n{report}"
    );
    let summary = report.lines().rev().find(|l| l.contains("passed"));
    eprintln!("python: {}", summary.unwrap_or("pytest passed"));
}
