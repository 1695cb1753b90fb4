//! The suite's entries and their cited verdicts, read by both `cargo bench --bench suite` and
//! the CI check in tests/cli/suite.rs (included there with `#[path]`), so the two read the same
//! grammar (docs/benchmarks.md): `# verdict: SPEC` and `# verdict(INPUT): SPEC` lines in each
//! model file beside a `# verdict-source:` line, and `PATH [--input NAME] | SPEC` lines in
//! systems/benchmarks/paper.list. The expectation is the cited one, never obsan's output.

use std::collections::BTreeSet;
use std::path::Path;

/// A cited verdict: the rank, and which variables are unobservable, where the source says.
#[derive(Debug, Default, PartialEq)]
pub struct Verdict {
    pub rank: Option<u64>,
    /// `Some(empty)` for "observable" (rank n); `None` when only the rank is cited.
    pub unobservable: Option<BTreeSet<String>>,
    /// With unknown inputs: the reconstructable ones (`reconstructable w1 w2`, or
    /// `reconstructable none`); `None` when not cited.
    pub reconstructable: Option<BTreeSet<String>>,
}

/// One suite entry: a file, an optional restriction, the verdict it cites.
pub struct Entry {
    pub path: String,
    pub input: Option<String>,
    pub verdict: Verdict,
}

/// Parse `observable; rank 6`, `unobservable x2 k1; rank 5` or `rank 4`, with unknown inputs
/// also `; reconstructable w1` (or `reconstructable none`).
pub fn parse_verdict(spec: &str) -> Result<Verdict, String> {
    let mut v = Verdict::default();
    for part in spec.split(';').map(str::trim) {
        let mut words = part.split_whitespace();
        match words.next() {
            Some("observable") if words.next().is_none() => {
                v.unobservable = Some(BTreeSet::new());
            }
            Some("unobservable") => {
                let names: BTreeSet<String> = words.map(String::from).collect();
                if names.is_empty() {
                    return Err(format!("'unobservable' names no variable in '{spec}'"));
                }
                v.unobservable = Some(names);
            }
            Some("reconstructable") => {
                let names: BTreeSet<String> = words.map(String::from).collect();
                v.reconstructable = Some(match names.iter().next().map(String::as_str) {
                    None => return Err(format!("'reconstructable' names nothing in '{spec}'")),
                    Some("none") if names.len() == 1 => BTreeSet::new(),
                    _ => names,
                });
            }
            Some("rank") => {
                let r = words.next().and_then(|w| w.parse().ok());
                if r.is_none() || words.next().is_some() {
                    return Err(format!("bad rank in '{spec}'"));
                }
                v.rank = r;
            }
            _ => return Err(format!("cannot read '{part}' in '{spec}'")),
        }
    }
    if v.rank.is_none() && v.unobservable.is_none() && v.reconstructable.is_none() {
        return Err(format!("empty verdict '{spec}'"));
    }
    Ok(v)
}

/// The `# verdict:` and `# verdict(NAME):` lines of a model file; errors name file and line.
pub fn file_entries(path: &str, text: &str) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let Some(rest) = line.strip_prefix("# verdict") else {
            continue;
        };
        if rest.starts_with("-source:") {
            continue;
        }
        let (input, spec) = if let Some(s) = rest.strip_prefix(':') {
            (None, s)
        } else if let Some((name, s)) = rest.strip_prefix('(').and_then(|r| r.split_once("):")) {
            (Some(name.trim().to_string()), s)
        } else {
            return Err(format!("{path}:{}: malformed verdict line '{line}'", i + 1));
        };
        let verdict = parse_verdict(spec).map_err(|e| format!("{path}:{}: {e}", i + 1))?;
        out.push(Entry {
            path: path.to_string(),
            input,
            verdict,
        });
    }
    Ok(out)
}

/// Every suite entry: the model files of systems/benchmarks/ and systems/vins.sys (each must
/// cite a source and at least one verdict), then systems/benchmarks/paper.list.
pub fn entries(root: &Path) -> Result<Vec<Entry>, String> {
    let dir = root.join("systems/benchmarks");
    let mut files = model_files(root, "systems/benchmarks")?;
    files.push("systems/vins.sys".to_string());
    let mut out = cited_entries(root, &files)?;
    let list =
        std::fs::read_to_string(dir.join("paper.list")).map_err(|e| format!("paper.list: {e}"))?;
    for (i, line) in list.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = format!("paper.list:{}", i + 1);
        let (lhs, spec) = line.split_once('|').ok_or(format!("{at}: no '|'"))?;
        let mut words = lhs.split_whitespace();
        let path = words.next().ok_or(format!("{at}: no path"))?.to_string();
        let input = match (words.next(), words.next(), words.next()) {
            (None, _, _) => None,
            (Some("--input"), Some(name), None) => Some(name.to_string()),
            _ => return Err(format!("{at}: cannot read '{lhs}'")),
        };
        let verdict = parse_verdict(spec).map_err(|e| format!("{at}: {e}"))?;
        out.push(Entry {
            path,
            input,
            verdict,
        });
    }
    Ok(out)
}

/// The StructuralIdentifiability.jl models, systems/benchmarks/si-jl/*.sys. Each must
/// name its source (`# Source:`) and carry a `# verdict-source:` line; the verdict itself is
/// optional (`verdict-source: none`): such an entry has `Verdict::default()` (neither rank nor
/// variables cited) and is timed but not judged.
pub fn si_jl_entries(root: &Path) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    for path in &model_files(root, "systems/benchmarks/si-jl")? {
        let text = std::fs::read_to_string(root.join(path)).map_err(|e| format!("{path}: {e}"))?;
        if !text.lines().any(|l| l.starts_with("# Source: ")) {
            return Err(format!("{path}: no '# Source:' line"));
        }
        if !text.lines().any(|l| l.starts_with("# verdict-source: ")) {
            return Err(format!("{path}: no '# verdict-source:' line"));
        }
        let e = file_entries(path, &text)?;
        if e.is_empty() {
            out.push(Entry {
                path: path.clone(),
                input: None,
                verdict: Verdict::default(),
            });
        }
        out.extend(e);
    }
    Ok(out)
}

/// SI.jl's published local and global times (s) by model key, from
/// systems/benchmarks/si-jl/published_times.list (`KEY | loc | glob`).
pub fn si_jl_published(root: &Path) -> Result<Vec<(String, String, String)>, String> {
    let p = root.join("systems/benchmarks/si-jl/published_times.list");
    let text = std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        match cells.as_slice() {
            [k, l, g] => out.push((k.to_string(), l.to_string(), g.to_string())),
            _ => {
                return Err(format!(
                    "published_times.list:{}: expected 'KEY | loc | glob'",
                    i + 1
                ))
            }
        }
    }
    Ok(out)
}

/// The unknown-input models, systems/benchmarks/unknown-inputs/*.sys: each cites its source
/// and at least one verdict (derived by hand in the file or from the SymPy oracle
/// benches/peers/unknown_inputs.py), with the reconstructable inputs.
pub fn unknown_input_entries(root: &Path) -> Result<Vec<Entry>, String> {
    cited_entries(
        root,
        &model_files(root, "systems/benchmarks/unknown-inputs")?,
    )
}

/// The entries of `files`, each of which must carry a `# verdict-source:` line and at least
/// one `# verdict:` line.
fn cited_entries(root: &Path, files: &[String]) -> Result<Vec<Entry>, String> {
    let mut out = Vec::new();
    for path in files {
        let text = std::fs::read_to_string(root.join(path)).map_err(|e| format!("{path}: {e}"))?;
        if !text.lines().any(|l| l.starts_with("# verdict-source: ")) {
            return Err(format!("{path}: no '# verdict-source:' line"));
        }
        let e = file_entries(path, &text)?;
        if e.is_empty() {
            return Err(format!("{path}: no '# verdict:' line"));
        }
        out.extend(e);
    }
    Ok(out)
}

/// The `.sys` files of the folder `dir` (relative to `root`), as paths relative to `root`, sorted.
fn model_files(root: &Path, dir: &str) -> Result<Vec<String>, String> {
    let full = root.join(dir);
    let mut files: Vec<String> = std::fs::read_dir(&full)
        .map_err(|e| format!("{}: {e}", full.display()))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".sys"))
        .map(|n| format!("{dir}/{n}"))
        .collect();
    files.sort();
    Ok(files)
}
