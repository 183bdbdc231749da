//! Preconditioned conjugate gradients: the one loop that shadelab's symmetric positive definite
//! solves run (the depth's Poisson equation, each step of the integrable method), the matrix
//! and the preconditioner given as the caller's functions.
//!
//! The dot products are summed in fixed chunks whose partial sums are added in order, and every
//! update is one pixel's own expression, so the result does not depend on the thread count.

use crate::parallel::prelude::*;

/// Values per partial sum of a dot product (a fixed split, whatever the thread count).
const SUM_CHUNK: usize = 1 << 13;

/// Σ uᵢvᵢ, summed in fixed chunks whose partial sums are added in order.
pub(crate) fn dot(u: &[f64], v: &[f64]) -> f64 {
    let partial: Vec<f64> = u
        .par_chunks(SUM_CHUNK)
        .zip(v.par_chunks(SUM_CHUNK))
        .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>())
        .collect();
    partial.iter().sum()
}

/// When a solve stops: at a residual of `tol`·‖b‖, or after `max_iter` iterations.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stop {
    pub(crate) tol: f64,
    pub(crate) max_iter: usize,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Outcome {
    pub(crate) iterations: usize,
    /// ‖b − A x‖ / ‖b‖ (0 for b = 0).
    pub(crate) relative_residual: f64,
    /// Whether the residual reached the tolerance.
    pub(crate) converged: bool,
}

/// Solves A x = b from x = 0 by conjugate gradients preconditioned by M ≈ A⁻¹.
///
/// - `apply(v, out)` sets out = A v; `precondition(r, out)` sets out = M r (both symmetric
///   positive definite);
/// - `residual` holds b on entry and b − A x on return (the caller's buffer, so that a large
///   solve keeps no copy of b);
/// - `work` is two more buffers of b's length (the direction, and A times it or the
///   preconditioned residual).
///
/// Stops early, not converged, where A's curvature along a direction is not positive (or not
/// a number), or where a stop was requested ([`crate::cancel`]).
pub(crate) fn solve(
    mut apply: impl FnMut(&[f64], &mut [f64]),
    mut precondition: impl FnMut(&[f64], &mut [f64]),
    residual: &mut [f64],
    x: &mut [f64],
    [p, q]: [&mut [f64]; 2],
    stop: Stop,
) -> Outcome {
    let r = residual;
    x.fill(0.0);
    let b_norm = dot(r, r).sqrt();
    if b_norm == 0.0 {
        return Outcome {
            iterations: 0,
            relative_residual: 0.0,
            converged: true,
        };
    }
    let target = stop.tol * b_norm;
    let mut norm = b_norm;
    let ended = |iterations: usize, norm: f64| Outcome {
        iterations,
        relative_residual: norm / b_norm,
        converged: norm <= target,
    };
    // q holds M r, then A p once p is set.
    precondition(r, q);
    p.copy_from_slice(q);
    let mut rz = dot(r, q);
    for iteration in 1..=stop.max_iter {
        // A requested stop ends the solve here, not converged: one iteration of a large
        // system is a fraction of a second, the whole solve can be seconds.
        if crate::cancel::requested() {
            return ended(iteration - 1, norm);
        }
        apply(p, q);
        let curvature = dot(p, q);
        if curvature.is_nan() || curvature <= 0.0 {
            return ended(iteration - 1, norm);
        }
        let alpha = rz / curvature;
        // The update and ‖r‖² in one pass (partial sums in the same chunks as `dot`).
        let partial: Vec<f64> = x
            .par_chunks_mut(SUM_CHUNK)
            .zip(r.par_chunks_mut(SUM_CHUNK))
            .zip(p.par_chunks(SUM_CHUNK).zip(q.par_chunks(SUM_CHUNK)))
            .map(|((x, r), (p, q))| {
                let mut rr = 0.0;
                for ((x, r), (p, q)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(q)) {
                    *x += alpha * p;
                    *r -= alpha * q;
                    rr += *r * *r;
                }
                rr
            })
            .collect();
        norm = f64::sqrt(partial.iter().sum());
        if norm <= target {
            return ended(iteration, norm);
        }
        precondition(r, q);
        let rz_next = dot(r, q);
        let beta = rz_next / rz;
        rz = rz_next;
        p.par_chunks_mut(SUM_CHUNK)
            .zip(q.par_chunks(SUM_CHUNK))
            .for_each(|(p, q)| {
                for (p, q) in p.iter_mut().zip(q) {
                    *p = q + beta * *p;
                }
            });
    }
    ended(stop.max_iter, norm)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 1-D Laplacian tridiag(−1, 2, −1) of n unknowns (Dirichlet ends), applied.
    fn laplacian(v: &[f64], out: &mut [f64]) {
        let n = v.len();
        for i in 0..n {
            let left = if i > 0 { v[i - 1] } else { 0.0 };
            let right = if i + 1 < n { v[i + 1] } else { 0.0 };
            out[i] = 2.0 * v[i] - left - right;
        }
    }

    fn run(
        b: &[f64],
        precondition: impl FnMut(&[f64], &mut [f64]),
        stop: Stop,
    ) -> (Vec<f64>, Vec<f64>, Outcome) {
        let n = b.len();
        let (mut r, mut x, mut p, mut q) = (b.to_vec(), vec![1.0; n], vec![0.0; n], vec![0.0; n]);
        let outcome = solve(
            laplacian,
            precondition,
            &mut r,
            &mut x,
            [&mut p, &mut q],
            stop,
        );
        (x, r, outcome)
    }

    /// On a literal 2 × 2 system the solve is exact in two iterations.
    #[test]
    fn a_two_by_two_system_in_two_iterations() {
        let apply = |v: &[f64], out: &mut [f64]| {
            out[0] = 2.0 * v[0] + v[1];
            out[1] = v[0] + 3.0 * v[1];
        };
        let identity = |r: &[f64], out: &mut [f64]| out.copy_from_slice(r);
        let (mut r, mut x, mut p, mut q) =
            (vec![3.0, 5.0], vec![9.0; 2], vec![0.0; 2], vec![0.0; 2]);
        let stop = Stop {
            tol: 1e-12,
            max_iter: 10,
        };
        let outcome = solve(apply, identity, &mut r, &mut x, [&mut p, &mut q], stop);
        assert!(outcome.converged && outcome.iterations == 2, "{outcome:?}");
        assert!(
            (x[0] - 0.8).abs() < 1e-14 && (x[1] - 1.4).abs() < 1e-14,
            "{x:?}"
        );
    }

    /// On the Laplacian of 20,000 unknowns (several sum chunks), the solution of L x = L·t is
    /// t to 1e-6 once the residual is 1e-10 of b's, and `residual` holds b − A x.
    #[test]
    fn the_solution_and_its_residual() {
        let n = 20_000;
        let t: Vec<f64> = (0..n).map(|i| (i as f64 * 0.001).sin() + 0.5).collect();
        let mut b = vec![0.0; n];
        laplacian(&t, &mut b);
        let identity = |r: &[f64], out: &mut [f64]| out.copy_from_slice(r);
        let stop = Stop {
            tol: 1e-10,
            max_iter: 100_000,
        };
        let (x, r, outcome) = run(&b, identity, stop);
        assert!(outcome.converged, "{outcome:?}");
        let worst = x
            .iter()
            .zip(&t)
            .fold(0.0f64, |a, (x, t)| a.max((x - t).abs()));
        assert!(worst < 1e-6, "{worst}");
        let mut ax = vec![0.0; n];
        laplacian(&x, &mut ax);
        let b_norm = dot(&b, &b).sqrt();
        for ((r, b), ax) in r.iter().zip(&b).zip(&ax) {
            assert!(
                (r - (b - ax)).abs() <= 1e-12 * b_norm,
                "{r} against {}",
                b - ax
            );
        }
        let measured = dot(&r, &r).sqrt() / b_norm;
        assert_eq!(outcome.relative_residual, measured);
    }

    /// Out of iterations, the solve says so; with b = 0 it returns x = 0 at once; where A is not
    /// positive along the first direction it stops there.
    #[test]
    fn it_says_how_it_ended() {
        let b: Vec<f64> = (0..500).map(|i| (i % 7) as f64 - 3.0).collect();
        let identity = |r: &[f64], out: &mut [f64]| out.copy_from_slice(r);
        let few = Stop {
            tol: 1e-12,
            max_iter: 3,
        };
        let (_, _, outcome) = run(&b, identity, few);
        assert_eq!(outcome.iterations, 3);
        assert!(!outcome.converged && outcome.relative_residual > 1e-12);
        let (x, _, outcome) = run(&[0.0; 10], identity, few);
        assert!(outcome.converged && outcome.iterations == 0 && x.iter().all(|&x| x == 0.0));
        let negative = |v: &[f64], out: &mut [f64]| {
            laplacian(v, out);
            out.iter_mut().for_each(|o| *o = -*o);
        };
        let (mut r, mut x) = (b.clone(), vec![1.0; b.len()]);
        let (mut p, mut q) = (vec![0.0; b.len()], vec![0.0; b.len()]);
        let outcome = solve(negative, identity, &mut r, &mut x, [&mut p, &mut q], few);
        assert_eq!(outcome.iterations, 0, "{outcome:?}");
        assert!(!outcome.converged && x.iter().all(|&x| x == 0.0) && r == b);
    }

    /// A better preconditioner takes fewer iterations: the Laplacian's exact inverse one.
    #[test]
    fn the_exact_inverse_takes_one_iteration() {
        let n = 64;
        let b: Vec<f64> = (0..n).map(|i| ((i * 13) % 5) as f64).collect();
        // L⁻¹ by the Thomas algorithm.
        let inverse = |r: &[f64], out: &mut [f64]| {
            let n = r.len();
            let (mut c, mut d) = (vec![0.0; n], vec![0.0; n]);
            for i in 0..n {
                let m = 2.0 + if i > 0 { c[i - 1] } else { 0.0 };
                c[i] = -1.0 / m;
                d[i] = (r[i] + if i > 0 { d[i - 1] } else { 0.0 }) / m;
            }
            for i in (0..n).rev() {
                out[i] = d[i] - if i + 1 < n { c[i] * out[i + 1] } else { 0.0 };
            }
        };
        let stop = Stop {
            tol: 1e-12,
            max_iter: 50,
        };
        let (_, _, outcome) = run(&b, inverse, stop);
        assert!(outcome.converged && outcome.iterations == 1, "{outcome:?}");
    }
}
