//! The integration of a first-order lag `va' = (v - va)/T`: its linear
//! part is integrated exactly (ETDRK4) with steps up to T, where plain
//! RK4 needed steps of T / 2. Both are compared with a reference at steps
//! of 1 ms (rows unmerged): the predicted outputs and their sensitivities,
//! whose error stays below what merging input rows into the default 0.5 s
//! steps costs a model without a lag.

use obsan_data::Series;
use obsan_fit::{Integration, Predictor};
use obsan_model::System;

/// A unicycle whose speed lags the command, observing two landmarks.
const MODEL: &str = "system lagged
state x, y, th, va
param kv, T
input v, omega
x' = (1 + kv)*va*cos(th)
y' = (1 + kv)*va*sin(th)
th' = omega
va' = (v - va)/T
output r1 = sqrt((6 - x)^2 + (2 - y)^2)
output b1 = atan2(2 - y, 6 - x) - th
output r2 = sqrt((-5 - x)^2 + (5 - y)^2)
output b2 = atan2(5 - y, -5 - x) - th
";

/// The same unicycle without the lag: its error at 0.5 s steps is that of
/// merging input rows alone.
const UNLAGGED: &str = "system unlagged
state x, y, th
param kv
input v, omega
x' = (1 + kv)*v*cos(th)
y' = (1 + kv)*v*sin(th)
th' = omega
output r1 = sqrt((6 - x)^2 + (2 - y)^2)
output b1 = atan2(2 - y, 6 - x) - th
output r2 = sqrt((-5 - x)^2 + (5 - y)^2)
output b2 = atan2(5 - y, -5 - x) - th
";

/// 50 Hz commands with steps (a stop-go speed) and a varying turn rate.
fn inputs() -> Series {
    let mut s = Series::new(vec!["v".into(), "omega".into()]);
    for k in 0..3000 {
        let t = k as f64 * 0.02;
        let v = if (t / 4.0).floor() as i64 % 2 == 0 {
            0.3
        } else {
            0.05
        };
        s.push(t, &[Some(v), Some(0.4 * (t / 5.0).cos())]);
    }
    s
}

/// The largest differences from `r` of the outputs and of the sensitivity
/// entries (each relative to the largest entry of its kind).
fn errors(p: &Predictor, x0: &[f64], ins: &Series, times: &[f64], step: f64) -> (f64, f64) {
    let run = |max_step| {
        let o = Integration {
            max_step,
            sensitivities: true,
            input_noise: None,
        };
        p.predict_with(x0, &[], ins, times, &o).unwrap()
    };
    let (r, a) = (run(0.001), run(step));
    let diff = |x: &[Vec<f64>], y: &[Vec<f64>]| {
        let scale = x.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = x
            .iter()
            .flatten()
            .zip(y.iter().flatten())
            .fold(0.0f64, |m, (u, v)| m.max((u - v).abs()));
        d / scale
    };
    (
        diff(&r.outputs, &a.outputs),
        diff(&r.jacobians, &a.jacobians),
    )
}

#[test]
fn an_exact_lag_step_adds_less_error_than_merging_rows() {
    let sys = System::parse(MODEL, "lagged.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let plain = System::parse(UNLAGGED, "unlagged.sys").unwrap();
    let q = Predictor::new(&plain.normal_form(None, &[]).unwrap());
    let ins = inputs();
    // Sparse output times, as MRCLAM's: the steps reach their bound.
    let times: Vec<f64> = (1..80).map(|k| k as f64 * 0.73 + 0.05).collect();
    // What the default 0.5 s steps cost without a lag (rows merged).
    let merge = errors(&q, &[0.2, -0.1, 0.5, 0.02], &ins, &times, 0.5);
    for t_lag in [0.03, 0.1, 0.3] {
        let x0 = [0.2, -0.1, 0.5, 0.1, 0.02, t_lag];
        let old = errors(&p, &x0, &ins, &times, t_lag / 2.0);
        let new = errors(&p, &x0, &ins, &times, 0.5);
        println!(
            "T {t_lag}: outputs {:.2e} (plain RK4 at T/2 {:.2e}, no lag {:.2e}), \
             sensitivities {:.2e} ({:.2e}, {:.2e})",
            new.0, old.0, merge.0, new.1, old.1, merge.1
        );
        assert!(
            new.0 < merge.0 && new.1 < merge.1,
            "T {t_lag}: {new:?} against {merge:?}"
        );
    }
}

/// A lag alone under a constant input: `s(t) = u + (s0 - u) e^{-t/T}`, and
/// its sensitivities to s0 and T, against the exact solution at steps of T.
#[test]
fn a_lag_under_a_constant_input_is_integrated_exactly() {
    let model = "system lag
state s
param T
input u
s' = (u - s)/T
output y = s
";
    let sys = System::parse(model, "lag.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let mut ins = Series::new(vec!["u".into()]);
    for k in 0..=100 {
        ins.push(k as f64 * 0.02, &[Some(1.5)]);
    }
    let (s0, t_lag, u) = (-0.4, 0.05, 1.5);
    let times: Vec<f64> = (1..=8).map(|k| k as f64 * 0.25).collect();
    let o = Integration {
        max_step: 0.5,
        sensitivities: true,
        input_noise: None,
    };
    let pred = p.predict_with(&[s0, t_lag], &[], &ins, &times, &o).unwrap();
    // Plain RK4 at its old bound T / 2, printed for the sensitivity to T
    // (its forcing decays with the lag: neither method is exact there).
    let rk4 = Integration {
        max_step: t_lag / 2.0,
        ..o.clone()
    };
    let old = p
        .predict_with(&[s0, t_lag], &[], &ins, &times, &rk4)
        .unwrap();
    for (k, &t) in times.iter().enumerate() {
        let e = (-t / t_lag).exp();
        let s = u + (s0 - u) * e;
        let ds_ds0 = e;
        let ds_dt = (s0 - u) * e * t / (t_lag * t_lag);
        let got = (
            pred.outputs[k][0],
            pred.jacobians[k][0],
            pred.jacobians[k][1],
        );
        assert!((got.0 - s).abs() < 1e-12, "t {t}: {} against {s}", got.0);
        assert!(
            (got.1 - ds_ds0).abs() < 1e-12,
            "t {t}: {} against {ds_ds0}",
            got.1
        );
        let old_err = (old.jacobians[k][1] - ds_dt).abs();
        println!(
            "t {t}: d s / d T error {:.2e}, plain RK4 at T/2 {old_err:.2e}",
            (got.2 - ds_dt).abs()
        );
        // Within 0.1 %: far below what moves a fit's step or its sd.
        assert!(
            (got.2 - ds_dt).abs() < 1e-3 * ds_dt.abs().max(1e-3),
            "t {t}: {} against {ds_dt}",
            got.2
        );
    }
}
