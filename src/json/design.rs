//! `obsan design` and `obsan rank`'s own objects for `--known`/`--known-generic` and
//! `--experiments auto` (docs/experiments.md).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `obsan design SYSTEM --json`: which sensors, which input families.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Design {
    /// The input families compared (without --candidates, or with --families); else null.
    pub inputs: Option<Inputs>,
    /// The input restriction the sensors are designed under (`--input`), or null.
    pub restriction: Option<String>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// The candidate sensors' design (with --candidates); else null.
    pub sensors: Option<Sensors>,
    /// The system's name.
    pub system: String,
}

/// The minimal sets of candidate sensors that reach the goal.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Sensors {
    /// Rank with every candidate added: the most any set can reach.
    pub all_rank: usize,
    /// The goal is met by the model's own outputs (nothing to add).
    pub already: bool,
    /// Rank with the model's own outputs.
    pub base_rank: usize,
    /// The variables not observable with the model's own outputs.
    pub base_unobservable_variables: Vec<String>,
    /// Each candidate alone.
    pub candidates: Vec<SensorCandidate>,
    /// Every subset size up to this was screened completely.
    pub complete_to_size: usize,
    /// Largest error bound of the ranks below full used (screen and rank tests).
    pub error_bound: f64,
    /// Every subset size was screened.
    pub exhaustive: bool,
    /// The state dimension (variables analysed).
    pub n: usize,
    /// The model's outputs and every candidate's, by name.
    pub outputs: Vec<String>,
    /// The goal is reachable with every candidate added.
    pub reachable: bool,
    /// Inclusion-minimal sets of candidates reaching the goal, by count then cost.
    pub sets: Vec<SensorSet>,
    /// The analysed variables.
    pub state: Vec<String>,
    /// How many subsets of candidates were screened.
    pub subsets_screened: usize,
    /// The model's symmetries w1, w2, ...: per vector, variable -> component (text).
    pub symmetries: Vec<BTreeMap<String, String>>,
    /// Why the symmetries were not computed, or null.
    pub symmetry_note: Option<String>,
    /// The variables that must become observable (every one without --target).
    pub target: Vec<String>,
}

/// One candidate sensor alone.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct SensorCandidate {
    /// The symmetries it breaks (w1, w2, ...).
    pub breaks: Vec<String>,
    /// Its cost (`cost C` in the candidates file; 1 by default).
    pub cost: f64,
    /// Its name.
    pub name: String,
    /// The outputs it adds.
    pub outputs: Vec<String>,
    /// The rank with it added.
    pub rank: usize,
}

/// A minimal set of candidates.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct SensorSet {
    /// The symmetries it breaks (w1, w2, ...).
    pub breaks: Vec<String>,
    /// The candidates in the set.
    pub candidates: Vec<String>,
    /// Their total cost.
    pub cost: f64,
    /// How many candidates.
    pub count: usize,
    /// The rank test's error bound (0 for full rank).
    pub error_bound: f64,
    /// Full rank, which is exact.
    pub exact: bool,
    /// The state dimension.
    pub n: usize,
    /// The rank with the set added.
    pub rank: usize,
    /// The variables still not observable.
    pub unobservable_variables: Vec<String>,
}

/// The input families (the model's restrictions), alone and combined.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Inputs {
    /// Minimal combinations of distinct families not sufficient alone, one experiment each.
    pub combinations: Vec<FamilyCombination>,
    /// False when more than 12 such families left the combinations untried.
    pub combinations_complete: bool,
    /// How many combinations were tried.
    pub combinations_tried: usize,
    /// Largest error bound of the ranks below full (full ranks are exact).
    pub error_bound: f64,
    /// Each family.
    pub families: Vec<Family>,
}

/// One input family.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Family {
    /// Experiments of it after which the rank stops growing (or is full).
    pub experiments: usize,
    /// Everything observable with `experiments` experiments.
    pub full: bool,
    /// The stacked dimension at `experiments` experiments.
    pub n: usize,
    /// The rank at `experiments` experiments.
    pub rank: usize,
    /// The restriction's name; null for the unrestricted model.
    pub restriction: Option<String>,
    /// Everything observable from one experiment.
    pub single_full: bool,
    /// The dimension of one experiment.
    pub single_n: usize,
    /// The rank of one experiment.
    pub single_rank: usize,
}

/// A combination of families, one experiment each.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct FamilyCombination {
    /// The families' restrictions ("unrestricted" for none).
    pub families: Vec<String>,
    /// The stacked dimension.
    pub n: usize,
    /// The rank.
    pub rank: usize,
}

/// One of several experiments (`--experiment`, `--experiments FILE`).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Experiment {
    /// Its input restriction, or null.
    pub restriction: Option<String>,
    /// Its constants' values: name -> exact rational as text.
    pub set: BTreeMap<String, String>,
}

/// `obsan rank --known NAME=VALUE | --known-generic NAME --json`: the rank with initial
/// values known.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct RankKnown {
    /// The Lie words of the basis.
    pub basis: Vec<BasisWord>,
    /// How the rank is certified, in words.
    pub certificate: String,
    /// `rank` is the answer (known values generic, invariant, or the point's certified lower
    /// bound met the generic upper bound); false: only point_rank <= rank <= generic_rank.
    pub determined: bool,
    /// 0 when identifiable, else the generic rank test's error bound.
    pub error_bound: f64,
    /// True when every unknown is identifiable (then proven).
    pub exact: bool,
    /// The stacked experiments, or null.
    pub experiments: Option<Vec<Experiment>>,
    /// The generic rank (every state unknown).
    pub generic_rank: usize,
    /// Every unknown is identifiable.
    pub identifiable: bool,
    /// With specific values: every field leaves the known coordinates at their values.
    pub invariant: bool,
    /// The states whose initial value is known: value as exact text, or null when generic.
    pub known: Vec<KnownValue>,
    /// The number of unknowns.
    pub n: usize,
    /// The unknowns identifiable on their own.
    pub observable_variables: Vec<String>,
    /// With specific values: every Lie word up to this order was evaluated.
    pub order_checked: usize,
    /// With specific values: the rank at that point (a certified lower bound); else null.
    pub point_rank: Option<usize>,
    /// The rank in the unknowns.
    pub rank: usize,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// The analysed variables.
    pub state: Vec<String>,
    /// The system's name.
    pub system: String,
    /// The unknowns (the state less the known values).
    pub unknowns: Vec<String>,
    /// The unknowns not identifiable on their own.
    pub unobservable_variables: Vec<String>,
    /// How many Lie words were evaluated.
    pub words_evaluated: usize,
}

/// A Lie word with its order.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct BasisWord {
    /// The Lie word, e.g. `L_f0 h1`.
    pub lie_derivative: String,
    /// Its order.
    pub order: usize,
}

/// A known initial value.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct KnownValue {
    /// The state.
    pub name: String,
    /// Its value as an exact rational, or null when known but generic.
    pub value: Option<String>,
}

/// `obsan rank --experiments auto --json`: how many generic experiments identify all they can.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct RankAuto {
    /// The constants that vary between experiments (their values generic).
    pub constants: Vec<String>,
    /// Largest error bound among the probabilistic ranks used.
    pub error_bound: f64,
    /// Full rank with no error bound.
    pub exact: bool,
    /// The smallest number of experiments after which the rank stops growing.
    pub experiments: usize,
    /// The rank is full.
    pub full_rank: bool,
    /// The stacked dimension at that number.
    pub n: usize,
    /// Dimension of the params.
    pub n_params: usize,
    /// The param directions fixed by the stack.
    pub param_rank: usize,
    /// Special values at which a denominator of the system is zero (no experiment there).
    pub poles: Vec<ConstantValue>,
    /// The rank at that number.
    pub rank: usize,
    /// The rank after each number of experiments.
    pub ranks: Vec<RankStep>,
    /// The input restriction, or null.
    pub restriction: Option<String>,
    /// Seed of the random evaluation points.
    pub seed: u64,
    /// Values of the constants that lose rank.
    pub special_values: Vec<SpecialValue>,
    /// The rank of one experiment's rows in its own state columns.
    pub state_rank: usize,
    /// The system's name.
    pub system: String,
}

/// A constant's value.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ConstantValue {
    /// The constant.
    pub constant: String,
    /// Its value as an exact rational.
    pub value: String,
}

/// The rank after some number of experiments.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct RankStep {
    /// The number of experiments.
    pub experiments: usize,
    /// The stacked dimension.
    pub n: usize,
    /// The rank.
    pub rank: usize,
}

/// A value of a constant that loses rank.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct SpecialValue {
    /// The constant.
    pub constant: String,
    /// It gives less than a generic experiment: either rank drops.
    pub degenerate: bool,
    /// The minimal design's rank with one experiment at this value, the others generic.
    pub design_rank: usize,
    /// One experiment's rank at this value.
    pub single_rank: usize,
    /// The value as an exact rational.
    pub value: String,
}
