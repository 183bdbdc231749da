//! Rendering a surface: image = R(n) inside the mask, a background level outside, optional cast
//! shadows, with the ground-truth layers (depth, normals, mask, shading) alongside.

use crate::grid::{Grid, Image, Mask};
use crate::reflectance::ReflectanceMap;
use crate::surface::Surface;

/// How to render.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Luminance outside the mask.
    pub background: f64,
    /// Whether the surface casts shadows on itself (ray-marched over the heightfield).
    pub cast_shadows: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            background: 0.0,
            cast_shadows: false,
        }
    }
}

/// A rendered image with its ground truth.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendering {
    /// The luminance image.
    pub image: Image,
    /// R(n) without cast shadows, inside the mask (0 outside).
    pub shading: Image,
    /// Pixels in cast shadow.
    pub cast_shadow: Mask,
}

/// Renders `surface` under `reflectance`.
pub fn render(
    surface: &Surface,
    reflectance: &dyn ReflectanceMap,
    options: &RenderOptions,
) -> Rendering {
    let (w, h) = (surface.width(), surface.height());
    let shading = Grid::from_fn(w, h, |c, r| {
        if *surface.mask.get(c, r) {
            reflectance.radiance(surface.normals.get(c, r))
        } else {
            0.0
        }
    });
    let cast_shadow = if options.cast_shadows {
        cast_shadows(surface, reflectance.light().direction())
    } else {
        Grid::new(w, h, false)
    };
    let ambient = reflectance.ambient();
    let image = Grid::from_fn(w, h, |c, r| {
        if !*surface.mask.get(c, r) {
            options.background
        } else if *cast_shadow.get(c, r) {
            ambient
        } else {
            *shading.get(c, r)
        }
    });
    Rendering {
        image,
        shading,
        cast_shadow,
    }
}

/// Marks the masked pixels from which a ray toward the light `s` passes below the heightfield.
///
/// The ray leaves each pixel centre in half-pixel steps; the heightfield between pixel centres
/// is bilinear over masked pixels. A bias of half a pixel keeps a smooth surface from shadowing
/// itself through discretisation.
pub fn cast_shadows(surface: &Surface, s: nalgebra::Vector3<f64>) -> Mask {
    let (w, h) = (surface.width(), surface.height());
    let horizontal = s.x.hypot(s.y);
    if horizontal < 1e-9 {
        return Grid::new(w, h, false);
    }
    // Per unit of image-plane distance: columns follow x, rows follow −y; z rises by s_z/|s_xy|.
    let (dc, dr, dz) = (s.x / horizontal, -s.y / horizontal, s.z / horizontal);
    let zmax = surface
        .depth
        .data()
        .iter()
        .zip(surface.mask.data())
        .filter(|(_, &m)| m)
        .map(|(z, _)| *z)
        .fold(f64::NEG_INFINITY, f64::max);
    let height_at = |x: f64, y: f64| -> Option<f64> {
        let (c0, r0) = (x.floor(), y.floor());
        let (fx, fy) = (x - c0, y - r0);
        let mut acc = 0.0;
        let mut wsum = 0.0;
        for (oc, or, wt) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (c, r) = ((c0 + oc) as isize, (r0 + or) as isize);
            if wt > 0.0 && *surface.mask.checked(c, r).unwrap_or(&false) {
                acc += wt * surface.depth.get(c as usize, r as usize);
                wsum += wt;
            }
        }
        (wsum > 0.5).then(|| acc / wsum)
    };
    Grid::from_fn(w, h, |col, row| {
        if !*surface.mask.get(col, row) {
            return false;
        }
        let z0 = *surface.depth.get(col, row) + 0.5;
        let mut t = 1.0;
        loop {
            let (x, y, z) = (col as f64 + dc * t, row as f64 + dr * t, z0 + dz * t);
            if x < 0.0 || y < 0.0 || x > (w - 1) as f64 || y > (h - 1) as f64 || z > zmax {
                return false;
            }
            if let Some(surface_z) = height_at(x, y) {
                if surface_z > z {
                    return true;
                }
            }
            t += 0.5;
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::Light;
    use crate::reflectance::Lambertian;
    use crate::surface::sphere;

    #[test]
    fn lambertian_render_is_clamped_cosine() {
        let s = sphere(64, 64, 28.0).unwrap();
        let light = Light::from_tilt_slant(30.0, 50.0).unwrap();
        let r = Lambertian {
            light,
            albedo: 1.0,
            ambient: 0.0,
        };
        let out = render(
            &s,
            &r,
            &RenderOptions {
                background: 0.25,
                cast_shadows: false,
            },
        );
        for row in 0..64 {
            for col in 0..64 {
                let v = *out.image.get(col, row);
                if *s.mask.get(col, row) {
                    let expect = s.normals.get(col, row).dot(&light.direction()).max(0.0);
                    assert!((v - expect).abs() < 1e-6);
                } else {
                    assert_eq!(v, 0.25);
                }
            }
        }
    }

    #[test]
    fn a_tall_bump_shadows_the_plane_behind_it() {
        // A plane with a tall column in the middle, lit at grazing slant from the left: the
        // shadow falls to the right of the column, not to its left.
        let (w, h) = (40, 9);
        let depth = Grid::from_fn(w, h, |c, _| if (18..22).contains(&c) { 10.0 } else { 0.0 });
        let s = crate::surface::Surface::from_depth(depth, Grid::new(w, h, true)).unwrap();
        let light = Light::from_tilt_slant(90.0, 80.0).unwrap();
        let m = cast_shadows(&s, light.direction());
        assert!(*m.get(25, 4) && *m.get(30, 4));
        assert!(!*m.get(10, 4) && !*m.get(19, 4));
    }
}
