//! Render a sphere under a light, reconstruct it from the picture alone, and compare the
//! recovered normals with the render's own: `cargo run --example render_and_solve`.

use shadelab::stimulus::{sphere, SphereParams};
use shadelab::{angular_error, Boundary, Geometry, NoProgress, Problem, ReconstructOptions};

fn main() -> shadelab::Result<()> {
    let mut params = SphereParams::default();
    params.lighting.light = "tilt=30,slant=40".parse()?; // from above, a little to the left
    let out = sphere(&params, &Geometry::square(128, 32.0))?;
    let (image, truth) = (out.image()?, out.surface_layers()?);
    // The engine assumes the light and reflectance the picture was rendered with.
    let map = params.lighting.reflectance()?;
    let problem = Problem {
        image,
        mask: &truth.mask,
        boundary: &Boundary::Occluding,
        reflectance: map.as_ref(),
    };
    let r = problem.reconstruct(ReconstructOptions::default(), &NoProgress)?;
    let error = angular_error(&r.normals(), &truth.normals, &truth.mask)?;
    println!("mean normal error: {:.4}°", error.mean_deg);
    Ok(())
}
