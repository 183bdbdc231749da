//! `shadelab solve`: shape from shading on one grayscale image, into an output folder.

use super::{progress, CliError, CliResult, Global};
use serde_json::json;
use shadelab::analysis::plot::{LinePlot, Series};
use shadelab::boundary::{Boundary, BOUNDARY_NAMES};
use shadelab::grid::{Grid, Image};
use shadelab::integrate::{
    gradients_from_fg, integrate_owned_gradients, rest_on_zero, write_mesh_obj, PoissonOptions,
    DEFAULT_MIN_NZ,
};
use shadelab::io::{self, AtomicDir, BitDepth};
use shadelab::light::Light;
use shadelab::light_estimation::estimate_light;
use shadelab::reflectance::BrdfSpec;
use shadelab::solver::{Method, Progress, Solution, SolveOptions, Solver, MULTIGRID_MAX_CYCLES};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The file that marks an output folder as written by `solve`.
const REPORT: &str = "report.json";

/// Arguments of `solve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The image: an 8/16-bit PNG (linear luminance) or a float H×W .npy.
    pub image: PathBuf,
    /// The light: x,y,z or tilt=T,slant=S or a name, with z > 0; or `estimate` to estimate it
    /// (and the albedo) from the image.
    #[arg(long, value_name = "L|estimate")]
    pub light: String,
    /// The object's mask (PNG, nonzero = inside); default: the whole image.
    #[arg(long, value_name = "PNG")]
    pub mask: Option<PathBuf>,
    /// Boundary condition: occluding, flat, free, or an H×W×3 .npy of normals for the rim.
    #[arg(
        long,
        value_name = "occluding|flat|free|FILE.npy",
        default_value = "occluding"
    )]
    pub boundary: String,
    /// The reflectance model (lambertian, blinn-phong, oren-nayar).
    #[arg(long, value_name = "NAME", default_value = "lambertian")]
    pub brdf: String,
    /// Surface albedo (default 1, or the estimate with --light estimate).
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    pub albedo: Option<f64>,
    /// Weight λ of the brightness term (> 0).
    #[arg(
        long = "lambda",
        value_name = "L",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub lambda: f64,
    /// Iteration: multigrid (Jacobi's answer in a few cycles), jacobi (stable, slow) or literal
    /// (R at the current value; unstable, for study).
    #[arg(
        long,
        value_name = "multigrid|jacobi|literal",
        default_value = "multigrid"
    )]
    pub method: String,
    /// Stop when the largest change of f or g in a Jacobi sweep is below this (for multigrid:
    /// the change the next Jacobi sweep would make).
    #[arg(
        long,
        value_name = "T",
        default_value_t = 1e-6,
        allow_hyphen_values = true
    )]
    pub tol: f64,
    /// Stop after this many sweeps, or cycles for multigrid [default: 1000 cycles for
    /// multigrid, 100000 sweeps for jacobi and literal].
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub max_iter: Option<usize>,
    /// Output folder (written whole or not at all).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Runs `solve`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    // Everything the user typed is checked before any file is read or work done.
    let method: Method = args.method.parse()?;
    let options = SolveOptions {
        lambda: args.lambda,
        tol: args.tol,
        max_iter: args.max_iter.unwrap_or(match method {
            Method::Multigrid => MULTIGRID_MAX_CYCLES,
            Method::Jacobi | Method::Literal => 100_000,
        }),
        method,
    };
    options.validate()?;
    let mut brdf = BrdfSpec::named(&args.brdf)?;
    if let Some(a) = args.albedo {
        if !(a.is_finite() && a > 0.0) {
            return Err(CliError::usage(format!(
                "--albedo {a} must be a positive number"
            )));
        }
    }
    let light_arg = args.light.trim();
    let given_light = if light_arg == "estimate" {
        None
    } else {
        let light: Light = light_arg.parse()?;
        check_light_in_front(&light)?;
        Some(light)
    };

    let (image, image_info) = read_image(&args.image, global.max_pixels)?;
    let (w, h) = (image.width(), image.height());
    let mask = match &args.mask {
        Some(path) => {
            let mask = io::read_mask(path, global.max_pixels)?;
            if !mask.same_size(&image) {
                return Err(CliError::usage(format!(
                    "mask {} is {}x{} but the image {} is {w}x{h}",
                    path.display(),
                    mask.width(),
                    mask.height(),
                    args.image.display()
                )));
            }
            if mask.count() == 0 {
                return Err(CliError::usage(format!(
                    "mask {} is empty: no pixel is inside the object",
                    path.display()
                )));
            }
            mask
        }
        None => Grid::new(w, h, true),
    };
    let boundary = read_boundary(&args.boundary, w, h, global.max_pixels)?;

    let estimate = match given_light {
        Some(_) => None,
        None => Some(estimate_light(&image, &mask)?),
    };
    let light = match (given_light, &estimate) {
        (Some(l), _) => l,
        (None, Some(e)) => e.light,
        (None, None) => return Err(CliError::usage("--light is required")),
    };
    check_light_in_front(&light)?;
    brdf.albedo = match (args.albedo, &estimate) {
        (Some(a), _) => a,
        (None, Some(e)) => e.albedo,
        (None, None) => 1.0,
    };
    let reflectance = brdf.build(light)?;

    // Claim the output folder before the long part, so an unwritable one fails at once.
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;

    let bar = progress::bar(options.max_iter as u64, "solving", global.quiet);
    // The largest update after each sweep (cycle), for convergence.csv and its plot.
    let mut history: Vec<f64> = Vec::new();
    let solve_started = Instant::now();
    let solution = {
        // The solver's buffers live only for the solve: the integration and the outputs make
        // their own, and memory peaks there.
        let mut solver = Solver::new(w, h)?;
        solver.solve_with_progress(
            &image,
            &mask,
            &boundary,
            reflectance.as_ref(),
            &options,
            &mut |p: &Progress| {
                history.push(p.last_update);
                bar.set_position(p.iteration as u64);
                if p.iteration % 64 == 0 {
                    bar.set_message(format!("solving (last update {:.2e})", p.last_update));
                }
            },
        )?
    };
    bar.finish_and_clear();
    let boundary_kind = boundary.name();
    drop((image, boundary));
    let solve_seconds = solve_started.elapsed().as_secs_f64();
    let unit = if method == Method::Multigrid {
        "cycles"
    } else {
        "sweeps"
    };
    if solution.diverged {
        return Err(CliError::from(shadelab::Error::Compute(format!(
            "the {method} iteration diverged after {} {unit} (last update {:.3e}); use \
             --method jacobi or a smaller --lambda",
            solution.iterations, solution.last_update
        ))));
    }
    // Not converging is not an error (the values may still be useful), but it is never silent:
    // it is in the report and on stderr, even with --quiet.
    let warning = (!solution.converged).then(|| {
        format!(
            "the {method} solve did not converge within --max-iter {} {unit}: the last update \
             {:.3e} is above --tol {:.3e}; raise --max-iter or --tol",
            options.max_iter, solution.last_update, options.tol
        )
    });

    // Outputs are made one at a time and each dropped once written, so that no more than two
    // full-size layers are alive beside the integration's own vectors (`docs/performance.md`).
    let dir = folder.path().to_path_buf();
    io::write_normals(&dir.join("normals.npy"), &solution.normals())?;
    let normals_picture = Grid::from_fn(w, h, |c, r| {
        let n = solution.normal(c, r);
        [0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5]
    });
    io::write_rgb(
        &dir.join("normals.png"),
        &normals_picture,
        BitDepth::Eight,
        None,
    )?;
    drop(normals_picture);
    write_convergence(&dir, &history, &method, unit, options.tol)?;
    let Solution {
        f,
        g,
        iterations,
        converged,
        last_update,
        unknowns,
        smoothness_energy,
        brightness_energy,
        ..
    } = solution;

    let integrate_started = Instant::now();
    let (dz_dx, dz_dy) = gradients_from_fg(f, g, &mask, DEFAULT_MIN_NZ)?;
    let integration = integrate_owned_gradients(dz_dx, dz_dy, &mask, &PoissonOptions::default())?;
    let integrate_seconds = integrate_started.elapsed().as_secs_f64();
    let (iterations_cg, relative_residual, integration_converged) = (
        integration.iterations,
        integration.relative_residual,
        integration.converged,
    );
    let mut depth = integration.depth;
    let highest = rest_on_zero(&mut depth, &mask)?;
    io::write_image(&dir.join("depth.npy"), &depth)?;
    let depth_picture = depth.map(|z| if highest > 0.0 { z / highest } else { 0.0 });
    io::write_gray(
        &dir.join("depth.png"),
        &depth_picture,
        BitDepth::Sixteen,
        None,
    )?;
    drop(depth_picture);
    let obj_path = dir.join("surface.obj");
    io::write_atomic(&obj_path, |out| {
        write_mesh_obj(&depth, &mask, out, &obj_path)
    })?;

    let direction = light.direction();
    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "command": "solve",
        "conventions": io::conventions_json(),
        "input": {
            "image": args.image.display().to_string(),
            "image_info": image_info,
            "width": w,
            "height": h,
            "mask": args.mask.as_ref().map(|p| p.display().to_string()),
            "mask_pixels": mask.count(),
        },
        "parameters": {
            "light": args.light,
            "boundary": args.boundary,
            "brdf": brdf,
            "albedo": brdf.albedo,
            "lambda": options.lambda,
            "method": method.to_string(),
            "tol": options.tol,
            "max_iter": options.max_iter,
            "out": args.out.display().to_string(),
        },
        "light": {
            "vector": [direction.x, direction.y, direction.z],
            "tilt_deg": light.tilt_deg(),
            "slant_deg": light.slant_deg(),
            "estimated": estimate.is_some(),
            "estimate": estimate,
        },
        "boundary": {
            "kind": boundary_kind,
            "occluding_shrink": shadelab::boundary::OCCLUDING_SHRINK,
        },
        "solver": {
            "method": method.to_string(),
            "iterations": iterations,
            "iteration_unit": unit,
            "converged": converged,
            "warning": warning,
            "last_update": last_update,
            "unknowns": unknowns,
            "smoothness_energy": smoothness_energy,
            "brightness_energy": brightness_energy,
            "seconds": solve_seconds,
        },
        "integration": {
            "method": "least-squares Poisson on the mask (conjugate gradients, multigrid-preconditioned)",
            "min_nz": DEFAULT_MIN_NZ,
            "iterations": iterations_cg,
            "relative_residual": relative_residual,
            "converged": integration_converged,
            "seconds": integrate_seconds,
        },
        "outputs": {
            "normals.npy": "H×W×3 float32 unit normals, (0,0,1) outside the mask",
            "depth.npy": "H×W float32 depth in pixels toward the viewer; lowest masked point 0, 0 outside the mask",
            "depth.png": format!("16-bit depth / {highest} (the depth range), 0 outside the mask"),
            "normals.png": "8-bit RGB n·0.5+0.5",
            "surface.obj": "triangle mesh of the masked depth, world axes, pixel units",
            "convergence.csv": format!("the largest update of f or g after each {}", &unit[..unit.len() - 1]),
            "convergence.png": "convergence.csv as a plot (log10 of the update)",
        },
        "depth_range": [0.0, highest],
        "seconds": started.elapsed().as_secs_f64(),
    });
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if let Some(warning) = &warning {
        eprintln!("warning: {warning}");
    }
    if !global.quiet {
        let state = if converged {
            "converged"
        } else {
            "did NOT converge (raise --max-iter or --tol)"
        };
        eprintln!(
            "{}: {state} after {} {unit}, last update {:.2e}, {:.2} s",
            target.display(),
            iterations,
            last_update,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// Writes the update history as `convergence.csv` and `convergence.png` (log10 of the update
/// against the sweep or cycle, with the tolerance as a reference line).
fn write_convergence(
    dir: &Path,
    history: &[f64],
    method: &Method,
    unit: &str,
    tol: f64,
) -> CliResult {
    let mut csv = format!("{},largest_update\n", &unit[..unit.len() - 1]);
    for (i, u) in history.iter().enumerate() {
        csv.push_str(&format!("{},{u:e}\n", i + 1));
    }
    io::write_text(&dir.join("convergence.csv"), &csv)?;
    let mut plot = LinePlot::new(
        &format!("{method} convergence"),
        unit,
        "log10 of the largest update of f or g",
        (1.0, history.len().max(2) as f64),
    );
    plot.reference_y = Some(tol.log10());
    plot.series.push(Series {
        name: method.to_string(),
        points: history
            .iter()
            .enumerate()
            .filter(|(_, u)| **u > 0.0)
            .map(|(i, u)| ((i + 1) as f64, u.log10()))
            .collect(),
    });
    plot.write_png(&dir.join("convergence.png"))?;
    Ok(())
}

/// Shape from shading needs the light strictly in front of the surface.
fn check_light_in_front(light: &Light) -> CliResult {
    let d = light.direction();
    if d.z <= 0.0 {
        return Err(CliError::usage(format!(
            "--light ({:.4}, {:.4}, {:.4}) must have z > 0 (a grazing or rear light leaves the \
             shading without an answer)",
            d.x, d.y, d.z
        )));
    }
    Ok(())
}

/// Reads a PNG or `.npy` image, with what was read for the report.
fn read_image(path: &Path, max_pixels: usize) -> Result<(Image, serde_json::Value), CliError> {
    match io::extension(path).as_str() {
        "png" => {
            let (image, info) = io::read_gray(path, max_pixels)?;
            Ok((image, serde_json::to_value(info).unwrap_or_default()))
        }
        "npy" => Ok((
            io::read_image(path, max_pixels)?,
            json!({ "format": "npy float" }),
        )),
        other => Err(CliError::usage(format!(
            "{}: IMAGE must be a .png or .npy file (got '.{other}')",
            path.display()
        ))),
    }
}

/// A built-in boundary by name, or normals read from a `.npy`.
fn read_boundary(text: &str, w: usize, h: usize, max_pixels: usize) -> Result<Boundary, CliError> {
    if BOUNDARY_NAMES.contains(&text) {
        return Ok(Boundary::named(text)?);
    }
    let path = Path::new(text);
    if io::extension(path) != "npy" {
        return Err(CliError::usage(format!(
            "--boundary '{text}' is neither {} nor a .npy file of normals",
            BOUNDARY_NAMES.join(", ")
        )));
    }
    let normals = io::read_normals(path, max_pixels)?;
    if (normals.width(), normals.height()) != (w, h) {
        return Err(CliError::usage(format!(
            "--boundary {text} is {}x{} but the image is {w}x{h}",
            normals.width(),
            normals.height()
        )));
    }
    Ok(Boundary::Given(normals))
}
