//! Parameter recovery of `fit observer`: simulated observers over a grid of (μ, κ, π, λ), each
//! fitted many times, with the bias of every estimate and how often its 95 % profile-likelihood
//! interval (and, in brackets, the parametric bootstrap's percentile interval) covers the
//! truth. Prints a Markdown table (docs/experiments.md, "Fitting the prior").
//!
//! `cargo run --release --example fit_recovery -- [DATA_SETS] [BOOTSTRAP] [REPEATS]`
//! (defaults 200, 200, 20: 24 directions every 15°, 20 trials each, as Mamassian & Goutcher's
//! design). Seeded: the same table every time, for any number of threads; each data set's seed
//! does not depend on the row, so `SHADELAB_RECOVERY_ROW=-90,1,0.5,0.1` prints that row alone,
//! with the same numbers.
//!
//! `cargo run --release --example fit_recovery -- worked OUT.csv` writes the worked example's
//! simulated responses instead (a 26°-left prior, the same design).

use rayon::prelude::*;
use shadelab::pipeline::fit::{
    fit, simulate, simulated_responses, wrap_180, FitOptions, ModelParams,
};

fn design() -> Vec<f64> {
    (0..24).map(|i| 15.0 * i as f64).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("worked") {
        let out = args.get(1).map(String::as_str).unwrap_or("responses.csv");
        let truth = ModelParams {
            tilt_deg: 26.0,
            kappa: 2.0,
            convexity_prior: 0.6,
            lapse: 0.03,
        };
        let csv = simulated_responses(&truth, &design(), 20, 2001, "sim1");
        std::fs::write(out, csv).expect("write the CSV");
        eprintln!("wrote {out}: {truth:?}");
        return;
    }
    let number = |i: usize, default: usize| {
        args.get(i)
            .and_then(|a| a.parse::<usize>().ok())
            .unwrap_or(default)
    };
    let (sets, bootstrap, repeats) = (number(0, 200), number(1, 200), number(2, 20));
    println!(
        "{sets} simulated data sets per row, {} trials each (24 directions × {repeats}), {bootstrap} bootstrap replicates per fit.\n",
        24 * repeats
    );
    println!("| μ | κ | π | λ | bias μ (°) | bias κ (median) | bias π | bias λ | cover μ | cover κ | cover π | cover λ |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for mu in [26.0, -90.0] {
        for kappa in [1.0, 3.0] {
            for pi in [0.5, 0.75] {
                for lapse in [0.02, 0.1] {
                    let truth = ModelParams {
                        tilt_deg: mu,
                        kappa,
                        convexity_prior: pi,
                        lapse,
                    };
                    // SHADELAB_RECOVERY_ROW=μ,κ,π,λ runs that row alone (the same numbers).
                    if let Ok(only) = std::env::var("SHADELAB_RECOVERY_ROW") {
                        if only != format!("{mu},{kappa},{pi},{lapse}") {
                            continue;
                        }
                    }
                    let seeds: Vec<u64> = (0..sets as u64).collect();
                    let rows: Vec<([f64; 4], [bool; 4], [bool; 4])> = seeds
                        .par_iter()
                        .map(|&s| {
                            let data = simulate(&truth, &design(), repeats, 1_000_003 * s + 17);
                            let options = FitOptions {
                                bootstrap,
                                seed: s,
                                ..FitOptions::default()
                            };
                            let f = fit(&data, &options, "simulated").expect("identifiable");
                            let inside = |ci: Option<[f64; 2]>, v: f64| {
                                ci.is_some_and(|[lo, hi]| lo <= v && v <= hi)
                            };
                            // μ's interval is centred on the estimate: compare the truth
                            // turned to lie within half a turn of it.
                            let mu_true =
                                f.prior_tilt_deg.value + wrap_180(mu - f.prior_tilt_deg.value);
                            (
                                [
                                    wrap_180(f.prior_tilt_deg.value - mu),
                                    f.prior_kappa.value - kappa,
                                    f.convexity_prior.value - pi,
                                    f.lapse.value - lapse,
                                ],
                                [
                                    inside(f.prior_tilt_deg.ci95, mu_true),
                                    inside(f.prior_kappa.ci95, kappa),
                                    inside(f.convexity_prior.ci95, pi),
                                    inside(f.lapse.ci95, lapse),
                                ],
                                [
                                    inside(f.prior_tilt_deg.ci95_bootstrap, mu_true),
                                    inside(f.prior_kappa.ci95_bootstrap, kappa),
                                    inside(f.convexity_prior.ci95_bootstrap, pi),
                                    inside(f.lapse.ci95_bootstrap, lapse),
                                ],
                            )
                        })
                        .collect();
                    let n = rows.len() as f64;
                    let mean = |k: usize| rows.iter().map(|r| r.0[k]).sum::<f64>() / n;
                    let median = |k: usize| {
                        let mut v: Vec<f64> = rows.iter().map(|r| r.0[k]).collect();
                        v.sort_by(f64::total_cmp);
                        0.5 * (v[(v.len() - 1) / 2] + v[v.len() / 2])
                    };
                    // The profile interval's coverage, with the bootstrap's after it.
                    let cover = |k: usize| {
                        let profile = 100.0 * rows.iter().filter(|r| r.1[k]).count() as f64 / n;
                        if bootstrap == 0 {
                            return format!("{profile:.1} %");
                        }
                        let boot = 100.0 * rows.iter().filter(|r| r.2[k]).count() as f64 / n;
                        format!("{profile:.1} % ({boot:.1} %)")
                    };
                    println!(
                        "| {mu} | {kappa} | {pi} | {lapse} | {:+.2} | {:+.3} ({:+.3}) | {:+.3} | {:+.3} | {} | {} | {} | {} |",
                        mean(0),
                        mean(1),
                        median(1),
                        mean(2),
                        mean(3),
                        cover(0),
                        cover(1),
                        cover(2),
                        cover(3)
                    );
                }
            }
        }
    }
}
