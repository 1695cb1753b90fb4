//! The least-squares core: one Levenberg–Marquardt loop with one options
//! struct, and the dense solves of its damped normal equations (nalgebra's
//! Cholesky; LU with partial pivoting where round-off or a secant term makes
//! the matrix indefinite). The trajectory-blocked fitter (`fit.rs`) assembles
//! its normal equations by blocks and solves them here; the small dense
//! problems of the paper's estimator and of the diagnosis run [`minimise`].

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
        }
    }
}

/// Where [`minimise`] stopped.
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
    mut normal: impl FnMut(&[f64]) -> (DMatrix<f64>, DVector<f64>),
    chart: impl Fn(&mut [f64]),
    opts: &LmOptions,
) -> LmResult {
    let mut x = x0.to_vec();
    let mut c = cost(&x);
    let mut lambda = opts.initial_damping;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < opts.max_iterations {
        if obsan_expr::cancel_requested() {
            break;
        }
        iterations += 1;
        let (jtj, jtr) = normal(&x);
        let mut improved = false;
        for _ in 0..opts.max_tries {
            let mut a = jtj.clone();
            for i in 0..a.nrows() {
                a[(i, i)] += lambda * jtj[(i, i)].max(opts.min_diagonal);
            }
            let Some(step) = a.cholesky().map(|ch| ch.solve(&jtr)) else {
                lambda *= opts.damping_up_singular;
                continue;
            };
            let mut cand: Vec<f64> = x.iter().zip(step.iter()).map(|(a, b)| a + b).collect();
            chart(&mut cand);
            let c2 = cost(&cand);
            if c2 < c || (opts.accept_equal_cost && c2 <= c) {
                // Relative decrease, as a product so that a zero cost is not divided by.
                improved = c - c2 > opts.relative_cost_tolerance * c.max(1e-300);
                x = cand;
                c = c2;
                lambda = (lambda / opts.damping_down).max(opts.min_damping);
                break;
            }
            lambda *= opts.damping_up;
        }
        if !improved {
            converged = true;
            break;
        }
    }
    LmResult {
        x,
        cost: c,
        iterations,
        converged,
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
