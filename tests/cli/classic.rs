//! Classic models of the identifiability literature: obsan agrees with the
//! published verdicts quoted in each .sys file.

use crate::util::*;
use serde_json::Value;

fn rank_json(args: &[&str]) -> Value {
    let mut a = vec!["rank"];
    a.extend_from_slice(args);
    a.push("--json");
    serde_json::from_str(&ok(&a)).unwrap()
}

fn check(file: &str, extra: &[&str], rank: u64, n: u64, unobservable: &[&str]) {
    let mut a = vec![file];
    a.extend_from_slice(extra);
    let v = rank_json(&a);
    assert_eq!(
        (v["rank"].as_u64().unwrap(), v["n"].as_u64().unwrap()),
        (rank, n),
        "{file}"
    );
    let un: Vec<&str> = v["unobservable_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(un, unobservable, "{file}");
}

#[test]
fn classic_verdicts() {
    check("systems/classic/lotka_volterra.sys", &[], 5, 6, &["y", "b"]);
    check(
        "systems/classic/two_compartment.sys",
        &[],
        5,
        6,
        &["x2", "k01", "k02", "k12", "k21"],
    );
    check("systems/classic/hiv.sys", &[], 9, 9, &[]);
    check("systems/classic/fitzhugh_nagumo.sys", &[], 5, 5, &[]);
    check("systems/classic/michaelis_menten_pk.sys", &[], 4, 4, &[]);
    check(
        "systems/classic/michaelis_menten_pk.sys",
        &["--input", "noinput"],
        3,
        4,
        &["x", "Vm", "Km", "V"],
    );
}

#[test]
fn classic_symmetries_and_modes() {
    // Lotka-Volterra: y -> l y, b -> b/l, i.e. the field y d/dy - b d/db.
    let out = ok(&[
        "check",
        "systems/classic/lotka_volterra.sys",
        "--mode",
        "b*y",
        "--mode",
        "a",
        "--mode",
        "c",
        "--mode",
        "d",
        "--mode",
        "x",
    ]);
    assert!(out.contains("complete: yes"), "{out}");
    let r = obsan(&["check", "systems/classic/lotka_volterra.sys", "--mode", "b"]);
    assert_eq!(r.code, 1);
    // Two compartments: the identifiable combinations of Bellman and Astrom.
    let out = ok(&[
        "check",
        "systems/classic/two_compartment.sys",
        "--mode",
        "k01 + k21",
        "--mode",
        "k02 + k12",
        "--mode",
        "k12*k21",
        "--mode",
        "x1",
        "--mode",
        "k12*x2",
    ]);
    assert!(out.contains("complete: yes"), "{out}");
}
