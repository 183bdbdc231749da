//! The library-first refactor (issue 13) must not change what any command writes: every file
//! of a render, a solve, a prior sweep, an observer, a study, a lightness analysis, the fading
//! analysis, the outline analysis, an observer fit and the gallery is compared, by MD5 digest, with the digests
//! recorded before the refactor (`tests/data/golden-outputs.json`). JSON is compared without its timings and
//! thread counts, as in the determinism test. `SHADELAB_BLESS=1` records the digests anew;
//! do that only for a change that means to alter outputs, and say so in its commit.

use super::cli::{scratch, shadelab};
use super::determinism::outputs;
use md5::{Digest, Md5};
use std::collections::BTreeMap;

const MANIFEST: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/data/golden-outputs.json"
);

/// The commands whose outputs are recorded, run in order in one folder.
const RUNS: &[&[&str]] = &[
    &[
        "render",
        "sphere",
        "--size",
        "64",
        "--layers",
        "--light",
        "tilt=30,slant=40",
        "--out",
        "sphere.png",
    ],
    &["render", "bumps", "--ppd", "16", "--out", "bumps.png"],
    &[
        "render",
        "crater",
        "--set",
        "rotation=180",
        "--ppd",
        "20",
        "--out",
        "crater.npy",
    ],
    &[
        "solve",
        "sphere.png",
        "--mask",
        "sphere_mask.png",
        "--light",
        "tilt=30,slant=40",
        "--out",
        "solved",
    ],
    &[
        "solve",
        "sphere.png",
        "--light",
        "estimate",
        "--boundary",
        "flat",
        "--out",
        "solved-estimate",
    ],
    &[
        "solve",
        "sphere.png",
        "--mask",
        "sphere_mask.png",
        "--light",
        "tilt=30,slant=40",
        "--method",
        "jacobi",
        "--max-iter",
        "300",
        "--out",
        "solved-jacobi",
    ],
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
        "--binding",
        "estimate",
        "--out",
        "sweep",
    ],
    &[
        "analyze",
        "observer",
        "--stimulus",
        "bumps",
        "--set",
        "rows=1",
        "--set",
        "columns=2",
        "--ppd",
        "12",
        "--size",
        "64x24",
        "--tilts",
        "0:360:45",
        "--rotations",
        "0:360:90",
        "--out",
        "observer",
    ],
    &[
        "analyze",
        "lightness",
        "--stimulus",
        "checker-shadow",
        "--ppd",
        "12",
        "--model",
        "all",
        "--out",
        "lightness",
    ],
    &[
        "analyze",
        "fading",
        "--stimulus",
        "fading-disk",
        "--ppd",
        "12",
        "--duration",
        "2",
        "--out",
        "fading",
    ],
    &[
        "analyze",
        "outline",
        "--stimulus",
        "boundary-strips",
        "--set",
        "boundary=sinusoidal,sawtooth",
        "--ppd",
        "12",
        "--out",
        "outline",
    ],
    &["study", "run", "study.json", "--out", "study"],
    &[
        "fit",
        "observer",
        "responses.csv",
        "--include-simulated",
        "--bootstrap",
        "50",
        "--nonparametric",
        "--out",
        "fit",
    ],
    &["gallery", "--out", "gallery"],
    &[
        "experiment",
        "--out",
        "experiment",
        "--rotations",
        "0:360:90",
        "--repeats",
        "2",
        "--ppd",
        "16",
        "--no-install",
    ],
];

const STUDY: &str = r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": [1, 2]},
    "shape": [24, 64], "ppd": 12}], "tilts": "0:360:90", "slants": [30, 45]}"#;

#[test]
fn every_command_writes_what_it_wrote_before_the_refactor() {
    let dir = scratch("golden-outputs");
    std::fs::write(dir.join("study.json"), STUDY).unwrap();
    // Responses of a simulated observer (26° left prior), 24 directions × 10 trials.
    let model = shadelab::pipeline::fit::ModelParams {
        tilt_deg: 26.0,
        kappa: 2.0,
        convexity_prior: 0.6,
        lapse: 0.03,
    };
    let rotations: Vec<f64> = (0..24).map(|i| 15.0 * i as f64).collect();
    let csv = shadelab::pipeline::fit::simulated_responses(&model, &rotations, 10, 5, "p1");
    std::fs::write(dir.join("responses.csv"), csv).unwrap();
    for args in RUNS {
        let mut full = vec!["--quiet"];
        full.extend_from_slice(args);
        let out = shadelab(&dir, &full);
        assert!(
            out.status.success(),
            "{full:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let files = outputs(&dir);
    // No NaN or infinity in any file any command wrote (docs/reliability.md).
    let found: Vec<String> = files
        .iter()
        .filter_map(|(name, bytes)| non_finite(name, bytes))
        .collect();
    assert!(found.is_empty(), "non-finite numbers written: {found:#?}");
    assert!(
        files.keys().any(|n| n.ends_with(".npy")) && files.keys().any(|n| n.ends_with(".csv")),
        "the scan saw no .npy or .csv"
    );
    let digests: BTreeMap<String, String> = files
        .into_iter()
        .filter(|(name, _)| name != "study.json" && name != "responses.csv")
        .map(|(name, bytes)| (name, format!("{:x}", Md5::digest(&bytes))))
        .collect();
    if std::env::var_os("SHADELAB_BLESS").is_some() {
        let text = serde_json::to_string_pretty(&digests).unwrap() + "\n";
        std::fs::write(MANIFEST, text).unwrap();
        eprintln!("recorded {} digests in {MANIFEST}", digests.len());
        return;
    }
    let recorded: BTreeMap<String, String> =
        serde_json::from_str(&std::fs::read_to_string(MANIFEST).unwrap()).unwrap();
    let differing: Vec<&String> = recorded
        .iter()
        .filter(|(name, digest)| digests.get(*name) != Some(digest))
        .map(|(name, _)| name)
        .collect();
    let new: Vec<&String> = digests
        .keys()
        .filter(|n| !recorded.contains_key(*n))
        .collect();
    assert!(
        differing.is_empty() && new.is_empty(),
        "outputs changed: {differing:?}; files not recorded: {new:?}"
    );
    assert!(recorded.len() >= 60, "{} files compared", recorded.len());
}

/// Where the file `name` holds a NaN or an infinity, in words (`None` when it holds none):
/// a field of a CSV, a value of a `.npy`, a number in an SVG, HTML, Markdown or text file
/// (any token that parses as a non-finite number: `NaN`, `inf`, `-inf`, `infinity`); JSON
/// cannot hold one (serde writes `null` for it, which the reports document), so a JSON file
/// that does not parse is reported.
pub fn non_finite(name: &str, bytes: &[u8]) -> Option<String> {
    let bad = |t: &str| t.trim().parse::<f64>().is_ok_and(|v| !v.is_finite());
    let ext = name.rsplit('.').next().unwrap_or("");
    match ext {
        "csv" => {
            let text = String::from_utf8_lossy(bytes);
            text.lines().enumerate().find_map(|(n, line)| {
                let fields = shadelab_io::csv_record(line).ok()?;
                let field = fields.iter().find(|f| bad(f))?;
                Some(format!("{name} line {}: '{field}'", n + 1))
            })
        }
        "npy" => {
            let array =
                shadelab_io::read_array_from_bytes(bytes, std::path::Path::new(name), usize::MAX)
                    .ok()?;
            let at = array.data.iter().position(|v| !v.is_finite())?;
            Some(format!("{name} value {at}: {}", array.data[at]))
        }
        "json" => serde_json::from_slice::<serde_json::Value>(bytes)
            .err()
            .map(|e| format!("{name}: not JSON ({e})")),
        "svg" | "html" | "md" | "txt" => {
            let text = String::from_utf8_lossy(bytes);
            let token = text
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '+'))
                .find(|t| bad(t))?;
            Some(format!("{name}: '{token}'"))
        }
        _ => None,
    }
}

#[test]
fn the_scan_finds_what_it_looks_for() {
    let npy = shadelab_io::encode_f64(&[2], &[0.5, f64::NAN]).unwrap();
    let cases: [(&str, &[u8], bool); 8] = [
        ("a.csv", b"a,b\n1,NaN\n", true),
        ("a.csv", b"a,b\n1,\"inf, or not\"\n2,-inf\n", true),
        ("a.csv", b"a,b\n1,2.5e-300\n", false),
        ("a.npy", &npy, true),
        (
            "a.svg",
            b"<path d=\"M 0 NaN L 1 2\"/><text>Information</text>",
            true,
        ),
        ("a.svg", b"<text>Information, infinite</text>", false),
        ("a.json", b"{\"a\": NaN}", true),
        ("a.json", b"{\"a\": null}", false),
    ];
    for (name, bytes, found) in cases {
        assert_eq!(
            non_finite(name, bytes).is_some(),
            found,
            "{name}: {}",
            String::from_utf8_lossy(bytes)
        );
    }
}
