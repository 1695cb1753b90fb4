//! The binary's own JSON output types: what `--json` prints is these structs, serialised;
//! `obsan schema COMMAND` prints the JSON Schema derived from them, whose descriptions are
//! the fields' doc comments. The library crates' types stay free to change: the command code
//! copies them into these (the binary owns its output, docs/architecture.md).
//!
//! Fields are declared in alphabetical order, the order `serde_json::json!` objects print in,
//! so that typing a command kept its output byte for byte.

mod along;
mod analysis;
mod design;
mod diagnose;
mod docs;
mod estimate;
mod expr;
mod from_diagnosis;
pub use from_diagnosis::diagnose;
mod global;
mod import;
mod modes;
mod partial;
mod unknown;

pub use along::{Along, AlongDataset, AlongStretch, AlongSymmetry, AlongWindow};
pub use analysis::{
    Certification, Check, Constant, DecompositionCheck, Formula, ModeCheck, Rank, Show,
    SymCertificate, Symmetries, Verify,
};
pub use global::{
    Global, GlobalVariable, OutputFormJson, OutputOrder, SimulateSys, StatesAfterIoJson,
    VariableKind, Verdict,
};
pub use import::{Import, ImportedModel};
pub use modes::{
    DerivedMode, Modes, ModesCertificate, ModesDerived, ModesFullRank, ModesUnknownInputs,
    PassCheck, Reduced, ReducedDynamics, ReducedOutput, ReducedUnknownInput, VariableMode,
};
pub use unknown::{
    Martinelli, MartinelliStep, NamedOrder, RankUnknownInputs, SymmetriesUnknownInputs,
    UnknownInputStep, UnknownInputWord,
};

pub use design::{
    BasisWord, ConstantValue, Design, Experiment, Family, FamilyCombination, Inputs, KnownValue,
    RankAuto, RankKnown, RankStep, SensorCandidate, SensorSet, Sensors, SpecialValue,
};
pub use diagnose::{
    Candidate, Combination, CommonMode, Correlation, Diagnose, Fit, InputCheck, NameEstimateSd,
    NameValue, Named, Num, Refit, Residuals, Rival, StructureTest, TrajectoryCheck,
};
pub use docs::markdown;
pub use estimate::{
    finite, Calibrate, Crlb, EncoderNoise, Estimate, McCell, McMethod, McPaper, McTable, MlFit,
    ModesSd, Trajectory,
};
pub use expr::{Diff, Lie, LieDerivative, Simplify};
pub use partial::{Partial, PartialCell, PartialOutcome, PartialRun, PartialTable};

use schemars::{schema_for, Schema};
use std::process::ExitCode;

/// A command whose `--json` output is typed.
pub struct Typed {
    /// The name `obsan schema` takes.
    pub name: &'static str,
    /// The command line that prints it.
    pub command: &'static str,
    /// Its JSON Schema.
    pub schema: fn() -> Schema,
}

/// Every typed output, in the order `obsan schema --list` prints them.
pub const TYPED: &[Typed] = &[
    Typed {
        name: "show",
        command: "obsan show SYSTEM --json",
        schema: || schema_for!(Show),
    },
    Typed {
        name: "simplify",
        command: "obsan simplify EXPR --json",
        schema: || schema_for!(Simplify),
    },
    Typed {
        name: "diff",
        command: "obsan diff EXPR VAR --json",
        schema: || schema_for!(Diff),
    },
    Typed {
        name: "lie",
        command: "obsan lie SYSTEM --order K --json",
        schema: || schema_for!(Lie),
    },
    Typed {
        name: "rank",
        command: "obsan rank SYSTEM --json",
        schema: || schema_for!(Rank),
    },
    Typed {
        name: "rank-unknown-inputs",
        command: "obsan rank SYSTEM --json (a model with unknown inputs)",
        schema: || schema_for!(RankUnknownInputs),
    },
    Typed {
        name: "rank-along",
        command: "obsan rank SYSTEM --along DATASET --json",
        schema: || schema_for!(Along),
    },
    Typed {
        name: "rank-known",
        command: "obsan rank SYSTEM --known NAME=VALUE | --known-generic NAME --json",
        schema: || schema_for!(RankKnown),
    },
    Typed {
        name: "rank-auto",
        command: "obsan rank SYSTEM --experiments auto --json",
        schema: || schema_for!(RankAuto),
    },
    Typed {
        name: "symmetries",
        command: "obsan symmetries SYSTEM --json",
        schema: || schema_for!(Symmetries),
    },
    Typed {
        name: "symmetries-unknown-inputs",
        command: "obsan symmetries SYSTEM --json (a model with unknown inputs)",
        schema: || schema_for!(SymmetriesUnknownInputs),
    },
    Typed {
        name: "check",
        command: "obsan check SYSTEM --mode EXPR --json",
        schema: || schema_for!(Check),
    },
    Typed {
        name: "verify",
        command: "obsan verify FILE.dec --json",
        schema: || schema_for!(Verify),
    },
    Typed {
        name: "modes",
        command: "obsan modes SYSTEM --json",
        schema: || schema_for!(Modes),
    },
    Typed {
        name: "modes-unknown-inputs",
        command: "obsan modes SYSTEM --json (a model with unknown inputs)",
        schema: || schema_for!(ModesUnknownInputs),
    },
    Typed {
        name: "global",
        command: "obsan global SYSTEM --json",
        schema: || schema_for!(Global),
    },
    Typed {
        name: "simulate",
        command: "obsan simulate MODEL.sys --until T --every DT --json",
        schema: || schema_for!(SimulateSys),
    },
    Typed {
        name: "import",
        command: "obsan import sbml|petab|si-jl|strike-goldd SOURCE --json",
        schema: || schema_for!(Import),
    },
    Typed {
        name: "diagnose",
        command: "obsan diagnose MODEL DATA --json (and the report's diagnosis.json)",
        schema: || schema_for!(Diagnose),
    },
    Typed {
        name: "calibrate",
        command: "obsan calibrate DATASET --json",
        schema: || schema_for!(Calibrate),
    },
    Typed {
        name: "crlb",
        command: "obsan crlb [DATASET] --json",
        schema: || schema_for!(Crlb),
    },
    Typed {
        name: "montecarlo",
        command: "obsan montecarlo --json (and obsan montecarlo merge PARTS --json)",
        schema: || schema_for!(Vec<McTable>),
    },
    Typed {
        name: "montecarlo-shard",
        command: "obsan montecarlo --shard K/N --json",
        schema: || schema_for!(Partial),
    },
    Typed {
        name: "design",
        command: "obsan design SYSTEM --json",
        schema: || schema_for!(Design),
    },
];

/// Commands with `--json` whose output is still built ad hoc (to be typed), and commands
/// without `--json`.
pub const UNTYPED: &[(&str, &str)] = &[
    (
        "simulate",
        "no --json without MODEL.sys: writes a dataset folder",
    ),
    ("import mrclam", "no --json: writes a dataset folder"),
];

/// The schema of a typed output, by name (`montecarlo merge` is `montecarlo`'s).
pub fn schema(name: &str) -> Option<Schema> {
    let name = if name == "montecarlo-merge" {
        "montecarlo"
    } else {
        name
    };
    TYPED.iter().find(|t| t.name == name).map(|t| (t.schema)())
}

/// Print a typed output as the commands print JSON: pretty, one value, a newline.
pub(crate) fn print<T: serde::Serialize>(v: &T) -> Result<(), crate::Failure> {
    outln!("{}", serde_json::to_string_pretty(v)?);
    Ok(())
}

/// `obsan schema`.
pub(crate) fn schema_cmd(a: &crate::cli::SchemaArgs) -> Result<ExitCode, crate::Failure> {
    if a.list {
        for t in TYPED {
            outln!("{:<18} {}", t.name, t.command);
        }
        for (name, note) in UNTYPED {
            outln!("{name:<18} {note}");
        }
    } else if a.markdown {
        out!("{}", markdown());
    } else {
        let name = a.command.as_deref().unwrap_or_default();
        let s = schema(name).ok_or_else(|| {
            let names: Vec<&str> = TYPED.iter().map(|t| t.name).collect();
            crate::Failure(format!(
                "no schema for '{name}': the typed outputs are {} (obsan schema --list)",
                names.join(", ")
            ))
        })?;
        print(&s)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// One symmetry vector as JSON: per state variable, its component's text
/// and LaTeX.
pub fn vector(
    nf: &obsan_model::NormalForm,
    v: &[obsan_expr::RatFun],
) -> std::collections::BTreeMap<String, Formula> {
    nf.state
        .iter()
        .zip(v)
        .map(|(n, e)| {
            let f = Formula {
                latex: nf.ctx.ratfun_latex(e),
                text: nf.ctx.ratfun_text(e),
            };
            (n.clone(), f)
        })
        .collect()
}
