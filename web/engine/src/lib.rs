//! The teaching page's engine: shadelab's core compiled to WebAssembly.
//!
//! One call, [`frame`], does a frame's work with the library's own pipelines and nothing
//! else: it renders the chosen stimulus under the true light
//! ([`shadelab::pipeline::source::PictureSource`], as `shadelab render` renders it), turns it by
//! 180° when asked ([`rotate_quarter_turns`]), solves it under the *assumed* light
//! with the Ikeuchi–Horn engine and integrates the result to depth
//! ([`shadelab::pipeline::perception`] and [`Interpreter`], as
//! `shadelab analyze prior-sweep` does for each tilt), and reads the central target
//! ([`central_token`]): its signed convexity and verdict, and the direction its
//! bright side faces ([`shadelab::pipeline::perception::Token::bright_side`]). [`p_convex_model`] is the observer's
//! P(convex) for that direction.
//!
//! The browser talks to it through a plain C ABI over the module's linear memory (the `sl_*`
//! functions at the end): numbers in, pointers to byte and `f32` buffers out, and JSON text for
//! the few named values. No wasm-bindgen: the page needs eight calls, and the plain ABI keeps
//! the build to one `cargo build` (see docs/teaching.md).

use serde_json::{json, Value};
use shadelab::pipeline::fit::ModelParams;
use shadelab::pipeline::perception::{
    self, central_token, rotate_quarter_turns, wrap_360, Interpreter, Verdict,
};
use shadelab::pipeline::source::PictureSource;
use shadelab::Colormap;
use shadelab::{Error, Pixels, Result};
use std::cell::RefCell;

/// How the page's light dial reaches a stimulus's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lit {
    /// A rendered surface: the dial sets its `light` to `tilt=T,slant=S`.
    Light,
    /// The sideways discs: the dial's tilt picks the side (`left` for tilts 0..180, else
    /// `right`) and its slant the `slant`.
    Side,
    /// Painted gradients (the strips): the dial does nothing; rotate the picture instead.
    Painted,
}

/// One stimulus of the page: the library's stimulus, the parameters the page fixes, and what
/// the page says about it.
#[derive(Debug, Clone, Copy)]
pub struct Stimulus {
    /// Its name, as `shadelab list` prints it (and the page's `stimulus` parameter).
    pub name: &'static str,
    /// Parameters the page fixes, as (key, JSON value).
    pub params: &'static [(&'static str, &'static str)],
    /// How the light dial reaches it.
    pub lit: Lit,
    /// Two or three sentences for the class.
    pub explanation: &'static str,
    /// The docs page (path in the repository, with its section) that explains it.
    pub docs: &'static str,
}

/// The page's stimuli, in the picker's order.
pub const STIMULI: &[Stimulus] = &[
    Stimulus {
        name: "gaussian",
        params: &[],
        lit: Lit::Light,
        explanation: "One smooth bump on a plane. Lit from above it looks like a bump; move the light below and the same bump looks like a dent. The engine cannot tell them apart either: assume the opposite light and it recovers a dent that explains the picture just as well.",
        docs: "docs/problem.md#the-reflectance-map",
    },
    Stimulus {
        name: "bumps",
        params: &[("rows", "3"), ("columns", "3"), ("pattern", "\"alternate\"")],
        lit: Lit::Light,
        explanation: "Discs shaded as bumps and dimples under one light. Vision assumes the light comes from above (a little to the left), so discs bright on top look like bumps. Turn the picture by 180° and every bump becomes a dimple.",
        docs: "docs/priors.md#light-from-above",
    },
    Stimulus {
        name: "sideways",
        params: &[],
        lit: Lit::Side,
        explanation: "The same discs lit from the side. The light-from-above prior says little about left or right, so each disc flips between bump and dimple (bistable); the prior's small leftward bias tips discs lit from the left toward bumps. The light dial only picks the side: left or right.",
        docs: "docs/priors.md#light-from-the-side",
    },
    Stimulus {
        name: "crater",
        params: &[("light_size", "0")],
        lit: Lit::Light,
        explanation: "A mound with a crater in its top, lit from above. Turn the picture by 180°: vision keeps the light above and sees a crater with a mound in it. The engine's reading follows the assumed light in the same way.",
        docs: "docs/priors.md#a-crater-turned-upside-down",
    },
    Stimulus {
        name: "strips",
        params: &[],
        lit: Lit::Painted,
        explanation: "Parallel strips with opposite luminance gradients. If one strip is seen as a ridge, its neighbours are seen as grooves: one light for the whole scene. The gradients are painted, so the light dial does nothing here; rotate the picture or turn the assumed light.",
        docs: "docs/priors.md#one-light-for-the-whole-scene",
    },
    Stimulus {
        name: "hollow-mask",
        params: &[("mode", "\"hollow\"")],
        lit: Lit::Light,
        explanation: "A hollow face lit from above. Vision sees a normal, convex face lit from below: knowing what faces look like beats the light-from-above prior. Raise the convexity prior π to model that knowledge.",
        docs: "docs/priors.md#the-hollow-mask",
    },
    Stimulus {
        name: "sphere",
        params: &[],
        lit: Lit::Light,
        explanation: "A hemisphere: the classic test of shape from shading. Every orientation facing the viewer appears once, so the picture is a map of the reflectance function. Assume the wrong light and the recovered shape distorts or turns inside out.",
        docs: "docs/ikeuchi-horn.md#reconstructions",
    },
];

/// The largest picture side the page may ask for, pixels.
pub const MAX_SIZE: usize = 512;
/// The smallest, pixels.
pub const MIN_SIZE: usize = 32;

/// The page's stimulus called `name`, or an error naming the valid ones.
pub fn stimulus(name: &str) -> Result<&'static Stimulus> {
    STIMULI.iter().find(|s| s.name == name).ok_or_else(|| {
        let names: Vec<&str> = STIMULI.iter().map(|s| s.name).collect();
        Error::invalid(format!(
            "unknown stimulus '{name}': the page shows {}",
            names.join(", ")
        ))
    })
}

/// The page's stimuli as JSON: name, the library's one-line summary, how the light dial
/// reaches it (`light`, `side` or `painted`), the explanation and the docs page.
pub fn stimuli_json() -> Result<Value> {
    let list = STIMULI
        .iter()
        .map(|s| {
            let d = shadelab::pipeline::render::describe(s.name)?;
            Ok(json!({
                "name": s.name,
                "summary": d.summary,
                "lit": match s.lit { Lit::Light => "light", Lit::Side => "side", Lit::Painted => "painted" },
                "explanation": s.explanation,
                "docs": s.docs,
            }))
        })
        .collect::<Result<Vec<Value>>>()?;
    Ok(Value::Array(list))
}

/// A light as the page's dials give it: tilt (0 = from above, +90 = from the left) and slant
/// from the line of sight, degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dial {
    /// Tilt, degrees.
    pub tilt_deg: f64,
    /// Slant, degrees.
    pub slant_deg: f64,
}

/// What one frame is asked to show.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The stimulus's name (see [`STIMULI`]).
    pub stimulus: String,
    /// The picture's longer side, pixels ([`MIN_SIZE`]..=[`MAX_SIZE`]).
    pub size: usize,
    /// The light the stimulus is rendered under.
    pub light: Dial,
    /// Whether the picture is turned by 180°.
    pub rotated: bool,
    /// The light the engine assumes.
    pub assume: Dial,
}

/// One frame's results.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Picture width, pixels.
    pub width: usize,
    /// Picture height, pixels.
    pub height: usize,
    /// The stimulus as shown (turned when asked), display-encoded RGBA.
    pub picture_rgba: Vec<u8>,
    /// The recovered depth as a colour map (viridis: yellow near, blue far), RGBA.
    pub depth_rgba: Vec<u8>,
    /// The recovered depth, pixels toward the viewer, row-major from the top row.
    pub depth: Vec<f32>,
    /// The central target's mask, row-major (1 inside).
    pub target: Vec<u8>,
    /// The central target's name.
    pub target_name: String,
    /// Its centre (column, row), pixels.
    pub target_centre: (f64, f64),
    /// Its signed convexity (> 0 convex).
    pub convexity: f64,
    /// Its verdict.
    pub verdict: Verdict,
    /// The direction its bright side faces (tilt convention, degrees in [0, 360)): the θ of
    /// the observer model.
    pub bright_side_deg: f64,
    /// How lopsided its brightness is toward that side (0 = evenly lit).
    pub bright_side_strength: f64,
    /// Whether the solver converged.
    pub converged: bool,
    /// Solver iterations (multigrid cycles, or Jacobi sweeps after a fallback).
    pub iterations: usize,
}

impl Frame {
    /// The named values as JSON (the buffers are read from memory).
    pub fn summary(&self) -> Value {
        json!({
            "width": self.width,
            "height": self.height,
            "target": self.target_name,
            "target_centre": [self.target_centre.0, self.target_centre.1],
            "convexity": self.convexity,
            "verdict": self.verdict,
            "bright_side_deg": self.bright_side_deg,
            "bright_side_strength": self.bright_side_strength,
            "converged": self.converged,
            "iterations": self.iterations,
        })
    }
}

/// The display gamma of the page's pictures (the gallery's).
const DISPLAY_GAMMA: f64 = shadelab::pipeline::gallery::THUMBNAIL_GAMMA;

fn check_dial(what: &str, d: Dial) -> Result<()> {
    if !d.tilt_deg.is_finite() {
        return Err(Error::invalid(format!(
            "{what} tilt {} must be a number of degrees",
            d.tilt_deg
        )));
    }
    if !(d.slant_deg.is_finite() && (0.0..90.0).contains(&d.slant_deg)) {
        return Err(Error::invalid(format!(
            "{what} slant {} must be in 0..90 degrees",
            d.slant_deg
        )));
    }
    Ok(())
}

/// The stimulus's parameters for the light `light`.
fn params(s: &Stimulus, light: Dial) -> Result<serde_json::Map<String, Value>> {
    let mut map = serde_json::Map::new();
    for (k, v) in s.params {
        let value = serde_json::from_str(v)
            .map_err(|e| Error::Compute(format!("parameter {k} of {}: {e}", s.name)))?;
        map.insert((*k).to_string(), value);
    }
    let tilt = wrap_360(light.tilt_deg);
    match s.lit {
        Lit::Light => {
            map.insert(
                "light".into(),
                json!(format!("tilt={tilt},slant={}", light.slant_deg)),
            );
        }
        Lit::Side => {
            let side = if tilt < 180.0 { "left" } else { "right" };
            map.insert("side".into(), json!(side));
            map.insert("slant".into(), json!(light.slant_deg.min(89.0)));
        }
        Lit::Painted => {}
    }
    Ok(map)
}

/// Renders, turns, solves, integrates and reads one frame (see the crate's documentation).
///
/// Fails with the library's one-line error on an unknown stimulus, a size outside
/// [`MIN_SIZE`]..=[`MAX_SIZE`], or a light that is not a finite tilt and a slant in 0..90.
pub fn frame(request: &Request) -> Result<Frame> {
    let s = stimulus(&request.stimulus)?;
    if !(MIN_SIZE..=MAX_SIZE).contains(&request.size) {
        return Err(Error::invalid(format!(
            "size {} must be {MIN_SIZE}..{MAX_SIZE} pixels",
            request.size
        )));
    }
    check_dial("light", request.light)?;
    check_dial("assumed light", request.assume)?;
    let (visual_h, visual_w) = shadelab::pipeline::render::describe(s.name)?.default_visual_size;
    // The longer side gets `size` pixels; the picture keeps the stimulus's proportions.
    let ppd = request.size as f64 / visual_h.max(visual_w);

    // Render under the true light, as `shadelab render` does.
    let max_pixels = shadelab::DEFAULT_MAX_PIXELS;
    let source = PictureSource {
        stimulus: Some(s.name.to_string()),
        params: params(s, request.light)?,
        ppd: Some(ppd),
        max_pixels,
        ..PictureSource::default()
    };
    let (loaded, _) = source.load_shaped(false, None)?;
    let turns = if request.rotated { 2 } else { 0 };
    let image = rotate_quarter_turns(&loaded.luminance(), turns);
    let (labels, names) = match &loaded.labels {
        Some((l, n)) => (Some(rotate_quarter_turns(l, turns)), n.clone()),
        None => (None, Vec::new()),
    };

    // Interpret the (turned) picture under the assumed light, as the perception analyses do,
    // with the stimulus's own albedo and ambient level.
    let mut config = perception::Config::new(PictureSource {
        pixels: Some(Pixels::Gray(image.clone())),
        labels,
        max_pixels,
        ..PictureSource::default()
    });
    config.slant_deg = request.assume.slant_deg;
    config.albedo = loaded.declared.albedo;
    config.ambient = loaded.declared.ambient;
    let setup = config.load(&shadelab::NoProgress)?;
    let scene = setup.scene();
    let reading = Interpreter::new(&scene, &setup.options)?
        .keep_depth(true)
        .interpret(&scene, request.assume.tilt_deg, &setup.lighting)?;
    let depth = reading
        .depth
        .ok_or_else(|| Error::Compute("the interpretation kept no depth".into()))?;

    // The central target.
    let (w, h) = (image.width(), image.height());
    let k = central_token(&setup.picture.tokens, w, h)
        .ok_or_else(|| Error::Compute("the picture has no target".into()))?;
    let token = &setup.picture.tokens[k];
    let mut target = vec![0u8; w * h];
    for &p in token.pixels() {
        target[p] = 1;
    }
    let (bright_side, lopsided) = token.bright_side(&image);
    let convexity = reading.tokens[k].convexity;
    let target_name = names
        .get(usize::from(token.label).wrapping_sub(1))
        .cloned()
        .unwrap_or_else(|| token.name.clone());

    // Pictures for the page.
    let picture_rgba =
        shadelab::display::display_rgba8(&image.map(|&v| [v; 3]), Some(DISPLAY_GAMMA))?;
    let (lo, hi) = depth
        .data()
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &z| {
            (lo.min(z), hi.max(z))
        });
    let colours = Colormap::Viridis.paint(&depth, (lo, hi), None, [0.0; 3]);
    let depth_rgba = shadelab::display::display_rgba8(&colours, Some(DISPLAY_GAMMA))?;
    Ok(Frame {
        width: w,
        height: h,
        picture_rgba,
        depth_rgba,
        depth: depth.data().iter().map(|&z| z as f32).collect(),
        target,
        target_name,
        target_centre: token.centroid(w),
        convexity,
        verdict: Verdict::of(convexity),
        bright_side_deg: bright_side,
        bright_side_strength: lopsided,
        converged: reading.converged,
        iterations: reading.iterations,
    })
}

/// The observer's P(convex | θ) for the bright side facing `theta_deg` (tilt convention), with
/// the prior's light tilt `mu_deg`, concentration `kappa`, convexity prior `pi` and lapse rate
/// `lapse`: the library's one observer model
/// ([`shadelab::pipeline::fit::ModelParams::p_convex`]), the model `shadelab fit
/// observer` estimates. NaN when a value is out of range (κ < 0, π or λ outside 0..1), so the
/// page shows no number rather than a wrong one.
///
/// ```
/// use shadelab_web::p_convex_model;
/// assert!((p_convex_model(26.0, 26.0, 0.0, 0.5, 0.0) - 0.5).abs() < 1e-12);
/// assert!(p_convex_model(0.0, 26.0, 2.0, 0.5, 0.0) > 0.9);
/// assert!(p_convex_model(180.0, 26.0, 2.0, 0.5, 0.0) < 0.1);
/// ```
pub fn p_convex_model(theta_deg: f64, mu_deg: f64, kappa: f64, pi: f64, lapse: f64) -> f64 {
    let model = ModelParams {
        tilt_deg: mu_deg,
        kappa,
        convexity_prior: pi,
        lapse,
    };
    match (theta_deg.is_finite(), model.validate()) {
        (true, Ok(())) => model.p_convex(theta_deg),
        _ => f64::NAN,
    }
}

// ---- The C ABI the page calls (one instance, one thread). ----

/// What the last calls left for the page to read.
#[derive(Default)]
struct State {
    frame: Option<Frame>,
    text: String,
}

thread_local! {
    static STATE: RefCell<State> = RefCell::new(State::default());
}

/// Memory for `len` bytes the page writes into (a stimulus name); free with [`sl_free`].
#[no_mangle]
pub extern "C" fn sl_alloc(len: usize) -> *mut u8 {
    let mut buffer = vec![0u8; len].into_boxed_slice();
    let ptr = buffer.as_mut_ptr();
    std::mem::forget(buffer);
    ptr
}

/// Frees what [`sl_alloc`] gave, with the same length.
///
/// # Safety
/// `ptr` and `len` must come from one call of [`sl_alloc`], freed once.
#[no_mangle]
pub unsafe extern "C" fn sl_free(ptr: *mut u8, len: usize) {
    if !ptr.is_null() {
        drop(Box::from_raw(std::ptr::slice_from_raw_parts_mut(ptr, len)));
    }
}

/// Puts the page's stimuli ([`stimuli_json`]) in the text buffer; 1 on success, 0 with the
/// error in the text buffer.
#[no_mangle]
pub extern "C" fn sl_stimuli() -> u32 {
    let result = stimuli_json().map(|v| v.to_string());
    store_text(result)
}

/// Runs [`frame`]: 1 on success (the summary JSON in the text buffer, the buffers readable),
/// 0 on failure (the one-line error in the text buffer, no buffers).
///
/// # Safety
/// `name_ptr` must point to `name_len` readable bytes (from [`sl_alloc`]).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn sl_frame(
    name_ptr: *const u8,
    name_len: usize,
    size: u32,
    light_tilt: f64,
    light_slant: f64,
    rotated: u32,
    assume_tilt: f64,
    assume_slant: f64,
) -> u32 {
    let bytes = std::slice::from_raw_parts(name_ptr, name_len);
    let name = String::from_utf8_lossy(bytes).into_owned();
    let request = Request {
        stimulus: name,
        size: size as usize,
        light: Dial {
            tilt_deg: light_tilt,
            slant_deg: light_slant,
        },
        rotated: rotated != 0,
        assume: Dial {
            tilt_deg: assume_tilt,
            slant_deg: assume_slant,
        },
    };
    let result = frame(&request);
    STATE.with(|s| {
        let mut s = s.borrow_mut();
        match result {
            Ok(f) => {
                s.text = f.summary().to_string();
                s.frame = Some(f);
                1
            }
            Err(e) => {
                s.text = e.to_string();
                s.frame = None;
                0
            }
        }
    })
}

fn store_text(result: Result<String>) -> u32 {
    STATE.with(|s| {
        let mut s = s.borrow_mut();
        match result {
            Ok(t) => {
                s.text = t;
                1
            }
            Err(e) => {
                s.text = e.to_string();
                0
            }
        }
    })
}

/// The text buffer (UTF-8): the last call's JSON or error.
#[no_mangle]
pub extern "C" fn sl_text_ptr() -> *const u8 {
    STATE.with(|s| s.borrow().text.as_ptr())
}

/// The text buffer's length in bytes.
#[no_mangle]
pub extern "C" fn sl_text_len() -> usize {
    STATE.with(|s| s.borrow().text.len())
}

/// A buffer of the last frame: 0 the picture (RGBA), 1 the depth colour map (RGBA), 2 the
/// depth (`f32`), 3 the central target's mask (bytes). Null without a frame.
#[no_mangle]
pub extern "C" fn sl_buffer(which: u32) -> *const u8 {
    STATE.with(|s| {
        let s = s.borrow();
        match (&s.frame, which) {
            (Some(f), 0) => f.picture_rgba.as_ptr(),
            (Some(f), 1) => f.depth_rgba.as_ptr(),
            (Some(f), 2) => f.depth.as_ptr().cast(),
            (Some(f), 3) => f.target.as_ptr(),
            _ => std::ptr::null(),
        }
    })
}

/// [`p_convex_model`] for the page.
#[no_mangle]
pub extern "C" fn sl_p_convex(theta: f64, mu: f64, kappa: f64, pi: f64, lapse: f64) -> f64 {
    p_convex_model(theta, mu, kappa, pi, lapse)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(stimulus: &str, light_tilt: f64, assume_tilt: f64) -> Request {
        Request {
            stimulus: stimulus.into(),
            size: 128,
            light: Dial {
                tilt_deg: light_tilt,
                slant_deg: 45.0,
            },
            rotated: false,
            assume: Dial {
                tilt_deg: assume_tilt,
                slant_deg: 45.0,
            },
        }
    }

    #[test]
    fn the_bump_reads_convex_under_the_true_light_and_concave_under_the_opposite() {
        let right = frame(&request("gaussian", 0.0, 0.0)).unwrap();
        assert_eq!(right.verdict, Verdict::Convex, "{:?}", right.summary());
        assert_eq!((right.width, right.height), (128, 128));
        assert_eq!(right.picture_rgba.len(), 128 * 128 * 4);
        assert_eq!(right.depth.len(), 128 * 128);
        // Lit from above, the bump's bright side faces up.
        let up = right.bright_side_deg;
        assert!(!(20.0..340.0).contains(&up), "{up}");
        let wrong = frame(&request("gaussian", 0.0, 180.0)).unwrap();
        assert_eq!(wrong.verdict, Verdict::Concave, "{:?}", wrong.summary());
        // The same picture either way.
        assert_eq!(right.picture_rgba, wrong.picture_rgba);
    }

    #[test]
    fn turning_the_picture_turns_the_bright_side_and_the_reading() {
        let mut r = request("gaussian", 0.0, 0.0);
        r.rotated = true;
        let turned = frame(&r).unwrap();
        assert_eq!(turned.verdict, Verdict::Concave);
        assert!((turned.bright_side_deg - 180.0).abs() < 20.0);
        let upright = frame(&request("gaussian", 0.0, 0.0)).unwrap();
        // Exactly the upright picture turned: the first row is the last row reversed.
        let row = |f: &Frame, r: usize| f.picture_rgba[r * 512..(r + 1) * 512].to_vec();
        let last: Vec<u8> = row(&upright, 127)
            .chunks(4)
            .rev()
            .flatten()
            .copied()
            .collect();
        assert_eq!(row(&turned, 0), last);
    }

    #[test]
    fn every_stimulus_renders_solves_and_reads_its_central_target() {
        for s in STIMULI {
            let f = frame(&request(s.name, 0.0, 0.0)).unwrap_or_else(|e| panic!("{}: {e}", s.name));
            assert!(f.width.max(f.height) == 128, "{}", s.name);
            assert!(f.target.contains(&1), "{}", s.name);
            assert!(f.convexity.is_finite(), "{}", s.name);
        }
        let json = stimuli_json().unwrap();
        assert_eq!(json.as_array().unwrap().len(), STIMULI.len());
    }

    #[test]
    fn bad_requests_are_one_line_errors() {
        let mut r = request("teapot", 0.0, 0.0);
        let e = frame(&r).unwrap_err().to_string();
        assert!(e.contains("teapot") && e.contains("gaussian"), "{e}");
        r.stimulus = "gaussian".into();
        r.size = 4;
        assert!(frame(&r).unwrap_err().to_string().contains("size 4"));
        r.size = 128;
        r.assume.slant_deg = 95.0;
        assert!(frame(&r).unwrap_err().to_string().contains("slant 95"));
        r.assume.slant_deg = 45.0;
        r.light.tilt_deg = f64::NAN;
        assert!(frame(&r).unwrap_err().to_string().contains("light tilt"));
    }

    #[test]
    fn every_docs_link_names_a_page_and_heading_that_exist() {
        let slug = |h: &str| -> String {
            h.trim()
                .to_lowercase()
                .chars()
                .filter_map(|c| match c {
                    ' ' => Some('-'),
                    c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                    _ => None,
                })
                .collect()
        };
        for s in STIMULI {
            let (page, anchor) = s.docs.split_once('#').unwrap();
            let text = std::fs::read_to_string(format!("../../{page}"))
                .unwrap_or_else(|e| panic!("{}: {page}: {e}", s.name));
            assert!(
                text.lines()
                    .filter_map(|l| l.strip_prefix('#'))
                    .any(|h| slug(h.trim_start_matches('#')) == anchor),
                "{}: no heading #{anchor} in {page}",
                s.name
            );
        }
    }

    #[test]
    fn the_observer_model() {
        // No prior: one half; a lapse pulls toward one half.
        assert_eq!(p_convex_model(90.0, 26.0, 0.0, 0.5, 0.0), 0.5);
        let p = p_convex_model(26.0, 26.0, 2.0, 0.5, 0.0);
        assert!((p - 1.0 / (1.0 + (-4.0f64).exp())).abs() < 1e-12, "{p}");
        let q = p_convex_model(26.0, 26.0, 2.0, 0.5, 0.2);
        assert!((q - (0.1 + 0.8 * p)).abs() < 1e-12);
        // Opposite bright sides are complementary without a convexity prior.
        let (a, b) = (
            p_convex_model(40.0, 26.0, 3.0, 0.5, 0.0),
            p_convex_model(220.0, 26.0, 3.0, 0.5, 0.0),
        );
        assert!((a + b - 1.0).abs() < 1e-12);
        // A convexity prior lifts P(convex) even for light from below; huge κ does not overflow.
        assert!(
            p_convex_model(180.0, 26.0, 1.0, 0.9, 0.0) > p_convex_model(180.0, 26.0, 1.0, 0.5, 0.0)
        );
        assert_eq!(p_convex_model(206.0, 26.0, 1e6, 0.5, 0.0), 0.0);
        assert!(p_convex_model(0.0, 26.0, -1.0, 0.5, 0.0).is_nan());
    }

    #[test]
    fn the_c_abi_round_trip() {
        let name = b"gaussian";
        let ptr = sl_alloc(name.len());
        unsafe {
            std::ptr::copy_nonoverlapping(name.as_ptr(), ptr, name.len());
            assert_eq!(sl_frame(ptr, name.len(), 64, 0.0, 45.0, 0, 0.0, 45.0), 1);
            sl_free(ptr, name.len());
        }
        let text = unsafe { std::slice::from_raw_parts(sl_text_ptr(), sl_text_len()) };
        let v: Value = serde_json::from_slice(text).unwrap();
        assert_eq!(v["verdict"], "convex");
        assert!(!sl_buffer(2).is_null() && sl_buffer(9).is_null());
        let bad = b"teapot";
        unsafe {
            assert_eq!(
                sl_frame(bad.as_ptr(), bad.len(), 64, 0.0, 45.0, 0, 0.0, 45.0),
                0
            )
        };
        assert!(sl_buffer(0).is_null());
        assert_eq!(sl_stimuli(), 1);
    }
}
