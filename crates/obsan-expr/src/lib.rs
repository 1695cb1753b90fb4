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
mod float_eval;
mod gauss;
mod gcd;
mod gcd_modular;
mod graph;
mod jet;
mod lower;
mod memo;
mod num;
mod parse;
mod poly;
mod print;
mod ratfun;
mod subst;
mod tanhalf;
pub mod tutorial;
mod undecided;

pub use budget::{
    budget_tripped, cancel_flag, cancel_requested, check_memory, with_cancel, within_thread_budget,
    within_thread_budget_keep, Budget, Limit, EXP_MAX, NUM_BITS_MAX, POW_MAX,
};
pub use eval::{
    degree_bounds, rational_angle, BadPoint, EvalQError, FpPoint, FrozenTape, Tape, UnboundSymbol,
};
pub use float_eval::FloatExpr;
pub use gcd::{gcd, EngineGcd, HeuristicGcd, ModularGcd, PolyGcd, PrsGcd};
pub use graph::{Id, Symbol};
pub use jet::{height_bounds, reached_states, Coord, LieJets, LieRow};
pub use lower::EngineError;
pub use memo::Ctx;
pub use num::{Fp, Int, SplitMix, P, Q};
pub use parse::{
    line_col, parse_ast, Ast, AstKind, BinOp, ParseError, Span, FUNCTIONS, MAX_DEPTH, MAX_DIGITS,
    MAX_HEIGHT,
};
pub use poly::{Mono, Poly, Var};
pub use print::{latex_name, within_text_cap};
pub use ratfun::RatFun;
pub use tanhalf::TanHalf;
