//! `obsan symmetries` with unknown inputs when the lost directions depend on
//! the known inputs (issue 33; docs/engine.md, "Symmetries with unknown
//! inputs"). Expected vectors derived by hand beside each test.

use crate::util::*;
use serde_json::Value;

/// The smallest case. y = x1, y' = p u + x2 (p and x2 only in this
/// combination), y'' = p u' + w: w is a new unknown at every order, so the
/// observable codistribution is span(dx1, dx2 + u dp), rank 2 of 3, and its
/// kernel in (x1, x2, p) is spanned by xi = (0, -u, 1).
/// Certificate by hand: F = (p u + x2, 0, 0), g = (0, 1, 0);
/// [F, xi] + d_t xi = (-(-u) - u, 0, 0) + (0, -u', 0) = -u' g, in span(xi, g);
/// [g, xi] = 0; L_xi y = 0.
const SMALL: &str = "system small_input_dependent
state x1, x2
param p
input u
unknown input w
x1' = p*u + x2
x2' = w
output y = x1
";

fn symmetries_json(f: &str) -> Value {
    serde_json::from_str(&ok(&["symmetries", "--json", f])).unwrap()
}

/// Component `x` of vector `a` as text the expression parser reads (a jet
/// `u3'` becomes the plain symbol `u3_d`).
fn comp(v: &Value, a: usize, x: &str) -> String {
    v["symmetries"][a][x]["text"]
        .as_str()
        .unwrap()
        .replace('\'', "_d")
}

#[test]
fn a_lost_direction_that_moves_with_the_known_input() {
    let f = temp_file("small_input_dependent.sys", SMALL);
    let v = symmetries_json(&f);
    assert_eq!(v["rank"], 2);
    assert_eq!(v["symmetries"].as_array().unwrap().len(), 1);
    assert_eq!(v["input_dependent"], true);
    assert_eq!(v["input_jets"], serde_json::json!(["u"]));
    assert_eq!(v["exact"], true);
    // Equal by span to (0, -u, 1): x1 not moved, x2 / p = -u.
    assert_eq!(comp(&v, 0, "x1"), "0");
    let ratio = format!("({})/({})", comp(&v, 0, "x2"), comp(&v, 0, "p"));
    assert!(same_function(&ratio, "-u"), "{ratio}");
    // (a) once per output and vector, (b) for F and for g: 3 identities.
    assert_eq!(v["identities"], 3);
    let out = ok(&["symmetries", &f]);
    assert!(out.contains("move with the known inputs"), "{out}");
    assert!(out.contains("[F, xi] + d_t xi"), "{out}");
    // The modes move with the input: derived since session 31
    // (unknown_input_jet_modes.rs), and verify checks a decomposition over
    // the same jet view (jet_decompositions.rs): this one misses the mode
    // x2 + p u and claims x1' = w (the true x1' is p u + x2), so it fails.
    let dec = temp_file(
        "small_input_dependent.dec",
        &format!("system {f}\nstate x1\nx1' = w\noutput y = x1\n"),
    );
    let r = obsan(&["verify", &dec]);
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(
        r.stdout
            .contains("FAIL they are complete (rank of the system is 3)"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("FAIL x1' = w"), "{}", r.stdout);
}

/// STRIKE-GOLDD's CSTR observer (cstr_observer.sys; rank 3 of 4, derived in
/// the file). y = Tc, y' = delta1 qc (u3 - Tc) + 3 (Tr - Tc): the lost
/// direction leaves Tc and y' unchanged, so xi_Tc = 0 and
/// qc (u3 - Tc) xi_delta1 + 3 xi_Tr = 0, i.e. xi_Tr / xi_delta1 =
/// -qc (u3 - Tc) / 3, which moves with u3; xi_Cr follows from y'' (it holds
/// u3'), checked by the exact certificate rather than here.
#[test]
fn cstr_observer_symmetry_moves_with_the_coolant_feed() {
    let f = "systems/benchmarks/unknown-inputs/cstr_observer.sys";
    let v = symmetries_json(f);
    assert_eq!(v["rank"], 3);
    assert_eq!(v["symmetries"].as_array().unwrap().len(), 1);
    assert_eq!(v["input_dependent"], true);
    assert_eq!(v["exact"], true);
    assert!(v["identities"].as_u64().unwrap() >= 3, "{v}");
    assert_eq!(comp(&v, 0, "Tc"), "0");
    let ratio = format!("({})/({})", comp(&v, 0, "Tr"), comp(&v, 0, "delta1"));
    assert!(same_function(&ratio, "-qc*(u3 - Tc)/3"), "{ratio}");
    let jets: Vec<&str> = v["input_jets"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j.as_str().unwrap())
        .collect();
    assert!(jets.contains(&"u3"), "{jets:?}");
}

/// y1 = x1, y2 = x2; y2' = w1 and y1' = x3 + p w1, so x3 + p y2' is seen:
/// dx3 + w1 dp is in the observable codistribution. y1'' = w2 + p w1' and
/// y2'' = w1' bring two new unknowns (w2, w1') for two equations, and so on
/// at every order: rank 3 of 4, kernel (0, 0, -w1, 1) in (x1, x2, x3, p),
/// which depends on the unknown input's value: no vector field on the state.
#[test]
fn a_kernel_that_moves_with_the_unknown_input_is_refused_plainly() {
    let f = temp_file(
        "unknown_history.sys",
        "system unknown_history
state x1, x2, x3
param p
unknown input w1, w2
x1' = x3 + p*w1
x2' = w1
x3' = w2
output y1 = x1
output y2 = x2
",
    );
    let err = bad(
        &["symmetries", &f],
        "the lost directions depend on the unknown inputs' history",
    );
    assert!(!err.contains("timed out"), "{err}");
}
