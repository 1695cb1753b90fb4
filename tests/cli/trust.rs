//! Regressions of issue 14 (trust): no silent wrong answer, no panic, no lost
//! file. One test per reported reproducer.

use crate::util::*;
use std::path::Path;

fn files_in(dir: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Issue 14.3: `cd my-folder && obsan simulate --out . --force` emptied the folder.
#[test]
fn force_never_replaces_the_working_directory() {
    let d = fresh_dir("force-cwd");
    std::fs::write(format!("{d}/thesis.tex"), "mine").unwrap();
    for out in [".", "..", "./", &d] {
        let r = obsan_in(&d, &["simulate", "--out", out, "--force"]);
        assert_eq!(r.code, 2, "--out {out}: {}", r.stderr);
        assert!(r.stderr.contains("refusing to replace"), "{}", r.stderr);
        assert!(!r.stderr.contains("panicked"));
    }
    assert_eq!(files_in(&d), ["thesis.tex"]);
    assert_eq!(
        std::fs::read_to_string(format!("{d}/thesis.tex")).unwrap(),
        "mine"
    );
}

/// Issue 14.3: --force on a folder holding files obsan did not write deletes nothing.
#[test]
fn force_never_deletes_what_obsan_did_not_write() {
    let root = fresh_dir("force-foreign");
    let mine = format!("{root}/mine");
    std::fs::create_dir_all(format!("{mine}/sub")).unwrap();
    std::fs::write(format!("{mine}/notes.txt"), "keep").unwrap();
    std::fs::write(format!("{mine}/sub/data.csv"), "keep").unwrap();
    bad(
        &["simulate", "--out", &mine, "--force"],
        "not written by obsan",
    );
    // A dataset to calibrate, then --plot and diagnose --report into the user's folder.
    let data = format!("{root}/data");
    ok(&["simulate", "--out", &data, "--q", "0.9,0,-1"]);
    bad(
        &["calibrate", &data, "--plot", &mine, "--force"],
        "refusing to replace",
    );
    bad(
        &[
            "diagnose",
            "--model",
            "systems/calib.sys",
            "--data",
            &data,
            "--report",
            &mine,
            "--force",
        ],
        "refusing to replace",
    );
    assert_eq!(files_in(&mine), ["notes.txt", "sub"]);
    assert_eq!(
        std::fs::read_to_string(format!("{mine}/sub/data.csv")).unwrap(),
        "keep"
    );
    // A folder obsan wrote is replaced by --force ...
    ok(&["simulate", "--out", &data, "--q", "0", "--force"]);
    assert!(!Path::new(&data).join("q0.9").exists());
    assert!(Path::new(&data).join("q0/outputs.csv").exists());
    // ... but not once the user has put a file of their own into it.
    std::fs::write(format!("{data}/q0/my-notes.md"), "keep").unwrap();
    let e = bad(
        &["simulate", "--out", &data, "--force"],
        "which obsan did not write",
    );
    assert!(e.contains("my-notes.md"), "{e}");
    assert!(Path::new(&data).join("q0/my-notes.md").exists());
    // A plain file is never replaced.
    let file = format!("{root}/file.txt");
    std::fs::write(&file, "keep").unwrap();
    bad(&["simulate", "--out", &file, "--force"], "not a folder");
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "keep");
}

/// Issue 14.4: the README's `obsan simulate --out data/sim` failed when data/ did not exist.
#[test]
fn missing_parent_folders_are_created() {
    let d = fresh_dir("mkdir-p");
    let r = obsan_in(&d, &["simulate", "--out", "data/deeper/sim", "--q", "0"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert!(Path::new(&d)
        .join("data/deeper/sim/q0/outputs.csv")
        .exists());
    // Nothing but the dataset itself: no temporary folder left behind.
    assert_eq!(files_in(&format!("{d}/data/deeper")), ["sim"]);
    // A parent that is a file gets a message saying so.
    std::fs::write(format!("{d}/plain"), "x").unwrap();
    let r = obsan_in(&d, &["simulate", "--out", "plain/sim", "--q", "0"]);
    assert_eq!(r.code, 2);
    assert!(
        r.stderr.contains("plain exists and is not a folder"),
        "{}",
        r.stderr
    );
}

/// Issue 14.8: an expression starting with '-' was read as a flag.
#[test]
fn expressions_may_start_with_a_minus() {
    let out = ok(&["simplify", "-x^2"]);
    assert!(same_function(out.trim(), "-(x^2)"), "{out}");
    let out = ok(&["diff", "-x^3", "x"]);
    assert!(same_function(out.trim(), "-3*x^2"), "{out}");
    let out = ok(&["simplify", "-x^2", "--json"]);
    assert!(out.contains('x'), "{out}");
    ok(&["check", "systems/localization.sys", "--mode", "-D"]);
}

/// A --timeout that no clock can hold was a panic in Duration::from_secs_f64.
#[test]
fn timeouts_are_checked() {
    for t in ["inf", "NaN", "-1", "0", "1e300"] {
        let flag = format!("--timeout={t}");
        bad(&["rank", "systems/calib.sys", &flag], "seconds");
    }
    // simplify, diff, show and lie honour --timeout (issue 14.6).
    ok(&["simplify", "x+x", "--timeout", "5"]);
    ok(&["diff", "x^2", "x", "--timeout", "5"]);
    ok(&["show", "systems/calib.sys", "--timeout", "5"]);
    ok(&[
        "lie",
        "systems/localization.sys",
        "--order",
        "1",
        "--timeout",
        "5",
    ]);
}

/// Issue 14.10: simulate wrote datasets that calibrate then refused.
#[test]
fn simulate_refuses_datasets_calibrate_cannot_use() {
    let d = fresh_dir("few-bearings");
    let out = format!("{d}/sim");
    bad(
        &["simulate", "--out", &out, "--bearing-rate", "0.001"],
        "calibrate needs at least",
    );
    assert!(files_in(&d).is_empty(), "nothing is written");
}

/// `obsan lie ... | head` panicked with "failed printing to stdout: Broken pipe".
#[test]
fn a_closed_pipe_ends_the_output_quietly() {
    use std::process::{Command, Stdio};
    // Order 4 prints over 1 MB, far more than a pipe buffers.
    let mut child = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(["lie", "systems/calib.sys", "--order", "4"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.code(), Some(0), "{stderr}");
}

/// Every example in a subcommand's --help runs (issue 19: examples in every --help).
/// Paths under data/ go to a temporary folder; the slow examples run smaller.
#[test]
fn every_help_example_runs() {
    let tmp = fresh_dir("help-examples");
    let commands = [
        "simulate",
        "show",
        "simplify",
        "diff",
        "rank",
        "symmetries",
        "lie",
        "check",
        "verify",
        "modes",
        "calibrate",
        "crlb",
        "montecarlo",
        "diagnose",
    ];
    let mut ran = 0;
    for c in commands {
        let help = ok(&[c, "--help"]);
        assert!(
            help.contains("Examples:"),
            "obsan {c} --help has no examples"
        );
        assert!(
            help.contains("--json prints") || c == "simulate",
            "obsan {c} --help does not say what --json prints"
        );
        for line in help.lines().filter(|l| l.starts_with("  obsan ")) {
            let cmd = line.split("  #").next().unwrap().trim();
            let words = shell_words(cmd);
            // The MRCLAM diagnosis takes tens of seconds: tests/cli/diagnose.rs runs it.
            if words.iter().any(|w| w.contains("mrclam")) {
                continue;
            }
            let words: Vec<String> = words
                .into_iter()
                .skip(1)
                .map(|w| {
                    w.replace("data/", &format!("{tmp}/"))
                        .replace("figs", &format!("{tmp}/figs"))
                })
                .map(|w| {
                    if w == "100" && c == "montecarlo" {
                        "2".into()
                    } else {
                        w
                    }
                })
                .map(|w| {
                    if w == "20" && c == "montecarlo" {
                        "2".into()
                    } else {
                        w
                    }
                })
                .collect();
            let args: Vec<&str> = words.iter().map(|s| s.as_str()).collect();
            let r = obsan(&args);
            assert_eq!(r.code, 0, "example `{line}` failed:\n{}", r.stderr);
            ran += 1;
        }
    }
    assert!(ran >= 25, "only {ran} examples ran");
}

/// Split a command line on spaces, keeping single-quoted words whole.
fn shell_words(s: &str) -> Vec<String> {
    let mut words = Vec::new();
    let mut cur = String::new();
    let mut quoted = false;
    for ch in s.chars() {
        match ch {
            '\'' => quoted = !quoted,
            ' ' if !quoted => {
                if !cur.is_empty() {
                    words.push(std::mem::take(&mut cur));
                }
            }
            _ => cur.push(ch),
        }
    }
    if !cur.is_empty() {
        words.push(cur);
    }
    words
}
