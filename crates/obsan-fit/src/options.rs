//! What a fit is given: the trajectories (data borrowed) and the options,
//! every tolerance explicit.

use crate::predict::Predictor;
use obsan_data::{Dataset, Series};

/// One trajectory to fit.
pub struct FitTrajectory<'a> {
    /// For messages.
    pub name: &'a str,
    pub inputs: &'a Series,
    pub outputs: &'a Series,
    /// Values of the predictor's constants (e.g. q).
    pub consts: Vec<f64>,
}

impl<'a> FitTrajectory<'a> {
    /// Every trajectory of a dataset, with the predictor's constants from
    /// each `meta.json` (0 where absent: a constant the dynamics do not use).
    pub fn all(p: &Predictor, data: &'a Dataset) -> Vec<FitTrajectory<'a>> {
        data.trajectories
            .iter()
            .map(|t| FitTrajectory {
                name: &t.name,
                inputs: &t.inputs,
                outputs: &t.outputs,
                consts: p
                    .consts
                    .iter()
                    .map(|c| t.meta.get(c).copied().unwrap_or(0.0))
                    .collect(),
            })
            .collect()
    }
}

/// Options of the fit; every tolerance explicit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost is below this.
    pub cost_tolerance: f64,
    /// Or when the undamped Gauss-Newton step from the current estimate is
    /// shorter than this many of its standard deviations
    /// (`sqrt(g^T (J^T J)^-1 g)`, `g = J^T r`, residuals normalised by
    /// sigma): the estimate would move by much less than its uncertainty.
    /// 0 disables.
    pub step_tolerance: f64,
    /// Noise standard deviation of each output (residuals are divided by it).
    pub sigma: Vec<f64>,
    /// Longest integration step (s) over merged input rows; 0 = one step per
    /// input row (see [`Integration::max_step`]).
    pub max_step: f64,
    /// Noise of the measured inputs (see [`Integration::input_noise`]);
    /// when given the fit is generalised least squares: the residuals of a
    /// trajectory are whitened by the Cholesky factor of their covariance
    /// `I + A M A^T` (output noise plus the integrated input noise,
    /// linearised), computed at the start, at the first estimate and at the
    /// final one (where the covariance and the cost are taken).
    pub input_noise: Option<Vec<f64>>,
}
