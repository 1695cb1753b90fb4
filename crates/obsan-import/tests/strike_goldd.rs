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

/// A model in the layout of SBML-exported STRIKE-GOLDD files: symbols
/// `sym(char(x), [4 1])`, derivatives set element by element in a vector of
/// zeros, `f` and `h` grown in loops, and the inputs and states re-listed
/// after the dynamics were written in the old `x(i)`. Written for obsan's tests.
const LOOPED: &str = "\
syms k1 k2 k3
syms x
x = sym(char(x),[4 1]);
r1 = k1*x(1)*x(3);
xdot = sym(zeros(numel(x),1));
xdot(1) = -r1;
xdot(3) = -r1 + k2*x(4);
xdot(4) = r1 - k2*x(4) - k3*x(2)*x(4);
x0 = zeros(4,1);
x0(3) = 1.5E3;
p = [k1; k2; k3];
h = []; f = []; ics = [];
for j = 4:-1:3
    h = [h; x(j)];
end
for i = 1:2, f = [f; xdot(i + 2)]; ics = [ics, x0(i)]; end
last = i;
g = [x(last), 0].';
u = [x(1);x(2)];
x = [x(3);x(4)];
";

#[test]
fn loops_zeros_indexed_assignment_and_reassigned_roles() {
    let c = strike_goldd_to_sys(LOOPED, "z_create_looped.m").unwrap();
    let s = &c.sys_text;
    // States x3, x4 (the re-listed x); x1, x2 the inputs (the re-assigned u).
    assert_eq!(names(s, Kind::State), ["x3", "x4"]);
    assert_eq!(names(s, Kind::Input), ["x1", "x2"]);
    assert_eq!(names(s, Kind::Param), ["k1", "k2", "k3"]);
    // f = [xdot(3); xdot(4)] by hand, r1 = k1*x1*x3 substituted.
    equation_is(s, "x3", "-k1*x1*x3 + k2*x4");
    equation_is(s, "x4", "k1*x1*x3 - k2*x4 - k3*x2*x4");
    // h grown from j = 4 down to 3.
    assert!(s.contains("output y1 = x4\noutput y2 = x3\n"), "{s}");
}

/// The refusal of a model file followed by `extra` (the model: 5 lines, so `extra` starts on line 6).
fn refused_after_model(extra: &str) -> obsan_import::ImportError {
    let model = "syms x1 k\nx = x1;\np = k;\nf = -k*x1;\nh = x1;\n";
    strike_goldd_to_sys(&format!("{model}{extra}"), "z_create_m.m").unwrap_err()
}

#[test]
fn unbounded_loop_is_refused_at_its_for_before_it_runs() {
    // 10^9 iterations, past the limit of 10^4.
    let r = refused_after_model("  for i = 1:1e9\n a = i;\nend\n");
    assert_eq!((r.line, r.col), (6, 3), "{r}");
    assert!(r.message.contains("1000000000 times"), "{r}");
}

#[test]
fn for_without_end_is_refused_at_the_for() {
    let r = refused_after_model("for i = 1:3\n a = i;\n");
    assert_eq!((r.line, r.col), (6, 1), "{r}");
    assert!(r.message.contains("no matching 'end'"), "{r}");
    // And an `end` closing nothing, at the `end`.
    let r = refused_after_model("a = 1;\nend\n");
    assert_eq!((r.line, r.col), (7, 1), "{r}");
}

#[test]
fn index_out_of_range_in_a_loop_is_refused_at_the_element() {
    // x has 2 entries; the third iteration reads x(3). `-k*x(i)` starts at line 7, column 11.
    let r = strike_goldd_to_sys(
        "syms x1 x2 k\nx = [x1; x2];\np = k;\nh = x1;\nf = [];\n\
         for i = 1:3\n  f = [f; -k*x(i)];\nend\n",
        "z_create_m.m",
    )
    .unwrap_err();
    assert_eq!((r.line, r.col), (7, 11), "{r}");
    assert!(r.message.contains("from 1 to 2"), "{r}");
}

#[test]
fn non_numeric_range_is_refused_at_the_bound() {
    // A symbol bound (`syms n` shifts the model one line down: the `for` is on line 7).
    let r = strike_goldd_to_sys(
        "syms n\nsyms x1 k\nx = x1;\np = k;\nf = -k*x1;\nh = x1;\nfor i = 1:n\nend\n",
        "z_create_m.m",
    )
    .unwrap_err();
    assert_eq!((r.line, r.col), (7, 11), "{r}");
    assert!(r.message.contains("whole numbers"), "{r}");
    // `length` of a matrix is not read (the reader keeps no shapes): the Markov files' refusal.
    let r = refused_after_model("M = [1 2; 3 4];\nfor i = 1:length(M)\n a = i;\nend\n");
    assert_eq!((r.line, r.col), (7, 11), "{r}");
    // A step of 0.
    let r = refused_after_model("for i = 1:0:3\nend\n");
    assert!(r.message.contains("step is 0"), "{r}");
}

#[test]
fn unrolled_statements_and_nesting_are_bounded() {
    // Nested loops running more statements than the file's limit: at the inner `for`,
    // once the earlier iterations have used the budget (100 000 statements).
    let r = refused_after_model("for i = 1:1000\n for j = 1:1000\n  a = j;\n end\nend\n");
    assert_eq!((r.line, r.col), (7, 2), "{r}");
    assert!(r.message.contains("100000"), "{r}");
    // Loops nested 17 deep.
    let deep = format!(
        "{}a = 1;\n{}",
        "for i = 1:1\n".repeat(17),
        "end\n".repeat(17)
    );
    assert!(refused_after_model(&deep).message.contains("nested"));
}

#[test]
fn work_limit_is_an_error() {
    // `a = [a; a]` doubles: 2^k copies of `k` after k iterations; the file's node budget
    // (2 * 10^6) stops it at the assignment when the total, 2^(k+1) - 1, passes it (k = 20).
    let src = "syms x1 k\nx = x1;\np = k;\nf = -k*x1;\nh = x1;\na = k;\n\
               for i = 1:60\n  a = [a; a];\nend\n";
    let r = strike_goldd_to_sys(src, "z_create_m.m").unwrap_err();
    assert_eq!((r.line, r.col), (8, 3), "{r}");
    assert!(r.message.contains("expression nodes"), "{r}");
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

    #[test]
    fn never_panics_on_loops(pos in 0usize..1000, ch in proptest::char::any(), cut in 0usize..1000) {
        let mut cs: Vec<char> = LOOPED.chars().collect();
        let i = pos % cs.len();
        cs[i] = ch;
        cs.truncate(cut.max(i + 1).min(cs.len()));
        let text: String = cs.into_iter().collect();
        let _ = strike_goldd_to_sys(&text, "z_create_m.m");
    }
}
