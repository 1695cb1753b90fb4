//! Which characteristic presentation the input-output route counts with.
//! Every orderly ranking of the outputs' jets gives one (io.rs: order
//! first, then the outputs in a chosen priority), and the coefficients of
//! any of them generate the same field, the multi-experiment identifiable
//! functions (Ovchinnikov, Pillay, Pogudin, Scanlon 2021): the counts do not
//! depend on the choice. The sizes do, by far: HIV's outputs as written give
//! a `w'''` relation of 328 monomials, the other priority a `z'''` one of 61,
//! and the reconstruction's points grow with the coefficients' terms, each
//! point's kernel with the cube of the support. And one ranking's relations
//! may be fixed by one experiment (a non-zero Wronskian, io.rs's
//! `independent_along`) where another's are not.
//!
//! So: the relations under the outputs as written and reversed (a small
//! ansatz, a bounded elimination), the smallest whose relations one
//! experiment fixes; then, with elimination and none such, the other
//! rotations; then the full ansatz and an unbounded elimination on the
//! outputs as written, as before the choice existed.

use super::io::{IoModel, IoRelation};
use super::io_elim::relation_by_elimination;
use super::model::ZModel;
use super::run::Rng;
use super::types::{err, GlobalOptions};
use crate::rank::AnalysisError;
use obsan_groebner::GbBudget;

/// The presentation chosen: the model with its outputs in priority order
/// (`perm[k]`: the output put `k`-th), the ranking's orders, each relation,
/// and whether one experiment fixes its coefficients.
pub(super) struct Presentation {
    pub(super) model: ZModel,
    pub(super) perm: Vec<usize>,
    pub(super) orders: Vec<usize>,
    pub(super) rels: Vec<IoRelation>,
    pub(super) single: Vec<bool>,
}

/// A presentation found, its Wronskian checks run lazily (a check of a
/// relation of `N` monomials expands one output to `N + 2` Taylor orders:
/// seconds for MAPK_5out's larger ones).
struct Candidate {
    model: ZModel,
    perm: Vec<usize>,
    io: IoModel,
    orders: Vec<usize>,
    rels: Vec<IoRelation>,
    single: Vec<Option<bool>>,
}

impl Candidate {
    fn size(&self) -> usize {
        self.rels.iter().map(|r| r.support.len()).sum()
    }

    fn check(&mut self, i: usize, theta: &[u64], rng: &mut Rng) -> bool {
        if let Some(s) = self.single[i] {
            return s;
        }
        let s = self
            .io
            .independent_along(theta, &self.orders, i, &self.rels[i].support, rng);
        self.single[i] = Some(s);
        s
    }

    /// Whether one experiment fixes every relation: the smallest relations
    /// checked first, stopping at the first that fails.
    fn all_single(&mut self, theta: &[u64], rng: &mut Rng) -> bool {
        let mut by_size: Vec<usize> = (0..self.rels.len()).collect();
        by_size.sort_by_key(|&i| self.rels[i].support.len());
        by_size.into_iter().all(|i| self.check(i, theta, rng))
    }

    fn done(mut self, theta: &[u64], rng: &mut Rng) -> Presentation {
        let single = (0..self.rels.len())
            .map(|i| self.check(i, theta, rng))
            .collect();
        Presentation {
            model: self.model,
            perm: self.perm,
            orders: self.orders,
            rels: self.rels,
            single,
        }
    }
}

/// How one priority's relations are looked for: the ansatz up to `cap`
/// monomials, then (when `eliminate`) elimination within `max_work`
/// multiply-adds and `max_bytes`, keeping a relation of at most
/// `max_support` monomials.
#[derive(Clone, Copy)]
struct Attempt {
    eliminate: bool,
    cap: usize,
    max_work: u64,
    max_bytes: usize,
    max_support: usize,
}

/// While priorities are compared: the ansatz's cap (a kernel near the full
/// cap costs about a second: cubic), and the elimination's work and memory
/// (HIV's 328-monomial relation takes 14 ms; Goodwin's 91-monomial one,
/// which its ansatz finds in 0.1 s, 6 s and 190 MB).
const SEARCH_CAP: usize = 330;
const SEARCH_WORK: u64 = 50_000_000;
const SEARCH_BYTES: usize = 16 << 20;

/// The note on a relation past an ansatz searched without elimination
/// (`--route auto` matches on it: mod.rs's elimination rung).
pub(super) const PAST_ANSATZ: &str = " (--route io finds it by elimination)";

/// Below this many monomials in all, a presentation one experiment fixes
/// is kept without looking further.
const SMALL: usize = 100;

/// The relations under the priority `perm`.
fn relations_under(
    m: &ZModel,
    opts: &GlobalOptions,
    theta: &[u64],
    rng: &mut Rng,
    t: Attempt,
    perm: &[usize],
) -> Result<Candidate, AnalysisError> {
    let mut mp = m.clone();
    mp.outputs = perm.iter().map(|&k| m.outputs[k].clone()).collect();
    mp.forms = perm.iter().map(|&k| m.forms[k].clone()).collect();
    // Modulo the route's first 52-bit prime, as the reconstruction: the
    // ansatz's kernels then run on IFMA too (io_count's `IO_PRIMES`).
    let mut io = IoModel::new(&mp, super::io_count::P0)?;
    io.deadline = opts.deadline;
    io.max_bytes = opts.max_bytes;
    io.max_work = opts.max_io_work;
    let orders = io.orders(theta, rng)?;
    let mut rels = Vec::with_capacity(orders.len());
    for (i, &out) in perm.iter().enumerate().take(orders.len()) {
        // The dense ansatz first (cheap for small relations, and the only
        // way with inputs), then elimination (io_elim.rs).
        let rel: IoRelation = match io.relation(theta, &orders, i, 60, t.cap, rng)? {
            Some(r) => r,
            None => {
                let found = if t.eliminate {
                    let budget = GbBudget {
                        max_work: t.max_work.min(opts.max_work),
                        max_bytes: t.max_bytes.min(opts.max_bytes),
                        ..opts.gb_budget()
                    };
                    relation_by_elimination(&io, theta, &orders, i, budget)?
                        .filter(|r| r.support.len() <= t.max_support)
                } else {
                    None
                };
                found.ok_or_else(|| {
                    if t.cap == 0 {
                        return err(format!(
                            "global (io): the input-output relation of output {} was not found by elimination within its bounds",
                            out + 1
                        ));
                    }
                    err(format!(
                        "global (io): the input-output relation of output {} needs more than {} ansatz monomials{}",
                        out + 1,
                        t.cap,
                        if !t.eliminate {
                            PAST_ANSATZ
                        } else if io.dims().1 > 0 {
                            " (with inputs: no elimination)"
                        } else {
                            ""
                        }
                    ))
                })?
            }
        };
        rels.push(rel);
    }
    let n = rels.len();
    Ok(Candidate {
        model: mp,
        perm: perm.to_vec(),
        io,
        orders,
        rels,
        single: vec![None; n],
    })
}

/// The outputs' priorities: as written, reversed, then the other
/// rotations and their reverses.
fn priorities(m: usize) -> Vec<Vec<usize>> {
    let mut c: Vec<Vec<usize>> = Vec::new();
    for r in 0..m {
        let rot: Vec<usize> = (0..m).map(|k| (k + r) % m).collect();
        let rev: Vec<usize> = rot.iter().rev().copied().collect();
        for p in [rot, rev] {
            if !c.contains(&p) {
                c.push(p);
            }
        }
    }
    c
}

fn past(opts: &GlobalOptions) -> Result<(), AnalysisError> {
    if opts.deadline.is_some_and(|d| std::time::Instant::now() > d) {
        return Err(AnalysisError::Timeout(
            "the input-output relations (global, --route io)".into(),
        ));
    }
    Ok(())
}

/// The presentation to count with (module doc), under the priority `only`
/// when given (tests: every priority counts the same). With
/// `opts.multi_experiment` the smallest is taken (one experiment need not
/// fix it); otherwise the smallest whose relations one experiment fixes, or
/// else the smallest (which the caller refuses).
pub(super) fn presentation(
    m: &ZModel,
    opts: &GlobalOptions,
    theta: &[u64],
    rng: &mut Rng,
    (eliminate, cap): (bool, usize),
    only: Option<&[usize]>,
) -> Result<Presentation, AnalysisError> {
    let all = match only {
        Some(p) => vec![p.to_vec()],
        None => priorities(m.outputs.len()),
    };
    let full = Attempt {
        eliminate,
        cap,
        max_work: u64::MAX,
        max_bytes: usize::MAX,
        max_support: usize::MAX,
    };
    if all.len() == 1 {
        // One output (or one priority asked for): nothing to compare.
        let c = relations_under(m, opts, theta, rng, full, &all[0])?;
        return Ok(c.done(theta, rng));
    }
    // The search eliminates also when the caller does not (`--route
    // auto`): its elimination is bounded, and a relation it finds is kept
    // only within the small ansatz's size, so the reconstruction costs no
    // more than the ansatz's relations would (HIV's reversed priority: 22 +
    // 61 monomials, whose dense ansatz passes the cap).
    let search = Attempt {
        eliminate: true,
        cap: cap.min(SEARCH_CAP),
        max_work: SEARCH_WORK,
        // Under a smaller work bound (`--route auto`'s cheap attempt,
        // io_choice.rs), less memory in proportion: measured before F4's
        // work counted its symbolic preprocessing, SIRC_forced's search
        // took 0.3 s under 5e6 multiply-adds, 0.13 s with 1.6 MB.
        max_bytes: (SEARCH_BYTES as u128 * u128::from(opts.max_work.min(SEARCH_WORK))
            / u128::from(SEARCH_WORK)) as usize,
        max_support: if eliminate {
            usize::MAX
        } else {
            cap.min(SEARCH_CAP)
        },
    };
    let mut found: Vec<Candidate> = Vec::new();
    for perm in all.iter().take(2) {
        past(opts)?;
        match relations_under(m, opts, theta, rng, search, perm) {
            Ok(mut c) => {
                let small = c.size() <= SMALL;
                if small && (opts.multi_experiment || c.all_single(theta, rng)) {
                    return Ok(c.done(theta, rng));
                }
                found.push(c);
            }
            Err(AnalysisError::Timeout(e)) => return Err(AnalysisError::Timeout(e)),
            Err(_) => {}
        }
    }
    if found.is_empty() {
        // Not found cheaply: the outputs as written, in full.
        let c = relations_under(m, opts, theta, rng, full, &all[0])?;
        return Ok(c.done(theta, rng));
    }
    found.sort_by_key(Candidate::size);
    if opts.multi_experiment {
        return Ok(found.swap_remove(0).done(theta, rng));
    }
    for k in 0..found.len() {
        past(opts)?;
        if found[k].all_single(theta, rng) {
            return Ok(found.swap_remove(k).done(theta, rng));
        }
    }
    // None that one experiment fixes: the other rotations, where a relation
    // past the ansatz costs a bounded elimination.
    if eliminate {
        for perm in all.iter().skip(2) {
            past(opts)?;
            if let Ok(mut c) = relations_under(m, opts, theta, rng, search, perm) {
                if c.all_single(theta, rng) {
                    return Ok(c.done(theta, rng));
                }
            }
        }
    }
    Ok(found.swap_remove(0).done(theta, rng))
}
