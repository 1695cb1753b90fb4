use std::process::Command;

/// Output of one obsan run.
pub struct Run {
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

/// Run obsan from the repository root.
pub fn obsan(args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("obsan runs");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// Run and expect success; returns stdout.
pub fn ok(args: &[&str]) -> String {
    let r = obsan(args);
    assert_eq!(r.code, 0, "obsan {args:?} failed:\n{}", r.stderr);
    r.stdout
}

/// Run and expect exit code 2 with a message containing `want`; returns stderr.
pub fn bad(args: &[&str], want: &str) -> String {
    let r = obsan(args);
    assert_eq!(
        r.code, 2,
        "obsan {args:?} should fail with 2, got {}:\n{}{}",
        r.code, r.stdout, r.stderr
    );
    assert!(
        r.stderr.contains(want),
        "obsan {args:?}: wanted '{want}' in:\n{}",
        r.stderr
    );
    assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
    r.stderr
}

/// Write a temporary file and return its path.
pub fn temp_file(name: &str, content: &str) -> String {
    let dir = std::env::temp_dir().join(format!("obsan-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p.to_string_lossy().into_owned()
}

/// Exact equality of two expressions, decided by the engine.
pub fn same_function(a: &str, b: &str) -> bool {
    let mut ctx = obsan_expr::Ctx::new();
    let (x, y) = (ctx.parse(a).unwrap(), ctx.parse(b).unwrap());
    ctx.canon(x) == ctx.canon(y)
}

/// Run obsan in another working directory.
pub fn obsan_in(dir: &str, args: &[&str]) -> Run {
    let out = Command::new(env!("CARGO_BIN_EXE_obsan"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("obsan runs");
    Run {
        code: out.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// A fresh, empty temporary folder for one test.
pub fn fresh_dir(name: &str) -> String {
    let d = std::env::temp_dir().join(format!("obsan-t-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d.to_string_lossy().into_owned()
}

/// The MRCLAM data folder: `$OBSAN_MRCLAM_DIR`, else `../shared/data/mrclam` beside the
/// repository. `None` (the caller skips) when it lacks `robot1_Odometry.txt`, except in CI
/// (`CI` set and not `false`/`0`), where a missing folder fails the test: a real-data
/// check that silently skips there would pass without running.
pub fn mrclam_dir() -> Option<String> {
    let d = std::env::var("OBSAN_MRCLAM_DIR")
        .unwrap_or_else(|_| format!("{}/../shared/data/mrclam", env!("CARGO_MANIFEST_DIR")));
    if std::path::Path::new(&format!("{d}/robot1_Odometry.txt")).exists() {
        return Some(d);
    }
    let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false" && v != "0");
    assert!(
        !ci,
        "CI is set and the MRCLAM data are not at {d} (robot1_Odometry.txt)"
    );
    eprintln!("skipped: the MRCLAM data are not at {d}");
    None
}

/// The subcommand names a help text lists under "Commands:" (not `help`).
pub fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// The first identifiers of the depth-1 items of the brace group `text`
/// starts at ("basis (Lie words ...)" -> "basis"; backticks and empty items
/// skipped): the keys a help text's `--json prints {...}` sentence names.
pub fn brace_items(text: &str) -> Vec<String> {
    let (mut depth, mut item, mut items) = (0i32, String::new(), Vec::new());
    for ch in text.chars() {
        match ch {
            '{' | '(' | '[' => depth += 1,
            '}' | ')' | ']' => depth -= 1,
            _ => {}
        }
        if depth == 0 {
            items.push(std::mem::take(&mut item));
            break;
        }
        if depth == 1 && ch == ',' {
            items.push(std::mem::take(&mut item));
        } else if depth >= 1 && !(depth == 1 && ch == '{') {
            item.push(ch);
        }
    }
    items
        .iter()
        .filter_map(|i| {
            let w: String = i
                .trim()
                .trim_start_matches('`')
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            (!w.is_empty()).then_some(w)
        })
        .collect()
}
