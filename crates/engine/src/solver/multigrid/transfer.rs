//! Moving between levels: residuals and reaction matrices restricted to the coarser level,
//! corrections prolongated back.

use super::*;

/// The half-open range of padded columns that holds every unknown of padded row `r` of a level
/// with colour spans `spans` (empty: (0, 0)).
#[inline]
pub(super) fn unknown_columns(spans: &[Vec<(u32, u32)>; 2], r: usize) -> (usize, usize) {
    let (mut lo, mut hi) = (usize::MAX, 0);
    for (colour, spans) in spans.iter().enumerate() {
        let (a, b) = spans[r];
        if a < b {
            let start = (r + colour) & 1;
            lo = lo.min(2 * a as usize + start);
            hi = hi.max(2 * (b as usize - 1) + start + 1);
        }
    }
    if lo < hi {
        (lo, hi)
    } else {
        (0, 0)
    }
}

/// The residual (k-scaled) of unknown cell (r, c) on coarse level `level`, and its reaction
/// matrix: the straightforward version of what `restrict_coarse_row` sums (its reference in
/// the tests).
#[cfg(test)]
pub(super) fn residual_at(level: &Level, r: usize, c: usize, kd: u8) -> (Pair, Sym) {
    let s = level.neighbours(r, c);
    let u = level.value(r, c);
    let k = (kd & K_BITS) as f64;
    let at = r * level.wp + c;
    let (b, a) = (level.rhs[at], level.reaction[at]);
    let res = [
        b[0] + s[0] - (k + a[0]) * u[0] - a[1] * u[1],
        b[1] + s[1] - a[1] * u[0] - (k + a[2]) * u[1],
    ];
    (res, a)
}

/// The coarse part of `Multigrid::restrict` (level `fine` ≥ 1) for coarse padded row `r`
/// (kinds `ckind_row`, unknowns in the columns `span`): the residuals of the unknown children
/// of each coarse unknown summed into `rhs_row`, and their reaction matrices into
/// `reaction_row` if `with_reaction`. Cells that are not unknowns are left as they are (no
/// sweep, residual or restriction reads them).
///
/// The same sums as [`residual_at`] over the children in the order of `children`, with the
/// rows of each colour cut once: in fine row fr, the child in column 2c − 1 is cell c − 1 of
/// colour (fr + 1) mod 2, the child in column 2c cell c of colour fr mod 2, and each one's
/// left and right neighbours are cells c − 1 and c of the other colour's row.
#[inline(never)]
pub(super) fn restrict_coarse_row<'a>(
    fine: &'a Level,
    ckind_row: &[u8],
    span: (usize, usize),
    r: usize,
    rhs_row: &mut [Pair],
    reaction_row: &mut [Sym],
    with_reaction: bool,
) {
    let (fwp, hw) = (fine.wp, fine.hw);
    let (lo, hi) = span;
    if lo >= hi {
        return;
    }
    // The two fine rows, cut once: kinds, right-hand sides and reaction matrices (padded
    // columns), and the rows above, at and below of each colour, x that of column 2c − 1 and y
    // that of column 2c. A row past the last (the padding, never unknown) is left out.
    let rows = [2 * r - 1, 2 * r].map(|fr| {
        (fr <= fine.h).then(|| {
            let (x, y) = (&fine.val[(fr + 1) & 1], &fine.val[fr & 1]);
            let three = |v: &'a [Pair]| -> [&'a [Pair]; 3] {
                [
                    &v[(fr - 1) * hw..fr * hw],
                    &v[fr * hw..(fr + 1) * hw],
                    &v[(fr + 1) * hw..(fr + 2) * hw],
                ]
            };
            let cells = fr * fwp..(fr + 1) * fwp;
            (
                &fine.kind[cells.clone()],
                &fine.rhs[cells.clone()],
                &fine.reaction[cells],
                three(x),
                three(y),
            )
        })
    });
    for c in lo..hi {
        if ckind_row[c] & UNKNOWN == 0 {
            continue;
        }
        let mut res = [0.0; 2];
        let mut react = [0.0; 3];
        for &(kind, rhs, reaction, x, y) in rows.iter().flatten() {
            for child in 0..2 {
                let fc = 2 * c - 1 + child;
                let kd = kind[fc];
                if kd & UNKNOWN == 0 {
                    continue;
                }
                // The child's own colour, the other colour and its index in their rows.
                let (own, [up, mid, down], j) = if child == 0 { (x, y, c - 1) } else { (y, x, c) };
                let (a, b) = (mid[c - 1], mid[c]);
                let (t, d) = (up[j], down[j]);
                let s = [a[0] + b[0] + t[0] + d[0], a[1] + b[1] + t[1] + d[1]];
                let u = own[1][j];
                let k = (kd & K_BITS) as f64;
                let (bb, m) = (rhs[fc], reaction[fc]);
                res[0] += bb[0] + s[0] - (k + m[0]) * u[0] - m[1] * u[1];
                res[1] += bb[1] + s[1] - m[1] * u[0] - (k + m[2]) * u[1];
                if with_reaction {
                    react[0] += m[0];
                    react[1] += m[1];
                    react[2] += m[2];
                }
            }
        }
        rhs_row[c] = res;
        if with_reaction {
            reaction_row[c] = react;
        }
    }
}

/// The finest level's part of `Multigrid::restrict` for coarse padded row `r` (kinds
/// `ckind_row`): the residuals and reaction matrices of the fine unknowns summed into
/// `rhs_row` and `reaction_row` over the children of each coarse unknown; returns the largest
/// Jacobi residual of the fine row pair.
///
/// The last thing done on the finest level is a full red-black sweep, which leaves every black
/// cell exactly at its Jacobi target (the same function of the same red values): its residual
/// is zero, bit for bit, and is not evaluated. Its reaction matrix is taken as its red
/// neighbours' (the red children's sum scaled by unknown children / red unknown children). The
/// map is evaluated a block of red cells at a time, with its Hessian for the curvature term.
pub(super) fn restrict_fine_row(
    ctx: &Context,
    fine: &Level,
    ckind_row: &[u8],
    r: usize,
    rhs_row: &mut [Pair],
    reaction_row: &mut [Sym],
) -> f64 {
    let (fwp, hw, w) = (fine.wp, fine.hw, fine.w);
    let cwp = ckind_row.len();
    let mut worst = 0.0;
    let mut samples = [Sample::ZERO; BLOCK];
    let mut hessians: [Hessian; BLOCK] = [[0.0; 3]; BLOCK];
    let mut c0 = 1;
    while c0 + 1 < cwp {
        let n = BLOCK.min(cwp - 1 - c0);
        let mut res = [[0.0; 2]; BLOCK];
        let mut react = [[0.0; 3]; BLOCK];
        let mut evaluated = [0u8; BLOCK];
        for fr in [2 * r - 1, 2 * r] {
            if fr > fine.h {
                continue;
            }
            // Red cells have (fr + fc) even: the red child of coarse column c is fine column
            // 2c − odd, index j = c − odd in the red row.
            let odd = fr & 1;
            let j0 = c0 - odd;
            let (lo, hi) = fine.span(0, fr);
            if hi <= j0 || j0 + n <= lo {
                continue;
            }
            let kind_row = &fine.kind[fr * fwp..(fr + 1) * fwp];
            let u = Averages::of(ctx, kind_row, &fine.val[1], hw, fr, odd, j0, n);
            ctx.reflectance.fg_hessian_batch(
                &u.f[..n],
                &u.g[..n],
                &mut samples[..n],
                &mut hessians[..n],
            );
            let image_row = &ctx.image[(fr - 1) * w..fr * w];
            let values = &fine.val[0][fr * hw..(fr + 1) * hw];
            for i in 0..n {
                let j = j0 + i;
                let fc = 2 * j + odd;
                let kd = kind_row[fc];
                if kd & UNKNOWN == 0 {
                    continue;
                }
                let intensity = image_row[fc - 1];
                let sample = &samples[i];
                let t = ctx.fine_update(kd, [u.f[i], u.g[i]], intensity, sample);
                let v = values[j];
                worst = track(worst, v, t);
                let k = (kd & K_BITS) as f64;
                let d = [k * (t[0] - v[0]), k * (t[1] - v[1])];
                let a = if kd & LIT != 0 {
                    let (d1, d2) = (sample.d1, sample.d2);
                    let gauss_newton = [ctx.data * d1 * d1, ctx.data * d1 * d2, ctx.data * d2 * d2];
                    ctx.with_curvature(intensity - sample.value, &hessians[i], gauss_newton)
                } else {
                    [0.0; 3]
                };
                res[i] = [res[i][0] + d[0], res[i][1] + d[1]];
                react[i] = [react[i][0] + a[0], react[i][1] + a[1], react[i][2] + a[2]];
                evaluated[i] += 1;
            }
        }
        for i in 0..n {
            let c = c0 + i;
            if ckind_row[c] & UNKNOWN == 0 {
                rhs_row[c] = [0.0; 2];
                reaction_row[c] = [0.0; 3];
                continue;
            }
            let mut a = react[i];
            if evaluated[i] > 0 && evaluated[i] < 4 {
                let (top, bottom) = ((2 * r - 1) * fwp + 2 * c - 1, 2 * r * fwp + 2 * c - 1);
                let unknown = fine.kind[top..top + 2]
                    .iter()
                    .chain(&fine.kind[bottom..bottom + 2])
                    .filter(|&&kd| kd & UNKNOWN != 0)
                    .count();
                if usize::from(evaluated[i]) < unknown {
                    let scale = unknown as f64 / f64::from(evaluated[i]);
                    a = [a[0] * scale, a[1] * scale, a[2] * scale];
                }
            }
            rhs_row[c] = res[i];
            reaction_row[c] = a;
        }
        c0 += n;
    }
    worst
}

impl Multigrid {
    /// Restricts the residual and the reaction matrices of level `l` to level `l + 1` (sums over
    /// the unknown children) and zeroes the correction there. On the finest level, returns the
    /// largest residual divided by k, the Jacobi residual (0 on the others).
    pub(super) fn restrict(&mut self, l: usize, ctx: &Context) -> f64 {
        // On the finest level only the red half is evaluated (see below).
        self.work += 0.25f64.powi(l as i32) * if l == 0 { 0.5 } else { 1.0 };
        if l + 1 >= self.used {
            return self.residual_only(ctx);
        }
        let (pre_sweeps, used) = (self.schedule.pre_sweeps, self.used);
        let (upper, lower) = self.levels.split_at_mut(l + 1);
        let fine = &upper[l];
        let coarse = &mut lower[0];
        let parallel = fine.parallel();
        let (cwp, chp) = (coarse.wp, coarse.hp);
        // The correction starts from zero. The red half of the first pre-sweep overwrites every
        // red unknown unread, and the red cells that are not unknowns are never written (they
        // stay at the zero of `setup`), so only the black cells are cleared, unless no
        // pre-sweep comes first or the level is the coarsest, whose tracked sweeps compare
        // with the old values.
        let clear_red = pre_sweeps == 0 || l + 2 == used;
        for v in coarse.val[usize::from(!clear_red)..].iter_mut() {
            v.fill([0.0; 2]);
        }
        // The reaction matrices of level 1 follow the fine values (restricted every time);
        // coarser ones once per cycle (see `Level::reaction_current`).
        let with_reaction = l == 0 || !coarse.reaction_current;
        if l == 0 {
            for level in lower.iter_mut().skip(1) {
                level.reaction_current = false;
            }
        } else {
            lower[0].reaction_current = true;
        }
        let coarse = &mut lower[0];
        let ckind = &coarse.kind[..];
        let cspans = &coarse.spans;
        let body = |(r, (rhs_row, reaction_row)): (usize, (&mut [Pair], &mut [Sym]))| {
            if r == 0 || r + 1 >= chp {
                return 0.0;
            }
            if l == 0 {
                let ckind_row = &ckind[r * cwp..(r + 1) * cwp];
                return restrict_fine_row(ctx, fine, ckind_row, r, rhs_row, reaction_row);
            }
            // Coarser levels: nobody reads their largest residual.
            let ckind_row = &ckind[r * cwp..(r + 1) * cwp];
            let span = unknown_columns(cspans, r);
            restrict_coarse_row(
                fine,
                ckind_row,
                span,
                r,
                rhs_row,
                reaction_row,
                with_reaction,
            );
            0.0
        };
        if parallel {
            crate::parallel::reduce(
                coarse
                    .rhs
                    .par_chunks_mut(cwp)
                    .zip(coarse.reaction.par_chunks_mut(cwp))
                    .enumerate()
                    .with_min_len((TASK_CELLS / (4 * cwp)).max(1))
                    .map(body),
                0.0,
                worst_of,
            )
        } else {
            coarse
                .rhs
                .chunks_mut(cwp)
                .zip(coarse.reaction.chunks_mut(cwp))
                .enumerate()
                .map(body)
                .fold(0.0, worst_of)
        }
    }

    /// Adds the correction of level `l + 1`, interpolated bilinearly, to the unknowns of level
    /// `l`.
    pub(super) fn prolongate(&mut self, l: usize, scale: f64) {
        self.work += 0.25f64.powi(l as i32) * 0.5;
        let first = usize::from(self.schedule.post_sweeps > 0);
        let (upper, lower) = self.levels.split_at_mut(l + 1);
        let fine = &mut upper[l];
        let coarse = &mut lower[0];
        let parallel = fine.parallel();
        let (wp, hp, hw) = (fine.wp, fine.hp, fine.hw);
        let kind = &fine.kind[..];
        let (cwp, chw) = (coarse.wp, coarse.hw);
        // The coarse correction in plain row-major order (column q of row r, from colour
        // (r + q) mod 2), put in the coarse right-hand side, which the coarse cycle has
        // finished with (the next restriction writes it again): the loop below then reads
        // neighbouring columns without choosing a colour for each.
        let Level { val, rhs, .. } = coarse;
        over_rows(rhs, cwp, coarse.unknowns >= PARALLEL_MIN_CELLS, |r, row| {
            let (a, b) = (
                &val[r & 1][r * chw..(r + 1) * chw],
                &val[(r + 1) & 1][r * chw..(r + 1) * chw],
            );
            for (k, pair) in row.chunks_mut(2).enumerate() {
                pair[0] = a[k];
                if let Some(odd) = pair.get_mut(1) {
                    *odd = b[k];
                }
            }
            0.0
        });
        let merged = &coarse.rhs[..];
        let ckind = &coarse.kind[..];
        // The first post-sweep's red half moves every red unknown to a value computed from its
        // black neighbours alone, so a correction added to the red cells would be overwritten
        // unread: only the black cells are corrected when a post-sweep follows (always, in the
        // solver's schedule).
        for colour in first..2 {
            let spans = &fine.spans[colour][..];
            over_rows(&mut fine.val[colour], hw, parallel, |r, row| {
                let (lo, hi) = spans[r];
                if lo >= hi || r == 0 || r + 1 >= hp {
                    return 0.0;
                }
                let start = (r + colour) & 1;
                // The parent row, and the coarse row on this fine row's side of it.
                let pr = ((r - 1) >> 1) + 1;
                let nr = if (r - 1) & 1 == 0 { pr - 1 } else { pr + 1 };
                let kind_row = &kind[r * wp..(r + 1) * wp];
                let (pk, nk) = (
                    &ckind[pr * cwp..(pr + 1) * cwp],
                    &ckind[nr * cwp..(nr + 1) * cwp],
                );
                let (pv, nv) = (
                    &merged[pr * cwp..(pr + 1) * cwp],
                    &merged[nr * cwp..(nr + 1) * cwp],
                );
                // Cell c = 2j + start: its parent column is j + start, the coarse column on
                // its side j + 1 − start.
                let (dp, dn) = (start, 1 - start);
                for j in lo as usize..hi as usize {
                    if kind_row[2 * j + start] & UNKNOWN == 0 {
                        continue;
                    }
                    let (pc, nc) = (j + dp, j + dn);
                    let p = pv[pc];
                    let pick = |kind: u8, v: Pair| if kind & IN_DOMAIN != 0 { v } else { p };
                    let x = pick(pk[nc], pv[nc]);
                    let y = pick(nk[pc], nv[pc]);
                    let d = pick(nk[nc], nv[nc]);
                    let slot = &mut row[j];
                    // × 1/16 is exact, as the division by 16 was.
                    slot[0] += scale * (9.0 * p[0] + 3.0 * (x[0] + y[0]) + d[0]) * 0.0625;
                    slot[1] += scale * (9.0 * p[1] + 3.0 * (x[1] + y[1]) + d[1]) * 0.0625;
                }
                0.0
            });
        }
    }
}
