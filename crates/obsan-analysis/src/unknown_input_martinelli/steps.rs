//! The steps of one run of Martinelli's algorithm (the parent module's `run`):
//! canonization by `nu = mu^{-1}`, the vanishing test of the residual fields,
//! the extension by the reconstructed inputs' derivatives, and the verdicts
//! from the final codistribution.

use super::{
    combine, feedthrough, inverse, row_degree, Growth, KnownJets, MartinelliReport, MartinelliStep,
    St,
};
use crate::rank::{AnalysisError, Echelon};
use obsan_expr::{evaluate::degree_bounds, Fp, Id, Var, P};
use obsan_model::NormalForm;

/// Canonization: with `ht` the observable functions whose `mu = [L_g ht]`
/// over the canonic inputs `cols` is invertible, the canonic fields
/// `ghat = g_cols nu`, the drift with their part removed (`g0 = f - ghat L_f ht`)
/// and the residual fields of the other inputs (`g - ghat L_g ht`).
#[allow(clippy::type_complexity)]
pub(super) fn canonize(
    st: &mut St,
    ht: &[Id],
    cols: &[usize],
    mw: usize,
) -> Result<(Vec<Vec<Id>>, Vec<Id>, Vec<Vec<Id>>), AnalysisError> {
    let m = cols.len();
    // Canonic inputs first.
    let others: Vec<usize> = (0..mw).filter(|k| !cols.contains(k)).collect();
    let gc: Vec<Vec<Id>> = cols.iter().map(|&k| st.g[k].clone()).collect();
    let gr: Vec<Vec<Id>> = others.iter().map(|&k| st.g[k].clone()).collect();
    // Canonization.
    let mu: Vec<Vec<Id>> = ht
        .iter()
        .map(|&h| gc.iter().map(|g| st.lie(h, g)).collect())
        .collect();
    let nu = inverse(st, &mu)?;
    let gc_refs: Vec<&Vec<Id>> = gc.iter().collect();
    let ghat: Vec<Vec<Id>> = (0..m)
        .map(|j| {
            let coefs: Vec<Id> = (0..m).map(|k| nu[k][j]).collect();
            combine(&mut st.ctx, &gc_refs, &coefs)
        })
        .collect();
    let drift = st.drift.clone();
    let a: Vec<Id> = ht.iter().map(|&h| st.lie(h, &drift)).collect();
    let mut g0 = drift.clone();
    if m > 0 {
        let refs: Vec<&Vec<Id>> = ghat.iter().collect();
        let corr = combine(&mut st.ctx, &refs, &a);
        for (x, c) in g0.iter_mut().zip(corr) {
            *x = st.ctx.sub(*x, c);
        }
    }
    let mut residual = Vec::new();
    for g in &gr {
        let coefs: Vec<Id> = ht.iter().map(|&h| st.lie(h, g)).collect();
        let mut r = g.clone();
        if m > 0 {
            let refs: Vec<&Vec<Id>> = ghat.iter().collect();
            let corr = combine(&mut st.ctx, &refs, &coefs);
            for (x, c) in r.iter_mut().zip(corr) {
                *x = st.ctx.sub(*x, c);
            }
        }
        residual.push(r);
    }
    Ok((ghat, g0, residual))
}

/// Whether every component of every residual field is the zero function.
pub(super) fn all_zero(st: &mut St, residual: &[Vec<Id>]) -> Result<bool, AnalysisError> {
    for r in residual {
        for &x in r {
            if !st.is_zero_fn(x)? {
                return Ok(false);
            }
        }
    }
    Ok(true)
}

/// The extension (a new iteration's unknowns): the canonic inputs'
/// derivatives up to order `ord` become states, the drift moves along
/// `ghat v`, the new input fields drive the top derivatives, and `theta`'s
/// order-`ord` derivative joins the observable functions.
#[allow(clippy::too_many_arguments)]
pub(super) fn extend(
    st: &mut St,
    iteration: usize,
    ord: usize,
    theta: Id,
    ghat: &[Vec<Id>],
    g0: &[Id],
    residual: &[Vec<Id>],
) {
    let m = ghat.len();
    // Extension: v_j^(l), l = 0..=ord, after the current unknowns.
    let zero = st.ctx.zero();
    let one = st.ctx.one();
    let mut chain: Vec<Vec<(Var, Id)>> = Vec::new();
    for j in 0..m {
        let mut c = Vec::new();
        for l in 0..=ord {
            let s = st.ctx.symbol(&format!("'v{iteration}_{j}^({l})"));
            c.push((s.var, s.id));
        }
        chain.push(c);
    }
    let mut comps = Vec::new();
    for c in &chain {
        for l in 0..=ord {
            comps.push(if l < ord { c[l + 1].1 } else { zero });
        }
    }
    let v0: Vec<Id> = chain.iter().map(|c| c[0].1).collect();
    let refs: Vec<&Vec<Id>> = ghat.iter().collect();
    let moved = combine(&mut st.ctx, &refs, &v0);
    let mut nd: Vec<Id> = g0.to_vec();
    for (x, y) in nd.iter_mut().zip(moved) {
        *x = st.ctx.add(&[*x, y]);
    }
    let nd = st.pad(&nd, &comps);
    let nchain = m * (ord + 1);
    let mut ng: Vec<Vec<Id>> = Vec::new();
    for j in 0..m {
        let mut e = vec![zero; nchain];
        e[j * (ord + 1) + ord] = one;
        let base = vec![zero; st.unknown.len() + st.known.len()];
        ng.push(st.pad(&base, &e));
    }
    for r in residual {
        ng.push(st.pad(r, &vec![zero; nchain]));
    }
    let pos = st.unknown.len();
    for (k, c) in chain.iter().enumerate() {
        for (l, &(v, _)) in c.iter().enumerate() {
            st.unknown.insert(pos + k * (ord + 1) + l, v);
        }
    }
    st.drift = nd.clone();
    st.g = ng;
    let mut thetav = theta;
    for _ in 0..ord {
        thetav = st.lie(thetav, &nd);
    }
    for c in &chain {
        for &(_, id) in c {
            st.hobs.push(id);
        }
    }
    st.hobs.push(thetav);
}

/// The verdicts from the final codistribution: which states are observable,
/// which unknown inputs reconstructable, the state part's rank, whether the
/// known inputs' jets were deep enough, and the error bound.
pub(super) fn verdicts(
    mut st: St,
    nf: &NormalForm,
    growth: Growth,
    steps: Vec<MartinelliStep>,
    top: Option<KnownJets>,
    jets: usize,
) -> Result<(MartinelliReport, bool), AnalysisError> {
    let n = nf.state.len();
    let mw = nf.unknown_inputs.len();
    // Verdicts from the final codistribution.
    let cod = growth.cod;
    let len = st.unknown.len();
    // With free roots: the codistribution's gradient rows, built, for the
    // claims that a unit row lies outside it and of its projection's rank.
    let sym_rows: Vec<Vec<Id>> = if st.claims.active {
        let cols = st.unknown.clone();
        growth
            .syms
            .iter()
            .map(|&f| cols.iter().map(|&v| st.ctx.diff(f, v)).collect())
            .collect()
    } else {
        Vec::new()
    };
    let (zero, one) = (st.ctx.zero(), st.ctx.one());
    let unit_row = |c: usize, w: usize| -> Vec<Id> {
        (0..w).map(|i| if i == c { one } else { zero }).collect()
    };
    let unit = |st: &mut St, col: usize| -> bool {
        let mut v = vec![Fp::ZERO; len];
        v[col] = Fp::ONE;
        let inside = cod.ech.reduce(v).iter().all(|x| x.is_zero());
        if inside {
            st.err_deg += cod.deg_sum as f64;
        } else {
            let mut rows = sym_rows.clone();
            rows.push(unit_row(col, len));
            st.claims.rank(rows, cod.ech.rank() + 1);
        }
        inside
    };
    let observable: Vec<bool> = (0..n).map(|i| unit(&mut st, i)).collect();
    let through = feedthrough(&mut st.ctx, nf);
    let mut reconstructable: Vec<Option<bool>> = vec![None; mw];
    for (a, &j) in through.iter().enumerate() {
        reconstructable[j] = Some(unit(&mut st, n + a));
    }
    // With the whole state observable, `x` and `x'` are known, so `G(x) w`
    // and the outputs' dependence on `w` are: `w_j` is reconstructable iff
    // `e_j` is in the row space of `[G; dh/dw]` (exact, and the converse:
    // nothing else is known about `w`).
    if observable.iter().all(|&b| b) && reconstructable.iter().any(Option::is_none) {
        let mut ids: Vec<Vec<Id>> = (0..n)
            .map(|k| (0..mw).map(|j| nf.unknown_fields[j][k]).collect())
            .collect();
        for o in &nf.outputs {
            let row = nf
                .unknown_input_vars
                .iter()
                .map(|&w| st.ctx.diff(o.1, w))
                .collect();
            ids.push(row);
        }
        let mut rows = Echelon::default();
        let mut kept: Vec<Vec<Id>> = Vec::new();
        let mut deg = 0u64;
        for r in &ids {
            let v = st
                .ctx
                .eval_fp(r, &st.point)
                .map_err(|_| AnalysisError::NoPoint)?;
            let d = row_degree(&degree_bounds(&st.ctx, r));
            if rows.insert(v) {
                deg = deg.saturating_add(d);
                kept.push(r.clone());
            } else {
                st.err_deg += deg.saturating_add(d) as f64;
            }
        }
        st.claims.rank(kept.clone(), kept.len());
        for (j, r) in reconstructable.iter_mut().enumerate() {
            if r.is_none() {
                let mut v = vec![Fp::ZERO; mw];
                v[j] = Fp::ONE;
                let inside = rows.reduce(v).iter().all(|x| x.is_zero());
                if inside {
                    st.err_deg += deg as f64;
                } else {
                    let mut with = kept.clone();
                    with.push(unit_row(j, mw));
                    st.claims.rank(with, kept.len() + 1);
                }
                *r = Some(inside);
            }
        }
    }
    // The state part: rank minus the rank of the projection on the others.
    let mut proj = Echelon::default();
    for r in &cod.rows {
        proj.insert(r[n..].to_vec());
    }
    let proj_rows: Vec<Vec<Id>> = sym_rows.iter().map(|r| r[n..].to_vec()).collect();
    st.claims.rank(proj_rows, proj.rank());
    st.err_deg += cod.deg_sum as f64;
    let rank = cod.ech.rank() - proj.rank();
    // The highest known-input jet in any expression built, plus the longest
    // word derived from them, reaches `u^(D)`: the run is not valid (each
    // Lie derivative raises the jet order by at most one).
    let reach = st.ctx.reachable(&st.built);
    let highest = top
        .iter()
        .flat_map(|t| t.iter())
        .filter(|(id, _)| reach.binary_search(id).is_ok())
        .map(|&(_, l)| l)
        .max()
        .unwrap_or(0);
    let used_top = top.is_some() && highest + st.max_word + 1 >= jets;
    let error_bound = (st.err_deg * st.draws as f64 / P as f64).min(1.0);
    let roots_field = if st.claims.active {
        let seed = st.seed;
        Some(crate::unknown_input_roots::prove(
            &mut st.ctx,
            &st.claims,
            seed,
        )?)
    } else {
        None
    };
    Ok((
        MartinelliReport {
            n,
            rank,
            observable,
            reconstructable,
            steps,
            rounds: growth.rounds,
            dimension: len,
            codistribution_rank: cod.ech.rank(),
            input_jets: jets,
            error_bound,
            roots_field,
        },
        used_top,
    ))
}
