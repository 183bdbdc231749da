//! `shadelab render`: one stimulus or surface to a file with its sidecar.

use super::{CliError, CliResult, Global};
use clap::builder::TypedValueParser;
use serde_json::Value;
use shadelab::parse_size;
use shadelab::pipeline::render::{self, RenderConfig};
use shadelab::stimulus::Range;
use shadelab::BitDepth;
use shadelab::{Error, NoProgress};
use std::path::{Path, PathBuf};

/// Arguments of `render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// What to render (see `shadelab list`); optional with --spec.
    pub name: Option<String>,
    /// A JSON spec naming the stimulus and its parameters, or the sidecar of an earlier render
    /// (which reproduces it, files and all); flags given here override it.
    #[arg(long, value_name = "FILE.json")]
    pub spec: Option<PathBuf>,
    /// Set a parameter (repeatable); `shadelab describe NAME` lists them.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = utf8_text())]
    pub set: Vec<String>,
    /// The light: x,y,z or tilt=T,slant=S or a name (front, above, below, left, right, above-left, above-right).
    #[arg(long, value_name = "L", allow_hyphen_values = true)]
    pub light: Option<String>,
    /// The reflectance model (lambertian, blinn-phong, oren-nayar).
    #[arg(long, value_name = "NAME")]
    pub brdf: Option<String>,
    /// The space of a reflectance-map figure: pq (gradient space) or fg (stereographic); the same as --set space=…
    #[arg(long, value_name = "pq|fg")]
    pub space: Option<String>,
    /// Size in pixels: N (square) or WxH (width first); the whole stimulus scales to fill it (ppd
    /// derived; another aspect adds field on the longer side). With --ppd: that scale, and more or less field.
    #[arg(long, value_name = "N|WxH", conflicts_with_all = ["width", "height"], allow_hyphen_values = true)]
    pub size: Option<String>,
    /// Width in pixels (with --height).
    #[arg(long, requires = "height", allow_hyphen_values = true)]
    pub width: Option<usize>,
    /// Height in pixels (with --width).
    #[arg(long, requires = "width", allow_hyphen_values = true)]
    pub height: Option<usize>,
    /// Visual size in degrees: D (square) or WxH (width first; JSON specs and sidecars write [h, w]).
    #[arg(long, value_name = "DEG|WxH", allow_hyphen_values = true)]
    pub visual_size: Option<String>,
    /// Pixels per degree of visual angle.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub ppd: Option<f64>,
    /// Seed for random layouts (recorded in the sidecar).
    #[arg(long, allow_hyphen_values = true)]
    pub seed: Option<u64>,
    /// Also write the ground-truth layers: FILE_depth.npy, FILE_normals.npy, FILE_shading.npy (FILE_mask.png, the target mask, is always written)
    #[arg(long)]
    pub layers: bool,
    /// Bits per channel of PNG output [default: 16, or the sidecar's].
    #[arg(long, value_name = "8|16", value_parser = clap::builder::PossibleValuesParser::new(["8", "16"]).map(|s| if s == "8" { 8u8 } else { 16u8 }))]
    pub bit_depth: Option<u8>,
    /// Display gamma for PNG output (recorded); default: linear values.
    #[arg(long, value_name = "G", allow_hyphen_values = true)]
    pub gamma: Option<f64>,
    /// Value range of float output: unit (0..1) or psychopy (-1..1) [default: unit, or the
    /// sidecar's].
    #[arg(long, value_name = "unit|psychopy", value_parser = ["unit", "psychopy"])]
    pub range: Option<String>,
    /// A display (PNG output): its codes are written through its model, the sidecar records
    /// each target's cd/m². FILE: shadelab's display JSON, a PsychoPy monitor file or a
    /// photometer CSV (code,luminance); see docs/display.md.
    #[arg(long, value_name = "FILE", conflicts_with_all = ["gamma", "bit_depth", "range"])]
    pub display: Option<PathBuf>,
    /// The cd/m² the stimulus's 0..1 is shown at, with --display: LO,HI or
    /// background=B,michelson=C [default: the display's black to white].
    #[arg(long, value_name = "LO,HI", requires = "display")]
    pub luminance: Option<String>,
    /// Output file: .png (16-bit by default), .npy (float32), .mat (MATLAB v5) or .npz (NumPy) bundles of img, target_mask and every parameter, or .svg (vector stimuli); the sidecar goes beside it as .json.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Text of a flag such as `--set KEY=VALUE`, refused with a message naming the flag when it is
/// not UTF-8: parameter values (mesh and depth-map paths among them) are recorded as text in
/// the sidecar.
pub fn utf8_text() -> impl TypedValueParser<Value = String> {
    clap::builder::OsStringValueParser::new().try_map(|text| {
        text.into_string().map_err(|_| {
            "not valid UTF-8 (parameter values are recorded as text in the sidecar; rename the file)"
        })
    })
}

/// Runs `render`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let spec = args
        .spec
        .as_deref()
        .map(RenderConfig::from_spec_file)
        .transpose()?;
    let mut config = match (&args.name, spec) {
        (Some(n), Some(s)) if *n != s.stimulus => {
            return Err(CliError::usage(format!(
                "the name '{n}' disagrees with the spec's stimulus '{}'",
                s.stimulus
            )))
        }
        (_, Some(s)) => s,
        (Some(n), None) => RenderConfig::new(n.as_str()),
        (None, None) => {
            return Err(CliError::usage(
                "name what to render (see `shadelab list`) or give --spec FILE.json",
            ))
        }
    };
    config
        .params
        .extend(shadelab::Params::parse_pairs(&args.set)?);
    if let Some(l) = &args.light {
        config
            .params
            .insert("light".into(), Value::from(l.as_str()));
    }
    if let Some(b) = &args.brdf {
        config.params.insert("brdf".into(), Value::from(b.as_str()));
    }
    if let Some(space) = &args.space {
        config.set_space(space).map_err(|e| match e {
            Error::Invalid(m) => CliError::usage(format!("--space: {m}")),
            other => other.into(),
        })?;
    }
    if let Some(s) = &args.size {
        config.size.set_shape(parse_size::<usize>(s, "--size")?);
    }
    if let (Some(w), Some(h)) = (args.width, args.height) {
        if w == 0 || h == 0 {
            return Err(CliError::usage(format!(
                "--width {w} --height {h}: both sides must be at least 1 pixel"
            )));
        }
        config.size.set_shape((h, w));
    }
    if let Some(v) = &args.visual_size {
        config.size.visual_size = Some(parse_size::<f64>(v, "--visual-size")?);
    }
    if args.ppd.is_some() {
        config.size.ppd = args.ppd;
    }
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    // A flag given overrides what a sidecar recorded; the rest keeps the recorded values (or
    // the defaults: 16 bits, no gamma, 0..1, no layers).
    let export = &mut config.export;
    match args.bit_depth {
        Some(8) => export.bit_depth = BitDepth::Eight,
        Some(_) => export.bit_depth = BitDepth::Sixteen,
        None => {}
    }
    if args.gamma.is_some() {
        export.gamma = args.gamma;
    }
    match args.range.as_deref() {
        Some("psychopy") => export.range = Range::Psychopy,
        Some(_) => export.range = Range::Unit,
        None => {}
    }
    if let Some(path) = &args.display {
        export.display = Some(shadelab::read_display(path)?);
    }
    if let Some(text) = &args.luminance {
        let mapping = text
            .parse()
            .map_err(|e| super::flags::usage("--luminance", e))?;
        export.luminance = Some(mapping);
    }
    export.layers |= args.layers;
    // A value given as a flag that the output's format cannot take is named by its flag.
    if args.range.is_some() {
        export
            .check_range(&args.out)
            .map_err(|e| super::flags::usage("--range", e))?;
    }
    if args.gamma.is_some() {
        export
            .check_gamma(&args.out)
            .map_err(|e| super::flags::usage("--gamma", e))?;
    }
    if args.display.is_some() {
        // The display and the format first, then the luminance asked of it.
        let luminance = export.luminance.take();
        export
            .check_display(&args.out)
            .map_err(|e| super::flags::usage("--display", e))?;
        export.luminance = luminance;
        export
            .check_display(&args.out)
            .map_err(|e| super::flags::usage("--luminance", e))?;
    }
    config.max_pixels = global.max_pixels;
    render_to(&config, &args.out, global)
}

/// Renders what `config` says and writes it with its sidecar; prints the files written unless
/// quiet.
pub fn render_to(config: &RenderConfig, out: &Path, global: &Global) -> CliResult {
    config.validate()?;
    config.check_output(out)?;
    let report = render::run(config, &NoProgress)?;
    let dest = super::output_to(out, global, config.files());
    let files = report.write(&dest)?;
    let out = super::output::Output::new(global);
    for w in &report.warnings {
        out.warn(w);
    }
    for f in files {
        out.note(format!("wrote {}", f.display()));
    }
    // The files are the result; with --json, the report of what was rendered.
    out.results("", &report)
}
