//! The @ODEmodel reader on small hand-written models; expected .sys lines are
//! written out by hand from SI.jl's reading rules (x'(t) state, y(t) output,
//! other u(t) input, bare names parameters) and Julia's operator precedence.

use obsan_import::{si_jl_convert, si_jl_models, ImportError};
use obsan_model::{Kind, System};
use proptest::prelude::*;

fn one(src: &str) -> Result<String, ImportError> {
    let models = si_jl_models(src)?;
    assert_eq!(models.len(), 1, "{models:?}");
    si_jl_convert(src, &models[0], "t.jl").map(|c| c.sys_text)
}

fn body(sys: &str) -> Vec<&str> {
    sys.lines().filter(|l| !l.starts_with('#')).collect()
}

#[test]
fn states_outputs_inputs_params_are_classified_as_si_jl_does() {
    let src = "using StructuralIdentifiability\n\
               ode = @ODEmodel(\n    x1'(t) = -(a01 + a21) * x1(t) + a12 * x2(t) + u(t),\n    \
               x2'(t) = a21 * x1(t) - a12 * x2(t) - x3(t) / b,\n    x3'(t) = x3(t),\n    \
               y(t) = x2(t)\n)\n";
    let sys = one(src).unwrap();
    assert_eq!(
        body(&sys),
        [
            "system ode",
            "state x1, x2, x3",
            "param a01, a21, a12, b",
            "input u",
            "x1' = -(a01 + a21)*x1 + a12*x2 + u",
            "x2' = a21*x1 - a12*x2 - x3/b",
            "x3' = x3",
            "output y = x2",
        ]
    );
    let s = System::parse(&sys, "t.sys").unwrap();
    let kind = |n: &str| s.decls.iter().find(|d| d.name == n).map(|d| d.kind);
    assert_eq!(kind("x3"), Some(Kind::State));
    assert_eq!(kind("b"), Some(Kind::Param));
    assert_eq!(kind("u"), Some(Kind::Input));
}

#[test]
fn julia_precedence_is_kept() {
    // `//` binds tighter than `/`: a / b // c is a / (b // c); `-x^2` is -(x^2);
    // `^` is right-associative; `2x` is 2*x.
    let src = "@ODEmodel(x'(t) = a / b // c - x(t)^2 + 2x(t) + 2^3^2 - (-x(t))^2, y(t) = x(t))";
    let sys = one(src).unwrap();
    assert!(
        sys.contains("x' = a/(b/c) - x^2 + 2*x + 2^3^2 - (-x)^2\n"),
        "{sys}"
    );
}

#[test]
fn dict_key_name_cite_and_parameter_values() {
    let src = r#"
benchmarks = Dict(
    :Demo => Dict(
        :name => "Demo model",
        :cite => "\\cite{x}",
        :ode => @ODEmodel(x'(t) = -k * x(t) + c, y(t) = x(t)),
    ),
)
ode = @ODEmodel(z'(t) = -k * z(t) + c * w(t), w'(t) = 0, y(t) = z(t))
ode = set_parameter_values(ode, Dict(c => QQ(1, 2), k => QQ(3)))
benchmarks[:Second] = Dict(:name => "Second", :ode => ode)
"#;
    let models = si_jl_models(src).unwrap();
    let keys: Vec<&str> = models.iter().map(|m| m.key.as_str()).collect();
    assert_eq!(keys, ["Demo", "Second"]);
    assert_eq!(models[0].name.as_deref(), Some("Demo model"));
    assert_eq!(models[0].cite.as_deref(), Some("\\cite{x}"));
    assert_eq!(models[0].line, 6);
    let c = si_jl_convert(src, &models[1], "b.jl").unwrap();
    assert!(
        c.sys_text.contains("z' = -3*z + (1/2)*w\n"),
        "{}",
        c.sys_text
    );
    assert!(!c.sys_text.contains("\nparam "), "{}", c.sys_text);
    // The z' line maps back to line 9 of the Julia text, column 17.
    let zline = c
        .sys_text
        .lines()
        .position(|l| l.starts_with("z'"))
        .unwrap()
        + 1;
    assert_eq!(c.source_of(zline), Some((9, 17)));
}

#[test]
fn reserved_names_and_bare_twins_are_renamed() {
    // `exp` is a .sys function name; `q` bare is a parameter distinct from the input q(t).
    let src = "@ODEmodel(x'(t) = -exp * x(t) + q * q(t), y(t) = x(t))";
    let sys = one(src).unwrap();
    assert!(sys.contains("x' = -exp_*x + q_p*q\n"), "{sys}");
    assert!(
        sys.contains("param exp_, q_p\n") && sys.contains("input q\n"),
        "{sys}"
    );
    System::parse(&sys, "t.sys").unwrap();
}

#[test]
fn linear_compartment_model_is_expanded_as_lincomp_jl() {
    // graph [[2], [1]]: 1 -> 2 at rate a_2_1, 2 -> 1 at rate a_1_2; leak a_0_2;
    // input u1 into x1; output y2 = x2 (SI.jl src/lincomp.jl).
    let src = ":L => Dict(:ode => linear_compartment_model([[2], [1]], inputs = [1], outputs = [2], leaks = [2]))";
    let sys = one(src).unwrap();
    assert_eq!(
        body(&sys),
        [
            "system L",
            "state x1, x2",
            "param a_2_1, a_1_2, a_0_2",
            "input u1",
            "x1' = -a_2_1*x1 + a_1_2*x2 + u1",
            "x2' = a_2_1*x1 - a_1_2*x2 - a_0_2*x2",
            "output y2 = x2",
        ]
    );
}

fn refused(src: &str) -> ImportError {
    match si_jl_models(src).and_then(|m| {
        let first = m.first().cloned().ok_or(ImportError {
            line: 0,
            col: 0,
            message: "no model".into(),
        })?;
        si_jl_convert(src, &first, "t.jl")
    }) {
        Ok(c) => panic!("accepted: {}", c.sys_text),
        Err(e) => e,
    }
}

#[test]
fn mistakes_are_refused_at_their_place() {
    let e = refused("@ODEmodel(\n  x'(t) = foo(x(t)),\n  y(t) = x(t))");
    assert_eq!((e.line, e.col), (2, 11), "{e}");
    let e = refused("@ODEmodel(x'(t) = -x(t), y(t) = x(t)");
    assert_eq!((e.line, e.col), (1, 10), "{e}");
    assert!(e.message.contains("never closed"), "{e}");
    let e = refused("@ODEmodel(x'(t) = -α * x(t), y(t) = x(t))");
    assert_eq!((e.line, e.col), (1, 20), "{e}");
    let e = refused("@ODEmodel(x'(t) = -x(t) + y(t), y(t) = x(t))");
    assert!(e.message.contains("output 'y'"), "{e}");
    let e = refused("@ODEmodel(x'(t) = -x(t) * t, y(t) = x(t))");
    assert_eq!((e.line, e.col), (1, 27), "{e}");
    let e = refused("@ODEmodel(x'(t) = -x(t), x'(t) = 1, y(t) = x(t))");
    assert!(e.message.contains("two equations"), "{e}");
    let e = refused("@ODEmodel(x'(t) = , y(t) = x(t))");
    assert_eq!(e.line, 1, "{e}");
    let e = refused("@ODEmodel(y(t) = a)");
    assert!(e.message.contains("no state"), "{e}");
    let e = refused("\"abc");
    assert!(e.message.contains("unterminated"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]
    /// Any text, and any mutation of a valid model: no panic; an error lies
    /// inside the text; what converts reads as .sys or is refused by obsan-model
    /// (never a panic there either).
    #[test]
    fn never_panics(cut in 0usize..200, ins in "[ -~\n]{0,6}", junk in "\\PC{0,60}") {
        let base = "m = Dict(:A => Dict(:name => \"A\", :ode => @ODEmodel(\n  x'(t) = -(a + b) * x(t) // c + u(t),\n  z'(t) = x(t)^2 - z(t),\n  y(t) = z(t))))\n";
        let k = base.char_indices().map(|(i, _)| i).nth(cut % base.chars().count()).unwrap_or(0);
        let mutated = format!("{}{}{}", &base[..k], ins, &base[k..]);
        for src in [mutated.as_str(), junk.as_str()] {
            let lines = src.split('\n').count();
            match si_jl_models(src) {
                Err(e) => prop_assert!(e.line >= 1 && e.line <= lines, "{e}"),
                Ok(ms) => for m in &ms {
                    match si_jl_convert(src, m, "p.jl") {
                        Err(e) => prop_assert!(e.line >= 1 && e.line <= lines, "{e}"),
                        Ok(c) => { let _ = System::parse(&c.sys_text, "p.sys"); }
                    }
                },
            }
        }
    }
}
