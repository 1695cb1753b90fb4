//! Discrete symmetries: candidate maps between the multi-valued variables,
//! each checked exactly on the model equations over Z.
//!
//! A candidate sends each variable `v` to `s * x_w^e` (`s, e = ±1`) of a
//! variable `w` of the same kind (state or param, angle or not). For a plain
//! variable `e = 1`: a signed permutation. For an angle, which the count sees
//! as `t = tan(theta/2)` (trig.rs), the four images of `t_w` are the angle
//! maps `theta -> phi` (`t`), `-phi` (`-t`), `phi + pi` (`-1/t`, since
//! `tan((phi + pi)/2) = -cot(phi/2)`) and `pi - phi` (`1/t`).

use super::model::ZModel;
use super::outputs::AngleOutput;
use super::run::{int_mod, Rng};
use super::types::MapImage;
use obsan_expr::{Ctx, Id, Int, Mono as ZMono, Poly as ZPoly, RatFun, Var};
use obsan_groebner::Field;
use std::collections::HashMap;

/// One variable's image in the half-angle coordinates: `x_v -> sign * x_var^exp`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Image {
    pub(super) var: usize,
    pub(super) sign: i8,
    /// 1, or -1 for an angle shifted by pi (`t -> ∓1/t`).
    pub(super) exp: i8,
}

impl Image {
    fn identity(v: usize) -> Image {
        Image {
            var: v,
            sign: 1,
            exp: 1,
        }
    }

    /// The map in the angle's own terms: `theta -> sign * phi (+ pi)`.
    pub(super) fn named(&self, var: &str, names: &[&str]) -> MapImage {
        MapImage {
            var: var.to_string(),
            // t -> -1/t is phi + pi; t -> 1/t is pi - phi.
            sign: if self.exp < 0 { -self.sign } else { self.sign },
            image: names[self.var].to_string(),
            plus_pi: self.exp < 0,
        }
    }
}

/// A map of the model's variables (dynamic states, then params): entry `v`
/// is the image of variable `v`.
pub(super) type Candidate = Vec<Image>;

/// `S(p) = p(x_v := s_v x_w^e_v)` as `N / M`, `M` a monomial (the negative
/// powers of `x_w` cleared).
struct Substituted {
    num: ZPoly,
    den: ZPoly,
}

fn substitute(p: &ZPoly, images: &HashMap<Var, (Var, i8, i8)>) -> Substituted {
    let mut terms: Vec<(HashMap<Var, i64>, Int)> = Vec::with_capacity(p.len());
    let mut low: HashMap<Var, i64> = HashMap::new();
    for (mono, c) in p.terms() {
        let mut neg = false;
        let mut exps: HashMap<Var, i64> = HashMap::new();
        for (v, k) in mono.iter() {
            let (w, s, e) = images.get(&v).copied().unwrap_or((v, 1, 1));
            if s < 0 && k % 2 == 1 {
                neg = !neg;
            }
            *exps.entry(w).or_insert(0) += i64::from(e) * i64::from(k);
        }
        for (&w, &k) in &exps {
            let l = low.entry(w).or_insert(0);
            *l = (*l).min(k);
        }
        terms.push((exps, if neg { -c.clone() } else { c.clone() }));
    }
    let shift = |w: &Var| -low.get(w).copied().unwrap_or(0);
    // Every term times `prod x_w^shift(w)`, also those without `x_w`.
    let num = ZPoly::from_terms(terms.into_iter().map(|(mut exps, c)| {
        for w in low.keys() {
            exps.entry(*w).or_insert(0);
        }
        let pairs = exps.iter().map(|(w, &k)| (*w, (k + shift(w)) as u32));
        (ZMono::from_pairs(pairs), c)
    }));
    let den_pairs = low.keys().map(|w| (*w, shift(w) as u32));
    let den = ZPoly::monomial(ZMono::from_pairs(den_pairs), Int::from(1));
    Substituted { num, den }
}

/// Whether `sigma` maps the model to itself exactly (over Z). With
/// `T(x)_v = g_v(x_w)` (`w` the image's variable) and `S(p) = p o T`:
/// `S(h) = h` for each output, and `S(f_v) = g_v'(x_w) f_w` for each state
/// (`T` maps solutions to solutions: `(g_v(x_w))' = g_v'(x_w) x_w'`), with
/// `g' = s` for `s x`, `-s/x^2` for `s/x`.
fn is_symmetry(m: &ZModel, sigma: &Candidate) -> bool {
    let vars: Vec<Var> = m.dyn_vars.iter().chain(&m.param_vars).copied().collect();
    let images: HashMap<Var, (Var, i8, i8)> = sigma
        .iter()
        .enumerate()
        .map(|(v, im)| (vars[v], (vars[im.var], im.sign, im.exp)))
        .collect();
    for (n, d) in &m.outputs {
        let (sn, sd) = (substitute(n, &images), substitute(d, &images));
        // sn.num/sn.den / (sd.num/sd.den) = n/d
        let lhs = sn.num.mul(&sd.den).mul(d);
        let rhs = n.mul(&sd.num).mul(&sn.den);
        if !lhs.sub(&rhs).is_zero() {
            return false;
        }
    }
    for (v, im) in sigma.iter().enumerate().take(m.dyn_vars.len()) {
        let (sn, sd) = (
            substitute(&m.rhs[v].0, &images),
            substitute(&m.rhs[v].1, &images),
        );
        let (nw, dw) = &m.rhs[im.var];
        // g' = c x_w^k: c = s, k = 0 for e = 1; c = -s, k = -2 for e = -1.
        let c = Int::from(i64::from(im.sign * im.exp));
        let mut lhs = sn.num.mul(&sd.den).mul(dw);
        if im.exp < 0 {
            let w = vars[im.var];
            lhs = lhs.mul(&ZPoly::var(w)).mul(&ZPoly::var(w));
        }
        let rhs = nw.mul(&sd.num).mul(&sn.den).mul(&ZPoly::constant(c));
        if !lhs.sub(&rhs).is_zero() {
            return false;
        }
    }
    true
}

/// The model's polynomials modulo `p = 2^61 - 1` at one random point, for a
/// cheap test before the exact one: `is_symmetry` compares polynomial
/// identities over Z, which hold at every point, so a candidate that fails
/// them at this point is no symmetry, and the exact check runs only on the
/// candidates that pass (Bilirubin: 87 % of `obsan global`'s time was the
/// exact check of 200,000 signed permutations, nearly all rejected).
struct Numeric {
    f: Field,
    /// The point: one value per symbol slot (model variables first, in the
    /// candidates' order, then inputs and constants), all non-zero.
    x: Vec<u64>,
    /// Per output and per state, numerator and denominator, as
    /// `(slot exponents, coefficient)` terms.
    outputs: Vec<(NPoly, NPoly)>,
    rhs: Vec<(NPoly, NPoly)>,
}

type NPoly = Vec<(Vec<(usize, u32)>, u64)>;

impl Numeric {
    fn new(m: &ZModel) -> Option<Numeric> {
        let f = Field::new((1 << 61) - 1)?;
        let mut slot: HashMap<Var, usize> = HashMap::new();
        for &v in m.dyn_vars.iter().chain(&m.param_vars) {
            let k = slot.len();
            slot.entry(v).or_insert(k);
        }
        let mut rng = Rng::new(0x5eed_0a95);
        let np = |p: &ZPoly, slot: &mut HashMap<Var, usize>| -> NPoly {
            p.terms()
                .iter()
                .map(|(mono, c)| {
                    let e = mono
                        .iter()
                        .map(|(v, k)| {
                            let n = slot.len();
                            (*slot.entry(v).or_insert(n), k)
                        })
                        .collect();
                    (e, int_mod(&f, c))
                })
                .collect()
        };
        let outputs = m
            .outputs
            .iter()
            .map(|(n, d)| (np(n, &mut slot), np(d, &mut slot)))
            .collect();
        let rhs = m
            .rhs
            .iter()
            .map(|(n, d)| (np(n, &mut slot), np(d, &mut slot)))
            .collect();
        let x = (0..slot.len()).map(|_| rng.elem(&f)).collect();
        Some(Numeric { f, x, outputs, rhs })
    }

    fn eval(&self, p: &NPoly, at: &[u64]) -> u64 {
        let f = &self.f;
        p.iter().fold(0, |acc, (e, c)| {
            let t = e
                .iter()
                .fold(*c, |t, &(v, k)| f.mul(t, f.pow(at[v], u64::from(k))));
            f.add(acc, t)
        })
    }

    /// `is_symmetry`'s identities at the point: `false` proves `sigma` is
    /// none. At `y = T(x)` (`y_v = s x_w^e`): `h(y) = h(x)` for each output,
    /// and `f_v(y) = g_v'(x_w) f_w(x)` for each state, cross-multiplied (the
    /// exact check's monomial denominators are non-zero at the point).
    fn may_be_symmetry(&self, sigma: &Candidate) -> bool {
        let f = &self.f;
        let mut y = self.x.clone();
        for (v, im) in sigma.iter().enumerate() {
            let xw = self.x[im.var];
            let mut val = if im.exp < 0 {
                match f.inv(xw) {
                    Some(i) => i,
                    None => return true,
                }
            } else {
                xw
            };
            if im.sign < 0 {
                val = f.neg(val);
            }
            y[v] = val;
        }
        for (n, d) in &self.outputs {
            let l = f.mul(self.eval(n, &y), self.eval(d, &self.x));
            let r = f.mul(self.eval(n, &self.x), self.eval(d, &y));
            if l != r {
                return false;
            }
        }
        for (v, im) in sigma.iter().enumerate().take(self.rhs.len()) {
            let (nv, dv) = &self.rhs[v];
            let (nw, dw) = &self.rhs[im.var];
            let xw = self.x[im.var];
            let mut l = f.mul(self.eval(nv, &y), self.eval(dw, &self.x));
            if im.exp < 0 {
                l = f.mul(l, f.mul(xw, xw));
            }
            let c = f.from_i64(i64::from(im.sign * im.exp));
            let r = f.mul(c, f.mul(self.eval(nw, &self.x), self.eval(dv, &y)));
            if l != r {
                return false;
            }
        }
        true
    }
}

/// The search: each movable variable to a movable variable of its kind not
/// yet used, with each of its images; at most `cap` candidates checked.
struct Search<'a> {
    m: &'a ZModel,
    movable: Vec<usize>,
    /// Per variable (states then params): an angle.
    angle: Vec<bool>,
    nx: usize,
    cap: usize,
    tried: usize,
    cur: Candidate,
    used: Vec<bool>,
    found: Vec<Candidate>,
    numeric: Option<Numeric>,
}

impl Search<'_> {
    fn rec(&mut self, i: usize) {
        if self.tried >= self.cap {
            return;
        }
        if i == self.movable.len() {
            let identity = self
                .cur
                .iter()
                .enumerate()
                .all(|(k, im)| *im == Image::identity(k));
            if !identity {
                self.tried += 1;
                let maybe = self
                    .numeric
                    .as_ref()
                    .is_none_or(|n| n.may_be_symmetry(&self.cur));
                if maybe && is_symmetry(self.m, &self.cur) {
                    self.found.push(self.cur.clone());
                }
            }
            return;
        }
        let v = self.movable[i];
        let exps: &[i8] = if self.angle[v] { &[1, -1] } else { &[1] };
        for k in 0..self.movable.len() {
            let w = self.movable[k];
            let same_kind = (v < self.nx) == (w < self.nx) && self.angle[v] == self.angle[w];
            if self.used[w] || !same_kind {
                continue;
            }
            for &exp in exps {
                for sign in [1i8, -1] {
                    self.used[w] = true;
                    self.cur[v] = Image { var: w, sign, exp };
                    self.rec(i + 1);
                    self.used[w] = false;
                }
            }
        }
        self.cur[v] = Image::identity(v);
    }
}

/// Maps of the multi-valued variables (states to states, params to params,
/// angles to angles), each checked exactly; at most `cap` candidates.
pub(super) fn find_maps(m: &ZModel, multi: &[bool], cap: usize) -> Vec<Candidate> {
    let nx = m.dyn_vars.len();
    let n = nx + m.param_vars.len();
    let mut s = Search {
        m,
        movable: (0..n).filter(|&i| multi[i]).collect(),
        angle: m.angle.clone(),
        nx,
        cap,
        tried: 0,
        cur: (0..n).map(Image::identity).collect(),
        used: vec![false; n],
        found: Vec::new(),
        numeric: Numeric::new(m),
    };
    s.rec(0);
    s.found
}

/// The group the maps generate (closure under composition), capped at `cap`
/// elements. Images compose as monomials: `x_v -> s x_w^e` then
/// `x_w -> s' x_u^e'` gives `x_v -> s s' x_u^(e e')` (`s'^e = s'`).
pub(super) fn group_order(maps: &[Candidate], n: usize, cap: usize) -> usize {
    let id: Candidate = (0..n).map(Image::identity).collect();
    let mut elems = vec![id];
    let mut k = 0;
    while k < elems.len() && elems.len() < cap {
        for g in maps {
            let c: Candidate = elems[k]
                .iter()
                .map(|a| {
                    let b = g[a.var];
                    Image {
                        var: b.var,
                        sign: a.sign * b.sign,
                        exp: a.exp * b.exp,
                    }
                })
                .collect();
            if !elems.contains(&c) {
                elems.push(c);
            }
        }
        k += 1;
    }
    elems.len()
}

/// Per angle output, whether the map keeps `(sin, cos)` (`Some(1)`), turns it
/// by pi (`Some(-1)`), or neither is proven (`None`). `symbols` are the
/// model's variables (states then params) in the candidates' order; an angle
/// variable's image in the angle's own terms is `sign * phi (+ pi)`.
pub(super) fn map_signs(
    ctx: &mut Ctx,
    angles: &[AngleOutput],
    symbols: &[Var],
    angle: &[bool],
    map: &Candidate,
) -> Vec<Option<i8>> {
    let mut subst: Vec<(Var, Id)> = Vec::new();
    for (v, im) in map.iter().enumerate() {
        // t -> -1/t is phi + pi; t -> 1/t is pi - phi (maps.rs).
        let (sign, plus_pi) = if angle[v] && im.exp < 0 {
            (-im.sign, true)
        } else {
            (im.sign, false)
        };
        if im.var == v && sign > 0 && !plus_pi {
            continue;
        }
        let Some(name) = ctx.symbol_name(symbols[im.var]).map(str::to_string) else {
            return vec![None; angles.len()];
        };
        let w = ctx.symbol(&name).id;
        let mut node = if sign < 0 { ctx.neg(w) } else { w };
        if plus_pi {
            let pi = ctx.pi();
            node = ctx.add(&[node, pi]);
        }
        subst.push((symbols[v], node));
    }
    let mut signs = Vec::with_capacity(angles.len());
    for a in angles {
        let mut one = |id: Id| -> Option<(RatFun, RatFun)> {
            let moved = ctx.substitute(id, &subst).ok()?;
            Some((ctx.try_canon(id).ok()?, ctx.try_canon(moved).ok()?))
        };
        let sign = match (one(a.sin), one(a.cos)) {
            (Some((s, s2)), Some((c, c2))) => {
                if s == s2 && c == c2 {
                    Some(1)
                } else if s.neg() == s2 && c.neg() == c2 {
                    Some(-1)
                } else {
                    None
                }
            }
            _ => None,
        };
        signs.push(sign);
    }
    signs
}

#[cfg(test)]
mod tests {
    use super::*;
    use obsan_model::System;

    /// Every candidate of the search's kinds (states to states, params to
    /// params, angles to angles; signs, and for angles `t -> ±1/t`).
    fn all_candidates(m: &ZModel) -> Vec<Candidate> {
        fn rec(
            m: &ZModel,
            v: usize,
            cur: &mut Candidate,
            used: &mut [bool],
            out: &mut Vec<Candidate>,
        ) {
            let nx = m.dyn_vars.len();
            if v == cur.len() {
                out.push(cur.clone());
                return;
            }
            for w in 0..cur.len() {
                let same = (v < nx) == (w < nx) && m.angle[v] == m.angle[w];
                if used[w] || !same {
                    continue;
                }
                let exps: &[i8] = if m.angle[v] { &[1, -1] } else { &[1] };
                for &exp in exps {
                    for sign in [1i8, -1] {
                        used[w] = true;
                        cur[v] = Image { var: w, sign, exp };
                        rec(m, v + 1, cur, used, out);
                        used[w] = false;
                    }
                }
            }
        }
        let n = m.dyn_vars.len() + m.param_vars.len();
        let mut cur: Candidate = (0..n).map(Image::identity).collect();
        let mut out = Vec::new();
        rec(m, 0, &mut cur, &mut vec![false; n], &mut out);
        out
    }

    /// The numeric test never rejects a symmetry the exact check proves
    /// (it compares the same identities at a point), and at its random
    /// point it rejects every candidate the exact check rejects on these
    /// models (a wrong point would only cost time).
    #[test]
    fn the_numeric_test_agrees_with_the_exact_one() {
        let models = [
            "state x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n",
            "state x\nparam a, b\nx' = -a^2*x + b\noutput y = x\n",
            "state x, y, th\nparam v\nx' = v*cos(th)\ny' = v*sin(th)\nth' = 0\noutput r = x^2 + y^2\n",
            "state x\nparam th\nx' = -x\noutput y = x*cos(th)^2\n",
            // th -> th + pi (t -> -1/t on a moving angle) and th -> -th, w -> -w.
            "state x, th\nparam w\nx' = -x\nth' = w\noutput y = x*cos(th)^2\n",
            "state x1, x2\nparam k, c\nx1' = -k*x1/(c + x2)\nx2' = k*x1/(c + x2)\noutput y = x1\n",
        ];
        let mut seen_symmetry = false;
        for src in models {
            let sys = System::parse(&format!("system t\n{src}"), "t.sys").unwrap();
            let mut nf = sys.normal_form(None, &[]).unwrap();
            let m = super::super::model::zmodel(&mut nf).unwrap();
            let num = Numeric::new(&m).unwrap();
            for c in all_candidates(&m) {
                let exact = is_symmetry(&m, &c);
                seen_symmetry |= exact
                    && c.iter()
                        .enumerate()
                        .any(|(k, im)| *im != Image::identity(k));
                assert_eq!(num.may_be_symmetry(&c), exact, "{src}: {c:?}");
            }
        }
        assert!(seen_symmetry, "no non-trivial symmetry among the models");
    }
}
