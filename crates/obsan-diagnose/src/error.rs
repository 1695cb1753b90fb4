//! The workflow's typed errors. `Display` is the exact text the CLI prints
//! (its tests compare the texts); `source()` gives the wrapped error of the
//! layer below (model, analysis, data, fit, calibration).

use obsan_analysis::AnalysisError;
use obsan_calib::CalibError;
use obsan_data::DerivedInputError;
use obsan_fit::FitError;
use obsan_model::ModelError;
use std::fmt;

/// What went wrong in a start, a fit, an input class or a rank test of the
/// discrepancy workflow.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum DiagnoseError {
    /// The model has no normal form (its message).
    Model(Box<ModelError>),
    /// An effect could not be applied to the model.
    Extend(Box<ModelError>),
    /// The stacked model of the rank test does not parse.
    Stacking(Box<ModelError>),
    /// The rank test failed (deadline, no usable point).
    Rank(AnalysisError),
    /// A gradient of the rank test's basis could not be compiled.
    GradientTape,
    /// The SVD gave no right singular vectors (it was asked for them).
    NoSingularVectors,
    /// The rank test's basis reaches more variables than the null vectors
    /// are computed for (`at`: the effect, located, or empty for the model).
    TooManyReached {
        reached: usize,
        limit: usize,
        at: String,
    },
    /// An effect's expressions use more new params than diagnose takes
    /// (`at`: FILE:LINE: effect 'NAME').
    EffectTooLarge {
        params: usize,
        limit: usize,
        at: String,
    },
    /// A model state has no equation, or an output no expression.
    Incomplete(&'static str),
    /// A fit or a noise estimate failed.
    Fit(FitError),
    /// The prediction at a fit failed on one trajectory.
    Predict {
        trajectory: String,
        source: FitError,
    },
    /// A derived input could not be added to one trajectory.
    DerivedInput {
        trajectory: String,
        source: Box<DerivedInputError>,
    },
    /// A model input has no column in a trajectory.
    NoInputColumn { trajectory: String, column: String },
    /// A trajectory has no input rows.
    NoInputRows { trajectory: String },
    /// A trajectory's inputs are not finite.
    NonFiniteInputs { trajectory: String },
    /// The SVD of a trajectory's input class did not converge.
    InputClassNotConverged { trajectory: String },
    /// None of the outputs is measured on the trajectories of a rank test.
    NoOutputMeasured,
    /// The input-noise covariance overflows on a trajectory.
    NoiseCovariance { trajectory: String },
    /// The paper's start failed (`first`) and no circle's modes can be read.
    CalibStart { first: Box<CalibError> },
    /// The screened start needs the states `mu` and `gamma`.
    ScreenNeedsMuGamma,
    /// The model diverges from every screened grid point.
    ScreenDiverges,
    /// None of the screened starts could be fitted.
    ScreenNoFit { tried: usize },
    /// `--init NAME=...` names neither a param nor a state.
    UnknownInit { name: String, system: String },
    /// A state has no start value on a trajectory.
    NoStartValue {
        state: String,
        system: String,
        trajectory: String,
    },
    /// A declared state start (`state va = EXPR`) cannot be evaluated.
    StateStart {
        state: String,
        trajectory: String,
        source: Box<DerivedInputError>,
    },
    /// A declared state start has no finite value at the first input row.
    StateStartNoValue {
        state: String,
        expr: String,
        trajectory: String,
    },
    /// A state added by an effect has no declared start (trajectory index).
    NewStateNoStart { state: String, trajectory: usize },
    /// A time param (a delay, a lag's time constant) estimated beyond the
    /// longest trajectory: no data of that length can fix it, so the fit
    /// failed rather than found it.
    OutOfRange {
        param: String,
        value: f64,
        longest: f64,
    },
}

impl fmt::Display for DiagnoseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use DiagnoseError::*;
        match self {
            Model(e) | Extend(e) => write!(f, "{e}"),
            Stacking(e) => write!(f, "stacking the model: {e}"),
            Rank(e) => write!(f, "{e}"),
            GradientTape => f.write_str("gradient tape"),
            NoSingularVectors => f.write_str("the SVD returned no right singular vectors"),
            EffectTooLarge { params, limit, at } => write!(
                f,
                "{at}: too large: its expressions use {params} new params, more than the {limit} \
                 diagnose fits (dense in their number squared; a param declared but never used \
                 costs nothing)"
            ),
            TooManyReached { reached, limit, at } => write!(
                f,
                "{at}{}too large: the outputs reach {reached} variables, more than the {limit} \
                 whose null vectors diagnose computes (a dense SVD in their number squared; \
                 params the outputs do not reach cost nothing)",
                if at.is_empty() { "" } else { ": " }
            ),
            Incomplete(what) => f.write_str(what),
            Fit(e) => write!(f, "{e}"),
            Predict { trajectory, source } => write!(f, "trajectory '{trajectory}': {source}"),
            DerivedInput { trajectory, source } => write!(f, "trajectory {trajectory}: {source}"),
            NoInputColumn { trajectory, column } => {
                write!(f, "trajectory {trajectory}: no input column '{column}'")
            }
            NoInputRows { trajectory } => write!(f, "trajectory {trajectory}: no input rows"),
            NonFiniteInputs { trajectory } => {
                write!(f, "trajectory {trajectory}: non-finite input values")
            }
            InputClassNotConverged { trajectory } => {
                write!(f, "trajectory {trajectory}: the input class did not converge")
            }
            NoOutputMeasured => f.write_str("no output is measured on the chosen trajectories"),
            NoiseCovariance { trajectory } => write!(
                f,
                "the input-noise covariance cannot be formed on trajectory {trajectory}: a state decays \
                 too fast over it for the linearised noise model (use --input-noise none)"
            ),
            CalibStart { first } => write!(
                f,
                "the calib start (DET + LS) failed: {first}, and no trajectory's modes can be \
                 read alone; give start values with --init NAME=VALUE"
            ),
            ScreenNeedsMuGamma => f.write_str("the screened start needs the states mu and gamma"),
            ScreenDiverges => {
                f.write_str("no start: the model diverges from every screened grid point")
            }
            ScreenNoFit { tried } => write!(
                f,
                "no start: none of the {tried} screened starts could be fitted"
            ),
            UnknownInit { name, system } => write!(
                f,
                "--init {name}: '{name}' is neither a param nor a state of {system}"
            ),
            NoStartValue {
                state,
                system,
                trajectory,
            } => write!(
                f,
                "no start value for state '{state}' of {system} on trajectory {trajectory}: give one with --init {state}=VALUE"
            ),
            StateStart {
                state,
                trajectory,
                source,
            } => write!(
                f,
                "start of state {state} on trajectory {trajectory}: {source}"
            ),
            StateStartNoValue {
                state,
                expr,
                trajectory,
            } => write!(
                f,
                "start of state {state} = {expr} on trajectory {trajectory}: no value at the first input row"
            ),
            OutOfRange {
                param,
                value,
                longest,
            } => write!(
                f,
                "{param} = {value:.3e} s is longer than the longest trajectory ({longest:.1} s): \
                 a failed fit, not a finding"
            ),
            NewStateNoStart { state, trajectory } => write!(
                f,
                "the new state {state} has no start value on trajectory {trajectory} (declare it as state {state} = EXPR)"
            ),
        }
    }
}

impl std::error::Error for DiagnoseError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        use DiagnoseError::*;
        match self {
            Model(e) | Extend(e) | Stacking(e) => Some(e.as_ref()),
            Rank(e) => Some(e),
            Fit(e) | Predict { source: e, .. } => Some(e),
            DerivedInput { source, .. } | StateStart { source, .. } => Some(source.as_ref()),
            CalibStart { first } => Some(first.as_ref()),
            _ => None,
        }
    }
}

impl DiagnoseError {
    /// The model's normal form failed.
    pub(crate) fn model(e: ModelError) -> DiagnoseError {
        DiagnoseError::Model(Box::new(e))
    }
}

impl From<FitError> for DiagnoseError {
    fn from(e: FitError) -> DiagnoseError {
        DiagnoseError::Fit(e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error;

    #[test]
    fn wrapped_errors_keep_their_text_and_source() {
        let e = DiagnoseError::Predict {
            trajectory: "r1".into(),
            source: FitError::DelayNotFinite,
        };
        assert_eq!(e.to_string(), "trajectory 'r1': the delay is not finite");
        assert_eq!(
            e.source().map(|s| s.to_string()).as_deref(),
            Some("the delay is not finite")
        );
        let e = DiagnoseError::from(FitError::SingularFisher);
        assert_eq!(e.to_string(), FitError::SingularFisher.to_string());
        assert!(e.source().is_some());
        let e = DiagnoseError::CalibStart {
            first: Box::new(CalibError::NoModel),
        };
        assert!(e
            .to_string()
            .starts_with("the calib start (DET + LS) failed: ml needs the model (calib.sys), and"));
        assert_eq!(
            e.source().map(|s| s.to_string()),
            Some(CalibError::NoModel.to_string())
        );
        assert!(DiagnoseError::ScreenDiverges.source().is_none());
    }

    #[test]
    fn start_messages_name_state_system_and_trajectory() {
        let e = DiagnoseError::NoStartValue {
            state: "va".into(),
            system: "lag".into(),
            trajectory: "c2".into(),
        };
        assert_eq!(
            e.to_string(),
            "no start value for state 'va' of lag on trajectory c2: give one with --init va=VALUE"
        );
        let e = DiagnoseError::UnknownInit {
            name: "zz".into(),
            system: "calib".into(),
        };
        assert_eq!(
            e.to_string(),
            "--init zz: 'zz' is neither a param nor a state of calib"
        );
    }
}
