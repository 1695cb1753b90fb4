//! Symmetries of a system whose outputs contain an unknown input (direct
//! feedthrough), through the system with that input made a state.
//!
//! **The extended system.** Each unknown input `w_j` an output contains
//! becomes a state with `w_j' = v_j`, `v_j` a new unknown input; the outputs
//! are then functions of the (extended) state, which the certificate of
//! `unknown_input_symmetry.rs` needs. The two systems have the same output
//! trajectories: `(S0, w(.))` with `w` smooth gives the same outputs as
//! `((S0, w(0)), v = w')`. Martinelli's rank test makes the same extension
//! (`unknown_input_martinelli.rs`).
//!
//! **The projection.** A certified symmetry `(xi_S, xi_w)` of the extended
//! system moves `(S0, w0)` without changing any output, whatever the inputs:
//! so `S0` and `S0 + eps xi_S` are indistinguishable in the original system
//! (the inputs `w` differ, which is the unknown inputs' freedom). Its
//! `S`-part `xi_S` is therefore an unobservable direction of the original, as
//! exactly as the extended certificate. The projected vectors are accepted
//! only if they are as many as the original rank test leaves
//! (`n - rank`) and keep the form the symmetries have (a 1 on their own
//! free column, 0 on the others'); otherwise the directions are refused.

use crate::rank::AnalysisError;
use crate::unknown_input::{unknown_input_rank, UnknownInputOptions};
use crate::unknown_input_symmetry::{symmetries_without_feedthrough, UnknownInputSymmetries};
use obsan_expr::{Id, RatFun};
use obsan_model::NormalForm;

/// The symmetries of a normal form with unknown inputs (module docs):
/// `Err(Invalid)` with the reason when a candidate is not certified or the
/// two rank routes disagree. Outputs holding an unknown input go through
/// the system with that input made a state (module docs). It lives here, not
/// in unknown_input_symmetry.rs, so that the module graph stays acyclic.
pub fn unknown_input_symmetries(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
) -> Result<UnknownInputSymmetries, AnalysisError> {
    let through = feedthrough_inputs(nf);
    if !through.is_empty() {
        return feedthrough_symmetries(nf, &through, opts);
    }
    symmetries_without_feedthrough(nf, opts)
}

/// The unknown inputs the outputs contain.
fn feedthrough_inputs(nf: &mut NormalForm) -> Vec<usize> {
    let outs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    let mut through = Vec::new();
    for (j, &v) in nf.unknown_input_vars.clone().iter().enumerate() {
        if outs.iter().any(|&h| {
            let h = nf.ctx.canon(h);
            !nf.ctx.rf_diff(&h, v).is_zero()
        }) {
            through.push(j);
        }
    }
    through
}

/// `nf` with the unknown inputs `through` made states at the end of the
/// state (after the params, so that the pivots of the kernel prefer them and
/// the free columns stay among the original variables), each driven by a new
/// unknown input `w'`.
fn extended(nf: &NormalForm, through: &[usize]) -> NormalForm {
    let mut e = nf.clone();
    let (zero, one) = (e.ctx.int(0), e.ctx.int(1));
    // The drift gains g_j w_j, w_j now a coordinate.
    for &j in through {
        let w = e.ctx.symbol(&nf.unknown_inputs[j]).id;
        for k in 0..nf.state.len() {
            let gw = e.ctx.mul(&[nf.unknown_fields[j][k], w]);
            e.f0[k] = e.ctx.add(&[e.f0[k], gw]);
        }
    }
    let len = nf.state.len() + through.len();
    for &j in through {
        e.state.push(nf.unknown_inputs[j].clone());
        e.state_vars.push(nf.unknown_input_vars[j]);
        e.f0.push(zero);
    }
    for f in e.fields.iter_mut() {
        f.resize(len, zero);
    }
    for (j, g) in e.unknown_fields.iter_mut().enumerate() {
        match through.iter().position(|&k| k == j) {
            Some(a) => {
                *g = vec![zero; len];
                g[nf.state.len() + a] = one;
            }
            None => g.resize(len, zero),
        }
    }
    for &j in through {
        let name = format!("{}'", nf.unknown_inputs[j]);
        let s = e.ctx.symbol(&name);
        e.unknown_inputs[j] = name;
        e.unknown_input_vars[j] = s.var;
    }
    e
}

/// Symmetries of `nf` (with feedthrough inputs `through`) from those of the
/// extended system (module docs).
fn feedthrough_symmetries(
    nf: &mut NormalForm,
    through: &[usize],
    opts: UnknownInputOptions,
) -> Result<UnknownInputSymmetries, AnalysisError> {
    let again = UnknownInputOptions {
        seed: opts.seed,
        deadline: opts.deadline,
        max_order: opts.max_order,
    };
    let report = unknown_input_rank(nf, again)?;
    if !report.agree {
        return Err(AnalysisError::Invalid(
            "the two unknown-input rank routes disagree (see `obsan rank`): no kernel to certify"
                .into(),
        ));
    }
    let n = nf.state.len();
    let mut ext = extended(nf, through);
    let es = symmetries_without_feedthrough(&mut ext, opts)?;
    let k = n - report.rank;
    let refuse = |why: &str| {
        AnalysisError::Invalid(format!(
            "symmetries with a direct feedthrough (an output holds an unknown input): {why}"
        ))
    };
    // A vector whose free column is an input made a state moves that input
    // alone among the free columns: its S-part is another direction, not in
    // the normalised form.
    // The jets' symbols live in the extended system's context, not in nf's.
    if es.input_dependent() {
        return Err(refuse(
            "the lost directions move with the known inputs, which is not handled with an input made a state",
        ));
    }
    if es.free.iter().any(|&c| c >= n) {
        return Err(refuse(
            "a lost direction of the extended system is free on an input made a state",
        ));
    }
    if es.vectors.len() != k {
        return Err(refuse(&format!(
            "the extended system loses {} direction(s) among the variables, the rank test {k}",
            es.vectors.len()
        )));
    }
    let vectors: Vec<Vec<RatFun>> = es.vectors.iter().map(|v| v[..n].to_vec()).collect();
    Ok(UnknownInputSymmetries {
        report,
        vectors,
        free: es.free,
        identities: es.identities,
        made_states: through
            .iter()
            .map(|&j| nf.unknown_inputs[j].clone())
            .collect(),
        input_jets: Vec::new(),
    })
}
