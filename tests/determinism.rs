//! The same inputs give the same bytes whatever the thread count: `--threads 1` and
//! `--threads 2` write identical files for a stimulus, a mesh render, a solve large enough to
//! take the parallel paths, a prior sweep and a study. Only the recorded timings may differ.

use super::cli::{scratch, shadelab};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// Every file under `dir`, by relative path. JSON files are compared without their timings
/// (`seconds` at any depth) and thread counts (`threads`), which legitimately differ.
pub fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn strip(v: &mut Value) {
        match v {
            Value::Object(map) => {
                map.remove("seconds");
                map.remove("threads");
                map.values_mut().for_each(strip);
            }
            Value::Array(items) => items.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            let mut bytes = std::fs::read(&p).unwrap();
            if name.ends_with(".json") {
                let mut v: Value = serde_json::from_slice(&bytes).unwrap();
                strip(&mut v);
                bytes = serde_json::to_vec(&v).unwrap();
            }
            files.insert(name, bytes);
        }
    }
    files
}

#[test]
fn one_and_two_threads_write_the_same_bytes() {
    let root = scratch("determinism");
    // The solve's input, rendered once: a Gaussian bump filling a 200×200 frame, solved over
    // the whole image, so the solver has 40,000 unknowns (above the 32,768 of its parallel
    // sweeps and the 16,384 of the multigrid's parallel levels).
    let out = shadelab(
        &root,
        &[
            "--quiet", "render", "gaussian", "--size", "200", "--light", "above", "--out", "g.png",
        ],
    );
    assert!(out.status.success());
    let runs: &[&[&str]] = &[
        &[
            "render",
            "sphere",
            "--size",
            "64",
            "--layers",
            "--out",
            "sphere.png",
        ],
        &[
            "render",
            "bunny",
            "--size",
            "96",
            "--layers",
            "--out",
            "bunny.npy",
        ],
        &["render", "bumps", "--out", "bumps.png"],
        &["solve", "../g.png", "--light", "above", "--out", "solved"],
        &[
            "analyze",
            "prior-sweep",
            "--stimulus",
            "bumps",
            "--set",
            "rows=1",
            "--set",
            "columns=2",
            "--ppd",
            "16",
            "--size",
            "80x32",
            "--tilts",
            "0:360:30",
            "--out",
            "sweep",
        ],
    ];
    let mut results = Vec::new();
    for threads in ["1", "2"] {
        let dir = root.join(format!("t{threads}"));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("study.json"),
            r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": [1, 2]},
                "shape": [24, 64], "ppd": 12}], "tilts": "0:360:90", "slants": [30, 45]}"#,
        )
        .unwrap();
        let mut all: Vec<&[&str]> = runs.to_vec();
        all.push(&["study", "run", "study.json", "--out", "study"]);
        for args in all {
            let mut full = vec!["--quiet", "--threads", threads];
            full.extend_from_slice(args);
            let out = shadelab(&dir, &full);
            assert!(
                out.status.success(),
                "{full:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        results.push(outputs(&dir));
    }
    let (one, two) = (&results[0], &results[1]);
    assert_eq!(
        one.keys().collect::<Vec<_>>(),
        two.keys().collect::<Vec<_>>()
    );
    for (name, bytes) in one {
        assert!(
            bytes == &two[name],
            "{name} differs between 1 and 2 threads"
        );
    }
    // The solve did take the parallel paths.
    let report: Value =
        serde_json::from_slice(&std::fs::read(root.join("t1/solved/report.json")).unwrap())
            .unwrap();
    assert!(report["solver"]["unknowns"].as_u64().unwrap() >= 32_768);
    assert!(one.len() >= 25, "{} files compared", one.len());
}
