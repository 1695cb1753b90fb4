//! `obsan global`: counts derived by hand in systems/global/*.sys, published
//! verdicts (StructuralIdentifiability.jl) and the errors a user meets.

use crate::util::*;
use serde_json::Value;

fn global_json(file: &str) -> Value {
    serde_json::from_str(&ok(&["global", file, "--json"])).unwrap()
}

/// (verdict, values) of a variable.
fn var(v: &Value, name: &str) -> (String, Option<u64>) {
    let x = v["variables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["name"] == name)
        .unwrap_or_else(|| panic!("no variable {name}"));
    (
        x["verdict"].as_str().unwrap().to_string(),
        x["values"].as_u64(),
    )
}

#[test]
fn squared_rate_sign_ambiguity() {
    // Hand derivation in the file: y'/y = -a^2, so a = ±sqrt(-y'/y); x(0) = y(0).
    let v = global_json("systems/global/squared_rate.sys");
    assert_eq!(var(&v, "a"), ("local".into(), Some(2)));
    assert_eq!(var(&v, "x"), ("global".into(), Some(1)));
    assert_eq!(v["solutions"], 2);
    assert_eq!(v["maps"][0], "a -> -a");
    // Text output names the map too.
    let t = ok(&["global", "systems/global/squared_rate.sys"]);
    assert!(t.contains("a -> -a"), "{t}");
    assert!(t.contains("locally identifiable, 2 values"), "{t}");
}

#[test]
fn two_decays_swap_and_single_decay() {
    let v = global_json("systems/global/two_decays.sys");
    for n in ["a", "b", "x1", "x2"] {
        assert_eq!(var(&v, n), ("local".into(), Some(2)), "{n}");
    }
    assert_eq!(v["maps"][0], "(x1, x2, a, b) -> (x2, x1, b, a)");
    assert_eq!(v["group_order"], 2);
    let s = global_json("systems/global/single_decay.sys");
    assert_eq!(s["solutions"], 1);
    assert_eq!(var(&s, "a"), ("global".into(), Some(1)));
}

#[test]
fn structural_identifiability_jl_readme() {
    // Published (SI.jl README): a01, a12, x1 locally; a21, x2 globally;
    // b, x3 not identifiable. (a01 and a12 come as a pair: 2 values each.)
    let v = global_json("systems/benchmarks/si_readme.sys");
    for n in ["a01", "a12", "x1"] {
        assert_eq!(var(&v, n), ("local".into(), Some(2)), "{n}");
    }
    for n in ["a21", "x2"] {
        assert_eq!(var(&v, n), ("global".into(), Some(1)), "{n}");
    }
    for n in ["b", "x3"] {
        assert_eq!(var(&v, n).0, "not identifiable", "{n}");
    }
}

#[test]
fn global_refuses_what_it_cannot_count() {
    // An angle outside sin/cos elsewhere than as a whole output (here in a
    // product with a state): not rational in the half-angle view. (An output
    // that is the angle itself is counted: `angles_measured_directly`.)
    let bare = temp_file(
        "global_bare_angle.sys",
        "system b\nstate th, x\ninput om\nth' = om\nx' = cos(th)\noutput y = x*th\n",
    );
    bad(&["global", &bare], "occurs outside sin/cos");
    let half = temp_file(
        "global_half_angle.sys",
        "system h\nstate x\nparam k, th\nx' = -k*x\noutput y = x*sin(th/2)\n",
    );
    bad(&["global", &half], "unit other than 1");
    // A function of a state times a state: no one-to-one reading.
    let at = temp_file(
        "global_atan.sys",
        "system a\nstate x\nparam k\nx' = -k*x\noutput y = x*atan(x)\n",
    );
    bad(&["global", &at], "not a plain symbol");
    bad(&["global", "systems/global/missing.sys"], "missing.sys");
}

#[test]
fn per_output_orders_and_bounds() {
    // x' = -a^2 x, y = x with theta = (a, x0): rows y (0, 1) and
    // y' = -a^2 x0 (-2 a x0, -a^2) are independent (rank 2 = full), so y'' is
    // the first dependent row: order 2.
    let v = global_json("systems/global/squared_rate.sys");
    assert_eq!(v["output_orders"][0]["output"], "y");
    assert_eq!(v["output_orders"][0]["order"], 2);
    // SIAN's D1 = (s + 1) 2 d0 s (n + 1)(1 + 2 d0 s) with n = 1, s = 2 and
    // d0 = deg(-a^2 x) = 3: 3 * 2 * 3 * 2 * 2 * 13 = 936.
    assert_eq!(v["degree_bound_local"], 936.0);
    let e = v["error_bound"].as_f64().unwrap();
    assert!(e > 0.0 && e < 1e-20, "{e}");
    let t = ok(&["global", "systems/global/squared_rate.sys"]);
    assert!(t.contains("y to order 2"), "{t}");
    assert!(t.contains("wrong with probability <="), "{t}");
    // angle_mod_pi: order 0 gives x0 (y1) and theta (y2); order 1 gives k from
    // y1' = -k x while y2' = 0 is dependent: y2 stops at 1, y1 at 2.
    let a = global_json("systems/global/angle_mod_pi.sys");
    assert_eq!(a["output_orders"][0]["order"], 2);
    assert_eq!(a["output_orders"][1]["order"], 1);
}

#[test]
fn angle_known_modulo_pi_against_atan2() {
    // Derived by hand in the files (trig form, counted as t = tan(theta/2)):
    // tan(theta) is the same at theta and theta + pi: 2 values; cos and sin
    // together fix theta modulo 2 pi: 1 value.
    let v = global_json("systems/global/angle_mod_pi.sys");
    assert_eq!(var(&v, "theta"), ("local".into(), Some(2)));
    assert_eq!(var(&v, "k"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "x"), ("global".into(), Some(1)));
    assert_eq!(v["solutions"], 2);
    let theta = v["variables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["name"] == "theta")
        .unwrap();
    assert_eq!(theta["angle"], true);
    let w = global_json("systems/global/angle_atan2.sys");
    assert_eq!(var(&w, "theta"), ("global".into(), Some(1)));
    assert_eq!(w["solutions"], 1);
    let t = ok(&["global", "systems/global/angle_mod_pi.sys"]);
    assert!(
        t.contains("theta") && t.contains("counted modulo 2 pi"),
        "{t}"
    );
}

#[test]
fn bearing_only_mirror() {
    // Derived by hand in the file: cos(beta) gives beta up to sign, and
    // r = -v (1 - y^2)/y'; the mirror beta -> -beta maps the model to itself.
    let v = global_json("systems/global/bearing_mirror.sys");
    assert_eq!(var(&v, "beta"), ("local".into(), Some(2)));
    assert_eq!(var(&v, "r"), ("global".into(), Some(1)));
    assert_eq!(v["solutions"], 2);
    assert_eq!(v["maps"][0], "beta -> -beta");
    assert_eq!(v["group_order"], 2);
}

#[test]
fn the_memory_budget_stops_the_groebner_stage() {
    // SI.jl's HIV: its Taylor system fits 1,000 units (2,000 KiB), its F4
    // matrices do not (counted in bytes, so the stage is named whatever
    // the machine's speed; each of the two parallel runs then retries alone
    // with the whole budget, so the message names it). (llw1987 at 60 units
    // was this test until session 33; HIV's basis is the larger, 0.05 s.)
    let e = bad(
        &[
            "global",
            "systems/benchmarks/si-jl/HIV.sys",
            "--max-terms",
            "1000",
            "--route",
            "taylor",
        ],
        "too large: the Groebner basis (F4 matrix of ",
    );
    assert!(e.contains("the memory budget is 1 MiB"), "{e}");
    assert!(e.contains("raise it with --max-terms"), "{e}");
    assert!(!e.contains("timed out"), "{e}");
    // The Taylor system, before any basis: at --max-terms 100 (200 KiB)
    // chemostat's derivatives do not fit; every monomial holds an exponent
    // for each of the derivation ring's variables (the params, and 27
    // Taylor orders of each state, denominator state and input).
    let e = bad(
        &[
            "global",
            "systems/benchmarks/chemostat.sys",
            "--max-terms",
            "100",
            "--route",
            "taylor",
        ],
        "too large: the Taylor system (derivatives of the right-hand sides and outputs",
    );
    assert!(e.contains("raise it with --max-terms"), "{e}");
}

#[test]
fn range_only_unicycles() {
    // Derived by hand in the files. Turning: bx = -y'/(2v), by from y''
    // (w != 0): one solution. Straight: by known only up to sign, and the
    // mirror by -> -by maps the model to itself.
    let v = global_json("systems/global/range_only_unicycle.sys");
    assert_eq!(var(&v, "bx"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "by"), ("global".into(), Some(1)));
    assert_eq!(v["solutions"], 1);
    let v = global_json("systems/global/range_only_straight.sys");
    assert_eq!(var(&v, "bx"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "by"), ("local".into(), Some(2)));
    assert_eq!(v["solutions"], 2);
    assert_eq!(v["maps"][0], "by -> -by");
    assert_eq!(v["group_order"], 2);
    // World frame: the rotation about the beacon leaves nothing identifiable;
    // a compass (cos and sin of the heading) breaks it and fixes p0 linearly.
    let v = global_json("systems/global/range_only_world.sys");
    for x in ["x", "y", "theta"] {
        assert_eq!(var(&v, x), ("not identifiable".into(), None), "{x}");
    }
    let t = ok(&["global", "systems/global/range_only_world.sys"]);
    assert!(t.contains("no variable is locally identifiable"), "{t}");
    let v = global_json("systems/global/range_compass_world.sys");
    for x in ["x", "y", "theta"] {
        assert_eq!(var(&v, x), ("global".into(), Some(1)), "{x}");
    }
    assert_eq!(v["solutions"], 1);
}

/// StructuralIdentifiability.jl's own published global verdicts (its test of
/// `assess_identifiability`, test/bodies/identifiability.jl; the models written
/// from its equations in systems/global/sijl_tests/, the expected verdicts in
/// each file's `# global:` line, copied from that test). Every file is either
/// answered with exactly those verdicts or refused with a budget error (exit 2,
/// never a count); the small ones must be answered.
#[test]
fn structural_identifiability_jl_test_verdicts() {
    let dir = "systems/global/sijl_tests";
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path().to_string_lossy().into_owned())
        .filter(|p| p.ends_with(".sys"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    let mut answered = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let spec = text
            .lines()
            .find_map(|l| l.strip_prefix("# global:"))
            .unwrap_or_else(|| panic!("{f}: no '# global:' line"));
        let run = obsan(&["global", f, "--json"]);
        if run.code == 2 && run.stderr.contains("too large") {
            continue;
        }
        assert_eq!(run.code, 0, "{f}: {}", run.stderr);
        let v: Value = serde_json::from_str(&run.stdout).unwrap();
        for part in spec.split(';') {
            let mut words = part.split_whitespace();
            let want = match words.next() {
                Some("globally") => "global",
                Some("locally") => "local",
                Some("nonidentifiable") => "not identifiable",
                w => panic!("{f}: unknown verdict {w:?}"),
            };
            for name in words {
                assert_eq!(var(&v, name).0, want, "{f}: {name}");
            }
        }
        answered += 1;
    }
    // Goodwin and SIWR need more than the default memory budget
    // (docs/performance.md, "Seventh round").
    assert!(answered >= 8, "{answered} of {} answered", files.len());
}

/// An output that is an integer combination of angles (a compass, a joint
/// encoder) is counted through the half-angle tangent of its part divided by
/// the multiples' gcd (docs/engine.md); each expectation is derived by hand
/// in its file.
#[test]
fn angles_measured_directly() {
    // The pendulum of the benchmark suite, y = th: om = y', and
    // om' = -a sin(th) - c om + e u is linear in (a, c, e) with generic
    // regressors: everything has 1 value.
    let v = global_json("systems/benchmarks/pendulum.sys");
    for n in ["a", "c", "e", "th", "om"] {
        assert_eq!(var(&v, n), ("global".into(), Some(1)), "{n}");
    }
    let v = global_json("systems/global/double_angle_encoder.sys");
    assert_eq!(var(&v, "theta"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "x"), ("global".into(), Some(1)));
    let v = global_json("systems/global/relative_angle.sys");
    assert_eq!(var(&v, "k"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "w2"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "th1").0, "not identifiable");
    assert_eq!(var(&v, "th2").0, "not identifiable");
}

#[test]
fn outputs_through_sqrt_atan_and_atan2() {
    // atan and sqrt are one-to-one: y = atan(x) of x' = -k x fixes x(0) = tan
    // y(0) and k = -x'/x, as y = x would: both global (counted through the
    // argument).
    let at = temp_file(
        "global_atan_ok.sys",
        "system a\nstate x\nparam k\nx' = -k*x\noutput y = atan(x)\n",
    );
    let v = global_json(&at);
    assert_eq!(var(&v, "k"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "x"), ("global".into(), Some(1)));
    assert_eq!(v["output_forms"][0]["counted_as"], "atan argument");
    // Hand derivations in the files.
    let v = global_json("systems/global/landmark_polar.sys");
    for n in ["lx", "ly"] {
        assert_eq!(var(&v, n), ("global".into(), Some(1)), "{n}");
    }
    assert_eq!(v["solutions"], 1);
    assert_eq!(v["solutions_at_most"], false);
    assert_eq!(v["output_forms"][0]["counted_as"], "tangent");
    assert_eq!(v["output_forms"][1]["counted_as"], "sqrt argument");
    // l -> -l keeps the tangent and turns the bearing by pi.
    assert_eq!(v["maps"].as_array().unwrap().len(), 0);
    assert_eq!(v["maps_modulo_pi"][0], "(lx, ly) -> (-lx, -ly)");
    let v = global_json("systems/global/bearing_atan2_compass_mod_pi.sys");
    for n in ["x", "y", "theta"] {
        assert_eq!(var(&v, n), ("local".into(), Some(2)), "{n}");
    }
    assert_eq!(v["solutions"], 2);
    assert_eq!(v["solutions_at_most"], false);
    assert_eq!(v["maps"][0], "(x, y, theta) -> (-x, -y, theta + pi)");
    let t = ok(&["global", "systems/global/bearing_atan2_compass_mod_pi.sys"]);
    assert!(
        t.contains("x      state  locally identifiable, 2 values"),
        "{t}"
    );
    let v = global_json("systems/global/bearing_of_a_quadratic.sys");
    assert_eq!(var(&v, "k"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "s"), ("global".into(), Some(1)));
    assert_eq!(var(&v, "x"), ("local".into(), Some(2)));
    let x = v["variables"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["name"] == "x")
        .unwrap();
    assert_eq!(x["at_most"], true);
    assert_eq!(v["solutions_at_most"], true);
    let t = ok(&["global", "systems/global/bearing_of_a_quadratic.sys"]);
    assert!(t.contains("at most 2 values"), "{t}");
}
