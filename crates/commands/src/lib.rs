//! shadelab's commands as library pipelines ([`pipeline`]): for each command a `Config` built
//! valid from plain values, a `run(&config, &dyn Progress)` that does the work, a typed,
//! serialisable `Report` and one writer for its output folder. The command line, the Python
//! module and the teaching page call these and nothing else. This is the top library floor:
//! it stands on all the others (docs/architecture.md).
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod pipeline;

// The floors below, under the module names their code has always used (`crate::grid`, ...).
use shadelab_analysis::{analysis, evaluation, lightness};
use shadelab_core::{
    error, gradient_space, grid, light, message, parallel, progress, random, visual_size,
};
use shadelab_engine::{
    albedo, boundary, imageops, integrate, light_estimation, reconstruct, reflectance, render,
    solver, surface,
};
use shadelab_io as io;
use shadelab_io::{colormap, display, plot};
use shadelab_stimuli as stimulus;
use shadelab_stimuli::gallery;

#[cfg(test)]
mod determinism;
