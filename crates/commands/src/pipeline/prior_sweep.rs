//! The prior sweep as a pipeline (`shadelab analyze prior-sweep`): the picture interpreted under
//! each assumed light tilt, with each token's convexity, residual and smoothness, the tilts
//! where it flips, and optionally the binding analysis (one light for the scene against a light
//! per token).

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::binding::{Binding, GlobalLight, UsedLight};
pub use crate::analysis::Sweep;

use super::perception::{self, field, interpretations_of, write_outputs, BadSetting, Header};
use super::CommandReport;
use crate::analysis::binding::binding;
use crate::analysis::{parse_angles, Interpreter};
use crate::error::{Error, Result};
use crate::progress::Progress;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// The default assumed tilts: every 15°.
pub const DEFAULT_TILTS: &str = "0:360:15";

/// What to sweep, as plain values.
#[derive(Debug, Clone)]
pub struct Config {
    /// The picture and how to interpret it.
    pub picture: perception::Config,
    /// The assumed light tilts, degrees (0 = from above, +90 = from the left).
    pub tilts: Vec<f64>,
    /// Also read the tokens under one global light and under a light estimated from each
    /// token alone.
    pub binding: Option<GlobalLight>,
}

impl Config {
    /// The defaults ([`DEFAULT_TILTS`], no binding) for `picture`.
    pub fn new(picture: perception::Config) -> Result<Config> {
        Ok(Config {
            picture,
            tilts: parse_angles(DEFAULT_TILTS, "tilts")?,
            binding: None,
        })
    }

    /// Checks everything that needs no file, naming the first bad field.
    pub fn check(&self) -> Result<(), BadSetting> {
        let tilts = if self.tilts.is_empty() {
            Err(Error::invalid("the sweep has no tilts"))
        } else if let Some(t) = self.tilts.iter().find(|t| !t.is_finite()) {
            Err(Error::invalid(format!("tilt {t} is not a finite number")))
        } else {
            Ok(())
        };
        field("tilts", tilts)?;
        if let Some(GlobalLight::Given(t)) = self.binding {
            let ok = if t.is_finite() {
                Ok(())
            } else {
                Err(Error::invalid(format!(
                    "global light tilt {t} is not a finite number"
                )))
            };
            field("binding", ok)?;
        }
        self.picture.check()
    }
}

/// Parses where the global light of the binding analysis comes from: `estimate` or a tilt in
/// degrees.
///
/// ```
/// use shadelab_analysis::analysis::binding::GlobalLight;
/// use shadelab::pipeline::prior_sweep::parse_global_light;
/// assert_eq!(parse_global_light("estimate").unwrap(), GlobalLight::Estimated);
/// assert_eq!(parse_global_light(" 90 ").unwrap(), GlobalLight::Given(90.0));
/// assert!(parse_global_light("nan").is_err());
/// ```
pub fn parse_global_light(text: &str) -> Result<GlobalLight> {
    match text.trim() {
        "estimate" => Ok(GlobalLight::Estimated),
        t => t
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .map(GlobalLight::Given)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "global light '{t}' is neither 'estimate' nor a tilt in degrees"
                ))
            }),
    }
}

/// One token's summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TokenSummary {
    /// Its label.
    pub label: u16,
    /// Its name.
    pub name: String,
    /// How many pixels it has.
    pub pixels: usize,
    /// Its half-width, pixels.
    pub half_width_px: f64,
    /// The assumed tilts where its convexity changes sign.
    pub flips_deg: Vec<f64>,
    /// The assumed tilts under which it reads convex.
    pub convex_tilts_deg: Vec<f64>,
    /// The assumed tilts under which it reads concave.
    pub concave_tilts_deg: Vec<f64>,
}

/// What a prior sweep found; serialised, it is `sweep.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The program, command, picture and settings.
    #[serde(flatten)]
    pub header: Header,
    /// The assumed tilts.
    pub tilts_deg: Vec<f64>,
    /// Whether the tilts cover the circle in equal steps.
    pub covers_circle: bool,
    /// How depth was integrated.
    pub depth_integration: &'static str,
    /// How convexity is measured.
    pub convexity: &'static str,
    /// One summary per token.
    pub tokens: Vec<TokenSummary>,
    /// The sweep (serialised as its interpretations).
    #[serde(rename = "interpretations", serialize_with = "interpretations_of")]
    pub sweep: Sweep,
    /// How many solves did not converge.
    pub unconverged_solves: usize,
    /// The binding analysis, when asked for.
    pub binding: Option<Binding>,
    /// The files written and what they hold.
    pub outputs: BTreeMap<&'static str, &'static str>,
    /// Seconds the run took.
    pub seconds: f64,
}

/// Sweeps the picture: loads it, interprets it under every tilt (in parallel, one progress
/// step per tilt) and, when asked, reads the binding.
pub fn run(config: &Config, progress: &dyn Progress) -> Result<Report> {
    let started = Instant::now();
    config.check()?;
    let setup = config.picture.load(progress)?;
    let scene = setup.scene();
    let fourier = Interpreter::new(&scene, &setup.options)?.uses_fourier();
    let result = setup.sweep(&config.tilts, progress, "prior sweep")?;
    let bound = match config.binding {
        Some(g) => Some(binding(&scene, &setup.lighting, g, &setup.options)?),
        None => None,
    };
    let tokens = setup
        .picture
        .tokens
        .iter()
        .enumerate()
        .map(|(k, t)| TokenSummary {
            label: t.label,
            name: t.name.clone(),
            pixels: t.pixels().len(),
            half_width_px: t.half_width(),
            flips_deg: result.flips(k),
            convex_tilts_deg: result.tilts_where(k, |v| v > 0.0),
            concave_tilts_deg: result.tilts_where(k, |v| v < 0.0),
        })
        .collect();
    // Said once the run succeeded: a refusal stays one line.
    setup.input_note.iter().for_each(|line| progress.note(line));
    Ok(Report {
        header: setup.header("analyze prior-sweep"),
        tilts_deg: config.tilts.clone(),
        covers_circle: result.covers_circle(),
        depth_integration: if fourier {
            "Frankot-Chellappa over the whole frame (flat boundary: a relief on a plane)"
        } else {
            "masked Poisson (conjugate gradients)"
        },
        convexity: "(mean depth over the token's core - mean over its rim) / half-width; > 0 convex toward the viewer",
        tokens,
        unconverged_solves: result.unconverged(),
        sweep: result,
        binding: bound,
        outputs: BTreeMap::from([
            ("sweep.csv", "one row per assumed tilt and token: convexity, residual e_R and smoothness e_S over the token"),
            ("sweep.png", "convexity (top) and surface residual e_Z (bottom) against assumed tilt, one curve per token (also .svg)"),
        ]),
        seconds: started.elapsed().as_secs_f64(),
    })
}

impl CommandReport for Report {
    /// The report, `sweep.json`.
    const MARKER: &'static str = "sweep.json";

    /// Writes `sweep.csv`, `sweep.png`, `sweep.svg` and the report, [`Report::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        let csv = self.sweep.csv();
        write_outputs(
            dir,
            ("sweep", &self.sweep.figure()),
            ("sweep.csv", &csv),
            Self::MARKER,
            self,
        )
    }
}
