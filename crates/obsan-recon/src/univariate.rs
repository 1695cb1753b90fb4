//! Univariate rational interpolation over F_p from as few points as the
//! function's degrees allow, with Thiele's early termination.
//!
//! The points' Newton interpolant `P` (degree below the `N` points) and the
//! nodes' product `M` are kept up to date in O(N) per point. A fraction is
//! read off the extended Euclidean algorithm on `(M, P)`: every remainder
//! `r_i` has a cofactor `s_i` with `r_i = s_i P mod M`, and the pair taken is
//! the one before the largest quotient (maximal-quotient rational
//! reconstruction, Monagan, ISSAC 2004; ties to the smallest denominator).
//! A fraction `n / d` of degrees `(a, b)`, coprime, is one of those pairs as
//! soon as `N >= a + b + 1`, and the one before a quotient of degree
//! `N - a - b`: from `N = a + b + 2` it stands out. So a polynomial of
//! degree `a` needs `a + 1` points and the fraction `a + b + 2` at most,
//! then `agree` more that it predicts; Thiele's continued fraction needs up
//! to `2 max(a, b) + 1` before them (a polynomial of degree 12: 15 points
//! here, 27 there), which is what the io route's axis probes paid.

use crate::field::{add, inv, mul, sub};
use crate::linalg::{eval, poly_divrem, poly_mul, trim};
use crate::thiele::{normalise, ThieleStep};

/// Univariate rational interpolation modulo a prime with early termination:
/// the same interface as [`Thiele`](crate::Thiele), from fewer points.
///
/// ```
/// use obsan_recon::{Univariate, PRIMES};
/// let p = PRIMES[0];
/// // f(t) = t^5 + 3: a polynomial, found from 6 points and 2 checks.
/// let f = |t: u64| (t.pow(5) + 3) % p;
/// let mut u = Univariate::new(p, 2);
/// let mut t = 10;
/// while !u.done() { u.add(t, f(t)); t += 1; }
/// assert_eq!(u.len(), 8);
/// assert_eq!(u.rational(), (vec![3, 0, 0, 0, 0, 1], vec![1]));
/// ```
#[derive(Clone, Debug)]
pub struct Univariate {
    p: u64,
    agree_needed: usize,
    agreed: usize,
    ts: Vec<u64>,
    /// The interpolant of all the points, lowest degree first.
    interp: Vec<u64>,
    /// `prod (t - t_i)` over the points, lowest degree first.
    nodes: Vec<u64>,
    /// The current fraction, normalised as [`Univariate::rational`] says;
    /// `None` when the Euclidean pair taken has a zero on a node.
    fraction: Option<(Vec<u64>, Vec<u64>)>,
}

impl Univariate {
    /// A new interpolation modulo the prime `p`, stopping after `agree`
    /// consecutive points agree with the current fraction (at least 1).
    pub fn new(p: u64, agree: usize) -> Self {
        Univariate {
            p,
            agree_needed: agree.max(1),
            agreed: 0,
            ts: Vec::new(),
            interp: Vec::new(),
            nodes: vec![1],
            fraction: None,
        }
    }

    /// True once `agree` consecutive points have agreed.
    pub fn done(&self) -> bool {
        self.agreed >= self.agree_needed
    }

    /// Points taken so far, the agreeing ones included: a fraction of
    /// degrees `(a, b)` is done after at most `a + b + 2 + agree`, a
    /// polynomial of degree `a` after `a + 1 + agree` (so one not done after
    /// `k` points has degree at least `k - agree`).
    pub fn len(&self) -> usize {
        self.ts.len()
    }

    /// True before the first point.
    pub fn is_empty(&self) -> bool {
        self.ts.is_empty()
    }

    /// Value of the current fraction at `t`; `None` at a pole or before a
    /// fraction is known.
    pub fn eval(&self, t: u64) -> Option<u64> {
        let (num, den) = self.fraction.as_ref()?;
        let d = inv(eval(den, t, self.p), self.p)?;
        Some(mul(eval(num, t, self.p), d, self.p))
    }

    /// Offers the point `(t, y)`: [`ThieleStep::Agreed`] when the current
    /// fraction passes through it (the point is kept all the same),
    /// [`ThieleStep::Unlucky`] for an abscissa already taken.
    pub fn add(&mut self, t: u64, y: u64) -> ThieleStep {
        let p = self.p;
        if self.ts.contains(&t) {
            return ThieleStep::Unlucky;
        }
        let agrees = self.eval(t) == Some(y);
        // Newton's step: P += (y - P(t)) / M(t) * M, then M *= (t - t_N).
        let Some(w) = inv(eval(&self.nodes, t, p), p) else {
            return ThieleStep::Unlucky;
        };
        let c = mul(sub(y, eval(&self.interp, t, p), p), w, p);
        if c != 0 {
            self.interp
                .resize(self.nodes.len().max(self.interp.len()), 0);
            for (a, &m) in self.interp.iter_mut().zip(&self.nodes) {
                *a = add(*a, mul(c, m, p), p);
            }
            self.interp = trim(std::mem::take(&mut self.interp));
        }
        let mut next = vec![0u64; self.nodes.len() + 1];
        for (k, &m) in self.nodes.iter().enumerate() {
            next[k + 1] = add(next[k + 1], m, p);
            next[k] = sub(next[k], mul(m, t, p), p);
        }
        self.nodes = next;
        self.ts.push(t);
        if agrees {
            self.agreed += 1;
            return ThieleStep::Agreed;
        }
        self.agreed = 0;
        self.fraction = self.reconstruct();
        ThieleStep::Added
    }

    /// The Euclidean pair before the largest quotient, if it interpolates
    /// (its denominator has no zero on a node).
    fn reconstruct(&self) -> Option<(Vec<u64>, Vec<u64>)> {
        let p = self.p;
        if self.interp.is_empty() {
            return Some((Vec::new(), vec![1]));
        }
        let (mut r0, mut r1) = (self.nodes.clone(), self.interp.clone());
        let (mut s0, mut s1): (Vec<u64>, Vec<u64>) = (Vec::new(), vec![1]);
        let mut best: Option<(usize, Vec<u64>, Vec<u64>)> = None;
        while !r1.is_empty() {
            let dq = r0.len() - r1.len();
            if best.as_ref().is_none_or(|b| dq > b.0) {
                best = Some((dq, r1.clone(), s1.clone()));
            }
            let (q, r2) = poly_divrem(&r0, &r1, p)?;
            let qs = poly_mul(&q, &s1, p);
            let mut s2 = vec![0u64; s0.len().max(qs.len())];
            for (k, s) in s2.iter_mut().enumerate() {
                *s = sub(
                    s0.get(k).copied().unwrap_or(0),
                    qs.get(k).copied().unwrap_or(0),
                    p,
                );
            }
            (r0, r1) = (r1, r2);
            (s0, s1) = (s1, trim(s2));
        }
        let (_, num, den) = best?;
        if self.ts.iter().any(|&t| eval(&den, t, p) == 0) {
            return None;
        }
        Some(normalise(num, den, p))
    }

    /// The fraction as `(numerator, denominator)` coefficient vectors,
    /// lowest degree first, coprime, normalised so that the lowest non-zero
    /// denominator coefficient is 1 (as [`Thiele::rational`](crate::Thiele::rational)).
    /// The zero function is `([], [1])`; before a fraction is known, the
    /// interpolant.
    pub fn rational(&self) -> (Vec<u64>, Vec<u64>) {
        match &self.fraction {
            Some(f) => f.clone(),
            None => normalise(self.interp.clone(), vec![1], self.p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::PRIMES;
    use crate::rng::Rng;

    /// Points until done, the fraction, and how many points it took.
    fn run(num: &[u64], den: &[u64], p: u64, seed: u64) -> (Vec<u64>, Vec<u64>, usize) {
        let mut rng = Rng::new(seed);
        let mut u = Univariate::new(p, 2);
        while !u.done() {
            let t = rng.nonzero(p);
            let Some(id) = inv(eval(den, t, p), p) else {
                continue;
            };
            u.add(t, mul(eval(num, t, p), id, p));
        }
        let (n, d) = u.rational();
        (n, d, u.len())
    }

    #[test]
    fn fractions_come_back_from_their_degrees_in_points() {
        let p = PRIMES[1];
        // (num, den, a + b + 2 + 2: the most points a coprime fraction takes)
        let cases: Vec<(Vec<u64>, Vec<u64>)> = vec![
            (vec![0, 0, 0, 0, 0, 7], vec![1]),       // 7 t^5
            (vec![1], vec![1, 0, 0, 0, 0, 0, 0, 3]), // 1/(1 + 3 t^7)
            (vec![4, 1, 0, 9], vec![1, 5]),          // (4 + t + 9 t^3)/(1 + 5 t)
            (vec![2], vec![0, 1, 1]),                // 2/(t + t^2)
            (vec![5, 0, 1], vec![0, 0, 0, 1]),       // (5 + t^2)/t^3
            (vec![], vec![1]),                       // zero
            (vec![6], vec![1]),                      // constant
        ];
        for (k, (num, den)) in cases.into_iter().enumerate() {
            let (n, d, used) = run(&num, &den, p, k as u64);
            let (a, b) = (num.len().saturating_sub(1), den.len() - 1);
            assert_eq!(poly_mul(&n, &den, p), poly_mul(&num, &d, p), "case {k}");
            assert_eq!(d.iter().find(|&&c| c != 0), Some(&1), "case {k}");
            let most = if b == 0 { a + 3 } else { a + b + 4 };
            assert!(used <= most, "case {k}: {used} points, at most {most}");
        }
        // The reduced form of 2 t/(t^2 + t^3): 2 / (t + t^2).
        let (n, d, _) = run(&[0, 2], &[0, 0, 1, 1], p, 9);
        assert_eq!((n, d), (vec![2], vec![0, 1, 1]));
    }
}
