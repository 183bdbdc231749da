//! Orthographic rasterisation of a mesh: fitting the view, a fixed-point z-buffer with an exact
//! tie rule, and normals facing the viewer.

use super::Mesh;
use crate::error::{Error, Result};
use crate::gradient_space::Normal;
use crate::grid::{check_size, Grid, DEFAULT_MAX_PIXELS};
use crate::surface::Surface;
use nalgebra::{Rotation3, Vector3};

/// How the normal varies across a rasterised triangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MeshShading {
    /// Barycentric interpolation of area-weighted vertex normals (smooth curved surfaces).
    #[default]
    Smooth,
    /// One normal per triangle (polyhedra such as a cube).
    Flat,
}

/// The largest `fill` accepted: beyond this the frame shows a tiny part of the mesh.
pub const MAX_FILL: f64 = 16.0;

/// Fixed-point subpixel resolution of the rasteriser: corners snap to 1/256 pixel, so edge
/// functions are exact integers and shared edges never crack or double-cover.
const SUBPIXEL: i64 = 256;

impl Mesh {
    /// Rasterises the mesh orthographically into a `width` × `height` [`Surface`].
    ///
    /// The mesh is turned by `view`, then scaled and centred so that its projected bounding box
    /// fills the fraction `fill` of the frame along its tighter axis (see [`Projection::fit`]).
    /// Each pixel centre takes the nearest (largest z) triangle covering it; depth is in pixel
    /// units above the mesh's farthest point. Normals face the viewer (n_z ≥ 0): a triangle
    /// seen from behind (an open mesh seen through a hole) has its normal flipped, and a smooth
    /// normal that would tilt away from the viewer near a silhouette is laid flat in the image
    /// plane. A pixel centre on an edge shared by two triangles belongs to exactly one of them.
    ///
    /// A triangle on the same three vertices as an earlier one in the same winding is the same
    /// surface again and is skipped; triangles on three vertices that also occur in the
    /// opposite winding form a zero-thickness fin and are all skipped. Decimated scans such as
    /// the Stanford bunny hold such fins (73 in the built-in bunny), whose opposite normals
    /// cancel at their vertices and showed as dark slivers. A smooth normal is used only where all three corners' vertex normals lie on the
    /// triangle's side; elsewhere (a fin, a crease sharper than 90°, inconsistent winding) the
    /// triangle is shaded flat rather than with a normal turned away from it.
    pub fn rasterize_with(
        &self,
        width: usize,
        height: usize,
        view: &Rotation3<f64>,
        fill: f64,
        shading: MeshShading,
    ) -> Result<Surface> {
        let projection = Projection::fit(self, width, height, view, fill)?;
        let pixel: Vec<Vector3<f64>> = self
            .vertices
            .iter()
            .map(|v| projection.to_pixel(v))
            .collect();
        let snap = |v: f64| (v * SUBPIXEL as f64).round() as i64;
        let fixed: Vec<[i64; 2]> = pixel.iter().map(|p| [snap(p.x), snap(p.y)]).collect();

        const NONE: u32 = u32::MAX;
        let n = width * height;
        let mut nearest = vec![f64::NEG_INFINITY; n];
        let mut owner = vec![NONE; n];
        let distinct = distinct_triangles(&self.triangles);
        for (t, tri) in self.triangles.iter().enumerate() {
            if !distinct[t] {
                continue;
            }
            let [a, b, c] = tri.map(|i| i as usize);
            let corners = [fixed[a], fixed[b], fixed[c]];
            let Some(plane) = DepthPlane::new(corners, [pixel[a].z, pixel[b].z, pixel[c].z]) else {
                continue;
            };
            cover(corners, width, height, |col, row| {
                let depth = plane.at(col, row);
                let k = row * width + col;
                if depth > nearest[k] {
                    nearest[k] = depth;
                    owner[k] = t as u32;
                }
            });
        }
        if owner.iter().all(|&t| t == NONE) {
            return Err(Error::Compute(format!(
                "the mesh covers no pixel centre of the frame {} at fill {fill}",
                crate::message::SizeText::Pixels(height, width)
            )));
        }

        // Normals in the turned mesh frame (right-handed like the world frame; the uniform
        // scale does not change directions).
        let turned: Vec<Vector3<f64>> = self.vertices.iter().map(|v| view * v).collect();
        let face_normals: Vec<Vector3<f64>> = self
            .triangles
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (turned[a as usize], turned[b as usize], turned[c as usize]);
                (b - a).cross(&(c - a))
            })
            .collect();
        let vertex_normals = match shading {
            MeshShading::Smooth => {
                area_weighted_vertex_normals(&self.triangles, &face_normals, &distinct)
            }
            MeshShading::Flat => Vec::new(),
        };
        let normal_at = |k: usize| -> Normal {
            let t = owner[k] as usize;
            let face = face_normals[t];
            let length = face.norm();
            if length == 0.0 {
                return Vector3::z();
            }
            // Seen from behind: flip so the visible side faces the viewer.
            let side = if face.z >= 0.0 { 1.0 } else { -1.0 };
            let flat = face * (side / length);
            if shading == MeshShading::Flat {
                return flat;
            }
            let [a, b, c] = self.triangles[t].map(|i| vertex_normals[i as usize]);
            // A corner normal with no direction or turned against the face: shade flat.
            if [a, b, c].iter().any(|v| v.dot(&face) <= 0.0) {
                return flat;
            }
            let corners = self.triangles[t].map(|i| fixed[i as usize]);
            let w = barycentric(corners, k % width, k / width);
            let smooth = (a * w[0] + b * w[1] + c * w[2]) * side;
            // Inconsistent winding or a sharp crease: the interpolated normal is meaningless.
            if smooth.dot(&flat) <= 0.0 || smooth.norm() < 1e-12 {
                return flat;
            }
            let mut normal = smooth.normalize();
            if normal.z < 0.0 {
                let planar = Vector3::new(normal.x, normal.y, 0.0);
                let length = planar.norm();
                normal = if length > 1e-12 {
                    planar / length
                } else {
                    flat
                };
            }
            normal
        };

        let mut depth = Grid::new(width, height, 0.0);
        let mut normals = Grid::new(width, height, Vector3::z());
        let mut mask = Grid::new(width, height, false);
        for k in 0..n {
            if owner[k] != NONE {
                depth.data_mut()[k] = nearest[k];
                normals.data_mut()[k] = normal_at(k);
                mask.data_mut()[k] = true;
            }
        }
        Ok(Surface {
            depth,
            normals,
            mask,
        })
    }
}

/// Which triangles are drawn: the first of those on the same three vertices in the same
/// winding (a repeat is the same surface again), and none of those on three vertices that
/// also appear in the opposite winding (a zero-thickness fin, which encloses nothing; the
/// rasteriser shows both sides of a single triangle anyway).
fn distinct_triangles(triangles: &[[u32; 3]]) -> Vec<bool> {
    use std::collections::hash_map::{Entry, HashMap};
    // Per vertex set: the first triangle, and which windings occur (bit 0 even, bit 1 odd).
    let mut sets: HashMap<[u32; 3], (usize, u8)> = HashMap::with_capacity(triangles.len());
    for (t, &[a, b, c]) in triangles.iter().enumerate() {
        let mut key = [a, b, c];
        key.sort_unstable();
        // (a, b, c) is an even permutation of its sorted order when its inversions are even.
        let inversions = u8::from(a > b) + u8::from(a > c) + u8::from(b > c);
        let winding = 1 << (inversions % 2);
        match sets.entry(key) {
            Entry::Vacant(e) => {
                e.insert((t, winding));
            }
            Entry::Occupied(mut e) => e.get_mut().1 |= winding,
        }
    }
    let mut drawn = vec![false; triangles.len()];
    for (first, windings) in sets.into_values() {
        drawn[first] = windings != 3;
    }
    drawn
}

/// Area-weighted vertex normals of the `used` triangles (the sum of the unnormalised face
/// normals around each vertex), normalised; zero where the faces cancel (the sum is under a
/// millionth of the summed face areas: rounding left over, not a direction).
fn area_weighted_vertex_normals(
    triangles: &[[u32; 3]],
    face_normals: &[Vector3<f64>],
    used: &[bool],
) -> Vec<Vector3<f64>> {
    let count = triangles
        .iter()
        .flatten()
        .map(|&i| i as usize + 1)
        .max()
        .unwrap_or(0);
    let mut sums = vec![Vector3::zeros(); count];
    let mut areas = vec![0.0; count];
    for ((tri, face), _) in triangles
        .iter()
        .zip(face_normals)
        .zip(used)
        .filter(|(_, &u)| u)
    {
        for &i in tri {
            sums[i as usize] += face;
            areas[i as usize] += face.norm();
        }
    }
    for (s, area) in sums.iter_mut().zip(areas) {
        let length = s.norm();
        *s = if length > 1e-6 * area {
            *s / length
        } else {
            Vector3::zeros()
        };
    }
    sums
}

/// The rotation for a view given in degrees, applied yaw first, then pitch, then roll:
/// - yaw turns about the vertical axis y; positive turns the mesh's front (+z) toward +x
///   (image right);
/// - pitch turns about x; positive tips the top (+y) toward the viewer, showing more of it;
/// - roll turns about the viewing axis z; positive is counter-clockwise in the image.
pub fn view_rotation(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> Result<Rotation3<f64>> {
    for (name, v) in [("yaw", yaw_deg), ("pitch", pitch_deg), ("roll", roll_deg)] {
        if !v.is_finite() {
            return Err(Error::invalid(format!(
                "view {name} = {v} must be a finite angle in degrees"
            )));
        }
    }
    let yaw = Rotation3::from_axis_angle(&Vector3::y_axis(), yaw_deg.to_radians());
    let pitch = Rotation3::from_axis_angle(&Vector3::x_axis(), pitch_deg.to_radians());
    let roll = Rotation3::from_axis_angle(&Vector3::z_axis(), roll_deg.to_radians());
    Ok(roll * pitch * yaw)
}

/// The orthographic projection that fits a turned mesh in a frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Projection {
    rotation: Rotation3<f64>,
    scale: f64,
    /// Turned-frame point that lands on the frame centre (x, y) at depth 0 (z).
    anchor: Vector3<f64>,
    width: usize,
    height: usize,
}

impl Projection {
    /// Fits `mesh` turned by `view` in a `width` × `height` frame: the bounding box of the
    /// triangles' vertices is centred, and scaled so that it spans `fill` × width or
    /// `fill` × height, whichever is reached first; its farthest point sits at depth 0.
    pub fn fit(
        mesh: &Mesh,
        width: usize,
        height: usize,
        view: &Rotation3<f64>,
        fill: f64,
    ) -> Result<Projection> {
        check_size(width, height, DEFAULT_MAX_PIXELS)?;
        if !(fill.is_finite() && fill > 0.0 && fill <= MAX_FILL) {
            return Err(Error::invalid(format!(
                "mesh fill = {fill} must be in (0, {MAX_FILL}] (the fraction of the frame the \
                 mesh's bounding box spans)"
            )));
        }
        mesh.check().map_err(Error::invalid)?;
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        let mut used = vec![false; mesh.vertices.len()];
        for &i in mesh.triangles.iter().flatten() {
            used[i as usize] = true;
        }
        for (v, _) in mesh.vertices.iter().zip(&used).filter(|(_, &u)| u) {
            let r = view * v;
            lo = lo.inf(&r);
            hi = hi.sup(&r);
        }
        let extent = hi - lo;
        let per_unit = |pixels: usize, e: f64| {
            if e > 0.0 {
                pixels as f64 / e
            } else {
                f64::INFINITY
            }
        };
        let scale = fill * per_unit(width, extent.x).min(per_unit(height, extent.y));
        if !scale.is_finite() {
            return Err(Error::invalid(
                "the mesh projects to a single point in this view (its triangles have no extent \
                 across the image)",
            ));
        }
        if !(scale * extent.z).is_finite() {
            return Err(Error::invalid(
                "the mesh is too deep for its projected size (depth would overflow)",
            ));
        }
        Ok(Projection {
            rotation: *view,
            scale,
            anchor: Vector3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z),
            width,
            height,
        })
    }

    /// Pixels per mesh unit.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// World position in pixel units of a mesh point: x right and y up from the frame centre
    /// (as [`crate::surface::world_xy`]), z = depth above the mesh's farthest point.
    pub fn to_world(&self, v: &Vector3<f64>) -> Vector3<f64> {
        (self.rotation * v - self.anchor) * self.scale
    }

    /// Pixel position of a mesh point: (column, row, depth), pixel centres at integers.
    pub fn to_pixel(&self, v: &Vector3<f64>) -> Vector3<f64> {
        let w = self.to_world(v);
        Vector3::new(
            w.x + (self.width as f64 - 1.0) / 2.0,
            (self.height as f64 - 1.0) / 2.0 - w.y,
            w.z,
        )
    }
}

/// Twice the signed area of (a, b, c) in fixed point; equals the edge function of a → b at c.
fn edge(a: [i64; 2], b: [i64; 2], p: [i64; 2]) -> i128 {
    (b[0] - a[0]) as i128 * (p[1] - a[1]) as i128 - (b[1] - a[1]) as i128 * (p[0] - a[0]) as i128
}

/// Whether a pixel centre lying exactly on the directed edge a → b counts as inside. The rule
/// is antisymmetric (exactly one of a → b and b → a owns ties), so a shared edge goes to one
/// triangle; it amounts to nudging every pixel centre by an infinitesimal fixed offset, which
/// also gives a vertex on a pixel centre to exactly one triangle of the fan around it.
fn owns_ties(a: [i64; 2], b: [i64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    dy > 0 || (dy == 0 && dx < 0)
}

/// Depth over a triangle as a linear function of the pixel position, anchored at a corner so
/// that steep (nearly edge-on) triangles lose no precision far from the origin.
struct DepthPlane {
    anchor: [f64; 3],
    per_col: f64,
    per_row: f64,
}

impl DepthPlane {
    /// `None` for a triangle of zero projected area.
    fn new(corners: [[i64; 2]; 3], depth: [f64; 3]) -> Option<DepthPlane> {
        let p = corners.map(|c| [c[0] as f64 / SUBPIXEL as f64, c[1] as f64 / SUBPIXEL as f64]);
        let d1 = [p[1][0] - p[0][0], p[1][1] - p[0][1], depth[1] - depth[0]];
        let d2 = [p[2][0] - p[0][0], p[2][1] - p[0][1], depth[2] - depth[0]];
        let area = d1[0] * d2[1] - d1[1] * d2[0];
        (area != 0.0).then(|| DepthPlane {
            anchor: [p[0][0], p[0][1], depth[0]],
            // The plane's normal is d1 × d2; its slopes are −n_x/n_z and −n_y/n_z.
            per_col: -(d1[1] * d2[2] - d1[2] * d2[1]) / area,
            per_row: -(d1[2] * d2[0] - d1[0] * d2[2]) / area,
        })
    }

    fn at(&self, col: usize, row: usize) -> f64 {
        self.anchor[2]
            + self.per_col * (col as f64 - self.anchor[0])
            + self.per_row * (row as f64 - self.anchor[1])
    }
}

/// Barycentric weights of pixel centre (`col`, `row`) in the triangle with fixed-point corners.
fn barycentric(corners: [[i64; 2]; 3], col: usize, row: usize) -> [f64; 3] {
    let p = [col as f64 * SUBPIXEL as f64, row as f64 * SUBPIXEL as f64];
    let [a, b, c] = corners.map(|c| [c[0] as f64, c[1] as f64]);
    let cross = |o: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - o[0]) * (r[1] - o[1]) - (q[1] - o[1]) * (r[0] - o[0])
    };
    let area = cross(a, b, c);
    [
        cross(b, c, p) / area,
        cross(c, a, p) / area,
        cross(a, b, p) / area,
    ]
}

/// Calls `visit(col, row)` for every pixel centre of a `width` × `height` frame inside the
/// triangle with fixed-point corners `corners` (column, row scaled by [`SUBPIXEL`]).
fn cover(corners: [[i64; 2]; 3], width: usize, height: usize, mut visit: impl FnMut(usize, usize)) {
    let [a, b, c] = corners;
    let signed = edge(a, b, c);
    if signed == 0 {
        return;
    }
    // Order the corners so that inside means all three edge functions are positive.
    let (b, c) = if signed < 0 { (c, b) } else { (b, c) };

    let floor_div = |v: i64| v.div_euclid(SUBPIXEL);
    let ceil_div = |v: i64| -(-v).div_euclid(SUBPIXEL);
    let xs = [a[0], b[0], c[0]];
    let ys = [a[1], b[1], c[1]];
    let col_lo = ceil_div(xs.into_iter().min().unwrap_or(0)).max(0);
    let col_hi = floor_div(xs.into_iter().max().unwrap_or(-1)).min(width as i64 - 1);
    let row_lo = ceil_div(ys.into_iter().min().unwrap_or(0)).max(0);
    let row_hi = floor_div(ys.into_iter().max().unwrap_or(-1)).min(height as i64 - 1);
    if col_lo > col_hi || row_lo > row_hi {
        return;
    }

    let edges = [(b, c), (c, a), (a, b)];
    // With integer edge functions, "E > 0, or E = 0 on an owning edge" is "E + bias ≥ 0".
    let bias = edges.map(|(p, q)| if owns_ties(p, q) { 0i128 } else { -1 });
    let step_col = edges.map(|(p, q)| -((q[1] - p[1]) as i128) * SUBPIXEL as i128);
    let step_row = edges.map(|(p, q)| ((q[0] - p[0]) as i128) * SUBPIXEL as i128);
    let start = [col_lo * SUBPIXEL, row_lo * SUBPIXEL];
    let mut row_start = edges.map(|(p, q)| edge(p, q, start));
    for row in row_lo..=row_hi {
        let mut e = row_start;
        for col in col_lo..=col_hi {
            if (0..3).all(|i| e[i] + bias[i] >= 0) {
                visit(col as usize, row as usize);
            }
            for (e, step) in e.iter_mut().zip(&step_col) {
                *e += step;
            }
        }
        for (e, step) in row_start.iter_mut().zip(&step_row) {
            *e += step;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient_space::angle_deg;

    /// How many triangles claim each pixel centre.
    fn coverage(tris: &[[[i64; 2]; 3]], w: usize, h: usize) -> Vec<u32> {
        let mut count = vec![0; w * h];
        for &t in tris {
            cover(t, w, h, |c, r| count[r * w + c] += 1);
        }
        count
    }

    #[test]
    fn shared_edges_and_vertices_on_pixel_centres_are_covered_exactly_once() {
        // A 6×6-pixel square on pixel centres split into a fan of 8 triangles around a vertex
        // on a pixel centre, plus diagonals through pixel centres, both windings mixed.
        let s = SUBPIXEL;
        let p = |c: i64, r: i64| [c * s, r * s];
        let centre = p(4, 4);
        let ring = [
            p(1, 1),
            p(4, 1),
            p(7, 1),
            p(7, 4),
            p(7, 7),
            p(4, 7),
            p(1, 7),
            p(1, 4),
        ];
        let mut tris = Vec::new();
        for i in 0..8 {
            let (a, b) = (ring[i], ring[(i + 1) % 8]);
            tris.push(if i % 2 == 0 {
                [centre, a, b]
            } else {
                [b, a, centre]
            });
        }
        let count = coverage(&tris, 10, 10);
        for r in 0..10 {
            for c in 0..10 {
                let k = count[r * 10 + c];
                let interior = (2..=6).contains(&c) && (2..=6).contains(&r);
                let boundary = (1..=7).contains(&c) && (1..=7).contains(&r) && !interior;
                if interior {
                    assert_eq!(k, 1, "pixel ({c},{r}) covered {k} times");
                } else if boundary {
                    assert!(k <= 1, "boundary pixel ({c},{r}) covered {k} times");
                } else {
                    assert_eq!(k, 0, "outside pixel ({c},{r}) covered");
                }
            }
        }
    }

    #[test]
    fn a_grid_of_subpixel_triangles_has_no_cracks() {
        // Vertices jittered off the pixel lattice at subpixel precision; every pixel centre
        // strictly inside the outer square is covered exactly once.
        let s = SUBPIXEL;
        let n = 6;
        let jitter = |i: i64, j: i64| ((i * 37 + j * 91) % 97 - 48) * s / 200;
        let corner = |i: i64, j: i64| {
            let edge = i == 0 || j == 0 || i == n || j == n;
            let (dx, dy) = if edge {
                (0, 0)
            } else {
                (jitter(i, j), jitter(j, i))
            };
            [i * 3 * s / 2 + s / 3 + dx, j * 3 * s / 2 + s / 3 + dy]
        };
        let mut tris = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let (a, b, c, d) = (
                    corner(i, j),
                    corner(i + 1, j),
                    corner(i + 1, j + 1),
                    corner(i, j + 1),
                );
                if (i + j) % 2 == 0 {
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                } else {
                    tris.push([b, a, d]);
                    tris.push([b, d, c]);
                }
            }
        }
        let count = coverage(&tris, 12, 12);
        let (lo, hi) = (s / 3, n * 3 * s / 2 + s / 3);
        for r in 0..12 {
            for c in 0..12 {
                let (x, y) = (c as i64 * s, r as i64 * s);
                let expected = u32::from(x > lo && x < hi && y > lo && y < hi);
                assert_eq!(count[r * 12 + c], expected, "pixel ({c},{r})");
            }
        }
    }

    #[test]
    fn barycentric_weights_and_depth_planes_interpolate_corners() {
        let s = SUBPIXEL;
        let (a, b, c) = ([0, 0], [8 * s, 0], [s / 3, 8 * s]);
        let z = [1.0, 5.0, -3.0];
        for (corners, z) in [([a, b, c], z), ([a, c, b], [z[0], z[2], z[1]])] {
            let plane = DepthPlane::new(corners, z).unwrap();
            let mut seen = 0;
            cover(corners, 10, 10, |col, row| {
                seen += 1;
                let w = barycentric(corners, col, row);
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                assert!(
                    w.iter().all(|&v| (-1e-12..=1.0 + 1e-12).contains(&v)),
                    "{w:?}"
                );
                let depth: f64 = (0..3).map(|i| w[i] * z[i]).sum();
                assert!((plane.at(col, row) - depth).abs() < 1e-12);
                // Reconstruct the pixel position from the weights.
                let x: f64 = (0..3).map(|i| w[i] * corners[i][0] as f64 / s as f64).sum();
                let y: f64 = (0..3).map(|i| w[i] * corners[i][1] as f64 / s as f64).sum();
                assert!((x - col as f64).abs() < 1e-9 && (y - row as f64).abs() < 1e-9);
            });
            // Pixel centres inside: 8 rows of 8 − row ± the sliver by the top-left corner.
            assert!((28..=45).contains(&seen), "{seen}");
        }
    }

    #[test]
    fn view_rotation_follows_the_documented_conventions() {
        let close = |a: Vector3<f64>, b: Vector3<f64>| (a - b).norm() < 1e-12;
        let yaw = view_rotation(90.0, 0.0, 0.0).unwrap();
        assert!(close(yaw * Vector3::z(), Vector3::x()));
        let pitch = view_rotation(0.0, 90.0, 0.0).unwrap();
        assert!(close(pitch * Vector3::y(), Vector3::z()));
        let roll = view_rotation(0.0, 0.0, 90.0).unwrap();
        assert!(close(roll * Vector3::x(), Vector3::y()));
        // Yaw first, then pitch: the front turns right, then stays level under pitch.
        let both = view_rotation(90.0, 30.0, 0.0).unwrap();
        assert!(close(both * Vector3::z(), Vector3::x()));
        assert!(view_rotation(f64::NAN, 0.0, 0.0).is_err());
    }

    const SQUARE: [[f64; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.5],
        [0.0, 1.0, 0.0],
    ];

    fn quad_mesh() -> Mesh {
        // A unit square in the z = 0 plane with a raised corner, wound counter-clockwise.
        Mesh::new(
            SQUARE.iter().map(|v| Vector3::from(*v)).collect(),
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap()
    }

    #[test]
    fn fit_centres_and_scales_the_bounding_box() {
        let m = quad_mesh();
        let p = Projection::fit(&m, 20, 10, &Rotation3::identity(), 0.5).unwrap();
        // Height limits: 0.5 × 10 pixels per unit.
        assert_eq!(p.scale(), 5.0);
        let c = p.to_pixel(&Vector3::new(0.5, 0.5, 0.0));
        assert_eq!((c.x, c.y, c.z), (9.5, 4.5, 0.0));
        let top_right = p.to_world(&Vector3::new(1.0, 1.0, 0.5));
        assert_eq!(top_right, Vector3::new(2.5, 2.5, 2.5));
        for bad in [0.0, -1.0, f64::NAN, 17.0] {
            assert!(Projection::fit(&m, 20, 10, &Rotation3::identity(), bad).is_err());
        }
        assert!(Projection::fit(&m, 0, 10, &Rotation3::identity(), 0.5).is_err());
        // Seen edge-on along x and y at once is impossible, but a line along z is a point.
        let needle = Mesh::new(
            vec![Vector3::zeros(), Vector3::z(), Vector3::z() * 2.0],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let e = Projection::fit(&needle, 8, 8, &Rotation3::identity(), 0.5).unwrap_err();
        assert!(e.to_string().contains("single point"));
    }

    #[test]
    fn zero_thickness_fins_and_repeated_triangles_are_not_drawn() {
        // The raised-corner square, plus a fin standing on its diagonal toward the viewer
        // (one triangle in both windings, as decimated scans hold them), plus a repeat of a
        // square triangle in its own winding: the picture is the square's alone.
        let m = quad_mesh();
        let mut vertices = m.vertices.clone();
        vertices.push(Vector3::new(0.6, 0.4, 2.0));
        let fin = [0, 2, 4];
        let mut triangles = m.triangles.clone();
        triangles.extend([fin, [0, 4, 2], [1, 2, 0]]);
        let with = Mesh::new(vertices, triangles).unwrap();
        for shading in [MeshShading::Flat, MeshShading::Smooth] {
            // Seen from the front, the apex lies over the square: both fit the same frame.
            let view = Rotation3::identity();
            let plain = m.rasterize_with(32, 32, &view, 0.8, shading).unwrap();
            let drawn = with.rasterize_with(32, 32, &view, 0.8, shading).unwrap();
            assert_eq!(drawn.mask, plain.mask);
            for k in 0..32 * 32 {
                if plain.mask.data()[k] {
                    assert!(angle_deg(&drawn.normals.data()[k], &plain.normals.data()[k]) < 1e-9);
                }
            }
        }
        assert_eq!(
            distinct_triangles(&[[0, 1, 2], [2, 1, 0], [1, 2, 3], [2, 3, 1], [3, 1, 2]]),
            vec![false, false, true, false, false]
        );
    }

    #[test]
    fn back_faces_and_smooth_normals_face_the_viewer() {
        let m = quad_mesh();
        let flipped = Mesh::new(m.vertices.clone(), vec![[0, 2, 1], [0, 3, 2]]).unwrap();
        for mesh in [&m, &flipped] {
            for shading in [MeshShading::Flat, MeshShading::Smooth] {
                let s = mesh
                    .rasterize_with(16, 16, &Rotation3::identity(), 0.75, shading)
                    .unwrap();
                for (n, &inside) in s.normals.data().iter().zip(s.mask.data()) {
                    if inside {
                        assert!(n.z > 0.0 && (n.norm() - 1.0).abs() < 1e-12);
                    }
                }
                // Triangle (0, 1, 2), below the diagonal x = y, is z = y/2; (0, 2, 3) is z = x/2.
                if shading == MeshShading::Flat {
                    for (col, row, expected) in [(13, 13, (0.0, -0.5)), (2, 2, (-0.5, 0.0))] {
                        let n = s.normals.get(col, row);
                        let expected = Vector3::new(expected.0, expected.1, 1.0).normalize();
                        assert!(angle_deg(n, &expected) < 1e-9, "({col},{row}): {n:?}");
                    }
                }
            }
        }
    }
}
