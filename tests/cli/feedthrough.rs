//! Symmetries of models whose outputs hold an unknown input (direct feedthrough):
//! STRIKE-GOLDD's 2DOF oscillators, whose second output is the acceleration of mass 2.
//! Expectations derived by hand beside each test.

use crate::util::ok;
use serde_json::Value;

fn symmetries(file: &str) -> Value {
    serde_json::from_str(&ok(&["symmetries", file, "--json"])).unwrap()
}

/// The components of a vector other than 0, by variable.
fn moved(v: &Value) -> Vec<(String, String)> {
    v.as_object()
        .unwrap()
        .iter()
        .filter(|(_, f)| f["text"] != "0")
        .map(|(k, f)| (k.clone(), f["text"].as_str().unwrap().to_string()))
        .collect()
}

#[test]
fn the_mass_behind_an_unmeasured_force_is_a_certified_symmetry() {
    // dx2' = (k2 (x1 - x2) + c2 (dx1 - dx2) + F2)/m2 = y2: the acceleration is measured.
    // m2 -> l m2 with F2 -> l F2 + (l - 1)(k2 (x1 - x2) + c2 (dx1 - dx2)) leaves dx2' and
    // y2 unchanged, and m2 appears nowhere else: d/dm2 is a symmetry, and the only one
    // (the rank test and the SymPy oracle of the model file: rank 6 of 7).
    let v = symmetries("systems/benchmarks/unknown-inputs/2dof.sys");
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(6), Some(7)));
    assert_eq!(v["made_states"], serde_json::json!(["F2"]));
    assert_eq!(v["exact"], true);
    let syms = v["symmetries"].as_array().unwrap();
    assert_eq!(syms.len(), 1);
    assert_eq!(moved(&syms[0]), vec![("m2".to_string(), "1".to_string())]);
    assert_eq!(v["unobservable_variables"], serde_json::json!(["m2"]));
}

#[test]
fn with_both_forces_unmeasured_only_the_first_mass_is_seen() {
    // F1 unknown makes dx1' arbitrary: y1 = x1 gives x1 and dx1 = y1' only. F2 unknown
    // absorbs any change of y2. Each of x2, dx2, k1, dk1, m2 moves alone (a constant
    // shift of x2 or dx2 is absorbed by F1 in dx1' and by F2 in y2 and dx2'): five
    // symmetries, rank 2 of 7.
    let v = symmetries("systems/benchmarks/unknown-inputs/2dof_2ui.sys");
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(7)));
    assert_eq!(v["made_states"], serde_json::json!(["F2"]));
    let mut lost: Vec<String> = v["symmetries"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|s| moved(s).into_iter().map(|m| m.0))
        .collect();
    lost.sort();
    assert_eq!(lost, ["dk1", "dx2", "k1", "m2", "x2"]);
    assert_eq!(v["observable_variables"], serde_json::json!(["x1", "dx1"]));
}

#[test]
fn an_output_that_is_the_state_plus_the_unknown_input_sees_nothing() {
    // y = x + w with w unmeasured: any x(0) is matched by w = y - x, so nothing is
    // observable (rank 0 of 1) and d/dx is the symmetry; w is not reconstructable.
    let dir = crate::util::fresh_dir("ui-feedthrough");
    let p = format!("{dir}/f.sys");
    std::fs::write(
        &p,
        "system f\nstate x\nunknown input w\nx' = w\noutput y = x + w\n",
    )
    .unwrap();
    let v = symmetries(&p);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(0), Some(1)));
    let syms = v["symmetries"].as_array().unwrap();
    assert_eq!(syms.len(), 1);
    assert_eq!(moved(&syms[0]), vec![("x".to_string(), "1".to_string())]);
    assert_eq!(v["reconstructable_inputs"], serde_json::json!([]));
}

/// The reduced system's expression of the output y2.
fn y2_of(v: &Value) -> &Value {
    let outs = v["reduced"]["outputs"].as_array().unwrap();
    &outs.iter().find(|o| o["name"] == "y2").unwrap()["expr"]
}

/// The reduced systems of the 2DOF oscillators close (issue 33): an output that reads an
/// unknown input reads its reduced combination.
#[test]
fn the_output_holding_the_force_reads_the_reduced_combination() {
    let modes = |f: &str| -> Value { serde_json::from_str(&ok(&["modes", f, "--json"])).unwrap() };
    // 2dof: y2 = dx2' exactly (the model file), and dx2 is a mode whose derivative is
    // the combination F2~ = F2/m2 + (k2 (x1 - x2) + c2 (dx1 - dx2))/m2: so y2 = F2~.
    let v = modes("systems/benchmarks/unknown-inputs/2dof.sys");
    assert_eq!(v["reduced"]["closed"], true);
    assert_eq!(v["verified"], true);
    let ri = &v["reduced_inputs"][0];
    assert_eq!(
        (ri["input"].as_str(), ri["mode"].as_str()),
        (Some("F2"), Some("dx2"))
    );
    assert_eq!(y2_of(&v), &ri["name"]);
    // 2dof_2ui: the modes are x1 and dx1 (above), which F2 never reaches (it moves
    // dx2 only); y2 = F2/m2 + ... is then no function of the modes and F1's
    // combination, and is itself the reduced input (measured: order 0).
    let v = modes("systems/benchmarks/unknown-inputs/2dof_2ui.sys");
    assert_eq!(v["reduced"]["closed"], true);
    assert_eq!(v["verified"], true);
    let held = v["reduced_inputs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["input"] == "F2")
        .unwrap();
    assert_eq!(
        (held["mode"].as_str(), held["order"].as_u64()),
        (Some("y2"), Some(0))
    );
    assert_eq!(y2_of(&v), &held["name"]);
}
