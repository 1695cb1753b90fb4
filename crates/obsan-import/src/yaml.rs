//! The YAML subset PEtab's problem files use: block mappings (`key: value`,
//! `key:` then an indented block), block lists (`- item`, also at the key's
//! indentation, and `- key: value` items that are mappings), flow lists
//! (`[a, b]`), plain and quoted scalars, `#` comments. Anything else (anchors,
//! tags, multi-line scalars, flow mappings, several documents) is refused at
//! its line: a well-kept YAML crate would read more, but PEtab v1 needs no
//! more than this, and serde_yaml is no longer maintained.

use crate::ImportError;

#[derive(Clone, Debug)]
pub(crate) enum Y {
    Str(String, (usize, usize)),
    List(Vec<Y>),
    Map(Vec<(String, Y, (usize, usize))>),
}

impl Y {
    pub fn get(&self, key: &str) -> Option<&Y> {
        match self {
            Y::Map(m) => m.iter().find(|e| e.0 == key).map(|e| &e.1),
            _ => None,
        }
    }
}

struct Line {
    indent: usize,
    text: String,
    no: usize,
}

const MAX_DEPTH: usize = 50;

pub(crate) fn parse(text: &str) -> Result<Y, ImportError> {
    let mut lines = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let no = k + 1;
        let raw = raw.strip_prefix('\u{feff}').unwrap_or(raw);
        let body = strip_comment(raw);
        if body.trim().is_empty() {
            continue;
        }
        if raw.starts_with('\t') {
            return Err(ImportError::at(
                no,
                1,
                "a tab indents this line (YAML indents with spaces)",
            ));
        }
        let t = body.trim();
        if t == "---" && lines.is_empty() {
            continue;
        }
        if t == "---" || t == "..." || t.starts_with(['&', '*', '!', '|', '>', '{', '%']) {
            return Err(ImportError::at(
                no,
                1,
                format!(
                    "YAML '{t}' is not read (PEtab problem files need only mappings and lists)"
                ),
            ));
        }
        let indent = body.len() - body.trim_start().len();
        lines.push(Line {
            indent,
            text: t.to_string(),
            no,
        });
    }
    if lines.is_empty() {
        return Err(ImportError::at(1, 1, "the YAML file is empty"));
    }
    let mut i = 0;
    let ind = lines[0].indent;
    let y = block(&mut lines, &mut i, ind, 0)?;
    if let Some(l) = lines.get(i) {
        return Err(ImportError::at(
            l.no,
            l.indent + 1,
            "unexpected indentation",
        ));
    }
    Ok(y)
}

/// The text before a `#` that starts a comment (outside quotes).
fn strip_comment(s: &str) -> &str {
    let mut quote = None;
    for (k, c) in s.char_indices() {
        match (quote, c) {
            (None, '\'' | '"') => quote = Some(c),
            (Some(q), c) if c == q => quote = None,
            (None, '#') if k == 0 || s[..k].ends_with(' ') => return &s[..k],
            _ => {}
        }
    }
    s
}

fn block(lines: &mut [Line], i: &mut usize, indent: usize, depth: usize) -> Result<Y, ImportError> {
    if depth > MAX_DEPTH {
        let no = lines.get(*i).map_or(1, |l| l.no);
        return Err(ImportError::at(no, 1, "YAML nested too deeply"));
    }
    let is_item = |t: &str| t == "-" || t.starts_with("- ");
    if lines.get(*i).is_some_and(|l| is_item(&l.text)) {
        let mut items = Vec::new();
        while let Some(l) = lines.get(*i) {
            if l.indent != indent || !is_item(&l.text) {
                break;
            }
            let rest = l.text[1..].trim_start().to_string();
            if rest.is_empty() {
                *i += 1;
                match lines.get(*i) {
                    Some(n) if n.indent > indent => {
                        let ni = n.indent;
                        items.push(block(lines, i, ni, depth + 1)?);
                    }
                    _ => items.push(Y::Str(String::new(), (l.no, l.indent + 1))),
                }
            } else {
                // The item's content continues as a block at its own column.
                let col = indent + (l.text.len() - rest.len());
                lines[*i].indent = col;
                lines[*i].text = rest;
                items.push(block(lines, i, col, depth + 1)?);
            }
        }
        return Ok(Y::List(items));
    }
    let first = &lines[*i];
    if key_value(&first.text).is_none() {
        let y = scalar(&first.text, (first.no, first.indent + 1))?;
        *i += 1;
        return Ok(y);
    }
    let mut map = Vec::new();
    while let Some(l) = lines.get(*i) {
        if l.indent != indent {
            if l.indent > indent {
                return Err(ImportError::at(
                    l.no,
                    l.indent + 1,
                    "unexpected indentation",
                ));
            }
            break;
        }
        let at = (l.no, l.indent + 1);
        let Some((k, v)) = key_value(&l.text) else {
            return Err(ImportError::at(at.0, at.1, "expected 'key: value'"));
        };
        let (k, v) = (k.to_string(), v.to_string());
        if map.iter().any(|e: &(String, Y, _)| e.0 == k) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("key '{k}' is given twice"),
            ));
        }
        *i += 1;
        let val = if v.is_empty() {
            match lines.get(*i) {
                Some(n) if n.indent > indent || (n.indent == indent && is_item(&n.text)) => {
                    let ni = n.indent;
                    block(lines, i, ni, depth + 1)?
                }
                _ => Y::Str(String::new(), at),
            }
        } else {
            let col = at.1 + l_text_offset(&k);
            scalar(&v, (at.0, col))?
        };
        map.push((k, val, at));
    }
    Ok(Y::Map(map))
}

fn l_text_offset(k: &str) -> usize {
    k.len() + 2
}

/// `key: value` (or `key:`), the key plain or quoted.
fn key_value(t: &str) -> Option<(&str, &str)> {
    let k = t
        .find(": ")
        .or_else(|| t.ends_with(':').then(|| t.len() - 1))?;
    let key = t[..k].trim().trim_matches(['"', '\'']);
    if key.is_empty() || t.starts_with('[') {
        return None;
    }
    Some((key, t[k + 1..].trim()))
}

fn scalar(v: &str, at: (usize, usize)) -> Result<Y, ImportError> {
    let unq = |s: &str| -> String {
        let s = s.trim();
        if s.len() >= 2
            && ((s.starts_with('"') && s.ends_with('"'))
                || (s.starts_with('\'') && s.ends_with('\'')))
        {
            s[1..s.len() - 1].to_string()
        } else {
            s.to_string()
        }
    };
    if let Some(inner) = v.strip_prefix('[') {
        let inner = inner
            .strip_suffix(']')
            .ok_or_else(|| ImportError::at(at.0, at.1, "this '[' is not closed on its line"))?;
        if inner.trim().is_empty() {
            return Ok(Y::List(Vec::new()));
        }
        return Ok(Y::List(
            inner.split(',').map(|s| Y::Str(unq(s), at)).collect(),
        ));
    }
    Ok(Y::Str(unq(v), at))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strs(y: Option<&Y>) -> Vec<String> {
        match y {
            Some(Y::List(v)) => v
                .iter()
                .map(|x| match x {
                    Y::Str(s, _) => s.clone(),
                    _ => "?".into(),
                })
                .collect(),
            _ => vec![],
        }
    }

    #[test]
    fn petab_layouts() {
        // The collection's layout (list at the key's indentation) and a flow list.
        let y = parse(
            "format_version: 1\nparameter_file: p.tsv  # comment\nproblems:\n- condition_files:\n  - c.tsv\n  sbml_files: [m.xml, 'n.xml']\n",
        )
        .unwrap();
        let Some(Y::List(ps)) = y.get("problems") else {
            panic!("{y:?}")
        };
        assert_eq!(strs(ps[0].get("condition_files")), ["c.tsv"]);
        assert_eq!(strs(ps[0].get("sbml_files")), ["m.xml", "n.xml"]);
        let Some(Y::Str(p, at)) = y.get("parameter_file") else {
            panic!()
        };
        assert_eq!((p.as_str(), *at), ("p.tsv", (2, 17)));
        // Indented list items.
        let y = parse("problems:\n  - sbml_files:\n      - m.xml\n").unwrap();
        let Some(Y::List(ps)) = y.get("problems") else {
            panic!("{y:?}")
        };
        assert_eq!(strs(ps[0].get("sbml_files")), ["m.xml"]);
        let e = parse("a: 1\n  b: 2\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(parse("a: &x 1\n").is_ok()); // a plain scalar '&x 1'
        assert_eq!(parse("a: 1\n&x\n").unwrap_err().line, 2);
    }
}
