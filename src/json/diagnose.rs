//! `obsan diagnose MODEL DATA --json` (and the report's diagnosis.json): the binary's own view
//! of the workflow's result, so that the library's field names are not the CLI's schema.
//! Fields keep the order the output has always had. Every float is a number or null (JSON has
//! no NaN or infinity: an sd that cannot be formed, a critical value with no candidate).
//! To add a key: a field here with its doc comment, filled in `from_diagnosis.rs`; the
//! schema, docs/json.md (`obsan schema --markdown`) and the tests follow from the type.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A float, or null where it is not finite.
pub type Num = Option<f64>;
/// A name with a value.
pub type NameValue = (String, Num);
/// A param's name, estimate and sd.
pub type NameEstimateSd = (String, Num, Num);

/// `obsan diagnose MODEL DATA --json`: which effects the model misses, named and fitted.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Diagnose {
    /// The model's name.
    pub model: String,
    /// How the nominal fit's start was found.
    pub start: String,
    /// Per output, the noise sd used.
    pub sigma: Vec<NameValue>,
    /// The output noise was estimated (not stated by dataset.json).
    pub sigma_estimated: bool,
    /// Per measured input, the noise intensity c (spectral density c |u|); empty: none.
    pub input_noise: Vec<NameValue>,
    /// `stated`, `estimated` or `none`.
    pub input_noise_source: String,
    /// When estimated: per estimate, the LR statistic of input noise against output noise alone.
    pub input_noise_lr: Vec<Num>,
    /// The measured inputs' class, in words.
    pub input_class: String,
    /// The nominal fit (converged; see `refits`).
    pub nominal: Fit,
    /// False: the fit from the start had not converged (`refits` says from where it was refitted).
    pub nominal_converged: bool,
    /// Every refit of the current model before a round's comparison.
    pub refits: Vec<Refit>,
    /// Per round, every candidate.
    pub rounds: Vec<Vec<Candidate>>,
    /// The named effects, in order.
    pub named: Vec<Named>,
    /// The last round's candidates suggested, not established (never named).
    pub suggested: Vec<Candidate>,
    /// Pairs of params fixed only in combination.
    pub combinations: Vec<Combination>,
    /// A generated winner fitted together with a competing file candidate.
    pub competing: Vec<Competing>,
    /// The effects on the measured inputs (`compare` relations).
    pub input_checks: Vec<InputCheck>,
    /// The final fit (nominal plus the named effects).
    pub final_fit: Fit,
    /// Effects these data cannot reveal, with what absorbs them.
    pub hidden: Vec<Candidate>,
    /// The extended model as .sys text.
    pub extended_sys: String,
    /// Per-round critical value of the LR statistic (the effects file's candidates).
    pub lr_critical: Num,
    /// The same for generated candidates; null when none are generated.
    pub lr_critical_generated: Num,
    /// Generated candidates left out before any fit: [name, reason].
    pub generated_dropped: Vec<(String, String)>,
    /// Generated candidates whose score is below this are not fitted; null: no screen.
    pub screen_threshold: Num,
    /// After each round that named an effect: the levels it was weighed under and those the next
    /// round uses (re-estimated where obsan estimated them; stated levels are kept).
    pub relevels: Vec<Relevel>,
}

/// The noise levels after one round's naming.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Relevel {
    /// The round (1-based) that named `named`.
    pub round: usize,
    /// The effect it named.
    pub named: String,
    /// `estimated` (re-estimated under the extended model) or `stated` (kept).
    pub source: String,
    /// Per output, the sd the round was weighed under.
    pub sigma_before: Vec<NameValue>,
    /// Per measured input, the noise intensity the round was weighed under.
    pub input_noise_before: Vec<NameValue>,
    /// Per output, the sd re-estimated (the next round's when `replaced`); stated: the sd the
    /// residuals give (RMS corrected for the fitted unknowns).
    pub sigma_after: Vec<NameValue>,
    /// Per measured input, the intensity the next round uses.
    pub input_noise_after: Vec<NameValue>,
    /// The level test's chi-square z of the extended model's fit under the levels before.
    pub chi2_z_before: Num,
    /// And under the levels the next round uses.
    pub chi2_z_after: Num,
    /// The next round is weighed under the levels after.
    pub replaced: bool,
    /// Stated levels the residuals contradict (|chi2_z_after| above 3.5): the text notes it.
    pub note: bool,
}

/// A fitted model and its residuals.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Fit {
    /// The model's name.
    pub model: String,
    /// Per param: [name, estimate, sd].
    pub params: Vec<NameEstimateSd>,
    /// Per param: its unit (`rad`, `s`, `1/s`, `m`; `1` a pure number; `[y]` the unit of
    /// column y of the data; docs/diagnose.md, Units), null where none could be derived.
    pub params_units: Vec<Option<String>>,
    /// Per param: the cluster-robust sd (trajectories as clusters; null with one).
    pub params_robust_sd: Vec<Num>,
    /// Per trajectory: the initial dynamic state.
    pub initial_states: Vec<Vec<Num>>,
    /// The sum of squared normalised residuals.
    pub cost: Num,
    /// With input noise: the log-determinant of the residuals' covariance (0 without).
    pub log_det: Num,
    /// The number of residuals.
    pub n: usize,
    /// The number of unknowns fitted.
    pub n_fitted: usize,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// Per output: the residual RMS (in its units).
    pub rms: Vec<NameValue>,
    /// The residuals' statistics.
    pub residuals: Residuals,
}

/// Residual statistics of a fit.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Residuals {
    /// The number of residuals.
    pub n: usize,
    /// The long-run variance factor (Bartlett, lags 1..=10), at least 1.
    pub correlation_factor: Num,
    /// The sum of squared normalised residuals.
    pub chi2: Num,
    /// Its degrees of freedom.
    pub dof: Num,
    /// Each structure test.
    pub tests: Vec<StructureTest>,
}

/// One residual structure test.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct StructureTest {
    /// Its short id: chi2, whiteness, bias, trend, loop, angle, wheel:<u>, input, lag.
    pub test: String,
    /// What it tests, in words.
    pub description: String,
    /// Its z statistic.
    pub z: Num,
    /// Significant.
    pub significant: bool,
}

/// A refit of the current model before a round's comparison.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Refit {
    /// The round (1-based).
    pub round: usize,
    /// The candidate whose point the refit started from.
    pub from: String,
    /// -2 log L before.
    pub m2ll_before: Num,
    /// -2 log L after.
    pub m2ll_after: Num,
}

/// What happened to one candidate in one round.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Candidate {
    /// The effect's name.
    pub effect: String,
    /// Its description.
    pub description: String,
    /// `effects file` or `generated`.
    pub origin: String,
    /// Its new params.
    pub params: Vec<String>,
    /// Identifiable on these data (the rank test).
    pub identifiable: bool,
    /// [rank, dimension] of the rank test, or null.
    pub rank: Option<(usize, usize)>,
    /// When not identifiable: what absorbs it, [param, component] of a null vector.
    pub symmetry: Vec<NameValue>,
    /// Its fitted new params: [name, estimate, sd].
    pub estimates: Vec<NameEstimateSd>,
    /// Per estimate: its unit (`rad`, `s`, `1/s`, `m`; `1` a pure number; `[y]` the unit of
    /// column y of the data; docs/diagnose.md, Units), null where none could be derived.
    pub units: Vec<Option<String>>,
    /// Their cluster-robust sds.
    pub robust_sd: Vec<Num>,
    /// The likelihood-ratio statistic.
    pub lr: Num,
    /// Its p-value.
    pub p_value: Num,
    /// The BIC change (negative is better).
    pub delta_bic: Num,
    /// Per output: the residual RMS.
    pub rms: Vec<NameValue>,
    /// The residual whiteness z.
    pub whiteness_z: Num,
    /// Its LR clears the critical value and its Wald z too.
    pub significant: bool,
    /// The smallest |estimate| / sd of its params (the Wald check).
    pub wald_z: Num,
    /// LR significant, Wald not: suggested, not established.
    pub suggested: bool,
    /// Weighed at white input noise.
    pub white_input_noise: bool,
    /// Weighed at noise levels estimated again with the effect in the model.
    pub joint_levels: bool,
    /// The significant residual tests its fit leaves: [test, z], strongest first.
    pub structure: Vec<NameValue>,
    /// The fit moved its new params from their start.
    pub moved: bool,
    /// Why it could not be fitted, or null.
    pub error: Option<String>,
    /// Its score statistic at the current fit, when computed.
    pub score: Num,
    /// Left unfitted: its score is below `screen_threshold`.
    pub screened_out: bool,
    /// The heading-free check of a candidate that rewrites angle outputs, or null.
    pub common_mode: Option<CommonMode>,
}

/// The heading-free (common-mode) check of a candidate.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct CommonMode {
    /// The check applies; when not, `note` says why.
    pub applies: bool,
    /// Why not, or a remark.
    pub note: String,
    /// The angle outputs the candidate rewrites.
    pub group: Vec<String>,
    /// The param checked.
    pub param: String,
    /// Instants at which two or more members were measured.
    pub instants: usize,
    /// The full fit's estimate.
    pub full: Num,
    /// Its cluster-robust sd.
    pub full_robust_sd: Num,
    /// The estimate from simultaneous differences.
    pub differences: Num,
    /// Its robust sd.
    pub differences_robust_sd: Num,
    /// |full - differences| in combined robust sds.
    pub z: Num,
    /// The limit of z (sqrt of the candidate's critical LR value).
    pub limit: Num,
    /// Not named for it: z > limit.
    pub vetoed: bool,
    /// The check is the prediction at the current fit (the candidate was not fitted).
    pub predicted: bool,
    /// The z predicted before the fit, or null.
    pub predicted_z: Num,
}

/// One named effect.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Named {
    /// The effect's name.
    pub effect: String,
    /// Its description.
    pub description: String,
    /// `effects file`, `generated` or `input relation`.
    pub origin: String,
    /// Its params: [name, estimate, sd].
    pub estimates: Vec<NameEstimateSd>,
    /// Per estimate: its unit (`rad`, `s`, `1/s`, `m`; `1` a pure number; `[y]` the unit of
    /// column y of the data; docs/diagnose.md, Units), null where none could be derived.
    pub units: Vec<Option<String>>,
    /// Their cluster-robust sds.
    pub robust_sd: Vec<Num>,
    /// Per output: the residual RMS before naming it.
    pub rms_before: Vec<NameValue>,
    /// And after.
    pub rms_after: Vec<NameValue>,
    /// The likelihood-ratio statistic.
    pub lr: Num,
    /// Its p-value.
    pub p_value: Num,
    /// Candidates of the same round that fit almost as well.
    pub rivals: Vec<Rival>,
    /// Its params' strong correlations with the final model's other params.
    pub correlated: Vec<Correlation>,
    /// A stand-in for an effect of another form: the outputs it rewrites still curve in their
    /// predicted value in the final fit (`|curvature.z|` above 3.5).
    pub stand_in: bool,
    /// The curvature test of the outputs it rewrites; null: it rewrites none, or too few residuals.
    pub curvature: Option<Curvature>,
    /// Its LR at the final levels (the final model without it against the final fit); null when
    /// the levels never moved after round 1, or that fit failed.
    pub lr_final: Num,
    /// Named under earlier levels, it would not pass under the final ones (`lr_final` at or below
    /// its critical value); the naming stands.
    pub weak_under_final_levels: bool,
}

/// The curvature test of the outputs a named effect rewrites: the whitened residual regressed on
/// the Legendre polynomials 1, x, (3x^2 - 1)/2 of the predicted value scaled to x in [-1, 1].
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Curvature {
    /// The outputs pooled.
    pub outputs: Vec<String>,
    /// The number of residuals pooled.
    pub n: usize,
    /// The predicted values' span [lo, hi], mapped to x in [-1, 1] (angles wrapped first).
    pub span: [Num; 2],
    /// The coefficient b2 of (3x^2 - 1)/2 in the outputs' units (b2 left at both ends of the span).
    pub coefficient: Num,
    /// Its sd (studentised, inflated by `correlation_factor`).
    pub sd: Num,
    /// coefficient / sd.
    pub z: Num,
    /// The long-run variance factor of the residual after the regression (at least 1).
    pub correlation_factor: Num,
}

/// A candidate that explains the data about as well as a named effect.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Rival {
    /// Its name.
    pub effect: String,
    /// Its BIC change minus the named effect's (>= 0).
    pub delta_bic: Num,
    /// It stays identifiable with the named effect in the model; null when not tested.
    pub jointly_identifiable: Option<bool>,
}

/// One param's correlation with another in the final fit.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Correlation {
    /// The named effect's param.
    pub param: String,
    /// The other param.
    pub with: String,
    /// The named effect owning `with`; null: a param of the user's model.
    pub with_effect: Option<String>,
    /// The correlation coefficient.
    pub r: Num,
}

/// Two params fixed in combination: `params[0] + weight * params[1]`.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Combination {
    /// The two params.
    pub params: [String; 2],
    /// The effects owning them.
    pub effects: [String; 2],
    /// Their estimates.
    pub values: [Num; 2],
    /// Their sds.
    pub sds: [Num; 2],
    /// Their correlation.
    pub r: Num,
    /// Their cluster-robust covariance; null entries where it could not be formed.
    pub robust_covariance: [[Num; 2]; 2],
    /// The weight of the second param.
    pub weight: Num,
    /// The combination's estimate.
    pub estimate: Num,
    /// Its sd.
    pub sd: Num,
    /// Its cluster-robust sd.
    pub robust_sd: Num,
    /// |estimate| over the larger sd.
    pub wald_z: Num,
    /// Each param alone: |value| over the larger of its sds.
    pub wald_z_alone: [Num; 2],
    /// Both effects are named.
    pub named: bool,
    /// `wald_z` clears the critical value: the data fix the combination.
    pub established: bool,
}

/// A generated winner and a file candidate fitted together (docs/diagnose.md, "Competing
/// explanations").
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Competing {
    /// The round (1-based) in which they competed.
    pub round: usize,
    /// The generated winner and the file candidate.
    pub effects: [String; 2],
    /// Each one's LR alone against the round's current model.
    pub lr_alone: [Num; 2],
    /// The joint fit's estimates of both effects' params: [name, estimate, sd].
    pub estimates: Vec<NameEstimateSd>,
    /// Per estimate: its unit (`rad`, `s`, `1/s`, `m`; `1` a pure number; `[y]` the unit of
    /// column y of the data; docs/diagnose.md, Units), null where none could be derived.
    pub units: Vec<Option<String>>,
    /// Their cluster-robust sds.
    pub robust_sd: Vec<Num>,
    /// Each effect's Wald z in the joint fit (the other present).
    pub wald_z: [Num; 2],
    /// The Wald z each must clear (square root of its LR critical value).
    pub wald_z_critical: [Num; 2],
    /// The residual tests each one's own fit leaves, [test, z].
    pub structure: [Vec<NameValue>; 2],
    /// The one still established with the other present (it is named); null: competing
    /// explanations not separated by these data (named_form: whether one form is named).
    pub established: Option<String>,
    /// Neither established, each significant alone (one effect in two forms): the form named,
    /// the stronger in the joint fit, and the search went on; null otherwise.
    pub named_form: Option<String>,
}

/// An effect on the measured inputs (a `compare` relation).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct InputCheck {
    /// The effect's name.
    pub effect: String,
    /// Its description.
    pub description: String,
    /// The relation's params: [name, estimate, sd].
    pub estimates: Vec<NameEstimateSd>,
    /// Per estimate: its unit (`rad`, `s`, `1/s`, `m`; `1` a pure number; `[y]` the unit of
    /// column y of the data; docs/diagnose.md, Units), null where none could be derived.
    pub units: Vec<Option<String>>,
    /// The largest |estimate / sd|.
    pub z: Num,
    /// Two-sided p-value of z.
    pub p_value: Num,
    /// Significant.
    pub significant: bool,
    /// `stated` or `estimated` encoder noise.
    pub noise: String,
    /// Weighted residual sum of squares over its degrees of freedom.
    pub dispersion: Num,
    /// The relation fitted on each trajectory alone.
    pub per_trajectory: Vec<TrajectoryCheck>,
    /// A remark.
    pub note: String,
}

/// One trajectory's own estimate of a relation's params.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct TrajectoryCheck {
    /// The trajectory.
    pub trajectory: String,
    /// [name, estimate, sd].
    pub estimates: Vec<NameEstimateSd>,
    /// The largest |estimate / sd|.
    pub z: Num,
}
