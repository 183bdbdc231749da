//! The `.mat` and `.npz` bundles: the picture, the target mask and every parameter in one
//! file, read back here by hand (MAT-file) and with npyz (npz), and with scipy/numpy and Octave
//! where they are installed.

use super::*;
use crate::cli::{scratch, shadelab};
use shadelab_stimuli::mat::{decode_all, MatValue};
use std::collections::BTreeMap;
use std::io::Read;
use std::process::Command;

/// Renders bumps (2 × 3, 1 000 × 700 … at 10 ppd: 100 rows × 140 columns) with its layers to
/// `file` in `dir`.
fn render_bumps(dir: &Path, file: &str, extra: &[&str]) {
    let mut args = vec![
        "--quiet",
        "render",
        "bumps",
        "--ppd",
        "10",
        "--set",
        "rows=2",
        "--set",
        "columns=3",
        "--light",
        "-1,1,1",
        "--layers",
        "--out",
        file,
    ];
    args.extend_from_slice(extra);
    ok(&shadelab(dir, &args));
}

#[test]
fn a_mat_bundle_holds_the_image_mask_parameters_and_layers() {
    let d = scratch("bundle-mat");
    render_bumps(&d, "b.mat", &[]);
    render_bumps(&d, "b.png", &[]);
    let vars: BTreeMap<String, MatValue> = decode_all(&std::fs::read(d.join("b.mat")).unwrap())
        .unwrap()
        .into_iter()
        .collect();
    let double = |name: &str| match &vars[name] {
        MatValue::Double { dims, data } => (dims.clone(), data.clone()),
        other => panic!("{name}: {other:?}"),
    };
    let (dims, img) = double("img");
    assert_eq!(dims, [100, 140]);
    // Column-major, equal to the 16-bit PNG to its last code.
    let (png, _) = shadelab_io::read_gray(&d.join("b.png"), MAX).unwrap();
    for r in 0..100 {
        for c in 0..140 {
            assert_eq!(codes(img[r + 100 * c]), codes(*png.get(c, r)));
        }
    }
    let (dims, mask) = double("target_mask");
    assert_eq!(dims, [100, 140]);
    let labels = shadelab_io::read_labels(&d.join("b_mask.png"), MAX).unwrap();
    for r in 0..100 {
        for c in 0..140 {
            assert_eq!(mask[r + 100 * c], f64::from(*labels.get(c, r)));
        }
    }
    let MatValue::Cell(names) = &vars["target_names"] else {
        panic!("target_names")
    };
    assert_eq!(names.len(), 6);
    assert_eq!(double("visual_size"), (vec![1, 2], vec![10.0, 14.0]));
    assert_eq!(double("shape"), (vec![1, 2], vec![100.0, 140.0]));
    assert_eq!(double("ppd"), (vec![1, 1], vec![10.0]));
    assert_eq!(double("rows"), (vec![1, 1], vec![2.0]));
    assert_eq!(vars["stimulus"], MatValue::Char("bumps".into()));
    // The light as the sidecar records it (tilt 45: from the upper left), and as a vector.
    assert_eq!(
        vars["light"],
        MatValue::Char("tilt=45,slant=54.73561".into())
    );
    let (dims, l) = double("light_direction");
    assert_eq!(dims, [1, 3]);
    let s = 3f64.sqrt();
    assert!(
        (l[0] + 1.0 / s).abs() < 1e-6 && (l[1] - 1.0 / s).abs() < 1e-6,
        "{l:?}"
    );
    // Every parameter the sidecar records is a field.
    let meta = sidecar(&d.join("b.json"));
    for key in meta["parameters"].as_object().unwrap().keys() {
        assert!(vars.contains_key(key.as_str()), "{key} missing");
    }
    // The layers, as the .npy files beside it hold them.
    let (dims, depth) = double("depth");
    assert_eq!(dims, [100, 140]);
    let npy = shadelab_io::read_image(&d.join("b_depth.npy"), MAX).unwrap();
    assert_eq!(depth[37 + 100 * 51] as f32, *npy.get(51, 37) as f32);
    assert_eq!(double("normals").0, [100, 140, 3]);
    assert!(vars.contains_key("shading"));
}

/// The raw bytes of each member of an `.npz`.
fn npz_members(path: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    let mut out = BTreeMap::new();
    for i in 0..zip.len() {
        let mut f = zip.by_index(i).unwrap();
        let mut bytes = Vec::new();
        f.read_to_end(&mut bytes).unwrap();
        out.insert(f.name().trim_end_matches(".npy").to_string(), bytes);
    }
    out
}

/// A float64 member: shape and values.
fn npz_numbers(bytes: &[u8]) -> (Vec<u64>, Vec<f64>) {
    let npy = npyz::NpyFile::new(bytes).unwrap();
    assert_eq!(npy.dtype(), npyz::DType::Plain("<f8".parse().unwrap()));
    (npy.shape().to_vec(), npy.into_vec::<f64>().unwrap())
}

/// A unicode member: its strings (UTF-32, zero-padded).
fn npz_texts(bytes: &[u8]) -> Vec<String> {
    let header_len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    let header = std::str::from_utf8(&bytes[10..10 + header_len]).unwrap();
    let width: usize = header
        .split("'<U")
        .nth(1)
        .and_then(|rest| rest.split('\'').next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("not unicode: {header}"));
    bytes[10 + header_len..]
        .chunks(4 * width)
        .map(|item| {
            item.chunks(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .take_while(|&c| c != 0)
                .filter_map(char::from_u32)
                .collect()
        })
        .collect()
}

#[test]
fn an_npz_bundle_holds_the_same_fields_and_reproduces() {
    let d = scratch("bundle-npz");
    render_bumps(&d, "b.npz", &["--range", "psychopy"]);
    render_bumps(&d, "b.mat", &["--range", "psychopy"]);
    let members = npz_members(&d.join("b.npz"));
    let mat: Vec<String> = decode_all(&std::fs::read(d.join("b.mat")).unwrap())
        .unwrap()
        .into_iter()
        .map(|(n, _)| n)
        .collect();
    let mut npz: Vec<&String> = members.keys().collect();
    let mut mat_sorted: Vec<&String> = mat.iter().collect();
    npz.sort();
    mat_sorted.sort();
    assert_eq!(npz, mat_sorted, "the two bundles hold the same fields");
    let (shape, img) = npz_numbers(&members["img"]);
    assert_eq!(shape, [100, 140]);
    assert!(img.iter().all(|v| (-1.0..=1.0).contains(v)));
    assert!(img.iter().any(|&v| v < 0.0), "psychopy range");
    assert_eq!(npz_numbers(&members["target_mask"]).0, [100, 140]);
    assert_eq!(
        npz_numbers(&members["shape"]),
        (vec![2], vec![100.0, 140.0])
    );
    assert_eq!(
        npz_numbers(&members["visual_size"]),
        (vec![2], vec![10.0, 14.0])
    );
    assert_eq!(npz_numbers(&members["ppd"]), (vec![], vec![10.0]));
    assert_eq!(npz_numbers(&members["normals"]).0, [100, 140, 3]);
    assert_eq!(npz_texts(&members["stimulus"]), ["bumps"]);
    assert_eq!(npz_texts(&members["range"]), ["-1..1"]);
    assert_eq!(npz_texts(&members["target_names"]).len(), 6);
    // The sidecar of a bundle reproduces it byte for byte.
    std::fs::create_dir_all(d.join("again")).unwrap();
    ok(&shadelab(
        &d,
        &[
            "--quiet",
            "render",
            "--spec",
            "b.json",
            "--out",
            "again/b.npz",
        ],
    ));
    assert_eq!(
        std::fs::read(d.join("b.npz")).unwrap(),
        std::fs::read(d.join("again/b.npz")).unwrap()
    );
}

/// Whether `python3` can import scipy and numpy; prints why not.
fn python_with_scipy() -> bool {
    match Command::new("python3")
        .args(["-c", "import scipy.io, numpy"])
        .output()
    {
        Ok(out) if out.status.success() => true,
        Ok(_) => {
            println!("skipped: python3 has no scipy/numpy (pip install numpy scipy)");
            false
        }
        Err(_) => {
            println!("skipped: no python3 on PATH");
            false
        }
    }
}

#[test]
fn scipy_loadmat_and_numpy_load_read_the_bundles() {
    if !python_with_scipy() {
        return;
    }
    let d = scratch("bundle-python");
    render_bumps(&d, "b.mat", &[]);
    render_bumps(&d, "b.npz", &[]);
    ok(&shadelab(
        &d,
        &[
            "--quiet",
            "render",
            "fading-disk",
            "--size",
            "40x20",
            "--out",
            "f.mat",
        ],
    ));
    let script = r#"
import json, sys
import numpy as np, scipy.io
m = scipy.io.loadmat("b.mat")
z = np.load("b.npz")  # no pickles needed
meta = json.load(open("b.json"))
for key in ["img", "target_mask", "target_names", "stimulus", "visual_size", "ppd", "shape",
            "seed", "light_direction", "depth", "normals", "shading"] + list(meta["parameters"]):
    assert key in m, ("mat", key)
    assert key in z.files, ("npz", key)
assert m["img"].shape == (100, 140) and z["img"].shape == (100, 140), m["img"].shape
assert np.array_equal(m["img"], z["img"])
assert m["target_mask"].shape == (100, 140) and set(np.unique(z["target_mask"])) == set(range(7))
assert m["shape"].tolist() == [[100, 140]] and z["shape"].tolist() == [100, 140]
assert m["visual_size"].tolist() == [[10, 14]] and z["visual_size"].tolist() == [10, 14]
assert m["ppd"].item() == 10 and z["ppd"].item() == 10
assert str(m["stimulus"][0]) == "bumps" and str(z["stimulus"]) == "bumps"
assert str(m["light"][0]) == meta["parameters"]["light"] == str(z["light"]) == "tilt=45,slant=54.73561"
names = [str(n[0]) for n in m["target_names"][0]]
assert names == [str(n) for n in z["target_names"]] == [t["name"] for t in meta["targets"]], names
assert m["rows"].item() == 2 and z["columns"].item() == 3
assert m["normals"].shape == (100, 140, 3) and z["normals"].shape == (100, 140, 3)
assert abs(np.linalg.norm(z["normals"][50, 70]) - 1) < 1e-6
assert np.allclose(z["light_direction"], np.array([-1, 1, 1]) / np.sqrt(3))
f = scipy.io.loadmat("f.mat")
assert f["img"].shape == (20, 40, 3), f["img"].shape
print("ok")
"#;
    let out = Command::new("python3")
        .args(["-c", script])
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).trim() == "ok",
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn octave_loads_the_mat_bundle() {
    let octave = ["octave-cli", "octave"].into_iter().find(|o| {
        Command::new(o)
            .arg("--version")
            .output()
            .is_ok_and(|out| out.status.success())
    });
    let Some(octave) = octave else {
        println!("skipped: no octave-cli or octave on PATH (Debian: apt-get install octave)");
        return;
    };
    let d = scratch("bundle-octave");
    render_bumps(&d, "b.mat", &[]);
    let script = "load('b.mat'); \
        assert(isequal(size(img), [100 140])); assert(isequal(size(target_mask), [100 140])); \
        assert(isequal(shape, [100 140])); assert(isequal(visual_size, [10 14])); \
        assert(ppd == 10); assert(strcmp(stimulus, 'bumps')); assert(strcmp(light, 'tilt=45,slant=54.73561')); \
        assert(iscell(target_names) && numel(target_names) == 6); \
        assert(isequal(size(normals), [100 140 3])); assert(rows == 2); disp('ok')";
    let out = Command::new(octave)
        .args([
            "--no-gui",
            "--quiet",
            "--no-window-system",
            "--eval",
            script,
        ])
        .current_dir(&d)
        .output()
        .unwrap();
    assert!(
        out.status.success() && String::from_utf8_lossy(&out.stdout).contains("ok"),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
