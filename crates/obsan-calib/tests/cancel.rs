//! A set cancel flag (`obsan_expr::with_cancel`, what Ctrl-C sets in the
//! Python package) stops every estimator and the Monte Carlo runs with
//! their typed errors; unset, the same calls give answers, so the error is
//! the flag's.

use obsan_calib::{
    calib_predictor, calibrate, run_runs, simulate, table, CalibError, CalibrateOptions, Method,
    MontecarloError, SimOptions,
};
use obsan_expr::with_cancel;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

#[test]
fn every_estimator_returns_cancelled() {
    let p = calib_predictor();
    let (data, _) = simulate(&SimOptions::default()).unwrap();
    for m in [Method::Det, Method::Ls, Method::Cekf, Method::Ml] {
        let o = CalibrateOptions::for_dataset(&data, m);
        assert!(calibrate(&data, Some(&p), &o).is_ok(), "{m:?}");
        let flag = Arc::new(AtomicBool::new(true));
        let r = with_cancel(flag, || calibrate(&data, Some(&p), &o));
        assert_eq!(r.unwrap_err(), CalibError::Cancelled, "{m:?}");
    }
    assert_eq!(CalibError::Cancelled.to_string(), "interrupted");
}

/// The flag, set by the first finished run, reaches rayon's worker threads:
/// the runs not yet started are skipped (at most one per worker can finish
/// after it), and the answer is `Cancelled`, not a table of fewer runs.
#[test]
fn monte_carlo_runs_stop_on_the_worker_threads() {
    let p = calib_predictor();
    let t = table(5).unwrap();
    let cell = &t.cells[0];
    let runs = 4 * rayon::current_num_threads() + 4;
    let flag = Arc::new(AtomicBool::new(false));
    let finished = AtomicUsize::new(0);
    let tick = || {
        finished.fetch_add(1, Ordering::Relaxed);
        flag.store(true, Ordering::Relaxed);
    };
    let r = with_cancel(flag.clone(), || {
        run_runs(cell, t.modes, 0..runs, 1, &p, &tick)
    });
    assert_eq!(r.unwrap_err(), MontecarloError::Cancelled);
    let n = finished.load(Ordering::Relaxed);
    assert!(
        (1..=rayon::current_num_threads()).contains(&n),
        "{n} of {runs} runs finished"
    );
}
