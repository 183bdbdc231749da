//! A study's grid: its points, and the combinations of parameters and priors they come from.

use crate::analysis::observer::LightPrior;
use crate::analysis::study::PriorGrid;
use crate::error::{Error, Result};
use serde_json::{Map, Value};

/// The most grid points a study may have.
pub const MAX_POINTS: usize = 1_000_000;

/// One grid point.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    /// Its number in the study.
    pub index: usize,
    /// Which stimulus entry it comes from.
    pub entry: usize,
    /// The stimulus parameters at this point.
    pub params: Map<String, Value>,
    /// The assumed slant.
    pub slant_deg: f64,
}

/// Every combination of the priors, tilt slowest and bias fastest.
pub(crate) fn prior_combinations(p: &PriorGrid) -> Vec<LightPrior> {
    let mut out = Vec::new();
    for &mean_tilt_deg in &p.tilt {
        for &kappa in &p.kappa {
            for &convexity_bias in &p.convexity_bias {
                out.push(LightPrior {
                    mean_tilt_deg,
                    kappa,
                    convexity_bias,
                });
            }
        }
    }
    out
}

/// Every combination of the parameters: lists are axes (keys in alphabetical order, the last
/// varying fastest), other values fixed.
pub(crate) fn param_combinations(params: &Map<String, Value>) -> Result<Vec<Map<String, Value>>> {
    let mut combos = vec![Map::new()];
    let mut keys: Vec<&String> = params.keys().collect();
    keys.sort();
    for key in keys {
        let values = match &params[key.as_str()] {
            Value::Array(v) if v.is_empty() => {
                return Err(Error::invalid(format!(
                    "parameter {key}: an empty list gives no grid points"
                )))
            }
            Value::Array(v) => v.clone(),
            other => vec![other.clone()],
        };
        let mut next = Vec::with_capacity(combos.len() * values.len());
        for c in &combos {
            for v in &values {
                let mut m = c.clone();
                m.insert(key.clone(), v.clone());
                next.push(m);
            }
        }
        if next.len() > MAX_POINTS {
            return Err(Error::invalid(format!(
                "the study has more than {MAX_POINTS} grid points"
            )));
        }
        combos = next;
    }
    Ok(combos)
}

/// Parameters as `key=value;key=value` (strings unquoted).
pub(crate) fn params_text(params: &Map<String, Value>) -> String {
    let mut keys: Vec<&String> = params.keys().collect();
    keys.sort();
    keys.iter()
        .map(|k| match &params[k.as_str()] {
            Value::String(s) => format!("{k}={s}"),
            v => format!("{k}={v}"),
        })
        .collect::<Vec<_>>()
        .join(";")
}
