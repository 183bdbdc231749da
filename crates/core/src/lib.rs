//! shadelab's core values: images, masks and labels on a pixel grid, lights, sizes in degrees of
//! visual angle, stimulus parameters, errors, progress and cancellation. Every other floor of
//! shadelab stands on these; this crate depends on no other of them (docs/architecture.md).
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used))]

pub mod cancel;
pub mod error;
pub mod gradient_space;
pub mod grid;
pub mod light;
pub mod message;
pub mod parallel;
pub mod params;
pub mod progress;
pub mod random;
pub mod visual_size;
