//! The SBML reader on small models written here (after the SBML semantic test suite's first case
//! and the SBML specification's constructs); expected equations are derived by hand beside each
//! test from SBML's semantics: d[S]/dt = sum(stoichiometry * rate) / compartment size.

use obsan_import::{sbml_to_sys, sbml_values, ImportError};
use obsan_model::System;
use proptest::prelude::*;

/// `d/dt of state` in the imported system equals `want` exactly.
fn equation_is(sys: &str, state: &str, want: &str) {
    let s = System::parse(sys, "t.sys").unwrap_or_else(|e| panic!("{e}\n{sys}"));
    let mut nf = s.normal_form(None, &[]).unwrap();
    let k = nf
        .state
        .iter()
        .position(|n| n == state)
        .unwrap_or_else(|| panic!("no state {state}:\n{sys}"));
    let got = nf.f0[k];
    let w = nf.parse_expr(want, true).unwrap();
    let d = nf.ctx.sub(got, w);
    assert!(
        nf.ctx.is_identically_zero(d),
        "{state}' = {} , wanted {want}\n{sys}",
        nf.ctx.to_text(got)
    );
}

const CASE1: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="case00001" name="S1 to S2">
    <listOfCompartments>
      <compartment id="compartment" size="1" constant="true"/>
    </listOfCompartments>
    <listOfSpecies>
      <species id="S1" compartment="compartment" initialAmount="0.00015" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="S2" compartment="compartment" initialAmount="0" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
    </listOfSpecies>
    <listOfParameters>
      <parameter id="k1" value="1" constant="true"/>
    </listOfParameters>
    <listOfReactions>
      <reaction id="reaction1" reversible="false">
        <listOfReactants><speciesReference species="S1" stoichiometry="1" constant="true"/></listOfReactants>
        <listOfProducts><speciesReference species="S2" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw>
          <math xmlns="http://www.w3.org/1998/Math/MathML">
            <apply><times/><ci> compartment </ci><ci> k1 </ci><ci> S1 </ci></apply>
          </math>
        </kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

#[test]
fn one_reaction_gives_mass_action_equations() {
    // rate = compartment*k1*S1 with compartment = 1: S1' = -k1 S1 / 1, S2' = +k1 S1 / 1.
    let c = sbml_to_sys(CASE1, "case.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S1", "-k1*S1");
    equation_is(&c.sys_text, "S2", "k1*S1");
    assert!(c.sys_text.contains("\nparam k1\n"), "{}", c.sys_text);
    assert!(
        c.sys_text.contains("output y_S1 = S1\noutput y_S2 = S2\n"),
        "{}",
        c.sys_text
    );
    // The S1 equation maps back to the <species id="S1"> element, line 8 column 7.
    let line = c
        .sys_text
        .lines()
        .position(|l| l.starts_with("S1'"))
        .unwrap()
        + 1;
    assert_eq!(c.source_of(line), Some((8, 7)));
}

const RICH: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level2/version4" level="2" version="4">
  <model id="rich" name="Rich model">
    <listOfFunctionDefinitions>
      <functionDefinition id="mm">
        <math xmlns="http://www.w3.org/1998/Math/MathML">
          <lambda><bvar><ci>v</ci></bvar><bvar><ci>s</ci></bvar><bvar><ci>km</ci></bvar>
            <apply><divide/><apply><times/><ci>v</ci><ci>s</ci></apply><apply><plus/><ci>km</ci><ci>s</ci></apply></apply>
          </lambda>
        </math>
      </functionDefinition>
    </listOfFunctionDefinitions>
    <listOfCompartments><compartment id="c" size="2"/></listOfCompartments>
    <listOfSpecies>
      <species id="A" compartment="c" initialConcentration="1"/>
      <species id="B" compartment="c" initialConcentration="1" boundaryCondition="true"/>
      <species id="C" compartment="c" initialConcentration="0"/>
    </listOfSpecies>
    <listOfParameters>
      <parameter id="vf" value="1"/><parameter id="E" value="1" constant="false"/>
      <parameter id="kd" value="0.1"/><parameter id="Vmax" constant="false"/>
    </listOfParameters>
    <listOfRules>
      <assignmentRule variable="Vmax">
        <math xmlns="http://www.w3.org/1998/Math/MathML"><apply><times/><ci>vf</ci><ci>E</ci></apply></math>
      </assignmentRule>
      <rateRule variable="E">
        <math xmlns="http://www.w3.org/1998/Math/MathML"><apply><minus/><apply><times/><ci>kd</ci><ci>E</ci></apply></apply></math>
      </rateRule>
    </listOfRules>
    <listOfReactions>
      <reaction id="R1">
        <listOfReactants><speciesReference species="A"/><speciesReference species="B"/></listOfReactants>
        <listOfProducts><speciesReference species="C" stoichiometry="2"/></listOfProducts>
        <kineticLaw>
          <math xmlns="http://www.w3.org/1998/Math/MathML">
            <apply><times/><ci>c</ci><apply><ci>mm</ci><ci>Vmax</ci><ci>A</ci><ci>Km</ci></apply><ci>B</ci></apply>
          </math>
          <listOfParameters><parameter id="Km" value="0.5"/></listOfParameters>
        </kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

#[test]
fn rules_functions_local_parameters_and_compartments_are_folded() {
    // rate = c * mm(Vmax, A, Km) * B = 2 * (vf E) A / (R1_Km + A) * B (Vmax by its rule, Km
    // local to R1). A' = -rate / 2; C' = 2 rate / 2; B is a boundary species (a param);
    // E' = -kd E by its rate rule.
    let c = sbml_to_sys(RICH, "rich.xml", &["A".into(), "Vmax".into()]).unwrap();
    let t = &c.sys_text;
    equation_is(t, "A", "-vf*E*A*B/(R1_Km + A)");
    equation_is(t, "C", "2*vf*E*A*B/(R1_Km + A)");
    equation_is(t, "E", "-kd*E");
    assert!(t.contains("output y_A = A\noutput y_Vmax = vf*E\n"), "{t}");
    let s = System::parse(t, "r.sys").unwrap();
    let params: Vec<&str> = s
        .decls
        .iter()
        .filter(|d| d.kind == obsan_model::Kind::Param)
        .map(|d| d.name.as_str())
        .collect();
    assert_eq!(params, ["vf", "kd", "R1_Km", "B"], "{t}");
}

const TIME: &str = "<csymbol encoding=\"text\" definitionURL=\"http://www.sbml.org/sbml/symbols/time\">time</csymbol>";

#[test]
fn time_is_the_sys_files_explicit_time() {
    // rate = compartment*k1*t*time with compartment = 1 and a parameter whose id is `t`
    // (written t_, since `t` is time in a .sys): S1' = -k1 t_ t, S2' = k1 t_ t.
    let src = CASE1
        .replace(
            "<ci> S1 </ci></apply>",
            &format!("<ci> t </ci>{TIME}</apply>"),
        )
        .replace(
            "<parameter id=\"k1\" value=\"1\" constant=\"true\"/>",
            "<parameter id=\"k1\" value=\"1\" constant=\"true\"/><parameter id=\"t\" value=\"2\" constant=\"true\"/>",
        );
    let c = sbml_to_sys(&src, "time.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S1", "-k1*t_*t");
    equation_is(&c.sys_text, "S2", "k1*t_*t");
    let vals = sbml_values(&src).unwrap();
    assert!(vals.contains(&("t_".to_string(), 2.0)), "{vals:?}");
    // An initial assignment holds its value at time 0 (the suite's case 00879):
    // k1 = 1/5 + k2 exp(time) is 1/5 + k2 for all times, so S1' = -(1/5 + k2) S1.
    let ia = CASE1.replace(
        "<parameter id=\"k1\" value=\"1\" constant=\"true\"/>",
        &format!(
            "<parameter id=\"k1\" constant=\"true\"/><parameter id=\"k2\" value=\"0.5\" constant=\"true\"/>\
             </listOfParameters><listOfInitialAssignments><initialAssignment symbol=\"k1\">\
             <math xmlns=\"http://www.w3.org/1998/Math/MathML\"><apply><plus/><cn>0.2</cn>\
             <apply><times/><ci>k2</ci><apply><exp/>{TIME}</apply></apply></apply></math>\
             </initialAssignment></listOfInitialAssignments><listOfParameters>"
        ),
    );
    let c = sbml_to_sys(&ia, "ia.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S1", "-(1/5 + k2)*S1");
}

fn refused(src: &str) -> ImportError {
    match sbml_to_sys(src, "x.xml", &[]) {
        Ok(c) => panic!("accepted:\n{}", c.sys_text),
        Err(e) => e,
    }
}

#[test]
fn unsupported_elements_are_refused_at_their_line() {
    let with = |extra: &str| CASE1.replace("  </model>", &format!("{extra}\n  </model>"));
    let e = refused(&with(
        "    <listOfEvents>\n      <event id=\"ev\"/>\n    </listOfEvents>",
    ));
    assert_eq!((e.line, e.col), (26, 7), "{e}");
    assert!(e.message.contains("'ev'"), "{e}");
    let e = refused(&with(
        "    <listOfRules><algebraicRule><math xmlns=\"http://www.w3.org/1998/Math/MathML\"><ci>S1</ci></math></algebraicRule></listOfRules>",
    ));
    assert_eq!((e.line, e.col), (25, 18), "{e}");
    let avogadro = CASE1.replace(
        "<ci> S1 </ci></apply>",
        "<csymbol encoding=\"text\" definitionURL=\"http://www.sbml.org/sbml/symbols/avogadro\">N</csymbol></apply>",
    );
    let e = refused(&avogadro);
    assert_eq!(e.line, 20, "{e}");
    assert!(e.message.contains("avogadro"), "{e}");
    let pw = CASE1.replace("<ci> S1 </ci></apply>", "<piecewise/></apply>");
    assert!(refused(&pw).message.contains("piecewise"));
    let unknown = CASE1.replace("<ci> S1 </ci></apply>", "<ci> S9 </ci></apply>");
    let e = refused(&unknown);
    assert_eq!(e.line, 20, "{e}");
    assert!(e.message.contains("'S9'"), "{e}");
    let cycle = CASE1.replace(
        "  </model>",
        "    <listOfRules>\n      <assignmentRule variable=\"k1\"><math xmlns=\"http://www.w3.org/1998/Math/MathML\"><ci>k2</ci></math></assignmentRule>\n      <assignmentRule variable=\"k2\"><math xmlns=\"http://www.w3.org/1998/Math/MathML\"><ci>k1</ci></math></assignmentRule>\n    </listOfRules>\n  </model>",
    );
    assert!(refused(&cycle).message.contains("cycle"));
    let e = refused("<sbml><model>\n<listOfSpecies>\n</model></sbml>");
    assert_eq!(e.line, 3, "{e}");
    let e = refused(&CASE1.replace(
        "initialAmount=\"0\" ",
        "initialAmount=\"0\" x=\"1\" x=\"2\" ",
    ));
    assert_eq!(e.line, 9, "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Cut or insert anywhere in a valid file: never a panic; a refusal lies inside the text.
    #[test]
    fn never_panics(cut in 0usize..4000, len in 0usize..40, ins in "[ -~\n]{0,8}") {
        let base = RICH;
        let n = base.len();
        let a = (cut % n).min(n);
        let b = (a + len).min(n);
        if base.is_char_boundary(a) && base.is_char_boundary(b) {
            let src = format!("{}{}{}", &base[..a], ins, &base[b..]);
            let lines = src.split('\n').count();
            match sbml_to_sys(&src, "p.xml", &[]) {
                Err(e) => prop_assert!(e.line >= 1 && e.line <= lines, "{e}"),
                Ok(c) => { let _ = System::parse(&c.sys_text, "p.sys"); }
            }
        }
    }
}

const VALUED: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="valued">
    <listOfCompartments>
      <compartment id="cell" size="2" constant="true"/>
    </listOfCompartments>
    <listOfSpecies>
      <species id="A" compartment="cell" initialAmount="3" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="B" compartment="cell" initialConcentration="0.5" hasOnlySubstanceUnits="true" boundaryCondition="false" constant="false"/>
      <species id="C" compartment="cell" initialConcentration="0.25" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
    </listOfSpecies>
    <listOfParameters>
      <parameter id="k" value="0.3" constant="true"/>
      <parameter id="j" value="7" constant="true"/>
    </listOfParameters>
    <listOfInitialAssignments>
      <initialAssignment symbol="j"><math xmlns="http://www.w3.org/1998/Math/MathML"><cn>1</cn></math></initialAssignment>
    </listOfInitialAssignments>
  </model>
</sbml>"#;

#[test]
fn values_are_given_as_the_states_are_written() {
    let got = sbml_values(VALUED).unwrap();
    // By hand, compartment size 2: A's amount 3 is the concentration 3/2;
    // B is an amount (hasOnlySubstanceUnits), 0.5 * 2 = 1; C stays 0.25;
    // j is set by the initial assignment j = 1, which replaces its `value` 7.
    let want: Vec<(String, f64)> = [
        ("A", 1.5),
        ("B", 1.0),
        ("C", 0.25),
        ("cell", 2.0),
        ("j", 1.0),
        ("k", 0.3),
    ]
    .iter()
    .map(|(n, v)| (n.to_string(), *v))
    .collect();
    assert_eq!(got, want);
}

#[test]
fn values_of_unreadable_xml_are_a_located_error() {
    let e = sbml_values("<sbml>\n<model>\n</sbml>").unwrap_err();
    assert_eq!(e.line, 3, "{e:?}");
}

#[test]
fn values_name_kinetic_law_parameters_as_the_sys_does() {
    // Reaction r1's local k (value 0.4) is the `.sys` param r1_k; the global k keeps 2.
    let text = r#"<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
<model id="m">
  <listOfCompartments><compartment id="c" size="1" constant="true"/></listOfCompartments>
  <listOfSpecies><species id="S" compartment="c" initialConcentration="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/></listOfSpecies>
  <listOfParameters><parameter id="k" value="2" constant="true"/></listOfParameters>
  <listOfReactions><reaction id="r1" reversible="false">
    <listOfReactants><speciesReference species="S" stoichiometry="1" constant="true"/></listOfReactants>
    <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><times/><ci>k</ci><ci>S</ci></apply></math>
      <listOfLocalParameters><localParameter id="k" value="0.4"/></listOfLocalParameters>
    </kineticLaw>
  </reaction></listOfReactions>
</model>
</sbml>"#;
    let got = sbml_values(text).unwrap();
    let want: Vec<(String, f64)> = [("S", 1.0), ("c", 1.0), ("k", 2.0), ("r1_k", 0.4)]
        .iter()
        .map(|(n, v)| (n.to_string(), *v))
        .collect();
    assert_eq!(got, want);
    let sys = sbml_to_sys(text, "m.xml", &[]).unwrap().sys_text;
    assert!(sys.contains("r1_k"), "{sys}");
}

#[test]
fn values_evaluate_initial_assignments_before_dividing_by_a_size() {
    // c's size 1 is replaced by the initial assignment c = 2 p = 2 * 0.5 = 1 (by hand); A's
    // amount 3 is divided by that size: concentration 3 / 1 = 3 (not by the stale attribute).
    let text = r#"<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
<model id="m">
  <listOfCompartments><compartment id="c" size="1" constant="true"/></listOfCompartments>
  <listOfSpecies><species id="A" compartment="c" initialAmount="3" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/></listOfSpecies>
  <listOfParameters><parameter id="p" value="0.5" constant="true"/></listOfParameters>
  <listOfInitialAssignments><initialAssignment symbol="c"><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><times/><cn>2</cn><ci>p</ci></apply></math></initialAssignment></listOfInitialAssignments>
</model>
</sbml>"#;
    let text = text.replace("value=\"0.5\"", "value=\"1.5\"");
    // With p = 1.5: c = 3, A = 3 / 3 = 1.
    let want: Vec<(String, f64)> = [("A", 1.0), ("c", 3.0), ("p", 1.5)]
        .iter()
        .map(|(n, v)| (n.to_string(), *v))
        .collect();
    assert_eq!(sbml_values(&text).unwrap(), want);
}

#[test]
fn values_evaluate_initial_assignments_that_use_each_other() {
    // After the suite's case 00471 (C = k2 / 50), chained: k2 = 2 k1 = 2 * 25 = 50, so C = 1,
    // and S's amount 2 over C is the concentration 2. An assignment that reads a value the
    // file does not give (q) is left out, not guessed.
    let text = r#"<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
<model id="m">
  <listOfCompartments><compartment id="C" size="7" constant="true"/></listOfCompartments>
  <listOfSpecies><species id="S" compartment="C" initialAmount="2" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/></listOfSpecies>
  <listOfParameters><parameter id="k1" value="25" constant="true"/><parameter id="k2" constant="true"/><parameter id="q" constant="true"/><parameter id="z" value="9" constant="true"/></listOfParameters>
  <listOfInitialAssignments>
    <initialAssignment symbol="C"><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><divide/><ci>k2</ci><cn type="integer">50</cn></apply></math></initialAssignment>
    <initialAssignment symbol="k2"><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><times/><cn>2</cn><ci>k1</ci></apply></math></initialAssignment>
    <initialAssignment symbol="z"><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><plus/><ci>q</ci><cn>1</cn></apply></math></initialAssignment>
  </listOfInitialAssignments>
</model>
</sbml>"#;
    let want: Vec<(String, f64)> = [("C", 1.0), ("S", 2.0), ("k1", 25.0), ("k2", 50.0)]
        .iter()
        .map(|(n, v)| (n.to_string(), *v))
        .collect();
    assert_eq!(sbml_values(text).unwrap(), want);
}

#[test]
fn fast_reactions_are_refused_at_their_line() {
    // SBML's fast reactions are in rapid equilibrium (an algebraic constraint): no .sys form.
    let e = refused(&CASE1.replace(
        r#"<reaction id="reaction1" reversible="false">"#,
        r#"<reaction id="reaction1" reversible="false" fast="true">"#,
    ));
    // CASE1's <reaction> is on its line 15.
    assert_eq!((e.line, e.col), (15, 7), "{e}");
    assert!(
        e.message.contains("'reaction1'") && e.message.contains("fast"),
        "{e}"
    );
}

#[test]
fn a_species_reference_id_is_its_stoichiometry() {
    // The product's reference `st` (stoichiometry 3): S2' = 3 k1 S1 (compartment 1), and the
    // kinetic law may read it too.
    let with_id = CASE1.replace(
        r#"<listOfProducts><speciesReference species="S2" stoichiometry="1""#,
        r#"<listOfProducts><speciesReference id="st" species="S2" stoichiometry="3""#,
    );
    let c = sbml_to_sys(&with_id, "x.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S2", "3*k1*S1");
    equation_is(&c.sys_text, "S1", "-k1*S1");
    // An initial assignment st = 2 k1 holds at all times (no events): S2' = 2 k1 * k1 S1.
    let ia = with_id.replace(
        "    <listOfReactions>",
        "    <listOfInitialAssignments><initialAssignment symbol=\"st\"><math xmlns=\"http://www.w3.org/1998/Math/MathML\"><apply><times/><cn>2</cn><ci>k1</ci></apply></math></initialAssignment></listOfInitialAssignments>\n    <listOfReactions>",
    );
    let c = sbml_to_sys(&ia, "x.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S2", "2*k1*k1*S1");
    // A rate rule st' = k1 makes it a state, with its attribute as initial value.
    let rr = with_id.replace(
        "    <listOfReactions>",
        "    <listOfRules><rateRule variable=\"st\"><math xmlns=\"http://www.w3.org/1998/Math/MathML\"><ci>k1</ci></math></rateRule></listOfRules>\n    <listOfReactions>",
    );
    let c = sbml_to_sys(&rr, "x.xml", &[]).unwrap();
    equation_is(&c.sys_text, "st", "k1");
    equation_is(&c.sys_text, "S2", "st*k1*S1");
    assert!(sbml_values(&rr).unwrap().contains(&("st".to_string(), 3.0)));
}

#[test]
fn stoichiometry_math_is_the_stoichiometry() {
    // SBML Level 2's <stoichiometryMath> 2 k1: S2' = 2 k1 * k1 S1.
    let c = sbml_to_sys(
        &CASE1.replace(
            r#"<speciesReference species="S2" stoichiometry="1" constant="true"/>"#,
            r#"<speciesReference species="S2"><stoichiometryMath><math xmlns="http://www.w3.org/1998/Math/MathML"><apply><times/><cn>2</cn><ci>k1</ci></apply></math></stoichiometryMath></speciesReference>"#,
        ),
        "x.xml",
        &[],
    )
    .unwrap();
    equation_is(&c.sys_text, "S2", "2*k1*k1*S1");
}

#[test]
fn conversion_factors_multiply_the_reaction_terms() {
    // SBML Level 3: dS/dt = conversionFactor * (sum of stoichiometry * rate) / size; the
    // model's factor cf applies to S1, S2's own cf2 overrides it.
    let text = CASE1
        .replace(
            r#"<model id="case00001""#,
            r#"<model id="case00001" conversionFactor="cf""#,
        )
        .replace(
            r#"<species id="S2" compartment="compartment""#,
            r#"<species id="S2" conversionFactor="cf2" compartment="compartment""#,
        )
        .replace(
            r#"<parameter id="k1" value="1" constant="true"/>"#,
            r#"<parameter id="k1" value="1" constant="true"/><parameter id="cf" value="2" constant="true"/><parameter id="cf2" value="3" constant="true"/>"#,
        );
    let c = sbml_to_sys(&text, "x.xml", &[]).unwrap();
    equation_is(&c.sys_text, "S1", "-cf*k1*S1");
    equation_is(&c.sys_text, "S2", "cf2*k1*S1");
}

/// CASE1 with its first kinetic law times a dose switched on at time 2 for a ramp.
fn dosed() -> String {
    CASE1.replace(
        "<ci> S1 </ci></apply>",
        &format!(
            "<ci> S1 </ci><piecewise><piece><apply><times/><cn>3</cn><apply><minus/>{TIME}<cn>2</cn>\
             </apply></apply><apply><geq/>{TIME}<cn>2</cn></apply></piece><otherwise><cn>0</cn>\
             </otherwise></piecewise></apply>"
        ),
    )
}

#[test]
fn a_piecewise_of_time_in_a_kinetic_law_is_a_known_input_with_its_course() {
    let c = sbml_to_sys(&dosed(), "x.xml", &[]).unwrap();
    assert!(
        c.sys_text.contains("\ninput u_reaction1\n"),
        "{}",
        c.sys_text
    );
    let i = obsan_import::sbml_inputs(&dosed(), Some(4.0)).unwrap();
    assert_eq!(i.names, vec!["u_reaction1".to_string()]);
    // 0 until 2, then 3 (t - 2): continuous at 2 (one row), 6 at 4.
    assert_eq!(i.csv(), "t,u_reaction1\n0.0,0.0\n2.0,0.0\n4.0,6.0\n");
    // No horizon: the names only.
    assert!(obsan_import::sbml_inputs(&dosed(), None)
        .unwrap()
        .rows
        .is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Cut or insert anywhere in a file with a piecewise: writing its course never panics,
    /// and a refusal lies inside the text.
    #[test]
    fn inputs_never_panic(cut in 0usize..4000, len in 0usize..40, ins in "[ -~\n]{0,8}") {
        let base = dosed();
        let n = base.len();
        let a = (cut % n).min(n);
        let b = (a + len).min(n);
        if base.is_char_boundary(a) && base.is_char_boundary(b) {
            let src = format!("{}{}{}", &base[..a], ins, &base[b..]);
            let lines = src.split('\n').count();
            if let Err(e) = obsan_import::sbml_inputs(&src, Some(10.0)) {
                prop_assert!(e.line >= 1 && e.line <= lines, "{e}");
            }
        }
    }
}
