//! `shadelab bench`: times the shape-from-shading solvers on a synthetic shape and prints a
//! table, with the NumPy reference solver beside them when python3 with numpy and the reference
//! folder are there.

use super::{CliError, CliResult, Global};
use shadelab::boundary::Boundary;
use shadelab::gradient_space::angle_deg;
use shadelab::light::Light;
use shadelab::reflectance::Lambertian;
use shadelab::render::{render, RenderOptions};
use shadelab::solver::{Method, Solution, SolveOptions, Solver};
use shadelab::surface::{sphere, vase, Surface};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// Arguments of `bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Image sides to time, comma separated.
    #[arg(
        long,
        value_name = "N,N,…",
        default_value = "128,256,512,1024",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub sizes: Vec<usize>,
    /// The shape: sphere (radius 0.45 of the side) or vase.
    #[arg(long, value_name = "sphere|vase", default_value = "sphere")]
    pub shape: String,
    /// The light (x,y,z, tilt=T,slant=S or a name), z > 0.
    #[arg(long, value_name = "L", default_value = "0,0,1")]
    pub light: String,
    /// Time plain Jacobi up to this side (it needs thousands of sweeps: 256² takes seconds,
    /// 1024² would take many minutes).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 256,
        allow_hyphen_values = true
    )]
    pub jacobi_up_to: usize,
    /// The folder of the NumPy reference (`run_reference.py`).
    #[arg(long, value_name = "PATH", default_value = "../shared/reference")]
    pub reference: PathBuf,
    /// Run the NumPy reference (red-black SOR) up to this side (512² takes minutes there).
    #[arg(
        long,
        value_name = "N",
        default_value_t = 256,
        allow_hyphen_values = true
    )]
    pub reference_up_to: usize,
    /// Time multigrid this many times per size and keep the fastest.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 3,
        allow_hyphen_values = true
    )]
    pub repeat: usize,
}

/// One timed solve.
struct Timing {
    seconds: f64,
    iterations: usize,
    converged: bool,
}

/// Runs `bench`.
pub fn run(args: Args, global: &Global) -> CliResult {
    if args.sizes.is_empty() || args.sizes.iter().any(|&n| n < 8) {
        return Err(CliError::usage(
            "--sizes must list sides of at least 8 pixels",
        ));
    }
    if args.repeat == 0 {
        return Err(CliError::usage("--repeat must be at least 1"));
    }
    if !["sphere", "vase"].contains(&args.shape.as_str()) {
        return Err(CliError::from(shadelab::Error::unknown(
            "shape",
            &args.shape,
            &["sphere", "vase"],
        )));
    }
    let light: Light = args.light.parse()?;
    let d = light.direction();
    if d.z <= 0.0 {
        return Err(CliError::usage(format!(
            "--light ({:.4}, {:.4}, {:.4}) must have z > 0",
            d.x, d.y, d.z
        )));
    }
    if let Some(&n) = args
        .sizes
        .iter()
        .find(|&&n| !matches!(n.checked_mul(n), Some(a) if a <= global.max_pixels))
    {
        return Err(CliError::usage(format!(
            "--sizes {n} exceeds --max-pixels {}",
            global.max_pixels
        )));
    }
    let reference = Reference::find(&args.reference);
    let map = Lambertian {
        light,
        albedo: 1.0,
        ambient: 0.0,
    };

    println!(
        "shadelab bench: {} (occluding boundary), light ({:.3}, {:.3}, {:.3}), λ = 1, tol 1e-6, \
         {} threads",
        if args.shape == "sphere" {
            "sphere of radius 0.45·side"
        } else {
            "vase"
        },
        d.x,
        d.y,
        d.z,
        rayon::current_num_threads()
    );
    println!();
    println!(
        "{:>6}  {:<10}  {:>16}  {:>10}  {:>10}  {:>13}  {:>12}",
        "size", "method", "iterations", "seconds", "vs jacobi", "vs numpy-sor", "Δ jacobi (°)"
    );
    let mut notes = Vec::new();
    for &size in &args.sizes {
        let surface = match args.shape.as_str() {
            "sphere" => sphere(size, size, 0.45 * size as f64)?,
            _ => vase(size, size)?,
        };
        let image = render(&surface, &map, &RenderOptions::default()).image;
        let mut solver = Solver::new(size, size)?;
        let mut solve = |method: Method| -> Result<(Timing, Solution), CliError> {
            let options = SolveOptions {
                method,
                ..SolveOptions::default()
            };
            let started = Instant::now();
            let s = solver.solve(&image, &surface.mask, &Boundary::Occluding, &map, &options)?;
            let timing = Timing {
                seconds: started.elapsed().as_secs_f64(),
                iterations: s.iterations,
                converged: s.converged,
            };
            Ok((timing, s))
        };
        let mut best: Option<(Timing, Solution)> = None;
        for _ in 0..args.repeat {
            let run = solve(Method::Multigrid)?;
            let faster = match &best {
                Some(b) => run.0.seconds < b.0.seconds,
                None => true,
            };
            if faster {
                best = Some(run);
            }
        }
        let Some((fast, fast_solution)) = best else {
            continue;
        };
        let jacobi = if size <= args.jacobi_up_to {
            Some(solve(Method::Jacobi)?)
        } else {
            None
        };
        let numpy = match &reference {
            Ok(r) if size <= args.reference_up_to => Some(r.run(&args.shape, size, &light)?),
            _ => None,
        };
        let ratio = |seconds: Option<f64>| match seconds {
            Some(s) => format!("{:.0}×", s / fast.seconds),
            None => "—".to_string(),
        };
        let difference = jacobi
            .as_ref()
            .map(|(_, j)| format!("{:.4}", mean_difference(&surface, &fast_solution, j)))
            .unwrap_or_else(|| "—".to_string());
        row(
            size,
            "multigrid",
            &fast,
            "cycles",
            &ratio(jacobi.as_ref().map(|(t, _)| t.seconds)),
            &ratio(numpy.as_ref().map(|t| t.seconds)),
            &difference,
        );
        if let Some((t, _)) = &jacobi {
            let vs_numpy = numpy
                .as_ref()
                .map(|n| format!("{:.1}×", n.seconds / t.seconds))
                .unwrap_or_else(|| "—".to_string());
            row(size, "jacobi", t, "sweeps", "1×", &vs_numpy, "0");
        }
        if let Some(t) = &numpy {
            row(size, "numpy-sor", t, "sweeps", "—", "1×", "—");
        }
    }
    if args.sizes.iter().all(|&n| n > args.jacobi_up_to) {
        notes.push(format!(
            "jacobi is not run: every size is above --jacobi-up-to {}",
            args.jacobi_up_to
        ));
    } else if args.sizes.iter().any(|&n| n > args.jacobi_up_to) {
        notes.push(format!(
            "jacobi is timed up to {0}² (--jacobi-up-to {0}); its sweeps grow about 3.4× per \
             doubling of the side",
            args.jacobi_up_to
        ));
    }
    match &reference {
        Ok(_) => {
            if args.sizes.iter().all(|&n| n > args.reference_up_to) {
                notes.push(format!(
                    "numpy-sor is not run: every size is above --reference-up-to {}",
                    args.reference_up_to
                ));
            } else if args.sizes.iter().any(|&n| n > args.reference_up_to) {
                notes.push(format!(
                    "numpy-sor (the reference's red-black SOR, same stopping rule) is run up to \
                     {0}² (--reference-up-to {0})",
                    args.reference_up_to
                ));
            }
        }
        Err(why) => notes.push(format!("vs numpy-sor column skipped: {why}")),
    }
    if let Some(peak) = peak_memory_bytes() {
        notes.push(format!(
            "peak memory of this process: {:.1} MiB",
            peak as f64 / (1024.0 * 1024.0)
        ));
    }
    println!();
    println!(
        "multigrid: best of {} runs; its iterations are cycles (W-cycles), the others' are sweeps;",
        args.repeat
    );
    println!("Δ jacobi: mean angle between the multigrid and Jacobi normals over the unknowns.");
    for note in notes {
        println!("note: {note}");
    }
    Ok(())
}

fn row(
    size: usize,
    method: &str,
    t: &Timing,
    unit: &str,
    vs_jacobi: &str,
    vs_numpy: &str,
    diff: &str,
) {
    let iterations = format!(
        "{} {unit}{}",
        t.iterations,
        if t.converged { "" } else { " (not conv.)" }
    );
    println!(
        "{size:>6}  {method:<10}  {iterations:>16}  {:>10.4}  {vs_jacobi:>10}  {vs_numpy:>13}  {diff:>12}",
        t.seconds
    );
}

/// Mean angle (degrees) between two solutions' normals inside the mask.
fn mean_difference(surface: &Surface, a: &Solution, b: &Solution) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for ((m, x), y) in surface
        .mask
        .data()
        .iter()
        .zip(a.normals().data())
        .zip(b.normals().data())
    {
        if *m {
            sum += angle_deg(x, y);
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// The NumPy reference solver, found and checked.
struct Reference {
    script: PathBuf,
}

impl Reference {
    /// The reference in `folder`, or why it cannot be used.
    fn find(folder: &Path) -> Result<Reference, String> {
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
    fn run(&self, shape: &str, size: usize, light: &Light) -> Result<Timing, CliError> {
        let d = light.direction();
        // The reference's y axis points down.
        let light_arg = format!("{},{},{}", d.x, -d.y, d.z);
        let out = Command::new("python3")
            .arg(&self.script)
            .args([
                shape,
                &size.to_string(),
                "--method",
                "sor",
                "--light",
                &light_arg,
            ])
            .output()
            .map_err(|e| CliError::from(anyhow::anyhow!("cannot run python3: {e}")))?;
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
            _ => Err(CliError::from(anyhow::anyhow!(
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
