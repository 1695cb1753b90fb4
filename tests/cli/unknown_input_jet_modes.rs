//! `obsan modes` with unknown inputs when the certified symmetries move with
//! the known inputs (issue 33; docs/engine.md, "Modes that move with the
//! inputs"). The modes are first integrals in the state and the inputs'
//! jets; each claim is checked here with the engine's own derivatives and
//! canonical forms, against forms derived by hand beside each test (apart
//! from unknown_inputs.rs, which is near the 900-line limit).

use crate::util::*;
use obsan_expr::{Ctx, Id};
use serde_json::Value;

/// Printed text as the expression parser reads it: a jet `u'`, `u''` becomes
/// the plain symbol `u_d`, `u_dd`.
fn plain(s: &str) -> String {
    s.replace("''", "_dd").replace('\'', "_d")
}

fn parse(ctx: &mut Ctx, s: &str) -> Id {
    ctx.parse(&plain(s))
        .unwrap_or_else(|e| panic!("{s}: {e:?}"))
}

/// The gradient of `e` over `vars`.
fn grad(ctx: &mut Ctx, e: Id, vars: &[&str]) -> Vec<Id> {
    vars.iter()
        .map(|x| {
            let v = ctx.symbol(x).var;
            ctx.diff(e, v)
        })
        .collect()
}

/// The determinant of a small square matrix of nodes (Laplace, first row).
fn det(ctx: &mut Ctx, m: &[Vec<Id>]) -> Id {
    if m.len() == 1 {
        return m[0][0];
    }
    let mut terms = Vec::new();
    for c in 0..m.len() {
        let minor: Vec<Vec<Id>> = m[1..]
            .iter()
            .map(|row| (0..row.len()).filter(|&k| k != c).map(|k| row[k]).collect())
            .collect();
        let d = det(ctx, &minor);
        let t = ctx.mul(&[m[0][c], d]);
        terms.push(if c % 2 == 0 { t } else { ctx.neg(t) });
    }
    ctx.add(&terms)
}

/// `f` is a function of `gs` (as many as `vars` less one; their gradients
/// independent): the Jacobian of `(gs, f)` over `vars` is singular,
/// decided exactly. The jets are not among `vars`: they are coordinates
/// no symmetry moves, so a function of them alone counts as a constant.
fn depends_on(ctx: &mut Ctx, f: Id, gs: &[Id], vars: &[&str]) -> bool {
    let mut m: Vec<Vec<Id>> = gs.iter().map(|&g| grad(ctx, g, vars)).collect();
    m.push(grad(ctx, f, vars));
    let d = det(ctx, &m);
    ctx.canon(d).is_zero()
}

/// The gradients of `gs` (one fewer than `vars`) are independent: some
/// unit row completes them to a non-singular matrix (exact).
fn independent(ctx: &mut Ctx, gs: &[Id], vars: &[&str]) -> bool {
    let rows: Vec<Vec<Id>> = gs.iter().map(|&g| grad(ctx, g, vars)).collect();
    (0..vars.len()).any(|j| {
        let mut m = rows.clone();
        m.push(
            (0..vars.len())
                .map(|k| ctx.int(i64::from(k == j)))
                .collect(),
        );
        let d = det(ctx, &m);
        !ctx.canon(d).is_zero()
    })
}

/// `dm/dt` along the model, taken here: `dm . field` over `vars` plus
/// `sum_l dm/du^(l) u^(l+1)` over the jets `(u^(l), u^(l+1))`.
fn time_derivative(
    ctx: &mut Ctx,
    m: Id,
    vars: &[&str],
    field: &[&str],
    jets: &[(&str, &str)],
) -> Id {
    let mut terms = Vec::new();
    for (x, c) in vars.iter().zip(field) {
        let v = ctx.symbol(x).var;
        let d = ctx.diff(m, v);
        let c = parse(ctx, c);
        terms.push(ctx.mul(&[c, d]));
    }
    for (u, next) in jets {
        let v = ctx.symbol(u).var;
        let d = ctx.diff(m, v);
        let c = parse(ctx, next);
        terms.push(ctx.mul(&[c, d]));
    }
    ctx.add(&terms)
}

/// Every reduced equation `z' = R(z, u, u', ..., w~)` of `v`, with the modes
/// and each combination `w~ = factor w + offset` written back in the state,
/// equals `dz/dt` taken here (`time_derivative`): the reduction checked by
/// the chain rule, independently of obsan's decomposition checks.
fn reduced_equations_hold(v: &Value, vars: &[&str], field: &[&str], jets: &[(&str, &str)]) {
    let mut ctx = Ctx::new();
    let mut back = Vec::new();
    for m in v["modes"].as_array().unwrap() {
        let var = ctx.symbol(m["name"].as_str().unwrap()).var;
        let e = parse(&mut ctx, m["expr"].as_str().unwrap());
        back.push((var, e));
    }
    for ri in v["reduced_inputs"].as_array().unwrap() {
        let var = ctx.symbol(ri["name"].as_str().unwrap()).var;
        let w = ctx.symbol(ri["input"].as_str().unwrap()).id;
        let e = match ri["factor"].as_str() {
            None => w,
            Some(f) => {
                let f = parse(&mut ctx, f);
                let fw = ctx.mul(&[f, w]);
                match ri["offset"].as_str() {
                    None => fw,
                    Some(o) => {
                        let o = parse(&mut ctx, o);
                        ctx.add(&[fw, o])
                    }
                }
            }
        };
        back.push((var, e));
    }
    let modes: Vec<(String, Id)> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let e = parse(&mut ctx, m["expr"].as_str().unwrap());
            (m["name"].as_str().unwrap().to_string(), e)
        })
        .collect();
    for d in v["reduced"]["dynamics"].as_array().unwrap() {
        let name = d["name"].as_str().unwrap();
        let rhs = d["rhs"].as_str().unwrap_or_else(|| panic!("{name}: {d}"));
        let r = parse(&mut ctx, rhs);
        let r = ctx.substitute(r, &back).unwrap();
        let m = modes.iter().find(|m| m.0 == name).unwrap().1;
        let want = time_derivative(&mut ctx, m, vars, field, jets);
        let diff = ctx.sub(r, want);
        assert!(ctx.canon(diff).is_zero(), "{name}' = {rhs}");
    }
}

/// The smallest case (tests/cli/unknown_input_jets.rs): x1' = p u + x2,
/// x2' = w, y = x1, whose lost direction is xi = (0, -u, 1) over
/// (x1, x2, p). By hand: with u frozen, the first integrals of xi are x1
/// and x2 + u p (xi . grad = -u + u = 0), rank 2. Their dynamics:
/// x1' = p u + x2 = z (the second), and (x2 + u p)' = w + p u', where p u'
/// is no function of (x1, x2 + u p) and the jets: the combination
/// w~ = w + p u' (factor 1, offset p u') drives it, recovered from y''.
const SMALL: &str = "system small_input_dependent
state x1, x2
param p
input u
unknown input w
x1' = p*u + x2
x2' = w
output y = x1
";

#[test]
fn modes_that_move_with_the_known_input_small() {
    let f = temp_file("small_input_dependent_modes.sys", SMALL);
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(3)));
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 2, "{v}");
    let vars = ["x1", "x2", "p"];
    let mut ctx = Ctx::new();
    let ms: Vec<Id> = modes
        .iter()
        .map(|m| parse(&mut ctx, m["expr"].as_str().unwrap()))
        .collect();
    // The same functions as {x1, x2 + u p}, over the state with u frozen.
    let hand = [parse(&mut ctx, "x1"), parse(&mut ctx, "x2 + u*p")];
    assert!(independent(&mut ctx, &ms, &vars), "{v}");
    // Each mode annihilated by xi = (0, -u, 1) (eq. 11, u held).
    let xi = [ctx.int(0), parse(&mut ctx, "-u"), ctx.int(1)];
    for &m in &ms {
        let g = grad(&mut ctx, m, &vars);
        let terms: Vec<Id> = g.iter().zip(&xi).map(|(&a, &b)| ctx.mul(&[a, b])).collect();
        let sum = ctx.add(&terms);
        assert!(ctx.canon(sum).is_zero(), "{v}");
    }
    for &h in &hand {
        assert!(depends_on(&mut ctx, h, &ms, &vars), "{v}");
    }
    for &m in &ms {
        assert!(depends_on(&mut ctx, m, &hand, &vars), "{v}");
    }
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    assert_eq!(v["verified"], true, "{v}");
    // The reduced system reads u and u'.
    let inputs: Vec<&str> = v["reduced"]["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert!(inputs.contains(&"u'"), "{inputs:?}");
    reduced_equations_hold(&v, &vars, &["p*u + x2", "w", "0"], &[("u", "u'")]);
    let out = ok(&["modes", &f]);
    assert!(out.contains("u'"), "{out}");
    assert!(out.contains("time derivative"), "{out}");
}

/// STRIKE-GOLDD's CSTR observer (cstr_observer.sys, the verdict derived in
/// the file). With E = exp(gamma Tr/(gamma + Tr/20)) and u3 frozen:
/// y = Tc; y' = delta1 qc (u3 - Tc) + 3 (Tr - Tc); y'' = delta1 qc (u3' -
/// Tc') + 3 Tr' - 3 Tc' with Tc' = y' and Tr' = q (u2 - Tr) + 0.576 E Cr -
/// 0.3 (Tr - Tc). The symmetry printed as w1 = [1, a, 0, b] over (Cr, Tr,
/// Tc, delta1) leaves Tc alone and y' invariant (3 a + qc (u3 - Tc) b = 0),
/// and y'' too (d enters only y''' through Cr' = ... + d): three invariants
/// of rank 3, the modes' span. The u2 term of y'' is a function of the jets
/// alone (no symmetry moves it): the comparison is over the state's four
/// coordinates, the jets held.
#[test]
fn cstr_observer_modes_move_with_the_coolant_feed() {
    let f = "systems/benchmarks/unknown-inputs/cstr_observer.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(3), Some(4)));
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3, "{v}");
    let vars = ["Cr", "Tr", "Tc", "delta1"];
    let mut ctx = Ctx::new();
    let ms: Vec<Id> = modes
        .iter()
        .map(|m| parse(&mut ctx, m["expr"].as_str().unwrap()))
        .collect();
    let e = "exp(gamma*Tr/(gamma + Tr/20))";
    let y1 = "delta1*qc*(u3 - Tc) + 3*(Tr - Tc)";
    let tr = format!("q*(u2 - Tr) + 0.576*{e}*Cr - 0.3*(Tr - Tc)");
    let y2 = format!("delta1*qc*(u3' - ({y1})) + 3*({tr}) - 3*({y1})");
    let hand = [
        parse(&mut ctx, "Tc"),
        parse(&mut ctx, y1),
        parse(&mut ctx, &y2),
    ];
    assert!(independent(&mut ctx, &hand, &vars));
    assert!(independent(&mut ctx, &ms, &vars), "{v}");
    // Each mode is annihilated by the symmetry `obsan symmetries` prints
    // (w1 = [1, a, 0, b]; eq. 11 taken here, the jets held).
    let s: Value = serde_json::from_str(&ok(&["symmetries", "--json", f])).unwrap();
    let w: Vec<Id> = vars
        .iter()
        .map(|x| parse(&mut ctx, s["symmetries"][0][x]["text"].as_str().unwrap()))
        .collect();
    assert!(ctx.canon(w[2]).is_zero(), "{s}");
    for &m in &ms {
        let g = grad(&mut ctx, m, &vars);
        let terms: Vec<Id> = g.iter().zip(&w).map(|(&a, &b)| ctx.mul(&[a, b])).collect();
        let sum = ctx.add(&terms);
        assert!(ctx.canon(sum).is_zero(), "{v}");
    }
    for &h in &hand {
        assert!(depends_on(&mut ctx, h, &ms, &vars), "{v}");
    }
    for &m in &ms {
        assert!(depends_on(&mut ctx, m, &hand, &vars), "{v}");
    }
    assert_eq!(v["verified"], true, "{v}");
    // The reduced system closes: Tc' = y' and y'' in the modes, and the
    // third mode's derivative (y''' holds d, Cr and u3'') is the
    // combination beta d + offset; each equation checked by the chain rule.
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    let field = [
        format!("q*(u1 - Cr) - 0.072*{e}*Cr + d"),
        tr.clone(),
        y1.to_string(),
        "0".to_string(),
    ];
    let field: Vec<&str> = field.iter().map(String::as_str).collect();
    reduced_equations_hold(&v, &vars, &field, &[("u3", "u3'"), ("u3_d", "u3''")]);
    let inputs: Vec<&str> = v["reduced"]["inputs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(inputs, ["u1", "u2", "u3", "u3'", "u3''"], "{v}");
    let out = ok(&["modes", f]);
    assert!(out.contains("u3'"), "{out}");
}

/// Two unknown inputs, one reconstructable: by hand, y2 = x4 gives w1 =
/// y2' - y2 (order 1); x2 and p enter only as x2 + u p (y1' = p u + x2), and
/// w2 is new at every order, so xi = (0, -u, 1, 0) over (x1, x2, p, x4)
/// (x2 + u p and x1, x4 invariant): modes x1, x4, x2 + u p, rank 3 of 4.
/// Reduced: x1' = z1, x4' = x4 + w1 (w1 itself), z1' = w2 + p u' (a
/// combination; p u' no function of the modes). The known inputs' term
/// p u' is projected along w2, the input that moves the open mode, not
/// along w1, the first one any mode sees.
const MIXED: &str = "system mixed
state x1, x2, x4
param p
input u
unknown input w1, w2
x1' = p*u + x2
x2' = w2
x4' = w1 + x4
output y1 = x1
output y2 = x4
";

#[test]
fn a_reconstructable_input_beside_modes_that_move_with_the_known_input() {
    let f = temp_file("mixed_input_dependent.sys", MIXED);
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(3), Some(4)));
    let vars = ["x1", "x2", "p", "x4"];
    let mut ctx = Ctx::new();
    let ms: Vec<Id> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| parse(&mut ctx, m["expr"].as_str().unwrap()))
        .collect();
    assert_eq!(ms.len(), 3, "{v}");
    let hand = [
        parse(&mut ctx, "x1"),
        parse(&mut ctx, "x4"),
        parse(&mut ctx, "x2 + u*p"),
    ];
    assert!(independent(&mut ctx, &ms, &vars), "{v}");
    for &h in &hand {
        assert!(depends_on(&mut ctx, h, &ms, &vars), "{v}");
    }
    for &m in &ms {
        assert!(depends_on(&mut ctx, m, &hand, &vars), "{v}");
    }
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    assert_eq!(v["verified"], true, "{v}");
    let ri = v["reduced_inputs"].as_array().unwrap();
    let w1 = ri.iter().find(|r| r["input"] == "w1").unwrap();
    assert!(w1["factor"].is_null(), "{v}");
    assert_eq!(w1["order"], 1, "{v}");
    reduced_equations_hold(
        &v,
        &vars,
        &["p*u + x2", "w2", "0", "w1 + x4"],
        &[("u", "u'")],
    );
}
