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
    // An output that is an integer combination of angles (`y = theta`, a
    // compass or a joint encoder; `y = theta1 - theta2`) is known, so
    // `tan(y/(2g))` is (`g` the gcd of the multiples; see
    // `tan_half_of_angle_sum`), and it is rational in the half-angle
    // tangents: the output is replaced by it. The model sees its angles only
    // through sin/cos, i.e. modulo 2 pi, and that knowledge fixes them modulo
    // 2 pi exactly as the real `y` does: every count is unchanged.
    for r in outputs.iter_mut() {
        if let Some(tan) = tan_half_of_angle_sum(ctx, r, vars, &t_of) {
            *r = tan;
        }
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

/// Largest multiple `k theta` of an angle read in an output: `tan(k theta/2)`
/// has degree `|k|` in `t`.
const MAX_ANGLE_MULTIPLE: i64 = 12;

/// `tan(y/(2g))` in the half-angle tangents when `y = sum k_i theta_i` with
/// integer `k_i` and every `theta_i` an angle (`t_of` set), by
/// `tan((a + b)/2) = (A + B)/(1 - A B)` and `tan(-a/2) = -A`; `None` for any
/// other output (a constant term, a non-angle variable, a fraction).
fn tan_half_of_angle_sum(
    ctx: &Ctx,
    y: &RatFun,
    vars: &[Var],
    t_of: &[Option<Var>],
) -> Option<RatFun> {
    if !y.denominator().is_one() || y.numerator().is_zero() {
        return None;
    }
    let add = |a: &RatFun, b: &RatFun| -> Option<RatFun> {
        let num = ctx.rf_add(a, b);
        let den = ctx.rf_sub(&RatFun::one(), &ctx.rf_mul(a, b));
        Some(ctx.rf_mul(&num, &ctx.rf_inv(&den)?))
    };
    let mut terms: Vec<(RatFun, i64)> = Vec::new();
    for (m, c) in y.numerator().terms() {
        let pairs: Vec<(Var, u32)> = m.iter().collect();
        let [(v, 1)] = pairs[..] else { return None };
        let i = vars.iter().position(|&x| x == v)?;
        let k = i64::try_from(c).ok()?;
        if k.abs() > MAX_ANGLE_MULTIPLE {
            return None;
        }
        terms.push((RatFun::var(t_of[i]?), k));
    }
    // `y` is a real number, not one modulo 2 pi: with `g` the gcd of the
    // `k_i`, `y/g = sum (k_i/g) theta_i` is known too, and fixes the angles
    // modulo 2 pi exactly as `y` does (a second solution needs
    // `sum k_i d_i` in `2 pi g Z` for shifts `d_i` of the angles, i.e.
    // `sum (k_i/g) d_i` in `2 pi Z`), where `tan(y/2)` alone would lose it
    // (`y = 2 theta` fixes theta, `tan(theta)` only theta modulo pi).
    let g = terms.iter().fold(0i64, |g, &(_, k)| gcd(g, k.abs()));
    let mut acc = RatFun::zero();
    for (t, k) in terms {
        let k = k / g;
        let step = if k > 0 { t } else { t.neg() };
        for _ in 0..k.abs() {
            acc = add(&acc, &step)?;
        }
    }
    Some(acc)
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
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
