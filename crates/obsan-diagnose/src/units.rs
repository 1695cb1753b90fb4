//! The units of the effects' params, by a small dimensional analysis of
//! where each enters (docs/diagnose.md, Units). Presentation only: nothing
//! here is fitted or weighed.
//!
//! Datasets are in SI units (docs/data-format.md) but `.sys` declares none,
//! so the analysis starts from what is known: an angle output (built on
//! `atan`/`atan2`) is in rad, time in s (a `delay`, `rate(u)` per s, the
//! session clock of generated drifts), the workflow's `later` and `index`
//! are pure numbers, and a `unit NAME = UNIT` declaration of the effects
//! file wins over everything. Any other output or input column has its own
//! opaque unit `[y]`. Every expression of an effect is then read as
//! dimensionally homogeneous: the terms of a sum share a unit, the two
//! sides of `output y = EXPR`, `subst u = EXPR`, `compare u = EXPR`,
//! `input d = EXPR` and `x' = EXPR` (x per s) agree, and a factor that is
//! the only unknown of a term is solved for. So `y + b` gives `b` the unit
//! of y, `(1 + k) y` a dimensionless k, `(u - s)/T` a T in s and
//! `u + k u t` a k in 1/s. A param met only beside the model's own params
//! and states (whose units nobody declared) stays unknown: `None`, and the
//! report prints no unit rather than a guess; so does a param two places
//! give different units.

use crate::generate::{Generated, SESSION_CLOCK};
use obsan_expr::{parse_ast, Ast, AstKind, BinOp};
use obsan_model::{Effect, EffectLibrary, Kind, System, Unit, UnitDecl};
use std::collections::{BTreeMap, BTreeSet};

/// Passes over an effect's equations: each pass can solve a name the next
/// one uses (a new state's unit, then its time constant).
const PASSES: usize = 6;

/// The unit of an expression as far as it is known.
#[derive(Clone, Debug, PartialEq)]
enum Val {
    Known(Unit),
    /// `known * var^exp`, `var` an unknown the analysis may solve for.
    Pending(Unit, String, i32),
    /// A literal 0: any unit.
    Any,
    Unknown,
}

/// The units known so far and the names still to solve.
struct Env {
    known: BTreeMap<String, Unit>,
    solvable: BTreeSet<String>,
    /// Names two places gave different units: never reported.
    conflict: BTreeSet<String>,
}

impl Env {
    fn ident(&self, n: &str) -> Val {
        if self.conflict.contains(n) {
            Val::Unknown
        } else if let Some(u) = self.known.get(n) {
            Val::Known(u.clone())
        } else if self.solvable.contains(n) {
            Val::Pending(Unit::one(), n.to_string(), 1)
        } else {
            Val::Unknown
        }
    }

    /// `known * var^exp = target`: var's unit, if the root exists.
    fn solve(&mut self, known: &Unit, var: &str, exp: i32, target: &Unit) {
        let Some(u) = target.times_pow(known, -1).and_then(|r| r.pow(1, exp)) else {
            return;
        };
        match self.known.get(var) {
            Some(old) if *old != u => {
                self.conflict.insert(var.to_string());
            }
            Some(_) => {}
            None => {
                self.known.insert(var.to_string(), u);
            }
        }
    }

    /// Both sides of an equation have one unit: solve a pending side.
    fn equate(&mut self, a: Val, b: Val) {
        match (a, b) {
            (Val::Known(t), Val::Pending(k, v, e)) | (Val::Pending(k, v, e), Val::Known(t)) => {
                self.solve(&k, &v, e, &t)
            }
            _ => {}
        }
    }

    fn eval(&mut self, a: &Ast) -> Val {
        match &a.kind {
            AstKind::Num(q) if q.is_zero() => Val::Any,
            AstKind::Num(_) | AstKind::Pi => Val::Known(Unit::one()),
            AstKind::Ident(n) => self.ident(n),
            AstKind::Neg(x) => self.eval(x),
            AstKind::Bin(BinOp::Add | BinOp::Sub, ..) => self.sum(a),
            AstKind::Bin(BinOp::Mul, l, r) => {
                let (l, r) = (self.eval(l), self.eval(r));
                product(l, r, 1)
            }
            AstKind::Bin(BinOp::Div, l, r) => {
                let (l, r) = (self.eval(l), self.eval(r));
                product(l, r, -1)
            }
            AstKind::Bin(BinOp::Pow, l, r) => {
                let base = self.eval(l);
                let p = match &r.kind {
                    AstKind::Num(q) => small_int(q),
                    AstKind::Neg(x) => match &x.kind {
                        AstKind::Num(q) => small_int(q).map(|p| -p),
                        _ => None,
                    },
                    _ => None,
                };
                match (base, p) {
                    (Val::Known(u), Some(p)) => u.pow(p, 1).map_or(Val::Unknown, Val::Known),
                    (Val::Pending(k, v, e), Some(p)) => match (k.pow(p, 1), e.checked_mul(p)) {
                        (Some(k), Some(e)) => Val::Pending(k, v, e),
                        _ => Val::Unknown,
                    },
                    (Val::Any, _) => Val::Any,
                    // A symbolic exponent needs a pure number below it.
                    (Val::Known(u), None) if u.is_one() => Val::Known(u),
                    _ => Val::Unknown,
                }
            }
            AstKind::Call(f, args) => {
                // The arguments may hold a sum to solve in.
                let vals: Vec<Val> = args.iter().map(|x| self.eval(x)).collect();
                match (f.as_str(), vals.as_slice()) {
                    ("atan" | "atan2", _) => Val::Known(Unit::base("rad")),
                    ("sqrt", [Val::Known(u)]) => u.pow(1, 2).map_or(Val::Unknown, Val::Known),
                    ("sqrt", [Val::Any]) => Val::Any,
                    ("sqrt", _) => Val::Unknown,
                    _ => Val::Known(Unit::one()),
                }
            }
        }
    }

    /// A sum's terms share its unit: the known ones fix it (when they
    /// agree) and each pending one is solved for it.
    fn sum(&mut self, a: &Ast) -> Val {
        let vals: Vec<Val> = a
            .additive_terms()
            .into_iter()
            .map(|(_, t)| self.eval(t))
            .collect();
        let mut unit: Option<&Unit> = None;
        for v in &vals {
            if let Val::Known(u) = v {
                match unit {
                    Some(w) if w != u => {
                        // Inhomogeneous: a unit solved for a name in it
                        // may be the wrong one of two.
                        for (n, _) in a.idents() {
                            if self.solvable.contains(n) {
                                self.conflict.insert(n.to_string());
                            }
                        }
                        return Val::Unknown;
                    }
                    _ => unit = Some(u),
                }
            }
        }
        let Some(u) = unit.cloned() else {
            let mut rest = vals.into_iter().filter(|v| *v != Val::Any);
            return match (rest.next(), rest.next()) {
                (None, _) => Val::Any,
                (Some(v), None) => v,
                _ => Val::Unknown,
            };
        };
        for v in vals {
            if let Val::Pending(k, var, e) = v {
                self.solve(&k, &var, e, &u);
            }
        }
        Val::Known(u)
    }

    /// The equation `lhs = text`; text that does not parse says nothing.
    fn equation(&mut self, lhs: Val, text: &str) {
        if let Ok(ast) = parse_ast(text) {
            let rhs = self.eval(&ast);
            self.equate(lhs, rhs);
        }
    }

    /// A derived input's definition: `rate(u)` is u per s.
    fn derived(&mut self, name: &str, def: &str) {
        let lhs = self.ident(name);
        let inner = def
            .trim()
            .strip_prefix("rate(")
            .and_then(|r| r.strip_suffix(')'));
        match inner.map(|u| self.ident(u.trim())) {
            Some(Val::Known(u)) => {
                let per_s = u.times_pow(&Unit::base("s"), -1);
                if let Some(r) = per_s {
                    self.equate(lhs, Val::Known(r));
                }
            }
            Some(_) => {}
            None => self.equation(lhs, def),
        }
    }
}

/// An integer exponent that fits a unit's (`None` otherwise).
fn small_int(q: &obsan_expr::Q) -> Option<i32> {
    let p = i32::try_from(q.num()).ok()?;
    (q.is_integer() && p.abs() <= obsan_model::MAX_UNIT_EXPONENT).then_some(p)
}

/// `l * r^sign`.
fn product(l: Val, r: Val, sign: i32) -> Val {
    match (l, r) {
        (Val::Any, _) | (_, Val::Any) => Val::Any,
        (Val::Known(a), Val::Known(b)) => a.times_pow(&b, sign).map_or(Val::Unknown, Val::Known),
        (Val::Known(a), Val::Pending(k, v, e)) => {
            match (a.times_pow(&k, sign), e.checked_mul(sign)) {
                (Some(k), Some(e)) => Val::Pending(k, v, e),
                _ => Val::Unknown,
            }
        }
        (Val::Pending(k, v, e), Val::Known(b)) => match k.times_pow(&b, sign) {
            Some(k) => Val::Pending(k, v, e),
            None => Val::Unknown,
        },
        (Val::Pending(k1, v1, e1), Val::Pending(k2, v2, e2)) if v1 == v2 => {
            let e = e2.checked_mul(sign).and_then(|e2| e1.checked_add(e2));
            match (k1.times_pow(&k2, sign), e) {
                (Some(k), Some(0)) => Val::Known(k),
                (Some(k), Some(e)) => Val::Pending(k, v1, e),
                _ => Val::Unknown,
            }
        }
        _ => Val::Unknown,
    }
}

/// What the model alone fixes: declarations, outputs (rad for an angle,
/// else the column's own unit), measured inputs (their column's), the
/// model's delay (s), then its derived inputs.
fn model_env(sys: &System, declared: &[UnitDecl], angular: &dyn Fn(&str) -> bool) -> Env {
    let mut known: BTreeMap<String, Unit> = BTreeMap::new();
    for y in sys.output_names() {
        let u = match angular(y) {
            true => Unit::base("rad"),
            false => Unit::column(y),
        };
        known.insert(y.to_string(), u);
    }
    for d in sys.decls_of(Kind::Input).filter(|d| d.derived.is_none()) {
        known.insert(d.name.clone(), Unit::column(&d.name));
    }
    if let Some(tau) = &sys.delay {
        known.insert(tau.clone(), Unit::base("s"));
    }
    for d in declared {
        known.insert(d.name.clone(), d.unit.clone());
    }
    let derived: Vec<(String, String)> = (sys.decls_of(Kind::Input))
        .filter_map(|d| d.derived.clone().map(|t| (d.name.clone(), t)))
        .filter(|(n, _)| !known.contains_key(n))
        .collect();
    let mut env = Env {
        known,
        solvable: derived.iter().map(|d| d.0.clone()).collect(),
        conflict: BTreeSet::new(),
    };
    for _ in 0..PASSES {
        for (n, t) in &derived {
            env.derived(n, t);
        }
    }
    env.solvable.clear();
    env
}

/// The units of one effect's params, in its order (`None`: not derived).
/// `generated`: an effect of obsan's own (its undefined `session_t` inputs
/// are the session clock, in s).
pub fn effect_units(
    sys: &System,
    effect: &Effect,
    generated: bool,
    declared: &[UnitDecl],
    angular: &dyn Fn(&str) -> bool,
) -> Vec<(String, Option<Unit>)> {
    let mut env = model_env(sys, declared, angular);
    effect_into(&mut env, effect, generated);
    effect
        .params
        .iter()
        .map(|p| {
            let u = (!env.conflict.contains(p))
                .then(|| env.known.get(p).cloned())
                .flatten();
            (p.clone(), u)
        })
        .collect()
}

fn effect_into(env: &mut Env, e: &Effect, generated: bool) {
    // A declared name keeps its declaration.
    let mut fixed: Vec<(String, Unit)> = Vec::new();
    for c in e.consts.iter().filter(|c| *c == "later" || *c == "index") {
        fixed.push((c.clone(), Unit::one()));
    }
    for (n, _) in e.inputs.iter().filter(|i| i.1.is_none()) {
        let u = match generated && n.starts_with(SESSION_CLOCK) {
            true => Unit::base("s"),
            false => Unit::column(n),
        };
        fixed.push((n.clone(), u));
    }
    if let Some(tau) = &e.delay {
        fixed.push((tau.clone(), Unit::base("s")));
    }
    for (n, u) in fixed {
        env.known.entry(n).or_insert(u);
    }
    env.solvable = (e.params.iter().chain(&e.states))
        .chain(e.inputs.iter().filter(|i| i.1.is_some()).map(|i| &i.0))
        .filter(|n| !env.known.contains_key(*n))
        .cloned()
        .collect();
    for _ in 0..PASSES {
        for (n, d) in &e.inputs {
            if let Some(d) = d {
                env.derived(n, d);
            }
        }
        for (x, start) in e.starts.iter().filter(|s| e.states.contains(&s.0)) {
            let lhs = env.ident(x);
            env.equation(lhs, start);
        }
        for (y, rhs) in e.outputs.iter().chain(&e.substs).chain(&e.compares) {
            let lhs = env.ident(y);
            env.equation(lhs, rhs);
        }
        for (x, rhs) in &e.dynamics {
            let lhs = product(env.ident(x), Val::Known(Unit::base("s")), -1);
            env.equation(lhs, rhs);
        }
    }
}

/// Every param's unit that can be derived: the model's (declared, or its
/// delay), the effects file's (model and input side) and the generated
/// candidates'. Effects are read one at a time on the nominal model, as
/// the workflow tries them.
pub fn param_units(
    sys: &System,
    lib: Option<&EffectLibrary>,
    generated: &[Generated],
    angular: &dyn Fn(&str) -> bool,
) -> BTreeMap<String, Unit> {
    let declared: &[UnitDecl] = lib.map_or(&[], |l| l.units.as_slice());
    let env = model_env(sys, declared, angular);
    let mut out: BTreeMap<String, Unit> = (sys.decls_of(Kind::Param))
        .filter_map(|d| env.known.get(&d.name).map(|u| (d.name.clone(), u.clone())))
        .collect();
    let file = lib.map(|l| l.effects.iter().map(|e| (e, false)));
    let gen = generated.iter().map(|g| (&g.effect, true));
    // Two effects may each have a param `k` (each extends the nominal
    // model alone): a name given two units has none.
    let mut two: BTreeSet<String> = BTreeSet::new();
    for (e, g) in file.into_iter().flatten().chain(gen) {
        for (p, u) in effect_units(sys, e, g, declared, angular) {
            match (u, out.get(&p)) {
                (Some(u), Some(old)) if *old == u => {}
                (Some(u), None) if !two.contains(&p) => {
                    out.insert(p, u);
                }
                _ => {
                    out.remove(&p);
                    two.insert(p);
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests;
