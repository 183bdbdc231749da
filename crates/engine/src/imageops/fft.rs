//! A planned 2-D real FFT with caller-owned scratch, for periodic transforms of a whole grid
//! and for linear (zero-padded) convolution of images.
//!
//! Plan once for a padded size `mx` × `my` with [`RealFft2::new`]; then
//! [`RealFft2::forward`] and [`RealFft2::inverse`] take `&self`, the data, the spectrum and a
//! scratch buffer of the caller's (from [`RealFft2::scratch`]), as RustFFT's
//! `process_with_scratch` does, so one plan serves any number of threads.
//!
//! Spectra hold the `mx / 2 + 1` non-negative horizontal frequencies and all `my` vertical
//! ones, stored column-major by horizontal frequency (`spec[fx * my + fy]`) so that the
//! vertical transforms run over contiguous memory. The forward transform skips the all-zero
//! padding rows and the inverse only transforms the rows the caller keeps: both halve the row
//! work of a 2× padded convolution. Every transform of a row or column is independent, so the
//! results do not depend on how rayon splits the work.

use crate::parallel::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::fmt;
use std::sync::Arc;

/// Complex numbers of the spectra.
pub type C64 = Complex<f64>;

/// Columns (or rows) handed to one rayon task: enough to amortise the scheduling.
const BLOCK: usize = 16;

/// The smallest length ≥ `n` whose prime factors are 2, 3, 5 or 7 (fast for RustFFT), even so
/// that the real transform splits in half.
///
/// ```
/// use shadelab_engine::imageops::fft::fast_len;
/// assert_eq!(fast_len(2047), 2048);
/// assert_eq!(fast_len(73), 80);
/// assert_eq!(fast_len(1), 2);
/// ```
pub fn fast_len(n: usize) -> usize {
    let mut m = n.max(2);
    loop {
        if m % 2 == 0 {
            let mut r = m;
            for p in [2, 3, 5, 7] {
                while r % p == 0 {
                    r /= p;
                }
            }
            if r == 1 {
                return m;
            }
        }
        m += 1;
    }
}

/// Forward and inverse plans of an `mx` × `my` real 2-D transform.
///
/// ```
/// use shadelab_engine::imageops::RealFft2;
/// // A 3×2 image on a 4×2 grid (one padding column): the DC term is the sum, and the
/// // inverse returns the image.
/// let data = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
/// let fft = RealFft2::new(4, 2);
/// let (mut spec, mut scratch) = (fft.spectrum(), fft.scratch());
/// fft.forward(&data, 3, 2, &mut spec, &mut scratch);
/// assert_eq!(spec[0].re, 21.0);
/// let mut back = [0.0; 6];
/// fft.inverse(&mut spec, 0, 0, 3, 2, &mut back, &mut scratch);
/// for (a, b) in data.iter().zip(&back) {
///     assert!((a - b).abs() < 1e-12);
/// }
/// ```
pub struct RealFft2 {
    mx: usize,
    my: usize,
    nfx: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    col_forward: Arc<dyn Fft<f64>>,
    col_inverse: Arc<dyn Fft<f64>>,
}

impl fmt::Debug for RealFft2 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("RealFft2")
            .field("mx", &self.mx)
            .field("my", &self.my)
            .finish_non_exhaustive()
    }
}

impl RealFft2 {
    /// Plans the transforms of an `mx` × `my` grid (both at least 1).
    pub fn new(mx: usize, my: usize) -> Self {
        let mut real = RealFftPlanner::<f64>::new();
        let mut complex = FftPlanner::<f64>::new();
        RealFft2 {
            mx,
            my,
            nfx: mx / 2 + 1,
            r2c: real.plan_fft_forward(mx),
            c2r: real.plan_fft_inverse(mx),
            col_forward: complex.plan_fft_forward(my),
            col_inverse: complex.plan_fft_inverse(my),
        }
    }

    /// Padded width.
    pub fn mx(&self) -> usize {
        self.mx
    }

    /// Padded height.
    pub fn my(&self) -> usize {
        self.my
    }

    /// Number of stored horizontal frequencies (`mx / 2 + 1`).
    pub fn nfx(&self) -> usize {
        self.nfx
    }

    /// Length of a spectrum buffer (`nfx · my`).
    pub fn spectrum_len(&self) -> usize {
        self.nfx * self.my
    }

    /// A zeroed spectrum buffer.
    pub fn spectrum(&self) -> Vec<C64> {
        vec![C64::new(0.0, 0.0); self.spectrum_len()]
    }

    /// A scratch buffer long enough for any call (the row spectra between the row and column
    /// passes). Keep it between calls: allocating (and page-faulting) tens of megabytes per
    /// transform would cost more than the transform.
    pub fn scratch(&self) -> Vec<C64> {
        self.spectrum()
    }

    /// The spectrum of the `w` × `h` row-major `data` placed at the top-left corner of the
    /// padded grid (zeros elsewhere), written into `spec`. `scratch` holds at least `h · nfx`
    /// values.
    pub fn forward(&self, data: &[f64], w: usize, h: usize, spec: &mut [C64], scratch: &mut [C64]) {
        assert!(w <= self.mx && h <= self.my && data.len() == w * h);
        assert_eq!(spec.len(), self.spectrum_len());
        let (mx, my, nfx) = (self.mx, self.my, self.nfx);
        let rows = &mut scratch[..h * nfx];
        rows.par_chunks_mut(nfx * BLOCK).enumerate().for_each_init(
            || (vec![0.0; mx], self.r2c.make_scratch_vec()),
            |(line, scratch), (block, out)| {
                for (k, out_row) in out.chunks_mut(nfx).enumerate() {
                    let y = block * BLOCK + k;
                    line[..w].copy_from_slice(&data[y * w..(y + 1) * w]);
                    line[w..].fill(0.0);
                    // Lengths are fixed by the plan, so the call cannot fail.
                    let _ = self.r2c.process_with_scratch(line, out_row, scratch);
                }
            },
        );
        let rows: &[C64] = rows;
        // Transpose into column-major order, zero below the data, then transform the columns.
        spec.par_chunks_mut(my * BLOCK).enumerate().for_each_init(
            || vec![C64::new(0.0, 0.0); self.col_forward.get_inplace_scratch_len()],
            |scratch, (block, cols)| {
                let f0 = block * BLOCK;
                let count = cols.len() / my;
                for (y, row) in rows.chunks(nfx).enumerate() {
                    for k in 0..count {
                        cols[k * my + y] = row[f0 + k];
                    }
                }
                for k in 0..count {
                    cols[k * my + h..(k + 1) * my].fill(C64::new(0.0, 0.0));
                }
                self.col_forward.process_with_scratch(cols, scratch);
            },
        );
    }

    /// The inverse transform of `spec` (destroyed), normalised by 1/(mx·my), keeping only the
    /// `w` × `h` window whose top-left corner is (`x0`, `y0`) of the padded grid; written
    /// row-major into `out`. `scratch` holds at least `h · nfx` values.
    #[allow(clippy::too_many_arguments)]
    pub fn inverse(
        &self,
        spec: &mut [C64],
        x0: usize,
        y0: usize,
        w: usize,
        h: usize,
        out: &mut [f64],
        scratch: &mut [C64],
    ) {
        assert!(x0 + w <= self.mx && y0 + h <= self.my && out.len() == w * h);
        assert_eq!(spec.len(), self.spectrum_len());
        let (mx, my, nfx) = (self.mx, self.my, self.nfx);
        spec.par_chunks_mut(my * BLOCK).for_each_init(
            || vec![C64::new(0.0, 0.0); self.col_inverse.get_inplace_scratch_len()],
            |scratch, cols| self.col_inverse.process_with_scratch(cols, scratch),
        );
        let spec: &[C64] = spec;
        let scale = 1.0 / (mx * my) as f64;
        let rows = &mut scratch[..h * nfx];
        out.par_chunks_mut(w * BLOCK)
            .zip(rows.par_chunks_mut(nfx * BLOCK))
            .enumerate()
            .for_each_init(
                || (vec![0.0; mx], self.c2r.make_scratch_vec()),
                |(line, scratch), (block, (out_rows, rows))| {
                    let ya = y0 + block * BLOCK;
                    let count = out_rows.len() / w;
                    for fx in 0..nfx {
                        let col = &spec[fx * my + ya..fx * my + ya + count];
                        for (k, &v) in col.iter().enumerate() {
                            rows[k * nfx + fx] = v;
                        }
                    }
                    for (k, out_row) in out_rows.chunks_mut(w).enumerate() {
                        let row = &mut rows[k * nfx..(k + 1) * nfx];
                        // A real signal has a real DC term, and a real Nyquist term when the
                        // length is even; drop the round-off.
                        row[0].im = 0.0;
                        if mx % 2 == 0 {
                            row[nfx - 1].im = 0.0;
                        }
                        let _ = self.c2r.process_with_scratch(row, line, scratch);
                        for (o, &v) in out_row.iter_mut().zip(&line[x0..x0 + w]) {
                            *o = v * scale;
                        }
                    }
                },
            );
    }
}

/// The length-`m` DFT of `values` placed at the start of a zero array: all `m` terms, or the
/// first `m / 2 + 1` when `half`.
///
/// ```
/// use shadelab_engine::imageops::fft::dft_1d;
/// let s = dft_1d(&[1.0, 1.0], 4, true);
/// assert_eq!(s.len(), 3);
/// assert_eq!((s[0].re, s[2].re), (2.0, 0.0));
/// ```
pub fn dft_1d(values: &[f64], m: usize, half: bool) -> Vec<C64> {
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(m);
    let mut buf = vec![C64::new(0.0, 0.0); m];
    for (b, &v) in buf.iter_mut().zip(values) {
        b.re = v;
    }
    fft.process(&mut buf);
    if half {
        buf.truncate(m / 2 + 1);
    }
    buf
}

/// exp(−2πi·f·c/m) for f = 0..n: the spectrum of a shift by `c` samples (c may be fractional).
///
/// ```
/// use shadelab_engine::imageops::fft::shift_phase;
/// let p = shift_phase(1.0, 4, 2);
/// assert_eq!(p[0].re, 1.0);
/// assert!((p[1].im + 1.0).abs() < 1e-15); // a quarter turn back
/// ```
pub fn shift_phase(c: f64, m: usize, n: usize) -> Vec<C64> {
    (0..n)
        .map(|f| {
            let angle = -2.0 * std::f64::consts::PI * (f as f64) * c / m as f64;
            C64::new(angle.cos(), angle.sin())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_lengths_are_smooth_and_even() {
        assert_eq!(fast_len(2047), 2048);
        assert_eq!(fast_len(2 * 300 - 1), 600);
        assert_eq!(fast_len(2 * 37 - 1), 80);
        assert_eq!(fast_len(1), 2);
    }

    #[test]
    fn forward_then_inverse_is_identity_on_the_data() {
        let (w, h) = (7, 5);
        let data: Vec<f64> = (0..w * h).map(|i| ((i * 37) % 11) as f64 - 4.5).collect();
        for (mx, my) in [(fast_len(2 * w - 1), fast_len(2 * h - 1)), (w, h)] {
            let fft = RealFft2::new(mx, my);
            let (mut spec, mut scratch) = (fft.spectrum(), fft.scratch());
            fft.forward(&data, w, h, &mut spec, &mut scratch);
            let mut back = vec![0.0; w * h];
            fft.inverse(&mut spec, 0, 0, w, h, &mut back, &mut scratch);
            for (a, b) in data.iter().zip(&back) {
                assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            }
        }
    }
}
