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
    for cmd in ["modes", "check", "global", "lie"] {
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

#[test]
fn symmetries_of_the_unicycle_with_unknown_speed() {
    // unicycle_one_landmark.sys: rotation about the landmark and scaling are
    // lost (derived in the file and in the analysis crate's
    // tests/unknown_input_symmetries.rs): two symmetries, rank 1, nothing
    // observable but the bearing, v not reconstructable.
    let f = "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys";
    let out = ok(&["symmetries", f]);
    assert!(
        out.contains("rank 1 of 3 with unknown inputs, 2 independent symmetries"),
        "{out}"
    );
    assert!(
        out.contains("unobservable (moved by a symmetry, exact): x, y, theta"),
        "{out}"
    );
    assert!(
        out.contains("exact: each symmetry leaves every output invariant"),
        "{out}"
    );
    let v: Value = serde_json::from_str(&ok(&["symmetries", "--json", f])).unwrap();
    assert_eq!(v["symmetries"].as_array().unwrap().len(), 2);
    assert_eq!(v["certificate"], "unknown_input_invariance");
    assert_eq!(v["exact"], true);
    assert_eq!(v["reconstructable_inputs"].as_array().unwrap().len(), 0);
    // --help names exactly the keys of this object (its second --json sentence).
    let help = ok(&["symmetries", "--help"]);
    let at = help
        .find("unknown inputs --json prints {")
        .expect("no unknown-input sentence");
    let text = &help[at + "unknown inputs --json prints {".len()..];
    let body = &text[..text.find('}').unwrap()];
    let mut promised: Vec<String> = body
        .split(',')
        .map(|i| {
            i.trim()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect();
    promised.sort();
    let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    got.sort();
    assert_eq!(promised, got);
}

#[test]
fn symmetries_with_unknown_inputs_full_rank_and_refusals() {
    // chain.sys: y, y' give x1, x2: no symmetry.
    let out = ok(&["symmetries", "systems/benchmarks/unknown-inputs/chain.sys"]);
    assert!(out.contains("0 independent symmetries"), "{out}");
    // Two-compartment, b known: x2, k1e, k12, k21 lost (file comment).
    let v: Value = serde_json::from_str(&ok(&[
        "symmetries",
        "--json",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]))
    .unwrap();
    assert_eq!(
        v["unobservable_variables"],
        serde_json::json!(["x2", "k1e", "k12", "k21"])
    );
    assert_eq!(v["observable_variables"], serde_json::json!(["x1"]));
    let dir = fresh_dir("ui-feedthrough");
    let p = format!("{dir}/f.sys");
    std::fs::write(
        &p,
        "system f\nstate x\nunknown input w\nx' = w\noutput y = x + w\n",
    )
    .unwrap();
    bad(&["symmetries", &p], "contains the unknown input w");
}
