//! A set cancel flag (`obsan_expr::with_cancel`) stops the F_p rank test,
//! which runs outside the engine's armed scope, with its typed error.

use obsan_analysis::{rank, AnalysisError, RankOptions};
use obsan_expr::with_cancel;
use obsan_model::System;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

#[test]
fn a_cancelled_rank_test_is_the_cancelled_error() {
    let path = format!("{ROOT}/systems/calib.sys");
    let sys = System::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    // Unset, the same test runs to its answer: eq. (16) is observable
    // (section IV, all 7 of state and parameters).
    let free = with_cancel(Arc::new(AtomicBool::new(false)), || {
        rank(&mut nf, RankOptions::default())
    })
    .unwrap();
    assert_eq!((free.rank, free.n), (7, 7));
    let r = with_cancel(Arc::new(AtomicBool::new(true)), || {
        rank(&mut nf, RankOptions::default())
    });
    assert_eq!(r.unwrap_err(), AnalysisError::Cancelled);
    assert_eq!(AnalysisError::Cancelled.to_string(), "interrupted");
}

/// The reconstruction of the symmetries and the search for modes run F_p
/// loops outside the engine too: a set flag stops them, and the result is an
/// error, never a partial answer passed on as the symmetries.
#[test]
fn cancelled_symmetries_and_modes_are_errors() {
    use obsan_analysis::{derive_modes, symmetries_with, DeriveOptions, Route, SymmetryOptions};
    let path = format!("{ROOT}/systems/calib.sys");
    let sys = System::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let mut nf = sys.normal_form(Some("q"), &[]).unwrap();
    let report = rank(&mut nf, RankOptions::default()).unwrap();
    let opts = SymmetryOptions {
        deadline: None,
        route: Route::Reconstruct,
    };
    // Unset: the three symmetries of eq. (16) on circles (eq. 17; rank 4 of 7).
    let free = with_cancel(Arc::new(AtomicBool::new(false)), || {
        symmetries_with(&mut nf, &report, &opts)
    })
    .unwrap();
    assert_eq!(free.vectors.len(), 3);
    let r = with_cancel(Arc::new(AtomicBool::new(true)), || {
        symmetries_with(&mut nf, &report, &opts)
    });
    assert_eq!(r.unwrap_err(), AnalysisError::Cancelled);
    let m = with_cancel(Arc::new(AtomicBool::new(true)), || {
        derive_modes(&mut nf, &report, &free, &DeriveOptions::default())
    });
    assert!(m.is_err(), "a cancelled search for modes gave an answer");
}
