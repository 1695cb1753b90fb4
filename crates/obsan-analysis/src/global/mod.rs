//! Global identifiability: how many values of each parameter and initial
//! state give the output of a generic one, and the discrete symmetries that
//! map one to another (docs/engine.md, "Global identifiability").
//!
//! SIAN's route (Hong, Ovchinnikov, Pogudin, Yap, Bioinformatics 2019): the
//! output's Taylor coefficients `y^(j)(0)` are polynomials in the parameters,
//! the initial state and the higher derivatives `x^(k)(0)` (new unknowns tied
//! by `x^(k+1) = D^k f`), the inputs' coefficients random. At a random point
//! the coefficients are numbers; the zeros of the system over the algebraic
//! closure of F_p are the (params, initial states) with the same output jet,
//! and a Gröbner basis over F_p (obsan-groebner) counts the values each
//! variable takes on them. Denominators are cleared by `z * den = 1`, with
//! `z' = -z^2 den'` so the system stays polynomial.

use crate::rank::AnalysisError;
use obsan_model::NormalForm;

mod count;
mod maps;
mod model;
mod run;
mod sian;
mod trig;
mod types;
mod weights;

use count::{count_once, error_bounds};
use maps::{find_maps, group_order};
use model::zmodel;
use run::Run;
use types::err;
pub use types::{DiscreteMap, GlobalOptions, GlobalReport, GlobalVariable, Identifiability};

/// Global identifiability of every parameter and initial state (SIAN's
/// route; the certificate and the bounds are in docs/engine.md): two
/// independent runs (different primes and random points) must agree.
pub fn global_identifiability(
    nf: &mut NormalForm,
    opts: &GlobalOptions,
) -> Result<GlobalReport, AnalysisError> {
    let m = zmodel(nf)?;
    let primes = [obsan_recon::PRIMES[0], obsan_recon::PRIMES[1]];
    let kmax = opts.max_order + 2;
    let mut results = Vec::new();
    for (r, &p) in primes.iter().enumerate() {
        let mut run = Run::new(&m, p, opts.seed.wrapping_add(r as u64), kmax)?;
        run.max_bytes = opts.max_bytes;
        results.push(count_once(&mut run, opts)?);
    }
    let (a, b) = (&results[0], &results[1]);
    if a.per_var != b.per_var || a.joint != b.joint || a.orders != b.orders {
        return Err(err(
            "global: two independent random points disagree on the counts (a non-generic point); try another --seed",
        ));
    }
    let nx = m.dyn_vars.len();
    let np = m.param_vars.len();
    let bounds = error_bounds(&m, &results, &primes);
    // Names: params then states, as the counts are ordered.
    let names: Vec<(String, bool)> = nf.state[nx..]
        .iter()
        .map(|s| (s.clone(), true))
        .chain(nf.state[..nx].iter().map(|s| (s.clone(), false)))
        .collect();
    let variables: Vec<GlobalVariable> = names
        .iter()
        .zip(&a.per_var)
        .enumerate()
        .map(|(i, ((name, param), c))| GlobalVariable {
            name: name.clone(),
            param: *param,
            angle: m.angle[if i < np { nx + i } else { i - np }],
            verdict: match c {
                None => Identifiability::NotIdentifiable,
                Some(1) => Identifiability::Global,
                Some(k) => Identifiability::Local(*k),
            },
        })
        .collect();
    let all_local = a.per_var.iter().all(|c| c.is_some());
    // Multi-valued variables in model order (states then params).
    let mut multi = vec![false; nx + np];
    for (i, c) in a.per_var.iter().enumerate() {
        let idx = if i < np { nx + i } else { i - np };
        multi[idx] = matches!(c, Some(k) if *k > 1);
    }
    let maps = if multi.iter().any(|&x| x) {
        find_maps(&m, &multi, 200_000)
    } else {
        Vec::new()
    };
    let group = group_order(&maps, nx + np, 100_000);
    let all_names: Vec<&str> = nf.state.iter().map(|s| s.as_str()).collect();
    let maps_out = maps
        .iter()
        .map(|s| DiscreteMap {
            images: s
                .iter()
                .enumerate()
                .filter(|(v, im)| *v != im.var || im.sign < 0 || im.exp < 0)
                .map(|(v, im)| im.named(all_names[v], &all_names))
                .collect(),
        })
        .collect();
    Ok(GlobalReport {
        variables,
        solutions: a.joint,
        all_local,
        maps: maps_out,
        group_order: group,
        order: a.orders.iter().copied().max().unwrap_or(0),
        rank_order: a.rank_order,
        output_orders: nf
            .outputs
            .iter()
            .zip(&a.orders)
            .map(|(o, &k)| (o.0.clone(), k))
            .collect(),
        delta_local: bounds.0,
        log10_delta_global: bounds.1,
        error_bound: bounds.2,
        unknowns: a.unknowns,
        equations: a.equations,
        primes,
    })
}

#[cfg(test)]
mod tests;
