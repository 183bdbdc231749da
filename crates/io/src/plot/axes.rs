//! Axes: tick placement and labels, and the one way every figure draws its axes.

#[cfg(feature = "plots")]
use super::FAMILY;
#[cfg(feature = "plots")]
use crate::error::{Error, Result};
#[cfg(feature = "plots")]
use plotters::prelude::*;

/// How an axis's ticks are placed and written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ticks {
    /// Round steps (1, 2 or 5 times a power of ten), with as many decimals as the step needs.
    Auto,
    /// Whole numbers only (counts: cycles, iterations), written without decimals.
    Integer,
    /// Angles in degrees: steps of 15, 30, 45 or 90 on wide axes, written without decimals.
    Degrees,
}

#[cfg(feature = "plots")]
/// One axis of [`axes`]: from, to, its ticks and its label.
pub(super) type AxisSpec<'s> = (f64, f64, Ticks, &'s str);

#[cfg(feature = "plots")]
/// The one way every figure draws its axes: `x` and `y` with their ticks, tick labels and
/// labels, and with `grid` light grey lines at the ticks. `what` names the figure in errors.
pub(super) fn axes<'a, DB: DrawingBackend>(
    builder: &mut ChartBuilder<'a, '_, DB>,
    what: &str,
    x: AxisSpec<'_>,
    y: AxisSpec<'_>,
    grid: bool,
) -> Result<ChartContext<'a, DB, Cartesian2d<TickAxis, TickAxis>>> {
    let fail =
        |e: &dyn std::fmt::Display| Error::Compute(format!("cannot draw the figure '{what}': {e}"));
    let (xt, xd) = ticks(x.0, x.1, x.2);
    let (yt, yd) = ticks(y.0, y.1, y.2);
    let mut chart = builder
        .build_cartesian_2d(TickAxis::new(x.0, x.1, xt), TickAxis::new(y.0, y.1, yt))
        .map_err(|e| fail(&e))?;
    let (fx, fy) = (
        move |v: &f64| tick_text(*v, xd),
        move |v: &f64| tick_text(*v, yd),
    );
    let mut mesh = chart.configure_mesh();
    mesh.x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .x_desc(x.3)
        .y_desc(y.3)
        .label_style((FAMILY, 15))
        .axis_desc_style((FAMILY, 17))
        .light_line_style(TRANSPARENT)
        .bold_line_style(RGBColor(220, 220, 220));
    if !grid {
        mesh.disable_mesh();
    }
    mesh.draw().map_err(|e| fail(&e))?;
    Ok(chart)
}

#[cfg(feature = "plots")]
/// A linear axis from `lo` to `hi` whose ticks (and grid lines) are exactly `ticks`.
#[derive(Clone)]
pub(super) struct TickAxis {
    range: plotters::coord::types::RangedCoordf64,
    ticks: Vec<f64>,
}

#[cfg(feature = "plots")]
impl TickAxis {
    pub(super) fn new(lo: f64, hi: f64, ticks: Vec<f64>) -> TickAxis {
        TickAxis {
            range: (lo..hi).into(),
            ticks,
        }
    }
}

#[cfg(feature = "plots")]
impl plotters::coord::ranged1d::Ranged for TickAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.range.map(value, limit)
    }
    fn key_points<Hint: plotters::coord::ranged1d::KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.max_num_points() == 0 {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }
    fn range(&self) -> std::ops::Range<f64> {
        self.range.range()
    }
}

#[cfg(feature = "plots")]
/// Tick positions from `lo` to `hi` and the decimals their labels need.
pub(super) fn ticks(lo: f64, hi: f64, kind: Ticks) -> (Vec<f64>, usize) {
    let span = (hi - lo).abs().max(1e-12);
    let round_step = |target: f64| {
        let raw = span / target;
        let mag = 10f64.powf(raw.log10().floor());
        [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * mag)
            .find(|s| *s >= raw * 0.999)
            .unwrap_or(10.0 * mag)
    };
    let (step, decimals) = match kind {
        Ticks::Degrees if span >= 60.0 => {
            let step = [15.0, 30.0, 45.0, 90.0, 180.0]
                .into_iter()
                .find(|s| span / s <= 12.0)
                .unwrap_or(180.0);
            (step, 0)
        }
        Ticks::Integer => (round_step(8.0).max(1.0).round(), 0),
        _ => {
            let step = round_step(8.0);
            (step, (-step.log10().floor()).clamp(0.0, 8.0) as usize)
        }
    };
    let first = (lo.min(hi) / step - 1e-9).ceil() as i64;
    let last = (lo.max(hi) / step + 1e-9).floor() as i64;
    let ticks = (first..=last).map(|k| k as f64 * step).collect();
    (ticks, decimals)
}

#[cfg(feature = "plots")]
/// A tick label with `decimals` decimals, never "-0".
pub(super) fn tick_text(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_string()
    } else {
        text
    }
}

/// The range of `xs` for an axis: smallest to largest, or one unit either side of a single
/// value (or of the first, when they are all equal).
///
/// ```
/// use shadelab_io::plot::span;
/// assert_eq!(span(&[30.0, 0.0, 90.0]), (0.0, 90.0));
/// assert_eq!(span(&[5.0]), (4.0, 6.0));
/// ```
pub fn span(xs: &[f64]) -> (f64, f64) {
    let lo = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, lo + 1.0)
    }
}

/// The step of `tilts` when they are equally spaced, increasing, and cover 360° exactly once.
pub fn circle_step(tilts: &[f64]) -> Option<f64> {
    if tilts.len() < 2 {
        return None;
    }
    let step = 360.0 / tilts.len() as f64;
    let ok = tilts
        .iter()
        .enumerate()
        .all(|(i, &t)| (t - (tilts[0] + i as f64 * step)).abs() < 1e-6);
    ok.then_some(step)
}
