//! A cheap screen for the generated candidates: the score
//! (Lagrange-multiplier) statistic of each candidate at the current fit,
//! from one pass of the extended model's sensitivities, no refit. Only the
//! candidates whose statistic clears `LR critical / SCREEN_SAFETY` are
//! rank-tested and fitted.
//!
//! At the current fit `theta` (the candidate's new params at zero), with
//! whitened residuals `r` and Jacobian `J` over every free quantity of the
//! extended model (old and new params, each trajectory's initial state),
//! `S = g^T (J^T J)^-1 g` with `g = J^T r` is the decrease of the cost that
//! a Gauss–Newton step of the extended model predicts; less the same form
//! over the base's columns alone, it is the part the new params add
//! (`effective_score`). At a converged base fit the old components of `g`
//! vanish and it is the classical score statistic (Rao 1948), asymptotically
//! the LR's chi-square under the null; at a base fit short of its optimum it
//! is Neyman's C(alpha) statistic. A candidate's new states are held at
//! their start (a lag's state at the first input), so an initial transient
//! gives no score.

use crate::common_mode::{self, difference_estimate, CommonModeCheck, Member};
use crate::error::DiagnoseError;
use crate::model_fit::{prepare, ModelFit, OUTLIER_Z};
use crate::report::CandidateResult;
use crate::start::extended_start;
use obsan_data::{wrap, Dataset};
use obsan_fit::{FitTrajectory, Integration, Measured, Predictor};
use obsan_model::{Effect, System};

/// The screen's threshold is the LR's critical value divided by this. The
/// score and the fitted LR of a candidate agree to first order; they part
/// where the effect is large or the model nonlinear in it, the score then
/// usually lower (a Gauss–Newton step predicts the decrease of a quadratic
/// model). On the tests' data the ratio LR / score stays within
/// [`SCREEN_SAFETY`] wherever the LR is above the threshold
/// (docs/diagnose.md, "Generated candidates": tests/diagb_generated.rs
/// prints both for every candidate).
pub const SCREEN_SAFETY: f64 = 4.0;

/// A candidate's score statistic and, where the heading-free check applies,
/// that check predicted at the current fit ([`common_mode::predicted`]).
#[derive(Clone, Debug)]
pub(crate) struct Scored {
    pub(crate) score: f64,
    pub(crate) check: Option<CommonModeCheck>,
}

impl Scored {
    /// The prediction vetoes the candidate: it is not fitted.
    fn vetoed(&self) -> bool {
        self.check.as_ref().is_some_and(|c| c.predicted && c.vetoed)
    }
}

/// The score statistic of extending `base` (fitted as `f` to `data`, output
/// levels `sigma`) by `e`, divided by `f`'s inflation as the LR is. Ordinary
/// least squares only: the caller fits every candidate when the residuals
/// are weighed by input noise. `crit`: the candidate's critical LR value,
/// for the heading-free check's prediction when it applies to `e`.
pub(crate) fn score(
    base: &System,
    f: &ModelFit,
    e: &Effect,
    data: &Dataset,
    sigma: &[f64],
    (max_step, crit): (f64, Option<f64>),
) -> Result<Scored, DiagnoseError> {
    let ext = base
        .extend(&[e], crate::generate::ORIGIN_GENERATED)
        .map_err(|e| DiagnoseError::Extend(Box::new(e)))?;
    let prepared = prepare(&ext, data)?;
    let base_pv: Vec<f64> = f.params.iter().map(|p| p.1).collect();
    let (pv, sv) = extended_start(&ext, &base_pv, &f.initial_states, &prepared)?;
    let nf = ext.normal_form(None, &[]).map_err(DiagnoseError::model)?;
    let p = Predictor::new(&nf);
    let trajs = FitTrajectory::all(&p, &prepared);
    let (np, nd) = (pv.len(), p.n_dynamic);
    // The base model's dynamic states are free per trajectory; the new
    // ones (the first `nd_old` are the base's) are held.
    let nd_old = f.initial_states.first().map_or(0, Vec::len).min(nd);
    let local = np + nd_old;
    let k = trajs.len();
    let dim = np + k * nd_old;
    let mut a = nalgebra::DMatrix::<f64>::zeros(dim, dim);
    let mut g = nalgebra::DVector::<f64>::zeros(dim);
    let integ = Integration {
        max_step,
        sensitivities: true,
        input_noise: None,
    };
    let n = p.state.len();
    // The heading-free check's inputs (common_mode.rs): the group's
    // outputs with the current fit's RMS (for its outlier rule) and the
    // param's column.
    let angular = |y: &str| f.series.iter().any(|s| s.output == y && s.angular);
    let target = crit.and_then(|crit| {
        let (group, param) = common_mode::eligible(e, &angular).ok()?;
        let pi = p.state.iter().position(|s| *s == param)?;
        let cols: Vec<(usize, f64)> = group
            .iter()
            .filter_map(|y| {
                let o = p.outputs.iter().position(|x| x == y)?;
                let rms = f.rms.iter().find(|r| r.0 == *y).map_or(0.0, |r| r.1);
                Some((o, rms))
            })
            .collect();
        Some((crit, group, param, pi, cols))
    });
    let mut locals = Vec::new();
    let mut clusters = Vec::new();
    for (ti, (t, x)) in trajs.iter().zip(&sv).enumerate() {
        let mut x0 = x.clone();
        x0.extend_from_slice(&pv);
        // Only the measured cells (a MRCLAM row measures one or two of 30
        // outputs): the same values and rows as the whole prediction's.
        let cells = Measured::new(&p, t.outputs);
        let pred = p
            .predict_measured(&x0, &t.consts, t.inputs, &cells, &integ)
            .map_err(|source| DiagnoseError::Predict {
                trajectory: t.name.to_string(),
                source,
            })?;
        // Local columns: the params, then this trajectory's own states.
        let mut al = nalgebra::DMatrix::<f64>::zeros(local, local);
        let mut gl = vec![0.0; local];
        let mut row = vec![0.0; local];
        let mut members = Vec::new();
        for (j, yj) in pred.outputs.iter().enumerate() {
            let (outs, values) = cells.at(j);
            for (i, (&o, &m)) in outs.iter().zip(values).enumerate() {
                let d = m - yj[i];
                let r = if p.angular[o] { wrap(d) } else { d } / sigma[o];
                let jac = &pred.jacobians[j][i * n..(i + 1) * n];
                if let Some((.., pi, cols)) = &target {
                    // As the check: gross outliers left out.
                    if let Some(&(_, rms)) = cols.iter().find(|c| c.0 == o) {
                        let e = wrap(d);
                        if !(rms > 0.0 && e.abs() > OUTLIER_Z * rms) {
                            let m = Member {
                                t: t.outputs.t()[j],
                                residual: e,
                                sensitivity: jac[*pi],
                            };
                            let raw: Vec<f64> = (0..local)
                                .map(|i| if i < np { jac[nd + i] } else { jac[i - np] })
                                .collect();
                            members.push((m, raw));
                        }
                    }
                }
                for (i, v) in row.iter_mut().enumerate() {
                    *v = if i < np { jac[nd + i] } else { jac[i - np] } / sigma[o];
                }
                for i in 0..local {
                    gl[i] += row[i] * r;
                    for l in 0..=i {
                        al[(i, l)] += row[i] * row[l];
                    }
                }
            }
        }
        let at = |i: usize| {
            if i < np {
                i
            } else {
                np + ti * nd_old + (i - np)
            }
        };
        for i in 0..local {
            g[at(i)] += gl[i];
            for l in 0..=i {
                a[(at(i), at(l))] += al[(i, l)];
                if l != i {
                    a[(at(l), at(i))] += al[(i, l)];
                }
            }
        }
        if target.is_some() {
            let cols: Vec<usize> = (0..local).map(at).collect();
            locals.push((cols, al, gl));
            clusters.push(members);
        }
    }
    // The new params' own share: the decrease with every column less the
    // decrease the base's columns alone predict.
    let np_old = base_pv.len().min(np);
    let old: Vec<usize> = (0..np_old).chain(np..dim).collect();
    let (a_old, g_old) = (
        a.select_rows(&old).select_columns(&old),
        g.select_rows(&old),
    );
    // One eigen-decomposition gives the score's form and, for the
    // heading-free prediction, the step.
    let (all, ainv) = spectral(a, g.clone(), target.is_some());
    let score = effective_score(all, a_old, g_old) / f.inflation();
    let check = target.zip(ainv).map(|((crit, group, param, _, _), ainv)| {
        let step = &ainv * &g;
        let robust_sd = robust_sd(&ainv, &step, &locals, np_old);
        // The members' residuals at the step, to first order: the check
        // reads them at the candidate's fit, whose states move with the
        // param (at the current states the predicted z was 0.1-0.35 too
        // high on MRCLAM robot 2).
        let moved: Vec<Vec<Member>> = clusters
            .iter()
            .zip(&locals)
            .map(|(ms, (cols, _, _))| {
                ms.iter()
                    .map(|(m, raw)| {
                        let shift: f64 = raw.iter().zip(cols).map(|(x, &c)| x * step[c]).sum();
                        Member {
                            residual: m.residual - shift,
                            ..*m
                        }
                    })
                    .collect()
            })
            .collect();
        let d = difference_estimate(&moved);
        let at = pv[np_old] + step[np_old];
        common_mode::predicted((group, param), (at, robust_sd), &d, (crit, score))
    });
    Ok(Scored { score, check })
}

/// The cluster-robust sd of component `i` of the Gauss-Newton step `step`
/// (`ainv` = `A^+`) as the fit would give it there (`obsan_fit`'s
/// sandwich, trajectories as clusters): each trajectory's score at the
/// step linearised, `g_k - A_k step`. `locals`: per trajectory, its
/// columns' places in `A`, its own `A_k` (lower triangle) and `g_k`.
fn robust_sd(
    ainv: &nalgebra::DMatrix<f64>,
    step: &nalgebra::DVector<f64>,
    locals: &[(Vec<usize>, nalgebra::DMatrix<f64>, Vec<f64>)],
    i: usize,
) -> f64 {
    let k = locals.len();
    if k < 2 {
        return f64::NAN;
    }
    let mut var = 0.0;
    for (cols, al, gl) in locals {
        let mut c = 0.0;
        for (r, &ar) in cols.iter().enumerate() {
            let mut u = gl[r];
            for (l, &cl) in cols.iter().enumerate() {
                let x = if l <= r { al[(r, l)] } else { al[(l, r)] };
                u -= x * step[cl];
            }
            c += ainv[(i, ar)] * u;
        }
        var += c * c;
    }
    (var * k as f64 / (k as f64 - 1.0)).sqrt()
}

/// Neyman's C(alpha) statistic (1959) by block inversion: `S(all) -
/// S(old)`, `S = g^T A^+ g` over the named columns (`all`: `S` over every
/// column). At a converged base fit
/// `g_old = 0` and it is the classical score statistic; at a base fit short
/// of its optimum (a fit stops where the decrease left is below
/// `STALL_DECREASE` per step, in directions the model cannot reach) the
/// plain statistic also counts what the base's own params would still gain,
/// the same for every candidate, which the candidate's fit does not realise
/// either: on MRCLAM robot 1, from the third round on, 7-11 for every
/// candidate whose fitted LR was 0-8. The difference is the decrease the
/// new params add, the quantity their LR estimates.
fn effective_score(all: f64, a_old: nalgebra::DMatrix<f64>, g_old: nalgebra::DVector<f64>) -> f64 {
    (all - quadratic_form(a_old, g_old)).max(0.0)
}

/// The screen's stand-in for an effect of the user's file (the generated
/// ones carry theirs, [`crate::Generated::screen`]): the effect itself when
/// it adds no state and no delay; for a first-order lag written as
/// `state s = u`, `s' = (u - s)/T`, `subst x = s` (mrclam.eff's
/// actuator_lag) its limit as T -> 0, `x = u - T rate(u)`, the state held at
/// the first input as the generated lag's; for a bare `delay tau`, every
/// measured input `u - tau rate(u)` (the delay to first order). `None`:
/// any other form, always fitted. `inputs` are the model's measured inputs.
pub(crate) fn file_stand_in(e: &Effect, inputs: &[String]) -> Option<Effect> {
    let bare = e.inputs.is_empty() && e.consts.is_empty() && e.compares.is_empty();
    if e.states.is_empty() && e.delay.is_none() {
        return Some(e.clone());
    }
    if !bare || e.params.len() != 1 || !e.outputs.is_empty() {
        return None;
    }
    let t = &e.params[0];
    let rate = |u: &str| format!("s_rate_{}_{u}", e.name);
    let mut body = format!("effect {}\nparam {t}\n", e.name);
    if let Some(tau) = &e.delay {
        if tau != t || !e.states.is_empty() || !e.substs.is_empty() || !e.dynamics.is_empty() {
            return None;
        }
        for u in inputs {
            let r = rate(u);
            body.push_str(&format!(
                "input {r} = rate({u})\nsubst {u} = {u} - {t}*{r}\n"
            ));
        }
    } else {
        let squash = |x: &str| x.chars().filter(|c| !c.is_whitespace()).collect::<String>();
        if e.substs.len() != e.states.len() || e.dynamics.len() != e.states.len() {
            return None;
        }
        for (x, s) in &e.substs {
            let s = squash(s);
            let u = e
                .starts
                .iter()
                .find(|(n, _)| *n == s)
                .map(|(_, u)| squash(u))?;
            let d = e
                .dynamics
                .iter()
                .find(|(n, _)| *n == s)
                .map(|(_, d)| squash(d))?;
            if !inputs.contains(&u) || d != format!("({u}-{s})/{t}") {
                return None;
            }
            let r = rate(&u);
            body.push_str(&format!(
                "input {r} = rate({u})\nsubst {x} = {u} - {t}*{r}\n"
            ));
        }
    }
    let lib = obsan_model::EffectLibrary::parse(&body, crate::generate::ORIGIN_GENERATED).ok()?;
    lib.effects.into_iter().next()
}

/// One candidate's outcome: its round entry and, when fitted, the extended
/// model and its fit (`T`, the workflow's record of it).
pub(crate) type Outcome<T> = (CandidateResult, Option<T>);

/// One round: every candidate that `score` gives no statistic for (the
/// file's, an exact delay, a failed score) is fitted; the scored ones
/// below `threshold` are not, nor those whose heading-free check is
/// predicted to veto them ([`common_mode::predicted`]: they cannot be
/// named); the others are fitted in decreasing order of score, a batch per
/// thread, while a score times [`SCREEN_SAFETY`] exceeds the largest
/// significant LR found so far: below that the candidate cannot win the
/// round, and only the winner is named. `threshold` `None`: fit every one.
/// The outcomes are in the order of `cands`.
///
/// When the best significant candidate is generated, every candidate of the
/// effects file (`is_file`) left unfitted is fitted too, unless its check
/// vetoes it: a generated form must not win against a file effect that was
/// never fitted (own-speed wheel slip named a bearing harmonic while the
/// file's turn-rate slip stayed screened out); both fitted, each entry says
/// the residual structure its fit leaves.
pub(crate) fn round<T, S, F, I>(
    cands: &[&Effect],
    score: S,
    fit: F,
    threshold: Option<f64>,
    is_file: I,
) -> Vec<Outcome<T>>
where
    T: Send,
    S: Fn(&Effect) -> Option<Scored> + Sync,
    F: Fn(&Effect, Option<&Scored>) -> Outcome<T> + Sync,
    I: Fn(&Effect) -> bool + Sync,
{
    use rayon::prelude::*;
    let scores: Vec<Option<Scored>> = cands.par_iter().map(|e| score(e)).collect();
    let mut out: Vec<Option<Outcome<T>>> = cands
        .par_iter()
        .zip(&scores)
        .map(|(e, s)| match (s, threshold) {
            (Some(_), Some(_)) => None,
            _ => Some(fit(e, s.as_ref())),
        })
        .collect();
    let Some(th) = threshold else {
        return out.into_iter().flatten().collect();
    };
    for ((e, s), o) in cands.iter().zip(&scores).zip(out.iter_mut()) {
        if let Some(s) = s.as_ref().filter(|s| s.vetoed()) {
            *o = Some((predicted_veto(e, s), None));
        }
    }
    let best = |out: &[Option<Outcome<T>>]| {
        out.iter()
            .flatten()
            .filter(|o| o.0.significant)
            .fold(0.0f64, |m, o| m.max(o.0.lr))
    };
    let mut order: Vec<(usize, f64)> = (0..cands.len())
        .filter(|&i| out[i].is_none())
        .filter_map(|i| scores[i].as_ref().map(|s| (i, s.score)))
        .collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    let batch = rayon::current_num_threads().max(1);
    let mut at = 0;
    while at < order.len() {
        let b = best(&out);
        let next: Vec<(usize, f64)> = order[at..]
            .iter()
            .take(batch)
            .copied()
            .filter(|&(_, s)| s >= th && s * SCREEN_SAFETY > b)
            .collect();
        if next.is_empty() {
            break;
        }
        at += next.len();
        let done: Vec<(usize, Outcome<T>)> = next
            .par_iter()
            .map(|&(i, _)| (i, fit(cands[i], scores[i].as_ref())))
            .collect();
        for (i, o) in done {
            out[i] = Some(o);
        }
    }
    let generated_wins = out
        .iter()
        .flatten()
        .filter(|o| o.0.significant)
        .max_by(|a, b| a.0.lr.total_cmp(&b.0.lr))
        .is_some_and(|o| o.0.origin == crate::generate::ORIGIN_GENERATED);
    if generated_wins {
        let rest: Vec<usize> = (0..cands.len())
            .filter(|&i| out[i].is_none() && is_file(cands[i]))
            .collect();
        let done: Vec<(usize, Outcome<T>)> = rest
            .par_iter()
            .map(|&i| (i, fit(cands[i], scores[i].as_ref())))
            .collect();
        for (i, o) in done {
            out[i] = Some(o);
        }
    }
    cands
        .iter()
        .zip(out)
        .zip(&scores)
        .map(|((e, o), s)| {
            o.unwrap_or_else(|| (screened(e, s.as_ref().map_or(0.0, |s| s.score)), None))
        })
        .collect()
}

/// The round's entry for a candidate left unfitted by its score (marked
/// generated; the workflow marks the file's).
pub(crate) fn screened(e: &Effect, score: f64) -> CandidateResult {
    CandidateResult {
        score: Some(score),
        screened_out: true,
        ..CandidateResult::untried(e, crate::generate::ORIGIN_GENERATED)
    }
}

/// The entry of a candidate left unfitted because its heading-free check,
/// predicted, vetoes it: screened out, the prediction as its check.
fn predicted_veto(e: &Effect, s: &Scored) -> CandidateResult {
    CandidateResult {
        common_mode: s.check.clone(),
        ..screened(e, s.score)
    }
}

/// `g^T A^+ g` for a symmetric positive semidefinite `A`: Jacobi-scaled, the
/// pseudo-inverse over eigenvalues above 1e-10 of the largest (directions
/// the data do not determine carry no score). 0 when not finite.
fn quadratic_form(a: nalgebra::DMatrix<f64>, g: nalgebra::DVector<f64>) -> f64 {
    spectral(a, g, false).0
}

/// [`quadratic_form`] and, when `inverse`, the pseudo-inverse `A^+` it
/// used (unscaled; NaN when not finite): one eigen-decomposition for both.
fn spectral(
    mut a: nalgebra::DMatrix<f64>,
    mut g: nalgebra::DVector<f64>,
    inverse: bool,
) -> (f64, Option<nalgebra::DMatrix<f64>>) {
    let n = g.len();
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let x = a[(i, i)];
            if x > 0.0 && x.is_finite() {
                1.0 / x.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    for i in 0..n {
        g[i] *= d[i];
        for j in 0..n {
            a[(i, j)] *= d[i] * d[j];
        }
    }
    if !a.iter().chain(g.iter()).all(|x| x.is_finite()) {
        let nan = inverse.then(|| nalgebra::DMatrix::from_element(n, n, f64::NAN));
        return (0.0, nan);
    }
    let eig = nalgebra::SymmetricEigen::new(a);
    let top = eig.eigenvalues.iter().fold(0.0f64, |m, x| m.max(*x));
    let mut s = 0.0;
    let mut inv = inverse.then(|| nalgebra::DMatrix::<f64>::zeros(n, n));
    for (i, &l) in eig.eigenvalues.iter().enumerate() {
        if l > 1e-10 * top {
            let v = eig.eigenvectors.column(i);
            let c = v.dot(&g);
            s += c * c / l;
            if let Some(m) = inv.as_mut() {
                m.ger(1.0 / l, &v, &v, 1.0);
            }
        }
    }
    if let Some(m) = inv.as_mut() {
        for i in 0..n {
            for j in 0..n {
                m[(i, j)] *= d[i] * d[j];
            }
        }
    }
    (s, inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_lags_and_delays_get_their_first_order_stand_ins() {
        let lib = obsan_model::EffectLibrary::parse(
            "effect lag\nparam T = 0.2\nstate va = v, wa = omega\nva' = (v - va)/T\n\
             wa' = (omega - wa)/T\nsubst v = va, omega = wa\n\
             effect late\nparam tau\ndelay tau\n\
             effect odd\nparam T\nstate s = v\ns' = (v - 2*s)/T\nsubst v = s\n\
             effect scale\nparam k\nsubst v = (1 + k)*v\n",
            "test",
        )
        .unwrap();
        let inputs = ["v".to_string(), "omega".to_string()];
        let st: Vec<Option<Effect>> = lib
            .effects
            .iter()
            .map(|e| file_stand_in(e, &inputs))
            .collect();
        // u - T rate(u) per lagged input, no state; the delay on each input.
        for (i, par) in [(0, "T"), (1, "tau")] {
            let e = st[i].as_ref().unwrap();
            assert!(e.states.is_empty() && e.delay.is_none());
            assert_eq!(e.params, vec![par.to_string()]);
            let substs: Vec<(&str, String)> = e
                .substs
                .iter()
                .map(|(u, x)| (u.as_str(), x.replace(' ', "")))
                .collect();
            let n = &lib.effects[i].name;
            assert_eq!(
                substs,
                vec![
                    ("v", format!("v-{par}*s_rate_{n}_v")),
                    ("omega", format!("omega-{par}*s_rate_{n}_omega"))
                ]
            );
        }
        // Another form of state is not guessed at; a plain effect is itself.
        assert!(st[2].is_none());
        assert_eq!(st[3].as_ref(), Some(&lib.effects[3]));
    }

    /// The C(alpha) identity: `S(all) - S(old)` is the quadratic form of
    /// the new params' adjusted score `g_n - A_no A_oo^-1 g_o` in the inverse
    /// of their efficient information `A_nn - A_no A_oo^-1 A_on`; it
    /// vanishes when the new columns explain nothing beyond the old.
    #[test]
    fn the_effective_score_is_the_adjusted_score_in_the_efficient_information() {
        use nalgebra::{DMatrix, DVector};
        let mut rng = obsan_fit::Rng::new(7);
        for case in 0..50 {
            let (rows, n_old, n_new) = (12, 1 + case % 4, 1 + case % 2);
            let n = n_old + n_new;
            let j = DMatrix::from_fn(rows, n, |_, _| rng.normal());
            let r = DVector::from_fn(rows, |_, _| rng.normal());
            let (a, g) = (j.transpose() * &j, j.transpose() * &r);
            let old: Vec<usize> = (0..n_old).collect();
            let new: Vec<usize> = (n_old..n).collect();
            let pick =
                |m: &DMatrix<f64>, r: &[usize], c: &[usize]| m.select_rows(r).select_columns(c);
            let (a_oo, a_no, a_nn) = (
                pick(&a, &old, &old),
                pick(&a, &new, &old),
                pick(&a, &new, &new),
            );
            let a_oo_inv = a_oo.clone().try_inverse().unwrap();
            let adj = g.select_rows(&new) - &a_no * &a_oo_inv * g.select_rows(&old);
            let eff = a_nn - &a_no * &a_oo_inv * a_no.transpose();
            let want = (adj.transpose() * eff.try_inverse().unwrap() * &adj)[(0, 0)];
            let got = effective_score(
                quadratic_form(a.clone(), g.clone()),
                a_oo,
                g.select_rows(&old),
            );
            assert!(
                (got - want).abs() < 1e-8 * (1.0 + want),
                "case {case}: {got} vs {want}"
            );
        }
        // A new column equal to an old one adds nothing.
        let j = DMatrix::from_row_slice(3, 2, &[1.0, 1.0, 2.0, 2.0, 0.5, 0.5]);
        let r = DVector::from_vec(vec![1.0, -1.0, 3.0]);
        let (a, g) = (j.transpose() * &j, j.transpose() * &r);
        let s = effective_score(
            quadratic_form(a.clone(), g.clone()),
            a.select_rows(&[0]).select_columns(&[0]),
            g.select_rows(&[0]),
        );
        assert!(s.abs() < 1e-9, "{s}");
    }

    #[test]
    fn quadratic_form_is_the_least_squares_decrease() {
        // r = (1, 2, 2), one column (1, 1, 0): the fitted decrease is
        // (1 + 2)^2 / 2 = 4.5; a second column equal to the first adds none.
        let a = nalgebra::DMatrix::from_row_slice(2, 2, &[2.0, 2.0, 2.0, 2.0]);
        let g = nalgebra::DVector::from_vec(vec![3.0, 3.0]);
        assert!((quadratic_form(a, g) - 4.5).abs() < 1e-9);
        let a = nalgebra::DMatrix::from_row_slice(1, 1, &[2.0]);
        let g = nalgebra::DVector::from_vec(vec![3.0]);
        assert!((quadratic_form(a, g) - 4.5).abs() < 1e-12);
    }
}
