//! The library's diagnosis copied into the binary's view (diagnose.rs), field by field.

use super::diagnose as v;
use super::finite as num;
use crate::diagnose_units::Units;
use obsan_diagnose as lib;

fn pairs(p: &[(String, f64)]) -> Vec<v::NameValue> {
    p.iter().map(|(n, x)| (n.clone(), num(*x))).collect()
}

fn triples(p: &[(String, f64, f64)]) -> Vec<v::NameEstimateSd> {
    p.iter()
        .map(|(n, x, s)| (n.clone(), num(*x), num(*s)))
        .collect()
}

/// The unit of each estimate's param.
fn units(p: &[(String, f64, f64)], u: &Units) -> Vec<Option<String>> {
    p.iter().map(|e| u.json(&e.0)).collect()
}

fn nums(p: &[f64]) -> Vec<v::Num> {
    p.iter().map(|x| num(*x)).collect()
}

fn two(p: [f64; 2]) -> [v::Num; 2] {
    [num(p[0]), num(p[1])]
}

fn fit(f: &lib::ModelFit, u: &Units) -> v::Fit {
    let r = &f.residuals;
    v::Fit {
        model: f.model.clone(),
        params: triples(&f.params),
        params_units: units(&f.params, u),
        params_robust_sd: nums(&f.params_robust_sd),
        initial_states: f.initial_states.iter().map(|s| nums(s)).collect(),
        cost: num(f.cost),
        log_det: num(f.log_det),
        n: f.n,
        n_fitted: f.n_fitted,
        iterations: f.iterations,
        rms: pairs(&f.rms),
        residuals: v::Residuals {
            n: r.n,
            correlation_factor: num(r.correlation_factor),
            chi2: num(r.chi2),
            dof: num(r.dof),
            tests: r
                .tests
                .iter()
                .map(|t| v::StructureTest {
                    test: t.test.clone(),
                    description: t.description.clone(),
                    z: num(t.z),
                    significant: t.significant,
                })
                .collect(),
        },
    }
}

fn common_mode(c: &lib::statistics::CommonModeCheck) -> v::CommonMode {
    v::CommonMode {
        applies: c.applies,
        note: c.note.clone(),
        group: c.group.clone(),
        param: c.param.clone(),
        instants: c.instants,
        full: num(c.full),
        full_robust_sd: num(c.full_robust_sd),
        differences: num(c.differences),
        differences_robust_sd: num(c.differences_robust_sd),
        z: num(c.z),
        limit: num(c.limit),
        vetoed: c.vetoed,
        predicted: c.predicted,
        predicted_z: num(c.predicted_z),
    }
}

fn candidate(c: &lib::CandidateResult, u: &Units) -> v::Candidate {
    v::Candidate {
        effect: c.effect.clone(),
        description: c.description.clone(),
        origin: c.origin.clone(),
        params: c.params.clone(),
        identifiable: c.identifiable,
        rank: c.rank,
        symmetry: pairs(&c.symmetry),
        estimates: triples(&c.estimates),
        units: units(&c.estimates, u),
        robust_sd: nums(&c.robust_sd),
        lr: num(c.lr),
        p_value: num(c.p_value),
        delta_bic: num(c.delta_bic),
        rms: pairs(&c.rms),
        whiteness_z: num(c.whiteness_z),
        significant: c.significant,
        wald_z: num(c.wald_z),
        suggested: c.suggested,
        white_input_noise: c.white_input_noise,
        joint_levels: c.joint_levels,
        structure: pairs(&c.structure),
        moved: c.moved,
        error: c.error.clone(),
        score: c.score.and_then(num),
        screened_out: c.screened_out,
        common_mode: c.common_mode.as_ref().map(common_mode),
    }
}

fn named(n: &lib::Named, u: &Units) -> v::Named {
    v::Named {
        effect: n.effect.clone(),
        description: n.description.clone(),
        origin: n.origin.clone(),
        estimates: triples(&n.estimates),
        units: units(&n.estimates, u),
        robust_sd: nums(&n.robust_sd),
        rms_before: pairs(&n.rms_before),
        rms_after: pairs(&n.rms_after),
        lr: num(n.lr),
        p_value: num(n.p_value),
        rivals: n
            .rivals
            .iter()
            .map(|r| v::Rival {
                effect: r.effect.clone(),
                delta_bic: num(r.delta_bic),
                jointly_identifiable: r.jointly_identifiable,
            })
            .collect(),
        correlated: n
            .correlated
            .iter()
            .map(|c| v::Correlation {
                param: c.param.clone(),
                with: c.with.clone(),
                with_effect: c.with_effect.clone(),
                r: num(c.r),
            })
            .collect(),
        stand_in: n.stand_in,
        curvature: n.curvature.as_ref().map(|c| v::Curvature {
            outputs: c.outputs.clone(),
            n: c.n,
            span: [num(c.span[0]), num(c.span[1])],
            coefficient: num(c.coefficient),
            sd: num(c.sd),
            z: num(c.z),
            correlation_factor: num(c.correlation_factor),
        }),
        lr_final: n.lr_final.and_then(num),
        weak_under_final_levels: n.weak_under_final_levels,
    }
}

fn combination(c: &lib::statistics::Combination) -> v::Combination {
    v::Combination {
        params: c.params.clone(),
        effects: c.effects.clone(),
        values: two(c.values),
        sds: two(c.sds),
        r: num(c.r),
        robust_covariance: [two(c.robust_covariance[0]), two(c.robust_covariance[1])],
        weight: num(c.weight),
        estimate: num(c.estimate),
        sd: num(c.sd),
        robust_sd: num(c.robust_sd),
        wald_z: num(c.wald_z),
        wald_z_alone: two(c.wald_z_alone),
        named: c.named,
        established: c.established,
    }
}

fn competing(c: &lib::Competing, u: &Units) -> v::Competing {
    v::Competing {
        round: c.round,
        effects: c.effects.clone(),
        lr_alone: two(c.lr_alone),
        estimates: triples(&c.estimates),
        units: units(&c.estimates, u),
        robust_sd: nums(&c.robust_sd),
        wald_z: two(c.wald_z),
        wald_z_critical: two(c.wald_z_critical),
        structure: [pairs(&c.structure[0]), pairs(&c.structure[1])],
        established: c.established.clone(),
        named_form: c.named_form.clone(),
    }
}

fn input_check(c: &lib::InputCheck, u: &Units) -> v::InputCheck {
    v::InputCheck {
        effect: c.effect.clone(),
        description: c.description.clone(),
        estimates: triples(&c.estimates),
        units: units(&c.estimates, u),
        z: num(c.z),
        p_value: num(c.p_value),
        significant: c.significant,
        noise: c.noise.clone(),
        dispersion: num(c.dispersion),
        per_trajectory: c
            .per_trajectory
            .iter()
            .map(|t| v::TrajectoryCheck {
                trajectory: t.trajectory.clone(),
                estimates: triples(&t.estimates),
                z: num(t.z),
            })
            .collect(),
        note: c.note.clone(),
    }
}

/// The diagnosis as JSON, each estimate with its unit.
pub fn diagnose(d: &lib::Diagnosis, u: &Units) -> v::Diagnose {
    {
        let candidates = |cs: &[lib::CandidateResult]| cs.iter().map(|c| candidate(c, u)).collect();
        v::Diagnose {
            model: d.model.clone(),
            start: d.start.clone(),
            sigma: pairs(&d.sigma),
            sigma_estimated: d.sigma_estimated,
            input_noise: pairs(&d.input_noise),
            input_noise_source: d.input_noise_source.clone(),
            input_noise_lr: nums(&d.input_noise_lr),
            input_class: d.input_class.clone(),
            nominal: fit(&d.nominal, u),
            nominal_converged: d.nominal_converged,
            refits: d
                .refits
                .iter()
                .map(|r| v::Refit {
                    round: r.round,
                    from: r.from.clone(),
                    m2ll_before: num(r.m2ll_before),
                    m2ll_after: num(r.m2ll_after),
                })
                .collect(),
            rounds: d.rounds.iter().map(|r| candidates(r)).collect(),
            named: d.named.iter().map(|n| named(n, u)).collect(),
            suggested: candidates(&d.suggested),
            combinations: d.combinations.iter().map(combination).collect(),
            competing: d.competing.iter().map(|c| competing(c, u)).collect(),
            input_checks: d.input_checks.iter().map(|c| input_check(c, u)).collect(),
            final_fit: fit(&d.final_fit, u),
            hidden: candidates(&d.hidden),
            extended_sys: d.extended_sys.clone(),
            lr_critical: num(d.lr_critical),
            lr_critical_generated: num(d.lr_critical_generated),
            generated_dropped: d.generated_dropped.clone(),
            screen_threshold: num(d.screen_threshold),
            relevels: d.relevels.iter().map(relevel).collect(),
        }
    }
}

fn relevel(r: &lib::Relevel) -> v::Relevel {
    v::Relevel {
        round: r.round,
        named: r.named.clone(),
        source: r.source.clone(),
        sigma_before: pairs(&r.sigma_before),
        input_noise_before: pairs(&r.input_noise_before),
        sigma_after: pairs(&r.sigma_after),
        input_noise_after: pairs(&r.input_noise_after),
        chi2_z_before: num(r.chi2_z_before),
        chi2_z_after: num(r.chi2_z_after),
        replaced: r.replaced,
        note: r.note,
    }
}
