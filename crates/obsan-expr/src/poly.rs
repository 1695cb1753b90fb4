//! Sparse multivariate polynomials with integer coefficients.
//!
//! A monomial is a list of packed `(variable, exponent)` words, sorted by
//! variable. The packing `((u32::MAX - var) << 32) | exp` in a `u64` makes the
//! derived lexicographic order of the word slices equal to the lex monomial
//! order with variable 0 highest, so sorting and leading terms need no custom
//! code. Every variable index and every exponent up to `u32::MAX` is
//! representable; exponent sums are checked (see `budget.rs`), never wrapped.

use crate::budget::{self, invariant};
use crate::num::{int, int_div_exact, int_gcd, Fp, Int};
use dashu_int::ops::BitTest;
use dashu_int::Sign;
use rustc_hash::FxHashMap as HashMap;
use smallvec::SmallVec;
use std::collections::BTreeMap;
use std::ops::{Add, Mul};

/// Index of a polynomial variable (a leaf of the expression context).
pub type Var = u32;

#[inline]
fn pack(v: Var, e: u32) -> u64 {
    debug_assert!(e > 0, "zero exponents are not stored");
    (((u32::MAX - v) as u64) << 32) | e as u64
}
#[inline]
fn unpack(w: u64) -> (Var, u32) {
    (u32::MAX - (w >> 32) as u32, w as u32)
}

/// `a + b` for exponents; past `u32::MAX` the budget trips (a panic outside
/// an armed scope) and the result is a placeholder the caller discards. The
/// softer degree budget is checked at coarser points (`Poly::max_exponent`).
#[inline]
fn add_exp(a: u32, b: u32) -> u32 {
    match a.checked_add(b) {
        Some(s) => s,
        None => {
            budget::check_degree(a as u64 + b as u64);
            1
        }
    }
}

/// A monomial: packed words in decreasing word order (increasing variable).
#[derive(Clone, PartialEq, Eq, Hash, PartialOrd, Ord, Debug, Default)]
pub struct Mono(SmallVec<[u64; 8]>);

impl Mono {
    pub fn one() -> Mono {
        Mono(SmallVec::new())
    }
    pub fn var(v: Var, e: u32) -> Mono {
        if e == 0 {
            Mono::one()
        } else {
            Mono(smallvec::smallvec![pack(v, e)])
        }
    }
    pub fn is_one(&self) -> bool {
        self.0.is_empty()
    }
    /// From `(variable, exponent)` pairs in any order (zero exponents dropped).
    pub fn from_pairs(pairs: impl IntoIterator<Item = (Var, u32)>) -> Mono {
        pairs
            .into_iter()
            .fold(Mono::one(), |m, (v, e)| m.mul(&Mono::var(v, e)))
    }
    /// `(variable, exponent)` pairs in increasing variable order.
    pub fn iter(&self) -> impl Iterator<Item = (Var, u32)> + '_ {
        self.0.iter().map(|&w| unpack(w))
    }
    pub fn degree(&self, v: Var) -> u32 {
        self.iter().find(|&(x, _)| x == v).map_or(0, |(_, e)| e)
    }
    pub fn total_degree(&self) -> u64 {
        self.iter().map(|(_, e)| e as u64).sum()
    }
    /// The largest exponent of any variable.
    pub fn max_exponent(&self) -> u32 {
        self.iter().map(|(_, e)| e).max().unwrap_or(0)
    }
    pub fn mul(&self, o: &Mono) -> Mono {
        let (a, b) = (&self.0, &o.0);
        let mut out: SmallVec<[u64; 8]> = SmallVec::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() && j < b.len() {
            let ((va, ea), (vb, eb)) = (unpack(a[i]), unpack(b[j]));
            if va == vb {
                out.push(pack(va, add_exp(ea, eb)));
                i += 1;
                j += 1;
            } else if va < vb {
                out.push(a[i]);
                i += 1;
            } else {
                out.push(b[j]);
                j += 1;
            }
        }
        out.extend_from_slice(&a[i..]);
        out.extend_from_slice(&b[j..]);
        Mono(out)
    }
    /// `self / o` when `o` divides `self`.
    pub fn div(&self, o: &Mono) -> Option<Mono> {
        let mut out: SmallVec<[u64; 8]> = SmallVec::with_capacity(self.0.len());
        let mut j = 0;
        for &w in &self.0 {
            let (v, e) = unpack(w);
            if j < o.0.len() {
                let (vo, eo) = unpack(o.0[j]);
                if vo < v {
                    return None;
                }
                if vo == v {
                    j += 1;
                    if eo > e {
                        return None;
                    }
                    if eo < e {
                        out.push(pack(v, e - eo));
                    }
                    continue;
                }
            }
            out.push(w);
        }
        if j < o.0.len() {
            return None;
        }
        Some(Mono(out))
    }
    /// Componentwise minimum (the gcd of two monomials).
    pub fn gcd(&self, o: &Mono) -> Mono {
        let mut out = SmallVec::new();
        for (v, e) in self.iter() {
            let eo = o.degree(v);
            if eo > 0 {
                out.push(pack(v, e.min(eo)));
            }
        }
        Mono(out)
    }
    /// The monomial with variable `v` removed, and its exponent.
    pub fn split(&self, v: Var) -> (u32, Mono) {
        let mut e = 0;
        let rest = self
            .0
            .iter()
            .copied()
            .filter(|&w| {
                let (x, ex) = unpack(w);
                if x == v {
                    e = ex;
                    false
                } else {
                    true
                }
            })
            .collect();
        (e, Mono(rest))
    }
}

/// Polynomial over Z: terms sorted by decreasing monomial, no zero coefficient.
#[derive(Clone, PartialEq, Eq, Hash, Debug, Default)]
pub struct Poly {
    terms: Vec<(Mono, Int)>,
}

impl Poly {
    pub fn zero() -> Poly {
        Poly { terms: Vec::new() }
    }
    pub fn constant(c: Int) -> Poly {
        if c.is_zero() {
            Poly::zero()
        } else {
            Poly {
                terms: vec![(Mono::one(), c)],
            }
        }
    }
    pub fn one() -> Poly {
        Poly::constant(int(1))
    }
    pub fn var(v: Var) -> Poly {
        Poly {
            terms: vec![(Mono::var(v, 1), int(1))],
        }
    }
    pub fn monomial(m: Mono, c: Int) -> Poly {
        if c.is_zero() {
            Poly::zero()
        } else {
            Poly {
                terms: vec![(m, c)],
            }
        }
    }
    /// Build from arbitrary terms (merged, sorted, zeros dropped).
    pub fn from_terms(terms: impl IntoIterator<Item = (Mono, Int)>) -> Poly {
        let mut map: HashMap<Mono, Int> = HashMap::default();
        for (m, c) in terms {
            *map.entry(m).or_insert_with(|| int(0)) += c;
        }
        let mut terms: Vec<_> = map.into_iter().filter(|(_, c)| !c.is_zero()).collect();
        terms.sort_unstable_by(|a, b| b.0.cmp(&a.0));
        Poly { terms }
    }
    pub fn terms(&self) -> &[(Mono, Int)] {
        &self.terms
    }
    pub fn len(&self) -> usize {
        self.terms.len()
    }
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }
    pub fn is_zero(&self) -> bool {
        self.terms.is_empty()
    }
    pub fn is_one(&self) -> bool {
        self.terms.len() == 1 && self.terms[0].0.is_one() && self.terms[0].1.is_one()
    }
    /// The constant value if the polynomial has no variable.
    pub fn as_constant(&self) -> Option<Int> {
        match self.terms.len() {
            0 => Some(int(0)),
            1 if self.terms[0].0.is_one() => Some(self.terms[0].1.clone()),
            _ => None,
        }
    }
    pub fn is_constant(&self) -> bool {
        self.as_constant().is_some()
    }
    pub fn leading(&self) -> Option<&(Mono, Int)> {
        self.terms.first()
    }
    pub fn lc_is_negative(&self) -> bool {
        self.lc_sign() == Sign::Negative
    }
    pub(crate) fn lc_sign(&self) -> Sign {
        self.terms.first().map_or(Sign::Positive, |t| t.1.sign())
    }
    pub fn neg(&self) -> Poly {
        Poly {
            terms: self
                .terms
                .iter()
                .map(|(m, c)| (m.clone(), -c.clone()))
                .collect(),
        }
    }
    pub fn add(&self, o: &Poly) -> Poly {
        self.merge(o, false)
    }
    pub fn sub(&self, o: &Poly) -> Poly {
        self.merge(o, true)
    }
    fn merge(&self, o: &Poly, negate: bool) -> Poly {
        let (a, b) = (&self.terms, &o.terms);
        let mut out = Vec::with_capacity(a.len() + b.len());
        let (mut i, mut j) = (0, 0);
        while i < a.len() || j < b.len() {
            let ord = if i == a.len() {
                std::cmp::Ordering::Less
            } else if j == b.len() {
                std::cmp::Ordering::Greater
            } else {
                a[i].0.cmp(&b[j].0)
            };
            match ord {
                std::cmp::Ordering::Greater => {
                    out.push(a[i].clone());
                    i += 1;
                }
                std::cmp::Ordering::Less => {
                    let c = if negate {
                        -b[j].1.clone()
                    } else {
                        b[j].1.clone()
                    };
                    out.push((b[j].0.clone(), c));
                    j += 1;
                }
                std::cmp::Ordering::Equal => {
                    let c = if negate {
                        &a[i].1 - &b[j].1
                    } else {
                        &a[i].1 + &b[j].1
                    };
                    if !c.is_zero() {
                        out.push((a[i].0.clone(), c));
                    }
                    i += 1;
                    j += 1;
                }
            }
        }
        budget::check_terms(out.len());
        Poly { terms: out }
    }
    pub fn mul(&self, o: &Poly) -> Poly {
        if self.is_zero() || o.is_zero() {
            return Poly::zero();
        }
        if self.terms.len() == 1 {
            return o.mul_term(&self.terms[0].0, &self.terms[0].1);
        }
        if o.terms.len() == 1 {
            return self.mul_term(&o.terms[0].0, &o.terms[0].1);
        }
        if budget::tripped() {
            return Poly::zero();
        }
        if let Some(p) = self.mul_packed(o) {
            return p;
        }
        self.mul_generic(o)
    }
    /// The product with a map keyed by word lists (any variables and degrees).
    fn mul_generic(&self, o: &Poly) -> Poly {
        // At most len(a) len(b) terms, usually far fewer: cap the reservation.
        let mut map: HashMap<Mono, Int> = HashMap::with_capacity_and_hasher(
            self.len().saturating_mul(o.len()).min(1 << 16),
            Default::default(),
        );
        for (ma, ca) in &self.terms {
            // The product only grows: stop as soon as it passes the budget.
            if !budget::poll() || !budget::check_terms(map.len()) {
                return Poly::zero();
            }
            for (mb, cb) in &o.terms {
                let c = ca * cb;
                match map.entry(ma.mul(mb)) {
                    std::collections::hash_map::Entry::Occupied(mut e) => *e.get_mut() += c,
                    std::collections::hash_map::Entry::Vacant(e) => {
                        e.insert(c);
                    }
                }
            }
        }
        let mut terms: Vec<_> = map.into_iter().filter(|(_, c)| !c.is_zero()).collect();
        budget::check_terms(terms.len());
        terms.sort_unstable_by(|a, b| b.0.cmp(&a.0));
        Poly { terms }
    }
    /// The product with every monomial packed into one `u64` (a field per
    /// variable, wide enough for the sum of the operands' degrees, so exponents
    /// never carry into each other); `None` when the fields do not fit. The
    /// map then holds 8-byte keys instead of word lists: the large products of
    /// a rationalisation are bound by memory traffic (issue: proptest seed 29).
    fn mul_packed(&self, o: &Poly) -> Option<Poly> {
        // Per variable, the largest exponent in each operand.
        let mut vars: Vec<(Var, u64)> = Vec::new();
        for p in [self, o] {
            let mut mine: BTreeMap<Var, u64> = BTreeMap::new();
            for (m, _) in &p.terms {
                for (v, e) in m.iter() {
                    let d = mine.entry(v).or_insert(0);
                    *d = (*d).max(e as u64);
                }
            }
            for (v, d) in mine {
                match vars.iter_mut().find(|(w, _)| *w == v) {
                    Some(x) => x.1 += d,
                    None => vars.push((v, d)),
                }
            }
        }
        vars.sort_unstable();
        // (variable, shift, width) per field; the exponent sums must stay in u32.
        let mut fields = Vec::with_capacity(vars.len());
        let mut shift = 0u32;
        for &(v, top) in &vars {
            if top > u32::MAX as u64 {
                return None;
            }
            let width = 64 - top.leading_zeros();
            fields.push((v, shift, width));
            shift += width;
            if shift > 64 {
                return None;
            }
        }
        let key = |m: &Mono| -> u64 {
            let mut k = 0u64;
            let mut f = 0;
            for (v, e) in m.iter() {
                while fields[f].0 != v {
                    f += 1;
                }
                k |= (e as u64) << fields[f].1;
            }
            k
        };
        let ka: Vec<u64> = self.terms.iter().map(|(m, _)| key(m)).collect();
        let kb: Vec<u64> = o.terms.iter().map(|(m, _)| key(m)).collect();
        let mut map: HashMap<u64, Int> = HashMap::with_capacity_and_hasher(
            self.len().saturating_mul(o.len()).min(1 << 16),
            Default::default(),
        );
        for (i, (_, ca)) in self.terms.iter().enumerate() {
            if !budget::poll() || !budget::check_terms(map.len()) {
                return Some(Poly::zero());
            }
            for (j, (_, cb)) in o.terms.iter().enumerate() {
                // Fields are wide enough for the sum: adding keys adds exponents.
                let c = ca * cb;
                match map.entry(ka[i] + kb[j]) {
                    std::collections::hash_map::Entry::Occupied(mut e) => *e.get_mut() += c,
                    std::collections::hash_map::Entry::Vacant(e) => {
                        e.insert(c);
                    }
                }
            }
        }
        let mut terms: Vec<(Mono, Int)> = map
            .into_iter()
            .filter(|(_, c)| !c.is_zero())
            .map(|(k, c)| {
                let mut w: SmallVec<[u64; 8]> = SmallVec::new();
                for &(v, sh, width) in &fields {
                    let e = if width == 64 {
                        k >> sh
                    } else {
                        (k >> sh) & ((1u64 << width) - 1)
                    };
                    if e > 0 {
                        w.push(pack(v, e as u32));
                    }
                }
                (Mono(w), c)
            })
            .collect();
        budget::check_terms(terms.len());
        terms.sort_unstable_by(|a, b| b.0.cmp(&a.0));
        Some(Poly { terms })
    }
    pub fn mul_term(&self, m: &Mono, c: &Int) -> Poly {
        if c.is_zero() {
            return Poly::zero();
        }
        // Multiplying by a monomial keeps the order.
        Poly {
            terms: self
                .terms
                .iter()
                .map(|(mm, cc)| (mm.mul(m), cc * c))
                .collect(),
        }
    }
    pub fn scale(&self, c: &Int) -> Poly {
        self.mul_term(&Mono::one(), c)
    }
    /// Whether `self^k`'s numbers fit the engine's number size; trips
    /// `Limit::Number` when not. The leading and trailing terms of `self^k` are
    /// those of `self` to the k-th power, with nothing to cancel them, so the
    /// result holds `lc^k` exactly: at least `k (bits - 1) + 1` bits. An exact
    /// lower bound, so nothing that fits is refused.
    pub(crate) fn power_fits(&self, k: u64) -> bool {
        let bits = [self.terms.first(), self.terms.last()]
            .into_iter()
            .flatten()
            .map(|(_, c)| c.bit_len() as u128)
            .max()
            .unwrap_or(0);
        let least = bits.saturating_sub(1).saturating_mul(k as u128) + 1;
        if bits > 1 && least > budget::NUM_BITS_MAX {
            budget::trip(budget::Limit::Number {
                bits: least,
                max: budget::NUM_BITS_MAX,
            });
            return false;
        }
        true
    }

    pub fn pow(&self, e: u32) -> Poly {
        if e > 1 {
            let top = self.max_exponent() as u64 * e as u64;
            if top > budget::max_degree() as u64 {
                budget::check_degree(top);
                return Poly::zero();
            }
            if !self.power_fits(e as u64) {
                return Poly::zero();
            }
        }
        let mut r = Poly::one();
        let mut b = self.clone();
        let mut e = e;
        while e > 0 {
            if e & 1 == 1 {
                r = r.mul(&b);
            }
            e >>= 1;
            if e > 0 {
                b = b.mul(&b);
            }
        }
        r
    }
    /// Exact quotient `self / d`, or `None` if `d` does not divide `self` over Z.
    /// `None` also for a zero divisor.
    pub fn div_exact(&self, d: &Poly) -> Option<Poly> {
        if d.is_zero() {
            return None;
        }
        if let Some(c) = d.as_constant() {
            let mut terms = Vec::with_capacity(self.len());
            for (m, x) in &self.terms {
                if !(x % &c).is_zero() {
                    return None;
                }
                terms.push((m.clone(), int_div_exact(x, &c)));
            }
            return Some(Poly { terms });
        }
        let (lm, lc) = d.leading().cloned()?;
        // Cheap necessary condition: degrees in every variable.
        for (v, e) in lm.iter() {
            let _ = e;
            if self.degree(v) < d.degree(v) {
                return if self.is_zero() {
                    Some(Poly::zero())
                } else {
                    None
                };
            }
        }
        // Remainder in an ordered map: each quotient term touches |d| entries.
        let mut r: BTreeMap<Mono, Int> = self.terms.iter().cloned().collect();
        let mut q = Vec::new();
        let rest: Vec<(Mono, Int)> = d.terms[1..].to_vec();
        while let Some((rm, rc)) = r.pop_last() {
            if !budget::poll() {
                return None;
            }
            let m = rm.div(&lm)?;
            if !(&rc % &lc).is_zero() {
                return None;
            }
            let c = int_div_exact(&rc, &lc);
            for (dm, dc) in &rest {
                let key = dm.mul(&m);
                let sub = dc * &c;
                match r.entry(key) {
                    std::collections::btree_map::Entry::Occupied(mut e) => {
                        *e.get_mut() -= sub;
                        if e.get().is_zero() {
                            e.remove();
                        }
                    }
                    std::collections::btree_map::Entry::Vacant(e) => {
                        e.insert(-sub);
                    }
                }
            }
            q.push((m, c));
        }
        Some(Poly { terms: q })
    }
    pub fn degree(&self, v: Var) -> u32 {
        self.terms
            .iter()
            .map(|(m, _)| m.degree(v))
            .max()
            .unwrap_or(0)
    }
    pub fn total_degree(&self) -> u64 {
        self.terms
            .iter()
            .map(|(m, _)| m.total_degree())
            .max()
            .unwrap_or(0)
    }
    /// The largest exponent of any variable in any term.
    pub fn max_exponent(&self) -> u32 {
        self.terms
            .iter()
            .map(|(m, _)| m.max_exponent())
            .max()
            .unwrap_or(0)
    }
    /// Sorted list of the variables that occur.
    pub fn vars(&self) -> Vec<Var> {
        let mut bits: SmallVec<[u64; 8]> = SmallVec::new();
        for (m, _) in &self.terms {
            for &w in m.0.iter() {
                let v = unpack(w).0 as usize;
                if bits.len() <= v / 64 {
                    bits.resize(v / 64 + 1, 0);
                }
                bits[v / 64] |= 1 << (v % 64);
            }
        }
        let mut out = Vec::new();
        for (i, &b) in bits.iter().enumerate() {
            let mut b = b;
            while b != 0 {
                let t = b.trailing_zeros();
                out.push((i * 64) as Var + t);
                b &= b - 1;
            }
        }
        out
    }
    pub fn contains_var(&self, v: Var) -> bool {
        self.terms.iter().any(|(m, _)| m.degree(v) > 0)
    }
    /// Coefficients with respect to `v`: `(exponent, coefficient)`, decreasing exponent.
    pub fn coeffs_in(&self, v: Var) -> Vec<(u32, Poly)> {
        let mut map: HashMap<u32, Vec<(Mono, Int)>> = HashMap::default();
        for (m, c) in &self.terms {
            let (e, rest) = m.split(v);
            map.entry(e).or_default().push((rest, c.clone()));
        }
        let mut out: Vec<(u32, Poly)> = map
            .into_iter()
            .map(|(e, mut ts)| {
                ts.sort_unstable_by(|a, b| b.0.cmp(&a.0));
                (e, Poly { terms: ts })
            })
            .collect();
        out.sort_unstable_by_key(|t| std::cmp::Reverse(t.0));
        out
    }
    /// Rebuild from coefficients in `v` (inverse of `coeffs_in`).
    pub fn from_coeffs(v: Var, cs: &[(u32, Poly)]) -> Poly {
        let mut acc = Poly::zero();
        for (e, c) in cs {
            acc = acc.add(&c.mul_term(&Mono::var(v, *e), &int(1)));
        }
        acc
    }
    /// Substitute the integer `x` for variable `v`.
    pub fn eval_var(&self, v: Var, x: &Int) -> Poly {
        let mut pows: Vec<Int> = vec![int(1)];
        Poly::from_terms(self.terms.iter().map(|(m, c)| {
            let (e, rest) = m.split(v);
            while pows.len() <= e as usize {
                let next = invariant(pows.last().cloned(), "powers start at 1") * x;
                pows.push(next);
            }
            (rest, c * &pows[e as usize])
        }))
    }
    /// Replace variable `v` by polynomial `p`.
    pub fn substitute(&self, v: Var, p: &Poly) -> Poly {
        if !self.contains_var(v) {
            return self.clone();
        }
        let cs = self.coeffs_in(v);
        // Horner in v.
        let mut acc = Poly::zero();
        let mut prev = cs[0].0;
        for (e, c) in &cs {
            acc = acc.mul(&p.pow(prev - e)).add(c);
            prev = *e;
        }
        acc.mul(&p.pow(prev))
    }
    /// Value at a point of F_p (`None` if a variable has no value).
    pub fn eval_fp(&self, val: &dyn Fn(Var) -> Fp) -> Fp {
        let mut acc = Fp::ZERO;
        for (m, c) in &self.terms {
            let mut t = Fp::from_int(c);
            for (v, e) in m.iter() {
                t = t.mul(val(v).pow(e as u64));
            }
            acc = acc.add(t);
        }
        acc
    }
    /// Dense univariate image in F_p[v], the other variables given values.
    /// Dense, so the caller bounds the degree first.
    pub fn univariate_image(&self, v: Var, val: &dyn Fn(Var) -> Fp) -> Vec<Fp> {
        let mut out = vec![Fp::ZERO; self.degree(v) as usize + 1];
        for (m, c) in &self.terms {
            let mut t = Fp::from_int(c);
            let mut ev = 0;
            for (x, e) in m.iter() {
                if x == v {
                    ev = e;
                } else {
                    t = t.mul(val(x).pow(e as u64));
                }
            }
            out[ev as usize] = out[ev as usize].add(t);
        }
        out
    }
    /// Gcd of the integer coefficients (positive; zero for the zero polynomial).
    pub fn content(&self) -> Int {
        let mut g = int(0);
        for (_, c) in &self.terms {
            g = int_gcd(&g, c);
            if g.is_one() {
                break;
            }
        }
        g
    }
    /// Gcd of all monomials.
    pub fn mono_content(&self) -> Mono {
        let mut it = self.terms.iter();
        let Some((first, _)) = it.next() else {
            return Mono::one();
        };
        let mut g = first.clone();
        for (m, _) in it {
            if g.is_one() {
                break;
            }
            g = g.gcd(m);
        }
        g
    }
    pub fn div_mono(&self, m: &Mono) -> Poly {
        Poly {
            terms: self
                .terms
                .iter()
                .map(|(mm, c)| (invariant(mm.div(m), "monomial content divides"), c.clone()))
                .collect(),
        }
    }
    /// Make the leading coefficient positive.
    pub fn normalize_sign(self) -> Poly {
        if self.lc_sign() == Sign::Negative {
            self.neg()
        } else {
            self
        }
    }
    pub fn max_abs_coeff(&self) -> Int {
        self.terms
            .iter()
            .map(|(_, c)| {
                if c.sign() == Sign::Negative {
                    -c.clone()
                } else {
                    c.clone()
                }
            })
            .max()
            .unwrap_or(int(0))
    }
    /// Partial derivative with respect to `v`.
    pub fn derivative(&self, v: Var) -> Poly {
        Poly::from_terms(self.terms.iter().filter_map(|(m, c)| {
            let e = m.degree(v);
            if e == 0 {
                return None;
            }
            let m2 = invariant(m.div(&Mono::var(v, 1)), "degree checked");
            Some((m2, c * int(e as i64)))
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn x(v: Var) -> Poly {
        Poly::var(v)
    }

    #[test]
    fn monomial_order_is_lex() {
        let a = Mono::var(0, 1);
        let b = Mono::var(1, 5);
        assert!(a > b);
        assert!(Mono::var(0, 2) > a.mul(&b));
        assert!(a.mul(&b) > a);
        assert!(a > Mono::one());
    }

    #[test]
    fn ring_identities() {
        let p = x(0).add(&x(1).scale(&int(3))).sub(&Poly::constant(int(2)));
        let q = x(1).mul(&x(2)).add(&x(0).pow(2));
        assert_eq!(p.mul(&q), q.mul(&p));
        assert_eq!(p.mul(&q).div_exact(&q), Some(p.clone()));
        assert_eq!(p.mul(&q).div_exact(&p), Some(q.clone()));
        assert_eq!(p.add(&Poly::one()).div_exact(&q), None);
        assert_eq!(p.pow(3), p.mul(&p).mul(&p));
        let s = p.substitute(1, &q);
        let direct = x(0).add(&q.scale(&int(3))).sub(&Poly::constant(int(2)));
        assert_eq!(s, direct);
        assert_eq!(Poly::from_coeffs(1, &q.coeffs_in(1)), q);
    }

    /// The packed product equals the generic one: exponent fields at their
    /// width limit (a sum needing exactly the field), a single variable with a
    /// 33-bit field, and operands whose fields do not fit (the fallback).
    #[test]
    fn packed_product_agrees_with_the_generic_one() {
        let seeds = [
            x(0).add(&x(1).pow(3)).sub(&x(2).scale(&int(-7))),
            x(3).pow(7).add(&x(0).mul(&x(3))).add(&Poly::one()),
            x(1).pow(15).sub(&x(2).pow(16).scale(&int(1 << 40))),
        ];
        for a in &seeds {
            for b in &seeds {
                let p = a.mul(b).add(&x(4));
                let q = b.pow(2).sub(&a.scale(&int(3)));
                let packed = p.mul_packed(&q).expect("small degrees fit one word");
                assert_eq!(packed, p.mul_generic(&q));
            }
        }
        let big = Poly::monomial(Mono::var(5, u32::MAX / 2), int(3)).add(&Poly::one());
        let packed = big.mul_packed(&big).expect("one 32-bit field fits");
        assert_eq!(packed, big.mul_generic(&big));
        assert_eq!(packed.degree(5), u32::MAX - 1);
        // Three variables of degree 2^30 need 93 bits: the generic path.
        let wide: Poly = (0..3)
            .map(|v| Poly::monomial(Mono::var(v, 1 << 30), int(1)))
            .fold(Poly::one(), |acc, t| acc.add(&t));
        assert!(wide.mul_packed(&wide).is_none());
        assert_eq!(wide.mul(&wide), wide.mul_generic(&wide));
    }
}
