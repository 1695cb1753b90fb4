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
