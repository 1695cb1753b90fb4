//! Maximum-likelihood fitting of a model to trajectories: Levenberg–Marquardt
//! over the shared parameters and each trajectory's initial dynamic state,
//! with Gaussian output noise (so least squares of residual / sigma). Angle
//! outputs have their residuals wrapped to (-pi, pi].
//!
//! The Jacobian comes from the forward sensitivity equations (exact
//! derivatives of the model from the engine, integrated with the state),
//! organised by trajectory: a trajectory's initial state affects only its
//! own residuals.

use crate::lsq::{solve_symmetric, LmOptions};
use crate::predict::{Integration, Measured, Predictor};
use crate::whiten::Whitener;
use crate::FitError;
use obsan_data::{wrap, Dataset, Series};

/// One trajectory to fit.
pub struct FitTrajectory<'a> {
    /// For messages.
    pub name: &'a str,
    pub inputs: &'a Series,
    pub outputs: &'a Series,
    /// Values of the predictor's constants (e.g. q).
    pub consts: Vec<f64>,
}

impl<'a> FitTrajectory<'a> {
    /// Every trajectory of a dataset, with the predictor's constants from
    /// each `meta.json` (0 where absent: a constant the dynamics do not use).
    pub fn all(p: &Predictor, data: &'a Dataset) -> Vec<FitTrajectory<'a>> {
        data.trajectories
            .iter()
            .map(|t| FitTrajectory {
                name: &t.name,
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
    /// Or when the undamped Gauss-Newton step from the current estimate is
    /// shorter than this many of its standard deviations
    /// (`sqrt(g^T (J^T J)^-1 g)`, `g = J^T r`, residuals normalised by
    /// sigma): the estimate would move by much less than its uncertainty.
    /// 0 disables.
    pub step_tolerance: f64,
    /// Noise standard deviation of each output (residuals are divided by it).
    pub sigma: Vec<f64>,
    /// Longest integration step (s) over merged input rows; 0 = one step per
    /// input row (see [`Integration::max_step`]).
    pub max_step: f64,
    /// Noise of the measured inputs (see [`Integration::input_noise`]);
    /// when given the fit is generalised least squares: the residuals of a
    /// trajectory are whitened by the Cholesky factor of their covariance
    /// `I + A M A^T` (output noise plus the integrated input noise,
    /// linearised), computed at the start, at the first estimate and at the
    /// final one (where the covariance and the cost are taken).
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
    /// Cluster-robust ("sandwich") standard deviations of the params, the
    /// trajectories being the clusters: right whatever the correlation of
    /// the residuals within a trajectory, since trajectories are
    /// independent (see [`clustered_sd`]). NaN with fewer than two.
    pub params_sd_robust: Vec<f64>,
    pub initial_states_sd: Vec<Vec<f64>>,
    /// The whole covariance, params first, then each trajectory's initial state.
    pub covariance: Vec<Vec<f64>>,
    /// Sum of squared normalised residuals at the estimate.
    pub cost: f64,
    pub n_residuals: usize,
    pub iterations: usize,
    /// Root mean square of the (un-normalised) residuals per output.
    pub residual_rms: Vec<f64>,
    /// Per trajectory, with input noise: the whitener (Cholesky factor L) of
    /// the covariance of its normalised residuals (rows in time order,
    /// outputs within a time in model order; measured cells only).
    pub whitening: Vec<Option<Whitener>>,
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
    /// Theta index of each column of trajectory `k`'s Jacobian: its own
    /// initial dynamic state, then the shared params.
    fn columns(&self, k: usize) -> Vec<usize> {
        (0..self.n_dyn)
            .map(|i| self.n_params + k * self.n_dyn + i)
            .chain(0..self.n_params)
            .collect()
    }
    fn state_of(&self, theta: &[f64], k: usize) -> Vec<f64> {
        let mut x: Vec<f64> =
            theta[self.n_params + k * self.n_dyn..self.n_params + (k + 1) * self.n_dyn].to_vec();
        x.extend_from_slice(&theta[..self.n_params]);
        x
    }
}

/// One trajectory's normalised residuals (measured cells only) and, when
/// asked, its Jacobian rows d(prediction / sigma) / d(x0) over the whole
/// initial state (dynamic states, then params), flat and row-major; with
/// input noise, the whitener's inputs: each row's dynamic-state part `a`
/// and `M(t)` at its output time.
struct Lin {
    r: Vec<f64>,
    rows: Vec<f64>,
    a: Vec<f64>,
    m: Vec<f64>,
}

/// [`Lin`] of one trajectory, from one prediction whose values are consumed
/// per output time (never a row per time kept twice).
fn residuals(
    p: &Predictor,
    t: &FitTrajectory,
    x0: &[f64],
    opts: &FitOptions,
    cells: &Measured,
    jac: bool,
    noise: bool,
) -> Result<Lin, FitError> {
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
    let (n, nd) = (p.state.len(), p.n_dynamic);
    let mut out = Lin {
        r: Vec::with_capacity(cells.len()),
        rows: Vec::with_capacity(if jac { cells.len() * n } else { 0 }),
        a: Vec::with_capacity(if noise { cells.len() * nd } else { 0 }),
        m: Vec::with_capacity(if noise { cells.len() * nd * nd } else { 0 }),
    };
    // The cells of each time in model order, as the residuals are stored.
    p.predict_measured_each(
        x0,
        &t.consts,
        t.inputs,
        cells,
        &integ,
        &mut |k, yk, jk, mk| {
            let (outs, values) = cells.at(k);
            for (i, (&o, &m)) in outs.iter().zip(values).enumerate() {
                let d = m - yk[i];
                let d = if p.angular[o] { wrap(d) } else { d };
                out.r.push(d / opts.sigma[o]);
                if jac {
                    let start = out.rows.len();
                    out.rows
                        .extend(jk[i * n..(i + 1) * n].iter().map(|v| v / opts.sigma[o]));
                    if noise {
                        out.a.extend_from_slice(&out.rows[start..start + nd]);
                        out.m.extend_from_slice(mk);
                    }
                }
            }
        },
    )
    .map_err(|e| FitError::Trajectory {
        name: t.name.to_string(),
        source: Box::new(e),
    })?;
    Ok(out)
}

/// The params block of `A^-1 B A^-1 K/(K-1)`: `A = J^T J` (its inverse
/// `cov`), `B = sum_k g_k g_k^T` with `g_k = J_k^T r_k` the score of
/// trajectory `k` (Liang and Zeger, Biometrika 1986; the small-sample factor
/// of Hansen 2007). Each trajectory's own initial state sets its part of
/// `g_k` to zero at the optimum, so with `K` trajectories the variance has
/// about `K - 1` degrees of freedom whatever the number of residuals.
fn clustered_sd(cov: &[Vec<f64>], score: &[Vec<f64>], lay: &Layout) -> Vec<f64> {
    let (k, n_params) = (score.len(), lay.n_params);
    if k < 2 {
        return vec![f64::NAN; n_params];
    }
    // For each param i: var_i = sum_k (row i of cov . g_k)^2 * K/(K-1).
    let mut var = vec![0.0; n_params];
    for (t, g) in score.iter().enumerate() {
        let idx = lay.columns(t);
        for (i, v) in var.iter_mut().enumerate() {
            let c: f64 = idx.iter().zip(g).map(|(&j, gj)| cov[i][j] * gj).sum();
            *v += c * c;
        }
    }
    let f = k as f64 / (k as f64 - 1.0);
    var.iter().map(|v| (v * f).sqrt()).collect()
}

/// Whiten one trajectory's residuals and Jacobian rows (flat, `nc` columns)
/// in place by `w` (`L^-1 r`, `L^-1 J`, column by column); `None` leaves
/// them as they are.
fn apply(w: Option<&Whitener>, r: &mut [f64], rows: &mut [f64], nc: usize) {
    let Some(l) = w else {
        return;
    };
    l.whiten_in_place(r);
    if rows.is_empty() || nc == 0 {
        return;
    }
    let nr = rows.len() / nc;
    let mut col = vec![0.0; nr];
    for j in 0..nc {
        for (i, c) in col.iter_mut().enumerate() {
            *c = rows[i * nc + j];
        }
        l.whiten_in_place(&mut col);
        for (i, c) in col.iter().enumerate() {
            rows[i * nc + j] = *c;
        }
    }
}

/// Most shared params a fit or a CRLB takes, refused before anything is
/// allocated: the normal equations, their secant model and the covariance
/// are dense in the number of unknowns squared (1,000 params: 8 MB each).
pub const MAX_FIT_PARAMS: usize = 1_000;

/// The problem's fixed parts: model, data, options, column indices.
struct Problem<'a> {
    p: &'a Predictor,
    trajs: &'a [FitTrajectory<'a>],
    opts: &'a FitOptions,
    lay: Layout,
    cols: Vec<Vec<usize>>,
    /// Per trajectory, its measured cells.
    cells: Vec<Measured>,
    /// Per trajectory, the whitening factor L (residuals become L^-1 r).
    /// A lock, not a cell: the trajectories are predicted in parallel.
    whiten: std::sync::RwLock<Vec<Option<Whitener>>>,
}

impl Problem<'_> {
    fn new<'a>(
        p: &'a Predictor,
        trajs: &'a [FitTrajectory<'a>],
        opts: &'a FitOptions,
        init_params: &[f64],
        init_states: &[Vec<f64>],
    ) -> Result<Problem<'a>, FitError> {
        let n_params = p.state.len() - p.n_dynamic;
        if n_params > MAX_FIT_PARAMS {
            return Err(FitError::TooManyParams {
                params: n_params,
                limit: MAX_FIT_PARAMS,
            });
        }
        if init_params.len() != n_params
            || init_states.len() != trajs.len()
            || init_states.iter().any(|s| s.len() != p.n_dynamic)
        {
            return Err(FitError::BadStart);
        }
        if opts.sigma.len() != p.outputs.len() || opts.sigma.iter().any(|s| s.is_nan() || *s <= 0.0)
        {
            return Err(FitError::NoiseLevels);
        }
        let cols: Vec<Vec<usize>> = trajs
            .iter()
            .map(|t| {
                p.outputs
                    .iter()
                    .map(|o| {
                        t.outputs
                            .columns()
                            .iter()
                            .position(|c| c == o)
                            .ok_or_else(|| FitError::MissingOutput(o.clone()))
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
            whiten: std::sync::RwLock::new(vec![None; trajs.len()]),
            cells: trajs.iter().map(|t| Measured::new(p, t.outputs)).collect(),
            cols,
        })
    }

    /// The whiteners. A panic elsewhere while they were written (the lock
    /// poisoned) leaves each entry whole, old or new: they are read as they
    /// are, never taken for white noise.
    fn whiteners(&self) -> std::sync::RwLockReadGuard<'_, Vec<Option<Whitener>>> {
        self.whiten.read().unwrap_or_else(|e| e.into_inner())
    }

    fn whiteners_mut(&self) -> std::sync::RwLockWriteGuard<'_, Vec<Option<Whitener>>> {
        self.whiten.write().unwrap_or_else(|e| e.into_inner())
    }

    /// Run `f` on every trajectory index in parallel (a trajectory's
    /// prediction is independent of the others'), the results in trajectory
    /// order so that every sum over them is the serial one, bit for bit;
    /// the first failing trajectory's error. The caller's cancel flag is
    /// thread-local: it is handed to the workers.
    fn per_trajectory<T: Send>(
        &self,
        f: impl Fn(usize) -> Result<T, FitError> + Sync,
    ) -> Result<Vec<T>, FitError> {
        use rayon::prelude::*;
        let cancel = obsan_expr::cancel_flag();
        let out: Vec<Result<T, FitError>> = (0..self.trajs.len())
            .into_par_iter()
            .map(|k| {
                obsan_expr::with_cancel(cancel.clone(), || {
                    cancel_point()?;
                    f(k)
                })
            })
            .collect();
        out.into_iter().collect()
    }

    /// The cost (sum of squared whitened residuals) at `theta`, without
    /// sensitivities.
    fn cost(&self, theta: &[f64]) -> Result<f64, FitError> {
        let parts = self.per_trajectory(|k| {
            let x0 = self.lay.state_of(theta, k);
            let t = &self.trajs[k];
            let mut r = residuals(self.p, t, &x0, self.opts, &self.cells[k], false, false)?.r;
            apply(self.whiteners()[k].as_ref(), &mut r, &mut [], 0);
            Ok(r.iter().map(|x| x * x).sum::<f64>())
        })?;
        Ok(parts.iter().sum())
    }

    /// Residuals and the normal equations `J^T J`, `J^T r`, trajectory by
    /// trajectory (a trajectory's initial state touches only its residuals),
    /// from one prediction with sensitivities per trajectory. With `refresh`
    /// (and input noise), the whitening is first recomputed at `theta`
    /// from the same prediction. With `keep_raw` the residuals before
    /// whitening are kept too (the final linearisation's, for their root
    /// mean square; without input noise they are `res`).
    fn normal(&self, theta: &[f64], refresh: bool, keep_raw: bool) -> Result<Normal, FitError> {
        let lay = &self.lay;
        let n = lay.len();
        let nc = self.p.state.len();
        let mut jtj = vec![vec![0.0; n]; n];
        let mut jtr = vec![0.0; n];
        let mut res = Vec::with_capacity(self.trajs.len());
        let mut raw = Vec::with_capacity(self.trajs.len());
        let mut jac = Vec::with_capacity(self.trajs.len());
        let mut score = Vec::with_capacity(self.trajs.len());
        let noise = refresh && self.opts.input_noise.is_some();
        // Per trajectory in parallel: its residuals, its whitener (new with
        // `noise`), its whitened residuals and rows; then the sums in order.
        #[allow(clippy::type_complexity)]
        let parts: Vec<(Vec<f64>, Option<Option<Whitener>>, Vec<f64>, Vec<f64>)> = self
            .per_trajectory(|k| {
                let Lin { r, mut rows, a, m } = residuals(
                    self.p,
                    &self.trajs[k],
                    &lay.state_of(theta, k),
                    self.opts,
                    &self.cells[k],
                    true,
                    noise,
                )?;
                let (mut r0, r) = if keep_raw {
                    (r.clone(), r)
                } else {
                    (r, vec![])
                };
                if noise {
                    let w = Whitener::new(self.p.n_dynamic, a, m);
                    apply(w.as_ref(), &mut r0, &mut rows, nc);
                    return Ok((r, Some(w), r0, rows));
                }
                apply(self.whiteners()[k].as_ref(), &mut r0, &mut rows, nc);
                Ok((r, None, r0, rows))
            })?;
        for (k, (r_raw, fresh, r0, rows)) in parts.into_iter().enumerate() {
            if let Some(fresh) = fresh {
                self.whiteners_mut()[k] = fresh;
            }
            let idx = lay.columns(k);
            // The trajectory's score J_k^T r_k (cluster-robust sds).
            let mut g = vec![0.0; nc];
            for (row, r) in rows.chunks_exact(nc.max(1)).zip(&r0) {
                for (a, &ja) in idx.iter().enumerate() {
                    jtr[ja] += row[a] * r;
                    g[a] += row[a] * r;
                    for (b, &jb) in idx.iter().enumerate() {
                        jtj[ja][jb] += row[a] * row[b];
                    }
                }
            }
            raw.push(r_raw);
            res.push(r0);
            jac.push(rows);
            score.push(g);
        }
        let cost = res.iter().flatten().map(|x| x * x).sum();
        Ok(Normal {
            res,
            raw,
            jtj,
            jtr,
            cost,
            jac,
            score,
            nc,
        })
    }
}

/// One linearisation: whitened residuals, their cost, the normal equations,
/// and the residuals before whitening (for their root mean square).
struct Normal {
    res: Vec<Vec<f64>>,
    raw: Vec<Vec<f64>>,
    jtj: Vec<Vec<f64>>,
    jtr: Vec<f64>,
    cost: f64,
    /// Per trajectory: the whitened Jacobian rows, flat (`nc` columns: its
    /// own initial state's, then the params', see [`Layout::columns`]).
    jac: Vec<Vec<f64>>,
    /// Per trajectory: its score `J_k^T r_k`, in the same columns.
    score: Vec<Vec<f64>>,
    nc: usize,
}

impl Normal {
    /// `J^T r` with this linearisation's Jacobian and another point's
    /// residuals (for the secant update of the residual curvature).
    fn jt(&self, res: &[Vec<f64>], lay: &Layout) -> Vec<f64> {
        let mut out = vec![0.0; lay.len()];
        for (k, (rows, r)) in self.jac.iter().zip(res).enumerate() {
            let idx = lay.columns(k);
            for (row, ri) in rows.chunks_exact(self.nc.max(1)).zip(r) {
                for (a, &ja) in idx.iter().enumerate() {
                    out[ja] += row[a] * ri;
                }
            }
        }
        out
    }
}

/// The fit stops when an iteration needed its damping raised (its first
/// trial failed) and the accepted step then lowered the cost, and was
/// predicted to lower it, by less than this (in whitened units: one is the
/// noise variance of one residual). Such a cost change moves any likelihood
/// ratio by less than this too (the diagnosis divides by an inflation of at
/// least 1), against critical values of about 10. Without it, fits whose
/// Gauss-Newton distance sits in near-null directions (MRCLAM windows that
/// stand still, with a lag's states) crept 14-60 iterations at 0.01-0.1 each.
/// A creep with every trial accepted (the damping falling) is not stalled:
/// the calib fits escape such valleys that way.
const STALL_DECREASE: f64 = 0.1;

/// Length of the undamped Gauss-Newton step from this linearisation in
/// standard deviations of the estimate, `sqrt(g^T (J^T J)^-1 g)` with
/// `g = J^T r`: how far the optimum is, whatever the damping did.
fn gn_distance(l: &Normal) -> f64 {
    match solve_symmetric(&l.jtj, &l.jtr) {
        Some(x) => dot(&x, &l.jtr).max(0.0).sqrt(),
        None => f64::INFINITY,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn mat_vec(m: &[Vec<f64>], v: &[f64]) -> Vec<f64> {
    m.iter().map(|row| dot(row, v)).collect()
}

/// The structured secant update of NL2SOL (Dennis, Gay and Welsch, ACM TOMS
/// 1981) of `s_mat`, the approximation of the residuals' own curvature
/// `sum_i r_i d2 r_i` that Gauss-Newton leaves out; `step` the last step, `y`
/// the change of the gradient of half the cost, `ys` the change of that
/// gradient that `J^T J` does not explain. Sized first so that the update
/// does not overshoot. Skipped when `y^T step` is not positive.
fn secant_update(s_mat: &mut [Vec<f64>], step: &[f64], y: &[f64], ys: &[f64]) {
    let n = step.len();
    let yt_s = dot(y, step);
    if yt_s <= 0.0 || !yt_s.is_finite() {
        return;
    }
    let ss = mat_vec(s_mat, step);
    let s_ss = dot(step, &ss);
    if s_ss != 0.0 {
        let tau = (dot(step, ys) / s_ss).abs().min(1.0);
        for row in s_mat.iter_mut() {
            for x in row.iter_mut() {
                *x *= tau;
            }
        }
    }
    let ss = mat_vec(s_mat, step);
    let w: Vec<f64> = ys.iter().zip(&ss).map(|(a, b)| a - b).collect();
    let ws = dot(&w, step);
    for i in 0..n {
        for j in 0..n {
            s_mat[i][j] += (w[i] * y[j] + y[i] * w[j]) / yt_s - ws * y[i] * y[j] / (yt_s * yt_s);
        }
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
) -> Result<Vec<Vec<f64>>, FitError> {
    let prob = Problem::new(p, trajs, opts, params, states)?;
    let jtj = prob.normal(&theta_of(params, states), true, false)?.jtj;
    inverse(&jtj).ok_or(FitError::SingularFisher)
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

/// `Err(Cancelled)` once the caller asked the work to stop (polled per
/// trajectory prediction: the fit's unit of work).
fn cancel_point() -> Result<(), FitError> {
    if obsan_expr::cancel_requested() {
        return Err(FitError::Cancelled);
    }
    Ok(())
}

/// Fit `params` (the predictor's params) and each trajectory's initial dynamic state.
pub fn fit(
    p: &Predictor,
    trajs: &[FitTrajectory],
    init_params: &[f64],
    init_states: &[Vec<f64>],
    opts: &FitOptions,
) -> Result<FitResult, FitError> {
    let prob = Problem::new(p, trajs, opts, init_params, init_states)?;
    let (lay, n_params) = (&prob.lay, prob.lay.n_params);
    let mut theta = theta_of(init_params, init_states);
    let n = lay.len();
    // The core's damping schedule; the loop itself stays here for the secant
    // model and the trajectory blocks.
    let lm = LmOptions {
        max_iterations: opts.max_iterations,
        max_tries: 20,
        relative_cost_tolerance: opts.cost_tolerance,
        ..LmOptions::default()
    };
    let mut lambda = lm.initial_damping;
    let mut iterations = 0;
    let mut cur = prob.normal(&theta, true, false)?;
    // Gauss-Newton leaves out the residuals' curvature; where it matters
    // (a weakly determined direction whose noise-driven curvature is
    // comparable to J^T J) plain steps zig-zag or creep. `s_mat`
    // approximates it by secant updates; each step uses the model (with
    // or without it) that predicted the last reduction better.
    let mut s_mat = vec![vec![0.0; n]; n];
    let mut augmented = false;
    // Whether the last iteration's first trial failed: then this one's
    // first trial is costed before it is linearised too.
    let mut retried = false;
    // With input noise: a second pass with the covariance at the first
    // estimate (the curvature model carries over: the residuals barely change).
    let passes = if opts.input_noise.is_some() { 2 } else { 1 };
    for pass in 0..passes {
        if pass > 0 {
            cur = prob.normal(&theta, true, false)?;
            lambda = lm.initial_damping;
        }
        // A pass that only places the whitening for the next one needs the
        // estimate to a tenth of its uncertainty, not more.
        let step_tolerance = if pass + 1 < passes {
            opts.step_tolerance.max(0.1)
        } else {
            opts.step_tolerance
        };
        loop {
            if iterations >= lm.max_iterations || gn_distance(&cur) < step_tolerance {
                break;
            }
            iterations += 1;
            let mut improved = false;
            for attempt in 0..lm.max_tries {
                let mut a = cur.jtj.clone();
                for (i, row) in a.iter_mut().enumerate() {
                    if augmented {
                        for (x, sx) in row.iter_mut().zip(&s_mat[i]) {
                            *x += sx;
                        }
                    }
                    row[i] += lambda * cur.jtj[i][i].max(lm.min_diagonal);
                }
                let step = solve_symmetric(&a, &cur.jtr).filter(|st| dot(st, &cur.jtr) > 0.0);
                let Some(step) = step else {
                    if augmented {
                        augmented = false;
                    } else {
                        lambda *= lm.damping_up_singular;
                    }
                    continue;
                };
                let cand: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + s).collect();
                // The first trial point of an iteration is linearised at once:
                // accepted steps (most, near the optimum) then need no second
                // prediction. After a rejection, trials are costed first, and
                // so is the first trial after an iteration that needed one:
                // a fit whose damping cycles (MRCLAM's lag fits rejected the
                // first trial of 15-18 of 22-26 iterations) would otherwise
                // pay for sensitivities it discards.
                if (attempt > 0 || retried) && !prob.cost(&cand).is_ok_and(|c| c < cur.cost) {
                    lambda *= lm.damping_up;
                    continue;
                }
                let next = match prob.normal(&cand, false, false) {
                    Ok(next) if next.cost < cur.cost => next,
                    _ => {
                        lambda *= lm.damping_up;
                        continue;
                    }
                };
                let rel = (cur.cost - next.cost) / cur.cost.max(1e-300);
                let jtj_s = mat_vec(&cur.jtj, &step);
                // Which model predicted this reduction better (cost = r^T r).
                let actual = cur.cost - next.cost;
                let gn = 2.0 * dot(&step, &cur.jtr) - dot(&step, &jtj_s);
                let aug = gn - dot(&step, &mat_vec(&s_mat, &step));
                // The secant model only near the optimum (within a few
                // standard deviations): far away the curvature it learnt
                // from long steps misleads.
                augmented = (aug - actual).abs() < (gn - actual).abs() && gn_distance(&next) < 3.0;
                // Half-cost gradient g = -J^T r: y = g+ - g, and the part
                // of it that J+^T J+ does not explain, -(J+ - J)^T r+.
                let y: Vec<f64> = cur.jtr.iter().zip(&next.jtr).map(|(a, b)| a - b).collect();
                let old_jt = cur.jt(&next.res, lay);
                let ys: Vec<f64> = old_jt.iter().zip(&next.jtr).map(|(a, b)| a - b).collect();
                secant_update(&mut s_mat, &step, &y, &ys);
                theta = cand;
                cur = next;
                retried = attempt > 0;
                lambda = (lambda / lm.damping_down).max(lm.min_damping);
                // Stalled: a larger step was just rejected (the quadratic
                // model fails beyond this trust region), and within it both
                // the predicted and the actual decrease are below
                // STALL_DECREASE. What is left lies along directions the
                // model cannot reach, and the fit would creep there.
                let stalled = attempt > 0 && actual < STALL_DECREASE && gn < STALL_DECREASE;
                improved = rel > lm.relative_cost_tolerance && !stalled;
                break;
            }
            if !improved {
                break;
            }
        }
    }
    // A cancel makes every trial above fail, which reads as convergence.
    cancel_point()?;
    // With input noise the last linearisation's weighting was placed at the
    // pass's start, not at the estimate: the covariance (and the cost and
    // log-determinant the likelihood ratios read) are those of the
    // weighting at the estimate itself.
    if opts.input_noise.is_some() {
        cur = prob.normal(&theta, true, true)?;
    }
    let Normal {
        res,
        raw,
        jtj,
        cost,
        score,
        ..
    } = cur;
    // Without input noise nothing was whitened: the raw residuals are `res`.
    let raw = if opts.input_noise.is_some() {
        &raw
    } else {
        &res
    };
    // Covariance: (J^T J)^-1 (residuals are already normalised by sigma).
    let covariance = inverse(&jtj).unwrap_or_else(|| vec![vec![f64::NAN; n]; n]);
    let cov_diag: Vec<f64> = (0..n).map(|i| covariance[i][i].max(0.0).sqrt()).collect();
    let params_sd_robust = clustered_sd(&covariance, &score, lay);
    let n_res: usize = res.iter().map(Vec::len).sum();
    let mut rms = vec![0.0; p.outputs.len()];
    let mut counts = vec![0usize; p.outputs.len()];
    for (k, t) in trajs.iter().enumerate() {
        let mut it = raw[k].iter();
        for row in 0..t.outputs.len() {
            for (o, &c) in prob.cols[k].iter().enumerate() {
                if t.outputs.values()[c][row].is_some() {
                    let Some(r) = it.next() else { break };
                    let r = r * opts.sigma[o];
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
    let whitening = prob.whiteners().clone();
    Ok(FitResult {
        params: theta[..n_params].to_vec(),
        initial_states: (0..trajs.len())
            .map(|k| theta[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        params_sd: cov_diag[..n_params].to_vec(),
        params_sd_robust,
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

#[cfg(test)]
mod tests {
    use super::*;
    use obsan_data::{Series, Trajectory};
    use obsan_model::System;
    use std::collections::BTreeMap;

    /// A damped oscillator driven by a measured input, two outputs (the
    /// second measured at one time in three), two trajectories.
    fn problem() -> (Predictor, Vec<Trajectory>) {
        let src = "system osc\nstate x, v\nparam k, c\ninput u\nx' = v\n\
                   v' = -k*x - c*v + u\noutput y = x\noutput s = v\n";
        let sys = System::parse(src, "osc.sys").unwrap();
        let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
        let trajs = (0..2)
            .map(|k| {
                let mut inputs = Series::new(vec!["u".into()]);
                let mut outputs = Series::new(vec!["y".into(), "s".into()]);
                for i in 0..=60 {
                    let t = i as f64 * 0.05;
                    inputs.push(t, &[Some((t * (1.0 + k as f64)).sin())]);
                    if i > 0 {
                        let y = (1.0 + 0.3 * k as f64) * (-0.2 * t).exp() * (1.3 * t).cos();
                        let s = (i % 3 == 0).then(|| -0.5 * (1.1 * t).sin());
                        outputs.push(t, &[Some(y), s]);
                    }
                }
                Trajectory {
                    name: format!("t{k}"),
                    inputs,
                    outputs,
                    meta: BTreeMap::new(),
                }
            })
            .collect();
        (p, trajs)
    }

    /// The normal equations accumulated trajectory by trajectory from
    /// streamed predictions equal `J^T J`, `J^T r` of the stacked Jacobian:
    /// every measured cell's row built from the kept prediction
    /// (`predict_with`, all outputs at every time) placed in the columns of
    /// theta, whitened (with input noise) by a whitener built from that
    /// prediction's own `M(t)`, and multiplied out densely.
    #[test]
    fn normal_equations_accumulated_per_trajectory_equal_the_stacked_ones() {
        let (p, data) = problem();
        let trajs: Vec<FitTrajectory> = data
            .iter()
            .map(|t| FitTrajectory {
                name: &t.name,
                inputs: &t.inputs,
                outputs: &t.outputs,
                consts: vec![],
            })
            .collect();
        for noise in [None, Some(vec![0.02])] {
            let opts = FitOptions {
                max_iterations: 10,
                cost_tolerance: 1e-12,
                step_tolerance: 0.0,
                sigma: vec![0.05, 0.1],
                max_step: 0.0,
                input_noise: noise.clone(),
            };
            let (params, states) = (vec![1.7, 0.4], vec![vec![1.0, 0.2], vec![1.2, -0.1]]);
            let prob = Problem::new(&p, &trajs, &opts, &params, &states).unwrap();
            let theta = theta_of(&params, &states);
            let lin = prob.normal(&theta, true, false).unwrap();
            let (lay, ns, nd) = (&prob.lay, p.state.len(), p.n_dynamic);
            let n = lay.len();
            let (mut rows, mut res) = (Vec::<f64>::new(), Vec::<f64>::new());
            for (k, t) in trajs.iter().enumerate() {
                let integ = Integration {
                    max_step: 0.0,
                    sensitivities: true,
                    input_noise: noise.clone(),
                };
                let pred = p
                    .predict_with(
                        &lay.state_of(&theta, k),
                        &[],
                        t.inputs,
                        t.outputs.t(),
                        &integ,
                    )
                    .unwrap();
                let (mut rk, mut jk, mut a, mut m) = (vec![], vec![], vec![], vec![]);
                for j in 0..t.outputs.len() {
                    for (o, name) in p.outputs.iter().enumerate() {
                        let Some(v) = t.outputs.column(name).unwrap()[j] else {
                            continue;
                        };
                        rk.push((v - pred.outputs[j][o]) / opts.sigma[o]);
                        let own = &pred.jacobians[j][o * ns..(o + 1) * ns];
                        a.extend(own[..nd].iter().map(|x| x / opts.sigma[o]));
                        if noise.is_some() {
                            m.extend_from_slice(&pred.noise_m[j]);
                        }
                        let mut full = vec![0.0; n];
                        for (c, &col) in lay.columns(k).iter().enumerate() {
                            full[col] = own[c] / opts.sigma[o];
                        }
                        jk.push(full);
                    }
                }
                if noise.is_some() {
                    let w = Whitener::new(nd, a, m).unwrap();
                    w.whiten_in_place(&mut rk);
                    for c in 0..n {
                        let mut col: Vec<f64> = jk.iter().map(|r| r[c]).collect();
                        w.whiten_in_place(&mut col);
                        for (r, x) in jk.iter_mut().zip(col) {
                            r[c] = x;
                        }
                    }
                }
                res.extend(rk);
                rows.extend(jk.into_iter().flatten());
            }
            let j = nalgebra::DMatrix::from_row_slice(res.len(), n, &rows);
            let r = nalgebra::DVector::from_column_slice(&res);
            let (jtj, jtr) = (j.transpose() * &j, j.transpose() * &r);
            let scale = jtj.amax();
            for a in 0..n {
                assert!((lin.jtr[a] - jtr[a]).abs() <= 1e-12 * scale.max(jtr.amax()));
                for b in 0..n {
                    assert!(
                        (lin.jtj[a][b] - jtj[(a, b)]).abs() <= 1e-12 * scale,
                        "{noise:?} ({a}, {b}): {} vs {}",
                        lin.jtj[a][b],
                        jtj[(a, b)]
                    );
                }
            }
            assert!((lin.cost - r.norm_squared()).abs() <= 1e-12 * lin.cost);
            // J^T r of the kept rows against other residuals (the secant
            // update's), and the scores summing to J^T r.
            let other: Vec<Vec<f64>> = lin
                .res
                .iter()
                .map(|v| v.iter().map(|x| 0.5 - x).collect())
                .collect();
            let r2 = nalgebra::DVector::from_iterator(res.len(), other.iter().flatten().copied());
            let jt2 = j.transpose() * r2;
            let got = lin.jt(&other, lay);
            let mut sum = vec![0.0; n];
            for (k, g) in lin.score.iter().enumerate() {
                for (&col, x) in lay.columns(k).iter().zip(g) {
                    sum[col] += x;
                }
            }
            for a in 0..n {
                assert!((got[a] - jt2[a]).abs() <= 1e-12 * scale.max(jt2.amax()));
                assert!((sum[a] - jtr[a]).abs() <= 1e-12 * scale.max(jtr.amax()));
            }
        }
    }
}
