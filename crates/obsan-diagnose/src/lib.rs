//! obsan's discrepancy workflow: where a model and measured data
//! disagree, which candidate effect explains it, and whether the data can
//! reveal it at all.
//!
//! 1. [`diagnose`] fits the nominal model by maximum likelihood (the same
//!    fitter as `obsan calibrate --method ml`), then tests its residuals
//!    ([`ResidualReport`]).
//! 2. Each candidate [`obsan_model::Effect`] extends the model. The rank
//!    test of the extended model on this data's input class
//!    ([`identifiability::input_class`], [`identifiability::stacked_rank`]) decides whether its params are
//!    identifiable; if not, the null vector that hides them is reported.
//! 3. Identifiable candidates are fitted from the current fit and scored
//!    (likelihood ratio, BIC); the best significant one is named, and the
//!    search repeats on the extended model. Candidates that fit about as
//!    well as the named one are reported with it ([`Rival`]), with whether
//!    the data can separate them at all.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod candidate;
mod combine;
mod common_mode;
mod compete;
mod correlation;
mod curvature;
mod error;
mod generate;
mod identify;
mod model_fit;
mod options;
mod phase;
mod relation;
mod relevel;
mod report;
mod residual;
mod sandwich;
mod screen;
mod settle;
mod start;
mod stats;
mod units;
mod workflow;

// The root keeps the workflow, its options and its report; the identifiability and
// statistical checks are behind public modules, so the root stays small (at most 40
// names, checked by scripts/module_dag.py --exports).
pub use curvature::{Curvature, MIN_STAND_IN_RESIDUALS, Z_STAND_IN};
pub use error::DiagnoseError;
pub use generate::{generate, levels, Generated, Generation, FILE_SHARE, ORIGIN_GENERATED};
pub use model_fit::{fit_model, input_noise, prepare, ModelFit, Start};
pub use options::{DiagnoseOptions, InputNoise, AUTO_ESTIMATE_BELOW};
pub use relation::{InputCheck, TrajectoryCheck};
pub use report::{
    CandidateResult, Competing, Diagnosis, Named, Refit, Relevel, Rival, MOVED_SD, ORIGIN_FILE,
    ORIGIN_RELATION, RIVAL_BIC,
};
pub use residual::{analyse, ResidualReport, ResidualSeries, Structure, Z_STRUCTURE};
pub use screen::SCREEN_SAFETY;
pub use start::start_values;
pub use workflow::diagnose;

/// Whether a candidate's params are identifiable on the data's input class: the stacked
/// rank test and the null vector that hides them.
pub mod identifiability {
    pub use crate::identify::{
        check_effect_sizes, input_class, stacked_rank, Identifiability, InputClass, DIRECTION,
        MAX_NULL_COLUMNS, VARYING,
    };
}

/// Statistics between fitted candidates: correlations of estimates and the common-mode
/// check of candidates that differ by a shared offset.
pub mod statistics {
    pub use crate::common_mode::{
        difference_estimate, CommonModeCheck, DifferenceEstimate, Member, PREDICTED_MARGIN,
    };
    pub use crate::compete::competing_text;
    pub use crate::correlation::{
        correlated, correlation, Combination, Correlation, CORRELATION_CAUTION,
    };
}

/// The units of the effects' params: a small dimensional analysis of where
/// each enters, declarations first (docs/diagnose.md, Units).
pub mod dimensions {
    pub use crate::units::{effect_units, param_units};
}
