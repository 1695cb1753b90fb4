//! SBML `<piecewise>` of time (dosing switches) imported as known inputs, their course
//! written by `import sbml --inputs-out`, simulated and compared with closed forms derived
//! here; the refusals, each located.

use crate::simulate::{close, simulate_json};
use crate::util::{bad, fresh_dir, obsan, ok, temp_file};

const TIME: &str = r#"<csymbol encoding="text" definitionURL="http://www.sbml.org/sbml/symbols/time">time</csymbol>"#;

/// A model `x' = k * dose` (x in a compartment of size 1, x(0) = 1) with `dose` given by
/// the MathML `dose_math` as an assignment rule, and a kinetic law `law`.
pub(crate) fn model(dose_math: &str, law: &str) -> String {
    format!(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="dosing">
    <listOfCompartments><compartment id="c" size="1" constant="true"/></listOfCompartments>
    <listOfSpecies><species id="x" compartment="c" initialConcentration="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/></listOfSpecies>
    <listOfParameters>
      <parameter id="k" value="0.5" constant="true"/>
      <parameter id="D" value="2" constant="true"/>
      <parameter id="ton" value="4.3" constant="true"/>
      <parameter id="dose" constant="false"/>
    </listOfParameters>
    <listOfRules>
      <assignmentRule variable="dose"><math xmlns="http://www.w3.org/1998/Math/MathML">
{dose_math}
      </math></assignmentRule>
    </listOfRules>
    <listOfReactions>
      <reaction id="R" reversible="false">
        <listOfProducts><speciesReference species="x" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
{law}
        </math></kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#
    )
}

/// `dose = D` from `time >= ton` on, else 0.
fn step_dose() -> String {
    format!(
        "<piecewise><piece><ci>D</ci><apply><geq/>{TIME}<ci>ton</ci></apply></piece>\
         <otherwise><cn>0</cn></otherwise></piecewise>"
    )
}

const K_DOSE: &str = "<apply><times/><ci>k</ci><ci>dose</ci></apply>";

/// `import sbml SRC` writing the `.sys`, its values and the inputs' course up to `until`.
fn import_with_course(src: &str, (sys, vals, inp): (&str, &str, &str), until: &str) {
    ok(&[
        "import",
        "sbml",
        src,
        "--out",
        sys,
        "--values",
        vals,
        "--inputs-out",
        inp,
        "--until",
        until,
    ]);
}

/// The rows of a CSV written by --inputs-out.
fn course(path: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("t,u_dose"));
    lines
        .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
        .collect()
}

#[test]
fn a_dose_switched_on_is_an_input_with_its_exact_step_and_simulates_to_the_closed_form() {
    let src = temp_file("pw-step.xml", &model(&step_dose(), K_DOSE));
    let dir = fresh_dir("pw-step");
    let (sys, vals, inp) = (
        format!("{dir}/m.sys"),
        format!("{dir}/m.values"),
        format!("{dir}/m.csv"),
    );
    // Without --inputs-out: the .sys declares the input and the user is told to supply it.
    let r = obsan(&["import", "sbml", &src]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(r.stdout.contains("input u_dose\n"), "{}", r.stdout);
    assert!(r.stdout.contains("x' = k*u_dose/1\n"), "{}", r.stdout);
    assert!(r.stderr.contains("the known input u_dose"), "{}", r.stderr);
    import_with_course(&src, (&sys, &vals, &inp), "10");
    // The step at ton = 4.3 exactly: 0 before, D = 2 after, constant in between.
    assert_eq!(
        course(&inp),
        vec![
            vec![0.0, 0.0],
            vec![4.3, 0.0],
            vec![4.3, 2.0],
            vec![10.0, 2.0]
        ]
    );
    // x' = k D for t > ton, 0 before: x = 1 + k D max(0, t - ton) = 1 + max(0, t - 4.3).
    let (cols, rows) = simulate_json(&[
        &sys, "--values", &vals, "--inputs", &inp, "--until", "10", "--every", "0.5",
    ]);
    let ix = cols.iter().position(|c| c == "x").unwrap();
    assert_eq!(rows.len(), 21);
    for r in &rows {
        close(r[ix], 1.0 + (r[0] - 4.3).max(0.0), "x");
    }
}

#[test]
fn a_ramp_in_a_window_of_a_kinetic_law_is_written_exactly_and_integrates_to_its_parabola() {
    // Rate k (time - 2) while 2 <= time < 6 (an `and` of two comparisons), else 0; the
    // dose rule is unused (dose = D, constant) so the input is the kinetic law's.
    let law = format!(
        "<piecewise><piece><apply><times/><ci>k</ci><apply><minus/>{TIME}<cn>2</cn></apply></apply>\
         <apply><and/><apply><leq/><cn>2</cn>{TIME}</apply><apply><lt/>{TIME}<cn>6</cn></apply></apply>\
         </piece><otherwise><cn>0</cn></otherwise></piecewise>"
    );
    let src = temp_file("pw-ramp.xml", &model("<ci>D</ci>", &law));
    let dir = fresh_dir("pw-ramp");
    let (sys, vals, inp) = (
        format!("{dir}/m.sys"),
        format!("{dir}/m.values"),
        format!("{dir}/m.csv"),
    );
    import_with_course(&src, (&sys, &vals, &inp), "9");
    let text = std::fs::read_to_string(&inp).unwrap();
    // 0 up to 2 (continuous there: one row), the ramp to k 4 = 2 at 6, the step down, 0 to 9.
    assert_eq!(text, "t,u_R\n0.0,0.0\n2.0,0.0\n6.0,2.0\n6.0,0.0\n9.0,0.0\n");
    // x' = k (t - 2) on [2, 6): x = 1 + k (t - 2)^2 / 2, then constant 1 + k 16 / 2 = 5.
    let (cols, rows) = simulate_json(&[
        &sys, "--values", &vals, "--inputs", &inp, "--until", "9", "--every", "0.25",
    ]);
    let ix = cols.iter().position(|c| c == "x").unwrap();
    for r in &rows {
        let s = (r[0].min(6.0) - 2.0).max(0.0);
        close(r[ix], 1.0 + 0.5 * s * s / 2.0, "x");
    }
}

#[test]
fn piecewise_refusals_are_located() {
    // A piecewise reading a state: refused at the state's <ci>, with the piecewise's line.
    let on_state = "<piecewise><piece><ci>D</ci><apply><gt/><ci>x</ci><cn>3</cn></apply></piece>\
         <otherwise><cn>0</cn></otherwise></piecewise>";
    let src = temp_file("pw-state.xml", &model(on_state, K_DOSE));
    let e = bad(&["import", "sbml", &src], "reads the state 'x'");
    assert!(e.contains("pw-state.xml:14:"), "{e}");
    // time squared in a condition: the import works, the course is refused at the piecewise.
    let sq = format!(
        "<piecewise><piece><ci>D</ci><apply><gt/><apply><times/>{TIME}{TIME}</apply><cn>4</cn>\
         </apply></piece><otherwise><cn>0</cn></otherwise></piecewise>"
    );
    let src = temp_file("pw-sq.xml", &model(&sq, K_DOSE));
    ok(&["import", "sbml", &src]);
    let dir = fresh_dir("pw-refused");
    let inp = format!("{dir}/u.csv");
    let e = bad(
        &["import", "sbml", &src, "--inputs-out", &inp, "--until", "5"],
        "not a comparison of time with a constant expression",
    );
    assert!(e.contains("pw-sq.xml:14:1:"), "{e}");
    assert!(!std::path::Path::new(&inp).exists());
    // A piece not affine in time (exp(-time)): refused, not sampled.
    let expo = format!(
        "<piecewise><piece><apply><exp/><apply><minus/>{TIME}</apply></apply>\
         <apply><geq/>{TIME}<ci>ton</ci></apply></piece><otherwise><cn>0</cn></otherwise></piecewise>"
    );
    let src = temp_file("pw-exp.xml", &model(&expo, K_DOSE));
    bad(
        &["import", "sbml", &src, "--inputs-out", &inp, "--until", "5"],
        "not affine in time",
    );
    // No piece holds and no <otherwise>.
    let none = format!(
        "<piecewise><piece><ci>D</ci><apply><gt/>{TIME}<cn>1</cn></apply></piece></piecewise>"
    );
    let src = temp_file("pw-none.xml", &model(&none, K_DOSE));
    bad(
        &["import", "sbml", &src, "--inputs-out", &inp, "--until", "5"],
        "no piece of this <piecewise> holds at time 0.5",
    );
    // A relation outside a piecewise stays refused.
    let rel = format!("<apply><gt/>{TIME}<cn>1</cn></apply>");
    let src = temp_file("pw-rel.xml", &model(&rel, K_DOSE));
    bad(&["import", "sbml", &src], "MathML <gt> is not supported");
}

#[test]
fn import_json_names_each_file_written_and_a_refused_target_writes_nothing() {
    let src = temp_file("pw-json.xml", &model(&step_dose(), K_DOSE));
    let dir = fresh_dir("pw-json");
    let (sys, vals, inp) = (
        format!("{dir}/m.sys"),
        format!("{dir}/m.values"),
        format!("{dir}/m.csv"),
    );
    let out = ok(&[
        "import",
        "sbml",
        &src,
        "--out",
        &sys,
        "--values",
        &vals,
        "--inputs-out",
        &inp,
        "--until",
        "10",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["format"], "sbml");
    assert_eq!(v["source"], src.as_str());
    assert_eq!(v["values"], vals.as_str());
    assert_eq!(v["inputs_out"], inp.as_str());
    assert_eq!(v["known_inputs"], serde_json::json!(["u_dose"]));
    assert_eq!(v["refused"], serde_json::json!([]));
    let m = &v["models"][0];
    assert_eq!(v["models"].as_array().unwrap().len(), 1);
    assert_eq!(m["path"], sys.as_str());
    assert!(m["text"].is_null());
    // The file named is the model written: its `system` line is the one reported.
    let written = std::fs::read_to_string(&sys).unwrap();
    let system = m["system"].as_str().unwrap();
    assert!(written.contains(&format!("system {system}\n")), "{written}");
    for f in [&vals, &inp] {
        assert!(std::path::Path::new(f).exists(), "{f} not written");
    }
    // Without --out the text is in the report, and it is the text stdout would have held.
    let plain = ok(&["import", "sbml", &src]);
    let v: serde_json::Value =
        serde_json::from_str(&ok(&["import", "sbml", &src, "--json"])).unwrap();
    assert_eq!(v["models"][0]["text"], plain.as_str());
    assert!(v["models"][0]["path"].is_null() && v["values"].is_null());
    // A target that cannot be written (the values file is a folder) is refused before
    // anything is written: no .sys is left behind.
    let dir = fresh_dir("pw-json-partial");
    let (sys, vals) = (format!("{dir}/m.sys"), format!("{dir}/m.values"));
    std::fs::create_dir_all(&vals).unwrap();
    bad(
        &["import", "sbml", &src, "--out", &sys, "--values", &vals],
        "m.values exists",
    );
    assert!(
        !std::path::Path::new(&sys).exists(),
        "a partial import left {sys}"
    );
    bad(
        &[
            "import", "sbml", &src, "--out", &sys, "--values", &vals, "--force",
        ],
        "m.values is a folder",
    );
    assert!(
        !std::path::Path::new(&sys).exists(),
        "a partial import left {sys}"
    );
}
