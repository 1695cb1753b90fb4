//! Rational reconstruction and monomials in F_p for the ansatz (the null
//! spaces are the engine's `Fp::null_space`, obsan-recon's one elimination).

use obsan_expr::{Fp, P, Q};

/// Rational number reconstruction (Wang): `a/b = u mod p` with |a|, |b| < sqrt(p/2).
pub(crate) fn rat_recon(u: Fp) -> Option<Q> {
    let p = P as i128;
    let bound = ((P / 2) as f64).sqrt() as i128;
    let (mut r0, mut r1) = (p, u.0 as i128);
    let (mut t0, mut t1) = (0i128, 1i128);
    while r1 > bound {
        let q = r0 / r1;
        (r0, r1) = (r1, r0 - q * r1);
        (t0, t1) = (t1, t0 - q * t1);
    }
    if t1 == 0 || t1.abs() > bound {
        return None;
    }
    let (a, b) = if t1 < 0 { (-r1, -t1) } else { (r1, t1) };
    let a = i64::try_from(a).ok()?;
    let b = i64::try_from(b).ok()?;
    Q::from_i64(a).div(&Q::from_i64(b))
}

/// Exponent vectors of total degree `lo..=hi` over `nb` blocks, by degree.
pub(crate) fn monomials(nb: usize, lo: usize, hi: usize) -> Vec<Vec<u32>> {
    fn rec(nb: usize, left: usize, cur: &mut Vec<u32>, out: &mut Vec<Vec<u32>>) {
        if cur.len() == nb {
            if left == 0 {
                out.push(cur.clone());
            }
            return;
        }
        for e in (0..=left).rev() {
            cur.push(e as u32);
            rec(nb, left - e, cur, out);
            cur.pop();
        }
    }
    let mut out = Vec::new();
    for d in lo..=hi {
        rec(nb, d, &mut Vec::new(), &mut out);
    }
    out
}

pub(crate) fn mono_value(e: &[u32], v: &[Fp]) -> Fp {
    e.iter()
        .zip(v)
        .fold(Fp::ONE, |a, (&k, &x)| a * x.pow(k as u64))
}

/// `w(m)` for a monomial from the block values and the blocks' `w`-derivatives.
pub(crate) fn mono_deriv(e: &[u32], v: &[Fp], dv: &[Fp]) -> Fp {
    let mut acc = Fp::ZERO;
    for k in 0..e.len() {
        if e[k] == 0 || dv[k].is_zero() {
            continue;
        }
        let mut t = Fp::from_i64(e[k] as i64) * dv[k];
        for l in 0..e.len() {
            let ex = if l == k { e[l] - 1 } else { e[l] };
            t = t * v[l].pow(ex as u64);
        }
        acc = acc + t;
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rational_reconstruction_inverts_reduction_mod_p() {
        for (a, b) in [(1i64, 1i64), (-3, 7), (22, 7), (-1, 2), (123_456, 789)] {
            let u = Fp::from_i64(a) * Fp::from_i64(b).inv().unwrap();
            let q = rat_recon(u).unwrap();
            assert_eq!(q, Q::from_i64(a).div(&Q::from_i64(b)).unwrap());
        }
    }

    #[test]
    fn monomials_count_as_binomials() {
        // C(nb + d, d) exponent vectors of degree <= d.
        assert_eq!(monomials(3, 0, 2).len(), 10);
        assert_eq!(monomials(4, 0, 3).len(), 35);
    }
}
