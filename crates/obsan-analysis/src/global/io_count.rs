//! The parameters' counts from the input-output relations (io.rs): each
//! relation's coefficients, normalised, reconstructed as rational functions
//! of the parameters over Q (obsan-recon, one kernel per point, verified at
//! fresh points), then `c_i(theta) = c_i(theta*)` at a random `theta*`
//! solved by a Gröbner basis over F_q and counted per parameter.
//!
//! What the count means (docs/engine.md, "Input-output route"): the
//! parameter values whose relations equal those of `theta*`, i.e. the
//! multi-experiment count (the coefficients generate the field of
//! multi-experiment identifiable functions: Ovchinnikov, Pillay, Pogudin,
//! Scanlon 2021). It is the single-experiment count when one output fixes
//! the coefficients: the relation's monomials are linearly independent
//! along a generic output (a non-zero Wronskian; Ovchinnikov, Pogudin,
//! Thompson 2023), checked here (io.rs, `independent_along`); the route
//! refuses otherwise.

use super::io::{elem, IoModel};
use super::io_pres::presentation;
use super::model::ZModel;
use super::run::Rng;
use super::types::{err, gb_err, too_large, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::{distinct_roots, groebner, term_bytes, Field, Mono, Order, Poly, Ring};
use obsan_recon::fp::{Echelon, Zp};
use obsan_recon::{
    interpolate_polys_vec, reconstruct_vec, DegreeBounds, Options, Rational, Thiele,
};
use std::collections::HashMap;

/// Sizes of one output's relation, as measured (docs/performance.md).
#[derive(Clone, Debug)]
pub struct IoSize {
    pub order: usize,
    pub variables: usize,
    pub degree: u32,
    pub ansatz: usize,
    pub support: usize,
    /// Black-box points of the reconstruction, and its terms.
    pub points: u64,
    pub terms: usize,
    pub max_degree: u32,
    /// Schwartz-Zippel bound of the reconstruction's check at fresh points.
    pub recon_error_bound: f64,
    /// The relation's monomials are linearly independent along a generic
    /// output (a non-zero Wronskian): one experiment fixes its coefficients.
    pub single: bool,
}

/// The route's answer on the parameters.
pub(super) struct IoCounts {
    /// Per parameter: its number of values (`None`: infinitely many).
    pub(super) per_param: Vec<Option<usize>>,
    pub(super) joint: Option<usize>,
    pub(super) sizes: Vec<IoSize>,
    /// The primes of the two counts (which agree).
    pub(super) primes: [u64; 2],
}

/// Largest ansatz (monomials) one relation's first kernel may use: its
/// dense elimination is cubic in it (measured, docs/performance.md: 792
/// monomials 1.0 s; 3003 monomials 245 s on a loaded machine).
pub(super) const MAX_ANSATZ: usize = 1000;

/// The counts, every relation's way tried (the unit tests' entry).
#[cfg_attr(not(test), allow(dead_code))]
pub(super) fn io_count(
    m: &ZModel,
    opts: &GlobalOptions,
    seed: u64,
) -> Result<IoCounts, AnalysisError> {
    io_count_with(m, opts, seed, true, MAX_ANSATZ)
}

/// [`io_count`], with the relations past the ansatz's cap (`cap`
/// monomials: [`MAX_ANSATZ`] but in tests) found by elimination (io_elim.rs)
/// only when `eliminate`: `--route auto` tries the other routes first, as a
/// large relation may keep the reconstruction busy far longer than they take.
pub(super) fn io_count_with(
    m: &ZModel,
    opts: &GlobalOptions,
    seed: u64,
    eliminate: bool,
    cap: usize,
) -> Result<IoCounts, AnalysisError> {
    io_count_under(m, opts, seed, (eliminate, cap), None)
}

/// [`io_count_with`] under the outputs' priority `only` (tests: every
/// priority counts the same) or the one [`presentation`] chooses.
pub(super) fn io_count_under(
    m: &ZModel,
    opts: &GlobalOptions,
    seed: u64,
    (eliminate, cap): (bool, usize),
    only: Option<&[usize]>,
) -> Result<IoCounts, AnalysisError> {
    let np = m.param_vars.len();
    let mut rng = Rng::new(seed);
    let theta: Vec<u64> = (0..np).map(|_| elem(&mut rng, obsan_expr::P)).collect();
    let pres = presentation(m, opts, &theta, &mut rng, (eliminate, cap), only)?;
    let (mp, perm) = (&pres.model, &pres.perm);
    let mut fns: Vec<Rational> = Vec::new();
    let mut sizes: Vec<(usize, IoSize)> = Vec::new();
    for (i, (rel, &single)) in pres.rels.iter().zip(&pres.single).enumerate() {
        let out = perm[i];
        if !single && !opts.multi_experiment {
            return Err(err(format!(
                "global (io): the monomials of output {}'s relation satisfy more than one linear relation along an output (zero Wronskian): its coefficients count multi-experiment identifiability only (--multi-experiment counts it)",
                out + 1
            )));
        }
        let mut size = IoSize {
            order: pres.orders[i],
            variables: rel.vars.len(),
            degree: rel.degree,
            ansatz: rel.ansatz,
            support: rel.support.len(),
            points: 0,
            terms: 0,
            max_degree: 0,
            recon_error_bound: 0.0,
            single,
        };
        // A monomial relation (`y' = 0`: Treatment's constant N) has no
        // coefficient to reconstruct and constrains no parameter.
        if rel.support.len() > 1 {
            let (r, points) = reconstruct(mp, &pres.orders, i, &rel.support, opts, seed)?;
            size.points = points;
            size.terms = r
                .functions
                .iter()
                .map(|f| f.num().terms().len() + f.den().terms().len())
                .sum();
            size.max_degree = r
                .functions
                .iter()
                .map(|f| f.num().degree().max(f.den().degree()))
                .max()
                .unwrap_or(0);
            size.recon_error_bound = r.certificate.error_bound;
            fns.extend(r.functions);
        }
        sizes.push((out, size));
    }
    // The sizes in the outputs' own order.
    sizes.sort_by_key(|s| s.0);
    let sizes: Vec<IoSize> = sizes.into_iter().map(|s| s.1).collect();
    // Two independent points and primes must agree, as on the Taylor route.
    let primes = [obsan_recon::PRIMES[0], obsan_recon::PRIMES[1]];
    let (per_param, joint) = count(&fns, np, opts, seed, primes[0])?;
    let again = count(&fns, np, opts, seed.wrapping_add(1), primes[1])?;
    if again != (per_param.clone(), joint) {
        return Err(err(
            "global (io): two independent random points disagree on the counts (a non-generic point); try another --seed",
        ));
    }
    Ok(IoCounts {
        per_param,
        joint,
        sizes,
        primes,
    })
}

/// The normalised coefficients of output `i`'s relation (the last one is 1,
/// left out) as rational functions of the parameters.
pub(super) fn reconstruct(
    m: &ZModel,
    orders: &[usize],
    i: usize,
    support: &[Vec<u32>],
    opts: &GlobalOptions,
    seed: u64,
) -> Result<(obsan_recon::Reconstruction, u64), AnalysisError> {
    let mut models: HashMap<u64, (IoModel, Rng)> = HashMap::new();
    let mut calls = 0u64;
    // The kernel normalised by its last coefficient (which is 1).
    let mut coeffs = |pt: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
        calls += 1;
        if let std::collections::hash_map::Entry::Vacant(e) = models.entry(p) {
            let rng = Rng::new(seed ^ p);
            let mut io = IoModel::new(m, p)?;
            io.deadline = opts.deadline;
            io.max_bytes = opts.max_bytes;
            e.insert((io, rng));
        }
        let Some((io, rng)) = models.get_mut(&p) else {
            return Ok(None);
        };
        io.on_support(pt, orders, i, support, rng)
    };
    let np = m.param_vars.len();
    let (j, alpha, axes) = normalisation(np, support.len(), &mut coeffs, seed)?;
    let bounds = axes.and_then(|fr| polynomial_bounds(&fr, &alpha));
    // Divided by a coefficient that is a monomial in the parameters and
    // scaled by their monomial denominators, the coefficients are (mostly)
    // polynomials, which need far fewer points than rational functions.
    let mut bb = |pt: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
        let Some(v) = coeffs(pt, p)? else {
            return Ok(None);
        };
        let Some(iv) = obsan_recon::fp::inv(v[j], p) else {
            return Ok(None);
        };
        Ok(Some(
            others(&v, j)
                .zip(&alpha)
                .map(|(c, a)| {
                    a.iter().zip(pt).fold(fmul(c, iv, p), |acc, (&e, &x)| {
                        fmul(acc, obsan_recon::fp::pow(x, u64::from(e), p), p)
                    })
                })
                .collect(),
        ))
    };
    let ropts = Options {
        deadline: opts.deadline,
        seed: seed ^ 0x10c0,
        ..Options::default()
    };
    let recon_err = |e: obsan_recon::ReconError<AnalysisError>| match e {
        obsan_recon::ReconError::BlackBox(e) => e,
        e => err(format!(
            "global (io): reconstructing the relations' coefficients: {e}"
        )),
    };
    // With the total degree along one generic line: the per-axis bounds
    // alone put HIV's 10 parameters' largest monomial value `prod q_i^d_i`
    // past the prime (7e20), their total degree (a few) far below it. A
    // denominator along the line proves a quotient is no polynomial.
    let bounds = match bounds {
        Some(mut b) => line_degree(&mut bb, np, support.len() - 1, seed)?.map(|d| {
            b.total = Some(d);
            b
        }),
        None => None,
    };
    // Polynomials on every axis: sparse interpolation first (about twice
    // their terms in points), the rational reconstruction when it does not
    // recognise them.
    let sparse = match &bounds {
        Some(b) => {
            let sopts = Options {
                max_terms: MAX_SPARSE_TERMS,
                ..ropts.clone()
            };
            interpolate_polys_vec(np, support.len() - 1, &mut bb, &sopts, b).map_err(recon_err)?
        }
        None => None,
    };
    let mut r = match sparse {
        Some(r) => r,
        None => reconstruct_vec(np, support.len() - 1, &mut bb, &ropts).map_err(recon_err)?,
    };
    for (f, a) in r.functions.iter_mut().zip(&alpha) {
        *f = f.over_monomial(a);
    }
    Ok((r, calls))
}

/// Terms per coefficient the sparse interpolation may find before the
/// rational reconstruction takes over (a false guess of polynomials costs
/// at most about twice this in points; SIWR_multiout's largest has 183).
const MAX_SPARSE_TERMS: usize = 2000;

/// Per-parameter degree bounds of the scaled quotients when every one has a
/// constant denominator along every axis line (then each is taken for a
/// polynomial; the sparse interpolation checks it): along axis `k` the
/// quotient `n(t) / (c t^a)` times `t^alpha_k` has degree `deg n + alpha_k -
/// a`, its degree in `theta_k` at a generic base point.
fn polynomial_bounds(axes: &[Vec<Fraction>], alpha: &[Vec<u32>]) -> Option<DegreeBounds> {
    let deg = |v: &[u64]| v.iter().rposition(|&c| c != 0).unwrap_or(0) as i64;
    let ord = |v: &[u64]| v.iter().position(|&c| c != 0).unwrap_or(0) as i64;
    let mut per_var = vec![0u32; axes.len()];
    for (k, fr) in axes.iter().enumerate() {
        for ((num, den), a) in fr.iter().zip(alpha) {
            if !is_monomial(den) {
                return None;
            }
            let d = deg(num) + i64::from(a[k]) - ord(den);
            per_var[k] = per_var[k].max(u32::try_from(d.max(0)).ok()?);
        }
    }
    Some(DegreeBounds {
        per_var,
        total: None,
    })
}

/// The largest total degree of the black box's `m` functions, from one
/// Thiele interpolation each along a random line `a + t b` (a polynomial's
/// degree along a generic line is its total degree); `None` when one has a
/// denominator there (not a polynomial) or the samples run out.
fn line_degree(
    bb: &mut BlackBox<'_>,
    np: usize,
    m: usize,
    seed: u64,
) -> Result<Option<u32>, AnalysisError> {
    let p = obsan_recon::PRIMES[0];
    let mut rng = Rng::new(seed ^ 0x1e4e);
    let a: Vec<u64> = (0..np).map(|_| elem(&mut rng, p)).collect();
    let b: Vec<u64> = (0..np).map(|_| elem(&mut rng, p)).collect();
    let mut th: Vec<Thiele> = (0..m).map(|_| Thiele::new(p, 2)).collect();
    let (mut t, mut misses) = (0u64, 0);
    while th.iter().any(|x| !x.done()) {
        t += 1;
        if misses > 8 || t as usize > MAX_AXIS_SAMPLES {
            return Ok(None);
        }
        let pt: Vec<u64> = a
            .iter()
            .zip(&b)
            .map(|(&x, &y)| obsan_recon::fp::add(x, fmul(t, y, p), p))
            .collect();
        let Some(v) = bb(&pt, p)? else {
            misses += 1;
            continue;
        };
        for (x, c) in th.iter_mut().zip(v) {
            if !x.done() {
                x.add(t, c);
            }
        }
    }
    let mut deg = 0;
    for x in &th {
        let (num, den) = x.rational();
        if den.iter().skip(1).any(|&c| c != 0) {
            return Ok(None);
        }
        deg = deg.max(num.iter().rposition(|&c| c != 0).unwrap_or(0) as u32);
    }
    Ok(Some(deg))
}

/// The coefficients at a point modulo a prime; `None` at a bad point.
type BlackBox<'a> = dyn FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, AnalysisError> + 'a;

use obsan_recon::fp::mul as fmul;

/// The entries of `v` but the `j`-th, in order.
fn others(v: &[u64], j: usize) -> impl Iterator<Item = u64> + '_ {
    v.iter()
        .enumerate()
        .filter(move |&(m, _)| m != j)
        .map(|(_, &c)| c)
}

fn is_monomial(v: &[u64]) -> bool {
    v.iter().filter(|&&c| c != 0).count() == 1
}

/// Samples of the black box along the axis lines `theta_k = t` (the other
/// parameters at one random point), kept so that every normalisation tried
/// reuses them.
struct Axes<'a, 'b> {
    bb: &'a mut BlackBox<'b>,
    base: Vec<u64>,
    samples: Vec<Vec<(u64, Vec<u64>)>>,
    next_t: Vec<u64>,
    misses: usize,
}

/// A univariate fraction modulo p: numerator and denominator coefficients,
/// lowest degree first (Thiele's reduced form).
type Fraction = (Vec<u64>, Vec<u64>);

/// Samples per axis before a probe gives up (the coefficients' degrees
/// along a line are 14 for Goodwin, 12 for SIWR_multiout).
const MAX_AXIS_SAMPLES: usize = 400;

impl Axes<'_, '_> {
    /// Along axis `k`, the reduced fractions `v_m / v_j` (`m != j`), `v` the
    /// black box's vector; `None` when the samples run out.
    fn fractions(&mut self, k: usize, j: usize) -> Result<Option<Vec<Fraction>>, AnalysisError> {
        let p = obsan_recon::PRIMES[0];
        let mut th: Option<Vec<Thiele>> = None;
        let mut idx = 0;
        while th.as_ref().is_none_or(|th| th.iter().any(|x| !x.done())) {
            while self.samples[k].len() <= idx {
                if self.misses > 8 || idx >= MAX_AXIS_SAMPLES {
                    return Ok(None);
                }
                let mut pt = self.base.clone();
                pt[k] = self.next_t[k];
                self.next_t[k] += 1;
                match (self.bb)(&pt, p)? {
                    Some(v) => self.samples[k].push((pt[k], v)),
                    None => self.misses += 1,
                }
            }
            let (t, v) = &self.samples[k][idx];
            idx += 1;
            let Some(iv) = obsan_recon::fp::inv(v[j], p) else {
                continue;
            };
            let th = th.get_or_insert_with(|| (1..v.len()).map(|_| Thiele::new(p, 2)).collect());
            for (x, c) in th.iter_mut().zip(others(v, j)) {
                if !x.done() {
                    x.add(*t, fmul(c, iv, p));
                }
            }
        }
        Ok(th.map(|th| th.iter().map(Thiele::rational).collect()))
    }
}

/// Which of the `n` coefficients to divide the others by, and per quotient
/// the exponents `a` of a monomial `theta^a` dividing its denominator.
///
/// Along each axis line `theta_k = t` (the other parameters at a random
/// point) one Thiele interpolation per quotient gives its pole order at
/// `theta_k = 0`. The last coefficient is tried first; if some quotient's
/// denominator along some axis is not a power of `t`, a coefficient `c_j`
/// that is a monomial in the parameters is looked for: then `c_m / c_j` has
/// a monomial denominator for every `m`, and conversely (the coefficients
/// have no common factor, so along a generic line `c_j(t)` dividing every
/// `c_m(t) t^b` is a power of `t`). A candidate is a `j` whose quotient by
/// the last one has a monomial numerator on every axis (`c_j / c_last =
/// n / d` reduced, `n` divides `c_j`); it is kept when every quotient by it
/// has a monomial denominator on every axis. A wrong choice (a non-generic
/// line) costs points only: the scaled functions are still rational
/// functions, reconstructed exactly and verified.
///
/// With them, per axis, the quotients by the coefficient kept (`None` when
/// the probes ran out or no normalisation gave monomial denominators).
#[allow(clippy::type_complexity)]
fn normalisation(
    np: usize,
    n: usize,
    bb: &mut BlackBox<'_>,
    seed: u64,
) -> Result<(usize, Vec<Vec<u32>>, Option<Vec<Vec<Fraction>>>), AnalysisError> {
    let p = obsan_recon::PRIMES[0];
    let mut rng = Rng::new(seed ^ 0xde40);
    let mut axes = Axes {
        bb,
        base: (0..np).map(|_| elem(&mut rng, p)).collect(),
        samples: vec![Vec::new(); np],
        next_t: vec![1; np],
        misses: 0,
    };
    let ord = |v: &[u64]| v.iter().position(|&c| c != 0).unwrap_or(0) as i64;
    let fallback = (n - 1, vec![vec![0u32; np]; n - 1], None);
    // Per axis, the quotients by the last coefficient.
    let mut by_last = Vec::with_capacity(np);
    for k in 0..np {
        let Some(f) = axes.fractions(k, n - 1)? else {
            return Ok(fallback);
        };
        by_last.push(f);
    }
    let alpha_of = |fr: &[Vec<Fraction>]| -> Vec<Vec<u32>> {
        (0..n - 1)
            .map(|m| {
                fr.iter()
                    .map(|f| (ord(&f[m].1) - ord(&f[m].0)).max(0) as u32)
                    .collect()
            })
            .collect()
    };
    let monomial_dens = |fr: &[Vec<Fraction>]| fr.iter().flatten().all(|(_, d)| is_monomial(d));
    if monomial_dens(&by_last) {
        let alpha = alpha_of(&by_last);
        return Ok((n - 1, alpha, Some(by_last)));
    }
    let candidates = (0..n - 1).filter(|&j| by_last.iter().all(|f| is_monomial(&f[j].0)));
    for j in candidates.take(4) {
        let mut fr = Vec::with_capacity(np);
        for k in 0..np {
            match axes.fractions(k, j)? {
                Some(f) => fr.push(f),
                None => break,
            }
        }
        if fr.len() == np && monomial_dens(&fr) {
            let alpha = alpha_of(&fr);
            return Ok((j, alpha, Some(fr)));
        }
    }
    Ok((n - 1, alpha_of(&by_last), None))
}

fn to_fp(p: &obsan_recon::Poly, ring: &Ring, q: u64) -> Result<Poly, AnalysisError> {
    let n = ring.n;
    let mut terms = Vec::with_capacity(p.terms().len());
    for t in p.terms() {
        let mut e = t.exps.clone();
        e.resize(n, 0);
        terms.push((
            Mono::from_exponents(e).map_err(gb_err)?,
            super::io::int_mod(&t.coeff, q),
        ));
    }
    Ok(ring.from_terms(terms))
}

/// `c_i(theta) = c_i(theta*)` at a random `theta*` over `F_q`, the
/// denominators kept non-zero by `z L(theta) = 1`; the parameters that are
/// not locally identifiable (Jacobian at `theta*`) sliced at `theta*`.
#[allow(clippy::type_complexity)]
fn count(
    fns: &[Rational],
    np: usize,
    opts: &GlobalOptions,
    seed: u64,
    q: u64,
) -> Result<(Vec<Option<usize>>, Option<usize>), AnalysisError> {
    let field = Field::new(q).ok_or_else(|| err("global (io): bad prime"))?;
    let ring = Ring::new(field, np + 1, Order::Grevlex);
    let mut rng = Rng::new(seed ^ 0xc0u64);
    let mut star = vec![0u64; np + 1];
    let mut eqs = Vec::new();
    let mut dens: Vec<Poly> = Vec::new();
    for _ in 0..16 {
        for s in star.iter_mut().take(np) {
            *s = elem(&mut rng, q);
        }
        eqs.clear();
        dens.clear();
        let mut ok = true;
        for f in fns {
            let (n, d) = (to_fp(f.num(), &ring, q)?, to_fp(f.den(), &ring, q)?);
            let (nv, dv) = (ring.eval(&n, &star), ring.eval(&d, &star));
            if dv == 0 {
                ok = false;
                break;
            }
            eqs.push(ring.sub(&ring.scale(&n, dv), &ring.scale(&d, nv)));
            if d.degree() > 0 && !dens.contains(&d) {
                dens.push(d);
            }
        }
        if ok {
            break;
        }
    }
    // Local identifiability: the Jacobian of the equations at theta*.
    let mut ech = Echelon::new(Zp(q));
    for e in &eqs {
        let row: Vec<u64> = (0..np)
            .map(|v| ring.eval(&ring.derivative(e, v), &star))
            .collect();
        ech.insert(row);
    }
    let local: Vec<bool> = (0..np).map(|t| ech.contains_unit(t, np)).collect();
    // Slice: non-local parameters fixed until the rank is full (count.rs's
    // transcendence slice, on the parameters alone).
    let mut gens = eqs.clone();
    for t in 0..np {
        if ech.rank() == np {
            break;
        }
        if local[t] {
            continue;
        }
        let mut u = vec![0u64; np];
        u[t] = 1;
        if ech.insert(u) {
            gens.push(ring.sub(&ring.var(t), &ring.constant(star[t])));
        }
    }
    // z * lcm-ish of the denominators - 1 (monomial denominators: their lcm).
    let mut l = ring.constant(1);
    let mut mono_lcm: Option<Mono> = Some(Mono::one(np + 1));
    for d in &dens {
        match (d.terms(), &mono_lcm) {
            ([(mo, _)], Some(acc)) => mono_lcm = Some(acc.lcm(mo)),
            _ => {
                mono_lcm = None;
            }
        }
    }
    match mono_lcm {
        Some(mo) => l = ring.from_terms([(mo, 1)]),
        None => {
            // The equations and the product count against the memory
            // budget: MAPK_6out's many denominators grew it past 5 GB.
            let n = np + 1;
            let held: usize = eqs.iter().map(|e| e.stored_bytes(n)).sum();
            for d in &dens {
                let bound = l
                    .len()
                    .saturating_mul(d.len())
                    .saturating_mul(term_bytes(n));
                let need = held.saturating_add(l.stored_bytes(n)).saturating_add(bound);
                if need > opts.max_bytes {
                    return Err(too_large(
                        need as u128,
                        opts.max_bytes as u128,
                        &format!(
                            "the count's product of the coefficients' {} denominators",
                            dens.len()
                        ),
                    ));
                }
                l = ring.mul(&l, d).map_err(gb_err)?;
            }
        }
    }
    if l.degree() > 0 {
        let zl = ring.mul(&l, &ring.var(np)).map_err(gb_err)?;
        gens.push(ring.sub(&zl, &ring.constant(1)));
    } else {
        gens.push(ring.var(np));
    }
    let b = groebner(&ring, &gens, opts.gb_budget()).map_err(gb_err)?;
    if b.is_unit() || !b.is_zero_dimensional() {
        return Err(err(
            "global (io): the coefficients' system at the random point is degenerate; try another --seed",
        ));
    }
    let steps = vec![1u32; np + 1];
    let mut per = Vec::with_capacity(np);
    for (t, &loc) in local.iter().enumerate() {
        if !loc {
            per.push(None);
            continue;
        }
        let xt = ring.var(t);
        let mp = b
            .minimal_polynomial_in(&xt, &steps, opts.max_solutions)
            .map_err(gb_err)?;
        per.push(Some(distinct_roots(field, &mp)));
    }
    let mut terms = Vec::new();
    for (t, &loc) in local.iter().enumerate() {
        if loc {
            terms.push((Mono::var(np + 1, t, 1), elem(&mut rng, q)));
        }
    }
    let joint = if terms.is_empty() {
        None
    } else {
        let lf = ring.from_terms(terms);
        let mp = b
            .minimal_polynomial_in(&lf, &steps, opts.max_solutions)
            .map_err(gb_err)?;
        Some(distinct_roots(field, &mp))
    };
    Ok((per, joint))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The total degree along a line: `x^2 y^3 + x` (5) and `x y + 7` (2)
    /// give 5; with `1 / (1 + x)` beside them, no degree (not polynomials).
    #[test]
    fn line_degree_is_the_total_degree() {
        let f = |pt: &[u64], p: u64, rational: bool| -> Option<Vec<u64>> {
            let (x, y) = (pt[0], pt[1]);
            let pw = |a: u64, e: u64| obsan_recon::fp::pow(a, e, p);
            let mut v = vec![
                obsan_recon::fp::add(fmul(pw(x, 2), pw(y, 3), p), x, p),
                obsan_recon::fp::add(fmul(x, y, p), 7, p),
            ];
            if rational {
                v.push(obsan_recon::fp::inv(obsan_recon::fp::add(1, x, p), p)?);
            }
            Some(v)
        };
        let mut poly = |pt: &[u64], p: u64| Ok(f(pt, p, false));
        assert_eq!(line_degree(&mut poly, 2, 2, 9).unwrap(), Some(5));
        let mut rat = |pt: &[u64], p: u64| Ok(f(pt, p, true));
        assert_eq!(line_degree(&mut rat, 2, 3, 9).unwrap(), None);
    }
}
