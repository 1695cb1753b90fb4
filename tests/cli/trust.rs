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
    for t in ["inf", "NaN", "-1", "1e300"] {
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
        "a dataset needs at least",
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

/// Issue 14.2 and 14.9: a BOM, non-ASCII text and invalid UTF-8 in a .sys file.
#[test]
fn sys_files_with_bom_unicode_or_bad_bytes() {
    let loc = std::fs::read_to_string("systems/localization.sys").unwrap();
    // A BOM and CRLF line endings read as the same system.
    let bom = temp_file("bom.sys", &format!("\u{feff}{}", loc.replace('\n', "\r\n")));
    let plain = ok(&["rank", "systems/localization.sys", "--json"]);
    let with_bom = ok(&["rank", &bom, "--json"]);
    let rank = |s: &str| serde_json::from_str::<serde_json::Value>(s).unwrap()["rank"].clone();
    assert_eq!(rank(&with_bom), rank(&plain));
    // A Greek state name and an umlaut in a comment: no panic; an answer or a located error.
    let greek = temp_file(
        "greek.sys",
        &loc.replace("thetaR", "θR")
            .replace("# Section II", "# für Section II"),
    );
    let r = obsan(&["rank", &greek]);
    assert!(r.code == 0 || r.code == 2, "{}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    if r.code == 2 {
        assert!(r.stderr.contains("greek.sys:"), "{}", r.stderr);
    }
    // Invalid UTF-8 on line 3: the error names the file, line and column.
    let dir = fresh_dir("bad-utf8");
    let p = format!("{dir}/bad.sys");
    let mut bytes = b"system s\nstate x\noutput y = x # caf".to_vec();
    bytes.extend([0xE9, b'\n']);
    std::fs::write(&p, bytes).unwrap();
    let e = bad(&["rank", &p], "invalid UTF-8");
    assert!(e.contains("bad.sys:3:"), "{e}");
    // A file that ends with an operator and no final newline.
    let cut = temp_file("cut.sys", "system s\nstate x\nx' = x*");
    bad(&["rank", &cut], "cut.sys:3:");
}

/// Issue 14.1: exponents above 65535 wrapped (x^70000 printed as x^4464).
#[test]
fn large_exponents_are_exact() {
    let seven = ["x^10000"; 7].join("*");
    let out = ok(&["simplify", &seven]);
    assert_eq!(out.trim(), "x^70000");
    let out = ok(&["simplify", "(x^10000)^7 - x^4464"]);
    assert!(same_function(out.trim(), "x^70000 - x^4464"), "{out}");
    assert_ne!(out.trim(), "0");
    // The same inside a .sys file.
    let sys = temp_file(
        "bigexp.sys",
        "system s\nstate x\ninput u\nx' = u*x^40000*x^40000\noutput y = x\n",
    );
    let out = ok(&["show", &sys, "--json"]);
    assert!(out.contains("x^80000"), "{out}");
}

/// Issue 14.2: `((x^10000)^10000)^100` panicked; past the engine's exponent
/// range it is a clear error, never a wrapped answer.
#[test]
fn exponents_past_the_range_are_an_error() {
    let r = obsan(&["simplify", "((x^10000)^10000)^100"]);
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    assert_eq!(r.code, 2, "{}{}", r.stdout, r.stderr);
    assert!(r.stderr.contains("exponent"), "{}", r.stderr);
}

/// Issue 14.2: a sum of 100,000 terms overflowed the stack (exit 134).
#[test]
fn long_and_deep_expressions_do_not_overflow_the_stack() {
    let terms = vec!["x"; 100_000].join(" + ");
    let sys = temp_file(
        "long.sys",
        &format!("system s\nstate x\ninput u\nx' = u*({terms})\noutput y = x\n"),
    );
    let out = ok(&["show", &sys]);
    assert!(out.contains("100000*"), "{out}");
    // Deep nesting: an answer or a located error, never a crash.
    let deep = format!("{}x{}", "(".repeat(100_000), ")".repeat(100_000));
    let sys = temp_file(
        "deep.sys",
        &format!("system s\nstate x\ninput u\nx' = u*{deep}\noutput y = x\n"),
    );
    let r = obsan(&["show", &sys]);
    assert!(r.code == 0 || r.code == 2, "exit {}: {}", r.code, r.stderr);
    assert!(
        !r.stderr.contains("panicked") && !r.stderr.contains("overflow"),
        "{}",
        r.stderr
    );
    if r.code == 2 {
        assert!(r.stderr.contains("deep.sys:4:"), "{}", r.stderr);
    }
}

/// Issue 14.6: a product of 22 binomials took 22 s and 1.5 GB; the budget
/// stops it with a clear error, and a flag raises the budget.
#[test]
fn expression_size_has_a_budget() {
    let product: Vec<String> = (1..=22).map(|i| format!("(x{i} + 1)")).collect();
    let e = bad(&["simplify", &product.join("*")], "too large");
    assert!(
        e.contains("--max-terms"),
        "the message says how to raise it: {e}"
    );
    // Small products are untouched, and --max-terms raises the limit.
    let small: Vec<String> = (1..=10).map(|i| format!("(x{i} + 1)")).collect();
    ok(&["simplify", &small.join("*")]);
    bad(
        &["simplify", &small.join("*"), "--max-terms", "100"],
        "too large",
    );
}

/// Issue 14.5: one value 1e308 in outputs.csv made calibrate and diagnose run for minutes.
#[test]
fn absurd_values_are_located_errors() {
    let d = fresh_dir("absurd");
    let data = format!("{d}/sim");
    ok(&["simulate", "--out", &data]);
    let path = format!("{data}/q0/outputs.csv");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let t = lines[4].split(',').next().unwrap().to_string();
    lines[4] = format!("{t},1e308");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    let e = bad(&["calibrate", &data], "outputs.csv:5");
    assert!(e.contains("beta"), "names the column: {e}");
    bad(
        &["diagnose", "--model", "systems/calib.sys", "--data", &data],
        "outputs.csv:5",
    );
}

/// Issue 14.7: what spreadsheets and loggers write is read as the same data:
/// a BOM, CRLF or CR-only line endings, comment lines, quoted headers, a
/// trailing comma and an extra text column.
#[test]
fn benign_data_file_variations_give_the_same_calibration() {
    let d = fresh_dir("benign");
    let data = format!("{d}/sim");
    ok(&["simulate", "--out", &data, "--q", "0.9,0,-1", "--seed", "4"]);
    let plain = ok(&["calibrate", &data, "--method", "ls", "--json"]);
    for (i, tr) in ["q0.9", "q0", "q-1"].iter().enumerate() {
        for file in ["inputs.csv", "outputs.csv"] {
            let path = format!("{data}/{tr}/{file}");
            let text = std::fs::read_to_string(&path).unwrap();
            let mut out = String::from("\u{feff}# exported by a logger\n");
            for (k, line) in text.lines().enumerate() {
                let quoted = if k == 0 {
                    line.split(',')
                        .map(|c| format!("\"{c}\""))
                        .collect::<Vec<_>>()
                        .join(",")
                } else {
                    line.to_string()
                };
                let note = if k == 0 { "note" } else { "ok" };
                out.push_str(&format!("{quoted},{note},"));
                out.push_str(["\r\n", "\r", "\n"][i]);
            }
            std::fs::write(&path, out).unwrap();
        }
    }
    let r = obsan(&["calibrate", &data, "--method", "ls", "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    assert_eq!(r.stdout, plain, "the same numbers from the same data");
    assert!(
        r.stderr.contains("note"),
        "the ignored column is named: {}",
        r.stderr
    );
}

/// The engine's budget covers the commands that read a system: a .sys file
/// whose expansion passes the exponent range, or an analysis past
/// --max-terms, ends in the limit's message with exit 2, never a panic.
#[test]
fn the_budget_covers_systems_and_analyses() {
    let sys = temp_file(
        "huge.sys",
        "system s\nstate x\ninput u\nx' = u*(x^2000000000 + 1)^3\noutput y = x\n",
    );
    for cmd in ["show", "rank", "lie"] {
        let mut args = vec![cmd, sys.as_str()];
        if cmd == "lie" {
            args.extend(["--order", "1"]);
        }
        bad(&args, "exponent too large");
    }
    let e = bad(
        &[
            "symmetries",
            "systems/calib.sys",
            "--input",
            "q",
            "--exact",
            "--max-terms",
            "1000",
        ],
        "expression too large",
    );
    assert!(e.contains("--max-terms"), "{e}");
}

/// `modes --out P --force` replaces only files obsan wrote.
#[test]
fn modes_force_keeps_the_users_files() {
    let d = fresh_dir("modes-force");
    let prefix = format!("{d}/loc");
    std::fs::write(format!("{prefix}.sys"), "my own system").unwrap();
    bad(
        &[
            "modes",
            "systems/localization.sys",
            "--out",
            &prefix,
            "--force",
        ],
        "obsan did not write it",
    );
    assert_eq!(
        std::fs::read_to_string(format!("{prefix}.sys")).unwrap(),
        "my own system"
    );
    std::fs::remove_file(format!("{prefix}.sys")).unwrap();
    ok(&["modes", "systems/localization.sys", "--out", &prefix]);
    ok(&[
        "modes",
        "systems/localization.sys",
        "--out",
        &prefix,
        "--force",
    ]);
    ok(&["rank", &format!("{prefix}.sys")]);
}
