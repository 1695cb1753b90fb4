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

mod decomp;
mod derive;
mod modes;
mod rank;
pub mod structure;
mod sym_recon;
mod symmetry;

pub use decomp::{verify_decomposition, Check, Decomposition};
pub use derive::{
    derive_modes, verify_derivation, Derivation, DeriveOptions, DerivedMode, ModeKind,
};
pub use modes::{check_modes, ModeCheck, ModeReport};
pub use rank::{rank, rank_symbolic, AnalysisError, Fields, LieWord, RankOptions, RankReport};
pub use structure::SymmetryKind;
pub use sym_recon::{certify_symmetries, RandomCheck, CHECK_POINTS, CHECK_PRIMES};
pub use symmetry::{
    canonical_lie, determinant, symmetries, symmetries_with, Certificate, Route, SymmetryOptions,
    SymmetryReport,
};

use obsan_expr::Id;
use obsan_model::NormalForm;

/// Names and vectors of the fields: `f0` when the drift is not zero, then one per input.
fn field_names(nf: &mut NormalForm) -> (Vec<String>, Vec<Vec<Id>>) {
    let mut names = Vec::new();
    let mut vectors = Vec::new();
    if !nf.drift_is_zero() {
        names.push("f0".to_string());
        vectors.push(nf.f0.clone());
    }
    for (i, f) in nf.fields.iter().enumerate() {
        names.push(nf.inputs[i].clone());
        vectors.push(f.clone());
    }
    // A delay tau (inputs u(t - tau)) to first order: u - tau du/dt, the rates
    // du/dt being further free inputs with fields -tau f_i.
    if let Some(d) = nf.delay {
        #[allow(clippy::expect_used)]
        // normal_form puts the delay param in the state and the context
        let tau = nf.ctx.lookup(&nf.state[d]).expect("delay param").id;
        let minus_tau = nf.ctx.neg(tau);
        for i in 0..nf.fields.len() {
            let v: Vec<Id> = nf.fields[i]
                .clone()
                .into_iter()
                .map(|x| nf.ctx.mul(&[minus_tau, x]))
                .collect();
            names.push(format!("rate_{}", nf.inputs[i]));
            vectors.push(v);
        }
    }
    (names, vectors)
}
