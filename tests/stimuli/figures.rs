//! Figures for a paper or a lecture: Adelson's checker-shadow with its letters, proof and
//! green cylinder; the crater's soft shadow; the disc on stimupy's pixel rule; and a named
//! target mask beside every stimulus.

use super::*;
use shadelab::pipeline::render::{self, RenderConfig};
use shadelab::stimulus::{disc, DiscParams, Pixels};
use shadelab::Geometry;
use shadelab::NoProgress;
use shadelab::Params;
use shadelab_io as io;

fn render_with(name: &str, pairs: &[&str]) -> Output {
    let given = Params::parse_pairs(pairs).unwrap();
    stimulus::generate(name, &given, &SizeRequest::default(), 0, MAX)
        .unwrap()
        .1
}

/// The luminance of every pixel with `label`.
fn values(out: &Output, label: u16) -> Vec<f64> {
    let lum = out.pixels.luminance();
    let t = out.targets.as_ref().unwrap();
    lum.data()
        .iter()
        .zip(t.labels.data())
        .filter(|(_, &l)| l == label)
        .map(|(&v, _)| v)
        .collect()
}

#[test]
fn checker_shadow_a_and_b_are_exactly_equal_with_letters_proof_and_colour() {
    for pairs in [
        &["letters=true"][..],
        &["proof=true"],
        &["cylinder_colour=green"],
        &["proof=true", "cylinder_colour=green", "letters=true"],
    ] {
        let out = render_with("checker-shadow", pairs);
        let t = out.targets.as_ref().unwrap();
        assert_eq!(t.names, ["A", "B"], "{pairs:?}");
        let dark = out.notes["a_and_b_value"].as_f64().unwrap();
        let (a, b) = (values(&out, 1), values(&out, 2));
        assert!(a.len() > 300 && b.len() > 300, "{pairs:?}");
        assert!(a.iter().chain(&b).all(|&v| v == dark), "{pairs:?}");
        let green = pairs.contains(&"cylinder_colour=green");
        assert_eq!(matches!(out.pixels, Pixels::Rgb(_)), green, "{pairs:?}");
        if let Pixels::Rgb(rgb) = &out.pixels {
            // A and B are gray in every channel; the cylinder is green.
            for (px, &l) in rgb.data().iter().zip(t.labels.data()) {
                if l > 0 {
                    assert_eq!(*px, [dark; 3]);
                }
            }
            assert!(rgb.data().iter().any(|p| p[1] > 1.5 * p[0] && p[1] > 0.2));
        }
    }
}

#[test]
fn checker_shadow_letters_are_ink_outside_the_mask_and_the_proof_bar_has_the_shared_value() {
    let plain = render_with("checker-shadow", &[]);
    let lettered = render_with("checker-shadow", &["letters=true"]);
    let (Pixels::Gray(p), Pixels::Gray(l)) = (&plain.pixels, &lettered.pixels) else {
        panic!("gray by default")
    };
    for label in [1, 2] {
        let (n_plain, n_lettered) = (values(&plain, label).len(), values(&lettered, label).len());
        assert!(
            n_lettered < n_plain,
            "letter {label} takes pixels out of the mask"
        );
        assert!(
            n_lettered * 10 > n_plain * 7,
            "letter {label} is small beside its square"
        );
    }
    // Pixels that leave the mask are darker than the square (black ink, anti-aliased).
    let dark = plain.notes["a_and_b_value"].as_f64().unwrap();
    let (tp, tl) = (
        &plain.targets.as_ref().unwrap().labels,
        &lettered.targets.as_ref().unwrap().labels,
    );
    let inked: Vec<f64> = (0..p.data().len())
        .filter(|&i| tp.data()[i] > 0 && tl.data()[i] == 0)
        .map(|i| l.data()[i])
        .collect();
    assert!(!inked.is_empty() && inked.iter().all(|&v| v < dark));
    assert!(inked.contains(&0.0), "fully inked pixels are black");
    // The proof: the pixel halfway between the letters' centres has exactly A's value.
    let proof = render_with("checker-shadow", &["proof=true", "letters=true"]);
    let Pixels::Gray(img) = &proof.pixels else {
        panic!()
    };
    let at = &proof.notes["letter_centres_px"];
    let mid = |k: usize| (at["A"][k].as_f64().unwrap() + at["B"][k].as_f64().unwrap()) / 2.0;
    let (c, r) = (mid(0).floor() as usize, mid(1).floor() as usize);
    assert_eq!(*img.get(c, r), dark);
    let count = |i: &shadelab::Image| i.data().iter().filter(|&&v| v == dark).count();
    assert!(
        count(img) > count(l) + 100,
        "the bar adds pixels of the shared value"
    );
}

/// Pixels strictly between shadow and light, and whether every pixel is one or the other.
fn penumbra(light_size: &str) -> (usize, bool) {
    let out = render_with("crater", &[&format!("light_size={light_size}")]);
    let Pixels::Gray(img) = &out.pixels else {
        panic!()
    };
    let shading = out.surface.as_ref().unwrap().shading.as_ref().unwrap();
    let ambient = 0.1;
    let mut between = 0;
    let mut hard = true;
    for (&v, &s) in img.data().iter().zip(shading.data()) {
        if v != s && v != ambient {
            hard = false;
        }
        if v > ambient + 1e-9 && v < s - 1e-9 {
            between += 1;
        }
    }
    (between, hard)
}

#[test]
fn crater_shadow_has_a_penumbra_that_widens_with_the_light_and_is_hard_for_a_point() {
    let (n0, hard0) = penumbra("0");
    assert!(hard0 && n0 == 0, "a point light casts the old hard shadow");
    let (n5, hard5) = penumbra("5");
    let (n20, _) = penumbra("20");
    let (n40, _) = penumbra("40");
    assert!(!hard5 && n5 > 20, "{n5}");
    assert!(n5 < n20 && n20 < n40, "{n5} {n20} {n40}");
    // With size 0 the picture is what the renderer's hard shadow gives, pixel for pixel.
    let out = render_with("crater", &["light_size=0"]);
    let Pixels::Gray(img) = &out.pixels else {
        panic!()
    };
    let shaded = img
        .data()
        .iter()
        .zip(
            out.surface
                .as_ref()
                .unwrap()
                .shading
                .as_ref()
                .unwrap()
                .data(),
        )
        .filter(|(v, s)| v != s)
        .count();
    assert!(shaded > 100, "the hard shadow darkens {shaded} pixels");
}

#[test]
fn disc_follows_stimupys_pixel_rule_on_hand_worked_cases() {
    // stimupy (components.radials.disc, origin "mean"): x = linspace(-W/2, W/2, w) and
    // y = linspace(-H/2, H/2, h) in degrees, inside when round(hypot(x, y), 8) <= radius.
    let mask = |w: usize, h: usize, ppd: f64, radius: f64| -> Vec<Vec<u8>> {
        let p = DiscParams {
            radius,
            ..Default::default()
        };
        let g = Geometry {
            width: w,
            height: h,
            ppd,
        };
        let out = disc(&p, &g).unwrap();
        let t = out.targets.unwrap();
        let Pixels::Gray(img) = out.pixels else {
            panic!()
        };
        (0..h)
            .map(|r| {
                (0..w)
                    .map(|c| {
                        assert_eq!(*t.labels.get(c, r) == 1, *img.get(c, r) == 1.0);
                        *t.labels.get(c, r) as u8
                    })
                    .collect()
            })
            .collect()
    };
    // 6 x 4 px at 2 ppd: x = -1.5, -0.9, -0.3, 0.3, 0.9, 1.5; y = -1, -1/3, 1/3, 1.
    // (0.9, 1/3) is 0.960 from the centre: in; (0.3, 1) is 1.044: out; (1.5, 1/3): out.
    // (A pixel-centre rule would take (±0.5, ±1.5) px = 0.79° too: 12 pixels.)
    assert_eq!(
        mask(6, 4, 2.0, 1.0),
        [
            vec![0, 0, 0, 0, 0, 0],
            vec![0, 1, 1, 1, 1, 0],
            vec![0, 1, 1, 1, 1, 0],
            vec![0, 0, 0, 0, 0, 0],
        ]
    );
    // 5 x 5 px at 1 ppd: x, y = -2.5, -1.25, 0, 1.25, 2.5. Radius 1.25 takes (0, ±1.25) and
    // (±1.25, 0), exactly on the edge (<=), but not (1.25, 1.25) = 1.77.
    assert_eq!(
        mask(5, 5, 1.0, 1.25),
        [
            vec![0, 0, 0, 0, 0],
            vec![0, 0, 1, 0, 0],
            vec![0, 1, 1, 1, 0],
            vec![0, 0, 1, 0, 0],
            vec![0, 0, 0, 0, 0],
        ]
    );
    // stimupy's disc(visual_size=16, ppd=64, radius=4) has 205,508 pixels.
    let big = mask(1024, 1024, 64.0, 4.0);
    let count: usize = big.iter().flatten().map(|&v| v as usize).sum();
    assert_eq!(count, 205_508);
}

#[test]
fn checkerboard_targets_are_stimupys_target_indices() {
    // No targets unless named, as stimupy (its target_mask is all zeros then).
    let out = render_with("checkerboard", &["check=2"]);
    assert!(out.targets.is_none());
    let out = render_with(
        "checkerboard",
        &["check=2", "targets=1,2;3,0", "intensity_target=0.25"],
    );
    let t = out.targets.as_ref().unwrap();
    assert_eq!(t.names, ["r1c2", "r3c0"]);
    let Pixels::Gray(img) = &out.pixels else {
        panic!()
    };
    assert_eq!(
        (*t.labels.get(128 + 5, 64 + 5), *img.get(133, 69)),
        (1, 0.25)
    );
    assert_eq!((*t.labels.get(5, 250), *img.get(5, 250)), (2, 0.25));
    assert_eq!((*t.labels.get(5, 5), *img.get(5, 5)), (0, 0.0));
    let given = Params::parse_pairs(&["targets=8,0"]).unwrap();
    let e = stimulus::generate("checkerboard", &given, &SizeRequest::default(), 0, MAX)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(e.contains("outside the board"), "{e}");
}

#[test]
fn every_stimulus_writes_a_named_target_mask_beside_its_image() {
    let d = crate::cli::scratch("stim-every-mask");
    let mut rendered = Vec::new();
    for s in render::list() {
        let out = d.join(format!("{}.png", s.name));
        let mut config = RenderConfig::new(s.name);
        // Its default visual size, at a ppd that keeps the picture near 128 pixels.
        let info = stimulus::find(s.name).unwrap().info();
        let (h, w) = info.default_visual_size;
        if s.name == "checkerboard" {
            // A checkerboard has targets only where named (as stimupy's target_indices).
            config.params.insert("targets".into(), "0,0;1,1".into());
        }
        config.size = SizeRequest {
            visual_size: Some((h, w)),
            ppd: Some((128.0 / w.max(h)).min(info.default_ppd)),
            shape: None,
        };
        let report = match render::run(&config, &NoProgress) {
            Ok(r) => r,
            // A stimulus that needs a file (a depth map, a mesh) has no defaults to render.
            Err(e) if e.to_string().to_lowercase().contains("file") => {
                eprintln!("every mask: {} needs a file ({e}); skipped", s.name);
                continue;
            }
            Err(e) => panic!("{}: {e}", s.name),
        };
        report.write(&shadelab::Output::new(&out)).unwrap();
        let mask_path = d.join(format!("{}_mask.png", s.name));
        assert!(mask_path.exists(), "{}: no mask beside the image", s.name);
        let labels = io::read_labels(&mask_path, MAX).unwrap();
        assert!(
            labels.data().iter().any(|&l| l > 0),
            "{}: the mask is empty",
            s.name
        );
        let meta = sidecar(&d.join(format!("{}.json", s.name)));
        let names = meta["targets"].as_array().unwrap();
        assert!(!names.is_empty(), "{}: no named targets", s.name);
        let top = labels.data().iter().max().copied().unwrap() as usize;
        assert!(top <= names.len(), "{}: label {top} has no name", s.name);
        assert!(
            names
                .iter()
                .all(|n| !n["name"].as_str().unwrap().is_empty()),
            "{}",
            s.name
        );
        rendered.push(s.name);
    }
    for must in ["checkerboard", "disc", "checker-shadow", "crater", "sphere"] {
        assert!(rendered.contains(&must), "{must} was not rendered");
    }
}
