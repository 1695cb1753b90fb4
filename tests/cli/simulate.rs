use crate::util::*;

fn tmp_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-sim-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d.to_string_lossy().into_owned()
}

#[test]
fn simulate_writes_the_data_format() {
    let out = tmp_dir("ok");
    ok(&["simulate", "--out", &out, "--q", "0,-1", "--seed", "3"]);
    for f in [
        "dataset.json",
        "truth.json",
        "q0/inputs.csv",
        "q0/outputs.csv",
        "q0/meta.json",
        "q-1/outputs.csv",
    ] {
        assert!(std::path::Path::new(&out).join(f).exists(), "{f}");
    }
    let text = std::fs::read_to_string(format!("{out}/q0/inputs.csv")).unwrap();
    let s = obsan_data::Series::parse_csv(&text, "inputs.csv", &["wR", "wL"], false).unwrap();
    assert_eq!(s.t()[3], 0.06, "time stamps are k/50 exactly as printed");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{out}/q-1/meta.json")).unwrap())
            .unwrap();
    assert_eq!(meta["q"], -1.0);
    // The same seed gives the same data.
    let again = tmp_dir("again");
    ok(&["simulate", "--out", &again, "--q", "0,-1", "--seed", "3"]);
    assert_eq!(
        std::fs::read_to_string(format!("{out}/q0/outputs.csv")).unwrap(),
        std::fs::read_to_string(format!("{again}/q0/outputs.csv")).unwrap()
    );
    // Refuses to overwrite; --force replaces.
    bad(&["simulate", "--out", &out], "already exists");
    ok(&["simulate", "--out", &out, "--q", "0", "--force"]);
    assert!(!std::path::Path::new(&out).join("q-1").exists());
}

#[test]
fn simulate_rejects_bad_options_and_leaves_nothing() {
    let out = tmp_dir("bad");
    bad(
        &["simulate", "--out", &out, "--effect", "bogus=1"],
        "unknown effect 'bogus'",
    );
    bad(
        &["simulate", "--out", &out, "--effect", "time_offset"],
        "expected NAME=VALUE",
    );
    bad(
        &["simulate", "--out", &out, "--speed-profile", "sine:2:10"],
        "|AMPLITUDE| < 1",
    );
    bad(
        &[
            "simulate",
            "--out",
            &out,
            "--q",
            "0.98409",
            "--sigma-beta-deg",
            "1",
        ],
        "degenerate trajectory",
    );
    bad(
        &["simulate", "--out", &out, "--d0", "0.1"],
        "must exceed rho",
    );
    bad(&["simulate", "--out", &out, "--iota=-1"], "--iota must be");
    let inputs = temp_file("wheels.csv", "t,wR,wL\n0,0.1,0.2\n1,0.1,abc\n");
    bad(
        &["simulate", "--out", &out, "--inputs", &inputs],
        "wheels.csv:3 (column wL): 'abc' is not a number",
    );
    assert!(!std::path::Path::new(&out).exists(), "no partial output");
    let parent = std::path::Path::new(&out).parent().unwrap();
    let leftovers = std::fs::read_dir(parent)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .contains(&format!("obsan-sim-{}-bad", std::process::id()))
        })
        .count();
    assert_eq!(leftovers, 0);
}
