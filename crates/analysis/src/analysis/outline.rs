//! Where a recovered shape bends, and the shape an outline implies.
//!
//! **Bend concentration.** Inside a sinusoidal outline the boundary-strips shading reads as
//! smooth corrugations, which bend everywhere a little; inside a sawtooth outline as a folded
//! roof, flat facets that bend only at the folds. The measure: take the recovered f (the
//! stereographic x-component of the normal) averaged down each column of the token, its change
//! from column to column |Δf̄| (the curvature across the strip's length), and the share of the
//! total change carried by the `top_fraction` of columns that change most. A sinusoid gives
//! about 0.31 for the top 20% (2·sin 18° / 2); facets with sharp folds approach 1.
//!
//! **The outline's shape** (Knill & Kersten 1991). A strip cut out of a corrugated sheet seen
//! from above shows the sheet's cross-section along its cut: the outline's height at each
//! column *is* the surface's profile z(x) (outline up = toward the viewer; the other reading,
//! every depth negated, explains the picture exactly as well under the mirrored light). The
//! profile is read from the token's pixels: its centre line, midway between its top and bottom
//! edge in each column, to half a pixel. That staircase is fitted by a crease-preserving trend
//! ([`fit_profile`]): least squares with a Charbonnier penalty on the profile's second
//! difference, quadratic below a curvature ε and linear above, so a smooth wave stays smooth
//! and a zigzag keeps its corners. Its slope p = dz/dx (times a depth scale, 1 = the outline's
//! own swing) gives the normal n = (−p, 0, 1)/√(1 + p²) of every pixel in that column.
//!
//! **Shading and paint.** Under a light s (given, or fitted: see [`fit_shading`]) that shape
//! predicts the shading Î = a + ρ·max(0, n·s); the albedo ρ ≥ 0 and the offset a (an ambient
//! level plus whatever the picture adds uniformly) are the least-squares fit over the token.
//! The share of the token's luminance variance the shape explains is 1 − Σ(I − Î)²/Σ(I − Ī)²,
//! and the remainder I − Î is what the shape leaves to paint (reflectance).

use super::convexity::Token;
use super::interpretation::{Interpreter, Lighting, Scene};
use super::picture::{Domain, TokenPicture};
use crate::boundary::{is_rim, Boundary, BoundaryConditions, Role};
use crate::error::{Error, Result};
use crate::gradient_space::{fg_from_pq, normal_from_pq, Normal};
use crate::grid::{Grid, Image, Mask};
use crate::light::{FrontLight, Light};
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
    picture: &TokenPicture,
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
    if steps.is_empty() || total <= FLAT_F * steps.len() as f64 {
        return 0.0;
    }
    steps.sort_by(|a, b| b.total_cmp(a));
    let keep = ((top_fraction.clamp(0.0, 1.0) * steps.len() as f64).round() as usize).max(1);
    steps[..keep].iter().sum::<f64>() / total
}

/// How the outline's profile is read (see the module's documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfileFit {
    /// Weight μ (> 0) of the curvature penalty against the fit to the centre line (pixels²).
    pub curvature_weight: f64,
    /// The curvature ε (> 0, per pixel) where the penalty turns from quadratic to linear:
    /// sharper bends are kept as corners.
    pub curvature_epsilon: f64,
    /// Depth per pixel of outline height (> 0): 1 reads the cut's profile at its own scale.
    pub depth_scale: f64,
}

impl Default for ProfileFit {
    /// μ = 10, ε = 0.1 per pixel, depth scale 1.
    fn default() -> Self {
        ProfileFit {
            curvature_weight: 10.0,
            curvature_epsilon: 0.1,
            depth_scale: 1.0,
        }
    }
}

impl ProfileFit {
    /// Checks every value, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("curvature weight", self.curvature_weight),
            ("curvature epsilon", self.curvature_epsilon),
            ("depth scale", self.depth_scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(format!(
                    "profile {name} {v} must be a positive number"
                )));
            }
        }
        Ok(())
    }
}

/// Reweightings of the profile fit: each solves a banded system of the profile's length.
const PROFILE_REWEIGHTS: usize = 50;

/// The profile an outline implies: the surface's height and slope in each column of a token.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Profile {
    /// The token's first column.
    pub first_column: usize,
    /// The centre line's height in each column from the first, pixels, y up (half-pixel steps).
    pub centre: Vec<f64>,
    /// The fitted surface height z in each column, in depth units (pixels × depth scale).
    pub height: Vec<f64>,
    /// The fitted slope p = dz/dx in each column.
    pub slope: Vec<f64>,
}

impl Profile {
    /// The slope in image column `col` (that of the nearest profile column outside it).
    pub fn slope_at(&self, col: usize) -> f64 {
        let k = col
            .saturating_sub(self.first_column)
            .min(self.slope.len().saturating_sub(1));
        self.slope.get(k).copied().unwrap_or(0.0)
    }

    /// The unit normal in image column `col`: (−p, 0, 1)/√(1 + p²) (a surface rising to the
    /// right faces left; in gradient space, p_gs = n_x/n_z = −dz/dx).
    pub fn normal_at(&self, col: usize) -> Normal {
        normal_from_pq(-self.slope_at(col), 0.0)
    }

    /// The stereographic (f, g) of the normal in image column `col`.
    pub fn fg_at(&self, col: usize) -> (f64, f64) {
        fg_from_pq(-self.slope_at(col), 0.0)
    }

    /// The bend concentration of the profile itself: [`curvature_concentration`] of its f
    /// along its columns (what a reconstruction that keeps the outline's shape gives).
    pub fn bend_concentration(&self) -> f64 {
        let n = self.slope.len();
        let f = Grid::from_fn(n, 1, |c, _| self.fg_at(self.first_column + c).0);
        let columns: Vec<usize> = (0..n).collect();
        curvature_concentration(&f, &columns, TOP_FRACTION)
    }

    /// The height range max z − min z.
    pub fn relief(&self) -> f64 {
        let (lo, hi) = crate::plot::span(&self.height);
        hi - lo
    }
}

/// The profile of `token` in a picture `width` pixels wide: its centre line in each column,
/// fitted by the crease-preserving trend [`fit_profile`]. Columns the token skips take the
/// centre of their neighbours, linearly. Fails for a token under 3 columns wide.
pub fn outline_profile(token: &Token, width: usize, fit: &ProfileFit) -> Result<Profile> {
    fit.validate()?;
    let mut span: Vec<Option<(usize, usize)>> = vec![None; width];
    for &p in token.pixels() {
        let (c, r) = (p % width, p / width);
        let s = &mut span[c];
        *s = Some(s.map_or((r, r), |(a, b)| (a.min(r), b.max(r))));
    }
    let first = span.iter().position(Option::is_some);
    let last = span.iter().rposition(Option::is_some);
    let (Some(first), Some(last)) = (first, last) else {
        return Err(Error::invalid(format!(
            "target '{}' has no pixels",
            token.name
        )));
    };
    if last - first + 1 < 3 {
        return Err(Error::invalid(format!(
            "target '{}' spans {} column(s): an outline profile needs at least 3",
            token.name,
            last - first + 1
        )));
    }
    // Rows grow downwards: the centre's height, y up, is minus the mean of the edge rows.
    let known: Vec<(usize, f64)> = (first..=last)
        .filter_map(|c| span[c].map(|(a, b)| (c, -0.5 * (a + b) as f64)))
        .collect();
    let mut centre = Vec::with_capacity(last - first + 1);
    for pair in known.windows(2) {
        let ((c0, y0), (c1, y1)) = (pair[0], pair[1]);
        for c in c0..c1 {
            centre.push(y0 + (y1 - y0) * (c - c0) as f64 / (c1 - c0) as f64);
        }
    }
    centre.push(known[known.len() - 1].1);
    let fitted = fit_profile(&centre, fit.curvature_weight, fit.curvature_epsilon)?;
    let height: Vec<f64> = fitted.iter().map(|z| z * fit.depth_scale).collect();
    let n = height.len();
    let slope = (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            (height[b] - height[a]) / (b - a) as f64
        })
        .collect();
    Ok(Profile {
        first_column: first,
        centre,
        height,
        slope,
    })
}

/// The crease-preserving trend of `values` (at least 3): the z minimising
/// Σ (z_i − v_i)² + μ Σ φ(z_{i−1} − 2 z_i + z_{i+1}), with the Charbonnier penalty
/// φ(d) = 2ε(√(d² + ε²) − ε) (≈ d² below ε, 2ε·|d| above), by reweighted least squares (each
/// step a banded solve).
///
/// ```
/// use shadelab_analysis::analysis::outline::fit_profile;
/// // A zigzag keeps its corner: the slope turns from +1 to −1 at i = 10, and most of that
/// // turn (a second difference of 2) stays at the corner pixel, where a quadratic penalty
/// // would spread it; a straight line is kept exactly.
/// let zigzag: Vec<f64> = (0..21).map(|i| -((i as f64) - 10.0).abs()).collect();
/// let z = fit_profile(&zigzag, 10.0, 0.1).unwrap();
/// assert!((z[10] - z[9]) - (z[11] - z[10]) > 1.4, "{:?}", &z[8..13]);
/// let line: Vec<f64> = (0..9).map(|i| 0.5 * i as f64).collect();
/// let z = fit_profile(&line, 10.0, 0.1).unwrap();
/// assert!(z.iter().zip(&line).all(|(a, b)| (a - b).abs() < 1e-9));
/// ```
pub fn fit_profile(values: &[f64], mu: f64, epsilon: f64) -> Result<Vec<f64>> {
    let n = values.len();
    if n < 3 {
        return Err(Error::invalid("a profile needs at least 3 values"));
    }
    let mut z = values.to_vec();
    for _ in 0..PROFILE_REWEIGHTS {
        let weights: Vec<f64> = (0..n - 2)
            .map(|k| {
                let d = z[k] - 2.0 * z[k + 1] + z[k + 2];
                mu * epsilon / (d * d + epsilon * epsilon).sqrt()
            })
            .collect();
        // M = I + Dᵀ diag(weights) D, pentadiagonal: band[i][j] = M(i, i + j), j = 0..=2.
        let mut band = vec![[1.0, 0.0, 0.0]; n];
        for (k, &w) in weights.iter().enumerate() {
            let stencil = [1.0, -2.0, 1.0];
            for a in 0..3 {
                for b in a..3 {
                    band[k + a][b - a] += w * stencil[a] * stencil[b];
                }
            }
        }
        z = banded_cholesky_solve(&band, values)?;
    }
    Ok(z)
}

/// Solves M z = v for a symmetric positive definite pentadiagonal M given by its upper band
/// (`band[i][j]` = M(i, i + j)).
fn banded_cholesky_solve(band: &[[f64; 3]], v: &[f64]) -> Result<Vec<f64>> {
    let n = band.len();
    let m = |i: usize, j: usize| -> f64 {
        let (a, b) = if i <= j { (i, j) } else { (j, i) };
        if b - a > 2 {
            0.0
        } else {
            band[a][b - a]
        }
    };
    // l[i][k] = L(i, i − 2 + k), k = 0..=2 (k = 2 the diagonal).
    let mut l = vec![[0.0f64; 3]; n];
    for i in 0..n {
        for j in i.saturating_sub(2)..=i {
            let mut sum = m(i, j);
            for k in i.saturating_sub(2)..j {
                if k + 2 >= j {
                    sum -= l[i][k + 2 - i] * l[j][k + 2 - j];
                }
            }
            if i == j {
                if sum.is_nan() || sum <= 0.0 {
                    return Err(Error::Compute(
                        "the profile fit's system is not positive definite".into(),
                    ));
                }
                l[i][2] = sum.sqrt();
            } else {
                l[i][j + 2 - i] = sum / l[j][2];
            }
        }
    }
    let mut y = vec![0.0; n];
    for i in 0..n {
        let mut s = v[i];
        for j in i.saturating_sub(2)..i {
            s -= l[i][j + 2 - i] * y[j];
        }
        y[i] = s / l[i][2];
    }
    let mut z = vec![0.0; n];
    for i in (0..n).rev() {
        let mut s = y[i];
        for j in i + 1..(i + 3).min(n) {
            s -= l[j][i + 2 - j] * z[j];
        }
        z[i] = s / l[i][2];
    }
    Ok(z)
}

/// The boundary conditions the outline gives `token`: its rim pixels on the cut (every rim
/// pixel but those in its first and last column, where the strip simply ends) hold the
/// profile's normal of their column; its other pixels are unknown; the rest is outside.
pub fn outline_conditions(
    token: &Token,
    profile: &Profile,
    width: usize,
    height: usize,
) -> BoundaryConditions {
    let mut mask = Mask::new(width, height, false);
    for &p in token.pixels() {
        mask.data_mut()[p] = true;
    }
    let last = profile.first_column + profile.slope.len() - 1;
    let mut roles = mask.map(|&m| if m { Role::Unknown } else { Role::Outside });
    let mut fixed = Vec::new();
    let mut pixels = token.pixels().to_vec();
    pixels.sort_unstable();
    for p in pixels {
        let (c, r) = (p % width, p / width);
        if c != profile.first_column && c != last && is_rim(&mask, c, r) {
            *roles.get_mut(c, r) = Role::Fixed;
            let (f, g) = profile.fg_at(c);
            fixed.push((p, [f, g]));
        }
    }
    BoundaryConditions::from_parts(roles, fixed)
}

/// The light a shape's shading was fitted under, and the fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ShadingFit {
    /// The light: the given one, or the fitted one.
    pub light: Light,
    /// Whether the light was fitted.
    pub light_fitted: bool,
    /// The fitted albedo ρ ≥ 0 (0 when the shape's shading is uniform: it explains nothing).
    pub albedo: f64,
    /// The fitted offset a (ambient level).
    pub offset: f64,
    /// The share of the luminance variance the shape explains, 1 − Σ(I − Î)²/Σ(I − Ī)²
    /// (1 for a target that does not vary, which the flat fit reproduces; 0 when the shape's
    /// shading does not vary or varies against the picture).
    pub explained: f64,
}

impl ShadingFit {
    /// The predicted luminance of a surface with normal `n`: a + ρ·max(0, n·s).
    pub fn predict(&self, n: &Normal) -> f64 {
        self.offset + self.albedo * n.dot(&self.light.direction()).max(0.0)
    }
}

/// Fits the shading of normals `normals` to the luminances `values` (one each): the albedo and
/// offset by least squares under `light`, or, when `light` is `None`, also the light. A
/// profile's normals all lie in the x–z plane, where a light's y-component changes nothing; so
/// the fitted light lies in that plane, from the left or the right at the slant that explains
/// most (searched every 0.5° over −89.5..89.5°, then refined to 0.001°; ties go to the least
/// slant). Fails for mismatched lengths.
pub fn fit_shading(
    values: &[f64],
    normals: &[Normal],
    light: Option<FrontLight>,
) -> Result<ShadingFit> {
    if values.len() != normals.len() || values.is_empty() {
        return Err(Error::invalid(format!(
            "{} luminances for {} normals: the shading fit needs one of each",
            values.len(),
            normals.len()
        )));
    }
    if let Some(l) = light {
        return Ok(fit_under(values, normals, l.light(), false));
    }
    // θ > 0: from the left (tilt 90°), θ < 0: from the right.
    let at = |theta: f64| -> Result<ShadingFit> {
        let (s, c) = crate::light::sin_cos_deg(theta);
        Ok(fit_under(
            values,
            normals,
            Light::from_vector(-s, 0.0, c)?,
            true,
        ))
    };
    let better = |a: &ShadingFit, a_theta: f64, b: &ShadingFit, b_theta: f64| {
        a.explained > b.explained + 1e-12
            || (a.explained >= b.explained - 1e-12 && a_theta.abs() < b_theta.abs())
    };
    let mut best_theta = 0.0;
    let mut best = at(0.0)?;
    let mut step: f64 = 0.5;
    let mut range = (-89.5, 89.5);
    for _ in 0..4 {
        let n = ((range.1 - range.0) / step).round() as i64;
        for k in 0..=n {
            let theta = (range.0 + k as f64 * step).clamp(-89.5, 89.5);
            let fit = at(theta)?;
            if better(&fit, theta, &best, best_theta) {
                best = fit;
                best_theta = theta;
            }
        }
        range = (best_theta - step, best_theta + step);
        step /= 10.0;
    }
    Ok(best)
}

/// A shape whose shading's variance (per pixel) is below this is taken as uniform: rounding
/// in a flat profile is not a shape.
const FLAT_SHADING: f64 = 1e-18;

/// A target whose values' variance (per pixel) is below this, a spread of 10⁻⁶ (a 16-bit
/// code is 1.5 × 10⁻⁵), does not vary.
const FLAT_VALUES: f64 = 1e-12;

/// A column-mean f whose total change is below this per column is taken as unchanging.
const FLAT_F: f64 = 1e-9;

/// The least-squares albedo and offset under `light`.
fn fit_under(values: &[f64], normals: &[Normal], light: Light, fitted: bool) -> ShadingFit {
    let s = light.direction();
    let n = values.len() as f64;
    let r: Vec<f64> = normals.iter().map(|m| m.dot(&s).max(0.0)).collect();
    let (mr, mv) = (r.iter().sum::<f64>() / n, values.iter().sum::<f64>() / n);
    let (mut srr, mut srv, mut svv) = (0.0, 0.0, 0.0);
    for (a, b) in r.iter().zip(values) {
        srr += (a - mr) * (a - mr);
        srv += (a - mr) * (b - mv);
        svv += (b - mv) * (b - mv);
    }
    // A shape whose shading does not vary, or varies against the picture, explains nothing.
    let albedo = if srr > FLAT_SHADING * n && srv > 0.0 {
        srv / srr
    } else {
        0.0
    };
    let offset = mv - albedo * mr;
    let residual: f64 = r
        .iter()
        .zip(values)
        .map(|(a, b)| {
            let e = b - offset - albedo * a;
            e * e
        })
        .sum();
    // A target that does not vary (to far below any stored code) is what the flat fit
    // reproduces: the rounding of its values in a float32 file or of their mean is no
    // variance to explain, and must not decide between 0 and 1.
    let explained = if svv > FLAT_VALUES * n {
        (1.0 - residual / svv).max(0.0)
    } else {
        1.0
    };
    ShadingFit {
        light,
        light_fitted: fitted,
        albedo,
        offset,
        explained,
    }
}

/// `values` laid on a token's pixels of a `width` × `height` grid, `outside` elsewhere.
pub fn on_token(
    token: &Token,
    width: usize,
    height: usize,
    outside: f64,
    value: impl Fn(usize) -> f64,
) -> Image {
    let mut image = Grid::new(width, height, outside);
    for &p in token.pixels() {
        image.data_mut()[p] = value(p);
    }
    image
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
