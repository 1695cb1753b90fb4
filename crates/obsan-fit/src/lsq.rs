//! The least-squares core: one Levenberg–Marquardt loop with one options
//! struct, and the dense solves of its damped normal equations (nalgebra's
//! Cholesky; LU with partial pivoting where round-off or a secant term makes
//! the matrix indefinite). One loop, [`levenberg_marquardt`], over an
//! [`LmModel`]: the trajectory-blocked fitter (`fit.rs`) streams its rows
//! into block normal equations and adds a secant model; the small dense
//! problems of the paper's estimator and of the diagnosis run [`minimise`],
//! whose normal equations come from a closure.

use nalgebra::{DMatrix, DVector};

/// Levenberg–Marquardt with Marquardt's scaling: each step solves
/// `(J^T J + lambda diag(max(J^T J_ii, min_diagonal))) step = J^T r`.
#[derive(Clone, Debug, PartialEq)]
pub struct LmOptions {
    /// Outer iterations (one linearisation each).
    pub max_iterations: usize,
    /// Damping increases tried per iteration before giving up.
    pub max_tries: usize,
    /// Damping at the start.
    pub initial_damping: f64,
    /// Damping divided by this after an accepted step ...
    pub damping_down: f64,
    /// ... never below this.
    pub min_damping: f64,
    /// Damping multiplied by this after a step that raised the cost.
    pub damping_up: f64,
    /// Damping multiplied by this when the damped matrix cannot be factorised.
    pub damping_up_singular: f64,
    /// Floor of the diagonal scaling (a column without information).
    pub min_diagonal: f64,
    /// Converged when an accepted step lowers the cost by at most this
    /// fraction of it.
    pub relative_cost_tolerance: f64,
    /// Accept a step that leaves the cost equal (not only lower).
    pub accept_equal_cost: bool,
    /// When the damped matrix is not positive definite (a secant curvature
    /// term can make it so), solve it by LU and keep the step only if it
    /// descends; otherwise only Cholesky, a failure raising the damping.
    pub indefinite_fallback: bool,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iterations: 100,
            max_tries: 30,
            initial_damping: 1e-3,
            damping_down: 3.0,
            min_damping: 1e-12,
            damping_up: 4.0,
            damping_up_singular: 10.0,
            min_diagonal: 1e-12,
            relative_cost_tolerance: 1e-12,
            accept_equal_cost: false,
            indefinite_fallback: false,
        }
    }
}

/// Where [`minimise`] (or a run of the core loop) stopped.
#[derive(Clone, Debug)]
pub struct LmResult {
    pub x: Vec<f64>,
    /// Cost (sum of squared residuals) at `x`.
    pub cost: f64,
    pub iterations: usize,
    /// The last accepted step met the relative cost tolerance (otherwise the
    /// iteration or damping budget, or a cancel, ended the loop).
    pub converged: bool,
}

/// What the one Levenberg–Marquardt loop ([`levenberg_marquardt`]) asks of a
/// problem: its normal equations at the current point (however they are
/// accumulated: `minimise` takes them from a closure, the trajectory fitter
/// streams rows into them), the cost of a trial point, and what to do when a
/// trial is accepted. The loop owns the damping schedule, the trial count,
/// the acceptance and the convergence test.
pub(crate) trait LmModel {
    type Error;
    /// What the model keeps of a trial point until it is accepted or
    /// rejected (its linearisation, say).
    type Trial;
    /// Before each iteration, at the current point `x`: have the normal
    /// equations ready; `false` ends the loop (unconverged) first.
    fn begin_iteration(&mut self, x: &[f64]) -> bool;
    /// `J^T J` and `J^T r` at the current point (`J = -dr/dx`).
    fn normal(&self) -> (&[Vec<f64>], &[f64]);
    /// A term added to `J^T J` before damping (a secant model of the
    /// residuals' curvature), if any.
    fn curvature(&self) -> Option<&[Vec<f64>]> {
        None
    }
    /// The damped matrix could not be solved: `true` when the model dropped
    /// its curvature term (then the trial is repeated at the same damping).
    fn drop_curvature(&mut self) -> bool {
        false
    }
    /// The cost at `cand` (the current point `x` plus a step, which the
    /// model may map onto its chart) with what it keeps of the trial, or
    /// `None` for a trial the model rejects itself (a failed prediction, or
    /// a cheaper test that showed no decrease below the current `cost`).
    /// Trial `attempt` of this iteration, counting from 0.
    fn trial(
        &mut self,
        x: &[f64],
        cand: &mut [f64],
        cost: f64,
        attempt: usize,
    ) -> Result<Option<(f64, Self::Trial)>, Self::Error>;
    /// The trial was accepted: `step` was taken. `true` when the model
    /// sees the fit stalled (the loop then ends as converged).
    fn accept(&mut self, trial: Self::Trial, step: &[f64], attempt: usize) -> bool;
    /// The trial was rejected: its cost was not lower.
    fn reject(&mut self, _trial: Self::Trial) {}
}

/// The one Levenberg–Marquardt loop, from `start` (its cost already known;
/// its iterations count on into `opts.max_iterations`, so that a second
/// pass shares the budget). Each trial solves
/// `(J^T J + S + lambda diag(max(J^T J_ii, min_diagonal))) step = J^T r`
/// with `S` the model's curvature term; see [`LmOptions`] for the schedule.
pub(crate) fn levenberg_marquardt<M: LmModel>(
    model: &mut M,
    start: LmResult,
    opts: &LmOptions,
) -> Result<LmResult, M::Error> {
    let LmResult {
        mut x,
        cost: mut c,
        mut iterations,
        ..
    } = start;
    let mut lambda = opts.initial_damping;
    let mut converged = false;
    while iterations < opts.max_iterations {
        if !model.begin_iteration(&x) {
            break;
        }
        iterations += 1;
        let mut improved = false;
        for attempt in 0..opts.max_tries {
            let Some(step) = damped_step(model, lambda, opts) else {
                if !model.drop_curvature() {
                    lambda *= opts.damping_up_singular;
                }
                continue;
            };
            let mut cand: Vec<f64> = x.iter().zip(&step).map(|(a, b)| a + b).collect();
            let (c2, trial) = match model.trial(&x, &mut cand, c, attempt)? {
                Some((c2, t)) if c2 < c || (opts.accept_equal_cost && c2 <= c) => (c2, t),
                Some((_, t)) => {
                    model.reject(t);
                    lambda *= opts.damping_up;
                    continue;
                }
                None => {
                    lambda *= opts.damping_up;
                    continue;
                }
            };
            let stalled = model.accept(trial, &step, attempt);
            // Relative decrease, as a product so that a zero cost is not divided by.
            improved = c - c2 > opts.relative_cost_tolerance * c.max(1e-300) && !stalled;
            x = cand;
            c = c2;
            lambda = (lambda / opts.damping_down).max(opts.min_damping);
            break;
        }
        if !improved {
            converged = true;
            break;
        }
    }
    Ok(LmResult {
        x,
        cost: c,
        iterations,
        converged,
    })
}

/// The step of the damped normal equations at `lambda`, or `None` when they
/// cannot be solved (see [`LmOptions::indefinite_fallback`]).
fn damped_step<M: LmModel>(model: &M, lambda: f64, opts: &LmOptions) -> Option<Vec<f64>> {
    let (jtj, jtr) = model.normal();
    let curvature = model.curvature();
    let mut a = jtj.to_vec();
    for (i, row) in a.iter_mut().enumerate() {
        if let Some(s) = curvature {
            for (x, sx) in row.iter_mut().zip(&s[i]) {
                *x += sx;
            }
        }
        row[i] += lambda * jtj[i][i].max(opts.min_diagonal);
    }
    if opts.indefinite_fallback {
        // A descent direction only: an indefinite matrix can give a step
        // that raises the cost to first order.
        return solve_symmetric(&a, jtr).filter(|st| dot(st, jtr) > 0.0);
    }
    let n = jtr.len();
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let step = m.cholesky()?.solve(&DVector::from_column_slice(jtr));
    Some(step.iter().copied().collect())
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// [`minimise`]'s problem: normal equations and cost from closures.
struct Closures<C, N, H> {
    cost: C,
    normal: N,
    chart: H,
    jtj: Vec<Vec<f64>>,
    jtr: Vec<f64>,
}

impl<C, N, H> LmModel for Closures<C, N, H>
where
    C: FnMut(&[f64]) -> f64,
    N: FnMut(&[f64]) -> (DMatrix<f64>, DVector<f64>),
    H: Fn(&mut [f64]),
{
    type Error = std::convert::Infallible;
    type Trial = ();
    fn begin_iteration(&mut self, x: &[f64]) -> bool {
        if obsan_expr::cancel_requested() {
            return false;
        }
        let (jtj, jtr) = (self.normal)(x);
        self.jtj = (0..jtj.nrows())
            .map(|i| jtj.row(i).iter().copied().collect())
            .collect();
        self.jtr = jtr.iter().copied().collect();
        true
    }
    fn normal(&self) -> (&[Vec<f64>], &[f64]) {
        (&self.jtj, &self.jtr)
    }
    fn trial(
        &mut self,
        _x: &[f64],
        cand: &mut [f64],
        _cost: f64,
        _attempt: usize,
    ) -> Result<Option<(f64, ())>, Self::Error> {
        (self.chart)(cand);
        Ok(Some(((self.cost)(cand), ())))
    }
    fn accept(&mut self, _trial: (), _step: &[f64], _attempt: usize) -> bool {
        false
    }
}

/// Minimise `cost(x) = |r(x)|^2` from `x0`. `normal(x)` returns `(J^T J, J^T r)`
/// with `J = -dr/dx` (so the step is `+ (J^T J)^-1 J^T r`), `cost(x)` the cost;
/// a non-finite cost counts as higher. `chart` maps each candidate onto the
/// parametrisation's canonical values (an angle wrapped, say) before it is
/// costed; `|_| {}` where there is none. A cancel
/// ([`obsan_expr::cancel_requested`]) ends the loop at once, unconverged:
/// the caller's entry point reports it as its cancelled error.
pub fn minimise(
    x0: &[f64],
    mut cost: impl FnMut(&[f64]) -> f64,
    normal: impl FnMut(&[f64]) -> (DMatrix<f64>, DVector<f64>),
    chart: impl Fn(&mut [f64]),
    opts: &LmOptions,
) -> LmResult {
    let start = LmResult {
        x: x0.to_vec(),
        cost: cost(x0),
        iterations: 0,
        converged: false,
    };
    let mut model = Closures {
        cost,
        normal,
        chart,
        jtj: Vec::new(),
        jtr: Vec::new(),
    };
    match levenberg_marquardt(&mut model, start, opts) {
        Ok(r) => r,
        Err(never) => match never {},
    }
}

/// Solve `a x = b` for a symmetric `a` (row-major): Cholesky when `a` is
/// positive definite, else LU with partial pivoting; `None` when singular or
/// the answer is not finite.
pub fn solve_symmetric(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let m = DMatrix::from_fn(n, n, |i, j| a[i][j]);
    let rhs = DVector::from_column_slice(b);
    let x = match m.clone().cholesky() {
        Some(ch) => ch.solve(&rhs),
        None => m.lu().solve(&rhs)?,
    };
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock's valley as least squares: r = (10 (x2 - x1^2), 1 - x1),
    /// minimum 0 at (1, 1).
    #[test]
    fn minimise_finds_rosenbrocks_minimum() {
        let r = |x: &[f64]| [10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]];
        let cost = |x: &[f64]| r(x).iter().map(|v| v * v).sum::<f64>();
        let normal = |x: &[f64]| {
            // J = -dr/dx.
            let j = DMatrix::from_row_slice(2, 2, &[20.0 * x[0], -10.0, 1.0, 0.0]);
            let rv = DVector::from_column_slice(&r(x));
            (j.transpose() * &j, j.transpose() * rv)
        };
        let out = minimise(&[-1.2, 1.0], cost, normal, |_| {}, &LmOptions::default());
        assert!(out.converged);
        assert!(
            (out.x[0] - 1.0).abs() < 1e-6 && (out.x[1] - 1.0).abs() < 1e-6,
            "{:?}",
            out.x
        );
        assert!(out.cost < 1e-12);
    }

    /// A linear problem `r = b - x` (J = I) whose model counts the loop's
    /// calls and can declare itself stalled: what fit.rs's model relies on.
    struct Linear {
        b: Vec<f64>,
        jtj: Vec<Vec<f64>>,
        jtr: Vec<f64>,
        stall: bool,
        curvature: Option<Vec<Vec<f64>>>,
        dropped: usize,
    }

    impl LmModel for Linear {
        type Error = ();
        type Trial = ();
        fn begin_iteration(&mut self, x: &[f64]) -> bool {
            let n = x.len();
            self.jtj = (0..n)
                .map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect())
                .collect();
            self.jtr = self.b.iter().zip(x).map(|(b, x)| b - x).collect();
            true
        }
        fn normal(&self) -> (&[Vec<f64>], &[f64]) {
            (&self.jtj, &self.jtr)
        }
        fn curvature(&self) -> Option<&[Vec<f64>]> {
            self.curvature.as_deref()
        }
        fn drop_curvature(&mut self) -> bool {
            self.dropped += 1;
            self.curvature.take().is_some()
        }
        fn trial(
            &mut self,
            _x: &[f64],
            cand: &mut [f64],
            _cost: f64,
            _attempt: usize,
        ) -> Result<Option<(f64, ())>, ()> {
            let c = self
                .b
                .iter()
                .zip(&*cand)
                .map(|(b, x)| (b - x).powi(2))
                .sum();
            Ok(Some((c, ())))
        }
        fn accept(&mut self, _trial: (), _step: &[f64], _attempt: usize) -> bool {
            self.stall
        }
    }

    fn linear(stall: bool, curvature: Option<Vec<Vec<f64>>>) -> (Linear, LmResult) {
        let b = vec![3.0, -1.0];
        let start = LmResult {
            cost: b.iter().map(|v| v * v).sum(),
            x: vec![0.0, 0.0],
            iterations: 0,
            converged: false,
        };
        let model = Linear {
            b,
            jtj: Vec::new(),
            jtr: Vec::new(),
            stall,
            curvature,
            dropped: 0,
        };
        (model, start)
    }

    /// The loop's contract with a model: a stall ends it after the accepted
    /// step, converged; a start whose iterations already fill the budget
    /// runs none (fit.rs's second pass shares the budget); a curvature term
    /// that leaves no descent step is dropped and the trial
    /// repeated, not the damping raised (then the first step is the one
    /// without it: damping 1e-3 on J = I gives x = b / 1.001).
    #[test]
    fn the_loop_honours_its_model() {
        let opts = LmOptions {
            indefinite_fallback: true,
            ..LmOptions::default()
        };
        let (mut m, start) = linear(true, None);
        let out = levenberg_marquardt(&mut m, start, &opts).unwrap();
        assert_eq!((out.iterations, out.converged), (1, true));

        let (mut m, mut start) = linear(false, None);
        start.iterations = opts.max_iterations;
        let out = levenberg_marquardt(&mut m, start, &opts).unwrap();
        assert_eq!(
            (out.iterations, out.x.clone()),
            (opts.max_iterations, vec![0.0, 0.0])
        );

        // With -2 I the damped matrix is -0.999 I: its LU step ascends.
        let minus = vec![vec![-2.0, 0.0], vec![0.0, -2.0]];
        let (mut m, start) = linear(true, Some(minus));
        let out = levenberg_marquardt(&mut m, start, &opts).unwrap();
        assert_eq!(m.dropped, 1);
        for (x, b) in out.x.iter().zip([3.0, -1.0]) {
            assert!((x - b / 1.001).abs() < 1e-12, "{:?}", out.x);
        }
    }

    #[test]
    fn solve_symmetric_agrees_with_the_product() {
        // Positive definite, and indefinite (Cholesky fails, LU answers).
        for a in [
            vec![
                vec![4.0, 1.0, 0.5],
                vec![1.0, 3.0, 0.2],
                vec![0.5, 0.2, 2.0],
            ],
            vec![
                vec![1.0, 2.0, 0.0],
                vec![2.0, 1.0, 1.0],
                vec![0.0, 1.0, -3.0],
            ],
        ] {
            let b = [1.0, -2.0, 0.5];
            let x = solve_symmetric(&a, &b).unwrap();
            for (row, bi) in a.iter().zip(b) {
                let ax: f64 = row.iter().zip(&x).map(|(p, q)| p * q).sum();
                assert!((ax - bi).abs() < 1e-12);
            }
        }
        let singular = vec![vec![1.0, 2.0], vec![2.0, 4.0]];
        assert!(solve_symmetric(&singular, &[1.0, 0.0]).is_none());
    }
}
