//! The fuzz targets' inputs replayed through the same library entry points as `fuzz/`:
//! the committed seed corpora (`fuzz/seeds/<target>/`, small valid inputs that must keep
//! working) and every input the fuzzers found to crash (`tests/data/fuzz/<target>/`, which must
//! now give an error, never a panic). Each input starts with the selector byte(s) the matching
//! fuzz target reads; see docs/reliability.md.

use serde_json::{Map, Value};
use shadelab::stimulus::{self, Spec};
use shadelab::Params;
use shadelab::SizeRequest;
use shadelab::{Image, Mask, Result};
use shadelab_analysis::analysis::study::{Study, StudySpec};
use shadelab_engine::surface::{view_rotation, Mesh, MeshShading};
use shadelab_io as io;
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The files of `dir`, sorted; `(name, bytes)`.
fn inputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect()
}

fn seeds(target: &str) -> Vec<(String, Vec<u8>)> {
    let v = inputs(&Path::new(ROOT).join("fuzz/seeds").join(target));
    assert!(!v.is_empty(), "no seeds for {target}");
    v
}

// ---- mesh: selector byte (bit 0: PLY 0 / OBJ 1), then the file ----

fn parse_mesh(data: &[u8]) -> Result<Mesh> {
    let (&selector, file) = data.split_first().expect("empty input");
    if selector & 1 == 0 {
        Mesh::from_ply(file, Path::new("fuzz.ply"))
    } else {
        Mesh::from_obj(file, Path::new("fuzz.obj"))
    }
}

/// As the fuzz target: shading and view from the selector byte, a 32×24 frame.
fn rasterize_as_fuzzed(selector: u8, mesh: &Mesh) -> Result<shadelab_engine::surface::Surface> {
    let shading = if selector & 2 == 0 {
        MeshShading::Smooth
    } else {
        MeshShading::Flat
    };
    let yaw = f64::from((selector >> 2) & 7) * 45.0;
    let pitch = f64::from(selector >> 5) * 45.0;
    mesh.rasterize_with(32, 24, &view_rotation(yaw, pitch, 0.0)?, 0.9, shading)
}

#[test]
fn mesh_seeds_parse_and_rasterise() {
    for (name, data) in seeds("mesh") {
        let mesh = parse_mesh(&data).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(mesh.triangles.len() >= 2, "{name}");
        let ident = view_rotation(0.0, 0.0, 0.0).unwrap();
        let s = mesh.rasterize(32, 24, &ident, 0.9).unwrap();
        assert!(s.mask.count() > 100, "{name}: {} pixels", s.mask.count());
        // The view the selector asks for must not panic either (an edge-on view may be an error).
        let _ = rasterize_as_fuzzed(data[0], &mesh);
    }
}

// ---- spec: selector byte % 3 (0 Spec JSON, 1 name + key=value lines, 2 study JSON) ----

/// As the fuzz target: prepares at the size asked for (which must succeed for a valid input),
/// then generates the same parameters at 48×32, which may fail (a pattern that needs more
/// degrees than the small frame has) but must not panic.
fn prepare_and_generate(
    name: &str,
    params: &Map<String, Value>,
    size: &SizeRequest,
    seed: u64,
) -> Result<()> {
    stimulus::prepare(name, params, size, seed, shadelab::DEFAULT_MAX_PIXELS)?;
    let small = SizeRequest {
        visual_size: None,
        ppd: size.ppd,
        shape: Some((32, 48)),
    };
    if let Ok((stim, request)) = stimulus::prepare(name, params, &small, seed, 16 * 1024) {
        let _ = stim.generate(&request);
    }
    Ok(())
}

fn run_spec(data: &[u8]) -> Result<()> {
    let (&selector, rest) = data.split_first().expect("empty input");
    match selector % 3 {
        0 => {
            let spec: Spec = serde_json::from_slice(rest)
                .map_err(|e| shadelab::Error::invalid(format!("bad stimulus spec: {e}")))?;
            prepare_and_generate(
                &spec.stimulus,
                &spec.params,
                &spec.size(),
                spec.seed.unwrap_or(0),
            )
        }
        1 => {
            let text = String::from_utf8_lossy(rest);
            let mut lines = text.lines();
            let name = lines.next().unwrap_or("").trim().to_string();
            let pairs: Vec<&str> = lines.collect();
            let params = Params::parse_pairs(&pairs)?;
            prepare_and_generate(&name, &params, &SizeRequest::default(), 0)
        }
        _ => {
            let spec: StudySpec = serde_json::from_slice(rest)
                .map_err(|e| shadelab::Error::invalid(format!("bad study spec: {e}")))?;
            Study::new(spec).map(|_| ())
        }
    }
}

#[test]
fn spec_seeds_prepare_without_panicking() {
    let all = seeds("spec");
    // Every shipped preset is a seed.
    let presets = all.iter().filter(|(n, _)| n.starts_with("preset_")).count();
    assert_eq!(presets, shadelab_stimuli::gallery::BUILTIN.len());
    for (name, data) in all {
        run_spec(&data).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

// ---- image_mask: selector byte (bit 0: PNG 0 / .npy 1), u16 LE image length, image, mask ----

fn read_image_and_mask(data: &[u8]) -> (Result<Image>, Result<Mask>) {
    const MAX_PIXELS: usize = 4 * 1024 * 1024;
    assert!(data.len() >= 3, "input too short");
    let split = (usize::from(data[1]) | usize::from(data[2]) << 8).min(data.len() - 3);
    let (image_bytes, mask_bytes) = data[3..].split_at(split);
    let image = if data[0] & 1 == 1 {
        io::read_image_from_bytes(image_bytes, Path::new("image.npy"), MAX_PIXELS)
    } else {
        io::read_gray_from_bytes(image_bytes, Path::new("image.png"), MAX_PIXELS).map(|(i, _)| i)
    };
    let mask = io::read_mask_from_bytes(mask_bytes, Path::new("mask.png"), MAX_PIXELS);
    (image, mask)
}

#[test]
fn image_mask_seeds_load_at_their_size() {
    for (name, data) in seeds("image_mask") {
        let (image, mask) = read_image_and_mask(&data);
        let image = image.unwrap_or_else(|e| panic!("{name}: {e}"));
        let mask = mask.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!((image.width(), image.height()), (8, 6), "{name}");
        assert!(
            image.data().iter().all(|v| (0.0..=1.0).contains(v)),
            "{name}"
        );
        // One seed pairs the image with a mask of another size, as `solve` must refuse.
        let rows = if name == "png_rgb" { 5 } else { 6 };
        assert_eq!((mask.width(), mask.height()), (8, rows), "{name}");
        assert!(mask.count() > 0, "{name}");
    }
}

#[test]
fn from_bytes_readers_match_the_path_readers() {
    let d = std::env::temp_dir().join(format!("shadelab-fuzzreg-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    for (name, data) in seeds("image_mask") {
        let split = usize::from(data[1]) | usize::from(data[2]) << 8;
        let (image_bytes, mask_bytes) = data[3..].split_at(split);
        let ext = if data[0] & 1 == 1 { "npy" } else { "png" };
        let image_path = d.join(format!("{name}.{ext}"));
        let mask_path = d.join(format!("{name}_mask.png"));
        std::fs::write(&image_path, image_bytes).unwrap();
        std::fs::write(&mask_path, mask_bytes).unwrap();
        let (image, mask) = read_image_and_mask(&data);
        let from_path = if ext == "npy" {
            io::read_image(&image_path, 1 << 22).unwrap()
        } else {
            io::read_gray(&image_path, 1 << 22).unwrap().0
        };
        assert_eq!(image.unwrap(), from_path, "{name}");
        assert_eq!(
            mask.unwrap(),
            io::read_mask(&mask_path, 1 << 22).unwrap(),
            "{name}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

// ---- csv_sidecar: selector byte % 3 (0 results.csv, 1 sweep.csv, 2 sidecar JSON), shape byte
// (shard count (b & 7) + 1, shard index (b >> 3) mod count, study points (b >> 5) × 3) ----

/// As the fuzz target: a shard's rows (with their points) or a sidecar's summary.
fn run_csv_sidecar(data: &[u8]) -> Result<Vec<(usize, String)>> {
    use shadelab_analysis::analysis::study::{merge::shard_rows, Shard, RESULTS, SWEEP};
    let [selector, shape, rest @ ..] = data else {
        panic!("input too short");
    };
    let count = usize::from(shape & 7) + 1;
    let shard = Shard {
        index: usize::from(shape >> 3) % count,
        count,
    };
    let points = usize::from(shape >> 5) * 3;
    match selector % 3 {
        mode @ (0 | 1) => {
            let file = if mode == 0 { RESULTS } else { SWEEP };
            shard_rows(rest, &Path::new("shard").join(file), shard, points)
        }
        _ => {
            let value: Value = serde_json::from_slice(rest)
                .map_err(|e| shadelab::Error::invalid(format!("not JSON: {e}")))?;
            let sidecar = io::RenderSidecar::from_value(Path::new("dir/image.json"), &value)?;
            Ok(vec![(0, sidecar.summary())])
        }
    }
}

#[test]
fn csv_sidecar_seeds_read_and_cut_rows_are_refused() {
    for (name, data) in seeds("csv_sidecar") {
        let rows = run_csv_sidecar(&data).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!rows.is_empty(), "{name}");
        if data[0] % 3 < 2 {
            // Shard 1 of 2 runs the odd points only.
            assert!(rows.iter().all(|(p, _)| p % 2 == 1), "{name}");
            // Cut anywhere inside its last row, the table is refused, naming the line.
            let lines = data.iter().filter(|&&b| b == b'\n').count();
            let cut = &data[..data.len() - 5];
            let e = run_csv_sidecar(cut).unwrap_err().to_string();
            assert!(
                e.contains(&format!("line {lines}: the row is truncated")),
                "{name}: {e}"
            );
        } else {
            assert!(rows[0].1.contains("ppd"), "{name}: {}", rows[0].1);
        }
    }
}

// ---- inputs the fuzzers found ----

/// Every crash input of `target` with the words its error must contain; every file in
/// `tests/data/fuzz/<target>/` must be listed in `expected`.
fn found(target: &str, expected: &[(&str, &str)]) -> Vec<(String, Vec<u8>, String)> {
    let files = inputs(&Path::new(ROOT).join("tests/data/fuzz").join(target));
    assert_eq!(
        files.len(),
        expected.len(),
        "every input in tests/data/fuzz/{target} needs an expected error here"
    );
    files
        .into_iter()
        .map(|(name, data)| {
            let (_, words) = expected
                .iter()
                .find(|(n, _)| *n == name)
                .unwrap_or_else(|| panic!("no expected error for {name}"));
            (name, data, words.to_string())
        })
        .collect()
}

#[test]
fn image_mask_crash_inputs_are_errors() {
    // A .npy header with 45 nested '{': npyz's backtracking header grammar took longer than the
    // fuzzer's 10 s timeout (exponential in the nesting); now refused before npyz sees it.
    // A PNG whose palette chunk is 256 bytes (not a multiple of 3): the png crate 0.18 panicked
    // ("range end index 3 out of range") expanding it; now refused before decoding.
    let cases = found(
        "image_mask",
        &[
            (
                "npy_nested_brackets_timeout",
                "image.npy: the .npy header nests brackets",
            ),
            (
                "png_palette_length_panic",
                "image.png: corrupt PNG: its palette (PLTE) is 256 bytes",
            ),
        ],
    );
    for (name, data, words) in cases {
        let (image, _mask) = read_image_and_mask(&data);
        let e = image.expect_err(&name).to_string();
        assert!(e.starts_with(&words), "{name}: {e}");
    }
}
