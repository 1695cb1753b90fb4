//! `obsan modes`: the observable modes and the reduced system (eqs. 9-11). A full-rank model
//! prints the short object (every variable a mode), any other the derivation.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `obsan modes SYSTEM --json`: one of two objects.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(untagged)]
pub enum Modes {
    /// Full rank: the modes are the variables.
    FullRank(ModesFullRank),
    /// Below full rank: the derived modes, the reduced system and its proof.
    Derived(Box<ModesDerived>),
}

/// `obsan modes` on a model with unknown inputs (docs/engine.md, "Modes with unknown
/// inputs"): its own object, as for `rank` and `symmetries`.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModesUnknownInputs {
    /// What is proven, and how, in words.
    pub certificate: String,
    /// The derived decomposition's checks (as `obsan verify`); null at full rank.
    pub checks: Option<Vec<PassCheck>>,
    /// The decomposition file, or null at full rank or when not closed.
    pub dec: Option<String>,
    /// False when atoms may be related (then the rank is an upper bound).
    pub decided: bool,
    /// Probability bound of the unknown-input rank test (the modes' count rests on it).
    pub error_bound: f64,
    /// Every variable observable: the modes are the variables, the reduced system the model.
    pub full_rank: bool,
    /// The modes (at full rank, the variables).
    pub modes: Vec<DerivedMode>,
    /// The number of analysed variables.
    pub n: usize,
    /// The rank with unknown inputs.
    pub rank: usize,
    /// The reduced system in the modes; null at full rank.
    pub reduced: Option<Reduced>,
    /// The unknown inputs, or their combinations, the reduced system is driven by.
    pub reduced_inputs: Vec<ReducedUnknownInput>,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The seed of the random points.
    pub seed: u64,
    /// The number of certified symmetries.
    pub symmetries: usize,
    /// The reduced system as .sys text (unknown inputs as inputs), or null.
    pub sys: Option<String>,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// The model's unknown inputs.
    pub unknown_inputs: Vec<String>,
    /// Every decomposition check passed (true at full rank).
    pub verified: bool,
}

/// An unknown input, or a combination `factor * input`, of the reduced system.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReducedUnknownInput {
    /// Null: the input itself; else the state function it is multiplied by.
    pub factor: Option<String>,
    /// The model's unknown input.
    pub input: String,
    /// The first mode whose derivative needs it; for a combination an output reads directly
    /// (no mode sees the input; `order` 0), that output.
    pub mode: String,
    /// Its name in the reduced system.
    pub name: String,
    /// Null, or the terms added to `factor * input`: the drift and known-input terms that are
    /// not functions of the modes and, for inputs projected jointly, the other unknown inputs'
    /// terms (the combination is then that mode's time derivative).
    pub offset: Option<String>,
    /// The output-derivative order it is reconstructable from (the rank test's; 0 for a
    /// combination an output reads directly); null for a combination recovered from the modes'
    /// first derivatives.
    pub order: Option<usize>,
}

/// `obsan modes` on a model of full rank.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModesFullRank {
    /// What proves the answer, in words.
    pub certificate: String,
    /// False when atoms may be related (then the full rank is an upper bound).
    pub decided: bool,
    /// True; null when not decided.
    pub full_rank: Option<bool>,
    /// The variables, each a mode.
    pub modes: Vec<VariableMode>,
    /// The number of analysed variables.
    pub n: usize,
    /// The generic rank.
    pub rank: usize,
    /// Always null: no reduction.
    pub reduced: Option<()>,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
}

/// A variable as its own mode.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct VariableMode {
    /// The variable.
    pub expr: String,
    /// Always `variable`.
    pub kind: String,
    /// The variable's name.
    pub name: String,
}

/// `obsan modes` below full rank.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModesDerived {
    /// What is proven, and how.
    pub certificate: ModesCertificate,
    /// The decomposition file (`obsan verify` reads it), or null when not closed.
    pub dec: Option<String>,
    /// False when atoms may be related (see `certificate`).
    pub decided: bool,
    /// Always false.
    pub full_rank: bool,
    /// The derived modes.
    pub modes: Vec<DerivedMode>,
    /// The number of analysed variables.
    pub n: usize,
    /// The generic rank (an upper bound when not decided).
    pub rank: usize,
    /// The reduced system in the modes.
    pub reduced: Reduced,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The number of symmetries (free directions included).
    pub symmetries: usize,
    /// The reduced system as .sys text, or null when not closed.
    pub sys: Option<String>,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// The variables no output reaches: unobservable, in no mode.
    pub unreached: Vec<String>,
}

/// One observable mode.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct DerivedMode {
    /// It is an angle (its values taken modulo 2 pi).
    pub angle: bool,
    /// Where it is defined, in words.
    pub domain: String,
    /// The mode's formula in the original variables.
    pub expr: String,
    /// How it was found: variable, angle difference, polynomial, rational, output, Lie
    /// derivative or cross-section.
    pub kind: String,
    /// Its name in the reduced system.
    pub name: String,
}

/// The reduced system in the modes.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Reduced {
    /// Every output and every mode's dynamics is written in the modes.
    pub closed: bool,
    /// Each mode's dynamics.
    pub dynamics: Vec<ReducedDynamics>,
    /// The known inputs; with unknown inputs whose symmetries move with the known inputs,
    /// then the known inputs' time derivatives the reduced system reads (`u3'`, `u3''`).
    pub inputs: Vec<String>,
    /// What could not be written in the modes.
    pub missing: Vec<String>,
    /// Each output in the modes.
    pub outputs: Vec<ReducedOutput>,
}

/// A mode's dynamics.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReducedDynamics {
    /// The mode.
    pub name: String,
    /// Its time derivative in the modes and inputs, or null when not found.
    pub rhs: Option<String>,
}

/// An output in the modes.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ReducedOutput {
    /// The output in the modes, or null when not found.
    pub expr: Option<String>,
    /// The output.
    pub name: String,
}

/// What `obsan modes` proved.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModesCertificate {
    /// The derived decomposition's checks (as `obsan verify`), or null when not closed.
    pub checks: Option<Vec<PassCheck>>,
    /// As many independent modes as the rank; null when not decided.
    pub complete: Option<bool>,
    /// The whole answer is proven.
    pub exact: bool,
    /// The modes' gradients are independent; null when not decided (false is certain).
    pub independent: Option<bool>,
    /// `closure` (the reduced system proves it) or `symmetries` (eq. 11 against them).
    pub method: String,
    /// Every mode satisfies eq. (11), independent and complete; null when not decided.
    pub modes_exact: Option<bool>,
    /// What certified the symmetries, in words.
    pub symmetries: String,
    /// The whole certificate, in words.
    pub text: String,
    /// The decomposition checks passed; null when not decided (false is certain).
    pub verified: Option<bool>,
}

/// A check that passed or not.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct PassCheck {
    /// Its name.
    pub check: String,
    /// What was found.
    pub detail: String,
    /// It passed.
    pub pass: bool,
}
