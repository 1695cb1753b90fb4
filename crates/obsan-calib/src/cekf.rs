//! CEKF: the EKF of Appendix D on `X = [A_v, V, xi_q, L]`, `A_v = A V`,
//! driven by the curve length `s` (eq. 39), with the Jacobians of eq. (40).
//! The mean is propagated by RK4 over each encoder interval (exact up to
//! RK4's error, where eq. 40 is the Euler step); the covariance by eq. (40),
//! with the encoder error model of [10] as input noise (`var(ds) = K^2 |ds| / r`).

use crate::circle::Closed;
use crate::error::CalibError;
use nalgebra::{Matrix4, Vector4};
use obsan_data::{wrap, Trajectory};
use std::f64::consts::PI;

/// The filter's state at the end of the trajectory.
#[derive(Clone, Debug)]
pub struct CekfResult {
    /// `[A_v, V, xi_q, L]`.
    pub x: Vector4<f64>,
    pub cov: Matrix4<f64>,
}

/// The initial state `[A_v, V, xi_q, L]` at s = 0 from a closed form.
pub fn cekf_start(c: &Closed) -> Vector4<f64> {
    let (a, v) = c.av(0.0);
    Vector4::new(a * v, v, c.xi_q, c.l)
}

fn f(x: &Vector4<f64>) -> Vector4<f64> {
    let (av, v, xq) = (x[0], x[1], x[2]);
    Vector4::new(av * av + v * xq - v * v, av * (2.0 * v - xq), 0.0, 0.0)
}

/// `beta = atan2(-A_v, V) - L + pi/2` (ERRATA.md: exact, no branch sign).
fn h(x: &Vector4<f64>) -> f64 {
    (-x[0]).atan2(x[1]) - x[3] + PI / 2.0
}

/// Run the filter over one trajectory. `input`/`output` name the right-wheel
/// speed and the bearing columns; `sigma_beta` is the bearing noise (rad) and
/// `encoder_var_per_rad` the encoder variance per radian of wheel rotation.
pub fn cekf(
    t: &Trajectory,
    input: &str,
    output: &str,
    x0: Vector4<f64>,
    p0: Matrix4<f64>,
    sigma_beta: f64,
    encoder_var_per_rad: f64,
) -> Result<CekfResult, CalibError> {
    let wr = t
        .inputs
        .column(input)
        .ok_or_else(|| CalibError::MissingInput(input.to_string()))?;
    let beta = t
        .outputs
        .column(output)
        .ok_or_else(|| CalibError::MissingOutput(output.to_string()))?;
    let (mut x, mut p) = (x0, p0);
    let r = sigma_beta * sigma_beta;
    let mut row = 0usize;
    let mut tcur = t.inputs.t().first().copied().unwrap_or(0.0);
    for (k, &tb) in t.outputs.t().iter().enumerate() {
        // Propagate to the bearing's time, one encoder interval at a time.
        while tcur < tb - 1e-12 {
            while row + 1 < t.inputs.len() && t.inputs.t()[row + 1] <= tcur + 1e-12 {
                row += 1;
            }
            let next = if row + 1 < t.inputs.len() {
                t.inputs.t()[row + 1].min(tb)
            } else {
                tb
            };
            let ds = wr[row].unwrap_or(0.0) * (next - tcur);
            // Eq. (40) at the start of the step.
            let (av, v, xq) = (x[0], x[1], x[2]);
            let fx = Matrix4::new(
                1.0 + 2.0 * ds * av,
                ds * (xq - 2.0 * v),
                ds * v,
                0.0,
                ds * (2.0 * v - xq),
                1.0 + 2.0 * ds * av,
                -ds * av,
                0.0,
                0.0,
                0.0,
                1.0,
                0.0,
                0.0,
                0.0,
                0.0,
                1.0,
            );
            let fu = f(&x);
            let k1 = f(&x);
            let k2 = f(&(x + k1 * (ds / 2.0)));
            let k3 = f(&(x + k2 * (ds / 2.0)));
            let k4 = f(&(x + k3 * ds));
            x += (k1 + 2.0 * k2 + 2.0 * k3 + k4) * (ds / 6.0);
            p = fx * p * fx.transpose() + fu * fu.transpose() * (encoder_var_per_rad * ds.abs());
            tcur = next;
            if x.iter().any(|v| !v.is_finite()) {
                return Err(CalibError::FilterDiverged { t: tcur });
            }
        }
        let Some(b) = beta[k] else { continue };
        // Update with the bearing (eq. 39's H).
        let d = x[1] * x[1] + x[0] * x[0];
        let hrow = Vector4::new(-x[1] / d, x[0] / d, 0.0, -1.0);
        let s = (hrow.transpose() * p * hrow)[0] + r;
        let gain = p * hrow / s;
        let innovation = wrap(b - h(&x));
        x += gain * innovation;
        // Joseph form keeps P symmetric positive definite.
        let ikh = Matrix4::identity() - gain * hrow.transpose();
        p = ikh * p * ikh.transpose() + gain * gain.transpose() * r;
    }
    x[3] = wrap(x[3]);
    Ok(CekfResult { x, cov: p })
}
