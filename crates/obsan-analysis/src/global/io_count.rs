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
use super::io_check;
use super::io_part;
use super::io_pres::{presentation, Presentation};
use super::model::ZModel;
use super::run::Rng;
use super::types::{err, gb_err, too_large, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::{distinct_roots, groebner, term_bytes, Field, Mono, Order, Poly, Ring};
use obsan_recon::fp::{Echelon, Zp};
use obsan_recon::{
    interpolate_polys_vec, reconstruct_vec, DegreeBounds, Options, Poly as RPoly, PrimeList,
    Rational, Univariate,
};
use std::cell::Cell;
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
    /// Normalised coefficients reconstructed: `support - 1`, or fewer when
    /// a generating part settled the count (io_count.rs, `generating_part`).
    pub reconstructed: usize,
    /// Terms of the common denominator the quotients were multiplied by
    /// when no coefficient is a monomial (`common_denominator`); 0 if none.
    pub common_denominator: usize,
    /// When the part's count was above 1 and its solutions were filtered by
    /// the whole relation's kernel (io_check.rs): how many; 0 otherwise.
    pub checked_solutions: usize,
}

/// The route's answer on the parameters.
pub(super) struct IoCounts {
    /// Per parameter: its number of values (`None`: infinitely many).
    pub(super) per_param: Vec<Option<usize>>,
    pub(super) joint: Option<usize>,
    pub(super) sizes: Vec<IoSize>,
    /// The primes of the two counts (which agree).
    pub(super) primes: [u64; 2],
    /// Signed permutations of the parameters keeping every coefficient
    /// exactly (io_check.rs, `param_maps`).
    pub(super) maps: Vec<io_check::ParamMap>,
    /// With two solutions and no such map: the other solution as rational
    /// functions of the parameters, checked exactly on every coefficient.
    pub(super) rational_map: Option<Vec<obsan_recon::Rational>>,
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
    let theta: Vec<u64> = (0..np).map(|_| elem(&mut rng, P0)).collect();
    let pres = presentation(m, opts, &theta, &mut rng, (eliminate, cap), only)?;
    let (mp, perm) = (&pres.model, &pres.perm);
    let mut sizes: Vec<(usize, IoSize)> = Vec::new();
    // Per relation, its coefficients: first a generating part where one is
    // far simpler than the whole (`Part::Generating`), else all of them.
    let mut coeffs: Vec<Option<Coefficients>> = Vec::new();
    let mut memos: Vec<Memo> = Vec::new();
    for (i, (rel, &single)) in pres.rels.iter().zip(&pres.single).enumerate() {
        let out = perm[i];
        if !single && !opts.multi_experiment {
            return Err(err(format!(
                "global (io): the monomials of output {}'s relation satisfy more than one linear relation along an output (zero Wronskian): its coefficients count multi-experiment identifiability only (--multi-experiment counts it)",
                out + 1
            )));
        }
        sizes.push((
            out,
            IoSize {
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
                reconstructed: 0,
                common_denominator: 0,
                checked_solutions: 0,
            },
        ));
        // A monomial relation (`y' = 0`: Treatment's constant N) has no
        // coefficient to reconstruct and constrains no parameter.
        memos.push(Memo::default());
        if rel.support.len() < 2 {
            coeffs.push(None);
            continue;
        }
        let c = reconstruct(
            mp,
            &pres.orders,
            i,
            &rel.support,
            opts,
            seed,
            (Part::Generating, &mut memos[i]),
        )?;
        coeffs.push(Some(c));
    }
    // Two independent points and primes must agree, as on the Taylor route.
    let primes = [IO_PRIMES[0], IO_PRIMES[1]];
    // Every relation's fractions, in one list (the counts' equations).
    let all_fns = |coeffs: &[Option<Coefficients>]| -> Vec<(RPoly, RPoly)> {
        coeffs
            .iter()
            .flatten()
            .flat_map(|c| c.fns.iter().cloned())
            .collect()
    };
    let counts = |coeffs: &[Option<Coefficients>], zeros: bool| {
        let fns = all_fns(coeffs);
        let a = count(&fns, np, opts, seed, (primes[0], zeros))?;
        let b = count(&fns, np, opts, seed.wrapping_add(1), (primes[1], zeros))?;
        if (&a.per, a.joint) != (&b.per, b.joint) {
            return Err(err(
                "global (io): two independent random points disagree on the counts (a non-generic point); try another --seed",
            ));
        }
        Ok([a, b])
    };
    let parted = coeffs.iter().flatten().any(|c| c.part.is_some());
    let mut runs = counts(&coeffs, parted)?;
    let (mut per_param, mut joint) = (runs[0].per.clone(), runs[0].joint);
    // A part answers for the whole when every parameter is globally
    // identifiable or not locally identifiable over it (`generating_part`).
    // A count above 1 may be larger over a part: the part's solutions are
    // then kept where the whole relations' kernels are those of `theta*`,
    // and counted (io_check.rs); when they cannot be (a solution outside
    // F_q, no kernel), all the coefficients are reconstructed.
    let mut checked = 0;
    if parted && per_param.iter().any(|k| matches!(k, Some(k) if *k > 1)) {
        checked = runs[0].zeros.as_ref().map_or(0, |z| z.points.len());
        match whole_from_part(mp, &pres, &coeffs, &runs, opts, seed)? {
            Some((per, k)) => (per_param, joint) = (per, Some(k)),
            None => checked = 0,
        }
    }
    if checked == 0 && parted && per_param.iter().any(|k| matches!(k, Some(k) if *k > 1)) {
        for (i, c) in coeffs.iter_mut().enumerate() {
            if c.as_ref().is_some_and(|c| c.part.is_some()) {
                let spent = c.as_ref().map_or(0, |c| c.points);
                let mut all = reconstruct(
                    mp,
                    &pres.orders,
                    i,
                    &pres.rels[i].support,
                    opts,
                    seed,
                    (Part::All, &mut memos[i]),
                )?;
                all.points += spent;
                *c = Some(all);
            }
        }
        runs = counts(&coeffs, false)?;
        (per_param, joint) = (runs[0].per.clone(), runs[0].joint);
    }
    // The maps, on every coefficient only (a part's do not settle them).
    let whole = coeffs.iter().flatten().all(|c| c.part.is_none());
    let maps = match &runs[0].zeros {
        Some(z) if whole && joint.is_some_and(|k| k > 1) => {
            let fns = all_fns(&coeffs);
            io_check::param_maps(&fns, &z.points, &runs[0].star, primes[0])
        }
        _ => Vec::new(),
    };
    // Two solutions and no signed permutation between them: the other as
    // rational functions of the parameters (io_check.rs, `rational_map`).
    let rational_map = match &runs[0].zeros {
        Some(z) if whole && maps.is_empty() && joint == Some(2) && z.complete => {
            let fns = all_fns(&coeffs);
            let terms: usize = fns
                .iter()
                .map(|(n, d)| n.terms().len() + d.terms().len())
                .sum();
            if terms <= io_check::MAP_FN_TERMS {
                io_check::rational_map(&fns, np, opts, seed)?
            } else {
                None
            }
        }
        _ => None,
    };
    for ((_, size), c) in sizes.iter_mut().zip(&coeffs) {
        let Some(c) = c else { continue };
        let f = &c.fns;
        size.points = c.points;
        size.terms = f
            .iter()
            .map(|(n, d)| n.terms().len() + d.terms().len())
            .sum();
        size.max_degree = f
            .iter()
            .map(|(n, d)| n.degree().max(d.degree()))
            .max()
            .unwrap_or(0);
        size.recon_error_bound = c.error_bound;
        size.reconstructed = f.len();
        size.common_denominator = c.denominator_terms;
        size.checked_solutions = if c.part.is_some() { checked } else { 0 };
    }
    // The sizes in the outputs' own order.
    sizes.sort_by_key(|s| s.0);
    let sizes: Vec<IoSize> = sizes.into_iter().map(|s| s.1).collect();
    Ok(IoCounts {
        per_param,
        joint,
        sizes,
        primes,
        maps,
        rational_map,
    })
}

/// The whole's counts from the part's solutions (io_check.rs): at both
/// counts' points, those whose parted relations have their kernels at
/// `theta*`, counted; `None` when a solution lies outside `F_q`, the black
/// box gives no kernel, or the two points disagree.
#[allow(clippy::type_complexity)]
pub(super) fn whole_from_part(
    m: &ZModel,
    pres: &Presentation,
    coeffs: &[Option<Coefficients>],
    runs: &[Counted; 2],
    opts: &GlobalOptions,
    seed: u64,
) -> Result<Option<(Vec<Option<usize>>, usize)>, AnalysisError> {
    let mut found = Vec::with_capacity(2);
    for (run, &q) in runs.iter().zip(&IO_PRIMES[..2]) {
        let Some(io_check::Zeros {
            points: zeros,
            complete: true,
        }) = &run.zeros
        else {
            return Ok(None);
        };
        if !zeros.contains(&run.star) {
            return Ok(None);
        }
        let mut keep = vec![true; zeros.len()];
        for (i, c) in coeffs.iter().enumerate() {
            if c.as_ref().is_none_or(|c| c.part.is_none()) {
                continue;
            }
            let rel = (pres.orders.as_slice(), i, pres.rels[i].support.as_slice());
            let Some(same) = io_check::same_kernel(m, rel, opts, seed, q, &run.star, zeros)? else {
                return Ok(None);
            };
            keep.iter_mut().zip(same).for_each(|(k, s)| *k &= s);
        }
        let kept: Vec<&Vec<u64>> = zeros
            .iter()
            .zip(&keep)
            .filter(|z| *z.1)
            .map(|z| z.0)
            .collect();
        let local: Vec<bool> = run.per.iter().map(Option::is_some).collect();
        found.push(io_check::counts_over(&kept, &local));
    }
    Ok((found[0] == found[1]).then(|| found.swap_remove(0)))
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
    (want, memo): (Part, &mut Memo),
) -> Result<Coefficients, AnalysisError> {
    let (calls, remember) = (Cell::new(0u64), Cell::new(true));
    let mut kernels = Kernels {
        m,
        orders,
        i,
        support,
        opts,
        seed,
        calls: &calls,
        remember: &remember,
        models: HashMap::new(),
        memo,
    };
    // The kernel normalised by its last coefficient (which is 1).
    let mut coeffs = |pt: &[u64], p: u64| kernels.at(pt, p);
    let np = m.param_vars.len();
    // The axis lines' base point (module `normalisation`).
    let p0 = IO_PRIMES[0];
    let mut base_rng = Rng::new(seed ^ 0xde40);
    let base: Vec<u64> = (0..np).map(|_| elem(&mut base_rng, p0)).collect();
    let recon_err = |e: obsan_recon::ReconError<AnalysisError>| match e {
        obsan_recon::ReconError::BlackBox(e) => e,
        e => err(format!(
            "global (io): reconstructing the relations' coefficients: {e}"
        )),
    };
    let ropts = Options {
        deadline: opts.deadline,
        seed: seed ^ 0x10c0,
        prime_list: PrimeList::Bits52,
        ..Options::default()
    };
    // A part chosen before every quotient is probed (io_part.rs); the
    // whole's probes below then reuse the samples (Kernels remembers them).
    if want == Part::Generating {
        let early =
            io_part::early_part(&mut Axes::new(&mut coeffs, &base), np, support.len(), seed)?;
        if let Some(e) = early {
            if let Some(c) =
                early_coefficients(&e, np, &mut coeffs, &ropts, &calls).map_err(recon_err)?
            {
                return Ok(c);
            }
        }
    }
    let norm = normalisation(np, support.len(), &mut Axes::new(&mut coeffs, &base))?;
    let (j, alpha) = (norm.j, norm.alpha.clone());
    // Per quotient its degree in each parameter after the scaling, the
    // bounds if every one is a polynomial, the quotients' Jacobian at the
    // base point (from the same axis samples), and the common denominator
    // when no coefficient is a monomial (`common_denominator`).
    let (per_axis, bounds, jac, den) =
        scaling(&norm, &base, np, &mut coeffs, &ropts).map_err(recon_err)?;
    // Divided by a coefficient that is a monomial in the parameters and
    // scaled by their monomial denominators, or times the common
    // denominator, the coefficients are (mostly) polynomials, which need
    // far fewer points than rational functions.
    let mut bb = |pt: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
        let Some(v) = coeffs(pt, p)? else {
            return Ok(None);
        };
        let Some(iv) = obsan_recon::fp::inv(v[j], p) else {
            return Ok(None);
        };
        let iv = match &den {
            Some(d) => fmul(iv, d.eval_mod(pt, p), p),
            None => iv,
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
    // The scaling undone: the monomial, or the common denominator (left
    // unreduced, `Coefficients::fns`).
    let unscale = |f: &Rational, a: &[u32]| -> (RPoly, RPoly) {
        match &den {
            Some(d) => (f.num().clone(), f.den().times(d)),
            None => {
                let g = f.over_monomial(a);
                (g.num().clone(), g.den().clone())
            }
        }
    };
    let mut line = Line::new(np, support.len() - 1, seed);
    // A part first (`Part::Generating`): the simplest quotients whose
    // Jacobian has the whole one's rank, when they are far simpler. It is
    // chosen as the line's samples come (`select_part`): once the part's
    // quotients have their degrees and every other one is known to be past
    // the part's cap (SIWR_orig: 67 quotients of total degree at most 6,
    // where the largest of the 770 has 24 and took half the time).
    let part: Option<Vec<usize>> = match (want, &bounds, &per_axis, &jac) {
        (Part::Generating, Some(_), Some(pa), Some(jac)) => loop {
            // A denominator along the line: no part (nor polynomial bounds
            // for the whole, `Line::finish`).
            if line.rational() {
                break None;
            }
            if let Some(part) = select_part(&line.estimates(pa), jac, p0) {
                break part;
            }
            if !line.step(&mut bb)? {
                break None;
            }
        },
        _ => None,
    };
    // (No part chosen, or its interpolation not recognised: the whole, on
    // the same probes.)
    if let (Some(part), Some(per)) = (&part, &per_axis) {
        let d = line.degrees_of(part);
        let per: Vec<Vec<u32>> = part.iter().map(|&q| per[q].clone()).collect();
        let mut bbp = |pt: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
            Ok(bb(pt, p)?.map(|v| part.iter().map(|&q| v[q]).collect()))
        };
        remember.set(false);
        if let Some(r) = interpolate_part(np, &per, &d, &mut bbp, &ropts).map_err(recon_err)? {
            return Ok(Coefficients {
                fns: r
                    .functions
                    .iter()
                    .zip(part)
                    .map(|(f, &q)| unscale(f, &alpha[q]))
                    .collect(),
                error_bound: r.certificate.error_bound,
                points: calls.get(),
                part: Some(part.clone()),
                denominator_terms: den.as_ref().map_or(0, |d| d.terms().len()),
                divisor: j,
            });
        }
    }
    // With the total degree along one generic line: the per-axis bounds
    // alone put HIV's 10 parameters' largest monomial value `prod q_i^d_i`
    // past the prime (7e20), their total degree (a few) far below it. A
    // denominator along the line proves a quotient is no polynomial.
    let bounds = match bounds {
        Some(mut b) => line.finish(&mut bb)?.map(|d| {
            b.total = Some(d.iter().copied().max().unwrap_or(0));
            b
        }),
        None => None,
    };
    // Polynomials on every axis: sparse interpolation first (about twice
    // their terms in points), the rational reconstruction when it does not
    // recognise them; on random points, no longer remembered.
    remember.set(false);
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
    let r = match sparse {
        Some(r) => r,
        None => reconstruct_vec(np, support.len() - 1, &mut bb, &ropts).map_err(recon_err)?,
    };
    Ok(Coefficients {
        fns: r
            .functions
            .iter()
            .zip(&alpha)
            .map(|(f, a)| unscale(f, a))
            .collect(),
        error_bound: r.certificate.error_bound,
        points: calls.get(),
        part: None,
        denominator_terms: den.as_ref().map_or(0, |d| d.terms().len()),
        divisor: j,
    })
}

/// The relation's kernels at parameter points, one [`IoModel`] per prime;
/// the probes' points (axes and line, sampled again when the whole follows
/// a part chosen early) remembered while `remember` is set, up to
/// [`MEMO_BYTES`].
struct Kernels<'a> {
    m: &'a ZModel,
    orders: &'a [usize],
    i: usize,
    support: &'a [Vec<u32>],
    opts: &'a GlobalOptions,
    seed: u64,
    /// Kernels computed (the points reported).
    calls: &'a Cell<u64>,
    remember: &'a Cell<bool>,
    models: HashMap<u64, (IoModel, Rng)>,
    memo: &'a mut Memo,
}

/// The kernels a relation's reconstructions remember, by prime and point:
/// the axis and line probes and the common denominator's points, which
/// the whole's reconstruction after a part's (`Part::All` after
/// `Part::Generating`) asks for again (SEAIJRC: 1,360 of them, 200 s).
/// A kernel is unique, so it does not depend on which rows found it.
#[derive(Default)]
pub(super) struct Memo {
    map: HashMap<(u64, Vec<u64>), Option<Vec<u64>>>,
    bytes: usize,
}

/// Bytes of kernels a [`Memo`] holds at most, and at most a quarter of the
/// memory budget (SIWR_orig's probes: 150 points of 771 entries, under a
/// megabyte; SEAIJRC's, 1,360 of 1,465, 16 MB).
const MEMO_BYTES: usize = 64 << 20;

impl Kernels<'_> {
    /// The kernel at `pt` modulo `p`, normalised by its last coefficient.
    fn at(&mut self, pt: &[u64], p: u64) -> Result<Option<Vec<u64>>, AnalysisError> {
        let key = (p, pt.to_vec());
        if let Some(v) = self.memo.map.get(&key) {
            return Ok(v.clone());
        }
        self.calls.set(self.calls.get() + 1);
        if let std::collections::hash_map::Entry::Vacant(e) = self.models.entry(p) {
            let rng = Rng::new(self.seed ^ p);
            let mut io = IoModel::new(self.m, p)?;
            io.deadline = self.opts.deadline;
            io.max_bytes = self.opts.max_bytes;
            io.max_work = self.opts.max_io_work;
            e.insert((io, rng));
        }
        let Some((io, rng)) = self.models.get_mut(&p) else {
            return Ok(None);
        };
        let v = io.on_support(pt, self.orders, self.i, self.support, rng)?;
        let bytes = 8 * (pt.len() + v.as_ref().map_or(0, Vec::len));
        let cap = MEMO_BYTES.min(self.opts.max_bytes / 4);
        if self.remember.get() && self.memo.bytes + bytes <= cap {
            self.memo.bytes += bytes;
            self.memo.map.insert(key, v.clone());
        }
        Ok(v)
    }
}

/// The coefficients of a part chosen early (io_part.rs): its quotients by
/// `c_j`, times their monomials, interpolated sparsely within the probes'
/// degree bounds; `None` when they are not recognised as polynomials.
fn early_coefficients(
    e: &io_part::Early,
    np: usize,
    coeffs: &mut BlackBox<'_>,
    ropts: &Options,
    calls: &Cell<u64>,
) -> Result<Option<Coefficients>, obsan_recon::ReconError<AnalysisError>> {
    let mut bbp = |pt: &[u64], p: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
        let Some(v) = coeffs(pt, p)? else {
            return Ok(None);
        };
        let Some(iv) = obsan_recon::fp::inv(v[e.j], p) else {
            return Ok(None);
        };
        Ok(Some(
            e.part
                .iter()
                .zip(&e.alpha)
                .map(|(&q, a)| {
                    let c = fmul(v[quotient_index(q, e.j)], iv, p);
                    a.iter().zip(pt).fold(c, |acc, (&x, &t)| {
                        fmul(acc, obsan_recon::fp::pow(t, u64::from(x), p), p)
                    })
                })
                .collect(),
        ))
    };
    let r = interpolate_part(np, &e.per, &e.degrees, &mut bbp, ropts)?;
    Ok(r.map(|r| Coefficients {
        fns: r
            .functions
            .iter()
            .zip(&e.alpha)
            .map(|(f, a)| {
                let g = f.over_monomial(a);
                (g.num().clone(), g.den().clone())
            })
            .collect(),
        error_bound: r.certificate.error_bound,
        points: calls.get(),
        part: Some(e.part.clone()),
        denominator_terms: 0,
        divisor: e.j,
    }))
}

/// A part's scaled quotients (`bbp`) interpolated sparsely, each of
/// per-axis degrees `per[q]` and total degree `degrees[q]`.
fn interpolate_part<F>(
    np: usize,
    per: &[Vec<u32>],
    degrees: &[u32],
    bbp: &mut F,
    ropts: &Options,
) -> Result<Option<obsan_recon::Reconstruction>, obsan_recon::ReconError<AnalysisError>>
where
    F: FnMut(&[u64], u64) -> Result<Option<Vec<u64>>, AnalysisError>,
{
    let bounds = DegreeBounds {
        per_var: (0..np)
            .map(|k| per.iter().map(|d| d[k]).max().unwrap_or(0))
            .collect(),
        total: degrees.iter().copied().max(),
    };
    let sopts = Options {
        max_terms: MAX_SPARSE_TERMS,
        ..ropts.clone()
    };
    interpolate_polys_vec(np, per.len(), bbp, &sopts, &bounds)
}

/// Per quotient its degree in each parameter after the scaling, the bounds
/// if every one is then a polynomial, the quotients' Jacobian at the base
/// point, and the common denominator when no coefficient is a monomial.
type Scaling = (
    Option<Vec<Vec<u32>>>,
    Option<DegreeBounds>,
    Option<Vec<Vec<u64>>>,
    Option<RPoly>,
);

/// [`reconstruct`]'s [`Scaling`] from the normalisation's axis probes: the
/// monomial one, or [`common_denominator`]'s.
fn scaling(
    norm: &Normalised,
    base: &[u64],
    np: usize,
    bb: &mut BlackBox<'_>,
    ropts: &Options,
) -> Result<Scaling, obsan_recon::ReconError<AnalysisError>> {
    let p0 = IO_PRIMES[0];
    Ok(match (&norm.axes, &norm.quotients) {
        (Some(fr), _) => (
            Some(axis_degrees(fr, &norm.alpha)),
            polynomial_bounds(fr, &norm.alpha),
            axis_jacobian(fr, base, p0),
            None,
        ),
        (None, Some(q)) => match common_denominator(q, base, norm.j, np, bb, ropts)? {
            Some((d, per)) => {
                let per_var = (0..np)
                    .map(|k| per.iter().map(|q| q[k]).max().unwrap_or(0))
                    .collect();
                let bounds = DegreeBounds {
                    per_var,
                    total: None,
                };
                (Some(per), Some(bounds), axis_jacobian(q, base, p0), Some(d))
            }
            None => (None, None, None, None),
        },
        (None, None) => (None, None, None, None),
    })
}

/// Which of a relation's normalised coefficients [`reconstruct`] recovers.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Part {
    /// Every one.
    All,
    /// Only a part whose Jacobian has the whole one's rank, when it is far
    /// simpler than the whole ([`generating_part`]); else every one.
    Generating,
}

/// A relation's coefficients as fractions, the black-box points they
/// took, and which quotients they are (`None`: all of them).
pub(super) struct Coefficients {
    /// Per quotient, its numerator and denominator over Z; not always
    /// coprime (over a common denominator, `common_denominator`): the count
    /// saturates by the denominators, so a common factor adds no solution.
    pub(super) fns: Vec<(RPoly, RPoly)>,
    /// The bound of the reconstruction's check at fresh points.
    pub(super) error_bound: f64,
    pub(super) points: u64,
    pub(super) part: Option<Vec<usize>>,
    /// Terms of the common denominator (`common_denominator`), 0 if none.
    pub(super) denominator_terms: usize,
    /// The coefficient `c_j` the quotients are `c_m / c_j` of (quotient `q`
    /// is `c_m`, `m = quotient_index(q, j)`).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) divisor: usize,
}

/// How much simpler (in monomials the bounds allow) the part must be than
/// the whole for [`Part::Generating`] to be tried: a part that does not
/// settle the count costs its points on top of the whole's.
const PART_GAIN: usize = 16;

/// The simplest quotients (by the monomials their degree bounds allow,
/// `est`) whose Jacobian rows at the base point reach the rank of all of
/// them, then every quotient no more complex than twice the last one taken
/// (a larger field, more often all the parameters); `None` when that part
/// is not [`PART_GAIN`] times simpler than the whole, or is the whole.
///
/// Why a part may answer for the whole (io_count_under): its coefficients
/// generate a subfield `K'` of the field `K` of all of them. A parameter in
/// `K'` is in `K` (globally identifiable); the Jacobians have the same rank,
/// so `K'` and `K` have the same transcendence degree and the same
/// parameters are locally identifiable. Only a count `k > 1` over `K'` may
/// be larger than over `K`: then the part's solutions are filtered by the
/// whole relation's kernel (io_check.rs), or else the whole is
/// reconstructed.
#[cfg(test)]
fn generating_part(est: &[usize], jac: &[Vec<u64>], p: u64) -> Option<Vec<usize>> {
    let exact: Vec<Estimate> = est.iter().map(|&e| Estimate::Exact(e)).collect();
    select_part(&exact, jac, p).flatten()
}

/// A quotient's size estimate (the monomials its degree bounds allow): its
/// own, or a lower bound while its degree along the line is not known.
#[derive(Clone, Copy, Debug)]
pub(super) enum Estimate {
    Exact(usize),
    AtLeast(usize),
}

impl Estimate {
    pub(super) fn low(self) -> usize {
        match self {
            Estimate::Exact(e) | Estimate::AtLeast(e) => e,
        }
    }
}

/// [`generating_part`] from estimates some of which are lower bounds:
/// `Some(answer)` when the lower bounds already decide it (the answer the
/// exact estimates would give), `None` while they do not. Why it is the
/// same answer: the prefix that reaches the rank holds exact estimates
/// only, and every inexact one is past the cap, hence past the prefix in the
/// exact order too; the whole's size is at least the largest lower bound.
fn select_part(est: &[Estimate], jac: &[Vec<u64>], p: u64) -> Option<Option<Vec<usize>>> {
    let full = obsan_recon::fp::rank(Zp(p), jac.iter().cloned());
    select_ranked(est, jac, p, full)
}

/// [`select_part`] when the whole Jacobian's rank is known to be `full`
/// (io_part.rs: every parameter, `np`, reached by rows known so far).
pub(super) fn select_ranked(
    est: &[Estimate],
    jac: &[Vec<u64>],
    p: u64,
    full: usize,
) -> Option<Option<Vec<usize>>> {
    if full == 0 {
        return Some(None);
    }
    let mut order: Vec<usize> = (0..est.len()).collect();
    order.sort_by_key(|&q| (est[q].low(), q));
    let mut ech = Echelon::new(Zp(p));
    let mut last = 0;
    for &q in &order {
        let Estimate::Exact(e) = est[q] else {
            return None;
        };
        ech.insert(jac[q].clone());
        if ech.rank() == full {
            last = e;
            break;
        }
    }
    let cap = last.saturating_mul(2).max(8);
    if est
        .iter()
        .any(|e| matches!(e, Estimate::AtLeast(l) if *l <= cap))
    {
        return None;
    }
    let part: Vec<usize> = order.into_iter().filter(|&q| est[q].low() <= cap).collect();
    let exact = est.iter().all(|e| matches!(e, Estimate::Exact(_)));
    let whole = est.iter().map(|e| e.low()).max().unwrap_or(0);
    if part.len() == est.len() {
        return Some(None);
    }
    if whole < cap.saturating_mul(PART_GAIN) {
        return if exact { Some(None) } else { None };
    }
    let mut part = part;
    part.sort_unstable();
    Some(Some(part))
}

/// Per quotient, its degree in each parameter along that parameter's axis
/// line (`polynomial_bounds`, quotient by quotient).
fn axis_degrees(axes: &[Vec<Fraction>], alpha: &[Vec<u32>]) -> Vec<Vec<u32>> {
    let deg = |v: &[u64]| v.iter().rposition(|&c| c != 0).unwrap_or(0) as i64;
    let ord = |v: &[u64]| v.iter().position(|&c| c != 0).unwrap_or(0) as i64;
    (0..alpha.len())
        .map(|q| {
            axes.iter()
                .enumerate()
                .map(|(k, fr)| {
                    let (num, den) = &fr[q];
                    (deg(num) + i64::from(alpha[q][k]) - ord(den)).max(0) as u32
                })
                .collect()
        })
        .collect()
}

/// The quotients' Jacobian at the axis lines' base point: row `q`, column
/// `k` is the derivative of quotient `q`'s fraction along axis `k` at
/// `base[k]`; `None` when a denominator vanishes there.
fn axis_jacobian(axes: &[Vec<Fraction>], base: &[u64], p: u64) -> Option<Vec<Vec<u64>>> {
    let n = axes.first().map_or(0, |fr| fr.len());
    let mut jac = vec![vec![0u64; axes.len()]; n];
    for (k, fr) in axes.iter().enumerate() {
        for (q, (num, den)) in fr.iter().enumerate() {
            jac[q][k] = fraction_derivative(num, den, base[k], p)?;
        }
    }
    Some(jac)
}

/// `d/dt (num/den)` at `t0` modulo `p` (coefficients lowest degree first).
pub(super) fn fraction_derivative(num: &[u64], den: &[u64], t0: u64, p: u64) -> Option<u64> {
    use obsan_recon::fp::{add, sub};
    // Value and derivative by Horner.
    let eval = |c: &[u64]| -> (u64, u64) {
        let (mut v, mut d) = (0u64, 0u64);
        for &a in c.iter().rev() {
            d = add(fmul(d, t0, p), v, p);
            v = add(fmul(v, t0, p), a, p);
        }
        (v, d)
    };
    let (n, dn) = eval(num);
    let (d, dd) = eval(den);
    let inv = obsan_recon::fp::inv(fmul(d, d, p), p)?;
    Some(fmul(sub(fmul(dn, d, p), fmul(n, dd, p), p), inv, p))
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
    if !axes.iter().flatten().all(|(_, den)| is_monomial(den)) {
        return None;
    }
    let per_q = axis_degrees(axes, alpha);
    let per_var = (0..axes.len())
        .map(|k| per_q.iter().map(|d| d[k]).max().unwrap_or(0))
        .collect();
    Some(DegreeBounds {
        per_var,
        total: None,
    })
}

/// The largest total degree of the black box's `m` functions, from one
/// univariate interpolation each along a random line `a + t b` (a polynomial's
/// degree along a generic line is its total degree); `None` when one has a
/// denominator there (not a polynomial) or the samples run out.
#[cfg(test)]
fn line_degree(
    bb: &mut BlackBox<'_>,
    np: usize,
    m: usize,
    seed: u64,
) -> Result<Option<u32>, AnalysisError> {
    Ok(line_degrees(bb, np, m, seed)?.map(|d| d.into_iter().max().unwrap_or(0)))
}

/// Each of the black box's `m` functions' total degree ([`line_degree`]).
#[cfg(test)]
fn line_degrees(
    bb: &mut BlackBox<'_>,
    np: usize,
    m: usize,
    seed: u64,
) -> Result<Option<Vec<u32>>, AnalysisError> {
    Line::new(np, m, seed).finish(bb)
}

/// The random line `a + t b` of the total degrees ([`Line`], and io_part.rs's
/// `RawLine` on the same points): `a` and `b`.
pub(super) fn line_ends(np: usize, seed: u64) -> (Vec<u64>, Vec<u64>) {
    let mut rng = Rng::new(seed ^ 0x1e4e);
    let a = (0..np).map(|_| elem(&mut rng, P0)).collect();
    let b = (0..np).map(|_| elem(&mut rng, P0)).collect();
    (a, b)
}

/// The point `a + t b` modulo [`P0`].
pub(super) fn line_point(a: &[u64], b: &[u64], t: u64) -> Vec<u64> {
    a.iter()
        .zip(b)
        .map(|(&x, &y)| obsan_recon::fp::add(x, fmul(t, y, P0), P0))
        .collect()
}

/// The black box's functions along one random line `a + t b`, sampled at
/// `t = 1, 2, ...`, one univariate interpolation each: their total degrees
/// ([`line_degree`]), sampled only as far as a caller needs.
struct Line {
    a: Vec<u64>,
    b: Vec<u64>,
    th: Vec<Univariate>,
    t: u64,
    misses: usize,
}

impl Line {
    fn new(np: usize, m: usize, seed: u64) -> Line {
        let (a, b) = line_ends(np, seed);
        Line {
            a,
            b,
            th: (0..m).map(|_| Univariate::new(P0, AGREE)).collect(),
            t: 0,
            misses: 0,
        }
    }

    /// One more sample, for the functions not yet done; false when the
    /// samples have run out (too many bad points, or too many samples).
    fn step(&mut self, bb: &mut BlackBox<'_>) -> Result<bool, AnalysisError> {
        let p = IO_PRIMES[0];
        loop {
            self.t += 1;
            if self.misses > 8 || self.t as usize > MAX_AXIS_SAMPLES {
                return Ok(false);
            }
            let pt = line_point(&self.a, &self.b, self.t);
            let Some(v) = bb(&pt, p)? else {
                self.misses += 1;
                continue;
            };
            for (x, c) in self.th.iter_mut().zip(v) {
                if !x.done() {
                    x.add(self.t, c);
                }
            }
            return Ok(true);
        }
    }

    /// Function `q`'s degree once its interpolation is done: `Some(Ok(d))`
    /// for a polynomial, `Some(Err(()))` when it has a denominator.
    fn degree(&self, q: usize) -> Option<Result<u32, ()>> {
        let x = &self.th[q];
        if !x.done() {
            return None;
        }
        let (num, den) = x.rational();
        if den.iter().skip(1).any(|&c| c != 0) {
            return Some(Err(()));
        }
        Some(Ok(num.iter().rposition(|&c| c != 0).unwrap_or(0) as u32))
    }

    /// Whether a function done so far has a denominator along the line.
    fn rational(&self) -> bool {
        (0..self.th.len()).any(|q| matches!(self.degree(q), Some(Err(()))))
    }

    /// Per function its size estimate under its per-axis degrees `per`: with
    /// its degree when known, else with the least degree its samples allow
    /// (a polynomial of degree `d` is done after `d + 1 + AGREE` samples, so
    /// `k` samples and not done mean `d >= k - AGREE`). A
    /// function with a denominator (the caller stops first: `rational`)
    /// is left at its lower bound.
    fn estimates(&self, per: &[Vec<u32>]) -> Vec<Estimate> {
        (0..self.th.len())
            .map(|q| {
                let size = |t: u32| {
                    DegreeBounds {
                        per_var: per[q].clone(),
                        total: Some(t),
                    }
                    .monomials()
                };
                match self.degree(q) {
                    Some(Ok(d)) => Estimate::Exact(size(d)),
                    _ => Estimate::AtLeast(size(self.th[q].len().saturating_sub(AGREE) as u32)),
                }
            })
            .collect()
    }

    /// The degrees of the functions in `part` (each done and a polynomial:
    /// `select_part` took only exact estimates into a part).
    fn degrees_of(&self, part: &[usize]) -> Vec<u32> {
        part.iter()
            .map(|&q| match self.degree(q) {
                Some(Ok(d)) => d,
                _ => 0,
            })
            .collect()
    }

    /// Every function's degree (sampling on until each is done), or `None`
    /// when one has a denominator along the line or the samples run out.
    fn finish(mut self, bb: &mut BlackBox<'_>) -> Result<Option<Vec<u32>>, AnalysisError> {
        while self.th.iter().any(|x| !x.done()) {
            if !self.step(bb)? {
                return Ok(None);
            }
        }
        Ok((0..self.th.len())
            .map(|q| self.degree(q).and_then(Result::ok))
            .collect())
    }
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

pub(super) fn is_monomial(v: &[u64]) -> bool {
    v.iter().filter(|&&c| c != 0).count() == 1
}

/// Samples of the black box along the axis lines `theta_k = t` (the other
/// parameters at one random point), and per coefficient divided by and
/// per axis one univariate interpolation per quotient, fed as far as asked:
/// every normalisation tried, and the part chosen early (io_part.rs), reuse
/// both.
pub(super) struct Axes<'a, 'b> {
    bb: &'a mut BlackBox<'b>,
    base: Vec<u64>,
    samples: Vec<Vec<(u64, Vec<u64>)>>,
    next_t: Vec<u64>,
    misses: usize,
    /// Per divisor `j`, per axis: the samples fed, and the interpolations
    /// (from the first sample where `v_j` does not vanish).
    probes: HashMap<usize, Vec<Probe>>,
}

/// One axis's interpolations of the quotients by one coefficient.
#[derive(Default)]
struct Probe {
    fed: usize,
    th: Option<Vec<Univariate>>,
}

/// A univariate fraction modulo p: numerator and denominator coefficients,
/// lowest degree first (`Univariate`'s reduced form).
type Fraction = (Vec<u64>, Vec<u64>);

/// Consecutive samples a univariate fraction must predict before it is
/// taken for the function (`Univariate`'s early termination).
pub(super) const AGREE: usize = 2;

/// Samples per axis before a probe gives up (the coefficients' degrees
/// along a line are 14 for Goodwin, 12 for SIWR_multiout).
pub(super) const MAX_AXIS_SAMPLES: usize = 400;

/// The entry of the black box's vector that is quotient `q` by coefficient
/// `j` (the quotients leave `j` out, `others`).
pub(super) fn quotient_index(q: usize, j: usize) -> usize {
    if q < j {
        q
    } else {
        q + 1
    }
}

impl<'a, 'b> Axes<'a, 'b> {
    pub(super) fn new(bb: &'a mut BlackBox<'b>, base: &[u64]) -> Self {
        Axes {
            bb,
            base: base.to_vec(),
            samples: vec![Vec::new(); base.len()],
            next_t: vec![1; base.len()],
            misses: 0,
            probes: HashMap::new(),
        }
    }

    pub(super) fn base(&self) -> &[u64] {
        &self.base
    }

    /// The black box at `pt` modulo the probes' prime.
    pub(super) fn call(&mut self, pt: &[u64]) -> Result<Option<Vec<u64>>, AnalysisError> {
        (self.bb)(pt, P0)
    }

    /// Along axis `k`, the quotients by coefficient `j` fed with the first
    /// `cap` samples, or fewer once every one is done; false when the
    /// samples run out first.
    pub(super) fn advance(
        &mut self,
        k: usize,
        j: usize,
        cap: usize,
    ) -> Result<bool, AnalysisError> {
        let np = self.samples.len();
        let mut probe = std::mem::take(
            &mut self
                .probes
                .entry(j)
                .or_insert_with(|| (0..np).map(|_| Probe::default()).collect())[k],
        );
        let r = self.feed(k, j, cap, &mut probe);
        if let Some(ps) = self.probes.get_mut(&j) {
            ps[k] = probe;
        }
        r
    }

    fn feed(
        &mut self,
        k: usize,
        j: usize,
        cap: usize,
        pr: &mut Probe,
    ) -> Result<bool, AnalysisError> {
        while pr.fed < cap && pr.th.as_ref().is_none_or(|th| th.iter().any(|x| !x.done())) {
            while self.samples[k].len() <= pr.fed {
                if self.misses > 8 || pr.fed >= MAX_AXIS_SAMPLES {
                    return Ok(false);
                }
                let mut pt = self.base.clone();
                pt[k] = self.next_t[k];
                self.next_t[k] += 1;
                match (self.bb)(&pt, P0)? {
                    Some(v) => self.samples[k].push((pt[k], v)),
                    None => self.misses += 1,
                }
            }
            let (t, v) = &self.samples[k][pr.fed];
            pr.fed += 1;
            let Some(iv) = obsan_recon::fp::inv(v[j], P0) else {
                continue;
            };
            let th = pr
                .th
                .get_or_insert_with(|| (1..v.len()).map(|_| Univariate::new(P0, AGREE)).collect());
            for (x, c) in th.iter_mut().zip(others(v, j)) {
                if !x.done() {
                    x.add(*t, fmul(c, iv, P0));
                }
            }
        }
        Ok(true)
    }

    /// Along axis `k`, the interpolations of the quotients by `j` so far.
    pub(super) fn probes(&self, k: usize, j: usize) -> Option<&[Univariate]> {
        self.probes.get(&j)?.get(k)?.th.as_deref()
    }

    /// Along axis `k`, the reduced fractions `v_m / v_j` (`m != j`), `v` the
    /// black box's vector; `None` when the samples run out.
    fn fractions(&mut self, k: usize, j: usize) -> Result<Option<Vec<Fraction>>, AnalysisError> {
        if !self.advance(k, j, usize::MAX)? {
            return Ok(None);
        }
        Ok(self
            .probes(k, j)
            .map(|th| th.iter().map(Univariate::rational).collect()))
    }
}

/// Which of the `n` coefficients to divide the others by, and per quotient
/// the exponents `a` of a monomial `theta^a` dividing its denominator.
///
/// Along each axis line `theta_k = t` (the other parameters at a random
/// point) one univariate interpolation per quotient gives its pole order at
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
fn normalisation(
    np: usize,
    n: usize,
    axes: &mut Axes<'_, '_>,
) -> Result<Normalised, AnalysisError> {
    let ord = |v: &[u64]| v.iter().position(|&c| c != 0).unwrap_or(0) as i64;
    let fallback = Normalised {
        j: n - 1,
        alpha: vec![vec![0u32; np]; n - 1],
        axes: None,
        quotients: None,
    };
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
        return Ok(Normalised {
            j: n - 1,
            alpha: alpha_of(&by_last),
            axes: Some(by_last),
            quotients: None,
        });
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
            return Ok(Normalised {
                j,
                alpha: alpha_of(&fr),
                axes: Some(fr),
                quotients: None,
            });
        }
    }
    // No monomial coefficient: divide by the one of fewest monomials (its
    // degrees along each axis read off the quotients by the last, whose
    // denominators' lcm there is the last coefficient's restriction), which
    // is then the quotients' common denominator (`common_denominator`).
    let lcms: Vec<Vec<u64>> = by_last
        .iter()
        .map(|fr| fr.iter().fold(vec![1], |l, (_, d)| ulcm(&l, d, P0)))
        .collect();
    let size = |m: usize| -> usize {
        by_last
            .iter()
            .zip(&lcms)
            .map(|(fr, l)| match fr.get(m) {
                Some((num, den)) => (udeg(num) + udeg(l)).saturating_sub(udeg(den)) + 1,
                None => udeg(l) + 1,
            })
            .fold(1usize, usize::saturating_mul)
    };
    let j = (0..n).min_by_key(|&m| (size(m), n - m)).unwrap_or(n - 1);
    let mut quotients = Vec::with_capacity(np);
    if j != n - 1 {
        for k in 0..np {
            match axes.fractions(k, j)? {
                Some(f) => quotients.push(f),
                None => break,
            }
        }
    }
    if quotients.len() == np {
        return Ok(Normalised {
            j,
            alpha: vec![vec![0u32; np]; n - 1],
            axes: None,
            quotients: Some(quotients),
        });
    }
    Ok(Normalised {
        j: n - 1,
        alpha: vec![vec![0u32; np]; n - 1],
        axes: None,
        quotients: Some(by_last),
    })
}

/// The first reconstruction prime (the axis probes' field).
pub(super) const P0: u64 = IO_PRIMES[0];

/// The input-output route's primes: its black box is a dense kernel modulo
/// the prime ([`Kernels`]), which runs on AVX-512 IFMA (3.5-4x) modulo
/// these 52-bit primes where the CPU has it; the same primes on every CPU,
/// so that the answers do not depend on it.
pub(super) const IO_PRIMES: &[u64; obsan_recon::PRIMES.len()] = &obsan_recon::PRIMES52;

/// A least common multiple of univariate polynomials modulo `p`.
fn ulcm(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let g = ugcd(a, b, p);
    umul(&udiv(a, &g, p), b, p)
}

/// [`normalisation`]'s choice.
struct Normalised {
    /// The coefficient the others are divided by.
    j: usize,
    /// Per quotient, the monomial `theta^alpha` it is multiplied by.
    alpha: Vec<Vec<u32>>,
    /// Per axis, the quotients by `c_j` when every one has a monomial
    /// denominator there; `None` otherwise.
    axes: Option<Vec<Vec<Fraction>>>,
    /// When no coefficient gave monomial denominators: per axis, the
    /// quotients by `c_j` (`alpha` zero), for [`common_denominator`].
    quotients: Option<Vec<Vec<Fraction>>>,
}

/// When no coefficient is a monomial (MAPK_5out's relations over several
/// experiments): the quotients' common denominator `D`, exactly, and per
/// quotient its degree in each parameter once multiplied by `D`.
///
/// The relation's coefficients have no common factor, so the least common
/// multiple of the reduced quotients `c_m / c_last` is `c_last` itself up
/// to a constant; along each axis line (generic) it is the lcm of their
/// univariate denominators. A few quotients whose denominators are coprime
/// along every axis and whose product is divisible by every other one's
/// there are chosen (greedily, smallest numerators first among those that
/// add the most degree), reconstructed alone as rational functions
/// (`reconstruct_vec`, verified at fresh points), and the product of their
/// denominators is `D`: generically the lcm. The quotients times `D` are
/// then polynomials, interpolated sparsely with the degree bounds
/// `deg n_m + deg D - deg d_m` per axis. A non-generic axis can only make
/// the choice wrong, never the answer: the products are then no
/// polynomials, the sparse interpolation does not recognise them and the
/// rational reconstruction takes them (times `D`, undone exactly). `None`
/// when no such choice exists.
#[allow(clippy::type_complexity)]
fn common_denominator(
    quotients: &[Vec<Fraction>],
    base: &[u64],
    j: usize,
    np: usize,
    bb: &mut BlackBox<'_>,
    ropts: &Options,
) -> Result<Option<(RPoly, Vec<Vec<u32>>)>, obsan_recon::ReconError<AnalysisError>> {
    let p = IO_PRIMES[0];
    let nq = quotients.first().map_or(0, Vec::len);
    // Per axis, the product of the chosen denominators so far (a multiple
    // of their lcm there: enough to tell when every one divides it).
    let mut cur: Vec<Vec<u64>> = vec![vec![1]; quotients.len()];
    let mut chosen: Vec<usize> = Vec::new();
    // A quotient's numerator size: the monomials its axis degrees allow.
    let size = |m: usize| {
        quotients
            .iter()
            .map(|fr| udeg(&fr[m].0) + 1)
            .fold(1usize, usize::saturating_mul)
    };
    let covered = |cur: &[Vec<u64>]| {
        quotients
            .iter()
            .zip(cur)
            .all(|(fr, c)| fr.iter().all(|(_, d)| divides(d, c, p)))
    };
    while !covered(&cur) {
        // The quotient of the smallest numerator (the monomials its
        // degrees allow) whose denominator adds a factor on some axis; ties
        // to the most degree added.
        let best = (0..nq)
            .filter(|m| !chosen.contains(m))
            .filter_map(|m| {
                let mut gain = 0;
                for (fr, c) in quotients.iter().zip(&cur) {
                    let d = &fr[m].1;
                    gain += udeg(d) - udeg(&ugcd(d, c, p));
                }
                (gain > 0).then_some((std::cmp::Reverse(size(m)), gain, m))
            })
            .max();
        let Some((_, _, m)) = best else {
            return Ok(None);
        };
        for (fr, c) in quotients.iter().zip(cur.iter_mut()) {
            *c = umul(c, &fr[m].1, p);
        }
        chosen.push(m);
    }
    if chosen.is_empty() {
        return Ok(None);
    }
    // The chosen quotients reconstructed as rational functions, and the
    // common multiple of their denominators built below; while it misses a
    // quotient's denominator on some axis, that quotient (the smallest
    // such) is chosen and reconstructed too. The product above counts a
    // repeated factor twice where the multiple built holds it once:
    // SEAIJRC's held `r^2` times a binomial where some quotients need `r^3`
    // (session 43), so they were no polynomials times it and went to the
    // dense rational reconstruction, which did not finish. (Each call's
    // points are the first one's, remembered: the repeats cost no kernel.)
    let mut dens: Vec<RPoly> = Vec::new();
    let mut todo = chosen.clone();
    let (mono, mut rests) = loop {
        let mut some = |pt: &[u64], q: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
            let Some(v) = bb(pt, q)? else {
                return Ok(None);
            };
            let Some(iv) = obsan_recon::fp::inv(v[j], q) else {
                return Ok(None);
            };
            let quo: Vec<u64> = others(&v, j).collect();
            Ok(Some(todo.iter().map(|&m| fmul(quo[m], iv, q)).collect()))
        };
        let r = reconstruct_vec(np, todo.len(), &mut some, ropts)?;
        dens.extend(r.functions.iter().map(|f| f.den().clone()));
        let refs: Vec<&RPoly> = dens.iter().collect();
        let (mono, rests) = factors(&refs, np);
        let d = product(&mono, &rests);
        let dks: Vec<Vec<u64>> = (0..quotients.len())
            .map(|k| restrict(&d, base, k, p))
            .collect();
        let missed = (0..nq)
            .filter(|m| !chosen.contains(m))
            .filter(|&m| {
                quotients
                    .iter()
                    .zip(&dks)
                    .any(|(fr, dk)| !divides(&fr[m].1, dk, p))
            })
            .min_by_key(|&m| (size(m), m));
        match missed {
            None => break (mono, rests),
            Some(m) => {
                chosen.push(m);
                todo = vec![m];
            }
        }
    };
    // A factor shared by two denominators (a binomial dividing a larger
    // one) is counted twice: dropped while the product, restricted to each
    // axis line, stays divisible by every quotient's denominator there.
    let covers = |rests: &[RPoly]| {
        let d = product(&mono, rests);
        quotients.iter().enumerate().all(|(k, fr)| {
            let dk = restrict(&d, base, k, p);
            fr.iter().all(|(_, den)| divides(den, &dk, p))
        })
    };
    // (The whole product covers now; checked, since one that did not would
    // send the scaled quotients, no polynomials, to the rational
    // reconstruction's many points.)
    if !covers(&rests) {
        return Ok(None);
    }
    for i in (0..rests.len()).rev() {
        let mut fewer = rests.clone();
        fewer.remove(i);
        if covers(&fewer) {
            rests = fewer;
        }
    }
    let d = product(&mono, &rests);
    // Along axis k (generic base) D has its degree in theta_k.
    let dk: Vec<usize> = (0..np)
        .map(|k| {
            d.terms()
                .iter()
                .map(|t| t.exps.get(k).copied().unwrap_or(0))
                .max()
                .unwrap_or(0) as usize
        })
        .collect();
    let per = (0..nq)
        .map(|m| {
            quotients
                .iter()
                .zip(&dk)
                .map(|(fr, &e)| (udeg(&fr[m].0) + e).saturating_sub(udeg(&fr[m].1)) as u32)
                .collect()
        })
        .collect();
    Ok(Some((d, per)))
}

/// `poly` on the axis line `theta_k = t` (the others at `base`), modulo
/// `p`: its coefficients in `t`, lowest first.
fn restrict(poly: &RPoly, base: &[u64], k: usize, p: u64) -> Vec<u64> {
    let mut out = vec![0u64];
    for t in poly.terms() {
        let e = t.exps.get(k).copied().unwrap_or(0) as usize;
        let mut rest = t.clone();
        if let Some(x) = rest.exps.get_mut(k) {
            *x = 0;
        }
        let v = RPoly::from_terms([rest]).eval_mod(base, p);
        if out.len() <= e {
            out.resize(e + 1, 0);
        }
        out[e] = obsan_recon::fp::add(out[e], v, p);
    }
    out
}

/// The monomial times the product of the factors.
fn product(mono: &[u32], rests: &[RPoly]) -> RPoly {
    let one = RPoly::from_terms([obsan_recon::Term {
        exps: mono.to_vec(),
        coeff: 1.into(),
    }]);
    rests.iter().fold(one, |acc, r| acc.times(r))
}

/// A common multiple of `dens`, close to their lcm without a multivariate
/// gcd: the largest monomial factor of each, then the product of the
/// remaining factors that differ up to a constant (any common multiple
/// keeps the products polynomials, only larger; `common_denominator` drops
/// the factors it can).
#[cfg(test)]
fn lcm_multiple(dens: &[&RPoly], np: usize) -> RPoly {
    let (mono, rests) = factors(dens, np);
    product(&mono, &rests)
}

/// [`lcm_multiple`]'s largest monomial and its other factors.
fn factors(dens: &[&RPoly], np: usize) -> (Vec<u32>, Vec<RPoly>) {
    use obsan_recon::Term;
    let mut mono = vec![0u32; np];
    let mut rests: Vec<RPoly> = Vec::new();
    for d in dens {
        let low: Vec<u32> = (0..np)
            .map(|k| {
                d.terms()
                    .iter()
                    .map(|t| t.exps.get(k).copied().unwrap_or(0))
                    .min()
                    .unwrap_or(0)
            })
            .collect();
        for (m, &l) in mono.iter_mut().zip(&low) {
            *m = (*m).max(l);
        }
        let rest = RPoly::from_terms(d.terms().iter().map(|t| {
            Term {
                exps: (0..np)
                    .map(|k| t.exps.get(k).copied().unwrap_or(0) - low[k])
                    .collect(),
                coeff: t.coeff.clone(),
            }
        }));
        let proportional = |a: &RPoly, b: &RPoly| {
            a.terms().len() == b.terms().len()
                && a.terms().iter().zip(b.terms()).all(|(x, y)| {
                    x.exps == y.exps
                        && &x.coeff * &b.terms()[0].coeff == &y.coeff * &a.terms()[0].coeff
                })
        };
        if rest.terms().len() > 1 && !rests.iter().any(|r| proportional(r, &rest)) {
            rests.push(rest);
        }
    }
    (mono, rests)
}

/// The degree of a univariate polynomial (coefficients lowest first).
pub(super) fn udeg(a: &[u64]) -> usize {
    a.iter().rposition(|&c| c != 0).unwrap_or(0)
}

/// The product of univariate polynomials modulo `p`.
pub(super) fn umul(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let (a, b) = (&a[..=udeg(a)], &b[..=udeg(b)]);
    let mut out = vec![0u64; a.len() + b.len() - 1];
    for (i, &x) in a.iter().enumerate() {
        for (j, &y) in b.iter().enumerate() {
            out[i + j] = obsan_recon::fp::add(out[i + j], fmul(x, y, p), p);
        }
    }
    out
}

/// A greatest common divisor of univariate polynomials modulo `p`
/// (Euclid; up to a constant).
pub(super) fn ugcd(a: &[u64], b: &[u64], p: u64) -> Vec<u64> {
    let (mut a, mut b) = (a.to_vec(), b.to_vec());
    while b.iter().any(|&c| c != 0) {
        let r = urem(&a, &b, p);
        a = b;
        b = r;
    }
    a
}

/// The quotient of `b` divided by `a` modulo `p` (`a` not zero; the
/// remainder dropped).
pub(super) fn udiv(b: &[u64], a: &[u64], p: u64) -> Vec<u64> {
    udivrem(b, a, p).0
}

/// The remainder of `b` divided by `a` modulo `p` (`a` not zero).
pub(super) fn urem(b: &[u64], a: &[u64], p: u64) -> Vec<u64> {
    udivrem(b, a, p).1
}

/// The quotient and remainder of `b` divided by `a` modulo `p` (`a` not
/// zero; coefficients lowest degree first).
fn udivrem(b: &[u64], a: &[u64], p: u64) -> (Vec<u64>, Vec<u64>) {
    use obsan_recon::fp::sub;
    let da = udeg(a);
    let il = obsan_recon::fp::inv(a[da], p).unwrap_or(0);
    let mut r: Vec<u64> = b.to_vec();
    let mut q = vec![0u64; udeg(b).saturating_sub(da) + 1];
    while let Some(dr) = r.iter().rposition(|&c| c != 0) {
        if dr < da {
            break;
        }
        let c = fmul(r[dr], il, p);
        q[dr - da] = c;
        for (i, &ai) in a[..=da].iter().enumerate() {
            let k = dr - da + i;
            r[k] = sub(r[k], fmul(c, ai, p), p);
        }
    }
    (q, r)
}

/// Whether `a` divides `b` modulo `p` (coefficients lowest degree first;
/// `a` not zero).
fn divides(a: &[u64], b: &[u64], p: u64) -> bool {
    a.iter().any(|&c| c != 0) && urem(b, a, p).iter().all(|&c| c == 0)
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

/// The count's system at `star` (the parameters' values) over `ring`'s
/// field: `c_i(theta) = c_i(star)`, the parameters that are not locally
/// identifiable there sliced at `star`, and `z L(theta) = 1`; with which
/// parameters are locally identifiable. `None` when a denominator vanishes
/// at `star`.
#[allow(clippy::type_complexity)]
pub(super) fn system_at(
    fns: &[(RPoly, RPoly)],
    ring: &Ring,
    star: &[u64],
    opts: &GlobalOptions,
) -> Result<Option<(Vec<Poly>, Vec<bool>)>, AnalysisError> {
    let (q, np) = (ring.field.modulus(), ring.n - 1);
    // The point with z = 0 beside it (z enters no equation evaluated here).
    let star: Vec<u64> = star.iter().copied().chain([0]).collect();
    let mut eqs = Vec::new();
    let mut dens: Vec<Poly> = Vec::new();
    for (fn_, fd) in fns {
        let (n, d) = (to_fp(fn_, ring, q)?, to_fp(fd, ring, q)?);
        let (nv, dv) = (ring.eval(&n, &star), ring.eval(&d, &star));
        if dv == 0 {
            return Ok(None);
        }
        eqs.push(ring.sub(&ring.scale(&n, dv), &ring.scale(&d, nv)));
        // Up to a constant (a common denominator comes scaled by each
        // fraction's own constant): the first coefficient made 1.
        let lead = d.terms().first().map_or(1, |t| t.1);
        let d = ring.scale(&d, obsan_recon::fp::inv(lead, q).unwrap_or(1));
        if d.degree() > 0 && !dens.contains(&d) {
            dens.push(d);
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
    Ok(Some((gens, local)))
}

/// `c_i(theta) = c_i(theta*)` at a random `theta*` over `F_q`, the
/// denominators kept non-zero by `z L(theta) = 1`; the parameters that are
/// not locally identifiable (Jacobian at `theta*`) sliced at `theta*`.
/// The solutions in `F_q` too when they are several and asked for
/// (`zeros`: the part's filter) or at most [`MAP_ZEROS`] (the maps), both
/// io_check.rs.
pub(super) fn count(
    fns: &[(RPoly, RPoly)],
    np: usize,
    opts: &GlobalOptions,
    seed: u64,
    (q, zeros): (u64, bool),
) -> Result<Counted, AnalysisError> {
    let field = Field::new(q).ok_or_else(|| err("global (io): bad prime"))?;
    let ring = Ring::new(field, np + 1, Order::Grevlex);
    let mut rng = Rng::new(seed ^ 0xc0u64);
    let mut star = vec![0u64; np];
    let mut system = None;
    for _ in 0..16 {
        for s in star.iter_mut() {
            *s = elem(&mut rng, q);
        }
        system = system_at(fns, &ring, &star, opts)?;
        if system.is_some() {
            break;
        }
    }
    let Some((gens, local)) = system else {
        return Err(err(
            "global (io): a coefficient's denominator vanished at 16 random points; try another --seed",
        ));
    };
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
    let (mut joint, mut points) = (None, None);
    if !terms.is_empty() {
        let lf = ring.from_terms(terms);
        let mp = b
            .minimal_polynomial_in(&lf, &steps, opts.max_solutions)
            .map_err(gb_err)?;
        let k = distinct_roots(field, &mp);
        joint = Some(k);
        // The zeros for the part's filter, or for the maps (a few).
        if k > 1 && (zeros || k <= MAP_ZEROS) {
            points = Some(io_check::zeros(
                &ring,
                &gens,
                (&lf, &mp),
                np,
                opts,
                &mut rng,
            )?);
        }
    }
    Ok(Counted {
        per,
        joint,
        star,
        zeros: points,
    })
}

/// One count (`count`): per parameter, jointly, its random point, and its
/// solutions when asked for and found.
pub(super) struct Counted {
    pub(super) per: Vec<Option<usize>>,
    pub(super) joint: Option<usize>,
    pub(super) star: Vec<u64>,
    pub(super) zeros: Option<io_check::Zeros>,
}

/// Most solutions read off one by one for the maps (io_check.rs,
/// `param_maps`): each costs a Gröbner basis of the count's system with
/// one more equation.
const MAP_ZEROS: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;

    /// Univariate gcd, lcm, quotient and divisibility modulo p on planted
    /// factors: a = f g, b = f h with f = (t + 3)(t - 5), g = t^2 + 7,
    /// h = 2 t - 1 (by hand): gcd ~ f, lcm ~ f g h, a / f = g exactly.
    #[test]
    fn univariate_gcd_lcm_by_planted_factors() {
        let p = P0;
        let m = |c: i64| if c < 0 { p - (-c) as u64 } else { c as u64 };
        let f = umul(&[3, 1], &[m(-5), 1], p);
        let g = vec![7, 0, 1];
        let h = vec![m(-1), 2];
        let (a, b) = (umul(&f, &g, p), umul(&f, &h, p));
        let gc = ugcd(&a, &b, p);
        assert_eq!(udeg(&gc), 2);
        assert!(divides(&gc, &f, p) && divides(&f, &gc, p));
        let l = ulcm(&a, &b, p);
        assert_eq!(udeg(&l), 5);
        assert!(divides(&a, &l, p) && divides(&b, &l, p));
        assert!(divides(&umul(&umul(&f, &g, p), &h, p), &l, p));
        let q = udiv(&a, &f, p);
        assert_eq!(&q[..=udeg(&q)], &g[..]);
        assert!(!divides(&h, &g, p));
        assert!(urem(&a, &f, p).iter().all(|&c| c == 0));
    }

    /// Regression (SEAIJRC, session 43): quotients `1/r`, `a/r^2`,
    /// `a^2/r^3` (by hand; params `r, a`). Taken smallest numerator first,
    /// the first two's denominators multiply to `r^3` on the `r` axis, which
    /// covers the third's, but the common denominator built from them is
    /// their lcm `r^2`, and `a^2/r^3` times it is no polynomial. The third,
    /// missed by it, is chosen too: the common denominator is `r^3`.
    #[test]
    fn common_denominator_covers_repeated_factors() {
        use obsan_recon::Term;
        let p = P0;
        let mono = |e: [u32; 2]| {
            RPoly::from_terms([Term {
                exps: e.to_vec(),
                coeff: 1.into(),
            }])
        };
        // c_m / c_last for m = 0, 1, 2 (the last coefficient is 1).
        let fns = [
            (mono([0, 0]), mono([1, 0])),
            (mono([0, 1]), mono([2, 0])),
            (mono([0, 2]), mono([3, 0])),
        ];
        let base = [123_456_789u64, 987_654_321];
        // Per axis, each quotient restricted there, reduced.
        let quotients: Vec<Vec<Fraction>> = (0..2)
            .map(|k| {
                fns.iter()
                    .map(|(n, d)| {
                        let (n, d) = (restrict(n, &base, k, p), restrict(d, &base, k, p));
                        let g = ugcd(&n, &d, p);
                        (udiv(&n, &g, p), udiv(&d, &g, p))
                    })
                    .collect()
            })
            .collect();
        let mut bb = |pt: &[u64], q: u64| -> Result<Option<Vec<u64>>, AnalysisError> {
            let mut v = Vec::new();
            for (n, d) in &fns {
                let Some(id) = obsan_recon::fp::inv(d.eval_mod(pt, q), q) else {
                    return Ok(None);
                };
                v.push(fmul(n.eval_mod(pt, q), id, q));
            }
            v.push(1);
            Ok(Some(v))
        };
        let ropts = Options {
            prime_list: PrimeList::Bits52,
            ..Options::default()
        };
        let Ok(Some((d, per))) = common_denominator(&quotients, &base, 3, 2, &mut bb, &ropts)
        else {
            panic!("no common denominator");
        };
        assert_eq!(d.terms().len(), 1);
        assert_eq!(d.terms()[0].exps, vec![3, 0]);
        // Times it, the quotients are r^2, a r, a^2: their degrees per axis.
        assert_eq!(per, vec![vec![2, 0], vec![1, 1], vec![0, 2]]);
    }

    /// The common multiple of x^2 y (b + c), x (b + c) and 3 (x + 1) is
    /// x^2 y (b + c)(x + 1): the largest monomial, each other factor once.
    #[test]
    fn common_multiple_of_monomials_and_binomials() {
        use obsan_recon::Term;
        let t = |e: [u32; 4], c: i64| Term {
            exps: e.to_vec(),
            coeff: c.into(),
        };
        // Variables x, y, b, c.
        let d1 = RPoly::from_terms([t([2, 1, 1, 0], 1), t([2, 1, 0, 1], 1)]);
        let d2 = RPoly::from_terms([t([1, 0, 1, 0], 2), t([1, 0, 0, 1], 2)]);
        let d3 = RPoly::from_terms([t([1, 0, 0, 0], 3), t([0, 0, 0, 0], 3)]);
        let l = lcm_multiple(&[&d1, &d2, &d3], 4);
        let want = RPoly::from_terms([t([2, 1, 1, 0], 1), t([2, 1, 0, 1], 1)])
            .times(&RPoly::from_terms([t([1, 0, 0, 0], 3), t([0, 0, 0, 0], 3)]));
        assert_eq!(l, want);
    }

    /// The derivative of a fraction: `(t^2 + 1) / (t + 2)` at `t = 3` is
    /// `(2t (t + 2) - (t^2 + 1)) / (t + 2)^2 = 20 / 25` (by hand).
    #[test]
    fn fraction_derivative_by_hand() {
        let p = obsan_recon::PRIMES[0];
        let d = fraction_derivative(&[1, 0, 1], &[2, 1], 3, p).unwrap();
        assert_eq!(fmul(d, 25, p), 20);
        assert_eq!(fraction_derivative(&[1], &[p - 3, 1], 3, p), None);
    }

    /// The part reaches the whole Jacobian's rank with the simplest rows,
    /// then takes every row up to twice the last one's size; none when it
    /// is not far simpler than the whole. Rows: `e1` (size 3), `e1` again
    /// (5), `e2` (9), `e1 + e2` (40), and one of size 10^4.
    #[test]
    fn the_generating_part_reaches_the_rank() {
        let p = obsan_recon::PRIMES[0];
        let jac = vec![vec![1, 0], vec![2, 0], vec![0, 1], vec![1, 1], vec![3, 5]];
        let est = [3, 5, 9, 40, 10_000];
        // The rank (2) is reached at the size-9 row; up to 18: rows 0, 1, 2.
        assert_eq!(generating_part(&est, &jac, p), Some(vec![0, 1, 2]));
        // The whole is not 16 times the cap (18): no part.
        assert_eq!(generating_part(&[3, 5, 9, 40, 200], &jac, p), None);
        // Rank 2 needs the size-40 row when `e2` is missing: the part is
        // rows up to 80, which leaves out only the 10^4 one.
        let jac2 = vec![vec![1, 0], vec![2, 0], vec![4, 0], vec![1, 1], vec![3, 5]];
        assert_eq!(generating_part(&est, &jac2, p), Some(vec![0, 1, 2, 3]));
    }

    /// Lower bounds decide the part only when the exact sizes would give
    /// the same one: every inexact size past the cap, the rank reached by
    /// exact ones, the whole at least 16 times the cap.
    #[test]
    fn lower_bounds_decide_the_part_only_as_the_exact_sizes_would() {
        use Estimate::{AtLeast, Exact};
        let p = obsan_recon::PRIMES[0];
        let jac = vec![vec![1, 0], vec![2, 0], vec![0, 1], vec![1, 1], vec![3, 5]];
        // As the first case above, the last two known past the cap (18).
        let est = [Exact(3), Exact(5), Exact(9), AtLeast(19), AtLeast(300)];
        assert_eq!(select_part(&est, &jac, p), Some(Some(vec![0, 1, 2])));
        // A lower bound within the cap: it may belong to the part.
        let est = [Exact(3), Exact(5), Exact(9), AtLeast(18), AtLeast(300)];
        assert_eq!(select_part(&est, &jac, p), None);
        // An inexact size where the rank would be reached: undecided.
        let est = [Exact(3), Exact(5), AtLeast(9), Exact(40), AtLeast(300)];
        assert_eq!(select_part(&est, &jac, p), None);
        // The whole not yet known to be 16 times the cap (288): undecided;
        // once it is, the part.
        let est = [Exact(3), Exact(5), Exact(9), AtLeast(40), AtLeast(200)];
        assert_eq!(select_part(&est, &jac, p), None);
        let est = [Exact(3), Exact(5), Exact(9), AtLeast(40), AtLeast(288)];
        assert_eq!(select_part(&est, &jac, p), Some(Some(vec![0, 1, 2])));
        // All exact and the whole too small: no part, decided.
        let est = [Exact(3), Exact(5), Exact(9), Exact(40), Exact(200)];
        assert_eq!(select_part(&est, &jac, p), Some(None));
    }

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
