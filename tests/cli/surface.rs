//! What every command shows its user (issue 19): each subcommand's --help,
//! found from `obsan --help` itself so a new one cannot be missed, ends with
//! examples and says what --json prints; `import` prints progress lines when
//! stderr is not a terminal (montecarlo's and diagnose's: montecarlo.rs).

use crate::util::ok;
use std::process::Command;

/// The subcommand names a help text lists under "Commands:" (not `help`).
fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

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
