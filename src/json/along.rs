//! `obsan rank SYSTEM --along DATASET --json`: observability along a dataset's truth
//! (docs/experiments.md). Every float is a number or null (not finite: JSON has no NaN).

use super::Num;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `obsan rank SYSTEM --along DATASET --json`: the numerical rank window by window.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Along {
    /// The dataset folder as given.
    pub along: String,
    /// The rank of the whole dataset's columns.
    pub dataset: AlongDataset,
    /// The relative tolerance of an input relation.
    pub input_rel_tol: Num,
    /// The number of analysed variables.
    pub n: usize,
    /// The floor of the rank tolerance (floating-point rounding).
    pub rounding_floor: Num,
    /// The analysed variables.
    pub state: Vec<String>,
    /// The degenerate stretches: consecutive windows below full rank.
    pub stretches: Vec<AlongStretch>,
    /// The system's name.
    pub system: String,
    /// The safety factor of the rank tolerance.
    pub tolerance_safety: Num,
    /// The window length (s).
    pub window: Num,
    /// Each window.
    pub windows: Vec<AlongWindow>,
}

/// One window.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlongWindow {
    /// The condition number, or null.
    pub condition: Num,
    /// The input relations the recorded inputs satisfy in it.
    pub input_relations: Vec<String>,
    /// A basis of the numerical kernel.
    pub kernel: Vec<Vec<Num>>,
    /// The numerical rank.
    pub rank: usize,
    /// Rows of the stacked gradients.
    pub rows: usize,
    /// The singular values.
    pub singular_values: Vec<Num>,
    /// Its start (s).
    pub t0: Num,
    /// Its end (s).
    pub t1: Num,
    /// The rank tolerance.
    pub tolerance: Num,
    /// The trajectory.
    pub trajectory: String,
    /// The weakest direction.
    pub weakest: Vec<Num>,
}

/// A degenerate stretch.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlongStretch {
    /// The input relations of its first window.
    pub input_relations: Vec<String>,
    /// The directions lost, in echelon form.
    pub lost: Vec<Vec<Num>>,
    /// Its rank.
    pub rank: usize,
    /// The symmetries of the restricted system it matches.
    pub symmetry: AlongSymmetry,
    /// Its start (s).
    pub t0: Num,
    /// Its end (s).
    pub t1: Num,
    /// The trajectory.
    pub trajectory: String,
    /// How many windows.
    pub windows: usize,
}

/// The kernel of a stretch against the restricted system's symmetries.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlongSymmetry {
    /// The largest principal angle allowed for a match (degrees).
    pub angle_bound_deg: Num,
    /// The principal angles (degrees).
    pub angles_deg: Vec<Num>,
    /// The symmetries are exact.
    pub exact: bool,
    /// The largest angle from the kernel to the symmetries (degrees).
    pub kernel_to_symmetries_deg: Num,
    /// The kernel and the symmetries span the same space.
    pub matches: bool,
    /// The rank of the restricted system.
    pub restricted_rank: usize,
    /// The largest angle from the symmetries to the kernel (degrees).
    pub symmetries_to_kernel_deg: Num,
    /// The symmetry vectors at the stretch's states.
    pub vectors: Vec<Vec<Num>>,
}

/// The rank of the dataset's columns.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct AlongDataset {
    /// The columns.
    pub columns: Vec<String>,
    /// A basis of the numerical kernel.
    pub kernel: Vec<Vec<Num>>,
    /// The number of columns.
    pub n: usize,
    /// The numerical rank.
    pub rank: usize,
    /// The singular values.
    pub singular_values: Vec<Num>,
    /// The rank tolerance.
    pub tolerance: Num,
}
