//! What every command shows its user: each subcommand's --help,
//! found from `obsan --help` itself so a new one cannot be missed, ends with
//! examples and says what --json prints; `import` prints progress lines when
//! stderr is not a terminal (montecarlo's and diagnose's: montecarlo.rs).

use crate::util::{brace_items, ok, subcommands};
use std::process::Command;

#[test]
fn every_subcommand_help_ends_with_examples_and_says_what_json_prints() {
    let mut todo: Vec<Vec<String>> = subcommands(&ok(&["--help"]))
        .into_iter()
        .map(|c| vec![c])
        .collect();
    assert!(todo.len() >= 14, "{todo:?}");
    let mut seen = Vec::new();
    while let Some(path) = todo.pop() {
        let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
        args.push("--help");
        let help = ok(&args);
        let name = path.join(" ");
        for sub in subcommands(&help) {
            let mut p = path.clone();
            p.push(sub);
            todo.push(p);
        }
        // clap prints after_help last: the examples follow every option.
        let examples = help.find("Examples");
        let options = help.rfind("Options:").unwrap_or(0);
        assert!(
            examples.is_some_and(|e| e > options),
            "obsan {name} --help does not end with examples:\n{help}"
        );
        let tail = &help[examples.unwrap_or(0)..];
        assert!(
            tail.lines().any(|l| l.contains(&format!("obsan {name}"))),
            "obsan {name} --help has no example of itself:\n{help}"
        );
        let has_json = help.lines().any(|l| l.trim_start().starts_with("--json"));
        assert!(
            !has_json || help.contains("--json prints"),
            "obsan {name} --help has --json but does not say what it prints:\n{help}"
        );
        seen.push(name);
    }
    for nested in ["import mrclam", "montecarlo merge"] {
        assert!(
            seen.iter().any(|s| s == nested),
            "{nested} not reached: {seen:?}"
        );
    }
}

#[test]
fn import_prints_progress_lines_when_stderr_is_not_a_terminal() {
    let Some(src) = crate::util::mrclam_dir() else {
        return;
    };
    let out_dir = std::env::temp_dir().join(format!("obsan-surface-{}-import", std::process::id()));
    let _ = std::fs::remove_dir_all(&out_dir);
    let out_dir = out_dir.to_string_lossy().into_owned();
    // OBSAN_PROGRESS_SECS=0: a line at every stage, not every 5 s.
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args([
            "import",
            "mrclam",
            &src,
            "--robot",
            "1",
            "--out",
            &out_dir,
            "--max-windows",
            "2",
        ])
        .env("OBSAN_PROGRESS_SECS", "0")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("import mrclam: "),
        "no progress line in:\n{err}"
    );
    // stdout is the summary alone.
    assert!(!String::from_utf8_lossy(&out.stdout).contains("import mrclam: "));
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// The top-level keys a `--json prints {...}` sentence names: the items at depth 0 of its first
/// brace group, each item's first identifier ("basis (Lie words ...)" -> "basis").
fn promised_keys(help: &str) -> Vec<String> {
    brace_items(&help[help.find("--json prints {").expect("no --json sentence") + 14..])
}

/// A user reads `--help` to find a JSON field; every top-level key the help names
/// must be in the output, and every key of the output must be named.
#[test]
fn each_json_help_names_exactly_the_keys_the_command_prints() {
    let runs: [&[&str]; 9] = [
        &["show", "systems/calib.sys"],
        &["simplify", "x + 1"],
        &["diff", "x^2", "x"],
        &["rank", "systems/localization.sys"],
        &["symmetries", "systems/localization.sys"],
        &["lie", "systems/localization.sys", "--order", "1"],
        &["check", "systems/localization.sys", "--mode", "D"],
        &["verify", "systems/decomp_21_22.dec"],
        &["modes", "systems/calib_q_nopsi.sys"],
    ];
    let dir = crate::util::fresh_dir("json-keys");
    let sim = format!("{dir}/sim");
    ok(&["simulate", "--out", &sim, "--bearings", "40"]);
    let with_data: [&[&str]; 2] = [&["calibrate", &sim], &["crlb", "--bearings", "40"]];
    for args in runs.iter().chain(&with_data) {
        let help = ok(&[args[0], "--help"]);
        let mut promised = promised_keys(&help);
        promised.sort();
        let mut a = args.to_vec();
        a.push("--json");
        let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
            .args(&a)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let v: serde_json::Value = serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("obsan {}: not JSON: {e}", a.join(" ")));
        let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        got.sort();
        assert_eq!(promised, got, "obsan {} --help against its --json", args[0]);
    }
}

/// The same for `import`, whose formats are subcommands: each --help's sentence against its
/// --json, on a STRIKE-GOLDD file and an SBML model of the repository.
#[test]
fn each_import_json_help_names_exactly_the_keys_it_prints() {
    let runs = [
        (
            "strike-goldd",
            "systems/benchmarks/strike-goldd/src/z_create_lotka_volterra.m",
        ),
        (
            "sbml",
            "crates/obsan-import/tests/petab/Bertozzi_PNAS2020/model.xml",
        ),
    ];
    for (format, file) in runs {
        let mut promised = promised_keys(&ok(&["import", format, "--help"]));
        promised.sort();
        let v: serde_json::Value =
            serde_json::from_str(&ok(&["import", format, file, "--json"])).unwrap();
        let mut got: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
        got.sort();
        assert_eq!(
            promised, got,
            "obsan import {format} --help against its --json"
        );
    }
}
