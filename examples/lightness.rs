//! A lightness model on Adelson's checker-shadow: squares A and B have one luminance, and ODOG
//! predicts how different they look: `cargo run --example lightness`.

use shadelab::{LightnessConfig, LightnessModel, NoProgress, PictureSource};

fn main() -> shadelab::Result<()> {
    let source = PictureSource {
        stimulus: Some("checker-shadow".into()),
        ppd: Some(12.0),
        max_pixels: shadelab::DEFAULT_MAX_PIXELS,
        ..Default::default()
    };
    let config = LightnessConfig::new(source, vec!["odog".parse::<LightnessModel>()?])?;
    let report = shadelab::pipeline::lightness::run(&config, &NoProgress)?;
    for model in &report.targets {
        for t in &model.targets {
            println!(
                "{} {}: luminance {:.4}, model output {:.4}",
                model.model, t.name, t.luminance, t.output
            );
        }
    }
    Ok(())
}
