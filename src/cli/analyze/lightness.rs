//! `shadelab analyze lightness`: a lightness model's output for an image or stimulus, the mean
//! output per target, and for the checker-shadow (targets named A and B) the pixel facts and
//! each model's verdict.

use super::{CliError, CliResult, Global, Source};
use serde_json::json;
use shadelab::grid::{Image, Mask};
use shadelab::io::{self, AtomicDir, BitDepth};
use shadelab::lightness::{checker, target_means, Model, TargetMean};
use std::path::Path;
use std::time::Instant;

/// The file that marks an output folder as written by `analyze lightness`.
const REPORT: &str = "lightness.json";

/// Arguments of `analyze lightness`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    source: Source,
    /// The model: odog, lodog, flodog, retinex, or all (each in turn).
    #[arg(long, value_name = "odog|lodog|flodog|retinex|all")]
    model: String,
    /// Output folder (written whole or not at all).
    #[arg(long, value_name = "DIR")]
    out: std::path::PathBuf,
}

/// Runs `analyze lightness`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let models: Vec<Model> = if args.model.trim().eq_ignore_ascii_case("all") {
        Model::NAMES
            .iter()
            .map(|n| n.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![args.model.parse()?]
    };
    args.source.check()?;
    if args.source.image.is_some() && args.source.ppd.is_none() {
        if let Some(m) = models.iter().find(|m| m.needs_ppd()) {
            return Err(CliError::usage(format!(
                "the {m} model works in degrees of visual angle: give the image's resolution \
                 with --ppd N (pixels per degree)"
            )));
        }
    }
    let input = args.source.load(false, global)?;
    let image = input.luminance();
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;
    let dir = folder.path().to_path_buf();

    let single = models.len() == 1;
    let mut outputs = Vec::new();
    let mut timings = serde_json::Map::new();
    for model in &models {
        let t = Instant::now();
        let out = model.predict(&image, input.ppd)?;
        timings.insert(model.name().into(), json!(t.elapsed().as_secs_f64()));
        let stem = if single {
            "lightness".to_string()
        } else {
            format!("lightness_{}", model.name())
        };
        io::write_image(&dir.join(format!("{stem}.npy")), &out)?;
        io::write_gray(
            &dir.join(format!("{stem}.png")),
            &picture(*model, &out),
            BitDepth::Eight,
            None,
        )?;
        outputs.push((*model, stem, out));
    }

    let mut targets = Vec::new();
    if let Some((labels, names)) = &input.labels {
        for (model, _, out) in &outputs {
            targets.push((*model, target_means(out, &image, labels, names)?));
        }
        write_targets(&dir, &targets)?;
    }
    let checker = input.labels.as_ref().and_then(|(labels, names)| {
        let index = |n: &str| names.iter().position(|x| x == n).map(|i| i as u16 + 1);
        let (a, b) = (index("A")?, index("B")?);
        Some(checker_section(&image, labels, a, b, &outputs))
    });

    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "command": "analyze lightness",
        "input": input.origin,
        "width": image.width(),
        "height": image.height(),
        "ppd": input.ppd,
        "models": models.iter().map(|m| m.name()).collect::<Vec<_>>(),
        "outputs": outputs.iter().map(|(m, stem, _)| json!({
            "model": m.name(),
            "npy": format!("{stem}.npy"),
            "png": format!("{stem}.png"),
            "units": units(*m),
        })).collect::<Vec<_>>(),
        "targets": targets.iter().map(|(m, t)| json!({ "model": m.name(), "targets": t }))
            .collect::<Vec<_>>(),
        "checker_shadow": checker,
        "seconds": { "models": timings, "total": started.elapsed().as_secs_f64() },
    });
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if !global.quiet {
        for (model, t) in &targets {
            for m in t {
                eprintln!(
                    "{model}: {} (label {}): luminance {:.4}, output {:.4}",
                    m.name, m.label, m.luminance, m.output
                );
            }
        }
        if let Some(c) = &report["checker_shadow"].as_object() {
            eprintln!(
                "checker-shadow: A and B pixels identical: {}",
                c["identical_pixels"]
            );
        }
        eprintln!(
            "wrote {} ({:.2} s)",
            target.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn units(model: Model) -> &'static str {
    match model {
        Model::Retinex => "estimated reflectance, lightest pixel = 1",
        Model::Odog(_) => "model brightness, arbitrary units, 0 = mid-grey, positive = brighter",
    }
}

/// The visualisation: Retinex as it is (0..1); the filter models symmetric about mid-grey,
/// ±(largest magnitude) mapped to 0..1.
fn picture(model: Model, out: &Image) -> Image {
    match model {
        Model::Retinex => out.clone(),
        Model::Odog(_) => {
            let m = out.data().iter().fold(0.0f64, |m, v| m.max(v.abs()));
            out.map(|v| if m > 0.0 { 0.5 + 0.5 * v / m } else { 0.5 })
        }
    }
}

fn write_targets(dir: &Path, targets: &[(Model, Vec<TargetMean>)]) -> CliResult {
    let mut csv = String::from("model,label,name,pixels,luminance,output\n");
    for (model, rows) in targets {
        for t in rows {
            csv.push_str(&format!(
                "{},{},{},{},{},{}\n",
                model.name(),
                t.label,
                t.name.replace(',', ";"),
                t.pixels,
                t.luminance,
                t.output
            ));
        }
    }
    let path = dir.join("targets.csv");
    io::write_text(&path, &csv)?;
    let json = serde_json::Value::Array(
        targets
            .iter()
            .map(|(m, t)| json!({ "model": m.name(), "targets": t }))
            .collect(),
    );
    io::write_json(&dir.join("targets.json"), &json)?;
    Ok(())
}

/// The checker-shadow facts (A and B pixels) and each model's verdict.
fn checker_section(
    image: &Image,
    labels: &shadelab::grid::Labels,
    a: u16,
    b: u16,
    outputs: &[(Model, String, Image)],
) -> serde_json::Value {
    let mask = |l: u16| -> Mask { labels.map(|&v| v == l) };
    let (ma, mb) = (mask(a), mask(b));
    let facts = checker::pixel_facts(image, &ma, &mb);
    let verdicts: Vec<_> = outputs
        .iter()
        .map(|(m, _, out)| checker::predict(m.name(), out, &ma, &mb))
        .collect();
    json!({
        "identical_pixels": facts.2,
        "a": facts.0,
        "b": facts.1,
        "percept": "B looks much lighter than A",
        "predictions": verdicts,
    })
}
