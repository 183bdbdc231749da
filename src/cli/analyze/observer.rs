//! `shadelab analyze observer`: a Bayesian observer's P(convex) for each token against the
//! picture's rotation, from one fine sweep of the upright picture.

use super::perception::{parameters, PictureArgs};
use super::{CliError, CliResult, Global};
use crate::cli::progress;
use serde_json::json;
use shadelab::analysis::observer::{DEFAULT_NOISE, DEFAULT_PRIOR_KAPPA, DEFAULT_PRIOR_TILT_DEG};
use shadelab::analysis::plot::{Legend, LinePlot, Marker, Series};
use shadelab::analysis::study::csv_field;
use shadelab::analysis::{
    observe, parse_angles, sweep, LightPrior, ObserverOptions, Percept, Scene, Sweep,
};
use shadelab::io::write_text;
use shadelab::io::{self, AtomicDir};
use std::path::PathBuf;
use std::time::Instant;

/// The file that marks an output folder as written by `analyze observer`.
const REPORT: &str = "observer.json";

/// Arguments of `analyze observer`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    picture: PictureArgs,
    /// Mean of the von Mises prior over light tilt, degrees (+26 = 26° left of vertical).
    #[arg(long, value_name = "DEG", default_value_t = DEFAULT_PRIOR_TILT_DEG, allow_hyphen_values = true)]
    prior_tilt: f64,
    /// Concentration κ of the tilt prior (0 = no preference; larger = firmer); a
    /// comma-separated list draws one curve per value.
    #[arg(long, value_name = "K[,K...]", default_value_t = DEFAULT_PRIOR_KAPPA.to_string(), allow_hyphen_values = true)]
    prior_kappa: String,
    /// Log prior odds of convex over concave for each token (0 = none).
    #[arg(
        long,
        value_name = "B",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    convexity_bias: f64,
    /// Image noise σ of the likelihood, luminance units.
    #[arg(long, value_name = "SIGMA", default_value_t = DEFAULT_NOISE, allow_hyphen_values = true)]
    noise: f64,
    /// Rotations of the picture to judge, degrees counter-clockwise: START:STOP:STEP or a list.
    #[arg(long, value_name = "START:STOP:STEP", default_value = "0:360:15")]
    rotations: String,
    /// Assumed light tilts of the sweep behind the observer; they must cover the circle in
    /// equal steps.
    #[arg(long, value_name = "START:STOP:STEP", default_value = "0:360:5")]
    tilts: String,
    /// Output folder (written whole or not at all).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Runs `analyze observer`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let tilts = parse_angles(&args.tilts, "--tilts")?;
    if shadelab::analysis::prior_sweep::circle_step(&tilts).is_none() {
        return Err(CliError::usage(format!(
            "--tilts '{}' must cover the circle in equal steps (e.g. 0:360:5)",
            args.tilts
        )));
    }
    let rotations = parse_angles(&args.rotations, "--rotations")?;
    let kappas = parse_kappas(&args.prior_kappa)?;
    let all_options: Vec<ObserverOptions> = kappas
        .iter()
        .map(|&kappa| ObserverOptions {
            prior: LightPrior {
                mean_tilt_deg: args.prior_tilt,
                kappa,
                convexity_bias: args.convexity_bias,
            },
            noise: args.noise,
        })
        .collect();
    for o in &all_options {
        o.validate()?;
    }
    args.picture.check()?;
    let loaded = args.picture.load(global)?;
    let scene = Scene {
        image: &loaded.picture.image,
        domain: &loaded.domain,
        boundary: &loaded.boundary,
        tokens: &loaded.picture.tokens,
    };
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;
    let bar = progress::bar(tilts.len() as u64, "observer sweep", global.quiet);
    let result = sweep(&scene, &tilts, &loaded.lighting, &loaded.options, &|| {
        bar.inc(1)
    })?;
    bar.finish_and_clear();
    let curves = all_options
        .iter()
        .map(|o| Ok((*o, observe(&result, o, &rotations)?)))
        .collect::<Result<Vec<_>, shadelab::Error>>()?;

    let dir = folder.path().to_path_buf();
    write_text(&dir.join("observer.csv"), &observer_csv(&result, &curves))?;
    let plot = p_convex_plot(&result, &curves);
    plot.write_png(&dir.join("p_convex.png"))?;
    plot.write_svg(&dir.join("p_convex.svg"))?;
    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "command": "analyze observer",
        "conventions": io::conventions_json(),
        "input": loaded.origin,
        "width": loaded.picture.image.width(),
        "height": loaded.picture.image.height(),
        "parameters": parameters(&loaded, &args.picture),
        "observer": {
            "prior_tilt_deg": args.prior_tilt,
            "prior_kappa": kappas,
            "convexity_bias": args.convexity_bias,
            "noise": args.noise,
        },
        "model": "posterior over the sweep's interpretations: von Mises prior on the light tilt (in the rotated picture's frame) x exp(B) per token read as convex x exp(-(e_R - min e_R)/(2 noise^2)); rotating the picture by r turns interpretation t into t + r",
        "tilts_deg": tilts,
        "tokens": result.tokens.iter().map(|(l, n)| json!({"label": l, "name": n})).collect::<Vec<_>>(),
        "percepts": curves.iter().map(|(o, p)| json!({
            "prior_kappa": o.prior.kappa,
            "percepts": p,
        })).collect::<Vec<_>>(),
        "sweep": result.interpretations,
        "outputs": {
            "observer.csv": "one row per prior kappa, rotation and token: P(convex), the most probable light tilt, P(light from above)",
            "p_convex.png": "P(convex) against rotation, one curve per token (also .svg)",
        },
        "seconds": started.elapsed().as_secs_f64(),
    });
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if !global.quiet {
        for (o, percepts) in &curves {
            for (k, (_, name)) in result.tokens.iter().enumerate().take(12) {
                let best = percepts.iter().fold(&percepts[0], |b, p| {
                    if p.p_convex[k] > b.p_convex[k] {
                        p
                    } else {
                        b
                    }
                });
                eprintln!(
                    "{name} (kappa {}): P(convex) is highest, {:.3}, at rotation {}°",
                    o.prior.kappa, best.p_convex[k], best.rotation_deg
                );
            }
        }
        eprintln!(
            "wrote {} ({:.2} s)",
            target.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn parse_kappas(text: &str) -> Result<Vec<f64>, CliError> {
    let bad = || {
        CliError::usage(format!(
            "--prior-kappa '{text}' must be a number ≥ 0 or a comma-separated list of them"
        ))
    };
    let kappas = text
        .split(',')
        .map(|k| k.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<Vec<_>, _>>()?;
    if kappas.iter().any(|k| !(k.is_finite() && *k >= 0.0)) {
        return Err(bad());
    }
    Ok(kappas)
}

type Curves = [(ObserverOptions, Vec<Percept>)];

fn observer_csv(sweep: &Sweep, curves: &Curves) -> String {
    let mut csv =
        String::from("prior_kappa,rotation_deg,token,label,p_convex,map_tilt_deg,p_light_above\n");
    for (o, percepts) in curves {
        for p in percepts {
            for (k, v) in p.p_convex.iter().enumerate() {
                let (label, name) = &sweep.tokens[k];
                csv.push_str(&format!(
                    "{},{},{},{label},{v},{},{}\n",
                    o.prior.kappa,
                    p.rotation_deg,
                    csv_field(name),
                    p.map_tilt_deg,
                    p.p_light_above
                ));
            }
        }
    }
    csv
}

fn p_convex_plot(sweep: &Sweep, curves: &Curves) -> LinePlot {
    let rs: Vec<f64> = curves[0].1.iter().map(|p| p.rotation_deg).collect();
    let lo = rs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = rs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, lo + 1.0)
    };
    let prior = curves[0].0.prior;
    let kappa_text = if curves.len() == 1 {
        format!("κ = {}", prior.kappa)
    } else {
        format!(
            "κ = {}",
            curves
                .iter()
                .map(|(o, _)| o.prior.kappa.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let mut plot = LinePlot::new(
        &format!(
            "P(convex) against rotation (prior tilt {}°, {kappa_text}, convexity bias {})",
            prior.mean_tilt_deg, prior.convexity_bias
        ),
        "rotation of the picture (deg, counter-clockwise)",
        "P(convex)",
        (lo, hi),
    );
    plot.y_range = Some((-0.02, 1.02));
    plot.reference_y = Some(0.5);
    plot.legend = Legend::Middle;
    let mean = prior.mean_tilt_deg;
    if mean >= lo && mean <= hi {
        plot.markers.push(Marker {
            x: mean,
            label: format!("prior {mean}°"),
        });
    }
    for (o, percepts) in curves {
        for (k, (_, name)) in sweep.tokens.iter().enumerate() {
            plot.series.push(Series {
                name: if curves.len() == 1 {
                    name.clone()
                } else {
                    format!("{name}, κ = {}", o.prior.kappa)
                },
                points: percepts
                    .iter()
                    .map(|p| (p.rotation_deg, p.p_convex[k]))
                    .collect(),
            });
        }
    }
    plot
}
