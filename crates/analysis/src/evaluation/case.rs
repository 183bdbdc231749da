//! One evaluation case: an image, its light and domain, solved by the engine, integrated to
//! depth, and measured against whatever truth there is.

use super::metrics::{
    angular_error, angular_error_map, depth_error, shading_residual, AngularError, DepthError,
};
use crate::boundary::{Boundary, LimbTest};
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask};
use crate::light::Light;
use crate::progress::NoProgress;
use crate::reconstruct::{NonConvergence, Problem, ReconstructOptions, Reconstructor};
use crate::reflectance::Lambertian;
use crate::solver::SolveOptions;
use serde::Serialize;
use std::time::Instant;

/// A shape-from-shading problem with its truth.
#[derive(Debug, Clone)]
pub struct Case {
    /// The set it belongs to (`bunny`, `mozart`, …).
    pub set: &'static str,
    /// The object (`bunny`, `bear`, `ball`, …).
    pub object: String,
    /// How the light is described in the table (`tilt 0°, slant 30°`, `052 (4°)`).
    pub light_label: String,
    /// The image, in units of the albedo (a surface facing the light has brightness 1).
    pub image: Image,
    /// Where the solver works.
    pub domain: Mask,
    /// Where errors are measured (inside `domain`).
    pub scored: Mask,
    /// The light.
    pub light: Light,
    /// The boundary condition.
    pub boundary: Boundary,
    /// The true normals, where known.
    pub truth_normals: Option<Grid<Normal>>,
    /// The true depth in pixels, where known.
    pub truth_depth: Option<Image>,
    /// The albedo the image was divided by, and how it was found.
    pub albedo: Albedo,
}

/// The albedo the image was divided by.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Albedo {
    /// The value used.
    pub value: f64,
    /// Where it came from (`known` for rendered images).
    pub method: &'static str,
    /// For photographs with true normals: the least-squares albedo those normals give, to
    /// judge the estimate by.
    pub with_true_normals: Option<f64>,
}

impl Albedo {
    /// The albedo of a rendered image: exactly 1.
    pub fn known() -> Albedo {
        Albedo {
            value: 1.0,
            method: "known (rendered with albedo 1)",
            with_true_normals: None,
        }
    }
}

/// The numbers of one solved case: a row of the table.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseResult {
    /// The set.
    pub set: &'static str,
    /// The object.
    pub object: String,
    /// The light as shown in the table.
    pub light_label: String,
    /// The light vector (x right, y up, z toward the viewer).
    pub light: [f64; 3],
    /// Tilt of the light in degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// Slant of the light from the view direction in degrees.
    pub slant_deg: f64,
    /// The boundary condition.
    pub boundary: &'static str,
    /// With the `limb` boundary, what its test found ([`crate::boundary::limb_conditions`]), as
    /// the fields `not_limb` and `dark_level`; absent for every other boundary.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub limb: Option<LimbTest>,
    /// The albedo the image was divided by.
    pub albedo: Albedo,
    /// Angle between recovered and true normals on the scored mask.
    pub normal_error: Option<AngularError>,
    /// Depth error after a least-squares scale and offset, where the true depth is known.
    pub depth_error: Option<DepthError>,
    /// Mean |R(n) − I| on the domain, in units of the albedo.
    pub residual: f64,
    /// The image size solved (after cropping to the object).
    pub width: usize,
    /// The image size solved.
    pub height: usize,
    /// Pixels in the domain.
    pub domain_pixels: usize,
    /// The solver method (`multigrid`, `integrable`, `jacobi`), as `solve --method` names it.
    pub method: String,
    /// Whether the multigrid cycles stalled or blew up and the energy descent finished the
    /// solve ([`crate::solver::Solution::globalised`]).
    pub globalised: bool,
    /// Iterations done, in the method's unit (multigrid cycles, Jacobi sweeps, integrable
    /// iterations; the integrable method's warm start not counted).
    pub iterations: usize,
    /// Whether the solve met its tolerance.
    pub converged: bool,
    /// Seconds for solving and integrating (not loading or rendering).
    pub seconds: f64,
}

/// What a solved case leaves besides its numbers: the grids the pictures are made of.
#[derive(Debug, Clone)]
pub struct CaseOutput {
    /// The numbers.
    pub result: CaseResult,
    /// The recovered normals.
    pub normals: Grid<Normal>,
    /// The recovered depth in pixels (lowest point of the domain at 0).
    pub depth: Image,
    /// Angle to the truth in degrees on the scored mask, where a truth exists.
    pub error_map: Option<Image>,
}

/// Solves `case` with `options` and measures it.
pub fn solve_case(case: &Case, options: &SolveOptions) -> Result<CaseOutput> {
    let (w, h) = (case.image.width(), case.image.height());
    let reflectance = Lambertian {
        light: case.light,
        albedo: 1.0,
        ambient: 0.0,
    };
    let started = Instant::now();
    let policy = ReconstructOptions::from_solve(options, NonConvergence::Report);
    let mut planner = Reconstructor::new(w, h, policy)?;
    let reconstruction = planner
        .reconstruct(
            &Problem {
                image: &case.image,
                mask: &case.domain,
                boundary: &case.boundary,
                reflectance: &reflectance,
            },
            &NoProgress,
        )
        .map_err(|e| match e {
            Error::Compute(why) => {
                Error::Compute(format!("{} {}: {why}", case.object, case.light_label))
            }
            other => other,
        })?;
    let seconds = started.elapsed().as_secs_f64();
    let solution = reconstruction.shape.solution;
    let depth = reconstruction.depth.depth;
    let normals = solution.normals();
    let normal_error = case
        .truth_normals
        .as_ref()
        .map(|t| angular_error(&normals, t, &case.scored))
        .transpose()?;
    let error_map = case
        .truth_normals
        .as_ref()
        .map(|t| angular_error_map(&normals, t, &case.scored))
        .transpose()?;
    let depth_error = case
        .truth_depth
        .as_ref()
        .map(|t| depth_error(&depth, t, &case.scored))
        .transpose()?;
    let residual = shading_residual(&normals, &case.image, &case.domain, &reflectance)?;
    let d = case.light.direction();
    Ok(CaseOutput {
        result: CaseResult {
            set: case.set,
            object: case.object.clone(),
            light_label: case.light_label.clone(),
            light: [d.x, d.y, d.z],
            tilt_deg: case.light.tilt_deg(),
            slant_deg: case.light.slant_deg(),
            boundary: case.boundary.name(),
            limb: solution.limb,
            albedo: case.albedo.clone(),
            normal_error,
            depth_error,
            residual,
            width: w,
            height: h,
            domain_pixels: case.domain.count(),
            method: options.method.to_string(),
            globalised: solution.globalised,
            iterations: solution.iterations,
            converged: solution.converged,
            seconds,
        },
        normals,
        depth,
        error_map,
    })
}
