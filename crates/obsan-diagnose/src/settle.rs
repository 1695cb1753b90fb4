//! What was named, settled against the final fit (step 5 of the workflow):
//! rivals the next round found confounded, refined estimates, correlations,
//! a generated effect's words, whether an effect rewriting outputs is a
//! stand-in (`curvature.rs`); and the extended model's text (step 6),
//! input relations included.

use crate::candidate::Fitted;
use crate::correlation::{correlated, CORRELATION_CAUTION};
use crate::curvature::{curvature, Z_STAND_IN};
use crate::generate::{Generation, ORIGIN_GENERATED};
use crate::model_fit::ModelFit;
use crate::relation::{with_relation, InputCheck};
use crate::report::{CandidateResult, Named, Rival, ORIGIN_RELATION, RIVAL_BIC};
use crate::screen::Outcome;
use obsan_model::{Effect, System};

/// What was named, settled against the final fit: rivals the next round
/// found confounded, whether each rival is jointly identifiable, estimates
/// refined by later rounds, correlations, and a generated effect's words.
pub(crate) fn settle(
    named: &mut [Named],
    rounds: &[Vec<CandidateResult>],
    current: &ModelFit,
    gen: &Generation,
) {
    confounded_rivals(named, rounds);
    // A rival's rank test in the round after its named effect says whether
    // the two are confounded on these data.
    for (i, n) in named.iter_mut().enumerate() {
        for rv in &mut n.rivals {
            rv.jointly_identifiable = rounds
                .get(i + 1)
                .and_then(|r| r.iter().find(|c| c.effect == rv.effect))
                .filter(|c| c.error.is_none() && !c.screened_out)
                .map(|c| c.identifiable);
        }
    }
    // Estimates of earlier named effects are refined by later rounds.
    for n in named.iter_mut() {
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
    correlations(named, current);
    // A generated effect's words follow the sign of its refined estimate.
    for n in named.iter_mut() {
        if let Some(g) = gen.candidates.iter().find(|g| g.effect.name == n.effect) {
            n.description = g.words(n.estimates.first().map_or(0.0, |x| x.1));
        }
    }
}

/// Each named effect that rewrites outputs gets its curvature test, and is
/// marked a stand-in when the test fires. `sigma` are the output noise
/// levels of the final fit, in the order of its outputs (`fit.rms`).
pub(crate) fn mark_stand_ins(
    named: &mut [Named],
    effects: &[&Effect],
    fit: &ModelFit,
    sigma: &[f64],
) {
    let level = |o: &str| {
        let i = fit.rms.iter().position(|x| x.0 == o)?;
        sigma.get(i).copied().filter(|s| s.is_finite() && *s > 0.0)
    };
    for n in named.iter_mut() {
        let Some(e) = effects.iter().find(|e| e.name == n.effect) else {
            continue;
        };
        let rewritten: Vec<String> = e.outputs.iter().map(|o| o.0.clone()).collect();
        if rewritten.is_empty() {
            continue;
        }
        n.curvature = curvature(&fit.series, (fit.n_fitted, fit.n), &rewritten, &level);
        n.stand_in = n.curvature.as_ref().is_some_and(|c| c.z.abs() > Z_STAND_IN);
    }
}

/// A significant candidate that the next round's rank test finds
/// confounded with the named effect is a rival whatever its BIC: on these
/// data the two differ only outside what the data identify.
fn confounded_rivals(named: &mut [Named], rounds: &[Vec<CandidateResult>]) {
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
            let confounded = next.iter().any(|x| {
                x.effect == c.effect && x.error.is_none() && !x.screened_out && !x.identifiable
            });
            if confounded && !n.rivals.iter().any(|r| r.effect == c.effect) {
                n.rivals.push(Rival {
                    effect: c.effect.clone(),
                    delta_bic: (c.delta_bic - best.unwrap_or(c.delta_bic)).max(0.0),
                    jointly_identifiable: None,
                });
            }
        }
    }
}

/// Correlations in the final fit: two named effects whose regressors are
/// nearly proportional on these data are fixed only in combination.
fn correlations(named: &mut [Named], current: &ModelFit) {
    let names: Vec<String> = current.params.iter().map(|p| p.0.clone()).collect();
    let owners: Vec<(String, String)> = named
        .iter()
        .flat_map(|n| n.estimates.iter().map(|e| (e.0.clone(), n.effect.clone())))
        .collect();
    let owner = |p: &str| owners.iter().find(|o| o.0 == p).map(|o| o.1.clone());
    for n in named.iter_mut() {
        let of: Vec<String> = n.estimates.iter().map(|e| e.0.clone()).collect();
        n.correlated = correlated(
            &names,
            &current.covariance,
            &of,
            &owner,
            CORRELATION_CAUTION,
        );
    }
}

/// The extended model as .sys text, each generated effect announced in a
/// comment with its estimates.
pub(crate) fn extended_model(named: &[Named], current_sys: &System) -> String {
    let mut extended_sys = String::new();
    for n in named.iter().filter(|n| n.origin == ORIGIN_GENERATED) {
        let est: Vec<String> = n
            .estimates
            .iter()
            .map(|(p, v, sd)| format!("{p} = {v:e} ± {sd:.1e}"))
            .collect();
        extended_sys.push_str(&format!(
            "# generated from the model's structure (not in the effects file): {}: {}, {}\n",
            n.effect,
            n.description,
            est.join(", ")
        ));
    }
    extended_sys.push_str(&current_sys.to_sys_text());
    extended_sys
}

/// A relation the measured inputs contradict is a missing effect too: the
/// data were not taken under the declared restriction. Named after the
/// model's effects (it changes no fit: the fit uses the measured inputs),
/// and written into the extended model's restriction.
pub(crate) fn name_relations(
    named: &mut Vec<Named>,
    extended_sys: &mut String,
    checks: &[InputCheck],
    effects: &[&Effect],
) {
    for (c, e) in checks
        .iter()
        .zip(effects.iter().filter(|e| e.is_input_side()))
    {
        if !c.significant {
            continue;
        }
        named.push(Named {
            effect: c.effect.clone(),
            description: c.description.clone(),
            origin: ORIGIN_RELATION.into(),
            estimates: c.estimates.clone(),
            robust_sd: vec![f64::NAN; c.estimates.len()],
            rms_before: vec![],
            rms_after: vec![],
            lr: c.z * c.z,
            p_value: c.p_value,
            ..Named::default()
        });
        *extended_sys = with_relation(extended_sys, e, &c.estimates);
    }
}

/// The other significant candidates of a round whose BIC is within
/// [`RIVAL_BIC`] of the best one's.
pub(crate) fn rivals(results: &[Outcome<Fitted>], best: &CandidateResult) -> Vec<Rival> {
    results
        .iter()
        .filter(|r| {
            r.0.significant
                && r.0.effect != best.effect
                && r.0.delta_bic - best.delta_bic < RIVAL_BIC
        })
        .map(|r| Rival {
            effect: r.0.effect.clone(),
            delta_bic: (r.0.delta_bic - best.delta_bic).max(0.0),
            jointly_identifiable: None,
        })
        .collect()
}
