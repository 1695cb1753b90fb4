//! The PEtab reader on a real problem of the PEtab benchmark collection
//! (Bertozzi_PNAS2020, BSD-3, tests/petab/ with its source) and on a small
//! problem written here. Expected equations are derived by hand beside each
//! test from the SBML and PEtab semantics (d[S]/dt = sum(stoichiometry *
//! rate) / size; estimated parameters unknown, fixed ones at their values;
//! one model copy per simulation condition).

use obsan_import::{petab_files, petab_to_sys, PetabFile, PetabTexts};
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

fn decl_names(sys: &str, kind: obsan_model::Kind) -> Vec<String> {
    let s = System::parse(sys, "t.sys").unwrap();
    s.decls
        .iter()
        .filter(|d| d.kind == kind)
        .map(|d| d.name.clone())
        .collect()
}

const B: &str = "tests/petab/Bertozzi_PNAS2020/";

#[test]
fn bertozzi_two_conditions_share_nothing_but_the_model() {
    let yaml = include_str!("petab/Bertozzi_PNAS2020/problem.yaml");
    let f = petab_files(yaml).unwrap();
    assert_eq!(f.sbml, "model.xml");
    assert_eq!(f.measurements, ["measurements.tsv"]);
    let t = PetabTexts {
        sbml: include_str!("petab/Bertozzi_PNAS2020/model.xml"),
        parameters: include_str!("petab/Bertozzi_PNAS2020/parameters.tsv"),
        observables: include_str!("petab/Bertozzi_PNAS2020/observables.tsv"),
        conditions: include_str!("petab/Bertozzi_PNAS2020/conditions.tsv"),
        measurements: vec![include_str!("petab/Bertozzi_PNAS2020/measurements.tsv")],
    };
    let c = petab_to_sys(&t, B, None).unwrap();
    let s = &c.sys_text;
    // SIR: infection S + I -> 2 I at beta_N*I*S, recovery I -> R at gamma_*I, amounts
    // (hasOnlySubstanceUnits), beta_N = R0_*gamma_/N_ (a constant's initial assignment).
    // Condition u_CA sets N_ = 39560000, R0_ = R0_CA, gamma_ = gamma_CA (both estimated):
    // I' = -beta I S + 2 beta I S - gamma I = beta I S - gamma I.
    equation_is(
        s,
        "I__u_CA",
        "R0_CA*gamma_CA/39560000*I__u_CA*S__u_CA - gamma_CA*I__u_CA",
    );
    equation_is(s, "S__u_CA", "-R0_CA*gamma_CA/39560000*I__u_CA*S__u_CA");
    equation_is(s, "R__u_NY", "gamma_NY*I__u_NY");
    equation_is(
        s,
        "I__u_NY",
        "R0_NY*gamma_NY/19540000*I__u_NY*S__u_NY - gamma_NY*I__u_NY",
    );
    // Each observable (I_) is measured in its own condition only.
    assert!(s.contains("output y_I_CA_u_CA = I__u_CA\n"), "{s}");
    assert!(s.contains("output y_I_NY_u_NY = I__u_NY\n"), "{s}");
    assert!(!s.contains("y_I_CA_u_NY"), "{s}");
    // I0_ only sets initial values; the noise parameters sd_ are not in any formula.
    let mut p = decl_names(s, obsan_model::Kind::Param);
    p.sort();
    assert_eq!(p, ["R0_CA", "R0_NY", "gamma_CA", "gamma_NY"]);
    // One condition alone: no suffixes, the other observable is not measured there.
    let c = petab_to_sys(&t, B, Some("u_NY")).unwrap();
    equation_is(
        &c.sys_text,
        "I_",
        "R0_NY*gamma_NY/19540000*I_*S_ - gamma_NY*I_",
    );
    assert!(
        c.sys_text.contains("output y_I_NY = I_\n"),
        "{}",
        c.sys_text
    );
}

const SBML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="mini">
    <listOfCompartments><compartment id="c" size="2" constant="true"/></listOfCompartments>
    <listOfSpecies>
      <species id="A" compartment="c" initialConcentration="1" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="B" compartment="c" initialConcentration="0" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="ext" compartment="c" initialConcentration="1" hasOnlySubstanceUnits="false" boundaryCondition="true" constant="false"/>
    </listOfSpecies>
    <listOfParameters>
      <parameter id="k1" value="0.5" constant="true"/>
      <parameter id="kin" value="7" constant="true"/>
    </listOfParameters>
    <listOfReactions>
      <reaction id="R0" reversible="false">
        <listOfProducts><speciesReference species="A" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>c</ci><ci>kin</ci><ci>ext</ci></apply></math></kineticLaw>
      </reaction>
      <reaction id="R1" reversible="false">
        <listOfReactants><speciesReference species="A" stoichiometry="1" constant="true"/></listOfReactants>
        <listOfProducts><speciesReference species="B" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>c</ci><ci>k1</ci><ci>A</ci></apply></math></kineticLaw>
      </reaction>
      <reaction id="R2" reversible="false">
        <listOfReactants><speciesReference species="B" stoichiometry="1" constant="true"/></listOfReactants>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>c</ci><ci>kdeg</ci><ci>B</ci></apply></math>
          <listOfLocalParameters><localParameter id="kdeg" value="3"/></listOfLocalParameters>
        </kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

const PARAMS: &str = "parameterId\tparameterScale\tnominalValue\testimate\n\
k1\tlog10\t0.5\t1\n\
kin\tlin\t0.25\t0\n\
scale\tlog10\t1\t1\n\
offset\tlin\t2\t0\n";

const OBS: &str = "observableId\tobservableFormula\tnoiseFormula\n\
obsB\tobservableParameter1_obsB * B + offset\tsd\n\
obsA\tA ** 2\tsd\n";

const CONDS: &str = "conditionId\tconditionName\text\tA\n\
c1\tfirst\t3\t1\n\
c2\tsecond\t5\t1\n";

const MEAS: &str = "observableId\tsimulationConditionId\tmeasurement\ttime\tobservableParameters\n\
obsB\tc1\t0.1\t1\tscale\n\
obsB\tc1\t0.1\t2\tscale\n\
obsB\tc1\t0.1\t2\t1.5\n\
obsA\tc2\t0.1\t2\t\n";

fn mini<'a>(p: &'a str, o: &'a str, c: &'a str, m: &'a str) -> PetabTexts<'a> {
    PetabTexts {
        sbml: SBML,
        parameters: p,
        observables: o,
        conditions: c,
        measurements: vec![m],
    }
}

#[test]
fn estimated_fixed_conditions_and_overrides() {
    let c = petab_to_sys(&mini(PARAMS, OBS, CONDS, MEAS), "mini.yaml", None).unwrap();
    let s = &c.sys_text;
    // A' = (c kin ext - c k1 A)/c = kin ext - k1 A; kin is fixed in the table at 0.25 (not
    // its SBML value 7); ext (a boundary species) is 3 in c1 and 5 in c2.
    equation_is(s, "A_c1", "kin*3 - k1*A_c1");
    equation_is(s, "A_c2", "kin*5 - k1*A_c2");
    // B' = k1 A - kdeg B; kdeg is local to R2, not in the table: its SBML value 3.
    equation_is(s, "B_c2", "k1*A_c2 - R2_kdeg*B_c2");
    assert!(s.contains("\nconst kin = 0.25\n"), "{s}");
    assert!(s.contains("\nconst R2_kdeg = 3\n"), "{s}");
    assert!(s.contains("\nconst offset = 2\n"), "{s}");
    let mut p = decl_names(s, obsan_model::Kind::Param);
    p.sort();
    assert_eq!(p, ["k1", "scale"]);
    // obsB is measured in c1 with two overrides (scale, 1.5): two outputs; obsA in c2 only.
    assert!(
        s.contains("output obsB_c1_1 = scale*B_c1 + offset\n"),
        "{s}"
    );
    assert!(s.contains("output obsB_c1_2 = 1.5*B_c1 + offset\n"), "{s}");
    assert!(s.contains("output obsA_c2 = A_c2^2\n"), "{s}");
    assert!(!s.contains("obsA_c1") && !s.contains("obsB_c2"), "{s}");
    // The initial value the conditions give A is not read, and said so.
    assert!(s.contains("initial values set by conditions"), "{s}");
    // An output line maps back to its observable's formula: line 2, column 6.
    let line = s
        .lines()
        .position(|l| l.starts_with("output obsB_c1_1"))
        .unwrap()
        + 1;
    assert!(c.table_lines.contains(&line));
    assert_eq!(c.source_of(line), Some((2, 6)));
}

#[test]
fn mistakes_are_located_in_their_file() {
    let at = |r: Result<obsan_import::Converted, obsan_import::PetabError>| {
        let e = r.unwrap_err();
        (e.file, e.error.line, e.error.col, e.error.message)
    };
    // estimate = 2 (row 3, fourth column: after "kin\tlin\t0.25\t").
    let p = PARAMS.replace("kin\tlin\t0.25\t0", "kin\tlin\t0.25\t2");
    let (f, l, c, m) = at(petab_to_sys(&mini(&p, OBS, CONDS, MEAS), "m", None));
    assert_eq!((f, l, c), (PetabFile::Parameters, 3, 14), "{m}");
    // An unknown name in a formula, at its column ("obsA\tA ** 2 + Q": Q is column 15).
    let o = OBS.replace("A ** 2", "A ** 2 + Q");
    let (f, l, c, m) = at(petab_to_sys(&mini(PARAMS, &o, CONDS, MEAS), "m", None));
    assert_eq!((f, l, c), (PetabFile::Observables, 3, 15), "{m}");
    // A condition column that is no id of the model: the cell of the first condition.
    let k = CONDS.replace("\text\t", "\tzz\t");
    let (f, l, c, m) = at(petab_to_sys(&mini(PARAMS, OBS, &k, MEAS), "m", None));
    assert_eq!((f, l, c), (PetabFile::Conditions, 2, 10), "{m}");
    assert!(m.contains("'zz'"), "{m}");
    // A fixed parameter without a nominal value.
    let p = PARAMS.replace("offset\tlin\t2\t0", "offset\tlin\t\t0");
    let (f, l, _, m) = at(petab_to_sys(&mini(&p, OBS, CONDS, MEAS), "m", None));
    assert_eq!((f, l), (PetabFile::Parameters, 5), "{m}");
    // A missing column.
    let (f, l, _, m) = at(petab_to_sys(
        &mini(PARAMS, "id\tformula\n", CONDS, MEAS),
        "m",
        None,
    ));
    assert_eq!((f, l), (PetabFile::Observables, 1), "{m}");
    // Problem files: two models, PEtab v2.
    let e = petab_files(
        "format_version: 1\nparameter_file: p.tsv\nproblems:\n- sbml_files: [a.xml, b.xml]\n",
    )
    .unwrap_err();
    assert_eq!(e.line, 4, "{e}");
    let e = petab_files("format_version: 2.0.0\n").unwrap_err();
    assert_eq!((e.line, e.col), (1, 17), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]
    /// Mutated problems (a byte replaced in any file) never panic.
    #[test]
    fn never_panics(k in 0usize..5, pos in 0usize..4000, ch in proptest::char::any()) {
        let mut files = [SBML.to_string(), PARAMS.to_string(), OBS.to_string(), CONDS.to_string(), MEAS.to_string()];
        let f = &mut files[k];
        let mut cs: Vec<char> = f.chars().collect();
        let i = pos % cs.len();
        cs[i] = ch;
        *f = cs.into_iter().collect();
        let _ = petab_to_sys(&mini(&files[1], &files[2], &files[3], &files[4]).with_sbml(&files[0]), "m", None);
        let _ = petab_files(&files[k]);
    }
}

trait WithSbml<'a> {
    fn with_sbml(self, s: &'a str) -> Self;
}

impl<'a> WithSbml<'a> for PetabTexts<'a> {
    fn with_sbml(mut self, s: &'a str) -> Self {
        self.sbml = s;
        self
    }
}
