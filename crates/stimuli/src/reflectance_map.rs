//! The reflectance map as a picture: R over gradient space (p, q) or stereographic space
//! (f, g) as a heat map with iso-brightness contours, and the contour of one measured intensity
//! highlighted: every orientation on it explains that pixel equally well, which is why one
//! image alone does not fix the shape.

use super::surfaces::LightingParams;
use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::colormap::viridis;
use crate::error::Result;
use crate::gradient_space::{normal_from_fg, normal_from_pq};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::Value;

param_choice! {
    /// The orientation space a reflectance map is drawn over.
    pub enum OrientationSpace {
        /// Gradient space (p, q).
        Pq = "pq",
        /// Stereographic space (f, g).
        Fg = "fg",
    }
}

stimulus_params! {
    /// Parameters of [`reflectance_map`].
    pub struct ReflectanceMapParams {
        /// gradient space (p, q) or stereographic space (f, g)
        space: OrientationSpace = OrientationSpace::Pq;
        /// half-width of the p–q window (f–g always shows its radius-2 disc and a margin)
        extent: f64 = 3.0, range 0.1..=100.0;
        /// iso-brightness contours at R = k/(N+1)
        contours: usize = 10, range 0..=100;
        /// the measured intensity whose contour is highlighted (0: none)
        intensity: f64 = 0.6, range 0.0..=1.0;
        /// draw a figure for a slide or a paper: the map with labelled axes and ticks, a colour bar of R and a title, in a picture of the requested size, as display codes (write it without a gamma; needs a build with plots)
        figure: bool = false;
        /// light and reflectance
        flatten lighting: LightingParams { light: "above-left" };
    }
}

/// The reflectance-map figure.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "reflectance-map",
        "R(p,q) or R(f,g) as a heat map with iso-brightness contours (the under-constrained problem)",
        (8.0, 8.0),
        64.0,
        |p, g, _| reflectance_map(p, g),
    )]
}

/// R(p, q) or R(f, g) as a heat map with iso-brightness contours and the contour of one
/// measured intensity highlighted.
pub fn reflectance_map(p: &ReflectanceMapParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let (w, h) = (g.width, g.height);
    let map = map_picture(p, w, h, true)?;
    let (extent, top, measured, fg) = (map.extent, map.top, p.intensity, map.fg);
    let mut out = Output::gray(map.values.map(|v| v.unwrap_or(0.0)));
    out.pixels = Pixels::Rgb(map.image);
    out.targets = Some(Targets {
        labels: map.labels,
        names: vec!["lit".into(), "self-shadowed".into()],
    });
    if p.figure {
        if let Some(figure) = figure_pixels(p, w, h)? {
            out.pixels = Pixels::Rgb(figure);
            // A figure's pixels are axes and labels, not orientations: no target mask.
            out.targets = None;
            out.notes.insert(
                "figure".into(),
                Value::from("the map with axes, tick labels, a colour bar of R and a title; pixel values are display codes (sRGB / 255)"),
            );
        }
    }
    out.notes
        .insert("space".into(), Value::from(if fg { "fg" } else { "pq" }));
    out.notes.insert("axes".into(), Value::from(if fg { "f right, g up, ticks at every unit; black circle: the rim f²+g² = 4 (white outside it: no visible normal); orange ringed dots: (2,0) = normal (1,0,0) and (0,2) = normal (0,1,0)" } else { "p right, q up, ticks at every unit" }));
    out.notes
        .insert("window_half_width".into(), Value::from(extent));
    out.notes.insert("max_R".into(), Value::from(top));
    out.notes
        .insert("highlighted_intensity".into(), Value::from(measured));
    out.notes.insert(
        "white_dot".into(),
        Value::from("the orientation facing the light (brightest)"),
    );
    Ok(out)
}

/// The map drawn at `w` × `h`: its picture (linear RGB), the values of R (none outside the
/// f–g disc), the largest R, the window's half-width and whether it is f–g space.
struct MapPicture {
    image: crate::grid::RgbImage,
    values: Grid<Option<f64>>,
    /// 1 = orientations facing the light (lit), 2 = visible ones facing away from it (attached
    /// shadow), 0 = outside the f–g disc (no orientation).
    labels: Grid<u16>,
    top: f64,
    extent: f64,
    fg: bool,
}

/// `ticks`: tick marks at every unit on the axes (a figure has labelled ticks of its own).
fn map_picture(p: &ReflectanceMapParams, w: usize, h: usize, ticks: bool) -> Result<MapPicture> {
    let light = p.lighting.light;
    let reflectance = p.lighting.reflectance()?;
    let fg = p.space == OrientationSpace::Fg;
    let extent = if fg { 2.2 } else { p.extent };
    let contours = p.contours;
    let measured = p.intensity;
    let scale = extent / (w.min(h) as f64 / 2.0);
    // Coordinates of pixel centres: first axis right, second axis up.
    let coord = |c: usize, r: usize| {
        (
            (c as f64 - (w as f64 - 1.0) / 2.0) * scale,
            ((h as f64 - 1.0) / 2.0 - r as f64) * scale,
        )
    };
    let values = Grid::from_fn(w, h, |c, r| {
        let (a, b) = coord(c, r);
        if fg {
            (a * a + b * b <= 4.0).then(|| reflectance.radiance(&normal_from_fg(a, b)))
        } else {
            Some(reflectance.radiance(&normal_from_pq(a, b)))
        }
    });
    let top = values
        .data()
        .iter()
        .flatten()
        .fold(0.0f64, |m, &v| m.max(v))
        .max(1e-12);
    // A contour passes between two pixels whose values lie on either side of its level.
    let crosses = |c: usize, r: usize, level: f64| -> bool {
        let Some(v) = *values.get(c, r) else {
            return false;
        };
        [(1isize, 0isize), (0, 1)].iter().any(|&(dc, dr)| {
            matches!(values.checked(c as isize + dc, r as isize + dr), Some(Some(u)) if (v - level) * (u - level) < 0.0)
        })
    };
    let near = |c: usize, r: usize, radius: isize, level: f64| -> bool {
        (-radius..=radius).any(|dr| {
            (-radius..=radius).any(|dc| {
                let (cc, rr) = (c as isize + dc, r as isize + dr);
                cc >= 0
                    && rr >= 0
                    && (cc as usize) < w
                    && (rr as usize) < h
                    && crosses(cc as usize, rr as usize, level)
            })
        })
    };
    let thick = ((w.min(h) as f64) / 300.0).round().max(1.0) as isize;
    let s = light.direction();
    let light_point = if fg {
        Some((2.0 * s.x / (1.0 + s.z), 2.0 * s.y / (1.0 + s.z)))
    } else if s.z > 1e-9 {
        Some((s.x / s.z, s.y / s.z))
    } else {
        None
    };
    let dot = 4.0 * scale * thick as f64;
    let line = scale * thick as f64 / 2.0;
    // Ticks at every unit of the axes, so the figure can be read without a plot frame.
    let tick = 3.0 * dot;
    let on_tick = |x: f64| (x - x.round()).abs() <= line && x.round() != 0.0;
    let axis_grey = [0.35, 0.35, 0.35];
    let image = Grid::from_fn(w, h, |c, r| {
        let (a, b) = coord(c, r);
        if fg {
            // The limb normals (1,0,0) and (0,1,0) as rings that reach past the disc's rim,
            // where they lie, so they are visible on white as well as on the map.
            let ring = |x: f64, y: f64| ((a - x).hypot(b - y) - 2.0 * dot).abs() <= line * 1.5;
            if ring(2.0, 0.0) || ring(0.0, 2.0) {
                return [1.0, 0.45, 0.0];
            }
            // The rim f² + g² = 4: the occluding boundary.
            if (a.hypot(b) - 2.0).abs() <= line {
                return [0.0, 0.0, 0.0];
            }
        }
        let Some(v) = *values.get(c, r) else {
            return [1.0, 1.0, 1.0];
        };
        if measured > 0.0 && near(c, r, thick, measured) {
            return [1.0, 0.1, 0.05];
        }
        if let Some((lx, ly)) = light_point {
            if (a - lx).hypot(b - ly) < dot {
                return [1.0, 1.0, 1.0];
            }
        }
        if fg && ((a - 2.0).hypot(b) < dot || a.hypot(b - 2.0) < dot) {
            return [1.0, 0.45, 0.0];
        }
        if (1..=contours).any(|k| crosses(c, r, top * k as f64 / (contours + 1) as f64)) {
            return [0.0, 0.0, 0.0];
        }
        if a.abs() <= scale / 2.0 || b.abs() <= scale / 2.0 {
            return axis_grey;
        }
        if ticks && ((b.abs() <= tick && on_tick(a)) || (a.abs() <= tick && on_tick(b))) {
            return axis_grey;
        }
        viridis(v / top)
    });
    let labels = Grid::from_fn(w, h, |c, r| {
        let (a, b) = coord(c, r);
        let n = if fg {
            if a * a + b * b > 4.0 {
                return 0u16;
            }
            normal_from_fg(a, b)
        } else {
            normal_from_pq(a, b)
        };
        if n.dot(&s) > 0.0 {
            1
        } else {
            2
        }
    });
    Ok(MapPicture {
        image,
        values,
        labels,
        top,
        extent,
        fg,
    })
}

/// The map as a figure of `w` × `h` pixels (the map drawn afresh at the size it is shown, so
/// that its contours stay whole), as display codes over 255; `None` in a build without plots.
fn figure_pixels(
    p: &ReflectanceMapParams,
    w: usize,
    h: usize,
) -> Result<Option<crate::grid::RgbImage>> {
    #[cfg(feature = "plots")]
    {
        use crate::colormap::Colormap;
        use crate::plot::{ColourBar, MapFigure};
        let fg = p.space == OrientationSpace::Fg;
        let (space, a, b) = if fg {
            ("f, g", "f", "g")
        } else {
            ("p, q", "p", "q")
        };
        let light = p.lighting.light;
        let mut title = format!(
            "Reflectance map R({space}), light tilt {:.0}°, slant {:.0}°",
            light.tilt_deg(),
            light.slant_deg()
        );
        if p.intensity > 0.0 {
            title.push_str(&format!("; red: R = {}", p.intensity));
        }
        let bar = |top: f64| ColourBar {
            colormap: Colormap::Viridis,
            range: (0.0, top),
            label: "R (radiance, linear luminance)".into(),
        };
        let mut figure = MapFigure::new(&title, Grid::new(w, h, [1.0; 3]), bar(1.0));
        figure.size = (w as u32, h as u32);
        let (mw, mh) = figure.map_size();
        let map = map_picture(p, mw, mh, false)?;
        let half = map.extent / (mw.min(mh) as f64 / 2.0);
        figure.x_range = (-half * mw as f64 / 2.0, half * mw as f64 / 2.0);
        figure.y_range = (-half * mh as f64 / 2.0, half * mh as f64 / 2.0);
        figure.x_label = if fg {
            format!("{a} (stereographic, = 2 n_x / (1 + n_z), no unit)")
        } else {
            format!("{a} (gradient space, = n_x / n_z, no unit)")
        };
        figure.y_label = if fg {
            format!("{b} (= 2 n_y / (1 + n_z))")
        } else {
            format!("{b} (= n_y / n_z)")
        };
        figure.bar = bar(map.top);
        figure.picture = map.image;
        let (bytes, _, _) = figure.rgb()?;
        let codes: Vec<[f64; 3]> = bytes
            .chunks_exact(3)
            .map(|c| [0, 1, 2].map(|k| c[k] as f64 / 255.0))
            .collect();
        Ok(Some(Grid::from_vec(w, h, codes)?))
    }
    #[cfg(not(feature = "plots"))]
    {
        let _ = (p, w, h);
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visual_size::SizeRequest;

    #[test]
    fn fg_map_is_white_outside_the_disc_and_peaks_toward_the_light() {
        let mut given = serde_json::Map::new();
        given.insert("space".into(), Value::from("fg"));
        given.insert("light".into(), Value::from("tilt=90,slant=45"));
        let size = SizeRequest {
            shape: Some((101, 101)),
            ..Default::default()
        };
        let (_, out) =
            super::super::generate("reflectance-map", &given, &size, 0, 1 << 20).unwrap();
        let Pixels::Rgb(img) = &out.pixels else {
            panic!("rgb expected")
        };
        assert_eq!(
            *img.get(0, 0),
            [1.0, 1.0, 1.0],
            "corner is outside f²+g² ≤ 4"
        );
        // The light is to the left: left of centre is brighter than right of centre on the f axis.
        let params = ReflectanceMapParams::from_map(&given).unwrap();
        assert_eq!(params.space, OrientationSpace::Fg);
        let lum = crate::grid::luminance;
        assert!(lum(*img.get(30, 50)) > lum(*img.get(70, 50)));
        // The rings marking (2,0) and (0,2) reach past the rim, where the map is white: one
        // unit is 50.5/2.2 pixels and a ring's radius 8 pixels, so the ring's top point over
        // (2,0) is pixel (96, 42), just outside the disc, and likewise (58, 4) beside (0,2).
        let orange = [1.0, 0.45, 0.0];
        assert_eq!(
            *img.get(96, 42),
            orange,
            "ring around (2,0) outside the disc"
        );
        assert_eq!(
            *img.get(58, 4),
            orange,
            "ring around (0,2) outside the disc"
        );
        assert_eq!(*img.get(100, 42), [1.0; 3], "outside the disc and the ring");
    }

    #[test]
    fn the_measured_contour_is_the_iso_brightness_curve_of_that_intensity() {
        // Light from the front: R = n_z = 1/√(1+p²+q²), so R = 0.6 is the circle p²+q² = (1/0.36 − 1).
        let mut given = serde_json::Map::new();
        given.insert("light".into(), Value::from("front"));
        given.insert("contours".into(), Value::from(0));
        let size = SizeRequest {
            shape: Some((201, 201)),
            ..Default::default()
        };
        let (_, out) =
            super::super::generate("reflectance-map", &given, &size, 0, 1 << 20).unwrap();
        let Pixels::Rgb(img) = &out.pixels else {
            panic!("rgb expected")
        };
        let radius = (1.0f64 / 0.36 - 1.0).sqrt() * 100.0 / 3.0;
        let red = [1.0, 0.1, 0.05];
        // On the circle (along the diagonal, away from the axes and their ticks): red; well
        // inside and outside it: not.
        let at = |r: f64| {
            let d = (r / std::f64::consts::SQRT_2).round() as usize;
            *img.get(100 + d, 100 + d)
        };
        assert_eq!(at(radius), red);
        assert_ne!(at(radius - 6.0), red);
        assert_ne!(at(radius + 6.0), red);
    }
}
