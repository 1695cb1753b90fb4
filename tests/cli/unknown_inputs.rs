//! `obsan rank` with unknown inputs, as a user runs it; verdicts
//! derived by hand in the model files (systems/benchmarks/unknown-inputs/).

use crate::util::*;
use serde_json::Value;

#[test]
fn rank_names_the_reconstructable_input_and_its_order() {
    // y = x1, y' = x2, y'' = w (chain.sys).
    let out = ok(&["rank", "systems/benchmarks/unknown-inputs/chain.sys"]);
    assert!(out.contains("rank 2 of 2"), "{out}");
    assert!(
        out.contains("w (from output derivatives of order 2)"),
        "{out}"
    );
    assert!(out.contains("both routes agree"), "{out}");
    let v: Value = serde_json::from_str(&ok(&[
        "rank",
        "--json",
        "systems/benchmarks/unknown-inputs/chain.sys",
    ]))
    .unwrap();
    assert_eq!(v["unknown_inputs"][0], "w");
    assert_eq!(v["reconstructable_inputs"][0]["name"], "w");
    assert_eq!(v["reconstructable_inputs"][0]["order"], 2);
    assert_eq!(v["observable_variables"][1]["name"], "x2");
    assert_eq!(v["observable_variables"][1]["order"], 1);
    assert_eq!(v["converged"], true);
    assert_eq!(v["agree"], true);
    assert_eq!(v["martinelli"]["reconstructable"][0], "w");
}

#[test]
fn a_negative_verdict_is_proven_and_says_what_is_not() {
    // c2m_known_b.sys: only x1 observable, at every order (derived in the
    // file): Martinelli's algorithm proves it whatever --order; w's verdict
    // (the state not observable) holds up to the order examined.
    let v: Value = serde_json::from_str(&ok(&[
        "rank",
        "--json",
        "--order",
        "3",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]))
    .unwrap();
    assert_eq!(v["rank"], 1);
    assert_eq!(v["max_order"], 3);
    assert_eq!(v["converged"], false);
    assert_eq!(v["agree"], true);
    assert_eq!(v["martinelli"]["rank"], 1);
    assert_eq!(v["martinelli"]["observable"][0], "x1");
    assert_eq!(v["unreconstructable_inputs"][0], "w");
    let out = ok(&[
        "rank",
        "--order",
        "3",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]);
    assert!(out.contains("rank 1 of 5 is final"), "{out}");
    assert!(
        out.contains("w not reconstructable up to order 3 only"),
        "{out}"
    );
}

#[test]
fn other_commands_refuse_unknown_inputs() {
    // global would otherwise count values as if w were absent (a wrong answer, not a refusal);
    // several experiments would stack the model without its unknown input.
    bad(
        &[
            "rank",
            "systems/benchmarks/unknown-inputs/chain.sys",
            "--experiment",
            "",
            "--experiment",
            "",
        ],
        "is an unknown input",
    );
    for cmd in ["check", "global", "lie"] {
        let mut args = vec![cmd, "systems/benchmarks/unknown-inputs/chain.sys"];
        if cmd == "check" {
            args.extend(["--mode", "x1"]);
        }
        if cmd == "lie" {
            args.extend(["--order", "1"]);
        }
        bad(&args, "has unknown inputs (w)");
    }
}

#[test]
fn symmetries_of_the_unicycle_with_unknown_speed() {
    // unicycle_one_landmark.sys: rotation about the landmark and scaling are
    // lost (derived in the file and in the analysis crate's
    // tests/unknown_input_symmetries.rs): two symmetries, rank 1, nothing
    // observable but the bearing, v not reconstructable.
    let f = "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys";
    let out = ok(&["symmetries", f]);
    assert!(
        out.contains("rank 1 of 3 with unknown inputs, 2 independent symmetries"),
        "{out}"
    );
    assert!(
        out.contains("unobservable (moved by a symmetry, exact): x, y, theta"),
        "{out}"
    );
    assert!(
        out.contains("exact: each symmetry leaves every output invariant"),
        "{out}"
    );
    let v: Value = serde_json::from_str(&ok(&["symmetries", "--json", f])).unwrap();
    assert_eq!(v["symmetries"].as_array().unwrap().len(), 2);
    assert_eq!(v["certificate"], "unknown_input_invariance");
    assert_eq!(v["exact"], true);
    assert_eq!(v["reconstructable_inputs"].as_array().unwrap().len(), 0);
    // --help names exactly the keys of this object (its second --json sentence).
    let help = ok(&["symmetries", "--help"]);
    let at = help
        .find("unknown inputs --json prints {")
        .expect("no unknown-input sentence");
    let text = &help[at + "unknown inputs --json prints {".len()..];
    let body = &text[..text.find('}').unwrap()];
    let mut promised: Vec<String> = body
        .split(',')
        .map(|i| {
            i.trim()
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect()
        })
        .collect();
    promised.sort();
    let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    got.sort();
    assert_eq!(promised, got);
}

#[test]
fn symmetries_with_unknown_inputs_full_rank_and_refusals() {
    // chain.sys: y, y' give x1, x2: no symmetry.
    let out = ok(&["symmetries", "systems/benchmarks/unknown-inputs/chain.sys"]);
    assert!(out.contains("0 independent symmetries"), "{out}");
    // Two-compartment, b known: x2, k1e, k12, k21 lost (file comment).
    let v: Value = serde_json::from_str(&ok(&[
        "symmetries",
        "--json",
        "systems/benchmarks/unknown-inputs/c2m_known_b.sys",
    ]))
    .unwrap();
    assert_eq!(
        v["unobservable_variables"],
        serde_json::json!(["x2", "k1e", "k12", "k21"])
    );
    assert_eq!(v["observable_variables"], serde_json::json!(["x1"]));
}

// Explicit time `t` (docs/sys-format.md, "Explicit time"): a known
// coordinate with t' = 1. Each verdict below is derived by hand beside it.

fn rank_json(name: &str, src: &str) -> Value {
    let f = temp_file(name, src);
    serde_json::from_str(&ok(&["rank", "--json", &f])).unwrap()
}

fn names(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.get("name").unwrap_or(x).as_str().unwrap().to_string())
        .collect()
}

#[test]
fn time_in_the_output_with_an_unknown_input() {
    // x' = w, y = x + t^2: x = y - t^2 (order 0), y' = w + 2t so
    // w = y' - 2t (order 1). The clock is not a state of the user's.
    let v = rank_json(
        "time_quad.sys",
        "system q\nstate x\nunknown input w\nx' = w\noutput y = x + t^2\n",
    );
    assert_eq!(v["state"], serde_json::json!(["x"]));
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(1)));
    assert_eq!(v["observable_variables"][0]["name"], "x");
    assert_eq!(v["observable_variables"][0]["order"], 0);
    assert_eq!(v["reconstructable_inputs"][0]["name"], "w");
    assert_eq!(v["reconstructable_inputs"][0]["order"], 1);
    assert_eq!(v["martinelli"]["rank"], 1);
    assert_eq!(v["agree"], true);
    // The clock's row is not in the printed basis: y and y' only.
    assert_eq!(v["basis"].as_array().unwrap().len(), 2);
}

#[test]
fn a_time_varying_gain_makes_a_state_observable_that_a_constant_gain_hides() {
    // x' = 0, y = x*t: x = y/t where t != 0 (and y' = x): observable.
    let v = rank_json(
        "time_gain.sys",
        "system g\nstate x\nx' = 0\noutput y = x*t\n",
    );
    assert_eq!(v["state"], serde_json::json!(["x"]));
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(1)));
    assert_eq!(names(&v["observable_variables"]), ["x"]);
    assert_eq!(v["weakly_locally_observable"], true);
    // The same model with t replaced by an unknown constant c: y = x*c,
    // y' = 0; (x, c) -> (l x, c/l) leaves y unchanged: rank 1 of 2, neither
    // observable.
    let v = rank_json(
        "const_gain.sys",
        "system g\nstate x\nparam c\nx' = 0\noutput y = x*c\n",
    );
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(2)));
    assert!(names(&v["observable_variables"]).is_empty());
    // With an unknown input too: y = x + c^2, y' = w: x is lost with c
    // (x + c^2 alone is seen), while y = x + t^2 above gives x.
    let v = rank_json(
        "const_quad.sys",
        "system q\nstate x\nparam c\nunknown input w\nx' = w\noutput y = x + c^2\n",
    );
    assert_eq!(v["rank"], 1);
    assert!(names(&v["observable_variables"]).is_empty());
    assert_eq!(v["reconstructable_inputs"][0]["name"], "w");
}

#[test]
fn time_in_the_benchmark_models() {
    // time_gain.sys: y = t*x1, y' = x1 + t*x2, y'' = 2*x2 + t*w (in the file).
    let v: Value = serde_json::from_str(&ok(&[
        "rank",
        "--json",
        "systems/benchmarks/unknown-inputs/time_gain.sys",
    ]))
    .unwrap();
    assert_eq!(v["state"], serde_json::json!(["x1", "x2"]));
    assert_eq!(v["rank"], 2);
    let orders: Vec<u64> = v["observable_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| o["order"].as_u64().unwrap())
        .collect();
    assert_eq!(orders, [0, 1]);
    assert_eq!(v["reconstructable_inputs"][0]["order"], 2);
    // time_offset.sys: y = x + b*t, y' = w + b; -t d/dx + d/db (with
    // w -> w - 1) is lost: rank 1 of 2, w not reconstructable.
    let f = "systems/benchmarks/unknown-inputs/time_offset.sys";
    let v: Value = serde_json::from_str(&ok(&["symmetries", "--json", f])).unwrap();
    assert_eq!(v["state"], serde_json::json!(["x", "b"]));
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(2)));
    let s = v["symmetries"].as_array().unwrap();
    assert_eq!(s.len(), 1);
    let comps = s[0].as_object().unwrap();
    assert_eq!(comps.len(), 2, "no clock component: {comps:?}");
    // Proportional to (-t, 1): x-component / b-component = -t.
    let (x, b) = (
        comps["x"]["text"].as_str().unwrap(),
        comps["b"]["text"].as_str().unwrap(),
    );
    assert!(same_function(&format!("({x})/({b})"), "-t"), "{x}, {b}");
    assert_eq!(v["unobservable_variables"], serde_json::json!(["x", "b"]));
    assert_eq!(v["reconstructable_inputs"], serde_json::json!([]));
}

#[test]
fn symmetries_with_time_and_known_inputs_leave_the_clock_out() {
    // x' = 0, param k, y = x*k*t: y' = x*k, y'' = 0; only x*k is seen, the
    // scaling x d/dx - k d/dk is lost: rank 1 of 2, one symmetry on (x, k).
    let f = temp_file(
        "time_scaling.sys",
        "system s\nstate x\nparam k\nx' = 0\noutput y = x*k*t\n",
    );
    let v: Value = serde_json::from_str(&ok(&["symmetries", "--json", &f])).unwrap();
    assert_eq!(v["state"], serde_json::json!(["x", "k"]));
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(2)));
    let s = v["symmetries"].as_array().unwrap();
    assert_eq!(s.len(), 1);
    let (x, k) = (
        s[0]["x"]["text"].as_str().unwrap(),
        s[0]["k"]["text"].as_str().unwrap(),
    );
    assert!(s[0].get("t").is_none());
    assert!(same_function(&format!("({x})/({k})"), "-x/k"), "{x}, {k}");
    let out = ok(&["show", &f]);
    assert!(out.contains("states: x\n"), "{out}");
    assert!(out.contains("time: "), "{out}");
}

#[test]
fn commands_without_a_clock_refuse_time_at_its_place() {
    let f = temp_file(
        "time_refused.sys",
        "system g\nstate x\ninput u\nx' = u\noutput y = x*t\n",
    );
    let place = format!("{f}:5:14: explicit time 't'");
    // `modes` handles it since session 25 (tests/cli/modes.rs,
    // `modes_with_explicit_time`).
    for (cmd, extra) in [
        ("global", vec![]),
        ("lie", vec!["--order", "1"]),
        ("check", vec!["--mode", "x"]),
    ] {
        let mut args = vec![cmd, f.as_str()];
        args.extend(extra);
        let err = bad(&args, &place);
        assert!(err.contains(&format!("`obsan {cmd}`")), "{err}");
    }
    let err = bad(&["rank", &f, "--known-generic", "x"], &place);
    assert!(err.contains("`obsan rank --known`"), "{err}");
    bad(
        &["rank", &f, "--experiment", "", "--experiment", ""],
        &place,
    );
}

#[test]
fn observable_over_related_atoms_is_not_claimed_under_unknown_inputs() {
    // h2 = y (log(x y) - log x - log y) is 0 where it is real (x, y > 0), so
    // y is truly unobservable; the engine keeps log(x y), log x, log y as
    // independent atoms, where the formal rank is 2 of 2. Full rank must
    // not be claimed: "not decided", with the atoms named.
    let v = rank_json(
        "related_atoms_ui.sys",
        "system r\nstate x, y\nunknown input w\nx' = w\ny' = 0\noutput h1 = x\noutput h2 = y*(log(x*y) - log(x) - log(y))\n",
    );
    assert_eq!(v["decided"], false, "{v}");
    assert!(v["weakly_locally_observable"].is_null(), "{v}");
    let atoms: Vec<String> = v["undecided_atoms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_str().unwrap().to_string())
        .collect();
    assert!(atoms.iter().any(|a| a.contains("log")), "{atoms:?}");
    // The text says the same, naming the atoms (not the unknown inputs left
    // unreconstructed, a different list).
    let f = temp_file(
        "related_atoms_ui_text.sys",
        "system r\nstate x, y\nunknown input w\nx' = w\ny' = 0\noutput h1 = x\noutput h2 = y*(log(x*y) - log(x) - log(y))\n",
    );
    let text = ok(&["rank", &f]);
    let line = text
        .lines()
        .find(|l| l.starts_with("not decided: the atoms"))
        .unwrap_or_else(|| panic!("no 'not decided' line:\n{text}"));
    assert!(line.contains("log") && !line.contains("atoms w "), "{line}");
    // A model over decided atoms keeps its verdict.
    let v = rank_json(
        "decided_atoms_ui.sys",
        "system d\nstate x, y\nunknown input w\nx' = w\ny' = 0\noutput h1 = x\noutput h2 = log(y)\n",
    );
    assert_eq!(v["decided"], true, "{v}");
    assert_eq!(v["weakly_locally_observable"], true, "{v}");
}

/// `v . grad(e)` over the named variables, decided zero by the engine (the
/// derivative taken here, independently of the command that printed `e`).
fn annihilates(e: &str, vars: &[&str], v: &[&str]) -> bool {
    let mut ctx = obsan_expr::Ctx::new();
    let id = ctx.parse(e).unwrap();
    let mut terms = Vec::new();
    for (x, c) in vars.iter().zip(v) {
        let var = ctx.symbol(x).var;
        let d = ctx.diff(id, var);
        let c = ctx.parse(c).unwrap();
        terms.push(ctx.mul(&[c, d]));
    }
    let s = ctx.add(&terms);
    ctx.canon(s).is_zero()
}

#[test]
fn modes_at_full_rank_are_the_states_and_name_the_recovered_input() {
    // chain.sys: y = x1, y' = x2, y'' = w: rank 2 of 2, so the modes are x1,
    // x2 and the reduced system is the model; w moves x2 first (g = (0, 1))
    // and is recovered from y'' (order 2).
    let f = "systems/benchmarks/unknown-inputs/chain.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!(v["full_rank"], true, "{v}");
    assert_eq!(names(&v["modes"]), ["x1", "x2"]);
    assert!(v["reduced"].is_null());
    let ri = v["reduced_inputs"].as_array().unwrap();
    assert_eq!(ri.len(), 1, "{v}");
    assert_eq!(ri[0]["input"], "w");
    assert_eq!(ri[0]["name"], "w");
    assert!(ri[0]["factor"].is_null());
    assert_eq!(ri[0]["mode"], "x2");
    assert_eq!(ri[0]["order"], 2);
    let out = ok(&["modes", f]);
    assert!(out.contains("the modes are the variables"), "{out}");
    assert!(
        out.contains("w (w, reconstructable from output derivatives of order 2)"),
        "{out}"
    );
}

#[test]
fn modes_of_the_unicycle_with_unknown_speed_one_landmark() {
    // unicycle_one_landmark.sys, by hand: the bearing beta = atan2(-y, -x) -
    // theta is invariant under the rotation about the landmark (-y, x, 1) and
    // the scaling (x, y, 0) (v scaled with it), the two lost directions; so
    // 3 - 2 = 1 mode, each printed mode annihilated by both. beta' = phi' -
    // omega with phi' = (x y' - y x')/rho^2 = v (x sin(theta) - y
    // cos(theta))/rho^2, not a function of the mode: the reduced system is
    // driven by the combination (dm . g) v, g = (cos(theta), sin(theta), 0),
    // which the mode's first derivative gives, while v itself is lost.
    let f = "systems/benchmarks/unknown-inputs/unicycle_one_landmark.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!(v["full_rank"], false, "{v}");
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(3)));
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 1, "{v}");
    let vars = ["x", "y", "theta"];
    for m in modes {
        let e = m["expr"].as_str().unwrap();
        assert!(annihilates(e, &vars, &["-y", "x", "1"]), "{e}");
        assert!(annihilates(e, &vars, &["x", "y", "0"]), "{e}");
        // Not a constant: it moves along the drive (dm . g != 0).
        assert!(
            !annihilates(e, &vars, &["cos(theta)", "sin(theta)", "0"]),
            "{e}"
        );
    }
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    assert_eq!(v["verified"], true, "{v}");
    let ri = v["reduced_inputs"].as_array().unwrap();
    assert_eq!(ri.len(), 1, "{v}");
    assert_eq!(ri[0]["input"], "v");
    assert!(ri[0]["order"].is_null());
    // The factor is dm . g, g = (cos(theta), sin(theta), 0).
    let (e, factor) = (
        modes[0]["expr"].as_str().unwrap(),
        ri[0]["factor"].as_str().unwrap(),
    );
    let mut ctx = obsan_expr::Ctx::new();
    let m = ctx.parse(e).unwrap();
    let (xv, yv) = (ctx.symbol("x").var, ctx.symbol("y").var);
    let (dx, dy) = (ctx.diff(m, xv), ctx.diff(m, yv));
    let (c, s, fa) = (
        ctx.parse("cos(theta)").unwrap(),
        ctx.parse("sin(theta)").unwrap(),
        ctx.parse(factor).unwrap(),
    );
    let (a, b) = (ctx.mul(&[c, dx]), ctx.mul(&[s, dy]));
    let lg = ctx.add(&[a, b]);
    assert_eq!(ctx.canon(lg), ctx.canon(fa), "{factor}");
    // The reduced dynamics use the combination and omega.
    let rhs = v["reduced"]["dynamics"][0]["rhs"].as_str().unwrap();
    let name = ri[0]["name"].as_str().unwrap();
    assert!(rhs.contains(name) && rhs.contains("omega"), "{rhs}");
    // --help names exactly the keys of this object (its unknown-input sentence).
    let help = ok(&["modes", "--help"]);
    let at = help
        .find("unknown inputs --json prints {")
        .expect("no unknown-input sentence");
    let mut promised = brace_items(&help[at + "unknown inputs --json prints ".len()..]);
    promised.sort();
    let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    got.sort();
    assert_eq!(promised, got);
}

#[test]
fn modes_refuse_a_reduced_system_needing_a_lost_input() {
    // x1' = w1 + w2, x2' = w2, y = x1: y' = w1 + w2 gives the sum only, so
    // neither w1 nor w2 is reconstructable, and x2 is lost (d/dx2 commutes
    // with the constant fields and leaves y alone). The one mode is x1 and
    // x1' = w1 + w2 needs w1: refused, naming both.
    let f = temp_file(
        "lost_input.sys",
        "system lost\nstate x1, x2\nunknown input w1, w2\nx1' = w1 + w2\nx2' = w2\noutput y = x1\n",
    );
    let err = bad(
        &["modes", &f],
        "the derivative of mode x1 needs the unknown input w1",
    );
    assert!(err.contains("not reconstructable"), "{err}");
    assert!(err.contains(&f), "{err}");
    // verify says the same of the decomposition x1, x1' = w1 + w2.
    let dec = temp_file(
        "lost_input.dec",
        &format!("system {f}\nstate x1\nx1' = w1 + w2\noutput y = x1\n"),
    );
    let r = obsan(&["verify", &dec]);
    assert_eq!(r.code, 1, "{}{}", r.stdout, r.stderr);
    assert!(
        r.stdout
            .contains("FAIL unknown input w1, which drives the reduced dynamics"),
        "{}",
        r.stdout
    );
}

#[test]
fn modes_and_verify_with_a_reconstructable_input() {
    // x1' = w, x2' = 0, y = x1 + x2: y' = w, so only x1 + x2 is observable
    // (symmetry (1, -1)), w is reconstructable from y' (order 1), and the
    // reduced system is z' = w, y = z with z = x1 + x2.
    let f = temp_file(
        "sum_input.sys",
        "system sum\nstate x1, x2\nunknown input w\nx1' = w\nx2' = 0\noutput y = x1 + x2\n",
    );
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 1, "{v}");
    let e = modes[0]["expr"].as_str().unwrap();
    assert!(annihilates(e, &["x1", "x2"], &["1", "-1"]), "{e}");
    assert_eq!(v["verified"], true, "{v}");
    assert_eq!(v["reduced_inputs"][0]["name"], "w");
    assert_eq!(v["reduced_inputs"][0]["order"], 1);
    let dec = temp_file(
        "sum_input.dec",
        &format!("system {f}\nlet z = x1 + x2\nstate z\nz' = w\noutput y = z\n"),
    );
    let out = ok(&["verify", &dec]);
    assert!(
        out.contains("PASS unknown input w, which drives the reduced dynamics, is reconstructable"),
        "{out}"
    );
    // The reduced system keeps w unknown: its rank says w is recovered from y'.
    let dir = fresh_dir("ui-modes-out");
    let prefix = format!("{dir}/sum");
    ok(&["modes", &f, "--out", &prefix]);
    let sys = std::fs::read_to_string(format!("{prefix}.sys")).unwrap();
    assert!(sys.contains("unknown input w\n"), "{sys}");
    let out = ok(&["rank", &format!("{prefix}.sys")]);
    assert!(
        out.contains("w (from output derivatives of order 1)"),
        "{out}"
    );
    // A wrong claim fails: z' = 2 w.
    let wrong = temp_file(
        "sum_input_wrong.dec",
        &format!("system {f}\nlet z = x1 + x2\nstate z\nz' = 2*w\noutput y = z\n"),
    );
    assert_eq!(obsan(&["verify", &wrong]).code, 1);
}

#[test]
fn a_drift_term_the_modes_cannot_write_moves_into_the_combination() {
    // x' = k + w, y = x, k a param: y' = k + w, so k is lost (d/dk: [f0, d/dk]
    // = -g, in the span) and so is w; x is the one mode. x' = k + w needs k,
    // not a function of x: the reduced input is w_x = 1*w + k = y', and the
    // reduced system x' = w_x, y = x.
    let f = temp_file(
        "drift_offset.sys",
        "system drift\nstate x\nparam k\nunknown input w\nx' = k + w\noutput y = x\n",
    );
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    assert_eq!(names(&v["modes"]), ["x"], "{v}");
    let ri = &v["reduced_inputs"][0];
    assert_eq!(ri["input"], "w");
    assert!(same_function(ri["factor"].as_str().unwrap(), "1"), "{ri}");
    assert!(same_function(ri["offset"].as_str().unwrap(), "k"), "{ri}");
    let name = ri["name"].as_str().unwrap();
    assert_eq!(v["reduced"]["dynamics"][0]["rhs"], name, "{v}");
    assert_eq!(v["verified"], true, "{v}");
}

#[test]
fn two_unknown_inputs_with_a_drift_are_projected_jointly() {
    // a' = c w1 + c, b' = c w2 + c, c' = 0, y = (a, b): c is lost (d/dc:
    // [f0, d/dc] = -(1, 1, 0) = -(g1 + g2)/c, [g_j, d/dc] = -g_j/c, in the
    // span), w1 and w2 with it (only c w_j is seen); a and b are the modes.
    // Both derivatives need c: with B = diag(c, c) and the drift projected
    // along both fields at once, a' = w1~ and b' = w2~ with w1~ = c w1 + c,
    // w2~ = c w2 + c. Projecting along one input at a time left b' = c w2 + c
    // with c in it: not closed.
    let f = temp_file(
        "joint_drift.sys",
        "system joint\nstate a, b, c\nunknown input w1, w2\n\
         a' = c*w1 + c\nb' = c*w2 + c\nc' = 0\noutput y1 = a\noutput y2 = b\n",
    );
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    assert_eq!(names(&v["modes"]), ["a", "b"], "{v}");
    let ri = v["reduced_inputs"].as_array().unwrap();
    assert_eq!(ri.len(), 2, "{v}");
    for (r, (w, state)) in ri.iter().zip([("w1", "a"), ("w2", "b")]) {
        assert_eq!(r["input"], w, "{r}");
        assert!(same_function(r["factor"].as_str().unwrap(), "c"), "{r}");
        assert!(same_function(r["offset"].as_str().unwrap(), "c"), "{r}");
        let dyn_ = v["reduced"]["dynamics"]
            .as_array()
            .unwrap()
            .iter()
            .find(|d| d["name"] == state)
            .unwrap_or_else(|| panic!("{state}' in {v}"));
        assert_eq!(dyn_["rhs"], r["name"], "{v}");
    }
    assert_eq!(v["verified"], true, "{v}");
}

#[test]
fn the_toggle_switch_reduced_system_closes() {
    // The toggle switch (TUIO6's example, two unknown inputs): the reduced
    // system in its four modes is proven by exact substitution, each field
    // and output written in the modes, with each unknown input's combination
    // the derivative of its paired mode (full column rank, checked).
    let root = env!("CARGO_MANIFEST_DIR");
    let f = format!("{root}/systems/benchmarks/unknown-inputs/toggle.sys");
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", &f])).unwrap();
    assert_eq!(v["verified"], true, "{v}");
    assert_eq!(v["reduced_inputs"].as_array().unwrap().len(), 2, "{v}");
    for d in v["reduced"]["dynamics"].as_array().unwrap() {
        assert!(d["rhs"].is_string(), "{d}");
    }
}

/// `sum_i field_i d e / d vars_i`, taken here (independently of obsan's
/// output), as a node.
fn along(
    ctx: &mut obsan_expr::Ctx,
    e: obsan_expr::Id,
    vars: &[&str],
    field: &[&str],
) -> obsan_expr::Id {
    let mut terms = Vec::new();
    for (x, c) in vars.iter().zip(field) {
        let var = ctx.symbol(x).var;
        let d = ctx.diff(e, var);
        let c = ctx.parse(c).unwrap();
        terms.push(ctx.mul(&[c, d]));
    }
    ctx.add(&terms)
}

/// The determinant of a small square matrix of nodes (Laplace, first row).
fn det(ctx: &mut obsan_expr::Ctx, m: &[Vec<obsan_expr::Id>]) -> obsan_expr::Id {
    if m.len() == 1 {
        return m[0][0];
    }
    let mut terms = Vec::new();
    for c in 0..m.len() {
        let minor: Vec<Vec<obsan_expr::Id>> = m[1..]
            .iter()
            .map(|row| (0..row.len()).filter(|&k| k != c).map(|k| row[k]).collect())
            .collect();
        let d = det(ctx, &minor);
        let t = ctx.mul(&[m[0][c], d]);
        terms.push(if c % 2 == 0 { t } else { ctx.neg(t) });
    }
    ctx.add(&terms)
}

#[test]
fn vio_planar_force_modes_close_in_the_outputs_and_the_body_velocity() {
    // By hand (vio_planar_force.sys): the rotation about the landmark R =
    // (-y, x, -vy, vx, 1) on (x, y, vx, vy, theta) is the one lost direction
    // (rank 4 of 5). With c, s = cos, sin(theta), the outputs zx = -(c x + s
    // y), zy = s x - c y and the body-frame velocity bvx = c vx + s vy, bvy =
    // -s vx + c vy are four invariants of R with independent gradients, and
    // everything is rational in them: zx' = -bvx + omega zy, zy' = -bvy -
    // omega zx, bv' = (ax, ay) + R(theta)^T w - omega J bv (J the rotation by
    // 90 degrees), the unknown part R^T w a reconstructable combination. So
    // the modes span the same differentials (each printed mode annihilated
    // by R, four of them independent) and a rational reduced system exists;
    // x^2 + y^2 in place of zx left c x + s y = +-sqrt(x^2 + y^2 - zy^2).
    let vars = ["x", "y", "vx", "vy", "theta"];
    let rot = ["-y", "x", "-vy", "vx", "1"];
    let field = [
        "vx",
        "vy",
        "cos(theta)*ax - sin(theta)*ay + wx",
        "sin(theta)*ax + cos(theta)*ay + wy",
        "omega",
    ];
    let hand = [
        ("zx", "-(cos(theta)*x + sin(theta)*y)"),
        ("zy", "sin(theta)*x - cos(theta)*y"),
        ("bvx", "cos(theta)*vx + sin(theta)*vy"),
        ("bvy", "-sin(theta)*vx + cos(theta)*vy"),
    ];
    let hand_dot = [
        "-bvx + omega*zy",
        "-bvy - omega*zx",
        "ax + omega*bvy + cos(theta)*wx + sin(theta)*wy",
        "ay - omega*bvx - sin(theta)*wx + cos(theta)*wy",
    ];
    let mut ctx = obsan_expr::Ctx::new();
    let hmap: Vec<(obsan_expr::Var, obsan_expr::Id)> = hand
        .iter()
        .map(|(n, e)| (ctx.symbol(n).var, ctx.parse(e).unwrap()))
        .collect();
    for ((_, e), want) in hand.iter().zip(hand_dot) {
        assert!(annihilates(e, &vars, &rot), "{e}");
        let id = ctx.parse(e).unwrap();
        let got = along(&mut ctx, id, &vars, &field);
        let want = ctx.parse(want).unwrap();
        let want = ctx.substitute(want, &hmap).unwrap();
        assert_eq!(ctx.canon(got), ctx.canon(want), "{e}'");
    }

    let f = "systems/benchmarks/unknown-inputs/vio_planar_force.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(4), Some(5)));
    assert_eq!(v["reduced"]["closed"], true, "{v}");
    assert_eq!(v["verified"], true, "{v}");
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4, "{v}");
    let mut map = Vec::new();
    for m in modes {
        let e = m["expr"].as_str().unwrap();
        assert!(annihilates(e, &vars, &rot), "{e}");
        let name = m["name"].as_str().unwrap();
        map.push((ctx.symbol(name).var, ctx.parse(e).unwrap()));
    }
    // Independent: the minor of the Jacobian on (x, y, vx, vy) is not zero.
    let jac: Vec<Vec<obsan_expr::Id>> = map
        .iter()
        .map(|&(_, e)| {
            vars[..4]
                .iter()
                .map(|x| {
                    let var = ctx.symbol(x).var;
                    ctx.diff(e, var)
                })
                .collect()
        })
        .collect();
    let d = det(&mut ctx, &jac);
    assert!(!ctx.canon(d).is_zero(), "dependent modes: {v}");
    // Each reduced input is factor * w + offset, in the model's names.
    for ri in v["reduced_inputs"].as_array().unwrap() {
        let text = format!(
            "({})*{} + ({})",
            ri["factor"].as_str().unwrap(),
            ri["input"].as_str().unwrap(),
            ri["offset"].as_str().unwrap_or("0")
        );
        let name = ri["name"].as_str().unwrap();
        map.push((ctx.symbol(name).var, ctx.parse(&text).unwrap()));
    }
    // The reduced system is the model rewritten: each mode's right-hand side,
    // the modes and combinations written out, is its derivative along the
    // model's field (taken here), and each output is what the model says.
    for (dy, m) in v["reduced"]["dynamics"]
        .as_array()
        .unwrap()
        .iter()
        .zip(modes)
    {
        assert_eq!(dy["name"], m["name"], "{v}");
        let rhs = ctx.parse(dy["rhs"].as_str().unwrap()).unwrap();
        let rhs = ctx.substitute(rhs, &map).unwrap();
        let e = ctx.parse(m["expr"].as_str().unwrap()).unwrap();
        let want = along(&mut ctx, e, &vars, &field);
        assert_eq!(ctx.canon(rhs), ctx.canon(want), "{dy}");
    }
    for o in v["reduced"]["outputs"].as_array().unwrap() {
        let got = ctx.parse(o["expr"].as_str().unwrap()).unwrap();
        let got = ctx.substitute(got, &map).unwrap();
        let name = o["name"].as_str().unwrap();
        let want = ctx
            .parse(hand.iter().find(|h| h.0 == name).unwrap().1)
            .unwrap();
        assert_eq!(ctx.canon(got), ctx.canon(want), "{o}");
    }
}

/// `obsan modes` with unknown inputs and explicit time (issue 33). In
/// time_offset.sys (`x' = w`, `y = x + b*t`, w unknown) the symmetry is
/// `-t d/dx + d/db` (derived in the file): rank 1 of the user's 2 variables,
/// and the one mode shown satisfies eq. (11), `-t dz/dx + dz/db = 0`, checked
/// here by the engine; the clock is never a printed mode. time_gain.sys is
/// observable (rank 2 of 2: `y = t x1`, `y' = x1 + t x2`).
#[test]
fn modes_with_unknown_inputs_and_explicit_time() {
    let f = "systems/benchmarks/unknown-inputs/time_offset.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(1), Some(2)));
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 1, "{modes:?}");
    let e = modes[0]["expr"].as_str().unwrap();
    let mut ctx = obsan_expr::Ctx::new();
    let z = ctx.parse(e).unwrap();
    let t = ctx.parse("t").unwrap();
    let (x, b) = (ctx.symbol("x").var, ctx.symbol("b").var);
    let (dx, db) = (ctx.diff(z, x), ctx.diff(z, b));
    let tdx = ctx.mul(&[t, dx]);
    let pde = ctx.sub(db, tdx);
    assert!(ctx.canon(pde).is_zero(), "{e} is not invariant");
    assert!(!ctx.canon(db).is_zero(), "{e} does not depend on b");
    let dyn_names: Vec<&str> = v["reduced"]["dynamics"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d["name"].as_str().unwrap())
        .collect();
    assert!(!dyn_names.contains(&"t"), "{dyn_names:?}");
    let g: Value = serde_json::from_str(&ok(&[
        "modes",
        "--json",
        "systems/benchmarks/unknown-inputs/time_gain.sys",
    ]))
    .unwrap();
    assert_eq!((g["rank"].as_u64(), g["n"].as_u64()), (Some(2), Some(2)));
    assert_eq!(g["full_rank"], true);
}

#[test]
fn big_with_its_meal_unknown_has_its_glucose_mode_over_roots_no_point_satisfies() {
    // systems/benchmarks/unknown-inputs/big.sys: its seven symmetries are the
    // unit vectors of beta, I and the five params (session 29), so the one
    // mode is G; G' = meal - (c + si I) G needs c, si and I, which are not
    // functions of G: the reduced input is meal_G = 1*meal - (c + si I) G
    // (= y'), and the reduced system G' = meal_G, y = G. Its roots
    // (sqrt(42/(5G)) sqrt(5G/24) = sqrt(7)/2) have no joint value mod p, and
    // none of these expressions reaches them: they are evaluated at points
    // where the roots have no value (exactly). Before: "no random point".
    let f = "systems/benchmarks/unknown-inputs/big.sys";
    let v: Value = serde_json::from_str(&ok(&["modes", "--json", f])).unwrap();
    assert_eq!(names(&v["modes"]), ["G"], "{v}");
    let ri = &v["reduced_inputs"][0];
    assert_eq!(ri["input"], "meal", "{ri}");
    assert!(same_function(ri["factor"].as_str().unwrap(), "1"), "{ri}");
    assert!(
        same_function(ri["offset"].as_str().unwrap(), "-(c + si*I)*G"),
        "{ri}"
    );
    let name = ri["name"].as_str().unwrap();
    assert_eq!(v["reduced"]["dynamics"][0]["rhs"], name, "{v}");
    assert_eq!(v["verified"], true, "{v}");
}
