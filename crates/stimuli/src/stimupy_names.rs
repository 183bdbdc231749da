//! stimupy's parameter names, accepted where a shadelab stimulus has the same idea under its
//! own name: one table ([`ALIASES`]), applied once where a stimulus's parameters are resolved
//! ([`super::prepare`]), so that the command line's `--set`, specs, sidecars and Python all take
//! them. What is recorded is shadelab's name.

use crate::error::{Error, Result};
use serde_json::{Map, Value};

/// How a stimupy value becomes shadelab's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Conversion {
    /// A (height, width) size whose two values must agree (shadelab's is one number: square).
    SquarePair,
    /// A pair split into two parameters, in order.
    Split(&'static str, &'static str),
    /// A list of (row, column) pairs as shadelab's `"r,c;r,c"` text.
    IndexPairs,
}

/// One stimupy name of a shadelab parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Alias {
    /// The shadelab stimulus.
    pub stimulus: &'static str,
    /// stimupy's parameter name.
    pub stimupy: &'static str,
    /// shadelab's parameter name (for [`Conversion::Split`], the pair it is split into).
    pub shadelab: &'static str,
    /// How the value is converted.
    pub conversion: Conversion,
}

/// Every stimupy name shadelab accepts (docs/python.md lists them).
pub const ALIASES: &[Alias] = &[
    Alias {
        stimulus: "checkerboard",
        stimupy: "check_visual_size",
        shadelab: "check",
        conversion: Conversion::SquarePair,
    },
    Alias {
        stimulus: "checkerboard",
        stimupy: "intensity_checks",
        shadelab: "intensity_first, intensity_second",
        conversion: Conversion::Split("intensity_first", "intensity_second"),
    },
    Alias {
        stimulus: "checkerboard",
        stimupy: "target_indices",
        shadelab: "targets",
        conversion: Conversion::IndexPairs,
    },
];

/// `value` as a list of numbers: a number, a list of numbers, or a text of numbers separated by
/// commas (as `--set` gives it).
fn numbers(value: &Value) -> Option<Vec<f64>> {
    match value {
        Value::Number(n) => n.as_f64().map(|v| vec![v]),
        Value::Array(items) => items.iter().map(Value::as_f64).collect(),
        Value::String(text) => text
            .split(',')
            .map(|t| t.trim().parse::<f64>().ok())
            .collect(),
        _ => None,
    }
}

/// The stimulus's parameters with every stimupy name of [`ALIASES`] replaced by shadelab's;
/// a name given both ways, or a value of the wrong form, is an error naming both.
pub fn translate(stimulus: &str, given: &Map<String, Value>) -> Result<Map<String, Value>> {
    let mut out = given.clone();
    for alias in ALIASES.iter().filter(|a| a.stimulus == stimulus) {
        let Some(value) = out.remove(alias.stimupy) else {
            continue;
        };
        let bad = |what: &str| {
            Error::invalid(format!(
                "{stimulus}: parameter {} (stimupy's name for {}): {what}, not {value}",
                alias.stimupy, alias.shadelab
            ))
        };
        let mut set = |name: &str, v: Value| -> Result<()> {
            if out.contains_key(name) {
                return Err(Error::invalid(format!(
                    "{stimulus}: {} and {name} are the same parameter (stimupy's name and \
                     shadelab's); give one",
                    alias.stimupy
                )));
            }
            out.insert(name.to_string(), v);
            Ok(())
        };
        match alias.conversion {
            Conversion::SquarePair => {
                match numbers(&value).as_deref() {
                    Some([v]) => set(alias.shadelab, Value::from(*v))?,
                    Some([h, w]) if h == w => set(alias.shadelab, Value::from(*h))?,
                    Some([_, _]) => return Err(bad(
                        "shadelab's checks are square: give one number or equal (height, width)",
                    )),
                    _ => return Err(bad("a number or a (height, width) pair")),
                }
            }
            Conversion::Split(first, second) => match numbers(&value).as_deref() {
                Some([a, b]) => {
                    set(first, Value::from(*a))?;
                    set(second, Value::from(*b))?;
                }
                _ => return Err(bad("a pair of two numbers")),
            },
            Conversion::IndexPairs => {
                let pairs: Option<Vec<String>> = match &value {
                    Value::Array(items) => items
                        .iter()
                        .map(|p| match numbers(p).as_deref() {
                            Some([r, c]) if r.fract() == 0.0 && c.fract() == 0.0 => {
                                Some(format!("{r},{c}"))
                            }
                            _ => None,
                        })
                        .collect(),
                    Value::String(text) => Some(vec![text.clone()]),
                    _ => None,
                };
                match pairs {
                    Some(p) => set(alias.shadelab, Value::from(p.join(";")))?,
                    None => return Err(bad("a list of (row, column) pairs")),
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn map(v: Value) -> Map<String, Value> {
        v.as_object().unwrap().clone()
    }

    #[test]
    fn stimupys_names_become_shadelabs() {
        let out = translate(
            "checkerboard",
            &map(
                json!({"check_visual_size": [0.5, 0.5], "intensity_checks": [0.2, 0.9],
                        "target_indices": [[1, 2], [3, 0]]}),
            ),
        )
        .unwrap();
        assert_eq!(
            Value::Object(out),
            json!({"check": 0.5, "intensity_first": 0.2, "intensity_second": 0.9,
                   "targets": "1,2;3,0"})
        );
        // As the command line's --set gives them: text.
        let out = translate(
            "checkerboard",
            &map(json!({"check_visual_size": "2", "intensity_checks": "0,1"})),
        )
        .unwrap();
        assert_eq!(
            Value::Object(out),
            json!({"check": 2.0, "intensity_first": 0.0, "intensity_second": 1.0})
        );
        // Other stimuli keep their parameters as given.
        let given = map(json!({"check_visual_size": 1}));
        assert_eq!(translate("disc", &given).unwrap(), given);
    }

    #[test]
    fn a_name_given_twice_or_a_bad_value_is_an_error() {
        let e = translate(
            "checkerboard",
            &map(json!({"check_visual_size": 1, "check": 1})),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("check_visual_size and check are the same parameter"),
            "{e}"
        );
        let e = translate("checkerboard", &map(json!({"check_visual_size": [1, 2]})))
            .unwrap_err()
            .to_string();
        assert!(e.contains("square"), "{e}");
        let e = translate("checkerboard", &map(json!({"intensity_checks": 0.5})))
            .unwrap_err()
            .to_string();
        assert!(e.contains("a pair of two numbers"), "{e}");
        let e = translate("checkerboard", &map(json!({"target_indices": [[1.5, 2]]})))
            .unwrap_err()
            .to_string();
        assert!(e.contains("(row, column) pairs"), "{e}");
    }
}
