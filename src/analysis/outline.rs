//! Where a recovered shape bends: curvature concentration along a token.
//!
//! Inside a sinusoidal outline the boundary-strips shading reads as smooth corrugations, which
//! bend everywhere a little; inside a sawtooth outline as a folded roof, flat facets that bend
//! only at the folds. The measure: take the recovered f (the stereographic x-component of the
//! normal) averaged down each column of the token, its change from column to column |Δf̄| (the
//! curvature across the strip's length), and the share of the total change carried by the
//! `top_fraction` of columns that change most. A sinusoid gives about 0.31 for the top 20%
//! (2·sin 18° / 2); facets with sharp folds approach 1.

use super::interpretation::{Interpreter, Lighting, Scene};
use super::picture::{Domain, Picture};
use crate::boundary::Boundary;
use crate::error::Result;
use crate::grid::Image;
use crate::solver::SolveOptions;
use serde::Serialize;

/// The share of columns whose change counts as "where the bending is".
pub const TOP_FRACTION: f64 = 0.2;

/// One token's recovered shape inside its outline.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OutlineReading {
    /// The token's name.
    pub token: String,
    /// Curvature concentration of the whole token's recovered f.
    pub concentration: f64,
    /// Curvature concentration over the token's core only (away from the boundary data).
    pub core_concentration: f64,
}

/// Solves each token of `picture` on its own pixels (the domain is the tokens) with
/// `boundary` taken from its outline, under the light of `tilt_deg`, and measures where the
/// recovered shape bends.
pub fn outline_shapes(
    picture: &Picture,
    boundary: &Boundary,
    tilt_deg: f64,
    lighting: &Lighting,
    options: &SolveOptions,
) -> Result<Vec<OutlineReading>> {
    let domain = picture.domain(Domain::Tokens);
    let scene = Scene {
        image: &picture.image,
        domain: &domain,
        boundary,
        tokens: &picture.tokens,
    };
    let mut interpreter = Interpreter::new(&scene, options)?.keep_depth(true);
    let reading = interpreter.interpret(&scene, tilt_deg, lighting)?;
    let f = reading
        .f
        .unwrap_or_else(|| Image::new(picture.image.width(), picture.image.height(), 0.0));
    Ok(picture
        .tokens
        .iter()
        .map(|t| OutlineReading {
            token: t.name.clone(),
            concentration: curvature_concentration(&f, t.pixels(), TOP_FRACTION),
            core_concentration: curvature_concentration(&f, t.core(), TOP_FRACTION),
        })
        .collect())
}

/// The share of the total column-to-column change of the column-mean f over `pixels` that the
/// `top_fraction` (0..1) of steps with the largest change carry; 0 when f does not change.
pub fn curvature_concentration(f: &Image, pixels: &[usize], top_fraction: f64) -> f64 {
    let w = f.width();
    let mut sums: Vec<(f64, usize)> = vec![(0.0, 0); w];
    for &p in pixels {
        let s = &mut sums[p % w];
        s.0 += f.data()[p];
        s.1 += 1;
    }
    let means: Vec<f64> = sums
        .iter()
        .filter(|s| s.1 > 0)
        .map(|s| s.0 / s.1 as f64)
        .collect();
    let mut steps: Vec<f64> = means.windows(2).map(|m| (m[1] - m[0]).abs()).collect();
    let total: f64 = steps.iter().sum();
    if steps.is_empty() || total <= 0.0 {
        return 0.0;
    }
    steps.sort_by(|a, b| b.total_cmp(a));
    let keep = ((top_fraction.clamp(0.0, 1.0) * steps.len() as f64).round() as usize).max(1);
    steps[..keep].iter().sum::<f64>() / total
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::convexity::tokens_from_labels;
    use crate::grid::Grid;

    #[test]
    fn a_sinusoid_spreads_its_bending_and_a_zigzag_concentrates_it() {
        let (w, h) = (200, 12);
        let labels = Grid::from_fn(w, h, |_, r| u16::from((2..10).contains(&r)));
        let token = &tokens_from_labels(&labels, &[]).unwrap()[0];
        let period = 40.0;
        let sine = Grid::from_fn(w, h, |c, _| {
            (std::f64::consts::TAU * c as f64 / period).sin()
        });
        // Facets: f constant ±1 on each half period, so all change happens at the folds.
        let facets = Grid::from_fn(w, h, |c, _| {
            if (c as f64 / period).fract() < 0.5 {
                1.0
            } else {
                -1.0
            }
        });
        let s = curvature_concentration(&sine, token.pixels(), 0.2);
        let f = curvature_concentration(&facets, token.pixels(), 0.2);
        assert!((s - 0.31).abs() < 0.03, "{s}");
        assert!(f > 0.99, "{f}");
        assert_eq!(
            curvature_concentration(&Grid::new(w, h, 0.3), token.pixels(), 0.2),
            0.0
        );
    }
}
