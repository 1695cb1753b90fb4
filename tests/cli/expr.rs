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
