//! The exact facts the illusions rest on: equal squares, exact rotations, where the light falls.

use super::*;
use crate::cli::{scratch, shadelab};
use shadelab::Image;
use shadelab_io as io;
use std::collections::BTreeSet;

fn labels_and_values(img: &Image, labels: &shadelab::Labels, label: u16) -> Vec<f64> {
    img.data()
        .iter()
        .zip(labels.data())
        .filter(|(_, &l)| l == label)
        .map(|(&v, _)| v)
        .collect()
}

#[test]
fn checker_shadow_squares_a_and_b_share_one_value_in_the_file() {
    let d = scratch("stim-checker");
    ok(&shadelab(
        &d,
        &["render", "checker-shadow", "--out", "c.png"],
    ));
    let (img, info) = io::read_gray(&d.join("c.png"), MAX).unwrap();
    assert_eq!(info.bit_depth, 16);
    let labels = io::read_labels(&d.join("c_mask.png"), MAX).unwrap();
    let meta = sidecar(&d.join("c.json"));
    assert_eq!(meta["targets"][0]["name"], "A");
    assert_eq!(meta["targets"][1]["name"], "B");
    let (a, b) = (
        labels_and_values(&img, &labels, 1),
        labels_and_values(&img, &labels, 2),
    );
    assert!(a.len() > 300 && b.len() > 300);
    let first = a[0];
    assert!(a.iter().chain(&b).all(|&v| v == first), "A and B differ");
    assert_eq!(
        codes(meta["notes"]["a_and_b_value"].as_f64().unwrap()),
        codes(first)
    );
}

#[test]
fn crater_rotation_180_is_the_exact_pixel_rotation() {
    let d = scratch("stim-crater");
    ok(&shadelab(&d, &["render", "crater", "--out", "up.npy"]));
    ok(&shadelab(
        &d,
        &[
            "render",
            "crater",
            "--set",
            "rotation=180",
            "--out",
            "down.npy",
        ],
    ));
    let up = io::read_image(&d.join("up.npy"), MAX).unwrap();
    let down = io::read_image(&d.join("down.npy"), MAX).unwrap();
    assert_eq!(up.rotated_180(), down);
    assert_ne!(up, down);
    let (mu, md) = (
        io::read_labels(&d.join("up_mask.png"), MAX).unwrap(),
        io::read_labels(&d.join("down_mask.png"), MAX).unwrap(),
    );
    let mut rotated = mu.data().to_vec();
    rotated.reverse();
    assert_eq!(rotated, md.data());
}

#[test]
fn bumps_lit_from_above_are_brighter_on_top_and_dimples_below() {
    let d = scratch("stim-bumps");
    ok(&shadelab(
        &d,
        &[
            "render",
            "bumps",
            "--set",
            "pattern=alternate",
            "--out",
            "b.npy",
        ],
    ));
    let img = io::read_image(&d.join("b.npy"), MAX).unwrap();
    let labels = io::read_labels(&d.join("b_mask.png"), MAX).unwrap();
    let meta = sidecar(&d.join("b.json"));
    let targets = meta["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 12);
    for t in targets {
        let label = t["label"].as_u64().unwrap() as u16;
        let rows: Vec<usize> = (0..img.height())
            .filter(|&r| (0..img.width()).any(|c| *labels.get(c, r) == label))
            .collect();
        let mid = (rows[0] + rows[rows.len() - 1]).div_ceil(2);
        let (mut top, mut bottom) = (0.0, 0.0);
        for &r in &rows {
            for c in 0..img.width() {
                if *labels.get(c, r) == label {
                    if r < mid {
                        top += img.get(c, r);
                    } else {
                        bottom += img.get(c, r);
                    }
                }
            }
        }
        let name = t["name"].as_str().unwrap();
        if name.starts_with("bump") {
            assert!(top > 1.5 * bottom, "{name}");
        } else {
            assert!(bottom > 1.5 * top, "{name}");
        }
    }
}

#[test]
fn binary_circles_have_exactly_two_levels_inside() {
    let d = scratch("stim-binary");
    ok(&shadelab(
        &d,
        &[
            "render",
            "circles-binary",
            "--set",
            "layout=random",
            "--seed",
            "5",
            "--out",
            "c.npy",
        ],
    ));
    let img = io::read_image(&d.join("c.npy"), MAX).unwrap();
    let labels = io::read_labels(&d.join("c_mask.png"), MAX).unwrap();
    let n = labels.data().iter().copied().max().unwrap();
    assert!(n >= 10);
    let mut levels = BTreeSet::new();
    for label in 1..=n {
        let v = labels_and_values(&img, &labels, label);
        let inside: BTreeSet<u64> = v.iter().map(|x| x.to_bits()).collect();
        let high = v.iter().filter(|&&x| x > 0.5).count();
        assert_eq!(inside.len(), 2, "circle {label}");
        assert_eq!(2 * high, v.len(), "circle {label}: halves");
        levels.extend(inside);
    }
    assert_eq!(levels.len(), 2, "the same two levels in every circle");
}

#[test]
fn hollow_face_lit_from_above_is_the_convex_face_lit_from_below() {
    let d = scratch("stim-hollow");
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=hollow",
            "--set",
            "light=above",
            "--out",
            "h.npy",
        ],
    ));
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=convex",
            "--set",
            "light=below",
            "--out",
            "c.npy",
        ],
    ));
    ok(&shadelab(
        &d,
        &[
            "render",
            "hollow-mask",
            "--set",
            "mode=convex",
            "--set",
            "light=above",
            "--layers",
            "--out",
            "a.npy",
        ],
    ));
    let h = io::read_image(&d.join("h.npy"), MAX).unwrap();
    let c = io::read_image(&d.join("c.npy"), MAX).unwrap();
    let a = io::read_image(&d.join("a.npy"), MAX).unwrap();
    assert_eq!(h, c);
    assert_ne!(h, a);
    for layer in [
        "a_depth.npy",
        "a_normals.npy",
        "a_shading.npy",
        "a_mask.png",
    ] {
        assert!(d.join(layer).exists(), "{layer}");
    }
}
