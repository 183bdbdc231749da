//! What a browser puts on its canvas of a stimulus PNG, measured in real headless Chromium:
//! each PNG is loaded in an `<img>`, drawn at its natural size on a canvas and read back with
//! `getImageData` three ways (as drawn, with `{colorSpace: 'srgb'}`, and from
//! `createImageBitmap(blob, {colorSpaceConversion: 'none'})`), and the codes are compared with
//! the file's own, decoded here by the `png` crate. Chromium colour-manages images: a gAMA chunk
//! says how the codes encode light, and Chromium converts them to sRGB on the way in.
//! The page runs twice, the second time with `--force-color-profile=srgb`. Skips, saying why,
//! where Chromium is not installed.
//!
//! What Chromium 148 (Debian 12) does, asserted below:
//! - gAMA 1/2.2 (shadelab's `--gamma 2.2`, the browser experiment's images): taken as sRGB,
//!   every code reaches the canvas as it is in the file, upright (canvas row 0 is file row 0).
//! - gAMA 1.0 (shadelab's linear default): re-encoded with the sRGB curve, code →
//!   round(255 · sRGB(code / 255)) within 1; only 0 and 255 keep their code.
//! - another gAMA 1/γ (e.g. `--gamma 2.4` or 1.8): converted from the power γ to sRGB.
//! - 16 bits: cut to 8 by keeping the high byte (code >> 8), then converted as above.
//! - `colorSpaceConversion: 'none'` gives the file's own codes (the high byte at 16 bits),
//!   whatever the gAMA; `{colorSpace: 'srgb'}` and `--force-color-profile=srgb` change nothing.

use crate::chromium::{chromium, run, Server};
use crate::cli::{scratch, shadelab};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::OnceLock;
use std::time::Duration;

/// The measuring page: `{{FILES}}` is replaced with the JSON list of PNGs to read.
const PAGE: &str = r#"<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>codes</title></head><body>
<pre id="result">pending</pre>
<script>
const files = {{FILES}};
// The red codes (two hex digits each, row by row from the top) of `source` drawn at w x h,
// and how many pixels are not opaque gray.
function read(source, w, h, options) {
  const canvas = document.createElement('canvas');
  canvas.width = w;
  canvas.height = h;
  const ctx = canvas.getContext('2d');
  ctx.drawImage(source, 0, 0);
  const data = options ? ctx.getImageData(0, 0, w, h, options).data
                       : ctx.getImageData(0, 0, w, h).data;
  let red = '', other = 0;
  for (let i = 0; i < w * h; i++) {
    const r = data[4 * i];
    red += r.toString(16).padStart(2, '0');
    if (data[4 * i + 1] !== r || data[4 * i + 2] !== r || data[4 * i + 3] !== 255) other++;
  }
  return {red, other};
}
async function measure(file) {
  const img = new Image();
  img.src = file;
  await img.decode();
  const w = img.naturalWidth, h = img.naturalHeight;
  const blob = await (await fetch(file)).blob();
  const raw = await createImageBitmap(blob, {colorSpaceConversion: 'none'});
  return {file, width: w, height: h, img: read(img, w, h),
          srgb: read(img, w, h, {colorSpace: 'srgb'}), raw: read(raw, w, h)};
}
Promise.all(files.map(measure)).then(
  r => { document.getElementById('result').textContent = 'RESULT ' + JSON.stringify(r) + ' END'; },
  e => { document.getElementById('result').textContent = 'RESULT "' + e + '" END'; });
</script></body></html>
"#;

/// One file's codes as the canvas got them.
#[derive(Debug, Clone, PartialEq)]
struct Drawn {
    width: usize,
    height: usize,
    /// `<img>` drawn on a canvas, `getImageData` as is.
    img: Vec<u8>,
    /// The same with `getImageData(…, {colorSpace: 'srgb'})`.
    srgb: Vec<u8>,
    /// `createImageBitmap(blob, {colorSpaceConversion: 'none'})` drawn on a canvas.
    raw: Vec<u8>,
    /// Pixels, over the three readings, that are not opaque gray (R = G = B, alpha 255).
    other: usize,
}

/// A PNG as the `png` crate decodes it: its codes (8 or 16 bits) and gAMA (hundred-thousandths).
struct File {
    codes: Vec<u16>,
    bits: u8,
    gama: Option<u32>,
    width: usize,
    height: usize,
}

/// Everything one test run measured.
struct Measured {
    files: BTreeMap<String, File>,
    drawn: BTreeMap<String, Drawn>,
    /// The same page with `--force-color-profile=srgb`.
    forced: BTreeMap<String, Drawn>,
    /// The experiment page's background (`design.json`'s `display.background`), one gray code.
    background: u8,
}

/// Reads `RESULT [...] END` from the dumped DOM: file name → what the canvas got.
fn parse_result(dom: &str) -> Result<BTreeMap<String, Drawn>, String> {
    let start = dom.find("RESULT ").ok_or("no RESULT")? + "RESULT ".len();
    let end = start + dom[start..].find(" END").ok_or("no END")?;
    let text = dom[start..end]
        .replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    let value: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let list = value
        .as_array()
        .ok_or(format!("the page failed: {value}"))?;
    let hex = |v: &serde_json::Value, key: &str| -> Result<(Vec<u8>, usize), String> {
        let red = v[key]["red"].as_str().ok_or(format!("no {key}"))?;
        let codes = (0..red.len() / 2)
            .map(|i| u8::from_str_radix(&red[2 * i..2 * i + 2], 16))
            .collect::<Result<Vec<u8>, _>>()
            .map_err(|e| e.to_string())?;
        Ok((codes, v[key]["other"].as_u64().unwrap_or(u64::MAX) as usize))
    };
    let mut out = BTreeMap::new();
    for v in list {
        let (img, a) = hex(v, "img")?;
        let (srgb, b) = hex(v, "srgb")?;
        let (raw, c) = hex(v, "raw")?;
        let size = |k: &str| v[k].as_u64().map(|n| n as usize).ok_or(format!("no {k}"));
        let file = v["file"].as_str().ok_or("no file")?.to_string();
        out.insert(
            file,
            Drawn {
                width: size("width")?,
                height: size("height")?,
                img,
                srgb,
                raw,
                other: a.saturating_add(b).saturating_add(c),
            },
        );
    }
    Ok(out)
}

/// Decodes `path` with the `png` crate, codes as stored (no transformations).
fn decode(path: &Path) -> File {
    let reader = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let mut decoder = png::Decoder::new(reader);
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().unwrap();
    let gama = reader.info().gamma().map(|g| g.into_scaled());
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Grayscale, "{path:?}");
    let (bits, codes) = match info.bit_depth {
        png::BitDepth::Eight => (8, buf.iter().map(|&c| u16::from(c)).collect()),
        png::BitDepth::Sixteen => (
            16,
            buf.chunks_exact(2)
                .map(|b| u16::from_be_bytes([b[0], b[1]]))
                .collect(),
        ),
        d => panic!("{path:?}: {d:?} bits"),
    };
    File {
        codes,
        bits,
        gama,
        width: info.width as usize,
        height: info.height as usize,
    }
}

/// A 16 × 16 gray ramp of every 8-bit code (row-major, 0 at the top left) with gAMA `gama`.
fn ramp(path: &Path, gama: u32) {
    let codes: Vec<u8> = (0..=255).collect();
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(file, 16, 16);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_source_gamma(png::ScaledFloat::from_scaled(gama));
    encoder
        .write_header()
        .unwrap()
        .write_image_data(&codes)
        .unwrap();
}

/// The sRGB code (0..255) of linear light `v` (IEC 61966-2-1).
fn srgb_code(v: f64) -> i32 {
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (255.0 * e).round() as i32
}

/// The files and what Chromium drew of them, once per test run; `None` (after printing why)
/// without Chromium.
fn measured() -> Option<&'static Measured> {
    static MEASURED: OnceLock<Option<Measured>> = OnceLock::new();
    MEASURED
        .get_or_init(|| {
            chromium()?;
            let d = scratch("display-browser");
            let render = |args: &[&str]| {
                let out = shadelab(&d, args);
                assert!(
                    out.status.success(),
                    "shadelab {args:?}: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
            };
            let sphere = ["--quiet", "render", "sphere", "--light", "above"];
            let size = ["--size", "64x48"];
            for (name, extra) in [
                ("gamma.png", &["--bit-depth", "8", "--gamma", "2.2"][..]),
                ("linear.png", &["--bit-depth", "8"][..]),
                ("gamma16.png", &["--gamma", "2.2"][..]),
                ("linear16.png", &[][..]),
            ] {
                render(&[&sphere[..], &size[..], extra, &["--out", name][..]].concat());
            }
            // The browser experiment as `shadelab experiment` writes it (8 bits, gamma 2.2).
            render(&[
                "--quiet",
                "experiment",
                "--out",
                "e",
                "--rotations",
                "0:360:90",
                "--visual-size",
                "2",
                "--ppd",
                "16",
                "--no-install",
            ]);
            for (name, gama) in [
                ("ramp-gamma.png", 45_455),
                ("ramp-linear.png", 100_000),
                ("ramp-2.4.png", 41_667),
                ("ramp-1.8.png", 55_556),
            ] {
                ramp(&d.join(name), gama);
            }
            let design: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(d.join("e/design.json")).unwrap())
                    .unwrap();
            let background = design["display"]["background"].as_str().unwrap();
            let background = u8::from_str_radix(&background[1..3], 16).unwrap();
            let mut names: Vec<String> = [
                "gamma.png",
                "linear.png",
                "gamma16.png",
                "linear16.png",
                "ramp-gamma.png",
                "ramp-linear.png",
                "ramp-2.4.png",
                "ramp-1.8.png",
            ]
            .map(String::from)
            .to_vec();
            for theta in ["000", "090", "180", "270"] {
                names.push(format!("e/images/theta-{theta}.png"));
            }
            let files: BTreeMap<String, File> = names
                .iter()
                .map(|n| (n.clone(), decode(&d.join(n))))
                .collect();
            let page = PAGE.replace("{{FILES}}", &serde_json::to_string(&names).unwrap());
            let server = Server::start(&d, &[("__codes.html", &page)]);
            let draw = |profile: &str, extra: &[&str]| {
                let args = [&["--virtual-time-budget=10000", "--dump-dom"][..], extra].concat();
                let dom = run(
                    &server.url("__codes.html"),
                    &d.join(profile),
                    &args,
                    Duration::from_secs(60),
                )
                .stdout;
                parse_result(&dom).unwrap_or_else(|e| panic!("{e}; chromium's DOM:\n{dom}"))
            };
            let drawn = draw("profile", &[]);
            let forced = draw("profile-srgb", &["--force-color-profile=srgb"]);
            drop(server);
            let _ = std::fs::remove_dir_all(&d);
            Some(Measured {
                files,
                drawn,
                forced,
                background,
            })
        })
        .as_ref()
}

impl Measured {
    /// The file `name` and what the canvas got of it, after checking that every file was drawn
    /// at its own size, in opaque gray.
    fn get(&self, name: &str) -> (&File, &Drawn) {
        let (file, drawn) = (&self.files[name], &self.drawn[name]);
        assert_eq!(
            (drawn.width, drawn.height),
            (file.width, file.height),
            "{name}: natural size"
        );
        for (how, codes) in [
            ("img", &drawn.img),
            ("srgb", &drawn.srgb),
            ("raw", &drawn.raw),
        ] {
            assert_eq!(codes.len(), file.codes.len(), "{name} {how}");
        }
        assert_eq!(drawn.other, 0, "{name}: pixels that are not opaque gray");
        (file, drawn)
    }
}

/// Where `got` differs from `want`: (how many codes, the largest difference got − want, the
/// smallest).
fn differences(got: &[u8], want: &[i32]) -> (usize, i32, i32) {
    let d: Vec<i32> = got
        .iter()
        .zip(want)
        .map(|(&g, &w)| i32::from(g) - w)
        .collect();
    (
        d.iter().filter(|&&x| x != 0).count(),
        d.iter().copied().max().unwrap_or(0),
        d.iter().copied().min().unwrap_or(0),
    )
}

/// Mean of the codes in rows [from, to) of a `width`-wide picture.
fn mean_rows(codes: &[u8], width: usize, from: usize, to: usize) -> f64 {
    let rows = &codes[from * width..to * width];
    rows.iter().map(|&c| f64::from(c)).sum::<f64>() / rows.len() as f64
}

/// The file's codes as i32 (8-bit files) or their high byte (16-bit files: what Chromium keeps).
fn high_byte(file: &File) -> Vec<i32> {
    let shift = if file.bits == 16 { 8 } else { 0 };
    file.codes.iter().map(|&c| i32::from(c >> shift)).collect()
}

#[test]
fn the_result_line_is_parsed() {
    let dom = "<pre id=\"result\">RESULT [{&quot;file&quot;:&quot;a.png&quot;,&quot;width&quot;:2,\
               &quot;height&quot;:1,&quot;img&quot;:{&quot;red&quot;:&quot;00ff&quot;,&quot;other&quot;:0},\
               &quot;srgb&quot;:{&quot;red&quot;:&quot;0a0b&quot;,&quot;other&quot;:1},\
               &quot;raw&quot;:{&quot;red&quot;:&quot;7f80&quot;,&quot;other&quot;:2}}] END</pre>";
    let r = parse_result(dom).unwrap();
    assert_eq!(
        r["a.png"],
        Drawn {
            width: 2,
            height: 1,
            img: vec![0, 255],
            srgb: vec![10, 11],
            raw: vec![127, 128],
            other: 3,
        }
    );
    assert!(parse_result("<pre>pending</pre>").is_err());
    assert!(parse_result("<pre>RESULT \"TypeError: x\" END</pre>").is_err());
}

#[test]
fn a_gamma_2_2_png_reaches_the_canvas_code_for_code_and_upright() {
    let Some(m) = measured() else { return };
    // Every 8-bit code, with shadelab's gAMA for --gamma 2.2 (1/2.2 = 45455): all unchanged,
    // however the canvas is read.
    let (file, drawn) = m.get("ramp-gamma.png");
    assert_eq!(file.gama, Some(45_455));
    let codes = high_byte(file);
    for (how, got) in [
        ("img", &drawn.img),
        ("srgb", &drawn.srgb),
        ("raw", &drawn.raw),
    ] {
        assert_eq!(differences(got, &codes), (0, 0, 0), "ramp, {how}");
    }
    // A sphere lit from above, as `render --bit-depth 8 --gamma 2.2` writes it.
    let (file, drawn) = m.get("gamma.png");
    assert_eq!((file.bits, file.gama), (8, Some(45_455)));
    let codes = high_byte(file);
    for (how, got) in [
        ("img", &drawn.img),
        ("srgb", &drawn.srgb),
        ("raw", &drawn.raw),
    ] {
        assert_eq!(differences(got, &codes), (0, 0, 0), "sphere, {how}");
    }
    // Upright: canvas row y is the file's row y (the whole picture is equal, above), and the
    // top third, which faces the light, is the brighter.
    let (w, h) = (drawn.width, drawn.height);
    assert_eq!((w, h), (64, 48));
    for y in [0, h / 4, h / 2, 3 * h / 4, h - 1] {
        let row: Vec<i32> = drawn.img[y * w..(y + 1) * w]
            .iter()
            .map(|&c| i32::from(c))
            .collect();
        assert_eq!(row, codes[y * w..(y + 1) * w], "row {y}");
    }
    let (top, bottom) = (
        mean_rows(&drawn.img, w, 0, h / 3),
        mean_rows(&drawn.img, w, h - h / 3, h),
    );
    eprintln!("gamma.png on the canvas: top third mean {top:.1}, bottom third {bottom:.1}");
    assert!(
        top > bottom + 20.0,
        "lit from above: top {top:.1}, bottom {bottom:.1}"
    );
    // --force-color-profile=srgb changes nothing on the canvas.
    assert_eq!(m.forced, m.drawn, "with --force-color-profile=srgb");
}

#[test]
fn a_linear_png_is_re_encoded_with_the_srgb_curve_unless_drawn_without_colour_conversion() {
    let Some(m) = measured() else { return };
    // Every 8-bit code with gAMA 1.0: round(255 · sRGB(code / 255)) within 1; only black and
    // white keep their code, and the darkest codes rise the most.
    let (file, drawn) = m.get("ramp-linear.png");
    assert_eq!(file.gama, Some(100_000));
    let srgb: Vec<i32> = (0..=255).map(|c| srgb_code(f64::from(c) / 255.0)).collect();
    let (n, above, below) = differences(&drawn.img, &srgb);
    eprintln!(
        "gAMA 1.0 ramp: {n} of 256 codes differ from round(255 sRGB(v)), by {below}..{above}"
    );
    assert!(above <= 1 && below >= -1, "{n} codes, {below}..{above}");
    let codes = high_byte(file);
    let (changed, rise, fall) = differences(&drawn.img, &codes);
    eprintln!("gAMA 1.0 ramp: {changed} of 256 codes changed, by {fall}..{rise}");
    assert_eq!((changed, fall), (254, 0));
    assert!((70..=75).contains(&rise), "largest rise {rise}");
    assert_eq!(&drawn.img[..4], &[0, 13, 22, 28], "the darkest codes");
    assert_eq!(
        drawn.srgb, drawn.img,
        "{{colorSpace: 'srgb'}} is the default"
    );
    assert_eq!(
        differences(&drawn.raw, &codes),
        (0, 0, 0),
        "colorSpaceConversion 'none'"
    );
    // The linear sphere (render --bit-depth 8): each code goes through the same table, upright.
    let table = &drawn.img;
    let (file, drawn) = m.get("linear.png");
    assert_eq!((file.bits, file.gama), (8, Some(100_000)));
    let codes = high_byte(file);
    let through: Vec<i32> = codes
        .iter()
        .map(|&c| i32::from(table[c as usize]))
        .collect();
    assert_eq!(differences(&drawn.img, &through), (0, 0, 0));
    let (changed, rise, _) = differences(&drawn.img, &codes);
    eprintln!(
        "linear.png: {changed} of {} codes changed, up to +{rise}",
        codes.len()
    );
    assert!(changed > codes.len() / 4, "{changed} changed");
    assert_eq!(differences(&drawn.raw, &codes), (0, 0, 0));
    let w = drawn.width;
    let (top, bottom) = (
        mean_rows(&drawn.img, w, 0, drawn.height / 3),
        mean_rows(&drawn.img, w, drawn.height - drawn.height / 3, drawn.height),
    );
    assert!(top > bottom + 20.0, "top {top:.1}, bottom {bottom:.1}");
}

#[test]
fn other_gammas_are_converted_to_srgb_and_16_bit_files_keep_their_high_byte() {
    let Some(m) = measured() else { return };
    // gAMA 1/2.4 and 1/1.8: the codes are taken as light = code^γ and re-encoded in sRGB.
    for (name, gamma, changed_at_least) in [("ramp-2.4.png", 2.4, 240), ("ramp-1.8.png", 1.8, 240)]
    {
        let (file, drawn) = m.get(name);
        let model: Vec<i32> = (0..=255)
            .map(|c| srgb_code((f64::from(c) / 255.0).powf(gamma)))
            .collect();
        let (n, above, below) = differences(&drawn.img, &model);
        let (changed, rise, fall) = differences(&drawn.img, &high_byte(file));
        eprintln!(
            "{name}: {changed} of 256 codes changed, by {fall}..{rise}; {n} differ from round(255 sRGB(v^{gamma})) by {below}..{above}"
        );
        assert!(above <= 1 && below >= -1, "{name}: {below}..{above}");
        assert!(changed >= changed_at_least, "{name}: {changed} changed");
        assert_eq!(differences(&drawn.raw, &high_byte(file)), (0, 0, 0));
    }
    // 16 bits, gAMA 1/2.2: the high byte of each code, exactly (truncated, not rounded), and
    // within 1 of the 8-bit file's code.
    let (file, drawn) = m.get("gamma16.png");
    assert_eq!((file.bits, file.gama), (16, Some(45_455)));
    let high = high_byte(file);
    assert_eq!(differences(&drawn.img, &high), (0, 0, 0));
    assert_eq!(differences(&drawn.raw, &high), (0, 0, 0));
    let eight = high_byte(m.get("gamma.png").0);
    let (n, above, below) = differences(&drawn.img, &eight);
    eprintln!(
        "gamma16.png: {n} of {} canvas codes differ from the 8-bit file's, by {below}..{above}",
        eight.len()
    );
    assert!(above <= 1 && below >= -1, "{below}..{above}");
    // 16 bits, gAMA 1.0: the high byte, through the same table as an 8-bit linear file.
    let table = &m.get("ramp-linear.png").1.img;
    let (file, drawn) = m.get("linear16.png");
    assert_eq!((file.bits, file.gama), (16, Some(100_000)));
    let high = high_byte(file);
    let through: Vec<i32> = high.iter().map(|&c| i32::from(table[c as usize])).collect();
    assert_eq!(differences(&drawn.img, &through), (0, 0, 0));
    assert_eq!(differences(&drawn.raw, &high), (0, 0, 0));
}

#[test]
fn the_experiment_images_and_their_background_reach_the_canvas_unchanged() {
    let Some(m) = measured() else { return };
    for theta in ["000", "090", "180", "270"] {
        let name = format!("e/images/theta-{theta}.png");
        let (file, drawn) = m.get(&name);
        assert_eq!((file.bits, file.gama), (8, Some(45_455)), "{name}");
        let codes = high_byte(file);
        for (how, got) in [
            ("img", &drawn.img),
            ("srgb", &drawn.srgb),
            ("raw", &drawn.raw),
        ] {
            assert_eq!(differences(got, &codes), (0, 0, 0), "{name}, {how}");
        }
        // The page's CSS background (sRGB, as CSS colours are) is the image's edge code.
        assert_eq!(drawn.img[0], m.background, "{name}: top-left code");
    }
}
