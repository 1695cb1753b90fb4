//! `obsan simplify` and `obsan diff`.

use crate::cli::{DiffArgs, ExprArgs, LimitArgs, OutputArgs};
use crate::{json, Failure};
use obsan_expr::{Budget, Ctx, Id};
use obsan_model::ModelError;
use std::process::ExitCode;

/// Parse a command-line expression; errors point into it with a caret.
pub fn parse_arg(ctx: &mut Ctx, src: &str, what: &str) -> Result<Id, Failure> {
    ctx.parse(src).map_err(|e| {
        Failure(ModelError::at(what, src, e.span.start, e.span.end, e.message).to_string())
    })
}

fn emit(
    ctx: &mut Ctx,
    input: &str,
    id: Id,
    out: &OutputArgs,
    variable: Option<&str>,
) -> Result<ExitCode, Failure> {
    // Under the engine's budget: a huge expansion is an error, not minutes of work.
    let c = ctx
        .try_canon(id)
        .map_err(|limit| Failure(format!("<expression>: {limit}")))?;
    // A nonzero form proves "nonzero" only over independent atoms; a zero
    // form is a proof of zero whatever its atoms.
    let undecided = if c.is_zero() {
        Vec::new()
    } else {
        ctx.within_budget(|ctx| ctx.undecided_atom_texts(&c))
            .map_err(|limit| Failure(format!("<expression>: {limit}")))?
    };
    let decided = undecided.is_empty();
    if out.json {
        let (canonical, latex) = (ctx.ratfun_text(&c), ctx.ratfun_latex(&c));
        let is_zero = decided.then(|| c.is_zero());
        let input = input.to_string();
        match variable {
            None => crate::json::print(&json::Simplify {
                canonical,
                decided,
                exact: decided,
                input,
                is_zero,
                latex,
                undecided_atoms: undecided,
            })?,
            Some(v) => crate::json::print(&json::Diff {
                canonical,
                decided,
                exact: decided,
                input,
                is_zero,
                latex,
                undecided_atoms: undecided,
                variable: v.to_string(),
            })?,
        }
    } else {
        if out.latex {
            outln!("{}", ctx.ratfun_latex(&c));
        } else {
            outln!("{}", ctx.ratfun_text(&c));
        }
        if !decided {
            outln!("{}", not_decided_note(&undecided));
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The text line for a nonzero form over atoms that may be related.
pub fn not_decided_note(atoms: &[String]) -> String {
    format!(
        "not decided: whether this is zero (the form is nonzero, but its atoms {} may be related in ways the engine does not detect; docs/engine.md, \"Decided and not decided\")",
        atoms.join(", ")
    )
}

/// A context whose budget is the command line's.
fn budgeted_ctx(limit: &LimitArgs) -> Ctx {
    let mut ctx = Ctx::new();
    ctx.set_budget(Budget {
        max_terms: limit.max_terms,
        ..Budget::default()
    });
    ctx
}

pub fn simplify(a: &ExprArgs) -> Result<ExitCode, Failure> {
    let mut ctx = budgeted_ctx(&a.limit);
    let id = parse_arg(&mut ctx, &a.expr, "<expression>")?;
    emit(&mut ctx, &a.expr, id, &a.out, None)
}

pub fn diff(a: &DiffArgs) -> Result<ExitCode, Failure> {
    let valid = a
        .var
        .chars()
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && a.var.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
        && a.var != "pi";
    if !valid {
        return Err(Failure(format!(
            "'{}' is not a symbol name to differentiate by",
            a.var
        )));
    }
    let mut ctx = budgeted_ctx(&a.limit);
    let id = parse_arg(&mut ctx, &a.expr, "<expression>")?;
    let x = ctx.symbol(&a.var);
    let d = ctx.diff(id, x.var);
    emit(&mut ctx, &a.expr, d, &a.out, Some(&a.var))
}

/// Parse a command-line expression over a system's state and constants.
pub fn parse_arg_in(nf: &mut obsan_model::NormalForm, src: &str) -> Result<Id, Failure> {
    nf.parse_expr(src, false).map_err(|e| {
        Failure(ModelError::at("--mode", src, e.span.start, e.span.end, e.message).to_string())
    })
}
