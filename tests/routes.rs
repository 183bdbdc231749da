//! One picture, one number, whatever its route (issue 59): a stimulus by name, the 16- and
//! 8-bit PNGs and the `.npy` shadelab wrote of it, and a picture read once through a pipe, with
//! its format told by its content.

use crate::cli::{assert_error, scratch, shadelab};
use serde_json::Value;
use std::path::Path;

fn report(out: &std::process::Output) -> Value {
    let (o, e) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "stdout: {o}\nstderr: {e}");
    serde_json::from_str(&o).unwrap_or_else(|err| panic!("not one JSON document: {err}\n{o}"))
}

/// Each token's convexity at each tilt (token-major) and its flips.
fn curves(r: &Value) -> Vec<(Vec<f64>, Vec<f64>)> {
    let tokens = r["tokens"].as_array().unwrap();
    (0..tokens.len())
        .map(|k| {
            let convexity = r["interpretations"]
                .as_array()
                .unwrap()
                .iter()
                .map(|i| i["tokens"][k]["convexity"].as_f64().unwrap())
                .collect();
            let flips = tokens[k]["flips_deg"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| f.as_f64().unwrap())
                .collect();
            (convexity, flips)
        })
        .collect()
}

/// The prior sweep of every stimulus with targets gives the numbers of `--stimulus NAME` from
/// the 16-bit PNG, the 8-bit PNG and the float32 `.npy` shadelab wrote of it: flips within
/// 0.1°, convexities within 1 % of the curve's largest value (2 % for 8 bits: the crater's
/// terminator, 0.004 wide in one 8-bit code, measured 1.8 %). Before issue 59 the crater's
/// 504 shadow pixels, a code off the ambient level, carried data in every file (11 % at 16
/// bits), and the hollow mask was solved on the whole frame from a file (67 %).
#[test]
fn every_route_gives_the_stimulus_numbers() {
    let d = scratch("routes");
    let names = [
        "crater",
        "bumps",
        "sideways",
        "strips",
        "hollow-mask",
        "circles-binary",
        "boundary-strips",
        "sphere",
    ];
    let sweep = |picture: &[&str], out: &str| {
        let args = [
            &["--json", "--quiet", "analyze", "prior-sweep"][..],
            picture,
            &["--tilts", "0:360:45", "--out", out],
        ]
        .concat();
        report(&shadelab(&d, &args))
    };
    let mut worst: Vec<(String, f64, f64)> = Vec::new();
    for name in names {
        let png16 = format!("{name}.png");
        let png8 = format!("{name}8.png");
        let npy = format!("{name}.npy");
        for (out, depth) in [(&png16, "16"), (&png8, "8"), (&npy, "16")] {
            let made = shadelab(
                &d,
                &[
                    "--quiet",
                    "render",
                    name,
                    "--bit-depth",
                    depth,
                    "--out",
                    out,
                ],
            );
            assert!(
                made.status.success(),
                "{}",
                String::from_utf8_lossy(&made.stderr)
            );
        }
        let base = sweep(&["--stimulus", name], &format!("{name}-name"));
        for (route, file, bound) in [
            ("png16", &png16, 0.01),
            ("png8", &png8, 0.02),
            ("npy", &npy, 0.01),
        ] {
            let r = sweep(&[file.as_str()], &format!("{name}-{route}"));
            assert_eq!(
                r["parameters"]["domain"], base["parameters"]["domain"],
                "{name} {route}"
            );
            for key in ["albedo", "ambient"] {
                let (a, b) = (
                    r["parameters"][key].as_f64().unwrap(),
                    base["parameters"][key].as_f64().unwrap(),
                );
                // The recorded albedo and ambient level, or one taken from the background.
                assert!((a - b).abs() < 0.005, "{name} {route} {key}: {a} vs {b}");
            }
            let (mut conv, mut flip) = (0.0f64, 0.0f64);
            for ((cb, fb), (cr, fr)) in curves(&base).iter().zip(curves(&r)) {
                let largest = cb.iter().fold(0.0f64, |m, c| m.max(c.abs())).max(1e-12);
                for (a, b) in cb.iter().zip(&cr) {
                    conv = conv.max((a - b).abs() / largest);
                }
                assert_eq!(fb.len(), fr.len(), "{name} {route}: flips {fb:?} vs {fr:?}");
                for (a, b) in fb.iter().zip(&fr) {
                    flip = flip.max((a - b).abs());
                }
            }
            eprintln!(
                "{name} {route}: convexity {:.2} % of the largest, flips {flip:.3}°",
                conv * 100.0
            );
            assert!(
                conv <= bound,
                "{name} {route}: convexity off by {:.2} % of the curve's largest",
                conv * 100.0
            );
            assert!(flip <= 0.1, "{name} {route}: a flip moved {flip}°");
            worst.push((format!("{name} {route}"), conv, flip));
        }
    }
    assert_eq!(worst.len(), names.len() * 3);
    let _ = std::fs::remove_dir_all(&d);
}

/// A picture given through a FIFO (read once: it cannot be read again) or under a name that
/// does not say its format is read by its content; `--mask` takes a 0/1 `.npy` too.
#[test]
fn a_picture_is_read_once_through_a_fifo_and_by_its_content() {
    let d = scratch("fifo");
    let made = shadelab(
        &d,
        &[
            "--quiet",
            "render",
            "sphere",
            "--size",
            "64",
            "--out",
            "sphere.png",
        ],
    );
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
    let bytes = std::fs::read(d.join("sphere.png")).unwrap();
    let solve = |picture: &str, out: &str| {
        let made = shadelab(
            &d,
            &[
                "--quiet", "solve", picture, "--light", "front", "--out", out,
            ],
        );
        assert!(
            made.status.success(),
            "{picture}: {}",
            String::from_utf8_lossy(&made.stderr)
        );
        std::fs::read(d.join(out).join("normals.npy")).unwrap()
    };
    // A copy without its sidecar: what a pipe gives (no X.json can lie beside /dev/fd/63).
    std::fs::write(d.join("bare.png"), &bytes).unwrap();
    let bare = solve("bare.png", "a");
    // The same bytes under a name without an extension: the content says PNG.
    std::fs::write(d.join("picture"), &bytes).unwrap();
    assert!(solve("picture", "b") == bare, "a PNG without its extension");
    // Through a FIFO named pipe.png, written once by a thread.
    let fifo = d.join("pipe.png");
    match std::process::Command::new("mkfifo").arg(&fifo).status() {
        Ok(s) if s.success() => {
            let writer = {
                let (fifo, bytes) = (fifo.clone(), bytes.clone());
                std::thread::spawn(move || std::fs::write(&fifo, &bytes))
            };
            let piped = solve("pipe.png", "c");
            writer.join().unwrap().unwrap();
            assert!(piped == bare, "the FIFO's picture");
        }
        _ => eprintln!("skipped the FIFO: mkfifo is not available here"),
    }
    // bash's process substitution (/dev/fd/63), where bash is.
    let exe = env!("CARGO_BIN_EXE_shadelab");
    match std::process::Command::new("bash")
        .arg("-c")
        .arg(format!(
            "'{exe}' --quiet solve <(cat sphere.png) --light front --out e"
        ))
        .current_dir(&d)
        .output()
    {
        Ok(out) if out.status.code() != Some(127) => {
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(std::fs::read(d.join("e/normals.npy")).unwrap() == bare);
        }
        _ => eprintln!("skipped process substitution: no bash here"),
    }
    // --mask takes a .npy of 0/1 values, and refuses other values naming the file.
    let mask: shadelab::Image = shadelab::Grid::from_fn(64, 64, |c, r| {
        f64::from(u8::from((c as f64 - 31.5).hypot(r as f64 - 31.5) < 20.0))
    });
    shadelab::internal::io::write_image(&d.join("mask.npy"), &mask).unwrap();
    let masked = report(&shadelab(
        &d,
        &[
            "--json", "--quiet", "solve", "bare.png", "--mask", "mask.npy", "--light", "front",
            "--out", "f",
        ],
    ));
    assert!(masked["solver"]["converged"].as_bool().unwrap(), "{masked}");
    let half = mask.map(|&v| v * 0.5);
    shadelab::internal::io::write_image(&d.join("half.npy"), &half).unwrap();
    let refused = shadelab(
        &d,
        &[
            "--quiet", "solve", "bare.png", "--mask", "half.npy", "--light", "front", "--out", "g",
        ],
    );
    assert_error(&refused, 1, "half.npy");
    let e = String::from_utf8_lossy(&refused.stderr);
    assert!(e.contains("booleans or 0/1 values"), "{e}");
    assert!(!Path::new(&d.join("g")).exists());
    let _ = std::fs::remove_dir_all(&d);
}
