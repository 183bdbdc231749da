//! The globalisation of the multigrid solve: what finishes a solve that the multigrid cycles
//! cannot.
//!
//! # Why the cycles can fail
//!
//! The Ikeuchi–Horn equations evaluate R at the neighbour average ū. Linearised about a
//! solution, a checkerboard error δ (ū = −δ at k = 4) meets the operator 8 − 4λ·∇R·∇Rᵀ, which
//! is indefinite once λ·|∇R|² > 2: there Jacobi's fixed point is a saddle of the iteration,
//! every sweep (Jacobi, Gauss–Seidel, damped or not) multiplies that mode by more than 1, and
//! a coarse grid cannot see it. That is the bound λ·R_f² < 2 of the module documentation, and
//! why `solve --lambda 30` on a rendered sphere blew up after one cycle. Below the bound the
//! cycles can still stall where the coarse model misjudges the operator (an attached shadow
//! beside an oblique light, a folded object).
//!
//! # What is done instead
//!
//! The multigrid cycles run first, unchanged: where they converge, the answer is Jacobi's
//! fixed point exactly as before. A `StallWatch` in the cycle loop stops them when their best
//! residual has not halved from one half of [`STALL_WINDOW`] cycles to the next (of
//! [`STRONG_DATA_STALL_WINDOW`] above λ = 1, where a stall leads to the continuation start);
//! a blow-up stops them at once.
//! Then the energy the method is named after,
//!
//! E(u) = e_S + λ·e_R = ¼ Σ |Δu|² + λ Σ (I − R(u))²  (R at the pixel itself),
//!
//! is minimised by truncated Newton steps with a backtracking (Armijo) line search on E and a
//! Levenberg–Marquardt shift μ: each step's system (L + 4λ·(∇R·∇Rᵀ − (I − R)·∇²R) + μ)·δ =
//! −2∇E is solved by conjugate gradients preconditioned by symmetric over-relaxation on the
//! system's positive definite part (the data block's negative eigenvalue dropped), stopped at
//! negative curvature and at a tolerance that tightens as the gradient falls. Every step is a
//! descent direction and no step is taken that raises E: the iteration cannot diverge.
//! (Gauss–Newton steps, ∇R·∇Rᵀ alone, converged linearly where I − R stays large: hundreds
//! of steps on the eval's photographs at λ = 30, Newton's 6–60.)
//! It starts from the multigrid solution at λ = 1 when λ is larger (λ continuation: there the
//! failed cycles' values are far from any solution), else from the cycles' last values; values
//! that are not numbers start at (0, 0).
//!
//! Its fixed point is the energy's stationary point, k·(u − ū) = 4λ·(I − R(u))·∇R(u): the
//! equations of [`super::Method::Literal`], which differ from Jacobi's only in where R is
//! read (at the pixel, not at the neighbour average). It stops when the largest pointwise step
//! of those equations, |k·(u − ū) − 4λ·(I − R)·∇R| / k, is below `tol`, the same measure as
//! the cycles' test, or after `max_iter` steps. Each step's energy is reported
//! ([`Solution::energy_history`], and [`Progress::energy`] after each step).

// The loops below walk several arrays indexed by the unknown's slot together.
#![allow(clippy::needless_range_loop)]

use super::{Posed, Progress, Solution, SolveOptions, SolveStats, Solver};
use crate::boundary::{BoundaryConditions, Role};
use crate::grid::Image;
use crate::reflectance::ReflectanceMap;

/// The multigrid cycles give up when the best residual of the last half of this many cycles
/// is not half the best of the half before: a solve that converges halves it every few cycles
/// (a slow one within tens).
pub const STALL_WINDOW: usize = 300;

/// Conjugate-gradient iterations at most per Newton step.
const CG_MAX: usize = 400;
/// A step's linear system is solved to at most this fraction of its right-hand side's norm,
/// less as the gradient falls (a forcing term of Eisenstat and Walker's kind: loose far from
/// the solution, tight near it, where Newton's steps converge fast if solved well).
const CG_REDUCTION: f64 = 1e-2;
/// The tightest fraction a step's system is solved to.
const CG_REDUCTION_MIN: f64 = 1e-6;
/// Over-relaxation of the symmetric SOR preconditioner.
const SSOR_OMEGA: f64 = 1.5;
/// Armijo's sufficient-decrease fraction.
const ARMIJO: f64 = 1e-4;
/// The line search gives up below this step length: no decrease is left to find.
const MIN_STEP: f64 = 1e-12;
/// The Levenberg–Marquardt shift starts here, is multiplied by [`SHIFT_FACTOR`] after a
/// step that had to be shortened and divided by it after a full step.
const START_SHIFT: f64 = 1e-3;
/// See [`START_SHIFT`].
const SHIFT_FACTOR: f64 = 4.0;
/// The smallest shift.
const MIN_SHIFT: f64 = 1e-9;
/// The λ of the continuation start when the cycles blew up at a larger λ.
const CONTINUATION_LAMBDA: f64 = 1.0;

/// The stall window above [`CONTINUATION_LAMBDA`]: there the cycles that do converge halve
/// their residual within tens of cycles, and those that do not (every eval case at λ = 10
/// stalled) are replaced by the continuation start anyway, so waiting [`STALL_WINDOW`] cycles
/// only costs time.
pub const STRONG_DATA_STALL_WINDOW: usize = 40;

/// Watches the multigrid cycles' residuals and says when they have stopped getting closer.
#[derive(Debug, Clone)]
pub(crate) struct StallWatch {
    residuals: Vec<f64>,
    window: usize,
}

impl StallWatch {
    /// A watch for a new solve at `lambda`: [`STALL_WINDOW`] cycles, or
    /// [`STRONG_DATA_STALL_WINDOW`] where a stall leads to the λ-continuation start.
    pub(crate) fn new(lambda: f64) -> StallWatch {
        let window = if needs_continuation(lambda) {
            STRONG_DATA_STALL_WINDOW
        } else {
            STALL_WINDOW
        };
        StallWatch {
            residuals: Vec::new(),
            window,
        }
    }

    /// Records one cycle's residual; true when the smallest residual of the last half window
    /// of cycles is not below half the smallest of the half window before (a solve that
    /// converges at all halves it far faster; one that oscillates never does).
    pub(crate) fn stalled(&mut self, residual: f64) -> bool {
        self.residuals.push(residual);
        let n = self.residuals.len();
        if n < self.window {
            return false;
        }
        let half = self.window / 2;
        let least = |range: &[f64]| range.iter().copied().fold(f64::INFINITY, f64::min);
        let before = least(&self.residuals[n - self.window..n - half]);
        let recent = least(&self.residuals[n - half..]);
        recent.is_nan() || recent >= 0.5 * before
    }
}

/// Whether the multigrid start should be replaced by a λ-continuation start: at a λ above
/// [`CONTINUATION_LAMBDA`] the cycles that failed oscillate through values far from any
/// solution (a descent from them can settle in a poor minimum: the vase at λ = 10 did, 56°
/// off), while below it they stalled near one.
pub(super) fn needs_continuation(lambda: f64) -> bool {
    lambda > CONTINUATION_LAMBDA
}

/// The options of the λ-continuation start.
pub(super) fn continuation_options(options: &SolveOptions) -> SolveOptions {
    SolveOptions {
        lambda: CONTINUATION_LAMBDA,
        ..*options
    }
}

/// One Newton step's linear algebra on the unknowns.
struct Linear {
    /// Diagonal 2 × 2 blocks (a11, a12, a22) of Newton's matrix 2·∇²E,
    /// L + 4λ·(∇R·∇Rᵀ − (I − R)·∇²R) (without the shift).
    diag: Vec<[f64; 3]>,
    /// The same with the data block's positive semidefinite part [·]₊ only: positive
    /// definite, the preconditioner's blocks.
    definite: Vec<[f64; 3]>,
    /// The gradient 2·∇E (k·(u − ū) − 4λ·(I − R)·∇R) at each unknown.
    grad: Vec<[f64; 2]>,
}

impl Solver {
    /// Minimises the energy from the start `start` ((f, g) grids; values that are not finite
    /// start at 0), after `cycles_before` multigrid cycles, reporting each step to `progress`.
    /// See the module documentation.
    pub(super) fn descend(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        start: (&Image, &Image),
        cycles_before: usize,
        progress: &mut dyn FnMut(&Progress),
    ) -> Solution {
        let Posed {
            bc, reflectance, ..
        } = posed;
        let lambda = options.lambda;
        let n = self.build(posed, lambda);
        for j in 0..n {
            let p = self.pixels[j] as usize;
            let (f, g) = (start.0.data()[p], start.1.data()[p]);
            let ok = f.is_finite() && g.is_finite() && self.nodes[j].inv_k != 0.0;
            self.cur_f[j] = if ok { f } else { 0.0 };
            self.cur_g[j] = if ok { g } else { 0.0 };
        }
        self.next_f.clone_from(&self.cur_f);
        self.next_g.clone_from(&self.cur_g);
        let constant = fixed_pairs_energy(bc);
        let mut energy = self.energy(n, reflectance, lambda, false) + constant;
        let mut history = Vec::new();
        let mut shift = START_SHIFT;
        let mut steps = 0;
        let mut converged = false;
        let mut last_update;
        let mut delta = vec![[0.0; 2]; n];
        let mut scratch = Scratch::new(n);
        let mut first_norm = None;
        loop {
            let linear = self.linearise(n, reflectance, lambda);
            last_update = self.step_measure(n, &linear);
            if last_update < options.tol {
                converged = true;
                break;
            }
            if steps >= options.max_iter || crate::cancel::requested() {
                break;
            }
            let norm = dot(&linear.grad[..n], &linear.grad[..n]).sqrt();
            let first = *first_norm.get_or_insert(norm);
            let reduction =
                (CG_REDUCTION * (norm / first).sqrt()).clamp(CG_REDUCTION_MIN, CG_REDUCTION);
            self.newton_direction(n, &linear, shift, reduction, &mut delta, &mut scratch);
            // The slope of E along δ: ∇E·δ, with ∇E = grad / 2.
            let slope: f64 = linear
                .grad
                .iter()
                .zip(&delta)
                .map(|(g, d)| 0.5 * (g[0] * d[0] + g[1] * d[1]))
                .sum();
            if slope.is_nan() || slope >= 0.0 {
                // Not a descent direction (rounding at a stationary point): nothing to gain.
                break;
            }
            let mut t = 1.0;
            let accepted = loop {
                for j in 0..n {
                    self.next_f[j] = self.cur_f[j] + t * delta[j][0];
                    self.next_g[j] = self.cur_g[j] + t * delta[j][1];
                }
                let trial = self.energy(n, reflectance, lambda, true) + constant;
                if trial.is_finite() && trial <= energy + ARMIJO * t * slope {
                    break Some(trial);
                }
                t *= 0.5;
                if t < MIN_STEP {
                    break None;
                }
            };
            let Some(trial) = accepted else { break };
            self.cur_f[..n].copy_from_slice(&self.next_f[..n]);
            self.cur_g[..n].copy_from_slice(&self.next_g[..n]);
            energy = trial;
            shift = if t == 1.0 {
                (shift / SHIFT_FACTOR).max(MIN_SHIFT)
            } else {
                shift * SHIFT_FACTOR
            };
            steps += 1;
            history.push(energy);
            progress(&Progress {
                iteration: cycles_before + steps,
                max_iter: cycles_before + options.max_iter,
                last_update,
                energy: Some(energy),
                level: 0,
                seconds_left: None,
            });
        }
        let mut solution = self.solution(
            posed,
            SolveStats {
                iterations: cycles_before + steps,
                converged,
                diverged: false,
                last_update,
                unknowns: n,
            },
        );
        solution.globalised = true;
        solution.energy_history = history;
        solution
    }

    /// e_S (less the pairs of fixed pixels) + λ·e_R of the current values, or of the trial
    /// values in `next` when `trial`.
    fn energy(&self, n: usize, reflectance: &dyn ReflectanceMap, lambda: f64, trial: bool) -> f64 {
        let (vf, vg) = if trial {
            (&self.next_f, &self.next_g)
        } else {
            (&self.cur_f, &self.cur_g)
        };
        let zero = self.cur_f.len() - 1;
        let mut smooth = 0.0;
        let mut data = 0.0;
        for (j, node) in self.nodes.iter().enumerate().take(n) {
            let (f, g) = (vf[j], vg[j]);
            for &q in &node.neighbours {
                let q = q as usize;
                // Each pair of unknowns once (from its lower slot); each unknown–fixed pair
                // from the unknown; missing neighbours point at the zero slot.
                if q == zero || (q < n && q < j) {
                    continue;
                }
                let (df, dg) = (vf[q] - f, vg[q] - g);
                smooth += 0.25 * (df * df + dg * dg);
            }
            if node.data_weight != 0.0 {
                let e = node.intensity - reflectance.fg(f, g).value;
                data += e * e;
            }
        }
        smooth + lambda * data
    }

    /// Newton's blocks (and their positive definite part) and the gradient at the current
    /// values.
    fn linearise(&self, n: usize, reflectance: &dyn ReflectanceMap, lambda: f64) -> Linear {
        let mut diag = Vec::with_capacity(n);
        let mut definite = Vec::with_capacity(n);
        let mut grad = Vec::with_capacity(n);
        let data = 4.0 * lambda;
        for (j, node) in self.nodes.iter().enumerate().take(n) {
            if node.inv_k == 0.0 {
                diag.push([1.0, 0.0, 1.0]);
                definite.push([1.0, 0.0, 1.0]);
                grad.push([0.0; 2]);
                continue;
            }
            let k = 1.0 / node.inv_k;
            let (f, g) = (self.cur_f[j], self.cur_g[j]);
            let [a, b, c, d] = node.neighbours.map(|q| q as usize);
            let sf = self.cur_f[a] + self.cur_f[b] + self.cur_f[c] + self.cur_f[d];
            let sg = self.cur_g[a] + self.cur_g[b] + self.cur_g[c] + self.cur_g[d];
            let mut r = [k * f - sf, k * g - sg];
            let mut m = [k, 0.0, k];
            let mut p = m;
            if node.data_weight != 0.0 {
                let (s, h) = reflectance.fg_hessian(f, g);
                let e = node.intensity - s.value;
                r[0] -= data * e * s.d1;
                r[1] -= data * e * s.d2;
                let block = [
                    s.d1 * s.d1 - e * h[0],
                    s.d1 * s.d2 - e * h[1],
                    s.d2 * s.d2 - e * h[2],
                ];
                let part = positive_part(block);
                p = [
                    m[0] + data * part[0],
                    m[1] + data * part[1],
                    m[2] + data * part[2],
                ];
                m[0] += data * block[0];
                m[1] += data * block[1];
                m[2] += data * block[2];
            }
            diag.push(m);
            definite.push(p);
            grad.push(r);
        }
        Linear {
            diag,
            definite,
            grad,
        }
    }

    /// The largest |grad| / k: the largest change one pointwise step of the energy's equations
    /// would make (∞ for a value that is not a number).
    fn step_measure(&self, n: usize, linear: &Linear) -> f64 {
        let mut worst: f64 = 0.0;
        for j in 0..n {
            let inv_k = self.nodes[j].inv_k;
            for v in linear.grad[j] {
                let change = (v * inv_k).abs();
                if change.is_nan() {
                    return f64::INFINITY;
                }
                worst = worst.max(change);
            }
        }
        worst
    }

    /// Solves (blocks + shift)·δ = −grad by preconditioned conjugate gradients, to `reduction`
    /// of the right-hand side's norm.
    fn newton_direction(
        &self,
        n: usize,
        linear: &Linear,
        shift: f64,
        reduction: f64,
        delta: &mut [[f64; 2]],
        s: &mut Scratch,
    ) {
        let shifted = |blocks: &[[f64; 3]]| -> Vec<[f64; 3]> {
            blocks
                .iter()
                .map(|m| [m[0] + shift, m[1], m[2] + shift])
                .collect()
        };
        let (blocks, definite) = (shifted(&linear.diag), shifted(&linear.definite));
        for j in 0..n {
            delta[j] = [0.0; 2];
            s.r[j] = [-linear.grad[j][0], -linear.grad[j][1]];
        }
        let norm0 = dot(&s.r, &s.r).sqrt();
        if norm0 == 0.0 {
            return;
        }
        self.ssor(n, &definite, &s.r, &mut s.z, &mut s.t);
        s.p.copy_from_slice(&s.z);
        let mut rz = dot(&s.r, &s.z);
        for iteration in 0..CG_MAX {
            self.apply(n, &blocks, &s.p, &mut s.q);
            let pq = dot(&s.p, &s.q);
            if pq.is_nan() || pq <= 0.0 {
                // Negative curvature (Newton's matrix is indefinite where the picture cannot
                // be matched): stop there, as truncated Newton does; with no step yet, take
                // the preconditioned gradient, a descent direction.
                if iteration == 0 {
                    delta[..n].copy_from_slice(&s.p[..n]);
                }
                break;
            }
            let alpha = rz / pq;
            for j in 0..n {
                for c in 0..2 {
                    delta[j][c] += alpha * s.p[j][c];
                    s.r[j][c] -= alpha * s.q[j][c];
                }
            }
            if dot(&s.r, &s.r).sqrt() <= reduction * norm0 {
                break;
            }
            self.ssor(n, &definite, &s.r, &mut s.z, &mut s.t);
            let next = dot(&s.r, &s.z);
            let beta = next / rz;
            rz = next;
            for j in 0..n {
                for c in 0..2 {
                    s.p[j][c] = s.z[j][c] + beta * s.p[j][c];
                }
            }
        }
    }

    /// out = (blocks − adjacency)·x over the unknowns (fixed neighbours hold no correction).
    fn apply(&self, n: usize, blocks: &[[f64; 3]], x: &[[f64; 2]], out: &mut [[f64; 2]]) {
        for j in 0..n {
            let m = blocks[j];
            let v = x[j];
            let mut o = [m[0] * v[0] + m[1] * v[1], m[1] * v[0] + m[2] * v[1]];
            if self.nodes[j].inv_k != 0.0 {
                for &q in &self.nodes[j].neighbours {
                    let q = q as usize;
                    if q < n {
                        o[0] -= x[q][0];
                        o[1] -= x[q][1];
                    }
                }
            }
            out[j] = o;
        }
    }

    /// z = M⁻¹·r for the symmetric SOR preconditioner M of (blocks − adjacency).
    fn ssor(
        &self,
        n: usize,
        blocks: &[[f64; 3]],
        r: &[[f64; 2]],
        z: &mut [[f64; 2]],
        t: &mut [[f64; 2]],
    ) {
        let w = SSOR_OMEGA;
        // Forward: (D/ω − lower)·x = r, into t.
        for j in 0..n {
            let mut b = r[j];
            if self.nodes[j].inv_k != 0.0 {
                for &q in &self.nodes[j].neighbours {
                    let q = q as usize;
                    if q < j {
                        b[0] += t[q][0];
                        b[1] += t[q][1];
                    }
                }
            }
            let x = solve_block(blocks[j], b);
            t[j] = [w * x[0], w * x[1]];
        }
        // Middle: (D/ω)·x; backward: (D/ω − upper)·z = (D/ω)·x, into z.
        for j in (0..n).rev() {
            let m = blocks[j];
            let x = t[j];
            let mut b = [
                (m[0] * x[0] + m[1] * x[1]) / w,
                (m[1] * x[0] + m[2] * x[1]) / w,
            ];
            if self.nodes[j].inv_k != 0.0 {
                for &q in &self.nodes[j].neighbours {
                    let q = q as usize;
                    if q > j && q < n {
                        b[0] += z[q][0];
                        b[1] += z[q][1];
                    }
                }
            }
            let y = solve_block(m, b);
            z[j] = [w * y[0], w * y[1]];
        }
        let scale = (2.0 - w) / w;
        for v in z.iter_mut().take(n) {
            v[0] *= scale;
            v[1] *= scale;
        }
    }
}

/// The conjugate-gradient vectors, allocated once per descent.
struct Scratch {
    r: Vec<[f64; 2]>,
    z: Vec<[f64; 2]>,
    p: Vec<[f64; 2]>,
    q: Vec<[f64; 2]>,
    t: Vec<[f64; 2]>,
}

impl Scratch {
    fn new(n: usize) -> Scratch {
        let v = vec![[0.0; 2]; n];
        Scratch {
            r: v.clone(),
            z: v.clone(),
            p: v.clone(),
            q: v.clone(),
            t: v,
        }
    }
}

/// Σ a·b over pairs.
fn dot(a: &[[f64; 2]], b: &[[f64; 2]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| x[0] * y[0] + x[1] * y[1])
        .sum()
}

/// The positive semidefinite part of the symmetric 2 × 2 block m = (a11, a12, a22): its
/// negative eigenvalue (or both) set to 0. Newton's data block ∇R·∇Rᵀ − (I − R)·∇²R is
/// indefinite where the surface cannot match the picture; its positive part keeps every
/// step's system positive definite, and where the energy is convex it is Newton's own block
/// (the Gauss–Newton block ∇R·∇Rᵀ alone left the descent converging linearly, slowly, where
/// the residual I − R stays large: hundreds of steps on the eval's cases at λ = 10).
fn positive_part(m: [f64; 3]) -> [f64; 3] {
    let mean = 0.5 * (m[0] + m[2]);
    let half = 0.5 * (m[0] - m[2]);
    let radius = (half * half + m[1] * m[1]).sqrt();
    let (high, low) = (mean + radius, mean - radius);
    if low >= 0.0 {
        return m;
    }
    if high <= 0.0 || radius == 0.0 {
        return [0.0; 3];
    }
    // high·v·vᵀ for the unit eigenvector v of the larger eigenvalue.
    let (x, y) = if half >= 0.0 {
        (half + radius, m[1])
    } else {
        (m[1], radius - half)
    };
    let norm = x * x + y * y;
    let scale = high / norm;
    [scale * x * x, scale * x * y, scale * y * y]
}

/// m⁻¹·b for a symmetric positive-definite 2 × 2 block m = (a11, a12, a22).
fn solve_block(m: [f64; 3], b: [f64; 2]) -> [f64; 2] {
    let det = m[0] * m[2] - m[1] * m[1];
    [
        (m[2] * b[0] - m[1] * b[1]) / det,
        (m[0] * b[1] - m[1] * b[0]) / det,
    ]
}

/// ¼ Σ |Δu|² over the 4-neighbour pairs of two fixed pixels: the part of e_S no step moves,
/// so that the energies reported are [`Solution`]'s e_S + λ·e_R.
fn fixed_pairs_energy(bc: &BoundaryConditions) -> f64 {
    let (w, h) = (bc.roles.width(), bc.roles.height());
    let mut total = 0.0;
    for r in 0..h {
        for c in 0..w {
            let Some(a) = fixed_at(bc, c, r) else {
                continue;
            };
            for (c2, r2) in [(c + 1, r), (c, r + 1)] {
                if c2 < w && r2 < h {
                    if let Some(b) = fixed_at(bc, c2, r2) {
                        let (df, dg) = (b[0] - a[0], b[1] - a[1]);
                        total += 0.25 * (df * df + dg * dg);
                    }
                }
            }
        }
    }
    total
}

/// The fixed value at (c, r), if the pixel is fixed.
fn fixed_at(bc: &BoundaryConditions, c: usize, r: usize) -> Option<[f64; 2]> {
    if *bc.roles.get(c, r) == Role::Fixed {
        bc.fixed_value(c, r)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::Boundary;
    use crate::gradient_space::angle_deg;
    use crate::light::Light;
    use crate::solver::tests::{bunny, picture};
    use crate::solver::{Method, SolveOptions};
    use crate::surface::{sphere, vase, Surface};

    /// Mean angle (degrees) from the truth over the mask.
    fn mean_error(solution: &Solution, truth: &Surface) -> f64 {
        let normals = solution.normals();
        let (mut sum, mut n) = (0.0, 0);
        for (i, inside) in truth.mask.data().iter().enumerate() {
            if *inside {
                sum += angle_deg(&normals.data()[i], &truth.normals.data()[i]);
                n += 1;
            }
        }
        sum / n as f64
    }

    /// Every λ from 0.01 to 100 converges on the sphere, the vase and the bunny under an
    /// oblique light; the energy never rises from one step of the descent to the next; where
    /// the cycles converge alone (λ = 1 here), nothing else runs.
    #[test]
    fn every_lambda_converges_with_an_energy_that_never_rises() {
        let light = Light::from_tilt_slant(0.0, 45.0).unwrap();
        for (name, surface) in [
            ("sphere", sphere(96, 96, 0.45 * 96.0).unwrap()),
            ("vase", vase(96, 96).unwrap()),
            ("bunny", bunny(96)),
        ] {
            let (image, map) = picture(&surface, light);
            let mut solver = Solver::new(96, 96).unwrap();
            let mut at_one = f64::NAN;
            for lambda in [0.01, 0.1, 1.0, 10.0, 30.0, 100.0] {
                let options = SolveOptions {
                    lambda,
                    ..SolveOptions::default()
                };
                let s = solver
                    .solve(&image, &surface.mask, &Boundary::Occluding, &map, &options)
                    .unwrap();
                let what = format!(
                    "{name} λ = {lambda}: {} iterations, last update {:.2e}, globalised {}",
                    s.iterations, s.last_update, s.globalised
                );
                assert!(s.converged && !s.diverged && s.last_update < 1e-6, "{what}");
                for pair in s.energy_history.windows(2) {
                    assert!(pair[1] <= pair[0], "{what}: energy rose {pair:?}");
                }
                if s.globalised {
                    let last = *s.energy_history.last().unwrap_or(&f64::NAN);
                    let end = s.smoothness_energy + lambda * s.brightness_energy;
                    assert!(
                        (last - end).abs() <= 1e-9 * end.max(1.0),
                        "{what}: {last} {end}"
                    );
                }
                if lambda == 1.0 {
                    assert!(!s.globalised, "{what}");
                }
                let err = mean_error(&s, &surface);
                // From λ = 1 on the data term rules: a larger λ finds the shape as well as
                // λ = 1 does (the errors are mostly in the attached shadow, which no λ sees).
                if lambda == 1.0 {
                    at_one = err;
                }
                if lambda > 1.0 {
                    assert!(
                        err < at_one + 1.0,
                        "{what}: {err}° against {at_one}° at λ = 1"
                    );
                }
                eprintln!("{what}: {err:.2}°");
            }
        }
    }

    /// At λ = 30, where Jacobi's sweeps blow up, the rendered sphere converges, to the shape
    /// as well as at λ = 1.
    #[test]
    fn a_sphere_at_lambda_30_converges_where_jacobi_blows_up() {
        let s = sphere(64, 64, 0.45 * 64.0).unwrap();
        let (image, map) = picture(&s, Light::from_tilt_slant(0.0, 45.0).unwrap());
        let mut solver = Solver::new(64, 64).unwrap();
        let mut run = |lambda: f64, method: Method| {
            let options = SolveOptions {
                lambda,
                ..SolveOptions::for_method(method)
            };
            solver
                .solve(&image, &s.mask, &Boundary::Occluding, &map, &options)
                .unwrap()
        };
        let jacobi = run(30.0, Method::Jacobi);
        assert!(jacobi.diverged, "Jacobi at λ = 30: {jacobi:?}");
        let at_one = run(1.0, Method::Multigrid);
        let at_30 = run(30.0, Method::Multigrid);
        assert!(!at_one.globalised && at_one.converged);
        assert!(at_30.converged && at_30.globalised, "{at_30:?}");
        assert!(!at_30.energy_history.is_empty());
        let (e1, e30) = (mean_error(&at_one, &s), mean_error(&at_30, &s));
        assert!(e30 < e1 + 0.5, "{e30}° at λ = 30, {e1}° at λ = 1");
    }

    #[test]
    fn the_watch_lets_steady_progress_run_and_stops_an_oscillation() {
        let mut steady = StallWatch::new(1.0);
        assert!((0..1_000).all(|i| !steady.stalled(0.97f64.powi(i))));
        let mut wobbly = StallWatch::new(1.0);
        let stop = (0..1_000).position(|i| wobbly.stalled(if i % 7 == 0 { 0.9 } else { 1.5 }));
        assert_eq!(stop, Some(STALL_WINDOW - 1));
    }
}
