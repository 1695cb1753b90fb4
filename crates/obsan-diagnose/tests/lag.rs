//! An effect that adds dynamic states: a first-order actuator lag hidden in
//! simulated range-bearing data of a unicycle (systems/mrclam.sys with the
//! landmarks on a ring), found by the workflow with its time constant.

mod common;

use common::{read, ring, Rng};
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
    simulate_noisy(sys, params, seed, [0.0, 0.0])
}

/// As [`simulate`], the recorded inputs carrying white noise of spectral
/// density `c_j |u_j|` (the true commands drive the motion).
fn simulate_noisy(sys: &System, params: &[f64], seed: u64, c: [f64; 2]) -> Dataset {
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let mut rng = Rng(SplitMix(seed));
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

/// A turn-rate scale of -5% hidden in data whose recorded commands drift
/// from the true ones (heading sd about 0.03 rad after 60 s): with the
/// input noise estimated (`InputNoise::Estimate`) the workflow names the
/// scale alone, within three cluster-robust sds, finds intensities of the
/// right size, and says that the lag cannot be weighed (its fast states
/// overflow the noise mapped back to the start) rather than comparing it.
#[test]
fn names_a_turn_scale_with_estimated_input_noise() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    let ext = sys
        .extend(&[lib.get("turn_scale").unwrap()], "mrclam.eff")
        .unwrap();
    let c = [3e-4, 1e-4];
    let data = simulate_noisy(&ext, &[-0.05], 4, c);
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
    for ((name, got), want) in d.input_noise.iter().zip(c) {
        assert!(
            got / want > 0.5 && got / want < 2.0,
            "{name}: {got} vs {want}"
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
