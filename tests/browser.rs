//! The gallery as a reader sees it: rendered to a folder, served over HTTP and opened in
//! headless Chromium, which must load every image of index.html. Skips, saying why, where
//! Chromium is not installed (Debian's `chromium`; `.ci/run` installs it when it can).
//!
//! The page is served from a tiny std::net server in the test, and Chromium loads a checking
//! page of the same origin that frames index.html, waits for it to load, and writes what it
//! found into its own DOM, which `--dump-dom` prints.

use crate::cli::{scratch, shadelab};
use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

const CHROMIUM: &str = "/usr/bin/chromium";

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

/// A static file server on 127.0.0.1 for one folder (plus the checking page), until dropped.
struct Server {
    port: u16,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Server {
    fn start(dir: &Path) -> Server {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind a local port");
        listener.set_nonblocking(true).unwrap();
        let port = listener.local_addr().unwrap().port();
        let stop = Arc::new(AtomicBool::new(false));
        let (dir, flag) = (dir.to_path_buf(), stop.clone());
        let thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        let _ = serve(stream, &dir);
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                        std::thread::sleep(Duration::from_millis(5));
                    }
                    Err(_) => break,
                }
            }
        });
        Server {
            port,
            stop,
            thread: Some(thread),
        }
    }

    fn url(&self, path: &str) -> String {
        format!("http://127.0.0.1:{}/{path}", self.port)
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Answers one request (HTTP/1.0 style: one response, then close).
fn serve(stream: TcpStream, dir: &Path) -> std::io::Result<()> {
    stream.set_nonblocking(false)?;
    stream.set_read_timeout(Some(Duration::from_secs(5)))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut request = String::new();
    reader.read_line(&mut request)?;
    // Drain the headers.
    let mut line = String::new();
    while reader.read_line(&mut line)? > 2 {
        line.clear();
    }
    let target = request.split_whitespace().nth(1).unwrap_or("/");
    let path = target.split(['?', '#']).next().unwrap_or("/");
    let path = path.trim_start_matches('/');
    let body: Option<Vec<u8>> = if path == "__check.html" {
        Some(CHECK_PAGE.as_bytes().to_vec())
    } else if path.split('/').any(|c| c == ".." || c.is_empty()) {
        None
    } else {
        std::fs::read(dir.join(path)).ok()
    };
    let mut out = stream;
    match body {
        Some(b) => {
            let kind = match Path::new(path).extension().and_then(|e| e.to_str()) {
                Some("html") => "text/html; charset=utf-8",
                Some("png") => "image/png",
                Some("gif") => "image/gif",
                Some("svg") => "image/svg+xml",
                Some("json") => "application/json",
                _ => "application/octet-stream",
            };
            write!(
                out,
                "HTTP/1.1 200 OK\r\nContent-Type: {kind}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                b.len()
            )?;
            out.write_all(&b)?;
        }
        None => {
            out.write_all(
                b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
            )?;
        }
    }
    out.flush()
}

/// What headless Chromium found on `dir`'s index.html: (number of images, broken sources).
fn check_images(dir: &Path, profile: &Path) -> (usize, Vec<String>) {
    let server = Server::start(dir);
    let mut child = Command::new(CHROMIUM)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--virtual-time-budget=20000",
            "--dump-dom",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(server.url("__check.html"))
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("chromium starts");
    // Chromium normally answers in a few seconds; never hang the test suite on it.
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within 120 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let dom = child.wait_with_output().unwrap().stdout;
    drop(server);
    parse_result(&String::from_utf8_lossy(&dom)).unwrap_or_else(|| {
        panic!(
            "no result in chromium's DOM:\n{}",
            String::from_utf8_lossy(&dom)
        )
    })
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

fn chromium() -> Option<PathBuf> {
    let p = PathBuf::from(CHROMIUM);
    if p.exists() {
        Some(p)
    } else {
        eprintln!(
            "browser test skipped: {CHROMIUM} is not installed (Debian: apt-get install chromium)"
        );
        None
    }
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
    let presets = shadelab::gallery::builtin_presets().unwrap().len();
    let (count, broken) = check_images(&d.join("g"), &d.join("profile"));
    assert!(
        broken.is_empty(),
        "broken images in the gallery: {broken:?}"
    );
    assert_eq!(count, presets, "one thumbnail per preset");
    let _ = std::fs::remove_dir_all(&d);
}
