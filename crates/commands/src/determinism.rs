//! The same bytes with and without worker threads (the `parallel` feature): a test of the whole
//! house, so it lives on the top library floor, where the solver and the lightness models meet.

use crate::boundary::Boundary;
use crate::grid::Grid;
use crate::grid::Image;
use crate::light::Light;
use crate::pipeline::lightness::{run as lightness, LightnessConfig};
use crate::pipeline::PictureSource;
use crate::progress::NoProgress;
use crate::reconstruct::{Problem, ReconstructOptions, Reconstructor};
use crate::reflectance::Lambertian;
use crate::render::{render, RenderOptions};
use crate::surface::gaussian;
use md5::{Digest, Md5};

/// The digests both builds must give, recorded by `SHADELAB_BLESS=1`.
const RECORDED: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../tests/data/parallel-digests.txt"
);

fn digest(images: &[&Image]) -> String {
    let mut md5 = Md5::new();
    for image in images {
        image
            .data()
            .iter()
            .for_each(|v| md5.update(v.to_le_bytes()));
    }
    format!("{:x}", md5.finalize())
}

/// A solve large enough for the solver's parallel sweeps and levels (40,000 unknowns), its
/// depth, and the ODOG model (parallel FFTs) give the same bytes with and without the
/// `parallel` feature: CI runs this test in both builds against one recorded digest.
#[test]
fn the_same_bytes_with_and_without_worker_threads() {
    let surface = gaussian(200, 200, 20.0, 20.0, 0.0, 0.0).unwrap();
    let map = Lambertian {
        light: Light::from_tilt_slant(20.0, 40.0).unwrap(),
        albedo: 1.0,
        ambient: 0.0,
    };
    let image = render(&surface, &map, &RenderOptions::default()).image;
    let everywhere = Grid::new(200, 200, true);
    let problem = Problem {
        image: &image,
        mask: &everywhere,
        boundary: &Boundary::Flat,
        reflectance: &map,
    };
    let mut planner = Reconstructor::new(200, 200, ReconstructOptions::default()).unwrap();
    let r = planner.reconstruct(&problem, &NoProgress).unwrap();
    assert!(r.shape.solution.unknowns >= 32_768);
    let source = PictureSource {
        stimulus: Some("checker-shadow".into()),
        ppd: Some(10.0),
        max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
        ..Default::default()
    };
    let config = LightnessConfig::new(source, vec!["odog".parse().unwrap()]).unwrap();
    let odog = lightness(&config, &NoProgress).unwrap();
    let s = &r.shape.solution;
    let found = format!(
        "solve {}\nodog {}\n",
        digest(&[&s.f, &s.g, &r.depth.depth]),
        digest(&[&odog.images[0].1])
    );
    if std::env::var_os("SHADELAB_BLESS").is_some() {
        std::fs::write(RECORDED, &found).unwrap();
    }
    let recorded = std::fs::read_to_string(RECORDED).unwrap();
    assert_eq!(found, recorded, "threads: {}", crate::parallel::threads());
}
