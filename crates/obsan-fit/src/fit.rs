//! Maximum-likelihood fitting of a model to trajectories: Levenberg–Marquardt
//! over the shared parameters and each trajectory's initial dynamic state,
//! with Gaussian output noise (so least squares of residual / sigma). Angle
//! outputs have their residuals wrapped to (-pi, pi].
//!
//! The Jacobian comes from the forward sensitivity equations (exact
//! derivatives of the model from the engine, integrated with the state),
//! organised by trajectory: a trajectory's initial state affects only its
//! own residuals.

use crate::lsq::{dot, levenberg_marquardt, solve_symmetric, LmModel, LmOptions, LmResult};
use crate::normal::{cancel_point, JacStore, Layout, Normal, Problem, Rows};
use crate::options::{FitOptions, FitTrajectory};
use crate::predict::Predictor;
use crate::whiten::Whitener;
use crate::FitError;

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
    /// Their whole cluster-robust covariance (params x params), whose
    /// diagonal is `params_sd_robust` squared: a combination of correlated
    /// params needs the cross terms (NaN with fewer than two trajectories).
    pub params_cov_robust: Vec<Vec<f64>>,
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

/// The params block of `A^-1 B A^-1 K/(K-1)`: `A = J^T J` (its inverse
/// `cov`), `B = sum_k g_k g_k^T` with `g_k = J_k^T r_k` the score of
/// trajectory `k` (Liang and Zeger, Biometrika 1986; the small-sample factor
/// of Hansen 2007). Each trajectory's own initial state sets its part of
/// `g_k` to zero at the optimum, so with `K` trajectories the variance has
/// about `K - 1` degrees of freedom whatever the number of residuals. With
/// input noise `J` and `r` are the whitened ones, so this is the one robust
/// covariance available there (obsan-diagnose's own sandwich is ordinary
/// least squares only).
fn clustered_cov(cov: &[Vec<f64>], score: &[Vec<f64>], lay: &Layout) -> Vec<Vec<f64>> {
    let (k, n_params) = (score.len(), lay.n_params);
    if k < 2 {
        return vec![vec![f64::NAN; n_params]; n_params];
    }
    // v_ij = sum_k c_ki c_kj K/(K-1), c_k = rows of cov . g_k.
    let f = k as f64 / (k as f64 - 1.0);
    let mut v = vec![vec![0.0; n_params]; n_params];
    for (t, g) in score.iter().enumerate() {
        let idx = lay.columns(t);
        let c: Vec<f64> = (0..n_params)
            .map(|i| idx.iter().zip(g).map(|(&j, gj)| cov[i][j] * gj).sum())
            .collect();
        for (i, row) in v.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += c[i] * c[j] * f;
            }
        }
    }
    v
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
    let jtj = prob.fisher(&theta_of(params, states))?;
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

/// The fit as the core loop's problem ([`LmModel`]): normal equations
/// assembled by trajectory blocks from streamed rows, and NL2SOL's secant
/// model of the residuals' curvature near the optimum.
struct Blocks<'p, 'a> {
    prob: &'p Problem<'a>,
    store: JacStore,
    /// The current point's linearisation.
    cur: Normal,
    /// Gauss-Newton leaves out the residuals' curvature; where it matters
    /// (a weakly determined direction whose noise-driven curvature is
    /// comparable to J^T J) plain steps zig-zag or creep. `s_mat`
    /// approximates it by secant updates; each step uses the model (with
    /// or without it: `augmented`) that predicted the last reduction better.
    s_mat: Vec<Vec<f64>>,
    augmented: bool,
    /// Whether the last iteration's first trial failed: then this one's
    /// first trial is costed before it is linearised too.
    retried: bool,
    /// Converged when the Gauss-Newton distance ([`gn_distance`]) falls
    /// below this.
    step_tolerance: f64,
}

impl LmModel for Blocks<'_, '_> {
    type Error = FitError;
    type Trial = Normal;

    fn begin_iteration(&mut self, _x: &[f64]) -> bool {
        gn_distance(&self.cur) >= self.step_tolerance
    }

    fn normal(&self) -> (&[Vec<f64>], &[f64]) {
        (&self.cur.jtj, &self.cur.jtr)
    }

    fn curvature(&self) -> Option<&[Vec<f64>]> {
        self.augmented.then_some(&self.s_mat[..])
    }

    fn drop_curvature(&mut self) -> bool {
        std::mem::replace(&mut self.augmented, false)
    }

    fn trial(
        &mut self,
        theta: &[f64],
        cand: &mut [f64],
        cost: f64,
        attempt: usize,
    ) -> Result<Option<(f64, Normal)>, FitError> {
        // The first trial point of an iteration is linearised at once:
        // accepted steps (most, near the optimum) then need no second
        // prediction. After a rejection, trials are costed first, and
        // so is the first trial after an iteration that needed one:
        // a fit whose damping cycles (MRCLAM's lag fits rejected the
        // first trial of 15-18 of 22-26 iterations) would otherwise
        // pay for sensitivities it discards.
        if (attempt > 0 || self.retried) && !self.prob.cost(cand).is_ok_and(|c| c < cost) {
            return Ok(None);
        }
        // A rejected trial without a spare overwrote the current
        // rows: they are computed again (the same numbers: the same
        // point and weighting).
        if !self.store.valid {
            self.prob.normal(theta, false, Rows::Keep(&self.store))?;
            self.store.valid = true;
        }
        match self.prob.normal(cand, false, Rows::Trial(&self.store)) {
            Ok(next) => Ok(Some((next.cost, next))),
            Err(_) => {
                self.store.settle(false);
                Ok(None)
            }
        }
    }

    fn reject(&mut self, _next: Normal) {
        self.store.settle(false);
    }

    fn accept(&mut self, next: Normal, step: &[f64], attempt: usize) -> bool {
        self.store.settle(true);
        let cur = &self.cur;
        let jtj_s = mat_vec(&cur.jtj, step);
        // Which model predicted this reduction better (cost = r^T r).
        let actual = cur.cost - next.cost;
        let gn = 2.0 * dot(step, &cur.jtr) - dot(step, &jtj_s);
        let aug = gn - dot(step, &mat_vec(&self.s_mat, step));
        // The secant model only near the optimum (within a few
        // standard deviations): far away the curvature it learnt
        // from long steps misleads.
        self.augmented = (aug - actual).abs() < (gn - actual).abs() && gn_distance(&next) < 3.0;
        // Half-cost gradient g = -J^T r: y = g+ - g, and the part
        // of it that J+^T J+ does not explain, -(J+ - J)^T r+.
        let y: Vec<f64> = cur.jtr.iter().zip(&next.jtr).map(|(a, b)| a - b).collect();
        let ys: Vec<f64> = next
            .old_jt
            .iter()
            .zip(&next.jtr)
            .map(|(a, b)| a - b)
            .collect();
        secant_update(&mut self.s_mat, step, &y, &ys);
        self.cur = next;
        self.retried = attempt > 0;
        // Stalled: a larger step was just rejected (the quadratic
        // model fails beyond this trust region), and within it both
        // the predicted and the actual decrease are below
        // STALL_DECREASE. What is left lies along directions the
        // model cannot reach, and the fit would creep there.
        attempt > 0 && actual < STALL_DECREASE && gn < STALL_DECREASE
    }
}

/// Fit `params` (the predictor's params) and each trajectory's initial dynamic state.
pub fn fit(
    p: &Predictor,
    trajs: &[FitTrajectory],
    init_params: &[f64],
    init_states: &[Vec<f64>],
    opts: &FitOptions,
) -> Result<FitResult, FitError> {
    fit_with(p, trajs, init_params, init_states, opts, None)
}

/// [`fit`], with a spare Jacobian or without (`None`: while it fits in
/// [`crate::normal::SPARE_JACOBIAN_BYTES`]); the estimate is the same
/// either way, number for number.
pub(crate) fn fit_with(
    p: &Predictor,
    trajs: &[FitTrajectory],
    init_params: &[f64],
    init_states: &[Vec<f64>],
    opts: &FitOptions,
    spare: Option<bool>,
) -> Result<FitResult, FitError> {
    let prob = Problem::new(p, trajs, opts, init_params, init_states)?;
    let (lay, n_params) = (&prob.lay, prob.lay.n_params);
    let n = lay.len();
    let lm = LmOptions {
        max_iterations: opts.max_iterations,
        max_tries: 20,
        relative_cost_tolerance: opts.cost_tolerance,
        indefinite_fallback: true,
        ..LmOptions::default()
    };
    // The current point's Jacobian rows, for the secant update (with a
    // spare beside them while two fit in memory, see SPARE_JACOBIAN_BYTES).
    let mut store = JacStore::new(trajs.len(), spare.unwrap_or_else(|| prob.spare_fits()));
    let theta = theta_of(init_params, init_states);
    let cur = prob.normal(&theta, true, Rows::Keep(&store))?;
    store.valid = true;
    let mut run = LmResult {
        x: theta,
        cost: cur.cost,
        iterations: 0,
        converged: false,
    };
    let mut model = Blocks {
        prob: &prob,
        store,
        cur,
        s_mat: vec![vec![0.0; n]; n],
        augmented: false,
        retried: false,
        step_tolerance: opts.step_tolerance,
    };
    // With input noise: a second pass with the covariance at the first
    // estimate (the curvature model carries over: the residuals barely
    // change; the damping starts afresh).
    let passes = if opts.input_noise.is_some() { 2 } else { 1 };
    for pass in 0..passes {
        if pass > 0 {
            model.cur = prob.normal(&run.x, true, Rows::Keep(&model.store))?;
            model.store.valid = true;
            run.cost = model.cur.cost;
        }
        // A pass that only places the whitening for the next one needs the
        // estimate to a tenth of its uncertainty, not more.
        model.step_tolerance = if pass + 1 < passes {
            opts.step_tolerance.max(0.1)
        } else {
            opts.step_tolerance
        };
        run = levenberg_marquardt(&mut model, run, &lm)?;
    }
    let Blocks { store, mut cur, .. } = model;
    let (theta, iterations) = (run.x, run.iterations);
    // A cancel makes every trial above fail, which reads as convergence.
    cancel_point()?;
    // With input noise the last linearisation's weighting was placed at the
    // pass's start, not at the estimate: the covariance (and the cost and
    // log-determinant the likelihood ratios read) are those of the
    // weighting at the estimate itself.
    if opts.input_noise.is_some() {
        drop(store);
        cur = prob.normal(&theta, true, Rows::Drop)?;
    }
    let Normal {
        jtj,
        cost,
        score,
        n_residuals,
        sq_sum,
        counts,
        ..
    } = cur;
    // Covariance: (J^T J)^-1 (residuals are already normalised by sigma).
    let covariance = inverse(&jtj).unwrap_or_else(|| vec![vec![f64::NAN; n]; n]);
    let cov_diag: Vec<f64> = (0..n).map(|i| covariance[i][i].max(0.0).sqrt()).collect();
    let params_cov_robust = clustered_cov(&covariance, &score, lay);
    let params_sd_robust = (0..n_params)
        .map(|i| params_cov_robust[i][i].sqrt())
        .collect();
    let residual_rms = sq_sum
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
        params_sd_robust,
        params_cov_robust,
        initial_states_sd: (0..trajs.len())
            .map(|k| cov_diag[n_params + k * lay.n_dyn..n_params + (k + 1) * lay.n_dyn].to_vec())
            .collect(),
        covariance,
        cost,
        n_residuals,
        iterations,
        residual_rms,
        whitening: prob.into_whiteners(),
    })
}
