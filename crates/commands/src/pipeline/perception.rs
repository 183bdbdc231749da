//! What the perception pipelines ([`super::prior_sweep`], [`super::observer`]) share: the
//! picture (an image or a rendered stimulus), where the engine solves, the boundary at the
//! domain's rim ([`BoundarySource`], as `solve` takes it), the lighting to assume besides its tilt, and the solver settings, with their
//! defaults; [`Config::load`] turns them into a [`Setup`] ready to interpret.

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::convexity::Token;
pub use crate::analysis::interpretation::{Lighting, Scene};
pub use crate::analysis::{Domain, Interpretation, TokenPicture, TokenReading};

// One picture read as the sweep reads it, for an interactive front end (the teaching page):
// the picture turned, interpreted under one light, its central token's verdict.
pub use crate::analysis::convexity::{central_token, Verdict};
pub use crate::analysis::rotation::rotate_quarter_turns;
pub use crate::analysis::{wrap_360, Interpreter};

// The syntax of angle lists and the solver budget every perception command shares.
pub use crate::analysis::interpretation::MULTIGRID_CYCLES;
pub use crate::analysis::parse_angles;

use super::solve::BoundarySource;
use super::source::{PictureInfo, PictureSource};
use crate::analysis::interpretation::analysis_solve_options;
use crate::analysis::{sweep, Sweep};
use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::grid::Mask;
use crate::io::{self, Stamp, TrueLight};
use crate::plot::Figure;
use crate::progress::Progress;
use crate::solver::SolveOptions;
use serde::{Serialize, Serializer};
use serde_json::Value;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The default slant of every assumed light, degrees from the line of sight.
pub const DEFAULT_SLANT_DEG: f64 = 45.0;

/// The default boundary: flat, since the analysed stimuli lie on a plane.
pub const DEFAULT_BOUNDARY: Boundary = Boundary::Flat;

/// A setting that failed its check: the name of its [`Config`] field and why. The command line
/// turns the field into its flag; everyone else may take the [`Error`] (`?` converts it).
#[derive(Debug)]
pub struct BadSetting {
    /// The field of the configuration, e.g. `"slant_deg"`.
    pub field: &'static str,
    /// What is wrong with it.
    pub error: Error,
}

impl From<BadSetting> for Error {
    fn from(bad: BadSetting) -> Error {
        bad.error
    }
}

/// Tags a check's failure with the field it checked.
pub(crate) fn field(name: &'static str, result: Result<()>) -> Result<(), BadSetting> {
    result.map_err(|error| BadSetting { field: name, error })
}

/// Where the engine solves: chosen by the picture ([`DomainSpec::Auto`], the default), a named
/// [`Domain`] or a mask file.
///
/// ```
/// use shadelab::pipeline::perception::DomainSpec;
/// let d: DomainSpec = "tokens".parse().unwrap();
/// assert_eq!(d.to_string(), "tokens");
/// assert_eq!("auto".parse::<DomainSpec>().unwrap(), DomainSpec::default());
/// assert!(matches!("mask.png".parse(), Ok(DomainSpec::Mask(_))));
/// assert!("mask.npy".parse::<DomainSpec>().is_err());
/// ```
#[derive(Debug, Clone, PartialEq, Default)]
pub enum DomainSpec {
    /// The targets where the picture's maker says they are objects on a backdrop that is no
    /// part of the surface (a rendered object, the hollow mask's face:
    /// [`Picture::on_backdrop`](super::source::Picture::on_backdrop)); the whole picture
    /// otherwise (a relief on a panel, a bare image).
    #[default]
    Auto,
    /// The whole picture or only its tokens.
    Named(Domain),
    /// A PNG mask of the picture's size, nonzero = inside.
    Mask(PathBuf),
}

impl FromStr for DomainSpec {
    type Err = Error;
    fn from_str(text: &str) -> Result<DomainSpec> {
        if text == "auto" {
            return Ok(DomainSpec::Auto);
        }
        if let Ok(d) = text.parse::<Domain>() {
            return Ok(DomainSpec::Named(d));
        }
        let path = Path::new(text);
        if io::extension(path) != "png" {
            return Err(Error::invalid(format!(
                "domain '{text}' is neither auto, image, tokens nor a .png mask"
            )));
        }
        Ok(DomainSpec::Mask(path.to_path_buf()))
    }
}

impl fmt::Display for DomainSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DomainSpec::Auto => f.write_str("auto"),
            DomainSpec::Named(d) => d.fmt(f),
            DomainSpec::Mask(path) => path.display().fmt(f),
        }
    }
}

impl DomainSpec {
    /// The named domain this stands for on a picture whose targets are (`on_backdrop`) or are
    /// not objects on a backdrop; `None` for a mask file.
    pub fn named(&self, on_backdrop: bool) -> Option<Domain> {
        match self {
            DomainSpec::Auto if on_backdrop => Some(Domain::Tokens),
            DomainSpec::Auto => Some(Domain::Image),
            DomainSpec::Named(d) => Some(*d),
            DomainSpec::Mask(_) => None,
        }
    }

    /// The domain's mask for `picture`, whose targets are (`on_backdrop`) or are not objects
    /// on a backdrop (a mask file is read and checked against its size).
    pub fn resolve(
        &self,
        picture: &TokenPicture,
        on_backdrop: bool,
        max_pixels: usize,
    ) -> Result<Mask> {
        match self {
            DomainSpec::Mask(path) => {
                let mask = io::read_mask(path, max_pixels)?;
                mask.check_same_size(
                    &format!("domain mask {} is", path.display()),
                    &picture.image,
                    "the image is",
                )?;
                if mask.count() == 0 {
                    return Err(Error::invalid(format!(
                        "domain mask {} is empty: no pixel to solve",
                        path.display()
                    )));
                }
                Ok(mask)
            }
            named => Ok(picture.domain(named.named(on_backdrop).unwrap_or_default())),
        }
    }
}

/// A picture and how to interpret it, as plain values.
#[derive(Debug, Clone)]
pub struct Config {
    /// The picture.
    pub source: PictureSource,
    /// The rendered stimulus's size in pixels (height, width), as NumPy's shape; only with a
    /// stimulus.
    pub size: Option<(usize, usize)>,
    /// Where the engine solves (default: [`DomainSpec::Auto`], the targets of an object on a
    /// backdrop, else the whole image).
    pub domain: DomainSpec,
    /// The boundary at the domain's rim (default: flat, a relief on a plane).
    pub boundary: BoundarySource,
    /// Slant of every assumed light, degrees from the line of sight (0 ≤ slant < 90).
    pub slant_deg: f64,
    /// Surface albedo; `None`: the stimulus's own, else the one that makes the background a
    /// surface facing the viewer.
    pub albedo: Option<f64>,
    /// Ambient level; `None`: the stimulus's own, else 0.
    pub ambient: Option<f64>,
    /// The solver settings (default: [`analysis_solve_options`], at most
    /// [`MULTIGRID_CYCLES`] multigrid cycles per solve, after which a solve that has not
    /// converged is repeated with Jacobi sweeps).
    pub solver: SolveOptions,
}

impl Config {
    /// The defaults for `source`.
    pub fn new(source: PictureSource) -> Config {
        Config {
            source,
            size: None,
            domain: DomainSpec::default(),
            boundary: BoundarySource::Named(DEFAULT_BOUNDARY),
            slant_deg: DEFAULT_SLANT_DEG,
            albedo: None,
            ambient: None,
            solver: analysis_solve_options(),
        }
    }

    /// Checks everything that needs no file, naming the first bad field.
    pub fn check(&self) -> Result<(), BadSetting> {
        field("source", self.source.check())?;
        if let Some((h, w)) = self.size {
            let ok = if self.source.stimulus.is_none() {
                Err(Error::invalid("a size applies to a rendered stimulus only"))
            } else if w == 0 || h == 0 {
                Err(Error::invalid(format!(
                    "size {} must be at least 1 pixel each way",
                    crate::message::SizeText::Pixels(h, w)
                )))
            } else {
                Ok(())
            };
            field("size", ok)?;
        }
        // The lighting's own checks, one value at a time with the others at valid values.
        let lit = |slant_deg, albedo, ambient| {
            Lighting {
                slant_deg,
                albedo,
                ambient,
            }
            .validate()
        };
        field("slant_deg", lit(self.slant_deg, 1.0, 0.0))?;
        if let Some(a) = self.albedo {
            field("albedo", lit(0.0, a, 0.0))?;
        }
        if let Some(a) = self.ambient {
            field("ambient", lit(0.0, 1.0, a))?;
        }
        // The solver's own checks, one value at a time with the others at valid values.
        let fine = analysis_solve_options();
        let solver = |o: SolveOptions| o.validate();
        field(
            "lambda",
            solver(SolveOptions {
                lambda: self.solver.lambda,
                ..fine
            }),
        )?;
        field(
            "tol",
            solver(SolveOptions {
                tol: self.solver.tol,
                ..fine
            }),
        )?;
        field("max_iter", solver(self.solver))
    }

    /// Checks everything that needs no file.
    pub fn validate(&self) -> Result<()> {
        Ok(self.check()?)
    }

    /// Reads or renders the picture (once: what was read with it is said through `progress`
    /// as soon as it is known) and resolves the domain, boundary, lighting and solver options.
    pub fn load(&self, progress: &dyn Progress) -> Result<Setup> {
        self.validate()?;
        let options = self.solver;
        let (loaded, _) = self.source.load_shaped(false, self.size)?;
        loaded.say_notes(progress);
        let labels = loaded.labels.as_ref().map(|(l, n)| (l, n.as_slice()));
        let mut picture = TokenPicture::from_image(loaded.luminance(), labels)
            .map_err(|e| self.naming_mask(e))?;
        // What the stimulus or the image's sidecar declares (the same reader for both).
        picture.albedo = loaded.declared.albedo;
        picture.ambient = loaded.declared.ambient;
        let max_pixels = self.source.max_pixels;
        let domain = self
            .domain
            .resolve(&picture, loaded.on_backdrop, max_pixels)?;
        let (w, h) = (picture.image.width(), picture.image.height());
        let boundary = self.boundary.resolve(w, h, max_pixels)?;
        let lighting = picture.lighting(&domain, self.slant_deg, self.albedo, self.ambient)?;
        // Shadow sits at the ambient level; stored as 8- or 16-bit codes or float32 it is a
        // code's width off it, which would decide the treatment of every shadowed pixel (in
        // the solver, data or not). Where the render's shadow is on record and the ambient
        // level is the one it declares, the record says which pixels are shadow (a lit pixel
        // may share the level's code: 19 of the crater's at 8 bits); elsewhere what the
        // picture cannot tell from the ambient level is the ambient level.
        let unlit = match self.ambient {
            None => loaded.unlit(max_pixels),
            Some(_) => None,
        };
        picture.image = loaded
            .quantum
            .settle(&picture.image, lighting.ambient, unlit.as_ref());
        picture.albedo = Some(lighting.albedo);
        picture.ambient = Some(lighting.ambient);
        let parameters = Parameters {
            slant_deg: lighting.slant_deg,
            albedo: lighting.albedo,
            ambient: lighting.ambient,
            boundary: self.boundary.to_string(),
            domain: self
                .domain
                .named(loaded.on_backdrop)
                .map_or_else(|| self.domain.to_string(), |d| d.to_string()),
            lambda: options.lambda,
            tol: options.tol,
            max_iter: options.max_iter,
            method: options.method.to_string(),
        };
        Ok(Setup {
            picture,
            domain,
            boundary,
            lighting,
            options,
            origin: loaded.origin,
            true_light: loaded.declared.light,
            parameters,
            input_note: loaded.input_note,
        })
    }

    /// Names the mask file in a token error, which otherwise does not say where the labels
    /// came from.
    fn naming_mask(&self, e: Error) -> Error {
        match (&self.source.mask, e) {
            (Some(path), Error::Invalid(m)) => {
                Error::invalid(format!("mask {}: {m}", path.display()))
            }
            (_, e) => e,
        }
    }
}

/// The settings an interpretation ran with, as reports record them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Parameters {
    /// Slant of every assumed light, degrees.
    pub slant_deg: f64,
    /// The albedo used.
    pub albedo: f64,
    /// The ambient level used.
    pub ambient: f64,
    /// The boundary, as given.
    pub boundary: String,
    /// The domain used: `image`, `tokens` (what `auto` chose, or as given) or the mask file.
    pub domain: String,
    /// Weight λ of the brightness term.
    pub lambda: f64,
    /// The solver's tolerance.
    pub tol: f64,
    /// The most iterations per solve.
    pub max_iter: usize,
    /// The solver's method.
    pub method: String,
}

/// A loaded picture ready to interpret.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The picture, its albedo and ambient set to the ones used.
    pub picture: TokenPicture,
    /// Where the engine solves.
    pub domain: Mask,
    /// The boundary at the domain's rim.
    pub boundary: Boundary,
    /// What is assumed besides the light's tilt.
    pub lighting: Lighting,
    /// The solver options.
    pub options: SolveOptions,
    /// Where the picture came from, for reports.
    pub origin: Value,
    /// The light the picture was rendered under, when its stimulus or sidecar says.
    pub true_light: Option<TrueLight>,
    /// The settings, for reports.
    pub parameters: Parameters,
    /// The note that the picture's codes were taken as sRGB, to say once the run succeeded
    /// ([`Picture::input_note`](super::source::Picture::input_note)).
    pub input_note: Option<crate::message::Message>,
}

impl Setup {
    /// The scene to interpret.
    pub fn scene(&self) -> Scene<'_> {
        Scene {
            image: &self.picture.image,
            domain: &self.domain,
            boundary: &self.boundary,
            tokens: &self.picture.tokens,
        }
    }

    /// The sweep of the scene over `tilts`, one step of `progress` (a stage called `what`) per
    /// tilt.
    pub fn sweep(&self, tilts: &[f64], progress: &dyn Progress, what: &str) -> Result<Sweep> {
        progress.start(tilts.len() as u64, what);
        let result = sweep(&self.scene(), tilts, &self.lighting, &self.options, &|| {
            progress.advance(1)
        });
        progress.finish();
        result
    }

    /// What every perception report begins with, for `command`.
    pub fn header(&self, command: &'static str) -> Header {
        Header {
            stamp: Stamp::of(command),
            picture: PictureInfo::new(
                &self.origin,
                self.picture.image.width(),
                self.picture.image.height(),
            ),
            true_light: self.true_light,
            parameters: self.parameters.clone(),
        }
    }
}

/// What every perception report begins with: the program, the command, the conventions, the
/// picture and the settings.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Header {
    /// The program, its version and the command.
    #[serde(flatten)]
    pub stamp: Stamp,
    /// The conventions, where the picture came from and its size.
    #[serde(flatten)]
    pub picture: PictureInfo,
    /// The light the picture was rendered under (its stimulus's or sidecar's), beside the
    /// assumed ones; `null` when unknown.
    pub true_light: Option<TrueLight>,
    /// The settings used.
    pub parameters: Parameters,
}

/// Serialises a sweep as its interpretations alone.
pub(crate) fn interpretations_of<S: Serializer>(sweep: &Sweep, s: S) -> Result<S::Ok, S::Error> {
    <[Interpretation]>::serialize(&sweep.interpretations, s)
}

/// Writes a perception report's files into `dir`: `figure` as `<stem>.png` and `<stem>.svg`,
/// the table `csv` as `csv_file` and `report` as JSON to `report_file`.
pub(crate) fn write_outputs(
    dir: &Path,
    (stem, figure): (&str, &Figure),
    (csv_file, csv): (&str, &str),
    report_file: &str,
    report: &impl Serialize,
) -> Result<()> {
    figure.write_png(&dir.join(format!("{stem}.png")))?;
    figure.write_svg(&dir.join(format!("{stem}.svg")))?;
    io::write_text(&dir.join(csv_file), csv)?;
    let value = serde_json::to_value(report)
        .map_err(|e| Error::Compute(format!("cannot serialise the report: {e}")))?;
    io::write_json(&dir.join(report_file), &value)
}
