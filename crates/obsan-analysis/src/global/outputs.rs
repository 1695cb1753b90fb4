//! Outputs read through a function of a rational form (docs/engine.md,
//! "Global identifiability", outputs through a function): the count sees
//! rational outputs only, so an output that is a one-to-one function of a
//! rational form is replaced by that form, and an angle output by its
//! tangent.
//!
//! - `c sqrt(u) + d` (`c != 0`, `d` numbers): `u` itself. The principal root
//!   is one-to-one on `u >= 0`, so the two outputs fix the same values.
//! - `c atan(u) + d`: `u` (atan is one-to-one on the reals).
//! - An angle `beta = sum c_j A_j + sum k_i theta_i + q pi` with `A_j` atan or
//!   atan2 atoms, integer `c_j, k_i` and `theta_i` symbols (a bearing
//!   `atan2(ly - y, lx - x) - theta`): `tan(beta) = sin(beta)/cos(beta)`,
//!   expanded by the engine. It fixes `beta` modulo pi only, so the counts
//!   over it are upper bounds for the real reading (a value with the same
//!   tangent may turn the bearing by pi). A global verdict (1 value) and
//!   a non-identifiable one stay exact: a subset of a one-point fibre has
//!   one point, and `tan` is a local diffeomorphism where `cos(beta) != 0`.
//!   A discrete symmetry of the tangent model is checked on `sin(beta)` and
//!   `cos(beta)` themselves (`sign`): `+1` keeps the reading, `-1` turns it
//!   by pi.

use super::types::err;
use crate::rank::AnalysisError;
use obsan_expr::{Ctx, Id, RatFun, Var};

/// How the count reads one output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OutputForm {
    /// As written (a rational function, angles in sin/cos).
    Direct,
    /// Through the argument of a one-to-one function (`"sqrt"`, `"atan"`).
    Argument(&'static str),
    /// An angle through its tangent: counts are upper bounds.
    Tangent,
}

/// An angle output's sine and cosine, as nodes, for the sign of a map.
#[derive(Clone)]
pub(super) struct AngleOutput {
    pub(super) sin: Id,
    pub(super) cos: Id,
}

/// The outputs as the count reads them.
pub(super) struct Prepared {
    pub(super) outputs: Vec<RatFun>,
    pub(super) forms: Vec<OutputForm>,
    pub(super) angles: Vec<AngleOutput>,
}

pub(super) fn prepare(ctx: &mut Ctx, outputs: &[(String, Id)]) -> Result<Prepared, AnalysisError> {
    let limit = |l: obsan_expr::Limit| err(format!("global: {l}"));
    let mut out = Prepared {
        outputs: Vec::with_capacity(outputs.len()),
        forms: Vec::with_capacity(outputs.len()),
        angles: Vec::new(),
    };
    for (name, id) in outputs {
        let r = ctx.try_canon(*id).map_err(limit)?;
        match classify(ctx, &r) {
            Shape::Other => {
                out.outputs.push(r);
                out.forms.push(OutputForm::Direct);
            }
            Shape::OneToOne(kind, arg) => {
                out.outputs.push(ctx.try_canon(arg).map_err(limit)?);
                out.forms.push(OutputForm::Argument(kind));
            }
            Shape::Angle => {
                let engine =
                    |e: obsan_expr::EngineError| err(format!("global: output {name}: {e}"));
                let sin = ctx.sin(*id).map_err(engine)?;
                let cos = ctx.cos(*id).map_err(engine)?;
                let s = ctx.try_canon(sin).map_err(limit)?;
                let c = ctx.try_canon(cos).map_err(limit)?;
                let inv = ctx.rf_inv(&c).ok_or_else(|| {
                    err(format!(
                        "global: output {name} has cos = 0 identically; its tangent is undefined"
                    ))
                })?;
                out.outputs.push(ctx.rf_mul(&s, &inv));
                out.forms.push(OutputForm::Tangent);
                out.angles.push(AngleOutput { sin, cos });
            }
        }
    }
    Ok(out)
}

enum Shape {
    Other,
    OneToOne(&'static str, Id),
    Angle,
}

/// The shape of a canonical output: linear in its atoms, with a constant
/// denominator.
fn classify(ctx: &Ctx, r: &RatFun) -> Shape {
    if !r.denominator().vars().is_empty() {
        return Shape::Other;
    }
    let mut funcs: Vec<Var> = Vec::new();
    let mut angle_atoms = 0usize;
    let mut symbols = 0usize;
    for (m, c) in r.numerator().terms() {
        let pairs: Vec<(Var, u32)> = m.iter().collect();
        match pairs[..] {
            [] => {}
            [(v, 1)] => {
                let integer = i64::try_from(c).is_ok();
                if ctx.sqrt_arg(v).is_some() {
                    funcs.push(v);
                } else if ctx.atan_args(v).is_some() {
                    funcs.push(v);
                    angle_atoms += usize::from(integer);
                } else if ctx.symbol_name(v).is_some() && integer {
                    symbols += 1;
                } else if ctx.leaf_text(v) == "pi" {
                    // q pi: a constant shift.
                } else {
                    return Shape::Other;
                }
            }
            _ => return Shape::Other,
        }
    }
    if funcs.is_empty() {
        return Shape::Other;
    }
    if funcs.len() == 1 && symbols == 0 {
        let v = funcs[0];
        if let Some(u) = ctx.sqrt_arg(v) {
            return Shape::OneToOne("sqrt", u);
        }
        if let Some((u, None)) = ctx.atan_args(v) {
            return Shape::OneToOne("atan", u);
        }
    }
    // An angle: every atom an atan/atan2 with an integer coefficient.
    if angle_atoms == funcs.len() && funcs.iter().all(|&v| ctx.atan_args(v).is_some()) {
        return Shape::Angle;
    }
    Shape::Other
}
