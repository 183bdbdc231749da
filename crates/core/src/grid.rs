//! A rectangular pixel grid: the one container for images, masks, label maps, depth and normals.
//!
//! Row 0 is the top row of the picture; world y points up, so world y = −row (see
//! `docs/conventions.md`). Data are stored row-major.

use crate::error::{Error, Result};
use crate::message::SizeText;

/// A width × height grid of `T`, stored row-major from the top-left pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

/// A single-channel image of linear luminance (nominally 0..1).
pub type Image = Grid<f64>;
/// A domain mask: `true` inside the object.
pub type Mask = Grid<bool>;
/// A label map: 0 = background, 1..N = named targets.
pub type Labels = Grid<u16>;
/// A linear RGB image (each channel nominally 0..1).
pub type RgbImage = Grid<[f64; 3]>;

/// The Rec. 709 / sRGB luminance weights of R, G and B: every colour-to-gray conversion of
/// shadelab uses them (see `io::LUMINANCE_FORMULA`).
pub const LUMINANCE_WEIGHTS: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The luminance of a linear RGB value, by [`LUMINANCE_WEIGHTS`].
pub fn luminance(rgb: [f64; 3]) -> f64 {
    let [r, g, b] = LUMINANCE_WEIGHTS;
    r * rgb[0] + g * rgb[1] + b * rgb[2]
}

/// The words of every size-mismatch error, `"{what} H px high × W px wide but {other_what} …"`
/// (the axes in words, [`crate::message::SizeText`]): what
/// [`Grid::check_same_size`] says, and the base of messages about a size that is not a grid's.
pub fn size_mismatch(
    what: &str,
    (width, height): (usize, usize),
    other_what: &str,
    (other_width, other_height): (usize, usize),
) -> String {
    format!(
        "{what} {} but {other_what} {}",
        SizeText::Pixels(height, width),
        SizeText::Pixels(other_height, other_width)
    )
}

/// The largest grid shadelab makes unless told otherwise (about 64 megapixels).
pub const DEFAULT_MAX_PIXELS: usize = 64 * 1024 * 1024;

/// Checks that `width × height` is a usable, non-empty size below `max_pixels`, and that the
/// memory of one buffer of that size can be had ([`check_memory`]): every image shadelab
/// reads or makes passes here before its pixels are allocated.
pub fn check_size(width: usize, height: usize, max_pixels: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::invalid(format!(
            "image size {} is empty (both sides must be at least 1 pixel)",
            SizeText::Pixels(height, width)
        )));
    }
    match width.checked_mul(height) {
        Some(n) if n <= max_pixels => check_memory(width, height),
        _ => Err(Error::TooLarge(format!(
            "image size {} exceeds the limit of {max_pixels} pixels",
            SizeText::Pixels(height, width)
        ))),
    }
}

/// The bytes per pixel of the largest single buffer a command makes (a normal map, three
/// float64 a pixel, is 24), with a margin: what [`check_memory`] asks for.
pub const PROBE_BYTES_PER_PIXEL: usize = 32;

/// Checks, before a command allocates its buffers, that one buffer of
/// [`PROBE_BYTES_PER_PIXEL`] bytes for each of `width × height` pixels can be allocated: the
/// memory is reserved (not touched) and given back at once, so that a size the machine cannot
/// hold is an error here rather than an abort half-way. Sizes under 256 MiB are not probed.
///
/// ```
/// assert!(shadelab_core::grid::check_memory(4000, 3000).is_ok());
/// let e = shadelab_core::grid::check_memory(usize::MAX / 2, 2).unwrap_err().to_string();
/// assert!(e.contains("more memory than this machine can give"), "{e}");
/// ```
pub fn check_memory(width: usize, height: usize) -> Result<()> {
    let bytes = width
        .saturating_mul(height)
        .saturating_mul(PROBE_BYTES_PER_PIXEL);
    if bytes < 1 << 28 {
        return Ok(());
    }
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(bytes).map_err(|_| {
        Error::Compute(format!(
            "image size {} needs buffers of {} each, more memory than this machine can give",
            SizeText::Pixels(height, width),
            crate::error::byte_size(bytes as u64)
        ))
    })
}

impl<T: Clone> Grid<T> {
    /// A grid filled with `value`.
    pub fn new(width: usize, height: usize, value: T) -> Self {
        Grid {
            width,
            height,
            data: vec![value; width * height],
        }
    }
}

impl<T: Clone> Grid<T> {
    /// The grid rotated by 180° (pixel (c, r) goes to (w−1−c, h−1−r)).
    pub fn rotated_180(&self) -> Self {
        let mut data = self.data.clone();
        data.reverse();
        Grid {
            width: self.width,
            height: self.height,
            data,
        }
    }
}

impl<T> Grid<T> {
    /// Wraps row-major `data`; fails when its length is not `width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Result<Self> {
        if width.checked_mul(height) != Some(data.len()) {
            return Err(Error::invalid(format!(
                "{} values do not fill a grid {}",
                data.len(),
                SizeText::Pixels(height, width)
            )));
        }
        Ok(Grid {
            width,
            height,
            data,
        })
    }

    /// A grid whose pixel (col, row) is `f(col, row)`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> T) -> Self {
        let mut data = Vec::with_capacity(width * height);
        for row in 0..height {
            for col in 0..width {
                data.push(f(col, row));
            }
        }
        Grid {
            width,
            height,
            data,
        }
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// Whether the grid has no pixels.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Whether `other` has the same width and height.
    pub fn same_size<U>(&self, other: &Grid<U>) -> bool {
        self.width == other.width && self.height == other.height
    }

    /// Checks that `other` has this grid's width and height; otherwise fails with
    /// [`Error::Invalid`] saying `"{what} WxH but {other_what} WxH"`. Each name carries its
    /// verb ("the mask is", "normals are"), so the message reads as a sentence.
    ///
    /// ```
    /// use shadelab::Grid;
    /// let image = Grid::new(3, 2, 0.5);
    /// assert!(image
    ///     .check_same_size("image is", &Grid::new(3, 2, true), "the mask is")
    ///     .is_ok());
    /// let e = image
    ///     .check_same_size("image is", &Grid::new(2, 3, true), "the mask is")
    ///     .unwrap_err();
    /// assert!(matches!(e, shadelab::Error::Invalid(_)));
    /// assert_eq!(e.to_string(), "image is 2 px high × 3 px wide but the mask is 3 px high × 2 px wide");
    /// ```
    pub fn check_same_size<U>(&self, what: &str, other: &Grid<U>, other_what: &str) -> Result<()> {
        if self.same_size(other) {
            return Ok(());
        }
        Err(Error::invalid(size_mismatch(
            what,
            (self.width, self.height),
            other_what,
            (other.width, other.height),
        )))
    }

    /// The pixel at column `col`, row `row` (row 0 at the top). Panics out of bounds.
    pub fn get(&self, col: usize, row: usize) -> &T {
        &self.data[row * self.width + col]
    }

    /// Mutable access to the pixel at (`col`, `row`). Panics out of bounds.
    pub fn get_mut(&mut self, col: usize, row: usize) -> &mut T {
        &mut self.data[row * self.width + col]
    }

    /// The pixel at (`col`, `row`), or `None` outside the grid (signed coordinates).
    pub fn checked(&self, col: isize, row: isize) -> Option<&T> {
        if col < 0 || row < 0 || col as usize >= self.width || row as usize >= self.height {
            None
        } else {
            Some(&self.data[row as usize * self.width + col as usize])
        }
    }

    /// Row-major pixel data.
    pub fn data(&self) -> &[T] {
        &self.data
    }

    /// Mutable row-major pixel data.
    pub fn data_mut(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Consumes the grid, returning its row-major data.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// A grid of the same size with `f` applied to every pixel.
    pub fn map<U>(&self, f: impl FnMut(&T) -> U) -> Grid<U> {
        Grid {
            width: self.width,
            height: self.height,
            data: self.data.iter().map(f).collect(),
        }
    }

    /// Row `row` as a slice.
    pub fn row(&self, row: usize) -> &[T] {
        &self.data[row * self.width..(row + 1) * self.width]
    }
}

impl Grid<f64> {
    /// Smallest and largest value (ignoring NaN); `None` when empty or all NaN.
    pub fn min_max(&self) -> Option<(f64, f64)> {
        let mut it = self.data.iter().copied().filter(|v| !v.is_nan());
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), v| (lo.min(v), hi.max(v))))
    }

    /// Mean of the values where `mask` is true; `None` when the mask is empty.
    pub fn masked_mean(&self, mask: &Mask) -> Option<f64> {
        let (sum, n) = self
            .data
            .iter()
            .zip(mask.data())
            .filter(|(_, &m)| m)
            .fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
        (n > 0).then(|| sum / n as f64)
    }
}

impl Grid<bool> {
    /// Number of pixels set.
    pub fn count(&self) -> usize {
        self.data.iter().filter(|&&m| m).count()
    }
}
