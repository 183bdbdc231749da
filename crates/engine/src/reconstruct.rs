//! The one reconstruction pipeline: a shaded image, its mask, a reflectance map and a boundary
//! condition → (f, g) by the Ikeuchi–Horn engine → unit normals → depth.
//!
//! A [`Reconstructor`] is planned once for an image size (RustFFT style) and owns the solver's
//! and the integrator's buffers, so the many solves of a prior sweep or a study reuse them. Its
//! [`ReconstructOptions`] carry every policy explicitly: the iteration method and its cap (one
//! default per method, [`Method::default_max_iter`]), what happens when the solve does not
//! converge ([`NonConvergence`]), how depth is integrated ([`DepthMethod`]) and whether it is
//! put to rest on zero (the lowest point of the domain at 0, 0 outside it).
//!
//! The light and albedo may be given or estimated from the image ([`LightAndAlbedo::resolve`]).
//!
//! ```
//! use shadelab::{Boundary, Lambertian, Light, Problem, ReconstructOptions, Reconstructor};
//! use shadelab_engine::render::{render, RenderOptions};
//! use shadelab_engine::surface::sphere;
//!
//! // A sphere lit from the front, reconstructed with an occluding boundary.
//! let surface = sphere(48, 48, 20.0)?;
//! let map = Lambertian { light: Light::FRONT, albedo: 1.0, ambient: 0.0 };
//! let image = render(&surface, &map, &RenderOptions::default()).image;
//! let mut planner = Reconstructor::new(48, 48, ReconstructOptions::default())?;
//! let problem = Problem {
//!     image: &image,
//!     mask: &surface.mask,
//!     boundary: &Boundary::Occluding,
//!     reflectance: &map,
//! };
//! let r = planner.reconstruct(&problem, &shadelab::NoProgress)?;
//! assert!(r.shape.converged());
//! // The centre faces the viewer and is the highest point; the rim rests on zero.
//! let n = r.shape.solution.normal(24, 24);
//! assert!(n.z > 0.99);
//! assert!(*r.depth.depth.get(24, 24) > 0.9 * r.depth.range);
//! # Ok::<(), shadelab::Error>(())
//! ```

use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::grid::{Image, Mask};
use crate::integrate::{
    gradients_from_fg, integrate_owned_gradients, rest_on_zero, FrankotChellappa, PoissonOptions,
    DEFAULT_MIN_NZ,
};
use crate::light::FrontLight;
use crate::light_estimation::{estimate_light_with, LightEstimate, Outline};
use crate::message::{Message, Setting};
use crate::progress::Progress;
use crate::reflectance::ReflectanceMap;
use crate::solver::{Method, Solution, SolveOptions, Solver};
use serde::Serialize;

/// What a solve that does not meet its tolerance within its cap leads to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum NonConvergence {
    /// Keep the values and report it ([`Shape::converged`] is false): `shadelab solve`.
    Report,
    /// Solve again with Jacobi sweeps (the same fixed point, reached more slowly), at most
    /// `max_sweeps`: the analyses, whose interpretations must all have settled to compare.
    FallBackToJacobi {
        /// The cap of the Jacobi solve.
        max_sweeps: usize,
    },
}

/// How the slopes of the recovered normals are integrated to depth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum DepthMethod {
    /// Least squares on the domain alone (masked Poisson, conjugate gradients with a multigrid
    /// preconditioner): silhouettes and the frame are free boundaries.
    Poisson(#[serde(skip)] PoissonOptions),
    /// Frankot–Chellappa over the whole frame (periodic): exact and fast when the slopes vanish
    /// at the frame, as for a relief on a plane (the flat boundary).
    FrankotChellappa,
}

/// Every policy of a reconstruction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReconstructOptions {
    /// How the equations are iterated.
    pub method: Method,
    /// Weight λ of the brightness term (> 0).
    pub lambda: f64,
    /// Stop when the largest update of f or g falls below this (> 0).
    pub tol: f64,
    /// The cap of iterations (cycles for multigrid, sweeps otherwise); `None` is the method's
    /// default, [`Method::default_max_iter`].
    pub max_iter: Option<usize>,
    /// What a solve that does not converge leads to.
    pub non_convergence: NonConvergence,
    /// How depth is integrated.
    pub depth: DepthMethod,
    /// The smallest n_z used when turning normals into slopes (caps the slope at the limb).
    pub min_nz: f64,
    /// Put the lowest point of the domain at depth 0 and everything outside it at 0 (`true`),
    /// or keep the integrator's own offset (`false`: the analyses read only depth differences).
    pub rest_on_zero: bool,
    /// The level at or above which pixels are clipped and carry no data term
    /// ([`SolveOptions::saturation`]); `None`: none.
    pub saturation: Option<f64>,
}

/// The cap of multigrid cycles an analysis spends on one solve before falling back to Jacobi:
/// multigrid settles in a handful of cycles when it settles at all.
pub const ANALYSIS_MULTIGRID_CYCLES: usize = 40;

/// The cap of the analyses' Jacobi fallback.
pub const ANALYSIS_JACOBI_SWEEPS: usize = 200_000;

impl Default for ReconstructOptions {
    /// The fast policy (`shadelab solve --method multigrid`): multigrid, λ = 1, tolerance
    /// 10⁻⁶, the method's default cap, non-convergence reported, masked Poisson integration.
    /// `shadelab solve`'s own default is [`ReconstructOptions::for_solve`].
    fn default() -> Self {
        ReconstructOptions::from_solve(&SolveOptions::default(), NonConvergence::Report)
    }
}

impl ReconstructOptions {
    /// `shadelab solve`'s and `eval`'s policy: [`Method::SOLVE_DEFAULT`] with its default
    /// tolerance and cap, λ = 1, non-convergence reported, masked Poisson integration.
    pub fn for_solve() -> Self {
        ReconstructOptions::from_solve(
            &SolveOptions::for_method(Method::SOLVE_DEFAULT),
            NonConvergence::Report,
        )
    }

    /// The analyses' policy: at most [`ANALYSIS_MULTIGRID_CYCLES`] multigrid cycles, then
    /// Jacobi (at most [`ANALYSIS_JACOBI_SWEEPS`]) when multigrid has not settled.
    pub fn for_analysis() -> Self {
        ReconstructOptions {
            max_iter: Some(ANALYSIS_MULTIGRID_CYCLES),
            non_convergence: NonConvergence::FallBackToJacobi {
                max_sweeps: ANALYSIS_JACOBI_SWEEPS,
            },
            rest_on_zero: false,
            ..ReconstructOptions::default()
        }
    }

    /// The policy with the solver settings of `solve` (its cap taken as given).
    pub fn from_solve(solve: &SolveOptions, non_convergence: NonConvergence) -> Self {
        ReconstructOptions {
            method: solve.method,
            lambda: solve.lambda,
            tol: solve.tol,
            max_iter: Some(solve.max_iter),
            non_convergence,
            depth: DepthMethod::Poisson(PoissonOptions::default()),
            min_nz: DEFAULT_MIN_NZ,
            rest_on_zero: true,
            saturation: solve.saturation,
        }
    }

    /// The cap of iterations in force: the given one or the method's default.
    pub fn max_iter(&self) -> usize {
        self.max_iter
            .unwrap_or_else(|| self.method.default_max_iter())
    }

    /// The solver's settings.
    pub fn solve_options(&self) -> SolveOptions {
        SolveOptions {
            lambda: self.lambda,
            tol: self.tol,
            max_iter: self.max_iter(),
            method: self.method,
            saturation: self.saturation,
        }
    }

    /// Checks every value, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        self.solve_options().validate()?;
        if let NonConvergence::FallBackToJacobi { max_sweeps: 0 } = self.non_convergence {
            return Err(Error::invalid("the Jacobi fallback needs at least 1 sweep"));
        }
        if !(self.min_nz.is_finite() && self.min_nz > 0.0 && self.min_nz <= 1.0) {
            return Err(Error::invalid(format!(
                "min_nz = {} must be in (0, 1]",
                self.min_nz
            )));
        }
        Ok(())
    }
}

/// The light and albedo a reconstruction assumes, and the estimate they came from if any.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightAndAlbedo {
    /// The light, in front of the surface.
    pub light: FrontLight,
    /// The albedo.
    pub albedo: f64,
    /// The estimate, when the light was estimated from the image.
    pub estimate: Option<LightEstimate>,
}

impl LightAndAlbedo {
    /// The light `given`, or (with `None`) the one estimated from `image` on `mask`; the albedo
    /// `albedo`, or the estimate's when the light is estimated, or 1. With the occluding
    /// `boundary` the mask's outline is taken as the limb and the estimate fits the brightness
    /// there ([`crate::light_estimation::EstimateMethod::LimbBand`] or
    /// [`crate::light_estimation::EstimateMethod::Limb`], where the outline is long enough);
    /// with any other, the interior statistics.
    ///
    /// Fails when the albedo is not a positive number or the estimate fails.
    pub fn resolve(
        given: Option<FrontLight>,
        albedo: Option<f64>,
        image: &Image,
        mask: &Mask,
        boundary: &Boundary,
    ) -> Result<LightAndAlbedo> {
        if let Some(a) = albedo {
            check_albedo(a)?;
        }
        let outline = match boundary {
            // The limb condition reads the same outline; only what it fixes there differs.
            Boundary::Occluding | Boundary::Limb => Outline::Occluding,
            _ => Outline::Unknown,
        };
        let estimate = match given {
            Some(_) => None,
            None => Some(estimate_light_with(image, mask, outline)?),
        };
        let light = match (given, &estimate) {
            (Some(l), _) => l,
            (None, Some(e)) => e.light,
            (None, None) => return Err(Error::invalid("no light given or estimated")),
        };
        let albedo = match (albedo, &estimate) {
            (Some(a), _) => a,
            (None, Some(e)) => e.albedo,
            (None, None) => 1.0,
        };
        Ok(LightAndAlbedo {
            light,
            albedo,
            estimate,
        })
    }
}

/// Fails unless `albedo` is a positive number.
pub fn check_albedo(albedo: f64) -> Result<()> {
    if albedo.is_finite() && albedo > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(format!(
            "albedo {albedo} must be a positive number"
        )))
    }
}

/// What a reconstruction is asked: the picture, where to solve, the condition at the domain's
/// rim and the reflectance map (light and albedo included).
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    /// The brightness (linear, in the reflectance map's units).
    pub image: &'a Image,
    /// Where the surface is solved for.
    pub mask: &'a Mask,
    /// The boundary condition at the mask's rim.
    pub boundary: &'a Boundary,
    /// The reflectance map R(f, g) assumed.
    pub reflectance: &'a dyn ReflectanceMap,
}

impl std::fmt::Debug for Problem<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Problem")
            .field("size", &(self.image.width(), self.image.height()))
            .field("mask_pixels", &self.mask.count())
            .field("boundary", &self.boundary.name())
            .finish_non_exhaustive()
    }
}

/// The solved shape: the solver's (f, g) with how it was reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// The solver's answer (f, g, energies, iterations, last update).
    pub solution: Solution,
    /// The method whose answer this is: the configured one, or Jacobi after a fallback.
    pub method: Method,
    /// Whether the configured method did not converge and Jacobi was run instead.
    pub fell_back: bool,
    /// The largest update after each iteration of the solve whose answer this is.
    pub history: Vec<f64>,
    /// The cap that solve ran under.
    pub max_iter: usize,
}

impl Shape {
    /// Whether the solve met its tolerance.
    pub fn converged(&self) -> bool {
        self.solution.converged
    }
}

/// The integrated depth and how the integration went.
#[derive(Debug, Clone, PartialEq)]
pub struct Depth {
    /// Depth toward the viewer in pixels: the lowest point of the domain at 0, 0 outside it.
    pub depth: Image,
    /// The depth range over the domain (with resting on zero: the highest point's height).
    pub range: f64,
    /// How it was integrated, with the iterative integrator's numbers.
    pub report: IntegrationReport,
}

/// How an integration went.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct IntegrationReport {
    /// Conjugate-gradient iterations (0 for Frankot–Chellappa).
    pub iterations: usize,
    /// The final relative residual (0 for Frankot–Chellappa).
    pub relative_residual: f64,
    /// Whether the iteration met its tolerance (always for Frankot–Chellappa).
    pub converged: bool,
}

/// A whole reconstruction.
#[derive(Debug, Clone, PartialEq)]
pub struct Reconstruction {
    /// The solved (f, g).
    pub shape: Shape,
    /// The depth.
    pub depth: Depth,
}

impl Reconstruction {
    /// The recovered unit normals.
    pub fn normals(&self) -> crate::grid::Grid<crate::gradient_space::Normal> {
        self.shape.solution.normals()
    }
}

impl Problem<'_> {
    /// Reconstructs this problem once: plans a [`Reconstructor`] for the image's size with
    /// `options` and runs it (plan one and reuse it to reconstruct many images of a size).
    pub fn reconstruct(
        &self,
        options: ReconstructOptions,
        progress: &dyn Progress,
    ) -> Result<Reconstruction> {
        Reconstructor::new(self.image.width(), self.image.height(), options)?
            .reconstruct(self, progress)
    }
}

/// What a step of a long solve says beside its estimate of the time left: the grid it is on
/// (a nested solve's coarser grids count from the image's, 0), the step and its change.
fn step_message(p: &crate::solver::Progress) -> String {
    let grid = if p.level > 0 {
        format!("coarse grid 1/{} side, ", 1 << p.level)
    } else {
        String::new()
    };
    format!(
        "solving ({grid}step {}, last update {:.2e})",
        p.iteration, p.last_update
    )
}

/// The reconstruction planner for one image size: the solver and the integrator, planned once
/// and reused by every reconstruction.
#[derive(Debug)]
pub struct Reconstructor {
    solver: Solver,
    fourier: Option<FrankotChellappa>,
    options: ReconstructOptions,
}

impl Reconstructor {
    /// A planner for `width` × `height` images with `options` (checked).
    pub fn new(width: usize, height: usize, options: ReconstructOptions) -> Result<Self> {
        options.validate()?;
        let fourier = match options.depth {
            DepthMethod::FrankotChellappa => Some(FrankotChellappa::new(width, height)?),
            DepthMethod::Poisson(_) => None,
        };
        Ok(Reconstructor {
            solver: Solver::new(width, height)?,
            fourier,
            options,
        })
    }

    /// The policy in force.
    pub fn options(&self) -> &ReconstructOptions {
        &self.options
    }

    /// Frees the solver's buffers (the multigrid hierarchy, the Jacobi vectors): a planner used
    /// once need not hold them through the integration. The next solve plans them again.
    pub fn release_solver(&mut self) -> Result<()> {
        self.solver = Solver::new(self.solver.width(), self.solver.height())?;
        Ok(())
    }

    /// Solves for (f, g), following the non-convergence policy; reports each iteration to
    /// `progress` (a stage as long as the cap). A solve that blows up is an error.
    pub fn solve(&mut self, problem: &Problem, progress: &dyn Progress) -> Result<Shape> {
        let options = self.options.solve_options();
        let mut shape = self.solve_once(problem, &options, progress)?;
        if let NonConvergence::FallBackToJacobi { max_sweeps } = self.options.non_convergence {
            if (shape.solution.diverged || !shape.solution.converged)
                && options.method != Method::Jacobi
            {
                let jacobi = SolveOptions {
                    method: Method::Jacobi,
                    max_iter: max_sweeps,
                    ..options
                };
                shape = self.solve_once(problem, &jacobi, progress)?;
                shape.fell_back = true;
            }
        }
        let s = &shape.solution;
        let blown = |v: f64| v.is_nan() || v.abs() >= crate::solver::BLOWN_UP;
        if s.diverged
            || blown(s.last_update)
            || s.f.data().iter().chain(s.g.data()).any(|&v| blown(v))
        {
            let mut why = Message::text(format!(
                "the {} iteration diverged after {} {} (last update {:.3e}); use ",
                shape.method,
                shape.solution.iterations,
                shape.method.iteration_unit(),
                shape.solution.last_update,
            ));
            if shape.method != Method::Jacobi {
                why = why
                    .setting(Setting::JacobiMethod, "the jacobi method")
                    .then(" or ");
            }
            return Err(Error::Setting(why.setting(Setting::Lambda, "a smaller λ")));
        }
        Ok(shape)
    }

    fn solve_once(
        &mut self,
        problem: &Problem,
        options: &SolveOptions,
        progress: &dyn Progress,
    ) -> Result<Shape> {
        progress.start(options.max_iter as u64, "solving");
        let mut history = Vec::new();
        // Once a solve estimates its time left, its steps are shown against the time.
        let mut estimating = false;
        let solution = self.solver.solve_with_progress(
            problem.image,
            problem.mask,
            problem.boundary,
            problem.reflectance,
            options,
            &mut |p| {
                // A nested solve's coarser grids report their steps too: the history is the
                // image's grid's.
                if p.level == 0 {
                    history.push(p.last_update);
                }
                match p.seconds_left {
                    Some(seconds) => {
                        estimating = true;
                        progress.time_left(seconds);
                        progress.message(&step_message(p));
                    }
                    None if estimating => progress.message(&step_message(p)),
                    None => {
                        progress.set_position(p.iteration as u64);
                        if p.iteration % 64 == 0 {
                            progress
                                .message(&format!("solving (last update {:.2e})", p.last_update));
                        }
                    }
                }
            },
        )?;
        progress.finish();
        // The solver stops its sweeps early when a stop was requested: no shape then.
        crate::cancel::check()?;
        Ok(Shape {
            solution,
            method: options.method,
            fell_back: false,
            history,
            max_iter: options.max_iter,
        })
    }

    /// Integrates the slopes of `shape`'s normals on `mask` to depth resting on zero.
    pub fn depth(&mut self, shape: &Shape, mask: &Mask) -> Result<Depth> {
        let (f, g) = (shape.solution.f.clone(), shape.solution.g.clone());
        self.depth_from_fg(f, g, mask)
    }

    /// [`Reconstructor::depth`] from (f, g) given by value: their buffers become the slopes,
    /// so a large reconstruction holds no extra full-size images.
    pub fn depth_from_fg(&mut self, f: Image, g: Image, mask: &Mask) -> Result<Depth> {
        let (dz_dx, dz_dy) = gradients_from_fg(f, g, mask, self.options.min_nz)?;
        let (mut depth, report) = match (&mut self.fourier, self.options.depth) {
            (Some(fc), _) => (
                fc.integrate(&dz_dx, &dz_dy)?,
                IntegrationReport {
                    iterations: 0,
                    relative_residual: 0.0,
                    converged: true,
                },
            ),
            (None, DepthMethod::Poisson(options)) => {
                let i = integrate_owned_gradients(dz_dx, dz_dy, mask, &options)?;
                (
                    i.depth,
                    IntegrationReport {
                        iterations: i.iterations,
                        relative_residual: i.relative_residual,
                        converged: i.converged,
                    },
                )
            }
            (None, DepthMethod::FrankotChellappa) => {
                return Err(Error::Compute(
                    "the Frankot–Chellappa integrator was not planned".into(),
                ))
            }
        };
        let range = if self.options.rest_on_zero {
            rest_on_zero(&mut depth, mask)?
        } else {
            crate::integrate::masked_range(&depth, mask).map_or(0.0, |(lo, hi)| hi - lo)
        };
        Ok(Depth {
            depth,
            range,
            report,
        })
    }

    /// Solves and integrates: [`Reconstructor::solve`] then [`Reconstructor::depth`].
    pub fn reconstruct(
        &mut self,
        problem: &Problem,
        progress: &dyn Progress,
    ) -> Result<Reconstruction> {
        let shape = self.solve(problem, progress)?;
        let depth = self.depth(&shape, problem.mask)?;
        Ok(Reconstruction { shape, depth })
    }
}
