//! Integration of gradient fields into depth maps.
//!
//! Two integrators, both least squares:
//! - [`FrankotChellappa`] projects the gradient field onto the integrable (periodic) surfaces in
//!   the Fourier domain. Fast (two real 2-D FFTs), but it assumes the field wraps around the
//!   image borders, and it knows nothing of a mask.
//! - [`integrate_gradients`] and [`integrate_differences`] solve the masked Poisson equation by
//!   conjugate gradients: only differences between neighbouring pixels that are both inside the
//!   mask count, so the silhouette and the image border are free (natural) boundaries. This is
//!   the one to use on an object with a silhouette, and it takes any difference field (log
//!   luminance for a lightness model, for instance), not only surface slopes.
//!
//! Gradients are in world axes: ∂z/∂x along the image's columns (x right) and ∂z/∂y upward
//! (y up, so ∂z/∂y = −∂z/∂row), in depth units per pixel. A unit normal gives ∂z/∂x = −n_x/n_z
//! and ∂z/∂y = −n_y/n_z ([`gradients_from_normals`]). [`mesh_obj`] writes a depth map as a
//! triangle mesh.

mod fourier;
mod mesh;
mod poisson;

pub use fourier::FrankotChellappa;
pub use mesh::{mesh_obj, write_mesh_obj};
pub(crate) use poisson::PreparedMask;
pub use poisson::{
    integrate_differences, integrate_gradients, integrate_gradients_from,
    integrate_owned_gradients, Integration, PoissonOptions,
};

use crate::error::{Error, Result};
use crate::gradient_space::{normal_from_fg, Normal};
use crate::grid::{Grid, Image, Mask};

/// The smallest n_z used when turning normals into slopes: at the occluding limb n_z → 0 and
/// the slope is infinite, so slopes are capped at 1/0.05 = 20.
pub const DEFAULT_MIN_NZ: f64 = 0.05;

/// The surface slopes (∂z/∂x, ∂z/∂y) of unit normals inside `mask`, with n_z clamped to at least
/// `min_nz` (0 outside the mask).
pub fn gradients_from_normals(
    normals: &Grid<Normal>,
    mask: &Mask,
    min_nz: f64,
) -> Result<(Image, Image)> {
    normals.check_same_size("normals are", mask, "the mask is")?;
    check_min_nz(min_nz)?;
    let slope = |pick: fn((f64, f64)) -> f64| {
        Grid::from_fn(normals.width(), normals.height(), |c, r| {
            if *mask.get(c, r) {
                pick(slopes_of(normals.get(c, r), min_nz))
            } else {
                0.0
            }
        })
    };
    Ok((slope(|s| s.0), slope(|s| s.1)))
}

/// (∂z/∂x, ∂z/∂y) of the unit normal `n`, with n_z clamped to at least `min_nz`.
fn slopes_of(n: &Normal, min_nz: f64) -> (f64, f64) {
    let nz = n.z.max(min_nz);
    (-n.x / nz, -n.y / nz)
}

/// Puts the lowest point of `depth` inside `mask` at 0 and sets 0 outside it (depth from slopes
/// has no offset of its own); returns the height of the highest point inside.
pub fn rest_on_zero(depth: &mut Image, mask: &Mask) -> Result<f64> {
    depth.check_same_size("depth is", mask, "the mask is")?;
    // An empty mask has no lowest point: everything is outside, and becomes 0.
    let lowest = Some(masked_fold(depth, mask, f64::INFINITY, f64::min))
        .filter(|z| z.is_finite())
        .unwrap_or(0.0);
    for (z, &m) in depth.data_mut().iter_mut().zip(mask.data()) {
        *z = if m { *z - lowest } else { 0.0 };
    }
    Ok(masked_fold(depth, mask, 0.0, f64::max))
}

/// The smallest and largest of `values` inside `mask`, or `None` for an empty mask.
///
/// ```
/// use shadelab::Grid;
/// use shadelab_engine::integrate::masked_range;
/// let z = Grid::from_vec(3, 1, vec![5.0, -1.0, 9.0])?;
/// let m = Grid::from_vec(3, 1, vec![true, true, false])?;
/// assert_eq!(masked_range(&z, &m), Some((-1.0, 5.0)));
/// assert_eq!(masked_range(&z, &Grid::new(3, 1, false)), None);
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn masked_range(values: &Image, mask: &Mask) -> Option<(f64, f64)> {
    let lo = masked_fold(values, mask, f64::INFINITY, f64::min);
    let hi = masked_fold(values, mask, f64::NEG_INFINITY, f64::max);
    (lo <= hi).then_some((lo, hi))
}

/// `values` inside `mask` folded from `start` with `op`.
fn masked_fold(values: &Image, mask: &Mask, start: f64, op: fn(f64, f64) -> f64) -> f64 {
    values
        .data()
        .iter()
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .fold(start, |acc, (v, _)| op(acc, *v))
}

/// [`gradients_from_normals`] for normals given by their stereographic (f, g) (as the solver
/// returns them), turned into the slopes (∂z/∂x, ∂z/∂y) in place: the two images are reused,
/// so no normals grid (24 bytes per pixel) is ever made. Same values as
/// `gradients_from_normals` of the normals of (f, g).
pub fn gradients_from_fg(
    mut f: Image,
    mut g: Image,
    mask: &Mask,
    min_nz: f64,
) -> Result<(Image, Image)> {
    if !f.same_size(&g) || !f.same_size(mask) {
        return Err(Error::invalid(format!(
            "f is {}, g {} and the mask {}: they must have one size",
            crate::message::SizeText::Pixels(f.height(), f.width()),
            crate::message::SizeText::Pixels(g.height(), g.width()),
            crate::message::SizeText::Pixels(mask.height(), mask.width())
        )));
    }
    check_min_nz(min_nz)?;
    for ((f, g), &inside) in f
        .data_mut()
        .iter_mut()
        .zip(g.data_mut().iter_mut())
        .zip(mask.data())
    {
        (*f, *g) = if inside {
            slopes_of(&normal_from_fg(*f, *g), min_nz)
        } else {
            (0.0, 0.0)
        };
    }
    Ok((f, g))
}

fn check_min_nz(min_nz: f64) -> Result<()> {
    if !(min_nz.is_finite() && min_nz > 0.0) {
        return Err(Error::invalid(format!(
            "min_nz = {min_nz} must be a positive number"
        )));
    }
    Ok(())
}

/// A least-squares fit truth ≈ scale·estimate + offset over a mask, and its residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScaleOffsetFit {
    /// The fitted scale.
    pub scale: f64,
    /// The fitted offset.
    pub offset: f64,
    /// Root-mean-square residual of the fit.
    pub rmse: f64,
}

/// Fits `truth ≈ scale·estimate + offset` over `mask` by least squares: the depth error left
/// once the unknown scale and offset of a reconstruction are taken out.
pub fn fit_scale_offset(estimate: &Image, truth: &Image, mask: &Mask) -> Result<ScaleOffsetFit> {
    if !estimate.same_size(truth) || !estimate.same_size(mask) {
        return Err(Error::invalid(
            "estimate, truth and mask must have the same size",
        ));
    }
    let pairs: Vec<(f64, f64)> = estimate
        .data()
        .iter()
        .zip(truth.data())
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|((&e, &t), _)| (e, t))
        .collect();
    if pairs.is_empty() {
        return Err(Error::invalid("the mask is empty: nothing to fit"));
    }
    let n = pairs.len() as f64;
    let (me, mt) = pairs
        .iter()
        .fold((0.0, 0.0), |(a, b), (e, t)| (a + e / n, b + t / n));
    let (mut see, mut set) = (0.0, 0.0);
    for (e, t) in &pairs {
        see += (e - me) * (e - me);
        set += (e - me) * (t - mt);
    }
    let scale = if see > 0.0 { set / see } else { 0.0 };
    let offset = mt - scale * me;
    let sse: f64 = pairs
        .iter()
        .map(|(e, t)| {
            let r = scale * e + offset - t;
            r * r
        })
        .sum();
    Ok(ScaleOffsetFit {
        scale,
        offset,
        rmse: (sse / n).sqrt(),
    })
}

/// Checks that two gradient grids match each other (and `width` × `height` when given) and
/// hold only finite numbers.
fn check_gradients(dz_dx: &Image, dz_dy: &Image) -> Result<()> {
    if !dz_dx.same_size(dz_dy) {
        return Err(Error::invalid(format!(
            "gradient fields differ in size: {} and {}",
            crate::message::SizeText::Pixels(dz_dx.height(), dz_dx.width()),
            crate::message::SizeText::Pixels(dz_dy.height(), dz_dy.width())
        )));
    }
    for (name, grid) in [("x", dz_dx), ("y", dz_dy)] {
        if let Some(i) = grid.data().iter().position(|v| !v.is_finite()) {
            return Err(Error::invalid(format!(
                "gradient along {name} at column {}, row {} is not a finite number",
                i % grid.width(),
                i / grid.width()
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
