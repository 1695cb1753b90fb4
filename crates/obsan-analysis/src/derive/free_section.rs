//! The reduced dynamics through a slice of the symmetries' free columns,
//! when neither the search of `in_modes` nor the cross-section of the
//! scalings (section.rs) writes an invariant in the modes (the unknown-input
//! pk model's `L_f0 z6`: its symmetries are not scalings).
//!
//! Let the symmetries `w_1..w_k` have an invertible `k x k` block on the
//! columns `F` (chosen at a random point). The slice `x_F = c` (numbers) is
//! then transversal to the orbits, and an invariant `t` is constant on them:
//! `t(x) = t(s(x))` with `s(x)` the point where the orbit of `x` meets the
//! slice. On the slice the modes are functions of the other `n - k`
//! variables; when they can be solved for them one at a time, each mode
//! Möbius (`(a v + b)/(c v + d)`, `ad - bc != 0`) in the one variable still
//! unsolved in it, the solution `x_j = X_j(z)` is rational and `t(c, X(z))`
//! is the form of `t` in the modes `z` (the same function whatever `c`, as
//! the modes are independent). Nothing here is trusted: the form is proven
//! like any other by the exact decomposition checks, so an unlucky slice
//! (a pole, a non-generic orbit) costs a form, never a wrong one.

use super::section::Section;
use super::*;
use obsan_expr::Var;

/// Slices tried: every free variable set to 1, then to distinct primes.
const SLICES: [[i64; 2]; 2] = [[1, 0], [2, 1]];

/// The slice of the free columns with the modes solved on it, or `None`
/// (no invertible block, a mode not Möbius in its last unsolved variable,
/// an atom in a mode, or a variable left unsolved).
pub(super) fn free_section(
    nf: &mut NormalForm,
    w_ids: &[Vec<Id>],
    modes: &[DerivedMode],
    seed: u64,
) -> Result<Option<Section>, AnalysisError> {
    let k = w_ids.len();
    if k == 0 || modes.iter().any(|m| m.angle) {
        return Ok(None);
    }
    let n = nf.state.len();
    let vars = nf.state_vars.clone();
    // Free columns: params first (a param fixed on the slice keeps the
    // states' dynamics simple), each taken when it raises the rank of the
    // block at a random point.
    let mut rng = SplitMix(seed ^ 0x5ec7_10f5_11ce);
    let (pt, _) = crate::rank::random_point_counted(&mut nf.ctx, &mut rng)?;
    let flat: Vec<Id> = w_ids.iter().flatten().copied().collect();
    let Ok(vals) = nf.ctx.eval_fp(&flat, &pt) else {
        return Ok(None);
    };
    let w = |a: usize, j: usize| vals[a * n + j];
    let order: Vec<usize> = (nf.n_dynamic..n).chain(0..nf.n_dynamic).collect();
    let mut free: Vec<usize> = Vec::new();
    for &j in &order {
        let mut t = free.clone();
        t.push(j);
        let cols: Vec<Vec<Fp>> = (0..k)
            .map(|a| t.iter().map(|&c| w(a, c)).collect())
            .collect();
        if Fp::matrix_rank(cols) == t.len() {
            free = t;
        }
        if free.len() == k {
            break;
        }
    }
    if free.len() != k {
        return Ok(None);
    }
    for [base, step] in SLICES {
        let consts: Vec<(usize, i64)> = free
            .iter()
            .enumerate()
            .map(|(i, &j)| (j, base + step * i as i64))
            .collect();
        if let Some(images) = solve_on_slice(nf, &vars, &consts, modes) {
            return Ok(Some(Section::from_images(images)));
        }
    }
    Ok(None)
}

/// The images of every state variable: the free ones their numbers, the
/// others solved from the modes (module docs), as nodes over the mode names.
fn solve_on_slice(
    nf: &mut NormalForm,
    vars: &[Var],
    consts: &[(usize, i64)],
    modes: &[DerivedMode],
) -> Option<Vec<(Var, Id)>> {
    let mut images: Vec<(Var, Id)> = consts
        .iter()
        .map(|&(j, c)| (vars[j], nf.ctx.int(c)))
        .collect();
    let mut unsolved: Vec<Var> = vars
        .iter()
        .enumerate()
        .filter(|(j, _)| !consts.iter().any(|c| c.0 == *j))
        .map(|(_, &v)| v)
        .collect();
    let mut pending: Vec<&DerivedMode> = modes.iter().collect();
    while !unsolved.is_empty() {
        let mut progress = false;
        let mut i = 0;
        while i < pending.len() {
            let m = pending[i];
            let e = nf.ctx.substitute(m.expr, &images).ok()?;
            let r = nf.ctx.try_canon(e).ok()?;
            // Every variable a named symbol (no atom hides a variable).
            if r.vars().iter().any(|&v| nf.ctx.symbol_name(v).is_none()) {
                return None;
            }
            let left: Vec<Var> = r
                .vars()
                .into_iter()
                .filter(|v| unsolved.contains(v))
                .collect();
            match left.as_slice() {
                [] => {
                    // Dependent on the slice: no variable to solve.
                    pending.remove(i);
                    continue;
                }
                [v] => {
                    let Some(x) = mobius_inverse(nf, &r, *v, &m.name) else {
                        i += 1;
                        continue;
                    };
                    let id = nf.ctx.from_canonical(&x);
                    images.push((*v, id));
                    unsolved.retain(|u| u != v);
                    pending.remove(i);
                    progress = true;
                    continue;
                }
                _ => i += 1,
            }
        }
        if !progress {
            return None;
        }
    }
    Some(images)
}

/// `v` from `z = (a v + b)/(c v + d)`: `(b - z d)/(z c - a)`, when the
/// numerator and denominator have degree at most 1 in `v` and `ad - bc`
/// is not zero.
fn mobius_inverse(nf: &mut NormalForm, r: &RatFun, v: Var, name: &str) -> Option<RatFun> {
    let split = |p: &Poly| -> Option<(Poly, Poly)> {
        let mut a = Poly::zero();
        let mut b = Poly::zero();
        for (e, c) in p.coeffs_in(v) {
            match e {
                0 => b = c,
                1 => a = c,
                _ => return None,
            }
        }
        Some((a, b))
    };
    let (a, b) = split(r.numerator())?;
    let (c, d) = split(r.denominator())?;
    let rf = RatFun::from_poly;
    let ctx = &nf.ctx;
    let det = ctx.rf_sub(&rf(a.mul(&d)), &rf(b.mul(&c)));
    if det.is_zero() {
        return None;
    }
    let z = RatFun::var(nf.ctx.symbol(name).var);
    let ctx = &nf.ctx;
    let num = ctx.rf_sub(&rf(b), &ctx.rf_mul(&z, &rf(d)));
    let den = ctx.rf_sub(&ctx.rf_mul(&z, &rf(c)), &rf(a));
    let inv = ctx.rf_inv(&den)?;
    Some(ctx.rf_mul(&num, &inv))
}
