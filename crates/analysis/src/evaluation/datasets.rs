//! The evaluation data: which files each set needs, and loading them into the crate's
//! conventions (x right, y up, z toward the viewer; row 0 at the top; lights toward the light).
//!
//! The layout is that of the shared data folder (its README describes the sources):
//!
//! | set | files |
//! |---|---|
//! | bunny | `bunny/bun_zipper_res2.ply` |
//! | mozart | `mozart/depth.npy`, `mozart/mask.png` |
//! | diligent | `diligent_normals/<object>/normal_map.png`, `mask.png` for the nine objects |
//! | ball | `diligent_ball/<image>.png`, `mask.png`, `normals_gt.npy`, `lights.json` |
//! | beethoven | `beethoven/image0..2.png`, `mask.png`, `lights.json` |

use super::holes::{fill_enclosed_holes, FilledDepth};
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask, DEFAULT_MAX_PIXELS, LUMINANCE_WEIGHTS};
use crate::io::{self, InputEncoding};
use crate::light::Light;
use crate::surface::{Mesh, Surface};
use nalgebra::{Rotation3, Vector3};
use serde_json::Value;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// One data set of the evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Set {
    /// The Stanford bunny mesh, rendered under several lights.
    Bunny,
    /// The Mozart depth map of the 1999 survey, rendered and solved.
    Mozart,
    /// The true normals of the nine DiLiGenT objects, rendered under one light.
    Diligent,
    /// Photographs of the DiLiGenT ball with its true normals.
    Ball,
    /// Photographs of the Beethoven bust (no ground truth).
    Beethoven,
}

/// Every set, in the order the evaluation runs them.
pub const SETS: [Set; 5] = [
    Set::Bunny,
    Set::Mozart,
    Set::Diligent,
    Set::Ball,
    Set::Beethoven,
];

/// The names of the sets, as `--only` spells them.
pub const SET_NAMES: &[&str] = &["bunny", "mozart", "diligent", "ball", "beethoven"];

/// The nine DiLiGenT objects whose normal maps the data folder holds.
pub const DILIGENT_OBJECTS: &[&str] = &[
    "bear", "buddha", "cat", "cow", "goblet", "harvest", "pot1", "pot2", "reading",
];

/// The DiLiGenT ball photographs: `052` near-frontal (4°), `076`, `008`, `029`, `049` about
/// 26° toward +x, +y, −x, −y, and `041` at 43°.
pub const BALL_IMAGES: &[&str] = &["052", "076", "008", "029", "049", "041"];

/// The Beethoven photographs.
pub const BEETHOVEN_IMAGES: &[&str] = &["image0", "image1", "image2"];

/// The bunny mesh file inside the data folder.
pub const BUNNY_MESH: &str = "bunny/bun_zipper_res2.ply";

impl Set {
    /// The set's name.
    pub fn name(self) -> &'static str {
        SET_NAMES[self as usize]
    }

    /// The files this set reads, relative to the data folder, for the chosen DiLiGenT objects
    /// and ball images.
    pub fn files(self, objects: &[String], ball_images: &[String]) -> Vec<PathBuf> {
        let p = |s: String| PathBuf::from(s);
        match self {
            Set::Bunny => vec![p(BUNNY_MESH.into())],
            Set::Mozart => vec![p("mozart/depth.npy".into()), p("mozart/mask.png".into())],
            Set::Diligent => objects
                .iter()
                .flat_map(|o| {
                    [
                        p(format!("diligent_normals/{o}/normal_map.png")),
                        p(format!("diligent_normals/{o}/mask.png")),
                    ]
                })
                .collect(),
            Set::Ball => {
                let mut v = vec![
                    p("diligent_ball/mask.png".into()),
                    p("diligent_ball/normals_gt.npy".into()),
                    p("diligent_ball/lights.json".into()),
                ];
                v.extend(
                    ball_images
                        .iter()
                        .map(|i| p(format!("diligent_ball/{i}.png"))),
                );
                v
            }
            Set::Beethoven => {
                let mut v = vec![
                    p("beethoven/mask.png".into()),
                    p("beethoven/lights.json".into()),
                ];
                v.extend(
                    BEETHOVEN_IMAGES
                        .iter()
                        .map(|i| p(format!("beethoven/{i}.png"))),
                );
                v
            }
        }
    }
}

impl FromStr for Set {
    type Err = Error;
    fn from_str(name: &str) -> Result<Set> {
        SET_NAMES
            .iter()
            .position(|&n| n == name)
            .map(|i| SETS[i])
            .ok_or_else(|| Error::unknown("evaluation set", name, SET_NAMES))
    }
}

impl fmt::Display for Set {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Checks that the data folder exists and holds every file the chosen sets read, before any
/// work is done; the error names the first thing missing.
pub fn check_files(
    data: &Path,
    sets: &[Set],
    objects: &[String],
    ball_images: &[String],
) -> Result<()> {
    if !data.is_dir() {
        return Err(Error::format(
            data,
            "evaluation data folder not found (expected a folder holding bunny/, mozart/, \
             diligent_normals/, diligent_ball/ and beethoven/, laid out as its README \
             describes)",
        ));
    }
    for &set in sets {
        for file in set.files(objects, ball_images) {
            let path = data.join(&file);
            if !path.is_file() {
                return Err(Error::format(
                    &path,
                    format!(
                        "missing: the {set} set expects {} in the data folder",
                        file.display()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The bunny mesh rasterised into a `size` × `size` frame, seen from the front (the mesh's own
/// axes), filling 85 % of the frame; normals are the mesh's interpolated vertex normals.
pub fn bunny(data: &Path, size: usize) -> Result<Surface> {
    let mesh = Mesh::load(data.join(BUNNY_MESH))?;
    mesh.rasterize(size, size, &Rotation3::identity(), 0.85)
}

/// A depth map with its holes filled (see [`super::holes`]) and the mask of pixels whose true
/// depth is known.
#[derive(Debug, Clone, PartialEq)]
pub struct DepthSet {
    /// The depth (pixels toward the viewer) with holes interpolated.
    pub filled: FilledDepth,
    /// Where the depth was measured (the mask file, holes excluded).
    pub measured: Mask,
}

/// The Mozart depth map and mask; enclosed zero-depth holes are filled for the solver and
/// left out of the errors.
pub fn mozart(data: &Path) -> Result<DepthSet> {
    let depth_path = data.join("mozart/depth.npy");
    let mask_path = data.join("mozart/mask.png");
    let depth = io::read_image(&depth_path, DEFAULT_MAX_PIXELS)?;
    let mask = io::read_mask(&mask_path, DEFAULT_MAX_PIXELS)?;
    same_size(&depth, &mask, &depth_path, &mask_path)?;
    // The mask file marks the non-zero depths; a pixel of depth 0 inside it is a hole too.
    let measured = Grid::from_fn(mask.width(), mask.height(), |c, r| {
        *mask.get(c, r) && *depth.get(c, r) != 0.0
    });
    non_empty(&measured, &mask_path)?;
    Ok(DepthSet {
        filled: fill_enclosed_holes(&depth, &measured),
        measured,
    })
}

/// True normals and the object's mask.
#[derive(Debug, Clone, PartialEq)]
pub struct NormalSet {
    /// Unit normals inside the mask, (0, 0, 1) outside.
    pub normals: Grid<Normal>,
    /// The object.
    pub mask: Mask,
}

/// The normal map of a DiLiGenT object: 16-bit RGB, n = v/65535·2 − 1 (R = x, G = y, B = z),
/// normalised; pixels whose decoded vector is zero leave the mask.
pub fn diligent_object(data: &Path, object: &str) -> Result<NormalSet> {
    let dir = data.join("diligent_normals").join(object);
    let (map_path, mask_path) = (dir.join("normal_map.png"), dir.join("mask.png"));
    let rgb = io::read_rgb_as(&map_path, DEFAULT_MAX_PIXELS, InputEncoding::Linear)?;
    let mask = io::read_mask(&mask_path, DEFAULT_MAX_PIXELS)?;
    same_size(&rgb, &mask, &map_path, &mask_path)?;
    let decoded = rgb.map(|v| Vector3::new(2.0 * v[0] - 1.0, 2.0 * v[1] - 1.0, 2.0 * v[2] - 1.0));
    let set = unit_normals(&decoded, &mask);
    non_empty(&set.mask, &mask_path)?;
    Ok(set)
}

/// A photograph with its calibrated light, already divided by the light's intensity.
#[derive(Debug, Clone, PartialEq)]
pub struct Photo {
    /// The image's name (its file stem).
    pub name: String,
    /// Calibrated gray image (linear).
    pub image: Image,
    /// The light, as calibrated.
    pub light: Light,
}

/// The DiLiGenT ball: its true normals and mask, and the chosen photographs.
#[derive(Debug, Clone, PartialEq)]
pub struct Ball {
    /// True normals and the ball's mask.
    pub truth: NormalSet,
    /// The photographs, in the order asked for.
    pub photos: Vec<Photo>,
}

/// Loads the DiLiGenT ball with the photographs `images` (names without `.png`).
pub fn ball(data: &Path, images: &[String]) -> Result<Ball> {
    let dir = data.join("diligent_ball");
    let mask_path = dir.join("mask.png");
    let normals_path = dir.join("normals_gt.npy");
    let lights_path = dir.join("lights.json");
    let mask = io::read_mask(&mask_path, DEFAULT_MAX_PIXELS)?;
    let (w, h) = (mask.width(), mask.height());
    let array = io::read_array(&normals_path, DEFAULT_MAX_PIXELS)?;
    if array.shape != [h, w, 3] {
        return Err(Error::format(
            &normals_path,
            format!(
                "expected an {h}×{w}×3 normal map (the size of {}), found shape {:?}",
                mask_path.display(),
                array.shape
            ),
        ));
    }
    let raw = Grid::from_vec(
        w,
        h,
        array
            .data
            .chunks_exact(3)
            .map(|c| Vector3::new(c[0], c[1], c[2]))
            .collect(),
    )?;
    let truth = unit_normals(&raw, &mask);
    non_empty(&truth.mask, &mask_path)?;
    let lights = read_json(&lights_path)?;
    let mut photos = Vec::with_capacity(images.len());
    for name in images {
        let file = format!("{name}.png");
        let entry = lights
            .get(&file)
            .ok_or_else(|| Error::format(&lights_path, format!("has no entry for {file}")))?;
        let light = json_light(entry, &lights_path, &file)?;
        let intensity = json_numbers::<3>(entry, "intensity_rgb", &lights_path, &file)?;
        if intensity.iter().any(|&v| !(v.is_finite() && v > 0.0)) {
            return Err(Error::format(
                &lights_path,
                format!("{file}: intensity_rgb must be three positive numbers"),
            ));
        }
        let path = dir.join(&file);
        // 16-bit linear photographs (DiLiGenT's calibration divides them by the light).
        let rgb = io::read_rgb_as(&path, DEFAULT_MAX_PIXELS, InputEncoding::Linear)?;
        same_size(&rgb, &mask, &path, &mask_path)?;
        // Calibrated: each channel divided by the light's intensity_rgb, then the crate's
        // Rec. 709 luminance weights.
        let image = rgb.map(|v| {
            (0..3)
                .map(|k| LUMINANCE_WEIGHTS[k] * v[k] / intensity[k])
                .sum::<f64>()
        });
        photos.push(Photo {
            name: name.clone(),
            image,
            light,
        });
    }
    Ok(Ball { truth, photos })
}

/// The Beethoven photographs (each divided by its light's relative intensity) and mask.
#[derive(Debug, Clone, PartialEq)]
pub struct Beethoven {
    /// The bust.
    pub mask: Mask,
    /// `image0..2`.
    pub photos: Vec<Photo>,
}

/// Loads the Beethoven photographs.
pub fn beethoven(data: &Path) -> Result<Beethoven> {
    let dir = data.join("beethoven");
    let mask_path = dir.join("mask.png");
    let lights_path = dir.join("lights.json");
    let mask = io::read_mask(&mask_path, DEFAULT_MAX_PIXELS)?;
    non_empty(&mask, &mask_path)?;
    let lights = read_json(&lights_path)?;
    let mut photos = Vec::new();
    for name in BEETHOVEN_IMAGES {
        let file = format!("{name}.png");
        let entry = lights
            .get(&file)
            .ok_or_else(|| Error::format(&lights_path, format!("has no entry for {file}")))?;
        let light = json_light(entry, &lights_path, &file)?;
        let [intensity] = json_numbers::<1>(entry, "intensity", &lights_path, &file)?;
        if !(intensity.is_finite() && intensity > 0.0) {
            return Err(Error::format(
                &lights_path,
                format!("{file}: intensity must be a positive number"),
            ));
        }
        let path = dir.join(&file);
        // 8-bit codes without a gamma chunk that are linear measurements, not sRGB: said
        // explicitly, since the default rule decodes such a picture as sRGB.
        let (image, _) = io::read_gray_as(&path, DEFAULT_MAX_PIXELS, InputEncoding::Linear)?;
        same_size(&image, &mask, &path, &mask_path)?;
        photos.push(Photo {
            name: name.to_string(),
            image: image.map(|v| v / intensity),
            light,
        });
    }
    Ok(Beethoven { mask, photos })
}

/// Normalises `raw` inside `mask`; pixels whose vector is (nearly) zero or not finite leave
/// the mask.
fn unit_normals(raw: &Grid<Vector3<f64>>, mask: &Mask) -> NormalSet {
    let usable = |v: &Vector3<f64>| v.iter().all(|c| c.is_finite()) && v.norm() > 1e-6;
    let mask = Grid::from_fn(mask.width(), mask.height(), |c, r| {
        *mask.get(c, r) && usable(raw.get(c, r))
    });
    let normals = Grid::from_fn(mask.width(), mask.height(), |c, r| {
        if *mask.get(c, r) {
            raw.get(c, r).normalize()
        } else {
            Vector3::z()
        }
    });
    NormalSet { normals, mask }
}

fn same_size<A, B>(a: &Grid<A>, b: &Grid<B>, a_path: &Path, b_path: &Path) -> Result<()> {
    if a.same_size(b) {
        Ok(())
    } else {
        Err(Error::format(
            a_path,
            format!(
                "is {} but {} is {}",
                crate::message::SizeText::Pixels(a.height(), a.width()),
                b_path.display(),
                crate::message::SizeText::Pixels(b.height(), b.width())
            ),
        ))
    }
}

fn non_empty(mask: &Mask, path: &Path) -> Result<()> {
    if mask.count() == 0 {
        Err(Error::format(path, "the mask is empty"))
    } else {
        Ok(())
    }
}

fn read_json(path: &Path) -> Result<Value> {
    let bytes = io::read_bytes(path)?;
    serde_json::from_slice(&bytes).map_err(|e| Error::format(path, format!("not valid JSON ({e})")))
}

fn json_numbers<const N: usize>(
    entry: &Value,
    key: &str,
    path: &Path,
    file: &str,
) -> Result<[f64; N]> {
    let bad = || {
        Error::format(
            path,
            format!(
                "{file}: '{key}' must be {N} number{}",
                if N == 1 { "" } else { "s" }
            ),
        )
    };
    let values: Vec<f64> = match entry.get(key) {
        Some(Value::Array(items)) => items.iter().map(Value::as_f64).collect::<Option<_>>(),
        Some(v) if N == 1 => v.as_f64().map(|x| vec![x]),
        _ => None,
    }
    .ok_or_else(bad)?;
    values.try_into().map_err(|_| bad())
}

fn json_light(entry: &Value, path: &Path, file: &str) -> Result<Light> {
    let [x, y, z] = json_numbers::<3>(entry, "direction", path, file)?;
    Light::from_vector(x, y, z).map_err(|e| Error::format(path, format!("{file}: direction: {e}")))
}
