//! A display in cd/m²: `render --display` writes the codes of a display's model (PsychoPy's
//! gamma equations, a PsychoPy monitor file, a photometer table) at 8, 10 or 16 bits, plain,
//! bit-stolen or dithered; the codes read back with the `png` crate give the luminances the
//! sidecar records, within half a step; the picture read back through its sidecar is the
//! stimulus again; bad display files are one-line errors naming the flag or file.

use crate::cli::{assert_error, files_in, scratch, shadelab};
use serde_json::Value;
use shadelab::display::{Display, GammaModel, Quantise, Response};
use std::path::Path;

/// The samples of a PNG as the `png` crate decodes them (big-endian 16-bit joined), with its
/// channel count, bit depth, sBIT chunk and gAMA chunk.
fn samples(path: &Path) -> (Vec<u16>, usize, u8, Option<Vec<u8>>, Option<u32>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let frame = reader.next_frame(&mut buf).unwrap();
    let info = reader.info();
    let sbit = info.sbit.as_ref().map(|s| s.to_vec());
    let gamma = info.gamma().map(|g| g.into_scaled());
    let channels = frame.color_type.samples();
    let bits = frame.bit_depth as u8;
    let data = &buf[..frame.buffer_size()];
    let values = if bits == 16 {
        data.chunks(2)
            .map(|b| u16::from_be_bytes([b[0], b[1]]))
            .collect()
    } else {
        data.iter().map(|&b| u16::from(b)).collect()
    };
    (values, channels, bits, sbit, gamma)
}

fn sidecar(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// The float picture shadelab renders for the same arguments (the linear truth).
fn linear(d: &Path, args: &[&str]) -> Vec<f64> {
    let mut all = vec!["render"];
    all.extend_from_slice(args);
    all.extend(["--out", "truth.npy"]);
    let out = shadelab(d, &all);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let array = shadelab_io::read_array(&d.join("truth.npy"), 1 << 24).unwrap();
    array.data
}

/// Renders `stimulus` (name and flags) for the display file `display` at `luminance` to `out`.
fn on_display(d: &Path, stimulus: &[&str], display: &str, luminance: &str, out: &str) {
    let mut args = vec!["render"];
    args.extend_from_slice(stimulus);
    args.extend(["--display", display, "--luminance", luminance, "--out", out]);
    let run = shadelab(d, &args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

const DISPLAY_8: &str =
    r#"{"name": "lab", "bit_depth": 8, "gamma": 2.2, "black_cd_m2": 0.5, "white_cd_m2": 120}"#;

#[test]
fn each_code_shows_its_pixel_within_half_a_step_at_8_10_and_16_bits() {
    let d = scratch("display-bits");
    let stimulus = ["sphere", "--light", "above", "--size", "96x64"];
    let truth = linear(&d, &stimulus);
    let mut rms_by_bits = Vec::new();
    for bits in [8u8, 10, 16] {
        let json = DISPLAY_8.replace("\"bit_depth\": 8", &format!("\"bit_depth\": {bits}"));
        std::fs::write(d.join("lab.json"), json).unwrap();
        on_display(&d, &stimulus, "lab.json", "2,100", "s.png");
        let (codes, channels, file_bits, sbit, gamma) = samples(&d.join("s.png"));
        assert_eq!(channels, 1);
        assert_eq!(
            gamma, None,
            "display codes are not a power law: no gAMA chunk"
        );
        assert_eq!(file_bits, if bits == 8 { 8 } else { 16 });
        assert_eq!(sbit, (bits == 10).then(|| vec![10]), "{bits} bits: sBIT");
        let model = GammaModel {
            equation: 1,
            black: 0.5,
            white: 120.0,
            gamma: 2.2,
            b: 0.0,
        };
        let top = (1u32 << bits) - 1;
        let side = sidecar(&d.join("s.json"));
        assert_eq!(side["display"]["bit_depth"], bits);
        assert_eq!(side["bit_depth"], file_bits);
        let mut sum2 = 0.0;
        for (&stored, &v) in codes.iter().zip(&truth) {
            // 10-bit codes are stored by bit replication: the top 10 bits are the code.
            let code = if bits == 10 {
                u32::from(stored >> 6)
            } else {
                u32::from(stored)
            };
            if bits == 10 {
                assert_eq!(stored & 0x3f, (stored >> 10) & 0x3f, "bit replication");
            }
            let l = |c: u32| model.luminance(f64::from(c) / f64::from(top));
            let wanted = 2.0 + v * 98.0;
            let shown = l(code);
            // Half the step on the side the wanted luminance lies (f32 truth: a hair of slack).
            let step = if wanted >= shown {
                l((code + 1).min(top)) - shown
            } else {
                shown - l(code.saturating_sub(1))
            };
            assert!(
                (shown - wanted).abs() <= 0.5 * step + 1e-4,
                "{bits} bits: code {code} shows {shown} for {wanted}"
            );
            sum2 += (shown - wanted).powi(2);
        }
        let rms = (sum2 / truth.len() as f64).sqrt();
        let recorded = side["luminance_error_cd_m2"]["rms"].as_f64().unwrap();
        assert!(
            (recorded - rms).abs() < 1e-3 * rms.max(1e-6),
            "{recorded} vs {rms}"
        );
        rms_by_bits.push(rms);
    }
    // Each 2 bits more: the error falls about fourfold.
    assert!(rms_by_bits[1] < rms_by_bits[0] / 3.0 && rms_by_bits[2] < rms_by_bits[1] / 30.0);
    eprintln!("rms error cd/m² at 8, 10, 16 bits: {rms_by_bits:?}");
}

#[test]
fn the_sidecar_records_each_targets_luminance_and_the_file_reads_back_as_the_stimulus() {
    let d = scratch("display-targets");
    std::fs::write(d.join("lab.json"), DISPLAY_8).unwrap();
    let stimulus = ["bumps", "--size", "160x120"];
    let truth = linear(&d, &stimulus);
    on_display(
        &d,
        &stimulus,
        "lab.json",
        "background=40,michelson=0.5",
        "b.png",
    );
    let side = sidecar(&d.join("b.json"));
    assert_eq!(side["luminance"]["black_cd_m2"], 20.0);
    assert_eq!(side["luminance"]["white_cd_m2"], 60.0);
    let display = Display::new(
        "lab",
        8,
        Response::Gamma(GammaModel {
            equation: 1,
            black: 0.5,
            white: 120.0,
            gamma: 2.2,
            b: 0.0,
        }),
        Quantise::Plain,
    )
    .unwrap();
    let (codes, ..) = samples(&d.join("b.png"));
    let labels = shadelab_io::read_labels(&d.join("b_mask.png"), 1 << 24).unwrap();
    for t in side["targets"].as_array().unwrap() {
        let label = t["label"].as_u64().unwrap() as u16;
        let inside: Vec<f64> = codes
            .iter()
            .zip(labels.data())
            .filter(|(_, &l)| l == label)
            .map(|(&c, _)| display.code_luminance(c))
            .collect();
        let mean = inside.iter().sum::<f64>() / inside.len() as f64;
        let recorded = t["luminance_cd_m2"].as_f64().unwrap();
        assert!(
            (mean - recorded).abs() < 1e-9,
            "{}: {mean} vs {recorded}",
            t["name"]
        );
        let weber = t["weber_vs_background"].as_f64().unwrap();
        assert!((weber - (mean - 40.0) / 40.0).abs() < 1e-12);
    }
    // Read back with its sidecar (the solve's and the analyses' reader): the stimulus again,
    // each value within half a display step (about 0.33 cd/m² of 40 here: 0.009 of 0..1).
    let source = shadelab::PictureSource {
        image: Some(d.join("b.png")),
        max_pixels: 1 << 24,
        ..Default::default()
    };
    let picture = source.load(false).unwrap();
    let shadelab::Pixels::Gray(back) = picture.pixels else {
        panic!("gray")
    };
    let worst = back
        .data()
        .iter()
        .zip(&truth)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 0.5 * 0.7 / 40.0 + 1e-6,
        "read back within half a step: {worst}"
    );
    // `--spec` of the sidecar reproduces the files byte for byte.
    let out = shadelab(&d, &["render", "--spec", "b.json", "--out", "again.png"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read(d.join("b.png")).unwrap(),
        std::fs::read(d.join("again.png")).unwrap()
    );
}

#[test]
fn a_psychopy_monitor_file_gives_psychopys_own_luminances() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let d = scratch("display-psychopy");
    std::fs::copy(
        data.join("psychopy-monitor-labcrt.json"),
        d.join("labcrt.json"),
    )
    .unwrap();
    // Of its two calibrations, the one PsychoPy's Monitor('labcrt') loads: the last by name
    // ('2026_11_28 09:03', method 1, white 110 cd/m²), not the newer by calibDate
    // ('2026_11_20 lab', 118 cd/m²); python/tests/test_psychopy_window.py asks PsychoPy itself.
    let display = shadelab::read_display(&d.join("labcrt.json")).unwrap();
    let c = display.calibration().unwrap();
    assert_eq!(
        (c.name.as_str(), c.named, c.all.len()),
        ("2026_11_28 09:03", false, 2)
    );
    assert_eq!(display.black_white(), (0.5, 110.0));
    // Named, the other calibration (method 4, Pelli & Zhang) against PsychoPy's gammaFun.
    std::fs::write(
        d.join("lab.json"),
        r#"{"psychopy_monitor": "labcrt.json", "calibration": "2026_11_20 lab"}"#,
    )
    .unwrap();
    let display = shadelab::read_display(&d.join("lab.json")).unwrap();
    assert!(
        display.name().contains("2026_11_20 lab") && display.calibration().unwrap().named,
        "{}",
        display.name()
    );
    std::fs::write(
        d.join("nope.json"),
        r#"{"psychopy_monitor": "labcrt.json", "calibration": "2026"}"#,
    )
    .unwrap();
    let e = shadelab::read_display(&d.join("nope.json"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no calibration '2026' in the monitor file (it holds '2026_11_20 lab', '2026_11_28 09:03')"),
        "{e}"
    );
    let table = std::fs::read_to_string(data.join("psychopy-gammafun-eq4.csv")).unwrap();
    let mut n = 0;
    for line in table.lines().skip(1) {
        let (code, l) = line.split_once(',').unwrap();
        let (code, l): (u16, f64) = (code.parse().unwrap(), l.parse().unwrap());
        let ours = display.code_luminance(code);
        assert!(
            (ours - l).abs() < 1e-9 * l.max(1.0),
            "code {code}: {ours} vs PsychoPy {l}"
        );
        n += 1;
    }
    assert_eq!(n, 256);
    // Named, the older calibration (method 1).
    std::fs::write(
        d.join("old.json"),
        r#"{"psychopy_monitor": "labcrt.json", "calibration": "2026_11_28 09:03", "bit_depth": 8}"#,
    )
    .unwrap();
    let old = shadelab::read_display(&d.join("old.json")).unwrap();
    let expect = 0.5 + (110.0 - 0.5) * (128.0f64 / 255.0).powf(2.4);
    assert!((old.code_luminance(128) - expect).abs() < 1e-9);
    // The monitor file itself renders with --display.
    let out = shadelab(
        &d,
        &[
            "render",
            "sphere",
            "--display",
            "labcrt.json",
            "--size",
            "32",
            "--out",
            "s.png",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The sidecar records which calibration, and why that one.
    let record = &sidecar(&d.join("s.json"))["display"];
    assert_eq!(record["response"]["equation"], 1);
    assert_eq!(record["white_cd_m2"], 110.0);
    assert_eq!(record["psychopy_calibration"]["name"], "2026_11_28 09:03");
    assert_eq!(
        record["psychopy_calibration"]["taken"],
        "PsychoPy's: the last by name, as Monitor(name) loads it"
    );
    // --spec of that sidecar takes the same display, its record included.
    let out = shadelab(&d, &["render", "--spec", "s.json", "--out", "again.png"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(sidecar(&d.join("again.json"))["display"], *record);
}

#[test]
fn a_photometer_table_bit_stealing_and_dithering() {
    let d = scratch("display-table");
    // A measured display: 9 readings, interpolated monotonically.
    let rows: Vec<String> = (0..=8)
        .map(|i| {
            let code = (i * 32).min(255);
            let v = f64::from(code) / 255.0;
            format!("{code},{}", 0.3 + 99.7 * v.powf(2.35))
        })
        .collect();
    std::fs::write(
        d.join("meter.csv"),
        format!("code,cd_m2\n{}\n", rows.join("\n")),
    )
    .unwrap();
    let mut errors = Vec::new();
    for quantise in ["plain", "bit-stealing", "dither"] {
        std::fs::write(
            d.join("lab.json"),
            format!(r#"{{"name": "lab", "table": "meter.csv", "quantise": "{quantise}"}}"#),
        )
        .unwrap();
        let out = shadelab(
            &d,
            &[
                "render",
                "sphere",
                "--light",
                "above",
                "--size",
                "128",
                "--display",
                "lab.json",
                "--luminance",
                "5,60",
                "--out",
                &format!("{quantise}.png"),
            ],
        );
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let (_, channels, ..) = samples(&d.join(format!("{quantise}.png")));
        assert_eq!(channels, if quantise == "bit-stealing" { 3 } else { 1 });
        let side = sidecar(&d.join(format!("{quantise}.json")));
        assert_eq!(side["display"]["response"]["model"], "table");
        let e = &side["luminance_error_cd_m2"];
        errors.push((e["max"].as_f64().unwrap(), e["rms"].as_f64().unwrap()));
    }
    eprintln!("(max, rms) cd/m²: plain, bit-stealing, dither: {errors:?}");
    let (plain, stolen) = (errors[0], errors[1]);
    assert!(
        stolen.0 < plain.0 / 2.0 && stolen.1 < plain.1 / 3.0,
        "{errors:?}"
    );
    // The table's rows are where the display is measured: the model passes through them.
    let display = shadelab::read_display(&d.join("meter.csv")).unwrap();
    for row in &rows {
        let (c, l) = row.split_once(',').unwrap();
        let l: f64 = l.parse().unwrap();
        assert!((display.code_luminance(c.parse().unwrap()) - l).abs() < 1e-9);
    }
}

#[test]
fn bad_displays_are_one_line_errors_naming_the_flag_or_file() {
    let d = scratch("display-bad");
    std::fs::write(d.join("ok.json"), DISPLAY_8).unwrap();
    let cases: &[(&str, &str, &str)] = &[
        (
            "unknown.json",
            r#"{"gamma": 2.2, "black_cd_m2": 0, "white_cd_m2": 100, "gama": 1}"#,
            "unknown key 'gama'",
        ),
        (
            "two.json",
            r#"{"gamma": 2.2, "black_cd_m2": 0, "white_cd_m2": 100, "table": "t.csv"}"#,
            "says its response once",
        ),
        (
            "dark.json",
            r#"{"gamma": 2.2, "black_cd_m2": 50, "white_cd_m2": 10}"#,
            "0 <= black < white",
        ),
        (
            "steal10.json",
            r#"{"bit_depth": 10, "quantise": "bit-stealing", "gamma": 2.2, "black_cd_m2": 0, "white_cd_m2": 100}"#,
            "bit-stealing is for 8-bit",
        ),
        (
            "nan.json",
            r#"{"gamma": "x", "black_cd_m2": 0, "white_cd_m2": 100}"#,
            "gamma \"x\" is not a number",
        ),
        (
            "falls.csv",
            "code,cd\n0,1\n128,50\n200,40\n255,90\n",
            "must rise",
        ),
        ("short.csv", "code,cd\n0,1\n128,50\n", "top code"),
        ("broken.json", "{\"gamma\": 2.2,", "invalid JSON"),
    ];
    for (file, text, needle) in cases {
        std::fs::write(d.join(file), text).unwrap();
        let out = shadelab(
            &d,
            &["render", "sphere", "--display", file, "--out", "s.png"],
        );
        // A display file that is wrong: exit 1, as any unreadable input.
        assert_error(&out, 1, needle);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(file), "names the file: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    let out = shadelab(
        &d,
        &[
            "render",
            "sphere",
            "--display",
            "missing.json",
            "--out",
            "s.png",
        ],
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.json"));
    for (args, needle) in [
        (
            ["--luminance", "1,200", "--out", "s.png"],
            "--luminance: the stimulus's luminance 1..200",
        ),
        (
            ["--luminance", "background=50,michelson=2", "--out", "s.png"],
            "--luminance",
        ),
        (
            ["--luminance", "5,50", "--out", "s.npy"],
            "--display: a display's codes are written as PNG",
        ),
    ] {
        let mut all = vec!["render", "sphere", "--display", "ok.json"];
        all.extend(args);
        let out = shadelab(&d, &all);
        assert_error(&out, 2, needle);
    }
    // Nothing but the inputs is left behind.
    let mut left = files_in(&d);
    left.retain(|f| !f.ends_with(".json") && !f.ends_with(".csv"));
    assert!(left.is_empty(), "{left:?}");
}
