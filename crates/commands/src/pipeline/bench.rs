//! `shadelab bench` as a library pipeline: the shape-from-shading solvers timed on a synthetic
//! shape (multigrid, plain Jacobi, and the NumPy reference's red-black SOR when python3 with
//! numpy and the reference folder are there), as typed rows and a printable table.

use crate::boundary::Boundary;
use crate::error::{Error, Result};
use crate::evaluation::metrics::angular_error;
use crate::light::{FrontLight, Light};
use crate::progress::Progress;
use crate::reconstruct::{NonConvergence, Problem, ReconstructOptions, Reconstructor};
use crate::reflectance::Lambertian;
use crate::render::{render, RenderOptions};
use crate::solver::{Method, Solution, SolveOptions};
use crate::surface::{sphere, vase};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The methods timed when none are named: multigrid, nested-lm and Jacobi.
pub const DEFAULT_BENCH_METHODS: &[Method] = &[Method::Multigrid, Method::NestedLm, Method::Jacobi];

/// The shapes the bench renders.
pub const BENCH_SHAPES: &[&str] = &["sphere", "vase"];

/// What to time.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchConfig {
    /// Image sides to time.
    pub sizes: Vec<usize>,
    /// The methods to time, in the table's order ([`DEFAULT_BENCH_METHODS`] by default).
    /// Multigrid is timed whether named or not: every ratio is to it. Jacobi is timed up to
    /// [`BenchConfig::jacobi_up_to`], the integrable methods up to
    /// [`BenchConfig::integrable_up_to`].
    pub methods: Vec<Method>,
    /// Weight λ of the brightness term (1 by default).
    pub lambda: f64,
    /// Time the integrable methods (integrable, integrable-lm, nested-lm) up to this side.
    pub integrable_up_to: usize,
    /// `sphere` (radius 0.45 of the side) or `vase`.
    pub shape: String,
    /// The light.
    pub light: FrontLight,
    /// Time plain Jacobi up to this side.
    pub jacobi_up_to: usize,
    /// The folder of the NumPy reference (`run_reference.py`).
    pub reference: PathBuf,
    /// Run the NumPy reference up to this side.
    pub reference_up_to: usize,
    /// Time multigrid this many times per size and keep the fastest.
    pub repeat: usize,
    /// The largest image made, in pixels.
    pub max_pixels: usize,
}

impl BenchConfig {
    /// Checks every value, naming the bad one.
    pub fn validate(&self) -> Result<()> {
        if self.sizes.is_empty() || self.sizes.iter().any(|&n| n < 8) {
            return Err(Error::invalid(
                "the sizes must list sides of at least 8 pixels",
            ));
        }
        if self.repeat == 0 {
            return Err(Error::invalid("repeat must be at least 1"));
        }
        if self.methods.contains(&Method::Literal) {
            return Err(Error::invalid(
                "the methods cannot include literal: its update is unstable and never converges \
                 (nothing to time)",
            ));
        }
        SolveOptions {
            lambda: self.lambda,
            ..SolveOptions::default()
        }
        .validate()?;
        if !BENCH_SHAPES.contains(&self.shape.as_str()) {
            return Err(Error::unknown("shape", &self.shape, BENCH_SHAPES));
        }
        if let Some(&n) = self
            .sizes
            .iter()
            .find(|&&n| !matches!(n.checked_mul(n), Some(a) if a <= self.max_pixels))
        {
            return Err(Error::invalid(format!(
                "size {n} exceeds the pixel limit {}",
                self.max_pixels
            )));
        }
        Ok(())
    }
}

/// One timed solve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Cycles (multigrid) or sweeps.
    pub iterations: usize,
    /// Whether it met the tolerance.
    pub converged: bool,
}

/// The timings at one size.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchRow {
    /// The image side.
    pub size: usize,
    /// Multigrid, the fastest of the repeats.
    pub multigrid: Timing,
    /// Plain Jacobi, up to its size limit.
    pub jacobi: Option<Timing>,
    /// The NumPy reference, when run.
    pub numpy: Option<Timing>,
    /// Mean angle between the multigrid and Jacobi normals, degrees.
    pub jacobi_difference_deg: Option<f64>,
    /// The other methods asked for (not multigrid, not Jacobi), each timed once, in the
    /// order asked, up to [`BenchConfig::integrable_up_to`].
    pub others: Vec<MethodTiming>,
    /// Mean angle between multigrid's normals and the true ones, degrees.
    pub multigrid_error_deg: f64,
}

/// One timed solve of a method other than multigrid and Jacobi.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MethodTiming {
    /// The method, as `--method` spells it.
    pub method: String,
    /// Its timing.
    pub timing: Timing,
    /// Its seconds over multigrid's.
    pub vs_multigrid: f64,
    /// Mean angle between its normals and the true ones, degrees.
    pub error_deg: f64,
}

/// The bench's results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BenchReport {
    /// What was timed, in words.
    pub setup: String,
    /// The methods timed, in the table's order (multigrid first).
    pub methods: Vec<String>,
    /// Worker threads.
    pub threads: usize,
    /// Multigrid repeats per size.
    pub repeat: usize,
    /// One row per size.
    pub rows: Vec<BenchRow>,
    /// Notes on what was not run and the memory used.
    pub notes: Vec<String>,
}

/// Times the solvers as `config` says.
pub fn run(config: &BenchConfig, progress: &dyn Progress) -> Result<BenchReport> {
    config.validate()?;
    let light = config.light;
    let map = Lambertian {
        light: light.light(),
        albedo: 1.0,
        ambient: 0.0,
    };
    let reference = Reference::find(&config.reference);
    let d = light.direction();
    let setup = format!(
        "{} (occluding boundary), light ({:.3}, {:.3}, {:.3}), λ = {}, tol: each method's own",
        if config.shape == "sphere" {
            "sphere of radius 0.45·side"
        } else {
            "vase"
        },
        d.x,
        d.y,
        d.z,
        config.lambda
    );
    // Multigrid first (every ratio is to it), then the others in the order asked, once each.
    let mut methods = vec![Method::Multigrid];
    for &m in &config.methods {
        if !methods.contains(&m) {
            methods.push(m);
        }
    }
    let mut rows = Vec::new();
    progress.start(config.sizes.len() as u64, "timing");
    for &size in &config.sizes {
        let surface = match config.shape.as_str() {
            "sphere" => sphere(size, size, 0.45 * size as f64)?,
            _ => vase(size, size)?,
        };
        let image = render(&surface, &map, &RenderOptions::default()).image;
        let problem = Problem {
            image: &image,
            mask: &surface.mask,
            boundary: &Boundary::Occluding,
            reflectance: &map,
        };
        // One planner per method and size, as a user would keep one: the repeats reuse it.
        let planner = |method: Method| {
            let options = ReconstructOptions {
                method,
                lambda: config.lambda,
                tol: method.default_tol(),
                // The method's own cap: the default options carry multigrid's 1,000, which
                // would stop Jacobi long before it converges.
                max_iter: None,
                non_convergence: NonConvergence::Report,
                ..ReconstructOptions::default()
            };
            Reconstructor::new(size, size, options)
        };
        let mut multigrid_planner = planner(Method::Multigrid)?;
        let time = |planner: &mut Reconstructor| -> Result<(Timing, Solution)> {
            let started = Instant::now();
            let shape = planner.solve(&problem, &crate::progress::NoProgress)?;
            let s = shape.solution;
            let timing = Timing {
                seconds: started.elapsed().as_secs_f64(),
                iterations: s.iterations,
                converged: s.converged,
            };
            Ok((timing, s))
        };
        let mut best: Option<(Timing, Solution)> = None;
        for _ in 0..config.repeat {
            let run = time(&mut multigrid_planner)?;
            if best.as_ref().map_or(true, |b| run.0.seconds < b.0.seconds) {
                best = Some(run);
            }
        }
        let Some((multigrid, fast)) = best else {
            continue;
        };
        let jacobi = (methods.contains(&Method::Jacobi) && size <= config.jacobi_up_to)
            .then(|| time(&mut planner(Method::Jacobi)?))
            .transpose()?;
        let truth = &surface.normals;
        let error = |s: &Solution| -> Result<f64> {
            Ok(angular_error(&s.normals(), truth, &surface.mask)?.mean_deg)
        };
        let mut others = Vec::new();
        for &method in &methods {
            if matches!(method, Method::Multigrid | Method::Jacobi)
                || size > config.integrable_up_to
            {
                continue;
            }
            let (timing, s) = time(&mut planner(method)?)?;
            others.push(MethodTiming {
                method: method.to_string(),
                timing,
                vs_multigrid: timing.seconds / multigrid.seconds,
                error_deg: error(&s)?,
            });
        }
        let numpy = match &reference {
            Ok(r) if size <= config.reference_up_to => Some(r.run(&config.shape, size, &light)?),
            _ => None,
        };
        rows.push(BenchRow {
            size,
            multigrid,
            jacobi_difference_deg: jacobi
                .as_ref()
                .map(|(_, j)| angular_error(&fast.normals(), &j.normals(), &surface.mask))
                .transpose()?
                .map(|e| e.mean_deg),
            jacobi: jacobi.map(|(t, _)| t),
            numpy,
            others,
            multigrid_error_deg: error(&fast)?,
        });
        progress.advance(1);
    }
    progress.finish();
    Ok(BenchReport {
        setup,
        methods: methods.iter().map(|m| m.to_string()).collect(),
        threads: crate::parallel::threads(),
        repeat: config.repeat,
        notes: notes(config, &reference),
        rows,
    })
}

/// What the table leaves out and why, and the memory used.
fn notes(config: &BenchConfig, reference: &std::result::Result<Reference, String>) -> Vec<String> {
    let mut notes = Vec::new();
    let above = |limit: usize| config.sizes.iter().filter(|&&n| n > limit).count();
    let jacobi_above = above(config.jacobi_up_to);
    let jacobi = config.methods.contains(&Method::Jacobi);
    if jacobi && jacobi_above == config.sizes.len() {
        notes.push(format!(
            "jacobi is not run: every size is above its limit of {}",
            config.jacobi_up_to
        ));
    } else if jacobi && jacobi_above > 0 {
        notes.push(format!(
            "jacobi is timed up to {0}²; its sweeps grow about 3.4× per doubling of the side",
            config.jacobi_up_to
        ));
    }
    match reference {
        Ok(_) => {
            let numpy_above = above(config.reference_up_to);
            if numpy_above == config.sizes.len() {
                notes.push(format!(
                    "numpy-sor is not run: every size is above its limit of {}",
                    config.reference_up_to
                ));
            } else if numpy_above > 0 {
                notes.push(format!(
                    "numpy-sor (the reference's red-black SOR, same stopping rule) is run up to \
                     {0}²",
                    config.reference_up_to
                ));
            }
        }
        Err(why) => notes.push(format!("vs numpy-sor column skipped: {why}")),
    }
    let integrable: Vec<String> = config
        .methods
        .iter()
        .filter(|m| !matches!(m, Method::Multigrid | Method::Jacobi))
        .map(|m| m.to_string())
        .collect();
    if !integrable.is_empty() && above(config.integrable_up_to) > 0 {
        notes.push(format!(
            "{} timed up to {}² (--integrable-up-to)",
            integrable.join(", "),
            config.integrable_up_to
        ));
    }
    if let Some(peak) = peak_memory_bytes() {
        notes.push(format!(
            "peak memory of this process: {:.1} MiB",
            peak as f64 / (1024.0 * 1024.0)
        ));
    }
    notes
}

impl BenchReport {
    /// The report as the table `shadelab bench` prints.
    pub fn table(&self) -> String {
        let mut t = format!(
            "shadelab bench: {}, {} threads\n\n",
            self.setup, self.threads
        );
        t += &format!(
            "{:>6}  {:<10}  {:>16}  {:>10}  {:>10}  {:>13}  {:>12}  {:>12}  {:>9}\n",
            "size",
            "method",
            "iterations",
            "seconds",
            "vs jacobi",
            "vs numpy-sor",
            "Δ jacobi (°)",
            "vs multigrid",
            "error (°)"
        );
        let ratio = |a: Option<f64>, b: f64, digits: usize| match a {
            Some(a) => format!("{:.*}×", digits, a / b),
            None => "—".to_string(),
        };
        for r in &self.rows {
            let fast = r.multigrid.seconds;
            let difference = r
                .jacobi_difference_deg
                .map(|d| format!("{d:.4}"))
                .unwrap_or_else(|| "—".into());
            let error = |e: f64| format!("{e:.3}");
            t += &row(
                r.size,
                "multigrid",
                &r.multigrid,
                "cycles",
                [
                    &ratio(r.jacobi.map(|j| j.seconds), fast, 0),
                    &ratio(r.numpy.map(|n| n.seconds), fast, 0),
                    &difference,
                    "1×",
                    &error(r.multigrid_error_deg),
                ],
            );
            for name in &self.methods {
                if let Some(o) = r.others.iter().find(|o| &o.method == name) {
                    let unit = o
                        .method
                        .parse::<Method>()
                        .map_or("steps", |m| m.iteration_unit());
                    let ratio = format!("{:.1}×", o.vs_multigrid);
                    t += &row(
                        r.size,
                        &o.method,
                        &o.timing,
                        unit,
                        ["—", "—", "—", &ratio, &error(o.error_deg)],
                    );
                }
                if let (Some(j), "jacobi") = (&r.jacobi, name.as_str()) {
                    let vs_numpy = ratio(r.numpy.map(|n| n.seconds), j.seconds, 1);
                    t += &row(
                        r.size,
                        "jacobi",
                        j,
                        "sweeps",
                        ["1×", &vs_numpy, "0", "—", "—"],
                    );
                }
            }
            if let Some(n) = &r.numpy {
                t += &row(r.size, "numpy-sor", n, "sweeps", ["—", "1×", "—", "—", "—"]);
            }
        }
        t += &format!(
            "\nmultigrid: best of {} runs; its iterations are cycles (W-cycles), the others' are \
             sweeps;\nΔ jacobi: mean angle between the multigrid and Jacobi normals over the \
             unknowns;\nintegrable, integrable-lm and nested-lm: one run each, their seconds over \
             multigrid's in vs multigrid (nested-lm's steps: the finest grid's);\n\
             error: mean angle between the normals and the true ones over the mask.\n",
            self.repeat
        );
        for note in &self.notes {
            t += &format!("note: {note}\n");
        }
        t
    }
}

/// One line of the table: the size, the method, its timing and the last five columns (vs
/// jacobi, vs numpy-sor, Δ jacobi, vs multigrid, error).
fn row(size: usize, method: &str, t: &Timing, unit: &str, columns: [&str; 5]) -> String {
    let [vs_jacobi, vs_numpy, diff, vs_multigrid, error] = columns;
    let iterations = format!(
        "{} {unit}{}",
        t.iterations,
        if t.converged { "" } else { " (not conv.)" }
    );
    format!(
        "{size:>6}  {method:<10}  {iterations:>16}  {:>10.4}  {vs_jacobi:>10}  {vs_numpy:>13}  \
         {diff:>12}  {vs_multigrid:>12}  {error:>9}\n",
        t.seconds
    )
}

/// The NumPy reference solver, found and checked.
struct Reference {
    script: PathBuf,
}

impl Reference {
    /// The reference in `folder`, or why it cannot be used.
    fn find(folder: &Path) -> std::result::Result<Reference, String> {
        let script = folder.join("run_reference.py");
        if !script.is_file() {
            return Err(format!("{} not found", script.display()));
        }
        match Command::new("python3")
            .args(["-c", "import numpy"])
            .output()
        {
            Ok(out) if out.status.success() => Ok(Reference { script }),
            Ok(_) => Err("python3 has no numpy (pip install numpy)".to_string()),
            Err(e) => Err(format!("python3 not found ({e})")),
        }
    }

    /// Runs the reference's red-black SOR on `shape` at `size`² under `light`.
    fn run(&self, shape: &str, size: usize, light: &Light) -> Result<Timing> {
        let d = light.direction();
        // The reference's y axis points down; `--light=x,y,z` in one word, so that argparse
        // takes a vector that starts with a minus sign as the value, not as a flag.
        let light_arg = format!("--light={},{},{}", d.x, -d.y, d.z);
        let out = Command::new("python3")
            .arg(&self.script)
            .args([shape, &size.to_string(), "--method", "sor", &light_arg])
            .output()
            .map_err(|e| Error::Compute(format!("cannot run python3: {e}")))?;
        let text = String::from_utf8_lossy(&out.stdout);
        let parsed = text
            .lines()
            .rev()
            .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok());
        match (out.status.success(), parsed) {
            (true, Some(v)) => Ok(Timing {
                seconds: v["wall_s"].as_f64().unwrap_or(f64::NAN),
                iterations: v["iterations"].as_u64().unwrap_or(0) as usize,
                converged: v["converged"].as_bool().unwrap_or(false),
            }),
            _ => Err(Error::Compute(format!(
                "the NumPy reference failed: {}",
                String::from_utf8_lossy(&out.stderr)
                    .lines()
                    .last()
                    .unwrap_or("no output")
            ))),
        }
    }
}

/// The peak resident memory of this process (Linux: VmHWM), if the system tells.
fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
