//! MRCLAM robots 2 and 3 diagnosed from their landmarks and from their Vicon
//! poses (issue 37.7; robot 1: `diagnose::mrclam_robot_1_...`). The rule:
//! every param that either side names agrees within three combined
//! cluster-robust sds with the other side's estimate (named, or fitted in
//! its last round), except where the two sides carry one effect in two
//! forms; those are compared through what both forms fix:
//!
//! - A lag or delay: the lag each input channel sees. A first-order lag of
//!   time constant T has an impulse response whose first moment is T, a
//!   delay tau's is tau, and a cascade's first moment is the sum of its
//!   parts'; so a channel's effective lag is the sum of the named lag and
//!   delay params acting on it (`actuator_lag`'s T and `time_offset`'s tau
//!   on both channels, a generated `u_lag*`/`u_delay*` on its input `u`).
//! - The forward speed's scale and its coupling with |omega|: the speed
//!   actually driven is `v (1 + kv)(1 + c |omega|)`, whose distance over the
//!   data is, to first order, `(1 + kv + c m)` times the commanded one, `m`
//!   the distance-weighted mean of |omega| (computed here from the
//!   dataset's inputs). `kv + m c` is what both forms fix; a side that
//!   named neither fitted each alone in its last round, and each alone then
//!   estimates that combination.
//!
//! Where the cross terms of a side's two params are unknown (different
//! fits, or no `combinations` entry) their sds add (the triangle
//! inequality: an upper bound). A disagreement that remains is asserted as
//! a known difference with its reason, so a fix shows as a failure here.
//! Params fitted on both sides but named by neither are printed, not
//! asserted: last-round fits on different base models (docs/diagnose.md).

use crate::diagnose::{along, combinations, diagnose_json, estimate, named, tmp_dir};
use crate::util::*;

/// The Vicon-side and landmark-side diagnoses of robot `r` (default
/// options), and the distance-weighted mean |omega| of its windows; `None`
/// when the MRCLAM data are absent (skipped with a message).
fn both_sides(r: &str) -> Option<(serde_json::Value, serde_json::Value, f64)> {
    let src = mrclam_dir()?;
    let lm = tmp_dir(&format!("mrclam{r}"));
    let out = ok(&["import", "mrclam", &src, "--robot", r, "--out", &lm]);
    assert!(out.contains("windows"), "{out}");
    let poses = tmp_dir(&format!("mrclam{r}-poses"));
    let args = ["import", "mrclam", &src, "--robot", r, "--out", &poses];
    let out = ok(&[&args[..], &["--vicon-poses"]].concat());
    assert!(out.contains("Vicon poses"), "{out}");
    let a = diagnose_json("systems/mrclam.sys", &lm, &[]);
    let b = diagnose_json("systems/mrclam-pose.sys", &poses, &[]);
    let m = mean_abs_omega(&lm);
    let _ = std::fs::remove_dir_all(&lm);
    let _ = std::fs::remove_dir_all(&poses);
    Some((a, b, m))
}

/// `sum |v| |omega| dt / sum |v| dt` over every window's inputs.csv (`t,v,omega`).
pub(crate) fn mean_abs_omega(dir: &str) -> f64 {
    let (mut d, mut dw) = (0.0, 0.0);
    let mut windows: Vec<_> = std::fs::read_dir(dir).unwrap().flatten().collect();
    windows.sort_by_key(|e| e.file_name());
    for w in windows.iter().filter(|w| w.path().is_dir()) {
        let text = std::fs::read_to_string(w.path().join("inputs.csv")).unwrap();
        let rows: Vec<[f64; 3]> = text
            .lines()
            .skip(1)
            .map(|l| {
                let x: Vec<f64> = l.split(',').map(|c| c.trim().parse().unwrap()).collect();
                [x[0], x[1], x[2]]
            })
            .collect();
        for p in rows.windows(2) {
            let dt = p[1][0] - p[0][0];
            d += p[0][1].abs() * dt;
            dw += p[0][1].abs() * p[0][2].abs() * dt;
        }
    }
    assert!(d > 0.0, "{dir}: no distance");
    dw / d
}

/// A param's estimate and robust sd among the named effects only.
fn named_estimate(j: &serde_json::Value, param: &str) -> Option<(f64, f64)> {
    j["named"].as_array()?.iter().find_map(|n| {
        let est = n["estimates"].as_array()?;
        let i = est.iter().position(|e| e[0].as_str() == Some(param))?;
        Some((est[i][1].as_f64()?, n["robust_sd"][i].as_f64()?))
    })
}

fn z((x, sx): (f64, f64), (y, sy): (f64, f64)) -> f64 {
    (x - y).abs() / (sx * sx + sy * sy).sqrt()
}

/// The lag the input `channel` (`v` or `omega`) sees in a side's final
/// model: the sum of its named lag and delay params acting on it, their
/// sds added. A side that named none for the channel: each lag or delay
/// param acting on it fitted alone in its last round (each alone then
/// estimates the channel's lag), else 0 (no lag in any of its fits).
fn channel_lag(j: &serde_json::Value, channel: &str) -> Vec<(f64, f64)> {
    let params = [
        "T".to_string(),
        "tau".to_string(),
        format!("gT_{channel}"),
        format!("gtau_{channel}"),
        "gtau_inputs".to_string(),
    ];
    let named: Vec<(f64, f64)> = params.iter().filter_map(|p| named_estimate(j, p)).collect();
    if !named.is_empty() {
        return vec![named.iter().fold((0.0, 0.0), |a, x| (a.0 + x.0, a.1 + x.1))];
    }
    let fitted: Vec<(f64, f64)> = params.iter().filter_map(|p| estimate(j, p)).collect();
    if fitted.is_empty() {
        return vec![(0.0, 0.0)];
    }
    fitted
}

/// An estimate and its robust sd.
type Sd = (f64, f64);

/// Every pair of one side's alternatives and the other's, with its z.
fn pairs(x: &[Sd], y: &[Sd]) -> Vec<(Sd, Sd, f64)> {
    x.iter()
        .flat_map(|&a| y.iter().map(move |&b| (a, b, z(a, b))))
        .collect()
}

/// `kv + m gc_v_omega` from one side: from its named params (the other 0
/// in its model), else each param fitted alone in its last round.
fn speed_factor(j: &serde_json::Value, m: f64) -> Vec<(f64, f64)> {
    let (kv, c) = (named_estimate(j, "kv"), named_estimate(j, "gc_v_omega"));
    if kv.is_some() || c.is_some() {
        let (kv, c) = (kv.unwrap_or((0.0, 0.0)), c.unwrap_or((0.0, 0.0)));
        return vec![(kv.0 + m * c.0, kv.1 + m * c.1)];
    }
    let kv = estimate(j, "kv");
    let c = estimate(j, "gc_v_omega").map(|(x, s)| (m * x, m * s));
    kv.into_iter().chain(c).collect()
}

const LAGS: [&str; 7] = [
    "T",
    "tau",
    "gT_v",
    "gT_omega",
    "gtau_v",
    "gtau_omega",
    "gtau_inputs",
];
const SPEED: [&str; 2] = ["kv", "gc_v_omega"];
const ODOMETRY: [&str; 9] = [
    "kv",
    "kw",
    "bw",
    "gc_v_omega",
    "gc_omega_v",
    "gd_v",
    "gd_omega",
    "gb_v",
    "gb_omega",
];

/// Every odometry param either side names, outside the lag and speed
/// forms, agrees with the other side's estimate; returns how many were
/// compared. Params fitted on both sides, named by neither, are printed.
fn named_agree(a: &serde_json::Value, b: &serde_json::Value, robot: &str) -> usize {
    let paired: Vec<[String; 2]> = combinations(a)
        .into_iter()
        .chain(combinations(b))
        .map(|c| c.0)
        .collect();
    let mut compared = 0;
    for p in ODOMETRY.iter().chain(&LAGS) {
        let (Some(x), Some(y)) = (estimate(a, p), estimate(b, p)) else {
            continue;
        };
        let either = named_estimate(a, p).is_some() || named_estimate(b, p).is_some();
        let both = named_estimate(a, p).is_some() && named_estimate(b, p).is_some();
        let form = LAGS.contains(p) || (SPEED.contains(p) && !both);
        let in_pair = paired.iter().any(|q| q.iter().any(|x| x == p));
        if !either || form || in_pair {
            eprintln!(
                "robot {robot} {p}: landmarks {x:?}, poses {y:?}, z {:.1} (not asserted: {})",
                z(x, y),
                if !either {
                    "named by neither"
                } else if form {
                    "compared as a form"
                } else {
                    "in a combination"
                }
            );
            continue;
        }
        assert!(
            x.1 > 0.0 && y.1 > 0.0,
            "robot {robot} {p}: robust sds {x:?} {y:?}"
        );
        assert!(
            z(x, y) < 3.0,
            "robot {robot} {p}: landmarks {x:?}, poses {y:?}: z {}",
            z(x, y)
        );
        compared += 1;
    }
    for (pair, w, ..) in combinations(a).into_iter().chain(combinations(b)) {
        if !pair.iter().all(|p| ODOMETRY.contains(&p.as_str())) {
            continue;
        }
        let (Some(x), Some(y)) = (along(a, &pair, w), along(b, &pair, w)) else {
            continue;
        };
        let zz = z(x, y);
        assert!(
            zz < 3.0,
            "robot {robot} {pair:?} w {w}: landmarks {x:?}, poses {y:?}: z {zz}"
        );
        compared += 1;
    }
    compared
}

/// The speed factor and the turn-rate lag agree, every alternative of a
/// side against every one of the other's (robot 1 too: `diagnose.rs`).
pub(crate) fn forms_agree(a: &serde_json::Value, b: &serde_json::Value, m: f64, robot: &str) {
    for (x, y, z) in pairs(&speed_factor(a, m), &speed_factor(b, m)) {
        assert!(
            z < 3.0,
            "robot {robot} kv + {m} gc_v_omega: landmarks {x:?}, poses {y:?}: z {z}"
        );
    }
    for (x, y, z) in pairs(&channel_lag(a, "omega"), &channel_lag(b, "omega")) {
        assert!(
            z < 3.0,
            "robot {robot} turn-rate lag: landmarks {x:?}, poses {y:?}: z {z}"
        );
    }
}

/// Robot 2: the landmarks name `actuator_lag` (T lags both channels), the
/// poses `omega_lag*` (the turn rate alone) and, fitting T on top of it,
/// find no common lag (T 0.02 ± 0.08 s). The turn-rate lag agrees; the
/// forward speed's does not: a known difference, the landmarks' v lag is
/// the form's (their one lag candidate that fits lags both channels), while
/// the poses, which see the distance driven directly, give it none.
#[test]
fn mrclam_robot_2_landmarks_agree_with_the_vicon_poses() {
    let Some((a, b, m)) = both_sides("2") else {
        return;
    };
    eprintln!(
        "robot 2 named: landmarks {:?}, poses {:?}",
        named(&a),
        named(&b)
    );
    assert!(named_agree(&a, &b, "2") >= 3);
    forms_agree(&a, &b, m, "2");
    let v = pairs(&channel_lag(&a, "v"), &channel_lag(&b, "v"));
    assert!(
        v.iter().all(|p| p.2 > 3.0),
        "the forward speed's lag now agrees ({v:?}): \
         the known difference is gone, update docs/diagnose.md and this test"
    );
}

/// Robot 3: the poses name speed_scale and v_with_abs_omega*, the
/// landmarks neither (both suggested): alone each absorbs the other, so
/// kv (z 6.5) and gc_v_omega (z 4.5) differ one by one while `kv + m c`,
/// the distance factor both fix, agrees.
#[test]
fn mrclam_robot_3_landmarks_agree_with_the_vicon_poses() {
    let Some((a, b, m)) = both_sides("3") else {
        return;
    };
    eprintln!(
        "robot 3 named: landmarks {:?}, poses {:?}",
        named(&a),
        named(&b)
    );
    assert!(named_agree(&a, &b, "3") >= 2);
    forms_agree(&a, &b, m, "3");
    for (x, y, z) in pairs(&channel_lag(&a, "v"), &channel_lag(&b, "v")) {
        assert!(z < 3.0, "robot 3 forward-speed lag: {x:?} {y:?}: z {z}");
    }
}
