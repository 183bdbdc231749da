//! The commands beyond render, solve and the perception analyses: the fading disk, the
//! outline analysis, the study (run and merge), the evaluation, the gallery, the solver timing
//! (`bench`) and the lightness benchmark against human data (`benchmark`).
//! Each builds the library's configuration from Python's values, runs the SAME `run` the
//! command line runs with the GIL released, and hands back its report as JSON text (with the
//! arrays a Python user reads, and a handle that writes the command line's folder).

use crate::reports::{Kind, ReportHandle};
use crate::{image_array, json_text, picture_source, run_released, to_py, PictureArgs};
use numpy::ndarray::{Array1, Array4};
use numpy::IntoPyArray;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shadelab::pipeline as pl;
use shadelab::{CommandReport, Error, NoProgress, Output};
use std::path::PathBuf;

/// The fading disk's band-pass filter and adaptation settings, `None` for each default:
/// tau, duration, dt, jitter, jitter seed, DoG centre σ, border half-width.
type FadingArgs = (
    Option<f64>,
    Option<f64>,
    Option<f64>,
    Option<f64>,
    Option<u64>,
    Option<f64>,
    Option<f64>,
);

/// The fading disk (`analyze fading`): (report JSON, arrays dict, handle).
#[pyfunction]
pub fn fading<'py>(
    py: Python<'py>,
    picture: PictureArgs<'py>,
    settings: FadingArgs,
) -> PyResult<(String, Bound<'py, PyDict>, ReportHandle)> {
    let (source, _) = picture_source(picture)?;
    let (tau, duration, dt, jitter, seed, dog_sigma, border) = settings;
    let mut band = shadelab::pipeline::fading::DogBand::default();
    band.centre_sigma_deg = dog_sigma.unwrap_or(band.centre_sigma_deg);
    band.border_half_width_deg = border.unwrap_or(band.border_half_width_deg);
    let mut adaptation = shadelab::pipeline::fading::AdaptationOptions::default();
    adaptation.tau_s = tau.unwrap_or(adaptation.tau_s);
    adaptation.duration_s = duration.unwrap_or(adaptation.duration_s);
    adaptation.dt_s = dt.unwrap_or(adaptation.dt_s);
    adaptation.jitter_deg = jitter.unwrap_or(adaptation.jitter_deg);
    adaptation.seed = seed.unwrap_or(adaptation.seed);
    let config = pl::fading::FadingConfig::new(source, band, adaptation).map_err(to_py)?;
    let report = run_released(py, || pl::fading::run(&config, &NoProgress))?;
    let text = json_text(&report)?;
    let arrays = PyDict::new(py);
    let course = &report.course;
    let column = |v: &[f64]| Array1::from(v.to_vec()).into_pyarray(py);
    arrays.set_item("times", column(&course.times))?;
    arrays.set_item("blurred", column(&course.blurred))?;
    arrays.set_item("sharp", column(&course.sharp))?;
    let eye: Vec<f64> = course.eye.iter().flat_map(|&(x, y)| [x, y]).collect();
    let eye = numpy::ndarray::Array2::from_shape_vec((course.eye.len(), 2), eye)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    arrays.set_item("eye", eye.into_pyarray(py))?;
    if let Some(first) = report.frames.first() {
        let (w, h) = (first.width(), first.height());
        let samples: Vec<f64> = report
            .frames
            .iter()
            .flat_map(|f| f.data().iter().flatten().copied())
            .collect();
        let frames = Array4::from_shape_vec((report.frames.len(), h, w, 3), samples)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        arrays.set_item("frames", frames.into_pyarray(py))?;
    }
    let inputs = config.source.files();
    Ok((
        text,
        arrays,
        ReportHandle::new(Kind::Fading(Box::new(report)), inputs),
    ))
}

/// The outline analysis (`analyze outline`): (report JSON, a dict of arrays per target name,
/// handle). `light` is the light's text (`None`: estimated per target).
#[pyfunction]
#[pyo3(signature = (picture, light, depth_scale, lam))]
pub fn outline<'py>(
    py: Python<'py>,
    picture: PictureArgs<'py>,
    light: Option<String>,
    depth_scale: f64,
    lam: f64,
) -> PyResult<(String, Bound<'py, PyDict>, ReportHandle)> {
    let (source, size) = picture_source(picture)?;
    let mut config = pl::outline::OutlineConfig::new(source);
    config.size = size.map(|(h, w)| (w, h));
    config.light = light
        .map(|t| t.parse::<shadelab::FrontLight>())
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("light: {e}")))?;
    config.profile.depth_scale = depth_scale;
    config.crease.lambda = lam;
    config.validate().map_err(to_py)?;
    let report = run_released(py, || pl::outline::run(&config, &NoProgress))?;
    let text = json_text(&report)?;
    let targets = PyDict::new(py);
    for t in &report.targets {
        let layers = PyDict::new(py);
        layers.set_item("shape", image_array(py, t.layers.shape.clone()))?;
        layers.set_item("shading", image_array(py, t.layers.shading.clone()))?;
        layers.set_item("paint", image_array(py, t.layers.paint.clone()))?;
        layers.set_item("inside", image_array(py, t.layers.inside.clone()))?;
        layers.set_item("origin", t.layers.origin)?;
        targets.set_item(&t.name, layers)?;
    }
    let inputs = config.source.files();
    Ok((
        text,
        targets,
        ReportHandle::new(Kind::Outline(Box::new(report)), inputs),
    ))
}

/// A study spec from a file or from JSON text.
fn study_config(
    spec_path: Option<PathBuf>,
    spec_json: Option<String>,
    shard: Option<&str>,
) -> PyResult<(pl::study::StudyRunConfig, Vec<PathBuf>)> {
    let shard = match shard {
        Some(text) => shadelab::pipeline::study::Shard::parse(text).map_err(to_py)?,
        None => shadelab::pipeline::study::Shard::WHOLE,
    };
    let max = shadelab::DEFAULT_MAX_PIXELS;
    match (spec_path, spec_json) {
        (Some(path), _) => Ok((
            pl::study::StudyRunConfig::load(&path, shard, max).map_err(to_py)?,
            vec![path],
        )),
        (None, Some(text)) => {
            let spec = serde_json::from_str(&text)
                .map_err(|e| PyValueError::new_err(format!("spec: bad study spec: {e}")))?;
            Ok((
                pl::study::StudyRunConfig::new(spec, shard, max).map_err(to_py)?,
                Vec::new(),
            ))
        }
        (None, None) => Err(PyValueError::new_err(
            "spec: give a study spec's path or a dict",
        )),
    }
}

/// One shard (or the whole) of a study (`study run`), in memory: (report JSON, results CSV,
/// sweep CSV, handle).
#[pyfunction]
#[pyo3(signature = (spec_path, spec_json, shard))]
pub fn study_run(
    py: Python<'_>,
    spec_path: Option<PathBuf>,
    spec_json: Option<String>,
    shard: Option<String>,
) -> PyResult<(String, String, String, ReportHandle)> {
    let (config, inputs) = study_config(spec_path, spec_json, shard.as_deref())?;
    let report = run_released(py, || pl::study::run(&config, &NoProgress))?;
    let text = json_text(&report)?;
    let (results, sweep) = (report.results.clone(), report.sweep.clone());
    Ok((
        text,
        results,
        sweep,
        ReportHandle::new(Kind::Study(Box::new(report)), inputs),
    ))
}

/// Joins shard folders into `out` (`study merge`): (report JSON, results CSV, sweep CSV,
/// folder written).
#[pyfunction]
pub fn study_merge(
    py: Python<'_>,
    dirs: Vec<PathBuf>,
    out: PathBuf,
    force: bool,
) -> PyResult<(String, String, String, String)> {
    let config = pl::study::StudyMergeConfig::new(dirs, &out).map_err(to_py)?;
    let (report, written) = run_released(py, || {
        let report = pl::study::merge(&config, &NoProgress)?;
        let written = report.write(&Output::new(&out).force(force).reads(config.dirs.clone()))?;
        Ok((report, written))
    })?;
    Ok((
        json_text(&report)?,
        report.results.clone(),
        report.sweep.clone(),
        written.display().to_string(),
    ))
}

/// The evaluation's settings as Python passes them: sets, DiLiGenT objects, ball images,
/// DiLiGenT light, boundary, albedo quantile, ball albedo from truth, bunny size, methods,
/// λ, tolerance, iteration cap.
type EvalArgs = (
    Option<Vec<String>>,
    Option<Vec<String>>,
    Option<Vec<String>>,
    Option<String>,
    Option<String>,
    Option<f64>,
    bool,
    Option<usize>,
    Option<Vec<String>>,
    Option<f64>,
    Option<f64>,
    Option<usize>,
);

/// The engine on the evaluation data (`eval`): (results JSON, Markdown table, folder written
/// or None).
#[pyfunction]
#[pyo3(signature = (data, out, force, settings))]
pub fn evaluate(
    py: Python<'_>,
    data: PathBuf,
    out: Option<PathBuf>,
    force: bool,
    settings: EvalArgs,
) -> PyResult<(String, String, Option<String>)> {
    use shadelab::pipeline::evaluation::{self, Config, Set};
    let (
        only,
        objects,
        balls,
        diligent_light,
        boundary,
        quantile,
        from_truth,
        bunny,
        methods,
        lam,
        tol,
        max_iter,
    ) = settings;
    let mut config = Config::new(&data).map_err(to_py)?;
    let list = |v: Vec<String>| {
        v.into_iter()
            .map(|s| s.trim().to_string())
            .collect::<Vec<_>>()
    };
    if let Some(sets) = only {
        config.sets = list(sets)
            .iter()
            .map(|s| s.parse::<Set>())
            .collect::<Result<_, _>>()
            .map_err(to_py)?;
    }
    if let Some(o) = objects {
        config.diligent_objects = list(o);
    }
    if let Some(b) = balls {
        config.ball_images = list(b)
            .into_iter()
            .map(|s| s.trim_end_matches(".png").to_string())
            .collect();
    }
    if let Some(l) = diligent_light {
        config.diligent_light = l
            .parse()
            .map_err(|e: Error| PyValueError::new_err(format!("diligent_light: {e}")))?;
    }
    config.boundary = boundary
        .as_deref()
        .map(shadelab::Boundary::named)
        .transpose()
        .map_err(to_py)?;
    config.albedo_quantile = quantile.unwrap_or(config.albedo_quantile);
    config.ball_albedo_from_truth = from_truth;
    config.bunny_size = bunny.unwrap_or(config.bunny_size);
    if let Some(m) = methods {
        config.methods = list(m)
            .iter()
            .map(|m| m.parse::<shadelab::Method>())
            .collect::<Result<_, _>>()
            .map_err(to_py)?;
        config.method_source = shadelab::MethodSource::Asked;
    }
    config.options.lambda = lam.unwrap_or(config.options.lambda);
    config.tol = tol;
    config.max_iter = max_iter;
    config.validate().map_err(to_py)?;
    let record = evaluation::Record {
        out: out.map(|o| Output::new(o).force(force)),
        commit: "unknown".into(),
        command: vec![format!(
            "shadelab.evaluate (Python, shadelab {})",
            shadelab::PROGRAM_VERSION
        )],
    };
    let (results, written) =
        run_released(py, || evaluation::run_into(&config, &record, &NoProgress))?;
    Ok((
        json_text(&results)?,
        evaluation::markdown_table(&results),
        written.map(|p| p.display().to_string()),
    ))
}

/// Every preset rendered into `out` with an index page (`gallery`): the report JSON.
#[pyfunction]
#[pyo3(signature = (out, presets, force))]
pub fn gallery(
    py: Python<'_>,
    out: PathBuf,
    presets: Option<PathBuf>,
    force: bool,
) -> PyResult<String> {
    let config = match &presets {
        Some(dir) => pl::gallery::GalleryConfig::from_folder(dir),
        None => pl::gallery::GalleryConfig::builtin(),
    }
    .map_err(to_py)?;
    let dest = Output::new(&out).force(force).reads(config.files());
    let (report, folder) = run_released(py, || {
        dest.check(pl::gallery::GalleryReport::MARKER)?;
        let report = pl::gallery::run(&config, &NoProgress)?;
        let folder = report.write(&dest)?;
        Ok((report, folder))
    })?;
    let index = folder.join(pl::gallery::GalleryReport::MARKER);
    json_text(&serde_json::json!({ "folder": folder, "index": index, "presets": report.presets }))
}

/// The solvers timed (`bench`): (report JSON, table).
#[pyfunction]
#[pyo3(signature = (sizes, methods, lambda, shape, light, jacobi_up_to, integrable_up_to, reference, reference_up_to, repeat))]
#[allow(clippy::too_many_arguments)]
pub fn bench(
    py: Python<'_>,
    sizes: Vec<usize>,
    methods: Vec<String>,
    lambda: f64,
    shape: String,
    light: &str,
    jacobi_up_to: usize,
    integrable_up_to: usize,
    reference: PathBuf,
    reference_up_to: usize,
    repeat: usize,
) -> PyResult<(String, String)> {
    let light: shadelab::FrontLight = light
        .parse()
        .map_err(|e: Error| PyValueError::new_err(format!("light: {e}")))?;
    let methods = methods
        .iter()
        .map(|m| {
            m.parse::<shadelab::Method>()
                .map_err(|e| PyValueError::new_err(format!("methods: {e}")))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let config = pl::bench::BenchConfig {
        sizes,
        methods,
        lambda,
        shape,
        light,
        jacobi_up_to,
        integrable_up_to,
        reference,
        reference_up_to,
        repeat,
        max_pixels: shadelab::DEFAULT_MAX_PIXELS,
    };
    config.validate().map_err(to_py)?;
    let report = run_released(py, || pl::bench::run(&config, &NoProgress))?;
    Ok((json_text(&report)?, report.table()))
}

/// The lightness models scored against stimupy's human data (`benchmark`), from the folder
/// `shadelab._benchmark_data` exported: (report JSON, Markdown table, folder written or None).
#[pyfunction]
#[pyo3(signature = (export, models, stimuli, out, force))]
pub fn benchmark(
    py: Python<'_>,
    export: PathBuf,
    models: &str,
    stimuli: Vec<String>,
    out: Option<PathBuf>,
    force: bool,
) -> PyResult<(String, String, Option<String>)> {
    let models = pl::benchmark::BenchmarkConfig::parse_models(models)
        .map_err(|e| PyValueError::new_err(format!("models: {e}")))?;
    let config =
        pl::benchmark::BenchmarkConfig::from_export(&export, models, &stimuli).map_err(to_py)?;
    let (report, written) = run_released(py, || {
        let report = pl::benchmark::run(&config, &NoProgress)?;
        let written = match &out {
            Some(out) => Some(
                report
                    .write(&Output::new(out).force(force))?
                    .display()
                    .to_string(),
            ),
            None => None,
        };
        Ok((report, written))
    })?;
    Ok((json_text(&report)?, report.markdown(), written))
}

/// The experiment's settings as Python passes them (JSON of the keywords given; each absent
/// keeps the library's default).
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct ExperimentArgs {
    rotations: Option<Vec<f64>>,
    repeats: Option<usize>,
    practice: Option<usize>,
    slant: Option<f64>,
    visual_size: Option<(f64, f64)>,
    ppd: Option<f64>,
    viewing_distance: Option<f64>,
    seed: Option<u64>,
    keys: Option<String>,
    break_every: Option<usize>,
    counterbalance_keys: Option<bool>,
    save_url: Option<String>,
    save_format: Option<String>,
    prolific_code: Option<String>,
    completion_url: Option<String>,
    install: Option<bool>,
}

/// A browser experiment written into `out` (`experiment`): (report JSON, folder written, the
/// files kept that the design did not write, why jsPsych was not installed or None).
#[pyfunction]
#[pyo3(signature = (out, stimulus, params_json, settings_json, force))]
pub fn experiment(
    py: Python<'_>,
    out: PathBuf,
    stimulus: Option<String>,
    params_json: &str,
    settings_json: &str,
    force: bool,
) -> PyResult<(String, String, Vec<String>, Option<String>)> {
    use pl::experiment::{Config, Install};
    let s: ExperimentArgs = serde_json::from_str(settings_json)
        .map_err(|e| PyValueError::new_err(format!("experiment: {e}")))?;
    let mut config = Config::new();
    if let Some(name) = &stimulus {
        config.set_stimulus(name).map_err(to_py)?;
    }
    config.params.extend(crate::params_from(params_json)?);
    let set = |v: &mut f64, given: Option<f64>| *v = given.unwrap_or(*v);
    config.rotations = s.rotations.unwrap_or(config.rotations);
    config.repeats = s.repeats.unwrap_or(config.repeats);
    config.practice = s.practice.unwrap_or(config.practice);
    set(&mut config.slant_deg, s.slant);
    config.visual_size = s.visual_size.unwrap_or(config.visual_size);
    set(&mut config.ppd, s.ppd);
    set(&mut config.viewing_distance_cm, s.viewing_distance);
    config.seed = s.seed.unwrap_or(config.seed);
    if let Some(keys) = &s.keys {
        config.keys = keys
            .parse()
            .map_err(|e| PyValueError::new_err(format!("keys {e}")))?;
    }
    config.break_every = s.break_every.unwrap_or(config.break_every);
    config.counterbalance_keys = s.counterbalance_keys.unwrap_or(false);
    config.save_url = s.save_url;
    if let Some(f) = &s.save_format {
        config.save_format = f
            .parse()
            .map_err(|e| PyValueError::new_err(format!("save_format {e}")))?;
    }
    if let Some(code) = &s.prolific_code {
        config.completion_url = Some(
            pl::experiment::prolific_completion_url(code)
                .map_err(|e| PyValueError::new_err(format!("prolific_code: {e}")))?,
        );
    }
    if s.completion_url.is_some() {
        config.completion_url = s.completion_url;
    }
    config.install = s.install.unwrap_or(false);
    config
        .check()
        .map_err(|e| PyValueError::new_err(format!("{}: {}", e.field, e.error)))?;
    let (report, written) = run_released(py, || {
        let dest = Output::new(&out).force(force);
        dest.check(pl::experiment::MARKER)?;
        let report = pl::experiment::run(&config, &NoProgress)?;
        let written = report.write(&dest)?;
        Ok((report, written))
    })?;
    let install = match &written.install {
        Install::Failed(why) => Some(why.clone()),
        _ => None,
    };
    Ok((
        json_text(&report)?,
        written.folder.display().to_string(),
        written
            .kept
            .iter()
            .map(|p| p.display().to_string())
            .collect(),
        install,
    ))
}

/// The observer model fitted to responses (`fit observer`): (report JSON, handle). The
/// responses are the file or folder `responses`, or with `text` that text (CSV or jsPsych
/// JSON) named `responses`.
#[pyfunction]
#[pyo3(signature = (responses, text, keys, include_simulated, mixed_designs, design, lapse, nonparametric, bootstrap, seed))]
#[allow(clippy::too_many_arguments)]
pub fn fit_observer(
    py: Python<'_>,
    responses: PathBuf,
    text: Option<String>,
    keys: Option<String>,
    include_simulated: bool,
    mixed_designs: bool,
    design: Option<PathBuf>,
    lapse: Option<f64>,
    nonparametric: bool,
    bootstrap: Option<usize>,
    seed: Option<u64>,
) -> PyResult<(String, ReportHandle)> {
    use pl::fit::{Config, KeyMap};
    let mut config = Config::new(&responses);
    let inputs = if text.is_some() {
        Vec::new()
    } else {
        vec![responses.clone()]
    };
    config.text = text;
    config.reading.keys = keys
        .map(|k| KeyMap::parse(&k))
        .transpose()
        .map_err(|e| PyValueError::new_err(format!("keys: {e}")))?;
    config.reading.include_simulated = include_simulated;
    config.reading.mixed_designs = mixed_designs;
    config.design = design;
    let d = config.options;
    config.options.lapse = lapse;
    config.options.nonparametric = nonparametric;
    config.options.bootstrap = bootstrap.unwrap_or(d.bootstrap);
    config.options.seed = seed.unwrap_or(d.seed);
    let report = run_released(py, || pl::fit::run(&config, &NoProgress))?;
    Ok((
        json_text(&report)?,
        ReportHandle::new(Kind::Fit(Box::new(report)), inputs),
    ))
}

/// `shadelab experiment pilot`: the trial rows the study `study` (its folder or design.json)
/// writes in pilot mode for the observer `simulate` (the page's `simulate` text) and
/// `participant`, through the library's pilot; written to `out` when given (replacing a file
/// only with `force`). Returns (the rows as CSV, the participant, the order seed).
#[pyfunction]
#[pyo3(signature = (study, simulate, participant, out, force))]
pub fn experiment_pilot(
    py: Python<'_>,
    study: PathBuf,
    simulate: &str,
    participant: Option<String>,
    out: Option<PathBuf>,
    force: bool,
) -> PyResult<(String, String, u32)> {
    let config = pl::experiment::PilotConfig {
        study,
        simulate: simulate
            .parse()
            .map_err(|e| PyValueError::new_err(format!("simulate {e}")))?,
        participant: participant
            .map(|p| p.parse())
            .transpose()
            .map_err(|e| PyValueError::new_err(format!("participant {e}")))?,
    };
    let report = run_released(py, || {
        let report = pl::experiment::run_pilot(&config)?;
        if let Some(out) = &out {
            report.write(out, &config.design_path(), force)?;
        }
        Ok(report)
    })?;
    Ok((report.csv(), report.participant.clone(), report.order_seed))
}
