//! The oriented difference-of-Gaussians brightness models: ODOG (Blakeslee & McCourt 1999) and
//! the LODOG and FLODOG variants of Robinson, Hammon & de Sa (2007), with the parameters of the
//! multyscale package's `RHS2007` models, so that outputs agree with multyscale's.
//!
//! The front end is a bank of 6 orientations (0°, 30°, …, 150°) × 7 scales. Scale s has centre
//! space constant 3°·2^(s−6) (octaves up to 3°), centre σ = space constant/√2, and the filter is
//! an isotropic centre Gaussian (σ, σ) minus a surround Gaussian (σ, 2σ) elongated along the
//! filter's orientation, each normalised to unit sum over a grid the size of the image. The
//! image is padded with 0.5 (mid-grey) and convolved in the Fourier domain; each scale is
//! weighted by (its peak frequency)^0.1, normalised to the middle scale.
//!
//! The three models differ in the divisive normalisation:
//! - **ODOG**: each orientation (all scales summed) is divided by its image-wide RMS.
//! - **LODOG**: each orientation is divided by its local RMS in a Gaussian window (σ = 2°).
//! - **FLODOG**: each filter is divided by the local RMS, in a window the size of the filter
//!   (σ = its centre σ), of a mix of the scales of its orientation weighted by a Gaussian of
//!   the scale difference (sdmix = 0.5, the weights being the normal density, unnormalised).
//!
//! The local RMS is sqrt(window ∗ n² + ε) + ε with ε = 10⁻⁶, the window convolution
//! zero-padded, as in multyscale.
//!
//! Speed: the spectra of the six orientation filters (ODOG, LODOG) are computed once per
//! size and resolution; applying the model costs one forward and six inverse real FFTs of twice
//! the image size (plus twelve for the LODOG windows). The filters are symmetric about the
//! grid centre, so each spectrum is stored as a real array times a shared shift phase.

use crate::error::{Error, Result};
use crate::grid::{size_mismatch, Grid, Image};
use crate::imageops::fft::{dft_1d, fast_len, shift_phase, RealFft2, C64};
use crate::parallel::prelude::*;
use std::fmt;
use std::str::FromStr;
use std::sync::Mutex;

/// Filter orientations in degrees, as multyscale's `gaussian2d` turns them: at 0° the surround
/// is elongated along y (vertically), so the filter responds to horizontal edges; x is the
/// column and y the row (downward).
pub const ORIENTATIONS_DEG: [f64; 6] = [0.0, 30.0, 60.0, 90.0, 120.0, 150.0];
/// Number of spatial scales.
pub const SCALES: usize = 7;
/// The largest centre space constant, in degrees.
pub const LARGEST_SPACE_CONSTANT_DEG: f64 = 3.0;
/// The smallest image side, in degrees, the models accept: the diameter (two space constants)
/// of the largest filter's centre. Smaller images truncate the coarse filters beyond use.
pub const MIN_SIDE_DEG: f64 = 2.0 * LARGEST_SPACE_CONSTANT_DEG;
/// ε of the local RMS of LODOG and FLODOG (multyscale's value).
pub const EPS: f64 = 1e-6;

/// Centre σ of each scale in degrees, finest first: 3°·2^(s−6)/√2.
pub fn centre_sigmas_deg() -> [f64; SCALES] {
    let mut s = [0.0; SCALES];
    for (i, v) in s.iter_mut().enumerate() {
        *v = LARGEST_SPACE_CONSTANT_DEG * 2f64.powi(i as i32 - (SCALES as i32 - 1))
            / std::f64::consts::SQRT_2;
    }
    s
}

/// The weight of each scale, finest first: (peak frequency)^0.1 normalised to the middle scale
/// and rounded to 5 decimals, as multyscale (after Robinson et al.'s MATLAB code) does. The peak
/// frequency is 1/(2·FWHM) with FWHM = 2σ√(2 ln 2).
pub fn scale_weights() -> [f64; SCALES] {
    let sig = centre_sigmas_deg();
    let freq = |s: f64| 1.0 / (2.0 * 2.0 * s * (2.0 * 2f64.ln()).sqrt());
    let middle = freq(sig[SCALES / 2]).powf(0.1);
    let mut w = [0.0; SCALES];
    for (v, &s) in w.iter_mut().zip(&sig) {
        *v = (freq(s).powf(0.1) / middle * 1e5).round() / 1e5;
    }
    w
}

/// Which normalisation the model uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Variant {
    /// Image-wide RMS per orientation (Blakeslee & McCourt 1999).
    Odog,
    /// Local RMS per orientation in a fixed Gaussian window (Robinson et al. 2007).
    Lodog,
    /// Local RMS per filter, window and scale mix tied to the filter's scale (Robinson et al.
    /// 2007).
    Flodog,
}

impl Variant {
    /// All variants.
    pub const ALL: [Variant; 3] = [Variant::Odog, Variant::Lodog, Variant::Flodog];

    /// The lower-case name used on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Variant::Odog => "odog",
            Variant::Lodog => "lodog",
            Variant::Flodog => "flodog",
        }
    }
}

impl fmt::Display for Variant {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Variant {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let lower = s.trim().to_ascii_lowercase();
        Variant::ALL
            .into_iter()
            .find(|v| v.name() == lower)
            .ok_or_else(|| Error::unknown("model", s, &Variant::ALL.map(|v| v.name())))
    }
}

/// Parameters that multyscale exposes. The defaults are those of the reference outputs
/// (`odog_white32.npz`): a 2° LODOG window and FLODOG windows the size of each filter (σ = the
/// filter's centre σ). The published multyscale classes default to a 4° LODOG window and
/// FLODOG windows 4× the filter's σ; set these fields to use those sizes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OdogOptions {
    /// The value the image is padded with before filtering (mid-grey of a 0..1 image).
    pub pad_value: f64,
    /// σ of the LODOG normalisation window, degrees.
    pub lodog_window_deg: f64,
    /// FLODOG window σ as a multiple of the filter's centre σ.
    pub flodog_window_scale: f64,
    /// FLODOG: standard deviation, in scale steps, of the Gaussian mixing of scales.
    pub flodog_sdmix: f64,
}

impl Default for OdogOptions {
    fn default() -> Self {
        OdogOptions {
            pad_value: 0.5,
            lodog_window_deg: 2.0,
            flodog_window_scale: 1.0,
            flodog_sdmix: 0.5,
        }
    }
}

/// A separable kernel's spectrum: the product of a horizontal and a vertical 1-D spectrum.
struct Separable {
    x: Vec<C64>,
    y: Vec<C64>,
}

/// An ODOG-family model planned for one image size and resolution. Build it once, then
/// [`apply`](Odog::apply) it to any number of images of that size.
pub struct Odog {
    width: usize,
    height: usize,
    ppd: f64,
    variant: Variant,
    options: OdogOptions,
    fft: RealFft2,
    /// The transforms' scratch, kept between calls (see [`RealFft2::scratch`]).
    scratch: Mutex<Vec<C64>>,
    /// Shift phase of a kernel centred on the grid: horizontal (nfx) and vertical (my).
    phase_x: Vec<C64>,
    phase_y: Vec<C64>,
    /// ODOG/LODOG: per orientation, the real spectrum of Σ_s w_s DoG_{o,s} (phase removed).
    orientation_spectra: Vec<Vec<f64>>,
    /// LODOG: one window; FLODOG: one per scale.
    windows: Vec<Separable>,
    weights: [f64; SCALES],
}

impl fmt::Debug for Odog {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Odog")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("ppd", &self.ppd)
            .field("variant", &self.variant)
            .field("options", &self.options)
            .finish_non_exhaustive()
    }
}

/// Buffers reused across the steps of one application, so that no transform faults in fresh
/// memory.
struct Work {
    /// Spectrum of the padded image.
    x: Vec<C64>,
    /// Scratch spectrum.
    spec: Vec<C64>,
    /// Scratch image-sized buffers.
    a: Vec<f64>,
    b: Vec<f64>,
}

impl Odog {
    /// Plans `variant` for `width` × `height` images at `ppd` pixels per degree, with the
    /// multyscale defaults.
    pub fn new(width: usize, height: usize, ppd: f64, variant: Variant) -> Result<Self> {
        Odog::with_options(width, height, ppd, variant, OdogOptions::default())
    }

    /// Plans `variant` with explicit `options`.
    pub fn with_options(
        width: usize,
        height: usize,
        ppd: f64,
        variant: Variant,
        options: OdogOptions,
    ) -> Result<Self> {
        check_geometry(width, height, ppd)?;
        check_options(&options)?;
        let fft = RealFft2::new(fast_len(2 * width - 1), fast_len(2 * height - 1));
        let phase_x = shift_phase((width - 1) as f64 / 2.0, fft.mx(), fft.nfx());
        let phase_y = shift_phase((height - 1) as f64 / 2.0, fft.my(), fft.my());
        let mut model = Odog {
            width,
            height,
            ppd,
            variant,
            options,
            scratch: Mutex::new(fft.scratch()),
            fft,
            phase_x,
            phase_y,
            orientation_spectra: Vec::new(),
            windows: Vec::new(),
            weights: scale_weights(),
        };
        match variant {
            Variant::Odog | Variant::Lodog => {
                let n = width * height;
                let (mut kernel, mut surround) = (vec![0.0; n], vec![0.0; n]);
                let mut spec = model.fft.spectrum();
                let mut spectra = Vec::with_capacity(ORIENTATIONS_DEG.len());
                for o in 0..ORIENTATIONS_DEG.len() {
                    kernel.fill(0.0);
                    for s in 0..SCALES {
                        model.add_dog(&mut kernel, &mut surround, o, s, model.weights[s]);
                    }
                    spectra.push(model.real_spectrum(&kernel, &mut spec));
                }
                model.orientation_spectra = spectra;
                if variant == Variant::Lodog {
                    model.windows = vec![model.window(options.lodog_window_deg)];
                }
            }
            Variant::Flodog => {
                let sig = centre_sigmas_deg();
                model.windows = sig
                    .iter()
                    .map(|s| model.window(options.flodog_window_scale * s))
                    .collect();
            }
        }
        Ok(model)
    }

    /// Image width the model was planned for.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Image height the model was planned for.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Pixels per degree.
    pub fn ppd(&self) -> f64 {
        self.ppd
    }

    /// The variant.
    pub fn variant(&self) -> Variant {
        self.variant
    }

    /// The model's brightness prediction for `image` (linear luminance, nominally 0..1): same
    /// size, arbitrary units, positive = brighter.
    pub fn apply(&self, image: &Image) -> Result<Image> {
        self.check_image(image)?;
        let mut work = self.work(image);
        let data = match self.variant {
            Variant::Odog => self.apply_odog(&mut work),
            Variant::Lodog => self.apply_lodog(&mut work),
            Variant::Flodog => self.apply_flodog(&mut work),
        };
        Grid::from_vec(self.width, self.height, data)
    }

    /// The weighted response of one filter (orientation index `o` of [`ORIENTATIONS_DEG`],
    /// scale `s`, finest = 0) to `image`, before any normalisation.
    pub fn filter_response(&self, image: &Image, o: usize, s: usize) -> Result<Image> {
        self.check_image(image)?;
        check_filter_index(o, s)?;
        let mut work = self.work(image);
        let mut kernel_spec = self.fft.spectrum();
        self.dog_spectrum(o, s, &mut work.a, &mut work.b, &mut kernel_spec);
        let mut out = vec![0.0; self.width * self.height];
        self.response(
            &work.x,
            &kernel_spec,
            self.weights[s],
            &mut work.spec,
            &mut out,
        );
        Grid::from_vec(self.width, self.height, out)
    }

    /// The (unweighted) filter of orientation index `o` and scale `s` as an image of the
    /// model's size, centred on the grid centre: centre Gaussian minus surround Gaussian, each
    /// of unit sum.
    pub fn filter(&self, o: usize, s: usize) -> Result<Image> {
        check_filter_index(o, s)?;
        let n = self.width * self.height;
        let (mut kernel, mut surround) = (vec![0.0; n], vec![0.0; n]);
        self.add_dog(&mut kernel, &mut surround, o, s, 1.0);
        Grid::from_vec(self.width, self.height, kernel)
    }

    fn check_image(&self, image: &Image) -> Result<()> {
        if image.width() != self.width || image.height() != self.height {
            return Err(Error::invalid(size_mismatch(
                "image is",
                (image.width(), image.height()),
                &format!("the {} model was planned for", self.variant),
                (self.width, self.height),
            )));
        }
        if let Some(i) = image.data().iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(format!(
                "image has a non-finite value ({}) at column {}, row {}",
                image.data()[i],
                i % self.width,
                i / self.width
            )));
        }
        Ok(())
    }

    /// The forward transform of the image-sized `data` into `spec` (see [`RealFft2::forward`]).
    fn forward(&self, data: &[f64], spec: &mut [C64]) {
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        self.fft
            .forward(data, self.width, self.height, spec, &mut scratch);
    }

    /// The inverse transform of `spec`, the image-sized window at (`x0`, `y0`) into `out` (see
    /// [`RealFft2::inverse`]).
    fn inverse(&self, spec: &mut [C64], x0: usize, y0: usize, out: &mut [f64]) {
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        self.fft
            .inverse(spec, x0, y0, self.width, self.height, out, &mut scratch);
    }

    /// The buffers of one application, with the spectrum of (image − pad value), zero outside
    /// the image: padding with the pad value is the same as this, since every filter sums to
    /// zero.
    fn work(&self, image: &Image) -> Work {
        let n = self.width * self.height;
        let pad = self.options.pad_value;
        let a: Vec<f64> = image.data().iter().map(|v| v - pad).collect();
        let mut x = self.fft.spectrum();
        self.forward(&a, &mut x);
        Work {
            x,
            spec: self.fft.spectrum(),
            a,
            b: vec![0.0; n],
        }
    }

    fn apply_odog(&self, work: &mut Work) -> Vec<f64> {
        let n = self.width * self.height;
        // multyscale divides by the plain RMS (no ε). An orientation whose RMS is at the level
        // of FFT round-off has no response at all (a uniform image at the pad value, say);
        // dividing its noise by its noise would add garbage, so it is left out.
        let input = work.a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let floor = 1e-10 * input;
        let mut r = vec![0.0; n];
        let mut out = vec![0.0; n];
        for o in 0..ORIENTATIONS_DEG.len() {
            self.orientation_response(o, work, &mut r);
            let rms = (ordered_sum_sq(&r, self.width) / n as f64).sqrt();
            if rms > floor && rms > 0.0 {
                out.par_iter_mut()
                    .zip(r.par_iter())
                    .for_each(|(o, v)| *o += v / rms);
            }
        }
        out
    }

    fn apply_lodog(&self, work: &mut Work) -> Vec<f64> {
        let n = self.width * self.height;
        let (mut r, mut energy) = (vec![0.0; n], vec![0.0; n]);
        let mut out = vec![0.0; n];
        for o in 0..ORIENTATIONS_DEG.len() {
            self.orientation_response(o, work, &mut r);
            self.local_rms(
                &r,
                &self.windows[0],
                &mut work.spec,
                &mut work.a,
                &mut energy,
            );
            for ((o, v), e) in out.iter_mut().zip(&r).zip(&energy) {
                *o += v / e;
            }
        }
        out
    }

    fn apply_flodog(&self, work: &mut Work) -> Vec<f64> {
        let n = self.width * self.height;
        let sd = self.options.flodog_sdmix;
        let mut responses = vec![vec![0.0; n]; SCALES];
        let (mut mix, mut energy) = (vec![0.0; n], vec![0.0; n]);
        let mut kernel_spec = self.fft.spectrum();
        let mut out = vec![0.0; n];
        for o in 0..ORIENTATIONS_DEG.len() {
            for (s, r) in responses.iter_mut().enumerate() {
                self.dog_spectrum(o, s, &mut work.a, &mut work.b, &mut kernel_spec);
                self.response(&work.x, &kernel_spec, self.weights[s], &mut work.spec, r);
            }
            for s in 0..SCALES {
                // The mix of this orientation's scales, weighted by the normal density of
                // the scale difference; multyscale does not renormalise these weights.
                mix.fill(0.0);
                for (t, r) in responses.iter().enumerate() {
                    let d = t as f64 - s as f64;
                    let g = (-d * d / (2.0 * sd * sd)).exp()
                        / (sd * (2.0 * std::f64::consts::PI).sqrt());
                    mix.par_iter_mut()
                        .zip(r.par_iter())
                        .for_each(|(m, v)| *m += g * v);
                }
                self.local_rms(
                    &mix,
                    &self.windows[s],
                    &mut work.spec,
                    &mut work.a,
                    &mut energy,
                );
                out.par_iter_mut()
                    .zip(responses[s].par_iter())
                    .zip(energy.par_iter())
                    .for_each(|((o, v), e)| *o += v / e);
            }
        }
        out
    }

    /// sqrt(window ∗ r² + ε) + ε into `out`, the window convolution zero-padded and aligned as
    /// scipy's `fftconvolve(mode="same")` aligns a kernel of the image's size.
    fn local_rms(
        &self,
        r: &[f64],
        window: &Separable,
        spec: &mut [C64],
        squared: &mut [f64],
        out: &mut [f64],
    ) {
        squared
            .par_iter_mut()
            .zip(r.par_iter())
            .for_each(|(s, v)| *s = v * v);
        self.forward(squared, spec);
        let my = self.fft.my();
        spec.par_chunks_mut(my)
            .zip(window.x.par_iter())
            .for_each(|(col, wx)| {
                for (v, wy) in col.iter_mut().zip(&window.y) {
                    *v *= wx * wy;
                }
            });
        self.inverse(spec, (self.width - 1) / 2, (self.height - 1) / 2, out);
        out.par_iter_mut()
            .for_each(|a| *a = (a.max(0.0) + EPS).sqrt() + EPS);
    }

    /// Convolution of the padded image with a filter given by its real spectrum (phase
    /// removed), aligned as multyscale aligns its filter bank, into `out`.
    /// The summed response of orientation `o` (all scales, weighted) to the image in `work`.
    fn orientation_response(&self, o: usize, work: &mut Work, out: &mut [f64]) {
        self.response_real(&work.x, &self.orientation_spectra[o], &mut work.spec, out);
    }

    fn response_real(&self, x: &[C64], real_spectrum: &[f64], spec: &mut [C64], out: &mut [f64]) {
        let my = self.fft.my();
        spec.par_chunks_mut(my)
            .zip(x.par_chunks(my))
            .zip(real_spectrum.par_chunks(my))
            .zip(self.phase_x.par_iter())
            .for_each(|(((out, xs), rs), px)| {
                for (((o, xv), r), py) in out.iter_mut().zip(xs).zip(rs).zip(&self.phase_y) {
                    *o = xv * (px * py) * r;
                }
            });
        self.bank_inverse(spec, out);
    }

    /// Convolution of the padded image with a filter given by its full spectrum, times
    /// `weight`, into `out`.
    fn response(
        &self,
        x: &[C64],
        kernel_spectrum: &[C64],
        weight: f64,
        spec: &mut [C64],
        out: &mut [f64],
    ) {
        spec.par_iter_mut()
            .zip(x.par_iter())
            .zip(kernel_spectrum.par_iter())
            .for_each(|((o, a), k)| *o = a * k * weight);
        self.bank_inverse(spec, out);
    }

    /// The inverse transform kept where multyscale's padded convolution puts the image: with
    /// the kernel centred at (N−1)/2, output pixel m sees input position m + 1/2 (even N).
    fn bank_inverse(&self, spec: &mut [C64], out: &mut [f64]) {
        self.inverse(spec, self.width / 2, self.height / 2, out);
    }

    /// The spectrum of `kernel` with the centring phase divided out; real because every
    /// filter is point-symmetric about the grid centre, so only the real part is kept.
    fn real_spectrum(&self, kernel: &[f64], spec: &mut [C64]) -> Vec<f64> {
        self.forward(kernel, spec);
        let my = self.fft.my();
        let mut real = vec![0.0; spec.len()];
        real.par_chunks_mut(my)
            .zip(spec.par_chunks(my))
            .zip(self.phase_x.par_iter())
            .for_each(|((out, col), px)| {
                for ((o, v), py) in out.iter_mut().zip(col).zip(&self.phase_y) {
                    *o = (v * (px * py).conj()).re;
                }
            });
        real
    }

    /// The spectrum of filter (o, s) into `spec`, using `kernel` and `surround` as scratch.
    fn dog_spectrum(
        &self,
        o: usize,
        s: usize,
        kernel: &mut [f64],
        surround: &mut [f64],
        spec: &mut [C64],
    ) {
        kernel.fill(0.0);
        self.add_dog(kernel, surround, o, s, 1.0);
        self.forward(kernel, spec);
    }

    /// A normalised isotropic Gaussian window of σ `sigma_deg`, as the spectrum of its two
    /// 1-D factors.
    fn window(&self, sigma_deg: f64) -> Separable {
        let gx = normalised_profile(&self.axis(self.width), sigma_deg);
        let gy = normalised_profile(&self.axis(self.height), sigma_deg);
        Separable {
            x: dft_1d(&gx, self.fft.mx(), true),
            y: dft_1d(&gy, self.fft.my(), false),
        }
    }

    /// Coordinates in degrees of the pixel centres along an axis of `n` pixels, 0 at the
    /// middle of the grid (between two pixels when `n` is even).
    fn axis(&self, n: usize) -> Vec<f64> {
        let c = (n as f64 - 1.0) / 2.0;
        (0..n).map(|i| (i as f64 - c) / self.ppd).collect()
    }

    /// Adds `weight` × (centre/Σcentre − surround/Σsurround) of filter (o, s) to `kernel`,
    /// using `surround` as scratch.
    fn add_dog(&self, kernel: &mut [f64], surround: &mut [f64], o: usize, s: usize, weight: f64) {
        let sigma = centre_sigmas_deg()[s];
        let (xs, ys) = (self.axis(self.width), self.axis(self.height));
        let cx: Vec<f64> = xs
            .iter()
            .map(|x| (-x * x / (2.0 * sigma * sigma)).exp())
            .collect();
        let cy: Vec<f64> = ys
            .iter()
            .map(|y| (-y * y / (2.0 * sigma * sigma)).exp())
            .collect();
        let centre_sum = cx.iter().sum::<f64>() * cy.iter().sum::<f64>();
        elliptic_gaussian(&xs, &ys, sigma, 2.0 * sigma, ORIENTATIONS_DEG[o], surround);
        let surround_sum = ordered_sum(surround, self.width);
        let w = self.width;
        kernel
            .par_chunks_mut(w)
            .zip(surround.par_chunks(w))
            .zip(cy.par_iter())
            .for_each(|((k, sr), cyv)| {
                for ((kv, sv), cxv) in k.iter_mut().zip(sr).zip(&cx) {
                    *kv += weight * (cxv * cyv / centre_sum - sv / surround_sum);
                }
            });
    }
}

/// exp(−x²/2σ²) on `axis`, normalised to unit sum.
fn normalised_profile(axis: &[f64], sigma: f64) -> Vec<f64> {
    let g: Vec<f64> = axis
        .iter()
        .map(|x| (-x * x / (2.0 * sigma * sigma)).exp())
        .collect();
    let sum: f64 = g.iter().sum();
    g.iter().map(|v| v / sum).collect()
}

/// multyscale's `gaussian2d`: exp(−(a x² + 2b x y + c y²)) with (σ₀, σ₁) along x and y before
/// rotating by `theta_deg`, evaluated on the grid `xs` × `ys` (row-major, y along rows) into
/// `out`.
fn elliptic_gaussian(xs: &[f64], ys: &[f64], s0: f64, s1: f64, theta_deg: f64, out: &mut [f64]) {
    let t = theta_deg.to_radians();
    let (sin, cos, sin2) = (t.sin(), t.cos(), (2.0 * t).sin());
    let a = cos * cos / (2.0 * s0 * s0) + sin * sin / (2.0 * s1 * s1);
    let b = -sin2 / (4.0 * s0 * s0) + sin2 / (4.0 * s1 * s1);
    let c = sin * sin / (2.0 * s0 * s0) + cos * cos / (2.0 * s1 * s1);
    let (w, h) = (xs.len(), ys.len());
    let (x0, dx) = (xs[0], if w > 1 { xs[1] - xs[0] } else { 1.0 });
    // The grid is symmetric about its centre (x_j = −x_{w−1−j} exactly, likewise y) and so is
    // the Gaussian: evaluate the top half and mirror it, bit for bit.
    let (top, bottom) = out.split_at_mut(h.div_ceil(2) * w);
    top.par_chunks_mut(w)
        .zip(ys.par_iter())
        .for_each(|(row, &y)| {
            row.fill(0.0);
            // exp(−q) is exactly 0 in f64 once q > 746: only evaluate where q is below that.
            const Q: f64 = 746.0;
            let disc = (b * y) * (b * y) - a * (c * y * y - Q);
            if disc < 0.0 {
                return;
            }
            let root = disc.sqrt();
            let (lo, hi) = ((-b * y - root) / a, (-b * y + root) / a);
            let j0 = (((lo - x0) / dx).floor() - 1.0).max(0.0) as usize;
            let j1 = ((((hi - x0) / dx).ceil() + 1.0).max(0.0) as usize).min(w);
            for j in j0.min(w)..j1 {
                let x = xs[j];
                row[j] = (-(a * x * x + 2.0 * b * x * y + c * y * y)).exp();
            }
        });
    let top: &[f64] = top;
    let done = h.div_ceil(2);
    bottom.par_chunks_mut(w).enumerate().for_each(|(k, row)| {
        let src = &top[(h - 1 - (done + k)) * w..(h - (done + k)) * w];
        for (d, s) in row.iter_mut().zip(src.iter().rev()) {
            *d = *s;
        }
    });
}

/// Sum of a row-major grid, row by row in order, so the result does not depend on threads.
fn ordered_sum(values: &[f64], width: usize) -> f64 {
    let rows: Vec<f64> = values
        .par_chunks(width)
        .map(|r| r.iter().sum::<f64>())
        .collect();
    rows.iter().sum()
}

/// Sum of squares, in the same fixed order as [`ordered_sum`].
fn ordered_sum_sq(values: &[f64], width: usize) -> f64 {
    let rows: Vec<f64> = values
        .par_chunks(width)
        .map(|r| r.iter().map(|v| v * v).sum::<f64>())
        .collect();
    rows.iter().sum()
}

fn check_geometry(width: usize, height: usize, ppd: f64) -> Result<()> {
    if !(ppd.is_finite() && ppd > 0.0) {
        return Err(Error::invalid(format!(
            "ppd {ppd} must be a positive number of pixels per degree"
        )));
    }
    crate::grid::check_size(width, height, crate::grid::DEFAULT_MAX_PIXELS)?;
    let (wd, hd) = (width as f64 / ppd, height as f64 / ppd);
    if wd < MIN_SIDE_DEG || hd < MIN_SIDE_DEG {
        return Err(Error::invalid(format!(
            "image {} at {ppd} ppd is {}, smaller than the largest filter ({MIN_SIDE_DEG}°, \
             twice its 3° space constant) either way: use a larger image or a smaller ppd",
            crate::message::SizeText::Pixels(height, width),
            crate::message::SizeText::Degrees(hd, wd)
        )));
    }
    Ok(())
}

fn check_options(o: &OdogOptions) -> Result<()> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !o.pad_value.is_finite() {
        return Err(Error::invalid(format!(
            "pad value {} must be finite",
            o.pad_value
        )));
    }
    if !positive(o.lodog_window_deg)
        || !positive(o.flodog_window_scale)
        || !positive(o.flodog_sdmix)
    {
        return Err(Error::invalid(format!(
            "LODOG window {}°, FLODOG window scale {} and sdmix {} must be positive",
            o.lodog_window_deg, o.flodog_window_scale, o.flodog_sdmix
        )));
    }
    Ok(())
}

fn check_filter_index(o: usize, s: usize) -> Result<()> {
    if o >= ORIENTATIONS_DEG.len() || s >= SCALES {
        return Err(Error::invalid(format!(
            "filter (orientation {o}, scale {s}) does not exist: orientations 0..{}, scales \
             0..{}",
            ORIENTATIONS_DEG.len() - 1,
            SCALES - 1
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Direct (spatial) convolution with multyscale's alignment: out[m] = Σ_j k[j]·x[m+c−j],
    /// x = image − pad outside-zero, c = N/2. The obviously correct reference of the FFT path.
    fn direct_bank(image: &Image, kernel: &[f64], pad: f64) -> Vec<f64> {
        let (w, h) = (image.width() as isize, image.height() as isize);
        let (cx, cy) = (w / 2, h / 2);
        let mut out = vec![0.0; (w * h) as usize];
        for my in 0..h {
            for mx in 0..w {
                let mut acc = 0.0;
                for jy in 0..h {
                    for jx in 0..w {
                        let (sx, sy) = (mx + cx - jx, my + cy - jy);
                        if sx >= 0 && sx < w && sy >= 0 && sy < h {
                            acc += kernel[(jy * w + jx) as usize]
                                * (image.get(sx as usize, sy as usize) - pad);
                        }
                    }
                }
                out[(my * w + mx) as usize] = acc;
            }
        }
        out
    }

    fn test_image(w: usize, h: usize) -> Image {
        Grid::from_fn(w, h, |c, r| {
            let bar = if (c / 3) % 2 == 0 { 0.9 } else { 0.1 };
            if (5..9).contains(&c) && (4..10).contains(&r) {
                0.5
            } else {
                bar + 0.01 * ((c * 7 + r * 13) % 5) as f64
            }
        })
    }

    #[test]
    fn weights_and_sigmas_match_multyscale() {
        let s = centre_sigmas_deg();
        assert!((s[6] - 3.0 / 2f64.sqrt()).abs() < 1e-15);
        assert!((s[0] - 3.0 / 64.0 / 2f64.sqrt()).abs() < 1e-15);
        let w = scale_weights();
        // (2^0.1)^k around the middle scale, rounded: the values multyscale prints.
        assert_eq!(w[3], 1.0);
        assert_eq!(
            w,
            [1.23114, 1.1487, 1.07177, 1.0, 0.93303, 0.87055, 0.81225]
        );
    }

    #[test]
    fn every_filter_sums_to_zero_and_is_point_symmetric() {
        let model = Odog::new(24, 20, 3.0, Variant::Odog).unwrap();
        for o in 0..6 {
            for s in 0..SCALES {
                let k = model.filter(o, s).unwrap();
                let sum: f64 = k.data().iter().sum();
                assert!(sum.abs() < 1e-12, "filter ({o},{s}) sums to {sum}");
                for r in 0..20 {
                    for c in 0..24 {
                        let d = k.get(c, r) - k.get(23 - c, 19 - r);
                        assert!(d.abs() < 1e-14);
                    }
                }
            }
        }
    }

    #[test]
    fn fft_convolution_matches_direct_convolution() {
        // Odd and even sizes exercise both alignments.
        for (w, h, ppd) in [(18, 16, 2.5), (17, 19, 2.5)] {
            let model = Odog::new(w, h, ppd, Variant::Flodog).unwrap();
            let image = test_image(w, h);
            for (o, s) in [(0, 6), (1, 5), (3, 4), (5, 2)] {
                let fast = model.filter_response(&image, o, s).unwrap();
                let kernel = model.filter(o, s).unwrap();
                let slow = direct_bank(&image, kernel.data(), 0.5);
                let wgt = scale_weights()[s];
                for (a, b) in fast.data().iter().zip(&slow) {
                    assert!(
                        (a - wgt * b).abs() < 1e-12,
                        "({o},{s}) {w}x{h}: {a} vs {}",
                        wgt * b
                    );
                }
            }
        }
    }

    #[test]
    fn real_spectrum_path_matches_the_sum_of_filters() {
        let (w, h) = (18, 16);
        let model = Odog::new(w, h, 2.5, Variant::Odog).unwrap();
        let image = test_image(w, h);
        let mut work = model.work(&image);
        for o in 0..6 {
            let mut fast = vec![0.0; w * h];
            model.orientation_response(o, &mut work, &mut fast);
            let mut slow = vec![0.0; w * h];
            for s in 0..SCALES {
                let r = model.filter_response(&image, o, s).unwrap();
                for (a, b) in slow.iter_mut().zip(r.data()) {
                    *a += b;
                }
            }
            for (a, b) in fast.iter().zip(&slow) {
                assert!((a - b).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn window_average_matches_direct_convolution() {
        let (w, h) = (15, 12);
        let model = Odog::new(w, h, 2.0, Variant::Lodog).unwrap();
        let r: Vec<f64> = (0..w * h)
            .map(|i| ((i * 31) % 17) as f64 / 17.0 - 0.4)
            .collect();
        let mut energy = vec![0.0; w * h];
        let (mut spec, mut sq) = (model.fft.spectrum(), vec![0.0; w * h]);
        model.local_rms(&r, &model.windows[0], &mut spec, &mut sq, &mut energy);
        let gx = normalised_profile(&model.axis(w), 2.0);
        let gy = normalised_profile(&model.axis(h), 2.0);
        let (cx, cy) = (((w - 1) / 2) as isize, ((h - 1) / 2) as isize);
        for my in 0..h as isize {
            for mx in 0..w as isize {
                let mut acc = 0.0;
                for jy in 0..h as isize {
                    for jx in 0..w as isize {
                        let (sx, sy) = (mx + cx - jx, my + cy - jy);
                        if sx >= 0 && sx < w as isize && sy >= 0 && sy < h as isize {
                            let v = r[(sy * w as isize + sx) as usize];
                            acc += gx[jx as usize] * gy[jy as usize] * v * v;
                        }
                    }
                }
                let want = (acc + EPS).sqrt() + EPS;
                let got = energy[(my * w as isize + mx) as usize];
                assert!((got - want).abs() < 1e-12, "{got} vs {want}");
            }
        }
    }

    #[test]
    fn mid_grey_gives_zero_and_odog_ignores_contrast_scale() {
        for v in Variant::ALL {
            let model = Odog::new(40, 40, 5.0, v).unwrap();
            let out = model.apply(&Grid::new(40, 40, 0.5)).unwrap();
            assert!(out.data().iter().all(|&x| x == 0.0), "{v}");
        }
        // ODOG divides by an RMS, so scaling the contrast about the pad value changes nothing.
        let model = Odog::new(40, 32, 5.0, Variant::Odog).unwrap();
        let image = test_image(40, 32);
        let a = model.apply(&image).unwrap();
        let b = model.apply(&image.map(|v| 0.5 + 0.3 * (v - 0.5))).unwrap();
        for (x, y) in a.data().iter().zip(b.data()) {
            assert!((x - y).abs() < 1e-9 * (1.0 + x.abs()));
        }
        assert!(a.data().iter().any(|v| v.abs() > 0.1));
    }

    #[cfg(feature = "parallel")]
    #[test]
    fn outputs_do_not_depend_on_the_thread_count() {
        let image = test_image(36, 30);
        for v in Variant::ALL {
            let model = Odog::new(36, 30, 4.0, v).unwrap();
            let many = model.apply(&image).unwrap();
            let one = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap()
                .install(|| model.apply(&image).unwrap());
            assert_eq!(many, one, "{v}");
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        assert!(Odog::new(40, 40, 0.0, Variant::Odog).is_err());
        assert!(Odog::new(40, 40, f64::NAN, Variant::Odog).is_err());
        let e = Odog::new(100, 100, 32.0, Variant::Odog)
            .unwrap_err()
            .to_string();
        assert!(e.contains("smaller than the largest filter"), "{e}");
        let model = Odog::new(40, 40, 5.0, Variant::Odog).unwrap();
        assert!(model.apply(&Grid::new(41, 40, 0.5)).is_err());
        let mut nan = Grid::new(40, 40, 0.5);
        *nan.get_mut(3, 4) = f64::NAN;
        let e = model.apply(&nan).unwrap_err().to_string();
        assert!(e.contains("column 3, row 4"), "{e}");
        assert!("ODOG".parse::<Variant>().is_ok());
        assert!("retinex".parse::<Variant>().is_err());
        assert!(model.filter(6, 0).is_err());
    }
}
