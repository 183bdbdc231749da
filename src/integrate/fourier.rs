//! Frankot–Chellappa integration with real FFTs, planned once per size.

use super::check_gradients;
use crate::error::{Error, Result};
use crate::grid::{Grid, Image};
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};
use std::f64::consts::PI;
use std::fmt;
use std::sync::Arc;

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
    row_forward: Arc<dyn RealToComplex<f64>>,
    row_inverse: Arc<dyn ComplexToReal<f64>>,
    column_forward: Arc<dyn Fft<f64>>,
    column_inverse: Arc<dyn Fft<f64>>,
    /// Half spectra (height rows of width/2 + 1), row-major.
    spectrum_x: Vec<Complex<f64>>,
    spectrum_y: Vec<Complex<f64>>,
    row: Vec<f64>,
    column: Vec<Complex<f64>>,
    scratch: Vec<Complex<f64>>,
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
        let mut real = RealFftPlanner::<f64>::new();
        let row_forward = real.plan_fft_forward(width);
        let row_inverse = real.plan_fft_inverse(width);
        let mut complex = FftPlanner::<f64>::new();
        let column_forward = complex.plan_fft_forward(height);
        let column_inverse = complex.plan_fft_inverse(height);
        let scratch_len = row_forward
            .get_scratch_len()
            .max(row_inverse.get_scratch_len())
            .max(column_forward.get_inplace_scratch_len())
            .max(column_inverse.get_inplace_scratch_len());
        let half = width / 2 + 1;
        Ok(FrankotChellappa {
            width,
            height,
            row_forward,
            row_inverse,
            column_forward,
            column_inverse,
            spectrum_x: vec![Complex::new(0.0, 0.0); half * height],
            spectrum_y: vec![Complex::new(0.0, 0.0); half * height],
            row: vec![0.0; width],
            column: vec![Complex::new(0.0, 0.0); height],
            scratch: vec![Complex::new(0.0, 0.0); scratch_len],
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
        if (dz_dx.width(), dz_dx.height()) != (w, h) {
            return Err(Error::invalid(format!(
                "gradient field is {}x{} but the integrator was planned for {w}x{h}",
                dz_dx.width(),
                dz_dx.height()
            )));
        }
        let half = w / 2 + 1;
        // ∂z/∂row = −∂z/∂y, since world y points up.
        self.forward(dz_dx, 1.0, true)?;
        self.forward(dz_dy, -1.0, false)?;
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
                let i = kr * half + kc;
                let denominator = wc * wc + wr * wr;
                self.spectrum_x[i] = if denominator == 0.0 || row_nyquist || col_nyquist {
                    Complex::new(0.0, 0.0)
                } else {
                    let s = self.spectrum_x[i] * wc + self.spectrum_y[i] * wr;
                    // −i·s / denominator.
                    Complex::new(s.im, -s.re) / denominator
                };
            }
        }
        self.inverse()
    }

    /// The half spectrum of `sign`·`field` into `spectrum_x` (`into_x`) or `spectrum_y`.
    fn forward(&mut self, field: &Image, sign: f64, into_x: bool) -> Result<()> {
        let (w, h) = (self.width, self.height);
        let half = w / 2 + 1;
        let spectrum = if into_x {
            &mut self.spectrum_x
        } else {
            &mut self.spectrum_y
        };
        for r in 0..h {
            for (dst, src) in self.row.iter_mut().zip(field.row(r)) {
                *dst = sign * src;
            }
            self.row_forward
                .process_with_scratch(
                    &mut self.row,
                    &mut spectrum[r * half..(r + 1) * half],
                    &mut self.scratch,
                )
                .map_err(|e| Error::Compute(format!("FFT failed: {e}")))?;
        }
        for kc in 0..half {
            for r in 0..h {
                self.column[r] = spectrum[r * half + kc];
            }
            self.column_forward
                .process_with_scratch(&mut self.column, &mut self.scratch);
            for r in 0..h {
                spectrum[r * half + kc] = self.column[r];
            }
        }
        Ok(())
    }

    /// The real image of the half spectrum in `spectrum_x`, normalised.
    fn inverse(&mut self) -> Result<Image> {
        let (w, h) = (self.width, self.height);
        let half = w / 2 + 1;
        for kc in 0..half {
            for r in 0..h {
                self.column[r] = self.spectrum_x[r * half + kc];
            }
            self.column_inverse
                .process_with_scratch(&mut self.column, &mut self.scratch);
            for r in 0..h {
                self.spectrum_x[r * half + kc] = self.column[r];
            }
        }
        let scale = 1.0 / (w * h) as f64;
        let mut depth = Vec::with_capacity(w * h);
        for r in 0..h {
            let line = &mut self.spectrum_x[r * half..(r + 1) * half];
            // The spectrum is Hermitian, so these are real up to rounding; the inverse real FFT
            // insists on exact zeros.
            line[0].im = 0.0;
            if w % 2 == 0 {
                line[half - 1].im = 0.0;
            }
            self.row_inverse
                .process_with_scratch(line, &mut self.row, &mut self.scratch)
                .map_err(|e| Error::Compute(format!("inverse FFT failed: {e}")))?;
            depth.extend(self.row.iter().map(|v| v * scale));
        }
        Grid::from_vec(w, h, depth)
    }
}
