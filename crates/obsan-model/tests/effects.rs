//! Effect libraries: every shipped effect extends its model into a valid
//! system, the extension round-trips through text, and bad files get
//! positioned errors.

use obsan_expr::Q;
use obsan_model::{Effect, EffectLibrary, Kind, Start, System};

fn read(p: &str) -> String {
    std::fs::read_to_string(format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn every_calib_effect_extends_calib() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    lib.check(&sys).unwrap();
    for want in [
        "time_offset",
        "bearing_scale",
        "bearing_distortion",
        "wheel_slip",
        "radius_change",
        "bearing_bias",
        "commanded_ratio",
    ] {
        assert!(lib.get(want).is_some(), "{want} missing");
    }
    let e = lib.get("time_offset").unwrap();
    let ext = sys.extend(&[e], "calib.eff").unwrap();
    // Old params first, the new one last.
    let params: Vec<&str> = ext.decls_of(Kind::Param).map(|d| d.name.as_str()).collect();
    assert_eq!(params, ["phi", "psi", "eta", "delta", "xi", "tau"]);
    // The time offset is a delay of the inputs by the new param.
    assert_eq!(ext.delay.as_deref(), Some("tau"));
    let nf = ext.normal_form(None, &[]).unwrap();
    assert_eq!(nf.delay, Some(7));
    // Text round trip: same text again, and the restriction survives.
    let again = System::parse(&ext.to_sys_text(), "again.sys").unwrap();
    assert_eq!(again.to_sys_text(), ext.to_sys_text());
    assert!(again.restriction("q").is_some());
    assert_eq!(again.delay.as_deref(), Some("tau"));
    // Two effects at once.
    let both = sys
        .extend(
            &[
                lib.get("bearing_scale").unwrap(),
                lib.get("bearing_bias").unwrap(),
            ],
            "calib.eff",
        )
        .unwrap();
    let out = both.rhs_text("beta").unwrap();
    assert!(out.contains("kb") && out.contains("+ b"), "{out}");
}

#[test]
fn extended_output_keeps_the_nominal_value_at_zero() {
    // With the new param at 0 the extended output equals the nominal one
    // (modulo 2 pi: the scale effect wraps beta into (-pi, pi]).
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/calib.eff"), "calib.eff").unwrap();
    let base = sys.normal_form(None, &[]).unwrap();
    let tb = obsan_expr::Tape::compile(&base.ctx, &[base.outputs[0].1], &base.state_vars).unwrap();
    for name in ["bearing_scale", "bearing_distortion", "bearing_bias"] {
        let ext = sys.extend(&[lib.get(name).unwrap()], "calib.eff").unwrap();
        let nf = ext.normal_form(None, &[]).unwrap();
        let te = obsan_expr::Tape::compile(&nf.ctx, &[nf.outputs[0].1], &nf.state_vars).unwrap();
        for k in 0..20 {
            let x = k as f64;
            let s = [0.3 + 0.02 * x, 0.7 * x, 0.1, 1.2 + 0.1 * x, 0.2, 1.0, 0.6];
            let mut se = s.to_vec();
            se.push(0.0);
            let d = te.eval(&se)[0] - tb.eval(&s)[0];
            let d = d - (d / std::f64::consts::TAU).round() * std::f64::consts::TAU;
            assert!(d.abs() < 1e-12, "{name}: {d}");
        }
    }
}

/// Each (source, place, words) is refused with a message holding both.
fn rejected(sys: &System, origin: &str, cases: &[(&str, &str, &str)]) {
    for (src, at, what) in cases {
        let r = EffectLibrary::parse(src, origin).and_then(|l| l.check(sys));
        let msg = r.expect_err(src).to_string();
        assert!(msg.contains(at) && msg.contains(what), "{src:?}: {msg}");
    }
}

#[test]
fn bad_effect_files_name_the_line() {
    let sys = System::parse(&read("systems/calib.sys"), "calib.sys").unwrap();
    let cases = [
        ("param x\n", "calib.eff:1:1", "before any 'effect"),
        ("effect a\nparam phi\n", "calib.eff:1", "already a name"),
        (
            "effect a\nparam k\nsubst vv = k\n",
            "calib.eff:1",
            "not an input",
        ),
        (
            "effect a\nparam k\noutput zz = k\n",
            "calib.eff:1",
            "not an output",
        ),
        (
            "effect a\nparam k\noutput beta = beta + k*nope\n",
            "calib.eff:1",
            "nope",
        ),
        ("effect a\nfrobnicate\n", "calib.eff:2:1", "expected one of"),
        ("effect a\neffect a\n", "calib.eff:2:1", "twice"),
        (
            "model other\neffect a\nparam k\noutput beta = beta + k\n",
            "calib.eff",
            "not 'calib'",
        ),
    ];
    rejected(&sys, "calib.eff", &cases);
}

#[test]
fn derived_inputs_are_checked() {
    let base = "system d\nstate x\ninput u\nx' = u*x\noutput y = x\n";
    for (decl, ok) in [
        ("input du = rate(u)\n", true),
        ("input a = sqrt(u^2)*u\n", true),
        ("input du = rate(x)\n", false),
        ("input a = x*u\n", false),
        // A rate of an earlier rate input is the next derivative; of a later
        // one, or of an expression input, it is refused.
        ("input du = rate(u)\ninput ddu = rate(du)\n", true),
        ("input ddu = rate(du)\ninput du = rate(u)\n", false),
        ("input a = 2*u\ninput b = rate(a)\n", false),
    ] {
        let r = System::parse(&format!("{base}{decl}"), "d.sys");
        assert_eq!(r.is_ok(), ok, "{decl}: {r:?}");
    }
}

#[test]
fn descriptions_are_one_line_of_free_text() {
    // Regression: a description ending with ',' swallowed the next
    // 'description' line, and one with an unclosed '(' the rest of the file.
    let src = "system d\ndescription about a feature at the origin,\ndescription with a range (in (-pi, pi]\nstate x\ninput u\nx' = u\noutput y = x\n";
    let s = System::parse(src, "d.sys").unwrap();
    assert_eq!(
        s.description,
        "about a feature at the origin, with a range (in (-pi, pi]"
    );
}

#[test]
fn every_mrclam_effect_extends_mrclam() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    lib.check(&sys).unwrap();
    let names: Vec<&str> = lib.effects.iter().map(|e| e.name.as_str()).collect();
    for want in [
        "speed_scale",
        "turn_scale",
        "turn_bias",
        "time_offset",
        "bearing_bias",
        "range_scale",
        "range_bias",
        "actuator_lag",
    ] {
        assert!(names.contains(&want), "{want}");
    }
}

#[test]
fn an_effect_can_add_states_with_start_values() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    let e = lib.get("actuator_lag").unwrap();
    let ext = sys.extend(&[e], "mrclam.eff").unwrap();
    let states: Vec<&str> = ext.decls_of(Kind::State).map(|d| d.name.as_str()).collect();
    assert_eq!(states, ["x", "y", "th", "va", "wa"]);
    let start = |n: &str| {
        ext.decls
            .iter()
            .find(|d| d.name == n)
            .and_then(|d| d.start.clone())
    };
    assert_eq!(start("va"), Some(Start::Inputs("v".into())));
    assert_eq!(start("T"), Some(Start::Number(Q::new(1.into(), 5.into()))));
    // `subst` rewrote the model's dynamics, not the new states' equations
    // (they see the commanded inputs).
    assert_eq!(ext.rhs_text("x"), Some("(va)*cos(th)"));
    assert_eq!(ext.rhs_text("va"), Some("(v - va)/T"));
    // Input-affine with a drift: va' = -va/T + v/T.
    let nf = ext.normal_form(None, &[]).unwrap();
    assert_eq!(nf.n_dynamic, 5);
    // The text round trip keeps the start values.
    let again = System::parse(&ext.to_sys_text(), "again.sys").unwrap();
    assert_eq!(again.to_sys_text(), ext.to_sys_text());
    assert!(ext
        .to_sys_text()
        .contains("state x, y, th, va = v, wa = omega"));
}

#[test]
fn new_states_are_checked() {
    let sys = System::parse(&read("systems/mrclam.sys"), "mrclam.sys").unwrap();
    let cases = [
        (
            "effect a\nstate z\nparam k\n",
            "a.eff:1",
            "needs an equation z' = ...",
        ),
        ("effect a\nstate th\nth' = 0\n", "a.eff:1", "already a name"),
        ("effect a\nstate z = x\nz' = -z\n", "a.eff:1", "not 'x'"),
        (
            "effect a\nparam k = v\nsubst v = k*v\n",
            "a.eff:1",
            "must be a number",
        ),
        ("effect a\nstate 2z\n", "a.eff:2:1", "not a valid name"),
    ];
    rejected(&sys, "a.eff", &cases);
}

#[test]
fn the_pose_model_shares_mrclams_odometry_effects() {
    let pose = System::parse(&read("systems/mrclam-pose.sys"), "mrclam-pose.sys").unwrap();
    let lib = EffectLibrary::parse(&read("systems/mrclam-pose.eff"), "mrclam-pose.eff").unwrap();
    lib.check(&pose).unwrap();
    let full = EffectLibrary::parse(&read("systems/mrclam.eff"), "mrclam.eff").unwrap();
    for e in &lib.effects {
        let f = full.get(&e.name).unwrap();
        // The same effect, wherever it sits in its file.
        assert_eq!(
            Effect {
                line: 0,
                ..e.clone()
            },
            Effect {
                line: 0,
                ..f.clone()
            },
            "{}",
            e.name
        );
    }
    assert_eq!(lib.effects.len(), 5);
}
