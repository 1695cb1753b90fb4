//! `obsan global` and `obsan simulate MODEL.sys`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `obsan global SYSTEM --json`: global identifiability (SIAN).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Global {
    /// Every variable is at least locally identifiable.
    pub all_local: bool,
    /// The degree bound of the local test.
    pub degree_bound_local: f64,
    /// The number of polynomial equations.
    pub equations: usize,
    /// Probability bound that some verdict is wrong.
    pub error_bound: f64,
    /// Always false: the answer is probabilistic (`error_bound`).
    pub exact: bool,
    /// Why the Taylor route did not answer, when `route` fell back on
    /// `input-output` or `lie`; else null.
    pub fallback: Option<String>,
    /// The order of the group of discrete symmetries found.
    pub group_order: usize,
    /// log10 of the degree bound of the global test.
    pub log10_degree_bound_global: f64,
    /// The discrete symmetries, as text: each keeps every output as written.
    pub maps: Vec<String>,
    /// Symmetries of the angle outputs' tangents only (outputs counted as
    /// `tangent`): each turns an angle output by pi, or is not decided on
    /// the angles; not symmetries of the model as written.
    pub maps_modulo_pi: Vec<String>,
    /// Discrete symmetries of the parameters alone (`input-output` route),
    /// as text: each keeps every input-output relation's coefficients,
    /// checked exactly over Q; the initial states' images are not sought.
    pub maps_of_parameters: Vec<String>,
    /// How the answer was found, in words.
    pub method: String,
    /// The counts are of multi-experiment identifiability only (`--multi-experiment`,
    /// and some output's input-output relation has a zero Wronskian, so one
    /// experiment may leave more values); false when they are single-experiment
    /// counts.
    pub multi_experiment: bool,
    /// The Taylor order used.
    pub order: usize,
    /// How each output is counted.
    pub output_forms: Vec<OutputFormJson>,
    /// Each output's order.
    pub output_orders: Vec<OutputOrder>,
    /// The two primes.
    pub primes: Vec<u64>,
    /// The order the rank needed.
    pub rank_order: usize,
    /// The input restriction applied, or null.
    pub restriction: Option<String>,
    /// The route that answered: `taylor` (SIAN's Taylor system: parameters
    /// and initial states), `input-output` (the outputs' input-output
    /// relations: parameters; `variables` lists the states only when
    /// `states_after_io.counted`) or `lie` (the iterated Lie derivatives:
    /// parameters and initial states indistinguishable for every input;
    /// `order` the longest word).
    pub route: String,
    /// The number of solutions, or null when not counted.
    pub solutions: Option<usize>,
    /// `solutions` is an upper bound: an angle output was read through its
    /// tangent (modulo pi) and the symmetries found do not settle the count.
    pub solutions_at_most: bool,
    /// With `route` `input-output` under `--route auto`: the initial states
    /// counted after it by the Taylor route with the parameters found
    /// globally identifiable fixed; null on the other routes and under
    /// `--route io`.
    pub states_after_io: Option<StatesAfterIoJson>,
    /// The system's name.
    pub system: String,
    /// The number of unknowns.
    pub unknowns: usize,
    /// Each variable's verdict.
    pub variables: Vec<GlobalVariable>,
}

/// The initial states after the input-output route (`--route auto`).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct StatesAfterIoJson {
    /// The states were counted (`variables` lists them); else `why_not`.
    pub counted: bool,
    /// The number of equations of that Taylor system.
    pub equations: usize,
    /// SIAN's probability bound on that count, given the parameters'
    /// verdicts (which carry none); 1 means no bound.
    pub error_bound: f64,
    /// The parameters fixed at the point's values: those the relations
    /// found globally identifiable.
    pub fixed_params: Vec<String>,
    /// Each output's Taylor order in that system.
    pub output_orders: Vec<OutputOrder>,
    /// The number of unknowns of that Taylor system.
    pub unknowns: usize,
    /// Why the states were not counted, or null.
    pub why_not: Option<String>,
}

/// How the count reads one output.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct OutputFormJson {
    /// `direct` (a rational function, angles in sin/cos), `sqrt argument`
    /// or `atan argument` (the function is one-to-one: the same count), or
    /// `tangent` (an angle modulo pi: counts above 1 are upper bounds).
    pub counted_as: String,
    /// The output.
    pub output: String,
}

/// An output's Taylor order.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct OutputOrder {
    /// Its order.
    pub order: usize,
    /// The output.
    pub output: String,
}

/// One variable's identifiability.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct GlobalVariable {
    /// It is an angle (values modulo 2 pi).
    pub angle: bool,
    /// `values` is an upper bound (an angle output read modulo pi).
    pub at_most: bool,
    /// `param` or `state`.
    pub kind: VariableKind,
    /// Its name.
    pub name: String,
    /// How many values the outputs allow (1: global), or null when not identifiable.
    pub values: Option<usize>,
    /// The verdict.
    pub verdict: Verdict,
}

/// A variable's kind.
#[derive(Serialize, Deserialize, JsonSchema, Debug, Clone, Copy)]
#[serde(rename_all = "lowercase")]
pub enum VariableKind {
    /// A parameter.
    Param,
    /// A state (its initial value).
    State,
}

/// Global identifiability verdicts.
#[derive(Serialize, Deserialize, JsonSchema, Debug, Clone, Copy)]
pub enum Verdict {
    /// One value.
    #[serde(rename = "global")]
    Global,
    /// Finitely many values.
    #[serde(rename = "local")]
    Local,
    /// Infinitely many values.
    #[serde(rename = "not identifiable")]
    NotIdentifiable,
}

/// `obsan simulate MODEL.sys --json`: the model integrated (RK4) at evenly spaced times.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct SimulateSys {
    /// `time`, then the states, then the outputs.
    pub columns: Vec<String>,
    /// The estimated integration error (relative to |value| + 1).
    pub error_estimate: f64,
    /// The model file as given.
    pub model: String,
    /// One row per time: the time, then each state and each output.
    pub rows: Vec<Vec<f64>>,
    /// The RK4 steps taken.
    pub steps: usize,
    /// The error the step size is chosen for.
    pub tolerance: f64,
}
