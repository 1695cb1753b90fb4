//! `obsan rank` with unknown inputs, as a user runs it; verdicts
//! derived by hand in the model files (systems/benchmarks/unknown-inputs/).

use crate::util::*;
use serde_json::Value;

#[test]
fn rank_names_the_reconstructable_input_and_its_order() {
    // y = x1, y' = x2, y'' = w (chain.sys).
    let out = ok(&["rank", "systems/benchmarks/unknown-inputs/chain.sys"]);
    assert!(out.contains("rank 2 of 2"), "{out}");
    assert!(
        out.contains("w (from output derivatives of order 2)"),
        "{out}"
    );
    assert!(out.contains("both routes agree"), "{out}");
    let v: Value = serde_json::from_str(&ok(&[
        "rank",
        "--json",
        "systems/benchmarks/unknown-inputs/chain.sys",
    ]))
    .unwrap();
    assert_eq!(v["unknown_inputs"][0], "w");
    assert_eq!(v["reconstructable_inputs"][0]["name"], "w");
    assert_eq!(v["reconstructable_inputs"][0]["order"], 2);
    assert_eq!(v["observable_variables"][1]["name"], "x2");
    assert_eq!(v["observable_variables"][1]["order"], 1);
    assert_eq!(v["converged"], true);
    assert_eq!(v["agree"], true);
    assert_eq!(v["martinelli"]["reconstructable"][0], "w");
}

#[test]
fn a_negative_verdict_is_proven_and_says_what_is_not() {
    // c2m_known_b.sys: only x1 observable, at every order (derived in the
    // file): Martinelli's algorithm proves it whatever --order; w's verdict
    // (the state not observable) holds up to the order examined.
    let v: Value = serde_json::from_str(&ok(&[
        "rank",
        "--json",
        "--order",
        "3",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]))
    .unwrap();
    assert_eq!(v["rank"], 1);
    assert_eq!(v["max_order"], 3);
    assert_eq!(v["converged"], false);
    assert_eq!(v["agree"], true);
    assert_eq!(v["martinelli"]["rank"], 1);
    assert_eq!(v["martinelli"]["observable"][0], "x1");
    assert_eq!(v["unreconstructable_inputs"][0], "w");
    let out = ok(&[
        "rank",
        "--order",
        "3",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]);
    assert!(out.contains("rank 1 of 5 is final"), "{out}");
    assert!(
        out.contains("w not reconstructable up to order 3 only"),
        "{out}"
    );
}

#[test]
fn other_commands_refuse_unknown_inputs() {
    // global would otherwise count values as if w were absent (a wrong answer, not a refusal);
    // several experiments would stack the model without its unknown input.
    bad(
        &[
            "rank",
            "systems/benchmarks/unknown-inputs/chain.sys",
            "--experiment",
            "",
            "--experiment",
            "",
        ],
        "is an unknown input",
    );
    for cmd in ["symmetries", "modes", "check", "global", "lie"] {
        let mut args = vec![cmd, "systems/benchmarks/unknown-inputs/chain.sys"];
        if cmd == "check" {
            args.extend(["--mode", "x1"]);
        }
        if cmd == "lie" {
            args.extend(["--order", "1"]);
        }
        bad(&args, "has unknown inputs (w)");
    }
}
