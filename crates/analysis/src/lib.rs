//! shadelab's analyses: perception under assumed lights and priors (prior sweeps, observers,
//! outlines, fits, studies), the lightness models, and the evaluation against measured data. They
//! stand on the engine and the stimuli (docs/architecture.md).
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod analysis;
pub mod evaluation;
pub mod lightness;

// The floors below, under the module names their code has always used (`crate::grid`, ...).
use shadelab_core::{
    error, gradient_space, grid, light, message, parallel, params, progress, random,
};
use shadelab_engine::{
    albedo, boundary, imageops, integrate, light_estimation, reconstruct, reflectance, render,
    solver, surface,
};
use shadelab_io as io;
use shadelab_io::{colormap, plot};
use shadelab_stimuli as stimulus;
