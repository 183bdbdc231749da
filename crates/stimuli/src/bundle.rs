//! The `.mat` and `.npz` bundles: one file holding what stimupy's export holds — the picture
//! `img`, the `target_mask` and every parameter as a field — so that `scipy.io.loadmat`,
//! `numpy.load` and MATLAB/Octave's `load` give everything in one step.
//!
//! Fields, in this order: `img` (H × W, or H × W × 3; in the value range asked for),
//! `target_mask` (H × W labels, 0 outside every target) and `target_names` where the stimulus
//! has targets; `stimulus`, `visual_size` (height, width in degrees), `ppd`, `shape` (height,
//! width in pixels), `seed`, `range`, `program`; `light_direction` (x right, y up, z toward the
//! viewer) where the stimulus has a light; every parameter under its own name (numbers as
//! doubles, booleans as 0/1, text as strings, lists as rows; a parameter whose name is taken by
//! a field above is prefixed `param_`); and with layers, `depth`, `normals` (H × W × 3),
//! `albedo` and `shading`. Sizes are (height, width) as in stimupy; in `.mat` a scalar is 1 × 1
//! and a pair 1 × 2, in `.npz` a scalar is a 0-d array and a pair has shape (2,).

use super::{Output, Pixels, Range, Request};
use crate::error::Result;
use crate::grid::Grid;
use serde_json::Value;

/// One field of a bundle.
#[derive(Debug, Clone, PartialEq)]
pub enum Field {
    /// Doubles of NumPy shape `dims` (`[]` a scalar, `[n]` a row) in C order.
    Numbers {
        /// The shape, outermost axis first.
        dims: Vec<usize>,
        /// The values, row-major.
        values: Vec<f64>,
    },
    /// One string.
    Text(String),
    /// A list of strings.
    Texts(Vec<String>),
}

impl Field {
    fn scalar(v: f64) -> Field {
        Field::Numbers {
            dims: vec![],
            values: vec![v],
        }
    }

    fn row(values: Vec<f64>) -> Field {
        Field::Numbers {
            dims: vec![values.len()],
            values,
        }
    }

    fn grid<T: Copy>(grid: &Grid<T>, channels: usize, value: impl Fn(T) -> Vec<f64>) -> Field {
        let mut dims = vec![grid.height(), grid.width()];
        if channels > 1 {
            dims.push(channels);
        }
        Field::Numbers {
            dims,
            values: grid.data().iter().flat_map(|&v| value(v)).collect(),
        }
    }
}

/// The fields of the bundle of a render (the module documentation lists them).
///
/// ```
/// use shadelab_stimuli::bundle;
/// use shadelab::stimulus::{generate, ExportOptions};
/// use shadelab::SizeRequest;
/// let size = SizeRequest { visual_size: Some((4.0, 8.0)), ppd: Some(8.0), shape: None };
/// let (request, output) = generate("checkerboard", &Default::default(), &size, 0, 1 << 20)?;
/// let fields = bundle::fields("checkerboard", &request, &output, &ExportOptions::default());
/// let get = |name: &str| fields.iter().find(|(n, _)| n == name).map(|(_, f)| f.clone());
/// assert_eq!(
///     get("shape"),
///     Some(bundle::Field::Numbers { dims: vec![2], values: vec![32.0, 64.0] })
/// );
/// assert!(matches!(get("img"), Some(bundle::Field::Numbers { dims, .. }) if dims == [32, 64]));
/// # Ok::<(), shadelab::Error>(())
/// ```
pub fn fields(
    name: &str,
    request: &Request,
    output: &Output,
    options: &super::ExportOptions,
) -> Vec<(String, Field)> {
    let to_range = |v: f64| options.range.apply(v);
    let g = &request.geometry;
    let mut out: Vec<(String, Field)> = Vec::new();
    let img = match &output.pixels {
        Pixels::Gray(img) => Field::grid(img, 1, |v| vec![to_range(v)]),
        Pixels::Rgb(img) => Field::grid(img, 3, |p| p.map(to_range).to_vec()),
    };
    out.push(("img".into(), img));
    if let Some(t) = &output.targets {
        out.push((
            "target_mask".into(),
            Field::grid(&t.labels, 1, |l| vec![f64::from(l)]),
        ));
        out.push(("target_names".into(), Field::Texts(t.names.clone())));
    }
    out.push(("stimulus".into(), Field::Text(name.to_string())));
    out.push((
        "visual_size".into(),
        Field::row(vec![g.height_deg(), g.width_deg()]),
    ));
    out.push(("ppd".into(), Field::scalar(g.ppd)));
    out.push((
        "shape".into(),
        Field::row(vec![g.height as f64, g.width as f64]),
    ));
    out.push(("seed".into(), Field::scalar(request.seed as f64)));
    let range = match options.range {
        Range::Unit => "0..1",
        Range::Psychopy => "-1..1",
    };
    out.push(("range".into(), Field::Text(range.into())));
    out.push((
        "program".into(),
        Field::Text(format!("shadelab {}", crate::io::PROGRAM_VERSION)),
    ));
    let params = request.params.to_json();
    let light = params
        .get("light")
        .and_then(Value::as_str)
        .and_then(|l| l.parse::<crate::light::Light>().ok());
    if let Some(light) = light {
        let d = light.direction();
        out.push(("light_direction".into(), Field::row(vec![d.x, d.y, d.z])));
    }
    let layers = match (&output.surface, options.layers) {
        (Some(s), true) => Some(s),
        _ => None,
    };
    let layer_names = ["depth", "normals", "albedo", "shading"];
    if let Value::Object(map) = &params {
        for (key, value) in map {
            let Some(field) = param_field(value) else {
                continue;
            };
            let mut key = variable_name(key);
            if out.iter().any(|(n, _)| *n == key) || layer_names.contains(&key.as_str()) {
                key = format!("param_{key}");
            }
            out.push((key, field));
        }
    }
    if let Some(s) = layers {
        out.push(("depth".into(), Field::grid(&s.depth, 1, |v| vec![v])));
        out.push((
            "normals".into(),
            Field::grid(&s.normals, 3, |n| vec![n.x, n.y, n.z]),
        ));
        if let Some(a) = &s.albedo {
            out.push(("albedo".into(), Field::grid(a, 1, |v| vec![v])));
        }
        if let Some(sh) = &s.shading {
            out.push(("shading".into(), Field::grid(sh, 1, |v| vec![v])));
        }
    }
    out
}

/// A parameter's value as a field: numbers as doubles, booleans as 0/1, text as a string,
/// lists of numbers as a row and of strings as a list; anything else as its JSON text.
fn param_field(value: &Value) -> Option<Field> {
    Some(match value {
        Value::Null => return None,
        Value::Bool(b) => Field::scalar(f64::from(u8::from(*b))),
        Value::Number(n) => Field::scalar(n.as_f64()?),
        Value::String(s) => Field::Text(s.clone()),
        Value::Array(items) if items.iter().all(Value::is_number) => {
            Field::row(items.iter().filter_map(Value::as_f64).collect())
        }
        Value::Array(items) if items.iter().all(Value::is_string) => Field::Texts(
            items
                .iter()
                .filter_map(|v| v.as_str().map(str::to_string))
                .collect(),
        ),
        other => Field::Text(other.to_string()),
    })
}

/// A parameter name as a MATLAB (and Python) identifier: letters, digits and `_`, starting
/// with a letter.
fn variable_name(key: &str) -> String {
    let mut name: String = key
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !name.starts_with(|c: char| c.is_ascii_alphabetic()) {
        name.insert_str(0, "p_");
    }
    name.truncate(63);
    name
}

/// The bundle as a MATLAB v5 MAT-file (see the `mat` module): scalars 1 × 1, rows 1 × n, text
/// as char arrays and lists of text as cell arrays.
pub fn to_mat(fields: &[(String, Field)]) -> Result<Vec<u8>> {
    use super::mat::{encode_vars, to_column_major, MatValue};
    let vars: Vec<(String, MatValue)> = fields
        .iter()
        .map(|(name, field)| {
            let value = match field {
                Field::Numbers { dims, values } => {
                    let dims = match dims.len() {
                        0 => vec![1, 1],
                        1 => vec![1, dims[0]],
                        _ => dims.clone(),
                    };
                    MatValue::Double {
                        data: to_column_major(&dims, values),
                        dims,
                    }
                }
                Field::Text(text) => MatValue::Char(text.clone()),
                Field::Texts(items) => MatValue::Cell(items.clone()),
            };
            (name.clone(), value)
        })
        .collect();
    encode_vars(&vars)
}

/// The bundle as a NumPy `.npz` archive: numbers as float64 arrays (a scalar 0-d, a row of
/// shape (n,)), text as unicode arrays (`np.load` needs no pickles).
pub fn to_npz(fields: &[(String, Field)]) -> Result<Vec<u8>> {
    use crate::io::{encode_f64, encode_npz, encode_text};
    let members = fields
        .iter()
        .map(|(name, field)| {
            let bytes = match field {
                Field::Numbers { dims, values } => encode_f64(dims, values)?,
                Field::Text(text) => encode_text(&[], std::slice::from_ref(text))?,
                Field::Texts(items) => encode_text(&[items.len()], items)?,
            };
            Ok((name.clone(), bytes))
        })
        .collect::<Result<Vec<_>>>()?;
    encode_npz(&members)
}
