//! `shadelab analyze prior-sweep`: the picture interpreted under each assumed light tilt, with
//! each token's convexity, residual and smoothness, and the tilts where it flips.

use super::perception::{parameters, PictureArgs};
use super::{CliError, CliResult, Global};
use crate::cli::progress;
use serde_json::json;
use shadelab::analysis::binding::{binding, GlobalLight};
use shadelab::analysis::plot::{Figure, Legend, LinePlot, Marker, Series};
use shadelab::analysis::study::csv_field;
use shadelab::analysis::{parse_angles, sweep, Interpreter, Scene, Sweep};
use shadelab::io::write_text;
use shadelab::io::{self, AtomicDir};
use std::path::PathBuf;
use std::time::Instant;

/// The file that marks an output folder as written by `analyze prior-sweep`.
const REPORT: &str = "sweep.json";

/// Arguments of `analyze prior-sweep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    picture: PictureArgs,
    /// Assumed light tilts, degrees: START:STOP:STEP (STOP excluded) or a list; 0 = from
    /// above, +90 = from the left.
    #[arg(long, value_name = "START:STOP:STEP", default_value = "0:360:15")]
    tilts: String,
    /// Also read the tokens under one global light (estimate, or a tilt in degrees) and under
    /// a light estimated from each token alone.
    #[arg(long, value_name = "estimate|TILT", allow_hyphen_values = true)]
    binding: Option<String>,
    /// Output folder (written whole or not at all).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
}

/// Runs `analyze prior-sweep`.
pub fn run(args: Args, global: &Global) -> CliResult {
    let started = Instant::now();
    let tilts = parse_angles(&args.tilts, "--tilts")?;
    let global_light = match args.binding.as_deref().map(str::trim) {
        None => None,
        Some("estimate") => Some(GlobalLight::Estimated),
        Some(t) => Some(GlobalLight::Given(
            t.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    CliError::usage(format!(
                        "--binding '{t}' is neither 'estimate' nor a tilt in degrees"
                    ))
                })?,
        )),
    };
    args.picture.check()?;
    let loaded = args.picture.load(global)?;
    let scene = Scene {
        image: &loaded.picture.image,
        domain: &loaded.domain,
        boundary: &loaded.boundary,
        tokens: &loaded.picture.tokens,
    };
    let fourier = Interpreter::new(&scene, &loaded.options)?.uses_fourier();
    let folder = AtomicDir::create(&args.out, REPORT, global.force)?;

    let bar = progress::bar(tilts.len() as u64, "prior sweep", global.quiet);
    let result = sweep(&scene, &tilts, &loaded.lighting, &loaded.options, &|| {
        bar.inc(1)
    })?;
    bar.finish_and_clear();
    let bound = match global_light {
        Some(g) => Some(binding(&scene, &loaded.lighting, g, &loaded.options)?),
        None => None,
    };

    let dir = folder.path().to_path_buf();
    write_text(&dir.join("sweep.csv"), &sweep_csv(&result))?;
    let figure = sweep_figure(&result);
    figure.write_png(&dir.join("sweep.png"))?;
    figure.write_svg(&dir.join("sweep.svg"))?;
    let tokens: Vec<_> = loaded
        .picture
        .tokens
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let c = result.convexities(k);
            json!({
                "label": t.label,
                "name": t.name,
                "pixels": t.pixels().len(),
                "half_width_px": t.half_width(),
                "flips_deg": result.flips(k),
                "convex_tilts_deg": tilts_where(&result, &c, |v| v > 0.0),
                "concave_tilts_deg": tilts_where(&result, &c, |v| v < 0.0),
            })
        })
        .collect();
    let unconverged = result
        .interpretations
        .iter()
        .filter(|i| !i.converged)
        .count();
    let report = json!({
        "program": "shadelab",
        "version": io::PROGRAM_VERSION,
        "command": "analyze prior-sweep",
        "conventions": io::conventions_json(),
        "input": loaded.origin,
        "width": loaded.picture.image.width(),
        "height": loaded.picture.image.height(),
        "parameters": parameters(&loaded, &args.picture),
        "tilts_deg": tilts,
        "covers_circle": result.covers_circle(),
        "depth_integration": if fourier { "Frankot-Chellappa over the whole frame (flat boundary: a relief on a plane)" } else { "masked Poisson (conjugate gradients)" },
        "convexity": "(mean depth over the token's core - mean over its rim) / half-width; > 0 convex toward the viewer",
        "tokens": tokens,
        "interpretations": result.interpretations,
        "unconverged_solves": unconverged,
        "binding": bound,
        "outputs": {
            "sweep.csv": "one row per assumed tilt and token: convexity, residual e_R and smoothness e_S over the token",
            "sweep.png": "convexity (top) and surface residual e_Z (bottom) against assumed tilt, one curve per token (also .svg)",
        },
        "seconds": started.elapsed().as_secs_f64(),
    });
    io::write_json(&dir.join(REPORT), &report)?;
    let target = folder.commit()?;
    if unconverged > 0 {
        eprintln!(
            "warning: {unconverged} of {} solves did not converge within --max-iter {}",
            tilts.len(),
            loaded.options.max_iter
        );
    }
    if !global.quiet {
        for (k, (_, name)) in result.tokens.iter().enumerate().take(12) {
            let flips: Vec<String> = result.flips(k).iter().map(|f| format!("{f:.1}")).collect();
            eprintln!(
                "{name}: convexity changes sign at assumed tilt {}",
                if flips.is_empty() {
                    "none".into()
                } else {
                    flips.join(", ") + "°"
                }
            );
        }
        if let Some(b) = &bound {
            let signs = |v: &[f64]| {
                v.iter()
                    .map(|&c| {
                        if c > 0.0 {
                            '+'
                        } else if c < 0.0 {
                            '-'
                        } else {
                            '0'
                        }
                    })
                    .collect::<String>()
            };
            eprintln!(
                "one light (tilt {:.1}°): {}; a light per token: {}",
                b.global_light.tilt_deg,
                signs(&b.global),
                signs(&b.per_token)
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

fn tilts_where(sweep: &Sweep, values: &[f64], keep: impl Fn(f64) -> bool) -> Vec<f64> {
    sweep
        .interpretations
        .iter()
        .zip(values)
        .filter(|(_, &v)| keep(v))
        .map(|(i, _)| i.tilt_deg)
        .collect()
}

/// One row per assumed tilt and token.
fn sweep_csv(sweep: &Sweep) -> String {
    let mut csv = String::from(
        "tilt_deg,token,label,convexity,residual,smoothness,surface_residual,converged\n",
    );
    for i in &sweep.interpretations {
        for (k, r) in i.tokens.iter().enumerate() {
            let (label, name) = &sweep.tokens[k];
            csv.push_str(&format!(
                "{},{},{label},{},{},{},{},{}\n",
                i.tilt_deg,
                csv_field(name),
                r.convexity,
                r.residual,
                r.smoothness,
                r.surface_residual,
                i.converged
            ));
        }
    }
    csv
}

/// Convexity (flips marked) and surface residual against assumed tilt, one curve per token.
fn sweep_figure(sweep: &Sweep) -> Figure {
    let tilts = sweep.tilts();
    let lo = tilts.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = tilts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        (lo - 1.0, lo + 1.0)
    };
    let x_label = "assumed light tilt (deg; 0 = above, 90 = left, 180 = below)";
    let mut convexity = LinePlot::new(
        "Convexity of each token under each assumed light",
        x_label,
        "convexity (> 0 convex)",
        (lo, hi),
    );
    convexity.reference_y = Some(0.0);
    convexity.legend = Legend::Middle;
    let mut fit = LinePlot::new(
        "How well the recovered surface reproduces the picture",
        x_label,
        "surface residual e_Z",
        (lo, hi),
    );
    fit.legend = Legend::UpperMiddle;
    for (k, (_, name)) in sweep.tokens.iter().enumerate() {
        convexity.series.push(Series {
            name: name.clone(),
            points: tilts.iter().copied().zip(sweep.convexities(k)).collect(),
        });
        fit.series.push(Series {
            name: name.clone(),
            points: sweep
                .interpretations
                .iter()
                .map(|i| (i.tilt_deg, i.tokens[k].surface_residual))
                .collect(),
        });
    }
    if sweep.tokens.len() == 1 {
        for f in sweep.flips(0) {
            if f >= lo && f <= hi {
                convexity.markers.push(Marker {
                    x: f,
                    label: format!("flip {f:.0}°"),
                });
            }
        }
    }
    Figure {
        panels: vec![convexity, fit],
        size: (900, 900),
    }
}
