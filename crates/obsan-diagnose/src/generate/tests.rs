//! Unit tests of the generated families.

use super::*;
use obsan_model::{Effect, EffectLibrary, System};

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn names(g: &Generation) -> Vec<&str> {
    g.candidates
        .iter()
        .map(|c| c.effect.name.as_str())
        .collect()
}

#[test]
fn mrclam_candidates_skip_what_the_file_has() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    let user: Vec<&Effect> = lib.effects.iter().collect();
    let all = generate(&sys, &[]);
    let g = generate(&sys, &user);
    let n = names(&g);
    // The file's speed and turn scales, turn bias, time offset, bearing
    // bias, range scale and bias are written differently but extend the
    // model in the same way: left out, each said so.
    for dup in [
        "v_scale",
        "omega_scale",
        "omega_bias",
        "inputs_delay",
        "b_bias",
        "r_scale",
        "r_bias",
    ] {
        assert!(
            names(&all).contains(&dup),
            "{dup} generated: {:?}",
            names(&all)
        );
        assert!(!n.contains(&dup), "{dup} kept: {n:?}");
        assert!(g
            .dropped
            .iter()
            .any(|d| d.0 == dup && d.1.contains("effects file")));
    }
    assert!(
        g.dropped.iter().all(|d| d.1.contains("the same as")),
        "{:?}",
        g.dropped
    );
    for new in [
        "v_delay",
        "omega_delay",
        "v_with_abs_omega",
        "omega_with_abs_v",
        "v_lag",
        "v_bias",
        "b_scale",
        "b_sin2",
    ] {
        assert!(n.contains(&new), "{new} missing: {n:?}");
    }
    // docs/diagnose.md's count: the 12 first families' survivors, and the
    // two drifts, the range quadratic and the two groups' biases with th
    // (new_families_follow_the_structure).
    assert_eq!(n.len(), 17, "{n:?}");
    // Grouped by form: one bearing scale for the 15 bearings.
    let bs = g
        .candidates
        .iter()
        .find(|c| c.effect.name == "b_scale")
        .unwrap();
    assert_eq!(bs.effect.outputs.len(), 15);
    let c = g
        .candidates
        .iter()
        .find(|c| c.effect.name == "v_with_abs_omega")
        .unwrap();
    assert_eq!(
        c.words(-0.1),
        "v falls with |omega|: v_eff = v (1 + gc_v_omega |omega|)"
    );
}

#[test]
fn calib_harmonics_and_scale_match_the_file() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let user: Vec<&Effect> = lib.effects.iter().filter(|e| !e.is_input_side()).collect();
    let g = generate(&sys, &user);
    let n = names(&g);
    for dup in ["beta_scale", "beta_bias", "beta_sin2"] {
        assert!(!n.contains(&dup), "{dup} kept: {n:?}");
    }
    for new in [
        "beta_sin1",
        "beta_cos1",
        "beta_cos2",
        "wR_scale",
        "wR_with_abs_wL",
    ] {
        assert!(n.contains(&new), "{new} missing: {n:?}");
    }
}

#[test]
fn new_families_follow_the_structure() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let g = generate(&sys, &[]);
    let n = names(&g);
    // Each wheel's drift and periodic error; the bearing's bias with the
    // only angle state (gamma, inside sin and cos); no quadratic, the
    // only output being an angle.
    for new in [
        "wR_drift",
        "wL_drift",
        "wR_periodic",
        "wL_periodic",
        "beta_bias_with_gamma",
        "own_speed_slip",
    ] {
        assert!(n.contains(&new), "{new} missing: {n:?}");
    }
    assert!(!n.iter().any(|c| c.contains("quadratic")), "{n:?}");
    assert!(!n.iter().any(|c| c.contains("with_mu")), "{n:?}");
    let mrclam = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let g = generate(&mrclam, &[]);
    let n = names(&g);
    // omega is integrated by th itself: body velocities, no periodic
    // error of either; the ranges (not angles) get a quadratic; both
    // groups a bias with th.
    for new in ["v_drift", "r_quadratic", "r_bias_with_th", "b_bias_with_th"] {
        assert!(n.contains(&new), "{new} missing: {n:?}");
    }
    for absent in [
        "v_periodic",
        "omega_periodic",
        "b_quadratic",
        "r_bias_with_x",
        "own_speed_slip",
    ] {
        assert!(!n.contains(&absent), "{absent} generated: {n:?}");
    }
    let q = g
        .candidates
        .iter()
        .find(|c| c.effect.name == "r_quadratic")
        .unwrap();
    assert_eq!(q.effect.outputs.len(), 15);
    assert_eq!(q.limits.len(), 1);
}

#[test]
fn own_speed_slip_scales_each_wheel_by_its_own_speed() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let g = generate(&sys, &[]);
    let c = g
        .candidates
        .iter()
        .find(|c| c.effect.name == "own_speed_slip")
        .unwrap();
    assert_eq!(c.effect.params, ["gs_wR", "gs_wL"]);
    // The same extension written by hand, wR (1 - a |wR|), wL (1 - b |wL|)
    // with |u| as sqrt(u^2), is recognised as it: the signature compares the extended model's
    // right-hand sides numerically, params matched in order.
    let hand = EffectLibrary::parse(
        "effect hand\nparam a, b\ninput hR = sqrt(wR^2)*wR\ninput hL = sqrt(wL^2)*wL\n\
         subst wR = wR - a*hR, wL = wL - b*hL\n",
        "hand.eff",
    )
    .unwrap();
    let user: Vec<&Effect> = hand.effects.iter().collect();
    let g2 = generate(&sys, &user);
    assert!(
        g2.dropped
            .iter()
            .any(|d| d.0 == "own_speed_slip" && d.1.contains("effects file")),
        "{:?}",
        g2.dropped
    );
    assert_eq!(c.limits.len(), 2);
}

#[test]
fn angle_states_are_the_arguments_of_sin_and_cos() {
    let sys = System::parse(
        "system s\nstate x, th, phi\ninput u\nx' = u*cos(2*th)\nth' = u\nphi' = u*x\noutput y = x + phi\n",
        "s.sys",
    )
    .unwrap();
    assert_eq!(families::angle_states(&sys), vec!["th".to_string()]);
}

#[test]
fn limits_read_the_session_and_the_outputs() {
    use obsan_data::{Dataset, DatasetMeta, Series, Trajectory};
    let mut inputs = Series::new(vec!["u".into()]);
    let mut outputs = Series::new(vec!["y".into()]);
    for k in 0..=10 {
        inputs.push(10.0 + k as f64 * 10.0, &[Some(1.0)]);
        outputs.push(10.0 + k as f64 * 10.0, &[Some(2.0 + k as f64 / 10.0)]);
    }
    let data = Dataset {
        meta: DatasetMeta::default(),
        trajectories: vec![Trajectory {
            name: "a".into(),
            inputs,
            outputs,
            meta: Default::default(),
        }],
    };
    // Session 100 s: a drift of 0.004 /s changes the scale by 0.4 (kept),
    // 0.006 /s by 0.6 (refused).
    let drift = Limit {
        param: "d".into(),
        bound: 0.5,
        per_second: true,
        columns: None,
        what: "the change".into(),
    };
    let est = |v: f64| vec![("d".to_string(), v, 0.001)];
    assert!(drift.violated(&est(0.004), &data).is_none());
    assert!(drift.violated(&est(-0.006), &data).is_some());
    // Readings 2..3: a quadratic c = 0.2 is 0.6 of the largest (refused),
    // c = 0.1 is 0.3 (kept); a bias 0.4 is 0.4 of the spread 1 (kept).
    let quad = Limit {
        columns: Some((vec!["y".into()], Reading::MaxAbs)),
        per_second: false,
        ..drift.clone()
    };
    assert!(quad.violated(&est(0.2), &data).is_some());
    assert!(quad.violated(&est(0.1), &data).is_none());
    let bias = Limit {
        columns: Some((vec!["y".into()], Reading::Spread)),
        ..quad.clone()
    };
    assert!(bias.violated(&est(0.4), &data).is_none());
    assert!(bias.violated(&est(f64::NAN), &data).is_some());
    // A measured input is read when no output has the name: u = 1
    // throughout, so a slip s = 0.6 is 0.6 of it (refused), 0.4 kept.
    let slip = Limit {
        columns: Some((vec!["u".into()], Reading::MaxAbs)),
        ..quad.clone()
    };
    assert!(slip.violated(&est(0.6), &data).is_some());
    assert!(slip.violated(&est(-0.4), &data).is_none());
}
