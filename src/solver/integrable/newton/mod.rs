//! The integrable method's energy E(f, g, z) and its minimisation by Levenberg–Marquardt: the
//! unknowns are the orientations (f, g) and the depth z of the domain's unknown pixels, all
//! moved together by each step. The energy and its pointwise relaxation are in `energy`, its
//! linearised model (the damped Gauss–Newton matrix, assembled for the multigrid
//! preconditioner) in `model`, and the minimiser (the damping, the stretched and soft steps,
//! Anderson acceleration and the final relaxation) in `minimiser`. Why each of those pieces is
//! there, with the measurements that chose them: docs/integrable-notes.md.

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
