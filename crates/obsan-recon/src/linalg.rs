//! Univariate polynomials and Vandermonde systems over F_p (the dense
//! elimination is `echelon.rs`).
//!
//! Univariate polynomials are coefficient vectors, lowest degree first,
//! without trailing zeros (the zero polynomial is empty).

use crate::field::{add, inv, mul, sub};

/// Solves the transposed Vandermonde system `sum_m c_m v_m^i = y_i`,
/// `i = 0..T`, in O(T^2) (Zippel 1990): with `P = prod (x - v_m)` and
/// `Q_m = P / (x - v_m)`, `c_m = (sum_i [x^i]Q_m y_i) / Q_m(v_m)`.
/// `None` when two `v_m` coincide.
pub(crate) fn vandermonde_t(v: &[u64], y: &[u64], p: u64) -> Option<Vec<u64>> {
    let t = v.len();
    debug_assert!(y.len() >= t);
    // Master polynomial, lowest degree first, degree t (monic).
    let mut master = vec![1u64];
    for &vm in v {
        let mut next = vec![0u64; master.len() + 1];
        for (i, &c) in master.iter().enumerate() {
            next[i + 1] = add(next[i + 1], c, p);
            next[i] = sub(next[i], mul(c, vm, p), p);
        }
        master = next;
    }
    let mut out = Vec::with_capacity(t);
    let mut q = vec![0u64; t];
    for &vm in v {
        // Synthetic division of master by (x - vm): q has degree t-1.
        let mut carry = 0u64;
        for i in (0..t).rev() {
            carry = add(master[i + 1], mul(carry, vm, p), p);
            q[i] = carry;
        }
        let mut num = 0u64;
        let mut den = 0u64;
        let mut pw = 1u64;
        for i in 0..t {
            num = add(num, mul(q[i], y[i], p), p);
            den = add(den, mul(q[i], pw, p), p);
            pw = mul(pw, vm, p);
        }
        out.push(mul(num, inv(den, p)?, p));
    }
    Some(out)
}

/// Newton interpolation: the polynomial of degree < `xs.len()` through the
/// points, as monomial coefficients. `None` when two abscissae coincide.
pub(crate) fn newton(xs: &[u64], ys: &[u64], p: u64) -> Option<Vec<u64>> {
    let n = xs.len();
    let mut dd = ys.to_vec();
    for j in 1..n {
        for i in (j..n).rev() {
            let d = inv(sub(xs[i], xs[i - j], p), p)?;
            dd[i] = mul(sub(dd[i], dd[i - 1], p), d, p);
        }
    }
    // Horner on the Newton form: c = dd[n-1]; c = c*(x - x_i) + dd[i].
    let mut c: Vec<u64> = Vec::with_capacity(n);
    for i in (0..n).rev() {
        // c <- c * (x - xs[i]) + dd[i]
        let mut next = vec![0u64; c.len() + 1];
        for (k, &ck) in c.iter().enumerate() {
            next[k + 1] = add(next[k + 1], ck, p);
            next[k] = sub(next[k], mul(ck, xs[i], p), p);
        }
        next[0] = add(next[0], dd[i], p);
        c = next;
    }
    c.truncate(n);
    Some(trim(c))
}

pub(crate) fn trim(mut a: Vec<u64>) -> Vec<u64> {
    while a.last() == Some(&0) {
        a.pop();
    }
    a
}

pub(crate) fn eval(a: &[u64], x: u64, p: u64) -> u64 {
    a.iter().rev().fold(0, |acc, &c| add(mul(acc, x, p), c, p))
}

pub(crate) fn poly_mul(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    if a.is_empty() || b.is_empty() {
        return Vec::new();
    }
    let mut out = vec![0u64; a.len() + b.len() - 1];
    for (i, &x) in a.iter().enumerate() {
        if x == 0 {
            continue;
        }
        for (j, &y) in b.iter().enumerate() {
            out[i + j] = add(out[i + j], mul(x, y, p), p);
        }
    }
    trim(out)
}

pub(crate) fn poly_add(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let mut out = vec![0u64; a.len().max(b.len())];
    for (i, o) in out.iter_mut().enumerate() {
        *o = add(
            a.get(i).copied().unwrap_or(0),
            b.get(i).copied().unwrap_or(0),
            p,
        );
    }
    trim(out)
}

/// Division with remainder; `b` must be non-zero.
pub(crate) fn poly_divrem(a: &[u64], b: &[u64], p: u64) -> Option<(Vec<u64>, Vec<u64>)> {
    let lb = *b.last()?;
    let il = inv(lb, p)?;
    let mut r = a.to_vec();
    if r.len() < b.len() {
        return Some((Vec::new(), trim(r)));
    }
    let mut q = vec![0u64; r.len() - b.len() + 1];
    for k in (0..q.len()).rev() {
        let c = mul(r[k + b.len() - 1], il, p);
        q[k] = c;
        if c != 0 {
            for (j, &bj) in b.iter().enumerate() {
                r[k + j] = sub(r[k + j], mul(c, bj, p), p);
            }
        }
    }
    r.truncate(b.len() - 1);
    Some((trim(q), trim(r)))
}

/// Monic gcd (Euclid); gcd(0, 0) = 0.
pub(crate) fn poly_gcd(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let (mut a, mut b) = (trim(a.to_vec()), trim(b.to_vec()));
    while !b.is_empty() {
        let Some((_, r)) = poly_divrem(&a, &b, p) else {
            break;
        };
        a = b;
        b = r;
    }
    match a.last().copied().and_then(|l| inv(l, p)) {
        Some(il) => a.iter().map(|&c| mul(c, il, p)).collect(),
        None => a,
    }
}

pub(crate) fn poly_scale(a: &[u64], s: u64, p: u64) -> Vec<u64> {
    trim(a.iter().map(|&c| mul(c, s, p)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;
    use crate::rng::Rng;

    const P: u64 = PRIMES[3];

    #[test]
    fn vandermonde_and_newton_recover_known_coefficients() {
        let mut rng = Rng::new(2);
        let c: Vec<u64> = (0..9).map(|_| rng.nonzero(P)).collect();
        let v: Vec<u64> = (0..9).map(|_| rng.nonzero(P)).collect();
        let y: Vec<u64> = (0..9u64)
            .map(|i| {
                c.iter().zip(&v).fold(0, |s, (&cm, &vm)| {
                    add(s, mul(cm, crate::field::pow(vm, i, P), P), P)
                })
            })
            .collect();
        assert_eq!(vandermonde_t(&v, &y, P).unwrap(), c);
        let xs: Vec<u64> = (0..9).map(|_| rng.nonzero(P)).collect();
        let ys: Vec<u64> = xs.iter().map(|&x| eval(&c, x, P)).collect();
        assert_eq!(newton(&xs, &ys, P).unwrap(), c);
    }

    #[test]
    fn gcd_finds_a_planted_common_factor() {
        let g = vec![5, 0, 1]; // x^2 + 5
        let a = poly_mul(&g, &[3, 1], P);
        let b = poly_mul(&g, &[P - 2, 7, 1], P);
        assert_eq!(poly_gcd(&a, &b, P), g);
        let (q, r) = poly_divrem(&a, &g, P).unwrap();
        assert_eq!(q, vec![3, 1]);
        assert!(r.is_empty());
    }
}
