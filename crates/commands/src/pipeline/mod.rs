//! Every command of the `shadelab` program as a library pipeline: a `Config` built and checked
//! from plain values, a `run(&config, &dyn Progress)` that does the work, and a typed,
//! serialisable `Report`. The command line, the Python module and the browser page call these
//! and nothing else; the command line only parses flags into a `Config`, draws progress and
//! writes what the report says.

pub mod bench;
pub mod benchmark;
pub mod evaluation;
pub mod experiment;
pub mod fading;
pub mod fit;
pub mod gallery;
pub mod lightness;
pub mod observer;
pub mod outline;
mod output;
pub mod perception;
pub mod prior_sweep;
pub mod render;
pub mod solve;
pub mod source;
pub mod study;

pub use output::{CommandReport, Output};
pub use source::{Picture, PictureInfo, PictureSource};
