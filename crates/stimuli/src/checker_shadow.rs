//! `checker-shadow`: Adelson's (1995) checker-shadow illusion. Square A (dark, in direct light)
//! and square B (light, in the shadow of a cylinder) have exactly the same pixel value, yet B
//! looks far lighter: vision discounts the soft illumination change of the shadow to recover
//! surface reflectance.
//!
//! A checkerboard lies on the ground, seen from `view_elevation` above and turned by 45°
//! (orthographic), with an upright cylinder on it. The light comes along the board's +X axis
//! from `light_elevation`; the cylinder's shadow is a capsule (its base swept away from the
//! light for height / tan(elevation)) with a smooth penumbra. In shadow the illumination falls
//! to k = dark_square / light_square, so a light square in full shadow has exactly the value of
//! a dark square in full light: the board's value is (1 − w)·lit + w·shadowed, with w exactly
//! 0 in light and exactly 1 in the umbra, and a light square's shadowed value *is*
//! `dark_square`. The cylinder is Lambertian with the same ambient fraction k.
//!
//! As in Adelson's figure, the letters A and B may stand on their squares (`letters=true`, as
//! the gallery's figures do; off by default, because black ink is part of what an observer in
//! an experiment or a lightness model sees: black vector glyphs, anti-aliased, their pixels
//! not in the target mask), the shadow is a broad soft band that
//! covers B and the squares beside it along the cylinder's side, and the cylinder may be green
//! (`cylinder_colour=green`: RGB output whose luminance is the gray cylinder's). `proof=true`
//! adds Adelson's proof: a bar of exactly the squares' shared value joins A to B, so a viewer
//! sees one uniform gray run from one square to the other.
//!
//! The view is orthographic by default. `viewing_distance` > 0 puts the eye that far from
//! the board's centre instead (central perspective, as in Adelson's figure): the board's far
//! squares shrink and its edges converge; the picture plane passes through the board's centre,
//! so the scene keeps about its orthographic size there. A and B keep exactly the same value.
//!
//! Lengths are in degrees measured on the board (before foreshortening).

use super::frame::smoothstep;
use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use std::f64::consts::SQRT_2;

/// Distance from (x, y) to the segment from (ax, ay) to (bx, ay) (a horizontal segment).
fn segment_distance(x: f64, y: f64, ax: f64, bx: f64, ay: f64) -> f64 {
    let (lo, hi) = (ax.min(bx), ax.max(bx));
    let dx = if x < lo {
        lo - x
    } else if x > hi {
        x - hi
    } else {
        0.0
    };
    dx.hypot(y - ay)
}

/// The camera, in units of squares: the picture plane passes through the board's centre,
/// `(u, w, z)` is a point of the scene (u across the view, w along the ground away from the
/// viewer, z up), a screen point is `(u', y')` (y' up). `dist` = 0 is orthographic.
#[derive(Clone, Copy)]
struct View {
    dist: f64,
    se: f64,
    ce: f64,
}

impl View {
    /// The screen point of the scene point (u, w, z).
    fn project(&self, u: f64, w: f64, z: f64) -> (f64, f64) {
        let (su, sy) = (u, w * self.se + z * self.ce);
        if self.dist == 0.0 {
            return (su, sy);
        }
        // Depth along the line of sight from the eye, over its depth at the board's centre.
        let scale = self.dist / (self.dist + w * self.ce - z * self.se);
        (su * scale, sy * scale)
    }

    /// Traces the ray through the screen point (su, sy) (perspective only): the cylinder's
    /// normal where the ray meets it first (its side or its top), and where the ray meets the
    /// ground (u, w), if it does (below the horizon).
    fn trace(
        &self,
        su: f64,
        sy: f64,
        (uc, wc): (f64, f64),
        rc: f64,
        hc: f64,
    ) -> (Option<[f64; 3]>, Option<(f64, f64)>) {
        let (d, se, ce) = (self.dist, self.se, self.ce);
        // Eye at (0, −d·cos e, d·sin e); ray direction toward the picture point.
        let eye = [0.0, -d * ce, d * se];
        let dir = [su, sy * se + d * ce, sy * ce - d * se];
        let at = |t: f64| {
            [
                eye[0] + t * dir[0],
                eye[1] + t * dir[1],
                eye[2] + t * dir[2],
            ]
        };
        let ground = (dir[2] < 0.0).then(|| {
            let p = at(-eye[2] / dir[2]);
            (p[0], p[1])
        });
        let mut best: Option<(f64, [f64; 3])> = None;
        // The side: (u − uc)² + (w − wc)² = rc², 0 ≤ z ≤ hc; the nearer root faces the eye.
        let (ou, ow) = (eye[0] - uc, eye[1] - wc);
        let a = dir[0] * dir[0] + dir[1] * dir[1];
        let b = 2.0 * (ou * dir[0] + ow * dir[1]);
        let c = ou * ou + ow * ow - rc * rc;
        let disc = b * b - 4.0 * a * c;
        if a > 0.0 && disc >= 0.0 {
            let t = (-b - disc.sqrt()) / (2.0 * a);
            let p = at(t);
            if t > 0.0 && (0.0..=hc).contains(&p[2]) {
                best = Some((t, [(p[0] - uc) / rc, (p[1] - wc) / rc, 0.0]));
            }
        }
        // The top: z = hc within the radius.
        if dir[2] != 0.0 {
            let t = (hc - eye[2]) / dir[2];
            let p = at(t);
            let inside = (p[0] - uc).powi(2) + (p[1] - wc).powi(2) <= rc * rc;
            if t > 0.0 && inside && best.map_or(true, |(tb, _)| t < tb) {
                best = Some((t, [0.0, 0.0, 1.0]));
            }
        }
        (best.map(|(_, n)| n), ground)
    }
}

param_choice! {
    /// The colour of the cylinder of [`checker_shadow`].
    pub enum CylinderColour {
        /// Gray, like the board: the output is one channel.
        Gray = "gray",
        /// Green, as in Adelson's figure: the output is RGB, with the gray cylinder's luminance.
        Green = "green",
    }
}

/// The green of the cylinder: linear RGB weights whose luminance (Rec. 709) is 1, so a green
/// cylinder has the luminance of the gray one.
const GREEN: [f64; 3] = [0.32, 1.24, 0.42];

stimulus_params! {
    /// Parameters of [`checker_shadow`].
    pub struct CheckerShadowParams {
        /// squares per side of the board
        squares: usize = 7, range 5..=16;
        /// side of one square on the board (deg)
        square: f64 = 0.8, range 0.01..=30.0;
        /// angle of the line of sight above the board (deg)
        view_elevation: f64 = 40.0, range 10.0..=90.0;
        /// distance from the eye to the board's centre (deg on the board's scale); 0 =
        /// orthographic (an eye infinitely far), else central perspective
        viewing_distance: f64 = 0.0, range 0.0..=10000.0;
        /// angle of the light above the board (deg)
        light_elevation: f64 = 40.0, range 10.0..=89.0;
        /// luminance of a light square in light
        light_square: f64 = 0.8, range 0.0..=1.0;
        /// luminance of a dark square in light (= a light square in full shadow)
        dark_square: f64 = 0.4, range 0.0..=1.0;
        /// radius of the cylinder (deg)
        cylinder_radius: f64 = 0.72, range 0.01..=30.0;
        /// height of the cylinder (deg)
        cylinder_height: f64 = 2.4, range 0.01..=60.0;
        /// distance from square B's centre to the cylinder's axis, toward the light (deg)
        cylinder_offset: f64 = 1.4, range 0.0..=60.0;
        /// half-width of the shadow's soft edge (deg)
        penumbra: f64 = 0.24, range 0.0..=10.0;
        /// luminance of the cylinder's top
        cylinder_albedo: f64 = 0.5, range 0.0..=1.0;
        /// colour of the cylinder (green gives RGB output of the same luminance)
        cylinder_colour: CylinderColour = CylinderColour::Gray;
        /// luminance around the board
        background: f64 = 0.9, range 0.0..=1.0;
        /// draw the letters A and B on their squares (for a figure: off by default, since the
        /// ink is part of the image an observer or a model sees)
        letters: bool = false;
        /// Adelson's proof: join A and B by a bar of their shared value
        proof: bool = false;
    }
}

/// Adelson's checker-shadow: squares A and B have the same value, B looks much lighter.
pub fn checker_shadow(p: &CheckerShadowParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let n = p.squares;
    let sq_deg = p.square;
    let side = g.px(sq_deg);
    if side < 4.0 {
        return Err(Error::invalid(format!(
            "checker-shadow: square {sq_deg}° is under 4 pixels at {} ppd",
            g.ppd
        )));
    }
    let (light, dark) = (p.light_square, p.dark_square);
    if dark > light || light == 0.0 {
        return Err(Error::invalid(format!(
            "checker-shadow: dark_square {dark} must not exceed light_square {light} (and light_square must be above 0)"
        )));
    }
    let k = dark / light;
    // Everything below is in squares, in the board's frame, origin at its centre.
    let in_squares = |degrees: f64| degrees / sq_deg;
    let (rc, hc, offset, pen) = (
        in_squares(p.cylinder_radius),
        in_squares(p.cylinder_height),
        in_squares(p.cylinder_offset),
        in_squares(p.penumbra),
    );
    let (se, ce) = p.view_elevation.to_radians().sin_cos();
    let (sl, cl) = p.light_elevation.to_radians().sin_cos();
    let half = n as f64 / 2.0;
    let (ib, jb) = (n / 2, n / 2);
    let (ia, ja) = (ib - 1, jb + 2);
    let centre = |i: usize| i as f64 + 0.5 - half;
    let (bx, by) = (centre(ib), centre(jb));
    let (cx, cy) = (bx + offset, by);
    let shadow_end = cx - hc * cl / sl;
    // Board (X, Y) → (u, w): turned by 45°; w runs away from the viewer.
    let (uc, wc) = ((cx - cy) / SQRT_2, (cx + cy) / SQRT_2);
    let dist = in_squares(p.viewing_distance);
    let view = View { dist, se, ce };
    if dist > 0.0 {
        // The eye must be outside the scene, beyond the board's far corner and the cylinder.
        let reach = (half * SQRT_2).max(wc.abs() + rc) + hc;
        if dist <= 2.0 * reach {
            return Err(Error::invalid(format!(
                "checker-shadow: viewing_distance {}° puts the eye too close to the board; use 0 (orthographic) or more than {:.2}°",
                p.viewing_distance,
                2.0 * reach * sq_deg
            )));
        }
    }
    // The picture's extent: the board's corners and the cylinder's rims, as projected.
    let mut extent = (0.0f64, f64::INFINITY, f64::NEG_INFINITY);
    let corners = [(0.0, -1.0), (0.0, 1.0), (-1.0, 0.0), (1.0, 0.0)]
        .map(|(u, w)| (u * half * SQRT_2, w * half * SQRT_2, 0.0));
    let rims = (0..64).flat_map(|k| {
        let a = k as f64 * std::f64::consts::TAU / 64.0;
        [0.0, hc].map(|z| (uc + rc * a.cos(), wc + rc * a.sin(), z))
    });
    for (u, w, z) in corners.into_iter().chain(rims) {
        let (su, sy) = view.project(u, w, z);
        extent = (extent.0.max(su.abs()), extent.1.min(sy), extent.2.max(sy));
    }
    let (top, bottom) = (extent.2, extent.1);
    let y_off = -(top + bottom) / 2.0;
    let content_w = 2.0 * extent.0 * side;
    let content_h = (top - bottom) * side;
    if content_w > g.width as f64 + 0.5 || content_h > g.height as f64 + 0.5 {
        return Err(Error::invalid(format!(
            "checker-shadow: the scene needs {} but the frame is {}: enlarge the visual size or shrink `square`",
            crate::message::SizeText::Degrees(content_h / g.ppd, content_w / g.ppd),
            g.size_text()
        )));
    }
    let (lu, lw, lz) = (cl / SQRT_2, cl / SQRT_2, sl);
    let cyl_albedo = p.cylinder_albedo;
    let cylinder_value = |nu: f64, nw: f64, nz: f64| -> f64 {
        let cos_i = (nu * lu + nw * lw + nz * lz).max(0.0);
        cyl_albedo * (k + (1.0 - k) * cos_i / sl)
    };
    let mut image = Grid::new(g.width, g.height, p.background);
    let mut labels = Grid::new(g.width, g.height, 0u16);
    let mut on_cylinder = Grid::new(g.width, g.height, false);
    let mut problems = Vec::new();
    for row in 0..g.height {
        for col in 0..g.width {
            // Pixel → (u, y') in squares.
            let u = g.x(col) / side;
            let yv = g.y(row) / side - y_off;
            let du = u - uc;
            let hit = (dist > 0.0).then(|| view.trace(u, yv, (uc, wc), rc, hc));
            let cyl = if let Some((cyl_normal, _)) = hit {
                cyl_normal.map(|[nu, nw, nz]| cylinder_value(nu, nw, nz))
            } else if du.abs() < rc {
                let root = (rc * rc - du * du).sqrt();
                let w_top = (yv - hc * ce) / se;
                let w_front = wc - root;
                if du * du + (w_top - wc).powi(2) <= rc * rc {
                    Some(cylinder_value(0.0, 0.0, 1.0))
                } else if yv >= w_front * se && yv <= w_front * se + hc * ce {
                    Some(cylinder_value(du / rc, (w_front - wc) / rc, 0.0))
                } else {
                    None
                }
            } else {
                None
            };
            let (u, w) = match hit {
                Some((_, Some(ground))) => ground,
                // Above the horizon: no ground there.
                Some((_, None)) => (f64::INFINITY, f64::INFINITY),
                None => (u, yv / se),
            };
            let (x, y) = ((u + w) / SQRT_2, (w - u) / SQRT_2);
            let on_board = x >= -half && x < half && y >= -half && y < half;
            let square = on_board.then(|| {
                (
                    ((x + half).floor() as usize).min(n - 1),
                    ((y + half).floor() as usize).min(n - 1),
                )
            });
            let label = match square {
                Some(s) if s == (ia, ja) => 1,
                Some(s) if s == (ib, jb) => 2,
                _ => 0,
            };
            let v = if let Some(v) = cyl {
                if label > 0 {
                    problems.push("hidden by the cylinder");
                }
                v
            } else if let Some((i, j)) = square {
                let dist = segment_distance(x, y, cx, shadow_end, cy);
                let shadow = 1.0 - smoothstep(rc - pen, rc + pen, dist);
                let light_square = (i + j) % 2 == 0;
                let (lit, shadowed) = if light_square {
                    (light, dark)
                } else {
                    (dark, dark * k)
                };
                if (label == 1 && shadow != 0.0) || (label == 2 && shadow != 1.0) {
                    problems.push("not wholly in light (A) or in the shadow's core (B)");
                }
                (1.0 - shadow) * lit + shadow * shadowed
            } else {
                continue;
            };
            *image.get_mut(col, row) = v;
            if cyl.is_none() {
                *labels.get_mut(col, row) = label;
            } else {
                *on_cylinder.get_mut(col, row) = true;
            }
        }
    }
    if let Some(why) = problems.first() {
        return Err(Error::invalid(format!(
            "checker-shadow: with these parameters square A or B is {why}; change cylinder_offset, cylinder_radius, penumbra or the elevations"
        )));
    }
    let tint = match p.cylinder_colour {
        CylinderColour::Gray => [1.0; 3],
        CylinderColour::Green => GREEN.map(|c| c / crate::grid::luminance(GREEN)),
    };
    let cylinder_peak = image
        .data()
        .iter()
        .zip(on_cylinder.data())
        .filter(|(_, &c)| c)
        .fold(0.0f64, |m, (&v, _)| m.max(v));
    let channel_peak = cylinder_peak * tint.iter().fold(0.0f64, |a, &b| a.max(b));
    if channel_peak > 1.0 {
        return Err(Error::invalid(format!(
            "checker-shadow: the cylinder's lit side reaches {channel_peak:.3} > 1; lower cylinder_albedo or raise light_elevation"
        )));
    }
    // Where the squares' centres fall in the picture (SVG/pixmap coordinates: pixels from the
    // top-left corner, y down).
    let square_centre = |i: usize, j: usize| {
        let (x, y) = (centre(i), centre(j));
        let (u, w) = ((x - y) / SQRT_2, (x + y) / SQRT_2);
        let (su, sy) = view.project(u, w, 0.0);
        g.svg_xy(su * side, (sy + y_off) * side)
    };
    let (a_at, b_at) = (square_centre(ia, ja), square_centre(ib, jb));
    if p.proof {
        // A bar of the shared value from A's centre to B's; the squares keep their own pixels
        // (of that value already), so A and B stay exactly equal.
        let bar = coverage(
            g,
            |pb| {
                pb.move_to(a_at.0 as f32, a_at.1 as f32);
                pb.line_to(b_at.0 as f32, b_at.1 as f32);
            },
            0.45 * side,
            tiny_skia::LineCap::Butt,
        )?;
        blend(&mut image, &labels, &bar, dark);
    }
    if p.letters {
        // Upright glyphs half a square high, black, on the squares' centres.
        let height = 0.5 * side * SQRT_2 * se;
        let stroke = 0.14 * height;
        for (at, glyph) in [(a_at, glyph_a as Glyph), (b_at, glyph_b as Glyph)] {
            let ink = coverage(
                g,
                |pb| glyph(pb, at, height),
                stroke,
                tiny_skia::LineCap::Round,
            )?;
            for (l, &a) in labels.data_mut().iter_mut().zip(ink.data()) {
                if a > 0.0 {
                    *l = 0;
                }
            }
            blend(&mut image, &labels, &ink, 0.0);
        }
    }
    let pixels = if p.cylinder_colour == CylinderColour::Gray {
        Pixels::Gray(image)
    } else {
        let data = image
            .data()
            .iter()
            .zip(on_cylinder.data())
            .map(|(&v, &cyl)| if cyl { tint.map(|t| v * t) } else { [v; 3] })
            .collect();
        Pixels::Rgb(Grid::from_vec(g.width, g.height, data)?)
    };
    let mut notes = Map::new();
    notes.insert("a_and_b_value".into(), json!(dark));
    notes.insert("shadow_illumination".into(), json!(k));
    notes.insert(
        "squares_ij".into(),
        json!({"A": [ia, ja], "B": [ib, jb], "note": "i along the board's X (toward the light), j along Y; (0,0) is the left corner"}),
    );
    // The squares whose centres lie at least half in shadow (the cylinder's base excluded).
    let shadowed: Vec<[usize; 2]> = (0..n)
        .flat_map(|i| (0..n).map(move |j| [i, j]))
        .filter(|&[i, j]| {
            let (x, y) = (centre(i), centre(j));
            let dist = segment_distance(x, y, cx, shadow_end, cy);
            (x - cx).hypot(y - cy) > rc && smoothstep(rc - pen, rc + pen, dist) <= 0.5
        })
        .collect();
    notes.insert("shadowed_squares_ij".into(), json!(shadowed));
    notes.insert(
        "letter_centres_px".into(),
        json!({"A": [a_at.0, a_at.1], "B": [b_at.0, b_at.1], "note": "from the top-left corner, y down"}),
    );
    Ok(Output {
        pixels,
        targets: Some(Targets {
            labels,
            names: vec!["A".into(), "B".into()],
        }),
        surface: None,
        svg: None,
        notes,
    })
}

/// A glyph drawn as strokes into a path builder, centred at a point, `height` pixels high.
type Glyph = fn(&mut tiny_skia::PathBuilder, (f64, f64), f64);

/// The letter A: two legs meeting at the top and a crossbar.
fn glyph_a(pb: &mut tiny_skia::PathBuilder, (cx, cy): (f64, f64), h: f64) {
    let at = |dx: f64, dy: f64| ((cx + dx * h) as f32, (cy + dy * h) as f32);
    let (x, y) = at(-0.36, 0.5);
    pb.move_to(x, y);
    let (x, y) = at(0.0, -0.5);
    pb.line_to(x, y);
    let (x, y) = at(0.36, 0.5);
    pb.line_to(x, y);
    let (x, y) = at(-0.2, 0.1);
    pb.move_to(x, y);
    let (x, y) = at(0.2, 0.1);
    pb.line_to(x, y);
}

/// The letter B: a stem and two bowls.
fn glyph_b(pb: &mut tiny_skia::PathBuilder, (cx, cy): (f64, f64), h: f64) {
    let at = |dx: f64, dy: f64| ((cx + dx * h) as f32, (cy + dy * h) as f32);
    let p =
        |pb: &mut tiny_skia::PathBuilder, dx, dy, f: fn(&mut tiny_skia::PathBuilder, f32, f32)| {
            let (x, y) = at(dx, dy);
            f(pb, x, y);
        };
    p(pb, -0.3, 0.5, tiny_skia::PathBuilder::move_to);
    p(pb, -0.3, -0.5, tiny_skia::PathBuilder::line_to);
    p(pb, 0.02, -0.5, tiny_skia::PathBuilder::line_to);
    let (c1, c2, end) = (at(0.3, -0.5), at(0.3, 0.0), at(0.02, 0.0));
    pb.cubic_to(c1.0, c1.1, c2.0, c2.1, end.0, end.1);
    p(pb, -0.3, 0.0, tiny_skia::PathBuilder::line_to);
    p(pb, 0.06, 0.0, tiny_skia::PathBuilder::move_to);
    let (c1, c2, end) = (at(0.36, 0.0), at(0.36, 0.5), at(0.06, 0.5));
    pb.cubic_to(c1.0, c1.1, c2.0, c2.1, end.0, end.1);
    p(pb, -0.3, 0.5, tiny_skia::PathBuilder::line_to);
}

/// The anti-aliased coverage (0..1 per pixel) of the path `draw` builds, stroked `width`
/// pixels wide with round joins and `cap`.
fn coverage(
    frame: &Geometry,
    draw: impl FnOnce(&mut tiny_skia::PathBuilder),
    width: f64,
    cap: tiny_skia::LineCap,
) -> Result<Grid<f64>> {
    let internal = || Error::Compute("checker-shadow: could not draw the letters".into());
    let mut pixmap = tiny_skia::Pixmap::new(
        u32::try_from(frame.width).map_err(|_| internal())?,
        u32::try_from(frame.height).map_err(|_| internal())?,
    )
    .ok_or_else(internal)?;
    let mut pb = tiny_skia::PathBuilder::new();
    draw(&mut pb);
    let path = pb.finish().ok_or_else(internal)?;
    let mut paint = tiny_skia::Paint::default();
    paint.set_color_rgba8(0, 0, 0, 255);
    paint.anti_alias = true;
    let stroke = tiny_skia::Stroke {
        width: width as f32,
        line_cap: cap,
        line_join: tiny_skia::LineJoin::Round,
        ..Default::default()
    };
    pixmap.stroke_path(
        &path,
        &paint,
        &stroke,
        tiny_skia::Transform::identity(),
        None,
    );
    let alpha = pixmap
        .pixels()
        .iter()
        .map(|p| f64::from(p.alpha()) / 255.0)
        .collect();
    Grid::from_vec(frame.width, frame.height, alpha)
}

/// Paints `value` over `image` with the coverage `cover`, except on target pixels.
fn blend(image: &mut Grid<f64>, labels: &Grid<u16>, cover: &Grid<f64>, value: f64) {
    for ((v, &a), &l) in image
        .data_mut()
        .iter_mut()
        .zip(cover.data())
        .zip(labels.data())
    {
        if a > 0.0 && l == 0 {
            *v = (1.0 - a) * *v + a * value;
        }
    }
}

/// The checker-shadow stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "checker-shadow",
        "Adelson's checker-shadow: squares A and B have the same value, B looks much lighter",
        (7.0, 9.0),
        40.0,
        |p, g, _| checker_shadow(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn generate(pairs: &[&str], ppd: f64) -> Result<Output> {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: (9.0 * ppd) as usize,
            height: (7.0 * ppd) as usize,
            ppd,
        };
        checker_shadow(&CheckerShadowParams::from_map(&given)?, &g)
    }

    #[test]
    fn a_and_b_have_exactly_the_same_value() {
        for pairs in [
            &[][..],
            &["light_square=0.7", "dark_square=0.3"],
            &[
                "squares=5",
                "square=1",
                "cylinder_radius=0.75",
                "cylinder_height=2.2",
                "cylinder_offset=1.7",
                "penumbra=0.15",
            ],
        ] {
            let out = generate(pairs, 20.0).unwrap();
            let Pixels::Gray(img) = &out.pixels else {
                panic!()
            };
            let t = out.targets.as_ref().unwrap();
            let values = |label: u16| -> Vec<f64> {
                img.data()
                    .iter()
                    .zip(t.labels.data())
                    .filter(|(_, &l)| l == label)
                    .map(|(&v, _)| v)
                    .collect()
            };
            let (a, b) = (values(1), values(2));
            assert!(a.len() > 50 && b.len() > 50, "{pairs:?}");
            let dark = out.notes["a_and_b_value"].as_f64().unwrap();
            assert!(a.iter().chain(&b).all(|&v| v == dark), "{pairs:?}");
            // A light square in light is brighter than B; B's neighbours in shadow are darker.
            assert!(img.data().iter().any(|&v| v > dark * 1.5));
        }
    }

    #[test]
    fn the_shadow_covers_b_and_its_neighbours_along_the_cylinders_side() {
        let out = generate(&[], 40.0).unwrap();
        let squares: Vec<[usize; 2]> =
            serde_json::from_value(out.notes["shadowed_squares_ij"].clone()).unwrap();
        let [ib, jb]: [usize; 2] =
            serde_json::from_value(out.notes["squares_ij"]["B"].clone()).unwrap();
        // B and the two squares beyond it, away from the light; A stays out.
        for s in [[ib, jb], [ib - 1, jb], [ib - 2, jb]] {
            assert!(squares.contains(&s), "{s:?} not in shadow: {squares:?}");
        }
        let a: [usize; 2] = serde_json::from_value(out.notes["squares_ij"]["A"].clone()).unwrap();
        assert!(!squares.contains(&a));
    }

    #[test]
    fn perspective_shrinks_the_far_square_and_keeps_a_and_b_equal() {
        let count = |out: &Output, label: u16| {
            let t = out.targets.as_ref().unwrap();
            t.labels.data().iter().filter(|&&l| l == label).count() as f64
        };
        // Orthographic: every square covers the same area (to its edge pixels).
        let flat = generate(&[], 40.0).unwrap();
        let (a, b) = (count(&flat, 1), count(&flat, 2));
        assert!((a / b - 1.0).abs() < 0.03, "{a} {b}");
        // With the eye 16° away, A (farther from the eye than B) covers fewer pixels.
        let near = generate(&["viewing_distance=16"], 40.0).unwrap();
        let (a, b) = (count(&near, 1), count(&near, 2));
        assert!(a < 0.97 * b, "{a} {b}");
        let Pixels::Gray(img) = &near.pixels else {
            panic!()
        };
        let t = near.targets.as_ref().unwrap();
        let dark = near.notes["a_and_b_value"].as_f64().unwrap();
        for (v, l) in img.data().iter().zip(t.labels.data()) {
            assert!(*l == 0 || *v == dark);
        }
        // The picture is not the orthographic one.
        let Pixels::Gray(flat_img) = &flat.pixels else {
            panic!()
        };
        assert_ne!(flat_img.data(), img.data());
        let e = generate(&["viewing_distance=2"], 40.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("too close"), "{e}");
    }

    #[test]
    fn impossible_layouts_are_refused() {
        let e = generate(&["cylinder_offset=0.3"], 20.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("hidden") || e.contains("not wholly"), "{e}");
        let e = generate(&["dark_square=0.9"], 20.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("must not exceed"), "{e}");
        let e = generate(&["square=1.5"], 20.0).unwrap_err().to_string();
        assert!(e.contains("enlarge"), "{e}");
    }
}
