//! Maximum-likelihood fitting of a model to trajectories: Levenberg–Marquardt
//! over the shared parameters and each trajectory's initial dynamic state,
//! with Gaussian output noise (so least squares of residual / sigma). Angle
//! outputs have their residuals wrapped to (-pi, pi].
//!
//! The Jacobian comes from the forward sensitivity equations (exact
//! derivatives of the model from the engine, integrated with the state),
//! organised by trajectory: a trajectory's initial state affects only its
//! own residuals.

use crate::data::Series;
use crate::predict::{Integration, Predictor};
use crate::sim::wrap;

/// One trajectory to fit.
pub struct FitTrajectory<'a> {
    pub inputs: &'a Series,
    pub outputs: &'a Series,
    /// Values of the predictor's constants (e.g. q).
    pub consts: Vec<f64>,
}

impl<'a> FitTrajectory<'a> {
    /// Every trajectory of a dataset, with the predictor's constants from
    /// each `meta.json` (0 where absent: a constant the dynamics do not use).
    pub fn all(p: &Predictor, data: &'a crate::data::Dataset) -> Vec<FitTrajectory<'a>> {
        data.trajectories
            .iter()
            .map(|t| FitTrajectory {
                inputs: &t.inputs,
                outputs: &t.outputs,
                consts: p
                    .consts
                    .iter()
                    .map(|c| t.meta.get(c).copied().unwrap_or(0.0))
                    .collect(),
            })
            .collect()
    }
}

/// Options of the fit; every tolerance explicit.
#[derive(Clone, Debug)]
pub struct FitOptions {
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost is below this.
    pub cost_tolerance: f64,
    /// Noise standard deviation of each output (residuals are divided by it).
    pub sigma: Vec<f64>,
    /// Longest integration step (s) over merged input rows; 0 = one step per
    /// input row (see [`Integration::max_step`]).
    pub max_step: f64,
    /// Noise of the measured inputs (see [`Integration::input_noise`]);
    /// when given the fit is generalised least squares: the residuals of a
    /// trajectory are whitened by the Cholesky factor of their covariance
    /// `I + A M A^T` (output noise plus the integrated input noise,
    /// linearised), computed at the start and again at the estimate.
    pub input_noise: Option<Vec<f64>>,
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
    /// The whole covariance, params first, then each trajectory's initial state.
    pub covariance: Vec<Vec<f64>>,
    /// Sum of squared normalised residuals at the estimate.
    pub cost: f64,
    pub n_residuals: usize,
    pub iterations: usize,
    /// Root mean square of the (un-normalised) residuals per output.
    pub residual_rms: Vec<f64>,
    /// Per trajectory, with input noise: the lower Cholesky factor L of the
    /// covariance of its normalised residuals (rows in time order, outputs
    /// within a time in model order; measured cells only).
    pub whitening: Vec<Option<nalgebra::DMatrix<f64>>>,
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

/// Normalised residuals of one trajectory (measured cells only) and, with
/// `jac`, the Jacobian rows d(prediction / sigma) / d(x0) over the whole
/// initial state (dynamic states, then params); with `noise`, also the
/// output-time index of each residual and the input-noise matrices `M(t)`.
#[allow(clippy::type_complexity)]
fn residuals(
    p: &Predictor,
    t: &FitTrajectory,
    x0: &[f64],
    opts: &FitOptions,
    cols: &[usize],
    jac: bool,
    noise: bool,
) -> Result<(Vec<f64>, Vec<Vec<f64>>, Vec<usize>, Vec<Vec<f64>>), String> {
    let integ = Integration {
        max_step: opts.max_step,
        sensitivities: jac || noise,
        input_noise: if noise {
            opts.input_noise.clone()
        } else {
            None
        },
    };
    let jac = jac || noise;
    let pred = p.predict_with(x0, &t.consts, t.inputs, &t.outputs.t, &integ)?;
    let n = p.state.len();
    let mut r = Vec::new();
    let mut rows = Vec::new();
    let mut at = Vec::new();
    for (k, yk) in pred.outputs.iter().enumerate() {
        for (o, &c) in cols.iter().enumerate() {
            if let Some(m) = t.outputs.values[c][k] {
                let d = m - yk[o];
                let d = if p.angular[o] { wrap(d) } else { d };
                r.push(d / opts.sigma[o]);
                at.push(k);
                if jac {
                    rows.push(
                        pred.jacobians[k][o * n..(o + 1) * n]
                            .iter()
                            .map(|v| v / opts.sigma[o])
                            .collect(),
                    );
                }
            }
        }
    }
    Ok((r, rows, at, pred.noise_m))
}

/// Lower Cholesky factor of `I + A M A^T` for one trajectory's residuals.
fn whitening(
    p: &Predictor,
    rows: &[Vec<f64>],
    at: &[usize],
    noise_m: &[Vec<f64>],
) -> Option<nalgebra::DMatrix<f64>> {
    let nd = p.n_dynamic;
    let nr = rows.len();
    // A_i M(t) for each row i at each needed t is formed on the fly.
    let mut c = nalgebra::DMatrix::<f64>::identity(nr, nr);
    for i in 0..nr {
        for j in 0..=i {
            // M at the earlier of the two times (at[] is non-decreasing).
            let mm = &noise_m[at[j].min(at[i])];
            let mut s = 0.0;
            for a in 0..nd {
                let mut t = 0.0;
                for b in 0..nd {
                    t += mm[a * nd + b] * rows[j][b];
                }
                s += rows[i][a] * t;
            }
            c[(i, j)] += s;
            if i != j {
                c[(j, i)] += s;
            }
        }
    }
    c.cholesky().map(|ch| ch.l())
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

/// The problem's fixed parts: model, data, options, column indices.
struct Problem<'a> {
    p: &'a Predictor,
    trajs: &'a [FitTrajectory<'a>],
    opts: &'a FitOptions,
    lay: Layout,
    cols: Vec<Vec<usize>>,
    /// Per trajectory, the whitening factor L (residuals become L^-1 r).
    whiten: std::cell::RefCell<Vec<Option<nalgebra::DMatrix<f64>>>>,
}

impl Problem<'_> {
    fn new<'a>(
        p: &'a Predictor,
        trajs: &'a [FitTrajectory<'a>],
        opts: &'a FitOptions,
        init_params: &[f64],
        init_states: &[Vec<f64>],
    ) -> Result<Problem<'a>, String> {
        let n_params = p.state.len() - p.n_dynamic;
        if init_params.len() != n_params
            || init_states.len() != trajs.len()
            || init_states.iter().any(|s| s.len() != p.n_dynamic)
        {
            return Err("initial values do not match the model".into());
        }
        if opts.sigma.len() != p.outputs.len() || opts.sigma.iter().any(|s| s.is_nan() || *s <= 0.0)
        {
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
        Ok(Problem {
            p,
            trajs,
            opts,
            lay: Layout {
                n_params,
                n_dyn: p.n_dynamic,
                n_traj: trajs.len(),
            },
            whiten: std::cell::RefCell::new(vec![None; trajs.len()]),
            cols,
        })
    }

    /// Compute the whitening factors at `theta` (no-op without input noise).
    fn set_whitening(&self, theta: &[f64]) -> Result<(), String> {
        if self.opts.input_noise.is_none() {
            return Ok(());
        }
        let mut w = self.whiten.borrow_mut();
        for (k, t) in self.trajs.iter().enumerate() {
            let (_, rows, at, m) = residuals(
                self.p,
                t,
                &self.lay.state_of(theta, k),
                self.opts,
                &self.cols[k],
                true,
                true,
            )?;
            w[k] = whitening(self.p, &rows, &at, &m);
        }
        Ok(())
    }

    fn apply(&self, k: usize, r: Vec<f64>, rows: Vec<Vec<f64>>) -> (Vec<f64>, Vec<Vec<f64>>) {
        let w = self.whiten.borrow();
        let Some(l) = &w[k] else {
            return (r, rows);
        };
        let nr = r.len();
        let rv = nalgebra::DVector::from_vec(r);
        let r2 = l
            .solve_lower_triangular(&rv)
            .map_or_else(|| rv.as_slice().to_vec(), |v| v.as_slice().to_vec());
        if rows.is_empty() {
            return (r2, rows);
        }
        let nc = rows[0].len();
        let jm = nalgebra::DMatrix::from_fn(nr, nc, |i, j| rows[i][j]);
        let j2 = l.solve_lower_triangular(&jm).unwrap_or(jm);
        let rows2 = (0..nr)
            .map(|i| (0..nc).map(|j| j2[(i, j)]).collect())
            .collect();
        (r2, rows2)
    }

    /// Residuals of every trajectory, whitened or (for their root mean
    /// square) not.
    fn residuals_of(&self, theta: &[f64], whiten: bool) -> Result<Vec<Vec<f64>>, String> {
        self.trajs
            .iter()
            .enumerate()
            .map(|(k, t)| {
                let x0 = self.lay.state_of(theta, k);
                let r = residuals(self.p, t, &x0, self.opts, &self.cols[k], false, false)?.0;
                Ok(if whiten {
                    self.apply(k, r, vec![]).0
                } else {
                    r
                })
            })
            .collect()
    }

    fn residuals(&self, theta: &[f64]) -> Result<Vec<Vec<f64>>, String> {
        self.residuals_of(theta, true)
    }

    /// Residuals and the normal equations `J^T J`, `J^T r`, trajectory by
    /// trajectory (a trajectory's initial state touches only its residuals).
    #[allow(clippy::type_complexity)]
    fn normal(&self, theta: &[f64]) -> Result<(Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<f64>), String> {
        let (lay, n_params) = (&self.lay, self.lay.n_params);
        let n = lay.len();
        let mut jtj = vec![vec![0.0; n]; n];
        let mut jtr = vec![0.0; n];
        let mut res = Vec::with_capacity(self.trajs.len());
        for (k, t) in self.trajs.iter().enumerate() {
            // Theta index of each column of the trajectory's Jacobian: its own
            // initial dynamic state, then the shared params.
            let idx: Vec<usize> = (0..lay.n_dyn)
                .map(|i| n_params + k * lay.n_dyn + i)
                .chain(0..n_params)
                .collect();
            let (r0, rows, _, _) = residuals(
                self.p,
                t,
                &lay.state_of(theta, k),
                self.opts,
                &self.cols[k],
                true,
                false,
            )?;
            let (r0, rows) = self.apply(k, r0, rows);
            for (row, r) in rows.iter().zip(&r0) {
                for (a, &ja) in idx.iter().enumerate() {
                    jtr[ja] += row[a] * r;
                    for (b, &jb) in idx.iter().enumerate() {
                        jtj[ja][jb] += row[a] * row[b];
                    }
                }
            }
            res.push(r0);
        }
        Ok((res, jtj, jtr))
    }
}

fn theta_of(init_params: &[f64], init_states: &[Vec<f64>]) -> Vec<f64> {
    let mut theta: Vec<f64> = init_params.to_vec();
    for s in init_states {
        theta.extend_from_slice(s);
    }
    theta
}

/// The inverse of the Fisher information `(J^T J)^-1` at the given values:
/// the Cramér–Rao bound of the model's params and initial states (in the
/// order of [`FitResult::covariance`]) for Gaussian output noise `opts.sigma`.
pub fn crlb(
    p: &Predictor,
    trajs: &[FitTrajectory],
    params: &[f64],
    states: &[Vec<f64>],
    opts: &FitOptions,
) -> Result<Vec<Vec<f64>>, String> {
    let prob = Problem::new(p, trajs, opts, params, states)?;
    prob.set_whitening(&theta_of(params, states))?;
    let (_, jtj, _) = prob.normal(&theta_of(params, states))?;
    inverse(&jtj).ok_or_else(|| {
        "the Fisher information is singular: some unknowns are not identifiable from these data"
            .into()
    })
}

fn inverse(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let inv = m.try_inverse()?;
    Some(
        (0..n)
            .map(|i| (0..n).map(|j| inv[(i, j)]).collect())
            .collect(),
    )
}

/// Fit `params` (the predictor's params) and each trajectory's initial dynamic state.
pub fn fit(
    p: &Predictor,
    trajs: &[FitTrajectory],
    init_params: &[f64],
    init_states: &[Vec<f64>],
    opts: &FitOptions,
) -> Result<FitResult, String> {
    let prob = Problem::new(p, trajs, opts, init_params, init_states)?;
    let (lay, n_params) = (&prob.lay, prob.lay.n_params);
    let mut theta = theta_of(init_params, init_states);
    let cost_of = |r: &[Vec<f64>]| r.iter().flatten().map(|x| x * x).sum::<f64>();
    let n = lay.len();
    let mut lambda = 1e-3;
    let mut iterations = 0;
    prob.set_whitening(&theta)?;
    let (mut res, mut jtj, mut jtr) = prob.normal(&theta)?;
    let mut cost = cost_of(&res);
    // With input noise: a second pass with the covariance at the first estimate.
    let passes = if opts.input_noise.is_some() { 2 } else { 1 };
    for pass in 0..passes {
        if pass > 0 {
            prob.set_whitening(&theta)?;
            (res, jtj, jtr) = prob.normal(&theta)?;
            cost = cost_of(&res);
            lambda = 1e-3;
        }
        loop {
            if iterations >= opts.max_iterations {
                break;
            }
            iterations += 1;
            let mut improved = false;
            let mut moved = false;
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
                if let Ok(r2) = prob.residuals(&cand) {
                    let c2 = cost_of(&r2);
                    if c2 < cost {
                        let rel = (cost - c2) / cost.max(1e-300);
                        theta = cand;
                        cost = c2;
                        lambda = (lambda / 3.0).max(1e-12);
                        improved = rel > opts.cost_tolerance;
                        moved = true;
                        break;
                    }
                }
                lambda *= 4.0;
            }
            if moved {
                (res, jtj, jtr) = prob.normal(&theta)?;
            }
            if !improved {
                break;
            }
        }
    }
    // Covariance: (J^T J)^-1 (residuals are already normalised by sigma).
    let covariance = inverse(&jtj).unwrap_or_else(|| vec![vec![f64::NAN; n]; n]);
    let cov_diag: Vec<f64> = (0..n).map(|i| covariance[i][i].max(0.0).sqrt()).collect();
    let n_res: usize = res.iter().map(Vec::len).sum();
    let raw = prob.residuals_of(&theta, false)?;
    let mut rms = vec![0.0; p.outputs.len()];
    let mut counts = vec![0usize; p.outputs.len()];
    for (k, t) in trajs.iter().enumerate() {
        let mut it = raw[k].iter();
        for row in 0..t.outputs.len() {
            for (o, &c) in prob.cols[k].iter().enumerate() {
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
    let whitening = prob.whiten.borrow().clone();
    Ok(FitResult {
        params: theta[..n_params].to_vec(),
        initial_states: (0..trajs.len())
            .map(|k| theta[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        params_sd: cov_diag[..n_params].to_vec(),
        initial_states_sd: (0..trajs.len())
            .map(|k| cov_diag[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        covariance,
        cost,
        n_residuals: n_res,
        iterations,
        residual_rms,
        whitening,
    })
}
