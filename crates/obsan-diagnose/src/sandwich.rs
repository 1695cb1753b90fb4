//! The cluster-robust covariance of a few params of a fit, cross terms
//! included: the fitter gives each param's robust sd alone, and a
//! combination of two correlated params needs their robust covariance.
//!
//! The sandwich `A^-1 B A^-1 K/(K-1)` of obsan-fit (trajectories as
//! clusters, `B = sum_k g_k g_k^T`, `g_k = J_k^T r_k` the score of
//! trajectory `k`), recomputed from one prediction with sensitivities per
//! trajectory at the fit: `A^-1` is the fit's covariance (params, then each
//! trajectory's initial state), and only the rows of the params asked for
//! are formed. Its diagonal is the fitter's `params_robust_sd` squared (a
//! unit test checks it). Ordinary least squares only: under input noise
//! the residuals' whitener per trajectory is not kept with the fit, and the
//! answer is `None`.

use crate::error::DiagnoseError;
use crate::model_fit::ModelFit;
use obsan_data::{wrap, Dataset};
use obsan_fit::{FitTrajectory, Integration, Measured, Predictor};
use obsan_model::System;

/// The robust covariance of the params at `which` (indices into
/// `f.params`) of fit `f` of `sys` to the prepared `data` at output levels
/// `sigma`; `None` with fewer than two trajectories, under input noise
/// (`weighted`), or without the fit's covariance.
pub(crate) fn robust_covariance(
    sys: &System,
    data: &Dataset,
    f: &ModelFit,
    (sigma, weighted, max_step): (&[f64], bool, f64),
    which: &[usize],
) -> Result<Option<Vec<Vec<f64>>>, DiagnoseError> {
    use rayon::prelude::*;
    let np = f.params.len();
    let k = f.initial_states.len();
    let nd = f.initial_states.first().map_or(0, Vec::len);
    let dim = np + k * nd;
    let square = f.covariance.len() == dim && f.covariance.iter().all(|r| r.len() == dim);
    if weighted || k < 2 || !square || which.iter().any(|&i| i >= np) {
        return Ok(None);
    }
    let nf = sys.normal_form(None, &[]).map_err(DiagnoseError::model)?;
    let p = Predictor::new(&nf);
    if p.n_dynamic != nd || p.state.len() != nd + np {
        return Ok(None);
    }
    let trajs = FitTrajectory::all(&p, data);
    if trajs.len() != k {
        return Ok(None);
    }
    let integ = Integration {
        max_step,
        sensitivities: true,
        input_noise: None,
    };
    let pv: Vec<f64> = f.params.iter().map(|x| x.1).collect();
    let n = nd + np;
    let cancel = obsan_expr::cancel_flag();
    // Per trajectory, `c_k = (A^-1 g_k)` at the rows asked for.
    let parts: Result<Vec<Vec<f64>>, DiagnoseError> = trajs
        .par_iter()
        .enumerate()
        .map(|(t, tr)| {
            obsan_expr::with_cancel(cancel.clone(), || {
                let mut x0 = f.initial_states[t].clone();
                x0.extend_from_slice(&pv);
                let cells = Measured::new(&p, tr.outputs);
                let pred = p
                    .predict_measured(&x0, &tr.consts, tr.inputs, &cells, &integ)
                    .map_err(|source| DiagnoseError::Predict {
                        trajectory: tr.name.to_string(),
                        source,
                    })?;
                // The score over the trajectory's own columns: its initial
                // state, then the params (the Jacobian's order).
                let mut g = vec![0.0; n];
                for (j, yj) in pred.outputs.iter().enumerate() {
                    let (outs, values) = cells.at(j);
                    for (i, (&o, &m)) in outs.iter().zip(values).enumerate() {
                        let d = m - yj[i];
                        let r = if p.angular[o] { wrap(d) } else { d } / sigma[o];
                        let jac = &pred.jacobians[j][i * n..(i + 1) * n];
                        for (gl, jl) in g.iter_mut().zip(jac) {
                            *gl += jl / sigma[o] * r;
                        }
                    }
                }
                let col = |l: usize| if l < nd { np + t * nd + l } else { l - nd };
                Ok(which
                    .iter()
                    .map(|&a| {
                        g.iter()
                            .enumerate()
                            .map(|(l, gl)| f.covariance[a][col(l)] * gl)
                            .sum()
                    })
                    .collect())
            })
        })
        .collect();
    let parts = parts?;
    let scale = k as f64 / (k as f64 - 1.0);
    let m = which.len();
    let mut v = vec![vec![0.0; m]; m];
    for c in &parts {
        for a in 0..m {
            for b in 0..m {
                v[a][b] += c[a] * c[b] * scale;
            }
        }
    }
    Ok(Some(v))
}
