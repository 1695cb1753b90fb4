//! Whitening of residuals whose errors are correlated by integrated input
//! noise, in O(n r^2) instead of a dense O(n^3) Cholesky factorisation.
//!
//! Linearised, the error of residual `i` (normalised by its output noise) is
//! `e_i = v_i + a_i^T w(t_i)`: `v_i` white with unit variance, `a_i` the
//! residual's sensitivity to the initial dynamic state (r entries) and
//! `w(t)` the input noise integrated up to `t` and mapped back to the
//! initial time, a random walk with `Cov w(t) = M(t)`
//! ([`crate::Integration::input_noise`]). So `Cov e = I + A M(min(t_i, t_j)) A^T`:
//! a semiseparable matrix, the covariance of a linear state-space model
//! with state `w`, identity transition and process noise `M(t_i) - M(t_{i-1})`.
//! The Kalman filter's normalised innovations of that model are exactly
//! `L^-1 e` for the lower Cholesky factor `L` of the covariance (innovations
//! form), and its gains do not depend on the data, so they are computed once
//! and applied to any vector (residuals, Jacobian columns) in O(n r).

use nalgebra::DMatrix;

/// The Cholesky factor of `I + A M(min(t_i, t_j)) A^T`, held as the gains of
/// the equivalent Kalman filter.
#[derive(Clone, Debug)]
pub struct Whitener {
    r: usize,
    /// Per residual: `a_i` (r entries).
    a: Vec<f64>,
    /// Per residual: `M(t_i)` (r x r, row-major); kept so that a subset of
    /// the residuals can be whitened on its own.
    m: Vec<f64>,
    /// Per residual: the gain `K_i = P_i a_i / S_i` (r entries).
    gain: Vec<f64>,
    /// Per residual: `sqrt(S_i)`, the square root of the innovation variance
    /// (the diagonal of `L`).
    sd: Vec<f64>,
}

impl Whitener {
    /// From each residual's `a_i` and `M(t_i)` (times non-decreasing, so
    /// `M(t_i) - M(t_{i-1})` is positive semi-definite). `None` when the
    /// increments are not positive semi-definite beyond rounding, or the
    /// sizes do not match.
    pub fn new(r: usize, a: Vec<f64>, m: Vec<f64>) -> Option<Whitener> {
        let n = a.len().checked_div(r).unwrap_or(0);
        if a.len() != n * r || m.len() != n * r * r {
            return None;
        }
        let mut b = WhitenerBuilder::new(r, n, true);
        for i in 0..n {
            b.push(&a[i * r..(i + 1) * r], &m[i * r * r..(i + 1) * r * r])?;
        }
        b.finish()
    }

    /// Residual `i`'s `a_i`, gain `K_i` and `sqrt(S_i)` (for [`RowFilter`]).
    pub(crate) fn step(&self, i: usize) -> (&[f64], &[f64], f64) {
        let r = self.r;
        (
            &self.a[i * r..(i + 1) * r],
            &self.gain[i * r..(i + 1) * r],
            self.sd[i],
        )
    }

    /// Number of residuals.
    pub fn len(&self) -> usize {
        self.sd.len()
    }

    pub fn is_empty(&self) -> bool {
        self.sd.is_empty()
    }

    /// `log det` of the covariance (twice the log of `L`'s diagonal).
    pub fn log_det(&self) -> f64 {
        self.sd.iter().map(|s| 2.0 * s.ln()).sum()
    }

    /// `L^-1 v` in place.
    pub fn whiten_in_place(&self, v: &mut [f64]) {
        debug_assert_eq!(v.len(), self.len());
        let r = self.r;
        // The filtered state estimate.
        let mut w = vec![0.0; r];
        for (i, vi) in v.iter_mut().enumerate() {
            let ai = &self.a[i * r..(i + 1) * r];
            let e = *vi - ai.iter().zip(w.iter()).map(|(x, y)| x * y).sum::<f64>();
            for (wx, g) in w.iter_mut().zip(&self.gain[i * r..(i + 1) * r]) {
                *wx += g * e;
            }
            *vi = e / self.sd[i];
        }
    }

    /// `L^-1 v`.
    pub fn whiten(&self, v: &[f64]) -> Vec<f64> {
        let mut out = v.to_vec();
        self.whiten_in_place(&mut out);
        out
    }

    /// The whitener of the residuals `idx` alone (increasing indices).
    pub fn subset(&self, idx: &[usize]) -> Option<Whitener> {
        let r = self.r;
        let mut a = Vec::with_capacity(idx.len() * r);
        let mut m = Vec::with_capacity(idx.len() * r * r);
        for &i in idx {
            a.extend_from_slice(self.a.get(i * r..(i + 1) * r)?);
            m.extend_from_slice(self.m.get(i * r * r..(i + 1) * r * r)?);
        }
        Whitener::new(r, a, m)
    }

    /// The covariance `I + A M(min(t_i, t_j)) A^T` as a dense matrix (for
    /// tests and small problems).
    pub fn covariance(&self) -> DMatrix<f64> {
        let (n, r) = (self.len(), self.r);
        DMatrix::from_fn(n, n, |i, j| {
            let lo = i.min(j);
            let mm = &self.m[lo * r * r..(lo + 1) * r * r];
            let (ai, aj) = (&self.a[i * r..(i + 1) * r], &self.a[j * r..(j + 1) * r]);
            let mut s = if i == j { 1.0 } else { 0.0 };
            for x in 0..r {
                for y in 0..r {
                    s += ai[x] * mm[x * r + y] * aj[y];
                }
            }
            s
        })
    }
}

/// [`Whitener::new`] one residual at a time, in time order: the filter's
/// gains are a forward recursion, so a prediction can be whitened while it
/// is produced, without its rows being stored first.
pub(crate) struct WhitenerBuilder {
    r: usize,
    /// The filter's error covariance `P` before the current residual.
    p: Vec<f64>,
    prev: Vec<f64>,
    pa: Vec<f64>,
    /// The last residual's `a_i` and gain (r entries each).
    a: Vec<f64>,
    gain: Vec<f64>,
    /// The whitener built, when it is kept (a bound on the Fisher
    /// information needs only each residual's gain as it passes).
    w: Option<Whitener>,
}

impl WhitenerBuilder {
    /// For `n` residuals (the capacity; more may be pushed); `keep`: build
    /// the whitener ([`WhitenerBuilder::finish`]), not only its gains.
    pub(crate) fn new(r: usize, n: usize, keep: bool) -> WhitenerBuilder {
        WhitenerBuilder {
            r,
            p: vec![0.0; r * r],
            prev: vec![0.0; r * r],
            pa: vec![0.0; r],
            a: vec![0.0; r],
            gain: vec![0.0; r],
            w: keep.then(|| Whitener {
                r,
                a: Vec::with_capacity(n * r),
                m: Vec::with_capacity(n * r * r),
                gain: Vec::with_capacity(n * r),
                sd: Vec::with_capacity(n),
            }),
        }
    }

    /// The next residual's `a_i` (r entries) and `M(t_i)` (r x r); its
    /// `a_i`, gain and `sqrt(S_i)`, or `None` (and the builder is spent)
    /// when the increment `M(t_i) - M(t_{i-1})` is not positive
    /// semi-definite.
    pub(crate) fn push(&mut self, ai: &[f64], mi: &[f64]) -> Option<(&[f64], &[f64], f64)> {
        let r = self.r;
        if ai.len() != r || mi.len() != r * r {
            return None;
        }
        let (p, pa) = (&mut self.p, &mut self.pa);
        for k in 0..r * r {
            p[k] += mi[k] - self.prev[k];
        }
        self.prev.copy_from_slice(mi);
        for (x, pa_x) in pa.iter_mut().enumerate() {
            *pa_x = (0..r).map(|y| p[x * r + y] * ai[y]).sum();
        }
        let s = 1.0 + ai.iter().zip(pa.iter()).map(|(x, y)| x * y).sum::<f64>();
        // S >= 1 for a positive semi-definite P; well below means the
        // increments were not.
        if !s.is_finite() || s < 1.0 - 1e-9 {
            return None;
        }
        let s = s.max(1.0);
        for x in 0..r {
            self.gain[x] = pa[x] / s;
            for y in 0..r {
                p[x * r + y] -= pa[x] * pa[y] / s;
            }
        }
        self.a.copy_from_slice(ai);
        let sd = s.sqrt();
        if let Some(w) = self.w.as_mut() {
            w.gain.extend_from_slice(&self.gain);
            w.sd.push(sd);
            w.a.extend_from_slice(ai);
            w.m.extend_from_slice(mi);
        }
        Some((&self.a, &self.gain, sd))
    }

    /// The whitener, when kept.
    pub(crate) fn finish(self) -> Option<Whitener> {
        self.w
    }
}

/// `L^-1` applied to several vectors at once, one residual (row) at a time:
/// the Kalman filter of [`Whitener::whiten_in_place`] with one state per
/// column, so a row of residual and Jacobian entries is whitened as soon as
/// it is known, with the same arithmetic as column by column.
pub(crate) struct RowFilter {
    r: usize,
    /// Per column, the filtered state estimate (r entries).
    w: Vec<f64>,
}

impl RowFilter {
    /// For rows of `width` entries and a whitener of `r` states.
    pub(crate) fn new(r: usize, width: usize) -> RowFilter {
        RowFilter {
            r,
            w: vec![0.0; r * width],
        }
    }

    /// Whiten the next row in place, given its residual's `a_i`, gain and
    /// `sqrt(S_i)` ([`Whitener::step`]).
    pub(crate) fn apply(&mut self, ai: &[f64], gain: &[f64], sd: f64, row: &mut [f64]) {
        for (v, w) in row.iter_mut().zip(self.w.chunks_exact_mut(self.r.max(1))) {
            let e = *v - ai.iter().zip(w.iter()).map(|(x, y)| x * y).sum::<f64>();
            for (wx, g) in w.iter_mut().zip(gain) {
                *wx += g * e;
            }
            *v = e / sd;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random walk increments D_i = B_i B_i^T, so M is non-decreasing.
    fn example(n: usize, r: usize, seed: u64) -> Whitener {
        let mut rng = crate::Rng::new(seed);
        let mut a = Vec::new();
        let mut m = Vec::new();
        let mut acc = vec![0.0; r * r];
        for _ in 0..n {
            for _ in 0..r {
                a.push(rng.normal() * 3.0);
            }
            let b: Vec<f64> = (0..r * r).map(|_| rng.normal() * 0.2).collect();
            for x in 0..r {
                for y in 0..r {
                    acc[x * r + y] += (0..r).map(|k| b[x * r + k] * b[y * r + k]).sum::<f64>();
                }
            }
            m.extend_from_slice(&acc);
        }
        Whitener::new(r, a, m).expect("positive semi-definite increments")
    }

    #[test]
    fn innovations_equal_the_dense_cholesky_solve() {
        for (n, r, seed) in [(1, 1, 1), (30, 2, 2), (57, 3, 3), (12, 9, 4)] {
            let w = example(n, r, seed);
            let l = w.covariance().cholesky().expect("SPD").l();
            let mut rng = crate::Rng::new(seed + 100);
            let v: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
            let dense = l
                .solve_lower_triangular(&nalgebra::DVector::from_column_slice(&v))
                .expect("nonsingular");
            let fast = w.whiten(&v);
            for (x, y) in dense.iter().zip(&fast) {
                assert!((x - y).abs() <= 1e-9 * (1.0 + x.abs()), "{x} vs {y}");
            }
        }
    }

    #[test]
    fn log_det_is_the_dense_determinants() {
        for (n, r, seed) in [(1, 1, 1), (30, 2, 2), (57, 3, 3)] {
            let w = example(n, r, seed);
            let dense = w.covariance().determinant().ln();
            assert!((w.log_det() - dense).abs() < 1e-9 * (1.0 + dense.abs()));
        }
    }

    #[test]
    fn subset_is_the_whitener_of_the_sub_covariance() {
        let w = example(40, 2, 7);
        let idx: Vec<usize> = (0..40).filter(|i| i % 3 != 1).collect();
        let s = w.subset(&idx).expect("subset");
        let c = w.covariance();
        let sub = DMatrix::from_fn(idx.len(), idx.len(), |a, b| c[(idx[a], idx[b])]);
        let diff = (s.covariance() - sub).abs().max();
        assert!(diff < 1e-12, "{diff}");
    }

    #[test]
    fn decreasing_noise_is_refused() {
        // M(t_1) < M(t_0): no random walk has this covariance.
        assert!(Whitener::new(1, vec![1.0, 1.0], vec![2.0, 0.5]).is_none());
    }
}
