//! Martinelli's unknown-input observability algorithm with its convergence
//! criterion (A. Martinelli, "Nonlinear unknown input observability and
//! unknown input reconstruction: the general analytical solution", arXiv
//! 2201.07610, Algorithm 5.1; the structure follows his MIT-licensed MATLAB
//! toolbox agomartinelli/TUIO6, re-derived here, not translated). It proves
//! where the growth stops, which the extended-state route of
//! `unknown_input.rs` cannot: there every order brings new unknown-input
//! jets.
//!
//! The system `x' = g0(x, t) + sum_j g^j(x, t) w_j`. The known inputs are
//! folded into `g0` as known coordinates (their jets `u, u', ..., u^(D)`, with
//! `u^(l)' = u^(l+1)`): a Lie derivative along `g0` is then the total time
//! derivative, as `d/dt` is in TUIO6. Each unknown input is first made a
//! state (`w_j' = ` a new unknown input): the outputs may then contain it
//! (direct feedthrough), the output trajectories are the same (a smooth
//! `w_j` with a free initial value either way), and `w_j` is reconstructable
//! iff that state is observable.
//!
//! One iteration, on the observable functions `hobs` (independent gradients):
//! 1. the degree of reconstructability `m`: the rank of the reconstructability
//!    matrix `RM_ik = L_{g^k} hobs_i`; `m` rows give `ht`, `m` columns the
//!    canonic unknown inputs (put first).
//! 2. `m == m_w`: canonic. Otherwise canonization: `mu = L_g ht` (`m x m`),
//!    `nu = mu^{-1}`, `ĝ^j = sum_k g^k nu_kj`, `ĝ0 = g0 - sum_j ĝ^j L_{g0} ht_j`,
//!    and the residual fields `Ĝ_k = g^k - sum_j ĝ^j L_{g^k} ht_j` of the other
//!    inputs (in them `ht` does not move).
//! 3. The codistribution grows from `hobs` by Lie derivatives along `ĝ0` and
//!    the `ĝ^j`, round by round, each generator first tested against the
//!    residual fields. If every residual field vanishes, or the growth stops
//!    (a round adds nothing) with every generator annihilated by them, the
//!    codistribution is the observable one: the convergence criterion.
//!    A generator `L^ord θ` moved by a residual field identifies a further
//!    input: with `m == 0` the growth continues along `ĝ0` without deriving
//!    the moved generators; otherwise the state is extended by
//!    `v_j = d ht_j / dt` and its derivatives up to `ord` (observable
//!    functions), `x' = ĝ0 + sum_j v_j ĝ^j`, the top derivatives and the
//!    residual inputs the new unknown inputs, and `θ^(ord)` is added. Either
//!    step raises `m`, so there are at most `m_w + 1` iterations.
//!
//! Exact: `nu` is built as an expression (Gauss–Jordan on the graph, pivots
//! chosen where their value is non-zero), never inverted in floating point.
//! Every "non-zero" and every "independent" is proven by a non-zero value in
//! F_p (`p = 2^61 - 1`); every "zero" and "dependent" holds unless the random
//! point is a root of a non-zero rational function whose numerator degree is
//! bounded ([`obsan_expr::evaluate::degree_bounds`]); the sum of those bounds over p is
//! the stated error bound (Schwartz–Zippel, union bound).
//!
//! Unlike TUIO6 the whole chain `v_j, ..., v_j^(ord)` is kept (all of it is
//! observable, so it changes no verdict), and the known-input jets are
//! truncated at `D`: the run is valid when no expression ever built contains
//! `u^(D)` (then the truncation `u^(D)' = 0` was never used); otherwise it is
//! repeated with `D` doubled.

use crate::rank::{rank_point, AnalysisError, Echelon};
use crate::unknown_input_roots::Claims;
use obsan_expr::{evaluate::degree_bounds, evaluate::FpPoint, Ctx, Fp, Id, SplitMix, Var};
use obsan_model::NormalForm;
use std::time::Instant;

mod steps;
use steps::{all_zero, canonize, extend, verdicts};

/// One iteration of the algorithm, for the report.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MartinelliStep {
    /// Degree of reconstructability at the start of the iteration.
    pub degree: usize,
    /// What ended it (`canonic`, `residual fields vanish`, `converged`,
    /// `extension to order k`, `growth along the drift`).
    pub action: String,
}

/// The result of Martinelli's algorithm.
#[derive(Clone, Debug)]
pub struct MartinelliReport {
    /// Dimension of the analysed state (states then params).
    pub n: usize,
    /// Dimension of the observable codistribution's part in the state.
    pub rank: usize,
    pub observable: Vec<bool>,
    /// Per unknown input: `None` when the algorithm does not decide it (it
    /// does for an input the outputs contain, made a state, and for every
    /// input when the whole state is observable).
    pub reconstructable: Vec<Option<bool>>,
    pub steps: Vec<MartinelliStep>,
    /// Rounds of Lie derivatives of the last growth; its last round added
    /// nothing (or the rank was full): the proven stopping point.
    pub rounds: usize,
    /// Dimension of the final extended space and rank of the final
    /// codistribution in it.
    pub dimension: usize,
    pub codistribution_rank: usize,
    /// Jets of the known inputs carried (`u, ..., u^(D)`).
    pub input_jets: usize,
    /// Probability that some decision is wrong (Schwartz–Zippel, module docs).
    pub error_bound: f64,
    /// Degree `k` of the field `F_(p^k)` where the decisions taken at free
    /// root values were proven (unknown_input_roots.rs); `None` when the
    /// points satisfied the roots' relations.
    pub roots_field: Option<u32>,
}

struct St {
    ctx: Ctx,
    /// Columns of the gradients: the state, the unknown inputs, extensions.
    unknown: Vec<Var>,
    /// Known coordinates: the known inputs' jets.
    known: Vec<Var>,
    /// Fields over `unknown ++ known`.
    drift: Vec<Id>,
    g: Vec<Vec<Id>>,
    hobs: Vec<Id>,
    point: FpPoint,
    rng: SplitMix,
    draws: u64,
    /// Sum of the degree bounds of every "zero" decision.
    err_deg: f64,
    built: Vec<Id>,
    /// Longest word of Lie derivatives evaluated by jets.
    max_word: usize,
    deadline: Option<Instant>,
    /// The points give the roots free values: decisions to prove
    /// (unknown_input_roots.rs).
    free: bool,
    claims: Claims,
    seed: u64,
}

fn row_degree(d: &[(u64, u64)]) -> u64 {
    let max_num = d.iter().map(|x| x.0).max().unwrap_or(0);
    let sum_den: u64 = d.iter().map(|x| x.1).fold(0, u64::saturating_add);
    max_num.saturating_add(sum_den)
}

impl St {
    fn all(&self) -> Vec<Var> {
        let mut a = self.unknown.clone();
        a.extend_from_slice(&self.known);
        a
    }
    fn check(&self) -> Result<(), AnalysisError> {
        if obsan_expr::cancel_requested() {
            return Err(AnalysisError::Cancelled);
        }
        if let Some(d) = self.deadline {
            if Instant::now() > d {
                return Err(AnalysisError::Timeout(format!(
                    "in Martinelli's algorithm, extended dimension {}",
                    self.unknown.len()
                )));
            }
        }
        Ok(())
    }
    fn redraw(&mut self) -> Result<(), AnalysisError> {
        let (p, k, _) = rank_point(&mut self.ctx, &mut self.rng, self.free)?;
        self.point = p;
        self.draws = self.draws.max(k);
        Ok(())
    }
    fn value(&self, f: Id) -> Result<Fp, AnalysisError> {
        self.ctx
            .eval_fp(&[f], &self.point)
            .map(|v| v[0])
            .map_err(|_| AnalysisError::NoPoint)
    }
    /// `f` is identically zero (proven if structurally zero, else with the
    /// stated bound when its value is 0).
    fn is_zero_fn(&mut self, f: Id) -> Result<bool, AnalysisError> {
        if self.ctx.is_zero(f) {
            return Ok(true);
        }
        if self.value(f)?.is_zero() {
            self.err_deg += degree_bounds(&self.ctx, &[f])[0].0 as f64;
            return Ok(true);
        }
        self.claims.nonzero(f);
        Ok(false)
    }
    /// `L_field f` for a claim only (not among `built`, whose jets decide
    /// whether the run is valid).
    fn lie_claim(&mut self, f: Id, field: &[Id]) -> Id {
        let all = self.all();
        self.ctx.lie_derivative(f, &all, field)
    }
    fn lie(&mut self, f: Id, field: &[Id]) -> Id {
        let all = self.all();
        let l = self.ctx.lie_derivative(f, &all, field);
        self.built.push(l);
        l
    }
    /// The gradient of `f` over the unknown columns at the point, and its
    /// row degree.
    fn grad(&mut self, f: Id) -> Result<(Vec<Fp>, u64), AnalysisError> {
        let vars = self.unknown.clone();
        let ids: Vec<Id> = vars.iter().map(|&v| self.ctx.diff(f, v)).collect();
        let vals = self
            .ctx
            .eval_fp(&ids, &self.point)
            .map_err(|_| AnalysisError::NoPoint)?;
        Ok((vals, row_degree(&degree_bounds(&self.ctx, &ids))))
    }
    /// Pad a field over the old `unknown ++ known` with `extra` new unknown
    /// components (inserted before the known ones).
    fn pad(&self, v: &[Id], extra: &[Id]) -> Vec<Id> {
        let nu = self.unknown.len();
        let mut out = v[..nu].to_vec();
        out.extend_from_slice(extra);
        out.extend_from_slice(&v[nu..]);
        out
    }
}

/// A codistribution: independent gradients at the point.
#[derive(Default)]
struct Cod {
    ech: Echelon,
    funcs: Vec<Id>,
    rows: Vec<Vec<Fp>>,
    deg_sum: u64,
}

impl Cod {
    /// Insert a row if independent (a rejection is wrong only at a root of
    /// a minor: its degree joins the error bound).
    fn insert(&mut self, st: &mut St, g: Vec<Fp>, d: u64) -> bool {
        if self.ech.insert(g.clone()) {
            self.rows.push(g);
            self.deg_sum = self.deg_sum.saturating_add(d);
            true
        } else {
            st.err_deg += self.deg_sum.saturating_add(d) as f64;
            false
        }
    }
    fn try_add(&mut self, st: &mut St, f: Id) -> Result<bool, AnalysisError> {
        let (g, d) = st.grad(f)?;
        let added = self.insert(st, g, d);
        if added {
            self.funcs.push(f);
        }
        Ok(added)
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Stop at the first generator moved by a residual field.
    Stop,
    /// Do not derive the generators moved by a residual field.
    Skip,
}

struct Growth {
    cod: Cod,
    rounds: usize,
    /// The root observable function and the round of the first generator
    /// moved by a residual field (mode `Stop`).
    found: Option<(Id, usize)>,
    /// The generators kept, as (index in `hobs`, word of fields).
    gens: Vec<(usize, Vec<usize>)>,
    /// With free roots, the codistribution's functions built (claims).
    syms: Vec<Id>,
}

/// The smallest codistribution containing `d hobs`, grown along `fields`
/// (the first is the drift: its Lie derivative is the time derivative),
/// with the residual-field test of `mode`. Lie derivatives along words are
/// evaluated with their gradients by `obsan-expr`'s F_p Taylor jets, never
/// built (the fields carry `nu`, and built derivatives of them swell).
fn grow(
    st: &mut St,
    fields: &[Vec<Id>],
    residual: &[Vec<Id>],
    mode: Mode,
) -> Result<Growth, AnalysisError> {
    let full = st.unknown.len();
    let nf_ = fields.len();
    let mut all_fields: Vec<Vec<Id>> = fields.to_vec();
    all_fields.extend(residual.iter().cloned());
    // The known coordinates' own components (`u^(l)' = u^(l+1)`) are the
    // jets' dynamics, counted by the word lengths instead.
    for f in &all_fields {
        st.built.extend_from_slice(&f[..full]);
    }
    st.built.extend_from_slice(&st.hobs.clone());
    let all = st.all();
    let jets = obsan_expr::lie::LieJets::new(&st.ctx, &all, &all_fields, &st.hobs);
    let mut cod = Cod::default();
    // (output, word, root output)
    let mut gens: Vec<(usize, Vec<usize>, usize)> = Vec::new();
    let row =
        |st: &mut St, out: usize, word: &[usize]| -> Result<(Fp, Vec<Fp>, u64), AnalysisError> {
            st.max_word = st.max_word.max(word.len());
            let r = jets
                .row(out, word, &st.point, true)
                .map_err(|_| AnalysisError::NoPoint)?;
            let mut g = r.gradient;
            g.truncate(full);
            // No bound: the top coefficient is structurally zero.
            Ok((r.value, g, r.degree.unwrap_or(0)))
        };
    // With free roots, each kept generator's function, built (claims).
    let mut syms: Vec<Id> = Vec::new();
    for o in 0..st.hobs.len() {
        let (_, g, d) = row(st, o, &[])?;
        if cod.insert(st, g, d) {
            gens.push((o, vec![], o));
            if st.claims.active {
                syms.push(st.hobs[o]);
            }
        }
    }
    let claim_rows = |st: &mut St, syms: &[Id]| {
        let cols = st.unknown.clone();
        st.claims.gradients(&mut st.ctx, syms, &cols, syms.len());
    };
    let mut old = 0;
    let mut rounds = 0;
    // At full rank nothing more is derived, but every generator is still
    // tested against the residual fields (a full-rank codistribution of
    // functions that an unknown input moves is not the observable one).
    while gens.len() > old {
        let new = gens.len();
        for i in old..new {
            st.check()?;
            let (out, word, root) = gens[i].clone();
            let mut moved = false;
            for k in 0..residual.len() {
                let mut w = word.clone();
                w.push(nf_ + k);
                if jets.support(out, &w).is_none() {
                    continue;
                }
                let (v, _, d) = row(st, out, &w)?;
                if v.is_zero() {
                    st.err_deg += d as f64;
                } else {
                    if st.claims.active {
                        let m = st.lie_claim(syms[i], &residual[k]);
                        st.claims.nonzero(m);
                    }
                    moved = true;
                    break;
                }
            }
            if moved {
                match mode {
                    Mode::Stop => {
                        claim_rows(st, &syms);
                        return Ok(Growth {
                            cod,
                            rounds,
                            found: Some((st.hobs[root], rounds)),
                            gens: vec![],
                            syms,
                        });
                    }
                    Mode::Skip => continue,
                }
            }
            for (f, field) in all_fields.iter().enumerate().take(nf_) {
                if cod.ech.rank() == full {
                    break;
                }
                let mut w = word.clone();
                w.push(f);
                if jets.support(out, &w).is_none() {
                    continue;
                }
                let (_, g, d) = row(st, out, &w)?;
                if cod.insert(st, g, d) {
                    gens.push((out, w, root));
                    if st.claims.active {
                        let m = st.lie_claim(syms[i], field);
                        syms.push(m);
                    }
                }
            }
        }
        old = new;
        rounds += 1;
    }
    claim_rows(st, &syms);
    Ok(Growth {
        cod,
        rounds,
        found: None,
        gens: gens.into_iter().map(|(o, w, _)| (o, w)).collect(),
        syms,
    })
}

/// Degree of reconstructability: the rank of `L_{g^k} hobs_i`, with the
/// chosen rows (`ht`) and columns (canonic inputs).
fn reconstructability(st: &mut St) -> Result<(Vec<Id>, Vec<usize>), AnalysisError> {
    let mw = st.g.len();
    let mut rows = Echelon::default();
    let mut picked = Vec::new();
    let mut picked_vals: Vec<Vec<Fp>> = Vec::new();
    let mut picked_ids: Vec<Vec<Id>> = Vec::new();
    let mut deg_sum = 0u64;
    for h in st.hobs.clone() {
        let ids: Vec<Id> = (0..mw)
            .map(|k| {
                let g = st.g[k].clone();
                st.lie(h, &g)
            })
            .collect();
        let vals = st
            .ctx
            .eval_fp(&ids, &st.point)
            .map_err(|_| AnalysisError::NoPoint)?;
        let d = row_degree(&degree_bounds(&st.ctx, &ids));
        if rows.insert(vals.clone()) {
            picked.push(h);
            picked_vals.push(vals);
            picked_ids.push(ids);
            deg_sum = deg_sum.saturating_add(d);
        } else {
            st.err_deg += deg_sum.saturating_add(d) as f64;
        }
    }
    // Columns: independent columns of the picked rows (full row rank, so
    // exactly `m` of them, proven by the non-zero minor).
    let mut cols = Echelon::default();
    let mut chosen = Vec::new();
    for k in 0..mw {
        let col: Vec<Fp> = picked_vals.iter().map(|r| r[k]).collect();
        if cols.insert(col) {
            chosen.push(k);
        }
    }
    // The chosen m x m minor is not zero (free roots: to be proven).
    let minor: Vec<Vec<Id>> = picked_ids
        .iter()
        .map(|r| chosen.iter().map(|&k| r[k]).collect())
        .collect();
    st.claims.rank(minor, chosen.len());
    Ok((picked, chosen))
}

/// `a^{-1}` as expressions (Gauss–Jordan, pivots where the value is
/// non-zero; the matrix is invertible, proven by its non-zero minor).
fn inverse(st: &mut St, a: &[Vec<Id>]) -> Result<Vec<Vec<Id>>, AnalysisError> {
    let m = a.len();
    let (zero, one) = (st.ctx.zero(), st.ctx.one());
    let mut e: Vec<Vec<Id>> = (0..m)
        .map(|i| {
            let mut r = a[i].clone();
            r.extend((0..m).map(|j| if i == j { one } else { zero }));
            r
        })
        .collect();
    let mut v: Vec<Vec<Fp>> = Vec::new();
    for r in &e {
        v.push(
            st.ctx
                .eval_fp(r, &st.point)
                .map_err(|_| AnalysisError::NoPoint)?,
        );
    }
    for c in 0..m {
        let Some(p) = (c..m).find(|&r| !v[r][c].is_zero()) else {
            return Err(AnalysisError::Invalid(
                "Martinelli's algorithm: the matrix mu is singular at the point".into(),
            ));
        };
        e.swap(c, p);
        v.swap(c, p);
        let piv = e[c][c];
        st.claims.nonzero(piv);
        let pinv = v[c][c].inv().ok_or(AnalysisError::NoPoint)?;
        for k in 0..2 * m {
            e[c][k] = st.ctx.div(e[c][k], piv);
            v[c][k] = v[c][k] * pinv;
        }
        for r in 0..m {
            if r == c || v[r][c].is_zero() && st.ctx.is_zero(e[r][c]) {
                continue;
            }
            let f = e[r][c];
            let fv = v[r][c];
            for k in 0..2 * m {
                let t = st.ctx.mul(&[f, e[c][k]]);
                e[r][k] = st.ctx.sub(e[r][k], t);
                v[r][k] = v[r][k] - fv * v[c][k];
            }
        }
    }
    Ok(e.into_iter().map(|r| r[m..].to_vec()).collect())
}

/// `sum_k coef_k * field_k`, componentwise.
fn combine(ctx: &mut Ctx, fields: &[&Vec<Id>], coefs: &[Id]) -> Vec<Id> {
    let len = fields.first().map_or(0, |f| f.len());
    (0..len)
        .map(|i| {
            let mut terms = Vec::new();
            for (f, &c) in fields.iter().zip(coefs) {
                if !ctx.is_zero(f[i]) {
                    terms.push(ctx.mul(&[c, f[i]]));
                }
            }
            ctx.add(&terms)
        })
        .collect()
}

/// The known-input jet symbols and their orders.
type KnownJets = Vec<(Id, usize)>;

fn setup(
    nf: &NormalForm,
    jets: usize,
    seed: u64,
    deadline: Option<Instant>,
) -> Result<(St, Option<KnownJets>), AnalysisError> {
    let mut ctx = nf.ctx.clone();
    let n = nf.state.len();
    let mw = nf.unknown_inputs.len();
    let zero = ctx.zero();
    let one = ctx.one();
    let mut unknown = nf.state_vars.clone();
    let through = feedthrough(&mut ctx, nf);
    let na = through.len();
    for &j in &through {
        unknown.push(nf.unknown_input_vars[j]);
    }
    // Known-input jets u^(0..=D); order 0 is the model's own symbol.
    let mut known = Vec::new();
    let mut kdrift = Vec::new();
    let mut top: Option<KnownJets> = None;
    for (u, &uv) in nf.inputs.iter().zip(&nf.input_vars) {
        let mut ids = vec![];
        for l in 0..=jets {
            let s = if l == 0 {
                ctx.symbol(u)
            } else {
                ctx.symbol(&format!("'{u}^({l})"))
            };
            debug_assert!(l > 0 || s.var == uv);
            known.push(s.var);
            ids.push(s.id);
            top.get_or_insert_with(Vec::new).push((s.id, l));
        }
        for l in 0..=jets {
            kdrift.push(if l < jets { ids[l + 1] } else { zero });
        }
    }
    let mut drift = Vec::new();
    for k in 0..n {
        let mut terms = vec![nf.f0[k]];
        for (i, f) in nf.fields.iter().enumerate() {
            let u = ctx.symbol(&nf.inputs[i]).id;
            terms.push(ctx.mul(&[f[k], u]));
        }
        for &j in &through {
            let w = ctx.symbol(&nf.unknown_inputs[j]).id;
            terms.push(ctx.mul(&[nf.unknown_fields[j][k], w]));
        }
        drift.push(ctx.add(&terms));
    }
    drift.extend(std::iter::repeat_n(zero, na));
    drift.extend(kdrift);
    let len = drift.len();
    // A feedthrough input is a state driven by a new unknown input (its
    // derivative); the others keep their fields.
    let g = (0..mw)
        .map(|j| match through.iter().position(|&k| k == j) {
            Some(a) => {
                let mut v = vec![zero; len];
                v[n + a] = one;
                v
            }
            None => {
                let mut v = nf.unknown_fields[j].clone();
                v.resize(len, zero);
                v
            }
        })
        .collect();
    let mut rng = SplitMix(seed ^ 0x3a27_1e11_5eed_0b5a);
    let (point, draws, free) = rank_point(&mut ctx, &mut rng, false)?;
    let st = St {
        ctx,
        unknown,
        known,
        drift,
        g,
        hobs: nf.outputs.iter().map(|o| o.1).collect(),
        point,
        rng,
        draws,
        err_deg: 0.0,
        built: Vec::new(),
        max_word: 0,
        deadline,
        free,
        claims: Claims {
            active: free,
            list: Vec::new(),
        },
        seed,
    };
    Ok((st, top))
}

/// The unknown inputs the outputs contain (direct feedthrough).
fn feedthrough(ctx: &mut Ctx, nf: &NormalForm) -> Vec<usize> {
    let outs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    let reach = ctx.reachable(&outs);
    (0..nf.unknown_inputs.len())
        .filter(|&j| reach.contains(&ctx.symbol(&nf.unknown_inputs[j]).id))
        .collect()
}

/// Martinelli's algorithm on a normal form with unknown inputs (module docs).
pub fn martinelli(
    nf: &NormalForm,
    seed: u64,
    deadline: Option<Instant>,
) -> Result<MartinelliReport, AnalysisError> {
    if nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "a delay and unknown inputs together are not supported by the rank test".into(),
        ));
    }
    let mut jets = nf.state.len() + 2;
    loop {
        let (r, used_top) = run(nf, jets, seed, deadline)?;
        if !used_top {
            return Ok(r);
        }
        if jets > 256 {
            return Err(AnalysisError::Invalid(format!(
                "Martinelli's algorithm: the known inputs' derivatives of order {jets} are still reached"
            )));
        }
        jets *= 2;
    }
}

fn run(
    nf: &NormalForm,
    jets: usize,
    seed: u64,
    deadline: Option<Instant>,
) -> Result<(MartinelliReport, bool), AnalysisError> {
    let mw = nf.unknown_inputs.len();
    let (mut st, top) = setup(nf, jets, seed, deadline)?;
    let mut steps = Vec::new();
    let mut last_m: Option<usize> = None;
    let mut iteration = 0usize;
    let growth = loop {
        st.check()?;
        // Keep the independent observable functions.
        let mut c = Cod::default();
        for h in st.hobs.clone() {
            c.try_add(&mut st, h)?;
        }
        let cols = st.unknown.clone();
        st.claims
            .gradients(&mut st.ctx, &c.funcs, &cols, c.funcs.len());
        st.hobs = c.funcs;
        let (ht, cols) = reconstructability(&mut st)?;
        let m = cols.len();
        if let Some(lm) = last_m {
            if m <= lm {
                return Err(AnalysisError::Invalid(format!(
                    "Martinelli's algorithm made no progress (degree of reconstructability stayed {m})"
                )));
            }
        }
        if iteration > mw + 1 {
            return Err(AnalysisError::Invalid(
                "Martinelli's algorithm: more iterations than unknown inputs".into(),
            ));
        }
        iteration += 1;
        let (ghat, g0, residual) = canonize(&mut st, &ht, &cols, mw)?;
        let mut fields = vec![g0.clone()];
        fields.extend(ghat.iter().cloned());
        if m == mw {
            steps.push(MartinelliStep {
                degree: m,
                action: "canonic".into(),
            });
            break grow(&mut st, &fields, &[], Mode::Stop)?;
        }
        let vanish = all_zero(&mut st, &residual)?;
        if vanish {
            steps.push(MartinelliStep {
                degree: m,
                action: "residual fields vanish".into(),
            });
            break grow(&mut st, &fields, &[], Mode::Stop)?;
        }
        let gr_found = grow(&mut st, &fields, &residual, Mode::Stop)?;
        let Some((theta, ord)) = gr_found.found else {
            steps.push(MartinelliStep {
                degree: m,
                action: "converged".into(),
            });
            break gr_found;
        };
        last_m = Some(m);
        if m == 0 {
            // Grow along the drift, not deriving the moved generators: the
            // first moved one (theta's order-ord derivative) joins hobs.
            let g2 = grow(&mut st, &fields[..1], &residual, Mode::Skip)?;
            let mut hobs = Vec::new();
            for (o, w) in g2.gens {
                let mut f = st.hobs[o];
                for _ in &w {
                    f = st.lie(f, &fields[0]);
                }
                hobs.push(f);
            }
            st.hobs = hobs;
            steps.push(MartinelliStep {
                degree: m,
                action: "growth along the drift".into(),
            });
            continue;
        }
        extend(&mut st, iteration, ord, theta, &ghat, &g0, &residual);
        st.redraw()?;
        steps.push(MartinelliStep {
            degree: m,
            action: format!("extension to order {ord}"),
        });
    };
    verdicts(st, nf, growth, steps, top, jets)
}
