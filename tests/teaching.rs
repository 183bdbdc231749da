//! The teaching page (web/): built by web/build.sh, loaded in real headless Chromium. Skips,
//! saying why, without Chromium, rustup or the wasm32-unknown-unknown target (`.ci/run`
//! installs both).

use crate::chromium::{chromium, run, Server};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::Duration;

const WASM_TARGET: &str = "wasm32-unknown-unknown";

/// The built site, once per test run; `None` (after printing why) when it cannot be built here.
fn site() -> Option<&'static Path> {
    static SITE: OnceLock<Option<PathBuf>> = OnceLock::new();
    SITE.get_or_init(|| {
        chromium()?;
        let installed = Command::new("rustup")
            .args(["target", "list", "--installed"])
            .output();
        match installed {
            Ok(o) if String::from_utf8_lossy(&o.stdout).lines().any(|l| l == WASM_TARGET) => {}
            _ => {
                eprintln!(
                    "teaching page test skipped: rustup's {WASM_TARGET} target is not installed (rustup target add {WASM_TARGET}; .ci/run does)"
                );
                return None;
            }
        }
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let out = crate::cli::scratch("teaching-site");
        // The engine's own target folder under target/, kept between runs.
        let status = Command::new("bash")
            .arg(repo.join("web/build.sh"))
            .arg(&out)
            .env("CARGO_TARGET_DIR", repo.join("target/teaching-web"))
            .status()
            .expect("bash runs web/build.sh");
        assert!(status.success(), "web/build.sh failed: {status}");
        Some(out)
    })
    .as_deref()
}

/// The text of the element `<tag id="id" ...>TEXT<` in a dumped DOM.
fn element_text<'a>(dom: &'a str, tag: &str, id: &str) -> &'a str {
    let open = format!("<{tag} id=\"{id}\"");
    let start = dom
        .find(&open)
        .unwrap_or_else(|| panic!("no {open} in the page"));
    let rest = &dom[start..];
    let body = &rest[rest.find('>').unwrap() + 1..];
    &body[..body.find('<').unwrap()]
}

/// Loads `query` on the page and returns (DOM, console lines).
fn load(server: &Server, query: &str, name: &str) -> (String, Vec<String>) {
    let profile = crate::cli::scratch(&format!("teaching-profile-{name}"));
    let r = run(
        &server.url(&format!("index.html?{query}")),
        &profile,
        &[
            "--dump-dom",
            "--enable-logging=stderr",
            "--v=0",
            "--window-size=1280,900",
        ],
        Duration::from_secs(120),
    );
    let console = r.console().iter().map(|l| l.to_string()).collect();
    (r.stdout, console)
}

#[test]
fn the_bump_reads_convex_under_the_true_light_and_concave_under_the_opposite_one() {
    let Some(site) = site() else { return };
    let server = Server::start(site, &[]);
    let light = "stimulus=gaussian&light=tilt:0,slant:45";
    for (query, want) in [
        (format!("{light}&assume=tilt:0,slant:45"), "convex"),
        (format!("{light}&assume=tilt:180,slant:45"), "concave"),
        // The picture turned upside down, read under the light from above: a dent.
        (
            format!("{light}&assume=tilt:0,slant:45&rotate=1"),
            "concave",
        ),
    ] {
        let (dom, console) = load(&server, &query, want);
        assert_eq!(element_text(&dom, "output", "verdict"), want, "{query}");
        let ms: f64 = element_text(&dom, "output", "frame-ms")
            .parse()
            .unwrap_or_else(|_| panic!("frame-ms is not a number: {query}"));
        assert!(ms > 0.0 && ms.is_finite(), "{ms}");
        assert!(console.is_empty(), "console output on {query}: {console:?}");
        // No message: every parameter was understood.
        assert_eq!(element_text(&dom, "div", "message"), "", "{query}");
    }
}

#[test]
fn bad_url_parameters_show_a_message_and_the_page_still_works() {
    let Some(site) = site() else { return };
    let server = Server::start(site, &[]);
    let (dom, console) = load(
        &server,
        "stimulus=teapot&light=tilt:up,slant:45&assume=tilt:0,slant:95&size=9999",
        "bad",
    );
    let message = element_text(&dom, "div", "message");
    for needle in [
        "stimulus=teapot",
        "gaussian, bumps",
        "light=tilt:up",
        "slant must be in 0..90",
        "size=9999",
    ] {
        assert!(message.contains(needle), "{needle} not in {message}");
    }
    // The defaults were used instead: the Gaussian bump under light from above reads convex.
    assert_eq!(element_text(&dom, "output", "verdict"), "convex");
    assert!(console.is_empty(), "{console:?}");
}

#[test]
fn every_stimulus_loads_and_the_benchmark_records_its_frame_times() {
    let Some(site) = site() else { return };
    let server = Server::start(site, &[]);
    for name in [
        "gaussian",
        "bumps",
        "sideways",
        "crater",
        "strips",
        "hollow-mask",
        "sphere",
    ] {
        let (dom, console) = load(&server, &format!("stimulus={name}&bench=8"), name);
        assert!(console.is_empty(), "{name}: {console:?}");
        let verdict = element_text(&dom, "output", "verdict");
        assert!(
            ["convex", "concave", "flat"].contains(&verdict),
            "{name}: {verdict}"
        );
        let bench: serde_json::Value =
            serde_json::from_str(&element_text(&dom, "output", "bench").replace("&quot;", "\""))
                .unwrap();
        assert_eq!(bench["frames"], 8, "{name}");
        assert_eq!(bench["size"], 128, "{name}");
        let times: Vec<f64> = bench["times_ms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_f64().unwrap())
            .collect();
        assert!(times.iter().all(|&t| t > 0.0), "{name}: {times:?}");
        let median = bench["median_ms"].as_f64().unwrap();
        eprintln!(
            "teaching page, {name} at 128 px: median frame {median:.1} ms, times {times:.0?}"
        );
        // The target is 100 ms a frame (measured: about 20-35 ms here, docs/performance.md);
        // the bound leaves room for a loaded machine and still catches a slow build or solver.
        assert!(median <= 200.0, "{name}: median frame {median} ms");
        // The page fits a 1280×900 screen (a lecture projector's) without scrolling, whatever
        // the stimulus's explanation and the picture's aspect. Headless Chromium's viewport is
        // shorter than the window it is given, so the laid-out height is held against 900.
        assert_eq!(bench["window_width"], 1280, "{name}");
        let page = bench["page_height"].as_f64().unwrap();
        assert!(page <= 900.0, "{name}: the page is {page} px tall");
    }
}

#[test]
fn a_screenshot_of_the_page_shows_the_picture_and_the_reading() {
    let Some(site) = site() else { return };
    let server = Server::start(site, &[]);
    let dir = crate::cli::scratch("teaching-screenshot");
    let png = dir.join("page.png");
    run(
        &server.url("index.html?stimulus=crater&rotate=1&prior=1"),
        &dir.join("profile"),
        &[
            &format!("--screenshot={}", png.display()),
            "--window-size=1280,900",
            "--virtual-time-budget=5000",
        ],
        Duration::from_secs(120),
    );
    let shot = shadelab_io::read_rgb(&png, 10_000_000).unwrap();
    assert_eq!((shot.width(), shot.height()), (1280, 900));
    // The picture, the depth map and the plots: many distinct colours, not a blank page.
    let mut colours: Vec<[u8; 3]> = shot
        .data()
        .iter()
        .map(|p| p.map(|v| (v * 255.0).round() as u8))
        .collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 500, "{} colours", colours.len());
}
