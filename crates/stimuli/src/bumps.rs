//! Shaded discs on a grey panel: `bumps` (light from above: bumps and dimples, Ramachandran
//! 1988) and `sideways` (light from the left or right: every disc is bistable).
//!
//! The panel and its discs are one heightfield rendered under one light: a plane with
//! hemispherical or Gaussian bumps (and their negatives, dimples), Lambertian, with the albedo
//! chosen so that the flat panel has exactly the `background` luminance:
//! L = background · max(0, n·s) / s_z. The `linear` profile draws Ramachandran's linear
//! luminance gradient instead, L = background · (1 ± contrast · t), t running from −1 to 1
//! across the disc toward the light; its layers are the hemisphere that gradient depicts (a
//! hemisphere's n_x, n_y are exactly linear in position).
//!
//! Disc centres are snapped to pixel corners, so every disc covers the same pixel pattern and
//! is mirror-symmetric on the pixel lattice.

use super::frame::grid_centres;
use super::{Output, Pixels, Stimulus, SurfaceLayers, Targets, Typed};
use crate::error::{Error, Result};
use crate::grid::Grid;
use crate::light::Light;
use crate::params::{param_choice, stimulus_params, ParamSet};
use crate::random::SplitMix64;
use crate::visual_size::Geometry;
use nalgebra::Vector3;
use serde_json::{json, Map};

param_choice! {
    /// The profile of a disc of [`bumps`] and [`sideways`].
    pub enum DiscProfile {
        /// A rendered hemisphere.
        Hemisphere = "hemisphere",
        /// A rendered Gaussian.
        Gaussian = "gaussian",
        /// Ramachandran's linear luminance gradient.
        Linear = "linear",
    }
}

param_choice! {
    /// Which discs of [`bumps`] and [`sideways`] are bumps and which dimples.
    pub enum DiscPattern {
        /// At random (seeded).
        Random = "random",
        /// A checkerboard of bumps and dimples.
        Alternate = "alternate",
        /// Rows of bumps and rows of dimples.
        Rows = "rows",
        /// All bumps.
        Bumps = "bumps",
        /// All dimples.
        Dimples = "dimples",
    }
}

stimulus_params! {
    /// The discs shared by [`bumps`] and [`sideways`].
    pub struct DiscArrayParams {
        /// disc profile: a rendered hemisphere or Gaussian, or a linear luminance gradient
        profile: DiscProfile = DiscProfile::Hemisphere;
        /// disc radius (deg)
        radius: f64 = 1.0, range 0.01..=90.0;
        /// centre-to-centre distance (deg)
        spacing: f64 = 3.0, range 0.01..=180.0;
        /// rows of discs
        rows: usize = 3, range 1..=50;
        /// columns of discs
        columns: usize = 4, range 1..=50;
        /// which discs are bumps and which dimples (random uses the seed)
        pattern: DiscPattern = DiscPattern::Random;
        /// peak height as a fraction of the radius (hemisphere) or of sigma (gaussian)
        height: f64 = 1.0, range 0.01..=10.0;
        /// Gaussian standard deviation as a fraction of the radius
        sigma: f64 = 0.35, range 0.05..=5.0;
        /// gradient amplitude relative to the background (linear profile)
        contrast: f64 = 0.5, range 0.0..=1.0;
        /// luminance of the panel
        background: f64 = 0.5, range 0.0..=1.0;
    }
}

stimulus_params! {
    /// Parameters of [`bumps`].
    ///
    /// ```
    /// use shadelab::{ParamSet, Params};
    /// use shadelab::stimulus::BumpsParams;
    ///
    /// let p = BumpsParams::default();
    /// assert_eq!(p.discs.radius, 1.0);
    /// assert_eq!((p.discs.rows, p.discs.columns), (3, 4));
    /// // Built from key=value pairs: a value out of range names the key and the range.
    /// let given = Params::parse_pairs(&["radius=100"]).unwrap();
    /// let e = BumpsParams::from_map(&given).unwrap_err().to_string();
    /// assert!(e.contains("radius") && e.contains("0.01..90"), "{e}");
    /// // The declarations are what `describe bumps` lists, in order.
    /// let names: Vec<_> = BumpsParams::specs().iter().map(|s| s.name).collect();
    /// assert_eq!(names[..2], ["profile", "radius"]);
    /// assert_eq!(names.last(), Some(&"light"));
    /// ```
    pub struct BumpsParams {
        /// the discs
        flatten discs: DiscArrayParams {};
        /// light direction (x,y,z | tilt=T,slant=S | name)
        light: Light = "above";
    }
}

param_choice! {
    /// The side a light comes from.
    pub enum LightSide {
        /// From the left (tilt 90°).
        Left = "left",
        /// From the right (tilt −90°).
        Right = "right",
    }
}

stimulus_params! {
    /// Parameters of [`sideways`].
    pub struct SidewaysParams {
        /// the discs
        flatten discs: DiscArrayParams { rows: 2, pattern: DiscPattern::Rows };
        /// where the light comes from
        side: LightSide = LightSide::Left;
        /// light slant from the line of sight (deg)
        slant: f64 = 45.0, range 0.0..=89.0;
    }
}

/// Discs shaded as bumps and dimples under one light (the light-from-above prior).
///
/// ```
/// use shadelab::stimulus::{bumps, BumpsParams, Pixels};
/// use shadelab::Geometry;
///
/// let mut p = BumpsParams::default();
/// (p.discs.rows, p.discs.columns) = (1, 1);
/// let g = Geometry { width: 40, height: 40, ppd: 10.0 };
/// let out = bumps(&p, &g, 0).unwrap();
/// let Pixels::Gray(image) = out.pixels else { panic!() };
/// // Outside the disc the panel has exactly the background luminance.
/// assert_eq!(*image.get(0, 0), p.discs.background);
/// ```
pub fn bumps(p: &BumpsParams, g: &Geometry, seed: u64) -> Result<Output> {
    p.validate()?;
    discs("bumps", &p.discs, g, seed, p.light)
}

/// Discs lit from the left or right: bump or dimple is ambiguous (bistable).
pub fn sideways(p: &SidewaysParams, g: &Geometry, seed: u64) -> Result<Output> {
    p.validate()?;
    let tilt = match p.side {
        LightSide::Left => 90.0,
        LightSide::Right => -90.0,
    };
    let light = Light::from_tilt_slant(tilt, p.slant)?;
    discs("sideways", &p.discs, g, seed, light)
}

/// Bump (+1) or dimple (−1) for each disc, in reading order.
fn polarities(pattern: DiscPattern, rows: usize, cols: usize, seed: u64) -> Vec<f64> {
    let mut rng = SplitMix64::new(seed);
    (0..rows * cols)
        .map(|i| {
            let (r, c) = (i / cols, i % cols);
            let bump = match pattern {
                DiscPattern::Random => rng.next_u64() >> 63 == 0,
                DiscPattern::Alternate => (r + c) % 2 == 0,
                DiscPattern::Rows => r % 2 == 0,
                DiscPattern::Dimples => false,
                DiscPattern::Bumps => true,
            };
            if bump {
                1.0
            } else {
                -1.0
            }
        })
        .collect()
}

fn discs(name: &str, p: &DiscArrayParams, g: &Geometry, seed: u64, light: Light) -> Result<Output> {
    let radius = g.px(p.radius);
    let spacing = g.px(p.spacing);
    let (rows, cols) = (p.rows, p.columns);
    let profile = p.profile;
    let linear = profile == DiscProfile::Linear;
    let (height, sigma) = (p.height, p.sigma * radius);
    let (contrast, background) = (p.contrast, p.background);
    if radius < 1.0 {
        return Err(Error::invalid(format!(
            "{name}: radius {}° is under one pixel at {} ppd",
            p.radius, g.ppd
        )));
    }
    if (rows > 1 || cols > 1) && spacing < 2.0 * radius {
        return Err(Error::invalid(format!(
            "{name}: spacing {}° is less than the disc diameter {}°: discs would overlap",
            p.spacing,
            2.0 * p.radius
        )));
    }
    let centres = grid_centres(g, rows, cols, spacing);
    g.check_inside(
        &format!("{name}: {rows} rows × {cols} columns of discs"),
        &centres,
        radius,
    )?;
    let sign = polarities(p.pattern, rows, cols, seed);
    let s = light.direction();
    let tilt_len = s.x.hypot(s.y);
    if linear && tilt_len < 1e-9 {
        return Err(Error::invalid(format!(
            "{name}: the linear profile needs a light with a direction in the image (slant > 0)"
        )));
    }
    if !linear && s.z < 1e-6 {
        return Err(Error::invalid(format!(
            "{name}: a grazing light (slant 90°) leaves the panel dark; use a slant below 90°"
        )));
    }
    if linear && background * (1.0 + contrast) > 1.0 {
        return Err(Error::invalid(format!(
            "{name}: background {background} × (1 + contrast {contrast}) exceeds 1; lower one of them"
        )));
    }
    let albedo = background / s.z;
    let (dx, dy) = (s.x / tilt_len.max(1e-300), s.y / tilt_len.max(1e-300));
    let (w, h) = (g.width, g.height);
    let mut depth = Grid::new(w, h, 0.0);
    let mut normals = Grid::new(w, h, Vector3::z());
    let mut labels = Grid::new(w, h, 0u16);
    let mut image = Grid::new(w, h, background);
    let mut names = Vec::with_capacity(centres.len());
    for (i, (&(cx, cy), &sg)) in centres.iter().zip(&sign).enumerate() {
        let kind = if sg > 0.0 { "bump" } else { "dimple" };
        names.push(format!("{kind} r{}c{}", i / cols + 1, i % cols + 1));
        let label = u16::try_from(i + 1).map_err(|_| Error::invalid("too many discs"))?;
        for row in g.rows(cy - radius, cy + radius) {
            for col in g.cols(cx - radius, cx + radius) {
                let (x, y) = (g.x(col) - cx, g.y(row) - cy);
                let rho2 = x * x + y * y;
                if rho2 >= radius * radius {
                    continue;
                }
                let (z, n) = match profile {
                    DiscProfile::Gaussian => {
                        let z = height * sigma * (-rho2 / (2.0 * sigma * sigma)).exp();
                        let k = z / (sigma * sigma);
                        (z, Vector3::new(sg * k * x, sg * k * y, 1.0).normalize())
                    }
                    DiscProfile::Linear => {
                        let root = (radius * radius - rho2).sqrt();
                        (root, Vector3::new(sg * x, sg * y, root).normalize())
                    }
                    DiscProfile::Hemisphere => {
                        let root = (radius * radius - rho2).sqrt();
                        (
                            height * root,
                            Vector3::new(sg * height * x, sg * height * y, root).normalize(),
                        )
                    }
                };
                *depth.get_mut(col, row) = sg * z;
                *normals.get_mut(col, row) = n;
                *labels.get_mut(col, row) = label;
                *image.get_mut(col, row) = if linear {
                    background * (1.0 + contrast * sg * (x * dx + y * dy) / radius)
                } else {
                    albedo * n.dot(&s).max(0.0)
                };
            }
        }
    }
    if !linear {
        let peak = image.data().iter().fold(0.0f64, |a, &b| a.max(b));
        if peak > 1.0 {
            return Err(Error::invalid(format!(
                "{name}: the brightest facet reaches {peak:.3} > 1 (background {background} / cos(slant {:.1}°)); lower the background or the light's slant",
                light.slant_deg()
            )));
        }
    }
    let shading = if linear {
        image.clone()
    } else {
        normals.map(|n| n.dot(&s).max(0.0))
    };
    let mut notes = Map::new();
    notes.insert("light_vector".into(), json!([s.x, s.y, s.z]));
    if !linear {
        notes.insert("albedo".into(), json!(albedo));
    }
    notes.insert(
        "bumps".into(),
        json!(sign.iter().filter(|&&v| v > 0.0).count()),
    );
    notes.insert(
        "dimples".into(),
        json!(sign.iter().filter(|&&v| v < 0.0).count()),
    );
    notes.insert(
        "centres_px".into(),
        json!(centres
            .iter()
            .map(|&(x, y)| g.svg_xy(x, y))
            .map(|(x, y)| [x, y])
            .collect::<Vec<_>>()),
    );
    Ok(Output {
        pixels: Pixels::Gray(image),
        targets: Some(Targets { labels, names }),
        surface: Some(SurfaceLayers {
            depth,
            normals,
            mask: Grid::new(w, h, true),
            albedo: None,
            shading: Some(shading),
        }),
        svg: None,
        notes,
    })
}

/// The disc stimuli.
pub fn all() -> Vec<Box<dyn Stimulus>> {
    vec![
        Typed::boxed(
            "bumps",
            "discs shaded as bumps and dimples under one light (light-from-above prior)",
            (10.0, 14.0),
            32.0,
            bumps,
        ),
        Typed::boxed(
            "sideways",
            "discs lit from the left or right: bump or dimple is ambiguous (bistable)",
            (7.0, 14.0),
            32.0,
            sideways,
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Params;
    use crate::visual_size::Geometry;
    use crate::Request;

    fn stim(name: &str) -> Box<dyn Stimulus> {
        crate::find(name).unwrap()
    }

    fn request(s: &dyn Stimulus, pairs: &[&str], ppd: f64) -> Request {
        let info = s.info();
        let given = Params::parse_pairs(pairs).unwrap();
        let (h, w) = info.default_visual_size;
        Request {
            params: Params::resolve(&info.params, &given).unwrap(),
            geometry: Geometry {
                width: (w * ppd).round() as usize,
                height: (h * ppd).round() as usize,
                ppd,
            },
            seed: 1,
        }
    }

    fn halves(out: &Output, label: u16) -> (f64, f64) {
        let (Pixels::Gray(img), Some(t)) = (&out.pixels, &out.targets) else {
            panic!("gray with targets expected")
        };
        let rows: Vec<usize> = (0..img.height())
            .filter(|&r| (0..img.width()).any(|c| *t.labels.get(c, r) == label))
            .collect();
        let mid = (rows[0] + rows[rows.len() - 1]).div_ceil(2);
        let (mut top, mut bottom) = (0.0, 0.0);
        for r in rows {
            for c in 0..img.width() {
                if *t.labels.get(c, r) == label {
                    if r < mid {
                        top += img.get(c, r);
                    } else {
                        bottom += img.get(c, r);
                    }
                }
            }
        }
        (top, bottom)
    }

    #[test]
    fn bumps_lit_from_above_are_bright_on_top_and_dimples_below() {
        for profile in DiscProfile::NAMES {
            let r = request(
                stim("bumps").as_ref(),
                &[&format!("profile={profile}"), "pattern=alternate"],
                16.0,
            );
            let out = stim("bumps").generate(&r).unwrap();
            let names = &out.targets.as_ref().unwrap().names;
            for (i, name) in names.iter().enumerate() {
                let (top, bottom) = halves(&out, i as u16 + 1);
                if name.starts_with("bump") {
                    assert!(top > 1.2 * bottom, "{profile} {name}: {top} vs {bottom}");
                } else {
                    assert!(bottom > 1.2 * top, "{profile} {name}: {top} vs {bottom}");
                }
            }
        }
    }

    #[test]
    fn the_panel_has_the_background_luminance_and_bumps_match_a_rendered_hemisphere() {
        let r = request(
            stim("bumps").as_ref(),
            &["background=0.4", "pattern=bumps"],
            16.0,
        );
        let out = stim("bumps").generate(&r).unwrap();
        let Pixels::Gray(img) = &out.pixels else {
            panic!()
        };
        let t = out.targets.as_ref().unwrap();
        let layers = out.surface.as_ref().unwrap();
        let s = "tilt=0,slant=45".parse::<Light>().unwrap().direction();
        for (i, &v) in img.data().iter().enumerate() {
            if t.labels.data()[i] == 0 {
                assert_eq!(v, 0.4);
            } else {
                let n = layers.normals.data()[i];
                assert!((v - 0.4 * n.dot(&s).max(0.0) / s.z).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn sideways_rows_are_mirror_images() {
        let r = request(
            stim("sideways").as_ref(),
            &["rows=2", "columns=1", "pattern=rows"],
            16.0,
        );
        let out = stim("sideways").generate(&r).unwrap();
        let Pixels::Gray(img) = &out.pixels else {
            panic!()
        };
        let t = out.targets.as_ref().unwrap();
        // Disc 2 (a dimple lit from the left) is disc 1 (a bump) mirrored left-right.
        let px = |label: u16| -> Vec<f64> {
            (0..img.height())
                .flat_map(|r| (0..img.width()).map(move |c| (c, r)))
                .filter(|&(c, r)| *t.labels.get(c, r) == label)
                .map(|(c, r)| *img.get(c, r))
                .collect()
        };
        let (a, b) = (px(1), px(2));
        assert_eq!(a.len(), b.len());
        let side = (a.len() as f64).sqrt().round() as usize;
        assert!(side > 10);
        let w = img.width();
        let row_of = |label: u16| {
            (0..img.height())
                .find(|&r| (0..w).any(|c| *t.labels.get(c, r) == label))
                .unwrap()
        };
        let (r1, r2) = (row_of(1), row_of(2));
        for dr in 0..10 {
            for c in 0..w {
                assert_eq!(img.get(c, r1 + dr), img.get(w - 1 - c, r2 + dr));
            }
        }
    }

    #[test]
    fn bad_layouts_are_one_line_errors() {
        let r = request(stim("bumps").as_ref(), &["spacing=1"], 16.0);
        assert!(stim("bumps")
            .generate(&r)
            .unwrap_err()
            .to_string()
            .contains("overlap"));
        let r = request(stim("bumps").as_ref(), &["rows=20"], 16.0);
        assert!(stim("bumps")
            .generate(&r)
            .unwrap_err()
            .to_string()
            .contains("enlarge"));
        let r = request(
            stim("bumps").as_ref(),
            &["background=0.9", "light=tilt=0,slant=70"],
            16.0,
        );
        assert!(stim("bumps")
            .generate(&r)
            .unwrap_err()
            .to_string()
            .contains("slant"));
    }
}
