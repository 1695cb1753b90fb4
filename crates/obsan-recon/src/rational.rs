//! Exact results: sparse integer polynomials, their quotient, and the
//! lifting of F_p images to Q (Chinese remaindering, rational reconstruction).

use std::cmp::Ordering;
use std::fmt;

use dashu_int::ops::{Gcd, UnsignedAbs};
use dashu_int::{IBig, UBig};

use crate::field::{add, inv, mul};

/// One term of a [`Poly`]: an integer coefficient times `prod x_i^exps[i]`.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Term {
    /// Exponent of each variable, in the order of the black box's point.
    pub exps: Vec<u32>,
    /// Non-zero integer coefficient.
    pub coeff: IBig,
}

/// A sparse polynomial with integer coefficients. Terms are non-zero and
/// sorted by descending total degree, then descending exponent vectors.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct Poly {
    terms: Vec<Term>,
}

/// Order of terms: higher total degree first, then lexicographically larger
/// exponent vectors first.
fn term_order(a: &[u32], b: &[u32]) -> Ordering {
    let da: u64 = a.iter().map(|&e| e as u64).sum();
    let db: u64 = b.iter().map(|&e| e as u64).sum();
    db.cmp(&da).then_with(|| b.cmp(a))
}

impl Poly {
    /// Builds a polynomial from terms in any order; like terms are added and
    /// zero terms dropped.
    pub fn from_terms(terms: impl IntoIterator<Item = Term>) -> Poly {
        let mut v: Vec<Term> = terms.into_iter().collect();
        v.sort_by(|a, b| term_order(&a.exps, &b.exps));
        let mut out: Vec<Term> = Vec::with_capacity(v.len());
        for t in v {
            match out.last_mut() {
                Some(last) if last.exps == t.exps => last.coeff += t.coeff,
                _ => out.push(t),
            }
        }
        out.retain(|t| t.coeff != IBig::ZERO);
        Poly { terms: out }
    }

    /// The product (a common denominator times a reduced one, for callers
    /// that keep fractions unreduced). Exponent vectors of different
    /// lengths are padded with zeros.
    pub fn times(&self, other: &Poly) -> Poly {
        Poly::from_terms(self.terms.iter().flat_map(|a| {
            other.terms.iter().map(move |b| {
                let n = a.exps.len().max(b.exps.len());
                let at = |e: &[u32], i: usize| e.get(i).copied().unwrap_or(0);
                Term {
                    exps: (0..n).map(|i| at(&a.exps, i) + at(&b.exps, i)).collect(),
                    coeff: &a.coeff * &b.coeff,
                }
            })
        }))
    }

    /// The terms, in the order described on [`Poly`].
    pub fn terms(&self) -> &[Term] {
        &self.terms
    }

    /// True for the zero polynomial.
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }

    /// Total degree (0 for constants and for zero).
    pub fn degree(&self) -> u32 {
        self.terms
            .iter()
            .map(|t| t.exps.iter().sum::<u32>())
            .max()
            .unwrap_or(0)
    }

    /// The value at `point` modulo the prime `p`.
    pub fn eval_mod(&self, point: &[u64], p: u64) -> u64 {
        let mut s = 0u64;
        for t in &self.terms {
            let mut v = ibig_mod(&t.coeff, p);
            for (&x, &e) in point.iter().zip(&t.exps) {
                v = mul(v, crate::field::pow(x % p, e as u64, p), p);
            }
            s = add(s, v, p);
        }
        s
    }

    /// Writes the polynomial in plain infix syntax over `names`.
    fn write(&self, f: &mut fmt::Formatter<'_>, names: &[&str]) -> fmt::Result {
        if self.terms.is_empty() {
            return f.write_str("0");
        }
        for (i, t) in self.terms.iter().enumerate() {
            let negative = t.coeff < IBig::ZERO;
            let mag = if negative {
                -t.coeff.clone()
            } else {
                t.coeff.clone()
            };
            match (i, negative) {
                (0, true) => f.write_str("-")?,
                (0, false) => {}
                (_, true) => f.write_str(" - ")?,
                (_, false) => f.write_str(" + ")?,
            }
            let mut first = true;
            if mag != IBig::ONE || t.exps.iter().all(|&e| e == 0) {
                write!(f, "{mag}")?;
                first = false;
            }
            for (k, &e) in t.exps.iter().enumerate() {
                if e == 0 {
                    continue;
                }
                if !first {
                    f.write_str("*")?;
                }
                first = false;
                match names.get(k) {
                    Some(n) => f.write_str(n)?,
                    None => write!(f, "x{k}")?,
                }
                if e > 1 {
                    write!(f, "^{e}")?;
                }
            }
        }
        Ok(())
    }

    fn is_atom(&self) -> bool {
        match self.terms.as_slice() {
            [t] => {
                let vars = t.exps.iter().filter(|&&e| e > 0).count();
                (vars == 0 && t.coeff > IBig::ZERO) || (vars == 1 && t.coeff == IBig::ONE)
            }
            _ => false,
        }
    }
}

/// An exact rational function `num / den` with integer coefficients in
/// canonical form: `num` and `den` coprime (as reconstructed), the
/// coefficients of both together have gcd 1, and the leading term of `den`
/// (its first term as printed) is positive.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct Rational {
    num: Poly,
    den: Poly,
}

impl Rational {
    /// The numerator.
    pub fn num(&self) -> &Poly {
        &self.num
    }

    /// The denominator (never zero).
    pub fn den(&self) -> &Poly {
        &self.den
    }

    /// The value at `point` modulo `p`; `None` where the denominator vanishes.
    pub fn eval_mod(&self, point: &[u64], p: u64) -> Option<u64> {
        let d = inv(self.den.eval_mod(point, p), p)?;
        Some(mul(self.num.eval_mod(point, p), d, p))
    }

    /// Plain infix text over the given variable names (`+ - * / ^` and
    /// integers), e.g. `(x^2 - 3*y)/(2*z + 1)`; variables beyond `names`
    /// print as `x0`, `x1`, ...
    pub fn display<'a>(&'a self, names: &'a [&'a str]) -> impl fmt::Display + 'a {
        Shown { r: self, names }
    }

    pub(crate) fn from_parts(num: Poly, den: Poly) -> Rational {
        Rational { num, den }
    }

    /// `self / x^exps`, the monomial common to the numerator and the new
    /// denominator cancelled (callers that scaled a black box by `x^exps`
    /// to make it a polynomial undo it here). The canonical form is kept:
    /// a monomial factor changes neither the coefficients nor the order of
    /// the terms.
    pub fn over_monomial(&self, exps: &[u32]) -> Rational {
        let n = exps.len().max(
            self.num
                .terms
                .iter()
                .chain(&self.den.terms)
                .map(|t| t.exps.len())
                .max()
                .unwrap_or(0),
        );
        let padded = |e: &[u32]| -> Vec<u32> {
            let mut v = e.to_vec();
            v.resize(n, 0);
            v
        };
        let den_e = padded(exps);
        // The smallest exponent of each variable over the denominator's
        // terms, once scaled, and over the numerator's.
        let low = |p: &Poly, add: &[u32]| -> Vec<u32> {
            (0..n)
                .map(|k| {
                    p.terms
                        .iter()
                        .map(|t| t.exps.get(k).copied().unwrap_or(0) + add[k])
                        .min()
                        .unwrap_or(0)
                })
                .collect()
        };
        let zero = vec![0u32; n];
        let common: Vec<u32> = low(&self.num, &zero)
            .iter()
            .zip(low(&self.den, &den_e))
            .map(|(&a, b)| a.min(b))
            .collect();
        let shift = |p: &Poly, add: &[u32]| -> Poly {
            Poly::from_terms(p.terms.iter().map(|t| {
                Term {
                    exps: padded(&t.exps)
                        .iter()
                        .zip(add)
                        .zip(&common)
                        .map(|((&e, &a), &c)| e + a - c)
                        .collect(),
                    coeff: t.coeff.clone(),
                }
            }))
        };
        Rational {
            num: shift(&self.num, &zero),
            den: shift(&self.den, &den_e),
        }
    }
}

struct Shown<'a> {
    r: &'a Rational,
    names: &'a [&'a str],
}

impl fmt::Display for Shown<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let one = self.r.den.terms.len() == 1
            && self.r.den.terms[0].coeff == IBig::ONE
            && self.r.den.terms[0].exps.iter().all(|&e| e == 0);
        if one {
            return self.r.num.write(f, self.names);
        }
        let np = self.r.num.terms.len() > 1;
        if np {
            f.write_str("(")?;
        }
        self.r.num.write(f, self.names)?;
        if np {
            f.write_str(")")?;
        }
        f.write_str("/")?;
        if self.r.den.is_atom() {
            self.r.den.write(f, self.names)
        } else {
            f.write_str("(")?;
            self.r.den.write(f, self.names)?;
            f.write_str(")")
        }
    }
}

impl fmt::Display for Rational {
    /// Infix text with variables `x0`, `x1`, ...
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Shown {
            r: self,
            names: &[],
        }
        .fmt(f)
    }
}

pub(crate) fn ibig_mod(c: &IBig, p: u64) -> u64 {
    let r = c % IBig::from(p);
    let r = if r < IBig::ZERO { r + IBig::from(p) } else { r };
    u64::try_from(&r).unwrap_or(0)
}

/// A residue modulo a product of primes, grown one prime at a time.
#[derive(Clone, Debug)]
pub(crate) struct Crt {
    pub(crate) value: UBig,
}

impl Crt {
    /// Combines `x = self mod m` with `x = b mod p` into `x mod m p`.
    pub(crate) fn push(&mut self, m: &UBig, b: u64, p: u64) -> Option<()> {
        let a_mod_p = u64::try_from(&(&self.value % UBig::from(p))).ok()?;
        let m_mod_p = u64::try_from(&(m % UBig::from(p))).ok()?;
        let k = mul(crate::field::sub(b, a_mod_p, p), inv(m_mod_p, p)?, p);
        self.value = &self.value + m * UBig::from(k);
        Some(())
    }
}

/// Rational number reconstruction (Wang 1981): the unique `n/d` with
/// `n = a d mod m`, `|n|, d <= sqrt(m/2)`, `gcd(n, d) = 1`, if any.
/// `None` means "not yet determined": more primes are needed.
pub(crate) fn rat_recon(a: &UBig, m: &UBig) -> Option<(IBig, UBig)> {
    // Extended Euclid on (m, a), tracking the cofactor of a; remainders
    // stay non-negative.
    let two = UBig::from(2u8);
    let fits = |x: &UBig| &two * x * x < *m;
    let (mut r0, mut r1) = (m.clone(), a % m);
    let (mut s0, mut s1) = (IBig::ZERO, IBig::ONE);
    while !fits(&r1) {
        if r1 == UBig::ZERO {
            return None;
        }
        let q = &r0 / &r1;
        let r2 = &r0 - &q * &r1;
        let s2 = &s0 - IBig::from(q) * &s1;
        r0 = r1;
        r1 = r2;
        s0 = s1;
        s1 = s2;
    }
    let negative = s1 < IBig::ZERO;
    let du = s1.unsigned_abs();
    if du == UBig::ZERO || !fits(&du) {
        return None;
    }
    if r1 != UBig::ZERO && (&r1).gcd(&du) != UBig::ONE {
        return None;
    }
    let n = IBig::from(r1);
    Some((if negative { -n } else { n }, du))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;

    #[test]
    fn product_is_the_product_of_values() {
        // (2 x - 3 y^2 + 1)(x y + 5) at points modulo a prime, against the
        // product of the values, and like terms collected.
        let t = |e: &[u32], c: i64| Term {
            exps: e.to_vec(),
            coeff: IBig::from(c),
        };
        let a = Poly::from_terms([t(&[1, 0], 2), t(&[0, 2], -3), t(&[0, 0], 1)]);
        let b = Poly::from_terms([t(&[1, 1], 1), t(&[0, 0], 5)]);
        let ab = a.times(&b);
        let p = PRIMES[0];
        for pt in [[3u64, 7], [p - 1, 2], [0, 11]] {
            assert_eq!(
                ab.eval_mod(&pt, p),
                mul(a.eval_mod(&pt, p), b.eval_mod(&pt, p), p)
            );
        }
        assert_eq!(ab.terms().len(), 6);
        let sq = Poly::from_terms([t(&[1], 1), t(&[0], 1)]);
        // (x + 1)(x + 1) = x^2 + 2 x + 1: the cross terms collected.
        assert_eq!(
            sq.times(&sq),
            Poly::from_terms([t(&[2], 1), t(&[1], 2), t(&[0], 1)])
        );
    }

    #[test]
    fn over_monomial_cancels() {
        // (x^2 y + 3 x) / 1 over x y^2 = (x y + 3) / y^2.
        let t = |e: &[u32], c: i64| Term {
            exps: e.to_vec(),
            coeff: IBig::from(c),
        };
        let r = Rational::from_parts(
            Poly::from_terms([t(&[2, 1], 1), t(&[1, 0], 3)]),
            Poly::from_terms([t(&[0, 0], 1)]),
        );
        let q = r.over_monomial(&[1, 2]);
        assert_eq!(q.display(&["x", "y"]).to_string(), "(x*y + 3)/y^2");
    }

    #[test]
    fn crt_then_reconstruction_recovers_fractions() {
        let cases: [(i64, u64); 5] = [
            (-7, 3),
            (0, 1),
            (123_456_789_011, 987_654_323),
            (1, 1),
            (-1, 2),
        ];
        for (n, d) in cases {
            let mut m = UBig::ONE;
            let mut crt = Crt { value: UBig::ZERO };
            for &p in &PRIMES[..3] {
                let nm = ibig_mod(&IBig::from(n), p);
                let b = mul(nm, inv(d % p, p).unwrap(), p);
                crt.push(&m, b, p).unwrap();
                m *= UBig::from(p);
            }
            let (rn, rd) = rat_recon(&crt.value, &m).unwrap();
            assert_eq!((rn, rd), (IBig::from(n), UBig::from(d)));
        }
    }

    #[test]
    fn reconstruction_declines_when_the_modulus_is_too_small() {
        // 2^100 + 1 over one 62-bit prime cannot be determined.
        let big = (IBig::ONE << 100) + IBig::ONE;
        let p = PRIMES[0];
        let a = UBig::from(ibig_mod(&big, p));
        let got = rat_recon(&a, &UBig::from(p));
        assert_ne!(got.map(|(n, _)| n), Some(big));
    }

    #[test]
    fn display_is_plain_infix() {
        let t = |e: &[u32], c: i64| Term {
            exps: e.to_vec(),
            coeff: IBig::from(c),
        };
        let num = Poly::from_terms([t(&[2, 0], 1), t(&[0, 1], -3), t(&[0, 0], 5)]);
        let den = Poly::from_terms([t(&[0, 1], 2), t(&[0, 0], 1)]);
        let r = Rational::from_parts(num.clone(), den);
        assert_eq!(
            r.display(&["x", "y"]).to_string(),
            "(x^2 - 3*y + 5)/(2*y + 1)"
        );
        let r = Rational::from_parts(num, Poly::from_terms([t(&[0, 0], 1)]));
        assert_eq!(r.to_string(), "x0^2 - 3*x1 + 5");
        let r = Rational::from_parts(
            Poly::from_terms([t(&[1, 1], -1)]),
            Poly::from_terms([t(&[0, 3], 1)]),
        );
        assert_eq!(r.display(&["a", "b"]).to_string(), "-a*b/b^3");
    }
}
