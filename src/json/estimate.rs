//! `obsan calibrate`, `obsan crlb` and `obsan montecarlo` (and `montecarlo merge`).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A float that may be undefined (a failed start, no run): null then, as JSON has no NaN.
pub fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

/// `obsan calibrate DATASET --json`: the calibration and its standard deviations.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Calibrate {
    /// Which wheel-encoder noise ml's sds include; null for the methods other than ml.
    pub encoder_noise: Option<EncoderNoise>,
    /// Always false: estimates from noisy data.
    pub exact: bool,
    /// The estimator: det, ls, cekf or ml.
    pub method: String,
    /// With --d0: rho, r_right, r_left, B (m) as {value, sd}; else null.
    pub metric: Option<BTreeMap<String, Estimate>>,
    /// The joint maximum-likelihood fit (ml only; else null).
    pub ml: Option<MlFit>,
    /// phi, psi (rad), eta, delta, xi (eq. 16) as {value, sd}.
    pub params: BTreeMap<String, Estimate>,
    /// The bearing noise standard deviation used (rad).
    pub sigma_beta: f64,
    /// True when sigma_beta was estimated from the residuals (not --sigma-beta-deg nor dataset.json).
    pub sigma_beta_estimated: bool,
    /// Per trajectory: its circle's modes and start.
    pub trajectories: Vec<Trajectory>,
}

/// A value and its standard deviation.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Estimate {
    /// The standard deviation; null when the information matrix is singular.
    pub sd: Option<f64>,
    /// The estimate.
    pub value: f64,
}

/// The wheel-encoder noise the ml standard deviations include.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(tag = "route", rename_all = "snake_case", deny_unknown_fields)]
pub enum EncoderNoise {
    /// Stated in dataset.json.
    Stated {
        /// The intensity c = K^2 / r.
        c: f64,
        /// The encoder noise K (m^1/2).
        k: f64,
    },
    /// Estimated from the wheel speeds, as dataset.json states none.
    Estimated {
        /// The intensity c = K^2 / r.
        c: f64,
        /// The encoder noise K (m^1/2).
        k: f64,
        /// The number of wheel-speed differences it was read from.
        samples: usize,
    },
    /// Neither stated nor read: the sds are the bearings' alone.
    BearingsOnly,
}

/// The maximum-likelihood fit's summary.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct MlFit {
    /// The final cost (negative log-likelihood up to a constant).
    pub cost: f64,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// The number of residuals fitted.
    pub residuals: usize,
}

/// One circular trajectory's closed-form modes (eq. 17) and start.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Trajectory {
    /// The mode L (rad).
    #[serde(rename = "L")]
    pub l: f64,
    /// The mode c.
    pub c: f64,
    /// The start gamma0 (rad); null when not estimated.
    pub gamma0: Option<f64>,
    /// The mode k.
    pub k: f64,
    /// The start mu0; null when not estimated.
    pub mu0: Option<f64>,
    /// The trajectory's folder name.
    pub name: String,
    /// DET's own period reading failed and the other circles' prediction replaced it.
    pub period_from_others: bool,
    /// The wheel-speed ratio of the circle.
    pub q: f64,
    /// RMS of the bearing residuals (rad).
    pub residual_rms: f64,
    /// Standard deviations of xi_q and L, when known; else null.
    pub sd: Option<ModesSd>,
    /// The mode xi_q.
    pub xi_q: f64,
}

/// Standard deviations of a trajectory's modes.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct ModesSd {
    /// sd of L (rad).
    #[serde(rename = "L")]
    pub l: f64,
    /// sd of xi_q.
    pub xi_q: f64,
}

/// `obsan crlb --json`: the Cramér–Rao lower bound of the calibration.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct Crlb {
    /// Per trajectory, "NAME COUNT": its number of bearings.
    pub bearings: Vec<String>,
    /// The bound with bearing noise alone, per column ("phi (deg)", "psi (deg)", "eta (%)",
    /// "delta (%)", "xi (%)"): an estimator that knows the circle exactly (ls with the commanded q).
    pub crlb_sd: BTreeMap<String, f64>,
    /// The bound with the encoder noise too (estimators driven by the measured wheel speeds, as
    /// ml), per column; null without encoder noise.
    pub crlb_sd_with_encoder_noise: Option<BTreeMap<String, f64>>,
    /// The set-up: simulated (its flags) or a dataset at its ML estimate.
    pub setup: String,
}

/// One table of `obsan montecarlo --json` (the output is a list of them).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct McTable {
    /// The cells run (all, or --cell).
    pub cells: Vec<McCell>,
    /// The column names of every value list, e.g. "phi (deg)" or "xi_q (%)".
    pub columns: Vec<String>,
    /// Runs per cell.
    pub runs: usize,
    /// Run r uses seed + r.
    pub seed: u64,
    /// The paper's table number (4 to 7).
    pub table: u8,
    /// The paper's table title.
    pub title: String,
}

/// One cell (a row of set-ups) of a Monte Carlo table.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct McCell {
    /// The cell number, 1-based as --cell.
    pub cell: usize,
    /// The CRLB sd per column with bearing noise alone (DET, LS, CEKF); null if not computed.
    pub crlb_sd: Option<Vec<Option<f64>>>,
    /// The CRLB sd per column with the encoder noise too (ML); null without encoder noise.
    pub crlb_sd_with_encoder_noise: Option<Vec<Option<f64>>>,
    /// The set-up, e.g. "iota = 0.04, sigma_beta = 1 deg".
    pub label: String,
    /// Per method: the statistics of its runs.
    pub methods: Vec<McMethod>,
    /// The paper's figures for this cell, per method.
    pub paper: Vec<McPaper>,
}

/// One method's statistics over a cell's runs (per column; null where undefined).
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct McMethod {
    /// Runs where the method failed.
    pub failures: usize,
    /// The first failure's message, or null.
    pub first_failure: Option<String>,
    /// Mean absolute error per column.
    pub mean_abs_error: Vec<Option<f64>>,
    /// Mean estimate per column.
    pub mean_estimate: Vec<Option<f64>>,
    /// The method: DET, LS, CEKF, CEKFd or ML.
    pub method: String,
    /// Root-mean-square error per column.
    pub rms_error: Vec<Option<f64>>,
}

/// The paper's figures of one method in a cell.
#[derive(Serialize, Deserialize, JsonSchema, Debug)]
#[serde(deny_unknown_fields)]
pub struct McPaper {
    /// The method.
    pub method: String,
    /// Per column, as the paper prints it; null where it prints none.
    pub values: Vec<Option<f64>>,
}
