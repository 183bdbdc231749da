//! Triangle meshes and depth maps from files: the Stanford bunny, a cube written as OBJ and as
//! binary PLY, a sphere mesh against the analytic sphere, and `.npy` depth maps.

use nalgebra::{Rotation3, Vector3};
use shadelab::Lambertian;
use shadelab::{Grid, Light};
use shadelab_core::gradient_space::angle_deg;
use shadelab_engine::render::{render, RenderOptions};
use shadelab_engine::surface::{
    self, load_depth_surface, view_rotation, world_xy, DepthDomain, Mesh, MeshShading, Projection,
    Surface,
};
use std::path::{Path, PathBuf};

fn bunny_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bun_zipper_res3.ply")
}

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("shadelab-mesh-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// (first col, last col, first row, last row) of the mask.
fn mask_box(s: &Surface) -> (usize, usize, usize, usize) {
    let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
    for r in 0..s.height() {
        for c in 0..s.width() {
            if *s.mask.get(c, r) {
                (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
            }
        }
    }
    (c0, c1, r0, r1)
}

#[test]
fn bunny_rasterises_with_the_expected_silhouette() {
    let bunny = Mesh::load(bunny_path()).unwrap();
    assert_eq!((bunny.vertices.len(), bunny.triangles.len()), (1889, 3851));
    let (n, fill) = (128, 0.8);
    let view = Rotation3::identity();
    let s = bunny.rasterize(n, n, &view, fill).unwrap();

    let area = s.mask.count() as f64 / (n * n) as f64;
    assert!(
        (0.3..0.5).contains(&area),
        "mask covers {area} of the frame"
    );

    // The silhouette spans the projected vertex bounding box (to within the pixel-centre
    // sampling), and the wider side (x) spans fill × 128 = 102.4 pixels.
    let p = Projection::fit(&bunny, n, n, &view, fill).unwrap();
    let px: Vec<Vector3<f64>> = bunny.vertices.iter().map(|v| p.to_pixel(v)).collect();
    let lo = px
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |a, v| a.inf(v));
    let hi = px
        .iter()
        .fold(Vector3::repeat(f64::NEG_INFINITY), |a, v| a.sup(v));
    assert!((hi.x - lo.x - 102.4).abs() < 1e-9);
    let (c0, c1, r0, r1) = mask_box(&s);
    for (mask_edge, vertex_edge) in [(c0, lo.x), (c1, hi.x), (r0, lo.y), (r1, hi.y)] {
        assert!(
            (mask_edge as f64 - vertex_edge).abs() <= 1.0,
            "mask edge {mask_edge} vs projected vertices {vertex_edge}"
        );
    }

    // y up, facing left as scanned: the topmost vertex is the tip of an ear and lands in the
    // top mask row; the top fifth of the silhouette is the two thin ears over the head (on the
    // left), not the broad base (upside down) nor anything right of the middle (mirrored).
    let top = bunny
        .vertices
        .iter()
        .max_by(|a, b| a.y.total_cmp(&b.y))
        .unwrap();
    assert!((p.to_pixel(top).y - r0 as f64).abs() <= 1.0);
    let fifth = r0 + (r1 - r0) / 5;
    let top_pixels = (r0..=fifth)
        .map(|r| s.mask.row(r).iter().filter(|&&m| m).count())
        .sum::<usize>();
    assert!(
        (top_pixels as f64) < 0.12 * s.mask.count() as f64,
        "the top fifth holds {top_pixels} of {} pixels",
        s.mask.count()
    );
    let mask = &s.mask;
    let rightmost = (r0..=fifth)
        .flat_map(|r| (0..n).filter(move |&c| *mask.get(c, r)))
        .max()
        .unwrap();
    assert!(
        (rightmost as f64) < c0 as f64 + 0.65 * (c1 - c0) as f64,
        "ears reach column {rightmost} of {c0}..{c1}"
    );

    // Normals: unit, facing the viewer; depth finite, within the mesh's depth extent.
    let depth_extent = hi.z - lo.z;
    for k in 0..n * n {
        let (nrm, z) = (s.normals.data()[k], s.depth.data()[k]);
        assert!((nrm.norm() - 1.0).abs() < 1e-9 && nrm.z >= 0.0, "{nrm:?}");
        if s.mask.data()[k] {
            assert!((0.0..=depth_extent + 1e-9).contains(&z), "depth {z}");
        } else {
            assert_eq!(z, 0.0);
        }
    }
}

#[test]
fn bunny_renders_lit_from_above_left() {
    let bunny = Mesh::load(bunny_path()).unwrap();
    let s = bunny
        .rasterize(256, 256, &Rotation3::identity(), 0.85)
        .unwrap();
    let light: Light = "above-left".parse().unwrap();
    let lambert = Lambertian {
        light,
        albedo: 1.0,
        ambient: 0.0,
    };
    let options = RenderOptions {
        background: 0.2,
        cast_shadows: true,
    };
    let out = render(&s, &lambert, &options);
    // Surfaces turned toward the light (up and left) are brighter than those turned away.
    let (mut toward, mut away) = (Vec::new(), Vec::new());
    for k in 0..s.mask.len() {
        let nrm = s.normals.data()[k];
        if s.mask.data()[k] {
            let lean = -nrm.x + nrm.y;
            if lean > 0.8 {
                toward.push(out.shading.data()[k]);
            } else if lean < -0.8 {
                away.push(out.shading.data()[k]);
            }
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(toward.len() > 100 && away.len() > 100);
    assert!(mean(&toward) > 0.6 && mean(&away) < 0.3);

    // For looking at: SHADELAB_PREVIEW_DIR=/tmp cargo test --test tests mesh::bunny_renders
    if let Some(dir) = std::env::var_os("SHADELAB_PREVIEW_DIR") {
        let png = image::GrayImage::from_fn(256, 256, |c, r| {
            let v = out.image.get(c as usize, r as usize).clamp(0.0, 1.0);
            image::Luma([(v.powf(1.0 / 2.2) * 255.0).round() as u8])
        });
        png.save(Path::new(&dir).join("bunny_above_left.png"))
            .unwrap();
    }
}

/// The unit cube centred at the origin as six outward, counter-clockwise quads.
fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 4]>) {
    let vertices = (0..8)
        .map(|i| {
            let bit = |b: u32| if i >> b & 1 == 1 { 0.5 } else { -0.5 };
            [bit(0), bit(1), bit(2)]
        })
        .collect();
    let quads = vec![
        [0, 2, 3, 1], // z = −0.5, seen from −z
        [4, 5, 7, 6], // z = +0.5
        [0, 1, 5, 4], // y = −0.5
        [2, 6, 7, 3], // y = +0.5
        [0, 4, 6, 2], // x = −0.5
        [1, 3, 7, 5], // x = +0.5
    ];
    (vertices, quads)
}

fn cube_obj() -> String {
    let (vertices, quads) = cube();
    let mut text = String::from("# unit cube\no cube\n");
    for v in &vertices {
        text += &format!("v {} {} {}\n", v[0], v[1], v[2]);
    }
    text += "vn 0 0 1\n";
    for (i, q) in quads.iter().enumerate() {
        // Alternate absolute, slashed and relative corner forms.
        let corner = |j: u32| match i % 3 {
            0 => format!("{}", j + 1),
            1 => format!("{}//1", j + 1),
            _ => format!("{}", j as i64 - vertices.len() as i64),
        };
        text += &format!(
            "f {} {} {} {}\n",
            corner(q[0]),
            corner(q[1]),
            corner(q[2]),
            corner(q[3])
        );
    }
    text
}

fn cube_ply(big_endian: bool, double: bool) -> Vec<u8> {
    let (vertices, quads) = cube();
    let (order, ty) = (
        if big_endian { "big" } else { "little" },
        if double { "double" } else { "float" },
    );
    let mut out = format!(
        "ply\nformat binary_{order}_endian 1.0\ncomment unit cube\nelement vertex 8\n\
         property {ty} x\nproperty {ty} y\nproperty {ty} z\nproperty float confidence\n\
         element face 6\nproperty list uchar uint vertex_indices\nend_header\n"
    )
    .into_bytes();
    let mut put = |bytes: &[u8]| {
        if big_endian {
            out.extend(bytes.iter().rev());
        } else {
            out.extend(bytes);
        }
    };
    for v in &vertices {
        for c in v {
            if double {
                put(&c.to_le_bytes());
            } else {
                put(&(*c as f32).to_le_bytes());
            }
        }
        put(&0.5f32.to_le_bytes());
    }
    for q in &quads {
        put(&[4]);
        for i in q {
            put(&i.to_le_bytes());
        }
    }
    out
}

#[test]
fn cube_from_obj_and_binary_ply_rasterises_exactly() {
    let dir = scratch("cube");
    let obj = dir.join("cube.obj");
    std::fs::write(&obj, cube_obj()).unwrap();
    let obj = Mesh::load(&obj).unwrap();
    assert_eq!(obj.triangles.len(), 12);
    for (big, double) in [(false, true), (true, false)] {
        let ply = dir.join("cube.ply");
        std::fs::write(&ply, cube_ply(big, double)).unwrap();
        assert_eq!(Mesh::load(&ply).unwrap(), obj, "big endian {big}");
    }
    std::fs::remove_dir_all(&dir).unwrap();

    // Head on, 8×8 at fill 0.75: 6 pixels per unit, the front face spans x, y ∈ [−3, 3] and
    // covers the pixel centres ±0.5 … ±2.5, at depth 6 above the back face.
    let s = obj
        .rasterize_with(8, 8, &Rotation3::identity(), 0.75, MeshShading::Flat)
        .unwrap();
    for r in 0..8 {
        for c in 0..8 {
            let inside = (1..=6).contains(&c) && (1..=6).contains(&r);
            assert_eq!(*s.mask.get(c, r), inside, "({c},{r})");
            if inside {
                assert!((s.depth.get(c, r) - 6.0).abs() < 1e-12);
                assert_eq!(*s.normals.get(c, r), Vector3::z());
            }
        }
    }

    // Turned 45° about y: two faces at 45°, the front (+z) face now on the right. 16×16 at
    // fill 0.75: the √2-wide projection spans 12 pixels, so x ∈ [−6, 6], y ∈ [−4.24, 4.24];
    // depth falls off 1:1 from 12 at the front edge.
    let view = view_rotation(45.0, 0.0, 0.0).unwrap();
    let s = obj
        .rasterize_with(16, 16, &view, 0.75, MeshShading::Flat)
        .unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    for r in 0..16 {
        for c in 0..16 {
            let (x, y) = world_xy(c, r, 16, 16);
            let inside = x.abs() < 6.0 && y.abs() < 0.75 * 16.0 / 2f64.sqrt() / 2.0;
            assert_eq!(*s.mask.get(c, r), inside, "({c},{r})");
            if inside {
                assert!((s.depth.get(c, r) - (12.0 - x.abs())).abs() < 1e-9);
                let expected = Vector3::new(x.signum() * h, 0.0, h);
                assert!(angle_deg(s.normals.get(c, r), &expected) < 1e-9);
            }
        }
    }

    // Pitched 30°: the top face tips toward the viewer and shows at the top of the image.
    let view = view_rotation(0.0, 30.0, 0.0).unwrap();
    let s = obj
        .rasterize_with(32, 32, &view, 0.75, MeshShading::Flat)
        .unwrap();
    let (c0, c1, r0, r1) = mask_box(&s);
    let (top, front) = (s.normals.get(16, r0), s.normals.get(16, r1));
    let (s30, c30) = (0.5, 3f64.sqrt() / 2.0);
    assert!(
        angle_deg(top, &Vector3::new(0.0, c30, s30)) < 1e-9,
        "{top:?}"
    );
    assert!(angle_deg(front, &Vector3::new(0.0, -s30, c30)) < 1e-9);
    assert_eq!((c0, c1), (7, 24));

    // Smooth normals (meaningless at a cube's corners, but still unit and facing the viewer).
    let s = obj.rasterize(32, 32, &view, 0.75).unwrap();
    for (nrm, &m) in s.normals.data().iter().zip(s.mask.data()) {
        assert!(!m || (nrm.z >= 0.0 && (nrm.norm() - 1.0).abs() < 1e-12));
    }
}

/// A latitude–longitude unit sphere, outward counter-clockwise triangles.
fn uv_sphere(bands: usize, sectors: usize) -> Mesh {
    let mut vertices = vec![Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, -1.0, 0.0)];
    for i in 1..bands {
        let polar = std::f64::consts::PI * i as f64 / bands as f64;
        for j in 0..sectors {
            let azimuth = 2.0 * std::f64::consts::PI * j as f64 / sectors as f64;
            vertices.push(Vector3::new(
                polar.sin() * azimuth.sin(),
                polar.cos(),
                polar.sin() * azimuth.cos(),
            ));
        }
    }
    let ring = |i: usize, j: usize| (2 + (i - 1) * sectors + j % sectors) as u32;
    let mut triangles = Vec::new();
    for j in 0..sectors {
        triangles.push([0, ring(1, j), ring(1, j + 1)]);
        triangles.push([1, ring(bands - 1, j + 1), ring(bands - 1, j)]);
        for i in 1..bands - 1 {
            let (a, b, c, d) = (
                ring(i, j),
                ring(i + 1, j),
                ring(i + 1, j + 1),
                ring(i, j + 1),
            );
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    Mesh::new(vertices, triangles).unwrap()
}

#[test]
fn sphere_mesh_matches_the_analytic_sphere() {
    let mesh = uv_sphere(48, 96);
    let (n, fill) = (96, 0.9);
    let radius = fill * n as f64 / 2.0;
    let exact = surface::sphere(n, n, radius).unwrap();
    let mut worst = [0.0f64; 2];
    for (shading, slot) in [(MeshShading::Smooth, 0), (MeshShading::Flat, 1)] {
        let s = mesh
            .rasterize_with(n, n, &Rotation3::identity(), fill, shading)
            .unwrap();
        for r in 0..n {
            for c in 0..n {
                let (x, y) = world_xy(c, r, n, n);
                // The polygon's chords sag less than 0.05 pixel inside the circle.
                if s.mask.get(c, r) != exact.mask.get(c, r) {
                    let off = x.hypot(y) - radius;
                    assert!(
                        off.abs() < 0.05,
                        "mask differs {off} from the rim at ({c},{r})"
                    );
                }
                if x.hypot(y) < 0.9 * radius {
                    let a = angle_deg(s.normals.get(c, r), exact.normals.get(c, r));
                    worst[slot] = worst[slot].max(a);
                    // Depth is measured from the back of the sphere.
                    let dz = s.depth.get(c, r) - radius - exact.depth.get(c, r);
                    assert!(dz.abs() < 0.1, "depth off by {dz} at ({c},{r})");
                }
            }
        }
    }
    assert!(worst[0] < 0.5, "smooth normals off by up to {}°", worst[0]);
    assert!(worst[1] < 4.0, "flat normals off by up to {}°", worst[1]);
    assert!(worst[0] < worst[1] / 2.0);
}

#[test]
fn unreadable_meshes_are_errors_naming_the_file() {
    let dir = scratch("bad");
    let path = dir.join("broken.ply");
    let mut bytes = std::fs::read(bunny_path()).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&path, &bytes).unwrap();
    let e = Mesh::load(&path).unwrap_err().to_string();
    assert!(e.starts_with(&format!("{}: ", path.display())), "{e}");
    assert!(e.contains("truncated"), "{e}");
    let path = dir.join("notes.obj");
    std::fs::write(&path, "this is not a mesh\n").unwrap();
    let e = Mesh::load(&path).unwrap_err().to_string();
    assert!(e.contains("notes.obj") && e.contains("no vertices"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A version-1 little-endian float32 `.npy` file of a depth grid.
fn write_npy(path: &Path, depth: &Grid<f64>) {
    let mut header = format!(
        "{{'descr': '<f4', 'fortran_order': False, 'shape': ({}, {}), }}",
        depth.height(),
        depth.width()
    );
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    for v in depth.data() {
        out.extend((*v as f32).to_le_bytes());
    }
    std::fs::write(path, out).unwrap();
}

#[test]
fn npy_depth_map_of_a_sphere_gives_its_normals() {
    let (n, radius) = (64, 28.0);
    let exact = surface::sphere(n, n, radius).unwrap();
    let dir = scratch("npy");
    let path = dir.join("sphere.npy");
    write_npy(&path, &exact.depth);
    let s = load_depth_surface(&path, DepthDomain::NonZero).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(s.mask, exact.mask);
    let mut worst: f64 = 0.0;
    for r in 0..n {
        for c in 0..n {
            let (x, y) = world_xy(c, r, n, n);
            if x.hypot(y) < 0.8 * radius {
                worst = worst.max(angle_deg(s.normals.get(c, r), exact.normals.get(c, r)));
            }
        }
    }
    // Central differences of a float32 sphere: second-order accurate away from the rim.
    assert!(worst < 0.5, "finite-difference normals off by {worst}°");
}

#[test]
fn mozart_depth_map_loads_when_shared_data_is_present() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/mozart/depth.npy");
    if !path.exists() {
        eprintln!("skipping: {} not found", path.display());
        return;
    }
    let s = load_depth_surface(&path, DepthDomain::NonZero).unwrap();
    assert_eq!((s.width(), s.height()), (256, 256));
    let (_, max) = s.depth.min_max().unwrap();
    assert!((max - 85.1).abs() < 0.1, "max depth {max}");
    let share = s.mask.count() as f64 / (256.0 * 256.0);
    assert!((0.2..0.8).contains(&share), "mask share {share}");
    for (nrm, &m) in s.normals.data().iter().zip(s.mask.data()) {
        assert!(!m || (nrm.z > 0.0 && (nrm.norm() - 1.0).abs() < 1e-9));
    }
}
