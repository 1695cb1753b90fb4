//! `obsan rank` and `obsan symmetries` on a model with unknown inputs: their own objects
//! (docs/engine.md, "Unknown inputs").

use super::Formula;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `obsan rank SYSTEM --json` when the model has unknown inputs.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct RankUnknownInputs {
    /// Whether the two routes (extended state, Martinelli's algorithm) give the same verdicts.
    pub agree: bool,
    /// Output derivatives whose gradients form a basis at the highest order reached.
    pub basis: Vec<UnknownInputWord>,
    /// Every state is observable or every unknown input decided.
    pub complete: bool,
    /// The extended-state growth converged.
    pub converged: bool,
    /// False when atoms may be related (then the rank is an upper bound).
    pub decided: bool,
    /// The Schwartz-Zippel degree bound of the rank test.
    pub degree_bound: u64,
    /// Probability bound that some verdict is wrong.
    pub error_bound: f64,
    /// How many derivatives were evaluated.
    pub evaluated: usize,
    /// Martinelli's algorithm: the proven verdicts and its stopping point.
    pub martinelli: Martinelli,
    /// The highest output derivative order examined.
    pub max_order: usize,
    /// The number of analysed variables.
    pub n: usize,
    /// The observable variables, each with the lowest order that shows it (not certified
    /// when `undecided_atoms` is not empty).
    pub observable_variables: Vec<NamedOrder>,
    /// The dimension of the observable codistribution in the state.
    pub rank: usize,
    /// The reconstructable unknown inputs, each with its lowest order.
    pub reconstructable_inputs: Vec<NamedOrder>,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// When no point mod p satisfies the roots' relations: the degree k of the field of p^k
    /// elements where every decision taken at free root values was proven; else null.
    pub roots_field_degree: Option<u32>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// The analysed variables.
    pub state: Vec<String>,
    /// The growth, order by order.
    pub steps: Vec<UnknownInputStep>,
    /// The system's name.
    pub system: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// The unknown inputs.
    pub unknown_inputs: Vec<String>,
    /// The variables not observable up to `max_order` (not certified when `undecided_atoms`
    /// is not empty).
    pub unobservable_variables: Vec<String>,
    /// The unknown inputs not reconstructable up to `max_order`.
    pub unreconstructable_inputs: Vec<String>,
    /// rank = n; null when full rank rests on undecided atoms.
    pub weakly_locally_observable: Option<bool>,
}

/// A variable or input with the lowest output derivative order from which it is seen.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct NamedOrder {
    /// Its name.
    pub name: String,
    /// The order.
    pub order: usize,
}

/// A basis derivative of an output.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct UnknownInputWord {
    /// The Lie word along the extended fields.
    pub derivative: String,
    /// Its order.
    pub order: usize,
    /// The output differentiated.
    pub output: String,
}

/// One derivative order of the extended-state growth.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct UnknownInputStep {
    /// The rank in the extended space (state and unknown-input jets).
    pub extended_rank: usize,
    /// The order.
    pub order: usize,
    /// The rank of its part in the state.
    pub state_rank: usize,
}

/// Martinelli's algorithm's report.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Martinelli {
    /// The rank of the final codistribution in the extended space.
    pub codistribution_rank: usize,
    /// The dimension of the final extended space.
    pub dimension: usize,
    /// Probability bound that some decision is wrong.
    pub error_bound: f64,
    /// Jets of the known inputs carried.
    pub input_jets: usize,
    /// The unknown inputs proven not reconstructable.
    pub not_reconstructable: Vec<String>,
    /// The observable variables.
    pub observable: Vec<String>,
    /// The rank of the observable codistribution's part in the state.
    pub rank: usize,
    /// The unknown inputs proven reconstructable.
    pub reconstructable: Vec<String>,
    /// Rounds of the last growth (its last added nothing): the proven stopping point.
    pub rounds: usize,
    /// Its iterations.
    pub steps: Vec<MartinelliStep>,
}

/// One iteration of Martinelli's algorithm.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct MartinelliStep {
    /// What ended it.
    pub action: String,
    /// The degree of reconstructability at its start.
    pub degree: usize,
}

/// `obsan symmetries SYSTEM --json` when the model has unknown inputs.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct SymmetriesUnknownInputs {
    /// Always `unknown_input_invariance`.
    pub certificate: String,
    /// The rank test's error bound (for the observable variables).
    pub error_bound: f64,
    /// Always true: the vectors are certified exactly.
    pub exact: bool,
    /// How many identities were checked exactly.
    pub identities: usize,
    /// The symmetries depend on the known inputs' values: their components hold the jets in
    /// `input_jets` (docs/engine.md, "Symmetries with unknown inputs").
    pub input_dependent: bool,
    /// The known inputs' jets the components hold: `u` the input, `u'`, `u''` its derivatives.
    pub input_jets: Vec<String>,
    /// The unknown inputs an output holds (direct feedthrough), made states `w' = v` for the
    /// certificate; the symmetries are the state part of the extended system's (docs/engine.md).
    pub made_states: Vec<String>,
    /// The number of analysed variables.
    pub n: usize,
    /// The variables no symmetry moves.
    pub observable_variables: Vec<String>,
    /// The dimension of the observable codistribution.
    pub rank: usize,
    /// The reconstructable unknown inputs.
    pub reconstructable_inputs: Vec<String>,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// The analysed variables.
    pub state: Vec<String>,
    /// One object per vector: variable -> component.
    pub symmetries: Vec<BTreeMap<String, Formula>>,
    /// The system's name.
    pub system: String,
    /// The unknown inputs.
    pub unknown_inputs: Vec<String>,
    /// The variables moved by a symmetry (exact).
    pub unobservable_variables: Vec<String>,
}
