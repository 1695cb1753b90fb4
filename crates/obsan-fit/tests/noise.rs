//! Maximum-likelihood noise levels on simulated data whose measured inputs
//! carry white noise of known intensity: the estimate recovers the output
//! noise and the input intensities; on data without input noise it finds
//! none worth the likelihood.

use obsan_data::{Dataset, DatasetMeta, Series, Trajectory};
use obsan_fit::{estimate_noise, fit, FitOptions, FitTrajectory, NoiseOptions, Predictor, Rng};
use obsan_model::System;
use std::collections::BTreeMap;

const MODEL: &str = "system uni
state x, y, th
input v, omega
x' = v*cos(th)
y' = v*sin(th)
th' = omega
output r1 = sqrt((6 - x)^2 + (2 - y)^2)
output b1 = atan2(2 - y, 6 - x) - th
output r2 = sqrt((-5 - x)^2 + (5 - y)^2)
output b2 = atan2(5 - y, -5 - x) - th
output r3 = sqrt((1 - x)^2 + (-6 - y)^2)
output b3 = atan2(-6 - y, 1 - x) - th
";

const SIGMA: [f64; 2] = [0.05, 0.02];
const DT: f64 = 0.02;

/// Eight 60 s windows: the true commands drive the motion, the recorded
/// inputs carry white noise of spectral density `c_j |u_j|` (variance
/// `c_j |u_j| / DT` per 50 Hz row); one landmark's range and bearing
/// every 0.1 s. Returns the data and each window's true initial state.
fn simulate(p: &Predictor, c: [f64; 2], seed: u64) -> (Dataset, Vec<Vec<f64>>) {
    let mut rng = Rng::new(seed);
    let mut trajectories = Vec::new();
    let mut starts = Vec::new();
    for w in 0..8 {
        let mut truth = Series::new(vec!["v".into(), "omega".into()]);
        let mut measured = Series::new(vec!["v".into(), "omega".into()]);
        let (mut v, mut om, mut next) = (0.0, 0.0, 0.0);
        for k in 0..3000 {
            let t = k as f64 * DT;
            if t >= next {
                v = [0.1, 0.2, 0.3][(rng.uniform() * 3.0) as usize];
                // Turning at 0.2-0.6 rad/s either way keeps every path
                // within a few metres of its start, away from the landmarks.
                om = (0.2 + 0.4 * rng.uniform()) * if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
                next = t + 0.5 + 2.5 * rng.uniform();
            }
            truth.push(t, &[Some(v), Some(om)]);
            let mv = v + (c[0] * v.abs() / DT).sqrt() * rng.normal();
            let mo = om + (c[1] * om.abs() / DT).sqrt() * rng.normal();
            measured.push(t, &[Some(mv), Some(mo)]);
        }
        let x0 = vec![
            rng.uniform() - 0.5,
            rng.uniform() - 0.5,
            6.0 * rng.uniform(),
        ];
        let times: Vec<f64> = (1..600).map(|k| k as f64 * 0.1).collect();
        let y = p.predict(&x0, &[], &truth, &times).unwrap();
        let mut outputs = Series::new(p.outputs.clone());
        for (t, yk) in times.iter().zip(&y) {
            let l = (rng.uniform() * 3.0) as usize;
            let mut row = vec![None; 6];
            row[2 * l] = Some(yk[2 * l] + SIGMA[0] * rng.normal());
            let b = yk[2 * l + 1] + SIGMA[1] * rng.normal();
            row[2 * l + 1] = Some(b.sin().atan2(b.cos()));
            outputs.push(*t, &row);
        }
        trajectories.push(Trajectory {
            name: format!("w{w}"),
            inputs: measured,
            outputs,
            meta: BTreeMap::new(),
        });
        starts.push(x0);
    }
    (
        Dataset {
            meta: DatasetMeta::default(),
            trajectories,
        },
        starts,
    )
}

fn predictor() -> Predictor {
    let sys = System::parse(MODEL, "uni.sys").unwrap();
    Predictor::new(&sys.normal_form(None, &[]).unwrap())
}

/// Fit the initial states (white noise at the true output levels), then
/// estimate the levels; refit by generalised least squares with them and
/// estimate again.
fn levels(c: [f64; 2], seed: u64) -> obsan_fit::NoiseEstimate {
    let p = predictor();
    let (data, starts) = simulate(&p, c, seed);
    let trajs = FitTrajectory::all(&p, &data);
    let sigma: Vec<f64> = (0..6).map(|o| SIGMA[o % 2]).collect();
    let mut fo = FitOptions {
        max_iterations: 30,
        cost_tolerance: 1e-8,
        step_tolerance: 1e-3,
        sigma,
        max_step: 0.5,
        input_noise: None,
    };
    let no = NoiseOptions::default();
    let mut states = starts;
    let mut est = None;
    for _ in 0..2 {
        let r = fit(&p, &trajs, &[], &states, &fo).unwrap();
        states = r.initial_states;
        let e = estimate_noise(&p, &trajs, &[], &states, &fo.sigma, &[true, true], &no).unwrap();
        fo.sigma = e.sigma.clone();
        fo.input_noise = Some(e.input_noise.clone());
        est = Some(e);
    }
    est.unwrap()
}

/// Median of `x`.
fn median(mut x: Vec<f64>) -> f64 {
    x.sort_by(f64::total_cmp);
    let n = x.len();
    if n % 2 == 1 {
        x[n / 2]
    } else {
        0.5 * (x[n / 2 - 1] + x[n / 2])
    }
}

#[test]
fn recovers_output_noise_and_input_intensities() {
    // Heading sd about 0.03 rad and along-track sd about 6 cm after 60 s:
    // the regime where the linearisation about the fitted path holds.
    let c = [3e-4, 1e-4];
    let mut ratios = [Vec::new(), Vec::new()];
    for seed in 11..21 {
        let e = levels(c, seed);
        for (o, s) in e.sigma.iter().enumerate() {
            let want = SIGMA[o % 2];
            assert!(
                (s / want - 1.0).abs() < 0.1,
                "seed {seed} output {o}: {s} vs {want}"
            );
        }
        for j in 0..2 {
            let r = e.input_noise[j] / c[j];
            // One seed's intensity scatters by tens of percent (a window
            // resolves some tens of independent increments).
            assert!((0.4..2.5).contains(&r), "seed {seed} input {j}: ratio {r}");
            ratios[j].push(r);
        }
        // The drift is plain to the likelihood.
        assert!(e.m2ll_white - e.m2ll > 100.0, "seed {seed}: {e:?}");
    }
    for (j, r) in ratios.into_iter().enumerate() {
        let m = median(r);
        assert!((m - 1.0).abs() < 0.2, "input {j}: median ratio {m}");
    }
}

#[test]
fn noiseless_inputs_get_no_intensity_worth_the_likelihood() {
    for seed in [21, 22, 23] {
        let e = levels([0.0, 0.0], seed);
        // Two extra parameters under the null: the LR is chi-square with at
        // most 2 degrees of freedom (a boundary mixture), so beyond 13.8 has
        // probability below 0.001.
        let lr = e.m2ll_white - e.m2ll;
        assert!((0.0..13.8).contains(&lr), "seed {seed}: LR {lr}, {e:?}");
        for (o, s) in e.sigma.iter().enumerate() {
            let want = SIGMA[o % 2];
            assert!(
                (s / want - 1.0).abs() < 0.1,
                "seed {seed} output {o}: {s} vs {want}"
            );
        }
    }
}

/// Thirty trajectories of `x' = (1 + k) u` (u = 1, 10 s) measured every
/// 0.1 s with white noise 0.01, the measured input carrying white noise of
/// density 0.002: within a trajectory the residuals follow a random walk.
/// Fitted as if white, over 200 repetitions: the Fisher sd of k understates
/// the scatter of the estimates; the cluster-robust sd matches it.
#[test]
fn cluster_robust_sd_matches_the_scatter_under_correlated_residuals() {
    let sys = System::parse(
        "system drift\nstate x\ninput u\nparam k\nx' = (1 + k)*u\noutput y = x\n",
        "drift.sys",
    )
    .unwrap();
    let p = Predictor::new(&sys.normal_form(None, &[]).unwrap());
    let mut rng = Rng::new(5);
    let (mut est, mut fisher, mut robust) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..200 {
        let mut trajectories = Vec::new();
        for w in 0..30 {
            let mut inputs = Series::new(vec!["u".into()]);
            let mut outputs = Series::new(vec!["y".into()]);
            let mut x = 0.0;
            for j in 0..=500 {
                let t = j as f64 * DT;
                if j % 5 == 0 && j > 0 {
                    outputs.push(t, &[Some(x + 0.01 * rng.normal())]);
                }
                // The true input is 1; the recorded one is noisy.
                inputs.push(t, &[Some(1.0 + (0.002 / DT).sqrt() * rng.normal())]);
                x += DT;
            }
            trajectories.push(Trajectory {
                name: format!("t{w}"),
                inputs,
                outputs,
                meta: BTreeMap::new(),
            });
        }
        let data = Dataset {
            meta: DatasetMeta::default(),
            trajectories,
        };
        let trajs = FitTrajectory::all(&p, &data);
        let fo = FitOptions {
            max_iterations: 20,
            cost_tolerance: 1e-10,
            step_tolerance: 0.0,
            sigma: vec![0.01],
            max_step: 0.0,
            input_noise: None,
        };
        let r = fit(&p, &trajs, &[0.0], &vec![vec![0.0]; 30], &fo).unwrap();
        est.push(r.params[0]);
        fisher.push(r.params_sd[0]);
        robust.push(r.params_sd_robust[0]);
    }
    let n = est.len() as f64;
    let mean = est.iter().sum::<f64>() / n;
    let scatter = (est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let (f, r) = (rms(&fisher), rms(&robust));
    // The scatter's own sampling error with 200 repetitions is about 5%.
    assert!(
        (r / scatter - 1.0).abs() < 0.15,
        "robust {r} vs scatter {scatter}"
    );
    assert!(f < 0.5 * scatter, "Fisher {f} vs scatter {scatter}");
}
