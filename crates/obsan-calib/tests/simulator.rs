//! The simulator against independent identities: the closed-form bearing of
//! ERRATA.md, circle geometry, and eq. (16) integrated from systems/calib.sys.

use obsan_calib::{simulate, Robot, SimOptions};
use obsan_data::{wrap, Series};
use obsan_fit::Rng;
use std::f64::consts::PI;

/// The model file the simulator must agree with.
fn calib_sys() -> obsan_model::System {
    let src = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/calib.sys"
    ))
    .unwrap();
    obsan_model::System::parse(&src, "calib.sys").unwrap()
}

fn noise_free(q: Vec<f64>) -> SimOptions {
    SimOptions {
        q,
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..SimOptions::default()
    }
}

#[test]
fn bearing_matches_the_closed_form_of_errata() {
    // beta = atan2(sin gamma, -mu - cos gamma) - psi, mu = rho/D, gamma = theta + phi,
    // theta = thetaR - atan2(yR, xR).
    let mut rng = Rng::new(3);
    for _ in 0..1000 {
        let robot = Robot {
            phi: rng.uniform() - 0.5,
            psi: 2.0 * rng.uniform(),
            ..Robot::default()
        };
        let (x, y, th) = (
            4.0 * rng.uniform() - 2.0,
            4.0 * rng.uniform() - 2.0,
            7.0 * rng.uniform(),
        );
        let d = (x * x + y * y).sqrt();
        if d < 0.5 {
            continue;
        }
        let mu = robot.rho / d;
        let gamma = th - y.atan2(x) + robot.phi;
        let closed = gamma.sin().atan2(-mu - gamma.cos()) - robot.psi;
        let diff = wrap(robot.bearing(x, y, th) - closed);
        assert!(diff.abs() < 1e-12, "{diff}");
    }
}

#[test]
fn noise_free_circles_have_the_paper_geometry() {
    let o = noise_free(vec![0.9, 0.0, -1.0]);
    let (data, truth) = simulate(&o).unwrap();
    let rb = &o.robot;
    for (tr, tt) in data.trajectories.iter().zip(&truth.trajectories) {
        let q = tt.q.unwrap();
        // The measured wheel-speed ratio is q exactly.
        let (wr, wl) = (
            tr.inputs.column("wR").unwrap(),
            tr.inputs.column("wL").unwrap(),
        );
        for k in 0..tr.inputs.len() {
            assert!((wl[k].unwrap() - q * wr[k].unwrap()).abs() < 1e-12);
        }
        // One loop takes 2 pi B / (nu (rR - q rL)) (eq. 12).
        let period = 2.0 * PI * rb.wheel_base / (o.nu * (rb.r_right - q * rb.r_left)).abs();
        assert!(
            (tt.duration - period).abs() <= 1.0 / o.encoder_rate + 1e-9,
            "{} vs {period}",
            tt.duration
        );
        // About one bearing per second over the loop.
        assert!((tr.outputs.len() as f64 - period.floor() - 1.0).abs() <= 1.0);
    }
    // eta, delta, xi of Table III, xi = 0.61237 (ERRATA: not 0.61236).
    assert!((truth.eta - 0.495).abs() < 1e-12);
    assert!((truth.delta - 1.016162).abs() < 1e-6);
    assert!((truth.xi - 0.6123711).abs() < 1e-7);
}

/// Integrate eq. (16) of systems/calib.sys (the model file itself) along the
/// simulated wheel speeds and compare its output with the simulated bearings.
#[test]
fn calib_sys_reproduces_the_simulated_bearings() {
    let sys = calib_sys();
    let nf = sys.normal_form(None, &[]).unwrap();
    let ctx = &nf.ctx;
    let mut roots = vec![
        nf.fields[0][0],
        nf.fields[0][1],
        nf.fields[1][0],
        nf.fields[1][1],
        nf.outputs[0].1,
    ];
    roots.extend(nf.f0[..2].iter().copied());
    let tape = obsan_expr::Tape::compile(ctx, &roots, &nf.state_vars).unwrap();
    for profile in [
        obsan_calib::SpeedProfile::Constant,
        obsan_calib::SpeedProfile::Sine {
            amplitude: 0.5,
            period: 20.0,
        },
    ] {
        let o = SimOptions {
            profile,
            ..noise_free(vec![0.9, -1.0])
        };
        let (data, truth) = simulate(&o).unwrap();
        let rb = &o.robot;
        let params = [rb.phi, rb.psi, truth.eta, truth.delta, truth.xi];
        for (tr, tt) in data.trajectories.iter().zip(&truth.trajectories) {
            let mut s = [tt.mu0, tt.gamma0];
            let dt = 1.0 / o.encoder_rate;
            let rhs = |s: [f64; 2], wr: f64, wl: f64| -> [f64; 2] {
                let mut x = vec![s[0], s[1]];
                x.extend_from_slice(&params);
                let v = tape.eval(&x);
                [v[0] * wr + v[2] * wl, v[1] * wr + v[3] * wl]
            };
            let beta_at = |s: [f64; 2]| {
                let mut x = vec![s[0], s[1]];
                x.extend_from_slice(&params);
                tape.eval(&x)[4]
            };
            let (wr, wl) = (
                tr.inputs.column("wR").unwrap(),
                tr.inputs.column("wL").unwrap(),
            );
            let mut k_out = 0;
            let mut worst: f64 = 0.0;
            for k in 0..=tr.inputs.len() {
                let t = k as f64 * dt;
                while k_out < tr.outputs.len() && (tr.outputs.t()[k_out] - t).abs() < 1e-9 {
                    let diff = wrap(beta_at(s) - tr.outputs.values()[0][k_out].unwrap());
                    worst = worst.max(diff.abs());
                    k_out += 1;
                }
                if k == tr.inputs.len() {
                    break;
                }
                let (a, b) = (wr[k].unwrap(), wl[k].unwrap());
                // RK4 over one encoder step with constant wheel speeds.
                let k1 = rhs(s, a, b);
                let k2 = rhs([s[0] + dt / 2.0 * k1[0], s[1] + dt / 2.0 * k1[1]], a, b);
                let k3 = rhs([s[0] + dt / 2.0 * k2[0], s[1] + dt / 2.0 * k2[1]], a, b);
                let k4 = rhs([s[0] + dt * k3[0], s[1] + dt * k3[1]], a, b);
                for i in 0..2 {
                    s[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
            }
            assert!(
                k_out >= tr.outputs.len() - 1,
                "compared {k_out} of {}",
                tr.outputs.len()
            );
            assert!(
                worst < 1e-7,
                "{}: eq. (16) and the simulator differ by {worst} rad",
                tr.name
            );
        }
    }
}

#[test]
fn effects_and_errors() {
    // bearing_scale: beta_meas = (1 + k) beta on noise-free data.
    let base = simulate(&noise_free(vec![0.0])).unwrap().0;
    let mut o = noise_free(vec![0.0]);
    o.effects.set("bearing_scale", 0.01).unwrap();
    let scaled = simulate(&o).unwrap().0;
    let (a, b) = (
        &base.trajectories[0].outputs.values()[0],
        &scaled.trajectories[0].outputs.values()[0],
    );
    for (x, y) in a.iter().zip(b) {
        assert!((wrap(y.unwrap() - 1.01 * x.unwrap())).abs() < 1e-12);
    }
    // dq: the executed (and measured) ratio is q + dq; the commanded q stays in meta.
    let o = SimOptions {
        dq: 0.05,
        ..noise_free(vec![0.0])
    };
    let d = simulate(&o).unwrap().0;
    let tr = &d.trajectories[0];
    assert!(
        (tr.inputs.column("wL").unwrap()[5].unwrap() / tr.inputs.column("wR").unwrap()[5].unwrap()
            - 0.05)
            .abs()
            < 1e-12
    );
    assert_eq!(tr.meta["q"], 0.0);
    assert!(o
        .clone()
        .effects
        .set("nope", 1.0)
        .unwrap_err()
        .to_string()
        .contains("unknown effect"));
    // A straight line never completes a loop: a clear error, not a wrong dataset.
    let straight = SimOptions {
        q: vec![0.297 / 0.3018],
        max_duration: 100.0,
        ..noise_free(vec![])
    };
    assert!(simulate(&straight)
        .unwrap_err()
        .to_string()
        .contains("degenerate trajectory"));
    let near = SimOptions {
        d0: 0.2,
        ..noise_free(vec![0.0])
    };
    assert!(simulate(&near)
        .unwrap_err()
        .to_string()
        .contains("must exceed rho"));
}

#[test]
fn encoder_and_bearing_noise_have_the_stated_variance() {
    let o = SimOptions {
        q: vec![0.9],
        ..SimOptions::default()
    };
    let (noisy, _) = simulate(&o).unwrap();
    let (clean, _) = simulate(&SimOptions {
        sigma_beta: 0.0,
        k_encoder: 0.0,
        ..o.clone()
    })
    .unwrap();
    let (a, b) = (
        &noisy.trajectories[0].outputs.values()[0],
        &clean.trajectories[0].outputs.values()[0],
    );
    let n = a.len() as f64;
    let var: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| wrap(x.unwrap() - y.unwrap()).powi(2))
        .sum::<f64>()
        / n;
    let sd = var.sqrt();
    // ~715 samples: the sample sd is within 10% of sigma with overwhelming probability.
    assert!((sd / o.sigma_beta - 1.0).abs() < 0.1, "bearing sd {sd}");
    // Encoder increments: variance K^2 |da| / r per step.
    let (wr_n, wr_c) = (
        noisy.trajectories[0].inputs.column("wR").unwrap(),
        clean.trajectories[0].inputs.column("wR").unwrap(),
    );
    let dt = 1.0 / o.encoder_rate;
    let da = wr_c[0].unwrap() * dt;
    let expect = (o.k_encoder * o.k_encoder * da / o.r_nominal).sqrt();
    let m = wr_n.len() as f64;
    let sd_e = (wr_n
        .iter()
        .zip(wr_c)
        .map(|(x, y)| ((x.unwrap() - y.unwrap()) * dt).powi(2))
        .sum::<f64>()
        / m)
        .sqrt();
    assert!((sd_e / expect - 1.0).abs() < 0.05, "{sd_e} vs {expect}");
}

#[test]
fn csv_roundtrip_and_rejections() {
    let mut s = Series::new(vec!["wR".into(), "wL".into()]);
    s.push(0.0, &[Some(0.168), Some(-0.168)]);
    s.push(0.02, &[Some(1.0 / 3.0), None]);
    let back = Series::parse_csv(&s.to_csv(), "x.csv", &["wR", "wL"], true).unwrap();
    assert_eq!(back, s);
    let cases = [
        ("t,wR\n0,1\n", "missing column 'wL'", Some(1)),
        (
            "t,wR,wL\n0,1,2\n0.02,1,abc\n",
            "'abc' is not a number",
            Some(3),
        ),
        (
            "t,wR,wL\n0,1,2\n0.02,1,NaN\n",
            "not a finite number",
            Some(3),
        ),
        (
            "t,wR,wL\n0,1,2\n0.02,1,inf\n",
            "not a finite number",
            Some(3),
        ),
        ("t,wR,wL\n1,1,2\n0.5,1,2\n", "time goes backwards", Some(3)),
        ("t,wR,wL\n0,1\n", "2 fields, the header has 3", Some(2)),
        ("t,wR,wL\n0,1,\n", "empty value", Some(2)),
        ("", "empty", None),
        ("x,wR,wL\n", "first column must be 't'", Some(1)),
    ];
    for (text, want, row) in cases {
        let e = Series::parse_csv(text, "in.csv", &["wR", "wL"], false).unwrap_err();
        assert!(e.message().contains(want), "{text:?}: {e}");
        assert_eq!(e.row, row, "{text:?}");
        assert!(e.to_string().starts_with("in.csv"));
    }
}

/// The generic predictor, fed systems/calib.sys, the true parameters and the
/// true initial state, reproduces the noise-free simulated bearings.
#[test]
fn predictor_reproduces_simulated_bearings() {
    let sys = calib_sys();
    let nf = sys.normal_form(None, &[]).unwrap();
    let p = obsan_fit::Predictor::new(&nf);
    assert_eq!(p.angular, vec![true], "beta is an angle");
    assert_eq!(p.consts, vec!["q"]);
    for profile in [
        obsan_calib::SpeedProfile::Constant,
        obsan_calib::SpeedProfile::StopGo {
            run: 7.0,
            pause: 3.0,
        },
    ] {
        let o = SimOptions {
            profile,
            ..noise_free(vec![0.9, 0.0, -1.0])
        };
        let (data, truth) = simulate(&o).unwrap();
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
            let y = p
                .predict(&x0, &[tt.q.unwrap()], &tr.inputs, tr.outputs.t())
                .unwrap();
            let worst = y
                .iter()
                .zip(&tr.outputs.values()[0])
                .map(|(a, b)| wrap(a[0] - b.unwrap()).abs())
                .fold(0.0, f64::max);
            assert!(worst < 1e-7, "{}: {worst}", tr.name);
        }
    }
    // The restricted model wants the input nu, which the data do not have.
    let nfq = sys.normal_form(Some("q"), &[]).unwrap();
    let pq = obsan_fit::Predictor::new(&nfq);
    let (data, _) = simulate(&noise_free(vec![0.0])).unwrap();
    let tr = &data.trajectories[0];
    let e = pq
        .predict(
            &[0.2, 1.0, 0.0, 1.5, 0.5, 1.0, 0.6],
            &[0.0],
            &tr.inputs,
            tr.outputs.t(),
        )
        .unwrap_err();
    // The typed error names the column, and its text says so too.
    assert!(
        matches!(&e, obsan_fit::FitError::MissingInput(c) if c == "nu"),
        "{e}"
    );
    assert!(e.to_string().contains("no column 'nu'"), "{e}");
}
