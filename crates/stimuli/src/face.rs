//! The built-in face: MediaPipe's canonical face model (© Google LLC, Apache License 2.0;
//! `assets/face/`), embedded in the binary, turned to face the viewer and rasterised by the
//! mesh rasteriser ([`Mesh::rasterize`]) with smooth vertex normals.
//!
//! The mesh as stored is turned about 11.6° about its vertical axis; [`face_view`] turns its
//! mirror plane (measured: every vertex's mirror image lies within 2·10⁻⁵ cm of another
//! vertex) edge on to the viewer, so the face looks straight out of the picture with its
//! nose on the vertical midline.

use crate::error::{Error, Result};
use crate::surface::{Mesh, Projection, Surface};
use nalgebra::{Rotation3, Vector3};

/// The canonical face mesh (Wavefront OBJ, centimetres, y up, z toward the viewer).
pub const FACE_OBJ: &str = include_str!("../assets/face/canonical_face_model.obj");

/// The unit normal of the stored mesh's mirror plane (which passes through the origin).
pub const FACE_MIRROR_NORMAL: [f64; 3] = [0.979_403_08, 0.011_966_23, 0.201_559_96];

/// The canonical face mesh, parsed.
pub fn face_mesh() -> Result<Mesh> {
    Mesh::from_obj(
        FACE_OBJ.as_bytes(),
        std::path::Path::new("canonical_face_model.obj"),
    )
}

/// The rotation that turns the stored face to look at the viewer: the least rotation taking
/// its mirror plane's normal to the image's x axis.
pub fn face_view() -> Rotation3<f64> {
    let n = Vector3::from(FACE_MIRROR_NORMAL).normalize();
    Rotation3::rotation_between(&n, &Vector3::x()).unwrap_or_else(Rotation3::identity)
}

/// A face rasterised into a `width` × `height` frame, and where the mesh landed.
#[derive(Debug, Clone)]
pub struct FaceRelief {
    /// The convex face: depth in pixels above its farthest point, smooth normals, its mask.
    pub surface: Surface,
    /// How mesh points map to pixels.
    pub projection: Projection,
    /// (column, row) of the nose tip, the mesh's vertex nearest the viewer.
    pub nose_tip: (f64, f64),
}

/// Rasterises the face, centred, `face_width` pixels wide (the turned mesh's width), with its
/// depth multiplied by `relief`.
///
/// ```
/// use shadelab_stimuli::face::face_relief;
/// let face = face_relief(60, 80, 50.0, 1.0).unwrap();
/// let (col, row) = face.nose_tip;
/// // The nose tip sits on the vertical midline, just below the frame's centre.
/// assert!((col - 29.5).abs() < 0.5 && row > 40.0);
/// assert!(face.surface.mask.count() > 2000);
/// ```
pub fn face_relief(
    width: usize,
    height: usize,
    face_width: f64,
    relief: f64,
) -> Result<FaceRelief> {
    if !(face_width.is_finite() && face_width > 0.0 && relief.is_finite() && relief > 0.0) {
        return Err(Error::invalid(format!(
            "face width {face_width} px and relief {relief} must be positive"
        )));
    }
    let mesh = face_mesh()?;
    let view = face_view();
    let (lo, hi) = mesh
        .vertices
        .iter()
        .map(|v| (view * v).x)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
            (lo.min(x), hi.max(x))
        });
    // `fill` is relative to the tighter axis of the frame: scale it to the width asked for.
    let full = Projection::fit(&mesh, width, height, &view, 1.0)?;
    let fill = face_width / (hi - lo) / full.scale();
    let projection = Projection::fit(&mesh, width, height, &view, fill)?;
    let mut surface = mesh.rasterize(width, height, &view, fill)?;
    if relief != 1.0 {
        surface.depth = surface.depth.map(|z| z * relief);
        surface.normals = surface
            .normals
            .map(|n| Vector3::new(n.x * relief, n.y * relief, n.z).normalize());
    }
    let tip = mesh.vertices.iter().map(|v| projection.to_pixel(v)).fold(
        Vector3::new(0.0, 0.0, f64::NEG_INFINITY),
        |best, p| {
            if p.z > best.z {
                p
            } else {
                best
            }
        },
    );
    Ok(FaceRelief {
        surface,
        projection,
        nose_tip: (tip.x, tip.y),
    })
}
