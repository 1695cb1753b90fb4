//! obsan's generic fitter for any `.sys` model: prediction along measured
//! inputs with exact sensitivities, maximum likelihood over shared params and
//! per-trajectory initial states, generalised least squares under integrated
//! input noise, restricted-ML noise levels, the CRLB and cluster-robust sds.
//! Nothing here knows the paper's calibration model.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod error;
mod fit;
mod lsq;
mod noise;
mod normal;
mod options;
mod predict;
mod rng;
mod whiten;

pub use error::FitError;
pub use fit::{crlb, fit, FitResult};
pub use lsq::{minimise, LmOptions, LmResult};
pub use noise::{
    estimate_noise, input_noise_from_samples, NoiseEstimate, NoiseOptions, SampledNoise,
};
pub use normal::MAX_FIT_PARAMS;
pub use options::{FitOptions, FitTrajectory};
pub use predict::{Integration, Measured, Prediction, Predictor};
pub use rng::{box_muller, Rng};
pub use whiten::Whitener;
