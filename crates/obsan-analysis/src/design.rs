//! Which sensor, which trajectory (docs/experiments.md).
//!
//! Sensors. The observability codistribution of a set of outputs is the
//! smallest codistribution containing their differentials and invariant
//! under every field; the Lie derivatives of an output involve only that
//! output, so the codistribution of outputs `A ∪ B` is the *sum* of theirs:
//! `Ω(A ∪ B) = Ω(A) + Ω(B)`. So one rank test per candidate (its basis
//! words) and the gradients of those words at two random points give the
//! rank of any subset by linear algebra over F_p at those points: the screen
//! costs microseconds per subset, all 2^m subsets of a few dozen candidates
//! are cheap. A screened rank is never above the generic rank (a minor at a
//! point); every set reported is then confirmed by the ordinary rank test on
//! the model with those outputs added (its certificate: full rank exact).
//! Subsets are visited by size, then cost; supersets of a set found are
//! skipped (they are not minimal).
//!
//! The symmetry a set breaks: a symmetry `w` of the model (a vector field
//! annihilating `Ω(model)`) stays a symmetry with the added outputs iff it
//! annihilates their codistribution too; at the points, `row · w ≠ 0` for a
//! row of the added outputs' codistribution means `w` is broken.
//!
//! Trajectories. Each input restriction of the model is a family of
//! experiments; several experiments of one family, or one of each of several
//! families, stack ([`obsan_model::System::stacked_normal_form`]). A family
//! alone: one experiment's rank, and [`crate::multi_experiment::experiments_auto`]'s smallest
//! number of generic experiments of it and the rank they reach. Combinations:
//! one generic experiment of each family in a set of distinct families, by
//! size, supersets of found sets skipped.

use crate::experiments::experiments_auto;
use crate::experiments::AutoOptions;
use crate::rank::{lie_jets, random_point, rank, AnalysisError, RankOptions, RankReport};
use crate::symmetry::{symmetries_with, SymmetryOptions, SymmetryReport};
use obsan_expr::{evaluate::FpPoint, Fp, FpEchelon, SplitMix, Q};
use obsan_model::{Experiment, NormalForm, System};
use std::time::Instant;

/// A candidate sensor: a name, a cost, and the outputs it adds (indices into
/// the normal form's `outputs`).
#[derive(Clone, Debug)]
pub struct Candidate {
    pub name: String,
    pub cost: f64,
    pub outputs: Vec<usize>,
}

/// Options of [`design_outputs`] and [`design_inputs`].
#[derive(Clone, Debug)]
pub struct DesignOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// At most this many subsets screened (sizes completed are exhaustive).
    pub max_subsets: usize,
    /// Compute the model's symmetries to say which each set breaks.
    pub symmetries: bool,
}

impl Default for DesignOptions {
    fn default() -> Self {
        DesignOptions {
            seed: 1,
            deadline: None,
            max_subsets: 1 << 20,
            symmetries: true,
        }
    }
}

/// A minimal set of candidates that reaches the goal.
#[derive(Clone, Debug)]
pub struct DesignSet {
    /// Indices into the candidates, ascending.
    pub members: Vec<usize>,
    pub cost: f64,
    /// The rank test of the model with these outputs added.
    pub rank: usize,
    pub error_bound: f64,
    /// Per state variable (of the normal form): observable on its own.
    pub observable: Vec<bool>,
    /// Indices into [`DesignReport::symmetries`] of the symmetries broken.
    pub breaks: Vec<usize>,
}

/// What one candidate does alone.
#[derive(Clone, Debug)]
pub struct CandidateEffect {
    /// Rank of the model with this candidate added (screened at the points).
    pub rank: usize,
    pub breaks: Vec<usize>,
}

/// The answer of [`design_outputs`].
#[derive(Clone, Debug)]
pub struct DesignReport {
    pub n: usize,
    /// Rank (and per-variable verdict) of the model's own outputs.
    pub base_rank: usize,
    pub base_observable: Vec<bool>,
    /// Rank with every candidate added: the most any set can reach.
    pub all_rank: usize,
    /// The variables that must become observable (indices into the state);
    /// every one when no target was named.
    pub target: Vec<usize>,
    /// The goal is met by the model alone (nothing to add).
    pub already: bool,
    /// The goal is reachable with every candidate added.
    pub reachable: bool,
    pub candidates: Vec<CandidateEffect>,
    /// Inclusion-minimal sets, sorted by count then cost.
    pub sets: Vec<DesignSet>,
    pub subsets_screened: usize,
    /// Every subset size up to this was screened completely (all sizes:
    /// `exhaustive`).
    pub complete_to_size: usize,
    pub exhaustive: bool,
    /// The model's symmetries (`None`: not asked, or not computed: `symmetry_note`).
    pub symmetries: Option<SymmetryReport>,
    pub symmetry_note: Option<String>,
    /// Largest error bound of the ranks below full used (screen and rank tests).
    pub error_bound: f64,
}

/// One group of outputs (the model's, or a candidate's): its rank test's
/// basis rows at each point.
struct Group {
    rows: Vec<Vec<Vec<Fp>>>,
    error_bound: f64,
}

fn rank_opts(seed: u64, deadline: Option<Instant>) -> RankOptions<'static> {
    RankOptions {
        seed,
        deadline,
        progress: None,
    }
}

/// The normal form with only the outputs `keep` (indices into `nf.outputs`).
fn with_outputs(nf: &NormalForm, keep: &[usize]) -> NormalForm {
    let mut m = nf.clone();
    m.outputs = keep.iter().map(|&i| nf.outputs[i].clone()).collect();
    m
}

fn dot(a: &[Fp], b: &[Fp]) -> Fp {
    a.iter().zip(b).fold(Fp::ZERO, |s, (x, y)| s + *x * *y)
}

/// A symmetry vector at a point (`None` if it names a variable the point
/// does not know, or has a pole there).
fn vector_at(v: &[obsan_expr::RatFun], point: &FpPoint, n_leaves: usize) -> Option<Vec<Fp>> {
    let mut out = Vec::with_capacity(v.len());
    for c in v {
        if c.vars().iter().any(|&x| x as usize >= n_leaves) {
            return None;
        }
        let val = |x| point.value(x);
        let num = c.numerator().eval_fp(&val);
        let den = c.denominator().eval_fp(&val);
        out.push(num * den.inv()?);
    }
    Some(out)
}

/// Minimal sets of candidate outputs (by count, then cost) that make every
/// variable of `target` (every state variable when `None`) observable, with
/// the model's own outputs `nf.outputs[..base]` (module doc).
pub fn design_outputs(
    nf: &NormalForm,
    base: usize,
    candidates: &[Candidate],
    target: Option<&[usize]>,
    opts: &DesignOptions,
) -> Result<DesignReport, AnalysisError> {
    let n = nf.state.len();
    let m = candidates.len();
    let target: Vec<usize> = target.map_or_else(|| (0..n).collect(), <[usize]>::to_vec);
    let base_outs: Vec<usize> = (0..base).collect();
    let sc = Screen::new(nf, &base_outs, candidates, target, opts)?;
    let mut error_bound = sc.error_bound;
    let (base_rank, already) = sc.screen(&[]);
    let mut base_model = with_outputs(nf, &base_outs);
    let base_report = if base > 0 {
        Some(rank(&mut base_model, rank_opts(opts.seed, opts.deadline))?)
    } else {
        None
    };
    let base_observable = base_report
        .as_ref()
        .map_or_else(|| vec![false; n], |r| r.observable.clone());
    let all: Vec<usize> = (0..m).collect();
    let (all_rank, reachable) = sc.screen(&all);
    let (symmetries, symmetry_note) =
        base_symmetries(&mut base_model, base_report.as_ref(), n, opts)?;
    let sym_at = sc.symmetries_at(symmetries.as_ref());
    let effects = (0..m)
        .map(|c| CandidateEffect {
            rank: sc.screen(&[c]).0,
            breaks: sc.breaks(&sym_at, &[c]),
        })
        .collect();
    let search = if !already && reachable {
        search_subsets(&sc, m, opts)?
    } else {
        Subsets {
            found: Vec::new(),
            screened: 0,
            complete_to_size: m,
            exhaustive: true,
        }
    };
    // Confirm each set by the rank test on the model with its outputs.
    let mut sets = Vec::new();
    for f in search.found {
        let mut outs = base_outs.clone();
        for &c in &f {
            outs.extend(&candidates[c].outputs);
        }
        let mut g = with_outputs(nf, &outs);
        let r = rank(&mut g, rank_opts(opts.seed, opts.deadline))?;
        if r.rank < n {
            error_bound = error_bound.max(r.error_bound);
        }
        // The screen's rank at a point is a lower bound of this rank.
        if !sc.target.iter().all(|&i| r.observable[i]) {
            continue;
        }
        sets.push(DesignSet {
            cost: f.iter().map(|&c| candidates[c].cost).sum(),
            breaks: sc.breaks(&sym_at, &f),
            members: f,
            rank: r.rank,
            error_bound: if r.rank == n { 0.0 } else { r.error_bound },
            observable: r.observable,
        });
    }
    sets.sort_by(|a, b| {
        a.members
            .len()
            .cmp(&b.members.len())
            .then(a.cost.total_cmp(&b.cost))
            .then(a.members.cmp(&b.members))
    });
    Ok(DesignReport {
        n,
        base_rank: base_report.as_ref().map_or(base_rank, |r| r.rank),
        base_observable,
        all_rank,
        target: sc.target,
        already,
        reachable,
        candidates: effects,
        sets,
        subsets_screened: search.screened,
        complete_to_size: search.complete_to_size,
        exhaustive: search.exhaustive,
        symmetries,
        symmetry_note,
        error_bound,
    })
}

/// The rank screen of subsets of candidates: each group's basis rows at two
/// random points, added to the model's own echelon basis there.
struct Screen {
    n: usize,
    target: Vec<usize>,
    points: [FpPoint; 2],
    n_leaves: usize,
    groups: Vec<Group>,
    base_ech: Vec<FpEchelon>,
    /// The largest error bound of the groups' rank tests.
    error_bound: f64,
}

impl Screen {
    fn new(
        nf: &NormalForm,
        base_outs: &[usize],
        candidates: &[Candidate],
        target: Vec<usize>,
        opts: &DesignOptions,
    ) -> Result<Screen, AnalysisError> {
        let mut full = nf.clone();
        let fields = crate::rank::Fields::of(&mut full);
        let jets = lie_jets(&full, &fields);
        let mut rng = SplitMix(opts.seed ^ 0x6465_7369_676e_0001);
        let points = [
            random_point(&mut full.ctx, &mut rng)?,
            random_point(&mut full.ctx, &mut rng)?,
        ];
        let n_leaves = full.ctx.leaf_count();
        // One rank test per group: its basis words, rows at the two points.
        let group = |outs: &[usize]| -> Result<Group, AnalysisError> {
            if outs.is_empty() {
                return Ok(Group {
                    rows: vec![vec![], vec![]],
                    error_bound: 0.0,
                });
            }
            let mut g = with_outputs(nf, outs);
            let r = rank(&mut g, rank_opts(opts.seed, opts.deadline))?;
            let mut rows = vec![Vec::new(), Vec::new()];
            for w in &r.basis {
                for (k, p) in points.iter().enumerate() {
                    let row = jets
                        .row(outs[w.output], &w.fields, p, false)
                        .map_err(|_| AnalysisError::NoPoint)?;
                    rows[k].push(row.gradient);
                }
            }
            let eb = if r.rank == r.n { 0.0 } else { r.error_bound };
            Ok(Group {
                rows,
                error_bound: eb,
            })
        };
        let g0 = group(base_outs)?;
        let mut groups = Vec::with_capacity(candidates.len());
        for c in candidates {
            groups.push(group(&c.outputs)?);
        }
        let error_bound = groups
            .iter()
            .chain(std::iter::once(&g0))
            .fold(0.0f64, |a, g| a.max(g.error_bound));
        // The model's echelon basis at each point, extended per subset.
        let base_ech: Vec<FpEchelon> = (0..2)
            .map(|k| {
                let mut e = FpEchelon::default();
                for r in &g0.rows[k] {
                    e.insert(r.clone());
                }
                e
            })
            .collect();
        Ok(Screen {
            n: nf.state.len(),
            target,
            points,
            n_leaves,
            groups,
            base_ech,
            error_bound,
        })
    }

    /// Screened rank of a subset and whether it meets the goal: the better
    /// point (a rank at a point is a lower bound of the generic rank).
    fn screen(&self, members: &[usize]) -> (usize, bool) {
        let n = self.n;
        let mut best = (0usize, false);
        for (k, b) in self.base_ech.iter().enumerate() {
            let mut e = b.clone();
            for &c in members {
                for r in &self.groups[c].rows[k] {
                    e.insert(r.clone());
                    if e.rank() == n {
                        break;
                    }
                }
            }
            let rk = e.rank();
            let met = self.target.iter().all(|&i| e.contains_unit(i, n));
            if rk > best.0 || (rk == best.0 && met) {
                best = (rk, met);
            }
        }
        best
    }

    /// The symmetry vectors at each point (`[point][symmetry]`).
    fn symmetries_at(&self, sym: Option<&SymmetryReport>) -> Vec<Vec<Option<Vec<Fp>>>> {
        (0..2)
            .map(|k| {
                sym.map_or_else(Vec::new, |s| {
                    s.vectors
                        .iter()
                        .map(|v| vector_at(v, &self.points[k], self.n_leaves))
                        .collect()
                })
            })
            .collect()
    }

    /// The symmetries a subset breaks: some row of its members is not
    /// orthogonal to the symmetry at one of the points.
    fn breaks(&self, sym_at: &[Vec<Option<Vec<Fp>>>], members: &[usize]) -> Vec<usize> {
        let n_sym = sym_at.first().map_or(0, Vec::len);
        (0..n_sym)
            .filter(|&j| {
                (0..2).any(|k| {
                    sym_at[k][j].as_ref().is_some_and(|w| {
                        members
                            .iter()
                            .any(|&c| self.groups[c].rows[k].iter().any(|r| !dot(r, w).is_zero()))
                    })
                })
            })
            .collect()
    }
}

/// The model's symmetries when it is rank-deficient (a failure to find them
/// is a note, not an error: the design stands without them).
fn base_symmetries(
    base_model: &mut NormalForm,
    report: Option<&RankReport>,
    n: usize,
    opts: &DesignOptions,
) -> Result<(Option<SymmetryReport>, Option<String>), AnalysisError> {
    match (report, opts.symmetries) {
        (Some(r), true) if r.rank < n => match symmetries_with(
            base_model,
            r,
            &SymmetryOptions {
                deadline: opts.deadline,
                ..Default::default()
            },
        ) {
            Ok(s) => Ok((Some(s), None)),
            Err(AnalysisError::Cancelled) => Err(AnalysisError::Cancelled),
            Err(e) => Ok((None, Some(format!("the model's symmetries: {e}")))),
        },
        _ => Ok((None, None)),
    }
}

/// The subsets that meet the goal, found by size.
struct Subsets {
    found: Vec<Vec<usize>>,
    screened: usize,
    complete_to_size: usize,
    exhaustive: bool,
}

/// Subsets by size; within a size in lexicographic order; supersets of a
/// found set skipped (they are not minimal).
fn search_subsets(sc: &Screen, m: usize, opts: &DesignOptions) -> Result<Subsets, AnalysisError> {
    let mut out = Subsets {
        found: Vec::new(),
        screened: 0,
        complete_to_size: 0,
        exhaustive: true,
    };
    for k in 1..=m {
        let mut idx: Vec<usize> = (0..k).collect();
        loop {
            if !out.found.iter().any(|f| f.iter().all(|x| idx.contains(x))) {
                if out.screened >= opts.max_subsets {
                    out.exhaustive = false;
                    return Ok(out);
                }
                if out.screened.is_multiple_of(256) {
                    check_time(opts.deadline, out.screened)?;
                }
                out.screened += 1;
                if sc.screen(&idx).1 {
                    out.found.push(idx.clone());
                }
            }
            if !next_combination(&mut idx, m) {
                break;
            }
        }
        out.complete_to_size = k;
    }
    Ok(out)
}

/// The next k-subset of `0..m` in lexicographic order (`false`: none).
fn next_combination(idx: &mut [usize], m: usize) -> bool {
    let k = idx.len();
    let Some(i) = (0..k).rev().find(|&i| idx[i] != m - k + i) else {
        return false;
    };
    idx[i] += 1;
    let first = idx[i];
    for (o, x) in idx[i + 1..].iter_mut().enumerate() {
        *x = first + 1 + o;
    }
    true
}

fn check_time(deadline: Option<Instant>, screened: usize) -> Result<(), AnalysisError> {
    if obsan_expr::cancel_requested() {
        return Err(AnalysisError::Cancelled);
    }
    if deadline.is_some_and(|d| Instant::now() > d) {
        return Err(AnalysisError::Timeout(format!(
            "after screening {screened} subsets"
        )));
    }
    Ok(())
}

/// One input family (a restriction of the model, or none: inputs free).
#[derive(Clone, Debug)]
pub struct FamilyReport {
    pub restriction: Option<String>,
    /// One generic experiment: rank and dimension.
    pub single_rank: usize,
    pub single_n: usize,
    /// Smallest number of generic experiments of this family after which
    /// the rank stops growing, and the rank and dimension they reach.
    pub experiments: usize,
    pub rank: usize,
    pub n: usize,
}

impl FamilyReport {
    pub fn single_full(&self) -> bool {
        self.single_rank == self.single_n
    }
    pub fn full(&self) -> bool {
        self.rank == self.n
    }
}

/// One generic experiment of each of several distinct families, stacked.
#[derive(Clone, Debug)]
pub struct Combination {
    /// Indices into [`InputDesignReport::families`].
    pub families: Vec<usize>,
    pub rank: usize,
    pub n: usize,
}

/// The answer of [`design_inputs`].
#[derive(Clone, Debug)]
pub struct InputDesignReport {
    pub families: Vec<FamilyReport>,
    /// Inclusion-minimal sets of distinct families (two or more, none of
    /// which suffices alone) whose experiments together identify everything.
    pub combinations: Vec<Combination>,
    pub combinations_tried: usize,
    /// `false` when there were too many families (over 12) to combine.
    pub combinations_complete: bool,
    pub error_bound: f64,
}

/// Which families of the model's input restrictions (and free inputs) make
/// everything observable alone, in several experiments, or combined.
pub fn design_inputs(
    sys: &System,
    set: &[(String, Q)],
    opts: &DesignOptions,
) -> Result<InputDesignReport, AnalysisError> {
    let mut names: Vec<Option<String>> = vec![None];
    names.extend(sys.restrictions.iter().map(|r| Some(r.name.clone())));
    let mut error_bound: f64 = 0.0;
    let mut families = Vec::new();
    for r in &names {
        check_time(opts.deadline, 0)?;
        let exp = Experiment {
            restriction: r.clone(),
            set: set.to_vec(),
        };
        let mut one = sys
            .stacked_normal_form(std::slice::from_ref(&exp))
            .map_err(|e| AnalysisError::Invalid(e.to_string()))?;
        let r1 = rank(&mut one, rank_opts(opts.seed, opts.deadline))?;
        if r1.rank < r1.n {
            error_bound = error_bound.max(r1.error_bound);
        }
        let auto = experiments_auto(
            sys,
            r.as_deref(),
            set,
            AutoOptions {
                seed: opts.seed,
                deadline: opts.deadline,
                special: vec![],
            },
        )?;
        error_bound = error_bound.max(auto.error_bound);
        families.push(FamilyReport {
            restriction: r.clone(),
            single_rank: r1.rank,
            single_n: r1.n,
            experiments: auto.experiments,
            rank: auto.rank,
            n: auto.n,
        });
    }
    // Combinations of distinct families that do not suffice alone.
    let pool: Vec<usize> = (0..families.len())
        .filter(|&i| !families[i].single_full())
        .collect();
    let mut combinations: Vec<Combination> = Vec::new();
    let mut tried = 0usize;
    let p = pool.len();
    if p <= 12 {
        for k in 2..=p {
            let mut idx: Vec<usize> = (0..k).collect();
            loop {
                let fam: Vec<usize> = idx.iter().map(|&i| pool[i]).collect();
                if !combinations
                    .iter()
                    .any(|c| c.families.iter().all(|x| fam.contains(x)))
                {
                    check_time(opts.deadline, tried)?;
                    tried += 1;
                    let exps: Vec<Experiment> = fam
                        .iter()
                        .map(|&f| Experiment {
                            restriction: names[f].clone(),
                            set: set.to_vec(),
                        })
                        .collect();
                    let mut nf = sys
                        .stacked_normal_form(&exps)
                        .map_err(|e| AnalysisError::Invalid(e.to_string()))?;
                    let r = rank(&mut nf, rank_opts(opts.seed, opts.deadline))?;
                    if r.rank == r.n {
                        combinations.push(Combination {
                            families: fam,
                            rank: r.rank,
                            n: r.n,
                        });
                    } else {
                        error_bound = error_bound.max(r.error_bound);
                    }
                }
                if !next_combination(&mut idx, p) {
                    break;
                }
            }
        }
    }
    Ok(InputDesignReport {
        families,
        combinations,
        combinations_tried: tried,
        combinations_complete: p <= 12,
        error_bound,
    })
}

#[cfg(test)]
mod tests {
    use super::next_combination;

    // Every k-subset of 0..m once, in lexicographic order: C(5, k) of them.
    #[test]
    fn combinations_enumerate_each_subset_once() {
        for (k, count) in [(1, 5), (2, 10), (3, 10), (5, 1)] {
            let mut idx: Vec<usize> = (0..k).collect();
            let mut seen = vec![idx.clone()];
            while next_combination(&mut idx, 5) {
                assert!(idx.windows(2).all(|w| w[0] < w[1]) && idx[k - 1] < 5);
                assert!(seen.last().is_some_and(|p| *p < idx));
                seen.push(idx.clone());
            }
            assert_eq!(seen.len(), count, "C(5, {k})");
        }
    }
}
