//! shadelab: shape-from-shading stimuli and analyses for vision science.
//!
//! Render a sphere under a light, recover its shape from the picture alone, and measure how far
//! the recovered normals are from the render's own:
//!
//! ```
//! use shadelab::stimulus::{sphere, SphereParams};
//! use shadelab::{angular_error, Boundary, Geometry, NoProgress, Problem, ReconstructOptions};
//!
//! let mut params = SphereParams::default();
//! params.lighting.light = "tilt=30,slant=40".parse()?; // from above-left
//! let out = sphere(&params, &Geometry::square(64, 16.0))?;
//! let (image, truth) = (out.image()?, out.surface_layers()?);
//! let map = params.lighting.reflectance()?; // the render's own light and reflectance
//! let problem = Problem { image, mask: &truth.mask, boundary: &Boundary::Occluding, reflectance: map.as_ref() };
//! let shape = problem.reconstruct(ReconstructOptions::default(), &NoProgress)?;
//! let error = angular_error(&shape.normals(), &truth.normals, &truth.mask)?;
//! assert!(error.mean_deg < 10.0, "{error:?}");
//! # Ok::<(), shadelab::Error>(())
//! ```
//!
//! The crate has two halves that share one core:
//! - a **stimulus generator** ([`stimulus`]) that renders the shading illusions of the literature
//!   as exact, reproducible psychophysics stimuli (linear luminance, sizes in degrees of visual
//!   angle, target masks, every parameter recorded), each with a typed parameter struct
//!   ([`stimulus::BumpsParams`], …) and a typed function, and the generic name-based interface
//!   the command line, specs and sidecars use ([`stimulus::generate`]);
//! - an **analyzer**: a shape-from-shading engine (reflectance maps in p–q and f–g space,
//!   occluding-boundary conditions, the Ikeuchi–Horn iteration, integration to depth), one
//!   reconstruction pipeline over it ([`Reconstructor`]), and the analyses built on it
//!   (perception under assumed lights and priors, lightness models).
//!
//! Every command of the `shadelab` program is a library pipeline in [`pipeline`]: a `Config` of
//! plain values → `run(&config, &dyn Progress)` → a typed, serialisable report, and a writer for
//! its output folder. `docs/architecture.md` draws the modules and the one-way data flow
//! stimulus → image → reconstruction → analysis → report.
//!
//! Conventions (see `docs/conventions.md`): x = image right, y = image up, z = toward the
//! viewer; pixel row 0 is the top row. p = −∂z/∂x, q = −∂z/∂y. Lights are unit vectors toward
//! the light, or tilt/slant in degrees with tilt 0 = from above and +90 = from the left.
//!
//! Features: `cli` (the command line), `plots` (figures), `parallel` (worker threads), all on by
//! default; `--no-default-features` builds the core alone, with the same bytes on one thread.
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub use shadelab_commands::pipeline;
pub use shadelab_core::cancel;
/// A display in physical units (gamma, cd/m², quantisation: [`shadelab_io::display`]), and how
/// linear values reach a screen without a measured display (a gamma alone), or from a display
/// described by a JSON value (the Python module's dicts) as [`read_display`] reads a file.
pub mod display {
    pub use shadelab_io::display::*;
    pub use shadelab_io::{display_from_value, display_rgba8, stimulus_codes};
}
pub use shadelab_stimuli as stimulus;

// The floors the names below come from, under their module names.
use shadelab_analysis::{evaluation, lightness};
use shadelab_core::{error, gradient_space, grid, light, message, params, progress, visual_size};
use shadelab_engine::{
    albedo, boundary, integrate, light_estimation, reconstruct, reflectance, render, solver,
};
use shadelab_io as io;
use shadelab_io::colormap;

// The core: images, lights, sizes, errors, progress.
pub use error::{nearest_name, Error, Result};
pub use gradient_space::Normal;
pub use grid::{check_size, Grid, Image, Labels, Mask, RgbImage, DEFAULT_MAX_PIXELS};
pub use light::{FrontLight, Light};
pub use message::{Message, Setting, SizeText};
pub use params::{ParamKind, ParamSet, ParamSpec, Params};
pub use progress::{NoProgress, Progress};
pub use visual_size::{parse_size, Geometry, SizeRequest, MAX_VISUAL_DEGREES};

// Files: what a picture's pixels mean when read, and how they are written.
pub use colormap::Colormap;
pub use io::{read_display, BitDepth, InputEncoding, Stamp, PROGRAM_VERSION};

// The engine: reflectance, boundary, solver, integration, and the one reconstruction over them.
pub use albedo::{AlbedoEstimate, Saturation};
pub use boundary::{Boundary, LimbTest};
pub use evaluation::metrics::{angular_error, AngularError};
pub use integrate::PoissonOptions;
pub use light_estimation::{EstimateMethod, LightEstimate};
pub use reconstruct::{
    Depth, DepthMethod, IntegrationReport, LightAndAlbedo, NonConvergence, Problem,
    ReconstructOptions, Reconstruction, Reconstructor, Shape,
};
pub use reflectance::{
    BrdfModel, BrdfSpec, Lambertian, ReflectanceMap, Sample as ReflectanceSample,
};
pub use render::RenderOptions;
pub use solver::crease::{CreaseOptions, Smoothness};
pub use solver::{Method, MethodSource, Solution, SolveOptions};

// Stimuli (the catalogue itself is the `stimulus` module).
pub use stimulus::{Pixels, SurfaceLayers, Targets};

// The commands as library pipelines: each command's Config and Report (their parts are in the
// command's `pipeline` module) and the contract they share.
pub use lightness::Model as LightnessModel;
pub use pipeline::bench::{BenchConfig, BenchReport};
pub use pipeline::benchmark::{BenchmarkConfig, BenchmarkReport};
pub use pipeline::evaluation::Config as EvaluationConfig;
pub use pipeline::experiment::{Config as ExperimentConfig, Report as ExperimentReport};
pub use pipeline::fading::{FadingConfig, FadingReport};
pub use pipeline::fit::{Config as FitConfig, Report as FitReport};
pub use pipeline::gallery::{GalleryConfig, GalleryReport};
pub use pipeline::lightness::{LightnessConfig, LightnessReport};
pub use pipeline::observer::{Config as ObserverConfig, Report as ObserverReport};
pub use pipeline::outline::{OutlineConfig, OutlineReport};
pub use pipeline::perception::Config as PerceptionConfig;
pub use pipeline::prior_sweep::{Config as PriorSweepConfig, Report as PriorSweepReport};
pub use pipeline::render::{RenderConfig, RenderReport};
pub use pipeline::solve::{SolveConfig, SolveReport, SolveRun};
pub use pipeline::study::{StudyMergeConfig, StudyMergeReport, StudyRunConfig, StudyRunReport};
pub use pipeline::{CommandReport, Output, Picture, PictureSource};

// Each command's run, under the command's name (the Python module's names).
pub use pipeline::{
    bench::run as bench,
    benchmark::run as benchmark,
    experiment::run as experiment,
    fading::run as fading,
    fit::run as fit_observer,
    gallery::run as gallery,
    lightness::run as lightness,
    observer::run as observer,
    outline::run as outline,
    prior_sweep::run as prior_sweep,
    render::run as render,
    solve::run as solve,
    study::{merge as study_merge, run as study_run},
};
