//! Accuracy of `calibrate` on simulated data (fixed seeds).

use obsan_estimate::{calibrate, simulate, CalibrateOptions, Method, Predictor, SimOptions, Truth};

fn predictor() -> Predictor {
    let src = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../systems/calib.sys")).unwrap();
    let sys = obsan_model::System::parse(&src, "calib.sys").unwrap();
    Predictor::new(&sys.normal_form(None, &[]).unwrap())
}

fn truth_values(t: &Truth) -> [f64; 5] {
    [t.phi, t.psi, t.eta, t.delta, t.xi]
}

#[test]
fn explore() {
    let p = predictor();
    for (label, o) in [
        ("noise-free", SimOptions { sigma_beta: 0.0, k_encoder: 0.0, ..SimOptions::default() }),
        ("paper noise", SimOptions::default()),
    ] {
        let (data, truth) = simulate(&o).unwrap();
        for (m, ms, tol) in [(Method::Det, 0.5, 1e-7), (Method::Ls, 0.5, 1e-7), (Method::Cekf, 0.5, 1e-7), (Method::Ml, 0.5, 1e-7)] {
            let mut co = CalibrateOptions::for_dataset(&data, m);
            co.ml_max_step = ms; co.ml_tolerance = tol;
            if co.sigma_beta.is_none() && m == Method::Cekf { co.sigma_beta = Some(1e-4); }
            let t0 = std::time::Instant::now();
            let r = calibrate(&data, Some(&p), &co);
            let el = t0.elapsed();
            match r {
                Ok(r) => {
                    let e: Vec<f64> = r.calibration.values().iter().zip(truth_values(&truth)).map(|(a, b)| a - b).collect();
                    eprintln!("{label} {ms} {tol} {:?} {:?} err {:?} sd {:?} metric {:?} ml iters {:?}", m, el, e, r.calibration.sd(), r.metric.as_ref().map(|m| m.0.values()), r.ml.as_ref().map(|f| f.iterations));
                }
                Err(e) => eprintln!("{label} {:?}: {e}", m),
            }
        }
    }
}

#[test]
fn timing_det() {
    let (data, _) = simulate(&SimOptions::default()).unwrap();
    for t in &data.trajectories {
        let arc = obsan_estimate::arc_data(t, "wR", "beta").unwrap();
        let t0 = std::time::Instant::now();
        for _ in 0..20 { obsan_estimate::det(&arc).unwrap(); }
        eprintln!("{} n={} det {:?}", t.name, arc.s.len(), t0.elapsed() / 20);
        let d = obsan_estimate::det(&arc).unwrap();
        let w = obsan_estimate::weights(&d.closed, &arc, 0.017, 0.0);
        let t0 = std::time::Instant::now();
        for _ in 0..20 { obsan_estimate::ls(&arc, &d.closed, &w, 100, 1e-12); }
        eprintln!("   ls {:?} iters {}", t0.elapsed() / 20, obsan_estimate::ls(&arc, &d.closed, &w, 100, 1e-12).iterations);
        let t0 = std::time::Instant::now();
        for _ in 0..20 { obsan_estimate::arc_data(t, "wR", "beta").unwrap(); }
        eprintln!("   arc {:?}", t0.elapsed() / 20);
    }
}
#[test]
fn explore3() {
    let p = predictor();
    for seed in 1..12 {
        let o = SimOptions { sigma_beta: 3f64.to_radians(), bearings: Some(100), seed, ..SimOptions::default() };
        let (data, truth) = simulate(&o).unwrap();
        let co = CalibrateOptions::for_dataset(&data, Method::Ls);
        let r = calibrate(&data, Some(&p), &co).unwrap();
        let e: Vec<f64> = r.calibration.values().iter().zip(truth_values(&truth)).map(|(a, b)| a - b).collect();
        let mut s = format!("seed {seed} phi err {:.4}", e[0]);
        for (te, tt) in r.trajectories.iter().zip(&truth.trajectories) {
            s += &format!(" | {} dxi {:.2e} dL {:.4} det dL {:.4}", te.name, te.closed.xi_q - tt.xi_q.unwrap(), obsan_estimate::wrap(te.closed.l - tt.l.unwrap()), obsan_estimate::wrap(te.det.closed.l - tt.l.unwrap()));
        }
        eprintln!("{s}");
    }
}
