//! SIAN's weighted ordering (Bessonov, Ilmer, Konstantinova, Ovchinnikov,
//! Pogudin, Soto, "Faster global identifiability testing via weighted
//! orderings", 2023, as cited in docs/engine.md): a
//! state first seen in the `L`-th derivative of the outputs gets weight
//! `L + 1`, on every one of its Taylor orders; a locally identifiable
//! parameter first seen at the deepest level `M` gets `M + 1`; the
//! denominators' auxiliary states get `min(3, M)` as SIAN's `z_aux`.
//!
//! The weights only choose the monomial order: the system is taken with
//! `x -> x^w` and counted under grevlex, which is the weighted grevlex order on
//! the original system (the substitution maps monomials injectively and
//! keeps their order, so it maps the reduced basis of the ideal under the
//! weighted order onto the reduced basis of the substituted ideal). The
//! counts are of the original variables: `x^w` (the original `x`) is counted,
//! in the subring of the `x^w` (obsan-groebner's `minimal_polynomial_in`),
//! whose quotient is the original quotient. So a weight can change the time,
//! never an answer.

use super::run::Run;
use obsan_groebner::{GbError, Mono, Poly, Ring};

/// The variables `p` uses (derivation-ring indices).
fn vars_of(p: &Poly, into: &mut Vec<usize>) {
    for (m, _) in p.terms() {
        for (v, &e) in m.exponents().iter().enumerate() {
            if e > 0 && !into.contains(&v) {
                into.push(v);
            }
        }
    }
}

/// The weight of every derivation-ring variable (1 where SIAN sets none).
/// `local[i]` says whether param `i` is locally identifiable.
pub(super) fn sian_weights(run: &Run, local_params: &[bool]) -> Vec<u32> {
    let n = run.ring.n;
    // Which state a derivation-ring variable at order 0 is.
    let state_of = |v: usize| (0..run.ns).find(|&s| run.sv(s, 0) == v);
    let mut level: Vec<Option<u32>> = vec![None; n];
    let mut frontier = Vec::new();
    for out in &run.out_d {
        vars_of(&out[0], &mut frontier);
    }
    let mut l = 0u32;
    let mut deepest = 0u32;
    while !frontier.is_empty() {
        let mut next = Vec::new();
        for &v in &frontier {
            if level[v].is_some() {
                continue;
            }
            level[v] = Some(l);
            deepest = l;
            if let Some(s) = state_of(v) {
                vars_of(&run.rhs_d[s][0], &mut next);
            }
        }
        next.retain(|&v| level[v].is_none());
        frontier = next;
        l += 1;
    }
    let mut w = vec![1u32; n];
    for s in 0..run.nx {
        let ws = level[run.sv(s, 0)].map_or(1, |l| l + 1);
        for k in 0..=run.kmax {
            w[run.sv(s, k)] = ws;
        }
    }
    // The auxiliary states' slots (unused by the cleared system) carry the
    // deepest level for z_weight.
    for s in run.nx..run.ns {
        w[run.sv(s, 0)] = deepest.clamp(1, 3);
    }
    for (i, &loc) in local_params.iter().enumerate() {
        if loc && level[i] == Some(deepest) {
            w[i] = deepest + 1;
        }
    }
    w
}

/// The weight of `z` in `z Q - 1` (sian.rs): SIAN's `min(3, M)`, at least 1.
pub(super) fn z_weight(w: &[u32], run: &Run) -> u32 {
    if run.ns > run.nx {
        w[run.sv(run.nx, 0)]
    } else {
        1
    }
}

/// `gens` with `x_i -> x_i^steps[i]` (the weighted order's view, module docs).
pub(super) fn raise(ring: &Ring, gens: &[Poly], steps: &[u32]) -> Result<Vec<Poly>, GbError> {
    let mut out = Vec::with_capacity(gens.len());
    for g in gens {
        let mut terms = Vec::with_capacity(g.len());
        for (m, c) in g.terms() {
            let mut e = Vec::with_capacity(steps.len());
            for (&k, &s) in m.exponents().iter().zip(steps) {
                e.push(k.checked_mul(s).ok_or(GbError::Degree)?);
            }
            terms.push((Mono::from_exponents(e)?, *c));
        }
        out.push(ring.from_terms(terms));
    }
    Ok(out)
}
