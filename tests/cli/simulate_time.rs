//! `obsan simulate MODEL.sys` with explicit time `t`, inputs that are
//! expressions of `t` (`--input u=EXPR`) and inputs from a time course
//! (`--inputs FILE.csv`). Each expected value is a closed form derived beside it.

use crate::simulate::{close, simulate_json};
use crate::util::*;

#[test]
fn explicit_time_in_a_field_matches_the_closed_forms() {
    // x' = t: x = x0 + t^2/2.
    let m = temp_file(
        "t-ramp.sys",
        "system ramp\nstate x\nx' = t\noutput y = 2*x\n",
    );
    let (cols, rows) = simulate_json(&[&m, "--init", "x=1", "--until", "3", "--every", "0.25"]);
    assert_eq!(cols, ["time", "x", "y"], "the clock is not printed");
    assert_eq!(rows.len(), 13);
    for r in &rows {
        close(r[1], 1.0 + r[0] * r[0] / 2.0, "x = 1 + t^2/2");
        close(r[2], 2.0 + r[0] * r[0], "y = 2 x");
    }
    // x' = -x + sin(t): a particular solution A sin t + B cos t needs A = -B and
    // -B = -A + 1, so A = 1/2, B = -1/2; with x(0) = x0,
    // x = (x0 + 1/2) e^(-t) + (sin t - cos t)/2.
    let m = temp_file(
        "t-forced.sys",
        "system forced\nstate x\nx' = -x + sin(t)\noutput y = x\n",
    );
    let (_, rows) = simulate_json(&[&m, "--init", "x=0.3", "--until", "10", "--every", "0.5"]);
    for r in &rows {
        let t = r[0];
        close(r[1], 0.8 * (-t).exp() + (t.sin() - t.cos()) / 2.0, "x");
    }
    // Time in an output: y = t x with x' = 0.
    let m = temp_file("t-out.sys", "system out\nstate x\nx' = 0\noutput y = t*x\n");
    let (_, rows) = simulate_json(&[&m, "--init", "x=2", "--until", "1", "--every", "0.5"]);
    for r in &rows {
        close(r[2], 2.0 * r[0], "y = t x");
    }
}

const INTEGRATOR: &str = "system acc\nstate x\nparam k\ninput u\nx' = k*u\noutput y = x\n";

#[test]
fn an_input_given_as_an_expression_of_time() {
    // x' = k u with u = sin(t), k = 1: x = x0 + 1 - cos(t).
    let m = temp_file("u-sin.sys", INTEGRATOR);
    let (_, rows) = simulate_json(&[
        &m, "--set", "k=1", "--init", "x=0.5", "--input", "u=sin(t)", "--until", "8", "--every",
        "0.5",
    ]);
    for r in &rows {
        close(r[1], 0.5 + 1.0 - r[0].cos(), "x = x0 + 1 - cos t");
    }
    // The model's params may appear: u = k t with k = 2 gives x' = 2 (2 t), x = 2 t^2.
    let (_, rows) = simulate_json(&[
        &m, "--set", "k=2", "--init", "x=0", "--input", "u=k*t", "--until", "2", "--every", "0.5",
    ]);
    for r in &rows {
        close(r[1], 2.0 * r[0] * r[0], "x = 2 t^2");
    }
    let base = [
        "simulate", &m, "--set", "k=1", "--init", "x=0", "--until", "1", "--every", "1",
    ];
    let with = |extra: &[&'static str]| -> Vec<String> {
        base.iter()
            .map(|s| s.to_string())
            .chain(extra.iter().map(|s| s.to_string()))
            .collect()
    };
    let run = |extra: &[&'static str], want: &str| {
        let a = with(extra);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        bad(&a, want)
    };
    // A name that is not t, a param or a constant: located at its column (9 in `u=2*sin(s)`).
    let e = run(&["--input", "u=2*sin(s)"], "--input u=2*sin(s): column 9:");
    assert!(e.contains("'s' is not t, a param or a constant"), "{e}");
    run(&["--input", "u=sin(t"], "--input u=sin(t: column");
    run(&["--input", "v=1"], "the model has no input 'v'");
}

/// The inputs file of the step test: u = 2 t up to t = 1, then a step to -1.
const STEP: &str = "# a ramp, then a step down\nt,u\n0,0\n1,2\n1,-1\n3,-1\n";

#[test]
fn an_input_time_course_with_a_step_integrates_exactly() {
    // x' = u: on [0, 1] u = 2 t, x = x0 + t^2; at 1 the step, then u = -1:
    // x = x0 + 1 - (t - 1). RK4 is exact on each piece (u linear in t), so only
    // the breakpoint at the step can spoil it, and the integrator stops there.
    let m = temp_file("u-step.sys", INTEGRATOR);
    let csv = temp_file("u-step.csv", STEP);
    let (cols, rows) = simulate_json(&[
        &m, "--set", "k=1", "--init", "x=0.5", "--inputs", &csv, "--until", "3", "--every", "0.25",
    ]);
    assert_eq!(cols, ["time", "x", "y"]);
    for r in &rows {
        let t = r[0];
        let x = if t <= 1.0 {
            0.5 + t * t
        } else {
            0.5 + 1.0 - (t - 1.0)
        };
        close(r[1], x, "piecewise x");
    }
    // A kink between output times (at 0.3, outputs every 0.25): u = 2 t, then 0:
    // x = x0 + t^2 up to 0.3, then x0 + 0.09.
    let csv = temp_file("u-kink.csv", "t,u\n0,0\n0.3,0.6\n0.3,0\n1,0\n");
    let (_, rows) = simulate_json(&[
        &m, "--set", "k=1", "--init", "x=0", "--inputs", &csv, "--until", "1", "--every", "0.25",
    ]);
    for r in &rows {
        let t = r[0];
        close(
            r[1],
            if t <= 0.3 { t * t } else { 0.09 },
            "x with a step at 0.3",
        );
    }
}

#[test]
fn an_inputs_file_is_refused_at_its_line_and_column() {
    let m = temp_file("u-bad.sys", INTEGRATOR);
    let args = |csv: &str, until: &'static str| -> Vec<String> {
        [
            "simulate", &m, "--set", "k=1", "--init", "x=0", "--inputs", csv, "--until", until,
            "--every", "1",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };
    let check = |name: &str, text: &str, until: &'static str, want: &str| {
        let csv = temp_file(name, text);
        let a = args(&csv, until);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        bad(&a, &format!("{csv}{want}"));
    };
    check(
        "short.csv",
        "t,u\n0,0\n1,1\n",
        "2",
        ":3:1: the inputs end at t 1",
    );
    check(
        "late.csv",
        "t,u\n0.5,0\n3,1\n",
        "2",
        ":2:1: the inputs start at t 0.5",
    );
    check(
        "cell.csv",
        "t,u\n0,0\n1,zero\n",
        "1",
        ":3:3: u 'zero' is not a finite number",
    );
    check(
        "back.csv",
        "t,u\n0,0\n2,1\n1,1\n",
        "1",
        ":4:1: t 1 is before",
    );
    check(
        "col.csv",
        "t,u,v\n0,0,0\n1,1,1\n",
        "1",
        ":1:5: the model has no input 'v'",
    );
    check(
        "head.csv",
        "time,u\n0,0\n",
        "1",
        ":1:1: the first column must be 't'",
    );
    // Given both ways.
    let csv = temp_file("both.csv", "t,u\n0,0\n1,1\n");
    bad(
        &[
            "simulate", &m, "--set", "k=1", "--init", "x=0", "--inputs", &csv, "--input", "u=1",
            "--until", "1", "--every", "1",
        ],
        "input 'u' is also given by --input",
    );
}

/// -> S1 at rate k * time (substance per time) with k = 0.4 in a compartment of size 2,
/// initial amount 1: d[S1]/dt = 0.4 t / 2, so [S1] = 0.5 + 0.1 t^2.
const SBML_TIMED: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="timed">
    <listOfCompartments><compartment id="cell" size="2" constant="true"/></listOfCompartments>
    <listOfSpecies>
      <species id="S1" compartment="cell" initialAmount="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
    </listOfSpecies>
    <listOfParameters><parameter id="k" value="0.4" constant="true"/></listOfParameters>
    <listOfReactions>
      <reaction id="R1" reversible="false">
        <listOfProducts><speciesReference species="S1" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>k</ci><csymbol encoding="text" definitionURL="http://www.sbml.org/sbml/symbols/time">time</csymbol></apply>
        </math></kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

#[test]
fn sbml_time_imports_as_t_and_simulates_to_the_closed_form() {
    let src = temp_file("timed.xml", SBML_TIMED);
    let dir = fresh_dir("sim-sbml-time");
    let (sys, vals) = (format!("{dir}/t.sys"), format!("{dir}/t.values"));
    ok(&["import", "sbml", &src, "--out", &sys, "--values", &vals]);
    let text = std::fs::read_to_string(&sys).unwrap();
    assert!(text.contains("k*t"), "{text}");
    let (cols, rows) = simulate_json(&[&sys, "--values", &vals, "--until", "4", "--every", "0.5"]);
    let i = cols.iter().position(|c| c == "S1").unwrap();
    for r in &rows {
        close(r[i], 0.5 + 0.1 * r[0] * r[0], "[S1]");
    }
}
