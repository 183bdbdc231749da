//! `strips`: parallel strips whose luminance gradients alternate in direction. Vision assumes
//! one light for the whole scene: once the strips bright on top are seen as facing up (light
//! from above), the others are seen as facing down, and the array reads as one corrugated
//! surface rather than as strips painted with gradients.
//!
//! Strip widths, gaps and lengths are whole pixels (rounded from degrees) so every strip
//! covers the same pixel pattern; the gradient is sampled at pixel centres,
//! L = background · (1 ± contrast · t(u)) with u running from −1 to 1 across the strip and
//! t(u) = u (linear) or sin(πu/2) (sinusoidal).

use super::svg::{document, gray, num};
use super::{Output, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use svg::node::element::{Definitions, LinearGradient, Rectangle, Stop};

/// The gradient profile t(u) for u in −1..1.
pub(crate) fn profile(kind: StripProfile, u: f64) -> f64 {
    match kind {
        StripProfile::Sinusoidal => (std::f64::consts::FRAC_PI_2 * u).sin(),
        StripProfile::Linear => u,
    }
}

/// SVG gradient stops for a profile going from t = −1 at offset 0 to t = 1 at offset 1.
pub(crate) fn stops(kind: StripProfile, level: impl Fn(f64) -> f64) -> Vec<Stop> {
    let n = if kind == StripProfile::Linear { 1 } else { 16 };
    (0..=n)
        .map(|i| {
            let offset = i as f64 / n as f64;
            Stop::new()
                .set("offset", num(offset))
                .set("stop-color", gray(level(profile(kind, 2.0 * offset - 1.0))))
        })
        .collect()
}

param_choice! {
    /// The direction [`strips`] run.
    pub enum StripOrientation {
        /// Left to right (stacked top to bottom).
        Horizontal = "horizontal",
        /// Top to bottom (stacked left to right).
        Vertical = "vertical",
    }
}

param_choice! {
    /// The shape of the gradient across a strip.
    pub enum StripProfile {
        /// t(u) = u.
        Linear = "linear",
        /// t(u) = sin(πu/2).
        Sinusoidal = "sinusoidal",
    }
}

stimulus_params! {
    /// Parameters of [`strips`].
    pub struct StripsParams {
        /// number of strips
        strips: usize = 6, range 1..=200;
        /// width of each strip (deg)
        strip_width: f64 = 1.0, range 0.01..=90.0;
        /// length of each strip (deg)
        length: f64 = 8.0, range 0.01..=180.0;
        /// gap between strips (deg)
        gap: f64 = 0.25, range 0.0..=90.0;
        /// direction the strips run (the gradient runs across them)
        orientation: StripOrientation = StripOrientation::Horizontal;
        /// shape of the gradient across a strip
        profile: StripProfile = StripProfile::Linear;
        /// gradient amplitude relative to the background
        contrast: f64 = 0.6, range 0.0..=1.0;
        /// mean luminance of the strips and of the background
        background: f64 = 0.5, range 0.0..=1.0;
    }
}

/// Parallel strips with opposite luminance gradients: one light for the whole scene.
pub fn strips(p: &StripsParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let n = p.strips;
    let horizontal = p.orientation == StripOrientation::Horizontal;
    let kind = p.profile;
    let (contrast, background) = (p.contrast, p.background);
    if background * (1.0 + contrast) > 1.0 {
        return Err(Error::invalid(format!(
            "strips: background {background} × (1 + contrast {contrast}) exceeds 1; lower one of them"
        )));
    }
    let width = g.px(p.strip_width).round() as usize;
    let gap = g.px(p.gap).round() as usize;
    let length = g.px(p.length).round() as usize;
    if width == 0 || length == 0 {
        return Err(Error::invalid(format!(
            "strips: strip_width and length must be at least one pixel at {} ppd",
            g.ppd
        )));
    }
    // Across = the axis the strips are stacked along; along = the axis they run.
    let (across_px, along_px) = if horizontal {
        (g.height, g.width)
    } else {
        (g.width, g.height)
    };
    let total = n * width + n.saturating_sub(1) * gap;
    if total > across_px || length > along_px {
        return Err(Error::invalid(format!(
            "strips: {n} strips need {} but the frame is {}: enlarge the visual size or make them smaller or fewer",
            crate::message::SizeText::Degrees(
                if horizontal { total } else { length } as f64 / g.ppd,
                if horizontal { length } else { total } as f64 / g.ppd,
            ),
            g.size_text()
        )));
    }
    let start = (across_px - total) / 2;
    let along0 = (along_px - length) / 2;
    let level = |sign: f64, k: usize| -> f64 {
        // An exact integer numerator makes u(k) = −u(width − 1 − k) to the last bit.
        let u = (2.0 * k as f64 + 1.0 - width as f64) / width as f64;
        background * (1.0 + contrast * sign * profile(kind, u))
    };
    let sign = |i: usize| if i % 2 == 0 { 1.0 } else { -1.0 };
    let mut image = Grid::new(g.width, g.height, background);
    let mut labels = Grid::new(g.width, g.height, 0u16);
    let mut names = Vec::with_capacity(n);
    for i in 0..n {
        let first = start + i * (width + gap);
        let label = u16::try_from(i + 1).map_err(|_| Error::invalid("too many strips"))?;
        // Sign +1: bright at the top (horizontal strips) or at the left (vertical ones).
        names.push(format!(
            "strip {} ({})",
            i + 1,
            match (horizontal, sign(i) > 0.0) {
                (true, true) => "bright top",
                (true, false) => "bright bottom",
                (false, true) => "bright left",
                (false, false) => "bright right",
            }
        ));
        for k in 0..width {
            // k counts from the top (or left) edge; t = +1 there for sign +1.
            let v = level(-sign(i), k);
            for a in along0..along0 + length {
                let (col, row) = if horizontal {
                    (a, first + k)
                } else {
                    (first + k, a)
                };
                *image.get_mut(col, row) = v;
                *labels.get_mut(col, row) = label;
            }
        }
    }
    let svg = {
        let mut defs = Definitions::new();
        for (id, sign) in [("g0", 1.0), ("g1", -1.0)] {
            let (x2, y2) = if horizontal { (0, 1) } else { (1, 0) };
            let mut g = LinearGradient::new()
                .set("id", id)
                .set("x1", 0)
                .set("y1", 0)
                .set("x2", x2)
                .set("y2", y2);
            for stop in stops(kind, |t| background * (1.0 - contrast * sign * t)) {
                g = g.add(stop);
            }
            defs = defs.add(g);
        }
        let mut doc = document(g, "strips", background).add(defs);
        for i in 0..n {
            let first = start + i * (width + gap);
            let (x, y, w, h) = if horizontal {
                (along0, first, length, width)
            } else {
                (first, along0, width, length)
            };
            doc = doc.add(
                Rectangle::new()
                    .set("x", x)
                    .set("y", y)
                    .set("width", w)
                    .set("height", h)
                    .set("fill", format!("url(#g{})", i % 2)),
            );
        }
        doc.to_string()
    };
    let mut notes = Map::new();
    notes.insert(
        "strip_px".into(),
        json!({"width": width, "gap": gap, "length": length}),
    );
    Ok(Output::drawn(image, Targets { labels, names }, svg, notes))
}

/// The strips stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "strips",
        "parallel strips with opposite luminance gradients: one light for the whole scene",
        (9.0, 10.0),
        32.0,
        |p, g, _| strips(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use crate::Pixels;

    fn generate(pairs: &[&str]) -> Result<Output> {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 200,
            height: 180,
            ppd: 20.0,
        };
        strips(&StripsParams::from_map(&given).unwrap(), &g)
    }

    #[test]
    fn neighbouring_strips_are_mirror_images_across_their_width() {
        let out = generate(&[]).unwrap();
        let Pixels::Gray(img) = &out.pixels else {
            panic!()
        };
        let t = out.targets.as_ref().unwrap();
        let col = 100;
        let rows = |label: u16| -> Vec<f64> {
            (0..180)
                .filter(|&r| *t.labels.get(col, r) == label)
                .map(|r| *img.get(col, r))
                .collect()
        };
        let (a, mut b) = (rows(1), rows(2));
        assert_eq!(a.len(), 20);
        assert!(a[0] > a[19], "strip 1 is bright on top");
        b.reverse();
        assert_eq!(a, b);
        // The mean of each strip is the background (the gradient is odd about the middle).
        let mean: f64 = a.iter().sum::<f64>() / 20.0;
        assert!((mean - 0.5).abs() < 1e-12);
    }

    #[test]
    fn too_many_strips_or_too_bright_is_an_error() {
        assert!(generate(&["strips=40"])
            .unwrap_err()
            .to_string()
            .contains("enlarge"));
        assert!(generate(&["background=0.8", "contrast=0.5"])
            .unwrap_err()
            .to_string()
            .contains("exceeds 1"));
    }
}
