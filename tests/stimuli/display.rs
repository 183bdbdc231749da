//! What reaches the display: the range rule (a stimulus is 0..1, refused with its fix when it
//! leaves it, never clipped) and PNGs that describe themselves (gAMA and iTXt chunks), read back
//! with the `png` crate's own decoder and through shadelab's reader without their sidecar.

use super::*;
use crate::cli::{assert_error, files_in, scratch, shadelab};
use shadelab_io as io;

/// The gAMA value (hundred-thousandths) and the iTXt chunks of a PNG, as the `png` crate reads
/// them.
fn chunks(path: &Path) -> (Option<u32>, Vec<(String, String)>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    let gamma = info.gamma().map(|g| g.into_scaled());
    let text = info
        .utf8_text
        .iter()
        .map(|t| (t.keyword.clone(), t.get_text().unwrap()))
        .collect();
    (gamma, text)
}

#[test]
fn a_picture_brighter_than_white_is_refused_with_the_scale_that_fits_it() {
    let d = scratch("display-range");
    // Blinn–Phong's highlight on albedo 1: 1 + 0.4 at the peak, less the sampling.
    let out = shadelab(
        &d,
        &[
            "render",
            "sphere",
            "--set",
            "brdf=blinn-phong",
            "--out",
            "s.png",
        ],
    );
    assert_error(&out, 2, "luminance reaches 1.3");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("pixels above 1"), "{err}");
    assert!(
        files_in(&d).is_empty(),
        "nothing written: {:?}",
        files_in(&d)
    );
    // The fix it gives, taken as given, renders, and the peak is white within a code.
    let fix: Vec<String> = err
        .split("set ")
        .nth(1)
        .and_then(|rest| rest.split(" (").next())
        .unwrap()
        .split(' ')
        .map(str::to_string)
        .collect();
    assert_eq!(fix.len(), 3, "albedo, ambient and specular: {fix:?}");
    let mut args = vec!["render", "sphere", "--set", "brdf=blinn-phong"];
    for f in &fix {
        args.extend(["--set", f]);
    }
    args.extend(["--out", "s.png"]);
    ok(&shadelab(&d, &args));
    let (img, _) = io::read_gray(&d.join("s.png"), MAX).unwrap();
    let peak = img.data().iter().cloned().fold(0.0, f64::max);
    assert!(peak <= 1.0 && peak > 1.0 - 2e-4, "peak {peak}");
    // Lambertian: ambient and albedo adding up past 1 is refused the same way, in the library
    // too (Python's render calls it).
    let mut given = Map::new();
    given.insert("ambient".into(), 0.5.into());
    let size = SizeRequest {
        visual_size: None,
        ppd: None,
        shape: Some((64, 64)),
    };
    let err = stimulus::generate("sphere", &given, &size, 0, MAX).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("luminance reaches 1.49"), "{text}");
    assert!(
        text.contains("set albedo=0.6667 ambient=0.3333 ("),
        "{text}"
    );
    assert!(
        !text.contains("specular"),
        "lambertian has no highlight: {text}"
    );
}

#[test]
fn every_stimulus_at_its_defaults_is_within_the_range() {
    let mut checked = 0;
    for name in stimulus::names() {
        let output = match small(name) {
            Ok((_, output)) => output,
            // Stimuli that need a file (a depth map, a mesh) have no defaults to render.
            Err(e) if e.to_string().contains("give the") => {
                eprintln!("range: {name} does not render from defaults alone; skipped ({e})");
                continue;
            }
            Err(e) => panic!("{name}: {e}"),
        };
        let (lo, hi) = output.pixels.extremes();
        assert!((0.0..=1.0).contains(&lo) && hi <= 1.0, "{name}: {lo}..{hi}");
        checked += 1;
    }
    assert!(checked >= 18, "only {checked} stimuli rendered");
}

#[test]
fn a_stimulus_png_says_how_it_encodes_light_and_what_it_is() {
    let d = scratch("display-png");
    ok(&shadelab(
        &d,
        &["render", "sphere", "--size", "60x40", "--out", "lin.png"],
    ));
    ok(&shadelab(
        &d,
        &[
            "render",
            "sphere",
            "--size",
            "60x40",
            "--gamma",
            "2.2",
            "--bit-depth",
            "8",
            "--out",
            "enc.png",
        ],
    ));
    let (gamma, text) = chunks(&d.join("lin.png"));
    assert_eq!(gamma, Some(100_000), "linear codes: gAMA 1.0");
    let get = |text: &[(String, String)], key: &str| {
        text.iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("no iTXt {key}"))
    };
    assert_eq!(
        get(&text, "Software"),
        format!("shadelab {}", env!("CARGO_PKG_VERSION"))
    );
    let record: Value = serde_json::from_str(&get(&text, "shadelab")).unwrap();
    let meta = sidecar(&d.join("lin.json"));
    for key in [
        "stimulus",
        "parameters",
        "seed",
        "visual_size",
        "ppd",
        "shape",
        "encoding",
    ] {
        assert_eq!(
            record[key], meta[key],
            "{key}: the PNG and its sidecar agree"
        );
    }
    assert_eq!(record["shape"], serde_json::json!([40, 60]));
    assert!(get(&text, "Description").contains("40 x 60 px (height x width)"));
    // Display-encoded: gAMA 1/2.2; the mask is labels, not light: no gAMA.
    let (gamma, text) = chunks(&d.join("enc.png"));
    assert_eq!(gamma, Some(45_455));
    let record: Value = serde_json::from_str(&get(&text, "shadelab")).unwrap();
    assert_eq!(record["gamma"], 2.2);
    assert_eq!(record["bit_depth"], 8);
    assert_eq!(chunks(&d.join("enc_mask.png")).0, None);

    // Apart from its sidecar, the encoded PNG still reads as the linear picture: within the
    // 8-bit step at the code (the slope of v^(1/2.2) is steepest near black).
    let alone = d.join("alone");
    std::fs::create_dir_all(&alone).unwrap();
    std::fs::copy(d.join("enc.png"), alone.join("enc.png")).unwrap();
    let (enc, info) = io::read_gray(&alone.join("enc.png"), MAX).unwrap();
    assert!(info.conversion.unwrap().contains("gAMA"));
    let (lin, _) = io::read_gray(&d.join("lin.png"), MAX).unwrap();
    for (a, b) in enc.data().iter().zip(lin.data()) {
        let code = (b.powf(1.0 / 2.2) * 255.0).round();
        let step =
            ((code + 0.5) / 255.0).min(1.0).powf(2.2) - ((code - 0.5).max(0.0) / 255.0).powf(2.2);
        assert!((a - b).abs() <= step, "{a} vs {b} (step {step})");
    }
}
