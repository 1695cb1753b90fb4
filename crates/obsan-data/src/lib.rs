//! obsan's dataset format (docs/data-format.md): per-trajectory CSV inputs and
//! outputs with optional JSON metadata, read from bytes with every rejection
//! naming file, row and column, and the MRCLAM importer. Text in, values out:
//! the binary does the file I/O.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod angle;
mod data;
mod error;
mod limits;
mod mrclam;

pub use angle::wrap;
pub use data::{
    add_derived_inputs, read_dataset, DataFile, DataWarning, Dataset, DatasetFiles, DatasetMeta,
    DatasetReader, ReadDataset, Series, Trajectory, TrajectoryFiles,
};
pub use error::{DataError, DataErrorKind, DerivedInputError};
pub use limits::{MAX_ABS_TIME, MAX_ABS_VALUE, MIN_OUTPUT_SAMPLES};
pub use mrclam::{
    convert as mrclam_convert, landmarks as mrclam_landmarks, model_text as mrclam_model_text,
    MrclamOutputs, MrclamText, WindowTruth, POSE_INTERVAL,
};
