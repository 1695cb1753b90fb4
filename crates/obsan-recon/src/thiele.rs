//! Univariate rational interpolation over F_p by Thiele's continued fraction
//!
//! `f(t) = a_0 + (t - t_0) / (a_1 + (t - t_1) / (a_2 + ...))`,
//! with early termination: a point on which the current fraction already
//! agrees is not added; after `agree` consecutive agreements the fraction is
//! taken as the function.

use crate::field::{add, inv, mul, sub};
use crate::linalg::{poly_add, poly_divrem, poly_gcd, poly_mul, poly_scale, trim};

/// What [`Thiele::add`] did with a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThieleStep {
    /// The point disagreed with the current fraction and extended it.
    Added,
    /// The current fraction already passes through the point.
    Agreed,
    /// The point cannot extend the fraction (a zero in a partial
    /// denominator, or an abscissa already used); take another point.
    Unlucky,
}

/// Thiele continued-fraction interpolation of a univariate rational
/// function modulo a prime, with early termination.
///
/// ```
/// use obsan_recon::{Thiele, PRIMES};
/// let p = PRIMES[0];
/// // f(t) = (t + 3) / (2 t^2 + 1), evaluated mod p.
/// let f = |t: u64| {
///     let num = (t + 3) as u128;
///     let den = (2 * (t as u128) * (t as u128) + 1) % p as u128;
///     // den^-1 by Fermat, u128 arithmetic
///     let (mut b, mut e, mut r) = (den, p as u128 - 2, 1u128);
///     while e > 0 { if e & 1 == 1 { r = r * b % p as u128; } b = b * b % p as u128; e >>= 1; }
///     (num * r % p as u128) as u64
/// };
/// let mut th = Thiele::new(p, 2);
/// let mut t = 10;
/// while !th.done() { th.add(t, f(t)); t += 1; }
/// let (num, den) = th.rational();
/// // Normalised so that the lowest non-zero denominator coefficient is 1.
/// assert_eq!(num, vec![3, 1]);
/// assert_eq!(den, vec![1, 0, 2]);
/// ```
#[derive(Clone, Debug)]
pub struct Thiele {
    p: u64,
    agree_needed: usize,
    agreed: usize,
    ts: Vec<u64>,
    a: Vec<u64>,
}

impl Thiele {
    /// A new interpolation modulo the prime `p`, stopping after
    /// `agree` consecutive points agree (at least 1).
    pub fn new(p: u64, agree: usize) -> Self {
        Thiele {
            p,
            agree_needed: agree.max(1),
            agreed: 0,
            ts: Vec::new(),
            a: Vec::new(),
        }
    }

    /// True once `agree` consecutive points have agreed.
    pub fn done(&self) -> bool {
        self.agreed >= self.agree_needed
    }

    /// Number of continued-fraction coefficients so far: a rational
    /// function of degrees (n, d) needs at most n + d + 1 ... 2 max(n, d) + 1.
    pub fn len(&self) -> usize {
        self.a.len()
    }

    /// True before the first point.
    pub fn is_empty(&self) -> bool {
        self.a.is_empty()
    }

    /// Value of the current fraction at `t`; `None` at a pole.
    pub fn eval(&self, t: u64) -> Option<u64> {
        let p = self.p;
        // Evaluate from the bottom; None stands for infinity.
        let mut v: Option<u64> = None;
        for j in (0..self.a.len()).rev() {
            v = match v {
                None if j + 1 == self.a.len() => Some(self.a[j]),
                None => Some(self.a[j]), // a_j + (t - t_j)/inf = a_j
                Some(w) => match inv(w, p) {
                    Some(iw) => Some(add(self.a[j], mul(sub(t, self.ts[j], p), iw, p), p)),
                    None if t == self.ts[j] => Some(self.a[j]), // 0/0 on a node: the node's value
                    None => None,
                },
            };
        }
        v
    }

    /// Offers the point `(t, y)`.
    pub fn add(&mut self, t: u64, y: u64) -> ThieleStep {
        let p = self.p;
        if self.ts.contains(&t) {
            return ThieleStep::Unlucky;
        }
        if !self.a.is_empty() && self.eval(t) == Some(y) {
            self.agreed += 1;
            return ThieleStep::Agreed;
        }
        let mut w = y;
        for j in 0..self.a.len() {
            let Some(d) = inv(sub(w, self.a[j], p), p) else {
                return ThieleStep::Unlucky;
            };
            w = mul(sub(t, self.ts[j], p), d, p);
        }
        self.a.push(w);
        self.ts.push(t);
        self.agreed = 0;
        ThieleStep::Added
    }

    /// The fraction as `(numerator, denominator)` coefficient vectors,
    /// lowest degree first, coprime, normalised so that the lowest non-zero
    /// denominator coefficient is 1. The zero function is `([], [1])`.
    pub fn rational(&self) -> (Vec<u64>, Vec<u64>) {
        let p = self.p;
        let Some((&last, rest)) = self.a.split_last() else {
            return (Vec::new(), vec![1]);
        };
        // From the bottom: N/D <- a_j + (t - t_j) D/N.
        let (mut num, mut den) = (trim(vec![last]), vec![1u64]);
        for j in (0..rest.len()).rev() {
            let lin = vec![sub(0, self.ts[j], p), 1];
            let new_num = poly_add(&poly_scale(&num, self.a[j], p), &poly_mul(&lin, &den, p), p);
            den = num;
            num = new_num;
        }
        normalise(num, den, p)
    }
}

/// Cancels the gcd and scales so that the lowest non-zero denominator
/// coefficient is 1.
pub(crate) fn normalise(num: Vec<u64>, den: Vec<u64>, p: u64) -> (Vec<u64>, Vec<u64>) {
    let (num, den) = (trim(num), trim(den));
    if num.is_empty() {
        return (Vec::new(), vec![1]);
    }
    let g = poly_gcd(&num, &den, p);
    let (num, den) = if g.len() > 1 {
        match (poly_divrem(&num, &g, p), poly_divrem(&den, &g, p)) {
            (Some((n, _)), Some((d, _))) => (n, d),
            _ => (num, den),
        }
    } else {
        (num, den)
    };
    let low = den
        .iter()
        .copied()
        .find(|&c| c != 0)
        .and_then(|c| inv(c, p));
    match low {
        Some(il) => (poly_scale(&num, il, p), poly_scale(&den, il, p)),
        None => (num, den),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;
    use crate::linalg::eval;
    use crate::rng::Rng;

    fn run(num: &[u64], den: &[u64], p: u64, seed: u64) -> (Vec<u64>, Vec<u64>, usize) {
        let mut rng = Rng::new(seed);
        let mut th = Thiele::new(p, 2);
        let mut used = 0;
        while !th.done() {
            let t = rng.nonzero(p);
            let d = eval(den, t, p);
            let Some(id) = inv(d, p) else { continue };
            th.add(t, mul(eval(num, t, p), id, p));
            used += 1;
        }
        let (n, d) = th.rational();
        (n, d, used)
    }

    #[test]
    fn polynomials_and_unbalanced_fractions_come_back() {
        let p = PRIMES[1];
        let cases: Vec<(Vec<u64>, Vec<u64>)> = vec![
            (vec![0, 0, 0, 0, 0, 7], vec![1]),       // 7 t^5
            (vec![1], vec![1, 0, 0, 0, 0, 0, 0, 3]), // 1/(1 + 3 t^7)
            (vec![4, 1, 0, 9], vec![1, 5]),          // (4 + t + 9 t^3)/(1 + 5 t)
            (vec![0, 2], vec![0, 0, 1, 1]),          // 2 t / (t^2 + t^3) = 2/(t + t^2)
            (vec![], vec![1]),                       // zero
            (vec![6], vec![1]),                      // constant
        ];
        for (k, (num, den)) in cases.into_iter().enumerate() {
            let (n, d, used) = run(&num, &den, p, k as u64);
            // Cross-multiplication is an identity independent of the form.
            let lhs = poly_mul(&n, &den, p);
            let rhs = poly_mul(&num, &d, p);
            assert_eq!(lhs, rhs, "case {k}");
            // Early termination: at most 2 max(deg) + 1 coefficients + 2 checks.
            let m = num.len().max(den.len());
            assert!(used <= 2 * m + 2, "case {k}: {used} points");
            assert_eq!(d.iter().find(|&&c| c != 0), Some(&1));
        }
        // The reduced form of 2 t/(t^2 + t^3): 2 / (t + t^2).
        let (n, d, _) = run(&[0, 2], &[0, 0, 1, 1], p, 9);
        assert_eq!((n, d), (vec![2], vec![0, 1, 1]));
    }
}
