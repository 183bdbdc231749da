//! How a picture's stored codes encode linear luminance, as the user says
//! (`--input-gamma auto|srgb|linear|G`), and the decoding that follows from it and from what
//! the file says of itself (docs/display.md, "Photographs and other pictures").

use crate::error::{Error, Result};
use std::fmt;
use std::str::FromStr;

/// How the codes of an input picture (scaled to 0..1) become linear luminance.
///
/// ```
/// use shadelab::InputEncoding;
/// assert_eq!("srgb".parse::<InputEncoding>()?, InputEncoding::Srgb);
/// assert_eq!("2.2".parse::<InputEncoding>()?, InputEncoding::Gamma(2.2));
/// assert_eq!(InputEncoding::Gamma(2.2).to_string(), "2.2");
/// assert!("0".parse::<InputEncoding>().is_err());
/// # Ok::<(), shadelab::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum InputEncoding {
    /// The file says (a PNG's sRGB or gAMA chunk); without a chunk, a 16-bit PNG, a TIFF, a
    /// `.npy` and any picture shadelab wrote are linear, and an 8-bit PNG or GIF or any JPEG
    /// is sRGB (the web's and cameras' default), which is said in a note.
    #[default]
    Auto,
    /// The sRGB transfer function (IEC 61966-2-1), whatever the file says.
    Srgb,
    /// The codes are linear luminance, whatever the file says.
    Linear,
    /// The file's gamma G: luminance = code^G, whatever the file says.
    Gamma(f64),
}

/// The smallest and largest gamma `--input-gamma G` accepts.
pub const INPUT_GAMMA_RANGE: (f64, f64) = (0.1, 10.0);

impl InputEncoding {
    /// Fails on a gamma that is not a finite number in 0.1..=10.
    pub fn validate(self) -> Result<()> {
        match self {
            InputEncoding::Gamma(g)
                if !(g.is_finite() && (INPUT_GAMMA_RANGE.0..=INPUT_GAMMA_RANGE.1).contains(&g)) =>
            {
                Err(Error::invalid(format!(
                    "input gamma {g} must be a number from {} to {} (luminance = code^G), or \
                     auto, srgb or linear",
                    INPUT_GAMMA_RANGE.0, INPUT_GAMMA_RANGE.1
                )))
            }
            _ => Ok(()),
        }
    }

    /// Whether the user said how to decode (anything but [`InputEncoding::Auto`]): the
    /// file's chunk and a sidecar's recorded gamma are then overridden.
    pub fn is_explicit(self) -> bool {
        self != InputEncoding::Auto
    }

    /// The decoding the user asked for; `None` for [`InputEncoding::Auto`].
    pub(crate) fn explicit(self) -> Option<Decoding> {
        match self {
            InputEncoding::Auto => None,
            InputEncoding::Srgb => Some(Decoding::Srgb),
            InputEncoding::Linear => Some(Decoding::Linear),
            InputEncoding::Gamma(g) => Some(Decoding::Power(g)),
        }
    }
}

impl fmt::Display for InputEncoding {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            InputEncoding::Auto => f.write_str("auto"),
            InputEncoding::Srgb => f.write_str("srgb"),
            InputEncoding::Linear => f.write_str("linear"),
            InputEncoding::Gamma(g) => write!(f, "{g}"),
        }
    }
}

impl FromStr for InputEncoding {
    type Err = Error;

    fn from_str(text: &str) -> Result<InputEncoding> {
        let encoding = match text.trim().to_ascii_lowercase().as_str() {
            "auto" => InputEncoding::Auto,
            "srgb" => InputEncoding::Srgb,
            "linear" => InputEncoding::Linear,
            other => InputEncoding::Gamma(other.parse().map_err(|_| {
                Error::invalid(format!(
                    "{text:?} is not auto, srgb, linear or a gamma G (luminance = code^G)"
                ))
            })?),
        };
        encoding.validate()?;
        Ok(encoding)
    }
}

/// The transfer function applied to codes scaled to 0..1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Decoding {
    /// The codes are the luminance.
    Linear,
    /// luminance = code^p.
    Power(f64),
    /// The sRGB transfer function.
    Srgb,
}

impl Decoding {
    /// The linear value of a code scaled to 0..1.
    pub(crate) fn linear(self, v: f64) -> f64 {
        match self {
            Decoding::Linear => v,
            Decoding::Power(1.0) => v,
            Decoding::Power(p) => v.max(0.0).powf(p),
            Decoding::Srgb if v <= 0.04045 => v / 12.92,
            Decoding::Srgb => ((v + 0.055) / 1.055).powf(2.4),
        }
    }

    /// Whether codes come out as they are.
    pub(crate) fn is_identity(self) -> bool {
        matches!(self, Decoding::Linear | Decoding::Power(1.0))
    }
}
