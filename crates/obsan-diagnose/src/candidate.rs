//! One candidate effect weighed against the current model (a round of
//! `workflow.rs`): the exact rank test on these data, then the fits
//! under the noise models in use and the likelihood ratio, moved out of
//! workflow.rs whole.

use crate::common_mode;
use crate::error::DiagnoseError;
use crate::identify::{input_class, stacked_rank, Identifiability, InputClass};
use crate::model_fit::{
    class_inputs, estimate_levels, fit_model, prepare, without_outliers, ModelFit, OUTLIER_Z,
};
use crate::options::DiagnoseOptions;
use crate::report::{CandidateResult, MOVED_SD};
use crate::start::extended_start;
use crate::stats::chi2_1_p;
use obsan_data::Dataset;
use obsan_model::{Effect, Kind, System};

/// Outputs per trajectory used by the rank test (the most measured ones).
pub(crate) const MAX_RANK_OUTPUTS: usize = 4;

/// The noise models a candidate is weighed under: the levels in use and,
/// under `auto` with estimated input noise, the white-input-noise end of
/// the same family (its output levels and the current model's fit there).
pub(crate) struct Noise<'a> {
    pub(crate) sigma: &'a [f64],
    pub(crate) noise: &'a [(String, f64)],
    pub(crate) white: Option<(&'a [f64], &'a ModelFit)>,
    /// The output levels are estimated: the white side's are then profiled
    /// (each output's RMS at that fit), not held at the nominal fit's.
    pub(crate) profile: bool,
}

/// A candidate's fit: the extended model, its fit under the noise model
/// that won, its fit at white input noise when that lost (the next round's
/// white side), and which won.
#[derive(Clone)]
pub(crate) struct Fitted {
    pub(crate) sys: System,
    pub(crate) fit: ModelFit,
    pub(crate) white: Option<ModelFit>,
    pub(crate) white_won: bool,
}

/// The extended model, its data, its start and its exact rank test on
/// these data: what every candidate needs before it is fitted.
struct Ranked {
    ext: System,
    prepared: Dataset,
    pv: Vec<f64>,
    sv: Vec<Vec<f64>>,
    warmed: bool,
}

/// Extend `base` by `e`, start it from `base_fit` (the new params at
/// `warm` when given) and rank-test it on `data`'s input class; `res`
/// gets the rank, the identifiability and, if not identifiable, the null
/// vector. `None`: not identifiable (nothing to fit).
#[allow(clippy::too_many_arguments)]
fn rank_test(
    base: &System,
    base_fit: &ModelFit,
    e: &Effect,
    data: &Dataset,
    which: &[usize],
    origin: &str,
    warm: Option<&[f64]>,
    res: &mut CandidateResult,
) -> Result<Option<Ranked>, DiagnoseError> {
    let ext = base
        .extend(&[e], origin)
        .map_err(|e| DiagnoseError::Extend(Box::new(e)))?;
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
    let (mut pv, sv) = extended_start(&ext, &base_pv, &base_fit.initial_states, &prepared)?;
    // A warm start: the new params at the candidate's previous estimate.
    let warm = warm.filter(|w| w.len() == pv.len() - base_pv.len());
    let warmed = warm.is_some();
    if let Some(w) = warm {
        pv[base_pv.len()..].copy_from_slice(w);
    }
    let id: Identifiability = stacked_rank(&ext, &class, &consts, &seen, which, (&pv, &sv))
        .map_err(|err| match err {
            DiagnoseError::TooManyReached { reached, limit, .. } => DiagnoseError::TooManyReached {
                reached,
                limit,
                at: format!("{origin}:{}: effect '{}'", e.line, e.name),
            },
            other => other,
        })?;
    res.rank = Some((id.rank, id.n));
    res.identifiable = e.params.iter().all(|p| id.param_observable(p));
    if !res.identifiable {
        if let Some((_, terms)) = id.symmetries.iter().find(|s| e.params.contains(&s.0)) {
            res.symmetry = terms.clone();
        }
        return Ok(None);
    }
    Ok(Some(Ranked {
        ext,
        prepared,
        pv,
        sv,
        warmed,
    }))
}

/// Fill in a screened candidate's round entry `res` from its rank test
/// alone (the first round's file candidates that the score screen leaves
/// unfitted: the "cannot reveal" report needs every one's rank). Not
/// identifiable: the entry the full route gives, no longer marked screened
/// out; identifiable: still screened out, with its rank.
pub(crate) fn rank_only(
    base: &System,
    base_fit: &ModelFit,
    e: &Effect,
    data: &Dataset,
    which: &[usize],
    origin: &str,
    res: &mut CandidateResult,
) {
    match rank_test(base, base_fit, e, data, which, origin, None, res) {
        Ok(None) => res.screened_out = false,
        Ok(Some(_)) => {}
        Err(err) => res.error = Some(err.to_string()),
    }
}

/// Under `auto` with estimated input noise, each side of the likelihood
/// ratio takes the better of its fits at the estimated levels and at white
/// input noise (`c = 0`, the boundary of the same family). That is the
/// profile over a two-point set of the levels: it never exceeds the profile
/// over all levels, so the test is no more liberal than the profile
/// likelihood ratio, while an effect that explains the residual drift the
/// estimate absorbed (a lag, whose fast states the linearised noise model
/// cannot even carry) is weighed where it lives, at white noise.
#[allow(clippy::too_many_arguments)]
pub(crate) fn candidate(
    base: &System,
    base_fit: &ModelFit,
    e: &Effect,
    data: &Dataset,
    which: &[usize],
    levels: Noise,
    (crit, wald_z_crit): (f64, Option<f64>),
    o: &DiagnoseOptions,
    origin: &str,
    warm: Option<&[f64]>,
) -> (CandidateResult, Option<Fitted>) {
    let Noise {
        sigma,
        noise,
        white,
        profile,
    } = levels;
    // -2 log L at white input noise, the output levels profiled when they
    // are estimated (a lag's misfit inflates the nominal fit's levels).
    let white_m2ll = |f: &ModelFit, sw: &[f64]| {
        if profile {
            f.m2ll_profiled()
        } else {
            f.m2ll_at(sw)
        }
    };
    let mut res = CandidateResult::untried(e, origin);
    let mut run = || -> Result<Option<Fitted>, DiagnoseError> {
        let Some(Ranked {
            ext,
            prepared,
            pv,
            sv,
            warmed,
        }) = rank_test(base, base_fit, e, data, which, origin, warm, &mut res)?
        else {
            return Ok(None);
        };
        // Each fit weighs its residuals by the covariance at its own
        // estimate; their likelihoods then differ by cost and log-determinant
        // ([`ModelFit::m2ll`]). (Holding the current fit's whiteners for
        // every candidate was tried: with large estimated drift the
        // candidate fits did not leave their start.)
        let rewrites_angle = e
            .outputs
            .iter()
            .any(|(y, _)| base_fit.series.iter().any(|s| s.output == *y && s.angular));
        let fit_under = |sigma: &[f64], noise: &[(String, f64)], base_m2ll: f64| {
            let mut f = fit_model(&ext, &prepared, &pv, &sv, sigma, noise, o)?;
            // A second start for a candidate that improves the fit, from a
            // fit without the gross outliers (|e| > OUTLIER_Z sigma).
            // Outputs that wrap make the cost discontinuous: a scaled bearing
            // jumps at +-pi, and one bearing left on the wrong side of the
            // jump by the nominal model's biased params is a 40-sigma
            // residual that holds the fit short of the effect's size.
            // Without it the fit finds the right side; the full data then
            // polish that start, and the lower cost wins. Only an effect that
            // replaces an angle output can make such a jump (the wrapped
            // residual of a continuous prediction is continuous), so only
            // those pay for the two extra fits (on MRCLAM a third of the fits
            // that carry the lag's states).
            // A warm start is the previous round's result, restart included.
            if rewrites_angle && !warmed && base_m2ll - f.m2ll() > crit * f.inflation() {
                if let Some(trimmed) = without_outliers(&prepared, &f, OUTLIER_Z) {
                    let pv: Vec<f64> = f.params.iter().map(|p| p.1).collect();
                    let f2 = fit_model(&ext, &trimmed, &pv, &f.initial_states, sigma, &[], o)
                        .and_then(|t| {
                            let pv: Vec<f64> = t.params.iter().map(|p| p.1).collect();
                            fit_model(&ext, &prepared, &pv, &t.initial_states, sigma, noise, o)
                        });
                    if let Ok(f2) = f2 {
                        if f2.m2ll() < f.m2ll() {
                            f = f2;
                        }
                    }
                }
            }
            Ok::<_, DiagnoseError>(f)
        };
        let held = fit_under(sigma, noise, base_fit.m2ll());
        // Both sides of the ratio at their better noise model (see above);
        // without a white side, the levels held and the fit's own m2ll.
        let (f, white_fit, white_won, base_m2ll, f_m2ll) = match white {
            None => {
                let f = held?;
                let m = f.m2ll();
                (f, None, false, base_fit.m2ll(), m)
            }
            Some((sw, bw)) => {
                let base_m2ll = base_fit.m2ll_at(sigma).min(white_m2ll(bw, sw));
                let white_side = fit_under(sw, &[], bw.m2ll());
                // Noise and effect decided jointly: an effect that the
                // estimated levels absorbed (a distortion read as heading
                // noise) gains at white noise but loses there to the absorbing
                // levels, and its fit at those levels does not leave its
                // start. The levels are estimated again with the effect in
                // the model, from its white-noise fit, and the candidate is
                // refitted under them: the profile over the levels of both
                // sides of the ratio.
                let joint_from = white_side
                    .as_ref()
                    .ok()
                    .filter(|w| white_m2ll(bw, sw) - white_m2ll(w, sw) > crit)
                    .cloned();
                let mut fits = match (held, white_side) {
                    (Ok(h), Ok(w)) if h.m2ll_at(sigma) <= white_m2ll(&w, sw) => {
                        let m = h.m2ll_at(sigma);
                        (h, Some(w), false, base_m2ll, m)
                    }
                    (_, Ok(w)) => {
                        let m = white_m2ll(&w, sw);
                        (w, None, true, base_m2ll, m)
                    }
                    (Ok(h), Err(_)) => {
                        let m = h.m2ll_at(sigma);
                        (h, None, false, base_m2ll, m)
                    }
                    (Err(e), Err(_)) => return Err(e),
                };
                if let Some(w) = joint_from.filter(|_| fits.3 - fits.4 <= crit) {
                    if let Some((j, m)) = joint(&ext, &prepared, &w, (sigma, profile), o) {
                        if m < fits.4 {
                            fits = (j, None, false, fits.3, m);
                            res.joint_levels = true;
                        }
                    }
                }
                fits
            }
        };
        score(
            &mut res,
            (e, &ext, &prepared),
            &f,
            (base_m2ll, f_m2ll, white_won),
            (&pv, warmed, rewrites_angle),
            (crit, wald_z_crit),
            o,
        )?;
        Ok(Some(Fitted {
            sys: ext,
            fit: f,
            white: white_fit,
            white_won,
        }))
    };
    match run() {
        Ok(x) => (res, x),
        Err(e) => {
            res.error = Some(e.to_string());
            (res, None)
        }
    }
}

/// A fitted candidate's scores: its LR against the current model (inflated
/// as the fit's dispersion says), p-value, BIC change, estimates with sds and
/// robust sds, whether it moved, its Wald z and the naming tests, the
/// common-mode check of a candidate that rewrites angle outputs, and the
/// residual structure its fit leaves.
#[allow(clippy::too_many_arguments)]
fn score(
    res: &mut CandidateResult,
    (e, ext, prepared): (&Effect, &System, &Dataset),
    f: &ModelFit,
    (base_m2ll, f_m2ll, white_won): (f64, f64, bool),
    (pv, warmed, rewrites_angle): (&[f64], bool, bool),
    (crit, wald_z_crit): (f64, Option<f64>),
    o: &DiagnoseOptions,
) -> Result<(), DiagnoseError> {
    let inflate = f.inflation();
    res.lr = (base_m2ll - f_m2ll).max(0.0) / inflate;
    res.white_input_noise = white_won;
    res.p_value = chi2_1_p(res.lr);
    res.delta_bic = -(res.lr - e.params.len() as f64 * (f.n as f64).ln());
    res.estimates = e
        .params
        .iter()
        .filter_map(|p| f.param(p).map(|(v, s)| (p.clone(), v, s * inflate.sqrt())))
        .collect();
    res.robust_sd = e.params.iter().filter_map(|p| f.robust_sd(p)).collect();
    // A warm start is the last round's estimate: a fit that stays there
    // with a gain was fitted (it converged at once).
    res.moved = moved(f, pv, &res.estimates) || (warmed && res.lr > 0.0);
    out_of_range(e, f, prepared)?;
    // `wald_z`: every new param also this many sds from 0, each sd the
    // larger of the model's (inflated) and the cluster-robust one. The
    // LR reads the residuals as independent within a trajectory; with
    // three trajectories the robust sd has two degrees of freedom and
    // can be 10 times too small, so neither alone is the evidence. A
    // candidate whose LR clears its critical value but not this is
    // suggested, not established.
    res.wald_z = wald_z(&res.estimates, &res.robust_sd);
    let wald_ok = wald_z_crit.is_none_or(|z| res.wald_z > z);
    let by_lr = res.lr > crit && res.delta_bic < 0.0;
    res.significant = by_lr && wald_ok;
    res.suggested = by_lr && !wald_ok;
    // A candidate that rewrites angle outputs must also be supported by
    // the simultaneous differences of its members, which cancel any
    // common-mode error (heading drift) it could be absorbing
    // (common_mode.rs). A failed check does not veto; it is reported.
    if rewrites_angle {
        let c = common_mode::check(e, ext, prepared, f, (crit, res.significant), o);
        res.common_mode =
            Some(c.unwrap_or_else(|err| common_mode::CommonModeCheck::failed(e, &err.to_string())));
        if res.common_mode.as_ref().is_some_and(|c| c.vetoed) {
            res.significant = false;
            res.suggested = false;
        }
    }
    res.structure = f
        .residuals
        .structure()
        .iter()
        .map(|t| (t.test.clone(), t.z))
        .collect();
    res.rms = f.rms.clone();
    res.whiteness_z = f
        .residuals
        .tests
        .iter()
        .find(|t| t.test == "whiteness")
        .map_or(0.0, |t| t.z);
    Ok(())
}

/// The candidate `ext` refitted at noise levels estimated with it in the
/// model, from its fit `w` at white input noise (the output levels `sigma`
/// re-estimated too when `profile`), and that fit's `-2 log L` with its own
/// levels' term; `None` when the estimate or the fit fails.
fn joint(
    ext: &System,
    data: &Dataset,
    w: &ModelFit,
    (sigma, profile): (&[f64], bool),
    o: &DiagnoseOptions,
) -> Option<(ModelFit, f64)> {
    let (s, c, _) = estimate_levels(ext, data, w, sigma, profile, o).ok()?;
    let pv: Vec<f64> = w.params.iter().map(|p| p.1).collect();
    let j = fit_model(ext, data, &pv, &w.initial_states, &s, &c, o).ok()?;
    let m = j.m2ll_at(&s);
    Some((j, m))
}

/// Whether the fit `f` moved the new params (`estimates`) from their start
/// (`pv`, in the order of `f.params`) by more than [`MOVED_SD`] of their sd;
/// an sd that is not finite counts a move larger than 1e-12 of the start.
fn moved(f: &ModelFit, pv: &[f64], estimates: &[(String, f64, f64)]) -> bool {
    estimates.iter().any(|(p, v, sd)| {
        let start = f
            .params
            .iter()
            .position(|q| q.0 == *p)
            .and_then(|i| pv.get(i))
            .copied()
            .unwrap_or(0.0);
        let scale = if sd.is_finite() && *sd > 0.0 {
            MOVED_SD * sd
        } else {
            1e-12 * start.abs().max(1.0)
        };
        (v - start).abs() > scale
    })
}

/// The smallest `|estimate| / sd` over a candidate's params, each sd the
/// larger of the model's and the cluster-robust one (a robust sd that is
/// not finite, one trajectory, leaves the model's); 0 when an sd is not
/// finite or not positive (nothing is established).
pub(crate) fn wald_z(estimates: &[(String, f64, f64)], robust: &[f64]) -> f64 {
    estimates
        .iter()
        .enumerate()
        .map(|(i, (_, v, sd))| {
            let r = robust.get(i).copied().filter(|r| r.is_finite());
            let s = r.map_or(*sd, |r| sd.max(r));
            if s.is_finite() && s > 0.0 {
                (v / s).abs()
            } else {
                0.0
            }
        })
        .fold(f64::INFINITY, f64::min)
        .min(f64::MAX)
}

/// The effect's time params: its delay and every param that divides in its
/// dynamics (`x' = (u - x)/T`: a time constant).
fn time_params(e: &Effect) -> Vec<&str> {
    let divides = |p: &str, rhs: &str| {
        let t: String = rhs.chars().filter(|c| !c.is_whitespace()).collect();
        [format!("/{p}"), format!("/({p})")].iter().any(|pat| {
            t.match_indices(pat.as_str()).any(|(i, m)| {
                !t[i + m.len()..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_alphanumeric() || c == '_')
            })
        })
    };
    e.params
        .iter()
        .filter(|p| {
            e.delay.as_deref() == Some(p.as_str()) || e.dynamics.iter().any(|d| divides(p, &d.1))
        })
        .map(String::as_str)
        .collect()
}

/// A time param estimated beyond the longest trajectory is a failed fit
/// (a 129 s lag on 60 s windows, a 10^4 s lag on a 715 s circle from a
/// nominal fit that stopped short), never a finding.
fn out_of_range(e: &Effect, f: &ModelFit, data: &Dataset) -> Result<(), DiagnoseError> {
    let longest = data
        .trajectories
        .iter()
        .map(|t| {
            let tt = t.outputs.t();
            tt.last().zip(tt.first()).map_or(0.0, |(b, a)| b - a)
        })
        .fold(0.0, f64::max);
    for p in time_params(e) {
        if let Some((v, _)) = f.param(p) {
            if v.is_nan() || v.abs() > longest {
                return Err(DiagnoseError::OutOfRange {
                    param: p.to_string(),
                    value: v,
                    longest,
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wald_z_takes_the_larger_sd() {
        let est = vec![("a".to_string(), 0.1, 0.01)];
        // The robust sd 10 times smaller than the model's: the model's counts.
        assert!((wald_z(&est, &[0.001]) - 10.0).abs() < 1e-12);
        // Larger: the robust one counts; not finite: the model's.
        assert!((wald_z(&est, &[0.05]) - 2.0).abs() < 1e-12);
        assert!((wald_z(&est, &[f64::NAN]) - 10.0).abs() < 1e-12);
        let bad = vec![("a".to_string(), 0.1, f64::NAN)];
        assert_eq!(wald_z(&bad, &[]), 0.0);
    }

    #[test]
    fn time_params_are_delays_and_divisors_in_the_dynamics() {
        let lib = obsan_model::EffectLibrary::parse(
            "effect lag\nparam T, k\nstate s = u\ns' = (u - s)/T + k*s\nsubst u = s\n\n\
             effect d\nparam tau\ndelay tau\n\neffect n\nparam Tx, Txy\nstate z = u\nz' = (u - z)*Tx/Txy\nsubst u = z\n",
            "t.eff",
        )
        .unwrap();
        let names: Vec<Vec<&str>> = lib.effects.iter().map(time_params).collect();
        assert_eq!(names, vec![vec!["T"], vec!["tau"], vec!["Txy"]]);
    }
}
