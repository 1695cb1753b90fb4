//! The few distribution functions the tests need, with their accuracy stated.
//!
//! Kept here rather than taken from `statrs`: the naming decisions need the
//! normal tail and the chi-square critical values only to the accuracy each
//! function states (erfc's fractional error is below 1.2e-7 over the whole
//! range, so a far-tail p-value such as 1e-180 keeps its exponent), and these
//! five functions would otherwise bring in a statistics crate and its
//! dependency tree for about 80 lines. Each is tested against tabulated values
//! in this module.

/// Complementary error function, |error| < 1.2e-7 (Numerical Recipes' Chebyshev fit).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Two-sided p-value of a standard normal z.
pub fn normal_two_sided(z: f64) -> f64 {
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// The z with two-sided p-value `alpha` (bisection on [`erfc`]; 1e-10 in z).
pub fn normal_critical(alpha: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 40.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if normal_two_sided(mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A chi-square statistic with `k` degrees of freedom as an approximate
/// standard normal z (Wilson–Hilferty; good to ~0.01 in z for k >= 3).
pub fn chi2_z(q: f64, k: f64) -> f64 {
    if k <= 0.0 {
        return 0.0;
    }
    // Exact tails for 1 and 2 degrees of freedom, then the one-sided z.
    let exact = if k == 1.0 {
        Some(chi2_1_p(q))
    } else if k == 2.0 {
        Some((-q.max(0.0) / 2.0).exp())
    } else {
        None
    };
    if let Some(p) = exact {
        return if p >= 0.5 {
            0.0
        } else {
            normal_critical(2.0 * p)
        };
    }
    let a = 2.0 / (9.0 * k);
    ((q / k).max(0.0).cbrt() - (1.0 - a)) / a.sqrt()
}

/// The upper `alpha` point of chi-square with `k` degrees of freedom
/// (bisection on [`chi2_z`]'s one-sided tail: exact for k = 1, 2,
/// Wilson–Hilferty above).
pub fn chi2_critical(alpha: f64, k: f64) -> f64 {
    let z = normal_critical(2.0 * alpha);
    let (mut lo, mut hi) = (0.0, 10.0 * k + 1000.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if chi2_z(mid, k) < z {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Upper-tail p-value of chi-square with 1 degree of freedom.
pub fn chi2_1_p(q: f64) -> f64 {
    normal_two_sided(q.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn known_values() {
        // Tabulated: erfc(1) = 0.157299207, 1.959964 is the 5% two-sided z.
        assert!((erfc(1.0) - 0.157_299_207).abs() < 2e-7);
        // The far tail keeps its relative accuracy: erfc(10) = 2.0884875837625e-45.
        assert!((erfc(10.0) / 2.088_487_583_762_5e-45 - 1.0).abs() < 1.2e-7);
        assert!((normal_critical(0.05) - 1.959_964).abs() < 1e-5);
        // chi2_1 upper 0.1% point is 10.8276.
        assert!((chi2_1_p(10.8276) - 1e-3).abs() < 1e-6);
        // Wilson-Hilferty: the chi2_10 upper 5% point 18.307 is z ~ 1.645.
        assert!((chi2_z(18.307, 10.0) - 1.645).abs() < 0.02);
        // Tabulated upper points: chi2_1 1% 6.635, chi2_2 1% 9.210,
        // chi2_10 5% 18.307, chi2_30 1% 50.892.
        assert!((chi2_critical(0.01, 1.0) - 6.635).abs() < 1e-3);
        assert!((chi2_critical(0.01, 2.0) - 9.210).abs() < 1e-3);
        assert!((chi2_critical(0.05, 10.0) - 18.307).abs() < 0.05);
        assert!((chi2_critical(0.01, 30.0) - 50.892).abs() < 0.1);
    }
}
