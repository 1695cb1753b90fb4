//! `obsan simplify`, `obsan diff` and `obsan lie`.

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `obsan simplify EXPR --json`: the exact canonical form of an expression.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Simplify {
    /// The canonical form as text: a reduced quotient of polynomials in the atoms.
    pub canonical: String,
    /// Whether `is_zero` is decided: false when the form is nonzero but its atoms may be related
    /// in ways the engine does not detect (a zero form is always decided).
    pub decided: bool,
    /// The same as `decided`: the answer is exact when it is decided.
    pub exact: bool,
    /// The expression as given on the command line.
    pub input: String,
    /// Whether the expression is identically zero; null when not decided.
    pub is_zero: Option<bool>,
    /// The canonical form as LaTeX.
    pub latex: String,
    /// The atoms (e.g. `log(x*y)`, `log(x)`) that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
}

/// `obsan diff EXPR VAR --json`: the derivative in canonical form.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Diff {
    /// The derivative's canonical form as text.
    pub canonical: String,
    /// Whether `is_zero` is decided (as for simplify).
    pub decided: bool,
    /// The same as `decided`.
    pub exact: bool,
    /// The expression as given on the command line (before differentiation).
    pub input: String,
    /// Whether the derivative is identically zero; null when not decided.
    pub is_zero: Option<bool>,
    /// The derivative's canonical form as LaTeX.
    pub latex: String,
    /// The atoms that may be related; empty when decided.
    pub undecided_atoms: Vec<String>,
    /// The symbol differentiated by.
    pub variable: String,
}

/// `obsan lie SYSTEM --order K --json`: the Lie derivatives of the outputs.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Lie {
    /// Always true: every Lie derivative is an exact canonical form.
    pub exact: bool,
    /// Every Lie word up to the order, outputs first, then by order.
    pub lie_derivatives: Vec<LieDerivative>,
    /// The input restriction applied (`--input`), or null.
    pub restriction: Option<String>,
    /// The system's name (its `system` statement).
    pub system: String,
}

/// One Lie derivative `L_a L_b h`.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct LieDerivative {
    /// Its canonical form as LaTeX.
    pub latex: String,
    /// The Lie word, e.g. `L_f0 L_f1 h1` (L_a L_b h = L_a(L_b(h))).
    pub lie_derivative: String,
    /// The number of fields in the word (0: the output itself).
    pub order: usize,
    /// Its canonical form as text.
    pub text: String,
}
