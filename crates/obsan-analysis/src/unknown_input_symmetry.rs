//! Continuous symmetries of a system with unknown inputs (docs/engine.md,
//! "Symmetries with unknown inputs").
//!
//! The system is `S' = f0 + sum f_i u_i + sum g_j w_j`, `y = h(S)`, with the
//! `w_j` unmeasured. Its observable codistribution `Omega` (Martinelli's, the
//! x-part of the extended-state codistribution, computed by
//! [`unknown_input_rank`]) has rank `r`; its kernel has dimension `k = n - r`.
//!
//! **Candidates.** At a point of `S` (the unknown-input jets, the clock and
//! the known inputs' coefficients fixed at random values), the rows of the
//! extended codistribution give `Omega` as the annihilator of the projection
//! on the S-columns of their kernel; the kernel vector with a 1 on free column
//! `j` and 0 on the other free columns is a rational function of the point,
//! which `obsan_recon` reconstructs (as the known-input route does).
//!
//! **Certificate (exact).** A candidate basis `xi_1..xi_k` is accepted only
//! if, in canonical form (the half-angle view for trig):
//! (a) `L_xi h = 0` for every output, and
//! (b) `[f, xi_a]` lies in `span(xi_1..xi_k, g_1..g_m)` over the rational
//! functions, for every `f` among `f0`, the `f_i` and the `g_j`.
//! Then every `xi` in `Delta = span(xi)` is an unobservable direction for
//! every unknown input: along a trajectory with input `w(t)`, the variation
//! `dS = sum c_a(t) xi_a(S(t))` satisfies the linearised dynamics with the
//! input variation `dw = sum c_a beta_a` when the `c_a` solve the linear ODE
//! `c' = -A^T c` given by `[F, xi_a] = sum_b A_ab xi_b + sum_j beta_aj g_j`
//! (`F` the field with the inputs' values: (b) holds for it since the
//! inputs do not depend on S), and it leaves `y` unchanged by (a). So no
//! function of the outputs and known inputs separates `S` from `S + eps xi`
//! to first order, and `dphi . xi = 0` for every `dphi` in `Omega`: the rank
//! is at most `n - k` and each variable a `xi` moves is unobservable, exactly.
//! That the rank is at least `n - k` (the variables no `xi` moves are
//! observable) is the rank test's verdict, with its probability bound.
//! A candidate failing (b) is reported as such: the lost directions then
//! depend on the input's history and have no certificate of this form.
//!
//! **Directions that move with the inputs.** The kernel may depend on the
//! fixed values (CSTR: `y' = delta1 qc (u3 - Tc) + 3 (Tr - Tc)` loses
//! `xi_Tr = -qc (u3 - Tc)/3 xi_delta1`); the black box is then no function of
//! the state alone. At the first random point, `Omega` is recomputed with (b)
//! the unknown inputs' jets, then (a) the known inputs' coefficients and
//! clock, redrawn (unknown_input_jets.rs). If (b) moves it, the command
//! refuses: no field on the state spans the kernel. If (a) moves it, the
//! known inputs' jets `u_i^(l)` (clock at `t = 0`, so `c_il = u_i^(l)/l!`)
//! are coordinates of the reconstruction too, printed `u`, `u'`, `u''`, and
//! the certificate is, with `F = f0 + sum f_i u_i` (inputs as symbols) and
//! `d_t xi = sum_{i,l} u_i^(l+1) d xi / d u_i^(l)`:
//! (a) `L_xi h = 0` per output, and (b') `[F, xi_a] + d_t xi_a` and
//! `[g_j, xi_a]` in `span(xi, g)` over the rational functions of the state
//! and the jets. Proof: along a trajectory with inputs `u(t)`, `w(t)`, put
//! `X_a(t, S) = xi_a(S, u(t), u'(t), ...)`, so `d/dt X_a(t, S(t)) = d_t xi_a
//! + D xi_a . S'`. For `dS = sum c_a X_a`, `dS' - D(F + G w) dS = sum c_a' X_a
//! + c_a ([F, xi_a] + d_t xi_a + sum_j w_j [g_j, xi_a])` (`w` does not depend
//! on S), which by (b') is `sum_a (c_a' + sum_b c_b M_ba) X_a + G dw` with `M`
//! the span coefficients and `dw` their `g` part: `c' = -M^T c` (a linear ODE
//! whose coefficients are known functions of time) makes `dS` solve the
//! linearised dynamics with the input variation `dw`, and (a) keeps `y`. As
//! above, every variable a vector moves is unobservable, for every unknown
//! input and the known one applied. (b') is an identity in the jets, so it
//! holds for every input; the jet `u^(L+1)` it introduces is a symbol.

use crate::rank::AnalysisError;
use crate::unknown_input::{extend, unknown_input_rank, UnknownInputOptions, UnknownInputReport};
use crate::unknown_input_jets::{
    at_jets, classify, drift_with_inputs, jet_coords, jet_name, redraw, time_derivative,
    unknown_history, used_jets, Fixed, Span,
};
use obsan_expr::{
    lie::Coord, lie::LieJets, Ctx, Fp, Id, Mono, Poly, RatFun, SplitMix, TanHalf, Var, P,
};
use obsan_model::NormalForm;
use obsan_recon::{reconstruct_vec, Limit, Options, ReconError};
use std::time::Instant;

/// Symmetries of a system with unknown inputs, with their exact certificate.
#[derive(Clone, Debug)]
pub struct UnknownInputSymmetries {
    /// The rank test (its verdicts and bound).
    pub report: UnknownInputReport,
    /// A basis of the kernel of the observable codistribution, each vector
    /// with a 1 on its free column and 0 on the other free columns.
    pub vectors: Vec<Vec<RatFun>>,
    /// The free column of each vector.
    pub free: Vec<usize>,
    /// Identities checked exactly: `L_xi h = 0` per output and vector, and
    /// one span membership per field and vector.
    pub identities: usize,
    /// The unknown inputs an output holds (direct feedthrough): the
    /// certificate is that of the system with them made states
    /// (unknown_input_feedthrough.rs). Empty otherwise.
    pub made_states: Vec<String>,
    /// The known inputs' jets `(input, order)` the vectors depend on (their
    /// symbols `u`, `u'`, `u''`, ...); empty when the symmetries do not move
    /// with the known inputs.
    pub input_jets: Vec<(usize, usize)>,
}

impl UnknownInputSymmetries {
    /// The vectors depend on the known inputs' values (module docs).
    pub fn input_dependent(&self) -> bool {
        !self.input_jets.is_empty()
    }
}

/// `unknown_input_symmetries` (unknown_input_feedthrough.rs) of a system
/// whose outputs are functions of
/// the state.
pub(crate) fn symmetries_without_feedthrough(
    nf: &mut NormalForm,
    opts: UnknownInputOptions,
) -> Result<UnknownInputSymmetries, AnalysisError> {
    let deadline = opts.deadline;
    let seed = opts.seed;
    let report = unknown_input_rank(nf, opts)?;
    if !report.agree {
        return Err(AnalysisError::Invalid(
            "the two unknown-input rank routes disagree (see `obsan rank`): no kernel to certify"
                .into(),
        ));
    }
    let n = report.n;
    let r = report.rank;
    let (vectors, free, input_jets) = if r == n {
        (vec![], vec![], vec![])
    } else if report.observable.iter().filter(|o| o.is_some()).count() == r {
        // The observable variables alone span the codistribution (r of them
        // independent, rank r): its kernel is spanned by the unit vectors of
        // the others, with no reconstruction (which needs points mod p: the
        // BIG model's roots have none). Nothing observable is the case r = 0.
        let lost: Vec<usize> = (0..n).filter(|&j| report.observable[j].is_none()).collect();
        let units = lost
            .iter()
            .map(|&j| {
                (0..n)
                    .map(|i| {
                        if i == j {
                            RatFun::one()
                        } else {
                            RatFun::zero()
                        }
                    })
                    .collect()
            })
            .collect();
        (units, lost, vec![])
    } else {
        candidates(nf, &report, seed, deadline)?
    };
    let identities = certify(nf, &vectors, &input_jets)?;
    Ok(UnknownInputSymmetries {
        report,
        vectors,
        free,
        identities,
        made_states: Vec::new(),
        input_jets,
    })
}

/// The rows of `Omega` (x-part) at one point of the extended space: the
/// annihilator in S-space of the S-projection of the extended kernel.
fn state_rows(ext_rows: &[Vec<Fp>], len: usize, n: usize) -> Vec<Vec<Fp>> {
    let ker = Fp::null_space(ext_rows.to_vec(), len);
    let proj: Vec<Vec<Fp>> = ker.iter().map(|v| v[..n].to_vec()).collect();
    Fp::null_space(proj, n)
}

/// The candidate vectors, their free columns and the known inputs' jets
/// `(input, order)` they depend on.
type Candidates = (Vec<Vec<RatFun>>, Vec<usize>, Vec<(usize, usize)>);

/// Candidate kernel vectors by reconstruction (module docs).
fn candidates(
    nf: &mut NormalForm,
    report: &UnknownInputReport,
    seed: u64,
    deadline: Option<Instant>,
) -> Result<Candidates, AnalysisError> {
    let n = report.n;
    let r = report.rank;
    // The first order whose state part has the final rank: its rows span
    // Omega already, and the jets up to it are exact in a system truncated
    // there (unknown_input.rs), much cheaper than the order the growth went on to.
    let m0 = report
        .steps
        .iter()
        .find(|s| s.state_rank == r)
        .map_or(report.max_order, |s| s.order);
    let ext = extend(nf, m0);
    let len = ext.unknown_cols;
    let jets = LieJets::new(&ext.ctx, &ext.vars, &ext.fields.vectors, &ext.outputs);
    // Each output's basis words are y^(0..=m): one jet gives all prefixes.
    let mut tops: Vec<usize> = vec![0; ext.outputs.len()];
    let mut used = vec![false; ext.outputs.len()];
    for w in report.basis.iter().filter(|w| w.order() <= m0) {
        used[w.output] = true;
        tops[w.output] = tops[w.output].max(w.order());
    }
    let mut nf_roots: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    nf_roots.extend(nf.f0.iter().copied());
    for f in nf.fields.iter().chain(&nf.unknown_fields) {
        nf_roots.extend(f.iter().copied());
    }
    let unsupported = || {
        AnalysisError::Invalid(
            "symmetries with unknown inputs: a square root in the system is not supported".into(),
        )
    };
    let xcoords = nf.ctx.free_coords(&nf_roots, &[]).ok_or_else(unsupported)?;
    let mut ext_roots = ext.outputs.clone();
    ext_roots.extend(ext.fields.vectors[0].iter().copied());
    let all = ext
        .ctx
        .free_coords(&ext_roots, &[])
        .ok_or_else(unsupported)?;
    let extra: Vec<Coord> = all.into_iter().filter(|c| !xcoords.contains(c)).collect();
    let kinds = classify(&ext.ctx, &nf.inputs, m0, &extra);
    let mut rng = SplitMix(seed ^ 0x51e0_7a11_c0de_0033);
    let fixed: Vec<Fp> = extra.iter().map(|_| rng.fp()).collect();
    let coords: Vec<Coord> = xcoords.iter().chain(&extra).cloned().collect();
    let rows_at = |ctx: &Ctx, x: &[Fp], fixed: &[Fp]| -> Option<Vec<Vec<Fp>>> {
        let vals: Vec<Fp> = x.iter().chain(fixed).copied().collect();
        let pt = ctx.fp_point_at(&coords, &vals).ok()?;
        let mut rows = Vec::new();
        for (o, &m) in tops.iter().enumerate() {
            if !used[o] {
                continue;
            }
            let rs = jets.prefix_rows(o, &vec![0; m], &pt).ok()?;
            rows.extend(rs.into_iter().map(|mut r| {
                r.gradient.truncate(len);
                r.gradient
            }));
        }
        let s = state_rows(&rows, len, n);
        (Fp::matrix_rank(s.clone()) == r).then_some(s)
    };
    // Pivots from the last column back at a random point, so that the free
    // columns are the earliest unobservable variables.
    let x0: Vec<Fp> = xcoords.iter().map(|_| rng.fp()).collect();
    let s0 = rows_at(&ext.ctx, &x0, &fixed).ok_or(AnalysisError::NoPoint)?;
    // Does Omega at x0 move when the unknown inputs' jets, then the known
    // inputs' coefficients and clock, are redrawn? (Same rank r: equal iff
    // the stacked rows keep rank r.) A wrong "no" (probability of a zero of
    // a minor) only sends the reconstruction on as before, where it fails.
    let moves = |s: Option<Vec<Vec<Fp>>>| {
        s.is_some_and(|s| Fp::matrix_rank(s0.iter().cloned().chain(s).collect()) != r)
    };
    let unknown = redraw(&fixed, &kinds, |k| k == Fixed::Unknown, || rng.fp());
    if moves(rows_at(&ext.ctx, &x0, &unknown)) {
        return Err(unknown_history(&nf.unknown_inputs));
    }
    let known = redraw(&fixed, &kinds, |k| k != Fixed::Unknown, || rng.fp());
    // The known inputs' jets become coordinates of the black box (clock at 0).
    let ujets = if moves(rows_at(&ext.ctx, &x0, &known)) {
        jet_coords(&kinds)
    } else {
        Vec::new()
    };
    let nx = xcoords.len();
    let mut piv: Vec<usize> = Vec::new();
    for c in (0..n).rev() {
        let mut t = piv.clone();
        t.push(c);
        let sub: Vec<Vec<Fp>> = s0
            .iter()
            .map(|row| t.iter().map(|&j| row[j]).collect())
            .collect();
        if Fp::matrix_rank(sub) == t.len() {
            piv = t;
        }
        if piv.len() == r {
            break;
        }
    }
    piv.sort_unstable();
    let free: Vec<usize> = (0..n).filter(|j| !piv.contains(j)).collect();
    let order: Vec<usize> = piv.iter().chain(&free).copied().collect();
    let k = free.len();
    let ctx = &ext.ctx;
    let mut bb = |x: &[u64], p: u64| -> Result<Option<Vec<u64>>, String> {
        if p != P {
            return Err(format!("internal: the black box works modulo {P} only"));
        }
        if obsan_expr::cancel_requested() {
            return Err("interrupted".into());
        }
        let vals: Vec<Fp> = x.iter().map(|&v| Fp::new(v)).collect();
        let s = if ujets.is_empty() {
            rows_at(ctx, &vals, &fixed)
        } else {
            let f = at_jets(&fixed, &kinds, &ujets, &vals[nx..]);
            rows_at(ctx, &vals[..nx], &f)
        };
        let Some(s) = s else {
            return Ok(None);
        };
        // Columns reordered pivots first: the echelon kernel then has its
        // unit entries on the free columns.
        let sp: Vec<Vec<Fp>> = s
            .iter()
            .map(|row| order.iter().map(|&j| row[j]).collect())
            .collect();
        let ker = Fp::null_space(sp, n);
        if ker.len() != k || ker.iter().enumerate().any(|(j, v)| v[r + j] != Fp::ONE) {
            return Ok(None);
        }
        Ok(Some(
            ker.iter()
                .flat_map(|v| v[..r].iter().map(|f| f.0))
                .collect(),
        ))
    };
    // One agreeing value ends an interpolation (as sym_recon.rs): a premature
    // stop gives a wrong candidate, which the exact certificate rejects.
    let opts = Options {
        primes: Some(vec![P]),
        agree: 1,
        deadline,
        seed: seed ^ 0x0b5a_0033,
        ..Options::default()
    };
    let rec = match reconstruct_vec(nx + ujets.len(), k * r, &mut bb, &opts) {
        Ok(x) => x,
        Err(_) if obsan_expr::cancel_requested() => return Err(AnalysisError::Cancelled),
        // Only the deadline is a timeout; a degree, term, point or prime
        // budget is a limit of the reconstruction, said as such.
        Err(
            e @ ReconError::Budget {
                limit: Limit::Deadline,
                ..
            },
        ) => {
            return Err(AnalysisError::Timeout(format!(
                "reconstructing the symmetries with unknown inputs: {e}"
            )))
        }
        Err(e) => {
            return Err(AnalysisError::Invalid(format!(
                "reconstructing the symmetries with unknown inputs: {e}"
            )))
        }
    };
    // The coordinates are nf's own leaves (the extended context is a clone
    // with the jets appended), so the forms are built in nf's context; the
    // known inputs' jets get their symbols there (`u`, `u'`, ...).
    let mut vcoords = xcoords.clone();
    for &(i, l) in &ujets {
        let v = nf.ctx.symbol(&jet_name(&nf.inputs[i], l)).var;
        vcoords.push(Coord::Leaf(v));
    }
    let th = nf.ctx.tan_half();
    let vectors = to_vectors(&mut nf.ctx, &th, &vcoords, &rec.functions, &piv, &free, n)?;
    let input_jets = used_jets(&mut nf.ctx, &nf.inputs, &ujets, &vectors);
    Ok((vectors, free, input_jets))
}

/// The reconstructed entries as canonical forms in sin/cos.
fn to_vectors(
    ctx: &mut Ctx,
    th: &TanHalf,
    coords: &[Coord],
    functions: &[obsan_recon::Rational],
    piv: &[usize],
    free: &[usize],
    n: usize,
) -> Result<Vec<Vec<RatFun>>, AnalysisError> {
    let r = piv.len();
    let to_poly = |p: &obsan_recon::Poly| {
        Poly::from_terms(p.terms().iter().map(|t| {
            let mono = Mono::from_pairs(
                t.exps
                    .iter()
                    .zip(coords)
                    .filter(|(&e, _)| e > 0)
                    .map(|(&e, c)| (c.var(), e)),
            );
            (mono, t.coeff.clone())
        }))
    };
    let angles = coords.iter().any(|c| matches!(c, Coord::Angle { .. }));
    let mut vectors = Vec::with_capacity(free.len());
    for (j, &fc) in free.iter().enumerate() {
        let mut v = vec![RatFun::zero(); n];
        v[fc] = RatFun::one();
        for (i, &pc) in piv.iter().enumerate() {
            let f = &functions[j * r + i];
            let num = RatFun::from_poly(to_poly(f.num()));
            let den = RatFun::from_poly(to_poly(f.den()));
            let inv = ctx.rf_inv(&den).ok_or_else(|| {
                AnalysisError::Invalid("internal: a reconstructed denominator is zero".into())
            })?;
            let e = ctx.rf_mul(&num, &inv);
            v[pc] = if angles { ctx.from_tan_half(th, &e) } else { e };
        }
        vectors.push(v);
    }
    Ok(vectors)
}

/// The exact certificate (a) and (b) of the module docs (with `d_t xi`
/// over the known inputs' jets `jets` when the vectors depend on them); the
/// number of identities checked, or the reason a candidate fails.
/// The span certificate of a known-input system's kernel basis (module docs,
/// (a) and (b) with no unknown input): every output invariant, every bracket
/// with `f0` and the input fields in the span. Exact; the identities counted.
pub(crate) fn certify_span(
    nf: &mut NormalForm,
    vectors: &[Vec<RatFun>],
) -> Result<usize, AnalysisError> {
    if !nf.unknown_inputs.is_empty() || nf.delay.is_some() {
        return Err(AnalysisError::Invalid(
            "the span certificate is for known inputs without delay".into(),
        ));
    }
    certify(nf, vectors, &[])
}

fn certify(
    nf: &mut NormalForm,
    vectors: &[Vec<RatFun>],
    jets: &[(usize, usize)],
) -> Result<usize, AnalysisError> {
    if vectors.is_empty() {
        return Ok(0);
    }
    // Built before the half-angle view, which then knows the jets' symbols.
    let dts: Vec<Vec<RatFun>> = if jets.is_empty() {
        Vec::new()
    } else {
        vectors
            .iter()
            .map(|xi| time_derivative(nf, jets, xi))
            .collect()
    };
    let th = nf.ctx.tan_half();
    // Roots: with no angle and every atom decided, the canonical forms are
    // elements of the field Q(x)(roots) written uniquely (docs/engine.md,
    // "Decided and not decided"), so the checks run on them as they are (a
    // zero is zero, a pivot not zero is not zero). With angles too, the
    // half-angle view does not carry the roots' relations: refused.
    let plain = !th.complete(&nf.ctx);
    if plain && (!th.is_empty() || !crate::decided::undecided_atoms_of(nf, &[]).is_empty()) {
        return Err(AnalysisError::Invalid(
            "symmetries with unknown inputs: a root beside an angle or an undecided atom is not supported".into(),
        ));
    }
    let view = |ctx: &Ctx, e: &RatFun| -> RatFun {
        if plain {
            e.clone()
        } else {
            ctx.to_tan_half(&th, e)
        }
    };
    let vars: Vec<Var> = nf.state_vars.clone();
    let canon_vec =
        |ctx: &mut Ctx, f: &[Id]| -> Vec<RatFun> { f.iter().map(|&e| ctx.canon(e)).collect() };
    // Input-dependent vectors: one field with the inputs as symbols, whose
    // bracket gains d_t xi (module docs); otherwise f0 and each f_i alone.
    let mut fields: Vec<(String, Vec<RatFun>)> = if jets.is_empty() {
        vec![("f0".into(), canon_vec(&mut nf.ctx, &nf.f0.clone()))]
    } else {
        vec![(
            "f0 + sum f_i u_i (with d_t xi)".into(),
            drift_with_inputs(nf),
        )]
    };
    if jets.is_empty() {
        for (name, f) in nf.inputs.clone().iter().zip(nf.fields.clone()) {
            fields.push((format!("the field of {name}"), canon_vec(&mut nf.ctx, &f)));
        }
    }
    let mut gs = Vec::new();
    for (name, g) in nf
        .unknown_inputs
        .clone()
        .iter()
        .zip(nf.unknown_fields.clone())
    {
        let gv = canon_vec(&mut nf.ctx, &g);
        gs.push(gv.clone());
        fields.push((format!("the field of {name}"), gv));
    }
    let mut count = 0;
    for (name, h) in nf.outputs.clone() {
        let h = nf.ctx.canon(h);
        for (a, xi) in vectors.iter().enumerate() {
            let d = nf.ctx.rf_lie_derivative(&h, &vars, xi);
            if !view(&nf.ctx, &d).is_zero() {
                return Err(AnalysisError::Invalid(format!(
                    "kernel vector {} of the observable codistribution changes output {name}: the rank test was unlucky; run again with another --seed",
                    a + 1
                )));
            }
            count += 1;
        }
    }
    let mut span = Span { rows: vec![] };
    for v in vectors.iter().chain(&gs) {
        let t: Vec<RatFun> = v.iter().map(|e| view(&nf.ctx, e)).collect();
        span.insert(&nf.ctx, t);
    }
    for (fi, (fname, f)) in fields.iter().enumerate() {
        for (a, xi) in vectors.iter().enumerate() {
            let mut b = Vec::with_capacity(vars.len());
            for i in 0..vars.len() {
                let p = nf.ctx.rf_lie_derivative(&xi[i], &vars, f);
                let q = nf.ctx.rf_lie_derivative(&f[i], &vars, xi);
                let mut d = nf.ctx.rf_sub(&p, &q);
                if fi == 0 && !dts.is_empty() {
                    d = nf.ctx.rf_add(&d, &dts[a][i]);
                }
                b.push(view(&nf.ctx, &d));
            }
            if span.reduce(&nf.ctx, b).iter().any(|x| !x.is_zero()) {
                return Err(AnalysisError::Invalid(format!(
                    "no exact certificate: the bracket of {fname} with kernel vector {} leaves the span of the kernel and the unknown inputs' fields, so the lost directions depend on the unknown input's history (docs/engine.md, \"Symmetries with unknown inputs\")",
                    a + 1
                )));
            }
            count += 1;
        }
    }
    Ok(count)
}
