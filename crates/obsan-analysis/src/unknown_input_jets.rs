//! Symmetries with unknown inputs that move with the known inputs
//! (unknown_input_symmetry.rs, docs/engine.md "Symmetries with unknown
//! inputs"): which of the extended route's fixed coordinates the kernel
//! depends on, the known inputs' jets as coordinates of the reconstruction,
//! and the time derivative `d_t xi` of the certificate.
//!
//! The extended route's fixed coordinates are the known inputs' clock `'t`
//! and coefficients `'u_c{l}` (`u(t) = sum_l c_l t^l`) and the unknown inputs'
//! jets. At `t = 0` the known inputs' jets are `u^(l) = l! c_l`, so a black box
//! in the jets reads the coefficients as `u^(l) / l!`.

use crate::rank::AnalysisError;
use obsan_expr::{lie::Coord, Ctx, Fp, RatFun, Var};
use obsan_model::NormalForm;

/// What a fixed coordinate of the extended route is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Fixed {
    /// The known inputs' clock `'t`.
    Clock,
    /// `c_il`, the `l`-th coefficient of known input `i`.
    Coeff(usize, usize),
    /// An unknown input's jet.
    Unknown,
}

/// The kind of each coordinate of `extra` (the extended context `ctx`,
/// known inputs `inputs`, polynomials of degree `order`).
pub(crate) fn classify(ctx: &Ctx, inputs: &[String], order: usize, extra: &[Coord]) -> Vec<Fixed> {
    let clock = ctx.lookup("'t").map(|s| s.var);
    let mut coeffs: Vec<(Var, usize, usize)> = Vec::new();
    for (i, u) in inputs.iter().enumerate() {
        for l in 0..=order {
            if let Some(s) = ctx.lookup(&format!("'{u}_c{l}")) {
                coeffs.push((s.var, i, l));
            }
        }
    }
    extra
        .iter()
        .map(|c| {
            let v = c.var();
            if Some(v) == clock {
                Fixed::Clock
            } else if let Some(&(_, i, l)) = coeffs.iter().find(|p| p.0 == v) {
                Fixed::Coeff(i, l)
            } else {
                Fixed::Unknown
            }
        })
        .collect()
}

/// `fixed` with the coordinates `which` selects redrawn by `draw`.
pub(crate) fn redraw(
    fixed: &[Fp],
    kinds: &[Fixed],
    which: impl Fn(Fixed) -> bool,
    mut draw: impl FnMut() -> Fp,
) -> Vec<Fp> {
    fixed
        .iter()
        .zip(kinds)
        .map(|(&v, &k)| if which(k) { draw() } else { v })
        .collect()
}

/// The known inputs' jets the black box takes as coordinates: `(input,
/// order)` for every coefficient present, in input then order.
pub(crate) fn jet_coords(kinds: &[Fixed]) -> Vec<(usize, usize)> {
    let mut j: Vec<(usize, usize)> = kinds
        .iter()
        .filter_map(|k| match *k {
            Fixed::Coeff(i, l) => Some((i, l)),
            _ => None,
        })
        .collect();
    j.sort_unstable();
    j.dedup();
    j
}

/// The fixed coordinates' values at the jets `u` (ordered as `jets`): the
/// clock at 0, `c_il = u_i^(l) / l!`, the unknown inputs' jets from `fixed`.
pub(crate) fn at_jets(fixed: &[Fp], kinds: &[Fixed], jets: &[(usize, usize)], u: &[Fp]) -> Vec<Fp> {
    kinds
        .iter()
        .zip(fixed)
        .map(|(k, &v)| match *k {
            Fixed::Clock => Fp::ZERO,
            Fixed::Coeff(i, l) => {
                let fact = (1..=l as u64).fold(Fp::ONE, |f, m| f * Fp::new(m));
                // l! is non-zero modulo p for every order the route reaches;
                // every coefficient is in `jets` (jet_coords lists them all).
                let inv = fact.inv().unwrap_or(Fp::ONE);
                jets.iter()
                    .position(|&p| p == (i, l))
                    .map_or(Fp::ZERO, |a| u[a] * inv)
            }
            Fixed::Unknown => v,
        })
        .collect()
}

/// The symbol of `u^(l)`: the input's own name, then `l` quotes (no `.sys`
/// name holds a quote, so it cannot clash).
pub(crate) fn jet_name(input: &str, l: usize) -> String {
    format!("{input}{}", "'".repeat(l))
}

/// The jets `(input, order)` the forms `vectors` depend on, in input then
/// order, with their symbols in `ctx`.
pub(crate) fn used_jets(
    ctx: &mut Ctx,
    inputs: &[String],
    jets: &[(usize, usize)],
    vectors: &[Vec<RatFun>],
) -> Vec<(usize, usize)> {
    let mut used = Vec::new();
    for &(i, l) in jets {
        let v = ctx.symbol(&jet_name(&inputs[i], l)).var;
        if vectors
            .iter()
            .flatten()
            .any(|e| !ctx.rf_diff(e, v).is_zero())
        {
            used.push((i, l));
        }
    }
    used
}

/// `d_t xi = sum_{i,l} u_i^(l+1) d xi / d u_i^(l)` over the jets `used`.
pub(crate) fn time_derivative(
    nf: &mut NormalForm,
    used: &[(usize, usize)],
    xi: &[RatFun],
) -> Vec<RatFun> {
    let mut vars = Vec::with_capacity(used.len());
    let mut next = Vec::with_capacity(used.len());
    for &(i, l) in used {
        vars.push(nf.ctx.symbol(&jet_name(&nf.inputs[i], l)).var);
        let s = nf.ctx.symbol(&jet_name(&nf.inputs[i], l + 1)).id;
        next.push(nf.ctx.canon(s));
    }
    xi.iter()
        .map(|e| nf.ctx.rf_lie_derivative(e, &vars, &next))
        .collect()
}

/// `F = f0 + sum f_i u_i`, the inputs as symbols, in canonical form.
pub(crate) fn drift_with_inputs(nf: &mut NormalForm) -> Vec<RatFun> {
    let n = nf.state.len();
    let us: Vec<_> = nf
        .inputs
        .clone()
        .iter()
        .map(|u| nf.ctx.symbol(u).id)
        .collect();
    (0..n)
        .map(|k| {
            let mut terms = vec![nf.f0[k]];
            for (f, &u) in nf.fields.clone().iter().zip(&us) {
                let t = nf.ctx.mul(&[f[k], u]);
                terms.push(t);
            }
            let e = nf.ctx.add(&terms);
            nf.ctx.canon(e)
        })
        .collect()
}

/// The error of a kernel that moves with the unknown inputs' jets.
pub(crate) fn unknown_history(names: &[String]) -> AnalysisError {
    AnalysisError::Invalid(format!(
        "the lost directions depend on the unknown inputs' history: the kernel of the observable codistribution changes with the values of {} and their derivatives, so no vector field on the state space spans it and there is no symmetry to certify (docs/engine.md, \"Symmetries with unknown inputs\")",
        names.join(", ")
    ))
}

/// An echelon basis of vectors of canonical forms in the half-angle view,
/// where a form is zero iff it is the zero function (exact membership).
pub(crate) struct Span {
    pub(crate) rows: Vec<(usize, Vec<RatFun>)>,
}

impl Span {
    pub(crate) fn reduce(&self, ctx: &Ctx, mut v: Vec<RatFun>) -> Vec<RatFun> {
        for (p, row) in &self.rows {
            if v[*p].is_zero() {
                continue;
            }
            // row[p] is 1.
            let f = v[*p].clone();
            for (x, y) in v.iter_mut().zip(row) {
                if !y.is_zero() {
                    let t = ctx.rf_mul(&f, y);
                    *x = ctx.rf_sub(x, &t);
                }
            }
        }
        v
    }

    /// Adds `v` (in the half-angle view); `false` if it was in the span.
    pub(crate) fn insert(&mut self, ctx: &Ctx, v: Vec<RatFun>) -> bool {
        let v = self.reduce(ctx, v);
        let Some(p) = v.iter().position(|x| !x.is_zero()) else {
            return false;
        };
        let Some(inv) = ctx.rf_inv(&v[p]) else {
            return false;
        };
        let v: Vec<RatFun> = v.iter().map(|x| ctx.rf_mul(x, &inv)).collect();
        self.rows.push((p, v));
        true
    }
}
