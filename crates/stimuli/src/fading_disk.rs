//! `fading-disk`: Troxler fading. A blue disk with a blurred edge in a green field, with a
//! fixation mark: under steady fixation the disk fades into the green, because a blurred edge
//! that does not move on the retina stops driving vision and the region is filled in from the
//! surround (Troxler 1804). The achromatic variant uses two grey levels.
//!
//! The edge is a raised cosine `blur` degrees wide centred on the radius: weight 1 inside
//! r − blur/2, 0 outside r + blur/2, (1 + cos(π·t))/2 between; each channel is
//! field + weight · (disk − field). Colours are linear RGB 0..1.

use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};

/// The colour `text` (r,g,b in 0..1) of the parameter `key`.
fn colour(key: &str, text: &str) -> Result<[f64; 3]> {
    let bad = || {
        Error::invalid(format!(
            "fading-disk: parameter {key}: '{text}' is not three numbers r,g,b in 0..1"
        ))
    };
    let v: Vec<f64> = text
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    match v[..] {
        [r, g, b] if v.iter().all(|c| (0.0..=1.0).contains(c)) => Ok([r, g, b]),
        _ => Err(bad()),
    }
}

/// The raised-cosine edge weight at distance `rho` from the centre.
fn edge(rho: f64, radius: f64, blur: f64) -> f64 {
    if blur <= 0.0 {
        return if rho < radius { 1.0 } else { 0.0 };
    }
    let t = (rho - (radius - blur / 2.0)) / blur;
    if t <= 0.0 {
        1.0
    } else if t >= 1.0 {
        0.0
    } else {
        0.5 * (1.0 + (std::f64::consts::PI * t).cos())
    }
}

param_choice! {
    /// The colours of [`fading_disk`].
    pub enum FadingVariant {
        /// Blue on green (RGB output).
        Colour = "colour",
        /// Grey on grey (one channel).
        Achromatic = "achromatic",
    }
}

stimulus_params! {
    /// Parameters of [`fading_disk`].
    pub struct FadingDiskParams {
        /// disk radius, at the middle of the edge (deg)
        radius: f64 = 2.5, range 0.01..=90.0;
        /// width of the blurred edge (deg)
        blur: f64 = 2.0, range 0.0..=90.0;
        /// blue on green (RGB output) or grey on grey (one channel)
        variant: FadingVariant = FadingVariant::Colour;
        /// disk colour, linear r,g,b in 0..1
        disk_colour: String = "0.35,0.5,0.95";
        /// field colour, linear r,g,b in 0..1
        field_colour: String = "0.3,0.75,0.3";
        /// disk luminance (achromatic)
        disk_gray: f64 = 0.35, range 0.0..=1.0;
        /// field luminance (achromatic)
        field_gray: f64 = 0.5, range 0.0..=1.0;
        /// radius of the fixation dot (deg; 0 for none)
        fixation_radius: f64 = 0.1, range 0.0..=10.0;
        /// horizontal offset of the fixation dot from the disk's centre (deg)
        fixation_offset: f64 = 0.0, range -90.0..=90.0;
        /// fixation dot colour, linear r,g,b
        fixation_colour: String = "0,0,0";
    }
}

/// A blurred disk in a field that fades under steady fixation (Troxler).
pub fn fading_disk(p: &FadingDiskParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let radius = g.px(p.radius);
    let blur = g.px(p.blur);
    if blur > 2.0 * radius {
        return Err(Error::invalid(format!(
            "fading-disk: blur {}° exceeds the disk's diameter {}°",
            p.blur,
            2.0 * p.radius
        )));
    }
    let achromatic = p.variant == FadingVariant::Achromatic;
    let (disk, field) = if achromatic {
        let (d, f) = (p.disk_gray, p.field_gray);
        ([d; 3], [f; 3])
    } else {
        (
            colour("disk_colour", &p.disk_colour)?,
            colour("field_colour", &p.field_colour)?,
        )
    };
    let fix_colour = colour("fixation_colour", &p.fixation_colour)?;
    let fix_r = g.px(p.fixation_radius);
    let fix_x = g.px(p.fixation_offset);
    let mut rgb = Grid::new(g.width, g.height, field);
    let mut labels = Grid::new(g.width, g.height, 0u16);
    for row in 0..g.height {
        for col in 0..g.width {
            let (x, y) = (g.x(col), g.y(row));
            let rho = x.hypot(y);
            let px = rgb.get_mut(col, row);
            if (x - fix_x).hypot(y) < fix_r {
                *px = fix_colour;
                *labels.get_mut(col, row) = 2;
                continue;
            }
            let wgt = edge(rho, radius, blur);
            if wgt > 0.0 {
                for k in 0..3 {
                    px[k] = field[k] + wgt * (disk[k] - field[k]);
                }
            }
            if rho < radius {
                *labels.get_mut(col, row) = 1;
            }
        }
    }
    let mut notes = Map::new();
    notes.insert("disk_rgb".into(), json!(disk));
    notes.insert("field_rgb".into(), json!(field));
    let pixels = if achromatic {
        Pixels::Gray(rgb.map(|c| c[0]))
    } else {
        Pixels::Rgb(rgb)
    };
    Ok(Output {
        pixels,
        targets: Some(Targets {
            labels,
            names: vec!["disk".into(), "fixation".into()],
        }),
        surface: None,
        svg: None,
        notes,
    })
}

/// The fading-disk stimulus.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![Typed::boxed(
        "fading-disk",
        "a blurred blue disk in a green field fades under steady fixation (Troxler)",
        (8.0, 10.0),
        32.0,
        |p, g, _| fading_disk(p, g),
    )]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;

    fn generate(pairs: &[&str]) -> Result<Output> {
        let given = Params::parse_pairs(pairs).unwrap();
        let g = Geometry {
            width: 100,
            height: 80,
            ppd: 10.0,
        };
        fading_disk(&FadingDiskParams::from_map(&given)?, &g)
    }

    #[test]
    fn the_edge_is_blurred_over_the_given_width_in_degrees() {
        let out = generate(&["fixation_radius=0"]).unwrap();
        let Pixels::Rgb(img) = &out.pixels else {
            panic!()
        };
        // Along the middle row (y = −0.5 px): inside r − blur/2 = 15 px the disk colour,
        // beyond r + blur/2 = 35 px the field colour, and in between a monotone ramp.
        let row = 40;
        let blue = |col: usize| img.get(col, row)[2];
        assert_eq!(img.get(50, row), &[0.35, 0.5, 0.95]);
        assert_eq!(img.get(50 + 36, row), &[0.3, 0.75, 0.3]);
        for c in 50 + 14..50 + 36 {
            assert!(blue(c) >= blue(c + 1));
        }
        let mid = blue(50 + 24);
        assert!((mid - 0.625).abs() < 0.05, "{mid}");
    }

    #[test]
    fn achromatic_variant_is_gray_and_colours_are_checked() {
        let out = generate(&["variant=achromatic"]).unwrap();
        assert!(matches!(out.pixels, Pixels::Gray(_)));
        let e = generate(&["disk_colour=0.2,0.3"]).unwrap_err().to_string();
        assert!(e.contains("disk_colour"), "{e}");
        let e = generate(&["field_colour=0.2,0.3,1.5"])
            .unwrap_err()
            .to_string();
        assert!(e.contains("field_colour"), "{e}");
    }
}
