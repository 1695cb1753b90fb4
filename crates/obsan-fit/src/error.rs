//! The fitter's typed errors. `Display` is the exact text the CLI prints.

use std::fmt;

/// What went wrong in a prediction, a fit, a CRLB or a noise estimate.
#[derive(Debug, Clone, PartialEq)]
pub enum FitError {
    /// The initial state or the constants have the wrong length.
    StateSize { states: usize, consts: usize },
    /// A model input has no column in the input series.
    MissingInput(String),
    /// A model output has no column in the output series.
    MissingOutput(String),
    /// The input-noise intensities are not one per input.
    InputNoiseSize(usize),
    /// Input noise was asked for without sensitivities.
    InputNoiseNeedsSensitivities,
    /// The delay parameter is NaN or infinite.
    DelayNotFinite,
    /// The dynamics are faster at the start than the input rows resolve.
    TooStiff { time_scale: f64, spacing: f64 },
    /// Output times go backwards or start before the inputs.
    TimeBeforeStart { target: f64, t: f64 },
    /// The integrated state became non-finite at time `t` with these params.
    Diverged { t: f64, params: Vec<(String, f64)> },
    /// An error in one named trajectory.
    Trajectory { name: String, source: Box<FitError> },
    /// The start values do not match the model's sizes (bad start).
    BadStart,
    /// The output noise levels are not one positive value per output.
    NoiseLevels,
    /// The Fisher information cannot be inverted.
    SingularFisher,
    /// The noise estimate's inputs do not match the model's sizes.
    NoiseSizes,
    /// The input noise cannot be carried back to the trajectories' starts.
    NoiseNotCarried,
    /// The caller asked the fit to stop ([`obsan_expr::with_cancel`]).
    Cancelled,
    /// More shared params than the fitter takes ([`crate::MAX_FIT_PARAMS`]).
    TooManyParams { params: usize, limit: usize },
}

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FitError::StateSize { states, consts } => {
                write!(f, "expected {states} state values and {consts} constants")
            }
            FitError::MissingInput(n) => write!(f, "the inputs have no column '{n}'"),
            FitError::TooManyParams { params, limit } => write!(
                f,
                "too large: {params} params to fit, more than the {limit} the fitter takes \
                 (its normal equations are dense in their number squared)"
            ),
            FitError::MissingOutput(o) => write!(f, "the outputs have no column '{o}'"),
            FitError::InputNoiseSize(m) => {
                write!(f, "input noise: expected {m} values, one per input")
            }
            FitError::InputNoiseNeedsSensitivities => {
                f.write_str("input noise needs the sensitivities")
            }
            FitError::DelayNotFinite => f.write_str("the delay is not finite"),
            FitError::TooStiff {
                time_scale,
                spacing,
            } => write!(
                f,
                "the dynamics have a time scale of {time_scale:.3e} s at the start, shorter than the input rows' spacing ({spacing:.3e} s)"
            ),
            FitError::TimeBeforeStart { target, t } => write!(
                f,
                "output time {target} is before {t}: times must not decrease and start at or after the inputs"
            ),
            FitError::Diverged { t, params } => {
                let at = if params.is_empty() {
                    "no parameters".to_string()
                } else {
                    params
                        .iter()
                        .map(|(n, v)| format!("{n} = {v}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                write!(
                    f,
                    "the state diverged at t = {t} with {at}: these parameter values (or the start values, --init) make the model blow up; try start values nearer the truth, or check the data's units"
                )
            }
            FitError::Trajectory { name, source } => write!(f, "trajectory '{name}': {source}"),
            FitError::BadStart => f.write_str("initial values do not match the model"),
            FitError::NoiseLevels => f.write_str("one positive noise level per output is needed"),
            FitError::SingularFisher => f.write_str(
                "the Fisher information is singular: some unknowns are not identifiable from these data",
            ),
            FitError::NoiseSizes => f.write_str("noise estimate: sizes do not match the model"),
            FitError::NoiseNotCarried => f.write_str(
                "the input noise cannot be carried back to the trajectories' starts \
                    (a state decays too fast over them): no intensity can be estimated",
            ),
            FitError::Cancelled => f.write_str("interrupted"),
        }
    }
}

impl std::error::Error for FitError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            FitError::Trajectory { source, .. } => Some(source.as_ref()),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trajectory_wraps_the_inner_message_and_source() {
        let e = FitError::Trajectory {
            name: "r1".into(),
            source: Box::new(FitError::DelayNotFinite),
        };
        assert_eq!(e.to_string(), "trajectory 'r1': the delay is not finite");
        let src = std::error::Error::source(&e).map(|s| s.to_string());
        assert_eq!(src.as_deref(), Some("the delay is not finite"));
    }

    #[test]
    fn diverged_lists_params_or_says_none() {
        let e = FitError::Diverged {
            t: 1.5,
            params: vec![("a".into(), 2.0), ("b".into(), -0.25)],
        };
        assert!(e
            .to_string()
            .starts_with("the state diverged at t = 1.5 with a = 2, b = -0.25: "));
        let e = FitError::Diverged {
            t: 0.5,
            params: vec![],
        };
        assert!(e
            .to_string()
            .starts_with("the state diverged at t = 0.5 with no parameters: "));
    }

    #[test]
    fn noise_not_carried_message_is_one_line() {
        let s = FitError::NoiseNotCarried.to_string();
        assert!(s.contains("starts (a state decays too fast over them): no"));
    }
}
