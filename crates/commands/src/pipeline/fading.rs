//! The fading (Troxler) disk analysis as a pipeline: which scenes are compared (a blurred and
//! a sharp disk), the border band-pass energy of each, the perceived-contrast time course of
//! the adaptation model with fixational jitter, and the animation in which the blurred disk
//! fades.
//!
//! The two disks come from a picture with target labels (label 1 = the blurred disk, 2 = the
//! sharp disk), or from a stimulus rendered twice: as given (the blurred disk) and with
//! `blur = 0` (the sharp one), each with its own target named `disk`.

// The parts of this command's configuration and report that other modules define.
pub use crate::lightness::fading::{AdaptationOptions, BorderEnergy, DogBand, TimeCourse};

use super::source::{render_record, Picture, PictureSource};
use super::CommandReport;
use crate::error::{Error, Result};
use crate::grid::{Image, Mask, RgbImage};
use crate::imageops::{shrink, side_by_side};
use crate::io::{self, Stamp};
use crate::lightness::fading::{adaptation_time_course, border_energy, Disk, PerceivedFrames};
use crate::message::{Message, Setting};
use crate::parallel::prelude::*;
use crate::plot::{LinePlot, Series};
use crate::progress::Progress;
use crate::stimulus::Pixels;
use serde::Serialize;
use serde_json::{Map, Value};
use std::path::Path;
use std::time::Instant;

/// The animation's frame rate.
const FPS: f64 = 10.0;
/// The animation's largest side in pixels.
const GIF_SIDE: usize = 480;

/// What to analyse and how.
#[derive(Debug, Clone)]
pub struct FadingConfig {
    /// The picture: an image with labels 1 (blurred disk) and 2 (sharp disk), or a stimulus.
    pub source: PictureSource,
    /// The band-pass filter and the border band's half-width.
    pub band: DogBand,
    /// The adaptation model.
    pub adaptation: AdaptationOptions,
}

impl FadingConfig {
    /// A checked configuration.
    pub fn new(
        source: PictureSource,
        band: DogBand,
        adaptation: AdaptationOptions,
    ) -> Result<Self> {
        let config = FadingConfig {
            source,
            band,
            adaptation,
        };
        config.validate()?;
        Ok(config)
    }

    /// Checks what needs no file: the source, the filter and the adaptation settings (an
    /// image's resolution and labels are checked when it is read, once).
    pub fn validate(&self) -> Result<()> {
        self.source.check()?;
        self.band.check()?;
        self.adaptation.check()?;
        Ok(())
    }
}

/// The relative perceived contrast of both disks at the end of the time course.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FinalContrast {
    /// The blurred disk.
    pub blurred: f64,
    /// The sharp disk.
    pub sharp: f64,
}

/// The animation's facts.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Animation {
    /// Its file name.
    pub file: String,
    /// Number of frames.
    pub frames: usize,
    /// Time per frame, milliseconds.
    pub delay_ms: u32,
    /// The factor by which the frames were reduced.
    pub reduced_by: usize,
    /// What a frame shows.
    pub rule: String,
    /// How the disks are laid out.
    pub layout: String,
}

/// What the fading analysis found; [`FadingReport::write`] writes it as a folder.
#[derive(Debug, Clone, Serialize)]
pub struct FadingReport {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// Where the picture(s) came from.
    pub input: Value,
    /// Pixels per degree.
    pub ppd: f64,
    /// The band-pass filter.
    pub band_pass: DogBand,
    /// Band-pass energy at the two borders.
    pub border_energy: BorderEnergy,
    /// The adaptation model's settings.
    pub adaptation: AdaptationOptions,
    /// The perceived contrast at the end.
    pub final_contrast: FinalContrast,
    /// What the time-course file holds.
    pub time_course: String,
    /// The animation.
    pub animation: Animation,
    /// Seconds taken.
    pub seconds: f64,
    /// The time course (written as `time_course.csv`).
    #[serde(skip)]
    pub course: TimeCourse,
    /// The animation's frames (written as the GIF).
    #[serde(skip)]
    pub frames: Vec<RgbImage>,
}

/// One disk: its picture (RGB for the animation, channels for the analysis) and mask.
struct Scene {
    picture: RgbImage,
    channels: Vec<Image>,
    mask: Mask,
}

/// Runs the fading analysis.
pub fn run(config: &FadingConfig, progress: &dyn Progress) -> Result<FadingReport> {
    let started = Instant::now();
    config.validate()?;
    let (band, options) = (&config.band, &config.adaptation);
    progress.start(3, "fading: loading");
    let (blurred, sharp, ppd, origin, input_note) = scenes(&config.source, progress)?;
    let (b, s) = (
        Disk {
            channels: &blurred.channels,
            mask: &blurred.mask,
        },
        Disk {
            channels: &sharp.channels,
            mask: &sharp.mask,
        },
    );
    progress.advance(1);
    let energy = border_energy(b, s, ppd, band)?;
    let course = adaptation_time_course(b, s, ppd, band, options)?;
    progress.advance(1);

    let every = ((1.0 / FPS) / options.dt_s).round().max(1.0) as usize;
    let same_picture = blurred.picture == sharp.picture;
    // Each frame is made, joined and reduced on its own: the animation is never held at full
    // size (at the fading disk's 110 ppd that was hundreds of megabytes).
    let (left, right) = if same_picture {
        let regions: [(&Mask, &[f64]); 2] = [
            (&blurred.mask, &course.blurred),
            (&sharp.mask, &course.sharp),
        ];
        (
            PerceivedFrames::new(&blurred.picture, &regions, ppd, band, every)?,
            None,
        )
    } else {
        (
            PerceivedFrames::new(
                &blurred.picture,
                &[(&blurred.mask, &course.blurred)],
                ppd,
                band,
                every,
            )?,
            Some(PerceivedFrames::new(
                &sharp.picture,
                &[(&sharp.mask, &course.sharp)],
                ppd,
                band,
                every,
            )?),
        )
    };
    let gap = (0.25 * ppd).ceil() as usize;
    let (w, h) = match &right {
        None => (blurred.picture.width(), blurred.picture.height()),
        Some(_) => (
            blurred.picture.width() + gap + sharp.picture.width(),
            blurred.picture.height().max(sharp.picture.height()),
        ),
    };
    let factor = w.max(h).div_ceil(GIF_SIDE);
    let count = right
        .as_ref()
        .map_or(left.len(), |r| left.len().min(r.len()));
    let frame = |k: usize| {
        let full = match &right {
            None => left.frame(k),
            Some(r) => side_by_side(&left.frame(k), &r.frame(k), gap, [0.0; 3]),
        };
        shrink(&full, factor)
    };
    let steps: Vec<usize> = (0..count).collect();
    let frames: Vec<RgbImage> = steps.par_iter().map(|&k| frame(k)).collect();
    let delay_ms = (every as f64 * options.dt_s * 1000.0).round() as u32;
    progress.advance(1);
    progress.finish();

    let last = course.times.len() - 1;
    // Said once the run succeeded: a refusal stays one line.
    input_note.iter().for_each(|line| progress.note(line));
    Ok(FadingReport {
        stamp: Stamp::of("analyze fading"),
        input: origin,
        ppd,
        band_pass: *band,
        border_energy: energy,
        adaptation: *options,
        final_contrast: FinalContrast {
            blurred: course.blurred[last],
            sharp: course.sharp[last],
        },
        time_course: "time_course.csv: relative perceived contrast (RMS adapted band-pass \
                      response in the border band over its value at onset) and eye position; \
                      time_course.png and .svg: the contrast of both disks against time"
            .into(),
        animation: Animation {
            file: "fading.gif".into(),
            frames: frames.len(),
            delay_ms,
            reduced_by: factor,
            rule: "inside each disk's region the picture is its surround colour plus the \
                   disk's relative contrast times the difference; values written as 8-bit \
                   codes without gamma"
                .into(),
            layout: if same_picture {
                "one picture"
            } else {
                "blurred disk left, sharp disk right"
            }
            .into(),
        },
        seconds: started.elapsed().as_secs_f64(),
        course,
        frames,
    })
}

impl CommandReport for FadingReport {
    /// The report, `fading.json`.
    const MARKER: &'static str = "fading.json";

    /// Writes `time_course.csv`, with plots `time_course.png` and `.svg`
    /// (the time course plotted), `fading.gif` and the report,
    /// [`FadingReport::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        let c = &self.course;
        let mut csv = String::from("time_s,blurred,sharp,eye_x_deg,eye_y_deg\n");
        for i in 0..c.times.len() {
            csv.push_str(&format!(
                "{},{},{},{},{}\n",
                c.times[i], c.blurred[i], c.sharp[i], c.eye[i].0, c.eye[i].1
            ));
        }
        io::write_text(&dir.join("time_course.csv"), &csv)?;
        let plot = self.time_course_plot();
        plot.write_png(&dir.join("time_course.png"))?;
        plot.write_svg(&dir.join("time_course.svg"))?;
        io::write_gif(
            &dir.join(&self.animation.file),
            &self.frames,
            self.animation.delay_ms,
        )?;
        let json = serde_json::to_value(self)
            .map_err(|e| Error::Compute(format!("cannot serialise the report: {e}")))?;
        io::write_json(&dir.join(Self::MARKER), &json)
    }
}

impl FadingReport {
    /// The time course as a plot: each disk's relative perceived contrast (1 = at onset)
    /// against time since stimulus onset in seconds.
    pub(crate) fn time_course_plot(&self) -> LinePlot {
        let c = &self.course;
        let end = c.times.last().copied().unwrap_or(1.0).max(1e-3);
        let mut plot = LinePlot::new(
            "Perceived contrast of the two disks during steady fixation",
            "time since stimulus onset (s)",
            "relative perceived contrast (1 = at onset)",
            (0.0, end),
        );
        plot.reference_y = Some(1.0);
        let top = c
            .blurred
            .iter()
            .chain(&c.sharp)
            .fold(1.0f64, |m, &v| m.max(v));
        plot.y_range = Some((0.0, 1.05 * top));
        for (name, values) in [("blurred disk", &c.blurred), ("sharp disk", &c.sharp)] {
            plot.series.push(Series {
                name: name.into(),
                points: c
                    .times
                    .iter()
                    .copied()
                    .zip(values.iter().copied())
                    .collect(),
            });
        }
        plot
    }
}

/// The blurred and the sharp disk, the resolution, and where they came from.
/// With the note to say once the run succeeded that a file's codes were taken as sRGB.
fn scenes(
    source: &PictureSource,
    progress: &dyn Progress,
) -> Result<(Scene, Scene, f64, Value, Option<Message>)> {
    if source.image.is_some() {
        // Read once: the picture, its sidecar and its labels.
        let input = source.load(true)?;
        input.say_notes(progress);
        // A fading disk rendered to a file (its sidecar records it) and no labels given: the
        // file holds the blurred disk, and its sharp twin is the render its record describes
        // with blur = 0, as for the stimulus by name, so that both routes give the same
        // numbers.
        let given_labels = source.mask.is_some() || source.labels.is_some();
        let render = input
            .record()
            .filter(|s| !given_labels && s.stimulus.as_deref() == Some(FADING_DISK));
        if let Some(sidecar) = render {
            let blur = Map::from_iter([("blur".to_string(), Value::from("0"))]);
            let sharp = render_record(sidecar, &blur, source.ppd, source.max_pixels)?;
            let note = input.input_note.clone();
            let (b, s, ppd, origin) = twin(input, sharp)?;
            return Ok((b, s, ppd, origin, note));
        }
        let Some(ppd) = input.ppd else {
            return Err(Error::Setting(
                Message::text(
                    "the fading analysis works in degrees of visual angle: give the image's \
                     resolution with ",
                )
                .setting(Setting::Ppd, "its ppd")
                .then(" (pixels per degree)"),
            ));
        };
        let Some((labels, names)) = input.labels.as_ref() else {
            return Err(Error::Setting(
                Message::text("an image needs ")
                    .setting(Setting::Mask, "target labels")
                    .then(" with label 1 = the blurred disk and 2 = the sharp disk"),
            ));
        };
        // Targets named by a render's sidecar are that render's (the fading disk's are `disk`
        // and `fixation`), not a blurred and a sharp disk: reading them as such would compare
        // the disk with the fixation dot.
        if names.len() >= 2 && !names[1].contains("sharp") {
            return Err(Error::invalid(format!(
                "the image's targets are {} (from its sidecar), not label 1 = the blurred disk \
                 and 2 = the sharp disk: analyse the stimulus itself (it is rendered blurred and \
                 sharp), or give target labels with those two disks",
                names.join(", ")
            )));
        }
        let mask = |l: u16, what: &str| -> Result<Mask> {
            let m = labels.map(|&v| v == l);
            if m.count() == 0 {
                return Err(Error::invalid(format!(
                    "the mask has no pixel labelled {l} (the {what} disk)"
                )));
            }
            Ok(m)
        };
        let (mb, ms) = (mask(1, "blurred")?, mask(2, "sharp")?);
        let picture = rgb(&input);
        let channels = channels(&input.pixels);
        let blurred = Scene {
            picture: picture.clone(),
            channels: channels.clone(),
            mask: mb,
        };
        let sharp = Scene {
            picture,
            channels,
            mask: ms,
        };
        return Ok((blurred, sharp, ppd, input.origin, input.input_note));
    }
    // A stimulus: as given for the blurred disk, with blur = 0 for the sharp one.
    let blurred_input = source.load(true)?;
    let mut sharp_source = source.clone();
    sharp_source.params.insert("blur".into(), Value::from("0"));
    let (b, s, ppd, origin) = twin(blurred_input, sharp_source.load(true)?)?;
    Ok((b, s, ppd, origin, None))
}

/// The fading disk's stimulus name.
const FADING_DISK: &str = "fading-disk";

/// The blurred and the sharp disk of two renders (or a file and a render), each found by its
/// `disk` target.
fn twin(blurred_input: Picture, sharp_input: Picture) -> Result<(Scene, Scene, f64, Value)> {
    let ppd = blurred_input.ppd.unwrap_or_default();
    let disk = |input: &Picture, what: &str| -> Result<Scene> {
        let (labels, names) = input.labels.as_ref().ok_or_else(|| {
            Error::invalid(format!(
                "the stimulus has no target mask to find the {what} disk in; give target labels"
            ))
        })?;
        let label = names
            .iter()
            .position(|n| n == "disk")
            .map(|i| i as u16 + 1)
            .unwrap_or(1);
        let mask = labels.map(|&v| v == label);
        if mask.count() == 0 {
            return Err(Error::invalid(format!(
                "the {what} render has no disk target (label {label})"
            )));
        }
        Ok(Scene {
            picture: rgb(input),
            channels: channels(&input.pixels),
            mask,
        })
    };
    let blurred = disk(&blurred_input, "blurred")?;
    let sharp = disk(&sharp_input, "sharp")?;
    let mut origin = Map::new();
    origin.insert("blurred".into(), blurred_input.origin);
    origin.insert("sharp".into(), sharp_input.origin);
    Ok((blurred, sharp, ppd, Value::Object(origin)))
}

fn rgb(input: &Picture) -> RgbImage {
    match &input.pixels {
        Pixels::Rgb(i) => i.clone(),
        Pixels::Gray(i) => i.map(|&v| [v, v, v]),
    }
}

fn channels(pixels: &Pixels) -> Vec<Image> {
    match pixels {
        Pixels::Gray(i) => vec![i.clone()],
        Pixels::Rgb(i) => (0..3).map(|k| i.map(|p| p[k])).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image file without a resolution, or without labels, is refused when it is read
    /// (once), each refusal naming the setting it lacks, as a usage error.
    #[test]
    fn an_image_without_resolution_or_labels_is_refused() {
        let dir = std::env::temp_dir().join(format!("shadelab-fading-bare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = dir.join("x.png");
        let gray = crate::grid::Grid::new(32, 32, 0.5);
        io::write_gray(&image, &gray, io::BitDepth::Sixteen, None).unwrap();
        let source = PictureSource {
            image: Some(image),
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            ..Default::default()
        };
        let refusal = |source: PictureSource| {
            let config = FadingConfig::new(source, DogBand::default(), Default::default()).unwrap();
            run(&config, &crate::progress::NoProgress).unwrap_err()
        };
        let e = refusal(source.clone());
        assert!(e.to_string().contains("pixels per degree"), "{e}");
        assert!(matches!(&e, Error::Setting(m) if m.settings().any(|s| s == Setting::Ppd)));
        assert!(e.is_usage());
        let e = refusal(PictureSource {
            ppd: Some(10.0),
            ..source
        });
        assert!(e.to_string().contains("label 1"), "{e}");
        assert!(matches!(&e, Error::Setting(m) if m.settings().any(|s| s == Setting::Mask)));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
