//! One run's counts: the per-output Taylor orders, local identifiability,
//! the Gröbner basis and the number of values of each variable; SIAN's bounds.

use super::model::ZModel;
use super::run::{Rng, Run};
use super::types::{err, gb_err, GlobalOptions};
use super::weights::{raise, sian_weights, z_weight};
use crate::rank::AnalysisError;
use obsan_expr::Poly as ZPoly;
use obsan_groebner::{distinct_roots, groebner, presolve_linear, GbBudget, Mono, Poly, Ring};
use obsan_recon::fp::{Echelon, Zp};
use std::time::Instant;

/// One run's answer: per target (params then model states) the number of
/// values (`None`: infinitely many), and the joint count.
pub(super) struct Counts {
    pub(super) per_var: Vec<Option<usize>>,
    pub(super) joint: Option<usize>,
    /// Per output, the Taylor order used (inclusive): the first order at
    /// which its row of the Jacobian is dependent on the rows kept before.
    pub(super) orders: Vec<usize>,
    /// Highest order of an independent (kept) row.
    pub(super) rank_order: usize,
    pub(super) unknowns: usize,
    pub(super) equations: usize,
    /// Total degrees of the equations in the unknowns (SIAN's Bezout product).
    pub(super) degrees: Vec<u32>,
    /// Number of locally identifiable targets (SIAN's |theta_l|).
    pub(super) n_local: usize,
}

/// One run: the per-output orders by SIAN's greedy rank test on the total
/// gradients of the output coefficients (docs/engine.md, "Taylor orders"),
/// local identifiability from the same Jacobian, then the counts.
pub(super) fn count_once(run: &mut Run, opts: &GlobalOptions) -> Result<Counts, AnalysisError> {
    let f = run.field;
    let targets: Vec<usize> = (0..run.np)
        .chain((0..run.nx).map(|s| run.sv(s, 0)))
        .collect();
    let nt = targets.len();
    // Total gradients d v / d (params, x(0)) of the derivation variables at
    // the point, built order by order (inputs are known: gradient 0).
    let mut grads: Vec<Option<Vec<u64>>> = vec![None; run.ring.n];
    for (t, &v) in targets.iter().enumerate() {
        let mut e = vec![0u64; nt];
        e[t] = 1;
        grads[v] = Some(e);
    }
    let combine = |g: &[(usize, u64)], grads: &[Option<Vec<u64>>]| -> Vec<u64> {
        let mut out = vec![0u64; nt];
        for &(v, c) in g {
            if let Some(gv) = &grads[v] {
                for (a, b) in out.iter_mut().zip(gv) {
                    *a = f.add(*a, f.mul(c, *b));
                }
            }
        }
        out
    };
    // z = 1/den at order 0: from z den - 1 = 0, grad z = -(sum_{v != z}
    // q_v grad v) / q_z.
    for (i, q) in run.inits.clone().iter().enumerate() {
        let zv = run.sv(run.nx + i, 0);
        let g = run.grad_at(q);
        let qz = g.iter().find(|(v, _)| *v == zv).map_or(0, |x| x.1);
        let rest: Vec<(usize, u64)> = g.into_iter().filter(|(v, _)| *v != zv).collect();
        let num = combine(&rest, &grads);
        let inv = f
            .inv(qz)
            .ok_or_else(|| err("global: a denominator's auxiliary state is degenerate"))?;
        let k = f.neg(inv);
        grads[zv] = Some(num.iter().map(|&x| f.mul(x, k)).collect());
    }
    let m = run.out_d.len();
    let mut open = vec![true; m];
    let mut orders = vec![0usize; m];
    // The one dense elimination over F_p (obsan-recon).
    let mut ech = Echelon::new(Zp(f.modulus()));
    let mut rank_order = 0;
    let mut j = 0;
    while open.iter().any(|&o| o) {
        if j >= opts.max_order {
            return Err(err(format!(
                "global: the outputs' Jacobian still gained rank at Taylor order {}",
                opts.max_order
            )));
        }
        run.prepare(j)?;
        if j >= 1 {
            for s in 0..run.ns {
                let g = run.grad_at(&run.rhs_d[s][j - 1]);
                let v = run.sv(s, j);
                grads[v] = Some(combine(&g, &grads));
            }
        }
        for i in 0..m {
            if !open[i] {
                continue;
            }
            let g = run.grad_at(&run.out_d[i][j]);
            if ech.insert(combine(&g, &grads)) {
                rank_order = j;
            } else {
                open[i] = false;
                orders[i] = j;
            }
        }
        if let Some(d) = opts.deadline {
            if Instant::now() > d {
                return Err(AnalysisError::Timeout("choosing the Taylor orders".into()));
            }
        }
        j += 1;
    }
    let (local, slice) = local_and_slice(&ech, nt, run.np)?;
    let budget = opts.gb_budget();
    count_at(
        run, &orders, &targets, &local, &slice, budget, opts, rank_order,
    )
}

/// From the outputs' Jacobian (rows in `ech`, `nt` targets, params first):
/// which targets are locally identifiable (`e_t` in the row space) and the
/// slice of the fibre (`transcendence_slice`).
pub(super) fn local_and_slice(
    ech: &Echelon<Zp>,
    nt: usize,
    np: usize,
) -> Result<(Vec<bool>, Vec<usize>), AnalysisError> {
    let local: Vec<bool> = (0..nt)
        .map(|t| {
            let mut e = vec![0u64; nt];
            e[t] = 1;
            ech.contains(e)
        })
        .collect();
    let slice = transcendence_slice(ech, &local, np, nt - ech.rank())?;
    Ok((local, slice))
}

/// SIAN's slice of a fibre of positive dimension `d` (Hong, Ovchinnikov,
/// Pogudin, Yap 2020, Algorithm 1, step 3: a transcendence basis of the
/// unknowns over the outputs' field, set to the point's values): `d` of the
/// variables that are not locally identifiable, chosen greedily (initial
/// states first, then params) so that their unit rows raise the Jacobian's rank by
/// `d`, i.e. they are algebraically independent over the field `K` the outputs
/// generate (Jacobian criterion at the point). Why the count is kept
/// (docs/engine.md, "Slicing"): every component of the fibre is defined over
/// the algebraic closure of `K` and projects dominantly onto these `d`
/// coordinates (the components are conjugate over `K`), and the point's values
/// of them are algebraically independent over that closure, so they lie in
/// every component's image: the slice meets every component in finitely many
/// points, and the locally identifiable variables are constant on each.
/// Fixing coordinates keeps the system sparse (the presolve substitutes
/// numbers), where a random hyperplane spreads one variable over all of them.
fn transcendence_slice(
    ech: &Echelon<Zp>,
    local: &[bool],
    np: usize,
    d: usize,
) -> Result<Vec<usize>, AnalysisError> {
    let nt = local.len();
    let mut e = ech.clone();
    let mut chosen = Vec::with_capacity(d);
    // Initial states first, then params: measured faster on SI.jl's Goodwin
    // (54 s against 80 s) and HIV (2.3 s against 4.8 s).
    for t in (np..nt).chain(0..np) {
        if chosen.len() == d {
            break;
        }
        if local[t] {
            continue;
        }
        let mut u = vec![0u64; nt];
        u[t] = 1;
        if e.insert(u) {
            chosen.push(t);
        }
    }
    if chosen.len() < d {
        return Err(err(
            "global: the fibre is larger than the non-identifiable variables span (a non-generic point); try another --seed",
        ));
    }
    Ok(chosen)
}

/// The counts on the truncated system. A fibre of positive dimension `d` (some
/// variables not locally identifiable) is first cut by fixing the `d`
/// variables of `slice` (`transcendence_slice`) to their values at the point.
#[allow(clippy::too_many_arguments)]
fn count_at(
    run: &mut Run,
    orders: &[usize],
    targets: &[usize],
    local: &[bool],
    slice: &[usize],
    budget: GbBudget,
    opts: &GlobalOptions,
    rank_order: usize,
) -> Result<Counts, AnalysisError> {
    let (mut eqs, unk) = run.sian_equations(orders)?;
    // The slice: each chosen variable fixed to its value at the point.
    for &t in slice {
        let v = targets[t];
        let r = &run.ring;
        eqs.push(r.sub(&r.var(v), &r.constant(run.point[v])));
    }
    // SIAN's weighted order (weights.rs): it changes the time, never a count.
    let np = run.np;
    let w = if opts.weighted {
        sian_weights(run, &local[..np])
    } else {
        vec![1; run.ring.n]
    };
    let q = run.cleared.q.clone();
    let (per_var, joint, unknowns, degrees) =
        count_system(run, &eqs, &unk, targets, local, &w, Some(q), budget, opts)?;
    Ok(Counts {
        per_var,
        joint,
        orders: orders.to_vec(),
        rank_order,
        unknowns,
        equations: eqs.len() + usize::from(run.cleared.q.degree() > 0),
        degrees,
        n_local: local.iter().filter(|&&l| l).count(),
    })
}

/// The counts on a polynomial system `eqs` (in the run's ring) in the
/// unknowns `unk`: the Gröbner basis after the linear presolve and the
/// weights `w` (per ring variable), then each target's minimal polynomial
/// and the joint count of the locally identifiable ones. With `zq`, one more
/// unknown `z` and the generator `z Q - 1` (sian.rs). Returns the per-target
/// counts, the joint count, the number of unknowns and the equations'
/// degrees in them (SIAN's Bezout product).
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(super) fn count_system(
    run: &mut Run,
    eqs: &[Poly],
    unk: &[usize],
    targets: &[usize],
    local: &[bool],
    w: &[u32],
    zq: Option<Poly>,
    budget: GbBudget,
    opts: &GlobalOptions,
) -> Result<(Vec<Option<usize>>, Option<usize>, usize, Vec<u32>), AnalysisError> {
    let mut eqs = eqs.to_vec();
    let mut steps: Vec<u32> = unk.iter().map(|&v| w[v]).collect();
    let mut degrees: Vec<u32> = eqs.iter().map(|e| degree_in(e, unk)).collect();
    // `z Q - 1` (sian.rs), `z` one more variable after the unknowns, when
    // there is a denominator (Q = 1 otherwise).
    let q = zq.unwrap_or_else(|| run.ring.constant(1));
    let with_z = q.degree() > 0;
    if with_z {
        degrees.push(degree_in(&q, unk) + 1);
        eqs.push(q);
    }
    let (ring, mut gens) = run.to_unknown_ring(&eqs, unk, usize::from(with_z))?;
    if with_z {
        steps.push(z_weight(w, run));
        let zq = gens.pop().unwrap_or_default();
        gens.push(ring.sub(
            &ring.mul(&zq, &ring.var(ring.n - 1)).map_err(gb_err)?,
            &ring.constant(1),
        ));
    }
    let tpos: Vec<usize> = targets
        .iter()
        .map(|v| unk.iter().position(|u| u == v).unwrap_or(0))
        .collect();
    let (per_var, joint) = count_gens(
        &ring,
        gens,
        &tpos,
        local,
        &steps,
        &mut run.rng,
        budget,
        opts,
    )?;
    Ok((per_var, joint, ring.n, degrees))
}

/// The counts on generators `gens` in `ring` (its variables the unknowns,
/// with weights `steps`): the linear presolve, the weights, the Gröbner
/// basis, then each target's (at `tpos`) number of values from its minimal
/// polynomial, and the joint count of the locally identifiable ones.
#[allow(clippy::too_many_arguments)]
pub(super) fn count_gens(
    ring: &Ring,
    gens: Vec<Poly>,
    tpos: &[usize],
    local: &[bool],
    steps: &[u32],
    rng: &mut Rng,
    budget: GbBudget,
    opts: &GlobalOptions,
) -> Result<(Vec<Option<usize>>, Option<usize>), AnalysisError> {
    let f = ring.field;
    let ring = ring.clone();
    // Linear generators solved first (the outputs fix many unknowns to
    // numbers), then the weights: presolve needs degree 1 to mean linear.
    let gens = presolve_linear(&ring, &gens, opts.max_bytes).map_err(gb_err)?;
    let gens = raise(&ring, &gens, steps).map_err(gb_err)?;
    let b = groebner(&ring, &gens, budget).map_err(gb_err)?;
    if b.is_unit() {
        return Err(err(
            "global: the system at the random point has no solution (a degenerate point); try another --seed",
        ));
    }
    if !b.is_zero_dimensional() {
        return Err(err(
            "global: the sliced system still has infinitely many solutions (a non-generic point); try another --seed",
        ));
    }
    let mut per_var = Vec::with_capacity(tpos.len());
    for (i, &t) in tpos.iter().enumerate() {
        if !local[i] {
            per_var.push(None);
            continue;
        }
        let xt = ring.from_terms([(Mono::var(ring.n, t, steps[t]), 1)]);
        let m = b
            .minimal_polynomial_in(&xt, steps, opts.max_solutions)
            .map_err(gb_err)?;
        per_var.push(Some(distinct_roots(f, &m)));
    }
    // A random linear form in the locally identifiable variables separates
    // their joint values (with probability at least 1 - C(s, 2)/p), so its
    // distinct values count them.
    let mut terms = Vec::new();
    for (i, &t) in tpos.iter().enumerate() {
        if local[i] {
            terms.push((Mono::var(ring.n, t, steps[t]), rng.elem(&f)));
        }
    }
    let lf = ring.from_terms(terms);
    let m = b
        .minimal_polynomial_in(&lf, steps, opts.max_solutions)
        .map_err(gb_err)?;
    let joint = Some(distinct_roots(f, &m));
    Ok((per_var, joint))
}

/// SIAN's bounds (Hong, Ovchinnikov, Pogudin, Yap 2020, Algorithm 1, steps
/// 2(b) and 3(a); docs/engine.md): with `n` states, `l` params, `s = n + l`,
/// `d0` the largest degree of `Q f`, `Q h` and `Q` (`Q` the lcm of the
/// denominators, here bounded by their product), the orders and local
/// verdicts are wrong only on a hypersurface of degree
/// `D1 = (s + 1) 2 d0 s (n + 1)(1 + 2 d0 s)` in the point, the global ones on
/// one of degree `D2 = 6 |theta_l| prod(deg E_t) (1 + 2 d0 max beta)`.
/// Schwartz–Zippel over F_p: one run errs with probability at most
/// `(D1 + D2)/p`; the two runs are independent and must agree.
pub(super) fn error_bounds(m: &ZModel, runs: &[Counts], primes: &[u64; 2]) -> (f64, f64, f64) {
    let n = m.dyn_vars.len() as f64;
    let s = n + m.param_vars.len() as f64;
    let mut dens: Vec<&ZPoly> = Vec::new();
    for (_, d) in m.rhs.iter().chain(&m.outputs) {
        if d.total_degree() > 0 && !dens.contains(&d) {
            dens.push(d);
        }
    }
    let deg_q: u64 = dens.iter().map(|d| d.total_degree()).sum();
    let mut d0 = deg_q;
    for (num, den) in m.rhs.iter().chain(&m.outputs) {
        d0 = d0.max(num.total_degree() + deg_q - den.total_degree().min(deg_q));
    }
    let d0 = d0.max(1) as f64;
    let d1 = (s + 1.0) * 2.0 * d0 * s * (n + 1.0) * (1.0 + 2.0 * d0 * s);
    let mut worst_log = f64::NEG_INFINITY;
    let mut probs = Vec::new();
    for (c, &p) in runs.iter().zip(primes) {
        let max_beta = c.orders.iter().copied().max().unwrap_or(0) as f64;
        let log_d2 = if c.n_local == 0 {
            f64::NEG_INFINITY
        } else {
            (6.0 * c.n_local as f64 * (1.0 + 2.0 * d0 * max_beta)).log10()
                + c.degrees
                    .iter()
                    .map(|&d| (d.max(1) as f64).log10())
                    .sum::<f64>()
        };
        worst_log = worst_log.max(log_d2);
        let total = d1 + 10f64.powf(log_d2);
        probs.push((total / p as f64).min(1.0));
    }
    (d1, worst_log, probs.iter().product())
}

/// The total degree of `p` in the variables `unk` (the others are numbers at
/// the point): SIAN's Bezout product counts the unweighted degrees.
fn degree_in(p: &Poly, unk: &[usize]) -> u32 {
    p.terms()
        .iter()
        .map(|(m, _)| unk.iter().map(|&v| m.exponents()[v]).sum::<u32>())
        .max()
        .unwrap_or(0)
}
