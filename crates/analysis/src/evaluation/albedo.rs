//! The albedo of a photographed object: the library's rule (`crate::albedo`), which
//! `solve --albedo estimate` uses too, re-exported where the evaluation has always found it.

use crate::error::Result;
use crate::grid::{Image, Mask};

pub use crate::albedo::{
    albedo_with_normals, brightness_quantile, estimate, BRIGHT_QUANTILE, TAIL_BAND, TAIL_SHARE,
};

/// The albedo of a photograph the evaluation divides it by, and how it was found: the
/// library's rule ([`estimate`], what `solve --albedo estimate` does) when `quantile` is
/// [`BRIGHT_QUANTILE`] (the evaluation's default), else that quantile of the brightness on
/// the mask (`eval --albedo-quantile`, a comparison).
pub fn photo_albedo(image: &Image, mask: &Mask, quantile: f64) -> Result<(f64, &'static str)> {
    if quantile == BRIGHT_QUANTILE {
        Ok((
            estimate(image, mask)?.value,
            "the library's rule (the bright tail extrapolated)",
        ))
    } else {
        Ok((
            brightness_quantile(image, mask, quantile)?,
            "quantile of the brightness on the mask",
        ))
    }
}
