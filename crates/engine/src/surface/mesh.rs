//! Triangle meshes: loaders for PLY (ASCII and binary in either byte order) and Wavefront OBJ,
//! and orthographic rasterisation to a [`Surface`] under a chosen view rotation.
//!
//! # Conventions
//! World axes are x right, y up, z toward the viewer. A mesh is read in its own axes with the
//! same meaning (the Stanford bunny's scanner frame is y up, z toward the viewer in its default
//! view), so the identity view shows the mesh as stored. A view rotation turns the mesh before
//! it is projected along −z; [`view_rotation`] builds one from yaw, pitch and roll in degrees.
//!
//! # What the loaders accept and reject
//! - Polygons with more than three corners are fan-triangulated: (v0, vi, vi+1).
//! - A triangle that repeats a vertex index covers nothing and is dropped silently; a triangle
//!   with distinct but collinear corners is kept (it covers no pixel and adds nothing to the
//!   vertex normals).
//! - Everything else that is wrong is an error naming the file and the problem: a bad or
//!   truncated header, data shorter than the header declares, a value that does not parse, a
//!   face with fewer than three corners, an index out of range, a NaN or infinite coordinate, no
//!   vertices, no faces left.
//! - Header counts are checked against the bytes that follow before anything is reserved, so a
//!   lying header cannot make the loader allocate more than the file's size warrants.

mod obj;
mod ply;
mod raster;

pub use raster::{view_rotation, MeshShading, Projection, MAX_FILL};

use super::Surface;
use crate::error::{Error, Result};
use nalgebra::{Rotation3, Vector3};
use std::path::Path;

/// The largest mesh file read, in bytes (1 GiB: a scan of some 20 million faces in binary PLY,
/// more than a rasterised stimulus can show; a bigger file, or a device, is refused before it
/// is read whole).
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// A triangle mesh: vertex positions and triangles indexing them.
///
/// The mask and depth do not depend on the winding; smooth normals need it consistent across
/// neighbouring triangles (either way round: normals are turned toward the viewer).
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// Vertex positions in the mesh's own units (x right, y up, z toward the viewer).
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// A mesh from vertices and triangles, checked: finite coordinates, indices in range, at
    /// least one triangle.
    pub fn new(vertices: Vec<Vector3<f64>>, triangles: Vec<[u32; 3]>) -> Result<Mesh> {
        let mesh = Mesh {
            vertices,
            triangles,
        };
        mesh.check().map_err(Error::invalid)?;
        Ok(mesh)
    }

    fn check(&self) -> std::result::Result<(), String> {
        if let Some((i, v)) = self
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !v.iter().all(|c| c.is_finite()))
        {
            return Err(format!(
                "mesh vertex {i} has a NaN or infinite coordinate ({}, {}, {})",
                v.x, v.y, v.z
            ));
        }
        if self.triangles.is_empty() {
            return Err("the mesh has no triangles".into());
        }
        let n = self.vertices.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(format!(
                    "mesh triangle {t} refers to vertex {i} but the mesh has {n} vertices"
                ));
            }
        }
        Ok(())
    }

    /// Reads a `.ply` or `.obj` file (chosen by extension, case-insensitive).
    pub fn load(path: impl AsRef<Path>) -> Result<Mesh> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        let parse = match ext.as_deref() {
            Some("ply") => Mesh::from_ply,
            Some("obj") => Mesh::from_obj,
            _ => {
                return Err(Error::format(
                    path,
                    "unknown mesh format (the file name must end in .ply or .obj)",
                ))
            }
        };
        let bytes = crate::io::read_capped(path, MAX_MESH_BYTES)?;
        parse(&bytes, path)
    }

    /// Parses PLY bytes (ASCII, binary little endian or binary big endian). `source` names the
    /// file in error messages.
    ///
    /// The `vertex` element needs scalar `x`, `y`, `z` properties of any numeric type; other
    /// vertex properties (confidence, intensity, colour, lists) are skipped. The `face` element
    /// needs an integer list `vertex_indices` (or `vertex_index`); other elements are skipped.
    pub fn from_ply(bytes: &[u8], source: &Path) -> Result<Mesh> {
        ply::parse(bytes, source)
    }

    /// Parses Wavefront OBJ bytes: `v x y z` and `f` lines (indices from 1, negative indices
    /// counting back from the latest vertex, corners written `i`, `i/t`, `i//n` or `i/t/n`);
    /// every other statement is ignored. `source` names the file in error messages.
    pub fn from_obj(bytes: &[u8], source: &Path) -> Result<Mesh> {
        obj::parse(bytes, source)
    }

    /// Rasterises the mesh orthographically into a `width` × `height` [`Surface`] with smooth
    /// normals; see [`Mesh::rasterize_with`].
    pub fn rasterize(
        &self,
        width: usize,
        height: usize,
        view: &Rotation3<f64>,
        fill: f64,
    ) -> Result<Surface> {
        self.rasterize_with(width, height, view, fill, MeshShading::Smooth)
    }
}

/// Appends the fan (c0, ci, ci+1) of a polygon, dropping triangles that repeat an index.
fn fan_triangulate(corners: &[u32], triangles: &mut Vec<[u32; 3]>) {
    let rest = corners.get(1..).unwrap_or(&[]);
    for pair in rest.windows(2) {
        let tri = [corners[0], pair[0], pair[1]];
        if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
            triangles.push(tri);
        }
    }
}

fn finish(vertices: Vec<Vector3<f64>>, triangles: Vec<[u32; 3]>, source: &Path) -> Result<Mesh> {
    if vertices.is_empty() {
        return Err(Error::format(source, "the mesh has no vertices"));
    }
    if triangles.is_empty() {
        return Err(Error::format(
            source,
            "the mesh has no faces (or only degenerate ones that repeat a vertex)",
        ));
    }
    let mesh = Mesh {
        vertices,
        triangles,
    };
    mesh.check().map_err(|m| Error::format(source, m))?;
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn load_picks_the_parser_by_extension_and_names_the_file() {
        let e = Mesh::load("model.stl").unwrap_err().to_string();
        assert!(e.contains("model.stl") && e.contains(".ply or .obj"), "{e}");
        let e = Mesh::load("/nonexistent/bunny.PLY")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("/nonexistent/bunny.PLY: "), "{e}");
    }

    #[test]
    fn constructed_meshes_are_checked() {
        let v = vec![Vector3::zeros(), Vector3::x(), Vector3::y()];
        assert!(Mesh::new(v.clone(), vec![[0, 1, 2]]).is_ok());
        assert!(Mesh::new(v.clone(), vec![[0, 1, 3]]).is_err());
        assert!(Mesh::new(v.clone(), vec![]).is_err());
        let mut bad = v;
        bad[1].x = f64::NAN;
        assert!(Mesh::new(bad, vec![[0, 1, 2]]).is_err());
        // Public fields can bypass `new`; rasterising must still not panic.
        let m = Mesh {
            vertices: vec![Vector3::zeros()],
            triangles: vec![[0, 5, 9]],
        };
        assert!(m.rasterize(8, 8, &Rotation3::identity(), 0.8).is_err());
    }
}
