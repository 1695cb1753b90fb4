//! Angles of datasets and models: one wrap used by the importers, the fitter
//! and the paper's estimator alike.

use std::f64::consts::PI;

/// Angle in (-pi, pi]; exact (no rounding) for angles already in range.
/// One floor instead of `rem_euclid`, whose `fmod` was a visible share of
/// every residual evaluation.
pub fn wrap(a: f64) -> f64 {
    let tau = 2.0 * PI;
    let mut b = a - tau * ((a + PI) / tau).floor();
    if b <= -PI {
        b += tau;
    } else if b > PI {
        b -= tau;
    }
    b
}
