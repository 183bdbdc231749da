//! Named, typed, range-checked parameters: what `--set key=value`, a JSON spec and
//! `shadelab describe NAME` all speak.
//!
//! A stimulus or shape declares its parameters as [`ParamSpec`]s; user values (strings from the
//! command line or JSON values from a spec) are checked against them by [`Params::resolve`], which
//! names the valid keys when one is unknown. A resolved [`Params`] holds every declared
//! parameter, defaults filled in, so a sidecar can record all of them.

use crate::error::{Error, Result};
use crate::light::Light;
use serde_json::{Map, Value};
use std::collections::BTreeMap;

/// The type and allowed range of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamKind {
    /// A real number in `min..=max`.
    Number {
        /// Smallest allowed value.
        min: f64,
        /// Largest allowed value.
        max: f64,
    },
    /// An integer in `min..=max`.
    Integer {
        /// Smallest allowed value.
        min: i64,
        /// Largest allowed value.
        max: i64,
    },
    /// One of a fixed set of words.
    Choice(&'static [&'static str]),
    /// `true` or `false`.
    Bool,
    /// A light (`x,y,z`, `tilt=T,slant=S`, or a name); stored in its `tilt=…,slant=…` form.
    Light,
    /// Free text (file paths, labels).
    Text,
}

/// One declared parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    /// The key used in `--set key=value` and in specs.
    pub name: &'static str,
    /// Type and range.
    pub kind: ParamKind,
    /// The default value.
    pub default: Value,
    /// One line saying what it is (with its unit).
    pub doc: &'static str,
}

impl ParamSpec {
    /// A number parameter in `min..=max` with a default.
    pub fn number(name: &'static str, default: f64, min: f64, max: f64, doc: &'static str) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Number { min, max },
            default: Value::from(default),
            doc,
        }
    }

    /// An integer parameter in `min..=max` with a default.
    pub fn integer(
        name: &'static str,
        default: i64,
        min: i64,
        max: i64,
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Integer { min, max },
            default: Value::from(default),
            doc,
        }
    }

    /// A choice among `options`, the first of which need not be the default.
    pub fn choice(
        name: &'static str,
        default: &'static str,
        options: &'static [&'static str],
        doc: &'static str,
    ) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Choice(options),
            default: Value::from(default),
            doc,
        }
    }

    /// A boolean parameter.
    pub fn boolean(name: &'static str, default: bool, doc: &'static str) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Bool,
            default: Value::from(default),
            doc,
        }
    }

    /// A light parameter with a default in any accepted light syntax.
    pub fn light(name: &'static str, default: &'static str, doc: &'static str) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Light,
            default: Value::from(default),
            doc,
        }
    }

    /// A text parameter (empty default means "not given").
    pub fn text(name: &'static str, default: &'static str, doc: &'static str) -> Self {
        ParamSpec {
            name,
            kind: ParamKind::Text,
            default: Value::from(default),
            doc,
        }
    }

    /// The range or choices as text, for `describe`.
    pub fn range_text(&self) -> String {
        match &self.kind {
            ParamKind::Number { min, max } => format!("{min}..{max}"),
            ParamKind::Integer { min, max } => format!("{min}..{max} (integer)"),
            ParamKind::Choice(options) => options.join("|"),
            ParamKind::Bool => "true|false".into(),
            ParamKind::Light => "x,y,z | tilt=T,slant=S | name".into(),
            ParamKind::Text => "text".into(),
        }
    }

    /// Checks `value` (a JSON value or a string from the command line) and returns its
    /// canonical JSON form.
    pub fn check(&self, value: &Value) -> Result<Value> {
        let bad = |why: String| Error::invalid(format!("parameter {}: {why}", self.name));
        let as_text = value.as_str();
        match &self.kind {
            ParamKind::Number { min, max } => {
                let v = match (value.as_f64(), as_text) {
                    (Some(v), _) => v,
                    (None, Some(t)) => t
                        .trim()
                        .parse::<f64>()
                        .map_err(|_| bad(format!("'{t}' is not a number")))?,
                    _ => return Err(bad(format!("{value} is not a number"))),
                };
                if !v.is_finite() || v < *min || v > *max {
                    return Err(bad(format!("{v} is outside {min}..{max}")));
                }
                Ok(Value::from(v))
            }
            ParamKind::Integer { min, max } => {
                let v = match (value.as_i64(), as_text) {
                    (Some(v), _) => v,
                    (None, Some(t)) => t
                        .trim()
                        .parse::<i64>()
                        .map_err(|_| bad(format!("'{t}' is not an integer")))?,
                    _ => return Err(bad(format!("{value} is not an integer"))),
                };
                if v < *min || v > *max {
                    return Err(bad(format!("{v} is outside {min}..{max}")));
                }
                Ok(Value::from(v))
            }
            ParamKind::Choice(options) => {
                let t = as_text.ok_or_else(|| bad(format!("{value} is not text")))?;
                if options.contains(&t) {
                    Ok(Value::from(t))
                } else {
                    Err(bad(format!("'{t}' is not one of {}", options.join(", "))))
                }
            }
            ParamKind::Bool => match (value.as_bool(), as_text) {
                (Some(b), _) => Ok(Value::from(b)),
                (None, Some("true" | "yes" | "1")) => Ok(Value::from(true)),
                (None, Some("false" | "no" | "0")) => Ok(Value::from(false)),
                _ => Err(bad(format!("{value} is not true or false"))),
            },
            ParamKind::Light => {
                let t = as_text.ok_or_else(|| bad(format!("{value} is not a light")))?;
                let light: Light = t.parse().map_err(|e| bad(format!("{e}")))?;
                Ok(Value::from(light.to_string()))
            }
            ParamKind::Text => match as_text {
                Some(t) => Ok(Value::from(t)),
                None => Err(bad(format!("{value} is not text"))),
            },
        }
    }
}

/// Every declared parameter with its checked value (defaults filled in).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Params {
    values: BTreeMap<String, Value>,
}

impl Params {
    /// Checks `given` against `specs`: unknown keys are errors that list the valid ones,
    /// values are range-checked, and missing ones take their defaults.
    pub fn resolve(specs: &[ParamSpec], given: &Map<String, Value>) -> Result<Params> {
        for key in given.keys() {
            if !specs.iter().any(|s| s.name == key) {
                let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
                return Err(Error::unknown("parameter", key, &names));
            }
        }
        let mut values = BTreeMap::new();
        for spec in specs {
            let v = match given.get(spec.name) {
                Some(v) => spec.check(v)?,
                None => spec.check(&spec.default)?,
            };
            values.insert(spec.name.to_string(), v);
        }
        Ok(Params { values })
    }

    /// Parses `key=value` pairs from the command line into a map for [`Params::resolve`];
    /// a later pair overrides an earlier one.
    pub fn parse_pairs<S: AsRef<str>>(pairs: &[S]) -> Result<Map<String, Value>> {
        let mut map = Map::new();
        for pair in pairs {
            let pair = pair.as_ref();
            let (k, v) = pair.split_once('=').ok_or_else(|| {
                Error::invalid(format!("--set '{pair}' is not of the form key=value"))
            })?;
            map.insert(k.trim().to_string(), Value::from(v.trim()));
        }
        Ok(map)
    }

    fn get(&self, name: &str) -> Result<&Value> {
        self.values
            .get(name)
            .ok_or_else(|| Error::Compute(format!("internal: parameter '{name}' is not declared")))
    }

    /// A number (or integer) parameter.
    pub fn f64(&self, name: &str) -> Result<f64> {
        self.get(name)?
            .as_f64()
            .ok_or_else(|| Error::Compute(format!("internal: parameter '{name}' is not a number")))
    }

    /// An integer parameter.
    pub fn i64(&self, name: &str) -> Result<i64> {
        self.get(name)?.as_i64().ok_or_else(|| {
            Error::Compute(format!("internal: parameter '{name}' is not an integer"))
        })
    }

    /// A non-negative integer parameter.
    pub fn usize(&self, name: &str) -> Result<usize> {
        usize::try_from(self.i64(name)?)
            .map_err(|_| Error::invalid(format!("parameter {name} must not be negative")))
    }

    /// A boolean parameter.
    pub fn bool(&self, name: &str) -> Result<bool> {
        self.get(name)?
            .as_bool()
            .ok_or_else(|| Error::Compute(format!("internal: parameter '{name}' is not a boolean")))
    }

    /// A text or choice parameter.
    pub fn str(&self, name: &str) -> Result<&str> {
        self.get(name)?
            .as_str()
            .ok_or_else(|| Error::Compute(format!("internal: parameter '{name}' is not text")))
    }

    /// A light parameter.
    pub fn light(&self, name: &str) -> Result<Light> {
        self.str(name)?.parse()
    }

    /// All values as a JSON object (for sidecars).
    pub fn to_json(&self) -> Value {
        Value::Object(
            self.values
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn specs() -> Vec<ParamSpec> {
        vec![
            ParamSpec::number("contrast", 0.5, 0.0, 1.0, "contrast"),
            ParamSpec::integer("rows", 3, 1, 20, "rows"),
            ParamSpec::choice(
                "profile",
                "gaussian",
                &["gaussian", "hemisphere"],
                "profile",
            ),
            ParamSpec::light("light", "above", "light"),
        ]
    }

    #[test]
    fn defaults_and_overrides() {
        let given = Params::parse_pairs(&["rows=5", "light=left"]).unwrap();
        let p = Params::resolve(&specs(), &given).unwrap();
        assert_eq!(p.i64("rows").unwrap(), 5);
        assert_eq!(p.f64("contrast").unwrap(), 0.5);
        assert_eq!(p.str("profile").unwrap(), "gaussian");
        assert!((p.light("light").unwrap().tilt_deg() - 90.0).abs() < 1e-9);
    }

    #[test]
    fn rejects_bad_values_naming_the_key() {
        for (pair, needle) in [
            ("contrast=1.5", "outside"),
            ("contrast=abc", "not a number"),
            ("rows=2.5", "not an integer"),
            ("profile=cube", "gaussian"),
            ("light=0,0,-1", "horizon"),
            ("colour=red", "contrast, rows"),
        ] {
            let given = Params::parse_pairs(&[pair]).unwrap();
            let e = Params::resolve(&specs(), &given).unwrap_err().to_string();
            assert!(e.contains(needle), "{pair}: {e}");
        }
        assert!(Params::parse_pairs(&["novalue"]).is_err());
    }
}
