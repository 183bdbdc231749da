//! One interpretation of a picture: the shape recovered under one assumed light.
//!
//! The picture is solved by the Ikeuchi–Horn engine (`crate::solver`, default method) under a
//! Lambertian reflectance map with the assumed light, integrated to depth, and read on each
//! token: convexity ([`crate::analysis::convexity`]), the irradiance residual
//! e_R = Σ (I − R(f, g))² over the token's unknown, lit pixels and the smoothness
//! e_S = ¼ Σ (Δf² + Δg²) over neighbour pairs within the token (the solver's own terms,
//! restricted to the token), and the *surface residual* e_Z: the integrated depth is a real
//! surface, and e_Z = Σ (I − R(n_z))² measures how well its own normals n_z reproduce the
//! picture under the assumed light. e_R cannot tell assumed tilts apart when the boundary is
//! flat or free: the solver's energy is unchanged when the light and every (f, g) turn together
//! about the line of sight, so the solve under tilt t + φ is the solve under t with its normals'
//! image-plane parts turned by φ, with the same e_R and e_S. Those turned normals do not form a
//! surface (they curl), and integration keeps only the part that does; e_Z sees the difference. When the configured method (multigrid by default) does not
//! converge, the solve is repeated with Jacobi sweeps, which reach the same fixed point.
//!
//! Depth: with the flat boundary the picture is a relief on a plane: the domain's rim, and
//! everything outside the domain, faces the viewer, so the slope field is zero there (and at the
//! frame) and Frankot–Chellappa's periodic integration over the whole frame is exact and fast.
//! Other boundaries are integrated on the domain alone by the masked Poisson solver.

use super::convexity::Token;
use crate::boundary::{domain_roles, Boundary, Role};
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask};
use crate::integrate::PoissonOptions;
use crate::light::Light;
use crate::progress::NoProgress;
use crate::reconstruct::{DepthMethod, Problem, ReconstructOptions, Reconstructor, Shape};
use crate::reflectance::{Lambertian, ReflectanceMap};
use crate::solver::{Method, Solution, SolveOptions};
use serde::Serialize;

pub use crate::reconstruct::{
    ANALYSIS_JACOBI_SWEEPS as JACOBI_FALLBACK_SWEEPS, ANALYSIS_MULTIGRID_CYCLES as MULTIGRID_CYCLES,
};

/// The solver settings analyses use: those of [`ReconstructOptions::for_analysis`] (the
/// engine's defaults, at most [`MULTIGRID_CYCLES`] cycles before the Jacobi fallback).
pub fn analysis_solve_options() -> SolveOptions {
    ReconstructOptions::for_analysis().solve_options()
}

/// What is assumed about the surface and light besides the light's tilt.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Lighting {
    /// The assumed light's slant from the line of sight, degrees (0 ≤ slant < 90).
    pub slant_deg: f64,
    /// Lambertian albedo ρ.
    pub albedo: f64,
    /// Ambient level (the brightness of surfaces in shadow).
    pub ambient: f64,
}

impl Lighting {
    /// Checks the values, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.slant_deg.is_finite() && (0.0..90.0).contains(&self.slant_deg)) {
            return Err(Error::invalid(format!(
                "slant {}° must be in 0..90 (90 is grazing: the shading says nothing)",
                self.slant_deg
            )));
        }
        if !(self.albedo.is_finite() && self.albedo > 0.0) {
            return Err(Error::invalid(format!(
                "albedo {} must be a positive number",
                self.albedo
            )));
        }
        if !(self.ambient.is_finite() && self.ambient >= 0.0) {
            return Err(Error::invalid(format!(
                "ambient {} must be a number ≥ 0",
                self.ambient
            )));
        }
        Ok(())
    }

    /// The albedo that makes a surface facing the viewer as bright as `flat_luminance` under
    /// this slant and ambient level: (L − ambient) / cos(slant). Fails when that is not
    /// positive.
    pub fn albedo_for_flat(flat_luminance: f64, slant_deg: f64, ambient: f64) -> Result<f64> {
        let a = (flat_luminance - ambient) / slant_deg.to_radians().cos();
        if a.is_finite() && a > 0.0 {
            Ok(a)
        } else {
            Err(Error::invalid(format!(
                "cannot take the albedo from a flat luminance of {flat_luminance} with ambient {ambient}: it must exceed the ambient level (give the albedo)"
            )))
        }
    }
}

/// The picture to interpret: its luminance, the domain the engine solves on, the boundary
/// condition at the domain's rim and the tokens read from each solution.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// Linear luminance.
    pub image: &'a Image,
    /// The solve domain.
    pub domain: &'a Mask,
    /// The boundary condition at the domain's rim.
    pub boundary: &'a Boundary,
    /// The tokens (each inside the domain).
    pub tokens: &'a [Token],
}

/// A token read from one interpretation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TokenReading {
    /// Signed convexity (> 0 convex toward the viewer).
    pub convexity: f64,
    /// Irradiance residual e_R over the token.
    pub residual: f64,
    /// Smoothness e_S over the token.
    pub smoothness: f64,
    /// The surface residual e_Z over the token: Σ (I − R(n_z))² with n_z the normals of the
    /// integrated depth (see [`surface_normals`]), over the token's lit pixels.
    pub surface_residual: f64,
}

/// One interpretation: the solve under one assumed light, read on every token.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Interpretation {
    /// The assumed light's tilt, degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// The irradiance residual e_R of the whole solution.
    pub residual: f64,
    /// The smoothness e_S of the whole solution.
    pub smoothness: f64,
    /// The surface residual e_Z of the whole domain (see [`TokenReading::surface_residual`]).
    pub surface_residual: f64,
    /// Whether the solver converged.
    pub converged: bool,
    /// Solver iterations (cycles for multigrid, sweeps for Jacobi).
    pub iterations: usize,
    /// The method whose answer this is: the configured one, or Jacobi when that did not
    /// converge.
    #[serde(serialize_with = "method_name")]
    pub method: Method,
    /// One reading per token, in the scene's token order.
    pub tokens: Vec<TokenReading>,
    /// The depth map, when asked for ([`Interpreter::keep_depth`]).
    #[serde(skip)]
    pub depth: Option<Image>,
    /// The recovered normals' stereographic f, when the depth is kept.
    #[serde(skip)]
    pub f: Option<Image>,
    /// The recovered normals' stereographic g, when the depth is kept.
    #[serde(skip)]
    pub g: Option<Image>,
}

/// Reusable state for interpreting pictures of one scene: the reconstruction planner (solver
/// and integrator) and the boundary roles, planned once and used for every assumed light.
#[derive(Debug)]
pub struct Interpreter {
    planner: Reconstructor,
    roles: Grid<Role>,
    keep_depth: bool,
}

impl Interpreter {
    /// An interpreter for `scene`'s size, domain and boundary, solving with `options` and, when
    /// they do not converge, falling back to Jacobi
    /// ([`crate::reconstruct::NonConvergence::FallBackToJacobi`]).
    ///
    /// Fails on mismatched sizes, non-finite luminance, an empty domain, no tokens, or a token
    /// that leaves the domain.
    pub fn new(scene: &Scene, options: &SolveOptions) -> Result<Interpreter> {
        check_scene(scene)?;
        let (w, h) = (scene.image.width(), scene.image.height());
        let analysis = ReconstructOptions::for_analysis();
        let policy = ReconstructOptions {
            depth: if *scene.boundary == Boundary::Flat {
                DepthMethod::FrankotChellappa
            } else {
                DepthMethod::Poisson(PoissonOptions::default())
            },
            rest_on_zero: analysis.rest_on_zero,
            ..ReconstructOptions::from_solve(options, analysis.non_convergence)
        };
        let roles = domain_roles(scene.domain, scene.boundary)?;
        Ok(Interpreter {
            planner: Reconstructor::new(w, h, policy)?,
            roles,
            keep_depth: false,
        })
    }

    /// Keep the depth map and (f, g) in every [`Interpretation`] (off by default: a sweep needs
    /// only the readings).
    pub fn keep_depth(mut self, keep: bool) -> Self {
        self.keep_depth = keep;
        self
    }

    /// Whether depth comes from Frankot–Chellappa (true) or the masked Poisson solver.
    pub fn uses_fourier(&self) -> bool {
        self.planner.options().depth == DepthMethod::FrankotChellappa
    }

    /// Interprets `scene` (the one this interpreter was made for) under the light of tilt
    /// `tilt_deg` and `lighting`.
    pub fn interpret(
        &mut self,
        scene: &Scene,
        tilt_deg: f64,
        lighting: &Lighting,
    ) -> Result<Interpretation> {
        let shape = self.solve(scene, tilt_deg, lighting)?;
        self.read(scene, shape, tilt_deg, lighting)
    }

    /// The solve alone of [`Interpreter::interpret`]: the shape recovered under the light of
    /// tilt `tilt_deg` and `lighting`, not yet integrated or read.
    pub fn solve(&mut self, scene: &Scene, tilt_deg: f64, lighting: &Lighting) -> Result<Shape> {
        lighting.validate()?;
        let map = lambertian(tilt_deg, lighting)?;
        self.planner
            .solve(
                &Problem {
                    image: scene.image,
                    mask: scene.domain,
                    boundary: scene.boundary,
                    reflectance: &map,
                },
                &NoProgress,
            )
            .map_err(|e| match e {
                Error::Compute(why) => {
                    Error::Compute(format!("under the light of tilt {tilt_deg}°: {why}"))
                }
                other => other,
            })
    }

    /// Whether the solve under one tilt, turned, is the solve under every other tilt
    /// ([`turned`]): true when the boundary condition does not single out a direction in the
    /// image plane (flat or free). The solver's equations then commute with turning the light
    /// and every (f, g) together about the line of sight: the Lambertian map depends on n·s
    /// only, the smoothness term and the neighbour averages are linear in (f, g), and the
    /// rim's values, (0, 0) or none, do not turn. An occluding or given rim fixes normals
    /// that do not turn with the light, and each tilt needs its own solve.
    pub fn turns_with_light(scene: &Scene) -> bool {
        matches!(scene.boundary, Boundary::Flat | Boundary::Free)
    }

    /// [`Interpreter::interpret`] under the light of tilt `tilt_deg` from `shape`, the solve
    /// under tilt `solved_tilt_deg` ([`Interpreter::solve`]), turned by the difference
    /// ([`turned`]) instead of solved again. Only for a scene where
    /// [`Interpreter::turns_with_light`] holds; there it is the same fixed point as the solve
    /// under `tilt_deg`, at the cost of an integration. A separate solve stops where its own
    /// largest update of f or g falls below the tolerance, and that maximum changes as (f, g)
    /// turn: the two agree to the solver's tolerance (about 1e-6 relative in the readings),
    /// and to rounding (about 1e-12) when the separate solve stops after the same cycle.
    pub fn interpret_turned(
        &mut self,
        scene: &Scene,
        shape: &Shape,
        solved_tilt_deg: f64,
        tilt_deg: f64,
        lighting: &Lighting,
    ) -> Result<Interpretation> {
        if !Interpreter::turns_with_light(scene) {
            return Err(Error::invalid(
                "a solve turned to another light needs a flat or free boundary",
            ));
        }
        let shape = turned(shape, tilt_deg - solved_tilt_deg);
        self.read(scene, shape, tilt_deg, lighting)
    }

    /// Integrates `shape` (solved under the light of tilt `tilt_deg`) and reads every token.
    fn read(
        &mut self,
        scene: &Scene,
        shape: Shape,
        tilt_deg: f64,
        lighting: &Lighting,
    ) -> Result<Interpretation> {
        lighting.validate()?;
        let map = lambertian(tilt_deg, lighting)?;
        let depth = self.planner.depth(&shape, scene.domain)?.depth;
        let (solution, method) = (shape.solution, shape.method);
        let rendered = surface_normals(&depth, scene.domain).map(|n| map.radiance(n));
        let misfit = Grid::from_fn(scene.image.width(), scene.image.height(), |c, r| {
            let i = *scene.image.get(c, r);
            if *scene.domain.get(c, r) && i > lighting.ambient {
                let e = i - rendered.get(c, r);
                e * e
            } else {
                0.0
            }
        });
        let surface_residual = misfit.data().iter().sum();
        let tokens = scene
            .tokens
            .iter()
            .map(|t| {
                read_token(
                    t,
                    scene.image,
                    &solution.f,
                    &solution.g,
                    &depth,
                    &misfit,
                    &self.roles,
                    &map,
                )
            })
            .collect();
        let keep = self.keep_depth;
        Ok(Interpretation {
            tilt_deg,
            residual: solution.brightness_energy,
            smoothness: solution.smoothness_energy,
            surface_residual,
            converged: solution.converged,
            iterations: solution.iterations,
            method,
            tokens,
            depth: keep.then_some(depth),
            f: keep.then(|| solution.f.clone()),
            g: keep.then_some(solution.g),
        })
    }
}

/// The Lambertian map of the assumed light of tilt `tilt_deg` and `lighting`.
fn lambertian(tilt_deg: f64, lighting: &Lighting) -> Result<Lambertian> {
    Ok(Lambertian {
        light: Light::from_tilt_slant(tilt_deg, lighting.slant_deg)?,
        albedo: lighting.albedo,
        ambient: lighting.ambient,
    })
}

/// `shape` with every (f, g) turned by `degrees` counter-clockwise about the line of sight
/// (the way the light turns when its tilt grows by `degrees`): the solve under a light turned
/// by `degrees`, where [`Interpreter::turns_with_light`] holds. Quarter turns are exact.
///
/// ```
/// use shadelab_analysis::analysis::interpretation::turned;
/// use shadelab::Shape;
/// use shadelab::{Method, Solution};
/// use shadelab::Grid;
/// let solution = Solution {
///     f: Grid::new(2, 1, 1.0),
///     g: Grid::new(2, 1, 0.0),
///     iterations: 3,
///     converged: true,
///     diverged: false,
///     smoothness_energy: 0.0,
///     brightness_energy: 0.0,
///     last_update: 0.0,
///     unknowns: 2,
///     globalised: false,
///     energy_history: vec![],
///     limb: None,
/// };
/// let shape = Shape { solution, method: Method::Multigrid, fell_back: false, history: vec![], max_iter: 40 };
/// let quarter = turned(&shape, 90.0); // (1, 0) turns to (0, 1)
/// assert_eq!((*quarter.solution.f.get(0, 0), *quarter.solution.g.get(0, 0)), (0.0, 1.0));
/// ```
pub fn turned(shape: &Shape, degrees: f64) -> Shape {
    let (sin, cos) = crate::light::sin_cos_deg(degrees);
    let s = &shape.solution;
    let mut f = s.f.clone();
    let mut g = s.g.clone();
    for (f, g) in f.data_mut().iter_mut().zip(g.data_mut().iter_mut()) {
        (*f, *g) = (cos * *f - sin * *g, sin * *f + cos * *g);
    }
    Shape {
        solution: Solution {
            f,
            g,
            iterations: s.iterations,
            converged: s.converged,
            diverged: s.diverged,
            smoothness_energy: s.smoothness_energy,
            brightness_energy: s.brightness_energy,
            last_update: s.last_update,
            unknowns: s.unknowns,
            globalised: s.globalised,
            energy_history: s.energy_history.clone(),
            limb: s.limb,
        },
        method: shape.method,
        fell_back: shape.fell_back,
        history: shape.history.clone(),
        max_iter: shape.max_iter,
    }
}

fn method_name<S: serde::Serializer>(m: &Method, s: S) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&m.to_string())
}

/// Checks a scene's sizes, values, domain and tokens.
pub fn check_scene(scene: &Scene) -> Result<()> {
    let (w, h) = (scene.image.width(), scene.image.height());
    scene
        .domain
        .check_same_size("the domain mask is", scene.image, "the image is")?;
    if let Some(i) = scene.image.data().iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(format!(
            "image value at column {}, row {} is not a finite number",
            i % w,
            i / w
        )));
    }
    if scene.domain.count() == 0 {
        return Err(Error::invalid("the domain mask is empty: nothing to solve"));
    }
    if scene.tokens.is_empty() {
        return Err(Error::invalid("no tokens to judge"));
    }
    for t in scene.tokens {
        if t.pixels().iter().any(|&p| p >= w * h) {
            return Err(Error::invalid(format!(
                "token '{}' does not fit an image {}",
                t.name,
                crate::message::SizeText::Pixels(h, w)
            )));
        }
        if !t.inside(scene.domain) {
            return Err(Error::invalid(format!(
                "token '{}' (label {}) has pixels outside the solve domain",
                t.name, t.label
            )));
        }
    }
    Ok(())
}

/// The unit normals of a depth map on `domain`: slopes by central differences between domain
/// pixels, one-sided where a neighbour is outside the domain (or the picture), 0 where both
/// are; (0, 0, 1) outside the domain.
pub fn surface_normals(depth: &Image, domain: &Mask) -> Grid<Normal> {
    let (w, h) = (depth.width(), depth.height());
    let inside = |c: isize, r: isize| domain.checked(c, r).copied().unwrap_or(false);
    let z = |c: isize, r: isize| *depth.get(c as usize, r as usize);
    // The slope along one axis from the neighbours before and after, where inside.
    let slope = |c: isize, r: isize, dc: isize, dr: isize| -> f64 {
        match (inside(c - dc, r - dr), inside(c + dc, r + dr)) {
            (true, true) => 0.5 * (z(c + dc, r + dr) - z(c - dc, r - dr)),
            (false, true) => z(c + dc, r + dr) - z(c, r),
            (true, false) => z(c, r) - z(c - dc, r - dr),
            (false, false) => 0.0,
        }
    };
    Grid::from_fn(w, h, |col, row| {
        let (c, r) = (col as isize, row as isize);
        if !inside(c, r) {
            return Normal::z();
        }
        // World y is up: one row down is −y.
        let (dz_dx, dz_dy) = (slope(c, r, 1, 0), -slope(c, r, 0, 1));
        Normal::new(-dz_dx, -dz_dy, 1.0).normalize()
    })
}

/// The readings of one token.
#[allow(clippy::too_many_arguments)]
fn read_token(
    token: &Token,
    image: &Image,
    f: &Image,
    g: &Image,
    depth: &Image,
    misfit: &Image,
    roles: &Grid<Role>,
    map: &dyn ReflectanceMap,
) -> TokenReading {
    let w = image.width();
    let ambient = map.ambient();
    let mut residual = 0.0;
    let mut smoothness = 0.0;
    let mut surface_residual = 0.0;
    let members = token.pixels();
    // The member one row below p, found by a pointer that only moves forward (members are in
    // row-major order, so p + w grows with p).
    let mut below = 0;
    for (k, &p) in members.iter().enumerate() {
        surface_residual += misfit.data()[p];
        let i = image.data()[p];
        if roles.data()[p] == Role::Unknown && i > ambient {
            let e = i - map.fg(f.data()[p], g.data()[p]).value;
            residual += e * e;
        }
        // Pairs to the right and below, both in the token (members are in row-major order).
        let (col, row) = (p % w, p / w);
        while below < members.len() && members[below] < p + w {
            below += 1;
        }
        let right = col + 1 < w && members.get(k + 1) == Some(&(p + 1));
        let down = row + 1 < image.height() && members.get(below) == Some(&(p + w));
        for q in [right.then_some(p + 1), down.then_some(p + w)]
            .into_iter()
            .flatten()
        {
            let (df, dg) = (f.data()[q] - f.data()[p], g.data()[q] - g.data()[p]);
            smoothness += 0.25 * (df * df + dg * dg);
        }
    }
    TokenReading {
        convexity: token.convexity(depth),
        residual,
        smoothness,
        surface_residual,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::convexity::tokens_from_labels;

    /// A hemispherical bump (radius `r`) on a plane, lit from `tilt`, slant 45°, flat panel at
    /// 0.5: the picture and its disc token.
    pub(crate) fn bump_picture(size: usize, r: f64, tilt: f64, sign: f64) -> (Image, Vec<Token>) {
        let s = Light::from_tilt_slant(tilt, 45.0).unwrap().direction();
        let c = (size as f64 - 1.0) / 2.0;
        let albedo = 0.5 / s.z;
        let image = Grid::from_fn(size, size, |col, row| {
            let (x, y) = (col as f64 - c, c - row as f64);
            let rho2 = x * x + y * y;
            if rho2 >= r * r {
                return 0.5;
            }
            let n = nalgebra::Vector3::new(sign * x, sign * y, (r * r - rho2).sqrt()).normalize();
            albedo * n.dot(&s).max(0.0)
        });
        let labels = Grid::from_fn(size, size, |col, row| {
            let (x, y) = (col as f64 - c, c - row as f64);
            u16::from(x * x + y * y < r * r)
        });
        (
            image,
            tokens_from_labels(&labels, &["disc".into()]).unwrap(),
        )
    }

    #[test]
    fn a_bump_is_convex_under_its_own_light_and_concave_under_the_opposite() {
        let (image, tokens) = bump_picture(48, 12.0, 0.0, 1.0);
        let domain = Mask::new(48, 48, true);
        let scene = Scene {
            image: &image,
            domain: &domain,
            boundary: &Boundary::Flat,
            tokens: &tokens,
        };
        let lighting = Lighting {
            slant_deg: 45.0,
            albedo: 0.5 / 45f64.to_radians().cos(),
            ambient: 0.0,
        };
        let mut it = Interpreter::new(&scene, &SolveOptions::default()).unwrap();
        assert!(it.uses_fourier());
        let above = it.interpret(&scene, 0.0, &lighting).unwrap();
        let below = it.interpret(&scene, 180.0, &lighting).unwrap();
        let (a, b) = (above.tokens[0], below.tokens[0]);
        assert!(a.convexity > 0.05, "{a:?}");
        assert!(
            (a.convexity + b.convexity).abs() < 1e-6 * a.convexity.abs(),
            "{a:?} {b:?}"
        );
        assert!((a.residual - b.residual).abs() <= 1e-6 * a.residual.max(1e-12));
        assert!(above.converged && below.converged);
        // The whole-picture token's energies are the solver's.
        let whole = [Token::whole(48, 48).unwrap()];
        let scene = Scene {
            tokens: &whole,
            ..scene
        };
        let one = it.interpret(&scene, 0.0, &lighting).unwrap();
        assert!((one.tokens[0].residual - one.residual).abs() <= 1e-12 * one.residual.max(1.0));
        assert!((one.tokens[0].smoothness - one.smoothness).abs() <= 1e-9 * one.smoothness);
    }

    #[test]
    fn a_turned_solve_is_the_solve_under_the_turned_light() {
        // A bump lit from 30°: separate solves under several assumed tilts against one solve
        // turned to each (flat and free boundaries), reading the same numbers to rounding.
        let (image, tokens) = bump_picture(40, 10.0, 30.0, 1.0);
        let domain = Mask::new(40, 40, true);
        let lighting = Lighting {
            slant_deg: 45.0,
            albedo: 0.5 / 45f64.to_radians().cos(),
            ambient: 0.0,
        };
        for boundary in [Boundary::Flat, Boundary::Free] {
            let scene = Scene {
                image: &image,
                domain: &domain,
                boundary: &boundary,
                tokens: &tokens,
            };
            assert!(Interpreter::turns_with_light(&scene));
            let mut it = Interpreter::new(&scene, &SolveOptions::default()).unwrap();
            let shape = it.solve(&scene, 10.0, &lighting).unwrap();
            for tilt in [10.0, 55.0, 100.0, 190.0, 333.0] {
                let direct = it.interpret(&scene, tilt, &lighting).unwrap();
                let turned = it
                    .interpret_turned(&scene, &shape, 10.0, tilt, &lighting)
                    .unwrap();
                // Separate solves stop where their own largest update (a maximum over f and
                // g, which turning changes) falls below the tolerance 1e-6: they agree with
                // the turned one to that tolerance, and to rounding where they stop after the
                // same cycle.
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-5 * a.abs().max(1e-6);
                let (d, t) = (direct.tokens[0], turned.tokens[0]);
                assert!(close(d.convexity, t.convexity), "{tilt}: {d:?} {t:?}");
                assert!(close(d.residual, t.residual), "{tilt}: {d:?} {t:?}");
                assert!(close(d.smoothness, t.smoothness), "{tilt}: {d:?} {t:?}");
                assert!(
                    close(d.surface_residual, t.surface_residual),
                    "{tilt}: {d:?} {t:?}"
                );
                assert!(close(direct.surface_residual, turned.surface_residual));
                assert_eq!(
                    (direct.converged, direct.method),
                    (turned.converged, turned.method)
                );
            }
        }
        // An occluding rim does not turn with the light: no shortcut.
        let scene = Scene {
            image: &image,
            domain: &domain,
            boundary: &Boundary::Occluding,
            tokens: &tokens,
        };
        assert!(!Interpreter::turns_with_light(&scene));
    }

    #[test]
    fn tokens_must_lie_in_the_domain() {
        let (image, tokens) = bump_picture(32, 8.0, 0.0, 1.0);
        let domain = Grid::from_fn(32, 32, |c, _| c < 16);
        let scene = Scene {
            image: &image,
            domain: &domain,
            boundary: &Boundary::Flat,
            tokens: &tokens,
        };
        let e = Interpreter::new(&scene, &SolveOptions::default()).unwrap_err();
        assert!(e.to_string().contains("outside the solve domain"), "{e}");
    }
}
