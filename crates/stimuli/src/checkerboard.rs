//! `checkerboard` and `disc`: the plain building blocks of lightness experiments, with the
//! same parameters as stimupy's (`checkerboard`: check size and two intensities; `disc`: radius,
//! disc and background intensities), so that shadelab can stand in for it and be compared with
//! it.
//!
//! No anti-aliasing: the checkerboard's pixels and checks are stimupy 1.2's, computed as it
//! computes them, a check side being rounded to whole pixels as stimupy rounds it (0.75° at
//! 10 ppd is 8 pixels, 0.8°, with a warning; see [`checkerboard`]), and a pixel of the disc
//! follows stimupy's rule (see [`disc`]); the SVG versions have their edges at the same places.
//!
//! Targets are stimupy's: a checkerboard has none (no target mask, as stimupy's all-zero
//! `target_mask`) unless `targets` names checks as stimupy's `target_indices` do, and then its
//! mask is stimupy's `target_mask` (those checks, drawn with `intensity_target`).

use super::svg::{document, gray, num};
use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Labels};
use crate::parallel::prelude::*;
use crate::params::{stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use svg::node::element::{Circle, Ellipse, Rectangle};

/// Rows per parallel work item: large enough that scheduling costs nothing.
const ROWS_PER_TASK: usize = 64;

stimulus_params! {
    /// Parameters of [`checkerboard`].
    pub struct CheckerboardParams {
        /// side of one check (deg)
        check: f64 = 1.0, range 0.001..=180.0;
        /// luminance of the top-left check
        intensity_first: f64 = 0.0, range 0.0..=1.0;
        /// luminance of its neighbours
        intensity_second: f64 = 1.0, range 0.0..=1.0;
        /// target checks as stimupy's target_indices: "row,col;row,col" from the top left, 0-based (empty: no targets, as stimupy)
        targets: String = "";
        /// luminance of the target checks (only with targets)
        intensity_target: f64 = 0.5, range 0.0..=1.0;
    }
}

stimulus_params! {
    /// Parameters of [`disc`].
    pub struct DiscParams {
        /// radius (deg)
        radius: f64 = 2.0, range 0.001..=180.0;
        /// luminance of the disc
        intensity_disc: f64 = 1.0, range 0.0..=1.0;
        /// luminance around it
        intensity_background: f64 = 0.0, range 0.0..=1.0;
    }
}

/// A picture of `frame`'s size and its label map, every value `background` and every label 0
/// until `paint(row, values, labels)` fills row `row` (rows in parallel, the same bytes for any
/// thread count).
fn paint_rows(
    frame: &Geometry,
    background: f64,
    paint: impl Fn(usize, &mut [f64], &mut [u16]) + Send + Sync,
) -> Result<(Image, Labels)> {
    let mut data = vec![background; frame.width * frame.height];
    let mut labels = vec![0u16; frame.width * frame.height];
    data.par_chunks_mut(frame.width * ROWS_PER_TASK)
        .zip(labels.par_chunks_mut(frame.width * ROWS_PER_TASK))
        .enumerate()
        .for_each(|(task, (chunk, lab))| {
            for (k, (row, lrow)) in chunk
                .chunks_mut(frame.width)
                .zip(lab.chunks_mut(frame.width))
                .enumerate()
            {
                paint(task * ROWS_PER_TASK + k, row, lrow);
            }
        });
    Ok((
        Grid::from_vec(frame.width, frame.height, data)?,
        Grid::from_vec(frame.width, frame.height, labels)?,
    ))
}

/// The checks `text` names as `row,col` pairs separated by `;` (stimupy's `target_indices`),
/// each inside a board of `rows` × `cols` checks.
fn parse_targets(text: &str, rows: usize, cols: usize) -> Result<Vec<(usize, usize)>> {
    let bad = |why: String| Error::invalid(format!("checkerboard: parameter targets: {why}"));
    text.split(';')
        .map(str::trim)
        .filter(|t| !t.is_empty())
        .map(|pair| {
            let (r, c) = pair
                .split_once(',')
                .ok_or_else(|| bad(format!("'{pair}' is not row,col")))?;
            let index = |t: &str| {
                t.trim()
                    .parse::<usize>()
                    .map_err(|_| bad(format!("'{pair}' is not two check indices (0, 1, 2 ...)")))
            };
            let (r, c) = (index(r)?, index(c)?);
            if r >= rows || c >= cols {
                return Err(bad(format!(
                    "check ({r},{c}) is outside the board of {rows} rows and {cols} columns"
                )));
            }
            Ok((r, c))
        })
        .collect()
}

/// The name of the check in row `r` and column `c` (0-based from the top left).
fn check_name(r: usize, c: usize) -> String {
    format!("r{r}c{c}")
}

/// A plain checkerboard (as stimupy's), starting with the first intensity at the top left.
///
/// The check side is whole pixels as stimupy 1.2 makes it: `round(check·ppd)` pixels (half to
/// even), recorded in the notes as [`CHECK_ROUNDED_NOTE`] (with a warning) where that changes
/// it; the checks run from the top-left corner. The picture and its target mask are stimupy's
/// pixel for pixel, including where stimupy's square waves put an edge a pixel off a whole
/// number of checks (see `StimupyGrating`).
///
/// Its targets are stimupy's: with no `targets` there are none (no target mask); with
/// `targets` (stimupy's `target_indices`), the named checks in the order given, named `r0c1`
/// (row 0, column 1, from the top left), drawn with `intensity_target` (as stimupy's
/// `target_mask`).
///
/// ```
/// use shadelab::stimulus::{checkerboard, CheckerboardParams, Pixels};
/// use shadelab::Geometry;
///
/// // 0.5° checks at 4 ppd are 2 pixels wide: columns 0-1 dark, 2-3 light. (On a frame of a
/// // few checks stimupy's square waves move edges: 6 × 4 pixels start 1, 0, 1, 1, 0, 1.)
/// let p = CheckerboardParams { check: 0.5, ..Default::default() };
/// let g = Geometry { width: 12, height: 8, ppd: 4.0 };
/// let out = checkerboard(&p, &g).unwrap();
/// let Pixels::Gray(image) = &out.pixels else { panic!() };
/// let top: Vec<f64> = (0..6).map(|c| *image.get(c, 0)).collect();
/// assert_eq!(top, [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]);
/// assert_eq!(*image.get(0, 2), 1.0);
/// // No targets unless named, as stimupy; named checks are drawn at intensity_target.
/// assert!(out.targets.is_none());
/// let p = CheckerboardParams { check: 0.5, targets: "1,2;0,0".into(), ..Default::default() };
/// let out = checkerboard(&p, &g).unwrap();
/// let targets = out.targets.unwrap();
/// assert_eq!(targets.names, ["r1c2", "r0c0"]);
/// assert_eq!((*targets.labels.get(5, 3), *targets.labels.get(0, 0), *targets.labels.get(2, 0)), (1, 2, 0));
/// ```
pub fn checkerboard(p: &CheckerboardParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let check = rounded_check(p.check, g.ppd);
    if check.pixels < 1.0 {
        return Err(Error::invalid(format!(
            "checkerboard: check {}° is under one pixel at {} ppd (stimupy rounds it to {} pixels)",
            p.check, g.ppd, check.pixels
        )));
    }
    let (first, second) = (p.intensity_first, p.intensity_second);
    let columns = StimupyGrating::new(g.width, g.ppd, check.pixels, (first, second));
    let rows = StimupyGrating::new(g.height, g.ppd, check.pixels, (first, second));
    let (nx, ny) = (columns.checks, rows.checks);
    let chosen = parse_targets(&p.targets, ny, nx)?;
    if chosen.len() > usize::from(u16::MAX) {
        return Err(Error::invalid(format!(
            "checkerboard: parameter targets names {} checks; a target mask holds at most {}",
            chosen.len(),
            u16::MAX
        )));
    }
    // The label of each check (row-major), 0 where it is not a target.
    let mut check_labels = vec![0u16; nx * ny];
    for (k, &(r, c)) in chosen.iter().enumerate() {
        if check_labels[r * nx + c] != 0 {
            return Err(Error::invalid(format!(
                "checkerboard: parameter targets names check ({r},{c}) twice"
            )));
        }
        check_labels[r * nx + c] = k as u16 + 1;
    }
    let names: Vec<String> = chosen.iter().map(|&(r, c)| check_name(r, c)).collect();
    let targets_drawn = !chosen.is_empty();
    let target_value = p.intensity_target;
    let pixel = |y: usize, x: usize| {
        let label = check_labels[rows.check[y] * nx + columns.check[x]];
        let value = if targets_drawn && label != 0 {
            target_value
        } else {
            stimupy_plaid(columns.value[x], rows.value[y], (first, second))
        };
        (value, label)
    };
    let (image, labels) = paint_rows(g, 0.0, |y, row, lrow| {
        for (x, (v, l)) in row.iter_mut().zip(lrow.iter_mut()).enumerate() {
            (*v, *l) = pixel(y, x);
        }
    })?;
    let mut notes = Map::new();
    notes.insert("checks".into(), json!([nx, ny]));
    if (check.degrees - p.check).abs() > 1e-9 * p.check {
        notes.insert(
            CHECK_ROUNDED_NOTE.into(),
            json!({
                "asked_check": p.check,
                "check": check.degrees,
                "check_px": check.pixels,
            }),
        );
    }
    let (column_runs, row_runs) = (columns.runs(), rows.runs());
    let svg = if column_runs.len() * row_runs.len() > MAX_SVG_CHECKS {
        notes.insert(
            "svg_omitted".into(),
            json!(format!(
                "{} checks are too many for an SVG document (limit {MAX_SVG_CHECKS})",
                nx * ny
            )),
        );
        None
    } else {
        let mut doc = document(g, "checkerboard", first);
        for &(y0, y1) in &row_runs {
            for &(x0, x1) in &column_runs {
                let (value, _) = pixel(y0, x0);
                if value != first {
                    doc = doc.add(
                        Rectangle::new()
                            .set("x", x0)
                            .set("y", y0)
                            .set("width", x1 - x0)
                            .set("height", y1 - y0)
                            .set("fill", gray(value)),
                    );
                }
            }
        }
        Some(doc.to_string())
    };
    Ok(Output {
        pixels: Pixels::Gray(image),
        targets: targets_drawn.then_some(Targets { labels, names }),
        surface: None,
        svg,
        notes,
    })
}

/// The note of a checkerboard whose check whole pixels changed (stimupy's rounding), recorded
/// in the sidecar's notes: `{"asked_check", "check", "check_px"}` in degrees and pixels; the
/// command line and Python say it as a warning ([`rounded_check_warning`]).
pub const CHECK_ROUNDED_NOTE: &str = "check_rounded";

/// The warning a render with [`CHECK_ROUNDED_NOTE`] gives, in one line (stimupy says
/// "Adjusted phase_width=0.75 -> 0.8 because of poor resolution").
pub fn rounded_check_warning(note: &serde_json::Value, ppd: f64) -> Option<String> {
    let (asked, check, pixels) = (
        note["asked_check"].as_f64()?,
        note["check"].as_f64()?,
        note["check_px"].as_f64()?,
    );
    Some(format!(
        "checkerboard: check {asked}° at {ppd} ppd is {pixels} px, rounded to whole pixels as \
         stimupy does: {check:.4}°"
    ))
}

/// A check side as stimupy 1.2 draws it (`stimupy.components.waves.resolve_grating_params`
/// with `round_phase_width`): its pixels, NumPy's `round(check·ppd)` (half to even), and the
/// degrees they are. stimupy first turns the check into checks per degree and back, as here.
struct RoundedCheck {
    pixels: f64,
    degrees: f64,
}

fn rounded_check(check: f64, ppd: f64) -> RoundedCheck {
    let per_degree = 1.0 / check;
    let pixels = (1.0 / per_degree * ppd).round_ties_even();
    RoundedCheck {
        pixels,
        degrees: pixels / ppd,
    }
}

/// One axis of stimupy 1.2's checkerboard, which is the plaid of two square-wave gratings
/// (`stimupy.components.waves.square`, origin "corner", distance "oblique"), computed as
/// stimupy computes it so that the pixels and the mask are its own whole or not:
///
/// - the distance of pixel i from the corner is `linspace(0, n/ppd, n)[i]` degrees (the ends on
///   the frame's edges), rounded to 6 decimals and stretched to run from 0.001 to its largest
///   value less 0.001;
/// - its value is `sin(π·distance/check)` scaled from its own range (min..max over the axis) to
///   the two intensities and rounded to the nearer one, so a grating that does not reach a
///   trough moves its first edge (33 rows at 10 ppd with 1° checks: row 0 a check of its own);
/// - its check (the mask's) is the nearest of the phase centres
///   `arange(0.001 + check/2, …, check)`, a tie to the later one, numbered as they occur.
///
/// (The vertical grating's distance also holds 6·10⁻¹⁷·x from stimupy's rotation by −90°,
/// below the rounding to 10⁻⁶ degrees.)
struct StimupyGrating {
    /// Each pixel's value, one of the two intensities.
    value: Vec<f64>,
    /// Each pixel's check, 0-based from the top left.
    check: Vec<usize>,
    /// The checks along the axis.
    checks: usize,
}

impl StimupyGrating {
    fn new(n: usize, ppd: f64, check_px: f64, (first, second): (f64, f64)) -> StimupyGrating {
        if n < 2 {
            // stimupy divides by the zero range of a one-pixel axis; its corner is lit.
            return StimupyGrating {
                value: vec![second; n],
                check: vec![0; n],
                checks: 1,
            };
        }
        let width = check_px / ppd;
        let round6 = |v: f64| (v * 1e6).round_ties_even() / 1e6;
        let raw: Vec<f64> = numpy_linspace(0.0, n as f64 / ppd, n)
            .into_iter()
            .map(round6)
            .collect();
        let (low, high) = min_max(&raw);
        let (start, stop) = (1e-3, high - 1e-3);
        let distance: Vec<f64> = raw
            .iter()
            .map(|&d| (d - low) / (high - low) * (stop - start) + start)
            .collect();
        let frequency = 1.0 / (2.0 * width);
        let sine: Vec<f64> = distance
            .iter()
            .map(|&d| (frequency * 2.0 * std::f64::consts::PI * d + 0.0).sin())
            .collect();
        let (s_low, s_high) = min_max(&sine);
        let (lo, hi) = (first.min(second), first.max(second));
        let value = sine
            .iter()
            .map(|&s| {
                let v = (s - s_low) / (s_high - s_low) * (second - first) + first;
                // stimupy.utils.round_to_vals: the lower one only when strictly nearer.
                if v <= lo || (v - lo).abs() < (v - hi).abs() {
                    lo
                } else {
                    hi
                }
            })
            .collect();
        // The phase centres, as NumPy's arange fills them: start + i·((start + step) − start).
        let (d_low, d_high) = min_max(&distance);
        let centre0 = d_low + width / 2.0;
        let end = d_high.max(-d_low) + width;
        let count = ((end - centre0) / width).ceil().max(1.0) as usize;
        let delta = (centre0 + width) - centre0;
        let centres: Vec<f64> = (0..count).map(|i| centre0 + i as f64 * delta).collect();
        let nearest: Vec<usize> = distance
            .iter()
            .map(|&d| {
                let i = centres.partition_point(|&c| c < d);
                let previous = i.max(1) - 1;
                if i == centres.len()
                    || (d - centres[previous]).abs() < (d - centres[i.min(centres.len() - 1)]).abs()
                {
                    previous
                } else {
                    i
                }
            })
            .collect();
        // Numbered in the order they occur (np.unique of the regions present).
        let mut present: Vec<usize> = nearest.clone();
        present.sort_unstable();
        present.dedup();
        let check = nearest
            .iter()
            .map(|k| present.partition_point(|p| p < k))
            .collect();
        StimupyGrating {
            value,
            check,
            checks: present.len(),
        }
    }

    /// The runs of pixels [start, end) with one value and one check.
    fn runs(&self) -> Vec<(usize, usize)> {
        let mut runs = Vec::new();
        let mut start = 0;
        for i in 1..=self.value.len() {
            if i == self.value.len()
                || self.value[i] != self.value[start]
                || self.check[i] != self.check[start]
            {
                runs.push((start, i));
                start = i;
            }
        }
        runs
    }
}

/// stimupy's plaid of two gratings' values: the second intensity where they sum to both
/// intensities (one grating at each), the first elsewhere.
fn stimupy_plaid(a: f64, b: f64, (first, second): (f64, f64)) -> f64 {
    if a + b == first + second {
        second
    } else {
        first
    }
}

/// The smallest and largest of `values`.
fn min_max(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

/// NumPy's `linspace(start, stop, n)`: start + i·step, the last one exactly `stop`.
fn numpy_linspace(start: f64, stop: f64, n: usize) -> Vec<f64> {
    let step = if n > 1 {
        (stop - start) / (n - 1) as f64
    } else {
        0.0
    };
    let mut axis: Vec<f64> = (0..n).map(|i| i as f64 * step + start).collect();
    if let (true, Some(last)) = (n > 1, axis.last_mut()) {
        *last = stop;
    }
    axis
}

/// The most checks an SVG document is made for (half of them become rectangles).
const MAX_SVG_CHECKS: usize = 500_000;

/// The x (or y) coordinates in degrees that stimupy gives the `n` pixels of an axis `n / ppd`
/// degrees long with its default origin ("mean"): `numpy.linspace(−L/2, L/2, n)`, computed as
/// NumPy does (start + i·step, the last one exactly L/2). The ends lie on the frame's edges, so
/// the spacing is L/(n − 1), a little more than a pixel's 1/ppd.
fn stimupy_axis(n: usize, ppd: f64) -> Vec<f64> {
    let length = n as f64 / ppd;
    numpy_linspace(-length / 2.0, length / 2.0, n)
}

/// NumPy's `round(v, 8)`: scaled by 10⁸, rounded half to even, scaled back.
fn round8(v: f64) -> f64 {
    (v * 1e8).round_ties_even() / 1e8
}

/// A plain disc centred in the frame, with stimupy's pixel rule
/// (`stimupy.components.shapes.disc`, origin "mean"): pixel (col, row) lies at
/// x = `linspace(−W/2, W/2, w)[col]`, y = `linspace(−H/2, H/2, h)[row]` degrees (W = w/ppd,
/// H = h/ppd, so the outermost pixel centres sit on the frame's edges), and belongs to the disc
/// when its distance from the origin, rounded to 8 decimals, is at most the radius
/// (`distance <= radius`). The image and mask match stimupy's pixel for pixel.
///
/// ```
/// use shadelab::stimulus::{disc, DiscParams, Pixels};
/// use shadelab::Geometry;
///
/// // 6 x 4 pixels at 2 ppd: x = -1.5, -0.9, -0.3, 0.3, 0.9, 1.5 and y = ±1, ±1/3 degrees, so
/// // a disc of radius 1° holds the 8 pixels of the two middle rows but their end columns.
/// let p = DiscParams { radius: 1.0, ..Default::default() };
/// let g = Geometry { width: 6, height: 4, ppd: 2.0 };
/// let Pixels::Gray(image) = disc(&p, &g).unwrap().pixels else { panic!() };
/// assert_eq!(image.data().iter().filter(|&&v| v == 1.0).count(), 8);
/// assert_eq!((*image.get(1, 1), *image.get(2, 0)), (1.0, 0.0));
/// ```
pub fn disc(p: &DiscParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let (inside, outside) = (p.intensity_disc, p.intensity_background);
    let xs2: Vec<f64> = stimupy_axis(g.width, g.ppd).iter().map(|x| x * x).collect();
    let ys2: Vec<f64> = stimupy_axis(g.height, g.ppd)
        .iter()
        .map(|y| y * y)
        .collect();
    let radius = p.radius;
    let (image, labels) = paint_rows(g, outside, |y, row, lrow| {
        let y2 = ys2[y];
        for ((v, l), x2) in row.iter_mut().zip(lrow.iter_mut()).zip(&xs2) {
            if round8((x2 + y2).sqrt()) <= radius {
                *v = inside;
                *l = 1;
            }
        }
    })?;
    // The SVG's edge passes where the raster's rule puts it: stimupy's axes are stretched by
    // (n − 1)/n against pixel units, so the circle is an ellipse when width ≠ height.
    let (cx, cy) = g.svg_xy(0.0, 0.0);
    let semi = |n: usize| g.px(radius) * (n.max(2) - 1) as f64 / n.max(2) as f64;
    let (rx, ry) = (semi(g.width), semi(g.height));
    let shape_svg = if rx == ry {
        document(g, "disc", outside).add(
            Circle::new()
                .set("cx", num(cx))
                .set("cy", num(cy))
                .set("r", num(rx))
                .set("fill", gray(inside)),
        )
    } else {
        document(g, "disc", outside).add(
            Ellipse::new()
                .set("cx", num(cx))
                .set("cy", num(cy))
                .set("rx", num(rx))
                .set("ry", num(ry))
                .set("fill", gray(inside)),
        )
    };
    let mut notes = Map::new();
    notes.insert(
        "pixel_rule".into(),
        json!("stimupy's: pixel centres at linspace(-size/2, size/2, n) degrees on each axis; inside when round(distance, 8) <= radius"),
    );
    Ok(Output {
        pixels: Pixels::Gray(image),
        targets: Some(Targets {
            labels,
            names: vec!["disc".into()],
        }),
        surface: None,
        svg: Some(shape_svg.to_string()),
        notes,
    })
}

/// The plain checkerboard and disc.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![
        Typed::boxed(
            "checkerboard",
            "a plain checkerboard (as stimupy's), first intensity at the top left; targets: none, or the checks named by targets (as stimupy's target_indices)",
            (8.0, 8.0),
            32.0,
            |p, g, _| checkerboard(p, g),
        ),
        Typed::boxed(
            "disc",
            "a plain disc centred in the frame, with stimupy's pixel rule (centres at linspace(-size/2, size/2, n) deg; inside when distance <= radius)",
            (8.0, 8.0),
            32.0,
            |p, g, _| disc(p, g),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use crate::visual_size::Geometry;

    fn generate(name: &str, pairs: &[&str], w: usize, h: usize, ppd: f64) -> Output {
        let s = crate::find(name).unwrap();
        let info = s.info();
        let given = Params::parse_pairs(pairs).unwrap();
        s.generate(&crate::Request {
            params: Params::resolve(&info.params, &given).unwrap(),
            geometry: Geometry {
                width: w,
                height: h,
                ppd,
            },
            seed: 0,
        })
        .unwrap()
    }

    #[test]
    fn checks_are_check_times_ppd_pixels_wide() {
        let out = generate("checkerboard", &["check=0.5"], 300, 200, 20.0);
        let Pixels::Gray(img) = out.pixels else {
            panic!()
        };
        // 0.5° × 20 ppd = 10 px: values change every 10 columns and every 10 rows.
        for c in 0..300 {
            assert_eq!(*img.get(c, 0), if (c / 10) % 2 == 0 { 0.0 } else { 1.0 });
        }
        for r in 0..200 {
            assert_eq!(*img.get(5, r), if (r / 10) % 2 == 0 { 0.0 } else { 1.0 });
        }
    }

    #[test]
    fn disc_area_is_that_of_stimupys_stretched_circle() {
        let out = generate("disc", &["radius=2"], 200, 160, 20.0);
        let Pixels::Gray(img) = out.pixels else {
            panic!()
        };
        let area = img.data().iter().filter(|&&v| v == 1.0).count() as f64;
        // stimupy's axes put the end pixels on the frame's edges: 40 px of radius become
        // 40·(n − 1)/n pixels along each axis.
        let expect = std::f64::consts::PI * (40.0 * 199.0 / 200.0) * (40.0 * 159.0 / 160.0);
        assert!((area - expect).abs() / expect < 0.005, "{area} vs {expect}");
        // Symmetric about both axes of the frame.
        assert_eq!(img, img.rotated_180());
    }
}
