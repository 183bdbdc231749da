//! Vector (SVG) renderings of the stimuli that are vector by nature: circle arrays, strips,
//! cut-outs, the checkerboard.
//!
//! One SVG user unit is one pixel of the raster version, so the two line up. Colours are the
//! linear luminance values written as percentages with four decimals (no display gamma, as in
//! the default PNG); gradients interpolate linearly in those values.

use crate::visual_size::Geometry;
use svg::node::element::{Rectangle, Title};
use svg::Document;

/// An empty document the size of `frame`, filled with `background`.
pub(crate) fn document(frame: &Geometry, title: &str, background: f64) -> Document {
    Document::new()
        .set("width", frame.width)
        .set("height", frame.height)
        .set("viewBox", (0, 0, frame.width, frame.height))
        .set("shape-rendering", "crispEdges")
        .add(Title::new(title))
        .add(
            Rectangle::new()
                .set("x", 0)
                .set("y", 0)
                .set("width", frame.width)
                .set("height", frame.height)
                .set("fill", gray(background)),
        )
}

/// An SVG colour for the linear gray level `v` (0..1).
pub(crate) fn gray(v: f64) -> String {
    rgb([v, v, v])
}

/// An SVG colour for linear RGB values (0..1).
pub(crate) fn rgb(c: [f64; 3]) -> String {
    let pct = |v: f64| format!("{:.4}%", (v.clamp(0.0, 1.0) * 100.0));
    format!("rgb({},{},{})", pct(c[0]), pct(c[1]), pct(c[2]))
}

/// A number rounded to 1/1000 pixel, for compact and reproducible path data.
pub(crate) fn num(v: f64) -> f64 {
    let r = (v * 1000.0).round() / 1000.0;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colours_and_numbers() {
        assert_eq!(gray(0.5), "rgb(50.0000%,50.0000%,50.0000%)");
        assert_eq!(rgb([0.0, 1.2, 0.25]), "rgb(0.0000%,100.0000%,25.0000%)");
        assert_eq!(num(1.23456), 1.235);
        assert_eq!(num(-0.0001), 0.0);
        let d = document(
            &Geometry {
                width: 4,
                height: 3,
                ppd: 1.0,
            },
            "t",
            0.5,
        )
        .to_string();
        assert!(d.contains("viewBox=\"0 0 4 3\"") && d.contains("<title>"));
    }
}
