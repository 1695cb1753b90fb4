//! Effects nobody wrote, wider: a differential-drive robot whose right
//! wheel wears during the session, is out of round, whose range sensor
//! bends with range, or whose bearing bias follows its heading. No effects
//! file: only the candidates generated from the model's structure compete.
//! Each test asks for the family that made the data, with an estimate
//! within 3 sd of the simulation's truth; on clean data none of these
//! families may be named.
//!
//! The data are made here by the robot's exact arcs over short substeps
//! (the wheel speeds the effects change at each substep's midpoint), not by
//! obsan's predictor, so the test does not check the code against itself.
//! The design (speeds, landmarks, noise, magnitudes) was chosen before the
//! tests were first run and not changed after; the noisy-encoder cases
//! were added after a drift was named on clean calib circles, whose
//! encoder noise the workflow had weighed as white (docs/diagnose.md).

use obsan_data::{Dataset, DatasetMeta, Series, Trajectory};
use obsan_diagnose::{diagnose, DiagnoseOptions, Diagnosis, Named, Start};
use obsan_expr::SplitMix;
use obsan_model::System;
use std::collections::BTreeMap;
use std::f64::consts::TAU;

/// Wheel radius 0.1 m, wheel base 0.4 m: `v = 0.05 (wR + wL)`, `omega =
/// 0.25 (wR - wL)`; four landmarks seen by range and bearing.
const MODEL: &str = "system dd
state x, y, th
input wR, wL
const lx1, ly1, lx2, ly2, lx3, ly3, lx4, ly4
x' = 0.05*(wR + wL)*cos(th)
y' = 0.05*(wR + wL)*sin(th)
th' = 0.25*(wR - wL)
output r1 = sqrt((lx1 - x)^2 + (ly1 - y)^2)
output r2 = sqrt((lx2 - x)^2 + (ly2 - y)^2)
output r3 = sqrt((lx3 - x)^2 + (ly3 - y)^2)
output r4 = sqrt((lx4 - x)^2 + (ly4 - y)^2)
output b1 = atan2(ly1 - y, lx1 - x) - th
output b2 = atan2(ly2 - y, lx2 - x) - th
output b3 = atan2(ly3 - y, lx3 - x) - th
output b4 = atan2(ly4 - y, lx4 - x) - th
";
const R: f64 = 0.1;
const B: f64 = 0.4;
const MARKS: [(f64, f64); 4] = [(3.0, 3.0), (-3.0, 3.0), (-3.0, -3.0), (3.0, -3.0)];
const SIGMA_RANGE: f64 = 0.03;
const SIGMA_BEARING: f64 = 0.01;
/// Input rows at 50 Hz, each integrated in `SUB` exact arcs.
const DT: f64 = 0.02;
const SUB: usize = 4;
/// Four windows of 60 s, 10 s apart: one session of 270 s.
const WINDOWS: usize = 4;
const ROWS: usize = 3000;
const GAP: f64 = 70.0;

struct Rng(SplitMix);
impl Rng {
    fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    /// A standard normal deviate by the library's Box–Muller (its first
    /// output only, so the data stay those of the seeds).
    fn normal(&mut self) -> f64 {
        let (a, b) = (self.uniform().max(1e-300), self.uniform());
        obsan_fit::box_muller(a, b).0
    }
}

/// What the simulated robot and sensors do beside the model.
#[derive(Clone, Copy, Default)]
struct Truth {
    /// The right wheel's radius is `R (1 + wear t)`, t the session time (s).
    wear: f64,
    /// The right wheel acts at `wR (1 + wobble cos(angle + phase))`, angle
    /// the integral of the measured wR, phase random per window.
    wobble: f64,
    /// Every range reads `r + quad r^2`.
    quad: f64,
    /// Every bearing reads `b + cos_th cos(th) + sin_th sin(th)`.
    cos_th: f64,
    sin_th: f64,
    /// The measured wheel speeds are the true ones plus white noise of
    /// this sd per row (rad/s): the integrated states then random-walk.
    encoder: f64,
}

/// The data and, per window, the robot's initial pose (x, y, th).
fn simulate(truth: Truth, seed: u64) -> (Dataset, Vec<Vec<f64>>) {
    let mut rng = Rng(SplitMix(seed));
    let mut meta = BTreeMap::new();
    for (i, (lx, ly)) in MARKS.iter().enumerate() {
        meta.insert(format!("lx{}", i + 1), *lx);
        meta.insert(format!("ly{}", i + 1), *ly);
    }
    let outs: Vec<String> = (1..=4)
        .map(|i| format!("r{i}"))
        .chain((1..=4).map(|i| format!("b{i}")))
        .collect();
    let mut trajectories = Vec::new();
    let mut poses = Vec::new();
    for w in 0..WINDOWS {
        let t0 = w as f64 * GAP;
        let mut inputs = Series::new(vec!["wR".into(), "wL".into()]);
        let mut outputs = Series::new(outs.clone());
        let (mut x, mut y, mut th) = (
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
            TAU * rng.uniform(),
        );
        poses.push(vec![x, y, th]);
        let mut angle = TAU * rng.uniform();
        let (mut wr, mut wl, mut next) = (0.0, 0.0, 0.0);
        for k in 0..ROWS {
            let t = t0 + k as f64 * DT;
            if k > 0 && k % 10 == 0 {
                let l = (rng.uniform() * 4.0) as usize;
                let (lx, ly) = MARKS[l];
                let r = (lx - x).hypot(ly - y);
                let b = (ly - y).atan2(lx - x) - th;
                let r = r + truth.quad * r * r + SIGMA_RANGE * rng.normal();
                let b = b + truth.cos_th * th.cos() + truth.sin_th * th.sin();
                let b = b + SIGMA_BEARING * rng.normal();
                let mut row = vec![None; outs.len()];
                row[l] = Some(r);
                row[4 + l] = Some(b.sin().atan2(b.cos()));
                outputs.push(t, &row);
            }
            if t - t0 >= next {
                // Forward 0.1-0.3 m/s, turning at most 0.5 rad/s; towards
                // the middle when far out, so the landmarks stay near.
                let v = 0.1 + 0.2 * rng.uniform();
                let mut om = rng.uniform() - 0.5;
                if x.hypot(y) > 3.0 {
                    let to = (-y).atan2(-x) - th;
                    om = 0.5 * to.sin().signum();
                }
                wr = (v + om * B / 2.0) / R;
                wl = (v - om * B / 2.0) / R;
                next = t - t0 + 0.5 + 2.0 * rng.uniform();
            }
            let e = truth.encoder;
            let (mr, ml) = (wr + e * rng.normal(), wl + e * rng.normal());
            inputs.push(t, &[Some(mr), Some(ml)]);
            let h = DT / SUB as f64;
            for s in 0..SUB {
                let mid = t + (s as f64 + 0.5) * h;
                let a_mid = angle + wr * h / 2.0;
                let wr_eff = wr * (1.0 + truth.wear * mid) * (1.0 + truth.wobble * a_mid.cos());
                let v = R / 2.0 * (wr_eff + wl);
                let om = R / B * (wr_eff - wl);
                let th1 = th + om * h;
                if om.abs() > 1e-12 {
                    x += v / om * (th1.sin() - th.sin());
                    y -= v / om * (th1.cos() - th.cos());
                } else {
                    x += v * h * th.cos();
                    y += v * h * th.sin();
                }
                th = th1;
                angle += wr * h;
            }
        }
        trajectories.push(Trajectory {
            name: format!("w{w}"),
            inputs,
            outputs,
            meta: meta.clone(),
        });
    }
    let data = Dataset {
        meta: DatasetMeta::default(),
        trajectories,
    };
    (data, poses)
}

fn run(truth: Truth, seed: u64) -> Diagnosis {
    let sys = System::parse(MODEL, "dd.sys").unwrap();
    let (data, poses) = simulate(truth, seed);
    // The true initial poses (obsan's own unicycle start reads `v` and
    // `omega`, not wheel speeds): the tests are about the effects.
    let start = Start(Vec::new(), poses, "the simulation's initial poses".into());
    let o = DiagnoseOptions {
        generate: true,
        ..DiagnoseOptions::default()
    };
    diagnose(&sys, None, &data, &start, &o, &|_| {}).unwrap()
}

fn summary(d: &Diagnosis) -> Vec<String> {
    d.named
        .iter()
        .map(|n| format!("{} {:?} [{:?}]", n.effect, n.estimates, n.robust_sd))
        .collect()
}

/// The named effect `name`, which must be the first named; each of its
/// params within 3 sd of `truth` (the larger of the model's and the
/// cluster-robust sd). `abs`: compare magnitudes (a periodic error's sign is
/// its phase's choice).
fn check(d: &Diagnosis, name: &str, truth: &[(&str, f64)], abs: bool) -> Named {
    eprintln!("named: {:?}", summary(d));
    let n = d
        .named
        .iter()
        .find(|n| n.effect == name)
        .unwrap_or_else(|| panic!("{name} not named: {:?}", summary(d)));
    assert_eq!(d.named[0].effect, name, "{:?}", summary(d));
    for (p, want) in truth {
        let i = n.estimates.iter().position(|e| e.0 == *p).unwrap();
        let (_, v, sd) = n.estimates[i];
        let sd = n
            .robust_sd
            .get(i)
            .copied()
            .filter(|r| r.is_finite())
            .map_or(sd, |r| sd.max(r));
        let v = if abs { v.abs() } else { v };
        assert!(
            (v - want).abs() < 3.0 * sd,
            "{p} = {v} ± {sd}, truth {want}"
        );
    }
    n.clone()
}

#[test]
fn a_wearing_wheel_is_named_as_a_drift_of_its_speed() {
    // The right radius shrinks by 2.7% over the 270 s session.
    let wear = -1e-4;
    let d = run(
        Truth {
            wear,
            ..Truth::default()
        },
        1,
    );
    let n = check(&d, "wR_drift", &[("gd_wR", wear)], false);
    assert!(
        n.description
            .starts_with("wR acts smaller as the session goes on"),
        "{}",
        n.description
    );
}

/// The same wear with noisy encoders (0.05 rad/s per 50 Hz row: a heading
/// random walk of about 0.02 rad per window, twice the bearing noise),
/// against which the drift is weighed at the estimated input noise.
#[test]
fn a_wearing_wheel_is_named_through_encoder_noise() {
    let wear = -1e-4;
    let truth = Truth {
        wear,
        encoder: 0.05,
        ..Truth::default()
    };
    let d = run(truth, 5);
    check(&d, "wR_drift", &[("gd_wR", wear)], false);
}

#[test]
fn an_out_of_round_wheel_is_named_as_periodic_in_its_angle() {
    let wobble = 0.08;
    let d = run(
        Truth {
            wobble,
            ..Truth::default()
        },
        2,
    );
    check(&d, "wR_periodic", &[("gw_wR", wobble)], true);
}

#[test]
fn a_range_bending_with_range_is_named_as_a_quadratic() {
    // 4.5 cm at 3 m, 12.5 cm at 5 m.
    let quad = 0.005;
    let d = run(
        Truth {
            quad,
            ..Truth::default()
        },
        3,
    );
    check(&d, "r_quadratic", &[("gq_r", quad)], false);
}

#[test]
fn a_bearing_bias_with_heading_is_named_with_both_terms() {
    let (c, s) = (0.03, -0.02);
    let d = run(
        Truth {
            cos_th: c,
            sin_th: s,
            ..Truth::default()
        },
        4,
    );
    check(
        &d,
        "b_bias_with_th",
        &[("gb_b_cos_th", c), ("gb_b_sin_th", s)],
        false,
    );
}

#[test]
fn clean_data_name_none_of_the_new_families() {
    // The third with noisy encoders: their random walk is a trend too.
    for (seed, encoder) in [(11, 0.0), (12, 0.0), (13, 0.05)] {
        let truth = Truth {
            encoder,
            ..Truth::default()
        };
        let d = run(truth, seed);
        eprintln!("seed {seed}: {:?}", summary(&d));
        for n in &d.named {
            for family in ["_drift", "_periodic", "_quadratic", "_bias_with_"] {
                assert!(!n.effect.contains(family), "seed {seed}: {:?}", summary(&d));
            }
        }
    }
}
