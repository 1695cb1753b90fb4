use crate::util::*;

fn tmp_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d.to_string_lossy().into_owned()
}

#[test]
fn simulate_writes_the_data_format() {
    let out = tmp_dir("ok");
    ok(&["simulate", "--out", &out, "--set", "q=0,-1", "--seed", "3"]);
    for f in [
        "dataset.json",
        "truth.json",
        "q0/inputs.csv",
        "q0/outputs.csv",
        "q0/meta.json",
        "q-1/outputs.csv",
    ] {
        assert!(std::path::Path::new(&out).join(f).exists(), "{f}");
    }
    let text = std::fs::read_to_string(format!("{out}/q0/inputs.csv")).unwrap();
    let s = obsan_data::Series::parse_csv(&text, "inputs.csv", &["wR", "wL"], false).unwrap();
    assert_eq!(s.t()[3], 0.06, "time stamps are k/50 exactly as printed");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{out}/q-1/meta.json")).unwrap())
            .unwrap();
    assert_eq!(meta["q"], -1.0);
    // The same seed gives the same data.
    let again = tmp_dir("again");
    ok(&[
        "simulate", "--out", &again, "--set", "q=0,-1", "--seed", "3",
    ]);
    assert_eq!(
        std::fs::read_to_string(format!("{out}/q0/outputs.csv")).unwrap(),
        std::fs::read_to_string(format!("{again}/q0/outputs.csv")).unwrap()
    );
    // Refuses to overwrite; --force replaces.
    bad(&["simulate", "--out", &out], "already exists");
    ok(&["simulate", "--out", &out, "--set", "q=0", "--force"]);
    assert!(!std::path::Path::new(&out).join("q-1").exists());
}

/// The wheel-speed ratio has one spelling, the model's constant: `--set q=RATIOS` (one
/// trajectory each). The old `--q RATIOS` is a hidden alias that gives the same data; giving
/// both, or another constant without a model, is refused.
#[test]
fn q_is_set_like_the_models_constant_and_the_old_flag_still_works() {
    let new = tmp_dir("q-new");
    let old = tmp_dir("q-old");
    ok(&[
        "simulate",
        "--out",
        &new,
        "--set",
        "q=0.5,-0.5",
        "--seed",
        "5",
    ]);
    ok(&["simulate", "--out", &old, "--q", "0.5,-0.5", "--seed", "5"]);
    for f in ["dataset.json", "q0.5/outputs.csv", "q-0.5/inputs.csv"] {
        let read = |d: &str| std::fs::read_to_string(format!("{d}/{f}")).unwrap();
        assert_eq!(read(&new), read(&old), "{f}");
    }
    // The default is the paper's three circles (section VI-A): q = 0.9, 0, -1.
    let default = tmp_dir("q-default");
    ok(&["simulate", "--out", &default, "--bearings", "20"]);
    for q in ["q0.9", "q0", "q-1"] {
        assert!(std::path::Path::new(&default).join(q).exists(), "{q}");
    }
    let crlb = |a: &[&str]| ok(&[&["crlb", "--bearings", "40", "--json"], a].concat());
    assert_eq!(crlb(&["--set", "q=0.9,0"]), crlb(&["--q", "0.9,0"]));
    assert_ne!(
        crlb(&["--set", "q=0.9,0"]),
        crlb(&[]),
        "the ratios are used"
    );
    let both = tmp_dir("q-both");
    bad(
        &["simulate", "--out", &both, "--set", "q=0", "--q", "0"],
        "q is given twice",
    );
    bad(
        &["simulate", "--out", &both, "--set", "mu=1"],
        "one constant, q",
    );
    bad(&["crlb", "--set", "q=0.9,x"], "finite ratios");
    assert!(!std::path::Path::new(&both).exists());
    // --help shows the one spelling only.
    let help = ok(&["simulate", "--help"]);
    assert!(
        help.contains("--set q=") && !help.contains("--q "),
        "{help}"
    );
}

#[test]
fn simulate_rejects_bad_options_and_leaves_nothing() {
    let out = tmp_dir("bad");
    bad(
        &["simulate", "--out", &out, "--effect", "bogus=1"],
        "unknown effect 'bogus'",
    );
    bad(
        &["simulate", "--out", &out, "--effect", "time_offset"],
        "expected NAME=VALUE",
    );
    bad(
        &["simulate", "--out", &out, "--speed-profile", "sine:2:10"],
        "|AMPLITUDE| < 1",
    );
    bad(
        &[
            "simulate",
            "--out",
            &out,
            "--set",
            "q=0.98409",
            "--sigma-beta-deg",
            "1",
        ],
        "degenerate trajectory",
    );
    bad(
        &["simulate", "--out", &out, "--d0", "0.1"],
        "must exceed rho",
    );
    bad(&["simulate", "--out", &out, "--iota=-1"], "--iota must be");
    let inputs = temp_file("wheels.csv", "t,wR,wL\n0,0.1,0.2\n1,0.1,abc\n");
    bad(
        &["simulate", "--out", &out, "--inputs", &inputs],
        "wheels.csv:3 (column wL): 'abc' is not a number",
    );
    assert!(!std::path::Path::new(&out).exists(), "no partial output");
    let parent = std::path::Path::new(&out).parent().unwrap();
    let leftovers = std::fs::read_dir(parent)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .contains(&format!("obsan-sim-{}-bad", std::process::id()))
        })
        .count();
    assert_eq!(leftovers, 0);
}

// ---- `obsan simulate MODEL.sys`: each expected value is a closed form derived beside it.

/// The simulator promises an estimated error within 1e-9 (|v| + 1) per value; the
/// values below are at most 3 in size, so 4e-9 each, and the Richardson estimate is
/// itself an estimate: allow 10x that.
pub(crate) const SIM_TOL: f64 = 4e-8;

/// Rows of `simulate ... --json` and its column names.
pub(crate) fn simulate_json(args: &[&str]) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut a = vec!["simulate"];
    a.extend_from_slice(args);
    a.push("--json");
    let v: serde_json::Value = serde_json::from_str(&ok(&a)).unwrap();
    let cols = v["columns"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_str().unwrap().to_string())
        .collect();
    let rows = v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect();
    assert!(v["error_estimate"].as_f64().unwrap() <= v["tolerance"].as_f64().unwrap());
    (cols, rows)
}

pub(crate) fn close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() <= SIM_TOL,
        "{what}: got {got}, want {want}"
    );
}

#[test]
fn simulate_model_exponential_decay_matches_the_closed_form() {
    // x' = -k x: x(t) = x0 exp(-k t); y = 3 x.
    let m = temp_file(
        "decay.sys",
        "system decay\nstate x\nparam k\nx' = -k*x\noutput y = 3*x\n",
    );
    let (cols, rows) = simulate_json(&[
        &m, "--set", "k=0.7", "--init", "x=2", "--until", "5", "--every", "0.5",
    ]);
    assert_eq!(cols, ["time", "x", "y"]);
    assert_eq!(rows.len(), 11, "0, 0.5, ..., 5");
    for r in &rows {
        let x = 2.0 * (-0.7 * r[0]).exp();
        close(r[1], x, "x");
        close(r[2] / 3.0, x, "y / 3");
    }
    close(rows[10][0], 5.0, "last time");
}

#[test]
fn simulate_model_harmonic_oscillator_keeps_its_energy() {
    // q' = p, p' = -w^2 q: q = q0 cos(w t) + p0/w sin(w t), p = -q0 w sin(w t) + p0 cos(w t),
    // and E = p^2 + w^2 q^2 is constant.
    let m = temp_file(
        "osc.sys",
        "system osc\nstate q, p\nparam w\nq' = p\np' = -w^2*q\noutput E = p^2 + w^2*q^2\n",
    );
    let (w, q0, p0) = (1.3f64, 1.0f64, 0.5f64);
    let (cols, rows) = simulate_json(&[
        &m, "--set", "w=1.3", "--init", "q=1", "--init", "p=0.5", "--until", "20", "--every",
        "0.25",
    ]);
    assert_eq!(cols, ["time", "q", "p", "E"]);
    let e0 = p0 * p0 + w * w * q0 * q0;
    for r in &rows {
        let t = r[0];
        close(r[1], q0 * (w * t).cos() + p0 / w * (w * t).sin(), "q");
        close(r[2], -q0 * w * (w * t).sin() + p0 * (w * t).cos(), "p");
        close(r[3], e0, "energy");
    }
}

#[test]
fn simulate_model_two_compartments_with_a_constant_input() {
    // x1' = u - k1 x1, x2' = k1 x1 - k2 x2, x1(0) = a, x2(0) = b:
    // x1 = u/k1 + (a - u/k1) e^(-k1 t); x2 = u/k2 + C e^(-k1 t) + D e^(-k2 t) with
    // C = (k1 a - u)/(k2 - k1) (substituting into x2' + k2 x2 = u + (k1 a - u) e^(-k1 t))
    // and D = b - u/k2 - C (from x2(0) = b).
    let m = temp_file(
        "two.sys",
        "system two\nstate x1, x2\nparam k1, k2\ninput u\nx1' = u - k1*x1\nx2' = k1*x1 - k2*x2\noutput y = x2\n",
    );
    let (k1, k2, a, b, u) = (0.8f64, 0.3f64, 1.0f64, 0.5f64, 0.2f64);
    let vals = temp_file(
        "two.values",
        "# from a test\nk1 = 0.8\nk2 = 0.3\nx1 = 1\nx2 = 0.5\n",
    );
    let (_, rows) = simulate_json(&[
        &m, "--values", &vals, "--input", "u=0.2", "--until", "12", "--every", "0.4",
    ]);
    let c = (k1 * a - u) / (k2 - k1);
    let d = b - u / k2 - c;
    for r in &rows {
        let t = r[0];
        close(r[1], u / k1 + (a - u / k1) * (-k1 * t).exp(), "x1");
        close(
            r[2],
            u / k2 + c * (-k1 * t).exp() + d * (-k2 * t).exp(),
            "x2",
        );
        close(r[3], r[2], "y = x2");
    }
    // --set and --init override the file; the CSV goes to --out.
    let dir = crate::util::fresh_dir("sim-two");
    let csv = format!("{dir}/two.csv");
    ok(&[
        "simulate", &m, "--values", &vals, "--input", "u=0.2", "--init", "x1=0", "--until", "1",
        "--every", "1", "--out", &csv,
    ]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time,x1,x2,y"));
    assert_eq!(lines.next(), Some("0.0,0.0,0.5,0.5"));
    let last: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    // x1 from 0 with input 0.2: u/k1 (1 - e^(-k1)).
    close(last[1], u / k1 * (1.0 - (-k1).exp()), "x1 from --init 0");
    bad(
        &[
            "simulate", &m, "--values", &vals, "--input", "u=0.2", "--until", "1", "--every", "1",
            "--out", &csv,
        ],
        "exists",
    );
}

/// S1 -> S2 at rate R1_k * S1 * cell with a local (kinetic-law) parameter k = 0.4,
/// compartment size 2, initial amounts 3 and 1: the concentrations are
/// [S1] = 1.5 e^(-0.4 t) and [S2] = 0.5 + 1.5 (1 - e^(-0.4 t)).
const SBML_DECAY: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="decay">
    <listOfCompartments><compartment id="cell" size="2" constant="true"/></listOfCompartments>
    <listOfSpecies>
      <species id="S1" compartment="cell" initialAmount="3" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="S2" compartment="cell" initialAmount="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
    </listOfSpecies>
    <listOfReactions>
      <reaction id="R1" reversible="false">
        <listOfReactants><speciesReference species="S1" stoichiometry="1" constant="true"/></listOfReactants>
        <listOfProducts><speciesReference species="S2" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>k</ci><ci>S1</ci><ci>cell</ci></apply>
        </math>
        <listOfLocalParameters><localParameter id="k" value="0.4"/></listOfLocalParameters>
        </kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

#[test]
fn simulate_model_from_sbml_values_matches_the_analytic_solution() {
    let src = temp_file("sim-decay.xml", SBML_DECAY);
    let dir = crate::util::fresh_dir("sim-sbml");
    let (sys, vals) = (format!("{dir}/d.sys"), format!("{dir}/d.values"));
    ok(&["import", "sbml", &src, "--out", &sys, "--values", &vals]);
    let (cols, rows) = simulate_json(&[&sys, "--values", &vals, "--until", "10", "--every", "0.5"]);
    let (i1, i2) = (
        cols.iter().position(|c| c == "S1").unwrap(),
        cols.iter().position(|c| c == "S2").unwrap(),
    );
    for r in &rows {
        let e = (-0.4 * r[0]).exp();
        close(r[i1], 1.5 * e, "[S1]");
        close(r[i2], 0.5 + 1.5 * (1.0 - e), "[S2]");
    }
}

#[test]
fn simulate_model_refuses_missing_values_by_name_and_huge_runs() {
    let m = temp_file(
        "two-miss.sys",
        "system two\nstate x1, x2\nparam k1, k2\ninput u\nx1' = u - k1*x1\nx2' = k1*x1 - k2*x2\noutput y = x2\n",
    );
    let e = bad(
        &[
            "simulate", &m, "--set", "k1=1", "--init", "x1=1", "--until", "1", "--every", "0.1",
        ],
        "missing values:",
    );
    for name in ["init x2", "param k2", "input u"] {
        assert!(e.contains(name), "{name} not named in: {e}");
    }
    assert!(!e.contains("k1"), "{e}");
    let full = [
        "simulate", &m, "--set", "k1=1", "--set", "k2=1", "--init", "x1=1", "--init", "x2=1",
        "--input", "u=0",
    ];
    fn with<'a>(full: &[&'a str], extra: &[&'a str]) -> Vec<&'a str> {
        [full, extra].concat()
    }
    bad(
        &with(&full, &["--until", "2e6", "--every", "1"]),
        "at most 1000000",
    );
    bad(&with(&full, &["--until", "1", "--every", "0"]), "--every");
    bad(
        &with(&full, &["--set", "k9=1", "--until", "1", "--every", "1"]),
        "no param or constant 'k9'",
    );
    bad(
        &with(&full, &["--init", "k1=1", "--until", "1", "--every", "1"]),
        "no state 'k1'",
    );
    bad(
        &with(&full, &["--input", "u=abc", "--until", "1", "--every", "1"]),
        "finite number",
    );
    bad(&with(&full, &[]), "--until");
    let vals = temp_file("bad.values", "k1 = 1\nk2 1\n");
    bad(
        &[
            "simulate", &m, "--values", &vals, "--until", "1", "--every", "1",
        ],
        "bad.values:2:1:",
    );
}

#[test]
fn simulate_model_json_has_the_keys_its_help_names() {
    let help = ok(&["simulate", "--help"]);
    assert!(help.contains("at most 1000000 rows"), "{help}");
    let m = temp_file(
        "keys.sys",
        "system k\nstate x\nparam k\nx' = -k*x\noutput y = x\n",
    );
    let out = ok(&[
        "simulate", &m, "--set", "k=1", "--init", "x=1", "--until", "1", "--every", "1", "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    keys.sort();
    let mut promised = vec![
        "model",
        "columns",
        "rows",
        "steps",
        "error_estimate",
        "tolerance",
    ];
    promised.sort();
    assert_eq!(keys, promised);
    let sentence = "--json prints {model, columns, rows, steps, error_estimate, tolerance}";
    assert!(help.contains(sentence), "{help}");
}
