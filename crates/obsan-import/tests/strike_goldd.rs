//! The STRIKE-GOLDD reader on model files written here in its MATLAB syntax
//! (no STRIKE-GOLDD file is used: it is GPL-3). Expected equations are the
//! ones written in each file, read by hand.

use obsan_import::strike_goldd_to_sys;
use obsan_model::{Kind, System};
use proptest::prelude::*;

fn equation_is(sys: &str, state: &str, want: &str) {
    let s = System::parse(sys, "t.sys").unwrap_or_else(|e| panic!("{e}\n{sys}"));
    let mut nf = s.normal_form(None, &[]).unwrap();
    let k = nf
        .state
        .iter()
        .position(|n| n == state)
        .unwrap_or_else(|| panic!("no state {state}:\n{sys}"));
    // f0 + sum_i f_i u_i, compared with `want` (inputs included).
    let mut got = nf.f0[k];
    for (i, u) in nf.inputs.clone().iter().enumerate() {
        let ui = nf.parse_expr(u, true).unwrap();
        let t = nf.ctx.mul(&[nf.fields[i][k], ui]);
        got = nf.ctx.add(&[got, t]);
    }
    let w = nf.parse_expr(want, true).unwrap();
    let d = nf.ctx.sub(got, w);
    assert!(
        nf.ctx.is_identically_zero(d),
        "{state}' = {} , wanted {want}\n{sys}",
        nf.ctx.to_text(got)
    );
}

fn names(sys: &str, kind: Kind) -> Vec<String> {
    System::parse(sys, "t.sys")
        .unwrap()
        .decls
        .iter()
        .filter(|d| d.kind == kind)
        .map(|d| d.name.clone())
        .collect()
}

/// A two-compartment model with a known input, written in every layout the
/// reader accepts: syms over continued lines, a transposed row vector,
/// an intermediate quantity, indexing, comments.
const TWO: &str = "\
clear all;
% Two compartments, written for obsan's tests.
syms x1 x2 ...      % states
     V ...          % a known volume (declared, in no role: a known constant)
     k12 k21 ke     % parameters
syms u1
x = [x1 x2].';
p = [k12; k21; ke];
u = [u1];
w = [];
out = k12 + ke;     % an intermediate quantity
f = [-out*x1 + k21*x2 + u(1);
     k12*x1 - k21*x2];
h = x1/V;
ics = [0 0];
known_ics = [0, 0];
save('two_comp','x','p','u','w','h','f','ics','known_ics');
";

#[test]
fn roles_vectors_intermediates_and_constants() {
    let c = strike_goldd_to_sys(TWO, "models/z_create_two.m").unwrap();
    let s = &c.sys_text;
    assert!(s.contains("\nsystem two_comp\n"), "{s}");
    // x1' = -(k12 + ke) x1 + k21 x2 + u1; x2' = k12 x1 - k21 x2; y1 = x1 / V.
    equation_is(s, "x1", "-(k12 + ke)*x1 + k21*x2 + u1");
    equation_is(s, "x2", "k12*x1 - k21*x2");
    assert!(s.contains("output y1 = x1/V\n"), "{s}");
    assert_eq!(names(s, Kind::Param), ["k12", "k21", "ke"]);
    assert_eq!(names(s, Kind::Const), ["V"]);
    assert_eq!(names(s, Kind::Input), ["u1"]);
    // The x2 equation maps to its entry of f: line 13, column 6.
    let line = s.lines().position(|l| l.starts_with("x2'")).unwrap() + 1;
    assert_eq!(c.source_of(line), Some((13, 6)));
}

#[test]
fn unknown_inputs_scalar_roles_and_matlab_operators() {
    // `u` declared by syms and never assigned is the input u; `h = x` the whole state;
    // MATLAB's elementwise operators and left-associative ^ (2^2^3 = 64).
    let src = "syms a b u w1\nsyms A B\nx = [A; B];\np = [a b];\nw = w1;\n\
               f = [a.*A.^2 - B./b + u; 2^2^3*w1 - A];\nh = x;\n";
    let c = strike_goldd_to_sys(src, "z_create_ops.m").unwrap();
    let s = &c.sys_text;
    assert!(s.contains("\nsystem ops\n"), "{s}");
    assert!(s.contains("\nunknown input w1\n"), "{s}");
    assert!(s.contains("output y1 = A\noutput y2 = B\n"), "{s}");
    let sys = System::parse(s, "t.sys").unwrap();
    let nf = sys.normal_form(None, &[]).unwrap();
    assert_eq!(nf.inputs, ["u"]);
    equation_is(s, "A", "a*A^2 - B/b + u");
}

#[test]
fn mistakes_are_refused_at_their_place() {
    let e = |src: &str| strike_goldd_to_sys(src, "z_create_m.m").unwrap_err();
    // Two states, one equation.
    let r = e("syms x1 x2 k\nx = [x1; x2];\np = k;\nf = [k*x1];\nh = x1;\n");
    assert_eq!((r.line, r.col), (4, 1), "{r}");
    // An undeclared name, at its column.
    let r = e("syms x1 k\nx = x1;\np = k;\nf = -k*x1 + t;\nh = x1;\n");
    assert_eq!((r.line, r.col), (4, 13), "{r}");
    assert!(r.message.contains("autonomous"), "{r}");
    // An unclosed bracket, at the bracket.
    let r = e("syms x1 k\nx = x1;\np = k;\nf = [-k*x1;\nh = x1;\n");
    assert_eq!((r.line, r.col), (4, 5), "{r}");
    // No outputs.
    let r = e("syms x1 k\nx = x1;\np = k;\nf = -k*x1;\n");
    assert!(r.message.contains("'h"), "{r}");
    // An index past the vector.
    let r = e("syms x1 k u1\nx = x1;\np = k;\nu = [u1];\nf = -k*x1 + u(2);\nh = x1;\n");
    assert_eq!(r.line, 5, "{r}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(500))]
    #[test]
    fn never_panics(pos in 0usize..1000, ch in proptest::char::any(), cut in 0usize..1000) {
        let mut cs: Vec<char> = TWO.chars().collect();
        let i = pos % cs.len();
        cs[i] = ch;
        cs.truncate(cut.max(i + 1).min(cs.len()));
        let text: String = cs.into_iter().collect();
        let _ = strike_goldd_to_sys(&text, "z_create_m.m");
    }
}
