//! `hollow-mask`: a face, convex or hollow, under any light. A hollow face lit from above is
//! seen as a normal, convex face lit from below: knowledge of faces overrides the
//! light-from-above prior (Gregory 1970; Hill & Bruce 1993).
//!
//! The face is MediaPipe's canonical face model ([`super::face`]), rasterised with smooth
//! vertex normals. The hollow face is the convex one with depth negated, so its normals are
//! (−n_x, −n_y, n_z) exactly: without cast shadows, the hollow face under light s is pixel for
//! pixel the convex face under (−s_x, −s_y, s_z) (tilt + 180°).
//!
//! `layout=pair` draws the teaching figure in a 2 × 2 grid: the convex face (top left) and the
//! hollow face (top right), lit the same, and below each its side profile, the cross-section
//! through the nose along the face's midline with the viewer to the right: the convex face
//! sticks out toward the viewer from the plane of its rim, the hollow one goes in.

use super::face::face_relief;
use super::surfaces::{BackdropParams, LightingParams};
use super::{Output, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::{Grid, Image};
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::render::render;
use crate::surface::Surface;
use crate::visual_size::Geometry;
use nalgebra::Vector3;
use serde_json::{json, Map};

param_choice! {
    /// How the face of [`hollow_mask`] is seen.
    pub enum FaceMode {
        /// From behind: depth negated.
        Hollow = "hollow",
        /// From the front.
        Convex = "convex",
    }
}

param_choice! {
    /// What [`hollow_mask`] draws.
    pub enum FaceLayout {
        /// One face, convex or hollow (`mode`), `face_width` wide.
        Face = "face",
        /// The convex and the hollow face side by side, lit the same, each above its side
        /// profile; each face fills its quarter of the frame.
        Pair = "pair",
    }
}

stimulus_params! {
    /// Parameters of [`hollow_mask`].
    pub struct HollowMaskParams {
        /// the face as seen from the front (convex) or from behind, hollow (depth negated)
        mode: FaceMode = FaceMode::Hollow;
        /// one face, or the convex and hollow faces with their side profiles
        layout: FaceLayout = FaceLayout::Face;
        /// width of the face (deg; layout=face)
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

/// Grey of a side profile's cross-section, and of the rim plane's line.
const PROFILE_FILL: f64 = 0.55;
const RIM_LINE: f64 = 0.9;

/// A face, convex or hollow, or the convex/hollow pair with side profiles, under one light.
pub fn hollow_mask(p: &HollowMaskParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let (w, h) = (g.width, g.height);
    let hollow = p.mode == FaceMode::Hollow;
    let (surface, names, profiles) = match p.layout {
        FaceLayout::Face => {
            let width = p.face_width * g.ppd;
            if width < 8.0 {
                return Err(Error::invalid(format!(
                    "hollow-mask: face_width {}° is under 8 pixels at {} ppd",
                    p.face_width, g.ppd
                )));
            }
            let convex = face_relief(w, h, width, p.relief)?.surface;
            let (surface, name) = if hollow {
                (convex.negated(), "hollow")
            } else {
                (convex, "convex")
            };
            let labels = surface.mask.map(|&m| u16::from(m));
            (surface, (labels, vec![name.to_string()]), None)
        }
        FaceLayout::Pair => pair(w, h, p.relief)?,
    };
    let light = p.lighting.light;
    let reflectance = p.lighting.reflectance()?;
    let options = p.backdrop.render_options();
    let mut rendering = render(&surface, reflectance.as_ref(), &options);
    let s = light.direction();
    let mut notes = Map::new();
    notes.insert("light_vector".into(), json!([s.x, s.y, s.z]));
    if let Some(profiles) = profiles {
        for (i, v) in rendering.image.data_mut().iter_mut().enumerate() {
            if let Some(p) = profiles.data()[i] {
                *v = p;
            }
        }
        notes.insert(
            "layout".into(),
            json!(
                "top: the convex face (left) and the hollow face (right), lit the same; \
                   below each: its side profile through the nose, the viewer to the right, \
                   the rim plane as a light line"
            ),
        );
    } else {
        notes.insert(
            "equivalent".into(),
            json!(format!(
                "without cast shadows this image equals the {} face lit from {}",
                if hollow { "convex" } else { "hollow" },
                light.opposite_tilt()
            )),
        );
    }
    let (labels, names) = names;
    Ok(Output::rendered(
        surface,
        rendering,
        Targets { labels, names },
        notes,
    ))
}

/// Target labels and names.
type Named = (Grid<u16>, Vec<String>);

/// Grey levels drawn over the rendering (`None` where the rendering shows).
type Overlay = Grid<Option<f64>>;

/// The 2 × 2 teaching figure: the surface (convex face top left, hollow face top right), the
/// targets, and the profile panels' grey levels (`None` where the rendering shows).
fn pair(w: usize, h: usize, relief: f64) -> Result<(Surface, Named, Option<Overlay>)> {
    let (cw, ch) = (w / 2, h / 2);
    if cw < 8 || ch < 8 {
        return Err(Error::invalid(format!(
            "hollow-mask: layout=pair needs at least 16 px high × 16 px wide, not {}",
            crate::message::SizeText::Pixels(h, w)
        )));
    }
    // The face fills 90 % of its quarter along the tighter axis.
    let probe = face_relief(cw, ch, cw as f64, 1.0)?;
    let tall = probe.surface.mask.map(|&m| m);
    let rows = (0..ch)
        .filter(|&r| (0..cw).any(|c| *tall.get(c, r)))
        .count();
    let width = 0.9 * cw as f64 * (ch as f64 / rows.max(1) as f64).min(1.0);
    let face = face_relief(cw, ch, width, relief)?;
    let convex = face.surface;
    let hollow = convex.negated();
    let mut depth = Image::new(w, h, 0.0);
    let mut normals = Grid::new(w, h, Vector3::z());
    let mut mask = Grid::new(w, h, false);
    let mut labels = Grid::new(w, h, 0u16);
    for (k, part) in [&convex, &hollow].into_iter().enumerate() {
        for r in 0..ch {
            for c in 0..cw {
                if *part.mask.get(c, r) {
                    let col = c + k * cw;
                    *depth.get_mut(col, r) = *part.depth.get(c, r);
                    *normals.get_mut(col, r) = *part.normals.get(c, r);
                    *mask.get_mut(col, r) = true;
                    *labels.get_mut(col, r) = k as u16 + 1;
                }
            }
        }
    }
    // The profile: depth along the face's midline column, for each row the face covers.
    let mid = nearest_column(&convex);
    let profile: Vec<Option<f64>> = (0..ch)
        .map(|r| convex.mask.get(mid, r).then(|| *convex.depth.get(mid, r)))
        .collect();
    let deepest = profile.iter().flatten().fold(0.0f64, |a, &b| a.max(b));
    let margin = ((cw as f64 - deepest) / 2.0).max(0.0).floor() as usize;
    let mut panels = Grid::new(w, h, None);
    for (k, sign) in [(0usize, 1.0f64), (1, -1.0)] {
        // The rim plane's column: near the left for the convex face (it grows right, toward
        // the viewer), near the right for the hollow one (it grows left, away).
        let rim = if sign > 0.0 {
            margin
        } else {
            cw - 1 - margin.min(cw - 1)
        };
        for (r, depth) in profile.iter().enumerate() {
            let row = r + ch;
            for c in 0..cw {
                let col = c + k * cw;
                let value = match *depth {
                    Some(z) => {
                        // Signed distance of the pixel centre from the rim toward the viewer.
                        let x = sign * (c as f64 - rim as f64);
                        if c == rim {
                            Some(RIM_LINE)
                        } else if x > 0.0 && x <= z {
                            Some(PROFILE_FILL)
                        } else {
                            None
                        }
                    }
                    None => None,
                };
                if let (Some(v), true) = (value, row < h) {
                    *panels.get_mut(col, row) = Some(v);
                }
            }
        }
    }
    let surface = Surface {
        depth,
        normals,
        mask,
    };
    Ok((
        surface,
        (labels, vec!["convex".into(), "hollow".into()]),
        Some(panels),
    ))
}

/// The column of the surface's nearest pixel (the first, in row-major order, of those at the
/// greatest depth): the nose tip's column, the face's midline.
pub(crate) fn nearest_column(surface: &Surface) -> usize {
    let w = surface.width();
    let (mut best, mut at) = (f64::NEG_INFINITY, 0);
    for (k, (&z, &inside)) in surface
        .depth
        .data()
        .iter()
        .zip(surface.mask.data())
        .enumerate()
    {
        if inside && z > best {
            (best, at) = (z, k);
        }
    }
    at % w
}

/// The hollow-mask stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "hollow-mask",
        "a face (MediaPipe's canonical face), convex or hollow, or the pair with side profiles: \
         a hollow face lit from above looks convex, lit from below",
        (9.0, 7.0),
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
    fn the_nose_tip_is_the_nearest_point_and_the_hollow_is_its_negative() {
        let out = generate(&["mode=convex"]);
        let d = &out.surface.as_ref().unwrap().depth;
        let top = d
            .data()
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |b, (i, &z)| if z > b.1 { (i, z) } else { b })
            .0;
        let (col, row) = (top % 70, top / 70);
        let tip = face_relief(70, 90, 50.0, 1.0).unwrap().nose_tip;
        assert!((col as f64 - tip.0).abs() <= 1.0 && (row as f64 - tip.1).abs() <= 1.0);
        let hollow = generate(&["mode=hollow"]);
        let hd = &hollow.surface.as_ref().unwrap().depth;
        assert_eq!(hd, &d.map(|z| -z));
        assert_eq!(hollow.targets.as_ref().unwrap().names, vec!["hollow"]);
    }
}
