//! The Ikeuchi–Horn shape-from-shading iteration in f–g space.
//!
//! Minimises e = e_S + λ·e_R over the unknown pixels of a [`BoundaryConditions`] domain, where
//! e_S = ¼ Σ [(Δf)² + (Δg)²] over the 4-neighbour pairs inside the mask (Horn's discrete
//! smoothness term; the ¼ makes λ mean what it means in Horn's update below) and
//! e_R = Σ (I − R(f, g))² over the unknown pixels that are lit.
//!
//! Each sweep moves every unknown pixel, simultaneously (Jacobi), to
//!
//! f ← f̄ + λ·(4/k)·(I − R)·∂R/∂f,  g ← ḡ + λ·(4/k)·(I − R)·∂R/∂g,
//!
//! with f̄, ḡ the mean over its k neighbours in the domain (k = 4 inside; fewer where the domain
//! has a free edge, which is the natural boundary condition). [`Method::Jacobi`] evaluates R
//! and its derivatives at (f̄, ḡ), as in Horn's *Robot Vision*: a checkerboard error is averaged
//! away before R sees it, and the sweep is stable while λ·R_f² < 2. [`Method::Literal`]
//! evaluates them at the pixel's current (f, g), as the update is often printed; there the
//! checkerboard mode is multiplied by about 1 + λ·R_f² every sweep and the iteration blows up.
//!
//! Pixels in attached shadow (I at or below the reflectance map's ambient level) say nothing
//! about their orientation and carry smoothness only; so do clipped pixels (I at or above
//! [`SolveOptions::saturation`], where the image was saturated and the true brightness is
//! unknown). [`carries_data`] is that rule, for every method. Unknown pixels start at (0, 0), facing
//! the viewer. The iteration stops when the largest change of f or g in a sweep falls below
//! the tolerance, or after the maximum number of sweeps.
//!
//! Jacobi needs a number of sweeps that grows with the square of the image side (thousands at
//! 256²). [`Method::Multigrid`], the default, reaches the same fixed point — it relaxes the very
//! equations whose solution the Jacobi sweep leaves unchanged, with coarse grids to remove the
//! smooth part of the error — in a handful of cycles whatever the size (see `multigrid.rs`).
//! Its tolerance means the same: it stops when the next Jacobi sweep would change no f or g by
//! more than `tol`.

use crate::boundary::{
    boundary_conditions, limb_conditions, Boundary, BoundaryConditions, LimbTest, Role,
};
use crate::error::{Error, Result};
use crate::gradient_space::{normal_from_fg, Normal};
use crate::grid::{Grid, Image, Mask};
use crate::parallel::prelude::*;
use crate::reflectance::ReflectanceMap;
use std::fmt;
use std::str::FromStr;

/// How the equations are iterated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// Multigrid (the default): the fixed point of [`Method::Jacobi`] in a few cycles, with
    /// work proportional to the number of pixels.
    #[default]
    Multigrid,
    /// Jacobi sweeps with R, ∂R/∂f, ∂R/∂g at the neighbour average (f̄, ḡ): stable, and slow.
    Jacobi,
    /// R, ∂R/∂f, ∂R/∂g at the current (f, g): the form often printed, which is unstable; kept
    /// to demonstrate that.
    Literal,
    /// Gradients and depth solved together (Horn 1990, "Height and gradient from shading"),
    /// from the multigrid solution: the normals become those of one surface
    /// (`integrable.rs`).
    Integrable,
    /// The integrable method's energy minimised itself, gradients and depth moved together by
    /// Levenberg–Marquardt steps (`integrable/newton.rs`), from the multigrid solution: slower
    /// than [`Method::Integrable`]'s alternation, which settles where its two steps balance
    /// rather than at a minimum of the energy, and closer to the truth on the folded objects
    /// of the evaluation.
    IntegrableLm,
    /// The integrable method's energy minimised as [`Method::IntegrableLm`] minimises it, by
    /// nested iteration: on a pyramid of half-size grids, coarsest first, each finer grid
    /// starting from the minimum its coarser grid found (`nested.rs`).
    NestedLm,
}

impl Method {
    /// The method of `shadelab solve` and `shadelab eval` (and of Python's `solve` and
    /// `evaluate`) when none is asked: nested-lm, the integrable answer (within 0.1° of
    /// integrable-lm's minimum on the bench sphere; 1.3° at 256² against multigrid's 6.5°) at
    /// about 50–150× the multigrid solve. The analyses and the teaching page keep
    /// [`Method::default`] (multigrid, docs/perception.md says why); a user who wants the fast
    /// answer asks for multigrid.
    pub const SOLVE_DEFAULT: Method = Method::NestedLm;

    /// The method to run and why: the one asked, or [`Method::SOLVE_DEFAULT`].
    pub fn chosen(asked: Option<Method>) -> (Method, MethodSource) {
        match asked {
            Some(m) => (m, MethodSource::Asked),
            None => (Method::SOLVE_DEFAULT, MethodSource::Default),
        }
    }
}

/// Why a solve ran the method it ran, as its report records it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum MethodSource {
    /// No method was asked: [`Method::SOLVE_DEFAULT`].
    #[default]
    Default,
    /// The user named it (`--method`, Python's `method=`).
    Asked,
}

/// The names of the methods, as `--method` spells them.
pub const METHOD_NAMES: &[&str] = &[
    "multigrid",
    "jacobi",
    "literal",
    "integrable",
    "integrable-lm",
    "nested-lm",
];

impl FromStr for Method {
    type Err = Error;
    fn from_str(name: &str) -> Result<Self> {
        match name {
            "multigrid" => Ok(Method::Multigrid),
            "jacobi" => Ok(Method::Jacobi),
            "literal" => Ok(Method::Literal),
            "integrable" => Ok(Method::Integrable),
            "integrable-lm" => Ok(Method::IntegrableLm),
            "nested-lm" => Ok(Method::NestedLm),
            other => Err(Error::unknown("solver method", other, METHOD_NAMES)),
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Method::Multigrid => "multigrid",
            Method::Jacobi => "jacobi",
            Method::Literal => "literal",
            Method::Integrable => "integrable",
            Method::IntegrableLm => "integrable-lm",
            Method::NestedLm => "nested-lm",
        })
    }
}

/// The parameters of a solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveOptions {
    /// Weight λ of the brightness term (> 0). Larger trusts the image more; the Jacobi sweep
    /// needs λ·R_f² < 2, about λ < 2 for a Lambertian surface of albedo 1.
    pub lambda: f64,
    /// Stop when the largest change of f or g in a sweep is below this (> 0); for multigrid,
    /// when the next Jacobi sweep would change none by this much.
    pub tol: f64,
    /// Stop after this many sweeps, or cycles for multigrid (≥ 1).
    pub max_iter: usize,
    /// How the equations are iterated.
    pub method: Method,
    /// The brightness at which the image was clipped (saturated): pixels at or above it carry
    /// no data term, as pixels in attached shadow do not (their true brightness is unknown);
    /// `None` (the default): no pixel is clipped. In the image's units (> 0).
    pub saturation: Option<f64>,
}

impl Method {
    /// The default cap of this method's iterations: [`MULTIGRID_MAX_CYCLES`] cycles for
    /// multigrid, [`JACOBI_MAX_SWEEPS`] sweeps for Jacobi and the literal update,
    /// [`INTEGRABLE_MAX_ITER`] iterations (depth solves) for the integrable method,
    /// [`INTEGRABLE_LM_MAX_STEPS`] steps for its Levenberg–Marquardt minimisation. The one
    /// place these caps are decided.
    pub const fn default_max_iter(self) -> usize {
        match self {
            Method::Multigrid => MULTIGRID_MAX_CYCLES,
            Method::Jacobi | Method::Literal => JACOBI_MAX_SWEEPS,
            Method::Integrable => INTEGRABLE_MAX_ITER,
            Method::IntegrableLm | Method::NestedLm => INTEGRABLE_LM_MAX_STEPS,
        }
    }

    /// The default tolerance of this method (the largest change of f or g at which it stops):
    /// 10⁻⁶ for all but nested-lm, whose finest grid stops at [`FINEST_TOL`] (its
    /// cheapest schedule that keeps integrable-lm's accuracy; a smaller `tol` polishes
    /// further). The one place these defaults are decided.
    pub const fn default_tol(self) -> f64 {
        match self {
            Method::NestedLm => FINEST_TOL,
            _ => DEFAULT_TOL,
        }
    }

    /// What one iteration of this method is called: `cycles` for multigrid, `iterations` for
    /// the integrable method (one depth solve and its gradient sweeps), `steps` for
    /// integrable-lm (one accepted Levenberg–Marquardt step), `sweeps` else.
    pub const fn iteration_unit(self) -> &'static str {
        match self {
            Method::Multigrid => "cycles",
            Method::Jacobi | Method::Literal => "sweeps",
            Method::Integrable => "iterations",
            Method::IntegrableLm | Method::NestedLm => "steps",
        }
    }
}

/// The tolerance every method but nested-lm stops at by default ([`Method::default_tol`]).
pub const DEFAULT_TOL: f64 = 1e-6;

/// The smoothness weights λ accepted (both ends included): the multigrid solve converges
/// across it on the rendered sphere and vase (tests/solve.rs); Jacobi sweeps are stable only
/// for the smaller λ of it (about λ ≤ 1 at 128², see docs/reliability.md) and fail with a
/// divergence error above. Beyond it the answer is either the data alone or smoothness alone.
pub const LAMBDA_RANGE: (f64, f64) = (1e-3, 1e3);

/// The stopping tolerances accepted: below 10⁻¹² a solve in f64 cannot get there; above 0.1
/// it stops before it has moved.
pub const TOL_RANGE: (f64, f64) = (1e-12, 0.1);

/// The largest iteration cap accepted.
pub const MAX_ITER_LIMIT: usize = 10_000_000;

/// A last update or value beyond this magnitude is a solve that blew up, never an answer.
pub const BLOWN_UP: f64 = 1e30;

impl Default for SolveOptions {
    /// Multigrid, λ = 1, tolerance 10⁻⁶, at most [`MULTIGRID_MAX_CYCLES`] cycles.
    fn default() -> Self {
        SolveOptions::for_method(Method::default())
    }
}

impl SolveOptions {
    /// The defaults (λ = 1, tolerance 10⁻⁶) for `method`, with its default cap
    /// ([`Method::default_max_iter`]).
    ///
    /// ```
    /// use shadelab::{Method, SolveOptions};
    /// assert_eq!(SolveOptions::for_method(Method::Multigrid).max_iter, 1_000);
    /// assert_eq!(SolveOptions::for_method(Method::Jacobi).max_iter, 100_000);
    /// assert_eq!(SolveOptions::default(), SolveOptions::for_method(Method::Multigrid));
    /// ```
    pub const fn for_method(method: Method) -> SolveOptions {
        SolveOptions {
            lambda: 1.0,
            tol: method.default_tol(),
            max_iter: method.default_max_iter(),
            method,
            saturation: None,
        }
    }

    /// Checks every parameter, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        let (lo, hi) = LAMBDA_RANGE;
        if !(self.lambda.is_finite() && (lo..=hi).contains(&self.lambda)) {
            return Err(Error::invalid(format!(
                "lambda = {:e} is outside {lo:e}..{hi:e}, the range in which the solvers are \
                 checked to converge",
                self.lambda
            )));
        }
        let (lo, hi) = TOL_RANGE;
        if !(self.tol.is_finite() && (lo..=hi).contains(&self.tol)) {
            return Err(Error::invalid(format!(
                "tol = {:e} is outside {lo:e}..{hi:e} (the largest change of f or g, or the \
                 residual, at which a solve stops)",
                self.tol
            )));
        }
        if !(1..=MAX_ITER_LIMIT).contains(&self.max_iter) {
            return Err(Error::invalid(format!(
                "max_iter = {} is outside 1..{MAX_ITER_LIMIT}",
                self.max_iter
            )));
        }
        if let Some(level) = self.saturation {
            if !(level.is_finite() && level > 0.0) {
                return Err(Error::invalid(format!(
                    "the saturation level {level} must be a positive number"
                )));
            }
        }
        Ok(())
    }
}

/// Whether a pixel of brightness `intensity` carries a data term: it is lit (above the
/// reflectance map's `ambient` level: attached shadow says nothing about the orientation) and
/// not clipped (below the `saturation` level, where one is given: the true brightness of a
/// clipped pixel is unknown). The one rule of every method (Jacobi, multigrid, the energy
/// descent, the integrable method); the others carry smoothness only.
///
/// ```
/// use shadelab_engine::solver::carries_data;
/// assert!(carries_data(0.5, 0.0, None));
/// assert!(!carries_data(0.0, 0.0, None)); // attached shadow
/// assert!(!carries_data(0.9, 0.0, Some(0.9))); // clipped
/// assert!(carries_data(0.89, 0.0, Some(0.9)));
/// ```
pub fn carries_data(intensity: f64, ambient: f64, saturation: Option<f64>) -> bool {
    intensity > ambient && saturation.map_or(true, |level| intensity < level)
}

/// The pixels of `mask` that `saturation` leaves out of the data term as clipped (at or above
/// the level; none without one).
pub fn clipped_pixels(image: &Image, mask: &Mask, saturation: Option<f64>) -> usize {
    let Some(level) = saturation else { return 0 };
    image
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(v, &m)| m && **v >= level)
        .count()
}

/// [`carries_data`] for one solve: the reflectance map's ambient level and the options'
/// saturation level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DataRange {
    ambient: f64,
    saturation: Option<f64>,
}

impl DataRange {
    /// The range of `reflectance` (its ambient level) and `saturation`.
    pub(crate) fn new(reflectance: &dyn ReflectanceMap, saturation: Option<f64>) -> DataRange {
        DataRange {
            ambient: reflectance.ambient(),
            saturation,
        }
    }

    /// Whether a pixel of brightness `intensity` carries a data term ([`carries_data`]).
    pub(crate) fn carries(&self, intensity: f64) -> bool {
        carries_data(intensity, self.ambient, self.saturation)
    }
}

/// Where a running solve stands; passed to the progress callback after every sweep (every
/// cycle for multigrid).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Sweeps (cycles) done.
    pub iteration: usize,
    /// The most sweeps (cycles) the solve will do.
    pub max_iter: usize,
    /// The largest change of f or g in the last sweep (for multigrid: that the next Jacobi
    /// sweep would make).
    pub last_update: f64,
    /// The energy e_S + λ·e_R after the step, where it is computed: after each step of the
    /// globalisation (`globalize.rs`), not after multigrid cycles or sweeps.
    pub energy: Option<f64>,
    /// The grid the step was taken on: 0 for the image's own, l for [`Method::NestedLm`]'s
    /// grid of 2^l times fewer pixels a side (its coarser grids report their steps too).
    pub level: usize,
    /// The seconds the whole solve has left, estimated from the time its steps took so far
    /// (`estimate.rs`): with every step of [`Method::IntegrableLm`], [`Method::NestedLm`] and
    /// [`Method::Integrable`]; `None` for the other methods, quick enough without.
    pub seconds_left: Option<f64>,
}

/// The result of a solve.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Stereographic f at every pixel (0 outside the mask).
    pub f: Image,
    /// Stereographic g at every pixel (0 outside the mask).
    pub g: Image,
    /// Sweeps done (cycles for multigrid).
    pub iterations: usize,
    /// Whether the last update fell below the tolerance.
    pub converged: bool,
    /// Whether the iteration blew up (an update larger than [`DIVERGENCE_UPDATE`], or not a
    /// number); the values are then meaningless.
    pub diverged: bool,
    /// The smoothness term e_S at the end.
    pub smoothness_energy: f64,
    /// The brightness term e_R at the end.
    pub brightness_energy: f64,
    /// The largest change of f or g in the last sweep (for multigrid: that the next Jacobi
    /// sweep would make from the values returned).
    pub last_update: f64,
    /// The number of unknown pixels.
    pub unknowns: usize,
    /// Whether the multigrid cycles stalled or blew up and the energy descent of
    /// `globalize.rs` finished the solve: the answer is then the energy's stationary point
    /// (R read at the pixel), not Jacobi's fixed point, and `converged` and `last_update`
    /// are the descent's.
    pub globalised: bool,
    /// The energy e_S + λ·e_R after each step of the energy descent (empty when the cycles
    /// converged alone); never increasing.
    pub energy_history: Vec<f64>,
    /// With [`Boundary::Limb`]: what the limb test found (the occluding pixels whose
    /// brightness ruled out a limb, and the dark level it allowed for); `None` for every
    /// other boundary.
    pub limb: Option<LimbTest>,
}

impl Solution {
    /// The unit normal at pixel (`col`, `row`) from its (f, g); (0, 0, 1) outside the mask,
    /// where f = g = 0.
    pub fn normal(&self, col: usize, row: usize) -> Normal {
        normal_from_fg(*self.f.get(col, row), *self.g.get(col, row))
    }

    /// The unit normals of every pixel (see [`Solution::normal`]). Computed on demand rather
    /// than kept: 24 bytes per pixel that a large solve need not hold while it runs.
    pub fn normals(&self) -> Grid<Normal> {
        Grid::from_fn(self.f.width(), self.f.height(), |c, r| self.normal(c, r))
    }
}

/// The default cap on multigrid cycles: a solve settles in tens of cycles, and one that has
/// not after a thousand will not; a cycle costs a few sweeps, so the cap is far below Jacobi's
/// [`JACOBI_MAX_SWEEPS`].
pub const MULTIGRID_MAX_CYCLES: usize = 1_000;

/// The default cap on Jacobi (and literal) sweeps: their count grows with the square of the
/// image side, thousands at 256².
pub const JACOBI_MAX_SWEEPS: usize = 100_000;

/// A change of f or g larger than this in one sweep means the iteration has blown up: the
/// whole visible hemisphere spans |(f, g)| ≤ 2, and a stable sweep moves a pixel by less than
/// its distance to the neighbour average.
pub const DIVERGENCE_UPDATE: f64 = 8.0;

/// Unknowns per parallel work item. Fixed, so the work split (and the result) does not depend
/// on the number of threads.
const CHUNK: usize = 4096;

/// Below this many unknowns a sweep runs on one thread: the split costs more than it saves.
const PARALLEL_MIN: usize = 32_768;

/// One unknown pixel: where its neighbours' values are, and its data term.
#[derive(Debug, Clone, Copy)]
struct Node {
    /// Value slots of the 4 neighbours; missing neighbours point at the slot that holds 0.
    neighbours: [u32; 4],
    /// 1/k for k neighbours in the domain (0 for an isolated pixel, which stays at (0, 0)).
    inv_k: f64,
    /// λ·4/k for pixels with a data term ([`carries_data`]), 0 in attached shadow or clipped.
    data_weight: f64,
    /// The image brightness.
    intensity: f64,
}

/// One problem on a domain already built: the image, its boundary conditions and the
/// reflectance map, which every solver's entry point takes together (sizes checked by
/// [`Solver::solve_with_progress`]).
#[derive(Clone, Copy)]
pub(crate) struct Posed<'a> {
    pub(crate) image: &'a Image,
    pub(crate) bc: &'a BoundaryConditions,
    pub(crate) reflectance: &'a dyn ReflectanceMap,
}

impl<'a> Posed<'a> {
    /// The problem of `image` on `bc` under `reflectance`.
    pub(crate) fn new(
        image: &'a Image,
        bc: &'a BoundaryConditions,
        reflectance: &'a dyn ReflectanceMap,
    ) -> Posed<'a> {
        Posed {
            image,
            bc,
            reflectance,
        }
    }
}

/// An Ikeuchi–Horn solver for images of one size; its buffers are allocated once and reused
/// by every [`Solver::solve`].
#[derive(Debug, Clone)]
pub struct Solver {
    width: usize,
    height: usize,
    /// Value slot of each pixel (unknowns first, then fixed pixels, then the zero slot).
    slot: Vec<u32>,
    /// Pixel index of each unknown.
    pixels: Vec<u32>,
    nodes: Vec<Node>,
    cur_f: Vec<f64>,
    cur_g: Vec<f64>,
    next_f: Vec<f64>,
    next_g: Vec<f64>,
    /// The multigrid hierarchy, planned on the first multigrid solve.
    multigrid: Option<multigrid::Multigrid>,
    /// The boundary conditions of the last solve with an occluding boundary, kept for the next
    /// solve of the same mask (its contour fit costs about a tenth of a 256² solve). The
    /// roles are the key: a pixel is outside exactly where the mask is false.
    occluding: Option<BoundaryConditions>,
    /// The saturation level of the solve under way ([`SolveOptions::saturation`]), which
    /// `build` and the energies read.
    saturation: Option<f64>,
}

const NO_SLOT: u32 = u32::MAX;

impl Solver {
    /// A solver for `width` × `height` images.
    pub fn new(width: usize, height: usize) -> Result<Solver> {
        crate::grid::check_size(width, height, crate::grid::DEFAULT_MAX_PIXELS)?;
        let n = width * height;
        if n >= NO_SLOT as usize {
            return Err(Error::invalid(format!(
                "image size {} is too large for the solver",
                crate::message::SizeText::Pixels(height, width)
            )));
        }
        Ok(Solver {
            width,
            height,
            // Filled on the first Jacobi or literal solve: multigrid does not need it.
            slot: Vec::new(),
            // The Jacobi buffers are sized on the first Jacobi or literal solve (and kept for
            // the next), so a multigrid solver never holds them.
            pixels: Vec::new(),
            nodes: Vec::new(),
            cur_f: Vec::new(),
            cur_g: Vec::new(),
            next_f: Vec::new(),
            next_g: Vec::new(),
            multigrid: None,
            occluding: None,
            saturation: None,
        })
    }

    /// Width of the images this solver takes.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height of the images this solver takes.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Recovers surface normals from `image` on `mask` under `reflectance`, with the boundary
    /// condition `boundary`.
    ///
    /// Fails on sizes that differ from the solver's, non-finite brightness, an empty mask or bad
    /// options. The light is the caller's to choose: shape from shading needs one in front of
    /// the surface, a [`FrontLight`](crate::light::FrontLight), made where the light is parsed or
    /// estimated; under a grazing light the answer means nothing.
    pub fn solve(
        &mut self,
        image: &Image,
        mask: &Mask,
        boundary: &Boundary,
        reflectance: &dyn ReflectanceMap,
        options: &SolveOptions,
    ) -> Result<Solution> {
        self.solve_with_progress(image, mask, boundary, reflectance, options, &mut |_| {})
    }

    /// [`Solver::solve`], calling `progress` after every sweep.
    pub fn solve_with_progress(
        &mut self,
        image: &Image,
        mask: &Mask,
        boundary: &Boundary,
        reflectance: &dyn ReflectanceMap,
        options: &SolveOptions,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Solution> {
        options.validate()?;
        self.saturation = options.saturation;
        let (w, h) = (self.width, self.height);
        for (what, gw, gh) in [
            ("image", image.width(), image.height()),
            ("mask", mask.width(), mask.height()),
        ] {
            if (gw, gh) != (w, h) {
                return Err(Error::invalid(format!(
                    "{what} is {} but the solver was made for {}",
                    crate::message::SizeText::Pixels(gh, gw),
                    crate::message::SizeText::Pixels(h, w)
                )));
            }
        }
        if let Some(i) = image.data().iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(format!(
                "image value at column {}, row {} is not a finite number",
                i % w,
                i / w
            )));
        }
        if !matches!(boundary, Boundary::Occluding | Boundary::Limb) {
            let bc = boundary_conditions(mask, boundary)?;
            return self.solve_conditions(Posed::new(image, &bc, reflectance), options, progress);
        }
        let bc = match self.occluding.take() {
            Some(bc) if same_domain(&bc, mask) => bc,
            _ => boundary_conditions(mask, &Boundary::Occluding)?,
        };
        let solution = if *boundary == Boundary::Limb {
            let limb = limb_conditions(&bc, image, reflectance, options.saturation);
            self.solve_conditions(
                Posed::new(image, &limb.conditions, reflectance),
                options,
                progress,
            )
            .map(|solution| Solution {
                limb: Some(limb.test),
                ..solution
            })
        } else {
            self.solve_conditions(Posed::new(image, &bc, reflectance), options, progress)
        };
        self.occluding = Some(bc);
        solution
    }

    /// [`Solver::solve_with_progress`] on a domain already built (checked sizes assumed).
    fn solve_conditions(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        progress: &mut dyn FnMut(&Progress),
    ) -> Result<Solution> {
        let (image, bc, reflectance) = (posed.image, posed.bc, posed.reflectance);
        if matches!(options.method, Method::Integrable | Method::IntegrableLm) {
            return self.solve_integrable(posed, options, progress);
        }
        if options.method == Method::NestedLm {
            return self.solve_nested(posed, options, progress);
        }
        if options.method == Method::Multigrid {
            let (w, h) = (self.width, self.height);
            let mg = self
                .multigrid
                .get_or_insert_with(|| multigrid::Multigrid::new(w, h));
            let (f, g, stats) = mg.solve(posed, options, progress);
            // Stalled or blown up (not stopped by the caller's cap or a cancel): globalise.
            let stalled = stats.cycles < options.max_iter;
            if !stats.converged && (stats.diverged || stalled) && !crate::cancel::requested() {
                return Ok(self.globalise(posed, options, (f, g), &stats, progress));
            }
            return Ok(finish(
                f,
                g,
                image,
                bc,
                DataRange::new(reflectance, options.saturation),
                reflectance,
                SolveStats {
                    iterations: stats.cycles,
                    converged: stats.converged,
                    diverged: stats.diverged,
                    last_update: stats.residual,
                    unknowns: bc.unknown_count(),
                },
            ));
        }
        let n_unknown = self.build(posed, options.lambda);
        let literal = options.method == Method::Literal;
        let stats = iterate(n_unknown, options, progress, |_| {
            let update = self.sweep(n_unknown, reflectance, literal);
            std::mem::swap(&mut self.cur_f, &mut self.next_f);
            std::mem::swap(&mut self.cur_g, &mut self.next_g);
            Ok(update)
        })?;
        Ok(self.solution(posed, stats))
    }

    /// The globalisation (`globalize.rs`) of a multigrid solve that stalled or blew up: the
    /// energy descent from the multigrid solution at λ = 1 when λ is larger (λ continuation),
    /// else from the cycles' last values.
    fn globalise(
        &mut self,
        posed: Posed<'_>,
        options: &SolveOptions,
        values: (Image, Image),
        stats: &multigrid::MultigridStats,
        progress: &mut dyn FnMut(&Progress),
    ) -> Solution {
        let (mut f, mut g) = values;
        if globalize::needs_continuation(options.lambda) {
            let gentle = globalize::continuation_options(options);
            let (w, h) = (self.width, self.height);
            let mg = self
                .multigrid
                .get_or_insert_with(|| multigrid::Multigrid::new(w, h));
            let (cf, cg, start) = mg.solve(posed, &gentle, &mut |_| {});
            (f, g) = if start.diverged {
                (Grid::new(w, h, 0.0), Grid::new(w, h, 0.0))
            } else {
                (cf, cg)
            };
        }
        self.descend(posed, options, (&f, &g), stats.cycles, progress)
    }

    /// Lays out the value slots and the nodes for `bc`; returns the number of unknowns.
    fn build(&mut self, posed: Posed<'_>, lambda: f64) -> usize {
        let (image, bc, reflectance) = (posed.image, posed.bc, posed.reflectance);
        let (w, h) = (self.width, self.height);
        let roles = bc.roles.data();
        self.slot.clear();
        self.slot.resize(w * h, NO_SLOT);
        self.pixels.clear();
        self.nodes.clear();
        self.cur_f.clear();
        self.cur_g.clear();
        for (i, role) in roles.iter().enumerate() {
            if *role == Role::Unknown {
                self.slot[i] = self.pixels.len() as u32;
                self.pixels.push(i as u32);
                self.cur_f.push(0.0);
                self.cur_g.push(0.0);
            }
        }
        let n_unknown = self.pixels.len();
        for &(i, [f, g]) in bc.fixed_values() {
            self.slot[i] = self.cur_f.len() as u32;
            self.cur_f.push(f);
            self.cur_g.push(g);
        }
        let zero = self.cur_f.len() as u32;
        self.cur_f.push(0.0);
        self.cur_g.push(0.0);
        self.next_f.clone_from(&self.cur_f);
        self.next_g.clone_from(&self.cur_g);
        let data = DataRange::new(reflectance, self.saturation);
        for &p in &self.pixels {
            let p = p as usize;
            let (col, row) = (p % w, p / w);
            let mut neighbours = [zero; 4];
            let mut k = 0;
            let candidates = [
                (col > 0).then(|| p - 1),
                (col + 1 < w).then(|| p + 1),
                (row > 0).then(|| p - w),
                (row + 1 < h).then(|| p + w),
            ];
            for q in candidates.into_iter().flatten() {
                if self.slot[q] != NO_SLOT {
                    neighbours[k] = self.slot[q];
                    k += 1;
                }
            }
            let intensity = image.data()[p];
            let (inv_k, data_weight) = if k == 0 {
                (0.0, 0.0)
            } else {
                (
                    1.0 / k as f64,
                    if data.carries(intensity) {
                        lambda * 4.0 / k as f64
                    } else {
                        0.0
                    },
                )
            };
            self.nodes.push(Node {
                neighbours,
                inv_k,
                data_weight,
                intensity,
            });
        }
        n_unknown
    }

    /// One Jacobi sweep from `cur` into `next`; returns the largest change (∞ for NaN).
    fn sweep(&mut self, n_unknown: usize, reflectance: &dyn ReflectanceMap, literal: bool) -> f64 {
        let (cur_f, cur_g) = (&self.cur_f[..], &self.cur_g[..]);
        sweep_chunks(
            &self.nodes,
            &mut self.next_f[..n_unknown],
            &mut self.next_g[..n_unknown],
            |nodes, first, nf, ng| {
                sweep_nodes(nodes, first, cur_f, cur_g, nf, ng, reflectance, literal)
            },
        )
    }

    /// The solution grids and energies from the current values.
    fn solution(&self, posed: Posed<'_>, stats: SolveStats) -> Solution {
        let (image, bc, reflectance) = (posed.image, posed.bc, posed.reflectance);
        let (f, g) = self.current_fg();
        let data = DataRange::new(reflectance, self.saturation);
        finish(f, g, image, bc, data, reflectance, stats)
    }

    /// The current values as (f, g) grids (the fixed pixels' values included, 0 outside the
    /// domain).
    fn current_fg(&self) -> (Image, Image) {
        let (w, h) = (self.width, self.height);
        let value = |i: usize, of: &[f64]| match self.slot[i] {
            NO_SLOT => 0.0,
            s => of[s as usize],
        };
        (
            Grid::from_fn(w, h, |c, r| value(r * w + c, &self.cur_f)),
            Grid::from_fn(w, h, |c, r| value(r * w + c, &self.cur_g)),
        )
    }
}

/// The [`Solution`] for the values `f`, `g`: the normals and both energy terms.
/// Whether `bc` was built from `mask`: its pixels outside are exactly the mask's false ones.
fn same_domain(bc: &BoundaryConditions, mask: &Mask) -> bool {
    bc.roles.same_size(mask)
        && bc
            .roles
            .data()
            .iter()
            .zip(mask.data())
            .all(|(role, &inside)| (*role != Role::Outside) == inside)
}

fn finish(
    f: Image,
    g: Image,
    image: &Image,
    bc: &BoundaryConditions,
    data: DataRange,
    reflectance: &dyn ReflectanceMap,
    stats: SolveStats,
) -> Solution {
    let (w, h) = (f.width(), f.height());
    let inside = |c: usize, r: usize| *bc.roles.get(c, r) != Role::Outside;
    let mut smoothness = 0.0;
    for r in 0..h {
        for c in 0..w {
            if !inside(c, r) {
                continue;
            }
            let (f0, g0) = (*f.get(c, r), *g.get(c, r));
            for (c2, r2) in [(c + 1, r), (c, r + 1)] {
                if c2 < w && r2 < h && inside(c2, r2) {
                    let (df, dg) = (f.get(c2, r2) - f0, g.get(c2, r2) - g0);
                    smoothness += 0.25 * (df * df + dg * dg);
                }
            }
        }
    }
    let mut brightness = 0.0;
    for (p, role) in bc.roles.data().iter().enumerate() {
        if *role == Role::Unknown {
            let i = image.data()[p];
            if data.carries(i) {
                let e = i - reflectance.fg(f.data()[p], g.data()[p]).value;
                brightness += e * e;
            }
        }
    }
    Solution {
        f,
        g,
        iterations: stats.iterations,
        converged: stats.converged,
        diverged: stats.diverged,
        smoothness_energy: smoothness,
        brightness_energy: brightness,
        last_update: stats.last_update,
        unknowns: stats.unknowns,
        globalised: false,
        energy_history: Vec::new(),
        limb: None,
    }
}

/// Runs `step` (given the number of iterations done; it returns the iteration's largest
/// change) until the change falls below the tolerance, `max_iter` iterations, a divergence (a
/// NaN or a change above [`DIVERGENCE_UPDATE`]) or a requested stop ([`crate::cancel`], which
/// the caller turns into an error), reporting each iteration to `progress`.
fn iterate(
    unknowns: usize,
    options: &SolveOptions,
    progress: &mut dyn FnMut(&Progress),
    mut step: impl FnMut(usize) -> Result<f64>,
) -> Result<SolveStats> {
    let mut stats = SolveStats {
        iterations: 0,
        converged: unknowns == 0,
        diverged: false,
        last_update: 0.0,
        unknowns,
    };
    while !stats.converged && stats.iterations < options.max_iter && !crate::cancel::requested() {
        stats.last_update = step(stats.iterations)?;
        stats.iterations += 1;
        progress(&Progress {
            iteration: stats.iterations,
            max_iter: options.max_iter,
            last_update: stats.last_update,
            energy: None,
            level: 0,
            seconds_left: None,
        });
        if stats.last_update.is_nan() || stats.last_update > DIVERGENCE_UPDATE {
            stats.diverged = true;
            break;
        }
        stats.converged = stats.last_update < options.tol;
    }
    Ok(stats)
}

/// Counters of a finished iteration.
struct SolveStats {
    iterations: usize,
    converged: bool,
    diverged: bool,
    last_update: f64,
    unknowns: usize,
}

/// A sweep of `nodes` (the unknowns `0..next_f.len()`) into `next_f`, `next_g`: `update`
/// gets each chunk of nodes with the index of its first unknown and that chunk's slices of the
/// outputs, on the worker threads from [`PARALLEL_MIN`] unknowns, and returns a largest change;
/// the result is the largest of those (max is exact and order-free, so it does not depend on
/// the thread count).
fn sweep_chunks<F>(nodes: &[Node], next_f: &mut [f64], next_g: &mut [f64], update: F) -> f64
where
    F: Fn(&[Node], usize, &mut [f64], &mut [f64]) -> f64 + Sync + Send,
{
    if next_f.len() < PARALLEL_MIN {
        return update(nodes, 0, next_f, next_g);
    }
    crate::parallel::reduce(
        nodes
            .par_chunks(CHUNK)
            .zip(next_f.par_chunks_mut(CHUNK))
            .zip(next_g.par_chunks_mut(CHUNK))
            .enumerate()
            .map(|(chunk, ((nodes, nf), ng))| update(nodes, chunk * CHUNK, nf, ng)),
        0.0,
        f64::max,
    )
}

/// The sweep over `nodes`, the unknowns `first..first + nodes.len()`; writes their new values
/// into `next_f`, `next_g` (indexed from `first`) and returns the largest change.
#[allow(clippy::too_many_arguments)]
fn sweep_nodes(
    nodes: &[Node],
    first: usize,
    cur_f: &[f64],
    cur_g: &[f64],
    next_f: &mut [f64],
    next_g: &mut [f64],
    reflectance: &dyn ReflectanceMap,
    literal: bool,
) -> f64 {
    let mut largest: f64 = 0.0;
    for (j, node) in nodes.iter().enumerate() {
        let [a, b, c, d] = node.neighbours;
        let (a, b, c, d) = (a as usize, b as usize, c as usize, d as usize);
        let f_bar = (cur_f[a] + cur_f[b] + cur_f[c] + cur_f[d]) * node.inv_k;
        let g_bar = (cur_g[a] + cur_g[b] + cur_g[c] + cur_g[d]) * node.inv_k;
        let (f_old, g_old) = (cur_f[first + j], cur_g[first + j]);
        let (mut f_new, mut g_new) = (f_bar, g_bar);
        if node.data_weight != 0.0 {
            let s = if literal {
                reflectance.fg(f_old, g_old)
            } else {
                reflectance.fg(f_bar, g_bar)
            };
            let e = node.data_weight * (node.intensity - s.value);
            f_new += e * s.d1;
            g_new += e * s.d2;
        }
        next_f[j] = f_new;
        next_g[j] = g_new;
        for change in [(f_new - f_old).abs(), (g_new - g_old).abs()] {
            // A NaN must register as a blow-up, not be skipped the way f64::max skips it.
            if change.is_nan() {
                largest = f64::INFINITY;
            } else if change > largest {
                largest = change;
            }
        }
    }
    largest
}

pub mod crease;
mod estimate;
mod globalize;
mod integrable;
mod multigrid;
mod nested;

pub use globalize::STALL_WINDOW;
pub use integrable::{
    ANDERSON_DEPTH, CG_MAX_ITER, CG_TOL, INTEGRABLE_LM_MAX_STEPS, INTEGRABLE_MAX_ITER,
    LM_ANDERSON_DEPTH, MU, SIGMA, SWEEPS,
};
pub use nested::{COARSEST_SIDE, FINEST_TOL, LEVEL_MAX_STEPS, LEVEL_TOL};

#[cfg(test)]
pub(crate) mod tests;
