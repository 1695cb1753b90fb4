//! `obsan global` by the input-output route (io.rs, io_count.rs): the
//! parameters' counts as a [`GlobalReport`], used when the Taylor system
//! passes a budget (or on request).

use super::io_count::io_count_with;
pub(super) use super::io_count::MAX_ANSATZ;
pub(super) use super::io_pres::PAST_ANSATZ;
use super::maps::{group_order, Candidate, Image};
use super::model::zmodel;
use super::outputs::OutputForm;
use super::types::{
    err, DiscreteMap, GlobalOptions, GlobalReport, GlobalVariable, Identifiability, MapImage, Route,
};
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
    // The relations' maps of the parameters (io_check.rs), named, and the
    // group they generate (the states fixed).
    let names: Vec<&str> = nf.state[nx..].iter().map(String::as_str).collect();
    let maps: Vec<DiscreteMap> = c
        .maps
        .iter()
        .map(|pm| DiscreteMap {
            images: pm
                .iter()
                .enumerate()
                .filter(|&(v, &(w, s))| v != w || s < 0)
                .map(|(v, &(w, s))| MapImage {
                    var: names[v].to_string(),
                    sign: s,
                    image: names[w].to_string(),
                    plus_pi: false,
                })
                .collect(),
            keeps_angles: Some(true),
            params_only: true,
        })
        .collect();
    let candidates: Vec<Candidate> = c
        .maps
        .iter()
        .map(|pm| {
            (0..nx)
                .map(|v| Image {
                    var: v,
                    sign: 1,
                    exp: 1,
                })
                .chain(pm.iter().map(|&(w, sign)| Image {
                    var: nx + w,
                    sign,
                    exp: 1,
                }))
                .collect()
        })
        .collect();
    let mut group_order = group_order(&candidates, nx + names.len(), 100_000);
    let mut maps = maps;
    // A rational map between two solutions: an involution (the other
    // solution's other is the first), its moved coordinates as formulas.
    if let Some(r) = &c.rational_map {
        maps.push(DiscreteMap {
            images: r
                .iter()
                .enumerate()
                .filter(|(v, f)| !super::io_check::is_identity(f, *v))
                .map(|(v, f)| MapImage {
                    var: names[v].to_string(),
                    sign: 1,
                    image: f.display(&names).to_string(),
                    plus_pi: false,
                })
                .collect(),
            keeps_angles: Some(true),
            params_only: true,
        });
        group_order = 2;
    }
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
        maps,
        group_order,
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
