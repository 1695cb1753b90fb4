//! Hand-derived cases of the count (each derivation beside its test).

use super::*;
use obsan_model::System;

fn report(src: &str) -> GlobalReport {
    let sys = System::parse(&format!("system t\n{src}"), "t.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    global_identifiability(&mut nf, &GlobalOptions::default()).unwrap()
}

fn verdict(r: &GlobalReport, name: &str) -> Identifiability {
    r.variables.iter().find(|v| v.name == name).unwrap().verdict
}

#[test]
fn single_decay_is_global() {
    // x' = -a x, y = x: y(0) = x0, y'(0) = -a x0, so a = -y'/y: unique.
    let r = report("state x\nparam a\nx' = -a*x\noutput y = x\n");
    assert_eq!(verdict(&r, "a"), Identifiability::Global);
    assert_eq!(verdict(&r, "x"), Identifiability::Global);
    assert_eq!(r.solutions, Some(1));
    assert!(r.maps.is_empty());
}

#[test]
fn squared_rate_has_two_values() {
    // x' = -a^2 x, y = x: y'/y = -a^2 fixes a only up to sign; x0 = y(0).
    let r = report("state x\nparam a\nx' = -a^2*x\noutput y = x\n");
    assert_eq!(verdict(&r, "a"), Identifiability::Local(2));
    assert_eq!(verdict(&r, "x"), Identifiability::Global);
    assert_eq!(r.solutions, Some(2));
    assert_eq!(r.maps.len(), 1);
    assert_eq!(r.maps[0].to_string(), "a -> -a");
    assert_eq!(r.group_order, 2);
}

#[test]
fn two_decays_swap() {
    // y = x1 e^{-a t} + x2 e^{-b t}: the exponents and amplitudes are
    // known as an unordered pair {(a, x1), (b, x2)}: 2 values each, and
    // the swap maps one to the other.
    let r = report("state x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n");
    for v in ["a", "b", "x1", "x2"] {
        assert_eq!(verdict(&r, v), Identifiability::Local(2), "{v}");
    }
    assert_eq!(r.solutions, Some(2));
    assert_eq!(r.maps.len(), 1);
    assert_eq!(r.maps[0].to_string(), "(x1, x2, a, b) -> (x2, x1, b, a)");
    assert_eq!(r.group_order, 2);
}

#[test]
fn unidentifiable_product() {
    // x' = -a b x, y = c x... here y = x, x' = a*b*x: only a*b is seen;
    // a and b take infinitely many values, x0 = y(0) is global.
    let r = report("state x\nparam a, b\nx' = a*b*x\noutput y = x\n");
    assert_eq!(verdict(&r, "a"), Identifiability::NotIdentifiable);
    assert_eq!(verdict(&r, "b"), Identifiability::NotIdentifiable);
    assert_eq!(verdict(&r, "x"), Identifiability::Global);
    assert!(!r.all_local);
    // Jointly only x is locally identifiable: one value.
    assert_eq!(r.solutions, Some(1));
}

fn file_report(rel: &str) -> GlobalReport {
    let path = format!("{}/../../systems/{rel}", env!("CARGO_MANIFEST_DIR"));
    let src = std::fs::read_to_string(path).unwrap();
    let sys = System::parse(&src, rel).unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    global_identifiability(&mut nf, &GlobalOptions::default()).unwrap()
}

#[test]
fn hiv_xia_moog_swaps_delta_and_c() {
    // Derived by hand: T' = s - d T - beta T V gives s, d, beta; with
    // V' = p I - c V and I' = beta T V - delta I,
    // V'' + (delta + c) V' + delta c V = p beta T V: the outputs see p and
    // only delta + c and delta c, so (delta, c) is an unordered pair (2
    // values each) and I = (V' + c V)/p takes 2 values; the rest is global.
    let r = file_report("classic/hiv.sys");
    for v in ["delta", "c", "I"] {
        assert_eq!(verdict(&r, v), Identifiability::Local(2), "{v}");
    }
    for v in ["s", "d", "beta", "p", "T", "V"] {
        assert_eq!(verdict(&r, v), Identifiability::Global, "{v}");
    }
    assert_eq!(r.solutions, Some(2));
    // Over parameters and states no signed permutation (I moves by an
    // affine map): none is claimed. On the parameters the swap of delta and
    // c keeps delta + c and delta c, so the relations' map is given, as a
    // map of the parameters alone.
    let maps: Vec<String> = r.maps.iter().map(|m| m.to_string()).collect();
    assert_eq!(maps, ["(delta, c) -> (c, delta)"]);
    assert!(r.maps.iter().all(|m| m.params_only));
    assert_eq!(r.group_order, 2);
}

#[test]
fn llw1987_published_pair() {
    // Published (SI.jl tutorial "Globally identifiable functions"): the
    // identifiable functions are p1 + p3, p2 p4, p1 p3: p1 and p3 are an
    // unordered pair (2 values each), p2, p4, x1, x2 not identifiable.
    let r = file_report("benchmarks/llw1987.sys");
    assert_eq!(verdict(&r, "p1"), Identifiability::Local(2));
    assert_eq!(verdict(&r, "p3"), Identifiability::Local(2));
    for v in ["p2", "p4", "x1", "x2"] {
        assert_eq!(verdict(&r, v), Identifiability::NotIdentifiable, "{v}");
    }
    assert_eq!(r.solutions, Some(2));
}

#[test]
fn rational_model_clears_denominators() {
    // x' = -x/(a + x)... y = x: y' = -y/(a + y) gives a = -y - y/y'
    // uniquely (Michaelis-Menten-like elimination by hand).
    let r = report("state x\nparam a\nx' = -x/(a + x)\noutput y = x\n");
    assert_eq!(verdict(&r, "a"), Identifiability::Global);
    assert_eq!(verdict(&r, "x"), Identifiability::Global);
}

#[test]
fn angle_maps_beyond_signed_permutations() {
    // Each derived by hand in its file (systems/global/): the map is checked
    // exactly on the equations and generates every counted solution.
    for (file, map) in [
        ("global/angle_mod_pi.sys", "theta -> theta + pi"),
        ("global/line_direction.sys", "theta -> theta + pi"),
        (
            "global/bearing_heading_mod_pi.sys",
            "(x, y, theta) -> (-x, -y, theta + pi)",
        ),
        (
            "global/wall_reflection.sys",
            "(x, theta) -> (-x, pi - theta)",
        ),
        ("global/bearing_mirror.sys", "beta -> -beta"),
    ] {
        let r = file_report(file);
        assert_eq!(r.solutions, Some(2), "{file}");
        assert_eq!(r.maps.len(), 1, "{file}");
        assert_eq!(r.maps[0].to_string(), map, "{file}");
        assert_eq!(r.group_order, 2, "{file}");
    }
    let r = file_report("global/wall_reflection.sys");
    assert_eq!(verdict(&r, "y"), Identifiability::Global);
    assert_eq!(verdict(&r, "theta"), Identifiability::Local(2));
}

#[test]
fn memory_errors_use_the_engines_words() {
    // The same text as the engine's other stages for the same numbers.
    let engine = obsan_expr::Limit::Memory {
        bytes: 3 << 20,
        max: 2 << 20,
        what: "the Groebner basis",
    };
    let ours = types::too_large(3 << 20, 2 << 20, "the Groebner basis");
    assert_eq!(ours.to_string(), engine.to_string());
}

#[test]
fn a_small_memory_budget_stops_the_count() {
    // Two summed decays (counted above under the default budget). In the
    // derivation ring's 2 + 2 * 27 = 56 variables a term takes 32 + 240
    // bytes, and the Taylor system to order 4 has 9 derivatives of one or two
    // terms: more than 4 KiB, so it must refuse, never count.
    let sys = System::parse(
        "system t\nstate x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n",
        "t.sys",
    )
    .unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    // The Taylor route's budget (auto would fall back on the io route).
    let opts = GlobalOptions {
        max_bytes: 4 << 10,
        route: Route::Taylor,
        ..GlobalOptions::default()
    };
    let e = global_identifiability(&mut nf, &opts)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("too large: the "), "{e}");
    assert!(e.ends_with("raise it with --max-terms"), "{e}");
}

/// The report of `src` with SIAN's weights on or off.
fn report_weighted(src: &str, weighted: bool) -> GlobalReport {
    let sys = System::parse(&format!("system t\n{src}"), "t.sys").unwrap();
    let mut nf = sys.normal_form(None, &[]).unwrap();
    let opts = GlobalOptions {
        weighted,
        ..GlobalOptions::default()
    };
    global_identifiability(&mut nf, &opts).unwrap()
}

#[test]
fn a_rational_rate_is_counted_through_its_cleared_equation() {
    // x' = -a^2 x/(1 + x), y = x: y'/y = -a^2/(1 + y) fixes a^2, so a takes
    // 2 values (a -> -a maps one to the other) and x0 = y(0) is global. The
    // denominator is cleared as SIAN does, (1 + x) x' + a^2 x = 0.
    let r = report("state x\nparam a\nx' = -a^2*x/(1 + x)\noutput y = x\n");
    assert_eq!(verdict(&r, "a"), Identifiability::Local(2));
    assert_eq!(verdict(&r, "x"), Identifiability::Global);
    assert_eq!(r.solutions, Some(2));
    assert_eq!(r.maps.len(), 1);
    assert_eq!(r.maps[0].to_string(), "a -> -a");
    // A rational output: y = x/(1 + b), x' = -a x. y'/y = -a fixes a; x0 and
    // b are seen only through x0/(1 + b): not identifiable.
    let r = report("state x\nparam a, b\nx' = -a*x\noutput y = x/(1 + b)\n");
    assert_eq!(verdict(&r, "a"), Identifiability::Global);
    assert_eq!(verdict(&r, "b"), Identifiability::NotIdentifiable);
    assert_eq!(verdict(&r, "x"), Identifiability::NotIdentifiable);
}

#[test]
fn weights_change_no_count() {
    // SIAN's weighted order only reorders the Gröbner computation
    // (weights.rs): every verdict, count and map must be the same without
    // it, on hand-derived cases, a rational one and two-level chains whose
    // states get weights 1, 2 and 3.
    let cases = [
        "state x\nparam a\nx' = -a^2*x\noutput y = x\n",
        "state x1, x2\nparam a, b\nx1' = -a*x1\nx2' = -b*x2\noutput y = x1 + x2\n",
        "state x\nparam a\nx' = -a^2*x/(1 + x)\noutput y = x\n",
        "state x1, x2, x3\nparam a, b, c\nx1' = -a*x1 + x2\nx2' = -b^2*x2 + x3\nx3' = -c*x3\noutput y = x1\n",
        "state x1, x2\nparam k12, k21, k1\nx1' = -(k12 + k1)*x1 + k21*x2\nx2' = k12*x1 - k21*x2\noutput y = x1\n",
    ];
    for src in cases {
        let a = report_weighted(src, true);
        let b = report_weighted(src, false);
        assert_eq!(a.solutions, b.solutions, "{src}");
        let va: Vec<_> = a.variables.iter().map(|v| (&v.name, v.verdict)).collect();
        let vb: Vec<_> = b.variables.iter().map(|v| (&v.name, v.verdict)).collect();
        assert_eq!(va, vb, "{src}");
        assert_eq!(a.maps, b.maps, "{src}");
    }
}

#[test]
fn kept_runs_count_as_fresh_ones() {
    // `--route auto` keeps the Taylor runs' derivatives from one attempt to
    // the next (`Prolonged`): an attempt stopped by the work bound after
    // deriving, then an unbounded one on the kept runs, must count exactly
    // as fresh runs do (Bilirubin's basis needs ~3e7 units, so 1e3 stops it).
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/benchmarks/si-jl/Bilirubin.sys"
    );
    let src = std::fs::read_to_string(path).unwrap();
    let mut nf = System::parse(&src, path)
        .unwrap()
        .normal_form(None, &[])
        .unwrap();
    let m = zmodel(&mut nf).unwrap();
    let primes = [obsan_recon::PRIMES[0], obsan_recon::PRIMES[1]];
    let opts = GlobalOptions::default();
    let kmax = opts.max_order + 2;
    let key = |c: &count::Counts| {
        (
            c.per_var.clone(),
            c.joint,
            c.orders.clone(),
            c.unknowns,
            c.equations,
            c.degrees.clone(),
        )
    };
    let fresh = taylor_runs(&m, &primes, kmax, &opts, false, &mut Prolonged::default()).unwrap();
    let mut kept = Prolonged::default();
    let small = GlobalOptions {
        max_work: 1000,
        ..opts.clone()
    };
    let stopped = taylor_runs(&m, &primes, kmax, &small, false, &mut kept);
    assert!(
        matches!(&stopped, Err(AnalysisError::Invalid(why)) if why.contains("work (multiply-adds")),
        "{:?}",
        stopped.err()
    );
    assert!(kept.held_bytes() > 0);
    let again = taylor_runs(&m, &primes, kmax, &opts, false, &mut kept).unwrap();
    assert_eq!(fresh.len(), again.len());
    for (a, b) in fresh.iter().zip(&again) {
        assert_eq!(key(a), key(b));
    }
}
