//! Perception, second round (issue 21): the light estimated without bias on rendered objects,
//! and the hollow mask read the same at any framing.

use serde_json::{Map, Value};
use shadelab::grid::{Image, Mask};
use shadelab::light_estimation::{estimate_light_with, EstimateMethod, LightEstimate, Outline};
use shadelab::stimulus;
use shadelab::visual_size::SizeRequest;

/// Renders stimulus `name` at `w`×`h` pixels (`ppd` pixels per degree) with `pairs`: its
/// linear luminance and its target mask (every labelled pixel).
fn render(name: &str, pairs: &[&str], (w, h): (usize, usize), ppd: f64) -> (Image, Mask) {
    let given: Map<String, Value> = shadelab::params::Params::parse_pairs(pairs).unwrap();
    let size = SizeRequest {
        visual_size: Some((h as f64 / ppd, w as f64 / ppd)),
        ppd: Some(ppd),
        shape: None,
    };
    let (_, output) = stimulus::generate(name, &given, &size, 1, 1 << 24).unwrap();
    let image = output.pixels.luminance();
    assert_eq!((image.width(), image.height()), (w, h), "{name}");
    let mask = output
        .targets
        .as_ref()
        .expect("a rendered object has a target")
        .labels
        .map(|&l| l != 0);
    (image, mask)
}

/// The difference between two tilts, degrees, 0..180.
fn tilt_error(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(360.0);
    d.min(360.0 - d)
}

const SLANTS: [f64; 5] = [0.0, 15.0, 30.0, 45.0, 60.0];
const TILTS: [f64; 6] = [0.0, 45.0, 90.0, 135.0, 180.0, 270.0];

/// The estimates of `object` rendered at 128² under every light of the grid, as (tilt, slant,
/// by the limb, by the moments).
fn grid_estimates(object: &str) -> Vec<(f64, f64, LightEstimate, LightEstimate)> {
    let mut out = Vec::new();
    for slant in SLANTS {
        for tilt in TILTS {
            let light = format!("light=tilt={tilt},slant={slant}");
            let (image, mask) = render(
                object,
                &[&light, "ambient=0", "albedo=0.8"],
                (128, 128),
                16.0,
            );
            let e = estimate_light_with(&image, &mask, Outline::Occluding).unwrap();
            let m = estimate_light_with(&image, &mask, Outline::Unknown).unwrap();
            out.push((tilt, slant, e, m));
        }
    }
    out
}

/// The largest errors (tilt where the slant is at least 15°, |slant|) of `object` over the grid,
/// by the limb and by the moments, printing the table (`--nocapture`).
fn grid_errors(object: &str) -> [(f64, f64); 2] {
    let mut worst = [(0.0f64, 0.0f64); 2];
    println!("{object}: tilt error, slant error (degrees) by the limb [moments]; rows slant, columns tilt");
    for (k, (tilt, slant, e, m)) in grid_estimates(object).into_iter().enumerate() {
        for (w, x) in worst.iter_mut().zip([&e, &m]) {
            if slant >= 15.0 {
                w.0 = w.0.max(tilt_error(x.tilt_deg, tilt));
            }
            w.1 = w.1.max((x.slant_deg - slant).abs());
        }
        if k % TILTS.len() == 0 {
            print!("  slant {slant:>2}:");
        }
        print!(
            " {tilt:>3}: {:5.1} {:+5.1} [{:5.1} {:+5.1}] |",
            tilt_error(e.tilt_deg, tilt),
            e.slant_deg - slant,
            tilt_error(m.tilt_deg, tilt),
            m.slant_deg - slant
        );
        if k % TILTS.len() == TILTS.len() - 1 {
            println!();
        }
    }
    println!("  worst: limb {:?}, moments {:?}", worst[0], worst[1]);
    worst
}

/// The sphere meets the goal everywhere (tilt within 5° where the slant is at least 15°, slant
/// within 5°); in fact within 1.2°.
#[test]
fn the_limb_estimate_is_unbiased_on_the_sphere() {
    let [limb, moments] = grid_errors("sphere");
    assert!(limb.0 < 0.5 && limb.1 < 1.5, "{limb:?}");
    // The moments were 22° off in slant at frontal light.
    assert!(moments.1 > 15.0, "{moments:?}");
}

/// The vase: the tilt within 5° except with the light from the lower or upper side at
/// slants of 45° and more (the vase's cut rim, not a limb, is then a large part of the lit
/// outline); the slant within 7°. Where one side only is lit (light from the side) the limb's
/// normals barely vary and the rim's own light (the fit's constant) cannot be told from the
/// light's sideways part: the limb's slant error is then large and the moments give the
/// slant.
#[test]
fn the_limb_estimate_on_the_vase() {
    let [limb, _] = grid_errors("vase");
    assert!(limb.1 < 7.0, "{limb:?}");
    for (tilt, slant, e, _) in grid_estimates("vase") {
        assert_ne!(e.method, EstimateMethod::Moments);
        if slant >= 15.0 && (slant <= 30.0 || tilt % 90.0 == 0.0) {
            assert!(
                tilt_error(e.tilt_deg, tilt) < 5.0,
                "tilt {tilt} slant {slant}: {e:?}"
            );
        }
        if e.method == EstimateMethod::LimbAndMoments {
            assert!(e.slant_se_deg.unwrap() > 3.0);
        }
    }
}

/// The bunny (a mesh with interpolated normals, whose silhouette normals are not quite in the
/// image plane): tilt within 5° from a slant of 30°, within 9° at 15°; the slant comes out
/// up to 11° low.
#[test]
fn the_limb_estimate_on_the_bunny() {
    let [limb, moments] = grid_errors("bunny");
    assert!(limb.0 < 9.0 && limb.1 < 12.0, "{limb:?}");
    for (tilt, slant, e, _) in grid_estimates("bunny") {
        if slant >= 30.0 {
            assert!(
                tilt_error(e.tilt_deg, tilt) < 5.0,
                "tilt {tilt} slant {slant}: {e:?}"
            );
        }
    }
    assert!(moments.0 > limb.0, "{moments:?} {limb:?}");
}

/// Without an occluding outline (the whole frame, or `Outline::Unknown`) the moments run, as
/// before, and say so.
#[test]
fn without_a_limb_the_moments_run() {
    let (image, mask) = render(
        "sphere",
        &["light=tilt=30,slant=40", "ambient=0"],
        (64, 64),
        16.0,
    );
    let e = estimate_light_with(&image, &mask, Outline::Unknown).unwrap();
    assert_eq!(e.method, EstimateMethod::Moments);
    assert_eq!(e.slant_se_deg, None);
    assert_eq!(e.limb_pixels, 0);
    let whole = Mask::new(64, 64, true);
    let e = estimate_light_with(&image, &whole, Outline::Occluding).unwrap();
    assert_eq!(e.method, EstimateMethod::Moments, "the frame is no limb");
    let e = estimate_light_with(&image, &mask, Outline::Occluding).unwrap();
    assert_eq!(e.method, EstimateMethod::Limb);
    assert!(e.limb_pixels >= 16 && e.tilt_se_deg < 5.0, "{e:?}");
}

mod hollow {
    use shadelab::analysis::observer::{observe, LightPrior, ObserverOptions};
    use shadelab::analysis::{Domain, Picture, Sweep};

    /// The hollow mask with `pairs`, `w`×`h` pixels at `ppd`.
    pub fn picture(pairs: &[&str], size: (usize, usize), ppd: f64) -> Picture {
        crate::analysis::picture("hollow-mask", pairs, size, ppd)
    }

    /// The face's interpretations under tilts every 30° (flat boundary, slant 45°).
    pub fn sweep_of(p: &Picture, domain: Domain) -> Sweep {
        let tilts: Vec<f64> = (0..12).map(|i| i as f64 * 30.0).collect();
        crate::analysis::interpretations(p, domain, &tilts).0
    }

    /// (P(convex), P(light from above), most probable tilt) upright, with convexity bias `bias`.
    pub fn percept(s: &Sweep, bias: f64) -> (f64, f64, f64) {
        let o = ObserverOptions {
            prior: LightPrior {
                convexity_bias: bias,
                ..LightPrior::default()
            },
            ..ObserverOptions::default()
        };
        let p = observe(s, &o, &[0.0]).unwrap().remove(0);
        (p.p_convex[0], p.p_light_above, p.map_tilt_deg)
    }
}

/// The hollow face lit from above, framed `w`×`h` degrees (10 ppd, the face 5° wide) on each
/// background (black, the default 0.1, mid grey): solved on the face's region (the background
/// is no part of the surface), it is seen hollow without a familiar-shape prior (P(convex)
/// < 0.1, the light from above) and convex lit from below with it (B = 7: P(convex) > 0.9,
/// the most probable light at 180°), with the same numbers for every framing and background;
/// solved over the whole picture, the background a surface too, the reading keeps its sign but
/// weakens where the background is one no facing plane under the declared light could give.
fn hollow_mask_reads_the_same(w: f64, h: f64) {
    use shadelab::analysis::Domain;
    let ppd = 10.0;
    let mut face_readings = Vec::new();
    for bg in ["0", "0.1", "0.5"] {
        let size = ((w * ppd) as usize, (h * ppd) as usize);
        let p = hollow::picture(&[&format!("background={bg}")], size, ppd);
        for domain in [Domain::Tokens, Domain::Image] {
            let s = hollow::sweep_of(&p, domain);
            let above = s.interpretations[0].tokens[0].convexity;
            let below = s.interpretations[6].tokens[0].convexity;
            let plain = hollow::percept(&s, 0.0);
            let familiar = hollow::percept(&s, 7.0);
            println!(
                "{w}x{h}° background {bg} domain {domain}: c above {above:+.4}, below {below:+.4}; \
                 B = 0: P(convex) {:.3}, P(above) {:.3}, MAP {}°; B = 7: {:.3}, {:.3}, {}°",
                plain.0, plain.1, plain.2, familiar.0, familiar.1, familiar.2
            );
            assert!(above < -0.004 && below > 0.004, "{bg} {domain}");
            assert!(
                familiar.0 > 0.9 && familiar.1 < 0.1,
                "{bg} {domain}: {familiar:?}"
            );
            if domain == Domain::Tokens {
                assert!(above < -0.01, "{bg}");
                assert!(
                    plain.0 < 0.1 && plain.1 > 0.9 && plain.2 == 0.0,
                    "{bg}: {plain:?}"
                );
                assert_eq!(familiar.2, 180.0, "{bg}");
                face_readings.push((plain.0, familiar.0));
            } else {
                assert!(plain.0 < 0.2 && plain.1 > 0.8, "{bg}: {plain:?}");
            }
        }
    }
    // On the face's region the background changes nothing.
    for r in &face_readings {
        assert!((r.0 - face_readings[0].0).abs() < 1e-6 && (r.1 - face_readings[0].1).abs() < 1e-6);
    }
}

#[test]
fn the_hollow_mask_reads_the_same_in_a_5_by_7_degree_frame() {
    hollow_mask_reads_the_same(5.0, 7.0);
}

#[test]
fn the_hollow_mask_reads_the_same_in_the_default_7_by_9_degree_frame() {
    hollow_mask_reads_the_same(7.0, 9.0);
}

#[test]
fn the_hollow_mask_reads_the_same_in_a_12_by_14_degree_frame() {
    hollow_mask_reads_the_same(12.0, 14.0);
}
