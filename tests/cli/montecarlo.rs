//! `obsan montecarlo`: one cell, shards and their merge, progress lines.

use crate::util::{bad, fresh_dir, ok};
use std::process::Command;

/// Table V, cell 3 (iota = 0.04, sigma_beta = 1 deg), 7 runs: the shards of
/// 3 are runs 0..2, 2..4, 4..7.
const CELL: [&str; 6] = ["--table", "5", "--cell", "3", "--runs", "7"];

fn args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    CELL.iter().copied().chain(extra.iter().copied()).collect()
}

/// The shards k/n of the cell (with `more` flags) written as JSON files.
fn shards(dir: &str, n: usize, more: &[&str]) -> Vec<String> {
    (1..=n)
        .map(|k| {
            let shard = format!("{k}/{n}");
            let mut a = vec!["montecarlo"];
            a.extend(args(&["--shard", &shard, "--json"]));
            a.extend(more);
            let path = format!("{dir}/part{k}-of-{n}{}.json", more.join(""));
            std::fs::write(&path, ok(&a)).unwrap();
            path
        })
        .collect()
}

#[test]
fn three_shards_merge_into_the_one_run_table_byte_for_byte() {
    let dir = fresh_dir("mc-merge");
    let one_text = ok(&[&["montecarlo"][..], &args(&[])].concat());
    let one_json = ok(&[&["montecarlo"][..], &args(&["--json"])].concat());
    let parts = shards(&dir, 3, &[]);
    let p: Vec<&str> = parts.iter().map(|s| s.as_str()).collect();
    // Any order of the parts: they are put in shard order.
    let merged_text = ok(&["montecarlo", "merge", p[2], p[0], p[1]]);
    let merged_json = ok(&["montecarlo", "merge", p[0], p[1], p[2], "--json"]);
    assert_eq!(merged_text, one_text);
    assert_eq!(merged_json, one_json);
    // The table is the cell's: one cell, the runs asked for, real numbers.
    let j: serde_json::Value = serde_json::from_str(&one_json).unwrap();
    assert_eq!(j[0]["runs"], 7);
    let cells = j[0]["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 1);
    assert_eq!(cells[0]["cell"], 3);
    assert_eq!(cells[0]["label"], "iota = 0.04, sigma_beta = 1 deg");
    let ls = &cells[0]["methods"][0];
    assert_eq!(ls["method"], "LS");
    assert!(ls["mean_abs_error"][0].as_f64().unwrap() > 0.0);
    // A shard holds only its runs: 2..4 of 7.
    let part: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(p[1]).unwrap()).unwrap();
    let runs: Vec<u64> = part["tables"][0]["cells"][0]["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["run"].as_u64().unwrap())
        .collect();
    assert_eq!(runs, [2, 3]);
    // Without --json a shard prints its own runs' statistics, saying so.
    let text = ok(&[&["montecarlo"][..], &args(&["--shard", "2/3"])].concat());
    assert!(text.contains("shard 2/3: runs 2..4 of 7"), "{text}");
}

#[test]
fn a_merge_of_parts_of_different_sweeps_or_a_missing_shard_is_refused() {
    let dir = fresh_dir("mc-refuse");
    let parts = shards(&dir, 3, &[]);
    let p: Vec<&str> = parts.iter().map(|s| s.as_str()).collect();
    let e = bad(&["montecarlo", "merge", p[0], p[2]], "missing shard 2/3");
    assert!(e.contains("table 5 cell 3 with 7 runs"), "{e}");
    bad(
        &["montecarlo", "merge", p[0], p[0], p[1], p[2]],
        "both shard 1/3",
    );
    // Another seed, another run count, another table: not one sweep.
    let seed2 = shards(&dir, 3, &["--seed", "2"]);
    bad(
        &["montecarlo", "merge", p[0], &seed2[1], p[2]],
        "not shards of one sweep: seed 2 vs 1",
    );
    let mut a = vec!["montecarlo", "--table", "5", "--cell", "3", "--runs", "8"];
    a.extend(["--shard", "2/3", "--json"]);
    let runs8 = format!("{dir}/runs8.json");
    std::fs::write(&runs8, ok(&a)).unwrap();
    bad(
        &["montecarlo", "merge", p[0], &runs8, p[2]],
        "table 5 cell 3 with 8 runs vs table 5 cell 3 with 7 runs",
    );
    let t4 = format!("{dir}/t4.json");
    let a = ["montecarlo", "--table", "4", "--shard", "2/3", "--json"];
    std::fs::write(&t4, ok(&a)).unwrap();
    bad(
        &["montecarlo", "merge", p[0], &t4, p[2]],
        "table 4 cells 1,2,3",
    );
    // A shard of another count, a file that is no part, bad flags.
    let of4 = shards(&dir, 4, &[]);
    bad(
        &["montecarlo", "merge", p[0], &of4[1], p[2]],
        "shard count 4 vs 3",
    );
    let junk = format!("{dir}/junk.json");
    std::fs::write(&junk, "{\"tables\": []}").unwrap();
    bad(&["montecarlo", "merge", &junk], "not a partial result");
    std::fs::write(&junk, "{\n  \"partial\": ").unwrap();
    bad(&["montecarlo", "merge", &junk], "junk.json:2:");
    bad(
        &["montecarlo", "--table", "5", "--shard", "4/3"],
        "--shard 4/3",
    );
    bad(
        &["montecarlo", "--table", "5", "--shard", "x"],
        "expected K/N",
    );
    bad(
        &["montecarlo", "--cell", "2"],
        "--cell needs a single --table",
    );
    let e = bad(
        &["montecarlo", "--table", "7", "--cell", "6"],
        "cells 1 to 5",
    );
    assert!(e.contains("5 dq = 0.1"), "{e}");
}

#[test]
fn a_long_run_prints_progress_lines_when_stderr_is_not_a_terminal() {
    // OBSAN_PROGRESS_SECS=0: a line at every run instead of every 5 s, so
    // the test does not depend on timing.
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(["montecarlo", "--table", "5", "--cell", "1", "--runs", "3"])
        .env("OBSAN_PROGRESS_SECS", "0")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    for k in 1..=3 {
        assert!(
            err.contains(&format!("montecarlo: {k}/3 runs, ")),
            "no progress line {k}/3 in:\n{err}"
        );
    }
    // stdout is the table alone.
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("/3 runs"), "{text}");
    // `off` silences them.
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(["montecarlo", "--table", "5", "--cell", "1", "--runs", "2"])
        .env("OBSAN_PROGRESS_SECS", "off")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("/2 runs"), "{err}");
}

#[test]
fn diagnose_prints_its_stages_as_progress_lines_when_stderr_is_not_a_terminal() {
    let data = format!("{}/data", fresh_dir("mc-diag-progress"));
    ok(&["simulate", "--out", &data, "--seed", "11"]);
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(["diagnose", "--model", "systems/calib.sys", "--data", &data])
        .env("OBSAN_PROGRESS_SECS", "0")
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("diagnose: fitting the nominal model, "),
        "no progress line in:\n{err}"
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("diagnose: fitting"));
}

/// Table V's first cell (iota = 0, sigma_beta = 1 deg): the paper's mean errors 0.10 deg,
/// 0.08 deg, 0.32 %, 0.005 %, 0.045 % against CRLB sds of 0.71 deg, 0.74 deg, 1.9 %, 0.013 %,
/// 0.11 % (docs/accuracy.md, item 3, from `obsan crlb --bearings 100`): every column is under
/// an efficient estimator's mean |error| of 0.80 sd, so the note names all five. Table IV
/// reports estimates, not errors: no note there.
#[test]
fn the_paper_figures_below_the_bound_are_pointed_out_beside_the_table() {
    let text = ok(&["montecarlo", "--table", "5", "--cell", "1", "--runs", "1"]);
    let note = text
        .lines()
        .find(|l| l.starts_with("note: the paper's mean errors"))
        .unwrap_or_else(|| panic!("no note beside the table:\n{text}"));
    for col in ["phi (deg)", "psi (deg)", "eta (%)", "delta (%)", "xi (%)"] {
        assert!(note.contains(col), "{col} not named: {note}");
    }
    assert!(note.contains("docs/accuracy.md"), "{note}");
    let t4 = ok(&["montecarlo", "--table", "4", "--runs", "1"]);
    assert!(!t4.contains("note: the paper's mean errors"), "{t4}");
}
