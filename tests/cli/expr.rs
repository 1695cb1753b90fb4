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
    assert_eq!(out.trim(), "\\cos \\theta");
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
