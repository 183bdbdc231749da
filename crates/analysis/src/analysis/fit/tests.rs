use super::*;

/// 24 rotations every 15°, the default design (shared with `profile`'s tests).
pub(super) fn design() -> Vec<f64> {
    (0..24).map(|i| 15.0 * i as f64).collect()
}

/// The observer whose intervals are tested here and in `profile`'s tests: Mamassian &
/// Goutcher's mean prior tilt (26° to the left), a moderate concentration and lapse.
pub(super) fn interval_truth() -> ModelParams {
    ModelParams {
        tilt_deg: 26.0,
        kappa: 1.5,
        convexity_prior: 0.6,
        lapse: 0.05,
    }
}

/// Recovery on a few seeded data sets, within bounds that a correct fit meets easily (the
/// full table with coverage is `examples/fit_recovery.rs`, in docs/experiments.md).
#[test]
fn simulated_observers_are_recovered() {
    for (i, truth) in [
        ModelParams {
            tilt_deg: 26.0,
            kappa: 2.0,
            convexity_prior: 0.5,
            lapse: 0.02,
        },
        ModelParams {
            tilt_deg: -40.0,
            kappa: 1.5,
            convexity_prior: 0.7,
            lapse: 0.08,
        },
        ModelParams {
            tilt_deg: 150.0,
            kappa: 4.0,
            convexity_prior: 0.3,
            lapse: 0.0,
        },
    ]
    .iter()
    .enumerate()
    {
        let data = simulate(truth, &design(), 40, 100 + i as u64);
        let f = fit_point(&data, None, false);
        let p = f.params;
        let dmu = super::super::wrap_180(p.tilt_deg - truth.tilt_deg).abs();
        assert!(dmu < 12.0, "{i}: {p:?}");
        assert!((p.kappa / truth.kappa).ln().abs() < 0.35, "{i}: {p:?}");
        assert!(
            (p.convexity_prior - truth.convexity_prior).abs() < 0.1,
            "{i}: {p:?}"
        );
        assert!((p.lapse - truth.lapse).abs() < 0.08, "{i}: {p:?}");
        // The optimum: the true parameters are no better.
        assert!(f.log_likelihood >= log_likelihood(truth, &data) - 1e-9);
    }
}

#[test]
fn intervals_are_the_same_bits_every_time_and_cover_the_estimate() {
    let truth = interval_truth();
    let data = simulate(&truth, &design(), 20, 7);
    let options = FitOptions {
        bootstrap: 40,
        seed: 3,
        nonparametric: true,
        ..FitOptions::default()
    };
    let a = fit(&data, &options, "test").unwrap();
    let b = fit(&data, &options, "test").unwrap();
    assert_eq!(a, b);
    for e in [a.prior_tilt_deg, a.prior_kappa, a.convexity_prior, a.lapse] {
        let [lo, hi] = e.ci95.unwrap();
        assert!(lo <= e.value && e.value <= hi, "{e:?}");
        let [lo, hi] = e.ci95_bootstrap.unwrap();
        assert!(lo < hi, "{e:?}");
    }
    let np = a.nonparametric_prior.unwrap();
    let sum: f64 = np.density.iter().map(|d| d.value).sum::<f64>() * std::f64::consts::TAU
        / PRIOR_DIRECTIONS as f64;
    assert!((sum - 1.0).abs() < 1e-12);
    // The smooth prior peaks near the von Mises fit's mean.
    let peak = (0..PRIOR_DIRECTIONS)
        .max_by(|&i, &j| np.density[i].value.total_cmp(&np.density[j].value))
        .unwrap();
    assert!(super::super::wrap_180(np.tilt_deg[peak] - a.prior_tilt_deg.value).abs() <= 45.0);
}

#[test]
fn unidentifiable_data_are_refused_with_the_reason() {
    let o = FitOptions::default();
    let one = [Bin {
        rotation_deg: 30.0,
        trials: 40,
        convex: 20,
    }];
    assert!(check_identifiable(&one, &o, "p1")
        .unwrap_err()
        .to_string()
        .contains("not identifiable"));
    let axis = [
        Bin {
            rotation_deg: 0.0,
            trials: 40,
            convex: 30,
        },
        Bin {
            rotation_deg: 180.0,
            trials: 40,
            convex: 10,
        },
    ];
    assert!(check_identifiable(&axis, &o, "p1")
        .unwrap_err()
        .to_string()
        .contains("axis"));
    let same: Vec<Bin> = (0..24)
        .map(|i| Bin {
            rotation_deg: 15.0 * i as f64,
            trials: 5,
            convex: 5,
        })
        .collect();
    assert!(check_identifiable(&same, &o, "p1")
        .unwrap_err()
        .to_string()
        .contains("all 120 responses are 'convex'"));
    let few = [
        Bin {
            rotation_deg: 0.0,
            trials: 3,
            convex: 2,
        },
        Bin {
            rotation_deg: 90.0,
            trials: 3,
            convex: 1,
        },
    ];
    assert!(check_identifiable(&few, &o, "p1")
        .unwrap_err()
        .to_string()
        .contains("too few"));
}
