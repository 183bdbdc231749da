//! Troxler fading of a blurred disk: band-pass energy at the border and a first-order
//! temporal adaptation model.
//!
//! Vision signals change in space and in time. A sharp edge carries band-pass
//! (difference-of-Gaussians) energy at fine scales; a blurred edge carries little. Under steady
//! fixation each retinal point adapts to its own input with time constant τ, so the signal of
//! an unchanging image decays; what keeps it alive is the small, incessant motion of the eye
//! (fixational jitter), which moves edges across receptors. The change it causes at a point is
//! the gradient of the band-pass image times the displacement: large at a sharp edge, small at
//! a blurred one. So with jitter the blurred disk's border signal adapts away and the disk is
//! filled in by its surround, while the sharp disk persists (Troxler 1804). Without jitter the
//! model lets both fade alike: the difference comes from eye movements, not from the edges
//! alone.
//!
//! The functions take each disk as a picture (its channels) and a mask: the two disks may be
//! in one picture or in two, so they work on any stimulus that provides them.

use crate::error::{Error, Result};
use crate::grid::{Grid, Image, Mask, RgbImage};
use crate::imageops::{bilinear, fill_holes, gaussian_blur};
use crate::random::SplitMix64;
use serde::Serialize;

/// The band-pass filter: a difference of isotropic Gaussians, each of unit sum.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DogBand {
    /// Centre σ in degrees.
    pub centre_sigma_deg: f64,
    /// Surround σ as a multiple of the centre σ (> 1).
    pub surround_ratio: f64,
    /// Half-width, in degrees, of the band on both sides of a disk's outline where energy is
    /// measured.
    pub border_half_width_deg: f64,
}

impl DogBand {
    /// Checks that both σ and the half-width are positive and the ratio is above 1.
    pub fn check(&self) -> Result<()> {
        let band = self;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let ratio_ok = band.surround_ratio.is_finite() && band.surround_ratio > 1.0;
        let band_ok =
            positive(band.centre_sigma_deg) && ratio_ok && positive(band.border_half_width_deg);
        if !band_ok {
            return Err(Error::invalid(format!(
                "DoG band (centre σ {}°, surround ratio {}, border half-width {}°): σ and \
                 half-width must be positive and the ratio above 1",
                band.centre_sigma_deg, band.surround_ratio, band.border_half_width_deg
            )));
        }
        Ok(())
    }
}

impl Default for DogBand {
    fn default() -> Self {
        DogBand {
            centre_sigma_deg: 0.05,
            surround_ratio: 2.0,
            border_half_width_deg: 0.5,
        }
    }
}

/// One disk to analyse: the picture it is in (one image per channel: luminance, or R, G, B)
/// and the disk's mask (true inside the disk, its outline at the middle of any blur).
#[derive(Debug, Clone, Copy)]
pub struct Disk<'a> {
    /// The picture's channels, all of one size.
    pub channels: &'a [Image],
    /// The disk.
    pub mask: &'a Mask,
}

/// Band-pass energy along the two borders.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BorderEnergy {
    /// Mean squared band-pass response (summed over channels) in the blurred disk's border band.
    pub blurred: f64,
    /// The same for the sharp disk.
    pub sharp: f64,
    /// blurred / sharp: how much less band-pass signal the blurred border carries.
    pub ratio: f64,
    /// Pixels in the blurred disk's border band.
    pub blurred_pixels: usize,
    /// Pixels in the sharp disk's border band.
    pub sharp_pixels: usize,
}

/// First-order adaptation settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct AdaptationOptions {
    /// Adaptation time constant τ in seconds.
    pub tau_s: f64,
    /// Simulated fixation time in seconds.
    pub duration_s: f64,
    /// Time step in seconds.
    pub dt_s: f64,
    /// RMS amplitude of the fixational jitter per axis, degrees (0 = perfectly steady eye).
    pub jitter_deg: f64,
    /// Correlation time of the jitter (an Ornstein–Uhlenbeck process), seconds.
    pub jitter_tau_s: f64,
    /// Seed of the jitter.
    pub seed: u64,
}

impl AdaptationOptions {
    /// Checks that the times are positive, the jitter is not negative and the steps are not
    /// too many.
    pub fn check(&self) -> Result<()> {
        let o = self;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(o.tau_s)
            || !positive(o.duration_s)
            || !positive(o.dt_s)
            || !positive(o.jitter_tau_s)
        {
            return Err(Error::invalid(format!(
                "τ {} s, duration {} s, time step {} s and jitter correlation time {} s must be \
                 positive",
                o.tau_s, o.duration_s, o.dt_s, o.jitter_tau_s
            )));
        }
        if !(o.jitter_deg.is_finite() && o.jitter_deg >= 0.0) {
            return Err(Error::invalid(format!(
                "jitter amplitude {}° must be ≥ 0",
                o.jitter_deg
            )));
        }
        if o.duration_s / o.dt_s > 100_000.0 {
            return Err(Error::invalid(format!(
                "{} s in steps of {} s is more than 100000 steps",
                o.duration_s, o.dt_s
            )));
        }
        Ok(())
    }
}

impl Default for AdaptationOptions {
    fn default() -> Self {
        AdaptationOptions {
            tau_s: 2.0,
            duration_s: 10.0,
            dt_s: 0.05,
            jitter_deg: 0.05,
            jitter_tau_s: 0.1,
            seed: 1,
        }
    }
}

/// The perceived-contrast time course of the two disks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimeCourse {
    /// Times in seconds (0 = stimulus onset).
    pub times: Vec<f64>,
    /// Relative perceived contrast of the blurred disk: RMS adapted band-pass response in its
    /// border band over its value at onset.
    pub blurred: Vec<f64>,
    /// The same for the sharp disk.
    pub sharp: Vec<f64>,
    /// Eye position (x right, y down) in degrees at each time.
    pub eye: Vec<(f64, f64)>,
}

/// Band-pass (DoG) energy along the borders of the `blurred` and the `sharp` disk.
pub fn border_energy(
    blurred: Disk<'_>,
    sharp: Disk<'_>,
    ppd: f64,
    band: &DogBand,
) -> Result<BorderEnergy> {
    check_inputs(&[("blurred", blurred), ("sharp", sharp)], ppd, band)?;
    let half = band.border_half_width_deg * ppd;
    let energy = |disk: Disk<'_>| -> (f64, usize) {
        let ring = border_band(disk.mask, half);
        let n = ring.count();
        let sum: f64 = disk
            .channels
            .iter()
            .map(|c| {
                band_pass(c, ppd, band)
                    .data()
                    .iter()
                    .zip(ring.data())
                    .filter(|(_, &m)| m)
                    .map(|(v, _)| v * v)
                    .sum::<f64>()
            })
            .sum();
        (sum / n.max(1) as f64, n)
    };
    let (eb, nb) = energy(blurred);
    let (es, ns) = energy(sharp);
    if nb == 0 || ns == 0 {
        return Err(Error::invalid(
            "a disk mask has no border (it is empty or fills the image)",
        ));
    }
    Ok(BorderEnergy {
        blurred: eb,
        sharp: es,
        ratio: if es > 0.0 { eb / es } else { f64::INFINITY },
        blurred_pixels: nb,
        sharp_pixels: ns,
    })
}

/// Runs the adaptation model and returns the relative perceived contrast of both disks over
/// time.
///
/// Each channel is band-pass filtered once; since filtering commutes with shifting and the
/// adaptation is linear, adapting the filtered retinal image is the same as filtering the
/// adapted one. At each step the eye position moves by the jitter process, every border pixel
/// samples the filtered image at its shifted position (bilinear), its adaptation state moves
/// toward that input by 1 − exp(−dt/τ), and the response is input − state. The state starts
/// at zero (adapted to a uniform field).
pub fn adaptation_time_course(
    blurred: Disk<'_>,
    sharp: Disk<'_>,
    ppd: f64,
    band: &DogBand,
    options: &AdaptationOptions,
) -> Result<TimeCourse> {
    check_inputs(&[("blurred", blurred), ("sharp", sharp)], ppd, band)?;
    options.check()?;
    let half = band.border_half_width_deg * ppd;
    let disks = [blurred, sharp];
    // Per disk: its band-pass channels and the pixels of its border band.
    let responses: Vec<Vec<Image>> = disks
        .iter()
        .map(|d| d.channels.iter().map(|c| band_pass(c, ppd, band)).collect())
        .collect();
    let pixels: Vec<Vec<(usize, usize)>> = disks
        .iter()
        .map(|d| {
            let w = d.mask.width();
            border_band(d.mask, half)
                .data()
                .iter()
                .enumerate()
                .filter(|(_, &m)| m)
                .map(|(i, _)| (i % w, i / w))
                .collect()
        })
        .collect();
    if pixels.iter().any(|p| p.is_empty()) {
        return Err(Error::invalid(
            "a disk mask has no border (it is empty or fills the image)",
        ));
    }
    let steps = (options.duration_s / options.dt_s).round() as usize;
    let gain = 1.0 - (-options.dt_s / options.tau_s).exp();
    let mut eye = Jitter::new(options);
    let mut state: Vec<Vec<Vec<f64>>> = pixels
        .iter()
        .zip(&responses)
        .map(|(p, r)| vec![vec![0.0; p.len()]; r.len()])
        .collect();
    let mut course = TimeCourse {
        times: Vec::with_capacity(steps + 1),
        blurred: Vec::with_capacity(steps + 1),
        sharp: Vec::with_capacity(steps + 1),
        eye: Vec::with_capacity(steps + 1),
    };
    let mut onset = [0.0; 2];
    for step in 0..=steps {
        let (ex, ey) = eye.position();
        let (sx, sy) = (ex * ppd, ey * ppd);
        let mut rms = [0.0; 2];
        for (k, list) in pixels.iter().enumerate() {
            let mut sum = 0.0;
            for (ch, resp) in responses[k].iter().enumerate() {
                let st = &mut state[k][ch];
                for (i, &(c, r)) in list.iter().enumerate() {
                    // The eye moved by (ex, ey): this retinal point now sees the image at
                    // its position minus the displacement.
                    let input = bilinear(resp, c as f64 - sx, r as f64 - sy);
                    let response = input - st[i];
                    sum += response * response;
                    st[i] += gain * (input - st[i]);
                }
            }
            rms[k] = (sum / list.len() as f64).sqrt();
        }
        if step == 0 {
            onset = rms;
        }
        course.times.push(step as f64 * options.dt_s);
        course.eye.push((ex, ey));
        course.blurred.push(relative(rms[0], onset[0]));
        course.sharp.push(relative(rms[1], onset[1]));
        eye.advance();
    }
    Ok(course)
}

fn relative(v: f64, onset: f64) -> f64 {
    if onset > 0.0 {
        v / onset
    } else {
        0.0
    }
}

/// An Ornstein–Uhlenbeck eye position per axis, started at its stationary distribution.
struct Jitter {
    rng: SplitMix64,
    decay: f64,
    kick: f64,
    x: f64,
    y: f64,
}

impl Jitter {
    fn new(o: &AdaptationOptions) -> Self {
        let mut rng = SplitMix64::new(o.seed);
        let decay = (-o.dt_s / o.jitter_tau_s).exp();
        let kick = o.jitter_deg * (1.0 - decay * decay).sqrt();
        let (x, y) = (o.jitter_deg * rng.normal(), o.jitter_deg * rng.normal());
        Jitter {
            rng,
            decay,
            kick,
            x,
            y,
        }
    }

    fn position(&self) -> (f64, f64) {
        (self.x, self.y)
    }

    fn advance(&mut self) {
        self.x = self.decay * self.x + self.kick * self.rng.normal();
        self.y = self.decay * self.y + self.kick * self.rng.normal();
    }
}

/// The DoG band-pass response of `image` (centre minus surround Gaussian, each of unit sum),
/// the image extended by repeating its edge pixels so that its border makes no edge.
pub fn band_pass(image: &Image, ppd: f64, band: &DogBand) -> Image {
    let centre = gaussian_blur(image, band.centre_sigma_deg * ppd);
    let surround = gaussian_blur(image, band.surround_ratio * band.centre_sigma_deg * ppd);
    Grid::from_fn(image.width(), image.height(), |c, r| {
        centre.get(c, r) - surround.get(c, r)
    })
}

/// Pixels within `half_width` pixels (Euclidean) of the outline of `mask` (its holes filled),
/// on either side.
pub fn border_band(mask: &Mask, half_width: f64) -> Mask {
    let mask = &fill_holes(mask);
    let (w, h) = (mask.width(), mask.height());
    let edge: Vec<(isize, isize)> = (0..h)
        .flat_map(|r| (0..w).map(move |c| (c, r)))
        .filter(|&(c, r)| {
            let m = *mask.get(c, r);
            let differs = |dc: isize, dr: isize| {
                mask.checked(c as isize + dc, r as isize + dr)
                    .is_some_and(|&n| n != m)
            };
            differs(1, 0) || differs(-1, 0) || differs(0, 1) || differs(0, -1)
        })
        .map(|(c, r)| (c as isize, r as isize))
        .collect();
    let mut band = Grid::new(w, h, false);
    let reach = half_width.max(0.5);
    let radius = reach.ceil() as isize;
    for &(c, r) in &edge {
        for dr in -radius..=radius {
            for dc in -radius..=radius {
                if ((dc * dc + dr * dr) as f64).sqrt() <= reach {
                    let (cc, rr) = (c + dc, r + dr);
                    if cc >= 0 && rr >= 0 && (cc as usize) < w && (rr as usize) < h {
                        *band.get_mut(cc as usize, rr as usize) = true;
                    }
                }
            }
        }
    }
    band
}

/// The animation's rule for what is seen: inside each disk's region (the disk and its border
/// band) the picture is the local surround colour plus the disk's relative contrast, capped
/// at one, times the difference from it; elsewhere the picture is unchanged. The surround
/// colour is the mean of a ring just outside the region.
///
/// The frames are made one at a time ([`PerceivedFrames::frame`]), so a caller that reduces
/// or encodes them never holds the whole animation at full size.
#[derive(Debug, Clone)]
pub struct PerceivedFrames<'a> {
    picture: &'a RgbImage,
    /// Per disk: its region, the region's surround colour and its contrast time course.
    regions: Vec<(Mask, [f64; 3], &'a [f64])>,
    every: usize,
    steps: usize,
}

impl<'a> PerceivedFrames<'a> {
    /// The frames of `picture` under the rule above. `regions` pairs each disk's mask with its
    /// contrast time course; a frame is made every `every` time steps.
    pub fn new(
        picture: &'a RgbImage,
        regions: &[(&Mask, &'a [f64])],
        ppd: f64,
        band: &DogBand,
        every: usize,
    ) -> Result<PerceivedFrames<'a>> {
        for (mask, _) in regions {
            picture.check_same_size("picture is", *mask, "a disk mask is")?;
        }
        let steps = regions.iter().map(|(_, c)| c.len()).min().unwrap_or(0);
        let half = band.border_half_width_deg * ppd;
        let regions = regions
            .iter()
            .map(|&(m, course)| {
                let region = union(m, &border_band(m, half));
                let ring = border_band(&region, 2.0_f64.max(0.2 * ppd));
                let mut mean = [0.0; 3];
                let mut n = 0usize;
                for (p, (&in_ring, &in_region)) in picture
                    .data()
                    .iter()
                    .zip(ring.data().iter().zip(region.data()))
                {
                    if in_ring && !in_region {
                        n += 1;
                        for k in 0..3 {
                            mean[k] += p[k];
                        }
                    }
                }
                for v in &mut mean {
                    *v /= n.max(1) as f64;
                }
                (region, mean, course)
            })
            .collect();
        Ok(PerceivedFrames {
            picture,
            regions,
            every: every.max(1),
            steps,
        })
    }

    /// The number of frames: one every `every` time steps of the shortest time course.
    pub fn len(&self) -> usize {
        self.steps.div_ceil(self.every)
    }

    /// Whether there is no frame (an empty time course).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Frame `k` (time step `k·every`), `k` < [`PerceivedFrames::len`].
    pub fn frame(&self, k: usize) -> RgbImage {
        let i = k * self.every;
        let mut frame = self.picture.clone();
        for (region, surround, course) in &self.regions {
            let g = course[i].min(1.0);
            for (p, &inside) in frame.data_mut().iter_mut().zip(region.data()) {
                if inside {
                    for k in 0..3 {
                        p[k] = surround[k] + g * (p[k] - surround[k]);
                    }
                }
            }
        }
        frame
    }
}

fn union(a: &Mask, b: &Mask) -> Mask {
    Grid::from_fn(a.width(), a.height(), |c, r| *a.get(c, r) || *b.get(c, r))
}

fn check_inputs(disks: &[(&str, Disk<'_>)], ppd: f64, band: &DogBand) -> Result<()> {
    for (name, disk) in disks {
        let first = disk
            .channels
            .first()
            .ok_or_else(|| Error::invalid(format!("the {name} disk's picture has no channels")))?;
        for c in disk.channels {
            if !c.same_size(first) {
                return Err(Error::invalid(format!(
                    "the {name} disk's picture has channels of different sizes"
                )));
            }
            if let Some(i) = c.data().iter().position(|v| !v.is_finite()) {
                return Err(Error::invalid(format!(
                    "the {name} disk's picture has a non-finite value at column {}, row {}",
                    i % c.width(),
                    i / c.width()
                )));
            }
        }
        disk.mask
            .check_same_size(&format!("the {name} disk mask is"), first, "its picture is")?;
        if disk.mask.count() == 0 {
            return Err(Error::invalid(format!("the {name} disk mask is empty")));
        }
    }
    if !(ppd.is_finite() && ppd > 0.0) {
        return Err(Error::invalid(format!(
            "ppd {ppd} must be a positive number of pixels per degree"
        )));
    }
    band.check()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::imageops::{shrink, side_by_side};

    /// A 12°×6° field at 20 ppd: a blurred disk (σ 0.4°) on the left, a sharp one on the
    /// right, both radius 1.5°, luminance 0.3 on 0.6.
    fn two_disks() -> (Image, Mask, Mask) {
        let (w, h, ppd) = (240, 120, 20.0);
        let disk = |cx: f64, c: usize, r: usize| {
            let (x, y) = ((c as f64 + 0.5) / ppd - cx, (r as f64 + 0.5) / ppd - 3.0);
            (x * x + y * y).sqrt() <= 1.5
        };
        let left = Grid::from_fn(w, h, |c, r| disk(3.0, c, r));
        let right = Grid::from_fn(w, h, |c, r| disk(9.0, c, r));
        let sharp = Grid::from_fn(w, h, |c, r| if *right.get(c, r) { 0.3 } else { 0.6 });
        let blurred_part = gaussian_blur(
            &Grid::from_fn(w, h, |c, r| if *left.get(c, r) { 0.3 } else { 0.6 }),
            0.4 * ppd,
        );
        let image = Grid::from_fn(w, h, |c, r| {
            if c < w / 2 {
                *blurred_part.get(c, r)
            } else {
                *sharp.get(c, r)
            }
        });
        (image, left, right)
    }

    fn disk<'a>(channels: &'a [Image], mask: &'a Mask) -> Disk<'a> {
        Disk { channels, mask }
    }

    #[test]
    fn blur_preserves_the_mean_and_a_constant() {
        let flat = Grid::new(30, 20, 0.7);
        let b = gaussian_blur(&flat, 3.0);
        assert!(b.data().iter().all(|v| (v - 0.7).abs() < 1e-12));
        let bp = band_pass(&flat, 10.0, &DogBand::default());
        assert!(bp.data().iter().all(|v| v.abs() < 1e-12));
    }

    #[test]
    fn a_hole_in_the_mask_is_not_part_of_the_outline() {
        let ring = Grid::from_fn(20, 20, |c, r| {
            (3..17).contains(&c)
                && (3..17).contains(&r)
                && !((9..11).contains(&c) && (9..11).contains(&r))
        });
        let filled = fill_holes(&ring);
        assert_eq!(filled.count(), 14 * 14);
        let band = border_band(&ring, 1.0);
        assert!(!*band.get(9, 9) && !*band.get(8, 10) && *band.get(3, 10));
    }

    #[test]
    fn border_band_of_a_square() {
        let sq = Grid::from_fn(20, 20, |c, r| (5..15).contains(&c) && (5..15).contains(&r));
        let band = border_band(&sq, 1.0);
        // The outline pixels (both sides) and their 4-neighbours, nothing deep inside.
        assert!(*band.get(5, 10) && *band.get(4, 10) && *band.get(6, 10) && *band.get(3, 10));
        assert!(!*band.get(10, 10) && !*band.get(0, 0));
    }

    #[test]
    fn the_blurred_border_carries_less_band_pass_energy() {
        let (image, left, right) = two_disks();
        let ch = [image];
        let e = border_energy(
            disk(&ch, &left),
            disk(&ch, &right),
            20.0,
            &DogBand::default(),
        )
        .unwrap();
        assert!(e.ratio < 0.05, "ratio {}", e.ratio);
        assert!(e.sharp > 0.0);
    }

    #[test]
    fn without_jitter_both_disks_fade_as_exp_minus_t_over_tau() {
        let (image, left, right) = two_disks();
        let ch = [image];
        let opts = AdaptationOptions {
            jitter_deg: 0.0,
            duration_s: 2.0,
            dt_s: 0.1,
            tau_s: 1.0,
            ..Default::default()
        };
        let band = DogBand::default();
        let tc = adaptation_time_course(disk(&ch, &left), disk(&ch, &right), 20.0, &band, &opts)
            .unwrap();
        for (i, t) in tc.times.iter().enumerate() {
            // Discrete first-order decay: (exp(−dt/τ))^step, exactly.
            let want = (-t / 1.0f64).exp();
            assert!(
                (tc.blurred[i] - want).abs() < 1e-9,
                "{t}: {}",
                tc.blurred[i]
            );
            assert!((tc.sharp[i] - want).abs() < 1e-9);
        }
    }

    #[test]
    fn with_jitter_the_blurred_disk_fades_and_the_sharp_one_persists() {
        let (image, left, right) = two_disks();
        let ch = [image];
        let opts = AdaptationOptions {
            duration_s: 8.0,
            ..Default::default()
        };
        let band = DogBand::default();
        let tc = adaptation_time_course(disk(&ch, &left), disk(&ch, &right), 20.0, &band, &opts)
            .unwrap();
        let tail = |v: &[f64]| v[v.len() - 40..].iter().sum::<f64>() / 40.0;
        let (b, s) = (tail(&tc.blurred), tail(&tc.sharp));
        assert!(s > 3.0 * b, "sharp {s} vs blurred {b}");
        assert!(b < 0.3, "blurred disk still at {b}");
        // The disks may come in two pictures: the same disks give the same course.
        let (sharp_only, blurred_only) = (
            ch[0].map(|&v| v),
            Grid::from_fn(
                240,
                120,
                |c, r| if c < 120 { *ch[0].get(c, r) } else { 0.6 },
            ),
        );
        let (a, b2) = ([blurred_only], [sharp_only]);
        let again =
            adaptation_time_course(disk(&a, &left), disk(&b2, &right), 20.0, &band, &opts).unwrap();
        assert_eq!(tc, again);
    }

    #[test]
    fn frames_fade_toward_the_surround() {
        let (image, left, right) = two_disks();
        let rgb = image.map(|&v| [v, v, v]);
        let (gone, kept) = ([1.0, 0.0], [1.0, 1.0]);
        let regions: [(&Mask, &[f64]); 2] = [(&left, &gone), (&right, &kept)];
        let perceived = PerceivedFrames::new(&rgb, &regions, 20.0, &DogBand::default(), 1).unwrap();
        assert_eq!(perceived.len(), 2);
        let frames = [perceived.frame(0), perceived.frame(1)];
        assert_eq!(frames[0], rgb);
        // The blurred disk's centre became the surround (about 0.6: the ring just outside the
        // region still holds a little of the blur); the sharp disk's stayed 0.3.
        assert!((frames[1].get(60, 60)[0] - 0.6).abs() < 0.05);
        assert!((frames[1].get(180, 60)[0] - 0.3).abs() < 1e-12);
        let both = side_by_side(&frames[0], &frames[1], 4, [0.0; 3]);
        assert_eq!((both.width(), both.height()), (484, 120));
        assert_eq!(both.get(244 + 180, 60), frames[1].get(180, 60));
        let small = shrink(&rgb, 4);
        assert_eq!((small.width(), small.height()), (60, 30));
        assert!((small.get(45, 15)[0] - 0.3).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_an_error() {
        let (image, left, right) = two_disks();
        let ch = [image];
        let band = DogBand::default();
        let empty = Grid::new(240, 120, false);
        let small = Grid::new(10, 10, true);
        assert!(border_energy(disk(&ch, &empty), disk(&ch, &right), 20.0, &band).is_err());
        assert!(border_energy(disk(&ch, &small), disk(&ch, &right), 20.0, &band).is_err());
        assert!(border_energy(disk(&ch, &left), disk(&ch, &right), 0.0, &band).is_err());
        assert!(border_energy(disk(&[], &left), disk(&ch, &right), 20.0, &band).is_err());
        let bad = AdaptationOptions {
            tau_s: 0.0,
            ..Default::default()
        };
        let d = (disk(&ch, &left), disk(&ch, &right));
        assert!(adaptation_time_course(d.0, d.1, 20.0, &band, &bad).is_err());
    }
}
