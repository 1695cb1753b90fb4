//! Input checks: an effect on the measured inputs themselves (`compare`
//! relations of the effects file), estimated by least squares on the inputs.

use crate::stats::normal_critical;
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
    pub estimates: Vec<(String, f64, f64)>,
    pub z: f64,
    pub significant: bool,
    pub note: String,
}

/// Fit the params of an input relation `compare u = EXPR` to the measured
/// inputs of every trajectory where EXPR can be evaluated (Gauss–Newton,
/// numeric derivatives; residual scatter gives the standard deviations).
pub(crate) fn input_check(e: &Effect, data: &Dataset, alpha: f64) -> InputCheck {
    let mut out = InputCheck {
        effect: e.name.clone(),
        description: e.description.clone(),
        estimates: vec![],
        z: 0.0,
        significant: false,
        note: String::new(),
    };
    let np = e.params.len();
    let resid = |theta: &[f64]| -> Vec<f64> {
        let mut r = Vec::new();
        for t in &data.trajectories {
            let mut consts: BTreeMap<String, f64> = t.meta.clone();
            for (p, v) in e.params.iter().zip(theta) {
                consts.insert(p.clone(), *v);
            }
            for (u, rhs) in &e.compares {
                let mut s = t.inputs.clone();
                if add_derived_inputs(&mut s, &[("__cmp".into(), rhs.clone())], &consts).is_err() {
                    continue;
                }
                let (Some(m), Some(c)) = (s.column(u), s.column("__cmp")) else {
                    continue;
                };
                // Compared over 1 s block means: averaging keeps the relation
                // (linear in the inputs) and removes the errors-in-variables
                // bias that per-sample encoder noise would give.
                let (mut a, mut b, mut n) = (0.0, 0.0, 0usize);
                let mut t0 = s.t.first().copied().unwrap_or(0.0);
                for ((x, y), t) in m.iter().zip(c).zip(&s.t) {
                    if *t >= t0 + 1.0 && n > 0 {
                        r.push((a - b) / n as f64);
                        (a, b, n, t0) = (0.0, 0.0, 0, *t);
                    }
                    if let (Some(x), Some(y)) = (x, y) {
                        a += x;
                        b += y;
                        n += 1;
                    }
                }
                if n > 0 {
                    r.push((a - b) / n as f64);
                }
            }
        }
        r
    };
    let theta = vec![0.0; np];
    let r0 = resid(&theta);
    if r0.is_empty() {
        out.note = "no trajectory has what the relation needs (e.g. q in meta.json)".into();
        return out;
    }
    // J = -dr/dtheta by forward differences; the normal equations of the core.
    let normal = |theta: &[f64]| {
        let r = resid(theta);
        let jac: Vec<Vec<f64>> = (0..np)
            .map(|i| {
                let mut t2 = theta.to_vec();
                let h = 1e-6 * (1.0 + theta[i].abs());
                t2[i] += h;
                let r2 = resid(&t2);
                r.iter().zip(&r2).map(|(a, b)| (a - b) / h).collect()
            })
            .collect();
        let jtj = nalgebra::DMatrix::from_fn(np, np, |i, j| {
            jac[i].iter().zip(&jac[j]).map(|(a, b)| a * b).sum()
        });
        let jtr =
            nalgebra::DVector::from_fn(np, |i, _| jac[i].iter().zip(&r).map(|(a, b)| a * b).sum());
        (jtj, jtr)
    };
    let cost = |theta: &[f64]| resid(theta).iter().map(|x| x * x).sum::<f64>();
    let theta = minimise(&theta, cost, normal, |_| {}, &LmOptions::default()).x;
    let Some(inv) = normal(&theta).0.try_inverse() else {
        out.note = "the inputs do not determine the relation's params".into();
        return out;
    };
    let r = resid(&theta);
    let s2 = r.iter().map(|x| x * x).sum::<f64>() / (r.len() as f64 - np as f64).max(1.0);
    let cov = inv * s2;
    let zcrit = normal_critical(alpha);
    out.estimates = e
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| (p.clone(), theta[i], cov[(i, i)].max(0.0).sqrt()))
        .collect();
    out.z = out
        .estimates
        .iter()
        .map(|(_, v, s)| if *s > 0.0 { (v / s).abs() } else { 0.0 })
        .fold(0.0, f64::max);
    out.significant = out.z > zcrit;
    out.note = format!("{} input samples", r0.len());
    out
}
