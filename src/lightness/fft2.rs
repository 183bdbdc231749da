//! A planned 2-D real FFT for linear (zero-padded) convolution of images with kernels of the
//! image's own size.
//!
//! Spectra are stored column-major by horizontal frequency (`spec[fx * my + fy]`) so that the
//! vertical transforms run over contiguous memory. The forward transform skips the all-zero
//! padding rows and the inverse only transforms the rows the caller keeps: both halve the row
//! work of a 2× padded convolution. Every transform of a row or column is independent, so the
//! results do not depend on how rayon splits the work.

use rayon::prelude::*;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};
use std::sync::{Arc, Mutex};

/// Complex numbers of the spectra.
pub(crate) type C64 = Complex<f64>;

/// Columns (or rows) handed to one rayon task: enough to amortise the scheduling.
const BLOCK: usize = 16;

/// The smallest length ≥ `n` whose prime factors are 2, 3, 5 or 7 (fast for RustFFT), even so
/// that the real transform splits in half.
pub(crate) fn fast_len(n: usize) -> usize {
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

/// Forward and inverse plans for an `mx` × `my` real transform.
pub(crate) struct Fft2 {
    mx: usize,
    my: usize,
    nfx: usize,
    r2c: Arc<dyn RealToComplex<f64>>,
    c2r: Arc<dyn ComplexToReal<f64>>,
    col_forward: Arc<dyn Fft<f64>>,
    col_inverse: Arc<dyn Fft<f64>>,
    /// Row spectra between the row and column passes, kept between calls: allocating (and
    /// page-faulting) tens of megabytes per transform would cost more than the transform.
    rows: Mutex<Vec<C64>>,
}

impl Fft2 {
    /// Plans the transforms of an `mx` × `my` grid (`mx` even).
    pub(crate) fn new(mx: usize, my: usize) -> Self {
        let mut real = RealFftPlanner::<f64>::new();
        let mut complex = FftPlanner::<f64>::new();
        Fft2 {
            mx,
            my,
            nfx: mx / 2 + 1,
            r2c: real.plan_fft_forward(mx),
            c2r: real.plan_fft_inverse(mx),
            col_forward: complex.plan_fft_forward(my),
            col_inverse: complex.plan_fft_inverse(my),
            rows: Mutex::new(Vec::new()),
        }
    }

    /// Padded width.
    pub(crate) fn mx(&self) -> usize {
        self.mx
    }

    /// Padded height.
    pub(crate) fn my(&self) -> usize {
        self.my
    }

    /// Number of stored horizontal frequencies (`mx / 2 + 1`).
    pub(crate) fn nfx(&self) -> usize {
        self.nfx
    }

    /// Length of a spectrum buffer.
    pub(crate) fn spectrum_len(&self) -> usize {
        self.nfx * self.my
    }

    /// A zeroed spectrum buffer.
    pub(crate) fn spectrum(&self) -> Vec<C64> {
        vec![C64::new(0.0, 0.0); self.spectrum_len()]
    }

    /// The spectrum of the `w` × `h` row-major `data` placed at the top-left corner of the
    /// padded grid (zeros elsewhere), written into `spec`.
    pub(crate) fn forward(&self, data: &[f64], w: usize, h: usize, spec: &mut [C64]) {
        debug_assert!(w <= self.mx && h <= self.my && data.len() == w * h);
        debug_assert_eq!(spec.len(), self.spectrum_len());
        let (mx, my, nfx) = (self.mx, self.my, self.nfx);
        let mut guard = self.rows.lock().unwrap_or_else(|e| e.into_inner());
        let rows = row_buffer(&mut guard, h * nfx);
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

    /// The inverse transform of `spec` (destroyed), normalised, keeping only the `w` × `h`
    /// window whose top-left corner is (`x0`, `y0`) of the padded grid; written row-major into
    /// `out`.
    pub(crate) fn inverse(
        &self,
        spec: &mut [C64],
        x0: usize,
        y0: usize,
        w: usize,
        h: usize,
        out: &mut [f64],
    ) {
        debug_assert!(x0 + w <= self.mx && y0 + h <= self.my && out.len() == w * h);
        debug_assert_eq!(spec.len(), self.spectrum_len());
        let (mx, my, nfx) = (self.mx, self.my, self.nfx);
        spec.par_chunks_mut(my * BLOCK).for_each_init(
            || vec![C64::new(0.0, 0.0); self.col_inverse.get_inplace_scratch_len()],
            |scratch, cols| self.col_inverse.process_with_scratch(cols, scratch),
        );
        let spec: &[C64] = spec;
        let scale = 1.0 / (mx * my) as f64;
        let mut guard = self.rows.lock().unwrap_or_else(|e| e.into_inner());
        let rows = row_buffer(&mut guard, h * nfx);
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
                        // A real signal has real DC and Nyquist terms; drop the round-off.
                        row[0].im = 0.0;
                        row[nfx - 1].im = 0.0;
                        let _ = self.c2r.process_with_scratch(row, line, scratch);
                        for (o, &v) in out_row.iter_mut().zip(&line[x0..x0 + w]) {
                            *o = v * scale;
                        }
                    }
                },
            );
    }
}

/// The first `len` elements of the kept row buffer, grown when too short.
fn row_buffer(buffer: &mut Vec<C64>, len: usize) -> &mut [C64] {
    if buffer.len() < len {
        buffer.resize(len, C64::new(0.0, 0.0));
    }
    &mut buffer[..len]
}

/// The length-`m` DFT of `values` placed at the start of a zero array: all `m` terms, or the
/// first `m / 2 + 1` when `half`.
pub(crate) fn dft_1d(values: &[f64], m: usize, half: bool) -> Vec<C64> {
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
pub(crate) fn shift_phase(c: f64, m: usize, n: usize) -> Vec<C64> {
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
        let fft = Fft2::new(fast_len(2 * w - 1), fast_len(2 * h - 1));
        let mut spec = fft.spectrum();
        fft.forward(&data, w, h, &mut spec);
        let mut back = vec![0.0; w * h];
        fft.inverse(&mut spec, 0, 0, w, h, &mut back);
        for (a, b) in data.iter().zip(&back) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
    }
}
