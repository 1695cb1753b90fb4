//! The expression arena: one node per distinct subexpression (hash-consing).
//!
//! Invariant: the children of a node, and the arguments of a leaf's atom, have
//! smaller ids than the node itself, so a pass in increasing id order visits
//! children first and no pass needs recursion (deep Lie derivatives would
//! overflow the stack otherwise). Debug builds assert it on every insertion.
//!
//! Nodes hold only `+`, `*`, integer powers, rational numbers and leaves.
//! Every function is lowered to leaves when it is built (see `lower.rs`):
//! `sin(gamma - phi)` becomes `s_gamma c_phi - c_gamma s_phi` over the per-symbol
//! leaves `sin(gamma)`, `cos(gamma)`, ...; `atan`, `exp`, `log`, `sqrt` of other
//! arguments become atom leaves with their derivative rules. The leaves are
//! exactly the variables of the canonical form's polynomials.

use crate::budget::{self, Budget, Limit, NUM_BITS_MAX, POW_MAX};
use crate::num::Q;
use crate::poly::Var;
use dashu_int::ops::BitTest;
use rustc_hash::FxHashMap;
use std::fmt;

/// Id of a node in a [`crate::Ctx`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Id(pub(crate) u32);

impl Id {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub(crate) enum Node {
    Num(Q),
    Leaf(Var),
    /// Sum of at least two children, sorted by id.
    Add(Box<[Id]>),
    /// Product of at least two children, sorted by id; at most one number, first.
    Mul(Box<[Id]>),
    /// Integer power, exponent not 0 or 1.
    Pow(Id, i32),
}

/// The angle of a `sin`/`cos` leaf.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub(crate) enum Angle {
    /// `sym / den` for a rational symbol (den >= 1): the per-symbol angle.
    Symbol { sym: Var, den: u32 },
    /// Any other argument, in canonical form (an atom of its own).
    Generic(Id),
}

/// What a leaf stands for.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub(crate) enum LeafKind {
    Symbol(String),
    Pi,
    Sin(Angle),
    Cos(Angle),
    /// `exp(sym / den)` per symbol, or `exp(arg)` for any other argument.
    Exp(Angle),
    Atan(Id),
    Atan2(Id, Id),
    Log(Id),
    /// The real q-th root `root_q(u)`, `q >= 2` (`q = 2` is `sqrt`), with the
    /// relation `r^q = u`.
    Root(Id, u32),
}

#[derive(Clone, Debug)]
pub(crate) struct Leaf {
    pub kind: LeafKind,
    pub node: Id,
    /// For `sin` leaves the matching `cos` leaf and vice versa.
    pub partner: Option<Var>,
}

/// The arena: nodes, leaves and symbols, and the node budget. The memo
/// tables of the passes live beside it in [`crate::Ctx`], which derefs to it.
#[derive(Default, Clone)]
pub struct Arena {
    pub(crate) nodes: Vec<Node>,
    dedup: FxHashMap<Node, Id>,
    pub(crate) leaves: Vec<Leaf>,
    leaf_dedup: FxHashMap<LeafKind, Var>,
    pub(crate) symbols: FxHashMap<String, Var>,
    /// Per-symbol unit denominators of angles and exponentials.
    pub(crate) angle_units: FxHashMap<(Var, bool), u32>,
    /// (sin leaf, cos leaf, half-angle symbol t) for every angle pair.
    pub(crate) half_angles: Vec<(Var, Var, Var)>,
    /// The limits of budgeted entry points ([`crate::Ctx::within_budget`]).
    pub(crate) budget: Budget,
    /// Arena size in cells (a node and its children).
    cells: usize,
    /// The node budget while a budgeted entry point runs.
    pub(crate) cell_cap: Option<usize>,
}

impl fmt::Debug for Arena {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Arena({} nodes, {} leaves)",
            self.nodes.len(),
            self.leaves.len()
        )
    }
}

/// A rational symbol of a context.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Symbol {
    pub var: Var,
    pub id: Id,
}

impl Arena {
    pub(crate) fn node(&self, id: Id) -> &Node {
        &self.nodes[id.index()]
    }

    /// Number of nodes in the arena.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    pub(crate) fn intern(&mut self, n: Node) -> Id {
        if let Some(&id) = self.dedup.get(&n) {
            return id;
        }
        let Ok(next) = u32::try_from(self.nodes.len()) else {
            budget::trip(Limit::Nodes {
                nodes: self.nodes.len(),
                max: u32::MAX as usize,
            });
            // Placeholder for a tripped computation, which is discarded.
            return Id(0);
        };
        let id = Id(next);
        self.cells += 1 + match &n {
            Node::Add(cs) | Node::Mul(cs) => cs.len(),
            _ => 0,
        };
        if let Some(max) = self.cell_cap.filter(|&m| self.cells > m) {
            budget::trip(Limit::Nodes {
                nodes: self.cells,
                max,
            });
        }
        #[cfg(debug_assertions)]
        match &n {
            Node::Add(cs) | Node::Mul(cs) => {
                debug_assert!(cs.iter().all(|c| *c < id), "child after parent")
            }
            Node::Pow(b, _) => debug_assert!(*b < id),
            _ => {}
        }
        self.nodes.push(n.clone());
        self.dedup.insert(n, id);
        id
    }

    /// The rational symbol `name`, created on first use.
    pub fn symbol(&mut self, name: &str) -> Symbol {
        if let Some(&v) = self.symbols.get(name) {
            return Symbol {
                var: v,
                id: self.leaves[v as usize].node,
            };
        }
        let v = self.leaf(LeafKind::Symbol(name.to_string()));
        self.symbols.insert(name.to_string(), v);
        Symbol {
            var: v,
            id: self.leaves[v as usize].node,
        }
    }

    /// Number of leaves (symbols and atoms); leaves are numbered 0..n.
    pub fn leaf_count(&self) -> usize {
        self.leaves.len()
    }

    /// Look up an existing symbol.
    pub fn lookup(&self, name: &str) -> Option<Symbol> {
        self.symbols.get(name).map(|&v| Symbol {
            var: v,
            id: self.leaves[v as usize].node,
        })
    }

    /// The arguments of an angle atom: `(u, None)` for `atan(u)`, `(y, Some(x))`
    /// for `atan2(y, x)`; `None` for any other leaf.
    pub fn atan_args(&self, v: Var) -> Option<(Id, Option<Id>)> {
        match self.leaves.get(v as usize)?.kind {
            LeafKind::Atan(u) => Some((u, None)),
            LeafKind::Atan2(y, x) => Some((y, Some(x))),
            _ => None,
        }
    }

    /// The radicand of a `sqrt` leaf; `None` for any other leaf (q-th roots
    /// with `q > 2` included: see [`Arena::root_arg`]).
    pub fn sqrt_arg(&self, v: Var) -> Option<Id> {
        match self.leaves.get(v as usize)?.kind {
            LeafKind::Root(u, 2) => Some(u),
            _ => None,
        }
    }

    /// The radicand and index `q` of a root leaf `root_q(u)` (`sqrt` is `q = 2`).
    pub fn root_arg(&self, v: Var) -> Option<(Id, u32)> {
        match self.leaves.get(v as usize)?.kind {
            LeafKind::Root(u, q) => Some((u, q)),
            _ => None,
        }
    }

    /// Name of a symbol variable (`None` for atoms).
    pub fn symbol_name(&self, v: Var) -> Option<&str> {
        match &self.leaves.get(v as usize)?.kind {
            LeafKind::Symbol(s) => Some(s),
            _ => None,
        }
    }

    pub(crate) fn leaf(&mut self, kind: LeafKind) -> Var {
        if let Some(&v) = self.leaf_dedup.get(&kind) {
            return v;
        }
        let Ok(v) = u32::try_from(self.leaves.len()) else {
            budget::trip(Limit::Nodes {
                nodes: self.leaves.len(),
                max: u32::MAX as usize,
            });
            return 0;
        };
        // Reserve the leaf before interning its node (the node refers to it).
        self.leaves.push(Leaf {
            kind: kind.clone(),
            node: Id(0),
            partner: None,
        });
        let node = self.intern(Node::Leaf(v));
        self.leaves[v as usize].node = node;
        self.leaf_dedup.insert(kind, v);
        v
    }

    pub(crate) fn leaf_node(&self, v: Var) -> Id {
        self.leaves[v as usize].node
    }

    /// The node of the leaf, and its arguments (for traversals).
    pub(crate) fn leaf_args(&self, v: Var) -> Vec<Id> {
        match &self.leaves[v as usize].kind {
            LeafKind::Sin(Angle::Generic(a))
            | LeafKind::Cos(Angle::Generic(a))
            | LeafKind::Exp(Angle::Generic(a)) => vec![*a],
            LeafKind::Atan(a) | LeafKind::Log(a) | LeafKind::Root(a, _) => vec![*a],
            LeafKind::Atan2(y, x) => vec![*y, *x],
            LeafKind::Sin(Angle::Symbol { sym, .. })
            | LeafKind::Cos(Angle::Symbol { sym, .. })
            | LeafKind::Exp(Angle::Symbol { sym, .. }) => {
                vec![self.leaf_node(*sym)]
            }
            LeafKind::Symbol(_) | LeafKind::Pi => vec![],
        }
    }

    /// Children of a node including leaf arguments.
    pub(crate) fn deps(&self, id: Id) -> Vec<Id> {
        match self.node(id) {
            Node::Num(_) => vec![],
            Node::Leaf(v) => self.leaf_args(*v),
            Node::Add(cs) | Node::Mul(cs) => cs.to_vec(),
            Node::Pow(b, _) => vec![*b],
        }
    }

    /// Whether `id` is a sum node (as written: `N - A - I` in a field).
    pub fn is_sum(&self, id: Id) -> bool {
        matches!(self.node(id), Node::Add(_))
    }

    /// All nodes reachable from `roots`, in increasing id order (children first).
    pub fn reachable(&self, roots: &[Id]) -> Vec<Id> {
        self.reachable_with(roots, true)
    }

    /// As [`Ctx::reachable`](crate::Ctx#method.reachable); without leaf arguments when `leaf_args` is false
    /// (for evaluations that are given the value of every leaf).
    pub(crate) fn reachable_with(&self, roots: &[Id], leaf_args: bool) -> Vec<Id> {
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<Id> = roots.to_vec();
        let mut out = Vec::new();
        while let Some(id) = stack.pop() {
            if std::mem::replace(&mut seen[id.index()], true) {
                continue;
            }
            out.push(id);
            if leaf_args || !matches!(self.node(id), Node::Leaf(_)) {
                stack.extend(self.deps(id));
            }
        }
        out.sort_unstable();
        out
    }

    /// Number of distinct nodes needed to represent `roots` (a size measure).
    pub fn count_nodes(&self, roots: &[Id]) -> usize {
        self.reachable(roots).len()
    }

    // ---- numbers -------------------------------------------------------

    pub fn num(&mut self, q: Q) -> Id {
        self.intern(Node::Num(q))
    }
    pub fn int(&mut self, n: i64) -> Id {
        self.num(Q::from_i64(n))
    }
    pub fn zero(&mut self) -> Id {
        self.int(0)
    }
    pub fn one(&mut self) -> Id {
        self.int(1)
    }
    pub fn as_num(&self, id: Id) -> Option<&Q> {
        match self.node(id) {
            Node::Num(q) => Some(q),
            _ => None,
        }
    }
    pub fn is_zero(&self, id: Id) -> bool {
        self.as_num(id).is_some_and(|q| q.is_zero())
    }
    pub fn pi(&mut self) -> Id {
        let v = self.leaf(LeafKind::Pi);
        self.leaf_node(v)
    }

    // ---- ring operations with light simplification -------------------

    /// Sum. Flattens, folds numbers, merges equal terms (`x + x = 2*x`) and sorts.
    pub fn add(&mut self, xs: &[Id]) -> Id {
        let mut c = Q::zero();
        let mut terms: Vec<(Id, Q)> = Vec::new();
        let mut stack: Vec<Id> = xs.to_vec();
        let mut others: Vec<Id> = Vec::new();
        // Read the nodes in place: cloning each one copied every nested sum's
        // child list and every number (a long printed form re-read as a
        // balanced tree of sums flattens each level again).
        while let Some(x) = stack.pop() {
            match self.node(x) {
                Node::Num(q) => c = c.add(q),
                Node::Add(cs) => stack.extend(cs.iter().copied()),
                _ => others.push(x),
            }
        }
        for x in others {
            let (k, rest) = self.split_coeff(x);
            terms.push((rest, k));
        }
        terms.sort_unstable_by_key(|t| t.0);
        let mut merged: Vec<Id> = Vec::new();
        let mut i = 0;
        while i < terms.len() {
            let mut k = terms[i].1.clone();
            let mut j = i + 1;
            while j < terms.len() && terms[j].0 == terms[i].0 {
                k = k.add(&terms[j].1);
                j += 1;
            }
            if k.is_one() {
                // A unit coefficient needs no product node (long sums rebuild many).
                merged.push(terms[i].0);
            } else if !k.is_zero() {
                let kn = self.num(k);
                merged.push(self.mul(&[kn, terms[i].0]));
            }
            i = j;
        }
        if !c.is_zero() {
            merged.push(self.num(c));
        }
        match merged.len() {
            0 => self.zero(),
            1 => merged[0],
            _ => {
                merged.sort_unstable();
                self.intern(Node::Add(merged.into()))
            }
        }
    }

    /// `k * rest` with k the numeric factor of a product.
    fn split_coeff(&mut self, x: Id) -> (Q, Id) {
        if let Node::Mul(cs) = self.node(x) {
            if let Some(Node::Num(q)) = cs.first().map(|c| self.node(*c)) {
                let q = q.clone();
                let rest: Vec<Id> = cs[1..].to_vec();
                let r = if rest.len() == 1 {
                    rest[0]
                } else {
                    self.intern(Node::Mul(rest.into()))
                };
                return (q, r);
            }
        }
        (Q::one(), x)
    }

    /// Product. Flattens, folds numbers, merges powers of equal factors, sorts.
    pub fn mul(&mut self, xs: &[Id]) -> Id {
        let mut c = Q::one();
        let mut facs: Vec<(Id, i64)> = Vec::new();
        let mut stack: Vec<Id> = xs.to_vec();
        while let Some(x) = stack.pop() {
            match self.node(x) {
                Node::Num(q) => c = c.mul(q),
                Node::Mul(cs) => stack.extend(cs.iter().copied()),
                Node::Pow(b, k) => facs.push((*b, *k as i64)),
                _ => facs.push((x, 1)),
            }
        }
        if c.is_zero() {
            return self.zero();
        }
        facs.sort_unstable_by_key(|t| t.0);
        let mut out: Vec<Id> = Vec::new();
        let mut i = 0;
        while i < facs.len() {
            // Each exponent is an i32 and there are fewer than 2^32 factors: no i64 overflow.
            let mut e = facs[i].1;
            let mut j = i + 1;
            while j < facs.len() && facs[j].0 == facs[i].0 {
                e = e.saturating_add(facs[j].1);
                j += 1;
            }
            if e != 0 {
                out.push(self.pow_raw(facs[i].0, e));
            }
            i = j;
        }
        out.sort_unstable();
        if !c.is_one() || out.is_empty() {
            let cn = self.num(c);
            out.insert(0, cn);
        }
        match out.len() {
            1 => out[0],
            _ => self.intern(Node::Mul(out.into())),
        }
    }

    fn pow_raw(&mut self, b: Id, e: i64) -> Id {
        let Some(e) = i32::try_from(e)
            .ok()
            .filter(|e| (*e as i64).abs() <= POW_MAX)
        else {
            budget::trip(Limit::Degree {
                degree: e.unsigned_abs() as u128,
                max: POW_MAX as u128,
            });
            return b;
        };
        match e {
            0 => self.one(),
            1 => b,
            _ => self.intern(Node::Pow(b, e)),
        }
    }

    /// Integer power. Panics on `0^-k` (the caller checks divisors) and on an
    /// exponent beyond `i32` outside a budgeted scope, where both are errors.
    pub fn pow(&mut self, b: Id, e: i64) -> Id {
        if let Node::Num(q) = self.node(b) {
            // Refuse a value over the number size before computing it.
            let bits = power_bits(q, e.unsigned_abs() as u128);
            if bits > NUM_BITS_MAX {
                budget::trip(Limit::Number {
                    bits,
                    max: NUM_BITS_MAX,
                });
                return b;
            }
            let Some(q) = q.powi(e) else {
                budget::trip(Limit::Internal("0 raised to a negative power"));
                return b;
            };
            return self.num(q);
        }
        if let Node::Pow(bb, k) = *self.node(b) {
            return self.pow(bb, (k as i64).saturating_mul(e));
        }
        self.pow_raw(b, e)
    }

    pub fn neg(&mut self, x: Id) -> Id {
        let m = self.int(-1);
        self.mul(&[m, x])
    }
    pub fn sub(&mut self, a: Id, b: Id) -> Id {
        let nb = self.neg(b);
        self.add(&[a, nb])
    }
    /// Quotient. Panics if `b` is the number 0; use [`Ctx::checked_div`](crate::Ctx#method.checked_div) for untrusted input.
    pub fn div(&mut self, a: Id, b: Id) -> Id {
        let ib = self.pow(b, -1);
        self.mul(&[a, ib])
    }
}

/// A lower bound on the bits of `q^e` (numerator and denominator together):
/// `|p| >= 2^(bits(p) - 1)`, so `p^e` has at least `e (bits(p) - 1) + 1` bits.
/// Being a lower bound, refusing above the limit never refuses a number that fits.
pub(crate) fn power_bits(q: &Q, e: u128) -> u128 {
    let above_one = |n: usize| (n as u128).saturating_sub(1);
    let bits = above_one(q.num().bit_len()) + above_one(q.den().bit_len());
    if bits == 0 {
        return 1;
    }
    bits.saturating_mul(e).saturating_add(1)
}

impl Arena {
    /// Whether an expression contains an `atan` or `atan2` leaf: its values
    /// are angles, and differences of them should be wrapped to (-pi, pi].
    pub fn is_angle_valued(&self, id: Id) -> bool {
        self.reachable(&[id])
            .iter()
            .any(|&n| matches!(self.node(n), Node::Leaf(v) if matches!(self.leaves[*v as usize].kind, LeafKind::Atan(_) | LeafKind::Atan2(_, _))))
    }
}

impl Arena {
    /// Set the limits that budgeted entry points ([`crate::Ctx::within_budget`],
    /// [`crate::Ctx::try_canon`], parsing, building and substitution) enforce.
    pub fn set_budget(&mut self, b: Budget) {
        self.budget = b;
    }

    /// The current limits (the defaults unless [`Ctx::set_budget`](crate::Ctx#method.set_budget) was called).
    pub fn budget(&self) -> Budget {
        self.budget
    }
}
