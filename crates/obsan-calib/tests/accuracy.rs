//! Accuracy of `calibrate` on simulated data (fixed seeds), against the
//! simulator's truth and the Cramér–Rao bound (docs/accuracy.md).

use obsan_calib::{calibrate, simulate, CalibrateOptions, Method, SimOptions, Truth};
use obsan_data::wrap;
use obsan_fit::Predictor;

fn predictor() -> Predictor {
    obsan_calib::calib_predictor()
}

fn truth_values(t: &Truth) -> [f64; 5] {
    [t.phi, t.psi, t.eta, t.delta, t.xi]
}

/// Errors in table units: deg, deg, %, %, %.
fn errors(est: [f64; 5], t: &Truth) -> [f64; 5] {
    let w = truth_values(t);
    [
        wrap(est[0] - w[0]).to_degrees(),
        wrap(est[1] - w[1]).to_degrees(),
        100.0 * (est[2] - w[2]) / w[2],
        100.0 * (est[3] - w[3]) / w[3],
        100.0 * (est[4] - w[4]) / w[4],
    ]
}

#[test]
fn every_method_recovers_noise_free_parameters() {
    let p = predictor();
    let o = SimOptions {
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..SimOptions::default()
    };
    let (data, truth) = simulate(&o).unwrap();
    for (m, tol) in [
        (Method::Det, 1e-3),
        (Method::Ls, 1e-6),
        (Method::Cekf, 1e-5),
        (Method::Ml, 1e-6),
    ] {
        let mut co = CalibrateOptions::for_dataset(&data, m);
        // Noise-free data: the filter still needs a measurement variance.
        co.sigma_beta = Some(1e-5);
        let r = calibrate(&data, Some(&p), &co).unwrap();
        for (k, (e, w)) in r
            .calibration
            .values()
            .iter()
            .zip(truth_values(&truth))
            .enumerate()
        {
            assert!(
                (e - w).abs() < tol * w.abs().max(1.0),
                "{m:?} parameter {k}: {e} vs {w}"
            );
        }
        // The metric step with the true d0 (end of section V-C), except CEKF
        // whose start state comes from DET.
        if m != Method::Cekf {
            let (metric, _) = r.metric.unwrap();
            let want = [truth.rho, truth.r_right, truth.r_left, truth.wheel_base];
            for (e, w) in metric.values().iter().zip(want) {
                assert!((e - w).abs() < 10.0 * tol, "{m:?} metric {e} vs {w}");
            }
        }
    }
}

/// RMS error over `runs` seeds, per parameter, in table units.
fn rms_errors(o: &SimOptions, m: Method, runs: u64, p: &Predictor) -> [f64; 5] {
    let mut acc = [0.0; 5];
    for seed in 0..runs {
        let (data, truth) = simulate(&SimOptions {
            seed: 1000 + seed,
            ..o.clone()
        })
        .unwrap();
        let co = CalibrateOptions::for_dataset(&data, m);
        let r = calibrate(&data, Some(p), &co).unwrap();
        for (a, e) in acc.iter_mut().zip(errors(r.calibration.values(), &truth)) {
            *a += e * e / runs as f64;
        }
    }
    acc.map(f64::sqrt)
}

#[test]
fn ml_and_ls_reach_the_cramer_rao_bound_with_the_papers_noise() {
    // sigma_beta = 1 deg, K = 0.001 (Tables II, III). ML is driven by the
    // measured wheel speeds: its bound includes the encoder noise. LS uses
    // the commanded q, exact here (the circle is known), so its bound is
    // the bearing-only one (which it could not beat).
    let p = predictor();
    let o = SimOptions {
        bearings: Some(100),
        ..SimOptions::default()
    };
    let bearing_only = o.crlb_sd(&p, false).unwrap();
    let with_encoders = o.crlb_sd(&p, true).unwrap();
    let ml = rms_errors(&o, Method::Ml, 100, &p);
    let ls = rms_errors(&o, Method::Ls, 100, &p);
    for k in 0..5 {
        // Encoder noise cannot make the bound smaller.
        assert!(with_encoders[k] >= bearing_only[k] * (1.0 - 1e-9));
        // 100 runs estimate an RMS to about 7%: 1.15 leaves two such errors.
        assert!(
            ml[k] < 1.15 * with_encoders[k],
            "ML parameter {k}: rms {} vs CRLB {}",
            ml[k],
            with_encoders[k]
        );
        assert!(
            ls[k] < 1.5 * bearing_only[k],
            "LS parameter {k}: rms {} vs CRLB {}",
            ls[k],
            bearing_only[k]
        );
    }
}

#[test]
fn ml_is_not_biased_by_a_ratio_error_that_biases_ls() {
    // Table VII, dq = 0.05: the executed ratio is q + dq. ML uses the measured
    // wheel speeds; LS assumes the commanded circle.
    let p = predictor();
    let o = SimOptions {
        dq: 0.05,
        bearings: Some(100),
        ..SimOptions::default()
    };
    let ml = rms_errors(&o, Method::Ml, 20, &p);
    let ls = rms_errors(&o, Method::Ls, 20, &p);
    // The paper's Table VII row dq = 0.05 (mean errors of LS): eta, delta, xi (%).
    let paper = [6.3, 4.1, 2.0];
    for k in 0..3 {
        assert!(
            ml[2 + k] < 0.5 * paper[k],
            "ML parameter {}: {} vs paper {}",
            2 + k,
            ml[2 + k],
            paper[k]
        );
    }
    // dq biases LS's delta and xi (eq. 18 with the wrong q); ML's stay at the noise level.
    for k in [3, 4] {
        assert!(
            5.0 * ml[k] < ls[k],
            "ML {} should beat biased LS {} by far",
            ml[k],
            ls[k]
        );
    }
}

/// Figures 5-7 on noise-free data: the closed form (DET, LS) and the
/// integrated model (ML) are independent computations of the same bearings,
/// so every curve lies on the observations; the nodes are centres of the
/// observation function's mirror symmetry, beta(n + x) + beta(n - x) equal
/// modulo pi for every x (Algorithm 1).
#[test]
fn figure_curves_lie_on_noise_free_data_and_nodes_are_mirror_centres() {
    let p = predictor();
    let o = SimOptions {
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..SimOptions::default()
    };
    let (data, _) = simulate(&o).unwrap();
    let mut co = CalibrateOptions::for_dataset(&data, Method::Ml);
    co.sigma_beta = Some(1e-5);
    let done = obsan_calib::calibrate(&data, Some(&p), &co).unwrap();
    let curves = done.figure_curves(&data, &p, &co).unwrap();
    assert_eq!(curves.len(), 3);
    for c in &curves {
        let ml = c.ml.as_ref().expect("ML converges on noise-free data");
        for (k, &b) in c.observed.iter().enumerate() {
            assert!(wrap(c.det[k] - b).abs() < 2e-3, "{} DET at {k}", c.name);
            assert!(wrap(c.ls[k] - b).abs() < 1e-6, "{} LS at {k}", c.name);
            assert!(wrap(ml[k] - b).abs() < 1e-6, "{} ML at {k}", c.name);
        }
        assert!(!c.nodes.is_empty(), "{}: no node inside the data", c.name);
        // Mirror symmetry about each node, read on the noise-free LS curve
        // (it equals the data, checked above) by linear interpolation.
        let at = |s: f64| -> Option<f64> {
            let i = c.s.windows(2).position(|w| w[0] <= s && s <= w[1])?;
            let u = (s - c.s[i]) / (c.s[i + 1] - c.s[i]);
            Some(c.ls[i] + u * wrap(c.ls[i + 1] - c.ls[i]))
        };
        let (lo, hi) = (c.s[0], c.s[c.s.len() - 1]);
        let widest = c
            .nodes
            .iter()
            .map(|&(n, _)| (n - lo).min(hi - n))
            .fold(0.0, f64::max);
        assert!(
            widest > (hi - lo) / 8.0,
            "{}: no node away from the ends",
            c.name
        );
        for &(n, _) in &c.nodes {
            let reach = (n - lo).min(hi - n);
            let pairs: Vec<f64> = (1..20)
                .map(|j| reach * j as f64 / 20.0)
                .filter_map(|x| Some(at(n + x)? + at(n - x)?))
                .collect();
            for v in &pairs {
                // Equal modulo pi: the doubled angles agree.
                let d = wrap(2.0 * (v - pairs[0]));
                assert!(d.abs() < 1e-2, "{} node {n}: {v} vs {}", c.name, pairs[0]);
            }
        }
    }
}

/// A circle whose bearings carry gross errors (a 11.7% bearing scale error
/// wraps some of the q = -1 circle's bearings to the other side of +-pi) can
/// hide its period from DET's scan; the other two circles predict it (eq. 18)
/// and LS from there finds xi_q = xi (1 - delta q) of the truth up to the
/// scale error's own bias (1.7% here; seed 1, whose period DET reads
/// directly, gets the same 1.257), where the misread period was 2.1 times it.
#[test]
fn a_misread_period_is_recovered_from_the_other_circles() {
    let mut o = SimOptions {
        seed: 4,
        ..SimOptions::default()
    };
    o.effects.set("bearing_scale", 0.117).unwrap();
    let (data, truth) = simulate(&o).unwrap();
    let r = calibrate(
        &data,
        None,
        &CalibrateOptions::for_dataset(&data, Method::Ls),
    )
    .unwrap();
    let t = r.trajectories.iter().find(|t| t.q == -1.0).unwrap();
    assert!(t.period_from_others, "the q = -1 period was read directly");
    let want = truth.xi * (1.0 + truth.delta);
    assert!(
        (t.closed.xi_q - want).abs() < 0.05 * want,
        "xi_q {} vs {want}",
        t.closed.xi_q
    );
    // The clean circles keep their own reading.
    assert!(
        r.trajectories
            .iter()
            .filter(|t| t.period_from_others)
            .count()
            == 1
    );
}

/// ML on Table VII's dq = 0.1 set-up (100 bearings per circle).
fn ml_at_dq_0_1(seed: u64) -> (obsan_calib::CalibrationReport, Truth) {
    let o = SimOptions {
        seed,
        dq: 0.1,
        bearings: Some(100),
        ..SimOptions::default()
    };
    let (data, truth) = simulate(&o).unwrap();
    let opts = CalibrateOptions::for_dataset(&data, Method::Ml);
    (calibrate(&data, Some(&predictor()), &opts).unwrap(), truth)
}

/// Regression: ML's phi was returned unwrapped (130679.94 deg, that is
/// -0.06 deg, on this run, where the start had eta near 0 so phi moved
/// freely); angles come back in (-pi, pi].
#[test]
fn ml_returns_phi_as_an_angle() {
    let (r, truth) = ml_at_dq_0_1(1);
    let c = &r.calibration;
    let sd = c.sd().unwrap();
    assert!(
        c.phi > -std::f64::consts::PI && c.phi <= std::f64::consts::PI,
        "{}",
        c.phi
    );
    assert!(
        (c.phi - truth.phi).abs() < 4.0 * sd[0],
        "{} ± {}",
        c.phi,
        sd[0]
    );
}

/// Table VII's dq = 0.1 makes the q = 0.9 circle nearly straight (q + dq
/// = 1.0 ~ rR / rL: a one-hour loop far from the feature); section V-C then
/// says eta ~ 0 and ML from there stopped in a wrong minimum (phi 167 deg,
/// eta -0.30 on this seed). ML now screens a few (phi, eta) starts when
/// V-C's eta is implausible and keeps the better fit.
#[test]
fn ml_recovers_the_parameters_when_a_circle_is_nearly_straight() {
    let (r, truth) = ml_at_dq_0_1(2);
    let est = r.calibration.values();
    let sd = r.calibration.sd().unwrap();
    let want = truth_values(&truth);
    for k in 0..5 {
        let e = if k < 2 {
            wrap(est[k] - want[k])
        } else {
            est[k] - want[k]
        };
        assert!(
            e.abs() < 4.0 * sd[k],
            "param {k}: {} vs {} (sd {})",
            est[k],
            want[k],
            sd[k]
        );
    }
}
