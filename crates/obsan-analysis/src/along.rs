//! Observability along recorded data (docs/experiments.md, "Observability
//! along data"): window by window, the numerical rank of the sensitivity of
//! the window's sampled outputs to the state at the window's start (dynamic
//! states and params), at the model's states along the recorded inputs.
//!
//! The matrix. For the window's inputs `u(t)` (held between samples, as
//! recorded) the outputs are `y_o(t_k) = h_o(x(t_k; x_w, p))`; row
//! `dh_o(x(t_k)) Phi(t_k)`, with `Phi = d(x, p)(t)/d(x_w, p)` from the
//! variational equation `Phi' = J(x, u) Phi`, `Phi(t_w) = I`, one row per
//! measured output sample. A vector `v` in its kernel moves no sampled output
//! to first order: that is what the window cannot see, by definition. The
//! link with the codistribution of eq. 16: under a constant input `u` the
//! sampled output is `sum_k t^k/k! L^k_{f(u)} h`, so the kernel at enough
//! samples is the kernel of the gradients of the Lie derivatives along
//! `f(u) = f0 + sum f_i u_i`; with varying inputs, along the words of the
//! fields the inputs span (by multilinearity) when the inputs excite them.
//! Every exact symmetry of the model restricted to the window's inputs
//! leaves every sampled output unchanged, so it is in the kernel exactly.
//!
//! The rank. The matrix is computed twice, with RK4 steps of the input
//! sample interval and of half of it; their difference `E` estimates the
//! error of the finer one (fourth order: the finer is ~16 times better).
//! Columns are scaled to unit norm (units cancel), and a singular value at
//! or below `TOL_SAFETY * ||E||_F` (Weyl: computed singular values move by at
//! most the error's norm), or below `ROUNDING_FLOOR * sigma_1`, is zero.

use crate::along_linalg::{dot, svd};
use crate::rank::AnalysisError;
use obsan_expr::{Id, Tape};
use obsan_model::NormalForm;
use std::time::Instant;

/// Multiple of the estimated integration error below which a singular value
/// counts as zero: the difference of the two step sizes estimates the
/// coarse matrix's error; the safety factor covers that estimate's own
/// uncertainty (a factor 16/15 for RK4) with a wide margin.
pub const TOL_SAFETY: f64 = 100.0;

/// Relative floor of the numerical rank: f64 rounding in the tape and in up to
/// ~10^6 integration steps accumulates to at most ~10^6 * 2^-53 ~ 1e-10 in
/// relative terms (linear worst case), below 1e-9 with margin.
pub const ROUNDING_FLOOR: f64 = 1e-9;

/// Windows per trajectory at most (each costs a small SVD and its report).
pub const MAX_WINDOWS: usize = 1_000_000;

/// One trajectory of a dataset, as plain numbers in the model's order.
#[derive(Clone, Debug)]
pub struct AlongTrajectory {
    pub name: String,
    /// Input sample times; `inputs[k]` (one value per model input) holds from
    /// `input_t[k]` until the next sample.
    pub input_t: Vec<f64>,
    pub inputs: Vec<Vec<f64>>,
    /// Output sample times and which of the model's outputs each row measured.
    pub output_t: Vec<f64>,
    pub measured: Vec<Vec<bool>>,
    /// Values of the analysed state (`nf.state`: dynamic states, then params)
    /// at the trajectory's first input time.
    pub start: Vec<f64>,
    /// Values of the model's generic constants ([`generic_consts`] order).
    pub consts: Vec<f64>,
}

/// The model's constants without a value (`--set` gives them one): each
/// trajectory gives its own (meta.json), in this order.
pub fn generic_consts(nf: &NormalForm) -> Vec<String> {
    nf.consts
        .iter()
        .filter(|c| c.1.is_none())
        .filter(|c| nf.ctx.lookup(&c.0).is_some())
        .map(|c| c.0.clone())
        .collect()
}

/// The tapes' input variables: the analysed state, then the generic constants.
pub(crate) fn tape_vars(nf: &NormalForm) -> Vec<obsan_expr::Var> {
    let mut vars = nf.state_vars.clone();
    for c in generic_consts(nf) {
        if let Some(s) = nf.ctx.lookup(&c) {
            vars.push(s.var);
        }
    }
    vars
}

/// Options of [`along`].
#[derive(Clone, Debug)]
pub struct AlongOptions {
    /// Window length (seconds).
    pub window: f64,
    pub deadline: Option<Instant>,
}

/// One window's verdict.
#[derive(Clone, Debug)]
pub struct AlongWindow {
    pub trajectory: usize,
    pub t0: f64,
    pub t1: f64,
    /// Output samples (rows) in the window.
    pub rows: usize,
    /// The model's state at `t0` (`nf.state` order).
    pub state: Vec<f64>,
    /// Singular values of the column-scaled sensitivity, descending.
    pub singular_values: Vec<f64>,
    /// Absolute threshold on those singular values (see the module doc).
    pub tolerance: f64,
    pub rank: usize,
    /// sigma_1 / sigma_rank (infinite at rank 0).
    pub condition: f64,
    /// Unit vectors (in the state's own coordinates) spanning what the window
    /// cannot see; empty at full rank.
    pub kernel: Vec<Vec<f64>>,
    /// The least visible direction (the last right singular vector).
    pub weakest: Vec<f64>,
    /// Which outputs the window measured (model order).
    pub outputs_seen: Vec<bool>,
    /// The recorded input samples active in the window (rows of `(1, u)`).
    pub input_rows: Vec<Vec<f64>>,
}

/// The compiled model: `f(u)` and its Jacobian, `h` and its gradient.
pub(crate) struct Compiled {
    n: usize,
    nd: usize,
    m: usize,
    /// Outputs per field F_i (F_0 = f0): nd values, then nd x n Jacobian.
    fields: Tape,
    /// Per output: its n-gradient.
    grads: Tape,
    n_out: usize,
}

pub(crate) fn compile(nf: &mut NormalForm) -> Result<Compiled, AnalysisError> {
    let (n, nd, m) = (nf.state.len(), nf.n_dynamic, nf.inputs.len());
    if nf.delay.is_some() || !nf.unknown_inputs.is_empty() {
        return Err(AnalysisError::Invalid(
            "observability along data needs a model without delay and unknown inputs".into(),
        ));
    }
    let state_vars = nf.state_vars.clone();
    let vars = tape_vars(nf);
    let mut all: Vec<Vec<Id>> = vec![nf.f0.clone()];
    all.extend(nf.fields.iter().cloned());
    let mut roots = Vec::with_capacity((m + 1) * nd * (n + 1));
    for f in &all {
        roots.extend(f[..nd].iter().copied());
        for &fk in &f[..nd] {
            for &v in &state_vars {
                roots.push(nf.ctx.diff(fk, v));
            }
        }
    }
    let outs: Vec<Id> = nf.outputs.iter().map(|o| o.1).collect();
    let mut groots = Vec::with_capacity(outs.len() * n);
    for &o in &outs {
        for &v in &state_vars {
            groots.push(nf.ctx.diff(o, v));
        }
    }
    let unbound = |e: obsan_expr::evaluate::UnboundSymbol| {
        AnalysisError::Invalid(format!(
            "'{}' has no value: give every constant a value (meta.json or --set)",
            e.0
        ))
    };
    Ok(Compiled {
        n,
        nd,
        m,
        fields: Tape::compile(&nf.ctx, &roots, &vars).map_err(unbound)?,
        grads: Tape::compile(&nf.ctx, &groots, &vars).map_err(unbound)?,
        n_out: outs.len(),
    })
}

/// The integrator's state: x (n values, params constant), the window's
/// sensitivity and the trajectory's (both nd x n, row-major).
struct Flow {
    z: Vec<f64>,
    phi_w: Vec<f64>,
    phi_t: Vec<f64>,
}

impl Compiled {
    /// d/dt of (x, Phi_w, Phi_t) at input `u`.
    fn rhs(&self, z: &[f64], u: &[f64], phis: [&[f64]; 2], scratch: &mut Vec<f64>) -> Vec<f64> {
        let (n, nd) = (self.n, self.nd);
        let vals = {
            let mut out = vec![0.0; self.fields.n_outputs()];
            self.fields.eval_into(z, scratch, &mut out);
            out
        };
        let block = nd * (n + 1);
        let mut dx = vec![0.0; nd];
        let mut jac = vec![0.0; nd * n];
        for i in 0..=self.m {
            let c = if i == 0 { 1.0 } else { u[i - 1] };
            if c == 0.0 {
                continue;
            }
            let b = &vals[i * block..(i + 1) * block];
            for (d, x) in dx.iter_mut().zip(&b[..nd]) {
                *d += c * x;
            }
            for (j, x) in jac.iter_mut().enumerate() {
                *x += c * b[nd + j];
            }
        }
        let mut out = dx;
        for phi in phis {
            // (J Phi_full)[k][j] with Phi_full = [Phi; 0 | I].
            for k in 0..nd {
                let jr = &jac[k * n..(k + 1) * n];
                for j in 0..n {
                    let mut s: f64 = (0..nd).map(|l| jr[l] * phi[l * n + j]).sum();
                    if j >= nd {
                        s += jr[j];
                    }
                    out.push(s);
                }
            }
        }
        out
    }

    fn step(&self, fl: &mut Flow, u: &[f64], h: f64, scratch: &mut Vec<f64>) {
        let (nd, pw) = (self.nd, self.nd * self.n);
        let pack = |fl: &Flow| {
            let mut y = fl.z[..nd].to_vec();
            y.extend(&fl.phi_w);
            y.extend(&fl.phi_t);
            y
        };
        let y0 = pack(fl);
        let eval = |y: &[f64], scratch: &mut Vec<f64>| {
            let mut z = fl.z.clone();
            z[..nd].copy_from_slice(&y[..nd]);
            self.rhs(&z, u, [&y[nd..nd + pw], &y[nd + pw..]], scratch)
        };
        let add = |a: &[f64], b: &[f64], s: f64| -> Vec<f64> {
            a.iter().zip(b).map(|(x, y)| x + s * y).collect()
        };
        let k1 = eval(&y0, scratch);
        let k2 = eval(&add(&y0, &k1, h / 2.0), scratch);
        let k3 = eval(&add(&y0, &k2, h / 2.0), scratch);
        let k4 = eval(&add(&y0, &k3, h), scratch);
        let y: Vec<f64> = (0..y0.len())
            .map(|i| y0[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
            .collect();
        fl.z[..nd].copy_from_slice(&y[..nd]);
        fl.phi_w.copy_from_slice(&y[nd..nd + pw]);
        fl.phi_t.copy_from_slice(&y[nd + pw..]);
    }

    /// Rows `dh_o Phi_full` of output `o` at the flow's point, for both Phis.
    fn rows(&self, fl: &Flow, measured: &[bool], scratch: &mut Vec<f64>) -> [Vec<Vec<f64>>; 2] {
        let n = self.n;
        let mut g = vec![0.0; self.grads.n_outputs()];
        self.grads.eval_into(&fl.z, scratch, &mut g);
        let mut out = [Vec::new(), Vec::new()];
        for o in (0..self.n_out).filter(|&o| measured.get(o) == Some(&true)) {
            let go = &g[o * n..(o + 1) * n];
            for (slot, phi) in out.iter_mut().zip([&fl.phi_w, &fl.phi_t]) {
                let row: Vec<f64> = (0..n)
                    .map(|j| {
                        let s: f64 = (0..self.nd).map(|l| go[l] * phi[l * n + j]).sum();
                        s + if j >= self.nd { go[j] } else { 0.0 }
                    })
                    .collect();
                slot.push(row);
            }
        }
        out
    }
}

/// Rows of a matrix.
pub(crate) type Rows = Vec<Vec<f64>>;

/// One window of one pass.
pub(crate) struct WindowRows {
    t0: f64,
    t1: f64,
    /// The model's state at `t0`.
    state: Vec<f64>,
    rows: Rows,
    /// Which outputs were measured.
    seen: Vec<bool>,
    /// The active input samples as `(1, u)`.
    inputs: Rows,
}

/// The matrices of one trajectory at one step refinement.
pub(crate) struct Pass {
    pub windows: Vec<WindowRows>,
    /// The whole trajectory's rows (sensitivity to its start).
    pub whole: Rows,
}

/// The whole trajectories' rows at the fine and the coarse step.
pub(crate) type Wholes = Vec<[Rows; 2]>;

fn identity_phi(nd: usize, n: usize) -> Vec<f64> {
    let mut p = vec![0.0; nd * n];
    for k in 0..nd {
        p[k * n + k] = 1.0;
    }
    p
}

/// Integrate one trajectory, each RK4 step split in `split` sub-steps.
pub(crate) fn integrate(
    c: &Compiled,
    tr: &AlongTrajectory,
    window: f64,
    split: usize,
    deadline: Option<Instant>,
) -> Result<Pass, AnalysisError> {
    let (n, nd) = (c.n, c.nd);
    let t_start = tr.input_t.first().copied().unwrap_or(0.0);
    let t_end = tr.output_t.last().copied().unwrap_or(t_start);
    let mut z = tr.start.clone();
    z.extend(&tr.consts);
    let mut fl = Flow {
        z,
        phi_w: identity_phi(nd, n),
        phi_t: identity_phi(nd, n),
    };
    // Whole windows; the remainder joins the last one (a sliver with a sample
    // or two would report what two samples cannot see, not the data's degeneracy).
    let count = ((t_end - t_start) / window).floor();
    if count > MAX_WINDOWS as f64 {
        return Err(AnalysisError::Invalid(format!(
            "trajectory '{}': {count} windows of {window} s (at most {MAX_WINDOWS}): choose a longer --window",
            tr.name
        )));
    }
    let n_win = (count as usize).max(1);
    let mut pass = Pass {
        windows: Vec::with_capacity(n_win),
        whole: Vec::new(),
    };
    let (mut ki, mut ko) = (0usize, 0usize);
    let mut scratch = Vec::new();
    let mut t = t_start;
    for w in 0..n_win {
        let w0 = t_start + w as f64 * window;
        let w1 = if w + 1 == n_win {
            f64::INFINITY
        } else {
            t_start + (w + 1) as f64 * window
        };
        fl.phi_w = identity_phi(nd, n);
        let state = fl.z[..n].to_vec();
        let mut rows = Vec::new();
        let mut seen = vec![false; c.n_out];
        let mut inputs = Vec::new();
        let ki_first = ki;
        let mut ki_last = ki;
        loop {
            if let Some(d) = deadline {
                if Instant::now() > d {
                    return Err(AnalysisError::Timeout(format!(
                        "at t = {t} s of trajectory '{}'",
                        tr.name
                    )));
                }
            }
            // Samples at the current time first.
            while ko < tr.output_t.len() && tr.output_t[ko] <= t && tr.output_t[ko] < w1 {
                let [rw, rt] = c.rows(&fl, &tr.measured[ko], &mut scratch);
                rows.extend(rw);
                pass.whole.extend(rt);
                for (s, &m) in seen.iter_mut().zip(&tr.measured[ko]) {
                    *s |= m;
                }
                ko += 1;
            }
            while ki + 1 < tr.input_t.len() && tr.input_t[ki + 1] <= t {
                ki += 1;
            }
            if t >= w1 || t >= t_end || ko >= tr.output_t.len() {
                break;
            }
            let mut next = w1.min(t_end);
            if ki + 1 < tr.input_t.len() {
                next = next.min(tr.input_t[ki + 1]);
            }
            if ko < tr.output_t.len() {
                next = next.min(tr.output_t[ko]);
            }
            ki_last = ki;
            let u = tr.inputs.get(ki).cloned().unwrap_or_else(|| vec![0.0; c.m]);
            let h = (next - t) / split as f64;
            for _ in 0..split {
                c.step(&mut fl, &u, h, &mut scratch);
            }
            if fl.z.iter().any(|x| !x.is_finite()) {
                return Err(AnalysisError::Invalid(format!(
                    "the model's state diverged at t = {next} s of trajectory '{}'",
                    tr.name
                )));
            }
            t = next;
        }
        for k in (ki_first..=ki_last).filter(|&k| k < tr.inputs.len()) {
            let mut r = vec![1.0];
            r.extend(&tr.inputs[k]);
            inputs.push(r);
        }
        pass.windows.push(WindowRows {
            t0: w0,
            t1: w1.min(t_end),
            state,
            rows,
            seen,
            inputs,
        });
        if ko >= tr.output_t.len() {
            break;
        }
    }
    Ok(pass)
}

/// Numerical rank of `fine` with the error estimated by `fine - coarse`:
/// (singular values, absolute tolerance, rank, right singular vectors in
/// the original coordinates, unit length).
pub(crate) fn numerical_rank(
    fine: &[Vec<f64>],
    coarse: &[Vec<f64>],
    n: usize,
) -> (Vec<f64>, f64, usize, Vec<Vec<f64>>) {
    let scale: Vec<f64> = (0..n)
        .map(|j| {
            let s = fine.iter().map(|r| r[j] * r[j]).sum::<f64>().sqrt();
            if s > 0.0 {
                s
            } else {
                1.0
            }
        })
        .collect();
    let scaled: Vec<Vec<f64>> = fine
        .iter()
        .map(|r| r.iter().zip(&scale).map(|(x, s)| x / s).collect())
        .collect();
    let err: f64 = fine
        .iter()
        .zip(coarse)
        .flat_map(|(a, b)| a.iter().zip(b).zip(&scale).map(|((x, y), s)| (x - y) / s))
        .map(|d| d * d)
        .sum::<f64>()
        .sqrt();
    let (s, v) = if scaled.is_empty() {
        (
            vec![0.0; n],
            crate::along_linalg::orthonormal(&identity_rows(n), 0.0),
        )
    } else {
        svd(&scaled, n)
    };
    let s1 = s.first().copied().unwrap_or(0.0);
    let tol = (TOL_SAFETY * err).max(ROUNDING_FLOOR * s1);
    let rank = s.iter().filter(|&&x| x > tol).count();
    let vecs = v
        .into_iter()
        .map(|x| {
            let y: Vec<f64> = x.iter().zip(&scale).map(|(a, s)| a / s).collect();
            let norm = dot(&y, &y).sqrt();
            y.iter().map(|a| a / norm).collect()
        })
        .collect();
    (s, tol, rank, vecs)
}

fn identity_rows(n: usize) -> Vec<Vec<f64>> {
    (0..n)
        .map(|j| (0..n).map(|i| f64::from(u8::from(i == j))).collect())
        .collect()
}

/// Every window of every trajectory, with its numerical rank.
pub(crate) fn windows(
    nf: &mut NormalForm,
    trajs: &[AlongTrajectory],
    opts: &AlongOptions,
) -> Result<(Vec<AlongWindow>, Wholes), AnalysisError> {
    let c = compile(nf)?;
    let n = c.n;
    let mut out = Vec::new();
    let mut wholes = Vec::new();
    for (ti, tr) in trajs.iter().enumerate() {
        if tr.start.len() != n || tr.consts.len() != generic_consts(nf).len() {
            return Err(AnalysisError::Invalid(format!(
                "trajectory '{}': {} start values for {n} variables, {} constants for {}",
                tr.name,
                tr.start.len(),
                tr.consts.len(),
                generic_consts(nf).len()
            )));
        }
        let coarse = integrate(&c, tr, opts.window, 1, opts.deadline)?;
        let fine = integrate(&c, tr, opts.window, 2, opts.deadline)?;
        for (wf, wc) in fine.windows.into_iter().zip(coarse.windows) {
            let WindowRows {
                t0,
                t1,
                state,
                rows,
                seen,
                inputs,
            } = wf;
            let (s, tol, rank, v) = numerical_rank(&rows, &wc.rows, n);
            let condition = if rank == 0 {
                f64::INFINITY
            } else {
                s[0] / s[rank - 1]
            };
            out.push(AlongWindow {
                trajectory: ti,
                t0,
                t1,
                rows: rows.len(),
                state,
                singular_values: s,
                tolerance: tol,
                rank,
                condition,
                kernel: v[rank..].to_vec(),
                weakest: v.last().cloned().unwrap_or_default(),
                outputs_seen: seen,
                input_rows: inputs,
            });
        }
        wholes.push([fine.whole, coarse.whole]);
    }
    Ok((out, wholes))
}
