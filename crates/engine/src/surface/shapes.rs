//! Analytic benchmark shapes with exact normals.

use super::Surface;
use crate::error::{Error, Result};
use crate::gradient_space::normal_from_pq;
use nalgebra::Vector3;

/// A hemisphere of `radius` pixels centred in the grid.
pub fn sphere(width: usize, height: usize, radius: f64) -> Result<Surface> {
    ellipsoid(width, height, radius, radius, radius)
}

/// The front half of an ellipsoid with semi-axes `a` (x), `b` (y), `c` (z) in pixels, centred.
pub fn ellipsoid(width: usize, height: usize, a: f64, b: f64, c: f64) -> Result<Surface> {
    for (name, v) in [("a", a), ("b", b), ("c", c)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(format!(
                "ellipsoid semi-axis {name} = {v} must be positive"
            )));
        }
    }
    Ok(Surface::from_fn(width, height, |x, y| {
        let (u, v) = (x / a, y / b);
        let r2 = u * u + v * v;
        (r2 < 1.0).then(|| {
            let w = (1.0 - r2).sqrt();
            // Gradient of the implicit function (x/a)²+(y/b)²+(z/c)² = 1.
            let n = Vector3::new(x / (a * a), y / (b * b), c * w / (c * c)).normalize();
            (c * w, n)
        })
    }))
}

/// A Gaussian bump (amplitude > 0) or dimple (amplitude < 0) on a plane: z = A·exp(−r²/2σ²)
/// centred at world (`cx`, `cy`), covering the whole grid.
pub fn gaussian(
    width: usize,
    height: usize,
    amplitude: f64,
    sigma: f64,
    cx: f64,
    cy: f64,
) -> Result<Surface> {
    if !(sigma.is_finite() && sigma > 0.0 && amplitude.is_finite()) {
        return Err(Error::invalid(format!(
            "gaussian: sigma {sigma} must be positive and amplitude {amplitude} finite"
        )));
    }
    Ok(Surface::from_fn(width, height, |x, y| {
        let (dx, dy) = (x - cx, y - cy);
        let z = amplitude * (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp();
        let (dz_dx, dz_dy) = (-dx / (sigma * sigma) * z, -dy / (sigma * sigma) * z);
        Some((z, normal_from_pq(-dz_dx, -dz_dy)))
    }))
}

/// The vase profile of Zhang, Tsai, Cryer & Shah (1999):
/// F(y) = 0.15 − 0.1·y·(6y+1)²·(y−1)²·(3y−2) for 0 ≤ y ≤ 1, and F′(y).
pub fn vase_profile(y: f64) -> (f64, f64) {
    let a = 6.0 * y + 1.0;
    let b = y - 1.0;
    let c = 3.0 * y - 2.0;
    let prod = y * a * a * b * b * c;
    let dprod = a * a * b * b * c
        + y * 12.0 * a * b * b * c
        + y * a * a * 2.0 * b * c
        + y * a * a * b * b * 3.0;
    (0.15 - 0.1 * prod, -0.1 * dprod)
}

/// The vase of Zhang et al. (1999): z = √(F(y)² − x²) on −0.5 ≤ x ≤ 0.5, 0 ≤ y ≤ 1, with the
/// unit square scaled to the grid's shorter side and centred.
pub fn vase(width: usize, height: usize) -> Result<Surface> {
    let scale = width.min(height) as f64;
    if scale < 1.0 {
        return Err(Error::invalid("vase: the grid is empty"));
    }
    Ok(Surface::from_fn(width, height, |x, y| {
        let (u, v) = (x / scale, y / scale + 0.5);
        if !(0.0..=1.0).contains(&v) {
            return None;
        }
        let (f, df) = vase_profile(v);
        let z2 = f * f - u * u;
        (z2 > 0.0).then(|| {
            let z = z2.sqrt();
            // ∇(z² − F² + x²) gives the normal direction (x, −F·F′, z) in unit-square units.
            (z * scale, Vector3::new(u, -f * df, z).normalize())
        })
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_space::angle_deg;
    use crate::surface::world_xy;

    #[test]
    fn vase_matches_its_formula() {
        let (w, h) = (128, 128);
        let s = vase(w, h).unwrap();
        let mut inside = 0;
        for row in 0..h {
            for col in 0..w {
                let (x, y) = world_xy(col, row, w, h);
                let (u, v) = (x / 128.0, y / 128.0 + 0.5);
                let f =
                    0.15 - 0.1 * v * (6.0 * v + 1.0).powi(2) * (v - 1.0).powi(2) * (3.0 * v - 2.0);
                let z2 = f * f - u * u;
                let in_formula = (0.0..=1.0).contains(&v) && z2 > 0.0;
                assert_eq!(*s.mask.get(col, row), in_formula, "({col},{row})");
                if in_formula {
                    inside += 1;
                    assert!((s.depth.get(col, row) - z2.sqrt() * 128.0).abs() < 1e-9);
                }
            }
        }
        assert!(inside > 2000);
    }

    #[test]
    fn analytic_normals_agree_with_finite_differences() {
        for s in [
            sphere(64, 64, 25.0).unwrap(),
            vase(96, 96).unwrap(),
            gaussian(64, 64, 8.0, 7.0, 0.0, 0.0).unwrap(),
        ] {
            let fd = Surface::from_depth(s.depth.clone(), s.mask.clone()).unwrap();
            // Compare away from the rim, where finite differences are one-sided.
            let eroded = |c: usize, r: usize| {
                (-2isize..=2).all(|dr| {
                    (-2isize..=2).all(|dc| {
                        *s.mask
                            .checked(c as isize + dc, r as isize + dr)
                            .unwrap_or(&false)
                    })
                })
            };
            let mut worst: f64 = 0.0;
            for r in 0..s.height() {
                for c in 0..s.width() {
                    if eroded(c, r) && s.normals.get(c, r).z > 0.5 {
                        worst = worst.max(angle_deg(s.normals.get(c, r), fd.normals.get(c, r)));
                    }
                }
            }
            assert!(worst < 2.0, "worst {worst}°");
        }
    }

    #[test]
    fn vase_profile_derivative() {
        for i in 1..20 {
            let y = i as f64 / 20.0;
            let h = 1e-6;
            let fd = (vase_profile(y + h).0 - vase_profile(y - h).0) / (2.0 * h);
            assert!((vase_profile(y).1 - fd).abs() < 1e-6);
        }
    }
}
