//! A set cancel flag (`obsan_expr::with_cancel`, what Ctrl-C sets in the
//! Python package) stops the fitter with its typed error; the same fit
//! without it succeeds, so the error is the flag's. The fitter predicts the
//! trajectories in parallel: the flag reaches its workers, and the result
//! does not depend on the number of threads.

use obsan_data::{Dataset, DatasetMeta, Series, Trajectory};
use obsan_expr::with_cancel;
use obsan_fit::{fit, minimise, FitError, FitOptions, FitTrajectory, LmOptions, Predictor};
use obsan_model::System;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// dx/dt = -k x + u observed directly; data from k = 0.5, x0 = 2 (and
/// 2.5, 3, ... for the further trajectories of [`problem_of`]).
fn problem() -> (Predictor, Dataset) {
    problem_of(1)
}

fn problem_of(n: usize) -> (Predictor, Dataset) {
    let src = "system decay\nstate x\nparam k\ninput u\nx' = -k*x + u\noutput y = x\n";
    let sys = System::parse(src, "decay.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let trajectories = (0..n)
        .map(|k| {
            let x0 = 2.0 + 0.5 * k as f64;
            let mut inputs = Series::new(vec!["u".into()]);
            let mut outputs = Series::new(vec!["y".into()]);
            for i in 0..=200 {
                let t = i as f64 * 0.05;
                inputs.push(t, &[Some(0.0)]);
                // A deterministic wobble, so that the residuals are not zero.
                let wobble = 1e-3 * ((i * (k + 3)) as f64).sin();
                if i > 0 {
                    outputs.push(t, &[Some(x0 * (-0.5 * t).exp() + wobble)]);
                }
            }
            Trajectory {
                name: format!("t{}", k + 1),
                inputs,
                outputs,
                meta: BTreeMap::new(),
            }
        })
        .collect();
    let data = Dataset {
        meta: DatasetMeta::default(),
        trajectories,
    };
    (p, data)
}

fn run_fit(p: &Predictor, data: &Dataset) -> Result<obsan_fit::FitResult, FitError> {
    let trajs = FitTrajectory::all(p, data);
    let opts = FitOptions {
        max_iterations: 50,
        cost_tolerance: 1e-14,
        step_tolerance: 0.0,
        sigma: vec![0.01],
        max_step: 0.0,
        input_noise: None,
    };
    let states: Vec<Vec<f64>> = trajs.iter().map(|_| vec![1.5]).collect();
    fit(p, &trajs, &[0.8], &states, &opts)
}

/// Run `f` on a pool of `n` threads.
fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .unwrap()
        .install(f)
}

#[test]
fn a_fit_over_many_trajectories_is_the_same_on_one_thread_and_on_three() {
    let (p, data) = problem_of(7);
    let one = on_threads(1, || run_fit(&p, &data)).unwrap();
    let three = on_threads(3, || run_fit(&p, &data)).unwrap();
    // The sums run in trajectory order whatever the threads: bit for bit.
    assert_eq!(one.params, three.params);
    assert_eq!(one.initial_states, three.initial_states);
    assert_eq!(one.cost.to_bits(), three.cost.to_bits());
    assert_eq!(one.iterations, three.iterations);
    // And the fit is right: k = 0.5, each x0 its own (to the wobble).
    assert!((one.params[0] - 0.5).abs() < 1e-3, "{:?}", one.params);
    for (k, s) in one.initial_states.iter().enumerate() {
        assert!((s[0] - (2.0 + 0.5 * k as f64)).abs() < 1e-2, "{k}: {s:?}");
    }
    // A set flag still stops the parallel fit with its typed error.
    let flag = Arc::new(AtomicBool::new(true));
    let r = on_threads(3, || with_cancel(flag, || run_fit(&p, &data)));
    assert_eq!(r.unwrap_err(), FitError::Cancelled);
}

#[test]
fn a_cancelled_fit_is_the_cancelled_error() {
    let (p, data) = problem();
    let free = run_fit(&p, &data).unwrap();
    assert!((free.params[0] - 0.5).abs() < 1e-6, "{:?}", free.params);
    let flag = Arc::new(AtomicBool::new(true));
    let r = with_cancel(flag, || run_fit(&p, &data));
    assert_eq!(r.unwrap_err(), FitError::Cancelled);
    assert_eq!(FitError::Cancelled.to_string(), "interrupted");
}

/// The least-squares core stops at its next iteration once the flag is set
/// (here by the cost itself, as another thread would), unconverged.
#[test]
fn the_least_squares_core_stops_at_a_cancel() {
    use nalgebra::{DMatrix, DVector};
    // Rosenbrock's valley: about 20 iterations from (-1.2, 1).
    let r = |x: &[f64]| [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]];
    let normal = |x: &[f64]| {
        let j = DMatrix::from_row_slice(2, 2, &[20.0 * x[0], -10.0, 1.0, 0.0]);
        let rv = DVector::from_column_slice(&r(x));
        (j.transpose() * &j, j.transpose() * rv)
    };
    let opts = LmOptions::default();
    let free = minimise(
        &[-1.2, 1.0],
        |x| r(x).iter().map(|v| v * v).sum(),
        normal,
        |_| {},
        &opts,
    );
    assert!(free.converged && free.iterations > 3);
    let flag = Arc::new(AtomicBool::new(false));
    let calls = std::cell::Cell::new(0);
    let out = with_cancel(flag.clone(), || {
        let cost = |x: &[f64]| {
            calls.set(calls.get() + 1);
            if calls.get() == 3 {
                flag.store(true, Ordering::Relaxed);
            }
            r(x).iter().map(|v| v * v).sum()
        };
        minimise(&[-1.2, 1.0], cost, normal, |_| {}, &opts)
    });
    assert!(!out.converged);
    assert!(
        out.iterations < free.iterations,
        "{} iterations",
        out.iterations
    );
}

/// More shared params than MAX_FIT_PARAMS is refused by its error before
/// the dense normal equations are allocated; at the limit the
/// problem is accepted (it fails later only on its own start values here).
#[test]
fn more_params_than_the_limit_is_refused() {
    let limit = obsan_fit::MAX_FIT_PARAMS;
    let names: Vec<String> = (0..limit).map(|i| format!("p{i}")).collect();
    let src = format!(
        "system decay\nstate x\nparam k, {}\ninput u\nx' = -k*x + u\noutput y = x\n",
        names.join(", ")
    );
    let sys = System::parse(&src, "decay.sys").unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let (_, data) = problem();
    let trajs = FitTrajectory::all(&p, &data);
    let opts = FitOptions {
        max_iterations: 5,
        cost_tolerance: 1e-14,
        step_tolerance: 0.0,
        sigma: vec![0.01],
        max_step: 0.0,
        input_noise: None,
    };
    let e = fit(&p, &trajs, &vec![0.5; limit + 1], &[vec![1.5]], &opts).unwrap_err();
    assert_eq!(
        e,
        FitError::TooManyParams {
            params: limit + 1,
            limit
        }
    );
    assert!(e.to_string().starts_with("too large: 1001 params"), "{e}");
}
