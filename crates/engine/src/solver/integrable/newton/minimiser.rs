//! The Levenberg–Marquardt loop: damping, stretched and soft steps, Anderson acceleration and the
//! final relaxation of lagging pixels.

use super::*;

/// The relative residual each step's conjugate-gradient solve stops at.
pub const CG_TOL: f64 = 0.1;

/// The most conjugate-gradient iterations of one step's solve.
pub const CG_MAX_ITER: usize = 100;

/// Where each step's conjugate-gradient solve stops.
pub(super) const CG_STOP: Stop = Stop {
    tol: CG_TOL,
    max_iter: CG_MAX_ITER,
};

/// How many past steps the Anderson acceleration of the steps combines (see the module
/// documentation): 3 and 5 took the same steps within 5 % on the evaluation's hard rows, and
/// each costs two vectors of the unknowns' length.
pub const LM_ANDERSON_DEPTH: usize = 3;

/// The damping ν of the first step (relative to H's diagonal).
pub(super) const START_DAMPING: f64 = 1e-3;

/// Where E falls by more than this many times the model's decrease, the step is stretched
/// along its direction.
pub(super) const STRETCH_ABOVE: f64 = 1.2;

/// How many stretches are tried, each a third as far beyond 1 as the last.
pub(super) const STRETCH_TRIES: usize = 3;

/// The most a step is stretched.
pub(super) const MAX_STRETCH: f64 = 8.0;

/// The soft model is taken up once a step whose largest change of f or g is below this finds
/// E flatter than the model (the end of a minimisation, where the stiff model's steps shrink
/// by a constant factor).
pub(super) const SOFT_BELOW: f64 = 1e-3;

/// The soft model is left where E falls by less than this share of its predicted decrease.
pub(super) const SOFT_TRUSTED: f64 = 0.5;

/// How many times the soft model may be left before the minimisation keeps to the stiff one:
/// where many pixels move at once, the soft model's negative curvatures line up and its steps
/// predict badly again and again (the free boundary on the ball photographs).
pub(super) const SOFT_TRIES: usize = 4;

/// The largest change of a pixel's f or g that one step may make (the visible hemisphere is
/// the disc |(f, g)| ≤ 2); a longer step is retried with more damping.
pub(super) const MAX_STEP: f64 = 1.0;

/// How many times one step may raise the damping before it gives up (ν × 4 each time).
pub(super) const MAX_RETRIES: usize = 30;

/// How pixels are relaxed one by one at the end of a minimisation (see the module's
/// documentation).
pub(super) struct Relaxation {
    /// Pixels are relaxed after each step whose largest change of f or g is below this.
    pub(super) below: f64,
    /// The pixels relaxed: those that the step moved by more than this share of its largest
    /// change,
    pub(super) share: f64,
    /// and only where they are at most this share of the unknowns: where the step moves most
    /// pixels alike (the free boundary on the ball photographs), it moves a smooth mode that
    /// only the whole step can, and relaxing pixel by pixel works against it.
    pub(super) most: f64,
    /// How many times the chosen pixels are relaxed in turn after a step.
    pub(super) sweeps: usize,
    /// Newton iterations of one pixel's relaxation.
    pub(super) iterations: usize,
    /// How many times a relaxation step is halved before the pixel stays where it is.
    pub(super) halvings: usize,
    /// A relaxation step's largest change of f or g.
    pub(super) max_step: f64,
    /// A pixel's 2 × 2 Hessian is raised until its least eigenvalue is this share of its
    /// largest.
    pub(super) floor: f64,
}

/// The relaxation's settings.
pub(super) const RELAX: Relaxation = Relaxation {
    below: 1e-2,
    share: 0.1,
    most: 0.1,
    sweeps: 3,
    iterations: 20,
    halvings: 30,
    max_step: 0.25,
    floor: 1e-3,
};

/// Levenberg–Marquardt on an [`Energy`].
pub(in crate::solver::integrable) struct Minimiser {
    /// The point [f…, g…, z…].
    pub(in crate::solver::integrable) x: Vec<f64>,
    pub(super) grad: Vec<f64>,
    pub(super) e: f64,
    pub(super) nu: f64,
    /// Conjugate-gradient iterations so far.
    pub(in crate::solver::integrable) cg_iterations: usize,
    /// The preconditioner, planned at the first step for the model's pattern (the same at
    /// every point) and refilled at each, and its V-cycle's buffers.
    pub(super) multigrid: Option<(Multigrid, Vec<[Vec<f64>; 3]>)>,
    /// Whether the steps use the soft model (see [`Energy::linearise`]).
    pub(super) soft: bool,
    /// How many times the soft model predicted badly (after [`SOFT_TRIES`], it is not taken up
    /// again).
    pub(super) soft_failed: usize,
    /// The acceleration of the steps, and the point before this step that it reads.
    pub(super) anderson: Anderson,
    pub(super) start: Vec<f64>,
    /// A point tried (a step's end, a stretched one, the accelerated one) and E's gradient
    /// there, swapped with `x` and `grad` where it is taken; and `value_and_gradient`'s 2n
    /// values of scratch.
    pub(super) trial: Vec<f64>,
    pub(super) trial_grad: Vec<f64>,
    pub(super) scratch: Vec<f64>,
}

impl Minimiser {
    /// Starts at `x`.
    pub(in crate::solver::integrable) fn new(energy: &Energy, x: Vec<f64>) -> Minimiser {
        Minimiser::with_acceleration(energy, x, LM_ANDERSON_DEPTH)
    }

    /// Starts at `x`, the steps accelerated over `depth` past steps (0: plain
    /// Levenberg–Marquardt).
    pub(super) fn with_acceleration(energy: &Energy, x: Vec<f64>, depth: usize) -> Minimiser {
        let len = x.len();
        let mut grad = vec![0.0; len];
        let mut scratch = vec![0.0; 2 * energy.len()];
        let e = energy.value_and_gradient(&x, &mut grad, &mut scratch);
        Minimiser {
            x,
            grad,
            e,
            nu: START_DAMPING,
            cg_iterations: 0,
            multigrid: None,
            soft: false,
            soft_failed: 0,
            anderson: Anderson::new(len, depth, Restart::Never),
            start: vec![0.0; len],
            trial: vec![0.0; len],
            trial_grad: vec![0.0; len],
            scratch,
        }
    }

    /// E now.
    #[cfg(test)]
    pub(in crate::solver::integrable) fn energy(&self) -> f64 {
        self.e
    }

    /// One step that lowers E (raising the damping until one does), then accelerated where
    /// that lowers E further; returns the largest change of f or g, 0 when no step lowers E.
    pub(in crate::solver::integrable) fn step(&mut self, energy: &Energy) -> f64 {
        self.start.copy_from_slice(&self.x);
        let change = self.descend(energy);
        if change == 0.0 {
            return 0.0;
        }
        change.max(self.accelerate(energy))
    }

    /// The Anderson-mixed point of the steps so far ([`LM_ANDERSON_DEPTH`]), taken where E is
    /// lower there than after this step; returns how far it moved f or g from there (0 where
    /// it was not taken).
    pub(super) fn accelerate(&mut self, energy: &Energy) -> f64 {
        self.trial.copy_from_slice(&self.x);
        if !self.anderson.step(&self.start, &mut self.trial) {
            return 0.0;
        }
        let e = energy.value_and_gradient(&self.trial, &mut self.trial_grad, &mut self.scratch);
        if e.is_nan() || e >= self.e {
            return 0.0;
        }
        let n = energy.len();
        let moved =
            crate::solver::integrable::largest_change(&self.trial[..2 * n], &self.x[..2 * n]);
        std::mem::swap(&mut self.x, &mut self.trial);
        std::mem::swap(&mut self.grad, &mut self.trial_grad);
        self.e = e;
        moved
    }

    /// One Levenberg–Marquardt step that lowers E (raising the damping until one does),
    /// stretched and relaxed as the module's documentation says; returns the largest change
    /// of f or g, 0 when no step lowers E.
    pub(super) fn descend(&mut self, energy: &Energy) -> f64 {
        let n = energy.len();
        let model = energy.linearise(&self.x, self.soft);
        if crate::cancel::requested() {
            return 0.0;
        }
        // Planned at the first step for the model's pattern and refilled at each; filled for
        // this step's first damping, it serves the raised ones too: a larger ν only makes the
        // matrix more diagonal.
        // A requested stop ends the step where it is, lowering nothing: every phase of a
        // step at 1024² (planning, filling, each damping's solve) is up to seconds, and the
        // caller's loop stops on the same flag.
        if self.multigrid.is_none() {
            let positions = |emit: &mut dyn FnMut(u32, u32)| {
                model.entries(self.nu, |r, c, _| emit(r, c));
            };
            let Some(mg) = Multigrid::plan(3 * n, positions, energy.places()) else {
                return 0.0;
            };
            let cycle = mg.scratch();
            self.multigrid = Some((mg, cycle));
        }
        let Some((mg, cycle)) = self.multigrid.as_mut() else {
            unreachable!("planned above")
        };
        if crate::cancel::requested() {
            return 0.0;
        }
        // The values go straight into the matrix, in the order the plan listed them.
        mg.fill(|emit| model.entries(self.nu, |_, _, v| emit(v)));
        let b: Vec<f64> = self.grad.iter().map(|g| -g).collect();
        let mut delta = vec![0.0; b.len()];
        let (trial, trial_grad, scratch) =
            (&mut self.trial, &mut self.trial_grad, &mut self.scratch);
        for _ in 0..MAX_RETRIES {
            if crate::cancel::requested() {
                return 0.0;
            }
            self.cg_iterations += model.solve(self.nu, (mg, cycle), &b, &mut delta, CG_STOP);
            if crate::cancel::requested() {
                return 0.0;
            }
            let largest = delta[..2 * n].iter().fold(0.0f64, |a, d| a.max(d.abs()));
            if largest > MAX_STEP {
                // Farther than the model can be trusted: more damping.
                self.nu *= 4.0;
                continue;
            }
            let slope = dot(&self.grad, &delta);
            let predicted = -(slope + model.quadratic(&delta));
            for ((t, x), d) in trial.iter_mut().zip(&self.x).zip(&delta) {
                *t = x + d;
            }
            let e = energy.value_and_gradient(trial, trial_grad, scratch);
            let actual = self.e - e;
            if actual > 0.0 && predicted > 0.0 {
                // Nielsen's rule: less damping where the model predicted well.
                let rho = actual / predicted;
                self.nu = (self.nu * (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0)).max(1e-12);
                // The soft model once small steps find E flatter than the model; the stiff one
                // again where the soft one predicts badly, for good after SOFT_TRIES times.
                if rho > STRETCH_ABOVE && largest < SOFT_BELOW && self.soft_failed < SOFT_TRIES {
                    self.soft = true;
                } else if self.soft && rho < SOFT_TRUSTED {
                    self.soft = false;
                    self.soft_failed += 1;
                }
                let start = self.e;
                std::mem::swap(&mut self.x, trial);
                std::mem::swap(&mut self.grad, trial_grad);
                self.e = e;
                let mut stretch = 1.0;
                if rho > STRETCH_ABOVE {
                    // E fell by more than the model said: along δ it is flatter than the
                    // model. Its parabola through E at 0 and 1 with the slope at 0 has its
                    // least at α; tried there, then closer to 1 where E is no parabola that
                    // far.
                    let curvature = 2.0 * (e - start - slope);
                    let mut alpha = if curvature > 0.0 {
                        (-slope / curvature).min(MAX_STRETCH)
                    } else {
                        MAX_STRETCH
                    };
                    for _ in 0..STRETCH_TRIES {
                        if alpha <= 1.05 {
                            break;
                        }
                        for ((t, x), d) in trial.iter_mut().zip(&self.x).zip(&delta) {
                            *t = x + (alpha - 1.0) * d;
                        }
                        let longer = energy.value_and_gradient(trial, trial_grad, scratch);
                        if longer < self.e {
                            std::mem::swap(&mut self.x, trial);
                            std::mem::swap(&mut self.grad, trial_grad);
                            self.e = longer;
                            stretch = alpha;
                            break;
                        }
                        alpha = 1.0 + (alpha - 1.0) / 3.0;
                    }
                }
                if stretch * largest >= RELAX.below {
                    return stretch * largest;
                }
                // The pixels the step moved most, each moved to the least of E along its own
                // orientation: where E is flatter than the model along a pixel's orientation,
                // the model's steps move it a little at a time.
                let cut = RELAX.share * largest;
                let chosen: Vec<usize> = (0..n)
                    .filter(|&j| delta[j].abs().max(delta[n + j].abs()) > cut)
                    .collect();
                if chosen.len() as f64 > RELAX.most * n as f64 {
                    return stretch * largest;
                }
                let before: Vec<(f64, f64)> = chosen
                    .iter()
                    .map(|&j| {
                        (
                            self.x[j] - stretch * delta[j],
                            self.x[n + j] - stretch * delta[n + j],
                        )
                    })
                    .collect();
                for _ in 0..RELAX.sweeps {
                    for &j in &chosen {
                        energy.relax(&mut self.x, j);
                    }
                }
                self.e = energy.value_and_gradient(&self.x, &mut self.grad, scratch);
                let relaxed = chosen.iter().zip(&before).fold(0.0f64, |a, (&j, &(f, g))| {
                    a.max((self.x[j] - f).abs()).max((self.x[n + j] - g).abs())
                });
                return (stretch * largest).max(relaxed);
            }
            self.nu *= 4.0;
        }
        0.0
    }
}
