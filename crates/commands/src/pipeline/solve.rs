//! `shadelab solve` as a library pipeline: one grayscale image (and its mask) → normals and
//! depth by the [`Reconstructor`], with a report that records every parameter and number.
//!
//! [`SolveConfig`] names the inputs and policy, [`run`] reads them and reconstructs,
//! [`SolveRun::write`] writes the output folder: `normals.npy`, `normals.png`, `depth.npy`,
//! `depth.png`, `surface.obj`, `convergence.csv` (and `convergence.png` with the `plots`
//! feature) and `report.json`.

use super::{CommandReport, Output};
// The albedo rule this command's configuration is checked by, defined in reconstruct.
pub use crate::reconstruct::check_albedo;
// The solver's budgets, the defaults of its options.
pub use crate::solver::{
    INTEGRABLE_LM_MAX_STEPS, INTEGRABLE_MAX_ITER, JACOBI_MAX_SWEEPS, MULTIGRID_MAX_CYCLES,
};

use crate::albedo::{AlbedoEstimate, Saturation};
use crate::boundary::{Boundary, LimbTest, BOUNDARY_NAMES, OCCLUDING_SHRINK};
use crate::error::{Error, Result};
use crate::gradient_space::normal_from_fg;
use crate::grid::{size_mismatch, Grid, Image, Mask};
use crate::io::{self, BitDepth, RenderSidecar, Stamp, TrueLight};
use crate::light::FrontLight;
use crate::light_estimation::LightEstimate;
use crate::message::{Message, Setting};
use crate::progress::Progress;
use crate::reconstruct::{
    Depth, LightAndAlbedo, Problem, ReconstructOptions, Reconstructor, Shape,
};
use crate::reflectance::BrdfSpec;
use crate::solver::MethodSource;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The light of a solve: given, or estimated from the image (with the albedo).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightChoice {
    /// This light.
    Given(FrontLight),
    /// Estimated from the image's shading (Zheng–Chellappa), with the albedo.
    Estimate,
}

impl std::str::FromStr for LightChoice {
    type Err = Error;
    /// `estimate`, or any light syntax ([`crate::light::Light`]'s `FromStr`) for a light in front.
    fn from_str(text: &str) -> Result<Self> {
        match text.trim() {
            "estimate" => Ok(LightChoice::Estimate),
            other => Ok(LightChoice::Given(other.parse()?)),
        }
    }
}

/// The boundary condition of a solve: built in, or normals read from a file.
#[derive(Debug, Clone, PartialEq)]
pub enum BoundarySource {
    /// `occluding`, `flat`, `free` or `limb`.
    Named(Boundary),
    /// An H×W×3 `.npy` of unit normals for the rim.
    File(PathBuf),
}

impl std::str::FromStr for BoundarySource {
    type Err = Error;
    /// A built-in name, or the path of a `.npy`.
    fn from_str(text: &str) -> Result<Self> {
        if BOUNDARY_NAMES.contains(&text) {
            return Ok(BoundarySource::Named(Boundary::named(text)?));
        }
        let path = Path::new(text);
        if io::extension(path) != "npy" {
            return Err(Error::invalid(format!(
                "boundary '{text}' is neither {} nor a .npy file of normals",
                BOUNDARY_NAMES.join(", ")
            )));
        }
        Ok(BoundarySource::File(path.to_path_buf()))
    }
}

impl BoundarySource {
    /// The boundary for a `w`×`h` picture (a normals file is read and checked against it).
    pub fn resolve(&self, w: usize, h: usize, max_pixels: usize) -> Result<Boundary> {
        match self {
            BoundarySource::Named(b) => Ok(b.clone()),
            BoundarySource::File(path) => read_boundary(path, w, h, max_pixels),
        }
    }
}

impl std::fmt::Display for BoundarySource {
    /// The name of a built-in boundary, or the file's path.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BoundarySource::Named(b) => f.write_str(b.name()),
            BoundarySource::File(path) => write!(f, "{}", path.display()),
        }
    }
}

/// Everything a solve needs, as plain values.
#[derive(Debug, Clone)]
pub struct SolveConfig {
    /// An 8/16-bit PNG, a JPEG, a TIFF or an H×W `.npy`, decoded as
    /// [`input_encoding`](Self::input_encoding) says.
    pub image: PathBuf,
    /// How the image's codes encode luminance (default [`io::InputEncoding::Auto`]: as the file
    /// says, see [`io::read_gray_as`]).
    pub input_encoding: io::InputEncoding,
    /// The object's mask (PNG, nonzero = inside); `None` is the whole image.
    pub mask: Option<PathBuf>,
    /// The light, given or estimated.
    pub light: LightChoice,
    /// The boundary condition.
    pub boundary: BoundarySource,
    /// The reflectance model (its albedo is replaced by [`SolveConfig::albedo`]'s resolution).
    pub brdf: BrdfSpec,
    /// The albedo; `None` is 1, or the estimate when the light is estimated.
    pub albedo: Option<f64>,
    /// Estimate the albedo from the image by the library's rule ([`crate::albedo::estimate`])
    /// instead: the image is divided by it and capped at 1, and solved with albedo 1, so the
    /// shape does not depend on how the image was scaled. Not with [`SolveConfig::albedo`].
    pub albedo_estimate: bool,
    /// Where the image was clipped: its pixels at or above that level carry no data term
    /// ([`crate::solver::carries_data`]). Replaces the options' own
    /// [`ReconstructOptions::saturation`]. Default [`Saturation::Auto`]: the clipped plateau
    /// the albedo estimate finds, when it is asked for.
    pub saturation: Saturation,
    /// The reconstruction's policy (method, λ, tolerance, cap, non-convergence, integration).
    pub options: ReconstructOptions,
    /// Whether [`ReconstructOptions::method`] was asked for or is the default
    /// ([`crate::solver::Method::SOLVE_DEFAULT`]); recorded in the report.
    pub method_source: MethodSource,
    /// The largest image accepted, in pixels.
    pub max_pixels: usize,
    /// How the light and boundary were written by the user and where the outputs go, recorded
    /// as they were given in the report's `parameters` (empty: their canonical form).
    pub record: SolveRecord,
}

/// What the report records of the request as the user wrote it.
#[derive(Debug, Clone, Default)]
pub struct SolveRecord {
    /// The light as written.
    pub light: String,
    /// The boundary as written.
    pub boundary: String,
    /// The output folder as written.
    pub out: String,
}

impl SolveConfig {
    /// The files this solve reads: the image and the sidecar beside it, the mask, the rim's
    /// normals (see [`crate::io::AtomicDir::reads`]: an output folder never replaces them).
    pub fn files(&self) -> Vec<PathBuf> {
        let mut files = vec![
            self.image.clone(),
            io::render_sidecar::sidecar_path(&self.image),
        ];
        files.extend(self.mask.clone());
        if let BoundarySource::File(path) = &self.boundary {
            files.push(path.clone());
        }
        files
    }

    /// A configuration with `shadelab solve`'s defaults: no mask, the occluding boundary,
    /// Lambertian reflectance, [`ReconstructOptions::for_solve`] (the default method).
    pub fn new(image: impl Into<PathBuf>, light: LightChoice) -> SolveConfig {
        SolveConfig {
            image: image.into(),
            input_encoding: io::InputEncoding::Auto,
            mask: None,
            light,
            boundary: BoundarySource::Named(Boundary::Occluding),
            brdf: BrdfSpec::default(),
            albedo: None,
            albedo_estimate: false,
            saturation: Saturation::Auto,
            options: ReconstructOptions::for_solve(),
            method_source: MethodSource::Default,
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            record: SolveRecord::default(),
        }
    }

    /// Checks everything that needs no file: the policy, the albedo.
    pub fn validate(&self) -> Result<()> {
        self.options.validate()?;
        self.saturation.validate()?;
        self.input_encoding.validate()?;
        if let Some(a) = self.albedo {
            crate::reconstruct::check_albedo(a)?;
        }
        if self.albedo_estimate && self.albedo.is_some() {
            return Err(Error::invalid(
                "give the albedo or ask for its estimate, not both",
            ));
        }
        Ok(())
    }
}

/// The report of a solve (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SolveReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The axes and light conventions.
    pub conventions: Value,
    /// What was read.
    pub input: SolveInput,
    /// The request.
    pub parameters: SolveParameters,
    /// The light assumed.
    pub light: LightReport,
    /// The boundary condition.
    pub boundary: BoundaryReport,
    /// How the solve went.
    pub solver: SolverReport,
    /// How the integration went.
    pub integration: IntegrationSummary,
    /// What each output file holds.
    pub outputs: BTreeMap<&'static str, String>,
    /// Lowest and highest depth inside the mask.
    pub depth_range: [f64; 2],
    /// Seconds for the whole run.
    pub seconds: f64,
}

/// The inputs as read.
#[derive(Debug, Clone, Serialize)]
pub struct SolveInput {
    /// The image file.
    pub image: String,
    /// What the reader found (format, bit depth, gamma).
    pub image_info: Value,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// The mask file, if any.
    pub mask: Option<String>,
    /// Pixels inside the mask.
    pub mask_pixels: usize,
    /// The shadelab sidecar read beside the image (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sidecar: Option<Value>,
}

/// The request, as given.
#[derive(Debug, Clone, Serialize)]
pub struct SolveParameters {
    /// The light as written.
    pub light: String,
    /// The boundary as written.
    pub boundary: String,
    /// The reflectance model.
    pub brdf: BrdfSpec,
    /// The albedo used (the estimate's value when it was estimated).
    pub albedo: f64,
    /// The albedo's estimate from the image, when asked for ([`SolveConfig::albedo_estimate`]).
    pub albedo_estimate: Option<AlbedoEstimate>,
    /// λ.
    pub lambda: f64,
    /// The method.
    pub method: String,
    /// Why that method: `default` (none was asked: [`crate::solver::Method::SOLVE_DEFAULT`]) or `asked`.
    pub method_source: MethodSource,
    /// The tolerance.
    pub tol: f64,
    /// The cap of iterations.
    pub max_iter: usize,
    /// The output folder as written.
    pub out: String,
}

/// The light assumed.
#[derive(Debug, Clone, Serialize)]
pub struct LightReport {
    /// Unit vector toward the light.
    pub vector: [f64; 3],
    /// Tilt in degrees (0 = from above, +90 = from the left).
    pub tilt_deg: f64,
    /// Slant from the view direction in degrees.
    pub slant_deg: f64,
    /// Whether it was estimated.
    pub estimated: bool,
    /// The estimate, if estimated.
    pub estimate: Option<LightEstimate>,
    /// The light the image was rendered under, from its sidecar (absent without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_light: Option<TrueLight>,
}

/// The boundary condition used.
#[derive(Debug, Clone, Serialize)]
pub struct BoundaryReport {
    /// Its name (`occluding`, `flat`, `free`, `limb`, `given`).
    pub kind: &'static str,
    /// The factor limb normals are shrunk by (see [`OCCLUDING_SHRINK`]).
    pub occluding_shrink: f64,
    /// With the `limb` boundary, what its test found, as the fields `not_limb` (the occluding
    /// pixels whose brightness rules out a limb, held at the slant the shading gives instead)
    /// and `dark_level` (the reading where a limb would be in attached shadow, which the test
    /// allowed for; 0 for an exact render); absent for every other boundary.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub limb: Option<LimbTest>,
}

/// How the solve went.
#[derive(Debug, Clone, Serialize)]
pub struct SolverReport {
    /// The method.
    pub method: String,
    /// Iterations done.
    pub iterations: usize,
    /// `cycles` or `sweeps`.
    pub iteration_unit: &'static str,
    /// Whether the tolerance was met.
    pub converged: bool,
    /// Why the result may not be trusted, when it did not converge.
    pub warning: Option<String>,
    /// The last update.
    pub last_update: f64,
    /// Unknown pixels.
    pub unknowns: usize,
    /// e_S at the end.
    pub smoothness_energy: f64,
    /// e_R at the end.
    pub brightness_energy: f64,
    /// Whether the multigrid cycles stalled or blew up and the energy descent finished the
    /// solve (`solver::Solution::globalised`).
    pub globalised: bool,
    /// e_S + λ·e_R after each step of the energy descent (empty when the cycles converged
    /// alone); never increasing.
    pub energy_per_step: Vec<f64>,
    /// The pixels left out of the data term as clipped ([`SolveConfig::saturation`]); absent
    /// when no saturation level was in force.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clipped: Option<ClippedReport>,
    /// Seconds of solving.
    pub seconds: f64,
}

/// The pixels a solve left out of the data term as clipped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClippedReport {
    /// The saturation level, in the image's units (before any albedo normalisation).
    pub level: f64,
    /// `plateau` (the albedo estimate's clipped plateau) or `given`.
    pub source: &'static str,
    /// Pixels of the mask at or above the level, left out of the data term.
    pub pixels: usize,
}

/// How the integration went.
#[derive(Debug, Clone, Serialize)]
pub struct IntegrationSummary {
    /// The integrator.
    pub method: &'static str,
    /// The smallest n_z used for slopes.
    pub min_nz: f64,
    /// Iterations.
    pub iterations: usize,
    /// Final relative residual.
    pub relative_residual: f64,
    /// Whether it met its tolerance.
    pub converged: bool,
    /// Seconds of integrating.
    pub seconds: f64,
}

/// A finished solve: the reconstruction and its report.
#[derive(Debug, Clone)]
pub struct SolveRun {
    /// The solved (f, g) with its convergence history.
    pub shape: Shape,
    /// The mask solved on.
    pub mask: Mask,
    /// The depth.
    pub depth: Depth,
    /// The report.
    pub report: SolveReport,
}

/// The solve done, before integration: what the report needs besides the depth.
struct Solved {
    shape: Shape,
    mask: Mask,
    planner: Reconstructor,
    lighting: LightAndAlbedo,
    brdf: BrdfSpec,
    image_info: Value,
    boundary_kind: &'static str,
    solve_seconds: f64,
    sidecar: Option<RenderSidecar>,
    albedo_estimate: Option<AlbedoEstimate>,
    clipped: Option<ClippedReport>,
    /// The note that the image's codes were taken as sRGB, said once the solve succeeded.
    input_note: Option<Message>,
}

/// The lines that say what the image read from `file` and its sidecar (`beside`) give the
/// solve, for the log, said through `progress` as soon as they are known: what was read, what
/// the config gives instead, which mask is solved. Returns the note that untagged codes were
/// taken as sRGB, said once the solve succeeded (a refusal stays one line).
fn say_notes(
    config: &SolveConfig,
    file: &io::PictureFile,
    beside: &io::Beside,
    progress: &dyn Progress,
) -> Option<Message> {
    let source = super::PictureSource {
        image: Some(config.image.clone()),
        input_encoding: config.input_encoding,
        mask: config.mask.clone(),
        ..Default::default()
    };
    let mut lines = source.notes_on(&config.image, file.npy_scale.as_ref(), beside);
    if let Some(s) = beside.sidecar() {
        if config.mask.is_none() && s.target_mask.is_some() && !s.silhouette {
            lines.push(
                Message::text(
                    "its targets are regions of a surface, not objects' outlines: the whole \
                     picture is solved (give ",
                )
                .setting(Setting::Mask, "a mask")
                .then(" to solve inside them)"),
            );
        }
    }
    lines.iter().for_each(|line| progress.note(line));
    super::source::assumed_srgb(file)
}

/// Reads the inputs and solves; the image and boundary are dropped before returning.
fn solve_stage(config: &SolveConfig, progress: &dyn Progress) -> Result<Solved> {
    config.validate()?;
    // Read once (a pipe cannot be read again).
    let file = io::read_picture(
        &config.image,
        config.max_pixels,
        config.input_encoding,
        false,
    )?;
    io::check_luminance_range(file.gray.data(), &config.image)?;
    let beside = RenderSidecar::of_picture(
        &config.image,
        &file,
        config.input_encoding,
        config.max_pixels,
    )?;
    let input_note = say_notes(config, &file, &beside, progress);
    let (mut image, image_info) = (file.gray, file.info);
    // A shadelab render's sidecar: its values made linear again and its ambient level taken
    // off (the solve's reflectance has no ambient term), its target mask as the object's.
    let sidecar =
        (beside.sidecar().cloned()).map(|s| super::source::without_gamma(s, config.input_encoding));
    if let Some(s) = &sidecar {
        let ambient = s.ambient.unwrap_or(0.0);
        // Shadow, at 0 once the ambient is taken off: the render's own where the picture is
        // the render its sidecar records, else what the stored codes cannot tell from the
        // ambient level (see perception's load).
        let quantum = file.quantum.map(|v| s.linearise(v));
        let linear = image.map(|&v| s.linearise(v));
        let unlit = super::source::recorded_unlit(s, &linear, &quantum, config.max_pixels);
        image = quantum
            .settle(&linear, ambient, unlit.as_ref())
            .map(|&v| (v - ambient).max(0.0));
    }
    let (w, h) = (image.width(), image.height());
    let mask_file = config
        .mask
        .as_deref()
        .or(sidecar.as_ref().and_then(|s| s.object_mask()));
    let mask = match mask_file {
        Some(path) => read_mask(path, config, &image)?,
        None => Grid::new(w, h, true),
    };
    let solved = solve_loaded(config, image, image_info, mask, sidecar, progress)?;
    Ok(Solved {
        input_note,
        ..solved
    })
}

/// Solves an image and mask already read (or handed over in memory), with what a render's
/// sidecar declares (albedo) unless the config says otherwise.
fn solve_loaded(
    config: &SolveConfig,
    image: Image,
    image_info: Value,
    mask: Mask,
    sidecar: Option<RenderSidecar>,
    progress: &dyn Progress,
) -> Result<Solved> {
    let (w, h) = (image.width(), image.height());
    let albedo_estimate = if config.albedo_estimate {
        Some(crate::albedo::estimate(&image, &mask)?)
    } else {
        None
    };
    // Clipped pixels (the estimate's plateau, or a level given) carry no data term; the level
    // follows the image into the albedo's units.
    let level = config.saturation.level(albedo_estimate.as_ref());
    let (image, albedo, saturation) = match &albedo_estimate {
        Some(e) => (
            crate::albedo::normalise(&image, e.value),
            Some(1.0),
            level.map(|l| crate::albedo::in_albedo_units(l, e.value)),
        ),
        None => (
            image,
            config.albedo.or(sidecar.as_ref().and_then(|s| s.albedo)),
            level,
        ),
    };
    let clipped = level.map(|level| ClippedReport {
        level,
        source: match config.saturation {
            Saturation::Level(_) => "given",
            _ => "plateau",
        },
        pixels: crate::solver::clipped_pixels(&image, &mask, saturation),
    });
    let boundary = config.boundary.resolve(w, h, config.max_pixels)?;
    if let BoundarySource::File(path) = &config.boundary {
        // The rim's normals checked here, where the file they came from is known.
        crate::boundary::boundary_conditions(&mask, &boundary)
            .map_err(|e| Error::format(path, e.to_string()))?;
    }
    let given = match config.light {
        LightChoice::Given(l) => Some(l),
        LightChoice::Estimate => None,
    };
    let lighting = LightAndAlbedo::resolve(given, albedo, &image, &mask, &boundary)?;
    let mut brdf = config.brdf.clone();
    brdf.albedo = lighting.albedo;
    let reflectance = brdf.build(lighting.light.light())?;
    let options = ReconstructOptions {
        saturation,
        ..config.options
    };
    let mut planner = Reconstructor::new(w, h, options)?;
    let started = Instant::now();
    let problem = Problem {
        image: &image,
        mask: &mask,
        boundary: &boundary,
        reflectance: reflectance.as_ref(),
    };
    let shape = planner.solve(&problem, progress)?;
    // The solver's buffers live only for the solve: the integration and the outputs make their
    // own, and memory peaks there.
    planner.release_solver()?;
    Ok(Solved {
        shape,
        mask,
        planner,
        lighting,
        brdf,
        image_info,
        boundary_kind: boundary.name(),
        solve_seconds: started.elapsed().as_secs_f64(),
        sidecar,
        albedo_estimate,
        clipped,
        input_note: None,
    })
}

/// Reads the inputs named by `config`, reconstructs, and reports, keeping everything in
/// memory (see [`run_into`] for the folder written as it goes).
pub fn run(config: &SolveConfig, progress: &dyn Progress) -> Result<SolveRun> {
    let started = Instant::now();
    let solved = solve_stage(config, progress)?;
    let input_note = solved.input_note.clone();
    let run = finish(config, solved, started)?;
    input_note.iter().for_each(|line| progress.note(line));
    Ok(run)
}

/// Integrates a solve to depth and reports, keeping the solution.
fn finish(config: &SolveConfig, mut solved: Solved, started: Instant) -> Result<SolveRun> {
    let (f, g) = (
        solved.shape.solution.f.clone(),
        solved.shape.solution.g.clone(),
    );
    let (depth, report) = integrate(config, &mut solved, f, g, started)?;
    Ok(SolveRun {
        shape: solved.shape,
        mask: solved.mask,
        depth,
        report,
    })
}

/// [`run`] on an image (and mask) already in memory, e.g. the Python module's NumPy arrays:
/// `config.image` and `config.mask` are not read, only recorded in the report as the names of
/// the inputs (e.g. `<array>`). The image is checked as a file's would be (size limit, finite
/// values), the mask against the image's size; `None` is the whole image.
///
/// ```
/// use shadelab::pipeline::solve::{run_image, LightChoice, SolveConfig};
/// use shadelab::{Grid, NoProgress};
/// let light: LightChoice = "0,0,1".parse()?;
/// let config = SolveConfig::new("<array>", light);
/// let flat = Grid::new(16, 8, 1.0); // lit head-on: a plane facing the viewer
/// let run = run_image(&config, flat, None, &NoProgress)?;
/// assert_eq!((run.report.input.width, run.report.input.height), (16, 8));
/// assert!(run.report.solver.converged);
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn run_image(
    config: &SolveConfig,
    image: Image,
    mask: Option<Mask>,
    progress: &dyn Progress,
) -> Result<SolveRun> {
    let started = Instant::now();
    config.validate()?;
    let name = config.image.display().to_string();
    crate::grid::check_size(image.width(), image.height(), config.max_pixels)?;
    crate::io::check_values(image.data(), 1, image.width(), &name)?;
    let mask = match mask {
        Some(mask) => {
            let mask_name = config
                .mask
                .as_deref()
                .unwrap_or(Path::new(super::source::IN_MEMORY));
            check_mask(mask, mask_name, config, &image)?
        }
        None => Grid::new(image.width(), image.height(), true),
    };
    let info = serde_json::json!({ "format": "in memory" });
    let solved = solve_loaded(config, image, info, mask, None, progress)?;
    finish(config, solved, started)
}

/// [`run`] and [`SolveRun::write`] in one, writing the outputs into the folder `out` as they
/// are made, each dropped once written: the normals before the integration, whose buffers take
/// over (f, g) (the memory a large solve needs stays near what the solve itself holds;
/// `docs/performance.md`). The folder is claimed before the solve, so that one that cannot be
/// written fails at once, and appears whole or not at all.
pub fn run_into(
    config: &SolveConfig,
    out: &Output,
    progress: &dyn Progress,
) -> Result<SolveReport> {
    let folder = out.folder(SolveRun::MARKER)?;
    let (report, input_note) = fill(config, folder.path(), progress)?;
    folder.commit()?;
    // Said once the solve succeeded and its folder is written: a refusal stays one line.
    input_note.iter().for_each(|line| progress.note(line));
    Ok(report)
}

/// The outputs of [`run_into`], written into `dir`.
fn fill(
    config: &SolveConfig,
    dir: &Path,
    progress: &dyn Progress,
) -> Result<(SolveReport, Option<Message>)> {
    let started = Instant::now();
    let mut solved = solve_stage(config, progress)?;
    write_normals(dir, &solved.shape.solution)?;
    write_convergence(dir, &solved.shape, config.options.tol)?;
    // (f, g) move into the integration; the empty grids left behind are never read again.
    let f = std::mem::replace(&mut solved.shape.solution.f, Grid::new(0, 0, 0.0));
    let g = std::mem::replace(&mut solved.shape.solution.g, Grid::new(0, 0, 0.0));
    let (depth, report) = integrate(config, &mut solved, f, g, started)?;
    write_depth(dir, &depth, &solved.mask)?;
    write_report(dir, &report)?;
    Ok((report, solved.input_note))
}

/// Integrates (f, g) to depth and makes the report.
fn integrate(
    config: &SolveConfig,
    solved: &mut Solved,
    f: Image,
    g: Image,
    started: Instant,
) -> Result<(Depth, SolveReport)> {
    let integrate_started = Instant::now();
    let depth = solved.planner.depth_from_fg(f, g, &solved.mask)?;
    let integrate_seconds = integrate_started.elapsed().as_secs_f64();
    let report = report(config, solved, &depth, integrate_seconds, started);
    Ok((depth, report))
}

/// The report of a solve.
fn report(
    config: &SolveConfig,
    solved: &Solved,
    depth: &Depth,
    integrate_seconds: f64,
    started: Instant,
) -> SolveReport {
    let (shape, lighting, brdf) = (&solved.shape, &solved.lighting, &solved.brdf);
    let s = &shape.solution;
    let boundary_kind = solved.boundary_kind;
    let method = shape.method;
    let unit = method.iteration_unit();
    // Not converging is not an error (the values may still be useful), but it is never silent.
    let warning = (!s.converged).then(|| {
        format!(
            "the {method} solve did not converge within max_iter {} {unit}: the last update \
             {:.3e} is above tol {:.3e}; raise max_iter or tol",
            shape.max_iter, s.last_update, config.options.tol
        )
    });
    let record = &config.record;
    let or = |given: &str, canonical: String| {
        if given.is_empty() {
            canonical
        } else {
            given.to_string()
        }
    };
    let direction = lighting.light.direction();
    let singular = &unit[..unit.len() - 1];
    let mut outputs = BTreeMap::from([
        ("normals.npy", "H×W×3 float32 unit normals, (0,0,1) outside the mask".to_string()),
        ("depth.npy", "H×W float32 depth in pixels toward the viewer; lowest masked point 0, 0 outside the mask".to_string()),
        ("depth.png", format!("16-bit depth / {} (the depth range), 0 outside the mask", depth.range)),
        ("normals.png", "8-bit RGB n·0.5+0.5".to_string()),
        ("surface.obj", "triangle mesh of the masked depth, world axes, pixel units".to_string()),
        ("convergence.csv", format!("the largest update of f or g after each {singular}")),
    ]);
    if cfg!(feature = "plots") {
        outputs.insert(
            "convergence.png",
            "convergence.csv as a plot (log10 of the update)".to_string(),
        );
    }
    SolveReport {
        stamp: Stamp::of("solve"),
        conventions: io::conventions_json(),
        input: SolveInput {
            image: config.image.display().to_string(),
            image_info: solved.image_info.clone(),
            width: solved.mask.width(),
            height: solved.mask.height(),
            mask: config
                .mask
                .as_ref()
                .map(|p| p.display().to_string())
                .or(solved
                    .sidecar
                    .as_ref()
                    .and_then(|s| s.object_mask())
                    .map(|p| p.display().to_string())),
            mask_pixels: solved.mask.count(),
            sidecar: solved.sidecar.as_ref().map(RenderSidecar::to_json),
        },
        parameters: SolveParameters {
            light: or(
                &record.light,
                match config.light {
                    LightChoice::Given(l) => l.to_string(),
                    LightChoice::Estimate => "estimate".to_string(),
                },
            ),
            boundary: or(&record.boundary, boundary_kind.to_string()),
            brdf: brdf.clone(),
            albedo: solved.albedo_estimate.map_or(brdf.albedo, |e| e.value),
            albedo_estimate: solved.albedo_estimate,
            lambda: config.options.lambda,
            method: config.options.method.to_string(),
            method_source: config.method_source,
            tol: config.options.tol,
            max_iter: config.options.max_iter(),
            out: record.out.clone(),
        },
        light: LightReport {
            vector: [direction.x, direction.y, direction.z],
            tilt_deg: lighting.light.tilt_deg(),
            slant_deg: lighting.light.slant_deg(),
            estimated: lighting.estimate.is_some(),
            estimate: lighting.estimate,
            true_light: solved.sidecar.as_ref().and_then(|s| s.light),
        },
        boundary: BoundaryReport {
            kind: boundary_kind,
            occluding_shrink: OCCLUDING_SHRINK,
            limb: s.limb,
        },
        solver: SolverReport {
            method: method.to_string(),
            iterations: s.iterations,
            iteration_unit: unit,
            converged: s.converged,
            warning,
            last_update: s.last_update,
            unknowns: s.unknowns,
            smoothness_energy: s.smoothness_energy,
            brightness_energy: s.brightness_energy,
            globalised: s.globalised,
            energy_per_step: s.energy_history.clone(),
            clipped: solved.clipped,
            seconds: solved.solve_seconds,
        },
        integration: IntegrationSummary {
            method:
                "least-squares Poisson on the mask (conjugate gradients, multigrid-preconditioned)",
            min_nz: config.options.min_nz,
            iterations: depth.report.iterations,
            relative_residual: depth.report.relative_residual,
            converged: depth.report.converged,
            seconds: integrate_seconds,
        },
        outputs,
        depth_range: [0.0, depth.range],
        seconds: started.elapsed().as_secs_f64(),
    }
}

impl CommandReport for SolveRun {
    /// The report, `report.json`.
    const MARKER: &'static str = "report.json";

    /// Writes `normals.npy`/`.png`, `convergence.csv`/`.png`, `depth.npy`/`.png`,
    /// `surface.obj` and the report, [`SolveRun::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        write_normals(dir, &self.shape.solution)?;
        write_convergence(dir, &self.shape, self.report.parameters.tol)?;
        write_depth(dir, &self.depth, &self.mask)?;
        write_report(dir, &self.report)
    }
}

/// `normals.npy` and `normals.png`, written from (f, g) without a grid of normals.
///
/// The files are written one after the other on the calling thread: written on worker
/// threads, their buffers stayed in those threads' allocator arenas and raised the command's
/// peak memory by a few megabytes (`docs/performance.md`).
fn write_normals(dir: &Path, s: &crate::solver::Solution) -> Result<()> {
    let (w, h) = (s.f.width(), s.f.height());
    let normals =
        s.f.data()
            .iter()
            .zip(s.g.data())
            .map(|(&f, &g)| normal_from_fg(f, g));
    let values = normals.flat_map(|n| [n.x, n.y, n.z]);
    io::write_f32(&dir.join("normals.npy"), &[h, w, 3], values)?;
    io::write_rgb_fn(
        &dir.join("normals.png"),
        (w, h),
        BitDepth::Eight,
        None,
        |c, r| {
            let n = s.normal(c, r);
            [0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5]
        },
    )
}

/// `depth.npy`, `depth.png` (scaled by the range, without a grid of the scaled values) and
/// `surface.obj` (its text formatted on the worker threads, [`crate::integrate::write_mesh_obj`]).
fn write_depth(dir: &Path, depth: &Depth, mask: &Mask) -> Result<()> {
    let (z, highest) = (&depth.depth, depth.range);
    io::write_image(&dir.join("depth.npy"), z)?;
    let size = (z.width(), z.height());
    io::write_gray_fn(
        &dir.join("depth.png"),
        size,
        BitDepth::Sixteen,
        None,
        |c, r| {
            let v = *z.get(c, r);
            if highest > 0.0 {
                v / highest
            } else {
                0.0
            }
        },
    )?;
    let obj = dir.join("surface.obj");
    io::write_atomic(&obj, |out| {
        crate::integrate::write_mesh_obj(z, mask, out, &obj)
    })
}

/// `report.json`.
fn write_report(dir: &Path, report: &SolveReport) -> Result<()> {
    let value = serde_json::to_value(report)
        .map_err(|e| Error::Compute(format!("the report cannot be serialised: {e}")))?;
    io::write_json(&dir.join(SolveRun::MARKER), &value)
}

/// `convergence.csv` and, with plots, `convergence.png`: log10 of the largest update against
/// the sweep or cycle, with the tolerance as a reference line.
fn write_convergence(dir: &Path, shape: &Shape, tol: f64) -> Result<()> {
    let method = shape.method;
    let unit = method.iteration_unit();
    let history = &shape.history;
    let mut csv = format!("{},largest_update\n", &unit[..unit.len() - 1]);
    for (i, u) in history.iter().enumerate() {
        csv.push_str(&format!("{},{u:e}\n", i + 1));
    }
    io::write_text(&dir.join("convergence.csv"), &csv)?;
    #[cfg(feature = "plots")]
    {
        use crate::plot::{LinePlot, Series, Ticks};
        let mut plot = LinePlot::new(
            &format!("{method} convergence"),
            &format!("{} (count)", &unit[..unit.len() - 1]),
            "log10 of the largest update of f or g (no unit)",
            (1.0, history.len().max(2) as f64),
        );
        plot.x_ticks = Ticks::Integer;
        plot.reference_y = Some(tol.log10());
        plot.reference_label = format!("tolerance {tol:e}");
        plot.series.push(Series {
            name: method.to_string(),
            points: history
                .iter()
                .enumerate()
                .filter(|(_, u)| **u > 0.0)
                .map(|(i, u)| ((i + 1) as f64, u.log10()))
                .collect(),
        });
        plot.write_png(&dir.join("convergence.png"))?;
    }
    #[cfg(not(feature = "plots"))]
    let _ = tol;
    Ok(())
}

/// The mask at `path` (nonzero = inside), checked against the image.
fn read_mask(path: &Path, config: &SolveConfig, image: &Image) -> Result<Mask> {
    check_mask(io::read_mask(path, config.max_pixels)?, path, config, image)
}

/// `mask` (named `path` in errors) if it has the image's size and a pixel inside.
fn check_mask(mask: Mask, path: &Path, config: &SolveConfig, image: &Image) -> Result<Mask> {
    mask.check_same_size(
        &format!("mask {} is", path.display()),
        image,
        &format!("the image {} is", config.image.display()),
    )?;
    if mask.count() == 0 {
        return Err(Error::invalid(format!(
            "mask {} is empty: no pixel is inside the object",
            path.display()
        )));
    }
    Ok(mask)
}

/// Rim normals read from a `.npy` of the image's size.
fn read_boundary(path: &Path, w: usize, h: usize, max_pixels: usize) -> Result<Boundary> {
    let normals = io::read_normals(path, max_pixels)?;
    let size = (normals.width(), normals.height());
    if size != (w, h) {
        return Err(Error::invalid(size_mismatch(
            &format!("boundary {} is", path.display()),
            size,
            "the image is",
            (w, h),
        )));
    }
    Ok(Boundary::Given(normals))
}
