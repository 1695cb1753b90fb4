//! The curvature test behind a stand-in (run by `settle` on the final fit):
//! an effect that rewrites outputs was named, yet the residuals of those
//! outputs still curve in the predicted value. Then the truth has another
//! form and the named effect only absorbs its linear part (a range bias
//! growing with range^2 named as a range scale and a range bias).
//!
//! The test: pooled over the outputs the effect rewrites and over every
//! trajectory, the whitened residual is regressed on the Legendre
//! polynomials P0 = 1, P1 = x, P2 = (3x^2 - 1)/2 of the predicted value
//! scaled to x in [-1, 1] over its pooled span, each divided by its output's
//! noise level (so the coefficients are in the outputs' units). The
//! curvature coefficient b2 is studentised: its sd uses the residual
//! variance the three regressors leave (never the stated level: a level
//! stated too large must not hide the curvature), on the degrees of freedom
//! left after the fit's share, inflated by that residual's long-run variance
//! factor (serial correlation).
//!
//! Size: when the named effect's form is right, the whitened residual is
//! white noise minus its projection on the fitted directions; the curvature
//! direction is orthogonal to P0 and P1, and a projection can only shrink the
//! variance of its component, so `z = b2 / sd(b2)` is at most Student's t on
//! `n - 3` degrees of freedom (and the estimated variance at least as large as
//! the noise's in expectation). With [`MIN_STAND_IN_RESIDUALS`] or more
//! residuals, P(|z| > [`Z_STAND_IN`]) is at most 7.0e-4 (t on 97 degrees of
//! freedom; 4.65e-4 in the normal limit) for each group of outputs tested,
//! and a dataset names few such groups (calib.sys one, mrclam.sys two).

use crate::residual::{orthonormal, serial_correlation, ResidualSeries};
use serde::Serialize;

/// |z| of the curvature coefficient above which a named effect is reported
/// as a stand-in: two-sided p 4.65e-4 in the normal limit, at most 7.0e-4
/// with [`MIN_STAND_IN_RESIDUALS`] residuals (Student's t, see the module
/// text).
pub const Z_STAND_IN: f64 = 3.5;

/// Fewer pooled residuals than this: no curvature test (the studentised
/// statistic's tail is then far from the normal's).
pub const MIN_STAND_IN_RESIDUALS: usize = 100;

/// The curvature test of the outputs a named effect rewrites.
#[derive(Clone, Debug, Serialize)]
pub struct Curvature {
    /// The outputs pooled: those the effect rewrites that have residuals.
    pub outputs: Vec<String>,
    /// The number of residuals pooled.
    pub n: usize,
    /// The predicted values' span `[lo, hi]`, mapped to x in [-1, 1]
    /// (angles wrapped to (-pi, pi] first).
    pub span: [f64; 2],
    /// The coefficient b2 of P2 = (3x^2 - 1)/2, in the outputs' units: the
    /// residual left is about b2 at both ends of the span and -b2/2 at its
    /// centre.
    pub coefficient: f64,
    /// Its sd (studentised, inflated by `correlation_factor`).
    pub sd: f64,
    /// `coefficient / sd`; a stand-in when `|z| >` [`Z_STAND_IN`].
    pub z: f64,
    /// The long-run variance factor of the residual after the regression.
    pub correlation_factor: f64,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `v - (b . v) b` for each (orthonormal) `b` of `basis`, in place.
fn remove(v: &mut [f64], basis: &[Vec<f64>]) {
    for b in basis {
        let d = dot(b, v);
        for (x, y) in v.iter_mut().zip(b) {
            *x -= d * y;
        }
    }
}

/// The curvature test of `outputs` in a fit's residual `series` (`n_fitted`
/// unknowns fitted to `n_total` residuals; see the module text), `level`
/// giving each output's noise level; `None` when fewer than
/// [`MIN_STAND_IN_RESIDUALS`] residuals, a span of zero width, or a
/// curvature direction the constant and the slope already span.
pub(crate) fn curvature(
    series: &[ResidualSeries],
    (n_fitted, n_total): (usize, usize),
    outputs: &[String],
    level: &dyn Fn(&str) -> Option<f64>,
) -> Option<Curvature> {
    let value = |s: &ResidualSeries, y: f64| if s.angular { obsan_data::wrap(y) } else { y };
    let series: Vec<(&ResidualSeries, f64)> = series
        .iter()
        .filter(|s| outputs.contains(&s.output) && !s.e.is_empty())
        .filter_map(|s| Some((s, level(&s.output)?)))
        .collect();
    let n: usize = series.iter().map(|s| s.0.e.len()).sum();
    let (lo, hi) = series
        .iter()
        .flat_map(|(s, _)| s.predicted.iter().map(|&y| value(s, y)))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
    if n < MIN_STAND_IN_RESIDUALS || hi <= lo || !(hi - lo).is_finite() {
        return None;
    }
    let (centre, half) = (0.5 * (hi + lo), 0.5 * (hi - lo));
    // Pooled whitened vectors: the residual and the three regressors.
    let (mut w, mut a0, mut a1, mut a2) = (vec![], vec![], vec![], vec![]);
    let mut lengths = vec![];
    for (s, sd) in &series {
        let x: Vec<f64> = s
            .predicted
            .iter()
            .map(|&y| (value(s, y) - centre) / half)
            .collect();
        w.extend(s.whitened(&s.e));
        a0.extend(s.whitened(&vec![1.0 / sd; x.len()]));
        a1.extend(s.whitened(&x.iter().map(|x| x / sd).collect::<Vec<_>>()));
        a2.extend(
            s.whitened(
                &x.iter()
                    .map(|x| (1.5 * x * x - 0.5) / sd)
                    .collect::<Vec<_>>(),
            ),
        );
        lengths.push(x.len());
    }
    let basis = orthonormal(&[a0, a1]);
    let mut u = a2.clone();
    remove(&mut u, &basis);
    let uu = dot(&u, &u);
    // A direction the constant and the slope span (or NaN): nothing to test.
    if uu.is_nan() || uu <= 1e-12 * dot(&a2, &a2) {
        return None;
    }
    let b2 = dot(&u, &w) / uu;
    let mut r = w;
    remove(&mut r, &basis);
    for (x, y) in r.iter_mut().zip(&u) {
        *x -= b2 * y;
    }
    // The fit's unknowns apportioned by the group's share of residuals.
    let share = n_fitted as f64 * n as f64 / n_total.max(1) as f64;
    let dof = n as f64 - share - 3.0;
    if dof < 1.0 {
        return None;
    }
    let mut segments = Vec::with_capacity(lengths.len());
    let mut at = 0;
    for len in lengths {
        segments.push(&r[at..at + len]);
        at += len;
    }
    let (_, _, factor) = serial_correlation(segments.into_iter());
    let sd = (dot(&r, &r) / dof * factor / uu).sqrt();
    Some(Curvature {
        outputs: outputs
            .iter()
            .filter(|o| series.iter().any(|s| s.0.output == **o))
            .cloned()
            .collect(),
        n,
        span: [lo, hi],
        coefficient: b2,
        sd,
        z: b2 / sd,
        correlation_factor: factor,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One series of `output` with predicted values spread evenly over
    /// [1, 3] and residual `(b2 P2(x) + sigma_true N(0, 1)) / sigma`.
    fn series(
        output: &str,
        n: usize,
        b2: f64,
        (sigma, sigma_true): (f64, f64),
        rng: &mut obsan_fit::Rng,
    ) -> ResidualSeries {
        let predicted: Vec<f64> = (0..n)
            .map(|i| 1.0 + 2.0 * i as f64 / (n - 1) as f64)
            .collect();
        let e = predicted
            .iter()
            .map(|y| {
                let x = y - 2.0;
                (b2 * (1.5 * x * x - 0.5) + sigma_true * rng.normal()) / sigma
            })
            .collect();
        ResidualSeries {
            trajectory: "t".into(),
            output: output.into(),
            t: (0..n).map(|i| i as f64).collect(),
            e,
            predicted,
            angular: false,
            inputs: vec![],
            input_integrals: vec![],
            whiten: None,
        }
    }

    fn test(s: &[ResidualSeries], sigma: f64) -> Option<Curvature> {
        let n = s.iter().map(|s| s.e.len()).sum();
        curvature(s, (0, n), &["y".into()], &|_| Some(sigma))
    }

    /// White noise of the right form: z is Student's t on n - 3 = 197
    /// degrees of freedom, whose variance is 197/195 = 1.010; the mean of
    /// 2000 squares has sd sqrt(2/2000) = 0.032 (the fourth moment a little
    /// above the normal's), so 0.15 is over four sds.
    #[test]
    fn white_noise_gives_a_unit_variance_z() {
        let mut rng = obsan_fit::Rng::new(7);
        let mut sum = 0.0;
        let runs = 2000;
        for _ in 0..runs {
            let c = test(&[series("y", 200, 0.0, (1.0, 1.0), &mut rng)], 1.0).unwrap();
            sum += c.z * c.z;
        }
        let mean = sum / runs as f64;
        assert!((mean - 1.010).abs() < 0.15, "mean z^2 {mean}");
    }

    /// A known curvature comes back in the outputs' units whatever the
    /// stated level (here four times the true one: the studentised sd does
    /// not read it), with z about b2 / (sigma / |P2|): |P2|^2 = n/5 over an
    /// even grid on [-1, 1], so 0.02 / (0.05 / sqrt(80)) = 3.6 per series,
    /// pooled over 4 series of 400: 7.2.
    #[test]
    fn a_known_curvature_is_measured_in_the_outputs_units() {
        let mut rng = obsan_fit::Rng::new(3);
        let s: Vec<ResidualSeries> = (0..4)
            .map(|_| series("y", 400, 0.02, (0.2, 0.05), &mut rng))
            .collect();
        let c = test(&s, 0.2).unwrap();
        assert!((c.coefficient - 0.02).abs() < 4.0 * c.sd, "{c:?}");
        assert!(
            (c.sd - 0.05 / (1600.0f64 / 5.0).sqrt()).abs() < 0.2 * c.sd,
            "{c:?}"
        );
        assert!(c.z > Z_STAND_IN, "{c:?}");
        assert_eq!(c.outputs, ["y"]);
        assert_eq!(c.span, [1.0, 3.0]);
    }

    /// Too few residuals, or predicted values without a span: no test.
    #[test]
    fn too_little_to_test_gives_none() {
        let mut rng = obsan_fit::Rng::new(1);
        let few = series("y", MIN_STAND_IN_RESIDUALS - 1, 0.0, (1.0, 1.0), &mut rng);
        assert!(test(&[few], 1.0).is_none());
        let mut flat = series("y", 200, 0.0, (1.0, 1.0), &mut rng);
        flat.predicted.iter_mut().for_each(|y| *y = 2.0);
        assert!(test(&[flat], 1.0).is_none());
        let other = series("z", 200, 0.0, (1.0, 1.0), &mut rng);
        assert!(test(&[other], 1.0).is_none());
    }
}
