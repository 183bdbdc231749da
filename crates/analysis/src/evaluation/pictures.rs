//! The picture of a solved case: one strip of panels, left to right,
//!
//! 1. the input image (display-encoded with gamma 2.2, clipped at the albedo);
//! 2. the recovered normals as colour, (n + 1)/2 → (R, G, B);
//! 3. the true normals, where known;
//! 4. the angle between them, viridis from 0° (dark blue) to [`ERROR_SCALE_DEG`] (yellow) and
//!    beyond, where known, followed by its colour bar (labelled in degrees in builds with
//!    plots);
//! 5. the recovered depth, rendered as a matte surface under a light from the upper left
//!    ([`DEPTH_LIGHT`]), which shows the shape the solver found better than a depth ramp does.
//!
//! Outside the object the panels are light gray; panels are separated by white gaps.

use super::case::{Case, CaseOutput};
use crate::colormap::viridis;
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask, RgbImage};
use crate::light::Light;
use crate::reflectance::{Lambertian, ReflectanceMap};
use crate::surface::Surface;

/// The angle shown as the top of the error colour scale, in degrees.
pub const ERROR_SCALE_DEG: f64 = 45.0;

/// The light of the shaded-depth panel: tilt 45° (upper left), slant 45°.
pub const DEPTH_LIGHT: (f64, f64) = (45.0, 45.0);

/// Display gamma of the gray panels.
const GAMMA: f64 = 2.2;

/// Gray outside the object.
const BACKGROUND: f64 = 0.92;

/// White gap between panels, in pixels.
const GAP: usize = 4;

/// The panel strip of a solved case (see the module docs).
pub fn case_panel(case: &Case, output: &CaseOutput) -> RgbImage {
    let mask = &case.domain;
    let mut panels = vec![
        gray_panel(&case.image, mask),
        normal_panel(&output.normals, mask),
    ];
    if let Some(truth) = &case.truth_normals {
        panels.push(normal_panel(truth, mask));
    }
    if let Some(error) = &output.error_map {
        panels.push(error_panel(error, &case.scored));
        panels.push(error_scale(error.height()));
    }
    panels.push(shaded_depth_panel(&output.depth, mask));
    side_by_side(&panels)
}

fn display(v: f64) -> f64 {
    v.clamp(0.0, 1.0).powf(1.0 / GAMMA)
}

fn gray_panel(image: &Image, mask: &Mask) -> RgbImage {
    Grid::from_fn(image.width(), image.height(), |c, r| {
        if *mask.get(c, r) {
            [display(*image.get(c, r)); 3]
        } else {
            [BACKGROUND; 3]
        }
    })
}

fn normal_panel(normals: &Grid<Normal>, mask: &Mask) -> RgbImage {
    Grid::from_fn(normals.width(), normals.height(), |c, r| {
        if *mask.get(c, r) {
            let n = normals.get(c, r);
            [0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5]
        } else {
            [BACKGROUND; 3]
        }
    })
}

fn error_panel(error: &Image, scored: &Mask) -> RgbImage {
    Grid::from_fn(error.width(), error.height(), |c, r| {
        if *scored.get(c, r) {
            // viridis is linear RGB; encode it like the gray panels.
            viridis((error.get(c, r) / ERROR_SCALE_DEG).min(1.0)).map(display)
        } else {
            [BACKGROUND; 3]
        }
    })
}

/// The error panel's colour bar, as tall as the panel: viridis from 0° (bottom) to
/// [`ERROR_SCALE_DEG`] (top), and beside it (with plots) its end values and the unit.
fn error_scale(height: usize) -> RgbImage {
    let h = height.max(2);
    let bar = Grid::from_fn(SCALE_BAR + SCALE_TEXT, h, |c, r| {
        if c < SCALE_BAR {
            viridis(1.0 - r as f64 / (h - 1) as f64).map(display)
        } else {
            [1.0; 3]
        }
    });
    label_error_scale(bar)
}

/// Width of the error colour bar and of the text beside it, in pixels.
const SCALE_BAR: usize = 14;
const SCALE_TEXT: usize = 46;

/// The error bar with its end values and the unit set beside it.
#[cfg(feature = "plots")]
fn label_error_scale(bar: RgbImage) -> RgbImage {
    use crate::plot::{caption_pixels, encode, Caption};
    let (width, h) = (bar.width(), bar.height());
    let size = (width as u32, h as u32);
    let mut bytes: Vec<u8> = bar
        .data()
        .iter()
        .flat_map(|p| p.map(|v| encode(v, None)))
        .collect();
    let x = (SCALE_BAR + SCALE_TEXT / 2) as i32;
    let text = (h as f64 / 8.0).clamp(9.0, 13.0);
    let label = |y: i32, t: &str| Caption {
        at: (x, y),
        text: t.into(),
        size: text,
        width: SCALE_TEXT as u32 - 2,
    };
    let bottom = (h as i32 - text as i32 - 2).max(0);
    let captions = [
        label(0, &format!("≥{ERROR_SCALE_DEG}°")),
        label(bottom / 2, "error"),
        label(bottom, "0°"),
    ];
    // A failure to set text leaves the bar unlabelled; the numbers are in the results.
    if caption_pixels(&mut bytes, size, &captions).is_err() {
        return bar;
    }
    Grid::from_fn(width, h, |c, r| {
        let i = (r * width + c) * 3;
        [0, 1, 2].map(|k| bytes[i + k] as f64 / 255.0)
    })
}

/// Without plots the bar stays unlabelled.
#[cfg(not(feature = "plots"))]
fn label_error_scale(bar: RgbImage) -> RgbImage {
    bar
}

fn shaded_depth_panel(depth: &Image, mask: &Mask) -> RgbImage {
    let surface = Surface::from_depth(depth.clone(), mask.clone());
    let light = Light::from_tilt_slant(DEPTH_LIGHT.0, DEPTH_LIGHT.1);
    match (surface, light) {
        (Ok(surface), Ok(light)) => {
            let map = Lambertian {
                light,
                albedo: 0.85,
                ambient: 0.1,
            };
            Grid::from_fn(depth.width(), depth.height(), |c, r| {
                if *mask.get(c, r) {
                    [display(map.radiance(surface.normals.get(c, r))); 3]
                } else {
                    [BACKGROUND; 3]
                }
            })
        }
        // A depth map the solver made is finite and matches its mask; never reached.
        _ => Grid::new(depth.width(), depth.height(), [BACKGROUND; 3]),
    }
}

/// `panels` (all the same height) left to right with white gaps.
fn side_by_side(panels: &[RgbImage]) -> RgbImage {
    let h = panels.iter().map(Grid::height).max().unwrap_or(0);
    let w = panels.iter().map(Grid::width).sum::<usize>() + GAP * panels.len().saturating_sub(1);
    let mut out = Grid::new(w, h, [1.0; 3]);
    let mut x0 = 0;
    for p in panels {
        for r in 0..p.height() {
            for c in 0..p.width() {
                *out.get_mut(x0 + c, r) = *p.get(c, r);
            }
        }
        x0 += p.width() + GAP;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_bar_runs_from_zero_at_the_bottom_to_the_scale_top() {
        let bar = error_scale(100);
        assert_eq!(bar.height(), 100);
        // Equal to the 8-bit code the picture is written with.
        let near = |a: [f64; 3], b: [f64; 3]| (0..3).all(|k| (a[k] - b[k]).abs() <= 0.5 / 255.0);
        assert!(near(*bar.get(0, 99), viridis(0.0).map(display)));
        assert!(near(*bar.get(SCALE_BAR - 1, 0), viridis(1.0).map(display)));
        // With plots, its labels are set in dark text beside it.
        let dark = (0..100)
            .flat_map(|r| (SCALE_BAR..bar.width()).map(move |c| (c, r)))
            .filter(|&(c, r)| bar.get(c, r)[0] < 0.3)
            .count();
        assert_eq!(dark > 20, cfg!(feature = "plots"), "{dark}");
    }
}
