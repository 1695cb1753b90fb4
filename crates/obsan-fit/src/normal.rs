//! One linearisation of the fit, streamed: each trajectory's prediction
//! hands on its residuals and Jacobian rows one output time at a time; each
//! row is normalised, whitened (the whitening is a forward Kalman recursion,
//! see `whiten.rs`, so it needs no later row) and added into that
//! trajectory's part of the normal equations `J^T J`, `J^T r` at once. No
//! residual vector is kept, and the Jacobian rows only where the fit's
//! secant model needs them ([`JacStore`]): memory is the data's size plus
//! one Jacobian, not several copies of it.

use crate::options::{FitOptions, FitTrajectory};
use crate::predict::{Integration, Measured, Predictor};
use crate::whiten::{RowFilter, Whitener, WhitenerBuilder};
use crate::FitError;
use obsan_data::wrap;
use std::sync::{Mutex, RwLock};

/// Most shared params a fit or a CRLB takes, refused before anything is
/// allocated: the normal equations, their secant model and the covariance
/// are dense in the number of unknowns squared (1,000 params: 8 MB each).
pub const MAX_FIT_PARAMS: usize = 1_000;

/// A second Jacobian (the trial point's, beside the current one) is kept
/// while both fit in this many bytes: then a rejected trial costs nothing
/// more. Past it the trial's rows overwrite the current ones row by row, and
/// a rejected trial makes the next trial re-linearise the current point
/// first (one more prediction, the same numbers): a large dataset's fit
/// holds one Jacobian, not two.
pub(crate) const SPARE_JACOBIAN_BYTES: usize = 64 << 20;

pub(crate) struct Layout {
    pub(crate) n_params: usize,
    pub(crate) n_dyn: usize,
    pub(crate) n_traj: usize,
}

impl Layout {
    pub(crate) fn len(&self) -> usize {
        self.n_params + self.n_dyn * self.n_traj
    }
    /// Theta index of each column of trajectory `k`'s Jacobian: its own
    /// initial dynamic state, then the shared params.
    pub(crate) fn columns(&self, k: usize) -> Vec<usize> {
        (0..self.n_dyn)
            .map(|i| self.n_params + k * self.n_dyn + i)
            .chain(0..self.n_params)
            .collect()
    }
    pub(crate) fn state_of(&self, theta: &[f64], k: usize) -> Vec<f64> {
        let mut x: Vec<f64> =
            theta[self.n_params + k * self.n_dyn..self.n_params + (k + 1) * self.n_dyn].to_vec();
        x.extend_from_slice(&theta[..self.n_params]);
        x
    }
}

/// One linearisation: the normal equations, the cost, per trajectory its
/// score, and the sums of the residuals' squares per output.
pub(crate) struct Normal {
    pub(crate) jtj: Vec<Vec<f64>>,
    pub(crate) jtr: Vec<f64>,
    pub(crate) cost: f64,
    /// Per trajectory: its score `J_k^T r_k`, in its columns
    /// ([`Layout::columns`]).
    pub(crate) score: Vec<Vec<f64>>,
    /// For a trial ([`Rows::Trial`]): `J^T r` of the stored (current)
    /// Jacobian with this point's residuals, for the secant update.
    pub(crate) old_jt: Vec<f64>,
    pub(crate) n_residuals: usize,
    /// Per output: the sum of the squared residuals before whitening (in
    /// the output's units) and their count.
    pub(crate) sq_sum: Vec<f64>,
    pub(crate) counts: Vec<usize>,
}

/// Per trajectory, the whitened Jacobian rows of the current linearisation
/// (flat, `nc` columns), and with a spare, the trial's beside them.
pub(crate) struct JacStore {
    bufs: Vec<Mutex<JacBuf>>,
    spare: bool,
    /// The current rows are those of the current point (false after a
    /// rejected trial overwrote them).
    pub(crate) valid: bool,
}

#[derive(Default)]
struct JacBuf {
    cur: Vec<f64>,
    next: Vec<f64>,
}

impl JacStore {
    pub(crate) fn new(n_traj: usize, spare: bool) -> JacStore {
        JacStore {
            bufs: (0..n_traj).map(|_| Mutex::new(JacBuf::default())).collect(),
            spare,
            valid: false,
        }
    }

    /// After a trial: accepted, its rows are the current ones; rejected (or
    /// failed), the current rows stay valid only if the trial had a spare.
    pub(crate) fn settle(&mut self, accepted: bool) {
        if self.spare {
            if accepted {
                for b in &mut self.bufs {
                    let b = b.get_mut().unwrap_or_else(|e| e.into_inner());
                    std::mem::swap(&mut b.cur, &mut b.next);
                }
            }
        } else {
            self.valid = accepted;
        }
    }
}

/// What a linearisation does with its Jacobian rows.
#[derive(Clone, Copy)]
pub(crate) enum Rows<'s> {
    /// Nothing (the CRLB, the final covariance, a cost).
    Drop,
    /// Store them as the current rows.
    Keep(&'s JacStore),
    /// A trial point's: `J^T r` of the current rows with this point's
    /// residuals ([`Normal::old_jt`]), and this point's rows stored in the
    /// spare or over the current ones.
    Trial(&'s JacStore),
}

/// How a trajectory's rows are whitened.
#[derive(Clone, Copy)]
enum Weights {
    /// By a whitener built from this prediction (kept or not).
    Fresh { keep: bool },
    /// By the whitener kept for the trajectory (none: not whitened).
    Kept,
    /// Not whitened.
    None,
}

/// One trajectory's part of a linearisation.
struct Part {
    /// `nc x nc`, row-major, in the trajectory's columns.
    jtj: Vec<f64>,
    g: Vec<f64>,
    old_g: Vec<f64>,
    cost: f64,
    n: usize,
    sq_sum: Vec<f64>,
    counts: Vec<usize>,
    /// With [`Weights::Fresh`]: the new whitener (`None` when the noise's
    /// increments were not positive semi-definite: then unwhitened).
    fresh: Option<Option<Whitener>>,
}

/// The problem's fixed parts: model, data, options, column indices.
pub(crate) struct Problem<'a> {
    pub(crate) p: &'a Predictor,
    pub(crate) trajs: &'a [FitTrajectory<'a>],
    pub(crate) opts: &'a FitOptions,
    pub(crate) lay: Layout,
    /// Per trajectory, its measured cells.
    cells: Vec<Measured<'a>>,
    /// Per trajectory, the whitening factor L (residuals become L^-1 r).
    /// A lock, not a cell: the trajectories are predicted in parallel.
    whiten: RwLock<Vec<Option<Whitener>>>,
}

impl Problem<'_> {
    pub(crate) fn new<'a>(
        p: &'a Predictor,
        trajs: &'a [FitTrajectory<'a>],
        opts: &'a FitOptions,
        init_params: &[f64],
        init_states: &[Vec<f64>],
    ) -> Result<Problem<'a>, FitError> {
        let n_params = p.state.len() - p.n_dynamic;
        if n_params > MAX_FIT_PARAMS {
            return Err(FitError::TooManyParams {
                params: n_params,
                limit: MAX_FIT_PARAMS,
            });
        }
        if init_params.len() != n_params
            || init_states.len() != trajs.len()
            || init_states.iter().any(|s| s.len() != p.n_dynamic)
        {
            return Err(FitError::BadStart);
        }
        if opts.sigma.len() != p.outputs.len() || opts.sigma.iter().any(|s| s.is_nan() || *s <= 0.0)
        {
            return Err(FitError::NoiseLevels);
        }
        for t in trajs {
            if let Some(o) = p.outputs.iter().find(|o| !t.outputs.columns().contains(o)) {
                return Err(FitError::MissingOutput(o.clone()));
            }
        }
        Ok(Problem {
            p,
            trajs,
            opts,
            lay: Layout {
                n_params,
                n_dyn: p.n_dynamic,
                n_traj: trajs.len(),
            },
            whiten: RwLock::new(vec![None; trajs.len()]),
            cells: trajs.iter().map(|t| Measured::new(p, t.outputs)).collect(),
        })
    }

    /// Whether a spare Jacobian fits in [`SPARE_JACOBIAN_BYTES`].
    pub(crate) fn spare_fits(&self) -> bool {
        let cells: usize = self.cells.iter().map(Measured::len).sum();
        cells.saturating_mul(self.p.state.len()).saturating_mul(8) <= SPARE_JACOBIAN_BYTES
    }

    /// The whiteners. A panic elsewhere while they were written (the lock
    /// poisoned) leaves each entry whole, old or new: they are read as they
    /// are, never taken for white noise.
    pub(crate) fn whiteners(&self) -> std::sync::RwLockReadGuard<'_, Vec<Option<Whitener>>> {
        self.whiten.read().unwrap_or_else(|e| e.into_inner())
    }

    /// The whiteners, moved out (they are as large as the data).
    pub(crate) fn into_whiteners(self) -> Vec<Option<Whitener>> {
        self.whiten.into_inner().unwrap_or_else(|e| e.into_inner())
    }

    fn whiteners_mut(&self) -> std::sync::RwLockWriteGuard<'_, Vec<Option<Whitener>>> {
        self.whiten.write().unwrap_or_else(|e| e.into_inner())
    }

    /// Run `f` on every trajectory index in parallel (a trajectory's
    /// prediction is independent of the others'), the results in trajectory
    /// order so that every sum over them is the serial one, bit for bit;
    /// the first failing trajectory's error. The caller's cancel flag is
    /// thread-local: it is handed to the workers.
    fn per_trajectory<T: Send>(
        &self,
        f: impl Fn(usize) -> Result<T, FitError> + Sync,
    ) -> Result<Vec<T>, FitError> {
        use rayon::prelude::*;
        let cancel = obsan_expr::cancel_flag();
        let out: Vec<Result<T, FitError>> = (0..self.trajs.len())
            .into_par_iter()
            .map(|k| {
                obsan_expr::with_cancel(cancel.clone(), || {
                    cancel_point()?;
                    f(k)
                })
            })
            .collect();
        out.into_iter().collect()
    }

    /// The cost (sum of squared whitened residuals) at `theta`, without
    /// sensitivities.
    pub(crate) fn cost(&self, theta: &[f64]) -> Result<f64, FitError> {
        let parts = self.per_trajectory(|k| {
            let x0 = self.lay.state_of(theta, k);
            Ok(self
                .trajectory(k, &x0, Weights::Kept, false, Rows::Drop)?
                .cost)
        })?;
        Ok(parts.iter().sum())
    }

    /// The normal equations `J^T J`, `J^T r` at `theta`, trajectory by
    /// trajectory (a trajectory's initial state touches only its residuals),
    /// from one prediction with sensitivities per trajectory. With `refresh`
    /// (and input noise), the whitening is first recomputed at `theta` from
    /// the same prediction.
    pub(crate) fn normal(
        &self,
        theta: &[f64],
        refresh: bool,
        rows: Rows,
    ) -> Result<Normal, FitError> {
        self.linearise(theta, refresh, true, rows)
    }

    /// The Fisher information `J^T J` at `theta` (whitened at `theta` with
    /// input noise), keeping neither rows nor whiteners.
    pub(crate) fn fisher(&self, theta: &[f64]) -> Result<Vec<Vec<f64>>, FitError> {
        Ok(self.linearise(theta, true, false, Rows::Drop)?.jtj)
    }

    fn linearise(
        &self,
        theta: &[f64],
        refresh: bool,
        keep: bool,
        rows: Rows,
    ) -> Result<Normal, FitError> {
        let lay = &self.lay;
        let n = lay.len();
        let n_out = self.p.outputs.len();
        let weights = if refresh && self.opts.input_noise.is_some() {
            Weights::Fresh { keep }
        } else {
            Weights::Kept
        };
        if keep && matches!(weights, Weights::Fresh { .. }) {
            // The old whiteners are not read by a fresh pass: dropped
            // first, they never sit beside the new ones (each is as large
            // as the data). A pass that fails ends the fit or bound anyway.
            self.whiteners_mut().iter_mut().for_each(|w| *w = None);
        }
        let parts = self
            .per_trajectory(|k| self.trajectory(k, &lay.state_of(theta, k), weights, true, rows))?;
        let mut out = Normal {
            jtj: vec![vec![0.0; n]; n],
            jtr: vec![0.0; n],
            cost: 0.0,
            score: Vec::with_capacity(parts.len()),
            old_jt: vec![0.0; n],
            n_residuals: 0,
            sq_sum: vec![0.0; n_out],
            counts: vec![0; n_out],
        };
        for (k, part) in parts.into_iter().enumerate() {
            if let Some(fresh) = part.fresh {
                self.whiteners_mut()[k] = fresh;
            }
            let idx = lay.columns(k);
            let nc = idx.len();
            for (a, &ja) in idx.iter().enumerate() {
                out.jtr[ja] += part.g[a];
                out.old_jt[ja] += part.old_g[a];
                for (b, &jb) in idx.iter().enumerate() {
                    out.jtj[ja][jb] += part.jtj[a * nc + b];
                }
            }
            out.cost += part.cost;
            out.n_residuals += part.n;
            for o in 0..n_out {
                out.sq_sum[o] += part.sq_sum[o];
                out.counts[o] += part.counts[o];
            }
            out.score.push(part.g);
        }
        Ok(out)
    }

    /// Trajectory `k`'s part of a linearisation at its initial state `x0`
    /// (with its Jacobian rows when `jac`). A fresh whitener that fails
    /// (increments not positive semi-definite) leaves the trajectory
    /// unwhitened, as a whitener built from stored rows would: it is
    /// linearised again without one.
    fn trajectory(
        &self,
        k: usize,
        x0: &[f64],
        weights: Weights,
        jac: bool,
        rows: Rows,
    ) -> Result<Part, FitError> {
        match self.stream(k, x0, weights, jac, rows)? {
            Some(part) => Ok(part),
            None => {
                let mut part = self
                    .stream(k, x0, Weights::None, jac, rows)?
                    .ok_or(FitError::BadStart)?;
                if matches!(weights, Weights::Fresh { keep: true }) {
                    part.fresh = Some(None);
                }
                Ok(part)
            }
        }
    }

    /// The streamed body of [`Problem::trajectory`]; `None` when a fresh
    /// whitener failed.
    fn stream(
        &self,
        k: usize,
        x0: &[f64],
        weights: Weights,
        jac: bool,
        rows: Rows,
    ) -> Result<Option<Part>, FitError> {
        let (p, opts, cells) = (self.p, self.opts, &self.cells[k]);
        let t = &self.trajs[k];
        let (n, nd) = (p.state.len(), p.n_dynamic);
        let (fresh, keep) = match weights {
            Weights::Fresh { keep } => (true, keep),
            _ => (false, false),
        };
        let integ = Integration {
            max_step: opts.max_step,
            sensitivities: jac || fresh,
            input_noise: if fresh {
                opts.input_noise.clone()
            } else {
                None
            },
        };
        let nc = if jac { n } else { 0 };
        let guard = self.whiteners();
        let kept = match weights {
            Weights::Kept => guard[k].as_ref(),
            _ => None,
        };
        let mut builder = fresh.then(|| WhitenerBuilder::new(nd, cells.len(), keep));
        let mut filter = (fresh || kept.is_some()).then(|| RowFilter::new(nd, 1 + nc));
        let n_out = p.outputs.len();
        let mut part = Part {
            jtj: vec![0.0; nc * nc],
            g: vec![0.0; nc],
            old_g: vec![0.0; nc],
            cost: 0.0,
            n: 0,
            sq_sum: vec![0.0; n_out],
            counts: vec![0; n_out],
            fresh: None,
        };
        let store = match rows {
            Rows::Drop => None,
            Rows::Keep(s) => Some((s, false)),
            Rows::Trial(s) => Some((s, true)),
        };
        // (the lock, a trial's, a trial with a spare); the lock is this
        // trajectory's alone.
        let mut buf = store.map(|(s, trial)| {
            let b = s.bufs[k].lock().unwrap_or_else(|e| e.into_inner());
            (b, trial, trial && s.spare)
        });
        if let Some((b, trial, spare)) = buf.as_mut() {
            // A trial without a spare overwrites the current rows in place.
            let dest = if *spare {
                Some(&mut b.next)
            } else if !*trial {
                Some(&mut b.cur)
            } else {
                None
            };
            if let Some(d) = dest {
                d.clear();
                d.reserve_exact(cells.len() * nc);
            }
        }
        let mut row = vec![0.0; 1 + nc];
        let mut broken = false;
        p.predict_measured_each(
            x0,
            &t.consts,
            t.inputs,
            cells,
            &integ,
            &mut |kt, yk, jk, mk| {
                let (outs, values) = cells.at(kt);
                for (i, (&o, &m)) in outs.iter().zip(values).enumerate() {
                    if broken {
                        return;
                    }
                    let d = m - yk[i];
                    let d = if p.angular[o] { wrap(d) } else { d };
                    let r = d / opts.sigma[o];
                    let raw = r * opts.sigma[o];
                    part.sq_sum[o] += raw * raw;
                    part.counts[o] += 1;
                    row[0] = r;
                    for (x, v) in row[1..].iter_mut().zip(&jk[i * nc..(i + 1) * nc]) {
                        *x = v / opts.sigma[o];
                    }
                    if let (Some(b), Some(f)) = (builder.as_mut(), filter.as_mut()) {
                        match b.push(&row[1..1 + nd], mk) {
                            Some((a, g, sd)) => f.apply(a, g, sd, &mut row),
                            None => broken = true,
                        }
                    } else if let (Some(w), Some(f)) = (kept, filter.as_mut()) {
                        let (a, g, sd) = w.step(part.n);
                        f.apply(a, g, sd, &mut row);
                    }
                    let (rw, jw) = (row[0], &row[1..]);
                    part.cost += rw * rw;
                    for (a, &ja) in jw.iter().enumerate() {
                        part.g[a] += ja * rw;
                        for (b, &jb) in jw.iter().enumerate() {
                            part.jtj[a * nc + b] += ja * jb;
                        }
                    }
                    if let Some((b, trial, spare)) = buf.as_mut() {
                        let at = part.n * nc..(part.n + 1) * nc;
                        if *trial {
                            if let Some(old) = b.cur.get(at.clone()) {
                                for (g, x) in part.old_g.iter_mut().zip(old) {
                                    *g += x * rw;
                                }
                            }
                        }
                        if *spare {
                            b.next.extend_from_slice(jw);
                        } else if *trial {
                            if let Some(old) = b.cur.get_mut(at) {
                                old.copy_from_slice(jw);
                            }
                        } else {
                            b.cur.extend_from_slice(jw);
                        }
                    }
                    part.n += 1;
                }
            },
        )
        .map_err(|e| FitError::Trajectory {
            name: t.name.to_string(),
            source: Box::new(e),
        })?;
        if broken {
            return Ok(None);
        }
        if keep {
            part.fresh = builder.map(WhitenerBuilder::finish);
        }
        Ok(Some(part))
    }
}

/// `Err(Cancelled)` once the caller asked the work to stop (polled per
/// trajectory prediction: the fit's unit of work).
pub(crate) fn cancel_point() -> Result<(), FitError> {
    if obsan_expr::cancel_requested() {
        return Err(FitError::Cancelled);
    }
    Ok(())
}

#[cfg(test)]
#[path = "normal_tests.rs"]
mod tests;
