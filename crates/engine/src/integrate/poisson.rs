//! Mask-aware least-squares integration: the masked Poisson equation by conjugate gradients,
//! preconditioned by a multigrid V-cycle.
//!
//! The matrix is the graph Laplacian of the mask's 4-neighbour graph. Plain (diagonally
//! preconditioned) CG needs O(N) iterations on an N×N domain; a V-cycle that smooths with
//! symmetric Gauss–Seidel and corrects from 2×2-aggregated coarse grids brings that down to about
//! 15 from 256² to 1024². The coarse operators are the exact Galerkin products PᵀAP for the
//! piecewise-constant prolongation P, which on a grid are again weighted 5-point Laplacians
//! (the weight of a coarse edge counts the fine mask edges crossing it), so masks, holes and
//! separate parts need no special handling at any level.

use super::check_gradients;
use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Mask};
use crate::imageops::parts::{parts, Parts, SumOrder};

/// Stopping rule of the conjugate-gradient solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoissonOptions {
    /// Stop when the residual norm falls below `tol` times the right-hand side's (> 0).
    pub tol: f64,
    /// Stop after this many iterations (≥ 1).
    pub max_iter: usize,
}

impl Default for PoissonOptions {
    /// A relative residual of 1e-6: on a 1024² solve of a sphere the depth is then within
    /// 6e-5 pixels of the fully converged one (below a float32's resolution at its height of
    /// 600 pixels, and 1/150 of a step of the 16-bit `depth.png`), and its error against the
    /// true depth the same to six digits (docs/performance.md, session 8).
    fn default() -> Self {
        PoissonOptions {
            tol: 1e-6,
            max_iter: 50_000,
        }
    }
}

/// A depth map and how its solve went.
#[derive(Debug, Clone, PartialEq)]
pub struct Integration {
    /// Depth inside the mask (0 outside); each connected part of the mask has zero mean, since
    /// differences say nothing about the offset between parts.
    pub depth: Image,
    /// Conjugate-gradient iterations.
    pub iterations: usize,
    /// Final residual norm relative to the right-hand side.
    pub relative_residual: f64,
    /// Whether the residual reached the tolerance.
    pub converged: bool,
}

/// The depth z on `mask` whose neighbour differences best match, in least squares, the
/// `right` and `down` differences: `right` at (c, r) is the wanted z(c+1, r) − z(c, r) and
/// `down` at (c, r) the wanted z(c, r+1) − z(c, r) (row r+1 is below row r). Only pairs of
/// pixels both inside the mask count.
///
/// This is the general entry point: a lightness model can pass thresholded differences of log
/// luminance here; [`integrate_gradients`] builds the differences from a slope field.
///
/// The normal equations are the Poisson equation L z = b with L the graph Laplacian of the
/// mask's 4-neighbour graph (natural boundary conditions on the silhouette and the image
/// border), solved by conjugate gradients preconditioned with a multigrid V-cycle (see the
/// module documentation). L is singular (a
/// constant can be added to each connected part); the solution is fixed by zero mean per part.
/// Every sum is taken in a fixed order: the result does not depend on threads.
pub fn integrate_differences(
    right: &Image,
    down: &Image,
    mask: &Mask,
    options: &PoissonOptions,
) -> Result<Integration> {
    check_inputs(right, down, mask, options)?;
    solve(mask, differences_rhs(right, down, mask), options)
}

/// The depth on `mask` whose slopes best match (`dz_dx`, `dz_dy`) in least squares (world axes:
/// x right, y up; see the module documentation). The difference between two neighbours is
/// taken as the mean of their slopes (the trapezoid rule); see [`integrate_differences`].
pub fn integrate_gradients(
    dz_dx: &Image,
    dz_dy: &Image,
    mask: &Mask,
    options: &PoissonOptions,
) -> Result<Integration> {
    check_gradient_inputs(dz_dx, dz_dy, mask, options)?;
    let b = gradient_rhs(dz_dx, dz_dy, mask);
    solve(mask, b, options)
}

/// [`integrate_gradients`] taking the slopes by value: they are freed as soon as the
/// right-hand side is built, before the solve allocates its own vectors. Same result, bit for
/// bit; it is what `shadelab solve` uses, where memory peaks at this step.
pub fn integrate_owned_gradients(
    dz_dx: Image,
    dz_dy: Image,
    mask: &Mask,
    options: &PoissonOptions,
) -> Result<Integration> {
    check_gradient_inputs(&dz_dx, &dz_dy, mask, options)?;
    let b = gradient_rhs(&dz_dx, &dz_dy, mask);
    drop((dz_dx, dz_dy));
    solve(mask, b, options)
}

/// [`integrate_gradients`] started from the depth `start` (same size as `mask`) rather than
/// from zero: for slopes that changed little since `start` was their depth, the solve only
/// corrects the difference, in a few iterations. It stops on the same rule (the residual of
/// the whole equation below `tol` times the right-hand side's), so it meets the same
/// tolerance; the result agrees with [`integrate_gradients`]'s to within it, not bit for bit.
pub fn integrate_gradients_from(
    dz_dx: &Image,
    dz_dy: &Image,
    mask: &Mask,
    options: &PoissonOptions,
    start: &Image,
) -> Result<Integration> {
    check_gradient_inputs(dz_dx, dz_dy, mask, options)?;
    PreparedMask::new(mask)?.integrate_gradients(dz_dx, dz_dy, options, Some(start))
}

/// A mask's Poisson solve prepared once for many solves on it: the multigrid hierarchy of its
/// Laplacian and its connected parts, which [`integrate_gradients`] and
/// [`integrate_gradients_from`] build afresh on every call (the integrable method solves one
/// depth per iteration on the same mask). Its solves give the same depth, bit for bit, as
/// those two functions.
pub(crate) struct PreparedMask<'a> {
    mask: &'a Mask,
    hierarchy: multigrid::Hierarchy,
    parts: Parts,
}

impl<'a> PreparedMask<'a> {
    /// The hierarchy and parts of `mask` (fails on an empty mask).
    pub(crate) fn new(mask: &'a Mask) -> Result<PreparedMask<'a>> {
        check_mask(mask)?;
        Ok(PreparedMask {
            mask,
            hierarchy: multigrid::Hierarchy::new(mask),
            parts: parts(mask),
        })
    }

    /// [`integrate_gradients`] on the prepared mask, or [`integrate_gradients_from`] `start`
    /// where one is given.
    pub(crate) fn integrate_gradients(
        &self,
        dz_dx: &Image,
        dz_dy: &Image,
        options: &PoissonOptions,
        start: Option<&Image>,
    ) -> Result<Integration> {
        let mask = self.mask;
        check_gradient_inputs(dz_dx, dz_dy, mask, options)?;
        let b = gradient_rhs(dz_dx, dz_dy, mask);
        let Some(start) = start else {
            return self.solve(b, options);
        };
        if !start.same_size(mask) || start.data().iter().any(|z| !z.is_finite()) {
            return Err(Error::invalid(
                "the starting depth must match the mask's size and be finite",
            ));
        }
        let z0: Vec<f64> = start
            .data()
            .iter()
            .zip(mask.data())
            .map(|(&z, &m)| if m { z } else { 0.0 })
            .collect();
        let mut r = self.hierarchy.apply_grid(&z0);
        for (r, b) in r.iter_mut().zip(&b) {
            *r = b - *r;
        }
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (b_norm, r_norm) = (norm(&b), norm(&r));
        let relative = if b_norm > 0.0 { r_norm / b_norm } else { 0.0 };
        let mut result = if relative <= options.tol {
            Integration {
                depth: Grid::from_vec(mask.width(), mask.height(), vec![0.0; z0.len()])?,
                iterations: 0,
                relative_residual: 1.0,
                converged: true,
            }
        } else {
            let correction = PoissonOptions {
                tol: options.tol / relative,
                ..*options
            };
            self.solve(r, &correction)?
        };
        for (z, z0) in result.depth.data_mut().iter_mut().zip(&z0) {
            *z += z0;
        }
        self.parts
            .subtract_means(result.depth.data_mut(), SumOrder::Index);
        result.relative_residual *= relative;
        Ok(result)
    }

    /// `solve` on the prepared hierarchy and parts. The one-off `solve` keeps its own body
    /// rather than calling this: it drops the hierarchy before it finds the parts, so that a
    /// large single integration never holds both (the whole solve's memory peaks there).
    fn solve(&self, b: Vec<f64>, options: &PoissonOptions) -> Result<Integration> {
        let (w, h) = (self.mask.width(), self.mask.height());
        let layout = self.hierarchy.layout();
        let b = layout.colour_order(&b);
        let (z, iterations, relative_residual, converged) = self.hierarchy.pcg(b, options);
        let mut z = layout.grid_order(&z);
        self.parts.subtract_means(&mut z, SumOrder::Index);
        Ok(Integration {
            depth: Grid::from_vec(w, h, z)?,
            iterations,
            relative_residual,
            converged,
        })
    }
}

/// The checks of [`integrate_gradients`].
fn check_gradient_inputs(
    dz_dx: &Image,
    dz_dy: &Image,
    mask: &Mask,
    options: &PoissonOptions,
) -> Result<()> {
    check_gradients(dz_dx, dz_dy)?;
    dz_dx.check_same_size("gradient fields are", mask, "the mask is")?;
    check_options(options)?;
    check_mask(mask)
}

/// The right-hand side for slopes: the difference between two neighbours is the mean of their
/// slopes (the trapezoid rule), formed on the fly rather than as two more images.
fn gradient_rhs(dz_dx: &Image, dz_dy: &Image, mask: &Mask) -> Vec<f64> {
    build_rhs(
        mask,
        |c, r| 0.5 * (dz_dx.get(c, r) + dz_dx.get(c + 1, r)),
        // One row down is one pixel toward −y.
        |c, r| -0.5 * (dz_dy.get(c, r) + dz_dy.get(c, r + 1)),
    )
}

/// The right-hand side for difference fields, read as they are.
fn differences_rhs(right: &Image, down: &Image, mask: &Mask) -> Vec<f64> {
    build_rhs(mask, |c, r| *right.get(c, r), |c, r| *down.get(c, r))
}

/// Checks sizes, finiteness, options and a non-empty mask, in the order the original
/// integrator did (so its error messages are unchanged).
fn check_inputs(right: &Image, down: &Image, mask: &Mask, options: &PoissonOptions) -> Result<()> {
    check_gradients(right, down)?;
    right.check_same_size("difference fields are", mask, "the mask is")?;
    check_options(options)?;
    check_mask(mask)
}

fn check_options(options: &PoissonOptions) -> Result<()> {
    if !(options.tol.is_finite() && options.tol > 0.0) || options.max_iter == 0 {
        return Err(Error::invalid(format!(
            "integration tolerance {} must be positive and max_iter {} at least 1",
            options.tol, options.max_iter
        )));
    }
    Ok(())
}

fn check_mask(mask: &Mask) -> Result<()> {
    if mask.count() == 0 {
        return Err(Error::invalid(
            "the mask is empty: there is nothing to integrate",
        ));
    }
    Ok(())
}

/// The right-hand side of the normal equations on the full grid (0 outside the mask):
/// b_k = Σ over pairs (i → k) of d − Σ over pairs (k → j) of d, for d the wanted z_j − z_i.
/// `right(c, r)` is only asked for when both (c, r) and (c+1, r) are inside, `down(c, r)` when
/// both (c, r) and (c, r+1) are.
fn build_rhs(
    mask: &Mask,
    right: impl Fn(usize, usize) -> f64,
    down: impl Fn(usize, usize) -> f64,
) -> Vec<f64> {
    let (w, h) = (mask.width(), mask.height());
    let inside = |c: usize, r: usize| *mask.get(c, r);
    let mut b = vec![0.0; w * h];
    for r in 0..h {
        for c in 0..w {
            if !inside(c, r) {
                continue;
            }
            let mut v = 0.0;
            if c + 1 < w && inside(c + 1, r) {
                v -= right(c, r);
            }
            if c > 0 && inside(c - 1, r) {
                v += right(c - 1, r);
            }
            if r + 1 < h && inside(c, r + 1) {
                v -= down(c, r);
            }
            if r > 0 && inside(c, r - 1) {
                v += down(c, r - 1);
            }
            b[r * w + c] = v;
        }
    }
    b
}

/// Solves L z = b on the mask by multigrid-preconditioned CG and fixes the gauge.
fn solve(mask: &Mask, b: Vec<f64>, options: &PoissonOptions) -> Result<Integration> {
    let (w, h) = (mask.width(), mask.height());
    let hierarchy = multigrid::Hierarchy::new(mask);
    let layout = hierarchy.layout();
    let b = layout.colour_order(&b);
    let (z, iterations, relative_residual, converged) = hierarchy.pcg(b, options);
    drop(hierarchy);
    let mut z = layout.grid_order(&z);
    // Means summed in row-major order.
    parts(mask).subtract_means(&mut z, SumOrder::Index);
    Ok(Integration {
        depth: Grid::from_vec(w, h, z)?,
        iterations,
        relative_residual,
        converged,
    })
}

mod multigrid;
#[cfg(test)]
pub(crate) mod reference;
#[cfg(test)]
mod tests;
