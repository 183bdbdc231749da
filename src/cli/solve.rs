//! `shadelab solve`: shape from shading on one grayscale image, into an output folder.

use super::{progress, CliError, CliResult, Global};
use serde_json::json;
use shadelab::boundary::{Boundary, BOUNDARY_NAMES};
use shadelab::grid::{Grid, Image, Mask};
use shadelab::integrate::{
    gradients_from_normals, integrate_gradients, write_mesh_obj, PoissonOptions, DEFAULT_MIN_NZ,
};
use shadelab::io::{self, AtomicDir, BitDepth};
use shadelab::light::Light;
use shadelab::light_estimation::estimate_light;
use shadelab::reflectance::BrdfSpec;
use shadelab::solver::{Method, Progress, SolveOptions, Solver};
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
    /// Stop after this many sweeps (multigrid: cycles).
    #[arg(long, value_name = "N", default_value_t = 100_000)]
    pub max_iter: usize,
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
        max_iter: args.max_iter,
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
    let mut solver = Solver::new(w, h)?;
    let solve_started = Instant::now();
    let solution = solver.solve_with_progress(
        &image,
        &mask,
        &boundary,
        reflectance.as_ref(),
        &options,
        &mut |p: &Progress| {
            bar.set_position(p.iteration as u64);
            if p.iteration % 64 == 0 {
                bar.set_message(format!("solving (last update {:.2e})", p.last_update));
            }
        },
    )?;
    bar.finish_and_clear();
    // The solver's buffers are not needed past this point: give their memory back before the
    // integration and the outputs, which make their own.
    drop(solver);
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

    let integrate_started = Instant::now();
    let (dz_dx, dz_dy) = gradients_from_normals(&solution.normals, &mask, DEFAULT_MIN_NZ)?;
    let integration = integrate_gradients(&dz_dx, &dz_dy, &mask, &PoissonOptions::default())?;
    let integrate_seconds = integrate_started.elapsed().as_secs_f64();
    // Depth from differences has no offset: put the lowest point of the object at 0.
    let lowest = masked_range(&integration.depth, &mask).0;
    let depth = Grid::from_fn(w, h, |c, r| {
        if *mask.get(c, r) {
            integration.depth.get(c, r) - lowest
        } else {
            0.0
        }
    });
    let (_, highest) = masked_range(&depth, &mask);
    let depth_picture = depth.map(|z| if highest > 0.0 { z / highest } else { 0.0 });
    let normals_picture = solution
        .normals
        .map(|n| [0.5 * n.x + 0.5, 0.5 * n.y + 0.5, 0.5 * n.z + 0.5]);

    let dir = folder.path().to_path_buf();
    io::write_normals(&dir.join("normals.npy"), &solution.normals)?;
    io::write_image(&dir.join("depth.npy"), &depth)?;
    io::write_gray(
        &dir.join("depth.png"),
        &depth_picture,
        BitDepth::Sixteen,
        None,
    )?;
    io::write_rgb(
        &dir.join("normals.png"),
        &normals_picture,
        BitDepth::Eight,
        None,
    )?;
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
            "kind": boundary.name(),
            "occluding_shrink": shadelab::boundary::OCCLUDING_SHRINK,
        },
        "solver": {
            "method": method.to_string(),
            "iterations": solution.iterations,
            "iteration_unit": unit,
            "converged": solution.converged,
            "warning": warning,
            "last_update": solution.last_update,
            "unknowns": solution.unknowns,
            "smoothness_energy": solution.smoothness_energy,
            "brightness_energy": solution.brightness_energy,
            "seconds": solve_seconds,
        },
        "integration": {
            "method": "least-squares Poisson on the mask (conjugate gradients, multigrid-preconditioned)",
            "min_nz": DEFAULT_MIN_NZ,
            "iterations": integration.iterations,
            "relative_residual": integration.relative_residual,
            "converged": integration.converged,
            "seconds": integrate_seconds,
        },
        "outputs": {
            "normals.npy": "H×W×3 float32 unit normals, (0,0,1) outside the mask",
            "depth.npy": "H×W float32 depth in pixels toward the viewer; lowest masked point 0, 0 outside the mask",
            "depth.png": format!("16-bit depth / {highest} (the depth range), 0 outside the mask"),
            "normals.png": "8-bit RGB n·0.5+0.5",
            "surface.obj": "triangle mesh of the masked depth, world axes, pixel units",
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
        let state = if solution.converged {
            "converged"
        } else {
            "did NOT converge (raise --max-iter or --tol)"
        };
        eprintln!(
            "{}: {state} after {} {unit}, last update {:.2e}, {:.2} s",
            target.display(),
            solution.iterations,
            solution.last_update,
            started.elapsed().as_secs_f64()
        );
    }
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

/// The smallest and largest value of `grid` inside `mask` ((0, 0) for an empty mask).
fn masked_range(grid: &Image, mask: &Mask) -> (f64, f64) {
    grid.data()
        .iter()
        .zip(mask.data())
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v)
        .fold(None, |acc: Option<(f64, f64)>, v| match acc {
            None => Some((v, v)),
            Some((lo, hi)) => Some((lo.min(v), hi.max(v))),
        })
        .unwrap_or((0.0, 0.0))
}
