//! `shadelab fit observer` end to end: simulated responses fitted back, per-participant fits,
//! refusals of data that cannot identify the model, and one model family with
//! `analyze observer` (a fit.json fed back predicts the fitted formula) and a study.

use super::cli::{assert_error, scratch, shadelab};
use serde_json::Value;
use shadelab::pipeline::fit::ModelParams;
use shadelab::pipeline::fit::{simulated_responses, RESPONSES_HEADER};
use std::path::Path;

fn design() -> Vec<f64> {
    (0..24).map(|i| 15.0 * i as f64).collect()
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Mamassian & Goutcher's design with a 26°-left prior, fitted back: every estimate near the
/// truth, its interval around the estimate, fit.json in the documented form, the figure and
/// the Methods paragraph written; the same seed gives the same bytes.
#[test]
fn simulated_responses_are_fitted_back() {
    let dir = scratch("fit-recovery");
    let truth = ModelParams {
        tilt_deg: 26.0,
        kappa: 2.0,
        convexity_prior: 0.65,
        lapse: 0.03,
    };
    std::fs::write(
        dir.join("r.csv"),
        simulated_responses(&truth, &design(), 20, 11, "p1"),
    )
    .unwrap();
    for out in ["a", "b"] {
        let run = shadelab(
            &dir,
            &[
                "--quiet",
                "fit",
                "observer",
                "r.csv",
                "--include-simulated",
                "--out",
                out,
                "--bootstrap",
                "200",
            ],
        );
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
    }
    let fit = read_json(&dir.join("a/fit.json"));
    let value = |k: &str| fit[k]["value"].as_f64().unwrap();
    assert!((value("prior_tilt_deg") - 26.0).abs() < 10.0, "{fit}");
    assert!((value("prior_kappa") / 2.0).ln().abs() < 0.4, "{fit}");
    assert!((value("convexity_prior") - 0.65).abs() < 0.1, "{fit}");
    assert!((value("lapse") - 0.03).abs() < 0.06, "{fit}");
    for k in ["prior_tilt_deg", "prior_kappa", "convexity_prior", "lapse"] {
        let ci = fit[k]["ci95"].as_array().unwrap();
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        assert!(lo <= value(k) && value(k) <= hi, "{k}: {fit}");
    }
    assert_eq!(fit["n_trials"], 480);
    assert_eq!(fit["design"]["rotations_deg"].as_array().unwrap().len(), 24);
    assert_eq!(fit["study"]["lapse"], fit["lapse"]["value"]);
    assert_eq!(
        fit["study"]["priors"]["tilt"][0],
        fit["prior_tilt_deg"]["value"]
    );
    assert!(fit["log_likelihood"].as_f64().unwrap() < 0.0);
    assert!(
        fit["models"][1]["log_likelihood"].as_f64().unwrap()
            <= fit["log_likelihood"].as_f64().unwrap() + 1e-9
    );
    let methods = std::fs::read_to_string(dir.join("a/methods.md")).unwrap();
    assert!(
        methods.contains("24 directions of the bright side, every 15°"),
        "{methods}"
    );
    assert!(
        methods.contains("Mamassian, P., & Goutcher, R. (2001)"),
        "{methods}"
    );
    assert!(dir.join("a/fit.png").is_file() || !cfg!(feature = "plots"));
    // Seeded: the same files, bar the timing.
    let strip = |mut v: Value| {
        v.as_object_mut().unwrap().remove("seconds");
        v
    };
    assert_eq!(
        strip(fit.clone()),
        strip(read_json(&dir.join("b/fit.json")))
    );
    assert_eq!(
        std::fs::read(dir.join("a/methods.md")).unwrap(),
        std::fs::read(dir.join("b/methods.md")).unwrap()
    );
}

/// Several participants: one fit each beside the pooled one; a participant with too few
/// trials is left out with a warning, never given a made-up estimate.
#[test]
fn participants_are_fitted_one_by_one() {
    let dir = scratch("fit-participants");
    let mut csv = String::from(RESPONSES_HEADER);
    for (who, tilt, seed) in [("ann", 30.0, 1), ("bob", -30.0, 2)] {
        let m = ModelParams {
            tilt_deg: tilt,
            kappa: 3.0,
            convexity_prior: 0.5,
            lapse: 0.02,
        };
        let text = simulated_responses(&m, &design(), 15, seed, who);
        csv.push_str(text.strip_prefix(RESPONSES_HEADER).unwrap().trim_end());
    }
    csv.push_str("\ncat,1,test,disc,0,convex,400,f,,,\ncat,2,test,disc,180,concave,400,j,,,\n");
    std::fs::write(dir.join("r.csv"), csv).unwrap();
    let run = shadelab(
        &dir,
        &[
            "fit",
            "observer",
            "r.csv",
            "--include-simulated",
            "--out",
            "f",
            "--bootstrap",
            "20",
            "--lapse",
            "0.02",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("warning: participant 'cat': 2 trials is too few"),
        "{err}"
    );
    let fit = read_json(&dir.join("f/fit.json"));
    let people = fit["participants"].as_array().unwrap();
    assert_eq!(people.len(), 2);
    assert_eq!(people[0]["participant"], "ann");
    let tilt = |p: &Value| p["prior_tilt_deg"]["value"].as_f64().unwrap();
    assert!((tilt(&people[0]) - 30.0).abs() < 15.0, "{}", people[0]);
    assert!((tilt(&people[1]) + 30.0).abs() < 15.0, "{}", people[1]);
    // The fixed lapse is reported as fixed: no interval.
    assert_eq!(fit["lapse"]["value"], 0.02);
    assert!(fit["lapse"]["ci95"].is_null());
    assert_eq!(fit["design"]["participants"], 3);
}

/// jsPsych's data of one participant as CSV: a consent row, then per trial a fixation row and
/// the trial's row with the key pressed (F = bump, J = dimple), as a lab's own study writes it.
fn jspsych_csv(model: &ModelParams, seed: u64, participant: Option<&str>) -> String {
    let plain = simulated_responses(model, &design(), 16, seed, "x");
    let mut csv =
        String::from("\"trial_type\",\"trial_index\",\"rotation_deg\",\"response\",\"rt\"");
    if participant.is_some() {
        csv.push_str(",\"participant\"");
    }
    csv.push_str("\r\n");
    let who = participant.map(|p| format!(",\"{p}\"")).unwrap_or_default();
    csv.push_str(&format!(
        "\"html-button-response\",\"0\",\"null\",\"0\",\"1200\"{who}\r\n"
    ));
    for (i, line) in plain.lines().skip(1).enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        let key = if fields[5] == "convex" { "f" } else { "j" };
        csv.push_str(&format!(
            "\"html-keyboard-response\",\"{}\",\"null\",\"null\",\"null\"{who}\r\n\
             \"image-keyboard-response\",\"{}\",\"{}\",\"{key}\",\"512\"{who}\r\n",
            2 * i + 1,
            2 * i + 2,
            fields[4]
        ));
    }
    csv
}

/// jsPsych data whose `response` is the key pressed: refused without the key mapping, naming
/// the flag; fitted with `--keys`.
#[test]
fn key_presses_are_fitted_with_the_key_mapping() {
    let dir = scratch("fit-keys");
    let m = ModelParams {
        tilt_deg: 26.0,
        kappa: 2.0,
        convexity_prior: 0.6,
        lapse: 0.02,
    };
    std::fs::write(dir.join("p.csv"), jspsych_csv(&m, 4, None)).unwrap();
    let out = shadelab(&dir, &["fit", "observer", "p.csv", "--out", "f"]);
    assert_error(&out, 1, "line 4: unknown response 'f'");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("for key presses give --keys BUMP,DIMPLE")
    );
    assert_error(
        &shadelab(
            &dir,
            &["fit", "observer", "p.csv", "--out", "f", "--keys", "fff"],
        ),
        2,
        "--keys",
    );
    assert_error(
        &shadelab(
            &dir,
            &["fit", "observer", "p.csv", "--out", "f", "--keys", "dk"],
        ),
        1,
        "response 'f' is neither the bump key 'd' nor the dimple key 'k'",
    );
    let ok = shadelab(
        &dir,
        &[
            "--quiet",
            "fit",
            "observer",
            "p.csv",
            "--out",
            "f",
            "--keys",
            "F,J",
            "--bootstrap",
            "0",
        ],
    );
    assert!(
        ok.status.success(),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let fit = read_json(&dir.join("f/fit.json"));
    assert_eq!(fit["n_trials"], 384);
    assert_eq!(
        fit["design"]["other_rows"], 385,
        "the consent and fixation rows"
    );
    let ci = &fit["prior_tilt_deg"]["ci95"];
    assert!(
        ci[0].as_f64().unwrap() <= 26.0 && 26.0 <= ci[1].as_f64().unwrap(),
        "{fit}"
    );
}

/// A folder of participants (jsPsych CSV and JSON, named by their files or their own column):
/// one fit each, the pooled fit, the group's spread, a figure of every participant, and a
/// Methods paragraph with the stimulus and apparatus from the design.json beside them.
#[test]
fn a_folder_of_participants_gets_a_fit_each_and_a_group_summary() {
    let dir = scratch("fit-folder");
    let data = dir.join("data");
    std::fs::create_dir_all(&data).unwrap();
    let truths = [
        ("p1", 10.0, 1),
        ("p2", 30.0, 2),
        ("p3", 40.0, 3),
        ("p4", 20.0, 4),
    ];
    for (who, tilt, seed) in truths {
        let m = ModelParams {
            tilt_deg: tilt,
            kappa: 2.5,
            convexity_prior: 0.6,
            lapse: 0.02,
        };
        match who {
            // jsPsych's JSON (as JATOS stores it), with its own participant column.
            "p3" => {
                let rows: Vec<Value> = simulated_responses(&m, &design(), 16, seed, who)
                    .lines()
                    .skip(1)
                    .map(|l| {
                        let f: Vec<&str> = l.split(',').collect();
                        serde_json::json!({
                            "trial_type": "image-keyboard-response",
                            "participant": "p3",
                            "block": "test",
                            "rotation_deg": f[4].parse::<f64>().unwrap(),
                            "response": if f[5] == "convex" { "f" } else { "j" },
                            "key_convex": "f",
                            "key_concave": "j",
                        })
                    })
                    .collect();
                std::fs::write(data.join("session-3.json"), Value::from(rows).to_string()).unwrap();
            }
            // Named by the file.
            _ => std::fs::write(data.join(format!("{who}.csv")), jspsych_csv(&m, seed, None))
                .unwrap(),
        }
    }
    // The experiment's design beside the data is read, not fitted.
    let design_out = shadelab(
        &dir,
        &[
            "--quiet",
            "experiment",
            "--out",
            "e",
            "--rotations",
            "0:360:90",
            "--repeats",
            "1",
            "--no-install",
        ],
    );
    assert!(design_out.status.success());
    std::fs::copy(dir.join("e/design.json"), data.join("design.json")).unwrap();
    let run = shadelab(
        &dir,
        &[
            "--quiet",
            "fit",
            "observer",
            "data",
            "--out",
            "f",
            "--keys",
            "fj",
            "--bootstrap",
            "0",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let fit = read_json(&dir.join("f/fit.json"));
    assert_eq!(fit["design"]["participants"], 4);
    assert_eq!(fit["design"]["files"].as_array().unwrap().len(), 4);
    assert_eq!(fit["n_trials"], 4 * 384);
    let people = fit["participants"].as_array().unwrap();
    let names: Vec<&str> = people
        .iter()
        .map(|p| p["participant"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["p1", "p2", "p4", "p3"], "in the order of the files");
    for p in people {
        let truth = truths.iter().find(|t| t.0 == p["participant"]).unwrap().1;
        let v = p["prior_tilt_deg"]["value"].as_f64().unwrap();
        let ci = &p["prior_tilt_deg"]["ci95"];
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        eprintln!(
            "recovery: {} μ simulated {truth}, fitted {v:.2} [{lo:.2}, {hi:.2}]",
            p["participant"]
        );
        assert!(lo <= truth && truth <= hi, "{p}");
    }
    // The group: the circular mean of the four near the mean of the truths (25°), their
    // spread near that of the truths (SD 12.9°).
    let g = &fit["group"];
    assert_eq!(g["participants"], 4);
    let mean = g["prior_tilt_mean_deg"].as_f64().unwrap();
    assert!((mean - 25.0).abs() < 8.0, "{g}");
    let ci = &g["prior_tilt_mean_ci95"];
    assert!(
        ci[0].as_f64().unwrap() < mean && mean < ci[1].as_f64().unwrap(),
        "{g}"
    );
    assert!(g["prior_tilt_sd_deg"].as_f64().unwrap() < 30.0, "{g}");
    assert!(dir.join("f/participants.png").is_file() && dir.join("f/participants.svg").is_file());
    let methods = std::fs::read_to_string(dir.join("f/methods.md")).unwrap();
    assert!(
        methods.contains("**Group.** Across the 4 participants"),
        "{methods}"
    );
    assert!(
        methods.contains("**Stimulus and apparatus.** Each trial showed one shaded `bumps`")
            && methods.contains("57 cm"),
        "{methods}"
    );
    assert_eq!(fit["experiment"]["program"], "shadelab");
    // A folder without data files, and a design that is not one, are refused in one line.
    std::fs::create_dir_all(dir.join("empty")).unwrap();
    assert_error(
        &shadelab(&dir, &["fit", "observer", "empty", "--out", "g"]),
        1,
        "holds no data files",
    );
    assert_error(
        &shadelab(
            &dir,
            &[
                "fit",
                "observer",
                "data",
                "--out",
                "g",
                "--keys",
                "fj",
                "--design",
                "data/p1.csv",
            ],
        ),
        1,
        "p1.csv",
    );
}

/// Data that cannot identify the model, or are not responses, are refused in one line.
#[test]
fn bad_responses_are_refused_in_one_line() {
    let dir = scratch("fit-bad");
    let all_convex: String = std::iter::once("rotation_deg,response\n".to_string())
        .chain((0..48).map(|i| format!("{},convex\n", 15 * (i % 24))))
        .collect();
    let one_rotation: String = std::iter::once("rotation_deg,response\n".to_string())
        .chain((0..48).map(|i| format!("90,{}\n", i % 2)))
        .collect();
    for (csv, code, needle) in [
        (
            "rotation_deg,response\n0,convex\n30,bump\n",
            1,
            "line 3: unknown response 'bump'",
        ),
        ("rotation_deg,answer\n0,convex\n", 1, "no 'response' column"),
        (
            "rotation_deg,response\n0,convex\n\"15,concave\n",
            1,
            "line 3: a quoted field is never closed",
        ),
        (all_convex.as_str(), 2, "all 48 responses are 'convex'"),
        (one_rotation.as_str(), 2, "light prior is not identifiable"),
    ] {
        std::fs::write(dir.join("r.csv"), csv).unwrap();
        let out = shadelab(
            &dir,
            &["fit", "observer", "r.csv", "--out", "f", "--bootstrap", "5"],
        );
        assert_error(&out, code, needle);
        assert!(!dir.join("f").exists());
    }
    let out = shadelab(
        &dir,
        &["fit", "observer", "r.csv", "--out", "f", "--lapse", "0.9"],
    );
    assert_error(&out, 2, "--lapse");
}

/// One model family: `analyze observer --prior fit.json` on one bump, with a small image
/// noise, predicts the fitted formula's P(convex | θ) at every rotation (to 1e-6; the engine's
/// bump and dimple interpretations render the disc exactly). A tiny noise never writes NaN.
#[test]
fn a_fit_fed_back_to_the_observer_predicts_the_formula() {
    let dir = scratch("fit-observer");
    let fit = r#"{"program": "shadelab", "prior_tilt_deg": {"value": 26.0, "ci95": null},
        "prior_kappa": {"value": 1.5, "ci95": null}, "convexity_prior": {"value": 0.7, "ci95": null},
        "lapse": {"value": 0.05, "ci95": null}}"#;
    std::fs::write(dir.join("fit.json"), fit).unwrap();
    let model = ModelParams {
        tilt_deg: 26.0,
        kappa: 1.5,
        convexity_prior: 0.7,
        lapse: 0.05,
    };
    let picture = [
        "--quiet",
        "analyze",
        "observer",
        "--stimulus",
        "bumps",
        "--set",
        "rows=1",
        "--set",
        "columns=1",
        "--set",
        "pattern=bumps",
        "--ppd",
        "16",
        "--size",
        "48x48",
        "--tilts",
        "0:360:15",
        "--rotations",
        "0:360:45",
    ];
    let mut args = picture.to_vec();
    args.extend(["--noise", "0.002", "--prior", "fit.json", "--out", "obs"]);
    let run = shadelab(&dir, &args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("obs/observer.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 8);
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let (theta, p): (f64, f64) = (f[1].parse().unwrap(), f[4].parse().unwrap());
        let want = model.p_convex(theta);
        assert!((p - want).abs() < 1e-6, "θ = {theta}: {p} vs {want}");
    }
    let report = read_json(&dir.join("obs/observer.json"));
    assert_eq!(report["observer"]["lapse"], 0.05);
    assert_eq!(report["observer"]["prior_from"], "fit.json");
    // A noise so small that 2σ² underflows: numbers, never NaN.
    let mut args = picture.to_vec();
    args.extend(["--noise", "1e-200", "--out", "tiny"]);
    let run = shadelab(&dir, &args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("tiny/observer.csv")).unwrap();
    assert!(!csv.to_lowercase().contains("nan"), "{csv}");
    std::fs::write(
        dir.join("study.json"),
        r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": 1}, "shape": [24, 24], "ppd": 12}],
            "tilts": "0:360:90", "rotations": "0:360:90", "noise": 1e-200}"#,
    )
    .unwrap();
    let run = shadelab(
        &dir,
        &["--quiet", "study", "run", "study.json", "--out", "study"],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("study/results.csv")).unwrap();
    assert!(!csv.to_lowercase().contains("nan"), "{csv}");
    // A study with the fitted priors and lapse (as fit.json's "study" gives them) predicts the
    // formula too.
    let spec = format!(
        r#"{{"stimuli": [{{"stimulus": "bumps", "params": {{"rows": 1, "columns": 1, "pattern": "bumps"}},
            "shape": [48, 48], "ppd": 16}}], "tilts": "0:360:15", "rotations": "0:360:45",
            "noise": 0.002, "priors": {{"tilt": [26], "kappa": [1.5], "convexity_bias": [{}]}},
            "lapse": 0.05}}"#,
        (0.7f64 / 0.3).ln()
    );
    std::fs::write(dir.join("fitted-study.json"), spec).unwrap();
    let run = shadelab(
        &dir,
        &[
            "--quiet",
            "study",
            "run",
            "fitted-study.json",
            "--out",
            "fitted",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("fitted/results.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    assert_eq!(rows.len(), 8);
    for row in rows {
        let f: Vec<&str> = row.split(',').collect();
        let (theta, p): (f64, f64) = (f[7].parse().unwrap(), f[9].parse().unwrap());
        let want = model.p_convex(theta);
        assert!((p - want).abs() < 1e-6, "study θ = {theta}: {p} vs {want}");
    }
    // A fit.json that is not one is refused, naming the file and the flag.
    std::fs::write(dir.join("bad.json"), r#"{"prior_tilt_deg": 3}"#).unwrap();
    let mut args = picture.to_vec();
    args.extend(["--prior", "bad.json", "--out", "x"]);
    assert_error(&shadelab(&dir, &args), 2, "no prior_tilt_deg.value");
}

/// The bootstrap gives the same bytes on one thread and on two.
#[test]
fn the_fit_is_the_same_for_any_thread_count() {
    let dir = scratch("fit-threads");
    let truth = ModelParams {
        tilt_deg: -20.0,
        kappa: 1.5,
        convexity_prior: 0.55,
        lapse: 0.05,
    };
    std::fs::write(
        dir.join("r.csv"),
        simulated_responses(&truth, &design(), 8, 3, "p"),
    )
    .unwrap();
    let mut fits = Vec::new();
    for threads in ["1", "2"] {
        let out = format!("t{threads}");
        let run = shadelab(
            &dir,
            &[
                "--quiet",
                "--threads",
                threads,
                "fit",
                "observer",
                "r.csv",
                "--include-simulated",
                "--out",
                &out,
                "--bootstrap",
                "60",
                "--nonparametric",
            ],
        );
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let mut v = read_json(&dir.join(&out).join("fit.json"));
        v.as_object_mut().unwrap().remove("seconds");
        fits.push(v);
    }
    assert_eq!(fits[0], fits[1]);
}

/// jsPsych's rows of one participant as a study saves them: a consent screen, then each
/// trial's row (its key, its rt, the design's hash), from a simulated observer's answers.
fn study_rows(model: &ModelParams, seed: u64, who: &str, design_hash: &str) -> Vec<Value> {
    let mut rows = vec![serde_json::json!({
        "trial_type": "html-button-response", "participant": who, "response": 0,
        "rt": 1500, "design_hash": design_hash,
    })];
    for (i, line) in simulated_responses(model, &design(), 4, seed, who)
        .lines()
        .skip(1)
        .enumerate()
    {
        let f: Vec<&str> = line.split(',').collect();
        rows.push(serde_json::json!({
            "trial_type": "image-keyboard-response", "participant": who, "block": "test",
            "rotation_deg": f[4].parse::<f64>().unwrap(),
            "response": if f[5] == "convex" { "f" } else { "j" },
            "rt": 350.5 + ((i * 37) % 500) as f64,
            "key_convex": "f", "key_concave": "j", "design_hash": design_hash,
        }));
    }
    rows
}

/// jsPsych rows as a CSV with `delimiter`; with `;` (a European Excel's), decimal commas.
fn rows_csv(rows: &[Value], delimiter: &str) -> String {
    let columns = [
        "trial_type",
        "participant",
        "block",
        "rotation_deg",
        "response",
        "rt",
        "key_convex",
        "key_concave",
        "design_hash",
    ];
    let mut csv = columns.join(delimiter) + "\r\n";
    for r in rows {
        let cells: Vec<String> = columns
            .iter()
            .map(|c| match &r[c] {
                Value::Null => String::new(),
                Value::String(s) => s.clone(),
                v if delimiter == ";" => v.to_string().replace('.', ","),
                v => v.to_string(),
            })
            .collect();
        csv += &(cells.join(delimiter) + "\r\n");
    }
    csv
}

/// A lab's folder as it arrives: a JATOS results export (one result per line: two
/// participants and a questionnaire) beside the server's copy of one of them, a participant's
/// file from a European Excel (semicolons, decimal commas), a timed-out trial and a pilot's
/// simulated file. The copy is counted once with a warning naming both files, the timed-out
/// trial and the pilot left out and counted, and all of it in fit.json and methods.md; a file
/// of another design is refused naming the files until --mixed-designs; --include-simulated
/// takes the pilot, and the Methods paragraph says it was simulated.
#[test]
fn a_labs_folder_is_read_as_it_arrives() {
    let dir = scratch("fit-lab-folder");
    let data = dir.join("data");
    std::fs::create_dir_all(&data).unwrap();
    let model = |tilt: f64| ModelParams {
        tilt_deg: tilt,
        kappa: 2.5,
        convexity_prior: 0.6,
        lapse: 0.02,
    };
    let p1 = study_rows(&model(20.0), 1, "p1", "d1");
    let mut p2 = study_rows(&model(30.0), 2, "p2", "d1");
    // p2's 10th trial timed out: jsPsych writes no key and no rt.
    p2[10]["response"] = Value::Null;
    p2[10]["rt"] = Value::Null;
    let questionnaire = serde_json::json!([{"trial_type": "survey-likert", "participant": "p2",
        "response": {"Q0": 3}}]);
    let jatos = format!(
        "{}\n{}\n{}\n",
        Value::from(p1.clone()),
        Value::from(p2),
        questionnaire
    );
    std::fs::write(data.join("jatos_results_20261201.txt"), jatos).unwrap();
    std::fs::write(data.join("p1.csv"), rows_csv(&p1, ",")).unwrap();
    let p3 = study_rows(&model(10.0), 3, "p3", "d1");
    let excel = rows_csv(&p3, ";");
    assert!(excel.contains(";350,5;"), "{excel}");
    std::fs::write(data.join("p3.csv"), excel).unwrap();
    std::fs::write(
        data.join("pilot.csv"),
        simulated_responses(&model(26.0), &design(), 4, 9, "pilot"),
    )
    .unwrap();
    let fit_args = |out: &'static str, more: &[&'static str]| {
        let mut a = vec![
            "fit",
            "observer",
            "data",
            "--out",
            out,
            "--bootstrap",
            "0",
            "--lapse",
            "0.02",
        ];
        a.extend_from_slice(more);
        a
    };
    let run = shadelab(&dir, &fit_args("f", &[]));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(
        err.contains(
            "warning: participant 'p1': the same 96 rows are in \
             data/jatos_results_20261201.txt (result 1) and in data/p1.csv; counted once"
        ),
        "{err}"
    );
    assert!(
        err.contains("warning: 96 simulated trials (a pilot's) left out"),
        "{err}"
    );
    assert!(
        err.contains("warning: 1 trials without a response (timed out) left out"),
        "{err}"
    );
    let fit = read_json(&dir.join("f/fit.json"));
    let d = &fit["design"];
    assert_eq!(fit["n_trials"], 3 * 96 - 1, "{d}");
    let people: Vec<&str> = fit["participants"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["participant"].as_str().unwrap())
        .collect();
    assert_eq!(people, ["p1", "p2", "p3"]);
    let trials = |i: usize| fit["participants"][i]["n_trials"].as_u64().unwrap();
    assert_eq!((trials(0), trials(1), trials(2)), (96, 95, 96));
    assert_eq!(d["no_response_rows"], 1);
    assert_eq!(d["simulated_rows_left_out"], 96);
    assert_eq!(d["simulated_trials"], 0);
    assert_eq!(
        d["other_rows"], 4,
        "three consent screens and the questionnaire"
    );
    assert_eq!(d["duplicates"][0]["left_out"], "data/p1.csv");
    assert_eq!(d["duplicates"][0]["rows"], 96);
    assert_eq!(d["designs"].as_array().unwrap().len(), 1);
    assert_eq!(fit["reading"]["include_simulated"], false);
    let methods = std::fs::read_to_string(dir.join("f/methods.md")).unwrap();
    assert!(
        methods.contains("3 participants (3 fitted individually) judged")
            && methods.contains(
                "(1 trials without a response (timed out), 96 simulated trials (a pilot's) and \
                 96 rows that a second copy of the same data repeated were not analysed)"
            )
            && !methods.contains("were simulated"),
        "{methods}"
    );
    // The semicolon file alone, as it is: its decimal commas read.
    let alone = shadelab(
        &dir,
        &[
            "--quiet",
            "fit",
            "observer",
            "data/p3.csv",
            "--out",
            "p3",
            "--bootstrap",
            "0",
        ],
    );
    assert!(
        alone.status.success(),
        "{}",
        String::from_utf8_lossy(&alone.stderr)
    );
    assert_eq!(read_json(&dir.join("p3/fit.json"))["n_trials"], 96);

    // The pilot taken when asked for: said in the report and in the Methods paragraph.
    let run = shadelab(&dir, &fit_args("g", &["--include-simulated"]));
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let fit = read_json(&dir.join("g/fit.json"));
    assert_eq!(fit["n_trials"], 4 * 96 - 1);
    assert_eq!(fit["design"]["simulated_trials"], 96);
    let methods = std::fs::read_to_string(dir.join("g/methods.md")).unwrap();
    assert!(
        methods.contains("**Design.** 3 participants and 1 simulated observer (4 fitted individually) answered whether")
            && methods.contains("96 of these trials were simulated (a pilot's rows, answered by the observer model), not judged by people."),
        "{methods}"
    );
    // The pilot alone: no participant, no person.
    let run = shadelab(
        &dir,
        &[
            "--quiet",
            "fit",
            "observer",
            "data/pilot.csv",
            "--out",
            "pilot",
            "--bootstrap",
            "0",
            "--include-simulated",
        ],
    );
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let methods = std::fs::read_to_string(dir.join("pilot/methods.md")).unwrap();
    assert!(
        methods.contains(
            "**Design.** These responses were simulated, not given by people: a simulated \
             observer (the observer model of shadelab's pilot mode) answered whether"
        ) && !methods.contains("participants judged")
            && !methods.contains("One participant"),
        "{methods}"
    );
    assert_error(
        &shadelab(
            &dir,
            &["fit", "observer", "data/pilot.csv", "--out", "pilot2"],
        ),
        1,
        "every trial with a response is simulated (96 trials whose 'simulated' column is set: \
         a pilot's, not people's); to fit them anyway give --include-simulated",
    );

    // Another design's file: refused naming the files, then pooled when asked for.
    std::fs::write(
        data.join("q.json"),
        Value::from(study_rows(&model(20.0), 4, "q", "d2")).to_string(),
    )
    .unwrap();
    assert_error(
        &shadelab(&dir, &fit_args("h", &[])),
        1,
        "data: trials of 2 designs (another design_hash): d1 in data/jatos_results_20261201.txt \
         (result 1), data/jatos_results_20261201.txt (result 2), data/p3.csv; d2 in data/q.json; \
         fit each design alone, or pool them with --mixed-designs",
    );
    assert!(!dir.join("h").exists());
    let run = shadelab(&dir, &fit_args("h", &["--mixed-designs"]));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(err.contains("warning: 2 designs pooled"), "{err}");
    assert_eq!(read_json(&dir.join("h/fit.json"))["n_trials"], 4 * 96 - 1);
}
