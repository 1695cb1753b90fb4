//! Where a fit leaves structure: tests of the normalised residuals against
//! white noise of the stated level (step 2 of the workflow).
//!
//! Every test is a chi-square statistic (a sum of squared projections of the
//! residuals, pooled over trajectories) turned into an approximate standard
//! normal z by Wilson–Hilferty; a test flags structure when z exceeds
//! [`Z_STRUCTURE`]. Under white noise of the stated level each z is about
//! N(0, 1), so with the dozen tests here a clean fit flags nothing with
//! probability about 0.997.

use crate::stats::chi2_z;
use serde::Serialize;

/// z above which a test reports structure (one-sided p ~ 2.3e-4 each).
pub const Z_STRUCTURE: f64 = 3.5;

/// One trajectory's residuals of one output, with what they may correlate with.
#[derive(Clone, Debug)]
pub struct ResidualSeries {
    pub trajectory: String,
    pub output: String,
    pub t: Vec<f64>,
    /// Residual / sigma (measured minus predicted, wrapped for angles).
    pub e: Vec<f64>,
    pub predicted: Vec<f64>,
    pub angular: bool,
    /// Measured inputs at the output times (held values), by name.
    pub inputs: Vec<(String, Vec<f64>)>,
    /// Integral of each measured input up to the output times (e.g. wheel angle).
    pub input_integrals: Vec<(String, Vec<f64>)>,
    /// Whitener (lower Cholesky factor L) of the covariance of `e` when the
    /// errors are correlated (input noise integrated by the dynamics): the
    /// tests run on `L^-1 e` and `L^-1 X` (generalised least squares).
    pub whiten: Option<std::sync::Arc<obsan_fit::Whitener>>,
}

impl ResidualSeries {
    /// `L^-1 v`, or `v` without whitening.
    pub fn whitened(&self, v: &[f64]) -> Vec<f64> {
        match &self.whiten {
            Some(l) if l.len() == v.len() => l.whiten(v),
            _ => v.to_vec(),
        }
    }
}

/// The result of one test.
#[derive(Clone, Debug, Serialize)]
pub struct Structure {
    /// Short id: chi2, whiteness, bias, trend, loop, angle, wheel:<u>, input, lag.
    pub test: String,
    pub description: String,
    pub z: f64,
    pub significant: bool,
}

/// Residual statistics of a fit.
#[derive(Clone, Debug, Serialize)]
pub struct ResidualReport {
    pub n: usize,
    /// Long-run variance factor of the residuals, `1 + 2 sum_k (1 - k/11) rho_k`
    /// over lags 1..=10 (Bartlett), at least 1: how many times fewer
    /// independent residuals there are than residuals. Likelihood ratios and
    /// standard deviations are corrected by it (serially correlated errors,
    /// e.g. from integrated encoder noise, would otherwise overstate them).
    pub correlation_factor: f64,
    /// Sum of squared normalised residuals and its degrees of freedom.
    pub chi2: f64,
    pub dof: f64,
    pub tests: Vec<Structure>,
}

impl ResidualReport {
    pub fn consistent_with_noise(&self) -> bool {
        !self.tests.iter().any(|s| s.significant)
    }
    /// The significant tests, strongest first.
    pub fn structure(&self) -> Vec<&Structure> {
        let mut v: Vec<&Structure> = self.tests.iter().filter(|s| s.significant).collect();
        v.sort_by(|a, b| b.z.total_cmp(&a.z));
        v
    }
}

/// Squared norm of the projection of `e` on the span of `cols` and the rank used.
fn projection(e: &[f64], cols: &[Vec<f64>]) -> (f64, usize) {
    let basis = orthonormal(cols);
    let q = basis
        .iter()
        .map(|b| b.iter().zip(e).map(|(x, y)| x * y).sum::<f64>().powi(2))
        .sum();
    (q, basis.len())
}

/// An orthonormal basis of the span of `cols` (Gram–Schmidt, dropping
/// columns that are dependent to 1e-9 of their norm).
pub(crate) fn orthonormal(cols: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for c in cols {
        let mut v = c.clone();
        let n0: f64 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n0 == 0.0 || !n0.is_finite() {
            continue;
        }
        for b in &basis {
            let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
            for (x, y) in v.iter_mut().zip(b) {
                *x -= d * y;
            }
        }
        let n1: f64 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n1 > 1e-9 * n0 {
            for x in &mut v {
                *x /= n1;
            }
            basis.push(v);
        }
    }
    basis
}

fn centred(v: &[f64]) -> Vec<f64> {
    let m = v.iter().sum::<f64>() / v.len().max(1) as f64;
    v.iter().map(|x| x - m).collect()
}

/// Serial correlation within each series longer than 30 at lags 1..=10,
/// pooled: the Ljung–Box statistic and its degrees of freedom, and the
/// long-run variance factor `1 + 2 sum_k (1 - k/11) rho_k` (Bartlett),
/// weighted by length and at least 1 (1 when no series is long enough).
pub(crate) fn serial_correlation<'a>(series: impl Iterator<Item = &'a [f64]>) -> (f64, f64, f64) {
    let (mut q, mut k) = (0.0, 0.0);
    let (mut lr_sum, mut lr_w) = (0.0, 0.0);
    for w in series.filter(|w| w.len() > 30) {
        let e = centred(w);
        let m = e.len() as f64;
        let c0: f64 = e.iter().map(|x| x * x).sum::<f64>().max(1e-300);
        let mut f = 1.0;
        for lag in 1..=10 {
            let r: f64 = e.iter().zip(&e[lag..]).map(|(a, b)| a * b).sum::<f64>() / c0;
            q += m * (m + 2.0) * r * r / (m - lag as f64);
            k += 1.0;
            f += 2.0 * (1.0 - lag as f64 / 11.0) * r;
        }
        lr_sum += f * m;
        lr_w += m;
    }
    let factor = if lr_w > 0.0 {
        (lr_sum / lr_w).max(1.0)
    } else {
        1.0
    };
    (q, k, factor)
}

/// Run the tests; `n_fitted` unknowns were fitted to these residuals.
pub fn analyse(series: &[ResidualSeries], n_fitted: usize) -> ResidualReport {
    let n: usize = series.iter().map(|s| s.e.len()).sum();
    let white: Vec<Vec<f64>> = series.iter().map(|s| s.whitened(&s.e)).collect();
    let chi2: f64 = white.iter().flatten().map(|x| x * x).sum();
    let dof = (n as f64 - n_fitted as f64).max(1.0);
    // The level test is two-sided: residuals far below the stated level
    // are a finding too (the stated sigma is too large, or named effects
    // absorb noise), never "consistent with noise".
    let z_level = (chi2 - dof) / (2.0 * dof).sqrt();
    let mut tests = vec![Structure {
        test: "chi2".into(),
        description: if z_level < -Z_STRUCTURE {
            format!(
                "residual level far below the stated noise: chi-square {chi2:.1} on {dof:.0} \
                 degrees of freedom (the stated levels are too large, or the fit absorbs noise)"
            )
        } else {
            format!("residual level: chi-square {chi2:.1} on {dof:.0} degrees of freedom")
        },
        z: z_level,
        significant: z_level.abs() > Z_STRUCTURE,
    }];
    let mut push = |test: &str, description: String, z: f64| {
        tests.push(Structure {
            test: test.into(),
            description,
            z,
            significant: z > Z_STRUCTURE,
        });
    };
    let (q, k, correlation_factor) = serial_correlation(white.iter().map(Vec::as_slice));
    push(
        "whiteness",
        "autocorrelation at lags 1-10 (Ljung-Box)".into(),
        chi2_z(q, k),
    );
    // Regressor families, projected per series and pooled.
    type Family<'a> = Box<dyn Fn(&ResidualSeries) -> Vec<Vec<f64>> + 'a>;
    let duration = |s: &ResidualSeries| {
        (s.t.last().copied().unwrap_or(0.0) - s.t.first().copied().unwrap_or(0.0)).max(1e-9)
    };
    let mut families: Vec<(String, String, Family)> = vec![
        (
            "bias".into(),
            "a constant offset".into(),
            Box::new(|s: &ResidualSeries| vec![vec![1.0; s.e.len()]]),
        ),
        (
            "trend".into(),
            "a linear trend over time".into(),
            Box::new(|s: &ResidualSeries| vec![centred(&s.t)]),
        ),
        (
            "loop".into(),
            "periodic over the trajectory (one cycle per trajectory: the loop period of a circle)"
                .into(),
            Box::new(move |s: &ResidualSeries| {
                let w = std::f64::consts::TAU / duration(s);
                vec![
                    s.t.iter().map(|t| (w * t).sin()).collect(),
                    s.t.iter().map(|t| (w * t).cos()).collect(),
                ]
            }),
        ),
        (
            "lag".into(),
            "proportional to the rate of change of the prediction (a time lag)".into(),
            Box::new(|s: &ResidualSeries| {
                let n = s.t.len();
                let mut d = vec![0.0; n];
                for (i, di) in d.iter_mut().enumerate() {
                    let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                    if b > a {
                        let mut dy = s.predicted[b] - s.predicted[a];
                        if s.angular {
                            dy = obsan_data::wrap(dy);
                        }
                        *di = dy / (s.t[b] - s.t[a]).max(1e-12);
                    }
                }
                vec![d]
            }),
        ),
    ];
    if series.iter().any(|s| s.angular) {
        families.push((
            "angle".into(),
            "periodic in the predicted angle (first and second harmonics)".into(),
            Box::new(|s: &ResidualSeries| {
                if !s.angular {
                    return vec![];
                }
                let f = |g: fn(f64) -> f64, k: f64| s.predicted.iter().map(|y| g(k * y)).collect();
                vec![
                    f(f64::sin, 1.0),
                    f(f64::cos, 1.0),
                    f(f64::sin, 2.0),
                    f(f64::cos, 2.0),
                ]
            }),
        ));
    }
    if let Some(first) = series.first() {
        for (name, _) in &first.input_integrals {
            let nm = name.clone();
            families.push((
                format!("wheel:{name}"),
                format!("periodic in the integral of {name} (e.g. a wheel's rotation angle)"),
                Box::new(move |s: &ResidualSeries| {
                    let Some((_, a)) = s.input_integrals.iter().find(|x| x.0 == nm) else {
                        return vec![];
                    };
                    vec![
                        a.iter().map(|x| x.sin()).collect(),
                        a.iter().map(|x| x.cos()).collect(),
                    ]
                }),
            ));
        }
        families.push((
            "input".into(),
            format!(
                "correlated with the inputs ({})",
                first
                    .inputs
                    .iter()
                    .map(|i| i.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            Box::new(|s: &ResidualSeries| s.inputs.iter().map(|(_, v)| centred(v)).collect()),
        ));
    }
    for (id, desc, f) in &families {
        let (mut q, mut k) = (0.0, 0usize);
        for (s, w) in series.iter().zip(&white).filter(|(s, _)| s.e.len() > 5) {
            let cols: Vec<Vec<f64>> = f(s).iter().map(|c| s.whitened(c)).collect();
            let (qs, ks) = projection(w, &cols);
            q += qs;
            k += ks;
        }
        if k > 0 {
            push(id, desc.clone(), chi2_z(q, k as f64));
        }
    }
    ResidualReport {
        n,
        correlation_factor,
        chi2,
        dof,
        tests,
    }
}
