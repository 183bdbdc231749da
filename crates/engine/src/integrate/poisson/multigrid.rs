//! Conjugate gradients on the masked Laplacian, preconditioned by a multigrid V-cycle with a
//! red-black Gauss–Seidel smoother.
//!
//! Every level is a weighted 5-point graph Laplacian on a grid, (A x)_i = d_i x_i − Σ w_ij x_j,
//! stored over the whole grid: a pixel outside the mask simply has no edges (d = 0) and its
//! value stays 0 throughout. Coarse levels aggregate 2×2 blocks; with the piecewise-constant
//! prolongation P, the Galerkin operator PᵀAP is again such a Laplacian whose edge weights
//! count the fine edges between two blocks. Weights are small integers, exact in f32.
//!
//! Cells are stored by colour ([`Layout`]): the red cells ((column + row) even) first, then the
//! black ones, each row padded and the grid framed by empty cells. A cell's four neighbours
//! have the other colour, so a colour's update reads only the other colour: the rows of one
//! colour are updated in parallel, each by one fixed formula, and the result does not depend
//! on how the rows are shared among threads. Sums over the whole grid (dot products) add fixed
//! chunks in order. The bytes do not depend on the thread count.
//!
//! The V-cycle (red then black before the coarse correction, black then red after it, a
//! palindrome of colour sweeps on the coarsest grid) is a fixed symmetric positive linear
//! operator, as CG requires. After the red-then-black sweep the black cells' residual is zero,
//! so only red residuals are restricted; the black values before the last sweeps are never
//! read, so the correction is prolonged to the red cells only.

use super::PoissonOptions;
use crate::conjugate_gradients::{self, Stop};
use crate::grid::Mask;
use crate::parallel::prelude::*;

/// Coarsening stops once a level has at most this many cells.
const COARSEST_CELLS: usize = 16;
/// Symmetric Gauss–Seidel sweeps on the coarsest level (tiny, so this is nearly exact).
const COARSEST_SWEEPS: usize = 40;
/// Scale of the coarse-grid correction. Piecewise-constant prolongation under-corrects smooth
/// errors; scaling it up (below 2, which keeps the preconditioner positive) is the standard
/// remedy for aggregation multigrid.
const COARSE_SCALE: f64 = 1.8;
/// Rows of one colour a worker updates at a time.
const BAND_ROWS: usize = 16;
/// Levels with fewer cells than this are done on the calling thread (threads cost more).
const PARALLEL_CELLS: usize = 1 << 15;

/// Where a cell of a `w` × `h` grid is stored: colour k = (column + row) mod 2 in the k-th half
/// of a vector; in it, row r (1-based, rows 0 and h + 1 are empty frames) at offset
/// r · stride and column c at c / 2. A row's last slot is always empty, so the left neighbour
/// of a row's first cell and the right neighbour of its last are empty slots too.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Layout {
    w: usize,
    h: usize,
    /// Slots per row of one colour.
    stride: usize,
    /// Slots of one colour.
    half: usize,
}

impl Layout {
    pub(super) fn new(w: usize, h: usize) -> Layout {
        let stride = w.div_ceil(2) + 1;
        Layout {
            w,
            h,
            stride,
            half: (h + 2) * stride,
        }
    }

    /// Slots of a vector of this layout (both colours).
    pub(super) fn len(&self) -> usize {
        2 * self.half
    }

    /// The slot of cell (c, r).
    #[inline]
    pub(super) fn at(&self, c: usize, r: usize) -> usize {
        ((c + r) % 2) * self.half + (r + 1) * self.stride + c / 2
    }

    /// A row-major grid's values as a vector in this layout (0 in the empty slots).
    pub(super) fn colour_order(&self, grid: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.len()];
        for (r, row) in grid.chunks(self.w.max(1)).take(self.h).enumerate() {
            for (c, &v) in row.iter().enumerate() {
                out[self.at(c, r)] = v;
            }
        }
        out
    }

    /// The values of a vector in this layout as a row-major grid.
    pub(super) fn grid_order(&self, v: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.w * self.h);
        for r in 0..self.h {
            out.extend((0..self.w).map(|c| v[self.at(c, r)]));
        }
        out
    }
}

/// One level: a weighted 5-point Laplacian on a grid, its cells in [`Layout`] order.
struct Level {
    layout: Layout,
    /// Weight of the edge to the right-hand neighbour (0 in the last column and empty slots).
    right: Vec<f32>,
    /// Weight of the edge to the neighbour below (0 in the last row and empty slots).
    down: Vec<f32>,
    /// Sum of the incident weights; 0 for a cell with no equation.
    diag: Vec<f32>,
}

/// The rows of one colour of a level, as slices of the level's vectors: what a colour's update
/// (or its residual) reads.
struct Rows<'a> {
    /// This colour's weights to the right and below, and diagonal.
    right: &'a [f32],
    down: &'a [f32],
    diag: &'a [f32],
    /// The other colour's weights to the right and below, and values.
    other_right: &'a [f32],
    other_down: &'a [f32],
    other_x: &'a [f64],
}

impl Rows<'_> {
    /// Σ_j w_ij x_j for the cells of row `r` (0-based) of this colour `k`, passed to `each` with
    /// their slot in the colour's half. Column parity of the row's cells: s = (k + r) mod 2;
    /// the left neighbour of slot i is the other colour's i − 1 + s, the right one i + s.
    #[inline(always)]
    fn for_row(&self, k: usize, r: usize, stride: usize, mut each: impl FnMut(usize, f64, f64)) {
        let s = (k + r) % 2;
        let base = (r + 1) * stride;
        let row = base..base + stride;
        let x = self.other_x;
        let (wr, wd, d) = (
            &self.right[row.clone()],
            &self.down[row.clone()],
            &self.diag[row],
        );
        let left = base + s - 1;
        let (xl, wl) = (
            &x[left..left + stride],
            &self.other_right[left..left + stride],
        );
        let (xr, xu, xd) = (
            &x[base + s..base + s + stride],
            &x[base - stride..base],
            &x[base + stride..base + 2 * stride],
        );
        let wu = &self.other_down[base - stride..base];
        for j in 0..stride {
            let sum = f64::from(wl[j]) * xl[j]
                + f64::from(wr[j]) * xr[j]
                + f64::from(wu[j]) * xu[j]
                + f64::from(wd[j]) * xd[j];
            each(j, sum, f64::from(d[j]));
        }
    }
}

impl Level {
    fn from_mask(mask: &Mask) -> Level {
        let (w, h) = (mask.width(), mask.height());
        let layout = Layout::new(w, h);
        let m = mask.data();
        let mut right = vec![0.0f32; layout.len()];
        let mut down = vec![0.0f32; layout.len()];
        for r in 0..h {
            for c in 0..w {
                let i = r * w + c;
                if m[i] && c + 1 < w && m[i + 1] {
                    right[layout.at(c, r)] = 1.0;
                }
                if m[i] && r + 1 < h && m[i + w] {
                    down[layout.at(c, r)] = 1.0;
                }
            }
        }
        Level::with_weights(layout, right, down)
    }

    fn with_weights(layout: Layout, right: Vec<f32>, down: Vec<f32>) -> Level {
        let mut diag = vec![0.0f32; layout.len()];
        for r in 0..layout.h {
            for c in 0..layout.w {
                let i = layout.at(c, r);
                let mut d = right[i] + down[i];
                if c > 0 {
                    d += right[layout.at(c - 1, r)];
                }
                if r > 0 {
                    d += down[layout.at(c, r - 1)];
                }
                diag[i] = d;
            }
        }
        Level {
            layout,
            right,
            down,
            diag,
        }
    }

    /// The Galerkin coarse level of 2×2 blocks.
    fn coarsen(&self) -> Level {
        let Layout { w, h, .. } = self.layout;
        let coarse = Layout::new(w.div_ceil(2), h.div_ceil(2));
        let mut right = vec![0.0f32; coarse.len()];
        let mut down = vec![0.0f32; coarse.len()];
        for r in 0..h {
            for c in 0..w {
                let (i, k) = (self.layout.at(c, r), coarse.at(c / 2, r / 2));
                // Only edges leaving a block through its right or lower side survive.
                if c % 2 == 1 {
                    right[k] += self.right[i];
                }
                if r % 2 == 1 {
                    down[k] += self.down[i];
                }
            }
        }
        Level::with_weights(coarse, right, down)
    }

    fn cells(&self) -> usize {
        self.layout.w * self.layout.h
    }

    fn parallel(&self) -> bool {
        self.cells() >= PARALLEL_CELLS
    }

    /// The colour-`k` rows of this level with the other colour's values from `x_other`.
    fn rows<'a>(&'a self, k: usize, x_other: &'a [f64]) -> Rows<'a> {
        let half = self.layout.half;
        let colour = |v: &'a [f32], k: usize| &v[k * half..(k + 1) * half];
        Rows {
            right: colour(&self.right, k),
            down: colour(&self.down, k),
            diag: colour(&self.diag, k),
            other_right: colour(&self.right, 1 - k),
            other_down: colour(&self.down, 1 - k),
            other_x: x_other,
        }
    }

    /// Runs `row(r, out_row)` for every row r of a colour, `out` being that colour's half of
    /// a vector (on the worker threads for a large level): each call gets its row's slots.
    fn each_row(&self, out: &mut [f64], row: impl Fn(usize, &mut [f64]) + Sync + Send) {
        let Layout { h, stride, .. } = self.layout;
        let inner = &mut out[stride..(h + 1) * stride];
        let band = |(b, rows): (usize, &mut [f64])| {
            for (i, slots) in rows.chunks_mut(stride).enumerate() {
                row(b * BAND_ROWS + i, slots);
            }
        };
        if self.parallel() {
            inner
                .par_chunks_mut(BAND_ROWS * stride)
                .enumerate()
                .for_each(band);
        } else {
            inner
                .chunks_mut(BAND_ROWS * stride)
                .enumerate()
                .for_each(band);
        }
    }

    /// One Gauss–Seidel update of the cells of colour `k` on A x = b.
    fn relax(&self, k: usize, x: &mut [f64], b: &[f64]) {
        let half = self.layout.half;
        let (red, black) = x.split_at_mut(half);
        let (own, other) = if k == 0 {
            (red, &*black)
        } else {
            (black, &*red)
        };
        let rows = self.rows(k, other);
        let b = &b[k * half..(k + 1) * half];
        let stride = self.layout.stride;
        self.each_row(own, |r, out| {
            let b = &b[(r + 1) * stride..(r + 2) * stride];
            rows.for_row(k, r, stride, |j, sum, d| {
                out[j] = if d > 0.0 { (b[j] + sum) / d } else { 0.0 };
            });
        });
    }

    /// out = A x.
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        let half = self.layout.half;
        let stride = self.layout.stride;
        let (out_red, out_black) = out.split_at_mut(half);
        for (k, out) in [(0, out_red), (1, out_black)] {
            let rows = self.rows(k, &x[(1 - k) * half..(2 - k) * half]);
            let own = &x[k * half..(k + 1) * half];
            self.each_row(out, |r, out| {
                let own = &own[(r + 1) * stride..(r + 2) * stride];
                rows.for_row(k, r, stride, |j, sum, d| out[j] = d * own[j] - sum);
            });
        }
    }

    /// coarse_b = Pᵀ (b − A x) for x just relaxed red then black, whose black residuals are
    /// zero: each block's (up to) two red residuals summed, top-left first.
    fn restrict_residual(&self, x: &[f64], b: &[f64], coarse: &Layout, coarse_b: &mut [f64]) {
        let Layout {
            h, stride, half, ..
        } = self.layout;
        let rows = self.rows(0, &x[half..]);
        let (x, b) = (&x[..half], &b[..half]);
        let residual_row = |r: usize, into: &mut [f64]| {
            if r >= h {
                into.fill(0.0);
                return;
            }
            let base = (r + 1) * stride;
            rows.for_row(0, r, stride, |j, sum, d| {
                into[j] = b[base + j] - (d * x[base + j] - sum);
            });
        };
        // Red cells of block (C, R): (2C, 2R), slot C of red row 2R, and (2C + 1, 2R + 1),
        // slot C of red row 2R + 1.
        let cstride = coarse.stride;
        let block_row = |(red, black): (&mut [f64], &mut [f64]), big_r: usize| {
            let mut first = vec![0.0; stride];
            let mut second = vec![0.0; stride];
            residual_row(2 * big_r, &mut first);
            residual_row(2 * big_r + 1, &mut second);
            for big_c in 0..coarse.w {
                let v = first[big_c] + second[big_c];
                // Coarse cell (C, R) is red when C + R is even.
                let slot = big_c / 2;
                if (big_c + big_r) % 2 == 0 {
                    red[slot] = v;
                } else {
                    black[slot] = v;
                }
            }
        };
        let (red, black) = coarse_b.split_at_mut(coarse.half);
        let inner = cstride..(coarse.h + 1) * cstride;
        let (red, black) = (&mut red[inner.clone()], &mut black[inner]);
        if self.parallel() {
            red.par_chunks_mut(cstride)
                .zip(black.par_chunks_mut(cstride))
                .enumerate()
                .for_each(|(big_r, pair)| block_row(pair, big_r));
        } else {
            red.chunks_mut(cstride)
                .zip(black.chunks_mut(cstride))
                .enumerate()
                .for_each(|(big_r, pair)| block_row(pair, big_r));
        }
    }

    /// x += scale · P coarse_x on the red cells that have an equation (the black ones are
    /// relaxed next, which overwrites them).
    fn prolong_red(&self, coarse: &Layout, coarse_x: &[f64], x: &mut [f64], scale: f64) {
        let Layout { stride, half, .. } = self.layout;
        let diag = &self.diag[..half];
        self.each_row(&mut x[..half], |r, out| {
            // Red cells of row r are columns 2j + s, s = r mod 2: block column j.
            let big_r = r / 2;
            let d = &diag[(r + 1) * stride..(r + 2) * stride];
            for (j, (x, d)) in out.iter_mut().zip(d).enumerate().take(coarse.w) {
                if *d > 0.0 {
                    *x += scale * coarse_x[coarse.at(j, big_r)];
                }
            }
        });
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
            let Layout { w, h, .. } = last.layout;
            if last.cells() <= COARSEST_CELLS || (w == 1 && h == 1) {
                break;
            }
            let next = last.coarsen();
            levels.push(next);
        }
        Hierarchy { levels }
    }

    /// The layout of the finest level: of the right-hand side and the solution.
    pub(super) fn layout(&self) -> Layout {
        self.levels[0].layout
    }

    /// A x on the finest level (the masked Laplacian itself), `x` and the result in row-major
    /// grid order.
    pub(super) fn apply_grid(&self, x: &[f64]) -> Vec<f64> {
        let layout = self.levels[0].layout;
        let x = layout.colour_order(x);
        let mut out = vec![0.0; x.len()];
        self.levels[0].apply(&x, &mut out);
        layout.grid_order(&out)
    }

    /// x = M⁻¹ b by one V-cycle from level `l` down, with `work` holding (x, b) of each
    /// coarser level.
    fn vcycle(&self, l: usize, x: &mut [f64], b: &[f64], work: &mut [(Vec<f64>, Vec<f64>)]) {
        let level = &self.levels[l];
        x.fill(0.0);
        let Some(((coarse_x, coarse_b), rest)) = work.split_first_mut() else {
            // A palindrome of colour sweeps: symmetric Gauss–Seidel, repeated.
            level.relax(0, x, b);
            for _ in 0..COARSEST_SWEEPS {
                level.relax(1, x, b);
                level.relax(0, x, b);
            }
            return;
        };
        let coarse = &self.levels[l + 1].layout;
        level.relax(0, x, b);
        level.relax(1, x, b);
        level.restrict_residual(x, b, coarse, coarse_b);
        self.vcycle(l + 1, coarse_x, coarse_b, rest);
        level.prolong_red(coarse, coarse_x, x, COARSE_SCALE);
        level.relax(1, x, b);
        level.relax(0, x, b);
    }

    /// Preconditioned conjugate gradients on A z = b (in [`Hierarchy::layout`] order) from
    /// z = 0, stopping on the relative residual ‖b − A z‖ ≤ tol·‖b‖ as the diagonally
    /// preconditioned solver did. Returns (z, iterations, relative residual, converged); z is 0
    /// where there is no equation.
    pub(super) fn pcg(
        &self,
        b: Vec<f64>,
        options: &PoissonOptions,
    ) -> (Vec<f64>, usize, f64, bool) {
        let fine = &self.levels[0];
        let n = b.len();
        let mut work: Vec<(Vec<f64>, Vec<f64>)> = self.levels[1..]
            .iter()
            .map(|l| (vec![0.0; l.layout.len()], vec![0.0; l.layout.len()]))
            .collect();
        // Four vectors of the image's size in all: z, the residual (b's own buffer), and the
        // direction and its product.
        let (mut z, mut r, mut p, mut q) = (vec![0.0; n], b, vec![0.0; n], vec![0.0; n]);
        let stop = Stop {
            tol: options.tol,
            max_iter: options.max_iter,
        };
        let outcome = conjugate_gradients::solve(
            |v, out| fine.apply(v, out),
            |r, out| self.vcycle(0, out, r, &mut work),
            &mut r,
            &mut z,
            [&mut p, &mut q],
            stop,
        );
        (
            z,
            outcome.iterations,
            outcome.relative_residual,
            outcome.converged,
        )
    }
}
