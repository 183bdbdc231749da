//! The integrable method's energy E(f, g, z) and its minimisation by Levenberg–Marquardt: the
//! unknowns are the orientations (f, g) and the depth z of the domain's unknown pixels, all
//! moved together by each step.
//!
//! E = σ·e_S + λ·e_R + μ·e_I as in the method's documentation, as a sum of squares:
//!
//! - smoothness: ½σ Σ_edges |(f, g)_a − (f, g)_b|² over the edges between unknown pixels and
//!   from unknown pixels to the fixed ring (linear in (f, g));
//! - data: ½·4λ Σ_pixels (φ(I) − φ(R(f, g)))², over the pixels with a data term;
//! - integrability: ½ Σ_pixels μ_j |(f, g)_j − t(p_j, q_j)|², t the stereographic map of
//!   [`fg_from_pq`] and (p_j, q_j) = (−∂z/∂x, −∂z/∂y) from the depth differences across the
//!   pixel's edges inside the domain (central inside, one-sided at its edge).
//!
//! Each step solves (H + ν·diag H) δ = −∇E by conjugate gradients, preconditioned by one
//! V-cycle of aggregation multigrid on the assembled matrix (`aggregation.rs`; session 13: with
//! the diagonal blocks alone, the smooth modes in which orientations and depth bend together
//! were left to conjugate gradients, and a 256² sphere did not converge in 200 steps), and is
//! kept only if it lowers E; ν follows how well the quadratic model predicted the decrease
//! (Nielsen's rule). Where E fell by more than the model said, the step is stretched along δ to
//! the least of E's parabola there, if that lowers E further: H, with its curvature dropped
//! where it is negative and without the integrability residual's own, is stiffer than E along
//! the steps near the end (E fell by 1.7–1.9 times the predicted decrease, step after step).
//! H is the Gauss–Newton matrix JᵀJ, except that the data term's 2 × 2 block is its own
//! Hessian (the residual's curvature included, its negative part dropped): near the brightest
//! orientation the angle residual's curvature is what holds a pixel, and with JᵀJ alone single
//! pixels there swung by 0.1 in g from step to step. H keeps the coupling of (f, g) and z that
//! the alternation drops, so a smooth change of the orientations moves the depth with it.
//!
//! That H is the stiff model. Stretching along δ helps where the whole step is too short, but
//! not where single pixels lag: on DiLiGenT pot2 the last hundred steps moved one pixel by
//! about 1e-4 each, the data term's negative curvature there (−1.5, against the 4.5 its
//! smoothness and pull put on its diagonal) dropped from the model. Once a step whose largest
//! change is below 1e-3 finds E flatter than the stiff model predicted, the steps use the soft
//! model, which keeps each pixel's negative curvature as far as its own diagonal holds it (no
//! eigenvalue of its block below half that diagonal); where the soft model predicts badly
//! (E falls by less than half the predicted decrease: its negative curvatures line up where many
//! pixels move at once), the stiff one takes over again, and after four such failures for good.
//! Used from the first step, the soft model reaches lower minima on some objects (pot2 E 462.51
//! against 463.13) whose normals are further from the truth (pot2 12.74° against 11.71°), and
//! the steps of the ball's free boundary stopped converging; used only at the end, it finishes
//! what the stiff model started. A step that would move a pixel's f or g by more than 1 is
//! retried with more damping.
//!
//! Neither model is E along every pixel's orientation: on DiLiGenT pot1 (occluding) the last
//! hundred steps moved one pixel by 1e-4 to 1e-3 each, 7 % of the way to its least each time,
//! and the soft model's steps moved others too far. Once a step's largest change is below 1e-2,
//! the pixels it moved by more than a tenth of that are relaxed in turn, three times over: each
//! moved to the least of E along its own orientation, every other unknown held (Newton's
//! method on its 2 × 2 problem with the data term's whole Hessian, which cannot raise E). The
//! step's change, the convergence test's, is then what the step and the relaxation moved
//! together. Where those pixels are more than a tenth of the unknowns (a smooth mode, as on the
//! ball photographs' free boundary), they are left to the steps: relaxed one by one, they stood
//! in the way of the stretched steps, and the ball's free rows stopped converging.
//!
//! Where E falls along a long, shallow valley the steps creep: on ball photograph 052 with the
//! free boundary (a light 4° from the view, nothing at the outline to hold the shape) each
//! step moved about 1.6e-3 in the direction of the last (cosine 0.985 between consecutive
//! steps), its model predicting it well (E fell by 1.0–1.4 times the predicted decrease, the
//! damping at its floor), and a step's linear solve taken to 1e-3 in place of 0.1 made the
//! same steps: the model itself is that curved along the valley. So each step is followed by
//! **Anderson acceleration** over the last [`LM_ANDERSON_DEPTH`] steps (`anderson.rs`): the
//! step's end less the combination of past steps that best cancels the present one, taken
//! only where E is lower there than at the step's end (so E still never rises), the history
//! kept even where the steps grow. The step's change is then the larger of the step's and
//! what the mixed point moved. Ball 052 (free) converges in 786 steps where 1000 had not
//! sufficed, and the evaluation's other 55 rows reach the same minima (their errors the same to
//! the evaluation table's digits) in 29 % fewer steps (3,453 against 4,867; harvest occluding
//! 314 → 245, pot2 occluding 207 → 156).
//!
//! Every loop runs over fixed chunks of pixels, each value computed by one pixel's own
//! expression (the depth's terms gathered from the pixels whose slopes read it, in a fixed
//! order), and the dot products in fixed chunks added in order (`conjugate_gradients::dot`):
//! the result does not depend on the thread count.

use super::super::{Node, CHUNK, PARALLEL_MIN};
use super::aggregation::{Multigrid, Place};
use super::anderson::{Anderson, Restart};
use super::{AngleScale, SIGMA};
use crate::conjugate_gradients::{self, dot, Stop};
use crate::gradient_space::{fg_from_pq, fg_pq_jacobian};
use crate::parallel::prelude::*;
use crate::reflectance::ReflectanceMap;

/// No unknown there.
const NONE: u32 = u32::MAX;

/// A depth slope at one pixel along one axis: up to two (unknown, weight) terms.
#[derive(Debug, Clone, Copy, Default)]
struct Stencil {
    at: [u32; 2],
    weight: [f64; 2],
    len: u8,
}

impl Stencil {
    /// The slope (ahead − back) at `j`: the central difference when both neighbours are
    /// unknowns, the one-sided one when one is, none when neither is.
    fn new(j: usize, back: u32, ahead: u32) -> Stencil {
        let j = j as u32;
        let (at, weight, len) = match (back != NONE, ahead != NONE) {
            (true, true) => ([ahead, back], [0.5, -0.5], 2),
            (false, true) => ([ahead, j], [1.0, -1.0], 2),
            (true, false) => ([j, back], [1.0, -1.0], 2),
            (false, false) => ([0, 0], [0.0, 0.0], 0),
        };
        Stencil { at, weight, len }
    }

    /// The terms.
    fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.at[..self.len as usize]
            .iter()
            .zip(&self.weight)
            .map(|(&k, &c)| (k as usize, c))
    }

    /// The slope of `z`.
    fn of(&self, z: &[f64]) -> f64 {
        self.terms().map(|(k, c)| c * z[k]).sum()
    }
}

/// The orientation t(p, q) of a depth slope and its Jacobian [∂f/∂p, ∂f/∂q, ∂g/∂p, ∂g/∂q].
fn orientation(p: f64, q: f64) -> ((f64, f64), [f64; 4]) {
    (fg_from_pq(p, q), fg_pq_jacobian(p, q))
}

/// E(f, g, z) on one domain. A point is one vector `[f…, g…, z…]` of 3n values for the n
/// unknown pixels.
pub(super) struct Energy<'a> {
    nodes: &'a [Node],
    /// f and g of every value slot (the unknowns' entries are not read; the fixed ring's are).
    slots: (&'a [f64], &'a [f64]),
    /// The slot of a missing neighbour.
    zero: usize,
    angles: &'a [f64],
    pull: &'a [f64],
    scale: AngleScale,
    reflectance: &'a dyn ReflectanceMap,
    /// The slope along x and along the rows at each unknown: p = −(x slope), q = (row slope).
    along_x: Vec<Stencil>,
    along_rows: Vec<Stencil>,
    /// Where each depth value enters the slopes: for depth k, `readers[reader_start[k]..
    /// reader_start[k + 1]]` are the pulled pixels j whose (p, q) read it, with ∂p_j/∂z_k and
    /// ∂q_j/∂z_k, in order of j.
    reader_start: Vec<usize>,
    readers: Vec<(u32, f64, f64)>,
    /// The (column, row) of each unknown.
    cells: Vec<(u32, u32)>,
}

impl<'a> Energy<'a> {
    /// The energy of the unknowns `nodes` (at row-major `pixels` of a grid of `size` (width,
    /// height) whose value slots are `slot`), the fixed ring's values in `slots`, φ(I) per
    /// unknown in `angles` and the integrability weight per unknown in `pull`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        nodes: &'a [Node],
        pixels: &[u32],
        slot: &[u32],
        (width, height): (usize, usize),
        slots: (&'a [f64], &'a [f64]),
        angles: &'a [f64],
        pull: &'a [f64],
        reflectance: &'a dyn ReflectanceMap,
    ) -> Energy<'a> {
        let n = nodes.len();
        let unknown = |q: usize| {
            if (slot[q] as usize) < n {
                slot[q]
            } else {
                NONE
            }
        };
        let (mut along_x, mut along_rows) = (Vec::with_capacity(n), Vec::with_capacity(n));
        let mut cells = Vec::with_capacity(n);
        for (j, &p) in pixels.iter().enumerate() {
            let p = p as usize;
            let (c, r) = (p % width, p / width);
            cells.push((c as u32, r as u32));
            let left = if c > 0 { unknown(p - 1) } else { NONE };
            let right = if c + 1 < width { unknown(p + 1) } else { NONE };
            let up = if r > 0 { unknown(p - width) } else { NONE };
            let down = if r + 1 < height {
                unknown(p + width)
            } else {
                NONE
            };
            along_x.push(Stencil::new(j, left, right));
            along_rows.push(Stencil::new(j, up, down));
        }
        // (depth, pixel, ∂p, ∂q), sorted by depth then pixel; a depth read by both of a
        // pixel's slopes appears twice.
        let mut entries: Vec<(u32, u32, f64, f64)> = Vec::with_capacity(4 * n);
        for j in 0..n {
            if pull[j] > 0.0 {
                for (k, c) in along_x[j].terms() {
                    entries.push((k as u32, j as u32, -c, 0.0));
                }
                for (k, c) in along_rows[j].terms() {
                    entries.push((k as u32, j as u32, 0.0, c));
                }
            }
        }
        entries.sort_by_key(|&(k, j, _, _)| (k, j));
        let mut reader_start = vec![0; n + 1];
        for &(k, ..) in &entries {
            reader_start[k as usize + 1] += 1;
        }
        for k in 0..n {
            reader_start[k + 1] += reader_start[k];
        }
        let readers = entries.into_iter().map(|(_, j, p, q)| (j, p, q)).collect();
        Energy {
            nodes,
            slots,
            zero: slots.0.len() - 1,
            angles,
            pull,
            scale: AngleScale::of(reflectance),
            reflectance,
            along_x,
            along_rows,
            reader_start,
            readers,
            cells,
        }
    }

    /// The number of unknown pixels.
    pub(super) fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Where each unknown of a point sits for the preconditioner's aggregation: f and g at
    /// their pixels, the depth by its sublattice (central differences leave the depth's four
    /// sublattices uncoupled), at the cell of a grid half as fine.
    fn places(&self) -> Vec<Place> {
        let mut places: Vec<Place> = Vec::with_capacity(3 * self.len());
        for field in 0..2u8 {
            places.extend(self.cells.iter().map(|&(c, r)| (field, c, r)));
        }
        places.extend(
            self.cells
                .iter()
                .map(|&(c, r)| (2 + (c & 1) as u8 + 2 * (r & 1) as u8, c / 2, r / 2)),
        );
        places
    }

    /// −Σ over the readers of depth k of (∂p·w_p + ∂q·w_q), `w` holding (w_p, w_q) per pixel:
    /// the depth's entry of Jᵀ(…) for per-pixel (p, q) sensitivities w.
    fn gather_depth(&self, k: usize, w: &[f64]) -> f64 {
        let mut sum = 0.0;
        for &(j, dp, dq) in &self.readers[self.reader_start[k]..self.reader_start[k + 1]] {
            let j = j as usize;
            sum -= dp * w[2 * j] + dq * w[2 * j + 1];
        }
        sum
    }

    /// E at `v`, and its gradient into `grad` (3n values); `scratch` holds 2n values.
    pub(super) fn value_and_gradient(
        &self,
        v: &[f64],
        grad: &mut [f64],
        scratch: &mut [f64],
    ) -> f64 {
        let n = self.len();
        let (f, rest) = v.split_at(n);
        let (g, z) = rest.split_at(n);
        let (grad_f, rest) = grad.split_at_mut(n);
        let (grad_g, grad_z) = rest.split_at_mut(n);
        let pixel = |j: usize, gf: &mut f64, gg: &mut f64, w: &mut [f64]| -> f64 {
            let node = &self.nodes[j];
            let (mut e, mut sf, mut sg) = (0.0, 0.0, 0.0);
            for &q in &node.neighbours {
                let q = q as usize;
                if q == self.zero {
                    continue;
                }
                let (df, dg) = if q < n {
                    (f[j] - f[q], g[j] - g[q])
                } else {
                    (f[j] - self.slots.0[q], g[j] - self.slots.1[q])
                };
                // An edge between unknowns is seen from both ends.
                let share = if q < n { 0.5 } else { 1.0 };
                e += 0.5 * SIGMA * share * (df * df + dg * dg);
                sf += SIGMA * df;
                sg += SIGMA * dg;
            }
            if node.data_weight != 0.0 {
                let four_lambda = node.data_weight / node.inv_k;
                let s = self.reflectance.fg(f[j], g[j]);
                let (r, slope) = self.scale.residual(self.angles[j], s.value);
                e += 0.5 * four_lambda * r * r;
                sf -= four_lambda * r * slope * s.d1;
                sg -= four_lambda * r * slope * s.d2;
            }
            let mu = self.pull[j];
            let (mut wp, mut wq) = (0.0, 0.0);
            if mu > 0.0 {
                let ((tf, tg), t) = self.target(j, z);
                let (ef, eg) = (f[j] - tf, g[j] - tg);
                e += 0.5 * mu * (ef * ef + eg * eg);
                sf += mu * ef;
                sg += mu * eg;
                wp = mu * (ef * t[0] + eg * t[2]);
                wq = mu * (ef * t[1] + eg * t[3]);
            }
            *gf = sf;
            *gg = sg;
            w[0] = wp;
            w[1] = wq;
            e
        };
        let e = per_pixel(n, grad_f, grad_g, scratch, pixel);
        per_item(grad_z, |k| self.gather_depth(k, scratch));
        e
    }

    /// t(p_j, q_j) and ∂t/∂(p, q) at pixel j for the depth `z`: the orientation its slopes
    /// give, which the integrability residual pulls it toward.
    fn target(&self, j: usize, z: &[f64]) -> ((f64, f64), [f64; 4]) {
        orientation(-self.along_x[j].of(z), self.along_rows[j].of(z))
    }

    /// Pixel j's data term at the orientation (f, g), for a pixel that has one: its value, its
    /// gradient and its whole Hessian [ff, fg, gg] (the residual's curvature included).
    fn data_term(&self, j: usize, (f, g): (f64, f64)) -> (f64, [f64; 2], [f64; 3]) {
        let node = &self.nodes[j];
        let four_lambda = node.data_weight / node.inv_k;
        let (s, h) = self.reflectance.fg_hessian(f, g);
        let (r, d) = self.scale.residual(self.angles[j], s.value);
        let dd = self.scale.second(s.value);
        let (a, b) = (d * s.d1, d * s.d2);
        // ∇²(½r²) = ∇r∇rᵀ + r∇²r, ∇r = −φ′∇R, ∇²r = −(φ″∇R∇Rᵀ + φ′∇²R).
        let hessian = [
            a * a - r * (dd * s.d1 * s.d1 + d * h[0]),
            a * b - r * (dd * s.d1 * s.d2 + d * h[1]),
            b * b - r * (dd * s.d2 * s.d2 + d * h[2]),
        ];
        (
            0.5 * four_lambda * r * r,
            [-(four_lambda * r * a), -(four_lambda * r * b)],
            hessian.map(|x| four_lambda * x),
        )
    }

    /// Pixel j's part of E as a function of its own orientation `at`, everything else held at
    /// `v`: its value, gradient and Hessian [ff, fg, gg] (the data term's whole Hessian, its
    /// negative curvature included), with the integrability residual's target `target` (t of
    /// the pixel's slopes; `None` where it has no pull).
    fn local(
        &self,
        v: &[f64],
        j: usize,
        target: Option<(f64, f64)>,
        (f, g): (f64, f64),
    ) -> (f64, [f64; 2], [f64; 3]) {
        let n = self.len();
        let node = &self.nodes[j];
        let (mut e, mut gradient, mut hessian) = (0.0, [0.0; 2], [0.0; 3]);
        for &q in &node.neighbours {
            let q = q as usize;
            if q == self.zero {
                continue;
            }
            let (df, dg) = if q < n {
                (f - v[q], g - v[n + q])
            } else {
                (f - self.slots.0[q], g - self.slots.1[q])
            };
            e += 0.5 * SIGMA * (df * df + dg * dg);
            gradient[0] += SIGMA * df;
            gradient[1] += SIGMA * dg;
            hessian[0] += SIGMA;
            hessian[2] += SIGMA;
        }
        if node.data_weight != 0.0 {
            let (data, slope, curvature) = self.data_term(j, (f, g));
            e += data;
            for i in 0..2 {
                gradient[i] += slope[i];
            }
            for i in 0..3 {
                hessian[i] += curvature[i];
            }
        }
        if let Some((tf, tg)) = target {
            let mu = self.pull[j];
            let (ef, eg) = (f - tf, g - tg);
            e += 0.5 * mu * (ef * ef + eg * eg);
            gradient[0] += mu * ef;
            gradient[1] += mu * eg;
            hessian[0] += mu;
            hessian[2] += mu;
        }
        (e, gradient, hessian)
    }

    /// Moves pixel j's orientation in `v` to the least of E along it, every other unknown
    /// held: Newton's method on the 2 × 2 problem, its Hessian raised where it is not
    /// positive definite, each step halved until it lowers E. E never rises.
    fn relax(&self, v: &mut [f64], j: usize) {
        let n = self.len();
        let z = &v[2 * n..];
        let target = (self.pull[j] > 0.0).then(|| self.target(j, z).0);
        let mut at = (v[j], v[n + j]);
        let (mut e, mut gradient, mut hessian) = self.local(v, j, target, at);
        for _ in 0..RELAX.iterations {
            let [a, b, c] = hessian;
            let mean = 0.5 * (a + c);
            let radius = (0.25 * (a - c) * (a - c) + b * b).sqrt();
            let floor = RELAX.floor * (mean + radius).abs().max(f64::MIN_POSITIVE);
            let raise = (floor - (mean - radius)).max(0.0);
            let (a, c) = (a + raise, c + raise);
            let det = a * c - b * b;
            let mut step = [
                -(c * gradient[0] - b * gradient[1]) / det,
                -(a * gradient[1] - b * gradient[0]) / det,
            ];
            let length = step[0].abs().max(step[1].abs());
            if !length.is_finite() {
                break;
            }
            if length > RELAX.max_step {
                step = step.map(|s| s * RELAX.max_step / length);
            }
            let mut moved = false;
            for _ in 0..RELAX.halvings {
                let next = (at.0 + step[0], at.1 + step[1]);
                let (e_next, gradient_next, hessian_next) = self.local(v, j, target, next);
                if e_next < e {
                    at = next;
                    (e, gradient, hessian) = (e_next, gradient_next, hessian_next);
                    moved = true;
                    break;
                }
                step = step.map(|s| 0.5 * s);
            }
            if !moved {
                break;
            }
        }
        v[j] = at.0;
        v[n + j] = at.1;
    }

    /// The model of E at `v`: its Gauss–Newton matrix, with the data term's own Hessian. The
    /// stiff model drops that Hessian's negative curvature; the `soft` one keeps it as far as
    /// each pixel's smoothness and pull hold it ([`held`]), so that its matrix is closer to E's
    /// Hessian, but may be indefinite where several pixels' negative curvatures line up.
    pub(super) fn linearise(&self, v: &[f64], soft: bool) -> Model<'_, 'a> {
        let n = self.len();
        let (f, rest) = v.split_at(n);
        let (g, z) = rest.split_at(n);
        let mut blocks = vec![Block::default(); n];
        let block = |j: usize| -> Block {
            let node = &self.nodes[j];
            let k = node
                .neighbours
                .iter()
                .filter(|&&q| q as usize != self.zero)
                .count() as f64;
            let mut data = [0.0; 3];
            if node.data_weight != 0.0 {
                let (_, _, h) = self.data_term(j, (f[j], g[j]));
                data = if soft {
                    held(h, SIGMA * k + self.pull[j])
                } else {
                    positive_part(h)
                };
            }
            let mu = self.pull[j];
            let slope = if mu > 0.0 {
                self.target(j, z).1
            } else {
                [0.0; 4]
            };
            let diagonal = SIGMA * k + mu;
            Block {
                fg: [diagonal + data[0], data[1], diagonal + data[2]],
                slope,
            }
        };
        per_item(&mut blocks, block);
        // z's diagonal: Σ over its readers of μ|T′(∂p, ∂q)|².
        let mut depth = vec![0.0; n];
        per_item(&mut depth, |k| {
            let mut sum = 0.0;
            for &(j, dp, dq) in &self.readers[self.reader_start[k]..self.reader_start[k + 1]] {
                let j = j as usize;
                let t = blocks[j].slope;
                let (u, w) = (t[0] * dp + t[1] * dq, t[2] * dp + t[3] * dq);
                sum += self.pull[j] * (u * u + w * w);
            }
            sum.max(DIAGONAL_FLOOR)
        });
        Model {
            energy: self,
            blocks,
            depth,
        }
    }
}

/// One pixel's part of the model.
#[derive(Debug, Clone, Copy, Default)]
struct Block {
    /// The (f, g) diagonal block [ff, fg, gg]: smoothness, pull and data.
    fg: [f64; 3],
    /// ∂t/∂(p, q) (0 where there is no pull).
    slope: [f64; 4],
}

/// Runs `pixel(j, &mut a[j], &mut b[j], &mut w[2j..2j + 2])` for every pixel over fixed
/// chunks and returns the sum of its results, added chunk by chunk in order.
fn per_pixel<F>(n: usize, a: &mut [f64], b: &mut [f64], w: &mut [f64], pixel: F) -> f64
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
fn per_item<T, F>(out: &mut [T], value: F)
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
pub(super) struct Model<'e, 'a> {
    energy: &'e Energy<'a>,
    blocks: Vec<Block>,
    /// z's diagonal entries (floored).
    depth: Vec<f64>,
}

impl Model<'_, '_> {
    /// out = (H + ν·diag H) x; `scratch` holds 2n values.
    fn apply(&self, nu: f64, x: &[f64], out: &mut [f64], scratch: &mut [f64]) {
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
    fn matrix(&self, nu: f64) -> super::aggregation::Csr {
        super::aggregation::Csr::from_triplets(3 * self.energy.len(), &self.triplets(nu))
    }

    /// The entries of [`Model::matrix`] as (row, column, value) triplets, summed where they
    /// meet.
    #[cfg(test)]
    fn triplets(&self, nu: f64) -> Vec<(u32, u32, f64)> {
        let mut t = Vec::with_capacity(48 * self.energy.len());
        self.entries(nu, |r, c, v| t.push((r, c, v)));
        t
    }

    /// Calls `emit(row, column, value)` for each entry of [`Model::matrix`] (summed where they
    /// meet): the matrix the preconditioner coarsens. The positions are the same at every
    /// point of one energy, in the same order, so the preconditioner is planned from them once
    /// and later steps read the values alone.
    fn entries(&self, nu: f64, mut emit: impl FnMut(u32, u32, f64)) {
        let e = self.energy;
        let n = e.len();
        let (f, g, z) = (
            |j: usize| j as u32,
            |j: usize| (n + j) as u32,
            |k: usize| (2 * n + k) as u32,
        );
        let mut terms: Vec<(usize, f64, f64)> = Vec::with_capacity(4);
        for j in 0..n {
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
    fn solve(
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
    fn quadratic(&self, x: &[f64]) -> f64 {
        let mut out = vec![0.0; x.len()];
        let mut scratch = vec![0.0; 2 * self.energy.len()];
        self.apply(0.0, x, &mut out, &mut scratch);
        0.5 * dot(x, &out)
    }
}

/// The symmetric 2 × 2 matrix [a, b, c] with its negative eigenvalues set to 0.
fn positive_part([a, b, c]: [f64; 3]) -> [f64; 3] {
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
const HELD: f64 = 0.5;

/// The data term's 2 × 2 Hessian `data` at a pixel whose smoothness and pull put `diagonal` on
/// its (f, g) diagonal, changed as little as makes the pixel's block diagonal·I + data have no
/// eigenvalue below [`HELD`]·diagonal: the data term's negative curvature (a residual pulling
/// the orientation past the brightness's ridge) is kept where the pixel's own smoothness and
/// pull hold it, and only the rest is dropped.
fn held(data: [f64; 3], diagonal: f64) -> [f64; 3] {
    let give = (1.0 - HELD) * diagonal;
    let [a, b, c] = positive_part([data[0] + give, data[1], data[2] + give]);
    [a - give, b, c - give]
}

/// The smallest diagonal entry of z that the damping uses, and what the preconditioner's matrix
/// adds to every diagonal entry: a depth that no slope reads (and the depth's checkerboard,
/// which central differences do not see) has none.
const DIAGONAL_FLOOR: f64 = 1e-6;

/// The relative residual each step's conjugate-gradient solve stops at.
pub const CG_TOL: f64 = 0.1;

/// The most conjugate-gradient iterations of one step's solve.
pub const CG_MAX_ITER: usize = 100;

/// Where each step's conjugate-gradient solve stops.
const CG_STOP: Stop = Stop {
    tol: CG_TOL,
    max_iter: CG_MAX_ITER,
};

/// How many past steps the Anderson acceleration of the steps combines (see the module
/// documentation): 3 and 5 took the same steps within 5 % on the evaluation's hard rows, and
/// each costs two vectors of the unknowns' length.
pub const LM_ANDERSON_DEPTH: usize = 3;

/// The damping ν of the first step (relative to H's diagonal).
const START_DAMPING: f64 = 1e-3;

/// Where E falls by more than this many times the model's decrease, the step is stretched
/// along its direction.
const STRETCH_ABOVE: f64 = 1.2;

/// How many stretches are tried, each a third as far beyond 1 as the last.
const STRETCH_TRIES: usize = 3;

/// The most a step is stretched.
const MAX_STRETCH: f64 = 8.0;

/// The soft model is taken up once a step whose largest change of f or g is below this finds
/// E flatter than the model (the end of a minimisation, where the stiff model's steps shrink
/// by a constant factor).
const SOFT_BELOW: f64 = 1e-3;

/// The soft model is left where E falls by less than this share of its predicted decrease.
const SOFT_TRUSTED: f64 = 0.5;

/// How many times the soft model may be left before the minimisation keeps to the stiff one:
/// where many pixels move at once, the soft model's negative curvatures line up and its steps
/// predict badly again and again (the free boundary on the ball photographs).
const SOFT_TRIES: usize = 4;

/// The largest change of a pixel's f or g that one step may make (the visible hemisphere is
/// the disc |(f, g)| ≤ 2); a longer step is retried with more damping.
const MAX_STEP: f64 = 1.0;

/// How many times one step may raise the damping before it gives up (ν × 4 each time).
const MAX_RETRIES: usize = 30;

/// How pixels are relaxed one by one at the end of a minimisation (see the module's
/// documentation).
struct Relaxation {
    /// Pixels are relaxed after each step whose largest change of f or g is below this.
    below: f64,
    /// The pixels relaxed: those that the step moved by more than this share of its largest
    /// change,
    share: f64,
    /// and only where they are at most this share of the unknowns: where the step moves most
    /// pixels alike (the free boundary on the ball photographs), it moves a smooth mode that
    /// only the whole step can, and relaxing pixel by pixel works against it.
    most: f64,
    /// How many times the chosen pixels are relaxed in turn after a step.
    sweeps: usize,
    /// Newton iterations of one pixel's relaxation.
    iterations: usize,
    /// How many times a relaxation step is halved before the pixel stays where it is.
    halvings: usize,
    /// A relaxation step's largest change of f or g.
    max_step: f64,
    /// A pixel's 2 × 2 Hessian is raised until its least eigenvalue is this share of its
    /// largest.
    floor: f64,
}

/// The relaxation's settings.
const RELAX: Relaxation = Relaxation {
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
pub(super) struct Minimiser {
    /// The point [f…, g…, z…].
    pub(super) x: Vec<f64>,
    grad: Vec<f64>,
    e: f64,
    nu: f64,
    /// Conjugate-gradient iterations so far.
    pub(super) cg_iterations: usize,
    /// The preconditioner, planned at the first step for the model's pattern (the same at
    /// every point) and refilled at each, and its V-cycle's buffers.
    multigrid: Option<(Multigrid, Vec<[Vec<f64>; 3]>)>,
    /// The model's matrix entries at this step, in the order of [`Model::entries`].
    values: Vec<f64>,
    /// Whether the steps use the soft model (see [`Energy::linearise`]).
    soft: bool,
    /// How many times the soft model predicted badly (after [`SOFT_TRIES`], it is not taken up
    /// again).
    soft_failed: usize,
    /// The acceleration of the steps, and the point before this step that it reads.
    anderson: Anderson,
    start: Vec<f64>,
    /// A point tried (a step's end, a stretched one, the accelerated one) and E's gradient
    /// there, swapped with `x` and `grad` where it is taken; and `value_and_gradient`'s 2n
    /// values of scratch.
    trial: Vec<f64>,
    trial_grad: Vec<f64>,
    scratch: Vec<f64>,
}

impl Minimiser {
    /// Starts at `x`.
    pub(super) fn new(energy: &Energy, x: Vec<f64>) -> Minimiser {
        Minimiser::with_acceleration(energy, x, LM_ANDERSON_DEPTH)
    }

    /// Starts at `x`, the steps accelerated over `depth` past steps (0: plain
    /// Levenberg–Marquardt).
    fn with_acceleration(energy: &Energy, x: Vec<f64>, depth: usize) -> Minimiser {
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
            values: Vec::new(),
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
    pub(super) fn energy(&self) -> f64 {
        self.e
    }

    /// One step that lowers E (raising the damping until one does), then accelerated where
    /// that lowers E further; returns the largest change of f or g, 0 when no step lowers E.
    pub(super) fn step(&mut self, energy: &Energy) -> f64 {
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
    fn accelerate(&mut self, energy: &Energy) -> f64 {
        self.trial.copy_from_slice(&self.x);
        if !self.anderson.step(&self.start, &mut self.trial) {
            return 0.0;
        }
        let e = energy.value_and_gradient(&self.trial, &mut self.trial_grad, &mut self.scratch);
        if e.is_nan() || e >= self.e {
            return 0.0;
        }
        let n = energy.len();
        let moved = super::largest_change(&self.trial[..2 * n], &self.x[..2 * n]);
        std::mem::swap(&mut self.x, &mut self.trial);
        std::mem::swap(&mut self.grad, &mut self.trial_grad);
        self.e = e;
        moved
    }

    /// One Levenberg–Marquardt step that lowers E (raising the damping until one does),
    /// stretched and relaxed as the module's documentation says; returns the largest change
    /// of f or g, 0 when no step lowers E.
    fn descend(&mut self, energy: &Energy) -> f64 {
        let n = energy.len();
        let model = energy.linearise(&self.x, self.soft);
        // Planned at the first step for the model's pattern and refilled at each; filled for
        // this step's first damping, it serves the raised ones too: a larger ν only makes the
        // matrix more diagonal.
        let (mg, cycle) = self.multigrid.get_or_insert_with(|| {
            let mut positions = Vec::with_capacity(48 * n);
            model.entries(self.nu, |r, c, _| positions.push((r, c)));
            let mg = Multigrid::plan(3 * n, positions.into_iter(), energy.places());
            let cycle = mg.scratch();
            (mg, cycle)
        });
        let values = &mut self.values;
        values.clear();
        model.entries(self.nu, |_, _, v| values.push(v));
        mg.fill(values.iter().copied());
        let b: Vec<f64> = self.grad.iter().map(|g| -g).collect();
        let mut delta = vec![0.0; b.len()];
        let (trial, trial_grad, scratch) =
            (&mut self.trial, &mut self.trial_grad, &mut self.scratch);
        for _ in 0..MAX_RETRIES {
            self.cg_iterations += model.solve(self.nu, (mg, cycle), &b, &mut delta, CG_STOP);
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

#[cfg(test)]
mod tests {
    use super::super::super::tests::picture;
    use super::super::{pull_weights, AngleScale};
    use super::*;
    use crate::boundary::{boundary_conditions, Boundary, Role};
    use crate::grid::Mask;
    use crate::light::Light;
    use crate::solver::Solver;
    use crate::surface::sphere;

    /// A 20² sphere's problem (occluding boundary, light from tilt 30°, slant 40°), and a point
    /// that is not its minimum: the truth's (f, g) bent by a smooth field, and a depth of its
    /// own.
    struct Case {
        solver: Solver,
        pull: Vec<f64>,
        angles: Vec<f64>,
        map: crate::reflectance::Lambertian,
        point: Vec<f64>,
    }

    fn case() -> Case {
        case_with(20, &Boundary::Occluding, (30.0, 40.0))
    }

    /// A `size`² sphere (radius 0.425 of the size) lit from (tilt, slant), solved with
    /// `boundary`, from a perturbed start.
    fn case_with(size: usize, boundary: &Boundary, (tilt, slant): (f64, f64)) -> Case {
        let surface = sphere(size, size, 0.425 * size as f64).unwrap();
        let (image, map) = picture(&surface, Light::from_tilt_slant(tilt, slant).unwrap());
        let bc = boundary_conditions(&surface.mask, boundary).unwrap();
        let mut solver = Solver::new(size, size).unwrap();
        let n = solver.build(&image, &bc, &map, 1.0);
        let domain: Mask = bc.roles.map(|r| *r == Role::Unknown);
        let pull = pull_weights(&domain, &solver.pixels);
        let scale = AngleScale::of(&map);
        let angles = solver.nodes[..n]
            .iter()
            .map(|node| scale.angle(node.intensity))
            .collect();
        let mut point = vec![0.0; 3 * n];
        for (j, &p) in solver.pixels.iter().enumerate() {
            let (c, r) = ((p as usize % size) as f64, (p as usize / size) as f64);
            let normal = surface.normals.data()[p as usize];
            let (f, g) = crate::gradient_space::fg_from_normal(&normal);
            point[j] = f + 0.1 * (0.3 * c).sin();
            point[n + j] = g - 0.08 * (0.2 * r).cos();
            point[2 * n + j] = 0.05 * c * r - 0.3 * c;
        }
        Case {
            solver,
            pull,
            angles,
            map,
            point,
        }
    }

    impl Case {
        fn energy(&self) -> Energy<'_> {
            let s = &self.solver;
            let n = self.angles.len();
            Energy::new(
                &s.nodes[..n],
                &s.pixels,
                &s.slot,
                (s.width, s.height),
                (&s.cur_f, &s.cur_g),
                &self.angles,
                &self.pull,
                &self.map,
            )
        }
    }

    /// The gradient is E's: central differences of E along 60 coordinates of f, g and z agree
    /// with it to 1e-6 relative.
    #[test]
    fn gradient_is_the_energys() {
        let case = case();
        let energy = case.energy();
        let x = case.point.clone();
        let mut grad = vec![0.0; x.len()];
        let mut work = vec![0.0; x.len()];
        energy.value_and_gradient(&x, &mut grad, &mut work);
        let mut scratch = vec![0.0; x.len()];
        let (mut y, h) = (x.clone(), 1e-6);
        for k in 0..60 {
            let i = (k * 7919) % x.len();
            y[i] = x[i] + h;
            let up = energy.value_and_gradient(&y, &mut scratch, &mut work);
            y[i] = x[i] - h;
            let down = energy.value_and_gradient(&y, &mut scratch, &mut work);
            y[i] = x[i];
            let numeric = (up - down) / (2.0 * h);
            assert!(
                (numeric - grad[i]).abs() <= 1e-6 * grad[i].abs().max(1.0),
                "coordinate {i}: {numeric} against {}",
                grad[i]
            );
        }
    }

    /// At a point where every residual is 0 the Gauss–Newton matrix is E's Hessian: its
    /// product with a vector agrees with central differences of the gradient to 1e-5
    /// relative, and it is symmetric.
    #[test]
    fn gauss_newton_matrix_is_the_hessian_where_the_residuals_vanish() {
        let mut case = case();
        let n = case.angles.len();
        // Orientations from the depth, and the brightness they give.
        let probe = case.energy();
        let mut x = case.point.clone();
        for j in 0..n {
            if case.pull[j] > 0.0 {
                let z = &case.point[2 * n..];
                let ((f, g), _) = probe.target(j, z);
                x[j] = f;
                x[n + j] = g;
            }
        }
        let scale = probe.scale;
        let angles: Vec<f64> = (0..n)
            .map(|j| scale.angle(case.map.fg(x[j], x[n + j]).value))
            .collect();
        drop(probe);
        case.angles = angles;
        let energy = case.energy();
        let gn = energy.linearise(&x, false);
        let mut work = vec![0.0; 2 * n];
        let v: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 37) % 11) as f64 / 11.0 - 0.4)
            .collect();
        let u: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 53) % 7) as f64 / 7.0 - 0.5)
            .collect();
        let (mut hv, mut hu) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        gn.apply(0.0, &v, &mut hv, &mut work);
        gn.apply(0.0, &u, &mut hu, &mut work);
        let (uhv, vhu) = (dot(&u, &hv), dot(&v, &hu));
        assert!(
            (uhv - vhu).abs() <= 1e-12 * uhv.abs().max(1.0),
            "{uhv} against {vhu}"
        );
        let h = 1e-6;
        let (mut up, mut down) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
        let shifted =
            |sign: f64| -> Vec<f64> { x.iter().zip(&v).map(|(x, v)| x + sign * h * v).collect() };
        energy.value_and_gradient(&shifted(1.0), &mut up, &mut work);
        energy.value_and_gradient(&shifted(-1.0), &mut down, &mut work);
        let largest = hv.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for i in 0..3 * n {
            let numeric = (up[i] - down[i]) / (2.0 * h);
            assert!(
                (numeric - hv[i]).abs() <= 1e-5 * largest,
                "entry {i}: {numeric} against {}",
                hv[i]
            );
        }
    }

    /// The sparse matrix the preconditioner coarsens is the model's: its product with a vector
    /// is `apply`'s, up to the diagonal floor.
    #[test]
    fn the_sparse_matrix_is_the_models() {
        let case = case();
        let energy = case.energy();
        let n = energy.len();
        let model = energy.linearise(&case.point, false);
        let v: Vec<f64> = (0..3 * n)
            .map(|i| ((i * 37) % 11) as f64 / 11.0 - 0.4)
            .collect();
        for nu in [0.0, 0.3] {
            let (mut want, mut got) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
            let mut work = vec![0.0; 2 * n];
            model.apply(nu, &v, &mut want, &mut work);
            model.matrix(nu).mul_vec(&v, &mut got);
            for i in 0..3 * n {
                // The floor: 1e-6 on every diagonal entry, and z's damping from its floored
                // diagonal.
                let slack = 2.0 * DIAGONAL_FLOOR * (1.0 + nu) * v[i].abs() + 1e-12;
                assert!(
                    (want[i] - got[i]).abs() <= slack,
                    "ν = {nu}, entry {i}: {} against {}",
                    got[i],
                    want[i]
                );
            }
        }
    }

    /// A pixel's block keeps the data term's Hessian where the pixel's smoothness and pull
    /// hold it (no eigenvalue below [`HELD`] of their diagonal); elsewhere only the eigenvalue
    /// below that floor changes, to the floor, along the same eigenvector.
    #[test]
    fn a_block_keeps_the_curvature_its_diagonal_holds() {
        // The eigenvalues (small, large) of [a, b, c] and the small one's unit eigenvector.
        let eigen = |[a, b, c]: [f64; 3]| {
            let (mean, radius) = (0.5 * (a + c), (0.25 * (a - c) * (a - c) + b * b).sqrt());
            let angle = 0.5 * (2.0 * b).atan2(a - c) + std::f64::consts::FRAC_PI_2;
            (mean - radius, mean + radius, (angle.cos(), angle.sin()))
        };
        let cases = [
            // Positive definite already.
            ([1.0, 0.3, 2.0], 4.5),
            // A ridge pixel of DiLiGenT pot2 (λ = 1): negative curvature −1.51, held by 4.5.
            ([-1.3036, -0.9289, 2.6370], 4.5),
            // Negative curvature beyond what the diagonal holds.
            ([-4.0, 1.0, 0.5], 4.5),
            ([-3.0, 2.5, -1.0], 2.0),
            // Both eigenvalues below the floor.
            ([-10.0, 0.0, -10.0], 2.0),
        ];
        for (data, diagonal) in cases {
            let block = held(data, diagonal);
            let whole = |m: [f64; 3]| [diagonal + m[0], m[1], diagonal + m[2]];
            let (low, high, soft) = eigen(whole(data));
            let (kept_low, kept_high, _) = eigen(whole(block));
            let floor = HELD * diagonal;
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0);
            if low >= floor {
                assert!(
                    data.iter().zip(&block).all(|(&a, &b)| close(a, b)),
                    "{data:?} became {block:?}"
                );
                continue;
            }
            assert!(
                close(kept_low, floor),
                "{data:?}: {kept_low} against {floor}"
            );
            assert!(close(kept_high, high.max(floor)), "{data:?}: {kept_high}");
            // The change is (floor − low)·vvᵀ for the soft eigenvector v where the stiff
            // eigenvalue is above the floor.
            if high > floor {
                let rise = floor - low;
                let (x, y) = soft;
                let want = [rise * x * x, rise * x * y, rise * y * y];
                for i in 0..3 {
                    assert!(close(block[i] - data[i], want[i]), "{data:?}: entry {i}");
                }
            }
        }
    }

    /// Every step lowers E, and the steps reach a minimum: once they stop changing (f, g) by
    /// 1e-10, the gradient is below 1e-6 of where it started.
    #[test]
    fn steps_lower_the_energy_to_a_minimum() {
        let case = case();
        let energy = case.energy();
        let mut minimiser = Minimiser::new(&energy, case.point.clone());
        let norm = |v: &[f64]| dot(v, v).sqrt();
        let start = norm(&minimiser.grad);
        let mut last = minimiser.energy();
        let mut steps = 0;
        loop {
            let change = minimiser.step(&energy);
            steps += 1;
            assert!(minimiser.energy() < last || change == 0.0, "step {steps}");
            last = minimiser.energy();
            if change < 1e-10 || steps == 500 {
                break;
            }
        }
        let end = norm(&minimiser.grad);
        assert!(end < 1e-6 * start, "{end} of {start} after {steps} steps");
    }

    /// Steps from the case's start until a step changes nothing by 1e-9 (or 2000 steps), with
    /// the acceleration over `depth` steps; returns the steps, E and |∇E| at the end.
    fn minimise(case: &Case, depth: usize) -> (usize, f64, f64) {
        let energy = case.energy();
        let mut minimiser = Minimiser::with_acceleration(&energy, case.point.clone(), depth);
        let mut last = minimiser.energy();
        let mut steps = 0;
        loop {
            let change = minimiser.step(&energy);
            steps += 1;
            // E never rises, but for rounding where the relaxation re-sums it.
            let e = minimiser.energy();
            assert!(
                e <= last * (1.0 + 1e-14),
                "depth {depth}, step {steps}: {last} → {e}"
            );
            last = minimiser.energy();
            if change < 1e-9 || steps == 2000 {
                break;
            }
        }
        (steps, last, dot(&minimiser.grad, &minimiser.grad).sqrt())
    }

    /// The acceleration keeps E falling at every step and ends at the plain steps' minimum,
    /// in fewer steps where they creep: on the sphere under an oblique light with the occluding
    /// boundary, and under a light 5° from the view with the free boundary (a shallow valley of
    /// E, as on ball photograph 052, where the plain steps shrink slowly).
    #[test]
    fn acceleration_reaches_the_same_minimum_in_fewer_steps() {
        for (size, boundary, light) in [
            (20, Boundary::Occluding, (30.0, 40.0)),
            (48, Boundary::Free, (30.0, 5.0)),
            (48, Boundary::Free, (30.0, 2.0)),
            (48, Boundary::Occluding, (30.0, 60.0)),
        ] {
            let case = case_with(size, &boundary, light);
            let plain = minimise(&case, 0);
            let fast = minimise(&case, LM_ANDERSON_DEPTH);
            eprintln!("{boundary:?}: plain {plain:?}, accelerated {fast:?}");
            assert!(plain.2 < 1e-6 && fast.2 < 1e-6, "{plain:?} {fast:?}");
            assert!(
                (plain.1 - fast.1).abs() < 1e-9 * plain.1,
                "{plain:?} {fast:?}"
            );
            assert!(fast.0 <= plain.0, "{plain:?} {fast:?}");
        }
    }

    /// Pixels of the case: some with a data term and a pull, and every one without either
    /// (the sphere's shadow, the pixels the depth cannot tilt; there is at least one).
    fn kinds_of_pixel(energy: &Energy) -> Vec<usize> {
        let n = energy.len();
        let mut chosen = Vec::new();
        for want in [(true, true), (true, false), (false, true), (false, false)] {
            let pick = (0..n)
                .filter(|&j| (energy.nodes[j].data_weight != 0.0, energy.pull[j] > 0.0) == want);
            chosen.extend(
                pick.step_by(if want == (true, true) { 7 } else { 1 })
                    .take(6),
            );
        }
        assert!(chosen.len() > 6, "{chosen:?}");
        chosen
    }

    /// A pixel's part of E is E along its orientation: moving the pixel changes E by what its
    /// part changes by (to 1e-10), its gradient is E's at the pixel, and its Hessian agrees
    /// with central differences of that gradient to 1e-5.
    #[test]
    fn a_pixels_part_is_e_along_its_orientation() {
        let case = case();
        let energy = case.energy();
        let n = energy.len();
        let x = case.point.clone();
        let z = &x[2 * n..];
        let (mut grad, mut work) = (vec![0.0; 3 * n], vec![0.0; 2 * n]);
        let e = energy.value_and_gradient(&x, &mut grad, &mut work);
        let mut scratch = vec![0.0; 3 * n];
        for j in kinds_of_pixel(&energy) {
            let target = (energy.pull[j] > 0.0).then(|| energy.target(j, z).0);
            let at = (x[j], x[n + j]);
            let (part, gradient, hessian) = energy.local(&x, j, target, at);
            let close = |a: f64, b: f64, tol: f64| (a - b).abs() <= tol * a.abs().max(1.0);
            assert!(close(gradient[0], grad[j], 1e-10), "pixel {j}: ∂f");
            assert!(close(gradient[1], grad[n + j], 1e-10), "pixel {j}: ∂g");
            let mut y = x.clone();
            y[j] += 0.03;
            y[n + j] -= 0.02;
            let moved = energy.local(&x, j, target, (y[j], y[n + j])).0;
            let e_moved = energy.value_and_gradient(&y, &mut scratch, &mut work);
            assert!(close(e_moved - e, moved - part, 1e-10), "pixel {j}: E");
            let h = 1e-6;
            let d = |df: f64, dg: f64| energy.local(&x, j, target, (at.0 + df, at.1 + dg)).1;
            let (fp, fm, gp, gm) = (d(h, 0.0), d(-h, 0.0), d(0.0, h), d(0.0, -h));
            let numeric = [
                (fp[0] - fm[0]) / (2.0 * h),
                (fp[1] - fm[1]) / (2.0 * h),
                (gp[1] - gm[1]) / (2.0 * h),
            ];
            for i in 0..3 {
                assert!(
                    close(hessian[i], numeric[i], 1e-5),
                    "pixel {j}: entry {i}, {} against {}",
                    hessian[i],
                    numeric[i]
                );
            }
        }
    }

    /// Relaxing a pixel never raises E and leaves it at a least of E along its orientation:
    /// E's gradient at the pixel is below 1e-6 of where it was, and no other unknown moves.
    #[test]
    fn relaxing_a_pixel_finds_the_least_along_its_orientation() {
        let case = case();
        let energy = case.energy();
        let n = energy.len();
        let (mut grad, mut work) = (vec![0.0; 3 * n], vec![0.0; 2 * n]);
        for j in kinds_of_pixel(&energy) {
            let x = case.point.clone();
            let e = energy.value_and_gradient(&x, &mut grad, &mut work);
            let before = grad[j].hypot(grad[n + j]);
            let mut y = x.clone();
            energy.relax(&mut y, j);
            let relaxed = energy.value_and_gradient(&y, &mut grad, &mut work);
            assert!(relaxed <= e, "pixel {j}: E {e} → {relaxed}");
            let after = grad[j].hypot(grad[n + j]);
            assert!(
                after <= 1e-6 * before.max(1.0),
                "pixel {j}: gradient {before} → {after}"
            );
            let others = (0..3 * n).filter(|&i| i != j && i != n + j);
            assert!(others.into_iter().all(|i| x[i] == y[i]), "pixel {j}");
        }
    }
}
