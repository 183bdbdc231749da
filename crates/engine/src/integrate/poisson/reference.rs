//! The original integrator, kept as a test reference: conjugate gradients with a diagonal
//! preconditioner on the masked Laplacian, over the mask's pixels only. The multigrid-
//! preconditioned solver in the parent module must reproduce its answer.

use super::{Integration, PoissonOptions};
use crate::error::Result;
use crate::grid::{Grid, Mask};
use crate::imageops::parts::{graph_parts, SumOrder};

/// The parent module's `solve` (L z = b on `mask`, for `full_b` on the full grid) by the
/// original, unpreconditioned (Jacobi) conjugate gradients.
pub(crate) fn solve_reference(
    mask: &Mask,
    full_b: &[f64],
    options: &PoissonOptions,
) -> Result<Integration> {
    let (w, h) = (mask.width(), mask.height());
    let problem = Laplacian::new(mask);
    let b: Vec<f64> = problem.pixels.iter().map(|&p| full_b[p]).collect();
    let (mut z, iterations, relative_residual, converged) = problem.solve(&b, options);
    // Means summed in index order, whatever order the search visited the nodes in.
    graph_parts(&problem.neighbours).subtract_means(&mut z, SumOrder::Index);
    let mut depth = Grid::new(w, h, 0.0);
    for (k, &p) in problem.pixels.iter().enumerate() {
        depth.data_mut()[p] = z[k];
    }
    Ok(Integration {
        depth,
        iterations,
        relative_residual,
        converged,
    })
}

/// The graph Laplacian of a mask's 4-neighbour graph, over its pixels in row-major order.
struct Laplacian {
    /// Pixel index of each unknown.
    pixels: Vec<usize>,
    /// Unknown indices of each unknown's neighbours; missing ones point at index n, which
    /// holds 0 in every vector the operator reads.
    neighbours: Vec<[u32; 4]>,
    /// Number of neighbours.
    degree: Vec<f64>,
}

impl Laplacian {
    fn new(mask: &Mask) -> Laplacian {
        let (w, h) = (mask.width(), mask.height());
        let mut index = vec![u32::MAX; w * h];
        let mut pixels = Vec::new();
        for (p, &m) in mask.data().iter().enumerate() {
            if m {
                index[p] = pixels.len() as u32;
                pixels.push(p);
            }
        }
        let missing = pixels.len() as u32;
        let mut neighbours = Vec::with_capacity(pixels.len());
        let mut degree = Vec::with_capacity(pixels.len());
        for &p in &pixels {
            let (c, r) = (p % w, p / w);
            let mut nb = [missing; 4];
            let mut k = 0;
            let candidates = [
                (c > 0).then(|| p - 1),
                (c + 1 < w).then(|| p + 1),
                (r > 0).then(|| p - w),
                (r + 1 < h).then(|| p + w),
            ];
            for q in candidates.into_iter().flatten() {
                if index[q] != u32::MAX {
                    nb[k] = index[q];
                    k += 1;
                }
            }
            neighbours.push(nb);
            degree.push(k as f64);
        }
        Laplacian {
            pixels,
            neighbours,
            degree,
        }
    }

    /// out = L x, for x holding n + 1 values (the last one 0).
    fn apply(&self, x: &[f64], out: &mut [f64]) {
        for (k, (nb, d)) in self.neighbours.iter().zip(&self.degree).enumerate() {
            let [a, b, c, e] = *nb;
            out[k] = d * x[k] - (x[a as usize] + x[b as usize] + x[c as usize] + x[e as usize]);
        }
    }

    /// Preconditioned conjugate gradients from z = 0; returns (z, iterations, relative
    /// residual, converged).
    fn solve(&self, b: &[f64], options: &PoissonOptions) -> (Vec<f64>, usize, f64, bool) {
        let n = b.len();
        let dot = |u: &[f64], v: &[f64]| -> f64 { u.iter().zip(v).map(|(a, b)| a * b).sum() };
        let b_norm = dot(b, b).sqrt();
        let mut z = vec![0.0; n];
        if b_norm == 0.0 {
            return (z, 0, 0.0, true);
        }
        // Isolated pixels have no equation (degree 0): their preconditioner entry is 0, which
        // keeps them at 0 and out of the Krylov space.
        let inv_degree: Vec<f64> = self
            .degree
            .iter()
            .map(|&d| if d > 0.0 { 1.0 / d } else { 0.0 })
            .collect();
        let mut r = b.to_vec();
        let mut s: Vec<f64> = r.iter().zip(&inv_degree).map(|(r, m)| r * m).collect();
        let mut p = s.clone();
        p.push(0.0);
        let mut lp = vec![0.0; n];
        let mut rs = dot(&r, &s);
        let target = options.tol * b_norm;
        let mut residual = b_norm;
        for iteration in 1..=options.max_iter {
            self.apply(&p, &mut lp);
            let curvature = dot(&p[..n], &lp);
            if curvature <= 0.0 {
                return (z, iteration - 1, residual / b_norm, residual <= target);
            }
            let alpha = rs / curvature;
            for k in 0..n {
                z[k] += alpha * p[k];
                r[k] -= alpha * lp[k];
            }
            residual = dot(&r, &r).sqrt();
            if residual <= target {
                return (z, iteration, residual / b_norm, true);
            }
            for k in 0..n {
                s[k] = r[k] * inv_degree[k];
            }
            let rs_next = dot(&r, &s);
            let beta = rs_next / rs;
            rs = rs_next;
            for k in 0..n {
                p[k] = s[k] + beta * p[k];
            }
        }
        (z, options.max_iter, residual / b_norm, false)
    }
}
