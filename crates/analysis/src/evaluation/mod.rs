//! Evaluation of the shape-from-shading engine on data nobody here made.
//!
//! Each case is an image with its light and the object's mask, solved by the engine as a user
//! would run it ([`crate::solver::Solver`] with each of [`Config::methods`]: by default the
//! method `shadelab solve` uses, a row per case and method; a boundary condition from
//! [`crate::boundary`], Lambertian reflectance, then [`crate::integrate`] to depth), and
//! measured against the truth the data set has:
//!
//! - **bunny**: the Stanford bunny mesh rasterised (its interpolated vertex normals are the
//!   truth, as is its depth) and rendered under several lights;
//! - **mozart**: the survey's depth map (holes filled, see [`holes`]), its finite-difference
//!   normals rendered and solved; depth error against the true depth;
//! - **diligent**: the true normals of the nine DiLiGenT objects rendered as max(n·l, 0)
//!   under one chosen light;
//! - **ball**: photographs of the DiLiGenT ball under calibrated lights, with its true
//!   normals; the albedo is estimated from the image ([`albedo`]);
//! - **beethoven**: photographs without truth: only the shading residual is measured.
//!
//! Rendered images have albedo 1 and no ambient light, and the solver is told the light and
//! the albedo; every image is cropped to its object ([`crop`]) first. The numbers are in
//! [`case::CaseResult`]; [`report::markdown_table`] makes the table and [`pictures`] the
//! picture of each case.

pub mod albedo;
pub mod case;
pub mod crop;
pub mod datasets;
pub mod holes;
pub mod metrics;
pub mod pictures;
pub mod report;

pub use case::{solve_case, Albedo, Case, CaseOutput, CaseResult};
pub use datasets::{Set, BALL_IMAGES, DILIGENT_OBJECTS, SETS, SET_NAMES};

use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{Grid, Image, Mask, RgbImage};
use crate::light::{FrontLight, Light};
use crate::parallel::prelude::*;
use crate::progress::Progress;
use crate::reflectance::Lambertian;
use crate::render::{render, RenderOptions};
use crate::solver::{Method, MethodSource, SolveOptions};
use crate::surface::Surface;
use crop::Crop;
use datasets::Photo;
use serde_json::{json, Value};
use std::path::PathBuf;

/// Pixels kept around the object's bounding box when cropping.
pub const CROP_MARGIN: usize = 2;

/// What to evaluate, and how.
#[derive(Debug, Clone)]
pub struct Config {
    /// The data folder.
    pub data: PathBuf,
    /// The sets to run, in this order.
    pub sets: Vec<Set>,
    /// Side of the square frame the bunny is rasterised into, in pixels.
    pub bunny_size: usize,
    /// The lights the bunny is rendered under.
    pub bunny_lights: Vec<FrontLight>,
    /// The lights the Mozart depth map is rendered under.
    pub mozart_lights: Vec<FrontLight>,
    /// The DiLiGenT objects to run.
    pub diligent_objects: Vec<String>,
    /// The light the DiLiGenT normals are rendered under.
    pub diligent_light: FrontLight,
    /// The ball photographs to run (names without `.png`).
    pub ball_images: Vec<String>,
    /// The boundary conditions the ball and Mozart are solved with, each giving a row: the
    /// two sets where the choice is open (see [`default_boundary`]).
    pub compared_boundaries: Vec<Boundary>,
    /// The boundary conditions the bunny, the DiLiGenT objects and Beethoven (objects seen
    /// whole against a background) are solved with, each giving a row: by default
    /// [`default_boundary`] (occluding) and the limb condition, which differ where the
    /// outline's shading rules out a limb.
    pub object_boundaries: Vec<Boundary>,
    /// One boundary condition for every case; `None`: [`Config::object_boundaries`] for the
    /// bunny, DiLiGenT and Beethoven, [`Config::compared_boundaries`] for the ball and Mozart.
    pub boundary: Option<Boundary>,
    /// How a photograph's albedo is found ([`albedo::photo_albedo`]): the library's rule at
    /// [`albedo::BRIGHT_QUANTILE`] (the default), else this quantile of its brightness.
    pub albedo_quantile: f64,
    /// Divide the ball photographs by the albedo their true normals give instead of the
    /// estimate: not a user's situation, a reference for how much the estimate costs.
    pub ball_albedo_from_truth: bool,
    /// The solver's parameter λ (its method, tolerance and cap are set per method by
    /// [`Config::options_for`]).
    pub options: SolveOptions,
    /// The methods every case is solved with, a row each, in this order.
    pub methods: Vec<Method>,
    /// Whether [`Config::methods`] were asked for or are the default
    /// ([`Method::SOLVE_DEFAULT`]); recorded in the report's settings.
    pub method_source: MethodSource,
    /// The tolerance for every method; `None`: each method's default
    /// ([`Method::default_tol`]).
    pub tol: Option<f64>,
    /// The cap of iterations for every method; `None`: each method's default
    /// ([`Method::default_max_iter`]).
    pub max_iter: Option<usize>,
}

/// The solver parameters of the evaluation: the defaults of `shadelab solve` (λ = 1; the
/// method, tolerance and cap are set per method, [`Config::options_for`]).
pub fn default_options() -> SolveOptions {
    SolveOptions::default()
}

/// The most multigrid cycles a case may take: `shadelab solve`'s default.
pub const MAX_CYCLES: usize = crate::solver::MULTIGRID_MAX_CYCLES;

/// The boundary condition of the bunny, the DiLiGenT objects and Beethoven unless told
/// otherwise: the occluding contour, since each is an object seen whole against a background.
/// The ball and Mozart are solved with each of [`Config::compared_boundaries`] instead: the
/// ball because which condition suits a photograph is the question users ask, Mozart because
/// its edge is partly where the scan ends (a cliff 24 to 69 pixels high, whose finite-
/// difference normals are not edge-on) rather than where the surface turns away; the limb
/// condition ([`crate::boundary::limb_conditions`]) tells the two apart by the shading.
pub fn default_boundary(_set: Set) -> Boundary {
    Boundary::Occluding
}

impl Config {
    /// Every set with its default lights, objects and images.
    pub fn new(data: impl Into<PathBuf>) -> Result<Config> {
        let light = |t, s| FrontLight::new(Light::from_tilt_slant(t, s)?);
        Ok(Config {
            data: data.into(),
            sets: SETS.to_vec(),
            bunny_size: 256,
            bunny_lights: vec![
                FrontLight::FRONT,
                light(0.0, 30.0)?,
                light(90.0, 45.0)?,
                light(-135.0, 60.0)?,
            ],
            // The two lights of the survey's Mozart images: (0, 0, 1) and (1, 0, 1).
            mozart_lights: vec![
                FrontLight::FRONT,
                FrontLight::new(Light::from_vector(1.0, 0.0, 1.0)?)?,
            ],
            diligent_objects: DILIGENT_OBJECTS.iter().map(|s| s.to_string()).collect(),
            diligent_light: light(0.0, 30.0)?,
            ball_images: BALL_IMAGES.iter().map(|s| s.to_string()).collect(),
            compared_boundaries: vec![Boundary::Occluding, Boundary::Free, Boundary::Limb],
            object_boundaries: vec![default_boundary(Set::Bunny), Boundary::Limb],
            boundary: None,
            albedo_quantile: albedo::BRIGHT_QUANTILE,
            ball_albedo_from_truth: false,
            options: default_options(),
            // The method `shadelab solve` uses, as a user would solve: a row per case. The
            // table of docs/evaluation.md names its methods with `--method`.
            methods: vec![Method::SOLVE_DEFAULT],
            method_source: MethodSource::Default,
            tol: None,
            max_iter: None,
        })
    }

    /// The solver's parameters for `method`: λ of [`Config::options`], the tolerance
    /// [`Config::tol`] and the cap [`Config::max_iter`] or the method's defaults.
    pub fn options_for(&self, method: Method) -> SolveOptions {
        SolveOptions {
            method,
            tol: self.tol.unwrap_or(method.default_tol()),
            max_iter: self.max_iter.unwrap_or(method.default_max_iter()),
            ..self.options
        }
    }

    /// Checks the parameters, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        if self.methods.is_empty() {
            return Err(Error::invalid("no solver method chosen"));
        }
        for &m in &self.methods {
            self.options_for(m).validate()?;
        }
        if !(16..=4096).contains(&self.bunny_size) {
            return Err(Error::invalid(format!(
                "bunny size {} must be from 16 to 4096 pixels",
                self.bunny_size
            )));
        }
        for o in &self.diligent_objects {
            if !DILIGENT_OBJECTS.contains(&o.as_str()) {
                return Err(Error::unknown("DiLiGenT object", o, DILIGENT_OBJECTS));
            }
        }
        for i in &self.ball_images {
            if !BALL_IMAGES.contains(&i.as_str()) {
                return Err(Error::unknown("ball image", i, BALL_IMAGES));
            }
        }
        if !(self.albedo_quantile > 0.0 && self.albedo_quantile <= 1.0) {
            return Err(Error::invalid(format!(
                "albedo quantile {} must be in (0, 1]",
                self.albedo_quantile
            )));
        }
        if self.sets.is_empty() {
            return Err(Error::invalid("no evaluation set chosen"));
        }
        Ok(())
    }

    /// The number of rows [`run`] will give: each case once per method.
    pub fn case_count(&self) -> usize {
        let compared = self.boundaries_compared().len();
        let objects = self.boundaries_of_objects().len();
        self.methods.len()
            * self
                .sets
                .iter()
                .map(|s| match s {
                    Set::Bunny => self.bunny_lights.len() * objects,
                    Set::Mozart => self.mozart_lights.len() * compared,
                    Set::Diligent => self.diligent_objects.len() * objects,
                    Set::Ball => self.ball_images.len() * compared,
                    Set::Beethoven => datasets::BEETHOVEN_IMAGES.len() * objects,
                })
                .sum::<usize>()
    }

    /// The boundary conditions the ball and Mozart are solved with.
    pub fn boundaries_compared(&self) -> Vec<Boundary> {
        match &self.boundary {
            Some(b) => vec![b.clone()],
            None => self.compared_boundaries.clone(),
        }
    }

    /// The boundary conditions the bunny, the DiLiGenT objects and Beethoven are solved with.
    pub fn boundaries_of_objects(&self) -> Vec<Boundary> {
        match &self.boundary {
            Some(b) => vec![b.clone()],
            None => self.object_boundaries.clone(),
        }
    }

    /// Everything that determines the numbers, for the JSON report.
    pub fn describe(&self) -> Value {
        let lights =
            |ls: &[FrontLight]| -> Vec<Value> { ls.iter().map(|l| light_json(l)).collect() };
        json!({
            "sets": self.sets.iter().map(|s| s.name()).collect::<Vec<_>>(),
            "bunny": {
                "mesh": datasets::BUNNY_MESH,
                "size_px": self.bunny_size,
                "fill": 0.85,
                "view": "front (the mesh's own axes)",
                "normals": "interpolated area-weighted vertex normals",
                "lights": lights(&self.bunny_lights),
            },
            "mozart": {
                "lights": lights(&self.mozart_lights),
                "normals": "central finite differences of the depth (one-sided at the edge)",
                "holes": "background pixels enclosed by the object are filled by Laplace interpolation, solved on, and left out of the errors",
            },
            "diligent": {
                "objects": self.diligent_objects,
                "light": light_json(&self.diligent_light),
                "image": "max(n·l, 0) of the true normals (albedo 1)",
            },
            "ball": {
                "images": self.ball_images,
                "boundaries": self.boundaries_compared().iter().map(Boundary::name).collect::<Vec<_>>(),
                "gray": "each channel divided by intensity_rgb, then Y = 0.2126 R + 0.7152 G + 0.0722 B",
                "albedo": if self.ball_albedo_from_truth {
                    "least squares with the true normals (reference only)".to_string()
                } else {
                    format!("quantile {} of the gray image on the mask, image then clipped at 1", self.albedo_quantile)
                },
            },
            "beethoven": {
                "images": datasets::BEETHOVEN_IMAGES,
                "gray": "8-bit value / 255 / the light's relative intensity",
                "albedo": format!("quantile {} of the image on the mask, image then clipped at 1", self.albedo_quantile),
            },
            "boundary": {
                "bunny, diligent, beethoven": self.boundaries_of_objects().iter().map(Boundary::name).collect::<Vec<_>>(),
                "mozart, ball": self.boundaries_compared().iter().map(Boundary::name).collect::<Vec<_>>(),
            },
            "occluding_shrink": crate::boundary::OCCLUDING_SHRINK,
            "solver": {
                "methods": self.methods.iter().map(Method::to_string).collect::<Vec<_>>(),
                "methods_source": self.method_source,
                "lambda": self.options.lambda,
                "tol": self.methods.iter().map(|&m| (m.to_string(), Value::from(self.options_for(m).tol))).collect::<serde_json::Map<_, _>>(),
                "max_iter": self.methods.iter().map(|&m| (m.to_string(), Value::from(self.options_for(m).max_iter))).collect::<serde_json::Map<_, _>>(),
                "reflectance": "Lambertian, albedo 1 (images divided by the albedo), no ambient",
            },
            "integration": {
                "method": "least-squares Poisson on the mask",
                "min_nz": crate::integrate::DEFAULT_MIN_NZ,
            },
            "crop_margin_px": CROP_MARGIN,
            "normal_error": "angle between recovered and true unit normals, degrees, on the object's mask",
            "depth_error": "RMS of truth − (scale·depth + offset) after a least-squares fit of scale and offset, pixels and % of the true depth range on the mask",
            "residual": "mean |R(n) − I| on the mask, in units of the albedo",
            "seconds": "solve + integration, excluding loading and rendering",
        })
    }
}

fn light_json(l: &Light) -> Value {
    let d = l.direction();
    json!({ "vector": [d.x, d.y, d.z], "tilt_deg": l.tilt_deg(), "slant_deg": l.slant_deg() })
}

/// A light as the table shows it.
pub fn light_label(light: &Light) -> String {
    let slant = light.slant_deg();
    if slant < 0.05 {
        "frontal".into()
    } else {
        format!("tilt {:.0}°, slant {:.0}°", light.tilt_deg(), slant)
    }
}

/// Runs the evaluation: every case solved by each of [`Config::methods`], a row each (the
/// methods' rows of a case one after the other), a few cases' rows at a time on the worker
/// threads (`CASE_BATCH`). `progress` is told the rows done as each row is handed on, in
/// order (a stage of one step per row; its message the label of the first case being solved); `picture` receives each
/// row's picture ([`pictures::case_panel`]) with a file name for it (the case's, with
/// `-<method>` added for every method but multigrid), when `want_pictures` is set.
/// Fails before any work when a file is missing ([`datasets::check_files`]).
pub fn run(
    config: &Config,
    want_pictures: bool,
    progress: &dyn Progress,
    picture: &mut dyn FnMut(&str, &RgbImage) -> Result<()>,
) -> Result<Vec<CaseResult>> {
    config.validate()?;
    datasets::check_files(
        &config.data,
        &config.sets,
        &config.diligent_objects,
        &config.ball_images,
    )?;
    let total = config.case_count();
    progress.start(total as u64, "evaluating");
    let mut results = Vec::with_capacity(total);
    // The cases are gathered in batches of CASE_BATCH and each batch's rows solved on the
    // worker threads (one row each), then handed on in order.
    let mut pending: Vec<(Case, String)> = Vec::with_capacity(CASE_BATCH);
    let mut solve_batch =
        |pending: &mut Vec<(Case, String)>, results: &mut Vec<CaseResult>| -> Result<()> {
            let rows: Vec<(usize, Method)> = (0..pending.len())
                .flat_map(|i| config.methods.iter().map(move |&method| (i, method)))
                .collect();
            if let Some((case, _)) = pending.first() {
                progress.message(&format!("{} {}", case.object, case.light_label));
            }
            let cases = &pending[..];
            let solved: Vec<Result<(CaseResult, Option<RgbImage>)>> = rows
                .par_iter()
                .map(|&(i, method)| {
                    let case = &cases[i].0;
                    let output = solve_case(case, &config.options_for(method))?;
                    let panel = want_pictures.then(|| pictures::case_panel(case, &output));
                    Ok((output.result, panel))
                })
                .collect();
            for (&(i, method), row) in rows.iter().zip(solved) {
                progress.set_position(results.len() as u64);
                let (result, panel) = row?;
                if let Some(panel) = panel {
                    picture(&method_file_name(&pending[i].1, method), &panel)?;
                }
                results.push(result);
            }
            pending.clear();
            Ok(())
        };
    let mut finish = |case: Case, file: String, results: &mut Vec<CaseResult>| -> Result<()> {
        pending.push((case, file));
        if pending.len() == CASE_BATCH {
            solve_batch(&mut pending, results)?;
        }
        Ok(())
    };
    // The picture of an object's occluding row keeps its name of before the limb rows; the
    // other conditions add theirs.
    let suffix = |boundary: &Boundary| match boundary {
        Boundary::Occluding => String::new(),
        other => format!("-{}", other.name()),
    };
    for &set in &config.sets {
        match set {
            Set::Bunny => {
                let surface = datasets::bunny(&config.data, config.bunny_size)?;
                for light in &config.bunny_lights {
                    for boundary in config.boundaries_of_objects() {
                        let file = format!("bunny-{}{}.png", file_label(light), suffix(&boundary));
                        let case = rendered_case(
                            "bunny",
                            "bunny".into(),
                            &surface,
                            &surface.mask,
                            light.light(),
                            boundary,
                            true,
                        )?;
                        finish(case, file, &mut results)?;
                    }
                }
            }
            Set::Mozart => {
                let m = datasets::mozart(&config.data)?;
                let surface = Surface::from_depth(m.filled.depth.clone(), m.filled.domain.clone())?;
                for light in &config.mozart_lights {
                    for boundary in config.boundaries_compared() {
                        let file = format!("mozart-{}-{}.png", file_label(light), boundary.name());
                        let case = rendered_case(
                            "mozart",
                            "mozart".into(),
                            &surface,
                            &m.measured,
                            light.light(),
                            boundary,
                            true,
                        )?;
                        finish(case, file, &mut results)?;
                    }
                }
            }
            Set::Diligent => {
                for object in &config.diligent_objects {
                    let truth = datasets::diligent_object(&config.data, object)?;
                    let surface = Surface {
                        depth: Grid::new(truth.mask.width(), truth.mask.height(), 0.0),
                        normals: truth.normals,
                        mask: truth.mask,
                    };
                    for boundary in config.boundaries_of_objects() {
                        let file = format!("diligent-{object}{}.png", suffix(&boundary));
                        let case = rendered_case(
                            "diligent",
                            object.clone(),
                            &surface,
                            &surface.mask,
                            config.diligent_light.light(),
                            boundary,
                            false,
                        )?;
                        finish(case, file, &mut results)?;
                    }
                }
            }
            Set::Ball => {
                let ball = datasets::ball(&config.data, &config.ball_images)?;
                let crop = Crop::around(&ball.truth.mask, CROP_MARGIN)?;
                let mask = crop.apply(&ball.truth.mask);
                let normals = crop.apply(&ball.truth.normals);
                let boundaries = config.boundaries_compared();
                for photo in &ball.photos {
                    let input = PhotoInput::new("ball", photo, &crop, &mask, Some(&normals));
                    let fitted =
                        albedo::albedo_with_normals(&input.image, &normals, &mask, &photo.light);
                    let albedo = match (config.ball_albedo_from_truth, fitted) {
                        (true, Some(value)) => Albedo {
                            value,
                            method: "least squares with the true normals (reference only)",
                            with_true_normals: fitted,
                        },
                        _ => {
                            let (value, method) =
                                albedo::photo_albedo(&input.image, &mask, config.albedo_quantile)?;
                            Albedo {
                                value,
                                method,
                                with_true_normals: fitted,
                            }
                        }
                    };
                    for boundary in &boundaries {
                        let file = format!("ball-{}-{}.png", photo.name, boundary.name());
                        finish(input.case(boundary.clone(), &albedo), file, &mut results)?;
                    }
                }
            }
            Set::Beethoven => {
                let b = datasets::beethoven(&config.data)?;
                let crop = Crop::around(&b.mask, CROP_MARGIN)?;
                let mask = crop.apply(&b.mask);
                for photo in &b.photos {
                    let input = PhotoInput::new("beethoven", photo, &crop, &mask, None);
                    let (value, method) =
                        albedo::photo_albedo(&input.image, &mask, config.albedo_quantile)?;
                    let albedo = Albedo {
                        value,
                        method,
                        with_true_normals: None,
                    };
                    for boundary in config.boundaries_of_objects() {
                        let file = format!("beethoven-{}{}.png", photo.name, suffix(&boundary));
                        finish(input.case(boundary, &albedo), file, &mut results)?;
                    }
                }
            }
        }
    }
    solve_batch(&mut pending, &mut results)?;
    progress.finish();
    Ok(results)
}

/// Cases gathered before their rows are solved, on the worker threads, a row each: enough to
/// keep two cores busy when one case's rows take far longer than another's, few enough that the
/// cases held at once (the DiLiGenT objects' are about 13 MB each) stay small. The rows and
/// their order do not depend on it, nor on the thread count; their seconds are those of rows
/// solved side by side.
const CASE_BATCH: usize = 4;

/// A case rendered from true normals: max(n·l, 0) with albedo 1 on `surface`'s mask, cropped
/// to it; errors on `scored`; the depth is truth when `depth_known`.
fn rendered_case(
    set: &'static str,
    object: String,
    surface: &Surface,
    scored: &Mask,
    light: Light,
    boundary: Boundary,
    depth_known: bool,
) -> Result<Case> {
    let map = Lambertian::unit(light);
    let image = render(surface, &map, &RenderOptions::default()).image;
    let crop = Crop::around(&surface.mask, CROP_MARGIN)?;
    Ok(Case {
        set,
        object,
        light_label: light_label(&light),
        image: crop.apply(&image),
        domain: crop.apply(&surface.mask),
        scored: crop.apply(scored),
        light,
        boundary,
        truth_normals: Some(crop.apply(&surface.normals)),
        truth_depth: depth_known.then(|| crop.apply(&surface.depth)),
        albedo: Albedo::known(),
    })
}

/// A photograph's part of its cases: the set, the photograph cropped to its object, the mask
/// and the true normals where known.
struct PhotoInput<'a> {
    set: &'static str,
    photo: &'a Photo,
    image: Image,
    mask: &'a Mask,
    truth_normals: Option<&'a Grid<Normal>>,
}

impl<'a> PhotoInput<'a> {
    /// `photo` of `set` cropped by `crop` (`mask` and `truth_normals` are already cropped).
    fn new(
        set: &'static str,
        photo: &'a Photo,
        crop: &Crop,
        mask: &'a Mask,
        truth_normals: Option<&'a Grid<Normal>>,
    ) -> Self {
        PhotoInput {
            set,
            photo,
            image: crop.apply(&photo.image),
            mask,
            truth_normals,
        }
    }

    /// The case with `boundary`, the photograph divided by `albedo`.
    fn case(&self, boundary: Boundary, albedo: &Albedo) -> Case {
        let light = self.photo.light;
        Case {
            set: self.set,
            object: self.set.into(),
            light_label: format!("{} (slant {:.0}°)", self.photo.name, light.slant_deg()),
            image: crate::albedo::normalise(&self.image, albedo.value),
            domain: self.mask.clone(),
            scored: self.mask.clone(),
            light,
            boundary,
            truth_normals: self.truth_normals.cloned(),
            truth_depth: None,
            albedo: albedo.clone(),
        }
    }
}

/// The picture file of a case solved by `method`: the case's own name for multigrid (the
/// default method, whose pictures the documentation shows), `-<method>` before the extension
/// for any other.
fn method_file_name(file: &str, method: Method) -> String {
    match (method, file.strip_suffix(".png")) {
        (Method::Multigrid, _) | (_, None) => file.to_string(),
        (_, Some(stem)) => format!("{stem}-{method}.png"),
    }
}

/// A light as part of a file name: `frontal`, `tilt0-slant30`.
fn file_label(light: &Light) -> String {
    if light.slant_deg() < 0.05 {
        "frontal".into()
    } else {
        format!("tilt{:.0}-slant{:.0}", light.tilt_deg(), light.slant_deg())
    }
}
