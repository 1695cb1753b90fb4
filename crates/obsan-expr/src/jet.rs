//! Lie derivatives and their gradients at a point of F_p, never built as
//! expressions (issue 15; reconstruction.md section 1).
//!
//! For a word `(a_1, ..., a_k)` (`a_1` applied first) and the flows `Phi^a_t`
//! of the fields,
//!
//! ```text
//! L_{a_k} ... L_{a_1} h (x) = d^k / dt_1 ... dt_k  h(Phi^{a_1}_{t_1} o ... o Phi^{a_k}_{t_k}(x))  at t = 0
//! ```
//!
//! (`L_b L_a h(x) = d/ds (L_a h)(Phi^b_s x)` and `L_a g(y) = d/dt g(Phi^a_t y)`).
//! A run of one field merges (`Phi^a_s o Phi^a_t = Phi^a_{s+t}`), so a run of
//! length m is one variable truncated at degree m, and the derivative is m!
//! times a coefficient. Each flow is a truncated Taylor series computed by
//! Picard iteration (one order per pass) on the expression DAG; every
//! coefficient also carries its first-order part in each state variable
//! (dual numbers), which is the gradient. Functions become series by their
//! Taylor expansions at the point (`exp`, `sin`/`cos` from the point's
//! values, `atan`, `atan2` by the angle-difference formulas, `log`, `sqrt` by
//! the binomial series): the same derivative rules as `diff.rs`, so the values
//! are those of the symbolic Lie derivatives at the point, exactly.
//!
//! ## Degree bound (Schwartz–Zippel)
//! Every number computed is a rational function of the random coordinates of
//! [`Ctx::random_fp_point`]. Alongside the values runs an abstract
//! interpretation of the same arithmetic, per grade (total degree in the t's,
//! plus one for a gradient part): a bound `Deg { n, e }` says the coefficient
//! is `P / prod_b B_b^e_b` with `deg P <= n`, where the `B_b` are *bases*:
//! the numerators of everything ever inverted (the value of a node raised to
//! a negative power, the argument of `log` and `sqrt`, `1 + u^2` of `atan u`,
//! `x^2 + y^2` of `atan2(y, x)`) and `1 + t^2` of each angle. Sums take the
//! largest exponent of each base (a common denominator), products add; the
//! inverse of a jet `a0 + N` is `sum_k (-N)^k / a0^(k+1)`, whose `1/a0` is
//! `prod B^e / P` with `P` a new base. Leaves follow [`degree_bounds`]:
//! symbols and atoms 1, sin/cos `2t/(1+t^2)`, a square root its radicand's
//! count. A minor of rows `N_i / D_i` is a polynomial of degree at most
//! `sum n_i` over the product of the `D_i`, which is non-zero at any point
//! where the evaluation succeeded (every base was inverted there), so the
//! minor vanishes at the point only where that numerator does.
//!
//! [`degree_bounds`]: crate::degree_bounds

use crate::eval::{BadPoint, FpPoint};
use crate::graph::{Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::{Fp, P};
use crate::poly::Var;
use rustc_hash::FxHashMap;

/// `P / prod_b B_b^e[b]` with `deg P <= n` (see the module docs).
#[derive(Clone, Debug, PartialEq, Eq)]
struct Deg {
    n: u64,
    e: Vec<u32>,
}

impl Deg {
    fn poly(n: u64) -> Deg {
        Deg { n, e: Vec::new() }
    }
}

/// The degrees of the bases.
#[derive(Clone, Debug, Default)]
struct Bases {
    deg: Vec<u64>,
}

impl Bases {
    fn mul(&self, a: &Deg, b: &Deg) -> Deg {
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
    fn add(&self, a: &Deg, b: &Deg) -> Deg {
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
enum Op {
    Const(Fp),
    /// A rational number with no value mod p.
    NoValue,
    /// The k-th state variable.
    State(usize),
    /// A leaf that is constant here (a symbol outside the state, pi, or an
    /// angle or exponential of such a symbol): its value at the point.
    Fixed(Var),
    Add(Vec<u32>),
    Mul(Vec<u32>),
    /// `x^e`, e > 0.
    Pow(u32, u32),
    /// `x^-e`, e > 0, with the bound of `1/x`.
    InvPow(u32, u32, usize),
    /// `exp(a)`, `sin(a)`, `cos(a)` with the argument `a = arg / den`.
    Exp(Var, u32, u64),
    /// With the partner leaf (cos of a sin leaf, sin of a cos leaf).
    Sin(Var, Var, u32, u64),
    Cos(Var, Var, u32, u64),
    /// `atan(u)`, with the bound index of `1/(1 + u^2)`.
    Atan(Var, u32, usize),
    /// `atan2(y, x)`, with the bound index of `1/(x^2 + y^2)`.
    Atan2(Var, u32, u32, usize),
    /// `log(u)`, `sqrt(u)`, with the bound index of `1/u`.
    Log(Var, u32, usize),
    Sqrt(Var, u32, usize),
}

/// A compiled set of roots.
#[derive(Clone, Debug)]
struct Program {
    ops: Vec<Op>,
    /// Bound of each op's value at the point (grade 0).
    deg0: Vec<Deg>,
    roots: Vec<u32>,
}

/// Evaluates Lie derivatives of the outputs along words of fields, with
/// their gradients, at points of F_p.
#[derive(Clone, Debug)]
pub struct LieJets {
    n: usize,
    states: Vec<Var>,
    fields: Vec<Program>,
    outputs: Vec<Program>,
    bases: Bases,
    /// Bounds of inverses, referred to by index from the ops.
    inverses: Vec<Deg>,
    /// State variables each field moves (a structurally non-zero component).
    moves: Vec<Vec<bool>>,
    /// State variables each output and each field component depends on.
    out_support: Vec<Vec<bool>>,
    field_support: Vec<Vec<Vec<bool>>>,
}

/// The gradient of one Lie derivative at a point, its value, and the
/// numerator degree bound of the row (see the module docs) when asked for.
#[derive(Clone, Debug)]
pub struct LieRow {
    pub value: Fp,
    pub gradient: Vec<Fp>,
    pub degree: Option<u64>,
}

impl LieJets {
    /// Compile the outputs `h` and the fields (one node per state variable
    /// each) over the state variables `states`.
    pub fn new(ctx: &Ctx, states: &[Var], fields: &[Vec<Id>], outputs: &[Id]) -> LieJets {
        let mut c = Compiler {
            ctx,
            states,
            bases: Bases::default(),
            inverses: Vec::new(),
            sin_base: FxHashMap::default(),
        };
        let fields_p: Vec<Program> = fields.iter().map(|f| c.compile(f)).collect();
        let outputs_p: Vec<Program> = outputs.iter().map(|&h| c.compile(&[h])).collect();
        let support = |id: Id| -> Vec<bool> {
            let mut s = vec![false; states.len()];
            for n in ctx.reachable(&[id]) {
                if let Node::Leaf(v) = ctx.node(n) {
                    if let Some(k) = states.iter().position(|x| x == v) {
                        s[k] = true;
                    }
                }
            }
            s
        };
        let moves = fields
            .iter()
            .map(|f| f.iter().map(|&x| !ctx.is_zero(x)).collect())
            .collect();
        let out_support = outputs.iter().map(|&h| support(h)).collect();
        let field_support = fields
            .iter()
            .map(|f| f.iter().map(|&x| support(x)).collect())
            .collect();
        LieJets {
            n: states.len(),
            states: states.to_vec(),
            fields: fields_p,
            outputs: outputs_p,
            bases: c.bases,
            inverses: c.inverses,
            moves,
            out_support,
            field_support,
        }
    }

    /// The state variables `L_word h_output` may depend on, or `None` if it
    /// is structurally zero (some field of the word moves nothing it depends
    /// on): `supp(L_f g)` lies in `supp(g)` and the supports of the
    /// components `f_i`, `i` in `supp(g)`, that are not zero.
    pub fn support(&self, output: usize, word: &[usize]) -> Option<Vec<bool>> {
        let mut s = self.out_support[output].clone();
        for &a in word {
            let mut next = s.clone();
            let mut any = false;
            for (i, &si) in s.iter().enumerate() {
                if si && self.moves[a][i] {
                    any = true;
                    for (x, &y) in next.iter_mut().zip(&self.field_support[a][i]) {
                        *x |= y;
                    }
                }
            }
            if !any {
                return None;
            }
            s = next;
        }
        Some(s)
    }

    /// `L_{word[k-1]} ... L_{word[0]} h_output` and its gradient at `point`,
    /// with the degree bound of the row if `track` (it does not depend on
    /// the point, and costs about as much as the values).
    pub fn row(
        &self,
        output: usize,
        word: &[usize],
        point: &FpPoint,
        track: bool,
    ) -> Result<LieRow, BadPoint> {
        // Runs of one field, first applied first: (field, length).
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for &a in word {
            match runs.last_mut() {
                Some((f, m)) if *f == a => *m += 1,
                _ => runs.push((a, 1)),
            }
        }
        let shape = Shape::new(self.n, &runs.iter().map(|r| r.1).collect::<Vec<_>>());
        let ar = Arith {
            sh: &shape,
            track,
            bases: &self.bases,
            inverses: &self.inverses,
            point,
        };
        // x + eps, then the flows from the last applied (innermost) outwards.
        let mut x: Vec<Jet> = self
            .states
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let mut j = ar.zero();
                j.c[0] = point.value(v);
                j.c[1 + k] = Fp::ONE;
                j.eps = true;
                if track {
                    j.d[0] = Some(Deg::poly(1));
                    j.d[1] = Some(Deg::poly(0));
                }
                j
            })
            .collect();
        for (j, &(field, m)) in runs.iter().enumerate().rev() {
            let x0 = x.clone();
            for _ in 0..m {
                let f = ar.run(&self.fields[field], &x)?;
                x = x0
                    .iter()
                    .zip(&f)
                    .map(|(a, b)| ar.add(a, &ar.integrate(b, j)))
                    .collect();
            }
        }
        let h = ar.run(&self.outputs[output], &x)?;
        let h = &h[0];
        let top = shape.size - 1;
        let w = self.n + 1;
        let mut fact = Fp::ONE;
        for &(_, m) in &runs {
            for i in 2..=m {
                fact = fact * Fp::new(i as u64);
            }
        }
        let degree = h.d.get(shape.grades).and_then(|d| d.as_ref()).map(|d| d.n);
        Ok(LieRow {
            value: h.c[top * w] * fact,
            gradient: h.c[top * w + 1..top * w + w]
                .iter()
                .map(|&g| g * fact)
                .collect(),
            degree,
        })
    }
}

impl LieJets {
    /// The rows of every prefix of `word` (lengths 0 to `word.len()`), from
    /// one jet: with the flows of the later runs at time 0 (the identity),
    /// the coefficient of `t_1^m_1 ... t_j^a` is the derivative along the
    /// prefix (runs 1..j-1 whole, a steps of run j), times `m_1! ... a!`.
    /// Same values as [`LieJets::row`] on each prefix; no degree bounds.
    pub fn prefix_rows(
        &self,
        output: usize,
        word: &[usize],
        point: &FpPoint,
    ) -> Result<Vec<LieRow>, BadPoint> {
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for &a in word {
            match runs.last_mut() {
                Some((f, m)) if *f == a => *m += 1,
                _ => runs.push((a, 1)),
            }
        }
        let shape = Shape::new(self.n, &runs.iter().map(|r| r.1).collect::<Vec<_>>());
        let ar = Arith {
            sh: &shape,
            track: false,
            bases: &self.bases,
            inverses: &self.inverses,
            point,
        };
        let mut x: Vec<Jet> = self
            .states
            .iter()
            .enumerate()
            .map(|(k, &v)| {
                let mut j = ar.zero();
                j.c[0] = point.value(v);
                j.c[1 + k] = Fp::ONE;
                j.eps = true;
                j
            })
            .collect();
        for (j, &(field, m)) in runs.iter().enumerate().rev() {
            let x0 = x.clone();
            for _ in 0..m {
                let f = ar.run(&self.fields[field], &x)?;
                x = x0
                    .iter()
                    .zip(&f)
                    .map(|(a, b)| ar.add(a, &ar.integrate(b, j)))
                    .collect();
            }
        }
        let h = ar.run(&self.outputs[output], &x)?;
        let h = &h[0];
        let w = self.n + 1;
        let row_at = |idx: usize, fact: Fp| LieRow {
            value: h.c[idx * w] * fact,
            gradient: h.c[idx * w + 1..idx * w + w]
                .iter()
                .map(|&g| g * fact)
                .collect(),
            degree: None,
        };
        let mut out = vec![row_at(0, Fp::ONE)];
        let (mut base, mut fact) = (0usize, Fp::ONE);
        for (j, &(_, m)) in runs.iter().enumerate() {
            for a in 1..=m {
                fact = fact * Fp::new(a as u64);
                out.push(row_at(base + a * shape.strides[j], fact));
            }
            base += m * shape.strides[j];
        }
        Ok(out)
    }
}

struct Compiler<'a> {
    ctx: &'a Ctx,
    states: &'a [Var],
    bases: Bases,
    inverses: Vec<Deg>,
    /// The base `1 + t^2` of each angle pair, by its sin leaf.
    sin_base: FxHashMap<Var, usize>,
}

impl Compiler<'_> {
    fn inverse(&mut self, d: &Deg) -> usize {
        let inv = self.bases.register_inverse(d);
        self.inverses.push(inv);
        self.inverses.len() - 1
    }

    fn compile(&mut self, roots: &[Id]) -> Program {
        let ctx = self.ctx;
        let order = ctx.reachable(roots);
        let mut local: FxHashMap<Id, u32> = FxHashMap::default();
        let mut ops = Vec::with_capacity(order.len());
        let mut deg0: Vec<Deg> = Vec::with_capacity(order.len());
        for (i, &id) in order.iter().enumerate() {
            local.insert(id, i as u32);
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
                    let d = cs
                        .iter()
                        .skip(1)
                        .fold(deg0[l(cs[0]) as usize].clone(), |a, c| {
                            self.bases.mul(&a, &deg0[l(*c) as usize])
                        });
                    (Op::Mul(cs.iter().map(|&c| l(c)).collect()), d)
                }
                Node::Pow(b, e) => {
                    let k = e.unsigned_abs();
                    let base = if *e > 0 {
                        deg0[l(*b) as usize].clone()
                    } else {
                        let idx = self.inverse(&deg0[l(*b) as usize].clone());
                        ops.push(Op::InvPow(l(*b), k, idx));
                        let d = pow_deg(&self.inverses[idx], k);
                        deg0.push(d);
                        continue;
                    };
                    (Op::Pow(l(*b), k), pow_deg(&base, k))
                }
                Node::Leaf(v) => self.leaf(*v, &l, &deg0),
            };
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
            LeafKind::Sqrt(u) => {
                // The convention of `degree_bounds` for a square root.
                let count = |p: &crate::poly::Poly| {
                    p.terms()
                        .iter()
                        .map(|(m, _)| m.iter().map(|(_, e)| 2 * e as u64).sum::<u64>())
                        .max()
                        .unwrap_or(0)
                };
                let n = ctx.radicand(v).map_or(0, |r| count(&r.num) + count(&r.den));
                let d = deg0[l(*u) as usize].clone();
                (Op::Sqrt(v, l(*u), self.inverse(&d)), Deg::poly(n))
            }
        }
    }
}

fn pow_deg(d: &Deg, k: u32) -> Deg {
    Deg {
        n: d.n.saturating_mul(k as u64),
        e: d.e.iter().map(|&x| x.saturating_mul(k)).collect(),
    }
}

/// The truncation box of a word: one variable per run, truncated at the
/// run's length (mixed radix, the first run fastest), and per coefficient
/// the value and one first-order part per state variable.
struct Shape {
    /// State variables + 1.
    w: usize,
    caps: Vec<usize>,
    strides: Vec<usize>,
    size: usize,
    /// The largest grade: the sum of the caps, plus one for a gradient part.
    grades: usize,
    /// For each index i: the (j, i + j) with i + j inside the box.
    table: Vec<Vec<(u32, u32)>>,
}

impl Shape {
    fn new(n: usize, caps: &[usize]) -> Shape {
        let mut strides = Vec::with_capacity(caps.len());
        let mut size = 1;
        for &m in caps {
            strides.push(size);
            size *= m + 1;
        }
        let digits = |i: usize| -> Vec<usize> {
            caps.iter()
                .zip(&strides)
                .map(|(&m, &s)| (i / s) % (m + 1))
                .collect()
        };
        let all: Vec<Vec<usize>> = (0..size).map(digits).collect();
        let table = (0..size)
            .map(|i| {
                (0..size)
                    .filter(|&j| {
                        all[i]
                            .iter()
                            .zip(&all[j])
                            .zip(caps)
                            .all(|((a, b), m)| a + b <= *m)
                    })
                    .map(|j| (j as u32, (i + j) as u32))
                    .collect()
            })
            .collect();
        Shape {
            w: n + 1,
            caps: caps.to_vec(),
            strides,
            size,
            grades: caps.iter().sum::<usize>() + 1,
            table,
        }
    }
}

/// A truncated series: `c[i * w]` the value of monomial i, `c[i * w + 1 + k]`
/// its first-order part in state variable k; `d[g]` the bound of grade g
/// (`None`: structurally zero).
#[derive(Clone, Debug)]
struct Jet {
    c: Vec<Fp>,
    d: Vec<Option<Deg>>,
    /// Only monomial 0 may be non-zero.
    tconst: bool,
    /// Some first-order part may be non-zero.
    eps: bool,
}

struct Arith<'a> {
    sh: &'a Shape,
    /// Track the degree bounds (`d` is empty otherwise).
    track: bool,
    bases: &'a Bases,
    inverses: &'a [Deg],
    point: &'a FpPoint,
}

/// Inverses of small integers and factorials, tabulated at compile time: a
/// series coefficient or an integration step would otherwise pay a Fermat
/// inversion (60 squarings) per use, which was a fifth of a jet's cost.
const SMALL: usize = 64;

const fn mul_p(a: u64, b: u64) -> u64 {
    let w = a as u128 * b as u128;
    let s = ((w as u64) & P) + (w >> 61) as u64;
    if s >= P {
        s - P
    } else {
        s
    }
}

const fn inv_p(a: u64) -> u64 {
    let (mut b, mut e, mut r) = (a, P - 2, 1u64);
    while e > 0 {
        if e & 1 == 1 {
            r = mul_p(r, b);
        }
        b = mul_p(b, b);
        e >>= 1;
    }
    r
}

/// `[0, 1/1, 1/2, ...]` (entry 0 unused) and `[1/0!, 1/1!, 1/2!, ...]`.
const fn small_tables() -> ([u64; SMALL], [u64; SMALL]) {
    let mut inv = [0u64; SMALL];
    let mut fact = [1u64; SMALL];
    let mut k = 1;
    while k < SMALL {
        inv[k] = inv_p(k as u64);
        fact[k] = mul_p(fact[k - 1], inv[k]);
        k += 1;
    }
    (inv, fact)
}

static TABLES: ([u64; SMALL], [u64; SMALL]) = small_tables();

fn inv_small(k: u64) -> Fp {
    if (1..SMALL as u64).contains(&k) {
        return Fp(TABLES.0[k as usize]);
    }
    #[allow(clippy::expect_used)]
    Fp::new(k)
        .inv()
        .expect("small positive integers are invertible mod p")
}

impl Arith<'_> {
    fn grades(&self) -> usize {
        if self.track {
            self.sh.grades + 1
        } else {
            0
        }
    }
    fn zero(&self) -> Jet {
        Jet {
            c: vec![Fp::ZERO; self.sh.size * self.sh.w],
            d: vec![None; self.grades()],
            tconst: true,
            eps: false,
        }
    }
    fn constant(&self, v: Fp, d: Deg) -> Jet {
        let mut j = self.zero();
        j.c[0] = v;
        if let Some(x) = j.d.first_mut() {
            *x = Some(d);
        }
        j
    }
    fn join(&self, a: &Option<Deg>, b: &Option<Deg>) -> Option<Deg> {
        match (a, b) {
            (None, x) | (x, None) => x.clone(),
            (Some(x), Some(y)) => Some(self.bases.add(x, y)),
        }
    }
    fn add(&self, a: &Jet, b: &Jet) -> Jet {
        Jet {
            c: a.c.iter().zip(&b.c).map(|(&x, &y)| x + y).collect(),
            d: a.d.iter().zip(&b.d).map(|(x, y)| self.join(x, y)).collect(),
            tconst: a.tconst && b.tconst,
            eps: a.eps || b.eps,
        }
    }
    fn neg(&self, a: &Jet) -> Jet {
        Jet {
            c: a.c.iter().map(|&x| -x).collect(),
            ..a.clone()
        }
    }
    fn scale(&self, a: &Jet, s: Fp, sd: &Deg) -> Jet {
        Jet {
            c: a.c.iter().map(|&x| x * s).collect(),
            d: a.d
                .iter()
                .map(|x| x.as_ref().map(|x| self.bases.mul(x, sd)))
                .collect(),
            ..*a
        }
    }
    /// `a` without its value at the point (the nilpotent part).
    fn nil(&self, a: &Jet) -> Jet {
        let mut n = a.clone();
        n.c[0] = Fp::ZERO;
        if let Some(x) = n.d.first_mut() {
            *x = None;
        }
        n
    }
    fn mul(&self, a: &Jet, b: &Jet) -> Jet {
        let (a, b) = if b.tconst && !a.tconst {
            (b, a)
        } else {
            (a, b)
        };
        let w = self.sh.w;
        let mut c = vec![Fp::ZERO; self.sh.size * w];
        let ilim = if a.tconst { 1 } else { self.sh.size };
        for i in 0..ilim {
            let ai = &a.c[i * w..i * w + w];
            if ai.iter().all(|x| x.is_zero()) {
                continue;
            }
            for &(j, k) in &self.sh.table[i] {
                let (j, k) = (j as usize, k as usize);
                if b.tconst && j > 0 {
                    break;
                }
                let bj = &b.c[j * w..j * w + w];
                let (av, bv) = (ai[0], bj[0]);
                let out = &mut c[k * w..k * w + w];
                out[0] = out[0] + av * bv;
                if b.eps && !av.is_zero() {
                    for s in 1..w {
                        out[s] = out[s] + av * bj[s];
                    }
                }
                if a.eps && !bv.is_zero() {
                    for s in 1..w {
                        out[s] = out[s] + ai[s] * bv;
                    }
                }
            }
        }
        let g = self.sh.grades;
        let mut d: Vec<Option<Deg>> = vec![None; self.grades()];
        for (i, x) in a.d.iter().enumerate() {
            let Some(x) = x else { continue };
            for (j, y) in b.d.iter().enumerate().take(g + 1 - i) {
                let Some(y) = y else { continue };
                let p = Some(self.bases.mul(x, y));
                d[i + j] = self.join(&d[i + j], &p);
            }
        }
        Jet {
            c,
            d,
            tconst: a.tconst && b.tconst,
            eps: a.eps || b.eps,
        }
    }
    /// `a^k` by squaring.
    fn pow(&self, a: &Jet, mut k: u32) -> Jet {
        let mut acc: Option<Jet> = None;
        let mut b = a.clone();
        loop {
            if k & 1 == 1 {
                acc = Some(match acc {
                    None => b.clone(),
                    Some(x) => self.mul(&x, &b),
                });
            }
            k >>= 1;
            if k == 0 {
                break;
            }
            b = self.mul(&b, &b);
        }
        acc.unwrap_or_else(|| self.constant(Fp::ONE, Deg::poly(0)))
    }
    fn is_const(a: &Jet) -> bool {
        a.tconst && !a.eps
    }
    /// `1 / a`, where `inverses[idx]` bounds `1 / a0`.
    fn inv(&self, a: &Jet, idx: usize) -> Result<Jet, BadPoint> {
        let i0 = a.c[0].inv().ok_or(BadPoint)?;
        let id = &self.inverses[idx];
        let c0 = self.constant(i0, id.clone());
        if Self::is_const(a) {
            return Ok(c0);
        }
        // 1/(a0 + N) = (1/a0) sum_k M^k, M = -N/a0, nilpotent of order <= grades.
        let m = self.scale(&self.neg(&self.nil(a)), i0, id);
        let one = self.constant(Fp::ONE, Deg::poly(0));
        let mut acc = one.clone();
        for _ in 0..self.sh.grades {
            acc = self.add(&one, &self.mul(&m, &acc));
        }
        Ok(self.mul(&c0, &acc))
    }
    /// `sum_k coeffs[k] N^k` for nilpotent N (k up to the grades).
    fn series(&self, n: &Jet, coeffs: &dyn Fn(u64) -> Fp) -> Jet {
        let g = self.sh.grades as u64;
        let mut acc = self.constant(coeffs(g), Deg::poly(0));
        for k in (0..g).rev() {
            acc = self.add(&self.constant(coeffs(k), Deg::poly(0)), &self.mul(n, &acc));
        }
        acc
    }
    /// `int_0^{t_v} a`.
    fn integrate(&self, a: &Jet, v: usize) -> Jet {
        let (w, s, m) = (self.sh.w, self.sh.strides[v], self.sh.caps[v]);
        let mut c = vec![Fp::ZERO; self.sh.size * w];
        for i in 0..self.sh.size {
            let digit = (i / s) % (m + 1);
            if digit == 0 {
                continue;
            }
            let inv = inv_small(digit as u64);
            let src = i - s;
            for q in 0..w {
                c[i * w + q] = a.c[src * w + q] * inv;
            }
        }
        let mut d = vec![None; self.grades()];
        if self.track {
            d[1..].clone_from_slice(&a.d[..self.sh.grades]);
        }
        Jet {
            c,
            d,
            tconst: false,
            eps: a.eps,
        }
    }
    fn fact_inv(k: u64) -> Fp {
        if k < SMALL as u64 {
            return Fp(TABLES.1[k as usize]);
        }
        (2..=k).fold(Fp::ONE, |a, i| a * inv_small(i))
    }

    fn run(&self, prog: &Program, x: &[Jet]) -> Result<Vec<Jet>, BadPoint> {
        let mut vals: Vec<Jet> = Vec::with_capacity(prog.ops.len());
        let pv = |v: Var| self.point.value(v);
        for (i, op) in prog.ops.iter().enumerate() {
            // Without tracking the bounds are dropped: no clone (an allocation
            // per op and pass).
            let d0 = if self.track {
                prog.deg0[i].clone()
            } else {
                Deg::poly(0)
            };
            let at = |k: &u32| &vals[*k as usize];
            let mut j = match op {
                Op::Const(v) => self.constant(*v, d0.clone()),
                Op::NoValue => return Err(BadPoint),
                Op::State(k) => x[*k].clone(),
                Op::Fixed(v) => self.constant(pv(*v), d0.clone()),
                Op::Add(cs) => {
                    let mut acc = at(&cs[0]).clone();
                    for c in &cs[1..] {
                        acc = self.add(&acc, at(c));
                    }
                    acc
                }
                Op::Mul(cs) => {
                    let mut acc = at(&cs[0]).clone();
                    for c in &cs[1..] {
                        acc = self.mul(&acc, at(c));
                    }
                    acc
                }
                Op::Pow(b, k) => self.pow(at(b), *k),
                Op::InvPow(b, k, idx) => self.pow(&self.inv(at(b), *idx)?, *k),
                Op::Exp(v, arg, den) | Op::Sin(v, _, arg, den) | Op::Cos(v, _, arg, den)
                    if Self::is_const(at(arg)) =>
                {
                    let _ = den;
                    self.constant(pv(*v), d0.clone())
                }
                Op::Exp(v, arg, den) => {
                    let n = self.scale(&self.nil(at(arg)), inv_small(*den), &Deg::poly(0));
                    let e = self.series(&n, &|k| Self::fact_inv(k));
                    self.scale(&e, pv(*v), &d0)
                }
                Op::Sin(v, p, arg, den) | Op::Cos(v, p, arg, den) => {
                    let n = self.scale(&self.nil(at(arg)), inv_small(*den), &Deg::poly(0));
                    let sign = |k: u64| {
                        if (k / 2).is_multiple_of(2) {
                            Fp::ONE
                        } else {
                            -Fp::ONE
                        }
                    };
                    let cs = self.series(&n, &|k| {
                        if k % 2 == 0 {
                            sign(k) * Self::fact_inv(k)
                        } else {
                            Fp::ZERO
                        }
                    });
                    let sn = self.series(&n, &|k| {
                        if k % 2 == 1 {
                            sign(k) * Self::fact_inv(k)
                        } else {
                            Fp::ZERO
                        }
                    });
                    let (me, other) = (pv(*v), pv(*p));
                    if matches!(op, Op::Sin(..)) {
                        // sin(a0 + N) = s0 cos N + c0 sin N
                        self.add(&self.scale(&cs, me, &d0), &self.scale(&sn, other, &d0))
                    } else {
                        // cos(a0 + N) = c0 cos N - s0 sin N
                        self.add(&self.scale(&cs, me, &d0), &self.scale(&sn, -other, &d0))
                    }
                }
                Op::Atan(v, u, idx) => {
                    let uj = at(u);
                    if Self::is_const(uj) {
                        self.constant(pv(*v), d0.clone())
                    } else {
                        // atan U - atan u0 = atan((U - u0) / (1 + u0 U)).
                        let u0 = self.constant(uj.c[0], prog.deg0[*u as usize].clone());
                        let one = self.constant(Fp::ONE, Deg::poly(0));
                        let den = self.add(&one, &self.mul(&u0, uj));
                        let z = self.mul(&self.nil(uj), &self.inv(&den, *idx)?);
                        self.add(&self.constant(pv(*v), d0.clone()), &self.atan_series(&z))
                    }
                }
                Op::Atan2(v, y, xx, idx) => {
                    let (yj, xj) = (at(y), at(xx));
                    if Self::is_const(yj) && Self::is_const(xj) {
                        self.constant(pv(*v), d0.clone())
                    } else {
                        // atan2(Y, X) - atan2(y0, x0) = atan((x0 Y - y0 X) / (x0 X + y0 Y)).
                        let y0 = self.constant(yj.c[0], prog.deg0[*y as usize].clone());
                        let x0 = self.constant(xj.c[0], prog.deg0[*xx as usize].clone());
                        let num = self.add(&self.mul(&x0, yj), &self.neg(&self.mul(&y0, xj)));
                        let den = self.add(&self.mul(&x0, xj), &self.mul(&y0, yj));
                        // The numerator's value is x0 y0 - y0 x0 = 0 exactly.
                        let z = self.mul(&self.nil(&num), &self.inv(&den, *idx)?);
                        self.add(&self.constant(pv(*v), d0.clone()), &self.atan_series(&z))
                    }
                }
                Op::Log(v, u, idx) | Op::Sqrt(v, u, idx) => {
                    let uj = at(u);
                    if Self::is_const(uj) {
                        self.constant(pv(*v), d0.clone())
                    } else {
                        let i0 = uj.c[0].inv().ok_or(BadPoint)?;
                        let m = self.scale(&self.nil(uj), i0, &self.inverses[*idx]);
                        if matches!(op, Op::Log(..)) {
                            // log U = log u0 + log(1 + M)
                            let s = self.series(&m, &|k| {
                                if k == 0 {
                                    Fp::ZERO
                                } else if k % 2 == 1 {
                                    inv_small(k)
                                } else {
                                    -inv_small(k)
                                }
                            });
                            self.add(&self.constant(pv(*v), d0.clone()), &s)
                        } else {
                            // sqrt U = s0 sqrt(1 + M), binomial(1/2, k) coefficients.
                            let s = self.series(&m, &|k| {
                                let half = inv_small(2);
                                (0..k).fold(Fp::ONE, |a, i| {
                                    a * (half - Fp::new(i)) * inv_small(i + 1)
                                })
                            });
                            self.scale(&s, pv(*v), &d0)
                        }
                    }
                }
            };
            if let Some(x) = j.d.first_mut() {
                *x = Some(d0);
            }
            vals.push(j);
        }
        Ok(prog
            .roots
            .iter()
            .map(|&r| vals[r as usize].clone())
            .collect())
    }

    fn atan_series(&self, z: &Jet) -> Jet {
        self.series(z, &|k| {
            if k % 2 == 0 {
                Fp::ZERO
            } else if (k / 2).is_multiple_of(2) {
                inv_small(k)
            } else {
                -inv_small(k)
            }
        })
    }
}

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
/// [`degree_bounds`]: crate::degree_bounds
pub fn height_bounds(ctx: &Ctx, roots: &[Id]) -> Vec<(f64, f64)> {
    use dashu_int::ops::BitTest;
    let order = ctx.reachable(roots);
    let mut h: Vec<(f64, f64)> = vec![(0.0, 0.0); ctx.len()];
    for id in order {
        let x = match ctx.node(id) {
            Node::Num(q) => (q.num().bit_len() as f64, q.den().bit_len() as f64),
            Node::Leaf(v) => match &ctx.leaves[*v as usize].kind {
                LeafKind::Sin(_) | LeafKind::Cos(_) => (1.0, 1.0),
                LeafKind::Sqrt(_) => (f64::INFINITY, f64::INFINITY),
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
/// their point (reconstruction, issue 15): every leaf's value at a point of
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
                LeafKind::Sqrt(_) => return None,
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
        Ok(FpPoint { values: out })
    }

    /// Exact leaf values at the rational point with these coordinate values
    /// (angles by [`crate::rational_angle`]), for [`Ctx::eval_q`]; leaves
    /// outside `coords` are unbound.
    pub fn q_point_at(&self, coords: &[Coord], values: &[crate::Q]) -> Vec<Option<crate::Q>> {
        let mut out = vec![None; self.leaves.len()];
        for (c, x) in coords.iter().zip(values) {
            match *c {
                Coord::Leaf(v) => out[v as usize] = Some(x.clone()),
                Coord::Angle { sin, cos, .. } => {
                    let (s, co) = crate::rational_angle(x);
                    out[sin as usize] = Some(s);
                    out[cos as usize] = Some(co);
                }
            }
        }
        out
    }
}

/// Arithmetic modulo a prime `q < 2^63` for [`Ctx::eval_mod_prime`].
fn mulq(a: u64, b: u64, q: u64) -> u64 {
    ((a as u128 * b as u128) % q as u128) as u64
}

fn powq(mut a: u64, mut e: u64, q: u64) -> u64 {
    let mut r = 1 % q;
    while e > 0 {
        if e & 1 == 1 {
            r = mulq(r, a, q);
        }
        a = mulq(a, a, q);
        e >>= 1;
    }
    r
}

fn invq(a: u64, q: u64) -> Option<u64> {
    (!a.is_multiple_of(q)).then(|| powq(a, q - 2, q))
}

fn int_mod(x: &crate::Int, q: u64) -> u64 {
    let qq = crate::Int::from(q);
    let mut r = x % &qq;
    if r < crate::Int::ZERO {
        r += &qq;
    }
    u64::try_from(&r).unwrap_or(0)
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
                    let d = invq(int_mod(c.den(), q), q).ok_or(BadPoint)?;
                    mulq(int_mod(c.num(), q), d, q)
                }
                Node::Leaf(v) => *leaf.get(*v as usize).ok_or(BadPoint)?,
                Node::Add(cs) => cs.iter().fold(0u64, |a, c| {
                    ((a as u128 + val[c.index()] as u128) % q as u128) as u64
                }),
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
        let addq = |a: u64, b: u64| ((a as u128 + b as u128) % q as u128) as u64;
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
                    let d = invq(int_mod(c.den(), q), q).ok_or(BadPoint)?;
                    t[base] = mulq(int_mod(c.num(), q), d, q);
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
                    let lv = *leaf.get(*v as usize).ok_or(BadPoint)?;
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
                        LeafKind::Sqrt(u) => {
                            let fac = invq(mulq(2, lv, q), q).ok_or(BadPoint)?;
                            chain(&mut t, *u, fac)?;
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
