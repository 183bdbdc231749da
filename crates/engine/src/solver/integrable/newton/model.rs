//! The linearised model of E at a point: the matrix (H + ν·diag H) applied and assembled, and its
//! damped linear solve.

use super::*;

/// One pixel's part of the model.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Block {
    /// The (f, g) diagonal block [ff, fg, gg]: smoothness, pull and data.
    pub(super) fg: [f64; 3],
    /// ∂t/∂(p, q) (0 where there is no pull).
    pub(super) slope: [f64; 4],
}

/// Runs `pixel(j, &mut a[j], &mut b[j], &mut w[2j..2j + 2])` for every pixel over fixed
/// chunks and returns the sum of its results, added chunk by chunk in order.
pub(super) fn per_pixel<F>(n: usize, a: &mut [f64], b: &mut [f64], w: &mut [f64], pixel: F) -> f64
where
    F: Fn(usize, &mut f64, &mut f64, &mut [f64]) -> f64 + Sync + Send,
{
    let chunk = |c: usize, a: &mut [f64], b: &mut [f64], w: &mut [f64]| -> f64 {
        let mut sum = 0.0;
        for (i, ((a, b), w)) in a.iter_mut().zip(b).zip(w.chunks_mut(2)).enumerate() {
            sum += pixel(c * CHUNK + i, a, b, w);
        }
        sum
    };
    if n < PARALLEL_MIN {
        return a
            .chunks_mut(CHUNK)
            .zip(b.chunks_mut(CHUNK))
            .zip(w.chunks_mut(2 * CHUNK))
            .enumerate()
            .map(|(c, ((a, b), w))| chunk(c, a, b, w))
            .sum();
    }
    let sums: Vec<f64> = a
        .par_chunks_mut(CHUNK)
        .zip(b.par_chunks_mut(CHUNK))
        .zip(w.par_chunks_mut(2 * CHUNK))
        .enumerate()
        .map(|(c, ((a, b), w))| chunk(c, a, b, w))
        .collect();
    sums.iter().sum()
}

/// out[k] = `value(k)` for every k (a pixel's block, a depth's entry), over fixed chunks.
pub(super) fn per_item<T, F>(out: &mut [T], value: F)
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
{
    let chunk = |c: usize, out: &mut [T]| {
        for (i, o) in out.iter_mut().enumerate() {
            *o = value(c * CHUNK + i);
        }
    };
    if out.len() < PARALLEL_MIN {
        out.chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, o)| chunk(c, o));
    } else {
        out.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, o)| chunk(c, o));
    }
}

/// The quadratic model of [`Energy`] at one point.
pub(in crate::solver::integrable) struct Model<'e, 'a> {
    pub(super) energy: &'e Energy<'a>,
    pub(super) blocks: Vec<Block>,
    /// z's diagonal entries (floored).
    pub(super) depth: Vec<f64>,
}

impl Model<'_, '_> {
    /// out = (H + ν·diag H) x; `scratch` holds 2n values.
    pub(super) fn apply(&self, nu: f64, x: &[f64], out: &mut [f64], scratch: &mut [f64]) {
        let e = self.energy;
        let n = e.len();
        let (xf, rest) = x.split_at(n);
        let (xg, xz) = rest.split_at(n);
        let (out_f, rest) = out.split_at_mut(n);
        let (out_g, out_z) = rest.split_at_mut(n);
        let pixel = |j: usize, of: &mut f64, og: &mut f64, w: &mut [f64]| -> f64 {
            let node = &e.nodes[j];
            let block = &self.blocks[j];
            let (mut sf, mut sg) = (0.0, 0.0);
            for &q in &node.neighbours {
                let q = q as usize;
                if q < n {
                    sf += xf[q];
                    sg += xg[q];
                }
            }
            let [ff, fg, gg] = block.fg;
            let mu = e.pull[j];
            // The diagonal block holds σk + μ + data; off it, −σ per unknown neighbour.
            let mut rf = (ff + nu * ff) * xf[j] + fg * xg[j] - SIGMA * sf;
            let mut rg = fg * xf[j] + (gg + nu * gg) * xg[j] - SIGMA * sg;
            let (mut wp, mut wq) = (0.0, 0.0);
            if mu > 0.0 {
                let t = block.slope;
                let (dp, dq) = (-e.along_x[j].of(xz), e.along_rows[j].of(xz));
                let (uf, ug) = (-mu * (t[0] * dp + t[1] * dq), -mu * (t[2] * dp + t[3] * dq));
                rf += uf;
                rg += ug;
                // T′ᵀ μ (x_j − T′(dp, dq)).
                let (vf, vg) = (mu * xf[j] + uf, mu * xg[j] + ug);
                wp = t[0] * vf + t[2] * vg;
                wq = t[1] * vf + t[3] * vg;
            }
            *of = rf;
            *og = rg;
            w[0] = wp;
            w[1] = wq;
            0.0
        };
        per_pixel(n, out_f, out_g, scratch, pixel);
        per_item(out_z, |k| {
            e.gather_depth(k, scratch) + nu * self.depth[k] * xz[k]
        });
    }

    /// H + ν·diag H as a sparse matrix, every diagonal entry raised by [`DIAGONAL_FLOOR`] (a
    /// depth that no slope reads has none).
    #[cfg(test)]
    pub(super) fn matrix(&self, nu: f64) -> crate::solver::integrable::aggregation::Csr {
        crate::solver::integrable::aggregation::Csr::from_triplets(
            3 * self.energy.len(),
            &self.triplets(nu),
        )
    }

    /// The entries of [`Model::matrix`] as (row, column, value) triplets, summed where they
    /// meet.
    #[cfg(test)]
    pub(super) fn triplets(&self, nu: f64) -> Vec<(u32, u32, f64)> {
        let mut t = Vec::with_capacity(48 * self.energy.len());
        self.entries(nu, |r, c, v| t.push((r, c, v)));
        t
    }

    /// Calls `emit(row, column, value)` for each entry of [`Model::matrix`] (summed where they
    /// meet): the matrix the preconditioner coarsens. The positions are the same at every
    /// point of one energy, in the same order, so the preconditioner is planned from them once
    /// and later steps read the values alone. Once a stop is requested ([`crate::cancel`]) it
    /// emits no more: a caller looks at the flag before it uses the entries.
    pub(super) fn entries(&self, nu: f64, mut emit: impl FnMut(u32, u32, f64)) {
        let e = self.energy;
        let n = e.len();
        let (f, g, z) = (
            |j: usize| j as u32,
            |j: usize| (n + j) as u32,
            |k: usize| (2 * n + k) as u32,
        );
        let mut terms: Vec<(usize, f64, f64)> = Vec::with_capacity(4);
        for j in 0..n {
            // A requested stop ends the listing early (at 1024² it takes a tenth of a second
            // or more); the caller looks at the same flag before it uses what was emitted.
            if j % CANCEL_PIXELS == 0 && crate::cancel::requested() {
                return;
            }
            let [ff, fg, gg] = self.blocks[j].fg;
            emit(f(j), f(j), ff * (1.0 + nu) + DIAGONAL_FLOOR);
            emit(f(j), g(j), fg);
            emit(g(j), f(j), fg);
            emit(g(j), g(j), gg * (1.0 + nu) + DIAGONAL_FLOOR);
            for &q in &e.nodes[j].neighbours {
                let q = q as usize;
                if q < n {
                    emit(f(j), f(q), -SIGMA);
                    emit(g(j), g(q), -SIGMA);
                }
            }
            let mu = e.pull[j];
            if mu > 0.0 {
                // The residual (f, g)_j − t(p_j, q_j): its depth coefficients.
                let s = self.blocks[j].slope;
                terms.clear();
                let x = e.along_x[j].terms().map(|(k, c)| (k, -c, 0.0));
                let rows = e.along_rows[j].terms().map(|(k, c)| (k, 0.0, c));
                for (k, dp, dq) in x.chain(rows) {
                    terms.push((k, -(s[0] * dp + s[1] * dq), -(s[2] * dp + s[3] * dq)));
                }
                for &(k, af, ag) in &terms {
                    emit(f(j), z(k), mu * af);
                    emit(z(k), f(j), mu * af);
                    emit(g(j), z(k), mu * ag);
                    emit(z(k), g(j), mu * ag);
                    for &(l, bf, bg) in &terms {
                        emit(z(k), z(l), mu * (af * bf + ag * bg));
                    }
                }
            }
        }
        for k in 0..n {
            emit(z(k), z(k), nu * self.depth[k] + DIAGONAL_FLOOR);
        }
    }

    /// Solves (H + ν·diag H) x = b by conjugate gradients preconditioned by `mg` (one V-cycle)
    /// from 0, to a residual of `tol`·|b| or `max_iter` iterations; returns the iterations.
    pub(super) fn solve(
        &self,
        nu: f64,
        (mg, cycle): (&Multigrid, &mut [[Vec<f64>; 3]]),
        b: &[f64],
        x: &mut [f64],
        stop: Stop,
    ) -> usize {
        let len = b.len();
        let mut residual = b.to_vec();
        let (mut p, mut q) = (vec![0.0; len], vec![0.0; len]);
        let mut scratch = vec![0.0; 2 * self.energy.len()];
        conjugate_gradients::solve(
            |v, out| self.apply(nu, v, out, &mut scratch),
            |r, out| mg.apply(r, out, cycle),
            &mut residual,
            x,
            [&mut p, &mut q],
            stop,
        )
        .iterations
    }

    /// ½ xᵀHx.
    pub(super) fn quadratic(&self, x: &[f64]) -> f64 {
        let mut out = vec![0.0; x.len()];
        let mut scratch = vec![0.0; 2 * self.energy.len()];
        self.apply(0.0, x, &mut out, &mut scratch);
        0.5 * dot(x, &out)
    }
}

/// The symmetric 2 × 2 matrix [a, b, c] with its negative eigenvalues set to 0.
pub(super) fn positive_part([a, b, c]: [f64; 3]) -> [f64; 3] {
    let mean = 0.5 * (a + c);
    let radius = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    let (large, small) = (mean + radius, mean - radius);
    if small >= 0.0 {
        return [a, b, c];
    }
    if large <= 0.0 {
        return [0.0; 3];
    }
    // large·vvᵀ for v the unit eigenvector of `large`.
    let (vx, vy) = if b != 0.0 {
        (large - c, b)
    } else if a >= c {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    let norm2 = vx * vx + vy * vy;
    [
        large * vx * vx / norm2,
        large * vx * vy / norm2,
        large * vy * vy / norm2,
    ]
}

/// The share of a pixel's smoothness-and-pull diagonal that its block keeps as its least
/// curvature: the data term's negative curvature is kept down to it.
pub(super) const HELD: f64 = 0.5;

/// The data term's 2 × 2 Hessian `data` at a pixel whose smoothness and pull put `diagonal` on
/// its (f, g) diagonal, changed as little as makes the pixel's block diagonal·I + data have no
/// eigenvalue below [`HELD`]·diagonal: the data term's negative curvature (a residual pulling
/// the orientation past the brightness's ridge) is kept where the pixel's own smoothness and
/// pull hold it, and only the rest is dropped.
pub(super) fn held(data: [f64; 3], diagonal: f64) -> [f64; 3] {
    let give = (1.0 - HELD) * diagonal;
    let [a, b, c] = positive_part([data[0] + give, data[1], data[2] + give]);
    [a - give, b, c - give]
}

/// The smallest diagonal entry of z that the damping uses, and what the preconditioner's matrix
/// adds to every diagonal entry: a depth that no slope reads (and the depth's checkerboard,
/// which central differences do not see) has none.
pub(super) const DIAGONAL_FLOOR: f64 = 1e-6;

/// Pixels listed by [`Model::entries`] between two looks for a requested stop.
const CANCEL_PIXELS: usize = 1 << 15;
