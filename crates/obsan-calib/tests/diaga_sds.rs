//! Issue 18, item 4: the standard deviations `obsan calibrate --method ml`
//! reports are honest. Over 100 seeded datasets the z-scores
//! `(estimate - truth) / sd` of every param have a standard deviation within
//! 0.85-1.2, both when dataset.json states the noise (generalised least
//! squares under the stated encoder noise, the covariance at the estimate)
//! and when it states none (the encoder noise estimated by restricted ML).
//! Small datasets (faster circles, fewer bearings) keep it CI-fast.

use obsan_calib::{calib_predictor, calibrate, simulate, CalibrateOptions, Method, SimOptions};
use obsan_data::wrap;
use rayon::prelude::*;

const RUNS: u64 = 100;

/// Per run the z-scores of phi, psi, eta, delta, xi.
fn z_scores(stated: bool) -> Vec<[f64; 5]> {
    let p = calib_predictor();
    (1..=RUNS)
        .into_par_iter()
        .map(|seed| {
            let o = SimOptions {
                seed,
                nu: 0.5,
                bearing_rate: 0.5,
                ..SimOptions::default()
            };
            let (mut data, truth) = simulate(&o).unwrap();
            if !stated {
                data.meta.noise.clear();
            }
            let opts = CalibrateOptions::for_dataset(&data, Method::Ml);
            let r = calibrate(&data, Some(&p), &opts).unwrap();
            if !stated {
                assert!(
                    r.input_noise_estimated.is_some(),
                    "seed {seed}: the encoder noise should have been estimated"
                );
            }
            let c = &r.calibration;
            let sd = c.sd().unwrap();
            let t = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
            let v = c.values();
            std::array::from_fn(|i| {
                let d = if i < 2 {
                    wrap(v[i] - t[i])
                } else {
                    v[i] - t[i]
                };
                d / sd[i]
            })
        })
        .collect()
}

fn check(stated: bool) {
    let z = z_scores(stated);
    let n = z.len() as f64;
    let names = ["phi", "psi", "eta", "delta", "xi"];
    let mut report = Vec::new();
    let mut bad = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let m = z.iter().map(|r| r[i]).sum::<f64>() / n;
        let sd = (z.iter().map(|r| (r[i] - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        report.push(format!("{name} {sd:.3} (mean {m:+.3})"));
        if !(0.85..=1.2).contains(&sd) {
            bad.push(*name);
        }
    }
    eprintln!("stated = {stated}: z-score sds {}", report.join(", "));
    assert!(
        bad.is_empty(),
        "z-score sd outside 0.85-1.2 for {bad:?}: {report:?}"
    );
}

#[test]
fn ml_sds_are_honest_with_the_noise_stated() {
    check(true);
}

#[test]
fn ml_sds_are_honest_without_stated_noise() {
    check(false);
}
