//! The outline analysis as a pipeline (`shadelab analyze outline`): for each target (a strip
//! cut by an outline), the shape its outline implies, the shading that shape predicts under
//! the light, and the split of the picture into what the shape explains and what is left over
//! as paint (Knill & Kersten 1991; see [`crate::analysis::outline`]).
//!
//! Per target: the outline's profile gives every column's normal; under the light (given, or
//! fitted in the plane of the profile) the albedo and an offset are fitted by least squares,
//! and `shape_explained` is the share of the target's luminance variance that shape explains.
//! The remainder is the paint layer. The engine then reconstructs the strip from the explained
//! shading (the shape layer) with the outline's normals held on the cut, once with the
//! crease-preserving smoothness ([`crate::solver::crease`], Charbonnier) and once with Horn's
//! quadratic smoothness, and the bend concentration of each reconstruction says whether its
//! bending sits at folds (near 1) or is spread (about 0.3).

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::outline::{ProfileFit, ShadingFit};

use super::source::{PictureInfo, PictureSource};
use super::CommandReport;
use crate::analysis::convexity::Token;
use crate::analysis::outline::{
    curvature_concentration, fit_shading, outline_conditions, outline_profile, Profile,
    TOP_FRACTION,
};
use crate::analysis::TokenPicture;
use crate::boundary::BoundaryConditions;
use crate::colormap::Colormap;
use crate::error::{Error, Result};
use crate::gradient_space::normal_from_fg;
use crate::grid::{Grid, Image, Mask};
use crate::io::{self, csv_field, Stamp};
use crate::light::FrontLight;
use crate::parallel::prelude::*;
use crate::plot::{ColourBar, MapFigure};
use crate::progress::Progress;
use crate::reflectance::Lambertian;
use crate::solver::crease::{self, CreaseOptions, CreaseSolution, Smoothness};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// The table's file name.
pub const CSV_FILE: &str = "outline.csv";

/// The colour of pixels outside the target in the gray pictures (linear RGB): a muted blue
/// that no gray level is.
const OUTSIDE: [f64; 3] = [0.12, 0.2, 0.4];

/// Pixels of margin around a target in its pictures.
const MARGIN: usize = 3;

/// What to analyse, as plain values.
#[derive(Debug, Clone)]
pub struct OutlineConfig {
    /// The picture; its targets (a stimulus's own, or a label mask) are the strips.
    pub source: PictureSource,
    /// The rendered stimulus's size in pixels (height, width); only with a stimulus.
    pub size: Option<(usize, usize)>,
    /// The light; `None`: fitted per target in the plane of its profile.
    pub light: Option<FrontLight>,
    /// How the outline's profile is read.
    pub profile: ProfileFit,
    /// The crease-preserving reconstruction's settings (its smoothness is the one compared
    /// with Horn's).
    pub crease: CreaseOptions,
    /// Start the reconstructions from the outline's shape (true) or from a flat surface: the
    /// same fixed point on the gallery's strips, reached in about half the sweeps.
    pub warm_start: bool,
}

impl OutlineConfig {
    /// The defaults for `source`: the light fitted, [`ProfileFit::default`],
    /// [`CreaseOptions::default`] with shadowed pixels filled along their column (the strip's
    /// generators), a warm start.
    pub fn new(source: PictureSource) -> OutlineConfig {
        OutlineConfig {
            source,
            size: None,
            light: None,
            profile: ProfileFit::default(),
            crease: CreaseOptions {
                shadow_along_columns: true,
                ..CreaseOptions::default()
            },
            warm_start: true,
        }
    }

    /// Checks everything that needs no file.
    pub fn validate(&self) -> Result<()> {
        self.source.check()?;
        if let Some((h, w)) = self.size {
            if self.source.stimulus.is_none() {
                return Err(Error::invalid("a size applies to a rendered stimulus only"));
            }
            if w == 0 || h == 0 {
                return Err(Error::invalid(format!(
                    "size {} must be at least 1 pixel each way",
                    crate::message::SizeText::Pixels(h, w)
                )));
            }
        }
        self.profile.validate()?;
        self.crease.validate()
    }
}

/// One target's reading.
#[derive(Debug, Clone, Serialize)]
pub struct TargetReading {
    /// Its label.
    pub label: u16,
    /// Its name.
    pub name: String,
    /// The stem of its pictures' file names.
    pub stem: String,
    /// How many pixels it has.
    pub pixels: usize,
    /// How many columns its profile spans.
    pub columns: usize,
    /// The relief of the outline's shape, max z − min z (pixels × depth scale).
    pub relief: f64,
    /// The light and the fitted albedo and offset.
    pub shading: ShadingFit,
    /// The light's tilt, degrees (0 = from above, +90 = from the left).
    pub light_tilt_deg: f64,
    /// The light's slant, degrees.
    pub light_slant_deg: f64,
    /// The share of the target's luminance variance the outline's shape explains.
    pub shape_explained: f64,
    /// The root-mean-square paint (I − Î) over the target.
    pub paint_rms: f64,
    /// The bend concentration of the outline's profile itself (the reference).
    pub outline_bend_concentration: f64,
    /// The bend concentration of the crease-preserving reconstruction.
    pub bend_concentration: f64,
    /// The bend concentration of the reconstruction with Horn's quadratic smoothness.
    pub bend_concentration_quadratic: f64,
    /// Sweeps of the crease-preserving reconstruction.
    pub sweeps: usize,
    /// Whether it converged.
    pub converged: bool,
    /// Sweeps of the quadratic one.
    pub sweeps_quadratic: usize,
    /// Whether that converged.
    pub converged_quadratic: bool,
    /// The pictures: the shape (normal x-component), the predicted shading and the paint.
    #[serde(skip)]
    pub layers: Layers,
}

/// One target's pictures, each cropped around it.
#[derive(Debug, Clone)]
pub struct Layers {
    /// The crease-preserving reconstruction's normal x-component, −1..1 (0 outside).
    pub shape: Image,
    /// The shading the outline's shape predicts, Î.
    pub shading: Image,
    /// The paint layer: the target's mean luminance plus the remainder I − Î.
    pub paint: Image,
    /// The target's pixels.
    pub inside: Mask,
    /// The crop's left column and top row in the picture.
    pub origin: (usize, usize),
    /// The picture's height, for the y axis.
    pub picture_height: usize,
}

/// What the outline analysis found; serialised, it is `outline.json`.
#[derive(Debug, Clone, Serialize)]
pub struct OutlineReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The conventions, where the picture came from and its size.
    #[serde(flatten)]
    pub picture: PictureInfo,
    /// The light as given, or `null` when fitted per target.
    pub light: Option<FrontLight>,
    /// How the profiles were read.
    pub profile: ProfileFit,
    /// The reconstructions' λ.
    pub lambda: f64,
    /// The crease-preserving smoothness's ε.
    pub crease_epsilon: f64,
    /// What each measure means.
    pub measures: BTreeMap<&'static str, &'static str>,
    /// One reading per target.
    pub targets: Vec<TargetReading>,
    /// The files written and what they hold.
    pub outputs: BTreeMap<String, String>,
    /// Seconds the run took.
    pub seconds: f64,
}

/// Runs the analysis: loads the picture, reads every target (one progress step each).
///
/// ```no_run
/// use shadelab::pipeline::outline::{run, OutlineConfig};
/// use shadelab::pipeline::PictureSource;
/// use shadelab::NoProgress;
///
/// let source = PictureSource {
///     stimulus: Some("boundary-strips".into()),
///     max_pixels: 1 << 24,
///     ..Default::default()
/// };
/// let report = run(&OutlineConfig::new(source), &NoProgress).unwrap();
/// for t in &report.targets {
///     println!("{}: {:.3} {:.3}", t.name, t.shape_explained, t.bend_concentration);
/// }
/// ```
pub fn run(config: &OutlineConfig, progress: &dyn Progress) -> Result<OutlineReport> {
    let started = Instant::now();
    config.validate()?;
    let (loaded, _) = config.source.load_shaped(false, config.size)?;
    loaded.say_notes(progress);
    let Some((labels, names)) = loaded.labels.as_ref() else {
        return Err(Error::invalid(
            "the picture has no targets: the outline analysis reads each target (label 1..N of a target mask) as a strip cut by an outline",
        ));
    };
    let picture = TokenPicture::from_image(loaded.luminance(), Some((labels, names.as_slice())))?;
    let (w, h) = (picture.image.width(), picture.image.height());
    progress.start(picture.tokens.len() as u64, "outline");
    // Every target's two reconstructions are independent: they run side by side, each one
    // sequential, so the results are the same bits for any number of threads.
    let setups = picture
        .tokens
        .iter()
        .map(|token| set_up_target(&picture.image, token, config))
        .collect::<Result<Vec<_>>>()?;
    let jobs: Vec<(usize, Smoothness)> = (0..setups.len())
        .flat_map(|k| [(k, config.crease.smoothness), (k, Smoothness::Quadratic)])
        .collect();
    let solved = jobs
        .par_iter()
        .map(|&(k, smoothness)| {
            let solution = setups[k].reconstruct(smoothness, config);
            if smoothness == Smoothness::Quadratic {
                progress.advance(1);
            }
            solution
        })
        .collect::<Vec<Result<CreaseSolution>>>();
    let mut solved = solved.into_iter();
    let mut targets: Vec<TargetReading> = Vec::new();
    for (setup, token) in setups.into_iter().zip(&picture.tokens) {
        let (Some(tv), Some(quadratic)) = (solved.next(), solved.next()) else {
            return Err(Error::Compute(
                "a target's reconstruction is missing".into(),
            ));
        };
        let mut reading = setup.reading(token, w, h, &tv?, &quadratic?);
        if targets.iter().any(|t| t.stem == reading.stem) {
            reading.stem = format!("{}-{}", reading.stem, token.label);
        }
        targets.push(reading);
    }
    progress.finish();
    let mut outputs = BTreeMap::from([
        (
            CSV_FILE.to_string(),
            "one row per target: the light, albedo and offset, shape_explained, paint_rms, bend_concentration (crease-preserving) and bend_concentration_quadratic (Horn)".to_string(),
        ),
        (
            OutlineReport::MARKER.to_string(),
            "this report".to_string(),
        ),
    ]);
    for t in &targets {
        outputs.insert(
            format!("{}-shape.png", t.stem),
            format!(
                "{}: the crease-preserving reconstruction's normal x-component",
                t.name
            ),
        );
        outputs.insert(
            format!("{}-shading.png", t.stem),
            format!("{}: the shading the outline's shape predicts", t.name),
        );
        outputs.insert(
            format!("{}-paint.png", t.stem),
            format!(
                "{}: the paint layer (mean luminance + what the shape leaves)",
                t.name
            ),
        );
    }
    let smoothness_epsilon = match config.crease.smoothness {
        Smoothness::Charbonnier { epsilon } => epsilon,
        Smoothness::Quadratic => 0.0,
    };
    // Said once the run succeeded: a refusal stays one line.
    loaded
        .input_note
        .iter()
        .for_each(|line| progress.note(line));
    Ok(OutlineReport {
        stamp: Stamp::of("analyze outline"),
        picture: PictureInfo::new(&loaded.origin, w, h),
        light: config.light,
        profile: config.profile,
        lambda: config.crease.lambda,
        crease_epsilon: smoothness_epsilon,
        measures: BTreeMap::from([
            ("shape_explained", "1 - sum (I - Ihat)^2 / sum (I - mean I)^2 over the target, Ihat = offset + albedo * max(0, n.s) with n from the outline's profile"),
            ("paint_rms", "root-mean-square of I - Ihat over the target"),
            ("bend_concentration", "share of the column-to-column change of the column-mean f carried by the 20% of columns that change most, on the reconstruction from the shape layer with the outline's normals on the cut"),
        ]),
        targets,
        outputs,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// One target's outline reading before its reconstructions: the profile, the shading fit
/// and what the reconstructions start from.
struct TargetSetup {
    /// The outline's profile.
    profile: Profile,
    /// The shading fit.
    fit: ShadingFit,
    /// The target's luminances, in the order of its pixels.
    values: Vec<f64>,
    /// The predicted shading Î at the target's pixels, in the same order.
    predicted: Vec<f64>,
    /// Î on the whole grid (0 outside the target): the reconstructions' data.
    shading: Image,
    /// The outline's boundary conditions.
    bc: BoundaryConditions,
    /// The outline's f in every target pixel (0 outside): the reconstructions' start.
    start_f: Image,
}

/// Fits the target's outline and shading (everything but the reconstructions).
fn set_up_target(image: &Image, token: &Token, config: &OutlineConfig) -> Result<TargetSetup> {
    let (w, h) = (image.width(), image.height());
    let profile = outline_profile(token, w, &config.profile)?;
    let pixels = token.pixels();
    let values: Vec<f64> = pixels.iter().map(|&p| image.data()[p]).collect();
    let normals: Vec<_> = pixels.iter().map(|&p| profile.normal_at(p % w)).collect();
    let fit = fit_shading(&values, &normals, config.light)?;
    let predicted: Vec<f64> = normals.iter().map(|n| fit.predict(n)).collect();
    let mut shading = Grid::new(w, h, 0.0);
    for (&p, &v) in pixels.iter().zip(&predicted) {
        shading.data_mut()[p] = v;
    }
    let bc = outline_conditions(token, &profile, w, h);
    let mut start_f = Grid::new(w, h, 0.0);
    for &p in pixels {
        start_f.data_mut()[p] = profile.fg_at(p % w).0;
    }
    Ok(TargetSetup {
        profile,
        fit,
        values,
        predicted,
        shading,
        bc,
        start_f,
    })
}

impl TargetSetup {
    /// The engine's reconstruction of the strip from the explained shading with the outline's
    /// normals on the cut, with `smoothness`; with a shape that explains nothing (albedo 0)
    /// the data carry nothing (λ = 0). With a warm start the sweeps start from the outline's
    /// own shape, else from a flat one.
    fn reconstruct(
        &self,
        smoothness: Smoothness,
        config: &OutlineConfig,
    ) -> Result<CreaseSolution> {
        let reflectance = Lambertian {
            light: self.fit.light,
            albedo: self.fit.albedo,
            ambient: self.fit.offset,
        };
        let lambda = if self.fit.albedo > 0.0 {
            config.crease.lambda
        } else {
            0.0
        };
        let zero = Grid::new(self.shading.width(), self.shading.height(), 0.0);
        crease::solve_from(
            &self.shading,
            &self.bc,
            &reflectance,
            &CreaseOptions {
                lambda,
                smoothness,
                ..config.crease
            },
            config.warm_start.then_some((&self.start_f, &zero)),
        )
    }

    /// The target's reading from its two reconstructions.
    fn reading(
        self,
        token: &Token,
        w: usize,
        h: usize,
        tv: &CreaseSolution,
        quadratic: &CreaseSolution,
    ) -> TargetReading {
        let pixels = token.pixels();
        let (values, predicted, fit, profile) =
            (self.values, self.predicted, self.fit, self.profile);
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let paint_rms = (values
            .iter()
            .zip(&predicted)
            .map(|(i, s)| (i - s) * (i - s))
            .sum::<f64>()
            / values.len() as f64)
            .sqrt();
        let index: BTreeMap<usize, usize> =
            pixels.iter().enumerate().map(|(k, &p)| (p, k)).collect();
        let at = |p: usize| index.get(&p).copied().unwrap_or(0);
        let layers = crop_layers(token, w, h, |p| {
            let k = at(p);
            (
                normal_from_fg(tv.f.data()[p], tv.g.data()[p]).x,
                predicted[k],
                mean + values[k] - predicted[k],
            )
        });
        TargetReading {
            label: token.label,
            name: token.name.clone(),
            stem: stem(&token.name, token.label),
            pixels: pixels.len(),
            columns: profile.slope.len(),
            relief: profile.relief(),
            light_tilt_deg: fit.light.tilt_deg(),
            light_slant_deg: fit.light.slant_deg(),
            shape_explained: fit.explained,
            shading: fit,
            paint_rms,
            outline_bend_concentration: profile.bend_concentration(),
            bend_concentration: curvature_concentration(&tv.f, pixels, TOP_FRACTION),
            bend_concentration_quadratic: curvature_concentration(
                &quadratic.f,
                pixels,
                TOP_FRACTION,
            ),
            sweeps: tv.sweeps,
            converged: tv.converged,
            sweeps_quadratic: quadratic.sweeps,
            converged_quadratic: quadratic.converged,
            layers,
        }
    }
}

/// The target's three layers, cropped to its bounding box and a margin; `value(p)` gives
/// (shape, shading, paint) at a target pixel p.
fn crop_layers(
    token: &Token,
    w: usize,
    h: usize,
    value: impl Fn(usize) -> (f64, f64, f64),
) -> Layers {
    let (mut c0, mut r0, mut c1, mut r1) = (w, h, 0, 0);
    for &p in token.pixels() {
        let (c, r) = (p % w, p / w);
        (c0, r0, c1, r1) = (c0.min(c), r0.min(r), c1.max(c), r1.max(r));
    }
    let (c0, r0) = (c0.saturating_sub(MARGIN), r0.saturating_sub(MARGIN));
    let (c1, r1) = ((c1 + MARGIN).min(w - 1), (r1 + MARGIN).min(h - 1));
    let (cw, ch) = (c1 - c0 + 1, r1 - r0 + 1);
    let mut inside = Mask::new(cw, ch, false);
    for &p in token.pixels() {
        *inside.get_mut(p % w - c0, p / w - r0) = true;
    }
    let layer = |k: usize| {
        Grid::from_fn(cw, ch, |c, r| {
            if *inside.get(c, r) {
                let v = value((r + r0) * w + c + c0);
                [v.0, v.1, v.2][k]
            } else {
                0.0
            }
        })
    };
    Layers {
        shape: layer(0),
        shading: layer(1),
        paint: layer(2),
        inside,
        origin: (c0, r0),
        picture_height: h,
    }
}

/// A file-name stem from a target's name: lower-case letters and digits, runs of anything
/// else as one '-'; `target-LABEL` when nothing is left.
fn stem(name: &str, label: u16) -> String {
    let mut s = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            s.push(ch.to_ascii_lowercase());
        } else if !s.is_empty() && !s.ends_with('-') {
            s.push('-');
        }
    }
    let s = s.trim_end_matches('-').to_string();
    if s.is_empty() {
        format!("target-{label}")
    } else {
        s
    }
}

impl TargetReading {
    /// The target's three figures: (file name, figure) for the shape, the shading and the
    /// paint.
    pub(crate) fn figures(&self) -> Vec<(String, MapFigure)> {
        let l = &self.layers;
        let (c0, r0) = l.origin;
        let (cw, ch) = (l.inside.width(), l.inside.height());
        let place = |mut fig: MapFigure| {
            fig.x_range = (c0 as f64, (c0 + cw) as f64);
            let top = (l.picture_height - r0) as f64;
            fig.y_range = (top - ch as f64, top);
            fig.size = (900, 300);
            fig
        };
        let gray = |values: &Image, title: String, label: &str| {
            let bar = ColourBar {
                colormap: Colormap::Gray,
                range: (0.0, 1.0),
                label: label.into(),
            };
            let picture = Colormap::Gray.paint(values, (0.0, 1.0), Some(&l.inside), OUTSIDE);
            place(MapFigure::new(&title, picture, bar))
        };
        let shape = {
            let bar = ColourBar {
                colormap: Colormap::Viridis,
                range: (-1.0, 1.0),
                label: "normal x (-1 faces left, +1 right)".into(),
            };
            let picture = Colormap::Viridis.paint(&l.shape, (-1.0, 1.0), Some(&l.inside), [1.0; 3]);
            place(MapFigure::new(
                &format!(
                    "{}: shape from the outline (bend concentration {:.2})",
                    self.name, self.bend_concentration
                ),
                picture,
                bar,
            ))
        };
        vec![
            (format!("{}-shape.png", self.stem), shape),
            (
                format!("{}-shading.png", self.stem),
                gray(
                    &l.shading,
                    format!(
                        "{}: shading the shape predicts (explains {:.0}%)",
                        self.name,
                        100.0 * self.shape_explained
                    ),
                    "luminance",
                ),
            ),
            (
                format!("{}-paint.png", self.stem),
                gray(
                    &l.paint,
                    format!("{}: paint (what the shape leaves)", self.name),
                    "luminance",
                ),
            ),
        ]
    }
}

impl OutlineReport {
    /// The table: one row per target.
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "target,label,pixels,light_tilt_deg,light_slant_deg,albedo,offset,shape_explained,paint_rms,bend_concentration,bend_concentration_quadratic,outline_bend_concentration,relief,converged\n",
        );
        for t in &self.targets {
            csv.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                csv_field(&t.name),
                t.label,
                t.pixels,
                t.light_tilt_deg,
                t.light_slant_deg,
                t.shading.albedo,
                t.shading.offset,
                t.shape_explained,
                t.paint_rms,
                t.bend_concentration,
                t.bend_concentration_quadratic,
                t.outline_bend_concentration,
                t.relief,
                t.converged && t.converged_quadratic
            ));
        }
        csv
    }
}

impl CommandReport for OutlineReport {
    /// The report, `outline.json`.
    const MARKER: &'static str = "outline.json";

    /// Writes [`CSV_FILE`], every target's pictures and the report, [`OutlineReport::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        io::write_text(&dir.join(CSV_FILE), &self.csv())?;
        for t in &self.targets {
            for (name, figure) in t.figures() {
                figure.write_png(&dir.join(name))?;
            }
        }
        let value = serde_json::to_value(self)
            .map_err(|e| Error::Compute(format!("cannot serialise the report: {e}")))?;
        io::write_json(&dir.join(Self::MARKER), &value)
    }
}

#[cfg(test)]
mod tests {
    use super::stem;

    #[test]
    fn stems_are_plain() {
        assert_eq!(stem("sinusoidal strip", 1), "sinusoidal-strip");
        assert_eq!(stem("  A/B  ", 2), "a-b");
        assert_eq!(stem("??", 3), "target-3");
    }
}
