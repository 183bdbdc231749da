//! Multigrid by aggregation: the preconditioner of the integrable-lm method's linear solves.
//!
//! The model's matrix H couples each pixel's (f, g) to its neighbours' (smoothness) and to the
//! depth around it (integrability). Its smooth modes, in which the orientations and the depth
//! bend together, are what a per-pixel preconditioner leaves to conjugate gradients, and their
//! number grows with the grid. Here H is coarsened by aggregates of 2 × 2 cells of one field
//! (f, g, or one of the depth's four sublattices: central differences do not couple
//! neighbouring depths, so the depths of even and odd columns and rows are separate fields to
//! them), each coarse matrix PᵀAP for P the aggregates' indicators (the entries summed by
//! aggregate, so the coarse stencils stay as compact as the fine ones), and the coarse
//! correction scaled by [`OVER_CORRECTION`] (Blaheta 1986; Vaněk, Mandel & Brezina 1996; Notay
//! 2010 on plain aggregation). One V-cycle (a forward block Gauss–Seidel sweep before the
//! coarse correction, a backward one after, a dense Cholesky solve at the coarsest level) is a
//! symmetric positive definite operator, so it preconditions conjugate gradients. The smoother
//! solves each cell's f and g together: the data term couples them by 4λ·∇R∇Rᵀ, and with f and
//! g relaxed one at a time, ball 041 at λ = 10 took 100 conjugate-gradient iterations a step
//! (the cap) and stopped at the cap of 200 steps after 65 s; solved together, 5–8 a step, and it
//! converges in 64 steps and 5 s.
//!
//! It is the scheme of the Poisson integrator's preconditioner (`integrate/poisson/
//! multigrid.rs`: 2 × 2 aggregates, Galerkin coarse operators, symmetric Gauss–Seidel, the
//! correction scaled by 1.8), which is written for one 5-point Laplacian stored by colour so
//! that its sweeps run on every thread; the coupled model has three fields and the depth's
//! wider stencil, so here the matrix is assembled and coarsened algebraically.
//!
//! Smoothing the aggregates' indicators (smoothed aggregation) was measured first, on a 256²
//! sphere: 6 conjugate-gradient iterations per step in place of 16, but 2.6 s to build each
//! step's hierarchy (its coarse stencils grew to 700 entries a row) against 0.1 s.
//!
//! The hierarchy is planned once per minimisation from the matrix's sparsity pattern, which is
//! the same at every step (the aggregates, every level's pattern, where each entry lands on
//! the next level), and refilled with each step's values ([`Multigrid::fill`]): building it
//! anew at each step, most of that time went to sorting each row's entries by column. The
//! V-cycle's buffers are the caller's ([`Multigrid::scratch`]).
//!
//! Everything runs on one thread in a fixed order: the result does not depend on the thread
//! count.

/// A sparse matrix in compressed rows, columns sorted within each row.
#[derive(Debug, Clone)]
pub(super) struct Csr {
    start: Vec<usize>,
    col: Vec<u32>,
    val: Vec<f64>,
}

impl Csr {
    /// The matrix of `rows` rows whose entries are the sums of the triplets' values at their
    /// (row, column), added in the triplets' order.
    #[cfg(test)]
    pub(super) fn from_triplets(rows: usize, triplets: &[(u32, u32, f64)]) -> Csr {
        let (mut a, entry) = Csr::pattern(rows, |emit| {
            triplets.iter().for_each(|&(r, c, _)| emit(r, c))
        })
        .expect("no stop is requested in tests");
        a.fill(&entry, |emit| triplets.iter().for_each(|t| emit(t.2)));
        a
    }

    /// The matrix of `rows` rows with an entry, 0, at each of the (row, column) positions that
    /// `list` emits (repeats stored once), and the index of each position's entry in the
    /// values. `list` is called twice and must emit the same positions in the same order: the
    /// positions are counted, then bucketed by row, never held as a list of their own (at
    /// 1024² they are tens of millions). `None` when a stop was requested meanwhile.
    fn pattern(rows: usize, list: impl Fn(&mut dyn FnMut(u32, u32))) -> Option<(Csr, Vec<u32>)> {
        // Bucket by row (stable), then sort each row's few entries by column (stable too).
        let mut count = vec![0usize; rows + 1];
        list(&mut |r, _| count[r as usize + 1] += 1);
        if crate::cancel::requested() {
            return None;
        }
        for i in 0..rows {
            count[i + 1] += count[i];
        }
        let total = count[rows];
        let mut next = count.clone();
        let mut bucket = vec![(0u32, 0u32); total];
        let mut k = 0u32;
        list(&mut |r, c| {
            bucket[next[r as usize]] = (c, k);
            next[r as usize] += 1;
            k += 1;
        });
        drop(next);
        if crate::cancel::requested() || k as usize != total {
            return None;
        }
        // Each row sorted, and its distinct columns counted, before the columns are stored:
        // the column list is allocated once at its size.
        let mut distinct = 0;
        for i in 0..rows {
            if i % CANCEL_ROWS == 0 && crate::cancel::requested() {
                return None;
            }
            let row = &mut bucket[count[i]..count[i + 1]];
            row.sort_by_key(|&(c, _)| c);
            distinct += row.len() - row.windows(2).filter(|w| w[0].0 == w[1].0).count();
        }
        let mut start = vec![0; rows + 1];
        let mut col: Vec<u32> = Vec::with_capacity(distinct);
        let mut entry = vec![0u32; total];
        for i in 0..rows {
            for &(c, k) in &bucket[count[i]..count[i + 1]] {
                if col.len() == start[i] || col.last() != Some(&c) {
                    col.push(c);
                }
                entry[k as usize] = (col.len() - 1) as u32;
            }
            start[i + 1] = col.len();
        }
        let val = vec![0.0; col.len()];
        Some((Csr { start, col, val }, entry))
    }

    /// Sets every entry to the sum of the values `list` emits whose index in `entry` points at
    /// it, added in their order (`list` emits them in the order of the positions `entry` was
    /// made from; one that stops early, on a requested stop, leaves the rest 0).
    fn fill(&mut self, entry: &[u32], list: impl FnOnce(&mut dyn FnMut(f64))) {
        self.val.fill(0.0);
        let (val, mut k) = (&mut self.val, 0);
        list(&mut |v| {
            val[entry[k] as usize] += v;
            k += 1;
        });
        debug_assert!(
            k == entry.len() || crate::cancel::requested(),
            "values for another pattern"
        );
    }

    /// The number of rows.
    pub(super) fn rows(&self) -> usize {
        self.start.len() - 1
    }

    /// Row `i`'s columns and values.
    fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.start[i]..self.start[i + 1];
        (&self.col[range.clone()], &self.val[range])
    }

    /// The entry at (`i`, `j`), 0 where none is stored.
    fn get(&self, i: usize, j: usize) -> f64 {
        let (cols, vals) = self.row(i);
        cols.binary_search(&(j as u32)).map_or(0.0, |k| vals[k])
    }

    /// y = A x.
    pub(super) fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        for (i, y) in y.iter_mut().enumerate() {
            let (cols, vals) = self.row(i);
            *y = cols.iter().zip(vals).map(|(&c, v)| v * x[c as usize]).sum();
        }
    }
}

/// Where an unknown sits for the aggregation: its field (f, g, or a sublattice of the depth)
/// and its cell (column, row) at its level.
pub(super) type Place = (u8, u32, u32);

/// Rows at or below which a level is solved directly.
const COARSEST: usize = 500;

/// Rows sorted between two looks for a requested stop ([`crate::cancel`]) while a pattern is
/// planned: the finest pattern of a 1024² picture takes seconds in all.
const CANCEL_ROWS: usize = 1 << 16;

/// Blocks inverted between two looks for a requested stop while the matrix is filled.
const CANCEL_BLOCKS: usize = 1 << 12;

/// The most levels.
const MAX_LEVELS: usize = 12;

/// The factor on each coarse correction: the aggregates' piecewise constants overestimate a
/// smooth error's energy, so their correction falls short, and scaling it makes up part of
/// that (below 2, the cycle stays a contraction in A's norm). On a 128² Laplacian, conjugate
/// gradients take 26 iterations with 1.0, 16 with 1.5, 14 with 1.8.
const OVER_CORRECTION: f64 = 1.8;

/// One level of the hierarchy.
#[derive(Debug)]
struct Level {
    a: Csr,
    /// The smoother's blocks, in the order it visits them.
    blocks: Vec<Block>,
    /// Each row's aggregate on the next level and, for each of A's stored entries, its entry
    /// in the next level's matrix (none at the coarsest).
    coarse: Option<(Vec<u32>, Vec<u32>)>,
}

/// An aggregation hierarchy for the symmetric positive semi-definite matrices of one sparsity
/// pattern: planned once from the pattern (the aggregates, every level's pattern and where
/// each entry goes on the next), then [`Multigrid::fill`]ed with each matrix's values, so that
/// a minimisation whose steps share a pattern sorts it once.
#[derive(Debug)]
pub(super) struct Multigrid {
    levels: Vec<Level>,
    /// Where each position of the finest pattern lands among its entries.
    entry: Vec<u32>,
    /// The coarsest matrix's Cholesky factor L (row-major, lower triangle).
    factor: Vec<f64>,
}

impl Multigrid {
    /// The hierarchy for matrices of `rows` rows with entries at the (row, column) `positions`
    /// (symmetric, the diagonal among them), whose unknowns sit at `places`; its values are 0
    /// until [`Multigrid::fill`]. `None` when a stop was requested meanwhile ([`crate::cancel`]).
    pub(super) fn plan(
        rows: usize,
        positions: impl Fn(&mut dyn FnMut(u32, u32)),
        places: Vec<Place>,
    ) -> Option<Multigrid> {
        let (mut a, entry) = Csr::pattern(rows, positions)?;
        let mut places = places;
        let mut levels = Vec::new();
        loop {
            let (aggregate, coarse_places) = aggregate(&places);
            // At the coarsest size, or where coarsening stalls (a thin domain): solve here,
            // by its factor, with no smoother.
            if a.rows() <= COARSEST
                || levels.len() + 1 == MAX_LEVELS
                || coarse_places.len() * 5 > a.rows() * 4
            {
                levels.push(Level {
                    a,
                    blocks: Vec::new(),
                    coarse: None,
                });
                return Some(Multigrid {
                    levels,
                    entry,
                    factor: Vec::new(),
                });
            }
            // PᵀAP for P the aggregates' indicators: the entries summed by aggregate.
            let positions = |emit: &mut dyn FnMut(u32, u32)| {
                for (i, &ai) in aggregate.iter().enumerate() {
                    for &c in a.row(i).0 {
                        emit(ai, aggregate[c as usize]);
                    }
                }
            };
            let (coarse, scatter) = Csr::pattern(coarse_places.len(), positions)?;
            levels.push(Level {
                blocks: blocks(&places),
                a,
                coarse: Some((aggregate, scatter)),
            });
            a = coarse;
            places = coarse_places;
        }
    }

    /// Sets the finest matrix to the sums of the values `list` emits at the planned positions
    /// (in their order), and every coarser level, smoother and factor from it.
    pub(super) fn fill(&mut self, list: impl FnOnce(&mut dyn FnMut(f64))) {
        // A requested stop ends the filling where it is (the caller's step then lowers
        // nothing and its loop stops on the same flag): at 1024² the whole fill is a few
        // hundred milliseconds.
        self.levels[0].a.fill(&self.entry, list);
        for l in 0..self.levels.len() {
            let (fine, coarser) = self.levels.split_at_mut(l + 1);
            let level = &mut fine[l];
            for (i, block) in level.blocks.iter_mut().enumerate() {
                if i % CANCEL_BLOCKS == 0 && crate::cancel::requested() {
                    return;
                }
                block.invert(&level.a);
            }
            match (&level.coarse, coarser.first_mut()) {
                (Some((_, scatter)), Some(next)) => {
                    next.a
                        .fill(scatter, |emit| level.a.val.iter().for_each(|&v| emit(v)));
                }
                _ => self.factor = cholesky(&level.a),
            }
        }
    }

    /// Buffers for [`Multigrid::apply`], three per level: its residual (on every level but the
    /// coarsest), and its right-hand side and solution (on every level but the finest, whose
    /// are the caller's).
    pub(super) fn scratch(&self) -> Vec<[Vec<f64>; 3]> {
        self.levels
            .iter()
            .enumerate()
            .map(|(l, level)| {
                let n = level.a.rows();
                let residual = if level.coarse.is_some() { n } else { 0 };
                let own = if l > 0 { n } else { 0 };
                [vec![0.0; residual], vec![0.0; own], vec![0.0; own]]
            })
            .collect()
    }

    /// x = one V-cycle applied to `b` from 0, in the buffers of [`Multigrid::scratch`].
    pub(super) fn apply(&self, b: &[f64], x: &mut [f64], scratch: &mut [[Vec<f64>; 3]]) {
        self.cycle(0, b, x, scratch);
    }

    fn cycle(&self, l: usize, b: &[f64], x: &mut [f64], scratch: &mut [[Vec<f64>; 3]]) {
        let level = &self.levels[l];
        let Some((aggregate, _)) = &level.coarse else {
            x.copy_from_slice(b);
            cholesky_solve(&self.factor, x);
            return;
        };
        x.fill(0.0);
        gauss_seidel(level, b, x, false);
        // Level l's buffers: its residual, and its right-hand side and solution (below the
        // finest).
        let (here, below) = scratch.split_at_mut(l + 1);
        let residual = &mut here[l][0];
        let [_, coarse_b, coarse_x] = &mut below[0];
        level.a.mul_vec(x, residual);
        coarse_b.fill(0.0);
        for ((res, b), &t) in residual.iter().zip(b).zip(aggregate) {
            coarse_b[t as usize] += b - res;
        }
        let coarse_b = std::mem::take(coarse_b);
        let mut coarse_x = std::mem::take(coarse_x);
        self.cycle(l + 1, &coarse_b, &mut coarse_x, scratch);
        for (x, &t) in x.iter_mut().zip(aggregate) {
            *x += OVER_CORRECTION * coarse_x[t as usize];
        }
        scratch[l + 1][1] = coarse_b;
        scratch[l + 1][2] = coarse_x;
        gauss_seidel(level, b, x, true);
    }
}

/// A block of the smoother: one unknown, or a cell's f and g together (the data term couples
/// them, strongly at a large λ), with the inverse of A's block.
#[derive(Debug, Clone, Copy)]
struct Block {
    rows: [u32; 2],
    pair: bool,
    /// The inverse [a, b, c] of the symmetric block (a alone for one unknown).
    inverse: [f64; 3],
}

impl Block {
    /// The inverse of `a`'s block at the block's rows.
    fn invert(&mut self, a: &Csr) {
        let [i, j] = self.rows.map(|r| r as usize);
        let d = a.get(i, i);
        self.inverse = if !self.pair {
            [1.0 / d, 0.0, 0.0]
        } else {
            let (b, c) = (a.get(i, j), a.get(j, j));
            let det = d * c - b * b;
            if det > 0.0 {
                [c / det, -b / det, d / det]
            } else {
                // Not positive definite in floating point: the two diagonals alone.
                [1.0 / d, 0.0, 1.0 / c]
            }
        };
    }
}

/// The smoother's blocks (to be inverted): each place of field 0 (f) with the place of field 1
/// (g) at its cell, every other unknown alone; in the order of their first rows.
fn blocks(places: &[Place]) -> Vec<Block> {
    let mut partner = vec![u32::MAX; places.len()];
    let mut g_rows: Vec<(u32, u32, usize)> = places
        .iter()
        .enumerate()
        .filter(|(_, p)| p.0 == 1)
        .map(|(i, p)| (p.1, p.2, i))
        .collect();
    g_rows.sort_unstable();
    for (i, p) in places.iter().enumerate() {
        if p.0 == 0 {
            if let Ok(k) = g_rows.binary_search_by_key(&(p.1, p.2), |&(x, y, _)| (x, y)) {
                let j = g_rows[k].2;
                partner[i] = j as u32;
                partner[j] = i as u32;
            }
        }
    }
    let mut out = Vec::with_capacity(places.len());
    for (i, &other) in partner.iter().enumerate() {
        let j = other as usize;
        if other != u32::MAX && j < i {
            continue;
        }
        let pair = other != u32::MAX;
        out.push(Block {
            rows: [i as u32, if pair { j as u32 } else { i as u32 }],
            pair,
            inverse: [0.0; 3],
        });
    }
    out
}

/// One block Gauss–Seidel sweep on A x = b, forward or backward (its adjoint).
fn gauss_seidel(level: &Level, b: &[f64], x: &mut [f64], backward: bool) {
    let sweep = |block: &Block, x: &mut [f64]| {
        let [i, j] = block.rows.map(|r| r as usize);
        // b − A x over the unknowns outside the block.
        let rest = |r: usize, x: &[f64]| {
            let (cols, vals) = level.a.row(r);
            let mut s = b[r];
            for (&c, v) in cols.iter().zip(vals) {
                let c = c as usize;
                if c != i && c != j {
                    s -= v * x[c];
                }
            }
            s
        };
        let [p, q, r] = block.inverse;
        if block.pair {
            let (si, sj) = (rest(i, x), rest(j, x));
            x[i] = p * si + q * sj;
            x[j] = q * si + r * sj;
        } else {
            x[i] = p * rest(i, x);
        }
    };
    if backward {
        level.blocks.iter().rev().for_each(|block| sweep(block, x));
    } else {
        level.blocks.iter().for_each(|block| sweep(block, x));
    }
}

/// The aggregates of 2 × 2 cells of one field: the tentative prolongation (each unknown's
/// aggregate) and the aggregates' places.
fn aggregate(places: &[Place]) -> (Vec<u32>, Vec<Place>) {
    let coarse: Vec<Place> = places.iter().map(|&(f, x, y)| (f, x / 2, y / 2)).collect();
    let mut order: Vec<usize> = (0..places.len()).collect();
    order.sort_by_key(|&i| coarse[i]);
    let (mut tentative, mut coarse_places) = (vec![0; places.len()], Vec::new());
    for i in order {
        if coarse_places.last() != Some(&coarse[i]) {
            coarse_places.push(coarse[i]);
        }
        tentative[i] = (coarse_places.len() - 1) as u32;
    }
    (tentative, coarse_places)
}

/// The dense Cholesky factor of `a`; a pivot below 1e-12 of the largest diagonal entry is
/// raised to it (the matrix may be singular along the depth's constant).
fn cholesky(a: &Csr) -> Vec<f64> {
    let n = a.rows();
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        let (cols, vals) = a.row(i);
        for (&c, &v) in cols.iter().zip(vals) {
            l[i * n + c as usize] = v;
        }
    }
    let largest = (0..n).map(|i| l[i * n + i]).fold(0.0f64, f64::max);
    let floor = 1e-12 * largest.max(f64::MIN_POSITIVE);
    for j in 0..n {
        let mut d = l[j * n + j];
        for k in 0..j {
            d -= l[j * n + k] * l[j * n + k];
        }
        let d = d.max(floor).sqrt();
        l[j * n + j] = d;
        for i in j + 1..n {
            let mut s = l[i * n + j];
            for k in 0..j {
                s -= l[i * n + k] * l[j * n + k];
            }
            l[i * n + j] = s / d;
        }
    }
    l
}

/// Solves L Lᵀ x = b in place.
fn cholesky_solve(l: &[f64], x: &mut [f64]) {
    let n = x.len();
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i * n + k] * x[k]).sum();
        x[i] = (x[i] - s) / l[i * n + i];
    }
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k * n + i] * x[k]).sum();
        x[i] = (x[i] - s) / l[i * n + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 5-point Laplacian of a w × h grid with a diagonal shift, its places one field.
    fn laplacian(w: usize, h: usize, shift: f64) -> (Csr, Vec<Place>) {
        let mut t = Vec::new();
        let id = |x: usize, y: usize| (y * w + x) as u32;
        for y in 0..h {
            for x in 0..w {
                t.push((id(x, y), id(x, y), 4.0 + shift));
                for (dx, dy) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < w && (ny as usize) < h {
                        t.push((id(x, y), id(nx as usize, ny as usize), -1.0));
                    }
                }
            }
        }
        let places = (0..h)
            .flat_map(|y| (0..w).map(move |x| (0u8, x as u32, y as u32)))
            .collect();
        (Csr::from_triplets(w * h, &t), places)
    }

    /// The hierarchy of `a`: planned for its pattern and filled with its values.
    fn hierarchy(a: &Csr, places: Vec<Place>) -> Multigrid {
        let positions = |emit: &mut dyn FnMut(u32, u32)| {
            for i in 0..a.rows() {
                a.row(i).0.iter().for_each(|&c| emit(i as u32, c));
            }
        };
        let mut mg =
            Multigrid::plan(a.rows(), positions, places).expect("no stop is requested in tests");
        mg.fill(|emit| a.val.iter().for_each(|&v| emit(v)));
        mg
    }

    /// A hierarchy planned once and filled with another matrix of the same pattern is the one
    /// planned for that matrix: the same V-cycle to the bit, at every level.
    #[test]
    fn a_refilled_hierarchy_is_the_matrixs_own() {
        let (first, places) = laplacian(70, 50, 0.5);
        let (second, _) = laplacian(70, 50, 0.01);
        // The second's values made uneven, so that no level is the first's scaled.
        let mut second = second;
        for (k, v) in second.val.iter_mut().enumerate() {
            if second.col[k] as usize == second.start.partition_point(|&s| s <= k) - 1 {
                *v += (k % 5) as f64 * 0.1;
            }
        }
        let mut refilled = hierarchy(&first, places.clone());
        refilled.fill(|emit| second.val.iter().for_each(|&v| emit(v)));
        let own = hierarchy(&second, places);
        assert!(own.levels.len() >= 3);
        for (a, b) in refilled.levels.iter().zip(&own.levels) {
            assert_eq!(a.a.val, b.a.val);
        }
        assert_eq!(refilled.factor, own.factor);
        let b: Vec<f64> = (0..second.rows()).map(|i| (i as f64 * 0.3).sin()).collect();
        let (mut x, mut y) = (vec![0.0; b.len()], vec![0.0; b.len()]);
        refilled.apply(&b, &mut x, &mut refilled.scratch());
        own.apply(&b, &mut y, &mut own.scratch());
        assert_eq!(x, y);
    }

    /// Triplets at one place are summed, rows and columns land where they say, and the
    /// product with a vector is the dense one.
    #[test]
    fn triplets_make_the_matrix() {
        let a = Csr::from_triplets(2, &[(1, 2, 1.0), (0, 0, 2.0), (1, 2, 3.0), (0, 1, -1.0)]);
        assert_eq!(a.row(0), (&[0u32, 1][..], &[2.0, -1.0][..]));
        assert_eq!(a.row(1), (&[2u32][..], &[4.0][..]));
        let mut y = vec![0.0; 2];
        a.mul_vec(&[1.0, 2.0, 3.0], &mut y);
        assert_eq!(y, vec![0.0, 12.0]);
    }

    /// The dense coarsest solve is exact.
    #[test]
    fn cholesky_solves() {
        let (a, _) = laplacian(5, 4, 0.1);
        let l = cholesky(&a);
        let want: Vec<f64> = (0..20).map(|i| (i as f64 * 0.7).sin()).collect();
        let mut x = vec![0.0; 20];
        a.mul_vec(&want, &mut x);
        cholesky_solve(&l, &mut x);
        for (x, w) in x.iter().zip(&want) {
            assert!((x - w).abs() < 1e-12, "{x} against {w}");
        }
    }

    /// Conjugate gradients on A x = b from 0 to a relative residual of 1e-8, preconditioned
    /// by `m`; the iterations.
    fn pcg(a: &Csr, b: &[f64], m: impl FnMut(&[f64], &mut [f64])) -> usize {
        let n = b.len();
        let (mut r, mut x, mut p, mut q) = (b.to_vec(), vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        let stop = crate::conjugate_gradients::Stop {
            tol: 1e-8,
            max_iter: 2000,
        };
        let apply = |v: &[f64], out: &mut [f64]| a.mul_vec(v, out);
        crate::conjugate_gradients::solve(apply, m, &mut r, &mut x, [&mut p, &mut q], stop)
            .iterations
    }

    /// Preconditioned by one V-cycle, conjugate gradients solve a Laplacian in a number of
    /// iterations that barely grows with the grid (4 × the unknowns at most 1.5 × the
    /// iterations), and in a fraction of what the diagonal takes.
    #[test]
    fn v_cycles_make_the_iterations_almost_independent_of_the_grid() {
        let mut counts = Vec::new();
        for side in [64, 128] {
            let (a, places) = laplacian(side, side, 1e-6);
            let b: Vec<f64> = (0..side * side)
                .map(|i| ((i % side) as f64 * 0.1).cos() + ((i / side) as f64 * 0.07).sin())
                .collect();
            let mg = hierarchy(&a, places);
            assert!(mg.levels.len() >= 3);
            let mut scratch = mg.scratch();
            let with = pcg(&a, &b, |r, z| mg.apply(r, z, &mut scratch));
            let jacobi = pcg(&a, &b, |r, z| {
                z.iter_mut().zip(r).for_each(|(z, r)| *z = r / (4.0 + 1e-6))
            });
            assert!(4 * with < jacobi, "{side}²: {with} against {jacobi}");
            counts.push(with);
        }
        assert!(2 * counts[1] <= 3 * counts[0], "{counts:?}");
    }

    /// Two fields on a 64² grid, each a Laplacian, coupled at every cell by κ·vvᵀ with v
    /// turning across the grid (the data term's 4λ·∇R∇Rᵀ at a large λ). The smoother pairs
    /// each cell's two unknowns with the exact inverse of their block, and at κ = 1e4 conjugate
    /// gradients preconditioned by the V-cycle take at most half the iterations they take when
    /// the two are relaxed one at a time (the second field's places moved off the first's
    /// cells, so that nothing pairs; measured 65 against 576).
    #[test]
    fn cells_with_stiff_coupled_blocks_are_smoothed_together() {
        let side = 64;
        let n = side * side;
        let kappa = 1e4;
        let (lap, cells) = laplacian(side, side, 1e-6);
        let mut t = Vec::new();
        for field in 0..2u32 {
            let o = field * n as u32;
            for i in 0..n {
                let (cols, vals) = lap.row(i);
                t.extend(
                    cols.iter()
                        .zip(vals)
                        .map(|(&c, &v)| (i as u32 + o, c + o, v)),
                );
            }
        }
        for i in 0..n {
            let angle = (i % side) as f64 * 0.05 + (i / side) as f64 * 0.03;
            let v = [angle.cos(), angle.sin()];
            for a in 0..2 {
                for b in 0..2 {
                    let (r, c) = ((a * n + i) as u32, (b * n + i) as u32);
                    t.push((r, c, kappa * v[a] * v[b]));
                }
            }
        }
        let a = Csr::from_triplets(2 * n, &t);
        let rhs: Vec<f64> = (0..2 * n).map(|i| ((i % 97) as f64 * 0.1).sin()).collect();
        let iterations = |offset: u32| {
            let places: Vec<Place> = cells
                .iter()
                .map(|&(_, x, y)| (0, x, y))
                .chain(cells.iter().map(|&(_, x, y)| (1, x + offset, y)))
                .collect();
            let mg = hierarchy(&a, places);
            let mut scratch = mg.scratch();
            (pcg(&a, &rhs, |r, z| mg.apply(r, z, &mut scratch)), mg)
        };
        let (paired, mg) = iterations(0);
        let block = mg.levels[0].blocks[5];
        assert!(block.pair && block.rows == [5, (n + 5) as u32]);
        let (aa, ab, bb) = (a.get(5, 5), a.get(5, n + 5), a.get(n + 5, n + 5));
        let [p, q, r] = block.inverse;
        for (x, want) in [
            (aa * p + ab * q, 1.0),
            (aa * q + ab * r, 0.0),
            (ab * q + bb * r, 1.0),
        ] {
            assert!((x - want).abs() < 1e-9, "{x} against {want}");
        }
        let (alone, mg) = iterations(1 << 20);
        assert!(mg.levels[0].blocks.iter().all(|b| !b.pair));
        assert!(2 * paired <= alone, "{paired} paired against {alone} alone");
    }

    /// The V-cycle is symmetric: uᵀM⁻¹v = vᵀM⁻¹u.
    #[test]
    fn the_cycle_is_symmetric() {
        let (a, places) = laplacian(40, 30, 0.01);
        let mg = hierarchy(&a, places);
        let mut scratch = mg.scratch();
        let n = 1200;
        let u: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let v: Vec<f64> = (0..n).map(|i| ((i * 53) % 7) as f64 - 3.0).collect();
        let (mut mu, mut mv) = (vec![0.0; n], vec![0.0; n]);
        mg.apply(&u, &mut mu, &mut scratch);
        mg.apply(&v, &mut mv, &mut scratch);
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
        let (x, y) = (dot(&v, &mu), dot(&u, &mv));
        assert!((x - y).abs() <= 1e-9 * x.abs().max(1.0), "{x} against {y}");
    }
}
