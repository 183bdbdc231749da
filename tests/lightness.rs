//! Lightness models against reference data: the ODOG family against multyscale 0.2's outputs
//! (`../shared/reference/odog_white32.npz`; skipped with a message when absent).

use shadelab::Grid;
use shadelab::Image;
use shadelab_analysis::lightness::{Odog, Variant};
use std::path::PathBuf;

fn reference_npz() -> Option<PathBuf> {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/reference/odog_white32.npz");
    if path.is_file() {
        Some(path)
    } else {
        eprintln!(
            "skipping: {} not found (the shared reference data is not checked out)",
            path.display()
        );
        None
    }
}

/// One array of the archive as (height, width, values), whatever its numeric dtype.
fn npz_array(archive: &mut zip::ZipArchive<std::fs::File>, name: &str) -> (usize, usize, Vec<f64>) {
    use std::io::Read;
    let mut bytes = Vec::new();
    archive
        .by_name(&format!("{name}.npy"))
        .unwrap_or_else(|e| panic!("array {name}: {e}"))
        .read_to_end(&mut bytes)
        .expect("readable archive");
    let file = npyz::NpyFile::new(&bytes[..]).expect("a .npy member");
    let shape: Vec<usize> = file.shape().iter().map(|&d| d as usize).collect();
    assert_eq!(shape.len(), 2, "{name} is not 2-D");
    let descr = file.dtype().descr();
    let data: Vec<f64> = if descr.contains("f4") {
        file.into_vec::<f32>()
            .unwrap()
            .into_iter()
            .map(f64::from)
            .collect()
    } else if descr.contains("f8") {
        file.into_vec::<f64>().unwrap()
    } else if descr.contains("u1") {
        file.into_vec::<u8>()
            .unwrap()
            .into_iter()
            .map(f64::from)
            .collect()
    } else {
        panic!("{name}: unexpected dtype {descr}")
    };
    (shape[0], shape[1], data)
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        sab += (x - ma) * (y - mb);
        saa += (x - ma) * (x - ma);
        sbb += (y - mb) * (y - mb);
    }
    sab / (saa * sbb).sqrt()
}

fn label_mean(values: &[f64], labels: &[f64], label: f64) -> f64 {
    let (s, n) = values
        .iter()
        .zip(labels)
        .filter(|(_, &l)| l == label)
        .fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
    s / n as f64
}

#[test]
fn odog_lodog_flodog_match_multyscale() {
    let Some(path) = reference_npz() else { return };
    let mut archive =
        zip::ZipArchive::new(std::fs::File::open(&path).expect("open the reference archive"))
            .expect("a zip archive");
    let (h, w, input) = npz_array(&mut archive, "input");
    let (_, _, labels) = npz_array(&mut archive, "target_mask");
    let image: Image = Grid::from_vec(w, h, input).unwrap();
    // README: 32 pixels per degree (visextent ±0.5·1023/32°).
    for (variant, name) in [
        (Variant::Odog, "ODOG"),
        (Variant::Lodog, "LODOG"),
        (Variant::Flodog, "FLODOG"),
    ] {
        let (_, _, want) = npz_array(&mut archive, name);
        let got = Odog::new(w, h, 32.0, variant)
            .unwrap()
            .apply(&image)
            .unwrap();
        let r = correlation(got.data(), &want);
        let max_abs = got
            .data()
            .iter()
            .zip(&want)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        eprintln!("{name}: correlation {r:.8}, max |difference| {max_abs:.2e}");
        assert!(r >= 0.999, "{name}: correlation {r}");
        for label in [1.0, 2.0] {
            let (g, m) = (
                label_mean(got.data(), &labels, label),
                label_mean(&want, &labels, label),
            );
            eprintln!("{name}: target {label}: shadelab {g:.5}, multyscale {m:.5}");
            assert!(
                (g - m).abs() <= 0.01 * m.abs(),
                "{name} target {label}: {g} vs multyscale {m}"
            );
        }
    }
}

mod cli {
    //! `shadelab analyze lightness` and `analyze fading` through the binary.

    use crate::cli::{assert_error, scratch, shadelab};
    use shadelab::Grid;
    use shadelab_io as io;

    fn read(path: &std::path::Path) -> String {
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    #[test]
    fn checker_shadow_reports_identical_pixels_and_the_models() {
        let dir = scratch("lightness-checker");
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "--stimulus",
                "checker-shadow",
                "--ppd",
                "20",
                "--model",
                "all",
                "--out",
                "res",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        for m in ["odog", "lodog", "flodog", "retinex", "highpass"] {
            assert!(dir.join(format!("res/lightness_{m}.npy")).is_file());
            assert!(dir.join(format!("res/lightness_{m}.png")).is_file());
        }
        let csv = read(&dir.join("res/targets.csv"));
        assert!(csv.starts_with("model,label,name,pixels,luminance,output\n"));
        assert_eq!(csv.lines().count(), 1 + 5 * 2, "{csv}");
        assert!(csv.contains("retinex,2,B,"));
        let report: serde_json::Value =
            serde_json::from_str(&read(&dir.join("res/lightness.json"))).unwrap();
        let checker = &report["checker_shadow"];
        assert_eq!(checker["identical_pixels"], true);
        assert_eq!(checker["a"]["min"], checker["b"]["max"]);
        let predictions = checker["predictions"].as_array().unwrap();
        assert_eq!(predictions.len(), 5);
        // The literature's property: FLODOG and Retinex, which discount the soft shadow,
        // predict B lighter than A (docs/lightness.md gives every model's numbers).
        for p in predictions {
            if p["model"] == "flodog" || p["model"] == "retinex" {
                assert_eq!(p["matches_percept"], true, "{p}");
                assert!(p["b_minus_a"].as_f64().unwrap() > 0.0, "{p}");
            }
        }
        // The model output over the targets in the CSV is what the .npy holds.
        let npy = io::read_image(&dir.join("res/lightness_odog.npy"), 1 << 24).unwrap();
        assert_eq!((npy.width(), npy.height()), (180, 140));
    }

    #[test]
    fn an_image_with_a_mask_gives_one_model_and_its_target_means() {
        let dir = scratch("lightness-image");
        // 8° at 16 ppd: a mid-grey square on a dark left and a light right half.
        let image = Grid::from_fn(128, 128, |c, r| {
            if (56..72).contains(&c) && (56..72).contains(&r) {
                0.5
            } else if c < 64 {
                0.1
            } else {
                0.9
            }
        });
        io::write_image(&dir.join("img.npy"), &image).unwrap();
        let labels = Grid::from_fn(128, 128, |c, r| {
            u16::from((56..72).contains(&c) && (56..72).contains(&r)) * if c < 64 { 1 } else { 2 }
        });
        io::write_labels(&dir.join("labels.png"), &labels).unwrap();
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "img.npy",
                "--ppd",
                "16",
                "--model",
                "odog",
                "--mask",
                "labels.png",
                "--out",
                "res",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let lightness = io::read_image(&dir.join("res/lightness.npy"), 1 << 20).unwrap();
        assert_eq!((lightness.width(), lightness.height()), (128, 128));
        assert!(dir.join("res/lightness.png").is_file());
        let targets: serde_json::Value =
            serde_json::from_str(&read(&dir.join("res/targets.json"))).unwrap();
        let rows = targets[0]["targets"].as_array().unwrap();
        assert_eq!(rows.len(), 2);
        // Simultaneous contrast: the half of the grey square on the dark side looks lighter.
        let (left, right) = (
            rows[0]["output"].as_f64().unwrap(),
            rows[1]["output"].as_f64().unwrap(),
        );
        assert!(left > right, "left {left}, right {right}");
        assert_eq!(rows[0]["pixels"], 8 * 16);
    }

    #[test]
    fn bad_input_is_a_one_line_error() {
        let dir = scratch("lightness-bad");
        let image = Grid::new(64, 64, 0.5);
        io::write_image(&dir.join("img.npy"), &image).unwrap();
        // No resolution for a plain image: the filter models need degrees.
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "img.npy",
                "--model",
                "lodog",
                "--out",
                "a",
            ],
        );
        assert_error(&out, 2, "--ppd");
        // 64 px at 32 ppd is 2°, smaller than the largest filter.
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "img.npy",
                "--ppd",
                "32",
                "--model",
                "odog",
                "--out",
                "b",
            ],
        );
        assert_error(&out, 2, "smaller than the largest filter");
        // A mask of another size.
        io::write_labels(&dir.join("m.png"), &Grid::new(60, 64, 1u16)).unwrap();
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "img.npy",
                "--ppd",
                "8",
                "--model",
                "odog",
                "--mask",
                "m.png",
                "--out",
                "c",
            ],
        );
        assert_error(&out, 2, "64 px high × 60 px wide");
        // NaN in the input.
        let mut nan = image.clone();
        *nan.get_mut(5, 7) = f64::NAN;
        io::write_image(&dir.join("nan.npy"), &nan).unwrap();
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "nan.npy",
                "--ppd",
                "8",
                "--model",
                "odog",
                "--out",
                "d",
            ],
        );
        assert!(!out.status.success());
        assert_eq!(String::from_utf8_lossy(&out.stderr).lines().count(), 1);
        assert!(String::from_utf8_lossy(&out.stderr).contains("NaN"));
        // An unknown model names the valid ones.
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "lightness",
                "img.npy",
                "--model",
                "odg",
                "--out",
                "e",
            ],
        );
        assert_error(&out, 2, "odog, lodog, flodog, retinex");
        // The fading analysis needs degrees and the two disks.
        let out = shadelab(&dir, &["analyze", "fading", "img.npy", "--out", "f"]);
        assert_error(&out, 2, "--ppd");
        let out = shadelab(
            &dir,
            &["analyze", "fading", "img.npy", "--ppd", "8", "--out", "g"],
        );
        assert_error(&out, 2, "--mask");
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "fading",
                "--stimulus",
                "fading-disk",
                "--tau",
                "0",
                "--out",
                "h",
            ],
        );
        assert_error(&out, 2, "τ 0 s");
        for d in ["a", "b", "c", "d", "e", "f", "g", "h"] {
            assert!(!dir.join(d).exists(), "{d} was written");
        }
    }

    #[test]
    fn the_blurred_disk_fades_and_the_sharp_one_persists() {
        let dir = scratch("fading");
        let out = shadelab(
            &dir,
            &[
                "analyze",
                "fading",
                "--stimulus",
                "fading-disk",
                "--ppd",
                "16",
                "--duration",
                "6",
                "--out",
                "res",
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let report: serde_json::Value =
            serde_json::from_str(&read(&dir.join("res/fading.json"))).unwrap();
        let ratio = report["border_energy"]["ratio"].as_f64().unwrap();
        assert!(ratio < 0.05, "energy ratio {ratio}");
        let (b, s) = (
            report["final_contrast"]["blurred"].as_f64().unwrap(),
            report["final_contrast"]["sharp"].as_f64().unwrap(),
        );
        assert!(s > 2.0 * b, "sharp {s}, blurred {b}");
        let csv = read(&dir.join("res/time_course.csv"));
        assert_eq!(csv.lines().count(), 1 + 121);
        let gif = std::fs::read(dir.join("res/fading.gif")).unwrap();
        assert!(gif.starts_with(b"GIF89a"));
    }
}

/// The lightness and fading analyses run as library pipelines, without the command line, and
/// write the same folder layout the command writes.
#[test]
fn lightness_and_fading_pipelines_run_from_plain_values() {
    use shadelab::pipeline::{fading, lightness, PictureSource};
    use shadelab::NoProgress;
    use shadelab_analysis::lightness::fading::{AdaptationOptions, DogBand};
    let source = |name: &str| PictureSource {
        stimulus: Some(name.into()),
        ppd: Some(12.0),
        max_pixels: shadelab::DEFAULT_MAX_PIXELS,
        ..Default::default()
    };
    let models = lightness::LightnessConfig::parse_models("retinex").unwrap();
    let config = lightness::LightnessConfig::new(source("checker-shadow"), models).unwrap();
    let report = lightness::run(&config, &NoProgress).unwrap();
    assert_eq!(report.models, ["retinex"]);
    assert_eq!(report.outputs[0].npy, "lightness.npy");
    let checker = report.checker_shadow.as_ref().unwrap();
    assert!(checker.identical_pixels);
    assert_eq!(report.images[0].1.width(), report.width);

    let adaptation = AdaptationOptions {
        duration_s: 1.0,
        ..Default::default()
    };
    let config =
        fading::FadingConfig::new(source("fading-disk"), DogBand::default(), adaptation).unwrap();
    let report = fading::run(&config, &NoProgress).unwrap();
    assert_eq!(report.course.times.len(), 21);
    assert!(report.border_energy.ratio < 1.0);
    assert_eq!(report.animation.frames, report.frames.len());
    let dir = std::env::temp_dir().join(format!("shadelab-fading-pipeline-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let written = shadelab::CommandReport::write(&report, &shadelab::Output::new(&dir)).unwrap();
    for file in ["fading.json", "fading.gif", "time_course.csv"] {
        assert!(written.join(file).is_file(), "{file}");
    }
    std::fs::remove_dir_all(&written).unwrap();
}
