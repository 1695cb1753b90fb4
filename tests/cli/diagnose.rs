use crate::util::*;

pub(crate) fn tmp_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-diag-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d.to_string_lossy().into_owned()
}

/// `obsan diagnose --model systems/calib.sys --data DATA` plus `extra`.
fn diag(data: &str, extra: &[&str]) -> Vec<String> {
    let mut a: Vec<String> = ["diagnose", "--model", "systems/calib.sys", "--data", data]
        .iter()
        .map(|x| x.to_string())
        .collect();
    a.extend(extra.iter().map(|x| x.to_string()));
    a
}

fn refs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

#[test]
fn diagnose_names_a_hidden_distortion_and_writes_the_report() {
    let data = tmp_dir("dist");
    let report = tmp_dir("dist-report");
    ok(&[
        "simulate",
        "--out",
        &data,
        "--seed",
        "4",
        "--effect",
        "bearing_distortion=0.06",
    ]);
    let out = ok(&[
        "diagnose",
        "--model",
        "systems/calib.sys",
        "--data",
        &data,
        "--report",
        &report,
    ]);
    assert!(out.contains("named: bearing_distortion: a2 = "), "{out}");
    // Failure 8 of the never-confidently-wrong rules: the verdict leads,
    // on the line after the header, naming the effect with its estimate.
    let second = out.lines().nth(1).unwrap_or("");
    assert!(
        second.starts_with("verdict: named bearing_distortion (a2 = "),
        "{out}"
    );
    // With its unit: a2 multiplies sin(2 beta), a pure number, and is
    // added to beta = atan2(...) - psi, an angle: rad, also shown in deg
    // (x rad = 180 x / pi deg, to 3 significant digits).
    let rest = &second["verdict: named bearing_distortion (a2 = ".len()..];
    let words: Vec<&str> = rest.split_whitespace().collect();
    assert_eq!((words[1], words[3]), ("±", "rad"), "{second}");
    let a2: f64 = words[0].parse().unwrap();
    let deg: f64 = words[4].trim_start_matches('(').parse().unwrap();
    assert_eq!(words[5], "deg)", "{second}");
    assert!(
        (deg - a2.to_degrees()).abs() <= 0.005 * deg.abs(),
        "{second}"
    );
    assert!(out.contains("bearing_bias: absorbed by psi"), "{out}");
    for f in [
        "report.md",
        "extended.sys",
        "diagnosis.json",
        "residuals_beta.svg",
        "residuals_beta_vs_beta.png",
        "residuals_beta_vs_wR.svg",
        "candidates.svg",
        "fit_0_beta.svg",
    ] {
        assert!(
            std::path::Path::new(&format!("{report}/{f}")).exists(),
            "{f} missing"
        );
    }
    // The report reads as a paper's section: the verdict first, then the
    // estimates (the effect's param new in the extended model) and the RMS
    // before and after, with the pooled residuals per output.
    let md = std::fs::read_to_string(format!("{report}/report.md")).unwrap();
    let body: Vec<&str> = md.lines().filter(|l| !l.trim().is_empty()).collect();
    assert!(
        body[1].starts_with("verdict: named bearing_distortion"),
        "{md}"
    );
    assert!(md.contains("| a2 | (not in the model) | 0.0"), "{md}");
    let a2_row = md.lines().find(|l| l.starts_with("| a2 |")).unwrap();
    assert!(a2_row.ends_with("| rad |"), "{a2_row}");
    let rms = md
        .lines()
        .find(|l| l.starts_with("| beta |"))
        .expect("an RMS row for beta");
    assert!(rms.ends_with("% |") && rms.contains("| -"), "{rms}");
    // Pooled: one legend entry per fit, none per trajectory (the simulated
    // trajectories are q0.9, q0, q-1).
    let svg = std::fs::read_to_string(format!("{report}/residuals_beta.svg")).unwrap();
    assert!(
        !svg.contains(">q0.9<") && svg.contains(">with effects<"),
        "{svg:.400}"
    );
    // The extended model is a valid system that the analysis reads: one more param.
    let ext = format!("{report}/extended.sys");
    let r = ok(&["rank", &ext, "--input", "q"]);
    assert!(
        r.contains("state [mu, gamma, phi, psi, eta, delta, xi, a2]"),
        "{r}"
    );
    // JSON: the named effect with its estimate and sd (truth 0.06), and
    // each estimate's unit. The wheel speeds declared in rad/s (calib.eff
    // with one more line), the generated coupling wR (1 + c |wL|) has c in
    // s/rad (c |wL| a pure number) and the drift wR (1 + d t) d in 1/s.
    let calib = std::fs::read_to_string("systems/calib.eff").unwrap();
    let eff = temp_file(
        "units.eff",
        &format!("{calib}\nunit wR = rad/s, wL = rad/s\n"),
    );
    let j: serde_json::Value = serde_json::from_str(&ok(&[
        "diagnose",
        "--model",
        "systems/calib.sys",
        "--data",
        &data,
        "--effects",
        &eff,
        "--json",
    ]))
    .unwrap();
    let est = &j["named"][0]["estimates"][0];
    let (v, sd) = (est[1].as_f64().unwrap(), est[2].as_f64().unwrap());
    assert!((v - 0.06).abs() < 3.0 * sd, "{v} ± {sd}");
    assert_eq!(j["named"][0]["units"], serde_json::json!(["rad"]));
    let unit_of = |effect: &str| {
        let c = j["rounds"][0]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["effect"] == effect);
        c.map(|c| c["units"].clone())
    };
    assert_eq!(
        unit_of("wR_with_abs_wL"),
        Some(serde_json::json!(["s/rad"]))
    );
    assert_eq!(unit_of("wR_drift"), Some(serde_json::json!(["1/s"])));
    assert_eq!(unit_of("bearing_scale"), Some(serde_json::json!(["1"])));
    // calib.sys's q has no unit: the commanded ratio's dq has none either.
    assert_eq!(j["input_checks"][0]["units"], serde_json::json!([null]));
    // One effect named: no other named effect to be confounded with, so no
    // correlation caution; --json carries the (here empty of named) list.
    assert!(!out.contains("correlate at r"), "{out}");
    let corr = j["named"][0]["correlated"].as_array().expect("a list");
    assert!(corr.iter().all(|c| c["with_effect"].is_null()), "{corr:?}");
    // The report folder is not overwritten without --force.
    bad(
        &refs(&diag(&data, &["--report", &report])),
        "already exists",
    );
}

#[test]
fn diagnose_says_consistent_with_noise_on_clean_data() {
    let data = tmp_dir("clean");
    ok(&["simulate", "--out", &data, "--seed", "11"]);
    let out = ok(&["diagnose", "--model", "systems/calib.sys", "--data", &data]);
    assert!(out.contains("named: none"), "{out}");
    assert!(out.contains("consistent with noise"), "{out}");
    let second = out.lines().nth(1).unwrap_or("");
    assert!(second.starts_with("verdict: nothing named"), "{out}");
    assert!(
        second.contains("the final fit is consistent with noise"),
        "{out}"
    );
    assert!(
        out.contains("time_offset: these data leave it without effect"),
        "{out}"
    );
}

/// Residuals far below the stated noise are a finding, never "consistent
/// with noise", in the verdict paragraph too. Clean circles without encoder
/// noise (`--k 0`, so the residual is the bearing noise alone) with the
/// bearing noise stated twice its simulated 1 degree: the whitened residuals
/// have variance 1/4, so the chi-square is about dof/4, and its z, (dof/4 -
/// dof) / sqrt(2 dof) = -0.53 sqrt(dof), is about -15 for the circles'
/// ~800 bearings: far below -3.5.
#[test]
fn diagnose_calls_residuals_far_below_the_stated_noise_a_finding() {
    let data = tmp_dir("overstated");
    ok(&["simulate", "--out", &data, "--seed", "11", "--k", "0"]);
    let p = format!("{data}/dataset.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    let noise = j["noise"].as_object_mut().unwrap();
    noise.remove("encoder_k");
    let stated = 2.0 * 1f64.to_radians();
    noise.insert("beta".into(), stated.into());
    std::fs::write(&p, j.to_string()).unwrap();
    let out = ok(&refs(&diag(&data, &[])));
    assert!(out.contains("named: none"), "{out}");
    let verdict = out.lines().nth(1).unwrap_or("");
    assert!(verdict.starts_with("verdict: nothing named"), "{out}");
    assert!(!verdict.contains("consistent"), "{out}");
    // The verdict lists the level test with its (negative) z.
    let z: f64 = verdict
        .split("chi2 (z ")
        .nth(1)
        .and_then(|r| r.split(')').next())
        .and_then(|x| x.parse().ok())
        .unwrap_or_else(|| panic!("no chi2 z in the verdict: {out}"));
    assert!(z < -3.5, "{out}");
    let dof: f64 = out
        .split("degrees of freedom")
        .next()
        .and_then(|h| h.rsplit(" on ").next())
        .and_then(|x| x.trim().parse().ok())
        .unwrap_or_else(|| panic!("no degrees of freedom: {out}"));
    // The chi-square of dof unit-variance residuals scaled by 1/4 has sd
    // sqrt(2 dof)/4 around dof/4: in z units 1/4, so 2 z units is 8 sds.
    let want = -0.75 * dof / (2.0 * dof).sqrt();
    assert!((z - want).abs() < 2.0, "z {z} against {want}: {out}");
    assert!(
        out.contains("residual level far below the stated noise"),
        "{out}"
    );
    assert!(!out.contains("consistent with noise"), "{out}");
}

/// Failure 8 of issue 37, its last clause: never "stated" for a level the
/// dataset does not state. The simulator's clean circles with the whole
/// `noise` block removed from dataset.json: every level obsan uses is then
/// its own estimate, so the output-noise line must say estimated, no line
/// may call a level stated, and (no effect simulated) nothing is named.
/// The verdict still leads, on the line after the title.
#[test]
fn diagnose_never_calls_a_level_stated_when_the_data_state_none() {
    let data = tmp_dir("unstated");
    ok(&["simulate", "--out", &data, "--seed", "11"]);
    let p = format!("{data}/dataset.json");
    let mut j: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap();
    j["noise"] = serde_json::json!({});
    std::fs::write(&p, j.to_string()).unwrap();
    let out = ok(&refs(&diag(&data, &[])));
    assert!(
        out.lines()
            .nth(1)
            .unwrap_or("")
            .starts_with("verdict: nothing named"),
        "{out}"
    );
    let levels = out
        .lines()
        .find(|l| l.starts_with("output noise:"))
        .unwrap_or_else(|| panic!("no output noise line: {out}"));
    assert!(levels.contains("estimated from the residuals"), "{out}");
    for l in out.lines() {
        let l = l.to_lowercase();
        let called = l.contains("stated") && (l.contains("noise") || l.contains("sigma"));
        assert!(!called, "a level called stated: {l}\n{out}");
    }
}

#[test]
fn diagnose_rejects_bad_input_with_positions() {
    let data = tmp_dir("bad");
    ok(&[
        "simulate",
        "--out",
        &data,
        "--seed",
        "1",
        "--set",
        "q=0.9,0,-1",
    ]);
    let eff = temp_file(
        "bad.eff",
        "model calib\neffect x\nparam k\noutput beta = beta + k*nope\n",
    );
    bad(&refs(&diag(&data, &["--effects", &eff])), "bad.eff:2");
    let eff = temp_file("bad2.eff", "effect x\nfrob\n");
    bad(&refs(&diag(&data, &["--effects", &eff])), "bad2.eff:2:1");
    // Unit declarations: an unreadable unit, a name of nothing.
    let body = "effect x\nparam k\noutput beta = beta + k\n";
    let eff = temp_file("bad3.eff", &format!("unit beta = m/\n{body}"));
    bad(&refs(&diag(&data, &["--effects", &eff])), "bad3.eff:1:15");
    let eff = temp_file("bad4.eff", &format!("{body}unit k = rad, zz = m\n"));
    bad(
        &refs(&diag(&data, &["--effects", &eff])),
        "bad4.eff:4:15: unit of 'zz'",
    );
    bad(
        &refs(&diag(&data, &["--init", "phi"])),
        "expected NAME=VALUE",
    );
    bad(
        &refs(&diag(&data, &["--init", "zz=1"])),
        "neither a param nor a state",
    );
    bad(&refs(&diag("/nonexistent/x", &[])), "not a dataset folder");
    bad(
        &refs(&diag(&data, &["--input-noise", "guess"])),
        "expected stated, estimate or none",
    );
    bad(
        &["diagnose", "--model", "systems/nope.sys", "--data", &data],
        "cannot read",
    );
    // A model without a data-only start needs --init for its states (a
    // state measured directly, `output beta = x`, would start at its first
    // measurement).
    let sys = temp_file(
        "lin.sys",
        "system lin\nstate x\nparam a\ninput wR, wL\nx' = a*wR\noutput beta = x + a\n",
    );
    bad(&["diagnose", "--model", &sys, "--data", &data], "--init x=");
}

/// A param's estimate and cluster-robust sd in a `--json` diagnosis: from
/// the named effects, else from the last round that fitted it.
pub(crate) fn estimate(j: &serde_json::Value, param: &str) -> Option<(f64, f64)> {
    let pick = |est: &serde_json::Value, robust: &serde_json::Value| {
        let i = est
            .as_array()?
            .iter()
            .position(|e| e[0].as_str() == Some(param))?;
        Some((est[i][1].as_f64()?, robust[i].as_f64()?))
    };
    for n in j["named"].as_array()? {
        if let Some(x) = pick(&n["estimates"], &n["robust_sd"]) {
            return Some(x);
        }
    }
    j["rounds"].as_array()?.iter().rev().find_map(|round| {
        round
            .as_array()?
            .iter()
            .find_map(|c| pick(&c["estimates"], &c["robust_sd"]))
    })
}

pub(crate) fn diagnose_json(model: &str, data: &str, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["diagnose", "--model", model, "--data", data, "--json"];
    args.extend_from_slice(extra);
    serde_json::from_str(&ok(&args)).unwrap()
}

/// The pairs a `--json` diagnosis fixes only in combination:
/// `(params, weight, values, robust covariance)`.
#[allow(clippy::type_complexity)]
pub(crate) fn combinations(
    j: &serde_json::Value,
) -> Vec<([String; 2], f64, [f64; 2], [[f64; 2]; 2])> {
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    j["combinations"]
        .as_array()
        .expect("combinations in --json")
        .iter()
        .map(|c| {
            let p = |i: usize| c["params"][i].as_str().unwrap().to_string();
            let rc = |a: usize, b: usize| f(&c["robust_covariance"][a][b]);
            (
                [p(0), p(1)],
                f(&c["weight"]),
                [f(&c["values"][0]), f(&c["values"][1])],
                [[rc(0, 0), rc(0, 1)], [rc(1, 0), rc(1, 1)]],
            )
        })
        .collect()
}

/// `x0 + w x1` and its robust sd from one side: through its own
/// combination of the pair (cross term included), else from the params it
/// fitted alone (a param it never fitted is 0 there, its model lacking
/// the effect); `None` when it fitted neither.
pub(crate) fn along(j: &serde_json::Value, pair: &[String; 2], w: f64) -> Option<(f64, f64)> {
    for (p, _, x, v) in combinations(j) {
        // The same pair in either order: swap to (pair[0], pair[1]).
        let (x, v) = if p == *pair {
            (x, v)
        } else if p[0] == pair[1] && p[1] == pair[0] {
            ([x[1], x[0]], [[v[1][1], v[1][0]], [v[0][1], v[0][0]]])
        } else {
            continue;
        };
        let var = v[0][0] + w * (v[0][1] + v[1][0]) + w * w * v[1][1];
        return Some((x[0] + w * x[1], var.sqrt()));
    }
    match (estimate(j, &pair[0]), estimate(j, &pair[1])) {
        (Some((x, s)), None) => Some((x, s)),
        (None, Some((y, s))) => Some((w * y, w.abs() * s)),
        // Both fitted, without a combination: |r| below the caution there,
        // and the cross term unknown: the triangle inequality bounds the sd.
        (Some((x, s)), Some((y, t))) => Some((x + w * y, s + w.abs() * t)),
        (None, None) => None,
    }
}

/// Every param fitted from both sources (named, or fitted in a last round)
/// agrees within three combined cluster-robust sds, except the params
/// either side fixes only in combination: those are compared through the
/// combination, along each side's own direction (the landmarks' and the
/// poses' best-determined combinations differ a little). Returns how many
/// params and combinations were compared.
fn agree(a: &serde_json::Value, b: &serde_json::Value, params: &[&str]) -> usize {
    let paired: Vec<[String; 2]> = combinations(a)
        .into_iter()
        .chain(combinations(b))
        .map(|c| c.0)
        .collect();
    let mut compared = 0;
    for p in params {
        if paired.iter().any(|q| q.iter().any(|x| x == p)) {
            continue;
        }
        let (Some((x, sx)), Some((y, sy))) = (estimate(a, p), estimate(b, p)) else {
            continue;
        };
        assert!(sx > 0.0 && sy > 0.0, "{p}: robust sds {sx} {sy}");
        let z = (x - y).abs() / (sx * sx + sy * sy).sqrt();
        assert!(
            z < 3.0,
            "{p}: landmarks {x} ± {sx}, poses {y} ± {sy}: z {z}"
        );
        compared += 1;
    }
    for (pair, w, ..) in combinations(a).into_iter().chain(combinations(b)) {
        let (Some((x, sx)), Some((y, sy))) = (along(a, &pair, w), along(b, &pair, w)) else {
            continue;
        };
        assert!(sx > 0.0 && sy > 0.0, "{pair:?}: robust sds {sx} {sy}");
        let z = (x - y).abs() / (sx * sx + sy * sy).sqrt();
        assert!(
            z < 3.0,
            "{} + {w} {}: landmarks {x} ± {sx}, poses {y} ± {sy}: z {z}",
            pair[0],
            pair[1]
        );
        compared += 1;
    }
    compared
}

pub(crate) fn named(j: &serde_json::Value) -> Vec<String> {
    j["named"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["effect"].as_str().unwrap().to_string())
        .collect()
}

/// Robot 1 diagnosed on the same windows from the landmarks
/// (systems/mrclam.sys; the workflow never sees the ground truth) and from
/// the Vicon poses (systems/mrclam-pose.sys: the ground truth's own
/// diagnosis with the same odometry effects), with the effects file alone
/// and with the generated candidates. Every odometry param that both fit
/// must agree within three combined cluster-robust sds; the stated
/// (Fisher) sds are two to five times smaller and did not
/// (docs/diagnose.md). A pair either side fixes only in combination (the
/// turn scale and the turn rate's coupling with |v|, r = -0.99 on both) is
/// compared through its combination: alone, each is an extrapolation (kw
/// 0.255 from the landmarks with the coupling, -0.065 from the poses
/// without it).
#[test]
fn mrclam_robot_1_landmarks_agree_with_the_vicon_poses() {
    let Some(src) = mrclam_dir() else { return };
    let lm = tmp_dir("mrclam1");
    let out = ok(&["import", "mrclam", &src, "--robot", "1", "--out", &lm]);
    assert!(out.contains("32 windows"), "{out}");
    let poses = tmp_dir("mrclam1-poses");
    let out = ok(&[
        "import",
        "mrclam",
        &src,
        "--robot",
        "1",
        "--out",
        &poses,
        "--vicon-poses",
    ]);
    assert!(
        out.contains("32 windows") && out.contains("Vicon poses"),
        "{out}"
    );
    // The effects file's candidates alone (--no-generated).
    let a = diagnose_json("systems/mrclam.sys", &lm, &["--no-generated"]);
    let b = diagnose_json("systems/mrclam-pose.sys", &poses, &["--no-generated"]);
    // From the landmarks: it turns less than commanded and reacts late,
    // through a first-order lag (the Vicon speed correlates best with the
    // command 0.25 s earlier).
    let na = named(&a);
    assert!(
        na.iter().any(|n| n == "turn_scale") && na.iter().any(|n| n == "actuator_lag"),
        "{na:?}"
    );
    let (lag, _) = estimate(&a, "T").unwrap();
    assert!(lag > 0.05 && lag < 0.5, "lag {lag}");
    // The poses name the speed shortfall (window sums of Vicon distance:
    // 7% less than commanded).
    let nb = named(&b);
    assert!(nb.iter().any(|n| n == "speed_scale"), "{nb:?}");
    let (kv, _) = estimate(&b, "kv").unwrap();
    assert!(kv < -0.02 && kv > -0.1, "kv {kv}");
    assert!(agree(&a, &b, &["kv", "kw", "bw", "T"]) >= 3);
    // The default adds the candidates generated from the model's structure.
    // The shortfall is then the forward speed falling with the turn rate,
    // v (1 + c |omega|), which no effects file holds: named from the
    // landmarks with c within three robust sds of the Vicon truth's 1 s
    // block regression, c = -0.98 s/rad (examples/mrclam_truth.rs, which
    // the workflow never reads), and from the poses too.
    let a = diagnose_json("systems/mrclam.sys", &lm, &[]);
    let b = diagnose_json("systems/mrclam-pose.sys", &poses, &[]);
    for j in [&a, &b] {
        let n = named(j);
        assert!(n.iter().any(|n| n == "v_with_abs_omega"), "{n:?}");
    }
    let (c, sc) = estimate(&a, "gc_v_omega").unwrap();
    assert!((c + 0.98).abs() < 3.0 * sc, "c {c} ± {sc} against -0.98");
    // Both fix the turn scale and the coupling only in combination: from
    // the landmarks both named, from the poses both suggested and fitted
    // together for their combination (established or not, it is what the
    // poses see).
    for j in [&a, &b] {
        let pairs: Vec<[String; 2]> = combinations(j).into_iter().map(|c| c.0).collect();
        assert!(
            pairs.iter().any(|p| {
                let mut p = p.clone();
                p.sort();
                p == ["gc_omega_v", "kw"]
            }),
            "{pairs:?}"
        );
    }
    // kv, bw, T, gc_v_omega alone and the pair's combination along each
    // side's direction.
    assert!(agree(&a, &b, &["kv", "kw", "bw", "T", "gc_v_omega", "gc_omega_v"]) >= 6);
    // The speed factor kv + m c and the turn rate's lag as robots 2 and 3
    // (diagnose_vicon.rs): the landmarks name omega_lag*, the poses no lag
    // (their last round fits T 0.14 [± 0.04] s).
    let m = crate::diagnose_vicon::mean_abs_omega(&lm);
    crate::diagnose_vicon::forms_agree(&a, &b, m, "1");
    // Kept on failure, for a look.
    let _ = std::fs::remove_dir_all(&lm);
    let _ = std::fs::remove_dir_all(&poses);
}

#[test]
fn import_mrclam_rejects_bad_input() {
    let Some(src) = mrclam_dir() else { return };
    let out = tmp_dir("mrclam-bad");
    bad(
        &["import", "mrclam", &src, "--robot", "9", "--out", &out],
        "robot9_Odometry.txt",
    );
    bad(
        &["import", "mrclam", &src, "--out", &out, "--window", "0"],
        "positive",
    );
    assert!(!std::path::Path::new(&out).exists());
}

/// `diagnose` takes its model and data by position as every other
/// command takes its input; `--model`/`--data` stay, and give the same answer.
#[test]
fn diagnose_takes_model_and_data_by_position_or_by_flag_alike() {
    let data = tmp_dir("positional");
    ok(&[
        "simulate",
        "--out",
        &data,
        "--seed",
        "2",
        "--bearings",
        "60",
    ]);
    let flags = ok(&refs(&diag(&data, &["--no-generated", "--json"])));
    let pos = ok(&[
        "diagnose",
        "systems/calib.sys",
        &data,
        "--no-generated",
        "--json",
    ]);
    assert_eq!(flags, pos);
    bad(&["diagnose", "systems/calib.sys"], "<DATA>");
    bad(
        &[
            "diagnose",
            "systems/calib.sys",
            &data,
            "--model",
            "systems/calib.sys",
        ],
        "cannot be used with",
    );
    let _ = std::fs::remove_dir_all(&data);
}

/// The unicycle of systems/mrclam.sys among its 15 landmarks on a ring of
/// radius 4 m (as scripts/false_alarms.sh's unicycle half): six 60 s
/// windows of 50 Hz commands, one landmark's range (sd [`SIGMA_RANGE`]) and
/// bearing (sd 0.02 rad) every 0.2 s, the robot moved by the exact arc of
/// each row (not by obsan's predictor, so the test does not check the code
/// against itself). `circles`: v 0.2 m/s, omega 0.3 rad/s; else random
/// piecewise-constant commands (v in {0, 0.15, 0.3} m/s, omega in
/// [-0.5, 0.5) rad/s, held 0.5-3 s). The sensor measures `range(r)` of the
/// true range r. Writes the dataset folder (no noise stated) and returns
/// the true ranges of every range measurement.
fn unicycle(dir: &str, seed: u64, circles: bool, range: impl Fn(f64) -> f64) -> Vec<f64> {
    let sys = std::fs::read_to_string("systems/mrclam.sys").unwrap();
    let codes: Vec<&str> = sys
        .lines()
        .filter_map(|l| l.strip_prefix("const lx")?.split(',').next())
        .collect();
    let outs: Vec<&str> = sys
        .lines()
        .filter_map(|l| l.strip_prefix("output ")?.split(' ').next())
        .collect();
    let marks: Vec<(f64, f64)> = (0..codes.len())
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / codes.len() as f64;
            (4.0 * a.cos(), 4.0 * a.sin())
        })
        .collect();
    let mut meta = serde_json::Map::new();
    for (c, (x, y)) in codes.iter().zip(&marks) {
        meta.insert(format!("lx{c}"), (*x).into());
        meta.insert(format!("ly{c}"), (*y).into());
    }
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(
        format!("{dir}/dataset.json"),
        r#"{"model": "systems/mrclam.sys"}"#,
    )
    .unwrap();
    let mut rng = obsan_fit::Rng::new(seed);
    let mut truth = Vec::new();
    let dt = 0.02;
    for w in 0..6 {
        let d = format!("{dir}/w{w}");
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(
            format!("{d}/meta.json"),
            serde_json::Value::Object(meta.clone()).to_string(),
        )
        .unwrap();
        let (mut x, mut y) = (rng.uniform() - 0.5, rng.uniform() - 0.5);
        let mut th = std::f64::consts::TAU * rng.uniform();
        let (mut v, mut om, mut next) = (0.0, 0.0, 0.0);
        let mut ins = String::from("t,v,omega\n");
        let mut obs = format!("t,{}\n", outs.join(","));
        for k in 0..3000 {
            let t = k as f64 * dt;
            if k > 0 && k % 10 == 0 {
                let l = ((rng.uniform() * codes.len() as f64) as usize).min(codes.len() - 1);
                let (lx, ly) = marks[l];
                let r = (lx - x).hypot(ly - y);
                truth.push(r);
                let b = (ly - y).atan2(lx - x) - th + 0.02 * rng.normal();
                let cells: Vec<String> = outs
                    .iter()
                    .map(|o| match *o {
                        o if o == format!("r{}", codes[l]) => {
                            format!("{}", range(r) + SIGMA_RANGE * rng.normal())
                        }
                        o if o == format!("b{}", codes[l]) => format!("{}", b.sin().atan2(b.cos())),
                        _ => String::new(),
                    })
                    .collect();
                obs += &format!("{t:.2},{}\n", cells.join(","));
            }
            if circles {
                (v, om) = (0.2, 0.3);
            } else if t >= next {
                v = [0.0, 0.15, 0.3][((rng.uniform() * 3.0) as usize).min(2)];
                om = rng.uniform() - 0.5;
                next = t + 0.5 + 2.5 * rng.uniform();
            }
            ins += &format!("{t:.2},{v},{om}\n");
            let th1 = th + om * dt;
            x += v / om * (th1.sin() - th.sin());
            y -= v / om * (th1.cos() - th.cos());
            th = th1;
        }
        std::fs::write(format!("{d}/inputs.csv"), ins).unwrap();
        std::fs::write(format!("{d}/outputs.csv"), obs).unwrap();
    }
    truth
}

/// The range noise of [`unicycle`] (m).
const SIGMA_RANGE: f64 = 0.05;

/// The named effects of a `--json` diagnosis that rewrite range outputs
/// (mrclam.eff's range_scale and range_bias): (name, stand_in, curvature).
fn range_effects(j: &serde_json::Value) -> Vec<(String, bool, serde_json::Value)> {
    j["named"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|n| n["effect"].as_str().unwrap().starts_with("range_"))
        .map(|n| {
            (
                n["effect"].as_str().unwrap().to_string(),
                n["stand_in"].as_bool().unwrap(),
                n["curvature"].clone(),
            )
        })
        .collect()
}

/// Failure 3's last clause: a named effect whose residual structure
/// persists is a stand-in. The range sensor reads `r + C r^2` (a bias
/// growing with the range squared), which mrclam.eff lacks (its range
/// effects are a scale and a constant bias; --no-generated keeps the
/// candidates to the file's, so the truth is outside them). The scale and
/// the bias absorb the part of `C r^2` linear in r; the rest, `C` times the
/// component of `r^2` orthogonal to `[1, r]`, is curvature in the predicted
/// range. Its expected z, before the fit's poses absorb any of it, is
/// `C |P r^2| / SIGMA_RANGE` with P the projection orthogonal to [1, r]
/// over the true ranges, computed below; the test's long-run variance
/// factor can shrink z by at most sqrt(11) (Bartlett's weights over lags
/// 1..10 sum to 5), so C is chosen for an expected z above
/// `3.5 sqrt(11) + 3 = 14.6`. In the Legendre basis over the true ranges'
/// span `[c - h, c + h]`, `C r^2 = C h^2 (2 P2(x) + 1)/3 + linear`, so the
/// reported coefficient is `(2/3) C h^2` (the predicted range is affine in
/// r, and maps the span's ends to its ends).
#[test]
fn diagnose_reports_a_named_effect_whose_residuals_still_curve_as_a_stand_in() {
    const C: f64 = 0.04;
    let data = tmp_dir("range-squared");
    let truth = unicycle(&data, 1, true, |r| r + C * r * r);
    // The expected z: |P r^2| over the true ranges.
    let n = truth.len() as f64;
    let mean = truth.iter().sum::<f64>() / n;
    let d: Vec<f64> = truth.iter().map(|r| r - mean).collect();
    let q: Vec<f64> = truth.iter().map(|r| r * r).collect();
    let q_mean = q.iter().sum::<f64>() / n;
    let slope = q.iter().zip(&d).map(|(q, d)| (q - q_mean) * d).sum::<f64>()
        / d.iter().map(|d| d * d).sum::<f64>();
    let perp: f64 = q
        .iter()
        .zip(&d)
        .map(|(q, d)| (q - q_mean - slope * d).powi(2))
        .sum::<f64>()
        .sqrt();
    let z_expected = C * perp / SIGMA_RANGE;
    assert!(z_expected > 3.5 * 11f64.sqrt() + 3.0, "{z_expected}");
    let j = diagnose_json(
        "systems/mrclam.sys",
        &data,
        &["--effects", "systems/mrclam.eff", "--no-generated"],
    );
    let ranges = range_effects(&j);
    assert!(!ranges.is_empty(), "no range effect named: {:?}", named(&j));
    let (lo, hi) = truth
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(*r), b.max(*r))
        });
    let b2_truth = 2.0 / 3.0 * C * (0.5 * (hi - lo)).powi(2);
    for (name, stand_in, c) in &ranges {
        assert!(stand_in, "{name} not a stand-in: {c}");
        let (z, b2, sd) = (
            c["z"].as_f64().unwrap(),
            c["coefficient"].as_f64().unwrap(),
            c["sd"].as_f64().unwrap(),
        );
        eprintln!(
            "{name}: z {z:.1} (expected before the poses absorb any: {z_expected:.1}), \
             b2 {b2:.4} ± {sd:.4} (truth {b2_truth:.4})"
        );
        assert!(z > 3.5, "{name}: {c}");
        assert!(
            (b2 - b2_truth).abs() < 3.0 * sd,
            "{name}: b2 {b2} ± {sd} against {b2_truth}"
        );
        assert_eq!(c["outputs"].as_array().unwrap().len(), 15, "{c}");
    }
    // The verdict paragraph says so.
    let out = ok(&[
        "diagnose",
        "--model",
        "systems/mrclam.sys",
        "--effects",
        "systems/mrclam.eff",
        "--data",
        &data,
        "--no-generated",
    ]);
    let verdict = out.lines().nth(1).unwrap_or("");
    assert!(
        verdict.contains("for an effect of another form: the residuals of r"),
        "{out}"
    );
    assert!(out.contains("  stand-in: "), "{out}");
    let _ = std::fs::remove_dir_all(&data);
}

/// The opposite: a true linear range scale (5 %) is named and not called a
/// stand-in. Random commands spread the ranges over 0-11 m, where a scale
/// and a bias separate. With the form right the curvature z is at most
/// Student's t (the fit only shrinks its numerator's variance), so each
/// set flags its range group with probability at most 7e-4, and these
/// three sets any named effect (range and bearing groups) with at most
/// 3 x 2 x 7e-4 = 4.2e-3.
#[test]
fn diagnose_does_not_call_a_true_range_scale_a_stand_in() {
    for seed in 1..=3 {
        let data = tmp_dir(&format!("range-scale-{seed}"));
        unicycle(&data, seed, false, |r| 1.05 * r);
        let j = diagnose_json(
            "systems/mrclam.sys",
            &data,
            &["--effects", "systems/mrclam.eff", "--no-generated"],
        );
        assert!(
            named(&j).contains(&"range_scale".to_string()),
            "seed {seed}: {:?}",
            named(&j)
        );
        for n in j["named"].as_array().unwrap() {
            assert_eq!(n["stand_in"].as_bool(), Some(false), "seed {seed}: {n}");
        }
        let (_, _, c) = range_effects(&j)
            .into_iter()
            .find(|r| r.0 == "range_scale")
            .unwrap();
        assert!(c["z"].as_f64().unwrap().abs() < 3.5, "seed {seed}: {c}");
        let _ = std::fs::remove_dir_all(&data);
    }
}
