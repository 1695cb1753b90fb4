//! The fits of the workflow: the dataset prepared for a model (derived
//! inputs), its input-noise levels stated or estimated, and one maximum-
//! likelihood fit with its residual tests.

use crate::error::DiagnoseError;
use crate::options::{DiagnoseOptions, AUTO_ESTIMATE_BELOW};
use crate::residual::{analyse, ResidualReport, ResidualSeries};
use obsan_data::{add_derived_inputs, wrap, Dataset};
use obsan_fit::{
    estimate_noise, fit, FitOptions, FitTrajectory, Integration, Measured, NoiseOptions, Predictor,
};
use obsan_model::{Kind, System};
use serde::Serialize;

/// A fitted model and its residuals.
#[derive(Clone, Debug, Serialize)]
pub struct ModelFit {
    pub model: String,
    pub params: Vec<(String, f64, f64)>,
    /// Per param: the cluster-robust sd, trajectories as clusters (right
    /// whatever the correlation within a trajectory; NaN with one).
    pub params_robust_sd: Vec<f64>,
    /// Their whole cluster-robust covariance (the fitter's, whitened under
    /// input noise).
    #[serde(skip)]
    pub params_robust_cov: Vec<Vec<f64>>,
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
    /// Shared: the workflow keeps and clones fits, and the series are the
    /// bulk of one (seven numbers per residual).
    #[serde(skip)]
    pub series: std::sync::Arc<Vec<ResidualSeries>>,
    #[serde(skip)]
    pub covariance: Vec<Vec<f64>>,
}

/// A fit for unit tests: `n` residuals with `n_fitted` unknowns, each
/// output's RMS and the residual series; every other field empty.
#[cfg(test)]
pub(crate) fn test_fit(
    n: usize,
    n_fitted: usize,
    rms: &[(&str, f64)],
    series: Vec<ResidualSeries>,
) -> ModelFit {
    ModelFit {
        model: "m".into(),
        params: vec![],
        params_robust_sd: vec![],
        params_robust_cov: vec![],
        initial_states: vec![],
        cost: 0.0,
        log_det: 0.0,
        n,
        n_fitted,
        iterations: 0,
        rms: rms.iter().map(|(y, r)| (y.to_string(), *r)).collect(),
        residuals: crate::residual::analyse(&[], 0),
        series: std::sync::Arc::new(series),
        covariance: vec![],
    }
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
    /// `-2 log L` with the output levels' own term (`2 ln sigma` per
    /// residual; `sigma` indexed as the fit's outputs): fits under
    /// different levels (white input noise against estimated) compare by it.
    pub fn m2ll_at(&self, sigma: &[f64]) -> f64 {
        let levels: f64 = self
            .series
            .iter()
            .filter_map(|s| {
                let i = self.rms.iter().position(|r| r.0 == s.output)?;
                Some(2.0 * s.e.len() as f64 * sigma.get(i)?.ln())
            })
            .sum();
        self.m2ll() + levels
    }
    /// [`Self::m2ll_at`] at the output levels that minimise it for this
    /// fit's residuals, each its output's RMS (white input noise only: the
    /// levels the data would give a white-noise model).
    pub fn m2ll_profiled(&self) -> f64 {
        let mut n = vec![0usize; self.rms.len()];
        for s in self.series.iter() {
            if let Some(i) = self.rms.iter().position(|r| r.0 == s.output) {
                n[i] += s.e.len();
            }
        }
        let rms: Vec<f64> = self.rms.iter().map(|r| r.1.max(1e-300)).collect();
        n.iter()
            .zip(&rms)
            .map(|(&k, r)| k as f64 * (1.0 + 2.0 * r.ln()))
            .sum()
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

/// The inputs whose class the rank test reads: the model's, then with a
/// delay each one's rate (`rate__<u>`, see `identify::stacked_rank`).
pub(crate) fn class_inputs(sys: &System) -> (Vec<String>, Vec<Option<String>>) {
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
pub fn prepare(sys: &System, data: &Dataset) -> Result<Dataset, DiagnoseError> {
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
    add_session_clocks(sys, &mut d);
    for (k, t) in d.trajectories.iter_mut().enumerate() {
        t.meta
            .entry("later".into())
            .or_insert(if k == 0 { 0.0 } else { 1.0 });
        t.meta.entry("index".into()).or_insert(k as f64);
        add_derived_inputs(&mut t.inputs, &derived, &t.meta).map_err(|source| {
            DiagnoseError::DerivedInput {
                trajectory: t.name.clone(),
                source: Box::new(source),
            }
        })?;
    }
    Ok(d)
}

/// The generated drifts' session clocks (measured inputs named
/// `session_t...` that the data lack): the time since the dataset's first
/// input row, one clock over every trajectory.
fn add_session_clocks(sys: &System, d: &mut Dataset) {
    let (t0, _) = crate::generate::session(d);
    let clocks: Vec<String> = sys
        .decls_of(Kind::Input)
        .filter(|x| x.derived.is_none() && x.name.starts_with(crate::generate::SESSION_CLOCK))
        .map(|x| x.name.clone())
        .collect();
    for tr in &mut d.trajectories {
        let missing: Vec<&String> = clocks
            .iter()
            .filter(|c| tr.inputs.column(c).is_none())
            .collect();
        if missing.is_empty() {
            continue;
        }
        let mut cols = tr.inputs.columns().to_vec();
        cols.extend(missing.iter().map(|c| c.to_string()));
        let mut s = obsan_data::Series::new(cols);
        let mut row: Vec<Option<f64>> = Vec::new();
        for (k, &t) in tr.inputs.t().iter().enumerate() {
            row.clear();
            row.extend(tr.inputs.values().iter().map(|c| c[k]));
            row.extend(missing.iter().map(|_| Some(t - t0)));
            s.push(t, &row);
        }
        tr.inputs = s;
    }
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
pub(crate) fn noise_vector(sys: &System, noise: &[(String, f64)]) -> Option<Vec<f64>> {
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
pub(crate) type Levels = (Vec<f64>, Vec<(String, f64)>, f64);

/// Restricted-ML noise levels at `f` (a fit of `sys`): the output levels
/// (held when `outputs` is false) and each measured input's intensity, with
/// the likelihood-ratio statistic against white output noise.
pub(crate) fn estimate_levels(
    sys: &System,
    data: &Dataset,
    f: &ModelFit,
    sigma: &[f64],
    outputs: bool,
    o: &DiagnoseOptions,
) -> Result<Levels, DiagnoseError> {
    let nf = sys.normal_form(None, &[]).map_err(DiagnoseError::model)?;
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
pub(crate) const OUTLIER_Z: f64 = 5.0;

/// `data` without the measurements whose residual in `f` exceeds `z`
/// sigmas; `None` when there are none.
pub(crate) fn without_outliers(data: &Dataset, f: &ModelFit, z: f64) -> Option<Dataset> {
    let mut out = data.clone();
    let mut removed = 0usize;
    for s in f.series.iter() {
        let Some(tr) = out.trajectories.iter_mut().find(|t| t.name == s.trajectory) else {
            continue;
        };
        let Some(c) = tr.outputs.columns().iter().position(|n| *n == s.output) else {
            continue;
        };
        for (t, e) in s.t.iter().zip(&s.e) {
            if e.abs() > z {
                if let Ok(j) = tr.outputs.t().binary_search_by(|x| x.total_cmp(t)) {
                    tr.outputs.values_mut(c)[j] = None;
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
) -> Result<ModelFit, DiagnoseError> {
    let nf = sys.normal_form(None, &[]).map_err(DiagnoseError::model)?;
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
    let mut r = fit(&p, &trajs, params0, states0, &fo)?;
    let log_det = r.whitening.iter().flatten().map(|w| w.log_det()).sum();
    // The noise is mapped back to each trajectory's start through the
    // inverse transition matrix, which a fast decaying state (a lag of time
    // constant T over a trajectory of many T) makes overflow: then the
    // residuals cannot be weighed and no likelihood can be compared.
    if weighted {
        if let Some(k) = r.whitening.iter().position(Option::is_none) {
            return Err(DiagnoseError::NoiseCovariance {
                trajectory: data.trajectories[k].name.clone(),
            });
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
        // Taken, not copied (it holds five numbers per residual).
        let whitener = r
            .whitening
            .get_mut(k)
            .and_then(Option::take)
            .map(std::sync::Arc::new);
        let mut x0 = r.initial_states[k].clone();
        x0.extend_from_slice(&r.params);
        let integ = Integration {
            max_step: o.max_step,
            sensitivities: false,
            input_noise: None,
        };
        // Only the measured cells (values equal predict_with's exactly): a
        // MRCLAM row measures one or two of its 30 outputs.
        let cells = Measured::new(&p, &tr.outputs);
        let pred = p
            .predict_measured(&x0, &ft.consts, &tr.inputs, &cells, &integ)
            .map_err(|source| DiagnoseError::Predict {
                trajectory: tr.name.clone(),
                source,
            })?;
        // Held input values and their integrals at every output time, once
        // per trajectory (shared by its outputs).
        let in_cols: Vec<Option<&[Option<f64>]>> =
            measured.iter().map(|n| tr.inputs.column(n)).collect();
        let held = |c: &Option<&[Option<f64>]>, row: usize| c.and_then(|c| c[row]).unwrap_or(0.0);
        // Flat: per output time, per measured input, (held value, integral).
        let nm = measured.len();
        let mut held_at: Vec<(f64, f64)> = Vec::with_capacity(tr.outputs.len() * nm);
        {
            let mut row = 0usize;
            let mut integral = vec![0.0; measured.len()];
            let mut t_int = tr.inputs.t().first().copied().unwrap_or(0.0);
            for &t in tr.outputs.t() {
                while row + 1 < tr.inputs.len() && tr.inputs.t()[row + 1] <= t {
                    for (m, c) in in_cols.iter().enumerate() {
                        integral[m] += held(c, row) * (tr.inputs.t()[row + 1] - t_int);
                    }
                    t_int = tr.inputs.t()[row + 1];
                    row += 1;
                }
                held_at.extend(in_cols.iter().enumerate().map(|(m, c)| {
                    let u = held(c, row);
                    (u, integral[m] + u * (t - t_int))
                }));
            }
        }
        for (oi, oname) in p.outputs.iter().enumerate() {
            let Some(col) = tr.outputs.column(oname) else {
                continue;
            };
            // Sized exactly: grown by doubling, the seven series of a
            // million residuals would hold up to twice their size.
            let len = row_of.iter().filter(|x| x.1 == oi).count();
            let mut s = ResidualSeries {
                trajectory: tr.name.clone(),
                output: oname.clone(),
                t: Vec::with_capacity(len),
                e: Vec::with_capacity(len),
                predicted: Vec::with_capacity(len),
                angular: p.angular[oi],
                inputs: measured
                    .iter()
                    .map(|n| (n.clone(), Vec::with_capacity(len)))
                    .collect(),
                input_integrals: measured
                    .iter()
                    .map(|n| (n.clone(), Vec::with_capacity(len)))
                    .collect(),
                whiten: None,
            };
            if let Some(w) = &whitener {
                if len == row_of.len() {
                    // Every residual is this output's: the whitener itself
                    // (its subset would be a copy of it, number for number).
                    s.whiten = Some(w.clone());
                } else {
                    let idx: Vec<usize> = row_of
                        .iter()
                        .enumerate()
                        .filter(|(_, x)| x.1 == oi)
                        .map(|(i, _)| i)
                        .collect();
                    s.whiten = w.subset(&idx).map(std::sync::Arc::new);
                }
            }
            for (j, &t) in tr.outputs.t().iter().enumerate() {
                let Some(m) = col[j] else { continue };
                let Some(i) = cells.at(j).0.iter().position(|&c| c == oi) else {
                    continue;
                };
                let y = pred.outputs[j][i];
                let d = if s.angular { wrap(m - y) } else { m - y };
                s.t.push(t);
                s.e.push(d / sigma[oi]);
                s.predicted.push(y);
                for (mi, &(u, integral)) in held_at[j * nm..(j + 1) * nm].iter().enumerate() {
                    s.inputs[mi].1.push(u);
                    s.input_integrals[mi].1.push(integral);
                }
            }
            if !s.e.is_empty() {
                series.push(s);
            }
        }
    }
    drop(r.whitening);
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
        params_robust_cov: r.params_cov_robust.clone(),
        initial_states: r.initial_states.clone(),
        cost: r.cost,
        log_det,
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
        series: std::sync::Arc::new(series),
        covariance: r.covariance,
    })
}

/// The fit from `start`; when it cannot be made (the model diverges from
/// the start on some trajectory), a continuation replaces the start: fits on
/// each trajectory's first eighth, quarter and half of its outputs, each
/// from the last, then the whole data. A start from which a trajectory
/// diverges is never the answer. `own` gives the data's own start (without
/// the values the user gave by name), tried as one more route: a user's
/// start that diverges must not keep the search away from the basin the data
/// themselves point to. The note says what was done.
pub(crate) fn first_fit(
    sys: &System,
    prepared: &Dataset,
    start: &Start,
    (sigma, noise): (&[f64], &[(String, f64)]),
    o: &DiagnoseOptions,
    own: &dyn Fn() -> Option<Start>,
) -> Result<(ModelFit, Option<String>), DiagnoseError> {
    let err = match fit_model(sys, prepared, &start.0, &start.1, sigma, noise, o) {
        Ok(f) => return Ok((f, None)),
        Err(e) => e,
    };
    // Every route that gives a fit; the lowest -2 log L is kept (a route
    // can end in another basin).
    let mut routes: Vec<(ModelFit, String)> = Vec::new();
    let (mut pv, mut sv) = (start.0.clone(), start.1.clone());
    let mut done = Vec::new();
    for (frac, what) in [(0.125, "eighth"), (0.25, "quarter"), (0.5, "half")] {
        if let Ok(f) = fit_model(sys, &shortened(prepared, frac), &pv, &sv, sigma, &[], o) {
            pv = f.params.iter().map(|p| p.1).collect();
            sv = f.initial_states;
            done.push(what);
        }
    }
    if !done.is_empty() {
        if let Ok(f) = fit_model(sys, prepared, &pv, &sv, sigma, noise, o) {
            let how = format!(
                "fits on each trajectory's first {} of its outputs, each started from the last",
                done.join(", ")
            );
            routes.push((f, how));
        }
    }
    // A trajectory the start cannot follow left out of a first fit, whose
    // params then start the whole data.
    for k in 0..prepared.trajectories.len().min(AUTO_ESTIMATE_BELOW) {
        let mut d = prepared.clone();
        d.trajectories.remove(k);
        let mut s0 = start.1.clone();
        s0.remove(k);
        let Ok(f) = fit_model(sys, &d, &start.0, &s0, sigma, &[], o) else {
            continue;
        };
        let pv: Vec<f64> = f.params.iter().map(|p| p.1).collect();
        let mut sv = f.initial_states;
        sv.insert(k, start.1[k].clone());
        if let Ok(f) = fit_model(sys, prepared, &pv, &sv, sigma, noise, o) {
            let how = format!(
                "a fit without trajectory '{}', whose params started the whole data",
                prepared.trajectories[k].name
            );
            routes.push((f, how));
        }
    }
    if let Some(s) = own() {
        if let Ok(f) = fit_model(sys, prepared, &s.0, &s.1, sigma, noise, o) {
            let how = format!(
                "the data's own start without the values given by name: {}",
                s.2
            );
            routes.push((f, how));
        }
    }
    let n = routes.len();
    let (f, how) = routes
        .into_iter()
        .min_by(|a, b| a.0.m2ll().total_cmp(&b.0.m2ll()))
        .ok_or(err.clone())?;
    let note = format!(
        "the fit from this start failed ({err}); replaced by {how} (the best of {n} routes)"
    );
    Ok((f, Some(note)))
}

/// `data` with each trajectory's outputs cut to the first `frac` of its
/// duration (at least two rows).
fn shortened(data: &Dataset, frac: f64) -> Dataset {
    let mut d = data.clone();
    for t in &mut d.trajectories {
        let tt = t.outputs.t();
        let (Some(a), Some(b)) = (tt.first(), tt.last()) else {
            continue;
        };
        let cut = a + frac * (b - a);
        let n = tt.iter().take_while(|x| **x <= cut).count().max(2);
        t.outputs.truncate(n);
    }
    d
}

/// Start values for `sys` on `data`: a function of the model (see
/// [`crate::start_values`]): the params, per trajectory the initial dynamic
/// state, and how they were found (printed with the diagnosis).
#[derive(Clone, Debug)]
pub struct Start(pub Vec<f64>, pub Vec<Vec<f64>>, pub String);

/// The output noise levels the options or `dataset.json` give; NaN where
/// neither does (estimated by [`output_levels`]).
pub(crate) fn given_levels(outputs: &[String], data: &Dataset, o: &DiagnoseOptions) -> Vec<f64> {
    match &o.sigma {
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
    }
}

/// The output levels not given are estimated from a fit at unit levels (its
/// RMS, corrected for the fitted params); then the chi-square test of the
/// level is void and the LR uses the fitted level. Returns the levels and
/// whether any was estimated.
pub(crate) fn output_levels(
    sys: &System,
    prepared: &Dataset,
    start: &Start,
    mut sigma: Vec<f64>,
    (o, own): (&DiagnoseOptions, &dyn Fn() -> Option<Start>),
) -> Result<(Vec<f64>, bool), DiagnoseError> {
    if !sigma.iter().any(|s| s.is_nan()) {
        return Ok((sigma, false));
    }
    let ones: Vec<f64> = sigma
        .iter()
        .map(|s| if s.is_nan() { 1.0 } else { *s })
        .collect();
    let (f, _) = first_fit(sys, prepared, start, (&ones, &[]), o, own)?;
    let scale = (f.n as f64 / (f.n as f64 - f.n_fitted as f64).max(1.0)).sqrt();
    for (s, r) in sigma.iter_mut().zip(&f.rms) {
        if s.is_nan() {
            *s = (r.1 * scale).max(1e-12);
        }
    }
    Ok((sigma, true))
}
