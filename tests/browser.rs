//! The gallery as a reader sees it: rendered to a folder, served over HTTP and opened in
//! headless Chromium, which must load every image of index.html. Skips, saying why, where
//! Chromium is not installed (Debian's `chromium`; `.ci/run` installs it when it can).
//!
//! The page is served by the tests' static server (`chromium.rs`), and Chromium loads a checking
//! page of the same origin that frames index.html, waits for it to load, and writes what it
//! found into its own DOM, which `--dump-dom` prints.

use crate::chromium::{chromium, run, Server};
use crate::cli::{scratch, shadelab};
use std::path::Path;
use std::time::Duration;

/// The checking page: frames `index.html`, then lists its images that did not load.
const CHECK_PAGE: &str = r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>check</title></head><body>
<pre id="result">pending</pre>
<iframe id="page" src="index.html" style="width:1200px;height:900px"></iframe>
<script>
const frame = document.getElementById('page');
frame.addEventListener('load', () => {
  const images = Array.from(frame.contentDocument.images);
  const settled = images.map(i => i.complete ? Promise.resolve() :
    new Promise(r => { i.addEventListener('load', r); i.addEventListener('error', r); }));
  Promise.all(settled).then(() => {
    const broken = images.filter(i => !(i.complete && i.naturalWidth > 0))
      .map(i => i.getAttribute('src'));
    document.getElementById('result').textContent =
      'RESULT images=' + images.length + ' broken=' + JSON.stringify(broken) + ' END';
  });
});
</script></body></html>
"#;

/// What headless Chromium found on `dir`'s index.html: (number of images, broken sources).
fn check_images(dir: &Path, profile: &Path) -> (usize, Vec<String>) {
    let server = Server::start(dir, &[("__check.html", CHECK_PAGE)]);
    let dom = run(
        &server.url("__check.html"),
        profile,
        &["--virtual-time-budget=20000", "--dump-dom"],
        Duration::from_secs(120),
    )
    .stdout;
    drop(server);
    parse_result(&dom).unwrap_or_else(|| panic!("no result in chromium's DOM:\n{dom}"))
}

/// Reads `RESULT images=N broken=[…] END` from the dumped DOM.
fn parse_result(dom: &str) -> Option<(usize, Vec<String>)> {
    let start = dom.find("RESULT images=")? + "RESULT images=".len();
    let rest = &dom[start..];
    let end = rest.find(" END")?;
    let (count, broken) = rest[..end].split_once(" broken=")?;
    let list: Vec<String> = serde_json::from_str(&broken.replace("&quot;", "\"")).ok()?;
    Some((count.parse().ok()?, list))
}

#[test]
fn the_result_line_is_parsed() {
    assert_eq!(
        parse_result("<pre id=\"result\">RESULT images=3 broken=[&quot;a.png&quot;] END</pre>"),
        Some((3, vec!["a.png".to_string()]))
    );
    assert_eq!(parse_result("<pre>pending</pre>"), None);
}

#[test]
fn every_image_of_the_gallery_loads_in_headless_chromium() {
    if chromium().is_none() {
        return;
    }
    let d = scratch("browser");
    // The check can fail: a page with one good and one missing image reports the missing one.
    let bad = d.join("bad");
    std::fs::create_dir_all(&bad).unwrap();
    let out = shadelab(
        &bad,
        &["render", "disc", "--size", "8", "--out", "good.png"],
    );
    assert!(out.status.success());
    std::fs::write(
        bad.join("index.html"),
        "<!DOCTYPE html><html><body><img src=\"good.png\"><img src=\"missing.png\"></body></html>",
    )
    .unwrap();
    assert_eq!(
        check_images(&bad, &d.join("profile-bad")),
        (2, vec!["missing.png".to_string()])
    );
    // The real gallery.
    let out = shadelab(&d, &["--quiet", "gallery", "--out", "g"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let presets = shadelab_stimuli::gallery::builtin_presets().unwrap().len();
    let (count, broken) = check_images(&d.join("g"), &d.join("profile"));
    assert!(
        broken.is_empty(),
        "broken images in the gallery: {broken:?}"
    );
    assert_eq!(count, presets, "one thumbnail per preset");
    // The folder stands alone: every link of the index is a file in it (no docs page beside a
    // checkout, no teaching page that was never built), and each card carries its explanation.
    let index = std::fs::read_to_string(d.join("g/index.html")).unwrap();
    let links = links_of(&index);
    assert!(links.len() > presets * 3, "{links:?}");
    for link in &links {
        assert!(
            !link.contains(':') && !link.starts_with('/') && !link.contains(".."),
            "{link} leaves the gallery's folder"
        );
        let file = link.split('#').next().unwrap();
        assert!(d.join("g").join(file).is_file(), "{link} is a dead link");
    }
    assert_eq!(
        index.matches("<div class=\"explained\"><h3>").count(),
        presets
    );
    // As a reader sees it (docs/testing.md: look at the page).
    let shot = std::env::temp_dir().join("shadelab-gallery-index.png");
    let server = Server::start(&d.join("g"), &[]);
    let screenshot = format!("--screenshot={}", shot.display());
    run(
        &server.url("index.html"),
        &d.join("profile-shot"),
        &[screenshot.as_str(), "--window-size=1200,1600"],
        Duration::from_secs(60),
    );
    drop(server);
    assert!(shot.is_file(), "no screenshot of the gallery");
    let _ = std::fs::remove_dir_all(&d);
}

/// The `href`s of a page's links.
fn links_of(html: &str) -> Vec<String> {
    html.split("<a href=\"")
        .skip(1)
        .filter_map(|rest| rest.split('"').next())
        .map(str::to_string)
        .collect()
}
