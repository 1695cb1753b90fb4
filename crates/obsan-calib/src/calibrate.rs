//! `obsan calibrate`: from a dataset of circles to phi, psi, eta, delta, xi
//! (and rho, rR, rL, B with one metric distance) by DET, LS, CEKF or joint
//! maximum likelihood.

use crate::calib::{arc_data, combine, start_state, Calibration, Metric, Modes};
use crate::cekf::{cekf, cekf_start};
use crate::circle::{det, det_at, ls, rms, weights, ArcData, Closed, Det};
use crate::error::CalibError::{self, Degenerate};
use crate::error::{cancel_point, or_cancelled};
use nalgebra::{Matrix4, SMatrix};
use obsan_data::{wrap, Dataset, Trajectory};
use obsan_fit::{
    crlb, fit, input_noise_from_samples, FitOptions, FitResult, FitTrajectory, Predictor,
};
use std::f64::consts::PI;

/// The calibration model, eq. (16): `systems/calib.sys`, compiled in so that
/// the estimators and the shipped file share one source of truth.
const CALIB_SYS: &str = include_str!("../../../systems/calib.sys");

/// `systems/calib.sys` (eq. 16) without restriction (inputs wR, wL), compiled
/// for prediction.
#[allow(clippy::expect_used)] // the shipped calib.sys is tested to parse
pub fn calib_predictor() -> Predictor {
    let sys = obsan_model::System::parse(CALIB_SYS, "systems/calib.sys")
        .expect("the shipped calib.sys parses");
    Predictor::new(
        &sys.normal_form(None, &[])
            .expect("calib.sys has a normal form"),
    )
}

/// The estimator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Det,
    Ls,
    Cekf,
    Ml,
}

impl TrajectoryEstimate {
    /// Standard deviations of xi_q and L, when known.
    pub fn modes_sd(&self) -> Option<[f64; 2]> {
        self.modes_cov
            .map(|c| [c[(0, 0)].max(0.0).sqrt(), c[(1, 1)].max(0.0).sqrt()])
    }
}

impl Method {
    pub fn name(self) -> &'static str {
        match self {
            Method::Det => "det",
            Method::Ls => "ls",
            Method::Cekf => "cekf",
            Method::Ml => "ml",
        }
    }
}

/// How CEKF starts.
#[derive(Clone, Debug, PartialEq)]
pub enum CekfInit {
    /// From DET (the paper's CEKFd), with this relative initial uncertainty.
    Det { relative_sd: f64 },
    /// From a given `[A_v, V, xi_q, L]` per trajectory, with this relative
    /// uncertainty (and `relative_sd` radians on L).
    Given {
        states: Vec<[f64; 4]>,
        relative_sd: f64,
    },
}

/// Options; every tolerance explicit.
#[derive(Clone, Debug)]
pub struct CalibrateOptions {
    pub method: Method,
    /// Initial distance (m) to the feature on the first trajectory.
    pub d0: Option<f64>,
    /// Bearing noise (rad); `None` estimates it from the LS residuals.
    pub sigma_beta: Option<f64>,
    /// Encoder noise K (m^1/2) and the nominal radius of its model.
    pub encoder_k: f64,
    pub r_nominal: f64,
    pub cekf_init: CekfInit,
    /// LS: iterations and relative cost decrease at which to stop.
    pub ls_max_iterations: usize,
    pub ls_tolerance: f64,
    /// ML: iterations, relative cost tolerance, step length in standard
    /// deviations (see `FitOptions::step_tolerance`), longest integration
    /// step (s).
    pub ml_max_iterations: usize,
    pub ml_tolerance: f64,
    pub ml_step_tolerance: f64,
    pub ml_max_step: f64,
    /// ML weighs the residuals by their covariance with the encoder noise
    /// (`encoder_k`) integrated through the model (generalised least
    /// squares): standard deviations then include it, and the estimates
    /// come closer to the bound with encoder noise. Off: bearings only.
    pub ml_input_noise: bool,
    /// When dataset.json states no `encoder_k`: ML estimates the encoder
    /// intensity from the measured wheel speeds ([`EncoderNoise::Estimated`])
    /// and weighs by it as if stated. Off (or `ml_input_noise` off): ML's
    /// sds are the bearings' alone.
    pub ml_estimate_encoder_noise: bool,
    /// Column names: right-wheel speed and bearing.
    pub input: String,
    pub output: String,
}

impl CalibrateOptions {
    /// Defaults, with the noise levels and d0 taken from `dataset.json` when present.
    pub fn for_dataset(data: &Dataset, method: Method) -> CalibrateOptions {
        let m = &data.meta;
        CalibrateOptions {
            method,
            d0: m.d0,
            sigma_beta: m.noise.get("beta").copied().filter(|s| *s > 0.0),
            encoder_k: m.noise.get("encoder_k").copied().unwrap_or(0.0),
            r_nominal: m.nominal.get("r_right").copied().unwrap_or(1.0),
            cekf_init: CekfInit::Det { relative_sd: 0.1 },
            ls_max_iterations: 100,
            ls_tolerance: 1e-12,
            ml_max_iterations: 50,
            ml_tolerance: 1e-10,
            ml_step_tolerance: 1e-2,
            ml_max_step: 0.5,
            ml_input_noise: true,
            ml_estimate_encoder_noise: !m.noise.contains_key("encoder_k"),
            input: "wR".into(),
            output: "beta".into(),
        }
    }
}

/// The wheel-encoder noise behind ML's weighting and standard deviations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EncoderNoise {
    /// dataset.json's `noise.encoder_k` = K (m^1/2): intensity `c = K^2 / r`.
    Stated { k: f64, c: f64 },
    /// Read from the measured wheel speeds (both wheels, every trajectory:
    /// one intensity, `obsan_fit::input_noise_from_samples`), from `samples`
    /// differences; `k = sqrt(c r)` with dataset.json's nominal r (1 if none).
    Estimated { k: f64, c: f64, samples: usize },
    /// None used: the sds are the bearings' alone (no noise stated and none
    /// estimated, stated as 0, or GLS switched off; and every method but ML).
    BearingsOnly,
}

impl EncoderNoise {
    /// The intensity `c` used (0 for bearings only).
    pub fn intensity(&self) -> f64 {
        match *self {
            EncoderNoise::Stated { c, .. } | EncoderNoise::Estimated { c, .. } => c,
            EncoderNoise::BearingsOnly => 0.0,
        }
    }
}

/// Rows of wheel speed averaged per block by the encoder-noise estimate:
/// 0.1 s at the paper's 50 Hz, so that noise correlated over a few rows
/// (resampled or filtered speeds) still counts at its integrated level.
const ENCODER_BLOCK: usize = 5;

/// One trajectory's observable modes (xi_q, L, c, k) and the DET curves.
/// A plain result record (fields public): nothing reads it back as input.
#[derive(Clone, Debug)]
pub struct TrajectoryEstimate {
    pub name: String,
    pub q: f64,
    pub closed: Closed,
    /// Covariance of (xi_q, L), when the method gives one.
    pub modes_cov: Option<SMatrix<f64, 2, 2>>,
    pub rms: f64,
    pub det: Det,
    pub arc: ArcData,
    /// The starting state (mu0, gamma0): from the closed form, or ML's.
    pub start: (f64, f64),
    /// DET's own period reading failed (LS fitted far worse than on the other
    /// trajectories) and was replaced by the period the other circles predict.
    pub period_from_others: bool,
}

/// The outcome of a calibration. A plain result record (fields public):
/// the binary prints it and nothing checks it on the way back in.
#[derive(Clone, Debug)]
pub struct CalibrationReport {
    pub method: Method,
    /// The bearing noise used to weigh the data, and whether it was estimated.
    pub sigma_beta: f64,
    pub sigma_estimated: bool,
    pub trajectories: Vec<TrajectoryEstimate>,
    pub calibration: Calibration,
    pub metric: Option<(Metric, Option<[f64; 4]>)>,
    pub ml: Option<FitResult>,
    /// ML's encoder noise and where it came from (`BearingsOnly` for the other methods).
    pub encoder_noise: EncoderNoise,
}

/// LS on one trajectory from its DET (section V-B weights).
fn ls_trajectory(tr: &mut TrajectoryEstimate, sigma: f64, enc_var: f64, o: &CalibrateOptions) {
    let w = weights(&tr.det.closed, &tr.arc, sigma, enc_var);
    let f = ls(
        &tr.arc,
        &tr.det.closed,
        &w,
        o.ls_max_iterations,
        o.ls_tolerance,
    );
    tr.closed = f.closed;
    tr.rms = f.rms;
    tr.modes_cov = Some(f.cov.fixed_view::<2, 2>(0, 0).into_owned());
}

/// A trajectory whose LS fit is far worse than the others' (RMS over four
/// times their median and over 4 sigma) most likely had its period misread
/// by DET: gross errors in its bearings (a sensor scale error wraps some
/// bearings to the other side of +-pi, for instance) can hide the true
/// period from the scan. With two or more good circles of distinct q,
/// `xi_q = xi (1 - delta q)` (eq. 18) predicts its `xi_q`; DET is rerun at
/// that period ([`det_at`]) and LS from there, and the new fit is kept if it
/// is better. Marks the trajectories it repaired.
fn repair_periods(
    trajs: &mut [TrajectoryEstimate],
    sigma: f64,
    enc_var: f64,
    o: &CalibrateOptions,
) {
    let mut rms: Vec<f64> = trajs.iter().map(|t| t.rms).collect();
    rms.sort_by(f64::total_cmp);
    let Some(&median) = rms.get(rms.len() / 2) else {
        return;
    };
    let limit = (4.0 * median).max(4.0 * sigma);
    let bad: Vec<usize> = (0..trajs.len()).filter(|&k| trajs[k].rms > limit).collect();
    let good: Vec<(f64, f64)> = trajs
        .iter()
        .filter(|t| t.rms <= limit)
        .map(|t| (t.q, t.closed.xi_q))
        .collect();
    let distinct = good.iter().any(|g| (g.0 - good[0].0).abs() > 1e-9);
    if bad.is_empty() || good.len() < 2 || !distinct {
        return;
    }
    // Least squares line xi_q = a + b q through the good circles.
    let n = good.len() as f64;
    let (mq, mx) = (
        good.iter().map(|g| g.0).sum::<f64>() / n,
        good.iter().map(|g| g.1).sum::<f64>() / n,
    );
    let sqq: f64 = good.iter().map(|g| (g.0 - mq).powi(2)).sum();
    let sqx: f64 = good.iter().map(|g| (g.0 - mq) * (g.1 - mx)).sum();
    let b = sqx / sqq;
    let a = mx - b * mq;
    for k in bad {
        let tr = &trajs[k];
        let Ok(d) = det_at(&tr.arc, a + b * tr.q) else {
            continue;
        };
        let mut cand = tr.clone();
        cand.det = d;
        ls_trajectory(&mut cand, sigma, enc_var, o);
        if cand.rms < trajs[k].rms {
            cand.period_from_others = true;
            trajs[k] = cand;
        }
    }
}

/// Calibrate. `predictor` (calib.sys without restriction) is needed by `ml` only.
pub fn calibrate(
    data: &Dataset,
    predictor: Option<&Predictor>,
    o: &CalibrateOptions,
) -> Result<CalibrationReport, CalibError> {
    let enc_var = o.encoder_k * o.encoder_k / o.r_nominal;
    // Per trajectory: DET always (it initialises everything else).
    let mut trajs = Vec::new();
    for t in &data.trajectories {
        cancel_point()?;
        trajs.push(det_trajectory(t, o)?);
    }
    let mut sigma = o.sigma_beta.unwrap_or(f64::NAN);
    let sigma_estimated = o.sigma_beta.is_none();
    // LS per trajectory (also the start of ML).
    let need_ls = matches!(o.method, Method::Ls | Method::Ml);
    if need_ls {
        for pass in 0..2 {
            let s_used = if sigma.is_nan() { 1e-2 } else { sigma };
            for tr in trajs.iter_mut() {
                cancel_point()?;
                ls_trajectory(tr, s_used, enc_var, o);
            }
            if pass == 0 {
                repair_periods(&mut trajs, s_used, enc_var, o);
            }
            let rss: f64 = trajs
                .iter()
                .map(|t| t.rms * t.rms * t.arc.s.len() as f64)
                .sum();
            let count: usize = trajs.iter().map(|t| t.arc.s.len()).sum();
            if pass == 0 && sigma_estimated {
                // sigma from the residuals (4 unknowns per trajectory), then weigh again.
                let dof = count.saturating_sub(4 * trajs.len()).max(1);
                sigma = (rss / dof as f64).sqrt().max(1e-12);
                continue;
            }
            break;
        }
    }
    let modes: Vec<Modes> = match o.method {
        Method::Det => trajs
            .iter()
            .map(|t| Modes {
                q: t.q,
                xi_q: t.closed.xi_q,
                l: t.closed.l,
                cov: None,
            })
            .collect(),
        Method::Ls | Method::Ml => trajs
            .iter()
            .map(|t| Modes {
                q: t.q,
                xi_q: t.closed.xi_q,
                l: t.closed.l,
                cov: t.modes_cov,
            })
            .collect(),
        Method::Cekf => cekf_modes(data, o, sigma, enc_var, &mut trajs).map_err(or_cancelled)?,
    };
    // ML starts from section V-C with the *measured* wheel-speed ratio of
    // each trajectory (integral of wL / integral of wR): a commanded-ratio
    // error (Table VII's dq) then biases neither the start nor the result.
    let modes = if o.method == Method::Ml {
        modes
            .into_iter()
            .zip(&data.trajectories)
            .map(|(m, t)| Modes {
                q: measured_ratio(t, &o.input, "wL").unwrap_or(m.q),
                ..m
            })
            .collect()
    } else {
        modes
    };
    let mut calibration = combine(&modes)?;
    for t in trajs.iter_mut() {
        t.start = start_state(&calibration, &t.closed, t.q);
    }
    let mut ml = None;
    let mut encoder_noise = EncoderNoise::BearingsOnly;
    if o.method == Method::Ml {
        let p = predictor.ok_or(CalibError::NoModel)?;
        encoder_noise = ml_encoder_noise(data, o, enc_var);
        let opts = FitOptions {
            max_iterations: o.ml_max_iterations,
            cost_tolerance: o.ml_tolerance,
            step_tolerance: o.ml_step_tolerance,
            sigma: vec![sigma],
            max_step: o.ml_max_step,
            // Generalised least squares with the encoder noise: the wheel
            // speeds drive the model, so their noise is in the residuals too.
            input_noise: {
                let c = encoder_noise.intensity();
                (c > 0.0).then(|| vec![c, c])
            },
        };
        let (c, r) =
            ml_refine(data, p, &opts, &modes, &mut trajs, &calibration).map_err(or_cancelled)?;
        calibration = c;
        ml = Some(r);
    }
    // Work cut short by a cancel (an unconverged fit, say) is not an answer.
    cancel_point()?;
    let metric =
        o.d0.map(|d0| metric_of(&calibration, &trajs, ml.as_ref(), d0));
    Ok(CalibrationReport {
        method: o.method,
        sigma_beta: sigma,
        sigma_estimated,
        trajectories: trajs,
        calibration,
        metric,
        ml,
        encoder_noise,
    })
}

/// The encoder noise ML weighs by: stated, or (dataset.json silent) read
/// from the wheel speeds, whose rows carry it directly (thousands of
/// samples per circle, where the bearings see it only through the drift
/// of three loops: restricted ML on the bearings gave 0 to 1.5 times the
/// truth, docs/accuracy.md).
fn ml_encoder_noise(data: &Dataset, o: &CalibrateOptions, enc_var: f64) -> EncoderNoise {
    if !o.ml_input_noise {
        return EncoderNoise::BearingsOnly;
    }
    if enc_var > 0.0 {
        return EncoderNoise::Stated {
            k: o.encoder_k,
            c: enc_var,
        };
    }
    if !o.ml_estimate_encoder_noise {
        return EncoderNoise::BearingsOnly;
    }
    let series: Vec<_> = data.trajectories.iter().map(|t| &t.inputs).collect();
    match input_noise_from_samples(&series, &[o.input.as_str(), "wL"], ENCODER_BLOCK) {
        Some(e) if e.c > 0.0 => EncoderNoise::Estimated {
            k: (e.c * o.r_nominal).sqrt(),
            c: e.c,
            samples: e.samples,
        },
        _ => EncoderNoise::BearingsOnly,
    }
}

/// Each trajectory's observable modes `(q, xi_q, L)` by DET + LS on that
/// trajectory alone, or why they cannot be read there: the pieces of a start
/// when section V-C cannot combine every trajectory (a loop that does not
/// close, a period DET cannot find, fewer than three distinct q).
pub fn circle_modes(
    data: &Dataset,
    o: &CalibrateOptions,
) -> Vec<Result<(f64, f64, f64), CalibError>> {
    let enc_var = o.encoder_k * o.encoder_k / o.r_nominal;
    let sigma = o.sigma_beta.unwrap_or(1e-2);
    data.trajectories
        .iter()
        .map(|t| {
            let mut tr = det_trajectory(t, o)?;
            ls_trajectory(&mut tr, sigma, enc_var, o);
            Ok((tr.q, tr.closed.xi_q, tr.closed.l))
        })
        .collect()
}

/// DET on one trajectory (it initialises every method), with the checks that
/// its loop is covered: the nodes and mirror points inside the data.
fn det_trajectory(t: &Trajectory, o: &CalibrateOptions) -> Result<TrajectoryEstimate, CalibError> {
    let q = *t.meta.get("q").ok_or_else(|| CalibError::NoQ {
        trajectory: t.name.clone(),
    })?;
    let arc = arc_data(t, &o.input, &o.output).map_err(|e| e.in_trajectory(&t.name))?;
    let d = det(&arc).map_err(|e| {
        Degenerate(format!(
            "trajectory '{}' (q = {q}): {e}; its xi_q and L are unknown, so phi, psi, eta, delta, xi cannot all be estimated",
            t.name
        ))
    })?;
    // Coverage: DET needs the node and the mirror points inside the data.
    // Gaps between bearings, and before the first / after the last one
    // (the trajectory's whole curve length from the encoders).
    let s_total = integral(t, &o.input).unwrap_or(0.0);
    let mut gap: f64 = arc.s[0].max(s_total - arc.s[arc.s.len() - 1]);
    for w in arc.s.windows(2) {
        gap = gap.max(w[1] - w[0]);
    }
    if gap > d.period.min(s_total.abs()) / 4.0 {
        return Err(Degenerate(format!(
            "trajectory '{}' (q = {q}): no bearing over {:.0}% of the loop (the feature is out of view): the nodes and mirror points of the observation function are not observed, so xi_q, L and k cannot be estimated from it",
            t.name,
            100.0 * gap / d.period
        )));
    }
    let span = arc.s.last().copied().unwrap_or(0.0) - arc.s[0];
    if span < 0.75 * d.period {
        return Err(Degenerate(format!(
            "trajectory '{}' (q = {q}): the data cover {:.0}% of a loop; one whole loop is needed to read xi_q (eq. 35)",
            t.name,
            100.0 * span / d.period
        )));
    }
    Ok(TrajectoryEstimate {
        name: t.name.clone(),
        q,
        closed: d.closed,
        modes_cov: None,
        rms: rms(&d.closed, &arc),
        det: d,
        arc,
        start: (f64::NAN, f64::NAN),
        period_from_others: false,
    })
}

/// Joint maximum likelihood (through obsan-fit) from section V-C's
/// `calibration`; each trajectory's start, closed form and modes covariance
/// updated from the fit.
fn ml_refine(
    data: &Dataset,
    p: &Predictor,
    opts: &FitOptions,
    modes: &[Modes],
    trajs: &mut [TrajectoryEstimate],
    calibration: &Calibration,
) -> Result<(Calibration, FitResult), CalibError> {
    let fts = FitTrajectory::all(p, data);
    // Each trajectory's (mu0, gamma0) from its closed form and a calibration.
    let states_for = |c: &Calibration| -> Vec<Vec<f64>> {
        trajs
            .iter()
            .zip(modes)
            .map(|(t, m)| {
                let (mu0, g0) = start_state(c, &t.closed, m.q);
                vec![mu0, g0]
            })
            .collect()
    };
    let states = states_for(calibration);
    let mut r = fit(p, &fts, &calibration.values(), &states, opts).map_err(CalibError::Ml)?;
    // Section V-C can fail (a nearly straight "circle": q + dq close to
    // rR / rL); it then says eta ~ 0, a sensor metres from the axle, and
    // ML from there can stop in a wrong minimum. Screen a small grid of
    // (phi, eta) starts (xi and delta from V-C, which stay good) with a
    // few iterations each, and finish from the best if it beats the fit.
    if calibration.eta.abs() < 0.02 {
        let screen = FitOptions {
            max_iterations: 4,
            input_noise: None,
            ..opts.clone()
        };
        let mut best: Option<FitResult> = None;
        for phi0 in [0.0, PI / 2.0, PI, -PI / 2.0] {
            for eta0 in [0.3, 1.0] {
                let c = Calibration {
                    phi: phi0,
                    eta: eta0,
                    ..*calibration
                };
                let st = states_for(&c);
                if let Ok(f) = fit(p, &fts, &c.values(), &st, &screen) {
                    if best.as_ref().is_none_or(|b| f.cost < b.cost) {
                        best = Some(f);
                    }
                }
            }
        }
        if let Some(b) = best {
            // (The screen's cost has no input noise: compare full fits.)
            if let Ok(f) = fit(p, &fts, &b.params, &b.initial_states, opts) {
                if f.cost < r.cost {
                    r = f;
                }
            }
        }
    }
    let mut cov = SMatrix::<f64, 5, 5>::from_fn(|i, j| r.covariance[i][j]);
    let (mut phi, mut eta) = (r.params[0], r.params[2]);
    if eta < 0.0 {
        // (phi + pi, -eta) gives eq. (16) exactly (cos and sin of
        // gamma - phi change sign with eta), so the likelihood cannot
        // tell them apart; eta = rR / (2 rho) > 0 picks the physical one.
        phi += PI;
        eta = -eta;
        for k in 0..5 {
            if k != 2 {
                cov[(2, k)] = -cov[(2, k)];
                cov[(k, 2)] = -cov[(k, 2)];
            }
        }
    }
    let calibration = Calibration {
        phi: wrap(phi),
        psi: wrap(r.params[1]),
        eta,
        delta: r.params[3],
        xi: r.params[4],
        cov: Some(cov),
    };
    for (k, t) in trajs.iter_mut().enumerate() {
        t.start = (r.initial_states[k][0], r.initial_states[k][1]);
        let (_, xq, l) = calibration.modes(t.q);
        t.closed.xi_q = xq;
        t.closed.l = l;
        // Covariance of (xi_q, L) from ML's by the delta method.
        let v = calibration.values();
        let mut j = SMatrix::<f64, 2, 5>::zeros();
        for c in 0..5 {
            let h = 1e-7 * v[c].abs().max(1e-3);
            let (mut vp, mut vm) = (v, v);
            vp[c] += h;
            vm[c] -= h;
            let cp = Calibration::from_values(&vp, None).modes(t.q);
            let cm = Calibration::from_values(&vm, None).modes(t.q);
            j[(0, c)] = (cp.1 - cm.1) / (2.0 * h);
            j[(1, c)] = wrap(cp.2 - cm.2) / (2.0 * h);
        }
        t.modes_cov = Some(j * cov * j.transpose());
    }
    Ok((calibration, r))
}

/// The CEKF of Appendix D on every trajectory, started from DET or from
/// given states: each one's modes `(xi_q, L)` with their covariance.
fn cekf_modes(
    data: &Dataset,
    o: &CalibrateOptions,
    sigma: f64,
    enc_var: f64,
    trajs: &mut [TrajectoryEstimate],
) -> Result<Vec<Modes>, CalibError> {
    if sigma.is_nan() {
        return Err(CalibError::NoBearingNoise);
    }
    let mut out = Vec::new();
    for (i, (tr, t)) in trajs.iter_mut().zip(&data.trajectories).enumerate() {
        let (x0, rel) = match &o.cekf_init {
            CekfInit::Det { relative_sd } => (cekf_start(&tr.det.closed), *relative_sd),
            CekfInit::Given {
                states,
                relative_sd,
            } => {
                let s = states.get(i).ok_or_else(|| CalibError::NoCekfStart {
                    trajectory: tr.name.clone(),
                })?;
                (nalgebra::Vector4::from(*s), *relative_sd)
            }
        };
        let p0 = Matrix4::from_diagonal(&nalgebra::Vector4::new(
            (rel * x0[0].abs().max(0.05)).powi(2),
            (rel * x0[1].abs().max(0.05)).powi(2),
            (rel * x0[2].abs()).powi(2),
            rel.max(0.05).powi(2),
        ));
        let r = cekf(t, &o.input, &o.output, x0, p0, sigma, enc_var)
            .map_err(|e| e.in_trajectory(&tr.name))?;
        tr.closed.xi_q = r.x[2];
        tr.closed.l = r.x[3];
        tr.modes_cov = Some(r.cov.fixed_view::<2, 2>(2, 2).into_owned());
        out.push(Modes {
            q: tr.q,
            xi_q: r.x[2],
            l: r.x[3],
            cov: tr.modes_cov,
        });
    }
    Ok(out)
}

/// The metric step from d0 on trajectory 0, with standard deviations by the
/// delta method from ML's joint covariance when there is one.
fn metric_of(
    calibration: &Calibration,
    trajs: &[TrajectoryEstimate],
    ml: Option<&FitResult>,
    d0: f64,
) -> (Metric, Option<[f64; 4]>) {
    let m = Metric::new(calibration, trajs[0].start.0, d0);
    // Standard deviations by the delta method from ML's joint covariance.
    let sd = ml.map(|r| {
        // Unknowns: eta (2), delta (3), xi (4), mu0 of trajectory 0 (index 5).
        let idx = [2usize, 3, 4, 5];
        let (eta, delta, xi) = (calibration.eta, calibration.delta, calibration.xi);
        let rho = m.rho;
        let grads: [[f64; 4]; 4] = [
            [0.0, 0.0, 0.0, d0],
            [2.0 * rho, 0.0, 0.0, 2.0 * d0 * eta],
            [
                2.0 * rho * delta,
                2.0 * rho * eta,
                0.0,
                2.0 * d0 * eta * delta,
            ],
            [
                2.0 * rho / xi,
                0.0,
                -2.0 * rho * eta / (xi * xi),
                2.0 * d0 * eta / xi,
            ],
        ];
        std::array::from_fn(|g| {
            let mut v = 0.0;
            for a in 0..4 {
                for b in 0..4 {
                    v += grads[g][a] * grads[g][b] * r.covariance[idx[a]][idx[b]];
                }
            }
            v.max(0.0).sqrt()
        })
    });
    (m, sd)
}

/// `integral of c dt` over a trajectory's inputs.
fn integral(t: &Trajectory, c: &str) -> Option<f64> {
    let v = t.inputs.column(c)?;
    Some(
        (0..t.inputs.len().saturating_sub(1))
            .map(|k| v[k].unwrap_or(0.0) * (t.inputs.t()[k + 1] - t.inputs.t()[k]))
            .sum(),
    )
}

/// `integral of wL dt / integral of wR dt` over a trajectory.
fn measured_ratio(t: &Trajectory, right: &str, left: &str) -> Option<f64> {
    let (r, l) = (t.inputs.column(right)?, t.inputs.column(left)?);
    let (mut sr, mut sl) = (0.0, 0.0);
    for k in 0..t.inputs.len().saturating_sub(1) {
        let dt = t.inputs.t()[k + 1] - t.inputs.t()[k];
        sr += r[k].unwrap_or(0.0) * dt;
        sl += l[k].unwrap_or(0.0) * dt;
    }
    (sr.abs() > 0.0).then(|| sl / sr)
}

/// One trajectory's curves for the paper's Figures 5-7, against the curve
/// length s (radians of right-wheel rotation, eq. 17).
#[derive(Clone, Debug)]
pub struct FigureCurves {
    pub name: String,
    pub q: f64,
    pub s: Vec<f64>,
    /// The measured bearings.
    pub observed: Vec<f64>,
    /// The closed-form observation function (eqs. 26-31) by DET and by LS.
    pub det: Vec<f64>,
    pub ls: Vec<f64>,
    /// The bearings predicted by joint maximum likelihood (eq. 16 driven by
    /// the measured wheel speeds); `None` when ML did not converge.
    pub ml: Option<Vec<f64>>,
    /// The nodes inside the data (Algorithm 1's node and those half a
    /// period away), as (s, bearing of the DET curve).
    pub nodes: Vec<(f64, f64)>,
    /// sigma(s_c) of Algorithm 1 and its minimiser.
    pub sigma_curve: Vec<(f64, f64)>,
    pub node: f64,
}

impl CalibrationReport {
    /// The curves of Figures 5-7 for every trajectory. Each figure compares DET,
    /// LS and ML: this report (a calibration of `data` with options `o`) is reused
    /// when it is the LS or ML run, the other runs are made here.
    pub fn figure_curves(
        &self,
        data: &Dataset,
        predictor: &Predictor,
        o: &CalibrateOptions,
    ) -> Result<Vec<FigureCurves>, CalibError> {
        let done = self;
        let with = |m: Method| CalibrateOptions {
            method: m,
            ..o.clone()
        };
        let ls_own;
        let ls_run = if done.method == Method::Ls {
            done
        } else {
            ls_own = calibrate(data, None, &with(Method::Ls))?;
            &ls_own
        };
        // ML may fail where LS does not (e.g. a poor start); the figure then
        // shows DET and LS only.
        let ml_own;
        let ml_run = if done.method == Method::Ml {
            Some(done)
        } else {
            ml_own = calibrate(data, Some(predictor), &with(Method::Ml)).ok();
            ml_own.as_ref()
        };
        let mut out = Vec::new();
        for (k, (tr, t)) in ls_run
            .trajectories
            .iter()
            .zip(&data.trajectories)
            .enumerate()
        {
            let curve = |c: &Closed| tr.arc.s.iter().map(|&s| c.beta(s)).collect::<Vec<f64>>();
            let ml = ml_run.and_then(|r| {
                let f = r.ml.as_ref()?;
                let consts: Vec<f64> = predictor
                    .consts
                    .iter()
                    .map(|c| t.meta.get(c).copied().unwrap_or(0.0))
                    .collect();
                let mut x0 = f.initial_states[k].clone();
                x0.extend(&f.params);
                let y = predictor.predict(&x0, &consts, &t.inputs, &tr.arc.t).ok()?;
                let col = predictor.outputs.iter().position(|n| *n == o.output)?;
                let v: Vec<f64> = y.iter().map(|r| wrap(r[col])).collect();
                (v.len() == tr.arc.s.len()).then_some(v)
            });
            let d = &tr.det;
            let (s_lo, s_hi) = (tr.arc.s[0], tr.arc.s[tr.arc.s.len() - 1]);
            let half = d.period / 2.0;
            let mut nodes = Vec::new();
            let mut s = d.node - half * ((d.node - s_lo) / half).floor();
            // A figure marks a few nodes: a degenerate period marks none.
            while s <= s_hi && half > 0.0 && nodes.len() < 10_000 {
                nodes.push((s, d.closed.beta(s)));
                s += half;
            }
            out.push(FigureCurves {
                name: tr.name.clone(),
                q: tr.q,
                s: tr.arc.s.clone(),
                observed: tr.arc.beta.clone(),
                det: curve(&d.closed),
                ls: curve(&tr.closed),
                ml,
                nodes,
                sigma_curve: d.sigma_curve.clone(),
                node: d.node,
            });
        }
        Ok(out)
    }
}

impl CalibrationReport {
    /// The Cramér–Rao bound for a measured dataset, evaluated at this
    /// report's joint maximum-likelihood estimate (the truth is unknown):
    /// standard deviations of phi, psi (rad), eta, delta, xi, with bearing
    /// noise only, and with the encoder noise this report used (stated or
    /// read from the wheel speeds, [`EncoderNoise`]; `None` when it used
    /// none). This bounds an estimator that uses the measured wheel speeds
    /// (ML); one that knows the circle exactly (LS with the commanded q) is
    /// bounded by the bearing-only figure. `data` and `o` are the ones this
    /// report was calibrated from; a report of another method than ML is
    /// refused (`NoMlEstimate`).
    pub fn crlb(
        &self,
        data: &Dataset,
        predictor: &Predictor,
        o: &CalibrateOptions,
    ) -> Result<([f64; 5], Option<[f64; 5]>), CalibError> {
        let f = self.ml.as_ref().ok_or(CalibError::NoMlEstimate)?;
        let fts = FitTrajectory::all(predictor, data);
        let enc_var = self.encoder_noise.intensity();
        let bound = |noise: Option<Vec<f64>>| -> Result<[f64; 5], CalibError> {
            let opts = FitOptions {
                max_iterations: 0,
                cost_tolerance: 0.0,
                step_tolerance: 0.0,
                sigma: vec![self.sigma_beta],
                max_step: o.ml_max_step,
                input_noise: noise,
            };
            let cov = crlb(predictor, &fts, &f.params, &f.initial_states, &opts)
                .map_err(CalibError::Crlb)?;
            Ok(std::array::from_fn(|i| cov[i][i].max(0.0).sqrt()))
        };
        let bearing = bound(None)?;
        let full = if enc_var > 0.0 {
            Some(bound(Some(vec![enc_var, enc_var]))?)
        } else {
            None
        };
        Ok((bearing, full))
    }
}
