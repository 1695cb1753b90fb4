//! Correlations between the final fit's params: whether the named effects'
//! estimates are determined separately, or only in a combination.
//!
//! Two regressors that are nearly proportional on these data (MRCLAM's
//! `∫omega` and `∫omega |v|`: |v| sits at 0.06–0.08 m/s most of the time)
//! let the LR name both effects while the data fix only their combination;
//! each estimate alone is then an extrapolation. The correlation of the two
//! estimates in the fit's covariance says so.

use serde::Serialize;

/// A named effect's param is reported as correlated with another param when
/// `|r|` reaches this: `r^2 >= 0.81`, a variance inflation `1/(1 - r^2)` of
/// 5.3 or more (the lower of the usual VIF limits, 5 and 10): either sd is
/// at least 2.3 times what it would be were the other known. Measured
/// (docs/diagnose.md, "Correlated named effects"): MRCLAM's turn scale with
/// the turn rate's coupling with |v| -0.99, -0.94, -0.98 on robots 1-3 (the
/// VIF limit of 10, 0.95, would miss robot 2); its speed scale with v's
/// coupling with |omega| -0.79 to -0.86 (below); two named effects on
/// simulated data at most 0.22 unless nearly proportional by construction
/// (tests/correlated.rs -0.99; bearing scale and sin 2b within ±1.1 rad
/// -0.86 to -0.93).
pub const CORRELATION_CAUTION: f64 = 0.9;

/// One param's correlation with another in the final fit's covariance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Correlation {
    /// The named effect's param.
    pub param: String,
    /// The other param of the final model.
    pub with: String,
    /// The named effect that owns `with`; `None`: a param of the user's model.
    pub with_effect: Option<String>,
    /// The correlation coefficient of the two estimates.
    pub r: f64,
}

impl Correlation {
    /// `1 / (1 - r^2)`: how much the two estimates' variances exceed what
    /// either would have were the other known (infinite at |r| = 1).
    pub fn variance_inflation(&self) -> f64 {
        1.0 / (1.0 - self.r * self.r).max(0.0)
    }

    /// The caution for a correlation between two named effects, `this`
    /// owning `param` and `other` owning `with` (as printed: a generated
    /// effect marked `*`).
    pub fn caution_text(&self, this: &str, other: &str) -> String {
        format!(
            "{} ({this}) and {} ({other}) correlate at r = {:+.2} in the final fit: the data fix \
             a combination of the two, not each alone (variance inflation {:.0})",
            self.param,
            self.with,
            self.r,
            self.variance_inflation()
        )
    }
}

/// Two params fixed in combination: the best-determined combination
/// `params[0] + weight * params[1]` of their joint covariance, in the units
/// of `params[0]`.
///
/// The direction is the smallest-variance eigenvector of the pair's
/// covariance with each param in units of its own sd (the correlation
/// matrix, eigenvalues `1 ± |r|`): `(1, -sign r) / sqrt 2`, so `weight =
/// -sign(r) sd_0 / sd_1`, and the combination's variance is `2 sd_0^2 (1 -
/// |r|)`. In the params' raw units the eigenvector would depend on the
/// units chosen (a param in mm against one in m would always win); scaled
/// by their sds it does not. For nearly proportional regressors (`omega`
/// and `omega |v|` at a nearly constant `|v| = v0`) it is `kw + v0 c`: the
/// turn-rate scale at the typical speed, which either effect alone fits.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Combination {
    /// The two params and the effects that own them.
    pub params: [String; 2],
    pub effects: [String; 2],
    /// Their estimates and sds (the model's, inflated as the named
    /// estimates are).
    pub values: [f64; 2],
    pub sds: [f64; 2],
    /// Their correlation in the fit.
    pub r: f64,
    /// Their cluster-robust covariance (trajectories as clusters), cross
    /// term included; NaN where it could not be formed (under input noise,
    /// one trajectory).
    pub robust_covariance: [[f64; 2]; 2],
    pub weight: f64,
    pub estimate: f64,
    pub sd: f64,
    pub robust_sd: f64,
    /// `|estimate|` over the larger of `sd` and `robust_sd`.
    pub wald_z: f64,
    /// Each param alone: `|value|` over the larger of its sd and its
    /// robust sd.
    pub wald_z_alone: [f64; 2],
    /// Both effects are named (`false`: the two were suggested, not
    /// established, and fitted together only for this).
    pub named: bool,
    /// `wald_z` clears the critical value (the square root of the LR's,
    /// the larger of the two effects'): the data fix the combination.
    pub established: bool,
}

impl Combination {
    /// The combination of two params with estimates `values`, model sds
    /// `sds`, correlation `r` and robust covariance `robust`.
    pub fn new(
        params: [String; 2],
        effects: [String; 2],
        (values, sds, r): ([f64; 2], [f64; 2], f64),
        robust: [[f64; 2]; 2],
    ) -> Combination {
        let sign = if r < 0.0 { -1.0 } else { 1.0 };
        let weight = -sign * sds[0] / sds[1];
        let estimate = values[0] + weight * values[1];
        let sd = sds[0] * (2.0 * (1.0 - r.abs())).max(0.0).sqrt();
        let robust_sd = quadratic(&robust, weight).sqrt();
        let z = |v: f64, s: f64, rs: f64| {
            let s = if rs.is_finite() { s.max(rs) } else { s };
            if s > 0.0 {
                (v / s).abs()
            } else {
                0.0
            }
        };
        Combination {
            wald_z: z(estimate, sd, robust_sd),
            wald_z_alone: [
                z(values[0], sds[0], robust[0][0].sqrt()),
                z(values[1], sds[1], robust[1][1].sqrt()),
            ],
            params,
            effects,
            values,
            sds,
            r,
            robust_covariance: robust,
            weight,
            estimate,
            sd,
            robust_sd,
            named: true,
            established: false,
        }
    }

    /// `params[0] + weight * params[1]` at another weight (the other side
    /// of a comparison's direction), with its robust sd.
    pub fn at(&self, weight: f64) -> (f64, f64) {
        (
            self.values[0] + weight * self.values[1],
            quadratic(&self.robust_covariance, weight).sqrt(),
        )
    }

    /// The text: `kw + 8.3e-2 gc = -2.8e-2 ± 3.5e-3 [± 5.1e-3]`.
    pub fn text(&self) -> String {
        let robust = if self.robust_sd.is_finite() {
            format!(" [± {:.1e}]", self.robust_sd)
        } else {
            String::new()
        };
        format!(
            "{} {} {:.3e} {} = {:.4e} ± {:.1e}{robust} (in the units of {}; r = {:+.3})",
            self.params[0],
            if self.weight < 0.0 { "-" } else { "+" },
            self.weight.abs(),
            self.params[1],
            self.estimate,
            self.sd,
            self.params[0],
            self.r
        )
    }
}

/// `(1, w) V (1, w)^T` of a 2 x 2 covariance.
fn quadratic(v: &[[f64; 2]; 2], w: f64) -> f64 {
    v[0][0] + w * (v[0][1] + v[1][0]) + w * w * v[1][1]
}

/// The correlation of entries `i` and `j` of covariance `cov`; `None` when
/// either variance is not positive and finite (a singular fit's NaN).
pub fn correlation(cov: &[Vec<f64>], i: usize, j: usize) -> Option<f64> {
    let v = |a: usize, b: usize| cov.get(a).and_then(|row| row.get(b)).copied();
    let (vi, vj, c) = (v(i, i)?, v(j, j)?, v(i, j)?);
    let ok = |x: f64| x.is_finite() && x > 0.0;
    if !(ok(vi) && ok(vj) && c.is_finite()) {
        return None;
    }
    // Rounding may push a correlation of 1 just past it.
    Some((c / (vi.sqrt() * vj.sqrt())).clamp(-1.0, 1.0))
}

/// Each param of `of` against every other param of `names` (the fit's
/// params, indexed as `cov`'s first rows) with `|r| >= threshold`, in
/// `names` order; `owner` names the named effect of a param, if any.
pub fn correlated(
    names: &[String],
    cov: &[Vec<f64>],
    of: &[String],
    owner: &dyn Fn(&str) -> Option<String>,
    threshold: f64,
) -> Vec<Correlation> {
    let mut out = Vec::new();
    for p in of {
        let Some(i) = names.iter().position(|n| n == p) else {
            continue;
        };
        for (j, w) in names.iter().enumerate() {
            if j == i {
                continue;
            }
            if let Some(r) = correlation(cov, i, j).filter(|r| r.abs() >= threshold) {
                out.push(Correlation {
                    param: p.clone(),
                    with: w.clone(),
                    with_effect: owner(w),
                    r,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn s(v: &[&str]) -> Vec<String> {
        v.iter().map(|x| x.to_string()).collect()
    }

    #[test]
    fn correlation_of_a_two_by_two_covariance() {
        // sd 2 and 3, covariance -3: r = -3 / (2 * 3) = -1/2.
        let cov = vec![vec![4.0, -3.0], vec![-3.0, 9.0]];
        assert_eq!(correlation(&cov, 0, 1), Some(-0.5));
        assert_eq!(correlation(&cov, 1, 0), Some(-0.5));
        let c = Correlation {
            param: "a".into(),
            with: "b".into(),
            with_effect: None,
            r: -0.5,
        };
        // 1 / (1 - 1/4) = 4/3.
        assert!((c.variance_inflation() - 4.0 / 3.0).abs() < 1e-12);
        assert_eq!(
            c.caution_text("e1", "e2*"),
            "a (e1) and b (e2*) correlate at r = -0.50 in the final fit: the data fix a \
             combination of the two, not each alone (variance inflation 1)"
        );
    }

    #[test]
    fn correlated_pairs_of_a_three_by_three_covariance_above_the_threshold() {
        // sds 1, 2, 3; r01 = 1.2 / 2 = 0.6, r02 = 0, r12 = -4.2 / 6 = -0.7
        // (positive definite: det of the correlations 1 - 0.36 - 0.49 > 0).
        // A fourth row (an initial state) is not a param and never named.
        let cov = vec![
            vec![1.0, 1.2, 0.0, 0.5],
            vec![1.2, 4.0, -4.2, 0.5],
            vec![0.0, -4.2, 9.0, 0.5],
            vec![0.5, 0.5, 0.5, 1.0],
        ];
        let names = s(&["a", "b", "c"]);
        let owner = |p: &str| (p == "c").then(|| "effect_c".to_string());
        let got = correlated(&names, &cov, &s(&["b"]), &owner, 0.65);
        assert_eq!(got.len(), 1, "{got:?}");
        assert_eq!((got[0].param.as_str(), got[0].with.as_str()), ("b", "c"));
        assert_eq!(got[0].with_effect.as_deref(), Some("effect_c"));
        assert!((got[0].r + 0.7).abs() < 1e-12, "{}", got[0].r);
        // Below the threshold: both of b's pairs, a param of the model
        // (owner None) first.
        let all = correlated(&names, &cov, &s(&["b"]), &owner, 0.5);
        let r: Vec<(&str, Option<&str>, f64)> = all
            .iter()
            .map(|c| (c.with.as_str(), c.with_effect.as_deref(), c.r))
            .collect();
        assert_eq!(r.len(), 2);
        assert_eq!((r[0].0, r[0].1), ("a", None));
        assert!((r[0].2 - 0.6).abs() < 1e-12);
        // a and c are uncorrelated: nothing at any positive threshold.
        assert!(correlated(&names, &cov, &s(&["a"]), &owner, 0.65).is_empty());
    }

    #[test]
    fn the_combination_of_a_pair_by_hand() {
        // sds 2 and 3, r = -0.8: weight = -sign(r) 2/3 = +2/3; values 1 and
        // -1.2 give 1 - 0.8 = 0.2; model sd 2 sqrt(2 (1 - 0.8)) = 1.2649.
        // The robust covariance equal to the model's ([[4, -4.8], [-4.8,
        // 9]]): 4 + (2/3)(-9.6) + (4/9) 9 = 1.6, the same variance.
        let robust = [[4.0, -4.8], [-4.8, 9.0]];
        let c = Combination::new(
            ["a".into(), "b".into()],
            ["e1".into(), "e2".into()],
            ([1.0, -1.2], [2.0, 3.0], -0.8),
            robust,
        );
        assert!((c.weight - 2.0 / 3.0).abs() < 1e-15);
        assert!((c.estimate - 0.2).abs() < 1e-15);
        assert!((c.sd - 2.0 * 0.4f64.sqrt()).abs() < 1e-15);
        assert!((c.robust_sd - 1.6f64.sqrt()).abs() < 1e-15);
        assert!((c.wald_z - 0.2 / 1.6f64.sqrt()).abs() < 1e-12);
        let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() + (a[1] - b[1]).abs() < 1e-15;
        assert!(near(c.wald_z_alone, [0.5, 0.4]), "{:?}", c.wald_z_alone);
        // Along another direction: weight 0 is the first param alone.
        assert_eq!(c.at(0.0), (1.0, 2.0));
        // Positive r: the weight changes sign (the difference is fixed):
        // 1 - (2/3) 1.2 = 0.2.
        let d = Combination::new(
            ["a".into(), "b".into()],
            ["e1".into(), "e2".into()],
            ([1.0, 1.2], [2.0, 3.0], 0.8),
            [[f64::NAN; 2]; 2],
        );
        assert!((d.weight + 2.0 / 3.0).abs() < 1e-15);
        assert!((d.estimate - 0.2).abs() < 1e-15 && d.robust_sd.is_nan());
        // No robust sd: the model's alone in the Wald z.
        assert!(near(d.wald_z_alone, [0.5, 0.4]), "{:?}", d.wald_z_alone);
        assert!(d.text().starts_with("a - 6.667e-1 b = "), "{}", d.text());
    }

    #[test]
    fn a_singular_fit_has_no_correlations() {
        let nan = vec![vec![f64::NAN; 2]; 2];
        assert_eq!(correlation(&nan, 0, 1), None);
        let zero = vec![vec![0.0, 0.0], vec![0.0, 1.0]];
        assert_eq!(correlation(&zero, 0, 1), None);
        assert_eq!(correlation(&zero, 0, 5), None);
        let names = s(&["a", "b"]);
        assert!(correlated(&names, &nan, &s(&["a", "missing"]), &|_| None, 0.0).is_empty());
    }
}
