//! `checkerboard` and `disc`: the plain building blocks of lightness experiments, with the
//! same parameters as stimupy's (`checkerboard`: check size and two intensities; `disc`: radius,
//! disc and background intensities), so that shadelab can stand in for it and be compared with
//! it.
//!
//! A pixel belongs to the check or disc that contains its centre (no anti-aliasing), as in
//! stimupy; the SVG versions have their edges at the same places.

use super::frame::Frame;
use super::svg::{document, gray, num};
use super::{Output, Pixels, Stimulus, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::parallel::prelude::*;
use crate::params::{stimulus_params, ParamSet};
use crate::visual_size::Geometry;
use serde_json::{json, Map};
use svg::node::element::{Circle, Rectangle};

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

/// A plain checkerboard (as stimupy's), starting with the first intensity at the top left.
///
/// ```
/// use shadelab::stimulus::{checkerboard, CheckerboardParams, Pixels};
/// use shadelab::visual_size::Geometry;
///
/// // 0.5° checks at 4 ppd are 2 pixels wide: columns 0-1 dark, 2-3 light.
/// let p = CheckerboardParams { check: 0.5, ..Default::default() };
/// let g = Geometry { width: 6, height: 4, ppd: 4.0 };
/// let Pixels::Gray(image) = checkerboard(&p, &g).unwrap().pixels else { panic!() };
/// let top: Vec<f64> = (0..6).map(|c| *image.get(c, 0)).collect();
/// assert_eq!(top, [0.0, 0.0, 1.0, 1.0, 0.0, 0.0]);
/// assert_eq!(*image.get(0, 2), 1.0);
/// ```
pub fn checkerboard(p: &CheckerboardParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let frame = Frame::new(g);
    let check = frame.px(p.check);
    if check < 1.0 {
        return Err(Error::invalid(format!(
            "checkerboard: check {}° is under one pixel at {} ppd",
            p.check, frame.ppd
        )));
    }
    let (first, second) = (p.intensity_first, p.intensity_second);
    let index = |i: usize| ((i as f64 + 0.5) / check).floor() as usize;
    let col_parity: Vec<usize> = (0..frame.w).map(|c| index(c) % 2).collect();
    let mut data = vec![0.0; frame.w * frame.h];
    data.par_chunks_mut(frame.w * ROWS_PER_TASK)
        .enumerate()
        .for_each(|(task, chunk)| {
            for (k, row) in chunk.chunks_mut(frame.w).enumerate() {
                let r = index(task * ROWS_PER_TASK + k) % 2;
                for (v, &c) in row.iter_mut().zip(&col_parity) {
                    *v = if (r + c) % 2 == 0 { first } else { second };
                }
            }
        });
    let image = Grid::from_vec(frame.w, frame.h, data)?;
    let (nx, ny) = (
        (frame.w as f64 / check).ceil() as usize,
        (frame.h as f64 / check).ceil() as usize,
    );
    let mut notes = Map::new();
    notes.insert("checks".into(), json!([nx, ny]));
    let svg = if nx * ny > MAX_SVG_CHECKS {
        notes.insert(
            "svg_omitted".into(),
            json!(format!(
                "{} checks are too many for an SVG document (limit {MAX_SVG_CHECKS})",
                nx * ny
            )),
        );
        None
    } else {
        Some(checks_svg(&frame, check, nx, ny, first, second))
    };
    Ok(Output {
        pixels: Pixels::Gray(image),
        targets: None,
        surface: None,
        svg,
        notes,
    })
}

/// The most checks an SVG document is made for (half of them become rectangles).
const MAX_SVG_CHECKS: usize = 500_000;

fn checks_svg(frame: &Frame, check: f64, nx: usize, ny: usize, first: f64, second: f64) -> String {
    let mut doc = document(frame, "checkerboard", first);
    for j in 0..ny {
        for i in 0..nx {
            if (i + j) % 2 == 1 {
                let (x0, y0) = (i as f64 * check, j as f64 * check);
                let (x1, y1) = (
                    ((i + 1) as f64 * check).min(frame.w as f64),
                    ((j + 1) as f64 * check).min(frame.h as f64),
                );
                doc = doc.add(
                    Rectangle::new()
                        .set("x", num(x0))
                        .set("y", num(y0))
                        .set("width", num(x1 - x0))
                        .set("height", num(y1 - y0))
                        .set("fill", gray(second)),
                );
            }
        }
    }
    doc.to_string()
}

/// A plain disc centred in the frame (as stimupy's).
pub fn disc(p: &DiscParams, g: &Geometry) -> Result<Output> {
    p.validate()?;
    let frame = Frame::new(g);
    let radius = frame.px(p.radius);
    let (inside, outside) = (p.intensity_disc, p.intensity_background);
    let r2 = radius * radius;
    let mut data = vec![outside; frame.w * frame.h];
    let mut labels = vec![0u16; frame.w * frame.h];
    data.par_chunks_mut(frame.w * ROWS_PER_TASK)
        .zip(labels.par_chunks_mut(frame.w * ROWS_PER_TASK))
        .enumerate()
        .for_each(|(task, (chunk, lab))| {
            for (k, (row, lrow)) in chunk
                .chunks_mut(frame.w)
                .zip(lab.chunks_mut(frame.w))
                .enumerate()
            {
                let y = frame.y(task * ROWS_PER_TASK + k);
                let y2 = y * y;
                if y2 >= r2 {
                    continue;
                }
                // The disc's chord on this row, found once; the loop only fills it.
                let half = (r2 - y2).sqrt();
                for col in frame.cols(-half, half) {
                    let x = frame.x(col);
                    if x * x + y2 < r2 {
                        row[col] = inside;
                        lrow[col] = 1;
                    }
                }
            }
        });
    let (cx, cy) = frame.svg_xy(0.0, 0.0);
    let doc = document(&frame, "disc", outside).add(
        Circle::new()
            .set("cx", num(cx))
            .set("cy", num(cy))
            .set("r", num(radius))
            .set("fill", gray(inside)),
    );
    Ok(Output {
        pixels: Pixels::Gray(Grid::from_vec(frame.w, frame.h, data)?),
        targets: Some(Targets {
            labels: Grid::from_vec(frame.w, frame.h, labels)?,
            names: vec!["disc".into()],
        }),
        surface: None,
        svg: Some(doc.to_string()),
        notes: Map::new(),
    })
}

/// The plain checkerboard and disc.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![
        Typed::boxed(
            "checkerboard",
            "a plain checkerboard (as stimupy's), starting with the first intensity at the top left",
            (8.0, 8.0),
            32.0,
            |p, g, _| checkerboard(p, g),
        ),
        Typed::boxed(
            "disc",
            "a plain disc centred in the frame (as stimupy's)",
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
        let s = crate::stimulus::find(name).unwrap();
        let info = s.info();
        let given = Params::parse_pairs(pairs).unwrap();
        s.generate(&crate::stimulus::Request {
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
    fn disc_area_is_pi_r_squared_in_pixels() {
        let out = generate("disc", &["radius=2"], 200, 160, 20.0);
        let Pixels::Gray(img) = out.pixels else {
            panic!()
        };
        let area = img.data().iter().filter(|&&v| v == 1.0).count() as f64;
        let expect = std::f64::consts::PI * 40.0 * 40.0;
        assert!((area - expect).abs() / expect < 0.005, "{area} vs {expect}");
        // Symmetric about both axes of the frame.
        assert_eq!(img, img.rotated_180());
    }
}
