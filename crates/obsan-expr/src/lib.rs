//! obsan's exact symbolic engine.
//!
//! Expressions live in a [`Ctx`]: a flat arena with one node per distinct
//! subexpression, children before parents. Functions are lowered to *leaves*
//! as they are built (per-symbol `sin`/`cos`/`exp`, and atoms for `atan`,
//! `atan2`, `log`, `sqrt` and other arguments), so that every expression is an
//! element of a field of rational functions in the leaves with the relations
//! `sin^2 + cos^2 = 1` and `sqrt(u)^2 = u`. [`Ctx::canon`] gives its exact
//! canonical form ([`RatFun`]); equality and zero-testing are exact.
//!
//! ```
//! use obsan_expr::Ctx;
//! let mut ctx = Ctx::new();
//! let e = ctx.parse("sin(g - p)*cos(p) + cos(g - p)*sin(p) - sin(g)").unwrap();
//! assert!(ctx.is_identically_zero(e));
//! let x = ctx.symbol("x");
//! let f = ctx.parse("atan2(x, 1)").unwrap();
//! let d = ctx.diff(f, x.var);
//! assert_eq!(ctx.to_text(d), "1/(x^2 + 1)");
//! ```
//!
//! See `docs/engine.md` in the repository for the mathematics and the
//! limitations, and the [`tutorial`] module for a guided tour.

#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod budget;
mod canon;
mod diff;
mod eval;
mod ext;
mod float_eval;
mod gauss;
mod gcd;
mod gcd_modular;
mod graph;
mod jet;
mod kummer;
mod lower;
mod memo;
mod num;
mod parse;
mod poly;
mod print;
mod ratfun;
mod root;
mod subst;
mod tanhalf;
pub mod tutorial;
mod undecided;
mod written;

// The root keeps what most users need; the rest is behind public modules, so the root
// stays small (at most 40 names, checked by scripts/module_dag.py --exports).
pub use budget::{cancel_flag, cancel_requested, with_cancel, within_thread_budget, Budget, Limit};
pub use eval::{FrozenTape, Tape};
pub use float_eval::FloatExpr;
pub use graph::{Id, Symbol};
pub use lower::EngineError;
pub use memo::Ctx;
pub use num::{Fp, FpEchelon, FpField, Int, SplitMix, P, Q};
pub use parse::{line_col, parse_ast, Ast, AstKind, BinOp, ParseError, Span, FUNCTIONS};
pub use poly::{Mono, Poly, Var};
pub use ratfun::RatFun;
pub use tanhalf::TanHalf;

/// The engine's limits: the hard caps of the canonical form and the parser, and the
/// per-thread budget's less common entry points ([`crate::Budget`] and [`crate::Limit`] are at the root).
pub mod limits {
    pub use crate::budget::{
        budget_reason, budget_tripped, check_memory, within_thread_budget_keep, EXP_MAX,
        NUM_BITS_MAX, POW_MAX,
    };
    pub use crate::parse::{MAX_DEPTH, MAX_DIGITS, MAX_HEIGHT};
}

/// Exact and modular evaluation: points of F_p, rational evaluation and its errors,
/// degree bounds for the Schwartz–Zippel lemma.
pub mod evaluate {
    pub use crate::eval::{
        degree_bounds, rational_angle, BadPoint, EvalQError, FpPoint, UnboundSymbol,
    };
    pub use crate::ext::{Ext, ExtField, ExtPoint, EXT_MAX};
}

/// Multivariate polynomial gcds: the engine's choice ([`crate::gcds::gcd`]) and each method
/// behind the `PolyGcd` trait (for tests and comparisons).
pub mod gcds {
    pub use crate::gcd::{gcd, EngineGcd, HeuristicGcd, ModularGcd, PolyGcd, PrsGcd};
}

/// Lie derivatives along words of fields and their gradients at an F_p point, by
/// truncated Taylor jets on the expression DAG.
pub mod lie {
    pub use crate::jet::{height_bounds, reached_states, Coord, LieJets, LieRow};
}

/// Text output helpers: LaTeX names and the cap on printed text.
pub mod text {
    pub use crate::print::{latex_name, within_text_cap};
}
