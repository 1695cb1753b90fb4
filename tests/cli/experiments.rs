//! Several experiments and known initial conditions from the command line
//! (docs/experiments.md); expected values from the paper and derivations
//! written here.

use crate::util::*;
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    serde_json::from_str(&ok(&a)).expect("json output")
}

// Paper, Table I / section V: a circle (eq. 17) keeps 4 modes of 7 (A_q,
// V_q, xi_q, L_q); k circles: 2k states fixed by A_q, V_q, and the params
// get xi_q (all in span{d xi, d(xi delta)}) and L_q: 2 + 2 + 1 = 5 only with
// three circles. So 4 of 7, 8 of 9, 11 of 11 (the paper's q = 0.9, 0, -1).
#[test]
fn three_circles_from_flags_and_from_a_file() {
    let v = json(&[
        "rank",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
        "--experiment",
        "q: q=-1",
    ]);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(11), Some(11)));
    assert_eq!(v["experiments"][0]["restriction"], "q");
    assert_eq!(v["experiments"][0]["set"]["q"], "9/10");
    assert_eq!(v["state"][0], "mu@1");
    let f = temp_file(
        "circles.exp",
        "# the paper's three circles (section VI-A)\nq: q=0.9\nq: q=0\n\nq: q=-1  # turning\n",
    );
    let w = json(&["rank", "systems/calib.sys", "--experiments", &f]);
    assert_eq!(w["rank"], v["rank"]);
    let two = json(&[
        "rank",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
    ]);
    assert_eq!(
        (two["rank"].as_u64(), two["n"].as_u64()),
        (Some(8), Some(9))
    );
    // Two distinct xi_q = xi - q (xi delta) give xi and delta themselves.
    let obs: Vec<&str> = two["observable_variables"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap())
        .collect();
    assert_eq!(obs, vec!["delta", "xi"]);
}

#[test]
fn auto_designs_the_papers_experiment() {
    let v = json(&[
        "rank",
        "systems/calib.sys",
        "--input",
        "q",
        "--experiments",
        "auto",
    ]);
    assert_eq!(v["experiments"], 3);
    assert_eq!((v["rank"].as_u64(), v["n"].as_u64()), (Some(11), Some(11)));
    let ranks: Vec<u64> = v["ranks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["rank"].as_u64().unwrap())
        .collect();
    assert_eq!(&ranks[..3], &[4, 8, 11]);
    assert_eq!(v["state_rank"], 2);
    // q = 1 and q = -1 would be a straight line / turning in place only if
    // delta = rL/rR were 1; delta is unknown, so no rational q degenerates.
    for s in v["special_values"].as_array().unwrap() {
        assert_eq!(s["degenerate"], false, "{s}");
    }
}

// S' = 1 + a S^2, y = S, S(0) = 0 (strike-goldd issue 7): y'''(0) = 2a
// (y'' = 2aS(1 + aS^2), so y''' = 2a(1 + aS^2)^2 + 4a^2 S^2 (...) = 2a at 0).
#[test]
fn known_zero_initial_state_keeps_a_identifiable() {
    let f = temp_file(
        "riccati.sys",
        "system riccati\nstate S\nparam a\nS' = 1 + a*S^2\noutput y = S\n",
    );
    let v = json(&["rank", &f, "--known", "S=0"]);
    assert_eq!(v["unknowns"], serde_json::json!(["a"]));
    assert_eq!(v["identifiable"], true);
    assert_eq!(v["point_rank"], 1);
    assert_eq!(v["order_checked"], 3);
    assert_eq!(v["basis"][0]["order"], 3);
    let text = ok(&["rank", &f, "--known", "S=0"]);
    assert!(text.contains("identifiable, proven"), "{text}");
}

// Two compartments, no input, started empty: x = 0 for ever, y = 0, and
// every Lie derivative is linear in x so its gradient in the rates is 0 there.
#[test]
fn empty_compartments_lose_every_rate() {
    let f = temp_file(
        "c2_empty.sys",
        "system c2\nstate x1, x2\nparam k01, k02, k12, k21\n\
         x1' = -(k01 + k21)*x1 + k12*x2\nx2' = k21*x1 - (k02 + k12)*x2\noutput y = x1\n",
    );
    let v = json(&["rank", &f, "--known", "x1=0", "--known", "x2=0"]);
    assert_eq!(v["rank"], 0);
    assert_eq!(v["n"], 4);
    assert_eq!(v["invariant"], true);
    assert_eq!(v["determined"], true);
    // Known but generic: s_k = e1' A^k x0 obey A's order-2 recurrence, so
    // y^(k)(0) are functions of (tr A, det A, a11 x1 + a12 x2): rank 3 of 4.
    let g = json(&["rank", &f, "--known-generic", "x1,x2"]);
    assert_eq!((g["rank"].as_u64(), g["n"].as_u64()), (Some(3), Some(4)));
}

#[test]
fn stacked_symmetries_keep_delta_and_xi_fixed() {
    // Two circles: 9 - 8 = 1 symmetry, and it cannot move delta or xi (both
    // identifiable, see three_circles_from_flags_and_from_a_file).
    let v = json(&[
        "symmetries",
        "systems/calib.sys",
        "--experiment",
        "q: q=0.9",
        "--experiment",
        "q: q=0",
    ]);
    let syms = v["symmetries"].as_array().unwrap();
    assert_eq!(syms.len(), 1);
    assert_eq!(syms[0]["delta"]["text"], "0");
    assert_eq!(syms[0]["xi"]["text"], "0");
}

#[test]
fn bad_experiment_input_is_a_clear_error() {
    bad(
        &["rank", "systems/calib.sys", "--experiment", "q: q"],
        "expected NAME=VALUE",
    );
    bad(
        &["rank", "systems/calib.sys", "--experiment", "nope: q=1"],
        "no restriction named 'nope'",
    );
    let f = temp_file("bad.exp", "q: q=0.9\nq: q=zz\n");
    bad(
        &["rank", "systems/calib.sys", "--experiments", &f],
        "bad.exp:2",
    );
    bad(
        &["symmetries", "systems/calib.sys", "--experiments", "auto"],
        "obsan rank",
    );
    bad(
        &["rank", "systems/calib.sys", "--known", "nosuch=0"],
        "not a state or param",
    );
    bad(
        &["rank", "systems/calib.sys", "--known", "gamma=0"],
        "--known-generic gamma",
    );
    bad(
        &[
            "rank",
            "systems/calib.sys",
            "--input",
            "q",
            "--experiment",
            "q: q=1",
        ],
        "cannot be used with",
    );
}

// Observability along data (docs/experiments.md, "Observability along data").

fn along(args: &[&str]) -> Value {
    let mut a = vec!["rank"];
    a.extend_from_slice(args);
    json(&a)
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_str().unwrap().to_string())
        .collect()
}

// The paper's calibration data (section VI-A) with noise-free encoders and a
// varying speed, so that every window's inputs are exactly the circle of
// eq. 17, wL = q wR. Table I: a circle keeps 4 of the 7 variables' modes, so
// every window has rank 4 and loses the 3 symmetries of calib.sys on circles;
// the three circles together fix everything: 2 modes per circle's own start
// (A_q, V_q) and the 5 params (derived beside `three_circles_from_flags_and_
// from_a_file` above), 11 of 11.
#[test]
fn paper_circles_lose_the_three_circle_symmetries() {
    let d = format!("{}/data", fresh_dir("along-circles"));
    ok(&[
        "simulate",
        "--out",
        &d,
        "--force",
        "--k",
        "0",
        "--speed-profile",
        "sine:0.5:20",
    ]);
    let v = along(&["systems/calib.sys", "--along", &d, "--window", "30"]);
    assert_eq!(v["n"], 7);
    let wins = v["windows"].as_array().unwrap();
    assert!(wins.len() >= 3);
    for w in wins {
        assert_eq!(w["rank"], 4, "window {w}");
        let rel = strings(&w["input_relations"]);
        // Eq. 17: wL = q wR, q from the trajectory's name (q0.9, q0, q-1).
        let expect = match w["trajectory"].as_str().unwrap() {
            "q0" => "wL = 0".to_string(),
            "q-1" => "wL = -wR".to_string(),
            name => format!("wL = {}*wR", &name[1..]),
        };
        assert_eq!(rel, vec![expect], "window {w}");
    }
    let st = v["stretches"].as_array().unwrap();
    // One stretch per circle: every window of a trajectory has the same
    // rank and relations.
    assert_eq!(st.len(), 3);
    for s in st {
        assert_eq!(s["lost"].as_array().unwrap().len(), 3);
        assert_eq!(s["symmetry"]["restricted_rank"], 4);
        assert_eq!(s["symmetry"]["vectors"].as_array().unwrap().len(), 3);
        assert_eq!(s["symmetry"]["matches"], true, "{s}");
    }
    // On q = 0 (wL = 0) eq. 16 has no delta (it multiplies wL only): d/d delta
    // itself is lost, a row of the reduced echelon basis (state order: mu,
    // gamma, phi, psi, eta, delta, xi).
    let q0 = st.iter().find(|s| s["trajectory"] == "q0").unwrap();
    let e_delta: Vec<f64> = vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    assert!(q0["lost"]
        .as_array()
        .unwrap()
        .iter()
        .any(|r| serde_json::from_value::<Vec<f64>>(r.clone()).unwrap() == e_delta));
    assert_eq!(v["dataset"]["n"], 11);
    assert_eq!(v["dataset"]["rank"], 11);
}

// A hand-built dataset of calib.sys: 20 s straight (wR = wL = 2 rad/s) then
// 20 s standing still, one bearing a second. Eq. 16 has no drift, so at a
// standstill the state stands still and every row is the one gradient of
// beta: rank 1 of 7, six directions lost, exactly the symmetries of the model
// with no motion. Equal wheel speeds (a straight line when the radii are
// equal) are the circle q = 1 of eq. 17, an ordinary circle (`--experiments
// auto` finds q = 1 not special: delta is unknown): rank 4, the three circle
// symmetries lost.
#[test]
fn hand_built_straight_line_and_standstill() {
    let d = fresh_dir("along-line-stop");
    let tr = format!("{d}/line_stop");
    std::fs::create_dir_all(&tr).unwrap();
    let mut inputs = String::from("t,wR,wL\n");
    for k in 0..2000 {
        let t = k as f64 * 0.02;
        let w = if t < 20.0 { 2.0 } else { 0.0 };
        inputs.push_str(&format!("{t},{w},{w}\n"));
    }
    let mut outputs = String::from("t,beta\n");
    for k in 0..40 {
        outputs.push_str(&format!("{k},0.5\n"));
    }
    std::fs::write(format!("{tr}/inputs.csv"), inputs).unwrap();
    std::fs::write(format!("{tr}/outputs.csv"), outputs).unwrap();
    std::fs::write(format!("{tr}/meta.json"), "{\"q\": 1}").unwrap();
    std::fs::write(
        format!("{d}/truth.json"),
        r#"{"phi": 0.1, "psi": 1.5, "eta": 0.5, "delta": 1.02, "xi": 0.6,
            "trajectories": [{"name": "line_stop", "mu0": 0.25, "gamma0": 1.2}]}"#,
    )
    .unwrap();
    let v = along(&["systems/calib.sys", "--along", &d, "--window", "10"]);
    let st = v["stretches"].as_array().unwrap();
    assert_eq!(st.len(), 2, "{st:?}");
    let (line, stop) = (&st[0], &st[1]);
    assert_eq!(
        (line["t0"].as_f64(), line["t1"].as_f64()),
        (Some(0.0), Some(20.0))
    );
    assert_eq!(line["rank"], 4);
    assert_eq!(
        strings(&line["input_relations"]),
        vec!["wL = 2".to_string(), "wR = 2".to_string()]
    );
    assert_eq!(line["symmetry"]["matches"], true, "{line}");
    assert_eq!(
        (stop["t0"].as_f64(), stop["rank"].as_u64()),
        (Some(20.0), Some(1))
    );
    assert_eq!(
        strings(&stop["input_relations"]),
        vec!["wL = 0".to_string(), "wR = 0".to_string()]
    );
    assert_eq!(stop["lost"].as_array().unwrap().len(), 6);
    assert_eq!(stop["symmetry"]["matches"], true, "{stop}");
}

// An MRCLAM robot (CI=true: the data must be there): the windows whose
// odometry is all zero must come out as standstills (relations v = 0 and
// omega = 0), those with omega all zero and some v as straight lines (omega
// = 0, and no v = 0), read here from the imported inputs.csv; 2 s windows,
// as the robots rarely hold still or straight for 10 s. At a standstill the
// state does not move, so each measured output column gives one row:
// the rank is at most the number of distinct outputs measured.
#[test]
fn mrclam_straight_lines_and_standstills_where_the_odometry_says() {
    let Some(src) = mrclam_dir() else { return };
    let d = format!("{}/data", fresh_dir("along-mrclam1"));
    ok(&[
        "import",
        "mrclam",
        &src,
        "--robot",
        "1",
        "--out",
        &d,
        "--force",
        "--max-windows",
        "6",
    ]);
    let v = along(&["systems/mrclam.sys", "--along", &d, "--window", "2"]);
    let wins = v["windows"].as_array().unwrap();
    let (mut stills, mut lines) = (0, 0);
    for w in wins {
        let name = w["trajectory"].as_str().unwrap();
        let (t0, t1) = (w["t0"].as_f64().unwrap(), w["t1"].as_f64().unwrap());
        let text = std::fs::read_to_string(format!("{d}/{name}/inputs.csv")).unwrap();
        let rows: Vec<(f64, f64, f64)> = text
            .lines()
            .skip(1)
            .map(|l| {
                let f: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                (f[0], f[1], f[2])
            })
            .collect();
        // Samples active in [t0, t1): from the last one at or before t0.
        let first = rows.iter().rposition(|r| r.0 <= t0).unwrap();
        let active: Vec<_> = rows[first..].iter().filter(|r| r.0 < t1).collect();
        let still = active.iter().all(|r| r.1 == 0.0 && r.2 == 0.0);
        let line = !still && active.iter().all(|r| r.2 == 0.0);
        let rel = strings(&w["input_relations"]);
        if still {
            stills += 1;
            assert_eq!(
                rel,
                vec!["omega = 0".to_string(), "v = 0".to_string()],
                "{w}"
            );
            let out = std::fs::read_to_string(format!("{d}/{name}/outputs.csv")).unwrap();
            let mut seen = std::collections::BTreeSet::new();
            for l in out.lines().skip(1) {
                let f: Vec<&str> = l.split(',').collect();
                let t: f64 = f[0].parse().unwrap();
                if t >= t0 && t < t1 {
                    seen.extend((1..f.len()).filter(|&i| !f[i].is_empty()));
                }
            }
            assert!(
                w["rank"].as_u64().unwrap() as usize <= seen.len().min(3),
                "{w}"
            );
        } else if line {
            // Straight: omega = 0, and v free (or constant, a second relation).
            lines += 1;
            assert!(rel.iter().any(|r| r == "omega = 0"), "{w}");
            assert!(!rel.iter().any(|r| r == "v = 0"), "{w}");
        } else {
            assert!(!rel.iter().any(|r| r == "omega = 0"), "{w}");
        }
    }
    assert!(
        stills > 0 && lines > 0,
        "{stills} standstills, {lines} straight lines"
    );
}
