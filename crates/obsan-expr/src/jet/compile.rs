//! Compilation of the fields and outputs into straight-line programs over
//! the DAG, with the grade-0 degree bound of every op (module docs of
//! [`super`]: bases and `Deg`).

use crate::graph::{Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::Fp;
use crate::poly::Var;
use rustc_hash::FxHashMap;

/// `P / prod_b B_b^e[b]` with `deg P <= n` (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Deg {
    pub(super) n: u64,
    pub(super) e: Vec<u32>,
}

impl Deg {
    pub(super) fn poly(n: u64) -> Deg {
        Deg { n, e: Vec::new() }
    }
}

/// The degrees of the bases.
#[derive(Clone, Debug, Default)]
pub(super) struct Bases {
    pub(super) deg: Vec<u64>,
}

impl Bases {
    pub(super) fn mul(&self, a: &Deg, b: &Deg) -> Deg {
        let len = a.e.len().max(b.e.len());
        let e = (0..len)
            .map(|i| {
                a.e.get(i)
                    .copied()
                    .unwrap_or(0)
                    .saturating_add(b.e.get(i).copied().unwrap_or(0))
            })
            .collect();
        Deg {
            n: a.n.saturating_add(b.n),
            e,
        }
    }
    /// A bound for the sum (and so for either summand): common denominator.
    pub(super) fn add(&self, a: &Deg, b: &Deg) -> Deg {
        let len = a.e.len().max(b.e.len());
        let mut e = Vec::with_capacity(len);
        let (mut ra, mut rb) = (a.n, b.n);
        for i in 0..len {
            let (x, y) = (
                a.e.get(i).copied().unwrap_or(0),
                b.e.get(i).copied().unwrap_or(0),
            );
            let m = x.max(y);
            ra = ra.saturating_add(((m - x) as u64).saturating_mul(self.deg[i]));
            rb = rb.saturating_add(((m - y) as u64).saturating_mul(self.deg[i]));
            e.push(m);
        }
        Deg { n: ra.max(rb), e }
    }
    /// The bound of `1 / v` for `v` bounded by `d`: `prod B^e / P`, P a new base.
    fn register_inverse(&mut self, d: &Deg) -> Deg {
        let n =
            d.e.iter()
                .zip(&self.deg)
                .map(|(&e, &g)| (e as u64).saturating_mul(g))
                .fold(0u64, u64::saturating_add);
        self.deg.push(d.n);
        let mut e = vec![0; self.deg.len()];
        e[self.deg.len() - 1] = 1;
        Deg { n, e }
    }
}

/// One op of a compiled program; arguments are indices of earlier ops.
#[derive(Clone, Debug)]
pub(super) enum Op {
    Const(Fp),
    /// A rational number with no value mod p.
    NoValue,
    /// The k-th state variable.
    State(usize),
    /// A leaf that is constant here (a symbol outside the state, pi, or an
    /// angle or exponential of such a symbol): its value at the point.
    Fixed(Var),
    Add(Vec<u32>),
    /// A binary product (products of more factors and powers are chains of
    /// them).
    Mul(u32, u32),
    /// `1/x`, with the bound of `1/x`.
    Inv(u32, usize),
    /// `exp(a)`, `sin(a)`, `cos(a)` with the argument `a = arg / den`.
    Exp(Var, u32, u64),
    /// With the partner leaf (cos of a sin leaf, sin of a cos leaf).
    Sin(Var, Var, u32, u64),
    Cos(Var, Var, u32, u64),
    /// `atan(u)`, with the bound index of `1/(1 + u^2)`.
    Atan(Var, u32, usize),
    /// `atan2(y, x)`, with the bound index of `1/(x^2 + y^2)`.
    Atan2(Var, u32, u32, usize),
    /// `log(u)`, `root_q(u)` (`sqrt`: q = 2), with the bound index of `1/u`.
    Log(Var, u32, usize),
    Root(Var, u32, usize, u32),
}

/// A compiled set of roots.
#[derive(Clone, Debug)]
pub(super) struct Program {
    pub(super) ops: Vec<Op>,
    /// Bound of each op's value at the point (grade 0).
    pub(super) deg0: Vec<Deg>,
    pub(super) roots: Vec<u32>,
}

pub(super) struct Compiler<'a> {
    pub(super) ctx: &'a Ctx,
    pub(super) states: &'a [Var],
    pub(super) bases: Bases,
    pub(super) inverses: Vec<Deg>,
    /// The base `1 + t^2` of each angle pair, by its sin leaf.
    pub(super) sin_base: FxHashMap<Var, usize>,
}

impl Compiler<'_> {
    fn inverse(&mut self, d: &Deg) -> usize {
        let inv = self.bases.register_inverse(d);
        self.inverses.push(inv);
        self.inverses.len() - 1
    }

    /// A binary product op (its bound is the product of the bounds).
    fn mul2(&mut self, ops: &mut Vec<Op>, deg0: &mut Vec<Deg>, a: u32, b: u32) -> u32 {
        let d = self.bases.mul(&deg0[a as usize], &deg0[b as usize]);
        ops.push(Op::Mul(a, b));
        deg0.push(d);
        (ops.len() - 1) as u32
    }

    /// A product of several factors as a chain of binary products, left to
    /// right: the series ops then hold every partial product, so a Picard
    /// pass can compute only its new coefficients of each (see
    /// [`super::series`]). The bounds are those of the n-ary fold.
    fn product(&mut self, ops: &mut Vec<Op>, deg0: &mut Vec<Deg>, args: &[u32]) -> u32 {
        let mut acc = args[0];
        for &c in &args[1..] {
            acc = self.mul2(ops, deg0, acc, c);
        }
        acc
    }

    /// `x^k`, k >= 1, as binary products by squaring (the order of the
    /// bounds' `pow`).
    fn power(&mut self, ops: &mut Vec<Op>, deg0: &mut Vec<Deg>, x: u32, mut k: u32) -> u32 {
        let (mut acc, mut b) = (None, x);
        loop {
            if k & 1 == 1 {
                acc = Some(match acc {
                    None => b,
                    Some(a) => self.mul2(ops, deg0, a, b),
                });
            }
            k >>= 1;
            if k == 0 {
                break;
            }
            b = self.mul2(ops, deg0, b, b);
        }
        acc.unwrap_or(x)
    }

    pub(super) fn compile(&mut self, roots: &[Id]) -> Program {
        let ctx = self.ctx;
        let order = ctx.reachable(roots);
        let mut local: FxHashMap<Id, u32> = FxHashMap::default();
        let mut ops = Vec::with_capacity(order.len());
        let mut deg0: Vec<Deg> = Vec::with_capacity(order.len());
        for &id in &order {
            let l = |x: Id| local[&x];
            let (op, d) = match ctx.node(id) {
                Node::Num(q) => match q.to_fp() {
                    Some(v) => (Op::Const(v), Deg::poly(0)),
                    // A denominator divisible by p: no point is good.
                    None => (Op::NoValue, Deg::poly(0)),
                },
                Node::Add(cs) => {
                    let d = cs
                        .iter()
                        .skip(1)
                        .fold(deg0[l(cs[0]) as usize].clone(), |a, c| {
                            self.bases.add(&a, &deg0[l(*c) as usize])
                        });
                    (Op::Add(cs.iter().map(|&c| l(c)).collect()), d)
                }
                Node::Mul(cs) => {
                    let args: Vec<u32> = cs.iter().map(|&c| l(c)).collect();
                    let top = self.product(&mut ops, &mut deg0, &args);
                    local.insert(id, top);
                    continue;
                }
                Node::Pow(b, e) => {
                    let k = e.unsigned_abs();
                    let mut base = l(*b);
                    if *e < 0 {
                        let idx = self.inverse(&deg0[base as usize].clone());
                        ops.push(Op::Inv(base, idx));
                        deg0.push(self.inverses[idx].clone());
                        base = (ops.len() - 1) as u32;
                    }
                    let top = self.power(&mut ops, &mut deg0, base, k);
                    local.insert(id, top);
                    continue;
                }
                Node::Leaf(v) => self.leaf(*v, &l, &deg0),
            };
            local.insert(id, ops.len() as u32);
            ops.push(op);
            deg0.push(d);
        }
        let roots = roots.iter().map(|r| local[r]).collect();
        Program { ops, deg0, roots }
    }

    fn leaf(&mut self, v: Var, l: &dyn Fn(Id) -> u32, deg0: &[Deg]) -> (Op, Deg) {
        let ctx = self.ctx;
        let leaf = &ctx.leaves[v as usize];
        let angle = |a: &Angle| match a {
            Angle::Symbol { sym, den } => (l(ctx.leaf_node(*sym)), *den as u64),
            Angle::Generic(g) => (l(*g), 1),
        };
        match &leaf.kind {
            LeafKind::Symbol(_) => match self.states.iter().position(|x| *x == v) {
                Some(k) => (Op::State(k), Deg::poly(1)),
                None => (Op::Fixed(v), Deg::poly(1)),
            },
            LeafKind::Pi => (Op::Fixed(v), Deg::poly(1)),
            LeafKind::Exp(a) => {
                let (arg, den) = angle(a);
                (Op::Exp(v, arg, den), Deg::poly(1))
            }
            LeafKind::Sin(a) | LeafKind::Cos(a) => {
                let partner = leaf.partner.unwrap_or(v);
                let key = v.min(partner);
                let b = match self.sin_base.get(&key) {
                    Some(&b) => b,
                    None => {
                        self.bases.deg.push(2);
                        let b = self.bases.deg.len() - 1;
                        self.sin_base.insert(key, b);
                        b
                    }
                };
                let mut e = vec![0; b + 1];
                e[b] = 1;
                let (arg, den) = angle(a);
                let op = if matches!(leaf.kind, LeafKind::Sin(_)) {
                    Op::Sin(v, partner, arg, den)
                } else {
                    Op::Cos(v, partner, arg, den)
                };
                (op, Deg { n: 2, e })
            }
            LeafKind::Atan(u) => {
                let du = &deg0[l(*u) as usize];
                let sq = self.bases.mul(du, du);
                let d = self.bases.add(&Deg::poly(0), &sq);
                (Op::Atan(v, l(*u), self.inverse(&d)), Deg::poly(1))
            }
            LeafKind::Atan2(y, x) => {
                let (dy, dx) = (&deg0[l(*y) as usize], &deg0[l(*x) as usize]);
                let d = self
                    .bases
                    .add(&self.bases.mul(dx, dx), &self.bases.mul(dy, dy));
                (Op::Atan2(v, l(*y), l(*x), self.inverse(&d)), Deg::poly(1))
            }
            LeafKind::Log(u) => {
                let d = deg0[l(*u) as usize].clone();
                (Op::Log(v, l(*u), self.inverse(&d)), Deg::poly(1))
            }
            LeafKind::Root(u, q) => {
                // The convention of `degree_bounds` for a root.
                let count = |p: &crate::poly::Poly| {
                    p.terms()
                        .iter()
                        .map(|(m, _)| m.iter().map(|(_, e)| *q as u64 * e as u64).sum::<u64>())
                        .max()
                        .unwrap_or(0)
                };
                let n = ctx.radicand(v).map_or(0, |r| count(&r.num) + count(&r.den));
                let d = deg0[l(*u) as usize].clone();
                (Op::Root(v, l(*u), self.inverse(&d), *q), Deg::poly(n))
            }
        }
    }
}
