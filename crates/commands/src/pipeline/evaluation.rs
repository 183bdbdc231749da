//! `eval`: the engine scored on data nobody here made (bunny, Mozart, DiLiGenT, the ball,
//! Beethoven), each case solved as a user would solve it and measured against its truth. The
//! evaluation itself lives in the crate's evaluation module; this is the command's surface: its
//! [`Config`], the [`Record`] that says where results stream to, [`run_into`] and the rows
//! ([`CaseResult`]) it returns, and [`markdown_table`] for docs/evaluation.md.

pub use crate::evaluation::albedo::BRIGHT_QUANTILE;
pub use crate::evaluation::metrics::DepthError;
pub use crate::evaluation::report::{markdown_table, run_into, Record, MARKER};
pub use crate::evaluation::{
    Albedo, CaseResult, Config, Set, BALL_IMAGES, DILIGENT_OBJECTS, SETS, SET_NAMES,
};
