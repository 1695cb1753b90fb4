//! The paper's simulator (section VI-A, Tables II and III, ERRATA.md): a
//! differential-drive robot (eqs. 1 and 12) with wheel encoders at 50 Hz
//! (error model of [10]) and a bearing sensor observing one feature at the
//! origin, plus the named effects of the discrepancy workflow.

use crate::error::CalibError;
use obsan_data::{wrap, Dataset, DatasetMeta, Series, Trajectory, MIN_OUTPUT_SAMPLES};
use obsan_fit::Rng;
use serde::Serialize;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// How the commanded wheel speed varies with time (the wheels keep the ratio q).
#[derive(Clone, Debug, PartialEq)]
pub enum SpeedProfile {
    Constant,
    /// nu (1 + a sin(2 pi t / period)).
    Sine {
        amplitude: f64,
        period: f64,
    },
    /// nu for `run` seconds, then 0 for `pause` seconds, repeated.
    StopGo {
        run: f64,
        pause: f64,
    },
}

impl std::str::FromStr for SpeedProfile {
    type Err = CalibError;
    /// `constant`, `sine:AMPLITUDE:PERIOD` or `stopgo:RUN:PAUSE` (seconds).
    fn from_str(s: &str) -> Result<SpeedProfile, CalibError> {
        let parts: Vec<&str> = s.split(':').collect();
        let num = |x: &str| x.parse::<f64>().ok().filter(|v| v.is_finite());
        match parts.as_slice() {
            ["constant"] => Ok(SpeedProfile::Constant),
            ["sine", a, p] => match (num(a), num(p)) {
                (Some(amplitude), Some(period)) if period > 0.0 && amplitude.abs() < 1.0 => {
                    Ok(SpeedProfile::Sine { amplitude, period })
                }
                _ => Err(CalibError::SpeedProfile(format!(
                    "{s}: sine:AMPLITUDE:PERIOD needs |AMPLITUDE| < 1 and PERIOD > 0"
                ))),
            },
            ["stopgo", r, p] => match (num(r), num(p)) {
                (Some(run), Some(pause)) if run > 0.0 && pause >= 0.0 => {
                    Ok(SpeedProfile::StopGo { run, pause })
                }
                _ => Err(CalibError::SpeedProfile(format!(
                    "{s}: stopgo:RUN:PAUSE needs RUN > 0 and PAUSE >= 0 (seconds)"
                ))),
            },
            _ => Err(CalibError::SpeedProfile(format!(
                "{s}: expected constant, sine:AMPLITUDE:PERIOD or stopgo:RUN:PAUSE"
            ))),
        }
    }
}

/// Effects hidden in the data for the discrepancy workflow (all off by default).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Effects {
    /// Camera clock minus encoder clock (s): a bearing stamped t was taken at t - offset.
    pub time_offset: f64,
    /// beta_meas = (1 + k) beta.
    pub bearing_scale: f64,
    /// beta_meas = beta + a sin(2 beta).
    pub bearing_distortion: f64,
    /// Each wheel loses the fraction a |omega| (omega in rad/s) of its rotation.
    pub wheel_slip: f64,
    /// The right wheel's radius changes by this amount (m) from the second trajectory on.
    pub radius_change: f64,
    /// beta_meas = beta + b (rad): a constant bearing bias.
    pub bearing_bias: f64,
}

impl Effects {
    /// Set an effect by name (`--effect NAME=VALUE`).
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), CalibError> {
        let slot = match name {
            "time_offset" => &mut self.time_offset,
            "bearing_scale" => &mut self.bearing_scale,
            "bearing_distortion" => &mut self.bearing_distortion,
            "wheel_slip" => &mut self.wheel_slip,
            "radius_change" => &mut self.radius_change,
            "bearing_bias" => &mut self.bearing_bias,
            _ => return Err(CalibError::UnknownEffect(name.to_string())),
        };
        *slot = value;
        Ok(())
    }
}

/// The robot and sensor (Table III defaults).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Robot {
    pub r_right: f64,
    pub r_left: f64,
    pub wheel_base: f64,
    pub rho: f64,
    pub phi: f64,
    pub psi: f64,
}

impl Default for Robot {
    fn default() -> Robot {
        Robot {
            r_right: 0.297,
            r_left: 0.3018,
            wheel_base: 0.485,
            rho: 0.3,
            phi: 0.0,
            psi: PI / 2.0,
        }
    }
}

/// Simulation options (Table II defaults). Fields public: every combination
/// is checked where it matters, by [`simulate`], which refuses a bad one with
/// its [`CalibError`] variant.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    pub robot: Robot,
    /// Commanded wheel-speed ratios, one trajectory each (eq. 17).
    pub q: Vec<f64>,
    /// Right wheel angular speed nu (rad/s).
    pub nu: f64,
    pub profile: SpeedProfile,
    /// Bearing noise standard deviation (rad).
    pub sigma_beta: f64,
    /// Encoder noise K (m^1/2); variance K^2 |increment| / r_nominal.
    pub k_encoder: f64,
    /// Nominal wheel radius (m) of the encoder error model.
    pub r_nominal: f64,
    /// Non-circular path: relative std of each wheel's displacement per segment.
    pub iota: f64,
    /// Number of segments of a loop for `iota`.
    pub segments: usize,
    /// Systematic error of the executed ratio: q + dq.
    pub dq: f64,
    pub encoder_rate: f64,
    pub bearing_rate: f64,
    /// Instead of `bearing_rate`: this many bearings per trajectory, evenly
    /// spread over it (the paper's Tables IV and V count bearings this way).
    pub bearings: Option<usize>,
    /// Initial distance to the feature (m).
    pub d0: f64,
    pub effects: Effects,
    pub seed: u64,
    /// A trajectory stops after one full loop or after this many seconds.
    pub max_duration: f64,
    /// Instead of circles: true wheel speeds (t, wR, wL) of one trajectory.
    pub inputs: Option<Series>,
}

impl Default for SimOptions {
    fn default() -> SimOptions {
        SimOptions {
            robot: Robot::default(),
            q: vec![0.9, 0.0, -1.0],
            nu: 0.168,
            profile: SpeedProfile::Constant,
            sigma_beta: 1f64.to_radians(),
            k_encoder: 0.001,
            r_nominal: 0.3,
            iota: 0.0,
            segments: 10_000,
            dq: 0.0,
            encoder_rate: 50.0,
            bearing_rate: 1.0,
            bearings: None,
            d0: 1.2,
            effects: Effects::default(),
            seed: 1,
            max_duration: 14_400.0,
            inputs: None,
        }
    }
}

/// What the estimators must recover (written to truth.json; never read by them).
/// A plain result record (fields public).
#[derive(Clone, Debug, Serialize)]
pub struct Truth {
    pub phi: f64,
    pub psi: f64,
    pub rho: f64,
    pub r_right: f64,
    pub r_left: f64,
    pub wheel_base: f64,
    pub eta: f64,
    pub delta: f64,
    pub xi: f64,
    pub effects: Effects,
    pub trajectories: Vec<TrajectoryTruth>,
}

/// Per trajectory: the start and the observable modes of a circle.
#[derive(Clone, Debug, Serialize)]
pub struct TrajectoryTruth {
    pub name: String,
    pub q: Option<f64>,
    pub x0: f64,
    pub y0: f64,
    pub theta0: f64,
    pub mu0: f64,
    pub gamma0: f64,
    pub duration: f64,
    /// eq. (18), with the right-wheel radius of this trajectory.
    pub eta_q: Option<f64>,
    pub xi_q: Option<f64>,
    /// L = psi - atan2(xi_q - eta_q sin(phi), eta_q cos(phi)) (ERRATA.md).
    pub l: Option<f64>,
}

impl Robot {
    /// Bearing of the feature at the origin seen from pose (x, y, theta), in (-pi, pi].
    pub fn bearing(&self, x: f64, y: f64, theta: f64) -> f64 {
        let cx = x + self.rho * (theta + self.phi).cos();
        let cy = y + self.rho * (theta + self.phi).sin();
        wrap((-cy).atan2(-cx) - theta - self.phi - self.psi)
    }
}

/// Advance a pose by wheel rotations (exact arc of constant v and omega).
fn step(
    robot: &Robot,
    r_right: f64,
    pose: (f64, f64, f64),
    da_r: f64,
    da_l: f64,
) -> (f64, f64, f64) {
    let ds = (r_right * da_r + robot.r_left * da_l) / 2.0;
    let dth = (r_right * da_r - robot.r_left * da_l) / robot.wheel_base;
    let (x, y, th) = pose;
    if dth.abs() < 1e-12 {
        (x + ds * th.cos(), y + ds * th.sin(), th)
    } else {
        let r = ds / dth;
        (
            x + r * ((th + dth).sin() - th.sin()),
            y - r * ((th + dth).cos() - th.cos()),
            th + dth,
        )
    }
}

fn speed(profile: &SpeedProfile, nu: f64, t: f64) -> f64 {
    match profile {
        SpeedProfile::Constant => nu,
        SpeedProfile::Sine { amplitude, period } => {
            nu * (1.0 + amplitude * (2.0 * PI * t / period).sin())
        }
        SpeedProfile::StopGo { run, pause } => {
            if t.rem_euclid(run + pause) < *run {
                nu
            } else {
                0.0
            }
        }
    }
}

/// Refuse options the simulation cannot honour.
fn check(o: &SimOptions) -> Result<(), CalibError> {
    let rb = &o.robot;
    if [rb.r_right, rb.r_left, rb.wheel_base, rb.rho]
        .iter()
        .any(|v| v.is_nan() || *v <= 0.0)
    {
        return Err(CalibError::RobotNotPositive);
    }
    if o.d0 <= rb.rho {
        return Err(CalibError::FeatureInsideRobot {
            d0: o.d0,
            rho: rb.rho,
        });
    }
    if o.encoder_rate.is_nan()
        || o.bearing_rate.is_nan()
        || o.encoder_rate <= 0.0
        || o.bearing_rate <= 0.0
        || o.encoder_rate < o.bearing_rate
    {
        return Err(CalibError::Rates);
    }
    Ok(())
}

/// One trajectory driven: the encoder readings (as wheel speeds) and the
/// true pose after each encoder step.
struct Drive {
    inputs: Series,
    /// The pose at each encoder time `k dt`, from the start.
    poses: Vec<(f64, f64, f64)>,
    duration: f64,
}

/// Drive one trajectory from `pose0` with the right-wheel radius `r_right`:
/// a circle of ratio `q` (one full loop), or the given inputs (to their end).
fn drive(
    o: &SimOptions,
    q: Option<f64>,
    r_right: f64,
    pose0: (f64, f64, f64),
    rng: &mut Rng,
) -> Result<Drive, CalibError> {
    let rb = &o.robot;
    let dt = 1.0 / o.encoder_rate;
    let mut pose = pose0;
    let mut poses = vec![pose];
    let mut inputs = Series::new(vec!["wR".into(), "wL".into()]);
    let mut turned = 0.0;
    let mut t = 0.0;
    let mut steps = 0u64;
    let loop_guess =
        q.map(|q| 2.0 * PI * rb.wheel_base / (o.nu * (rb.r_right - q * rb.r_left)).abs());
    let seg_len = loop_guess.map_or(f64::INFINITY, |l| l / o.segments as f64);
    let mut seg_index = usize::MAX;
    let (mut fr, mut fl) = (1.0, 1.0);
    loop {
        let (w_r, w_l) = match (&o.inputs, q) {
            (Some(s), _) => {
                let k = s.t().partition_point(|&x| x <= t).saturating_sub(1);
                let get = |c: usize| s.values()[c][k].unwrap_or(0.0);
                (get(0), get(1))
            }
            (None, Some(q)) => {
                let nu = speed(&o.profile, o.nu, t);
                (nu, (q + o.dq) * nu)
            }
            (None, None) => unreachable!("a plan has q or inputs"),
        };
        if o.iota > 0.0 {
            let s = (t / seg_len) as usize;
            if s != seg_index {
                seg_index = s;
                fr = 1.0 + o.iota * rng.normal();
                fl = 1.0 + o.iota * rng.normal();
            }
        }
        let (da_r, da_l) = (w_r * fr * dt, w_l * fl * dt);
        // Encoders measure the wheel rotation (error model of [10]).
        let noise = |rng: &mut Rng, da: f64| {
            da + (o.k_encoder * o.k_encoder * da.abs() / o.r_nominal).sqrt() * rng.normal()
        };
        let (m_r, m_l) = (noise(rng, da_r), noise(rng, da_l));
        inputs.push(t, &[Some(m_r / dt), Some(m_l / dt)]);
        // Slip proportional to the turn rate reduces the rotation that moves the robot.
        let omega = (r_right * da_r - rb.r_left * da_l) / rb.wheel_base / dt;
        let keep = 1.0 - o.effects.wheel_slip * omega.abs();
        let next = step(rb, r_right, pose, da_r * keep, da_l * keep);
        turned += next.2 - pose.2;
        pose = next;
        poses.push(pose);
        steps += 1;
        t = steps as f64 * dt; // not accumulated: clean time stamps
        let done = match (&o.inputs, q) {
            (Some(s), _) => t >= *s.t().last().unwrap_or(&0.0),
            _ => turned.abs() >= 2.0 * PI,
        };
        if done {
            break;
        }
        if t > o.max_duration {
            return Err(CalibError::NoLoop {
                q,
                turned: turned.abs(),
                max_duration: o.max_duration,
                ratio: rb.r_right / rb.r_left,
            });
        }
    }
    Ok(Drive {
        inputs,
        poses,
        duration: t,
    })
}

/// The bearings along a driven trajectory, at the bearing rate (or the
/// requested count), in camera time, with the effects and the noise.
fn bearings(o: &SimOptions, d: &Drive, rng: &mut Rng) -> Series {
    let (rb, dt, duration, poses) = (&o.robot, 1.0 / o.encoder_rate, d.duration, &d.poses);
    let mut outputs = Series::new(vec!["beta".into()]);
    let mut k = 0usize;
    loop {
        let tc = match o.bearings {
            Some(n) if k >= n => break,
            Some(n) => k as f64 * duration / n as f64,
            None => k as f64 / o.bearing_rate,
        };
        if tc > duration + 1e-9 {
            break;
        }
        let te = tc - o.effects.time_offset;
        k += 1;
        if te < 0.0 || te > duration {
            continue;
        }
        // Pose at encoder time te: linear interpolation within the 20 ms step.
        let i = ((te / dt) as usize).min(poses.len() - 2);
        let f = (te - i as f64 * dt) / dt;
        let (a, b) = (poses[i], poses[i + 1]);
        let p = (
            a.0 + f * (b.0 - a.0),
            a.1 + f * (b.1 - a.1),
            a.2 + f * (b.2 - a.2),
        );
        let beta = rb.bearing(p.0, p.1, p.2);
        let e = &o.effects;
        let meas = (1.0 + e.bearing_scale) * beta
            + e.bearing_distortion * (2.0 * beta).sin()
            + e.bearing_bias
            + o.sigma_beta * rng.normal();
        outputs.push(tc, &[Some(wrap(meas))]);
    }
    outputs
}

/// A trajectory's truth: its start and, for a circle, its observable modes
/// (eq. 18 with this trajectory's right-wheel radius; L as in ERRATA.md).
fn trajectory_truth(
    o: &SimOptions,
    name: &str,
    q: Option<f64>,
    r_right: f64,
    pose0: (f64, f64, f64),
    duration: f64,
) -> TrajectoryTruth {
    let rb = &o.robot;
    let (eta, delta, xi) = (
        r_right / (2.0 * rb.rho),
        rb.r_left / r_right,
        r_right / rb.wheel_base,
    );
    let modes = q.map(|q| {
        let (eta_q, xi_q) = (eta * (1.0 + q * delta), xi * (1.0 - q * delta));
        (
            eta_q,
            xi_q,
            rb.psi - (xi_q - eta_q * rb.phi.sin()).atan2(eta_q * rb.phi.cos()),
        )
    });
    let theta_rel = pose0.2 - pose0.1.atan2(pose0.0);
    TrajectoryTruth {
        name: name.to_string(),
        q,
        x0: pose0.0,
        y0: pose0.1,
        theta0: pose0.2,
        mu0: rb.rho / o.d0,
        gamma0: wrap(theta_rel + rb.phi),
        duration,
        eta_q: modes.map(|m| m.0),
        xi_q: modes.map(|m| m.1),
        l: modes.map(|m| wrap(m.2)),
    }
}

/// Simulate the dataset and its truth.
pub fn simulate(o: &SimOptions) -> Result<(Dataset, Truth), CalibError> {
    check(o)?;
    let rb = &o.robot;
    let mut trajectories = Vec::new();
    let mut truths = Vec::new();
    let plans: Vec<(String, Option<f64>)> = match &o.inputs {
        Some(_) => vec![("custom".to_string(), None)],
        None => o.q.iter().map(|q| (format!("q{q}"), Some(*q))).collect(),
    };
    for (index, (name, q)) in plans.iter().enumerate() {
        let mut rng = Rng::new(o.seed.wrapping_mul(1_000_003).wrapping_add(index as u64));
        let r_right = rb.r_right
            + if index >= 1 {
                o.effects.radius_change
            } else {
                0.0
            };
        // Start at distance d0 from the feature, heading so that it lies to the left.
        let pose0 = (o.d0, 0.0, PI / 2.0);
        let driven = drive(o, *q, r_right, pose0, &mut rng)?;
        let outputs = bearings(o, &driven, &mut rng);
        let duration = driven.duration;
        // The readers refuse such a trajectory (data.rs): refuse to write it.
        if outputs.len() < MIN_OUTPUT_SAMPLES {
            return Err(CalibError::TooFewBearings {
                trajectory: name.clone(),
                bearings: outputs.len(),
                duration,
                needed: MIN_OUTPUT_SAMPLES,
            });
        }
        let mut meta = BTreeMap::new();
        if let Some(q) = q {
            meta.insert("q".to_string(), *q);
        }
        truths.push(trajectory_truth(o, name, *q, r_right, pose0, duration));
        trajectories.push(Trajectory {
            name: name.clone(),
            inputs: driven.inputs,
            outputs,
            meta,
        });
    }
    let mut nominal = BTreeMap::new();
    nominal.insert("r_right".to_string(), o.r_nominal);
    nominal.insert("r_left".to_string(), o.r_nominal);
    let mut noise = BTreeMap::new();
    noise.insert("beta".to_string(), o.sigma_beta);
    noise.insert("encoder_k".to_string(), o.k_encoder);
    let meta = DatasetMeta {
        model: Some("systems/calib.sys".into()),
        nominal,
        d0: Some(o.d0),
        noise,
    };
    let truth = Truth {
        phi: rb.phi,
        psi: rb.psi,
        rho: rb.rho,
        r_right: rb.r_right,
        r_left: rb.r_left,
        wheel_base: rb.wheel_base,
        eta: rb.r_right / (2.0 * rb.rho),
        delta: rb.r_left / rb.r_right,
        xi: rb.r_right / rb.wheel_base,
        effects: o.effects.clone(),
        trajectories: truths,
    };
    Ok((Dataset { meta, trajectories }, truth))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `wrap` lands in (-pi, pi] and differs from its argument by a whole
    /// number of turns; in-range angles come back unchanged.
    #[test]
    fn wrap_is_the_angle_modulo_a_turn() {
        let mut rng = Rng::new(5);
        let special = [PI, -PI, 0.0, 3.0 * PI, -3.0 * PI, 1e-300, -1e-300, 1e6];
        for a in special
            .into_iter()
            .chain((0..2000).map(|_| (rng.uniform() - 0.5) * 200.0))
        {
            let w = wrap(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            let turns = (a - w) / (2.0 * PI);
            assert!(
                (turns - turns.round()).abs() < 1e-9 * (1.0 + a.abs()),
                "{a} -> {w}"
            );
            if a > -PI && a <= PI {
                assert_eq!(w, a);
            }
        }
    }
}
