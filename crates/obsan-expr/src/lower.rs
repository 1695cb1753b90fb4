//! Functions, lowered to leaves as they are built (engine.md section 2).
//!
//! - `sin`, `cos` of `sum_i n_i x_i + k pi + rest`: expanded by the addition
//!   formulas into per-symbol leaves `sin(x_i)`, `cos(x_i)`, exact values for
//!   multiples of pi/4 and pi/6, and one angle atom for `rest`;
//! - `exp` likewise into per-symbol leaves `exp(x_i)` times an atom for the rest;
//! - `atan`, `atan2`, `log`, `sqrt`: one atom per canonical argument, after
//!   normalisation (odd symmetry of atan, square factors out of sqrt);
//! - `tan = sin / cos`, `a^(n/2) = sqrt(a)^n`, `a^(p/q) = root_q(a)^p`
//!   (root.rs), `a^b = exp(b log a)`.
//!
//! A symbol's angles must be integer multiples of one unit (`x` and `2x`, or
//! `x/2` and `3x/2`); mixing `sin(x)` with `sin(x/3)` is refused with an error,
//! never silently treated as independent.

use crate::budget;
use crate::gauss;
use crate::graph::{power_bits, Angle, Id, LeafKind, Node};
use crate::memo::Ctx;
use crate::num::{int, int_exact_sqrt, trial_factor, Int, Q};
use crate::poly::{Mono, Poly, Var};
use crate::ratfun::RatFun;
use std::fmt;

/// An error from building an expression (the parser adds the position).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EngineError(pub String);

impl fmt::Display for EngineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for EngineError {}

pub(crate) type R<T> = Result<T, EngineError>;

pub(crate) fn err<T>(msg: impl Into<String>) -> R<T> {
    Err(EngineError(msg.into()))
}

impl From<crate::budget::Limit> for EngineError {
    fn from(l: crate::budget::Limit) -> EngineError {
        EngineError(l.to_string())
    }
}

/// An error if the budget has tripped: no leaf may be made from a placeholder.
pub(crate) fn stop() -> R<()> {
    if budget::tripped() {
        let why = budget::reason().map_or_else(|| "engine limit".to_string(), |l| l.to_string());
        return err(why);
    }
    Ok(())
}

/// The linear part of an argument: `sum coeff_i sym_i + pi_coeff pi + rest`.
struct Linear {
    syms: Vec<(Var, Q)>,
    pi: Q,
    rest: RatFun,
}

impl Ctx {
    /// The canonical form, or an error if computing it hit the budget.
    pub(crate) fn canon_ok(&mut self, u: Id) -> R<RatFun> {
        let c = self.canon(u);
        stop()?;
        Ok(c)
    }

    fn split_linear(&self, c: &RatFun) -> Linear {
        let Some(d) = c.den.as_constant() else {
            return Linear {
                syms: vec![],
                pi: Q::zero(),
                rest: c.clone(),
            };
        };
        let mut syms = Vec::new();
        let mut pi = Q::zero();
        let mut rest = Vec::new();
        for (m, k) in c.num.terms() {
            let mut it = m.iter();
            let single = match (it.next(), it.next()) {
                (Some((v, 1)), None) => Some(v),
                _ => None,
            };
            let coeff = Q::new(k.clone(), d.clone());
            match single.map(|v| &self.leaves[v as usize].kind) {
                Some(LeafKind::Symbol(_)) => {
                    if let Some(v) = single {
                        syms.push((v, coeff))
                    }
                }
                Some(LeafKind::Pi) => pi = pi.add(&coeff),
                _ => rest.push((m.clone(), k.clone())),
            }
        }
        let rest = RatFun {
            num: Poly::from_terms(rest),
            den: Poly::constant(d),
        };
        let rest = if rest.num.is_zero() {
            RatFun::zero()
        } else {
            self.normalize(rest.num, rest.den)
        };
        Linear { syms, pi, rest }
    }

    /// The unit denominator of symbol `sym`'s angles (or exponentials), and the
    /// integer multiple of that unit which `coeff` is.
    fn unit_multiple(&mut self, sym: Var, coeff: &Q, exp: bool) -> R<(u32, i64)> {
        let name = self.symbol_name(sym).unwrap_or("?").to_string();
        let den = u32::try_from(coeff.den()).ok().filter(|d| *d <= 1000);
        let Some(den) = den else {
            return err(format!(
                "the coefficient {coeff} of {name} inside a function is too fine a fraction"
            ));
        };
        let unit = *self.angle_units.entry((sym, exp)).or_insert(den);
        let n = coeff.mul(&Q::from_i64(unit as i64));
        if !n.is_integer() {
            let f = if exp { "exp" } else { "sin/cos" };
            return err(format!(
                "{f} of {name} is used both with unit {name}/{unit} and with coefficient {coeff}: \
                 angles of one symbol must be integer multiples of one unit (introduce a new symbol for the fraction)"
            ));
        }
        let n = i64::try_from(n.num()).ok().filter(|n| n.abs() <= 64);
        match n {
            Some(n) => Ok((unit, n)),
            None => err(format!(
                "the multiple of {name} inside {} is too large",
                if exp { "exp" } else { "sin/cos" }
            )),
        }
    }

    /// The (cos, sin) leaf nodes of an angle, created together.
    fn angle_pair(&mut self, a: Angle) -> (Id, Id) {
        let s = self.leaf(LeafKind::Sin(a.clone()));
        let c = self.leaf(LeafKind::Cos(a));
        if self.leaves[s as usize].partner.is_none() {
            self.leaves[s as usize].partner = Some(c);
            self.leaves[c as usize].partner = Some(s);
            // The half-angle symbol of this pair (see tanhalf.rs), made now so
            // that inversion, which only reads the context, can use it.
            let t = self.symbol(&format!("\u{27e8}t{s}\u{27e9}")).var;
            self.half_angles.push((s, c, t));
        }
        (self.leaf_node(c), self.leaf_node(s))
    }

    fn cmul(&mut self, (c1, s1): (Id, Id), (c2, s2): (Id, Id)) -> (Id, Id) {
        let a = self.mul(&[c1, c2]);
        let b = self.mul(&[s1, s2]);
        let c = self.sub(a, b);
        let d = self.mul(&[s1, c2]);
        let e = self.mul(&[c1, s2]);
        let s = self.add(&[d, e]);
        (c, s)
    }

    fn cpow(&mut self, (c, s): (Id, Id), n: i64) -> (Id, Id) {
        let base = if n < 0 { (c, self.neg(s)) } else { (c, s) };
        let (one, zero) = (self.one(), self.zero());
        let mut r = (one, zero);
        for _ in 0..n.unsigned_abs() {
            r = self.cmul(r, base);
        }
        r
    }

    /// (cos, sin) of `k pi`: exact for multiples of pi/4 and pi/6.
    fn pi_rotation(&mut self, k: &Q) -> R<(Id, Id)> {
        // Reduce k modulo 2.
        let q = k.mul(&Q::new(int(1), int(2)));
        let fl = q.num() / q.den()
            - if q.is_negative() && !q.is_integer() {
                int(1)
            } else {
                int(0)
            };
        let k = k.sub(&Q::from_int(fl * int(2)));
        let den = k.den().clone();
        // k is reduced to [0, 2), and its denominator is small when it matters.
        let num = i64::try_from(k.num()).unwrap_or(0);
        let (cq, sq): (Id, Id);
        if den == int(1) || den == int(2) {
            let quarter = if den == int(1) { num * 2 } else { num }; // multiples of pi/2
            let (c, s) = [(1, 0), (0, 1), (-1, 0), (0, -1)][quarter.rem_euclid(4) as usize];
            return Ok((self.int(c), self.int(s)));
        }
        if den == int(4) {
            let r2 = self.sqrt_const(&Q::from_i64(2))?;
            let h = self.num(Q::new(int(1), int(2)));
            let v = self.mul(&[h, r2]);
            let nv = self.neg(v);
            let (c, s) = match num.rem_euclid(8) {
                1 => (v, v),
                3 => (nv, v),
                5 => (nv, nv),
                _ => (v, nv),
            };
            return Ok((c, s));
        }
        if den == int(3) || den == int(6) {
            let sixth = if den == int(3) { num * 2 } else { num }; // multiples of pi/6
            let r3 = self.sqrt_const(&Q::from_i64(3))?;
            let h = self.num(Q::new(int(1), int(2)));
            let hr3 = self.mul(&[h, r3]);
            let table: [(i64, i64); 12] = [
                (2, 0),
                (3, 1),
                (1, 3),
                (0, 2),
                (-1, 3),
                (-3, 1),
                (-2, 0),
                (-3, -1),
                (-1, -3),
                (0, -2),
                (1, -3),
                (3, -1),
            ];
            let (a, b) = table[sixth.rem_euclid(12) as usize];
            // a, b encode values: 2 -> 1, 1 -> 1/2, 3 -> sqrt(3)/2, 0 -> 0 (with sign).
            let mut val = |x: i64| -> Id {
                let m = match x.abs() {
                    0 => self.zero(),
                    1 => h,
                    2 => self.one(),
                    _ => hr3,
                };
                if x < 0 {
                    self.neg(m)
                } else {
                    m
                }
            };
            cq = val(a);
            sq = val(b);
            return Ok((cq, sq));
        }
        // Other multiples of pi: an angle atom with a constant argument.
        let pi = self.pi();
        let kn = self.num(k);
        let arg = self.mul(&[kn, pi]);
        let c = self.canon_ok(arg)?;
        let id = self.from_canonical(&c);
        Ok(self.angle_pair(Angle::Generic(id)))
    }

    /// (cos u, sin u).
    fn cos_sin(&mut self, u: Id) -> R<(Id, Id)> {
        let c = self.canon_ok(u)?;
        let lin = self.split_linear(&c);
        stop()?;
        let (one, zero) = (self.one(), self.zero());
        let mut acc = (one, zero);
        let (atans, rest) = self.split_const_atans(lin.rest)?;
        let lin = Linear { rest, ..lin };
        for (pair, n) in atans {
            let p = self.cpow(pair, n);
            acc = self.cmul(acc, p);
        }
        if !lin.rest.is_zero() {
            // sin(-r) = -sin(r): keep the atom's argument with a positive leading coefficient.
            // The sign by the printing order, so the atom is the same in any context.
            let flip = self.frac_sign_negative(&lin.rest);
            let r = if flip {
                lin.rest.neg()
            } else {
                lin.rest.clone()
            };
            let id = self.from_canonical(&r);
            let (c, s) = self.angle_pair(Angle::Generic(id));
            let pair = if flip { (c, self.neg(s)) } else { (c, s) };
            // Multiply in: the constant atans above are already in `acc`
            // (assigning here dropped them: sin(1 + atan(pi)) read as sin(1)).
            acc = self.cmul(acc, pair);
        }
        for (sym, coeff) in lin.syms {
            let (den, n) = self.unit_multiple(sym, &coeff, false)?;
            let pair = self.angle_pair(Angle::Symbol { sym, den });
            let p = self.cpow(pair, n);
            acc = self.cmul(acc, p);
        }
        if !lin.pi.is_zero() {
            let rot = self.pi_rotation(&lin.pi)?;
            acc = self.cmul(acc, rot);
        }
        Ok(acc)
    }

    /// Split `n atan(u)` terms with a constant `u` and an integer `n` off an
    /// angle's remainder: their cosine and sine are algebraic in `u`
    /// ([`Ctx::atan_cos_sin`]), so they must not hide inside an angle atom
    /// (`cos(atan(2))` is `sin(atan(1/2))`, and `tan(atan(u))` is `u`).
    /// Fractional multiples stay in the atom (not detected: docs/engine.md).
    ///
    /// Non-constant arguments too: `cos(atan u) =
    /// 1/sqrt(1 + u^2)`, `sin(atan u) = u/sqrt(1 + u^2)` for every real `u`,
    /// and `cos(atan2(y, x)) = x/r`, `sin(atan2(y, x)) = y/r` with
    /// `r = sqrt(x^2 + y^2)` wherever atan2 is defined (`(x, y) != (0, 0)`);
    /// so `tan(atan2(y, x)) = y/x`. When the root would be of a perfect
    /// square (refused by `sqrt`), the term stays in the angle atom.
    #[allow(clippy::type_complexity)]
    fn split_const_atans(&mut self, rest: RatFun) -> R<(Vec<((Id, Id), i64)>, RatFun)> {
        self.split_terms(rest, |ctx, v, coeff| {
            let atan = matches!(
                ctx.leaves[v as usize].kind,
                LeafKind::Atan(_) | LeafKind::Atan2(..)
            );
            if !atan || !coeff.is_integer() {
                return Ok(None);
            }
            let n = i64::try_from(coeff.num()).ok().filter(|n| n.abs() <= 64);
            let Some(n) = n else {
                let a = ctx.leaf_text(v);
                return err(format!(
                    "the multiple {coeff} of {a} inside sin/cos is too large"
                ));
            };
            Ok(ctx.atan_cos_sin(v)?.map(|pair| (pair, n)))
        })
    }

    /// The terms `c * leaf` (`c` rational, one leaf to the first power) of
    /// `rest`, a polynomial over a constant denominator, that `take` maps to
    /// a part, split off; the other terms recombined as the new rest. Nothing
    /// is split when the denominator is not constant.
    fn split_terms<T>(
        &mut self,
        rest: RatFun,
        mut take: impl FnMut(&mut Self, Var, &Q) -> R<Option<T>>,
    ) -> R<(Vec<T>, RatFun)> {
        let Some(d) = rest.den.as_constant() else {
            return Ok((vec![], rest));
        };
        let mut parts = Vec::new();
        let mut keep = Vec::new();
        for (m, k) in rest.num.terms() {
            let mut it = m.iter();
            let part = match (it.next(), it.next()) {
                (Some((v, 1)), None) => take(self, v, &Q::new(k.clone(), d.clone()))?,
                _ => None,
            };
            match part {
                Some(p) => parts.push(p),
                None => keep.push((m.clone(), k.clone())),
            }
        }
        if parts.is_empty() {
            return Ok((parts, rest));
        }
        let num = Poly::from_terms(keep);
        let rest = if num.is_zero() {
            RatFun::zero()
        } else {
            self.normalize(num, Poly::constant(d))
        };
        stop()?;
        Ok((parts, rest))
    }

    /// Whether `r` has a negative leading coefficient in the printing order
    /// (numerator and denominator together): `atan(-u) = -atan(u)` and
    /// `sin(-u) = -sin(u)` keep the atom with the positive one, chosen by
    /// symbol names rather than creation order so it is one atom everywhere.
    fn frac_sign_negative(&self, r: &RatFun) -> bool {
        self.name_lc_negative(&r.num) != (!r.den.is_one() && self.name_lc_negative(&r.den))
    }

    /// `(cos a, sin a)` for the leaf `a = atan(u)`: `(1, u)/sqrt(1 + u^2)`,
    /// exact for every real `u` (cos of a principal atan is positive); for
    /// `a = atan2(y, x)`: `(x, y)/sqrt(x^2 + y^2)`, exact for `(x, y) != 0`.
    /// `None` when that root is of a perfect square (`sqrt` refuses it).
    fn atan_cos_sin(&mut self, a: Var) -> R<Option<(Id, Id)>> {
        let (x, y) = match self.leaves[a as usize].kind {
            LeafKind::Atan(u) => (self.one(), u),
            LeafKind::Atan2(y, x) => (x, y),
            _ => return err("internal: not an atan leaf"),
        };
        let x2 = self.mul(&[x, x]);
        let y2 = self.mul(&[y, y]);
        let rad = self.add(&[x2, y2]);
        let r = match self.sqrt(rad) {
            Ok(r) => r,
            Err(e) if budget::tripped() => return Err(e),
            Err(_) => return Ok(None),
        };
        let inv = self.pow(r, -1);
        let c = self.mul(&[x, inv]);
        let s = self.mul(&[y, inv]);
        Ok(Some((c, s)))
    }

    /// Split `n log(u)` terms (`n` an integer or a half) off an exponent:
    /// `exp(n log u) = u^n`, exact where `log u` is real (`u > 0`). Left in
    /// the exponent when `u^n` is refused (a root of a perfect square).
    fn split_logs(&mut self, rest: RatFun) -> R<(Vec<Id>, RatFun)> {
        self.split_terms(rest, |ctx, v, coeff| {
            let LeafKind::Log(u) = ctx.leaves[v as usize].kind else {
                return Ok(None);
            };
            if !coeff.is_integer() && coeff.den() != &int(2) {
                return Ok(None);
            }
            match ctx.pow_q(u, coeff) {
                Ok(p) => Ok(Some(p)),
                Err(e) if budget::tripped() => Err(e),
                Err(_) => Ok(None),
            }
        })
    }

    /// The exponent of an `exp` leaf, as a node.
    fn exp_arg(&mut self, v: Var) -> Option<Id> {
        match self.leaves[v as usize].kind {
            LeafKind::Exp(Angle::Symbol { sym, den }) => {
                let s = self.leaf_node(sym);
                let k = self.num(Q::new(int(1), int(den as i64)));
                Some(self.mul(&[k, s]))
            }
            LeafKind::Exp(Angle::Generic(id)) => Some(id),
            _ => None,
        }
    }

    pub fn sin(&mut self, u: Id) -> R<Id> {
        Ok(self.cos_sin(u)?.1)
    }
    pub fn cos(&mut self, u: Id) -> R<Id> {
        Ok(self.cos_sin(u)?.0)
    }
    pub fn tan(&mut self, u: Id) -> R<Id> {
        let (c, s) = self.cos_sin(u)?;
        if self.canon_ok(c)?.is_zero() {
            return err("tan is undefined here: its cosine is identically 0");
        }
        Ok(self.div(s, c))
    }

    pub fn exp(&mut self, u: Id) -> R<Id> {
        let c = self.canon_ok(u)?;
        let lin = self.split_linear(&c);
        stop()?;
        let (mut factors, mut rest) = self.split_logs(lin.rest.clone())?;
        if !lin.pi.is_zero() {
            let pv = self.pi_var();
            let pi_part = self.rf_mul(&RatFun::from_q(&lin.pi), &RatFun::var(pv));
            rest = self.rf_add(&rest, &pi_part);
            stop()?;
        }
        for (sym, coeff) in lin.syms {
            let (den, n) = self.unit_multiple(sym, &coeff, true)?;
            let e = self.leaf(LeafKind::Exp(Angle::Symbol { sym, den }));
            let en = self.leaf_node(e);
            factors.push(self.pow(en, n));
        }
        // exp(c + r) = exp(c) exp(r) for a rational c (all reals): the
        // constant gets its own atom, so exp(x y + 1) = exp(1) exp(x y).
        if let (Some(d), true) = (rest.den.as_constant(), rest.num.len() > 1) {
            let c0 = rest.num.terms().iter().find(|(m, _)| m.is_one());
            if let Some((_, k)) = c0 {
                let c = RatFun::from_q(&Q::new(k.clone(), d));
                rest = self.rf_sub(&rest, &c);
                let cid = self.from_canonical(&c);
                let e = self.leaf(LeafKind::Exp(Angle::Generic(cid)));
                factors.push(self.leaf_node(e));
            }
        }
        if !rest.is_zero() {
            let id = self.from_canonical(&rest);
            let e = self.leaf(LeafKind::Exp(Angle::Generic(id)));
            factors.push(self.leaf_node(e));
        }
        Ok(self.mul(&factors))
    }

    fn pi_var(&mut self) -> Var {
        self.leaf(LeafKind::Pi)
    }

    pub fn atan(&mut self, u: Id) -> R<Id> {
        let c = self.canon_ok(u)?;
        if c.is_zero() {
            return Ok(self.zero());
        }
        if let Some(q) = c.as_q() {
            // atan(p/q) = arg(q + ip), q > 0 (gauss.rs).
            return Ok(self.gaussian_arg(q.den(), q.num()));
        }
        let flip = self.frac_sign_negative(&c);
        let r = if flip { c.neg() } else { c };
        let id = self.from_canonical(&r);
        let a = self.leaf(LeafKind::Atan(id));
        let n = self.leaf_node(a);
        Ok(if flip { self.neg(n) } else { n })
    }

    pub fn atan2(&mut self, y: Id, x: Id) -> R<Id> {
        let (cy, cx) = (self.canon_ok(y)?, self.canon_ok(x)?);
        if cy.is_zero() && cx.is_zero() {
            return err("atan2(0, 0) is undefined");
        }
        if let (Some(qy), Some(qx)) = (cy.as_q(), cx.as_q()) {
            let pi = self.pi();
            let frac = |s: &mut Ctx, a: i64, b: i64| {
                let k = s.num(Q::new(int(a), int(b)));
                s.mul(&[k, pi])
            };
            if qy.is_zero() {
                return Ok(if qx.is_negative() { pi } else { self.zero() });
            }
            if qx.is_zero() {
                return Ok(frac(self, if qy.is_negative() { -1 } else { 1 }, 2));
            }
            // arg(x + iy) with the denominators cleared by a positive factor.
            let (x, y) = (qx.num() * qy.den(), qy.num() * qx.den());
            return Ok(self.gaussian_arg(&x, &y));
        }
        let (iy, ix) = (self.from_canonical(&cy), self.from_canonical(&cx));
        let a = self.leaf(LeafKind::Atan2(iy, ix));
        Ok(self.leaf_node(a))
    }

    /// The principal argument of `x + iy` in the normal form of gauss.rs:
    /// `k pi/4 + sum n atan(d/c)` over canonical atoms `atan(d/c)`, `c > d > 0`.
    fn gaussian_arg(&mut self, x: &Int, y: &Int) -> Id {
        let Some(form) = gauss::arg(x, y) else {
            return self.zero();
        };
        let mut terms = Vec::with_capacity(form.atoms.len() + 1);
        if form.quarters != 0 {
            let pi = self.pi();
            let k = self.num(Q::new(int(form.quarters), int(4)));
            terms.push(self.mul(&[k, pi]));
        }
        for ((c, d), n) in form.atoms {
            // Atom arguments are canonical nodes (printing reads their form).
            let r = self.from_canonical(&RatFun::from_q(&Q::new(d, c)));
            let a = self.leaf(LeafKind::Atan(r));
            let an = self.leaf_node(a);
            let k = self.int(n);
            terms.push(self.mul(&[k, an]));
        }
        self.add(&terms)
    }

    pub fn log(&mut self, u: Id) -> R<Id> {
        let c = self.canon_ok(u)?;
        if let Some(q) = c.as_q() {
            if q.is_one() {
                return Ok(self.zero());
            }
            if q.is_zero() || q.is_negative() {
                return err(format!("log of the constant {q} is undefined"));
            }
        }
        // log(exp(a)^k w) = k a + log(w), exact where the log is real
        // (w > 0 there): the exp leaves of the monomial content of the
        // numerator and the denominator come out.
        let (mn, md) = (c.num.mono_content(), c.den.mono_content());
        let pulled = |m: &Mono| -> Vec<(Var, u32)> {
            m.iter()
                .filter(|(v, _)| matches!(self.leaves[*v as usize].kind, LeafKind::Exp(_)))
                .collect()
        };
        let (en, ed) = (pulled(&mn), pulled(&md));
        if !en.is_empty() || !ed.is_empty() {
            let mut terms = Vec::new();
            for (v, e, sign) in en
                .iter()
                .map(|&(v, e)| (v, e, 1))
                .chain(ed.iter().map(|&(v, e)| (v, e, -1)))
            {
                if let Some(a) = self.exp_arg(v) {
                    let k = self.int(sign * e as i64);
                    terms.push(self.mul(&[k, a]));
                }
            }
            let w = RatFun {
                num: c.num.div_mono(&Mono::from_pairs(en.iter().copied())),
                den: c.den.div_mono(&Mono::from_pairs(ed.iter().copied())),
            };
            let w = self.normalize(w.num, w.den);
            stop()?;
            let wid = self.from_canonical(&w);
            terms.push(self.log(wid)?);
            return Ok(self.add(&terms));
        }
        let id = self.from_canonical(&c);
        let l = self.leaf(LeafKind::Log(id));
        Ok(self.leaf_node(l))
    }

    fn sqrt_const(&mut self, q: &Q) -> R<Id> {
        let id = self.num(q.clone());
        self.sqrt(id)
    }

    pub fn sqrt(&mut self, u: Id) -> R<Id> {
        let c = self.canon_ok(u)?;
        if c.is_zero() {
            return Ok(self.zero());
        }
        // Pull the largest square factor of the constant content out.
        let cn = c.num.content();
        let cd = c.den.content();
        if let Some(q) = c.as_q() {
            if q.is_negative() {
                return err(format!("sqrt of the negative constant {q} is undefined"));
            }
        }
        let (sn, _) = square_part(&cn);
        let (sd, _) = square_part(&cd);
        // sqrt(c) = (sn/sd) * sqrt(c * sd^2 / sn^2)
        let outside = Q::new(sn.clone(), sd.clone());
        let inner = RatFun {
            num: budget::invariant(
                c.num.div_exact(&Poly::constant(&sn * &sn)),
                "square divides content",
            ),
            den: budget::invariant(
                c.den.div_exact(&Poly::constant(&sd * &sd)),
                "square divides content",
            ),
        };
        stop()?;
        let out = self.num(outside);
        if inner.is_one() {
            return Ok(out);
        }
        if let (Some(a), Some(b)) = (inner.num.as_constant(), inner.den.as_constant()) {
            // sqrt(a/b) = sqrt(a b) / b for constants, so the atom is an integer.
            if !b.is_one() {
                let ab = self.num(Q::from_int(&a * &b));
                let r = self.sqrt(ab)?;
                let inv_b = self.num(Q::new(int(1), b));
                return Ok(self.mul(&[out, r, inv_b]));
            }
        }
        if let Some(a) = inner.as_q().filter(|q| q.is_integer()) {
            // A square-free integer: one atom per prime, so that sqrt(10) and
            // sqrt(2) sqrt(5) have one form (square roots of distinct primes
            // are independent, each a quadratic extension of the others).
            let (factors, cofactor) = trial_factor(a.num());
            let mut fs = vec![out];
            for p in factors.into_iter().map(|(p, _)| p).chain([cofactor]) {
                if !p.is_one() {
                    fs.push(self.sqrt_leaf(RatFun::from_q(&Q::from_int(p))));
                }
            }
            return Ok(self.mul(&fs));
        }
        if is_square_poly(&inner.num.mul(&inner.den)) {
            return err(
                "sqrt of a perfect square is not supported (it is |.|, not a polynomial): write the root without sqrt",
            );
        }
        stop()?;
        let n = self.sqrt_leaf(inner);
        Ok(self.mul(&[out, n]))
    }

    /// The leaf `sqrt(inner)` for a radicand with its square factors removed.
    fn sqrt_leaf(&mut self, inner: RatFun) -> Id {
        self.root_leaf(inner, 2)
    }

    /// The leaf `root_q(inner)` (relation `r^q = inner`) for a radicand whose
    /// relation the caller has made irreducible; through a root of the same
    /// radicand at an index dividing or divided by `q` when there is one.
    pub(crate) fn root_leaf(&mut self, inner: RatFun, q: u32) -> Id {
        if let Some(r) = self.related_root(&inner, q) {
            return r;
        }
        let id = self.from_canonical(&inner);
        let v = self.leaf(LeafKind::Root(id, q));
        self.memo.radicands.insert(v, inner);
        self.leaf_node(v)
    }

    /// `b^(p/q)` for a rational exponent in lowest terms: `b^p` for an
    /// integer, else `root_q(b)^p` (`sqrt` for `q = 2`), which the relation
    /// `r^q = b` reduces to `b^floor(p/q) root_q(b)^(p mod q)`.
    pub fn pow_q(&mut self, b: Id, q: &Q) -> R<Id> {
        // Only a negative power needs the zero test (and its canonical form).
        let zero = if q.is_negative() {
            self.canon_ok(b)?.is_zero()
        } else {
            false
        };
        let e = i64::try_from(q.num())
            .ok()
            .filter(|e| e.abs() <= budget::POW_MAX);
        let Some(e) = e else {
            return err(format!("exponent {q} is too large"));
        };
        if zero && e < 0 {
            return err("division by zero: 0 raised to a negative power");
        }
        if q.is_integer() {
            return Ok(self.pow(b, e));
        }
        let k = match u32::try_from(q.den()) {
            Ok(k) if k <= budget::ROOT_MAX => k,
            _ => {
                return err(format!(
                    "exponent {q} is not supported: the root index {} is above {}",
                    q.den(),
                    budget::ROOT_MAX
                ))
            }
        };
        // A number to a fractional power is raised after its root, where the
        // graph's check on a number's power no longer sees a bare number:
        // check the value's size (`e / k` times the number's) here.
        if let Node::Num(n) = self.node(b) {
            let size = power_bits(n, e.unsigned_abs() as u128) / k as u128;
            if size > budget::NUM_BITS_MAX {
                return Err(budget::Limit::Number {
                    bits: size,
                    max: budget::NUM_BITS_MAX,
                }
                .into());
            }
        }
        let r = self.root(b, k)?;
        Ok(self.pow(r, e))
    }

    /// `b^e`: a constant exponent goes to [`Ctx::pow_q`], any other is `exp(e log b)`.
    pub fn pow_expr(&mut self, b: Id, e: Id) -> R<Id> {
        if let Some(q) = self.canon_ok(e)?.as_q() {
            return self.pow_q(b, &q);
        }
        let l = self.log(b)?;
        let m = self.mul(&[e, l]);
        self.exp(m)
    }

    /// Checked division: an error when the divisor is identically zero.
    pub fn checked_div(&mut self, a: Id, b: Id) -> R<Id> {
        if self.canon_ok(b)?.is_zero() {
            return err("division by an expression that is identically zero");
        }
        Ok(self.div(a, b))
    }
}

/// `n = s^2 t` with `s` as large as trial division finds ([`trial_factor`]):
/// `t` is square-free unless its cofactor without small primes has a square
/// factor and is not itself a square (it is then at least 2^48).
fn square_part(n: &Int) -> (Int, Int) {
    if n.is_zero() {
        return (int(1), n.clone());
    }
    if let Some(r) = int_exact_sqrt(n) {
        return (r, int(1));
    }
    let (factors, cofactor) = trial_factor(n);
    let mut s = int(1);
    for (p, e) in factors {
        for _ in 0..e / 2 {
            s *= &p;
        }
    }
    if let Some(r) = int_exact_sqrt(&cofactor) {
        s *= r;
    }
    let t = n / (&s * &s);
    (s, t)
}

/// Whether a polynomial is the square of a polynomial (schoolbook square root).
pub(crate) fn is_square_poly(p: &Poly) -> bool {
    if p.is_zero() {
        return true;
    }
    let Some((lm, lc)) = p.leading().cloned() else {
        return true;
    };
    if lm.iter().any(|(_, e)| e % 2 == 1) {
        return false;
    }
    let Some(rc) = int_exact_sqrt(&lc) else {
        return false;
    };
    let rm = Mono::from_pairs(lm.iter().map(|(v, e)| (v, e / 2)));
    let mut root = Poly::monomial(rm.clone(), rc.clone());
    let two_lead = (rm, &rc * int(2));
    for _ in 0..=p.len() {
        if !budget::poll() {
            return false;
        }
        let rem = p.sub(&root.mul(&root));
        let Some((m, c)) = rem.leading().cloned() else {
            return true;
        };
        let Some(q) = m.div(&two_lead.0) else {
            return false;
        };
        if !(&c % &two_lead.1).is_zero() {
            return false;
        }
        root = root.add(&Poly::monomial(q, &c / &two_lead.1));
    }
    false
}
