//! When a nonzero canonical form proves "this expression is not zero".
//!
//! The canonical form is unique in the formal field of the leaves (with
//! `s^2 + c^2 = 1` and `r^q = u` only). It says "nonzero" truthfully only when
//! the leaves it contains satisfy no other algebraic relation. This module
//! decides a sufficient condition for that (docs/engine.md, "Decided and not
//! decided", gives the argument) and names the atoms that break it.

use crate::gcd::gcd;
use crate::gcd_modular::is_prime;
use crate::graph::{Angle, Id, LeafKind};
use crate::lower::is_square_poly;
use crate::memo::Ctx;
use crate::num::{Fp, SplitMix};
use crate::poly::{Poly, Var};
use crate::ratfun::RatFun;
use crate::root::{poly_root, prime_factors, tower_parent};
use rustc_hash::FxHashSet;

/// The role of one leaf in the independence argument.
enum Role {
    /// Independent by construction (symbols, per-symbol angles and exponentials,
    /// the roots of proven primes are `PrimeRoot`).
    Free,
    /// A transcendental constant; `baker` for `pi` and the arctangent atoms of
    /// Gaussian primes (logarithms of algebraic numbers, Baker's theorem). The
    /// key groups `sin c`, `cos c` as one number.
    Transcendental { key: Var, baker: bool },
    /// A function atom over the symbols only: its class, its key (`sin u`
    /// and `cos u` share one) and its exponent (the argument of `exp`/`sin`,
    /// the atom itself for `log`, `atan`, `atan2`).
    Class(Class, Var, Id),
    /// A q-th root of a rational function of the symbols (`sqrt`: q = 2).
    FunctionRoot(u32),
    /// `root_q(p)` of a proven prime `p`: independent unless another root of
    /// the same prime has an index sharing a factor with `q`.
    PrimeRoot(u64, u32),
    /// Not provably independent of anything else.
    Undecided,
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum Class {
    Log,
    Arctangent,
    Exp,
    Angle,
}

impl Ctx {
    /// The atoms of `r` (and of its atoms' arguments) whose algebraic
    /// independence the engine cannot prove, sorted. Empty: `r` is zero exactly
    /// when its form is zero, so a nonzero form is a proof of "nonzero". Not
    /// empty: a nonzero form proves nothing (the atoms may be related, as
    /// `log(x y)`, `log(x)`, `log(y)` are). A zero form is always a proof of zero.
    pub fn undecided_atoms(&mut self, r: &RatFun) -> Vec<Var> {
        self.undecided_atoms_in(std::slice::from_ref(r), true)
    }

    /// The atoms of several forms that a claim built from all of them
    /// cannot rest on. With `linear_ok` false every product of the forms is
    /// covered (a rank's minors), so two transcendental constants are never
    /// decided; with `linear_ok` true each form is one number or function.
    pub fn undecided_atoms_in(&mut self, forms: &[RatFun], linear_ok: bool) -> Vec<Var> {
        let leaves = self.leaf_closure(forms);
        let mut bad: FxHashSet<Var> = FxHashSet::default();
        let mut trans: Vec<(Var, Var, bool)> = Vec::new();
        let mut classes: Vec<(Class, Var, Var, Id)> = Vec::new();
        let mut sqrts: Vec<(Var, u32)> = Vec::new();
        let mut prime_roots: Vec<(Var, u64, u32)> = Vec::new();
        for &v in &leaves {
            match self.role(v) {
                Role::Free => {}
                Role::Transcendental { key, baker } => trans.push((v, key, baker)),
                Role::Class(c, key, e) => classes.push((c, key, v, e)),
                Role::FunctionRoot(q) => sqrts.push((v, q)),
                Role::PrimeRoot(p, q) => prime_roots.push((v, p, q)),
                Role::Undecided => {
                    bad.insert(v);
                }
            }
        }
        // Ax's theorem: the atoms of each part are independent when their
        // exponents (generic arguments, logarithms) are Q-linearly
        // independent modulo constants together with the symbols.
        for part in [[Class::Log, Class::Exp], [Class::Arctangent, Class::Angle]] {
            let mut members: Vec<(Var, Id)> = Vec::new();
            for e in classes.iter().filter(|e| part.contains(&e.0)) {
                if !members.iter().any(|m| m.0 == e.1) {
                    members.push((e.1, e.3));
                }
            }
            if !members.is_empty() && !self.exponents_independent(&members, &leaves) {
                bad.extend(classes.iter().filter(|e| part.contains(&e.0)).map(|e| e.2));
            }
        }
        if !self.sqrts_independent(&sqrts) && !self.roots_independent_over_q(&sqrts, &prime_roots) {
            bad.extend(sqrts.iter().map(|s| s.0));
        }
        // Roots of distinct primes are independent (Besicovitch), and so are
        // p^(1/a), p^(1/b) with gcd(a, b) = 1 (they generate p^(1/ab), of
        // degree ab by Eisenstein); p^(1/2), p^(1/4) are not.
        for &(v, p, q) in &prime_roots {
            let shared = prime_roots
                .iter()
                .any(|&(w, p2, q2)| w != v && p2 == p && gcd_u32(q, q2) > 1);
            if shared {
                bad.insert(v);
            }
        }
        if !constants_independent(forms, &trans, linear_ok) {
            bad.extend(trans.iter().map(|t| t.0));
        }
        let mut out: Vec<Var> = bad.into_iter().collect();
        out.sort_unstable();
        out
    }

    /// [`Ctx::undecided_atoms`] as text, one atom each (`log(x)`, `sin(x*y)`).
    pub fn undecided_atom_texts(&mut self, r: &RatFun) -> Vec<String> {
        let vs = self.undecided_atoms(r);
        self.atom_texts(&vs)
    }

    /// Leaves as sorted, distinct text.
    pub fn atom_texts(&self, vs: &[Var]) -> Vec<String> {
        let mut out: Vec<String> = vs.iter().map(|&v| self.leaf_text(v)).collect();
        out.sort();
        out.dedup();
        out
    }

    /// Every leaf of `r`, and of the canonical forms of its atoms' arguments.
    fn leaf_closure(&mut self, forms: &[RatFun]) -> Vec<Var> {
        let mut seen: FxHashSet<Var> = FxHashSet::default();
        let mut stack: Vec<Var> = Vec::new();
        for r in forms {
            stack.extend(r.num.vars());
            stack.extend(r.den.vars());
        }
        while let Some(v) = stack.pop() {
            if !seen.insert(v) {
                continue;
            }
            for a in self.leaf_args(v) {
                let f = self.canon(a);
                stack.extend(f.num.vars());
                stack.extend(f.den.vars());
            }
        }
        let mut out: Vec<Var> = seen.into_iter().collect();
        out.sort_unstable();
        out
    }

    /// The canonical form of an atom's argument, if it is a function of the
    /// symbols only (no other leaf).
    fn symbols_only(&mut self, a: Id) -> Option<RatFun> {
        self.argument_over(a, false)
    }

    /// The canonical form of an atom's argument if its leaves are symbols
    /// or, with `per_symbol`, also the per-symbol `sin`, `cos`, `exp` (whose
    /// field is, by Ax's theorem, that of independent transcendentals).
    fn argument_over(&mut self, a: Id, per_symbol: bool) -> Option<RatFun> {
        let f = self.canon(a);
        let only = f.num.vars().into_iter().chain(f.den.vars()).all(|w| {
            match &self.leaves[w as usize].kind {
                LeafKind::Symbol(_) => true,
                LeafKind::Sin(Angle::Symbol { .. })
                | LeafKind::Cos(Angle::Symbol { .. })
                | LeafKind::Exp(Angle::Symbol { .. }) => per_symbol,
                _ => false,
            }
        });
        only.then_some(f)
    }

    fn role(&mut self, v: Var) -> Role {
        let leaf = &self.leaves[v as usize];
        let partner = leaf.partner;
        match leaf.kind.clone() {
            LeafKind::Symbol(_) => Role::Free,
            LeafKind::Sin(Angle::Symbol { .. })
            | LeafKind::Cos(Angle::Symbol { .. })
            | LeafKind::Exp(Angle::Symbol { .. }) => Role::Free,
            LeafKind::Pi => Role::Transcendental {
                key: v,
                baker: true,
            },
            LeafKind::Root(a, k) => {
                // A tower over another root (root.rs, `related_root`): its
                // relation is irreducible by construction and it generates
                // nothing beyond its base's root of the product index.
                let base = self.canon(a);
                if tower_parent(&base).is_some_and(|w| self.root_arg(w).is_some()) {
                    return Role::Free;
                }
                let Some(f) = self.symbols_only(a) else {
                    return Role::Undecided;
                };
                match f.as_q() {
                    // An atom per prime (lower.rs, root.rs): a cofactor that is
                    // not proven prime may share a power class with a product.
                    Some(q) => match u64::try_from(q.num()) {
                        Ok(n) if q.is_integer() && is_prime(n) => Role::PrimeRoot(n, k),
                        _ => Role::Undecided,
                    },
                    None => Role::FunctionRoot(k),
                }
            }
            LeafKind::Atan(a) => match self.argument_over(a, true) {
                Some(f) => match f.as_q() {
                    // arg(q + ip) of a Gaussian prime (gauss.rs) when its norm is prime.
                    Some(q) => {
                        let norm = q.num() * q.num() + q.den() * q.den();
                        match u64::try_from(&norm) {
                            Ok(n) if is_prime(n) => Role::Transcendental {
                                key: v,
                                baker: true,
                            },
                            _ => Role::Undecided,
                        }
                    }
                    None => Role::Class(Class::Arctangent, v, self.leaf_node(v)),
                },
                None => Role::Undecided,
            },
            LeafKind::Atan2(y, x) => {
                let fy = self.argument_over(y, true);
                let fx = self.argument_over(x, true);
                match (fy, fx) {
                    (Some(fy), Some(fx)) if fy.as_q().is_none() || fx.as_q().is_none() => {
                        Role::Class(Class::Arctangent, v, self.leaf_node(v))
                    }
                    _ => Role::Undecided,
                }
            }
            LeafKind::Log(a) => {
                let node = self.leaf_node(v);
                self.constant_or_class(a, v, Class::Log, node)
            }
            LeafKind::Exp(Angle::Generic(a)) => self.constant_or_class(a, v, Class::Exp, a),
            LeafKind::Sin(Angle::Generic(a)) | LeafKind::Cos(Angle::Generic(a)) => {
                let key = partner.map_or(v, |p| p.min(v));
                self.constant_or_class(a, key, Class::Angle, a)
            }
        }
    }

    /// A log, exp or angle atom: of a rational constant, a transcendental
    /// number (Lindemann); of a function of the symbols, a member of its class.
    fn constant_or_class(&mut self, a: Id, key: Var, class: Class, exponent: Id) -> Role {
        match self.argument_over(a, true) {
            Some(f) => match f.as_q() {
                Some(_) => Role::Transcendental { key, baker: false },
                None => Role::Class(class, key, exponent),
            },
            None => Role::Undecided,
        }
    }

    /// Whether no nonzero Q-combination of the exponents is a constant plus a
    /// Q-combination of the symbols: equivalently (differentiate twice) their
    /// Hessians in the symbols are Q-linearly independent. Proven when the
    /// Hessians' values at random points of F_p have full rank (a relation
    /// over Q, made integral and primitive, would survive reduction mod p);
    /// otherwise answered "no", which only leaves a form undecided.
    fn exponents_independent(&mut self, members: &[(Var, Id)], leaves: &[Var]) -> bool {
        let syms: Vec<Var> = leaves
            .iter()
            .copied()
            .filter(|&w| matches!(self.leaves[w as usize].kind, LeafKind::Symbol(_)))
            .collect();
        let mut hess: Vec<Id> = Vec::new();
        for &(_, f) in members {
            for (i, &a) in syms.iter().enumerate() {
                let da = self.diff(f, a);
                for &b in &syms[i..] {
                    hess.push(self.diff(da, b));
                }
            }
        }
        let per = hess.len() / members.len().max(1);
        if per == 0 {
            return false;
        }
        let mut rows: Vec<Vec<Fp>> = vec![Vec::new(); members.len()];
        let mut rng = SplitMix(0x5eed_0b5a_4e11_u64 ^ members.len() as u64);
        let mut points = 0;
        for _ in 0..4 * members.len() + 4 {
            if points > members.len() {
                break;
            }
            let Ok(pt) = self.random_point(&mut rng, &|_| None, false) else {
                continue;
            };
            let Ok(vals) = self.eval_fp(&hess, &pt) else {
                continue;
            };
            for (j, row) in rows.iter_mut().enumerate() {
                row.extend_from_slice(&vals[j * per..(j + 1) * per]);
            }
            points += 1;
        }
        Fp::matrix_rank(rows) == members.len()
    }

    /// Square roots of rational functions of the symbols generate a proper
    /// tower when the square-free classes of their radicands are independent:
    /// sufficient, each radicand's primitive part (numerator times denominator,
    /// content and sign removed) is not a square and any two are coprime, so
    /// that every product of a subset has an irreducible factor to an odd power.
    fn sqrts_independent(&self, sqrts: &[(Var, u32)]) -> bool {
        let mut parts: Vec<Poly> = Vec::new();
        let mut groups: Vec<(RatFun, Vec<u32>)> = Vec::new();
        for &(v, q) in sqrts {
            let Some(r) = self.radicand(v) else {
                return false;
            };
            // N/D is an l-th power over C iff the primitive part of N D^(l-1)
            // (sign and content removed) is one in Z[x].
            for l in prime_factors(q) {
                let p = r.num.mul(&r.den.pow(l - 1));
                let c = p.content();
                let Some(prim) = p.div_exact(&Poly::constant(c)) else {
                    return false;
                };
                let prim = prim.normalize_sign();
                let power = if l == 2 {
                    is_square_poly(&prim)
                } else {
                    poly_root(&prim, l).is_some()
                };
                if power {
                    return false;
                }
            }
            // Roots of one radicand at pairwise coprime indices generate its
            // root of their product (no l-th power for any l dividing it), so
            // the radicand counts once below.
            if let Some(g) = groups.iter_mut().find(|g| &g.0 == r) {
                if g.1.iter().any(|&k| gcd_u32(k, q) > 1) {
                    return false;
                }
                g.1.push(q);
                continue;
            }
            groups.push((r.clone(), vec![q]));
            let p = r.num.mul(&r.den);
            let c = p.content();
            let Some(prim) = p.div_exact(&Poly::constant(c)) else {
                return false;
            };
            parts.push(prim.normalize_sign());
        }
        // Kummer theory splits by primes: roots whose indices share no prime
        // never interact (sqrt(u), v^(1/5) generate a field of degree 10 for any
        // non-square u and non-5th-power v), so only those that share one need
        // coprime radicands.
        for (i, a) in parts.iter().enumerate() {
            for (j, b) in parts.iter().enumerate().skip(i + 1) {
                let share = groups[i]
                    .1
                    .iter()
                    .any(|&x| groups[j].1.iter().any(|&y| gcd_u32(x, y) > 1));
                if share && !gcd(a, b).is_constant() {
                    return false;
                }
            }
        }
        true
    }
}

fn gcd_u32(mut a: u32, mut b: u32) -> u32 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Numbers built from the transcendental constants are decided when there is
/// at most one of them (it is transcendental over the algebraic numbers), or
/// when all are `pi` and arctangents of Gaussian primes and every term of the
/// form is of degree at most 1 in them jointly (a linear form in logarithms of
/// algebraic numbers that are Q-independent: Baker's theorem).
fn constants_independent(forms: &[RatFun], trans: &[(Var, Var, bool)], linear_ok: bool) -> bool {
    let keys: FxHashSet<Var> = trans.iter().map(|t| t.1).collect();
    if keys.len() <= 1 {
        return true;
    }
    if !linear_ok || !trans.iter().all(|t| t.2) {
        return false;
    }
    let tv: FxHashSet<Var> = trans.iter().map(|t| t.0).collect();
    forms.iter().flat_map(|r| [&r.num, &r.den]).all(|p| {
        p.terms().iter().all(|(m, _)| {
            m.iter()
                .filter(|(v, _)| tv.contains(v))
                .map(|(_, e)| u64::from(e))
                .sum::<u64>()
                <= 1
        })
    })
}
