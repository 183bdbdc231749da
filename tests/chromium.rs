//! Headless Chromium for the browser tests: a static file server for one folder and a runner
//! that loads a page and returns what Chromium printed (`--dump-dom`, `--screenshot`, the
//! console on stderr). Every browser test goes through here.
//!
//! Tests skip, saying why, where Chromium is not installed (Debian's `chromium`; `.ci/run`
//! installs it when it can): call [`chromium`] first.

use std::io::{BufRead, BufReader, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Where Debian installs Chromium.
pub const CHROMIUM: &str = "/usr/bin/chromium";

/// Chromium's path, or `None` after printing why the calling test skips.
pub fn chromium() -> Option<PathBuf> {
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

/// A static file server on 127.0.0.1 for one folder, until dropped. `extra` pages (name,
/// body) are served beside the folder's files, e.g. a checking page that frames the real one.
pub struct Server {
    port: u16,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Server {
    /// Serves `dir` (and the `extra` pages) on a free local port.
    pub fn start(dir: &Path, extra: &[(&str, &str)]) -> Server {
        let listener = TcpListener::bind("127.0.0.1:0").expect("bind a local port");
        listener.set_nonblocking(true).unwrap();
        let port = listener.local_addr().unwrap().port();
        let stop = Arc::new(AtomicBool::new(false));
        let (dir, flag) = (dir.to_path_buf(), stop.clone());
        let extra: Vec<(String, Vec<u8>)> = extra
            .iter()
            .map(|(n, b)| (n.to_string(), b.as_bytes().to_vec()))
            .collect();
        let thread = std::thread::spawn(move || {
            while !flag.load(Ordering::Relaxed) {
                match listener.accept() {
                    Ok((stream, _)) => {
                        let _ = serve(stream, &dir, &extra);
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

    /// The address of `path` (with any query) on this server.
    pub fn url(&self, path: &str) -> String {
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

/// The content type a static host sends for a file name (`.wasm` must be `application/wasm`
/// for streaming compilation).
fn content_type(path: &str) -> &'static str {
    match Path::new(path).extension().and_then(|e| e.to_str()) {
        Some("html") => "text/html; charset=utf-8",
        Some("js" | "mjs") => "text/javascript; charset=utf-8",
        Some("css") => "text/css; charset=utf-8",
        Some("wasm") => "application/wasm",
        Some("png") => "image/png",
        Some("gif") => "image/gif",
        Some("svg") => "image/svg+xml",
        Some("json") => "application/json",
        Some("csv") => "text/csv; charset=utf-8",
        Some("txt" | "md") => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// Answers one request (HTTP/1.0 style: one response, then close).
fn serve(stream: TcpStream, dir: &Path, extra: &[(String, Vec<u8>)]) -> std::io::Result<()> {
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
    let mut path = path.trim_start_matches('/').to_string();
    if path.is_empty() || path.ends_with('/') {
        path.push_str("index.html");
    }
    let body: Option<Vec<u8>> = if let Some((_, b)) = extra.iter().find(|(n, _)| *n == path) {
        Some(b.clone())
    } else if path.split('/').any(|c| c == ".." || c.is_empty()) {
        None
    } else {
        std::fs::read(dir.join(&path)).ok()
    };
    let mut out = stream;
    match body {
        Some(b) => {
            write!(
                out,
                "HTTP/1.1 200 OK\r\nContent-Type: {}\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                content_type(&path),
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

/// What one headless Chromium run printed.
pub struct Run {
    /// Standard output: the DOM with `--dump-dom`.
    pub stdout: String,
    /// Standard error: with `--enable-logging=stderr`, the page's console lines
    /// (`…:CONSOLE(line)] "message", source: …`).
    pub stderr: String,
}

impl Run {
    /// The console lines Chromium logged (needs `--enable-logging=stderr --v=0` in `args`).
    pub fn console(&self) -> Vec<&str> {
        self.stderr
            .lines()
            .filter(|l| l.contains(":CONSOLE"))
            .collect()
    }
}

/// Runs headless Chromium on `url` with a fresh profile under `profile` and the extra `args`
/// (e.g. `--dump-dom`, `--screenshot=PATH`, `--window-size=W,H`,
/// `--virtual-time-budget=MS`), and waits for it (at most `timeout`; a hang fails the test
/// rather than the whole suite).
pub fn run(url: &str, profile: &Path, args: &[&str], timeout: Duration) -> Run {
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
        ])
        .args(args)
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(url)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("chromium starts");
    // Read both pipes on threads so a chatty Chromium never blocks on a full pipe.
    let mut out = child.stdout.take().unwrap();
    let mut err = child.stderr.take().unwrap();
    let read_out = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = std::io::Read::read_to_end(&mut out, &mut s);
        s
    });
    let read_err = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = std::io::Read::read_to_end(&mut err, &mut s);
        s
    });
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        if start.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish within {timeout:?} on {url}");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Run {
        stdout: String::from_utf8_lossy(&read_out.join().unwrap()).into_owned(),
        stderr: String::from_utf8_lossy(&read_err.join().unwrap()).into_owned(),
    }
}

#[test]
fn the_server_serves_files_extra_pages_and_nothing_outside() {
    let d = crate::cli::scratch("chromium-server");
    std::fs::create_dir_all(d.join("sub")).unwrap();
    std::fs::write(d.join("index.html"), "home").unwrap();
    std::fs::write(d.join("sub/a.wasm"), [0u8, 97, 115, 109]).unwrap();
    let server = Server::start(&d, &[("__check.html", "check")]);
    let get = |path: &str| -> String {
        let mut s = TcpStream::connect(
            server
                .url("")
                .trim_start_matches("http://")
                .trim_end_matches('/'),
        )
        .unwrap();
        write!(s, "GET /{path} HTTP/1.0\r\n\r\n").unwrap();
        let mut r = String::new();
        std::io::Read::read_to_string(&mut s, &mut r).unwrap();
        r
    };
    assert!(get("").ends_with("home"));
    assert!(get("index.html?x=1").ends_with("home"));
    assert!(get("__check.html").ends_with("check"));
    assert!(get("sub/a.wasm").contains("Content-Type: application/wasm"));
    assert!(get("../etc/passwd").starts_with("HTTP/1.1 404"));
    assert!(get("missing.png").starts_with("HTTP/1.1 404"));
    drop(server);
    let _ = std::fs::remove_dir_all(&d);
}
