//! Command-line arguments.

use clap::{Args, Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "obsan",
    version,
    about = "Exact nonlinear observability analysis and sensor self-calibration"
)]
#[command(after_help = "Exit codes: 0 success, 1 a check failed, 2 bad input or error.")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand)]
pub enum Command {
    /// Print a system in input-affine normal form: states, params, consts,
    /// inputs, f0, each f_i, outputs (after a restriction, if one is named).
    Show(ShowArgs),
    /// Print the exact canonical form of an expression.
    Simplify(ExprArgs),
    /// Print the derivative of an expression with respect to a symbol, in canonical form.
    Diff(DiffArgs),
}

/// Options shared by every command that reads a system.
#[derive(Args, Clone)]
pub struct SystemArgs {
    /// A system description in the .sys format.
    pub system: String,
    /// Apply the named input restriction declared in the file (e.g. `q`).
    #[arg(long = "input", value_name = "NAME")]
    pub restriction: Option<String>,
    /// Give a known constant a value, e.g. `--set q=0.9` (others stay generic).
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
}

#[derive(Args)]
pub struct OutputArgs {
    /// Machine-readable JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Formulas as LaTeX.
    #[arg(long, conflicts_with = "json")]
    pub latex: bool,
}

#[derive(Args)]
pub struct ShowArgs {
    #[command(flatten)]
    pub sys: SystemArgs,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct ExprArgs {
    /// An expression, e.g. 'sin(x)^2 + cos(x)^2'.
    pub expr: String,
    #[command(flatten)]
    pub out: OutputArgs,
}

#[derive(Args)]
pub struct DiffArgs {
    /// An expression.
    pub expr: String,
    /// The symbol to differentiate by.
    pub var: String,
    #[command(flatten)]
    pub out: OutputArgs,
}
