//! Real q-th roots `root_q(u)`, the atoms of rational exponents
//! (`u^(p/q) = root_q(u)^p`, lower.rs `pow_q`; docs/engine.md "Roots").
//!
//! A root leaf carries the relation `r^q = u` (canon.rs reduces every
//! numerator to degree `< q` in it). The form over it is canonical when
//! `x^q - u` is irreducible over the field of the other leaves (then
//! `1, r, .., r^(q-1)` is a basis). By Capelli's theorem that fails exactly
//! when `u` is an `l`-th power for a prime `l | q`, or `u = -4 w^4` with
//! `4 | q`; both are handled here before a leaf is made: an odd `l`-th power
//! becomes a root of lower index (`root_q(a^l) = root_(q/l)(a)`, real odd
//! roots), the others are refused as `sqrt(x^2)` is (`|.|`, or no real root).
//! Constants get one atom per prime and reduced index: `4^(1/6) = 2^(1/3)`,
//! `(1/2)^(1/3) = 2^(2/3)/2`, so that powers of one prime have one form.

use crate::budget::{self, ROOT_MAX};
use crate::graph::Id;
use crate::lower::{err, stop, R};
use crate::memo::Ctx;
use crate::num::{int, trial_factor, Int, Q};
use crate::poly::{Mono, Poly, Var};
use crate::ratfun::RatFun;
use dashu_int::ops::{BitTest, UnsignedAbs};
use dashu_int::{IBig, Sign, UBig};

impl Ctx {
    /// The real `q`-th root of `u` (`q = 2`: [`Ctx::sqrt`]); defined for
    /// `u >= 0`, where every rewrite below is an identity.
    pub fn root(&mut self, u: Id, q: u32) -> R<Id> {
        match q {
            0 => err("a root of index 0 is undefined"),
            1 => Ok(u),
            2 => self.sqrt(u),
            _ if q > ROOT_MAX => err(format!("root index {q} is above {ROOT_MAX}")),
            _ if prime_factors(q).len() > 1 => self.root_composite(u, q),
            _ => self.root_general(u, q),
        }
    }

    /// `root_q(u)` as atoms of prime-power index, through the existing roots
    /// of the same radicand: roots of one radicand at powers of one prime are
    /// then a tower (each the `l^b`-th root of the one below), so every
    /// relation among them is the tower's own and `x^(1/2)`, `x^(1/4)`,
    /// `x^(1/6)`, `x^(1/3)` have one form in any order of appearance.
    /// - `q = prod l^a` not a prime power: `u^(1/q) = u^n prod root_(l^a)(u)^c`
    ///   with `1/q = n + sum c/l^a` (partial fractions, `0 <= c < l^a`);
    /// - a root of `u` of effective index `l^b` exists with `b >= a`: its power
    ///   `l^(b-a)`; with `b < a` (the largest): the `l^(a-b)`-th root of it
    ///   (irreducible: `x^q - u` is, so `[K(root_q u) : K(root_(l^b) u)] = l^(a-b)`).
    ///
    /// `None`: make the leaf `root_q(u)` itself.
    pub(crate) fn related_root(&mut self, u: &RatFun, q: u32) -> Option<Id> {
        if prime_factors(q).len() > 1 {
            let id = self.from_canonical(u);
            return self.root_composite(id, q).ok();
        }
        let mut best: Option<(Var, u32)> = None;
        for v in 0..self.leaves.len() as Var {
            let Some((base, eff)) = self.root_base(v) else {
                continue;
            };
            if eff == q || &base != u || (!eff.is_multiple_of(q) && !q.is_multiple_of(eff)) {
                continue;
            }
            if eff % q == 0 {
                let node = self.leaf_node(v);
                return Some(self.pow(node, (eff / q) as i64));
            }
            if best.is_none_or(|b| b.1 < eff) {
                best = Some((v, eff));
            }
        }
        let (v, eff) = best?;
        Some(self.root_leaf(RatFun::var(v), q / eff))
    }

    /// `u^(1/q)` for `q` with several primes: `u^n prod root_(l^a)(u)^c` with
    /// `1/q = n + sum c/l^a` (partial fractions, `c = (q/l^a)^-1 mod l^a`), each
    /// root of prime-power index made by [`Ctx::root`] (its own content split).
    fn root_composite(&mut self, u: Id, q: u32) -> R<Id> {
        if self.canon_ok(u)?.is_zero() {
            return Ok(self.zero());
        }
        let mut fs = Vec::new();
        let mut acc: i64 = 0; // sum c q / l^a
        for l in prime_factors(q) {
            let mut pa = 1u32;
            while q.is_multiple_of(pa * l) {
                pa *= l;
            }
            let rest = (q / pa) as i64;
            let Some(c) = (1..pa as i64).find(|c| (c * rest) % pa as i64 == 1) else {
                return err(format!("no partial fraction of 1/{q} at {pa}"));
            };
            acc += c * rest;
            let r = self.root(u, pa)?;
            fs.push(self.pow(r, c));
        }
        // n q = 1 - acc exactly.
        fs.push(self.pow(u, (1 - acc) / q as i64));
        Ok(self.mul(&fs))
    }

    /// The radicand at the bottom of a root leaf's tower and its effective
    /// index (the product of the indices on the way down).
    fn root_base(&self, v: Var) -> Option<(RatFun, u32)> {
        let (_, k) = self.root_arg(v)?;
        let r = self.radicand(v)?;
        match tower_parent(r).filter(|&w| self.root_arg(w).is_some()) {
            Some(w) => {
                let (base, e) = self.root_base(w)?;
                Some((base, e.checked_mul(k)?))
            }
            None => Some((r.clone(), k)),
        }
    }

    fn root_general(&mut self, u: Id, q: u32) -> R<Id> {
        let c = self.canon_ok(u)?;
        if c.is_zero() {
            return Ok(self.zero());
        }
        if let Some(a) = c.as_q() {
            if a.is_negative() {
                return err(format!(
                    "a root of index {q} of the negative constant {a} is not supported (the real domain of u^(p/q) is u >= 0)"
                ));
            }
            return self.root_const(&a, q);
        }
        // The q-th powers of the constant content come out: c = k N'/D' with
        // k = outside^q * inside, `inside` a positive integer (a constant
        // denominator is rationalised into it).
        let (cn, cd) = (c.num.content(), c.den.content());
        let (outside, inside) = power_split(&Q::new(cn.clone(), cd.clone()), q);
        let div = |p: &Poly, k: Int| {
            budget::invariant(p.div_exact(&Poly::constant(k)), "content divides")
        };
        let inner = RatFun {
            num: div(&c.num, cn).mul(&Poly::constant(inside)),
            den: div(&c.den, cd),
        };
        stop()?;
        let out = self.num(outside);
        // Capelli: x^q - N/D is reducible iff N D^(l-1) is an l-th power for a
        // prime l | q (exactly in Z[x]: Gauss), or 4 | q and N D^3 = -4 w^4.
        for l in prime_factors(q) {
            let p = inner.num.mul(&inner.den.pow(l - 1));
            if let Some(a) = poly_root(&p, l) {
                if l == 2 {
                    return err(format!(
                        "a root of index {q} of a perfect square is not supported (it is a root of |.|): write the root of its base"
                    ));
                }
                // N/D = (a/D)^l and the real odd root of a^l is a.
                let base = self.normalize(a, inner.den.clone());
                stop()?;
                let b = self.from_canonical(&base);
                let r = self.root(b, q / l)?;
                return Ok(self.mul(&[out, r]));
            }
        }
        if q.is_multiple_of(4) {
            let p = inner.num.mul(&inner.den.pow(3)).neg();
            let four = Poly::constant(int(4));
            if p.div_exact(&four)
                .is_some_and(|w| poly_root(&w, 4).is_some())
            {
                return err(format!(
                    "a root of index {q} of -4 w^4 is not supported (it is not real where w != 0)"
                ));
            }
        }
        stop()?;
        let r = self.root_leaf(inner, q);
        Ok(self.mul(&[out, r]))
    }

    /// `a^(1/q)` for a rational `a > 0`: per prime `p^e` of `a` (`e` of either
    /// sign), `p^floor(e/q)` times `root_q'(p)^k'` with `k'/q' = (e mod q)/q` in
    /// lowest terms. Roots of distinct primes are independent (Besicovitch),
    /// so the form is canonical; a cofactor trial division leaves is one atom.
    fn root_const(&mut self, a: &Q, q: u32) -> R<Id> {
        let mut coeff = Q::one();
        let mut fs = Vec::new();
        let powers = prime_powers(a.num(), 1)
            .into_iter()
            .chain(prime_powers(a.den(), -1));
        for (p, e) in powers {
            let (fl, rem) = (e.div_euclid(q as i64), e.rem_euclid(q as i64));
            let pq = Q::from_int(p.clone());
            let Some(f) = pq.powi(fl) else {
                return err("a prime factor is zero");
            };
            coeff = coeff.mul(&f);
            if rem > 0 {
                let g = gcd_u64(rem as u64, q as u64);
                let (k, qq) = (rem as u64 / g, q as u64 / g);
                let leaf = self.root_leaf(RatFun::from_q(&pq), qq as u32);
                fs.push(self.pow(leaf, k as i64));
            }
        }
        stop()?;
        fs.push(self.num(coeff));
        Ok(self.mul(&fs))
    }
}

fn gcd_u64(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// The leaf `w` when a radicand is exactly `w` (a tower over another root).
pub(crate) fn tower_parent(r: &RatFun) -> Option<Var> {
    if !r.den.is_one() || r.num.len() != 1 {
        return None;
    }
    let (m, c) = r.num.leading()?;
    let mut it = m.iter();
    match (it.next(), it.next()) {
        (Some((w, 1)), None) if c.is_one() => Some(w),
        _ => None,
    }
}

/// The distinct primes of `q`.
pub(crate) fn prime_factors(mut q: u32) -> Vec<u32> {
    let mut out = Vec::new();
    let mut d = 2;
    while d * d <= q {
        if q.is_multiple_of(d) {
            out.push(d);
            while q.is_multiple_of(d) {
                q /= d;
            }
        }
        d += 1;
    }
    if q > 1 {
        out.push(q);
    }
    out
}

/// `|n|` as prime powers `(p, sign e)` by trial division; the cofactor left
/// (no prime below the trial bound) enters as `(w, sign j)` with `cofactor =
/// w^j`, `j` maximal, so no atom is a perfect power.
fn prime_powers(n: &Int, sign: i64) -> Vec<(Int, i64)> {
    if n.is_zero() {
        return vec![];
    }
    let (factors, cofactor) = trial_factor(n);
    let mut out: Vec<(Int, i64)> = factors
        .into_iter()
        .map(|(p, e)| (p, sign * e as i64))
        .collect();
    if cofactor.is_one() {
        return out;
    }
    let (mut w, mut j) = (cofactor, 1i64);
    // w has no prime factor below 2^16 (or 1000), so w = b^k needs b above
    // that: k <= bits / 10.
    let mut k = 2;
    while k as usize <= w.bit_len() / 10 + 1 {
        match int_exact_root(&w, k) {
            Some(b) => {
                w = b;
                j *= k as i64;
            }
            None => k += 1,
        }
    }
    out.push((w, sign * j));
    out
}

/// The integer `k`-th root of `n` if `n` is a `k`-th power.
fn int_exact_root(n: &Int, k: u32) -> Option<Int> {
    let neg = n.sign() == Sign::Negative;
    if neg && k.is_multiple_of(2) {
        return None;
    }
    let u: UBig = n.clone().unsigned_abs();
    let r = u.nth_root(k as usize);
    if r.pow(k as usize) != u {
        return None;
    }
    let r = IBig::from(r);
    Some(if neg { -r } else { r })
}

/// `a` with `a^k = p` in Z[x] if there is one (schoolbook root: the leading
/// term of `p - a^k` fixes the next term of `a`; each term is smaller than the
/// one before and its exponents are at most `deg p / k`, so it terminates).
pub(crate) fn poly_root(p: &Poly, k: u32) -> Option<Poly> {
    if p.is_zero() {
        return Some(Poly::zero());
    }
    // Cheap refutations first: the first and last terms must be k-th powers.
    let (lm, lc) = p.leading().cloned()?;
    let (tm, tc) = p.terms().last().cloned()?;
    let powered = |m: &Mono| m.iter().all(|(_, e)| e.is_multiple_of(k));
    if !powered(&lm) || !powered(&tm) || int_exact_root(&tc, k).is_none() {
        return None;
    }
    let rc = int_exact_root(&lc, k)?;
    let rm = Mono::from_pairs(lm.iter().map(|(v, e)| (v, e / k)));
    let box_: Vec<(Var, u32)> = p.vars().iter().map(|&v| (v, p.degree(v) / k)).collect();
    let lead_m = Mono::from_pairs(rm.iter().map(|(v, e)| (v, e * (k - 1))));
    let lead_c: Int = int(k as i64) * rc.pow(k as usize - 1);
    let mut root = Poly::monomial(rm, rc);
    loop {
        if !budget::poll() {
            return None;
        }
        let rem = p.sub(&root.pow(k));
        let Some((m, c)) = rem.leading().cloned() else {
            return Some(root);
        };
        let t = m.div(&lead_m)?;
        let inside = |(v, e): (Var, u32)| box_.iter().any(|b| b.0 == v && e <= b.1);
        if !t.iter().all(inside) || !(&c % &lead_c).is_zero() {
            return None;
        }
        root = root.add(&Poly::monomial(t, &c / &lead_c));
    }
}

/// `a = outside^q * inside` with `inside` a positive integer free of q-th
/// powers (up to trial division's cofactor) and `outside` rational.
fn power_split(a: &Q, q: u32) -> (Q, Int) {
    let mut outside = Q::one();
    let mut inside = int(1);
    let powers = prime_powers(a.num(), 1)
        .into_iter()
        .chain(prime_powers(a.den(), -1));
    for (p, e) in powers {
        let (fl, rem) = (e.div_euclid(q as i64), e.rem_euclid(q as i64));
        if let Some(f) = Q::from_int(p.clone()).powi(fl) {
            outside = outside.mul(&f);
        }
        inside *= p.pow(rem as usize);
    }
    (outside, inside)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_roots() {
        let x = Poly::var(0);
        let y = Poly::var(1);
        let a = x.add(&y.mul(&Poly::constant(int(2)))).sub(&Poly::one());
        for k in 2..6 {
            assert_eq!(poly_root(&a.pow(k), k), Some(a.clone()));
            assert_eq!(poly_root(&a.pow(k).add(&Poly::one()), k), None);
        }
        // -8 (x - 1)^3 = (-2 (x - 1))^3
        let b = x.sub(&Poly::one());
        let m = b.pow(3).mul(&Poly::constant(int(-8)));
        assert_eq!(poly_root(&m, 3), Some(b.mul(&Poly::constant(int(-2)))));
        assert_eq!(poly_root(&x.mul(&y), 2), None);
    }

    #[test]
    fn constant_splits() {
        // 48 = 2^4 * 3 = 2^3 * 6: cube root 2 * 6^(1/3).
        assert_eq!(power_split(&Q::from_i64(48), 3), (Q::from_i64(2), int(6)));
        // 1/2 = 2^-3 * 4.
        assert_eq!(
            power_split(&Q::new(int(1), int(2)), 3),
            (Q::new(int(1), int(2)), int(4))
        );
        // A cofactor that is a cube of a prime above 2^16: 65537^3.
        let p = int(65537);
        assert_eq!(prime_powers(&(&p * &p * &p), 1), vec![(p, 3)]);
        assert_eq!(prime_factors(360), vec![2, 3, 5]);
    }
}
