//! Options of the exact commands (show, simplify, diff, rank, symmetries, lie, check, modes,
//! verify, global, design) and of `obsan schema`.

use super::seconds;
use clap::Args;

#[derive(Args)]
pub struct SchemaArgs {
    /// The command (as `obsan schema --list` names it).
    #[arg(required_unless_present_any = ["list", "markdown"])]
    pub command: Option<String>,
    /// List the commands with a schema, and those without one yet.
    #[arg(long, conflicts_with_all = ["command", "markdown"])]
    pub list: bool,
    /// Print docs/json.md: every schema as tables.
    #[arg(long, conflicts_with = "command")]
    pub markdown: bool,
}

#[derive(Args)]
pub struct GlobalArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// `taylor` (SIAN's Taylor system), `io` (input-output relations:
    /// parameters only), `lie` (iterated Lie derivatives: indistinguishable
    /// for every input), or `auto`: taylor, then io when the Taylor system
    /// passes a budget, then lie (docs/engine.md, "Input-output route", "Lie
    /// route").
    #[arg(long, default_value = "auto", value_parser = ["auto", "taylor", "io", "lie"])]
    pub route: String,
    /// Count the params over enough independent experiments, each from its
    /// own generic initial state (SI.jl's multi-experiment identifiability):
    /// by the input-output relations' coefficients, also where one
    /// experiment does not fix them (a zero Wronskian, which `--route io`
    /// refuses). Params only; the answer says whether the counts are
    /// single-experiment ones too.
    #[arg(long, conflicts_with_all = ["experiment", "experiments"])]
    pub multi_experiment: bool,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

/// Options of the analysis commands.
#[derive(Args, Clone)]
pub struct AnalysisArgs {
    /// Seed of the random evaluation points (same seed, same answer).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
}

/// The time limit of the commands that do exact work but take no analysis options.
#[derive(Args, Clone)]
pub struct LimitArgs {
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
}

#[derive(Args)]
pub struct RankArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// With unknown inputs: the highest output derivative order examined
    /// (default: the state dimension + 1).
    #[arg(long, value_name = "M")]
    pub order: Option<usize>,
    /// A state whose initial value is known, e.g. `--known S=0`: the rank in
    /// the other unknowns with every Lie derivative evaluated at that value
    /// (docs/experiments.md). In several experiments `S` means every copy,
    /// `S@2` one.
    #[arg(long = "known", value_name = "NAME=VALUE", value_delimiter = ',')]
    pub known: Vec<String>,
    /// A state whose initial value is known but generic (comma-separated or repeated).
    #[arg(long = "known-generic", value_name = "NAME", value_delimiter = ',')]
    pub known_generic: Vec<String>,
    /// With --known: evaluate every Lie derivative up to this order at the point.
    #[arg(long = "known-order", value_name = "K", default_value_t = 12)]
    pub known_order: usize,
    /// Observability along a dataset (docs/experiments.md): window by window,
    /// the numerical rank at the recorded truth's states with the recorded
    /// inputs, and the degenerate stretches with the symmetries they match.
    #[arg(long = "along", value_name = "DATASET")]
    pub along: Option<String>,
    /// With --along: the window length in seconds.
    #[arg(
        long = "window",
        value_name = "SECONDS",
        default_value_t = 10.0,
        requires = "along"
    )]
    pub window: f64,
    /// With --along: the states and params to start each trajectory from, a
    /// JSON file shaped like truth.json (default: DATASET/truth.json).
    #[arg(long = "truth", value_name = "FILE", requires = "along")]
    pub truth: Option<String>,
}

#[derive(Args)]
pub struct SymArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Always take the exact route (canonical forms and the exact closure
    /// check), however long it takes, instead of reconstruction.
    #[arg(long)]
    pub exact: bool,
}

impl SymArgs {
    /// Symmetries stop after 60 s unless told otherwise.
    pub fn timeout(&self) -> f64 {
        self.an.timeout.unwrap_or(60.0)
    }
}

#[derive(Args)]
pub struct LieArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// Highest order (all words of every order up to it).
    #[arg(long)]
    pub order: usize,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct CheckArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// A candidate observable mode (repeat the flag for several).
    #[arg(
        long = "mode",
        value_name = "EXPR",
        required = true,
        allow_hyphen_values = true
    )]
    pub modes: Vec<String>,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Compute the symmetries by the exact route (canonical forms and the
    /// exact closure check), however long it takes, instead of the default.
    #[arg(long)]
    pub exact: bool,
}

#[derive(Args)]
pub struct ModesArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    /// Seed of the random evaluation points (same seed, same answer).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Write PREFIX.sys (the reduced system) and PREFIX.dec (its decomposition file).
    #[arg(long = "out", value_name = "PREFIX")]
    pub out_prefix: Option<String>,
    /// Largest polynomial (terms) the engine may build before it stops with
    /// "expression too large" (docs/engine.md, Limits).
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Replace existing PREFIX.sys / PREFIX.dec.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct VerifyArgs {
    /// A decomposition file (docs/decomposition-format.md).
    pub file: String,
    #[command(flatten)]
    pub an: AnalysisArgs,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Compute the symmetries by the exact route (canonical forms and the
    /// exact closure check), however long it takes, instead of the default.
    #[arg(long)]
    pub exact: bool,
}

/// Options shared by every command that reads a system.
#[derive(Args, Clone)]
pub struct SystemArgs {
    /// A system description in the .sys format.
    pub system: String,
    /// Apply the named input restriction declared in the file (e.g. `q`).
    #[arg(long = "input", value_name = "NAME")]
    pub restriction: Option<String>,
    /// Give a known constant a value, e.g. `--set q=0.9` (others stay generic).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// One of several experiments (repeat): `RESTRICTION: c=VALUE, ...`, e.g.
    /// `--experiment 'q: q=0.9'`; an empty restriction is none. Each has its own
    /// states (`x@1`, `x@2` ...); params are shared (docs/experiments.md).
    #[arg(
        long = "experiment",
        value_name = "SPEC",
        conflicts_with = "restriction"
    )]
    pub experiment: Vec<String>,
    /// Experiments from a file, one SPEC a line (`#` comments); or `auto`
    /// (obsan rank): the smallest number of generic experiments that identifies
    /// all it can, under --input's restriction or none.
    #[arg(long = "experiments", value_name = "FILE|auto")]
    pub experiments: Option<String>,
}

#[derive(Args)]
pub struct OutputArgs {
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Formulas as LaTeX.
    #[arg(long, conflicts_with = "json")]
    pub latex: bool,
}

#[derive(Args)]
pub struct ShowArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct ExprArgs {
    /// An expression, e.g. 'sin(x)^2 + cos(x)^2' (a leading '-' is part of it).
    #[arg(allow_hyphen_values = true)]
    pub expr: String,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct DiffArgs {
    /// An expression (a leading '-' is part of it).
    #[arg(allow_hyphen_values = true)]
    pub expr: String,
    /// The symbol to differentiate by.
    pub var: String,
    #[command(flatten)]
    pub limit: LimitArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct DesignArgs {
    /// A system description in the .sys format.
    pub system: String,
    /// Candidate sensors: `candidate NAME [cost C]` lines, each followed by
    /// `output` statements (docs/experiments.md).
    #[arg(long, value_name = "FILE")]
    pub candidates: Option<String>,
    /// The variables the added sensors must make observable (default: all).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub target: Vec<String>,
    /// Compare the input families (restrictions) too when --candidates is given.
    #[arg(long)]
    pub families: bool,
    /// Sensors under this input restriction of the model.
    #[arg(long = "input", value_name = "NAME")]
    pub restriction: Option<String>,
    /// Give a known constant a value, e.g. `--set q=0.9`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    /// Screen at most this many subsets of candidates.
    #[arg(long, value_name = "N", default_value_t = 1 << 20)]
    pub max_subsets: usize,
    /// Seed of the random evaluation points.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Give up after this many seconds (exit code 2).
    #[arg(long, value_name = "SECONDS", value_parser = seconds)]
    pub timeout: Option<f64>,
    /// Largest polynomial (terms) the engine may build.
    #[arg(long, value_name = "N", default_value_t = obsan_expr::Budget::DEFAULT_MAX_TERMS)]
    pub max_terms: usize,
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
}
