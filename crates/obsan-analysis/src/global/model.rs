//! The model over Z, as the count sees it: rational right-hand sides and
//! outputs, angles in their half-angle view (trig.rs).

use super::outputs::{self, AngleOutput, OutputForm};
use super::trig;
use super::types::err;
use crate::rank::AnalysisError;
use obsan_expr::{Poly as ZPoly, Var};
use obsan_model::NormalForm;

/// The model over Z: dynamic states (with their derivative `num/den`), params,
/// inputs, known constants (given random values), outputs.
#[derive(Clone)]
pub(super) struct ZModel {
    /// Per state then param: an angle counted as `t = tan(theta/2)`.
    pub(super) angle: Vec<bool>,
    pub(super) dyn_vars: Vec<Var>,
    pub(super) param_vars: Vec<Var>,
    pub(super) input_vars: Vec<Var>,
    pub(super) const_vars: Vec<Var>,
    pub(super) rhs: Vec<(ZPoly, ZPoly)>,
    pub(super) outputs: Vec<(ZPoly, ZPoly)>,
    /// How each output is read (outputs.rs), and the angle outputs read
    /// through their tangent.
    pub(super) forms: Vec<OutputForm>,
    pub(super) angle_outputs: Vec<AngleOutput>,
    /// The model's own symbols (states then params), before the half-angle view.
    pub(super) symbols: Vec<Var>,
}

pub(super) fn zmodel(nf: &mut NormalForm) -> Result<ZModel, AnalysisError> {
    if nf.delay.is_some() {
        return Err(err(
            "global: a model with `delay` is analysed only to first order; global counts need the exact dynamics",
        ));
    }
    let nd = nf.n_dynamic;
    let input_vars = nf.input_vars.clone();
    let mut const_vars = Vec::new();
    for (name, _) in &nf.consts {
        if let Some(s) = nf.ctx.lookup(name) {
            const_vars.push(s.var);
        }
    }
    let limit = |l: obsan_expr::Limit| err(format!("global: {l}"));
    let mut rhs = Vec::with_capacity(nd);
    for s in 0..nd {
        let mut parts = vec![nf.f0[s]];
        for (i, field) in nf.fields.iter().enumerate() {
            let u = nf
                .ctx
                .lookup(&nf.inputs[i])
                .ok_or_else(|| err("global: an input without a symbol"))?;
            let t = nf.ctx.mul(&[field[s], u.id]);
            parts.push(t);
        }
        let id = nf.ctx.add(&parts);
        rhs.push(nf.ctx.try_canon(id).map_err(limit)?);
    }
    // Outputs through sqrt, atan or an angle's tangent (outputs.rs).
    let prepared = outputs::prepare(&mut nf.ctx, &nf.outputs)?;
    let mut outputs = prepared.outputs;
    // Angles in sin/cos become their half-angle tangents (trig.rs).
    let mut vars = nf.state_vars.clone();
    let angle = trig::half_angle_view(&mut nf.ctx, &mut vars, &mut rhs, &mut outputs)?;
    let dyn_vars = vars[..nd].to_vec();
    let param_vars = vars[nd..].to_vec();
    let parts = |r: obsan_expr::RatFun| (r.numerator().clone(), r.denominator().clone());
    let rhs: Vec<(ZPoly, ZPoly)> = rhs.into_iter().map(parts).collect();
    let outputs: Vec<(ZPoly, ZPoly)> = outputs.into_iter().map(parts).collect();
    let known: Vec<Var> = dyn_vars
        .iter()
        .chain(&param_vars)
        .chain(&input_vars)
        .chain(&const_vars)
        .copied()
        .collect();
    for (n, d) in rhs.iter().chain(&outputs) {
        for v in n.vars().into_iter().chain(d.vars()) {
            if !known.contains(&v) {
                return Err(err(format!(
                    "global: `{}` is not a plain symbol; only sin/cos of a state or parameter (counted in the half-angle view) and rational functions are counted; atan/exp/log/sqrt and sin/cos of inputs are not",
                    nf.ctx.leaf_text(v)
                )));
            }
        }
    }
    Ok(ZModel {
        symbols: nf.state_vars.clone(),
        forms: prepared.forms,
        angle_outputs: prepared.angles,
        angle,
        dyn_vars,
        param_vars,
        input_vars,
        const_vars,
        rhs,
        outputs,
    })
}

impl ZModel {
    /// The model with the params marked in `fixed` made known constants
    /// (given random values at the point, as every constant): the Taylor
    /// system of the others, for the initial states' count after the
    /// input-output route (mod.rs, `states_after_io`). A param that takes
    /// one value on every generic fibre is constant on it, so fixing it at
    /// the point's value removes no solution.
    pub(super) fn with_fixed_params(&self, fixed: &[bool]) -> ZModel {
        let mut m = self.clone();
        let nx = self.dyn_vars.len();
        m.param_vars.clear();
        m.angle.truncate(nx);
        for (i, &v) in self.param_vars.iter().enumerate() {
            if fixed.get(i).copied().unwrap_or(false) {
                m.const_vars.push(v);
            } else {
                m.param_vars.push(v);
                m.angle.push(self.angle[nx + i]);
            }
        }
        m
    }
}
