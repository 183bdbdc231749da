//! The lightness analysis as a pipeline: one or all of the lightness models on a picture, the
//! mean output per target, and for the checker-shadow (targets named A and B) the pixel facts
//! and each model's verdict.

// The parts of this command's configuration and report that other modules define.
pub use crate::lightness::checker::{Prediction, SquareFacts};
pub use crate::lightness::{TargetMean, Variant};

use super::source::PictureSource;
use super::CommandReport;
use crate::colormap::Colormap;
use crate::error::{Error, Result};
use crate::grid::{Image, Labels, Mask};
use crate::io::{self, BitDepth, Stamp};
use crate::lightness::checker::{self};
use crate::lightness::{target_means, Model};
use crate::message::{Message, Setting};
use crate::plot::{ColourBar, MapFigure, Outline};
use crate::progress::Progress;
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// What to analyse and with which models.
#[derive(Debug, Clone)]
pub struct LightnessConfig {
    /// The picture.
    pub source: PictureSource,
    /// The models, run in this order (at least one).
    pub models: Vec<Model>,
}

impl LightnessConfig {
    /// A checked configuration.
    pub fn new(source: PictureSource, models: Vec<Model>) -> Result<Self> {
        let config = LightnessConfig { source, models };
        config.validate()?;
        Ok(config)
    }

    /// The models named by `text`: one model's name, or `all` for every model in turn.
    ///
    /// ```
    /// use shadelab::pipeline::lightness::LightnessConfig;
    /// assert_eq!(LightnessConfig::parse_models("all").unwrap().len(), 5);
    /// assert_eq!(LightnessConfig::parse_models("retinex").unwrap().len(), 1);
    /// assert!(LightnessConfig::parse_models("blah").is_err());
    /// ```
    pub fn parse_models(text: &str) -> Result<Vec<Model>> {
        if text.trim().eq_ignore_ascii_case("all") {
            Model::NAMES.iter().map(|n| n.parse()).collect()
        } else {
            Ok(vec![text.parse()?])
        }
    }

    /// Checks what needs no file: the source and a model to run (a picture's resolution, where
    /// a model works in degrees, is checked when it is read, once).
    pub fn validate(&self) -> Result<()> {
        self.source.check()?;
        if self.models.is_empty() {
            return Err(Error::invalid("no lightness model to run"));
        }
        Ok(())
    }
}

/// One model's output files.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LightnessOutput {
    /// The model's name.
    pub model: String,
    /// The output as float `.npy`.
    pub npy: String,
    /// The output as a picture.
    pub png: String,
    /// The output as a figure with axes, a colour bar and the targets outlined and named
    /// (written by builds with plots).
    pub figure: Option<String>,
    /// What the values mean.
    pub units: String,
}

/// One model's mean output per target.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelTargets {
    /// The model's name.
    pub model: String,
    /// Mean output and luminance per target label.
    pub targets: Vec<TargetMean>,
}

/// The checker-shadow facts and verdicts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckerSection {
    /// Whether every pixel of A and of B has one and the same value.
    pub identical_pixels: bool,
    /// Square A's pixels.
    pub a: SquareFacts,
    /// Square B's pixels.
    pub b: SquareFacts,
    /// What people see.
    pub percept: String,
    /// Each model's prediction.
    pub predictions: Vec<Prediction>,
}

/// Time taken.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Seconds {
    /// Per model.
    pub models: BTreeMap<String, f64>,
    /// In all.
    pub total: f64,
}

/// What the lightness analysis found; [`LightnessReport::write`] writes it as a folder.
#[derive(Debug, Clone, Serialize)]
pub struct LightnessReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// Where the picture came from.
    pub input: Value,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Pixels per degree, when known.
    pub ppd: Option<f64>,
    /// The models run.
    pub models: Vec<String>,
    /// Each model's output files.
    pub outputs: Vec<LightnessOutput>,
    /// Each model's mean output per target (empty without target labels).
    pub targets: Vec<ModelTargets>,
    /// The checker-shadow section, when the targets include A and B.
    pub checker_shadow: Option<CheckerSection>,
    /// Time taken.
    pub seconds: Seconds,
    /// Each model's output, in the order of `outputs`.
    #[serde(skip)]
    pub images: Vec<(Model, Image)>,
    /// The targets, outlined on the figures.
    #[serde(skip)]
    pub(crate) outlines: Vec<Outline>,
}

/// Runs the lightness analysis.
pub fn run(config: &LightnessConfig, progress: &dyn Progress) -> Result<LightnessReport> {
    let started = Instant::now();
    config.validate()?;
    let input = config.source.load(false)?;
    input.say_notes(progress);
    if input.ppd.is_none() {
        if let Some(m) = config.models.iter().find(|m| m.needs_ppd()) {
            return Err(Error::Setting(
                Message::text(format!(
                    "the {m} model works in degrees of visual angle: give the image's \
                     resolution with "
                ))
                .setting(Setting::Ppd, "its ppd")
                .then(" (pixels per degree)"),
            ));
        }
    }
    let image = input.luminance();
    let single = config.models.len() == 1;
    progress.start(config.models.len() as u64, "lightness models");
    let mut outputs = Vec::new();
    let mut images = Vec::new();
    let mut timings = BTreeMap::new();
    for model in &config.models {
        let t = Instant::now();
        let out = model.predict(&image, input.ppd)?;
        timings.insert(model.name().to_string(), t.elapsed().as_secs_f64());
        let stem = if single {
            "lightness".to_string()
        } else {
            format!("lightness_{}", model.name())
        };
        outputs.push(LightnessOutput {
            model: model.name().into(),
            npy: format!("{stem}.npy"),
            png: format!("{stem}.png"),
            figure: cfg!(feature = "plots").then(|| format!("{stem}_figure.png")),
            units: units(*model).into(),
        });
        images.push((*model, out));
        progress.advance(1);
    }
    progress.finish();

    let mut targets = Vec::new();
    if let Some((labels, names)) = &input.labels {
        for (model, out) in &images {
            targets.push(ModelTargets {
                model: model.name().into(),
                targets: target_means(out, &image, labels, names)?,
            });
        }
    }
    let checker_shadow = input.labels.as_ref().and_then(|(labels, names)| {
        let index = |n: &str| names.iter().position(|x| x == n).map(|i| i as u16 + 1);
        let (a, b) = (index("A")?, index("B")?);
        Some(checker_section(&image, labels, a, b, &images))
    });
    // Said once the run succeeded: a refusal stays one line.
    input.input_note.iter().for_each(|line| progress.note(line));
    Ok(LightnessReport {
        stamp: Stamp::of("analyze lightness"),
        input: input.origin,
        width: image.width(),
        height: image.height(),
        ppd: input.ppd,
        models: config.models.iter().map(|m| m.name().into()).collect(),
        outputs,
        targets,
        checker_shadow,
        seconds: Seconds {
            models: timings,
            total: started.elapsed().as_secs_f64(),
        },
        images,
        outlines: input
            .labels
            .as_ref()
            .map(|(labels, names)| {
                names
                    .iter()
                    .enumerate()
                    .map(|(i, name)| Outline {
                        mask: labels.map(|&v| usize::from(v) == i + 1),
                        name: name.clone(),
                    })
                    .filter(|o| o.mask.count() > 0)
                    .collect()
            })
            .unwrap_or_default(),
    })
}

impl CommandReport for LightnessReport {
    /// The report, `lightness.json`.
    const MARKER: &'static str = "lightness.json";

    /// Writes each model's `.npy` and `.png` (and figure), `targets.csv` and `targets.json`
    /// when there are targets, and the report, [`LightnessReport::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        for (files, (model, image)) in self.outputs.iter().zip(&self.images) {
            io::write_image(&dir.join(&files.npy), image)?;
            io::write_gray(
                &dir.join(&files.png),
                &picture(*model, image),
                BitDepth::Eight,
                None,
            )?;
            if let Some(file) = &files.figure {
                self.figure(*model, image).write_png(&dir.join(file))?;
            }
        }
        if !self.targets.is_empty() {
            write_targets(dir, &self.targets)?;
        }
        io::write_json(&dir.join(Self::MARKER), &to_json(self)?)
    }
}

impl LightnessReport {
    /// One model's output as a figure: the same gray levels as its `.png`, in degrees when the
    /// resolution is known, with a colour bar in the model's units and the targets outlined
    /// and named.
    pub(crate) fn figure(&self, model: Model, out: &Image) -> MapFigure {
        let range = match model {
            Model::Retinex => (0.0, 1.0),
            Model::Odog(_) | Model::HighPass => {
                let m = out.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
                if m > 0.0 {
                    (-m, m)
                } else {
                    (-1.0, 1.0)
                }
            }
        };
        let bar = ColourBar {
            colormap: Colormap::Gray,
            range,
            label: match model {
                Model::Retinex => "estimated reflectance (lightest pixel = 1)",
                Model::Odog(_) => "model brightness (arbitrary units, 0 = mid-grey)",
                Model::HighPass => "luminance minus its blur (0 = as its surround)",
            }
            .into(),
        };
        let picture = Colormap::Gray.paint(out, range, None, [1.0; 3]);
        let mut figure = MapFigure::new(
            &format!("{}: predicted lightness", model.title()),
            picture,
            bar,
        );
        // The gray levels are the `.png`'s codes, written without gamma.
        figure.gamma = None;
        if let Some(ppd) = self.ppd.filter(|p| *p > 0.0) {
            figure.x_label = "x (deg)".into();
            figure.y_label = "y (deg, up)".into();
            figure.x_range = (0.0, out.width() as f64 / ppd);
            figure.y_range = (0.0, out.height() as f64 / ppd);
        }
        figure.outlines = self.outlines.clone();
        figure
    }
}

fn to_json<T: Serialize>(value: &T) -> Result<Value> {
    serde_json::to_value(value)
        .map_err(|e| Error::Compute(format!("cannot serialise the report: {e}")))
}

fn units(model: Model) -> &'static str {
    match model {
        Model::Retinex => "estimated reflectance, lightest pixel = 1",
        Model::Odog(_) => "model brightness, arbitrary units, 0 = mid-grey, positive = brighter",
        Model::HighPass => {
            "luminance minus its Gaussian blur, positive = brighter than the surround"
        }
    }
}

/// The visualisation: Retinex as it is (0..1); the filter models symmetric about mid-grey,
/// ±(largest magnitude) mapped to 0..1.
fn picture(model: Model, out: &Image) -> Image {
    match model {
        Model::Retinex => out.clone(),
        Model::Odog(_) | Model::HighPass => {
            let m = out.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            out.map(|v| if m > 0.0 { 0.5 + 0.5 * v / m } else { 0.5 })
        }
    }
}

fn write_targets(dir: &Path, targets: &[ModelTargets]) -> Result<()> {
    let mut csv = String::from("model,label,name,pixels,luminance,output\n");
    for rows in targets {
        for t in &rows.targets {
            csv.push_str(&format!(
                "{},{},{},{},{},{}\n",
                rows.model,
                t.label,
                t.name.replace(',', ";"),
                t.pixels,
                t.luminance,
                t.output
            ));
        }
    }
    io::write_text(&dir.join("targets.csv"), &csv)?;
    io::write_json(&dir.join("targets.json"), &to_json(&targets)?)
}

/// The checker-shadow facts (A and B pixels) and each model's verdict.
fn checker_section(
    image: &Image,
    labels: &Labels,
    a: u16,
    b: u16,
    outputs: &[(Model, Image)],
) -> CheckerSection {
    let mask = |l: u16| -> Mask { labels.map(|&v| v == l) };
    let (ma, mb) = (mask(a), mask(b));
    let facts = checker::pixel_facts(image, &ma, &mb);
    CheckerSection {
        identical_pixels: facts.2,
        a: facts.0,
        b: facts.1,
        percept: "B looks much lighter than A".into(),
        predictions: outputs
            .iter()
            .map(|(m, out)| checker::predict(m.name(), out, &ma, &mb))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image file without a resolution is refused, when it is read (once), for a model
    /// that works in degrees only, naming the setting (no flag: the front end names it).
    #[test]
    fn an_image_without_resolution_is_refused_for_a_filter_model_only() {
        let dir =
            std::env::temp_dir().join(format!("shadelab-lightness-bare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = dir.join("x.png");
        let gray = crate::grid::Grid::from_fn(32, 32, |c, _| 0.25 + 0.5 * (c % 2) as f64);
        io::write_gray(&image, &gray, io::BitDepth::Sixteen, None).unwrap();
        let source = PictureSource {
            image: Some(image),
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            ..Default::default()
        };
        let odog = LightnessConfig::parse_models("odog").unwrap();
        let config = LightnessConfig::new(source.clone(), odog).unwrap();
        let e = run(&config, &crate::progress::NoProgress).unwrap_err();
        assert!(e.to_string().contains("pixels per degree"), "{e}");
        assert!(!e.to_string().contains("--"), "{e}");
        assert!(matches!(&e, Error::Setting(m) if m.settings().any(|s| s == Setting::Ppd)));
        let retinex = LightnessConfig::parse_models("retinex").unwrap();
        let config = LightnessConfig::new(source.clone(), retinex).unwrap();
        assert!(run(&config, &crate::progress::NoProgress).is_ok());
        assert!(LightnessConfig::new(source, Vec::new()).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
