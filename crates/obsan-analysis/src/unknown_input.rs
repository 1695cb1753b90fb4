//! Observability with unknown inputs: which states and params are
//! observable, and which unknown inputs are reconstructable and from which
//! derivative order of the outputs, when `S' = f0 + sum f_i u_i + sum g_j w_j`
//! with the `u_i` known and the `w_j` unmeasured.
//!
//! Route (docs/engine.md, "Unknown inputs"): the state is extended by the
//! jets of the unknown inputs and a clock `t` for the known inputs, `Z = (S,
//! w, ..., w^(M), t)`, each known input a polynomial in `t` of degree `M`
//! with random coefficients (its jets at the point are then random), and the
//! one drift `F = (f0 + sum f_i u_i(t) + sum g_j w_j, w', ..., w^(M), 0, 1)`.
//! Its Lie derivative `L_F^m h` is the time derivative `y^(m)`, a function of
//! `S`, `w, ..., w^(m)` and the known inputs' jets, so for `m <= M` it never
//! meets the truncation `w^(M+1) = 0`: the rows are exact. The observable codistribution `O_m` is the span of the
//! gradients of `y^(0..m)` with respect to the unknowns (`S` and the `w`
//! jets); the known inputs' jets are given numbers at the random point, never
//! columns. (Hermann–Krener's separation by the coefficients of each known
//! input is not valid here: the unknown input may depend on the known one,
//! and `y' = a(S, w') + b(S) u` says nothing of `b` when `w'` is free. The
//! 2DOF model of the suite shows it: splitting claims its `m2`.) This is the
//! extended-state route of FISPO / ORC-DF and of Martinelli (IEEE TAC 2019,
//! section 3) before his reduction.
//!
//! A state `x_i` is observable from derivatives up to order `m` iff
//! `dx_i` is in `O_m`; an unknown input `w_j` is reconstructable from order
//! `m` iff `dw_j` is in `O_m`. The x-part `O_m ∩ span(dS)` has dimension
//! `rank O_m - rank(projection of O_m on the w-columns)`.
//!
//! What is certified: every rank and membership is decided exactly in F_p,
//! `p = 2^61 - 1`, at random points (wrong with the stated Schwartz–Zippel
//! bound). A positive verdict (observable, reconstructable at order m) holds
//! for all orders. The negative verdicts are proven by Martinelli's
//! algorithm with its convergence criterion (arXiv 2201.07610, Algorithm
//! 5.1; `unknown_input_martinelli.rs`), run first: this route is then grown
//! (order doubled, up to `2 (n + m_w) + 4`) until it finds every variable
//! that algorithm finds observable, for the orders, and the report says
//! whether the two routes agree. (`converged` still says whether this growth
//! itself stopped: every state and input found, or a level added nothing,
//! `O` then invariant under `F` and the `f_i` in the whole jet space.)

use crate::rank::{rank_point, AnalysisError, Echelon, Fields, LieWord};
use crate::unknown_input_martinelli::{martinelli, MartinelliReport};
use crate::unknown_input_roots::{prove, Claims};
use obsan_expr::{evaluate::FpPoint, lie::LieJets, Ctx, Fp, Id, SplitMix, Var, P};
use obsan_model::NormalForm;
use std::collections::HashMap;
use std::time::Instant;

/// Options of the unknown-input rank test.
pub struct UnknownInputOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Highest derivative order of the outputs examined; `None`: `n + 1`
    /// (`n` the analysed state's dimension), enough for any relative degree.
    pub max_order: Option<usize>,
}

impl Default for UnknownInputOptions {
    fn default() -> Self {
        UnknownInputOptions {
            seed: 1,
            deadline: None,
            max_order: None,
        }
    }
}

/// One derivative order of the growth.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OrderStep {
    pub order: usize,
    /// Rank of `O_m` in the extended space (state and unknown-input jets).
    pub rank: usize,
    /// Dimension of its x-part `O_m ∩ span(dS)`: the observable
    /// codistribution of the original state.
    pub state_rank: usize,
}

/// The result of the unknown-input rank test.
#[derive(Clone, Debug)]
pub struct UnknownInputReport {
    /// Dimension of the analysed state (states then params).
    pub n: usize,
    /// Dimension of the observable codistribution in the state (the x-part).
    pub rank: usize,
    /// Per state variable: the lowest output derivative order from which it
    /// is observable, `None` if not up to `max_order`.
    pub observable: Vec<Option<usize>>,
    /// Per unknown input: the lowest output derivative order from which it
    /// is reconstructable, `None` if not up to `max_order`.
    pub reconstructable: Vec<Option<usize>>,
    /// The growth, order by order.
    pub steps: Vec<OrderStep>,
    /// The highest order examined.
    pub max_order: usize,
    /// `true` when the extended-state growth itself converged (see module
    /// docs); the verdicts are proven by `martinelli` in any case.
    pub converged: bool,
    /// Martinelli's algorithm: the proven verdicts and stopping point.
    pub martinelli: MartinelliReport,
    /// Both routes give the same verdicts: every variable Martinelli's
    /// algorithm finds observable (input reconstructable) was found by the
    /// extended-state route, at the order reported, and no other.
    pub agree: bool,
    /// Lie derivatives along the extended fields whose gradients form a
    /// basis of `O` at the highest order reached.
    pub basis: Vec<LieWord>,
    /// Names of the extended fields (`f0` then the known inputs).
    pub fields: Vec<String>,
    /// How many Lie derivatives were evaluated.
    pub evaluated: usize,
    pub degree_bound: u64,
    /// Probability that some verdict is wrong (union over the two points).
    pub error_bound: f64,
    pub seed: u64,
    /// Degree `k` of the field `F_(p^k)` where the decisions taken at free
    /// root values were proven (unknown_input_roots.rs), when no point mod p
    /// satisfies the roots' relations; `None` otherwise.
    pub roots_field: Option<u32>,
}

impl UnknownInputReport {
    /// Every state observable and every unknown input reconstructable.
    pub fn complete(&self) -> bool {
        self.observable.iter().all(Option::is_some)
            && self.reconstructable.iter().all(Option::is_some)
    }
}

/// The extended system: its context (with the jet symbols), coordinates and
/// fields.
pub(crate) struct Extended {
    pub(crate) ctx: Ctx,
    pub(crate) vars: Vec<Var>,
    pub(crate) fields: Fields,
    pub(crate) outputs: Vec<Id>,
    /// Column of `w_j` (order 0) in the extended state.
    w_cols: Vec<usize>,
    /// First column of the unknown-input jets.
    first_w: usize,
    /// Columns before this one are unknowns (state and unknown-input jets);
    /// the clock of the known inputs follows, known, so never part of a row.
    pub(crate) unknown_cols: usize,
}

pub(crate) fn extend(nf: &NormalForm, order: usize) -> Extended {
    let mut ctx = nf.ctx.clone();
    let n = nf.state.len();
    let nw = nf.unknown_inputs.len();
    let mut vars = nf.state_vars.clone();
    // jets(names)[l][j] = the l-th derivative of input j; names with a quote
    // cannot clash with a user name, and order 0 is the model's own symbol
    // (`symbol` returns it).
    let jets = |ctx: &mut Ctx, names: &[String], vars: &mut Vec<Var>| {
        let mut all: Vec<Vec<Id>> = Vec::new();
        for l in 0..=order + 1 {
            let mut lev = Vec::new();
            for w in names {
                let s = ctx.symbol(&format!("{w}{}", "'".repeat(l)));
                if l <= order {
                    vars.push(s.var);
                }
                lev.push(s.id);
            }
            all.push(lev);
        }
        all
    };
    let wj = jets(&mut ctx, &nf.unknown_inputs, &mut vars);
    let first_u = vars.len();
    // The known inputs: u_i = sum_l c_il t^l (l <= order) along a clock
    // t' = 1, the c_il random at the point. At a point t0 their jets
    // u_i^(l)(t0) are an invertible (triangular, diagonal l!) linear image of
    // the c_il, so they are as random as independent jets, for one extra
    // column instead of one per input and order.
    let zero = ctx.int(0);
    let one = ctx.int(1);
    let mut u_of_t = Vec::new();
    if !nf.inputs.is_empty() {
        let t = ctx.symbol("'t");
        vars.push(t.var);
        for u in &nf.inputs {
            let mut terms = Vec::new();
            for l in 0..=order {
                let c = ctx.symbol(&format!("'{u}_c{l}")).id;
                let tl = ctx.pow(t.id, l as i64);
                terms.push(ctx.mul(&[c, tl]));
            }
            u_of_t.push(ctx.add(&terms));
        }
    }
    let mut f0 = Vec::with_capacity(vars.len());
    for k in 0..n {
        let mut terms = vec![nf.f0[k]];
        for (i, f) in nf.fields.iter().enumerate() {
            let t = ctx.mul(&[f[k], u_of_t[i]]);
            terms.push(t);
        }
        for (g, &w) in nf.unknown_fields.iter().zip(&wj[0]) {
            let t = ctx.mul(&[g[k], w]);
            terms.push(t);
        }
        f0.push(ctx.add(&terms));
    }
    // Unknown-input jets: w^(l)' = w^(l+1); the last one's derivative is
    // never reached at orders <= `order` (module docs), so it is set to 0.
    for l in 0..=order {
        if l < order {
            f0.extend_from_slice(&wj[l + 1]);
        } else {
            f0.extend(std::iter::repeat_n(zero, nw));
        }
    }
    if !nf.inputs.is_empty() {
        f0.push(one);
    }
    Extended {
        ctx,
        vars,
        fields: Fields {
            names: vec!["f0".to_string()],
            vectors: vec![f0],
        },
        outputs: nf.outputs.iter().map(|o| o.1).collect(),
        w_cols: (0..nw).map(|j| n + j).collect(),
        first_w: n,
        unknown_cols: first_u,
    }
}

/// One run of the growth at one point.
struct Run {
    steps: Vec<OrderStep>,
    observable: Vec<Option<usize>>,
    reconstructable: Vec<Option<usize>>,
    basis: Vec<LieWord>,
    evaluated: usize,
    degree: u64,
    worst_rejected: u64,
    converged: bool,
}

fn unit_in(e: &Echelon, len: usize, col: usize) -> bool {
    let mut v = vec![Fp::ZERO; len];
    v[col] = Fp::ONE;
    e.reduce(v).iter().all(|x| x.is_zero())
}

#[allow(clippy::too_many_arguments)]
fn grow(
    ext: &Extended,
    jets: &LieJets,
    degrees: &mut HashMap<(usize, Vec<usize>), u64>,
    point: &FpPoint,
    n: usize,
    max_order: usize,
    opts: &UnknownInputOptions,
) -> Result<Run, AnalysisError> {
    let len = ext.unknown_cols;
    let nw = ext.w_cols.len();
    let mut run = Run {
        steps: vec![],
        observable: vec![None; n],
        reconstructable: vec![None; nw],
        basis: vec![],
        evaluated: 0,
        degree: 0,
        worst_rejected: 0,
        converged: false,
    };
    let mut echelon = Echelon::default();
    // Projections of the basis rows on the unknown-input columns.
    let mut w_part = Echelon::default();
    let mut level: Vec<LieWord> = (0..ext.outputs.len())
        .map(|output| LieWord {
            output,
            fields: vec![],
        })
        .collect();
    for order in 0..=max_order {
        let mut kept = Vec::new();
        for word in level {
            if obsan_expr::cancel_requested() {
                return Err(AnalysisError::Cancelled);
            }
            if let Some(d) = opts.deadline {
                if Instant::now() > d {
                    return Err(AnalysisError::Timeout(format!(
                        "at output derivative order {order}, extended rank {} so far",
                        echelon.rank()
                    )));
                }
            }
            let key = (word.output, word.fields.clone());
            let known = degrees.get(&key).copied();
            let row = jets
                .row(word.output, &word.fields, point, known.is_none())
                .map_err(|_| AnalysisError::NoPoint)?;
            let degree = known.or(row.degree).unwrap_or(0);
            degrees.insert(key, degree);
            run.evaluated += 1;
            let mut g = row.gradient;
            g.truncate(len);
            let wp: Vec<Fp> = g[ext.first_w..].to_vec();
            if echelon.insert(g) {
                w_part.insert(wp);
                run.degree = run.degree.saturating_add(degree);
                kept.push(word.clone());
                run.basis.push(word);
            } else {
                run.worst_rejected = run.worst_rejected.max(degree);
            }
        }
        for (i, o) in run.observable.iter_mut().enumerate() {
            if o.is_none() && unit_in(&echelon, len, i) {
                *o = Some(order);
            }
        }
        for (j, r) in run.reconstructable.iter_mut().enumerate() {
            if r.is_none() && unit_in(&echelon, len, ext.w_cols[j]) {
                *r = Some(order);
            }
        }
        run.steps.push(OrderStep {
            order,
            rank: echelon.rank(),
            state_rank: echelon.rank() - w_part.rank(),
        });
        let complete = run.observable.iter().all(Option::is_some)
            && run.reconstructable.iter().all(Option::is_some);
        // Nothing new at this order: O is invariant under every field of the
        // (untruncated) jet system, so no higher order adds anything.
        if complete || kept.is_empty() {
            run.converged = true;
            break;
        }
        let mut next = Vec::new();
        for w in &kept {
            for k in 0..ext.fields.vectors.len() {
                let mut f = w.fields.clone();
                f.push(k);
                if jets.support(w.output, &f).is_some() {
                    next.push(LieWord {
                        output: w.output,
                        fields: f,
                    });
                }
            }
        }
        level = next;
    }
    Ok(run)
}

/// The unknown-input rank test of a normal form with unknown inputs (module
/// docs): Martinelli's algorithm for the proven verdicts, and the
/// extended-state route, grown until it finds them, for the derivative order
/// of each (by default; `max_order` fixes the order instead).
pub fn unknown_input_rank(
    nf: &NormalForm,
    opts: UnknownInputOptions,
) -> Result<UnknownInputReport, AnalysisError> {
    let mart = martinelli(nf, opts.seed, opts.deadline)?;
    let n = nf.state.len();
    let nw = nf.unknown_inputs.len();
    let cap = opts.max_order.unwrap_or(2 * (n + nw) + 4);
    let mut order = opts.max_order.unwrap_or(n + 1).min(cap);
    loop {
        let ext = extended_route(nf, &opts, order)?;
        let agree = ext
            .observable
            .iter()
            .zip(&mart.observable)
            .all(|(x, &y)| x.is_some() == y)
            && ext
                .reconstructable
                .iter()
                .zip(&mart.reconstructable)
                .all(|(x, y)| y.is_none_or(|y| x.is_some() == y));
        if agree || ext.converged || order >= cap || opts.max_order.is_some() {
            return Ok(UnknownInputReport {
                n,
                rank: mart.rank,
                observable: ext.observable,
                reconstructable: ext.reconstructable,
                steps: ext.steps,
                max_order: ext.max_order,
                converged: ext.converged,
                agree,
                basis: ext.basis,
                fields: ext.fields,
                evaluated: ext.evaluated,
                degree_bound: ext.degree_bound,
                error_bound: (ext.error_bound + mart.error_bound).min(1.0),
                seed: opts.seed,
                roots_field: ext.roots_field.or(mart.roots_field),
                martinelli: mart,
            });
        }
        order = (2 * order).min(cap);
    }
}

/// The extended-state route's part of the report.
struct ExtReport {
    observable: Vec<Option<usize>>,
    reconstructable: Vec<Option<usize>>,
    steps: Vec<OrderStep>,
    max_order: usize,
    converged: bool,
    basis: Vec<LieWord>,
    fields: Vec<String>,
    evaluated: usize,
    degree_bound: u64,
    error_bound: f64,
    roots_field: Option<u32>,
}

/// The extended-state route up to output derivative order `max_order`, by
/// two runs at independent random points of F_p.
fn extended_route(
    nf: &NormalForm,
    opts: &UnknownInputOptions,
    max_order: usize,
) -> Result<ExtReport, AnalysisError> {
    if nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "a delay and unknown inputs together are not supported by the rank test".into(),
        ));
    }
    let n = nf.state.len();
    let mut ext = extend(nf, max_order);
    let jets = LieJets::new(&ext.ctx, &ext.vars, &ext.fields.vectors, &ext.outputs);
    let mut rng = SplitMix(opts.seed ^ 0x0b5a_5e1f_0b5a_5e1f);
    let mut degrees = HashMap::new();
    let (p1, k1, free) = rank_point(&mut ext.ctx, &mut rng, false)?;
    let r1 = grow(&ext, &jets, &mut degrees, &p1, n, max_order, opts)?;
    let (p2, k2, _) = rank_point(&mut ext.ctx, &mut rng, free)?;
    let r2 = grow(&ext, &jets, &mut degrees, &p2, n, max_order, opts)?;
    // The run with the larger ranks (lexicographically by order): ranks at a
    // point are never above the generic ones.
    let key = |r: &Run| r.steps.iter().map(|s| s.rank).collect::<Vec<_>>();
    let best = if key(&r2) > key(&r1) { r2 } else { r1 };
    let roots_field = if free {
        let claims = growth_claims(&mut ext, &best, n);
        Some(prove(&mut ext.ctx, &claims, opts.seed)?)
    } else {
        None
    };
    let draws = k1.max(k2) as f64;
    let degree_bound = best.degree.saturating_add(best.worst_rejected).max(1);
    let per_point = (degree_bound as f64 * draws / P as f64).min(1.0);
    Ok(ExtReport {
        observable: best.observable,
        reconstructable: best.reconstructable,
        max_order: best.steps.last().map_or(0, |s| s.order),
        converged: best.converged,
        basis: best.basis,
        fields: ext.fields.names.clone(),
        evaluated: best.evaluated,
        degree_bound,
        error_bound: (2.0 * per_point).min(1.0),
        steps: best.steps,
        roots_field,
    })
}

/// What a growth at free root values decided that a true point must confirm
/// (unknown_input_roots.rs): order by order, the rank of the basis rows so
/// far and of their projection on the unknown-input columns, and for each
/// variable and input not yet in the span at an order, that it is not
/// (its unit row raises the rank). Memberships, rejected rows and the
/// growth's end are dependences, which carry over.
fn growth_claims(ext: &mut Extended, run: &Run, n: usize) -> Claims {
    let mut claims = Claims {
        active: true,
        list: Vec::new(),
    };
    let len = ext.unknown_cols;
    let cols: Vec<Var> = ext.vars[..len].to_vec();
    let (zero, one) = (ext.ctx.zero(), ext.ctx.one());
    // The basis functions y^(m), built along the one drift.
    let drift = ext.fields.vectors[0].clone();
    let mut funcs: Vec<(usize, Id)> = Vec::new();
    for w in &run.basis {
        let mut f = ext.outputs[w.output];
        for _ in &w.fields {
            f = ext.ctx.lie_derivative(f, &ext.vars, &drift);
        }
        funcs.push((w.order(), f));
    }
    let unit =
        |c: usize| -> Vec<Id> { (0..len).map(|i| if i == c { one } else { zero }).collect() };
    for s in &run.steps {
        let upto: Vec<Id> = funcs
            .iter()
            .filter(|(o, _)| *o <= s.order)
            .map(|p| p.1)
            .collect();
        let rows: Vec<Vec<Id>> = upto
            .iter()
            .map(|&f| cols.iter().map(|&v| ext.ctx.diff(f, v)).collect())
            .collect();
        claims.rank(rows.clone(), s.rank);
        let wrows: Vec<Vec<Id>> = rows.iter().map(|r| r[ext.first_w..].to_vec()).collect();
        claims.rank(wrows, s.rank - s.state_rank);
        let outside = |first: &Option<usize>| first.is_none_or(|m| m > s.order);
        let mut units: Vec<usize> = (0..n).filter(|&i| outside(&run.observable[i])).collect();
        units.extend(
            ext.w_cols
                .iter()
                .zip(&run.reconstructable)
                .filter(|(_, r)| outside(r))
                .map(|(&c, _)| c),
        );
        for c in units {
            let mut with = rows.clone();
            with.push(unit(c));
            claims.rank(with, s.rank + 1);
        }
    }
    claims
}
