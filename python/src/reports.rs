//! A command's report kept on the Rust side after the call, so that Python can write the
//! command line's output folder from it (`save`, the same writer, so the same files) and read
//! its figures as arrays (the PNGs that writer makes, decoded), without running the work again.

use crate::run_released;
use numpy::ndarray::Array3;
use numpy::IntoPyArray;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use shadelab::pipeline as pl;
use shadelab::{CommandReport, Error, Output};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// The reports whose output folder Python can write.
pub enum Kind {
    /// `analyze prior-sweep`.
    PriorSweep(Box<pl::prior_sweep::Report>),
    /// `analyze observer`.
    Observer(Box<pl::observer::Report>),
    /// `analyze lightness`.
    Lightness(Box<pl::lightness::LightnessReport>),
    /// `analyze fading`.
    Fading(Box<pl::fading::FadingReport>),
    /// `analyze outline`.
    Outline(Box<pl::outline::OutlineReport>),
    /// `study run`.
    Study(Box<pl::study::StudyRunReport>),
    /// `solve`.
    Solve(Box<pl::solve::SolveRun>),
    /// `fit observer`.
    Fit(Box<pl::fit::Report>),
}

/// A report and the files its run read (which its folder may never replace).
#[pyclass(frozen, module = "shadelab._shadelab")]
pub struct ReportHandle {
    kind: Kind,
    inputs: Vec<PathBuf>,
}

impl ReportHandle {
    /// A handle on `kind`, whose run read `inputs`.
    pub fn new(kind: Kind, inputs: Vec<PathBuf>) -> ReportHandle {
        ReportHandle { kind, inputs }
    }

    /// Writes the output folder `out` as the command line does: whole or not at all, into a
    /// folder shadelab did not write only with `force`, never over an input.
    fn write_folder(&self, out: &Path, force: bool) -> Result<PathBuf, Error> {
        let out = Output::new(out)
            .force(force)
            .reads(self.inputs.iter().cloned());
        match &self.kind {
            Kind::PriorSweep(r) => r.write(&out),
            Kind::Observer(r) => r.write(&out),
            Kind::Outline(r) => r.write(&out),
            Kind::Lightness(r) => r.write(&out),
            Kind::Fading(r) => r.write(&out),
            Kind::Study(r) => r.write(&out),
            Kind::Solve(r) => r.write(&out),
            Kind::Fit(r) => r.write(&out),
        }
    }
}

/// Numbers the scratch folders of [`ReportHandle::figures`] within this process.
static SCRATCH: AtomicU64 = AtomicU64::new(0);

#[pymethods]
impl ReportHandle {
    /// Writes the command line's output folder; returns its path.
    #[pyo3(signature = (out, force))]
    fn write(&self, py: Python<'_>, out: PathBuf, force: bool) -> PyResult<String> {
        let written = run_released(py, || self.write_folder(&out, force))?;
        Ok(written.display().to_string())
    }

    /// The figures the output folder holds, as `{relative name without .png: H×W×C uint8}`
    /// (C = 3 or 4, the PNG's own channels): the folder is written to a scratch folder by the
    /// same writer, its PNGs decoded, and the scratch folder removed.
    fn figures<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let n = SCRATCH.fetch_add(1, Ordering::Relaxed);
        let scratch =
            std::env::temp_dir().join(format!("shadelab-figures-{}-{n}", std::process::id()));
        let decoded = run_released(py, || {
            let result = self
                .write_folder(&scratch, false)
                .and_then(|dir| read_pngs(&dir, &dir));
            let _ = std::fs::remove_dir_all(&scratch);
            result
        })?;
        let figures = PyDict::new(py);
        for (name, (h, w, c, bytes)) in decoded {
            let array = Array3::from_shape_vec((h, w, c), bytes)
                .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
            figures.set_item(name, array.into_pyarray(py))?;
        }
        Ok(figures)
    }
}

/// A decoded PNG: height, width, channels, 8-bit samples.
type Decoded = (usize, usize, usize, Vec<u8>);

/// Every PNG under `dir` (sorted by name), decoded to 8-bit samples, keyed by its path
/// relative to `root` without `.png`. Masks and 16-bit stimuli are data, not figures: only
/// 8-bit RGB and RGBA files are read.
fn read_pngs(root: &Path, dir: &Path) -> Result<Vec<(String, Decoded)>, Error> {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    let mut out = Vec::new();
    for path in entries {
        if path.is_dir() {
            out.extend(read_pngs(root, &path)?);
            continue;
        }
        if path.extension().and_then(|e| e.to_str()) != Some("png") {
            continue;
        }
        let bytes = shadelab_io::read_bytes(&path)?;
        let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = decoder
            .read_info()
            .map_err(|e| Error::format(&path, e.to_string()))?;
        let (colour, depth) = reader.output_color_type();
        let channels = match colour {
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            _ => continue,
        };
        if depth != png::BitDepth::Eight {
            continue;
        }
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| Error::format(&path, "too large to decode"))?;
        let mut buf = vec![0; size];
        let info = reader
            .next_frame(&mut buf)
            .map_err(|e| Error::format(&path, e.to_string()))?;
        buf.truncate(info.buffer_size());
        let name = path
            .strip_prefix(root)
            .unwrap_or(&path)
            .with_extension("")
            .to_string_lossy()
            .replace('\\', "/");
        out.push((
            name,
            (info.height as usize, info.width as usize, channels, buf),
        ));
    }
    Ok(out)
}
