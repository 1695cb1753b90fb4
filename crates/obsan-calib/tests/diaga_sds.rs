//! The standard deviations `obsan calibrate --method ml`
//! reports are honest whether or not dataset.json states the noise: over
//! 100 seeded datasets the z-scores `(estimate - truth) / sd` of every param
//! have a standard deviation within 0.85-1.2. Stated: generalised least
//! squares under the stated encoder noise, the covariance at the final
//! estimate. Unstated (the same datasets with `noise` emptied, as a user's
//! files would be): the bearing noise from the LS residuals and the encoder
//! intensity from the wheel speeds (`EncoderNoise::Estimated`), then the same
//! GLS. Small datasets (faster circles, 200 bearings each) keep it CI-fast.

use obsan_calib::{
    calib_predictor, calibrate, simulate, CalibrateOptions, EncoderNoise, Method, SimOptions,
};
use obsan_data::wrap;
use rayon::prelude::*;

const RUNS: u64 = 100;

/// Per run the z-scores of phi, psi, eta, delta, xi, and the encoder
/// intensity used over the true one.
fn z_scores(stated: bool) -> Vec<([f64; 5], f64)> {
    let p = calib_predictor();
    (1..=RUNS)
        .into_par_iter()
        .map(|seed| {
            let o = SimOptions {
                seed,
                nu: 0.5,
                bearings: Some(200),
                ..SimOptions::default()
            };
            let (mut data, truth) = simulate(&o).unwrap();
            if !stated {
                data.meta.noise.clear();
            }
            let opts = CalibrateOptions::for_dataset(&data, Method::Ml);
            let r = calibrate(&data, Some(&p), &opts).unwrap();
            let c_true = o.k_encoder.powi(2) / o.r_nominal;
            let ratio = match (stated, r.encoder_noise) {
                (true, EncoderNoise::Stated { c, .. }) => c / c_true,
                (false, EncoderNoise::Estimated { c, .. }) => c / c_true,
                (_, e) => panic!("seed {seed}: stated {stated} but {e:?}"),
            };
            let c = &r.calibration;
            let sd = c.sd().unwrap();
            let t = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
            let v = c.values();
            let z = std::array::from_fn(|i| {
                let d = if i < 2 {
                    wrap(v[i] - t[i])
                } else {
                    v[i] - t[i]
                };
                d / sd[i]
            });
            (z, ratio)
        })
        .collect()
}

fn check(stated: bool) {
    let runs = z_scores(stated);
    let n = runs.len() as f64;
    let names = ["phi", "psi", "eta", "delta", "xi"];
    let mut report = Vec::new();
    let mut bad = Vec::new();
    for (i, name) in names.iter().enumerate() {
        let m = runs.iter().map(|r| r.0[i]).sum::<f64>() / n;
        let sd = (runs.iter().map(|r| (r.0[i] - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        report.push(format!("{name} {sd:.3} (mean {m:+.3})"));
        if !(0.85..=1.2).contains(&sd) {
            bad.push(*name);
        }
    }
    let (lo, hi) = runs.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| {
        (a.min(r.1), b.max(r.1))
    });
    eprintln!(
        "stated {stated}: z-score sds {}; encoder intensity / truth {lo:.3}-{hi:.3}",
        report.join(", ")
    );
    assert!(
        bad.is_empty(),
        "z-score sd outside 0.85-1.2 for {bad:?}: {report:?}"
    );
    // The wheel speeds' thousands of rows pin the intensity (a few % each).
    assert!(lo > 0.85 && hi < 1.15, "intensity ratio {lo}-{hi}");
}

#[test]
fn ml_sds_are_honest_with_the_noise_stated() {
    check(true);
}

#[test]
fn ml_sds_are_honest_without_stated_noise() {
    check(false);
}
