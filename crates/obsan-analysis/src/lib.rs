//! obsan's observability analysis of an input-affine system in normal form:
//! the rank test, continuous symmetries (Definition 2 of Martinelli 2011),
//! observable-mode checks (eq. 11) and local decompositions (eq. 9).
//!
//! ```
//! let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../systems/localization.sys")).unwrap();
//! let sys = obsan_model::System::parse(&src, "localization.sys").unwrap();
//! let mut nf = sys.normal_form(None, &[]).unwrap();
//! let r = obsan_analysis::rank(&mut nf, Default::default()).unwrap();
//! assert_eq!((r.rank, r.n), (2, 3));
//! ```

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod along;
mod along_linalg;
mod along_report;
mod along_sym;
mod decided;
mod decomp;
mod decomp_jets;
mod derive;
mod design;
mod experiments;
mod fields;
mod fp_linalg;
mod global;
mod modes;
mod rank;
mod rank_roots;
mod reach;
pub mod structure;
mod sym_blocks;
mod sym_recon;
mod sym_report;
mod symmetry;
mod unknown_input;
mod unknown_input_feedthrough;
mod unknown_input_jet_view;
mod unknown_input_jets;
mod unknown_input_joint;
mod unknown_input_martinelli;
mod unknown_input_modes;
mod unknown_input_roots;
mod unknown_input_symmetry;

// The root keeps what most users need (rank, symmetries, modes, decompositions); the
// other questions are behind public modules, so the root stays small (at most 40 names,
// checked by scripts/module_dag.py --exports).
pub use decomp::{verify_decomposition, verify_decomposition_with, Check, Decomposition};
pub use derive::{
    derive_modes, verify_derivation, Derivation, DeriveOptions, DerivedMode, ModeKind,
};
pub use modes::{check_modes, ModeCheck, ModeReport};
pub use rank::{rank, rank_symbolic, AnalysisError, Fields, LieWord, RankOptions, RankReport};
pub use reach::{reached_variables, restrict_to_reached, Reached};
pub use structure::SymmetryKind;
pub use sym_blocks::rank_by_blocks;
pub use symmetry::{
    canonical_lie, determinant, symmetries, symmetries_with, Certificate, Route, SymmetryOptions,
    SymmetryReport,
};

/// The rank along a recorded trajectory (`obsan along`): windows of a dataset, the rank
/// on each, and whether a symmetry survives the inputs actually applied.
pub mod trajectory {
    pub use crate::along::{
        generic_consts, AlongOptions, AlongTrajectory, AlongWindow, ROUNDING_FLOOR, TOL_SAFETY,
    };
    pub use crate::along_report::{along, AlongReport, AlongStretch, DatasetRank};
    pub use crate::along_sym::{InputSpan, SymmetryMatch, INPUT_REL_TOL};
}

/// Which inputs or outputs to add so that a system becomes observable (`obsan design`).
pub mod sensor_design {
    pub use crate::design::{
        design_inputs, design_outputs, Candidate, CandidateEffect, Combination, DesignOptions,
        DesignReport, DesignSet, FamilyReport, InputDesignReport,
    };
}

/// Several experiments at once: the rank with known values, and the search for the
/// experiments that make a system observable (`obsan experiments`).
pub mod multi_experiment {
    pub use crate::experiments::{
        experiments_auto, rank_known, AutoOptions, AutoReport, Known, KnownOptions, KnownReport,
        SpecialValue,
    };
}

/// Global (not only local) identifiability by Gröbner bases (`obsan global`).
pub mod global_id {
    pub use crate::global::{
        global_identifiability, DiscreteMap, GlobalOptions, GlobalReport, GlobalVariable,
        Identifiability, IoSize, OutputForm, Route, StatesAfterIo,
    };
}

/// Observability with unknown inputs: the extended rank test, Martinelli's algorithm and
/// the symmetries of a system with unknown inputs.
pub mod unknown_inputs {
    pub use crate::decomp::combination_checks;
    pub use crate::decomp_jets::jet_check_text;
    pub use crate::unknown_input::{
        unknown_input_rank, OrderStep, UnknownInputOptions, UnknownInputReport,
    };
    pub use crate::unknown_input_feedthrough::unknown_input_symmetries;
    pub use crate::unknown_input_jet_view::JetName;
    pub use crate::unknown_input_martinelli::{martinelli, MartinelliReport, MartinelliStep};
    pub use crate::unknown_input_modes::{
        inputs_driving_modes, unknown_input_modes, unknown_input_view, unknown_input_view_jets,
        ReducedInput, UnknownInputModes,
    };
    pub use crate::unknown_input_symmetry::UnknownInputSymmetries;
}

/// Certificates: the random-point check of reconstructed symmetries, and the atoms whose
/// independence the engine cannot prove.
pub mod certify {
    pub use crate::decided::undecided_atoms_of;
    pub use crate::sym_recon::{certify_symmetries, RandomCheck, CHECK_POINTS, CHECK_PRIMES};
}
