//! The observability rank test (Hermann–Krener), exactly modulo a prime at
//! random points (engine.md section 3).
//!
//! The codistribution is grown level by level: level 0 is the outputs; level
//! k+1 is `L_f phi` for every field f (the drift f0 when it is not zero, and
//! each input field) and every function phi *kept* at level k. A function is
//! kept when its gradient at the point raises the rank. If d(phi) is in the
//! span, d(L_f phi) is in the span of the old gradients and of the L_f of the
//! kept functions, so nothing is lost; the growth stops when a level adds
//! nothing, after at most n levels.
//!
//! Each Lie derivative's gradient is evaluated at the point by truncated
//! Taylor jets along the flows of the fields ([`obsan_expr::lie::LieJets`]), never
//! built as an expression: the cost is polynomial in the order. The degree
//! bound of each row comes from the same computation (see that module). The
//! older route, which builds every Lie derivative on the expression graph
//! and differentiates it, stays as [`rank_symbolic`], an independent
//! computation for the tests.

use crate::fields::field_names;
use obsan_expr::{
    evaluate::degree_bounds, evaluate::BadPoint, evaluate::FpPoint, lie::reached_states,
    lie::LieJets, Ctx, Fp, Id, SplitMix, Var, P,
};
use obsan_model::NormalForm;
use std::collections::HashMap;
use std::fmt;
use std::time::Instant;

/// A Lie derivative, named by the fields applied to an output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LieWord {
    pub output: usize,
    /// Field indices (into [`Fields`]) in the order applied: `[a, b]` is `L_b L_a h`.
    pub fields: Vec<usize>,
}

impl LieWord {
    pub fn order(&self) -> usize {
        self.fields.len()
    }
    /// Operator notation, last field applied first: `L_wL L_wR beta`.
    pub fn display(&self, field_names: &[String], outputs: &[String]) -> String {
        let mut s = String::new();
        for &f in self.fields.iter().rev() {
            s.push_str(&format!("L_{} ", field_names[f]));
        }
        s.push_str(&outputs[self.output]);
        s
    }
}

/// The vector fields of a normal form: the drift (when not identically zero)
/// and one field per input.
#[derive(Clone, Debug)]
pub struct Fields {
    pub names: Vec<String>,
    pub vectors: Vec<Vec<Id>>,
}

impl Fields {
    pub fn of(nf: &mut NormalForm) -> Fields {
        let (names, vectors) = field_names(nf);
        Fields { names, vectors }
    }
}

/// Options of the rank test.
pub struct RankOptions<'a> {
    pub seed: u64,
    /// Give up (with [`AnalysisError::Timeout`]) after this instant.
    pub deadline: Option<Instant>,
    /// Called after each level: (level, rank so far, state dimension).
    pub progress: Option<&'a mut dyn FnMut(usize, usize, usize)>,
}

impl Default for RankOptions<'_> {
    fn default() -> Self {
        RankOptions {
            seed: 1,
            deadline: None,
            progress: None,
        }
    }
}

/// Errors of the analysis.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum AnalysisError {
    /// The deadline passed; the message says how far it got.
    Timeout(String),
    /// No usable random point was found (poles or non-square radicands everywhere).
    NoPoint,
    /// Anything else, with a message for the user.
    Invalid(String),
    /// The caller asked the computation to stop ([`obsan_expr::with_cancel`]).
    Cancelled,
}

impl fmt::Display for AnalysisError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AnalysisError::Timeout(s) => write!(f, "timed out: {s}"),
            AnalysisError::NoPoint => f.write_str("no random point avoided the poles of the system and satisfied its roots' relations mod p = 2^61-1 (is a denominator identically zero on the domain, or do radicands multiply to a constant with no root mod p, as sqrt(42/(5x)) sqrt(5x/6) = sqrt(7)? `obsan rank` certifies such roots in an extension field; this command needs points mod p)"),
            AnalysisError::Invalid(s) => f.write_str(s),
            AnalysisError::Cancelled => f.write_str("interrupted"),
        }
    }
}
impl std::error::Error for AnalysisError {}

/// The result of the rank test.
#[derive(Clone, Debug)]
pub struct RankReport {
    /// Dimension of the analysed state.
    pub n: usize,
    /// Generic rank of the observability codistribution.
    pub rank: usize,
    /// Lie derivatives whose gradients form a basis, in the order found
    /// (their expressions: [`RankReport::basis_functions`]).
    pub basis: Vec<LieWord>,
    /// The highest order among the basis functions.
    pub max_order: usize,
    /// How many Lie derivatives were evaluated.
    pub evaluated: usize,
    /// Per state variable: whether it is observable on its own (e_i in the span).
    pub observable: Vec<bool>,
    /// Pivot columns of the basis rows (a non-singular minor), at the point.
    pub pivots: Vec<usize>,
    /// Schwartz–Zippel degree bound D of the minors involved.
    pub degree_bound: u64,
    /// Probability that the reported rank is below the generic rank: (D/p)^2
    /// for two independent points. (The rank is never above it.)
    pub error_bound: f64,
    pub fields: Fields,
    /// The seed the points were drawn from.
    pub seed: u64,
    /// No point mod p satisfies the root leaves' relations together (their
    /// radicands multiply to a constant that is no power mod p), so the roots
    /// took free values ([`Ctx::random_fp_point_free_roots`]): the rank is an
    /// upper bound, as over undecided atoms.
    pub free_roots: bool,
    /// `Some(k)`: no point of F_p satisfied the roots' relations, and the
    /// rank was certified at a point of F_(p^k) where every root is a root
    /// of its radicand (rank_roots.rs); `free_roots` is then false.
    pub roots_field: Option<u32>,
}

/// Row echelon basis over F_p: obsan-recon's one elimination on the
/// engine's field (the unknown-input routes use it too).
pub(crate) use obsan_expr::FpEchelon as Echelon;

pub(crate) fn random_point(ctx: &mut Ctx, rng: &mut SplitMix) -> Result<FpPoint, AnalysisError> {
    random_point_counted(ctx, rng).map(|p| p.0)
}

/// A random point and the number of draws it took. Each square root needs
/// its radicand to be a square mod p (half the values), so a system with k
/// independent radicands (e.g. ranges to k landmarks) needs about 2^k draws;
/// up to 2^22 are tried. The accepted point is uniform on the points where
/// every radicand is a square, a set of density about 1/draws, so the
/// Schwartz–Zippel bound D/p of a bad point grows by that factor at most.
/// With roots, [`exact_draws`] bounds the tries (the rank's count: where
/// points exist, that many failures have probability below e^-64), so a
/// system no point satisfies (BIG's `sqrt(7)`) fails in a moment, not 2^22
/// draws later.
pub(crate) fn random_point_counted(
    ctx: &mut Ctx,
    rng: &mut SplitMix,
) -> Result<(FpPoint, u64), AnalysisError> {
    let tries = if has_roots(ctx) {
        exact_draws(ctx)
    } else {
        1u64 << 22
    };
    for k in 1..=tries {
        if let Ok(p) = ctx.random_fp_point(rng, &|_| None) {
            return Ok((p, k));
        }
    }
    Err(AnalysisError::NoPoint)
}

/// Gradient ids of `f` with respect to the state.
pub(crate) fn gradient(nf: &mut NormalForm, f: Id) -> Vec<Id> {
    let vars = nf.state_vars.clone();
    vars.iter().map(|&x| nf.ctx.diff(f, x)).collect()
}

struct Run {
    basis: Vec<LieWord>,
    echelon: Echelon,
    evaluated: usize,
    degree: u64,
    worst_rejected: u64,
    point: FpPoint,
}

fn row_degree(ctx: &Ctx, grad: &[Id]) -> u64 {
    let d = degree_bounds(ctx, grad);
    let max_num = d.iter().map(|x| x.0).max().unwrap_or(0);
    let sum_den: u64 = d.iter().map(|x| x.1).fold(0, u64::saturating_add);
    max_num.saturating_add(sum_den)
}

/// How one route of the rank test gets rows: the symbolic route carries each
/// Lie derivative's graph id, the jet route nothing (a word is enough).
trait Rows {
    type Node;
    /// The gradient of the word's Lie derivative at the point, and the
    /// Schwartz–Zippel degree of its entries.
    fn row(
        &mut self,
        nf: &mut NormalForm,
        word: &LieWord,
        node: &Self::Node,
        point: &FpPoint,
    ) -> Result<(Vec<Fp>, u64), AnalysisError>;
    /// The Lie derivative of `node` along field `k`; `None` when it is
    /// structurally zero (never evaluated, never counted).
    fn extend(
        &mut self,
        nf: &mut NormalForm,
        word: &LieWord,
        node: &Self::Node,
        k: usize,
    ) -> Option<Self::Node>;
}

/// Every Lie derivative built on the expression graph, its gradient
/// differentiated there and evaluated at the point.
struct SymbolicRows<'a> {
    /// The reached state variables and the fields' components along them.
    vars: &'a [Var],
    vectors: &'a [Vec<Id>],
}

impl Rows for SymbolicRows<'_> {
    type Node = Id;
    fn row(
        &mut self,
        nf: &mut NormalForm,
        _: &LieWord,
        f: &Id,
        point: &FpPoint,
    ) -> Result<(Vec<Fp>, u64), AnalysisError> {
        let grad: Vec<Id> = self.vars.iter().map(|&x| nf.ctx.diff(*f, x)).collect();
        let vals = nf
            .ctx
            .eval_fp(&grad, point)
            .map_err(|BadPoint| AnalysisError::NoPoint)?;
        Ok((vals, row_degree(&nf.ctx, &grad)))
    }
    fn extend(&mut self, nf: &mut NormalForm, _: &LieWord, f: &Id, k: usize) -> Option<Id> {
        let g = nf.ctx.lie_derivative(*f, self.vars, &self.vectors[k]);
        (!nf.ctx.is_zero(g)).then_some(g)
    }
}

/// Gradients by Taylor jets at the point; degree bounds depend on the word
/// only, so they are computed at the first point and kept.
struct JetRows<'a> {
    jets: &'a LieJets,
    degrees: &'a mut HashMap<(usize, Vec<usize>), u64>,
    /// Gradients at this point of the words of one field repeated, by
    /// (output, field, order): one sweep of a longer such word gives every
    /// shorter one ([`LieJets::run_rows`]).
    runs: HashMap<(usize, usize, usize), Vec<Fp>>,
    /// The longest word the growth can ask for (it stops once every level
    /// has raised the rank: at most m - 1 fields for m columns).
    cap: usize,
    /// Whether to compute degree bounds (not needed when the rank is full:
    /// a non-zero minor proves it). Off, every degree reads 0.
    track: bool,
}

impl JetRows<'_> {
    /// The row of `field` applied `k` times to `output`, from the cache or
    /// from the sweep of a longer run: twice as long (so the sweeps of a
    /// chain of orders cost a constant factor of the last one, O(k^2) each),
    /// or the longest possible once that is within four times as long.
    fn run_row(
        &mut self,
        output: usize,
        field: usize,
        k: usize,
        point: &FpPoint,
    ) -> Result<Option<(Vec<Fp>, u64)>, AnalysisError> {
        let key = (output, field, k);
        if !self.runs.contains_key(&key) {
            let mut len = if 4 * k >= self.cap { self.cap } else { 2 * k }.max(k);
            if obsan_expr::limits::check_memory(self.jets.sweep_bytes(&vec![field; len]), "")
                .is_err()
            {
                len = k;
            }
            obsan_expr::limits::check_memory(
                self.jets.sweep_bytes(&vec![field; len]),
                "the jets of the rank test",
            )
            .map_err(|l| AnalysisError::Invalid(l.to_string()))?;
            let track = self.track
                && (1..=len).any(|j| !self.degrees.contains_key(&(output, vec![field; j])));
            let rows = self
                .jets
                .run_rows(output, field, len, point, track)
                .map_err(|BadPoint| AnalysisError::NoPoint)?;
            for (j, row) in rows.into_iter().enumerate().skip(1) {
                if let Some(d) = row.degree {
                    self.degrees.entry((output, vec![field; j])).or_insert(d);
                }
                self.runs.insert((output, field, j), row.gradient);
            }
        }
        let degree = self.degrees.get(&(output, vec![field; k])).copied();
        Ok(self
            .runs
            .get(&key)
            .map(|g| (g.clone(), degree.unwrap_or(0))))
    }
}

impl Rows for JetRows<'_> {
    type Node = ();
    fn row(
        &mut self,
        _: &mut NormalForm,
        word: &LieWord,
        _: &(),
        point: &FpPoint,
    ) -> Result<(Vec<Fp>, u64), AnalysisError> {
        if let [first, rest @ ..] = word.fields.as_slice() {
            if rest.iter().all(|f| f == first) {
                let k = word.fields.len();
                if let Some(r) = self.run_row(word.output, *first, k, point)? {
                    return Ok(r);
                }
            }
        }
        let key = (word.output, word.fields.clone());
        let known = self.degrees.get(&key).copied();
        obsan_expr::limits::check_memory(
            self.jets.sweep_bytes(&word.fields),
            "the jets of the rank test",
        )
        .map_err(|l| AnalysisError::Invalid(l.to_string()))?;
        let row = self
            .jets
            .row(
                word.output,
                &word.fields,
                point,
                self.track && known.is_none(),
            )
            .map_err(|BadPoint| AnalysisError::NoPoint)?;
        let degree = known.or(row.degree).unwrap_or(0);
        if self.track {
            self.degrees.insert(key, degree);
        }
        Ok((row.gradient, degree))
    }
    fn extend(&mut self, _: &mut NormalForm, word: &LieWord, _: &(), k: usize) -> Option<()> {
        let mut fields = word.fields.clone();
        fields.push(k);
        // Structurally zero (the symbolic route's `is_zero` skip).
        self.jets.support(word.output, &fields).map(|_| ())
    }
}

/// Breadth-first growth of the basis: the outputs, then the Lie derivatives
/// of the kept words along every field, until the rank is n or no word of
/// the last order was independent.
fn grow<R: Rows>(
    nf: &mut NormalForm,
    rows: &mut R,
    roots: Vec<R::Node>,
    fields: &Fields,
    point: FpPoint,
    opts: &mut RankOptions,
    m: usize,
) -> Result<Run, AnalysisError> {
    // The rows have one column per reached variable; the full rank is m.
    let n = m;
    let mut run = Run {
        basis: vec![],
        echelon: Echelon::default(),
        evaluated: 0,
        degree: 0,
        worst_rejected: 0,
        point,
    };
    let mut level: Vec<(LieWord, R::Node)> = roots
        .into_iter()
        .enumerate()
        .map(|(i, node)| {
            (
                LieWord {
                    output: i,
                    fields: vec![],
                },
                node,
            )
        })
        .collect();
    let outputs: Vec<String> = nf.outputs.iter().map(|o| o.0.clone()).collect();
    let mut depth = 0;
    loop {
        let mut kept = Vec::new();
        for (word, node) in level {
            // The F_p rows never enter the engine's armed scope, which is
            // where a cancel is otherwise noticed.
            if obsan_expr::cancel_requested() {
                return Err(AnalysisError::Cancelled);
            }
            if let Some(d) = opts.deadline {
                if Instant::now() > d {
                    return Err(AnalysisError::Timeout(format!(
                        "at Lie derivative order {depth}, rank {} of {n} so far (last: {})",
                        run.echelon.rank(),
                        word.display(&fields.names, &outputs)
                    )));
                }
            }
            let (vals, degree) = rows.row(nf, &word, &node, &run.point)?;
            run.evaluated += 1;
            if run.echelon.insert(vals) {
                run.degree = run.degree.saturating_add(degree);
                kept.push((word.clone(), node));
                run.basis.push(word);
            } else {
                run.worst_rejected = run.worst_rejected.max(degree);
            }
            if run.echelon.rank() == n {
                break;
            }
        }
        if let Some(p) = opts.progress.as_mut() {
            p(depth, run.echelon.rank(), n);
        }
        if kept.is_empty() || run.echelon.rank() == n {
            break;
        }
        depth += 1;
        let mut next = Vec::new();
        for (word, node) in &kept {
            for k in 0..fields.vectors.len() {
                if let Some(g) = rows.extend(nf, word, node, k) {
                    let mut w = word.clone();
                    w.fields.push(k);
                    next.push((w, g));
                }
            }
        }
        level = next;
    }
    Ok(run)
}

/// Outputs and fields compiled for jet evaluation.
pub(crate) fn lie_jets(nf: &NormalForm, fields: &Fields) -> LieJets {
    let outputs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    LieJets::new(&nf.ctx, &nf.state_vars, &fields.vectors, &outputs)
}

impl RankReport {
    /// The basis Lie derivatives as expressions on the graph (built here,
    /// prefixes shared; the rank test itself never builds them).
    pub fn basis_functions(&self, nf: &mut NormalForm) -> Vec<Id> {
        self.words_on_graph(nf, &self.basis)
    }

    /// Lie derivatives along `words` on the expression graph (never
    /// canonicalised), prefixes shared.
    pub(crate) fn words_on_graph(&self, nf: &mut NormalForm, words: &[LieWord]) -> Vec<Id> {
        let mut memo: std::collections::HashMap<(usize, Vec<usize>), Id> = Default::default();
        let vars = nf.state_vars.clone();
        words
            .iter()
            .map(|w| {
                let mut g = nf.outputs[w.output].1;
                for (i, &k) in w.fields.iter().enumerate() {
                    let key = (w.output, w.fields[..=i].to_vec());
                    g = match memo.get(&key) {
                        Some(&x) => x,
                        None => {
                            // The fields as written (obsan-expr written.rs):
                            // the same functions, a far smaller graph.
                            let f: Vec<Id> = self.fields.vectors[k]
                                .iter()
                                .map(|&c| nf.ctx.written_form(c))
                                .collect();
                            let x = nf.ctx.lie_derivative(g, &vars, &f);
                            memo.insert(key, x);
                            x
                        }
                    };
                }
                g
            })
            .collect()
    }
}

/// The generic rank of the observability codistribution, by two independent
/// runs at random points of F_p (the larger is the answer).
pub fn rank(nf: &mut NormalForm, opts: RankOptions) -> Result<RankReport, AnalysisError> {
    rank_with(nf, opts, false)
}

/// [`rank`] by the older route: every Lie derivative built on the expression
/// graph and differentiated there, its gradient evaluated at the point, the
/// degree bound from the gradient expressions. The same points and the same
/// growth, so the same ranks, words and pivots; kept as an independent
/// computation for the tests (and much slower at high orders).
pub fn rank_symbolic(nf: &mut NormalForm, opts: RankOptions) -> Result<RankReport, AnalysisError> {
    rank_with(nf, opts, true)
}

fn rank_with(
    nf: &mut NormalForm,
    mut opts: RankOptions,
    symbolic: bool,
) -> Result<RankReport, AnalysisError> {
    let fields = Fields::of(nf);
    let n = nf.state.len();
    let mut rng = SplitMix(opts.seed ^ 0x0b5a_0b5a_0b5a_0b5a);
    let (p1, k1, free_roots) = rank_point(&mut nf.ctx, &mut rng, false)?;
    // Only the variables the outputs reach through the fields get columns:
    // every other column is zero in every row, exactly (reached_states), so
    // an unused parameter costs nothing (12,000 of them
    // made the dense (n + 1)-wide jets take gigabytes).
    let outputs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    // The symbolic route keeps every column: an independent check of this
    // restriction in the tests (tests/jets.rs).
    let reach = if symbolic {
        (0..n).collect()
    } else {
        reached_states(&nf.ctx, &nf.state_vars, &fields.vectors, &outputs)
    };
    let m = reach.len();
    let r_vars: Vec<Var> = reach.iter().map(|&i| nf.state_vars[i]).collect();
    let r_vectors: Vec<Vec<Id>> = fields
        .vectors
        .iter()
        .map(|v| reach.iter().map(|&i| v[i]).collect())
        .collect();
    if !symbolic {
        // Compiling the jets keeps a support set per component (m^2 per
        // field), and the first sweep m (m + 1) coefficients.
        let mu = m as u128;
        let k = (fields.vectors.len() + outputs.len()) as u128;
        let bytes = k * mu * mu + 8 * (mu + 1) * (3 * mu + 1);
        obsan_expr::limits::check_memory(bytes, "the jets of the rank test")
            .map_err(|l| AnalysisError::Invalid(l.to_string()))?;
    }
    let jets = (!symbolic).then(|| LieJets::new(&nf.ctx, &r_vars, &r_vectors, &outputs));
    let mut degrees = HashMap::new();
    let mut grow_at =
        |nf: &mut NormalForm, p: FpPoint, opts: &mut RankOptions, track: bool| match &jets {
            Some(jets) => {
                let mut rows = JetRows {
                    jets,
                    degrees: &mut degrees,
                    runs: HashMap::new(),
                    cap: m.saturating_sub(1).max(1),
                    track,
                };
                grow(
                    nf,
                    &mut rows,
                    vec![(); nf.outputs.len()],
                    &fields,
                    p,
                    opts,
                    m,
                )
            }
            None => {
                let roots = nf.outputs.iter().map(|o| o.1).collect();
                grow(
                    nf,
                    &mut SymbolicRows {
                        vars: &r_vars,
                        vectors: &r_vectors,
                    },
                    roots,
                    &fields,
                    p,
                    opts,
                    m,
                )
            }
        };
    // The first point without degree bounds: a full rank there is exact (a
    // non-zero minor proves it), and needs neither a bound nor a second
    // point. Otherwise the second point runs with bounds, and so does the
    // first again in the rare case it gave the higher rank. (At free roots
    // a full rank is only an upper bound: both points, as before.)
    let r1 = grow_at(nf, p1.clone(), &mut opts, free_roots)?;
    let full = r1.echelon.rank() == m && !free_roots;
    let (best, draws) = if full {
        (r1, 0.0)
    } else {
        let (p2, k2, _) = rank_point(&mut nf.ctx, &mut rng, free_roots)?;
        let r2 = grow_at(nf, p2, &mut opts, true)?;
        // Density correction of the sampling (see random_point_counted).
        let draws = k1.max(k2) as f64;
        if r1.echelon.rank() > r2.echelon.rank() {
            let r1 = if free_roots {
                r1
            } else {
                grow_at(nf, p1, &mut opts, true)?
            };
            (r1, draws)
        } else {
            (r2, draws)
        }
    };
    let rank = best.echelon.rank();
    // Single variables: e_i in the span at the point (never for a variable
    // the outputs do not reach: its column is zero).
    let mut observable = vec![false; n];
    for (j, &i) in reach.iter().enumerate() {
        observable[i] = best.echelon.contains_unit(j, m);
    }
    let mut pivots: Vec<usize> = best.echelon.pivots().map(|p| reach[p]).collect();
    pivots.sort_unstable();
    // 0 at a full rank: exact, no bound involved.
    let degree_bound = if full {
        0
    } else {
        best.degree.saturating_add(best.worst_rejected).max(1)
    };
    let per_point = (degree_bound as f64 * draws / P as f64).min(1.0);
    let max_order = best.basis.iter().map(|w| w.order()).max().unwrap_or(0);
    let mut report = RankReport {
        n,
        rank,
        max_order,
        evaluated: best.evaluated,
        basis: best.basis,
        observable,
        pivots,
        degree_bound,
        error_bound: per_point * per_point,
        fields,
        seed: opts.seed,
        free_roots,
        roots_field: None,
    };
    if free_roots {
        let basis = report.basis.clone();
        let funcs = report.words_on_graph(nf, &basis);
        if let Some(c) = crate::rank_roots::certify_in_extension(nf, &funcs, rank, opts.seed) {
            report.observable = c.observable;
            report.pivots = c.pivots;
            report.free_roots = false;
            report.roots_field = Some(c.degree);
        }
    }
    Ok(report)
}

/// A point for the rank test: on the roots' relations when one exists, else
/// (and at once with `free`) with free root values (`RankReport::free_roots`).
pub(crate) fn rank_point(
    ctx: &mut Ctx,
    rng: &mut SplitMix,
    free: bool,
) -> Result<(FpPoint, u64, bool), AnalysisError> {
    if !free {
        if !has_roots(ctx) {
            return random_point_counted(ctx, rng).map(|(p, k)| (p, k, false));
        }
        for k in 1..=exact_draws(ctx) {
            if let Ok(p) = ctx.random_fp_point(rng, &|_| None) {
                return Ok((p, k, false));
            }
        }
    }
    for k in 1..=(1u64 << 22) {
        if let Ok(p) = ctx.random_fp_point_free_roots(rng, &|_| None) {
            return Ok((p, k, true));
        }
    }
    Err(AnalysisError::NoPoint)
}

/// Draws before the roots are taken free: a radicand is a q-th power mod p
/// for a fraction `1/g`, `g = gcd(q, p - 1)`, of the values, so where points on
/// all the relations exist they have density at least `1/prod g` (the index
/// of the subgroup the conditions cut out); 64 times that many failures happen
/// by chance with probability below e^-64. At most 2^22, as for square roots.
fn exact_draws(ctx: &Ctx) -> u64 {
    let gcd = |mut a: u64, mut b: u64| {
        while b != 0 {
            (a, b) = (b, a % b);
        }
        a
    };
    let inverse_density = (0..ctx.leaf_count())
        .filter_map(|v| ctx.root_arg(v as Var))
        .fold(1u64, |d, (_, q)| d.saturating_mul(gcd(q as u64, P - 1)));
    inverse_density.saturating_mul(64).min(1 << 22)
}

fn has_roots(ctx: &Ctx) -> bool {
    (0..ctx.leaf_count()).any(|v| ctx.root_arg(v as Var).is_some())
}
