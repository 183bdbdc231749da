//! `circles-binary` and `circles-gradient`: arrays of shaded circles (Ramachandran 1988).
//! Each circle is half light and half dark (binary) or carries a linear gradient; rows of
//! opposite polarity group into bumps and dimples together (one light for the scene), and one
//! circle of opposite polarity among many pops out (`odd_one_out`).
//!
//! Circle centres are snapped to pixel corners, so no pixel centre lies on a circle's dividing
//! line: a binary circle has exactly two values inside, in equal halves. Layout is a grid or a
//! seeded random placement (SplitMix64), so the same seed gives the same array.

use super::frame::{grid_centres, random_centres};
use super::svg::{document, gray, num};
use super::{Output, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::random::SplitMix64;
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use svg::node::element::path::Data;
use svg::node::element::{Circle, Definitions, LinearGradient, Path, Stop};

/// How each circle of [`circles`] is shaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CircleShading {
    /// Half light, half dark (`circles-binary`).
    Binary,
    /// A smooth gradient (`circles-gradient`).
    Gradient,
}

param_choice! {
    /// How the circles of [`circles`] are placed.
    pub enum CircleLayout {
        /// Rows and columns.
        Grid = "grid",
        /// A seeded random placement.
        Random = "random",
    }
}

param_choice! {
    /// Which circles of [`circles`] are light on top.
    pub enum CirclePolarity {
        /// Alternate rows.
        Rows = "rows",
        /// All of them.
        Same = "same",
        /// At random (seeded).
        Random = "random",
    }
}

param_choice! {
    /// The direction of the shading of a circle.
    pub enum ShadingAxis {
        /// Top–bottom.
        Vertical = "vertical",
        /// Left–right.
        Horizontal = "horizontal",
    }
}

stimulus_params! {
    /// Parameters of [`circles`].
    pub struct CirclesParams {
        /// circle radius (deg)
        radius: f64 = 0.8, range 0.01..=90.0;
        /// centre-to-centre distance (deg; the least distance in a random layout)
        spacing: f64 = 2.4, range 0.01..=180.0;
        /// rows and columns, or a seeded random placement
        layout: CircleLayout = CircleLayout::Grid;
        /// rows (grid layout)
        rows: usize = 4, range 1..=50;
        /// columns (grid layout)
        columns: usize = 6, range 1..=50;
        /// number of circles (random layout)
        count: usize = 12, range 1..=1000;
        /// which circles are light on top: alternate rows, all, or at random (seeded)
        polarity: CirclePolarity = CirclePolarity::Rows;
        /// flip the polarity of one circle (chosen by the seed)
        odd_one_out: bool = false;
        /// direction of the shading: top–bottom or left–right
        axis: ShadingAxis = ShadingAxis::Vertical;
        /// light and dark levels are background · (1 ± contrast)
        contrast: f64 = 0.6, range 0.0..=1.0;
        /// luminance around the circles
        background: f64 = 0.5, range 0.0..=1.0;
    }
}

/// Arrays of shaded circles, half light and half dark or graded (Ramachandran 1988).
pub fn circles(
    p: &CirclesParams,
    shading: CircleShading,
    g: &Geometry,
    seed: u64,
) -> Result<Output> {
    p.validate()?;
    Circles { shading }.generate(p, g, seed)
}

struct Circles {
    shading: CircleShading,
}

impl Circles {
    fn name(&self) -> &'static str {
        match self.shading {
            CircleShading::Binary => "circles-binary",
            CircleShading::Gradient => "circles-gradient",
        }
    }

    fn generate(&self, p: &CirclesParams, g: &Geometry, seed: u64) -> Result<Output> {
        let name = self.name();
        let radius = g.px(p.radius);
        let spacing = g.px(p.spacing);
        let (contrast, background) = (p.contrast, p.background);
        if background * (1.0 + contrast) > 1.0 {
            return Err(Error::invalid(format!(
                "{name}: background {background} × (1 + contrast {contrast}) exceeds 1; lower one of them"
            )));
        }
        if radius < 1.0 {
            return Err(Error::invalid(format!(
                "{name}: radius {}° is under one pixel at {} ppd",
                p.radius, g.ppd
            )));
        }
        let random_layout = p.layout == CircleLayout::Random;
        let (rows, cols) = (p.rows, p.columns);
        let count = if random_layout { p.count } else { rows * cols };
        if count > 1 && spacing < 2.0 * radius {
            return Err(Error::invalid(format!(
                "{name}: spacing {}° is less than the circle diameter {}°: circles would overlap",
                p.spacing,
                2.0 * p.radius
            )));
        }
        // Layout and polarity draw from separate streams so that changing one keeps the other.
        let centres = if random_layout {
            random_centres(name, g, count, radius, spacing, seed)?
        } else {
            let c = grid_centres(g, rows, cols, spacing);
            g.check_inside(
                &format!("{name}: {rows} rows × {cols} columns of circles"),
                &c,
                radius,
            )?;
            c
        };
        let mut rng = SplitMix64::new(seed ^ 0x0005_EED0_FC1B_C1E5);
        let mut light_top: Vec<bool> = match p.polarity {
            CirclePolarity::Same => vec![true; count],
            CirclePolarity::Random => (0..count).map(|_| rng.next_u64() >> 63 == 0).collect(),
            _ if random_layout => {
                // Rows of a scattered array: above or below the middle of the frame.
                centres.iter().map(|&(_, y)| y >= 0.0).collect()
            }
            _ => (0..count).map(|i| (i / cols) % 2 == 0).collect(),
        };
        let odd = if p.odd_one_out {
            let i = rng.below(count);
            light_top[i] = !light_top[i];
            Some(i)
        } else {
            None
        };
        let vertical = p.axis == ShadingAxis::Vertical;
        let (light, dark) = (background * (1.0 + contrast), background * (1.0 - contrast));
        let mut image = Grid::new(g.width, g.height, background);
        let mut labels = Grid::new(g.width, g.height, 0u16);
        let mut names = Vec::with_capacity(count);
        for (i, (&(cx, cy), &up)) in centres.iter().zip(&light_top).enumerate() {
            let label = u16::try_from(i + 1).map_err(|_| Error::invalid("too many circles"))?;
            let side = match (vertical, up) {
                (true, true) => "light top",
                (true, false) => "light bottom",
                (false, true) => "light left",
                (false, false) => "light right",
            };
            let odd_mark = if odd == Some(i) { ", odd one out" } else { "" };
            names.push(format!("circle {} ({side}{odd_mark})", i + 1));
            let sign = if up { 1.0 } else { -1.0 };
            for row in g.rows(cy - radius, cy + radius) {
                for col in g.cols(cx - radius, cx + radius) {
                    let (x, y) = (g.x(col) - cx, g.y(row) - cy);
                    if x * x + y * y >= radius * radius {
                        continue;
                    }
                    // Toward the light side: +y (top) or −x (left).
                    let t = if vertical { y } else { -x };
                    let v = match self.shading {
                        CircleShading::Binary => {
                            if (t > 0.0) == up {
                                light
                            } else {
                                dark
                            }
                        }
                        CircleShading::Gradient => {
                            background * (1.0 + contrast * sign * t / radius)
                        }
                    };
                    *image.get_mut(col, row) = v;
                    *labels.get_mut(col, row) = label;
                }
            }
        }
        let svg = self.svg(
            g, &centres, &light_top, radius, vertical, background, light, dark,
        );
        let mut notes = Map::new();
        notes.insert("light_level".into(), json!(light));
        notes.insert("dark_level".into(), json!(dark));
        if let Some(i) = odd {
            notes.insert("odd_one_out_label".into(), json!(i + 1));
        }
        notes.insert(
            "centres_px".into(),
            json!(centres
                .iter()
                .map(|&(x, y)| {
                    let (x, y) = g.svg_xy(x, y);
                    [x, y]
                })
                .collect::<Vec<_>>()),
        );
        Ok(Output::drawn(image, Targets { labels, names }, svg, notes))
    }

    #[allow(clippy::too_many_arguments)]
    fn svg(
        &self,
        frame: &Geometry,
        centres: &[(f64, f64)],
        light_top: &[bool],
        radius: f64,
        vertical: bool,
        background: f64,
        light: f64,
        dark: f64,
    ) -> String {
        let mut doc = document(frame, self.name(), background);
        if self.shading == CircleShading::Gradient {
            // Gradient "up" runs from the light side (offset 0) to the dark side.
            let (x2, y2) = if vertical { (0, 1) } else { (1, 0) };
            let mut defs = Definitions::new();
            for (id, first, last) in [("up", light, dark), ("down", dark, light)] {
                defs = defs.add(
                    LinearGradient::new()
                        .set("id", id)
                        .set("x1", 0)
                        .set("y1", 0)
                        .set("x2", x2)
                        .set("y2", y2)
                        .add(Stop::new().set("offset", 0).set("stop-color", gray(first)))
                        .add(Stop::new().set("offset", 1).set("stop-color", gray(last))),
                );
            }
            doc = doc.add(defs);
        }
        for (&(cx, cy), &up) in centres.iter().zip(light_top) {
            let (x, y) = frame.svg_xy(cx, cy);
            match self.shading {
                CircleShading::Gradient => {
                    doc = doc.add(
                        Circle::new()
                            .set("cx", num(x))
                            .set("cy", num(y))
                            .set("r", num(radius))
                            .set("fill", if up { "url(#up)" } else { "url(#down)" }),
                    );
                }
                CircleShading::Binary => {
                    // Two half discs; the first is the top (or left) half.
                    let (ax, ay, bx, by) = if vertical {
                        (x - radius, y, x + radius, y)
                    } else {
                        (x, y + radius, x, y - radius)
                    };
                    for (first_half, sweep) in [(true, 1), (false, 0)] {
                        let data = Data::new()
                            .move_to((num(ax), num(ay)))
                            .elliptical_arc_to((
                                num(radius),
                                num(radius),
                                0,
                                0,
                                sweep,
                                num(bx),
                                num(by),
                            ))
                            .close();
                        let fill = if first_half == up { light } else { dark };
                        doc = doc.add(Path::new().set("d", data).set("fill", gray(fill)));
                    }
                }
            }
        }
        doc.to_string()
    }
}

/// The circle arrays.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    const SIZE: (f64, f64) = (10.0, 15.0);
    const PPD: f64 = 32.0;
    vec![
        Typed::boxed(
            "circles-binary",
            "circles half light, half dark: rows of opposite polarity read as bumps and dimples",
            SIZE,
            PPD,
            |p, g, seed| circles(p, CircleShading::Binary, g, seed),
        ),
        Typed::boxed(
            "circles-gradient",
            "smoothly graded circles in rows or scattered; an odd one out pops out",
            SIZE,
            PPD,
            |p, g, seed| circles(p, CircleShading::Gradient, g, seed),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use crate::Pixels;

    fn generate(shading: CircleShading, pairs: &[&str], seed: u64) -> Output {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 240,
            height: 160,
            ppd: 16.0,
        };
        circles(&CirclesParams::from_map(&given).unwrap(), shading, &g, seed).unwrap()
    }

    #[test]
    fn binary_circles_have_exactly_two_levels_in_equal_halves() {
        for pairs in [
            &["axis=vertical"][..],
            &["axis=horizontal", "layout=random"],
        ] {
            let out = generate(CircleShading::Binary, pairs, 7);
            let Pixels::Gray(img) = &out.pixels else {
                panic!()
            };
            let t = out.targets.as_ref().unwrap();
            for label in 1..=t.names.len() as u16 {
                let v: Vec<f64> = img
                    .data()
                    .iter()
                    .zip(t.labels.data())
                    .filter(|(_, &l)| l == label)
                    .map(|(&v, _)| v)
                    .collect();
                let light = v.iter().filter(|&&x| x == 0.5 * (1.0 + 0.6)).count();
                let dark = v.iter().filter(|&&x| x == 0.5 * (1.0 - 0.6)).count();
                assert_eq!(light + dark, v.len(), "only two levels inside");
                assert_eq!(light, dark, "equal halves");
                assert!(v.len() > 100);
            }
        }
    }

    #[test]
    fn odd_one_out_flips_exactly_one_and_is_named() {
        let same = generate(CircleShading::Gradient, &["polarity=same"], 3);
        let odd = generate(
            CircleShading::Gradient,
            &["polarity=same", "odd_one_out=true"],
            3,
        );
        let label = odd.notes["odd_one_out_label"].as_u64().unwrap() as u16;
        let (Pixels::Gray(a), Pixels::Gray(b)) = (&same.pixels, &odd.pixels) else {
            panic!()
        };
        let labels = &odd.targets.as_ref().unwrap().labels;
        for i in 0..a.len() {
            if labels.data()[i] == label {
                assert!((a.data()[i] - 0.5) * (b.data()[i] - 0.5) <= 0.0);
            } else {
                assert_eq!(a.data()[i], b.data()[i]);
            }
        }
        assert!(odd.targets.unwrap().names[label as usize - 1].contains("odd one out"));
    }

    #[test]
    fn random_layout_depends_on_the_seed_only() {
        let a = generate(CircleShading::Binary, &["layout=random"], 1);
        assert_eq!(a, generate(CircleShading::Binary, &["layout=random"], 1));
        assert_ne!(
            a.pixels,
            generate(CircleShading::Binary, &["layout=random"], 2).pixels
        );
    }
}
