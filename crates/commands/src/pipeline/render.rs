//! `render` as a pipeline: one stimulus or surface, from its name (or a spec) and plain
//! parameter values, to a picture in memory ([`run`]), written with its sidecar (and mask and
//! layers) by [`RenderReport::write`]; and `list` and `describe`, what can be rendered and with
//! which parameters.
//!
//! ```
//! use shadelab::pipeline::render::{run, RenderConfig};
//! use shadelab::NoProgress;
//!
//! let mut config = RenderConfig::new("sphere");
//! config.size.set_shape((24, 32)); // (height, width), as stimupy's shape
//! config.validate().unwrap();
//! let report = run(&config, &NoProgress).unwrap();
//! assert_eq!((report.geometry.height, report.geometry.width), (24, 32));
//! assert_eq!(report.output.pixels.size(), (32, 24));
//! // Nothing is written until `write` is called.
//! assert!(!std::path::Path::new("sphere.png").exists());
//! ```

use crate::error::{Error, Result};
use crate::grid::Labels;
use crate::progress::Progress;
use crate::stimulus::{self, Edited, ExportOptions, Output, Pixels, Range, Request, Spec};
use crate::visual_size::{Geometry, SizeRequest};
use serde::Serialize;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// How to render: what, at which size and seed, and how to encode it (where is the
/// [`Output`](super::Output) given to [`RenderReport::write`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RenderConfig {
    /// The stimulus or surface (see [`list`]).
    pub stimulus: String,
    /// Parameter values, checked against the stimulus's declarations (see [`describe`]);
    /// missing ones take their defaults.
    pub params: Map<String, Value>,
    /// Size in pixels and/or degrees, (height, width) as in stimupy; what is not given comes
    /// from the stimulus's defaults (see [`SizeRequest`] for the rule).
    pub size: SizeRequest,
    /// Seed for random layouts (recorded in the sidecar).
    pub seed: u64,
    /// Bit depth, gamma, value range, display and layers of the files written.
    pub export: ExportOptions,
    /// The spec file this render was read from, if any: an input, never replaced.
    pub spec: Option<PathBuf>,
    /// The largest picture made, in pixels.
    pub max_pixels: usize,
}

impl RenderConfig {
    /// Renders `stimulus` with its defaults (size, parameters, seed 0).
    pub fn new(stimulus: impl Into<String>) -> RenderConfig {
        RenderConfig {
            stimulus: stimulus.into(),
            params: Map::new(),
            size: SizeRequest::default(),
            seed: 0,
            export: ExportOptions::default(),
            spec: None,
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
        }
    }

    /// Renders what a stimulus spec names (stimulus, parameters, size and seed).
    pub fn from_spec(spec: &Spec) -> RenderConfig {
        RenderConfig {
            params: spec.params.clone(),
            size: spec.size(),
            seed: spec.seed.unwrap_or(0),
            ..RenderConfig::new(spec.stimulus.clone())
        }
    }

    /// Renders what a spec file names: a stimulus spec ([`Spec`]), or a sidecar that
    /// shadelab wrote beside an earlier render. A sidecar records everything that render used —
    /// the stimulus, every parameter, the size in pixels and ppd, the seed, and how the files
    /// were written (bit depth, gamma, value range, layers) — so rendering it again to a file of
    /// the same name gives the same files, byte for byte.
    ///
    /// ```
    /// use shadelab::{NoProgress, Output, RenderConfig};
    /// let dir = std::env::temp_dir().join(format!("shadelab-doc-sidecar-{}", std::process::id()));
    /// std::fs::create_dir_all(dir.join("again"))?;
    /// let mut first = RenderConfig::new("bumps");
    /// first.size.ppd = Some(8.0);
    /// shadelab::render(&first, &NoProgress)?.write(&Output::new(dir.join("b.png")))?;
    /// let again = RenderConfig::from_spec_file(&dir.join("b.json"))?;
    /// let out = Output::new(dir.join("again/b.png")).reads(again.files());
    /// shadelab::render(&again, &NoProgress)?.write(&out)?;
    /// assert_eq!(std::fs::read(dir.join("b.png"))?, std::fs::read(dir.join("again/b.png"))?);
    /// assert_eq!(std::fs::read(dir.join("b.json"))?, std::fs::read(dir.join("again/b.json"))?);
    /// # std::fs::remove_dir_all(&dir)?;
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_spec_file(path: &Path) -> Result<RenderConfig> {
        let bytes = crate::io::read_bytes(path)?;
        let value: Value = serde_json::from_slice(&bytes)
            .map_err(|e| Error::format(path, format!("bad stimulus spec: {e}")))?;
        let is_sidecar = value.get("program").and_then(Value::as_str) == Some("shadelab")
            && value.get("parameters").is_some();
        if !is_sidecar {
            let spec: Spec = serde_json::from_value(value)
                .map_err(|e| Error::format(path, format!("bad stimulus spec: {e}")))?;
            return Ok(RenderConfig {
                spec: Some(path.to_path_buf()),
                ..RenderConfig::from_spec(&spec)
            });
        }
        // A shadelab sidecar describes its own set: rendering it again may replace it.
        from_sidecar(&value).map_err(|e| Error::format(path, format!("{e}")))
    }

    /// Renders what a shadelab sidecar already read records (`sidecar.record`, read from
    /// `sidecar.path`), as [`from_spec_file`](Self::from_spec_file) would from its file.
    pub fn from_sidecar_record(sidecar: &crate::io::RenderSidecar) -> Result<RenderConfig> {
        from_sidecar(&sidecar.record).map_err(|e| Error::format(&sidecar.path, format!("{e}")))
    }

    /// The files the render reads (its spec, if any), for [`Output::reads`](super::Output::reads).
    pub fn files(&self) -> Vec<PathBuf> {
        self.spec.iter().cloned().collect()
    }

    /// Sets the space of a figure drawn in one (`pq` or `fg`, the reflectance map's), the same
    /// as the parameter `space`; fails for a stimulus without that parameter.
    pub fn set_space(&mut self, space: &str) -> Result<()> {
        let has_space = stimulus::find(&self.stimulus)?
            .info()
            .params
            .iter()
            .any(|p| p.name == "space");
        if !has_space {
            return Err(Error::invalid(format!(
                "'{}' has no space parameter (only figures drawn in a space have one, e.g. reflectance-map)",
                self.stimulus
            )));
        }
        self.params.insert("space".into(), Value::from(space));
        Ok(())
    }

    /// Checks what needs no rendering: the stimulus exists. Parameters and size are checked
    /// when rendering resolves them, the export options against the output's format by
    /// [`RenderConfig::check_output`] and when writing.
    pub fn validate(&self) -> Result<()> {
        stimulus::find(&self.stimulus)?;
        Ok(())
    }

    /// Checks, before rendering, that the export options suit the format of `out` (`.png`,
    /// `.npy`, `.mat`, `.svg`).
    pub fn check_output(&self, out: &Path) -> Result<()> {
        self.export.check(out).map(drop)
    }
}

/// A rendered stimulus: what was resolved (for reports), and the picture itself.
#[derive(Debug, Clone, Serialize)]
pub struct RenderReport {
    /// The stimulus rendered.
    pub stimulus: String,
    /// Every parameter, defaults filled in.
    pub parameters: Value,
    /// The seed.
    pub seed: u64,
    /// Size in pixels and degrees.
    pub geometry: Geometry,
    /// Facts the stimulus recorded (e.g. the shared value of the checker squares).
    pub notes: Map<String, Value>,
    /// What the user should know though nothing failed, one line each: a visual size that
    /// whole pixels made smaller (stimupy's rounding down), a checkerboard's check that whole
    /// pixels changed (stimupy's rounding).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The resolved request.
    #[serde(skip)]
    pub request: Request,
    /// The picture, targets and layers.
    #[serde(skip)]
    pub output: Output,
    /// How the files are encoded ([`RenderConfig::export`]).
    #[serde(skip)]
    pub export: ExportOptions,
    /// Set when the picture is no longer the render ([`RenderReport::with_picture`]).
    #[serde(skip)]
    pub edited: Option<Edited>,
}

/// Renders the config's stimulus (nothing is written; see [`RenderReport::write`]).
pub fn run(config: &RenderConfig, progress: &dyn Progress) -> Result<RenderReport> {
    progress.start(1, "render");
    let rendered = stimulus::generate(
        &config.stimulus,
        &config.params,
        &config.size,
        config.seed,
        config.max_pixels,
    );
    progress.finish();
    let (request, output) = rendered?;
    let warnings = config
        .size
        .rounded_visual_size(&request.geometry)
        .map(|asked| stimulus::rounded_warning(&config.stimulus, &request.geometry, asked))
        .into_iter()
        .chain(
            output
                .notes
                .get(stimulus::CHECK_ROUNDED_NOTE)
                .and_then(|note| stimulus::rounded_check_warning(note, request.geometry.ppd)),
        )
        .collect();
    Ok(RenderReport {
        stimulus: config.stimulus.clone(),
        parameters: request.params.to_json(),
        seed: request.seed,
        geometry: request.geometry,
        notes: output.notes.clone(),
        warnings,
        request,
        output,
        export: config.export.clone(),
        edited: None,
    })
}

/// How far a value handed back may lie from the render's and still be the render: far below
/// every format's step (float32 at 1 is 6e-8 apart, 16-bit codes 1.5e-5), so that an array
/// that went through float64 arithmetic unchanged is not called edited.
const SAME_VALUE: f64 = 1e-9;

impl RenderReport {
    /// The render with the caller's picture in place of its own: `pixels` (in `range`, as
    /// the render was handed over) are what [`RenderReport::write`] writes. Where they are the
    /// render's (every value within 1e-9) nothing changes and the files are the render's,
    /// byte for byte; otherwise the report is marked [`Edited`] and its sidecar says so. The
    /// picture must have the render's size and channels and be linear luminance 0..1 without
    /// NaN, as every picture shadelab reads; `what` names it in errors.
    ///
    /// ```
    /// use shadelab::pipeline::render::{run, RenderConfig};
    /// use shadelab::stimulus::{Pixels, Range};
    /// let mut config = RenderConfig::new("bumps");
    /// config.size.set_shape((16, 24));
    /// let report = run(&config, &shadelab::NoProgress).unwrap();
    /// let Pixels::Gray(img) = &report.output.pixels else { unreachable!() };
    /// let same = report.clone().with_picture(Pixels::Gray(img.clone()), Range::Unit, "img").unwrap();
    /// assert!(same.edited.is_none());
    /// let halved = Pixels::Gray(img.map(|v| v * 0.5));
    /// let edited = report.with_picture(halved, Range::Unit, "img").unwrap();
    /// assert!(edited.edited.is_some());
    /// ```
    pub fn with_picture(
        mut self,
        pixels: Pixels,
        range: Range,
        what: &str,
    ) -> Result<RenderReport> {
        let ((w, h), (rw, rh)) = (pixels.size(), self.output.pixels.size());
        let pixels = match (pixels, &self.output.pixels) {
            (Pixels::Gray(i), Pixels::Gray(_)) => Pixels::Gray(i.map(|&v| range.to_unit(v))),
            (Pixels::Rgb(i), Pixels::Rgb(_)) => Pixels::Rgb(i.map(|p| p.map(|v| range.to_unit(v)))),
            (given, _) => {
                let channels = |p: &Pixels| match p {
                    Pixels::Gray(_) => "gray (height × width)",
                    Pixels::Rgb(_) => "RGB (height × width × 3)",
                };
                return Err(Error::invalid(format!(
                    "{what}: the picture is {} but {} renders {}",
                    channels(&given),
                    self.stimulus,
                    channels(&self.output.pixels)
                )));
            }
        };
        if (w, h) != (rw, rh) {
            return Err(Error::invalid(format!(
                "{what}: the picture is {h} high × {w} wide but the render it records is {rh} \
                 high × {rw} wide"
            )));
        }
        let (values, channels): (&[f64], usize) = match &pixels {
            Pixels::Gray(i) => (i.data(), 1),
            Pixels::Rgb(i) => (i.data().as_flattened(), 3),
        };
        crate::io::check_values(values, channels, w, what)?;
        let rendered: &[f64] = match &self.output.pixels {
            Pixels::Gray(i) => i.data(),
            Pixels::Rgb(i) => i.data().as_flattened(),
        };
        let same = values
            .iter()
            .zip(rendered)
            .all(|(a, b)| (a - b).abs() <= SAME_VALUE);
        if !same {
            self.edited.get_or_insert_with(Edited::default).rendered_md5 =
                Some(stimulus::pixels_md5(&self.output.pixels));
            self.output.pixels = pixels;
        }
        Ok(self)
    }

    /// The render with the caller's target mask in place of its own: `labels` (0 the
    /// background, `k` the target `names[k - 1]`) are the mask [`RenderReport::write`] writes,
    /// and the targets the sidecar describes. Where they are the render's (the same labels and
    /// names, or no targets and an all-zero mask, stimupy's habit) nothing changes; otherwise
    /// the report is marked [`Edited`] (`target_mask`). `what` names the mask in errors.
    ///
    /// ```
    /// use shadelab::pipeline::render::{run, RenderConfig};
    /// let mut config = RenderConfig::new("bumps");
    /// config.size.set_shape((16, 24));
    /// let report = run(&config, &shadelab::NoProgress).unwrap();
    /// let targets = report.output.targets.clone().unwrap();
    /// let same = report.clone().with_targets(targets.labels.clone(), targets.names.clone(), "target_mask").unwrap();
    /// assert!(same.edited.is_none());
    /// let cleared = targets.labels.map(|_| 0);
    /// let edited = report.with_targets(cleared, targets.names, "target_mask").unwrap();
    /// assert!(edited.edited.unwrap().target_mask);
    /// ```
    pub fn with_targets(
        mut self,
        labels: Labels,
        names: Vec<String>,
        what: &str,
    ) -> Result<RenderReport> {
        let ((w, h), (rw, rh)) = ((labels.width(), labels.height()), self.output.pixels.size());
        if (w, h) != (rw, rh) {
            return Err(Error::invalid(format!(
                "{what}: the mask is {h} high × {w} wide but the render it records is {rh} \
                 high × {rw} wide"
            )));
        }
        let top = labels.data().iter().copied().max().unwrap_or(0);
        if usize::from(top) > names.len() {
            return Err(Error::invalid(format!(
                "{what}: label {top} has no name ({} target names given)",
                names.len()
            )));
        }
        let same = match &self.output.targets {
            Some(t) => t.labels == labels && t.names == names,
            None => top == 0,
        };
        if !same {
            self.edited.get_or_insert_with(Edited::default).target_mask = true;
            self.output.targets = Some(stimulus::Targets { labels, names });
        }
        Ok(self)
    }

    /// Writes the render to the file `out` (`.png`, `.npy`, `.mat` or `.svg`) with its sidecar,
    /// mask and (if asked) layers, whole or not at all (see [`stimulus::write_output`]); a file
    /// shadelab did not write is replaced only with [`Output::force`](super::Output::force), and
    /// never one of [`Output::reads`](super::Output::reads) (a spec beside the render whose
    /// sidecar would take its name). Returns every file written.
    pub fn write(&self, out: &super::Output) -> Result<Vec<PathBuf>> {
        let sidecar = crate::io::render_sidecar::sidecar_path(out.path());
        // The files already there under the names written, each resolved once.
        let replaced: Vec<PathBuf> = [out.path(), sidecar.as_path()]
            .iter()
            .filter_map(|p| std::fs::canonicalize(p).ok())
            .collect();
        let is_replaced =
            |input: &&PathBuf| std::fs::canonicalize(input).is_ok_and(|c| replaced.contains(&c));
        if let Some(input) = out.inputs().iter().find(is_replaced) {
            return Err(Error::format(
                input,
                "is the spec this render reads, and the render's files would replace it (even \
                 when forced): give the output another name",
            ));
        }
        stimulus::write_output(
            &self.stimulus,
            &self.request,
            &self.output,
            out.path(),
            &self.export,
            out.forced(),
            self.edited.as_ref(),
        )
    }
}

/// One stimulus of [`list`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Its name.
    pub name: &'static str,
    /// What it shows, in one line.
    pub summary: &'static str,
}

/// Everything that can be rendered, in the library's order.
///
/// ```
/// let all = shadelab::pipeline::render::list();
/// assert!(all.iter().any(|s| s.name == "bumps"));
/// ```
pub fn list() -> Vec<Summary> {
    stimulus::all()
        .iter()
        .map(|s| {
            let info = s.info();
            Summary {
                name: info.name,
                summary: info.summary,
            }
        })
        .collect()
}

/// One parameter of a [`Description`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamDescription {
    /// The key (as in a spec's `params`).
    pub name: &'static str,
    /// Its default value.
    pub default: Value,
    /// The range or the choices, as text.
    pub range: String,
    /// What it is, with its unit.
    pub doc: &'static str,
}

/// A stimulus's parameters with their defaults and ranges, and its default size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Description {
    /// Its name.
    pub name: &'static str,
    /// What it shows, in one line.
    pub summary: &'static str,
    /// Default (height, width) in degrees, as stimupy's `visual_size`.
    pub default_visual_size: (f64, f64),
    /// Default pixels per degree.
    pub default_ppd: f64,
    /// Its parameters.
    pub params: Vec<ParamDescription>,
    /// stimupy's names it accepts for its parameters: stimupy's → shadelab's
    /// (docs/python.md lists them).
    pub stimupy_names: std::collections::BTreeMap<&'static str, &'static str>,
}

/// Describes the stimulus `name` (an unknown name lists the valid ones).
///
/// ```
/// let d = shadelab::pipeline::render::describe("bumps").unwrap();
/// assert_eq!(d.name, "bumps");
/// assert!(d.params.iter().any(|p| p.name == "rows"));
/// assert!(shadelab::pipeline::render::describe("teapot").is_err());
/// ```
pub fn describe(name: &str) -> Result<Description> {
    let info = stimulus::find(name)?.info();
    Ok(Description {
        name: info.name,
        summary: info.summary,
        default_visual_size: info.default_visual_size,
        default_ppd: info.default_ppd,
        params: info
            .params
            .iter()
            .map(|p| ParamDescription {
                name: p.name,
                default: p.default.clone(),
                range: p.range_text(),
                doc: p.doc,
            })
            .collect(),
        stimupy_names: stimulus::stimupy_names::ALIASES
            .iter()
            .filter(|a| a.stimulus == info.name)
            .map(|a| (a.stimupy, a.shadelab))
            .collect(),
    })
}

/// The render a sidecar records.
fn from_sidecar(v: &Value) -> Result<RenderConfig> {
    if v.get(stimulus::EDITED_KEY).is_some_and(|e| !e.is_null()) {
        return Err(Error::invalid(
            "records a picture edited after rendering: rendering it again gives the render, \
             not that picture (render the stimulus from its parameters under another name)",
        ));
    }
    let field = |key: &str| {
        v.get(key)
            .ok_or_else(|| Error::invalid(format!("the sidecar has no '{key}'")))
    };
    let bad =
        |key: &str| Error::invalid(format!("the sidecar's '{key}' is not what shadelab writes"));
    let stimulus = field("stimulus")?.as_str().ok_or_else(|| bad("stimulus"))?;
    let params = field("parameters")?
        .as_object()
        .ok_or_else(|| bad("parameters"))?
        .clone();
    let seed = field("seed")?.as_u64().ok_or_else(|| bad("seed"))?;
    let ppd = field("ppd")?.as_f64().ok_or_else(|| bad("ppd"))?;
    let shape = sidecar_shape(v).ok_or_else(|| bad("shape"))?;
    let bit_depth = match v.get("bit_depth") {
        Some(Value::Number(n)) if n.as_u64() == Some(8) => crate::io::BitDepth::Eight,
        Some(Value::Number(n)) if n.as_u64() == Some(16) => crate::io::BitDepth::Sixteen,
        None | Some(Value::Null) => crate::io::BitDepth::Sixteen,
        Some(_) => return Err(bad("bit_depth")),
    };
    let gamma = match v.get("gamma") {
        None | Some(Value::Null) => None,
        Some(g) => Some(g.as_f64().ok_or_else(|| bad("gamma"))?),
    };
    let range = match v.get("range").and_then(Value::as_str) {
        None | Some("0..1") => stimulus::Range::Unit,
        Some("-1..1") => stimulus::Range::Psychopy,
        Some(_) => return Err(bad("range")),
    };
    let display = match v.get("display") {
        None | Some(Value::Null) => None,
        Some(d) => Some(crate::display::Display::from_record(d)?),
    };
    let luminance = match v.get("luminance") {
        Some(l) if display.is_some() => Some(crate::display::Luminance::from_record(l)?),
        _ => None,
    };
    let layers = v
        .get("files")
        .and_then(Value::as_object)
        .is_some_and(|f| f.contains_key("depth"));
    Ok(RenderConfig {
        params,
        size: SizeRequest {
            visual_size: None,
            ppd: Some(ppd),
            shape: Some(shape),
        },
        seed,
        export: ExportOptions {
            bit_depth,
            gamma,
            range,
            layers,
            display,
            luminance,
        },
        ..RenderConfig::new(stimulus)
    })
}

/// A sidecar's size in pixels, (height, width): `"shape": [h, w]` as shadelab writes it now,
/// or the `"shape_px": {"width": w, "height": h}` of sidecars written before.
fn sidecar_shape(v: &Value) -> Option<(usize, usize)> {
    let px = |n: Option<&Value>| n?.as_u64().and_then(|n| usize::try_from(n).ok());
    match (v.get("shape"), v.get("shape_px")) {
        (Some(Value::Array(hw)), _) if hw.len() == 2 => Some((px(hw.first())?, px(hw.get(1))?)),
        (None, Some(old)) => Some((px(old.get("height"))?, px(old.get("width"))?)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;

    #[test]
    fn configs_are_checked_and_specs_fill_them() {
        assert!(RenderConfig::new("teapot").validate().is_err());
        let mut config = RenderConfig::new("sphere");
        assert!(config.check_output(Path::new("a.tiff")).is_err());
        assert!(config.check_output(Path::new("a.png")).is_ok());
        let e = config.set_space("fg").unwrap_err().to_string();
        assert!(e.contains("'sphere' has no space parameter"), "{e}");
        assert!(!e.contains("--"), "{e}");
        let mut figure = RenderConfig::new("reflectance-map");
        figure.set_space("fg").unwrap();
        assert_eq!(figure.params["space"], "fg");
        let spec: Spec =
            serde_json::from_str(r#"{"stimulus": "sphere", "shape": [20, 10], "seed": 7}"#)
                .unwrap();
        config = RenderConfig::from_spec(&spec);
        assert_eq!((config.seed, config.size.shape), (7, Some((20, 10))));
        let report = run(&config, &NoProgress).unwrap();
        // (height, width): 20 rows of 10 pixels; `Pixels::size` is (width, height).
        assert_eq!(report.output.pixels.size(), (10, 20));
        let json = serde_json::to_value(&report).unwrap();
        assert_eq!(json["stimulus"], "sphere");
        assert_eq!(
            (&json["geometry"]["height"], &json["geometry"]["width"]),
            (&20.into(), &10.into())
        );
    }

    #[test]
    fn list_and_describe_agree_with_the_library() {
        let all = list();
        assert_eq!(all.len(), stimulus::names().len());
        for s in &all {
            let d = describe(s.name).unwrap();
            assert_eq!((d.name, d.summary), (s.name, s.summary));
        }
    }
}
