//! `obsan import si-jl`: StructuralIdentifiability.jl's @ODEmodel text to .sys, end to end.
//! Expected verdicts are published ones (SI.jl's README example) or derived beside the test.

use crate::util::*;
use serde_json::Value;

/// Two models in SI.jl's benchmarks.jl layout. :Readme is SI.jl's README example, whose
/// published answer is: x3 and b not identifiable (only x3/b is seen), everything else locally
/// identifiable, so rank 7 - 1 = 6. :Lin is x' = -k x + u, y = x: k and x observable, rank 2.
const TWO: &str = r#"benchmarks = Dict(
    :Readme => Dict(
        :name => "README example",
        :ode => @ODEmodel(
            x1'(t) = -(a01 + a21) * x1(t) + a12 * x2(t) + u(t),
            x2'(t) = a21 * x1(t) - a12 * x2(t) - x3(t) / b,
            x3'(t) = x3(t),
            y(t) = x2(t)
        ),
    ),
    :Lin => Dict(:name => "Linear", :ode => @ODEmodel(x'(t) = -k * x(t) + u(t), y(t) = x(t))),
)
"#;

#[test]
fn si_jl_import_lists_converts_and_the_verdict_is_the_published_one() {
    let src = temp_file("two.jl", TWO);
    let list = ok(&["import", "si-jl", &src, "--list"]);
    let keys: Vec<&str> = list
        .lines()
        .map(|l| l.split('\t').next().unwrap())
        .collect();
    assert_eq!(keys, ["Readme", "Lin"]);
    bad(&["import", "si-jl", &src], "holds 2 models");
    bad(
        &["import", "si-jl", &src, "--model", "Nope"],
        "no model 'Nope'",
    );
    let dir = fresh_dir("sijl-one");
    let out = format!("{dir}/readme.sys");
    ok(&["import", "si-jl", &src, "--model", "Readme", "--out", &out]);
    bad(
        &["import", "si-jl", &src, "--model", "Readme", "--out", &out],
        "--force",
    );
    let v: Value = serde_json::from_str(&ok(&["rank", &out, "--json"])).unwrap();
    assert_eq!(v["n"], 7);
    assert_eq!(v["rank"], 6);
    let un: Vec<&str> = v["unobservable_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(un, ["x3", "b"]);
    let stdout = ok(&["import", "si-jl", &src, "--model", "Lin"]);
    assert!(stdout.contains("x' = -k*x + u\n"), "{stdout}");
}

#[test]
fn si_jl_model_outside_the_class_is_refused_at_its_line_and_all_writes_the_rest() {
    // x' = p*u/(k + u) is not affine in u (as SI.jl's p53 model): refused at line 4, column 9,
    // where the equation of x starts in the Julia file.
    let text = "\nbenchmarks[:Sat] = Dict(:name => \"Saturating\", :ode => @ODEmodel(\n    \
                z'(t) = -z(t),\n    x'(t) = p * u(t) / (k + u(t)),\n    y(t) = x(t) + z(t)))\n";
    let src = temp_file("sat.jl", text);
    let e = bad(&["import", "si-jl", &src], "not affine in the inputs");
    assert!(e.contains(&format!("{src}:4:5: model :Sat")), "{e}");
    let both = temp_file("both.jl", &format!("{TWO}{text}"));
    let dir = fresh_dir("sijl-all");
    bad(&["import", "si-jl", &both, "--all", &dir], "1 model(s)");
    assert!(std::path::Path::new(&format!("{dir}/Readme.sys")).exists());
    assert!(std::path::Path::new(&format!("{dir}/Lin.sys")).exists());
    assert!(!std::path::Path::new(&format!("{dir}/Sat.sys")).exists());
}

#[test]
fn si_jl_bad_julia_is_refused_with_a_place() {
    let src = temp_file(
        "bad.jl",
        "ode = @ODEmodel(\n  x'(t) = -x(t) +,\n  y(t) = x(t))\n",
    );
    bad(&["import", "si-jl", &src], "bad.jl:2:18");
    let src = temp_file("open.jl", "ode = @ODEmodel(x'(t) = -x(t), y(t) = x(t)\n");
    bad(
        &["import", "si-jl", &src],
        "open.jl:1:16: this bracket is never closed",
    );
    let src = temp_file("none.jl", "x = 1\n");
    bad(&["import", "si-jl", &src], "no @ODEmodel");
}

/// S1 -> S2 at rate k1*S1 (compartment size 1), S2 measured: y = S2, y' = k1 S1,
/// y'' = -k1^2 S1, so k1 = -y''/y' and S1 = y'/k1: all three variables observable, rank 3.
const SBML: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version1/core" level="3" version="1">
  <model id="conv">
    <listOfCompartments><compartment id="cell" size="1" constant="true"/></listOfCompartments>
    <listOfSpecies>
      <species id="S1" compartment="cell" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
      <species id="S2" compartment="cell" hasOnlySubstanceUnits="false" boundaryCondition="false" constant="false"/>
    </listOfSpecies>
    <listOfParameters><parameter id="k1" value="1" constant="true"/></listOfParameters>
    <listOfReactions>
      <reaction id="r1" reversible="false">
        <listOfReactants><speciesReference species="S1" stoichiometry="1" constant="true"/></listOfReactants>
        <listOfProducts><speciesReference species="S2" stoichiometry="1" constant="true"/></listOfProducts>
        <kineticLaw><math xmlns="http://www.w3.org/1998/Math/MathML">
          <apply><times/><ci>k1</ci><ci>S1</ci></apply>
        </math></kineticLaw>
      </reaction>
    </listOfReactions>
  </model>
</sbml>
"#;

#[test]
fn sbml_import_then_rank_gives_the_derived_verdict() {
    let src = temp_file("conv.xml", SBML);
    let dir = fresh_dir("sbml");
    let out = format!("{dir}/conv.sys");
    ok(&["import", "sbml", &src, "--observe", "S2", "--out", &out]);
    let v: Value = serde_json::from_str(&ok(&["rank", &out, "--json"])).unwrap();
    assert_eq!((v["n"].as_u64(), v["rank"].as_u64()), (Some(3), Some(3)));
    // The file states k1 = 1 and the size 1 of cell; S1 and S2 have no initial value.
    let vals = format!("{dir}/conv.values");
    ok(&[
        "import", "sbml", &src, "--out", &out, "--values", &vals, "--force",
    ]);
    assert_eq!(
        std::fs::read_to_string(&vals).unwrap(),
        "cell = 1.0\nk1 = 1.0\n"
    );
    bad(
        &["import", "sbml", &src, "--observe", "S9"],
        "'S9' is not an id",
    );
    let ev = temp_file(
        "ev.xml",
        &SBML.replace(
            "  </model>",
            "    <listOfEvents><event id=\"e1\"/></listOfEvents>\n  </model>",
        ),
    );
    bad(&["import", "sbml", &ev], "ev.xml:19:19: <event> 'e1'");
    let broken = temp_file("broken.xml", "<sbml>\n<model>\n</sbml>\n");
    bad(&["import", "sbml", &broken], "broken.xml:3:");
}

/// Bertozzi_PNAS2020 (PEtab collection, BSD-3, in crates/obsan-import/tests/petab/): SIR,
/// beta = R0 gamma / N (N known per condition), y = I. Derivation: I' = (beta S - gamma) I, so
/// z = beta S - gamma is known from y; z' = beta S' = -beta I (z + gamma) gives beta and
/// beta gamma, hence gamma, R0 = beta N / gamma and S = (z + gamma) / beta; R enters nothing
/// measured. One condition: 3 states + R0, gamma: rank 4 of 5. Both: 6 states + 4 params, each
/// condition's own R lost: rank 8 of 10.
#[test]
fn petab_import_then_rank_gives_the_derived_verdict() {
    let yaml = "crates/obsan-import/tests/petab/Bertozzi_PNAS2020/problem.yaml";
    let dir = fresh_dir("petab");
    let one = format!("{dir}/ny.sys");
    ok(&[
        "import",
        "petab",
        yaml,
        "--condition",
        "u_NY",
        "--out",
        &one,
    ]);
    let v: Value = serde_json::from_str(&ok(&["rank", &one, "--json"])).unwrap();
    assert_eq!((v["n"].as_u64(), v["rank"].as_u64()), (Some(5), Some(4)));
    let both = format!("{dir}/both.sys");
    ok(&["import", "petab", yaml, "--out", &both]);
    let v: Value = serde_json::from_str(&ok(&["rank", &both, "--json"])).unwrap();
    assert_eq!((v["n"].as_u64(), v["rank"].as_u64()), (Some(10), Some(8)));
    // A condition column that is not an id of the model: the table, line and column (the
    // cell of u_CA under it: "u_CA", 39560000, I0_CA, then R0_CA at column 21).
    let src = std::path::Path::new(yaml).parent().unwrap();
    let bad_dir = fresh_dir("petab_bad");
    for f in [
        "problem.yaml",
        "model.xml",
        "parameters.tsv",
        "observables.tsv",
        "measurements.tsv",
    ] {
        std::fs::copy(src.join(f), format!("{bad_dir}/{f}")).unwrap();
    }
    let conds = std::fs::read_to_string(src.join("conditions.tsv")).unwrap();
    std::fs::write(
        format!("{bad_dir}/conditions.tsv"),
        conds.replace("R0_\t", "R9_\t"),
    )
    .unwrap();
    bad(
        &["import", "petab", &format!("{bad_dir}/problem.yaml")],
        "conditions.tsv:2:21: column 'R9_' is not a parameter",
    );
    bad(
        &["import", "petab", yaml, "--condition", "u_XX"],
        "no condition 'u_XX'",
    );
}

/// A STRIKE-GOLDD file written here: x1' = -(k12 + ke) x1 + k21 x2 + u, x2' = k12 x1 - k21 x2,
/// y = x1 / V with V known. The transfer function (s + k21) / (s^2 + (k12 + ke + k21) s +
/// ke k21) gives k21, k12 + ke and ke k21: every parameter, and both states (x2 through
/// x1'): rank 5 of 5.
#[test]
fn strike_goldd_import_then_rank_gives_the_derived_verdict() {
    let src = temp_file(
        "z_create_two.m",
        "syms x1 x2 V k12 k21 ke u1\nx = [x1; x2];\np = [k12; k21; ke];\nu = u1;\n\
         f = [-(k12 + ke)*x1 + k21*x2 + u1; k12*x1 - k21*x2];\nh = x1/V;\n",
    );
    let dir = fresh_dir("sg");
    let out = format!("{dir}/two.sys");
    ok(&["import", "strike-goldd", &src, "--out", &out]);
    let v: Value = serde_json::from_str(&ok(&["rank", &out, "--json"])).unwrap();
    assert_eq!((v["n"].as_u64(), v["rank"].as_u64()), (Some(5), Some(5)));
    let bad_src = temp_file(
        "z_create_bad.m",
        "syms x1 k\nx = x1;\np = k;\nf = [-k*x1;\nh = x1;\n",
    );
    bad(
        &["import", "strike-goldd", &bad_src],
        "z_create_bad.m:4:5: this '[' is never closed",
    );
}

/// `syms C(t)` declares a function of time: a known input. Model: x' = -k x + C(t) + d x, with
/// `d` declared plain first and then re-declared `syms d(t)` (MATLAB: `d` in `p`, assigned
/// before, stays the old plain symbol; the `d(t)` of `f` is the function, the input `d_t`).
/// y = x: y' = (d_t - k) y + C, so k = d_t + (C - y')/y: x and k observable; d enters nothing, so
/// n = 3 (x, k, d), rank 2, d unobservable. `E(t)`, used bare in `f` and listed in no role, is
/// a known input too: y' = (d_t - k) y + C + E leaves the same verdict.
#[test]
fn strike_goldd_functions_of_time_are_inputs() {
    let src = temp_file(
        "z_create_ft.m",
        "syms x k d\nx = x;\np = [k; d];\nsyms C(t) d(t) E(t)\nu = [C(t) d(t)];\n\
         f = -k*x + C(t) + d(t)*x + E;\nh = x;\n",
    );
    let out = ok(&["import", "strike-goldd", &src]);
    assert!(out.contains("param k, d\ninput C, d_t, E\n"), "{out}");
    assert!(out.contains("x' = -k*x + C + d_t*x + E\n"), "{out}");
    let dir = fresh_dir("sg-ft");
    let sys = format!("{dir}/ft.sys");
    ok(&["import", "strike-goldd", &src, "--out", &sys]);
    let v: Value = serde_json::from_str(&ok(&["rank", &sys, "--json"])).unwrap();
    assert_eq!((v["n"].as_u64(), v["rank"].as_u64()), (Some(3), Some(2)));
    assert_eq!(v["unobservable_variables"], serde_json::json!(["d"]));
    // A function of time is called at t only, and is no state or parameter.
    let at2 = temp_file(
        "z_create_at2.m",
        "syms x k C(t)\nx = x;\np = k;\nf = -k*x + C(2);\nh = x;\n",
    );
    bad(
        &["import", "strike-goldd", &at2],
        "z_create_at2.m:4:5: 'C' is a function of time (syms C(t)): write C(t)",
    );
    let as_p = temp_file(
        "z_create_asp.m",
        "syms x C(t)\nx = x;\np = C(t);\nf = -C*x;\nh = x;\n",
    );
    bad(
        &["import", "strike-goldd", &as_p],
        "z_create_asp.m:3:5: 'C' is a function of time (syms ...(t)): an input, not a parameter",
    );
}

/// MATLAB/Fortran `D` exponents are numbers: 1.5D-3 = 0.0015, 2d1 = 20. x' = -(1.5D-3) x, y =
/// 2d1 x. Both as written (lower-case e), so the rank is that of x' = -c x, y = 20 x with c
/// known: x observable, n = rank = 1.
#[test]
fn strike_goldd_reads_d_exponents() {
    let src = temp_file(
        "z_create_dexp.m",
        "syms x\nx = x;\nf = -1.5D-3*x;\nh = 2d1*x;\n",
    );
    let out = ok(&["import", "strike-goldd", &src]);
    assert!(out.contains("x' = -1.5e-3*x\noutput y1 = 2e1*x\n"), "{out}");
}

/// STRIKE-GOLDD's CHO models write arrays of symbols (`sym('x', [34 1])`, `sym(char(x), [28 1])`), elements set one by
/// one (`f = sym('f'); f(1) = ...`), index lists with ranges (`p([1:47,49:56,58:end])`) and
/// `f.'`. Model (derived by hand): x1' = -k1 x1 + k2 x2, x2' = k1 x1 - k2 x2, y = x1, with k3
/// unknown and unused. x1 + x2 = c is constant, so y' = k2 c - (k1 + k2) y: y determines x1,
/// k1 + k2 and k2 c only, and (k2, x2, k1) -> (l k2, c/l - x1, k1 + k2 - l k2) keeps them: 5
/// variables, rank 3, x2, k1, k2, k3 unobservable.
#[test]
fn strike_goldd_reads_symbol_arrays_and_elements() {
    let src = temp_file(
        "z_create_arrays.m",
        "syms x\nx = sym(char(x), [2 1]);\nk = sym('k', [3 1]);\np = k([1, 2:end]);\nu = [];\n\
         f = sym('f');\nf(1) = -k(1)*x(1) + k(2)*x(2);\nf(2) = k(1)*x(1) - k(2)*x(2);\nf = f.';\n\
         h = x([1]);\n",
    );
    let out = ok(&["import", "strike-goldd", &src]);
    assert!(out.contains("state x1, x2\nparam k1, k2, k3\n"), "{out}");
    let sys = temp_file("arrays.sys", &out);
    let v: Value = serde_json::from_str(&ok(&["rank", &sys, "--json"])).unwrap();
    assert_eq!(
        (v["n"].as_u64(), v["rank"].as_u64()),
        (Some(5), Some(3)),
        "{v}"
    );
    assert_eq!(
        v["unobservable_variables"],
        serde_json::json!(["x2", "k1", "k2", "k3"]),
        "{v}"
    );
}

/// What the reader does not follow is refused at its place, never skipped: a loop filling
/// `f`, an element assignment, an array of symbols.
#[test]
fn strike_goldd_unread_matlab_is_refused_at_its_place() {
    let cases = [
        // (A `for` over a whole-number range is read since session 30: see the next test.)
        (
            "syms x1 x2 k\nx = [x1; x2];\nf = [0; 0];\ni = 1;\nwhile i <= 2\n  f(i) = -k*x(i);\n  \
             i = i + 1;\nend\nh = x1;\n",
            "5:1: 'while' (MATLAB control flow) is not read",
        ),
        (
            "syms x1 k\nx = x1;\nf = 0;\nf(3) = -k*x1;\nh = x1;\n",
            "4:1: 'f(3) = ...': element 3 of a vector of 1",
        ),
        (
            "x = sym('x', [3 3]);\nf = -x;\nh = x(1);\n",
            "1:5: 'sym('x', [3 3])': only vectors of symbols",
        ),
        // Found by the fuzzer (CI, session 28): an empty right-hand side panicked the reader.
        (
            "syms x k\nx = x;\nu =; [k];\nf = -k*x;\nh = x;\n",
            "3:3: nothing to read after '='",
        ),
    ];
    for (k, (text, want)) in cases.iter().enumerate() {
        let src = temp_file(&format!("z_create_unread{k}.m"), text);
        bad(
            &["import", "strike-goldd", &src],
            &format!("z_create_unread{k}.m:{want}"),
        );
    }
}

/// A `for` loop over a whole-number range is unrolled (session 30): `f(i) = -k*x(i)` for i = 1, 2
/// gives x1' = -k x1, x2' = -k x2 (read off the source). A bound that is no number, or a loop
/// past the iteration limit, is refused at its place with exit 2.
#[test]
fn strike_goldd_unrolls_for_loops() {
    let src = temp_file(
        "z_create_loop.m",
        "syms x1 x2 k\nx = [x1; x2];\nf = [0; 0];\nfor i = 1:2\n  f(i) = -k*x(i);\nend\nh = x1;\n",
    );
    let out = ok(&["import", "strike-goldd", &src]);
    assert!(out.contains("x1' = -k*x1\nx2' = -k*x2\n"), "{out}");
    let cases = [
        (
            "syms x k n\nx = x;\nf = -k*x;\nfor i = 1:n\nend\nh = x;\n",
            "4:11: 'n': a loop's bounds",
        ),
        (
            "syms x k\nx = x;\nf = -k*x;\nfor i = 1:20000\nend\nh = x;\n",
            "4:1: this loop runs 20000 times",
        ),
    ];
    for (k, (text, want)) in cases.iter().enumerate() {
        let src = temp_file(&format!("z_create_loop{k}.m"), text);
        bad(
            &["import", "strike-goldd", &src],
            &format!("z_create_loop{k}.m:{want}"),
        );
    }
}

/// How many files of systems/benchmarks/strike-goldd/ may say `verdict-source: none`: none since
/// symident's verdict pass retries goodwin (its first rank a lower bound) with reconstruct=True
/// and microbial_community (its engine refuses `b^m`) with `exp(m log b)`
/// (benches/peers/symident_suite.py, `--one-verdict`).
const MAX_UNJUDGED: usize = 0;

/// systems/benchmarks/strike-goldd/: each NAME.sys is `obsan import strike-goldd` of
/// its src/z_create_NAME.m (written for obsan from the model's equations) under a header, and
/// obsan's rank agrees with the verdict the file cites (SymPy, benches/peers/sg_verdicts.py).
#[test]
fn strike_goldd_suite_is_the_import_of_its_sources_and_matches_its_verdicts() {
    let dir = "systems/benchmarks/strike-goldd";
    let mut names: Vec<String> = std::fs::read_dir(format!("{dir}/src"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("z_create_") && n.ends_with(".m"))
        .collect();
    names.sort();
    assert!(names.len() >= 78, "{names:?}");
    let mut unjudged = 0;
    for m in &names {
        let name = &m["z_create_".len()..m.len() - 2];
        let path = format!("{dir}/{name}.sys");
        let text = std::fs::read_to_string(&path).unwrap();
        let run = obsan_in(dir, &["import", "strike-goldd", &format!("src/{m}")]);
        assert_eq!(run.code, 0, "{m}: {}", run.stderr);
        let body: String = text
            .lines()
            .filter(|l| !l.starts_with("# Source:") && !l.starts_with("# verdict"))
            .map(|l| format!("{l}\n"))
            .collect();
        assert_eq!(body, run.stdout, "{path} is not the import of src/{m}");
        let entries = crate::suite_entries::file_entries(&path, &text).unwrap();
        if entries.is_empty() {
            // SymPy gave no verdict in time: the file must say so, and cites none.
            assert!(
                text.lines()
                    .any(|l| l.starts_with("# verdict-source: none (")),
                "{path}: neither a verdict nor 'verdict-source: none'"
            );
            unjudged += 1;
            continue;
        }
        assert_eq!(entries.len(), 1, "{path}");
        let v: Value = serde_json::from_str(&ok(&["rank", &path, "--json"])).unwrap();
        let want = &entries[0].verdict;
        assert_eq!(want.rank, v["rank"].as_u64(), "{path}");
        let un: std::collections::BTreeSet<String> = v["unobservable_variables"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap().to_string())
            .collect();
        assert_eq!(want.unobservable.as_ref(), Some(&un), "{path}");
    }
    // Every file cites SymPy's verdict or symident's (docs/benchmarks.md).
    assert_eq!(unjudged, MAX_UNJUDGED, "{unjudged} files without a verdict");
}

/// With `--all`, a model past the term budget is refused alone: the models
/// after it are still written. `(a + b + c + d + e + f)^30` has C(35, 5) =
/// 324,632 terms once expanded, past the default budget of 100,000.
#[test]
fn si_jl_all_holds_each_model_to_its_own_budget() {
    let big = "benchmarks[:Big] = Dict(:name => \"Big\", :ode => @ODEmodel(\n    \
               x'(t) = (a + b + c + d + e + f)^30 * x(t),\n    y(t) = x(t)))\n\n";
    let src = temp_file("big.jl", &format!("{big}{TWO}"));
    let e = bad(
        &["import", "si-jl", &src, "--model", "Big"],
        "expression too large",
    );
    assert!(e.contains("budget 100000"), "{e}");
    let dir = fresh_dir("sijl-big");
    let e = bad(&["import", "si-jl", &src, "--all", &dir], "1 model(s)");
    assert!(e.contains("model :Big"), "{e}");
    assert!(std::path::Path::new(&format!("{dir}/Readme.sys")).exists());
    assert!(std::path::Path::new(&format!("{dir}/Lin.sys")).exists());
    assert!(!std::path::Path::new(&format!("{dir}/Big.sys")).exists());
}
