//! Predicting the outputs of any `.sys` model along measured inputs: the
//! forward model of maximum-likelihood fitting and of the
//! discrepancy workflow. The dynamics come from the model file,
//! the single source of truth.

use crate::FitError;
use obsan_data::Series;
use obsan_expr::{FrozenTape, Tape, Var};
use obsan_model::NormalForm;
use step::{Rk4, Stages};

mod step;

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

/// A compiled model: `S' = f0 + sum_i f_i u_i`, `y = h(S)`.
#[derive(Clone, Debug)]
pub struct Predictor {
    /// Dynamic states (integrated) and params (constant), in model order.
    pub state: Vec<String>,
    pub n_dynamic: usize,
    /// Known constants the model needs a value for (e.g. q), in order.
    pub consts: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    /// Per output: its values are angles (contains atan/atan2), so residuals wrap.
    pub angular: Vec<bool>,
    /// Index in `state` of the delay param: the dynamics see `u(t - tau)`.
    pub delay: Option<usize>,
    /// Roots: for each dynamic state k, f0[k] then f_i[k] for each input.
    dyn_tape: Tape,
    out_tape: Tape,
    /// The roots of `dyn_tape`, then the structurally non-zero
    /// d(root)/d(state_j) listed in `jac_entries`: one tape so that shared
    /// subexpressions (sines, cosines) are computed once.
    dyn_jac_tape: Tape,
    /// Per non-zero derivative of `dyn_jac_tape`: (dynamic state k, term f
    /// (0 the drift, i + 1 input i's field), state j). The Jacobians of
    /// these models are sparse (a lag state depends on itself and T, a
    /// position on the heading and the speed): only these are computed.
    jac_entries: Vec<(usize, usize, usize)>,
    /// Per dynamic state k, the dynamic states j < n_dynamic with a
    /// non-zero d f[k] / d x_j (the columns `J Phi` needs).
    jac_dyn_cols: Vec<Vec<usize>>,
    /// Per dynamic state k: d f[k] / d x_k (drift and every field) depends
    /// on no dynamic state, so `x_k' = lambda x_k + rest` with `lambda`
    /// constant over a step (see [`EXP_STEP`]).
    self_linear: Vec<bool>,
    /// The structurally non-zero d(output)/d(state_j), as (output, j).
    out_jac_tape: Tape,
    out_jac_entries: Vec<(usize, usize)>,
    /// Per output alone: its value (`value`) and its value then its
    /// structurally non-zero gradient entries (`with_grad`, over the states
    /// `grad_of`), for [`Predictor::predict_measured`]: a row of MRCLAM's
    /// outputs measures one or two of its 30 landmark outputs.
    per_output: Vec<OutputTapes>,
}

#[derive(Clone, Debug)]
struct OutputTapes {
    value: Tape,
    with_grad: Tape,
    grad_of: Vec<usize>,
}

impl Predictor {
    // The normal form's expressions use only its state and constants, so
    // every symbol looked up and every tape compiled exists.
    #[allow(clippy::expect_used)]
    pub fn new(nf: &NormalForm) -> Predictor {
        let n_dynamic = nf.n_dynamic;
        let m = nf.inputs.len();
        let mut roots = Vec::with_capacity(n_dynamic * (m + 1));
        for k in 0..n_dynamic {
            roots.push(nf.f0[k]);
            for f in &nf.fields {
                roots.push(f[k]);
            }
        }
        let consts: Vec<String> = nf
            .consts
            .iter()
            .filter(|c| c.1.is_none())
            .map(|c| c.0.clone())
            .collect();
        let mut vars: Vec<Var> = nf.state_vars.clone();
        vars.extend(
            consts
                .iter()
                .map(|c| nf.ctx.lookup(c).expect("const symbol").var),
        );
        let dyn_tape = Tape::compile(&nf.ctx, &roots, &vars)
            .expect("dynamics use only the state and constants");
        let outs: Vec<_> = nf.outputs.iter().map(|o| o.1).collect();
        let out_tape =
            Tape::compile(&nf.ctx, &outs, &vars).expect("outputs use only the state and constants");
        // Exact partial derivatives from the engine, for the sensitivities.
        let mut ctx = nf.ctx.clone();
        let mut jac_roots = Vec::new();
        let mut jac_entries = Vec::new();
        for (ri, &r) in roots.iter().enumerate() {
            for (j, &x) in nf.state_vars.iter().enumerate() {
                let d = ctx.diff(r, x);
                if !ctx.is_zero(d) {
                    jac_roots.push(d);
                    jac_entries.push((ri / (m + 1), ri % (m + 1), j));
                }
            }
        }
        // A state is self-linear when it has a diagonal entry and none of
        // its diagonal entries depends on a dynamic state.
        let mut has_diag = vec![false; n_dynamic];
        let mut state_dependent = vec![false; n_dynamic];
        for (&(k, _, j), &d) in jac_entries.iter().zip(&jac_roots) {
            if j != k {
                continue;
            }
            has_diag[k] = true;
            for &x in &nf.state_vars[..n_dynamic] {
                let dd = ctx.diff(d, x);
                if !ctx.is_zero(dd) {
                    state_dependent[k] = true;
                }
            }
        }
        let self_linear: Vec<bool> = (0..n_dynamic)
            .map(|k| has_diag[k] && !state_dependent[k])
            .collect();
        let mut jac_dyn_cols = vec![Vec::new(); n_dynamic];
        for &(k, _, j) in &jac_entries {
            if j < n_dynamic && !jac_dyn_cols[k].contains(&j) {
                jac_dyn_cols[k].push(j);
            }
        }
        let mut out_jac_roots = Vec::new();
        let mut out_jac_entries = Vec::new();
        let mut per_output = Vec::with_capacity(outs.len());
        for (o, &h) in outs.iter().enumerate() {
            let mut one = vec![h];
            let mut grad_of = Vec::new();
            for (j, &x) in nf.state_vars.iter().enumerate() {
                let d = ctx.diff(h, x);
                if !ctx.is_zero(d) {
                    out_jac_roots.push(d);
                    out_jac_entries.push((o, j));
                    one.push(d);
                    grad_of.push(j);
                }
            }
            per_output.push(OutputTapes {
                value: Tape::compile(&ctx, &[h], &vars).expect("outputs use the same symbols"),
                with_grad: Tape::compile(&ctx, &one, &vars)
                    .expect("derivatives use the same symbols"),
                grad_of,
            });
        }
        let all: Vec<_> = roots.iter().chain(&jac_roots).copied().collect();
        let dyn_jac_tape =
            Tape::compile(&ctx, &all, &vars).expect("derivatives use the same symbols");
        let out_jac_tape =
            Tape::compile(&ctx, &out_jac_roots, &vars).expect("derivatives use the same symbols");
        Predictor {
            state: nf.state.clone(),
            n_dynamic,
            consts,
            inputs: nf.inputs.clone(),
            outputs: nf.outputs.iter().map(|o| o.0.clone()).collect(),
            angular: outs.iter().map(|&h| nf.ctx.is_angle_valued(h)).collect(),
            delay: nf.delay,
            dyn_tape,
            out_tape,
            dyn_jac_tape,
            jac_entries,
            jac_dyn_cols,
            self_linear,
            out_jac_tape,
            out_jac_entries,
            per_output,
        }
    }

    /// `d(state)/dt` (`jac` false) or, with `jac`, also the sensitivity
    /// `d(Phi)/dt = J Phi_full` packed after the state (`nd + nd*n` values).
    #[allow(clippy::too_many_arguments)]
    fn derivative(
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

    /// Outputs at `times`, integrating from `x0` (the whole analysed state:
    /// dynamic states then params) at `inputs.t[0]`, inputs held constant from
    /// each row to the next (classical RK4 on every such interval, split at
    /// the output times). `consts` gives the values of [`Predictor::consts`].
    pub fn predict(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        times: &[f64],
    ) -> Result<Vec<Vec<f64>>, FitError> {
        Ok(self
            .predict_with(x0, consts, inputs, times, &Integration::default())?
            .outputs)
    }

    /// [`Predictor::predict`] with integration options: merged input rows
    /// (`max_step`) and, on request, the exact sensitivities of the outputs
    /// to the whole initial state (forward sensitivity equations built from
    /// the engine's symbolic Jacobian, integrated with the state).
    pub fn predict_with(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        times: &[f64],
        opts: &Integration,
    ) -> Result<Prediction, FitError> {
        self.collect(x0, consts, inputs, times, opts, None)
    }

    /// [`Predictor::predict_with`] at the times of `cells`, computing only
    /// the measured cells: `outputs[k]` holds the values of the outputs
    /// [`Measured::at`]`(k)` lists, in that order, and `jacobians[k]` their
    /// rows (so `at(k).len()` x state). Values and rows equal
    /// `predict_with`'s exactly.
    pub fn predict_measured(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        cells: &Measured,
        opts: &Integration,
    ) -> Result<Prediction, FitError> {
        self.collect(x0, consts, inputs, cells.t, opts, Some(cells))
    }

    /// [`Predictor::predict_measured`] handing each output time's values,
    /// rows and (with input noise) `M(t)` to `sink` as they are computed
    /// instead of keeping them: a fit accumulates its normal equations from
    /// them, so a prediction's memory does not grow with its length.
    pub(crate) fn predict_measured_each(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        cells: &Measured,
        opts: &Integration,
        sink: &mut Sink,
    ) -> Result<(), FitError> {
        self.integrate(x0, consts, inputs, cells.t, opts, Some(cells), sink)
    }

    /// [`Predictor::integrate`] kept whole, as a [`Prediction`].
    fn collect(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        times: &[f64],
        opts: &Integration,
        needed: Option<&Measured>,
    ) -> Result<Prediction, FitError> {
        let mut out = Prediction {
            outputs: Vec::with_capacity(times.len()),
            jacobians: Vec::new(),
            noise_m: Vec::new(),
        };
        let (sens, noise) = (opts.sensitivities, opts.input_noise.is_some());
        self.integrate(
            x0,
            consts,
            inputs,
            times,
            opts,
            needed,
            &mut |_, y, j, m| {
                out.outputs.push(y.to_vec());
                if sens {
                    out.jacobians.push(j.to_vec());
                }
                if noise {
                    out.noise_m.push(m.to_vec());
                }
            },
        )?;
        Ok(out)
    }

    /// The integration of `predict_with`; with `needed`, only its cells
    /// are evaluated. At each output time `sink` gets its index, the
    /// outputs, their rows of dy/dx0 (empty without sensitivities) and
    /// `M(t)` (empty without input noise).
    #[allow(clippy::too_many_arguments)]
    fn integrate(
        &self,
        x0: &[f64],
        consts: &[f64],
        inputs: &Series,
        times: &[f64],
        opts: &Integration,
        needed: Option<&Measured>,
        sink: &mut Sink,
    ) -> Result<(), FitError> {
        if x0.len() != self.state.len() || consts.len() != self.consts.len() {
            return Err(FitError::StateSize {
                states: self.state.len(),
                consts: self.consts.len(),
            });
        }
        let cols = self.input_columns(inputs)?;
        let nd = self.n_dynamic;
        let n = self.state.len();
        let m = self.inputs.len();
        let nz = if opts.sensitivities { nd + nd * n } else { nd };
        let mut z = vec![0.0; nz];
        z[..nd].copy_from_slice(&x0[..nd]);
        if opts.sensitivities {
            for k in 0..nd {
                z[nd + k * n + k] = 1.0;
            }
        }
        // Tape inputs: the whole state then the constants; params and
        // constants are fixed along the integration, so every subexpression
        // of theirs is evaluated once here.
        let x: Vec<f64> = x0.iter().chain(consts).copied().collect();
        let varying: Vec<bool> = (0..x.len()).map(|i| i < nd).collect();
        let nv = self.dyn_tape.n_outputs();
        // The whole output tapes, or (with `needed`) each output's own,
        // frozen when first needed.
        let whole = needed.is_none();
        let mut w = Work {
            dyn_only: self.dyn_tape.freeze(&x, &varying),
            dyn_jac: self.dyn_jac_tape.freeze(&x, &varying),
            out: whole.then(|| self.out_tape.freeze(&x, &varying)),
            out_jac: (whole && opts.sensitivities).then(|| self.out_jac_tape.freeze(&x, &varying)),
            one: (0..self.outputs.len()).map(|_| None).collect(),
            x,
            vals: vec![0.0; nv],
            jvals: vec![0.0; self.dyn_jac_tape.n_outputs() - nv],
            jac: vec![0.0; nd * n],
        };
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
        let sens = opts.sensitivities;
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
                // Each self-linear state's lambda over this step; 0 (plain
                // RK4, bit for bit as before) where h |lambda| is within
                // STIFF_STEP.
                let mut stiff_here = false;
                for (k, l) in lam.iter_mut().enumerate() {
                    *l = 0.0;
                    if self.self_linear[k] {
                        let row = &lambda_of[k * (m + 1)..(k + 1) * (m + 1)];
                        let v = row[0] + row[1..].iter().zip(&u).map(|(a, b)| a * b).sum::<f64>();
                        if (v * h).abs() > STIFF_STEP * (1.0 + 1e-9) {
                            *l = v;
                            stiff_here = true;
                        }
                    }
                }
                if stiff_here {
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

    /// Every output at state `z` (set into `w.x`) from the whole output tapes,
    /// with (`sens`) its row of dy/dx0.
    fn all_outputs(
        &self,
        z: &[f64],
        sens: bool,
        w: &mut Work,
        y: &mut Vec<f64>,
        jrow: &mut Vec<f64>,
    ) {
        let (nd, n, no) = (self.n_dynamic, self.state.len(), self.outputs.len());
        y.clear();
        jrow.clear();
        if let Some(out) = &mut w.out {
            y.extend_from_slice(out.eval(&w.x));
        }
        if let (true, Some(out_jac)) = (sens, &mut w.out_jac) {
            let gy = out_jac.eval(&w.x);
            // dy/dx0 = grad h * Phi_full, over the non-zero grad h entries.
            let phi = &z[nd..];
            jrow.resize(no * n, 0.0);
            for (&(o, j), g) in self.out_jac_entries.iter().zip(gy) {
                add_grad(&mut jrow[o * n..(o + 1) * n], j, *g, phi, nd);
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

    /// The state's columns in `inputs`, in the model's input order.
    fn input_columns(&self, inputs: &Series) -> Result<Vec<usize>, FitError> {
        self.inputs
            .iter()
            .map(|n| {
                inputs
                    .columns()
                    .iter()
                    .position(|c| c == n)
                    .ok_or_else(|| FitError::MissingInput(n.clone()))
            })
            .collect()
    }

    /// The outputs `which` at the state in `w.x` and, with `sens`, their
    /// rows `grad h * Phi_full`, each output's tape frozen at its first use.
    #[allow(clippy::too_many_arguments)]
    fn measured_outputs<'a>(
        &'a self,
        z: &[f64],
        which: &[usize],
        sens: bool,
        varying: &[bool],
        w: &mut Work<'a>,
        y: &mut Vec<f64>,
        jrow: &mut Vec<f64>,
    ) {
        let (nd, n) = (self.n_dynamic, self.state.len());
        y.clear();
        y.resize(which.len(), 0.0);
        jrow.clear();
        if sens {
            jrow.resize(which.len() * n, 0.0);
        }
        for (i, &o) in which.iter().enumerate() {
            let tapes = &self.per_output[o];
            let tape = if sens { &tapes.with_grad } else { &tapes.value };
            let frozen = w.one[o].get_or_insert_with(|| tape.freeze(&w.x, varying));
            let v = frozen.eval(&w.x);
            y[i] = v[0];
            if !sens {
                continue;
            }
            let phi = &z[nd..];
            let row = &mut jrow[i * n..(i + 1) * n];
            for (&j, g) in tapes.grad_of.iter().zip(&v[1..]) {
                add_grad(row, j, *g, phi, nd);
            }
        }
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

/// `row += g d(x_j)/d(x0)`: the sensitivity row `Phi[j]` for a dynamic
/// state j, the unit row for a param (params are constant).
fn add_grad(row: &mut [f64], j: usize, g: f64, phi: &[f64], nd: usize) {
    let n = row.len();
    if j < nd {
        for (r, p) in row.iter_mut().zip(&phi[j * n..(j + 1) * n]) {
            *r += g * p;
        }
    } else {
        row[j] += g;
    }
}

/// The measured cells of one trajectory's outputs, in time order: per
/// output time, which of a predictor's outputs are measured (in model
/// order) and their values. Built once per fit, so that the predictions
/// and residuals visit only these (a MRCLAM row measures one or two of 30
/// outputs, and scanning the empty cells cost a cache miss each); times borrowed.
#[derive(Clone, Debug)]
pub struct Measured<'a> {
    t: &'a [f64],
    /// The cells of time k are `start[k]..start[k + 1]`.
    start: Vec<usize>,
    output: Vec<usize>,
    value: Vec<f64>,
}

impl<'a> Measured<'a> {
    /// The cells of `outputs` present in the column named after each of
    /// `p`'s outputs (an output without a column is never measured).
    pub fn new(p: &Predictor, outputs: &'a Series) -> Measured<'a> {
        let cols: Vec<Option<&[Option<f64>]>> =
            p.outputs.iter().map(|o| outputs.column(o)).collect();
        let mut start = Vec::with_capacity(outputs.len() + 1);
        let (mut output, mut value) = (Vec::new(), Vec::new());
        for k in 0..outputs.len() {
            start.push(output.len());
            for (o, c) in cols.iter().enumerate() {
                if let Some(v) = c.and_then(|c| c[k]) {
                    output.push(o);
                    value.push(v);
                }
            }
        }
        start.push(output.len());
        Measured {
            t: outputs.t(),
            start,
            output,
            value,
        }
    }

    /// At output time `k`: the measured outputs and their values.
    pub fn at(&self, k: usize) -> (&[usize], &[f64]) {
        let r = self.start[k]..self.start[k + 1];
        (&self.output[r.clone()], &self.value[r])
    }

    /// Number of output times.
    pub fn n_times(&self) -> usize {
        self.t.len()
    }

    /// Number of measured cells.
    pub fn len(&self) -> usize {
        self.value.len()
    }

    pub fn is_empty(&self) -> bool {
        self.value.is_empty()
    }
}

/// What a prediction hands on at each output time: its index, the outputs,
/// their rows of dy/dx0 (empty without sensitivities) and `M(t)` (empty
/// without input noise).
pub(crate) type Sink<'a> = dyn FnMut(usize, &[f64], &[f64], &[f64]) + 'a;

/// Integration options of [`Predictor::predict_with`].
#[derive(Clone, Debug, Default)]
pub struct Integration {
    /// Merge consecutive input rows into one RK4 step of at most this length
    /// (inputs averaged over the step); 0 keeps one step per row, which is
    /// exact up to RK4's error. Merging is exact for constant inputs and, for
    /// a driftless model, changes the result only through the commutator of
    /// the fields times the input variation within a step.
    pub max_step: f64,
    /// Also integrate the forward sensitivities.
    pub sensitivities: bool,
    /// Input noise (needs `sensitivities`): per input, `c_i` such that the
    /// measured input carries white noise of spectral density `c_i |u_i|`
    /// (encoders with the error model of [10]: `c = K^2 / r`). Then
    /// [`Prediction::noise_m`] holds, per output time t, the matrix
    /// `M(t) = int_0^t Phi(s)^-1 B(s) Q(s) B(s)^T Phi(s)^-T ds` (dynamic
    /// states), so that the state error it causes has covariance
    /// `Phi(t_i) M(min(t_i, t_j)) Phi(t_j)^T`.
    pub input_noise: Option<Vec<f64>>,
}

/// Outputs (per time, per output) and, when requested, their Jacobians with
/// respect to the whole initial state (per time: outputs x state, row-major).
#[derive(Clone, Debug)]
pub struct Prediction {
    pub outputs: Vec<Vec<f64>>,
    pub jacobians: Vec<Vec<f64>>,
    /// Per output time, `M(t)` (n_dynamic x n_dynamic, row-major) when
    /// [`Integration::input_noise`] is given.
    pub noise_m: Vec<Vec<f64>>,
}

struct Work<'a> {
    /// Tape inputs: dynamic state (updated per evaluation), params, constants.
    x: Vec<f64>,
    dyn_only: FrozenTape<'a>,
    dyn_jac: FrozenTape<'a>,
    out: Option<FrozenTape<'a>>,
    out_jac: Option<FrozenTape<'a>>,
    /// Per output, its own tape (see `Predictor::measured_outputs`).
    one: Vec<Option<FrozenTape<'a>>>,
    vals: Vec<f64>,
    jvals: Vec<f64>,
    jac: Vec<f64>,
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
