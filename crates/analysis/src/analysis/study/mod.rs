//! Studies: a grid of stimuli × parameters × slants × priors, run whole or in shards, merged
//! into exactly the files a single run writes.
//!
//! A *grid point* is one picture at one assumed slant: a stimulus with one value for each of
//! its varied parameters. Each point costs one prior sweep; the priors and rotations that the
//! observer then applies to that sweep are cheap and are rows of the same point. Points are
//! numbered in the spec's order (stimuli in order, then their parameters, keys in alphabetical
//! order with the last varying fastest, then the slants), and shard i of n runs the points
//! with number ≡ i (mod n), which spreads expensive stimuli over the shards. Every row starts
//! with its point's number and every computation is deterministic, so the merge, a stable sort
//! of the shards' rows by point, is byte-identical to the unsharded run.
//!
//! The spec is JSON (unknown keys are refused):
//!
//! ```json
//! {
//!   "stimuli": [
//!     {"stimulus": "bumps", "params": {"pattern": ["bumps", "dimples"], "rows": 1, "columns": 1},
//!      "shape": [64, 64], "seed": 0}
//!   ],
//!   "tilts": "0:360:15",
//!   "slants": [45],
//!   "priors": {"tilt": [26], "kappa": [1, 2], "convexity_bias": [0]},
//!   "rotations": "0:360:45",
//!   "noise": 0.05,
//!   "boundary": "flat",
//!   "domain": "image"
//! }
//! ```
//!
//! A parameter given as a list is a grid axis; anything else is held fixed.
//!
//! The parts: [`spec`] reads and checks a spec, [`grid`] expands it into points, [`shard`]
//! picks a shard's points, [`run`] runs them, [`merge`](mod@merge) joins the shards' folders.

pub mod grid;
pub mod merge;
pub mod run;
pub mod shard;
pub mod spec;

pub use crate::io::csv_field;
pub use grid::{Point, MAX_POINTS};
pub use merge::{merge, Merged};
pub use run::StudyOutput;
pub use shard::Shard;
pub use spec::{PriorGrid, StimulusEntry, Study, StudySpec};

/// The file that holds a study folder's report (and marks it as shadelab's).
pub const REPORT: &str = "study.json";
/// The observer's results: one row per point × prior × rotation × token.
pub const RESULTS: &str = "results.csv";
/// The raw sweeps: one row per point × assumed tilt × token.
pub const SWEEP: &str = "sweep.csv";

/// The header of `results.csv`.
pub const RESULTS_HEADER: &str = "point,stimulus,params,slant_deg,prior_tilt_deg,prior_kappa,convexity_bias,rotation_deg,token,p_convex,map_tilt_deg\n";
/// The header of `sweep.csv`.
pub const SWEEP_HEADER: &str =
    "point,stimulus,params,slant_deg,tilt_deg,token,convexity,residual,smoothness,surface_residual,converged\n";
