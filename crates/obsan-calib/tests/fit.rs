//! Maximum-likelihood fitting of systems/calib.sys to simulated data.

use obsan_calib::{simulate, SimOptions};
use obsan_fit::{fit, FitOptions, FitTrajectory, Predictor};

fn predictor() -> Predictor {
    obsan_calib::calib_predictor()
}

fn run(o: &SimOptions, sigma: f64) -> (obsan_fit::FitResult, obsan_calib::Truth) {
    let p = predictor();
    let (data, truth) = simulate(o).unwrap();
    let trajs: Vec<FitTrajectory> = data
        .trajectories
        .iter()
        .map(|t| FitTrajectory {
            name: &t.name,
            inputs: &t.inputs,
            outputs: &t.outputs,
            consts: vec![t.meta["q"]],
        })
        .collect();
    // A start 5-10% off the truth (the estimators' own initialisation is DET/LS).
    let init = vec![
        truth.phi + 0.05,
        truth.psi * 0.95,
        truth.eta * 1.08,
        truth.delta * 0.97,
        truth.xi * 1.05,
    ];
    let states: Vec<Vec<f64>> = truth
        .trajectories
        .iter()
        .map(|t| vec![t.mu0 * 1.1, t.gamma0 - 0.05])
        .collect();
    let opts = FitOptions {
        max_iterations: 50,
        cost_tolerance: 1e-14,
        step_tolerance: 0.0,
        sigma: vec![sigma],
        max_step: 0.0,
        input_noise: None,
    };
    (fit(&p, &trajs, &init, &states, &opts).unwrap(), truth)
}

#[test]
fn noise_free_data_give_the_true_parameters() {
    let o = SimOptions {
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..SimOptions::default()
    };
    let (r, truth) = run(&o, 1f64.to_radians());
    let want = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
    for (k, (e, w)) in r.params.iter().zip(want).enumerate() {
        assert!(
            (e - w).abs() < 1e-6,
            "param {k}: {e} vs {w} after {} iterations",
            r.iterations
        );
    }
    for (s, t) in r.initial_states.iter().zip(&truth.trajectories) {
        assert!((s[0] - t.mu0).abs() < 1e-6 && (s[1] - t.gamma0).abs() < 1e-6);
    }
    assert!(r.residual_rms[0] < 1e-8);
}

#[test]
fn noisy_data_give_estimates_within_their_standard_deviations() {
    let o = SimOptions {
        seed: 11,
        ..SimOptions::default()
    };
    let (r, truth) = run(&o, o.sigma_beta);
    let want = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
    for (k, ((e, w), sd)) in r.params.iter().zip(want).zip(&r.params_sd).enumerate() {
        assert!(sd.is_finite() && *sd > 0.0);
        assert!(
            (e - w).abs() < 4.0 * sd,
            "param {k}: error {} is more than 4 sd ({sd})",
            e - w
        );
    }
    // The residual level matches the bearing noise (1 deg) within 10%.
    assert!(
        (r.residual_rms[0] / o.sigma_beta - 1.0).abs() < 0.1,
        "rms {}",
        r.residual_rms[0]
    );
}

#[test]
fn derived_inputs_rate_telescopes_and_abs_keeps_its_sign() {
    use obsan_data::{add_derived_inputs, Series};
    let mut s = Series::new(vec!["u".into(), "w".into()]);
    for k in 0..50 {
        let t = k as f64 * 0.1;
        s.push(t, &[Some((t * 0.7).sin()), Some(-1.0 - t)]);
    }
    let defs = vec![
        ("du".to_string(), "rate(u)".to_string()),
        ("a".to_string(), "sqrt((u - w)^2)*w".to_string()),
        ("b".to_string(), "sqrt(w^2)".to_string()),
    ];
    add_derived_inputs(&mut s, &defs, &Default::default()).unwrap();
    let du = s.column("du").unwrap();
    // The integral of rate(u) over rows 0..k is u[k] - u[0] (identity).
    let mut acc = 0.0;
    for (k, d) in du.iter().enumerate().take(49) {
        acc += d.unwrap() * (s.t()[k + 1] - s.t()[k]);
        let want = s.column("u").unwrap()[k + 1].unwrap() - s.column("u").unwrap()[0].unwrap();
        assert!((acc - want).abs() < 1e-12);
    }
    for k in 0..50 {
        let (u, w) = (s.values()[0][k].unwrap(), s.values()[1][k].unwrap());
        assert!((s.column("a").unwrap()[k].unwrap() - (u - w).abs() * w).abs() < 1e-12);
        // sqrt(w^2) is |w|, not w, for negative w.
        assert!((s.column("b").unwrap()[k].unwrap() - w.abs()).abs() < 1e-12);
    }
}

/// A delayed unicycle-like model: x' = v cos(th), th' = w, y = atan2(x, 1) ...
fn delayed() -> Predictor {
    let src = "system d\nstate x, th\nparam tau\ninput v, w\ndelay tau\nx' = v*cos(th)\nth' = w\noutput y = atan2(1 - x, 1 + th)\n";
    let sys = obsan_model::System::parse(src, "d.sys").unwrap();
    Predictor::new(&sys.normal_form(None, &[]).unwrap())
}

fn steps() -> obsan_data::Series {
    let mut s = obsan_data::Series::new(vec!["v".into(), "w".into()]);
    for k in 0..400 {
        let t = k as f64 * 0.02;
        let v = if (t as i64) % 3 == 0 {
            0.0
        } else {
            0.3 + 0.1 * (t * 0.7).sin()
        };
        s.push(t, &[Some(v), Some(0.2 * (t * 1.3).cos())]);
    }
    s
}

#[test]
fn a_delay_equals_shifted_inputs_exactly() {
    // Identity: with delay tau the prediction equals the undelayed model
    // driven by the inputs re-stamped t + tau (first row held before).
    let p = delayed();
    let inputs = steps();
    let times: Vec<f64> = (1..70).map(|k| k as f64 * 0.11).collect();
    let tau = 0.37;
    let a = p.predict(&[0.1, 0.2, tau], &[], &inputs, &times).unwrap();
    let row = |k: usize| [inputs.values()[0][k], inputs.values()[1][k]];
    let mut shifted = obsan_data::Series::new(inputs.columns().to_vec());
    shifted.push(0.0, &row(0));
    for (k, t) in inputs.t().iter().enumerate() {
        shifted.push(t + tau, &row(k));
    }
    let b = p.predict(&[0.1, 0.2, 0.0], &[], &shifted, &times).unwrap();
    for (x, y) in a.iter().zip(&b) {
        assert!((x[0] - y[0]).abs() < 1e-12, "{x:?} {y:?}");
    }
}

#[test]
fn the_delay_sensitivity_matches_finite_differences() {
    let p = delayed();
    let inputs = steps();
    // Output times halfway between row changes (t_k + tau): at a row change
    // the output is not differentiable in tau (one-sided derivatives differ).
    let times: Vec<f64> = (5..390)
        .step_by(7)
        .map(|k| 0.37 + 0.02 * k as f64 + 0.01)
        .collect();
    for max_step in [0.0, 0.5] {
        let integ = obsan_fit::Integration {
            max_step,
            sensitivities: true,
            input_noise: None,
        };
        let x0 = [0.1, 0.2, 0.37];
        let pr = p.predict_with(&x0, &[], &inputs, &times, &integ).unwrap();
        let h = 1e-6;
        let plain = obsan_fit::Integration {
            max_step,
            ..Default::default()
        };
        let up = p
            .predict_with(&[0.1, 0.2, 0.37 + h], &[], &inputs, &times, &plain)
            .unwrap();
        let dn = p
            .predict_with(&[0.1, 0.2, 0.37 - h], &[], &inputs, &times, &plain)
            .unwrap();
        let fd: Vec<f64> = (0..times.len())
            .map(|k| (up.outputs[k][0] - dn.outputs[k][0]) / (2.0 * h))
            .collect();
        let scale = fd.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (k, f) in fd.iter().enumerate() {
            let an = pr.jacobians[k][2];
            // The analytic column spreads each row change's impulse over its
            // step: first order in the step length (0.02 s here; it tends to
            // the finite difference as the rows get finer). It only guides the
            // fit; the residuals themselves are exact.
            assert!(
                (f - an).abs() < 5e-3 * scale,
                "max_step {max_step} t {}: {f} vs {an}",
                times[k]
            );
        }
    }
}

/// A first-order lag `va' = (v - va)/T` driven by a unit step at t = 1 s,
/// with input rows 0.02 s apart: the prediction must follow the exact
/// solution `1 - exp(-(t - 1)/T)` even when T is far below max_step
/// (explicit RK4 over merged 0.5 s steps would blow up for T = 0.05: the
/// steps are bounded by the dynamics' own time scale).
#[test]
fn a_fast_lag_follows_its_exact_solution() {
    let src = "system lag\nstate va = v\nparam T = 1/5\ninput v\nva' = (v - va)/T\noutput y = va\n";
    let sys = obsan_model::System::parse(src, "lag.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let mut s = obsan_data::Series::new(vec!["v".into()]);
    for k in 0..300 {
        s.push(k as f64 * 0.02, &[Some(if k >= 50 { 1.0 } else { 0.0 })]);
    }
    let times: Vec<f64> = (1..100).map(|k| k as f64 * 0.05).collect();
    for t_lag in [0.05, 0.3] {
        for max_step in [0.0, 0.5] {
            let integ = obsan_fit::Integration {
                max_step,
                ..Default::default()
            };
            let pr = p
                .predict_with(&[0.0, t_lag], &[], &s, &times, &integ)
                .unwrap();
            for (t, y) in times.iter().zip(&pr.outputs) {
                let want = if *t <= 1.0 {
                    0.0
                } else {
                    1.0 - (-(t - 1.0) / t_lag).exp()
                };
                assert!(
                    (y[0] - want).abs() < 5e-4,
                    "T {t_lag}, max_step {max_step}, t {t}: {} vs {want}",
                    y[0]
                );
            }
        }
    }
}

/// A start that makes the state blow up is an error that
/// names the trajectory, the parameter values and what to do.
#[test]
fn a_diverging_start_names_the_trajectory_and_the_params() {
    let p = predictor();
    let (data, truth) = simulate(&SimOptions::default()).unwrap();
    let trajs = FitTrajectory::all(&p, &data);
    let init = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
    // mu' = -mu^2 eta (wR + delta wL) cos(gamma - phi) from mu = -50 and
    // gamma = phi reaches -inf in about 1/(50 * 0.16) s.
    let states: Vec<Vec<f64>> = truth
        .trajectories
        .iter()
        .map(|_| vec![-50.0, truth.phi])
        .collect();
    let opts = FitOptions {
        max_iterations: 5,
        cost_tolerance: 1e-14,
        step_tolerance: 0.0,
        sigma: vec![1f64.to_radians()],
        max_step: 0.0,
        input_noise: None,
    };
    let e = fit(&p, &trajs, &init, &states, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("trajectory 'q0.9'"), "{e}");
    assert!(
        e.contains("diverged") && e.contains(&format!("eta = {}", truth.eta)),
        "{e}"
    );
    assert!(e.contains("start values"), "{e}");
}
