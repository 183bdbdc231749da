//! `shadelab benchmark`: the scores' arithmetic, the table's files, and the models on stimupy's
//! own stimuli with their human data. The stimupy tests need a Python with stimupy 1.2
//! (`SHADELAB_STIMUPY_PYTHON`, else `target/python/venv/bin/python` where `.ci/run` installs
//! it, else `python3`); without one they say why and pass, unless `SHADELAB_REQUIRE_STIMUPY=1`.

use crate::cli::{assert_error, scratch, shadelab};
use shadelab::internal::lightness::benchmark::spearman;
use shadelab::pipeline::benchmark::{
    self as bm, contrast_stimulus, BenchmarkConfig, BenchmarkRow, Human,
};
use shadelab::NoProgress;
use std::path::PathBuf;

/// The interpreter with stimupy, or `None` (having said why) when there is none.
fn stimupy_python() -> Option<String> {
    let venv = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/python/venv/bin/python");
    let python = std::env::var("SHADELAB_STIMUPY_PYTHON")
        .ok()
        .unwrap_or_else(|| {
            if venv.is_file() {
                venv.display().to_string()
            } else {
                "python3".into()
            }
        });
    if bm::stimupy_available(&python) {
        return Some(python);
    }
    let why = format!("{python} cannot import stimupy and numpy (pip install stimupy==1.2.0)");
    if std::env::var("SHADELAB_REQUIRE_STIMUPY").is_ok_and(|v| v == "1") {
        panic!("benchmark test cannot run, and SHADELAB_REQUIRE_STIMUPY=1: {why}");
    }
    eprintln!("benchmark test SKIPPED: {why}");
    None
}

fn row(stimulus: &str, human: f64, effect: f64) -> BenchmarkRow {
    BenchmarkRow {
        set: "synthetic".into(),
        stimulus: stimulus.into(),
        model: "m".into(),
        human,
        human_ci95: None,
        human_direction: if human > 0.0 { 1 } else { 0 },
        effect,
        agrees: (human > 0.0).then_some(effect > 0.0),
    }
}

#[test]
fn scores_on_three_stimuli_match_the_hand_computed_ones() {
    // Human 1, 2, 3 against effects 0.1, 0.3, −0.2: ranks (1, 2, 3) and (2, 3, 1), d² = 1 + 1
    // + 4 = 6, ρ = 1 − 6·6 / (3·(9 − 1)) = −0.5; two of three effects have the human sign.
    let rows = [row("a", 1.0, 0.1), row("b", 2.0, 0.3), row("c", 3.0, -0.2)];
    let s = &bm::scores(&rows)[0];
    assert_eq!(
        (s.direction_agrees, s.direction_counted, s.stimuli),
        (2, 3, 3)
    );
    assert!(
        (s.spearman.unwrap() - (-0.5)).abs() < 1e-12,
        "{:?}",
        s.spearman
    );
    // A stimulus without a human effect is ranked but not counted for the direction.
    let rows = [row("a", 1.0, 0.1), row("b", 0.0, -0.3), row("c", 3.0, 0.2)];
    let s = &bm::scores(&rows)[0];
    assert_eq!((s.direction_agrees, s.direction_counted), (2, 2));
    assert_eq!(s.spearman, spearman(&[1.0, 0.0, 3.0], &[0.1, -0.3, 0.2]));
    assert!((s.spearman.unwrap() - 1.0).abs() < 1e-12);
}

#[test]
fn the_tables_csv_and_json_hold_the_same_rows() {
    let stimuli = (1..=3)
        .map(|i| {
            contrast_stimulus(
                &format!("sbc{i}"),
                32 * i,
                8.0,
                Human::EffectStrength { value: i as f64 },
            )
        })
        .collect();
    let config = BenchmarkConfig::new(
        stimuli,
        BenchmarkConfig::parse_models("retinex,highpass").unwrap(),
        "test".into(),
    )
    .unwrap();
    let report = bm::run(&config, &NoProgress).unwrap();
    let dir = scratch("benchmark-tables");
    let written =
        shadelab::CommandReport::write(&report, &shadelab::Output::new(dir.join("res"))).unwrap();
    let csv_path = written.join("benchmark.csv");
    let from_csv =
        bm::parse_rows_csv(&std::fs::read_to_string(&csv_path).unwrap(), &csv_path).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(written.join(bm::MARKER)).unwrap()).unwrap();
    let from_json: Vec<BenchmarkRow> = serde_json::from_value(json["rows"].clone()).unwrap();
    assert_eq!(from_csv, from_json);
    assert_eq!(from_csv, report.rows);
    assert_eq!(from_csv.len(), 6);
    let md = std::fs::read_to_string(written.join("benchmark.md")).unwrap();
    assert!(md.contains("| highpass |") && md.contains("sbc3"), "{md}");
    // The high-pass model sees simultaneous contrast in the direction people do.
    assert!(report
        .rows
        .iter()
        .filter(|r| r.model == "highpass")
        .all(|r| r.agrees == Some(true)));
    if cfg!(feature = "plots") {
        assert!(written.join("benchmark.png").is_file());
    }
}

#[test]
fn odog_predicts_the_direction_of_whites_effect_on_stimupys_stimuli() {
    let Some(python) = stimupy_python() else {
        return;
    };
    let dir = scratch("benchmark-stimupy");
    let out = shadelab(
        &dir,
        &[
            "--json",
            "--quiet",
            "benchmark",
            "--python",
            &python,
            "--models",
            "odog,highpass",
            "--stimuli",
            "murray2020/white,simcon,snake",
            "--out",
            "res",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["stimupy_version"], "1.2.0");
    let rows = report["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3 * 2);
    for r in rows.iter().filter(|r| r["model"] == "odog") {
        // White's effect, simultaneous contrast and the snake: ODOG puts the target people
        // see as lighter above the other (Blakeslee & McCourt 1999). murray2020's pictures are
        // small (128 × 128 at 16 ppd): RHS2007's 1024 × 1024 ones would take minutes here.
        assert_eq!(r["agrees"], true, "{r}");
        assert_eq!(r["human_direction"], 1, "{r}");
    }
    let human_of = |name: &str| {
        rows.iter()
            .find(|r| r["stimulus"] == name)
            .map(|r| r["human"].as_f64().unwrap())
            .unwrap()
    };
    // The human values are stimupy's (Murray's proportion expected and its interval).
    assert_eq!(human_of("white"), 0.95);
    assert_eq!(human_of("snake"), 0.9625);
    for f in ["benchmark.csv", "scores.csv", "benchmark.md", bm::MARKER] {
        assert!(dir.join("res").join(f).is_file(), "{f}");
    }
    // An unknown stimulus, and an interpreter that cannot be run: one line each.
    let bad = shadelab(
        &dir,
        &["benchmark", "--python", &python, "--stimuli", "nope"],
    );
    assert_error(&bad, 2, "nope");
}

/// The mean luminance of the free pixels (label 0) that share an edge with target `t`: above
/// and below it (`.0`), left and right of it (`.1`), and all of them (`.2`).
fn neighbour_means(s: &bm::BenchmarkStimulus, t: u16) -> (f64, f64, f64) {
    let (w, h) = (s.image.width(), s.image.height());
    let (mut vert, mut horiz) = ((0.0, 0usize), (0.0, 0usize));
    for r in 0..h {
        for c in 0..w {
            if *s.targets.get(c, r) != 0 {
                continue;
            }
            let is_t = |dc: isize, dr: isize| {
                s.targets.checked(c as isize + dc, r as isize + dr) == Some(&t)
            };
            let v = *s.image.get(c, r);
            if is_t(0, -1) || is_t(0, 1) {
                vert = (vert.0 + v, vert.1 + 1);
            }
            if is_t(-1, 0) || is_t(1, 0) {
                horiz = (horiz.0 + v, horiz.1 + 1);
            }
        }
    }
    assert!(
        vert.1 > 0 && horiz.1 > 0,
        "{}: target {t} has no free neighbour",
        s.name
    );
    let all = (vert.0 + horiz.0) / (vert.1 + horiz.1) as f64;
    (vert.0 / vert.1 as f64, horiz.0 / horiz.1 as f64, all)
}

#[test]
fn the_lighter_target_is_the_one_the_published_illusion_makes_lighter() {
    let Some(python) = stimupy_python() else {
        return;
    };
    let only: Vec<String> = [
        "RHS2007/sbc_small",
        "murray2020/simcon",
        "RHS2007/WE_thick",
        "murray2020/white",
        "RHS2007/checkerboard_094",
        "murray2020/checkassim",
        "RHS2007/grating_induction",
        "RHS2007/benary_cross",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let models = BenchmarkConfig::parse_models("highpass").unwrap();
    let config = BenchmarkConfig::from_stimupy(&python, models, &only).unwrap();
    let by_name = |set: &str, name: &str| {
        config
            .stimuli
            .iter()
            .find(|s| s.set == set && s.name == name)
            .unwrap_or_else(|| panic!("{set}/{name} not exported"))
    };
    // Checked on stimupy's own pixels, not on any model: the two targets have the same value,
    // and what surrounds each decides which one people see as lighter.
    for s in &config.stimuli {
        let (l, d) = (s.lighter, s.darker);
        let mean_of = |t: u16| {
            let px: Vec<f64> = (0..s.image.len())
                .filter(|&i| s.targets.data()[i] == t)
                .map(|i| s.image.data()[i])
                .collect();
            px.iter().sum::<f64>() / px.len() as f64
        };
        assert!(
            (mean_of(l) - mean_of(d)).abs() < 1e-9,
            "{}: targets differ",
            s.name
        );
    }
    // Simultaneous contrast: the target on the dark background looks lighter.
    for (set, name) in [("RHS2007", "sbc_small"), ("murray2020", "simcon")] {
        let s = by_name(set, name);
        let (lighter, darker) = (neighbour_means(s, s.lighter), neighbour_means(s, s.darker));
        assert!(lighter.2 < darker.2, "{name}: {lighter:?} vs {darker:?}");
        assert!(
            s.convention_checked && s.convention == "contrast",
            "{}",
            s.convention
        );
    }
    // White's effect: the target lying on a dark stripe (the stripe continues beyond its ends,
    // above and below it in RHS2007, left and right in Murray's rotated version) looks lighter
    // although its long sides border white.
    let s = by_name("RHS2007", "WE_thick");
    let (lighter, darker) = (neighbour_means(s, s.lighter), neighbour_means(s, s.darker));
    assert!(
        lighter.0 < darker.0 && lighter.1 > darker.1,
        "{lighter:?} {darker:?}"
    );
    let s = by_name("murray2020", "white");
    let (lighter, darker) = (neighbour_means(s, s.lighter), neighbour_means(s, s.darker));
    assert!(
        lighter.1 < darker.1 && lighter.0 > darker.0,
        "{lighter:?} {darker:?}"
    );
    // Checkerboard contrast: the target among white checks looks lighter (not the one among
    // black checks, as plain contrast would have it); RHS2007's target 1 is among black checks.
    for (set, name) in [
        ("RHS2007", "checkerboard_094"),
        ("murray2020", "checkassim"),
    ] {
        let s = by_name(set, name);
        let (lighter, darker) = (neighbour_means(s, s.lighter), neighbour_means(s, s.darker));
        assert!(lighter.2 > darker.2, "{name}: {lighter:?} vs {darker:?}");
    }
    assert_eq!(by_name("RHS2007", "checkerboard_094").lighter, 2);
    // Grating induction: the strip looks modulated in the grating's opposite phase, so the
    // part with the dark phase above and below it looks lighter.
    let s = by_name("RHS2007", "grating_induction");
    let (lighter, darker) = (neighbour_means(s, s.lighter), neighbour_means(s, s.darker));
    assert!(lighter.0 < darker.0, "{lighter:?} vs {darker:?}");
    // A stimulus without a verified rule keeps stimupy's order and says so.
    let s = by_name("RHS2007", "benary_cross");
    assert!(!s.convention_checked && s.lighter == 1, "{}", s.convention);
    assert!(s.convention.contains("not checked"), "{}", s.convention);
}

#[test]
fn a_missing_python_is_one_line_saying_how_to_install_stimupy() {
    let dir = scratch("benchmark-no-python");
    let out = shadelab(
        &dir,
        &[
            "benchmark",
            "--python",
            "/nonexistent/python3",
            "--stimuli",
            "WE_thick",
        ],
    );
    assert_error(&out, 2, "pip install stimupy==1.2.0");
    assert!(!dir.join("res").exists());
}
