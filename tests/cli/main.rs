//! The one integration-test target: runs the `obsan` binary as a user would.

mod analysis;
mod calibrate;
mod classic;
mod design;
mod diagnose;
mod diagnose_vicon;
mod experiments;
mod expr;
mod feedthrough;
mod global;
mod global_io;
mod global_lie;
mod global_maps;
mod import;
mod jet_decompositions;
mod json_schema;
mod measured_inputs;
mod modes;
mod modes_closure;
mod montecarlo;
mod qroot;
mod sbml_piecewise;
mod show;
mod simulate;
mod simulate_time;
mod suite;
#[path = "../../benches/suite_entries.rs"]
mod suite_entries;
mod surface;
mod symmetry_invariance;
mod trust;
mod tutorial;
mod unknown_input_jet_modes;
mod unknown_input_jets;
mod unknown_inputs;
mod util;
