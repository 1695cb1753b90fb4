//! Monte Carlo runs laid out like the paper's Tables IV-VII, with the
//! paper's figures beside ours, the Cramér–Rao bound and the efficiency
//! (RMS error / CRLB standard deviation). Runs are independent and seeded by
//! `seed + run` (`run_seed`), so a run's numbers depend only on the seed,
//! the cell and the run's index: any subset of the runs (a shard) can be
//! computed anywhere, and [`summarize`] of all of them, in index order, is
//! bit for bit the table one process gives.

use crate::calib::av_from_state;
use crate::calibrate::{calibrate, CalibrateOptions, CekfInit, Method};
use crate::error::CalibError;
use crate::sim::{simulate, SimOptions, Truth};
use obsan_data::{wrap, Dataset};
use obsan_fit::{crlb, FitOptions, FitTrajectory, Predictor};
use rayon::prelude::*;
use std::ops::Range;

/// Why run records could not be assembled into a cell's table. (Failures of
/// the simulator and the bound are [`CalibError`]s.)
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum MontecarloError {
    /// Records given to [`summarize`] or [`merge_runs`] are not the runs
    /// 0, 1, ..., n-1 of the cell, each with one outcome per method and the
    /// table's columns: the message says where they differ.
    Records(String),
    /// The caller asked the runs to stop ([`obsan_expr::with_cancel`]).
    Cancelled,
}

impl std::fmt::Display for MontecarloError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MontecarloError::Records(s) => f.write_str(s),
            MontecarloError::Cancelled => f.write_str("interrupted"),
        }
    }
}

impl std::error::Error for MontecarloError {}

/// A method as the tables name it (CEKF from a 30% off guess, CEKFd from DET).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum McMethod {
    Det,
    Ls,
    Cekf,
    Cekfd,
    Ml,
}

impl McMethod {
    pub fn name(self) -> &'static str {
        match self {
            McMethod::Det => "DET",
            McMethod::Ls => "LS",
            McMethod::Cekf => "CEKF",
            McMethod::Cekfd => "CEKFd",
            McMethod::Ml => "ML",
        }
    }
}

/// One cell: a set-up, its label, the methods to run and the paper's figures.
#[derive(Clone, Debug)]
pub struct Cell {
    pub label: String,
    pub sim: SimOptions,
    pub methods: Vec<McMethod>,
    /// The paper's figures for (method, values) in this cell's columns.
    pub paper: Vec<(McMethod, Vec<f64>)>,
}

/// A table: which columns it reports.
#[derive(Clone, Debug)]
pub struct Table {
    pub number: u8,
    pub title: String,
    /// Column names; Table VI reports the modes, the others the parameters.
    pub columns: Vec<&'static str>,
    pub modes: bool,
    /// Table IV reports estimates of a single run, not errors.
    pub estimates: bool,
    pub cells: Vec<Cell>,
}

impl Table {
    pub const PARAM_COLUMNS: [&str; 5] =
        ["phi (deg)", "psi (deg)", "eta (%)", "delta (%)", "xi (%)"];
    pub const MODE_COLUMNS: [&str; 4] = ["xi_q (%)", "L (deg)", "c (deg)", "k (%)"];
}

fn setup(sigma_deg: f64, iota: f64, dq: f64, bearings: usize) -> SimOptions {
    SimOptions {
        sigma_beta: sigma_deg.to_radians(),
        iota,
        dq,
        bearings: Some(bearings),
        ..SimOptions::default()
    }
}

/// The paper's tables as cells (bearings per trajectory: 300 in Table IV,
/// 100 elsewhere, as the paper states).
pub fn table(number: u8) -> Option<Table> {
    let p = |m, v: &[f64]| (m, v.to_vec());
    Some(match number {
        4 => Table {
            number,
            title: "Table IV: estimates by LS (initialised by DET), one run per sigma_beta, 300 bearings".into(),
            columns: vec!["phi (deg)", "psi (deg)", "eta", "delta", "xi"],
            modes: false,
            estimates: true,
            cells: [
                (1.0, [-0.08, 90.05, 0.49596, 1.01610, 0.61296]),
                (3.0, [0.21, 90.08, 0.49362, 1.01629, 0.61167]),
                (5.0, [0.13, 89.83, 0.50103, 1.01607, 0.61323]),
            ]
            .iter()
            .map(|(s, v)| Cell {
                label: format!("sigma_beta = {s} deg"),
                sim: setup(*s, 0.0, 0.0, 300),
                methods: vec![McMethod::Ls, McMethod::Ml],
                paper: vec![p(McMethod::Ls, v)],
            })
            .collect(),
        },
        5 => Table {
            number,
            title: "Table V: mean absolute errors over the runs, 100 bearings per trajectory".into(),
            columns: Table::PARAM_COLUMNS.to_vec(),
            modes: false,
            estimates: false,
            cells: [
                (0.0, 1.0, [0.10, 0.08, 0.32, 0.005, 0.045]),
                (0.02, 1.0, [0.65, 0.37, 1.5, 0.05, 0.15]),
                (0.04, 1.0, [1.3, 0.5, 3.2, 0.10, 0.19]),
                (0.0, 3.0, [0.19, 0.13, 0.53, 0.012, 0.087]),
                (0.02, 3.0, [1.2, 0.71, 2.5, 0.11, 0.25]),
                (0.04, 3.0, [2.2, 0.9, 5.2, 0.23, 0.41]),
                (0.0, 5.0, [0.28, 0.23, 0.85, 0.019, 0.13]),
                (0.02, 5.0, [1.7, 1.0, 3.9, 0.18, 0.56]),
                (0.04, 5.0, [3.1, 1.6, 5.7, 0.35, 0.66]),
            ]
            .iter()
            .map(|(iota, s, v)| Cell {
                label: format!("iota = {iota}, sigma_beta = {s} deg"),
                sim: setup(*s, *iota, 0.0, 100),
                methods: vec![McMethod::Ls, McMethod::Ml],
                paper: vec![p(McMethod::Ls, v)],
            })
            .collect(),
        },
        6 => Table {
            number,
            title: "Table VI: mean absolute errors of the modes (all trajectories), 100 bearings per trajectory".into(),
            columns: Table::MODE_COLUMNS.to_vec(),
            modes: true,
            estimates: false,
            cells: [
                (0.04, 5.0, [9.3, 4.3], [3.2, 3.8, 1.1, 27.0], [1.6, 1.2], [0.74, 0.41, 0.83, 1.6]),
                (0.0, 5.0, [2.8, 1.5], [1.4, 1.1, 0.45, 16.0], [0.55, 0.37], [0.23, 0.17, 0.22, 0.85]),
                (0.04, 1.0, [5.8, 3.5], [3.1, 0.25, 0.28, 6.3], [0.87, 0.13], [0.18, 0.11, 0.27, 0.29]),
                (0.0, 1.0, [1.7, 0.75], [1.5, 0.061, 0.093, 2.7], [0.11, 0.039], [0.059, 0.040, 0.065, 0.12]),
            ]
            .iter()
            .map(|(iota, s, cekf, det, cekfd, ls)| Cell {
                label: format!("iota = {iota}, sigma_beta = {s} deg"),
                sim: setup(*s, *iota, 0.0, 100),
                methods: vec![McMethod::Cekf, McMethod::Det, McMethod::Cekfd, McMethod::Ls, McMethod::Ml],
                paper: vec![
                    p(McMethod::Cekf, cekf),
                    p(McMethod::Det, det),
                    p(McMethod::Cekfd, cekfd),
                    p(McMethod::Ls, ls),
                ],
            })
            .collect(),
        },
        7 => Table {
            number,
            title: "Table VII: mean absolute errors under a systematic ratio error dq, sigma_beta = 1 deg, 100 bearings".into(),
            columns: Table::PARAM_COLUMNS.to_vec(),
            modes: false,
            estimates: false,
            cells: [
                (0.0, [0.10, 0.08, 0.32, 0.005, 0.045]),
                (0.01, [0.17, 0.20, 1.4, 0.69, 0.40]),
                (0.03, [0.48, 0.51, 3.3, 2.3, 1.2]),
                (0.05, [0.83, 0.92, 6.3, 4.1, 2.0]),
                (0.10, [1.5, 1.6, 13.0, 7.9, 4.2]),
            ]
            .iter()
            .map(|(dq, v)| Cell {
                label: format!("dq = {dq}"),
                sim: setup(1.0, 0.0, *dq, 100),
                methods: vec![McMethod::Ls, McMethod::Ml],
                paper: vec![p(McMethod::Ls, v)],
            })
            .collect(),
        },
        _ => return None,
    })
}

/// Per method: the mean absolute error, the RMS error (or, for Table IV, the
/// mean estimate) per column, and the runs it could not complete.
#[derive(Clone, Debug)]
pub struct MethodStats {
    pub method: McMethod,
    pub mean_abs: Vec<f64>,
    pub rms: Vec<f64>,
    pub mean_estimate: Vec<f64>,
    pub failures: usize,
    pub first_failure: Option<String>,
}

/// A cell's outcome.
#[derive(Clone, Debug)]
pub struct CellResult {
    pub label: String,
    pub runs: usize,
    pub methods: Vec<MethodStats>,
    /// CRLB standard deviation per parameter column (bearing noise only), if
    /// computed: the bound of an estimator that knows the circle (DET, LS, CEKF).
    pub crlb_sd: Option<Vec<f64>>,
    /// With the encoder noise too: the bound of one driven by the measured
    /// wheel speeds (ML); `None` without encoder noise.
    pub crlb_sd_encoders: Option<Vec<f64>>,
}

impl CellResult {
    /// The bound that matches a method's information (see the fields), and
    /// its name: "CRLB" (bearings) or "CRLB+enc".
    pub fn bound_for(&self, m: McMethod) -> Option<(&[f64], &'static str)> {
        match (m, &self.crlb_sd_encoders) {
            (McMethod::Ml, Some(b)) => Some((b, "CRLB+enc")),
            _ => self.crlb_sd.as_deref().map(|b| (b, "CRLB")),
        }
    }
}

/// Errors of one run in the table's units: parameters (deg, deg, %, %, %)
/// or modes (%, deg, deg, %), averaged over the trajectories for modes.
fn param_errors(est: &[f64; 5], t: &Truth) -> Vec<f64> {
    vec![
        wrap(est[0] - t.phi).to_degrees(),
        wrap(est[1] - t.psi).to_degrees(),
        100.0 * (est[2] - t.eta) / t.eta,
        100.0 * (est[3] - t.delta) / t.delta,
        100.0 * (est[4] - t.xi) / t.xi,
    ]
}

fn param_estimates(est: &[f64; 5]) -> Vec<f64> {
    vec![
        est[0].to_degrees(),
        est[1].to_degrees(),
        est[2],
        est[3],
        est[4],
    ]
}

/// (k, c) of eqs. (30)-(31) from A0, V0.
pub fn kc_from_av(xi_q: f64, a0: f64, v0: f64) -> (f64, f64) {
    let k = (1.0 + a0 * a0) * v0 * v0 / (2.0 * v0 - xi_q);
    let sw = -a0.signum() * v0.signum();
    let c = (sw * ((2.0 * k - xi_q) * v0 - xi_q * k) / (xi_q * a0 * v0)).atan();
    (k, c)
}

fn true_cal(t: &Truth) -> crate::Calibration {
    crate::Calibration {
        phi: t.phi,
        psi: t.psi,
        eta: t.eta,
        delta: t.delta,
        xi: t.xi,
        cov: None,
    }
}

/// One method's outcome on one run: (errors, estimates) per column, or why
/// it failed. The failure stays text on purpose: it is data (reported,
/// counted, never raised) and round-trips through `--shard` record files,
/// from which no typed [`CalibError`] could be rebuilt.
pub type RunOutcome = Result<(Vec<f64>, Vec<f64>), String>;
type Outcome = (Vec<f64>, Vec<f64>);

/// One run of a cell: its index and one outcome per method of the cell.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRecord {
    pub run: usize,
    pub outcomes: Vec<RunOutcome>,
}

/// The simulator's seed of run `run`: `seed + run` (wrapping), the same
/// in every cell and table, so a run can be recomputed on its own.
fn run_seed(seed: u64, run: usize) -> u64 {
    seed.wrapping_add(run as u64)
}

/// The runs of shard `k` of `n` (1-based) out of `runs`: contiguous blocks
/// `[(k-1) runs / n, k runs / n)`, which cover `0..runs` exactly once.
/// `None` unless `1 <= k <= n`.
pub fn shard_runs(runs: usize, k: usize, n: usize) -> Option<Range<usize>> {
    if k == 0 || k > n {
        return None;
    }
    // u128: runs * k cannot overflow.
    let at = |i: usize| (runs as u128 * i as u128 / n as u128) as usize;
    Some(at(k - 1)..at(k))
}

/// Run one calibration of a simulated dataset; the per-column errors.
fn one(
    method: McMethod,
    data: &Dataset,
    truth: &Truth,
    predictor: &Predictor,
    modes: bool,
) -> RunOutcome {
    let m = match method {
        McMethod::Det => Method::Det,
        McMethod::Ls => Method::Ls,
        McMethod::Cekf | McMethod::Cekfd => Method::Cekf,
        McMethod::Ml => Method::Ml,
    };
    let mut o = CalibrateOptions::for_dataset(data, m);
    let cal_true = true_cal(truth);
    if method == McMethod::Cekf {
        // The paper's CEKF: every initial component 30% off (L by 0.3 rad).
        let states = truth
            .trajectories
            .iter()
            .map(|tt| {
                let q = tt.q.unwrap_or(0.0);
                let (a, v) = av_from_state(&cal_true, q, tt.mu0, tt.gamma0);
                let (_, xq, l) = cal_true.modes(q);
                [a * v * 1.3, v * 1.3, xq * 1.3, l + 0.3]
            })
            .collect();
        o.cekf_init = CekfInit::Given {
            states,
            relative_sd: 0.3,
        };
    }
    let r = calibrate(data, Some(predictor), &o).map_err(|e| e.to_string())?;
    let est = r.calibration.values();
    if !modes {
        return Ok((param_errors(&est, truth), param_estimates(&est)));
    }
    // Modes: mean over trajectories of |error| per column (c, k by DET and LS only).
    let mut acc = vec![0.0; 4];
    let n = r.trajectories.len() as f64;
    for (te, tt) in r.trajectories.iter().zip(&truth.trajectories) {
        let q = tt.q.unwrap_or(0.0);
        let (a0, v0) = av_from_state(&cal_true, q, tt.mu0, tt.gamma0);
        let (_, xq, l) = cal_true.modes(q);
        let (k, c) = kc_from_av(xq, a0, v0);
        acc[0] += (100.0 * (te.closed.xi_q - xq) / xq).abs() / n;
        acc[1] += wrap(te.closed.l - l).to_degrees().abs() / n;
        if matches!(method, McMethod::Det | McMethod::Ls) {
            // c is defined modulo pi.
            let dc = wrap(2.0 * (te.closed.c() - c)) / 2.0;
            acc[2] += dc.to_degrees().abs() / n;
            acc[3] += (100.0 * (te.closed.k() - k) / k).abs() / n;
        } else {
            acc[2] = f64::NAN;
            acc[3] = f64::NAN;
        }
    }
    Ok((acc.clone(), acc))
}

impl SimOptions {
    /// The CRLB standard deviations (table units) of the parameters for this
    /// set-up: the inverse Fisher information of the bearings at the truth, on
    /// the noise-free data of the set-up (circles: iota = 0); bearing noise
    /// only, or with the encoder noise too.
    pub fn crlb_sd(
        &self,
        predictor: &Predictor,
        with_encoder_noise: bool,
    ) -> Result<Vec<f64>, CalibError> {
        let sim = self;
        let clean = SimOptions {
            sigma_beta: 0.0,
            k_encoder: 0.0,
            iota: 0.0,
            ..sim.clone()
        };
        let (data, truth) = simulate(&clean)?;
        let fts = FitTrajectory::all(predictor, &data);
        let states: Vec<Vec<f64>> = truth
            .trajectories
            .iter()
            .map(|t| vec![t.mu0, t.gamma0])
            .collect();
        // Encoder noise of [10] as the simulator draws it: white noise on each
        // wheel's rotation with density K^2 / r_nominal per radian turned. The
        // bound is then the linearised one of the errors-in-variables model
        // (residual covariance I + A M A^T, see `Integration::input_noise`).
        let c = sim.k_encoder * sim.k_encoder / sim.r_nominal;
        let opts = FitOptions {
            max_iterations: 0,
            cost_tolerance: 0.0,
            step_tolerance: 0.0,
            sigma: vec![sim.sigma_beta],
            max_step: 0.5,
            input_noise: (with_encoder_noise && c > 0.0).then(|| vec![c, c]),
        };
        let params = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
        let cov = crlb(predictor, &fts, &params, &states, &opts).map_err(CalibError::Crlb)?;
        let sd: Vec<f64> = (0..5).map(|i| cov[i][i].max(0.0).sqrt()).collect();
        Ok(vec![
            sd[0].to_degrees(),
            sd[1].to_degrees(),
            100.0 * sd[2] / truth.eta,
            100.0 * sd[3] / truth.delta,
            100.0 * sd[4] / truth.xi,
        ])
    }
}

/// The runs `runs` of a cell (run `r` simulated with seed `seed + r`, wrapping), each calibrated by
/// every method of the cell, in parallel; the records in run order. `tick`
/// is called after each run. The caller's cancel flag
/// ([`obsan_expr::with_cancel`]) reaches the worker threads: once it is
/// set, the runs not started are skipped, the running ones stop at their
/// estimator's next poll, and the answer is `Cancelled`.
pub fn run_runs(
    cell: &Cell,
    modes: bool,
    runs: Range<usize>,
    seed: u64,
    predictor: &Predictor,
    tick: &(dyn Fn() + Sync),
) -> Result<Vec<RunRecord>, MontecarloError> {
    let flag = obsan_expr::cancel_flag();
    let records: Option<Vec<RunRecord>> = runs
        .into_par_iter()
        .map(|r| {
            obsan_expr::with_cancel(flag.clone(), || {
                run_one(cell, modes, r, seed, predictor, tick)
            })
        })
        .collect();
    match records {
        Some(records) if !obsan_expr::cancel_requested() => Ok(records),
        _ => Err(MontecarloError::Cancelled),
    }
}

/// Run `r` of [`run_runs`], on a worker thread; `None` once cancelled.
fn run_one(
    cell: &Cell,
    modes: bool,
    r: usize,
    seed: u64,
    predictor: &Predictor,
    tick: &(dyn Fn() + Sync),
) -> Option<RunRecord> {
    if obsan_expr::cancel_requested() {
        return None;
    }
    let sim = SimOptions {
        seed: run_seed(seed, r),
        ..cell.sim.clone()
    };
    let outcomes = match simulate(&sim) {
        Ok((data, truth)) => cell
            .methods
            .iter()
            .map(|&m| one(m, &data, &truth, predictor, modes))
            .collect(),
        Err(e) => cell.methods.iter().map(|_| Err(e.to_string())).collect(),
    };
    if obsan_expr::cancel_requested() {
        // Its outcomes may be "interrupted" failures, not answers.
        return None;
    }
    tick();
    Some(RunRecord { run: r, outcomes })
}

impl Cell {
    /// The Cramér–Rao bounds this cell reports (see [`CellResult`]): they
    /// depend on the set-up only (noise-free data), not on any run. A bound
    /// that cannot be computed is left out of the table.
    pub fn bounds(&self, modes: bool, predictor: &Predictor) -> CellBounds {
        CellBounds {
            crlb_sd: if modes {
                None
            } else {
                self.sim.crlb_sd(predictor, false).ok()
            },
            crlb_sd_encoders: if modes || self.sim.k_encoder <= 0.0 {
                None
            } else {
                self.sim.crlb_sd(predictor, true).ok()
            },
        }
    }
}

/// [`CellResult::crlb_sd`] and [`CellResult::crlb_sd_encoders`].
#[derive(Clone, Debug, PartialEq)]
pub struct CellBounds {
    pub crlb_sd: Option<Vec<f64>>,
    pub crlb_sd_encoders: Option<Vec<f64>>,
}

/// Shards' records, in shard order, as the records of runs `0..runs`; an
/// error names the first run missing, repeated or out of place.
pub fn merge_runs(
    parts: Vec<Vec<RunRecord>>,
    runs: usize,
) -> Result<Vec<RunRecord>, MontecarloError> {
    let all: Vec<RunRecord> = parts.into_iter().flatten().collect();
    if let Some((i, r)) = all.iter().enumerate().find(|(i, r)| r.run != *i) {
        return Err(MontecarloError::Records(format!(
            "run {i} expected, run {} found in its place",
            r.run
        )));
    }
    if all.len() != runs {
        return Err(MontecarloError::Records(format!(
            "{} runs given, {runs} expected",
            all.len()
        )));
    }
    Ok(all)
}

/// A cell's statistics from its run records (all of them or a shard's),
/// reduced in record order: given the records of runs `0..n` in order,
/// the result is bit for bit that of [`run_cell`] with `n` runs.
pub fn summarize(
    cell: &Cell,
    modes: bool,
    records: &[RunRecord],
    bounds: CellBounds,
) -> Result<CellResult, MontecarloError> {
    let ncols = if modes { 4 } else { 5 };
    for r in records {
        if r.outcomes.len() != cell.methods.len() {
            return Err(MontecarloError::Records(format!(
                "run {}: {} method outcomes, the cell has {} methods",
                r.run,
                r.outcomes.len(),
                cell.methods.len()
            )));
        }
        if let Some((e, v)) = r
            .outcomes
            .iter()
            .flatten()
            .find(|(e, v)| e.len() != ncols || v.len() != ncols)
        {
            return Err(MontecarloError::Records(format!(
                "run {}: {} errors and {} estimates, the table has {ncols} columns",
                r.run,
                e.len(),
                v.len()
            )));
        }
    }
    let runs = records.len();
    let methods = cell
        .methods
        .iter()
        .enumerate()
        .map(|(mi, &m)| {
            let ok: Vec<&Outcome> = records
                .iter()
                .filter_map(|r| r.outcomes[mi].as_ref().ok())
                .collect();
            let first_failure = records
                .iter()
                .find_map(|r| r.outcomes[mi].as_ref().err().cloned());
            let n = ok.len().max(1) as f64;
            let col = |f: &dyn Fn(&Outcome, usize) -> f64| -> Vec<f64> {
                (0..ncols)
                    .map(|c| ok.iter().map(|e| f(e, c)).sum::<f64>() / n)
                    .collect()
            };
            MethodStats {
                method: m,
                mean_abs: col(&|e, c| e.0[c].abs()),
                rms: col(&|e, c| e.0[c] * e.0[c])
                    .iter()
                    .map(|v| v.sqrt())
                    .collect(),
                mean_estimate: col(&|e, c| e.1[c]),
                failures: runs - ok.len(),
                first_failure,
            }
        })
        .collect();
    Ok(CellResult {
        label: cell.label.clone(),
        runs,
        methods,
        crlb_sd: bounds.crlb_sd,
        crlb_sd_encoders: bounds.crlb_sd_encoders,
    })
}

/// Run a cell: `runs` simulations (seeds `seed + run`), each calibrated by
/// every method of the cell. `tick` is called after each run.
pub fn run_cell(
    cell: &Cell,
    modes: bool,
    runs: usize,
    seed: u64,
    predictor: &Predictor,
    tick: &(dyn Fn() + Sync),
) -> Result<CellResult, MontecarloError> {
    let records = run_runs(cell, modes, 0..runs, seed, predictor, tick)?;
    summarize(cell, modes, &records, cell.bounds(modes, predictor))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calib_predictor;

    #[test]
    fn shards_cover_every_run_once_in_order() {
        for runs in [0, 1, 2, 7, 100, 101] {
            for n in 1..=9 {
                let all: Vec<usize> = (1..=n)
                    .flat_map(|k| shard_runs(runs, k, n).unwrap())
                    .collect();
                assert_eq!(
                    all,
                    (0..runs).collect::<Vec<_>>(),
                    "{runs} runs, {n} shards"
                );
            }
        }
        assert_eq!(shard_runs(10, 0, 3), None);
        assert_eq!(shard_runs(10, 4, 3), None);
        assert_eq!(
            shard_runs(usize::MAX, 2, 2).map(|r| r.end),
            Some(usize::MAX)
        );
    }

    fn bits(r: &CellResult) -> Vec<u64> {
        let mut v = Vec::new();
        for m in &r.methods {
            for x in m.mean_abs.iter().chain(&m.rms).chain(&m.mean_estimate) {
                v.push(x.to_bits());
            }
            v.push(m.failures as u64);
        }
        v.push(r.runs as u64);
        v
    }

    #[test]
    fn merged_shards_reduce_to_the_one_run_table_bit_for_bit() {
        let p = calib_predictor();
        let t = table(6).unwrap(); // modes: NaN columns for CEKF, five methods
        let cell = &t.cells[3];
        let one = run_cell(cell, t.modes, 5, 7, &p, &|| {}).unwrap();
        let parts: Vec<Vec<RunRecord>> = (1..=3)
            .map(|k| run_runs(cell, t.modes, shard_runs(5, k, 3).unwrap(), 7, &p, &|| {}).unwrap())
            .collect();
        let merged = merge_runs(parts.clone(), 5).unwrap();
        let m = summarize(cell, t.modes, &merged, cell.bounds(t.modes, &p)).unwrap();
        assert_eq!(bits(&m), bits(&one));
        assert!(one.methods.iter().any(|m| m.mean_abs[0] != 0.0));
        // A missing shard, or shards out of order, is an error naming the run.
        let e = merge_runs(vec![parts[0].clone(), parts[2].clone()], 5).unwrap_err(); // runs 0, 3, 4
        assert!(e.to_string().contains("run 1 expected, run 3 found"), "{e}");
        let e = merge_runs(vec![parts[0].clone(), parts[1].clone()], 5).unwrap_err();
        assert!(e.to_string().contains("3 runs given, 5 expected"), "{e}");
        // Records of another table's cell (other column count) are refused.
        let v = table(5).unwrap();
        let e = summarize(&v.cells[0], v.modes, &merged, cell.bounds(true, &p)).unwrap_err();
        assert!(matches!(e, MontecarloError::Records(_)), "{e}");
    }
}
