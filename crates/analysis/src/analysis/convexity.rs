//! Tokens and their convexity.
//!
//! A *token* is one element of a picture that an observer judges as a whole: a disc, a strip, a
//! face, or the whole picture. Its convexity in a recovered depth map z is
//!
//! c = (mean of z over the token's core − mean of z over its rim) / D,
//!
//! where D is the token's half-width (the largest Euclidean distance from one of its pixels to
//! the nearest pixel outside it, in pixels), the *rim* is the token's pixels within
//! max(1, D/4) of its edge and the *core* those farther than max(rim width, D/2). c > 0 is convex
//! toward the viewer (the middle stands out), c < 0 concave. It is a difference of two means, so
//! it ignores the depth's unknown offset, and it is linear in z, so negating the depth negates it
//! exactly (to the last bit: every term changes sign and nothing else changes). It is roughly
//! the token's relief height over its half-width: about 0.4 for a hemispherical bump.

use crate::error::{Error, Result};
use crate::grid::{Image, Labels};

/// Convexities of smaller magnitude than this count as zero (no verdict) when locating flips:
/// values that small are the solver's tolerance showing through, not a shape.
pub const CONVEXITY_ZERO: f64 = 1e-6;

/// One token: which pixels it has, its core and rim.
#[derive(Debug, Clone, PartialEq)]
pub struct Token {
    /// Its label in the target mask (0 for the whole picture).
    pub label: u16,
    /// Its name (from the stimulus, or `label N`).
    pub name: String,
    /// Pixel indices (row-major) of the token.
    pixels: Vec<usize>,
    /// Pixel indices of the core.
    core: Vec<usize>,
    /// Pixel indices of the rim.
    rim: Vec<usize>,
    /// Half-width D in pixels.
    half_width: f64,
}

impl Token {
    /// The token of every pixel of a `width` × `height` picture, named `image`.
    pub fn whole(width: usize, height: usize) -> Result<Token> {
        let labels = Labels::new(width, height, 1);
        let mut token = tokens_from_labels(&labels, &[])?.remove(0);
        token.label = 0;
        token.name = "image".into();
        Ok(token)
    }

    /// Pixel indices (row-major) of the token.
    pub fn pixels(&self) -> &[usize] {
        &self.pixels
    }

    /// Pixel indices of the core: the pixels farther than max(rim width, D/2) from the edge.
    pub fn core(&self) -> &[usize] {
        &self.core
    }

    /// Half-width D in pixels: the largest distance from a pixel to the token's edge.
    pub fn half_width(&self) -> f64 {
        self.half_width
    }

    /// Mean depth over the core.
    pub fn core_mean(&self, depth: &Image) -> f64 {
        mean_over(depth, &self.core)
    }

    /// Mean depth over the rim.
    pub fn rim_mean(&self, depth: &Image) -> f64 {
        mean_over(depth, &self.rim)
    }

    /// The signed convexity of `depth` on this token (see the module documentation).
    pub fn convexity(&self, depth: &Image) -> f64 {
        (self.core_mean(depth) - self.rim_mean(depth)) / self.half_width
    }

    /// The token's centroid (column, row) in pixels, in a picture `width` pixels wide.
    ///
    /// ```
    /// use shadelab_analysis::analysis::convexity::Token;
    /// assert_eq!(Token::whole(4, 3)?.centroid(4), (1.5, 1.0));
    /// # Ok::<(), shadelab::Error>(())
    /// ```
    pub fn centroid(&self, width: usize) -> (f64, f64) {
        let n = self.pixels.len().max(1) as f64;
        let (sx, sy) = self.pixels.iter().fold((0.0, 0.0), |(sx, sy), &p| {
            (sx + (p % width) as f64, sy + (p / width) as f64)
        });
        (sx / n, sy / n)
    }

    /// The direction the token's bright side faces in `image` (a picture of the labels' size),
    /// as a tilt in degrees in [0, 360) (0 = up, +90 = left, the light's convention), and how
    /// lopsided the brightness is (0 = evenly lit, larger = brighter on that side).
    ///
    /// It is the direction from the token's centroid to its brightness-weighted centroid:
    /// d = Σ (I − Ī)·(x − x̄, y − ȳ) over the token's pixels (x right, y up, Ī the token's mean
    /// luminance); the strength is |d| / (Σ |I − Ī| · D) with D the half-width. A bump lit from
    /// tilt t faces its bright side to t, a dimple to t + 180°: this is the θ of the observer's
    /// P(convex | θ). An evenly lit token gives tilt 0 and strength 0.
    ///
    /// ```
    /// use shadelab_analysis::analysis::convexity::Token;
    /// use shadelab::Grid;
    /// // Brighter toward the top row: the bright side faces up (tilt 0).
    /// let image = Grid::from_fn(9, 9, |_, r| 1.0 - r as f64 / 10.0);
    /// let (tilt, strength) = Token::whole(9, 9)?.bright_side(&image);
    /// assert!(tilt.abs() < 1e-9 && strength > 0.0);
    /// # Ok::<(), shadelab::Error>(())
    /// ```
    pub fn bright_side(&self, image: &Image) -> (f64, f64) {
        let (dx, dy, spread) = luminance_moment(image, &self.pixels);
        let length = dx.hypot(dy);
        if length == 0.0 || !length.is_finite() {
            return (0.0, 0.0);
        }
        (
            moment_tilt(dx, dy),
            length / (spread * self.half_width.max(1.0)),
        )
    }

    /// Whether every pixel of the token is set in `mask`.
    pub fn inside(&self, mask: &crate::grid::Mask) -> bool {
        self.pixels.iter().all(|&p| mask.data()[p])
    }
}

/// The luminance moment of `pixels` (row-major indices into `image`): Σ (v − v̄)·(x − x̄, y − ȳ)
/// with x right and y up, and the spread Σ |v − v̄|. The moment points from the pixels' plain
/// centroid toward their luminance-weighted one: the way their bright side faces
/// ([`moment_tilt`]). The one home of that measure ([`Token::bright_side`], the experiment's
/// images).
pub fn luminance_moment(image: &Image, pixels: &[usize]) -> (f64, f64, f64) {
    let w = image.width();
    let n = pixels.len().max(1) as f64;
    let at = |p: usize| (p % w) as f64;
    let up = |p: usize| -((p / w) as f64);
    let (mx, my, mi) = pixels.iter().fold((0.0, 0.0, 0.0), |(x, y, i), &p| {
        (x + at(p), y + up(p), i + image.data()[p])
    });
    let (mx, my, mi) = (mx / n, my / n, mi / n);
    let (mut dx, mut dy, mut spread) = (0.0, 0.0, 0.0);
    for &p in pixels {
        let weight = image.data()[p] - mi;
        dx += weight * (at(p) - mx);
        dy += weight * (up(p) - my);
        spread += weight.abs();
    }
    (dx, dy, spread)
}

/// The tilt (0 = up, +90 = left, degrees in [0, 360)) of a moment (dx, dy) with y up.
pub fn moment_tilt(dx: f64, dy: f64) -> f64 {
    crate::analysis::wrap_360((-dx).atan2(dy).to_degrees())
}

/// The reading of a token's signed convexity: convex, concave, or flat when it is within
/// [`CONVEXITY_ZERO`] of zero.
///
/// ```
/// use shadelab_analysis::analysis::convexity::Verdict;
/// assert_eq!(Verdict::of(0.3), Verdict::Convex);
/// assert_eq!(Verdict::of(-0.3).to_string(), "concave");
/// assert_eq!(Verdict::of(0.0), Verdict::Flat);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// The middle stands out toward the viewer.
    Convex,
    /// The middle lies back, away from the viewer.
    Concave,
    /// Neither: the convexity is (numerically) zero.
    Flat,
}

impl Verdict {
    /// The verdict on a signed convexity (NaN reads as flat).
    pub fn of(convexity: f64) -> Verdict {
        if convexity.is_nan() || convexity.abs() <= CONVEXITY_ZERO {
            Verdict::Flat
        } else if convexity > 0.0 {
            Verdict::Convex
        } else {
            Verdict::Concave
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Verdict::Convex => "convex",
            Verdict::Concave => "concave",
            Verdict::Flat => "flat",
        })
    }
}

/// The index of the token whose centroid lies nearest the centre of a `width`-pixel-wide
/// picture (the first of equals), `None` when there are no tokens: the *central target* a
/// single judgement is about.
///
/// ```
/// use shadelab_analysis::analysis::convexity::{central_token, tokens_from_labels};
/// use shadelab::Grid;
/// // Two 4x4 squares in a 12x4 picture: label 1 on the left, label 2 in the middle.
/// let labels = Grid::from_fn(12, 4, |c, _| if c < 4 { 1u16 } else if (4..8).contains(&c) { 2 } else { 0 });
/// let tokens = tokens_from_labels(&labels, &[])?;
/// assert_eq!(central_token(&tokens, 12, 4), Some(1));
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn central_token(tokens: &[Token], width: usize, height: usize) -> Option<usize> {
    let (cx, cy) = ((width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0);
    let distance = |t: &Token| {
        let (x, y) = t.centroid(width);
        (x - cx).hypot(y - cy)
    };
    let mut best: Option<(usize, f64)> = None;
    for (i, t) in tokens.iter().enumerate() {
        let d = distance(t);
        if best.map_or(true, |(_, b)| d < b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

fn mean_over(depth: &Image, pixels: &[usize]) -> f64 {
    // A fixed order of summation: same answer whatever else runs.
    let sum: f64 = pixels.iter().map(|&p| depth.data()[p]).sum();
    sum / pixels.len() as f64
}

/// The tokens of a label map, in label order: label k is named `names[k − 1]` when given,
/// `label k` otherwise; labels that no pixel carries are skipped.
///
/// Fails when no pixel carries a label (a mask with no tokens), or when a token is too thin to
/// have a core apart from its rim (under 3 pixels across).
pub fn tokens_from_labels(labels: &Labels, names: &[String]) -> Result<Vec<Token>> {
    let (w, h) = (labels.width(), labels.height());
    // Bounding boxes per label, in one pass.
    let max_label = labels.data().iter().copied().max().unwrap_or(0) as usize;
    let mut boxes: Vec<Option<(usize, usize, usize, usize)>> = vec![None; max_label + 1];
    for row in 0..h {
        for col in 0..w {
            let l = *labels.get(col, row) as usize;
            if l == 0 {
                continue;
            }
            let b = boxes[l].get_or_insert((col, row, col, row));
            b.0 = b.0.min(col);
            b.1 = b.1.min(row);
            b.2 = b.2.max(col);
            b.3 = b.3.max(row);
        }
    }
    let mut tokens = Vec::new();
    for (label, bbox) in boxes.iter().enumerate() {
        let Some(bbox) = *bbox else { continue };
        let label = label as u16;
        let name = names
            .get(label as usize - 1)
            .cloned()
            .unwrap_or_else(|| format!("label {label}"));
        tokens.push(token_in_box(labels, label, name, bbox)?);
    }
    if tokens.is_empty() {
        return Err(Error::invalid(
            "the target mask has no tokens: every pixel is 0 (background)",
        ));
    }
    Ok(tokens)
}

/// Builds the token of `label` whose pixels lie in the box (c0, r0, c1, r1), inclusive.
fn token_in_box(
    labels: &Labels,
    label: u16,
    name: String,
    (c0, r0, c1, r1): (usize, usize, usize, usize),
) -> Result<Token> {
    let w = labels.width();
    // The box grown by one pixel on each side, so that its border is outside the token even
    // where the token touches the picture's frame (the frame is an edge too).
    let (bw, bh) = (c1 - c0 + 3, r1 - r0 + 3);
    let inside = |bc: usize, br: usize| -> bool {
        if bc == 0 || br == 0 || bc == bw - 1 || br == bh - 1 {
            return false;
        }
        *labels.get(c0 + bc - 1, r0 + br - 1) == label
    };
    let mut dist2 = vec![0.0; bw * bh];
    for br in 0..bh {
        for bc in 0..bw {
            dist2[br * bw + bc] = if inside(bc, br) { FAR } else { 0.0 };
        }
    }
    squared_distance_transform(&mut dist2, bw, bh);
    let mut pixels = Vec::new();
    let mut dists = Vec::new();
    for br in 1..bh - 1 {
        for bc in 1..bw - 1 {
            if inside(bc, br) {
                pixels.push((r0 + br - 1) * w + (c0 + bc - 1));
                dists.push(dist2[br * bw + bc].sqrt());
            }
        }
    }
    let half_width = dists.iter().fold(0.0f64, |a, &b| a.max(b));
    let rim_width = (0.25 * half_width).max(1.0);
    let core_from = rim_width.max(0.5 * half_width);
    let rim: Vec<usize> = pixels
        .iter()
        .zip(&dists)
        .filter(|(_, &d)| d <= rim_width)
        .map(|(&p, _)| p)
        .collect();
    let core: Vec<usize> = pixels
        .iter()
        .zip(&dists)
        .filter(|(_, &d)| d > core_from)
        .map(|(&p, _)| p)
        .collect();
    if core.is_empty() || rim.is_empty() {
        return Err(Error::invalid(format!(
            "token '{name}' (label {label}) is too thin to judge its convexity: it needs pixels at least 2 pixels from its edge"
        )));
    }
    Ok(Token {
        label,
        name,
        pixels,
        core,
        rim,
        half_width,
    })
}

/// A squared distance larger than any in a picture, standing for "not yet reached"; finite, so
/// that the envelope arithmetic below never meets ∞ − ∞.
const FAR: f64 = 1e18;

/// The exact squared Euclidean distance transform (Felzenszwalb & Huttenlocher 2012), in place:
/// on entry 0 at the sites (pixels outside the token) and [`FAR`] elsewhere; on return each
/// value is the squared distance to the nearest site. Columns first, then rows.
fn squared_distance_transform(grid: &mut [f64], w: usize, h: usize) {
    let n = w.max(h);
    let mut f = vec![0.0; n];
    let mut d = vec![0.0; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0.0; n + 1];
    for col in 0..w {
        for row in 0..h {
            f[row] = grid[row * w + col];
        }
        lower_envelope(&f[..h], &mut d[..h], &mut v, &mut z);
        for row in 0..h {
            grid[row * w + col] = d[row];
        }
    }
    for row in 0..h {
        f[..w].copy_from_slice(&grid[row * w..(row + 1) * w]);
        lower_envelope(&f[..w], &mut d[..w], &mut v, &mut z);
        grid[row * w..(row + 1) * w].copy_from_slice(&d[..w]);
    }
}

/// One-dimensional pass: d(q) = min over p of (q − p)² + f(p), by the lower envelope of the
/// parabolas rooted at each p.
fn lower_envelope(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    let mut k = 0usize;
    v[0] = 0;
    z[0] = f64::NEG_INFINITY;
    z[1] = f64::INFINITY;
    for q in 1..n {
        let qf = q as f64;
        // z[0] = −∞, so the search always stops at k ≥ 0.
        let mut s;
        loop {
            let p = v[k] as f64;
            s = ((f[q] + qf * qf) - (f[v[k]] + p * p)) / (2.0 * qf - 2.0 * p);
            if s > z[k] {
                break;
            }
            k -= 1;
        }
        k += 1;
        v[k] = q;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    k = 0;
    for (q, out) in d.iter_mut().enumerate() {
        while z[k + 1] < q as f64 {
            k += 1;
        }
        let dq = q as f64 - v[k] as f64;
        *out = dq * dq + f[v[k]];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Grid;

    #[test]
    fn verdicts_and_the_central_token() {
        assert_eq!(Verdict::of(2.0 * CONVEXITY_ZERO), Verdict::Convex);
        assert_eq!(Verdict::of(-2.0 * CONVEXITY_ZERO), Verdict::Concave);
        assert_eq!(Verdict::of(CONVEXITY_ZERO), Verdict::Flat);
        assert_eq!(Verdict::of(f64::NAN), Verdict::Flat);
        assert_eq!(
            serde_json::to_string(&Verdict::Concave).unwrap(),
            "\"concave\""
        );
        // A 3x3 grid of 5x5 squares in a 17x17 picture: the middle one (label 5) is central,
        // whatever the label order.
        let labels = Grid::from_fn(17, 17, |c, r| {
            let (i, j) = (c / 6, r / 6);
            if c % 6 == 5 || r % 6 == 5 {
                0u16
            } else {
                [3u16, 1, 7, 2, 5, 8, 9, 4, 6][j * 3 + i]
            }
        });
        let tokens = tokens_from_labels(&labels, &[]).unwrap();
        let k = central_token(&tokens, 17, 17).unwrap();
        assert_eq!(tokens[k].label, 5);
        assert_eq!(central_token(&[], 17, 17), None);
    }

    #[test]
    fn the_bright_side_of_a_lit_bump_faces_the_light_and_a_dimple_away() {
        use crate::light::Light;
        // A hemisphere of radius 10 under lights of several tilts: the bright side faces the
        // light's tilt; the depth-negated dimple faces the opposite way.
        let (w, h, rad) = (25usize, 25usize, 10.0);
        for tilt in [0.0, 26.0, 90.0, 200.0, 300.0] {
            let s = Light::from_tilt_slant(tilt, 45.0).unwrap().direction();
            for sign in [1.0, -1.0] {
                let image = Grid::from_fn(w, h, |c, r| {
                    let (x, y) = (c as f64 - 12.0, 12.0 - r as f64);
                    let z2 = rad * rad - x * x - y * y;
                    let n = if z2 > 0.0 {
                        [sign * x / rad, sign * y / rad, z2.sqrt() / rad]
                    } else {
                        [0.0, 0.0, 1.0]
                    };
                    (n[0] * s.x + n[1] * s.y + n[2] * s.z).max(0.0)
                });
                let (side, strength) = Token::whole(w, h).unwrap().bright_side(&image);
                let want = if sign > 0.0 { tilt } else { tilt + 180.0 };
                let off = crate::analysis::wrap_180(side - want).abs();
                assert!(off < 1.0, "tilt {tilt} sign {sign}: {side}");
                assert!(strength > 0.01, "{strength}");
            }
        }
        let flat = Grid::new(5, 5, 0.5);
        assert_eq!(Token::whole(5, 5).unwrap().bright_side(&flat), (0.0, 0.0));
    }

    /// Brute-force distance from each token pixel to the nearest non-token pixel (the frame
    /// counting as outside).
    fn brute(labels: &Labels, label: u16) -> Vec<f64> {
        let (w, h) = (labels.width() as isize, labels.height() as isize);
        let mut out = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if *labels.get(c as usize, r as usize) != label {
                    continue;
                }
                let mut best = f64::INFINITY;
                for rr in -1..=h {
                    for cc in -1..=w {
                        let outside = labels.checked(cc, rr).is_none_or(|&l| l != label);
                        if outside {
                            let d = (((cc - c) * (cc - c) + (rr - r) * (rr - r)) as f64).sqrt();
                            best = best.min(d);
                        }
                    }
                }
                out.push(best);
            }
        }
        out
    }

    #[test]
    fn distance_transform_matches_brute_force() {
        // Two touching blobs and a token cut by the frame.
        let labels = Grid::from_fn(23, 17, |c, r| {
            let (x, y) = (c as f64 - 7.0, r as f64 - 8.0);
            if x * x + 0.5 * y * y < 40.0 {
                1
            } else if c > 14 && r < 12 {
                2
            } else {
                0
            }
        });
        for label in [1u16, 2] {
            let want = brute(&labels, label);
            let (c0, r0, c1, r1) = {
                let mut b = (usize::MAX, usize::MAX, 0, 0);
                for r in 0..17 {
                    for c in 0..23 {
                        if *labels.get(c, r) == label {
                            b = (b.0.min(c), b.1.min(r), b.2.max(c), b.3.max(r));
                        }
                    }
                }
                b
            };
            let (bw, bh) = (c1 - c0 + 3, r1 - r0 + 3);
            let mut g = vec![0.0; bw * bh];
            for br in 1..bh - 1 {
                for bc in 1..bw - 1 {
                    if *labels.get(c0 + bc - 1, r0 + br - 1) == label {
                        g[br * bw + bc] = FAR;
                    }
                }
            }
            squared_distance_transform(&mut g, bw, bh);
            let mut got = Vec::new();
            for br in 1..bh - 1 {
                for bc in 1..bw - 1 {
                    if *labels.get(c0 + bc - 1, r0 + br - 1) == label {
                        got.push(g[br * bw + bc].sqrt());
                    }
                }
            }
            assert_eq!(got.len(), want.len());
            for (a, b) in got.iter().zip(&want) {
                assert!((a - b).abs() < 1e-9, "label {label}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn a_bump_is_convex_a_dimple_concave_and_negation_is_exact() {
        let (w, h) = (40, 30);
        let labels = Grid::from_fn(w, h, |c, r| {
            let (x, y) = (c as f64 - 19.5, r as f64 - 14.5);
            u16::from(x * x + y * y < 100.0)
        });
        let tokens = tokens_from_labels(&labels, &["disc".into()]).unwrap();
        assert_eq!(tokens.len(), 1);
        let t = &tokens[0];
        assert_eq!(t.name, "disc");
        assert!((t.half_width() - 10.0).abs() < 1.5, "{}", t.half_width());
        let bump = Grid::from_fn(w, h, |c, r| {
            let (x, y) = (c as f64 - 19.5, r as f64 - 14.5);
            (100.0 - x * x - y * y).max(0.0).sqrt() + 3.0
        });
        let dimple = bump.map(|z| -z);
        let c = t.convexity(&bump);
        assert!(c > 0.3 && c < 0.6, "{c}");
        assert_eq!(t.convexity(&dimple), -c);
        // An offset changes nothing, a plane tilted across the token nothing either.
        let tilted = Grid::from_fn(w, h, |col, row| {
            bump.get(col, row) + 100.0 + 0.3 * (col as f64 - 19.5)
        });
        assert!((t.convexity(&tilted) - c).abs() < 1e-9);
    }

    #[test]
    fn no_tokens_and_thin_tokens_are_errors() {
        let empty = Labels::new(8, 8, 0);
        let e = tokens_from_labels(&empty, &[]).unwrap_err().to_string();
        assert!(e.contains("no tokens"), "{e}");
        let line = Grid::from_fn(8, 8, |_, r| u16::from(r == 3));
        let e = tokens_from_labels(&line, &[]).unwrap_err().to_string();
        assert!(e.contains("too thin") && e.contains("label 1"), "{e}");
        let whole = Token::whole(9, 7).unwrap();
        assert_eq!(whole.pixels().len(), 63);
        assert_eq!(whole.name, "image");
    }
}
