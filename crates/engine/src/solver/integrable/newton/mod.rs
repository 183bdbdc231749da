//! The integrable method's energy E(f, g, z) and its minimisation by Levenberg–Marquardt: the
//! unknowns are the orientations (f, g) and the depth z of the domain's unknown pixels, all
//! moved together by each step. The energy and its pointwise relaxation are in `energy`, its
//! linearised model (the damped Gauss–Newton matrix, assembled for the multigrid
//! preconditioner) in `model`, and the minimiser (the damping, the stretched and soft steps,
//! Anderson acceleration and the final relaxation) in `minimiser`. Why each of those pieces is
//! there, with the measurements that chose them: docs/integrable-notes.md.
//!
//! **Mirror images.** The minimisation is not exactly mirror-equivariant. Its steps are
//! inexact (conjugate gradients to [`CG_TOL`]), preconditioned by block Gauss–Seidel sweeps
//! in row-major order, and ended by relaxing lagging pixels in that order; a mirror reverses
//! the order, so a picture and its mirror image take different steps, and where E is nearly
//! flat along some direction they end at different points. Measured on the bunny lit at tilt
//! 30° slant 40° with the occluding boundary, against its mirror image under tilt −30°:
//! integrable-lm agrees to 2e-6 at 80² and 96², but at 128² differs by up to 0.09 in f or g
//! (26 of 6,623 pixels above 1e-3), at the same mean error (9.118° and 9.117°); nested-lm
//! differs by up to 0.10 at 96² and 0.29 at 128² (256 pixels above 1e-3; 9.109° and 9.118°),
//! and solving its coarse grid to 1e-9 instead of its `LEVEL_TOL` of 1e-4 changes neither.
//! The Ikeuchi–Horn multigrid is held to it by a test
//! (`mirrored_pictures_give_mirrored_solutions`).

use super::super::{Node, CHUNK, PARALLEL_MIN};
use super::aggregation::{Multigrid, Place};
use super::anderson::{Anderson, Restart};
use super::{AngleScale, SIGMA};
use crate::conjugate_gradients::{self, dot, Stop};
use crate::gradient_space::{fg_from_pq, fg_pq_jacobian};
use crate::parallel::prelude::*;
use crate::reflectance::ReflectanceMap;

mod energy;
mod minimiser;
mod model;

pub(super) use energy::Energy;
pub(super) use minimiser::Minimiser;
use minimiser::RELAX;
pub use minimiser::{CG_MAX_ITER, CG_TOL, LM_ANDERSON_DEPTH};
use model::{held, per_item, per_pixel, positive_part, Block, Model, DIAGONAL_FLOOR};

#[cfg(test)]
mod tests;
