//! `crater`: a mound with a crater on top, lit from above. Turned by 180° (`rotation=180`,
//! an exact pixel rotation of the upright picture) the same image reads as a mound inside a
//! crater: vision keeps its light above and turns the depth inside out.
//!
//! The heightfield is radial, z(ρ) = H·exp(−ρ²/2σ²) − D·(1 − ρ²/R²)² (the last term only
//! for ρ < R): a Gaussian mound of spread σ (`mound_radius`) with a smooth bowl of radius R
//! (`crater_radius`) taken out of its top, which leaves a raised rim. Lambertian with an
//! ambient level, the albedo chosen so that the flat ground has the `background` luminance,
//! with cast shadows by default.
//!
//! The light has an angular size (`light_size`, its angular diameter): the cast shadow's edge
//! is a penumbra whose value at each pixel is ambient + albedo·max(0, n·s)·V, where V is the
//! fraction of the light's disc the pixel sees (its visibility, averaged over 32 fixed
//! directions spread evenly over the disc on a sunflower spiral). With `light_size=0` the
//! light is a point and the shadow is hard (V is 0 or 1).

use super::{Output, Pixels, Stimulus, SurfaceLayers, Targets, Typed};
use crate::error::{Error, Result};
use crate::gradient_space::normal_from_pq;
use crate::grid::Grid;
use crate::light::Light;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::reflectance::Lambertian;
use crate::render::{render, RenderOptions, ShadowCaster};
use crate::surface::Surface;
use crate::visual_size::Geometry;
use nalgebra::Vector3;
use serde_json::{json, Map};

param_choice! {
    /// How the finished picture of [`crater`] is turned.
    pub enum CraterRotation {
        /// Upright: a mound with a crater.
        Upright = "0",
        /// Turned by 180° (exact pixel rotation): seen as a crater with a mound.
        Turned = "180",
    }
}

stimulus_params! {
    /// Parameters of [`crater`].
    pub struct CraterParams {
        /// spread σ of the Gaussian mound (deg)
        mound_radius: f64 = 1.0, range 0.01..=90.0;
        /// radius of the bowl-shaped pit in its top (deg)
        crater_radius: f64 = 0.7, range 0.01..=90.0;
        /// mound height as a multiple of mound_radius
        height: f64 = 1.2, range 0.0..=10.0;
        /// pit depth as a multiple of mound_radius
        depth: f64 = 1.0, range 0.0..=10.0;
        /// turn the finished picture by 180° (exact pixel rotation)
        rotation: CraterRotation = CraterRotation::Upright;
        /// light direction (x,y,z | tilt=T,slant=S | name)
        light: Light = "above";
        /// luminance of the flat ground
        background: f64 = 0.5, range 0.0..=1.0;
        /// luminance of surfaces the light does not reach (attached and cast shadows)
        ambient: f64 = 0.1, range 0.0..=1.0;
        /// ray-march cast shadows over the heightfield
        cast_shadows: bool = true;
        /// angular diameter of the light (deg): the shadow's penumbra widens with it; 0 = a point light and a hard shadow
        light_size: f64 = 10.0, range 0.0..=60.0;
    }
}

/// A mound with a crater on top, lit from above (or turned by 180°).
pub fn crater(p: &CraterParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let sm = g.px(p.mound_radius);
    let sc = g.px(p.crater_radius);
    let (hh, dd) = (p.height * sm, p.depth * sm);
    if sm < 1.0 || sc < 0.5 {
        return Err(Error::invalid(format!(
            "crater: mound_radius and crater_radius must span at least a pixel at {} ppd",
            g.ppd
        )));
    }
    let light = p.light;
    let s = light.direction();
    if s.z < 1e-6 {
        return Err(Error::invalid(
            "crater: a grazing light (slant 90°) leaves the ground dark; use a slant below 90°",
        ));
    }
    let profile = |rho2: f64| -> (f64, f64) {
        let em = (-rho2 / (2.0 * sm * sm)).exp();
        let bowl = (1.0 - rho2 / (sc * sc)).max(0.0);
        // z and k with p = k·x, q = k·y (p = −∂z/∂x for a radial profile).
        (
            hh * em - dd * bowl * bowl,
            hh * em / (sm * sm) - 4.0 * dd * bowl / (sc * sc),
        )
    };
    // The rim is where the profile peaks; the mound ends where it has fallen to 2% of H.
    let (mut rim, mut best, mut edge) = (0.0, f64::NEG_INFINITY, 0.0);
    let steps = 4000;
    for i in 0..=steps {
        let rho = 4.0 * sm.max(sc) * i as f64 / steps as f64;
        let z = profile(rho * rho).0;
        if z > best {
            (best, rim) = (z, rho);
        }
        if z.abs() > 0.02 * hh.max(dd) {
            edge = rho;
        }
    }
    let (w, h) = (g.width, g.height);
    let mut depth = Grid::new(w, h, 0.0);
    let mut normals = Grid::new(w, h, Vector3::z());
    let mut labels = Grid::new(w, h, 0u16);
    for row in 0..h {
        for col in 0..w {
            let (x, y) = (g.x(col), g.y(row));
            let rho2 = x * x + y * y;
            let (z, k) = profile(rho2);
            *depth.get_mut(col, row) = z;
            *normals.get_mut(col, row) = normal_from_pq(k * x, k * y);
            if rho2 < rim * rim {
                *labels.get_mut(col, row) = 1;
            } else if rho2 < edge * edge {
                *labels.get_mut(col, row) = 2;
            }
        }
    }
    let surface = Surface {
        depth,
        normals,
        mask: Grid::new(w, h, true),
    };
    let (background, ambient) = (p.background, p.ambient);
    if ambient > background {
        return Err(Error::invalid(format!(
            "crater: ambient {ambient} exceeds the background {background} (the lit ground cannot be darker than shadow)"
        )));
    }
    let albedo = (background - ambient) / s.z;
    let reflectance = Lambertian {
        light,
        albedo,
        ambient,
    };
    // A light of some size replaces the hard shadow by its penumbra (image and shadow layer
    // both), so the hard one is only cast for a point light.
    let soft = p.cast_shadows && p.light_size > 0.0;
    let options = RenderOptions {
        background: 0.0,
        cast_shadows: p.cast_shadows && !soft,
    };
    let mut rendering = render(&surface, &reflectance, &options);
    if soft {
        soften_shadow(&surface, &mut rendering, s, p.light_size, ambient);
    }
    let peak = rendering.image.min_max().map_or(0.0, |m| m.1);
    if peak > 1.0 {
        return Err(Error::invalid(format!(
            "crater: the brightest slope reaches {peak:.3} > 1; lower the background or the light's slant"
        )));
    }
    let mut notes = Map::new();
    notes.insert("light_vector".into(), json!([s.x, s.y, s.z]));
    notes.insert("albedo".into(), json!(albedo));
    notes.insert("rim_radius_deg".into(), json!(rim / g.ppd));
    let names = vec!["crater".to_string(), "mound".to_string()];
    let mut out = Output::rendered(surface, rendering, Targets { labels, names }, notes);
    if p.rotation == CraterRotation::Turned {
        out = rotated(out);
        let seen = light.opposite_tilt();
        out.notes.insert(
            "rotation".into(),
            json!(format!(
                "the picture is turned by 180°: physically the same mound lit from {seen} (the layers describe it); seen as a crater lit from {light}"
            )),
        );
    }
    Ok(out)
}

/// How many directions sample the light's disc.
const LIGHT_SAMPLES: usize = 32;

/// `LIGHT_SAMPLES` unit directions spread evenly over the disc of angular diameter
/// `size_deg` around `s` (a sunflower spiral: radius ∝ √((k + ½)/N), the golden angle apart).
fn light_disc(s: Vector3<f64>, size_deg: f64) -> Vec<Vector3<f64>> {
    // Two unit vectors perpendicular to s (s has z > 0, so x̂ × s is never zero unless s ∥ x̂).
    let u = if s.x.abs() < 0.9 {
        Vector3::x().cross(&s).normalize()
    } else {
        Vector3::y().cross(&s).normalize()
    };
    let v = s.cross(&u);
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let radius = (size_deg / 2.0).to_radians();
    (0..LIGHT_SAMPLES)
        .map(|k| {
            let angle = radius * ((k as f64 + 0.5) / LIGHT_SAMPLES as f64).sqrt();
            let phi = golden * k as f64;
            let (sa, ca) = angle.sin_cos();
            (s * ca + (u * phi.cos() + v * phi.sin()) * sa).normalize()
        })
        .collect()
}

/// Replaces the hard cast shadow of `rendering` by the penumbra of a light of angular diameter
/// `size_deg` around `s`: each pixel's lit part is scaled by the fraction of the light's disc
/// it sees. The `cast_shadow` layer keeps the pixels that see none of it.
fn soften_shadow(
    surface: &Surface,
    rendering: &mut crate::render::Rendering,
    s: Vector3<f64>,
    size_deg: f64,
    ambient: f64,
) {
    use crate::parallel::prelude::*;
    let directions = light_disc(s, size_deg);
    let caster = ShadowCaster::new(surface);
    let shadows: Vec<crate::grid::Mask> = directions.par_iter().map(|d| caster.cast(*d)).collect();
    let (w, h) = (surface.width(), surface.height());
    let mut hidden = Grid::new(w, h, 0usize);
    for shadow in &shadows {
        for (count, &dark) in hidden.data_mut().iter_mut().zip(shadow.data()) {
            *count += usize::from(dark);
        }
    }
    let n = directions.len() as f64;
    rendering.image = Grid::from_fn(w, h, |c, r| {
        let visible = 1.0 - *hidden.get(c, r) as f64 / n;
        ambient + (*rendering.shading.get(c, r) - ambient) * visible
    });
    rendering.cast_shadow = hidden.map(|&k| k == directions.len());
}

/// The output turned by 180° in the image plane: pixels, labels and layers move with the
/// picture, and normals turn with it ((n_x, n_y) → (−n_x, −n_y)).
fn rotated(out: Output) -> Output {
    Output {
        pixels: match out.pixels {
            Pixels::Gray(g) => Pixels::Gray(g.rotated_180()),
            Pixels::Rgb(g) => Pixels::Rgb(g.rotated_180()),
        },
        targets: out.targets.map(|t| Targets {
            labels: t.labels.rotated_180(),
            names: t.names,
        }),
        surface: out.surface.map(|s| SurfaceLayers {
            depth: s.depth.rotated_180(),
            normals: s
                .normals
                .rotated_180()
                .map(|n| Vector3::new(-n.x, -n.y, n.z)),
            mask: s.mask.rotated_180(),
            albedo: s.albedo.as_ref().map(Grid::rotated_180),
            shading: s.shading.as_ref().map(Grid::rotated_180),
        }),
        svg: out.svg,
        notes: out.notes,
    }
}

/// The crater stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "crater",
        "a mound with a crater lit from above; rotation=180 turns it into a crater with a mound",
        (6.0, 6.0),
        40.0,
        |p, g, _| crater(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn generate(pairs: &[&str]) -> Output {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 96,
            height: 80,
            ppd: 12.0,
        };
        crater(&CraterParams::from_map(&given).unwrap(), &g).unwrap()
    }

    #[test]
    fn rotation_180_is_the_exact_pixel_rotation() {
        let up = generate(&["cast_shadows=true"]);
        let down = generate(&["cast_shadows=true", "rotation=180"]);
        let (Pixels::Gray(a), Pixels::Gray(b)) = (&up.pixels, &down.pixels) else {
            panic!()
        };
        assert_eq!(&a.rotated_180(), b);
        assert_eq!(
            up.targets.as_ref().unwrap().labels.rotated_180(),
            down.targets.as_ref().unwrap().labels
        );
        // The turned picture's layers describe the same mound lit from below.
        let plain = generate(&["cast_shadows=false", "rotation=180"]);
        let Pixels::Gray(img) = &plain.pixels else {
            panic!()
        };
        let below = "tilt=180,slant=45"
            .parse::<crate::light::Light>()
            .unwrap()
            .direction();
        let albedo = plain.notes["albedo"].as_f64().unwrap();
        let normals = &plain.surface.as_ref().unwrap().normals;
        for (v, n) in img.data().iter().zip(normals.data()) {
            assert!((v - (0.1 + albedo * n.dot(&below).max(0.0))).abs() < 1e-12);
        }
    }

    #[test]
    fn the_rim_is_lit_on_its_upper_side_and_the_pit_on_its_lower_side() {
        let out = generate(&[]);
        let Pixels::Gray(img) = &out.pixels else {
            panic!()
        };
        // Along the central column: the outer slope above the rim faces up (bright); inside
        // the pit, its lower wall faces up (bright) and its upper wall faces down (dark).
        let rim_px = out.notes["rim_radius_deg"].as_f64().unwrap() * 12.0;
        let (c, mid) = (48, 40.0 - 0.5);
        let at = |dy: f64| *img.get(c, (mid - dy).round() as usize);
        assert!(at(rim_px + 3.0) > 0.5 && at(-(rim_px + 3.0)) < 0.5);
        assert!(at(rim_px * 0.5) < at(-rim_px * 0.5));
    }
}
