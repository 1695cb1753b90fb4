//! Predicting the outputs of any `.sys` model along measured inputs: the
//! forward model of maximum-likelihood fitting and of the
//! discrepancy workflow. The dynamics come from the model file,
//! the single source of truth.

use crate::FitError;
use integrate::Work;
use obsan_data::Series;
use obsan_expr::{Tape, Var};
use obsan_model::NormalForm;

mod integrate;
mod step;

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
    /// constant over a step (see `EXP_STEP` in `integrate.rs`).
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
        self.collect(&Run {
            x0,
            consts,
            inputs,
            times,
            opts,
            needed: None,
        })
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
        self.collect(&Run::measured(x0, consts, inputs, cells, opts))
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
        self.integrate(&Run::measured(x0, consts, inputs, cells, opts), sink)
    }

    /// [`Predictor::integrate`] kept whole, as a [`Prediction`].
    fn collect(&self, run: &Run) -> Result<Prediction, FitError> {
        let mut out = Prediction {
            outputs: Vec::with_capacity(run.times.len()),
            jacobians: Vec::new(),
            noise_m: Vec::new(),
        };
        let (sens, noise) = (run.opts.sensitivities, run.opts.input_noise.is_some());
        self.integrate(run, &mut |_, y, j, m| {
            out.outputs.push(y.to_vec());
            if sens {
                out.jacobians.push(j.to_vec());
            }
            if noise {
                out.noise_m.push(m.to_vec());
            }
        })?;
        Ok(out)
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
/// One prediction's arguments: from `x0` (the whole analysed state) with
/// `consts` along `inputs` to the output `times`, evaluating only the cells
/// of `needed` when given (see [`Predictor::predict_measured`]).
struct Run<'a> {
    x0: &'a [f64],
    consts: &'a [f64],
    inputs: &'a Series,
    times: &'a [f64],
    opts: &'a Integration,
    needed: Option<&'a Measured<'a>>,
}

impl<'a> Run<'a> {
    /// At the times of `cells`, computing only them.
    fn measured(
        x0: &'a [f64],
        consts: &'a [f64],
        inputs: &'a Series,
        cells: &'a Measured<'a>,
        opts: &'a Integration,
    ) -> Run<'a> {
        Run {
            x0,
            consts,
            inputs,
            times: cells.t,
            opts,
            needed: Some(cells),
        }
    }
}

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
