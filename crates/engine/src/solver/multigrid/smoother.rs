//! Red-black Gauss–Seidel: the half-sweeps of every level, the band sweeps and the residual
//! checks, with the pointwise helpers they share.

use super::*;

/// The sum of the four neighbours of padded cell (r, c) (index j in its colour's rows), read
/// from the other colour's values.
#[inline]
pub(super) fn neighbour_sum(other: &[Pair], hw: usize, r: usize, c: usize, j: usize) -> Pair {
    let row = r * hw;
    let o = c & 1;
    let (a, b) = (other[row + j + o - 1], other[row + j + o]);
    let (u, d) = (other[row - hw + j], other[row + hw + j]);
    [a[0] + b[0] + u[0] + d[0], a[1] + b[1] + u[1] + d[1]]
}

/// The larger of `worst` and the change from `old` to `new`; a NaN change counts as infinite.
#[inline]
pub(super) fn track(worst: f64, old: Pair, new: Pair) -> f64 {
    let mut m = worst;
    for change in [(new[0] - old[0]).abs(), (new[1] - old[1]).abs()] {
        if change.is_nan() || change > m {
            m = if change.is_nan() {
                f64::INFINITY
            } else {
                change
            };
        }
    }
    m
}

/// NaN-aware maximum for reductions.
#[inline]
pub(super) fn worst_of(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::INFINITY
    } else {
        a.max(b)
    }
}

/// Runs `f(r, row)` over the rows of `out` (`len` items each), in parallel when asked, and
/// returns the largest value it returned.
pub(super) fn over_rows<T, F>(out: &mut [T], len: usize, parallel: bool, f: F) -> f64
where
    T: Send,
    F: Fn(usize, &mut [T]) -> f64 + Sync + Send,
{
    if parallel {
        crate::parallel::reduce(
            out.par_chunks_mut(len)
                .enumerate()
                .with_min_len((TASK_CELLS / len).max(1))
                .map(|(r, row)| f(r, row)),
            0.0,
            worst_of,
        )
    } else {
        out.chunks_mut(len)
            .enumerate()
            .map(|(r, row)| f(r, row))
            .fold(0.0, worst_of)
    }
}

/// (k·Id + A)⁻¹ b.
#[inline]
pub(super) fn solve2(k: f64, a: Sym, b: Pair) -> Pair {
    let (m11, m12, m22) = (k + a[0], a[1], k + a[2]);
    let inv_det = 1.0 / (m11 * m22 - m12 * m12);
    [
        (m22 * b[0] - m12 * b[1]) * inv_det,
        (m11 * b[1] - m12 * b[0]) * inv_det,
    ]
}

/// Where a half-sweep works in a level's colour arrays: padded row `r` of arrays `hw` cells
/// wide, the cells c = 2j + `start` for j in `span` (one colour's cells of the row).
#[derive(Debug, Clone, Copy)]
pub(super) struct HalfRow {
    pub(super) hw: usize,
    pub(super) r: usize,
    pub(super) start: usize,
    pub(super) span: (usize, usize),
}

/// One half-sweep of padded row `r` of a coarse level (kinds `kind_row`, right-hand sides
/// `rhs_row`, reaction matrices `reaction_row`): the cells of one colour (c = 2j + `start`, j in
/// `span`) in `row` solved pointwise from the other colour's values `other`. Returns the largest
/// change.
#[inline(never)]
pub(super) fn coarse_row<const TRACK: bool>(
    kind_row: &[u8],
    (rhs_row, reaction_row): (&[Pair], &[Sym]),
    other: &[Pair],
    HalfRow { hw, r, start, span }: HalfRow,
    row: &mut [Pair],
) -> f64 {
    let mut worst = 0.0;
    let (lo, hi) = span;
    if lo >= hi {
        return worst;
    }
    // The other colour's rows above, beside and below: the left and right neighbours of cell
    // j are at j + start − 1 and j + start of the middle row (as in `neighbour_sum`).
    let (up, mid, down) = (
        &other[(r - 1) * hw..r * hw],
        &other[r * hw..(r + 1) * hw],
        &other[(r + 1) * hw..(r + 2) * hw],
    );
    // Every array cut to the span (cells c = 2j + start of the padded rows: every other one),
    // so that the loop runs on zipped iterators without index checks.
    let first = 2 * lo + start;
    let cells = row[lo..hi]
        .iter_mut()
        .zip(kind_row[first..].iter().step_by(2))
        .zip(rhs_row[first..].iter().step_by(2))
        .zip(reaction_row[first..].iter().step_by(2));
    let neighbours = mid[lo + start - 1..hi + start - 1]
        .iter()
        .zip(&mid[lo + start..hi + start])
        .zip(up[lo..hi].iter().zip(&down[lo..hi]));
    for ((((slot, &kd), b), &reaction), ((a, e), (u, d))) in cells.zip(neighbours) {
        if kd & UNKNOWN == 0 {
            continue;
        }
        let s = [a[0] + e[0] + u[0] + d[0], a[1] + e[1] + u[1] + d[1]];
        let new = solve2((kd & K_BITS) as f64, reaction, [b[0] + s[0], b[1] + s[1]]);
        if TRACK {
            worst = track(worst, *slot, new);
        }
        *slot = new;
    }
    worst
}

impl Multigrid {
    /// One red-black Gauss–Seidel sweep over the band (local relaxation; `Multigrid::find_band`).
    /// Next to an occluding boundary the solution turns sharply (f, g approach the limb's
    /// values of length 2, where the map's gradient is steep) and the coarse levels,
    /// whose cells beside the fixed ring are fixed themselves, cannot correct it: there the
    /// error fell by only about 0.2 per cycle and held the Jacobi residual, while the interior
    /// was a hundred times below it (a 1024² sphere: the largest residual 3 pixels inside the
    /// rim, 1e-6 there against 1e-8 at 95 % of the radius). A few sweeps over the band, a
    /// fraction of a percent of a sweep's cells, make up for it. The same holds at the edge of
    /// an attached shadow, where the data term ends: under a light at tilt 0°, slant 45° the
    /// last cycles of a 1024² sphere were spent on some twenty cells just inside the shadow
    /// (ten cycles; six with the band). Over 48 lights (8 tilts × slants 20°, 45°, 70°) at
    /// 256² and 512² no solve needed more cycles with the band than without it and most one
    /// fewer; a 256² sphere lit at tilt 90°, slant 60° needed 11 against 7, its third cycle's
    /// residual rising and halving the coarse correction (`RISE`).
    pub(super) fn smooth_band(&mut self, ctx: &Context) {
        let level = &mut self.levels[0];
        let (wp, w) = (level.wp, level.w);
        if level.unknowns > 0 {
            self.work += (self.band[0].len() + self.band[1].len()) as f64 / level.unknowns as f64;
        }
        for list in &self.band {
            for &at in list {
                let at = at as usize;
                let (r, c) = (at / wp, at % wp);
                let target =
                    ctx.fine_target(level.kind[at], level.neighbours(r, c), (r - 1) * w + c - 1);
                level.set_value(r, c, target);
            }
        }
    }

    /// One red-black Gauss–Seidel sweep on level `l`.
    pub(super) fn smooth(&mut self, l: usize, ctx: &Context) {
        self.work += 0.25f64.powi(l as i32);
        self.half_sweep::<false, true>(l, 0, ctx);
        self.half_sweep::<false, true>(l, 1, ctx);
    }

    /// [`Multigrid::smooth`], returning the largest change (NaN counts as infinite): the
    /// coarsest level's relaxation stops on it; elsewhere it is not needed and not tracked.
    pub(super) fn smooth_tracked(&mut self, l: usize, ctx: &Context) -> f64 {
        self.work += 0.25f64.powi(l as i32);
        let a = self.half_sweep::<true, true>(l, 0, ctx);
        let b = self.half_sweep::<true, true>(l, 1, ctx);
        worst_of(a, b)
    }

    /// Updates the cells of colour `colour` on level `l`; returns the largest change if `TRACK`
    /// (else 0). Without `WRITE` (finest level only) the cells are left as they are and only
    /// the change they would make is measured.
    pub(super) fn half_sweep<const TRACK: bool, const WRITE: bool>(
        &mut self,
        l: usize,
        colour: usize,
        ctx: &Context,
    ) -> f64 {
        debug_assert!(WRITE || l == 0);
        let level = &mut self.levels[l];
        let parallel = level.parallel();
        let (wp, hp, hw, w) = (level.wp, level.hp, level.hw, level.w);
        let kind = &level.kind[..];
        let spans = &level.spans[colour][..];
        let (rhs, reaction) = (&level.rhs[..], &level.reaction[..]);
        let [red, black] = &mut level.val;
        let (out, other): (&mut [Pair], &[Pair]) = if colour == 0 {
            (red, black)
        } else {
            (black, red)
        };
        over_rows(out, hw, parallel, |r, row| {
            let (lo, hi) = spans[r];
            if lo >= hi || r == 0 || r + 1 >= hp {
                return 0.0;
            }
            let half = HalfRow {
                hw,
                r,
                start: (r + colour) & 1,
                span: (lo as usize, hi as usize),
            };
            let kind_row = &kind[r * wp..(r + 1) * wp];
            if l == 0 {
                let image_row = &ctx.image[(r - 1) * w..r * w];
                return ctx.fine_row::<TRACK, WRITE>(kind_row, image_row, other, half, row);
            }
            let at = r * wp..(r + 1) * wp;
            let coarse = (&rhs[at.clone()], &reaction[at]);
            coarse_row::<TRACK>(kind_row, coarse, other, half, row)
        })
    }

    /// The finest level's Jacobi residual as `Multigrid::restrict` returns it (the largest
    /// change a red half-sweep would make; the black cells sit at their targets), without the
    /// restriction.
    pub(super) fn red_residual(&mut self, ctx: &Context) -> f64 {
        self.work += 0.5;
        self.half_sweep::<true, false>(0, 0, ctx)
    }

    /// The largest Jacobi residual of the finest level, when it is the only level.
    pub(super) fn residual_only(&self, ctx: &Context) -> f64 {
        let level = &self.levels[0];
        let mut worst = 0.0;
        for r in 1..level.hp - 1 {
            for c in 1..level.wp - 1 {
                let kd = level.kind[r * level.wp + c];
                if kd & UNKNOWN != 0 {
                    let t = ctx.fine_target(kd, level.neighbours(r, c), (r - 1) * level.w + c - 1);
                    worst = track(worst, level.value(r, c), t);
                }
            }
        }
        worst
    }
}
