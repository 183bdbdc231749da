//! A crease-preserving smoothness for the Ikeuchi–Horn energy.
//!
//! Horn's smoothness ¼ Σ |Δ(f, g)|² over neighbour pairs charges a fold by the square of its
//! jump, so a solve spreads every crease over many pixels: a sawtooth roof comes back as
//! smooth corrugations. This solver minimises
//!
//! e = Σ φ(|Δ(f, g)|) + λ·Σ (I − R(f, g))²
//!
//! over the unknown pixels of a [`BoundaryConditions`] domain, with a choice of φ
//! ([`Smoothness`]): Horn's φ(d) = ¼ d², or the Charbonnier penalty
//! φ(d) = ½ ε (√(d² + ε²) − ε), which is ¼ d² for changes much smaller than ε and ½ ε·d (a
//! total variation, linear in the jump) for larger ones. A fold then costs its height, not its
//! square, whether it is sharp or spread; so it stays sharp where the boundary or the data put
//! it.
//!
//! The iteration is iteratively reweighted least squares: each neighbour pair gets the weight
//! w = 2 φ′(d)/d of its current change d (1 for Horn's term, ε/√(d² + ε²) for Charbonnier), and
//! a successive over-relaxation sweep (row-major, in place: deterministic, one thread; meant
//! for domains of tens of thousands of pixels, which a caller may solve side by side) moves
//! each unknown towards the weighted neighbour mean (f̄, ḡ) plus the Gauss–Newton step of the
//! brightness term taken there, by ω (1.92 by default: [`CreaseOptions::relaxation`]) times
//! the way:
//!
//! (f, g) ← (f̄, ḡ) + 4λ (I − R) ∇R / (W + 4λ |∇R|²),  R and ∇R = (∂R/∂f, ∂R/∂g) at (f̄, ḡ),
//!
//! with W the sum of the pixel's weights. For Horn's weights (W = k neighbours) and small ∇R
//! this is Horn's update with its 4λ/k; the |∇R|² in the denominator keeps the step stable for
//! any λ and any W (a pixel whose neighbours are all across folds has a small W). Values stay
//! in the visible disc |(f, g)| ≤ 2. Pixels in attached shadow (I at or below the ambient
//! level) and λ = 0 (pure interpolation of the boundary values) carry smoothness only; with
//! [`CreaseOptions::shadow_along_columns`] such pixels are coupled only along their image
//! column (a strip's generators), so the boundary above and below decides them. The sweeps
//! stop when no f or g changes by more than the tolerance; they may start from a given shape
//! ([`solve_from`]), which changes the sweeps needed, not the fixed point they reach.

use super::carries_data;
use crate::boundary::{BoundaryConditions, Role};
use crate::error::{Error, Result};
use crate::gradient_space::FG_RADIUS;
use crate::grid::{Grid, Image};
use crate::reflectance::ReflectanceMap;

/// The smoothness penalty φ of a change d = |Δ(f, g)| between neighbours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Smoothness {
    /// Horn's φ(d) = ¼ d²: spreads folds.
    Quadratic,
    /// Charbonnier φ(d) = ½ ε (√(d² + ε²) − ε): quadratic below ε, linear (total variation)
    /// above; keeps folds.
    Charbonnier {
        /// The change ε (> 0) where the penalty turns from quadratic to linear.
        epsilon: f64,
    },
}

impl Smoothness {
    /// The penalty φ(d) of a change `d` ≥ 0.
    ///
    /// ```
    /// use shadelab::Smoothness;
    /// let tv = Smoothness::Charbonnier { epsilon: 0.01 };
    /// // Small changes cost what Horn's term charges; a large jump costs ½ ε d, not ¼ d².
    /// assert!((tv.penalty(1e-4) / Smoothness::Quadratic.penalty(1e-4) - 1.0).abs() < 1e-3);
    /// assert!((tv.penalty(1.0) - 0.5 * 0.01 * (1.0 - 0.01)).abs() < 1e-6);
    /// ```
    pub fn penalty(self, d: f64) -> f64 {
        match self {
            Smoothness::Quadratic => 0.25 * d * d,
            Smoothness::Charbonnier { epsilon: e } => 0.5 * e * ((d * d + e * e).sqrt() - e),
        }
    }

    /// The reweighting weight 2 φ′(d)/d of a change `d` ≥ 0: 1 for Horn's term, ε/√(d² + ε²)
    /// for Charbonnier.
    pub fn weight(self, d: f64) -> f64 {
        self.weight_squared(d * d)
    }

    /// [`Smoothness::weight`] of the change whose square is `d2`.
    fn weight_squared(self, d2: f64) -> f64 {
        match self {
            Smoothness::Quadratic => 1.0,
            Smoothness::Charbonnier { epsilon: e } => e / (d2 + e * e).sqrt(),
        }
    }
}

/// The parameters of a crease-preserving solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CreaseOptions {
    /// Weight λ ≥ 0 of the brightness term (0: the boundary values interpolated by the
    /// smoothness alone).
    pub lambda: f64,
    /// The smoothness penalty.
    pub smoothness: Smoothness,
    /// Stop when no f or g changes by more than this in a sweep (> 0).
    pub tol: f64,
    /// Stop after this many sweeps (≥ 1).
    pub max_sweeps: usize,
    /// The over-relaxation factor ω of the sweeps, 1 ≤ ω < 2 (1: plain Gauss–Seidel). It
    /// changes how fast the sweeps reach the fixed point, not the fixed point.
    pub relaxation: f64,
    /// In attached shadow (and everywhere when λ = 0), couple a pixel only to the pixels
    /// above and below it (along the image column), not beside it, wherever both columns hold
    /// a fixed pixel: the shading there says only that the surface faces away from the light,
    /// and a cylinder whose generators run down the columns (a strip profiled column by
    /// column) takes its normal from the boundary along its generator.
    pub shadow_along_columns: bool,
}

impl Default for CreaseOptions {
    /// λ = 1, Charbonnier with ε = 0.02, tolerance 10⁻⁶, at most 20 000 sweeps, ω = 1.92,
    /// shadowed pixels coupled in every direction.
    fn default() -> Self {
        CreaseOptions {
            lambda: 1.0,
            smoothness: Smoothness::Charbonnier { epsilon: 0.02 },
            tol: 1e-6,
            max_sweeps: 20_000,
            relaxation: 1.92,
            shadow_along_columns: false,
        }
    }
}

impl CreaseOptions {
    /// Checks every parameter, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        let hi = super::LAMBDA_RANGE.1;
        if !(self.lambda >= 0.0 && self.lambda <= hi) {
            return Err(Error::invalid(format!(
                "lambda = {:e} is outside 0..{hi:e} (0: the data alone)",
                self.lambda
            )));
        }
        if let Smoothness::Charbonnier { epsilon } = self.smoothness {
            if !(epsilon.is_finite() && epsilon > 0.0) {
                return Err(Error::invalid(format!(
                    "crease epsilon = {epsilon} must be a positive number"
                )));
            }
        }
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(Error::invalid(format!(
                "tol = {} must be a positive number",
                self.tol
            )));
        }
        if !(self.relaxation >= 1.0 && self.relaxation < 2.0) {
            return Err(Error::invalid(format!(
                "relaxation = {} must be at least 1 and below 2",
                self.relaxation
            )));
        }
        if self.max_sweeps == 0 {
            return Err(Error::invalid("the most sweeps must be at least 1"));
        }
        Ok(())
    }
}

/// The result of a crease-preserving solve.
#[derive(Debug, Clone, PartialEq)]
pub struct CreaseSolution {
    /// Stereographic f at every pixel (the fixed values on fixed pixels, 0 outside).
    pub f: Image,
    /// Stereographic g at every pixel.
    pub g: Image,
    /// Sweeps done.
    pub sweeps: usize,
    /// Whether the last sweep changed no value by more than the tolerance.
    pub converged: bool,
    /// The smoothness term Σ φ(|Δ(f, g)|) over neighbour pairs inside the domain.
    pub smoothness_energy: f64,
    /// The brightness term Σ (I − R)² over the lit unknown pixels.
    pub brightness_energy: f64,
}

/// Solves for (f, g) on `bc`'s domain from `image` under `reflectance` with a
/// crease-preserving smoothness (see the module's documentation). Unknowns start at (0, 0).
///
/// Fails on an image of another size than the domain, bad options, or a value that is not a
/// number (from a non-finite brightness). The light is the caller's to choose (a
/// [`FrontLight`](crate::light::FrontLight)).
///
/// ```
/// use shadelab_engine::boundary::{boundary_conditions, Boundary};
/// use shadelab::{Grid, Mask};
/// use shadelab::Light;
/// use shadelab::Lambertian;
/// use shadelab_engine::solver::crease::{solve, CreaseOptions};
///
/// // A strip whose left column faces left and right column faces right, with no data
/// // (λ = 0): the smoothness alone fills the middle.
/// let (w, h) = (9, 3);
/// let mask = Mask::new(w, h, true);
/// let normals = Grid::from_fn(w, h, |c, _| {
///     let x = if c < w / 2 { -0.5 } else { 0.5 };
///     nalgebra::Vector3::new(x, 0.0, 1.0)
/// });
/// let bc = boundary_conditions(&mask, &Boundary::Given(normals)).unwrap();
/// let light = Lambertian::unit(Light::FRONT);
/// let options = CreaseOptions { lambda: 0.0, ..CreaseOptions::default() };
/// let s = solve(&Grid::new(w, h, 1.0), &bc, &light, &options).unwrap();
/// assert!(s.converged);
/// assert!(*s.f.get(1, 1) < 0.0 && *s.f.get(7, 1) > 0.0);
/// ```
pub fn solve(
    image: &Image,
    bc: &BoundaryConditions,
    reflectance: &dyn ReflectanceMap,
    options: &CreaseOptions,
) -> Result<CreaseSolution> {
    solve_from(image, bc, reflectance, options, None)
}

/// [`solve`] with the unknowns starting at `start` = (f, g), two images of the domain's size,
/// instead of (0, 0) (a warm start: from a coarser solve, or from a shape to test).
pub fn solve_from(
    image: &Image,
    bc: &BoundaryConditions,
    reflectance: &dyn ReflectanceMap,
    options: &CreaseOptions,
    start: Option<(&Image, &Image)>,
) -> Result<CreaseSolution> {
    options.validate()?;
    let (w, h) = (bc.roles.width(), bc.roles.height());
    image.check_same_size("image is", &bc.roles, "the domain is")?;
    let roles = bc.roles.data();
    let (mut f, mut g) = match start {
        Some((f0, g0)) => {
            for s in [f0, g0] {
                s.check_same_size("the start is", &bc.roles, "the domain is")?;
            }
            (f0.data().to_vec(), g0.data().to_vec())
        }
        None => (vec![0.0; w * h], vec![0.0; w * h]),
    };
    for (p, role) in roles.iter().enumerate() {
        if *role != Role::Unknown {
            (f[p], g[p]) = (0.0, 0.0);
        }
    }
    for &(i, [fv, gv]) in bc.fixed_values() {
        f[i] = fv;
        g[i] = gv;
    }
    let ambient = reflectance.ambient();
    let pairs = Pairs::new(image, bc, ambient, options);
    let four_lambda = 4.0 * options.lambda;
    let omega = options.relaxation;
    let mut sweeps = 0;
    let mut converged = pairs.unknowns.is_empty();
    while !converged && sweeps < options.max_sweeps && !crate::cancel::requested() {
        let mut largest: f64 = 0.0;
        for (k, &p) in pairs.unknowns.iter().enumerate() {
            let (f0, g0) = (f[p], g[p]);
            let (mut sw, mut sf, mut sg) = (0.0, 0.0, 0.0);
            for &(q, factor) in pairs.of(k) {
                let (fq, gq) = (f[q], g[q]);
                let (df, dg) = (f0 - fq, g0 - gq);
                let wt = factor * options.smoothness.weight_squared(df * df + dg * dg);
                sw += wt;
                sf += wt * fq;
                sg += wt * gq;
            }
            if sw <= 0.0 {
                continue;
            }
            let (mut fn_, mut gn) = (sf / sw, sg / sw);
            let intensity = image.data()[p];
            if four_lambda > 0.0 && carries_data(intensity, ambient, None) {
                let s = reflectance.fg(fn_, gn);
                let k = four_lambda * (intensity - s.value)
                    / (sw + four_lambda * (s.d1 * s.d1 + s.d2 * s.d2));
                fn_ += k * s.d1;
                gn += k * s.d2;
            }
            fn_ = f0 + omega * (fn_ - f0);
            gn = g0 + omega * (gn - g0);
            let r2 = fn_ * fn_ + gn * gn;
            if r2 > FG_RADIUS * FG_RADIUS {
                let scale = FG_RADIUS / r2.sqrt();
                fn_ *= scale;
                gn *= scale;
            }
            let change = (fn_ - f0).abs().max((gn - g0).abs());
            largest = if change.is_nan() {
                f64::INFINITY
            } else {
                largest.max(change)
            };
            f[p] = fn_;
            g[p] = gn;
        }
        sweeps += 1;
        if !largest.is_finite() {
            return Err(Error::Compute(
                "the crease-preserving solve produced a value that is not a number".into(),
            ));
        }
        converged = largest < options.tol;
    }
    let mut smoothness_energy = 0.0;
    for p in 0..w * h {
        if roles[p] == Role::Outside {
            continue;
        }
        let (c, r) = (p % w, p / w);
        for q in [(c + 1 < w).then(|| p + 1), (r + 1 < h).then(|| p + w)]
            .into_iter()
            .flatten()
        {
            if roles[q] != Role::Outside {
                let d = (f[p] - f[q]).hypot(g[p] - g[q]);
                smoothness_energy += pairs.factor(p, q) * options.smoothness.penalty(d);
            }
        }
    }
    let mut brightness_energy = 0.0;
    for &p in &pairs.unknowns {
        let i = image.data()[p];
        if carries_data(i, ambient, None) {
            let e = i - reflectance.fg(f[p], g[p]).value;
            brightness_energy += e * e;
        }
    }
    Ok(CreaseSolution {
        f: Grid::from_vec(w, h, f)?,
        g: Grid::from_vec(w, h, g)?,
        sweeps,
        converged,
        smoothness_energy,
        brightness_energy,
    })
}

/// The unknowns in row-major order, each with its in-domain 4-neighbours and the factor of
/// each pair's smoothness (1, or 0 for a pair across a column in shadow; see
/// [`CreaseOptions::shadow_along_columns`]), flattened.
struct Pairs {
    /// The unknown pixels.
    unknowns: Vec<usize>,
    /// Where each unknown's pairs start in `pairs` (one more entry than unknowns).
    offsets: Vec<usize>,
    /// (neighbour, factor) of every unknown in turn.
    pairs: Vec<(usize, f64)>,
    /// The image's width.
    width: usize,
    /// Whether each pixel is in attached shadow (only with shadow along columns; else empty).
    shadow: Vec<bool>,
    /// Whether each column holds a fixed pixel (only with shadow along columns).
    anchored: Vec<bool>,
}

impl Pairs {
    /// The pairs of `bc`'s unknowns; with shadow along columns, the pixels the data say
    /// nothing about are those at or below the `ambient` level, or every pixel when λ = 0.
    fn new(image: &Image, bc: &BoundaryConditions, ambient: f64, options: &CreaseOptions) -> Pairs {
        let (w, h) = (bc.roles.width(), bc.roles.height());
        let roles = bc.roles.data();
        let (mut shadow, mut anchored) = (Vec::new(), Vec::new());
        if options.shadow_along_columns {
            anchored = vec![false; w];
            for (p, role) in roles.iter().enumerate() {
                anchored[p % w] |= *role == Role::Fixed;
            }
            let no_data = options.lambda == 0.0;
            shadow = image
                .data()
                .iter()
                .map(|&i| no_data || !carries_data(i, ambient, None))
                .collect();
        }
        let mut pairs = Pairs {
            unknowns: Vec::new(),
            offsets: vec![0],
            pairs: Vec::new(),
            width: w,
            shadow,
            anchored,
        };
        for p in 0..w * h {
            if roles[p] != Role::Unknown {
                continue;
            }
            let (c, r) = (p % w, p / w);
            for q in [
                (c > 0).then(|| p - 1),
                (c + 1 < w).then(|| p + 1),
                (r > 0).then(|| p - w),
                (r + 1 < h).then(|| p + w),
            ]
            .into_iter()
            .flatten()
            {
                if roles[q] != Role::Outside {
                    let factor = pairs.factor(p, q);
                    pairs.pairs.push((q, factor));
                }
            }
            pairs.unknowns.push(p);
            pairs.offsets.push(pairs.pairs.len());
        }
        pairs
    }

    /// The pairs of the `k`-th unknown.
    fn of(&self, k: usize) -> &[(usize, f64)] {
        &self.pairs[self.offsets[k]..self.offsets[k + 1]]
    }

    /// The smoothness factor of the pair of in-domain neighbours `p`, `q`: 0 for side-by-side
    /// neighbours in anchored columns one of which is in shadow (with shadow along columns),
    /// else 1.
    fn factor(&self, p: usize, q: usize) -> f64 {
        let w = self.width;
        if p.abs_diff(q) == 1
            && !self.shadow.is_empty()
            && (self.shadow[p] || self.shadow[q])
            && self.anchored[p % w]
            && self.anchored[q % w]
        {
            0.0
        } else {
            1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::boundary::{boundary_conditions, Boundary};
    use crate::grid::Mask;
    use crate::light::Light;
    use crate::reflectance::Lambertian;
    use nalgebra::Vector3;

    /// A band fixed on its top and bottom rows to a step in f at mid-width (a fold), with no
    /// data: Horn's smoothness spreads the step, Charbonnier keeps it.
    #[test]
    fn charbonnier_keeps_a_fold_that_horn_spreads() {
        let (w, h) = (40, 21);
        let normals = Grid::from_fn(w, h, |c, _| {
            Vector3::new(if c < w / 2 { -0.6 } else { 0.6 }, 0.0, 1.0)
        });
        // Only the top and bottom rows hold the fold; the left and right ends are free.
        let roles = Grid::from_fn(w, h, |_, r| {
            if r == 0 || r == h - 1 {
                Role::Fixed
            } else {
                Role::Unknown
            }
        });
        let fixed = (0..w * h)
            .filter(|&p| p / w == 0 || p / w == h - 1)
            .map(|p| {
                let n = normals.get(p % w, p / w).normalize();
                let (f, g) = crate::gradient_space::fg_from_normal(&n);
                (p, [f, g])
            })
            .collect();
        let bc = BoundaryConditions::from_parts(roles, fixed);
        let light = Lambertian::unit(Light::FRONT);
        let image = Grid::new(w, h, 1.0);
        let jump = |s: Smoothness| {
            let o = CreaseOptions {
                lambda: 0.0,
                smoothness: s,
                tol: 1e-9,
                max_sweeps: 200_000,
                ..CreaseOptions::default()
            };
            let sol = solve(&image, &bc, &light, &o).unwrap();
            assert!(sol.converged);
            let mid = h / 2;
            // The share of the middle row's total change carried by its largest step.
            let row: Vec<f64> = (0..w).map(|c| *sol.f.get(c, mid)).collect();
            let steps: Vec<f64> = row.windows(2).map(|p| (p[1] - p[0]).abs()).collect();
            steps.iter().cloned().fold(0.0, f64::max) / steps.iter().sum::<f64>()
        };
        let horn = jump(Smoothness::Quadratic);
        let tv = jump(Smoothness::Charbonnier { epsilon: 0.01 });
        assert!(horn < 0.3, "Horn's smoothness spreads the fold: {horn}");
        assert!(tv > 0.75, "Charbonnier keeps it: {tv}");
    }

    #[test]
    fn data_consistent_with_the_boundary_is_a_fixed_point() {
        // A tilted plane, its shading exact: starting from (0, 0), the solve recovers it.
        let (w, h) = (12, 10);
        let mask = Mask::new(w, h, true);
        let n = Vector3::new(-0.3, 0.0, 1.0).normalize();
        let bc = boundary_conditions(&mask, &Boundary::Given(Grid::new(w, h, n))).unwrap();
        let light = Lambertian {
            light: Light::from_tilt_slant(90.0, 45.0).unwrap(),
            albedo: 0.8,
            ambient: 0.05,
        };
        let (fv, gv) = crate::gradient_space::fg_from_normal(&n);
        let i = light.fg(fv, gv).value;
        let o = CreaseOptions {
            tol: 1e-12,
            ..CreaseOptions::default()
        };
        let s = solve(&Grid::new(w, h, i), &bc, &light, &o).unwrap();
        assert!(s.converged);
        for v in s.f.data() {
            assert!((v - fv).abs() < 1e-9, "{v} vs {fv}");
        }
        assert!(s.brightness_energy < 1e-18);
    }

    /// A band whose top and bottom rows hold f = 0.8 in its middle third and 0 elsewhere, all
    /// in attached shadow: filled along the columns, each column takes its rows' value
    /// exactly; filled from every side, the middle sags towards its neighbours. Over-relaxed
    /// or not, the sweeps reach the same fixed point.
    #[test]
    fn shadow_along_columns_takes_the_boundary_down_each_column() {
        let (w, h) = (30, 21);
        let roles = Grid::from_fn(w, h, |_, r| {
            if r == 0 || r == h - 1 {
                Role::Fixed
            } else {
                Role::Unknown
            }
        });
        let rim = |c: usize| if (10..20).contains(&c) { 0.8 } else { 0.0 };
        let fixed = (0..w * h)
            .filter(|&p| p / w == 0 || p / w == h - 1)
            .map(|p| (p, [rim(p % w), 0.0]))
            .collect();
        let bc = BoundaryConditions::from_parts(roles, fixed);
        let light = Lambertian {
            light: Light::from_tilt_slant(90.0, 45.0).unwrap(),
            albedo: 0.8,
            ambient: 0.1,
        };
        let image = Grid::new(w, h, 0.1);
        let solve_with = |along: bool, omega: f64| {
            let o = CreaseOptions {
                tol: 1e-12,
                shadow_along_columns: along,
                relaxation: omega,
                ..CreaseOptions::default()
            };
            let s = solve(&image, &bc, &light, &o).unwrap();
            assert!(s.converged);
            s
        };
        let along = solve_with(true, 1.92);
        for r in 0..h {
            for c in 0..w {
                assert!((along.f.get(c, r) - rim(c)).abs() < 1e-9, "({c}, {r})");
            }
        }
        let across = solve_with(false, 1.92);
        assert!(
            *across.f.get(15, h / 2) < 0.7,
            "{}",
            across.f.get(15, h / 2)
        );
        let plain = solve_with(false, 1.0);
        assert!(plain.sweeps > across.sweeps);
        for (a, b) in plain.f.data().iter().zip(across.f.data()) {
            assert!((a - b).abs() < 1e-8, "{a} vs {b}");
        }
    }

    #[test]
    fn bad_options_are_named() {
        let bad = CreaseOptions {
            relaxation: 2.0,
            ..CreaseOptions::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("relaxation"));
        let bad = CreaseOptions {
            smoothness: Smoothness::Charbonnier { epsilon: 0.0 },
            ..CreaseOptions::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("epsilon"));
        let bad = CreaseOptions {
            lambda: -1.0,
            ..CreaseOptions::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("lambda"));
    }
}
