use crate::util::*;

fn tmp_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-cal-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d.to_string_lossy().into_owned()
}

fn truth(dir: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(format!("{dir}/truth.json")).unwrap()).unwrap()
}

#[test]
fn calibrate_recovers_the_parameters_within_their_standard_deviations() {
    let out = tmp_dir("ok");
    ok(&[
        "simulate",
        "--out",
        &out,
        "--seed",
        "7",
        "--bearings",
        "100",
    ]);
    let t = truth(&out);
    for method in ["ls", "ml", "cekf"] {
        let j: serde_json::Value =
            serde_json::from_str(&ok(&["calibrate", &out, "--method", method, "--json"])).unwrap();
        for name in ["phi", "psi", "eta", "delta", "xi"] {
            let (v, sd) = (
                j["params"][name]["value"].as_f64().unwrap(),
                j["params"][name]["sd"].as_f64().unwrap(),
            );
            let want = t[name].as_f64().unwrap();
            // delta's spread includes encoder noise, which the bearing-only sd leaves out.
            let k = if name == "delta" { 8.0 } else { 4.0 };
            assert!(
                (v - want).abs() < k * sd,
                "{method} {name}: {v} ± {sd} vs {want}"
            );
        }
        assert_eq!(j["trajectories"].as_array().unwrap().len(), 3);
    }
    // Text output names every parameter and the metric values (d0 from dataset.json).
    let text = ok(&["calibrate", &out, "--method", "det"]);
    for w in [
        "phi",
        "xi_q",
        "rho",
        "B",
        "det gives no standard deviations",
    ] {
        assert!(text.contains(w), "{w} in\n{text}");
    }
}

#[test]
fn degenerate_data_get_a_message_naming_what_cannot_be_estimated() {
    let two = tmp_dir("two");
    ok(&["simulate", "--out", &two, "--set", "q=0,-1"]);
    bad(&["calibrate", &two], "phi, psi and eta need a third circle");
    let one = tmp_dir("one");
    ok(&["simulate", "--out", &one, "--set", "q=0"]);
    bad(&["calibrate", &one], "xi and delta need two circles");
    // The feature out of view half of the time: drop the second half's bearings.
    let half = tmp_dir("half");
    ok(&["simulate", "--out", &half, "--seed", "2"]);
    let path = format!("{half}/q0/outputs.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let n = lines.len();
    let cut: Vec<String> = lines
        .iter()
        .enumerate()
        .map(|(i, l)| {
            if i > n / 2 {
                format!("{},", l.split(',').next().unwrap())
            } else {
                l.to_string()
            }
        })
        .collect();
    std::fs::write(&path, cut.join("\n") + "\n").unwrap();
    bad(&["calibrate", &half], "out of view");
    // Bad input: a malformed cell names file, row and column.
    let broken = tmp_dir("broken");
    ok(&["simulate", "--out", &broken, "--set", "q=0,-1,0.5"]);
    let path = format!("{broken}/q0/inputs.csv");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replacen("\n0.04,", "\n0.04,abc", 1);
    std::fs::write(&path, text).unwrap();
    bad(&["calibrate", &broken], "inputs.csv:");
    bad(&["calibrate", "/nonexistent/obsan"], "not a dataset folder");
    bad(
        &["calibrate", &two, "--method", "magic"],
        "expected det, ls, cekf or ml",
    );
}

#[test]
fn crlb_and_montecarlo_run() {
    let text = ok(&["crlb", "--bearings", "100"]);
    assert!(text.contains("sd phi (deg)"), "{text}");
    let j: serde_json::Value =
        serde_json::from_str(&ok(&["montecarlo", "--table", "4", "--json"])).unwrap();
    let cells = j[0]["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 3);
    // Table IV reports estimates, one run per cell, of the truth psi = 90 deg
    // (Table II). The bearings' Fisher information scales as 1/sigma_beta^2, so
    // the bearing-only bound's sd must scale exactly as sigma_beta (1, 3, 5 deg):
    // an identity. Each single-run LS estimate is within 4 sds of its cell's
    // bound with encoder noise (the data's two noise sources; a 4-sd miss of an
    // efficient estimator has probability 6e-5): the paper's own LS rows are
    // within 0.2 deg of 90 with sds 0.5-2.2 deg.
    let sd = |c: &serde_json::Value, key: &str| c[key][1].as_f64().unwrap();
    let base = sd(&cells[0], "crlb_sd");
    for (c, sigma) in cells.iter().zip([1.0, 3.0, 5.0]) {
        let ratio = sd(c, "crlb_sd") / base;
        assert!(
            (ratio - sigma).abs() < 1e-3 * sigma,
            "{ratio} for sigma {sigma}"
        );
        let psi = c["methods"][0]["mean_estimate"][1].as_f64().unwrap();
        let bound = sd(c, "crlb_sd_with_encoder_noise");
        assert!((psi - 90.0).abs() < 4.0 * bound, "{psi} against sd {bound}");
    }
    bad(
        &["montecarlo", "--table", "9"],
        "expected 4, 5, 6, 7 or all",
    );
}

#[test]
fn plot_writes_figures_5_to_7_as_png_and_svg_and_never_overwrites() {
    let data = tmp_dir("plotdata");
    ok(&[
        "simulate",
        "--out",
        &data,
        "--seed",
        "2",
        "--bearings",
        "100",
    ]);
    let figs = tmp_dir("figs");
    let r = obsan(&["calibrate", &data, "--method", "ls", "--plot", &figs]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    for traj in ["q0.9", "q0", "q-1"] {
        for kind in ["observation", "sigma", "fits"] {
            let png = std::fs::read(format!("{figs}/{traj}_{kind}.png")).unwrap();
            assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{traj}_{kind}.png");
            // IHDR: width and height at twice the 760 x 360 chart.
            assert_eq!(&png[16..24], &[0, 0, 5, 0xf0, 0, 0, 2, 0xd0]);
            let svg = std::fs::read_to_string(format!("{figs}/{traj}_{kind}.svg")).unwrap();
            assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        }
        // The fits figure compares the methods, as in Figure 6e-f.
        let svg = std::fs::read_to_string(format!("{figs}/{traj}_fits.svg")).unwrap();
        for m in [">DET<", ">LS<", ">ML<", ">observed<"] {
            assert!(svg.contains(m), "{m} in {traj}_fits.svg");
        }
        // Angles drawn in degrees, as the CLI prints them: a bearing spans more
        // than the +-pi of radians, so some tick label lies beyond 4 in magnitude.
        assert!(svg.contains(">beta (deg)<"), "{traj}_fits.svg axis label");
        let ticks: Vec<f64> = svg
            .split('>')
            .filter_map(|t| t.split('<').next()?.trim().parse::<f64>().ok())
            .collect();
        assert!(ticks.iter().any(|t| t.abs() > 4.0), "{traj}: {ticks:?}");
    }
    // curves.json keeps radians for other tools: every observed bearing within [-pi, pi].
    let curves: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{figs}/curves.json")).unwrap())
            .unwrap();
    for c in curves.as_array().unwrap() {
        for b in c["observed"].as_array().unwrap() {
            assert!(b.as_f64().unwrap().abs() <= std::f64::consts::PI);
        }
    }
    assert!(std::fs::read_to_string(format!("{figs}/index.md"))
        .unwrap()
        .contains("q0.9_sigma.png"));
    // An existing folder is kept unless --force.
    bad(
        &["calibrate", &data, "--plot", &figs],
        "already exists (use --force",
    );
    ok(&["calibrate", &data, "--plot", &figs, "--force"]);
}

#[test]
fn crlb_of_a_dataset_at_its_estimate_matches_the_bound_at_the_truth() {
    // Two routes to one bound: `crlb --bearings 100` evaluates the Fisher
    // information at the simulator's truth; `crlb DATASET` at the ML estimate
    // from those data. They agree to within the estimate's error.
    let data = tmp_dir("crlbdata");
    ok(&[
        "simulate",
        "--out",
        &data,
        "--seed",
        "5",
        "--bearings",
        "100",
    ]);
    let at_truth: serde_json::Value =
        serde_json::from_str(&ok(&["crlb", "--bearings", "100", "--json"])).unwrap();
    let at_estimate: serde_json::Value =
        serde_json::from_str(&ok(&["crlb", &data, "--json"])).unwrap();
    for key in ["crlb_sd", "crlb_sd_with_encoder_noise"] {
        for (c, v) in at_truth[key].as_object().unwrap() {
            let (a, b) = (v.as_f64().unwrap(), at_estimate[key][c].as_f64().unwrap());
            assert!((a - b).abs() < 0.1 * a, "{key} {c}: {a} vs {b}");
        }
    }
    // Encoder noise raises delta's bound (it is read from the wheel speeds).
    let d = |k: &str| at_truth[k]["delta (%)"].as_f64().unwrap();
    assert!(d("crlb_sd_with_encoder_noise") > 1.5 * d("crlb_sd"));
    bad(&["crlb", &data, "--seed", "3"], "cannot be used with");
}

/// A unicycle dataset (inputs v, omega) given to calibrate gets the missing column
/// and the command that fits any model, with exit 2.
#[test]
fn calibrate_on_another_models_data_points_to_diagnose() {
    let d = tmp_dir("other-model");
    let w = format!("{d}/w000");
    std::fs::create_dir_all(&w).unwrap();
    std::fs::write(
        format!("{w}/inputs.csv"),
        "t,v,omega\n0,1,0\n1,1,0\n2,1,0\n",
    )
    .unwrap();
    std::fs::write(format!("{w}/outputs.csv"), "t,b\n0,0.1\n1,0.2\n2,0.3\n").unwrap();
    let e = bad(&["calibrate", &d], "missing column 'wR'");
    assert!(e.contains("obsan diagnose --model"), "{e}");
}
