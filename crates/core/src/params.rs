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
        // A number where text is meant (Python's `rotation=180`) is its text: whole numbers
        // without a decimal point, as they are written on the command line.
        let number_text = value.as_f64().map(|v| match value.as_i64() {
            Some(i) => i.to_string(),
            None if v.fract() == 0.0 && v.abs() < 1e15 => format!("{v:.0}"),
            None => v.to_string(),
        });
        let as_text = value.as_str().or(number_text.as_deref());
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
        Params::check_names(specs, given.keys(), &[])?;
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

    /// Checks that every name in `given` is a parameter of `specs`; an unknown one is an
    /// error listing the valid names and naming the nearest among them and `also`, the other
    /// names the caller accepts beside the parameters (a Python function's own keywords:
    /// `observer("bumps", prior_kappa=2)` suggests the observer's `kappas`).
    pub fn check_names<'a>(
        specs: &[ParamSpec],
        given: impl IntoIterator<Item = &'a String>,
        also: &[&str],
    ) -> Result<()> {
        for key in given {
            if !specs.iter().any(|s| s.name == key) {
                let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
                let nearby: Vec<&str> = names.iter().chain(also).copied().collect();
                let hint = match crate::error::nearest_name(key, &nearby) {
                    Some(n) if also.contains(&n) && !names.contains(&n) => {
                        format!("; did you mean the keyword '{n}'?")
                    }
                    Some(n) => format!("; did you mean '{n}'?"),
                    None => String::new(),
                };
                return Err(Error::Unknown {
                    kind: "parameter",
                    name: key.clone(),
                    hint,
                    valid: names.join(", "),
                });
            }
        }
        Ok(())
    }

    /// Parses `key=value` pairs from the command line into a map for [`Params::resolve`];
    /// a later pair overrides an earlier one.
    pub fn parse_pairs<S: AsRef<str>>(pairs: &[S]) -> Result<Map<String, Value>> {
        let mut map = Map::new();
        for pair in pairs {
            let pair = pair.as_ref();
            let (k, v) = pair.split_once('=').ok_or_else(|| {
                Error::invalid(format!("parameter '{pair}' is not of the form key=value"))
            })?;
            map.insert(k.trim().to_string(), Value::from(v.trim()));
        }
        Ok(map)
    }

    /// The checked value of parameter `name`.
    pub fn get(&self, name: &str) -> Result<&Value> {
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

/// A Rust type that one parameter can have: how it is declared ([`ParamKind`]), read back from
/// a checked JSON value, and written to one.
///
/// Implemented for `f64`, `usize`, `bool`, `String`, [`Light`] and the choice enums
/// declared with `param_choice!`.
pub trait ParamType: Sized {
    /// The kind of the parameter, with its range where the type has one.
    fn kind(range: Option<std::ops::RangeInclusive<Self>>) -> ParamKind;
    /// The value from its checked (or default) JSON form; `None` when it has another type.
    fn from_value(value: &Value) -> Option<Self>;
    /// The value as JSON (checked again by [`Params::resolve`] when converted back).
    fn to_value(&self) -> Value;
    /// A stand-in used only if a declared default cannot be read (never, for a declaration that
    /// passes the tests).
    fn fallback() -> Self;
}

impl ParamType for f64 {
    fn kind(range: Option<std::ops::RangeInclusive<Self>>) -> ParamKind {
        let (min, max) = range.map_or((f64::MIN, f64::MAX), |r| (*r.start(), *r.end()));
        ParamKind::Number { min, max }
    }
    fn from_value(value: &Value) -> Option<Self> {
        value.as_f64()
    }
    fn to_value(&self) -> Value {
        Value::from(*self)
    }
    fn fallback() -> Self {
        0.0
    }
}

macro_rules! integer_param_type {
    ($($t:ty),*) => {$(
        impl ParamType for $t {
            fn kind(range: Option<std::ops::RangeInclusive<Self>>) -> ParamKind {
                let (min, max) = range.map_or((0, i64::MAX), |r| {
                    (
                        i64::try_from(*r.start()).unwrap_or(i64::MAX),
                        i64::try_from(*r.end()).unwrap_or(i64::MAX),
                    )
                });
                ParamKind::Integer { min, max }
            }
            fn from_value(value: &Value) -> Option<Self> {
                value.as_u64().and_then(|v| <$t>::try_from(v).ok())
            }
            fn to_value(&self) -> Value {
                Value::from(*self)
            }
            fn fallback() -> Self {
                0
            }
        }
    )*};
}
integer_param_type!(usize);

impl ParamType for bool {
    fn kind(_: Option<std::ops::RangeInclusive<Self>>) -> ParamKind {
        ParamKind::Bool
    }
    fn from_value(value: &Value) -> Option<Self> {
        value.as_bool()
    }
    fn to_value(&self) -> Value {
        Value::from(*self)
    }
    fn fallback() -> Self {
        false
    }
}

impl ParamType for String {
    fn kind(_: Option<std::ops::RangeInclusive<Self>>) -> ParamKind {
        ParamKind::Text
    }
    fn from_value(value: &Value) -> Option<Self> {
        value.as_str().map(str::to_string)
    }
    fn to_value(&self) -> Value {
        Value::from(self.as_str())
    }
    fn fallback() -> Self {
        String::new()
    }
}

impl ParamType for Light {
    fn kind(_: Option<std::ops::RangeInclusive<Self>>) -> ParamKind {
        ParamKind::Light
    }
    fn from_value(value: &Value) -> Option<Self> {
        value.as_str().and_then(|t| t.parse().ok())
    }
    fn to_value(&self) -> Value {
        Value::from(self.to_string())
    }
    fn fallback() -> Self {
        Light::FRONT
    }
}

/// A typed set of parameters: a struct declared with `stimulus_params!`, convertible from and
/// to the generic, name-based [`Params`].
pub trait ParamSet: Sized + Default {
    /// The declarations, in order, with the defaults replaced by `overrides` (name, value)
    /// where one names the parameter (the first match wins).
    fn specs_with(overrides: &[(&'static str, Value)]) -> Vec<ParamSpec>;

    /// The default value with the defaults replaced by `overrides`.
    fn default_with(overrides: &[(&'static str, Value)]) -> Self;

    /// Reads every parameter from resolved `params`.
    fn from_params(params: &Params) -> Result<Self>;

    /// Writes every parameter, unchecked, into `values`.
    fn write_values(&self, values: &mut Map<String, Value>);

    /// The declarations, in order, with their defaults (what `describe` shows).
    fn specs() -> Vec<ParamSpec> {
        Self::specs_with(&[])
    }

    /// Checks `given` (key → value, as from `key=value` pairs or a spec) and reads it; missing
    /// keys take their defaults.
    fn from_map(given: &Map<String, Value>) -> Result<Self> {
        Self::from_params(&Params::resolve(&Self::specs(), given)?)
    }

    /// The generic form, every value range-checked: what a sidecar records.
    fn to_params(&self) -> Result<Params> {
        let mut values = Map::new();
        self.write_values(&mut values);
        Params::resolve(&Self::specs(), &values)
    }

    /// Checks every value against its declared range or choices.
    fn validate(&self) -> Result<()> {
        self.to_params().map(drop)
    }
}

/// The value `overrides` gives `name`, else `default`.
#[doc(hidden)]
pub fn override_or(overrides: &[(&'static str, Value)], name: &str, default: Value) -> Value {
    overrides
        .iter()
        .find(|(n, _)| *n == name)
        .map_or(default, |(_, v)| v.clone())
}

/// `outer` followed by `local`: the overrides a nested set sees.
#[doc(hidden)]
pub fn chain_overrides(
    outer: &[(&'static str, Value)],
    local: Vec<(&'static str, Value)>,
) -> Vec<(&'static str, Value)> {
    outer.iter().cloned().chain(local).collect()
}

/// Reads parameter `name` of type `T` from resolved `params`.
#[doc(hidden)]
pub fn read_param<T: ParamType>(params: &Params, name: &str) -> Result<T> {
    T::from_value(params.get(name)?).ok_or_else(|| {
        Error::Compute(format!(
            "internal: parameter '{name}' does not have its declared type"
        ))
    })
}

/// The typed default of a parameter from its JSON default.
#[doc(hidden)]
pub fn default_param<T: ParamType>(value: &Value) -> T {
    T::from_value(value).unwrap_or_else(T::fallback)
}

/// Declares an enum of words for a choice parameter, with `NAMES` (in declaration order, as
/// `describe` lists them), `FromStr`, `Display`, serde as the word, and [`ParamType`].
#[macro_export]
macro_rules! param_choice {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $( $(#[doc = $doc:literal])* $variant:ident = $word:literal, )+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name {
            $( $(#[doc = $doc])* $variant, )+
        }

        impl $name {
            /// The words, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$($word),+];

            /// The word for this choice.
            pub fn name(self) -> &'static str {
                match self {
                    $( $name::$variant => $word, )+
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl std::str::FromStr for $name {
            type Err = $crate::error::Error;
            fn from_str(text: &str) -> $crate::error::Result<Self> {
                match text {
                    $( $word => Ok($name::$variant), )+
                    other => Err($crate::error::Error::unknown(
                        stringify!($name),
                        other,
                        Self::NAMES,
                    )),
                }
            }
        }

        impl From<$name> for serde_json::Value {
            fn from(v: $name) -> Self {
                serde_json::Value::from(v.name())
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let text = <String as serde::Deserialize>::deserialize(d)?;
                text.parse().map_err(serde::de::Error::custom)
            }
        }

        impl $crate::params::ParamType for $name {
            fn kind(_: Option<std::ops::RangeInclusive<Self>>) -> $crate::params::ParamKind {
                $crate::params::ParamKind::Choice(Self::NAMES)
            }
            fn from_value(value: &serde_json::Value) -> Option<Self> {
                value.as_str().and_then(|t| t.parse().ok())
            }
            fn to_value(&self) -> serde_json::Value {
                serde_json::Value::from(self.name())
            }
            fn fallback() -> Self {
                [$($name::$variant),+][0]
            }
        }
    };
}
pub use crate::param_choice;

/// Declares a typed parameter set: the struct, its `Default`, its [`ParamSet`] impl (the
/// [`ParamSpec`]s in field order, reading from and writing to [`Params`]) and
/// `TryFrom<&Params>`, all from one declaration per parameter:
///
/// ```text
/// stimulus_params! {
///     /// Discs on a panel.
///     pub struct DiscParams {
///         /// disc radius (deg)
///         radius: f64 = 1.0, range 0.01..=90.0;
///         /// light direction
///         light: Light = "above";
///         /// the shading parameters, with other defaults (flattened: their keys are ours)
///         flatten shading: ShadingParams { light: "above-left" };
///     }
/// }
/// ```
///
/// The parameter's key is the field's name and its one-line doc the field's doc comment.
#[macro_export]
macro_rules! stimulus_params {
    (
        $(#[$meta:meta])*
        pub struct $name:ident { $($body:tt)* }
    ) => {
        $crate::stimulus_params!(@munch [$(#[$meta])*] $name [] $($body)*);
    };
    // A flattened set, with its defaults overridden.
    (@munch $meta:tt $name:ident [$($done:tt)*]
        $(#[doc = $doc:literal])*
        flatten $f:ident : $ty:ty { $($o:ident : $ov:expr),* $(,)? };
        $($rest:tt)*
    ) => {
        $crate::stimulus_params!(@munch $meta $name
            [$($done)* (flat [$($doc)*] $f $ty [$($o : $ov),*] ())] $($rest)*);
    };
    // A parameter with a range.
    (@munch $meta:tt $name:ident [$($done:tt)*]
        $(#[doc = $doc:literal])*
        $f:ident : $ty:ty = $default:expr, range $range:expr;
        $($rest:tt)*
    ) => {
        $crate::stimulus_params!(@munch $meta $name
            [$($done)* (plain [$($doc)*] $f $ty [$default] (Some($range)))] $($rest)*);
    };
    // A parameter without one.
    (@munch $meta:tt $name:ident [$($done:tt)*]
        $(#[doc = $doc:literal])*
        $f:ident : $ty:ty = $default:expr;
        $($rest:tt)*
    ) => {
        $crate::stimulus_params!(@munch $meta $name
            [$($done)* (plain [$($doc)*] $f $ty [$default] (None))] $($rest)*);
    };
    (@munch [$($meta:tt)*] $name:ident
        [$(($kind:ident [$($doc:literal)*] $f:ident $ty:ty [$($default:tt)*] ($($range:tt)*)))*]
    ) => {
        $($meta)*
        #[derive(Debug, Clone, PartialEq)]
        pub struct $name {
            $( $(#[doc = $doc])* pub $f: $ty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                <Self as $crate::params::ParamSet>::default_with(&[])
            }
        }

        impl $crate::params::ParamSet for $name {
            #[allow(clippy::vec_init_then_push)] // one push per declared field
            fn specs_with(
                overrides: &[(&'static str, serde_json::Value)],
            ) -> Vec<$crate::params::ParamSpec> {
                let mut specs = Vec::new();
                $( $crate::stimulus_params!(@spec $kind specs overrides $f $ty
                    [concat!($($doc),*)] [$($default)*] ($($range)*)); )*
                specs
            }

            fn default_with(overrides: &[(&'static str, serde_json::Value)]) -> Self {
                $name {
                    $( $f: $crate::stimulus_params!(@default $kind overrides $f $ty
                        [$($default)*]), )*
                }
            }

            fn from_params(params: &$crate::params::Params) -> $crate::error::Result<Self> {
                Ok($name {
                    $( $f: $crate::stimulus_params!(@read $kind params $f $ty), )*
                })
            }

            fn write_values(&self, values: &mut serde_json::Map<String, serde_json::Value>) {
                $( $crate::stimulus_params!(@write $kind self values $f $ty); )*
            }
        }

        impl TryFrom<&$crate::params::Params> for $name {
            type Error = $crate::error::Error;
            fn try_from(params: &$crate::params::Params) -> $crate::error::Result<Self> {
                <Self as $crate::params::ParamSet>::from_params(params)
            }
        }
    };
    (@spec plain $specs:ident $ov:ident $f:ident $ty:ty [$doc:expr] [$default:expr] ($range:expr)) => {
        $specs.push($crate::params::ParamSpec {
            name: stringify!($f),
            kind: <$ty as $crate::params::ParamType>::kind($range),
            default: $crate::params::override_or(
                $ov,
                stringify!($f),
                serde_json::Value::from($default),
            ),
            doc: $doc.trim(),
        });
    };
    (@spec flat $specs:ident $ov:ident $f:ident $ty:ty [$doc:expr] [$($o:ident : $v:expr),*] ()) => {
        $specs.extend(<$ty as $crate::params::ParamSet>::specs_with(
            &$crate::params::chain_overrides(
                $ov,
                vec![$((stringify!($o), serde_json::Value::from($v))),*],
            ),
        ));
    };
    (@default plain $ov:ident $f:ident $ty:ty [$default:expr]) => {
        $crate::params::default_param::<$ty>(&$crate::params::override_or(
            $ov,
            stringify!($f),
            serde_json::Value::from($default),
        ))
    };
    (@default flat $ov:ident $f:ident $ty:ty [$($o:ident : $v:expr),*]) => {
        <$ty as $crate::params::ParamSet>::default_with(&$crate::params::chain_overrides(
            $ov,
            vec![$((stringify!($o), serde_json::Value::from($v))),*],
        ))
    };
    (@read plain $params:ident $f:ident $ty:ty) => {
        $crate::params::read_param::<$ty>($params, stringify!($f))?
    };
    (@read flat $params:ident $f:ident $ty:ty) => {
        <$ty as $crate::params::ParamSet>::from_params($params)?
    };
    (@write plain $self:ident $values:ident $f:ident $ty:ty) => {
        $values.insert(
            stringify!($f).to_string(),
            $crate::params::ParamType::to_value(&$self.$f),
        );
    };
    (@write flat $self:ident $values:ident $f:ident $ty:ty) => {
        $crate::params::ParamSet::write_values(&$self.$f, $values);
    };
}
pub use crate::stimulus_params;

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

#[cfg(test)]
mod typed_tests {
    use super::*;

    param_choice! {
        /// A test choice.
        pub enum Shape {
            /// Round.
            Round = "round",
            /// Square.
            Square = "square",
        }
    }

    stimulus_params! {
        /// A shared test set.
        pub struct Inner {
            /// a length (deg)
            length: f64 = 1.0, range 0.0..=10.0;
            /// the shape
            shape: Shape = Shape::Round;
        }
    }

    stimulus_params! {
        /// A test set.
        pub struct Outer {
            /// how many
            count: usize = 3, range 1..=9;
            /// the inner set, longer by default
            flatten inner: Inner { length: 2.5 };
            /// where the light is
            light: Light = "left";
            /// on or off
            on: bool = true;
            /// a label
            label: String = "x";
        }
    }

    #[test]
    fn declarations_come_in_field_order_with_overridden_defaults() {
        let specs = Outer::specs();
        let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
        assert_eq!(names, ["count", "length", "shape", "light", "on", "label"]);
        assert_eq!(specs[0].kind, ParamKind::Integer { min: 1, max: 9 });
        assert_eq!(specs[1].default, Value::from(2.5));
        assert_eq!(specs[1].doc, "a length (deg)");
        assert_eq!(specs[2].kind, ParamKind::Choice(&["round", "square"]));
        assert_eq!(specs[3].default, Value::from("left"));
        assert_eq!(Inner::default().length, 1.0);
        let d = Outer::default();
        assert_eq!(
            (d.count, d.inner.length, d.inner.shape),
            (3, 2.5, Shape::Round)
        );
        assert!((d.light.tilt_deg() - 90.0).abs() < 1e-9);
        assert_eq!((d.on, d.label.as_str()), (true, "x"));
    }

    #[test]
    fn typed_values_convert_both_ways() {
        let given = Params::parse_pairs(&["shape=square", "count=9", "light=0,1,1"]).unwrap();
        let resolved = Params::resolve(&Outer::specs(), &given).unwrap();
        let typed = Outer::try_from(&resolved).unwrap();
        assert_eq!((typed.count, typed.inner.shape), (9, Shape::Square));
        assert_eq!(typed.to_params().unwrap(), resolved);
        assert_eq!("square".parse::<Shape>().unwrap().to_string(), "square");
        assert!("oval"
            .parse::<Shape>()
            .unwrap_err()
            .to_string()
            .contains("round"));
        let e = Outer::from_map(&Params::parse_pairs(&["count=10"]).unwrap())
            .unwrap_err()
            .to_string();
        assert!(e.contains("count") && e.contains("1..9"), "{e}");
        // A struct built in Rust is checked on the way back.
        let bad = Outer {
            count: 0,
            ..Outer::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("count"));
    }
}
