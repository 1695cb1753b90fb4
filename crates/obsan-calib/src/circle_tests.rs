//! DET, LS and section V-C on simulated circles, against the simulator's truth
//! (unit tests: the closed-form steps are not part of the public API).

use crate::calib::{arc_data, av_from_state, combine, start_state, Metric, Modes};
use crate::circle::{det, ls, weights};
use crate::montecarlo::kc_from_av;
use crate::sim::{simulate, SimOptions};

fn noise_free() -> SimOptions {
    SimOptions {
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..SimOptions::default()
    }
}

#[test]
fn det_and_ls_recover_the_modes_of_noise_free_circles() {
    let (data, truth) = simulate(&noise_free()).unwrap();
    let mut modes = Vec::new();
    let mut fits = Vec::new();
    for (t, tt) in data.trajectories.iter().zip(&truth.trajectories) {
        let d = arc_data(t, "wR", "beta").unwrap();
        let dr = det(&d).unwrap();
        let (xq, l) = (tt.xi_q.unwrap(), tt.l.unwrap());
        eprintln!(
            "{}: det xi_q {} (true {xq}), L {} (true {l}) eps {}",
            t.name, dr.closed.xi_q, dr.closed.l, dr.closed.eps
        );
        assert!((dr.closed.xi_q - xq).abs() < 1e-3 * xq.abs(), "DET xi_q");
        eprintln!(
            "node {} period {} mirror {:?} ",
            dr.node, dr.period, dr.mirror
        );
        let w0 = weights(&dr.closed, &d, 1e-3, 0.0);
        let f0 = ls(&d, &dr.closed, &w0, 100, 1e-15);
        eprintln!("ls from det: {:?} rms {}", f0.closed, f0.rms);
        let mut sc: Vec<_> = dr.sigma_curve.iter().map(|p| (p.1, p.0)).collect();
        sc.sort_by(|a, b| a.0.total_cmp(&b.0));
        eprintln!("sigma {:?}", &sc[..5]);
        assert!(obsan_data::wrap(dr.closed.l - l).abs() < 1e-3, "DET L");
        let w = weights(&dr.closed, &d, 1e-3, 0.0);
        let f = ls(&d, &dr.closed, &w, 100, 1e-15);
        eprintln!(
            "   ls xi_q {} L {} rms {:e}",
            f.closed.xi_q, f.closed.l, f.rms
        );
        assert!((f.closed.xi_q - xq).abs() < 1e-9, "LS xi_q");
        assert!(obsan_data::wrap(f.closed.l - l).abs() < 1e-9, "LS L");
        modes.push(Modes {
            q: t.meta["q"],
            xi_q: f.closed.xi_q,
            l: f.closed.l,
            cov: None,
        });
        fits.push(f);
    }
    let cal = combine(&modes).unwrap();
    let want = [truth.phi, truth.psi, truth.eta, truth.delta, truth.xi];
    eprintln!("{:?}\n{:?}", cal.values(), want);
    for (e, w) in cal.values().iter().zip(want) {
        assert!((e - w).abs() < 1e-6);
    }
    // Initial state of each trajectory from (21), (23) and the closed form.
    for ((f, tt), t) in fits.iter().zip(&truth.trajectories).zip(&data.trajectories) {
        let (mu0, g0) = start_state(&cal, &f.closed, t.meta["q"]);
        eprintln!("mu0 {mu0} ({}) g0 {g0} ({})", tt.mu0, tt.gamma0);
        assert!((mu0 - tt.mu0).abs() < 1e-6 && obsan_data::wrap(g0 - tt.gamma0).abs() < 1e-6);
        // A0, V0 of the sign-free form against (21) and (23) from the true state.
        let (a, v) = av_from_state(&cal, t.meta["q"], tt.mu0, tt.gamma0);
        let (a2, v2) = f.closed.av(0.0);
        assert!(
            (a - a2).abs() < 1e-8 * a.abs().max(1.0) && (v - v2).abs() < 1e-8,
            "{a} {a2} {v} {v2}"
        );
        // k and c: eq. (30)-(31) from A0, V0 against the sign-free form's.
        let (k, c) = kc_from_av(f.closed.xi_q, a, v);
        assert!((k - f.closed.k()).abs() < 1e-8 * k.abs() && (c - f.closed.c()).abs() < 1e-8);
    }
    let (mu0, _) = start_state(&cal, &fits[0].closed, data.trajectories[0].meta["q"]);
    let m = Metric::new(&cal, mu0, data.meta.d0.unwrap());
    let want = [truth.rho, truth.r_right, truth.r_left, truth.wheel_base];
    for (e, w) in m.values().iter().zip(want) {
        assert!((e - w).abs() < 1e-6);
    }
}
