//! The reader's limits, at the bottom of the module graph: data.rs enforces them
//! and error.rs names them in its messages, neither importing the other for them.

/// The largest magnitude of a value in a CSV file (docs/data-format.md):
/// far outside any physical range of the models' inputs and outputs (SI
/// units), and small enough that sums of squares stay far from overflow.
pub const MAX_ABS_VALUE: f64 = 1e9;
/// The largest magnitude of a time (s): room for Unix timestamps.
pub const MAX_ABS_TIME: f64 = 1e10;

/// The fewest output samples a trajectory may have.
pub const MIN_OUTPUT_SAMPLES: usize = 10;
