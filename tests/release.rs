//! One version (docs/releasing.md): the workspace's `Cargo.toml` sets it, and everything that
//! carries a version says the same: every member's manifest (each inherits it), the one lock
//! file, the wheel (pyproject.toml takes it from the binding's manifest), CITATION.cff and its release date, the changelog, the program's
//! `--version`, a sidecar, the PNG's `Software` text, a report, and the pages that show a
//! version as an example of what shadelab writes.

use crate::cli::{scratch, shadelab};
use std::path::{Path, PathBuf};

const VERSION: &str = env!("CARGO_PKG_VERSION");

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &str) -> String {
    let p = root().join(path);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The lines of a TOML file's `[section]` table, up to the next table.
fn table<'a>(toml: &'a str, section: &str) -> Vec<&'a str> {
    toml.lines()
        .skip_while(|l| l.trim() != section)
        .skip(1)
        .take_while(|l| !l.trim_start().starts_with('['))
        .collect()
}

/// The quoted value of `key = "value"` among `lines`, if there is one.
fn quoted<'a>(lines: &[&'a str], key: &str) -> Option<&'a str> {
    lines.iter().find_map(|l| {
        let (k, v) = l.split_once('=')?;
        (k.trim() == key).then(|| v.trim().trim_matches('"'))
    })
}

/// The version a Cargo.lock records for the package `name`.
fn locked(lock: &str, name: &str) -> Option<String> {
    let mut lines = lock.lines();
    while let Some(l) = lines.next() {
        if l.trim() == format!("name = \"{name}\"") {
            let v = lines.next()?;
            return quoted(&[v], "version").map(str::to_string);
        }
    }
    None
}

/// Every version-like token (`1.2.3`) that follows `prefix` in `text`.
fn versions_after(text: &str, prefix: &str) -> Vec<String> {
    text.match_indices(prefix)
        .filter_map(|(i, _)| {
            let rest = &text[i + prefix.len()..];
            let token: String = rest
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            let token = token.trim_end_matches('.').to_string();
            (token.split('.').count() == 3 && token.split('.').all(|p| !p.is_empty()))
                .then_some(token)
        })
        .collect()
}

#[test]
fn every_manifest_lock_and_citation_carries_the_crates_version() {
    // The workspace sets the version once; every member inherits it, and the one lock file
    // records it for each of them.
    let root_manifest = read("Cargo.toml");
    assert_eq!(
        quoted(&table(&root_manifest, "[workspace.package]"), "version"),
        Some(VERSION),
        "the workspace's version"
    );
    // Each floor as the others name it: a path with the same version (crates.io needs both).
    let floors: Vec<&str> = table(&root_manifest, "[workspace.dependencies]")
        .into_iter()
        .filter(|l| l.starts_with("shadelab-"))
        .collect();
    assert_eq!(floors.len(), 6, "the workspace names its six floors");
    for floor in floors {
        assert!(
            floor.contains(&format!("version = \"{VERSION}\"")),
            "the workspace's dependency {floor}"
        );
    }
    let lock = read("Cargo.lock");
    let members = [
        ("Cargo.toml", "shadelab"),
        ("crates/core/Cargo.toml", "shadelab-core"),
        ("crates/io/Cargo.toml", "shadelab-io"),
        ("crates/engine/Cargo.toml", "shadelab-engine"),
        ("crates/stimuli/Cargo.toml", "shadelab-stimuli"),
        ("crates/analysis/Cargo.toml", "shadelab-analysis"),
        ("crates/commands/Cargo.toml", "shadelab-commands"),
        ("python/Cargo.toml", "shadelab-python"),
        ("web/engine/Cargo.toml", "shadelab-web"),
    ];
    for (manifest, name) in members {
        let text = read(manifest);
        let package = table(&text, "[package]");
        assert!(
            package
                .iter()
                .any(|l| l.trim() == "version.workspace = true"),
            "{manifest} does not inherit the workspace's version"
        );
        assert_eq!(
            quoted(&package, "version"),
            None,
            "{manifest} sets a version"
        );
        assert_eq!(
            locked(&lock, name).as_deref(),
            Some(VERSION),
            "Cargo.lock's {name}"
        );
        assert!(
            root_manifest.contains(&format!("\"{}\"", manifest.trim_end_matches("/Cargo.toml")))
                || manifest == "Cargo.toml",
            "{manifest} is not a member of the workspace"
        );
    }

    // The wheel's version is maturin's reading of python/Cargo.toml: pyproject.toml must not
    // set a second one.
    let py = read("python/pyproject.toml");
    let project = table(&py, "[project]");
    assert_eq!(
        quoted(&project, "version"),
        None,
        "pyproject.toml sets a version"
    );
    assert!(
        project
            .iter()
            .any(|l| l.replace(' ', "") == r#"dynamic=["version"]"#),
        "pyproject.toml's [project] lacks dynamic = [\"version\"]"
    );

    // CITATION.cff cites this version, released on the changelog's date for it.
    let cff = read("CITATION.cff");
    let field = |key: &str| {
        cff.lines()
            .find_map(|l| l.strip_prefix(key))
            .map(|v| v.trim().trim_matches('"').to_string())
    };
    assert_eq!(field("version:").as_deref(), Some(VERSION), "CITATION.cff");
    let changelog = read("CHANGELOG.md");
    // Keep a Changelog's order: `[Unreleased]` first (empty right after a release), then this
    // version's section, the newest released: a release renames `[Unreleased]` to it.
    let sections: Vec<&str> = changelog
        .lines()
        .filter(|l| l.starts_with("## ["))
        .take(2)
        .collect();
    assert!(
        sections.first() == Some(&"## [Unreleased]")
            && sections
                .get(1)
                .is_some_and(|s| s.starts_with(&format!("## [{VERSION}] - "))),
        "CHANGELOG.md's first sections are {sections:?}: '## [Unreleased]', then '## [{VERSION}] - DATE'"
    );
    let heading = format!("## [{VERSION}] - ");
    let date = changelog
        .lines()
        .find_map(|l| l.strip_prefix(heading.as_str()))
        .unwrap_or_else(|| panic!("CHANGELOG.md has no '{heading}DATE' section"));
    assert_eq!(
        field("date-released:").as_deref(),
        Some(date.trim()),
        "CITATION.cff's date-released against CHANGELOG.md"
    );
}

#[test]
fn the_program_its_files_and_the_docs_say_the_crates_version() {
    let d = scratch("release-version");
    let out = shadelab(&d, &["--version"]);
    assert!(out.status.success());
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim(),
        format!("shadelab {VERSION}")
    );

    let out = shadelab(
        &d,
        &[
            "render", "sphere", "--size", "32", "--light", "front", "--out", "s.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("s.json")).unwrap()).unwrap();
    assert_eq!(sidecar["version"], VERSION, "the sidecar");
    let png = std::fs::read(d.join("s.png")).unwrap();
    let png = String::from_utf8_lossy(&png);
    assert_eq!(
        versions_after(&png, "shadelab "),
        [VERSION],
        "the PNG's Software text"
    );

    let out = shadelab(
        &d,
        &[
            "solve",
            "s.png",
            "--mask",
            "s_mask.png",
            "--light",
            "front",
            "--out",
            "solved",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("solved/report.json")).unwrap()).unwrap();
    assert_eq!(report["program"], "shadelab");
    assert_eq!(report["version"], VERSION, "the solve's report");
    let _ = std::fs::remove_dir_all(&d);

    // The pages that show what shadelab writes show this version (records of a measured run,
    // such as docs/benchmark/, keep the version that made them).
    for page in [
        "README.md",
        "python/README.md",
        "docs/display.md",
        "docs/experiments.md",
        "docs/python.md",
        "docs/releasing.md",
    ] {
        let text = read(page);
        for prefix in ["shadelab-", "shadelab ", "\"version\": \""] {
            for v in versions_after(&text, prefix) {
                assert_eq!(v, VERSION, "{page} says {prefix}{v}");
            }
        }
    }
    assert!(Path::new(&root().join("docs/releasing.md")).is_file());
}
