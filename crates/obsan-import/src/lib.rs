//! obsan's importers: foreign model text in, `.sys` text out (docs/import.md):
//! StructuralIdentifiability.jl's `@ODEmodel`, SBML, PEtab and STRIKE-GOLDD's
//! MATLAB model files.
//!
//! The crate does no file I/O and depends on no other obsan crate: it only
//! translates. The `obsan import` commands read the file, call a translator
//! here, and let `obsan-model` read the produced `.sys` text, mapping any
//! error back to the foreign file through [`Converted::line_map`].
//!
//! ```
//! let src = "ode = @ODEmodel(x'(t) = -a * x(t) + u(t), y(t) = x(t))";
//! let models = obsan_import::si_jl_models(src).unwrap();
//! let c = obsan_import::si_jl_convert(src, &models[0], "m.jl").unwrap();
//! assert!(c.sys_text.contains("x' = -a*x + u"));
//! ```

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod error;
mod ex;
mod infix;
mod julia;
mod matlab;
mod matlab_exec;
mod petab;
mod sbml;
mod sbml_inputs;
mod sbml_math;
mod sbml_pw;
mod sbml_values;
mod yaml;

pub use error::ImportError;
pub use julia::{si_jl_convert, si_jl_models, SiJlModel};
pub use matlab::strike_goldd_to_sys;
pub use petab::{petab_files, petab_to_sys, PetabError, PetabFile, PetabFiles, PetabTexts};
pub use sbml::sbml_to_sys;
pub use sbml_inputs::{sbml_inputs, SbmlInputs};
pub use sbml_values::sbml_values;

/// A translated model: its `.sys` text and, for each `.sys` line that came
/// from the foreign file, that place (1-based line and column there).
#[derive(Clone, Debug)]
pub struct Converted {
    /// A name usable as a file stem (the model's key in the source).
    pub name: String,
    pub sys_text: String,
    /// `(sys line, source line, source column)`, sorted by sys line.
    pub line_map: Vec<(usize, usize, usize)>,
    /// The `.sys` lines whose place in `line_map` is in a second source file
    /// (PEtab's observable table) rather than the main one (the SBML model).
    pub table_lines: Vec<usize>,
}

impl Converted {
    /// The source place of `.sys` line `line`, if it came from one.
    pub fn source_of(&self, line: usize) -> Option<(usize, usize)> {
        self.line_map
            .iter()
            .find(|(s, _, _)| *s == line)
            .map(|&(_, l, c)| (l, c))
    }
}
