//! Boundary conditions for shape from shading, derived from a mask.
//!
//! The solver works on the masked domain. Some of its pixels hold known (f, g) values — the
//! Dirichlet data — and the rest are unknowns. Which pixels are fixed, and to what, depends on
//! the [`Boundary`] chosen:
//!
//! - [`Boundary::Occluding`] (Ikeuchi & Horn 1981): on the silhouette the surface turns away
//!   from the viewer, so its normal is perpendicular to the view v = (0, 0, 1) and to the
//!   contour tangent e: n = e × v, with e the counter-clockwise tangent so that n points out of
//!   the object. Such normals lie on the rim of the f–g disc, |(f, g)| = 2, which shadelab
//!   shrinks by [`OCCLUDING_SHRINK`] = 0.9 (see there why). The tangent comes from a smooth fit
//!   to the digitised contour, not from a raw 8-neighbour step, so a digitised circle gives
//!   radial normals to a fraction of a degree ([`occluding_normals`]).
//! - [`Boundary::Flat`]: the object is a relief on a plane facing the viewer; the rim and the
//!   image border hold n = (0, 0, 1).
//! - [`Boundary::Free`]: nothing is fixed (the natural boundary condition: no smoothness
//!   coupling across the domain's edge).
//! - [`Boundary::Given`]: the rim holds normals supplied by the user.
//!
//! Where the mask reaches the image frame the object is cut by the frame, not occluded: with
//! [`Boundary::Occluding`] those pixels are a free boundary, never fixed to the limb.
//!
//! The *rim* of a mask is its pixels with at least one 4-neighbour outside the mask or outside
//! the image.

use crate::error::{Error, Result};
use crate::gradient_space::{fg_from_normal, Normal, FG_RADIUS};
use crate::grid::{Grid, Image, Mask};
use crate::reflectance::ReflectanceMap;
use nalgebra::Vector3;
use serde::Serialize;

/// The factor by which occluding-boundary values are pulled in from the rim of the f–g disc:
/// fixed pixels get |(f, g)| = [`FG_RADIUS`] × `OCCLUDING_SHRINK` = 1.8.
///
/// The limb itself (factor 1) is where the surface is seen edge-on, but the centres of the
/// rim pixels lie inside the silhouette, about half a pixel on average, where the surface
/// already turns toward the viewer: on a sphere of radius R pixels, half a pixel in gives
/// n_z ≈ 1/√R and |(f, g)| = 2·√((1 − n_z)/(1 + n_z)), a factor 0.83 at R = 29, 0.88 at
/// R = 58, 0.91 at R = 115. Measured on the 128² sphere (R = 57.6, frontal light) the mean
/// normal error is 0.24° with factor 1 and 0.14° with 0.9; on the 128² vase 3.44° and 3.32°.
pub const OCCLUDING_SHRINK: f64 = 0.9;

/// The standard deviation, in pixels, of the Gaussian that smooths the mask for the rough
/// contour direction (see [`occluding_normals`]).
pub const CONTOUR_SMOOTHING_PX: f64 = 2.0;

/// The standard deviation, in pixels, of the Gaussian window of the local cubic fit to the
/// contour that gives its tangent (see [`occluding_normals`]).
pub const CONTOUR_FIT_PX: f64 = 6.0;

/// Which boundary condition holds where the mask ends.
#[derive(Debug, Clone, PartialEq)]
pub enum Boundary {
    /// The silhouette is an occluding contour: n = e × v, outward, |(f, g)| = 2.
    Occluding,
    /// A relief on a plane facing the viewer: n = (0, 0, 1) on the rim and the image border.
    Flat,
    /// Nothing fixed: the natural boundary condition everywhere.
    Free,
    /// The occluding contour where the shading allows a limb; elsewhere the contour's
    /// outward direction at the slant the brightness gives ([`limb_conditions`]).
    Limb,
    /// The rim holds these normals (a grid the size of the image; only rim pixels are read).
    Given(Grid<Normal>),
}

/// The names of the built-in boundary conditions, as `--boundary` spells them.
pub const BOUNDARY_NAMES: &[&str] = &["occluding", "flat", "free", "limb"];

impl Boundary {
    /// The built-in condition called `name` (`occluding`, `flat`, `free` or `limb`).
    pub fn named(name: &str) -> Result<Boundary> {
        match name {
            "occluding" => Ok(Boundary::Occluding),
            "flat" => Ok(Boundary::Flat),
            "free" => Ok(Boundary::Free),
            "limb" => Ok(Boundary::Limb),
            other => Err(Error::unknown("boundary", other, BOUNDARY_NAMES)),
        }
    }

    /// A short name for reports (`given` for user normals).
    pub fn name(&self) -> &'static str {
        match self {
            Boundary::Occluding => "occluding",
            Boundary::Flat => "flat",
            Boundary::Free => "free",
            Boundary::Limb => "limb",
            Boundary::Given(_) => "given",
        }
    }
}

/// What a pixel is to the solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Outside the mask: not part of the problem.
    Outside,
    /// An unknown (f, g), coupled by smoothness to its 4-neighbours inside the mask.
    Unknown,
    /// A known (f, g), held fixed.
    Fixed,
}

/// The domain of a shape-from-shading problem: each pixel's role and the values of the fixed
/// ones.
///
/// The fixed values are kept per fixed pixel, not as two full images: they are a thin ring, and
/// a full-size copy would be 16 bytes per pixel at the moment a large solve's memory peaks.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundaryConditions {
    /// Each pixel's role.
    pub roles: Grid<Role>,
    /// (row-major pixel index, (f, g)) of every fixed pixel, in increasing index order.
    fixed: Vec<(usize, [f64; 2])>,
}

impl BoundaryConditions {
    /// The number of unknown pixels.
    pub fn unknown_count(&self) -> usize {
        self.roles
            .data()
            .iter()
            .filter(|&&r| r == Role::Unknown)
            .count()
    }

    /// The number of fixed pixels.
    pub fn fixed_count(&self) -> usize {
        self.fixed.len()
    }

    /// The (f, g) held at pixel (`col`, `row`), or `None` where the pixel is not fixed.
    pub fn fixed_value(&self, col: usize, row: usize) -> Option<[f64; 2]> {
        let index = row * self.roles.width() + col;
        self.fixed
            .binary_search_by_key(&index, |&(i, _)| i)
            .ok()
            .map(|k| self.fixed[k].1)
    }

    /// Conditions from their parts: `fixed` must be in increasing index order, and exactly the
    /// pixels whose role is [`Role::Fixed`].
    pub fn from_parts(roles: Grid<Role>, fixed: Vec<(usize, [f64; 2])>) -> Self {
        debug_assert!(fixed.windows(2).all(|w| w[0].0 < w[1].0));
        BoundaryConditions { roles, fixed }
    }

    /// Every fixed pixel as (row-major pixel index, (f, g)), in increasing index order.
    pub fn fixed_values(&self) -> &[(usize, [f64; 2])] {
        &self.fixed
    }
}

/// Whether pixel (`col`, `row`) of `mask` is on its rim: inside, with a 4-neighbour outside the
/// mask or outside the image.
pub fn is_rim(mask: &Mask, col: usize, row: usize) -> bool {
    if !*mask.get(col, row) {
        return false;
    }
    let (c, r) = (col as isize, row as isize);
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .iter()
        .any(|&(dc, dr)| !mask.checked(c + dc, r + dr).copied().unwrap_or(false))
}

/// Whether pixel (`col`, `row`) is on the occluding part of the rim: inside, with a 4-neighbour
/// that lies inside the image but outside the mask. Rim pixels that only touch the image frame
/// are where the frame cuts the object, and are not occluding.
pub fn is_occluding(mask: &Mask, col: usize, row: usize) -> bool {
    if !*mask.get(col, row) {
        return false;
    }
    let (c, r) = (col as isize, row as isize);
    [(1, 0), (-1, 0), (0, 1), (0, -1)]
        .iter()
        .any(|&(dc, dr)| mask.checked(c + dc, r + dr) == Some(&false))
}

/// The outward normal of the occluding contour at every occluding pixel (`None` elsewhere):
/// n = e × v with e the counter-clockwise unit tangent and v = (0, 0, 1), so n lies in the
/// image plane (n_z = 0).
///
/// The contour is the chain of edge midpoints between occluding pixels and their outside
/// 4-neighbours. A digitised contour is a staircase: near an axis it runs flat for many pixels
/// and then steps, so any estimate from a few pixels (an 8-neighbour step, or the gradient of a
/// slightly blurred mask) is off by several degrees (up to 9° on a digitised circle of radius
/// 58 with a blur of 2 pixels). The tangent at a pixel is instead the slope, at the pixel, of
/// a cubic v = a + b·u + c·u² + d·u³ fitted by Gaussian-weighted least squares
/// ([`CONTOUR_FIT_PX`]) to the nearby midpoints, in a frame (u along the rough tangent, v along
/// the rough normal) given by the gradient of the mask smoothed by a Gaussian of
/// [`CONTOUR_SMOOTHING_PX`]. The polynomial follows the contour's bending (the cubic term keeps
/// a changing curvature from tilting the slope), so the window can be wide enough to average
/// the staircase out: about 0.5° mean (1.5° worst) error on a digitised circle of radius 58,
/// 0.7° on the 128² vase. Near a corner the direction is a blend over the window.
/// Midpoints whose rough normal faces away from the pixel's (the far side of a thin neck) are
/// left out. The mask is extended past the image frame by replicating its edge, since an object
/// cut by the frame continues beyond it.
pub fn occluding_normals(mask: &Mask) -> Grid<Option<Normal>> {
    let mut normals = Grid::new(mask.width(), mask.height(), None);
    for (index, n) in occluding_normal_list(mask) {
        normals.data_mut()[index] = Some(n);
    }
    normals
}

/// [`occluding_normals`] as (row-major pixel index, normal) of the occluding pixels, in
/// increasing index order: the contour is a thin set, and per-pixel grids of it would cost tens
/// of bytes per pixel of the whole image.
fn occluding_normal_list(mask: &Mask) -> Vec<(usize, Normal)> {
    let (w, h) = (mask.width(), mask.height());
    let rough = rough_outward_normals(mask);
    // Which entry of `rough` each pixel is (NONE where it is not occluding).
    const NONE: u32 = u32::MAX;
    let mut entry = vec![NONE; w * h];
    for (k, &(index, _)) in rough.iter().enumerate() {
        entry[index] = k as u32;
    }
    // Contour midpoints of each occluding pixel, (world x, world y, owner's rough normal), in
    // `rough`'s order: those of entry k are points[start[k]..start[k + 1]].
    let mut points: Vec<(f64, f64, [f64; 2])> = Vec::new();
    let mut start = Vec::with_capacity(rough.len() + 1);
    for &(index, o) in &rough {
        start.push(points.len());
        let (col, row) = (index % w, index / w);
        let (x, y) = crate::surface::world_xy(col, row, w, h);
        let (c, r) = (col as isize, row as isize);
        for (dc, dr) in [(1isize, 0isize), (-1, 0), (0, 1), (0, -1)] {
            if mask.checked(c + dc, r + dr) == Some(&false) {
                // World y = −row.
                points.push((x + 0.5 * dc as f64, y - 0.5 * dr as f64, o));
            }
        }
    }
    start.push(points.len());
    let sigma = CONTOUR_FIT_PX;
    let reach = (3.0 * sigma).ceil() as isize;
    rough
        .iter()
        .map(|&(index, o)| {
            let (col, row) = (index % w, index / w);
            let t = [-o[1], o[0]];
            let (x0, y0) = crate::surface::world_xy(col, row, w, h);
            // Weighted normal equations of the fit v = a + b·u + c·u² + d·u³.
            let mut ata = nalgebra::Matrix4::<f64>::zeros();
            let mut atv = nalgebra::Vector4::<f64>::zeros();
            let mut count = 0;
            let (c0, r0) = (col as isize, row as isize);
            for r in (r0 - reach).max(0)..=(r0 + reach).min(h as isize - 1) {
                for c in (c0 - reach).max(0)..=(c0 + reach).min(w as isize - 1) {
                    let k = entry[r as usize * w + c as usize];
                    if k == NONE {
                        continue;
                    }
                    let k = k as usize;
                    for &(px, py, po) in &points[start[k]..start[k + 1]] {
                        if po[0] * o[0] + po[1] * o[1] <= 0.0 {
                            continue;
                        }
                        let (dx, dy) = (px - x0, py - y0);
                        let d2 = dx * dx + dy * dy;
                        if d2 > (3.0 * sigma) * (3.0 * sigma) {
                            continue;
                        }
                        let wt = (-d2 / (2.0 * sigma * sigma)).exp();
                        let u = dx * t[0] + dy * t[1];
                        let v = dx * o[0] + dy * o[1];
                        let basis = nalgebra::Vector4::new(1.0, u, u * u, u * u * u);
                        ata += basis * basis.transpose() * wt;
                        atv += basis * (v * wt);
                        count += 1;
                    }
                }
            }
            let slope = if count >= 5 {
                ata.cholesky().map(|ch| ch.solve(&atv)[1])
            } else {
                None
            };
            // Without enough contour to fit (a speck, a one-pixel line), the rough normal
            // stands.
            let b = slope.filter(|b| b.is_finite()).unwrap_or(0.0);
            // The contour runs along (1, b) in the (t, o) frame; its outward normal is (−b, 1).
            let (nx, ny) = (o[0] - b * t[0], o[1] - b * t[1]);
            let len = nx.hypot(ny);
            // Counter-clockwise tangent: the object lies to its left, so e = outward turned
            // +90°.
            let e = Vector3::new(-ny / len, nx / len, 0.0);
            (index, e.cross(&Vector3::z()))
        })
        .collect()
}

/// The rough outward unit normal (world x, y) at each occluding pixel: minus the gradient of
/// the mask smoothed by a Gaussian of [`CONTOUR_SMOOTHING_PX`], with the mask replicated past
/// the image frame. Where that gradient vanishes (a one-pixel line) the direction away from the
/// pixel's inside neighbours is used.
fn rough_outward_normals(mask: &Mask) -> Vec<(usize, [f64; 2])> {
    let (w, h) = (mask.width(), mask.height());
    let sigma = CONTOUR_SMOOTHING_PX;
    let radius = (3.0 * sigma).ceil() as isize;
    // Derivative-of-Gaussian taps; the common normalisation does not matter for a direction.
    let taps: Vec<(isize, isize, f64)> = (-radius..=radius)
        .flat_map(|dr| (-radius..=radius).map(move |dc| (dc, dr)))
        .map(|(dc, dr)| {
            let d2 = (dc * dc + dr * dr) as f64;
            (dc, dr, (-d2 / (2.0 * sigma * sigma)).exp())
        })
        .collect();
    let inside = |c: isize, r: isize| -> f64 {
        let c = c.clamp(0, w as isize - 1) as usize;
        let r = r.clamp(0, h as isize - 1) as usize;
        if *mask.get(c, r) {
            1.0
        } else {
            0.0
        }
    };
    let mut rough = Vec::new();
    for (index, (col, row)) in (0..h).flat_map(|r| (0..w).map(move |c| (c, r))).enumerate() {
        if !is_occluding(mask, col, row) {
            continue;
        }
        let (c, r) = (col as isize, row as isize);
        // Gradient of the smoothed mask along +col and +row; it points into the object.
        let (mut gc, mut gr) = (0.0, 0.0);
        for &(dc, dr, wt) in &taps {
            let m = inside(c + dc, r + dr);
            gc += wt * dc as f64 * m;
            gr += wt * dr as f64 * m;
        }
        // World y = −row, so outward in world axes is (−gc, gr).
        let (mut ox, mut oy) = (-gc, gr);
        if ox.hypot(oy) < 1e-9 {
            (ox, oy) = (0.0, 0.0);
            for (dc, dr) in [(1isize, 0isize), (-1, 0), (0, 1), (0, -1)] {
                if mask.checked(c + dc, r + dr) == Some(&false) {
                    ox += dc as f64;
                    oy -= dr as f64;
                }
            }
            if ox.hypot(oy) < 1e-9 {
                // Outside on opposite sides: a one-pixel line; pick one of its sides.
                (ox, oy) = if mask.checked(c + 1, r) == Some(&false) {
                    (1.0, 0.0)
                } else {
                    (0.0, 1.0)
                };
            }
        }
        let len = ox.hypot(oy);
        rough.push((index, [ox / len, oy / len]));
    }
    rough
}

/// How far below 0 a given unit normal's z may be (rounding of an in-plane normal) before it
/// is taken to face away from the viewer.
const FACING_AWAY_TOLERANCE: f64 = 1e-9;

/// The domain and fixed values that `boundary` gives on `mask`.
///
/// Fails when the mask is empty, or when given normals have the wrong size or are not finite,
/// non-zero vectors facing the viewer (n_z ≥ 0) on the rim.
pub fn boundary_conditions(mask: &Mask, boundary: &Boundary) -> Result<BoundaryConditions> {
    let (w, h) = (mask.width(), mask.height());
    if mask.count() == 0 {
        return Err(Error::invalid(
            "the mask is empty: there is no object to reconstruct",
        ));
    }
    let mut roles = mask.map(|&m| if m { Role::Unknown } else { Role::Outside });
    let mut fixed = Vec::new();
    match boundary {
        Boundary::Free => {}
        Boundary::Flat => {
            for row in 0..h {
                for col in 0..w {
                    if is_rim(mask, col, row) {
                        fixed.push((row * w + col, [0.0, 0.0]));
                    }
                }
            }
        }
        Boundary::Limb => {
            return Err(Error::invalid(
                "the limb boundary depends on the image and the reflectance map: build it from \
                 the occluding conditions with limb_conditions",
            ))
        }
        Boundary::Occluding => {
            let radius = FG_RADIUS * OCCLUDING_SHRINK;
            for (index, n) in occluding_normal_list(mask) {
                // An in-plane unit normal maps to 2(n_x, n_y); scale to the radius.
                let r = n.x.hypot(n.y);
                fixed.push((index, [radius * n.x / r, radius * n.y / r]));
            }
        }
        Boundary::Given(normals) => {
            normals.check_same_size("boundary normals are", mask, "the image is")?;
            for row in 0..h {
                for col in 0..w {
                    if !is_rim(mask, col, row) {
                        continue;
                    }
                    let n = normals.get(col, row);
                    let len = n.norm();
                    if !len.is_finite() || len < 1e-9 {
                        return Err(Error::invalid(format!(
                            "boundary normal at column {col}, row {row} is ({}, {}, {}): it must \
                             be a finite non-zero vector",
                            n.x, n.y, n.z
                        )));
                    }
                    // z points toward the viewer: a visible surface's normal has n_z ≥ 0, and
                    // n_z = 0 is the occluding rim itself (what `occluding` fixes); a little
                    // below 0 is taken for rounding.
                    if n.z / len < -FACING_AWAY_TOLERANCE {
                        return Err(Error::invalid(format!(
                            "boundary normal at column {col}, row {row} is ({}, {}, {}): it faces \
                             away from the viewer (n_z < 0, with z toward the viewer), so that \
                             surface could not be seen",
                            n.x, n.y, n.z
                        )));
                    }
                    let (fv, gv) = fg_from_normal(&(n / len));
                    fixed.push((row * w + col, [fv, gv]));
                }
            }
        }
    }
    for &(index, _) in &fixed {
        roles.data_mut()[index] = Role::Fixed;
    }
    Ok(BoundaryConditions { roles, fixed })
}

/// The largest n_z that [`limb_conditions`] allows a rim pixel on a limb: the centre of a rim
/// pixel lies up to one pixel inside the silhouette, where a surface whose cross-section has a
/// radius of curvature of r pixels has turned to n_z ≈ √(2/r) toward the viewer; 0.5 is r = 8
/// pixels (a slant of 60°), below which an object is too small for shape from shading anyway.
pub const LIMB_MAX_NZ: f64 = 0.5;

/// How far, in degrees, [`limb_conditions`] lets the in-plane direction of a limb's normal
/// differ from the contour's fitted outward normal: the fit is within 1.5° on a smooth contour
/// ([`occluding_normals`]), a few degrees near a corner, where it blends.
pub const LIMB_DIRECTION_TOLERANCE_DEG: f64 = 5.0;

/// The fewest rim pixels in attached shadow from which [`limb_conditions`] estimates the
/// image's dark level ([`dark_level`]; fewer give none): the median of a handful of pixels
/// says little about a picture's black.
pub const LIMB_DARK_MIN_PIXELS: usize = 16;

/// The highest dark level [`limb_conditions`] accepts, as a fraction of the albedo: a
/// photograph's black reads a few thousandths to a percent or two of its albedo (a median of
/// 0.005, readings 0–0.016, on the DiLiGenT ball's shadowed limb at slant 43°); a shadowed rim
/// that reads more is lit, a cut seen in light, and gets no allowance.
pub const LIMB_MAX_DARK_LEVEL: f64 = 0.05;

/// The occluding conditions with the shading's test applied ([`limb_conditions`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LimbConditions {
    /// The conditions to solve with.
    pub conditions: BoundaryConditions,
    /// What the test found: the figures a solve reports.
    pub test: LimbTest,
}

/// What the limb test found on an outline ([`limb_conditions`]); a solve's report and the
/// evaluation's rows give its two fields.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LimbTest {
    /// The occluding pixels whose brightness rules out a limb: fixed at the slant the shading
    /// gives, or left free where the image is clipped there.
    pub not_limb: usize,
    /// The image's dark level read on the outline, the tolerance added to the limb's brightness
    /// bound ([`dark_level`]): 0 for an exact render.
    pub dark_level: f64,
}

/// The dark level of an image from the `readings` of its rim pixels where a limb would be in
/// attached shadow (R = 0 for every normal a limb could have there): their median, what the
/// picture reads where no light falls. A photograph's black is an offset plus noise; the offset
/// is a bias that the limb test must allow for, the noise is zero-mean and left, as everywhere
/// else, to the solve. It is 0 where at least half of them read exactly 0 (a render's shadow),
/// where there are fewer than [`LIMB_DARK_MIN_PIXELS`], and where the median exceeds
/// [`LIMB_MAX_DARK_LEVEL`] (the shadowed rim is then mostly lit, a cut, and its readings are
/// shading, not a dark level).
///
/// ```
/// use shadelab_engine::boundary::dark_level;
///
/// // A render: the shadowed limb reads exactly 0.
/// assert_eq!(dark_level(&[0.0; 40]), 0.0);
/// // A photograph: a plateau of 0.000–0.010.
/// let plateau: Vec<f64> = (0..41).map(|k| 0.00025 * k as f64).collect();
/// assert!((dark_level(&plateau) - 0.005).abs() < 1e-12);
/// // Mostly lit: a cut, not a dark level.
/// assert_eq!(dark_level(&[0.3; 40]), 0.0);
/// ```
pub fn dark_level(readings: &[f64]) -> f64 {
    if readings.len() < LIMB_DARK_MIN_PIXELS {
        return 0.0;
    }
    let mut sorted = readings.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[(sorted.len() - 1) / 2];
    if median > LIMB_MAX_DARK_LEVEL {
        return 0.0;
    }
    median
}

/// The occluding conditions where the shading allows a limb, and elsewhere the contour's
/// outward direction at the slant the shading gives ([`Boundary::Limb`]).
///
/// `occluding` are the conditions [`boundary_conditions`] gives with [`Boundary::Occluding`];
/// each fixed pixel's (f, g) points along the contour's outward normal m. A rim pixel on a limb
/// has a normal nearly in the image plane along m: n = (cos ε·m, sin ε) with
/// sin ε = n_z ≤ [`LIMB_MAX_NZ`], the in-plane direction within
/// [`LIMB_DIRECTION_TOLERANCE_DEG`] of m. A pixel brighter than the reflectance map gives any
/// of those normals cannot be on a limb: the outline there is a cut (the edge of a range scan,
/// a relief's border), and the surface faces the viewer more than a limb does. Such a pixel is
/// fixed at the azimuth of m with the smallest elevation ε ≥ asin(`LIMB_MAX_NZ`) at which
/// R = I (the orientation closest to edge-on that the brightness allows; where no elevation
/// reaches I, the one that comes closest), so that it keeps the outward direction, which tells
/// a bump from a dent, and loses only the slant that the brightness contradicts. Where the
/// image is clipped (I ≥ `saturation`) the brightness gives no slant and the pixel is left
/// free. Dark pixels keep their occluding value: a limb in shadow is consistent with them.
/// A pixel counts as brighter than a limb only above the bound plus the image's dark level
/// ([`dark_level`], the median reading of the rim pixels where a limb would be in attached
/// shadow): a photograph reads an offset plus noise, not 0, where no light falls (0–0.016 of
/// the albedo, median 0.005, on the DiLiGenT ball at a slant of 43°), and without the offset
/// its whole shadowed limb would read as surface just past the terminator. The noise about
/// the offset is not allowed for: those brighter than it are held past the terminator as the
/// data term pulls them. An exact render's shadow is 0, its dark level 0, and the test is the
/// bare bound.
/// On a true limb under any light nothing changes.
///
/// ```
/// use shadelab_engine::boundary::{boundary_conditions, limb_conditions, Boundary};
/// use shadelab_core::gradient_space::normal_from_fg;
/// use shadelab::Lambertian;
/// use shadelab_engine::render::{render, RenderOptions};
/// use shadelab_engine::surface::sphere;
/// use shadelab::Light;
///
/// let ball = sphere(64, 64, 28.0).unwrap();
/// let map = Lambertian::unit(Light::FRONT);
/// let mut image = render(&ball, &map, &RenderOptions::default()).image;
/// let occluding = boundary_conditions(&ball.mask, &Boundary::Occluding).unwrap();
/// // A sphere's outline is a limb: nothing changes.
/// let limb = limb_conditions(&occluding, &image, &map, None);
/// assert_eq!((limb.test.not_limb, &limb.conditions), (0, &occluding));
/// // A rim pixel at brightness 0.9 under a frontal light faces the viewer (n_z = 0.9).
/// let (index, _) = occluding.fixed_values()[0];
/// image.data_mut()[index] = 0.9;
/// let limb = limb_conditions(&occluding, &image, &map, None);
/// assert_eq!(limb.test.not_limb, 1);
/// let (col, row) = (index % 64, index / 64);
/// let [f, g] = limb.conditions.fixed_value(col, row).unwrap();
/// assert!((normal_from_fg(f, g).z - 0.9).abs() < 1e-6);
/// ```
pub fn limb_conditions(
    occluding: &BoundaryConditions,
    image: &Image,
    reflectance: &dyn ReflectanceMap,
    saturation: Option<f64>,
) -> LimbConditions {
    let mut roles = occluding.roles.clone();
    let mut fixed = Vec::with_capacity(occluding.fixed.len());
    let mut not_limb = 0;
    // Each fixed pixel's contour azimuth and the brightest a limb there can be.
    let limbs: Vec<(f64, f64)> = (occluding.fixed.iter())
        .map(|&(_, fg)| {
            let azimuth = fg[1].atan2(fg[0]);
            (azimuth, limb_brightness_bound(azimuth, reflectance))
        })
        .collect();
    let shadowed: Vec<f64> = (occluding.fixed.iter().zip(&limbs))
        .filter(|&(_, &(_, bound))| bound <= 0.0)
        .map(|(&(index, _), _)| image.data()[index])
        .collect();
    let dark = dark_level(&shadowed);
    for (&(index, fg), &(azimuth, bound)) in occluding.fixed.iter().zip(&limbs) {
        let intensity = image.data()[index];
        if intensity <= bound + dark {
            fixed.push((index, fg));
            continue;
        }
        not_limb += 1;
        if saturation.is_some_and(|s| intensity >= s) {
            roles.data_mut()[index] = Role::Unknown;
            continue;
        }
        let elevation = shading_elevation(azimuth, intensity, reflectance);
        let (f, g) = fg_from_normal(&in_plane_normal(azimuth, elevation));
        fixed.push((index, [f, g]));
    }
    LimbConditions {
        conditions: BoundaryConditions { roles, fixed },
        test: LimbTest {
            not_limb,
            dark_level: dark,
        },
    }
}

/// Each pixel's role under `boundary`, before any image is read: for [`Boundary::Limb`] those
/// of [`Boundary::Occluding`], since the limb condition fixes the same pixels (only where the
/// image is clipped does it leave one of them free, which needs the image); for the others
/// those of [`boundary_conditions`].
///
/// Fails as [`boundary_conditions`] does.
pub fn domain_roles(mask: &Mask, boundary: &Boundary) -> Result<Grid<Role>> {
    let boundary = match boundary {
        Boundary::Limb => &Boundary::Occluding,
        other => other,
    };
    Ok(boundary_conditions(mask, boundary)?.roles)
}

/// How many occluding pixels of `mask` the shading of `image` rules out as a limb
/// ([`LimbTest::not_limb`]): what the solver's [`Boundary::Limb`] does, counted for a
/// report.
///
/// Fails when the mask is empty or the image is not the mask's size.
pub fn limb_count(
    mask: &Mask,
    image: &Image,
    reflectance: &dyn ReflectanceMap,
    saturation: Option<f64>,
) -> Result<usize> {
    image.check_same_size("image is", mask, "the mask is")?;
    let occluding = boundary_conditions(mask, &Boundary::Occluding)?;
    Ok(limb_conditions(&occluding, image, reflectance, saturation)
        .test
        .not_limb)
}

/// The unit normal at `azimuth` in the image plane (radians from +x toward +y), raised by
/// `elevation` toward the viewer.
fn in_plane_normal(azimuth: f64, elevation: f64) -> Normal {
    Vector3::new(
        elevation.cos() * azimuth.cos(),
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
    )
}

/// The brightest a limb pixel whose contour's outward normal is at `azimuth` can be: the
/// largest R over the normals with 0 ≤ n_z ≤ [`LIMB_MAX_NZ`] whose in-plane direction is
/// within [`LIMB_DIRECTION_TOLERANCE_DEG`] of `azimuth` (sampled every 2° of elevation and
/// 2.5° of direction, ends included).
fn limb_brightness_bound(azimuth: f64, reflectance: &dyn ReflectanceMap) -> f64 {
    const ELEVATION_STEPS: usize = 15;
    const DIRECTION_STEPS: usize = 4;
    let top = LIMB_MAX_NZ.asin();
    let tolerance = LIMB_DIRECTION_TOLERANCE_DEG.to_radians();
    let mut bound = f64::NEG_INFINITY;
    for i in 0..=ELEVATION_STEPS {
        let elevation = top * i as f64 / ELEVATION_STEPS as f64;
        for j in 0..=DIRECTION_STEPS {
            let a = azimuth + tolerance * (2.0 * j as f64 / DIRECTION_STEPS as f64 - 1.0);
            bound = bound.max(reflectance.radiance(&in_plane_normal(a, elevation)));
        }
    }
    bound
}

/// The smallest elevation from asin([`LIMB_MAX_NZ`]) up to the viewer's at which the normal at
/// `azimuth` has R = `intensity` (found on a 1° grid, then by bisection), or, where R never
/// reaches it, the grid elevation at which R comes closest (the lowest of equals).
fn shading_elevation(azimuth: f64, intensity: f64, reflectance: &dyn ReflectanceMap) -> f64 {
    const GRID_STEPS: usize = 60;
    const BISECTIONS: usize = 40;
    let (low, high) = (LIMB_MAX_NZ.asin(), std::f64::consts::FRAC_PI_2);
    let at = |k: usize| low + (high - low) * k as f64 / GRID_STEPS as f64;
    let excess = |e: f64| reflectance.radiance(&in_plane_normal(azimuth, e)) - intensity;
    let mut closest = (f64::INFINITY, low);
    let mut previous = excess(low);
    if previous == 0.0 {
        return low;
    }
    for k in 1..=GRID_STEPS {
        let e = at(k);
        let d = excess(e);
        if d == 0.0 {
            return e;
        }
        if (d > 0.0) != (previous > 0.0) {
            let (mut a, mut b) = (at(k - 1), e);
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (a + b);
                if (excess(mid) > 0.0) == (previous > 0.0) {
                    a = mid;
                } else {
                    b = mid;
                }
            }
            return 0.5 * (a + b);
        }
        if previous.abs() < closest.0 {
            closest = (previous.abs(), at(k - 1));
        }
        previous = d;
    }
    if previous.abs() < closest.0 {
        closest = (previous.abs(), high);
    }
    closest.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::{sphere, vase, world_xy};

    /// A disc of radius `rad` centred at world (`cx`, `cy`).
    fn disc(w: usize, h: usize, cx: f64, cy: f64, rad: f64) -> Mask {
        Grid::from_fn(w, h, |c, r| {
            let (x, y) = world_xy(c, r, w, h);
            (x - cx).hypot(y - cy) < rad
        })
    }

    #[test]
    fn occluding_values_of_a_disc_are_radial_and_on_the_shrunk_circle() {
        let s = sphere(128, 128, 57.6).unwrap();
        let bc = boundary_conditions(&s.mask, &Boundary::Occluding).unwrap();
        let normals = occluding_normals(&s.mask);
        let (mut worst, mut sum, mut fixed): (f64, f64, usize) = (0.0, 0.0, 0);
        for row in 0..128 {
            for col in 0..128 {
                if bc.roles.get(col, row) != &Role::Fixed {
                    assert!(normals.get(col, row).is_none());
                    continue;
                }
                fixed += 1;
                let [f, g] = bc.fixed_value(col, row).unwrap();
                // The stated shrink: radius 2 × 0.9.
                assert!(
                    (f.hypot(g) - 1.8).abs() < 1e-12,
                    "|(f, g)| = {}",
                    f.hypot(g)
                );
                let n = normals.get(col, row).unwrap();
                assert!(n.z.abs() < 1e-12 && (n.norm() - 1.0).abs() < 1e-12);
                // The fixed value points along the limb normal.
                assert!((f / 1.8 - n.x).abs() < 1e-12 && (g / 1.8 - n.y).abs() < 1e-12);
                let (x, y) = world_xy(col, row, 128, 128);
                let radial = Vector3::new(x, y, 0.0).normalize();
                let err = crate::gradient_space::angle_deg(&n, &radial);
                worst = worst.max(err);
                sum += err;
            }
        }
        assert_eq!(OCCLUDING_SHRINK, 0.9);
        assert!(fixed > 300, "{fixed} fixed pixels");
        // A raw 8-neighbour step is off by up to 22.5°, a blurred-mask gradient by up to 9°.
        let mean = sum / fixed as f64;
        assert!(
            mean < 0.6 && worst < 2.0,
            "contour normal error mean {mean}°, worst {worst}°"
        );
        // The rim separates every unknown from the outside.
        for row in 0..128 {
            for col in 0..128 {
                if bc.roles.get(col, row) == &Role::Unknown {
                    assert!(!is_rim(&s.mask, col, row));
                }
            }
        }
    }

    #[test]
    fn small_and_thin_masks_get_finite_outward_normals() {
        // A disc of radius 6: the fit window covers most of it.
        let small = disc(24, 24, 0.0, 0.0, 6.0);
        let n = occluding_normals(&small);
        for row in 0..24 {
            for col in 0..24 {
                if let Some(n) = n.get(col, row) {
                    let (x, y) = world_xy(col, row, 24, 24);
                    let err = crate::gradient_space::angle_deg(n, &Vector3::new(x, y, 0.0));
                    assert!(err < 12.0, "({col},{row}) off by {err}°");
                }
            }
        }
        // A one-pixel line and a single pixel: no panic, unit in-plane normals.
        let line = Grid::from_fn(20, 9, |c, r| {
            r == 4 && (3..17).contains(&c) || (c, r) == (1, 1)
        });
        let n = occluding_normals(&line);
        let mut seen = 0;
        for v in n.data().iter().flatten() {
            seen += 1;
            assert!((v.norm() - 1.0).abs() < 1e-12 && v.z == 0.0, "{v}");
        }
        assert_eq!(seen, 15);
    }

    #[test]
    fn normal_is_tangent_cross_view_and_points_outward() {
        // A square: on its right edge the outward normal is +x, on its top edge +y (away from
        // the corners, where the direction is a blend over the fit window).
        let mask = Grid::from_fn(80, 80, |c, r| {
            (10..=70).contains(&c) && (10..=70).contains(&r)
        });
        let n = occluding_normals(&mask);
        for i in 30..=50 {
            let right = n.get(70, i).unwrap();
            assert!(
                (right - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-9,
                "{right}"
            );
            let top = n.get(i, 10).unwrap();
            assert!((top - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-9, "{top}");
            let left = n.get(10, i).unwrap();
            assert!(
                (left - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-9,
                "{left}"
            );
            let bottom = n.get(i, 70).unwrap();
            assert!(
                (bottom - Vector3::new(0.0, -1.0, 0.0)).norm() < 1e-9,
                "{bottom}"
            );
        }
        assert!(n.get(20, 20).is_none() && n.get(5, 5).is_none());
    }

    #[test]
    fn the_image_frame_is_a_free_boundary_never_occluding() {
        // A disc centred on the bottom edge: the frame cuts it along the bottom row.
        let (w, h) = (64, 48);
        let mask = disc(w, h, 0.0, -23.5, 20.0);
        let bc = boundary_conditions(&mask, &Boundary::Occluding).unwrap();
        let bottom = h - 1;
        let mut cut = 0;
        for col in 0..w {
            if !*mask.get(col, bottom) {
                continue;
            }
            let interior_of_cut = *mask.get(col.saturating_sub(1), bottom)
                && col + 1 < w
                && *mask.get(col + 1, bottom);
            if interior_of_cut {
                cut += 1;
                assert_eq!(bc.roles.get(col, bottom), &Role::Unknown, "col {col}");
            }
        }
        assert!(cut > 30);
        // Near the frame the contour is still a circle: the replicated mask keeps the normal
        // radial instead of bending it along the frame.
        let normals = occluding_normals(&mask);
        for row in h - 4..h {
            for col in 0..w {
                if let Some(n) = normals.get(col, row) {
                    let (x, y) = world_xy(col, row, w, h);
                    let radial = Vector3::new(x, y + 23.5, 0.0).normalize();
                    let err = crate::gradient_space::angle_deg(n, &radial);
                    assert!(err < 8.0, "({col},{row}) off by {err}°");
                }
            }
        }
        // The vase touches the top and bottom of the frame: those rows stay unknown.
        let v = vase(128, 128).unwrap();
        let bc = boundary_conditions(&v.mask, &Boundary::Occluding).unwrap();
        assert_eq!(bc.roles.get(64, 0), &Role::Unknown);
        assert_eq!(bc.roles.get(64, 127), &Role::Unknown);
    }

    #[test]
    fn flat_fixes_the_rim_and_the_image_border_to_the_view() {
        let mask = Grid::new(10, 8, true);
        let bc = boundary_conditions(&mask, &Boundary::Flat).unwrap();
        for row in 0..8 {
            for col in 0..10 {
                let border = col == 0 || row == 0 || col == 9 || row == 7;
                let want = if border { Role::Fixed } else { Role::Unknown };
                assert_eq!(bc.roles.get(col, row), &want);
                assert_eq!(bc.fixed_value(col, row).unwrap_or([0.0, 0.0]), [0.0, 0.0]);
            }
        }
        assert_eq!(bc.fixed_count(), 2 * 10 + 2 * 6);
        let free = boundary_conditions(&mask, &Boundary::Free).unwrap();
        assert_eq!(free.fixed_count(), 0);
        assert_eq!(free.unknown_count(), 80);
    }

    #[test]
    fn given_normals_are_used_on_the_rim_and_checked() {
        let mask = disc(20, 20, 0.0, 0.0, 6.0);
        let n = Vector3::new(0.3, -0.2, 0.9).normalize();
        let bc = boundary_conditions(&mask, &Boundary::Given(Grid::new(20, 20, n * 3.0))).unwrap();
        let (fv, gv) = fg_from_normal(&n);
        assert!(bc.fixed_count() > 10);
        for row in 0..20 {
            for col in 0..20 {
                if bc.roles.get(col, row) == &Role::Fixed {
                    assert!(is_rim(&mask, col, row));
                    let [f, g] = bc.fixed_value(col, row).unwrap();
                    assert!((f - fv).abs() < 1e-12);
                    assert!((g - gv).abs() < 1e-12);
                }
            }
        }
        let wrong = Boundary::Given(Grid::new(19, 20, n));
        assert!(boundary_conditions(&mask, &wrong).is_err());
        let nan = Boundary::Given(Grid::new(20, 20, Vector3::new(f64::NAN, 0.0, 1.0)));
        assert!(boundary_conditions(&mask, &nan).is_err());
        // Facing away from the viewer: refused, naming the pixel; in the image plane: the rim.
        let away = Boundary::Given(Grid::new(20, 20, Vector3::new(0.2, 0.1, -0.5)));
        let e = boundary_conditions(&mask, &away).unwrap_err().to_string();
        assert!(
            e.contains("faces away from the viewer") && e.contains("column"),
            "{e}"
        );
        let rim = Boundary::Given(Grid::new(20, 20, Vector3::new(0.6, -0.8, 0.0)));
        let bc = boundary_conditions(&mask, &rim).unwrap();
        let [f, g] = bc.fixed_values()[0].1;
        assert!((f.hypot(g) - FG_RADIUS).abs() < 1e-12);
        let empty = Grid::new(20, 20, false);
        let e = boundary_conditions(&empty, &Boundary::Flat).unwrap_err();
        assert!(e.to_string().contains("empty"));
        assert!(Boundary::named("wobbly").is_err());
        assert_eq!(Boundary::named("flat").unwrap(), Boundary::Flat);
    }
}
