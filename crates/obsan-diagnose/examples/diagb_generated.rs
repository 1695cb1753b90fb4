//! The figures of docs/diagnose.md ("Generated candidates"): what the workflow
//! names on the simulated unicycle with and without generated candidates, over
//! `DIAGB_SEEDS` seeds (default 4). The simulation is the test suite's own
//! (tests/diagb_generated.rs), shared rather than copied.
//!
//! `cargo run --release -p obsan-diagnose --example diagb_generated`

#[path = "../tests/diagb_generated.rs"]
#[allow(dead_code, unused_imports)] // the tests' helpers and imports the figures do not use
mod diagb;

fn main() {
    diagb::naming_with_and_without_generation();
}
