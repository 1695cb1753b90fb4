//! Every error the .sys reader gives: message, line and column.

use obsan_model::{ModelError, System};

const GOOD: &str = "system s
state x, y
param a
const k
input u, w
x' = a*y + u
y' = -x + k*w
output h = x
restrict r: u = v, w = 2*v
";

fn fail(src: &str) -> ModelError {
    match System::parse(src, "t.sys") {
        Ok(_) => panic!("accepted:\n{src}"),
        Err(e) => e,
    }
}

/// Expect an error at `line:col` whose message contains `want`.
fn check(src: &str, line: usize, col: usize, want: &str) {
    let e = fail(src);
    assert!(e.message.contains(want), "wanted '{want}', got: {e}");
    assert_eq!((e.line, e.col), (Some(line), Some(col)), "position of: {e}");
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("t.sys:{line}:{col}: ")),
        "{shown}"
    );
    assert!(shown.contains('^'), "caret under the place: {shown}");
}

fn general(src: &str, want: &str) {
    let e = fail(src);
    assert!(e.message.contains(want), "wanted '{want}', got: {e}");
    assert!(e.to_string().starts_with("t.sys: "));
}

fn edit(from: &str, to: &str) -> String {
    assert!(GOOD.contains(from), "{from}");
    GOOD.replacen(from, to, 1)
}

#[test]
fn the_good_file_is_accepted() {
    let s = System::parse(GOOD, "t.sys").unwrap();
    assert_eq!(s.name, "s");
    let nf = s.normal_form(Some("r"), &[]).unwrap();
    assert_eq!(nf.inputs, vec!["v"]);
}

#[test]
fn statement_errors() {
    check(
        &edit("state x, y", "stat x, y"),
        2,
        1,
        "expected a declaration",
    );
    check(&edit("x' = a*y + u", "x = a*y + u"), 6, 1, "write x' = ...");
    check(&edit("system s", "system"), 1, 1, "'system' needs one name");
    check(
        &edit("system s", "system s t"),
        1,
        1,
        "'system' needs one name",
    );
    check(
        &format!("{GOOD}system t\n"),
        10,
        1,
        "a second 'system' line",
    );
    general(&GOOD.replace("system s\n", ""), "no 'system NAME' line");
    check(&edit("state x, y", "state"), 2, 1, "needs a list of names");
    check(
        &edit("state x, y", "state x, 2y"),
        2,
        10,
        "not a valid name",
    );
    check(&edit("state x, y", "state x,, y"), 2, 9, "not a valid name");
    // `param a = 3` is a start value; it must be a number.
    check(
        &edit("param a", "param a = k"),
        3,
        11,
        "a param's start value must be a number, not 'k'",
    );
    check(
        &edit("state x, y", "state x = y, y"),
        2,
        11,
        "a state's start value may use measured inputs and constants, not 'y'",
    );
    check(&edit("const k", "const k = z"), 4, 11, "must be a number");
    check(&edit("x' = a*y + u", "x' a*y + u"), 6, 1, "needs '='");
    check(
        &edit("output h = x", "output h"),
        8,
        1,
        "needs a name and an expression",
    );
    check(&edit("output h = x", "output = x"), 8, 8, "needs a name");
    check(
        &edit("restrict r: u = v, w = 2*v", "restrict r u = v"),
        9,
        1,
        "needs a name and a colon",
    );
    check(
        &edit(
            "restrict r: u = v, w = 2*v",
            "restrict r: u = v\nrestrict r: w = v",
        ),
        10,
        10,
        "defined twice",
    );
    check(&edit("x' = a*y + u", "x' = (a*y + u"), 6, 6, "never closed");
}

#[test]
fn declaration_errors() {
    check(
        &edit("param a", "param a, x"),
        3,
        10,
        "declared twice (first as a state at line 2, column 7)",
    );
    check(&edit("param a", "param sin"), 3, 7, "reserved word");
    check(&edit("param a", "param pi"), 3, 7, "reserved word");
    general(
        "system s\nconst k\ninput u\noutput h = k\n",
        "no state and no param",
    );
    check(
        &edit("x' = a*y + u\n", ""),
        2,
        7,
        "state 'x' has no equation",
    );
    check(
        &format!("{GOOD}z' = 1\n"),
        10,
        1,
        "'z', which is not declared",
    );
    check(&format!("{GOOD}a' = 1\n"), 10, 1, "params are constant");
    check(
        &format!("{GOOD}k' = 1\n"),
        10,
        1,
        "only states have equations",
    );
    check(&format!("{GOOD}x' = 1\n"), 10, 1, "a second equation");
    check(&edit("x' = a*y + u", "x' ="), 6, 1, "no right-hand side");
}

#[test]
fn expression_errors() {
    check(
        &edit("x' = a*y + u", "x' = a*yy + u"),
        6,
        8,
        "unknown symbol 'yy' in the dynamics of x (did you mean 'y'?)",
    );
    check(
        &edit("x' = a*y + u", "x' = a*y + foo(u)"),
        6,
        12,
        "unknown function 'foo'",
    );
    check(
        &edit("x' = a*y + u", "x' = a*y +* u"),
        6,
        11,
        "unexpected operator",
    );
    check(
        &edit("x' = a*y + u", "x' = a*y/(y - y) + u"),
        6,
        10,
        "identically zero",
    );
    check(&edit("output h = x", "output x = x"), 8, 8, "already used");
    check(
        &edit("output h = x", "output h = x\noutput h = y"),
        9,
        8,
        "already used",
    );
    check(
        &edit("output h = x", "output h = "),
        8,
        8,
        "has no expression",
    );
    general(&edit("output h = x\n", ""), "no output");
    // A statement that continues over lines keeps exact positions.
    check(
        &edit("x' = a*y + u", "x' = a*y +\n     u*zz"),
        7,
        8,
        "unknown symbol 'zz'",
    );
}

#[test]
fn non_affine_terms_are_named() {
    check(
        &edit("x' = a*y + u", "x' = a*y + u^2"),
        6,
        12,
        "the term 'u^2' is not",
    );
    check(
        &edit("x' = a*y + u", "x' = sin(u) + a*y"),
        6,
        6,
        "the term 'sin(u)' is not",
    );
    check(
        &edit("y' = -x + k*w", "y' = -x + u*w"),
        7,
        11,
        "the term 'u*w' is not",
    );
    check(
        &edit("y' = -x + k*w", "y' = -x - w/(1 + u)"),
        7,
        11,
        "the term 'w/(1 + u)' is not",
    );
    // Affine after simplification is accepted: u^2/u = u.
    System::parse(&edit("x' = a*y + u", "x' = a*y + u^2/u"), "t.sys").unwrap();
}

#[test]
fn restriction_errors() {
    check(
        &edit("u = v, w = 2*v", "z = v"),
        9,
        13,
        "'z' is not a declared input",
    );
    check(
        &edit("u = v, w = 2*v", "x = v"),
        9,
        13,
        "'x' is a state, not an input",
    );
    check(
        &edit("u = v, w = 2*v", "u = v, u = 2*v"),
        9,
        20,
        "sets 'u' twice",
    );
    check(
        &edit("u = v, w = 2*v", "u = v, w = x*v"),
        9,
        24,
        "not the state 'x'",
    );
    check(
        &edit("u = v, w = 2*v", "u = v, w = u"),
        9,
        24,
        "also uses it",
    );
    check(
        &edit("u = v, w = 2*v", "u = v^2, w = v"),
        9,
        17,
        "not affine in the inputs",
    );
    check(
        &edit("u = v, w = 2*v", "u = v, w = h"),
        9,
        24,
        "is an output",
    );
    check(&edit("u = v, w = 2*v", "u v"), 9, 13, "INPUT = EXPR");
    check(&edit("u = v, w = 2*v", "u ="), 9, 13, "needs an expression");
    check(
        &edit("restrict r: u = v, w = 2*v", "restrict r:"),
        9,
        10,
        "substitutes nothing",
    );
}

#[test]
fn normal_form_flag_errors() {
    let s = System::parse(GOOD, "t.sys").unwrap();
    let e = s.normal_form(Some("nope"), &[]).unwrap_err();
    assert!(
        e.to_string()
            .contains("no restriction named 'nope' (it declares: r)"),
        "{e}"
    );
    let q = obsan_expr::Q::from_i64(1);
    let e = s
        .normal_form(None, &[("zz".into(), q.clone())])
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("'zz' is not a constant of s (its constants: k)"),
        "{e}"
    );
    let e = s.normal_form(None, &[("a".into(), q)]).unwrap_err();
    assert!(
        e.to_string()
            .contains("'a' is a param of s, not a known constant"),
        "{e}"
    );
}

#[test]
fn restrictions_and_constants_give_the_right_fields() {
    let s = System::parse(GOOD, "t.sys").unwrap();
    let mut nf = s
        .normal_form(Some("r"), &[("k".into(), obsan_expr::Q::from_i64(3))])
        .unwrap();
    // x' = a y + v, y' = -x + 3*2 v: f0 = [a y, -x, 0], f_v = [1, 6, 0].
    let t: Vec<String> = nf.fields[0]
        .clone()
        .iter()
        .map(|&i| nf.ctx.to_text(i))
        .collect();
    assert_eq!(t, vec!["1", "6", "0"]);
    let f0: Vec<String> = nf.f0.clone().iter().map(|&i| nf.ctx.to_text(i)).collect();
    assert_eq!(f0, vec!["a*y", "-x", "0"]);
    // A restriction that keeps an original input.
    let src = GOOD.replace("restrict r: u = v, w = 2*v", "restrict straight: w = u");
    let s = System::parse(&src, "t.sys").unwrap();
    let nf = s.normal_form(Some("straight"), &[]).unwrap();
    assert_eq!(nf.inputs, vec!["u"]);
}

/// Unknown inputs: declared with `unknown input` or `varying`,
/// affine together with the known inputs, allowed in outputs, with their
/// fields g_j in the normal form.
#[test]
fn unknown_inputs() {
    let src = "system s\nstate x, y\nparam a\ninput u\nunknown input w\nvarying k\nx' = a*y + u + x*w\ny' = -k*x\noutput h = x + w\n";
    let s = System::parse(src, "t.sys").unwrap();
    let mut nf = s.normal_form(None, &[]).unwrap();
    assert_eq!(nf.inputs, vec!["u"]);
    assert_eq!(nf.unknown_inputs, vec!["w", "k"]);
    // g_w = (x, 0, 0), g_k = (0, -x, 0); f0 keeps a*y only.
    let x = nf.parse_expr("x", false).unwrap();
    let mx = nf.parse_expr("-x", false).unwrap();
    let ay = nf.parse_expr("a*y", false).unwrap();
    let eq = |nf: &mut obsan_model::NormalForm, a, b| {
        let d = nf.ctx.sub(a, b);
        nf.ctx.is_identically_zero(d)
    };
    let (gw, gk, f0) = (
        nf.unknown_fields[0].clone(),
        nf.unknown_fields[1].clone(),
        nf.f0.clone(),
    );
    assert!(eq(&mut nf, gw[0], x) && nf.ctx.is_identically_zero(gw[1]));
    assert!(eq(&mut nf, gk[1], mx) && nf.ctx.is_identically_zero(gk[0]));
    assert!(eq(&mut nf, f0[0], ay));
    // Printed back and read again: the same declarations.
    let again = System::parse(&s.to_sys_text(), "t.sys").unwrap();
    let nf2 = again.normal_form(None, &[]).unwrap();
    assert_eq!(nf2.unknown_inputs, vec!["w", "k"]);

    // Not affine in w, or a product of a known and an unknown input.
    let base = "system s\nstate x\ninput u\nunknown input w\nx' = -x + w\noutput h = x\n";
    let e = |from: &str, to: &str| base.replacen(from, to, 1);
    check(
        &e("x' = -x + w", "x' = -x + w^2"),
        5,
        11,
        "the term 'w^2' is not",
    );
    check(
        &e("x' = -x + w", "x' = -x + u*w"),
        5,
        11,
        "the term 'u*w' is not",
    );
    check(
        &e("x' = -x + w", "x' = sin(w) - x"),
        5,
        6,
        "the term 'sin(w)' is not",
    );
    // Declarations.
    check(
        &e("unknown input w", "unknown w"),
        4,
        1,
        "'unknown' must be followed by 'input'",
    );
    check(
        &e("unknown input w", "unknown input w = 3"),
        4,
        15,
        "'w' is an unknown input: it takes no value",
    );
    check(
        &e("unknown input w", "unknown input w\nparam w"),
        5,
        7,
        "'w' is declared twice",
    );
    // A restriction may not use an unknown input on its right side.
    check(
        &format!("{base}restrict r: u = w\n"),
        7,
        17,
        "not the unknown input 'w'",
    );
}

#[test]
fn time_is_read_in_right_hand_sides_and_outputs_and_never_declared() {
    let src = "system s\nstate x\nparam a\ninput u\nx' = -a*x + sin(t)*u\noutput y = x*t\n";
    let s = System::parse(src, "t.sys").unwrap();
    assert!(s.uses_time());
    let mut nf = s.normal_form(None, &[]).unwrap();
    // The clock: last dynamic state, t' = 1 in the drift, no input moves it;
    // its output first.
    assert_eq!(nf.state, vec!["x", "t", "a"]);
    assert_eq!((nf.n_dynamic, nf.clock()), (2, Some(1)));
    assert_eq!(nf.ctx.to_text(nf.f0[1]), "1");
    assert!(nf.ctx.is_identically_zero(nf.fields[0][1]));
    assert_eq!(nf.outputs[0].0, "t");
    assert_eq!(nf.ctx.to_text(nf.outputs[0].1), "t");
    // The user's field keeps t as a coordinate: f_u = sin(t) on x.
    assert_eq!(nf.ctx.to_text(nf.fields[0][0]), "sin(t)");
    // A model without t has no clock.
    let plain = System::parse(GOOD, "t.sys").unwrap();
    assert!(!plain.uses_time());
    assert_eq!(plain.normal_form(None, &[]).unwrap().clock(), None);
    // Declared, named as an output, substituted or measured: refused at its place.
    check(&edit("state x, y", "state x, y, t"), 2, 13, "'t' is time");
    check(&edit("param a", "param a, t"), 3, 10, "'t' is time");
    check(&edit("output h = x", "output t = x"), 8, 8, "'t' is time");
    check(
        &edit("restrict r: u = v, w = 2*v", "restrict r: u = t*v, w = 2*v"),
        9,
        17,
        "time 't' cannot be substituted",
    );
    check(
        &edit("input u, w", "input u, w\ninput d = t*u"),
        6,
        11,
        "not 't'",
    );
    // The first use locates the refusal of a route without a clock.
    let e = s.time_refusal("`obsan modes`").unwrap();
    assert_eq!((e.line, e.col), (Some(5), Some(17)));
    assert!(e.message.contains("`obsan modes`"), "{e}");
    assert!(plain.time_refusal("`obsan modes`").is_none());
}
