//! shadelab's shape-from-shading engine: reflectance maps, occluding and other boundaries, the
//! solvers (Ikeuchi–Horn by multigrid, the integrable methods), integration to depth, light and
//! albedo estimation, rendering and the surfaces it renders. It stands on `shadelab-core` and
//! `shadelab-io` (docs/architecture.md).
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod albedo;
pub mod boundary;
pub mod conjugate_gradients;
pub mod imageops;
pub mod integrate;
pub mod light_estimation;
pub mod reconstruct;
pub mod reflectance;
pub mod render;
pub mod solver;
pub mod surface;

// The floors below, under the module names their code has always used (`crate::grid`, ...).
use shadelab_core::{
    cancel, error, gradient_space, grid, light, message, parallel, params, progress,
};
use shadelab_io as io;
