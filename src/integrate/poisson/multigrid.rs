//! Conjugate gradients on the masked Laplacian, preconditioned by a multigrid V-cycle.
//!
//! Every level is a weighted 5-point graph Laplacian on a grid, (A x)_i = d_i x_i − Σ w_ij x_j,
//! stored over the whole grid: a pixel outside the mask simply has no edges (d = 0) and its
//! value stays 0 throughout. Coarse levels aggregate 2×2 blocks; with the piecewise-constant
//! prolongation P, the Galerkin operator PᵀAP is again such a Laplacian whose edge weights
//! count the fine edges between two blocks. Weights are small integers, exact in f32.
//!
//! The V-cycle (one forward Gauss–Seidel sweep before the coarse correction, one backward
//! sweep after, a fixed number of symmetric sweeps on the coarsest grid) is a fixed symmetric
//! positive linear operator, as CG requires. Everything runs in one fixed order, so results
//! do not depend on the thread count.

use super::PoissonOptions;
use crate::grid::Mask;

/// Coarsening stops once a level has at most this many cells.
const COARSEST_CELLS: usize = 16;
/// Symmetric Gauss–Seidel sweeps on the coarsest level (tiny, so this is nearly exact).
const COARSEST_SWEEPS: usize = 40;
/// Scale of the coarse-grid correction. Piecewise-constant prolongation under-corrects smooth
/// errors; scaling it up (below 2, which keeps the preconditioner positive) is the standard
/// remedy for aggregation multigrid.
const COARSE_SCALE: f64 = 1.8;

/// The neighbour a Gauss–Seidel sweep has just updated.
#[derive(Clone, Copy)]
enum Side {
    /// The forward sweep's: the cell to the left.
    Left,
    /// The backward sweep's: the cell to the right.
    Right,
}

/// One level: a weighted 5-point Laplacian on a `w` × `h` grid.
struct Level {
    w: usize,
    h: usize,
    /// Weight of the edge to the right-hand neighbour (0 in the last column).
    right: Vec<f32>,
    /// Weight of the edge to the neighbour below (0 in the last row).
    down: Vec<f32>,
    /// Sum of the incident weights; 0 for a cell with no equation.
    diag: Vec<f32>,
}

impl Level {
    fn from_mask(mask: &Mask) -> Level {
        let (w, h) = (mask.width(), mask.height());
        let m = mask.data();
        let mut right = vec![0.0f32; w * h];
        let mut down = vec![0.0f32; w * h];
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                if m[i] && c + 1 < w && m[i + 1] {
                    right[i] = 1.0;
                }
                if m[i] && r + 1 < h && m[i + w] {
                    down[i] = 1.0;
                }
            }
        }
        Level::with_weights(w, h, right, down)
    }

    fn with_weights(w: usize, h: usize, right: Vec<f32>, down: Vec<f32>) -> Level {
        let mut diag = vec![0.0f32; w * h];
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                let mut d = right[i] + down[i];
                if c > 0 {
                    d += right[i - 1];
                }
                if r > 0 {
                    d += down[i - w];
                }
                diag[i] = d;
            }
        }
        Level {
            w,
            h,
            right,
            down,
            diag,
        }
    }

    /// The Galerkin coarse level of 2×2 blocks.
    fn coarsen(&self) -> Level {
        let (w, h) = (self.w, self.h);
        let (cw, ch) = (w.div_ceil(2), h.div_ceil(2));
        let mut right = vec![0.0f32; cw * ch];
        let mut down = vec![0.0f32; cw * ch];
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                let k = (r / 2) * cw + c / 2;
                // Only edges leaving a block through its right or lower side survive.
                if c % 2 == 1 {
                    right[k] += self.right[i];
                }
                if r % 2 == 1 {
                    down[k] += self.down[i];
                }
            }
        }
        Level::with_weights(cw, ch, right, down)
    }

    fn cells(&self) -> usize {
        self.w * self.h
    }

    /// Σ_j w_ij x_j over the grid neighbours of cell i = (c, r).
    #[inline(always)]
    fn neighbour_sum(&self, x: &[f64], c: usize, r: usize, i: usize) -> f64 {
        let w = self.w;
        let mut s = 0.0;
        if c > 0 {
            s += f64::from(self.right[i - 1]) * x[i - 1];
        }
        if c + 1 < w {
            s += f64::from(self.right[i]) * x[i + 1];
        }
        if r > 0 {
            s += f64::from(self.down[i - w]) * x[i - w];
        }
        if r + 1 < self.h {
            s += f64::from(self.down[i]) * x[i + w];
        }
        s
    }

    /// out = A x.
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        for r in 0..self.h {
            for c in 0..self.w {
                let i = r * self.w + c;
                let d = self.diag[i];
                out[i] = if d > 0.0 {
                    f64::from(d) * x[i] - self.neighbour_sum(x, c, r, i)
                } else {
                    0.0
                };
            }
        }
    }

    /// One Gauss–Seidel sweep on A x = b in row-major order.
    ///
    /// The sweep is sequential along a row: each value needs the one just updated to its
    /// left. Only that term is added after the others (which are already known) and the
    /// division is a multiplication by 1/d, computed beside the chain: the dependency from
    /// one pixel to the next is one multiply-add and one multiply instead of four additions
    /// and a division.
    fn sweep_forward(&self, x: &mut [f64], b: &[f64]) {
        let w = self.w;
        for r in 0..self.h {
            for c in 0..w {
                let i = r * w + c;
                let d = self.diag[i];
                if d > 0.0 {
                    let known = b[i] + self.sum_except(x, c, r, i, Side::Left);
                    let left = if c > 0 {
                        f64::from(self.right[i - 1]) * x[i - 1]
                    } else {
                        0.0
                    };
                    x[i] = (known + left) * (1.0 / f64::from(d));
                }
            }
        }
    }

    /// One Gauss–Seidel sweep in reverse row-major order (the adjoint of the forward sweep),
    /// with the term of the right-hand neighbour, just updated, added last.
    fn sweep_backward(&self, x: &mut [f64], b: &[f64]) {
        let w = self.w;
        for r in (0..self.h).rev() {
            for c in (0..w).rev() {
                let i = r * w + c;
                let d = self.diag[i];
                if d > 0.0 {
                    let known = b[i] + self.sum_except(x, c, r, i, Side::Right);
                    let right = if c + 1 < w {
                        f64::from(self.right[i]) * x[i + 1]
                    } else {
                        0.0
                    };
                    x[i] = (known + right) * (1.0 / f64::from(d));
                }
            }
        }
    }

    /// Σ_j w_ij x_j over the grid neighbours of cell i = (c, r) but the one on `skip`'s side.
    #[inline(always)]
    fn sum_except(&self, x: &[f64], c: usize, r: usize, i: usize, skip: Side) -> f64 {
        let w = self.w;
        let mut s = 0.0;
        if r > 0 {
            s += f64::from(self.down[i - w]) * x[i - w];
        }
        if r + 1 < self.h {
            s += f64::from(self.down[i]) * x[i + w];
        }
        match skip {
            Side::Left if c + 1 < w => s += f64::from(self.right[i]) * x[i + 1],
            Side::Right if c > 0 => s += f64::from(self.right[i - 1]) * x[i - 1],
            _ => {}
        }
        s
    }

    /// coarse_b = Pᵀ (b − A x): each block's residuals summed, in row-major order.
    fn restrict_residual(&self, x: &[f64], b: &[f64], coarse_b: &mut [f64]) {
        let cw = self.w.div_ceil(2);
        coarse_b.fill(0.0);
        for r in 0..self.h {
            for c in 0..self.w {
                let i = r * self.w + c;
                let d = self.diag[i];
                if d > 0.0 {
                    let residual = b[i] - (f64::from(d) * x[i] - self.neighbour_sum(x, c, r, i));
                    coarse_b[(r / 2) * cw + c / 2] += residual;
                }
            }
        }
    }

    /// x += scale · P coarse_x on the cells that have an equation.
    fn prolong_add(&self, coarse_x: &[f64], x: &mut [f64], scale: f64) {
        let cw = self.w.div_ceil(2);
        for r in 0..self.h {
            for c in 0..self.w {
                let i = r * self.w + c;
                if self.diag[i] > 0.0 {
                    x[i] += scale * coarse_x[(r / 2) * cw + c / 2];
                }
            }
        }
    }
}

/// The levels of a mask's Laplacian, finest first.
pub(super) struct Hierarchy {
    levels: Vec<Level>,
}

impl Hierarchy {
    pub(super) fn new(mask: &Mask) -> Hierarchy {
        let mut levels = vec![Level::from_mask(mask)];
        while let Some(last) = levels.last() {
            if last.cells() <= COARSEST_CELLS || (last.w == 1 && last.h == 1) {
                break;
            }
            let next = last.coarsen();
            levels.push(next);
        }
        Hierarchy { levels }
    }

    /// out = A x on the finest level (the masked Laplacian itself).
    pub(super) fn apply(&self, x: &[f64], out: &mut [f64]) {
        self.levels[0].apply(x, out);
    }

    /// x = M⁻¹ b by one V-cycle from level `l` down, with `work` holding (x, b) of each
    /// coarser level.
    fn vcycle(&self, l: usize, x: &mut [f64], b: &[f64], work: &mut [(Vec<f64>, Vec<f64>)]) {
        let level = &self.levels[l];
        x.fill(0.0);
        let Some(((coarse_x, coarse_b), rest)) = work.split_first_mut() else {
            for _ in 0..COARSEST_SWEEPS {
                level.sweep_forward(x, b);
                level.sweep_backward(x, b);
            }
            return;
        };
        level.sweep_forward(x, b);
        level.restrict_residual(x, b, coarse_b);
        self.vcycle(l + 1, coarse_x, coarse_b, rest);
        level.prolong_add(coarse_x, x, COARSE_SCALE);
        level.sweep_backward(x, b);
    }

    /// Preconditioned conjugate gradients on A z = b from z = 0, stopping on the relative
    /// residual ‖b − A z‖ ≤ tol·‖b‖ as the diagonally preconditioned solver did. Returns (z,
    /// iterations, relative residual, converged); z is 0 where there is no equation.
    pub(super) fn pcg(
        &self,
        b: Vec<f64>,
        options: &PoissonOptions,
    ) -> (Vec<f64>, usize, f64, bool) {
        let fine = &self.levels[0];
        let n = b.len();
        let dot = |u: &[f64], v: &[f64]| -> f64 { u.iter().zip(v).map(|(a, b)| a * b).sum() };
        let b_norm = dot(&b, &b).sqrt();
        let mut z = vec![0.0; n];
        if b_norm == 0.0 {
            return (z, 0, 0.0, true);
        }
        let mut work: Vec<(Vec<f64>, Vec<f64>)> = self.levels[1..]
            .iter()
            .map(|l| (vec![0.0; l.cells()], vec![0.0; l.cells()]))
            .collect();
        let mut r = b;
        // q holds A p and, once r is updated, the preconditioned residual M⁻¹ r: four vectors
        // of the image's size in all.
        let mut q = vec![0.0; n];
        self.vcycle(0, &mut q, &r, &mut work);
        let mut p = q.clone();
        let mut rs = dot(&r, &q);
        let target = options.tol * b_norm;
        let mut residual = b_norm;
        for iteration in 1..=options.max_iter {
            fine.apply(&p, &mut q);
            let curvature = dot(&p, &q);
            if curvature <= 0.0 {
                return (z, iteration - 1, residual / b_norm, residual <= target);
            }
            let alpha = rs / curvature;
            // The update and ‖r‖² in one pass (summed in index order, as `dot`).
            let mut rr = 0.0;
            for ((z, r), (p, q)) in z.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&q)) {
                *z += alpha * p;
                *r -= alpha * q;
                rr += *r * *r;
            }
            residual = f64::sqrt(rr);
            if residual <= target {
                return (z, iteration, residual / b_norm, true);
            }
            self.vcycle(0, &mut q, &r, &mut work);
            let rs_next = dot(&r, &q);
            let beta = rs_next / rs;
            rs = rs_next;
            for (p, q) in p.iter_mut().zip(&q) {
                *p = q + beta * *p;
            }
        }
        (z, options.max_iter, residual / b_norm, false)
    }
}
