//! `obsan import sbml | petab | si-jl | strike-goldd --json`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `obsan import FORMAT SOURCE --json`: the models converted and the files written.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Import {
    /// The source format: `sbml`, `petab`, `si-jl` or `strike-goldd`.
    pub format: String,
    /// `--inputs-out`'s file, when written (an SBML model with known inputs); null otherwise.
    pub inputs_out: Option<String>,
    /// The known inputs the conversion made (an SBML `<piecewise>` of time becomes `u_ID`),
    /// in the order of the .sys.
    pub known_inputs: Vec<String>,
    /// The models converted, in the source's order.
    pub models: Vec<ImportedModel>,
    /// The models `si-jl --all` refused: each message names its file, line and column.
    pub refused: Vec<String>,
    /// The source file as given.
    pub source: String,
    /// `--values`' file, when written; null otherwise.
    pub values: Option<String>,
}

/// One converted model.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ImportedModel {
    /// SI.jl's model key (`Goodwin`); null for the other formats.
    pub key: Option<String>,
    /// Where the .sys was written; null when it is given in `text` (no --out).
    pub path: Option<String>,
    /// The `system` name of the .sys.
    pub system: String,
    /// The .sys text when it was not written (no --out); null otherwise.
    pub text: Option<String>,
}
