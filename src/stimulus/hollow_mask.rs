//! `hollow-mask`: a procedural face relief, convex or hollow, under any light. A hollow face lit
//! from above is seen as a normal, convex face lit from below: knowledge of faces overrides
//! the light-from-above prior (Gregory 1970; Hill & Bruce 1993).
//!
//! The face is a smooth heightfield with no data files: a flattened half-ellipsoid head with
//! Gaussian features (forehead, brow ridges, eye sockets and eyes, nose ridge and tip, nostril
//! wings, cheeks, lips and the line between them, chin), in units of the face's half-width.
//! The hollow face is the convex one with depth negated, so its normals are (−n_x, −n_y, n_z)
//! exactly: without cast shadows, the hollow face under light s is pixel for pixel the convex
//! face under (−s_x, −s_y, s_z) (tilt + 180°).

use super::frame::{smoothstep, Frame};
use super::surfaces::{BackdropParams, LightingParams};
use super::{Output, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::render::render;
use crate::surface::Surface;
use crate::visual_size::Geometry;
use serde_json::{json, Map};

/// Face outline: u² + (v/OVAL)² < 1 in units of the half-width.
const OVAL: f64 = 1.35;

/// One Gaussian feature: centre (u, v), spreads, height (negative: a hollow); mirrored in u
/// when `pair`.
struct Feature {
    u: f64,
    v: f64,
    su: f64,
    sv: f64,
    h: f64,
    pair: bool,
}

const fn f(u: f64, v: f64, su: f64, sv: f64, h: f64, pair: bool) -> Feature {
    Feature {
        u,
        v,
        su,
        sv,
        h,
        pair,
    }
}

/// The features of the face, in units of its half-width (v up).
const FEATURES: &[Feature] = &[
    f(0.0, 0.62, 0.55, 0.3, 0.06, false),     // forehead
    f(0.33, 0.36, 0.22, 0.09, 0.07, true),    // brow ridges
    f(0.33, 0.16, 0.2, 0.15, -0.17, true),    // eye sockets
    f(0.33, 0.15, 0.11, 0.08, 0.07, true),    // eyes
    f(0.0, -0.2, 0.13, 0.12, 0.11, false),    // nose tip
    f(0.14, -0.25, 0.08, 0.07, 0.05, true),   // nostril wings
    f(0.45, -0.17, 0.2, 0.2, 0.08, true),     // cheeks
    f(0.0, -0.46, 0.23, 0.06, 0.05, false),   // upper lip
    f(0.0, -0.59, 0.2, 0.065, 0.055, false),  // lower lip
    f(0.0, -0.525, 0.22, 0.02, -0.02, false), // the line between the lips
    f(0.0, -0.88, 0.22, 0.14, 0.08, false),   // chin
];

/// Relief height at (u, v) in units of the half-width, or `None` outside the face.
fn relief(u: f64, v: f64) -> Option<f64> {
    // The outline narrows toward the jaw.
    let jaw = (-v / OVAL).clamp(0.0, 1.0);
    let uo = u / (1.0 - 0.25 * jaw * jaw);
    let r2 = uo * uo + (v / OVAL).powi(2);
    if r2 >= 1.0 {
        return None;
    }
    let mut z = 0.6 * (1.0 - r2).sqrt();
    for ft in FEATURES {
        let mut add = |uc: f64| {
            let (du, dv) = ((u - uc) / ft.su, (v - ft.v) / ft.sv);
            z += ft.h * (-0.5 * (du * du + dv * dv)).exp();
        };
        add(ft.u);
        if ft.pair {
            add(-ft.u);
        }
    }
    // The nose ridge: rising from the bridge between the eyes to the tip.
    let rise = smoothstep(-0.3, 0.14, -v) * (1.0 - smoothstep(0.14, 0.34, -v));
    z += 0.24 * rise * (-0.5 * (u / 0.09).powi(2)).exp();
    Some(z)
}

param_choice! {
    /// How the face of [`hollow_mask`] is seen.
    pub enum FaceMode {
        /// From behind: depth negated.
        Hollow = "hollow",
        /// From the front.
        Convex = "convex",
    }
}

stimulus_params! {
    /// Parameters of [`hollow_mask`].
    pub struct HollowMaskParams {
        /// the face as seen from the front (convex) or from behind, hollow (depth negated)
        mode: FaceMode = FaceMode::Hollow;
        /// width of the face (deg)
        face_width: f64 = 5.0, range 0.05..=180.0;
        /// depth scale (1 = a natural face)
        relief: f64 = 1.0, range 0.01..=10.0;
        /// light and reflectance: a face fully lit at the default slant would reach 1 with
        /// albedo 1, and some light in the shadows keeps the eye sockets from going black
        flatten lighting: LightingParams { albedo: 0.7, ambient: 0.06 };
        /// background and cast shadows
        flatten backdrop: BackdropParams { background: 0.1 };
    }
}

/// A face relief, convex or hollow, rendered under one light.
pub fn hollow_mask(p: &HollowMaskParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let frame = Frame::new(g);
    let half = frame.px(p.face_width) / 2.0;
    if half < 4.0 {
        return Err(Error::invalid(format!(
            "hollow-mask: face_width {}° is under 8 pixels at {} ppd",
            p.face_width, frame.ppd
        )));
    }
    let scale = half * p.relief;
    let (w, h) = (frame.w, frame.h);
    let mut depth = Grid::new(w, h, 0.0);
    let mut mask = Grid::new(w, h, false);
    for row in frame.rows(-half * OVAL, half * OVAL) {
        for col in frame.cols(-half, half) {
            if let Some(z) = relief(frame.x(col) / half, frame.y(row) / half) {
                *depth.get_mut(col, row) = scale * z;
                *mask.get_mut(col, row) = true;
            }
        }
    }
    if mask.count() == 0 {
        return Err(Error::invalid("hollow-mask: the face covers no pixel"));
    }
    let convex = Surface::from_depth(depth, mask)?;
    let hollow = p.mode == FaceMode::Hollow;
    let surface = if hollow { convex.negated() } else { convex };
    let light = p.lighting.light;
    let reflectance = p.lighting.reflectance()?;
    let options = p.backdrop.render_options();
    let rendering = render(&surface, reflectance.as_ref(), &options);
    let s = light.direction();
    let mut notes = Map::new();
    notes.insert("light_vector".into(), json!([s.x, s.y, s.z]));
    notes.insert(
        "equivalent".into(),
        json!(format!(
            "without cast shadows this image equals the {} face lit from {}",
            if hollow { "convex" } else { "hollow" },
            light.opposite_tilt()
        )),
    );
    let targets = Targets {
        labels: surface.mask.map(|&m| u16::from(m)),
        names: vec!["face".into()],
    };
    Ok(Output::rendered(surface, rendering, targets, notes))
}

/// The hollow-mask stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "hollow-mask",
        "a face relief, convex or hollow: a hollow face lit from above looks convex, lit from below",
        (7.0, 9.0),
        40.0,
        |p, g, _| hollow_mask(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn generate(pairs: &[&str]) -> Output {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 70,
            height: 90,
            ppd: 10.0,
        };
        hollow_mask(&HollowMaskParams::from_map(&given).unwrap(), &g).unwrap()
    }

    #[test]
    fn hollow_from_above_is_convex_from_below_pixel_for_pixel() {
        for (a, b) in [
            ("above", "below"),
            ("tilt=30,slant=60", "tilt=210,slant=60"),
        ] {
            let hollow = generate(&["mode=hollow", &format!("light={a}")]);
            let convex = generate(&["mode=convex", &format!("light={b}")]);
            assert_eq!(hollow.pixels, convex.pixels, "{a} vs {b}");
            let other = generate(&["mode=convex", &format!("light={a}")]);
            assert_ne!(hollow.pixels, other.pixels);
        }
    }

    #[test]
    fn the_nose_points_at_the_viewer_in_the_convex_face() {
        let out = generate(&["mode=convex"]);
        let d = &out.surface.as_ref().unwrap().depth;
        // Frame 70x90: the nose tip (v = −0.2 half-widths = −5 px) lies near row 50.
        let nose = *d.get(35, 50);
        let cheek = *d.get(22, 50);
        assert!(nose > cheek + 2.0, "{nose} vs {cheek}");
        let hollow = generate(&["mode=hollow"]);
        assert_eq!(*hollow.surface.as_ref().unwrap().depth.get(35, 50), -nose);
    }
}
