//! The Bayesian observer as a pipeline (`shadelab analyze observer`): one fine sweep of the
//! upright picture, then each token's P(convex) against the picture's rotation, one curve per
//! prior concentration κ.

// The parts of this command's configuration and report that other modules define.
pub use crate::analysis::observer::{
    parse_kappas, Curve, LightPrior, ObserverOptions, Percept, DEFAULT_NOISE, DEFAULT_PRIOR_KAPPA,
    DEFAULT_PRIOR_TILT_DEG,
};

use super::perception::{self, field, interpretations_of, write_outputs, BadSetting, Header};
use super::CommandReport;
use crate::analysis::observer::{check_circle, curves_csv, p_convex_plot};
use crate::analysis::{observe, parse_angles, Sweep};
use crate::error::{Error, Result};
use crate::plot::Figure;
use crate::progress::Progress;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// The default assumed tilts of the sweep behind the observer: every 5°.
pub const DEFAULT_TILTS: &str = "0:360:5";

/// The default rotations of the picture: every 15°.
pub const DEFAULT_ROTATIONS: &str = "0:360:15";

/// What to observe, as plain values.
#[derive(Debug, Clone)]
pub struct Config {
    /// The picture and how to interpret it.
    pub picture: perception::Config,
    /// Mean of the von Mises prior over light tilt, degrees (default 26° left, Mamassian &
    /// Goutcher 2001; see [`DEFAULT_PRIOR_TILT_DEG`]).
    pub prior_tilt_deg: f64,
    /// Concentrations κ of the tilt prior, one curve each.
    pub kappas: Vec<f64>,
    /// Log prior odds of convex over concave for each token.
    pub convexity_bias: f64,
    /// Image noise σ of the likelihood, luminance units.
    pub noise: f64,
    /// The lapse rate λ: how often the observer answers at random.
    pub lapse: f64,
    /// The `fit.json` the prior and lapse were read from, if any (for the report).
    pub prior_from: Option<String>,
    /// Rotations of the picture to judge, degrees counter-clockwise.
    pub rotations: Vec<f64>,
    /// Assumed light tilts of the sweep; they must cover the circle in equal steps.
    pub tilts: Vec<f64>,
}

impl Config {
    /// The defaults for `picture`: the observer of [`ObserverOptions::default`] over
    /// [`DEFAULT_ROTATIONS`], from a sweep over [`DEFAULT_TILTS`].
    pub fn new(picture: perception::Config) -> Result<Config> {
        Ok(Config {
            picture,
            prior_tilt_deg: DEFAULT_PRIOR_TILT_DEG,
            kappas: vec![DEFAULT_PRIOR_KAPPA],
            convexity_bias: 0.0,
            noise: DEFAULT_NOISE,
            lapse: 0.0,
            prior_from: None,
            rotations: parse_angles(DEFAULT_ROTATIONS, "rotations")?,
            tilts: parse_angles(DEFAULT_TILTS, "tilts")?,
        })
    }

    /// Takes the prior (μ, κ, B = logit π) and the lapse from a `fit.json` written by
    /// [`crate::pipeline::fit`], so that the observer predicts with the fitted model.
    pub fn use_fit(&mut self, path: &Path) -> Result<()> {
        let model = crate::pipeline::fit::read_fit(path)?;
        let o = ObserverOptions::from_model(&model, self.noise)
            .map_err(|e| Error::format(path, e.to_string()))?;
        self.prior_tilt_deg = o.prior.mean_tilt_deg;
        self.kappas = vec![o.prior.kappa];
        self.convexity_bias = o.prior.convexity_bias;
        self.lapse = o.lapse;
        self.prior_from = Some(path.display().to_string());
        Ok(())
    }

    /// The observer's options for each κ.
    pub fn observers(&self) -> Vec<ObserverOptions> {
        self.kappas
            .iter()
            .map(|&kappa| ObserverOptions {
                prior: LightPrior {
                    mean_tilt_deg: self.prior_tilt_deg,
                    kappa,
                    convexity_bias: self.convexity_bias,
                },
                noise: self.noise,
                lapse: self.lapse,
            })
            .collect()
    }

    /// Checks everything that needs no file, naming the first bad field.
    pub fn check(&self) -> Result<(), BadSetting> {
        field("tilts", check_circle(&self.tilts))?;
        let rotations = match self.rotations.iter().find(|r| !r.is_finite()) {
            _ if self.rotations.is_empty() => Err(Error::invalid("no rotations to judge")),
            Some(r) => Err(Error::invalid(format!(
                "rotation {r} is not a finite number"
            ))),
            None => Ok(()),
        };
        field("rotations", rotations)?;
        if self.kappas.is_empty() {
            field("kappas", Err(Error::invalid("no prior kappa given")))?;
        }
        // Each value alone, with the others at their defaults, so the failure names its field.
        let alone = |o: ObserverOptions| o.validate();
        let d = ObserverOptions::default();
        let prior = |p: LightPrior| alone(ObserverOptions { prior: p, ..d });
        field(
            "prior_tilt_deg",
            prior(LightPrior {
                mean_tilt_deg: self.prior_tilt_deg,
                ..d.prior
            }),
        )?;
        for &kappa in &self.kappas {
            field("kappas", prior(LightPrior { kappa, ..d.prior }))?;
        }
        field(
            "convexity_bias",
            prior(LightPrior {
                convexity_bias: self.convexity_bias,
                ..d.prior
            }),
        )?;
        field(
            "noise",
            alone(ObserverOptions {
                noise: self.noise,
                ..d
            }),
        )?;
        field(
            "lapse",
            alone(ObserverOptions {
                lapse: self.lapse,
                ..d
            }),
        )?;
        self.picture.check()
    }
}

/// The observer's settings, as the report records them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObserverSettings {
    /// Mean of the tilt prior, degrees.
    pub prior_tilt_deg: f64,
    /// The concentrations κ, one curve each.
    pub prior_kappa: Vec<f64>,
    /// Log prior odds of convex over concave.
    pub convexity_bias: f64,
    /// Image noise σ of the likelihood.
    pub noise: f64,
    /// The lapse rate λ.
    pub lapse: f64,
    /// The `fit.json` the prior and lapse came from, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior_from: Option<String>,
}

/// A token's label and name.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TokenName {
    /// Its label.
    pub label: u16,
    /// Its name.
    pub name: String,
}

/// What the observer concluded; serialised, it is `observer.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// The program, command, picture and the sweep's settings.
    #[serde(flatten)]
    pub header: Header,
    /// The observer's settings.
    pub observer: ObserverSettings,
    /// The observer's model, in words.
    pub model: &'static str,
    /// The assumed tilts of the sweep.
    pub tilts_deg: Vec<f64>,
    /// The tokens.
    pub tokens: Vec<TokenName>,
    /// The percepts, one curve per κ.
    pub percepts: Vec<Curve>,
    /// The sweep behind the observer (serialised as its interpretations).
    #[serde(serialize_with = "interpretations_of")]
    pub sweep: Sweep,
    /// The files written and what they hold.
    pub outputs: BTreeMap<&'static str, &'static str>,
    /// Seconds the run took.
    pub seconds: f64,
}

/// Runs the observer: loads the picture, sweeps it (one progress step per tilt) and judges
/// every rotation under every κ.
pub fn run(config: &Config, progress: &dyn Progress) -> Result<Report> {
    let started = Instant::now();
    config.check()?;
    let setup = config.picture.load(progress)?;
    let result = setup.sweep(&config.tilts, progress, "observer sweep")?;
    let curves = config
        .observers()
        .into_iter()
        .map(|options| {
            Ok(Curve {
                options,
                percepts: observe(&result, &options, &config.rotations)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // Said once the run succeeded: a refusal stays one line.
    setup.input_note.iter().for_each(|line| progress.note(line));
    Ok(Report {
        header: setup.header("analyze observer"),
        observer: ObserverSettings {
            prior_tilt_deg: config.prior_tilt_deg,
            prior_kappa: config.kappas.clone(),
            convexity_bias: config.convexity_bias,
            noise: config.noise,
            lapse: config.lapse,
            prior_from: config.prior_from.clone(),
        },
        model: "posterior over the sweep's interpretations: von Mises prior on the light tilt (in the rotated picture's frame) x exp(B) per token read as convex x exp(-(e_R - min e_R)/(2 noise^2)); rotating the picture by r turns interpretation t into t + r; P(convex) = lapse/2 + (1 - lapse) x posterior P(convex) (for one disc and small noise: the observer model that fit observer estimates, with B = logit(convexity prior))",
        tilts_deg: config.tilts.clone(),
        tokens: result
            .tokens
            .iter()
            .map(|(label, name)| TokenName {
                label: *label,
                name: name.clone(),
            })
            .collect(),
        percepts: curves,
        sweep: result,
        outputs: BTreeMap::from([
            ("observer.csv", "one row per prior kappa, rotation and token: P(convex), the most probable light tilt, P(light from above)"),
            ("p_convex.png", "P(convex) against rotation, one curve per token (also .svg)"),
        ]),
        seconds: started.elapsed().as_secs_f64(),
    })
}

impl CommandReport for Report {
    /// The report, `observer.json`.
    const MARKER: &'static str = "observer.json";

    /// Writes `observer.csv`, `p_convex.png`, `p_convex.svg` and the report, [`Report::MARKER`].
    fn write_into(&self, dir: &Path) -> Result<()> {
        let plot = p_convex_plot(&self.sweep, &self.percepts)?;
        let figure = Figure {
            size: plot.size,
            panels: vec![plot],
        };
        let csv = curves_csv(&self.sweep, &self.percepts);
        write_outputs(
            dir,
            ("p_convex", &figure),
            ("observer.csv", &csv),
            Self::MARKER,
            self,
        )
    }
}
