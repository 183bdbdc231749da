//! Stimuli: every picture shadelab renders, from a benchmark sphere to Adelson's checker-shadow,
//! behind one interface. A stimulus declares its parameters and default size; given resolved
//! parameters, a geometry (size in degrees and pixels) and a seed, it returns linear luminance
//! with its target mask and, where a surface exists, the ground-truth layers.
//!
//! Two ways in: by name ([`find`], [`generate`], [`Spec`]), with the parameters as key=value
//! pairs or JSON checked against the stimulus's declarations; or typed, with one parameter
//! struct and one function per stimulus ([`bumps`] with [`BumpsParams`], [`sphere`] with
//! [`SphereParams`] ...). Each struct is declared once (`stimulus_params!`), which gives its defaults, ranges, docs and the conversion to and from
//! the generic [`Params`] that sidecars record.

#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod gallery;

mod boundary_strips;
mod bumps;
pub mod bundle;
mod checker_shadow;
mod checkerboard;
mod circles;
mod crater;
mod export;
pub mod face;
mod fading_disk;
mod frame;
mod hollow_mask;
pub mod mat;
mod reflectance_map;
pub mod stimupy_names;

// The floors below, under the module names their code has always used (`crate::grid`, ...).
use shadelab_core::{
    cancel, error, gradient_space, grid, light, message, parallel, params, random, visual_size,
};
use shadelab_engine::{reflectance, render, surface};
use shadelab_io as io;
use shadelab_io::{colormap, display, plot};
mod strips;
mod surfaces;
mod svg;

pub use crate::surface::{Mesh, MeshShading, Projection, Surface};
pub(crate) use export::planned_files;
pub use export::{
    pixels_md5, shown_on_display, write_output, Edited, ExportOptions, Range, EDITED_KEY,
};

// The typed interface: one parameter struct and one function per stimulus.
pub use boundary_strips::{boundary_strips, BoundaryStripsParams, StripShading};
pub use bumps::{
    bumps, sideways, BumpsParams, DiscArrayParams, DiscPattern, DiscProfile, LightSide,
    SidewaysParams,
};
pub use checker_shadow::{checker_shadow, CheckerShadowParams, CylinderColour};
pub use checkerboard::{
    checkerboard, disc, rounded_check_warning, CheckerboardParams, DiscParams, CHECK_ROUNDED_NOTE,
};
pub use circles::{
    circles, CircleLayout, CirclePolarity, CircleShading, CirclesParams, ShadingAxis,
};
pub use crater::{crater, CraterParams, CraterRotation};
pub use fading_disk::{fading_disk, FadingDiskParams, FadingVariant};
pub use hollow_mask::{hollow_mask, FaceLayout, FaceMode, HollowMaskParams};
pub use reflectance_map::{reflectance_map, OrientationSpace, ReflectanceMapParams};
pub use strips::{strips, StripOrientation, StripProfile, StripsParams};
pub use surfaces::{
    bunny, ellipsoid, gaussian, heightfield, mesh, sphere, vase, BackdropParams, BunnyParams,
    EllipsoidParams, GaussianParams, HeightfieldParams, LightingParams, MeshNormals, MeshParams,
    SphereParams, VaseParams, ViewParams,
};

use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Labels, Mask, RgbImage};
use crate::message::SizeText;
use crate::params::{ParamSet, ParamSpec, Params};
use crate::visual_size::{Geometry, SizeRequest};
use serde::Deserialize;
use serde_json::{Map, Value};

/// What a stimulus is, for `list`, `describe` and the gallery.
#[derive(Debug, Clone)]
pub struct Info {
    /// The name used on the command line.
    pub name: &'static str,
    /// One line: what it shows.
    pub summary: &'static str,
    /// Its parameters.
    pub params: Vec<ParamSpec>,
    /// Default (height, width) in degrees, as a [`SizeRequest`]'s.
    pub default_visual_size: (f64, f64),
    /// Default pixels per degree.
    pub default_ppd: f64,
}

/// A fully resolved request to render a stimulus.
#[derive(Debug, Clone)]
pub struct Request {
    /// Checked parameters, defaults filled in.
    pub params: Params,
    /// Size in pixels and degrees.
    pub geometry: Geometry,
    /// Seed for anything random (layouts, jitter).
    pub seed: u64,
}

/// Luminance, gray or colour, linear 0..1.
#[derive(Debug, Clone, PartialEq)]
pub enum Pixels {
    /// One channel.
    Gray(Image),
    /// Three channels (linear RGB).
    Rgb(RgbImage),
}

impl Pixels {
    /// Width and height.
    pub fn size(&self) -> (usize, usize) {
        match self {
            Pixels::Gray(i) => (i.width(), i.height()),
            Pixels::Rgb(i) => (i.width(), i.height()),
        }
    }

    /// The smallest and largest value of any channel (NaN ignored).
    pub fn extremes(&self) -> (f64, f64) {
        let values: Box<dyn Iterator<Item = f64> + '_> = match self {
            Pixels::Gray(i) => Box::new(i.data().iter().copied()),
            Pixels::Rgb(i) => Box::new(i.data().iter().flatten().copied()),
        };
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        })
    }

    /// The luminance (Rec. 709 weights for colour).
    pub fn luminance(&self) -> Image {
        match self {
            Pixels::Gray(i) => i.clone(),
            Pixels::Rgb(i) => i.map(|&p| crate::grid::luminance(p)),
        }
    }
}

/// A target mask: 0 = background, label k = `names[k − 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Targets {
    /// The label map.
    pub labels: Labels,
    /// The names of labels 1..N.
    pub names: Vec<String>,
}

/// Ground truth for stimuli made by rendering a surface.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceLayers {
    /// Depth toward the viewer, pixel units.
    pub depth: Image,
    /// Unit normals.
    pub normals: Grid<Normal>,
    /// Where the surface is (the target mask records it for the file).
    pub mask: Mask,
    /// Reflectance factor per pixel, where the stimulus varies it.
    pub albedo: Option<Image>,
    /// Shading R(n) before albedo and cast shadows, where distinct from the image.
    pub shading: Option<Image>,
}

/// What a stimulus produces.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The picture.
    pub pixels: Pixels,
    /// Named target regions, if the stimulus has any.
    pub targets: Option<Targets>,
    /// Ground-truth surface layers, if the stimulus is a rendered surface.
    pub surface: Option<SurfaceLayers>,
    /// An SVG rendering, for stimuli that are vector by nature (in pixel units).
    pub svg: Option<String>,
    /// Extra facts worth recording in the sidecar (e.g. the shared value of checker squares).
    pub notes: Map<String, Value>,
}

impl Output {
    /// A rendered surface: its image, the surface's layers with the shading before shadows,
    /// and `targets` and `notes`. A surface that leaves part of the frame to the backdrop
    /// makes its targets objects' silhouettes (the note [`crate::io::SILHOUETTE_NOTE`]), so
    /// that the sidecar says what the picture rendered in memory says (its analyses solve on
    /// the targets by either route).
    pub(crate) fn rendered(
        surface: crate::surface::Surface,
        rendering: crate::render::Rendering,
        targets: Targets,
        mut notes: Map<String, Value>,
    ) -> Self {
        if surface.mask.data().iter().any(|&inside| !inside) {
            notes.insert(crate::io::SILHOUETTE_NOTE.into(), true.into());
        }
        Output {
            pixels: Pixels::Gray(rendering.image),
            targets: Some(targets),
            surface: Some(SurfaceLayers {
                depth: surface.depth,
                normals: surface.normals,
                mask: surface.mask,
                albedo: None,
                shading: Some(rendering.shading),
            }),
            svg: None,
            notes,
        }
    }

    /// A gray picture drawn as vector graphics, with its targets and notes.
    pub(crate) fn drawn(
        image: Image,
        targets: Targets,
        svg: String,
        notes: Map<String, Value>,
    ) -> Self {
        Output {
            pixels: Pixels::Gray(image),
            targets: Some(targets),
            surface: None,
            svg: Some(svg),
            notes,
        }
    }

    /// A gray output with no targets, layers or notes.
    pub fn gray(image: Image) -> Self {
        Output {
            pixels: Pixels::Gray(image),
            targets: None,
            surface: None,
            svg: None,
            notes: Map::new(),
        }
    }

    /// The picture's luminance, when it is a gray picture (what shape from shading reads).
    pub fn image(&self) -> Result<&Image> {
        match &self.pixels {
            Pixels::Gray(image) => Ok(image),
            Pixels::Rgb(_) => Err(Error::invalid(
                "a colour picture has no single luminance: render a gray one",
            )),
        }
    }

    /// The rendered surface's layers (depth, normals, mask), when it is a rendered surface.
    pub fn surface_layers(&self) -> Result<&SurfaceLayers> {
        self.surface.as_ref().ok_or_else(|| {
            Error::invalid("only a rendered surface has layers (depth, normals, mask)")
        })
    }
}

/// A stimulus that shadelab can render.
pub trait Stimulus: Send + Sync {
    /// Its name, parameters and defaults.
    fn info(&self) -> Info;

    /// Renders it.
    fn generate(&self, request: &Request) -> Result<Output>;

    /// The size in pixels, (width, height), the stimulus has by nature (a depth map's own
    /// size), used when the user gives no size in pixels.
    fn natural_shape(&self, _params: &Params) -> Result<Option<(usize, usize)>> {
        Ok(None)
    }
}

/// The size in pixels that typed parameters give a stimulus, if any.
type NaturalShape<P> = fn(&P) -> Result<Option<(usize, usize)>>;

/// A stimulus drawn by a typed function from its typed parameters `P`: the one place where
/// the generic [`Params`] of a [`Request`] become a typed struct.
pub(crate) struct Typed<P> {
    name: &'static str,
    summary: &'static str,
    default_visual_size: (f64, f64),
    default_ppd: f64,
    render: fn(&P, &Geometry, u64) -> Result<Output>,
    natural: NaturalShape<P>,
}

impl<P: ParamSet + Send + Sync + 'static> Typed<P> {
    /// A stimulus called `name` with its default size, drawn by `render(params, geometry, seed)`
    /// (set `natural` for one whose parameters give its size in pixels).
    pub(crate) fn new(
        name: &'static str,
        summary: &'static str,
        default_visual_size: (f64, f64),
        default_ppd: f64,
        render: fn(&P, &Geometry, u64) -> Result<Output>,
    ) -> Self {
        Typed {
            name,
            summary,
            default_visual_size,
            default_ppd,
            render,
            natural: |_| Ok(None),
        }
    }

    /// [`Typed::new`], boxed.
    pub(crate) fn boxed(
        name: &'static str,
        summary: &'static str,
        default_visual_size: (f64, f64),
        default_ppd: f64,
        render: fn(&P, &Geometry, u64) -> Result<Output>,
    ) -> Box<dyn Stimulus> {
        Box::new(Self::new(
            name,
            summary,
            default_visual_size,
            default_ppd,
            render,
        ))
    }
}

impl<P: ParamSet + Send + Sync> Stimulus for Typed<P> {
    fn info(&self) -> Info {
        Info {
            name: self.name,
            summary: self.summary,
            params: P::specs(),
            default_visual_size: self.default_visual_size,
            default_ppd: self.default_ppd,
        }
    }

    fn generate(&self, request: &Request) -> Result<Output> {
        let params = P::from_params(&request.params)?;
        (self.render)(&params, &request.geometry, request.seed)
    }

    fn natural_shape(&self, params: &Params) -> Result<Option<(usize, usize)>> {
        (self.natural)(&P::from_params(params)?)
    }
}

/// Every stimulus, in the order `list` shows them.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    let mut v: Vec<Box<dyn Stimulus>> = Vec::new();
    v.extend(surfaces::all());
    v.extend(bumps::all());
    v.extend(crater::all());
    v.extend(strips::all());
    v.extend(circles::all());
    v.extend(boundary_strips::all());
    v.extend(hollow_mask::all());
    v.extend(checker_shadow::all());
    v.extend(fading_disk::all());
    v.extend(checkerboard::all());
    v.extend(reflectance_map::all());
    v
}

/// The names of every stimulus.
pub fn names() -> Vec<&'static str> {
    all().iter().map(|s| s.info().name).collect()
}

/// Checks that every name in `given` is a parameter of the stimulus `name` or one of its
/// stimupy names (`check_visual_size` for `checkerboard`'s `check`), naming the nearest among
/// those and `also` (the caller's other names, such as a Python function's keywords) when one
/// is not ([`Params::check_names`]).
pub fn check_param_names<'a>(
    name: &str,
    given: impl IntoIterator<Item = &'a String>,
    also: &[&str],
) -> Result<()> {
    let stimupy: Vec<&str> = stimupy_names::ALIASES
        .iter()
        .filter(|a| a.stimulus == name)
        .map(|a| a.stimupy)
        .collect();
    let own = given
        .into_iter()
        .filter(|key| !stimupy.contains(&key.as_str()));
    Params::check_names(&find(name)?.info().params, own, also)
}

/// The stimulus called `name`; the error lists the valid names.
pub fn find(name: &str) -> Result<Box<dyn Stimulus>> {
    all()
        .into_iter()
        .find(|s| s.info().name == name)
        .ok_or_else(|| Error::unknown("stimulus", name, &names()))
}

/// Declares a struct that asks for a stimulus by name, with the fields that a stimulus spec
/// file and an entry of a study spec share (`stimulus`, `params`, `visual_size`, `ppd`,
/// `shape`, in that order), then its own fields, and a `size` method that gathers the size
/// triple. The doc comment before `params;` documents the parameters.
#[macro_export]
macro_rules! stimulus_request {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            #[doc = $params_doc:literal]
            params;
            $($rest:tt)*
        }
    ) => {
        $(#[$meta])*
        pub struct $name {
            /// The stimulus name.
            pub stimulus: String,
            #[doc = $params_doc]
            #[serde(default)]
            pub params: serde_json::Map<String, serde_json::Value>,
            /// Visual size (height, width) in degrees, as stimupy's `visual_size`.
            #[serde(default)]
            pub visual_size: Option<(f64, f64)>,
            /// Pixels per degree.
            #[serde(default)]
            pub ppd: Option<f64>,
            /// Size (height, width) in pixels, as stimupy's `shape`.
            #[serde(default)]
            pub shape: Option<(usize, usize)>,
            $($rest)*
        }

        impl $name {
            /// The size request this makes.
            pub fn size(&self) -> ::shadelab_core::visual_size::SizeRequest {
                ::shadelab_core::visual_size::SizeRequest {
                    visual_size: self.visual_size,
                    ppd: self.ppd,
                    shape: self.shape,
                }
            }
        }
    };
}

stimulus_request! {
/// A stimulus spec file: `{"stimulus": NAME, "params": {...}, "visual_size": [h, w],
/// "ppd": N, "shape": [h, w], "seed": S}`; everything but `stimulus` is optional. Sizes are
/// (height, width) as in stimupy: `"visual_size": [4, 8], "ppd": 32` is 128 rows × 256 columns.
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    /// Parameter values (checked against the stimulus's declarations).
    params;
    /// Random seed.
    #[serde(default)]
    pub seed: Option<u64>,
    /// A caption for the gallery: what a viewer sees and why.
    #[serde(default)]
    pub caption: Option<String>,
    /// A title for the gallery.
    #[serde(default)]
    pub title: Option<String>,
    /// The docs page and anchor that explain it, from the repository root
    /// (`docs/priors.md#light-from-above`); the gallery links to it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub docs: Option<String>,
}
}

impl Spec {
    /// Reads and checks a spec file.
    pub fn load(path: &std::path::Path) -> Result<Spec> {
        let bytes = crate::io::read_bytes(path)?;
        serde_json::from_slice(&bytes)
            .map_err(|e| Error::format(path, format!("bad stimulus spec: {e}")))
    }
}

/// Resolves a render: finds the stimulus, checks the parameters against its declarations and
/// resolves the size triple against its defaults.
pub fn prepare(
    name: &str,
    given: &Map<String, Value>,
    size: &SizeRequest,
    seed: u64,
    max_pixels: usize,
) -> Result<(Box<dyn Stimulus>, Request)> {
    let stimulus = find(name)?;
    let info = stimulus.info();
    let given = stimupy_names::translate(name, given)?;
    let params = Params::resolve(&info.params, &given)
        .map_err(|e| Error::invalid(format!("{name}: {e}")))?;
    let mut size = *size;
    if size.shape.is_none() && !(size.visual_size.is_some() && size.ppd.is_some()) {
        size.shape = stimulus.natural_shape(&params)?.map(|(w, h)| (h, w));
    }
    let geometry = size.resolve(info.default_visual_size, info.default_ppd, max_pixels)?;
    Ok((
        stimulus,
        Request {
            params,
            geometry,
            seed,
        },
    ))
}

/// How far outside 0..1 a value may lie as floating-point rounding (1 ± 1e-9 is 65535 in
/// 16 bits and exactly 1.0 in float32).
const RANGE_ROUNDING: f64 = 1e-9;

/// The range rule: a stimulus is linear luminance from the display's black (0) to its white
/// (1), in every format. A picture that leaves 0..1 — a specular highlight, an ambient level
/// that lifts a lit surface over white — is refused with its extreme and the scale that would
/// fit it, never clipped or rescaled behind the user's back (docs/display.md).
fn check_range(name: &str, params: &Params, pixels: &Pixels) -> Result<()> {
    let (lo, hi) = pixels.extremes();
    if lo.is_nan() || hi.is_nan() || (lo >= -RANGE_ROUNDING && hi <= 1.0 + RANGE_ROUNDING) {
        return Ok(());
    }
    let count = |out: &dyn Fn(f64) -> bool| -> usize {
        match pixels {
            Pixels::Gray(i) => i.data().iter().filter(|&&v| out(v)).count(),
            Pixels::Rgb(i) => i
                .data()
                .iter()
                .filter(|p| p.iter().any(|&v| out(v)))
                .count(),
        }
    };
    if lo < -RANGE_ROUNDING {
        let n = count(&|v| v < -RANGE_ROUNDING);
        return Err(Error::invalid(format!(
            "{name}: luminance reaches {lo:.4} ({n} pixels below 0, the display's black); raise the darkest parameter"
        )));
    }
    let n = count(&|v| v > 1.0 + RANGE_ROUNDING);
    // The light adds up linearly in these parameters: scaled by 1/peak they give the same
    // picture with its peak at white.
    let specular = params.get("brdf").ok().and_then(Value::as_str) == Some("blinn-phong");
    let scaled: Vec<String> = ["albedo", "ambient", "specular"]
        .into_iter()
        .filter(|&p| p != "specular" || specular)
        .filter_map(|p| Some((p, params.get(p).ok()?.as_f64()?)))
        .map(|(p, v)| {
            // Rounded down to 4 decimals, so that the peak lands at or just below 1.
            let text = format!("{:.4}", (v / hi * 1e4).floor() / 1e4);
            format!("{p}={}", text.trim_end_matches('0').trim_end_matches('.'))
        })
        .collect();
    let fix = if scaled.is_empty() {
        "lower the brightest parameter".to_string()
    } else {
        format!(
            "set {} (the same picture with its peak at 1), or lower them",
            scaled.join(" ")
        )
    };
    Err(Error::invalid(format!(
        "{name}: luminance reaches {hi:.4} ({n} pixels above 1, the display's white; a stimulus is 0..1 and is never clipped): {fix}"
    )))
}

/// Prepares and renders in one step, and holds the picture to the range rule
/// (0..1, refused with the fix otherwise: docs/display.md).
pub fn generate(
    name: &str,
    given: &Map<String, Value>,
    size: &SizeRequest,
    seed: u64,
    max_pixels: usize,
) -> Result<(Request, Output)> {
    let (stimulus, request) = prepare(name, given, size, seed, max_pixels)?;
    let mut output = stimulus.generate(&request)?;
    check_range(name, &request.params, &output.pixels)?;
    if let Some(asked) = size.rounded_visual_size(&request.geometry) {
        let g = &request.geometry;
        output.notes.insert(
            ROUNDED_NOTE.into(),
            serde_json::json!({
                "asked_visual_size": [asked.0, asked.1],
                "visual_size": [g.height_deg(), g.width_deg()],
                "shape": [g.height, g.width],
            }),
        );
    }
    Ok((request, output))
}

/// The note of a render whose visual size whole pixels made smaller (stimupy's rounding
/// down), recorded in the sidecar's notes; the command line and Python say it as a warning.
pub const ROUNDED_NOTE: &str = "visual_size_rounded";

/// The warning a render with [`ROUNDED_NOTE`] gives, in one line.
pub fn rounded_warning(name: &str, g: &Geometry, asked: (f64, f64)) -> String {
    format!(
        "{name}: visual size {} at {} ppd is {}, rounded down to whole pixels as stimupy does: \
         {}",
        SizeText::Degrees(asked.0, asked.1),
        g.ppd,
        SizeText::Pixels(g.height, g.width),
        g.size_text()
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_described() {
        let names = names();
        let mut sorted = names.clone();
        sorted.sort();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len());
        for s in all() {
            let info = s.info();
            assert!(!info.summary.is_empty());
            // Every default must pass its own check.
            Params::resolve(&info.params, &Map::new()).unwrap();
        }
    }

    fn defaults_round_trip<P: ParamSet + PartialEq + std::fmt::Debug>() {
        let resolved = Params::resolve(&P::specs(), &Map::new()).unwrap();
        assert_eq!(P::default(), P::from_params(&resolved).unwrap());
        assert_eq!(P::default().to_params().unwrap(), resolved);
    }

    #[test]
    fn typed_defaults_are_the_declared_defaults() {
        defaults_round_trip::<BoundaryStripsParams>();
        defaults_round_trip::<BumpsParams>();
        defaults_round_trip::<SidewaysParams>();
        defaults_round_trip::<CheckerShadowParams>();
        defaults_round_trip::<CheckerboardParams>();
        defaults_round_trip::<DiscParams>();
        defaults_round_trip::<CirclesParams>();
        defaults_round_trip::<CraterParams>();
        defaults_round_trip::<FadingDiskParams>();
        defaults_round_trip::<HollowMaskParams>();
        defaults_round_trip::<ReflectanceMapParams>();
        defaults_round_trip::<StripsParams>();
        defaults_round_trip::<SphereParams>();
        defaults_round_trip::<EllipsoidParams>();
        defaults_round_trip::<GaussianParams>();
        defaults_round_trip::<VaseParams>();
        defaults_round_trip::<HeightfieldParams>();
        defaults_round_trip::<BunnyParams>();
        defaults_round_trip::<MeshParams>();
        // Overridden defaults of a shared set reach the typed default.
        let mask = HollowMaskParams::default();
        assert_eq!((mask.lighting.albedo, mask.backdrop.background), (0.7, 0.1));
        assert_eq!(SidewaysParams::default().discs.pattern, DiscPattern::Rows);
        assert_eq!(BumpsParams::default().discs.pattern, DiscPattern::Random);
    }

    #[test]
    fn by_name_and_typed_give_the_same_output_and_params() {
        let given = Params::parse_pairs(&["light=left", "profile=gaussian", "rows=2"]).unwrap();
        let size = SizeRequest {
            visual_size: Some((10.0, 14.0)),
            ppd: Some(16.0),
            shape: None,
        };
        let (request, by_name) = generate("bumps", &given, &size, 5, 1 << 20).unwrap();
        let typed = BumpsParams::from_map(&given).unwrap();
        assert_eq!(typed.discs.profile, DiscProfile::Gaussian);
        assert_eq!(typed.light, "left".parse().unwrap());
        assert_eq!(typed.to_params().unwrap(), request.params);
        assert_eq!(bumps(&typed, &request.geometry, 5).unwrap(), by_name);
    }

    #[test]
    fn typed_values_are_range_checked() {
        let p = SphereParams {
            radius: 7.0,
            ..Default::default()
        };
        let g = Geometry {
            width: 8,
            height: 8,
            ppd: 1.0,
        };
        let e = sphere(&p, &g).unwrap_err().to_string();
        assert!(e.contains("radius") && e.contains("0.01..5"), "{e}");
        let p = CirclesParams {
            rows: 0,
            ..Default::default()
        };
        assert!(p.validate().unwrap_err().to_string().contains("rows"));
    }

    #[test]
    fn unknown_names_list_the_valid_ones() {
        let e = find("teapot").err().unwrap().to_string();
        assert!(e.contains("teapot") && e.contains("sphere"), "{e}");
        let spec: std::result::Result<Spec, _> =
            serde_json::from_str(r#"{"stimulus":"sphere","colour":1}"#);
        assert!(spec.is_err());
    }
}
