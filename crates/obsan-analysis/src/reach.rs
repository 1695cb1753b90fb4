//! The subsystem over the variables the outputs reach.
//!
//! A state variable that no output reaches through the fields
//! ([`obsan_expr::lie::reached_states`]) enters no Lie derivative: its column of
//! the codistribution is zero, exactly, so it is unobservable and `d/dx` is a
//! symmetry (Definition 2). The Lie derivatives of the outputs depend only
//! on the reached variables and read only the fields' reached components,
//! so the subsystem made of those variables, those components and every
//! output has the same codistribution, restricted to them: the same rank
//! and, extended by zeros, the same symmetries. The symmetry and mode
//! commands work on it, so an unused parameter costs nothing but its name.

use crate::fields::field_names;
use crate::rank::AnalysisError;
use obsan_expr::{lie::reached_states, Ctx, Id};
use obsan_model::NormalForm;

/// A system restricted to its reached variables.
#[derive(Clone, Debug)]
pub struct Reached {
    /// The subsystem: state `keep`, every input and output of the system.
    pub nf: NormalForm,
    /// Indices (in the system's state) of the subsystem's state, increasing.
    pub keep: Vec<usize>,
    /// Indices of the variables no output reaches: each is its own symmetry
    /// direction `d/dx` and unobservable.
    pub unreached: Vec<usize>,
}

/// The variables the outputs reach through every field (drift, inputs,
/// a delay's rates, unknown inputs).
pub fn reached_variables(nf: &mut NormalForm) -> Vec<usize> {
    let (_, mut fields) = field_names(nf);
    fields.extend(nf.unknown_fields.iter().cloned());
    let outputs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    reached_states(&nf.ctx, &nf.state_vars, &fields, &outputs)
}

/// The subsystem over the reached variables, or `None` when every variable
/// is reached (or the system has a delay, whose param stays in the state).
/// The subsystem takes `nf`'s context (its canonical forms and leaves stay
/// valid in `nf`): give it back with
/// `nf.ctx = std::mem::replace(&mut sub.nf.ctx, Ctx::new())` to go on with `nf`.
pub fn restrict_to_reached(nf: &mut NormalForm) -> Option<Reached> {
    if nf.delay.is_some() {
        return None;
    }
    let keep = reached_variables(nf);
    let n = nf.state.len();
    if keep.len() == n {
        return None;
    }
    let mut is_kept = vec![false; n];
    for &k in &keep {
        is_kept[k] = true;
    }
    let unreached: Vec<usize> = (0..n).filter(|&k| !is_kept[k]).collect();
    let pick = |v: &[Id]| -> Vec<Id> { keep.iter().map(|&k| v[k]).collect() };
    let sub = NormalForm {
        ctx: std::mem::replace(&mut nf.ctx, Ctx::new()),
        name: nf.name.clone(),
        description: nf.description.clone(),
        state: keep.iter().map(|&k| nf.state[k].clone()).collect(),
        state_vars: keep.iter().map(|&k| nf.state_vars[k]).collect(),
        n_dynamic: keep.iter().filter(|&&k| k < nf.n_dynamic).count(),
        consts: nf.consts.clone(),
        inputs: nf.inputs.clone(),
        input_vars: nf.input_vars.clone(),
        f0: pick(&nf.f0),
        fields: nf.fields.iter().map(|f| pick(f)).collect(),
        outputs: nf.outputs.clone(),
        restriction: nf.restriction.clone(),
        delay: None,
        unknown_inputs: nf.unknown_inputs.clone(),
        unknown_input_vars: nf.unknown_input_vars.clone(),
        unknown_fields: nf.unknown_fields.iter().map(|f| pick(f)).collect(),
        written: nf.written.clone(),
        measured_inputs: nf.measured_inputs.clone(),
    };
    Some(Reached {
        nf: sub,
        keep,
        unreached,
    })
}

/// Bytes of the dense work of the symmetry routes over `m` variables with
/// `k` symmetries: the F_p rows of the cheap structure (about `2 m` rows of
/// `m` entries, twice, 8 bytes each), and `k` vectors of `m` canonical forms.
pub(crate) fn check_symmetry_memory(m: usize, k: usize) -> Result<(), AnalysisError> {
    let (m, k) = (m as u128, k as u128);
    let rf = std::mem::size_of::<obsan_expr::RatFun>() as u128;
    let bytes = 32 * (m + 4) * m + k * m * rf;
    obsan_expr::limits::check_memory(bytes, "the symmetries (dense in the reached variables)")
        .map_err(|l| AnalysisError::Invalid(l.to_string()))
}
