//! Outputs that read known inputs (issue 32): the normal form measures each such input
//! (a coordinate `u` with `u' = u'` known and the output `u`), and the verdicts are about
//! the original variables. Expectations derived by hand beside each test.

use crate::util::{bad, ok, temp_file};
use serde_json::{json, Value};

fn rank(file: &str, extra: &[&str]) -> Value {
    let mut args = vec!["rank", file, "--json"];
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

const OFFSET: &str = "system offset
state x
param c
input u
x' = u
output y = x + c*u
";

#[test]
fn an_input_read_by_the_output_makes_its_coefficient_observable() {
    // y = x + c u, y' = u + c u' with u and u' known: c = (y' - u)/u' (u' != 0
    // generically), then x = y - c u. Both observable: rank 2 of 2.
    let f = temp_file("offset.sys", OFFSET);
    let v = rank(&f, &[]);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(2)));
    assert_eq!(v["state"], json!(["x", "c"]));
    assert_eq!(v["measured_inputs"], json!(["u"]));
    assert_eq!(v["observable_variables"], json!(["x", "c"]));
    assert_eq!(v["exact"], true);
    let text = ok(&["rank", &f]);
    assert!(text.contains("outputs read the known input u"), "{text}");
    assert!(text.contains("u' known"), "{text}");
    assert!(text.contains("rank 2 of 2"), "{text}");
    // SIAN's route agrees: x(0) and c globally identifiable; u is not listed.
    let g = ok(&["global", &f]);
    assert!(g.contains("c  param  globally identifiable"), "{g}");
    assert!(g.contains("x  state  globally identifiable"), "{g}");
    assert!(!g.contains("u  state"), "{g}");
}

#[test]
fn an_input_read_by_the_output_can_leave_a_scaling() {
    // x' = -k x, y = c x u: x -> l x, c -> c/l keeps y and the dynamics, for any u.
    // y/u = c x =: z with z' = -k z, so k = -z'/z is observable and only the product c x
    // of the other two: rank 2 of 3, x and c unobservable, the symmetry moves x and c
    // (x d/dx - c d/dc) and never u.
    let f = temp_file(
        "scaled.sys",
        "system scaled\nstate x\nparam k, c\ninput u\nx' = -k*x\noutput y = c*x*u\n",
    );
    let v = rank(&f, &[]);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(3)));
    assert_eq!(v["observable_variables"], json!(["k"]));
    assert_eq!(v["unobservable_variables"], json!(["x", "c"]));
    let s: Value = serde_json::from_str(&ok(&["symmetries", &f, "--json"])).unwrap();
    assert_eq!((s["rank"].as_u64(), s["n"].as_u64()), (Some(2), Some(3)));
    let syms = s["symmetries"].as_array().unwrap();
    assert_eq!(syms.len(), 1, "{s}");
    let w = syms[0].as_object().unwrap();
    let mut moved: Vec<&str> = w
        .iter()
        .filter(|(_, c)| c["text"] != "0")
        .map(|(k, _)| k.as_str())
        .collect();
    moved.sort();
    assert_eq!(moved, ["c", "x"], "{s}");
}

#[test]
fn an_output_that_is_an_input_changes_nothing() {
    // x1' = u x2, x2' = 0, param p, y = x1: y' = u x2 gives x2; p is in nothing:
    // rank 2 of 3, p unobservable. Adding the output y2 = u measures u: by the derivation
    // in obsan-model's measured.rs the codistribution over (x1, x2, p) is the same.
    let base = "system same\nstate x1, x2\nparam p\ninput u\nx1' = u*x2\nx2' = 0\noutput y = x1\n";
    let f = temp_file("same.sys", base);
    let g = temp_file("same_u.sys", &format!("{base}output y2 = u\n"));
    let (a, b) = (rank(&f, &[]), rank(&g, &[]));
    for v in [&a, &b] {
        assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(2), Some(3)));
        assert_eq!(v["unobservable_variables"], json!(["p"]));
        assert_eq!(v["state"], json!(["x1", "x2", "p"]));
    }
    assert_eq!(a["measured_inputs"], json!([]));
    assert_eq!(b["measured_inputs"], json!(["u"]));
}

#[test]
fn a_restriction_comes_first_then_the_inputs_it_leaves_are_measured() {
    // `hold: u = 1`: y = x + c, x' = 1: only x + c is seen (rank 1 of 2) and no input is
    // read. `double: u = 2 v`: y = x + 2 c v, x' = 2 v: as the first test over v, rank 2.
    let f = temp_file(
        "restricted.sys",
        &format!("{OFFSET}restrict hold: u = 1\nrestrict double: u = 2*v\n"),
    );
    let h = rank(&f, &["--input", "hold"]);
    assert_eq!((h["rank"].as_u64(), h["n"].as_u64()), (Some(1), Some(2)));
    assert_eq!(h["measured_inputs"], json!([]));
    let d = rank(&f, &["--input", "double"]);
    assert_eq!((d["rank"].as_u64(), d["n"].as_u64()), (Some(2), Some(2)));
    assert_eq!(d["measured_inputs"], json!(["v"]));
}

#[test]
fn simulate_evaluates_the_output_at_the_input_of_its_time() {
    // x' = u, y = x + c u, c = 2, x(0) = 0. With u = t: x = t^2/2, y = t^2/2 + 2t:
    // (0, 0), (0.5, 1.125), (1, 2.5). With the table u = 1 + 2t (rows (0, 1), (1, 3)):
    // x = t + t^2, y = x + 2 u: (0, 2), (0.5, 4.75), (1, 8). RK4 is exact on these
    // polynomials of degree 2, so the values compare to 1e-12.
    let f = temp_file("offset_sim.sys", OFFSET);
    let table = temp_file("offset_u.csv", "t,u\n0,1\n1,3\n");
    let common = [
        "--until", "1", "--every", "0.5", "--set", "c=2", "--init", "x=0",
    ];
    for (drive, want) in [
        (vec!["--input", "u=t"], [0.0, 1.125, 2.5]),
        (vec!["--inputs", table.as_str()], [2.0, 4.75, 8.0]),
    ] {
        let mut args = vec!["simulate", f.as_str()];
        args.extend_from_slice(&common);
        args.extend_from_slice(&drive);
        let csv = ok(&args);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "time,x,y", "{csv}");
        for (row, w) in lines[1..].iter().zip(want) {
            let y: f64 = row.split(',').nth(2).unwrap().parse().unwrap();
            assert!((y - w).abs() < 1e-12, "{drive:?}: {row} against y = {w}");
        }
    }
}

#[test]
fn what_does_not_handle_them_refuses_at_the_input() {
    // The output `y = x + c*u` is line 6; `u` at column 18.
    let f = temp_file("offset_refused.sys", OFFSET);
    for args in [
        vec!["modes", f.as_str()],
        vec!["lie", f.as_str(), "--order", "1"],
        vec![
            "rank",
            f.as_str(),
            "--experiment",
            "a: ",
            "--experiment",
            "b: ",
        ],
    ] {
        let e = bad(&args, ":6:18: an output reads the known input 'u'");
        assert!(
            e.contains("does not handle outputs that read known inputs"),
            "{e}"
        );
    }
    // `verify` reads the system its decomposition names.
    let dec = f.replace("offset_refused.sys", "offset_refused.dec");
    std::fs::write(
        &dec,
        "system offset_refused.sys\nstate x, c\noutput y = x + c*u\n",
    )
    .unwrap();
    bad(
        &["verify", &dec],
        ":6:18: an output reads the known input 'u': `obsan verify` does not handle",
    );
    // Combinations refused by the model itself.
    let d = temp_file("offset_delay.sys", &format!("{OFFSET}delay c\n"));
    bad(
        &["rank", &d],
        ":6:18: an output reads the known input 'u': a model with `delay`",
    );
    let w = temp_file(
        "offset_unknown.sys",
        "system w\nstate x\nparam c\ninput u\nunknown input w\nx' = u + w\noutput y = x + c*u\n",
    );
    bad(
        &["rank", &w],
        ":7:18: an output reads the known input 'u': a model with unknown inputs",
    );
}
