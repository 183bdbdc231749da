//! `shadelab._shadelab`: the compiled half of the Python package. Each function turns Python
//! values into one of the library's pipeline configurations (`shadelab::pipeline::*`), runs the
//! SAME `run` the command line runs with the GIL released, and hands the results back as NumPy
//! arrays that own the library's buffers (no copy) and reports as JSON text (the pure-Python
//! layer, `shadelab/__init__.py`, turns that into dicts). No algorithm lives here.

use numpy::ndarray::{Array2, Array3, ArrayView2};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Map, Value};
use shadelab::pipeline::{self as pl, perception};
use shadelab::{Error, NoProgress, Pixels, Setting, SizeRequest};
use shadelab::{Grid, Image, Labels, Mask, RgbImage};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::time::Duration;

mod commands;
mod reports;

use reports::{Kind, ReportHandle};

/// The library's error as the Python exception a Python user expects, with its one-line text.
pub(crate) fn to_py(e: Error) -> PyErr {
    let text = e.to_string();
    match &e {
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(text)
        }
        // What the keyword remedies, as the command line names its flag.
        Error::NotOurs { path, .. } if path.is_dir() => PyOSError::new_err(format!(
            "{text}; pass force=True to write into it (every file shadelab did not write stays)"
        )),
        Error::NotOurs { .. } => {
            PyOSError::new_err(format!("{text}; pass force=True to replace it"))
        }
        Error::Io { .. } | Error::Locked { .. } => PyOSError::new_err(text),
        Error::Compute(_) => PyRuntimeError::new_err(text),
        // The settings a message names, as Python's keywords.
        Error::Setting(message) => {
            let text = message.render(|setting, words| match setting {
                Setting::Mask => "mask=".into(),
                Setting::Ppd => "ppd=".into(),
                Setting::InputGamma => "input_gamma=".into(),
                Setting::Keys => "keys='fj' (bump, dimple)".into(),
                Setting::Lambda => format!("{words} (lam=)"),
                Setting::JacobiMethod => format!("{words} (method='jacobi')"),
                Setting::IncludeSimulated => "include_simulated=True".into(),
                Setting::MixedDesigns => "mixed_designs=True".into(),
                _ => words.into(),
            });
            if message.settings().any(|s| s == Setting::Lambda) {
                PyRuntimeError::new_err(text)
            } else {
                PyValueError::new_err(text)
            }
        }
        _ => PyValueError::new_err(text),
    }
}

/// How often a running call looks for Ctrl-C (Python's pending signals).
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Runs `work` with the GIL released; a library error becomes its Python exception and a panic
/// (a bug, never expected) a RuntimeError without the panic's text.
///
/// Ctrl-C: the work runs on a worker thread while the calling thread looks for Python's
/// pending signals every [`SIGNAL_POLL`] (`check_signals`, which runs Python's handlers: the
/// default SIGINT handler raises KeyboardInterrupt). When one raises, the library's stop flag
/// ([`shadelab::cancel`]) is raised, the work stops at its next check (an output being written
/// is removed, never left half-written), the flag is lowered for the next call, and the
/// handler's exception is raised in Python.
pub(crate) fn run_released<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Error> + Send,
) -> PyResult<T> {
    run_watched(py, work, |_| Ok(()))
}

/// [`run_released`] that also runs `watch` on the calling thread, with the GIL, at every look
/// for Ctrl-C and once at the end; an exception it raises stops the work as Ctrl-C does and is
/// raised in Python.
fn run_watched<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> Result<T, Error> + Send,
    mut watch: impl FnMut(Python<'_>) -> PyResult<()> + Send,
) -> PyResult<T> {
    let (outcome, interrupted) = py.detach(|| {
        std::thread::scope(|scope| {
            let (done, finished) = mpsc::channel();
            let worker = scope.spawn(move || {
                let outcome = catch_unwind(AssertUnwindSafe(work));
                let _ = done.send(());
                outcome
            });
            let mut interrupted = None;
            while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(SIGNAL_POLL) {
                if interrupted.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals().and_then(|_| watch(py)))
                    {
                        shadelab::cancel::request();
                        interrupted = Some(e);
                    }
                }
            }
            let outcome = worker.join().unwrap_or_else(Err);
            if interrupted.is_none() {
                if let Err(e) = Python::attach(&mut watch) {
                    interrupted = Some(e);
                }
            }
            if interrupted.is_some() {
                shadelab::cancel::reset();
            }
            (outcome, interrupted)
        })
    });
    if let Some(e) = interrupted {
        return Err(e);
    }
    outcome
        .map_err(|_| {
            PyRuntimeError::new_err(
                "shadelab failed unexpectedly (an internal error); please report it with the call that caused it",
            )
        })?
        .map_err(to_py)
}

/// Where a running call stands, as its last progress reports left it (see
/// [`shadelab::Progress`]); read by the calling thread, which hands it to Python's callback.
#[derive(Default)]
struct Standing {
    stage: String,
    message: String,
    done: u64,
    total: u64,
    seconds_left: Option<f64>,
    /// Whether a report came since the callback last saw it.
    changed: bool,
}

/// The library's progress reports kept for Python's `progress` callback.
#[derive(Default)]
struct Reported(std::sync::Mutex<Standing>);

impl Reported {
    fn update(&self, change: impl FnOnce(&mut Standing)) {
        if let Ok(mut s) = self.0.lock() {
            change(&mut s);
            s.changed = true;
        }
    }

    /// Calls `callback` with a dict of where the call stands, if a report came since the last
    /// call: `stage`, `message`, `done` and `total` (steps of the stage) and `seconds_left`
    /// (the work's own estimate, or None where it makes none).
    fn hand_to(&self, py: Python<'_>, callback: &Py<PyAny>) -> PyResult<()> {
        let dict = {
            let Ok(mut s) = self.0.lock() else {
                return Ok(());
            };
            if !s.changed {
                return Ok(());
            }
            s.changed = false;
            let dict = PyDict::new(py);
            dict.set_item("stage", &s.stage)?;
            dict.set_item("message", &s.message)?;
            dict.set_item("done", s.done)?;
            dict.set_item("total", s.total)?;
            dict.set_item("seconds_left", s.seconds_left)?;
            dict
        };
        callback.call1(py, (dict,)).map(|_| ())
    }
}

impl shadelab::Progress for Reported {
    fn start(&self, total: u64, what: &str) {
        self.update(|s| {
            *s = Standing {
                stage: what.to_string(),
                message: what.to_string(),
                total,
                ..Standing::default()
            }
        });
    }
    fn advance(&self, steps: u64) {
        self.update(|s| s.done += steps);
    }
    fn set_position(&self, done: u64) {
        self.update(|s| s.done = done);
    }
    fn time_left(&self, seconds: f64) {
        self.update(|s| s.seconds_left = Some(seconds));
    }
    fn message(&self, text: &str) {
        self.update(|s| s.message = text.to_string());
    }
}

/// Runs `work` as [`run_released`] does, handing its progress to `callback` (when given) from
/// the calling thread every [`SIGNAL_POLL`] while it changes, and once at the end.
fn run_reporting<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    work: impl FnOnce(&dyn shadelab::Progress) -> Result<T, Error> + Send,
) -> PyResult<T> {
    let Some(callback) = callback else {
        return run_released(py, || work(&NoProgress));
    };
    let reported = Reported::default();
    run_watched(py, || work(&reported), |py| reported.hand_to(py, &callback))
}

/// The library's size request from Python's pairs: both are (height, width), as stimupy's.
fn size_request(
    visual_size: Option<(f64, f64)>,
    ppd: Option<f64>,
    shape: Option<(usize, usize)>,
) -> SizeRequest {
    SizeRequest {
        visual_size,
        ppd,
        shape,
    }
}

/// A JSON object of parameters from its text (written by the Python layer's `json.dumps`).
pub(crate) fn params_from(json: &str) -> PyResult<Map<String, Value>> {
    match serde_json::from_str(json) {
        Ok(Value::Object(map)) => Ok(map),
        _ => Err(PyValueError::new_err(
            "parameters must be a dict of numbers, strings and booleans",
        )),
    }
}

/// JSON text of any report.
pub(crate) fn json_text(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(value)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot serialise the report: {e}")))
}

/// An H×W array owning the grid's buffer (no copy).
pub(crate) fn image_array<'py, T: numpy::Element>(
    py: Python<'py>,
    grid: Grid<T>,
) -> Bound<'py, PyArray2<T>> {
    let (w, h) = (grid.width(), grid.height());
    Array2::from_shape_vec((h, w), grid.into_vec())
        .expect("a grid's buffer holds width × height values")
        .into_pyarray(py)
}

/// An H×W×3 array owning the grid's buffer (no copy: `[f64; 3]` per pixel is already three
/// consecutive values).
pub(crate) fn rgb_array<'py>(py: Python<'py>, grid: RgbImage) -> Bound<'py, PyArray3<f64>> {
    let (w, h) = (grid.width(), grid.height());
    Array3::from_shape_vec((h, w, 3), grid.into_vec().into_flattened())
        .expect("a grid's buffer holds width × height pixels")
        .into_pyarray(py)
}

/// Unit normals (x right, y up, z toward the viewer) as an H×W×3 array.
fn normals_array<'py>(
    py: Python<'py>,
    normals: Grid<shadelab::Normal>,
) -> Bound<'py, PyArray3<f64>> {
    let (w, h) = (normals.width(), normals.height());
    // Same size and alignment: the collect reuses the buffer.
    let xyz: Vec<[f64; 3]> = normals
        .into_vec()
        .into_iter()
        .map(|n| [n.x, n.y, n.z])
        .collect();
    rgb_array(py, Grid::from_vec(w, h, xyz).expect("w × h normals"))
}

/// A grid from a 2-D array of any memory order or stride (values read in row-major order).
fn grid_from<T: Clone + numpy::Element>(a: ArrayView2<'_, T>) -> Grid<T> {
    let (h, w) = a.dim();
    let data: Vec<T> = a.iter().cloned().collect();
    Grid::from_vec(w, h, data).expect("h × w values")
}

/// The picture handed over from Python: H×W gray or H×W×3 RGB, float64 (the Python layer
/// converts other real dtypes the way the command line reads a `.npy`).
#[derive(FromPyObject)]
enum ArrayIn<'py> {
    Gray(PyReadonlyArray2<'py, f64>),
    Rgb(PyReadonlyArray3<'py, f64>),
}

impl ArrayIn<'_> {
    fn pixels(&self) -> PyResult<Pixels> {
        match self {
            ArrayIn::Gray(a) => Ok(Pixels::Gray(grid_from(a.as_array()))),
            ArrayIn::Rgb(a) => {
                let a = a.as_array();
                let (h, w, c) = a.dim();
                if c != 3 {
                    return Err(PyValueError::new_err(format!(
                        "an image must be H×W (gray) or H×W×3 (RGB), not {h}×{w}×{c}"
                    )));
                }
                let data: Vec<[f64; 3]> = a
                    .outer_iter()
                    .flat_map(|row| {
                        row.outer_iter()
                            .map(|p| [p[0], p[1], p[2]])
                            .collect::<Vec<_>>()
                    })
                    .collect();
                Ok(Pixels::Rgb(
                    Grid::from_vec(w, h, data).expect("h × w pixels"),
                ))
            }
        }
    }
}

/// The stimuli: (name, one-line description) in the library's order.
#[pyfunction]
fn stimuli() -> Vec<(&'static str, &'static str)> {
    pl::render::list()
        .into_iter()
        .map(|s| (s.name, s.summary))
        .collect()
}

/// A stimulus's description (parameters, defaults, ranges, docs) as JSON text, its default
/// visual size as (height, width).
#[pyfunction]
fn describe(name: &str) -> PyResult<String> {
    let description = pl::render::describe(name).map_err(to_py)?;
    json_text(&description)
}

/// Checks the keyword names `given` to a Python function against the stimulus's parameters:
/// an unknown one is a ValueError naming the nearest among them and the function's own
/// `keywords`, where keywords enter, before anything is rendered.
#[pyfunction]
fn check_params(stimulus: &str, given: Vec<String>, keywords: Vec<String>) -> PyResult<()> {
    let keywords: Vec<&str> = keywords.iter().map(String::as_str).collect();
    shadelab::stimulus::check_param_names(stimulus, &given, &keywords).map_err(to_py)
}

/// The size of an array handed over as a picture, mask or labels, checked against the pixel
/// limit before anything is allocated for it (`what` names it in the error): `shape` is
/// NumPy's, height first.
#[pyfunction]
fn check_shape(shape: Vec<usize>, what: &str) -> PyResult<()> {
    let (h, w) = match shape.as_slice() {
        [h, w] | [h, w, _] => (*h, *w),
        _ => return Ok(()),
    };
    let limit = shadelab::DEFAULT_MAX_PIXELS;
    shadelab::check_size(w, h, limit).map_err(|e| match e {
        Error::TooLarge(_) => PyValueError::new_err(format!(
            "{what}: {h} high × {w} wide is over the limit of {limit} pixels"
        )),
        other => PyValueError::new_err(format!("{what}: {other}")),
    })
}

/// Renders a stimulus: (report JSON, img, target_mask or None, target names one a line, layers dict).
#[pyfunction]
#[pyo3(signature = (name, params_json, visual_size, ppd, shape, seed, layers, bit_depth, gamma, range, display, display_json, luminance))]
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    name: &str,
    params_json: &str,
    visual_size: Option<(f64, f64)>,
    ppd: Option<f64>,
    shape: Option<(usize, usize)>,
    seed: u64,
    layers: bool,
    bit_depth: Option<u8>,
    gamma: Option<f64>,
    range: &str,
    display: Option<std::path::PathBuf>,
    display_json: Option<String>,
    luminance: Option<String>,
) -> PyResult<(
    String,
    Bound<'py, PyAny>,
    Option<Bound<'py, PyArray2<u16>>>,
    String,
    Bound<'py, PyDict>,
)> {
    let mut config = pl::render::RenderConfig::new(name);
    config.params = params_from(params_json)?;
    config.size = size_request(visual_size, ppd, shape);
    config.seed = seed;
    let display = (display, display_json);
    config.export = export_options(bit_depth.unwrap_or(16), gamma, range, display, luminance)?;
    let export = config.export.clone();
    let (report, shown) = run_released(py, || {
        let report = pl::render::run(&config, &NoProgress)?;
        let shown = shadelab::stimulus::shown_on_display(name, &report.output, &export)?;
        Ok((report, shown))
    })?;
    let text = json_text(&report)?;
    let output = report.output;
    let extra = PyDict::new(py);
    // What a file of these options holds: a display's codes and the cd/m² they show, or the
    // PNG codes of a bit depth or gamma asked for.
    if let (Some(mut shown), Some(display)) = (shown, &export.display) {
        let (w, h) = output.pixels.size();
        let codes = std::mem::take(&mut shown.codes);
        let codes = if shown.channels == 3 {
            Array3::from_shape_vec((h, w, 3), codes).map(|a| a.into_pyarray(py).into_any())
        } else {
            Array2::from_shape_vec((h, w), codes).map(|a| a.into_pyarray(py).into_any())
        }
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        extra.set_item("codes", codes)?;
        extra.set_item("luminance_cd_m2", image_array(py, shown.luminance.clone()))?;
        let mut record = display.to_json();
        if let Value::Object(fields) = &mut record {
            fields.extend(shown.to_json());
        }
        if let Some(t) = &output.targets {
            record["targets"] = serde_json::to_value(shown.targets(&t.labels, &t.names))
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        }
        extra.set_item("display_json", record.to_string())?;
    } else if export.gamma.is_some() || bit_depth.is_some() {
        if let Pixels::Gray(i) = &output.pixels {
            let codes = shadelab::display::stimulus_codes(i.data(), export.bit_depth, export.gamma)
                .map_err(to_py)?;
            let grid = Grid::from_vec(i.width(), i.height(), codes).map_err(to_py)?;
            extra.set_item("codes", image_array(py, grid))?;
        }
    }
    let range = config.export.range;
    // The library's buffer itself in the unit range (no copy); a new one in another range.
    let unit = range == shadelab::stimulus::Range::Unit;
    let img = match output.pixels {
        Pixels::Gray(i) if unit => image_array(py, i).into_any(),
        Pixels::Rgb(i) if unit => rgb_array(py, i).into_any(),
        Pixels::Gray(i) => image_array(py, i.map(|&v| range.apply(v))).into_any(),
        Pixels::Rgb(i) => rgb_array(py, i.map(|p| p.map(|v| range.apply(v)))).into_any(),
    };
    // The names as one text, a name a line (split by the Python layer): one string to hand
    // over instead of one per target (a 32 × 32 checkerboard has 1024).
    let (mask, names) = match output.targets {
        Some(t) => (Some(image_array(py, t.labels)), t.names.join("\n")),
        None => (None, String::new()),
    };
    if layers {
        let Some(s) = output.surface else {
            return Err(PyValueError::new_err(format!(
                "'{name}' is not a rendered surface: it has no depth, normals or shading layers"
            )));
        };
        extra.set_item("depth", image_array(py, s.depth))?;
        extra.set_item("normals", normals_array(py, s.normals))?;
        if let Some(a) = s.albedo {
            extra.set_item("albedo", image_array(py, a))?;
        }
        if let Some(sh) = s.shading {
            extra.set_item("shading", image_array(py, sh))?;
        }
    }
    Ok((text, img, mask, names, extra))
}

/// The value range of Python's `range` keyword: `unit` (0..1) or `psychopy` (-1..1).
fn value_range(range: &str) -> PyResult<shadelab::stimulus::Range> {
    match range {
        "unit" => Ok(shadelab::stimulus::Range::Unit),
        "psychopy" => Ok(shadelab::stimulus::Range::Psychopy),
        other => Err(PyValueError::new_err(format!(
            "range '{other}': unit (0..1) or psychopy (-1..1)"
        ))),
    }
}

/// The export options of Python's `render`/`save` keywords, checked as the command line's
/// flags are: a bit depth of 8 or 16, a range `unit` or `psychopy`, a display from a file or
/// a dict's JSON (relative names resolve against the working folder), a luminance `LO,HI` or
/// `background=B,michelson=C`.
fn export_options(
    bit_depth: u8,
    gamma: Option<f64>,
    range: &str,
    (display, display_json): (Option<std::path::PathBuf>, Option<String>),
    luminance: Option<String>,
) -> PyResult<shadelab::stimulus::ExportOptions> {
    let mut export = shadelab::stimulus::ExportOptions {
        gamma,
        ..Default::default()
    };
    export.bit_depth = match bit_depth {
        8 => shadelab::BitDepth::Eight,
        16 => shadelab::BitDepth::Sixteen,
        other => {
            return Err(PyValueError::new_err(format!(
                "bit_depth {other}: a PNG is written with 8 or 16 bits"
            )))
        }
    };
    export.range = value_range(range)?;
    export.display = match (display, display_json) {
        (Some(path), _) => Some(shadelab::read_display(&path).map_err(to_py)?),
        (None, Some(text)) => {
            let value: Value = serde_json::from_str(&text)
                .map_err(|e| PyValueError::new_err(format!("display: {e}")))?;
            Some(
                shadelab::display::display_from_value(&value, std::path::Path::new("."))
                    .map_err(to_py)?,
            )
        }
        (None, None) => None,
    };
    if let Some(text) = luminance {
        export.luminance = Some(
            text.parse()
                .map_err(|e: Error| PyValueError::new_err(format!("luminance: {e}")))?,
        );
    }
    // The command line refuses these together by its flags.
    if export.display.is_some() && (gamma.is_some() || bit_depth != 16 || range != "unit") {
        return Err(PyValueError::new_err(
            "display: a display's model sets the codes; give it without gamma, bit_depth or range",
        ));
    }
    export.check_display_options().map_err(to_py)?;
    Ok(export)
}

/// Writes the picture `image` of a render as `shadelab render` writes that render (the
/// picture in the format its extension names, its mask, its sidecar, with `layers` the
/// surface layers): the render is made again from its record for its mask, layers and
/// sidecar, and the picture written is `image` (in `image_range`, as `render` handed it
/// over), through the same writer; an `image` that is not the render is recorded as edited
/// ([`pl::render::RenderReport::with_picture`]), and so are `targets` (the dict's
/// `target_mask` and `target_names`) that are not its targets
/// ([`pl::render::RenderReport::with_targets`]). Returns the paths written.
#[pyfunction]
#[pyo3(signature = (image, image_range, targets, name, params_json, ppd, shape, seed, out, bit_depth, gamma, range, display, display_json, luminance, layers, force))]
#[allow(clippy::too_many_arguments)]
fn save(
    py: Python<'_>,
    image: ArrayIn<'_>,
    image_range: &str,
    targets: Option<(PyReadonlyArray2<'_, u16>, Vec<String>)>,
    name: &str,
    params_json: &str,
    ppd: f64,
    shape: (usize, usize),
    seed: u64,
    out: std::path::PathBuf,
    bit_depth: u8,
    gamma: Option<f64>,
    range: &str,
    display: Option<std::path::PathBuf>,
    display_json: Option<String>,
    luminance: Option<String>,
    layers: bool,
    force: bool,
) -> PyResult<Vec<String>> {
    let mut config = pl::render::RenderConfig::new(name);
    config.params = params_from(params_json)?;
    config.size = size_request(None, Some(ppd), Some(shape));
    config.seed = seed;
    config.export = export_options(bit_depth, gamma, range, (display, display_json), luminance)?;
    let export = &mut config.export;
    export.layers = layers;
    let pixels = image.pixels()?;
    let image_range = value_range(image_range)?;
    let targets =
        targets.map(|(labels, names)| -> (Labels, _) { (grid_from(labels.as_array()), names) });
    let written = run_released(py, || {
        config.validate()?;
        config.check_output(&out)?;
        let mut report =
            pl::render::run(&config, &NoProgress)?.with_picture(pixels, image_range, "img")?;
        if let Some((labels, names)) = targets {
            report = report.with_targets(labels, names, "target_mask")?;
        }
        report.write(&shadelab::Output::new(&out).force(force))
    })?;
    Ok(written
        .into_iter()
        .map(|p| p.display().to_string())
        .collect())
}

/// Solves an image for shape: (normals, depth, f, g, report JSON).
#[pyfunction]
#[pyo3(signature = (image, mask, light, boundary, albedo, albedo_estimate, lam, method, tol, max_iter, saturation, progress=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn solve<'py>(
    py: Python<'py>,
    image: PyReadonlyArray2<'py, f64>,
    mask: Option<PyReadonlyArray2<'py, bool>>,
    light: &str,
    boundary: &str,
    albedo: Option<f64>,
    albedo_estimate: bool,
    lam: f64,
    method: Option<&str>,
    tol: Option<f64>,
    max_iter: Option<usize>,
    saturation: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<(
    Bound<'py, PyArray3<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    String,
    ReportHandle,
)> {
    let image: Image = grid_from(image.as_array());
    let mask: Option<Mask> = mask.map(|m| grid_from(m.as_array()));
    let asked = method.map(str::parse).transpose().map_err(to_py)?;
    let (method, method_source) = shadelab::Method::chosen(asked);
    let mut options = shadelab::SolveOptions::for_method(method);
    options.lambda = lam;
    if let Some(t) = tol {
        options.tol = t;
    }
    if let Some(n) = max_iter {
        options.max_iter = n;
    }
    let light_choice: pl::solve::LightChoice = light.parse().map_err(to_py)?;
    let mut config =
        pl::solve::SolveConfig::new(shadelab::pipeline::source::IN_MEMORY, light_choice);
    config.boundary = boundary.parse().map_err(to_py)?;
    config.albedo = albedo;
    config.albedo_estimate = albedo_estimate;
    config.saturation = saturation.parse().map_err(to_py)?;
    config.options =
        shadelab::ReconstructOptions::from_solve(&options, shadelab::NonConvergence::Report);
    config.method_source = method_source;
    config.record = pl::solve::SolveRecord {
        light: light.to_string(),
        boundary: boundary.to_string(),
        out: String::new(),
    };
    let run = run_reporting(py, progress, |progress| {
        pl::solve::run_image(&config, image, mask, progress)
    })?;
    let text = json_text(&run.report)?;
    // Copies for NumPy; the run itself stays with the handle, for its writer.
    let solution = &run.shape.solution;
    let normals = normals_array(py, solution.normals());
    let arrays = (
        normals,
        image_array(py, run.depth.depth.clone()),
        image_array(py, solution.f.clone()),
        image_array(py, solution.g.clone()),
    );
    let handle = ReportHandle::new(Kind::Solve(Box::new(run)), Vec::new());
    Ok((arrays.0, arrays.1, arrays.2, arrays.3, text, handle))
}

/// The picture of an analysis, as the Python layer passes it: an array or a stimulus name,
/// the stimulus's parameters (JSON), seed, ppd, rendered shape (height, width), target
/// labels and a rendered dict's record (JSON of its `parameters` and `notes`, and
/// `own_targets`: whether the labels are the dict's own target mask, named `target_names`).
pub(crate) type PictureArgs<'py> = (
    Option<ArrayIn<'py>>,
    Option<String>,
    String,
    Option<u64>,
    Option<f64>,
    Option<(usize, usize)>,
    Option<PyReadonlyArray2<'py, u16>>,
    Option<String>,
);

/// What the perception analyses assume: domain, boundary, slant, albedo, ambient.
type AssumptionArgs = (String, String, f64, Option<f64>, Option<f64>);

/// How the perception analyses solve: reconstruction method, λ, tolerance, iteration cap; each
/// `None` keeps the library's default, and the config's `check` checks them with the rest.
type SolverArgs = (Option<String>, Option<f64>, Option<f64>, Option<usize>);

/// The library's description of a picture, and the rendered shape (the library's order).
pub(crate) fn picture_source(
    picture: PictureArgs<'_>,
) -> PyResult<(shadelab::PictureSource, Option<(usize, usize)>)> {
    let (image, stimulus, params_json, seed, ppd, shape, labels, record) = picture;
    // A rendered dict's record (its parameters and notes), read as a sidecar's is.
    let (declared, silhouette, label_names) = match record {
        None => Default::default(),
        Some(text) => {
            let record: Value = serde_json::from_str(&text).map_err(|e| {
                PyValueError::new_err(format!("image: the dict's record is not JSON: {e}"))
            })?;
            let none = Value::Null;
            let part = |key: &str| record.get(key).unwrap_or(&none).clone();
            let notes = part("notes");
            let declared =
                shadelab::pipeline::source::Declared::from_record(&part("parameters"), &notes)
                    .map_err(|e| PyValueError::new_err(format!("image: the dict's record: {e}")))?;
            // The notes speak of the dict's own targets, not of a mask given beside it.
            let silhouette = notes.get(shadelab::pipeline::source::SILHOUETTE_NOTE)
                == Some(&Value::Bool(true))
                && record.get("own_targets") == Some(&Value::Bool(true));
            // The names of the dict's own targets, as a sidecar names them.
            let names: Vec<String> = match record.get("target_names") {
                Some(Value::Array(items))
                    if record.get("own_targets") == Some(&Value::Bool(true)) =>
                {
                    items
                        .iter()
                        .filter_map(Value::as_str)
                        .map(String::from)
                        .collect()
                }
                _ => Vec::new(),
            };
            (declared, silhouette, names)
        }
    };
    let source = shadelab::PictureSource {
        declared,
        silhouette,
        pixels: image.as_ref().map(ArrayIn::pixels).transpose()?,
        stimulus,
        params: params_from(&params_json)?,
        seed,
        ppd,
        labels: labels.map(|l| -> Labels { grid_from(l.as_array()) }),
        label_names,
        max_pixels: shadelab::DEFAULT_MAX_PIXELS,
        ..Default::default()
    };
    Ok((source, shape))
}

/// The perception settings shared by `prior_sweep` and `observer`.
fn perception_config(
    picture: PictureArgs<'_>,
    assumptions: AssumptionArgs,
    solver: SolverArgs,
) -> PyResult<perception::Config> {
    let (source, size) = picture_source(picture)?;
    let (domain, boundary, slant, albedo, ambient) = assumptions;
    let mut config = perception::Config::new(source);
    let (method, lambda, tol, max_iter) = solver;
    if let Some(method) = method {
        config.solver.method = method.parse().map_err(to_py)?;
    }
    config.solver.lambda = lambda.unwrap_or(config.solver.lambda);
    config.solver.tol = tol.unwrap_or(config.solver.tol);
    config.solver.max_iter = max_iter.unwrap_or(config.solver.max_iter);
    config.size = size;
    config.domain = domain.parse().map_err(to_py)?;
    config.boundary = boundary.parse().map_err(to_py)?;
    config.slant_deg = slant;
    config.albedo = albedo;
    config.ambient = ambient;
    Ok(config)
}

/// The prior sweep: (report JSON, tilts, convexity tokens × tilts).
#[pyfunction]
#[allow(clippy::type_complexity)]
fn prior_sweep<'py>(
    py: Python<'py>,
    picture: PictureArgs<'py>,
    assumptions: AssumptionArgs,
    solver: SolverArgs,
    tilts: Option<Vec<f64>>,
    binding: Option<&str>,
) -> PyResult<(
    String,
    Bound<'py, PyAny>,
    Bound<'py, PyArray2<f64>>,
    ReportHandle,
)> {
    let mut config = pl::prior_sweep::Config::new(perception_config(picture, assumptions, solver)?)
        .map_err(to_py)?;
    if let Some(t) = tilts {
        config.tilts = t;
    }
    config.binding = binding
        .map(pl::prior_sweep::parse_global_light)
        .transpose()
        .map_err(to_py)?;
    let report = run_released(py, || {
        config.check()?;
        pl::prior_sweep::run(&config, &NoProgress)
    })?;
    let text = json_text(&report)?;
    let tilts = report.sweep.tilts();
    let n = report.sweep.tokens.len();
    let rows: Vec<f64> = (0..n).flat_map(|k| report.sweep.convexities(k)).collect();
    let convexity = Array2::from_shape_vec((n, tilts.len()), rows)
        .expect("one convexity per token and tilt")
        .into_pyarray(py);
    let handle = ReportHandle::new(
        Kind::PriorSweep(Box::new(report)),
        config.picture.source.files(),
    );
    Ok((text, tilts.into_pyarray(py).into_any(), convexity, handle))
}

/// The observer's own settings: prior tilt, kappas, convexity bias, noise, rotations, tilts.
type ObserverArgs = (
    Option<f64>,
    Option<Vec<f64>>,
    Option<f64>,
    Option<f64>,
    Option<Vec<f64>>,
    Option<Vec<f64>>,
);

/// The Bayesian observer: report JSON.
#[pyfunction]
fn observer(
    py: Python<'_>,
    picture: PictureArgs<'_>,
    assumptions: AssumptionArgs,
    solver: SolverArgs,
    settings: ObserverArgs,
) -> PyResult<(String, ReportHandle)> {
    let mut config = pl::observer::Config::new(perception_config(picture, assumptions, solver)?)
        .map_err(to_py)?;
    let (prior_tilt, kappas, convexity_bias, noise, rotations, tilts) = settings;
    config.prior_tilt_deg = prior_tilt.unwrap_or(config.prior_tilt_deg);
    config.kappas = kappas.unwrap_or(config.kappas);
    config.convexity_bias = convexity_bias.unwrap_or(config.convexity_bias);
    config.noise = noise.unwrap_or(config.noise);
    config.rotations = rotations.unwrap_or(config.rotations);
    config.tilts = tilts.unwrap_or(config.tilts);
    let report = run_released(py, || {
        config.check()?;
        pl::observer::run(&config, &NoProgress)
    })?;
    let text = json_text(&report)?;
    let files = config.picture.source.files();
    Ok((
        text,
        ReportHandle::new(Kind::Observer(Box::new(report)), files),
    ))
}

/// A lightness model's output: (H×W output, report JSON).
#[pyfunction]
fn lightness<'py>(
    py: Python<'py>,
    picture: PictureArgs<'py>,
    model: &str,
) -> PyResult<(Bound<'py, PyArray2<f64>>, String, ReportHandle)> {
    let (source, _) = picture_source(picture)?;
    let model: shadelab::LightnessModel = model.parse().map_err(to_py)?;
    let config = pl::lightness::LightnessConfig::new(source, vec![model]).map_err(to_py)?;
    let report = run_released(py, || pl::lightness::run(&config, &NoProgress))?;
    let text = json_text(&report)?;
    let (_, out) = report
        .images
        .first()
        .ok_or_else(|| PyRuntimeError::new_err("the lightness model gave no output"))?;
    let out = image_array(py, out.clone());
    let files = config.source.files();
    Ok((
        out,
        text,
        ReportHandle::new(Kind::Lightness(Box::new(report)), files),
    ))
}

/// The compiled module.
#[pymodule]
fn _shadelab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", shadelab::PROGRAM_VERSION)?;
    m.add_function(wrap_pyfunction!(stimuli, m)?)?;
    m.add_function(wrap_pyfunction!(describe, m)?)?;
    m.add_function(wrap_pyfunction!(check_params, m)?)?;
    m.add_function(wrap_pyfunction!(check_shape, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(prior_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(observer, m)?)?;
    m.add_function(wrap_pyfunction!(lightness, m)?)?;
    m.add_function(wrap_pyfunction!(commands::fading, m)?)?;
    m.add_function(wrap_pyfunction!(commands::outline, m)?)?;
    m.add_function(wrap_pyfunction!(commands::study_run, m)?)?;
    m.add_function(wrap_pyfunction!(commands::study_merge, m)?)?;
    m.add_function(wrap_pyfunction!(commands::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(commands::gallery, m)?)?;
    m.add_function(wrap_pyfunction!(commands::bench, m)?)?;
    m.add_function(wrap_pyfunction!(commands::benchmark, m)?)?;
    m.add_function(wrap_pyfunction!(commands::experiment, m)?)?;
    m.add_function(wrap_pyfunction!(commands::experiment_pilot, m)?)?;
    m.add_function(wrap_pyfunction!(commands::fit_observer, m)?)?;
    m.add_class::<ReportHandle>()?;
    Ok(())
}
