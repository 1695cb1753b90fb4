//! The JSON Schemas (`obsan schema`): every typed command's real `--json` output
//! deserializes into its type (which denies unknown fields) and validates against the
//! schema the binary prints; its `--help` (or doc page) names exactly the schema's keys;
//! docs/json.md is `obsan schema --markdown`; every command is listed, typed or not.

use crate::util::{bad, brace_items, fresh_dir, ok, subcommands, temp_file};
use obsan_cli::json;
use serde::de::DeserializeOwned;
use serde_json::Value;

/// The schema `obsan schema NAME` prints.
fn schema(name: &str) -> Value {
    serde_json::from_str(&ok(&["schema", name])).expect("a schema is JSON")
}

/// Run a command with --json; its output must deserialize into `T` (unknown or missing
/// keys, wrong types fail) and validate against the schema `name`. Returns the value.
fn typed<T: DeserializeOwned>(name: &str, args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    let out = ok(&a);
    if let Err(e) = serde_json::from_str::<T>(&out) {
        panic!("obsan {}: not a {name} output: {e}\n{out}", a.join(" "));
    }
    let v: Value = serde_json::from_str(&out).unwrap();
    let s = schema(name);
    if let Err(e) = validate(&v, &s, &s, "$") {
        panic!("obsan {}: against `obsan schema {name}`: {e}", a.join(" "));
    }
    v
}

/// A small validator for the subset of JSON Schema (2020-12) that schemars derives: $ref to
/// $defs, anyOf/oneOf, type (or a list of types), const, properties, required,
/// additionalProperties (false or a schema), items, prefixItems.
fn validate(v: &Value, s: &Value, root: &Value, at: &str) -> Result<(), String> {
    if let Some(r) = s.get("$ref").and_then(Value::as_str) {
        let name = r.strip_prefix("#/$defs/").ok_or(format!("{at}: ref {r}"))?;
        return validate(v, &root["$defs"][name], root, at);
    }
    if let Some(alts) = s.get("anyOf").or_else(|| s.get("oneOf")) {
        let ok = alts
            .as_array()
            .unwrap()
            .iter()
            .filter(|a| validate(v, a, root, at).is_ok());
        let n = ok.count();
        let one = s.get("oneOf").is_some();
        if n == 0 || (one && n > 1) {
            return Err(format!("{at}: {v} matches {n} of the alternatives of {s}"));
        }
    }
    if let Some(c) = s.get("const") {
        if c != v {
            return Err(format!("{at}: {v} is not {c}"));
        }
    }
    if let Some(t) = s.get("type") {
        let types: Vec<&str> = match t {
            Value::String(t) => vec![t.as_str()],
            t => t
                .as_array()
                .unwrap()
                .iter()
                .filter_map(Value::as_str)
                .collect(),
        };
        let is = |t: &str| match t {
            "null" => v.is_null(),
            "boolean" => v.is_boolean(),
            "integer" => v.is_u64() || v.is_i64(),
            "number" => v.is_number(),
            "string" => v.is_string(),
            "array" => v.is_array(),
            "object" => v.is_object(),
            _ => false,
        };
        if !types.iter().any(|t| is(t)) {
            return Err(format!("{at}: {v} is not of type {t}"));
        }
    }
    if let (Some(o), Some(props)) = (v.as_object(), s.get("properties")) {
        for r in s
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let r = r.as_str().unwrap();
            if !o.contains_key(r) {
                return Err(format!("{at}: required key {r} missing"));
            }
        }
        for (k, x) in o {
            let here = format!("{at}.{k}");
            match (props.get(k), s.get("additionalProperties")) {
                (Some(p), _) => validate(x, p, root, &here)?,
                (None, Some(Value::Bool(false))) => {
                    return Err(format!("{here}: not in the schema"))
                }
                (None, Some(a)) => validate(x, a, root, &here)?,
                (None, None) => {}
            }
        }
    } else if let (Some(o), Some(a)) = (v.as_object(), s.get("additionalProperties")) {
        for (k, x) in o {
            validate(x, a, root, &format!("{at}.{k}"))?;
        }
    }
    if let Some(items) = v.as_array() {
        if let Some(pre) = s.get("prefixItems").and_then(Value::as_array) {
            for (i, (x, p)) in items.iter().zip(pre).enumerate() {
                validate(x, p, root, &format!("{at}[{i}]"))?;
            }
        } else if let Some(p) = s.get("items") {
            for (i, x) in items.iter().enumerate() {
                validate(x, p, root, &format!("{at}[{i}]"))?;
            }
        }
    }
    Ok(())
}

/// The keys of the first `{...}` group at or after `marker` in `text`: the items at its depth 1,
/// each item's first identifier ("params (name -> {value, sd})" -> "params").
fn keys_after(text: &str, marker: &str) -> Vec<String> {
    let from = text
        .find(marker)
        .unwrap_or_else(|| panic!("no '{marker}' in:\n{text}"));
    // The group starts at the first brace of the marker or after it.
    let text = &text[from..];
    let text = &text[text.find('{').expect("a brace group")..];
    let mut keys = brace_items(text);
    keys.sort();
    keys
}

/// The property names of an object schema (following a $ref, or an array's items).
fn properties(s: &Value, root: &Value) -> Vec<String> {
    if let Some(r) = s.get("$ref").and_then(Value::as_str) {
        return properties(&root["$defs"][r.rsplit('/').next().unwrap()], root);
    }
    if let Some(alts) = s.get("anyOf").and_then(Value::as_array) {
        return alts.iter().flat_map(|a| properties(a, root)).collect();
    }
    if s.get("type").and_then(Value::as_str) == Some("array") {
        return properties(&s["items"], root);
    }
    let mut keys: Vec<String> = s
        .get("properties")
        .and_then(Value::as_object)
        .map(|p| p.keys().cloned().collect())
        .unwrap_or_default();
    keys.sort();
    keys
}

/// The keys of every alternative of a schema, once each, sorted.
fn all_properties(s: &Value, root: &Value) -> Vec<String> {
    let mut keys = properties(s, root);
    keys.sort();
    keys.dedup();
    keys
}

#[test]
fn expression_outputs_match_their_types_and_schemas() {
    let v = typed::<json::Simplify>("simplify", &["simplify", "-x^2 + (x+1)^2"]);
    assert_eq!(v["is_zero"], false);
    // Not decided: is_zero is null, the atoms listed (a type with `is_zero: bool` would fail).
    let v = typed::<json::Simplify>("simplify", &["simplify", "log(x*y) - log(x) - log(y)"]);
    assert!(v["is_zero"].is_null() && v["decided"] == false, "{v}");
    typed::<json::Diff>("diff", &["diff", "x^3*exp(x)", "x"]);
    let v = typed::<json::Lie>("lie", &["lie", "systems/localization.sys", "--order", "1"]);
    // One output, two fields (v, omega; no drift): 1 + 2 words.
    assert_eq!(
        v["lie_derivatives"].as_array().map(Vec::len),
        Some(3),
        "{v}"
    );
}

#[test]
fn rank_known_and_auto_match_their_types_and_schemas() {
    let f = "systems/classic/two_compartment.sys";
    typed::<json::RankKnown>("rank-known", &["rank", f, "--known-generic", "x1,x2"]);
    let v = typed::<json::RankKnown>("rank-known", &["rank", f, "--known", "x1=0,x2=0"]);
    assert_eq!(v["known"][0]["value"], "0", "{v}");
    let v = typed::<json::RankKnown>(
        "rank-known",
        &[
            "rank",
            "systems/calib.sys",
            "--experiment",
            "q: q=0.9",
            "--experiment",
            "q: q=0",
            "--known-generic",
            "mu",
        ],
    );
    assert_eq!(v["experiments"][0]["set"]["q"], "9/10", "{v}");
    typed::<json::RankAuto>(
        "rank-auto",
        &[
            "rank",
            "systems/calib.sys",
            "--input",
            "q",
            "--experiments",
            "auto",
        ],
    );
}

#[test]
fn show_and_rank_outputs_match_their_types_and_schemas() {
    let v = typed::<json::Show>(
        "show",
        &[
            "show",
            "systems/calib.sys",
            "--input",
            "q",
            "--set",
            "q=0.9",
        ],
    );
    assert_eq!(v["consts"][0]["value"], "9/10", "{v}");
    // localization.sys: x' = f0 + v f_v + omega f_omega, one output (eq. 3).
    let v = typed::<json::Show>("show", &["show", "systems/localization.sys"]);
    assert_eq!(v["fields"].as_object().map(|f| f.len()), Some(2), "{v}");
    // Rank 2 of 3 (Martinelli 2011, section II: one symmetry).
    let v = typed::<json::Rank>("rank", &["rank", "systems/localization.sys"]);
    assert_eq!(
        (v["rank"].as_u64(), v["n"].as_u64()),
        (Some(2), Some(3)),
        "{v}"
    );
    assert_eq!(v["weakly_locally_observable"], false, "{v}");
    let v = typed::<json::Rank>(
        "rank",
        &[
            "rank",
            "systems/calib.sys",
            "--experiment",
            "q: q=0.9",
            "--experiment",
            "q: q=0",
        ],
    );
    assert_eq!(v["experiments"][1]["set"]["q"], "0", "{v}");
    // The unknown-input route prints its own object: v is not reconstructable (the
    // file's hand derivation), the bearing's rank is 1 of the 3 states.
    let v = typed::<json::RankUnknownInputs>(
        "rank-unknown-inputs",
        &[
            "rank",
            "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys",
        ],
    );
    assert_eq!(
        v["unreconstructable_inputs"],
        serde_json::json!(["v"]),
        "{v}"
    );
    // A plain rank's output is not an unknown-input one, nor the other way round.
    let plain = ok(&["rank", "systems/localization.sys", "--json"]);
    assert!(serde_json::from_str::<json::RankUnknownInputs>(&plain).is_err());
}

#[test]
fn symmetry_and_mode_outputs_match_their_types_and_schemas() {
    // localization.sys: the one symmetry [0, 1, 1] (a rotation about the feature, eq. 3).
    let v = typed::<json::Symmetries>("symmetries", &["symmetries", "systems/localization.sys"]);
    let w = &v["symmetries"];
    assert_eq!(w.as_array().map(Vec::len), Some(1), "{v}");
    let (d, p, t) = (
        &w[0]["D"]["text"],
        &w[0]["phiR"]["text"],
        &w[0]["thetaR"]["text"],
    );
    assert!(d == "0" && p != "0" && p == t, "{v}");
    let v = typed::<json::SymmetriesUnknownInputs>(
        "symmetries-unknown-inputs",
        &[
            "symmetries",
            "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys",
        ],
    );
    assert_eq!(v["certificate"], "unknown_input_invariance", "{v}");
    // unicycle_one_landmark.sys: rank 1 of 3 (its file's hand derivation), one mode.
    let v = typed::<json::ModesUnknownInputs>(
        "modes-unknown-inputs",
        &[
            "modes",
            "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys",
        ],
    );
    assert_eq!(v["modes"].as_array().map(Vec::len), Some(1), "{v}");
    let v = typed::<json::Check>(
        "check",
        &[
            "check",
            "systems/localization.sys",
            "--mode",
            "D",
            "--mode",
            "thetaR - phiR",
        ],
    );
    assert_eq!(v["checks"][1]["observable_mode"], true, "{v}");
    let v = typed::<json::Verify>("verify", &["verify", "systems/decomp_21_22.dec"]);
    assert_eq!(v["pass"], true, "{v}");
    // Below full rank the derivation, at full rank (calib.sys: 7 of 7) the short object.
    let v = typed::<json::Modes>("modes", &["modes", "systems/calib_q_nopsi.sys"]);
    assert!(v["reduced"].is_object() && v["full_rank"] == false, "{v}");
    let v = typed::<json::Modes>("modes", &["modes", "systems/calib.sys"]);
    assert!(v["reduced"].is_null() && v["full_rank"] == true, "{v}");
}

#[test]
fn global_and_simulate_outputs_match_their_types_and_schemas() {
    // squared_rate.sys: x' = -a^2 x, y = x; by hand (in the file) a has 2 values, x 1.
    let v = typed::<json::Global>("global", &["global", "systems/global/squared_rate.sys"]);
    let vars = v["variables"].as_array().expect("variables");
    let of = |n: &str| vars.iter().find(|x| x["name"] == n).cloned().unwrap();
    assert_eq!(
        (of("a")["verdict"].clone(), of("a")["values"].clone()),
        ("local".into(), 2.into())
    );
    assert_eq!(of("x")["verdict"], "global", "{v}");
    // Times 0, 0.5, 1: three rows of time, the two states, the output.
    let v = typed::<json::SimulateSys>(
        "simulate",
        &[
            "simulate",
            "systems/classic/lotka_volterra.sys",
            "--set",
            "a=1",
            "--set",
            "b=0.5",
            "--set",
            "c=1",
            "--set",
            "d=0.2",
            "--init",
            "x=4",
            "--init",
            "y=2",
            "--until",
            "1",
            "--every",
            "0.5",
        ],
    );
    assert_eq!(v["rows"].as_array().map(Vec::len), Some(3), "{v}");
    assert_eq!(v["rows"][0][1], 4.0, "x(0) = 4: {v}");
}

#[test]
fn rank_along_matches_its_type_and_schema() {
    let dir = fresh_dir("json-schema-along");
    let sim = format!("{dir}/sim");
    ok(&["simulate", "--out", &sim, "--bearings", "40"]);
    let v = typed::<json::Along>(
        "rank-along",
        &[
            "rank",
            "systems/calib.sys",
            "--along",
            &sim,
            "--window",
            "20",
        ],
    );
    // calib.sys has 7 variables (rank 7 of 7, eq. 16).
    assert_eq!(v["n"], 7, "{v}");
    assert!(
        v["windows"].as_array().is_some_and(|w| !w.is_empty()),
        "{v}"
    );
}

#[test]
fn diagnose_output_and_report_match_the_type_and_schema() {
    let dir = fresh_dir("json-schema-diag");
    let sim = format!("{dir}/sim");
    ok(&[
        "simulate",
        "--out",
        &sim,
        "--bearings",
        "200",
        "--effect",
        "bearing_scale=0.04",
    ]);
    let report = format!("{dir}/report");
    let v = typed::<json::Diagnose>(
        "diagnose",
        &["diagnose", "systems/calib.sys", &sim, "--report", &report],
    );
    assert!(v["rounds"].as_array().is_some_and(|r| !r.is_empty()), "{v}");
    // The report's diagnosis.json is the same view.
    let file = std::fs::read_to_string(format!("{report}/diagnosis.json")).unwrap();
    serde_json::from_str::<json::Diagnose>(&file).expect("diagnosis.json is a Diagnose");
    assert_eq!(serde_json::from_str::<Value>(&file).unwrap(), v);
}

#[test]
fn estimation_outputs_match_their_types_and_schemas() {
    let dir = fresh_dir("json-schema-est");
    let sim = format!("{dir}/sim");
    ok(&["simulate", "--out", &sim, "--bearings", "40"]);
    let v = typed::<json::Calibrate>("calibrate", &["calibrate", &sim]);
    assert!(v["encoder_noise"]["route"].is_string(), "{v}");
    // ls with --d0: no encoder_noise nor ml, a metric.
    let v = typed::<json::Calibrate>(
        "calibrate",
        &["calibrate", &sim, "--method", "ls", "--d0", "1.2"],
    );
    assert!(
        v["encoder_noise"].is_null() && v["metric"]["B"]["value"].is_number(),
        "{v}"
    );
    typed::<json::Crlb>("crlb", &["crlb", "--bearings", "40"]);
    typed::<json::Crlb>("crlb", &["crlb", &sim]);
    let cell = ["montecarlo", "--table", "5", "--cell", "3", "--runs", "2"];
    let v = typed::<Vec<json::McTable>>("montecarlo", &cell);
    assert_eq!(v[0]["cells"][0]["cell"], 3, "{v}");
    // Table IV (single-run estimates) and VI (the modes) have their own columns.
    typed::<Vec<json::McTable>>(
        "montecarlo",
        &["montecarlo", "--table", "4", "--cell", "1", "--runs", "1"],
    );
    typed::<Vec<json::McTable>>(
        "montecarlo",
        &["montecarlo", "--table", "6", "--cell", "1", "--runs", "1"],
    );
    // A shard's partial result, and the merge of the two.
    let mut parts = Vec::new();
    for k in ["1/2", "2/2"] {
        let mut a = cell.to_vec();
        a.extend(["--shard", k, "--json"]);
        let out = ok(&a);
        let v: Value = serde_json::from_str(&out).unwrap();
        let s = schema("montecarlo-shard");
        validate(&v, &s, &s, "$").unwrap_or_else(|e| panic!("shard {k}: {e}"));
        let p = format!("{dir}/part{}.json", parts.len());
        std::fs::write(&p, out).unwrap();
        parts.push(p);
    }
    let merged = typed::<Vec<json::McTable>>(
        "montecarlo-merge",
        &["montecarlo", "merge", &parts[0], &parts[1]],
    );
    assert_eq!(merged, v, "the merge is the one-run table");
}

#[test]
fn design_outputs_match_their_types_and_schemas() {
    let cand = temp_file(
        "schema_sensors.cand",
        "candidate heading cost 2\noutput yh = thetaR\ncandidate bearing\noutput yb = phiR\n",
    );
    let v = typed::<json::Design>(
        "design",
        &["design", "systems/localization.sys", "--candidates", &cand],
    );
    assert!(
        v["sensors"]["sets"]
            .as_array()
            .is_some_and(|s| !s.is_empty()),
        "{v}"
    );
    let v = typed::<json::Design>("design", &["design", "systems/calib.sys"]);
    assert!(
        v["sensors"].is_null() && v["inputs"]["families"].is_array(),
        "{v}"
    );
}

/// A user reads `--help` (or the doc page) to find a field: it names exactly the schema's
/// top-level keys, and for design the nested sensors and inputs objects' keys too.
#[test]
fn help_names_exactly_the_schema_keys() {
    let help = |c: &[&str]| ok(&[c, &["--help"]].concat());
    let cases: [(&str, String, &str); 20] = [
        ("diagnose", help(&["diagnose"]), "--json prints"),
        ("rank-along", help(&["rank"]), "--along --json prints"),
        ("show", help(&["show"]), "--json prints"),
        ("rank", help(&["rank"]), "--json prints"),
        (
            "rank-unknown-inputs",
            help(&["rank"]),
            "With unknown inputs, --json prints",
        ),
        ("symmetries", help(&["symmetries"]), "--json prints"),
        (
            "symmetries-unknown-inputs",
            help(&["symmetries"]),
            "with unknown inputs --json prints",
        ),
        ("check", help(&["check"]), "--json prints"),
        ("verify", help(&["verify"]), "--json prints"),
        // Both objects' keys: the full-rank one's are a subset of the derivation's.
        ("modes", help(&["modes"]), "--json prints"),
        (
            "modes-unknown-inputs",
            help(&["modes"]),
            "With unknown inputs --json prints",
        ),
        ("global", help(&["global"]), "--json prints"),
        ("simulate", help(&["simulate"]), "--json prints"),
        ("simplify", help(&["simplify"]), "--json prints"),
        ("diff", help(&["diff"]), "--json prints"),
        ("lie", help(&["lie"]), "--json prints"),
        ("calibrate", help(&["calibrate"]), "--json prints"),
        ("crlb", help(&["crlb"]), "--json prints"),
        (
            "montecarlo",
            help(&["montecarlo"]),
            "--json prints a list of tables",
        ),
        ("design", help(&["design"]), "--json prints"),
    ];
    let experiments =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/experiments.md"))
            .unwrap();
    let docs = [
        (
            "rank-known",
            experiments.clone(),
            "With `--known`, `--json` prints",
        ),
        (
            "rank-auto",
            experiments.clone(),
            "`--experiments auto` prints",
        ),
    ];
    for (name, text, marker) in cases.iter().chain(&docs) {
        let s = schema(name);
        assert_eq!(
            keys_after(text, marker),
            all_properties(&s, &s),
            "{name}: {marker}"
        );
    }
    let d = schema("design");
    let h = help(&["design"]);
    let sensors = properties(&d["$defs"]["Sensors"], &d);
    let inputs = properties(&d["$defs"]["Inputs"], &d);
    assert_eq!(
        keys_after(&h, "sensors: {"),
        sensors,
        "design --help, sensors"
    );
    assert_eq!(keys_after(&h, "inputs: {"), inputs, "design --help, inputs");
    assert_eq!(
        keys_after(&experiments, "`sensors` (or null): "),
        sensors,
        "docs, sensors"
    );
    assert_eq!(
        keys_after(&experiments, "`inputs` (or null): "),
        inputs,
        "docs, inputs"
    );
}

#[test]
fn docs_json_md_is_the_schemas_page() {
    let page = ok(&["schema", "--markdown"]);
    let file =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/json.md")).unwrap();
    assert!(
        page == file,
        "docs/json.md is out of date: cargo run --release -p obsan -- schema --markdown > docs/json.md"
    );
    // Each schema's every object has documented fields: the descriptions are the docs.
    for t in json::TYPED {
        let s = serde_json::to_value((t.schema)()).unwrap();
        let defs = s
            .get("$defs")
            .and_then(Value::as_object)
            .cloned()
            .unwrap_or_default();
        for (what, o) in std::iter::once(("root".to_string(), &s))
            .chain(defs.iter().map(|(k, v)| (k.clone(), v)))
        {
            for (k, p) in o
                .get("properties")
                .and_then(Value::as_object)
                .into_iter()
                .flatten()
            {
                assert!(
                    p.get("description").is_some(),
                    "{}: {what}.{k} has no description",
                    t.name
                );
            }
        }
    }
}

#[test]
fn every_command_is_listed_typed_or_not() {
    let list = ok(&["schema", "--list"]);
    let listed: Vec<&str> = list
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(|n| n.split('-').next().unwrap_or(n))
        .collect();
    let commands = subcommands(&ok(&["--help"]));
    for c in commands.iter().filter(|c| *c != "schema") {
        assert!(
            listed.contains(&c.as_str()),
            "obsan {c} is not in `obsan schema --list`:\n{list}"
        );
    }
    bad(&["schema", "rankk"], "no schema for 'rankk'");
}

/// The validator is not vacuous: an unknown key, a missing one, a wrong type, a wrong
/// nested type each fail.
#[test]
fn the_validator_refuses_what_the_schema_does_not_allow() {
    let s = schema("simplify");
    let good: Value = serde_json::from_str(&ok(&["simplify", "x + 1", "--json"])).unwrap();
    validate(&good, &s, &s, "$").unwrap();
    let broken = |f: &dyn Fn(&mut serde_json::Map<String, Value>)| {
        let mut v = good.clone();
        f(v.as_object_mut().unwrap());
        validate(&v, &s, &s, "$").is_err()
    };
    assert!(broken(&|o| {
        o.insert("extra".into(), Value::Null);
    }));
    assert!(broken(&|o| {
        o.remove("canonical");
    }));
    assert!(broken(&|o| {
        o.insert("decided".into(), "yes".into());
    }));
    assert!(broken(&|o| {
        o.insert("undecided_atoms".into(), serde_json::json!([1]));
    }));
    // Null where the schema allows it, not elsewhere.
    assert!(!broken(&|o| {
        o.insert("is_zero".into(), Value::Null);
    }));
    assert!(broken(&|o| {
        o.insert("latex".into(), Value::Null);
    }));
    let d = schema("calibrate");
    let bad_route = serde_json::json!({"route": "guessed"});
    assert!(validate(&bad_route, &d["$defs"]["EncoderNoise"], &d, "$").is_err());
}
