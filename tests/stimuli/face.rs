//! The built-in face (MediaPipe's canonical face model) in the hollow-mask stimulus, and the
//! mesh rasteriser at the size where the bunny showed dark slivers.

use serde_json::{Map, Value};
use shadelab::stimulus::{self, hollow_mask, HollowMaskParams, Output, Pixels};
use shadelab::Grid;
use shadelab::{Geometry, SizeRequest};
use shadelab::{ParamSet, Params};
use shadelab_engine::imageops::fill_holes;
use shadelab_stimuli::face::{face_mesh, face_relief, face_view, FACE_MIRROR_NORMAL};

fn mask_face(pairs: &[&str], width: usize, height: usize, ppd: f64) -> Output {
    let params = HollowMaskParams::from_map(&Params::parse_pairs(pairs).unwrap()).unwrap();
    let g = Geometry { width, height, ppd };
    hollow_mask(&params, &g).unwrap()
}

fn gray(out: &Output) -> &Grid<f64> {
    match &out.pixels {
        Pixels::Gray(img) => img,
        Pixels::Rgb(_) => panic!("the hollow mask is grey"),
    }
}

/// (column, row) of the greatest value inside the mask (the first in row-major order).
fn argmax(values: &Grid<f64>, mask: &Grid<bool>) -> (usize, usize) {
    let (mut best, mut at) = (f64::NEG_INFINITY, 0);
    for (k, (&v, &m)) in values.data().iter().zip(mask.data()).enumerate() {
        if m && v > best {
            (best, at) = (v, k);
        }
    }
    (at % values.width(), at / values.width())
}

#[test]
fn the_stored_mesh_is_mirror_symmetric_about_the_recorded_plane() {
    let mesh = face_mesh().unwrap();
    assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (468, 898));
    let n = nalgebra::Vector3::from(FACE_MIRROR_NORMAL);
    assert!((n.norm() - 1.0).abs() < 1e-7);
    for v in &mesh.vertices {
        let mirrored = v - n * (2.0 * v.dot(&n));
        let nearest = mesh
            .vertices
            .iter()
            .map(|u| (u - mirrored).norm())
            .fold(f64::INFINITY, f64::min);
        assert!(nearest < 1e-4, "{v:?}: {nearest}");
    }
    // Turned by the view, the mirror plane is x = 0.
    let turned = face_view() * n.normalize();
    assert!((turned - nalgebra::Vector3::x()).norm() < 1e-12);
}

#[test]
fn the_nose_tip_is_nearest_in_the_convex_face_and_farthest_in_the_hollow_one() {
    let (w, h, ppd) = (140, 180, 20.0);
    let convex = mask_face(&["mode=convex"], w, h, ppd);
    let hollow = mask_face(&["mode=hollow"], w, h, ppd);
    let (cs, hs) = (convex.surface.unwrap(), hollow.surface.unwrap());
    assert_eq!(cs.mask, hs.mask);
    // Depth of the hollow face is the convex face's, negated, at every pixel.
    assert_eq!(hs.depth, cs.depth.map(|z| -z));
    let tip = face_relief(w, h, 5.0 * ppd, 1.0).unwrap().nose_tip;
    let near = argmax(&cs.depth, &cs.mask);
    let far = argmax(&hs.depth.map(|z| -z), &hs.mask);
    assert_eq!(near, far);
    assert!(
        (near.0 as f64 - tip.0).abs() <= 1.0 && (near.1 as f64 - tip.1).abs() <= 1.0,
        "nearest pixel {near:?}, the mesh's nose tip at {tip:?}"
    );
    // The nose is on the vertical midline, below the centre of the frame.
    assert!((tip.0 - (w as f64 - 1.0) / 2.0).abs() < 0.5, "{tip:?}");
    assert!(tip.1 > h as f64 / 2.0);
    assert_eq!(convex.targets.unwrap().names, vec!["convex"]);
    assert_eq!(hollow.targets.unwrap().names, vec!["hollow"]);
}

#[test]
fn the_eyes_sit_in_sockets_where_the_mesh_has_them() {
    let (w, h) = (200, 240);
    let face = face_relief(w, h, 180.0, 1.0).unwrap();
    let back = face_view().inverse();
    let pixel = |x: f64, y: f64| {
        face.projection
            .to_pixel(&(back * nalgebra::Vector3::new(x, y, 0.0)))
    };
    let (depth, mask) = (&face.surface.depth, &face.surface.mask);
    // In the mesh (turned to face the viewer, centimetres), 2 cm either side of the midline
    // the depth falls from the cheek (y = −1) to the eye at y ≈ 1.75 and rises to the brow
    // (y = 4).
    let cm = face.projection.scale();
    for side in [-1.0, 1.0] {
        let eye = pixel(2.0 * side, 1.75);
        let col = eye.x.round() as usize;
        let (top, bottom) = (pixel(0.0, 4.0).y.round(), pixel(0.0, -1.0).y.round());
        let rows = top as usize..=bottom as usize;
        assert!(rows.clone().all(|r| *mask.get(col, r)));
        let socket = rows
            .clone()
            .min_by(|&a, &b| depth.get(col, a).total_cmp(depth.get(col, b)))
            .unwrap();
        assert!(
            (socket as f64 - eye.y).abs() < 0.5 * cm,
            "side {side}: socket at row {socket}, the mesh's eye at {}",
            eye.y
        );
        let z = *depth.get(col, socket);
        assert!(*depth.get(col, top as usize) > z + 1.0 * cm);
        assert!(*depth.get(col, bottom as usize) > z + 0.4 * cm);
    }
    // The two eyes mirror each other (the face is symmetric about its midline).
    let (l, r) = (pixel(-2.0, 1.75), pixel(2.0, 1.75));
    assert!((l.x + r.x - (w as f64 - 1.0)).abs() < 1e-3 && (l.y - r.y).abs() < 1e-3);
}

#[test]
fn the_pair_shows_both_faces_lit_the_same_above_their_side_profiles() {
    let (w, h) = (160, 200);
    let out = mask_face(&["layout=pair", "light=above"], w, h, 20.0);
    let (cw, ch) = (w / 2, h / 2);
    let s = out.surface.as_ref().unwrap();
    let targets = out.targets.as_ref().unwrap();
    assert_eq!(targets.names, vec!["convex", "hollow"]);
    let img = gray(&out);
    let cell = |grid: &Grid<f64>, k: usize| Grid::from_fn(cw, ch, |c, r| *grid.get(c + k * cw, r));
    let cell_mask = |k: usize| Grid::from_fn(cw, ch, |c, r| *s.mask.get(c + k * cw, r));
    // The hollow face (top right) is the convex face (top left) with depth negated, and the
    // labels say which is which.
    assert_eq!(cell_mask(0), cell_mask(1));
    assert_eq!(cell(&s.depth, 1), cell(&s.depth, 0).map(|z| -z));
    for r in 0..h {
        for c in 0..w {
            let expected = match (*s.mask.get(c, r), c < cw) {
                (false, _) => 0,
                (true, true) => 1,
                (true, false) => 2,
            };
            assert_eq!(*targets.labels.get(c, r), expected, "({c},{r})");
        }
    }
    // Lit the same from above: the convex face's brows are bright on top, the hollow face's
    // bright side is its lower one; the mean luminance of the two is the same only by chance,
    // so check the nose: the pixel above the tip is brighter than below in the convex face and
    // darker in the hollow one.
    let depth0 = cell(&s.depth, 0);
    let (tc, tr) = argmax(&depth0, &cell_mask(0));
    let (above, below) = (*img.get(tc, tr - 3), *img.get(tc, tr + 3));
    assert!(above > below, "convex nose: {above} above, {below} below");
    let (above, below) = (*img.get(tc + cw, tr - 3), *img.get(tc + cw, tr + 3));
    assert!(above < below, "hollow nose: {above} above, {below} below");
    // The side profiles (bottom row): every row the midline crosses is filled from the rim
    // plane toward the viewer (right) by the convex depth, and away from it (left) for the
    // hollow face; the rim plane is a light line; everything else is background.
    let fill = 0.55;
    let rim_line = 0.9;
    let background = *img.get(0, h - 1);
    let rims: Vec<usize> = (0..2)
        .map(|k| {
            (0..cw)
                .find(|&c| (0..ch).any(|r| *img.get(c + k * cw, r + ch) == rim_line))
                .unwrap()
        })
        .collect();
    assert!(rims[0] < cw / 2 && rims[1] > cw / 2, "{rims:?}");
    let mut filled = 0;
    for r in 0..ch {
        let z = depth0.get(tc, r);
        let inside = *cell_mask(0).get(tc, r);
        for (k, sign) in [(0usize, 1.0f64), (1, -1.0)] {
            for c in 0..cw {
                let x = sign * (c as f64 - rims[k] as f64);
                let v = *img.get(c + k * cw, r + ch);
                let expected = if !inside {
                    background
                } else if c == rims[k] {
                    rim_line
                } else if x > 0.0 && x <= *z {
                    filled += 1;
                    fill
                } else {
                    background
                };
                assert_eq!(v, expected, "profile {k} at ({c},{r}), depth {z}");
            }
        }
    }
    assert!(filled > 1000, "{filled}");
}

#[test]
fn the_bunny_at_1024_pixels_has_no_holes_and_no_dark_slivers() {
    let size = SizeRequest {
        visual_size: None,
        ppd: Some(32.0),
        shape: Some((1024, 1024)),
    };
    let (_, out) =
        stimulus::generate("bunny", &Map::<String, Value>::new(), &size, 0, 1 << 24).unwrap();
    let s = out.surface.unwrap();
    assert_eq!((s.mask.width(), s.mask.height()), (1024, 1024));
    // No pixel inside the silhouette is left uncovered.
    assert_eq!(fill_holes(&s.mask), s.mask);
    // Away from the silhouette and from occluding edges (a depth step over 2 pixels), the
    // surface never turns edge on: the zero-thickness fins of the decimated scan, whose
    // vertex normals cancelled, showed here as dark slivers (13 pixels before the fix).
    let (w, h) = (1024usize, 1024usize);
    let edge = Grid::from_fn(w, h, |c, r| {
        if !*s.mask.get(c, r) {
            return true;
        }
        let z = *s.depth.get(c, r);
        [(1, 0), (-1, 0), (0, 1), (0, -1)].iter().any(|&(dc, dr)| {
            let (cc, rr) = (c as isize + dc, r as isize + dr);
            (0..w as isize).contains(&cc)
                && (0..h as isize).contains(&rr)
                && (s.depth.get(cc as usize, rr as usize) - z).abs() > 2.0
        })
    });
    let near_edge = |c: usize, r: usize| {
        (c.saturating_sub(3)..(c + 4).min(w))
            .any(|cc| (r.saturating_sub(3)..(r + 4).min(h)).any(|rr| *edge.get(cc, rr)))
    };
    let mut grazing = Vec::new();
    for r in 0..h {
        for c in 0..w {
            if *s.mask.get(c, r) && s.normals.get(c, r).z < 0.05 && !near_edge(c, r) {
                grazing.push((c, r));
            }
        }
    }
    assert!(grazing.is_empty(), "{} pixels: {grazing:?}", grazing.len());
}
