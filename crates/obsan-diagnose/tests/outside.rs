//! Never confidently wrong when the noise model or the effect's form is not
//! what the data hold. Each test simulates calib data (obsan's simulator,
//! or its output post-processed by a small simulator of the effect here)
//! and checks the diagnosis against the simulation's truth.

use obsan_calib::{simulate, SimOptions};
use obsan_data::Dataset;
use obsan_diagnose::{diagnose, start_values, DiagnoseOptions, Diagnosis};
use obsan_model::{EffectLibrary, System};

#[allow(dead_code)]
mod common;
use common::{read, Rng};

fn run(d: &Dataset) -> Diagnosis {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let start = start_values(&sys, d, &Default::default()).unwrap();
    diagnose(
        &sys,
        Some(&lib),
        d,
        &start,
        &DiagnoseOptions::default(),
        &|_| {},
    )
    .unwrap()
}

/// One line per candidate of every round, for failure messages.
fn summary(r: &Diagnosis) -> String {
    let mut s = format!(
        "noise {} {:?} sigma {:?}\n",
        r.input_noise_source, r.input_noise, r.sigma
    );
    for (k, round) in r.rounds.iter().enumerate() {
        for c in round {
            s += &format!(
                "  round {} {} ({}): lr {:.2} est {:?} white {} joint {} moved {} sig {} sugg {} screened {} err {:?} leaves {:?}\n",
                k + 1,
                c.effect,
                c.origin,
                c.lr,
                c.estimates,
                c.white_input_noise,
                c.joint_levels,
                c.moved,
                c.significant,
                c.suggested,
                c.screened_out,
                c.error,
                c.structure
            );
        }
    }
    s += &format!("final structure {:?}\n", r.final_fit.residuals.structure());
    let named: Vec<String> = r
        .named
        .iter()
        .map(|n| format!("{} {:?}", n.effect, n.estimates))
        .collect();
    s + &format!("named {named:?}\n")
}

/// Simulated calib data with every noise level removed from the metadata.
fn unstated(design: &str, effect: Option<(&str, f64)>, seed: u64) -> Dataset {
    let mut o = SimOptions {
        seed,
        profile: design.parse().expect("a speed profile"),
        ..SimOptions::default()
    };
    if let Some((n, v)) = effect {
        o.effects.set(n, v).unwrap();
    }
    let (mut d, _) = simulate(&o).unwrap();
    d.meta.noise.clear();
    d
}

/// The nominal radius (m) of obsan's simulator's encoder model: the variance
/// of a measured rotation increment `da` is `K^2 |da| / r`
/// (`SimOptions::k_encoder`, `r_nominal`).
const R_NOMINAL: f64 = 0.3;

/// Calib data whose wheels slip in proportion to their own speed: the
/// robot moves with the rotation `w (1 - s |w|)` of each wheel while its
/// encoder counts `w` (the file's `wheel_slip` is proportional to the turn
/// rate instead; the generated `own_speed_slip` has this form).
/// obsan's simulator runs without encoder noise, so its measured speeds are
/// the rotation that moved the robot, `m = w (1 - s |w|)`; here each is
/// replaced by the `w` that gives it (the root of `s w^2 - w + m = 0` near
/// `m`) plus the simulator's encoder noise, drawn from `seed`.
/// `k` is the encoder noise level drawn; the dataset states none (nor does
/// it state the bearing noise).
fn own_speed_slip(design: &str, s: f64, k: f64, seed: u64) -> Dataset {
    let o = SimOptions {
        seed,
        profile: design.parse().expect("a speed profile"),
        k_encoder: 0.0,
        ..SimOptions::default()
    };
    let (mut d, _) = simulate(&o).unwrap();
    let mut rng = Rng(obsan_expr::SplitMix(seed ^ 0x5eed));
    for t in &mut d.trajectories {
        let dt = 1.0 / o.encoder_rate;
        for c in 0..2 {
            for v in t.inputs.values_mut(c).iter_mut().flatten() {
                let m = v.abs();
                let w = (1.0 - (1.0 - 4.0 * s * m).sqrt()) / (2.0 * s);
                let da = w * dt;
                let e = (k * k * da / R_NOMINAL).sqrt() * rng.normal();
                *v = v.signum() * w + e / dt;
            }
        }
    }
    d.meta.noise.clear();
    d
}

/// The truth of failure 2: a second-harmonic bearing distortion of 3.9 deg.
const A2: f64 = 3.9 * std::f64::consts::PI / 180.0;

/// Failure 2: the noise model swallowed the effect. With no noise stated,
/// the automatic input-noise estimate (three trajectories, so estimated)
/// can read a bearing distortion as heading noise; the candidates' fits at
/// those levels then did not leave their start (LR 0), and the text said
/// the model misses something outside the effects file. Each candidate is
/// now also weighed at levels estimated with it in the model
/// (`joint_levels`), and a fit that never moved says so (`moved`). On
/// constant-speed circles (seed 1) the distortion is named with its
/// magnitude within 3 sd of the truth, and nothing else; every file
/// candidate whose fit never moved is marked so (then its LR is 0: a fit
/// that never left its start gains nothing).
#[test]
fn a_distortion_the_estimated_noise_could_absorb_is_named_jointly() {
    let r = run(&unstated("constant", Some(("bearing_distortion", A2)), 1));
    let s = summary(&r);
    let names: Vec<&str> = r.named.iter().map(|n| n.effect.as_str()).collect();
    assert_eq!(names, ["bearing_distortion"], "{s}");
    let (_, a2, sd) = r.named[0].estimates[0].clone();
    assert!((a2 - A2).abs() < 3.0 * sd, "a2 = {a2} ± {sd}\n{s}");
    for c in r.rounds.iter().flatten() {
        if c.identifiable && c.error.is_none() && !c.screened_out && !c.moved {
            // LR below a thousandth: MOVED_SD of an sd changes -2 log L by
            // MOVED_SD^2 = 1e-6, and the white side is the same fit.
            assert!(c.lr < 1e-3, "{} not moved at LR {}\n{s}", c.effect, c.lr);
        }
    }
}

/// The truth of failure 5: each wheel loses the fraction `S |w|` of its
/// rotation (s/rad), a 5 % slip at the simulator's nominal wheel speed.
const S: f64 = 0.3;

/// Failure 5: the wrong form, confidently named. The wheels slip in
/// proportion to their own speed, which the file's turn-rate slip does not
/// express; before the generated family of that form, the coupling
/// `wR_with_abs_wL` (gc -0.047) stayed established beside the file's slip
/// and was named. On varying-speed circles (amplitude 0.5, period 60 s,
/// seed 1, encoders exact, no noise stated) the truth is now inside the
/// generated families: `own_speed_slip`, `u (1 - gs_u |u|)` per wheel.
/// Expected estimates: with gs_wR = gs_wL = S and the simulator's
/// calibration the extended model moves the robot by exactly the rotation
/// the simulator used (each measured w was made so that w (1 - S |w|) = m),
/// and the encoders are exact, so the only noise is the bearing's and the
/// fit's expected estimates are S for both wheels.
///
/// The truth-derived outcome: the family wins the first round, each of its
/// estimates within 3 sd of S (the larger of the model's and the
/// cluster-robust sd); the file's slip, fitted too, competes with it; and
/// what is named is either the family alone, its estimates within 3 sd of
/// S, or nothing, the pair reported as not separated. (On each circle the
/// turn-rate slip takes from each wheel nearly a fixed multiple of that
/// wheel's u |u|, the multiple set by the circle's ratio q, so only the three
/// circles' different q tell the two forms apart: fitted together, each
/// param's sd grows about threefold.) Never a wrong form named.
#[test]
fn a_slip_with_each_wheel_s_own_speed_is_named_by_its_own_form_or_left_competing() {
    let r = run(&own_speed_slip("sine:0.5:60", S, 0.0, 1));
    let s = summary(&r) + &format!("competing {:?}\n", r.competing);
    let near_s = |est: &[(String, f64, f64)], robust: &[f64]| {
        est.len() == 2
            && est.iter().enumerate().all(|(k, (_, v, sd))| {
                let sd = robust.get(k).map_or(*sd, |r| sd.max(*r));
                (v - S).abs() < 3.0 * sd
            })
    };
    let first = r.rounds[0]
        .iter()
        .filter(|c| c.significant)
        .max_by(|a, b| a.lr.total_cmp(&b.lr))
        .unwrap_or_else(|| panic!("nothing significant\n{s}"));
    assert_eq!(first.effect, "own_speed_slip", "{s}");
    assert!(near_s(&first.estimates, &first.robust_sd), "{s}");
    let slip = r.rounds[0]
        .iter()
        .find(|c| c.effect == "wheel_slip")
        .unwrap();
    assert!(!slip.screened_out && slip.moved, "{s}");
    let c = r
        .competing
        .iter()
        .find(|c| c.round == 1)
        .unwrap_or_else(|| panic!("no pair fitted together\n{s}"));
    assert_eq!(c.effects, ["own_speed_slip", "wheel_slip"], "{s}");
    let names: Vec<&str> = r.named.iter().map(|n| n.effect.as_str()).collect();
    match names[..] {
        [] => assert!(c.established.is_none(), "{s}"),
        ["own_speed_slip"] => {
            assert!(near_s(&r.named[0].estimates, &r.named[0].robust_sd), "{s}")
        }
        _ => panic!("named {names:?}\n{s}"),
    }
}
