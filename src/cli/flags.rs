//! Flag groups that several subcommands share, each one clap `Args` struct to flatten, and the
//! translation of the library's complaints about a setting back into the flag that set it.
//! Defaults are the library's: a flag left out leaves the library's value in place.

use super::CliError;
use shadelab::pipeline::perception::MULTIGRID_CYCLES;
use shadelab::pipeline::perception::{BadSetting, DomainSpec, DEFAULT_BOUNDARY};
use shadelab::pipeline::solve::BoundarySource;
use shadelab::pipeline::solve::{
    INTEGRABLE_LM_MAX_STEPS, INTEGRABLE_MAX_ITER, JACOBI_MAX_SWEEPS, MULTIGRID_MAX_CYCLES,
};
use shadelab::{Method, SolveOptions};

/// The solver's settings: λ, the tolerance and the iteration cap (left out, the cap is the one
/// the library's configuration of the command already holds).
#[derive(Debug, Clone, clap::Args)]
pub struct SolverFlags {
    /// Weight λ of the brightness term (0.001 to 1000, where the solvers are checked to
    /// converge; Jacobi sweeps diverge above about 1).
    #[arg(
        long = "lambda",
        value_name = "L",
        default_value_t = SolveOptions::default().lambda,
        allow_hyphen_values = true
    )]
    pub lambda: f64,
    #[arg(long, value_name = "T", allow_hyphen_values = true, help = tol_help())]
    pub tol: Option<f64>,
    /// Stop a solve after this many sweeps, or cycles for multigrid.
    #[arg(long, value_name = "N", allow_hyphen_values = true, help = max_iter_help())]
    pub max_iter: Option<usize>,
}

/// The `--tol` help, with the library's defaults.
fn tol_help() -> String {
    format!(
        "Stop when the largest change of f or g in a Jacobi sweep or step is below this (for \
         multigrid: the change the next Jacobi sweep would make); 1e-12 to 0.1 [default: {:e} \
         for nested-lm (its finest grid's steps), {:e} for the others]",
        Method::NestedLm.default_tol(),
        Method::Multigrid.default_tol()
    )
}

/// The `--max-iter` help, with the library's defaults.
fn max_iter_help() -> String {
    format!(
        "Stop a solve after this many sweeps, or cycles for multigrid [default: {MULTIGRID_CYCLES} \
         cycles in the analyses, which repeat a solve that has not converged with Jacobi sweeps; \
         in solve and eval, {MULTIGRID_MAX_CYCLES} cycles for multigrid, {JACOBI_MAX_SWEEPS} \
         sweeps for jacobi and literal, {INTEGRABLE_MAX_ITER} iterations for integrable, \
         {INTEGRABLE_LM_MAX_STEPS} steps for integrable-lm and nested-lm (on the finest grid)]"
    )
}

impl SolverFlags {
    /// Sets λ and (when given) the tolerance and the cap of `options`, each checked alone
    /// ([`SolveOptions::validate`]) so that a refusal names its own flag and the range.
    pub fn apply(&self, options: &mut SolveOptions) -> Result<(), CliError> {
        let alone = |flag: &str, set: &dyn Fn(&mut SolveOptions)| {
            let mut one = SolveOptions::default();
            set(&mut one);
            one.validate().map_err(|e| usage(flag, e))
        };
        alone("--lambda", &|o| o.lambda = self.lambda)?;
        if let Some(t) = self.tol {
            alone("--tol", &|o| o.tol = t)?;
        }
        if let Some(n) = self.max_iter {
            alone("--max-iter", &|o| o.max_iter = n)?;
        }
        options.lambda = self.lambda;
        if let Some(t) = self.tol {
            options.tol = t;
        }
        if let Some(n) = self.max_iter {
            options.max_iter = n;
        }
        Ok(())
    }
}

/// What the analyses assume about the picture besides the light's tilt.
#[derive(Debug, Clone, clap::Args)]
pub struct AnalysisFlags {
    /// Where the engine solves: auto (the targets of an object on a backdrop, such as a
    /// rendered object or the hollow mask's face; else the whole picture), image (the whole
    /// picture, a relief on a plane), tokens (only the target regions), or a PNG mask
    /// (nonzero = inside).
    #[arg(long, value_name = "auto|image|tokens|PNG", default_value_t = DomainSpec::default().to_string())]
    pub domain: String,
    /// Boundary condition at the domain's rim: flat (the default: these stimuli lie on a
    /// plane), free, occluding, or an H×W×3 .npy of normals for the rim.
    #[arg(
        long,
        value_name = "flat|free|occluding|FILE.npy",
        default_value_t = DEFAULT_BOUNDARY.name().to_string()
    )]
    pub boundary: String,
    /// Slant of every assumed light, degrees from the line of sight (0 ≤ S < 90).
    #[arg(
        long,
        value_name = "S",
        default_value_t = shadelab::pipeline::perception::DEFAULT_SLANT_DEG,
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
}

impl AnalysisFlags {
    /// The domain, parsed.
    pub fn domain(&self) -> Result<DomainSpec, CliError> {
        self.domain.parse().map_err(|e| usage("--domain", e))
    }

    /// The boundary, parsed.
    pub fn boundary(&self) -> Result<BoundarySource, CliError> {
        self.boundary.parse().map_err(|e| usage("--boundary", e))
    }
}

/// The help of `--input-gamma`, shared by every command that reads a picture.
pub const INPUT_GAMMA_HELP: &str = "How the picture's codes encode luminance: auto (a PNG's sRGB or gAMA chunk; without one, a 16-bit PNG, a TIFF, a .npy and shadelab's own pictures are linear, and an 8-bit PNG or a JPEG is decoded as sRGB, with a note), srgb, linear, or G, the file's gamma (luminance = code^G, 0.1 to 10); anything but auto overrides the file's chunk and a sidecar's gamma";

/// The encoding `--input-gamma` names.
pub fn input_gamma(text: &str) -> Result<shadelab::InputEncoding, CliError> {
    text.parse().map_err(|e| usage("--input-gamma", e))
}

/// Angles in degrees from `START:STOP:STEP` or a list, for `flag`.
pub fn angles(text: &str, flag: &str) -> Result<Vec<f64>, CliError> {
    Ok(shadelab::pipeline::perception::parse_angles(text, flag)?)
}

/// A usage error about `flag`.
pub fn usage(flag: &str, e: shadelab::Error) -> CliError {
    CliError::usage(format!("{flag}: {e}"))
}

/// A library message with each setting it names said as its flag.
pub fn worded(message: &shadelab::Message) -> String {
    use shadelab::Setting;
    message.render(|setting, words| match setting {
        Setting::Mask => "--mask".into(),
        Setting::Ppd => "--ppd".into(),
        Setting::InputGamma => "--input-gamma".into(),
        Setting::Keys => "--keys BUMP,DIMPLE".into(),
        Setting::Lambda => format!("{words} (--lambda)"),
        Setting::JacobiMethod => format!("{words} (--method jacobi)"),
        Setting::IncludeSimulated => "--include-simulated".into(),
        Setting::MixedDesigns => "--mixed-designs".into(),
        _ => words.into(),
    })
}

/// The flag behind each configuration field the pipelines name.
const FIELD_FLAGS: &[(&str, &str)] = &[
    ("size", "--size"),
    ("slant_deg", "--slant"),
    ("albedo", "--albedo"),
    ("ambient", "--ambient"),
    ("lambda", "--lambda"),
    ("tol", "--tol"),
    ("max_iter", "--max-iter"),
    ("tilts", "--tilts"),
    ("binding", "--binding"),
    ("rotations", "--rotations"),
    ("prior_tilt_deg", "--prior-tilt"),
    ("kappas", "--prior-kappa"),
    ("convexity_bias", "--convexity-bias"),
    ("noise", "--noise"),
    ("lapse", "--lapse"),
    ("repeats", "--repeats"),
    ("practice", "--practice"),
    ("seed", "--seed"),
    ("ppd", "--ppd"),
    ("viewing_distance_cm", "--viewing-distance"),
    ("visual_size", "--visual-size"),
    ("keys", "--keys"),
    ("break_every", "--break-every"),
    ("save_url", "--save-url"),
    ("completion_url", "--completion-url"),
];

/// A bad setting, named by its flag.
pub fn setting(bad: BadSetting) -> CliError {
    match FIELD_FLAGS.iter().find(|(field, _)| *field == bad.field) {
        Some((_, flag)) => usage(flag, bad.error),
        None => bad.error.into(),
    }
}

/// The `--out` folder of a command that writes one: the output-set rule stated in one place.
#[derive(Debug, Clone, clap::Args)]
pub struct OutFolder {
    /// Output folder (written whole or not at all; it replaces only the files shadelab writes and keeps every other file).
    #[arg(long, value_name = "DIR")]
    pub out: std::path::PathBuf,
}
