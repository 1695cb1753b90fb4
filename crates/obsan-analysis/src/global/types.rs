//! The types of `obsan global`'s answer and options, and the error helpers
//! every step shares (the bottom of the module graph).

use crate::rank::AnalysisError;
use obsan_groebner::{GbBudget, GbError};
use std::time::Instant;

/// Options of [`global_identifiability`](super::global_identifiability).
#[derive(Clone, Debug)]
pub struct GlobalOptions {
    /// Seed of the random points (two independent runs use `seed` and `seed + 1`).
    pub seed: u64,
    pub deadline: Option<Instant>,
    /// Largest Taylor order tried.
    pub max_order: usize,
    /// Largest Gröbner basis (elements added) before giving up.
    pub max_basis: usize,
    /// Largest quotient dimension counted.
    pub max_solutions: usize,
    /// Bytes the Taylor system, the Gröbner basis and the counts may hold
    /// (the engine's memory budget: `--max-terms` times
    /// `obsan_expr::Budget::BYTES_PER_TERM`).
    pub max_bytes: usize,
    /// Multiply-adds the Gröbner stage's F4 eliminations may take
    /// (`obsan_groebner::GbBudget::max_work`): `u64::MAX`, no bound, except
    /// in `--route auto`'s first attempt.
    pub max_work: u64,
    /// Multiply-adds the input-output route's dense kernels may take, per
    /// model and prime (io.rs, `IoModel::max_work`): `u64::MAX`, no bound,
    /// except in `--route auto`'s cheap input-output attempt (io_choice.rs).
    pub max_io_work: u64,
    /// SIAN's weighted order (weights.rs): on by default; it changes the
    /// time of the Gröbner basis, never a count (the tests compare both).
    pub weighted: bool,
    /// Which route counts (docs/engine.md, "Input-output route").
    pub route: Route,
    /// Count the parameters over enough independent experiments (each from
    /// its own generic initial state; SI.jl's multi-experiment
    /// identifiability): the input-output relations' coefficients, also
    /// where a relation's Wronskian is zero (io_count.rs). The io route only.
    pub multi_experiment: bool,
}

impl GlobalOptions {
    /// The Gröbner stage's budget from these options.
    pub(super) fn gb_budget(&self) -> GbBudget {
        GbBudget {
            max_basis: self.max_basis,
            max_bytes: self.max_bytes,
            max_work: self.max_work,
            deadline: self.deadline,
            ..GbBudget::default()
        }
    }
}

/// The route of `obsan global`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Route {
    /// SIAN's Taylor system; the input-output relations (parameters only)
    /// when it passes a budget.
    #[default]
    Auto,
    /// SIAN's Taylor system only.
    Taylor,
    /// The input-output relations only: parameters, no initial states.
    InputOutput,
    /// Iterated Lie derivatives along the drift and each input's field
    /// (lie.rs): indistinguishability for every input (Hermann–Krener).
    Lie,
}

impl Default for GlobalOptions {
    fn default() -> Self {
        GlobalOptions {
            seed: 0x5eed_61b0,
            deadline: None,
            max_order: 24,
            max_basis: 20_000,
            max_solutions: 100_000,
            max_bytes: memory_budget(obsan_expr::Budget::DEFAULT_MAX_TERMS),
            max_work: u64::MAX,
            max_io_work: u64::MAX,
            weighted: true,
            route: Route::Auto,
            multi_experiment: false,
        }
    }
}

/// The verdict on one variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Identifiability {
    /// One value: globally identifiable.
    Global,
    /// Finitely many values (`k > 1`) over the complex numbers.
    Local(usize),
    /// Infinitely many values.
    NotIdentifiable,
}

#[derive(Clone, Debug)]
pub struct GlobalVariable {
    pub name: String,
    /// A parameter (else the initial value of a state).
    pub param: bool,
    /// An angle entering only through sin/cos: its values are counted modulo
    /// 2 pi (as its half-angle tangent `tan(theta/2)`).
    pub angle: bool,
    pub verdict: Identifiability,
    /// The count `k > 1` is an upper bound: an output was read through its
    /// angle's tangent (outputs.rs), which fixes the angle modulo pi only.
    pub at_most: bool,
}

/// A discrete symmetry: each moved variable and its image. Checked exactly:
/// the dynamics and outputs are invariant as rational functions over Q (in
/// the half-angle view for angles).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DiscreteMap {
    pub images: Vec<MapImage>,
    /// With outputs read through an angle's tangent: whether the map keeps
    /// every such angle itself (`Some(true)`), turns one by pi
    /// (`Some(false)`: a symmetry of the tangents only), or neither is
    /// proven (`None`). `Some(true)` without such outputs.
    pub keeps_angles: Option<bool>,
    /// A map of the parameters alone (the input-output route): it keeps
    /// every relation's coefficients, checked exactly over Q, so the
    /// parameters and their images give the same outputs (the initial
    /// states' images are not sought).
    pub params_only: bool,
}

/// `var -> sign * image`, plus pi when `plus_pi` (angles only: `theta ->
/// phi + pi` or `pi - phi`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MapImage {
    pub var: String,
    pub sign: i8,
    pub image: String,
    pub plus_pi: bool,
}

impl std::fmt::Display for MapImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (self.sign < 0, self.plus_pi) {
            (false, false) => write!(f, "{}", self.image),
            (true, false) => write!(f, "-{}", self.image),
            (false, true) => write!(f, "{} + pi", self.image),
            (true, true) => write!(f, "pi - {}", self.image),
        }
    }
}

impl std::fmt::Display for DiscreteMap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let lhs: Vec<&str> = self.images.iter().map(|m| m.var.as_str()).collect();
        let rhs: Vec<String> = self.images.iter().map(|m| m.to_string()).collect();
        if lhs.len() == 1 {
            write!(f, "{} -> {}", lhs[0], rhs[0])
        } else {
            write!(f, "({}) -> ({})", lhs.join(", "), rhs.join(", "))
        }
    }
}

/// The answer of [`global_identifiability`](super::global_identifiability).
#[derive(Clone, Debug)]
pub struct GlobalReport {
    /// Parameters, then initial states, in the system's order.
    pub variables: Vec<GlobalVariable>,
    /// How many (params, initial states) give the output of the generic one
    /// (counting only the locally identifiable variables when some are not:
    /// `None` then means that even those take infinitely many joint values).
    pub solutions: Option<usize>,
    /// Whether every variable is at least locally identifiable.
    pub all_local: bool,
    /// Exact discrete symmetries found: signed permutations of the variables,
    /// angles also shifted by pi or reflected (`theta -> phi + pi`, `pi - phi`).
    pub maps: Vec<DiscreteMap>,
    /// Size of the group the maps generate (an orbit of a generic point).
    pub group_order: usize,
    /// `solutions` is an upper bound (an output read through its tangent,
    /// and the maps do not settle the count; outputs.rs).
    pub solutions_at_most: bool,
    /// Per output, how the count reads it.
    pub output_forms: Vec<(String, super::outputs::OutputForm)>,
    /// Highest Taylor order used, and the highest order of a row that
    /// raised the Jacobian's rank.
    pub order: usize,
    pub rank_order: usize,
    /// Per output, the Taylor order used (inclusive): the proven truncation
    /// of docs/engine.md, "Taylor orders".
    pub output_orders: Vec<(String, usize)>,
    /// SIAN's degree bounds for one run (Hong, Ovchinnikov, Pogudin, Yap
    /// 2020, Algorithm 1): `delta_local` for the orders and local verdicts,
    /// `log10_delta_global` (log10 of the Bezout bound, which can pass any
    /// float) for the global verdicts.
    pub delta_local: f64,
    pub log10_delta_global: f64,
    /// Probability that a verdict (global / local / not identifiable) is
    /// wrong: both independent runs would have to be wrong,
    /// `min(1, D/p1) * min(1, D/p2)` with `D = delta_local + delta_global`.
    /// 1 means no bound.
    pub error_bound: f64,
    /// Unknowns and equations of the polynomial system at `order`.
    pub unknowns: usize,
    pub equations: usize,
    /// The primes of the two independent runs.
    pub primes: [u64; 2],
    /// The route that answered ([`Route::Taylor`] or
    /// [`Route::InputOutput`]: then `variables` holds the parameters only),
    /// and why the Taylor route did not when it fell back.
    pub route: Route,
    pub fallback: Option<String>,
    /// The input-output relations' sizes (that route only).
    pub io_sizes: Vec<super::io_count::IoSize>,
    /// The counts are of multi-experiment identifiability only: asked for
    /// (`GlobalOptions::multi_experiment`) and some relation's monomials are
    /// dependent along an output (a zero Wronskian), so one experiment may
    /// leave more values. False when every relation's Wronskian is non-zero
    /// (the counts are then single-experiment ones too).
    pub multi_experiment: bool,
    /// `--route auto` when the input-output route answered: the initial
    /// states counted after it (mod.rs, `states_after_io`). None on the
    /// other routes and under `--route io`.
    pub states_after_io: Option<StatesAfterIo>,
}

/// The initial states after the input-output route (`--route auto`): the
/// Taylor route on the model whose params the relations found globally
/// identifiable are known constants at random values. Every generic fibre
/// holds one value of each, so fixing them removes no solution, and the
/// system is far smaller (SI.jl's Goodwin: 28 unknowns instead of 43, with
/// b, c, sigma known).
#[derive(Clone, Debug)]
pub struct StatesAfterIo {
    /// The params fixed (the relations' global ones), in the model's order.
    pub fixed: Vec<String>,
    /// The states were counted (`variables` lists them); else `why_not`.
    pub counted: bool,
    /// That Taylor system's order per output, its unknowns and equations.
    pub output_orders: Vec<(String, usize)>,
    pub unknowns: usize,
    pub equations: usize,
    /// SIAN's bound on that Taylor count (docs/engine.md), given the
    /// params' verdicts, which carry none: 1 means no bound.
    pub error_bound: f64,
    /// Why the states were not counted (the Taylor attempt's error).
    pub why_not: Option<String>,
}

/// The memory budget of a term budget, as every engine stage counts it.
fn memory_budget(max_terms: usize) -> usize {
    let b = (max_terms as u128).saturating_mul(obsan_expr::Budget::BYTES_PER_TERM);
    usize::try_from(b).unwrap_or(usize::MAX)
}

/// A stage that would pass the memory budget, in the words of the engine's
/// other stages (`obsan_expr::Limit::Memory`).
pub(super) fn too_large(bytes: u128, max: u128, what: &str) -> AnalysisError {
    err(format!(
        "too large: {what} would need {} MiB, the memory budget is {} MiB ({} bytes per --max-terms); raise it with --max-terms",
        bytes.div_ceil(1 << 20),
        max >> 20,
        obsan_expr::Budget::BYTES_PER_TERM
    ))
}

pub(super) fn err(s: impl Into<String>) -> AnalysisError {
    AnalysisError::Invalid(s.into())
}

pub(super) fn gb_err(e: GbError) -> AnalysisError {
    match e {
        GbError::Budget("deadline") => {
            AnalysisError::Timeout("the Gröbner basis did not finish".into())
        }
        GbError::Memory { bytes, max, what } => too_large(bytes, max, &what),
        e => err(format!("global: {e}")),
    }
}
