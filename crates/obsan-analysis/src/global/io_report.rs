//! `obsan global` by the input-output route (io.rs, io_count.rs): the
//! parameters' counts as a [`GlobalReport`], used when the Taylor system
//! passes a budget (or on request).

use super::io_count::io_count_with;
pub(super) use super::io_count::MAX_ANSATZ;
pub(super) use super::io_pres::PAST_ANSATZ;
use super::model::zmodel;
use super::outputs::OutputForm;
use super::types::{err, GlobalOptions, GlobalReport, GlobalVariable, Identifiability, Route};
use crate::rank::AnalysisError;
use obsan_model::NormalForm;

/// Whether the Taylor route's error is a budget the other route may avoid
/// (not a refusal of the model, not the deadline).
pub(super) fn falls_back(why: &str) -> bool {
    why.contains("too large") || why.contains("Gröbner basis budget exhausted")
}

pub(super) fn io_route(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
    fallback: Option<String>,
    eliminate: bool,
    cap: usize,
) -> Result<GlobalReport, AnalysisError> {
    let m = zmodel(nf)?;
    if m.angle.iter().any(|&a| a) || m.forms.iter().any(|f| *f != OutputForm::Direct) {
        return Err(err(
            "global (io): angles, and outputs read through sqrt, atan or a tangent, are counted by the Taylor route only",
        ));
    }
    let c = io_count_with(&m, opts, opts.seed, eliminate, cap)?;
    let nx = m.dyn_vars.len();
    let variables: Vec<GlobalVariable> = nf.state[nx..]
        .iter()
        .zip(&c.per_param)
        .map(|(name, k)| GlobalVariable {
            name: name.clone(),
            param: true,
            angle: false,
            verdict: match k {
                None => Identifiability::NotIdentifiable,
                Some(1) => Identifiability::Global,
                Some(k) => Identifiability::Local(*k),
            },
            at_most: false,
        })
        .collect();
    Ok(GlobalReport {
        all_local: c.per_param.iter().all(|k| k.is_some()),
        variables,
        solutions: c.joint,
        maps: Vec::new(),
        group_order: 1,
        solutions_at_most: false,
        output_forms: nf
            .outputs
            .iter()
            .zip(&m.forms)
            .map(|(o, f)| (o.0.clone(), f.clone()))
            .collect(),
        order: c.sizes.iter().map(|s| s.order).max().unwrap_or(0),
        rank_order: 0,
        output_orders: nf
            .outputs
            .iter()
            .zip(&c.sizes)
            .map(|(o, s)| (o.0.clone(), s.order))
            .collect(),
        delta_local: 0.0,
        log10_delta_global: 0.0,
        // The coefficients are verified (c.recon_bound); the two random
        // points of the count carry no degree bound yet.
        error_bound: 1.0,
        unknowns: m.param_vars.len() + 1,
        equations: c.sizes.iter().map(|s| s.support - 1).sum(),
        primes: c.primes,
        route: Route::InputOutput,
        fallback,
        multi_experiment: c.sizes.iter().any(|s| !s.single),
        io_sizes: c.sizes,
        states_after_io: None,
    })
}
