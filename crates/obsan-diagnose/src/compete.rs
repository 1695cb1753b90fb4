//! A generated winner against a file candidate (failure 5 of the
//! never-confidently-wrong rules): when a form generated from the model's
//! structure wins a round and a file candidate competes with it, the two
//! are fitted together as one extended model. One is named only if it alone
//! stays established with the other present, by the test that names any
//! effect (its Wald z, each sd the larger of the model's and the
//! cluster-robust one, above the square root of its LR critical value).
//! Otherwise neither is named: the data do not separate them, and which
//! residual structure each one's own fit leaves is reported.

use crate::candidate::{wald_z, Fitted};
use crate::combine::{pair, At};
use crate::correlation::{correlation, Combination, CORRELATION_CAUTION};
use crate::error::DiagnoseError;
use crate::generate::ORIGIN_GENERATED;
use crate::model_fit::{fit_model, prepare, ModelFit};
use crate::options::DiagnoseOptions;
use crate::report::{CandidateResult, Competing, Named, ORIGIN_RELATION};
use crate::screen::Outcome;
use crate::start::extended_start;
use obsan_data::Dataset;
use obsan_model::{Effect, System};

/// Whether a file candidate competes with the generated winner `gen`:
/// fitted, and either above its LR critical value too (significant or
/// suggested) or removing some of the same residual structure of the
/// current fit (`current`: the tests it fails) as the winner.
pub(crate) fn competes(
    gen: &CandidateResult,
    file: &CandidateResult,
    current: &[(String, f64)],
) -> bool {
    if file.error.is_some() || file.screened_out || file.estimates.is_empty() {
        return false;
    }
    let removes = |c: &CandidateResult, t: &str| !c.structure.iter().any(|s| s.0 == t);
    let overlap = current
        .iter()
        .any(|(t, _)| removes(gen, t) && removes(file, t));
    file.significant || file.suggested || overlap
}

/// The file candidate (best by LR) that competes with a generated winner
/// `best` of `results`, with its fit; `None` when the winner is the
/// file's. `current`: the fit the round's candidates extend.
pub(crate) fn file_rival(
    best: &CandidateResult,
    results: &[Outcome<Fitted>],
    current: &ModelFit,
) -> Option<(CandidateResult, Fitted)> {
    if best.origin != ORIGIN_GENERATED {
        return None;
    }
    let cur: Vec<(String, f64)> = (current.residuals.structure().iter())
        .map(|t| (t.test.clone(), t.z))
        .collect();
    results
        .iter()
        .filter(|r| r.0.origin != ORIGIN_GENERATED && competes(best, &r.0, &cur))
        .filter_map(|r| Some((r.0.clone(), r.1.clone()?)))
        .max_by(|a, b| a.0.lr.total_cmp(&b.0.lr))
}

/// The pair fitted together from the current fit `(sys, fit)` and each
/// one's own estimates, under the levels `(sigma, noise)`; `crit` is each
/// one's LR critical value. Errors: the joint fit failed (the caller then
/// keeps the round's winner as before).
#[allow(clippy::too_many_arguments)]
pub(crate) fn fit_together(
    (sys, fit, data): (&System, &ModelFit, &Dataset),
    (gen, eg): (&CandidateResult, &Effect),
    (file, ef): (&CandidateResult, &Effect),
    (sigma, noise): (&[f64], &[(String, f64)]),
    crit: [f64; 2],
    round: usize,
    o: &DiagnoseOptions,
) -> Result<Competing, DiagnoseError> {
    let ext = sys
        .extend(&[eg, ef], ORIGIN_GENERATED)
        .map_err(|e| DiagnoseError::Extend(Box::new(e)))?;
    let prepared = prepare(&ext, data)?;
    let base: Vec<f64> = fit.params.iter().map(|p| p.1).collect();
    let (mut pv, sv) = extended_start(&ext, &base, &fit.initial_states, &prepared)?;
    let names: Vec<String> = ext
        .decls_of(obsan_model::Kind::Param)
        .map(|d| d.name.clone())
        .collect();
    for (p, v, _) in gen.estimates.iter().chain(&file.estimates) {
        if let Some(slot) = names
            .iter()
            .position(|n| n == p)
            .and_then(|k| pv.get_mut(k))
            .filter(|_| v.is_finite())
        {
            *slot = *v;
        }
    }
    let f = fit_model(&ext, &prepared, &pv, &sv, sigma, noise, o)?;
    let inflate = f.inflation();
    let of = |e: &Effect| -> (Vec<(String, f64, f64)>, Vec<f64>) {
        let est = e
            .params
            .iter()
            .filter_map(|p| f.param(p).map(|(v, s)| (p.clone(), v, s * inflate.sqrt())))
            .collect();
        let rob = e.params.iter().filter_map(|p| f.robust_sd(p)).collect();
        (est, rob)
    };
    let ((eg_est, eg_rob), (ef_est, ef_rob)) = (of(eg), of(ef));
    let z = [wald_z(&eg_est, &eg_rob), wald_z(&ef_est, &ef_rob)];
    let zc = [crit[0].sqrt(), crit[1].sqrt()];
    let established = match (z[0] > zc[0], z[1] > zc[1]) {
        (true, false) => Some(gen.effect.clone()),
        (false, true) => Some(file.effect.clone()),
        // Both stay: the winner is named as before (the other competes
        // again in the next round, against the model with the winner).
        (true, true) => Some(gen.effect.clone()),
        (false, false) => None,
    };
    // Neither established beside the other while each alone is
    // significant: each removes what the other would (else it would stay
    // established), one effect in two forms (MRCLAM robot 1's lag as
    // omega_lag* and actuator_lag, joint z 2.3 and 0.4). Stopping the
    // search there leaves that effect, established whichever form carries
    // it, out of the model, and every later effect unweighed. The stronger
    // form, its joint Wald z against its line, is named and the rounds go
    // on; the pair is reported as not separated.
    let named_form = stronger_form(established.is_some(), [gen, file], z, zc);
    Ok(Competing {
        round,
        effects: [gen.effect.clone(), file.effect.clone()],
        lr_alone: [gen.lr, file.lr],
        estimates: eg_est.into_iter().chain(ef_est).collect(),
        robust_sd: eg_rob.into_iter().chain(ef_rob).collect(),
        wald_z: z,
        wald_z_critical: zc,
        structure: [gen.structure.clone(), file.structure.clone()],
        established,
        named_form,
    })
}

/// Of a pair neither of which is `established` beside the other, the one
/// named as the stronger form of one effect: both significant alone, the
/// larger Wald z over its line (the winner, first, on a tie); `None`
/// otherwise.
fn stronger_form(
    established: bool,
    pair: [&CandidateResult; 2],
    z: [f64; 2],
    zc: [f64; 2],
) -> Option<String> {
    if established || !pair.iter().all(|c| c.significant) {
        return None;
    }
    let k = usize::from(z[1] / zc[1] > z[0] / zc[0]);
    Some(pair[k].effect.clone())
}

/// A later round's winner `res` against the effects already named: the
/// same rule as a generated winner against a file candidate, where the
/// rival was named in an earlier round. The winner's fit (`at.fit` of
/// `at.sys`) already holds both; where one of its params correlates with a
/// named effect's at [`CORRELATION_CAUTION`] or more, the pair's
/// combination is formed, and the winner may be named only if both stay
/// established there, each by its Wald z alone (each sd the larger of the
/// model's, inflated, and the cluster-robust one) above the square root of
/// its own LR critical value. Otherwise the data fix only the combination
/// (a bearing scale and the second harmonic within a narrow field of
/// view, `(1 + k) b + a sin 2b ~ (1 + k + 2a) b`): the returned pair, the
/// named effect first, is reported and the winner is not named. `None`:
/// no such correlation, or the pair separated.
pub(crate) fn against_named(
    at: &At,
    res: &CandidateResult,
    named: &[Named],
    crit: &dyn Fn(&str) -> f64,
) -> Result<Option<Combination>, DiagnoseError> {
    let index = |p: &str| at.fit.params.iter().position(|x| x.0 == p);
    let mine: Vec<usize> = res.estimates.iter().filter_map(|e| index(&e.0)).collect();
    let mut best: Option<(f64, usize, usize, &Named)> = None;
    for n in named.iter().filter(|n| n.origin != ORIGIN_RELATION) {
        for i in n.estimates.iter().filter_map(|e| index(&e.0)) {
            for &j in &mine {
                let Some(r) = correlation(&at.fit.covariance, i, j) else {
                    continue;
                };
                if r.abs() >= CORRELATION_CAUTION && best.is_none_or(|b| r.abs() > b.0) {
                    best = Some((r.abs(), i, j, n));
                }
            }
        }
    }
    let Some((_, i, j, n)) = best else {
        return Ok(None);
    };
    let prepared = prepare(at.sys, at.data)?;
    let (cn, cw) = (crit(&n.origin), crit(&res.origin));
    let effects = [n.effect.clone(), res.effect.clone()];
    let Some(mut c) = pair(at, (at.sys, &prepared, at.fit), (i, j), effects, cn.max(cw)) else {
        return Ok(None);
    };
    if c.wald_z_alone[0] > cn.sqrt() && c.wald_z_alone[1] > cw.sqrt() {
        return Ok(None);
    }
    c.named = false;
    Ok(Some(c))
}

/// The text of a pair the data do not separate, for the verdict and the
/// details.
pub fn competing_text(c: &Competing) -> String {
    let st = |s: &[(String, f64)]| {
        if s.is_empty() {
            "no residual structure left".to_string()
        } else {
            let v: Vec<String> = s.iter().map(|(t, z)| format!("{t} z {z:.1}")).collect();
            format!("leaves {}", v.join(", "))
        }
    };
    format!(
        "{} (LR {:.1} alone; {}) and {} (LR {:.1} alone; {}): fitted together, Wald z {:.1} and \
         {:.1} (each must clear {:.2} and {:.2})",
        c.effects[0],
        c.lr_alone[0],
        st(&c.structure[0]),
        c.effects[1],
        c.lr_alone[1],
        st(&c.structure[1]),
        c.wald_z[0],
        c.wald_z[1],
        c.wald_z_critical[0],
        c.wald_z_critical[1],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cand(sig: bool, sugg: bool, structure: &[&str]) -> CandidateResult {
        let e = Effect {
            name: "e".into(),
            description: String::new(),
            params: vec!["p".into()],
            states: vec![],
            starts: vec![],
            consts: vec![],
            inputs: vec![],
            substs: vec![],
            outputs: vec![],
            dynamics: vec![],
            compares: vec![],
            delay: None,
            line: 1,
        };
        let mut c = CandidateResult::untried(&e, "effects");
        c.significant = sig;
        c.suggested = sugg;
        c.estimates = vec![("p".into(), 1.0, 0.1)];
        c.structure = structure.iter().map(|s| (s.to_string(), 5.0)).collect();
        c
    }

    /// MRCLAM robot 1's round 2 (omega_lag* z 2.27 of 3.62, actuator_lag
    /// 0.43 of 3.42, both significant alone): the generated form is named;
    /// the file's when its ratio is the larger; none when one was not
    /// significant alone or one is established.
    #[test]
    fn the_stronger_of_two_forms_is_named_only_when_both_are_significant_alone() {
        let (mut g, mut f) = (cand(true, false, &[]), cand(true, false, &[]));
        (g.effect, f.effect) = ("omega_lag".into(), "actuator_lag".into());
        let zc = [3.62, 3.42];
        let named =
            |g: &CandidateResult, f: &CandidateResult, z, est| stronger_form(est, [g, f], z, zc);
        assert_eq!(
            named(&g, &f, [2.27, 0.43], false).as_deref(),
            Some("omega_lag")
        );
        assert_eq!(
            named(&g, &f, [0.43, 2.27], false).as_deref(),
            Some("actuator_lag")
        );
        assert_eq!(named(&g, &f, [2.27, 0.43], true), None);
        f.significant = false;
        assert_eq!(named(&g, &f, [2.27, 0.43], false), None);
    }

    #[test]
    fn a_file_candidate_competes_when_above_its_line_or_removing_the_same_structure() {
        let gen = cand(true, false, &[]);
        let cur = vec![("trend".to_string(), 6.0)];
        // Below its line, and leaving the trend the winner removed: no.
        assert!(!competes(&gen, &cand(false, false, &["trend"]), &cur));
        // Below its line, but removing the same trend: competes.
        assert!(competes(&gen, &cand(false, false, &[]), &cur));
        // Above its line (significant or only suggested): competes.
        assert!(competes(&gen, &cand(true, false, &["trend"]), &cur));
        assert!(competes(&gen, &cand(false, true, &["trend"]), &cur));
        // Not fitted: never.
        let mut screened = cand(true, false, &[]);
        screened.screened_out = true;
        assert!(!competes(&gen, &screened, &cur));
    }
}
