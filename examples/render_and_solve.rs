//! Render a sphere under a light, reconstruct it from the picture alone, and compare the
//! recovered normals with the render's own: `cargo run --example render_and_solve`.

use shadelab::evaluation::metrics::angular_error;
use shadelab::stimulus::{sphere, Pixels, SphereParams};
use shadelab::{Boundary, Error, Geometry, NoProgress, Problem, ReconstructOptions, Reconstructor};

fn main() -> shadelab::Result<()> {
    let mut params = SphereParams::default();
    params.lighting.light = "tilt=30,slant=40".parse()?; // from above, a little to the left
    let geometry = Geometry {
        width: 128,
        height: 128,
        ppd: 32.0,
    };
    let out = sphere(&params, &geometry)?;
    let (Pixels::Gray(image), Some(truth)) = (&out.pixels, &out.surface) else {
        return Err(Error::invalid("a sphere renders in gray with its layers"));
    };
    // The engine assumes the light and reflectance the picture was rendered with.
    let map = params.lighting.reflectance()?;
    let problem = Problem {
        image,
        mask: &truth.mask,
        boundary: &Boundary::Occluding,
        reflectance: map.as_ref(),
    };
    let mut planner = Reconstructor::new(128, 128, ReconstructOptions::default())?;
    let r = planner.reconstruct(&problem, &NoProgress)?;
    let error = angular_error(&r.shape.solution.normals(), &truth.normals, &truth.mask)?;
    println!("mean normal error: {:.4}°", error.mean_deg);
    Ok(())
}
