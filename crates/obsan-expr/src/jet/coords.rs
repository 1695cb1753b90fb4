//! Coordinates of black-box points (the tangent half-angle view), leaf
//! values and gradients modulo arbitrary primes (the certificates' fresh
//! primes), and coefficient-height bounds.

use crate::eval::{BadPoint, FpPoint};
use crate::graph::{Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::Fp;
use crate::poly::Var;
use obsan_recon::fp;

/// Bounds on the coefficient sizes of `roots` as rational functions of the
/// coordinates of [`Ctx::free_coords`], in the form of [`degree_bounds`]
/// (`P / B` with the common denominators that bound assumes): per root,
/// `(log2 ||P||_1, log2 ||B||_1)` for integer polynomials P and B (the
/// L1 norm of the coefficients, which is submultiplicative). Sin/cos leaves
/// are `2t/(1+t^2)` and `(1-t^2)/(1+t^2)` (1 bit each); other leaves are
/// coordinates (0 bits); a rational constant `a/b` is `|a|` over `|b|`. A
/// square root gives infinity. Used for the chance that a random prime
/// divides the content of a non-zero identity (its content is at most
/// `2^bits`).
///
/// [`degree_bounds`]: crate::evaluate::degree_bounds
pub fn height_bounds(ctx: &Ctx, roots: &[Id]) -> Vec<(f64, f64)> {
    use dashu_int::ops::BitTest;
    let order = ctx.reachable(roots);
    let mut h: Vec<(f64, f64)> = vec![(0.0, 0.0); ctx.len()];
    for id in order {
        let x = match ctx.node(id) {
            Node::Num(q) => (q.num().bit_len() as f64, q.den().bit_len() as f64),
            Node::Leaf(v) => match &ctx.leaves[*v as usize].kind {
                LeafKind::Sin(_) | LeafKind::Cos(_) => (1.0, 1.0),
                LeafKind::Root(..) => (f64::INFINITY, f64::INFINITY),
                _ => (0.0, 0.0),
            },
            Node::Add(cs) => {
                // sum_c P_c prod_{d != c} B_d over prod_d B_d.
                let den: f64 = cs.iter().map(|c| h[c.index()].1).sum();
                let top = cs
                    .iter()
                    .map(|c| h[c.index()].0 + den - h[c.index()].1)
                    .fold(0.0, f64::max);
                (top + (cs.len() as f64).log2(), den)
            }
            Node::Mul(cs) => cs.iter().fold((0.0, 0.0), |a, c| {
                (a.0 + h[c.index()].0, a.1 + h[c.index()].1)
            }),
            Node::Pow(b, e) => {
                let (n, d) = h[b.index()];
                let k = e.unsigned_abs() as f64;
                if *e > 0 {
                    (n * k, d * k)
                } else {
                    (d * k, n * k)
                }
            }
        };
        h[id.index()] = x;
    }
    roots.iter().map(|r| h[r.index()]).collect()
}

/// One free coordinate of a point, for black boxes that must be functions of
/// their point (reconstruction): every leaf's value at a point of
/// [`Ctx::fp_point_at`] is a rational function of the coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coord {
    /// A leaf whose value is free: a symbol or a transcendental atom.
    Leaf(Var),
    /// An angle pair (sin leaf, cos leaf) in the tangent half-angle view,
    /// with its half-angle symbol `t`: `sin = 2t/(1+t^2)`, `cos = (1-t^2)/(1+t^2)`.
    Angle { sin: Var, cos: Var, t: Var },
}

impl Coord {
    /// The variable of this coordinate in the half-angle view.
    pub fn var(&self) -> Var {
        match *self {
            Coord::Leaf(v) => v,
            Coord::Angle { t, .. } => t,
        }
    }
}

impl Ctx {
    /// The free coordinates of the leaves whose values `roots` depend on,
    /// and of the symbols `extra`, in leaf order; `None` if a square root is
    /// among them (its value is not a rational function of the others). A
    /// symbol seen only as the angle of its own sin/cos (or exp) pair is not
    /// a coordinate: values and derivatives there come from the pair's leaves.
    pub fn free_coords(&self, roots: &[Id], extra: &[Var]) -> Option<Vec<Coord>> {
        let mut used = vec![false; self.leaves.len()];
        for &v in extra {
            used[v as usize] = true;
        }
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<Id> = roots.to_vec();
        while let Some(id) = stack.pop() {
            if std::mem::replace(&mut seen[id.index()], true) {
                continue;
            }
            match self.node(id) {
                Node::Leaf(v) => {
                    used[*v as usize] = true;
                    let own_angle = matches!(
                        self.leaves[*v as usize].kind,
                        LeafKind::Sin(Angle::Symbol { .. })
                            | LeafKind::Cos(Angle::Symbol { .. })
                            | LeafKind::Exp(Angle::Symbol { .. })
                    );
                    if !own_angle {
                        stack.extend(self.leaf_args(*v));
                    }
                }
                _ => stack.extend(self.deps(id)),
            }
        }
        let mut out = Vec::new();
        for (v, leaf) in self.leaves.iter().enumerate() {
            if !used[v] {
                continue;
            }
            let v = v as Var;
            match leaf.kind {
                LeafKind::Root(..) => return None,
                LeafKind::Sin(_) | LeafKind::Cos(_) => {
                    let &(sin, cos, t) = self
                        .half_angles
                        .iter()
                        .find(|&&(s, c, _)| s == v || c == v)?;
                    let c = Coord::Angle { sin, cos, t };
                    if !out.contains(&c) {
                        out.push(c);
                    }
                }
                _ => out.push(Coord::Leaf(v)),
            }
        }
        Some(out)
    }

    /// The point with the given coordinate values; leaves outside `coords`
    /// are 0. `BadPoint` if some `1 + t^2` vanishes (never for 2^61 - 1).
    pub fn fp_point_at(&self, coords: &[Coord], values: &[Fp]) -> Result<FpPoint, BadPoint> {
        let mut out = vec![Fp::ZERO; self.leaves.len()];
        for (c, &x) in coords.iter().zip(values) {
            match *c {
                Coord::Leaf(v) => out[v as usize] = x,
                Coord::Angle { sin, cos, .. } => {
                    let t2 = x * x;
                    let inv = (Fp::ONE + t2).inv().ok_or(BadPoint)?;
                    out[sin as usize] = Fp(2) * x * inv;
                    out[cos as usize] = (Fp::ONE - t2) * inv;
                }
            }
        }
        Ok(FpPoint {
            values: out,
            forbidden: Vec::new(),
        })
    }

    /// Exact leaf values at the rational point with these coordinate values
    /// (angles by [`crate::evaluate::rational_angle`]), for [`Ctx::eval_q`]; leaves
    /// outside `coords` are unbound.
    pub fn q_point_at(&self, coords: &[Coord], values: &[crate::Q]) -> Vec<Option<crate::Q>> {
        let mut out = vec![None; self.leaves.len()];
        for (c, x) in coords.iter().zip(values) {
            match *c {
                Coord::Leaf(v) => out[v as usize] = Some(x.clone()),
                Coord::Angle { sin, cos, .. } => {
                    let (s, co) = crate::eval::rational_angle(x);
                    out[sin as usize] = Some(s);
                    out[cos as usize] = Some(co);
                }
            }
        }
        out
    }
}

/// Arithmetic modulo a prime `q < 2^63` for [`Ctx::eval_mod_prime`]:
/// obsan-recon's `fp`, the workspace's one implementation.
fn mulq(a: u64, b: u64, q: u64) -> u64 {
    fp::mul(a, b, q)
}

fn powq(a: u64, e: u64, q: u64) -> u64 {
    fp::pow(a % q, e, q)
}

fn invq(a: u64, q: u64) -> Option<u64> {
    fp::inv(a % q, q)
}

impl Ctx {
    /// Leaf values modulo the prime `q` (below 2^63) at the point with these
    /// coordinate values (each `< q`), as [`Ctx::fp_point_at`] does modulo
    /// 2^61 - 1; `BadPoint` if some `1 + t^2` vanishes mod q.
    pub fn mod_point_at(
        &self,
        coords: &[Coord],
        values: &[u64],
        q: u64,
    ) -> Result<Vec<u64>, BadPoint> {
        let mut out = vec![0; self.leaves.len()];
        for (c, &x) in coords.iter().zip(values) {
            match *c {
                Coord::Leaf(v) => out[v as usize] = x % q,
                Coord::Angle { sin, cos, .. } => {
                    let t2 = mulq(x, x, q);
                    let inv = invq((1 + t2) % q, q).ok_or(BadPoint)?;
                    out[sin as usize] = mulq(mulq(2 % q, x, q), inv, q);
                    out[cos as usize] = mulq((1 + q - t2) % q, inv, q);
                }
            }
        }
        Ok(out)
    }

    /// Values of `roots` modulo the prime `q` (below 2^63) given every leaf's
    /// value mod q: checks modulo primes the engine's `Fp` does not use.
    /// `BadPoint` at a pole (a zero mod q raised to a negative power, or a
    /// rational constant whose denominator q divides).
    pub fn eval_mod_prime(&self, roots: &[Id], leaf: &[u64], q: u64) -> Result<Vec<u64>, BadPoint> {
        let order = self.reachable_with(roots, false);
        let mut val = vec![0u64; self.len()];
        for id in order {
            let x = match self.node(id) {
                Node::Num(c) => {
                    let d = invq(crate::num::int_mod(c.den(), q), q).ok_or(BadPoint)?;
                    mulq(crate::num::int_mod(c.num(), q), d, q)
                }
                Node::Leaf(v) => *leaf.get(*v as usize).ok_or(BadPoint)? % q,
                Node::Add(cs) => cs.iter().fold(0u64, |a, c| fp::add(a, val[c.index()], q)),
                Node::Mul(cs) => cs.iter().fold(1 % q, |a, c| mulq(a, val[c.index()], q)),
                Node::Pow(b, e) => {
                    let base = val[b.index()];
                    let base = if *e < 0 {
                        invq(base, q).ok_or(BadPoint)?
                    } else {
                        base
                    };
                    powq(base, e.unsigned_abs() as u64, q)
                }
            };
            val[id.index()] = x;
        }
        Ok(roots.iter().map(|r| val[r.index()]).collect())
    }
}

impl Ctx {
    /// Gradients with respect to `vars` of `roots` modulo the prime `q`
    /// (below 2^63), by forward-mode differentiation on the graph (the
    /// chain rule of `diff.rs` through every leaf, nothing built), given
    /// every leaf's value mod q. `BadPoint` at a pole.
    pub fn grad_mod_prime(
        &self,
        roots: &[Id],
        leaf: &[u64],
        vars: &[Var],
        q: u64,
    ) -> Result<Vec<Vec<u64>>, BadPoint> {
        let n = vars.len();
        let w = n + 1;
        let order = self.reachable_with(roots, true);
        let mut slot = vec![u32::MAX; self.len()];
        let mut t: Vec<u64> = Vec::with_capacity(order.len() * w);
        let addq = |a: u64, b: u64| fp::add(a, b, q);
        for id in order {
            let base = t.len();
            t.resize(base + w, 0);
            let get = |_: &Vec<u64>, c: Id| -> Result<usize, BadPoint> {
                let k = slot[c.index()];
                if k == u32::MAX {
                    return Err(BadPoint);
                }
                Ok(k as usize * w)
            };
            match self.node(id) {
                Node::Num(c) => {
                    let d = invq(crate::num::int_mod(c.den(), q), q).ok_or(BadPoint)?;
                    t[base] = mulq(crate::num::int_mod(c.num(), q), d, q);
                }
                Node::Add(cs) => {
                    for c in cs.iter() {
                        let o = get(&t, *c)?;
                        for i in 0..w {
                            t[base + i] = addq(t[base + i], t[o + i]);
                        }
                    }
                }
                Node::Mul(cs) => {
                    t[base] = 1 % q;
                    for c in cs.iter() {
                        let o = get(&t, *c)?;
                        // (v, g) * (a, h) = (v a, v h + a g)
                        let (v, a) = (t[base], t[o]);
                        for i in 1..w {
                            t[base + i] = addq(mulq(v, t[o + i], q), mulq(a, t[base + i], q));
                        }
                        t[base] = mulq(v, a, q);
                    }
                }
                Node::Pow(b, e) => {
                    let o = get(&t, *b)?;
                    let bv = t[o];
                    let k = e.unsigned_abs() as u64;
                    let (val, dfac) = if *e < 0 {
                        let inv = invq(bv, q).ok_or(BadPoint)?;
                        // d b^-k = -k b^-(k+1) db
                        (
                            powq(inv, k, q),
                            mulq((q - k % q) % q, powq(inv, k + 1, q), q),
                        )
                    } else {
                        (powq(bv, k, q), mulq(k % q, powq(bv, k - 1, q), q))
                    };
                    t[base] = val;
                    for i in 1..w {
                        t[base + i] = mulq(dfac, t[o + i], q);
                    }
                }
                Node::Leaf(v) => {
                    let lv = *leaf.get(*v as usize).ok_or(BadPoint)? % q;
                    t[base] = lv;
                    let l = &self.leaves[*v as usize];
                    // d(leaf) = fac * d(arg) for one argument node (or a symbol).
                    let angle_d = |t: &mut Vec<u64>, a: &Angle, fac: u64| -> Result<(), BadPoint> {
                        match a {
                            Angle::Symbol { sym, den } => {
                                if let Some(k) = vars.iter().position(|x| x == sym) {
                                    let d = invq(*den as u64 % q, q).ok_or(BadPoint)?;
                                    t[base + 1 + k] = mulq(fac, d, q);
                                }
                            }
                            Angle::Generic(arg) => {
                                let o = get(t, *arg)?;
                                for i in 1..w {
                                    t[base + i] = mulq(fac, t[o + i], q);
                                }
                            }
                        }
                        Ok(())
                    };
                    let chain = |t: &mut Vec<u64>, arg: Id, fac: u64| -> Result<(), BadPoint> {
                        let o = get(t, arg)?;
                        for i in 1..w {
                            t[base + i] = mulq(fac, t[o + i], q);
                        }
                        Ok(())
                    };
                    match &l.kind {
                        LeafKind::Symbol(_) => {
                            if let Some(k) = vars.iter().position(|x| x == v) {
                                t[base + 1 + k] = 1 % q;
                            }
                        }
                        LeafKind::Pi => {}
                        LeafKind::Sin(a) | LeafKind::Cos(a) => {
                            let p = l.partner.ok_or(BadPoint)?;
                            let pv = *leaf.get(p as usize).ok_or(BadPoint)?;
                            let fac = if matches!(l.kind, LeafKind::Sin(_)) {
                                pv
                            } else {
                                (q - pv) % q
                            };
                            angle_d(&mut t, a, fac)?;
                        }
                        LeafKind::Exp(a) => angle_d(&mut t, a, lv)?,
                        LeafKind::Atan(u) => {
                            let uv = t[get(&t, *u)?];
                            let fac = invq(addq(1, mulq(uv, uv, q)), q).ok_or(BadPoint)?;
                            chain(&mut t, *u, fac)?;
                        }
                        LeafKind::Log(u) => {
                            let uv = t[get(&t, *u)?];
                            chain(&mut t, *u, invq(uv, q).ok_or(BadPoint)?)?;
                        }
                        LeafKind::Root(u, 2) => {
                            let fac = invq(mulq(2, lv, q), q).ok_or(BadPoint)?;
                            chain(&mut t, *u, fac)?;
                        }
                        LeafKind::Root(u, k) => {
                            // d r = r du / (k u)
                            let uv = t[get(&t, *u)?];
                            let inv = invq(mulq(*k as u64 % q, uv, q), q).ok_or(BadPoint)?;
                            chain(&mut t, *u, mulq(lv, inv, q))?;
                        }
                        LeafKind::Atan2(y, x) => {
                            let (oy, ox) = (get(&t, *y)?, get(&t, *x)?);
                            let (yv, xv) = (t[oy], t[ox]);
                            let inv =
                                invq(addq(mulq(xv, xv, q), mulq(yv, yv, q)), q).ok_or(BadPoint)?;
                            for i in 1..w {
                                let num = addq(mulq(xv, t[oy + i], q), q - mulq(yv, t[ox + i], q));
                                t[base + i] = mulq(num, inv, q);
                            }
                        }
                    }
                }
            }
            slot[id.index()] = (base / w) as u32;
        }
        roots
            .iter()
            .map(|r| {
                let k = slot[r.index()];
                if k == u32::MAX {
                    return Err(BadPoint);
                }
                let o = k as usize * w;
                Ok(t[o + 1..o + w].to_vec())
            })
            .collect()
    }
}
