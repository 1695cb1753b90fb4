//! From the observable modes of three or more circles to the calibration
//! parameters (section V-C), the metric step (end of V-C), and the starting
//! state of each trajectory (the initialisation of maximum likelihood).

use crate::circle::Closed;
use crate::error::CalibError::{self, Degenerate};
use crate::ArcData;
use nalgebra::{DMatrix, DVector, SMatrix};
use obsan_data::{wrap, Series, Trajectory};
use obsan_fit::{minimise, LmOptions};

/// phi, psi, eta, delta, xi (eq. 15) with their covariance, when known.
#[derive(Clone, Debug)]
pub struct Calibration {
    pub phi: f64,
    pub psi: f64,
    pub eta: f64,
    pub delta: f64,
    pub xi: f64,
    /// Covariance in the order above (None when the method gives none).
    pub cov: Option<SMatrix<f64, 5, 5>>,
}

impl Calibration {
    pub fn values(&self) -> [f64; 5] {
        [self.phi, self.psi, self.eta, self.delta, self.xi]
    }
    pub(crate) fn from_values(v: &[f64], cov: Option<SMatrix<f64, 5, 5>>) -> Calibration {
        Calibration {
            phi: wrap(v[0]),
            psi: wrap(v[1]),
            eta: v[2],
            delta: v[3],
            xi: v[4],
            cov,
        }
    }
    /// Standard deviations in the order of [`Calibration::values`].
    pub fn sd(&self) -> Option<[f64; 5]> {
        self.cov
            .map(|c| std::array::from_fn(|i| c[(i, i)].max(0.0).sqrt()))
    }

    /// The modes of a circle with ratio q: `(eta_q, xi_q, L)` (eq. 18 and ERRATA's exact L).
    pub fn modes(&self, q: f64) -> (f64, f64, f64) {
        modes(&self.values(), q)
    }
}

/// The names of the calibration parameters, in order.
pub const PARAMS: [&str; 5] = ["phi", "psi", "eta", "delta", "xi"];

fn modes(v: &[f64], q: f64) -> (f64, f64, f64) {
    let (phi, psi, eta, delta, xi) = (v[0], v[1], v[2], v[3], v[4]);
    let eta_q = eta * (1.0 + q * delta);
    let xi_q = xi * (1.0 - q * delta);
    let l = psi - (xi_q - eta_q * phi.sin()).atan2(eta_q * phi.cos());
    (eta_q, xi_q, wrap(l))
}

/// The modes of one trajectory that enter section V-C.
#[derive(Clone, Debug)]
pub struct Modes {
    pub q: f64,
    pub xi_q: f64,
    pub l: f64,
    /// Covariance of (xi_q, L); None weighs xi_q and L by fixed nominal errors.
    pub cov: Option<SMatrix<f64, 2, 2>>,
}

/// Section V-C: xi and delta from xi_q = xi (1 - q delta) (linear), then
/// `eta_x tan(psi - L_q) + eta_y = f_q` made linear in `(P, Q, a = tan psi)`
/// with `P = eta_x a + eta_y`, `Q = eta_y a - eta_x` (multiplied through by
/// `(1 + q delta) cos L_q` so that no row blows up), then weighted
/// Gauss-Newton on all modes at once (least squares when there are more than
/// three trajectories), which also gives the covariance.
pub fn combine(modes_in: &[Modes]) -> Result<Calibration, CalibError> {
    let mut qs: Vec<f64> = modes_in.iter().map(|m| m.q).collect();
    qs.sort_by(f64::total_cmp);
    qs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    if qs.len() < 2 {
        return Err(Degenerate(format!(
            "{} distinct q: xi and delta need two circles with different q, and phi, psi, eta need three (section V-C); nothing can be estimated",
            qs.len()
        )));
    }
    // xi_q = xi - (xi delta) q.
    let n = modes_in.len();
    let a = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { -modes_in[i].q });
    let b = DVector::from_fn(n, |i, _| modes_in[i].xi_q);
    let sol =
        lstsq(&a, &b).ok_or_else(|| Degenerate("xi_q does not determine xi and delta".into()))?;
    let (xi, delta) = (sol[0], sol[1] / sol[0]);
    if qs.len() < 3 {
        return Err(Degenerate(format!(
            "only {} distinct q: xi = {xi:.6} and delta = {delta:.6} are estimated, but phi, psi and eta need a third circle with another q (section V-C)",
            qs.len()
        )));
    }
    // eta_x tan(psi - L) + eta_y = f_q, times (1 + q delta) cos(psi - L):
    // g cos(L) U + g sin(L) W - xi_q cos(L) cos(psi) - xi_q sin(L) sin(psi) = 0
    // with U = eta_x sin psi + eta_y cos psi, W = eta_y sin psi - eta_x cos psi:
    // homogeneous and linear in (U, W, cos psi, sin psi), and regular at psi = 90 deg.
    let a = DMatrix::from_fn(n.max(4), 4, |i, j| {
        if i >= n {
            return 0.0;
        }
        let m = &modes_in[i];
        let g = 1.0 + m.q * delta;
        let (sl, cl) = m.l.sin_cos();
        [g * cl, g * sl, -m.xi_q * cl, -m.xi_q * sl][j]
    });
    if a.iter().any(|x| !x.is_finite()) {
        return Err(Degenerate("the modes are not finite numbers".into()));
    }
    let Some(svd) = nalgebra::SVD::try_new_unordered(a, false, true, SVD_EPS, SVD_MAX_ITERATIONS)
    else {
        return Err(Degenerate(format!(
            "the singular value decomposition of the circles' equations did not converge in {SVD_MAX_ITERATIONS} iterations"
        )));
    };
    let Some(vt) = svd.v_t else {
        return Err(Degenerate(
            "the decomposition returned no right singular vectors".into(),
        ));
    };
    let mut order: Vec<usize> = (0..4).collect();
    order.sort_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]));
    if svd.singular_values[order[1]] < 1e-9 * svd.singular_values[order[3]] {
        return Err(Degenerate(
            "the circles' L do not determine phi, psi, eta (their equations are dependent: use three different q)".into(),
        ));
    }
    let v = vt.row(order[0]);
    let norm = v[2].hypot(v[3]);
    let (u, w, cpsi, spsi) = (v[0] / norm, v[1] / norm, v[2] / norm, v[3] / norm);
    let ex = spsi * u - cpsi * w;
    let ey = cpsi * u + spsi * w;
    let (phi, eta) = (ey.atan2(ex), ex.hypot(ey));
    // The null vector's sign gives psi or psi + pi; the branch is the one where
    // cos(psi - L) has the sign of eta_q cos(phi) (ERRATA's exact L).
    let base = spsi.atan2(cpsi);
    let score = |psi: f64| -> f64 {
        modes_in
            .iter()
            .map(|m| ((1.0 + m.q * delta) * ex) * (psi - m.l).cos())
            .sum()
    };
    let psi = if score(base) >= score(base + std::f64::consts::PI) {
        base
    } else {
        wrap(base + std::f64::consts::PI)
    };
    refine(modes_in, &[phi, psi, eta, delta, xi])
}

/// An iteration cap of nalgebra's SVD (whose default, 0, runs until
/// convergence, which non-finite or extreme entries never reach). Well-posed
/// 4-column problems converge in a few dozen sweeps.
const SVD_MAX_ITERATIONS: usize = 10_000;
/// nalgebra's default tolerance of `svd()`.
const SVD_EPS: f64 = 5.0 * f64::EPSILON;

fn lstsq(a: &DMatrix<f64>, b: &DVector<f64>) -> Option<DVector<f64>> {
    if a.iter().chain(b.iter()).any(|x| !x.is_finite()) {
        return None;
    }
    let svd = nalgebra::SVD::try_new_unordered(a.clone(), true, true, SVD_EPS, SVD_MAX_ITERATIONS)?;
    let smax = svd.singular_values.max();
    if smax == 0.0 || svd.singular_values.min() < 1e-12 * smax {
        return None;
    }
    svd.solve(b, 1e-14 * smax).ok()
}

/// Weighted Gauss-Newton (Levenberg-Marquardt damped) of the modes model.
fn refine(modes_in: &[Modes], init: &[f64; 5]) -> Result<Calibration, CalibError> {
    // Whitening of each trajectory's (xi_q, L) residual.
    let whiten: Vec<SMatrix<f64, 2, 2>> = modes_in
        .iter()
        .map(|m| {
            let cov = m.cov.unwrap_or_else(|| {
                SMatrix::<f64, 2, 2>::from_diagonal(&nalgebra::Vector2::new(
                    (1e-3 * m.xi_q.abs().max(1e-3)).powi(2),
                    (1e-3f64).powi(2),
                ))
            });
            cov.cholesky()
                .and_then(|c| c.l().try_inverse())
                .unwrap_or_else(SMatrix::<f64, 2, 2>::identity)
        })
        .collect();
    let res = |v: &[f64]| -> DVector<f64> {
        let mut r = DVector::zeros(2 * modes_in.len());
        for (i, m) in modes_in.iter().enumerate() {
            let (_, xq, l) = modes(v, m.q);
            let d = nalgebra::Vector2::new(m.xi_q - xq, wrap(m.l - l));
            let w = whiten[i] * d;
            r[2 * i] = w[0];
            r[2 * i + 1] = w[1];
        }
        r
    };
    let jac = |v: &[f64]| -> DMatrix<f64> {
        let r0 = res(v);
        let mut j = DMatrix::zeros(r0.len(), 5);
        for c in 0..5 {
            let h = 1e-7 * v[c].abs().max(1e-3);
            let (mut vp, mut vm) = (v.to_vec(), v.to_vec());
            vp[c] += h;
            vm[c] -= h;
            // r = z - g, so -dr/dv = dg/dv.
            let d = (res(&vm) - res(&vp)) / (2.0 * h);
            j.set_column(c, &d);
        }
        j
    };
    // Section V-C's constants: little damping at first (the start is close),
    // a step that leaves the cost equal accepted.
    let opts = LmOptions {
        max_iterations: 50,
        max_tries: 20,
        initial_damping: 1e-6,
        damping_up: 10.0,
        relative_cost_tolerance: 1e-15,
        accept_equal_cost: true,
        ..LmOptions::default()
    };
    let v = minimise(
        init,
        |v| res(v).norm_squared(),
        |v| {
            let j = jac(v);
            (j.transpose() * &j, j.transpose() * res(v))
        },
        |_| {},
        &opts,
    )
    .x;
    let j = jac(&v);
    let info = j.transpose() * &j;
    let has_cov = modes_in.iter().all(|m| m.cov.is_some());
    let cov = if has_cov {
        info.try_inverse()
            .map(|c| SMatrix::<f64, 5, 5>::from_fn(|i, k| c[(i, k)]))
    } else {
        None
    };
    if v.iter().any(|x| !x.is_finite()) {
        return Err(Degenerate("the calibration diverged".into()));
    }
    Ok(Calibration::from_values(&v, cov))
}

/// The starting state `(mu0, gamma0)` of a circle from its closed form and
/// the calibration (end of section V-C): `Psi1` from (21), `Psi3` and
/// `Psi2` from `A0`, `V0` by inverting (23), then `gamma0`, `mu0` from (21).
pub fn start_state(cal: &Calibration, closed: &Closed, q: f64) -> (f64, f64) {
    let (eta_q, xi_q, _) = cal.modes(q);
    let (a0, v0) = closed.av(0.0);
    let psi1 = (xi_q - eta_q * cal.phi.sin()) / (eta_q * cal.phi.cos());
    let psi3 = (psi1 - a0) / (1.0 + a0 * psi1);
    let psi2 = v0 * (1.0 + psi3 * psi3) / (1.0 + psi1 * psi3);
    // Psi2 = mu eta_q cos(phi) / sin(g), Psi3 = (mu + cos g) / sin g.
    let m = psi2 / (eta_q * cal.phi.cos());
    let sm = m.signum();
    let gamma = sm.atan2(sm * (psi3 - m));
    (m * gamma.sin(), gamma)
}

/// rho, rR, rL, B from one known initial distance d0 (end of section V-C).
#[derive(Clone, Debug)]
pub struct Metric {
    pub rho: f64,
    pub r_right: f64,
    pub r_left: f64,
    pub wheel_base: f64,
}

impl Metric {
    /// From the calibration and the first trajectory's initial mu0.
    pub fn new(cal: &Calibration, mu0: f64, d0: f64) -> Metric {
        let rho = mu0 * d0;
        let r_right = 2.0 * rho * cal.eta;
        Metric {
            rho,
            r_right,
            r_left: cal.delta * r_right,
            wheel_base: r_right / cal.xi,
        }
    }
    pub fn values(&self) -> [f64; 4] {
        [self.rho, self.r_right, self.r_left, self.wheel_base]
    }
}

/// Curve length `s = integral of wR dt` at the measured bearings of a
/// trajectory (inputs hold from their row's t to the next), with the
/// bearings. `input` names the right-wheel column and `output` the bearing.
pub fn arc_data(t: &Trajectory, input: &str, output: &str) -> Result<ArcData, CalibError> {
    let wr = column(&t.inputs, input)?;
    let beta = column(&t.outputs, output)?;
    let mut s = Vec::new();
    let mut b = Vec::new();
    let mut times = Vec::new();
    let (mut acc, mut row) = (0.0, 0usize);
    let mut tcur = t.inputs.t().first().copied().unwrap_or(0.0);
    for (k, &tb) in t.outputs.t().iter().enumerate() {
        let Some(value) = beta[k] else { continue };
        if tb < tcur {
            continue; // before the first input
        }
        while tcur < tb {
            let next = if row + 1 < t.inputs.len() {
                t.inputs.t()[row + 1].min(tb)
            } else {
                tb
            };
            acc += wr[row].unwrap_or(0.0) * (next - tcur);
            tcur = next;
            if row + 1 < t.inputs.len() && t.inputs.t()[row + 1] <= tcur {
                row += 1;
            }
        }
        s.push(acc);
        b.push(value);
        times.push(tb);
    }
    Ok(ArcData {
        s,
        beta: b,
        t: times,
    })
}

fn column<'a>(s: &'a Series, name: &str) -> Result<&'a [Option<f64>], CalibError> {
    s.column(name)
        .ok_or_else(|| CalibError::MissingColumn(name.to_string()))
}

/// `(A, V)` of eq. (23) from the state `(mu, gamma)` of eq. (16) and the
/// calibration, through `Psi1..Psi3` of eq. (21).
pub fn av_from_state(cal: &Calibration, q: f64, mu: f64, gamma: f64) -> (f64, f64) {
    let (eta_q, xi_q, _) = cal.modes(q);
    let psi1 = (xi_q - eta_q * cal.phi.sin()) / (eta_q * cal.phi.cos());
    let psi2 = mu * eta_q * cal.phi.cos() / gamma.sin();
    let psi3 = (mu + gamma.cos()) / gamma.sin();
    (
        (psi1 - psi3) / (1.0 + psi1 * psi3),
        psi2 * (1.0 + psi1 * psi3) / (1.0 + psi3 * psi3),
    )
}
