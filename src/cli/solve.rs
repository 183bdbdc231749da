//! `shadelab solve`: shape from shading on one grayscale image, into an output folder.

use super::flags::{input_gamma, usage, OutFolder, SolverFlags};
use super::output::Output;
use super::{progress::Bar, CliError, CliResult, Global};
use shadelab::pipeline::solve::check_albedo;
use shadelab::pipeline::solve::{self, LightChoice, SolveConfig, SolveRecord};
use shadelab::BrdfSpec;
use shadelab::{Method, SolveOptions};
use shadelab::{NonConvergence, ReconstructOptions};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `solve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The image: an 8/16-bit PNG, a JPEG or a 16-bit TIFF (decoded as --input-gamma says) or an H×W .npy (float 0..1, or uint8/uint16 scaled by their largest value; H×W×3 RGB becomes luminance).
    pub image: PathBuf,
    #[arg(long, value_name = "auto|srgb|linear|G", default_value = "auto", help = super::flags::INPUT_GAMMA_HELP)]
    pub input_gamma: String,
    /// The light: x,y,z or tilt=T,slant=S or a name, with z > 0; or `estimate` to estimate it
    /// (and the albedo) from the image.
    #[arg(long, value_name = "L|estimate", allow_hyphen_values = true)]
    pub light: String,
    /// The object's mask (PNG, nonzero = inside); default: the whole image.
    #[arg(long, value_name = "PNG")]
    pub mask: Option<PathBuf>,
    /// Boundary condition: occluding, flat, free, limb (occluding where the shading allows a
    /// limb, elsewhere the outline's direction at the slant the brightness gives), or an H×W×3
    /// .npy of normals for the rim.
    #[arg(
        long,
        value_name = "occluding|flat|free|limb|FILE.npy",
        default_value = "occluding"
    )]
    pub boundary: String,
    /// The reflectance model (lambertian, blinn-phong, oren-nayar).
    #[arg(long, value_name = "NAME", default_value = "lambertian")]
    pub brdf: String,
    /// Surface albedo (default 1, or the estimate with --light estimate); or `estimate`: the
    /// bright tail of the brightness on the mask extrapolated to the brightest normal, the
    /// image divided by it and capped at 1 (the same shape however the image was scaled).
    #[arg(long, value_name = "A|estimate", allow_hyphen_values = true)]
    pub albedo: Option<String>,
    /// Where the image was clipped: pixels at or above this brightness (0..1, as read) carry
    /// no brightness term, only smoothness; `auto`: the clipped plateau that --albedo estimate
    /// finds (pixels tied at the image's maximum), none without it; `none`: no pixel is
    /// clipped.
    #[arg(
        long,
        value_name = "auto|none|LEVEL",
        default_value = "auto",
        allow_hyphen_values = true
    )]
    pub saturation: String,
    /// Iteration [default: nested-lm]: nested-lm (the integrable energy minimised coarse to
    /// fine, each grid starting from its half-size grid's minimum: the normals of one surface,
    /// about 1.3° from the truth on a 256² sphere where multigrid is 6.5° off, at 50–150× its
    /// time), multigrid (Ikeuchi–Horn: Jacobi's answer in a few cycles, the fast choice),
    /// jacobi (stable, slow), literal (R at the current value; unstable, for study),
    /// integrable (depth and gradients solved together from the multigrid answer, Horn 1990)
    /// or integrable-lm (nested-lm's energy minimised on the full grid only: its reference,
    /// slower).
    #[arg(
        long,
        value_name = "nested-lm|multigrid|jacobi|literal|integrable|integrable-lm"
    )]
    pub method: Option<String>,
    #[command(flatten)]
    pub solver: SolverFlags,
    #[command(flatten)]
    pub output: OutFolder,
}

/// Runs `solve`: flags → [`SolveConfig`] → [`solve::run`] → the output folder.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let config = config(&args, global)?;
    let out = Output::new(global);
    // The folder is claimed before the long part, so an unwritable one fails at once.
    let dest = super::output_to(&args.output.out, global, config.files());
    let report = solve::run_into(&config, &dest, &Bar::new(global.quiet))?;
    let target = dest.path().to_path_buf();
    let solver = &report.solver;
    let unit = solver.iteration_unit;
    if !solver.converged {
        out.warn(format!(
            "the {} solve did not converge within --max-iter {} {unit}: the last update \
             {:.3e} is above --tol {:.3e}; raise --max-iter or --tol",
            solver.method, report.parameters.max_iter, solver.last_update, config.options.tol
        ));
    }
    out.wrote(&target, started.elapsed().as_secs_f64());
    let state = if solver.converged {
        "converged"
    } else {
        "did NOT converge"
    };
    let light = &report.light;
    let mut text = format!(
        "{state} after {} {unit}, last update {:.2e}\n\
         light: tilt {:.1}° slant {:.1}°{}\n",
        solver.iterations,
        solver.last_update,
        light.tilt_deg,
        light.slant_deg,
        if light.estimated { " (estimated)" } else { "" },
    );
    if let Some(warning) = light.estimate.and_then(|e| e.warning) {
        out.warn(warning);
    }
    if let Some(e) = &light.estimate {
        text += &format!(
            "estimated by {}: tilt ± {:.1}°, slant {}\n",
            e.method.name(),
            e.tilt_se_deg,
            e.slant_se_deg
                .map_or("error not given".to_string(), |s| format!("± {s:.1}°"))
        );
    }
    if let Some(limb) = &report.boundary.limb {
        text += &format!(
            "limb test: {} rim pixels rule out a limb (held at their shading's slant, or free \
             where clipped); dark level {:.4}\n",
            limb.not_limb, limb.dark_level
        );
    }
    if let Some(t) = &light.true_light {
        text += &format!(
            "true light (sidecar): tilt {:.1}° slant {:.1}°\n",
            t.tilt_deg, t.slant_deg
        );
    }
    text += &format!(
        "albedo {:.4}; {} pixels solved; depth {:.3} to {:.3} px\n",
        report.parameters.albedo,
        report.input.mask_pixels,
        report.depth_range[0],
        report.depth_range[1]
    );
    out.results(&text, &report)
}

/// The library configuration from the flags; every flag is checked before any file is read.
fn config(args: &Args, global: &Global) -> Result<SolveConfig, CliError> {
    let input_encoding = input_gamma(&args.input_gamma)?;
    let asked = args.method.as_deref().map(str::parse).transpose()?;
    let (method, method_source) = Method::chosen(asked);
    let mut solve = SolveOptions::for_method(method);
    args.solver.apply(&mut solve)?;
    let options = ReconstructOptions::from_solve(&solve, NonConvergence::Report);
    options
        .validate()
        .map_err(|e| CliError::usage(e.to_string()))?;
    let (albedo, albedo_estimate) = match args.albedo.as_deref() {
        None => (None, false),
        Some("estimate") => (None, true),
        Some(text) => {
            let a: f64 = text.parse().map_err(|_| {
                CliError::usage(format!(
                    "--albedo: {text:?} is neither a number nor `estimate`"
                ))
            })?;
            check_albedo(a).map_err(|e| usage("--albedo", e))?;
            (Some(a), false)
        }
    };
    let light: LightChoice = args.light.parse().map_err(|e| usage("--light", e))?;
    let boundary = args.boundary.parse().map_err(|e| usage("--boundary", e))?;
    Ok(SolveConfig {
        image: args.image.clone(),
        input_encoding,
        mask: args.mask.clone(),
        light,
        boundary,
        brdf: BrdfSpec::named(&args.brdf)?,
        albedo,
        albedo_estimate,
        saturation: args
            .saturation
            .parse()
            .map_err(|e| usage("--saturation", e))?,
        options,
        method_source,
        max_pixels: global.max_pixels,
        record: SolveRecord {
            light: args.light.clone(),
            boundary: args.boundary.clone(),
            out: args.output.out.display().to_string(),
        },
    })
}
