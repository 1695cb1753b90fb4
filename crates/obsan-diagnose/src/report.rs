//! The workflow's result types: what happened to each candidate, what was named,
//! and the whole [`Diagnosis`]. Near the bottom of the module graph: they name the
//! fit, check and correlation types and no step of the workflow.

use crate::common_mode::CommonModeCheck;
use crate::correlation::{Combination, Correlation};
use crate::curvature::Curvature;
use crate::generate::ORIGIN_GENERATED;
use crate::model_fit::ModelFit;
use crate::relation::InputCheck;
use obsan_model::Effect;
use serde::Serialize;

/// What happened to one candidate in one round.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateResult {
    pub effect: String,
    pub description: String,
    /// [`ORIGIN_FILE`] or [`ORIGIN_GENERATED`].
    pub origin: String,
    /// The effect's new params.
    pub params: Vec<String>,
    /// Identifiable on these data (the rank test).
    pub identifiable: bool,
    pub rank: Option<(usize, usize)>,
    /// When not identifiable: what absorbs it (a null vector at the fit).
    pub symmetry: Vec<(String, f64)>,
    /// Fitted new params with standard deviations.
    pub estimates: Vec<(String, f64, f64)>,
    /// Their cluster-robust sds (trajectories as clusters).
    pub robust_sd: Vec<f64>,
    /// Likelihood-ratio statistic (quasi-likelihood: divided by the larger
    /// model's reduced chi-square when above 1), its p-value, BIC change
    /// (negative is better), residual RMS per output, whiteness z.
    pub lr: f64,
    pub p_value: f64,
    pub delta_bic: f64,
    pub rms: Vec<(String, f64)>,
    pub whiteness_z: f64,
    pub significant: bool,
    /// The smallest `|estimate| / sd` of its params, each sd the larger of
    /// the model's and the cluster-robust one (the Wald check).
    pub wald_z: f64,
    /// Its LR clears the critical value but its Wald z does not: suggested,
    /// not established (never named).
    pub suggested: bool,
    /// Weighed at white input noise: under `auto` with estimated input
    /// noise, the candidate fitted better there than at the estimated levels.
    pub white_input_noise: bool,
    /// Weighed at noise levels estimated again with the effect in the
    /// model (its white-noise fit gained, but lost to the levels that had
    /// absorbed it; see `candidate::joint`).
    pub joint_levels: bool,
    /// The residual structure its fit leaves: each significant residual
    /// test (`Structure::test`) with its z, strongest first. When a
    /// generated and a file candidate compete, this says what each fails
    /// to explain.
    pub structure: Vec<(String, f64)>,
    /// The fit moved its new params from their start (by more than
    /// [`MOVED_SD`] of their sd). `false` with an LR near 0: the candidate
    /// was not really fitted, so it is not ruled out.
    pub moved: bool,
    pub error: Option<String>,
    /// The candidate's score statistic at the current fit (see
    /// `screen.rs`), when computed: generated candidates in every
    /// round, the file's from the second round on.
    pub score: Option<f64>,
    /// Left unfitted: its score is below [`Diagnosis::screen_threshold`].
    pub screened_out: bool,
    /// The heading-free check of a candidate that rewrites angle outputs
    /// ([`CommonModeCheck`]); a veto makes it not significant.
    pub common_mode: Option<CommonModeCheck>,
}

impl CandidateResult {
    /// A candidate's entry before anything is known of it: not identifiable,
    /// not fitted. `origin` is the generated marker or anything else (the
    /// effects file).
    pub(crate) fn untried(e: &Effect, origin: &str) -> CandidateResult {
        CandidateResult {
            effect: e.name.clone(),
            description: e.description.clone(),
            origin: if origin == ORIGIN_GENERATED {
                ORIGIN_GENERATED
            } else {
                ORIGIN_FILE
            }
            .into(),
            params: e.params.clone(),
            identifiable: false,
            rank: None,
            symmetry: vec![],
            estimates: vec![],
            robust_sd: vec![],
            lr: 0.0,
            p_value: 1.0,
            delta_bic: 0.0,
            rms: vec![],
            whiteness_z: 0.0,
            significant: false,
            wald_z: 0.0,
            suggested: false,
            white_input_noise: false,
            joint_levels: false,
            structure: vec![],
            moved: false,
            error: None,
            score: None,
            screened_out: false,
            common_mode: None,
        }
    }
}

/// One named effect.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Named {
    pub effect: String,
    pub description: String,
    /// Where the effect comes from: [`ORIGIN_FILE`] (the user's effects
    /// file, fitted in the model) or [`ORIGIN_RELATION`] (a `compare`
    /// relation the measured inputs contradict, fitted on the inputs).
    pub origin: String,
    pub estimates: Vec<(String, f64, f64)>,
    /// Cluster-robust sds of the estimates (trajectories as clusters).
    pub robust_sd: Vec<f64>,
    pub rms_before: Vec<(String, f64)>,
    pub rms_after: Vec<(String, f64)>,
    pub lr: f64,
    pub p_value: f64,
    /// Other significant candidates of the same round that fit almost as
    /// well (BIC within [`RIVAL_BIC`]): the data hardly tell them apart.
    pub rivals: Vec<Rival>,
    /// Its params' correlations with the final model's other params with
    /// `|r| >=` [`crate::statistics::CORRELATION_CAUTION`]: with another named effect's, the
    /// data fix a combination of the two rather than each. Those with the
    /// user's model's own params are informative only (a correct radius
    /// change correlates with calib.sys's delta at 0.999). Empty for an
    /// input relation, which is not in the fit.
    pub correlated: Vec<Correlation>,
    /// A stand-in for an effect of another form: it rewrites outputs whose
    /// residuals in the final fit still curve in the predicted value
    /// (`|curvature.z| >` [`crate::Z_STAND_IN`]).
    pub stand_in: bool,
    /// The curvature test of the outputs it rewrites; `None`: it rewrites
    /// none, or too few residuals to test.
    pub curvature: Option<Curvature>,
    /// Its LR at the final levels: the final model without it, fitted under
    /// them, against the final fit (`None`: the levels never moved after
    /// round 1, or that fit failed; see `relevel::weak_under_final`).
    pub lr_final: Option<f64>,
    /// `lr_final` is at or below its critical value: named under earlier
    /// levels, it would not pass under the final ones (the naming stands).
    pub weak_under_final_levels: bool,
}

/// The current model refitted before a round's comparison: a candidate's
/// point with its params at 0 fitted better than the current fit, which
/// had stopped short.
#[derive(Clone, Debug, Serialize)]
pub struct Refit {
    /// The round (1-based) whose candidates were weighed again.
    pub round: usize,
    /// The candidate whose point the refit started from.
    pub from: String,
    /// `-2 log L` of the current fit before and after.
    pub m2ll_before: f64,
    pub m2ll_after: f64,
}

/// A candidate that explains the data about as well as a named effect.
#[derive(Clone, Debug, Serialize)]
pub struct Rival {
    pub effect: String,
    /// Its BIC change minus the named effect's (>= 0).
    pub delta_bic: f64,
    /// Whether it stays identifiable once the named effect is in the model
    /// (the next round's rank test); `false`: on these data the two are
    /// confounded, so naming one rather than the other is arbitrary.
    pub jointly_identifiable: Option<bool>,
}

/// [`Named::origin`] of an effect from the effects file.
pub const ORIGIN_FILE: &str = "effects file";

/// A candidate whose new params ended within this fraction of their sd of
/// their start was not moved by its fit ([`CandidateResult::moved`]): a
/// thousandth of an sd changes `-2 log L` by about 1e-6, nothing any test
/// can see, so such a fit says nothing about the effect.
pub const MOVED_SD: f64 = 1e-3;
/// [`Named::origin`] of an input relation the measured inputs contradict.
pub const ORIGIN_RELATION: &str = "input relation";

/// Candidates whose BIC is within this of the best one's are reported as
/// rivals ("strong evidence" starts at 6 on Kass and Raftery's scale).
pub const RIVAL_BIC: f64 = 6.0;

/// Two candidates of one round fitted together: the generated winner
/// first, the file's competitor second.
#[derive(Clone, Debug, Serialize)]
pub struct Competing {
    /// Round (1-based) in which they competed.
    pub round: usize,
    pub effects: [String; 2],
    /// Each one's LR alone (against the current model of the round).
    pub lr_alone: [f64; 2],
    /// The joint fit's estimates of both effects' params (name, value,
    /// model sd inflated as a candidate's), then their cluster-robust sds.
    pub estimates: Vec<(String, f64, f64)>,
    pub robust_sd: Vec<f64>,
    /// Each effect's Wald z in the joint fit (the other present).
    pub wald_z: [f64; 2],
    /// The Wald z each must clear (square root of its LR critical value).
    pub wald_z_critical: [f64; 2],
    /// The residual tests each one's own fit leaves, `[test, z]`.
    pub structure: [Vec<(String, f64)>; 2],
    /// The one still established with the other present (it is named), or
    /// `None`: competing explanations, not separated by these data
    /// (`named_form` says whether one form is named).
    pub established: Option<String>,
    /// Neither established, each significant alone (one effect in two
    /// forms): the form named, the stronger in the joint fit; the search
    /// goes on. `None` otherwise.
    pub named_form: Option<String>,
}

/// The levels after one round's naming: those the round was weighed under,
/// those the next round is weighed under (or, stated, those the data give),
/// and the level test of the extended model's fit under each.
#[derive(Clone, Debug, Serialize)]
pub struct Relevel {
    /// The round (1-based) that named `named`.
    pub round: usize,
    pub named: String,
    /// `estimated`: obsan estimated the levels and re-estimated them here;
    /// `stated`: they were given and are kept (`*_after` is what the data
    /// give, for the note).
    pub source: String,
    /// The levels round `round` was weighed under.
    pub sigma_before: Vec<(String, f64)>,
    pub input_noise_before: Vec<(String, f64)>,
    /// Re-estimated (round `round + 1` is weighed under them when
    /// `replaced`), or, stated, each output's RMS corrected for the fitted
    /// unknowns.
    pub sigma_after: Vec<(String, f64)>,
    pub input_noise_after: Vec<(String, f64)>,
    /// The level test's chi-square z of the extended model's fit under the
    /// levels before and under those round `round + 1` uses.
    pub chi2_z_before: f64,
    pub chi2_z_after: f64,
    /// The next round is weighed under `*_after`.
    pub replaced: bool,
    /// Stated levels the residuals contradict (|`chi2_z_after`| above
    /// [`crate::Z_STRUCTURE`]): the text prints a note.
    pub note: bool,
}

/// The whole outcome.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    pub model: String,
    /// How the nominal fit's start was found (see [`crate::start_values`]).
    pub start: String,
    pub sigma: Vec<(String, f64)>,
    pub sigma_estimated: bool,
    /// Per measured input, the noise intensity `c` (spectral density
    /// `c |u|`) used in the final fit; empty: none.
    pub input_noise: Vec<(String, f64)>,
    /// "stated", "estimated" or "none".
    pub input_noise_source: String,
    /// When estimated: per estimate (at the nominal fit, then after each
    /// named effect), the likelihood-ratio statistic of the input noise
    /// against white output noise alone.
    pub input_noise_lr: Vec<f64>,
    pub input_class: String,
    /// The nominal fit, converged: when a candidate's point showed that the
    /// fit from the start had stopped short, its refit (see `refits`).
    pub nominal: ModelFit,
    /// `false`: the fit from the start had not converged (`refits` says
    /// from where it was refitted, and by how much `-2 log L` fell).
    pub nominal_converged: bool,
    /// Every refit of the current model before a round's comparison.
    pub refits: Vec<Refit>,
    pub rounds: Vec<Vec<CandidateResult>>,
    pub named: Vec<Named>,
    /// The last round's candidates whose LR clears the critical value but
    /// whose estimate is not established (Wald z, with the larger of the
    /// model's and the cluster-robust sd, below the critical value):
    /// suggested, not established, never named.
    pub suggested: Vec<CandidateResult>,
    /// Pairs of params fixed only in combination (`|r| >=`
    /// [`crate::statistics::CORRELATION_CAUTION`]): of two named effects in the final
    /// fit, then of two suggested candidates fitted together (`named`
    /// false). Compare such a pair through its combination, not each
    /// param alone.
    pub combinations: Vec<Combination>,
    /// A generated winner fitted together with a competing file candidate
    /// ([`Competing`]); with `established` `None` neither is named
    /// (competing explanations, not separated by these data) and the
    /// search stopped there.
    pub competing: Vec<Competing>,
    pub input_checks: Vec<InputCheck>,
    pub final_fit: ModelFit,
    /// Effects these data cannot reveal, with what absorbs them.
    pub hidden: Vec<CandidateResult>,
    /// The extended model (nominal plus the named effects) as .sys text.
    pub extended_sys: String,
    /// Per-round critical value of the LR statistic (the effects file's
    /// candidates).
    pub lr_critical: f64,
    /// The same for the generated candidates (their share of alpha split
    /// over more candidates; infinite when none are generated).
    pub lr_critical_generated: f64,
    /// Generated candidates left out before any fit, with the reason (the
    /// same as a user effect, or not an extension of the model).
    pub generated_dropped: Vec<(String, String)>,
    /// Generated candidates whose score statistic is below this are not
    /// fitted (`lr_critical_generated / SCREEN_SAFETY`; infinite: no screen,
    /// as under input noise, which the score does not weigh).
    pub screen_threshold: f64,
    /// After each round that named an effect, the levels before and after
    /// (re-estimated, or stated with what the data give).
    pub relevels: Vec<Relevel>,
}

impl Diagnosis {
    /// The `k`-th named effect's correlations with the effects named before
    /// it, each with that effect: a pair once, under the later of the two.
    pub fn correlated_with_earlier(&self, k: usize) -> Vec<(&Correlation, &Named)> {
        let (Some(n), Some(earlier)) = (self.named.get(k), self.named.get(..k)) else {
            return vec![];
        };
        n.correlated
            .iter()
            .filter_map(|c| {
                let w = c.with_effect.as_ref()?;
                Some((c, earlier.iter().find(|m| m.effect == *w)?))
            })
            .collect()
    }
}
