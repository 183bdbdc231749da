//! Progress of long work, reported to whoever drives the library: the command line draws it as
//! a bar on stderr, Python and the browser may ignore it or show their own.
//!
//! Every long `run` takes a `&dyn Progress`. Calls may come from worker threads, so the methods
//! take `&self` and implementations are `Sync`; every method has a do-nothing default.
//!
//! ```
//! use shadelab::{NoProgress, Progress};
//! use std::sync::atomic::{AtomicU64, Ordering};
//!
//! /// Counts the steps reported.
//! struct Count(AtomicU64);
//! impl Progress for Count {
//!     fn advance(&self, steps: u64) {
//!         self.0.fetch_add(steps, Ordering::Relaxed);
//!     }
//! }
//! let count = Count(AtomicU64::new(0));
//! count.start(3, "working");
//! (0..3).for_each(|_| count.advance(1));
//! assert_eq!(count.0.load(Ordering::Relaxed), 3);
//! NoProgress.start(10, "ignored"); // the silent one
//! ```

use crate::message::Message;

/// A receiver of progress reports. All methods default to doing nothing.
pub trait Progress: Sync {
    /// A stage of `total` steps called `what` begins (a new stage replaces the last).
    fn start(&self, _total: u64, _what: &str) {}
    /// `steps` more steps are done.
    fn advance(&self, _steps: u64) {}
    /// `done` steps of the stage are done.
    fn set_position(&self, _done: u64) {}
    /// An estimate of the seconds the stage has left, made by the work itself from the time
    /// its steps took so far (finite, not negative), where the steps of a stage differ in cost
    /// or their number is not known in advance (a nested-lm solve); a receiver shows it rather
    /// than extrapolate the steps' rate.
    fn time_left(&self, _seconds: f64) {}
    /// A short message about the current step (e.g. the solver's last update).
    fn message(&self, _text: &str) {}
    /// The stage is over; whatever was drawn may be cleared.
    fn finish(&self) {}
    /// A line for the log about what was read, said once, as soon as it is known: what a
    /// picture's sidecar gives and what a given value replaces, how a `.npy`'s integers were
    /// scaled, that an untagged 8-bit picture was decoded as sRGB. Its words may name a
    /// [`Setting`](crate::message::Setting), which each front end names its own way.
    fn note(&self, _line: &Message) {}
}

/// Progress that goes nowhere.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {}
