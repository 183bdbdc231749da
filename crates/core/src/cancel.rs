//! Stopping a run early: one process-wide flag that a front end raises (the command line does
//! on Ctrl-C, SIGTERM or SIGHUP) and the library's long loops check.
//!
//! The flag is global rather than a method of [`crate::progress::Progress`] for two reasons: a signal
//! handler can reach only global state, and many loops that must stop (the solver's sweeps,
//! the gallery's workers, every file write) receive no `Progress`. One process has one Ctrl-C,
//! so one flag is enough.
//!
//! Workers only look at the flag and stop; they never clean up. A stopped pipeline returns
//! [`Error::Cancelled`] to the thread that called it, whose temporaries (an
//! `io::AtomicDir`, an `io::OutputSet`) are then dropped and removed, so
//! that no partial output ever appears under its final name.
//!
//! ```
//! use shadelab::{cancel, Error};
//! assert!(cancel::check().is_ok());
//! cancel::request();
//! assert!(matches!(cancel::check(), Err(Error::Cancelled)));
//! cancel::reset(); // ready for the next run
//! assert!(!cancel::requested());
//! ```

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks every running loop to stop (safe to call from a signal handler).
pub fn request() {
    REQUESTED.store(true, Ordering::SeqCst);
}

/// Whether a stop was requested.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// [`Error::Cancelled`] when a stop was requested; for loops to end with `?`.
pub fn check() -> Result<()> {
    if requested() {
        Err(Error::Cancelled)
    } else {
        Ok(())
    }
}

/// Lowers the flag (for a front end that goes on after a stopped run, e.g. Python).
pub fn reset() {
    REQUESTED.store(false, Ordering::SeqCst);
}
