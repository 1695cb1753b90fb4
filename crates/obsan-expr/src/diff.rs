//! Formal differentiation on the shared graph, with the chain rule through
//! every leaf (engine.md section 2). Memoised per (node, variable); children
//! first in id order, so no recursion.

use crate::graph::{Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::Q;
use crate::poly::Poly;
use crate::poly::Var;
use crate::ratfun::RatFun;
use rustc_hash::FxHashSet;

impl Ctx {
    /// d `id` / d `x`, where `x` is a rational symbol.
    pub fn diff(&mut self, id: Id, x: Var) -> Id {
        if let Some(&d) = self.memo.diff.get(&(id, x)) {
            return d;
        }
        let mut todo = Vec::new();
        let mut seen = FxHashSet::default();
        let mut stack = vec![id];
        while let Some(n) = stack.pop() {
            if self.memo.diff.contains_key(&(n, x)) || !seen.insert(n) {
                continue;
            }
            todo.push(n);
            stack.extend(self.deps(n));
        }
        todo.sort_unstable();
        for n in todo {
            let d = self.diff_node(n, x);
            if crate::budget::tripped() {
                // A placeholder: never memoise it (the budgeted caller discards it).
                return d;
            }
            self.memo.diff.insert((n, x), d);
        }
        self.memo.diff[&(id, x)]
    }

    fn d(&self, n: Id, x: Var) -> Id {
        self.memo.diff[&(n, x)]
    }

    fn diff_node(&mut self, n: Id, x: Var) -> Id {
        match self.node(n).clone() {
            Node::Num(_) => self.zero(),
            Node::Add(cs) => {
                let ds: Vec<Id> = cs
                    .iter()
                    .map(|&c| self.d(c, x))
                    .filter(|&d| !self.is_zero(d))
                    .collect();
                self.add(&ds)
            }
            Node::Mul(cs) => {
                let mut terms = Vec::new();
                for (i, &c) in cs.iter().enumerate() {
                    let dc = self.d(c, x);
                    if self.is_zero(dc) {
                        continue;
                    }
                    let mut f: Vec<Id> = cs
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, &y)| y)
                        .collect();
                    f.push(dc);
                    terms.push(self.mul(&f));
                }
                self.add(&terms)
            }
            Node::Pow(b, e) => {
                let db = self.d(b, x);
                if self.is_zero(db) {
                    return self.zero();
                }
                let k = self.int(e as i64);
                let p = self.pow(b, e as i64 - 1);
                self.mul(&[k, p, db])
            }
            Node::Leaf(v) => self.diff_leaf(v, x),
        }
    }

    fn diff_leaf(&mut self, v: Var, x: Var) -> Id {
        let leaf = self.leaves[v as usize].clone();
        let node = leaf.node;
        match leaf.kind {
            LeafKind::Symbol(_) => {
                if v == x {
                    self.one()
                } else {
                    self.zero()
                }
            }
            LeafKind::Pi => self.zero(),
            LeafKind::Sin(a) | LeafKind::Cos(a) => {
                let is_sin = matches!(self.leaves[v as usize].kind, LeafKind::Sin(_));
                let partner = self.leaf_node(crate::budget::invariant(
                    leaf.partner,
                    "angle leaves come in pairs",
                ));
                let darg = self.angle_darg(&a, x);
                if self.is_zero(darg) {
                    return self.zero();
                }
                let p = if is_sin { partner } else { self.neg(partner) };
                self.mul(&[p, darg])
            }
            LeafKind::Exp(a) => {
                let darg = self.angle_darg(&a, x);
                self.mul(&[node, darg])
            }
            LeafKind::Atan(u) => {
                let du = self.d(u, x);
                if self.is_zero(du) {
                    return self.zero();
                }
                let one = self.one();
                let u2 = self.pow(u, 2);
                let den = self.add(&[one, u2]);
                self.div(du, den)
            }
            LeafKind::Atan2(y, xx) => {
                let (dy, dx) = (self.d(y, x), self.d(xx, x));
                if self.is_zero(dy) && self.is_zero(dx) {
                    return self.zero();
                }
                let a = self.mul(&[xx, dy]);
                let b = self.mul(&[y, dx]);
                let num = self.sub(a, b);
                let x2 = self.pow(xx, 2);
                let y2 = self.pow(y, 2);
                let den = self.add(&[x2, y2]);
                self.div(num, den)
            }
            LeafKind::Log(u) => {
                let du = self.d(u, x);
                if self.is_zero(du) {
                    return self.zero();
                }
                self.div(du, u)
            }
            LeafKind::Root(u, 2) => {
                let du = self.d(u, x);
                if self.is_zero(du) {
                    return self.zero();
                }
                let half = self.num(Q::new(1.into(), 2.into()));
                let inv = self.pow(node, -1);
                self.mul(&[half, du, inv])
            }
            LeafKind::Root(u, q) => {
                // r^q = u: q r^(q-1) r' = u', so r' = r u' / (q u).
                let du = self.d(u, x);
                if self.is_zero(du) {
                    return self.zero();
                }
                let k = self.num(Q::new(1.into(), (q as i64).into()));
                let inv_u = self.pow(u, -1);
                self.mul(&[k, du, node, inv_u])
            }
        }
    }

    /// Derivative of the argument of an angle or exponential leaf.
    fn angle_darg(&mut self, a: &Angle, x: Var) -> Id {
        match a {
            Angle::Symbol { sym, den } => {
                if *sym == x {
                    self.num(Q::new(1.into(), (*den as i64).into()))
                } else {
                    self.zero()
                }
            }
            Angle::Generic(arg) => self.d(*arg, x),
        }
    }

    /// Lie derivative `L_f g = grad(g) . f` (eq. 7) along the field `f`, given
    /// as one node per state variable.
    pub fn lie_derivative(&mut self, g: Id, states: &[Var], f: &[Id]) -> Id {
        assert_eq!(states.len(), f.len(), "field and state lengths differ");
        let mut terms = Vec::with_capacity(states.len());
        for (&x, &fx) in states.iter().zip(f) {
            if self.is_zero(fx) {
                continue;
            }
            let d = self.diff(g, x);
            if self.is_zero(d) {
                continue;
            }
            terms.push(self.mul(&[d, fx]));
        }
        self.add(&terms)
    }
}

impl Ctx {
    /// d/dx of a canonical form, computed on the form itself (quotient rule,
    /// chain rule through the leaves); the result is canonical. Much cheaper
    /// than canonicalising a differentiated graph node by node.
    pub fn rf_diff(&mut self, r: &RatFun, x: Var) -> RatFun {
        let dn = self.poly_diff(&r.num, x);
        if r.den.is_one() {
            return dn;
        }
        let dd = self.poly_diff(&r.den, x);
        if dn.is_zero() && dd.is_zero() {
            return RatFun::zero();
        }
        let num = RatFun {
            num: r.num.clone(),
            den: Poly::one(),
        };
        if dd.den.is_one() {
            // With g = gcd(D, D'), D = g D1, D' = g E:
            // (N' D - N D')/D^2 = (N' D1 - N E)/(D D1); the rest rarely cancels.
            let g = crate::gcd::gcd(&r.den, &dd.num);
            let d1 = crate::budget::invariant(r.den.div_exact(&g), "gcd divides");
            let e = crate::budget::invariant(dd.num.div_exact(&g), "gcd divides");
            let a = self.rf_mul(
                &dn,
                &RatFun {
                    num: d1.clone(),
                    den: Poly::one(),
                },
            );
            let b = self.rf_mul(
                &num,
                &RatFun {
                    num: e,
                    den: Poly::one(),
                },
            );
            let top = self.rf_sub(&a, &b);
            let inv = RatFun {
                num: Poly::one(),
                den: r.den.mul(&d1),
            };
            return self.rf_mul(&top, &inv);
        }
        let den = RatFun {
            num: r.den.clone(),
            den: Poly::one(),
        };
        let a = self.rf_mul(&dn, &den);
        let b = self.rf_mul(&num, &dd);
        let top = self.rf_sub(&a, &b);
        let inv = RatFun {
            num: Poly::one(),
            den: r.den.mul(&r.den),
        };
        self.rf_mul(&top, &inv)
    }

    /// d/dx of a polynomial in the leaves, as a canonical form.
    fn poly_diff(&mut self, p: &Poly, x: Var) -> RatFun {
        let mut poly_part = Poly::zero();
        let mut rat_part = RatFun::zero();
        for v in p.vars() {
            let lv = self.leaf_derivative_rf(v, x);
            if lv.is_zero() {
                continue;
            }
            let dv = p.derivative(v);
            if lv.den.is_one() {
                poly_part = poly_part.add(&dv.mul(&lv.num));
            } else {
                let t = self.rf_mul(
                    &RatFun {
                        num: dv,
                        den: Poly::one(),
                    },
                    &lv,
                );
                rat_part = self.rf_add(&rat_part, &t);
            }
        }
        let pp = self.normalize(poly_part, Poly::one());
        self.rf_add(&pp, &rat_part)
    }

    /// d(leaf v)/dx in canonical form (memoised through the graph's memo tables).
    fn leaf_derivative_rf(&mut self, v: Var, x: Var) -> RatFun {
        if let LeafKind::Symbol(_) = self.leaves[v as usize].kind {
            return if v == x {
                RatFun::one()
            } else {
                RatFun::zero()
            };
        }
        let n = self.leaf_node(v);
        let d = self.diff(n, x);
        self.canon(d)
    }

    /// Lie derivative on canonical forms: `sum_i d g/d x_i f_i` (eq. 7).
    pub fn rf_lie_derivative(&mut self, g: &RatFun, states: &[Var], f: &[RatFun]) -> RatFun {
        let mut acc = RatFun::zero();
        for (&x, fx) in states.iter().zip(f) {
            if fx.is_zero() {
                continue;
            }
            let d = self.rf_diff(g, x);
            if d.is_zero() {
                continue;
            }
            let t = self.rf_mul(&d, fx);
            acc = self.rf_add(&acc, &t);
        }
        acc
    }
}
