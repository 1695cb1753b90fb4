use crate::util::*;

#[test]
fn simplify_gives_exact_canonical_forms() {
    assert_eq!(ok(&["simplify", "sin(x)^2 + cos(x)^2"]).trim(), "1");
    assert_eq!(
        ok(&["simplify", "sin(g-p)*cos(p) + cos(g-p)*sin(p) - sin(g)"]).trim(),
        "0"
    );
    assert_eq!(ok(&["simplify", "(x^2 - 1)/(x - 1)"]).trim(), "x + 1");
    assert_eq!(ok(&["simplify", "0.1 + 0.2"]).trim(), "3/10");
}

#[test]
fn diff_matches_the_hand_derivative() {
    // d/dg atan2(sin g, -mu - cos g) = -(1 + mu cos g)/(1 + 2 mu cos g + mu^2).
    let out = ok(&["diff", "atan2(sin(g), -mu - cos(g))", "g"]);
    assert!(
        same_function(out.trim(), "-(1 + mu*cos(g))/(1 + 2*mu*cos(g) + mu^2)"),
        "{out}"
    );
    let out = ok(&["diff", "x^3*y", "x"]);
    assert!(same_function(out.trim(), "3*x^2*y"));
    assert_eq!(ok(&["diff", "y", "x"]).trim(), "0");
}

#[test]
fn json_and_latex_output() {
    let out = ok(&["simplify", "x/y + 1", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["exact"], true);
    assert_eq!(v["is_zero"], false);
    assert!(same_function(v["canonical"].as_str().unwrap(), "(x + y)/y"));
    assert!(v["latex"].as_str().unwrap().contains("\\frac"));
    let out = ok(&["diff", "sin(theta)", "theta", "--latex"]);
    assert_eq!(out.trim(), "\\cos(\\theta)");
    let v: serde_json::Value = serde_json::from_str(&ok(&["diff", "x^2", "x", "--json"])).unwrap();
    assert_eq!(v["variable"], "x");
}

#[test]
fn bad_expressions_exit_2_with_a_caret() {
    let e = bad(
        &["simplify", "sin(x) + foo(y)"],
        "<expression>:1:10: unknown function 'foo'",
    );
    assert!(e.contains("^^^"));
    bad(&["simplify", "1/(x - x)"], "identically zero");
    bad(&["simplify", "(x"], "')'");
    bad(&["diff", "x", "2x"], "not a symbol name");
    bad(&["diff", "x", "pi"], "not a symbol name");
}

/// Fuzz timeout-5952913f: 77 characters whose canonical form prints as
/// 19.7 MB (crates/obsan-expr/tests/trust.rs measures it). Every output
/// style is refused with the size, exit 2, and nothing cut short is printed.
#[test]
fn a_form_too_long_to_print_is_an_error_naming_the_size() {
    let src = " sqrt((lx45 - x)^2 + sqrt(( - c*(V - V*(V - V^4/ x)^2 / y)^27 )+ r)^3/3 + R)";
    for style in [None, Some("--latex"), Some("--json")] {
        let mut args = vec!["simplify", src];
        args.extend(style);
        let r = obsan(&args);
        assert_eq!(r.code, 2, "{args:?}: {}", r.stderr);
        assert!(
            r.stderr.contains("too long to print")
                && r.stderr.contains("1048576 bytes")
                && r.stderr.contains("1 MiB"),
            "{args:?}: {}",
            r.stderr
        );
        assert!(r.stdout.is_empty(), "{args:?}: {} bytes", r.stdout.len());
    }
    // Its derivative by a symbol it does not hold is 0, which prints.
    assert_eq!(ok(&["diff", src, "q"]).trim(), "0");
}

/// An identity outside the decided fragment (log(x y) = log x + log y for
/// x, y > 0) is "not decided", never "nonzero"; its atoms are listed.
#[test]
fn simplify_does_not_claim_nonzero_over_related_atoms() {
    let out = ok(&["simplify", "log(x*y) - log(x) - log(y)", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["is_zero"], serde_json::Value::Null);
    assert_eq!(v["decided"], false);
    assert_eq!(v["exact"], false);
    assert_eq!(
        v["undecided_atoms"],
        serde_json::json!(["log(x)", "log(x*y)", "log(y)"])
    );
    let text = ok(&["simplify", "log(x*y) - log(x) - log(y)"]);
    assert!(
        text.contains("not decided") && text.contains("log(x*y)"),
        "{text}"
    );
    // Independent atoms (one logarithm, by Ax's theorem): decided.
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["simplify", "log(x) - x", "--json"])).unwrap();
    assert_eq!(v["is_zero"], false);
    assert_eq!(v["decided"], true);
    // Two bearings to different points are independent arctangents: decided.
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "simplify",
        "atan2(1 - y, 2 - x) - atan2(-y, -x)",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["decided"], true, "{v}");
    // A zero form is decided whatever its atoms.
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["simplify", "log(x*y) - log(x*y)", "--json"])).unwrap();
    assert_eq!(v["is_zero"], true);
    assert_eq!(v["decided"], true);
}

/// h = x log(2x) - x log(x) - x log(2) is identically 0 for x > 0, so the true
/// rank is 0; with the three logarithms taken as independent, dh/dx =
/// log(2x) - log(x) - log(2) looks nonzero and the rank 1 of 1. The full
/// rank must not be claimed exact.
#[test]
fn rank_over_related_atoms_is_not_claimed_exact() {
    let sys = temp_file(
        "undecided_rank.sys",
        "system undecided_rank\nstate x\nx' = 0\noutput h = x*log(2*x) - x*log(x) - x*log(2)\n",
    );
    let v: serde_json::Value = serde_json::from_str(&ok(&["rank", &sys, "--json"])).unwrap();
    assert_eq!(v["exact"], false, "{v}");
    assert_eq!(v["decided"], false);
    assert_eq!(v["weakly_locally_observable"], serde_json::Value::Null);
    let atoms = v["undecided_atoms"].as_array().unwrap();
    assert!(
        atoms.iter().any(|a| a == "log(x)") && atoms.len() >= 2,
        "{v}"
    );
    let text = ok(&["rank", &sys]);
    assert!(text.contains("not decided"), "{text}");
    assert!(!text.contains("exact: a non-singular minor"), "{text}");
}

/// g = y (log(x y) - log(x) - log(y)) is identically 0 (a mode, trivially);
/// its residual along the symmetry d/dy looks nonzero over independent
/// logarithms, so check says NOT DECIDED rather than FAIL.
#[test]
fn check_and_verify_say_not_decided_over_related_atoms() {
    let sys = temp_file(
        "undecided_check.sys",
        "system undecided_check\nstate x, y\nx' = 0\ny' = 0\noutput h = x\n",
    );
    let mode = "y*(log(x*y) - log(x) - log(y))";
    let r = obsan(&["check", &sys, "--mode", mode]);
    assert_eq!(r.code, 1, "{}", r.stderr);
    assert!(r.stdout.contains("NOT DECIDED"), "{}", r.stdout);
    assert!(!r.stdout.contains("FAIL"), "{}", r.stdout);
    let r = obsan(&["check", &sys, "--mode", mode, "--json"]);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["checks"][0]["observable_mode"], serde_json::Value::Null);
    assert_eq!(v["checks"][0]["decided"], false);
    // A provable failure stays FAIL.
    let r = obsan(&["check", &sys, "--mode", "y"]);
    assert!(r.stdout.contains("FAIL y"), "{}", r.stdout);
    // verify: the claimed output differs from h by x (log(2x) - log(x) - log(2)),
    // identically 0, so its check is NOT DECIDED.
    let dir = fresh_dir("undecided_verify");
    std::fs::write(
        format!("{dir}/s.sys"),
        "system undecided_check\nstate x, y\nx' = 0\ny' = 0\noutput h = x\n",
    )
    .unwrap();
    let dec = format!("{dir}/d.dec");
    std::fs::write(
        &dec,
        "system s.sys\nstate x\nx' = 0\noutput h = x + x*(log(2*x) - log(x) - log(2))\n",
    )
    .unwrap();
    let r = obsan(&["verify", &dec]);
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(r.stdout.contains("NOT DECIDED output h"), "{}", r.stdout);
    assert!(
        r.stdout.contains("decomposition not decided"),
        "{}",
        r.stdout
    );
}
