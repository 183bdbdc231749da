//! shadelab: shape-from-shading stimuli and analyses for vision science.
//!
//! The crate has two halves that share one core:
//! - a **stimulus generator** that renders the shading illusions of the literature as exact,
//!   reproducible psychophysics stimuli (linear luminance, sizes in degrees of visual angle,
//!   target masks, every parameter recorded), and
//! - an **analyzer**: a shape-from-shading engine (reflectance maps in p–q and f–g space,
//!   occluding-boundary conditions, the Ikeuchi–Horn iteration, integration to depth) and the
//!   analyses built on it.
//!
//! Conventions (see `docs/conventions.md`): x = image right, y = image up, z = toward the
//! viewer; pixel row 0 is the top row. p = −∂z/∂x, q = −∂z/∂y. Lights are unit vectors toward
//! the light, or tilt/slant in degrees with tilt 0 = from above and +90 = from the left.
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod analysis;
pub mod boundary;
pub mod colormap;
pub mod error;
pub mod evaluation;
pub mod gallery;
pub mod gradient_space;
pub mod grid;
pub mod imageops;
pub mod integrate;
pub mod io;
pub mod light;
pub mod light_estimation;
pub mod lightness;
pub mod parallel;
pub mod params;
pub mod pipeline;
pub mod progress;
pub mod random;
pub mod reconstruct;
pub mod reflectance;
pub mod render;
pub mod solver;
pub mod stimulus;
pub mod surface;
pub mod visual_size;

pub use boundary::Boundary;
pub use error::{Error, Result};
pub use grid::{Grid, Image, Labels, Mask, RgbImage};
pub use light::Light;
pub use progress::{NoProgress, Progress};
pub use reconstruct::{
    DepthMethod, Lighting, NonConvergence, Problem, ReconstructOptions, Reconstruction,
    Reconstructor,
};
pub use reflectance::{Lambertian, ReflectanceMap};
pub use solver::{Method, SolveOptions};
