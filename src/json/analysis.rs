//! `obsan show`, `obsan rank` (plain), `obsan symmetries`, `obsan check`, `obsan verify`.

use super::{BasisWord, Experiment};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A formula in exact canonical form.
#[derive(Serialize, Deserialize, JsonSchema, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Formula {
    /// As LaTeX.
    pub latex: String,
    /// As text (parses back to the same form).
    pub text: String,
}

/// A known constant of the model.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Constant {
    /// Its name.
    pub name: String,
    /// Its value as an exact rational (`--set`), or null when generic.
    pub value: Option<String>,
}

/// `obsan show SYSTEM --json`: the system in input-affine normal form.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Show {
    /// The known constants, with their values.
    pub consts: Vec<Constant>,
    /// The model's description (its comment lines), possibly empty.
    pub description: String,
    /// Always true: every formula is an exact canonical form.
    pub exact: bool,
    /// The drift f0: state -> its component.
    pub f0: BTreeMap<String, Formula>,
    /// The input fields f_i: input -> (state -> component).
    pub fields: BTreeMap<String, BTreeMap<String, Formula>>,
    /// The file as given on the command line.
    pub file: String,
    /// The known inputs, one field each.
    pub inputs: Vec<String>,
    /// The outputs: name -> formula.
    pub outputs: BTreeMap<String, Formula>,
    /// The unknown parameters (states with zero dynamics in the analysis).
    pub params: Vec<String>,
    /// The input restriction applied (`--input`), or null.
    pub restriction: Option<String>,
    /// The states (without the clock of explicit time).
    pub states: Vec<String>,
    /// The system's name.
    pub system: String,
}

/// `obsan rank SYSTEM --json`: the generic observability rank (Hermann-Krener).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Rank {
    /// The Lie words of a basis of the codistribution.
    pub basis: Vec<BasisWord>,
    /// False when the atoms listed in `undecided_atoms` may be related: then the rank is an
    /// upper bound, full rank is not proven, and the per-variable lists (those of the system
    /// with the atoms independent) are certified neither way.
    pub decided: bool,
    /// The Schwartz-Zippel degree bound of the rank test; 0 when the rank equals the number of variables the outputs reach (exact: a non-zero minor proves it, and no second point is drawn).
    pub degree_bound: u64,
    /// 0 when exact, else the probability bound that the rank is too low.
    pub error_bound: f64,
    /// How many Lie derivatives were evaluated.
    pub evaluated: usize,
    /// Full rank proven (a nonzero minor over decided atoms).
    pub exact: bool,
    /// The stacked experiments (`--experiment`, `--experiments FILE`), or null.
    pub experiments: Option<Vec<Experiment>>,
    /// The highest order of Lie derivative examined.
    pub max_order: usize,
    /// The known inputs that outputs read: each analysed as a measured coordinate with its
    /// derivative a known input, and left out of `n`, `rank`, `state` and the lists.
    pub measured_inputs: Vec<String>,
    /// The number of analysed variables.
    pub n: usize,
    /// The variables observable on their own (not certified when `decided` is false).
    pub observable_variables: Vec<String>,
    /// The generic rank.
    pub rank: usize,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// `k` when no point mod p satisfied the roots' relations and the rank was certified at
    /// a point of the field of p^k elements where every root has its value; else null.
    pub roots_field_degree: Option<u32>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// The analysed variables (states and params; not the clock of explicit time).
    pub state: Vec<String>,
    /// The system's name.
    pub system: String,
    /// The atoms (e.g. `log(x*y)`, `log(x)`) that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// The variables not observable on their own (not certified when `decided` is false).
    pub unobservable_variables: Vec<String>,
    /// rank = n; null when full rank rests on undecided atoms.
    pub weakly_locally_observable: Option<bool>,
}

/// What certified the symmetries.
#[derive(Serialize, Deserialize, JsonSchema, Debug, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum SymCertificate {
    /// The exact closure check (exact Gauss-Jordan).
    Closure,
    /// Cheap structure, proven by invariance.
    Invariance,
    /// Reconstruction modulo a prime, proven exactly: outputs invariant, brackets with the fields in the span.
    Span,
    /// Reconstruction modulo primes, certified at random points (`certification`).
    Random,
}

/// The figures of a random certificate.
#[derive(Serialize, Deserialize, JsonSchema, Debug, Clone)]
#[serde(deny_unknown_fields)]
pub struct Certification {
    /// The degree bound of the certified identities.
    pub degree: u64,
    /// The probability bound that a certified vector is wrong.
    pub error_bound: f64,
    /// How many identities were checked.
    pub identities: usize,
    /// How many random points.
    pub points: u32,
    /// Over how many primes.
    pub primes: u32,
}

/// `obsan symmetries SYSTEM --json`: a certified basis of the continuous symmetries.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Symmetries {
    /// How many independent blocks the system was solved in.
    pub blocks: usize,
    /// What certified the vectors.
    pub certificate: SymCertificate,
    /// For `random`: its figures; else null.
    pub certification: Option<Certification>,
    /// False when atoms may be related: each vector still annihilates the codistribution,
    /// but the count and the independence rest on the rank over them.
    pub decided: bool,
    /// The whole answer (vectors, count, independence) is proven.
    pub exact: bool,
    /// The variables no output reaches: each d/dx is a symmetry too, listed by name.
    pub free_directions: Vec<String>,
    /// The number of analysed variables.
    pub n: usize,
    /// The generic rank.
    pub rank: usize,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// How many rows of the codistribution the vectors were checked against.
    pub rows_checked: usize,
    /// The analysed variables.
    pub state: Vec<String>,
    /// One object per vector: variable -> component.
    pub symmetries: Vec<BTreeMap<String, Formula>>,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
}

/// One candidate mode of `obsan check`.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModeCheck {
    /// Its residuals are zero over decided atoms.
    pub decided: bool,
    /// The mode as given.
    pub mode: String,
    /// It satisfies eq. (11) for every symmetry; null when not decided.
    pub observable_mode: Option<bool>,
    /// Its eq. (11) residual against each symmetry (exact canonical text).
    pub residuals: Vec<String>,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
}

/// `obsan check SYSTEM --mode EXPR --json`: candidate modes against eq. (11).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Check {
    /// What certified the symmetries.
    pub certificate: SymCertificate,
    /// For `random`: its figures; else null.
    pub certification: Option<Certification>,
    /// One per mode, in the order given.
    pub checks: Vec<ModeCheck>,
    /// As many independent modes as the rank; null when not decided.
    pub complete: Option<bool>,
    /// Every part of the answer is proven.
    pub exact: bool,
    /// The modes' gradients are independent; null when not decided (false is certain).
    pub independent: Option<bool>,
    /// The number of independent modes.
    pub independent_count: usize,
    /// The generic rank.
    pub rank: usize,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The number of symmetries.
    pub symmetries: usize,
    /// The system's name.
    pub system: String,
}

/// One check of a decomposition.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct DecompositionCheck {
    /// Its name.
    pub check: String,
    /// Decided over independent atoms.
    pub decided: bool,
    /// What was found.
    pub detail: String,
    /// It passed.
    pub pass: bool,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
}

/// `obsan verify FILE.dec --json`: a claimed local decomposition, checked exactly.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Verify {
    /// What certified the symmetries.
    pub certificate: SymCertificate,
    /// For `random`: its figures; else null.
    pub certification: Option<Certification>,
    /// Each check, in order.
    pub checks: Vec<DecompositionCheck>,
    /// The verdict rests on decided atoms (a pass on every atom decided; a failure certain).
    pub decided: bool,
    /// The decomposition file as given.
    pub decomposition: String,
    /// It passed and the verdict is proven.
    pub exact: bool,
    /// Every check passed.
    pub pass: bool,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The number of symmetries.
    pub symmetries: usize,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// What the verdict rests on, in words.
    pub verdict: String,
}
