//! Issue 37: never confidently wrong. Each test simulates calib data with a
//! known hidden effect (obsan's simulator, the paper's three constant-speed
//! circles, seed 1) and checks the diagnosis against the simulation's truth.

use obsan_calib::{simulate, Effects, SimOptions};
use obsan_diagnose::{diagnose, start_values, DiagnoseOptions, Diagnosis};
use obsan_model::{EffectLibrary, System};
use std::collections::BTreeMap;

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// The truth of every test: a bearing scale of 0.04.
const KB: f64 = 0.04;

/// Diagnose circles with a bearing scale of [`KB`] from the data's own start
/// with `init` overriding it by name (as `--init` does).
fn run(init: &[(&str, f64)]) -> Diagnosis {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let o = SimOptions {
        seed: 1,
        effects: Effects {
            bearing_scale: KB,
            ..Effects::default()
        },
        ..SimOptions::default()
    };
    let (d, _) = simulate(&o).unwrap();
    let given: BTreeMap<String, f64> = init.iter().map(|(n, v)| (n.to_string(), *v)).collect();
    let start = start_values(&sys, &d, &given).unwrap();
    diagnose(
        &sys,
        Some(&lib),
        &d,
        &start,
        &DiagnoseOptions::default(),
        &|_| {},
    )
    .unwrap()
}

/// The named effects' names.
fn named(r: &Diagnosis) -> Vec<&str> {
    r.named.iter().map(|n| n.effect.as_str()).collect()
}

/// Failure 0. From eta = 0.526, delta = 0.9 (truth 0.495, 1.016) the
/// nominal fit stopped at 39 sigma, and bearing_distortion (a2 = -0.002 ±
/// 0.003), radius_change, bearing_scale and bearing_bias (b = 0.003 ± 0.58)
/// were all named, a 10^4 s wheel lag beside them at LR 158,000. The
/// bearing_distortion candidate's point with a2 = 0 shows the nominal fit
/// had not converged: it is refitted there, said, and then only the truth
/// is named, within 3 sd of 0.04.
#[test]
fn a_nominal_fit_that_stopped_short_is_refitted_before_any_comparison() {
    let r = run(&[("eta", 0.526), ("delta", 0.9)]);
    assert!(!r.nominal_converged, "the refit is reported");
    assert!(r
        .refits
        .iter()
        .any(|f| f.round == 1 && f.m2ll_after < f.m2ll_before - 1.0));
    assert_eq!(named(&r), ["bearing_scale"], "{:#?}", r.named);
    let (_, kb, sd) = r.named[0].estimates[0].clone();
    assert!((kb - KB).abs() < 3.0 * sd, "kb = {kb} ± {sd}");
    // No time param is ever an estimate beyond the longest trajectory
    // (715 s): such a fit fails, it is not scored.
    for c in r.rounds.iter().flatten() {
        if c.effect.ends_with("_lag") || c.effect.ends_with("_delay") {
            assert!(
                c.error.is_some() || c.estimates.iter().all(|e| e.1.abs() < 715.0),
                "{c:#?}"
            );
        }
    }
}

/// Failure 1 and failure 4. From eta = 100 the q = 0.9 circle diverges at
/// t = 2.5 s, and diagnose stopped there (exit 2). The start is replaced
/// (and the start text says so), and the diagnosis is made. The fits on
/// the trajectories' first parts diverge too, and the fit without q0.9
/// alone ended in another basin (bearing_scale 0.025 ± 0.004 and a
/// generated beta_cos1 named, level z 22); the data's own start (without
/// the value given by name) is a route too, and from it the truth is named
/// alone, within 3 sd of 0.04. Every named effect stands at least the
/// critical value of sds from 0 with the larger of the model's and the
/// cluster-robust sd (failure 4: with three trajectories the robust sd
/// alone can be 10 times too small), and anything above its LR critical
/// value without that is listed apart.
#[test]
fn a_diverging_start_is_replaced_and_weak_evidence_is_only_suggested() {
    let r = run(&[("eta", 100.0)]);
    assert!(r.start.contains("replaced by"), "{}", r.start);
    assert_eq!(named(&r), ["bearing_scale"], "{:#?}", r.named);
    let (_, kb, sd) = r.named[0].estimates[0].clone();
    assert!((kb - KB).abs() < 3.0 * sd, "kb = {kb} ± {sd}");
    let crit_file = r.lr_critical.sqrt();
    let crit_gen = r.lr_critical_generated.sqrt();
    for (k, n) in r.named.iter().enumerate() {
        let c = r
            .rounds
            .get(k)
            .and_then(|round| round.iter().find(|c| c.effect == n.effect))
            .unwrap();
        let crit = if c.origin == obsan_diagnose::ORIGIN_GENERATED {
            crit_gen
        } else {
            crit_file
        };
        // The Wald z recomputed here from the round's printed numbers.
        let z = c
            .estimates
            .iter()
            .zip(&c.robust_sd)
            .map(|((_, v, sd), rs)| v.abs() / if rs.is_finite() { sd.max(*rs) } else { *sd })
            .fold(f64::INFINITY, f64::min);
        assert!(z > crit, "{} named at Wald z {z} < {crit}", n.effect);
    }
    for c in &r.suggested {
        assert!(!c.significant && c.wald_z <= crit_gen.max(crit_file));
        assert!(!named(&r).contains(&c.effect.as_str()));
    }
}

/// Failure 3. Residuals far below the stated noise are a finding, never
/// "consistent with noise". Clean circles (no effect, no encoder noise, so
/// the residual is the bearing noise alone) with the bearing noise stated
/// twice its true value: the whitened residuals have variance 1/4, so the
/// chi-square is about dof/4 and its z, (dof/4 - dof) / sqrt(2 dof) =
/// -0.53 sqrt(dof), is far below -Z_STRUCTURE for the circles' thousands of
/// bearings. Nothing may be named on clean data, and the final fit must not
/// be called consistent with noise.
#[test]
fn residuals_far_below_the_stated_noise_are_a_finding() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let o = SimOptions {
        seed: 1,
        k_encoder: 0.0,
        ..SimOptions::default()
    };
    let (mut d, _) = simulate(&o).unwrap();
    d.meta.noise.remove("encoder_k");
    let stated = 2.0 * o.sigma_beta;
    d.meta.noise.insert("beta".into(), stated);
    let start = start_values(&sys, &d, &BTreeMap::new()).unwrap();
    let r = diagnose(
        &sys,
        Some(&lib),
        &d,
        &start,
        &DiagnoseOptions::default(),
        &|_| {},
    )
    .unwrap();
    assert!(r.named.is_empty(), "{:?}", named(&r));
    assert!(!r.sigma_estimated);
    let st = r.final_fit.residuals.structure();
    let level = st
        .iter()
        .find(|s| s.test == "chi2")
        .unwrap_or_else(|| panic!("{st:?}"));
    let n = r.final_fit.n as f64;
    let dof = n - r.final_fit.n_fitted as f64;
    let want = -0.75 * dof / (2.0 * dof).sqrt();
    // The chi-square of dof unit-variance residuals scaled by 1/4 has sd
    // sqrt(2 dof)/4 around dof/4: in z units 1/4, so a 2 z-unit window is 8
    // of its sds.
    assert!((level.z - want).abs() < 2.0, "z {} against {want}", level.z);
    assert!(level.z < -obsan_diagnose::Z_STRUCTURE);
    assert!(level.description.contains("far below the stated noise"));
    assert!(!r.final_fit.residuals.consistent_with_noise());
}
