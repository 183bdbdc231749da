//! `shadelab experiment`: the design (every rotation repeated, a seeded order), the images (their
//! bright side faces θ), refusals, the folder, the command line, and the jsPsych study itself in
//! headless Chromium: a participant pressing keys, the study as a participant's link opens it
//! (fullscreen asked for, the card calibration's pixels per degree, the images drawn at their
//! degrees), the pilot mode's data fitted back by `shadelab fit observer` to the simulated prior,
//! each participant's own order, the data POSTed to a real local server (and the download when it
//! refuses), JATOS through a double of its `jatos` object, and a lab's own jsPsych page embedding
//! the timeline. The browser tests skip, saying why, where Chromium is not installed or npm
//! cannot install jsPsych (into target/jspsych/, once).

use crate::chromium::{chromium, run, Server};
use crate::cli::{assert_error, scratch, shadelab};
use shadelab::pipeline::experiment::{self, Config, CSV_HEADER};
use shadelab::{NoProgress, Output};
use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

/// How the fit reads a pilot's rows (the page's simulated participant): taken, not left out.
fn pilot() -> shadelab::pipeline::fit::Reading {
    shadelab::pipeline::fit::Reading {
        include_simulated: true,
        ..Default::default()
    }
}

/// The design's test trials per rotation.
fn counts(report: &experiment::Report) -> BTreeMap<String, usize> {
    let mut n = BTreeMap::new();
    for t in report.design.trials.iter().filter(|t| t.block == "test") {
        *n.entry(format!("{}", t.rotation_deg)).or_insert(0) += 1;
    }
    n
}

#[test]
fn the_default_design_shows_every_rotation_repeats_times_in_a_seeded_order() {
    let config = Config::new();
    let report = experiment::run(&config, &NoProgress).unwrap();
    let d = &report.design;
    assert_eq!(d.rotations_deg.len(), 24);
    assert_eq!(d.rotations_deg[1], 15.0);
    assert_eq!(d.test_trials, 24 * experiment::DEFAULT_REPEATS);
    assert_eq!(d.trials.len(), d.test_trials + d.practice_trials);
    let n = counts(&report);
    assert_eq!(n.len(), 24);
    assert!(
        n.values().all(|&c| c == experiment::DEFAULT_REPEATS),
        "{n:?}"
    );
    // Practice first, numbered from 1 in presentation order.
    let blocks: Vec<&str> = d.trials.iter().map(|t| t.block).collect();
    assert!(blocks[..8].iter().all(|b| *b == "practice"));
    assert!(blocks[8..].iter().all(|b| *b == "test"));
    assert!(d.trials.iter().enumerate().all(|(i, t)| t.trial == i + 1));
    // Shuffled: the test block is not the rotations in their order.
    let first: Vec<f64> = d.trials[8..32].iter().map(|t| t.rotation_deg).collect();
    assert_ne!(first, d.rotations_deg);
    // The same seed gives the same order; another seed another order of the same trials.
    let again = experiment::run(&config, &NoProgress).unwrap();
    assert_eq!(again.design.trials, d.trials);
    let mut other = config.clone();
    other.seed = 2;
    let other = experiment::run(&other, &NoProgress).unwrap();
    assert_ne!(other.design.trials, d.trials);
    assert_eq!(counts(&other), n);
    // Every image's measured bright side lies near its rotation.
    for image in &d.images {
        let off = (image.bright_side_deg - image.rotation_deg + 540.0).rem_euclid(360.0) - 180.0;
        assert!(off.abs() < 5.0, "{image:?}");
    }
}

/// Mean luminance of the rows `rows` and columns `cols` of an image file.
fn mean(path: &Path, rows: std::ops::Range<usize>, cols: std::ops::Range<usize>) -> f64 {
    let (image, _) = shadelab_io::read_luminance(path, 1 << 24).unwrap();
    let mut sum = 0.0;
    for r in rows.clone() {
        for c in cols.clone() {
            sum += *image.get(c, r);
        }
    }
    sum / (rows.len() * cols.len()) as f64
}

#[test]
fn the_written_images_bright_side_faces_theta() {
    let d = scratch("experiment-images");
    let mut config = Config::new();
    config.rotations = vec![0.0, 90.0, 180.0, 270.0];
    config.repeats = 1;
    let report = experiment::run(&config, &NoProgress).unwrap();
    let folder = report.write(&Output::new(d.join("e"))).unwrap().folder;
    let img = |deg: &str| folder.join(format!("images/theta-{deg}.png"));
    let (h, w) = report.design.display.shape;
    assert_eq!((h, w), (128, 128));
    let (top, bottom) = (0..h / 2, h / 2..h);
    let (left, right) = (0..w / 2, w / 2..w);
    let margin = 0.03;
    // θ = 0: bright side up; 90: left; 180: down; 270: right.
    assert!(
        mean(&img("000"), top.clone(), 0..w) > mean(&img("000"), bottom.clone(), 0..w) + margin
    );
    assert!(
        mean(&img("090"), 0..h, left.clone()) > mean(&img("090"), 0..h, right.clone()) + margin
    );
    assert!(
        mean(&img("180"), bottom.clone(), 0..w) > mean(&img("180"), top.clone(), 0..w) + margin
    );
    assert!(mean(&img("270"), 0..h, right) > mean(&img("270"), 0..h, left) + margin);
    // Up and down are balanced when the light comes from the side.
    let side = (mean(&img("090"), top, 0..w) - mean(&img("090"), bottom, 0..w)).abs();
    assert!(side < 1e-3, "{side}");
    // Each image has its sidecar, which records the light that turned it.
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("images/theta-090.json")).unwrap())
            .unwrap();
    assert_eq!(sidecar["parameters"]["light"], "tilt=90,slant=45");
    assert_eq!(sidecar["program"], "shadelab");
    assert!(folder.join("images/theta-090_mask.png").exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn bad_configs_are_refused_with_one_line() {
    type Change = fn(&mut Config);
    let cases: &[(Change, &str)] = &[
        (|c| c.stimulus = "disc".into(), "no light to turn"),
        (|c| c.stimulus = "teapot".into(), "unknown stimulus"),
        (
            |c| {
                c.params.insert("light".into(), "above".into());
            },
            "set by each trial's rotation",
        ),
        (|c| c.slant_deg = 90.0, "slant"),
        (|c| c.slant_deg = f64::NAN, "slant"),
        (|c| c.rotations.clear(), "at least one rotation"),
        (|c| c.rotations = vec![0.0, 360.0], "given twice"),
        (|c| c.rotations = vec![f64::INFINITY], "not a number"),
        (|c| c.repeats = 0, "repeats"),
        (|c| c.practice = 1000, "practice"),
        (|c| c.seed = 1 << 53, "2^53 − 1: the page's JavaScript"),
        (|c| c.ppd = 0.0, "pixels per degree"),
        (|c| c.viewing_distance_cm = 1.0, "viewing distance"),
        (|c| c.visual_size = (0.0, 4.0), "visual size"),
        (|c| c.keys.concave = 'f', "both 'f'"),
        (|c| c.keys.convex = 'F', "lower-case"),
        (|c| c.gamma = Some(0.0), "gamma"),
        (
            |c| c.save_url = Some("ftp://lab.example/save".into()),
            "the save URL",
        ),
        (
            |c| c.save_url = Some("https://lab.example/a b".into()),
            "without spaces",
        ),
        (
            |c| c.completion_url = Some("/done".into()),
            "the completion URL",
        ),
    ];
    for (change, needle) in cases {
        let mut config = Config::new();
        change(&mut config);
        let e = config.validate().unwrap_err().to_string();
        assert!(e.contains(needle), "'{needle}' not in: {e}");
        assert!(!e.contains('\n') && !e.contains("--"), "{e}");
        assert!(experiment::run(&config, &NoProgress).is_err());
    }
    // What only rendering shows: two targets, and a dimple (its bright side faces away).
    let mut two = Config::new();
    two.params.insert("columns".into(), 2.into());
    two.visual_size = (4.0, 8.0);
    let e = experiment::run(&two, &NoProgress).unwrap_err().to_string();
    assert!(e.contains("shows 2 targets"), "{e}");
    let mut dimple = Config::new();
    dimple.params.insert("pattern".into(), "dimples".into());
    let e = experiment::run(&dimple, &NoProgress)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("bright side") && e.contains("not a dimple"),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
}

#[test]
fn the_folder_is_whole_and_replaced_only_when_it_is_shadelabs() {
    let d = scratch("experiment-folder");
    let mut config = Config::new();
    config.rotations = vec![0.0, 120.0, 240.0];
    config.repeats = 2;
    config.practice = 1;
    let report = experiment::run(&config, &NoProgress).unwrap();
    let folder = report.write(&Output::new(d.join("e"))).unwrap().folder;
    for f in [
        "index.html",
        "jatos.html",
        "experiment.js",
        "shadelab-timeline.js",
        "experiment.css",
        "package.json",
        "design.json",
        "README.md",
    ] {
        assert!(folder.join(f).is_file(), "{f}");
    }
    // jsPsych comes from npm at pinned versions; not installed unless asked.
    let package: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("package.json")).unwrap()).unwrap();
    for (name, version, _) in experiment::JSPSYCH_PACKAGES {
        assert_eq!(package["dependencies"][name], *version, "{package}");
    }
    assert_eq!(package["dependencies"]["jspsych"], "8.3.0");
    assert!(!folder.join("node_modules").exists());
    let design: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("design.json")).unwrap()).unwrap();
    assert_eq!(design["program"], "shadelab");
    assert_eq!(design["seed"], 1);
    assert_eq!(design["trials"].as_array().unwrap().len(), 7);
    assert_eq!(
        design["display"]["visual_size"],
        serde_json::json!([4.0, 4.0])
    );
    assert_eq!(design["model"]["responses_csv"], CSV_HEADER);
    assert_eq!(
        design["keys"],
        serde_json::json!({"convex": "f", "concave": "j"})
    );
    // The page embeds the same design, so it also runs when opened as a file.
    let page = std::fs::read_to_string(folder.join("index.html")).unwrap();
    let embedded = page
        .split("<script id=\"design\" type=\"application/json\">")
        .nth(1)
        .and_then(|s| s.split("</script>").next())
        .unwrap();
    assert_eq!(
        serde_json::from_str::<serde_json::Value>(embedded).unwrap(),
        design
    );
    // Nothing points outside the folder: jsPsych from node_modules/, JATOS's script only in
    // jatos.html.
    assert!(!page.contains("http://") && !page.contains("https://"));
    assert!(page.contains("<script src=\"node_modules/jspsych/dist/index.browser.min.js\">"));
    assert!(!page.contains("jatos.js"));
    let jatos = std::fs::read_to_string(folder.join("jatos.html")).unwrap();
    assert!(jatos.contains("<script src=\"jatos.js\"></script>"));
    assert_eq!(
        jatos.replace("<script src=\"jatos.js\"></script>\n", ""),
        page
    );
    let js = std::fs::read_to_string(folder.join("experiment.js")).unwrap();
    assert!(!js.contains("http://") && !js.contains("https://"));
    // Written again: replaced (it is shadelab's); the same bytes.
    let before = std::fs::read(folder.join("design.json")).unwrap();
    report.write(&Output::new(d.join("e"))).unwrap();
    assert_eq!(std::fs::read(folder.join("design.json")).unwrap(), before);
    // A folder of someone else's is refused, and left alone.
    let foreign = d.join("theirs");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let e = report.write(&Output::new(&foreign)).unwrap_err();
    assert!(matches!(e, shadelab::Error::NotOurs { .. }), "{e}");
    assert_eq!(
        std::fs::read_to_string(foreign.join("notes.txt")).unwrap(),
        "mine"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_command_line_writes_the_folder_and_refuses_bad_flags() {
    let d = scratch("experiment-cli");
    let out = shadelab(
        &d,
        &[
            "experiment",
            "--out",
            "e",
            "--rotations",
            "0:360:90",
            "--repeats",
            "3",
            "--practice",
            "2",
            "--keys",
            "d,k",
            "--visual-size",
            "6x3",
            "--ppd",
            "20",
            "--seed",
            "9",
            "--break-every",
            "5",
            "--save-url",
            "https://lab.example/save",
            "--save-format",
            "csv",
            "--prolific-code",
            "C1234ABC",
            "--counterbalance-keys",
            "--no-install",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("14 trials (2 practice, 4 rotations x 3 repeats)"),
        "{stdout}"
    );
    let design: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("e/design.json")).unwrap()).unwrap();
    assert_eq!(
        design["keys"],
        serde_json::json!({"convex": "d", "concave": "k"})
    );
    assert_eq!(design["display"]["shape"], serde_json::json!([60, 120]));
    assert_eq!(design["seed"], 9);
    assert_eq!(design["break_every"], 5);
    assert_eq!(design["save_url"], "https://lab.example/save");
    assert_eq!(design["save_format"], "csv");
    assert_eq!(design["counterbalance_keys"], true);
    assert_eq!(
        design["completion_url"],
        "https://app.prolific.com/submissions/complete?cc=C1234ABC"
    );
    assert!(!d.join("e/node_modules").exists());
    for (flags, needle) in [
        (&["--save-format", "xml"][..], "--save-format 'xml'"),
        (
            &["--seed", "9007199254740992"][..],
            "--seed: seed 9007199254740992 must be at most 9007199254740991",
        ),
        (&["--prolific-code", "no spaces"][..], "--prolific-code"),
        (&["--save-url", "lab.example/save"][..], "--save-url"),
        (
            &["--completion-url", "javascript:alert(1)"][..],
            "--completion-url",
        ),
    ] {
        let args = [&["experiment", "--out", "x", "--no-install"][..], flags].concat();
        assert_error(&shadelab(&d, &args), 2, needle);
    }
    assert_error(
        &shadelab(&d, &["experiment", "--out", "x", "--keys", "fjk"]),
        2,
        "--keys",
    );
    assert_error(
        &shadelab(&d, &["experiment", "--out", "x", "--stimulus", "disc"]),
        2,
        "no light to turn",
    );
    assert_error(
        &shadelab(&d, &["experiment", "--out", "x", "--rotations", "0,360"]),
        2,
        "given twice",
    );
    assert_error(
        &shadelab(&d, &["experiment", "--out", "x", "--set", "light=above"]),
        2,
        "rotation",
    );
    assert!(!d.join("x").exists());
    let _ = std::fs::remove_dir_all(&d);
}

/// `node_modules/` with the study's packages (its package.json, as `shadelab experiment` writes
/// it), installed by npm once into target/jspsych/; `None` after saying why the calling test
/// skips (no Chromium, no npm, no network).
fn jspsych() -> Option<PathBuf> {
    chromium()?;
    static MODULES: OnceLock<Option<PathBuf>> = OnceLock::new();
    let found = MODULES.get_or_init(|| {
        let package = experiment::package_json();
        let hash: String = {
            use md5::{Digest, Md5};
            Md5::digest(package.as_bytes())
                .iter()
                .take(6)
                .map(|b| format!("{b:02x}"))
                .collect()
        };
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/jspsych");
        let dir = root.join(&hash);
        let modules = dir.join("node_modules");
        if modules.join("jspsych/dist/index.browser.min.js").is_file() {
            return Some(modules);
        }
        let temp = root.join(format!("{hash}.tmp-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&temp);
        std::fs::create_dir_all(&temp).unwrap();
        std::fs::write(temp.join("package.json"), &package).unwrap();
        let out = std::process::Command::new("npm")
            .args(["install", "--no-audit", "--no-fund", "--loglevel=error"])
            .current_dir(&temp)
            .output();
        match out {
            Ok(o) if o.status.success() => {
                let _ = std::fs::rename(&temp, &dir);
                let _ = std::fs::remove_dir_all(&temp);
                Some(modules).filter(|m| m.join("jspsych").is_dir())
            }
            Ok(o) => {
                eprintln!(
                    "jsPsych test skipped: npm install failed: {}",
                    String::from_utf8_lossy(&o.stderr)
                        .lines()
                        .next()
                        .unwrap_or("")
                );
                None
            }
            Err(e) => {
                eprintln!("jsPsych test skipped: npm is not available ({e})");
                None
            }
        }
    });
    if found.is_none() {
        eprintln!("jsPsych test skipped: jsPsych could not be installed (see above)");
    }
    found.clone()
}

/// Writes the experiment of `config` with jsPsych linked in (as `npm install` would put it).
fn study(config: &Config, out: &Path, modules: &Path) -> (experiment::Report, PathBuf) {
    let report = experiment::run(config, &NoProgress).unwrap();
    let folder = report.write(&Output::new(out)).unwrap().folder;
    std::os::unix::fs::symlink(modules, folder.join("node_modules")).unwrap();
    (report, folder)
}

/// The text of the element `<tag id="id">` in a dumped DOM, unescaped.
fn element(dom: &str, tag: &str, id: &str) -> Option<String> {
    let open = format!("<{tag} id=\"{id}\"");
    let start = dom.find(&open)?;
    let start = start + dom[start..].find('>')? + 1;
    let end = dom[start..].find(&format!("</{tag}>"))?;
    Some(
        dom[start..start + end]
            .replace("&quot;", "\"")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&"),
    )
}

/// jsPsych's CSV as rows of named fields.
fn rows(csv: &str) -> Vec<BTreeMap<String, String>> {
    let table = shadelab_io::parse_csv(csv).unwrap();
    let (_, header) = &table[0];
    table[1..]
        .iter()
        .map(|(_, r)| header.iter().cloned().zip(r.iter().cloned()).collect())
        .collect()
}

/// The bump/dimple trial rows of jsPsych data.
fn trials(rows: &[BTreeMap<String, String>]) -> Vec<&BTreeMap<String, String>> {
    rows.iter().filter(|r| r["shadelab"] == "trial").collect()
}

const ARGS: [&str; 4] = [
    "--virtual-time-budget=30000",
    "--dump-dom",
    "--enable-logging=stderr",
    "--v=0",
];

/// A page that frames the study (`index.html?` + `query`) and plays a participant: every 100 ms,
/// on the card calibration's screen it drags the card's corner until the card is `CARD_PX` wide
/// and goes on; elsewhere it clicks the screen's button if it has one, else presses the space
/// bar, F or J in turn (keydown and keyup, where jsPsych listens), until the end screen. It
/// copies the `<pre id="results">` out into `<pre id="result">`, and into `<pre id="sizes">`
/// the size on the page (CSS pixels) of each trial's image, as `width x height` lines.
fn participant(query: &str) -> String {
    r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><link rel="icon" href="data:,"><title>participant</title></head><body>
<pre id="result">pending</pre>
<pre id="sizes"></pre>
<iframe id="page" src="index.html?QUERY" style="width:1000px;height:800px"></iframe>
<script>
const frame = document.getElementById('page');
frame.addEventListener('load', async () => {
  const w = frame.contentWindow, doc = frame.contentDocument;
  const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
  const sizes = [];
  const mouse = (target, type, x) => target.dispatchEvent(
    new w.MouseEvent(type, { clientX: x, clientY: 300, bubbles: true }));
  for (let i = 0; i < 3000 && !doc.getElementById('results'); i++) {
    await sleep(100);
    const card = doc.getElementById('item');
    const handle = doc.getElementById('jspsych-resize-handle');
    if (card && handle) {
      // The plugin widens the card by twice the drag.
      const from = parseInt(card.style.width, 10);
      mouse(handle, 'mousedown', 100);
      mouse(handle, 'mousemove', 100 + (CARD_PX - from) / 2);
      mouse(doc, 'mouseup', 100 + (CARD_PX - from) / 2);
      doc.getElementById('end_resize_phase').click();
      continue;
    }
    const image = doc.getElementById('jspsych-image-keyboard-response-stimulus');
    if (image && image.dataset.seen !== '1') {
      image.dataset.seen = '1';
      const r = image.getBoundingClientRect();
      sizes.push(`${r.width} x ${r.height}`);
    }
    const button = doc.querySelector('.jspsych-btn');
    if (button) { button.click(); continue; }
    const key = i % 3 === 0 ? ' ' : (i % 3 === 1 ? 'f' : 'j');
    const target = doc.querySelector('.jspsych-content-wrapper') || doc.body;
    for (const type of ['keydown', 'keyup']) {
      target.dispatchEvent(new w.KeyboardEvent(type, { key: key, bubbles: true }));
    }
  }
  await sleep(500);
  const r = doc.getElementById('results');
  document.getElementById('sizes').textContent = sizes.join('\n');
  document.getElementById('result').textContent = r ? r.textContent : 'no results';
});
</script></body></html>
"#
    .replace("QUERY", query)
    .replace("CARD_PX", &CARD_PX.to_string())
}

/// The width (CSS pixels) the participant of [`participant`] drags the calibration's card to.
const CARD_PX: u32 = 400;

#[test]
fn a_participant_answers_by_key_and_the_jspsych_data_are_complete() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-participant");
    let mut config = Config::new();
    config.rotations = vec![0.0, 90.0, 180.0, 270.0];
    config.repeats = 2;
    config.practice = 1;
    config.break_every = 3;
    let (report, folder) = study(&config, &d.join("e"), &modules);
    let page = participant("participant=T1&fullscreen=0&calibration=none");
    let server = Server::start(&folder, &[("__participant.html", &page)]);
    let page = run(
        &server.url("__participant.html"),
        &d.join("profile"),
        &[
            "--virtual-time-budget=60000",
            "--dump-dom",
            "--enable-logging=stderr",
            "--v=0",
        ],
        Duration::from_secs(120),
    );
    assert!(page.console().is_empty(), "console: {:#?}", page.console());
    let csv = element(&page.stdout, "pre", "result").unwrap();
    let all = rows(&csv);
    let shown = trials(&all);
    assert_eq!(shown.len(), 9, "{csv}");
    // Two breaks in 8 test trials, every 3 (none after the last).
    let breaks: Vec<_> = all.iter().filter(|r| r["shadelab"] == "break").collect();
    assert_eq!(breaks.len(), 2, "{csv}");
    assert!(breaks.iter().all(|r| r["break"] == "true"));
    let d_ = &report.design;
    // The participant's order holds the design's trials, each once.
    let mut seen: Vec<(String, String)> = shown
        .iter()
        .map(|r| (r["block"].clone(), r["rotation_deg"].clone()))
        .collect();
    let mut planned: Vec<(String, String)> = d_
        .trials
        .iter()
        .map(|t| (t.block.to_string(), t.rotation_deg.to_string()))
        .collect();
    seen.sort();
    planned.sort();
    assert_eq!(seen, planned);
    assert_eq!(shown[0]["block"], "practice");
    assert_eq!(shown[0]["practice"], "true");
    for (i, r) in shown.iter().enumerate() {
        // The participant, their order, the display, the design: in every trial row.
        assert_eq!(r["participant"], "T1");
        assert_eq!(r["design_hash"], d_.design_hash);
        assert_eq!(r["shadelab_trial"], (i + 1).to_string());
        assert_eq!(r["trial_type"], "image-keyboard-response");
        assert_eq!(r["ppd"], "32");
        assert!(r["ppd_method"].starts_with("none"), "{r:?}");
        assert_eq!(r["viewing_distance_cm"], "57");
        assert!(r["user_agent"].contains("Chrome"), "{r:?}");
        for k in [
            "screen_width",
            "screen_height",
            "window_width",
            "window_height",
        ] {
            assert!(r[k].parse::<u32>().unwrap() > 0, "{k}: {r:?}");
        }
        assert_eq!(r["fullscreen"], "false");
        assert!(!r["order_seed"].is_empty());
        assert_eq!(r["stimulus"], r["image"]);
        let (response, judgement) = (r["response"].as_str(), r["judgement"].as_str());
        assert!(
            (response, judgement) == ("f", "convex") || (response, judgement) == ("j", "concave"),
            "{r:?}"
        );
        // Keys come every 100 ms, so a trial is answered within about 300 ms of its onset.
        let rt: f64 = r["rt"].parse().unwrap();
        assert!((0.0..=1000.0).contains(&rt), "{r:?}");
    }
    // Without a calibration, one image pixel is one CSS pixel: the images' own size.
    let ((h, w), ppd) = (report.design.display.visual_size, report.design.display.ppd);
    let own = format!("{} x {}", (w * ppd).round(), (h * ppd).round());
    let sizes = element(&page.stdout, "pre", "sizes").unwrap();
    assert_eq!(sizes.lines().count(), 9, "{sizes}");
    assert!(sizes.lines().all(|l| l == own), "{sizes} (expected {own})");
    // The fit reads the data as they are: the key mapping from the rows.
    std::fs::write(d.join("t1.csv"), &csv).unwrap();
    let r = shadelab::pipeline::fit::read_responses(&d.join("t1.csv")).unwrap();
    assert_eq!(r.participants.len(), 1);
    assert_eq!(r.participants[0].0, "T1");
    assert_eq!(r.participants[0].1.len(), 8);
    assert_eq!(r.practice_rows, 1);
    assert!(r.other_rows > 10, "{}", r.other_rows);
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_card_calibration_sets_pixels_per_degree_and_the_images_subtend_their_degrees() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-card");
    let mut config = Config::new();
    config.rotations = vec![0.0, 180.0];
    config.repeats = 1;
    config.practice = 0;
    let (report, folder) = study(&config, &d.join("e"), &modules);
    // The study as a participant's link opens it: fullscreen and the card calibration on.
    let page = participant("participant=T2");
    let server = Server::start(&folder, &[("__participant.html", &page)]);
    let page = run(
        &server.url("__participant.html"),
        &d.join("profile"),
        &ARGS,
        Duration::from_secs(120),
    );
    // A scripted click is no user gesture, so Chromium refuses fullscreen (what a participant's
    // click would grant); that refusal, said twice, is all the console may hold: the study goes
    // on without it.
    let refused = |l: &&str| {
        l.contains("can only be initiated by a user gesture")
            || l.contains("Uncaught (in promise) TypeError: Permissions check failed")
    };
    let console = page.console();
    assert!(console.iter().all(refused), "console: {console:#?}");
    let csv = element(&page.stdout, "pre", "result").unwrap();
    let all = rows(&csv);
    // Fullscreen asked for before the calibration and left after the test.
    let fullscreen: Vec<_> = all
        .iter()
        .enumerate()
        .filter(|(_, r)| r["shadelab"] == "fullscreen")
        .map(|(i, _)| i)
        .collect();
    let calibration = all.iter().position(|r| r["shadelab"] == "calibration");
    let last_trial = all.iter().rposition(|r| r["shadelab"] == "trial");
    assert_eq!(fullscreen.len(), 2, "{csv}");
    assert!(
        Some(fullscreen[0]) < calibration && last_trial < Some(fullscreen[1]),
        "{csv}"
    );
    // The card screen's row: the card as wide as the participant made it (a credit card is
    // 85.6 mm wide).
    let card: Vec<_> = all
        .iter()
        .filter(|r| r["shadelab"] == "calibration")
        .collect();
    assert_eq!(card.len(), 1, "{csv}");
    assert_eq!(card[0]["item_width_px"], CARD_PX.to_string(), "{csv}");
    assert_eq!(card[0]["item_width_mm"], "85.6", "{csv}");
    // Pixels per degree at the viewing distance D: the card's pixels per cm times the length
    // that subtends one degree, 2 D tan(0.5°), exact (not from jsPsych's px2mm, rounded to
    // two decimals).
    let distance = report.design.display.viewing_distance_cm;
    let ppd = f64::from(CARD_PX) / 8.56 * 2.0 * distance * 0.5_f64.to_radians().tan();
    let shown = trials(&all);
    assert_eq!(shown.len(), 2, "{csv}");
    for r in &shown {
        let got: f64 = r["ppd"].parse().unwrap();
        assert!(
            (got - ppd).abs() < 1e-9 * ppd,
            "ppd {got}, expected {ppd}: {r:?}"
        );
        assert_eq!(r["ppd_method"], "virtual-chinrest card", "{r:?}");
        assert_eq!(r["fullscreen"], "false", "{r:?}");
    }
    // Each image is drawn at its visual size in degrees times that ppd, in CSS pixels.
    let (h, w) = report.design.display.visual_size;
    let expected = format!("{} x {}", (w * ppd).round(), (h * ppd).round());
    assert_ne!(ppd.round(), 32.0, "the card must change the images' scale");
    let sizes = element(&page.stdout, "pre", "sizes").unwrap();
    assert_eq!(sizes.lines().count(), 2, "{sizes}");
    assert!(
        sizes.lines().all(|l| l == expected),
        "{sizes} (expected {expected})"
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

/// The rotations of a pilot's test trials, in the order shown.
fn order(dom: &str) -> Vec<String> {
    let csv = element(dom, "pre", "results").unwrap_or_else(|| panic!("no results in {dom}"));
    trials(&rows(&csv))
        .iter()
        .filter(|r| r["block"] == "test")
        .map(|r| r["rotation_deg"].clone())
        .collect()
}

#[test]
fn the_pilot_is_fitted_back_and_each_participant_gets_their_own_order() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-browser");
    let config = Config::new();
    let (report, folder) = study(&config, &d.join("e"), &modules);
    let server = Server::start(&folder, &[]);
    let timeout = Duration::from_secs(120);
    let pilot = "index.html?simulate=tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1";

    // The pilot: jsPsych's simulation mode, every trial answered by the model.
    let page = run(&server.url(pilot), &d.join("profile-sim"), &ARGS, timeout);
    let console = page.console();
    assert!(console.is_empty(), "console: {console:#?}");
    let csv = element(&page.stdout, "pre", "results")
        .unwrap_or_else(|| panic!("no <pre id=\"results\"> in:\n{}", page.stdout));
    let all = rows(&csv);
    let shown = trials(&all);
    let d_ = &report.design;
    assert_eq!(shown.len(), d_.trials.len());
    assert!(shown.iter().all(|r| r["participant"] == "simulated-seed1"));
    assert!(shown
        .iter()
        .all(|r| r["simulated"] == "tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1"));
    // Three breaks in 384 test trials (one every 96).
    assert_eq!(all.iter().filter(|r| r["shadelab"] == "break").count(), 3);
    // The loop closed: the page's data, fitted back by `shadelab fit observer`, recover the
    // simulated observer (384 test trials, the default design).
    std::fs::write(d.join("pilot.csv"), &csv).unwrap();
    // A pilot's rows never pass for people's: refused unless asked for, then said.
    let refused = shadelab(&d, &["fit", "observer", "pilot.csv", "--out", "fit"]);
    assert!(!refused.status.success());
    let why = String::from_utf8_lossy(&refused.stderr);
    assert!(
        why.contains("384 trials whose 'simulated' column is set")
            && why.contains("--include-simulated"),
        "{why}"
    );
    let fitted = shadelab(
        &d,
        &[
            "--quiet",
            "fit",
            "observer",
            "pilot.csv",
            "--include-simulated",
            "--out",
            "fit",
            "--bootstrap",
            "0",
            "--design",
            "e/design.json",
        ],
    );
    assert!(
        fitted.status.success(),
        "{}",
        String::from_utf8_lossy(&fitted.stderr)
    );
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(d.join("fit/fit.json")).unwrap()).unwrap();
    let within = |key: &str, truth: f64| {
        let v = fit[key]["value"].as_f64().unwrap();
        let ci = &fit[key]["ci95"];
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        eprintln!("recovery: {key} simulated {truth}, fitted {v:.3} [{lo:.3}, {hi:.3}]");
        assert!(
            lo <= truth && truth <= hi,
            "{key}: {truth} not in [{lo}, {hi}]"
        );
        v
    };
    let tilt = within("prior_tilt_deg", 26.0);
    assert!((tilt - 26.0).abs() < 10.0, "prior tilt {tilt}");
    within("prior_kappa", 2.0);
    within("convexity_prior", 0.7);
    assert_eq!(fit["n_trials"], 384, "only the test trials are fitted");
    let methods = std::fs::read_to_string(d.join("fit/methods.md")).unwrap();
    assert!(
        methods.contains("**Stimulus and apparatus.**")
            && methods.contains("4 × 4 degrees")
            && methods.contains("57 cm")
            && methods.contains("jsPsych 8.3.0")
            && methods.contains("participant's own random order"),
        "{methods}"
    );

    // Each participant their own order: two ids two orders, the same id the same one, and
    // each order the design's trials.
    let a = order(
        &run(
            &server.url(&format!("{pilot}&participant=A")),
            &d.join("p-a"),
            &ARGS,
            timeout,
        )
        .stdout,
    );
    let b = order(
        &run(
            &server.url(&format!("{pilot}&participant=B")),
            &d.join("p-b"),
            &ARGS,
            timeout,
        )
        .stdout,
    );
    let a2 = order(
        &run(
            &server.url(&format!("{pilot}&participant=A")),
            &d.join("p-a2"),
            &ARGS,
            timeout,
        )
        .stdout,
    );
    assert_eq!(a.len(), 384);
    assert_eq!(a, a2, "the same participant, the same order");
    assert_ne!(a, b, "two participants, two orders");
    let (mut sa, mut sb) = (a.clone(), b.clone());
    sa.sort();
    sb.sort();
    assert_eq!(sa, sb);
    // Prolific's id stands in for a participant id.
    let p = run(
        &server.url(&format!("{pilot}&PROLIFIC_PID=A&STUDY_ID=S1&SESSION_ID=X9")),
        &d.join("p-prolific"),
        &ARGS,
        timeout,
    );
    assert_eq!(order(&p.stdout), a, "PROLIFIC_PID=A is participant A");
    let csv = element(&p.stdout, "pre", "results").unwrap();
    let prolific = rows(&csv);
    assert!(prolific
        .iter()
        .all(|r| r["prolific_pid"] == "A" && r["study_id"] == "S1" && r["session_id"] == "X9"));

    // Bad parameters: a message on the page, no results.
    for (query, needle) in [
        ("simulate=tilt:26,kappa:-1", "kappa '-1' must be"),
        ("simulate=tilt:26,kapa:2", "unknown parameter 'kapa'"),
        ("simulate=kappa:2", "give tilt"),
        ("simulate=tilt:x,kappa:2", "tilt 'x' must be"),
        (
            "simulate=tilt:26,kappa:2&save_format=xml",
            "save_format 'xml'",
        ),
        ("participant=a%20b", "participant: use letters"),
    ] {
        let page = run(
            &server.url(&format!("index.html?{query}")),
            &d.join("profile-bad"),
            &ARGS,
            timeout,
        );
        assert!(
            page.stdout.contains("id=\"message\"") && page.stdout.contains(needle),
            "{query}: '{needle}' not in {}",
            page.stdout
        );
        assert!(element(&page.stdout, "pre", "results").is_none(), "{query}");
    }

    // A screenshot of the first test trial as a participant sees it, its bright side facing
    // the trial's rotation on screen.
    let shots = std::env::temp_dir().join("shadelab-experiment-screenshots");
    let _ = std::fs::create_dir_all(&shots);
    let path = shots.join("trial.png");
    let _ = std::fs::remove_file(&path);
    let shot = run(
        &server.url("index.html?preview=trial"),
        &d.join("profile-shot"),
        &[
            "--virtual-time-budget=5000",
            &format!("--screenshot={}", path.display()),
            "--window-size=1200,900",
            "--hide-scrollbars",
            "--enable-logging=stderr",
            "--v=0",
        ],
        timeout,
    );
    assert!(shot.console().is_empty(), "{:#?}", shot.console());
    assert!(path.exists(), "no screenshot: {}", shot.stderr);
    let first = d_.trials.iter().find(|t| t.block == "test").unwrap();
    let on_screen = bright_side_on_screen(&path);
    let off = (on_screen - first.rotation_deg + 540.0).rem_euclid(360.0) - 180.0;
    assert!(
        off.abs() < 15.0,
        "the first trial shows θ = {}, the screen's bright side faces {on_screen:.1}",
        first.rotation_deg
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

/// Where the bright side of the middle 300 × 300 pixels of a screenshot faces (tilt
/// convention, degrees), as the library measures its images.
fn bright_side_on_screen(path: &Path) -> f64 {
    let (image, _) = shadelab_io::read_luminance(path, 1 << 24).unwrap();
    let (cx, cy) = (image.width() / 2, image.height() / 2);
    experiment::bright_side(&image, &|c, r| c.abs_diff(cx) < 150 && r.abs_diff(cy) < 150)
        .unwrap_or_else(|| panic!("nothing shaded in the middle of {}", path.display()))
}

/// A lab's data server on 127.0.0.1, until dropped: it answers CORS preflights, keeps every
/// POST's content type and body, and serves `/done` (where a completion URL may point).
struct Receiver {
    port: u16,
    posts: Arc<Mutex<Vec<(String, String)>>>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Receiver {
    fn start() -> Receiver {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        listener.set_nonblocking(true).unwrap();
        let port = listener.local_addr().unwrap().port();
        let posts = Arc::new(Mutex::new(Vec::new()));
        let stop = Arc::new(AtomicBool::new(false));
        let (kept, flag) = (posts.clone(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        let _ = Receiver::answer(stream, &kept);
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    Err(_) => break,
                }
            }
        });
        Receiver {
            port,
            posts,
            stop,
            thread: Some(thread),
        }
    }

    fn url(&self, path: &str) -> String {
        format!("http://127.0.0.1:{}/{path}", self.port)
    }

    fn answer(
        stream: std::net::TcpStream,
        posts: &Mutex<Vec<(String, String)>>,
    ) -> std::io::Result<()> {
        stream.set_nonblocking(false)?;
        stream.set_read_timeout(Some(Duration::from_secs(5)))?;
        let mut reader = BufReader::new(stream.try_clone()?);
        let mut request = String::new();
        reader.read_line(&mut request)?;
        let (mut length, mut content_type) = (0usize, String::new());
        loop {
            let mut line = String::new();
            if reader.read_line(&mut line)? <= 2 {
                break;
            }
            let lower = line.to_ascii_lowercase();
            if let Some(v) = lower.strip_prefix("content-length:") {
                length = v.trim().parse().unwrap_or(0);
            }
            if let Some(v) = lower.strip_prefix("content-type:") {
                content_type = v.trim().to_string();
            }
        }
        let cors = "Access-Control-Allow-Origin: *\r\nAccess-Control-Allow-Methods: POST\r\nAccess-Control-Allow-Headers: Content-Type\r\n";
        let mut out = stream;
        let method = request.split_whitespace().next().unwrap_or("");
        let body = match method {
            "POST" => {
                let mut body = vec![0u8; length];
                reader.read_exact(&mut body)?;
                posts
                    .lock()
                    .unwrap()
                    .push((content_type, String::from_utf8_lossy(&body).into_owned()));
                "saved".to_string()
            }
            // The completion page tells the page framing the study where it arrived.
            "GET" => "<!DOCTYPE html><html><head><link rel=\"icon\" href=\"data:,\"></head><body><p id=\"done\">back at the study site</p><script>parent.postMessage('completed ' + location.href, '*');</script></body></html>".to_string(),
            _ => String::new(),
        };
        let status = if method == "OPTIONS" {
            "204 No Content"
        } else {
            "200 OK"
        };
        write!(
            out,
            "HTTP/1.1 {status}\r\n{cors}Content-Type: text/html\r\nContent-Length: {}\r\nConnection: close\r\n\r\n{body}",
            body.len()
        )?;
        out.flush()
    }
}

impl Drop for Receiver {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// A page that frames the study (with this page's own query) and shows where the study sent
/// the participant at the end (headless Chromium's `--dump-dom` never returns once the page
/// itself goes elsewhere, so the frame goes instead).
const FRAME: &str = r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><link rel="icon" href="data:,"><title>frame</title></head><body>
<pre id="result">pending</pre>
<iframe id="page"></iframe>
<script>
window.addEventListener('message', (e) => { document.getElementById('result').textContent = e.data; });
document.getElementById('page').src = 'index.html' + location.search;
</script></body></html>
"#;

#[test]
fn the_data_reach_a_real_server_by_post_and_a_refused_one_falls_back_to_the_download() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-save");
    let receiver = Receiver::start();
    // The default design (24 rotations x 16, 8 practice trials).
    let mut config = Config::new();
    config.completion_url = Some(receiver.url("done?cc=C1234ABC"));
    let (report, folder) = study(&config, &d.join("e"), &modules);
    let server = Server::start(&folder, &[("__frame.html", FRAME)]);
    let timeout = Duration::from_secs(120);
    let simulate = "simulate=tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:1";
    let completed = format!("completed {}", receiver.url("done?cc=C1234ABC"));
    let prolific = "PROLIFIC_PID=5f1a&STUDY_ID=st7&SESSION_ID=se9";

    // JSON to the lab's server (cross-origin, as a separate data server is), then on to the
    // completion URL.
    let save = receiver.url("save");
    let page = run(
        &server.url(&format!(
            "__frame.html?{simulate}&{prolific}&save_url={save}"
        )),
        &d.join("profile-json"),
        &ARGS,
        timeout,
    );
    assert!(page.console().is_empty(), "console: {:#?}", page.console());
    assert_eq!(
        element(&page.stdout, "pre", "result").as_deref(),
        Some(completed.as_str()),
        "not sent on to the completion URL"
    );
    let (kind, body) = receiver.posts.lock().unwrap()[0].clone();
    assert_eq!(kind, "application/json");
    let data: Vec<serde_json::Value> = serde_json::from_str(&body).unwrap();
    let shown: Vec<&serde_json::Value> = data.iter().filter(|r| r["shadelab"] == "trial").collect();
    assert_eq!(shown.len(), report.design.trials.len());
    assert!(data.iter().all(|r| r["participant"] == "5f1a"
        && r["prolific_pid"] == "5f1a"
        && r["study_id"] == "st7"
        && r["session_id"] == "se9"));
    // The fit reads what the server received, and recovers the simulated prior.
    std::fs::create_dir_all(d.join("data")).unwrap();
    std::fs::write(d.join("data/5f1a.json"), &body).unwrap();
    let mut fit = shadelab::pipeline::fit::Config::new(&d.join("data/5f1a.json"));
    fit.options.bootstrap = 0;
    fit.reading.include_simulated = true;
    let fitted = shadelab::pipeline::fit::run(&fit, &NoProgress).unwrap();
    let ci = fitted.pooled.prior_tilt_deg.ci95.unwrap();
    eprintln!(
        "recovery (POSTed JSON, 384 trials): μ simulated 26, fitted {:.2} [{:.2}, {:.2}]; κ simulated 2, fitted {:.2} {:?}",
        fitted.pooled.prior_tilt_deg.value, ci[0], ci[1], fitted.pooled.prior_kappa.value, fitted.pooled.prior_kappa.ci95
    );
    assert!(ci[0] <= 26.0 && 26.0 <= ci[1], "{ci:?}");
    assert_eq!(fitted.pooled.n_trials, 384);

    // CSV, as text/csv.
    let page = run(
        &server.url(&format!(
            "__frame.html?{simulate}&participant=P2&save_url={save}&save_format=csv"
        )),
        &d.join("profile-csv"),
        &ARGS,
        timeout,
    );
    assert_eq!(
        element(&page.stdout, "pre", "result").as_deref(),
        Some(completed.as_str())
    );
    let (kind, body) = receiver.posts.lock().unwrap()[1].clone();
    assert_eq!(kind, "text/csv");
    std::fs::write(d.join("data/P2.csv"), &body).unwrap();
    // The folder of both: one fit each, and the group.
    let mut fit = shadelab::pipeline::fit::Config::new(&d.join("data"));
    fit.options.bootstrap = 0;
    fit.reading.include_simulated = true;
    let both = shadelab::pipeline::fit::run(&fit, &NoProgress).unwrap();
    let ids: Vec<&str> = both
        .participants
        .iter()
        .map(|p| p.participant.as_str())
        .collect();
    assert_eq!(ids, ["5f1a", "P2"], "in the order of the file names");
    assert_eq!(both.group.as_ref().unwrap().participants, 2);

    // A server that refuses (nothing listens on the port): tried, then the download, the
    // participant told, and no redirect before they have it.
    let closed = {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let page = run(
        &server.url(&format!(
            "index.html?{simulate}&participant=P3&save_url=http://127.0.0.1:{closed}/save"
        )),
        &d.join("profile-refused"),
        &ARGS,
        timeout,
    );
    let status = element(&page.stdout, "p", "save-status").unwrap();
    assert!(status.contains("could not be sent"), "{status}");
    assert!(
        page.stdout.contains("download=\"shadelab-P3.csv\""),
        "{}",
        page.stdout
    );
    assert!(!page.stdout.contains("id=\"done\""));
    assert!(page
        .stdout
        .contains(&format!("href=\"{}\"", receiver.url("done?cc=C1234ABC"))));
    let csv = element(&page.stdout, "pre", "results").unwrap();
    assert_eq!(trials(&rows(&csv)).len(), report.design.trials.len());
    assert_eq!(
        receiver.posts.lock().unwrap().len(),
        2,
        "nothing more arrived"
    );
    drop(server);
    drop(receiver);
    let _ = std::fs::remove_dir_all(&d);
}

/// A double of JATOS's `jatos` object (jatos.js, as JATOS serves it beside a study), shaped as
/// its documented API: onLoad, urlQueryParameters, submitResultData (a Promise) and endStudy;
/// it shows what it was given on the page.
const JATOS_DOUBLE: &str = r#"
window.jatos = {
  urlQueryParameters: { PROLIFIC_PID: 'jatos-worker-1', simulate: 'tilt:26,kappa:2,seed:4' },
  submitted: null,
  onLoad(callback) { setTimeout(callback, 0); },
  submitResultData(data) {
    this.submitted = data;
    return Promise.resolve();
  },
  endStudy(successful, message) {
    const pre = document.createElement('pre');
    pre.id = 'jatos-data';
    pre.textContent = this.submitted;
    const p = document.createElement('p');
    p.id = 'jatos-ended';
    p.textContent = `${successful} ${message}`;
    document.body.replaceChildren(pre, p);
  },
};
"#;

#[test]
fn under_jatos_the_data_go_to_submit_result_data_and_the_study_ends() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-jatos");
    let mut config = Config::new();
    config.rotations = vec![0.0, 90.0, 180.0, 270.0];
    config.repeats = 2;
    let (report, folder) = study(&config, &d.join("e"), &modules);
    let server = Server::start(&folder, &[("jatos.js", JATOS_DOUBLE)]);
    let page = run(
        &server.url("jatos.html"),
        &d.join("profile"),
        &ARGS,
        Duration::from_secs(120),
    );
    assert!(page.console().is_empty(), "console: {:#?}", page.console());
    assert_eq!(
        element(&page.stdout, "p", "jatos-ended").as_deref(),
        Some("true shadelab study completed"),
        "{}",
        page.stdout
    );
    let data: Vec<serde_json::Value> =
        serde_json::from_str(&element(&page.stdout, "pre", "jatos-data").unwrap()).unwrap();
    let shown: Vec<_> = data.iter().filter(|r| r["shadelab"] == "trial").collect();
    assert_eq!(shown.len(), report.design.trials.len());
    // JATOS's own query parameters: the Prolific id is the participant.
    assert!(shown.iter().all(|r| r["participant"] == "jatos-worker-1"));
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

/// A lab's own jsPsych study: its consent and questionnaire around shadelab's timeline (with
/// the timeline's `options`), the study's files under `prefix` (the design fetched from there),
/// the lab's `extra` scripts, run in jsPsych's simulation mode; at the end the page shows, as
/// JSON in `<pre id="lab-data">`, `{plugin, data}`: whether the lab's own plugin ran
/// (`window.labPlugin`) and its data.
fn lab_page(prefix: &str, extra: &str, options: &str) -> String {
    r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><link rel="icon" href="data:,"><title>our lab's study</title>
<script src="node_modules/jspsych/dist/index.browser.min.js"></script>
<script src="node_modules/@jspsych/plugin-preload/dist/index.browser.min.js"></script>
<script src="node_modules/@jspsych/plugin-html-button-response/dist/index.browser.min.js"></script>
<script src="node_modules/@jspsych/plugin-html-keyboard-response/dist/index.browser.min.js"></script>
<script src="node_modules/@jspsych/plugin-image-keyboard-response/dist/index.browser.min.js"></script>
EXTRA<script src="PREFIXshadelab-timeline.js"></script>
</head><body><script>
(async () => {
  const design = await (await fetch('PREFIXdesign.json')).json();
  const jsPsych = initJsPsych({
    on_finish: () => {
      const pre = document.createElement('pre');
      pre.id = 'lab-data';
      pre.textContent = JSON.stringify({ plugin: window.labPlugin || 'missing', data: jsPsych.data.get().values() });
      document.body.replaceChildren(pre);
    },
  });
  const consent = { type: jsPsychHtmlButtonResponse, stimulus: 'Our consent form', choices: ['Yes'], data: { lab: 'consent' } };
  const questionnaire = { type: jsPsychHtmlButtonResponse, stimulus: 'Did the discs look like bumps?', choices: ['Mostly', 'Rarely'], data: { lab: 'questionnaire' } };
  const shading = shadelabTimeline(design, Object.assign({ jsPsych: jsPsych }, OPTIONS));
  jsPsych.simulate([consent, shading, questionnaire], 'data-only');
})();
</script></body></html>
"#
    .replace("PREFIX", prefix)
    .replace("EXTRA", extra)
    .replace("OPTIONS", options)
}

#[test]
fn a_labs_own_jspsych_page_embeds_the_timeline_between_its_trials() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-lab");
    let lab = d.join("lab");
    std::fs::create_dir_all(&lab).unwrap();
    let mut config = Config::new();
    config.rotations = vec![0.0, 90.0, 180.0, 270.0];
    config.repeats = 3;
    config.practice = 1;
    let report = experiment::run(&config, &NoProgress).unwrap();
    report.write(&Output::new(lab.join("shadelab"))).unwrap();
    std::os::unix::fs::symlink(&modules, lab.join("node_modules")).unwrap();
    // No calibration and no participant given: Prolific's ids come in the page's URL.
    let page = lab_page(
        "shadelab/",
        "",
        "{ imagePath: 'shadelab/', simulate: shadelabTimeline.parseSimulate('tilt:26,kappa:2,seed:5') }",
    );
    std::fs::write(lab.join("index.html"), page).unwrap();
    let server = Server::start(&lab, &[]);
    let page = run(
        &server.url("index.html?PROLIFIC_PID=lab-007&STUDY_ID=study-3&SESSION_ID=session-9"),
        &d.join("profile"),
        &ARGS,
        Duration::from_secs(120),
    );
    // Uncalibrated: the console says the ppd is assumed, once.
    let console = page.console();
    assert_eq!(console.len(), 1, "console: {console:#?}");
    assert!(
        console[0].contains("32 pixels per degree are assumed")
            && console[0].contains("docs/experiments.md"),
        "{console:?}"
    );
    let json = element(&page.stdout, "pre", "lab-data")
        .unwrap_or_else(|| panic!("the lab's study did not finish: {}", page.stdout));
    let out: serde_json::Value = serde_json::from_str(&json).unwrap();
    let data = out["data"].as_array().unwrap();
    let json = serde_json::to_string(data).unwrap();
    assert_eq!(data.first().unwrap()["lab"], "consent");
    assert_eq!(data.last().unwrap()["lab"], "questionnaire");
    // The lab's own rows carry the participant and the session (its Prolific ids).
    for r in [data.first().unwrap(), data.last().unwrap()] {
        assert_eq!(r["participant"], "lab-007", "{r}");
        assert_eq!(r["study_id"], "study-3", "{r}");
    }
    let shown: Vec<_> = data.iter().filter(|r| r["shadelab"] == "trial").collect();
    assert_eq!(shown.len(), 13);
    // Every shadelab row carries the standalone study's columns.
    for r in data.iter().filter(|r| r["shadelab"].is_string()) {
        assert_eq!(r["participant"], "lab-007", "{r}");
        assert_eq!(r["prolific_pid"], "lab-007", "{r}");
        assert_eq!(r["study_id"], "study-3", "{r}");
        assert_eq!(r["session_id"], "session-9", "{r}");
        assert_eq!(r["shadelab_version"], report.design.version, "{r}");
        assert_eq!(r["viewing_distance_cm"], 57.0, "{r}");
        assert!(r["user_agent"].as_str().unwrap().contains("Chrome"), "{r}");
        assert!(r["screen_width"].as_u64().unwrap() > 0, "{r}");
        assert!(r["screen_height"].as_u64().unwrap() > 0, "{r}");
        assert_eq!(
            r["simulated"], "tilt:26,kappa:2,convex:0.5,lapse:0,seed:5",
            "{r}"
        );
        assert_eq!(r["design_hash"], report.design.design_hash.as_str(), "{r}");
    }
    for r in &shown {
        for column in experiment::DATA_COLUMNS.split(',') {
            assert!(r.get(column).is_some(), "no {column} in {r}");
        }
        assert!(r["stimulus"]
            .as_str()
            .unwrap()
            .starts_with("shadelab/images/"));
        // Uncalibrated: the images' own ppd, said to be assumed.
        assert_eq!(r["ppd"], 32.0, "{r}");
        assert_eq!(r["ppd_method"], "assumed", "{r}");
    }
    // The preload found every image under the lab's path.
    let preload = data.iter().find(|r| r["shadelab"] == "preload").unwrap();
    assert_eq!(preload["success"], true, "{preload}");
    // And the lab's file fits as it is.
    std::fs::write(d.join("lab.json"), &json).unwrap();
    let r = shadelab::pipeline::fit::read_responses_with(&d.join("lab.json"), &pilot()).unwrap();
    assert_eq!(r.participants[0].0, "lab-007");
    assert_eq!(r.participants[0].1.len(), 12);
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn counterbalanced_keys_are_swapped_for_half_of_the_participants_and_read_back() {
    let Some(modules) = jspsych() else { return };
    let d = scratch("experiment-counterbalance");
    let mut config = Config::new();
    config.rotations = vec![0.0, 90.0, 180.0, 270.0];
    config.repeats = 3;
    config.counterbalance_keys = true;
    let (_, folder) = study(&config, &d.join("e"), &modules);
    let server = Server::start(&folder, &[]);
    let mut assignments = Vec::new();
    for id in ["A", "B", "C", "D", "E", "F"] {
        let page = run(
            &server.url(&format!(
                "index.html?simulate=tilt:26,kappa:2,seed:2&participant={id}"
            )),
            &d.join(format!("profile-{id}")),
            &ARGS,
            Duration::from_secs(120),
        );
        let csv = element(&page.stdout, "pre", "results").unwrap();
        let all = rows(&csv);
        let shown = trials(&all);
        let keys = (
            shown[0]["key_convex"].clone(),
            shown[0]["key_concave"].clone(),
        );
        // One assignment per participant, and each answer's judgement by that assignment.
        for r in &shown {
            assert_eq!((r["key_convex"].clone(), r["key_concave"].clone()), keys);
            let convex = r["response"] == keys.0;
            assert_eq!(r["judgement"], if convex { "convex" } else { "concave" });
        }
        // The order seed's parity decides.
        let odd = shown[0]["order_seed"].parse::<u64>().unwrap() % 2 == 1;
        assert_eq!(keys.0 == "j", odd, "{id}: {keys:?}");
        // The fit reads the judgements through each row's own keys.
        std::fs::write(d.join(format!("{id}.csv")), &csv).unwrap();
        let r =
            shadelab::pipeline::fit::read_responses_with(&d.join(format!("{id}.csv")), &pilot())
                .unwrap();
        let from_rows: Vec<bool> = shown
            .iter()
            .filter(|r| r["block"] == "test")
            .map(|r| r["judgement"] == "convex")
            .collect();
        let read: Vec<bool> = r.participants[0].1.iter().map(|t| t.1).collect();
        assert_eq!(read, from_rows);
        assignments.push(keys.0);
    }
    assert!(
        assignments.iter().any(|k| k == "f") && assignments.iter().any(|k| k == "j"),
        "{assignments:?}"
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_rerun_keeps_the_labs_node_modules_lock_and_plugins_and_updates_its_own_pins() {
    let d = scratch("experiment-rerun");
    let small = [
        "--rotations",
        "0,90,180,270",
        "--repeats",
        "2",
        "--practice",
        "1",
    ];
    let write_study = |extra: &[&str]| {
        let mut args = vec!["experiment", "--out", "study"];
        args.extend(small);
        args.extend(extra);
        shadelab(&d, &args)
    };
    let first = write_study(&["--no-install"]);
    assert!(first.status.success(), "{first:?}");
    let study = d.join("study");
    // The lab adds a plugin of its own (a local package: no network needed), as npm leaves
    // it: a dependency in package.json, its files in node_modules/, a package-lock.json; and
    // an older jsPsych pin.
    let plugin = study.join("lab-plugins/plugin-lab-note");
    std::fs::create_dir_all(&plugin).unwrap();
    let manifest = r#"{"name": "plugin-lab-note", "version": "1.0.0", "main": "index.js"}"#;
    let script = "window.labPlugin = 'loaded';\n";
    std::fs::write(plugin.join("package.json"), manifest).unwrap();
    std::fs::write(plugin.join("index.js"), script).unwrap();
    let installed = study.join("node_modules/plugin-lab-note");
    std::fs::create_dir_all(&installed).unwrap();
    std::fs::write(installed.join("package.json"), manifest).unwrap();
    std::fs::write(installed.join("index.js"), script).unwrap();
    let lock = "{\"name\": \"shadelab-experiment\", \"lockfileVersion\": 3, \"lab\": true}\n";
    std::fs::write(study.join("package-lock.json"), lock).unwrap();
    let mut package: serde_json::Value =
        serde_json::from_slice(&std::fs::read(study.join("package.json")).unwrap()).unwrap();
    package["dependencies"]["plugin-lab-note"] = "file:lab-plugins/plugin-lab-note".into();
    package["dependencies"]["jspsych"] = "8.0.0".into();
    package["scripts"] = serde_json::json!({"serve": "python3 -m http.server"});
    std::fs::write(
        study.join("package.json"),
        serde_json::to_string_pretty(&package).unwrap(),
    )
    .unwrap();
    // The lab's page in the study folder, with its plugin from node_modules/.
    let page = lab_page(
        "",
        "<script src=\"node_modules/plugin-lab-note/index.js\"></script>\n",
        "{ participant: 'lab-008', ppd: 32, ppdMethod: 'lab screen', \
         simulate: shadelabTimeline.parseSimulate('tilt:26,kappa:2,seed:5') }",
    );
    std::fs::write(study.join("lab.html"), page).unwrap();
    // Without --force the lab's page and plugin folder are refused as collected data? but npm's
    // files are not among them.
    let refused = write_study(&["--no-install"]);
    assert_eq!(refused.status.code(), Some(1), "{refused:?}");
    let why = String::from_utf8_lossy(&refused.stderr);
    assert!(
        why.contains("lab.html") && !why.contains("node_modules") && !why.contains("package-lock"),
        "{why}"
    );
    let check = |what: &str| {
        let package: serde_json::Value =
            serde_json::from_slice(&std::fs::read(study.join("package.json")).unwrap()).unwrap();
        let deps = &package["dependencies"];
        assert_eq!(
            deps["plugin-lab-note"], "file:lab-plugins/plugin-lab-note",
            "{what}: {package}"
        );
        assert_eq!(
            package["scripts"]["serve"], "python3 -m http.server",
            "{what}"
        );
        for (name, version, _) in experiment::JSPSYCH_PACKAGES {
            assert_eq!(deps[name], *version, "{what}: {package}");
        }
        assert_eq!(
            std::fs::read_to_string(study.join("node_modules/plugin-lab-note/index.js")).unwrap(),
            script,
            "{what}"
        );
        assert!(study.join("package-lock.json").is_file(), "{what}");
        assert!(study.join("lab.html").is_file(), "{what}");
    };
    // Rerun without installing: npm's files as they were, byte for byte.
    let again = write_study(&["--no-install", "--force"]);
    assert!(again.status.success(), "{again:?}");
    check("--no-install --force");
    assert_eq!(
        std::fs::read_to_string(study.join("package-lock.json")).unwrap(),
        lock
    );
    let said = String::from_utf8_lossy(&again.stderr);
    assert!(
        !said.contains("node_modules") && !said.contains("package-lock"),
        "{said}"
    );
    // The manifest never claims npm's files, so no later run deletes them.
    let listed = std::fs::read_to_string(study.join(".shadelab-files.json")).unwrap();
    assert!(
        !listed.contains("node_modules") && !listed.contains("package-lock"),
        "{listed}"
    );
    // Rerun with npm install (where npm and Chromium are, to run the lab's page after).
    if jspsych().is_none() {
        let _ = std::fs::remove_dir_all(&d);
        return;
    }
    let installed = write_study(&["--force"]);
    assert!(installed.status.success(), "{installed:?}");
    let said = String::from_utf8_lossy(&installed.stderr);
    if said.contains("jsPsych is not installed") {
        eprintln!("the npm half of the rerun test skipped: {said}");
        let _ = std::fs::remove_dir_all(&d);
        return;
    }
    check("--force");
    let lock = std::fs::read_to_string(study.join("package-lock.json")).unwrap();
    assert!(
        lock.contains("plugin-lab-note") && lock.contains("\"node_modules/jspsych\""),
        "{lock}"
    );
    // The lab's page runs after: its plugin loaded, shadelab's trials done.
    let server = Server::start(&study, &[]);
    let page = run(
        &server.url("lab.html"),
        &d.join("profile"),
        &ARGS,
        Duration::from_secs(120),
    );
    let json = element(&page.stdout, "pre", "lab-data")
        .unwrap_or_else(|| panic!("the lab's page did not finish: {}", page.stdout));
    let out: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(out["plugin"], "loaded");
    let data = out["data"].as_array().unwrap();
    assert_eq!(data.iter().filter(|r| r["shadelab"] == "trial").count(), 9);
    assert!(data.iter().all(|r| r["participant"] == "lab-008"));
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn the_pilot_without_a_browser_writes_the_rows_the_page_writes() {
    let d = scratch("experiment-pilot-cli");
    let study = [
        "experiment",
        "--out",
        "study",
        "--rotations",
        "0:360:30",
        "--repeats",
        "3",
        "--practice",
        "4",
        "--counterbalance-keys",
        "--no-install",
        "--quiet",
    ];
    assert!(shadelab(&d, &study).status.success());
    let model = "tilt:26,kappa:2,convex:0.7,lapse:0.02,seed:7";
    let pilot = |participant: &str, out: &str| {
        let o = shadelab(
            &d,
            &[
                "experiment",
                "pilot",
                "study",
                "--simulate",
                model,
                "--participant",
                participant,
                "--out",
                out,
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(d.join(out)).unwrap()
    };
    let csv = pilot("P-odd", "p1.csv");
    let table = rows(&csv);
    assert_eq!(table.len(), 4 + 12 * 3);
    assert_eq!(
        csv.lines().next().unwrap(),
        experiment::PILOT_COLUMNS.join(",")
    );
    // Same seed, same file; another participant, another order.
    assert_eq!(pilot("P-odd", "p2.csv"), csv);
    assert_ne!(pilot("P-even", "p3.csv"), csv);
    // Refusals: one line each, nothing written.
    let refused = |study: &str, extra: &[&str], out: &str, code: i32, needle: &str| {
        let mut args = vec!["experiment", "pilot", study];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", out]);
        assert_error(&shadelab(&d, &args), code, needle);
    };
    refused(
        "study",
        &["--simulate", "tilt:26"],
        "x.csv",
        2,
        "--simulate give kappa",
    );
    refused(
        "study",
        &["--simulate", model, "--participant", "P odd"],
        "x.csv",
        2,
        "--participant 'P odd': use letters, digits",
    );
    refused("study", &["--simulate", model], "p1.csv", 1, "p1.csv");
    refused("nowhere", &["--simulate", model], "x.csv", 1, "nowhere");
    assert!(!d.join("x.csv").exists());
    // fit observer reads the pilot's file as it reads the page's.
    let read =
        shadelab::pipeline::fit::read_responses_with(&d.join("p1.csv"), &self::pilot()).unwrap();
    assert_eq!(read.participants[0].0, "P-odd");
    assert_eq!(read.participants[0].1.len(), 36);
    // The page, in pilot mode for the same participant and observer, writes the same rows:
    // its trial rows, cut to the pilot's columns, byte for byte. (The page's other columns
    // are the browser's: its user agent, screen and window, jsPsych's clock.)
    let Some(modules) = jspsych() else { return };
    let folder = d.join("study");
    std::os::unix::fs::symlink(modules, folder.join("node_modules")).unwrap();
    let server = Server::start(&folder, &[]);
    for (participant, file) in [("P-odd", "p1.csv"), ("P-even", "p3.csv")] {
        let page = run(
            &server.url(&format!(
                "index.html?simulate={model}&participant={participant}"
            )),
            &d.join(format!("profile-{participant}")),
            &ARGS,
            Duration::from_secs(120),
        );
        let all = rows(&element(&page.stdout, "pre", "results").unwrap());
        let mut page_csv = experiment::PILOT_COLUMNS.join(",") + "\n";
        for r in trials(&all) {
            let cells: Vec<String> = experiment::PILOT_COLUMNS
                .iter()
                .map(|c| experiment::csv_cell(&r[*c]))
                .collect();
            page_csv += &(cells.join(",") + "\n");
        }
        assert_eq!(
            page_csv,
            std::fs::read_to_string(d.join(file)).unwrap(),
            "{participant}"
        );
    }
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}
