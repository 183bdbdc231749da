//! The image-operations toolbox: the small algorithms on [`Grid`](crate::grid::Grid)s that
//! the models, solvers and analyses share, one algorithm a file.
//!
//! - [`parts`](mod@parts): connected parts (4-connected labelling of a mask, or of any graph),
//!   in a fixed visiting order.
//! - [`holes`](mod@holes): a mask with its enclosed holes filled.
//! - [`blur`](mod@blur): separable Gaussian blur with edge-replicating borders.
//! - [`sample`](mod@sample): bilinear sampling at fractional positions.
//! - [`composite`](mod@composite): pictures side by side, and reduction by block averaging.
//! - [`fft`](mod@fft): a planned 2-D real FFT with caller-owned scratch.

pub mod blur;
pub mod composite;
pub mod fft;
pub mod holes;
pub mod parts;
pub mod sample;

pub use blur::gaussian_blur;
pub use composite::{shrink, side_by_side};
pub use fft::RealFft2;
pub use holes::fill_holes;
pub use parts::{graph_parts, parts, Parts, SumOrder};
pub use sample::bilinear;
