//! obsan's system model: the `.sys` text format (see `docs/sys-format.md`),
//! the checks that make a description an input-affine system, and its normal
//! form `S' = f0(S) + sum_i f_i(S) u_i`, `y = h(S)`, optionally after an input
//! restriction and with known constants given values.
//!
//! ```
//! let src = "system demo\nstate x\ninput u\nx' = -x + u\noutput y = x^2\n";
//! let sys = obsan_model::System::parse(src, "demo.sys").unwrap();
//! let mut nf = sys.normal_form(None, &[]).unwrap();
//! assert_eq!(nf.ctx.to_text(nf.f0[0]), "-x");
//! assert_eq!(nf.ctx.to_text(nf.fields[0][0]), "1");
//! ```

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod effect;
mod error;
mod experiment;
mod measured;
mod normal;
mod sys;
mod unit;

pub use effect::{substitute as substitute_names, Effect, EffectLibrary};
pub use error::{decode_text, normalize_text, ModelError};
pub use experiment::{experiment_name, Experiment};
pub use measured::DERIVATIVE_MARK;
pub use normal::NormalForm;
pub use sys::{Decl, Kind, Restriction, Start, System, TIME};
pub use unit::{Unit, UnitDecl, MAX_UNIT_EXPONENT};
