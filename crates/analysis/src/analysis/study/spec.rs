//! A study spec: its JSON form, read and checked, with its grid expanded into points.

use super::grid::{param_combinations, prior_combinations, Point, MAX_POINTS};
use crate::analysis::observer::ObserverOptions;
use crate::analysis::parse_angles;
use crate::analysis::picture::Domain;
use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::io;
use md5::{Digest, Md5};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A study spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudySpec {
    /// The stimuli, each with fixed and varied parameters.
    pub stimuli: Vec<StimulusEntry>,
    /// Assumed light tilts of each sweep (`START:STOP:STEP` or a list; they must cover the
    /// circle in equal steps for the observer).
    #[serde(default = "default_tilts")]
    pub tilts: String,
    /// Assumed light slants, degrees; each is a grid axis.
    #[serde(default = "default_slants")]
    pub slants: Vec<f64>,
    /// The observer's priors (every combination).
    #[serde(default)]
    pub priors: PriorGrid,
    /// Picture rotations the observer judges (degrees counter-clockwise).
    #[serde(default = "default_rotations")]
    pub rotations: String,
    /// Image noise σ of the observer's likelihood.
    #[serde(default = "default_noise")]
    pub noise: f64,
    /// The observer's lapse rate λ (0..1; 0, the default, is left out of the canonical JSON,
    /// so older specs keep their md5).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub lapse: f64,
    /// Boundary condition: `flat`, `free` or `occluding`.
    #[serde(default = "default_boundary")]
    pub boundary: String,
    /// Solve domain: `image` or `tokens`.
    #[serde(default = "default_domain")]
    pub domain: String,
}

fn default_tilts() -> String {
    "0:360:15".into()
}
fn default_slants() -> Vec<f64> {
    vec![45.0]
}
fn default_rotations() -> String {
    "0".into()
}
fn default_noise() -> f64 {
    crate::analysis::observer::DEFAULT_NOISE
}
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}
fn default_boundary() -> String {
    "flat".into()
}
fn default_domain() -> String {
    "image".into()
}

crate::stimulus::stimulus_request! {
/// One stimulus of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StimulusEntry {
    /// Parameters: a list is a grid axis, anything else a fixed value.
    params;
    /// Random seed.
    #[serde(default)]
    pub seed: u64,
}
}

/// The observer priors of a study: every combination is applied to every point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PriorGrid {
    /// Prior mean tilts, degrees.
    #[serde(default = "default_prior_tilt")]
    pub tilt: Vec<f64>,
    /// Prior concentrations κ.
    #[serde(default = "default_prior_kappa")]
    pub kappa: Vec<f64>,
    /// Convexity biases B (log odds).
    #[serde(default = "default_bias")]
    pub convexity_bias: Vec<f64>,
}

fn default_prior_tilt() -> Vec<f64> {
    vec![crate::analysis::observer::DEFAULT_PRIOR_TILT_DEG]
}
fn default_prior_kappa() -> Vec<f64> {
    vec![crate::analysis::observer::DEFAULT_PRIOR_KAPPA]
}
fn default_bias() -> Vec<f64> {
    vec![0.0]
}

impl Default for PriorGrid {
    fn default() -> Self {
        PriorGrid {
            tilt: default_prior_tilt(),
            kappa: default_prior_kappa(),
            convexity_bias: default_bias(),
        }
    }
}

/// A checked spec with its expanded grid.
#[derive(Debug, Clone)]
pub struct Study {
    /// The spec as given.
    pub spec: StudySpec,
    /// The md5 of the spec's canonical JSON: shards of one study share it.
    pub spec_md5: String,
    /// The assumed tilts.
    pub tilts: Vec<f64>,
    /// The rotations.
    pub rotations: Vec<f64>,
    /// The boundary condition.
    pub boundary: Boundary,
    /// The domain.
    pub domain: Domain,
    /// Every grid point, in order.
    pub points: Vec<Point>,
    /// The largest picture a point may make, in pixels (`--max-pixels`).
    pub max_pixels: usize,
}

impl Study {
    /// Reads and checks a spec file, with pictures of at most the default number of pixels.
    pub fn load(path: &Path) -> Result<Study> {
        Study::load_with_max_pixels(path, crate::grid::DEFAULT_MAX_PIXELS)
    }

    /// Reads and checks a spec file whose pictures may have up to `max_pixels` pixels.
    pub fn load_with_max_pixels(path: &Path, max_pixels: usize) -> Result<Study> {
        let bytes = io::read_bytes(path)?;
        let spec: StudySpec = serde_json::from_slice(&bytes)
            .map_err(|e| Error::format(path, format!("bad study spec: {e}")))?;
        Study::new_with_max_pixels(spec, max_pixels).map_err(|e| match e {
            Error::Invalid(m) => Error::format(path, m),
            Error::TooLarge(m) => Error::TooLarge(format!("{}: {m}", path.display())),
            unknown @ Error::Unknown { .. } => Error::format(path, unknown.to_string()),
            other => other,
        })
    }

    /// Checks a spec and expands its grid. Every stimulus is checked by name and parameters
    /// here, so a bad spec fails before any work.
    pub fn new(spec: StudySpec) -> Result<Study> {
        Study::new_with_max_pixels(spec, crate::grid::DEFAULT_MAX_PIXELS)
    }

    /// [`Study::new`] with pictures of up to `max_pixels` pixels; each stimulus's size is
    /// resolved here too, so that an impossible size fails before any work.
    pub fn new_with_max_pixels(spec: StudySpec, max_pixels: usize) -> Result<Study> {
        if spec.stimuli.is_empty() {
            return Err(Error::invalid("the study has no stimuli"));
        }
        let tilts = parse_angles(&spec.tilts, "tilts")?;
        if crate::plot::circle_step(&tilts).is_none() {
            return Err(Error::invalid(format!(
                "tilts '{}' must cover the circle in equal steps for the observer (e.g. 0:360:15)",
                spec.tilts
            )));
        }
        let rotations = parse_angles(&spec.rotations, "rotations")?;
        if spec.slants.is_empty() {
            return Err(Error::invalid("slants is empty: give at least one"));
        }
        for &s in &spec.slants {
            if !(s.is_finite() && (0.0..90.0).contains(&s)) {
                return Err(Error::invalid(format!("slant {s} must be in 0..90")));
            }
        }
        let p = &spec.priors;
        if p.tilt.is_empty() || p.kappa.is_empty() || p.convexity_bias.is_empty() {
            return Err(Error::invalid(
                "priors: tilt, kappa and convexity_bias each need at least one value",
            ));
        }
        for prior in prior_combinations(p) {
            ObserverOptions {
                prior,
                noise: spec.noise,
                lapse: spec.lapse,
            }
            .validate()?;
        }
        let boundary = match spec.boundary.as_str() {
            "flat" | "free" | "occluding" => Boundary::named(&spec.boundary)?,
            other => {
                return Err(Error::unknown(
                    "boundary",
                    other,
                    &["flat", "free", "occluding"],
                ))
            }
        };
        let domain: Domain = spec.domain.parse()?;
        let mut points = Vec::new();
        for (entry_index, entry) in spec.stimuli.iter().enumerate() {
            let info = crate::stimulus::find(&entry.stimulus)?.info();
            let combos = param_combinations(&entry.params)?;
            for combo in combos {
                // Checked now against the stimulus's declarations, so typos fail at once.
                crate::params::Params::resolve(&info.params, &combo)
                    .map_err(|e| Error::invalid(format!("{}: {e}", entry.stimulus)))?;
                let size = entry.size();
                crate::stimulus::prepare(&entry.stimulus, &combo, &size, entry.seed, max_pixels)
                    .map_err(|e| match e {
                        Error::Invalid(m) => Error::invalid(format!("{}: {m}", entry.stimulus)),
                        Error::TooLarge(m) => Error::TooLarge(format!("{}: {m}", entry.stimulus)),
                        other => other,
                    })?;
                for &slant in &spec.slants {
                    if points.len() >= MAX_POINTS {
                        return Err(Error::invalid(format!(
                            "the study has more than {MAX_POINTS} grid points"
                        )));
                    }
                    points.push(Point {
                        index: points.len(),
                        entry: entry_index,
                        params: combo.clone(),
                        slant_deg: slant,
                    });
                }
            }
        }
        let canonical = serde_json::to_string(&spec)
            .map_err(|e| Error::Compute(format!("cannot serialise the spec: {e}")))?;
        let spec_md5 = Md5::digest(canonical.as_bytes())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        Ok(Study {
            spec,
            spec_md5,
            tilts,
            rotations,
            boundary,
            domain,
            points,
            max_pixels,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::study::grid::params_text;
    use serde_json::json;

    fn spec(text: &str) -> Result<Study> {
        let spec: StudySpec = serde_json::from_str(text)
            .map_err(|e| Error::invalid(format!("bad study spec: {e}")))?;
        Study::new(spec)
    }

    #[test]
    fn the_grid_expands_in_order_and_bad_specs_fail() {
        let s = spec(
            r#"{"stimuli":[{"stimulus":"bumps","params":{"rows":1,"columns":1,
               "pattern":["bumps","dimples"],"height":[0.5,1]}}],"slants":[30,45]}"#,
        )
        .unwrap();
        assert_eq!(s.points.len(), 8);
        // Keys alphabetical (height before pattern), last fastest, then slants.
        assert_eq!(s.points[0].params["height"], json!(0.5));
        assert_eq!(s.points[0].slant_deg, 30.0);
        assert_eq!(s.points[1].slant_deg, 45.0);
        assert_eq!(s.points[2].params["pattern"], json!("dimples"));
        assert_eq!(s.points[4].params["height"], json!(1));
        assert_eq!(
            params_text(&s.points[0].params),
            "columns=1;height=0.5;pattern=bumps;rows=1"
        );
        for (bad, needle) in [
            (
                r#"{"stimuli":[{"stimulus":"bumps"}],"colour":1}"#,
                "unknown field",
            ),
            (r#"{"stimuli":[{"stimulus":"teapot"}]}"#, "teapot"),
            (
                r#"{"stimuli":[{"stimulus":"bumps","params":{"radius":[]}}]}"#,
                "empty list",
            ),
            (
                r#"{"stimuli":[{"stimulus":"bumps","params":{"hue":1}}]}"#,
                "hue",
            ),
            (
                r#"{"stimuli":[{"stimulus":"bumps"}],"tilts":"0:180:15"}"#,
                "cover the circle",
            ),
            (r#"{"stimuli":[]}"#, "no stimuli"),
            (r#"{"stimuli":[{"stimulus":"bumps"}],"noise":0}"#, "noise"),
        ] {
            let e = spec(bad).unwrap_err().to_string();
            assert!(e.contains(needle), "{bad}: {e}");
        }
    }
}
