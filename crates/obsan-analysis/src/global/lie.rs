//! The Lie route (docs/engine.md, "Lie route"): for an input-affine system
//! `x' = f0(x) + sum_i u_i f_i(x)`, two (params, initial states) are
//! indistinguishable for every input iff every iterated Lie derivative
//! `L_{f_i1} ... L_{f_ik} h` takes the same value at both (Hermann and Krener
//! 1977; for analytic systems through the Chen–Fliess series): the paper's
//! notion of observability (Martinelli 2011, section II). So the fibre is
//! cut out by equations in the parameters and initial states alone, with no
//! Taylor unknowns `x^(k)`: what makes the paper's calibration system,
//! whose Taylor system carries every input's jets, small.
//!
//! Truncation (proven, as SIAN's orders): let `K` be the field the Lie
//! derivatives generate. Greedily, level by level, a candidate is kept when
//! its gradient raises the Jacobian's rank, and the next level's candidates
//! are `L_{f_i} c` for the kept `c` only. When a level keeps none, the set
//! `E` of every candidate met (the outputs included) generates `K`: the kept
//! ones `B` are a transcendence basis of `K`; for `b` in `B`, `L_{f_i} b` is
//! in `E`; any other `e` in `E` is algebraic over `Q(B)`, and differentiating
//! its minimal polynomial `P` (`P'(e) L e + P^L(e) = 0`, `P' != 0` in
//! characteristic 0) puts `L_{f_i} e` in `Q(E)`. So `Q(E)` is closed under
//! every `L_{f_i}` and holds the outputs: it is `K`. The zeros of
//! `e(theta) = e(theta*)`, `e` in `E`, with every denominator non-zero, are
//! then the indistinguishable (params, initial states): each Lie derivative
//! is a rational function of `E` whose denominator is non-zero at the
//! generic values.
//!
//! The Lie derivatives are exact canonical forms over Q (the engine's
//! `rf_lie_derivative`, common factors cancelled), computed once and shared
//! by both runs; each run reduces them modulo its prime at its own point.
//! An angle output is read through its tangent `T` at length 0 and through
//! the angle's own derivatives beyond (`L_f beta = L_f T / (1 + T^2)`, free
//! of the offsets a bearing carries): `Q(T, L_w beta)` is closed under the
//! derivations as well (`L_f T = (1 + T^2) L_f beta`).

use super::count::{count_gens, local_and_slice, Counts};
use super::model::ZModel;
use super::outputs::OutputForm;
use super::run::{int_mod, Rng};
use super::types::{err, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_expr::{Ctx, Poly as ZPoly, RatFun, Var};
use obsan_groebner::{Field, Mono, Order, Poly, Ring};
use obsan_recon::fp::{Echelon, Zp};
use std::collections::HashMap;
use std::time::Instant;

/// The exact Lie derivatives, by (output, word), computed on demand.
struct LieForms {
    states: Vec<Var>,
    /// The drift (when not zero) and each input's field, per dynamic state.
    fields: Vec<Vec<RatFun>>,
    outputs: Vec<RatFun>,
    tangent: Vec<bool>,
    /// The distinct non-constant denominators every Lie derivative's
    /// denominator divides a power of (`z Q = 1` keeps them non-zero).
    base: Vec<ZPoly>,
    cache: HashMap<(usize, Vec<usize>), RatFun>,
    max_terms: usize,
}

fn ratfun(ctx: &Ctx, (n, d): &(ZPoly, ZPoly)) -> Result<RatFun, AnalysisError> {
    let inv = ctx
        .rf_inv(&RatFun::from_poly(d.clone()))
        .ok_or_else(|| err("global (lie): a zero denominator"))?;
    Ok(ctx.rf_mul(&RatFun::from_poly(n.clone()), &inv))
}

impl LieForms {
    fn new(ctx: &mut Ctx, m: &ZModel, max_terms: usize) -> Result<LieForms, AnalysisError> {
        let rhs: Vec<RatFun> = m
            .rhs
            .iter()
            .map(|p| ratfun(ctx, p))
            .collect::<Result<_, _>>()?;
        // Each input's field is the right-hand side's derivative in it (the
        // model is affine in its inputs); the drift is what remains.
        let mut fields = Vec::new();
        let mut drift = rhs.clone();
        for &u in &m.input_vars {
            let fi: Vec<RatFun> = rhs.iter().map(|r| ctx.rf_diff(r, u)).collect();
            for g in &fi {
                if m.input_vars.iter().any(|&w| !ctx.rf_diff(g, w).is_zero()) {
                    return Err(err(
                        "global (lie): the right-hand side is not affine in the inputs",
                    ));
                }
            }
            for (d, g) in drift.iter_mut().zip(&fi) {
                let t = ctx.rf_mul(g, &RatFun::var(u));
                *d = ctx.rf_sub(d, &t);
            }
            if fi.iter().any(|g| !g.is_zero()) {
                fields.push(fi);
            }
        }
        if drift.iter().any(|g| !g.is_zero()) {
            fields.insert(0, drift);
        }
        let outputs: Vec<RatFun> = m
            .outputs
            .iter()
            .map(|p| ratfun(ctx, p))
            .collect::<Result<_, _>>()?;
        // Lie derivatives of h(x): an output reading an input would need its
        // derivatives too (the Taylor route has them).
        if outputs
            .iter()
            .any(|o| o.vars().iter().any(|v| m.input_vars.contains(v)))
        {
            return Err(err(
                "global (lie): an output reads an input; the Lie route takes outputs of the states and params only (use --route taylor)",
            ));
        }
        let tangent: Vec<bool> = m.forms.iter().map(|f| *f == OutputForm::Tangent).collect();
        let mut base: Vec<ZPoly> = Vec::new();
        let add = |d: &ZPoly, base: &mut Vec<ZPoly>| {
            if d.total_degree() > 0 && !base.contains(d) {
                base.push(d.clone());
            }
        };
        for (_, d) in m.rhs.iter().chain(&m.outputs) {
            add(d, &mut base);
        }
        // 1 + T^2 = (N^2 + D^2)/D^2 of a tangent output.
        for (o, &t) in outputs.iter().zip(&tangent) {
            if t {
                let (n, d) = (o.numerator(), o.denominator());
                add(&n.mul(n).add(&d.mul(d)), &mut base);
            }
        }
        Ok(LieForms {
            states: m.dyn_vars.clone(),
            fields,
            outputs,
            tangent,
            base,
            cache: HashMap::new(),
            max_terms,
        })
    }

    /// `L_{f_wk} ... L_{f_w1} h_y` (the word's first field applied first);
    /// for an angle output, of the angle once the word is not empty.
    fn form(&mut self, ctx: &mut Ctx, y: usize, word: &[usize]) -> Result<RatFun, AnalysisError> {
        let key = (y, word.to_vec());
        if let Some(r) = self.cache.get(&key) {
            return Ok(r.clone());
        }
        let r = match word.split_last() {
            None => self.outputs[y].clone(),
            Some((&i, rest)) => {
                let g = self.form(ctx, y, rest)?;
                let l = ctx.rf_lie_derivative(&g, &self.states, &self.fields[i]);
                if rest.is_empty() && self.tangent[y] {
                    let t2 = ctx.rf_mul(&g, &g);
                    let den = ctx.rf_add(&RatFun::one(), &t2);
                    let inv = ctx
                        .rf_inv(&den)
                        .ok_or_else(|| err("global (lie): 1 + T^2 vanishes"))?;
                    ctx.rf_mul(&l, &inv)
                } else {
                    l
                }
            }
        };
        // The engine's budget tripped (its values are placeholders from
        // here): the error says so with the limit's own text, which the
        // binary keeps over the bare limit, so `--route auto` still says
        // which attempts failed before and why.
        if let Some(limit) = obsan_expr::limits::budget_reason() {
            return Err(err(format!(
                "{limit} (a Lie derivative of length {})",
                word.len()
            )));
        }
        if r.term_count() > self.max_terms {
            return Err(err(format!(
                "expression too large: a Lie derivative of length {} has {} terms, past --max-terms {} (the Lie route)",
                word.len(),
                r.term_count(),
                self.max_terms
            )));
        }
        self.cache.insert(key, r.clone());
        Ok(r)
    }
}

/// Both runs of the Lie route (one per prime, each at its own random point
/// drawn from `seed + run`); `orders` of each answer hold, per output, the
/// longest word used.
pub(super) fn lie_counts(
    m: &ZModel,
    ctx: &mut Ctx,
    primes: &[u64; 2],
    opts: &GlobalOptions,
) -> Result<Vec<Counts>, AnalysisError> {
    let max_terms = opts.max_bytes / obsan_expr::Budget::BYTES_PER_TERM as usize;
    let mut forms = LieForms::new(ctx, m, max_terms.max(1))?;
    let mut out = Vec::new();
    for (r, &p) in primes.iter().enumerate() {
        out.push(lie_once(
            m,
            ctx,
            &mut forms,
            p,
            opts.seed.wrapping_add(r as u64),
            opts,
        )?);
    }
    Ok(out)
}

/// `p` modulo the field with every symbol at its value in `at`.
fn at_point(f: &Field, p: &ZPoly, at: &HashMap<Var, u64>) -> Result<u64, AnalysisError> {
    let mut acc = 0u64;
    for (mono, c) in p.terms() {
        let mut t = int_mod(f, c);
        for (v, k) in mono.iter() {
            let x = at
                .get(&v)
                .ok_or_else(|| err("global (lie): a symbol without a value"))?;
            t = f.mul(t, f.pow(*x, k as u64));
        }
        acc = f.add(acc, t);
    }
    Ok(acc)
}

/// `p` in the ring of the unknowns (params, then states, then `z`), known
/// constants at their values.
fn to_ring(
    ring: &Ring,
    p: &ZPoly,
    index: &HashMap<Var, usize>,
    consts: &HashMap<Var, u64>,
) -> Result<Poly, AnalysisError> {
    let f = &ring.field;
    let mut terms = Vec::with_capacity(p.len());
    for (mono, c) in p.terms() {
        let mut c = int_mod(f, c);
        let mut e = vec![0u32; ring.n];
        for (v, k) in mono.iter() {
            if let Some(&i) = index.get(&v) {
                e[i] += k;
            } else if let Some(&x) = consts.get(&v) {
                c = f.mul(c, f.pow(x, k as u64));
            } else {
                return Err(err(
                    "global (lie): a symbol that is no unknown nor constant",
                ));
            }
        }
        terms.push((Mono::from_exponents(e).map_err(super::types::gb_err)?, c));
    }
    Ok(ring.from_terms(terms))
}

fn lie_once(
    m: &ZModel,
    ctx: &mut Ctx,
    forms: &mut LieForms,
    p: u64,
    seed: u64,
    opts: &GlobalOptions,
) -> Result<Counts, AnalysisError> {
    let f = Field::new(p).ok_or_else(|| err("global: bad prime"))?;
    let (np, nx) = (m.param_vars.len(), m.dyn_vars.len());
    let nt = np + nx;
    // Unknowns: params, states (targets, in the order of the counts), z.
    let ring = Ring::new(f, nt + 1, Order::Grevlex);
    let mut index: HashMap<Var, usize> = HashMap::new();
    for (i, &v) in m.param_vars.iter().chain(&m.dyn_vars).enumerate() {
        index.insert(v, i);
    }
    let mut rng = Rng::new(seed);
    let mut consts: HashMap<Var, u64> = HashMap::new();
    let mut at: HashMap<Var, u64> = HashMap::new();
    let mut point = vec![0u64; nt + 1];
    let mut q = ZPoly::one();
    for d in &forms.base {
        q = q.mul(d);
    }
    let mut found = false;
    for _ in 0..16 {
        consts.clear();
        at.clear();
        for &v in &m.const_vars {
            let x = rng.elem(&f);
            consts.insert(v, x);
            at.insert(v, x);
        }
        for (i, &v) in m.param_vars.iter().chain(&m.dyn_vars).enumerate() {
            point[i] = rng.elem(&f);
            at.insert(v, point[i]);
        }
        let q0 = at_point(&f, &q, &at)?;
        if let Some(z) = f.inv(q0) {
            point[nt] = z;
            found = true;
            break;
        }
    }
    if !found {
        return Err(AnalysisError::NoPoint);
    }
    let qp = to_ring(&ring, &q, &index, &consts)?;
    let fx = f;
    let grad = |num: &Poly, den: &Poly, n0: u64, d0: u64| -> Vec<u64> {
        // d(N/D) is proportional to D dN - N dD at the point.
        let mut g = vec![0u64; nt];
        for (t, gt) in g.iter_mut().enumerate() {
            let dn = ring.eval(&ring.derivative(num, t), &point);
            let dd = ring.eval(&ring.derivative(den, t), &point);
            *gt = fx.sub(fx.mul(d0, dn), fx.mul(n0, dd));
        }
        g
    };
    let mut ech = Echelon::new(Zp(p));
    let mut eqs: Vec<Poly> = Vec::new();
    let mut degrees: Vec<u32> = Vec::new();
    let mut level: Vec<(usize, Vec<usize>)> =
        (0..m.outputs.len()).map(|y| (y, Vec::new())).collect();
    let (mut depth, mut rank_level) = (0usize, 0usize);
    loop {
        let mut kept = Vec::new();
        for (y, w) in level {
            let c = forms.form(ctx, y, &w)?;
            if c.vars().iter().all(|v| !index.contains_key(v)) {
                continue; // constant in the unknowns: no information
            }
            let num = to_ring(&ring, c.numerator(), &index, &consts)?;
            let den = to_ring(&ring, c.denominator(), &index, &consts)?;
            let (n0, d0) = (ring.eval(&num, &point), ring.eval(&den, &point));
            let di = f.inv(d0).ok_or_else(|| {
                err("global (lie): a denominator vanishes at the point; try another --seed")
            })?;
            // N - c* D, c* = N/D at the point.
            let e = ring.sub(&num, &ring.scale(&den, f.mul(n0, di)));
            degrees.push(e.degree());
            eqs.push(e);
            if ech.insert(grad(&num, &den, n0, d0)) {
                kept.push((y, w));
                rank_level = depth;
            }
            if let Some(d) = opts.deadline {
                if Instant::now() > d {
                    return Err(AnalysisError::Timeout("the Lie route's derivatives".into()));
                }
            }
        }
        if kept.is_empty() {
            break;
        }
        depth += 1;
        if depth > opts.max_order {
            return Err(err(format!(
                "global: the Lie derivatives still gained rank at length {}",
                opts.max_order
            )));
        }
        level = kept
            .iter()
            .flat_map(|(y, w)| {
                (0..forms.fields.len()).map(move |i| {
                    let mut v = w.clone();
                    v.push(i);
                    (*y, v)
                })
            })
            .collect();
    }
    let (local, slice) = local_and_slice(&ech, nt, np)?;
    let mut gens = eqs;
    degrees.push(qp.degree() + 1);
    gens.push(ring.sub(
        &ring.mul(&qp, &ring.var(nt)).map_err(super::types::gb_err)?,
        &ring.constant(1),
    ));
    for &t in &slice {
        gens.push(ring.sub(&ring.var(t), &ring.constant(point[t])));
    }
    let budget = opts.gb_budget();
    let equations = gens.len();
    let tpos: Vec<usize> = (0..nt).collect();
    let steps = vec![1u32; nt + 1];
    let (per_var, joint) = count_gens(&ring, gens, &tpos, &local, &steps, &mut rng, budget, opts)?;
    Ok(Counts {
        per_var,
        joint,
        orders: vec![depth; m.outputs.len()],
        rank_order: rank_level,
        unknowns: nt + 1,
        equations,
        degrees,
        n_local: local.iter().filter(|&&l| l).count(),
    })
}
