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

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod calib;
mod calibrate;
mod cekf;
mod circle;
mod data;
mod fit;
mod montecarlo;
mod mrclam;
mod noise;
mod predict;
mod rng;
mod sim;
mod whiten;

pub use calib::{
    arc_data, av_from_state, combine, start_state, Calibration, Metric, Modes, PARAMS,
};
pub use calibrate::{
    calib_predictor, calibrate, dataset_crlb, figure_curves, CalibrateOptions, CalibrationReport,
    CekfInit, DatasetCrlb, FigureCurves, Method, TrajectoryEstimate, CALIB_SYS,
};
pub use cekf::{cekf, cekf_start, CekfResult};
pub use circle::{det, det_at, ls, weights, ArcData, Closed, Degenerate, Det, LsFit};
pub use data::{
    add_derived_inputs, read_dataset, DataError, DataFile, DataWarning, Dataset, DatasetFiles,
    DatasetMeta, ReadDataset, Series, Trajectory, TrajectoryFiles, MAX_ABS_TIME, MAX_ABS_VALUE,
    MIN_OUTPUT_SAMPLES,
};
pub use fit::{crlb, fit, FitOptions, FitResult, FitTrajectory};
pub use montecarlo::{
    crlb_sd, kc_from_av, run_cell, table, Cell, CellResult, McMethod, MethodStats, Table,
    MODE_COLUMNS, PARAM_COLUMNS,
};
pub use mrclam::{
    convert as mrclam_convert, landmarks as mrclam_landmarks, model_text as mrclam_model_text,
    MrclamOutputs, MrclamText, WindowTruth, POSE_INTERVAL,
};
pub use noise::{estimate_noise, NoiseEstimate, NoiseOptions};
pub use predict::{Integration, Prediction, Predictor};
pub use rng::Rng;
pub use sim::{
    bearing, simulate, wrap, Effects, Robot, SimOptions, SpeedProfile, TrajectoryTruth, Truth,
};
pub use whiten::Whitener;
