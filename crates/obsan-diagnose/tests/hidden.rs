//! The discrepancy workflow on simulated data with hidden effects:
//! each identifiable effect is named with its magnitude, effects the data
//! cannot reveal are reported as such, clean data name nothing.
//!
//! Magnitudes: "small" and "large" make the nominal model's bearing residual
//! RMS about 1.3 and 3 times the noise (ordinary least squares; docs/diagnose.md
//! has the scan). Data designs: the paper's constant-speed circles, and
//! speed profiles where an effect needs a varying speed; a design is named
//! by its `--speed-profile` (`constant`, `sine:0.9:60`, ...).

use obsan_calib::{simulate, SimOptions, Truth};
use obsan_diagnose::{
    diagnose, start_values, CandidateResult, DiagnoseOptions, Diagnosis, InputNoise, ORIGIN_FILE,
    ORIGIN_GENERATED,
};
use obsan_model::{EffectLibrary, System};
use rayon::prelude::*;

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

pub fn run(design: &str, effects: &[(&str, f64)], seed: u64) -> (Diagnosis, Truth) {
    run_opts(design, effects, seed, DiagnoseOptions::default())
}

fn run_opts(
    design: &str,
    effects: &[(&str, f64)],
    seed: u64,
    opts: DiagnoseOptions,
) -> (Diagnosis, Truth) {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let mut o = SimOptions {
        seed,
        profile: design.parse().expect("a speed profile"),
        ..SimOptions::default()
    };
    for (n, v) in effects {
        if *n == "dq" {
            o.dq = *v;
        } else {
            o.effects.set(n, *v).unwrap();
        }
    }
    let (data, truth) = simulate(&o).unwrap();
    let start = start_values(&sys, &data, &Default::default()).unwrap();
    let d = diagnose(&sys, Some(&lib), &data, &start, &opts, &|_| {}).unwrap();
    (d, truth)
}

/// The true value of an effect's param, from the simulator's definition.
pub fn true_param(effect: &str, v: f64, t: &Truth) -> f64 {
    match effect {
        "radius_change" => v / t.r_right,
        _ => v,
    }
}

pub fn named(d: &Diagnosis) -> Vec<String> {
    d.named.iter().map(|n| n.effect.clone()).collect()
}

/// (effect, design, small, large)
pub const CASES: [(&str, &str, f64, f64); 5] = [
    ("bearing_scale", "constant", 0.032, 0.117),
    ("bearing_distortion", "constant", 0.032, 0.118),
    ("radius_change", "sine:0.9:60", 0.046, 0.1),
    ("wheel_slip", "sine:0.9:60", 0.4, 1.34),
    ("time_offset", "sine:0.9:60", 1.0, 2.5),
];

const SEEDS: [u64; 3] = [1, 2, 3];

/// Named the hidden effect first, with its magnitude within 3 sd, on every
/// seed, at both magnitudes, and nothing else from the effects file. The
/// generated candidates (on by default) have their own share of alpha per
/// round, so over the six runs one may add one generated effect after the
/// hidden one, never more: measured, wheel_slip 1.34 on seed 3 names
/// beta_cos1* in round 2 (LR 14.4 against 12.61), where the simulator's
/// slip, driven by the true wheel rotations, differs at second order from
/// the effect's, driven by the noisy measured ones.
fn named_with_magnitude(effect: &str) {
    let c = CASES.iter().find(|c| c.0 == effect).unwrap();
    let jobs: Vec<(f64, u64)> = [c.2, c.3]
        .iter()
        .flat_map(|v| SEEDS.iter().map(move |s| (*v, *s)))
        .collect();
    let runs: Vec<(bool, usize, String)> = jobs
        .par_iter()
        .map(|&(v, seed)| {
            let (d, t) = run(c.1, &[(effect, v)], seed);
            let want = true_param(effect, v, &t);
            let first = d.named.first().is_some_and(|n| {
                n.effect == effect
                    && n.estimates
                        .iter()
                        .all(|(_, x, sd)| (x - want).abs() < 3.0 * sd)
            });
            let extras = &d.named[d.named.len().min(1)..];
            let ok = first && extras.iter().all(|n| n.origin == ORIGIN_GENERATED);
            let say = format!(
                "{effect}={v} seed {seed}: named {:?} {:?} (truth {want})",
                named(&d),
                d.named.first().map(|n| &n.estimates)
            );
            (ok, extras.len(), say)
        })
        .collect();
    let bad: Vec<&String> = runs.iter().filter(|r| !r.0).map(|r| &r.2).collect();
    assert!(bad.is_empty(), "{bad:#?}");
    let extra: Vec<&String> = runs.iter().filter(|r| r.1 > 0).map(|r| &r.2).collect();
    assert!(
        extra.len() <= 1 && runs.iter().all(|r| r.1 <= 1),
        "generated extras beyond one in six runs: {extra:#?}"
    );
}

#[test]
fn names_bearing_distortion() {
    named_with_magnitude("bearing_distortion");
}

#[test]
fn names_radius_change() {
    named_with_magnitude("radius_change");
}

#[test]
fn names_wheel_slip_when_the_speed_varies() {
    named_with_magnitude("wheel_slip");
}

#[test]
fn names_time_offset_when_the_speed_varies() {
    named_with_magnitude("time_offset");
}

#[test]
fn names_bearing_scale() {
    // Regression: the magnitude was 18% low (one bearing on the wrong side
    // of the +-pi jump held the fit); the outlier-free restart fixed it.
    named_with_magnitude("bearing_scale");
}

/// A hidden bearing bias's null vector moves psi with it, one for one.
fn assert_psi_absorbs(h: &CandidateResult) {
    let psi = h
        .symmetry
        .iter()
        .find(|t| t.0 == "psi")
        .expect("psi absorbs it");
    assert!((psi.1 - 1.0).abs() < 1e-6, "{:?}", h.symmetry);
}

#[test]
fn what_constant_speed_circles_cannot_reveal() {
    // A camera-encoder time offset changes nothing on constant-speed circles
    // (the derived input rate(w) vanishes); a constant bearing bias is
    // absorbed by psi anywhere. Neither is named; both are reported hidden,
    // the bias with psi in its null vector.
    for (effect, v) in [("time_offset", 0.5), ("bearing_bias", 0.05)] {
        let (d, _) = run("constant", &[(effect, v)], 1);
        assert!(d.named.is_empty(), "{effect}: named {:?}", named(&d));
        let h = d
            .hidden
            .iter()
            .find(|c| c.effect == effect)
            .expect("reported hidden");
        if effect == "bearing_bias" {
            assert_psi_absorbs(h);
        } else {
            assert_eq!(h.symmetry.len(), 1, "{:?}", h.symmetry);
        }
    }
    // With a varying speed the rank test finds the time offset identifiable.
    let (d, _) = run("sine:0.5:60", &[], 1);
    let c = d.rounds[0]
        .iter()
        .find(|c| c.effect == "time_offset")
        .unwrap();
    assert!(c.identifiable);
}

/// With generation and ordinary least squares the first round scores the
/// file's candidates too and fits only those the screen keeps; the ones it
/// leaves are rank-tested alone, so the hidden report is the one every
/// candidate's full route gives: the bias hidden, psi in its null vector,
/// the same file effects as without generation.
#[test]
fn the_screened_first_round_still_reports_what_the_data_cannot_reveal() {
    let ols = |generate| DiagnoseOptions {
        generate,
        input_noise: InputNoise::None,
        ..DiagnoseOptions::default()
    };
    let (with, _) = run_opts("constant", &[("bearing_bias", 0.05)], 1, ols(true));
    let (without, _) = run_opts("constant", &[("bearing_bias", 0.05)], 1, ols(false));
    let file_hidden = |d: &Diagnosis| {
        let mut h: Vec<String> = d
            .hidden
            .iter()
            .filter(|c| c.origin == ORIGIN_FILE)
            .map(|c| c.effect.clone())
            .collect();
        h.sort();
        h
    };
    assert_eq!(file_hidden(&with), file_hidden(&without));
    let h = with
        .hidden
        .iter()
        .find(|c| c.effect == "bearing_bias")
        .expect("reported hidden");
    assert!(!h.identifiable && !h.screened_out && h.rank.is_some());
    assert_psi_absorbs(h);
    // The first round did score the file's candidates and left some unfitted,
    // each with its rank.
    let first = &with.rounds[0];
    assert!(first
        .iter()
        .any(|c| c.origin == ORIGIN_FILE && c.score.is_some()));
    for c in first
        .iter()
        .filter(|c| c.screened_out && c.origin == ORIGIN_FILE)
    {
        assert!(
            c.rank.is_some() && c.identifiable,
            "{}: {:?}",
            c.effect,
            c.rank
        );
    }
}

#[test]
fn clean_data_name_nothing() {
    let seeds: Vec<u64> = (101..121).collect();
    let named_runs: Vec<(u64, Vec<String>)> = seeds
        .par_iter()
        .map(|&s| (s, named(&run("constant", &[], s).0)))
        .filter(|(_, n)| !n.is_empty())
        .collect();
    // At least 95% of 20 runs name nothing.
    assert!(named_runs.len() <= 1, "{named_runs:?}");
}

#[test]
fn two_hidden_effects_are_both_named() {
    let (d, t) = run(
        "constant",
        &[("bearing_distortion", 0.06), ("radius_change", 0.06)],
        7,
    );
    let mut n = named(&d);
    n.sort();
    // On constant-speed circles a radius change and turn-rate slip are
    // confounded (the next round's rank test says so): either may be named,
    // the other then reported as its rival.
    if n[1] == "wheel_slip" {
        let e = d.named.iter().find(|e| e.effect == "wheel_slip").unwrap();
        let rv = e.rivals.iter().find(|r| r.effect == "radius_change");
        assert!(
            rv.is_some_and(|r| r.jointly_identifiable == Some(false)),
            "{e:?}"
        );
        n[1] = "radius_change".into();
    }
    assert_eq!(n, ["bearing_distortion", "radius_change"]);
    // A bearing harmonic and an odometry error act through different
    // regressors: the final fit determines each alone, so no caution.
    assert!(d.correlated_with_earlier(1).is_empty(), "{:?}", d.named);
    for e in d.named.iter().filter(|e| e.effect != "wheel_slip") {
        let (name, x, sd) = &e.estimates[0];
        let want = if name == "kr" { 0.06 / t.r_right } else { 0.06 };
        assert!((x - want).abs() < 3.0 * sd, "{name} {x} ± {sd} vs {want}");
    }
}

#[test]
fn commanded_ratio_error_shows_in_the_inputs() {
    let (d, _) = run("constant", &[("dq", 0.02)], 3);
    let c = &d.input_checks[0];
    assert!(c.significant);
    let (_, x, sd) = c.estimates[0];
    assert!((x - 0.02).abs() < 3.0 * sd, "{x} ± {sd}");
    // The bearings do not see it: the fit uses the measured wheel speeds;
    // it is named as the input relation it is, and only that.
    assert_eq!(named(&d), ["commanded_ratio"]);
    assert_eq!(d.named[0].origin, obsan_diagnose::ORIGIN_RELATION);
}

/// Regression: at a large bearing scale error the q = -1 circle's bearings
/// wrap at +-pi where the model's do not, DET read a period twice the true
/// one there (LS RMS 78 deg), the nominal fit stayed at 31 sigma and
/// wheel_slip was named. The calibration now rereads that circle's period
/// from the other two (eq. 18).
#[test]
fn names_a_large_bearing_scale_when_one_circles_period_is_misread() {
    let (d, t) = run("constant", &[("bearing_scale", 0.117)], 4);
    assert_eq!(named(&d), ["bearing_scale"]);
    let (_, x, sd) = d.named[0].estimates[0].clone();
    let want = true_param("bearing_scale", 0.117, &t);
    assert!((x - want).abs() < 3.0 * sd, "{x} ± {sd} vs {want}");
}

/// On the paper's constant-speed circles wheel slip and a radius change are
/// each identifiable but not both (rank test): whichever is named, the other
/// is reported with it as a rival the data cannot separate from it.
#[test]
fn confounded_effects_are_named_with_their_rival() {
    let (d, _) = run("constant", &[("radius_change", 0.046)], 1);
    for c in &d.rounds[0] {
        eprintln!(
            "DBG {} lr {} dbic {} sig {}",
            c.effect, c.lr, c.delta_bic, c.significant
        );
    }
    assert_eq!(d.named.len(), 1, "{:?}", named(&d));
    let n = &d.named[0];
    let other = if n.effect == "radius_change" {
        "wheel_slip"
    } else {
        "radius_change"
    };
    assert!(n.effect == "radius_change" || n.effect == "wheel_slip");
    let rv = n
        .rivals
        .iter()
        .find(|r| r.effect == other)
        .expect("the other effect as a rival");
    assert_eq!(rv.jointly_identifiable, Some(false));
}
