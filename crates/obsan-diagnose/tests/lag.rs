//! An effect that adds dynamic states: a first-order actuator lag hidden in
//! simulated range-bearing data of a unicycle (systems/mrclam.sys with the
//! landmarks on a ring), found by the workflow with its time constant.

mod common;

use common::{read, ring, Rng, Source};
use obsan_data::{Dataset, DatasetMeta, Series, Trajectory};
use obsan_diagnose::{diagnose, start_values, DiagnoseOptions, Diagnosis, InputNoise};
use obsan_expr::SplitMix;
use obsan_fit::Predictor;
use obsan_model::{EffectLibrary, System};

const SIGMA_RANGE: f64 = 0.05;
const SIGMA_BEARING: f64 = 0.02;

/// Six 60 s windows of piecewise-constant commands (50 Hz rows), one
/// landmark's range and bearing every 0.2 s, driven through `sys` (the
/// nominal model or one extended by an effect) at `params`.
fn simulate(sys: &System, params: &[f64], seed: u64) -> Dataset {
    simulate_noisy(sys, params, &mut Rng(SplitMix(seed)), [0.0, 0.0])
}

/// As [`simulate`], the recorded inputs carrying white noise of spectral
/// density `c_j |u_j|` (the true commands drive the motion).
fn simulate_noisy(sys: &System, params: &[f64], rng: &mut impl Source, c: [f64; 2]) -> Dataset {
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let common::Ring { codes, meta, .. } = ring(sys);
    let consts: Vec<f64> = p.consts.iter().map(|c| meta[c]).collect();
    let mut trajectories = Vec::new();
    for w in 0..6 {
        let mut inputs = Series::new(vec!["v".into(), "omega".into()]);
        let mut recorded = Series::new(vec!["v".into(), "omega".into()]);
        let (mut v, mut om, mut next) = (0.0, 0.0, 0.0);
        for k in 0..3000 {
            let t = k as f64 * 0.02;
            if t >= next {
                v = [0.0, 0.15, 0.3][(rng.uniform() * 3.0) as usize];
                om = rng.uniform() - 0.5;
                next = t + 0.5 + 2.5 * rng.uniform();
            }
            inputs.push(t, &[Some(v), Some(om)]);
            let nv = (c[0] * f64::abs(v) / 0.02).sqrt() * rng.normal();
            let nw = (c[1] * f64::abs(om) / 0.02).sqrt() * rng.normal();
            recorded.push(t, &[Some(v + nv), Some(om + nw)]);
        }
        // Start near the centre; lag states (if any) at the first command.
        let mut x0 = vec![
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
            std::f64::consts::TAU * rng.uniform(),
        ];
        x0.extend(p.state[3..p.n_dynamic].iter().map(|s| {
            let c = if s == "va" { 0 } else { 1 };
            inputs.values()[c][0].unwrap()
        }));
        x0.extend_from_slice(params);
        let times: Vec<f64> = (1..300).map(|k| k as f64 * 0.2).collect();
        let y = p.predict(&x0, &consts, &inputs, &times).unwrap();
        let mut outputs = Series::new(p.outputs.clone());
        for (t, yk) in times.iter().zip(&y) {
            let c = (rng.uniform() * codes.len() as f64) as usize;
            let mut row = vec![None; p.outputs.len()];
            let ri = p
                .outputs
                .iter()
                .position(|o| *o == format!("r{}", codes[c]))
                .unwrap();
            let bi = p
                .outputs
                .iter()
                .position(|o| *o == format!("b{}", codes[c]))
                .unwrap();
            row[ri] = Some(yk[ri] + SIGMA_RANGE * rng.normal());
            let b = yk[bi] + SIGMA_BEARING * rng.normal();
            row[bi] = Some(b.sin().atan2(b.cos()));
            outputs.push(*t, &row);
        }
        trajectories.push(Trajectory {
            name: format!("w{w}"),
            inputs: recorded,
            outputs,
            meta: meta.clone(),
        });
    }
    Dataset {
        meta: DatasetMeta::default(),
        trajectories,
    }
}

fn run(effect: Option<(&str, f64)>, seed: u64) -> Diagnosis {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    let data = match effect {
        Some((name, value)) => {
            let ext = sys.extend(&[lib.get(name).unwrap()], "mrclam.eff").unwrap();
            simulate(&ext, &[value], seed)
        }
        None => simulate(&sys, &[], seed),
    };
    let start = start_values(&sys, &data, &Default::default()).unwrap();
    diagnose(
        &sys,
        Some(&lib),
        &data,
        &start,
        &DiagnoseOptions::default(),
        &|_| {},
    )
    .unwrap()
}

#[test]
fn names_a_hidden_actuator_lag_with_its_time_constant() {
    for seed in [1, 2] {
        let d = run(Some(("actuator_lag", 0.3)), seed);
        let named: Vec<&str> = d.named.iter().map(|n| n.effect.as_str()).collect();
        assert_eq!(named, ["actuator_lag"], "seed {seed}");
        let (_, t, sd) = d.named[0].estimates[0].clone();
        assert!((t - 0.3).abs() < 3.0 * sd, "seed {seed}: T {t} ± {sd}");
    }
}

#[test]
fn clean_unicycle_data_name_nothing() {
    let d = run(None, 3);
    assert!(
        d.named.is_empty(),
        "{:?}",
        d.named.iter().map(|n| &n.effect).collect::<Vec<_>>()
    );
}

/// The relative sampling sd of each estimated intensity `c` (v, omega) of
/// [`simulate_noisy`]'s data, from the efficient variance of a diffusion's
/// variance seen through white measurement noise (Gloter & Jacod 2001, the
/// local asymptotic normality of `Y_i = s W(t_i) + tau e_i`, `n` points on
/// `[0, T]`): `var(s^2) / s^4 = 8 tau / (s sqrt(n T))` per window, divided by
/// the windows' number. Each input's error integrates to a walk: along the
/// track for v (`s^2 = c_v mean|v|`, `mean|v|` = 0.15 m/s over {0, 0.15,
/// 0.3}), in heading for omega (`s^2 = c_w mean|omega|`, 0.25 rad/s over
/// [-0.5, 0.5)). What one row reads of the walk, `tau`: for the heading the
/// bearing's sd (the ranges' lateral information left out); for the track,
/// one range (sensitivity `cos phi`, sd 0.05 m) and one bearing (`sin phi /
/// r`, r about 4 m) to a landmark at a random angle `phi`, information
/// `1/2 / 0.05^2 + 1/2 / (4 x 0.02)^2` per row. An efficient estimator's sd
/// (a lower bound): the estimator here also fits the starts, the output
/// levels and the named scale, and the intensity varies with `|u|` within a
/// window, so the band of 3 such sds is the narrowest one honest here.
fn intensity_sd(c: [f64; 2]) -> [f64; 2] {
    let (n, t, windows) = (299.0_f64, 60.0_f64, 6.0);
    let tau_track = (0.5 / SIGMA_RANGE.powi(2) + 0.5 / (4.0 * SIGMA_BEARING).powi(2))
        .sqrt()
        .recip();
    let rel = |c: f64, mean_abs: f64, tau: f64| {
        let s = (c * mean_abs).sqrt();
        (8.0 * tau / (s * (n * t).sqrt()) / windows).sqrt()
    };
    [rel(c[0], 0.15, tau_track), rel(c[1], 0.25, SIGMA_BEARING)]
}

/// A turn-rate scale of -5% hidden in data whose recorded commands drift
/// from the true ones (heading sd about 0.03 rad after 60 s): with the
/// input noise estimated (`InputNoise::Estimate`) the workflow names the
/// scale alone, within three cluster-robust sds, finds intensities of the
/// right size (within three sampling sds, `intensity_sd`), and says that
/// the lag cannot be weighed (its fast states overflow the noise mapped
/// back to the start) rather than comparing it.
#[test]
fn names_a_turn_scale_with_estimated_input_noise() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    let ext = sys
        .extend(&[lib.get("turn_scale").unwrap()], "mrclam.eff")
        .unwrap();
    let c = [3e-4, 1e-4];
    let data = simulate_noisy(&ext, &[-0.05], &mut Rng(SplitMix(4)), c);
    let start = start_values(&sys, &data, &Default::default()).unwrap();
    let o = DiagnoseOptions {
        input_noise: InputNoise::Estimate,
        ..DiagnoseOptions::default()
    };
    let d = diagnose(&sys, Some(&lib), &data, &start, &o, &|_| {}).unwrap();
    let named: Vec<&str> = d.named.iter().map(|n| n.effect.as_str()).collect();
    assert_eq!(named, ["turn_scale"]);
    let (_, kw, _) = d.named[0].estimates[0].clone();
    let r = d.named[0].robust_sd[0];
    assert!((kw + 0.05).abs() < 3.0 * r, "kw {kw} ± {r}");
    assert_eq!(d.input_noise_source, "estimated");
    // Estimated at the nominal fit, then again with the named scale in the
    // model: one likelihood-ratio statistic each.
    assert_eq!(d.input_noise_lr.len(), 2, "{:?}", d.input_noise_lr);
    for (((name, got), want), sd) in d.input_noise.iter().zip(c).zip(intensity_sd(c)) {
        assert!(
            (got / want - 1.0).abs() < 3.0 * sd,
            "{name}: {got} vs {want} (relative sd {sd:.2})"
        );
    }
    let lag = d.rounds[0]
        .iter()
        .find(|c| c.effect == "actuator_lag")
        .unwrap();
    assert!(
        lag.error
            .as_deref()
            .is_some_and(|e| e.contains("decays too fast")),
        "{lag:?}"
    );
}
