//! The paper's calibration (Martinelli 2011, sections V–VI): the simulator of
//! section VI-A, the estimators DET, LS (circle.rs, eqs. 37–38 and the
//! sign-free closed form of ERRATA.md), section V-C's combination, the CEKF of
//! Appendix D and joint maximum likelihood through obsan-fit, end to end in
//! [`calibrate`]; the Monte Carlo of Tables IV–VII.
//!
//! ```
//! use obsan_calib::{simulate, SimOptions};
//! let (data, truth) = simulate(&SimOptions { q: vec![0.0], ..SimOptions::default() }).unwrap();
//! assert_eq!(data.trajectories.len(), 1);
//! assert!((truth.xi - 0.297 / 0.485).abs() < 1e-12);
//! ```

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod calib;
mod calibrate;
mod cekf;
mod circle;
#[cfg(test)]
mod circle_tests;
mod error;
mod montecarlo;
mod sim;

pub use calib::{Calibration, Metric, PARAMS};
pub use calibrate::{
    calib_predictor, calibrate, circle_modes, CalibrateOptions, CalibrationReport, CekfInit,
    EncoderNoise, FigureCurves, Method, TrajectoryEstimate,
};
pub use circle::{ArcData, Closed, Det};
pub use error::CalibError;
pub use montecarlo::{
    merge_runs, run_cell, run_runs, shard_runs, summarize, table, Cell, CellBounds, CellResult,
    McMethod, MethodStats, MontecarloError, RunOutcome, RunRecord, Table,
};
pub use sim::{simulate, Effects, Robot, SimOptions, SpeedProfile, TrajectoryTruth, Truth};
