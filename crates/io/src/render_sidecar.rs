//! Reading the sidecar that `shadelab render` writes beside a picture (`X.png` → `X.json`):
//! what an analysis of that picture should know about it — its target mask and names, its
//! resolution, the albedo and ambient level it was rendered with, how its values were encoded
//! (display gamma, value range) and its true light. The writer is `stimulus::write_output`.

use crate::display::{Display, Luminance};
use crate::error::{Error, Result};
use crate::light::Light;
use serde::Serialize;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// The sidecar note (`notes.target_is_silhouette: true`) that says a stimulus's target mask is
/// an object's silhouette, its occluding outline against the background (the rendered
/// surfaces), not regions of a surface that goes on outside them (bumps, discs, a crater).
pub const SILHOUETTE_NOTE: &str = "target_is_silhouette";

/// What a shadelab render sidecar says about its picture.
///
/// ```
/// use shadelab_io::RenderSidecar;
/// use std::path::Path;
/// let text = r#"{"program": "shadelab", "stimulus": "crater", "ppd": 40.0,
///   "targets": [{"label": 1, "name": "crater"}, {"label": 2, "name": "mound"}],
///   "files": {"image": "c.png", "target_mask": "c_mask.png"}, "gamma": null,
///   "parameters": {"ambient": 0.1}, "notes": {"albedo": 0.5, "light_vector": [0.0, 0.6, 0.8]}}"#;
/// let value = serde_json::from_str(text).unwrap();
/// let s = RenderSidecar::from_value(Path::new("out/c.json"), &value).unwrap();
/// assert_eq!(s.target_names(), vec!["crater", "mound"]);
/// assert_eq!(s.target_mask.as_deref(), Some(Path::new("out/c_mask.png")));
/// assert_eq!((s.ppd, s.albedo, s.ambient), (Some(40.0), Some(0.5), Some(0.1)));
/// assert_eq!(s.light.unwrap().tilt_deg.round(), 0.0);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RenderSidecar {
    /// The sidecar file.
    pub path: PathBuf,
    /// The stimulus rendered, when recorded.
    pub stimulus: Option<String>,
    /// The target mask file, resolved against the sidecar's folder.
    pub target_mask: Option<PathBuf>,
    /// The targets: (label, name), labels 1..N.
    pub targets: Vec<(u16, String)>,
    /// Pixels per degree: the `ppd` key, or the height in pixels over the height in degrees
    /// (`shape`/`visual_size` as `[h, w]`, or `shape_px`/`visual_size_deg` objects).
    pub ppd: Option<f64>,
    /// The surface albedo (`parameters.albedo`, else `notes.albedo`).
    pub albedo: Option<f64>,
    /// The ambient level (`parameters.ambient`, else `notes.ambient`).
    pub ambient: Option<f64>,
    /// The display gamma the values were encoded with (undone by [`RenderSidecar::linearise`]).
    pub gamma: Option<f64>,
    /// The image file's own gAMA chunk says the gamma, so the reader undid it (and `gamma` is
    /// `None`): files written since shadelab wrote the chunk.
    pub gamma_decoded_by_file: bool,
    /// The PNG bit depth recorded (8 or 16), for reports.
    pub bit_depth: Option<u64>,
    /// Whether the values were mapped to -1..1 (PsychoPy's range; undone by
    /// [`RenderSidecar::linearise`]).
    pub psychopy_range: bool,
    /// The display whose codes the file holds and the luminance its 0..1 was shown at (undone
    /// by [`RenderSidecar::linearise`]: code → cd/m² → 0..1).
    #[serde(skip)]
    pub display: Option<(Display, Luminance)>,
    /// The light the picture was rendered under (`notes.light_vector`, else
    /// `parameters.light`).
    pub light: Option<TrueLight>,
    /// Every parameter, as recorded.
    pub parameters: Value,
    /// The stimulus's notes, as recorded.
    pub notes: Value,
    /// Whether the target mask is an object's silhouette against its background (an occluding
    /// outline, as for the rendered surfaces: `notes.target_is_silhouette`), rather than
    /// regions of a picture whose surface goes on outside them (bumps, discs, a crater).
    pub silhouette: bool,
    /// The picture file it records (`files.image`), when it says.
    #[serde(skip)]
    pub image: Option<String>,
    /// The whole record as read, so that what it records (the render, to make again) is taken
    /// from this one reading, never from the file again. Not written again with the record's
    /// summary (it is the file).
    #[serde(skip)]
    pub record: Value,
    /// The recorded picture's size (height, width), when it says.
    #[serde(skip)]
    pub shape: Option<(usize, usize)>,
}

/// The light a picture was rendered under, as reports record it beside the assumed one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TrueLight {
    /// Tilt, degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// Slant, degrees from the line of sight.
    pub slant_deg: f64,
    /// The unit vector toward the light (x right, y up, z toward the viewer).
    pub vector: [f64; 3],
}

impl TrueLight {
    /// The light as reports record it.
    pub fn of(light: &Light) -> TrueLight {
        let d = light.direction();
        TrueLight {
            tilt_deg: light.tilt_deg(),
            slant_deg: light.slant_deg(),
            vector: [d.x, d.y, d.z],
        }
    }
}

/// What a render declares about its surface and light: the albedo and ambient level (its
/// parameters first, then its notes) and the light (`notes.light_vector`, else
/// `parameters.light`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Declared {
    /// The surface albedo.
    pub albedo: Option<f64>,
    /// The ambient level.
    pub ambient: Option<f64>,
    /// The true light.
    pub light: Option<TrueLight>,
}

impl Declared {
    /// What `parameters` and `notes` (as a render records them) declare; a malformed
    /// `notes.light_vector` is an error.
    pub fn from_record(parameters: &Value, notes: &Value) -> std::result::Result<Declared, String> {
        let take = |key: &str| {
            parameters
                .get(key)
                .and_then(Value::as_f64)
                .or_else(|| notes.get(key).and_then(Value::as_f64))
        };
        let light = match notes.get("light_vector") {
            Some(v) => {
                let xyz: Option<Vec<f64>> = v
                    .as_array()
                    .map(|a| a.iter().filter_map(Value::as_f64).collect());
                match xyz.as_deref() {
                    Some(&[x, y, z]) => Some(TrueLight::of(
                        &Light::from_vector(x, y, z)
                            .map_err(|e| format!("notes.light_vector: {e}"))?,
                    )),
                    _ => return Err(format!("notes.light_vector {v} is not [x, y, z]")),
                }
            }
            None => parameters
                .get("light")
                .and_then(Value::as_str)
                .and_then(|text| text.parse::<Light>().ok())
                .map(|l| TrueLight::of(&l)),
        };
        Ok(Declared {
            albedo: take("albedo"),
            ambient: take("ambient"),
            light,
        })
    }
}

/// The sidecar's path for a picture: the same name with `.json`.
pub fn sidecar_path(image: &Path) -> PathBuf {
    image.with_extension("json")
}

/// What lies beside a picture.
#[derive(Debug, Clone, PartialEq)]
pub enum Beside {
    /// No `.json` beside it.
    Nothing,
    /// A JSON file that shadelab did not write (no `"program": "shadelab"`): ignored.
    Foreign(PathBuf),
    /// A shadelab render sidecar.
    Ours(Box<RenderSidecar>),
}

impl Beside {
    /// The sidecar, when it is shadelab's.
    pub fn sidecar(&self) -> Option<&RenderSidecar> {
        match self {
            Beside::Ours(s) => Some(s),
            _ => None,
        }
    }
}

impl RenderSidecar {
    /// This record of a picture whose own chunk states its encoding: the reader decodes it,
    /// so the recorded gamma is not undone a second time.
    pub(crate) fn decoded_by_file(&mut self) {
        if self.gamma.is_some() {
            self.gamma = None;
            self.gamma_decoded_by_file = true;
        }
    }

    /// Reads a sidecar file; an error unless it is a well-formed shadelab sidecar.
    pub fn read(path: &Path) -> Result<RenderSidecar> {
        let value = read_json(path)?;
        if value.get("program").and_then(Value::as_str) != Some("shadelab") {
            return Err(Error::format(
                path,
                "not a shadelab sidecar (no \"program\": \"shadelab\")",
            ));
        }
        Self::from_value(path, &value)
    }

    /// The sidecar `value`, read from `path` (relative file names resolve against its folder).
    pub fn from_value(path: &Path, value: &Value) -> Result<RenderSidecar> {
        let bad = |what: String| Error::format(path, what);
        let folder = path.parent().unwrap_or(Path::new(""));
        let target_mask = match value.pointer("/files/target_mask") {
            None | Some(Value::Null) => None,
            Some(Value::String(name)) => Some(folder.join(name)),
            Some(other) => {
                return Err(bad(format!("files.target_mask {other} is not a file name")))
            }
        };
        let mut targets = Vec::new();
        match value.get("targets") {
            None | Some(Value::Null) => {}
            Some(Value::Array(items)) => {
                for t in items {
                    let label = t.get("label").and_then(Value::as_u64);
                    let name = t.get("name").and_then(Value::as_str);
                    match (label, name) {
                        (Some(l @ 1..=65535), Some(n)) => targets.push((l as u16, n.to_string())),
                        _ => {
                            return Err(bad(format!(
                                "target {t} needs a label 1..65535 and a name"
                            )))
                        }
                    }
                }
            }
            Some(other) => return Err(bad(format!("targets {other} is not a list"))),
        }
        let number = |key: &str| -> Result<Option<f64>> {
            match value.get(key) {
                None | Some(Value::Null) => Ok(None),
                Some(v) => match v.as_f64() {
                    Some(x) if x.is_finite() && x > 0.0 => Ok(Some(x)),
                    _ => Err(bad(format!("{key} {v} is not a positive number"))),
                },
            }
        };
        let ppd = match number("ppd")? {
            Some(p) => Some(p),
            None => ppd_from_sizes(value),
        };
        let gamma = number("gamma")?;
        let bit_depth = match value.get("bit_depth") {
            None | Some(Value::Null) => None,
            Some(v) => match v.as_u64() {
                Some(d @ (8 | 16)) => Some(d),
                _ => return Err(bad(format!("bit_depth {v} is neither 8 nor 16"))),
            },
        };
        let psychopy_range = match value.get("range") {
            None | Some(Value::Null) => false,
            Some(Value::String(r)) if r == "0..1" => false,
            Some(Value::String(r)) if r == "-1..1" => true,
            Some(other) => {
                return Err(bad(format!(
                    "range {other} is neither \"0..1\" nor \"-1..1\""
                )))
            }
        };
        let display = match (value.get("display"), value.get("luminance")) {
            (None | Some(Value::Null), _) => None,
            (Some(d), Some(l)) => Some((
                Display::from_record(d).map_err(|e| bad(e.to_string()))?,
                Luminance::from_record(l).map_err(|e| bad(e.to_string()))?,
            )),
            (Some(_), None) => return Err(bad("a display without its luminance".into())),
        };
        let parameters = value.get("parameters").cloned().unwrap_or(json!({}));
        let notes = value.get("notes").cloned().unwrap_or(json!({}));
        let declared = Declared::from_record(&parameters, &notes).map_err(bad)?;
        Ok(RenderSidecar {
            path: path.to_path_buf(),
            stimulus: value
                .get("stimulus")
                .and_then(Value::as_str)
                .map(String::from),
            target_mask,
            targets,
            ppd,
            albedo: declared.albedo,
            ambient: declared.ambient,
            gamma,
            gamma_decoded_by_file: false,
            bit_depth,
            psychopy_range,
            display,
            light: declared.light,
            parameters,
            silhouette: notes
                .get(SILHOUETTE_NOTE)
                .and_then(Value::as_bool)
                .unwrap_or(false),
            notes,
            image: value
                .pointer("/files/image")
                .and_then(Value::as_str)
                .map(String::from),
            shape: recorded_shape(value),
            record: value.clone(),
        })
    }

    /// The target names by label (`names[l - 1]` names label `l`; a label the sidecar skips is
    /// "label l").
    pub fn target_names(&self) -> Vec<String> {
        let n = self.targets.iter().map(|t| t.0).max().unwrap_or(0) as usize;
        let mut names: Vec<String> = (1..=n).map(|l| format!("label {l}")).collect();
        for (label, name) in &self.targets {
            names[*label as usize - 1] = name.clone();
        }
        names
    }

    /// A stored value back to linear 0..1: PsychoPy's -1..1 mapped back, a display gamma
    /// undone (v^gamma).
    pub fn linearise(&self, v: f64) -> f64 {
        let v = if self.psychopy_range {
            (v + 1.0) / 2.0
        } else {
            v
        };
        if let Some((display, mapping)) = &self.display {
            // The code (10-bit codes are stored in 16 bits by bit replication), its luminance,
            // and where that lies between the cd/m² of 0 and 1 (within half a step of the
            // stimulus's value, so clamped to 0..1 at the ends).
            let code = (v.clamp(0.0, 1.0) * f64::from(display.top_code())).round() as u16;
            let (lo, hi) = mapping.span();
            return ((display.code_luminance(code) - lo) / (hi - lo)).clamp(0.0, 1.0);
        }
        match self.gamma {
            Some(g) => v.max(0.0).powf(g),
            None => v,
        }
    }

    /// The target mask when it is an object's silhouette ([`silhouette`](Self::silhouette)):
    /// the mask a solve of the picture takes as the object's.
    pub fn object_mask(&self) -> Option<&Path> {
        self.target_mask.as_deref().filter(|_| self.silhouette)
    }

    /// One line saying what an analysis takes from the sidecar, e.g. "read crater.json: mask
    /// crater_mask.png, 2 targets (crater, mound), ppd 40, albedo 0.566, ambient 0.1, light
    /// tilt 0 slant 45".
    pub fn summary(&self) -> String {
        let mut parts = Vec::new();
        if let Some(m) = &self.target_mask {
            parts.push(format!("mask {}", m.display()));
        }
        if !self.targets.is_empty() {
            let names: Vec<&str> = self.targets.iter().map(|t| t.1.as_str()).collect();
            let s = if names.len() == 1 { "" } else { "s" };
            parts.push(format!("{} target{s} ({})", names.len(), names.join(", ")));
        }
        if let Some(p) = self.ppd {
            parts.push(format!("ppd {}", round3(p)));
        }
        if let Some(a) = self.albedo {
            parts.push(format!("albedo {}", round3(a)));
        }
        if let Some(a) = self.ambient {
            parts.push(format!("ambient {}", round3(a)));
        }
        if let Some(g) = self.gamma {
            parts.push(format!("gamma {} (undone)", round3(g)));
        }
        if let Some((display, _)) = &self.display {
            parts.push(format!(
                "codes of the display '{}' (undone)",
                display.name()
            ));
        }
        if self.gamma_decoded_by_file {
            parts.push("gamma undone by the file's gAMA chunk".into());
        }
        if self.psychopy_range {
            parts.push("range -1..1 (mapped back to 0..1)".into());
        }
        if let Some(l) = &self.light {
            parts.push(format!(
                "light tilt {} slant {}",
                round3(l.tilt_deg),
                round3(l.slant_deg)
            ));
        }
        if parts.is_empty() {
            parts.push("nothing to take".into());
        }
        format!("read {}: {}", self.path.display(), parts.join(", "))
    }

    /// The sidecar as a report's input records it.
    pub fn to_json(&self) -> Value {
        serde_json::to_value(self).unwrap_or(Value::Null)
    }
}

/// The JSON in the file at `path`; an error naming it when it is not JSON.
pub(crate) fn read_json(path: &Path) -> Result<Value> {
    let bytes = super::read_bytes(path)?;
    serde_json::from_slice(&bytes)
        .map_err(|e| Error::format(path, format!("the sidecar is not valid JSON: {e}")))
}

/// `x` rounded to 3 decimals, without trailing zeros.
fn round3(x: f64) -> f64 {
    let r = (x * 1000.0).round() / 1000.0;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// The recorded size (height, width): `shape: [h, w]` or `shape_px: {height, width}`.
fn recorded_shape(value: &Value) -> Option<(usize, usize)> {
    let v = value.get("shape").or_else(|| value.get("shape_px"))?;
    let pair = match v.as_array() {
        Some(a) => (a.first()?.as_u64()?, a.get(1)?.as_u64()?),
        None => (v.get("height")?.as_u64()?, v.get("width")?.as_u64()?),
    };
    Some((pair.0 as usize, pair.1 as usize))
}

/// Pixels per degree from the recorded sizes: the height in pixels over the height in degrees.
/// Accepts stimupy's `shape: [h, w]` / `visual_size: [h, w]` and the objects
/// `shape_px: {height, width}` / `visual_size_deg: {height, width}`.
fn ppd_from_sizes(value: &Value) -> Option<f64> {
    let height = |v: Option<&Value>| -> Option<f64> {
        let v = v?;
        v.get("height")
            .and_then(Value::as_f64)
            .or_else(|| v.as_array()?.first()?.as_f64())
    };
    let px = height(value.get("shape").or_else(|| value.get("shape_px")))?;
    let deg = height(
        value
            .get("visual_size")
            .or_else(|| value.get("visual_size_deg")),
    )?;
    let ppd = px / deg;
    (ppd.is_finite() && ppd > 0.0).then_some(ppd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ppd_from_either_size_form() {
        let old = json!({"program": "shadelab", "shape_px": {"height": 240, "width": 120},
            "visual_size_deg": {"height": 6.0, "width": 3.0}});
        let new = json!({"program": "shadelab", "shape": [240, 120], "visual_size": [6.0, 3.0]});
        for v in [old, new] {
            let s = RenderSidecar::from_value(Path::new("a.json"), &v).unwrap();
            assert_eq!(s.ppd, Some(40.0));
        }
    }

    #[test]
    fn linearise_undoes_gamma_and_range() {
        let v = json!({"program": "shadelab", "gamma": 2.0, "range": "-1..1"});
        let s = RenderSidecar::from_value(Path::new("a.json"), &v).unwrap();
        assert_eq!(s.linearise(0.0), 0.25);
        assert_eq!(s.linearise(1.0), 1.0);
    }

    #[test]
    fn malformed_fields_name_the_file() {
        for bad in [
            json!({"program": "shadelab", "ppd": -3}),
            json!({"program": "shadelab", "targets": [{"label": 0, "name": "x"}]}),
            json!({"program": "shadelab", "range": "0..255"}),
            json!({"program": "shadelab", "notes": {"light_vector": [1, 2]}}),
        ] {
            let e = RenderSidecar::from_value(Path::new("dir/a.json"), &bad).unwrap_err();
            assert!(e.to_string().contains("dir/a.json"), "{e}");
        }
    }
}
