//! Dense f64 linear algebra for observability along data: a one-sided Jacobi
//! SVD (accurate small singular values, which is what a numerical rank
//! needs: forming `A^T A` would square the condition number) and the
//! rationalisation of recorded numbers.

use obsan_expr::Q;

/// Sweeps of the Jacobi SVD before giving up (each sweep is O(m n^2); the
/// method converges quadratically, ten sweeps are typical).
const MAX_SWEEPS: usize = 100;

/// Singular values (descending) and right singular vectors (`v[k]` belongs to
/// `s[k]`) of the `rows x n` matrix `a` (row-major). Hestenes' one-sided
/// Jacobi: rotate column pairs of A until they are orthogonal; the column
/// norms are the singular values, the accumulated rotations V.
pub fn svd(a: &[Vec<f64>], n: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut cols: Vec<Vec<f64>> = (0..n).map(|j| a.iter().map(|r| r[j]).collect()).collect();
    let mut v: Vec<Vec<f64>> = (0..n)
        .map(|j| (0..n).map(|i| f64::from(u8::from(i == j))).collect())
        .collect();
    for _ in 0..MAX_SWEEPS {
        let mut rotated = false;
        for p in 0..n {
            for q in p + 1..n {
                let alpha: f64 = cols[p].iter().map(|x| x * x).sum();
                let beta: f64 = cols[q].iter().map(|x| x * x).sum();
                let gamma: f64 = cols[p].iter().zip(&cols[q]).map(|(x, y)| x * y).sum();
                if gamma == 0.0 || gamma.abs() <= 1e-15 * (alpha * beta).sqrt() {
                    continue;
                }
                rotated = true;
                let zeta = (beta - alpha) / (2.0 * gamma);
                let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                let t = if zeta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                rotate(&mut cols, p, q, c, s);
                rotate(&mut v, p, q, c, s);
            }
        }
        if !rotated {
            break;
        }
    }
    let mut order: Vec<(f64, usize)> = cols
        .iter()
        .enumerate()
        .map(|(j, c)| (c.iter().map(|x| x * x).sum::<f64>().sqrt(), j))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0));
    let s = order.iter().map(|o| o.0).collect();
    let vs = order.iter().map(|o| v[o.1].clone()).collect();
    (s, vs)
}

fn rotate(m: &mut [Vec<f64>], p: usize, q: usize, c: f64, s: f64) {
    let (lo, hi) = m.split_at_mut(q);
    for (x, y) in lo[p].iter_mut().zip(hi[0].iter_mut()) {
        let (a, b) = (*x, *y);
        *x = c * a - s * b;
        *y = s * a + c * b;
    }
}

/// Largest principal angle (radians) between span(`a`) and span(`b`), each
/// given by orthonormal vectors, when dim a <= dim b: the angle of the
/// worst-approximated direction of `a`, `acos(sigma_min(B^T A))`.
pub fn max_principal_angle(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    if b.is_empty() {
        return std::f64::consts::FRAC_PI_2;
    }
    let m: Vec<Vec<f64>> = a
        .iter()
        .map(|x| b.iter().map(|y| dot(x, y)).collect())
        .collect();
    let (s, _) = svd(&m, b.len());
    // The singular values of the |a| x |b| matrix are its row space's: with
    // |a| <= |b| the smallest of the first |a| is sigma_min.
    let smin = s.get(a.len() - 1).copied().unwrap_or(0.0);
    smin.clamp(-1.0, 1.0).acos()
}

/// Orthonormal basis of span(`vs`) (modified Gram-Schmidt, twice), dropping
/// vectors whose remainder is below `rel` of their norm.
pub fn orthonormal(vs: &[Vec<f64>], rel: f64) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for v in vs {
        let norm0 = dot(v, v).sqrt();
        let mut w = v.clone();
        for _ in 0..2 {
            for u in &out {
                let c = dot(&w, u);
                for (x, y) in w.iter_mut().zip(u) {
                    *x -= c * y;
                }
            }
        }
        let norm = dot(&w, &w).sqrt();
        if norm0 > 0.0 && norm > rel * norm0 {
            out.push(w.iter().map(|x| x / norm).collect());
        }
    }
    out
}

pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The simplest rational within `tol` of `x` (continued fractions), when
/// its denominator stays below 10^12: recorded inputs are decimal text, so
/// their exact relations have such rationals.
pub fn rationalise(x: f64, tol: f64) -> Option<Q> {
    if !x.is_finite() {
        return None;
    }
    let (mut h0, mut h1, mut k0, mut k1) = (0i128, 1i128, 1i128, 0i128);
    let mut r = x;
    for _ in 0..64 {
        let a = r.floor();
        if a.abs() > 1e15 {
            return None;
        }
        let a = a as i128;
        let (h2, k2) = (a * h1 + h0, a * k1 + k0);
        (h0, h1, k0, k1) = (h1, h2, k1, k2);
        if k1 > 1_000_000_000_000 {
            return None;
        }
        if (h1 as f64 / k1 as f64 - x).abs() <= tol {
            let num = i64::try_from(h1).ok()?;
            let den = i64::try_from(k1).ok()?;
            return Q::from_i64(num).div(&Q::from_i64(den));
        }
        let frac = r - r.floor();
        if frac == 0.0 {
            return None;
        }
        r = 1.0 / frac;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn svd_of_a_rank_one_matrix() {
        // [[1, 2], [2, 4]] = (1,2)^T (1,2): singular values 5 and 0, the
        // kernel (2, -1)/sqrt(5).
        let (s, v) = svd(&[vec![1.0, 2.0], vec![2.0, 4.0]], 2);
        assert!((s[0] - 5.0).abs() < 1e-12 && s[1].abs() < 1e-12);
        let k = &v[1];
        assert!((k[0] * 1.0 + k[1] * 2.0).abs() < 1e-12);
    }

    #[test]
    fn rationals_of_decimals() {
        assert_eq!(
            rationalise(0.9, 1e-12),
            Q::from_i64(9).div(&Q::from_i64(10))
        );
        assert_eq!(
            rationalise(-0.1512, 1e-12),
            Q::from_i64(-189).div(&Q::from_i64(1250))
        );
    }

    #[test]
    fn angle_between_planes() {
        let a = vec![vec![1.0, 0.0, 0.0]];
        let b = vec![vec![0.0, 1.0, 0.0], vec![0.0, 0.0, 1.0]];
        assert!((max_principal_angle(&a, &b) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let c = vec![vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]];
        assert!(max_principal_angle(&a, &c) < 1e-12);
    }
}
