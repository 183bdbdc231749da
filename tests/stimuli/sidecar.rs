//! A sidecar reproduces its render: `render --spec SIDECAR.json` writes the same files, byte
//! for byte, for every gallery preset and for every way of writing (bit depth, gamma, range,
//! layers, formats).

use crate::cli::{files_in, scratch, shadelab};
use std::path::Path;

/// Renders `args` into `first/`, then the sidecar it wrote into `again/` under the same file
/// name, and compares every file of the two folders.
fn reproduces(dir: &Path, name: &str, args: &[&str]) {
    for sub in ["first", "again"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let first = format!("first/{name}");
    let mut full = vec!["--quiet", "render"];
    full.extend_from_slice(args);
    full.extend_from_slice(&["--out", &first]);
    let out = shadelab(dir, &full);
    assert!(
        out.status.success(),
        "{full:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stem = Path::new(name)
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .into_owned();
    let sidecar = format!("first/{stem}.json");
    let again = format!("again/{name}");
    let out = shadelab(
        dir,
        &["--quiet", "render", "--spec", &sidecar, "--out", &again],
    );
    assert!(
        out.status.success(),
        "{sidecar}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let files = files_in(&dir.join("first"));
    assert_eq!(files, files_in(&dir.join("again")), "{name}");
    for f in &files {
        let (a, b) = (dir.join("first").join(f), dir.join("again").join(f));
        assert!(
            std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(),
            "{name}: {f} differs"
        );
    }
    for sub in ["first", "again"] {
        std::fs::remove_dir_all(dir.join(sub)).unwrap();
    }
}

#[test]
fn every_gallery_preset_is_reproduced_by_its_sidecar() {
    let dir = scratch("sidecar-presets");
    let presets = Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli");
    let mut count = 0;
    for entry in files_in(&presets) {
        let spec = presets.join(&entry);
        let spec = spec.to_str().unwrap();
        let stem = entry.trim_end_matches(".json");
        reproduces(&dir, &format!("{stem}.png"), &["--spec", spec, "--layers"]);
        count += 1;
    }
    assert!(count >= 19, "{count} presets");
}

#[test]
fn the_way_of_writing_is_reproduced_too() {
    let dir = scratch("sidecar-options");
    let sphere = [
        "sphere",
        "--size",
        "40",
        "--light",
        "tilt=60,slant=30",
        "--layers",
    ];
    reproduces(
        &dir,
        "s.png",
        &[&sphere[..], &["--bit-depth", "8", "--gamma", "2.2"]].concat(),
    );
    reproduces(
        &dir,
        "s.npy",
        &[&sphere[..], &["--range", "psychopy"]].concat(),
    );
    reproduces(&dir, "s.mat", &sphere);
    reproduces(
        &dir,
        "s.npz",
        &[&sphere[..], &["--range", "psychopy"]].concat(),
    );
    reproduces(&dir, "c.svg", &["circles-binary", "--ppd", "10"]);
    reproduces(
        &dir,
        "b.png",
        &[
            "bumps",
            "--seed",
            "7",
            "--set",
            "pattern=random",
            "--ppd",
            "9",
        ],
    );
    // A flag given beside the sidecar overrides it.
    std::fs::create_dir_all(dir.join("o")).unwrap();
    let out = shadelab(
        &dir,
        &[
            "--quiet", "render", "sphere", "--size", "16", "--out", "o/a.png",
        ],
    );
    assert!(out.status.success());
    let out = shadelab(
        &dir,
        &[
            "--quiet",
            "render",
            "--spec",
            "o/a.json",
            "--bit-depth",
            "8",
            "--out",
            "o/b.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let b: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("o/b.json")).unwrap()).unwrap();
    assert_eq!(b["bit_depth"], 8);
}
