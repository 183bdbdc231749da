//! Frankot–Chellappa integration with real FFTs, planned once per size.

use super::check_gradients;
use crate::error::{Error, Result};
use crate::grid::{size_mismatch, Grid, Image};
use crate::imageops::fft::{RealFft2, C64};
use std::f64::consts::PI;
use std::fmt;

/// Frankot & Chellappa (1988) integration for one image size: the FFT plans and every buffer
/// are made once by [`FrankotChellappa::new`] and reused by each [`FrankotChellappa::integrate`].
///
/// With A, B the 2-D Fourier transforms of ∂z/∂col and ∂z/∂row and ω the angular frequencies
/// (radians per pixel), the integrable surface closest to the field in least squares is
/// Z = −i(ω_col·A + ω_row·B)/(ω_col² + ω_row²), with Z(0, 0) = 0 (zero mean depth). A Nyquist
/// frequency (on an even side) has no sign, so no derivative, and its coefficient is set to 0.
/// The field is taken as periodic: for an object with a silhouette use
/// [`super::integrate_gradients`] instead.
pub struct FrankotChellappa {
    width: usize,
    height: usize,
    fft: RealFft2,
    /// Half spectra (width/2 + 1 columns of height values), column-major.
    spectrum_x: Vec<C64>,
    spectrum_y: Vec<C64>,
    /// −∂z/∂y, i.e. ∂z/∂row.
    dz_drow: Vec<f64>,
    scratch: Vec<C64>,
}

impl fmt::Debug for FrankotChellappa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FrankotChellappa")
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

impl FrankotChellappa {
    /// Plans the transforms for `width` × `height` fields.
    pub fn new(width: usize, height: usize) -> Result<Self> {
        crate::grid::check_size(width, height, crate::grid::DEFAULT_MAX_PIXELS)?;
        let fft = RealFft2::new(width, height);
        Ok(FrankotChellappa {
            width,
            height,
            spectrum_x: fft.spectrum(),
            spectrum_y: fft.spectrum(),
            dz_drow: vec![0.0; width * height],
            scratch: fft.scratch(),
            fft,
        })
    }

    /// Width of the fields this integrator takes.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height of the fields this integrator takes.
    pub fn height(&self) -> usize {
        self.height
    }

    /// The depth (zero mean, periodic least squares) whose slopes are closest to
    /// (`dz_dx`, `dz_dy`), in world axes (see the module documentation).
    pub fn integrate(&mut self, dz_dx: &Image, dz_dy: &Image) -> Result<Image> {
        check_gradients(dz_dx, dz_dy)?;
        let (w, h) = (self.width, self.height);
        let size = (dz_dx.width(), dz_dx.height());
        if size != (w, h) {
            return Err(Error::invalid(size_mismatch(
                "gradient field is",
                size,
                "the integrator was planned for",
                (w, h),
            )));
        }
        let half = w / 2 + 1;
        // ∂z/∂row = −∂z/∂y, since world y points up.
        for (d, v) in self.dz_drow.iter_mut().zip(dz_dy.data()) {
            *d = -v;
        }
        self.fft
            .forward(dz_dx.data(), w, h, &mut self.spectrum_x, &mut self.scratch);
        self.fft
            .forward(&self.dz_drow, w, h, &mut self.spectrum_y, &mut self.scratch);
        for kr in 0..h {
            let signed_r = if kr <= h / 2 {
                kr as f64
            } else {
                kr as f64 - h as f64
            };
            let row_nyquist = h % 2 == 0 && kr == h / 2;
            let wr = 2.0 * PI * signed_r / h as f64;
            for kc in 0..half {
                let col_nyquist = w % 2 == 0 && kc == w / 2;
                let wc = 2.0 * PI * kc as f64 / w as f64;
                let i = kc * h + kr;
                let denominator = wc * wc + wr * wr;
                self.spectrum_x[i] = if denominator == 0.0 || row_nyquist || col_nyquist {
                    C64::new(0.0, 0.0)
                } else {
                    let s = self.spectrum_x[i] * wc + self.spectrum_y[i] * wr;
                    // −i·s / denominator.
                    C64::new(s.im, -s.re) / denominator
                };
            }
        }
        let mut depth = vec![0.0; w * h];
        self.fft.inverse(
            &mut self.spectrum_x,
            0,
            0,
            w,
            h,
            &mut depth,
            &mut self.scratch,
        );
        Grid::from_vec(w, h, depth)
    }
}
