//! `boundary-strips`: one internal shading pattern seen through differently shaped outlines.
//! Inside a wavy (sinusoidal) outline the shading reads as round corrugations; inside a zigzag
//! (sawtooth) one as a folded roof; inside arched ends as a row of cylinders; inside straight
//! edges as flat paint (Knill & Kersten 1991). The outline, not the shading, decides.
//!
//! The shading is a function of x alone, periodic with `period`: L = mean · (1 + contrast ·
//! t(u)), u = the phase within the period, t = sin(2πu) (sinusoidal) or 1 − 2u (ramp). A strip
//! is the set of pixels between two copies of the boundary curve b(u), `height` apart:
//! y_c − height/2 + b(u) < y ≤ y_c + height/2 + b(u). Pixels inside take the shading value
//! there whatever the boundary, so wherever two boundary kinds both cover a pixel, its value is
//! identical. The curves (peak at mid-period, amplitude `amplitude`): sinusoidal −cos(2πu),
//! sawtooth (a zigzag) 1 − 4|u − ½|, arched 2√(1 − (2u − 1)²) − 1, straight 0.

use super::svg::{document, gray, num};
use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use std::f64::consts::TAU;
use svg::node::element::path::Data;
use svg::node::element::{Definitions, LinearGradient, Path, Stop};

/// The boundary kinds.
pub const BOUNDARIES: &[&str] = &["sinusoidal", "sawtooth", "arched", "straight"];

/// The boundary curve at phase `u` in 0..1, from −1 to 1.
fn boundary(kind: &str, u: f64) -> f64 {
    match kind {
        "sinusoidal" => -(TAU * u).cos(),
        "sawtooth" => 1.0 - 4.0 * (u - 0.5).abs(),
        "arched" => 2.0 * (1.0 - (2.0 * u - 1.0).powi(2)).max(0.0).sqrt() - 1.0,
        _ => 0.0,
    }
}

/// The shading at phase `u` in 0..1, from −1 to 1.
fn shade(kind: StripShading, u: f64) -> f64 {
    match kind {
        StripShading::Ramp => 1.0 - 2.0 * u,
        StripShading::Sinusoidal => (TAU * u).sin(),
    }
}

fn parse_boundaries(text: &str) -> Result<Vec<&str>> {
    let kinds: Vec<&str> = text.split(',').map(str::trim).collect();
    for k in &kinds {
        if !BOUNDARIES.contains(k) {
            return Err(Error::invalid(format!(
                "boundary-strips: parameter boundary: '{k}' is not one of {} (give one or a comma-separated list)",
                BOUNDARIES.join(", ")
            )));
        }
    }
    Ok(kinds)
}

param_choice! {
    /// The internal pattern of [`boundary_strips`].
    pub enum StripShading {
        /// A sinusoid per period.
        Sinusoidal = "sinusoidal",
        /// A sawtooth ramp per period.
        Ramp = "ramp",
    }
}

stimulus_params! {
    /// Parameters of [`boundary_strips`].
    pub struct BoundaryStripsParams {
        /// outline kind, or a comma-separated list stacked top to bottom (sinusoidal, sawtooth, arched, straight)
        boundary: String = "sinusoidal,sawtooth,arched,straight";
        /// the internal pattern: a sinusoid or a sawtooth ramp per period
        shading: StripShading = StripShading::Sinusoidal;
        /// period of pattern and outline (deg)
        period: f64 = 1.5, range 0.01..=90.0;
        /// periods per strip
        periods: usize = 6, range 1..=200;
        /// vertical distance between the strip's two outlines (deg)
        height: f64 = 1.6, range 0.01..=90.0;
        /// how far the outline swings up and down (deg)
        amplitude: f64 = 0.3, range 0.0..=45.0;
        /// space between stacked strips (deg)
        gap: f64 = 0.8, range 0.0..=90.0;
        /// shading amplitude relative to the mean
        contrast: f64 = 0.7, range 0.0..=1.0;
        /// mean luminance of the shading
        mean: f64 = 0.5, range 0.0..=1.0;
        /// luminance around the strips
        background: f64 = 0.2, range 0.0..=1.0;
    }
}

/// One shading pattern inside sinusoidal, sawtooth, arched or straight outlines.
pub fn boundary_strips(p: &BoundaryStripsParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let kinds = parse_boundaries(&p.boundary)?;
    let shading = p.shading;
    let period = g.px(p.period);
    let periods = p.periods;
    let height = g.px(p.height);
    let amplitude = g.px(p.amplitude);
    let gap = g.px(p.gap);
    let (contrast, mean, background) = (p.contrast, p.mean, p.background);
    if mean * (1.0 + contrast) > 1.0 {
        return Err(Error::invalid(format!(
            "boundary-strips: mean {mean} × (1 + contrast {contrast}) exceeds 1; lower one of them"
        )));
    }
    if period < 2.0 || height < 1.0 {
        return Err(Error::invalid(format!(
            "boundary-strips: period and height must span at least 2 and 1 pixels at {} ppd",
            g.ppd
        )));
    }
    let width = period * periods as f64;
    // Each strip's band, including the outline's swing, stacked and centred.
    let band = height + 2.0 * amplitude;
    let n = kinds.len();
    let stack = n as f64 * band + (n as f64 - 1.0) * gap;
    let (fw, fh) = (g.width as f64, g.height as f64);
    if width > fw || stack > fh {
        return Err(Error::invalid(format!(
            "boundary-strips: {n} strips need {} but the frame is {}: enlarge the visual size or shorten them",
            crate::message::SizeText::Degrees(stack / g.ppd, width / g.ppd),
            g.size_text()
        )));
    }
    let x0 = g.snap(-width / 2.0, 0.0).0;
    let centre_y = |i: usize| stack / 2.0 - band / 2.0 - i as f64 * (band + gap);
    let phase = |x: f64| ((x - x0) / period).rem_euclid(1.0);
    let level = |u: f64| mean * (1.0 + contrast * shade(shading, u));
    let mut image = Grid::new(g.width, g.height, background);
    let mut labels = Grid::new(g.width, g.height, 0u16);
    for col in g.cols(x0, x0 + width) {
        let x = g.x(col);
        if x < x0 || x >= x0 + width {
            continue;
        }
        let u = phase(x);
        let v = level(u);
        for (i, kind) in kinds.iter().enumerate() {
            let yc = centre_y(i) + amplitude * boundary(kind, u);
            let (lo, hi) = (yc - height / 2.0, yc + height / 2.0);
            for row in g.rows(lo, hi) {
                let y = g.y(row);
                if y > lo && y <= hi {
                    *image.get_mut(col, row) = v;
                    *labels.get_mut(col, row) = i as u16 + 1;
                }
            }
        }
    }
    let svg = {
        let (gx0, _) = g.svg_xy(x0, 0.0);
        let mut gradient = LinearGradient::new()
            .set("id", "shading")
            .set("gradientUnits", "userSpaceOnUse")
            .set("spreadMethod", "repeat")
            .set("x1", num(gx0))
            .set("y1", 0)
            .set("x2", num(gx0 + period))
            .set("y2", 0);
        // A ramp is exact with two stops (jumping at the period's end); a sinusoid is
        // sampled with 32 stops per period.
        let n_stops = if shading == StripShading::Ramp { 1 } else { 32 };
        for k in 0..=n_stops {
            let u = k as f64 / n_stops as f64;
            let value = if shading == StripShading::Ramp && k == n_stops {
                level(1.0)
            } else {
                level(u)
            };
            gradient = gradient.add(
                Stop::new()
                    .set("offset", num(u))
                    .set("stop-color", gray(value)),
            );
        }
        let mut doc =
            document(g, "boundary-strips", background).add(Definitions::new().add(gradient));
        let samples = 64 * periods;
        for (i, kind) in kinds.iter().enumerate() {
            let curve = |k: usize, offset: f64| -> (f64, f64) {
                let x = x0 + width * k as f64 / samples as f64;
                let u = if k == samples { 1.0 } else { phase(x) };
                g.svg_xy(x, centre_y(i) + amplitude * boundary(kind, u) + offset)
            };
            let start = curve(0, height / 2.0);
            let mut data = Data::new().move_to((num(start.0), num(start.1)));
            for k in 1..=samples {
                let (x, y) = curve(k, height / 2.0);
                data = data.line_to((num(x), num(y)));
            }
            for k in (0..=samples).rev() {
                let (x, y) = curve(k, -height / 2.0);
                data = data.line_to((num(x), num(y)));
            }
            doc = doc.add(
                Path::new()
                    .set("d", data.close())
                    .set("fill", "url(#shading)")
                    .set("data-boundary", *kind),
            );
        }
        doc.to_string()
    };
    let mut notes = Map::new();
    notes.insert("boundaries".into(), json!(kinds));
    notes.insert("strip_left_px".into(), json!(g.svg_xy(x0, 0.0).0));
    Ok(Output {
        pixels: Pixels::Gray(image),
        targets: Some(Targets {
            labels,
            names: kinds.iter().map(|k| format!("{k} strip")).collect(),
        }),
        surface: None,
        svg: Some(svg),
        notes,
    })
}

/// The boundary-strips stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "boundary-strips",
        "one shading pattern inside sinusoidal, sawtooth, arched or straight outlines: the outline decides the shape",
        (12.0, 11.0),
        32.0,
        |p, g, _| boundary_strips(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn generate(pairs: &[&str]) -> Result<Output> {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 220,
            height: 120,
            ppd: 20.0,
        };
        boundary_strips(&BoundaryStripsParams::from_map(&given)?, &g)
    }

    #[test]
    fn any_two_boundaries_agree_wherever_both_cover_a_pixel() {
        let outs: Vec<Output> = BOUNDARIES
            .iter()
            .map(|b| generate(&[&format!("boundary={b}")]).unwrap())
            .collect();
        for (i, a) in outs.iter().enumerate() {
            for b in &outs[i + 1..] {
                let (Pixels::Gray(ia), Pixels::Gray(ib)) = (&a.pixels, &b.pixels) else {
                    panic!()
                };
                let (la, lb) = (
                    &a.targets.as_ref().unwrap().labels,
                    &b.targets.as_ref().unwrap().labels,
                );
                let mut shared = 0;
                for k in 0..ia.len() {
                    if la.data()[k] > 0 && lb.data()[k] > 0 {
                        assert_eq!(ia.data()[k], ib.data()[k]);
                        shared += 1;
                    }
                }
                assert!(shared > 1000);
                assert_ne!(la, lb, "the outlines differ");
            }
        }
    }

    #[test]
    fn outlines_have_their_shape() {
        // The top edge of the sinusoidal strip is highest at mid-period, lowest at its ends.
        let out = generate(&["boundary=sinusoidal"]).unwrap();
        let t = &out.targets.unwrap().labels;
        let left = out.notes["strip_left_px"].as_f64().unwrap();
        let top = |col: usize| (0..120).find(|&r| *t.get(col, r) > 0).unwrap();
        let (mid, end) = ((left + 15.0) as usize, (left + 1.0) as usize);
        assert!(top(mid) + 8 < top(end), "{} vs {}", top(mid), top(end));
        let out = generate(&["boundary=straight"]).unwrap();
        let t = &out.targets.unwrap().labels;
        let top = |col: usize| (0..120).find(|&r| *t.get(col, r) > 0).unwrap();
        assert_eq!(top(mid), top(end));
    }

    #[test]
    fn unknown_boundaries_are_named() {
        let e = generate(&["boundary=sinusoidal,wavy"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("'wavy'") && e.contains("sawtooth"), "{e}");
    }
}
