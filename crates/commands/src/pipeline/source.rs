//! Where an analysed picture comes from: an image file (PNG or `.npy`), a stimulus rendered on
//! the spot, or a render spec (or sidecar) rendered in memory, with its resolution, target
//! labels and what its maker declares when they are known.
//!
//! An image file with a shadelab sidecar beside it (`X.png` → `X.json`, see
//! [`RenderSidecar`]) is read as its render: the sidecar's target mask and names, ppd, albedo,
//! ambient level and true light are taken, and a recorded display gamma or PsychoPy range is
//! undone, so that the picture is linear again. Values given explicitly win over the sidecar's.

// What a loaded picture's sidecar says, defined in io.
pub use crate::io::{Beside, Declared, Quantum, RenderSidecar, TrueLight, SILHOUETTE_NOTE};

use crate::error::{Error, Result};
use crate::grid::{size_mismatch, Image, Labels, Mask};
use crate::io::{self, InputEncoding};
use crate::message::{Message, Setting};
use crate::solver::carries_data;
use crate::stimulus::{self, Pixels};
use crate::visual_size::SizeRequest;
use serde::Serialize;
use serde_json::{json, Map, Value};
use std::path::PathBuf;

/// How a picture handed over in memory is named in reports and errors.
pub const IN_MEMORY: &str = "<array>";

/// Plain values naming a picture: exactly one of `image`, `stimulus`, `spec` and `pixels`.
#[derive(Debug, Clone, Default)]
pub struct PictureSource {
    /// An 8/16-bit PNG, a JPEG, a TIFF or an H×W `.npy` (told apart by their content, read
    /// once: a pipe works), decoded as
    /// [`input_encoding`](Self::input_encoding) says; a shadelab sidecar beside it is read (see
    /// the module's documentation).
    pub image: Option<PathBuf>,
    /// How the image file's codes encode luminance (default [`InputEncoding::Auto`]: as the
    /// file says, see [`io::read_gray_as`]); an explicit one overrides the file's chunk and a
    /// sidecar's recorded gamma.
    pub input_encoding: InputEncoding,
    /// A stimulus spec or a shadelab sidecar, rendered in memory as `render` would.
    pub spec: Option<PathBuf>,
    /// A stimulus to render (see [`crate::stimulus::names`]), analysed with its own targets.
    pub stimulus: Option<String>,
    /// The stimulus's parameters (checked against its declarations when it is rendered).
    pub params: Map<String, Value>,
    /// The stimulus seed (default 0).
    pub seed: Option<u64>,
    /// Pixels per degree: the image's resolution, or the one to render the stimulus at.
    pub ppd: Option<f64>,
    /// Target labels: an 8/16-bit grayscale PNG or an H×W `.npy` of booleans or whole
    /// numbers, 0 = background, 1..N = targets.
    pub mask: Option<PathBuf>,
    /// The largest picture accepted or made, in pixels.
    pub max_pixels: usize,
    /// A picture already in memory (e.g. the Python module's NumPy array), checked as a file's
    /// would be.
    pub pixels: Option<Pixels>,
    /// Target labels in memory (0 = background, 1..N = targets), instead of a `mask` file.
    pub labels: Option<Labels>,
    /// The names of the [`labels`](Self::labels) (`names[l - 1]` names label `l`), as their
    /// maker gives them (a rendered dict's `target_names`); empty when unnamed.
    pub label_names: Vec<String>,
    /// What the maker of the picture in memory declares (albedo, ambient level, true light),
    /// as a rendered picture's sidecar would: a stimupy-style dict of `shadelab.render`
    /// carries them. Only with [`pixels`](Self::pixels).
    pub declared: Declared,
    /// Whether the maker of the picture in memory says its targets, the [`labels`](Self::labels)
    /// given with it, are objects' silhouettes on a backdrop (a rendered dict's
    /// `notes.target_is_silhouette` with its own `target_mask`, as a sidecar says it; see
    /// [`Picture::on_backdrop`]). Only with [`pixels`](Self::pixels).
    pub silhouette: bool,
}

/// What a report says of the picture it analysed: the coordinate conventions, where the picture
/// came from and its size (flattened into the outline and perception reports).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PictureInfo {
    /// The coordinate conventions.
    pub conventions: Value,
    /// Where the picture came from.
    pub input: Value,
    /// The picture's width, pixels.
    pub width: usize,
    /// The picture's height, pixels.
    pub height: usize,
}

impl PictureInfo {
    /// The description of a picture from `origin` of `width` × `height` pixels.
    pub(crate) fn new(origin: &Value, width: usize, height: usize) -> Self {
        PictureInfo {
            conventions: crate::io::conventions_json(),
            input: origin.clone(),
            width,
            height,
        }
    }
}

/// A loaded picture with what is known about it.
#[derive(Debug, Clone)]
pub struct Picture {
    /// The pixels (gray or RGB).
    pub pixels: Pixels,
    /// Pixels per degree, when known.
    pub ppd: Option<f64>,
    /// Target labels and their names (names empty when the labels came from a file).
    pub labels: Option<(Labels, Vec<String>)>,
    /// Where it came from, for reports.
    pub origin: Value,
    /// What its maker declares: albedo, ambient level, true light (nothing for a bare image).
    pub declared: Declared,
    /// Whether its maker says the targets are objects in front of a backdrop that is no part
    /// of the surface: a rendered stimulus whose surface does not fill the frame (the
    /// benchmark objects, the hollow mask's face), or an image whose sidecar says its target
    /// is an object's silhouette. The perception analyses then solve on the targets by
    /// default ([`crate::pipeline::perception::DomainSpec::Auto`]).
    pub on_backdrop: bool,
    /// How finely its values were stored (a file's 8- or 16-bit codes or float32; float64
    /// for a picture rendered or handed over in memory), so that a level it records (the
    /// ambient) is found in it to its own precision ([`Quantum::settle`]).
    pub quantum: Quantum,
    /// Where its shadow is on record ([`Picture::unlit`]).
    pub shadow: ShadowRecord,
    /// What was read with it, for the log, in the order said: how a `.npy`'s integers were
    /// scaled, what its sidecar gives and what a given value replaces. Empty for a stimulus or
    /// a picture in memory. A pipeline says them through
    /// [`Progress::note`](crate::progress::Progress::note) as soon as the picture is read
    /// ([`Picture::say_notes`]).
    pub notes: Vec<Message>,
    /// The line (beginning `note: `) that says its codes were taken as sRGB by the default
    /// rule, where they were: a pipeline says it once its run has succeeded, so that a refusal
    /// stays one line.
    pub input_note: Option<Message>,
}

/// Where a picture's shadow (attached and cast: the pixels its render leaves at the declared
/// ambient level, where the light does not reach) is on record, so that it is taken from the
/// record and not decided from values that the picture's codes may not tell apart
/// ([`Quantum::settle`]).
#[derive(Debug, Clone, Default)]
pub enum ShadowRecord {
    /// Nowhere (a picture without a sidecar, or handed over in memory): its values decide.
    #[default]
    None,
    /// A stimulus rendered here: the pixels of its own render.
    Rendered(Mask),
    /// A file with a shadelab sidecar: the render it records, made again and checked against
    /// the picture only when asked ([`Picture::unlit`]).
    Sidecar(Box<RenderSidecar>),
}

impl Picture {
    /// The record (a shadelab sidecar) it was read with, where it has one.
    pub fn record(&self) -> Option<&RenderSidecar> {
        match &self.shadow {
            ShadowRecord::Sidecar(sidecar) => Some(sidecar),
            _ => None,
        }
    }

    /// Says [`notes`](Self::notes) through `progress`, once, in order.
    pub fn say_notes(&self, progress: &dyn crate::progress::Progress) {
        self.notes.iter().for_each(|line| progress.note(line));
    }

    /// The luminance of the pixels (Rec. 709 weights for colour).
    pub fn luminance(&self) -> Image {
        self.pixels.luminance()
    }

    /// The pixels its render leaves at the declared ambient level, where that is on record
    /// ([`ShadowRecord`]): a stimulus rendered here, or a file that is the render its sidecar
    /// records (rendered again from the sidecar, up to `max_pixels` pixels, as `render --spec`
    /// would, and every stored value found within its code of it); `None` leaves the shadow
    /// to the values.
    pub fn unlit(&self, max_pixels: usize) -> Option<Mask> {
        match (&self.shadow, &self.pixels) {
            (ShadowRecord::None, _) => None,
            (ShadowRecord::Rendered(unlit), _) => Some(unlit.clone()),
            (ShadowRecord::Sidecar(s), Pixels::Gray(gray)) => {
                recorded_unlit(s, gray, &self.quantum, max_pixels)
            }
            (ShadowRecord::Sidecar(_), Pixels::Rgb(_)) => None,
        }
    }
}

impl PictureSource {
    /// The files this source reads: the image and the sidecar beside it, the spec, the mask
    /// (see [`crate::io::AtomicDir::reads`]: an output folder never replaces them).
    pub fn files(&self) -> Vec<PathBuf> {
        let mut files: Vec<PathBuf> = [&self.image, &self.spec, &self.mask]
            .into_iter()
            .flatten()
            .cloned()
            .collect();
        files.extend(self.image.as_deref().map(io::render_sidecar::sidecar_path));
        files
    }

    /// Checks what needs no file: a positive resolution, the input encoding and exactly one
    /// source.
    pub fn check(&self) -> Result<()> {
        self.input_encoding.validate()?;
        if let Some(p) = self.ppd {
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::invalid(format!(
                    "ppd {p} must be a positive number of pixels per degree"
                )));
            }
        }
        let given = [
            self.image.is_some(),
            self.stimulus.is_some(),
            self.spec.is_some(),
            self.pixels.is_some(),
        ];
        match given.iter().filter(|&&g| g).count() {
            0 => Err(Error::invalid(
                "give an image file, a stimulus name or a stimulus spec",
            )),
            1 if self.mask.is_some() && self.labels.is_some() => Err(Error::invalid(
                "give target labels as a mask file or in memory, not both",
            )),
            1 => Ok(()),
            _ => Err(Error::invalid(
                "give one of an image file, a stimulus name and a stimulus spec, not several",
            )),
        }
    }

    /// The lines that say what the picture read from `image` gives and what is given instead,
    /// for a log ([`Picture::notes`]): how its integers were scaled (`npy_scale`, a `.npy`'s,
    /// the one rule of docs/conventions.md), what its sidecar (`beside`) gives, and what a
    /// value given here replaces.
    pub(crate) fn notes_on(
        &self,
        image: &std::path::Path,
        npy_scale: Option<&io::IntegerScale>,
        beside: &Beside,
    ) -> Vec<Message> {
        let mut lines: Vec<Message> = Vec::new();
        if let Some(scale) = npy_scale {
            lines.push(format!("{}: {}", image.display(), scale.note()).into());
        }
        match beside {
            Beside::Nothing => {}
            Beside::Foreign(path) => lines.push(
                format!(
                    "{} is not a shadelab sidecar (no \"program\": \"shadelab\"): ignored",
                    path.display()
                )
                .into(),
            ),
            Beside::Ours(s) => {
                lines.push(s.summary().into());
                if let (Some(g), true) = (s.gamma, self.input_encoding.is_explicit()) {
                    lines.push(
                        Message::default()
                            .setting(Setting::InputGamma, "the given input gamma")
                            .then(format!(
                                " {} replaces the sidecar's gamma {g}",
                                self.input_encoding
                            )),
                    );
                }
                if let (Some(given), Some(own)) = (self.ppd, s.ppd.filter(|&p| Some(p) != self.ppd))
                {
                    lines.push(
                        Message::default()
                            .setting(Setting::Ppd, "the given ppd")
                            .then(format!(" {given} replaces the sidecar's {own}")),
                    );
                }
                let other_mask = s
                    .target_mask
                    .as_ref()
                    .filter(|&m| self.mask.as_ref().is_some_and(|g| !same_file(g, m)));
                if let (Some(given), Some(own)) = (&self.mask, other_mask) {
                    lines.push(
                        Message::default()
                            .setting(Setting::Mask, "the given mask")
                            .then(format!(
                                " {} replaces the sidecar's {}",
                                given.display(),
                                own.display()
                            )),
                    );
                }
            }
        }
        lines
    }

    /// Reads the image or renders the stimulus; with `colour`, PNGs are read as RGB.
    pub fn load(&self, colour: bool) -> Result<Picture> {
        Ok(self.load_shaped(colour, None)?.0)
    }

    /// Like [`load`](Self::load), but a stimulus is rendered `shape` = (height, width) pixels
    /// when given, and its request (resolved parameters and geometry) comes back too (`None`
    /// for an image file).
    pub fn load_shaped(
        &self,
        colour: bool,
        shape: Option<(usize, usize)>,
    ) -> Result<(Picture, Option<stimulus::Request>)> {
        self.check()?;
        let max_pixels = self.max_pixels;
        let mut request = None;
        let mut picture = match (&self.image, &self.stimulus) {
            (Some(path), _) => {
                let encoding = self.input_encoding;
                // Read once (a pipe cannot be read again): the pixels, how finely they were
                // stored, and whether the file states its own encoding.
                let file = io::read_picture(path, max_pixels, encoding, colour)?;
                // The image is read first: a broken image is reported before its sidecar.
                let beside = RenderSidecar::of_picture(path, &file, encoding, max_pixels)?;
                let notes = self.notes_on(path, file.npy_scale.as_ref(), &beside);
                let input_note = assumed_srgb(&file);
                let (mut pixels, info) = match file.rgb {
                    Some(rgb) => (Pixels::Rgb(rgb), Value::Null),
                    None => (Pixels::Gray(file.gray), file.info),
                };
                let mut quantum = file.quantum;
                let sidecar = beside
                    .sidecar()
                    .cloned()
                    .map(|s| without_gamma(s, encoding));
                let sidecar = sidecar.as_ref();
                if let Some(s) = sidecar {
                    pixels = match pixels {
                        Pixels::Gray(i) => Pixels::Gray(i.map(|&v| s.linearise(v))),
                        Pixels::Rgb(i) => Pixels::Rgb(i.map(|p| p.map(|v| s.linearise(v)))),
                    };
                    quantum = quantum.map(|v| s.linearise(v));
                }
                check_pixel_values(&pixels, &path.display().to_string())?;
                let mut origin = json!({ "image": path.display().to_string() });
                // How the codes were decoded, where the user said or the default rule assumed
                // sRGB (a picture that says its own encoding is recorded as before).
                if encoding.is_explicit() || file.assumed_srgb.is_some() {
                    origin["input_encoding"] = encoding.to_string().into();
                    if let Some(conversion) = info.get("conversion") {
                        origin["conversion"] = conversion.clone();
                    }
                }
                let mut picture = Picture {
                    pixels,
                    ppd: self.ppd,
                    labels: None,
                    origin: Value::Null,
                    declared: Declared::default(),
                    on_backdrop: false,
                    quantum,
                    shadow: ShadowRecord::None,
                    notes,
                    input_note,
                };
                if let Some(s) = sidecar {
                    origin["sidecar"] = s.to_json();
                    picture.ppd = self.ppd.or(s.ppd);
                    picture.declared = Declared {
                        albedo: s.albedo,
                        ambient: s.ambient,
                        light: s.light,
                    };
                    picture.on_backdrop = s.silhouette;
                    picture.shadow = ShadowRecord::Sidecar(Box::new(s.clone()));
                    if let (Some(mask), None) = (&s.target_mask, &self.mask) {
                        let labels = io::read_labels(mask, max_pixels)
                            .map_err(|e| Error::invalid(format!("{}: {e}", s.path.display())))?;
                        check_same_size(&labels, &picture.pixels, mask)?;
                        picture.labels = Some((labels, s.target_names()));
                    }
                }
                picture.origin = origin;
                picture
            }
            (None, None) if self.pixels.is_some() => Picture {
                pixels: self.in_memory(colour)?,
                ppd: self.ppd,
                labels: None,
                origin: json!({ "image": IN_MEMORY }),
                declared: self.declared,
                on_backdrop: self.silhouette,
                quantum: Quantum::default(),
                // The caller's values are the record (float64, as rendered).
                shadow: ShadowRecord::None,
                notes: Vec::new(),
                input_note: None,
            },
            (None, None) if self.spec.is_some() => {
                let spec = self.spec.as_deref().unwrap_or(std::path::Path::new(""));
                // The output name is not used: the spec is rendered in memory.
                let config = crate::pipeline::render::RenderConfig::from_spec_file(spec)?;
                let (picture, made) = render_config(&config, &self.params, self.ppd, max_pixels)?;
                request = Some(made);
                picture
            }
            (None, Some(name)) => {
                let size = SizeRequest {
                    ppd: self.ppd,
                    shape,
                    ..Default::default()
                };
                let seed = self.seed.unwrap_or(0);
                let (made, output) =
                    stimulus::generate(name, &self.params, &size, seed, max_pixels)?;
                let picture = rendered(name, &made, output, seed)?;
                request = Some(made);
                picture
            }
            (None, None) => {
                return Err(Error::invalid(
                    "give an image file, a stimulus name or a stimulus spec",
                ))
            }
        };
        if self.mask.is_some() || (self.labels.is_some() && !self.silhouette) {
            // Targets given here say nothing of a backdrop, unless the maker of the picture in
            // memory says that they, its own targets, are silhouettes.
            picture.on_backdrop = false;
        }
        if let Some(path) = &self.mask {
            let labels = io::read_labels(path, max_pixels)?;
            check_same_size(&labels, &picture.pixels, path)?;
            picture.labels = Some((labels, Vec::new()));
        }
        if let Some(labels) = &self.labels {
            let size = (labels.width(), labels.height());
            if size != picture.pixels.size() {
                return Err(Error::invalid(size_mismatch(
                    "the target labels are",
                    size,
                    "the image is",
                    picture.pixels.size(),
                )));
            }
            picture.labels = Some((labels.clone(), self.label_names.clone()));
        }
        Ok((picture, request))
    }

    /// The in-memory picture, checked as a file's would be (size, finite values); gray unless
    /// `colour`.
    fn in_memory(&self, colour: bool) -> Result<Pixels> {
        let Some(pixels) = &self.pixels else {
            return Err(Error::invalid("give an image file or a stimulus name"));
        };
        let (w, h) = pixels.size();
        crate::grid::check_size(w, h, self.max_pixels)?;
        check_pixel_values(pixels, IN_MEMORY)?;
        Ok(match pixels {
            Pixels::Rgb(_) if !colour => Pixels::Gray(pixels.luminance()),
            _ => pixels.clone(),
        })
    }
}

/// The sidecar `sidecar` as a picture read under `encoding` takes it: an explicit encoding
/// replaces the display gamma it records (which is then not undone a second time).
pub fn without_gamma(mut sidecar: RenderSidecar, encoding: InputEncoding) -> RenderSidecar {
    if encoding.is_explicit() {
        sidecar.gamma = None;
    }
    sidecar
}

/// The picture `config` renders in memory, with `params` given beside it winning over its own
/// and the resolution `ppd` where given, and the request it was made from.
fn render_config(
    config: &crate::pipeline::render::RenderConfig,
    params: &Map<String, Value>,
    ppd: Option<f64>,
    max_pixels: usize,
) -> Result<(Picture, stimulus::Request)> {
    let mut size = config.size;
    if ppd.is_some() {
        size.ppd = ppd;
    }
    let mut all = config.params.clone();
    all.extend(params.clone());
    let (made, output) =
        stimulus::generate(&config.stimulus, &all, &size, config.seed, max_pixels)?;
    let picture = rendered(&config.stimulus, &made, output, config.seed)?;
    Ok((picture, made))
}

/// The render a picture's record (its sidecar, as read with it) describes, made again in
/// memory from that record, with `params` given beside it winning over its own and the
/// resolution `ppd` where given (the fading disk's sharp twin: `blur = 0`).
pub(crate) fn render_record(
    sidecar: &RenderSidecar,
    params: &Map<String, Value>,
    ppd: Option<f64>,
    max_pixels: usize,
) -> Result<Picture> {
    let config = crate::pipeline::render::RenderConfig::from_sidecar_record(sidecar)?;
    Ok(render_config(&config, params, ppd, max_pixels)?.0)
}

/// The line (beginning `note: `) that says a picture file's codes were taken as sRGB by the
/// default rule, where they were.
pub(crate) fn assumed_srgb(file: &io::PictureFile) -> Option<Message> {
    let line = file.assumed_srgb.as_ref()?;
    Some(Message::text(format!("note: {line}")))
}

/// A rendered stimulus as a picture, with its targets and what it declares.
fn rendered(
    name: &str,
    made: &stimulus::Request,
    output: stimulus::Output,
    seed: u64,
) -> Result<Picture> {
    let parameters = made.params.to_json();
    let notes = Value::Object(output.notes.clone());
    let declared = Declared::from_record(&parameters, &notes)
        .map_err(|e| Error::invalid(format!("stimulus {name}: {e}")))?;
    // A rendered surface that leaves part of the frame to the backdrop: its targets are the
    // objects (a relief on a panel fills the frame), as its notes say, for a sidecar too.
    let on_backdrop =
        output.targets.is_some() && output.notes.get(SILHOUETTE_NOTE) == Some(&Value::Bool(true));
    let shadow = match (&output.pixels, declared.ambient) {
        (Pixels::Gray(gray), Some(ambient)) => ShadowRecord::Rendered(unlit_pixels(gray, ambient)),
        _ => ShadowRecord::None,
    };
    Ok(Picture {
        pixels: output.pixels,
        ppd: Some(made.geometry.ppd),
        labels: output.targets.map(|t| (t.labels, t.names)),
        origin: json!({
            "stimulus": name,
            "parameters": parameters,
            "seed": seed,
            "geometry": made.geometry,
            "notes": notes,
        }),
        declared,
        on_backdrop,
        quantum: Quantum::default(),
        shadow,
        notes: Vec::new(),
        input_note: None,
    })
}

/// The pixels of a render `image` at or below its `ambient` level, where the light does not
/// reach (attached and cast shadow): the pixels without a data term by the solver's own rule
/// ([`carries_data`]), found on the render's exact values.
fn unlit_pixels(image: &Image, ambient: f64) -> Mask {
    image.map(|&v| !carries_data(v, ambient, None))
}

/// The pixels that the render a shadelab sidecar records leaves at its ambient level
/// ([`ShadowRecord`]), when `gray`, the picture read beside it (linear, stored as `quantum`
/// says), is that render: rendered again from the record (as `render --spec` would), every
/// pixel of it lies within the stored value's code. `None` where the sidecar declares no
/// ambient level, its render cannot be made again (another version's, an edited record) or
/// is in colour, or the picture is not that render (edited, or another picture): such a
/// picture's shadow is decided by its values.
pub(crate) fn recorded_unlit(
    sidecar: &RenderSidecar,
    gray: &Image,
    quantum: &Quantum,
    max_pixels: usize,
) -> Option<Mask> {
    let ambient = sidecar.ambient?;
    sidecar.stimulus.as_ref()?;
    // The render the record describes, made again from the record as read (not the file).
    let render = render_record(sidecar, &Map::new(), None, max_pixels).ok()?;
    let Pixels::Gray(exact) = render.pixels else {
        return None;
    };
    let same = (exact.width(), exact.height()) == (gray.width(), gray.height())
        && gray
            .data()
            .iter()
            .zip(exact.data())
            .all(|(&stored, &v)| quantum.could_store(stored, v));
    same.then(|| unlit_pixels(&exact, ambient))
}

/// Whether two paths name the same file (compared as written when either cannot be resolved).
fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Fails unless the label map `labels` (read from `path`) has the picture's size.
fn check_same_size(labels: &Labels, pixels: &Pixels, path: &std::path::Path) -> Result<()> {
    let size = (labels.width(), labels.height());
    if size != pixels.size() {
        return Err(Error::invalid(size_mismatch(
            &format!("mask {} is", path.display()),
            size,
            "the image is",
            pixels.size(),
        )));
    }
    Ok(())
}

/// Fails on the first NaN or infinity of `pixels`, naming its column and row, and on values
/// outside 0..1.
fn check_pixel_values(pixels: &Pixels, what: &str) -> Result<()> {
    let (values, channels) = match pixels {
        Pixels::Gray(i) => (i.data(), 1),
        Pixels::Rgb(i) => (i.data().as_flattened(), 3),
    };
    io::check_values(values, channels, pixels.size().0, what)
}
