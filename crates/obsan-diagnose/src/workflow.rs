//! The discrepancy workflow (issue 5): fit the nominal model, test the
//! residuals, try every candidate effect that the data can reveal, name the
//! significant ones greedily.

use crate::identify::{input_class, stacked_rank, Identifiability, InputClass};
use crate::residual::{analyse, ResidualReport, ResidualSeries};
use crate::start::extended_start;
use crate::stats::{chi2_1_p, normal_critical};
use obsan_data::{add_derived_inputs, wrap, Dataset};
use obsan_fit::{
    estimate_noise, fit, minimise, FitOptions, FitTrajectory, Integration, LmOptions, NoiseOptions,
    Predictor,
};
use obsan_model::{Effect, EffectLibrary, Kind, System};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;

/// Outputs per trajectory used by the rank test (the most measured ones).
pub const MAX_RANK_OUTPUTS: usize = 4;

/// Options; every threshold explicit.
#[derive(Clone, Debug)]
pub struct DiagnoseOptions {
    /// Probability of naming an effect on data without one, per round
    /// (split over the candidates, Bonferroni).
    pub alpha: f64,
    /// At most this many effects are named (default: no limit; the rounds
    /// go on while a candidate stays significant).
    pub max_rounds: usize,
    pub max_iterations: usize,
    pub cost_tolerance: f64,
    /// Stop a fit when its step is shorter than this many standard deviations.
    pub step_tolerance: f64,
    /// Longest integration step (s), see `obsan_fit::Integration`.
    pub max_step: f64,
    /// Trajectories stacked in the rank test (the first ones).
    pub rank_trajectories: usize,
    /// Output noise levels; `None` takes `dataset.json`'s, else estimates.
    pub sigma: Option<Vec<f64>>,
    /// Where the measured inputs' noise comes from (it weighs the residuals
    /// by generalised least squares, see [`input_noise`]).
    pub input_noise: InputNoise,
}

/// The source of the measured inputs' noise levels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputNoise {
    /// `dataset.json`'s, none if it states none.
    Stated,
    /// Estimated by restricted maximum likelihood (with the output levels
    /// unless they are given), at the nominal fit and again after every
    /// named effect ([`obsan_fit::estimate_noise`]). Linearised about
    /// the fitted path: for drift that stays small against the geometry
    /// (docs/diagnose.md says where it does not).
    Estimate,
    /// None: ordinary least squares.
    None,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            alpha: 0.01,
            max_rounds: usize::MAX,
            max_iterations: 60,
            cost_tolerance: 1e-6,
            step_tolerance: 1e-2,
            max_step: 0.5,
            rank_trajectories: 4,
            sigma: None,
            input_noise: InputNoise::Stated,
        }
    }
}

/// A fitted model and its residuals.
#[derive(Clone, Debug, Serialize)]
pub struct ModelFit {
    pub model: String,
    pub params: Vec<(String, f64, f64)>,
    /// Per param: the cluster-robust sd, trajectories as clusters (right
    /// whatever the correlation within a trajectory; NaN with one).
    pub params_robust_sd: Vec<f64>,
    /// Per trajectory: initial dynamic state.
    pub initial_states: Vec<Vec<f64>>,
    /// Sum of squared normalised residuals, their number, unknowns fitted.
    pub cost: f64,
    /// With input noise: the log-determinant of the residuals' covariance
    /// (normalised by the output levels), which depends on the params; the
    /// likelihood ratio between two fits needs it (0 without input noise).
    pub log_det: f64,
    pub n: usize,
    pub n_fitted: usize,
    pub iterations: usize,
    /// Per output: residual RMS (in the output's units).
    pub rms: Vec<(String, f64)>,
    pub residuals: ResidualReport,
    #[serde(skip)]
    pub series: Vec<ResidualSeries>,
    #[serde(skip)]
    pub covariance: Vec<Vec<f64>>,
}

impl ModelFit {
    pub fn param(&self, name: &str) -> Option<(f64, f64)> {
        self.params.iter().find(|p| p.0 == name).map(|p| (p.1, p.2))
    }
    /// A param's cluster-robust sd.
    pub fn robust_sd(&self, name: &str) -> Option<f64> {
        let i = self.params.iter().position(|p| p.0 == name)?;
        self.params_robust_sd.get(i).copied()
    }
    /// `-2 log L` up to terms that do not depend on the fit (the output
    /// levels are shared by the fits compared).
    pub fn m2ll(&self) -> f64 {
        self.cost + self.log_det
    }
    fn reduced_chi2(&self) -> f64 {
        self.cost / (self.n as f64 - self.n_fitted as f64).max(1.0)
    }
    /// Variance inflation of the quasi-likelihood: excess residual level
    /// times serial correlation, at least 1.
    pub fn inflation(&self) -> f64 {
        self.reduced_chi2().max(1.0) * self.residuals.correlation_factor
    }
}

/// What happened to one candidate in one round.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateResult {
    pub effect: String,
    pub description: String,
    /// The effect's new params.
    pub params: Vec<String>,
    /// Identifiable on these data (the rank test).
    pub identifiable: bool,
    pub rank: Option<(usize, usize)>,
    /// When not identifiable: what absorbs it (a null vector at the fit).
    pub symmetry: Vec<(String, f64)>,
    /// Fitted new params with standard deviations.
    pub estimates: Vec<(String, f64, f64)>,
    /// Their cluster-robust sds (trajectories as clusters).
    pub robust_sd: Vec<f64>,
    /// Likelihood-ratio statistic (quasi-likelihood: divided by the larger
    /// model's reduced chi-square when above 1), its p-value, BIC change
    /// (negative is better), residual RMS per output, whiteness z.
    pub lr: f64,
    pub p_value: f64,
    pub delta_bic: f64,
    pub rms: Vec<(String, f64)>,
    pub whiteness_z: f64,
    pub significant: bool,
    pub error: Option<String>,
}

/// One named effect.
#[derive(Clone, Debug, Serialize)]
pub struct Named {
    pub effect: String,
    pub description: String,
    pub estimates: Vec<(String, f64, f64)>,
    /// Cluster-robust sds of the estimates (trajectories as clusters).
    pub robust_sd: Vec<f64>,
    pub rms_before: Vec<(String, f64)>,
    pub rms_after: Vec<(String, f64)>,
    pub lr: f64,
    pub p_value: f64,
    /// Other significant candidates of the same round that fit almost as
    /// well (BIC within [`RIVAL_BIC`]): the data hardly tell them apart.
    pub rivals: Vec<Rival>,
}

/// A candidate that explains the data about as well as a named effect.
#[derive(Clone, Debug, Serialize)]
pub struct Rival {
    pub effect: String,
    /// Its BIC change minus the named effect's (>= 0).
    pub delta_bic: f64,
    /// Whether it stays identifiable once the named effect is in the model
    /// (the next round's rank test); `false`: on these data the two are
    /// confounded, so naming one rather than the other is arbitrary.
    pub jointly_identifiable: Option<bool>,
}

/// Candidates whose BIC is within this of the best one's are reported as
/// rivals ("strong evidence" starts at 6 on Kass and Raftery's scale).
pub const RIVAL_BIC: f64 = 6.0;

/// An effect on the measured inputs (`compare` relations).
#[derive(Clone, Debug, Serialize)]
pub struct InputCheck {
    pub effect: String,
    pub description: String,
    pub estimates: Vec<(String, f64, f64)>,
    pub z: f64,
    pub significant: bool,
    pub note: String,
}

/// The whole outcome.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    pub model: String,
    pub sigma: Vec<(String, f64)>,
    pub sigma_estimated: bool,
    /// Per measured input, the noise intensity `c` (spectral density
    /// `c |u|`) used in the final fit; empty: none.
    pub input_noise: Vec<(String, f64)>,
    /// "stated", "estimated" or "none".
    pub input_noise_source: String,
    /// When estimated: per estimate (at the nominal fit, then after each
    /// named effect), the likelihood-ratio statistic of the input noise
    /// against white output noise alone.
    pub input_noise_lr: Vec<f64>,
    pub input_class: String,
    pub nominal: ModelFit,
    pub rounds: Vec<Vec<CandidateResult>>,
    pub named: Vec<Named>,
    pub input_checks: Vec<InputCheck>,
    pub final_fit: ModelFit,
    /// Effects these data cannot reveal, with what absorbs them.
    pub hidden: Vec<CandidateResult>,
    /// The extended model (nominal plus the named effects) as .sys text.
    pub extended_sys: String,
    /// Per-round critical value of the LR statistic.
    pub lr_critical: f64,
}

/// The inputs whose class the rank test reads: the model's, then with a
/// delay each one's rate (`rate__<u>`, see `identify::stacked_rank`).
fn class_inputs(sys: &System) -> (Vec<String>, Vec<Option<String>>) {
    let mut ins: Vec<String> = sys.decls_of(Kind::Input).map(|d| d.name.clone()).collect();
    let mut der: Vec<Option<String>> = sys
        .decls_of(Kind::Input)
        .map(|d| d.derived.clone())
        .collect();
    if sys.delay.is_some() {
        let n = ins.len();
        for i in 0..n {
            der.push(Some(format!("rate({})", ins[i])));
            ins.push(format!("rate__{}", ins[i]));
        }
    }
    (ins, der)
}

/// The dataset with the model's derived inputs and the workflow's
/// constants (`later`: 0 on the first trajectory, 1 after; `index`).
pub fn prepare(sys: &System, data: &Dataset) -> Result<Dataset, String> {
    let mut d = data.clone();
    let mut derived: Vec<(String, String)> = sys
        .decls_of(Kind::Input)
        .filter_map(|x| x.derived.clone().map(|t| (x.name.clone(), t)))
        .collect();
    if sys.delay.is_some() {
        for d in sys.decls_of(Kind::Input) {
            derived.push((format!("rate__{}", d.name), format!("rate({})", d.name)));
        }
    }
    for (k, t) in d.trajectories.iter_mut().enumerate() {
        t.meta
            .entry("later".into())
            .or_insert(if k == 0 { 0.0 } else { 1.0 });
        t.meta.entry("index".into()).or_insert(k as f64);
        add_derived_inputs(&mut t.inputs, &derived, &t.meta)
            .map_err(|e| format!("trajectory {}: {e}", t.name))?;
    }
    Ok(d)
}

/// The measured inputs' noise (see `obsan_fit::Integration::input_noise`)
/// from `dataset.json`, per measured input of `sys` by name: `noise.<input>`
/// gives `c` for that input; otherwise `noise.encoder_k` = K with
/// `nominal.r_right` = r gives `c = K^2 / r` for every measured input (wheel
/// encoders, the error model of [10]). Empty when the dataset states none.
pub fn input_noise(sys: &System, data: &Dataset) -> Vec<(String, f64)> {
    let m = &data.meta;
    let enc = match (m.noise.get("encoder_k"), m.nominal.get("r_right")) {
        (Some(k), Some(r)) if *k > 0.0 && *r > 0.0 => Some(k * k / r),
        _ => None,
    };
    let c: Vec<(String, f64)> = sys
        .decls_of(Kind::Input)
        .filter(|d| d.derived.is_none())
        .map(|d| {
            let c = m.noise.get(&d.name).copied().or(enc).unwrap_or(0.0);
            (d.name.clone(), c)
        })
        .collect();
    if c.iter().any(|x| x.1 > 0.0) {
        c
    } else {
        vec![]
    }
}

/// The per-input vector of `sys`'s predictor for named intensities (derived
/// inputs carry none); `None` when there is no noise.
fn noise_vector(sys: &System, noise: &[(String, f64)]) -> Option<Vec<f64>> {
    let c: Vec<f64> = sys
        .decls_of(Kind::Input)
        .map(|d| match &d.derived {
            Some(_) => 0.0,
            None => noise.iter().find(|n| n.0 == d.name).map_or(0.0, |n| n.1),
        })
        .collect();
    c.iter().any(|x| *x > 0.0).then_some(c)
}

/// Output levels, named input intensities, and the likelihood-ratio
/// statistic of the input noise.
type Levels = (Vec<f64>, Vec<(String, f64)>, f64);

/// Restricted-ML noise levels at `f` (a fit of `sys`): the output levels
/// (held when `outputs` is false) and each measured input's intensity, with
/// the likelihood-ratio statistic against white output noise.
fn estimate_levels(
    sys: &System,
    data: &Dataset,
    f: &ModelFit,
    sigma: &[f64],
    outputs: bool,
    o: &DiagnoseOptions,
) -> Result<Levels, String> {
    let nf = sys.normal_form(None, &[]).map_err(|e| e.to_string())?;
    let p = Predictor::new(&nf);
    let trajs = FitTrajectory::all(&p, data);
    let mask: Vec<bool> = sys
        .decls_of(Kind::Input)
        .map(|d| d.derived.is_none())
        .collect();
    let names: Vec<String> = sys.decls_of(Kind::Input).map(|d| d.name.clone()).collect();
    let params: Vec<f64> = f.params.iter().map(|p| p.1).collect();
    let opts = NoiseOptions {
        max_step: o.max_step,
        outputs,
        ..NoiseOptions::default()
    };
    let e = estimate_noise(&p, &trajs, &params, &f.initial_states, sigma, &mask, &opts)?;
    let named = names
        .into_iter()
        .zip(e.input_noise)
        .zip(mask)
        .filter(|(_, m)| *m)
        .map(|(x, _)| x)
        .collect();
    Ok((e.sigma, named, e.m2ll_white - e.m2ll))
}

/// Normalised residuals beyond this are gross outliers for the restart of
/// a candidate fit (see `candidate`): no Gaussian noise gives them.
const OUTLIER_Z: f64 = 5.0;

/// `data` without the measurements whose residual in `f` exceeds `z`
/// sigmas; `None` when there are none.
fn without_outliers(data: &Dataset, f: &ModelFit, z: f64) -> Option<Dataset> {
    let mut out = data.clone();
    let mut removed = 0usize;
    for s in &f.series {
        let Some(tr) = out.trajectories.iter_mut().find(|t| t.name == s.trajectory) else {
            continue;
        };
        let Some(c) = tr.outputs.columns.iter().position(|n| *n == s.output) else {
            continue;
        };
        for (t, e) in s.t.iter().zip(&s.e) {
            if e.abs() > z {
                if let Ok(j) = tr.outputs.t.binary_search_by(|x| x.total_cmp(t)) {
                    tr.outputs.values[c][j] = None;
                    removed += 1;
                }
            }
        }
    }
    (removed > 0).then_some(out)
}

/// Fit `sys` to prepared `data` from the given start, with output levels
/// `sigma` and input-noise intensities `noise` by input name (generalised
/// least squares, the covariance at the fit's own estimate; empty: none).
pub fn fit_model(
    sys: &System,
    data: &Dataset,
    params0: &[f64],
    states0: &[Vec<f64>],
    sigma: &[f64],
    noise: &[(String, f64)],
    o: &DiagnoseOptions,
) -> Result<ModelFit, String> {
    let nf = sys.normal_form(None, &[]).map_err(|e| e.to_string())?;
    let p = Predictor::new(&nf);
    let trajs = FitTrajectory::all(&p, data);
    let fo = FitOptions {
        max_iterations: o.max_iterations,
        cost_tolerance: o.cost_tolerance,
        step_tolerance: o.step_tolerance,
        sigma: sigma.to_vec(),
        max_step: o.max_step,
        input_noise: noise_vector(sys, noise),
    };
    let weighted = fo.input_noise.is_some();
    let r = fit(&p, &trajs, params0, states0, &fo)?;
    // The noise is mapped back to each trajectory's start through the
    // inverse transition matrix, which a fast decaying state (a lag of time
    // constant T over a trajectory of many T) makes overflow: then the
    // residuals cannot be weighed and no likelihood can be compared.
    if weighted {
        if let Some(k) = r.whitening.iter().position(Option::is_none) {
            return Err(format!(
                "the input-noise covariance cannot be formed on trajectory {}: a state decays \
                 too fast over it for the linearised noise model (use --input-noise none)",
                data.trajectories[k].name
            ));
        }
    }
    let names: Vec<String> = sys.decls_of(Kind::Param).map(|d| d.name.clone()).collect();
    let measured: Vec<String> = sys
        .decls_of(Kind::Input)
        .filter(|d| d.derived.is_none())
        .map(|d| d.name.clone())
        .collect();
    let mut series = Vec::new();
    for (k, (tr, ft)) in data.trajectories.iter().zip(&trajs).enumerate() {
        // The fit's residual rows: (time index, output) of the measured cells.
        let cols: Vec<Option<&[Option<f64>]>> =
            p.outputs.iter().map(|o| tr.outputs.column(o)).collect();
        let mut row_of = Vec::new();
        for j in 0..tr.outputs.len() {
            for (oi, c) in cols.iter().enumerate() {
                if c.is_some_and(|c| c[j].is_some()) {
                    row_of.push((j, oi));
                }
            }
        }
        let whitener = r.whitening.get(k).cloned().flatten();
        let mut x0 = r.initial_states[k].clone();
        x0.extend_from_slice(&r.params);
        let integ = Integration {
            max_step: o.max_step,
            sensitivities: false,
            input_noise: None,
        };
        let pred = p.predict_with(&x0, &ft.consts, &tr.inputs, &tr.outputs.t, &integ)?;
        // Held input values and their integrals at every output time, once
        // per trajectory (shared by its outputs).
        let in_cols: Vec<Option<&[Option<f64>]>> =
            measured.iter().map(|n| tr.inputs.column(n)).collect();
        let held = |c: &Option<&[Option<f64>]>, row: usize| c.and_then(|c| c[row]).unwrap_or(0.0);
        let mut held_at = Vec::with_capacity(tr.outputs.len());
        {
            let mut row = 0usize;
            let mut integral = vec![0.0; measured.len()];
            let mut t_int = tr.inputs.t.first().copied().unwrap_or(0.0);
            for &t in &tr.outputs.t {
                while row + 1 < tr.inputs.len() && tr.inputs.t[row + 1] <= t {
                    for (m, c) in in_cols.iter().enumerate() {
                        integral[m] += held(c, row) * (tr.inputs.t[row + 1] - t_int);
                    }
                    t_int = tr.inputs.t[row + 1];
                    row += 1;
                }
                let at: Vec<(f64, f64)> = in_cols
                    .iter()
                    .enumerate()
                    .map(|(m, c)| {
                        let u = held(c, row);
                        (u, integral[m] + u * (t - t_int))
                    })
                    .collect();
                held_at.push(at);
            }
        }
        for (oi, oname) in p.outputs.iter().enumerate() {
            let Some(col) = tr.outputs.column(oname) else {
                continue;
            };
            let mut s = ResidualSeries {
                trajectory: tr.name.clone(),
                output: oname.clone(),
                t: vec![],
                e: vec![],
                predicted: vec![],
                angular: p.angular[oi],
                inputs: measured.iter().map(|n| (n.clone(), vec![])).collect(),
                input_integrals: measured.iter().map(|n| (n.clone(), vec![])).collect(),
                whiten: None,
            };
            if let Some(w) = &whitener {
                let idx: Vec<usize> = row_of
                    .iter()
                    .enumerate()
                    .filter(|(_, x)| x.1 == oi)
                    .map(|(i, _)| i)
                    .collect();
                s.whiten = w.subset(&idx).map(std::sync::Arc::new);
            }
            for (j, &t) in tr.outputs.t.iter().enumerate() {
                let Some(m) = col[j] else { continue };
                let y = pred.outputs[j][oi];
                let d = if s.angular { wrap(m - y) } else { m - y };
                s.t.push(t);
                s.e.push(d / sigma[oi]);
                s.predicted.push(y);
                for (mi, &(u, integral)) in held_at[j].iter().enumerate() {
                    s.inputs[mi].1.push(u);
                    s.input_integrals[mi].1.push(integral);
                }
            }
            if !s.e.is_empty() {
                series.push(s);
            }
        }
    }
    let n_fitted = r.params.len() + r.initial_states.iter().map(Vec::len).sum::<usize>();
    let residuals = analyse(&series, n_fitted);
    Ok(ModelFit {
        model: sys.name.clone(),
        params: names
            .iter()
            .zip(r.params.iter().zip(&r.params_sd))
            .map(|(n, (v, s))| (n.clone(), *v, *s))
            .collect(),
        params_robust_sd: r.params_sd_robust.clone(),
        initial_states: r.initial_states.clone(),
        cost: r.cost,
        log_det: r.whitening.iter().flatten().map(|w| w.log_det()).sum(),
        n: r.n_residuals,
        n_fitted,
        iterations: r.iterations,
        rms: p
            .outputs
            .iter()
            .cloned()
            .zip(r.residual_rms.iter().copied())
            .collect(),
        residuals,
        series,
        covariance: r.covariance,
    })
}

/// Start values for `sys` on `data`: a function of the model (see
/// [`crate::start_values`]).
pub type Start = (Vec<f64>, Vec<Vec<f64>>);

/// Run the workflow. `progress` is told what is being done.
pub fn diagnose(
    sys: &System,
    lib: Option<&EffectLibrary>,
    data: &Dataset,
    start: &Start,
    o: &DiagnoseOptions,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Diagnosis, String> {
    let outputs: Vec<String> = sys.output_names().iter().map(|s| s.to_string()).collect();
    // Noise levels: given, from dataset.json, or estimated (then the chi-square
    // test of the level is void and the LR uses the fitted level).
    let mut sigma_estimated = false;
    let mut sigma: Vec<f64> = match &o.sigma {
        Some(s) => s.clone(),
        None => outputs
            .iter()
            .map(|n| {
                data.meta
                    .noise
                    .get(n)
                    .copied()
                    .filter(|s| *s > 0.0)
                    .unwrap_or(f64::NAN)
            })
            .collect(),
    };
    let prepared = prepare(sys, data)?;
    progress("fitting the nominal model");
    if sigma.iter().any(|s| s.is_nan()) {
        sigma_estimated = true;
        let ones: Vec<f64> = sigma
            .iter()
            .map(|s| if s.is_nan() { 1.0 } else { *s })
            .collect();
        let f = fit_model(sys, &prepared, &start.0, &start.1, &ones, &[], o)?;
        let scale = (f.n as f64 / (f.n as f64 - f.n_fitted as f64).max(1.0)).sqrt();
        for (s, r) in sigma.iter_mut().zip(&f.rms) {
            if s.is_nan() {
                *s = (r.1 * scale).max(1e-12);
            }
        }
    }
    // Input noise: stated, or estimated by restricted ML (twice: the levels
    // at the white-noise fit, the refit under them, the levels again).
    let stated = input_noise(sys, data);
    let estimate = o.input_noise == InputNoise::Estimate;
    let mut noise = match o.input_noise {
        InputNoise::Stated => stated,
        InputNoise::Estimate | InputNoise::None => vec![],
    };
    let mut nominal = fit_model(sys, &prepared, &start.0, &start.1, &sigma, &noise, o)?;
    let mut noise_lr = Vec::new();
    if estimate {
        progress("estimating the noise levels");
        let mut lr = 0.0;
        for _ in 0..2 {
            let (s, c, l) = estimate_levels(sys, &prepared, &nominal, &sigma, sigma_estimated, o)?;
            (sigma, noise, lr) = (s, c, l);
            let pv: Vec<f64> = nominal.params.iter().map(|p| p.1).collect();
            let states = nominal.initial_states.clone();
            nominal = fit_model(sys, &prepared, &pv, &states, &sigma, &noise, o)?;
        }
        noise_lr.push(lr);
    }
    let effects: Vec<&Effect> = lib.map(|l| l.effects.iter().collect()).unwrap_or_default();
    let model_effects: Vec<&Effect> = effects
        .iter()
        .copied()
        .filter(|e| !e.is_input_side())
        .collect();
    let k = model_effects.len().max(1);
    let crit = normal_critical(o.alpha / k as f64).powi(2);
    let input_checks: Vec<InputCheck> = effects
        .iter()
        .filter(|e| e.is_input_side())
        .map(|e| input_check(e, data, o.alpha / k as f64))
        .collect();

    let which: Vec<usize> = (0..data.trajectories.len().min(o.rank_trajectories)).collect();
    let mut current_sys = sys.clone();
    let mut current = nominal.clone();
    let mut named: Vec<Named> = Vec::new();
    let mut rounds: Vec<Vec<CandidateResult>> = Vec::new();
    let mut hidden = Vec::new();
    let mut class_text = String::new();
    for round in 0..o.max_rounds {
        let remaining: Vec<&Effect> = model_effects
            .iter()
            .copied()
            .filter(|e| !named.iter().any(|n| n.effect == e.name))
            .collect();
        if remaining.is_empty() {
            break;
        }
        progress(&format!(
            "round {}: {} candidate effects",
            round + 1,
            remaining.len()
        ));
        let results: Vec<(CandidateResult, Option<(System, ModelFit)>)> = remaining
            .par_iter()
            .map(|e| {
                candidate(
                    &current_sys,
                    &current,
                    e,
                    data,
                    &which,
                    (&sigma, &noise),
                    crit,
                    o,
                    lib,
                )
            })
            .collect();
        if round == 0 {
            if let Ok(ext) = current_sys.extend(&[], "") {
                let prepared = prepare(&ext, data)?;
                let (ins, der) = class_inputs(&ext);
                if let Ok(c) = input_class(&ins, &der, &prepared) {
                    class_text = c.describe();
                }
            }
            hidden = results
                .iter()
                .filter(|r| !r.0.identifiable && r.0.error.is_none())
                .map(|r| r.0.clone())
                .collect();
        }
        let best = results
            .iter()
            .filter(|r| r.0.significant)
            .max_by(|a, b| a.0.lr.total_cmp(&b.0.lr))
            .map(|r| (r.0.clone(), r.1.clone()));
        let rivals: Vec<Rival> = best
            .as_ref()
            .map(|(b, _)| {
                results
                    .iter()
                    .filter(|r| {
                        r.0.significant
                            && r.0.effect != b.effect
                            && r.0.delta_bic - b.delta_bic < RIVAL_BIC
                    })
                    .map(|r| Rival {
                        effect: r.0.effect.clone(),
                        delta_bic: (r.0.delta_bic - b.delta_bic).max(0.0),
                        jointly_identifiable: None,
                    })
                    .collect()
            })
            .unwrap_or_default();
        rounds.push(results.into_iter().map(|r| r.0).collect());
        let Some((res, Some((ext_sys, ext_fit)))) = best else {
            break;
        };
        // `best` is one of the candidates, each from `model_effects`.
        let Some(eff) = model_effects.iter().find(|e| e.name == res.effect) else {
            break;
        };
        named.push(Named {
            effect: res.effect.clone(),
            description: eff.description.clone(),
            estimates: res.estimates.clone(),
            robust_sd: res.robust_sd.clone(),
            rms_before: current.rms.clone(),
            rms_after: ext_fit.rms.clone(),
            lr: res.lr,
            p_value: res.p_value,
            rivals,
        });
        current_sys = ext_sys;
        current = ext_fit;
        // The named effect takes its share of the drift: the levels again,
        // and the extended model refitted under them (the next round's
        // candidates are compared with that fit).
        if estimate {
            progress("estimating the noise levels");
            let prep = prepare(&current_sys, data)?;
            let est = estimate_levels(&current_sys, &prep, &current, &sigma, sigma_estimated, o);
            if let Ok((s, c, l)) = est {
                let pv: Vec<f64> = current.params.iter().map(|p| p.1).collect();
                let states = current.initial_states.clone();
                if let Ok(f) = fit_model(&current_sys, &prep, &pv, &states, &s, &c, o) {
                    (sigma, noise) = (s, c);
                    noise_lr.push(l);
                    current = f;
                }
            }
        }
    }
    // A significant candidate that the next round's rank test finds
    // confounded with the named effect is a rival whatever its BIC: on
    // these data the two differ only outside what the data identify.
    for (i, n) in named.iter_mut().enumerate() {
        let (Some(this), Some(next)) = (rounds.get(i), rounds.get(i + 1)) else {
            continue;
        };
        let best = this
            .iter()
            .find(|c| c.effect == n.effect)
            .map(|c| c.delta_bic);
        for c in this
            .iter()
            .filter(|c| c.significant && c.effect != n.effect)
        {
            let confounded = next
                .iter()
                .any(|x| x.effect == c.effect && x.error.is_none() && !x.identifiable);
            if confounded && !n.rivals.iter().any(|r| r.effect == c.effect) {
                n.rivals.push(Rival {
                    effect: c.effect.clone(),
                    delta_bic: (c.delta_bic - best.unwrap_or(c.delta_bic)).max(0.0),
                    jointly_identifiable: None,
                });
            }
        }
    }
    // A rival's rank test in the round after its named effect says whether
    // the two are confounded on these data.
    for (i, n) in named.iter_mut().enumerate() {
        for rv in &mut n.rivals {
            rv.jointly_identifiable = rounds
                .get(i + 1)
                .and_then(|r| r.iter().find(|c| c.effect == rv.effect))
                .filter(|c| c.error.is_none())
                .map(|c| c.identifiable);
        }
    }
    // Estimates of earlier named effects are refined by later rounds.
    for n in &mut named {
        for (i, e) in n.estimates.iter_mut().enumerate() {
            if let Some((v, s)) = current.param(&e.0) {
                e.1 = v;
                e.2 = s * current.inflation().sqrt();
            }
            if let (Some(r), Some(slot)) = (current.robust_sd(&e.0), n.robust_sd.get_mut(i)) {
                *slot = r;
            }
        }
    }
    Ok(Diagnosis {
        model: sys.name.clone(),
        sigma: outputs.into_iter().zip(sigma).collect(),
        sigma_estimated,
        input_noise_source: if estimate {
            "estimated"
        } else if noise.is_empty() {
            "none"
        } else {
            "stated"
        }
        .into(),
        input_noise: noise,
        input_noise_lr: noise_lr,
        input_class: class_text,
        nominal,
        rounds,
        named,
        input_checks,
        final_fit: current,
        hidden,
        extended_sys: current_sys.to_sys_text(),
        lr_critical: crit,
    })
}

#[allow(clippy::too_many_arguments)]
fn candidate(
    base: &System,
    base_fit: &ModelFit,
    e: &Effect,
    data: &Dataset,
    which: &[usize],
    (sigma, noise): (&[f64], &[(String, f64)]),
    crit: f64,
    o: &DiagnoseOptions,
    lib: Option<&EffectLibrary>,
) -> (CandidateResult, Option<(System, ModelFit)>) {
    let mut res = CandidateResult {
        effect: e.name.clone(),
        description: e.description.clone(),
        params: e.params.clone(),
        identifiable: false,
        rank: None,
        symmetry: vec![],
        estimates: vec![],
        robust_sd: vec![],
        lr: 0.0,
        p_value: 1.0,
        delta_bic: 0.0,
        rms: vec![],
        whiteness_z: 0.0,
        significant: false,
        error: None,
    };
    let origin = lib.map_or("effects", |l| l.origin.as_str());
    let mut run = || -> Result<Option<(System, ModelFit)>, String> {
        let ext = base.extend(&[e], origin).map_err(|x| x.to_string())?;
        let prepared = prepare(&ext, data)?;
        let (ins, der) = class_inputs(&ext);
        let class: InputClass = input_class(&ins, &der, &prepared)?;
        let consts: Vec<Vec<(String, f64)>> = prepared
            .trajectories
            .iter()
            .map(|t| {
                ext.decls_of(Kind::Const)
                    .filter(|c| c.value.is_none())
                    .map(|c| (c.name.clone(), t.meta.get(&c.name).copied().unwrap_or(0.0)))
                    .collect()
            })
            .collect();
        let outs = ext.output_names();
        // Per trajectory, the most measured outputs (at most
        // MAX_RANK_OUTPUTS): enough for the test, and every square-root
        // output (a range) halves the density of usable random points.
        let seen: Vec<Vec<bool>> = prepared
            .trajectories
            .iter()
            .map(|t| {
                let counts: Vec<usize> = outs
                    .iter()
                    .map(|o| {
                        t.outputs
                            .column(o)
                            .map_or(0, |c| c.iter().filter(|v| v.is_some()).count())
                    })
                    .collect();
                let mut order: Vec<usize> = (0..outs.len()).filter(|&i| counts[i] > 0).collect();
                order.sort_by(|&a, &b| counts[b].cmp(&counts[a]).then(a.cmp(&b)));
                order.truncate(MAX_RANK_OUTPUTS);
                (0..outs.len()).map(|i| order.contains(&i)).collect()
            })
            .collect();
        let base_pv: Vec<f64> = base_fit.params.iter().map(|p| p.1).collect();
        let (pv, sv) = extended_start(&ext, &base_pv, &base_fit.initial_states, &prepared)?;
        let id: Identifiability = stacked_rank(&ext, &class, &consts, &seen, which, (&pv, &sv))?;
        res.rank = Some((id.rank, id.n));
        res.identifiable = e.params.iter().all(|p| id.param_observable(p));
        if !res.identifiable {
            if let Some((_, terms)) = id.symmetries.iter().find(|s| e.params.contains(&s.0)) {
                res.symmetry = terms.clone();
            }
            return Ok(None);
        }
        // Each fit weighs its residuals by the covariance at its own
        // estimate; their likelihoods then differ by cost and log-determinant
        // ([`ModelFit::m2ll`]). (Holding the current fit's whiteners for
        // every candidate was tried: with large estimated drift the
        // candidate fits did not leave their start.)
        let mut f = fit_model(&ext, &prepared, &pv, &sv, sigma, noise, o)?;
        // A second start for a candidate that improves the fit, from a fit
        // without the gross outliers (|e| > OUTLIER_Z sigma). Outputs that
        // wrap make the cost discontinuous: a scaled bearing jumps at +-pi,
        // and one bearing left on the wrong side of the jump by the nominal
        // model's biased params is a 40-sigma residual that holds the fit
        // short of the effect's size. Without it the fit finds the right
        // side; the full data then polish that start, and the lower cost wins.
        if base_fit.m2ll() - f.m2ll() > crit * f.inflation() {
            if let Some(trimmed) = without_outliers(&prepared, &f, OUTLIER_Z) {
                let pv: Vec<f64> = f.params.iter().map(|p| p.1).collect();
                let f2 = fit_model(&ext, &trimmed, &pv, &f.initial_states, sigma, &[], o).and_then(
                    |t| {
                        let pv: Vec<f64> = t.params.iter().map(|p| p.1).collect();
                        fit_model(&ext, &prepared, &pv, &t.initial_states, sigma, noise, o)
                    },
                );
                if let Ok(f2) = f2 {
                    if f2.m2ll() < f.m2ll() {
                        f = f2;
                    }
                }
            }
        }
        let inflate = f.inflation();
        res.lr = (base_fit.m2ll() - f.m2ll()).max(0.0) / inflate;
        res.p_value = chi2_1_p(res.lr);
        res.delta_bic = -(res.lr - e.params.len() as f64 * (f.n as f64).ln());
        res.significant = res.lr > crit && res.delta_bic < 0.0;
        res.estimates = e
            .params
            .iter()
            .filter_map(|p| f.param(p).map(|(v, s)| (p.clone(), v, s * inflate.sqrt())))
            .collect();
        res.robust_sd = e.params.iter().filter_map(|p| f.robust_sd(p)).collect();
        res.rms = f.rms.clone();
        res.whiteness_z = f
            .residuals
            .tests
            .iter()
            .find(|t| t.test == "whiteness")
            .map_or(0.0, |t| t.z);
        Ok(Some((ext, f)))
    };
    match run() {
        Ok(x) => (res, x),
        Err(msg) => {
            res.error = Some(msg);
            (res, None)
        }
    }
}

/// Fit the params of an input relation `compare u = EXPR` to the measured
/// inputs of every trajectory where EXPR can be evaluated (Gauss–Newton,
/// numeric derivatives; residual scatter gives the standard deviations).
fn input_check(e: &Effect, data: &Dataset, alpha: f64) -> InputCheck {
    let mut out = InputCheck {
        effect: e.name.clone(),
        description: e.description.clone(),
        estimates: vec![],
        z: 0.0,
        significant: false,
        note: String::new(),
    };
    let np = e.params.len();
    let resid = |theta: &[f64]| -> Vec<f64> {
        let mut r = Vec::new();
        for t in &data.trajectories {
            let mut consts: BTreeMap<String, f64> = t.meta.clone();
            for (p, v) in e.params.iter().zip(theta) {
                consts.insert(p.clone(), *v);
            }
            for (u, rhs) in &e.compares {
                let mut s = t.inputs.clone();
                if add_derived_inputs(&mut s, &[("__cmp".into(), rhs.clone())], &consts).is_err() {
                    continue;
                }
                let (Some(m), Some(c)) = (s.column(u), s.column("__cmp")) else {
                    continue;
                };
                // Compared over 1 s block means: averaging keeps the relation
                // (linear in the inputs) and removes the errors-in-variables
                // bias that per-sample encoder noise would give.
                let (mut a, mut b, mut n) = (0.0, 0.0, 0usize);
                let mut t0 = s.t.first().copied().unwrap_or(0.0);
                for ((x, y), t) in m.iter().zip(c).zip(&s.t) {
                    if *t >= t0 + 1.0 && n > 0 {
                        r.push((a - b) / n as f64);
                        (a, b, n, t0) = (0.0, 0.0, 0, *t);
                    }
                    if let (Some(x), Some(y)) = (x, y) {
                        a += x;
                        b += y;
                        n += 1;
                    }
                }
                if n > 0 {
                    r.push((a - b) / n as f64);
                }
            }
        }
        r
    };
    let theta = vec![0.0; np];
    let r0 = resid(&theta);
    if r0.is_empty() {
        out.note = "no trajectory has what the relation needs (e.g. q in meta.json)".into();
        return out;
    }
    // J = -dr/dtheta by forward differences; the normal equations of the core.
    let normal = |theta: &[f64]| {
        let r = resid(theta);
        let jac: Vec<Vec<f64>> = (0..np)
            .map(|i| {
                let mut t2 = theta.to_vec();
                let h = 1e-6 * (1.0 + theta[i].abs());
                t2[i] += h;
                let r2 = resid(&t2);
                r.iter().zip(&r2).map(|(a, b)| (a - b) / h).collect()
            })
            .collect();
        let jtj = nalgebra::DMatrix::from_fn(np, np, |i, j| {
            jac[i].iter().zip(&jac[j]).map(|(a, b)| a * b).sum()
        });
        let jtr =
            nalgebra::DVector::from_fn(np, |i, _| jac[i].iter().zip(&r).map(|(a, b)| a * b).sum());
        (jtj, jtr)
    };
    let cost = |theta: &[f64]| resid(theta).iter().map(|x| x * x).sum::<f64>();
    let theta = minimise(&theta, cost, normal, |_| {}, &LmOptions::default()).x;
    let Some(inv) = normal(&theta).0.try_inverse() else {
        out.note = "the inputs do not determine the relation's params".into();
        return out;
    };
    let r = resid(&theta);
    let s2 = r.iter().map(|x| x * x).sum::<f64>() / (r.len() as f64 - np as f64).max(1.0);
    let cov = inv * s2;
    let zcrit = normal_critical(alpha);
    out.estimates = e
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| (p.clone(), theta[i], cov[(i, i)].max(0.0).sqrt()))
        .collect();
    out.z = out
        .estimates
        .iter()
        .map(|(_, v, s)| if *s > 0.0 { (v / s).abs() } else { 0.0 })
        .fold(0.0, f64::max);
    out.significant = out.z > zcrit;
    out.note = format!("{} input samples", r0.len());
    out
}
