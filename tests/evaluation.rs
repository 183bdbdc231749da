//! `shadelab eval` and the evaluation library on the shared data (skipped when it is absent),
//! and its errors when data is missing.

use crate::cli::{assert_error, scratch, shadelab};
use shadelab::Boundary;
use shadelab::Method;
use shadelab_analysis::evaluation::{self, CaseResult, Config, Set};
use std::path::PathBuf;

/// The shared evaluation data, or `None` (with the reason printed) when it is not there.
fn data() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    if dir.join("README.md").is_file() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: the evaluation data {} is not present",
            dir.display()
        );
        None
    }
}

/// Records the progress reports of a run.
#[derive(Default)]
struct Steps(std::sync::Mutex<(u64, Vec<u64>)>);

impl shadelab::Progress for Steps {
    fn start(&self, total: u64, _what: &str) {
        self.0.lock().unwrap().0 = total;
    }
    fn set_position(&self, done: u64) {
        self.0.lock().unwrap().1.push(done);
    }
}

fn run(config: &Config) -> Vec<CaseResult> {
    let steps = Steps::default();
    let results = evaluation::run(config, false, &steps, &mut |_, _| {
        panic!("no pictures were asked for")
    })
    .unwrap();
    let (total, positions) = steps.0.into_inner().unwrap();
    assert_eq!(positions.len(), config.case_count());
    assert_eq!(total as usize, results.len());
    assert_eq!(positions, (0..results.len() as u64).collect::<Vec<_>>());
    results
}

/// The engine's errors on a fast subset, against bounds measured on the working tree at commit
/// 4d4e493 (November 2026) with a margin (measured: bunny 128² frontal mean 18.3°, median
/// 11.7°, depth 8.3 % of its range; ball 052 occluding 2.06° / 1.76°; Mozart lit from
/// (1, 0, 1), free boundary, 18.7° and 14.9 %).
#[test]
fn errors_on_real_data_stay_within_measured_bounds() {
    let Some(dir) = data() else { return };
    let mut config = Config::new(&dir).unwrap();
    config.sets = vec![Set::Ball, Set::Bunny];
    config.bunny_size = 128;
    config.bunny_lights = vec![shadelab::FrontLight::FRONT];
    config.ball_images = vec!["052".into()];
    config.compared_boundaries = vec![Boundary::Occluding];
    config.object_boundaries = vec![Boundary::Occluding];
    config.methods = vec![Method::Multigrid];
    let r = run(&config);
    assert_eq!(r.len(), 2);
    let (ball, bunny) = (&r[0], &r[1]);
    assert_eq!((ball.set, ball.boundary), ("ball", "occluding"));
    let e = ball.normal_error.unwrap();
    assert!(e.mean_deg < 3.0 && e.median_deg < 2.7, "ball 052: {e:?}");
    assert!(ball.depth_error.is_none());
    // The albedo estimate is within 10 % of what the true normals give.
    let fitted = ball.albedo.with_true_normals.unwrap();
    assert!(
        (ball.albedo.value / fitted - 1.0).abs() < 0.1,
        "{:?}",
        ball.albedo
    );
    assert!(ball.residual < 0.02, "{}", ball.residual);

    let e = bunny.normal_error.unwrap();
    assert!(e.mean_deg < 21.0 && e.median_deg < 14.0, "bunny: {e:?}");
    let d = bunny.depth_error.unwrap();
    assert!(d.rms_percent_of_range < 10.5, "bunny depth: {d:?}");
    assert!(d.scale > 0.0, "the bunny came out hollow: {d:?}");

    let mut config = Config::new(&dir).unwrap();
    config.sets = vec![Set::Mozart];
    config.mozart_lights = vec!["1,0,1".parse().unwrap()];
    config.compared_boundaries = vec![Boundary::Free];
    config.methods = vec![Method::Multigrid];
    let r = run(&config);
    let e = r[0].normal_error.unwrap();
    assert!(e.mean_deg < 22.0, "mozart: {e:?}");
    let d = r[0].depth_error.unwrap();
    assert!(d.rms_percent_of_range < 18.0, "mozart depth: {d:?}");
    // Holes are solved on but not scored: fewer scored pixels than domain pixels.
    assert!(
        e.pixels < r[0].domain_pixels,
        "{} {}",
        e.pixels,
        r[0].domain_pixels
    );
}

/// `shadelab eval` on ball photograph 052 with the occluding boundary (one quick case), quiet,
/// with `more` flags.
fn ball_052<'a>(data: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "eval",
        "--data",
        data,
        "--only",
        "ball",
        "--ball-images",
        "052",
        "--boundary",
        "occluding",
        "--quiet",
    ];
    args.extend_from_slice(more);
    args
}

#[test]
fn eval_writes_table_report_and_pictures() {
    let Some(dir) = data() else { return };
    let d = scratch("eval-out");
    let data = dir.display().to_string();
    let out = shadelab(
        &d,
        &ball_052(
            &data,
            &[
                "--commit",
                "abc1234",
                "--method",
                "multigrid,integrable,integrable-lm",
                "--out",
                "res",
            ],
        ),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("| ball | ball | 052 (slant 4°) | occluding |"),
        "{stdout}"
    );
    let res = d.join("res");
    let md = std::fs::read_to_string(res.join("evaluation.md")).unwrap();
    assert!(
        md.contains("abc1234") && md.contains("| ball | ball |"),
        "{md}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(res.join("evaluation.json")).unwrap()).unwrap();
    assert_eq!(report["commit"], "abc1234");
    // A row per method, multigrid first, with the fields scripts read.
    let cases = report["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 3);
    for (case, method) in cases
        .iter()
        .zip(["multigrid", "integrable", "integrable-lm"])
    {
        assert_eq!(case["method"], method);
        assert_eq!(case["object"], "ball");
        assert_eq!(case["boundary"], "occluding");
        assert_eq!(case["converged"], true);
        assert!(case["normal_error"]["mean_deg"].as_f64().unwrap() < 3.0);
    }
    assert_eq!(
        report["parameters"]["solver"]["methods"],
        serde_json::json!(["multigrid", "integrable", "integrable-lm"])
    );
    assert!(
        stdout.contains("| ball | ball | 052 (slant 4°) | occluding | integrable |"),
        "{stdout}"
    );
    assert!(res.join("ball-052-occluding-integrable.png").is_file());
    // One picture: input, recovered normals, true normals, error and its colour bar (14 px of
    // bar and 46 of labels), shaded depth side by side, with 4 px gaps.
    let (w, h) = image_size(&res.join("ball-052-occluding.png"));
    assert_eq!(h, 146);
    assert_eq!(w, 5 * 146 + (14 + 46) + 5 * 4);
}

/// Without `--method`, eval solves each case once, with the method `shadelab solve` uses by
/// default, nested-lm since issue 62 (issue 43: the evaluation runs the default; the other
/// methods are asked for).
#[test]
fn eval_runs_the_solve_default_alone_unless_asked() {
    let Some(dir) = data() else { return };
    let d = scratch("eval-default");
    let data = dir.display().to_string();
    let out = shadelab(&d, &ball_052(&data, &["--json"]));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cases: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cases = cases.as_array().unwrap();
    assert_eq!(cases.len(), 1, "{cases:?}");
    assert_eq!(
        cases[0]["method"],
        shadelab::Method::SOLVE_DEFAULT.to_string()
    );
    assert_eq!(cases[0]["method"], "nested-lm");
}

fn image_size(path: &std::path::Path) -> (usize, usize) {
    let rgb = shadelab_io::read_rgb(path, 1 << 24).unwrap();
    (rgb.width(), rgb.height())
}

#[test]
fn missing_data_is_a_one_line_error_naming_what_was_expected() {
    let d = scratch("eval-missing");
    let out = shadelab(&d, &["eval", "--data", "no-such-folder"]);
    assert_error(&out, 1, "no-such-folder: evaluation data folder not found");
    // A folder without the file a chosen set needs: the file is named, nothing is written.
    std::fs::create_dir_all(d.join("data/bunny")).unwrap();
    let out = shadelab(
        &d,
        &["eval", "--data", "data", "--only", "bunny", "--out", "res"],
    );
    assert_error(&out, 1, "bunny/bun_zipper_res2.ply");
    assert!(!d.join("res").exists());
    let out = shadelab(&d, &["eval", "--data", "data", "--only", "teapot"]);
    assert_error(&out, 2, "unknown evaluation set 'teapot'");
    let out = shadelab(&d, &["eval", "--data", "data", "--objects", "teapot"]);
    assert_error(&out, 2, "unknown DiLiGenT object 'teapot'");
}

/// The integrable method against its goals of issue 20 on the cases that are quick: the
/// oblique Mozart with the free boundary (measured 13.62°, depth 7.9 % of its range, at its
/// cap of 200 iterations; 14.30° and 8.7 % before the angle residual of session 9; the best
/// public method, Quéau et al.'s ADMM, 15.78° and 12.2 %; multigrid 18.68°) and the ball
/// photograph 008 (26°, measured 3.40°, 3.58° before, converged; multigrid 5.15°), each more
/// than 1° better than multigrid's row.
#[test]
fn integrable_method_beats_ikeuchi_horn_on_mozart_and_the_ball() {
    let Some(dir) = data() else { return };
    let mut config = Config::new(&dir).unwrap();
    config.mozart_lights = vec!["1,0,1".parse().unwrap()];
    config.compared_boundaries = vec![Boundary::Free];
    config.ball_images = vec!["008".into()];
    config.methods = vec![Method::Multigrid, Method::Integrable];
    // The ball with the occluding boundary, Mozart with the free one.
    config.sets = vec![Set::Mozart];
    let mozart = run(&config);
    config.sets = vec![Set::Ball];
    config.compared_boundaries = vec![Boundary::Occluding];
    let ball = run(&config);
    for rows in [&mozart, &ball] {
        assert_eq!(rows.len(), 2);
        let (ih, int) = (&rows[0], &rows[1]);
        assert_eq!(
            (ih.method.as_str(), int.method.as_str()),
            ("multigrid", "integrable")
        );
        let (a, b) = (ih.normal_error.unwrap(), int.normal_error.unwrap());
        assert!(b.mean_deg < a.mean_deg - 1.0, "{a:?} {b:?}");
    }
    let e = mozart[1].normal_error.unwrap();
    let d = mozart[1].depth_error.unwrap();
    assert!(
        e.mean_deg < 14.0 && d.rms_percent_of_range < 8.5,
        "{e:?} {d:?}"
    );
    let e = ball[1].normal_error.unwrap();
    assert!(e.mean_deg < 3.5 && ball[1].converged, "{e:?}");
}

/// The angle residual of the integrable method (session 9) on the cases it moved most that
/// are quick: Mozart under the frontal light with its occluding boundary (measured 10.80°,
/// depth 5.9 % of its range; 12.15° and 6.2 % before; multigrid 17.72°) and the ball
/// photograph 041 lit at 43° (measured 6.68°, 6.75° before; multigrid 8.69°; the goal of
/// issue 20, 6°, is not met).
#[test]
fn integrable_angle_residual_on_mozart_frontal_and_ball_041() {
    let Some(dir) = data() else { return };
    let mut config = Config::new(&dir).unwrap();
    config.mozart_lights = vec![shadelab::FrontLight::FRONT];
    config.compared_boundaries = vec![Boundary::Occluding];
    config.ball_images = vec!["041".into()];
    config.methods = vec![Method::Integrable];
    config.sets = vec![Set::Mozart, Set::Ball];
    let rows = run(&config);
    assert_eq!(rows.len(), 2);
    let (mozart, ball) = (&rows[0], &rows[1]);
    assert_eq!(
        (mozart.object.as_str(), ball.object.as_str()),
        ("mozart", "ball")
    );
    let e = mozart.normal_error.unwrap();
    let d = mozart.depth_error.unwrap();
    assert!(
        e.mean_deg < 11.3 && d.rms_percent_of_range < 6.2 && mozart.converged,
        "{e:?} {d:?}"
    );
    let e = ball.normal_error.unwrap();
    assert!(e.mean_deg < 6.72 && ball.converged, "{e:?}");
}

/// The objects seen whole (bunny, DiLiGenT, Beethoven) get a row per boundary by default,
/// occluding and limb. On the goblet, whose rim is a cut facing the viewer rather than a limb,
/// the limb condition is the better one by more than 3° (multigrid 25.32° → 21.99°).
#[test]
fn whole_objects_get_an_occluding_and_a_limb_row() {
    let Some(dir) = data() else { return };
    let mut config = Config::new(&dir).unwrap();
    config.sets = vec![Set::Diligent];
    config.diligent_objects = vec!["goblet".into()];
    config.methods = vec![Method::Multigrid];
    assert_eq!(config.case_count(), 2);
    let r = run(&config);
    assert_eq!(r.len(), 2);
    assert_eq!((r[0].boundary, r[1].boundary), ("occluding", "limb"));
    let occluding = r[0].normal_error.unwrap().mean_deg;
    let limb = r[1].normal_error.unwrap().mean_deg;
    assert!(
        limb < occluding - 3.0,
        "occluding {occluding}°, limb {limb}°"
    );
    // The limb row says what its test found (a render: no dark level); the occluding row
    // has no test to report.
    assert_eq!(r[0].limb, None);
    let limb = r[1].limb.unwrap();
    assert!(limb.not_limb > 0);
    assert_eq!(limb.dark_level, 0.0);
}
