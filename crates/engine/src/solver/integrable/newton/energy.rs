//! The energy E(f, g, z): its value, gradient and pointwise relaxation, and its linearisation
//! at a point.

use super::*;

/// No unknown there.
pub(super) const NONE: u32 = u32::MAX;

/// A depth slope at one pixel along one axis: up to two (unknown, weight) terms.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Stencil {
    pub(super) at: [u32; 2],
    pub(super) weight: [f64; 2],
    pub(super) len: u8,
}

impl Stencil {
    /// The slope (ahead − back) at `j`: the central difference when both neighbours are
    /// unknowns, the one-sided one when one is, none when neither is.
    pub(super) fn new(j: usize, back: u32, ahead: u32) -> Stencil {
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
    pub(super) fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.at[..self.len as usize]
            .iter()
            .zip(&self.weight)
            .map(|(&k, &c)| (k as usize, c))
    }

    /// The slope of `z`.
    pub(super) fn of(&self, z: &[f64]) -> f64 {
        self.terms().map(|(k, c)| c * z[k]).sum()
    }
}

/// The orientation t(p, q) of a depth slope and its Jacobian [∂f/∂p, ∂f/∂q, ∂g/∂p, ∂g/∂q].
pub(super) fn orientation(p: f64, q: f64) -> ((f64, f64), [f64; 4]) {
    (fg_from_pq(p, q), fg_pq_jacobian(p, q))
}

/// E(f, g, z) on one domain. A point is one vector `[f…, g…, z…]` of 3n values for the n
/// unknown pixels.
pub(in crate::solver::integrable) struct Energy<'a> {
    pub(super) nodes: &'a [Node],
    /// f and g of every value slot (the unknowns' entries are not read; the fixed ring's are).
    pub(super) slots: (&'a [f64], &'a [f64]),
    /// The slot of a missing neighbour.
    pub(super) zero: usize,
    pub(super) angles: &'a [f64],
    pub(super) pull: &'a [f64],
    pub(super) scale: AngleScale,
    pub(super) reflectance: &'a dyn ReflectanceMap,
    /// The slope along x and along the rows at each unknown: p = −(x slope), q = (row slope).
    pub(super) along_x: Vec<Stencil>,
    pub(super) along_rows: Vec<Stencil>,
    /// Where each depth value enters the slopes: for depth k, `readers[reader_start[k]..
    /// reader_start[k + 1]]` are the pulled pixels j whose (p, q) read it, with ∂p_j/∂z_k and
    /// ∂q_j/∂z_k, in order of j.
    pub(super) reader_start: Vec<usize>,
    pub(super) readers: Vec<(u32, f64, f64)>,
    /// The (column, row) of each unknown.
    pub(super) cells: Vec<(u32, u32)>,
}

impl<'a> Energy<'a> {
    /// The energy of the unknowns `nodes` (at row-major `pixels` of a grid of `size` (width,
    /// height) whose value slots are `slot`), the fixed ring's values in `slots`, φ(I) per
    /// unknown in `angles` and the integrability weight per unknown in `pull`.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::solver::integrable) fn new(
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
    pub(in crate::solver::integrable) fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Where each unknown of a point sits for the preconditioner's aggregation: f and g at
    /// their pixels, the depth by its sublattice of column and row parity, at the cell of a
    /// grid half as fine. Central differences never couple neighbouring depths: a pixel's p
    /// reads the depths two columns apart, its q those two rows apart, and t(p, q) couples the
    /// two, so the four sublattices fall into two coupled pairs (c + r even, c + r odd); an
    /// aggregate keeps to one sublattice.
    pub(super) fn places(&self) -> Vec<Place> {
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
    pub(super) fn gather_depth(&self, k: usize, w: &[f64]) -> f64 {
        let mut sum = 0.0;
        for &(j, dp, dq) in &self.readers[self.reader_start[k]..self.reader_start[k + 1]] {
            let j = j as usize;
            sum -= dp * w[2 * j] + dq * w[2 * j + 1];
        }
        sum
    }

    /// E at `v`, and its gradient into `grad` (3n values); `scratch` holds 2n values.
    pub(in crate::solver::integrable) fn value_and_gradient(
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
    pub(super) fn target(&self, j: usize, z: &[f64]) -> ((f64, f64), [f64; 4]) {
        orientation(-self.along_x[j].of(z), self.along_rows[j].of(z))
    }

    /// Pixel j's data term at the orientation (f, g), for a pixel that has one: its value, its
    /// gradient and its whole Hessian [ff, fg, gg] (the residual's curvature included).
    pub(super) fn data_term(&self, j: usize, (f, g): (f64, f64)) -> (f64, [f64; 2], [f64; 3]) {
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
    pub(super) fn local(
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
    pub(super) fn relax(&self, v: &mut [f64], j: usize) {
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
    pub(in crate::solver::integrable) fn linearise(&self, v: &[f64], soft: bool) -> Model<'_, 'a> {
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
