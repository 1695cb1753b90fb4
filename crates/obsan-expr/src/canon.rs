//! The exact canonical form (engine.md section 4).
//!
//! An expression is a fraction `num / den` of integer polynomials in the
//! leaves, where
//! - `num` has degree at most 1 in every `sin` leaf (`s^2 -> 1 - c^2`) and in
//!   every `sqrt` leaf (`r^2 -> radicand`), below q in a `root_q` leaf;
//! - `den` contains no `sin` and no `sqrt` leaf (made so by multiplying with
//!   the conjugate, `(b0 + s b1)(b0 - s b1) = b0^2 - (1 - c^2) b1^2`), and a
//!   `root_q` leaf only where it is not a monomial in it (engine.md, "Roots");
//! - `gcd(num, den) = 1` and the leading coefficient of `den` is positive.
//!
//! Two expressions are equal as functions iff their forms are identical (up
//! to the limitations listed in docs/engine.md), so zero-testing is exact.

use crate::budget::{self, invariant, Limit};
use crate::gcd::gcd;
use crate::graph::{Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::{int, Q};
use crate::poly::{Mono, Poly, Var};
use crate::ratfun::RatFun;
use rustc_hash::FxHashSet;

/// Sums and products with more operands than this are combined pairwise.
const BALANCE_MIN: usize = 64;

/// The algebraic relation a leaf satisfies, if any.
enum Relation<'a> {
    /// `s^2 = 1 - c^2`.
    Sin(Var),
    /// `r^q = radicand`.
    Root(&'a RatFun, u32),
}

impl Ctx {
    fn relation(&self, v: Var) -> Option<Relation<'_>> {
        let leaf = &self.leaves[v as usize];
        match leaf.kind {
            LeafKind::Sin(_) => leaf.partner.map(Relation::Sin),
            LeafKind::Root(_, q) => self.radicand(v).map(|r| Relation::Root(r, q)),
            _ => None,
        }
    }

    /// Whether a form contains no `sin` and no `sqrt` leaf (its inverse is cheap).
    pub fn is_relation_free(&self, r: &RatFun) -> bool {
        !r.num.vars().iter().any(|&v| self.has_relation(v))
    }

    pub(crate) fn has_relation(&self, v: Var) -> bool {
        matches!(
            self.leaves[v as usize].kind,
            LeafKind::Sin(_) | LeafKind::Root(..)
        )
    }

    /// The index `q` of a root leaf.
    fn root_index(&self, v: Var) -> Option<u32> {
        match self.leaves[v as usize].kind {
            LeafKind::Root(_, q) => Some(q),
            _ => None,
        }
    }

    /// Whether a denominator holds a root leaf (only q > 2 can stay there).
    fn kept_root(&self, d: &Poly) -> bool {
        !d.is_constant() && d.vars().iter().any(|&v| self.root_index(v).is_some())
    }

    /// The degree from which a relation leaf is reduced (2 for `sin`, q for roots).
    fn relation_degree(&self, v: Var) -> u32 {
        self.root_index(v).unwrap_or(2)
    }

    /// Reduce all relation leaves (`sin`, `sqrt` to degree <= 1, `root_q` to
    /// degree < q): returns `(n, m)` with `p = n / m`.
    pub(crate) fn reduce_poly(&self, p: Poly) -> (Poly, Poly) {
        let mut num = p;
        let mut den = Poly::one();
        while budget::poll() {
            // Highest leaf first: reductions only introduce lower leaves.
            let v = num
                .vars()
                .into_iter()
                .rev()
                .find(|&v| self.has_relation(v) && num.degree(v) >= self.relation_degree(v));
            let Some(v) = v else { break };
            let cs = num.coeffs_in(v);
            let Some(rel) = self.relation(v) else {
                budget::trip(Limit::Internal(
                    "a sin leaf without cos, or a sqrt without radicand",
                ));
                break;
            };
            match rel {
                Relation::Sin(c) => {
                    let one_minus_c2 = Poly::one().sub(&Poly::var(c).pow(2));
                    let mut acc = Poly::zero();
                    for (e, k) in cs {
                        let t = k
                            .mul_term(&Mono::var(v, e % 2), &int(1))
                            .mul(&one_minus_c2.pow(e / 2));
                        acc = acc.add(&t);
                    }
                    num = acc;
                }
                Relation::Root(rad, q) => {
                    // r^e = r^(e mod q) (N/D)^(e div q), over the common D^top.
                    let top = cs[0].0 / q;
                    let mut acc = Poly::zero();
                    for (e, k) in cs {
                        let t = k
                            .mul_term(&Mono::var(v, e % q), &int(1))
                            .mul(&rad.num.pow(e / q))
                            .mul(&rad.den.pow(top - e / q));
                        acc = acc.add(&t);
                    }
                    num = acc;
                    den = den.mul(&rad.den.pow(top));
                }
            }
        }
        (num, den)
    }

    /// Bring any fraction to canonical form.
    pub(crate) fn normalize(&self, num: Poly, den: Poly) -> RatFun {
        if den.is_zero() {
            if !budget::tripped() {
                budget::trip(Limit::Internal("canonical form with zero denominator"));
            }
            return RatFun::zero();
        }
        if num.is_zero() {
            return RatFun::zero();
        }
        let (mut num, m1) = self.reduce_poly(num);
        let mut den = den.mul(&m1);
        let (d, m2) = self.reduce_poly(den);
        den = d;
        num = num.mul(&m2);
        // Rationalise: remove relation leaves from the denominator, highest
        // first; a q-th root (q > 2) only where the denominator is a monomial
        // in it (engine.md, "Roots": the others stay, reduced).
        let mut kept: Vec<Var> = Vec::new();
        while let Some(v) = den
            .vars()
            .into_iter()
            .rev()
            .find(|&v| self.has_relation(v) && !kept.contains(&v))
        {
            if !budget::poll() {
                return RatFun::zero();
            }
            let cs = den.coeffs_in(v);
            if let Some(q) = self.root_index(v).filter(|&q| q > 2) {
                if let [(e, _)] = cs[..] {
                    // d r^e (e < q) times r^(q - e) is d u.
                    let r = Poly::var(v).pow(q - e);
                    let (n2, m3) = self.reduce_poly(num.mul(&r));
                    let (d2, m4) = self.reduce_poly(den.mul(&r));
                    num = n2.mul(&m4);
                    den = d2.mul(&m3);
                } else {
                    kept.push(v);
                }
                continue;
            }
            let d1 = cs
                .iter()
                .find(|c| c.0 == 1)
                .map(|c| c.1.clone())
                .unwrap_or_default();
            let d0 = cs
                .iter()
                .find(|c| c.0 == 0)
                .map(|c| c.1.clone())
                .unwrap_or_default();
            let conj = d0.sub(&d1.mul(&Poly::var(v)));
            let (n2, m3) = self.reduce_poly(num.mul(&conj));
            let (d2, m4) = self.reduce_poly(den.mul(&conj));
            if d2.is_zero() {
                if !budget::tripped() {
                    budget::trip(Limit::Internal(
                        "conjugate norm vanished: a sqrt radicand is a perfect square",
                    ));
                }
                return RatFun::zero();
            }
            num = n2.mul(&m4);
            den = d2.mul(&m3);
        }
        let g = gcd(&num, &den);
        if !g.is_one() {
            num = invariant(num.div_exact(&g), "gcd divides numerator");
            den = invariant(den.div_exact(&g), "gcd divides denominator");
        }
        if den.lc_sign() == dashu_int::Sign::Negative {
            num = num.neg();
            den = den.neg();
        }
        RatFun { num, den }
    }

    pub fn rf_add(&self, a: &RatFun, b: &RatFun) -> RatFun {
        if a.is_zero() {
            return b.clone();
        }
        if b.is_zero() {
            return a.clone();
        }
        if self.kept_root(&a.den) || self.kept_root(&b.den) {
            // Cross products with a root kept in a denominator leave the
            // numerator unreduced: reduce it (the zero test reads it).
            let num = a.num.mul(&b.den).add(&b.num.mul(&a.den));
            return self.normalize(num, a.den.mul(&b.den));
        }
        if a.den == b.den {
            let num = a.num.add(&b.num);
            if a.den.is_one() || num.is_zero() {
                return RatFun {
                    num,
                    den: a.den.clone(),
                }
                .fix_zero();
            }
            let g = gcd(&num, &a.den);
            return RatFun {
                num: invariant(num.div_exact(&g), "gcd divides"),
                den: invariant(a.den.div_exact(&g), "gcd divides"),
            }
            .fix_zero();
        }
        // Henrici: only the gcd of the denominators can cancel.
        let g = gcd(&a.den, &b.den);
        let da = invariant(a.den.div_exact(&g), "gcd divides");
        let db = invariant(b.den.div_exact(&g), "gcd divides");
        let num = a.num.mul(&db).add(&b.num.mul(&da));
        if num.is_zero() {
            return RatFun::zero();
        }
        let den = a.den.mul(&db);
        let g2 = gcd(&num, &g);
        if g2.is_one() {
            RatFun { num, den }
        } else {
            RatFun {
                num: invariant(num.div_exact(&g2), "gcd divides"),
                den: invariant(den.div_exact(&g2), "gcd divides"),
            }
        }
    }

    pub fn rf_mul(&self, a: &RatFun, b: &RatFun) -> RatFun {
        if a.is_zero() || b.is_zero() {
            return RatFun::zero();
        }
        if a.den.is_one() && b.den.is_one() && (a.num.is_constant() || b.num.is_constant()) {
            // A constant times a reduced polynomial stays reduced.
            return RatFun {
                num: a.num.mul(&b.num),
                den: Poly::one(),
            };
        }
        let g1 = gcd(&a.num, &b.den);
        let g2 = gcd(&b.num, &a.den);
        let an = invariant(a.num.div_exact(&g1), "gcd divides");
        let bn = invariant(b.num.div_exact(&g2), "gcd divides");
        let ad = invariant(a.den.div_exact(&g2), "gcd divides");
        let bd = invariant(b.den.div_exact(&g1), "gcd divides");
        let num = an.mul(&bn);
        let den = ad.mul(&bd);
        // A product of two reduced numerators may need the relations again.
        let av = an.vars();
        // A q-th root kept in a denominator may reach degree q there.
        let needs = bn
            .vars()
            .iter()
            .any(|v| self.has_relation(*v) && av.contains(v))
            || self.kept_root(&den);
        if needs {
            self.normalize(num, den)
        } else {
            RatFun { num, den }
        }
    }

    /// Inverse; `None` for zero.
    pub fn rf_inv(&self, a: &RatFun) -> Option<RatFun> {
        if a.is_zero() {
            return None;
        }
        let vars = a.num.vars();
        if vars.iter().any(|v| self.has_relation(*v)) {
            let sqrt = vars
                .iter()
                .any(|v| matches!(self.leaves[*v as usize].kind, LeafKind::Root(..)));
            if sqrt {
                return Some(self.normalize(a.den.clone(), a.num.clone()));
            }
            return Some(self.inv_via_tan_half(a));
        }
        let (mut num, mut den) = (a.den.clone(), a.num.clone());
        if den.lc_sign() == dashu_int::Sign::Negative {
            num = num.neg();
            den = den.neg();
        }
        Some(RatFun { num, den })
    }

    pub fn rf_pow(&self, a: &RatFun, e: i64) -> Option<RatFun> {
        let base = if e < 0 { self.rf_inv(a)? } else { a.clone() };
        let mut k = e.unsigned_abs();
        // The result's degree is known in advance: refuse it before computing.
        let top = base.num.max_exponent().max(base.den.max_exponent()) as u128 * k as u128;
        if k > 1 && top > budget::max_degree() as u128 {
            budget::trip(Limit::Degree {
                degree: top,
                max: budget::max_degree() as u128,
            });
            return Some(RatFun::zero());
        }
        // The numerator and denominator are coprime, so their powers are too and
        // nothing cancels: the size check on each power's extreme coefficients holds.
        if k > 1 && !(base.num.power_fits(k) && base.den.power_fits(k)) {
            return Some(RatFun::zero());
        }
        let mut r = RatFun::one();
        let mut b = base;
        while k > 0 && !budget::tripped() {
            if k & 1 == 1 {
                r = self.rf_mul(&r, &b);
            }
            k >>= 1;
            if k > 0 {
                b = self.rf_mul(&b, &b);
            }
        }
        Some(r)
    }

    pub fn rf_sub(&self, a: &RatFun, b: &RatFun) -> RatFun {
        self.rf_add(a, &b.neg())
    }

    /// The canonical form of a node (memoised; children first, no recursion).
    ///
    /// Panics only on a division by an expression whose canonical form is zero
    /// (builders reject such divisions with an error first) and on the hard
    /// limits of docs/engine.md; no size or time limit applies. Use
    /// [`Ctx::try_canon`] for untrusted input.
    pub fn canon(&mut self, id: Id) -> RatFun {
        if let Some(r) = self.memo.canon.get(&id) {
            return r.clone();
        }
        // Nodes below `id` whose form is not known yet.
        let mut todo = Vec::new();
        let mut seen = FxHashSet::default();
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            if self.memo.canon.contains_key(&n) || !seen.insert(n) {
                continue;
            }
            todo.push(n);
            match self.node(n) {
                Node::Add(cs) | Node::Mul(cs) => stack.extend(cs.iter().copied()),
                Node::Pow(b, _) => stack.push(*b),
                _ => {}
            }
        }
        todo.sort_unstable();
        for n in todo {
            let r = match self.node(n).clone() {
                Node::Num(q) => RatFun::from_q(&q),
                Node::Leaf(v) => RatFun::var(v),
                Node::Add(cs) => self.canon_tree(&cs, false),
                Node::Mul(cs) => self.canon_tree(&cs, true),
                Node::Pow(b, e) => invariant(
                    self.rf_pow(&self.memo.canon[&b], e as i64),
                    "no division by zero in a canonical form (builders check divisors)",
                ),
            };
            // A tripped computation leaves placeholders: never memoise them.
            let d = r.num.max_exponent().max(r.den.max_exponent());
            if !budget::check_degree(d as u64) || budget::tripped() {
                return RatFun::zero();
            }
            self.memo.canon.insert(n, r);
        }
        self.memo.canon[&id].clone()
    }

    /// The form of a sum or product of already canonical children, combined
    /// in a balanced tree: a long chain costs O(n log n) term copies instead
    /// of O(n^2).
    fn canon_tree(&self, cs: &[Id], product: bool) -> RatFun {
        let mut level: Vec<RatFun> = cs.iter().map(|c| self.memo.canon[c].clone()).collect();
        // Short chains, and sums of fractions (pairing two large denominators
        // costs a large gcd), go left to right: each step meets a small operand.
        if level.len() <= BALANCE_MIN || (!product && level.iter().any(|r| !r.den.is_one())) {
            let mut acc = if product {
                RatFun::one()
            } else {
                RatFun::zero()
            };
            for r in &level {
                if budget::tripped() {
                    return RatFun::zero();
                }
                acc = if product {
                    self.rf_mul(&acc, r)
                } else {
                    self.rf_add(&acc, r)
                };
            }
            return acc;
        }
        while level.len() > 1 {
            if !budget::poll() {
                return RatFun::zero();
            }
            let mut next = Vec::with_capacity(level.len().div_ceil(2));
            let mut it = level.into_iter();
            while let Some(a) = it.next() {
                next.push(match it.next() {
                    Some(b) if product => self.rf_mul(&a, &b),
                    Some(b) => self.rf_add(&a, &b),
                    None => a,
                });
            }
            level = next;
        }
        level.pop().unwrap_or_else(RatFun::zero)
    }

    /// [`Ctx::canon`] under the context's budget ([`Ctx::set_budget`](Ctx#method.set_budget)): the
    /// entry point for untrusted input.
    pub fn try_canon(&mut self, id: Id) -> Result<RatFun, Limit> {
        self.within_budget(|c| c.canon(id))
    }

    /// [`Ctx::is_identically_zero`] under the context's budget.
    pub fn try_is_identically_zero(&mut self, id: Id) -> Result<bool, Limit> {
        self.within_budget(|c| c.canon(id).is_zero())
    }

    /// `true` iff the expression is identically zero (exact).
    pub fn is_identically_zero(&mut self, id: Id) -> bool {
        self.canon(id).is_zero()
    }

    /// A node whose canonical form is `r` (deterministic, so equal forms give equal ids).
    pub fn from_canonical(&mut self, r: &RatFun) -> Id {
        let num = self.poly_node(&r.num);
        let id = if r.den.is_one() {
            num
        } else {
            let den = self.poly_node(&r.den);
            self.div(num, den)
        };
        if !budget::tripped() {
            self.memo.canon.entry(id).or_insert_with(|| r.clone());
        }
        id
    }

    fn poly_node(&mut self, p: &Poly) -> Id {
        let mut terms = Vec::with_capacity(p.len());
        for (m, c) in p.terms() {
            let mut f = vec![self.num(Q::from_int(c.clone()))];
            for (v, e) in m.iter() {
                let ln = self.leaf_node(v);
                f.push(self.pow(ln, e as i64));
            }
            terms.push(self.mul(&f));
        }
        self.add(&terms)
    }
}
