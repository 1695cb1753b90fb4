//! Dense linear algebra and univariate polynomials over F_p.
//!
//! Univariate polynomials are coefficient vectors, lowest degree first,
//! without trailing zeros (the zero polynomial is empty).

use crate::field::{add, inv, mul, sub};

/// Solves the square system `a x = b` (rows of `a` with `b` appended as the
/// last column). `None` when the matrix is singular.
pub(crate) fn solve(mut a: Vec<Vec<u64>>, p: u64) -> Option<Vec<u64>> {
    let n = a.len();
    for col in 0..n {
        let piv = (col..n).find(|&r| a[r][col] != 0)?;
        a.swap(col, piv);
        let ip = inv(a[col][col], p)?;
        for v in a[col].iter_mut().skip(col) {
            *v = mul(*v, ip, p);
        }
        for r in 0..n {
            if r != col && a[r][col] != 0 {
                let f = a[r][col];
                let (pivot_row, row) = if r < col {
                    let (lo, hi) = a.split_at_mut(col);
                    (&hi[0], &mut lo[r])
                } else {
                    let (lo, hi) = a.split_at_mut(r);
                    (&lo[col], &mut hi[0])
                };
                for k in col..=n {
                    row[k] = sub(row[k], mul(f, pivot_row[k], p), p);
                }
            }
        }
    }
    Some(a.into_iter().map(|row| row[n]).collect())
}

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

/// Solves the possibly overdetermined system `a x = b` (rows of `a`, `cols`
/// unknowns, with `b` appended as the last column): `None` unless it has
/// exactly one solution (full column rank, every extra row consistent).
pub(crate) fn solve_over(mut a: Vec<Vec<u64>>, cols: usize, p: u64) -> Option<Vec<u64>> {
    let m = a.len();
    for col in 0..cols {
        let piv = (col..m).find(|&r| a[r][col] != 0)?;
        a.swap(col, piv);
        let ip = inv(a[col][col], p)?;
        for v in a[col].iter_mut().skip(col) {
            *v = mul(*v, ip, p);
        }
        let (lo, hi) = a.split_at_mut(col);
        let (pivot_row, hi) = hi.split_at_mut(1);
        let pivot_row = &pivot_row[0];
        for row in lo.iter_mut().chain(hi.iter_mut()) {
            let f = row[col];
            if f != 0 {
                for k in col..=cols {
                    row[k] = sub(row[k], mul(f, pivot_row[k], p), p);
                }
            }
        }
    }
    if a[cols..].iter().any(|row| row[cols] != 0) {
        return None;
    }
    Some(a.iter().take(cols).map(|row| row[cols]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;
    use crate::rng::Rng;

    const P: u64 = PRIMES[3];

    /// A random solution x and `m` augmented rows `[a | a.x]` in `n` unknowns.
    fn random_system(rng: &mut Rng, m: usize, n: usize) -> (Vec<u64>, Vec<Vec<u64>>) {
        let x: Vec<u64> = (0..n).map(|_| rng.nonzero(P)).collect();
        let rows = (0..m)
            .map(|_| {
                let mut r: Vec<u64> = (0..n).map(|_| rng.nonzero(P)).collect();
                let b = r
                    .iter()
                    .zip(&x)
                    .fold(0, |s, (&a, &xi)| add(s, mul(a, xi, P), P));
                r.push(b);
                r
            })
            .collect();
        (x, rows)
    }

    #[test]
    fn gauss_solves_a_random_system() {
        let mut rng = Rng::new(1);
        let n = 7;
        let (x, rows) = random_system(&mut rng, n, n);
        assert_eq!(solve(rows, P).unwrap(), x);
        // Two equal rows: singular.
        let row = vec![1, 2, 3];
        assert_eq!(solve(vec![row.clone(), row], P), None);
    }

    #[test]
    fn overdetermined_systems_need_consistency_and_full_rank() {
        let mut rng = Rng::new(2);
        let (m, n) = (9, 5);
        let (x, mut rows) = random_system(&mut rng, m, n);
        assert_eq!(solve_over(rows.clone(), n, P).unwrap(), x);
        // One right-hand side off: no solution.
        rows[7][n] = add(rows[7][n], 1, P);
        assert_eq!(solve_over(rows.clone(), n, P), None);
        // Fewer independent rows than unknowns: not determined.
        let few: Vec<Vec<u64>> = (0..m).map(|_| rows[0].clone()).collect();
        assert_eq!(solve_over(few, n, P), None);
    }

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
