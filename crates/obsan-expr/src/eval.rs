//! Evaluation of expression graphs: compiled f64 tapes (compile once,
//! evaluate many times), exact rationals, and F_p at random points with the
//! angle parametrisation of engine.md section 3.

use crate::graph::{Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::{Fp, SplitMix, Q};
use crate::poly::Var;
use std::fmt;
use std::ops::{Add, Mul, Sub};

#[derive(Clone, Debug)]
enum Op {
    Const(f64),
    Input(u32),
    Add2(u32, u32),
    Mul2(u32, u32),
    /// Children `args[start..start + len]` of the tape's flat argument list.
    Add(u32, u32),
    Mul(u32, u32),
    Square(u32),
    Pow(u32, i32),
    Sin(u32, f64),
    Cos(u32, f64),
    Exp(u32, f64),
    Atan(u32),
    Atan2(u32, u32),
    Log(u32),
    Sqrt(u32),
    /// `u^(1/q)` (`powf`, NaN below 0 as `sqrt`), with `1/q`.
    Root(u32, f64),
}

/// A compiled f64 evaluator for a set of expressions.
#[derive(Clone, Debug)]
pub struct Tape {
    ops: Vec<Op>,
    /// Children of the n-ary sums and products, flat (no box per op).
    args: Vec<u32>,
    outputs: Vec<u32>,
    n_inputs: usize,
}

/// A symbol the tape needs but was not given an input slot.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnboundSymbol(pub String);

impl fmt::Display for UnboundSymbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "no value given for symbol {}", self.0)
    }
}
impl std::error::Error for UnboundSymbol {}

impl Tape {
    /// Compile `roots` with input slots for the symbols `inputs`, in that order.
    pub fn compile(ctx: &Ctx, roots: &[Id], inputs: &[Var]) -> Result<Tape, UnboundSymbol> {
        let order = ctx.reachable(roots);
        let mut slot = vec![u32::MAX; ctx.len()];
        let mut ops = Vec::with_capacity(order.len());
        let mut args = Vec::new();
        for (i, &id) in order.iter().enumerate() {
            slot[id.index()] = i as u32;
            let s = |x: Id| {
                debug_assert!(slot[x.index()] != u32::MAX, "child compiled after parent");
                slot[x.index()]
            };
            let op = match ctx.node(id) {
                Node::Num(q) => Op::Const(q.to_f64()),
                Node::Add(cs) if cs.len() == 2 => Op::Add2(s(cs[0]), s(cs[1])),
                Node::Mul(cs) if cs.len() == 2 => Op::Mul2(s(cs[0]), s(cs[1])),
                Node::Add(cs) | Node::Mul(cs) => {
                    // Fits: the arena stores every child id (4 bytes) too, and
                    // 2^32 of them would take 16 GB before a tape is compiled.
                    let start = args.len() as u32;
                    args.extend(cs.iter().map(|&c| s(c)));
                    let len = cs.len() as u32;
                    if matches!(ctx.node(id), Node::Add(_)) {
                        Op::Add(start, len)
                    } else {
                        Op::Mul(start, len)
                    }
                }
                Node::Pow(b, 2) => Op::Square(s(*b)),
                Node::Pow(b, e) => Op::Pow(s(*b), *e),
                Node::Leaf(v) => match &ctx.leaves[*v as usize].kind {
                    LeafKind::Symbol(name) => match inputs.iter().position(|x| x == v) {
                        Some(k) => Op::Input(k as u32),
                        None => return Err(UnboundSymbol(name.clone())),
                    },
                    LeafKind::Pi => Op::Const(std::f64::consts::PI),
                    LeafKind::Sin(a) | LeafKind::Cos(a) | LeafKind::Exp(a) => {
                        let (arg, scale) = match a {
                            Angle::Symbol { sym, den } => {
                                (s(ctx.leaf_node(*sym)), 1.0 / *den as f64)
                            }
                            Angle::Generic(g) => (s(*g), 1.0),
                        };
                        match &ctx.leaves[*v as usize].kind {
                            LeafKind::Sin(_) => Op::Sin(arg, scale),
                            LeafKind::Cos(_) => Op::Cos(arg, scale),
                            _ => Op::Exp(arg, scale),
                        }
                    }
                    LeafKind::Atan(u) => Op::Atan(s(*u)),
                    LeafKind::Atan2(y, x) => Op::Atan2(s(*y), s(*x)),
                    LeafKind::Log(u) => Op::Log(s(*u)),
                    LeafKind::Root(u, 2) => Op::Sqrt(s(*u)),
                    LeafKind::Root(u, q) => Op::Root(s(*u), 1.0 / *q as f64),
                },
            };
            ops.push(op);
        }
        let outputs = roots.iter().map(|r| slot[r.index()]).collect();
        Ok(Tape {
            ops,
            args,
            outputs,
            n_inputs: inputs.len(),
        })
    }

    pub fn n_inputs(&self) -> usize {
        self.n_inputs
    }
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }
    pub fn len(&self) -> usize {
        self.ops.len()
    }
    pub fn is_empty(&self) -> bool {
        self.ops.is_empty()
    }

    /// Evaluate; `scratch` is reused between calls to avoid allocation.
    pub fn eval_into(&self, inputs: &[f64], scratch: &mut Vec<f64>, out: &mut [f64]) {
        assert_eq!(inputs.len(), self.n_inputs, "wrong number of inputs");
        scratch.clear();
        scratch.resize(self.ops.len(), 0.0);
        for (i, op) in self.ops.iter().enumerate() {
            scratch[i] = op.eval(inputs, scratch, &self.args);
        }
        for (o, &s) in out.iter_mut().zip(&self.outputs) {
            *o = scratch[s as usize];
        }
    }

    pub fn eval(&self, inputs: &[f64]) -> Vec<f64> {
        let mut scratch = Vec::new();
        let mut out = vec![0.0; self.outputs.len()];
        self.eval_into(inputs, &mut scratch, &mut out);
        out
    }

    /// This tape with the inputs not flagged in `varying` fixed at their
    /// values in `inputs`: every op that does not depend on a varying input
    /// is evaluated here, once (e.g. `sin(phi)` of a parameter while only the
    /// state changes along an integration).
    pub fn freeze(&self, inputs: &[f64], varying: &[bool]) -> FrozenTape<'_> {
        assert_eq!(inputs.len(), self.n_inputs, "wrong number of inputs");
        assert_eq!(varying.len(), self.n_inputs, "one flag per input");
        let mut values = Vec::new();
        let mut out = vec![0.0; self.outputs.len()];
        self.eval_into(inputs, &mut values, &mut out);
        let mut depends = vec![false; self.ops.len()];
        let mut ops = Vec::new();
        for (i, op) in self.ops.iter().enumerate() {
            let d = match op {
                Op::Const(_) => false,
                Op::Input(k) => varying[*k as usize],
                Op::Add2(a, b) | Op::Mul2(a, b) => depends[*a as usize] || depends[*b as usize],
                Op::Add(st, len) | Op::Mul(st, len) => self.args
                    [*st as usize..(*st + *len) as usize]
                    .iter()
                    .any(|&c| depends[c as usize]),
                Op::Square(a)
                | Op::Pow(a, _)
                | Op::Sin(a, _)
                | Op::Cos(a, _)
                | Op::Exp(a, _)
                | Op::Atan(a)
                | Op::Log(a)
                | Op::Sqrt(a)
                | Op::Root(a, _) => depends[*a as usize],
                Op::Atan2(y, x) => depends[*y as usize] || depends[*x as usize],
            };
            depends[i] = d;
            if d {
                ops.push(i as u32);
            }
        }
        FrozenTape {
            tape: self,
            ops,
            values,
            out,
        }
    }
}

impl Op {
    /// The value of this op given the values of the earlier ops.
    #[inline]
    fn eval(&self, inputs: &[f64], before: &[f64], args: &[u32]) -> f64 {
        let v = |i: &u32| before[*i as usize];
        let children = |st: u32, len: u32| &args[st as usize..(st + len) as usize];
        match self {
            Op::Const(c) => *c,
            Op::Input(k) => inputs[*k as usize],
            Op::Add2(a, b) => v(a) + v(b),
            Op::Mul2(a, b) => v(a) * v(b),
            Op::Add(st, len) => children(*st, *len).iter().map(v).sum(),
            Op::Mul(st, len) => children(*st, *len).iter().map(v).product(),
            Op::Square(b) => v(b) * v(b),
            Op::Pow(b, e) => v(b).powi(*e),
            Op::Sin(a, k) => (v(a) * k).sin(),
            Op::Cos(a, k) => (v(a) * k).cos(),
            Op::Exp(a, k) => (v(a) * k).exp(),
            Op::Atan(a) => v(a).atan(),
            Op::Atan2(y, x) => v(y).atan2(v(x)),
            Op::Log(a) => v(a).ln(),
            Op::Sqrt(a) => v(a).sqrt(),
            Op::Root(a, k) => v(a).powf(*k),
        }
    }
}

/// A [`Tape`] partially evaluated at fixed values of some inputs
/// ([`Tape::freeze`]); each evaluation recomputes only the ops that depend on
/// the varying inputs.
#[derive(Clone, Debug)]
pub struct FrozenTape<'a> {
    tape: &'a Tape,
    /// Indices of the ops to recompute, in tape order (children first).
    ops: Vec<u32>,
    /// The value of every op at the last evaluation.
    values: Vec<f64>,
    out: Vec<f64>,
}

impl FrozenTape<'_> {
    /// Evaluate at `inputs` (all inputs; only the varying ones are read)
    /// and return the outputs.
    pub fn eval(&mut self, inputs: &[f64]) -> &[f64] {
        assert_eq!(inputs.len(), self.tape.n_inputs, "wrong number of inputs");
        for &i in &self.ops {
            let x = self.tape.ops[i as usize].eval(inputs, &self.values, &self.tape.args);
            self.values[i as usize] = x;
        }
        for (o, &s) in self.out.iter_mut().zip(&self.tape.outputs) {
            *o = self.values[s as usize];
        }
        &self.out
    }

    /// Number of ops recomputed per evaluation (the tape has [`Tape::len`]).
    pub fn n_varying_ops(&self) -> usize {
        self.ops.len()
    }
}

/// The chosen point was a zero of a denominator or gave a non-square under a
/// root: pick another point (probability at most `degree / p`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadPoint;

impl fmt::Display for BadPoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the evaluation point hit a pole or a non-square radicand")
    }
}
impl std::error::Error for BadPoint {}

/// Values in F_p for every leaf of a context, consistent with the relations:
/// `sin`/`cos` from `t` as `2t/(1+t^2)`, `(1-t^2)/(1+t^2)` (1 + t^2 is never 0
/// since -1 is not a square mod 2^61 - 1), square roots by Tonelli–Shanks,
/// every transcendental atom independent and uniform.
#[derive(Clone, Debug)]
pub struct FpPoint {
    pub(crate) values: Vec<Fp>,
    /// Leaves with no value at this point ([`Ctx::random_fp_point_root_free`]):
    /// `eval_fp` and the jets fail on an expression that reaches one. Empty
    /// for every other point.
    pub(crate) forbidden: Vec<bool>,
}

impl FpPoint {
    /// The value of leaf `v`. At a root-free point a root leaf reads 0 here:
    /// evaluate through [`Ctx::eval_fp`] or the jets, which refuse it.
    pub fn value(&self, v: Var) -> Fp {
        self.values[v as usize]
    }
    /// Whether some leaf has no value ([`Ctx::random_fp_point_root_free`]).
    pub fn has_forbidden(&self) -> bool {
        self.forbidden.iter().any(|&f| f)
    }
    fn forbids(&self, v: Var) -> bool {
        self.forbidden.get(v as usize).copied().unwrap_or(false)
    }
}

/// What a random point gives the root leaves.
#[derive(Clone, Copy, PartialEq, Eq)]
enum RootValues {
    Zero,
    Roots,
    Free,
    /// No value: the point knows the other leaves only.
    Forbidden,
}

impl Ctx {
    /// A random point; `fixed` gives values of some symbols (others are uniform).
    pub fn random_fp_point(
        &mut self,
        rng: &mut SplitMix,
        fixed: &dyn Fn(Var) -> Option<Fp>,
    ) -> Result<FpPoint, BadPoint> {
        self.random_point(rng, fixed, true)
    }

    /// A random point where every root leaf (`sqrt`, `root_q`) takes a free
    /// uniform value instead of a root of its radicand: values of the system
    /// with the roots independent of their radicands (a constant multiple of
    /// each root, `r = mu root_q(u)`, is one such family; the derivative rule
    /// `r' = r u'/(q u)` holds for all of it), whose generic rank bounds the
    /// true one from above. For radicands no point satisfies together mod p
    /// (`sqrt(3) x`: 3 is no square mod 2^61 - 1).
    pub fn random_fp_point_free_roots(
        &mut self,
        rng: &mut SplitMix,
        fixed: &dyn Fn(Var) -> Option<Fp>,
    ) -> Result<FpPoint, BadPoint> {
        self.random_point_mode(rng, fixed, RootValues::Free)
    }

    /// A random point where every root leaf has no value: [`Ctx::eval_fp`]
    /// (and the jets) fail with `BadPoint` on any expression that reaches
    /// one, so what does evaluate is exact and free of the roots. For
    /// radicands no point satisfies together mod p (BIG's `sqrt(7)`), where
    /// the expressions a computation needs avoid the roots.
    pub fn random_fp_point_root_free(
        &mut self,
        rng: &mut SplitMix,
        fixed: &dyn Fn(Var) -> Option<Fp>,
    ) -> Result<FpPoint, BadPoint> {
        self.random_point_mode(rng, fixed, RootValues::Forbidden)
    }

    /// A random point; with `roots` false every `sqrt` leaf is 0 (for roots
    /// that reach no square root: a non-square radicand is then no `BadPoint`).
    pub(crate) fn random_point(
        &mut self,
        rng: &mut SplitMix,
        fixed: &dyn Fn(Var) -> Option<Fp>,
        roots: bool,
    ) -> Result<FpPoint, BadPoint> {
        let mode = if roots {
            RootValues::Roots
        } else {
            RootValues::Zero
        };
        self.random_point_mode(rng, fixed, mode)
    }

    fn random_point_mode(
        &mut self,
        rng: &mut SplitMix,
        fixed: &dyn Fn(Var) -> Option<Fp>,
        mode: RootValues,
    ) -> Result<FpPoint, BadPoint> {
        let mut values = vec![Fp::ZERO; self.leaves.len()];
        let mut forbidden = Vec::new();
        let mut done = vec![false; self.leaves.len()];
        for v in 0..self.leaves.len() {
            if done[v] {
                continue;
            }
            let leaf = self.leaves[v].clone();
            match &leaf.kind {
                LeafKind::Symbol(_) => values[v] = fixed(v as Var).unwrap_or_else(|| rng.fp()),
                LeafKind::Sin(_) | LeafKind::Cos(_) => {
                    let t = rng.fp();
                    let t2 = t.mul(t);
                    let inv = Fp::ONE.add(t2).inv().ok_or(BadPoint)?;
                    let s = Fp(2).mul(t).mul(inv);
                    let c = Fp::ONE.sub(t2).mul(inv);
                    let p = leaf.partner.ok_or(BadPoint)? as usize;
                    let is_sin = matches!(leaf.kind, LeafKind::Sin(_));
                    values[v] = if is_sin { s } else { c };
                    values[p] = if is_sin { c } else { s };
                    done[p] = true;
                }
                LeafKind::Root(..) if mode == RootValues::Zero => values[v] = Fp::ZERO,
                LeafKind::Root(..) if mode == RootValues::Free => values[v] = rng.fp(),
                LeafKind::Root(..) if mode == RootValues::Forbidden => {
                    forbidden.resize(self.leaves.len(), false);
                    forbidden[v] = true;
                }
                LeafKind::Root(_, q) => {
                    let r = self.radicand(v as Var).ok_or(BadPoint)?;
                    let val = |x: Var| values[x as usize];
                    let n = r.num.eval_fp(&val);
                    let d = r.den.eval_fp(&val);
                    let u = n.mul(d.inv().ok_or(BadPoint)?);
                    values[v] = u.root(*q).ok_or(BadPoint)?;
                }
                _ => values[v] = rng.fp(),
            }
            done[v] = true;
        }
        Ok(FpPoint { values, forbidden })
    }

    /// Values of `roots` at an F_p point.
    pub fn eval_fp(&self, roots: &[Id], point: &FpPoint) -> Result<Vec<Fp>, BadPoint> {
        let order = self.reachable(roots);
        let mut val = vec![Fp::ZERO; self.len()];
        for id in order {
            let x = match self.node(id) {
                Node::Num(q) => q.to_fp().ok_or(BadPoint)?,
                Node::Leaf(v) if point.forbids(*v) => return Err(BadPoint),
                Node::Leaf(v) => point.value(*v),
                Node::Add(cs) => cs.iter().fold(Fp::ZERO, |a, c| a.add(val[c.index()])),
                Node::Mul(cs) => cs.iter().fold(Fp::ONE, |a, c| a.mul(val[c.index()])),
                Node::Pow(b, e) => {
                    let base = val[b.index()];
                    let base = if *e < 0 {
                        base.inv().ok_or(BadPoint)?
                    } else {
                        base
                    };
                    base.pow(e.unsigned_abs() as u64)
                }
            };
            val[id.index()] = x;
        }
        Ok(roots.iter().map(|r| val[r.index()]).collect())
    }

    /// Exact value of `roots` given a rational value for every leaf they use
    /// (leaf values must respect the relations, e.g. from [`rational_angle`]).
    pub fn eval_q(
        &self,
        roots: &[Id],
        leaf: &dyn Fn(Var) -> Option<Q>,
    ) -> Result<Vec<Q>, EvalQError> {
        let order = self.reachable_with(roots, false);
        let mut val: Vec<Option<Q>> = vec![None; self.len()];
        for id in order {
            // Children come first in `order`, so their values are set.
            let get = |c: &Id| val[c.index()].clone().unwrap_or_else(Q::zero);
            let x = match self.node(id) {
                Node::Num(q) => q.clone(),
                Node::Leaf(v) => leaf(*v).ok_or(EvalQError::Unbound(*v))?,
                Node::Add(cs) => cs.iter().fold(Q::zero(), |a, c| a.add(&get(c))),
                Node::Mul(cs) => cs.iter().fold(Q::one(), |a, c| a.mul(&get(c))),
                Node::Pow(b, e) => get(b).powi(*e as i64).ok_or(EvalQError::DivisionByZero)?,
            };
            val[id.index()] = Some(x);
        }
        Ok(roots
            .iter()
            .map(|r| val[r.index()].clone().unwrap_or_else(Q::zero))
            .collect())
    }
}

/// Why an exact evaluation failed.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EvalQError {
    Unbound(Var),
    DivisionByZero,
}

/// `(sin, cos)` of the rational angle parameter `t`: `(2t/(1+t^2), (1-t^2)/(1+t^2))`.
pub fn rational_angle(t: &Q) -> (Q, Q) {
    let t2 = t.mul(t);
    let d = Q::one().add(&t2);
    // 1 + t^2 >= 1, so both quotients exist.
    let s = Q::from_i64(2).mul(t).div(&d).unwrap_or_else(Q::zero);
    let c = Q::one().sub(&t2).div(&d).unwrap_or_else(Q::one);
    (s, c)
}

/// Degree bounds `(numerator, denominator)` of expressions as rational
/// functions of the random coordinates of [`Ctx::random_fp_point`]: symbols and
/// transcendental atoms have degree 1, sin/cos leaves are (2, 2) in their
/// parameter t, square roots count their radicand's degrees. Used for the
/// Schwartz–Zippel error bound of probabilistic tests.
pub fn degree_bounds(ctx: &Ctx, roots: &[Id]) -> Vec<(u64, u64)> {
    let order = ctx.reachable(roots);
    let mut deg: Vec<(u64, u64)> = vec![(0, 0); ctx.len()];
    for id in order {
        let d = match ctx.node(id) {
            Node::Num(_) => (0, 0),
            Node::Leaf(v) => match &ctx.leaves[*v as usize].kind {
                LeafKind::Sin(_) | LeafKind::Cos(_) => (2, 2),
                LeafKind::Root(_, q) => {
                    let q = *q as u64;
                    let Some(r) = ctx.radicand(*v) else {
                        return vec![(u64::MAX, u64::MAX); roots.len()];
                    };
                    let leaf_deg = |p: &crate::poly::Poly| {
                        p.terms()
                            .iter()
                            .map(|(m, _)| m.iter().map(|(_, e)| q * e as u64).sum::<u64>())
                            .max()
                            .unwrap_or(0)
                    };
                    (leaf_deg(&r.num) + leaf_deg(&r.den), 0)
                }
                _ => (1, 0),
            },
            Node::Add(cs) => {
                let den: u64 = cs
                    .iter()
                    .map(|c| deg[c.index()].1)
                    .fold(0, u64::saturating_add);
                let num = cs
                    .iter()
                    .map(|c| deg[c.index()].0.saturating_add(den - deg[c.index()].1))
                    .max()
                    .unwrap_or(0);
                (num, den)
            }
            Node::Mul(cs) => cs.iter().fold((0u64, 0u64), |a, c| {
                (
                    a.0.saturating_add(deg[c.index()].0),
                    a.1.saturating_add(deg[c.index()].1),
                )
            }),
            Node::Pow(b, e) => {
                let (n, d) = deg[b.index()];
                let k = e.unsigned_abs() as u64;
                if *e > 0 {
                    (n.saturating_mul(k), d.saturating_mul(k))
                } else {
                    (d.saturating_mul(k), n.saturating_mul(k))
                }
            }
        };
        deg[id.index()] = d;
    }
    roots.iter().map(|r| deg[r.index()]).collect()
}
