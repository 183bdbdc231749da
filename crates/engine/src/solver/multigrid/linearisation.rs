//! The linearised equations: the data term's reaction matrices and the finest level's
//! pointwise updates, evaluated a block of pixels at a time.

use super::*;

/// The positive semidefinite part of a symmetric 2 × 2 matrix: its negative eigenvalues set to 0.
#[inline]
pub(super) fn positive_part(m: Sym) -> Sym {
    let (a, b, c) = (m[0], m[1], m[2]);
    let det = a * c - b * b;
    // Both eigenvalues of one sign (or zero) when the determinant is not negative: the
    // matrix is kept or dropped whole, without the eigenvalues' square root.
    if det >= 0.0 {
        return if a >= 0.0 && c >= 0.0 { m } else { [0.0; 3] };
    }
    let mid = 0.5 * (a + c);
    let half = 0.5 * (a - c);
    let radius = (half * half + b * b).sqrt();
    let (high, low) = (mid + radius, mid - radius);
    // M = high·P + low·(I − P) with P = (M − low·I)/(high − low); keep high·P.
    let s = high / (high - low);
    [s * (a - low), s * b, s * (c - low)]
}

/// Points of the finest level evaluated together: one call of the reflectance map's batch per
/// block, on the stack (no allocation, and the same in WebAssembly).
pub(super) const BLOCK: usize = 64;

/// What the finest level's sweeps need to know about the problem.
pub(super) struct Context<'a> {
    /// The image, row-major, unpadded.
    pub(super) image: &'a [f64],
    pub(super) reflectance: &'a dyn ReflectanceMap,
    /// 1/k for k = 0..4 (0 for k = 0).
    pub(super) inv_k: [f64; 5],
    /// 4λ/k for k = 0..4: the weight of the data term in the Jacobi update.
    pub(super) data_k: [f64; 5],
    /// 4λ: the data weight of one lit pixel in the k-scaled equation.
    pub(super) data: f64,
}

/// The neighbour averages ū of a block of cells of one colour in one padded row of the finest
/// level, as structure of arrays for the reflectance map's batch.
pub(super) struct Averages {
    pub(super) f: [f64; BLOCK],
    pub(super) g: [f64; BLOCK],
}

impl Averages {
    /// ū of the cells j0..j0 + n of colour-row `r` (cells c = 2j + start), read from `other`
    /// (the other colour); cells outside the domain get (0, 0) (their k is 0).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn of(
        ctx: &Context,
        kind_row: &[u8],
        other: &[Pair],
        hw: usize,
        r: usize,
        start: usize,
        j0: usize,
        n: usize,
    ) -> Averages {
        let mut u = Averages {
            f: [0.0; BLOCK],
            g: [0.0; BLOCK],
        };
        // As `neighbour_sum`, with the rows sliced once: cell j's left and right neighbours
        // are j + start − 1 and j + start of the middle row. A block never starts at the
        // padding column 0 of a row whose cells start at column 0 (j0 ≥ 1 there); a last cell
        // with j + start = hw is the right padding column, left at (0, 0).
        let (up, mid, down) = (
            &other[(r - 1) * hw..r * hw],
            &other[r * hw..(r + 1) * hw],
            &other[(r + 1) * hw..(r + 2) * hw],
        );
        let inside = n.min(hw - start - j0);
        let end = j0 + inside;
        let kinds = kind_row[2 * j0 + start..].iter().step_by(2);
        let neighbours = mid[j0 + start - 1..end + start - 1]
            .iter()
            .zip(&mid[j0 + start..end + start])
            .zip(up[j0..end].iter().zip(&down[j0..end]));
        let out = u.f[..inside].iter_mut().zip(&mut u.g[..inside]);
        for (((f, g), &kd), ((a, b), (t, d))) in out.zip(kinds).zip(neighbours) {
            let inv_k = ctx.inv_k[(kd & K_BITS) as usize];
            *f = (a[0] + b[0] + t[0] + d[0]) * inv_k;
            *g = (a[1] + b[1] + t[1] + d[1]) * inv_k;
        }
        u
    }
}

impl<'a> Context<'a> {
    /// The context of a solve of `image` under `reflectance` with smoothness weight `lambda`.
    pub(super) fn new(
        image: &'a Image,
        reflectance: &'a dyn ReflectanceMap,
        lambda: f64,
    ) -> Context<'a> {
        let mut inv_k = [0.0; 5];
        let mut data_k = [0.0; 5];
        for k in 1..5 {
            inv_k[k] = 1.0 / k as f64;
            data_k[k] = lambda * 4.0 / k as f64;
        }
        Context {
            image: image.data(),
            reflectance,
            inv_k,
            data_k,
            data: 4.0 * lambda,
        }
    }

    /// The coarse model's reaction `a` (Gauss–Newton, 4λ·∇R·∇Rᵀ) of a lit fine unknown, plus
    /// the positive part of the curvature term −4λ·(I − R)·∇²R that Gauss–Newton leaves out,
    /// from the map's [`ReflectanceMap::fg_hessian`] at the neighbour average, where
    /// `brightness_error` is I − R.
    ///
    /// Where the picture is brighter than the assumed light lets the surface be (I > R near
    /// the map's peak, where ∇²R is negative definite, as under a mismatched light), that term
    /// makes the true operator stiffer than the model: the coarse correction then overshoots,
    /// and by more than a factor 2 it grows a mode from cycle to cycle (seen on the strips at
    /// oblique assumed tilts: the residual fell to 1e-6, then rose ×10 per cycle). Its
    /// negative part (a softer true operator) only slows the correction, and would make the
    /// coarse problem indefinite, so it is left out. ∇²R is evaluated only here (once per
    /// cycle), not in the sweeps.
    #[inline]
    pub(super) fn with_curvature(&self, brightness_error: f64, hessian: &Hessian, a: Sym) -> Sym {
        let w = -self.data * brightness_error;
        let extra = positive_part([w * hessian[0], w * hessian[1], w * hessian[2]]);
        if extra.iter().any(|v| !v.is_finite()) {
            return a;
        }
        [a[0] + extra[0], a[1] + extra[1], a[2] + extra[2]]
    }

    /// The Jacobi update ū + (4λ/k)·w·(I − R(ū))·∇R(ū) of a fine unknown with flags `kind`,
    /// neighbour average `u` = ū and brightness `intensity`, given the map's sample at ū.
    #[inline]
    pub(super) fn fine_update(&self, kind: u8, u: Pair, intensity: f64, sample: &Sample) -> Pair {
        if kind & LIT == 0 {
            return u;
        }
        let e = self.data_k[(kind & K_BITS) as usize] * (intensity - sample.value);
        [u[0] + e * sample.d1, u[1] + e * sample.d2]
    }

    /// The Jacobi update of one fine unknown with flags `kind` and neighbour sum `s` at image
    /// index `pixel` (one evaluation of the map: for the single-level residual).
    pub(super) fn fine_target(&self, kind: u8, s: Pair, pixel: usize) -> Pair {
        let k = (kind & K_BITS) as usize;
        let u = [s[0] * self.inv_k[k], s[1] * self.inv_k[k]];
        let sample = if kind & LIT != 0 {
            self.reflectance.fg(u[0], u[1])
        } else {
            Sample::ZERO
        };
        self.fine_update(kind, u, self.image[pixel], &sample)
    }

    /// One half-sweep of padded row `r` of the finest level: the cells of one colour
    /// (c = 2j + `start`, j in `span`) in `row`, moved to their Jacobi targets from the other
    /// colour's values `other` (without `WRITE` only measured). Returns the largest change.
    #[inline(never)]
    pub(super) fn fine_row<const TRACK: bool, const WRITE: bool>(
        &self,
        kind_row: &[u8],
        image_row: &[f64],
        other: &[Pair],
        half: HalfRow,
        row: &mut [Pair],
    ) -> f64 {
        let HalfRow { hw, r, start, span } = half;
        let mut worst = 0.0;
        let mut samples = [Sample::ZERO; BLOCK];
        let mut j0 = span.0;
        while j0 < span.1 {
            let n = BLOCK.min(span.1 - j0);
            let u = Averages::of(self, kind_row, other, hw, r, start, j0, n);
            self.reflectance
                .fg_batch(&u.f[..n], &u.g[..n], &mut samples[..n]);
            // Cell j is padded column c = 2j + start, image column c − 1 (c ≥ 1: the span
            // starts and ends at unknowns); zipped, without an index check per cell.
            let first = 2 * j0 + start;
            let cells = row[j0..j0 + n]
                .iter_mut()
                .zip(&samples[..n])
                .zip(u.f[..n].iter().zip(&u.g[..n]))
                .zip(kind_row[first..].iter().step_by(2))
                .zip(image_row[first - 1..].iter().step_by(2));
            for ((((slot, sample), (&f, &g)), &kd), &intensity) in cells {
                if kd & UNKNOWN == 0 {
                    continue;
                }
                let new = self.fine_update(kd, [f, g], intensity, sample);
                if TRACK {
                    worst = track(worst, *slot, new);
                }
                if WRITE {
                    *slot = new;
                }
            }
            j0 += n;
        }
        worst
    }
}
