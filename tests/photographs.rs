//! Photographs as they are (issue 39): an 8-bit picture without a gamma chunk, a JPEG and a
//! TIFF, read by the default rule and as `--input-gamma` says (docs/display.md, "Photographs
//! and other pictures").

use crate::cli::{assert_error, scratch, shadelab};
use shadelab::DEFAULT_MAX_PIXELS as MAX;
use shadelab_io::{self as io, InputEncoding};
use std::path::Path;

/// IEC 61966-2-1: the linear value of an sRGB code scaled to 0..1.
fn srgb(v: f64) -> f64 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// An 8-bit gray PNG of one row of `codes`, by the `png` crate, with what `chunks` adds.
fn png8(path: &Path, codes: &[u8], chunks: impl FnOnce(&mut png::Encoder<'_, std::fs::File>)) {
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = png::Encoder::new(file, codes.len() as u32, 1);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    chunks(&mut encoder);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(codes).unwrap();
    writer.finish().unwrap();
}

const CODES: [u8; 7] = [0, 10, 64, 128, 200, 250, 255];

/// The note the one reading of the picture at `path` makes where its codes were taken as sRGB
/// by the default rule.
fn note_of(path: &std::path::Path, encoding: InputEncoding) -> Option<String> {
    io::read_picture(path, MAX, encoding, false)
        .unwrap()
        .assumed_srgb
}

#[test]
fn an_untagged_8_bit_png_is_srgb_by_default_and_as_said_otherwise() {
    let d = scratch("photo-png8");
    let p = d.join("photo.png");
    png8(&p, &CODES, |_| {});
    let scaled = CODES.map(|c| f64::from(c) / 255.0);

    // Auto: sRGB, said in the conversion and in the note.
    let (auto, info) = io::read_gray(&p, MAX).unwrap();
    for (got, v) in auto.data().iter().zip(scaled) {
        assert!((got - srgb(v)).abs() < 1e-12, "{got} vs {}", srgb(v));
    }
    assert!(
        (auto.get(3, 0) - 0.215861).abs() < 1e-6,
        "{}",
        auto.get(3, 0)
    );
    let conversion = info.conversion.unwrap();
    assert!(conversion.contains("decoded as sRGB"), "{conversion}");
    let note = note_of(&p, InputEncoding::Auto).unwrap();
    assert!(
        note.starts_with(&format!("{}: 8-bit picture", p.display())),
        "{note}"
    );
    assert!(note.contains("--input-gamma linear"), "{note}");
    // The same through read_luminance, with the conversion in its report.
    let (lum, info) = io::read_luminance(&p, MAX).unwrap();
    assert_eq!(lum.data(), auto.data());
    assert!(
        info["conversion"].as_str().unwrap().contains("sRGB"),
        "{info}"
    );

    // Linear: the codes over 255, exactly, and nothing said.
    let (linear, info) = io::read_gray_as(&p, MAX, InputEncoding::Linear).unwrap();
    assert_eq!(linear.data(), &scaled[..]);
    assert_eq!(info.conversion, None);
    assert_eq!(note_of(&p, InputEncoding::Linear), None);

    // Gamma 2.2: luminance = code^2.2.
    let (gamma, info) = io::read_gray_as(&p, MAX, InputEncoding::Gamma(2.2)).unwrap();
    for (got, v) in gamma.data().iter().zip(scaled) {
        assert!(
            (got - v.powf(2.2)).abs() < 1e-12,
            "{got} vs {}",
            v.powf(2.2)
        );
    }
    assert!(info.conversion.unwrap().contains("code^2.2"));

    // RGB reads decode each channel the same way.
    let rgb = io::read_rgb_as(&p, MAX, InputEncoding::Gamma(2.2)).unwrap();
    // (through the image crate's 32-bit floats)
    assert!((rgb.get(3, 0)[1] - gamma.get(3, 0)).abs() < 1e-7);
    assert!((io::read_rgb(&p, MAX).unwrap().get(3, 0)[0] - auto.get(3, 0)).abs() < 1e-7);
}

#[test]
fn a_chunk_a_shadelab_text_or_sidecar_or_16_bits_keep_the_codes_linear_by_default() {
    let d = scratch("photo-kept");
    let scaled = CODES.map(|c| f64::from(c) / 255.0);
    // A gAMA chunk of 1 (as shadelab writes): linear; an explicit encoding overrides it.
    let tagged = d.join("tagged.png");
    png8(&tagged, &CODES, |e| {
        e.set_source_gamma(png::ScaledFloat::from_scaled(100_000))
    });
    let (image, info) = io::read_gray(&tagged, MAX).unwrap();
    assert_eq!(image.data(), &scaled[..]);
    assert_eq!(info.conversion, None);
    assert_eq!(note_of(&tagged, InputEncoding::Auto), None);
    let (image, info) = io::read_gray_as(&tagged, MAX, InputEncoding::Srgb).unwrap();
    assert!((image.get(3, 0) - 0.215861).abs() < 1e-6);
    let conversion = info.conversion.unwrap();
    assert!(
        conversion.contains("overriding the file's gAMA chunk (1)"),
        "{conversion}"
    );

    // shadelab's own text chunk, without gAMA: linear.
    let text = d.join("text.png");
    png8(&text, &CODES, |e| {
        e.add_itxt_chunk("Software".into(), "shadelab 0.1.0".into())
            .unwrap()
    });
    assert_eq!(io::read_gray(&text, MAX).unwrap().0.data(), &scaled[..]);
    // Another program's: sRGB.
    let other = d.join("other.png");
    png8(&other, &CODES, |e| {
        e.add_itxt_chunk("Software".into(), "GIMP 2.10".into())
            .unwrap()
    });
    assert!((io::read_gray(&other, MAX).unwrap().0.get(3, 0) - 0.215861).abs() < 1e-6);

    // A shadelab sidecar beside it (a render from before the gAMA chunk): linear.
    let old = d.join("old.png");
    png8(&old, &CODES, |_| {});
    std::fs::write(d.join("old.json"), r#"{"program": "shadelab"}"#).unwrap();
    assert_eq!(io::read_gray(&old, MAX).unwrap().0.data(), &scaled[..]);
    assert_eq!(note_of(&old, InputEncoding::Auto), None);

    // 16 bits without a chunk: scientific data, linear.
    let deep = d.join("deep.png");
    let codes16: Vec<u16> = vec![0, 1000, 32768, 65535];
    let file = std::fs::File::create(&deep).unwrap();
    let mut encoder = png::Encoder::new(file, 4, 1);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Sixteen);
    let bytes: Vec<u8> = codes16.iter().flat_map(|c| c.to_be_bytes()).collect();
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(&bytes).unwrap();
    writer.finish().unwrap();
    let (image, info) = io::read_gray(&deep, MAX).unwrap();
    let want: Vec<f64> = codes16.iter().map(|&c| f64::from(c) / 65535.0).collect();
    assert_eq!(image.data(), &want[..]);
    assert_eq!(info.conversion, None);
}

#[test]
fn an_input_gamma_outside_its_range_and_a_float_npy_with_a_gamma_are_refused() {
    for bad in ["0", "0.05", "10.5", "nan", "inf", "-2", "gamma"] {
        let e = bad.parse::<InputEncoding>().unwrap_err().to_string();
        assert!(e.contains("auto, srgb") && !e.contains('\n'), "{bad}: {e}");
    }
    assert_eq!(
        "0.1".parse::<InputEncoding>().unwrap(),
        InputEncoding::Gamma(0.1)
    );
    assert_eq!(
        "10".parse::<InputEncoding>().unwrap(),
        InputEncoding::Gamma(10.0)
    );
    assert!(InputEncoding::Gamma(0.0).validate().is_err());

    let d = scratch("photo-npy");
    // uint8 .npy: divided by 255, then decoded as said; float .npy: linear only.
    npy(&d.join("u8.npy"), "|u1", &CODES);
    let values: Vec<u8> = CODES
        .iter()
        .flat_map(|&c| (f64::from(c) / 255.0).to_le_bytes())
        .collect();
    npy(&d.join("f8.npy"), "<f8", &values);
    let (image, info) =
        io::read_luminance_as(&d.join("u8.npy"), MAX, InputEncoding::Gamma(2.2)).unwrap();
    for (got, c) in image.data().iter().zip(CODES) {
        assert!((got - (f64::from(c) / 255.0).powf(2.2)).abs() < 1e-12);
    }
    assert!(
        info["conversion"].as_str().unwrap().contains("code^2.2"),
        "{info}"
    );
    let (auto, _) = io::read_luminance(&d.join("u8.npy"), MAX).unwrap();
    let (float, _) = io::read_luminance(&d.join("f8.npy"), MAX).unwrap();
    assert_eq!(auto.data(), float.data());
    let (float, _) = io::read_luminance_as(&d.join("f8.npy"), MAX, InputEncoding::Linear).unwrap();
    assert_eq!(auto.data(), float.data());
    let e = io::read_luminance_as(&d.join("f8.npy"), MAX, InputEncoding::Srgb)
        .unwrap_err()
        .to_string();
    assert!(e.contains("f8.npy") && e.contains("float .npy"), "{e}");

    // Another extension: the error lists those read.
    std::fs::write(d.join("a.bmp"), b"BM").unwrap();
    let e = io::read_luminance(&d.join("a.bmp"), MAX)
        .unwrap_err()
        .to_string();
    for ext in [".png", ".npy", ".jpg", ".jpeg", ".tif", ".tiff", "'.bmp'"] {
        assert!(e.contains(ext), "{ext} not in {e}");
    }
}

/// Writes an H=1 × W `.npy` of `dtype` holding `data` (little-endian bytes).
fn npy(path: &Path, dtype: &str, data: &[u8]) {
    let size = dtype[2..].parse::<usize>().unwrap();
    let mut header = format!(
        "{{'descr': '{dtype}', 'fortran_order': False, 'shape': (1, {}), }}",
        data.len() / size
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    bytes.extend(data);
    std::fs::write(path, bytes).unwrap();
}

/// A 64×48 gray gradient (codes 30..219) as a JPEG at quality 100, by the `image` crate.
#[cfg(feature = "photos")]
fn jpeg(path: &Path) -> Vec<u8> {
    let codes: Vec<u8> = (0..48)
        .flat_map(|r| (0..64).map(move |c| (30 + 3 * c + r / 16) as u8))
        .collect();
    let mut bytes = Vec::new();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
        .encode(&codes, 64, 48, image::ExtendedColorType::L8)
        .unwrap();
    std::fs::write(path, &bytes).unwrap();
    codes
}

#[cfg(feature = "photos")]
#[test]
fn a_jpeg_is_decoded_as_srgb_within_its_compression_error() {
    let d = scratch("photo-jpeg");
    let p = d.join("photo.jpg");
    let codes = jpeg(&p);
    let mean = |v: &mut dyn Iterator<Item = f64>| {
        let (sum, n) = v.fold((0.0, 0), |(s, n), x| (s + x, n + 1));
        sum / f64::from(n)
    };
    let want_srgb = mean(&mut codes.iter().map(|&c| srgb(f64::from(c) / 255.0)));
    let want_linear = mean(&mut codes.iter().map(|&c| f64::from(c) / 255.0));
    let (image, info) = io::read_luminance(&p, MAX).unwrap();
    assert_eq!((image.width(), image.height()), (64, 48));
    let got = mean(&mut image.data().iter().copied());
    // Quality 100 keeps the codes within about one step: the means within 1e-3, while sRGB
    // and linear readings of these codes differ by 0.17.
    assert!((got - want_srgb).abs() < 1e-3, "{got} vs {want_srgb}");
    assert!((want_linear - want_srgb).abs() > 0.1);
    for (got, &c) in image.data().iter().zip(&codes) {
        let want = srgb(f64::from(c) / 255.0);
        assert!((got - want).abs() < 0.02, "{got} vs {want}");
    }
    assert!(
        info["conversion"]
            .as_str()
            .unwrap()
            .contains("decoded as sRGB"),
        "{info}"
    );
    assert!(note_of(&p, InputEncoding::Auto).is_some());
    // Linear: the codes over 255.
    let (image, _) = io::read_luminance_as(&p, MAX, InputEncoding::Linear).unwrap();
    let got = mean(&mut image.data().iter().copied());
    assert!((got - want_linear).abs() < 1e-3, "{got} vs {want_linear}");

    // A colour JPEG becomes the luminance of its decoded channels.
    let mut bytes = Vec::new();
    let pixels: Vec<u8> = (0..16 * 16).flat_map(|_| [200u8, 100, 50]).collect();
    image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 100)
        .encode(&pixels, 16, 16, image::ExtendedColorType::Rgb8)
        .unwrap();
    std::fs::write(d.join("colour.jpeg"), &bytes).unwrap();
    let (image, _) = io::read_luminance(&d.join("colour.jpeg"), MAX).unwrap();
    let want =
        0.2126 * srgb(200.0 / 255.0) + 0.7152 * srgb(100.0 / 255.0) + 0.0722 * srgb(50.0 / 255.0);
    let got = mean(&mut image.data().iter().copied());
    assert!((got - want).abs() < 0.01, "{got} vs {want}");
}

#[cfg(feature = "photos")]
#[test]
fn a_truncated_jpeg_is_a_one_line_error_naming_the_file() {
    let d = scratch("photo-truncated");
    jpeg(&d.join("whole.jpg"));
    let bytes = std::fs::read(d.join("whole.jpg")).unwrap();
    for (name, cut) in [("half.jpg", bytes.len() / 2), ("end.jpg", bytes.len() - 2)] {
        std::fs::write(d.join(name), &bytes[..cut]).unwrap();
        let e = io::read_luminance(&d.join(name), MAX)
            .unwrap_err()
            .to_string();
        assert!(e.contains(name) && e.contains("truncated"), "{e}");
    }
    // Not a JPEG at all, by its extension.
    std::fs::write(d.join("fake.jpg"), b"hello, this is text").unwrap();
    let e = io::read_luminance(&d.join("fake.jpg"), MAX)
        .unwrap_err()
        .to_string();
    assert!(e.contains("fake.jpg") && e.contains("not a JPEG"), "{e}");
    let out = shadelab(&d, &["solve", "half.jpg", "--light", "0,0,1", "--out", "o"]);
    assert_error(&out, 1, "half.jpg");
    assert!(!d.join("o").exists());
}

#[cfg(feature = "photos")]
#[test]
fn a_16_bit_tiff_reads_back_exactly_linear() {
    use image::{ImageBuffer, Luma, Rgb};
    let d = scratch("photo-tiff");
    let gray: ImageBuffer<Luma<u16>, Vec<u16>> =
        ImageBuffer::from_fn(40, 30, |c, r| Luma([(c * 1500 + r * 37) as u16]));
    gray.save(d.join("gray.tif")).unwrap();
    let (image, info) = io::read_luminance(&d.join("gray.tif"), MAX).unwrap();
    assert_eq!((image.width(), image.height()), (40, 30));
    for (got, code) in image.data().iter().zip(gray.as_raw()) {
        assert_eq!(*got, f64::from(*code) / 65535.0);
    }
    let conversion = info["conversion"].as_str().unwrap();
    assert!(
        conversion.contains("TIFF has no gamma chunk"),
        "{conversion}"
    );
    assert_eq!(note_of(&d.join("gray.tif"), InputEncoding::Auto), None);
    // With a gamma: code^G.
    let (image, _) =
        io::read_luminance_as(&d.join("gray.tif"), MAX, InputEncoding::Gamma(2.0)).unwrap();
    assert_eq!(
        *image.get(5, 7),
        (f64::from(*gray.get_pixel(5, 7).0.first().unwrap()) / 65535.0).powi(2)
    );
    // 16-bit RGB: linear channels, exactly.
    let rgb: ImageBuffer<Rgb<u16>, Vec<u16>> = ImageBuffer::from_fn(8, 4, |c, r| {
        Rgb([(c * 8000) as u16, (r * 9000) as u16, 65535])
    });
    rgb.save(d.join("rgb.tiff")).unwrap();
    let read = io::read_rgb(&d.join("rgb.tiff"), MAX).unwrap();
    for r in 0..4 {
        for c in 0..8 {
            let want = rgb.get_pixel(c, r).0.map(|v| f64::from(v) / 65535.0);
            let got = read.get(c as usize, r as usize);
            for k in 0..3 {
                assert!((got[k] - want[k]).abs() < 1e-7, "{got:?} vs {want:?}");
            }
        }
    }
}

#[cfg(feature = "photos")]
#[test]
fn solve_says_once_that_a_jpeg_is_decoded_as_srgb_and_refuses_a_bad_input_gamma() {
    let d = scratch("photo-cli");
    jpeg(&d.join("photo.jpg"));
    let out = shadelab(
        &d,
        &["solve", "photo.jpg", "--light", "0,0,1", "--out", "o"],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let note = "note: photo.jpg: 8-bit picture without a gamma chunk decoded as sRGB";
    assert_eq!(err.matches(note).count(), 1, "{err}");
    let report = std::fs::read_to_string(d.join("o/report.json")).unwrap();
    assert!(report.contains("decoded as sRGB"), "{report}");
    // Linear said: no note, and the codes as they are.
    let out = shadelab(
        &d,
        &[
            "solve",
            "photo.jpg",
            "--light",
            "0,0,1",
            "--input-gamma",
            "linear",
            "--out",
            "l",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success() && !err.contains("note:"), "{err}");
    // An analysis says it once too.
    let out = shadelab(
        &d,
        &[
            "analyze",
            "lightness",
            "photo.jpg",
            "--model",
            "odog",
            "--ppd",
            "5",
            "--out",
            "a",
        ],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert_eq!(err.matches(note).count(), 1, "{err}");
    // A gamma outside 0.1..10: a usage error naming the flag, before anything is read.
    for args in [
        &[
            "solve",
            "photo.jpg",
            "--light",
            "0,0,1",
            "--input-gamma",
            "0",
            "--out",
            "z",
        ][..],
        &[
            "analyze",
            "lightness",
            "photo.jpg",
            "--model",
            "odog",
            "--input-gamma",
            "11",
            "--out",
            "z",
        ][..],
    ] {
        let out = shadelab(&d, args);
        assert_error(&out, 2, "--input-gamma");
    }
    assert!(!d.join("z").exists());
}
