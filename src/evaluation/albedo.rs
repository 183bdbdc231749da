//! The albedo of a photographed object: the library's rule ([`crate::albedo`]), which
//! `solve --albedo estimate` uses too, re-exported where the evaluation has always found it.

pub use crate::albedo::{
    albedo_from_brightest, albedo_with_normals, brightness_quantile, BRIGHT_QUANTILE,
};
