//! Where the nominal fit starts. Maximum likelihood needs a start near the
//! optimum; for the models obsan ships there is a data-only initialiser
//! (the paper's DET + LS + section V-C for calib.sys); for any other model
//! the user gives values by name; otherwise a declaration's start value
//! (`param T = 0.2`, `state va = v`) is used, and params without one start
//! at 0.
//!
//! When the paper's start cannot be made on every trajectory (DET needs one
//! whole loop and a readable period, eq. 35; a large wheel slip or a short
//! recording denies it), it is made on the trajectories that allow it, and
//! each remaining trajectory's initial state comes from a screened grid over
//! (mu0, gamma0) at those params; the few best combinations are each fitted
//! briefly by maximum likelihood and the lowest cost is the start. The
//! start says which route it took (the third field of [`Start`]).

use crate::error::DiagnoseError;
use crate::model_fit::{prepare, Start};
use obsan_calib::{calibrate, circle_modes, CalibrateOptions, Method};
use obsan_data::{add_derived_inputs, wrap, Dataset, Trajectory};
use obsan_fit::{fit, FitError, FitOptions, FitTrajectory, Predictor};
use obsan_model::{Decl, Kind, Start as DeclStart, System};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// The calibration params read by the paper's start, in its order.
const CALIB: [&str; 5] = ["phi", "psi", "eta", "delta", "xi"];

/// What the paper's start gave: params, per trajectory (mu0, gamma0) where
/// DET + LS could be made, the bearing noise LS read, and how.
struct CalibStart {
    /// The params, or (when section V-C could not be made) a grid of them.
    params: Vec<[f64; 5]>,
    states: Vec<Option<(f64, f64)>>,
    sigma: f64,
    how: String,
}

/// Whether the model can be integrated from a start (params, per
/// trajectory its (mu0, gamma0) where known): `Err` names the trajectory.
type Usable<'a> = &'a Check<'a>;
type Check<'a> = dyn Fn(&[f64; 5], &[Option<(f64, f64)>]) -> Result<(), String> + 'a;

/// How the paper's start on all trajectories went, when it is not the start.
enum First {
    /// DET + LS or section V-C failed.
    Failed(obsan_calib::CalibError),
    /// It was made, but the model cannot be integrated from it (why).
    Unusable(Box<CalibStart>, String),
}

/// DET + LS + section V-C on `data`; when that fails, on the largest subsets
/// of its trajectories where it succeeds (leaving out one, then two), the
/// subset whose LS residuals are smallest. A start the model cannot be
/// integrated from counts as failed: section V-C can return absurd values
/// (eta = 4e5 under a large slip and radius change on slow circles), whose
/// dynamics are too fast for any step, and the fit would refuse at once.
fn calib_start(data: &Dataset, usable: Usable) -> Result<CalibStart, DiagnoseError> {
    let run = |d: &Dataset| {
        let opts = CalibrateOptions::for_dataset(d, Method::Ls);
        calibrate(d, None, &opts)
    };
    let first = match run(data) {
        Ok(r) => {
            let start = CalibStart {
                params: vec![r.calibration.values()],
                states: r.trajectories.iter().map(|t| Some(t.start)).collect(),
                sigma: r.sigma_beta,
                how: "DET + LS per trajectory and section V-C (the paper's start)".into(),
            };
            match usable(&start.params[0], &start.states) {
                Ok(()) => return Ok(start),
                Err(why) => First::Unusable(Box::new(start), why),
            }
        }
        Err(e) => First::Failed(e),
    };
    let first_text = match &first {
        First::Failed(e) => e.to_string(),
        First::Unusable(_, why) => format!("its values leave the model unusable: {why}"),
    };
    let k = data.trajectories.len();
    for drop in 1..=2usize.min(k.saturating_sub(2)) {
        let mut best: Option<(Vec<usize>, obsan_calib::CalibrationReport, _)> = None;
        for left_out in subsets(k, drop) {
            let mut d = data.clone();
            d.trajectories = (0..k)
                .filter(|i| !left_out.contains(i))
                .map(|i| data.trajectories[i].clone())
                .collect();
            if let Ok(r) = run(&d) {
                if r.sigma_beta.is_finite()
                    && best.as_ref().is_none_or(|b| r.sigma_beta < b.1.sigma_beta)
                {
                    let mut states = vec![None; k];
                    let kept = (0..k).filter(|i| !left_out.contains(i));
                    for (i, t) in kept.zip(&r.trajectories) {
                        states[i] = Some(t.start);
                    }
                    if usable(&r.calibration.values(), &states).is_ok() {
                        best = Some((left_out, r, states));
                    }
                }
            }
        }
        if let Some((left_out, r, states)) = best {
            let names: Vec<String> = left_out
                .iter()
                .map(|&i| format!("'{}'", data.trajectories[i].name))
                .collect();
            return Ok(CalibStart {
                params: vec![r.calibration.values()],
                states,
                sigma: r.sigma_beta,
                how: format!(
                    "the paper's start failed ({first_text}); DET + LS and section V-C on the other \
                     trajectories, the initial state of {} from a screened grid over (mu0, gamma0)",
                    names.join(", ")
                ),
            });
        }
    }
    // Section V-C cannot be made: xi and delta from the circles whose modes
    // LS reads (eq. 18), psi from one circle's L given (phi, eta) on a grid.
    let opts = CalibrateOptions::for_dataset(data, Method::Ls);
    let modes: Vec<(f64, f64, f64)> = circle_modes(data, &opts).into_iter().flatten().collect();
    let Some(&(q1, xq1, l1)) = modes.first() else {
        // No other route: an unusable paper start is returned (the fit
        // then says why), a failed one is the error.
        return match first {
            First::Unusable(start, _) => Ok(*start),
            First::Failed(e) => Err(DiagnoseError::CalibStart { first: Box::new(e) }),
        };
    };
    // delta from the line when two q are read, and the nominal radii's
    // ratio (a wrong model, such as wheel slip, can bend the line).
    let nominal = &data.meta.nominal;
    let delta_nominal = match (nominal.get("r_left"), nominal.get("r_right")) {
        (Some(l), Some(r)) if *r > 0.0 && *l > 0.0 => l / r,
        _ => 1.0,
    };
    let mut xd = vec![(xq1 / (1.0 - delta_nominal * q1), delta_nominal)];
    if let Some(line) = xi_delta(&modes).filter(|l| l.0 > 0.0 && l.1 > 0.0) {
        xd.insert(0, line);
    }
    let mut grid = Vec::new();
    for &(xi, delta) in &xd {
        for i in 0..PHI_STEPS {
            let phi = wrap(2.0 * PI * i as f64 / PHI_STEPS as f64);
            for &eta in &ETA_GRID {
                let eta_q = eta * (1.0 + q1 * delta);
                let psi = wrap(l1 + (xq1 - eta_q * phi.sin()).atan2(eta_q * phi.cos()));
                grid.push([phi, psi, eta, delta, xi]);
            }
        }
    }
    let sigma = opts.sigma_beta.unwrap_or(1e-2);
    Ok(CalibStart {
        params: grid,
        states: vec![None; k],
        sigma,
        how: format!(
            "the paper's start failed ({first_text}); xi, delta from the modes of {} circle(s) \
             (eq. 18), a screened grid over phi and eta with psi from one circle's L, and every \
             trajectory's (mu0, gamma0) screened",
            modes.len()
        ),
    })
}

/// Grid over the sensor's angle phi and eta when section V-C cannot be made.
const PHI_STEPS: usize = 8;
const ETA_GRID: [f64; 3] = [0.3, 0.6, 1.2];

/// `xi_q = xi (1 - delta q)` (eq. 18) through circles of at least two
/// distinct q, by least squares: `(xi, delta)`.
fn xi_delta(modes: &[(f64, f64, f64)]) -> Option<(f64, f64)> {
    let n = modes.len() as f64;
    let mq = modes.iter().map(|m| m.0).sum::<f64>() / n;
    let mx = modes.iter().map(|m| m.1).sum::<f64>() / n;
    let sqq: f64 = modes.iter().map(|m| (m.0 - mq).powi(2)).sum();
    if sqq < 1e-12 {
        return None;
    }
    let b = modes.iter().map(|m| (m.0 - mq) * (m.1 - mx)).sum::<f64>() / sqq;
    let a = mx - b * mq;
    (a != 0.0).then(|| (a, -b / a))
}

/// Every `m`-element subset of `0..k`, in lexicographic order.
fn subsets(k: usize, m: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    fn rec(start: usize, k: usize, m: usize, cur: &mut Vec<usize>, out: &mut Vec<Vec<usize>>) {
        if cur.len() == m {
            out.push(cur.clone());
            return;
        }
        for i in start..k {
            cur.push(i);
            rec(i + 1, k, m, cur, out);
            cur.pop();
        }
    }
    rec(0, k, m, &mut cur, &mut out);
    out
}

/// Grid of the screen: gamma0 every 22.5 degrees, mu0 (= rho / D) over more
/// than a decade.
const GAMMA_STEPS: usize = 16;
const MU_GRID: [f64; 5] = [0.06, 0.12, 0.25, 0.5, 1.0];
/// The screen compares predictions over the first bearings only (the
/// initial state shows there, before drift of a wrong param accumulates).
const SCREEN_OUTPUTS: usize = 25;
/// Combinations fitted briefly, and their iterations.
/// Eight, not three: under a large slip and radius change on slow circles
/// (`sine:0.3:60`, seeds 1, 2, 3, 6) the three best screened combinations
/// all fitted to one wrong basin (cost about 750,000), the best eight reach
/// the right one (about 13,700), for 10 % more time (4.0 to 4.4 s).
const STARTS: usize = 8;
const START_ITERATIONS: usize = 10;

/// Cost (sum of squared normalised, wrapped residuals) of trajectory `t`'s
/// first [`SCREEN_OUTPUTS`] output rows from `x0`; infinite when the state
/// diverges.
fn screen_cost(p: &Predictor, t: &Trajectory, x0: &[f64], sigma: &[f64]) -> f64 {
    let Ok(y) = first_rows(p, t, x0) else {
        return f64::INFINITY;
    };
    let mut c = 0.0;
    for (o, name) in p.outputs.iter().enumerate() {
        let Some(col) = t.outputs.column(name) else {
            continue;
        };
        for (j, yj) in y.iter().enumerate() {
            if let Some(m) = col[j] {
                let d = if p.angular[o] {
                    wrap(m - yj[o])
                } else {
                    m - yj[o]
                };
                c += (d / sigma[o]).powi(2);
            }
        }
    }
    if c.is_finite() {
        c
    } else {
        f64::INFINITY
    }
}

/// The model's outputs at trajectory `t`'s first [`SCREEN_OUTPUTS`] output
/// times from `x0`.
fn first_rows(p: &Predictor, t: &Trajectory, x0: &[f64]) -> Result<Vec<Vec<f64>>, FitError> {
    rows(p, t, x0, SCREEN_OUTPUTS)
}

/// The model's outputs at trajectory `t`'s first `n` output times from `x0`.
fn rows(p: &Predictor, t: &Trajectory, x0: &[f64], n: usize) -> Result<Vec<Vec<f64>>, FitError> {
    let consts: Vec<f64> = p
        .consts
        .iter()
        .map(|c| t.meta.get(c).copied().unwrap_or(0.0))
        .collect();
    let rows = t.outputs.len().min(n);
    p.predict(x0, &consts, &t.inputs, &t.outputs.t()[..rows])
}

/// Initial states of calib.sys trajectories the paper's start could not
/// give (`missing`), for each candidate param vector (`pvs`): per
/// trajectory the grid points screened at those params; the combinations
/// (a param vector with the i-th best state of every missing trajectory)
/// are ranked by their summed screen cost, the best [`STARTS`] each fitted
/// briefly (all params and states), and the lowest cost is kept.
fn screened_states(
    sys: &System,
    data: &Dataset,
    pvs: &[Vec<f64>],
    sv: &[Vec<f64>],
    missing: &[usize],
    sigma: f64,
) -> Result<Start, DiagnoseError> {
    let nf = sys.normal_form(None, &[]).map_err(DiagnoseError::model)?;
    let p = Predictor::new(&nf);
    let prepared = prepare(sys, data)?;
    let sig = vec![sigma; p.outputs.len()];
    let (imu, igamma) = (
        p.state.iter().position(|s| s == "mu"),
        p.state.iter().position(|s| s == "gamma"),
    );
    let (Some(imu), Some(igamma)) = (imu, igamma) else {
        return Err(DiagnoseError::ScreenNeedsMuGamma);
    };
    // (screen cost, params, states) of every combination.
    let mut combos: Vec<(f64, Vec<f64>, Vec<Vec<f64>>)> = pvs
        .par_iter()
        .flat_map_iter(|pv| {
            let mut ranked: Vec<Vec<(f64, Vec<f64>)>> = Vec::new();
            for &k in missing {
                let t = &prepared.trajectories[k];
                let mut cands: Vec<(f64, Vec<f64>)> = Vec::new();
                for g in 0..GAMMA_STEPS {
                    let gamma = -PI + 2.0 * PI * (g as f64 + 0.5) / GAMMA_STEPS as f64;
                    for &mu in &MU_GRID {
                        let mut x = sv[k].clone();
                        x[imu] = mu;
                        x[igamma] = gamma;
                        let mut x0 = x.clone();
                        x0.extend_from_slice(pv);
                        cands.push((screen_cost(&p, t, &x0, &sig), x));
                    }
                }
                cands.retain(|c| c.0.is_finite());
                cands.sort_by(|a, b| a.0.total_cmp(&b.0));
                cands.truncate(STARTS);
                ranked.push(cands);
            }
            let depth = ranked.iter().map(Vec::len).min().unwrap_or(0);
            (0..depth)
                .map(|i| {
                    let mut states = sv.to_vec();
                    let mut cost = 0.0;
                    for (m, &k) in missing.iter().enumerate() {
                        cost += ranked[m][i].0;
                        states[k] = ranked[m][i].1.clone();
                    }
                    (cost, pv.clone(), states)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    if combos.is_empty() {
        return Err(DiagnoseError::ScreenDiverges);
    }
    combos.sort_by(|a, b| a.0.total_cmp(&b.0));
    combos.truncate(STARTS);
    let trajs = FitTrajectory::all(&p, &prepared);
    let opts = FitOptions {
        max_iterations: START_ITERATIONS,
        cost_tolerance: 1e-6,
        step_tolerance: 0.1,
        sigma: sig,
        max_step: 0.5,
        input_noise: None,
    };
    let tried = combos.len();
    // The caller's cancel flag is thread-local: hand it to the workers.
    let cancel = obsan_expr::cancel_flag();
    let best = combos
        .par_iter()
        .filter_map(|(_, pv, states)| {
            obsan_expr::with_cancel(cancel.clone(), || fit(&p, &trajs, pv, states, &opts)).ok()
        })
        .min_by(|a, b| a.cost.total_cmp(&b.cost));
    let Some(r) = best else {
        return Err(DiagnoseError::ScreenNoFit { tried });
    };
    Ok(Start(
        r.params,
        r.initial_states,
        format!(
            "{} grid points per trajectory and param vector ({} of those), the best {tried} \
             combinations each fitted for up to {START_ITERATIONS} iterations, the lowest cost \
             ({:.1}) kept",
            GAMMA_STEPS * MU_GRID.len(),
            pvs.len(),
            r.cost
        ),
    ))
}

/// The check behind [`calib_start`]'s `usable`: the model predicts every
/// output row of every trajectory whose (mu0,
/// gamma0) is known from the calib params given, its other params at
/// `given` or their declared values (else 0), its other states at 0.
fn integrable<'a>(
    sys: &System,
    data: &'a Dataset,
    given: &'a BTreeMap<String, f64>,
) -> Result<Box<Check<'a>>, DiagnoseError> {
    let nf = sys.normal_form(None, &[]).map_err(DiagnoseError::model)?;
    let p = Predictor::new(&nf);
    let prepared = prepare(sys, data)?;
    let declared: BTreeMap<String, f64> = sys
        .decls_of(Kind::Param)
        .filter_map(|d| Some((d.name.clone(), declared_number(d)?)))
        .collect();
    Ok(Box::new(
        move |pv: &[f64; 5], states: &[Option<(f64, f64)>]| {
            for (t, st) in prepared.trajectories.iter().zip(states) {
                let Some((mu, gamma)) = st else { continue };
                let x0: Vec<f64> = p
                    .state
                    .iter()
                    .map(|n| match n.as_str() {
                        "mu" => *mu,
                        "gamma" => *gamma,
                        _ => given
                            .get(n)
                            .or_else(|| CALIB.iter().position(|c| c == n).map(|i| &pv[i]))
                            .or_else(|| declared.get(n))
                            .copied()
                            .unwrap_or(0.0),
                    })
                    .collect();
                // The whole trajectory, not its first rows: a DET + LS start
                // whose q = 0 circle diverges at t = 31 s was the fit's
                // first point, and diagnose stopped there.
                if let Err(e) = rows(&p, t, &x0, usize::MAX) {
                    return Err(format!("trajectory '{}': {e}", t.name));
                }
            }
            Ok(())
        },
    ))
}

/// The data's own start, without the values given by name, when it differs
/// from `start`: a route for a start that cannot be fitted.
pub(crate) fn own_start(sys: &System, data: &Dataset, start: &Start) -> Option<Start> {
    let own = start_values(sys, data, &BTreeMap::new()).ok()?;
    (own.0 != start.0 || own.1 != start.1).then_some(own)
}

/// Start values (params, per trajectory the dynamic state) for `sys` on
/// `data`, with how they were found; `given` overrides by name (a state's
/// value applies to every trajectory).
pub fn start_values(
    sys: &System,
    data: &Dataset,
    given: &BTreeMap<String, f64>,
) -> Result<Start, DiagnoseError> {
    let params: Vec<String> = sys.decls_of(Kind::Param).map(|d| d.name.clone()).collect();
    let states: Vec<String> = sys.decls_of(Kind::State).map(|d| d.name.clone()).collect();
    let mut p: BTreeMap<String, f64> = BTreeMap::new();
    let mut s: Vec<BTreeMap<String, f64>> = vec![BTreeMap::new(); data.trajectories.len()];
    let mut how = Vec::new();
    // Trajectories whose calib start must be screened, with LS's noise level.
    let mut screen: Option<(Vec<usize>, Vec<[f64; 5]>, f64)> = None;
    let calib_like =
        states == ["mu", "gamma"] && CALIB.iter().all(|c| params.iter().any(|x| x == c));
    let given_state = states.iter().any(|n| given.contains_key(n));
    if calib_like {
        // The paper's pipeline: DET, LS per circle, section V-C.
        let usable = integrable(sys, data, given)?;
        let c = calib_start(data, &usable)?;
        for (n, v) in CALIB.iter().zip(c.params[0]) {
            p.insert(n.to_string(), v);
        }
        let mut missing = Vec::new();
        for (k, st) in c.states.iter().enumerate() {
            match st {
                Some((mu, gamma)) => {
                    s[k].insert("mu".into(), *mu);
                    s[k].insert("gamma".into(), *gamma);
                }
                None => {
                    // Placeholders, replaced by the screen.
                    s[k].insert("mu".into(), 0.0);
                    s[k].insert("gamma".into(), 0.0);
                    missing.push(k);
                }
            }
        }
        how.push(c.how);
        if !missing.is_empty() && !given_state {
            screen = Some((missing, c.params, c.sigma));
        }
    }
    if states.starts_with(&["x".to_string(), "y".to_string(), "th".to_string()]) {
        for (k, t) in data.trajectories.iter().enumerate() {
            if let Some(x0) = unicycle_start(t) {
                s[k].insert("x".into(), x0[0]);
                s[k].insert("y".into(), x0[1]);
                s[k].insert("th".into(), x0[2]);
            }
        }
    }
    // A state measured directly (`output px = x`, or its angle
    // `atan2(sin(th), cos(th))`) starts at its first measurement.
    for (k, t) in data.trajectories.iter().enumerate() {
        for n in &states {
            if s[k].contains_key(n) {
                continue;
            }
            let direct = [n.clone(), format!("atan2(sin({n}), cos({n}))")];
            let first = sys
                .output_names()
                .iter()
                .filter(|o| {
                    sys.rhs_text(o)
                        .is_some_and(|r| direct.iter().any(|d| d == r))
                })
                .find_map(|o| t.outputs.column(o)?.iter().flatten().next().copied());
            if let Some(v) = first {
                s[k].insert(n.clone(), v);
            }
        }
    }
    // Declared starts where nothing better is known.
    for d in sys.decls_of(Kind::Param) {
        if let Some(v) = declared_number(d) {
            p.entry(d.name.clone()).or_insert(v);
        }
    }
    for (k, t) in data.trajectories.iter().enumerate() {
        for d in sys.decls_of(Kind::State) {
            if let Some(DeclStart::Inputs(e)) = &d.start {
                if !s[k].contains_key(&d.name) {
                    s[k].insert(d.name.clone(), state_start(&d.name, e, t)?);
                }
            }
        }
    }
    for (n, v) in given {
        if params.contains(n) {
            p.insert(n.clone(), *v);
        } else if states.contains(n) {
            for sk in &mut s {
                sk.insert(n.clone(), *v);
            }
        } else {
            return Err(DiagnoseError::UnknownInit {
                name: n.clone(),
                system: sys.name.clone(),
            });
        }
    }
    let pv: Vec<f64> = params
        .iter()
        .map(|n| p.get(n).copied().unwrap_or(0.0))
        .collect();
    let mut sv = Vec::new();
    for (k, sk) in s.iter().enumerate() {
        let mut v = Vec::new();
        for n in &states {
            match sk.get(n) {
                Some(x) => v.push(*x),
                None => {
                    return Err(DiagnoseError::NoStartValue {
                        state: n.clone(),
                        system: sys.name.clone(),
                        trajectory: data.trajectories[k].name.clone(),
                    })
                }
            }
        }
        sv.push(v);
    }
    if let Some((missing, grid, sigma)) = screen {
        // Each candidate's calib params in place of the start's; --init
        // values and other params kept.
        let pvs: Vec<Vec<f64>> = grid
            .iter()
            .map(|g| {
                let mut v = pv.clone();
                for (n, x) in CALIB.iter().zip(g) {
                    if let Some(i) = params.iter().position(|q| q == n) {
                        if !given.contains_key(*n) {
                            v[i] = *x;
                        }
                    }
                }
                v
            })
            .collect();
        let Start(pv2, sv2, note) = screened_states(sys, data, &pvs, &sv, &missing, sigma)?;
        how.push(note);
        return Ok(Start(pv2, sv2, how.join("; ")));
    }
    if how.is_empty() {
        how.push(if given.is_empty() {
            "declared start values (params without one at 0)".to_string()
        } else {
            "--init values, declared start values elsewhere".to_string()
        });
    }
    Ok(Start(pv, sv, how.join("; ")))
}

/// The start pose of a unicycle window observing known landmarks (outputs
/// `r<c>`, `b<c>`, constants `lx<c>`, `ly<c>`): dead-reckon the window from
/// the origin with the commanded (v, omega), turn every range-bearing
/// measurement into the landmark's position in that frame, and register
/// those points onto the known landmarks (2-D Procrustes, closed form).
fn unicycle_start(t: &obsan_data::Trajectory) -> Option<[f64; 3]> {
    let (v, w) = (t.inputs.column("v")?, t.inputs.column("omega")?);
    // Relative poses at the input rows.
    let mut pose = vec![(0.0f64, 0.0f64, 0.0f64)];
    for k in 0..t.inputs.len().saturating_sub(1) {
        let dt = t.inputs.t()[k + 1] - t.inputs.t()[k];
        let (x, y, th) = pose[k];
        let (vk, wk) = (v[k].unwrap_or(0.0), w[k].unwrap_or(0.0));
        let thm = th + 0.5 * wk * dt;
        pose.push((
            x + vk * dt * thm.cos(),
            y + vk * dt * thm.sin(),
            th + wk * dt,
        ));
    }
    let mut q = Vec::new();
    let mut l = Vec::new();
    for (ci, name) in t.outputs.columns().iter().enumerate() {
        let Some(code) = name.strip_prefix('r') else {
            continue;
        };
        let Some(bi) = t
            .outputs
            .columns()
            .iter()
            .position(|c| c == &format!("b{code}"))
        else {
            continue;
        };
        let (Some(lx), Some(ly)) = (
            t.meta.get(&format!("lx{code}")),
            t.meta.get(&format!("ly{code}")),
        ) else {
            continue;
        };
        for (j, &tj) in t.outputs.t().iter().enumerate() {
            let (Some(r), Some(b)) = (t.outputs.values()[ci][j], t.outputs.values()[bi][j]) else {
                continue;
            };
            let k = t
                .inputs
                .t()
                .partition_point(|&x| x <= tj)
                .saturating_sub(1)
                .min(pose.len() - 1);
            let (px, py, pth) = pose[k];
            q.push((px + r * (pth + b).cos(), py + r * (pth + b).sin()));
            l.push((*lx, *ly));
        }
    }
    if q.len() < 2 {
        return None;
    }
    let n = q.len() as f64;
    let qc = (
        q.iter().map(|p| p.0).sum::<f64>() / n,
        q.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let lc = (
        l.iter().map(|p| p.0).sum::<f64>() / n,
        l.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let (mut sc, mut ss) = (0.0, 0.0);
    for (a, b) in q.iter().zip(&l) {
        let (ax, ay, bx, by) = (a.0 - qc.0, a.1 - qc.1, b.0 - lc.0, b.1 - lc.1);
        sc += ax * bx + ay * by;
        ss += ax * by - ay * bx;
    }
    let th0 = ss.atan2(sc);
    let (c, s) = (th0.cos(), th0.sin());
    let x0 = lc.0 - (c * qc.0 - s * qc.1);
    let y0 = lc.1 - (s * qc.0 + c * qc.1);
    Some([x0, y0, th0])
}

/// A param's declared start value (`param T = 0.2`).
fn declared_number(d: &Decl) -> Option<f64> {
    match &d.start {
        Some(DeclStart::Number(q)) => Some(q.to_f64()),
        _ => None,
    }
}

/// A state's declared start on one trajectory: `expr` evaluated at the
/// inputs' first row (with the trajectory's constants).
fn state_start(name: &str, expr: &str, t: &Trajectory) -> Result<f64, DiagnoseError> {
    let mut head = t.inputs.clone();
    head.truncate(2);
    let key = format!("{name}__start");
    add_derived_inputs(&mut head, &[(key.clone(), expr.to_string())], &t.meta).map_err(
        |source| DiagnoseError::StateStart {
            state: name.to_string(),
            trajectory: t.name.clone(),
            source: Box::new(source),
        },
    )?;
    head.column(&key)
        .and_then(|c| c.first().copied().flatten())
        .filter(|v| v.is_finite())
        .ok_or_else(|| DiagnoseError::StateStartNoValue {
            state: name.to_string(),
            expr: expr.to_string(),
            trajectory: t.name.clone(),
        })
}

/// Start values of `ext`, a model extended from one whose fit gave
/// `params` and `states` (per trajectory): those first, then each new
/// param's declared start (else 0) and each new state's declared start.
pub fn extended_start(
    ext: &System,
    params: &[f64],
    states: &[Vec<f64>],
    data: &Dataset,
) -> Result<(Vec<f64>, Vec<Vec<f64>>), DiagnoseError> {
    let mut pv = params.to_vec();
    for d in ext.decls_of(Kind::Param).skip(params.len()) {
        pv.push(declared_number(d).unwrap_or(0.0));
    }
    let mut sv = Vec::with_capacity(states.len());
    for (k, (x0, t)) in states.iter().zip(&data.trajectories).enumerate() {
        let mut x = x0.clone();
        for d in ext.decls_of(Kind::State).skip(x0.len()) {
            match &d.start {
                Some(DeclStart::Inputs(e)) => x.push(state_start(&d.name, e, t)?),
                _ => {
                    return Err(DiagnoseError::NewStateNoStart {
                        state: d.name.clone(),
                        trajectory: k,
                    })
                }
            }
        }
        sv.push(x);
    }
    Ok((pv, sv))
}
