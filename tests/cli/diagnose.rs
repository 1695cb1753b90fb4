use crate::util::*;

fn tmp_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-diag-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d.to_string_lossy().into_owned()
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
    assert!(out.contains("bearing_bias: absorbed by psi"), "{out}");
    for f in [
        "report.md",
        "extended.sys",
        "diagnosis.json",
        "residuals_before.svg",
        "residuals_after.svg",
        "candidates.svg",
        "fit_0_beta.svg",
    ] {
        assert!(
            std::path::Path::new(&format!("{report}/{f}")).exists(),
            "{f} missing"
        );
    }
    // The extended model is a valid system that the analysis reads: one more param.
    let ext = format!("{report}/extended.sys");
    let r = ok(&["rank", &ext, "--input", "q"]);
    assert!(
        r.contains("state [mu, gamma, phi, psi, eta, delta, xi, a2]"),
        "{r}"
    );
    // JSON: the named effect with its estimate and sd (truth 0.06).
    let j: serde_json::Value = serde_json::from_str(&ok(&[
        "diagnose",
        "--model",
        "systems/calib.sys",
        "--data",
        &data,
        "--json",
    ]))
    .unwrap();
    let est = &j["named"][0]["estimates"][0];
    let (v, sd) = (est[1].as_f64().unwrap(), est[2].as_f64().unwrap());
    assert!((v - 0.06).abs() < 3.0 * sd, "{v} ± {sd}");
    // The report folder is not overwritten without --force.
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--report",
            &report,
        ],
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
    assert!(
        out.contains("time_offset: these data leave it without effect"),
        "{out}"
    );
}

#[test]
fn diagnose_rejects_bad_input_with_positions() {
    let data = tmp_dir("bad");
    ok(&["simulate", "--out", &data, "--seed", "1", "--q", "0.9,0,-1"]);
    let eff = temp_file(
        "bad.eff",
        "model calib\neffect x\nparam k\noutput beta = beta + k*nope\n",
    );
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--effects",
            &eff,
        ],
        "bad.eff:2",
    );
    let eff = temp_file("bad2.eff", "effect x\nfrob\n");
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--effects",
            &eff,
        ],
        "bad2.eff:2:1",
    );
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--init",
            "phi",
        ],
        "expected NAME=VALUE",
    );
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--init",
            "zz=1",
        ],
        "neither a param nor a state",
    );
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            "/nonexistent/x",
        ],
        "not a dataset folder",
    );
    bad(
        &["diagnose", "--model", "systems/nope.sys", "--data", &data],
        "cannot read",
    );
    // A model without a data-only start needs --init for its states.
    let sys = temp_file(
        "lin.sys",
        "system lin\nstate x\nparam a\ninput wR, wL\nx' = a*wR\noutput beta = x\n",
    );
    bad(&["diagnose", "--model", &sys, "--data", &data], "--init x=");
}
