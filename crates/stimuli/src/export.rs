//! Writing a rendered stimulus: the picture in the format its extension names (.png, .npy,
//! .svg, or a `.mat`/`.npz` bundle of picture, mask and every parameter: see [`super::bundle`]),
//! the target mask, the ground-truth layers and a JSON sidecar recording every parameter.

use super::{Output, Pixels, Request};
use crate::display::{Display, Luminance, Shown};
use crate::error::{Error, Result};
use crate::io::{self, BitDepth};
use serde_json::{json, Map, Value};
use std::fs;
use std::path::{Path, PathBuf};

/// The value range of float outputs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    /// Linear luminance 0..1.
    Unit,
    /// PsychoPy's −1..1 (v·2 − 1), for float formats.
    Psychopy,
}

impl Range {
    /// A linear value 0..1 in this range.
    pub fn apply(self, v: f64) -> f64 {
        match self {
            Range::Unit => v,
            Range::Psychopy => v * 2.0 - 1.0,
        }
    }

    /// A value in this range as linear 0..1 (the inverse of [`Range::apply`]).
    pub fn to_unit(self, v: f64) -> f64 {
        match self {
            Range::Unit => v,
            Range::Psychopy => (v + 1.0) / 2.0,
        }
    }
}

/// How to write a stimulus.
#[derive(Debug, Clone, PartialEq)]
pub struct ExportOptions {
    /// Bits per channel of PNG output.
    pub bit_depth: BitDepth,
    /// Display gamma applied to PNG output (recorded); `None` writes linear values.
    pub gamma: Option<f64>,
    /// Value range for float formats.
    pub range: Range,
    /// Also write the ground-truth layers (depth, normals, albedo, shading).
    pub layers: bool,
    /// Write the codes of this display (PNG only): the stimulus shown through its inverse
    /// response at the luminances of `luminance`, at the display's bit depth.
    pub display: Option<Display>,
    /// The cd/m² the stimulus's 0..1 is shown at (with `display`; default: the display's black
    /// to white).
    pub luminance: Option<Luminance>,
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions {
            bit_depth: BitDepth::Sixteen,
            gamma: None,
            range: Range::Unit,
            layers: false,
            display: None,
            luminance: None,
        }
    }
}

impl ExportOptions {
    /// Checks that these options can write `path`: a known format (by extension), a PsychoPy range
    /// only for float formats, a gamma only for PNG. Returns the format (the lower-case extension).
    ///
    /// ```
    /// use shadelab::stimulus::{ExportOptions, Range};
    /// use std::path::Path;
    /// let options = ExportOptions::default();
    /// assert_eq!(options.check(Path::new("a.PNG")).unwrap(), "png");
    /// assert!(options.check(Path::new("a.tiff")).is_err());
    /// let psychopy = ExportOptions { range: Range::Psychopy, ..options };
    /// assert!(psychopy.check(Path::new("a.png")).is_err());
    /// assert!(psychopy.check(Path::new("a.npy")).is_ok());
    /// ```
    pub fn check(&self, path: &Path) -> Result<String> {
        let ext = io::extension(path);
        if !FORMATS.contains(&ext.as_str()) {
            return Err(Error::invalid(format!(
                "{}: unknown output format '.{ext}' (use one of: {})",
                path.display(),
                FORMATS
                    .iter()
                    .map(|f| format!(".{f}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
        self.check_range(path)?;
        self.check_gamma(path)?;
        self.check_display(path)?;
        Ok(ext)
    }

    /// A display's codes for a file named `path`: PNG only, and the display options
    /// themselves ([`check_display_options`](Self::check_display_options)).
    pub fn check_display(&self, path: &Path) -> Result<()> {
        if self.display.is_some() && io::extension(path) != "png" {
            return Err(Error::invalid(format!(
                "a display's codes are written as PNG, not .{} (float formats stay linear \
                 0..1; the sidecar of a PNG records the cd/m²)",
                io::extension(path)
            )));
        }
        self.check_display_options()
    }

    /// The display options, whatever the file: a luminance mapping only with a display and
    /// inside what it shows; a display not display-encoded by a gamma as well.
    pub fn check_display_options(&self) -> Result<()> {
        match (&self.display, self.luminance) {
            (None, Some(_)) => Err(Error::invalid(
                "a luminance in cd/m² needs a display (its model turns cd/m² into codes)",
            )),
            (None, None) => Ok(()),
            (Some(_), _) if self.gamma.is_some() => Err(Error::invalid(
                "a display's model replaces a display gamma: give one or the other",
            )),
            (Some(display), _) => display.check_mapping(self.mapping_on(display)),
        }
    }

    /// The cd/m² the stimulus's 0..1 is shown at: `luminance`, else the display's black to
    /// white; `None` without a display.
    pub fn mapping(&self) -> Option<Luminance> {
        self.display.as_ref().map(|d| self.mapping_on(d))
    }

    /// [`mapping`](Self::mapping) on `display`.
    fn mapping_on(&self, display: &Display) -> Luminance {
        self.luminance.unwrap_or(display.full_range())
    }

    /// The bits per channel of the PNG written: the display's (10 in 16-bit codes) or
    /// `bit_depth`.
    pub fn png_bits(&self) -> u8 {
        match &self.display {
            Some(d) if d.bits() == 8 => 8,
            Some(_) => 16,
            None => self.bit_depth.bits(),
        }
    }

    /// The range for a file named `path`: psychopy's −1..1 only in float formats.
    pub fn check_range(&self, path: &Path) -> Result<()> {
        let ext = io::extension(path);
        if self.range == Range::Psychopy && !matches!(ext.as_str(), "npy" | "mat" | "npz") {
            return Err(Error::invalid(format!(
                "range psychopy applies to float formats (.npy, .mat, .npz), not .{ext}"
            )));
        }
        Ok(())
    }

    /// The display gamma for a file named `path`: PNG only.
    pub fn check_gamma(&self, path: &Path) -> Result<()> {
        if self.gamma.is_some() && io::extension(path) != "png" {
            return Err(Error::invalid(
                "a display gamma applies to PNG output only (float formats stay linear)",
            ));
        }
        Ok(())
    }
}

/// The output formats, by extension.
pub const FORMATS: &[&str] = &["png", "npy", "mat", "npz", "svg"];

/// A picture that is no longer the render its sidecar records: the caller changed it after
/// rendering (Python's `save` of an edited `img`). Its sidecar says so (`edited`), with the
/// digest of the render it came from beside the picture's own, and `render --spec` of that
/// sidecar refuses to claim it reproduces the picture.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Edited {
    /// The render's own digest (`md5_float64_rounded8` of the picture as rendered), when the
    /// picture's values were changed (`None`: the picture is the render's).
    pub rendered_md5: Option<String>,
    /// The target mask (or its names) was changed: the mask written, and the target facts of
    /// the sidecar, are the caller's, not the render's.
    pub target_mask: bool,
}

impl Edited {
    /// What the sidecar and the PNG's own record say of the edit (under [`EDITED_KEY`]).
    pub fn to_json(&self) -> Value {
        let mut record = serde_json::Map::new();
        if let Some(md5) = &self.rendered_md5 {
            record.insert("rendered_md5_float64_rounded8".into(), md5.as_str().into());
        }
        if self.target_mask {
            record.insert(
                "target_mask".into(),
                "edited: the mask and the target facts are the caller's, not the render's".into(),
            );
        }
        record.insert(
            "note".into(),
            "changed after rendering: this is not the render the parameters describe \
             (md5_float64_rounded8 is the picture's own)"
                .into(),
        );
        Value::Object(record)
    }
}

/// The sidecar key that marks an edited picture ([`Edited`]).
pub const EDITED_KEY: &str = "edited";

/// The digest the sidecar records of a picture (`md5_float64_rounded8`, stimupy's: float64
/// values rounded to 8 decimals; an RGB picture's channels in turn, pixel by pixel).
pub fn pixels_md5(pixels: &Pixels) -> String {
    match pixels {
        Pixels::Gray(img) => io::image_md5(img),
        Pixels::Rgb(img) => io::image_md5(&crate::grid::Grid::from_fn(
            img.width() * 3,
            img.height(),
            |c, r| img.get(c / 3, r)[c % 3],
        )),
    }
}

/// The name of the picture in a `.mat` or `.npz` bundle (stimupy's).
pub const MAT_VARIABLE: &str = "img";

/// Writes `output` to `path` (format from the extension) with its sidecar `path.json`
/// (extension replaced), target mask `*_mask.png` and, with `options.layers`, the surface
/// layers, replacing a file shadelab did not write only with `force` (the caller's output
/// policy, as `pipeline::Output` holds it). Returns every file written. The files are
/// committed as a set ([`io::OutputSet`]): whatever stops the write, the old set or the new set
/// is there whole, never a mix; a second run writing the same output meanwhile fails with
/// [`Error::Locked`]. `edited` says the picture is not the render `request` describes (its
/// sidecar says so). The sidecar and mask beside `path` are one picture's: when they are the
/// record of another picture of the same name (`a.npy` beside `a.png`) that is still there,
/// the write is refused, naming it, even when forced.
pub fn write_output(
    name: &str,
    request: &Request,
    output: &Output,
    path: &Path,
    options: &ExportOptions,
    force: bool,
    edited: Option<&Edited>,
) -> Result<Vec<PathBuf>> {
    let ext = options.check(path)?;
    if ext == "svg" && edited.is_some_and(|e| e.rendered_md5.is_some()) {
        return Err(Error::format(
            path,
            "an edited picture has no vector form (the SVG draws the render); write it as .png, .npy or .mat",
        ));
    }
    if ext == "svg" && output.svg.is_none() {
        let why = match output.notes.get("svg_omitted").and_then(|v| v.as_str()) {
            Some(reason) => format!(" here ({reason})"),
            None => String::new(),
        };
        return Err(Error::invalid(format!(
            "{name} has no vector form{why}; write it as .png, .npy or .mat (SVG is for circle arrays, strips, cut-outs and checkerboards)"
        )));
    }
    let sidecar = io::sibling(path, "", "json");
    // The set, the sidecar last: it is the commit record (see `io::OutputSet`).
    // In the order they were always listed (companions, image, sidecar).
    let mut files = planned_files(path, output, options);
    files.rotate_left(1);
    files.push(sidecar.clone());
    let set = io::OutputSet::begin(&files)?;
    // Under the lock, the record already there, read once for both decisions below.
    let old = old_record(&sidecar);
    check_not_another_pictures(
        path,
        &sidecar,
        old.as_ref(),
        &pixels_md5(&output.pixels),
        options,
    )?;
    // Every file this call will write is checked before the first is written: the image and
    // its companions are replaced only when the sidecar beside them is shadelab's, and the
    // sidecar only when it is one.
    for target in &files {
        io::check_overwrite(target, &sidecar, force)?;
    }
    // The companions of the old set that the new one lacks (a render with `layers` replaced
    // by one without), as the old sidecar lists them.
    let stale = stale_companions(path, old.as_ref(), &files);
    let picture = Picture {
        name,
        request,
        output,
        edited,
    };
    write_all(&picture, path, &ext, &sidecar, options, &set).map_err(|e| set.final_names(e))?;
    set.commit()?;
    // The new sidecar no longer lists them: they go with the set they belonged to.
    for file in stale {
        fs::remove_file(&file).map_err(|e| Error::io(&file, e))?;
    }
    Ok(files)
}

/// What [`write_all`] writes: the stimulus, its request and output, and whether the picture
/// was edited.
struct Picture<'a> {
    name: &'a str,
    request: &'a Request,
    output: &'a Output,
    edited: Option<&'a Edited>,
}

/// Refuses to write `path` when the shadelab sidecar beside it is the record of another
/// picture of the same name that is still there (`a.json` of `a.npy` when writing `a.png`):
/// replacing it would leave that picture with this one's record and mask. The same picture in
/// another file (the same digest `md5`, and the same gamma and range, no display: what a
/// reader of either file takes from the record) shares it. A sidecar whose picture is gone,
/// or a sidecar that is not shadelab's, is left to the overwrite rule.
fn check_not_another_pictures(
    path: &Path,
    sidecar: &Path,
    old: Option<&Value>,
    md5: &str,
    options: &ExportOptions,
) -> Result<()> {
    let Some(old) = old else {
        return Ok(());
    };
    let Some(image) = old.pointer("/files/image").and_then(Value::as_str) else {
        return Ok(());
    };
    let ours = path.file_name().and_then(|n| n.to_str());
    // Only a plain file name beside it counts: a hand-edited record cannot point elsewhere.
    let other = sidecar.with_file_name(image);
    let plain = Path::new(image).file_name().and_then(|n| n.to_str()) == Some(image);
    if ours == Some(image) || !plain || !other.is_file() {
        return Ok(());
    }
    let range = match options.range {
        Range::Unit => "0..1",
        Range::Psychopy => "-1..1",
    };
    let same_picture = old.get("md5_float64_rounded8").and_then(Value::as_str) == Some(md5)
        && old.get(EDITED_KEY).is_none()
        && old.get("gamma").and_then(Value::as_f64) == options.gamma
        && old.get("range").and_then(Value::as_str) == Some(range)
        && old.get("display").map_or(true, Value::is_null)
        && options.display.is_none();
    if same_picture {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!(
            "{} beside it is the record of {image}, another picture (its sidecar and mask would \
             be replaced); give this one another name, or remove {image} first",
            io::file_name_of(sidecar)
        ),
    ))
}

/// The shadelab sidecar already beside the picture (`None` when there is none, or it is not
/// JSON or not shadelab's), read once per write.
fn old_record(sidecar: &Path) -> Option<Value> {
    let bytes = io::read_capped(sidecar, io::MAX_TEXT_BYTES).ok()?;
    let old: Value = serde_json::from_slice(&bytes).ok()?;
    (old.get("program").and_then(Value::as_str) == Some("shadelab")).then_some(old)
}

/// The companion files (mask, layers) beside `path` that the shadelab sidecar `old` lists and
/// the new set (`files`) does not write. Only names a render can write are considered, so a
/// sidecar edited by hand cannot make shadelab delete anything else.
fn stale_companions(path: &Path, old: Option<&Value>, files: &[PathBuf]) -> Vec<PathBuf> {
    let Some(old) = old else {
        return Vec::new();
    };
    let listed: Vec<&str> = old
        .get("files")
        .and_then(Value::as_object)
        .map(|m| m.values().filter_map(Value::as_str).collect())
        .unwrap_or_default();
    [
        ("_mask", "png"),
        ("_depth", "npy"),
        ("_normals", "npy"),
        ("_albedo", "npy"),
        ("_shading", "npy"),
    ]
    .iter()
    .map(|(suffix, ext)| io::sibling(path, suffix, ext))
    .filter(|p| !files.contains(p) && p.is_file())
    .filter(|p| {
        p.file_name()
            .and_then(|n| n.to_str())
            .is_some_and(|n| listed.contains(&n))
    })
    .collect()
}

/// The image and the companion files `write_all` writes beside it (not the sidecar).
pub(crate) fn planned_files(path: &Path, output: &Output, options: &ExportOptions) -> Vec<PathBuf> {
    let mut files = vec![path.to_path_buf()];
    if output.targets.is_some() {
        files.push(io::sibling(path, "_mask", "png"));
    }
    if let (true, Some(s)) = (options.layers, &output.surface) {
        files.push(io::sibling(path, "_depth", "npy"));
        files.push(io::sibling(path, "_normals", "npy"));
        if s.albedo.is_some() {
            files.push(io::sibling(path, "_albedo", "npy"));
        }
        if s.shading.is_some() {
            files.push(io::sibling(path, "_shading", "npy"));
        }
    }
    files
}

fn write_all(
    picture: &Picture<'_>,
    path: &Path,
    ext: &str,
    sidecar: &Path,
    options: &ExportOptions,
    set: &io::OutputSet,
) -> Result<()> {
    let Picture {
        name,
        request,
        output,
        edited,
    } = *picture;
    let mut files = Map::new();
    let mut record = |key: &str, p: &Path| {
        files.insert(
            key.to_string(),
            Value::from(
                p.file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            ),
        );
    };
    if let Some(t) = &output.targets {
        let p = io::sibling(path, "_mask", "png");
        io::write_labels(set.staged(&p)?, &t.labels)?;
        record("target_mask", &p);
    }
    if options.layers {
        if let Some(s) = &output.surface {
            let p = io::sibling(path, "_depth", "npy");
            io::write_image(set.staged(&p)?, &s.depth)?;
            record("depth", &p);
            let p = io::sibling(path, "_normals", "npy");
            io::write_normals(set.staged(&p)?, &s.normals)?;
            record("normals", &p);
            if let Some(a) = &s.albedo {
                let p = io::sibling(path, "_albedo", "npy");
                io::write_image(set.staged(&p)?, a)?;
                record("albedo", &p);
            }
            if let Some(sh) = &s.shading {
                let p = io::sibling(path, "_shading", "npy");
                io::write_image(set.staged(&p)?, sh)?;
                record("shading", &p);
            }
        }
    }
    let to_range = |v: f64| options.range.apply(v);
    let image = set.staged(path)?;
    let (depth, gamma) = (options.bit_depth, options.gamma);
    let shown = shown_on_display(name, output, options)?;
    match (ext, &output.pixels) {
        ("png", _) if shown.is_some() => {
            let (shown, display) = (shown.as_ref(), options.display.as_ref());
            let (Some(shown), Some(display)) = (shown, display) else {
                unreachable!("a display's codes are shown on a display")
            };
            let size = output.pixels.size();
            let text = png_text(name, request, options, edited);
            let codes = io::DisplayCodes {
                codes: &shown.codes,
                channels: shown.channels,
                bits: display.bits(),
            };
            io::write_display_codes(image, size, codes, &text)?
        }
        ("png", pixels) => {
            let picture = match pixels {
                Pixels::Gray(img) => io::PngPicture::Gray(img),
                Pixels::Rgb(img) => io::PngPicture::Rgb(img),
            };
            let text = png_text(name, request, options, edited);
            io::write_stimulus(image, picture, depth, gamma, &text)?
        }
        ("npy", Pixels::Gray(img)) => io::write_image(image, &img.map(|&v| to_range(v)))?,
        ("npy", Pixels::Rgb(img)) => io::write_f32(
            image,
            &[img.height(), img.width(), 3],
            img.data().iter().flat_map(|p| p.map(to_range)),
        )?,
        ("mat" | "npz", _) => {
            let fields = super::bundle::fields(name, request, output, options);
            let bytes = if ext == "mat" {
                super::bundle::to_mat(&fields)?
            } else {
                super::bundle::to_npz(&fields)?
            };
            io::write_atomic(image, |out| {
                out.write_all(&bytes).map_err(|e| Error::io(path, e))
            })?
        }
        ("svg", _) => {
            let text = output.svg.as_deref().unwrap_or_default();
            io::write_atomic(image, |out| {
                out.write_all(text.as_bytes())
                    .and_then(|_| out.write_all(b"\n"))
                    .map_err(|e| Error::io(path, e))
            })?
        }
        _ => return Err(Error::invalid(format!("unknown output format '.{ext}'"))),
    }
    record("image", path);
    let mut value = sidecar_json(name, request, output, ext, options, files, shown.as_ref());
    if let (Some(edited), Value::Object(fields)) = (edited, &mut value) {
        fields.insert(EDITED_KEY.into(), edited.to_json());
    }
    io::write_json(set.staged(sidecar)?, &value)
}

/// What the display of `options` shows of a gray stimulus (`None` without a display).
pub fn shown_on_display(
    name: &str,
    output: &Output,
    options: &ExportOptions,
) -> Result<Option<Shown>> {
    let Some(display) = &options.display else {
        return Ok(None);
    };
    match &output.pixels {
        Pixels::Gray(img) => display.show(img, options.mapping_on(display)).map(Some),
        Pixels::Rgb(_) => Err(Error::invalid(format!(
            "{name} is a colour picture; a display's model applies to gray stimuli"
        ))),
    }
}

/// How the file's values encode linear luminance, in words (the sidecar's `encoding`).
fn encoding(format: &str, options: &ExportOptions) -> String {
    if let (Some(d), Some(mapping), "png") = (&options.display, options.mapping(), format) {
        let (lo, hi) = mapping.span();
        let stored = if d.bits() == 10 {
            "; 10-bit codes in 16 bits by bit replication (code * 64 + code / 16, sBIT 10)"
        } else {
            ""
        };
        return format!(
            "display codes of '{}' ({}-bit, {}): v shown at {lo} + v * {} cd/m² through the \
             display's inverse response{stored}",
            d.name(),
            d.bits(),
            d.quantise().name(),
            hi - lo
        );
    }
    match (format, options.gamma) {
        ("png", Some(g)) => format!("display-encoded: code = round(v^(1/{g}) * max)"),
        ("png", None) => "linear: code = round(v * max)".to_string(),
        ("svg", _) => "vector; colours are linear values as percentages, 1 user unit = 1 pixel".to_string(),
        ("mat" | "npz", _) => format!(
            "{}; picture '{MAT_VARIABLE}' (H x W [x 3]) {}, with target_mask and every parameter as fields",
            if format == "mat" { "MATLAB v5 bundle, doubles" } else { "NumPy npz bundle, float64" },
            match options.range { Range::Unit => "linear 0..1", Range::Psychopy => "linear mapped to -1..1 (v*2-1)" }
        ),
        _ => match options.range {
            Range::Unit => "float32, linear 0..1".to_string(),
            Range::Psychopy => "float32, linear mapped to -1..1 (v*2-1)".to_string(),
        },
    }
}

/// The text a stimulus PNG carries (iTXt chunks), so that the file alone says what it is:
/// `Software`, a one-line `Description`, and `shadelab`, the sidecar's record of the stimulus
/// (name, parameters, seed, size triple, encoding) as JSON. Its gAMA chunk says the same
/// encoding to viewers (1.0 for linear codes, 1/gamma for display-encoded ones). An edited
/// picture ([`Edited`]) says so in both.
pub fn png_text(
    name: &str,
    request: &Request,
    options: &ExportOptions,
    edited: Option<&Edited>,
) -> Vec<(String, String)> {
    let g = &request.geometry;
    let version = io::PROGRAM_VERSION;
    let bits = options.png_bits();
    let light = match (&options.display, options.mapping(), options.gamma) {
        (Some(d), Some(mapping), _) => {
            let (lo, hi) = mapping.span();
            format!(
                "codes of the display '{}' (not luminance) showing 0..1 at {lo}..{hi} cd/m²",
                d.name()
            )
        }
        (_, _, Some(gamma)) => {
            format!("display-encoded luminance, code = round(v^(1/{gamma}) * max)")
        }
        _ => "linear luminance 0..1, code = round(v * max)".to_string(),
    };
    let edit = if edited.is_some() {
        " (edited after rendering)"
    } else {
        ""
    };
    let description = format!(
        "{name}{edit}: {light}, {bits}-bit; {} x {} px (height x width), {:.4} x {:.4} deg at {} ppd",
        g.height,
        g.width,
        g.height_deg(),
        g.width_deg(),
        g.ppd
    );
    let mut record = stimulus_record(name, request);
    record.extend([
        ("bit_depth".to_string(), Value::from(bits)),
        ("gamma".to_string(), json!(options.gamma)),
        (
            "encoding".to_string(),
            Value::from(encoding("png", options)),
        ),
        ("range".to_string(), Value::from("0..1")),
    ]);
    if let (Some(d), Some(mapping)) = (&options.display, options.mapping()) {
        record.insert("display".to_string(), d.to_json());
        record.insert("luminance".to_string(), mapping.to_json());
    }
    if let Some(edited) = edited {
        record.insert(EDITED_KEY.to_string(), edited.to_json());
    }
    vec![
        ("Software".to_string(), format!("shadelab {version}")),
        ("Description".to_string(), description),
        ("shadelab".to_string(), Value::Object(record).to_string()),
    ]
}

/// The sidecar of a rendered stimulus: program, version, conventions, stimulus, every
/// parameter, geometry, seed, format, gamma, range, checksum, targets and files. The geometry
/// is stimupy's triple in stimupy's order: `visual_size` [height, width] in degrees, `ppd`, and
/// `shape` [height, width] in pixels.
pub fn sidecar_json(
    name: &str,
    request: &Request,
    output: &Output,
    format: &str,
    options: &ExportOptions,
    files: Map<String, Value>,
    shown: Option<&Shown>,
) -> Value {
    let channels = match &output.pixels {
        Pixels::Gray(_) => 1,
        Pixels::Rgb(_) => 3,
    };
    let md5 = pixels_md5(&output.pixels);
    let mut sidecar = stimulus_record(name, request);
    let Value::Object(rest) = json!({
        "channels": channels,
        "format": format,
        "bit_depth": if format == "png" { Value::from(options.png_bits()) } else { Value::Null },
        "gamma": options.gamma,
        "encoding": encoding(format, options),
        "range": match options.range { Range::Unit => "0..1", Range::Psychopy => "-1..1" },
        "md5_float64_rounded8": md5,
        "targets": output.targets.as_ref().map(|t| {
            t.names.iter().enumerate().map(|(i, n)| json!({"label": i + 1, "name": n})).collect::<Vec<_>>()
        }),
        "notes": output.notes,
        "files": files,
        "conventions": io::conventions_json(),
    }) else {
        unreachable!("json! of an object literal is an object")
    };
    sidecar.extend(rest);
    if let (Some(d), Some(shown)) = (&options.display, shown) {
        sidecar.insert("display".into(), d.to_json());
        sidecar.extend(shown.to_json());
        // Each target's luminance beside its label and name.
        let Some(t) = &output.targets else {
            return Value::Object(sidecar);
        };
        let shown = shown.targets(&t.labels, &t.names);
        // The sidecar's targets are labels 1..N in order.
        if let Some(Value::Array(items)) = sidecar.get_mut("targets") {
            for target in &shown {
                let Some(item) = items.get_mut(usize::from(target.label) - 1) else {
                    continue;
                };
                item["luminance_cd_m2"] = json!(target.luminance_cd_m2);
                if let Some(w) = target.weber_vs_background {
                    item["weber_vs_background"] = json!(w);
                }
            }
        }
    }
    Value::Object(sidecar)
}

/// What a stimulus is, as its sidecar and its PNG's text both record it: program, version,
/// stimulus, every parameter, seed and the size triple (stimupy's order, height first).
fn stimulus_record(name: &str, request: &Request) -> Map<String, Value> {
    let g = &request.geometry;
    let Value::Object(record) = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "stimulus": name,
        "parameters": request.params.to_json(),
        "seed": request.seed,
        "visual_size": [g.height_deg(), g.width_deg()],
        "ppd": g.ppd,
        "shape": [g.height, g.width],
    }) else {
        unreachable!("json! of an object literal is an object")
    };
    record
}
