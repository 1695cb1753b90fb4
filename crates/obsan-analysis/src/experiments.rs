//! The experimenter's questions: known initial conditions, and how many
//! experiments identify everything (docs/experiments.md).
//!
//! Known initial conditions. Knowing `x_K(0)` removes those coordinates from
//! the unknowns: the question is the rank, in the unknown columns `U`, of the
//! gradients of every Lie derivative `L_w h` (the output's derivatives at
//! t = 0 are polynomials in the input derivatives with these as
//! coefficients).
//! - Known but generic (`--known-generic`): the rank test's growth (only
//!   words that raised the rank are extended) is valid for the full
//!   gradients, so every gradient is a rational combination of the basis
//!   gradients, and so are their restrictions to `U`: the answer is the rank
//!   of the basis rows restricted to `U`, at random points (a lower bound,
//!   too low with the rank test's probability).
//! - Known specific values (`--known S=0`): at a given point that growth is
//!   wrong (the combination's coefficients may have a pole exactly there:
//!   `S' = 1 + a S^2`, `y = S` at `S = 0` has no `a` in orders 0-2 and `2a` in
//!   order 3), so every word is evaluated, order by order, at the point
//!   (known coordinates at their values, the others random). A non-zero
//!   minor there proves the rank at those values is at least what was found
//!   (certified lower bound); the rank of a matrix of analytic functions only
//!   drops on special points, so the generic-known rank is an upper bound.
//!   When the two meet, the rank is determined; otherwise both are reported
//!   with the order up to which every word was evaluated.
//!
//! Several experiments: `auto` stacks k generic experiments
//! ([`obsan_model::System::stacked_normal_form`]) for k = 1, 2, ... The rows
//! of experiment e involve only its states and the params, so the stacked
//! rank is `r_k = k a + s_k`, with `a` the rank of one experiment's rows in
//! its own state columns and `s_k` the dimension of the sum of the param
//! directions each experiment fixes once its states are eliminated. `s_k`
//! never decreases and is at most the number of params; once
//! `r_{k+1} - r_k = a` (`s_{k+1} = s_k`), a generic new experiment adds no
//! direction, hence none ever does (the condition holds for a generic
//! experiment, so for all): k is the smallest number of experiments.

use crate::rank::{lie_jets, random_point, rank, AnalysisError, Fields, LieWord, RankOptions};
use obsan_expr::{evaluate::FpPoint, lie::LieJets, Fp, FpEchelon, SplitMix, Var, Q};
use obsan_model::{Experiment, Kind, NormalForm, System};
use std::time::Instant;

/// A state (or param) whose initial value is known: a specific rational
/// value, or generic (known, but its value is not special).
#[derive(Clone, Debug, PartialEq)]
pub struct Known {
    /// Index into the normal form's `state`.
    pub index: usize,
    pub value: Option<Q>,
}

/// Options of [`rank_known`].
pub struct KnownOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// At a specific point: evaluate every word up to this order.
    pub max_order: usize,
    /// At a specific point: at most this many words in all.
    pub max_words: usize,
}

impl Default for KnownOptions {
    fn default() -> Self {
        KnownOptions {
            seed: 1,
            deadline: None,
            max_order: 12,
            max_words: 1_000,
        }
    }
}

/// The rank test with some initial conditions known.
#[derive(Clone, Debug)]
pub struct KnownReport {
    /// Indices (into the state) of the unknowns, in order.
    pub unknown: Vec<usize>,
    /// Rank in the unknown columns with the known values generic: an upper
    /// bound at any specific values (itself never too high, too low with
    /// probability at most `generic_error_bound`).
    pub generic_rank: usize,
    pub generic_error_bound: f64,
    /// With specific values: the rank found at that point, a certified
    /// lower bound (a non-zero minor there).
    pub point_rank: Option<usize>,
    /// The rank reported: `point_rank` if there are specific values, else
    /// `generic_rank`.
    pub rank: usize,
    /// Whether `rank` is the answer, as sure as the rank test's (full:
    /// proven; below: too low with probability at most
    /// `generic_error_bound`): known values generic, or M invariant, or the
    /// point's certified lower bound met the upper bound. `false`: only
    /// `point_rank <= rank at the values <= generic_rank` is known.
    pub determined: bool,
    /// With specific values: every field leaves the known coordinates at
    /// their values, so the rank is that of the system restricted to them
    /// (its rank test: never too high, too low with the generic bound).
    pub invariant: bool,
    /// With specific values: every word up to this order was evaluated.
    pub order_checked: usize,
    pub words_evaluated: usize,
    /// Lie words whose restricted gradients form the basis found.
    pub basis: Vec<LieWord>,
    pub fields: Fields,
    /// Per unknown (aligned with `unknown`): identifiable on its own.
    pub observable: Vec<bool>,
}

impl KnownReport {
    pub fn full(&self) -> bool {
        self.rank == self.unknown.len()
    }
}

fn restrict(g: &[Fp], cols: &[usize]) -> Vec<Fp> {
    cols.iter().map(|&c| g[c]).collect()
}

/// Rows of `words` at `point`, restricted to `cols`, into a basis.
fn restricted_basis(
    jets: &LieJets,
    words: &[LieWord],
    point: &FpPoint,
    cols: &[usize],
) -> Result<(FpEchelon, Vec<LieWord>), AnalysisError> {
    let mut b = FpEchelon::default();
    let mut kept = Vec::new();
    for w in words {
        let row = jets
            .row(w.output, &w.fields, point, false)
            .map_err(|_| AnalysisError::NoPoint)?;
        if b.insert(restrict(&row.gradient, cols)) {
            kept.push(w.clone());
        }
    }
    Ok((b, kept))
}

/// The generic rank in the columns `cols` (the other coordinates known but
/// generic), from the rank test's basis at two fresh random points.
/// Rank in the columns, per-column verdicts, the basis words kept, the rank
/// test's error bound and its fields.
type ColumnRank = (usize, Vec<bool>, Vec<LieWord>, f64, Fields);

pub(crate) fn rank_in_columns(
    nf: &mut NormalForm,
    cols: &[usize],
    seed: u64,
    deadline: Option<Instant>,
) -> Result<ColumnRank, AnalysisError> {
    let r = rank(
        nf,
        RankOptions {
            seed,
            deadline,
            progress: None,
        },
    )?;
    let jets = lie_jets(nf, &r.fields);
    let mut rng = SplitMix(seed ^ 0x6b6e_6f77_6e00_0001);
    let mut best: Option<(FpEchelon, Vec<LieWord>)> = None;
    for _ in 0..2 {
        let p = random_point(&mut nf.ctx, &mut rng)?;
        let b = restricted_basis(&jets, &r.basis, &p, cols)?;
        if best.as_ref().is_none_or(|x| b.0.rank() > x.0.rank()) {
            best = Some(b);
        }
    }
    let (b, kept) = best.ok_or(AnalysisError::NoPoint)?;
    let obs = (0..cols.len())
        .map(|i| b.contains_unit(i, cols.len()))
        .collect();
    // Minors of the restricted rows are minors of the full rows' entries.
    Ok((b.rank(), obs, kept, r.error_bound, r.fields))
}

/// Names that appear in a leaf's text (identifiers may contain `@`).
fn mentions(text: &str, name: &str) -> bool {
    text.split(|c: char| !(c.is_alphanumeric() || c == '_' || c == '@'))
        .any(|t| t == name)
}

/// The rank test with the initial conditions `known` (docs/experiments.md).
pub fn rank_known(
    nf: &mut NormalForm,
    known: &[Known],
    opts: KnownOptions,
) -> Result<KnownReport, AnalysisError> {
    let n = nf.state.len();
    let unknown: Vec<usize> = (0..n)
        .filter(|i| !known.iter().any(|k| k.index == *i))
        .collect();
    let (generic_rank, generic_obs, generic_basis, generic_error_bound, fields) =
        rank_in_columns(nf, &unknown, opts.seed, opts.deadline)?;
    let specific = specific_values(nf, known)?;
    if specific.is_empty() {
        return Ok(KnownReport {
            rank: generic_rank,
            determined: true,
            invariant: false,
            point_rank: None,
            order_checked: 0,
            words_evaluated: 0,
            basis: generic_basis,
            fields,
            observable: generic_obs,
            unknown,
            generic_rank,
            generic_error_bound,
        });
    }
    refuse_functions_of_known(nf, &specific)?;
    // If every field leaves the known coordinates where they are, the state
    // stays on M = {x_K = values}, where the Lie derivatives are those of
    // the system restricted to M: its rank test (valid there with pruning)
    // gives the rank at generic points of M, not just a bound.
    let invariant = reduce_on_invariant(nf, known)?;
    let upper = match &invariant {
        Some((m, cols)) => {
            let mut m = m.clone();
            let (r, _, _, _, _) = rank_in_columns(&mut m, cols, opts.seed, opts.deadline)?;
            r
        }
        None => generic_rank,
    };
    let fixed: Vec<(Var, Fp)> = specific.iter().map(|s| (s.0, s.1)).collect();
    let point = point_with_known(nf, opts.seed, &fixed)?;
    let cap = upper.min(unknown.len());
    let at = words_at_point(nf, &fields, &point, &unknown, cap, &opts)?;
    let (point_rank, words, evaluated, order_checked) =
        (at.rank, at.words, at.evaluated, at.order_checked);
    let observable = at.observable;
    let (rank, observable) = match &invariant {
        // The restricted system's rank test is the answer on M.
        Some((m, cols)) => {
            let mut m = m.clone();
            let (r, obs, _, _, _) = rank_in_columns(&mut m, cols, opts.seed, opts.deadline)?;
            (r, obs)
        }
        None => (point_rank, observable),
    };
    Ok(KnownReport {
        rank,
        invariant: invariant.is_some(),
        determined: invariant.is_some()
            || point_rank == unknown.len()
            || point_rank == generic_rank,
        point_rank: Some(point_rank),
        order_checked,
        words_evaluated: evaluated,
        basis: words,
        fields,
        observable,
        unknown,
        generic_rank,
        generic_error_bound,
    })
}

/// The known values at a specific point, in F_p, with their variables and names.
fn specific_values(
    nf: &NormalForm,
    known: &[Known],
) -> Result<Vec<(Var, Fp, String)>, AnalysisError> {
    known
        .iter()
        .filter_map(|k| k.value.as_ref().map(|q| (k.index, q)))
        .map(|(i, q)| {
            q.to_fp()
                .map(|f| (nf.state_vars[i], f, nf.state[i].clone()))
                .ok_or_else(|| {
                    AnalysisError::Invalid(format!(
                        "the value {q} of {} has a denominator divisible by 2^61-1",
                        nf.state[i]
                    ))
                })
        })
        .collect()
}

/// A value fixes a symbol; a function of it (sin, exp, atan ...) is an
/// atom the point would give an unrelated random value, so refuse. A
/// square root is computed from its radicand at the point: consistent.
fn refuse_functions_of_known(
    nf: &NormalForm,
    specific: &[(Var, Fp, String)],
) -> Result<(), AnalysisError> {
    for v in 0..nf.ctx.leaf_count() {
        let v = v as Var;
        if nf.ctx.symbol_name(v).is_some() || nf.ctx.sqrt_arg(v).is_some() {
            continue;
        }
        let text = nf.ctx.leaf_text(v);
        if let Some((_, _, name)) = specific.iter().find(|s| mentions(&text, &s.2)) {
            return Err(AnalysisError::Invalid(format!(
                "--known {name}=...: {name} appears inside {text}, whose value at a specific point is not a rational number obsan evaluates exactly; use --known-generic {name}"
            )));
        }
    }
    Ok(())
}

/// A random F_p point with the known values `fixed`, avoiding the system's poles (64
/// tries).
fn point_with_known(
    nf: &mut NormalForm,
    seed: u64,
    fixed: &[(Var, Fp)],
) -> Result<FpPoint, AnalysisError> {
    let mut rng = SplitMix(seed ^ 0x6b6e_6f77_6e00_0002);
    for _ in 0..64 {
        if let Ok(p) = nf
            .ctx
            .random_fp_point(&mut rng, &|v| fixed.iter().find(|f| f.0 == v).map(|f| f.1))
        {
            return Ok(p);
        }
    }
    Err(AnalysisError::Invalid(
        "no point with the known values avoided the system's poles (is a denominator zero there?)"
            .into(),
    ))
}

/// What [`words_at_point`] found at the point.
struct PointRank {
    rank: usize,
    observable: Vec<bool>,
    /// The words whose gradients raised the rank.
    words: Vec<LieWord>,
    evaluated: usize,
    order_checked: usize,
}

/// The rank at one point of the gradients (restricted to the `unknown` columns) of
/// every word, order by order (no pruning: see the module doc), until `cap` rows, the
/// order `opts.max_order` or `opts.max_words` words.
fn words_at_point(
    nf: &NormalForm,
    fields: &Fields,
    point: &FpPoint,
    unknown: &[usize],
    cap: usize,
    opts: &KnownOptions,
) -> Result<PointRank, AnalysisError> {
    let jets = lie_jets(nf, fields);
    // Every word, order by order (no pruning: see the module doc).
    let n_out = nf.outputs.len();
    let mut level: Vec<LieWord> = (0..n_out)
        .map(|o| LieWord {
            output: o,
            fields: vec![],
        })
        .collect();
    let mut basis = FpEchelon::default();
    let mut words = Vec::new();
    let mut evaluated = 0usize;
    let mut order_checked = 0usize;
    'orders: for order in 0..=opts.max_order {
        for w in &level {
            if obsan_expr::cancel_requested() {
                return Err(AnalysisError::Cancelled);
            }
            if let Some(d) = opts.deadline {
                if Instant::now() > d {
                    return Err(AnalysisError::Timeout(format!(
                        "at Lie derivative order {order}, rank {} at the point so far",
                        basis.rank()
                    )));
                }
            }
            let row = jets.row(w.output, &w.fields, point, false).map_err(|_| {
                AnalysisError::Invalid(format!(
                    "a Lie derivative has a pole at the known values ({})",
                    w.display(
                        &fields.names,
                        &nf.outputs.iter().map(|o| o.0.clone()).collect::<Vec<_>>()
                    )
                ))
            })?;
            evaluated += 1;
            if basis.insert(restrict(&row.gradient, unknown)) {
                words.push(w.clone());
            }
            if basis.rank() >= cap {
                order_checked = order;
                break 'orders;
            }
        }
        order_checked = order;
        if order == opts.max_order {
            break;
        }
        let mut next = Vec::new();
        for w in &level {
            for k in 0..fields.vectors.len() {
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
        if next.is_empty() || evaluated + next.len() > opts.max_words {
            break;
        }
        level = next;
    }
    Ok(PointRank {
        rank: basis.rank(),
        observable: (0..unknown.len())
            .map(|i| basis.contains_unit(i, unknown.len()))
            .collect(),
        words,
        evaluated,
        order_checked,
    })
}

/// Options of [`experiments_auto`].
pub struct AutoOptions {
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Values of the experiment constants tried for degeneracy.
    pub special: Vec<Q>,
}

impl Default for AutoOptions {
    fn default() -> Self {
        let q = |n: i64, d: i64| Q::new(n.into(), d.into());
        AutoOptions {
            seed: 1,
            deadline: None,
            special: vec![
                q(0, 1),
                q(1, 1),
                q(-1, 1),
                q(2, 1),
                q(-2, 1),
                q(1, 2),
                q(-1, 2),
            ],
        }
    }
}

/// A special value of an experiment constant and what it does.
#[derive(Clone, Debug)]
pub struct SpecialValue {
    pub constant: String,
    pub value: Q,
    /// Rank of one experiment at this value (generic: [`AutoReport::ranks`]`[0]`).
    pub single_rank: usize,
    /// Rank of the minimal design with one experiment at this value and the
    /// others generic (generic design: [`AutoReport::rank`]).
    pub design_rank: usize,
    /// It gives less than a generic experiment: either rank drops.
    pub degenerate: bool,
}

/// `--experiments auto`: the smallest number of generic experiments after
/// which the rank stops growing.
#[derive(Clone, Debug)]
pub struct AutoReport {
    /// `(k, rank, n)` of k stacked generic experiments, k = 1, 2, ...
    pub ranks: Vec<(usize, usize, usize)>,
    /// `a`: the rank of one experiment's rows in its own state columns.
    pub state_rank: usize,
    /// The smallest number of experiments: the rank of one more grows by
    /// `state_rank` only (or the stack is of full rank).
    pub experiments: usize,
    /// Rank and dimension of that stack.
    pub rank: usize,
    pub n: usize,
    /// The param directions fixed by that stack (`s_k`) and the params.
    pub param_rank: usize,
    pub n_params: usize,
    /// The constants that vary between experiments (their values generic).
    pub constants: Vec<String>,
    pub special: Vec<SpecialValue>,
    /// Special values at which a denominator of the system is zero (no
    /// experiment to run there).
    pub poles: Vec<(String, Q)>,
    /// Largest error bound among the probabilistic ranks used.
    pub error_bound: f64,
}

fn stack(sys: &System, exps: &[Experiment]) -> Result<NormalForm, AnalysisError> {
    sys.stacked_normal_form(exps)
        .map_err(|e| AnalysisError::Invalid(e.to_string()))
}

fn rank_of(
    nf: &mut NormalForm,
    seed: u64,
    deadline: Option<Instant>,
) -> Result<(usize, f64), AnalysisError> {
    let r = rank(
        nf,
        RankOptions {
            seed,
            deadline,
            progress: None,
        },
    )?;
    let eb = if r.rank == r.n { 0.0 } else { r.error_bound };
    Ok((r.rank, eb))
}

/// The constants a restriction mentions (they vary between experiments).
fn restriction_consts(
    sys: &System,
    restriction: Option<&str>,
) -> Result<Vec<String>, AnalysisError> {
    let probe = [Experiment {
        restriction: restriction.map(str::to_string),
        set: vec![],
    }];
    let nf = stack(sys, &probe)?;
    Ok(sys
        .decls_of(Kind::Const)
        .filter(|d| {
            nf.consts
                .iter()
                .any(|(c, _)| c == &obsan_model::experiment_name(&d.name, 1))
        })
        .map(|d| d.name.clone())
        .collect())
}

/// The smallest number of generic experiments (all under `restriction`,
/// with `set` values) after which the rank stops growing, and which special
/// values of the experiment constants are degenerate (module doc).
pub fn experiments_auto(
    sys: &System,
    restriction: Option<&str>,
    set: &[(String, Q)],
    opts: AutoOptions,
) -> Result<AutoReport, AnalysisError> {
    let generic = Experiment {
        restriction: restriction.map(str::to_string),
        set: set.to_vec(),
    };
    let nd = sys.decls_of(Kind::State).count();
    let n_params = sys.decls_of(Kind::Param).count();
    let mut error_bound: f64 = 0.0;
    // a: one experiment's rank in its own state columns.
    let mut one = stack(sys, std::slice::from_ref(&generic))?;
    let cols: Vec<usize> = (0..nd).collect();
    let (a, _, _, eb, _) = rank_in_columns(&mut one, &cols, opts.seed, opts.deadline)?;
    if a < nd {
        error_bound = error_bound.max(eb);
    }
    let mut ranks: Vec<(usize, usize, usize)> = Vec::new();
    let mut k = 1;
    let chosen = loop {
        let exps = vec![generic.clone(); k];
        let mut nf = stack(sys, &exps)?;
        let n = nf.state.len();
        let (r, eb) = rank_of(&mut nf, opts.seed, opts.deadline)?;
        error_bound = error_bound.max(eb);
        ranks.push((k, r, n));
        if r == n {
            break k;
        }
        if k >= 2 {
            let prev = ranks[k - 2].1;
            if r <= prev + a {
                break k - 1;
            }
        }
        // s_k grows by at least one per experiment until it stops, and is at
        // most the number of params: the loop ends by k = n_params + 2.
        if k > n_params + 2 {
            return Err(AnalysisError::Invalid(format!(
                "the rank kept growing past {k} experiments with {n_params} params: the ranks {ranks:?} contradict r_k = k a + s_k (a = {a})"
            )));
        }
        k += 1;
    };
    let (_, rank_k, n_k) = ranks[chosen - 1];
    let param_rank = rank_k - chosen * a;
    let constants = restriction_consts(sys, restriction)?
        .into_iter()
        .filter(|c| !set.iter().any(|(n, _)| n == c))
        .collect::<Vec<_>>();
    let mut special = Vec::new();
    let mut poles = Vec::new();
    for c in &constants {
        for v in &opts.special {
            let mut sx = generic.clone();
            sx.set.push((c.clone(), v.clone()));
            let single = match stack(sys, std::slice::from_ref(&sx))
                .and_then(|mut nf| rank_of(&mut nf, opts.seed, opts.deadline))
            {
                Ok(x) => x,
                // A value that makes a denominator zero is degenerate too,
                // but not an experiment one can run; skip it, said as such.
                Err(AnalysisError::Invalid(_)) | Err(AnalysisError::NoPoint) => {
                    poles.push((c.clone(), v.clone()));
                    continue;
                }
                Err(e) => return Err(e),
            };
            let mut exps = vec![generic.clone(); chosen - 1];
            exps.push(sx);
            let mut nf = stack(sys, &exps)?;
            let (design, eb2) = rank_of(&mut nf, opts.seed, opts.deadline)?;
            error_bound = error_bound.max(single.1).max(eb2);
            special.push(SpecialValue {
                constant: c.clone(),
                value: v.clone(),
                single_rank: single.0,
                design_rank: design,
                degenerate: single.0 < ranks[0].1 || design < rank_k,
            });
        }
    }
    Ok(AutoReport {
        ranks,
        state_rank: a,
        experiments: chosen,
        rank: rank_k,
        n: n_k,
        param_rank,
        n_params,
        constants,
        special,
        poles,
        error_bound,
    })
}

/// The system on `M = {x_K = values}` when every field's known components
/// vanish there (M invariant), with the positions of the unknowns in it
/// (known-generic coordinates stay as states); `None` when M is not
/// invariant.
fn reduce_on_invariant(
    nf: &mut NormalForm,
    known: &[Known],
) -> Result<Option<(NormalForm, Vec<usize>)>, AnalysisError> {
    let mut map = Vec::new();
    for k in known {
        if let Some(q) = &k.value {
            let id = nf.ctx.num(q.clone());
            map.push((nf.state_vars[k.index], id));
        }
    }
    let mut m = nf.clone();
    let sub = |m: &mut NormalForm, id| {
        m.ctx
            .substitute(id, &map)
            .map_err(|e| AnalysisError::Invalid(format!("at the known values: {}", e.0)))
    };
    let n = m.state.len();
    let fixed: Vec<bool> = (0..n)
        .map(|i| known.iter().any(|k| k.index == i && k.value.is_some()))
        .collect();
    let mut f0 = Vec::new();
    for (i, &fx) in fixed.iter().enumerate() {
        let f = sub(&mut m, nf.f0[i])?;
        if fx {
            if !m.ctx.is_identically_zero(f) {
                return Ok(None);
            }
        } else {
            f0.push(f);
        }
    }
    let mut fields = Vec::new();
    for fi in &nf.fields {
        let mut v = Vec::new();
        for (&g, &fx) in fi.iter().zip(&fixed) {
            let f = sub(&mut m, g)?;
            if fx {
                if !m.ctx.is_identically_zero(f) {
                    return Ok(None);
                }
            } else {
                v.push(f);
            }
        }
        fields.push(v);
    }
    // (A delay's first-order fields are -tau f_i: they vanish with f_i.)
    let mut outputs = Vec::new();
    for (name, h) in nf.outputs.clone() {
        outputs.push((name, sub(&mut m, h)?));
    }
    let keep: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
    m.state = keep.iter().map(|&i| nf.state[i].clone()).collect();
    m.state_vars = keep.iter().map(|&i| nf.state_vars[i]).collect();
    m.n_dynamic = keep.iter().filter(|&&i| i < nf.n_dynamic).count();
    m.delay = nf.delay.and_then(|d| keep.iter().position(|&i| i == d));
    m.f0 = f0;
    m.fields = fields;
    m.outputs = outputs;
    let cols = keep
        .iter()
        .enumerate()
        .filter(|(_, &i)| !known.iter().any(|k| k.index == i))
        .map(|(j, _)| j)
        .collect();
    Ok(Some((m, cols)))
}
