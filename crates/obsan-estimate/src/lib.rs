//! obsan's calibration estimator (sections V–VI of Martinelli 2011): the
//! dataset format and the paper's simulator. The estimators (DET, LS, CEKF,
//! joint maximum likelihood) build on these.
//!
//! ```
//! use obsan_estimate::{simulate, SimOptions};
//! let (data, truth) = simulate(&SimOptions { q: vec![0.0], ..SimOptions::default() }).unwrap();
//! assert_eq!(data.trajectories.len(), 1);
//! assert!((truth.xi - 0.297 / 0.485).abs() < 1e-12);
//! ```

mod data;
mod fit;
mod predict;
mod rng;
mod sim;

pub use data::{DataError, Dataset, DatasetMeta, Series, Trajectory, MIN_OUTPUT_SAMPLES};
pub use fit::{fit, FitOptions, FitResult, FitTrajectory};
pub use predict::Predictor;
pub use rng::Rng;
pub use sim::{
    bearing, simulate, wrap, Effects, Robot, SimOptions, SpeedProfile, TrajectoryTruth, Truth,
};
