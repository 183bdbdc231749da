//! Perception, second round (issue 21): the light estimated without bias on rendered objects,
//! and the hollow mask read the same at any framing.

use serde_json::{Map, Value};
use shadelab::pipeline::perception::Domain;
use shadelab::pipeline::perception::{self, DomainSpec};
use shadelab::pipeline::source::PictureSource;
use shadelab::stimulus;
use shadelab::NoProgress;
use shadelab::SizeRequest;
use shadelab::{Image, Mask};
use shadelab_engine::light_estimation::{
    estimate_light_with, EstimateMethod, LightEstimate, Outline,
};

/// Renders stimulus `name` at `w`×`h` pixels (`ppd` pixels per degree) with `pairs`: its
/// linear luminance and its target mask (every labelled pixel).
fn render(name: &str, pairs: &[&str], (w, h): (usize, usize), ppd: f64) -> (Image, Mask) {
    let given: Map<String, Value> = shadelab::Params::parse_pairs(pairs).unwrap();
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
    grid_estimates_at(object, &[], 16.0)
}

/// The estimates of stimulus `object` with the further parameters `pairs` (see
/// [`grid_estimates`]) in the same 8° frame at `ppd` pixels per degree (16: 128², 32: 256², the
/// objects' default size).
fn grid_estimates_at(
    object: &str,
    pairs: &[&str],
    ppd: f64,
) -> Vec<(f64, f64, LightEstimate, LightEstimate)> {
    let side = (8.0 * ppd).round() as usize;
    let mut out = Vec::new();
    for slant in SLANTS {
        for tilt in TILTS {
            let light = format!("light=tilt={tilt},slant={slant}");
            let mut all = vec![light.as_str(), "ambient=0", "albedo=0.8"];
            all.extend_from_slice(pairs);
            let (image, mask) = render(object, &all, (side, side), ppd);
            let e = estimate_light_with(&image, &mask, Outline::Occluding).unwrap();
            let m = estimate_light_with(&image, &mask, Outline::Unknown).unwrap();
            out.push((tilt, slant, e, m));
        }
    }
    out
}

/// The largest errors (tilt where the slant is at least 15°, |slant|) of the grid's `estimates`
/// of `object`, by the limb and by the moments, printing the table (`--nocapture`).
fn print_grid_errors(
    object: &str,
    estimates: &[(f64, f64, LightEstimate, LightEstimate)],
) -> [(f64, f64); 2] {
    let mut worst = [(0.0f64, 0.0f64); 2];
    println!(
        "{object}: tilt error, slant error (degrees), method [moments]; rows slant, columns tilt"
    );
    for (k, &(tilt, slant, e, m)) in estimates.iter().enumerate() {
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
            " {tilt:>3}: {:5.1} {:+5.1} {:<12} [{:5.1} {:+5.1}] |",
            tilt_error(e.tilt_deg, tilt),
            e.slant_deg - slant,
            e.method.name(),
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
/// within 5°), by the limb band fit; in fact within 1°.
#[test]
fn the_limb_estimate_is_unbiased_on_the_sphere() {
    let estimates = grid_estimates("sphere");
    let [limb, moments] = print_grid_errors("sphere", &estimates);
    assert!(limb.0 < 0.5 && limb.1 < 1.0, "{limb:?}");
    // The moments were 22° off in slant at frontal light.
    assert!(moments.1 > 15.0, "{moments:?}");
    for &(tilt, slant, e, _) in &estimates {
        assert_eq!(e.method, EstimateMethod::LimbBand, "{tilt} {slant}");
        // The ± covers the model's misfit too (widest at slant 15°, 2.1°), and the truth.
        assert!(e.slant_se_deg.unwrap() < 3.0, "{e:?}");
        if slant >= 15.0 {
            assert!(
                (e.slant_deg - slant).abs() <= 2.0 * e.slant_se_deg.unwrap(),
                "{e:?}"
            );
            assert!(e.tilt_se_deg < 2.5, "{e:?}");
            assert!(tilt_error(e.tilt_deg, tilt) <= 2.0 * e.tilt_se_deg, "{e:?}");
        }
    }
}

/// The vase meets the goal everywhere too (within 3.8°): the band's per-pixel cross-section radius follows
/// the vase's narrow neck and wide belly, where the rim fit's one constant could not (it
/// missed the tilt by 13° lit from the lower left at 45°, and the slant by up to 30° lit from
/// the side).
#[test]
fn the_limb_estimate_is_unbiased_on_the_vase() {
    let estimates = grid_estimates("vase");
    let [limb, _] = print_grid_errors("vase", &estimates);
    assert!(limb.0 < 5.0 && limb.1 < 5.0, "{limb:?}");
    for &(tilt, slant, e, _) in &estimates {
        // At frontal light the band's residuals (3.1 % of the albedo) just miss the check and
        // the rim fit runs, within 0.3°.
        let band = slant >= 15.0;
        assert_eq!(e.method == EstimateMethod::LimbBand, band, "{tilt} {slant}");
    }
}

/// The bunny (whose outline pixels face the viewer, its cross-sections at the limb being a few
/// pixels in radius at 128², and whose outline is partly a cut) is not explained by the band's model (residuals above
/// 3 % of the albedo), so the rim fit runs, trimmed one-sided (the limb is the lower envelope of
/// the outline's brightness): tilt within 3° from a slant of 30°, within 6.3° at 15°; the slant
/// within 7.4° (it was 11° low with a symmetric trim). The goal is not met on the bunny: this
/// asserts what is achieved.
#[test]
fn the_limb_estimate_on_the_bunny() {
    let estimates = grid_estimates("bunny");
    let [limb, moments] = print_grid_errors("bunny", &estimates);
    assert!(limb.0 < 6.5 && limb.1 < 7.5, "{limb:?}");
    for &(tilt, slant, e, _) in &estimates {
        assert_ne!(e.method, EstimateMethod::LimbBand, "{tilt} {slant}");
        if slant >= 30.0 {
            assert!(
                tilt_error(e.tilt_deg, tilt) < 3.0,
                "tilt {tilt} slant {slant}: {e:?}"
            );
        }
    }
    assert!(moments.0 > limb.0, "{moments:?} {limb:?}");
}

/// At the objects' default size (8° at 32 pixels per degree, 256²) the bunny's cross-sections
/// at the limb are twice as many pixels in radius, its outline pixels' n_z ≈ √(2δ/R) falls by
/// √2, and the rim fit comes within the goal's tilt (3.8° at slant 15°) but not quite its slant
/// (5.7° high lit from below at 60°, where the lit outline is the open base, a cut). This asserts
/// what is achieved.
#[test]
fn the_limb_estimate_on_the_bunny_at_its_default_size() {
    let estimates = grid_estimates_at("bunny", &[], 32.0);
    let [limb, moments] = print_grid_errors("bunny 256²", &estimates);
    assert!(limb.0 < 4.0 && limb.1 < 6.0, "{limb:?}");
    assert!(moments.0 > limb.0, "{moments:?} {limb:?}");
}

/// A large object's limb is fitted with its own cross-section: at 512² the sphere's radius is
/// about 218 pixels, beyond the band's first radii (up to 128), and its slant came out 5–9°
/// high with a radius held at 128. With the radii continued to the mask's size it is within 1°.
#[test]
fn the_band_fits_a_large_sphere() {
    for (tilt, slant) in [(0.0, 30.0), (135.0, 45.0), (270.0, 60.0), (90.0, 15.0)] {
        let light = format!("light=tilt={tilt},slant={slant}");
        let (image, mask) = render(
            "sphere",
            &[&light, "ambient=0", "albedo=0.8"],
            (512, 512),
            64.0,
        );
        let e = estimate_light_with(&image, &mask, Outline::Occluding).unwrap();
        assert_eq!(e.method, EstimateMethod::LimbBand, "{tilt} {slant}");
        assert!(
            tilt_error(e.tilt_deg, tilt) < 0.5 && (e.slant_deg - slant).abs() < 1.0,
            "tilt {tilt} slant {slant}: {e:?}"
        );
    }
}

/// The finer Stanford bunny of the shared data (`bun_zipper_res2`, 8,171 vertices, rendered
/// by the `mesh` stimulus in the same upright view) fares no better: its silhouette normals are
/// no closer to edge-on, and its open base and ear tips are cuts. The rim fit runs (the band's
/// residuals are 4–8 % of the albedo): tilt within 4.3° from a slant of 30° but 10.2° at 15°,
/// the slant within 7.3° (it was 15.6° low with a symmetric trim). The goal is not met; this
/// asserts what is achieved.
#[test]
fn the_limb_estimate_on_the_finer_bunny() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/bunny/bun_zipper_res2.ply");
    if !path.is_file() {
        eprintln!(
            "skipping: {} not found (the shared reference data is not checked out)",
            path.display()
        );
        return;
    }
    let pair = format!("path={}", path.display());
    let estimates = grid_estimates_at("mesh", &[&pair], 16.0);
    let [limb, moments] = print_grid_errors("bunny res2", &estimates);
    assert!(limb.0 < 10.5 && limb.1 < 7.5, "{limb:?}");
    assert!(moments.0 > limb.0, "{moments:?} {limb:?}");
    for &(tilt, slant, e, _) in &estimates {
        assert_ne!(e.method, EstimateMethod::LimbBand, "{tilt} {slant}");
        if slant >= 30.0 {
            assert!(
                tilt_error(e.tilt_deg, tilt) < 5.0,
                "tilt {tilt} slant {slant}: {e:?}"
            );
        }
    }
}

/// What limits the bunny, measured against its true shading normals (docs/perception.md): on the
/// sphere the outline's normals are edge-on to within n_z = 0.19 (the pixel centres lie half a
/// pixel inside the limb) and point along the mask's contour normal to within 2°; on the bunny
/// they face the viewer by n_z = 0.24 on average, above 0.5 for a tenth of the outline, and
/// their in-plane direction is 4.5° off the contour normal (median; 27° at the 90th
/// percentile), so the rim's brightness mixes the light with an unknown turn toward the viewer.
/// The turn is the bunny's shape sampled half a pixel inside its limb, not its coarse mesh's
/// interpolated normals: a pixel centre a distance δ inside the limb of a cross-section of
/// radius R has n_z ≈ √(2δ/R), so rendered 4 times finer (512²) the outline's mean n_z halves,
/// on the sphere and on the bunny alike (a mesh artefact would stay). The limb still holds the
/// answer: with the true normals of the same lit outline pixels, a least-squares fit I = g·n
/// recovers the light.
#[test]
fn the_bunny_outline_is_not_edge_on() {
    use shadelab_engine::boundary::occluding_normals;
    // (mean n_z, share above 0.5, median and 90th-percentile angle to the contour normal).
    let outline = |name: &str, tilt: f64, slant: f64, ppd: f64| {
        let light = format!("light=tilt={tilt},slant={slant}");
        let given = shadelab::Params::parse_pairs(&[&light, "ambient=0", "albedo=0.8"]).unwrap();
        let size = SizeRequest {
            visual_size: Some((8.0, 8.0)),
            ppd: Some(ppd),
            shape: None,
        };
        let (_, output) = stimulus::generate(name, &given, &size, 1, 1 << 24).unwrap();
        let image = output.pixels.luminance();
        let truth = output.surface.expect("a rendered surface has its normals");
        let contour = occluding_normals(&truth.mask);
        let mut nz = Vec::new();
        let mut angles = Vec::new();
        let (mut ata, mut atb) = (nalgebra::Matrix3::zeros(), nalgebra::Vector3::zeros());
        for (k, c) in contour.data().iter().enumerate() {
            let Some(c) = c else { continue };
            let n = truth.normals.data()[k];
            nz.push(n.z);
            let along = (n.x * c.x + n.y * c.y) / n.x.hypot(n.y);
            angles.push(along.clamp(-1.0, 1.0).acos().to_degrees());
            if image.data()[k] > 0.0 {
                ata += n * n.transpose();
                atb += n * image.data()[k];
            }
        }
        angles.sort_by(f64::total_cmp);
        let g = ata.try_inverse().unwrap() * atb;
        let fitted = (
            (-g.x).atan2(g.y).to_degrees(),
            g.x.hypot(g.y).atan2(g.z).to_degrees(),
        );
        let count = nz.len() as f64;
        let mean = nz.iter().sum::<f64>() / count;
        let above = nz.iter().filter(|&&z| z > 0.5).count() as f64 / count;
        let max = nz.iter().copied().fold(0.0, f64::max);
        let median = angles[angles.len() / 2];
        let p90 = angles[angles.len() * 9 / 10];
        (mean, above, max, median, p90, fitted)
    };
    let (sphere_mean, above, max, median, p90, _) = outline("sphere", 0.0, 30.0, 16.0);
    assert!(above == 0.0 && max < 0.2 && median < 1.0 && p90 < 2.0);
    let (mean, above, _, median, p90, (tilt, slant)) = outline("bunny", 135.0, 30.0, 16.0);
    assert!((0.2..0.3).contains(&mean), "{mean}");
    assert!((0.08..0.12).contains(&above), "{above}");
    assert!((3.0..6.0).contains(&median) && p90 > 20.0, "{median} {p90}");
    assert!(
        tilt_error(tilt, 135.0) < 0.5 && (slant - 30.0).abs() < 0.5,
        "{tilt} {slant}"
    );
    // Four times finer (512²): n_z ≈ √(2δ/R) with δ and R in pixels halves, on both.
    for (name, coarse) in [("sphere", sphere_mean), ("bunny", mean)] {
        let (fine, ..) = outline(name, 135.0, 30.0, 64.0);
        let ratio = fine / coarse;
        assert!((0.4..0.6).contains(&ratio), "{name}: {coarse} -> {fine}");
    }
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
    assert_eq!(e.method, EstimateMethod::LimbBand);
    assert!(e.limb_pixels >= 16 && e.tilt_se_deg < 5.0, "{e:?}");
}

mod hollow {
    use shadelab::pipeline::observer::{LightPrior, ObserverOptions};
    use shadelab::pipeline::prior_sweep::Sweep;
    use shadelab_analysis::analysis::observer::observe;

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

/// The hollow mask with `background`, framed `w`×`h` degrees at 10 ppd, as the perception
/// pipeline loads it with `domain` (the default: [`DomainSpec::Auto`]), slant 45°.
fn hollow_setup(w: f64, h: f64, background: &str, domain: DomainSpec) -> perception::Setup {
    let ppd = 10.0;
    let source = PictureSource {
        stimulus: Some("hollow-mask".into()),
        params: shadelab::Params::parse_pairs(&[&format!("background={background}")]).unwrap(),
        ppd: Some(ppd),
        max_pixels: 1 << 24,
        ..Default::default()
    };
    let mut config = perception::Config::new(source);
    config.size = Some(((h * ppd) as usize, (w * ppd) as usize));
    config.domain = domain;
    config.load(&NoProgress).unwrap()
}

/// The hollow face lit from above (light from tilt 0°, slant 45°), framed `w`×`h` degrees
/// (10 ppd, the face 5° wide) on each background (black, the default 0.1, mid grey). By
/// default the perception pipeline solves it on the face's region (the backdrop is no part of
/// the surface): seen hollow without a familiar-shape prior (P(convex) < 0.1, the light from
/// above, the most probable light the true one, 0°) and convex lit from below with it (B = 7:
/// P(convex) > 0.9, the most probable light at 180°, the true light's mirror), with the same
/// numbers for every framing and background. Solved over the whole picture (`domain image`),
/// the backdrop a surface too, the reading keeps its sign, but the backdrop pulls the most
/// probable light up to 60° off the true one.
fn hollow_mask_reads_the_same(w: f64, h: f64) {
    let tilts: Vec<f64> = (0..12).map(|i| i as f64 * 30.0).collect();
    let mut face_readings = Vec::new();
    for bg in ["0", "0.1", "0.5"] {
        for domain in [DomainSpec::Auto, DomainSpec::Named(Domain::Image)] {
            let setup = hollow_setup(w, h, bg, domain.clone());
            let on_face = domain == DomainSpec::Auto;
            // The default is the face's region, and the report says so.
            let face = setup.picture.domain(Domain::Tokens);
            assert_eq!(setup.domain == face, on_face, "{bg} {domain}");
            let used = if on_face { "tokens" } else { "image" };
            assert_eq!(setup.parameters.domain, used);
            let s = setup.sweep(&tilts, &NoProgress, "sweep").unwrap();
            let above = s.interpretations[0].tokens[0].convexity;
            let below = s.interpretations[6].tokens[0].convexity;
            let plain = hollow::percept(&s, 0.0);
            let familiar = hollow::percept(&s, 7.0);
            println!(
                "{w}x{h}° background {bg} domain {used}: c above {above:+.4}, below {below:+.4}; \
                 B = 0: P(convex) {:.3}, P(above) {:.3}, MAP {}°; B = 7: {:.3}, {:.3}, {}°",
                plain.0, plain.1, plain.2, familiar.0, familiar.1, familiar.2
            );
            assert!(above < -0.004 && below > 0.004, "{bg} {used}");
            assert!(
                familiar.0 > 0.9 && familiar.1 < 0.1,
                "{bg} {used}: {familiar:?}"
            );
            if on_face {
                assert!(above < -0.01, "{bg}");
                // The most probable light is the true one (0°) without the prior and its
                // mirror (180°) with it, to the sweep's step.
                assert!(
                    plain.0 < 0.1 && plain.1 > 0.9 && plain.2 == 0.0,
                    "{bg}: {plain:?}"
                );
                assert_eq!(familiar.2, 180.0, "{bg}");
                face_readings.push((plain.0, familiar.0));
            } else {
                assert!(plain.0 < 0.2 && plain.1 > 0.8, "{bg}: {plain:?}");
                assert!(tilt_error(plain.2, 0.0) <= 60.0, "{bg}: {plain:?}");
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

/// The default domain is the targets only where they are objects on a backdrop: a rendered
/// object (and the hollow mask, above), not a relief on a panel, whose targets are regions of
/// one surface; targets given by the caller say nothing of a backdrop.
#[test]
fn the_default_domain_is_the_targets_of_an_object_on_a_backdrop_only() {
    let load = |name: &str, labels: Option<shadelab::Labels>| {
        let source = PictureSource {
            stimulus: Some(name.into()),
            ppd: Some(8.0),
            labels,
            max_pixels: 1 << 24,
            ..Default::default()
        };
        perception::Config::new(source).load(&NoProgress).unwrap()
    };
    for (name, used) in [
        ("sphere", "tokens"),
        ("vase", "tokens"),
        ("bumps", "image"),
        ("crater", "image"),
    ] {
        let setup = load(name, None);
        assert_eq!(setup.parameters.domain, used, "{name}");
        let whole = setup.domain.data().iter().all(|&m| m);
        assert_eq!(whole, used == "image", "{name}");
    }
    let sphere = load("sphere", None);
    let (w, h) = (sphere.domain.width(), sphere.domain.height());
    let given = load("sphere", Some(sphere.domain.map(|&m| u16::from(m))));
    assert_eq!(given.parameters.domain, "image");
    assert_eq!(given.domain.count(), w * h);
}
