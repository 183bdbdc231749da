//! A prior sweep: the bumps stimulus read under assumed lights all around the clock, and the
//! tilts at which each disc flips between bump and dimple: `cargo run --example prior_sweep`.

use shadelab::{NoProgress, PerceptionConfig, PictureSource, PriorSweepConfig};

fn main() -> shadelab::Result<()> {
    let mut source = PictureSource {
        stimulus: Some("bumps".into()),
        ppd: Some(12.0),
        ..Default::default()
    };
    source.params.insert("rows".into(), 1.into());
    source.params.insert("columns".into(), 2.into());
    source.max_pixels = shadelab::DEFAULT_MAX_PIXELS;
    let mut config = PriorSweepConfig::new(PerceptionConfig::new(source))?;
    config.tilts = (0..24).map(|k| 15.0 * k as f64).collect();
    let report = shadelab::pipeline::prior_sweep::run(&config, &NoProgress)?;
    for token in &report.tokens {
        println!(
            "{}: flips at {:?}° (convex under {} of {} tilts)",
            token.name,
            token.flips_deg,
            token.convex_tilts_deg.len(),
            report.tilts_deg.len()
        );
    }
    Ok(())
}
