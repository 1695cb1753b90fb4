//! Several experiments and known initial conditions from the command line
//! (docs/experiments.md); expected values from the paper and derivations
//! written here.

use crate::util::*;
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    serde_json::from_str(&ok(&a)).expect("json output")
}

// Paper, Table I / section V: a circle (eq. 17) keeps 4 modes of 7 (A_q,
// V_q, xi_q, L_q); k circles: 2k states fixed by A_q, V_q, and the params
// get xi_q (all in span{d xi, d(xi delta)}) and L_q: 2 + 2 + 1 = 5 only with
// three circles. So 4 of 7, 8 of 9, 11 of 11 (the paper's q = 0.9, 0, -1).
#[test]
fn three_circles_from_flags_and_from_a_file() {
    let v = json(&[
        "rank",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
        "--experiment",
        "q: q=-1",
    ]);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(11), Some(11)));
    assert_eq!(v["experiments"][0]["restriction"], "q");
    assert_eq!(v["experiments"][0]["set"]["q"], "9/10");
    assert_eq!(v["state"][0], "mu@1");
    let f = temp_file(
        "circles.exp",
        "# the paper's three circles (section VI-A)\nq: q=0.9\nq: q=0\n\nq: q=-1  # turning\n",
    );
    let w = json(&["rank", "systems/calib.sys", "--experiments", &f]);
    assert_eq!(w["rank"], v["rank"]);
    let two = json(&[
        "rank",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
    ]);
    assert_eq!(
        (two["rank"].as_u64(), two["n"].as_u64()),
        (Some(8), Some(9))
    );
    // Two distinct xi_q = xi - q (xi delta) give xi and delta themselves.
    let obs: Vec<&str> = two["observable_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(obs, vec!["delta", "xi"]);
}

#[test]
fn auto_designs_the_papers_experiment() {
    let v = json(&[
        "rank",
        "systems/calib.sys",
        "--input",
        "q",
        "--experiments",
        "auto",
    ]);
    assert_eq!(v["experiments"], 3);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(11), Some(11)));
    let ranks: Vec<u64> = v["ranks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["rank"].as_u64().unwrap())
        .collect();
    assert_eq!(&ranks[..3], &[4, 8, 11]);
    assert_eq!(v["state_rank"], 2);
    // q = 1 and q = -1 would be a straight line / turning in place only if
    // delta = rL/rR were 1; delta is unknown, so no rational q degenerates.
    for s in v["special_values"].as_array().unwrap() {
        assert_eq!(s["degenerate"], false, "{s}");
    }
}

// S' = 1 + a S^2, y = S, S(0) = 0 (strike-goldd issue 7): y'''(0) = 2a
// (y'' = 2aS(1 + aS^2), so y''' = 2a(1 + aS^2)^2 + 4a^2 S^2 (...) = 2a at 0).
#[test]
fn known_zero_initial_state_keeps_a_identifiable() {
    let f = temp_file(
        "riccati.sys",
        "system riccati\nstate S\nparam a\nS' = 1 + a*S^2\noutput y = S\n",
    );
    let v = json(&["rank", &f, "--known", "S=0"]);
    assert_eq!(v["unknowns"], serde_json::json!(["a"]));
    assert_eq!(v["identifiable"], true);
    assert_eq!(v["point_rank"], 1);
    assert_eq!(v["order_checked"], 3);
    assert_eq!(v["basis"][0]["order"], 3);
    let text = ok(&["rank", &f, "--known", "S=0"]);
    assert!(text.contains("identifiable, proven"), "{text}");
}

// Two compartments, no input, started empty: x = 0 for ever, y = 0, and
// every Lie derivative is linear in x so its gradient in the rates is 0 there.
#[test]
fn empty_compartments_lose_every_rate() {
    let f = temp_file(
        "c2_empty.sys",
        "system c2\nstate x1, x2\nparam k01, k02, k12, k21\n\
         x1' = -(k01 + k21)*x1 + k12*x2\nx2' = k21*x1 - (k02 + k12)*x2\noutput y = x1\n",
    );
    let v = json(&["rank", &f, "--known", "x1=0", "--known", "x2=0"]);
    assert_eq!(v["rank"], 0);
    assert_eq!(v["n"], 4);
    assert_eq!(v["invariant"], true);
    assert_eq!(v["determined"], true);
    // Known but generic: s_k = e1' A^k x0 obey A's order-2 recurrence, so
    // y^(k)(0) are functions of (tr A, det A, a11 x1 + a12 x2): rank 3 of 4.
    let g = json(&["rank", &f, "--known-generic", "x1,x2"]);
    assert_eq!((g["rank"].as_u64(), g["n"].as_u64()), (Some(3), Some(4)));
}

#[test]
fn stacked_symmetries_keep_delta_and_xi_fixed() {
    // Two circles: 9 - 8 = 1 symmetry, and it cannot move delta or xi (both
    // identifiable, see three_circles_from_flags_and_from_a_file).
    let v = json(&[
        "symmetries",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
    ]);
    let syms = v["symmetries"].as_array().unwrap();
    assert_eq!(syms.len(), 1);
    assert_eq!(syms[0]["delta"]["text"], "0");
    assert_eq!(syms[0]["xi"]["text"], "0");
}

#[test]
fn bad_experiment_input_is_a_clear_error() {
    bad(
        &["rank", "systems/calib.sys", "--experiment", "q: q"],
        "expected NAME=VALUE",
    );
    bad(
        &["rank", "systems/calib.sys", "--experiment", "nope: q=1"],
        "no restriction named 'nope'",
    );
    let f = temp_file("bad.exp", "q: q=0.9\nq: q=zz\n");
    bad(
        &["rank", "systems/calib.sys", "--experiments", &f],
        "bad.exp:2",
    );
    bad(
        &["symmetries", "systems/calib.sys", "--experiments", "auto"],
        "obsan rank",
    );
    bad(
        &["rank", "systems/calib.sys", "--known", "nosuch=0"],
        "not a state or param",
    );
    bad(
        &["rank", "systems/calib.sys", "--known", "gamma=0"],
        "--known-generic gamma",
    );
    bad(
        &[
            "rank",
            "systems/calib.sys",
            "--input",
            "q",
            "--experiment",
            "q: q=1",
        ],
        "cannot be used with",
    );
}
