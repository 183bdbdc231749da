//! Hostile input for every command: broken, odd and oversized images, arrays, meshes and specs,
//! bad numbers and names, non-UTF-8 paths and outputs that cannot or must not be written. Each
//! refusal exits 1 or 2 with one `error: ` line naming the file or flag and the problem, never
//! panics, and leaves the folder exactly as it was (no output, no temporary file, no foreign
//! file touched). The odd inputs that are valid (RGBA, palette, 16-bit, 1×1, non-UTF-8 names)
//! must work.

use super::cli::{assert_error, scratch, shadelab};
use std::collections::hash_map::DefaultHasher;
use std::ffi::{OsStr, OsString};
use std::hash::{Hash, Hasher};
use std::os::unix::ffi::OsStrExt;
use std::path::Path;
use std::process::{Command, Output};

// ---------------------------------------------------------------------------------------------
// Files written by hand, so that they can say what an encoder would refuse to.

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A zlib stream of stored (uncompressed) deflate blocks.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = if data.is_empty() {
        vec![&[]]
    } else {
        data.chunks(65_535).collect()
    };
    for (i, block) in blocks.iter().enumerate() {
        out.push(u8::from(i + 1 == blocks.len()));
        let len = block.len() as u16;
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &x in data {
        a = (a + x as u32) % 65_521;
        b = (b + a) % 65_521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
}

/// A PNG of any size, colour type and bit depth; `rows` are the unfiltered scanlines.
fn png(
    width: u32,
    height: u32,
    bit_depth: u8,
    colour: u8,
    palette: Option<&[u8]>,
    rows: &[Vec<u8>],
) -> Vec<u8> {
    fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
    }
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[bit_depth, colour, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    if let Some(p) = palette {
        chunk(&mut out, b"PLTE", p);
    }
    let raw: Vec<u8> = rows
        .iter()
        .flat_map(|r| std::iter::once(0u8).chain(r.iter().copied()))
        .collect();
    chunk(&mut out, b"IDAT", &zlib_stored(&raw));
    chunk(&mut out, b"IEND", &[]);
    out
}

/// 16×16 scanlines of `channels` samples of `bytes` each (big-endian), a smooth ramp.
fn ramp_rows(channels: usize, bytes: usize) -> Vec<Vec<u8>> {
    (0..16)
        .map(|r| {
            (0..16)
                .flat_map(|c| {
                    (0..channels).flat_map(move |k| {
                        let v = (40 + 8 * c + 4 * r + 10 * k) as u16;
                        if bytes == 2 {
                            (v * 257).to_be_bytes().to_vec()
                        } else {
                            vec![v as u8]
                        }
                    })
                })
                .collect()
        })
        .collect()
}

/// A `.npy` file with a header of our choosing over `data`.
fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

fn f64s(values: impl IntoIterator<Item = f64>) -> Vec<u8> {
    values.into_iter().flat_map(f64::to_le_bytes).collect()
}

const PLY_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
    property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n\
    end_header\n";

/// Every input file of the cases, under `dir/in/`, and the output-side obstacles in `dir`.
fn fixtures(dir: &Path) {
    let i = dir.join("in");
    std::fs::create_dir_all(&i).unwrap();
    let put = |name: &str, bytes: &[u8]| std::fs::write(i.join(name), bytes).unwrap();
    let dir_in = |name: &str| std::fs::create_dir_all(i.join(name)).unwrap();
    // A mesh over the 1 GiB read limit (sparse: no disk used): refused by its length.
    std::fs::File::create(i.join("huge.ply"))
        .unwrap()
        .set_len(shadelab_engine::surface::MAX_MESH_BYTES + 1)
        .unwrap();

    // Images.
    let ok = png(16, 16, 8, 0, None, &ramp_rows(1, 1));
    put("ok.png", &ok);
    put("trunc.png", &ok[..ok.len() / 2]);
    put("corrupt.png", b"\x89PNG\r\n\x1a\n this is not a chunk");
    put("empty.png", b"");
    dir_in("dir.png");
    put("zero.png", &png(0, 0, 8, 0, None, &[]));
    put("one.png", &png(1, 1, 8, 0, None, &[vec![128]]));
    // 10^10 pixels declared over a body of a few bytes.
    put(
        "bomb.png",
        &png(100_000, 100_000, 8, 0, None, &[vec![0; 16]]),
    );
    put("rgba.png", &png(16, 16, 8, 6, None, &ramp_rows(4, 1)));
    let palette: Vec<u8> = (0..=255u8).flat_map(|v| [v, v / 2, 255 - v]).collect();
    put(
        "palette.png",
        &png(16, 16, 8, 3, Some(&palette), &ramp_rows(1, 1)),
    );
    put("gray16.png", &png(16, 16, 16, 0, None, &ramp_rows(1, 2)));
    put("rgb16.png", &png(16, 16, 16, 2, None, &ramp_rows(3, 2)));
    put("graya16.png", &png(16, 16, 16, 4, None, &ramp_rows(2, 2)));
    put("mask8.png", &png(8, 8, 8, 0, None, &vec![vec![255; 8]; 8]));
    put(
        "mask_empty.png",
        &png(16, 16, 8, 0, None, &vec![vec![0; 16]; 16]),
    );
    let halves: Vec<Vec<u8>> = (0..16).map(|r| vec![1 + u8::from(r >= 8); 16]).collect();
    put("labels12.png", &png(16, 16, 8, 0, None, &halves));
    std::fs::write(i.join(OsStr::from_bytes(b"caf\xe9.png")), &ok).unwrap();

    // Arrays.
    let bump = f64s((0..256).map(|k| {
        let (c, r) = ((k % 16) as f64 - 7.5, (k / 16) as f64 - 7.5);
        (20.0 - (c * c + r * r) / 4.0).max(0.0)
    }));
    put("ok.npy", &npy("<f8", "(16, 16)", &bump));
    let luminance = f64s((0..256).map(|k| 0.2 + 0.002 * k as f64));
    put("luminance.npy", &npy("<f8", "(16, 16)", &luminance));
    put("complex.npy", &npy("<c16", "(16, 16)", &[0; 16 * 256]));
    put("text.npy", &npy("<U2", "(2,)", &[0; 16]));
    put("rank1.npy", &npy("<f8", "(16,)", &f64s([1.0; 16])));
    put("rank3.npy", &npy("<f8", "(16, 16, 2)", &f64s([1.0; 512])));
    let with = |bad: f64| f64s((0..256).map(move |k| if k == 52 { bad } else { 1.0 }));
    put("nan.npy", &npy("<f8", "(16, 16)", &with(f64::NAN)));
    put("inf.npy", &npy("<f8", "(16, 16)", &with(f64::INFINITY)));
    put("zeros.npy", &npy("<f8", "(16, 16)", &f64s([0.0; 256])));
    put("huge.npy", &npy("<f8", "(100000, 100000)", &[]));
    put("short.npy", &npy("<f8", "(16, 16)", &[0; 10]));
    put("empty.npy", b"");
    let normals = |n: usize, v: f64| f64s(vec![v; n * n * 3]);
    put("normals8.npy", &npy("<f8", "(8, 8, 3)", &normals(8, 1.0)));
    put(
        "normals_zero.npy",
        &npy("<f8", "(16, 16, 3)", &normals(16, 0.0)),
    );
    let mut nan_normals = normals(16, 1.0);
    nan_normals[24..32].copy_from_slice(&f64::NAN.to_le_bytes());
    put("normals_nan.npy", &npy("<f8", "(16, 16, 3)", &nan_normals));

    // Meshes.
    put("tri.obj", b"v -1 -1 0\nv 1 -1 0\nv 0 1 0.5\nf 1 2 3\n");
    put(
        "oor.ply",
        format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n").as_bytes(),
    );
    put(
        "nan.ply",
        format!("{PLY_HEAD}0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n").as_bytes(),
    );
    put(
        "degenerate.ply",
        format!("{PLY_HEAD}0 0 0\n1 0 0\n0 1 0\n3 0 1 1\n").as_bytes(),
    );
    put(
        "lying.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n\
          property float y\nproperty float z\nelement face 1\n\
          property list uchar int vertex_indices\nend_header\n\x00\x00",
    );
    put("oor.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    put("nan.obj", b"v 0 0 0\nv NaN 0 0\nv 0 1 0\nf 1 2 3\n");
    put("inf.obj", b"v 0 0 0\nv 0 inf 0\nv 0 1 0\nf 1 2 3\n");
    put("two_corners.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
    put("degenerate.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\n");
    put("collinear.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    put("zero_index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    put("empty.ply", b"");
    put("empty.obj", b"");
    put("model.stl", b"solid x\nendsolid x\n");
    dir_in("dir.ply");

    // Specs.
    put("truncated.json", br#"{"stimulus": "sphere", "#);
    put(
        "unknown_key.json",
        br#"{"stimulus": "sphere", "colour": 3}"#,
    );
    put("wrong_type.json", br#"{"stimulus": 3}"#);
    put("nan.json", br#"{"stimulus": "sphere", "ppd": NaN}"#);
    put("empty.json", b"");
    dir_in("dir.json");
    put("teapot.json", br#"{"stimulus": "teapot"}"#);
    put(
        "huge_spec.json",
        br#"{"stimulus": "sphere", "shape": [100000, 100000]}"#,
    );
    put(
        "bad_param.json",
        br#"{"stimulus": "sphere", "params": {"radius": -1}}"#,
    );
    let study = |name: &str, text: &str| put(name, text.as_bytes());
    study("study.json", STUDY);
    study(
        "study_unknown.json",
        r#"{"stimuli": [{"stimulus": "bumps"}], "prior": {}}"#,
    );
    study(
        "study_unknown_entry.json",
        r#"{"stimuli": [{"stimulus": "bumps", "colour": 1}]}"#,
    );
    study(
        "study_unknown_prior.json",
        r#"{"stimuli": [{"stimulus": "bumps"}], "priors": {"sigma": [1]}}"#,
    );
    study(
        "study_teapot.json",
        r#"{"stimuli": [{"stimulus": "teapot"}]}"#,
    );
    study("study_none.json", r#"{"stimuli": []}"#);
    study(
        "study_huge.json",
        r#"{"stimuli": [{"stimulus": "bumps", "shape": [100000, 100000]}]}"#,
    );
    study(
        "study_noise.json",
        r#"{"stimuli": [{"stimulus": "bumps"}], "noise": -1}"#,
    );
    study(
        "study_slant.json",
        r#"{"stimuli": [{"stimulus": "bumps"}], "slants": [90]}"#,
    );
    study(
        "study_tilts.json",
        r#"{"stimuli": [{"stimulus": "bumps"}], "tilts": "0:180:5"}"#,
    );
    study(
        "study_shape.json",
        r#"{"stimuli": [{"stimulus": "bumps", "shape": [-1, 24]}]}"#,
    );
    let preset_dir = |name: &str, file: &str, text: &str| {
        dir_in(name);
        std::fs::write(i.join(name).join(file), text).unwrap();
    };
    preset_dir(
        "presets_ok",
        "sphere.json",
        r#"{"stimulus": "sphere", "shape": [8, 8]}"#,
    );
    dir_in("presets_empty");
    preset_dir("presets_truncated", "a.json", r#"{"stimulus": "#);
    preset_dir(
        "presets_unknown",
        "a.json",
        r#"{"stimulus": "sphere", "colour": 1}"#,
    );
    preset_dir("presets_teapot", "a.json", r#"{"stimulus": "teapot"}"#);
    preset_dir(
        "presets_huge",
        "a.json",
        r#"{"stimulus": "sphere", "shape": [100000, 100000]}"#,
    );
    preset_dir(
        "presets_bad_name",
        "a b.json",
        r#"{"stimulus": "sphere", "shape": [8, 8]}"#,
    );

    // Output-side obstacles: a regular file, a folder and files of someone else's.
    std::fs::write(dir.join("afile"), "not a folder").unwrap();
    std::fs::create_dir_all(dir.join("foreign")).unwrap();
    std::fs::write(dir.join("foreign/holiday.jpg"), "x").unwrap();
    std::fs::create_dir_all(dir.join("fake")).unwrap();
    // Each command's marker file, but someone else's.
    for marker in [
        "report.json",
        "lightness.json",
        "sweep.json",
        "observer.json",
        "fading.json",
        "study.json",
        "evaluation.json",
    ] {
        std::fs::write(dir.join("fake").join(marker), r#"{"program": "darktable"}"#).unwrap();
    }
    std::fs::write(dir.join("fake/index.html"), "<html>my photos</html>").unwrap();
    std::fs::write(dir.join("foreign.png"), "precious").unwrap();
    std::fs::write(dir.join("photo.json"), r#"{"camera": "x"}"#).unwrap();
    std::fs::write(dir.join("shot_mask.png"), "precious").unwrap();
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
}

/// A study small enough to run in a moment: one bumps picture, four tilts, two slants.
const STUDY: &str = r#"{"stimuli": [{"stimulus": "bumps", "params": {"rows": 1, "columns": 1},
    "shape": [24, 24], "ppd": 12}], "tilts": "0:360:90", "slants": [30, 45]}"#;

// ---------------------------------------------------------------------------------------------
// Running and checking.

fn run_os(dir: &Path, args: &[OsString]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the shadelab binary runs")
}

fn words(line: &str) -> Vec<OsString> {
    line.split_whitespace().map(OsString::from).collect()
}

/// Files up to this size are compared by their bytes in [`tree`].
const HASHED_BYTES: u64 = 64 << 20;

/// Every path under `dir` (hidden ones included) with a hash of each file's bytes, or for a
/// file over [`HASHED_BYTES`] (the sparse 1 GiB mesh, which no command may touch) of its length
/// and modification time: reading it twice per case cost minutes of the suite.
fn tree(dir: &Path) -> Vec<(String, u64)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let name = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                out.push((name + "/", 0));
                stack.push(p);
            } else {
                let mut h = DefaultHasher::new();
                let meta = std::fs::metadata(&p).unwrap();
                if meta.len() > HASHED_BYTES {
                    (meta.len(), meta.modified().unwrap()).hash(&mut h);
                } else {
                    std::fs::read(&p).unwrap().hash(&mut h);
                }
                out.push((name, h.finish()));
            }
        }
    }
    out.sort();
    out
}

/// Runs `args` in `dir` and asserts a clean refusal that mentions every needle and leaves `dir`
/// exactly as it was.
fn refused(dir: &Path, args: &[OsString], needles: &[&str]) {
    let shown: Vec<String> = args
        .iter()
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let shown = shown.join(" ");
    let before = tree(dir);
    let out = run_os(dir, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        matches!(out.status.code(), Some(1 | 2)),
        "`{shown}`: exit {:?}, stderr: {err}",
        out.status.code()
    );
    assert!(!err.contains("panicked at"), "`{shown}`: {err}");
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        lines.len() == 1 && lines[0].starts_with("error: "),
        "`{shown}`: one `error: ` line expected, got: {err}"
    );
    for n in needles {
        assert!(lines[0].contains(n), "`{shown}`: '{n}' not in: {err}");
    }
    assert_eq!(tree(dir), before, "`{shown}` changed the folder");
}

/// Every case of a table: the command line (split at spaces) and what the error must say.
fn refused_all(dir: &Path, cases: &[(String, Vec<&str>)]) {
    for (line, needles) in cases {
        refused(dir, &words(line), needles);
    }
}

/// Runs `line` in `dir` and asserts success.
fn works(dir: &Path, line: &str) {
    let out = run_os(dir, &words(&format!("--quiet {line}")));
    assert!(
        out.status.success(),
        "`{line}`: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn cases(table: &[(&str, &[&'static str])]) -> Vec<(String, Vec<&'static str>)> {
    table
        .iter()
        .map(|(l, n)| (l.to_string(), n.to_vec()))
        .collect()
}

/// The commands that read one image, each with `{}` where the image goes and `{out}` where the
/// output goes.
const IMAGE_COMMANDS: &[&str] = &[
    "solve {} --light above --out o",
    "analyze lightness {} --model retinex --out o",
    "analyze prior-sweep {} --tilts 0:360:90 --out o",
    "analyze observer {} --tilts 0:360:90 --out o",
    "analyze fading {} --ppd 8 --mask in/labels12.png --out o",
];

/// Broken images and what the error says about them.
const BAD_IMAGES: &[(&str, &str)] = &[
    ("in/trunc.png", "cannot decode"),
    (
        "in/corrupt.png",
        "corrupt PNG: it does not begin with its header (IHDR) chunk",
    ),
    ("in/empty.png", "not a PNG image"),
    ("in/dir.png", "is a directory"),
    ("in/zero.png", "image size 0 px high × 0 px wide is empty"),
    (
        "in/bomb.png",
        "100000 px high × 100000 px wide exceeds the limit",
    ),
    ("in/missing.png", "No such file"),
    ("in/complex.npy", "unsupported dtype"),
    ("in/text.npy", "unsupported dtype"),
    ("in/rank1.npy", "expected a 2-D"),
    ("in/rank3.npy", "expected a 2-D"),
    ("in/nan.npy", "NaN"),
    ("in/inf.npy", "inf"),
    ("in/huge.npy", "exceeds the limit"),
    ("in/short.npy", "truncated"),
    ("in/empty.npy", "not a .npy"),
    ("in/model.stl", "must be a .png or .npy"),
];

#[test]
fn broken_images_are_refused_by_every_command_that_reads_one() {
    let d = scratch("hostile-images");
    fixtures(&d);
    let mut table = Vec::new();
    for command in IMAGE_COMMANDS {
        for (file, problem) in BAD_IMAGES {
            table.push((command.replace("{}", file), vec![*file, *problem]));
        }
        // The cap, lowered below a 16×16 picture.
        table.push((
            format!("{} --max-pixels 255", command.replace("{}", "in/ok.png")),
            vec!["in/ok.png", "exceeds the limit of 255"],
        ));
        // Raised, a bomb is still refused before anything is allocated: here by the memory
        // check (a machine with terabytes to spare would get to the decoder's own limit).
        table.push((
            format!(
                "{} --max-pixels 100000000000",
                command.replace("{}", "in/bomb.png")
            ),
            vec!["in/bomb.png", "100000 px high × 100000 px wide"],
        ));
    }
    refused_all(&d, &table);
    // A name that is not UTF-8 is shown lossily.
    for command in IMAGE_COMMANDS {
        let mut args = Vec::new();
        for w in command.split_whitespace() {
            args.push(if w == "{}" {
                OsStr::from_bytes(b"in/missing\xff.png").to_os_string()
            } else {
                OsString::from(w)
            });
        }
        refused(&d, &args, &["in/missing\u{fffd}.png", "No such file"]);
    }
}

#[test]
fn odd_but_valid_images_are_read_as_documented() {
    let d = scratch("hostile-odd-read");
    fixtures(&d);
    let i = d.join("in");
    let max = shadelab::DEFAULT_MAX_PIXELS;
    let value = |c: usize, r: usize, k: usize| (40 + 8 * c + 4 * r + 10 * k) as f64;
    // 16-bit gray: the codes over 65535, exactly.
    let (g, info) = shadelab_io::read_gray(&i.join("gray16.png"), max).unwrap();
    assert_eq!((info.bit_depth, info.channels), (16, 1));
    assert_eq!(*g.get(3, 5), value(3, 5, 0) * 257.0 / 65535.0);
    // Gray + alpha: the alpha is ignored.
    let (g, info) = shadelab_io::read_gray(&i.join("graya16.png"), max).unwrap();
    assert_eq!(info.channels, 2);
    assert_eq!(*g.get(7, 2), value(7, 2, 0) * 257.0 / 65535.0);
    // RGBA and 16-bit RGB: Rec. 709 luminance of the stored values, alpha ignored (read as
    // linear: by default an 8-bit picture without a gamma chunk is sRGB, tests/photographs.rs).
    let linear = shadelab::InputEncoding::Linear;
    for (file, scale) in [("rgba.png", 255.0), ("rgb16.png", 65535.0 / 257.0)] {
        let (y, _) = shadelab_io::read_gray_as(&i.join(file), max, linear).unwrap();
        let lum =
            (0.2126 * value(4, 9, 0) + 0.7152 * value(4, 9, 1) + 0.0722 * value(4, 9, 2)) / scale;
        assert!((y.get(4, 9) - lum).abs() < 1e-6, "{file}: {}", y.get(4, 9));
    }
    // Palette: the index looks up the colour.
    let rgb = shadelab_io::read_rgb_as(&i.join("palette.png"), max, linear).unwrap();
    let v = value(2, 3, 0);
    let expect = [v / 255.0, (v / 2.0).floor() / 255.0, (255.0 - v) / 255.0];
    for (got, want) in rgb.get(2, 3).iter().zip(expect) {
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
    }
    // 1×1.
    let (one, _) = shadelab_io::read_gray_as(&i.join("one.png"), max, linear).unwrap();
    assert_eq!(one.data(), &[128.0 / 255.0]);
}

#[test]
fn odd_but_valid_images_work_in_every_command() {
    let d = scratch("hostile-odd-run");
    fixtures(&d);
    let mut n = 0;
    for file in [
        "rgba.png",
        "palette.png",
        "gray16.png",
        "rgb16.png",
        "graya16.png",
        "luminance.npy",
    ] {
        for command in IMAGE_COMMANDS {
            n += 1;
            let out = format!("out{n}");
            works(
                &d,
                &command
                    .replace("{}", &format!("in/{file}"))
                    .replace("--out o", &format!("--out {out}")),
            );
            assert!(d.join(&out).is_dir());
        }
    }
    // A 1×1 picture can be solved and its lightness read.
    works(&d, "solve in/one.png --light above --out one_solve");
    works(
        &d,
        "analyze lightness in/one.png --model retinex --out one_light",
    );
    // Colour masks count any non-zero channel.
    works(
        &d,
        "solve in/ok.png --light above --mask in/rgba.png --out m",
    );
    // The cap, raised to exactly the picture.
    works(
        &d,
        "solve in/ok.png --light above --max-pixels 256 --out cap",
    );
    // A file whose name is not UTF-8 reads, and an output name that is not UTF-8 is written.
    let out = run_os(
        &d,
        &[
            "--quiet".into(),
            "solve".into(),
            OsStr::from_bytes(b"in/caf\xe9.png").into(),
            "--light".into(),
            "above".into(),
            "--out".into(),
            OsStr::from_bytes(b"r\xe9sultat").into(),
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d
        .join(OsStr::from_bytes(b"r\xe9sultat/report.json"))
        .is_file());
    let out = run_os(
        &d,
        &[
            "--quiet".into(),
            "render".into(),
            "sphere".into(),
            "--size".into(),
            "8".into(),
            "--out".into(),
            OsStr::from_bytes(b"sph\xe8re.png").into(),
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(d.join(OsStr::from_bytes(b"sph\xe8re.json")).is_file());
}

#[test]
fn broken_masks_boundaries_and_domains_are_refused() {
    let d = scratch("hostile-masks");
    fixtures(&d);
    let table = cases(&[
        // solve --mask
        (
            "solve in/ok.png --light above --mask in/mask8.png --out o",
            &[
                "in/mask8.png",
                "8 px high × 8 px wide",
                "16 px high × 16 px wide",
            ],
        ),
        (
            "solve in/ok.png --light above --mask in/mask_empty.png --out o",
            &["in/mask_empty.png", "empty"],
        ),
        (
            "solve in/ok.png --light above --mask in/trunc.png --out o",
            &["in/trunc.png", "decode"],
        ),
        (
            "solve in/ok.png --light above --mask in/bomb.png --out o",
            &["in/bomb.png", "exceeds"],
        ),
        (
            "solve in/ok.png --light above --mask in/dir.png --out o",
            &["in/dir.png", "directory"],
        ),
        (
            "solve in/ok.png --light above --mask in/empty.png --out o",
            &["in/empty.png", "not a PNG image"],
        ),
        // solve --boundary FILE.npy
        (
            "solve in/ok.png --light above --boundary in/normals8.npy --out o",
            &["in/normals8.npy", "8 px high × 8 px wide"],
        ),
        (
            "solve in/ok.png --light above --boundary in/normals_nan.npy --out o",
            &["in/normals_nan.npy", "NaN"],
        ),
        (
            "solve in/ok.png --light above --boundary in/normals_zero.npy --out o",
            &["in/normals_zero.npy", "zero"],
        ),
        (
            "solve in/ok.png --light above --boundary in/ok.npy --out o",
            &["in/ok.npy", "H×W×3"],
        ),
        (
            "solve in/ok.png --light above --boundary in/complex.npy --out o",
            &["in/complex.npy", "dtype"],
        ),
        (
            "solve in/ok.png --light above --boundary in/huge.npy --out o",
            &["in/huge.npy", "exceeds"],
        ),
        (
            "solve in/ok.png --light above --boundary in/missing.npy --out o",
            &["in/missing.npy", "No such file"],
        ),
        (
            "solve in/ok.png --light above --boundary wobbly --out o",
            &["--boundary", "wobbly"],
        ),
        // analyze: target labels
        (
            "analyze lightness in/ok.png --model retinex --mask in/mask8.png --out o",
            &["in/mask8.png", "8 px high × 8 px wide"],
        ),
        (
            "analyze lightness in/ok.png --model retinex --mask in/rgba.png --out o",
            &["in/rgba.png", "grayscale"],
        ),
        (
            "analyze lightness in/ok.png --model retinex --mask in/corrupt.png --out o",
            &["in/corrupt.png", "corrupt PNG"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/mask8.png --out o",
            &["in/mask8.png", "8 px high × 8 px wide"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/mask_empty.png --out o",
            &["no pixel labelled 1"],
        ),
        (
            "analyze prior-sweep in/ok.png --mask in/mask8.png --out o",
            &["in/mask8.png", "8 px high × 8 px wide"],
        ),
        (
            "analyze observer in/ok.png --mask in/bomb.png --out o",
            &["in/bomb.png", "exceeds"],
        ),
        (
            "analyze prior-sweep --stimulus bumps --mask in/mask8.png --out o",
            &["in/mask8.png", "8 px high × 8 px wide"],
        ),
        // analyze prior-sweep / observer: domain and boundary
        (
            "analyze prior-sweep in/ok.png --domain in/mask8.png --out o",
            &["domain mask in/mask8.png", "8 px high × 8 px wide"],
        ),
        (
            "analyze prior-sweep in/ok.png --domain in/mask_empty.png --out o",
            &["domain mask in/mask_empty.png", "empty"],
        ),
        (
            "analyze prior-sweep in/ok.png --domain in/ok.npy --out o",
            &["--domain", "in/ok.npy"],
        ),
        (
            "analyze observer in/ok.png --domain in/trunc.png --out o",
            &["in/trunc.png", "decode"],
        ),
        (
            "analyze prior-sweep in/ok.png --boundary in/normals8.npy --out o",
            &["in/normals8.npy", "8 px high × 8 px wide"],
        ),
        (
            "analyze observer in/ok.png --boundary in/normals_nan.npy --out o",
            &["in/normals_nan.npy", "NaN"],
        ),
        (
            "analyze prior-sweep in/ok.png --boundary in/rank1.npy --out o",
            &["in/rank1.npy", "H×W×3"],
        ),
    ]);
    refused_all(&d, &table);
}

#[test]
fn render_refuses_broken_depth_maps_meshes_and_specs() {
    let d = scratch("hostile-render-files");
    fixtures(&d);
    let mut table = Vec::new();
    for (file, problem) in [
        ("in/trunc.png", "not a .npy file"),
        ("in/complex.npy", "unsupported dtype"),
        ("in/text.npy", "unsupported dtype"),
        ("in/rank1.npy", "expected a 2-D"),
        ("in/rank3.npy", "expected a 2-D"),
        ("in/nan.npy", "NaN"),
        ("in/inf.npy", "inf"),
        ("in/zeros.npy", "empty"),
        ("in/huge.npy", "exceeds the limit"),
        ("in/short.npy", "truncated"),
        ("in/empty.npy", "not a .npy"),
        ("in/dir.png", "is a directory"),
        ("in/missing.npy", "No such file"),
    ] {
        table.push((
            format!("render heightfield --set path={file} --out o.png"),
            vec![file, problem],
        ));
    }
    for (file, problem) in [
        ("in/oor.ply", "out of range"),
        ("in/nan.ply", "NaN"),
        ("in/degenerate.ply", "no faces"),
        ("in/lying.ply", "cannot hold them"),
        ("in/oor.obj", "refers to vertex 9"),
        ("in/nan.obj", "NaN"),
        ("in/inf.obj", "infinite"),
        ("in/two_corners.obj", "at least 3 corners"),
        ("in/degenerate.obj", "no faces"),
        ("in/collinear.obj", "covers no pixel"),
        ("in/zero_index.obj", "start at 1"),
        ("in/empty.ply", "empty"),
        ("in/empty.obj", "no vertices"),
        ("in/model.stl", "unknown mesh format"),
        ("in/huge.ply", "is larger than 1 GiB"),
        ("in/dir.ply", "directory"),
        ("in/missing.ply", "No such file"),
    ] {
        table.push((
            format!("render mesh --set path={file} --size 16 --out o.png"),
            vec![file, problem],
        ));
    }
    for (file, problem) in [
        ("in/truncated.json", "bad stimulus spec"),
        ("in/unknown_key.json", "unknown field `colour`"),
        ("in/wrong_type.json", "invalid type"),
        ("in/nan.json", "bad stimulus spec"),
        ("in/empty.json", "bad stimulus spec"),
        ("in/dir.json", "is a directory"),
        ("in/missing.json", "No such file"),
    ] {
        table.push((
            format!("render --spec {file} --out o.png"),
            vec![file, problem],
        ));
    }
    table.extend(cases(&[
        (
            "render --spec in/teapot.json --out o.png",
            &["unknown stimulus 'teapot'"],
        ),
        (
            "render --spec in/huge_spec.json --out o.png",
            &["100000 px high × 100000 px wide", "--max-pixels"],
        ),
        (
            "render --spec in/bad_param.json --out o.png",
            &["radius", "outside"],
        ),
        (
            "render disc --spec in/unknown_key.json --out o.png",
            &["in/unknown_key.json", "colour"],
        ),
    ]));
    refused_all(&d, &table);
    // A parameter value that is not UTF-8 names the flag.
    let mut args = words("render heightfield --out o.png --set");
    args.push(OsStr::from_bytes(b"path=in/\xff.npy").into());
    refused(&d, &args, &["--set", "UTF-8"]);
    // The valid ones work: a depth map at its own size, a mesh, a spec.
    works(&d, "render heightfield --set path=in/ok.npy --out h.png");
    works(
        &d,
        "render mesh --set path=in/tri.obj --size 16 --out t.png",
    );
    std::fs::write(
        d.join("in/s.json"),
        r#"{"stimulus": "sphere", "shape": [8, 8]}"#,
    )
    .unwrap();
    works(&d, "render --spec in/s.json --out s.png");
}

#[test]
fn render_refuses_bad_numbers_names_and_sizes() {
    let d = scratch("hostile-render-numbers");
    fixtures(&d);
    let table = cases(&[
        ("render sphere --size -1 --out o.png", &["--size", "-1"]),
        (
            "render sphere --size 0 --out o.png",
            &["--size '0'", "both sides must be positive"],
        ),
        (
            "render sphere --size 0x5 --out o.png",
            &["--size '0x5'", "both sides must be positive"],
        ),
        (
            "render sphere --width 0 --height 5 --out o.png",
            &["--width 0 --height 5", "at least 1 pixel"],
        ),
        ("render sphere --size nan --out o.png", &["--size", "nan"]),
        (
            "render sphere --size 100000 --out o.png",
            &["100000 px high × 100000 px wide", "--max-pixels"],
        ),
        (
            "render sphere --size 18446744073709551615 --out o.png",
            &["--max-pixels"],
        ),
        (
            "render sphere --size 18446744073709551616 --out o.png",
            &["--size"],
        ),
        (
            "render sphere --size 16 --max-pixels 255 --out o.png",
            &["16 px high × 16 px wide", "255"],
        ),
        (
            "render sphere --set radius=-1 --out o.png",
            &["radius", "-1", "outside"],
        ),
        (
            "render sphere --set radius=nan --out o.png",
            &["radius", "NaN"],
        ),
        (
            "render sphere --set radius=inf --out o.png",
            &["radius", "inf"],
        ),
        (
            "render sphere --set radius=1e400 --out o.png",
            &["radius", "inf"],
        ),
        (
            "render sphere --set radius=big --out o.png",
            &["radius", "big"],
        ),
        (
            "render sphere --set size=-1 --out o.png",
            &["unknown parameter 'size'"],
        ),
        ("render sphere --set radius --out o.png", &["radius"]),
        ("render sphere --ppd nan --out o.png", &["ppd", "NaN"]),
        ("render sphere --ppd inf --out o.png", &["ppd", "inf"]),
        ("render sphere --ppd -1 --out o.png", &["ppd", "-1"]),
        ("render sphere --ppd 0 --out o.png", &["ppd", "0"]),
        (
            "render sphere --visual-size inf --out o.png",
            &["visual size", "inf"],
        ),
        (
            "render sphere --visual-size -2 --out o.png",
            &["--visual-size '-2'", "both sides must be positive"],
        ),
        (
            "render sphere --visual-size 1e300 --ppd 1e300 --out o.png",
            &["inf"],
        ),
        ("render sphere --gamma nan --out o.png", &["gamma", "NaN"]),
        ("render sphere --gamma 0 --out o.png", &["gamma", "0"]),
        ("render sphere --gamma -1 --out o.png", &["gamma", "-1"]),
        (
            "render sphere --bit-depth 12 --out o.png",
            &["--bit-depth", "12"],
        ),
        ("render sphere --seed -1 --out o.png", &["-1"]),
        ("render teapot --out o.png", &["unknown stimulus 'teapot'"]),
        (
            "render sphere --light 0,0,-1 --out o.png",
            &["light", "below the horizon"],
        ),
        (
            "render sphere --light tilt=0,slant=120 --out o.png",
            &["light", "outside 0..90"],
        ),
        (
            "render sphere --light nan,0,1 --out o.png",
            &["light", "NaN"],
        ),
        (
            "render sphere --light 0,0,0 --out o.png",
            &["light", "not a direction"],
        ),
        (
            "render sphere --light sideways --out o.png",
            &["light", "sideways"],
        ),
        ("render sphere --brdf chalk --out o.png", &["brdf", "chalk"]),
        (
            "render sphere --set brdf=chalk --out o.png",
            &["brdf", "chalk"],
        ),
        (
            "render mesh --set path=in/tri.obj --set fill=0 --out o.png",
            &["fill", "0"],
        ),
        (
            "render mesh --set path=in/tri.obj --set shading=wavy --out o.png",
            &["shading", "wavy"],
        ),
        (
            "render sphere --out o.tiff",
            &["o.tiff", "unknown output format"],
        ),
        ("render sphere --out o", &["unknown output format"]),
        ("list everything", &["everything"]),
        ("describe teapot", &["unknown stimulus 'teapot'"]),
        ("describe", &["NAME"]),
        ("render sphere --threads 0 --out o.png", &["--threads"]),
    ]);
    refused_all(&d, &table);
    // A light with huge but finite components still has a direction.
    works(
        &d,
        "render sphere --size 8 --light 1e308,1e308,1e308 --out big.png",
    );
    // `describe mesh` lists the mesh's parameters.
    let out = shadelab(&d, &["describe", "mesh"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && text.contains("path") && text.contains("fill"));
}

/// The commands that write an output folder, with `{}` where the folder goes.
const FOLDER_COMMANDS: &[&str] = &[
    "solve in/ok.png --light above --out {}",
    "analyze lightness in/ok.png --model retinex --out {}",
    "analyze prior-sweep in/ok.png --tilts 0:360:90 --out {}",
    "analyze observer in/ok.png --tilts 0:360:90 --out {}",
    "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --out {}",
    "study run in/study.json --out {}",
    "gallery --presets in/presets_ok --out {}",
];

#[test]
fn outputs_that_cannot_or_must_not_be_written_are_refused() {
    let d = scratch("hostile-outputs");
    fixtures(&d);
    let mut table = Vec::new();
    for command in FOLDER_COMMANDS {
        let at = |out: &str| command.replace("{}", out);
        table.push((at("afile/o"), vec!["afile", "not a folder"]));
        table.push((at("missing/o"), vec!["missing", "does not exist"]));
        table.push((
            at("foreign"),
            vec!["foreign", "not written by shadelab", "--force"],
        ));
        table.push((at("fake"), vec!["fake", "not shadelab's", "--force"]));
        table.push((at("foreign.png"), vec!["foreign.png", "not a folder"]));
    }
    table.extend(cases(&[
        (
            "render sphere --size 8 --out afile/o.png",
            &["afile", "not a folder"],
        ),
        (
            "render sphere --size 8 --out missing/o.png",
            &["missing", "does not exist"],
        ),
        (
            "render sphere --size 8 --out foreign.png",
            &["foreign.png", "not written by shadelab", "--force"],
        ),
        (
            "render sphere --size 8 --out photo.png",
            &["photo.json", "not a shadelab sidecar", "--force"],
        ),
        (
            "render sphere --size 8 --out shot.png",
            &["shot_mask.png", "not written by shadelab"],
        ),
        (
            "render sphere --size 8 --out folder.png",
            &["folder.png", "directory"],
        ),
        (
            "render sphere --size 8 --out in/ok.png",
            &["in/ok.png", "not written by shadelab"],
        ),
        (
            "render heightfield --set path=in/ok.npy --out in/ok.npy",
            &["in/ok.npy", "not written by shadelab"],
        ),
    ]));
    refused_all(&d, &table);
}

#[test]
fn own_outputs_may_be_replaced_and_foreign_ones_with_force() {
    let d = scratch("hostile-replace");
    fixtures(&d);
    // Re-running over shadelab's own output is fine, for files and folders.
    for _ in 0..2 {
        works(&d, "render sphere --size 8 --layers --out s.png");
        for (k, command) in FOLDER_COMMANDS.iter().enumerate() {
            works(&d, &command.replace("{}", &format!("own{k}")));
        }
    }
    // A render's sidecar is what makes its files replaceable: without it, they are protected.
    std::fs::remove_file(d.join("s.json")).unwrap();
    let out = shadelab(&d, &["render", "sphere", "--size", "8", "--out", "s.png"]);
    assert_error(&out, 1, "--force");
    // --force replaces files shadelab did not write, and writes into a folder it did not
    // write, keeping every file of the user's there (the output-folder rule).
    works(&d, "render sphere --size 8 --force --out foreign.png");
    works(&d, "render sphere --size 8 --force --out photo.png");
    let sidecar: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("photo.json")).unwrap()).unwrap();
    assert_eq!(sidecar["program"], "shadelab");
    let holiday = std::fs::read(d.join("foreign/holiday.jpg")).unwrap();
    works(&d, "solve in/ok.png --light above --force --out foreign");
    assert_eq!(
        std::fs::read(d.join("foreign/holiday.jpg")).unwrap(),
        holiday
    );
    assert!(d.join("foreign/report.json").exists());
}

#[test]
fn solve_refuses_bad_numbers_and_names() {
    let d = scratch("hostile-solve");
    fixtures(&d);
    let s = "solve in/ok.png --out o";
    let mut table = Vec::new();
    for (flags, needles) in [
        ("--light above --lambda nan", vec!["lambda", "NaN"]),
        ("--light above --lambda -1", vec!["lambda", "-1"]),
        ("--light above --lambda 0", vec!["lambda", "0"]),
        ("--light above --tol nan", vec!["tol", "NaN"]),
        ("--light above --tol inf", vec!["tol", "inf"]),
        ("--light above --tol -1", vec!["tol", "-1"]),
        ("--light above --albedo inf", vec!["--albedo", "inf"]),
        ("--light above --albedo -1", vec!["--albedo", "-1"]),
        ("--light above --albedo nan", vec!["--albedo", "NaN"]),
        ("--light above --max-iter 0", vec!["max-iter"]),
        ("--light above --max-iter -3", vec!["--max-iter", "-3"]),
        ("--light above --method fast", vec!["method", "fast"]),
        (
            "--light above --brdf chalk",
            vec!["reflectance model", "chalk"],
        ),
        ("--light 0,0,-1", vec!["light", "below the horizon"]),
        ("--light 1,0,0", vec!["--light", "z > 0"]),
        ("--light tilt=0,slant=90", vec!["--light", "z > 0"]),
        ("--light nan,0,1", vec!["light", "NaN"]),
        ("--light inf,0,1", vec!["light", "inf"]),
        ("--light tilt=nan,slant=3", vec!["light", "finite"]),
        ("--light sideways", vec!["light", "sideways"]),
        ("", vec!["--light"]),
    ] {
        table.push((format!("{s} {flags}"), needles));
    }
    table.push((
        "solve in/zeros.npy --light estimate --out o".into(),
        vec!["black"],
    ));
    table.push(("solve --light above --out o".into(), vec!["IMAGE"]));
    refused_all(&d, &table);
}

#[test]
fn analyze_refuses_bad_numbers_and_names() {
    let d = scratch("hostile-analyze");
    fixtures(&d);
    let table = cases(&[
        // lightness
        (
            "analyze lightness in/ok.png --model blah --out o",
            &["model", "blah"],
        ),
        (
            "analyze lightness in/ok.png --model odog --out o",
            &["--ppd"],
        ),
        (
            "analyze lightness in/ok.png --model odog --ppd nan --out o",
            &["--ppd", "NaN"],
        ),
        (
            "analyze lightness in/ok.png --model odog --ppd -3 --out o",
            &["--ppd", "-3"],
        ),
        (
            "analyze lightness in/ok.png --model odog --ppd 8 --out o",
            &["smaller than the largest filter"],
        ),
        (
            "analyze lightness in/one.png --model all --ppd 8 --out o",
            &["1 px high × 1 px wide", "smaller"],
        ),
        (
            "analyze lightness --model retinex --out o",
            &["IMAGE", "--stimulus"],
        ),
        (
            "analyze lightness --stimulus teapot --model retinex --out o",
            &["unknown stimulus 'teapot'"],
        ),
        (
            "analyze lightness --stimulus disc --set foo=1 --model retinex --out o",
            &["unknown parameter 'foo'"],
        ),
        (
            "analyze lightness --stimulus disc --ppd 1e6 --model retinex --out o",
            &["exceeds", "--max-pixels"],
        ),
        (
            "analyze lightness --stimulus disc --ppd 0.01 --model retinex --out o",
            &["0 pixels high × 0 wide"],
        ),
        (
            "analyze lightness in/ok.png --stimulus disc --model retinex --out o",
            &["--stimulus"],
        ),
        // fading
        (
            "analyze fading in/ok.png --mask in/labels12.png --out o",
            &["--ppd"],
        ),
        ("analyze fading in/ok.png --ppd 8 --out o", &["--mask"]),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --tau nan --out o",
            &["τ NaN"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --dt 0 --out o",
            &["time step 0"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --dt 1e-9 --out o",
            &["steps"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --duration inf --out o",
            &["duration inf"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --jitter -1 --out o",
            &["jitter", "-1"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --dog-sigma nan --out o",
            &["σ NaN"],
        ),
        (
            "analyze fading in/ok.png --ppd 8 --mask in/labels12.png --border 0 --out o",
            &["half-width 0"],
        ),
        (
            "analyze fading --stimulus sphere --ppd 4 --out o",
            &["blur"],
        ),
        // prior-sweep and observer
        ("analyze prior-sweep in/one.png --out o", &["too thin"]),
        (
            "analyze prior-sweep in/ok.png --slant 90 --out o",
            &["--slant", "90"],
        ),
        (
            "analyze prior-sweep in/ok.png --slant nan --out o",
            &["--slant", "NaN"],
        ),
        (
            "analyze prior-sweep in/ok.png --tilts 0:360:0 --out o",
            &["--tilts", "step"],
        ),
        (
            "analyze prior-sweep in/ok.png --tilts nan --out o",
            &["--tilts", "nan"],
        ),
        (
            "analyze prior-sweep in/ok.png --tilts 0:1e9:1e-9 --out o",
            &["--tilts", "at most"],
        ),
        (
            "analyze prior-sweep in/ok.png --binding nan --out o",
            &["--binding", "nan"],
        ),
        (
            "analyze prior-sweep in/ok.png --lambda inf --out o",
            &["lambda", "inf"],
        ),
        (
            "analyze prior-sweep in/ok.png --albedo -1 --out o",
            &["--albedo", "-1"],
        ),
        (
            "analyze prior-sweep in/ok.png --ambient nan --out o",
            &["--ambient", "NaN"],
        ),
        (
            "analyze prior-sweep in/ok.png --max-iter 0 --out o",
            &["max-iter"],
        ),
        (
            "analyze prior-sweep in/ok.png --domain everywhere --out o",
            &["--domain", "everywhere"],
        ),
        (
            "analyze prior-sweep in/ok.png --boundary wobbly --out o",
            &["--boundary", "wobbly"],
        ),
        (
            "analyze prior-sweep --stimulus bumps --size 0 --out o",
            &["--size", "0"],
        ),
        (
            "analyze prior-sweep --stimulus bumps --size 100000 --out o",
            &["exceeds", "--max-pixels"],
        ),
        (
            "analyze prior-sweep --stimulus bumps --size -4 --out o",
            &["--size"],
        ),
        (
            "analyze observer in/ok.png --prior-kappa nan --out o",
            &["--prior-kappa", "nan"],
        ),
        (
            "analyze observer in/ok.png --prior-kappa -1 --out o",
            &["--prior-kappa", "-1"],
        ),
        (
            "analyze observer in/ok.png --prior-tilt inf --out o",
            &["prior tilt", "inf"],
        ),
        (
            "analyze observer in/ok.png --noise 0 --out o",
            &["noise", "0"],
        ),
        (
            "analyze observer in/ok.png --convexity-bias nan --out o",
            &["convexity bias", "NaN"],
        ),
        (
            "analyze observer in/ok.png --rotations 1:2:3:4 --out o",
            &["--rotations"],
        ),
        (
            "analyze observer in/ok.png --tilts 0:180:5 --out o",
            &["--tilts", "circle"],
        ),
        (
            "analyze observer --stimulus teapot --out o",
            &["unknown stimulus 'teapot'"],
        ),
        ("analyze wobble in/ok.png --out o", &["wobble"]),
    ]);
    refused_all(&d, &table);
    let mut args = words("analyze lightness --stimulus heightfield --model retinex --out o --set");
    args.push(OsStr::from_bytes(b"path=\xff.npy").into());
    refused(&d, &args, &["--set", "UTF-8"]);
}

#[test]
fn study_gallery_and_bench_refuse_bad_specs_and_arguments() {
    let d = scratch("hostile-study");
    fixtures(&d);
    works(&d, "study run in/study.json --shard 0/2 --out in/s0");
    works(&d, "study run in/study.json --shard 1/2 --out in/s1");
    let shard = |name: &str, edit: &dyn Fn(&Path)| {
        let to = d.join("in").join(name);
        std::fs::create_dir_all(&to).unwrap();
        for f in ["results.csv", "sweep.csv", "study.json"] {
            std::fs::copy(d.join("in/s1").join(f), to.join(f)).unwrap();
        }
        edit(&to);
    };
    shard("s_truncated", &|p| {
        std::fs::write(p.join("study.json"), "{").unwrap()
    });
    shard("s_no_shard", &|p| {
        std::fs::write(p.join("study.json"), r#"{"program": "shadelab"}"#).unwrap()
    });
    shard("s_bad_csv", &|p| {
        std::fs::write(p.join("results.csv"), "x\n").unwrap()
    });
    shard("s_no_csv", &|p| {
        std::fs::remove_file(p.join("sweep.csv")).unwrap()
    });
    // Rows that do not fit (issue 16): cut inside the last row, an extra field, a number that
    // is NaN, a point of the other shard (shard 0's tables under shard 1's report), a point
    // beyond the study, and a whole last row lost.
    let edit_results = |p: &Path, edit: &dyn Fn(String) -> String| {
        let text = std::fs::read_to_string(p.join("results.csv")).unwrap();
        std::fs::write(p.join("results.csv"), edit(text)).unwrap()
    };
    shard("s_cut", &|p| {
        edit_results(p, &|t| t[..t.len() - 7].to_string())
    });
    shard("s_extra_field", &|p| {
        edit_results(p, &|t| {
            let (head, rest) = t.split_once('\n').unwrap();
            let (row, rest) = rest.split_once('\n').unwrap();
            format!("{head}\n{row},x\n{rest}")
        })
    });
    shard("s_nan", &|p| {
        edit_results(p, &|t| {
            let (head, row) = t.split_once('\n').unwrap();
            let (row, rest) = row.split_once('\n').unwrap();
            let mut fields: Vec<&str> = row.split(',').collect();
            let n = fields.len();
            fields[n - 2] = "NaN";
            format!("{head}\n{}\n{rest}", fields.join(","))
        })
    });
    shard("s_foreign", &|p| {
        for f in ["results.csv", "sweep.csv"] {
            std::fs::copy(d.join("in/s0").join(f), p.join(f)).unwrap();
        }
    });
    shard("s_beyond", &|p| {
        edit_results(p, &|t| {
            let last = t.lines().last().unwrap();
            let (_, tail) = last.split_once(',').unwrap();
            format!("{t}1001,{tail}\n")
        })
    });
    shard("s_lost_rows", &|p| {
        edit_results(p, &|t| {
            let keep: Vec<&str> = t.lines().filter(|l| !l.starts_with("1,")).collect();
            keep.join("\n") + "\n"
        })
    });
    let table = cases(&[
        (
            "study run in/truncated.json --out o",
            &["in/truncated.json", "bad study spec"],
        ),
        (
            "study run in/empty.json --out o",
            &["in/empty.json", "bad study spec"],
        ),
        (
            "study run in/dir.json --out o",
            &["in/dir.json", "is a directory"],
        ),
        (
            "study run in/missing.json --out o",
            &["in/missing.json", "No such file"],
        ),
        (
            "study run in/study_unknown.json --out o",
            &["in/study_unknown.json", "unknown field `prior`"],
        ),
        (
            "study run in/study_unknown_entry.json --out o",
            &["in/study_unknown_entry.json", "unknown field `colour`"],
        ),
        (
            "study run in/study_unknown_prior.json --out o",
            &["in/study_unknown_prior.json", "unknown field `sigma`"],
        ),
        (
            "study run in/study_teapot.json --out o",
            &["in/study_teapot.json", "teapot"],
        ),
        (
            "study run in/study_none.json --out o",
            &["in/study_none.json", "no stimuli"],
        ),
        (
            "study run in/study_huge.json --out o",
            &["in/study_huge.json", "exceeds", "--max-pixels"],
        ),
        (
            "study run in/study.json --max-pixels 100 --out o",
            &["in/study.json", "24 px high × 24 px wide", "100"],
        ),
        (
            "study run in/study_noise.json --out o",
            &["in/study_noise.json", "noise -1"],
        ),
        (
            "study run in/study_slant.json --out o",
            &["in/study_slant.json", "slant 90"],
        ),
        (
            "study run in/study_tilts.json --out o",
            &["in/study_tilts.json", "circle"],
        ),
        (
            "study run in/study_shape.json --out o",
            &["in/study_shape.json", "-1"],
        ),
        (
            "study run in/study.json --shard 3/2 --out o",
            &["--shard", "3/2"],
        ),
        (
            "study run in/study.json --shard x --out o",
            &["--shard", "'x'"],
        ),
        (
            "study run in/study.json --shard 0/0 --out o",
            &["--shard", "0/0"],
        ),
        ("study merge in/s0 --out o", &["shard 1/2 missing"]),
        ("study merge in/s0 in/s0 --out o", &["in/s0", "as is"]),
        (
            "study merge in/s0 in/s1 --out in/s1",
            &["--out in/s1", "one of the shard folders"],
        ),
        (
            "study merge in/s0 in/s_truncated --out o",
            &["in/s_truncated/study.json", "bad study report"],
        ),
        (
            "study merge in/s0 in/s_no_shard --out o",
            &["in/s_no_shard/study.json", "no spec_md5"],
        ),
        (
            "study merge in/s0 in/s_bad_csv --out o",
            &["in/s_bad_csv/results.csv", "header"],
        ),
        (
            "study merge in/s0 in/s_no_csv --out o",
            &["in/s_no_csv/sweep.csv", "No such file"],
        ),
        (
            "study merge in/s0 afile --out o",
            &["afile", "not a study output folder"],
        ),
        (
            "study merge in/s0 foreign --out o",
            &["foreign", "not a study output folder"],
        ),
        (
            "study merge in/s0 in/s_cut --out o",
            &["in/s_cut/results.csv: line ", "the row is truncated"],
        ),
        (
            "study merge in/s0 in/s_extra_field --out o",
            &["in/s_extra_field/results.csv: line 2:", "12 fields", "11"],
        ),
        (
            "study merge in/s0 in/s_nan --out o",
            &[
                "in/s_nan/results.csv: line 2:",
                "'NaN', not a finite number",
            ],
        ),
        (
            "study merge in/s0 in/s_foreign --out o",
            &[
                "in/s_foreign/results.csv: line 2:",
                "point 0 belongs to shard 0/2, not to this shard 1/2",
            ],
        ),
        (
            "study merge in/s0 in/s_beyond --out o",
            &[
                "in/s_beyond/results.csv: line ",
                "point 1001 is not in the study",
            ],
        ),
        (
            "study merge in/s0 in/s_lost_rows --out o",
            &["no shard's results.csv has rows for point 1 ", "shard 1/2"],
        ),
        (
            "study merge in/s0 in/s1 --out afile/o",
            &["afile", "not a folder"],
        ),
        (
            "study merge in/s0 in/s1 --out foreign",
            &["foreign", "--force"],
        ),
        (
            "study merge in/s0 in/s1 --out fake",
            &["fake", "not shadelab's"],
        ),
        ("study merge --out o", &["DIRS"]),
        (
            "gallery --presets in/presets_empty --out o",
            &["in/presets_empty", "no stimulus specs"],
        ),
        (
            "gallery --presets in/presets_truncated --out o",
            &["in/presets_truncated/a.json", "bad stimulus spec"],
        ),
        (
            "gallery --presets in/presets_unknown --out o",
            &["in/presets_unknown/a.json", "unknown field `colour`"],
        ),
        (
            "gallery --presets in/presets_teapot --out o",
            &["in/presets_teapot/a.json", "teapot"],
        ),
        (
            "gallery --presets in/presets_huge --out o",
            &["in/presets_huge/a.json", "exceeds", "--max-pixels"],
        ),
        (
            "gallery --presets in/presets_bad_name --out o",
            &["a b.json", "letters, digits"],
        ),
        (
            "gallery --presets in/missing --out o",
            &["in/missing", "No such file"],
        ),
        (
            "gallery --presets afile --out o",
            &["afile", "Not a directory"],
        ),
        (
            "gallery --presets in/presets_ok --max-pixels 10 --out o",
            &["8 px high × 8 px wide", "10"],
        ),
        ("bench --sizes 4", &["--sizes", "8"]),
        ("bench --sizes 16 --repeat 0", &["--repeat"]),
        ("bench --sizes 16 --shape cube", &["shape", "cube"]),
        (
            "bench --sizes 16 --light 0,0,-1",
            &["light", "below the horizon"],
        ),
        ("bench --sizes 16 --light 1,0,0", &["--light", "z > 0"]),
        ("bench --sizes 100000", &["--sizes 100000", "--max-pixels"]),
        (
            "bench --sizes 4294967296",
            &["--sizes 4294967296", "--max-pixels"],
        ),
        (
            "bench --sizes 18446744073709551615",
            &["--sizes 18446744073709551615", "--max-pixels"],
        ),
        (
            "bench --sizes 16 --max-pixels 100",
            &["--sizes 16", "--max-pixels 100"],
        ),
        ("bench --sizes 16,,32", &["--sizes"]),
        ("bench --sizes=-1", &["--sizes", "-1"]),
    ]);
    refused_all(&d, &table);
}

#[test]
fn eval_refuses_missing_and_broken_data() {
    let d = scratch("hostile-eval");
    fixtures(&d);
    let data = d.join("in/evaldata");
    std::fs::create_dir_all(data.join("bunny")).unwrap();
    std::fs::create_dir_all(data.join("mozart")).unwrap();
    std::fs::copy(d.join("in/oor.ply"), data.join("bunny/bun_zipper_res2.ply")).unwrap();
    std::fs::copy(d.join("in/nan.npy"), data.join("mozart/depth.npy")).unwrap();
    let table = cases(&[
        ("eval --data in/missing", &["in/missing", "not found"]),
        ("eval --data afile", &["afile", "not found"]),
        (
            "eval --data in/evaldata --only blah",
            &["evaluation set", "blah"],
        ),
        ("eval --data in/evaldata --bunny-size 0", &["bunny size 0"]),
        ("eval --data in/evaldata --lambda nan", &["lambda", "NaN"]),
        ("eval --data in/evaldata --tol -1", &["tol", "-1"]),
        (
            "eval --data in/evaldata --diligent-light 0,0,-1",
            &["light", "below the horizon"],
        ),
        (
            "eval --data in/evaldata --only bunny --bunny-size 16",
            &["in/evaldata/bunny/bun_zipper_res2.ply", "out of range"],
        ),
        (
            "eval --data in/evaldata --only mozart",
            &["in/evaldata/mozart/", "mozart"],
        ),
        (
            "eval --data in/evaldata --only bunny --bunny-size 16 --out afile/o",
            &["afile", "not a folder"],
        ),
        (
            "eval --data in/evaldata --only bunny --bunny-size 16 --out foreign",
            &["foreign", "--force"],
        ),
        (
            "eval --data in/evaldata --only bunny --bunny-size 16 --out fake",
            &["fake", "not shadelab's"],
        ),
    ]);
    assert!(table
        .iter()
        .all(|(l, _)| l.starts_with("eval") || !l.contains("evaldata")));
    refused_all(&d, &table);
}

// ---------------------------------------------------------------------------------------------
// Input limits and numeric ranges (issue 16).

/// Runs `args` in `dir`, killing it after `limit`: its output, or `None` when it ran over.
fn run_within(dir: &Path, args: &[&str], limit: std::time::Duration) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_shadelab"))
        .args(args)
        .current_dir(dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the shadelab binary runs");
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap();
            child.wait().unwrap();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Some(child.wait_with_output().unwrap())
}

/// Runs `args` with a limit of 30 s and asserts one `error: ` line holding every needle.
fn refused_within(dir: &Path, args: &[&str], needles: &[&str]) {
    let limit = std::time::Duration::from_secs(30);
    let out = run_within(dir, args, limit)
        .unwrap_or_else(|| panic!("{args:?} still ran after {limit:?}"));
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert!(
        matches!(out.status.code(), Some(1 | 2)) && lines.len() == 1,
        "{args:?}: exit {:?}, stderr: {err}",
        out.status.code()
    );
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{n}' not in: {err}");
    }
}

#[test]
fn inputs_are_read_only_as_far_as_needed() {
    let d = scratch("hostile-limits");
    let link = |name: &str, to: &str| std::os::unix::fs::symlink(to, d.join(name)).unwrap();
    // Endless inputs: read whole, these never end (or end when memory does).
    link("endless.png", "/dev/zero");
    link("endless.npy", "/dev/zero");
    link("endless.json", "/dev/urandom");
    // A 1 GiB file (sparse) that declares a 2×2 PNG: read no further than a 2×2 PNG can be.
    let mut head = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR\0\0\0\x02\0\0\0\x02".to_vec();
    head.extend_from_slice(&[8, 0, 0, 0, 0]);
    std::fs::write(d.join("big.png"), &head).unwrap();
    let big = std::fs::OpenOptions::new()
        .write(true)
        .open(d.join("big.png"))
        .unwrap();
    big.set_len(1 << 30).unwrap();
    // And a 1 GiB file that is not a PNG at all.
    std::fs::File::create(d.join("gig.png"))
        .unwrap()
        .set_len(1 << 30)
        .unwrap();
    for image in ["endless.png", "gig.png"] {
        refused_within(
            &d,
            &["solve", image, "--light", "above", "--out", "o"],
            &[image, "not a PNG image"],
        );
    }
    refused_within(
        &d,
        &["solve", "big.png", "--light", "above", "--out", "o"],
        &["big.png: is larger than 16 MiB"],
    );
    refused_within(
        &d,
        &["analyze", "observer", "endless.npy", "--out", "o"],
        &["endless.npy", "not a .npy file"],
    );
    let capped = "is larger than 64 MiB, the most shadelab reads from such a file";
    refused_within(
        &d,
        &["render", "--spec", "endless.json", "--out", "r.png"],
        &["endless.json: ", capped],
    );
    refused_within(
        &d,
        &["study", "run", "endless.json", "--out", "o"],
        &["endless.json: ", capped],
    );
    // A size the machine cannot hold: an error before any buffer, not an abort.
    refused_within(
        &d,
        &[
            "--max-pixels",
            "10000000000",
            "render",
            "sphere",
            "--size",
            "100000",
            "--out",
            "huge.png",
        ],
        &[
            "100000 px high × 100000 px wide",
            "more memory than this machine can give",
        ],
    );
    assert!(!d.join("huge.png").exists());
    // Absurd thread counts are capped at once, not spent starting threads.
    let started = std::time::Instant::now();
    let out = run_within(
        &d,
        &[
            "--threads",
            "100000",
            "render",
            "sphere",
            "--size",
            "16",
            "--out",
            "t.png",
        ],
        std::time::Duration::from_secs(30),
    )
    .expect("--threads 100000 finishes");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(started.elapsed() < std::time::Duration::from_secs(10));
}

/// A `.npy` of one-byte or two-byte values (`descr` `|u1`, `<u2`, …) of shape (16, 16).
fn npy_of(descr: &str, values: impl IntoIterator<Item = i64>) -> Vec<u8> {
    let size: usize = descr[2..].parse().unwrap();
    let data: Vec<u8> = values
        .into_iter()
        .flat_map(|v| v.to_le_bytes()[..size].to_vec())
        .collect();
    npy(descr, "(16, 16)", &data)
}

#[test]
fn picture_values_follow_one_rule() {
    let d = scratch("hostile-values");
    fixtures(&d);
    let i = d.join("in");
    let put = |name: &str, bytes: &[u8]| std::fs::write(i.join(name), bytes).unwrap();
    let codes = || (0..256).map(|k| (40 + k / 2) as i64);
    put("u8.npy", &npy_of("|u1", codes()));
    put("u16.npy", &npy_of("<u2", codes().map(|c| c * 257)));
    put("i64.npy", &npy_of("<i8", (0..256).map(|k| k % 201)));
    put("i16.npy", &npy_of("<i2", codes()));
    put(
        "two.npy",
        &npy("<f8", "(16, 16)", &f64s((0..256).map(|k| k as f64 / 128.0))),
    );
    put(
        "below.npy",
        &npy(
            "<f8",
            "(16, 16)",
            &f64s((0..256).map(|k| 0.5 - (k % 3) as f64 / 3.0)),
        ),
    );
    let away: Vec<f64> = (0..256).flat_map(|_| [0.3, 0.2, -0.9]).collect();
    put("normals_away.npy", &npy("<f8", "(16, 16, 3)", &f64s(away)));
    // uint8 and uint16: the codes of a PNG of that depth, exactly.
    let max = shadelab::DEFAULT_MAX_PIXELS;
    for (file, scale) in [("u8.npy", 255.0), ("u16.npy", 65535.0 / 257.0)] {
        let (image, info) = shadelab_io::read_luminance(&i.join(file), max).unwrap();
        let want: Vec<f64> = codes().map(|c| c as f64 / scale).collect();
        for (got, want) in image.data().iter().zip(&want) {
            assert!((got - want).abs() < 1e-15, "{file}: {got} vs {want}");
        }
        assert!(
            info["conversion"].as_str().unwrap().contains("divided by"),
            "{info}"
        );
    }
    // ... and said once on stderr where a command reads one.
    let out = run_os(
        &d,
        &words("analyze observer in/u8.npy --tilts 0:360:90 --out o8"),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert_eq!(
        err.matches("uint8 values divided by 255").count(),
        1,
        "{err}"
    );
    let table = cases(&[
        (
            "solve in/i64.npy --light above --out o",
            &["in/i64.npy: int64 pictures are refused", "uint8"],
        ),
        (
            "analyze observer in/i16.npy --out o",
            &["in/i16.npy: int16 pictures are refused"],
        ),
        (
            "solve in/two.npy --light above --out o",
            &["in/two.npy: 127 of 256 values are outside 0..1 (from 0 to 1.9921875)"],
        ),
        (
            "analyze lightness in/below.npy --model retinex --out o",
            &[
                "in/below.npy: 85 of 256 values are outside 0..1 (from -0.1666",
                "to 0.5)",
            ],
        ),
        (
            "solve in/ok.png --light above --boundary in/normals_away.npy --out o",
            &["faces away from the viewer", "n_z < 0"],
        ),
    ]);
    refused_all(&d, &table);
}

#[test]
fn no_output_holds_nan_even_at_extreme_noise() {
    let d = scratch("hostile-noise");
    let args = words(
        "analyze observer --stimulus bumps --set rows=1 --set columns=1 --size 32x32 --ppd 8 \
         --tilts 0:360:90 --rotations 0,90 --noise 1e-200 --out o",
    );
    let out = run_os(&d, &args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    if !out.status.success() {
        // Refused, one line, nothing written.
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(!d.join("o").exists());
    }
    for (name, bytes) in super::determinism::outputs(&d) {
        assert_eq!(super::golden_outputs::non_finite(&name, &bytes), None);
    }
}
