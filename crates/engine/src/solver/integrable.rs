//! The integrable method ([`super::Method::Integrable`]): gradients and depth solved together,
//! after Horn (1990), "Height and gradient from shading" (IJCV 5(1)).
//!
//! The unknowns are the orientations (f, g) of the domain's unknown pixels and the depth z of
//! the whole domain. The energy is
//!
//! E = σ·e_S + λ·e_R + μ·e_I,  e_I = ¼ Σ_pixels |(f, g) − (f, g)_z|²,
//!
//! with e_S and e_R the Ikeuchi–Horn terms (`mod.rs`) and (f, g)_z the orientation of the depth
//! at the pixel: its slopes are the mean of the depth differences across the pixel's edges in
//! the domain (the central difference inside, the one-sided one at the domain's edge). The
//! method alternates two steps, each of which lowers an objective of its own:
//!
//! 1. **depth**: z is the least-squares integral of the slopes of (f, g) on the unknown
//!    pixels, the masked Poisson solve of [`crate::integrate::integrate_gradients`] (the same
//!    one that turns any solve's normals into depth), each solve started from the previous
//!    depth ([`crate::integrate::integrate_gradients_from`]). The fixed ring is left out of
//!    this fit: at the occluding limb its slopes are infinite (capped at 1/`DEFAULT_MIN_NZ` =
//!    20), and fitting them bent the depth, and so the pull, near the boundary (leaving it out
//!    lowered the evaluation's errors by 0.3–4° on the bunny, Mozart frontal, buddha, cow,
//!    harvest and reading, raised goblet's by 2.8° and the 26° balls' by 0.1–0.3°). A pixel
//!    with no unknown neighbour along x or along y is not pulled (the depth cannot tilt it that
//!    way);
//! 2. **gradients**: a few sweeps of the Ikeuchi–Horn update pulled toward (f, g)_z,
//!
//!    x ← x̃ + 4λ(φ(I) − φ(R(x̃)))·J / (D + 4λ|J|²),  J = φ′(R(x̃))·∇R(x̃),
//!    x̃ = (σk·x̄ + μ·x_z)/D,  D = σk + μ,
//!
//!    for x = (f, g), x̄ the mean of the k neighbours in the domain: the pixel's equation
//!    linearised at x̃ and solved exactly (a pointwise Gauss–Newton step), which no choice of
//!    λ, σ or μ makes unstable.
//!
//! **The data residual is measured as an angle** (session 9). The brightness residual I − R
//! loses its grip near the brightest orientation: R = cos θ (θ the angle to the light) is flat
//! at θ = 0, so a normal 10° from the light is only 1.5 % darker than one facing it, and the
//! smoothness and integrability terms alone place the orientations around the brightest point
//! (on a rendered ball lit at 43°, they put it several pixels off and left a fan of 10–20°
//! errors around it). φ(u) = asin(u), u = (R − ambient)/(peak − ambient), is 90° − θ for a
//! Lambertian surface: the residual φ(I) − φ(R) is the angle between the orientation the pixel
//! has and the one its brightness asks for, as firm at the top as at the terminator. Above
//! u = 0.943 (19.5° from the light) φ continues as a straight line of slope
//! [`ANGLE_SLOPE_CAP`] = 3, so that a pixel at the peak, where asin's slope is infinite, does
//! not amplify noise, a highlight or an albedo error without bound (uncapped, Mozart frontal
//! diverged). The warm start (multigrid) keeps the brightness residual. On the evaluation this
//! lowered most rows (rendered ball 041 6.30° → 4.25°, Mozart frontal 12.15° → 10.80°, see
//! docs/evaluation.md).
//!
//! It starts from the Ikeuchi–Horn solution (multigrid, with its globalisation), with σ =
//! [`SIGMA`] = 1 and μ = [`MU`]. Horn proposes shrinking σ once the field must be integrable;
//! on the evaluation's cases σ = 0.5 gained a little on Mozart (12.2° against 12.8° frontal)
//! but let the folded DiLiGenT objects drift to wrong surfaces (goblet 55.9°, reading 57.3°),
//! so σ stays 1. The boundary conditions are the solver's: the fixed pixels (the occluding
//! limb, the flat rim) keep their (f, g) and take part in the depth solve; a free edge has
//! fewer neighbours, as before. Pixels in attached shadow carry no data term.
//!
//! One iteration is one depth solve and [`SWEEPS`] sweeps, a map y = T(x) of the (f, g); the
//! alternation alone contracts slowly (about 0.98 per iteration on the ball photographs: the
//! smooth part of the field moves the way a Jacobi sweep moves it). Up to session 9 the next
//! iterate was y + β·(y − y_previous) with momentum β = 0.8, restarted whenever the
//! update grew; since session 10 it is **Anderson acceleration** (Walker & Ni 2011): T(x) less
//! the combination of the last [`ANDERSON_DEPTH`] = 5 steps of T whose matching combination of
//! residuals T(x) − x best cancels the present one (a 5 × 5 least-squares problem, summed in
//! index order on one thread), the history dropped whenever the residual's norm grew. It has
//! converged when an iteration moves no f or g by more than `tol` (the test is unchanged).
//! Everything runs in a fixed order (sweeps in fixed chunks, the Poisson solve and the
//! acceleration sequential), so the result does not depend on the thread count.
//!
//! **Speed (session 10, measured).** Where the time went (perf, the Mozart rows, one thread):
//! the sweeps about 55 % (asin 12 %, the reflectance map 5 %), the depth solves about 30 %, of
//! which a tenth rebuilt the Poisson hierarchy (twice per warm-started solve) and the mask's
//! parts each iteration. Both are now built once per solve
//! ([`crate::integrate::PreparedMask`]) and φ(I) once per pixel instead of in every sweep: the
//! same bytes (every picture of the evaluation identical), fewer instructions per iteration.
//! The acceleration cut the iterations of the rows that converge (ball 041 59 → 37, ball 052
//! 24 → 20, bunny 45° 154 → 92, −135° 100 → 58, cow 54 → 49, buddha 183 → 163; on a 64²
//! oblique sphere 90 → 22 and a bump 997 → 58 against the plain alternation, the same fixed
//! point within 1.4e-3 in f, g and 0.02° mean error) and made five of the six free-boundary
//! ball rows converge (93–196 iterations, 0.75–5.5° better); Mozart frontal takes 178
//! iterations instead of 159 and Beethoven image2 reaches the cap (it converged in 114).
//! Together: ball 041 in 2.75 G instructions instead of 4.90 G (callgrind, the whole command;
//! 3.79 G with the same 59 iterations). [`SWEEPS`] 5 or 20 instead of 10 lost more than they
//! gained (5: five more rows stop at the cap; 20: 50 % more time). Tried and dropped: a
//! **coarse-to-fine start** (the integrable problem on the half-size grids, λ and μ × 4 per
//! level, interpolated up): the coarse levels settle in other basins (Mozart frontal 10.80° →
//! 14.18°, Mozart oblique occluding 16.99° → 56.06°) and the finest level of ball 041 still
//! took 63 iterations (59 from multigrid): what keeps the iteration long is not a smooth start
//! error but fronts that move across the object. **What stays unconverged** (bear, cat,
//! goblet, harvest, pot1, pot2, reading, both oblique Mozart rows, the free-boundary ball 052,
//! Beethoven image2): at the cap the largest change per iteration is 0.1–1 in f or g (goblet:
//! 15,000 of its pixels still move by more than 1e-4 per iteration, with or without momentum,
//! and the pixel that moves most wanders over the object), or a slow drift of 5e-4–7e-4
//! (Mozart oblique free): the method has not settled, and a looser or relative test would
//! only hide it.
//!
//! **What the fixed point is (session 11, measured).** The alternation is written for E but does
//! not minimise it: the depth step fits the slopes on the domain's edges (the Poisson least
//! squares), not e_I in (f, g), and the sweep's equation is linearised at the neighbours' mean.
//! Its fixed point is where those two objectives balance. Evaluated after each iteration, 2E
//! on bear (limb) falls from 287 to 222.8 at iteration 5 and climbs to 262.0 at the fixed
//! point; on ball 041 (limb) it is lowest at iteration 6. The rows that stop at the cap of
//! [`INTEGRABLE_MAX_ITER`] are mid-transient: with a cap of 3000, 51 of the evaluation's 56
//! rows converge, mostly at worse errors (cat 14.76° → 19.48°, goblet 21.84° → 29.33°), so the
//! cap acts as an early stop. A descent on E itself (L-BFGS on (f, g, z), not kept: in 1000
//! iterations it converged on 3 rows and took twice the time) reached lower energies and lower
//! errors on 36 of 50 rows (cat 9.89°, bear 10.68°). docs/evaluation.md, "Session 11: the
//! coupled problem of the integrable method", has the figures.
//!
//! **E minimised itself: [`Method::IntegrableLm`] (session 12).** `integrable/newton.rs` takes
//! the same start (the multigrid solution and the depth of its slopes) and minimises E over
//! (f, g, z) together by Levenberg–Marquardt steps, each solved by conjugate gradients
//! preconditioned by the per-pixel blocks, each kept only if it lowers E. It is a method of
//! its own beside the alternation rather than a replacement: on the evaluation it is closer to
//! the truth on 36 of 56 rows (bear 15.91° → 9.89°, cat 14.76° → 9.87°, reading 18.60° →
//! 15.05°, 15 of the 18 DiLiGenT rows, the ball photographs by 0.04–0.44°, Mozart oblique with
//! the occluding boundary 16.85° → 11.94°) and farther on 11 (Mozart frontal 10.34° → 13.88°,
//! where E prefers the neck folded the other way, pot1 and harvest limb by 0.2–0.4°, the bunny
//! at slant 30° and 60° by 0.2–0.6°); it converged on 23 rows against 36 and took 1.8–20
//! times as long (the figures: docs/evaluation.md, "Session 12"). Session 13 preconditions its
//! linear solves by aggregation multigrid (`integrable/aggregation.rs`) and stretches a step
//! along its direction where E fell by more than the model said: it now converges on 41 rows,
//! in 3.1–32 times the alternation's time (median 6.1), and a 256² sphere converges in 48
//! steps where it stopped at the cap of 200 (docs/evaluation.md, "Session 13").
//!
//! The returned (f, g) are the last gradients, within μ's pull of the depth's own: integrating
//! them (as every solve is integrated) gives the depth of the last depth solve to within the
//! last iteration's change (below `tol` once converged).

use super::estimate::{Estimate, Level};
use super::{
    iterate, sweep_chunks, Method, Node, Posed, Progress, Solution, SolveOptions, Solver,
    MULTIGRID_MAX_CYCLES,
};
use crate::boundary::Role;
use crate::error::Result;
use crate::gradient_space::fg_from_pq;
use crate::grid::{Image, Mask};
use crate::integrate::{gradients_from_fg, PoissonOptions, PreparedMask, DEFAULT_MIN_NZ};
use crate::reflectance::ReflectanceMap;

/// Gradient sweeps per iteration (between two depth solves).
pub const SWEEPS: usize = 10;

/// The weight μ of the integrability term.
pub const MU: f64 = 0.5;

/// The weight σ of the smoothness term (see the module documentation).
pub const SIGMA: f64 = 1.0;

/// How many past iterations the Anderson acceleration combines (see the module documentation).
pub const ANDERSON_DEPTH: usize = 5;

/// The default cap on iterations of the integrable method (the warm start's multigrid cycles
/// not counted).
pub const INTEGRABLE_MAX_ITER: usize = 200;

/// The default cap on the steps of [`Method::IntegrableLm`] (the warm start's multigrid cycles
/// not counted): the slowest of the evaluation's rows, ball photograph 052 with the free
/// boundary (a light 4° from the view, and nothing at the outline to hold the shape), takes
/// 562–786 steps at λ = 0.1, 1, 10 and 30; every other row converges within 260 (session 16).
pub const INTEGRABLE_LM_MAX_STEPS: usize = 1000;

pub use newton::{CG_MAX_ITER, CG_TOL, LM_ANDERSON_DEPTH};

/// The relative tolerance of each depth solve. Each solve starts from the previous depth, so
/// what it leaves is carried into the next and keeps shrinking; 1e-5 per solve changed the
/// evaluation's errors by at most 0.01° against 1e-7, with a third fewer PCG iterations
/// (1e-4 moved ball 041 by 0.15°).
const POISSON_TOL: f64 = 1e-5;

/// Where [`Solver::minimise_from`] starts: the orientations (grids of the image's size; the
/// unknown pixels' values are read), the depth at the unknown pixels (`None`: the least-squares
/// depth of the orientations' slopes) and the factor on the integrability weight μ.
pub(super) struct LmStart<'a> {
    pub(super) f: &'a Image,
    pub(super) g: &'a Image,
    pub(super) depth: Option<&'a Image>,
    pub(super) weight: f64,
}

impl Solver {
    /// The integrable method on a domain already built (see the module documentation).
    pub(super) fn solve_integrable(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Solution> {
        self.integrable_with_history(posed, options, ANDERSON_DEPTH, progress)
    }

    /// Lays out the unknowns for `image` and starts them at the slopes `(f, g)`: returns the
    /// number of unknowns, the domain the depth is fitted on and its pull weights. The depth is
    /// fitted to the unknown pixels' slopes only: the fixed ring's (the limb's slopes are
    /// infinite, capped at 1/DEFAULT_MIN_NZ) would bend it near the boundary.
    fn start_at(
        &mut self,
        posed: Posed<'_>,
        lambda: f64,
        (f, g): (&Image, &Image),
    ) -> (usize, Mask, Vec<f64>) {
        let bc = posed.bc;
        let n = self.build(posed, lambda);
        for (j, &p) in self.pixels.iter().enumerate() {
            self.cur_f[j] = f.data()[p as usize];
            self.cur_g[j] = g.data()[p as usize];
        }
        self.next_f.clone_from(&self.cur_f);
        self.next_g.clone_from(&self.cur_g);
        let domain: Mask = bc.roles.map(|r| *r == Role::Unknown);
        let pull = pull_weights(&domain, &self.pixels);
        (n, domain, pull)
    }

    /// [`Solver::solve_integrable`] with Anderson acceleration over `history` iterations (0:
    /// the plain alternation, for comparison).
    fn integrable_with_history(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        history: usize,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Solution> {
        let reflectance = posed.reflectance;
        let warm = SolveOptions {
            method: Method::Multigrid,
            max_iter: MULTIGRID_MAX_CYCLES,
            ..*options
        };
        let start = self.solve_conditions(posed, &warm, &mut |_| {})?;
        if start.diverged || crate::cancel::requested() {
            return Ok(start);
        }
        let mut estimate = Estimate::new(vec![Level {
            unknowns: start.unknowns,
            tol: options.tol,
            cap: options.max_iter,
        }]);
        let progress = &mut |p: &Progress| progress(&estimate.report(p));
        if options.method == Method::IntegrableLm {
            let lm = LmStart {
                f: &start.f,
                g: &start.g,
                depth: None,
                weight: 1.0,
            };
            return self
                .minimise_from(posed, options, lm, progress)
                .map(|(solution, _)| solution);
        }
        let (n, domain, pull) = self.start_at(posed, options.lambda, (&start.f, &start.g));
        // The domain's Poisson hierarchy and parts, built once for every depth solve.
        let prepared = PreparedMask::new(&domain)?;
        // φ(I) of each unknown, which the sweeps read ten times per iteration.
        let scale = AngleScale::of(reflectance);
        let angles: Vec<f64> = self.nodes[..n]
            .iter()
            .map(|node| scale.angle(node.intensity))
            .collect();
        let poisson = PoissonOptions {
            tol: POISSON_TOL,
            ..PoissonOptions::default()
        };
        let mut depth: Option<Image> = None;
        let (mut target_f, mut target_g) = (vec![0.0; n], vec![0.0; n]);
        let (mut before_f, mut before_g) = (vec![0.0; n], vec![0.0; n]);
        // (input, result) of an iteration, f then g.
        let mut x = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
        let mut anderson = Anderson::new(2 * n, history, Restart::OnGrowth);
        let stats = iterate(n, options, progress, |_| {
            let (f, g) = self.current_fg();
            let (dz_dx, dz_dy) = gradients_from_fg(f, g, &domain, DEFAULT_MIN_NZ)?;
            // Each depth solve starts from the last one: the slopes moved little since.
            let z = prepared
                .integrate_gradients(&dz_dx, &dz_dy, &poisson, depth.as_ref())?
                .depth;
            depth_orientations(&z, &domain, &self.pixels, &mut target_f, &mut target_g);
            depth = Some(z);
            before_f.copy_from_slice(&self.cur_f[..n]);
            before_g.copy_from_slice(&self.cur_g[..n]);
            for _ in 0..SWEEPS {
                self.screened_sweep(
                    n,
                    reflectance,
                    Weights {
                        mu: &pull,
                        sigma: SIGMA,
                    },
                    &angles,
                    (&target_f, &target_g),
                );
                std::mem::swap(&mut self.cur_f, &mut self.next_f);
                std::mem::swap(&mut self.cur_g, &mut self.next_g);
            }
            let last_update = largest_change(&before_f, &self.cur_f[..n])
                .max(largest_change(&before_g, &self.cur_g[..n]));
            // The next iterate from this one and its result (Anderson acceleration).
            x.0[..n].copy_from_slice(&before_f);
            x.0[n..].copy_from_slice(&before_g);
            x.1[..n].copy_from_slice(&self.cur_f[..n]);
            x.1[n..].copy_from_slice(&self.cur_g[..n]);
            anderson.step(&x.0, &mut x.1);
            self.cur_f[..n].copy_from_slice(&x.1[..n]);
            self.cur_g[..n].copy_from_slice(&x.1[n..]);
            Ok(last_update)
        })?;
        Ok(self.solution(posed, stats))
    }

    /// The integrable energy minimised by Levenberg–Marquardt steps ([`Method::IntegrableLm`])
    /// from `start`, at most `options.max_iter` steps to `options.tol`; returns the solution
    /// and the depth of the last point (at the unknown pixels, 0 elsewhere). `start.weight`
    /// multiplies the integrability weight μ (the brightness term's λ is `options.lambda`):
    /// the coarse levels of [`Method::NestedLm`] weight both by the pixels each stands for.
    pub(super) fn minimise_from(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        start: LmStart<'_>,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<(Solution, Image)> {
        let Posed {
            image, reflectance, ..
        } = posed;
        let (n, domain, mut pull) = self.start_at(posed, options.lambda, (start.f, start.g));
        if start.weight != 1.0 {
            pull.iter_mut().for_each(|w| *w *= start.weight);
        }
        let scale = AngleScale::of(reflectance);
        let angles: Vec<f64> = self.nodes[..n]
            .iter()
            .map(|node| scale.angle(node.intensity))
            .collect();
        let computed;
        let z = match start.depth {
            Some(z) => z,
            None => {
                // The depth of the start's slopes starts the joint minimisation.
                let prepared = PreparedMask::new(&domain)?;
                let poisson = PoissonOptions {
                    tol: POISSON_TOL,
                    ..PoissonOptions::default()
                };
                let (f, g) = self.current_fg();
                let (dz_dx, dz_dy) = gradients_from_fg(f, g, &domain, DEFAULT_MIN_NZ)?;
                computed = prepared
                    .integrate_gradients(&dz_dx, &dz_dy, &poisson, None)?
                    .depth;
                &computed
            }
        };
        // The depth's Poisson solve above stops early on a requested stop: no step then.
        crate::cancel::check()?;
        let mut x = vec![0.0; 3 * n];
        x[..n].copy_from_slice(&self.cur_f[..n]);
        x[n..2 * n].copy_from_slice(&self.cur_g[..n]);
        for (j, &p) in self.pixels.iter().enumerate() {
            x[2 * n + j] = z.data()[p as usize];
        }
        let energy = newton::Energy::new(
            &self.nodes[..n],
            &self.pixels,
            &self.slot,
            (image.width(), image.height()),
            (&self.cur_f, &self.cur_g),
            &angles,
            &pull,
            reflectance,
        );
        let mut minimiser = newton::Minimiser::new(&energy, x);
        let stats = iterate(n, options, progress, |_| Ok(minimiser.step(&energy)))?;
        let x = minimiser.x;
        self.cur_f[..n].copy_from_slice(&x[..n]);
        self.cur_g[..n].copy_from_slice(&x[n..2 * n]);
        let mut depth = Image::new(image.width(), image.height(), 0.0);
        for (j, &p) in self.pixels.iter().enumerate() {
            depth.data_mut()[p as usize] = x[2 * n + j];
        }
        Ok((self.solution(posed, stats), depth))
    }

    /// One sweep of the screened update from `cur` into `next` (see the module documentation).
    fn screened_sweep(
        &mut self,
        n: usize,
        reflectance: &dyn ReflectanceMap,
        weights: Weights,
        angles: &[f64],
        target: (&[f64], &[f64]),
    ) {
        let (cur_f, cur_g) = (&self.cur_f[..], &self.cur_g[..]);
        sweep_chunks(
            &self.nodes,
            &mut self.next_f[..n],
            &mut self.next_g[..n],
            |nodes, first, nf, ng| {
                screened_nodes(
                    nodes,
                    first,
                    (cur_f, cur_g),
                    (nf, ng),
                    target,
                    (reflectance, angles),
                    weights,
                );
                0.0
            },
        );
    }
}

/// The weights of the smoothness (σ) and integrability (μ) terms in a sweep.
#[derive(Debug, Clone, Copy)]
struct Weights<'a> {
    mu: &'a [f64],
    sigma: f64,
}

/// The screened update of the unknowns `first..first + nodes.len()`.
fn screened_nodes(
    nodes: &[Node],
    first: usize,
    (cur_f, cur_g): (&[f64], &[f64]),
    (next_f, next_g): (&mut [f64], &mut [f64]),
    (target_f, target_g): (&[f64], &[f64]),
    (reflectance, angles): (&dyn ReflectanceMap, &[f64]),
    Weights { mu, sigma }: Weights,
) {
    let scale = AngleScale::of(reflectance);
    for (j, node) in nodes.iter().enumerate() {
        let [a, b, c, d] = node.neighbours.map(|s| s as usize);
        let sum_f = cur_f[a] + cur_f[b] + cur_f[c] + cur_f[d];
        let sum_g = cur_g[a] + cur_g[b] + cur_g[c] + cur_g[d];
        // k neighbours: inv_k = 1/k (0 for an isolated pixel), and λ·4/k is the data weight.
        let k = if node.inv_k > 0.0 {
            1.0 / node.inv_k
        } else {
            0.0
        };
        let (tf, tg) = (target_f[first + j], target_g[first + j]);
        let mu = mu[first + j];
        let denominator = sigma * k + mu;
        if denominator <= 0.0 {
            next_f[j] = cur_f[first + j];
            next_g[j] = cur_g[first + j];
            continue;
        }
        let f_tilde = (sigma * sum_f + mu * tf) / denominator;
        let g_tilde = (sigma * sum_g + mu * tg) / denominator;
        let (mut f_new, mut g_new) = (f_tilde, g_tilde);
        if node.data_weight != 0.0 {
            let four_lambda = node.data_weight * k;
            let s = reflectance.fg(f_tilde, g_tilde);
            // The residual and its gradient in angle units (module documentation).
            let (residual, slope) = scale.residual(angles[first + j], s.value);
            let (j1, j2) = (slope * s.d1, slope * s.d2);
            let gain = four_lambda * residual / (denominator + four_lambda * (j1 * j1 + j2 * j2));
            f_new += gain * j1;
            g_new += gain * j2;
        }
        next_f[j] = f_new;
        next_g[j] = g_new;
    }
}

mod aggregation;
mod anderson;
mod newton;

use anderson::{Anderson, Restart};

/// The slope cap of the angle residual: dφ/du ≤ [`ANGLE_SLOPE_CAP`], reached where the
/// brightness is 94 % of its peak (19.5° from the light for a Lambertian surface).
pub const ANGLE_SLOPE_CAP: f64 = 3.0;

/// The brightness of a reflectance map measured as an angle (module documentation): u = (R −
/// ambient)/(peak − ambient), the fraction of the brightness range above the ambient level,
/// taken to φ(u) = asin(u) (for a Lambertian surface, 90° less the angle between the normal
/// and the light), continued as a straight line of slope [`ANGLE_SLOPE_CAP`] above the
/// brightness where asin's slope reaches it.
#[derive(Debug, Clone, Copy)]
struct AngleScale {
    /// The ambient level.
    ambient: f64,
    /// peak − ambient, the brightness range (> 0), or 0 for a map without one.
    range: f64,
    /// The u above which φ is a straight line.
    knee: f64,
}

impl AngleScale {
    /// The scale of `reflectance`: its peak is its brightness facing the light.
    fn of(reflectance: &dyn ReflectanceMap) -> AngleScale {
        let ambient = reflectance.ambient();
        let range = reflectance.radiance(&reflectance.light().direction()) - ambient;
        AngleScale {
            ambient,
            range: if range.is_finite() && range > 0.0 {
                range
            } else {
                0.0
            },
            knee: (1.0 - 1.0 / (ANGLE_SLOPE_CAP * ANGLE_SLOPE_CAP)).sqrt(),
        }
    }

    /// φ(u).
    fn phi(&self, u: f64) -> f64 {
        if u <= self.knee {
            u.max(-1.0).asin()
        } else {
            self.knee.asin() + ANGLE_SLOPE_CAP * (u - self.knee)
        }
    }

    /// The brightness `intensity` as an angle, φ(u) (the brightness itself for a map with no
    /// brightness range): what [`AngleScale::residual`] takes.
    fn angle(&self, intensity: f64) -> f64 {
        if self.range == 0.0 {
            intensity
        } else {
            self.phi(self.fraction(intensity))
        }
    }

    /// d²φ/dR² at `value` (0 for a map with no brightness range and above the knee).
    fn second(&self, value: f64) -> f64 {
        if self.range == 0.0 {
            return 0.0;
        }
        let u = self.fraction(value);
        if u > self.knee {
            return 0.0;
        }
        let u = u.max(-self.knee);
        u / (1.0 - u * u).powf(1.5) / (self.range * self.range)
    }

    /// u of a brightness.
    fn fraction(&self, value: f64) -> f64 {
        (value - self.ambient) / self.range
    }

    /// The residual φ(intensity) − φ(value), given `angle` = [`AngleScale::angle`] of the
    /// intensity, and dφ/dR at `value` (the factor that turns ∇R into the residual's
    /// gradient); the plain brightness residual and 1 for a map with no brightness range.
    fn residual(&self, angle: f64, value: f64) -> (f64, f64) {
        if self.range == 0.0 {
            return (angle - value, 1.0);
        }
        let u = self.fraction(value);
        let slope = if u <= self.knee {
            1.0 / (1.0 - u.clamp(-self.knee, self.knee).powi(2)).sqrt()
        } else {
            ANGLE_SLOPE_CAP
        };
        (angle - self.phi(u), slope / self.range)
    }
}

/// The weight μ of the integrability pull at each unknown pixel (`pixels`, row-major
/// indices): [`MU`], or 0 where the pixel has no neighbour in `domain` along x or along y, so
/// that the depth cannot tilt it that way (its slope there would read 0 and pull it flat).
fn pull_weights(domain: &Mask, pixels: &[u32]) -> Vec<f64> {
    let (w, h) = (domain.width(), domain.height());
    let md = domain.data();
    let inside = |i: Option<usize>| i.is_some_and(|i| md[i]);
    pixels
        .iter()
        .map(|&p| {
            let i = p as usize;
            let (c, r) = (i % w, i / w);
            let along_x = inside((c > 0).then(|| i - 1)) || inside((c + 1 < w).then(|| i + 1));
            let along_y = inside((r > 0).then(|| i - w)) || inside((r + 1 < h).then(|| i + w));
            if along_x && along_y {
                MU
            } else {
                0.0
            }
        })
        .collect()
}

/// The orientation (f, g) of the depth `z` at each unknown pixel (`pixels`, row-major
/// indices): slopes from the mean of the depth differences across the pixel's edges inside
/// `domain` (0 along an axis with none).
fn depth_orientations(
    z: &Image,
    domain: &Mask,
    pixels: &[u32],
    target_f: &mut [f64],
    target_g: &mut [f64],
) {
    let (w, h) = (z.width(), z.height());
    let (zd, md) = (z.data(), domain.data());
    let slope = |i: usize, back: Option<usize>, ahead: Option<usize>| -> f64 {
        let mut sum = 0.0;
        let mut count = 0.0;
        if let Some(b) = back.filter(|&b| md[b]) {
            sum += zd[i] - zd[b];
            count += 1.0;
        }
        if let Some(a) = ahead.filter(|&a| md[a]) {
            sum += zd[a] - zd[i];
            count += 1.0;
        }
        if count > 0.0 {
            sum / count
        } else {
            0.0
        }
    };
    for (j, &p) in pixels.iter().enumerate() {
        let i = p as usize;
        let (c, r) = (i % w, i / w);
        let dz_dx = slope(i, (c > 0).then(|| i - 1), (c + 1 < w).then(|| i + 1));
        // Rows run downward and y upward: ∂z/∂y = −∂z/∂row.
        let dz_dy = -slope(i, (r > 0).then(|| i - w), (r + 1 < h).then(|| i + w));
        // p = −∂z/∂x, q = −∂z/∂y.
        let (f, g) = fg_from_pq(-dz_dx, -dz_dy);
        target_f[j] = f;
        target_g[j] = g;
    }
}

/// The largest |a − b| (∞ when one is not a number).
fn largest_change(a: &[f64], b: &[f64]) -> f64 {
    let mut largest: f64 = 0.0;
    for (x, y) in a.iter().zip(b) {
        let change = (x - y).abs();
        if change.is_nan() {
            return f64::INFINITY;
        } else if change > largest {
            largest = change;
        }
    }
    largest
}

#[cfg(test)]
mod tests;
