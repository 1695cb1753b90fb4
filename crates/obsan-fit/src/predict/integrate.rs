//! The integration of [`Predictor`]'s prediction: the state and its forward
//! sensitivities from the initial state to each output time, along the
//! measured inputs (rows merged into steps, a delay shifting them), with the
//! input noise's covariance accumulated on request. A child module of
//! predict.rs, apart so that the file stays short; it reads the predictor's
//! private tapes as its own. One step is `step.rs`'s.

use super::step::{Rk4, Stages};
use super::{Integration, Predictor, Run, Sink};
use crate::FitError;
use obsan_data::Series;
use obsan_expr::FrozenTape;

/// Integration steps are at most this over the largest diagonal entry of
/// the dynamics' Jacobian (see `predict_with`).
const STIFF_STEP: f64 = 0.5;

/// For a state whose own rate is linear in itself with a coefficient set by
/// the params and inputs alone (a first-order lag `s' = (u - s)/T`), the
/// linear part is integrated exactly (exponential time differencing, Cox and
/// Matthews 2002, ETDRK4) once `h |lambda|` exceeds [`STIFF_STEP`]; its step
/// bound is then this over `|lambda|`, for the states it drives (their RK4
/// stages sample the lag's transient).
const EXP_STEP: f64 = 1.0;

impl Predictor {
    /// The integration of `predict_with` ([`Run`]'s arguments); with
    /// `needed`, only its cells are evaluated. At each output time `sink` gets its index, the
    /// outputs, their rows of dy/dx0 (empty without sensitivities) and
    /// `M(t)` (empty without input noise).
    pub(super) fn integrate(&self, run: &Run, sink: &mut Sink) -> Result<(), FitError> {
        let Run {
            x0,
            consts,
            inputs,
            times,
            opts,
            needed,
        } = *run;
        if x0.len() != self.state.len() || consts.len() != self.consts.len() {
            return Err(FitError::StateSize {
                states: self.state.len(),
                consts: self.consts.len(),
            });
        }
        let cols = self.input_columns(inputs)?;
        let nd = self.n_dynamic;
        let m = self.inputs.len();
        let sens = opts.sensitivities;
        let mut z = self.initial_z(x0, sens);
        let nz = z.len();
        // Tape inputs: the whole state then the constants; params and
        // constants are fixed along the integration, so every subexpression
        // of theirs is evaluated once here.
        let x: Vec<f64> = x0.iter().chain(consts).copied().collect();
        let varying: Vec<bool> = (0..x.len()).map(|i| i < nd).collect();
        let mut w = self.work(x, &varying, needed.is_none(), sens);
        let noise = input_noise(opts, m)?;
        let mut noise_acc = vec![0.0; nd * nd];
        // Reused at every output time (a row each, never kept here).
        let mut y = Vec::new();
        let mut jrow = Vec::new();
        let t_start = inputs.t().first().copied().unwrap_or(0.0);
        // With a delay tau the rows act at t_k + tau (the first row also
        // before that): the state is the one seen from the output clock.
        let tau = self.delay.map_or(0.0, |d| x0[d]);
        if !tau.is_finite() {
            return Err(FitError::DelayNotFinite);
        }
        let mut dudtau = vec![0.0; m];
        // A fast decaying state (a first-order lag `va' = (v - va)/T`) needs
        // steps shorter than its time constant: bound h by STIFF_STEP over
        // the largest diagonal Jacobian entry at the start (h |lambda| <= 1/2
        // keeps RK4's decay factor per step within 2.5e-4 of exp). One bound per
        // prediction, so the steps do not depend on whether sensitivities
        // are computed.
        // Per self-linear state k and term f (drift, then each input's
        // field): d f[k] / d x_k, constant along the prediction.
        let mut lambda_of = vec![0.0; nd * (m + 1)];
        let max_step = self.step_bound(&mut w, inputs, &cols, opts, &mut lambda_of)?;
        let mut t = t_start;
        let mut row = 0usize;
        let mut k1 = vec![0.0; nz];
        let mut rk = Rk4 {
            k2: vec![0.0; nz],
            k3: vec![0.0; nz],
            k4: vec![0.0; nz],
            tmp: z.clone(),
        };
        let mut u = vec![0.0; m];
        let mut lam = vec![0.0; nd];
        let mut stages = Stages::new(nd, nz);
        for (ti, &target) in times.iter().enumerate() {
            if target < t - 1e-12 {
                return Err(FitError::TimeBeforeStart { target, t });
            }
            while t < target - 1e-12 {
                let (before, next) = merge_rows(
                    inputs,
                    &cols,
                    tau,
                    (t, target),
                    (max_step, opts.max_step),
                    &mut row,
                    &mut u,
                );
                let h = next - t;
                // d(mean input)/dtau: each row change inside the step moves
                // later with tau; the sum telescopes to (before - last) / h.
                let dd = if sens && self.delay.is_some() {
                    for (d, &c) in dudtau.iter_mut().zip(&cols) {
                        let a = inputs.values()[c][before].unwrap_or(0.0);
                        let b = inputs.values()[c][row].unwrap_or(0.0);
                        *d = (a - b) / h;
                    }
                    Some(dudtau.as_slice())
                } else {
                    None
                };
                self.derivative(&z, &u, sens, dd, &mut w, &mut k1);
                if let Some(c) = &noise {
                    // w.vals now holds f0 and the fields at the step start.
                    self.accumulate_noise(&z, &w.vals, &u, c, h, &mut noise_acc);
                }
                if self.stiff_lambdas(&lambda_of, &u, h, &mut lam) {
                    self.etd_step(&mut z, &k1, &u, (sens, dd), &mut w, h, &lam, &mut stages);
                } else {
                    self.rk4_step(&mut z, &k1, &u, (sens, dd), &mut w, h, &mut rk);
                }
                if z[..nd].iter().any(|v| !v.is_finite()) {
                    return Err(FitError::Diverged {
                        t: next,
                        params: self.state[nd..]
                            .iter()
                            .cloned()
                            .zip(x0[nd..].iter().copied())
                            .collect(),
                    });
                }
                t = next;
            }
            w.x[..nd].copy_from_slice(&z[..nd]);
            if let Some(needed) = needed {
                self.measured_outputs(
                    &z,
                    needed.at(ti).0,
                    sens,
                    &varying,
                    &mut w,
                    &mut y,
                    &mut jrow,
                );
            } else {
                self.all_outputs(&z, sens, &mut w, &mut y, &mut jrow);
            }
            let m_now: &[f64] = if noise.is_some() { &noise_acc } else { &[] };
            sink(ti, &y, &jrow, m_now);
        }
        Ok(())
    }

    /// The integrated vector at the start: the dynamic state, then (with
    /// `sens`) its sensitivity `Phi = d x / d x0`, row-major `nd x n`, at
    /// `[I 0]`.
    fn initial_z(&self, x0: &[f64], sens: bool) -> Vec<f64> {
        let (nd, n) = (self.n_dynamic, self.state.len());
        let nz = if sens { nd + nd * n } else { nd };
        let mut z = vec![0.0; nz];
        z[..nd].copy_from_slice(&x0[..nd]);
        if sens {
            for k in 0..nd {
                z[nd + k * n + k] = 1.0;
            }
        }
        z
    }

    /// The tapes frozen at the tape inputs `x` (only the `varying` ones
    /// change): the whole output tapes when `whole`, otherwise each
    /// output's own, frozen when first needed.
    fn work<'a>(&'a self, x: Vec<f64>, varying: &[bool], whole: bool, sens: bool) -> Work<'a> {
        let nv = self.dyn_tape.n_outputs();
        Work {
            dyn_only: self.dyn_tape.freeze(&x, varying),
            dyn_jac: self.dyn_jac_tape.freeze(&x, varying),
            out: whole.then(|| self.out_tape.freeze(&x, varying)),
            out_jac: (whole && sens).then(|| self.out_jac_tape.freeze(&x, varying)),
            one: (0..self.outputs.len()).map(|_| None).collect(),
            vals: vec![0.0; nv],
            jvals: vec![0.0; self.dyn_jac_tape.n_outputs() - nv],
            jac: vec![0.0; self.n_dynamic * self.state.len()],
            x,
        }
    }

    /// Each self-linear state's lambda over a step of length `h` with
    /// inputs `u` into `lam` (from `lambda_of`, see `step_bound`); 0 (plain
    /// RK4, bit for bit as before) where h |lambda| is within STIFF_STEP.
    /// Whether any is stiff.
    fn stiff_lambdas(&self, lambda_of: &[f64], u: &[f64], h: f64, lam: &mut [f64]) -> bool {
        let m = self.inputs.len();
        let mut stiff_here = false;
        for (k, l) in lam.iter_mut().enumerate() {
            *l = 0.0;
            if self.self_linear[k] {
                let row = &lambda_of[k * (m + 1)..(k + 1) * (m + 1)];
                let v = row[0] + row[1..].iter().zip(u).map(|(a, b)| a * b).sum::<f64>();
                if (v * h).abs() > STIFF_STEP * (1.0 + 1e-9) {
                    *l = v;
                    stiff_here = true;
                }
            }
        }
        stiff_here
    }

    /// `d(state)/dt` (`jac` false) or, with `jac`, also the sensitivity
    /// `d(Phi)/dt = J Phi_full` packed after the state (`nd + nd*n` values).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn derivative(
        &self,
        z: &[f64],
        u: &[f64],
        jac: bool,
        dudtau: Option<&[f64]>,
        w: &mut Work,
        dz: &mut [f64],
    ) {
        let nd = self.n_dynamic;
        let n = self.state.len();
        let m = self.inputs.len();
        // The tapes take the whole state (dynamic then params) then the
        // constants; only the dynamic part changes.
        w.x[..nd].copy_from_slice(&z[..nd]);
        let nv = w.vals.len();
        if jac {
            let all = w.dyn_jac.eval(&w.x);
            w.vals.copy_from_slice(&all[..nv]);
            w.jvals.copy_from_slice(&all[nv..]);
        } else {
            let v = w.dyn_only.eval(&w.x);
            w.vals.copy_from_slice(v);
        }
        for (k, d) in dz.iter_mut().enumerate().take(nd) {
            let row = &w.vals[k * (m + 1)..(k + 1) * (m + 1)];
            *d = row[0] + row[1..].iter().zip(u).map(|(f, ui)| f * ui).sum::<f64>();
        }
        if !jac {
            return;
        }
        // J (nd x n): sum over the drift and the fields of d f[k] / d x_j
        // times u, over the structurally non-zero entries only.
        w.jac.fill(0.0);
        for (&(k, f, j), d) in self.jac_entries.iter().zip(&w.jvals) {
            w.jac[k * n + j] += if f == 0 { *d } else { d * u[f - 1] };
        }
        // dPhi/dt = J * Phi_full, where Phi_full = [Phi; 0 I] (params are constant).
        let phi = &z[nd..];
        for k in 0..nd {
            let cols = &self.jac_dyn_cols[k];
            let out = &mut dz[nd + k * n..nd + (k + 1) * n];
            out.copy_from_slice(&w.jac[k * n..(k + 1) * n]);
            out[..nd].fill(0.0);
            for &j in cols {
                let a = w.jac[k * n + j];
                for (o, p) in out.iter_mut().zip(&phi[j * n..(j + 1) * n]) {
                    *o += a * p;
                }
            }
        }
        // The delay enters through the inputs: B (the fields) times d(u)/d(tau).
        if let (Some(d), Some(du)) = (self.delay, dudtau) {
            for k in 0..nd {
                let row = &w.vals[k * (m + 1)..(k + 1) * (m + 1)];
                dz[nd + k * n + d] += row[1..].iter().zip(du).map(|(f, x)| f * x).sum::<f64>();
            }
        }
    }

    /// The longest step of a prediction: `max_step`, and STIFF_STEP (EXP_STEP
    /// for a self-linear state, integrated exactly) over each dynamic state's
    /// diagonal Jacobian entry at the start; fills `lambda_of` (per self-linear
    /// state k and term f, drift then each input's field, d f[k] / d x_k,
    /// constant along the prediction). A time scale below the input rows'
    /// spacing is an error.
    fn step_bound(
        &self,
        w: &mut Work,
        inputs: &Series,
        cols: &[usize],
        opts: &Integration,
        lambda_of: &mut [f64],
    ) -> Result<f64, FitError> {
        let (nd, m, nv) = (self.n_dynamic, self.inputs.len(), self.dyn_tape.n_outputs());
        let all = w.dyn_jac.eval(&w.x);
        let jv = &all[nv..];
        let u0: Vec<f64> = cols
            .iter()
            .map(|&c| inputs.values()[c].first().copied().flatten().unwrap_or(0.0))
            .collect();
        let mut diag = vec![0.0f64; nd];
        for (&(k, f, j), d) in self.jac_entries.iter().zip(jv) {
            if j == k {
                diag[k] += if f == 0 {
                    d.abs()
                } else {
                    (d * u0[f - 1]).abs()
                };
                if self.self_linear[k] {
                    lambda_of[k * (m + 1) + f] = *d;
                }
            }
        }
        let stiff = diag.iter().copied().fold(0.0f64, f64::max);
        // A self-linear state's linear part is integrated exactly: its
        // bound is the looser EXP_STEP.
        let bound = (0..nd)
            .map(|k| {
                let c = if self.self_linear[k] {
                    EXP_STEP
                } else {
                    STIFF_STEP
                };
                if diag[k] > 0.0 {
                    c / diag[k]
                } else {
                    f64::INFINITY
                }
            })
            .fold(f64::INFINITY, f64::min);
        // max_step 0 means row by row (no merging), not no bound.
        let cap = if opts.max_step > 0.0 {
            opts.max_step
        } else {
            f64::INFINITY
        };
        // A time scale below the input rows' spacing cannot be resolved
        // from these data, and steps that short would cost without
        // bound: refuse it (a fit then rejects the trial, so a fitted
        // lag stops at the rows' spacing instead of running to 0).
        let n_rows = inputs.t().len();
        let spacing = if n_rows > 1 {
            (inputs.t()[n_rows - 1] - inputs.t()[0]) / (n_rows - 1) as f64
        } else {
            0.0
        };
        if !stiff.is_finite() || stiff * spacing > 1.0 {
            return Err(FitError::TooStiff {
                time_scale: 1.0 / stiff,
                spacing,
            });
        }
        Ok(cap.min(bound))
    }

    /// `acc += h * sum_i c_i |u_i| (Phi^-1 f_i)(Phi^-1 f_i)^T` (left point).
    fn accumulate_noise(
        &self,
        z: &[f64],
        vals: &[f64],
        u: &[f64],
        c: &[f64],
        h: f64,
        acc: &mut [f64],
    ) {
        let nd = self.n_dynamic;
        let n = self.state.len();
        let m = self.inputs.len();
        let phi = nalgebra::DMatrix::from_fn(nd, nd, |i, j| z[nd + i * n + j]);
        let Some(inv) = phi.try_inverse() else {
            return;
        };
        for (i, (&ci, &ui)) in c.iter().zip(u).enumerate() {
            let q = ci * ui.abs();
            if q == 0.0 {
                continue;
            }
            let b = nalgebra::DVector::from_fn(nd, |k, _| vals[k * (m + 1) + 1 + i]);
            let g = &inv * b;
            for a in 0..nd {
                for bb in 0..nd {
                    acc[a * nd + bb] += h * q * g[a] * g[bb];
                }
            }
        }
    }
}

/// The frozen tapes and scratch buffers of one prediction.
pub(super) struct Work<'a> {
    /// Tape inputs: dynamic state (updated per evaluation), params, constants.
    pub(super) x: Vec<f64>,
    pub(super) dyn_only: FrozenTape<'a>,
    pub(super) dyn_jac: FrozenTape<'a>,
    pub(super) out: Option<FrozenTape<'a>>,
    pub(super) out_jac: Option<FrozenTape<'a>>,
    /// Per output, its own tape (see `Predictor::measured_outputs`).
    pub(super) one: Vec<Option<FrozenTape<'a>>>,
    pub(super) vals: Vec<f64>,
    pub(super) jvals: Vec<f64>,
    pub(super) jac: Vec<f64>,
}

/// The input noise intensities of a prediction (one per input), which need
/// the sensitivities.
fn input_noise(opts: &Integration, m: usize) -> Result<Option<Vec<f64>>, FitError> {
    match &opts.input_noise {
        Some(c) if opts.sensitivities => {
            if c.len() != m {
                return Err(FitError::InputNoiseSize(m));
            }
            Ok(Some(c.clone()))
        }
        Some(_) => Err(FitError::InputNoiseNeedsSensitivities),
        None => Ok(None),
    }
}

/// One step's inputs from `t` towards `target`: the row in force at `t`
/// (`row` moves to it), merged with the next rows while the step stays within
/// `max_step` and `limit` (the caller's `Integration::max_step`; a row longer
/// than `max_step` is split), the inputs averaged over time into `u`. Rows act
/// at their time plus `tau`. Returns the row in force just before the step (a
/// row change at the step's start belongs to this step, for d/dtau) and the
/// step's end.
fn merge_rows(
    inputs: &Series,
    cols: &[usize],
    tau: f64,
    (t, target): (f64, f64),
    (max_step, limit): (f64, f64),
    row: &mut usize,
    u: &mut [f64],
) -> (usize, f64) {
    let et = |k: usize| inputs.t()[k] + tau;
    let mut r0 = *row;
    while r0 + 1 < inputs.len() && et(r0 + 1) <= t + 1e-12 {
        r0 += 1;
    }
    let before = if r0 > 0 && (et(r0) - t).abs() <= 1e-12 {
        r0 - 1
    } else {
        r0
    };
    // This row's interval, merged with the next rows below.
    let mut next = if r0 + 1 < inputs.len() {
        et(r0 + 1).min(target)
    } else {
        target
    }
    .min(t + max_step);
    for (ui, &c) in u.iter_mut().zip(cols) {
        *ui = inputs.values()[c][r0].unwrap_or(0.0) * (next - t);
    }
    while next < target - 1e-12 && r0 + 1 < inputs.len() {
        let r = r0 + 1;
        let end = if r + 1 < inputs.len() {
            et(r + 1).min(target)
        } else {
            target
        };
        if end - t > max_step.min(limit) {
            break;
        }
        for (ui, &c) in u.iter_mut().zip(cols) {
            *ui += inputs.values()[c][r].unwrap_or(0.0) * (end - next);
        }
        r0 = r;
        next = end;
    }
    let h = next - t;
    for ui in u.iter_mut() {
        *ui /= h;
    }
    *row = r0;
    (before, next)
}
