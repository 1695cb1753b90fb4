//! Maximum-likelihood fitting of a model to trajectories: Levenberg–Marquardt
//! over the shared parameters and each trajectory's initial dynamic state,
//! with Gaussian output noise (so least squares of residual / sigma). Angle
//! outputs have their residuals wrapped to (-pi, pi].
//!
//! The Jacobian is by forward differences, organised by trajectory: a
//! trajectory's initial state affects only its own residuals.

use crate::data::Series;
use crate::predict::Predictor;
use crate::sim::wrap;

/// One trajectory to fit.
pub struct FitTrajectory<'a> {
    pub inputs: &'a Series,
    pub outputs: &'a Series,
    /// Values of the predictor's constants (e.g. q).
    pub consts: Vec<f64>,
}

/// Options of the fit; every tolerance explicit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost is below this.
    pub cost_tolerance: f64,
    /// Noise standard deviation of each output (residuals are divided by it).
    pub sigma: Vec<f64>,
    /// Relative step of the forward differences.
    pub diff_step: f64,
}

/// The estimate and its uncertainty.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// Shared parameters, in the order of the predictor's params.
    pub params: Vec<f64>,
    /// Per trajectory, the initial dynamic state.
    pub initial_states: Vec<Vec<f64>>,
    /// Standard deviations from the inverse Fisher information (J^T J)^-1.
    pub params_sd: Vec<f64>,
    pub initial_states_sd: Vec<Vec<f64>>,
    /// Sum of squared normalised residuals at the estimate.
    pub cost: f64,
    pub n_residuals: usize,
    pub iterations: usize,
    /// Root mean square of the (un-normalised) residuals per output.
    pub residual_rms: Vec<f64>,
}

struct Layout {
    n_params: usize,
    n_dyn: usize,
    n_traj: usize,
}

impl Layout {
    fn len(&self) -> usize {
        self.n_params + self.n_dyn * self.n_traj
    }
    fn state_of(&self, theta: &[f64], k: usize) -> Vec<f64> {
        let mut x: Vec<f64> =
            theta[self.n_params + k * self.n_dyn..self.n_params + (k + 1) * self.n_dyn].to_vec();
        x.extend_from_slice(&theta[..self.n_params]);
        x
    }
}

/// Normalised residuals of one trajectory (measured cells only).
fn residuals(
    p: &Predictor,
    t: &FitTrajectory,
    x0: &[f64],
    opts: &FitOptions,
    cols: &[usize],
) -> Result<Vec<f64>, String> {
    let y = p.predict(x0, &t.consts, t.inputs, &t.outputs.t)?;
    let mut r = Vec::new();
    for (k, yk) in y.iter().enumerate() {
        for (o, &c) in cols.iter().enumerate() {
            if let Some(m) = t.outputs.values[c][k] {
                let d = m - yk[o];
                let d = if p.angular[o] { wrap(d) } else { d };
                r.push(d / opts.sigma[o]);
            }
        }
    }
    Ok(r)
}

/// Solve the symmetric system `a x = b` by Gaussian elimination with partial pivoting.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Option<Vec<f64>> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[p][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        for i in c + 1..n {
            let f = a[i][c] / a[c][c];
            if f != 0.0 {
                let pivot = a[c].clone();
                for (x, y) in a[i].iter_mut().zip(&pivot).skip(c) {
                    *x -= f * y;
                }
                b[i] -= f * b[c];
            }
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    Some(x)
}

/// Fit `params` (the predictor's params) and each trajectory's initial dynamic state.
pub fn fit(
    p: &Predictor,
    trajs: &[FitTrajectory],
    init_params: &[f64],
    init_states: &[Vec<f64>],
    opts: &FitOptions,
) -> Result<FitResult, String> {
    let n_params = p.state.len() - p.n_dynamic;
    let lay = Layout {
        n_params,
        n_dyn: p.n_dynamic,
        n_traj: trajs.len(),
    };
    if init_params.len() != n_params
        || init_states.len() != trajs.len()
        || init_states.iter().any(|s| s.len() != p.n_dynamic)
    {
        return Err("initial values do not match the model".into());
    }
    if opts.sigma.len() != p.outputs.len() || opts.sigma.iter().any(|s| s.is_nan() || *s <= 0.0) {
        return Err("one positive noise level per output is needed".into());
    }
    let cols: Vec<Vec<usize>> = trajs
        .iter()
        .map(|t| {
            p.outputs
                .iter()
                .map(|o| {
                    t.outputs
                        .columns
                        .iter()
                        .position(|c| c == o)
                        .ok_or_else(|| format!("the outputs have no column '{o}'"))
                })
                .collect()
        })
        .collect::<Result<_, _>>()?;
    // Output index of each residual of each trajectory (the same for every evaluation).
    let which: Vec<Vec<usize>> = trajs
        .iter()
        .zip(&cols)
        .map(|(t, c)| {
            (0..t.outputs.len())
                .flat_map(|row| {
                    c.iter()
                        .enumerate()
                        .filter(move |(_, &ci)| t.outputs.values[ci][row].is_some())
                        .map(|(o, _)| o)
                })
                .collect()
        })
        .collect();
    let mut theta: Vec<f64> = init_params.to_vec();
    for s in init_states {
        theta.extend_from_slice(s);
    }
    let all_res = |theta: &[f64]| -> Result<Vec<Vec<f64>>, String> {
        trajs
            .iter()
            .enumerate()
            .map(|(k, t)| residuals(p, t, &lay.state_of(theta, k), opts, &cols[k]))
            .collect()
    };
    let cost_of = |r: &[Vec<f64>]| r.iter().flatten().map(|x| x * x).sum::<f64>();
    let mut res = all_res(&theta)?;
    let mut cost = cost_of(&res);
    let n = lay.len();
    let mut lambda = 1e-3;
    let mut iterations = 0;
    let mut jtj = vec![vec![0.0; n]; n];
    loop {
        // Normal equations J^T J and J^T r, trajectory by trajectory.
        jtj = vec![vec![0.0; n]; n];
        let mut jtr = vec![0.0; n];
        for (k, t) in trajs.iter().enumerate() {
            let idx: Vec<usize> = (0..n_params)
                .chain((0..lay.n_dyn).map(|i| n_params + k * lay.n_dyn + i))
                .collect();
            let mut cols_j: Vec<Vec<f64>> = Vec::with_capacity(idx.len());
            for &j in &idx {
                let h = opts.diff_step * theta[j].abs().max(1e-3);
                let mut th = theta.clone();
                th[j] += h;
                let r2 = residuals(p, t, &lay.state_of(&th, k), opts, &cols[k])?;
                // r = meas - pred, so dr/dtheta = -(dpred/dtheta); keep J = d(-r)/dtheta.
                cols_j.push(
                    r2.iter()
                        .zip(&res[k])
                        .zip(&which[k])
                        .map(|((a, b), &o)| -fold(a - b, o, p, opts) / h)
                        .collect(),
                );
            }
            for (a, &ja) in idx.iter().enumerate() {
                jtr[ja] += cols_j[a]
                    .iter()
                    .zip(&res[k])
                    .map(|(x, y)| x * y)
                    .sum::<f64>();
                for (b, &jb) in idx.iter().enumerate() {
                    jtj[ja][jb] += cols_j[a]
                        .iter()
                        .zip(&cols_j[b])
                        .map(|(x, y)| x * y)
                        .sum::<f64>();
                }
            }
        }
        if iterations >= opts.max_iterations {
            break;
        }
        iterations += 1;
        let mut improved = false;
        for _ in 0..20 {
            let mut a = jtj.clone();
            for (i, row) in a.iter_mut().enumerate() {
                row[i] += lambda * jtj[i][i].max(1e-12);
            }
            let Some(step) = solve(a, jtr.clone()) else {
                lambda *= 10.0;
                continue;
            };
            let cand: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + s).collect();
            if let Ok(r2) = all_res(&cand) {
                let c2 = cost_of(&r2);
                if c2 < cost {
                    let rel = (cost - c2) / cost.max(1e-300);
                    theta = cand;
                    res = r2;
                    cost = c2;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = rel > opts.cost_tolerance;
                    break;
                }
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    // Covariance: (J^T J)^-1 (residuals are already normalised by sigma).
    let cov_diag: Vec<f64> = (0..n)
        .map(|i| {
            let mut e = vec![0.0; n];
            e[i] = 1.0;
            solve(jtj.clone(), e).map_or(f64::NAN, |x| x[i].max(0.0).sqrt())
        })
        .collect();
    let n_res: usize = res.iter().map(Vec::len).sum();
    let mut rms = vec![0.0; p.outputs.len()];
    let mut counts = vec![0usize; p.outputs.len()];
    for (k, t) in trajs.iter().enumerate() {
        let mut it = res[k].iter();
        for row in 0..t.outputs.len() {
            for (o, &c) in cols[k].iter().enumerate() {
                if t.outputs.values[c][row].is_some() {
                    let r = it.next().expect("residual") * opts.sigma[o];
                    rms[o] += r * r;
                    counts[o] += 1;
                }
            }
        }
    }
    let residual_rms = rms
        .iter()
        .zip(&counts)
        .map(|(s, c)| (s / (*c).max(1) as f64).sqrt())
        .collect();
    Ok(FitResult {
        params: theta[..n_params].to_vec(),
        initial_states: (0..trajs.len())
            .map(|k| theta[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        params_sd: cov_diag[..n_params].to_vec(),
        initial_states_sd: (0..trajs.len())
            .map(|k| cov_diag[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        cost,
        n_residuals: n_res,
        iterations,
        residual_rms,
    })
}

/// A difference of normalised residuals of output `o`: for an angle it can
/// jump by 2 pi / sigma across the wrap, and a difference step is tiny, so
/// such jumps are folded back.
fn fold(d: f64, o: usize, p: &Predictor, opts: &FitOptions) -> f64 {
    if !p.angular[o] {
        return d;
    }
    let period = 2.0 * std::f64::consts::PI / opts.sigma[o];
    d - period * (d / period).round()
}
