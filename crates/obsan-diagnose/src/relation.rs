//! Input checks: an effect on the measured inputs themselves (`compare`
//! relations of the effects file), estimated by weighted least squares on
//! the inputs under the encoder-noise model.
//!
//! A measured input `u` held for `dt` carries white noise of variance
//! `c |u| / dt` (the encoder model of [10], `c = K^2 / r`; see
//! `obsan_fit::Integration::input_noise`). The relation `u = EXPR(inputs)`
//! is compared over 1 s block means (averaging keeps a relation linear in
//! the inputs and removes the errors-in-variables bias of per-sample
//! noise); each block's residual has variance
//! `sum_j sum_i g_ij^2 c_i |u_ij| / dt_j / n^2` over its n rows, with `g_ij`
//! the derivative of `u - EXPR` with respect to input i at row j. Each
//! trajectory is weighed by its own noise: a trajectory whose compared input
//! is commanded still (q = 0: `wL = q wR = 0`) has almost noiseless wheel
//! readings there, so one that turns anyway shows the relation's error
//! plainly, where an unweighted pool drowns it in the other trajectories'
//! noise.

use crate::stats::{normal_critical, normal_two_sided};
use obsan_data::{add_derived_inputs, Dataset};
use obsan_fit::{minimise, LmOptions};
use obsan_model::Effect;
use serde::Serialize;
use std::collections::BTreeMap;

/// An effect on the measured inputs (`compare` relations).
#[derive(Clone, Debug, Serialize)]
pub struct InputCheck {
    pub effect: String,
    pub description: String,
    /// The relation's params, each with its sd (scaled by
    /// `max(1, dispersion)` under stated noise, by the dispersion when the
    /// noise level is estimated).
    pub estimates: Vec<(String, f64, f64)>,
    /// The largest |estimate / sd| (0 is the declared relation).
    pub z: f64,
    /// Two-sided p-value of `z`.
    pub p_value: f64,
    pub significant: bool,
    /// "stated" (dataset.json's encoder noise) or "estimated" (one common
    /// intensity for every input, read from the relation's scatter).
    pub noise: String,
    /// Weighted residual sum of squares over its degrees of freedom at the
    /// estimate: 1 when the encoder model holds; with estimated noise, the
    /// intensity `c` itself.
    pub dispersion: f64,
    /// The same relation fitted on each trajectory alone (linearised at the
    /// joint estimate, exact for a relation linear in its params).
    pub per_trajectory: Vec<TrajectoryCheck>,
    pub note: String,
}

/// One trajectory's own estimate of a relation's params.
#[derive(Clone, Debug, Serialize)]
pub struct TrajectoryCheck {
    pub trajectory: String,
    pub estimates: Vec<(String, f64, f64)>,
    pub z: f64,
}

/// One block: its trajectory, the rows it averages, the residual variance
/// per unit intensity.
struct Block {
    traj: usize,
    rows: std::ops::Range<usize>,
    var: f64,
}

/// The compared input's column and the relation's right side, per row.
type Sides = (Vec<Option<f64>>, Vec<Option<f64>>);

/// Length of the blocks (s) whose means are compared.
const BLOCK: f64 = 1.0;

/// Variances below this fraction of the median block variance are raised
/// to it: a compared input that reads exactly 0 has no encoder noise under
/// the model (its variance is proportional to |u|), which would weigh it
/// infinitely; 1e-12 keeps the normal equations finite while still letting
/// such blocks dominate.
const VAR_FLOOR: f64 = 1e-12;

/// Fit the params of an input relation `compare u = EXPR` to the measured
/// inputs of every trajectory where EXPR can be evaluated. `noise` holds
/// each measured input's intensity `c` (empty or all 0: not stated, then
/// one common intensity is estimated); `source` says where `noise` comes
/// from (printed: a level the fit estimated is never called stated);
/// `alpha` is the test's level.
pub(crate) fn input_check(
    e: &Effect,
    data: &Dataset,
    (noise, source): (&[(String, f64)], &str),
    alpha: f64,
) -> InputCheck {
    let mut out = InputCheck {
        effect: e.name.clone(),
        description: e.description.clone(),
        estimates: vec![],
        z: 0.0,
        p_value: 1.0,
        significant: false,
        noise: String::new(),
        dispersion: f64::NAN,
        per_trajectory: vec![],
        note: String::new(),
    };
    let np = e.params.len();
    let stated = noise.iter().any(|(_, c)| *c > 0.0);
    out.noise = if stated { "stated" } else { "estimated" }.into();
    let theta0 = vec![0.0; np];
    let base = relation_sides(e, data, &theta0);
    let blocks = noise_blocks(e, data, &base, (noise, stated));
    if blocks.is_empty() {
        out.note = "no trajectory has what the relation needs (e.g. q in meta.json)".into();
        return out;
    }
    let (weights, floor) = block_weights(&blocks);
    let resid = |theta: &[f64]| block_residuals(&relation_sides(e, data, theta), &blocks, &weights);
    // J = -dr/dtheta by forward differences, rows of the blocks.
    let jacobian = |theta: &[f64], r: &[f64]| -> Vec<Vec<f64>> {
        (0..np)
            .map(|i| {
                let mut t2 = theta.to_vec();
                let h = 1e-6 * (1.0 + theta[i].abs());
                t2[i] += h;
                let r2 = resid(&t2);
                r.iter().zip(&r2).map(|(a, b)| (a - b) / h).collect()
            })
            .collect()
    };
    let normal = |theta: &[f64]| {
        let r = resid(theta);
        let jac = jacobian(theta, &r);
        normal_of(np, &jac, &r, &|_| true)
    };
    let cost = |theta: &[f64]| resid(theta).iter().map(|x| x * x).sum::<f64>();
    let theta = minimise(&theta0, cost, normal, |_| {}, &LmOptions::default()).x;
    let r = resid(&theta);
    let jac = jacobian(&theta, &r);
    let (jtj, _) = normal_of(np, &jac, &r, &|_| true);
    let Some(inv) = jtj.try_inverse() else {
        out.note = "the inputs do not determine the relation's params".into();
        return out;
    };
    let dof = (r.len() as f64 - np as f64).max(1.0);
    let dispersion = r.iter().map(|x| x * x).sum::<f64>() / dof;
    out.dispersion = dispersion;
    // Stated noise: the model's own variance, inflated if the scatter is
    // larger (quasi-likelihood); estimated: the scatter sets the level.
    let s2 = if stated && floor.is_some() {
        dispersion.max(1.0)
    } else {
        dispersion
    };
    let cov = inv * s2;
    out.estimates = with_sd(e, &theta, &cov);
    out.z = zmax(&out.estimates);
    out.p_value = normal_two_sided(out.z);
    out.significant = out.z > normal_critical(alpha);
    // Each trajectory alone: one Gauss-Newton step from the joint estimate
    // on its own blocks.
    for (k, t) in data.trajectories.iter().enumerate() {
        let pick = |b: usize| blocks[b].1.traj == k;
        if !(0..r.len()).any(pick) {
            continue;
        }
        let (a, g) = normal_of(np, &jac, &r, &pick);
        let Some(ai) = a.try_inverse() else { continue };
        let step = &ai * g;
        let x: Vec<f64> = (0..np).map(|i| theta[i] + step[i]).collect();
        let est = with_sd(e, &x, &(ai * s2));
        out.per_trajectory.push(TrajectoryCheck {
            trajectory: t.name.clone(),
            z: zmax(&est),
            estimates: est,
        });
    }
    out.note = format!(
        "{} blocks of {BLOCK} s; encoder noise {}{}",
        r.len(),
        if stated {
            source
        } else {
            "estimated from the relation's scatter"
        },
        if stated {
            format!(", dispersion {dispersion:.2}")
        } else {
            format!(", c = {dispersion:.2e} (one for every input)")
        }
    );
    out
}

/// Trajectory `k`'s constants with the relation's params at `theta`.
fn consts_at(e: &Effect, data: &Dataset, k: usize, theta: &[f64]) -> BTreeMap<String, f64> {
    let mut c = data.trajectories[k].meta.clone();
    for (p, v) in e.params.iter().zip(theta) {
        c.insert(p.clone(), *v);
    }
    c
}

/// The relation's right side per (trajectory, compare) at `theta`, with the
/// compared input; None where it cannot be evaluated (e.g. no q).
fn relation_sides(e: &Effect, data: &Dataset, theta: &[f64]) -> Vec<Option<Sides>> {
    let mut v = Vec::new();
    for (k, t) in data.trajectories.iter().enumerate() {
        let consts = consts_at(e, data, k, theta);
        for (u, rhs) in &e.compares {
            let mut s = t.inputs.clone();
            let ok = add_derived_inputs(&mut s, &[("__cmp".into(), rhs.clone())], &consts);
            v.push(match (ok, s.column(u), s.column("__cmp")) {
                (Ok(()), Some(m), Some(c)) => Some((m.to_vec(), c.to_vec())),
                _ => None,
            });
        }
    }
    v
}

/// Blocks of `BLOCK` s per (trajectory, compare) and their variances per
/// unit intensity, at the declared relation (theta = 0: the null hypothesis
/// the test is about), as (side index, block).
fn noise_blocks(
    e: &Effect,
    data: &Dataset,
    base: &[Option<Sides>],
    (noise, stated): (&[(String, f64)], bool),
) -> Vec<(usize, Block)> {
    let nc = e.compares.len();
    let theta0 = vec![0.0; e.params.len()];
    let mut blocks: Vec<(usize, Block)> = Vec::new();
    for (k, t) in data.trajectories.iter().enumerate() {
        let consts = consts_at(e, data, k, &theta0);
        for (ci, (u, rhs)) in e.compares.iter().enumerate() {
            let si = k * nc + ci;
            let Some((m, c)) = &base[si] else { continue };
            let s = &t.inputs;
            // d(u - EXPR)/d(input i) per row, by a forward difference on the
            // whole column (EXPR is evaluated row by row).
            let mut grads: Vec<(usize, Vec<f64>, f64)> = Vec::new(); // input, g per row, c_i
            for (i, name) in s.columns().iter().enumerate() {
                let ci = if stated {
                    noise.iter().find(|n| n.0 == *name).map_or(0.0, |n| n.1)
                } else {
                    1.0
                };
                if ci <= 0.0 {
                    continue;
                }
                let scale = s.values()[i]
                    .iter()
                    .flatten()
                    .fold(0.0f64, |a, x| a.max(x.abs()));
                let h = 1e-6 * (1.0 + scale);
                let mut p = s.clone();
                for x in p.values_mut(i).iter_mut().flatten() {
                    *x += h;
                }
                let _ = add_derived_inputs(&mut p, &[("__cmp".into(), rhs.clone())], &consts);
                let Some(c2) = p.column("__cmp") else {
                    continue;
                };
                let own = if name == u { 1.0 } else { 0.0 };
                let g: Vec<f64> = c
                    .iter()
                    .zip(c2)
                    .map(|(a, b)| match (a, b) {
                        (Some(a), Some(b)) => own - (b - a) / h,
                        _ => 0.0,
                    })
                    .collect();
                grads.push((i, g, ci));
            }
            let n_rows = s.t().len();
            let dt = |j: usize| -> f64 {
                if j + 1 < n_rows {
                    s.t()[j + 1] - s.t()[j]
                } else if j > 0 {
                    s.t()[j] - s.t()[j - 1]
                } else {
                    BLOCK
                }
            };
            let mut start = 0usize;
            while start < n_rows {
                let t0 = s.t()[start];
                let mut end = start;
                while end < n_rows && s.t()[end] < t0 + BLOCK {
                    end += 1;
                }
                let mut var = 0.0;
                let mut n = 0usize;
                for j in start..end {
                    if m[j].is_none() || c[j].is_none() {
                        continue;
                    }
                    n += 1;
                    let d = dt(j).max(1e-9);
                    for (col, g, ci) in &grads {
                        let uj = s.values()[*col][j].unwrap_or(0.0).abs();
                        var += g[j] * g[j] * ci * uj / d;
                    }
                }
                if n > 0 {
                    blocks.push((
                        si,
                        Block {
                            traj: k,
                            rows: start..end,
                            var: var / (n * n) as f64,
                        },
                    ));
                }
                start = end.max(start + 1);
            }
        }
    }
    blocks
}

/// Each block's weight, 1/sd, with the variances floored at `VAR_FLOOR`
/// times their median (and the floor: `None` when no block has noise, then
/// unweighted, the scale estimated).
fn block_weights(blocks: &[(usize, Block)]) -> (Vec<f64>, Option<f64>) {
    let mut pos: Vec<f64> = blocks
        .iter()
        .map(|b| b.1.var)
        .filter(|v| *v > 0.0)
        .collect();
    pos.sort_by(f64::total_cmp);
    let floor = pos.get(pos.len() / 2).map(|m| m * VAR_FLOOR);
    let weights = blocks
        .iter()
        .map(|b| match floor {
            Some(f) => 1.0 / b.1.var.max(f).sqrt(),
            None => 1.0,
        })
        .collect();
    (weights, floor)
}

/// The weighted mean of `u - EXPR` over each block.
fn block_residuals(sd: &[Option<Sides>], blocks: &[(usize, Block)], weights: &[f64]) -> Vec<f64> {
    blocks
        .iter()
        .zip(weights)
        .map(|((si, b), w)| {
            let Some((m, c)) = &sd[*si] else { return 0.0 };
            let (mut a, mut n) = (0.0, 0usize);
            for j in b.rows.clone() {
                if let (Some(x), Some(y)) = (m[j], c[j]) {
                    a += x - y;
                    n += 1;
                }
            }
            w * a / n.max(1) as f64
        })
        .collect()
}

/// The normal equations `(J^T J, J^T r)` over the blocks `pick` keeps.
fn normal_of(
    np: usize,
    jac: &[Vec<f64>],
    r: &[f64],
    pick: &dyn Fn(usize) -> bool,
) -> (nalgebra::DMatrix<f64>, nalgebra::DVector<f64>) {
    let jtj = nalgebra::DMatrix::from_fn(np, np, |i, j| {
        (0..r.len())
            .filter(|&b| pick(b))
            .map(|b| jac[i][b] * jac[j][b])
            .sum()
    });
    let jtr = nalgebra::DVector::from_fn(np, |i, _| {
        (0..r.len())
            .filter(|&b| pick(b))
            .map(|b| jac[i][b] * r[b])
            .sum()
    });
    (jtj, jtr)
}

/// The relation's params at `x` with their sds from `cov`.
fn with_sd(e: &Effect, x: &[f64], cov: &nalgebra::DMatrix<f64>) -> Vec<(String, f64, f64)> {
    e.params
        .iter()
        .enumerate()
        .map(|(i, p)| (p.clone(), x[i], cov[(i, i)].max(0.0).sqrt()))
        .collect()
}

/// The largest |estimate / sd|.
fn zmax(est: &[(String, f64, f64)]) -> f64 {
    est.iter()
        .map(|(_, v, s)| if *s > 0.0 { (v / s).abs() } else { 0.0 })
        .fold(0.0, f64::max)
}

/// `text` (a .sys file) with a contradicted input relation written in: its
/// params as known constants at their estimates, and in every restriction
/// that sets the compared input, that input's right side replaced by the
/// relation (its other inputs replaced by the restriction's expressions for
/// them), e.g. `restrict q: wR = nu, wL = q*nu` with `compare wL = (q +
/// dq)*wR` becomes `restrict q: wR = nu, wL = ((q + dq)*(nu))`.
pub(crate) fn with_relation(text: &str, e: &Effect, estimates: &[(String, f64, f64)]) -> String {
    let mut out = String::new();
    let mut declared = false;
    for line in text.lines() {
        let trimmed = line.trim_start();
        if !declared && trimmed.starts_with("restrict ") {
            out.push_str(&relation_consts(e, estimates));
            declared = true;
        }
        let Some(body) = trimmed.strip_prefix("restrict ") else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        let Some((name, rhs)) = body.split_once(':') else {
            out.push_str(line);
            out.push('\n');
            continue;
        };
        let parts: Vec<(String, String)> = split_assignments(rhs);
        let mut changed = parts.clone();
        for (u, expr) in &e.compares {
            if let Some(slot) = changed.iter_mut().find(|p| p.0 == *u) {
                let mut x = expr.clone();
                for (v, ve) in &parts {
                    if v != u {
                        x = replace_ident(&x, v, &format!("({ve})"));
                    }
                }
                slot.1 = format!("({x})");
            }
        }
        let joined: Vec<String> = changed.iter().map(|(a, b)| format!("{a} = {b}")).collect();
        out.push_str(&format!(
            "restrict {}: {}\n",
            name.trim(),
            joined.join(", ")
        ));
    }
    if !declared {
        out.push_str(&relation_consts(e, estimates));
    }
    out
}

fn relation_consts(e: &Effect, estimates: &[(String, f64, f64)]) -> String {
    let mut s = format!(
        "# named input relation {} (fitted on the measured inputs): {}\n",
        e.name, e.description
    );
    for (p, v, sd) in estimates {
        s.push_str(&format!("const {p} = {v:e}   # ± {sd:.1e}\n"));
    }
    s
}

/// `a = x, b = f(y, z)` as (name, expression) pairs, split at top-level commas.
fn split_assignments(s: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i32, 0usize);
    let bytes: Vec<char> = s.chars().collect();
    let mut push = |part: String| {
        if let Some((a, b)) = part.split_once('=') {
            out.push((a.trim().to_string(), b.trim().to_string()));
        }
    };
    for (i, c) in bytes.iter().enumerate() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                push(bytes[start..i].iter().collect());
                start = i + 1;
            }
            _ => {}
        }
    }
    push(bytes[start..].iter().collect());
    out
}

/// `expr` with every whole-word occurrence of the identifier `name` replaced.
fn replace_ident(expr: &str, name: &str, by: &str) -> String {
    let is_id = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let chars: Vec<char> = expr.chars().collect();
    let target: Vec<char> = name.chars().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < chars.len() {
        let fits = chars[i..].starts_with(&target)
            && (i == 0 || !is_id(chars[i - 1]))
            && chars.get(i + target.len()).is_none_or(|c| !is_id(*c));
        if fits {
            out.push_str(by);
            i += target.len();
        } else {
            out.push(chars[i]);
            i += 1;
        }
    }
    out
}
