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
//! a Gauss–Seidel sweep (row-major, in place: deterministic, one thread; meant for domains of
//! tens of thousands of pixels) moves each unknown to the weighted neighbour mean (f̄, ḡ) plus
//! the Gauss–Newton step of the brightness term taken there:
//!
//! (f, g) ← (f̄, ḡ) + 4λ (I − R) ∇R / (W + 4λ |∇R|²),  R and ∇R = (∂R/∂f, ∂R/∂g) at (f̄, ḡ),
//!
//! with W the sum of the pixel's weights. For Horn's weights (W = k neighbours) and small ∇R
//! this is Horn's update with its 4λ/k; the |∇R|² in the denominator keeps the step stable for
//! any λ and any W (a pixel whose neighbours are all across folds has a small W). Values stay
//! in the visible disc |(f, g)| ≤ 2. Pixels in attached shadow (I at or below the ambient
//! level) and λ = 0 (pure interpolation of the boundary values) carry smoothness only. The
//! sweeps stop when no f or g changes by more than the tolerance.

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
    /// use shadelab::solver::crease::Smoothness;
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
        match self {
            Smoothness::Quadratic => 1.0,
            Smoothness::Charbonnier { epsilon: e } => e / (d * d + e * e).sqrt(),
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
}

impl Default for CreaseOptions {
    /// λ = 1, Charbonnier with ε = 0.02, tolerance 10⁻⁶, at most 20 000 sweeps.
    fn default() -> Self {
        CreaseOptions {
            lambda: 1.0,
            smoothness: Smoothness::Charbonnier { epsilon: 0.02 },
            tol: 1e-6,
            max_sweeps: 20_000,
        }
    }
}

impl CreaseOptions {
    /// Checks every parameter, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.lambda.is_finite() && self.lambda >= 0.0) {
            return Err(Error::invalid(format!(
                "lambda = {} must be a number ≥ 0",
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
/// Fails on an image of another size than the domain, a light not in front of the surface,
/// bad options, or a value that is not a number (from a non-finite brightness).
///
/// ```
/// use shadelab::boundary::{boundary_conditions, Boundary};
/// use shadelab::grid::{Grid, Mask};
/// use shadelab::light::Light;
/// use shadelab::reflectance::Lambertian;
/// use shadelab::solver::crease::{solve, CreaseOptions};
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
    options.validate()?;
    let (w, h) = (bc.roles.width(), bc.roles.height());
    if (image.width(), image.height()) != (w, h) {
        return Err(Error::invalid(format!(
            "image is {}x{} but the domain is {w}x{h}",
            image.width(),
            image.height()
        )));
    }
    crate::reconstruct::check_light_in_front(&reflectance.light())?;
    let roles = bc.roles.data();
    let mut f = vec![0.0; w * h];
    let mut g = vec![0.0; w * h];
    for &(i, [fv, gv]) in bc.fixed_values() {
        f[i] = fv;
        g[i] = gv;
    }
    // Each unknown with its in-domain neighbours, in row-major order.
    let unknowns: Vec<(usize, Vec<usize>)> = (0..w * h)
        .filter(|&p| roles[p] == Role::Unknown)
        .map(|p| (p, neighbours(p, w, h, roles)))
        .collect();
    let ambient = reflectance.ambient();
    let four_lambda = 4.0 * options.lambda;
    let mut sweeps = 0;
    let mut converged = unknowns.is_empty();
    while !converged && sweeps < options.max_sweeps && !crate::cancel::requested() {
        let mut largest: f64 = 0.0;
        for (p, nbs) in &unknowns {
            let p = *p;
            let (f0, g0) = (f[p], g[p]);
            let (mut sw, mut sf, mut sg) = (0.0, 0.0, 0.0);
            for &q in nbs {
                let d = (f0 - f[q]).hypot(g0 - g[q]);
                let wt = options.smoothness.weight(d);
                sw += wt;
                sf += wt * f[q];
                sg += wt * g[q];
            }
            if sw <= 0.0 {
                continue;
            }
            let (mut fn_, mut gn) = (sf / sw, sg / sw);
            let intensity = image.data()[p];
            if four_lambda > 0.0 && intensity > ambient {
                let s = reflectance.fg(fn_, gn);
                let k = four_lambda * (intensity - s.value)
                    / (sw + four_lambda * (s.d1 * s.d1 + s.d2 * s.d2));
                fn_ += k * s.d1;
                gn += k * s.d2;
            }
            let r = fn_.hypot(gn);
            if r > FG_RADIUS {
                fn_ *= FG_RADIUS / r;
                gn *= FG_RADIUS / r;
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
                smoothness_energy += options.smoothness.penalty(d);
            }
        }
    }
    let mut brightness_energy = 0.0;
    for (p, _) in &unknowns {
        let i = image.data()[*p];
        if i > ambient {
            let e = i - reflectance.fg(f[*p], g[*p]).value;
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

/// The 4-neighbours of pixel `p` inside the domain (unknown or fixed).
fn neighbours(p: usize, w: usize, h: usize, roles: &[Role]) -> Vec<usize> {
    let (c, r) = (p % w, p / w);
    [
        (c > 0).then(|| p - 1),
        (c + 1 < w).then(|| p + 1),
        (r > 0).then(|| p - w),
        (r + 1 < h).then(|| p + w),
    ]
    .into_iter()
    .flatten()
    .filter(|&q| roles[q] != Role::Outside)
    .collect()
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

    #[test]
    fn bad_options_are_named() {
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
