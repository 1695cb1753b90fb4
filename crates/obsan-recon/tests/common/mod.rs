//! Test-side reference: rational functions with known exact coefficients,
//! evaluated modulo p by arithmetic independent of the crate's.
#![allow(dead_code)]

use dashu_int::IBig;
use obsan_recon::{Poly, Rational, Term};

pub type Terms = Vec<(Vec<u32>, IBig)>;

fn mulmod(a: u64, b: u64, p: u64) -> u64 {
    (a as u128 * b as u128 % p as u128) as u64
}

fn powmod(mut a: u64, mut e: u64, p: u64) -> u64 {
    let mut r = 1u64;
    while e > 0 {
        if e & 1 == 1 {
            r = mulmod(r, a, p);
        }
        a = mulmod(a, a, p);
        e >>= 1;
    }
    r
}

pub fn reduce(c: &IBig, p: u64) -> u64 {
    let pi = IBig::from(p);
    let r = ((c % &pi) + &pi) % &pi;
    u64::try_from(&r).unwrap()
}

pub fn eval_terms(t: &Terms, x: &[u64], p: u64) -> u64 {
    let mut s = 0u128;
    for (e, c) in t {
        let mut v = reduce(c, p);
        for (&xi, &ei) in x.iter().zip(e) {
            v = mulmod(v, powmod(xi, ei as u64, p), p);
        }
        s = (s + v as u128) % p as u128;
    }
    s as u64
}

/// `num/den` at x mod p; `None` at a pole.
pub fn eval(num: &Terms, den: &Terms, x: &[u64], p: u64) -> Option<u64> {
    let d = eval_terms(den, x, p);
    if d == 0 {
        return None;
    }
    Some(mulmod(eval_terms(num, x, p), powmod(d, p - 2, p), p))
}

pub fn to_terms(p: &Poly) -> Terms {
    p.terms()
        .iter()
        .map(|t| (t.exps.clone(), t.coeff.clone()))
        .collect()
}

/// Exact product of sparse integer polynomials, as a canonical Poly.
pub fn mul(a: &Terms, b: &Terms) -> Poly {
    let mut out = Vec::new();
    for (ea, ca) in a {
        for (eb, cb) in b {
            out.push(Term {
                exps: ea.iter().zip(eb).map(|(x, y)| x + y).collect(),
                coeff: ca * cb,
            });
        }
    }
    Poly::from_terms(out)
}

/// True when `r` equals `num/den` as a rational function (cross-multiplied).
pub fn same_function(r: &Rational, num: &Terms, den: &Terms) -> bool {
    mul(&to_terms(r.num()), den) == mul(num, &to_terms(r.den()))
}

/// Canonical-form invariants: the gcd of all coefficients is 1 and the
/// leading denominator term (highest total degree, then largest exponent
/// vector) is positive.
pub fn is_canonical(r: &Rational) -> bool {
    use dashu_int::ops::Gcd;
    use dashu_int::UBig;
    let mut g = UBig::ZERO;
    for t in r.num().terms().iter().chain(r.den().terms()) {
        g = (&g).gcd(
            &UBig::try_from(if t.coeff < IBig::ZERO {
                -t.coeff.clone()
            } else {
                t.coeff.clone()
            })
            .unwrap(),
        );
    }
    let low = r
        .den()
        .terms()
        .iter()
        .max_by_key(|t| (t.exps.iter().sum::<u32>(), t.exps.clone()))
        .unwrap();
    g == UBig::ONE && low.coeff > IBig::ZERO
}

pub fn t(e: &[u32], c: i64) -> (Vec<u32>, IBig) {
    (e.to_vec(), IBig::from(c))
}

pub fn tb(e: &[u32], c: IBig) -> (Vec<u32>, IBig) {
    (e.to_vec(), c)
}
