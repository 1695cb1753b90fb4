use crate::util::*;

#[test]
fn show_calib_normal_form() {
    let out = ok(&["show", "systems/calib.sys"]);
    assert!(out.contains("states: mu, gamma"), "{out}");
    assert!(out.contains("params: phi, psi, eta, delta, xi"));
    assert!(out.contains("inputs: wR, wL"));
    assert!(out.contains("f0: 0"));
    assert!(out.contains("output beta = "));
}

#[test]
fn show_json_fields_match_errata() {
    // ERRATA.md: f_R = [-mu^2 eta cos(gamma - phi), xi - mu eta sin(gamma - phi), 0...],
    // f_L = [-delta mu^2 eta cos(gamma - phi), -delta (xi + mu eta sin(gamma - phi)), 0...].
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["show", "systems/calib.sys", "--json"])).unwrap();
    let f = |input: &str, s: &str| v["fields"][input][s]["text"].as_str().unwrap().to_string();
    assert!(same_function(&f("wR", "mu"), "-mu^2*eta*cos(gamma - phi)"));
    assert!(same_function(
        &f("wR", "gamma"),
        "xi - mu*eta*sin(gamma - phi)"
    ));
    assert!(same_function(
        &f("wL", "mu"),
        "-delta*mu^2*eta*cos(gamma - phi)"
    ));
    assert!(same_function(
        &f("wL", "gamma"),
        "-delta*(xi + mu*eta*sin(gamma - phi))"
    ));
    for s in ["phi", "psi", "eta", "delta", "xi"] {
        assert_eq!(f("wR", s), "0");
        assert_eq!(f("wL", s), "0");
    }
    assert_eq!(v["exact"], true);
}

#[test]
fn show_with_restriction_and_set() {
    let v: serde_json::Value = serde_json::from_str(&ok(&[
        "show",
        "systems/calib.sys",
        "--input",
        "q",
        "--json",
    ]))
    .unwrap();
    assert_eq!(v["inputs"], serde_json::json!(["nu"]));
    // f_nu = f_R + q f_L (eq. 17).
    let fmu = v["fields"]["nu"]["mu"]["text"].as_str().unwrap();
    assert!(same_function(
        fmu,
        "-mu^2*eta*cos(gamma - phi)*(1 + q*delta)"
    ));
    let out = ok(&[
        "show",
        "systems/calib.sys",
        "--input",
        "q",
        "--set",
        "q=0.9",
    ]);
    assert!(out.contains("q = 9/10"), "{out}");
    let out = ok(&["show", "systems/localization.sys", "--latex"]);
    assert!(out.contains("\\frac"), "{out}");
}

#[test]
fn show_errors_exit_2() {
    bad(
        &["show", "systems/nope.sys"],
        "cannot read systems/nope.sys",
    );
    bad(
        &["show", "systems/calib.sys", "--input", "circle"],
        "no restriction named 'circle' (it declares: q)",
    );
    bad(
        &["show", "systems/calib.sys", "--set", "eta=1"],
        "'eta' is a param of calib, not a known constant",
    );
    bad(
        &["show", "systems/calib.sys", "--set", "q"],
        "expected NAME=VALUE",
    );
    bad(
        &["show", "systems/calib.sys", "--set", "q=x"],
        "must be a rational number",
    );
    let p = temp_file(
        "bad.sys",
        "system b\nstate x\ninput u\nx' = x*u^2\noutput y = x\n",
    );
    let e = bad(
        &["show", &p],
        "bad.sys:4:6: the dynamics of x are not affine in the inputs (u): the term 'x*u^2' is not",
    );
    assert!(e.contains("^^^^^"), "{e}");
}
