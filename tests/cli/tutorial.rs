//! docs/tutorial.md cannot go stale: every `$ obsan ...` line in a console
//! block is run and its output compared with the lines that follow it.

use crate::util::obsan;

/// Split a command line like a shell would for simple single-quoted words.
fn split(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let (mut quoted, mut any) = (false, false);
    for ch in line.chars() {
        match ch {
            '\'' => {
                quoted = !quoted;
                any = true;
            }
            c if c.is_whitespace() && !quoted => {
                if any {
                    out.push(std::mem::take(&mut cur));
                    any = false;
                }
            }
            c => {
                cur.push(c);
                any = true;
            }
        }
    }
    if any {
        out.push(cur);
    }
    out
}

#[test]
fn tutorial_outputs_are_current() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/tutorial.md"))
        .expect("docs/tutorial.md");
    let mut in_block = false;
    let mut current: Option<(String, Vec<String>)> = None;
    let mut cases = Vec::new();
    for line in doc.lines() {
        if line.starts_with("```console") {
            in_block = true;
            continue;
        }
        if in_block && line.starts_with("```") {
            in_block = false;
            cases.extend(current.take());
            continue;
        }
        if !in_block {
            continue;
        }
        if let Some(cmd) = line.strip_prefix("$ ") {
            cases.extend(current.take());
            current = Some((cmd.to_string(), Vec::new()));
        } else if let Some((_, out)) = current.as_mut() {
            out.push(line.to_string());
        }
    }
    assert!(cases.len() >= 10, "the tutorial shows its commands");
    for (cmd, expected) in cases {
        let words = split(&cmd);
        assert_eq!(words[0], "obsan", "{cmd}");
        let args: Vec<&str> = words[1..].iter().map(|s| s.as_str()).collect();
        let r = obsan(&args);
        assert!(r.code == 0 || r.code == 1, "{cmd} failed: {}", r.stderr);
        assert_eq!(
            r.stdout.trim_end(),
            expected.join("\n").trim_end(),
            "output of `{cmd}` changed: update docs/tutorial.md"
        );
    }
}
