//! A multigrid solver for the Ikeuchi–Horn equations: it reaches the fixed point of the stable
//! Jacobi sweep ([`super::Method::Jacobi`]) with work that grows linearly with the number of
//! pixels.
//!
//! # The equations
//!
//! A fixed point of the Jacobi sweep solves, at every unknown pixel i with k_i domain neighbours,
//!
//! N(u)_i = k_i·u_i − Σ_nb u_nb − 4λ·w_i·(I_i − R(ū_i))·∇R(ū_i) = 0,   ū_i = Σ_nb u_nb / k_i,
//!
//! with u = (f, g), w_i = 1 for lit pixels and 0 in attached shadow: the sweep moves u_i to
//! u_i − N(u)_i / k_i, so the largest |N_i| / k_i is exactly the largest change the next Jacobi
//! sweep would make. That is the convergence test here, so `tol` means what it means for Jacobi.
//! The finest level relaxes N itself by red-black Gauss–Seidel (u_i enters N_i only through
//! k_i·u_i, so the pointwise solve is the Jacobi update applied in place), which is why the
//! answer is Jacobi's fixed point and not that of some other discretisation.
//!
//! # The coarse-grid correction
//!
//! Gauss–Seidel removes rough errors fast and smooth ones slowly; coarser grids remove the smooth
//! ones. The correction is linear (a Newton–multigrid scheme): each cycle linearises N at the
//! current values, dropping the term in (I − R)·∇²R as Gauss–Newton does, which leaves a
//! diffusion–reaction system for the error e,
//!
//! k_i·e_i − Σ_nb e_nb + A_i·e_i = r_i,   A_i = 4λ·w_i·∇R·∇Rᵀ (at ū_i),
//!
//! whose reaction matrix is positive semi-definite. Its coarse versions are solved by a linear
//! W-cycle with exact 2 × 2 pointwise solves, which is robust however large the reaction grows on
//! coarse grids. (A full-approximation scheme, which solves nonlinear problems on the coarse
//! grids, was tried first: on grids of 16 × 16 and coarser its reflectance term dominates so
//! strongly that the coarse problems jumped between solutions and the cycle did not converge.)
//!
//! # The levels
//!
//! Level l+1 has one cell per 2 × 2 block of level l (cell-centred coarsening; odd sides round
//! up). A coarse cell is *fixed* (its correction is zero) if any of its children is fixed, so the
//! Dirichlet ring of an occluding or flat boundary stays closed however thin it is; otherwise
//! *unknown* if any child is unknown; otherwise outside. Coarse cells couple to their domain
//! neighbours with unit weight (the 5-point operator rediscretised at spacing 2^l and scaled by
//! the squared spacing, like the fine one); residuals and reaction matrices are restricted by
//! summing the unknown children, corrections prolongated bilinearly (weights 9, 3, 3, 1 / 16),
//! with a neighbour outside the domain lending the parent's correction (natural boundary) and a
//! fixed one lending zero. Only the black cells receive it: the red half-sweep that begins every
//! post-sweep moves each red unknown to a value computed from its black neighbours alone.
//! Coarsening stops at a level with few unknowns, which is relaxed until it settles.
//!
//! # The schedule
//!
//! The start: problems with at least `NESTED_MIN_UNKNOWNS` unknowns start from a coarse
//! solution (nested iteration, `Multigrid::start_from_coarse_solution`): the same problem on the
//! half-size grid, solved the same way (so recursively from the coarsest grid up) to a loose
//! tolerance, interpolated bilinearly onto the fine unknowns (weights 9, 3, 3, 1 / 16 from the
//! nearest coarse cells, a coarse neighbour that is not an unknown lending the parent's value;
//! the piecewise-constant spread used before left steps that cost a 1024² sphere a cycle, and
//! some oblique lights 10 or more). Smaller problems start from
//! (0, 0) at the unknowns, as Jacobi does. The start only moves the iteration closer; the
//! equations and the convergence test are the fine problem's.
//!
//! Then cycles of one Gauss–Seidel sweep, the residual (checked against `tol` on exactly the
//! values that would be returned), the coarse correction and two more sweeps, until the
//! residual is below `tol` or `max_iter` cycles are done. Every cycle ends with `BAND_SWEEPS`
//! sweeps over the band of unknowns within `BAND_WIDTH` steps of the domain's edge or of the
//! data term's (the terminator; `Multigrid::smooth_band`, local relaxation: the error there is
//! the last to go). A cycle that the last two residuals predict to be the last measures its
//! residual first and restricts only if the test fails. The coarse correction is a W-cycle
//! (`CycleSchedule::W_CYCLE`): every coarser level is visited twice per visit of the level
//! above, each visit with the same pre- and post-sweeps. After a full red-black sweep every black
//! cell sits exactly at its Jacobi target, so the residual is only evaluated on the red half.
//!
//! The equations have more than one fixed point (see below): a solve from the coarse start may
//! settle on a neighbour of the one that Jacobi reaches from (0, 0); the differences are those
//! measured below.
//!
//! # Which fixed point
//!
//! Where a lit pixel's neighbour average faces away from the light, R and ∇R vanish and the data
//! term pulls nowhere, so beside the terminator of an oblique light a range of values are all
//! fixed points. Multigrid and Jacobi can settle on different ones there; over the sphere and the
//! vase at 128² and 256² under oblique light the normals differ by 0.02–0.06° on average (a few
//! pixels by up to a couple of degrees) against Jacobi stopped at the same `tol`
//! (tests/fast_solver.rs), and by 0.005–0.02° against Jacobi run to 1e-8 or 1e-9, whose own
//! answer at `tol` = 1e-6 is still 0.008–0.06° short of that. Without an attached shadow they
//! agree to 0.001°.
//!
//! # Determinism
//!
//! Every sweep updates one colour from the other, so cells of a colour are independent and the
//! work can be split across threads in any way; the only reduction is a maximum, which is exact.
//! The result is bit-identical for any number of threads.

use super::{Posed, Progress, SolveOptions, DIVERGENCE_UPDATE};
use crate::boundary::{BoundaryConditions, Role};
use crate::grid::{Grid, Image};
use crate::parallel::prelude::*;
use crate::reflectance::{Hessian, ReflectanceMap, Sample};

/// The number of domain neighbours k (0–4) of an unknown cell.
const K_BITS: u8 = 0b111;
/// The cell is an unknown.
const UNKNOWN: u8 = 1 << 3;
/// The cell holds a fixed value.
const FIXED: u8 = 1 << 4;
/// Finest level only: the pixel is lit (it has a data term).
const LIT: u8 = 1 << 5;
/// Finest level, while `Multigrid::find_band` runs: the cell is in the band.
const BAND: u8 = 1 << 6;
/// Unknown or fixed: a cell of the domain.
const IN_DOMAIN: u8 = UNKNOWN | FIXED;

/// (f, g), or a correction to them, at one cell.
type Pair = [f64; 2];
/// A symmetric 2 × 2 matrix (a11, a12, a22).
type Sym = [f64; 3];

/// How each cycle visits the levels: sweeps before and after the coarse correction, and how
/// many times the next coarser level is visited per visit of a level (1: a V-cycle, 2: a
/// W-cycle).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct CycleSchedule {
    /// Gauss–Seidel sweeps (each a red and a black half-sweep) before the coarse correction.
    pre_sweeps: usize,
    /// Gauss–Seidel sweeps after the coarse correction.
    post_sweeps: usize,
    /// Visits to the next coarser level per visit of a level.
    coarse_visits: usize,
}

impl CycleSchedule {
    /// The schedule the solver uses: one sweep before, two after, and a W-cycle (two coarse
    /// visits), which the oblique-light problems need to converge at a steady rate.
    const W_CYCLE: CycleSchedule = CycleSchedule {
        pre_sweeps: 1,
        post_sweeps: 2,
        coarse_visits: 2,
    };
}

/// Stop coarsening at a level with at most this many unknowns.
const COARSEST_UNKNOWNS: usize = 64;
/// Sweeps at most on the coarsest level per visit.
const COARSEST_SWEEPS: usize = 100;
/// The coarsest level is relaxed until its largest change falls below this fraction of its
/// largest correction.
const COARSEST_REDUCTION: f64 = 1e-4;
/// Coarse levels with fewer unknowns than this are swept on one thread: the split costs more
/// than it saves (measured on 2 cores: splitting the 256² level of a 1024² solve made it
/// slower, 0.155 s against 0.138 s).
const PARALLEL_MIN_CELLS: usize = 131_072;
/// The same for the finest level, whose sweeps evaluate the reflectance map at every cell and
/// so pay for the split sooner (a 256² solve: 8.3–9.3 ms split, 9.4–9.7 ms not).
const FINE_PARALLEL_MIN_CELLS: usize = 16_384;
/// Gauss–Seidel sweeps over the band beside the domain's and the data term's edges after every
/// cycle (see `Multigrid::smooth_band`).
const BAND_SWEEPS: usize = 4;
/// The band: unknowns within this many steps (through unknowns) of a cell that is not one, or
/// of an unknown whose data term differs (see `Multigrid::find_band`).
const BAND_WIDTH: usize = 4;
/// Nested iteration (see `Multigrid::start_from_coarse_solution`) is used on problems with at
/// least this many unknowns; smaller ones start from (0, 0).
const NESTED_MIN_UNKNOWNS: usize = 1024;
/// The coarse problem of nested iteration is solved to this tolerance (or the caller's, if
/// looser): a start, not the answer.
const NESTED_TOL: f64 = 1e-3;
/// At most this many cycles on the coarse problem of nested iteration.
const NESTED_MAX_CYCLES: usize = 30;
/// A cycle whose residual exceeds the smallest so far by this factor halves the coarse
/// correction; one that falls below the smallest by this factor after such a halving doubles it
/// back, at most [`RESTORES`] times in a solve.
const RISE: f64 = 2.0;
/// How often a halved coarse correction may be doubled back (see [`RISE`]). Once is enough for
/// a passing rise and bounds the cycles a persistent overshoot can waste: over spheres and vases
/// at 128², 256² and 512² under 25 lights, twelve solves whose one rise had halved the
/// correction for good took 10–14 cycles, 7–8 with it restored (none took more), and on the
/// evaluation harvest went from 226 cycles to 124, ball 029 from 31 to 19, each to the same
/// normals within 0.0005°.
const RESTORES: usize = 1;
/// Below this the coarse correction is left out: the cycles are plain Gauss–Seidel sweeps.
const MIN_DAMPING: f64 = 1.0 / 64.0;
/// Cells per parallel work item (whole rows; the split does not affect the result).
const TASK_CELLS: usize = 2_048;

/// Counters of a finished multigrid solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct MultigridStats {
    /// Cycles on the finest level; the last one stops after its residual check when that
    /// passes, so that the values returned are the values checked.
    pub cycles: usize,
    /// The largest change the next Jacobi sweep would make (the Jacobi residual).
    pub residual: f64,
    /// Whether `residual` fell below the tolerance.
    pub converged: bool,
    /// Whether the iteration blew up.
    pub diverged: bool,
    /// Levels used, the finest included.
    pub levels: usize,
    /// Work in units of one finest-level sweep (a coarse level counts a quarter of the one
    /// above; a residual pass counts as a sweep).
    pub work: f64,
}

/// A multigrid solver for one image size: its level hierarchy is allocated once and reused by
/// every solve.
#[derive(Debug, Clone)]
pub(crate) struct Multigrid {
    width: usize,
    height: usize,
    levels: Vec<Level>,
    /// Levels in use for the current problem (≤ levels.len()).
    used: usize,
    /// Work counter (finest-sweep units) of the current solve.
    work: f64,
    /// The most levels to use (tests restrict it to check the pieces).
    max_levels: usize,
    /// The cycle's sweeps and coarse visits (`CycleSchedule::W_CYCLE`).
    schedule: CycleSchedule,
    /// Whether to start from the solution of the half-size problem (nested iteration) rather
    /// than from (0, 0).
    nested: bool,
    /// Sweeps over the band after every cycle (`BAND_SWEEPS`; the tests turn them off).
    band_sweeps: usize,
    /// How often a halved coarse correction may be doubled back (`RESTORES`; the tests turn it
    /// off).
    restores: usize,
    /// The finest level's unknowns beside the domain's edge or the data term's (see
    /// `Multigrid::find_band`), by colour, as padded indices r·wp + c.
    band: [Vec<u32>; 2],
}

impl Multigrid {
    /// A hierarchy for `width` × `height` images, coarsened down to 2 × 2 or less.
    pub(crate) fn new(width: usize, height: usize) -> Multigrid {
        let mut levels = vec![Level::new(width, height, false)];
        let (mut w, mut h) = (width, height);
        while w > 2 || h > 2 {
            w = w.div_ceil(2);
            h = h.div_ceil(2);
            levels.push(Level::new(w, h, true));
        }
        Multigrid {
            width,
            height,
            levels,
            used: 1,
            work: 0.0,
            max_levels: usize::MAX,
            schedule: CycleSchedule::W_CYCLE,
            nested: true,
            band_sweeps: BAND_SWEEPS,
            restores: RESTORES,
            band: [Vec::new(), Vec::new()],
        }
    }
}

mod driver;
mod levels;
mod linearisation;
mod smoother;
mod transfer;

pub(super) use levels::half_size_problem;
use levels::Level;
use linearisation::{Averages, Context, BLOCK};
use smoother::{neighbour_sum, over_rows, track, worst_of, HalfRow};
#[cfg(test)]
use transfer::residual_at;
use transfer::unknown_columns;

#[cfg(test)]
mod tests;
