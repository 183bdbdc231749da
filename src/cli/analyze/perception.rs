//! What `analyze prior-sweep` and `analyze observer` share: the picture (an image or a
//! stimulus), the solve domain, boundary, assumed lighting and solver settings.

use super::{CliError, Global, Source};
use serde_json::{json, Map, Value};
use shadelab::analysis::{Domain, Lighting, Picture};
use shadelab::boundary::{Boundary, BOUNDARY_NAMES};
use shadelab::grid::Mask;
use shadelab::io;
use shadelab::solver::{Method, SolveOptions};
use shadelab::stimulus;
use shadelab::visual_size::{parse_pair, SizeRequest};
use std::path::Path;

/// The picture and how to interpret it.
#[derive(Debug, clap::Args)]
pub struct PictureArgs {
    #[command(flatten)]
    pub source: Source,
    /// Size of the rendered stimulus in pixels: N (square) or WxH (with --stimulus).
    #[arg(
        long,
        value_name = "N|WxH",
        requires = "stimulus",
        allow_hyphen_values = true
    )]
    pub size: Option<String>,
    /// Where the engine solves: image (the whole picture, a relief on a plane), tokens (only
    /// the target regions), or a PNG mask (nonzero = inside).
    #[arg(long, value_name = "image|tokens|PNG", default_value = "image")]
    pub domain: String,
    /// Boundary condition at the domain's rim: flat (the default: these stimuli lie on a
    /// plane), free, occluding, or an H×W×3 .npy of normals for the rim.
    #[arg(
        long,
        value_name = "flat|free|occluding|FILE.npy",
        default_value = "flat"
    )]
    pub boundary: String,
    /// Slant of every assumed light, degrees from the line of sight (0 ≤ S < 90).
    #[arg(
        long,
        value_name = "S",
        default_value_t = 45.0,
        allow_hyphen_values = true
    )]
    pub slant: f64,
    /// Surface albedo (default: the stimulus's own, else the one that makes the background
    /// a surface facing the viewer).
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub albedo: Option<f64>,
    /// Ambient level, the brightness of shadowed surfaces (default: the stimulus's own, else 0).
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub ambient: Option<f64>,
    /// Weight λ of the brightness term of each solve (> 0).
    #[arg(
        long = "lambda",
        value_name = "L",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub lambda: f64,
    /// Solver tolerance (see `solve --tol`).
    #[arg(
        long,
        value_name = "T",
        default_value_t = 1e-6,
        allow_hyphen_values = true
    )]
    pub tol: f64,
    /// Most multigrid cycles per solve; a solve that has not converged by then is repeated
    /// with Jacobi sweeps (same answer, slower).
    #[arg(long, value_name = "N", default_value_t = shadelab::analysis::interpretation::MULTIGRID_CYCLES, allow_hyphen_values = true)]
    pub max_iter: usize,
}

/// A loaded picture ready to interpret.
pub struct Loaded {
    pub picture: Picture,
    pub domain: Mask,
    pub domain_name: String,
    pub boundary: Boundary,
    pub lighting: Lighting,
    pub options: SolveOptions,
    pub origin: Value,
}

impl PictureArgs {
    /// Checks everything that needs no file.
    pub fn check(&self) -> Result<SolveOptions, CliError> {
        self.source.check()?;
        let options = SolveOptions {
            lambda: self.lambda,
            tol: self.tol,
            max_iter: self.max_iter,
            method: Method::default(),
        };
        options.validate()?;
        if !(self.slant.is_finite() && (0.0..90.0).contains(&self.slant)) {
            return Err(CliError::usage(format!(
                "--slant {} must be in 0..90 degrees (90 is grazing)",
                self.slant
            )));
        }
        for (flag, v) in [("--albedo", self.albedo), ("--ambient", self.ambient)] {
            if let Some(v) = v {
                let ok = v.is_finite()
                    && if flag == "--albedo" {
                        v > 0.0
                    } else {
                        v >= 0.0
                    };
                if !ok {
                    return Err(CliError::usage(format!(
                        "{flag} {v} must be a {} number",
                        if flag == "--albedo" {
                            "positive"
                        } else {
                            "non-negative"
                        }
                    )));
                }
            }
        }
        if let Some(size) = &self.size {
            parse_size(size)?;
        }
        Ok(options)
    }

    /// Reads or renders the picture and resolves the domain, boundary and lighting.
    pub fn load(&self, global: &Global) -> Result<Loaded, CliError> {
        let options = self.check()?;
        let (mut picture, origin) = match &self.source.stimulus {
            Some(name) => self.render(name, global)?,
            None => {
                let input = self.source.load(false, global)?;
                let image = input.luminance();
                let picture = match &input.labels {
                    Some((labels, names)) => Picture::from_image(image, Some((labels, names))),
                    None => Picture::from_image(image, None),
                }
                .map_err(|e| with_mask(e, &self.source))?;
                (picture, input.origin)
            }
        };
        let (w, h) = (picture.image.width(), picture.image.height());
        let (domain, domain_name) = match self.domain.as_str() {
            "image" | "tokens" => {
                let d: Domain = self.domain.parse()?;
                (picture.domain(d), d.to_string())
            }
            other => {
                let path = Path::new(other);
                if io::extension(path) != "png" {
                    return Err(CliError::usage(format!(
                        "--domain '{other}' is neither image, tokens nor a .png mask"
                    )));
                }
                let mask = io::read_mask(path, global.max_pixels)?;
                if (mask.width(), mask.height()) != (w, h) {
                    return Err(CliError::usage(format!(
                        "--domain {other} is {}x{} but the image is {w}x{h}",
                        mask.width(),
                        mask.height()
                    )));
                }
                if mask.count() == 0 {
                    return Err(CliError::usage(format!(
                        "--domain {other} is empty: no pixel to solve"
                    )));
                }
                (mask, other.to_string())
            }
        };
        let boundary = self.read_boundary(w, h, global)?;
        let lighting = picture.lighting(&domain, self.slant, self.albedo, self.ambient)?;
        picture.albedo = Some(lighting.albedo);
        picture.ambient = Some(lighting.ambient);
        Ok(Loaded {
            picture,
            domain,
            domain_name,
            boundary,
            lighting,
            options,
            origin,
        })
    }

    fn render(&self, name: &str, global: &Global) -> Result<(Picture, Value), CliError> {
        let given: Map<String, Value> = shadelab::params::Params::parse_pairs(&self.source.set)?;
        let size = SizeRequest {
            ppd: self.source.ppd,
            shape: self.size.as_deref().map(parse_size).transpose()?,
            ..Default::default()
        };
        let seed = self.source.seed.unwrap_or(0);
        let (request, mut output) =
            stimulus::generate(name, &given, &size, seed, global.max_pixels)?;
        if let Some(path) = &self.source.mask {
            let labels = io::read_labels(path, global.max_pixels)?;
            let (w, h) = output.pixels.size();
            if (labels.width(), labels.height()) != (w, h) {
                return Err(CliError::usage(format!(
                    "mask {} is {}x{} but the image is {w}x{h}",
                    path.display(),
                    labels.width(),
                    labels.height()
                )));
            }
            output.targets = Some(stimulus::Targets {
                labels,
                names: Vec::new(),
            });
        }
        let picture =
            Picture::from_stimulus(&request, &output).map_err(|e| with_mask(e, &self.source))?;
        let origin = json!({
            "stimulus": name,
            "parameters": request.params.to_json(),
            "seed": seed,
            "geometry": request.geometry,
            "notes": output.notes,
        });
        Ok((picture, origin))
    }

    fn read_boundary(&self, w: usize, h: usize, global: &Global) -> Result<Boundary, CliError> {
        let text = self.boundary.as_str();
        if BOUNDARY_NAMES.contains(&text) {
            return Ok(Boundary::named(text)?);
        }
        let path = Path::new(text);
        if io::extension(path) != "npy" {
            return Err(CliError::usage(format!(
                "--boundary '{text}' is neither {} nor a .npy file of normals",
                BOUNDARY_NAMES.join(", ")
            )));
        }
        let normals = io::read_normals(path, global.max_pixels)?;
        if (normals.width(), normals.height()) != (w, h) {
            return Err(CliError::usage(format!(
                "--boundary {text} is {}x{} but the image is {w}x{h}",
                normals.width(),
                normals.height()
            )));
        }
        Ok(Boundary::Given(normals))
    }
}

/// Names the mask file in a token error, which otherwise does not say where the labels came
/// from.
fn with_mask(e: shadelab::Error, source: &Source) -> CliError {
    match (&source.mask, e) {
        (Some(path), shadelab::Error::Invalid(m)) => {
            CliError::usage(format!("mask {}: {m}", path.display()))
        }
        (_, e) => e.into(),
    }
}

/// `N` or `WxH`.
pub fn parse_size(text: &str) -> Result<(usize, usize), CliError> {
    let (w, h) = parse_pair::<usize>(text, "--size")?;
    if w == 0 || h == 0 {
        return Err(CliError::usage(format!(
            "--size {text} must be at least 1 pixel each way"
        )));
    }
    Ok((w, h))
}

/// The solve parameters for a report.
pub fn parameters(loaded: &Loaded, args: &PictureArgs) -> Value {
    json!({
        "slant_deg": loaded.lighting.slant_deg,
        "albedo": loaded.lighting.albedo,
        "ambient": loaded.lighting.ambient,
        "boundary": args.boundary,
        "domain": loaded.domain_name,
        "lambda": loaded.options.lambda,
        "tol": loaded.options.tol,
        "max_iter": loaded.options.max_iter,
        "method": loaded.options.method.to_string(),
    })
}
