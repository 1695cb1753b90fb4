//! Trig models counted in the tangent half-angle view (docs/engine.md,
//! "Global identifiability", trig models): an angle `theta` (a state or a
//! parameter) whose only occurrences are `sin`/`cos` leaves of unit 1 becomes
//! `t = tan(theta/2)`, with `sin theta = 2t/(1 + t^2)`,
//! `cos theta = (1 - t^2)/(1 + t^2)` (the engine's own view, obsan-expr's
//! `to_tan_half`) and, for a state, `t' = (1 + t^2)/2 theta'`. The map
//! `theta -> t` is a bijection from the angles modulo 2 pi (minus
//! `theta = pi`) to the line, so the count of `t` values is the count of
//! angles modulo 2 pi, and the variable keeps the angle's name.

use super::types::err;
use crate::rank::AnalysisError;
use obsan_expr::{Ctx, Int, Poly as ZPoly, RatFun, Var, Q};

/// The half-angle view of the forms in place: each angle variable in `vars`
/// replaced by its `t`, and `rhs[s]` of an angle state multiplied by
/// `(1 + t^2)/2`. Returns, per entry of `vars`, whether it became an angle.
/// `vars` are the dynamic states (the first `rhs.len()`) then the params.
pub(super) fn half_angle_view(
    ctx: &mut Ctx,
    vars: &mut [Var],
    rhs: &mut [RatFun],
    outputs: &mut [RatFun],
) -> Result<Vec<bool>, AnalysisError> {
    let mut angle = vec![false; vars.len()];
    let mut leaves: Vec<Var> = Vec::new();
    for r in rhs.iter().chain(outputs.iter()) {
        for v in r.vars() {
            if ctx.symbol_name(v).is_none() && !leaves.contains(&v) {
                leaves.push(v);
            }
        }
    }
    if leaves.is_empty() {
        return Ok(angle);
    }
    let th = ctx.tan_half();
    // theta -> t for every sin/cos leaf of an angle variable.
    let mut t_of: Vec<Option<Var>> = vec![None; vars.len()];
    for &leaf in &leaves {
        let image = ctx.to_tan_half(&th, &RatFun::var(leaf));
        let tv = image.vars();
        if tv.len() != 1 || tv[0] == leaf {
            continue; // not a sin/cos leaf: refused below, by name
        }
        let t = tv[0];
        let moved: Vec<usize> = (0..vars.len())
            .filter(|&i| !ctx.rf_diff(&RatFun::var(leaf), vars[i]).is_zero())
            .collect();
        let [i] = moved[..] else {
            continue; // an angle of inputs or of several variables
        };
        // Unit 1: d leaf/d theta in the t view equals d image/dt * dt/dtheta,
        // dt/dtheta = (1 + t^2)/2; an angle theta/k would differ by 1/k.
        let lhs = ctx.rf_diff(&RatFun::var(leaf), vars[i]);
        let lhs = ctx.to_tan_half(&th, &lhs);
        let dimg = ctx.rf_diff(&image, t);
        let rhs_ = ctx.rf_mul(&dimg, &dt_dtheta(ctx, t));
        if ctx.rf_sub(&lhs, &rhs_).is_zero() {
            match t_of[i] {
                Some(t0) if t0 != t => {
                    return Err(err(format!(
                        "global: `{}` enters sin/cos through two different angle units; counted only for sin/cos of {0} and its integer multiples",
                        ctx.symbol_name(vars[i]).unwrap_or("?")
                    )))
                }
                _ => t_of[i] = Some(t),
            }
        } else {
            return Err(err(format!(
                "global: sin/cos of a fraction of `{}` (unit other than 1): the half-angle count would be modulo a multiple of 2 pi; not counted",
                ctx.symbol_name(vars[i]).unwrap_or("?")
            )));
        }
    }
    if t_of.iter().all(|t| t.is_none()) {
        return Ok(angle);
    }
    for r in rhs.iter_mut().chain(outputs.iter_mut()) {
        *r = ctx.to_tan_half(&th, r);
    }
    for (i, t) in t_of.iter().enumerate() {
        let Some(t) = *t else { continue };
        let theta = vars[i];
        let name = ctx.symbol_name(theta).unwrap_or("?").to_string();
        if rhs
            .iter()
            .chain(outputs.iter())
            .any(|r| r.vars().contains(&theta))
        {
            return Err(err(format!(
                "global: the angle `{name}` occurs outside sin/cos (theta = 2 atan t is not rational in the half-angle view); not counted"
            )));
        }
        if i < rhs.len() {
            rhs[i] = ctx.rf_mul(&rhs[i], &dt_dtheta(ctx, t));
        }
        vars[i] = t;
        angle[i] = true;
    }
    Ok(angle)
}

/// `dt/dtheta = (1 + t^2)/2` for `t = tan(theta/2)`.
fn dt_dtheta(ctx: &Ctx, t: Var) -> RatFun {
    let tp = ZPoly::var(t);
    let one_plus = RatFun::from_poly(ZPoly::one().add(&tp.mul(&tp)));
    ctx.rf_mul(
        &one_plus,
        &RatFun::from_q(&Q::new(Int::from(1), Int::from(2))),
    )
}
