//! Estimation benchmark: simulating the paper's experiment, one prediction of
//! all three trajectories by the generic predictor, and each calibration
//! method end to end (compute only, no process start or file reading).
//! Run: `cargo bench --bench estimate`.

use obsan_calib::{calibrate, simulate, CalibrateOptions, Method, SimOptions};
use std::time::Instant;

fn main() {
    let p = obsan_calib::calib_predictor();
    let o = SimOptions::default();
    let reps = 21;
    let mut sim = Vec::new();
    let mut pred = Vec::new();
    let mut steps = 0;
    for seed in 0..reps {
        let t = Instant::now();
        let (data, truth) = simulate(&SimOptions { seed, ..o.clone() }).expect("simulates");
        sim.push(t.elapsed());
        steps = data
            .trajectories
            .iter()
            .map(|t| t.inputs.len())
            .sum::<usize>();
        let t = Instant::now();
        for (tr, tt) in data.trajectories.iter().zip(&truth.trajectories) {
            let x0 = [
                tt.mu0,
                tt.gamma0,
                truth.phi,
                truth.psi,
                truth.eta,
                truth.delta,
                truth.xi,
            ];
            p.predict(&x0, &[tt.q.unwrap_or(0.0)], &tr.inputs, tr.outputs.t())
                .expect("predicts");
        }
        pred.push(t.elapsed());
    }
    sim.sort();
    pred.sort();
    let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
    println!("paper's experiment (q = 0.9, 0, -1; {steps} encoder steps), median (min) of {reps}:");
    println!(
        "simulate: {:.2} ms ({:.2})",
        ms(sim[reps as usize / 2]),
        ms(sim[0])
    );
    println!(
        "predict all trajectories from calib.sys (RK4 per encoder step): {:.2} ms ({:.2})",
        ms(pred[reps as usize / 2]),
        ms(pred[0])
    );
    for (label, o) in [
        ("1 Hz bearings (808 in all)", SimOptions::default()),
        (
            "100 bearings per trajectory",
            SimOptions {
                bearings: Some(100),
                ..SimOptions::default()
            },
        ),
    ] {
        println!("calibration of three trajectories, {label}, median (min) of {reps}:");
        for m in [Method::Det, Method::Ls, Method::Cekf, Method::Ml] {
            let mut times = Vec::new();
            for seed in 0..reps {
                let (data, _) = simulate(&SimOptions { seed, ..o.clone() }).expect("simulates");
                let co = CalibrateOptions::for_dataset(&data, m);
                let t = Instant::now();
                calibrate(&data, Some(&p), &co).expect("calibrates");
                times.push(t.elapsed());
            }
            times.sort();
            println!(
                "  {:<5} {:.2} ms ({:.2})",
                m.name(),
                ms(times[reps as usize / 2]),
                ms(times[0])
            );
        }
    }
}
