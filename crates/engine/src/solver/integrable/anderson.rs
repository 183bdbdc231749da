//! Anderson acceleration of a fixed-point iteration x ← T(x) (Walker & Ni 2011, "Anderson
//! acceleration for fixed-point iterations", SIAM J. Numer. Anal. 49(4)), shared by the
//! integrable method's two iterations: the alternation of depth solves and gradient sweeps
//! (`integrable.rs`), and the Levenberg–Marquardt steps on its energy (`newton.rs`).
//!
//! The next iterate is T(x) − Σ γᵢ ΔTᵢ, with ΔTᵢ the differences of the last `depth` results
//! and γ the least-squares coefficients that make the same combination of the residuals
//! r = T(x) − x smallest. On a linear iteration this is GMRES on its residuals: the history
//! spans the slow modes that the plain iteration takes thousands of steps to leave.
//!
//! When the history is dropped is the caller's choice ([`Restart`]): the alternation drops it
//! whenever the residual's norm grew (it has no energy to check the mixed iterate by); the
//! Levenberg–Marquardt steps keep it and take the mixed iterate only where it lowers their
//! energy. Every sum runs in index order on one thread, so the result does not depend on the
//! thread count.

/// When an [`Anderson`] acceleration drops its history.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Restart {
    /// Whenever the residual's norm grew (as the momentum that the acceleration replaced was
    /// restarted): for an iteration with no objective to check the mixed iterate by.
    OnGrowth,
    /// Only where the least-squares problem is singular: for an iteration whose caller checks
    /// each mixed iterate itself. Along a long valley the steps (the residuals) grow while the
    /// objective falls, and restarting there undid the acceleration (measured on ball
    /// photograph 052 with the free boundary: the mixed iterate was taken at 2 of 400 steps).
    Never,
}

/// Anderson acceleration over vectors of one length (see the module documentation).
pub(super) struct Anderson {
    /// The largest number of differences kept (0: the plain iteration).
    depth: usize,
    restart: Restart,
    /// Differences of consecutive residuals, oldest first.
    residual_steps: Vec<Vec<f64>>,
    /// Differences of consecutive results, oldest first.
    result_steps: Vec<Vec<f64>>,
    /// The last residual and result, and a buffer for the present residual.
    last_residual: Vec<f64>,
    last_result: Vec<f64>,
    residual: Vec<f64>,
    /// The last residual's norm (∞ before the first step).
    last_norm: f64,
}

impl Anderson {
    /// Acceleration over vectors of `len` values, keeping `depth` differences.
    pub(super) fn new(len: usize, depth: usize, restart: Restart) -> Anderson {
        Anderson {
            depth,
            restart,
            residual_steps: Vec::new(),
            result_steps: Vec::new(),
            last_residual: vec![0.0; len],
            last_result: vec![0.0; len],
            residual: vec![0.0; len],
            last_norm: f64::INFINITY,
        }
    }

    /// One step: `x` the iteration's input, `result` T(x), replaced by the next iterate.
    /// Returns whether a combination was applied (false while there is no history: `result`
    /// is then left as it is).
    pub(super) fn step(&mut self, x: &[f64], result: &mut [f64]) -> bool {
        for ((r, t), x) in self.residual.iter_mut().zip(&*result).zip(x) {
            *r = t - x;
        }
        let norm = dot(&self.residual, &self.residual).sqrt();
        let grew = norm > self.last_norm && self.restart == Restart::OnGrowth;
        if norm.is_nan() || grew {
            // Grew, or not a number: restart.
            self.clear();
        } else if self.depth > 0 && self.last_norm.is_finite() {
            push_difference(
                &mut self.residual_steps,
                self.depth,
                &self.residual,
                &self.last_residual,
            );
            push_difference(
                &mut self.result_steps,
                self.depth,
                result,
                &self.last_result,
            );
        }
        std::mem::swap(&mut self.last_residual, &mut self.residual);
        self.last_result.copy_from_slice(result);
        self.last_norm = if norm.is_nan() { f64::INFINITY } else { norm };
        let Some(gamma) = least_squares(&self.residual_steps, &self.last_residual) else {
            self.clear();
            return false;
        };
        for (g, step) in gamma.iter().zip(&self.result_steps) {
            for (t, d) in result.iter_mut().zip(step) {
                *t -= g * d;
            }
        }
        !gamma.is_empty()
    }

    /// Drops the history (the last residual and result stay, for the next difference).
    fn clear(&mut self) {
        self.residual_steps.clear();
        self.result_steps.clear();
    }
}

/// Appends a − b to `history`, dropping (and reusing) its oldest entry once it holds `depth`.
fn push_difference(history: &mut Vec<Vec<f64>>, depth: usize, a: &[f64], b: &[f64]) {
    let mut difference = if history.len() >= depth {
        history.remove(0)
    } else {
        Vec::with_capacity(a.len())
    };
    difference.clear();
    difference.extend(a.iter().zip(b).map(|(a, b)| a - b));
    history.push(difference);
}

/// The coefficients γ that minimise |r − Σ γᵢ columnsᵢ| (normal equations, with a relative
/// ridge of 1e-10 on their diagonal, by Gaussian elimination with partial pivoting); empty
/// for no columns, `None` for a singular or non-finite system.
fn least_squares(columns: &[Vec<f64>], r: &[f64]) -> Option<Vec<f64>> {
    let k = columns.len();
    // The augmented matrix [AᵀA | Aᵀr].
    let mut a = vec![vec![0.0; k + 1]; k];
    let mut trace = 0.0;
    for i in 0..k {
        for j in 0..=i {
            let v = dot(&columns[i], &columns[j]);
            a[i][j] = v;
            a[j][i] = v;
        }
        trace += a[i][i];
        a[i][k] = dot(&columns[i], r);
    }
    for (i, row) in a.iter_mut().enumerate() {
        row[i] += 1e-10 * trace;
    }
    for col in 0..k {
        let pivot = (col..k)
            .max_by(|&p, &q| a[p][col].abs().total_cmp(&a[q][col].abs()))
            .unwrap_or(col);
        a.swap(col, pivot);
        let d = a[col][col];
        if !(d.abs() > 0.0 && d.is_finite()) {
            return None;
        }
        let (upper, lower) = a.split_at_mut(col + 1);
        let pivot_row = &upper[col];
        for row in lower.iter_mut() {
            let factor = row[col] / d;
            for (x, p) in row[col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= factor * p;
            }
        }
    }
    let mut gamma = vec![0.0; k];
    for i in (0..k).rev() {
        let tail: f64 = (i + 1..k).map(|j| a[i][j] * gamma[j]).sum();
        gamma[i] = (a[i][k] - tail) / a[i][i];
    }
    gamma.iter().all(|g| g.is_finite()).then_some(gamma)
}

/// Σ aᵢbᵢ in index order.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs x ← Mx + b (M given by `map`) from 0 with `anderson` until x is within 1e-8 of
    /// `fixed` or 100 steps; returns the steps taken.
    fn steps_to_fixed_point(
        mut anderson: Anderson,
        map: impl Fn(&[f64]) -> Vec<f64>,
        fixed: &[f64],
    ) -> usize {
        let mut x = vec![0.0; fixed.len()];
        let mut steps = 0;
        while super::super::largest_change(&x, fixed) > 1e-8 && steps < 100 {
            let mut t = map(&x);
            anderson.step(&x, &mut t);
            x = t;
            steps += 1;
        }
        steps
    }

    /// Anderson acceleration on a linear contraction x ← Mx + b whose slowest mode contracts
    /// by 0.999 per step: the plain iteration needs thousands of steps, the accelerated one
    /// reaches the fixed point in a handful (as GMRES would: the history spans the modes),
    /// whichever the restart policy (the residuals only shrink here).
    #[test]
    fn anderson_solves_a_slow_linear_contraction() {
        let rates = [0.999, 0.99, 0.9, 0.5];
        let b = [1.0, -2.0, 0.5, 3.0];
        let fixed: Vec<f64> = rates.iter().zip(&b).map(|(m, b)| b / (1.0 - m)).collect();
        let map = |x: &[f64]| -> Vec<f64> {
            x.iter()
                .zip(rates.iter().zip(&b))
                .map(|(x, (m, b))| m * x + b)
                .collect()
        };
        for restart in [Restart::OnGrowth, Restart::Never] {
            let steps = steps_to_fixed_point(Anderson::new(4, 5, restart), map, &fixed);
            // The plain iteration would need ln(1e-8 / 1000) / ln(0.999) ≈ 25,000 steps.
            assert!(steps <= 8, "{restart:?}: {steps}");
        }
        // Depth 0 is the plain iteration.
        let plain = steps_to_fixed_point(Anderson::new(4, 0, Restart::Never), map, &fixed);
        assert_eq!(plain, 100);
    }

    /// A contraction whose residuals grow before they shrink (M = [[0.95, 1], [0, 0.95]], not
    /// normal: the residual r ← M r grows while its second component feeds the first): kept,
    /// the history solves the two-dimensional problem in four steps, as GMRES would; dropped
    /// at every growth, the acceleration is lost for as long as the residual grows.
    #[test]
    fn a_kept_history_rides_out_growing_residuals() {
        let b = [0.0, 1.0];
        let map = |x: &[f64]| vec![0.95 * x[0] + x[1] + b[0], 0.95 * x[1] + b[1]];
        // (I − M) x = b: x₁ = 1 / 0.05 = 20, x₀ = 20 / 0.05 = 400.
        let fixed = [400.0, 20.0];
        let kept = steps_to_fixed_point(Anderson::new(2, 3, Restart::Never), map, &fixed);
        let dropped = steps_to_fixed_point(Anderson::new(2, 3, Restart::OnGrowth), map, &fixed);
        assert!(kept <= 4, "{kept}");
        assert!(dropped > kept + 2, "{dropped} {kept}");
    }

    /// The mixed iterate is T(x) less the combination of past results that best cancels the
    /// residual: on a step with one difference kept, checked against the formula by hand.
    #[test]
    fn one_difference_mixes_by_its_least_squares_coefficient() {
        let mut anderson = Anderson::new(2, 1, Restart::Never);
        let (x0, mut t0) = ([0.0, 0.0], [1.0, 2.0]);
        assert!(!anderson.step(&x0, &mut t0), "no history yet");
        assert_eq!(t0, [1.0, 2.0]);
        let (x1, mut t1) = ([1.0, 2.0], [1.5, 2.5]);
        assert!(anderson.step(&x1, &mut t1));
        // r0 = (1, 2), r1 = (0.5, 0.5); Δr = (−0.5, −1.5), ΔT = (0.5, 0.5);
        // γ = Δr·r1 / Δr·Δr = −1 / 2.5 = −0.4 (less the 1e-10 ridge); T − γ ΔT = (1.7, 2.7).
        assert!(
            (t1[0] - 1.7).abs() < 1e-9 && (t1[1] - 2.7).abs() < 1e-9,
            "{t1:?}"
        );
    }
}
