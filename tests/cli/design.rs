//! `obsan design` (docs/experiments.md, "Which sensor, which trajectory"):
//! the expected sets and families are derived by hand here, from the models'
//! equations and symmetries, never from obsan's output.

use crate::util::*;
use serde_json::Value;

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    serde_json::from_str(&ok(&a)).expect("json output")
}

fn sets(v: &Value) -> Vec<Vec<String>> {
    v["sensors"]["sets"]
        .as_array()
        .expect("sets")
        .iter()
        .map(|s| {
            s["candidates"]
                .as_array()
                .expect("candidates")
                .iter()
                .map(|c| c.as_str().expect("name").to_string())
                .collect()
        })
        .collect()
}

fn names(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

// vins.sys: the symmetries (Martinelli 2012; Hesch et al. 2014) are the
// translations T_x, T_y, T_z (moving r and pf together) and the yaw rotation
// R_z (about the vertical through pf: it moves rx, ry, v, q, not rz or pf).
// A remaining direction is a w = a R_z + b T_x + c T_y + d T_z. Candidates
// (systems/design/vins_sensors.cand), each row of the new codistribution
// dotted with w:
//   gps (rx, ry, rz): rx gives 2a(ry - pfy) + b = 0, ry gives
//     -2a(rx - pfx) + c = 0, rz gives d = 0, and rx' = vx gives 2a vy = 0:
//     a = b = c = d = 0. Alone: everything (cost 10).
//   gps_xy (rx, ry): a = b = c = 0, T_z left (rank 18).
//   baro (rz): d = 0 only (rz and its derivatives vz, R_3.(am - ba) - g do
//     not see a yaw rotation); rank 16.
//   mag (a yaw-dependent attitude entry): a = 0; rank 16.
//   landmark (pf): b = c = d = 0 (R_z fixes pf); rank 18.
// Everything observable: {gps}; then pairs {gps_xy, baro} (cost 7),
// {mag, landmark} (cost 7), {gps_xy, landmark} (cost 11); no other pair
// ({gps_xy, mag}: T_z; {baro, mag}: T_x, T_y; {baro, landmark}: R_z), and no
// triple that is not a superset of these.
#[test]
fn vins_which_sensor_fixes_position_and_yaw() {
    let cand = "systems/design/vins_sensors.cand";
    let v = json(&["design", "systems/vins.sys", "--candidates", cand]);
    let s = &v["sensors"];
    assert_eq!(
        (s["base_rank"].as_u64(), s["n"].as_u64()),
        (Some(15), Some(19))
    );
    assert_eq!(s["all_rank"], 19);
    let ranks: Vec<u64> = s["candidates"]
        .as_array()
        .expect("candidates")
        .iter()
        .map(|c| c["rank"].as_u64().expect("rank"))
        .collect();
    assert_eq!(ranks, vec![19, 18, 16, 16, 18]);
    assert_eq!(
        sets(&v),
        vec![
            names(&["gps"]),
            names(&["gps_xy", "baro"]),
            names(&["mag", "landmark"]),
            names(&["gps_xy", "landmark"]),
        ]
    );
    for set in s["sets"].as_array().expect("sets") {
        assert_eq!(set["rank"], 19);
        assert_eq!(set["exact"], true);
    }
    // Which symmetry each breaks: the yaw rotation is the vector with a qw
    // component, the translations those moving pf.
    let syms = s["symmetries"].as_array().expect("symmetries");
    assert_eq!(syms.len(), 4);
    let moves = |w: &Value, x: &str| w[x].as_str().is_some_and(|t| t != "0");
    let yaw = syms.iter().position(|w| moves(w, "qw")).expect("yaw");
    let tz = syms
        .iter()
        .position(|w| moves(w, "pfz"))
        .expect("z translation");
    let breaks = |c: usize| -> Vec<String> {
        s["candidates"][c]["breaks"]
            .as_array()
            .expect("breaks")
            .iter()
            .map(|b| b.as_str().expect("w").to_string())
            .collect()
    };
    let w = |i: usize| format!("w{}", i + 1);
    assert_eq!(breaks(3), vec![w(yaw)], "mag breaks the yaw rotation only");
    assert_eq!(breaks(2), vec![w(tz)], "baro breaks the z translation only");
    assert!(!breaks(4).contains(&w(yaw)), "a known landmark leaves yaw");
    assert_eq!(breaks(0).len(), 4);

    // Yaw (the attitude) alone: needs a = 0 on what remains: mag (cost 2),
    // gps_xy (6), gps (10); baro and landmark never remove R_z, together
    // neither.
    let v = json(&[
        "design",
        "systems/vins.sys",
        "--candidates",
        cand,
        "--target",
        "qw,qx,qy,qz",
    ]);
    assert_eq!(
        sets(&v),
        vec![names(&["mag"]), names(&["gps_xy"]), names(&["gps"])]
    );
    // Position: R_z moves rx, ry (unless a = 0), T moves r: the same sets as
    // for everything.
    let p = json(&[
        "design",
        "systems/vins.sys",
        "--candidates",
        cand,
        "--target",
        "rx,ry,rz",
    ]);
    assert_eq!(sets(&p)[..2], [names(&["gps"]), names(&["gps_xy", "baro"])]);
    assert_eq!(sets(&p).len(), 4);
}

// calib.sys (Martinelli 2011): with free wheel speeds the system is
// observable (rank 7, section IV); on one circle (eq. 17) three directions
// are lost (Table I, rank 4 of 7); k circles give 2k states and 2 + k
// param directions (docs/experiments.md), so 3 circles: 11 of 11.
#[test]
fn calib_circles_alone_never_several_yes() {
    let v = json(&["design", "systems/calib.sys"]);
    assert!(v["sensors"].is_null());
    let f = &v["inputs"]["families"];
    assert_eq!(f[0]["restriction"], Value::Null);
    assert_eq!(f[0]["single_full"], true);
    assert_eq!(f[1]["restriction"], "q");
    assert_eq!(
        (f[1]["single_rank"].as_u64(), f[1]["single_n"].as_u64()),
        (Some(4), Some(7))
    );
    assert_eq!(f[1]["single_full"], false);
    assert_eq!(
        (f[1]["experiments"].as_u64(), f[1]["full"].as_bool()),
        (Some(3), Some(true))
    );
}

// systems/design/c2m_inputs.sys (Villaverde et al. 2019; STRIKE-GOLDD
// manual 4.3.1): x1'' + a1 x1' + a0 x1 = b k21 u + b u', a1 = k12 + k1e +
// k21, a0 = k1e k21. Constant u (u' = 0): only a1, a0, b k21, in every
// experiment alike, and y'(0) for x2: rank 3 + 3 = 6 of 7, never full. A
// ramp (u' = c known): b k21 from the t term and b c from the constant, so b,
// k21, k1e, k12 and x2: 7 of 7 from one experiment. Free: the same.
#[test]
fn two_compartment_needs_a_ramp() {
    let v = json(&["design", "systems/design/c2m_inputs.sys"]);
    let f = v["inputs"]["families"].as_array().expect("families");
    let by = |r: &str| {
        f.iter()
            .find(|x| x["restriction"] == r)
            .expect("family")
            .clone()
    };
    let c = by("constant");
    assert_eq!(
        (c["single_rank"].as_u64(), c["single_n"].as_u64()),
        (Some(6), Some(7))
    );
    assert_eq!(c["full"], false, "no number of constant inputs");
    assert_eq!(by("ramp")["single_full"], true);
    assert_eq!(f[0]["single_full"], true);
}

// Two families each seeing one param: x' = a u1 + b u2, y = x. Only u1
// (u2 = 0): y' = a u1 shows a; however many such experiments, never b (each
// adds its own x@k: rank k + 1 of k + 2). One experiment of each: x@1, x@2,
// a, b all seen: the one minimal combination.
#[test]
fn families_combined() {
    let m = temp_file(
        "two_families.sys",
        "system two\nstate x\nparam a, b\ninput u1, u2\nx' = a*u1 + b*u2\noutput y = x\nrestrict only1: u2 = 0\nrestrict only2: u1 = 0\n",
    );
    let v = json(&["design", &m]);
    let i = &v["inputs"];
    assert_eq!(i["families"][1]["full"], false);
    assert_eq!(i["families"][2]["full"], false);
    let c = i["combinations"].as_array().expect("combinations");
    assert_eq!(c.len(), 1);
    assert_eq!(c[0]["families"], serde_json::json!(["only1", "only2"]));
    assert_eq!(
        (c[0]["rank"].as_u64(), c[0]["n"].as_u64()),
        (Some(4), Some(4))
    );
}

#[test]
fn design_errors_name_the_place() {
    let m = "systems/vins.sys";
    let f = temp_file(
        "bad.cand",
        "candidate gps cost 10\noutput gx = rx +\n  nosuch\n",
    );
    let e = bad(&["design", m, "--candidates", &f], "bad.cand:3");
    assert!(e.contains("nosuch"), "{e}");
    let f = temp_file("state.cand", "candidate x\nstate s\n");
    bad(&["design", m, "--candidates", &f], "state.cand:2");
    let f = temp_file("orphan.cand", "output gx = rx\n");
    bad(&["design", m, "--candidates", &f], "orphan.cand:1");
    let f = temp_file("cost.cand", "candidate gps cost -1\noutput gx = rx\n");
    bad(&["design", m, "--candidates", &f], "cost.cand:1");
    let f = temp_file("dup.cand", "candidate gps\noutput u1 = rx\n");
    bad(&["design", m, "--candidates", &f], "dup.cand:2");
    let f = temp_file("ok.cand", "candidate gps\noutput gx = rx\n");
    bad(
        &["design", m, "--candidates", &f, "--target", "nosuch"],
        "--target nosuch",
    );
    bad(&["design", m], "no `restrict` statements");
}
