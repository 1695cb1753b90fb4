//! Pass 0 of reading `.sys`: logical statements with their source maps,
//! and the small text helpers (names, comma lists, spans) both passes use.

use crate::error::ModelError;
use obsan_expr::Span;

/// A logical statement: its text and, per byte, the source offset.
pub(super) struct Stmt {
    pub(super) text: String,
    pub(super) map: Vec<usize>,
}

impl Stmt {
    pub(super) fn src(&self, i: usize) -> usize {
        self.map
            .get(i)
            .copied()
            .unwrap_or_else(|| self.map.last().map_or(0, |x| x + 1))
    }
    /// Text and source map of `a..b` (clamped; empty if not on characters).
    pub(super) fn slice(&self, a: usize, b: usize) -> (&str, Vec<usize>) {
        let b = b.min(self.text.len());
        let a = a.min(b);
        match (self.text.get(a..b), self.map.get(a..b)) {
            (Some(t), Some(m)) => (t, m.to_vec()),
            _ => ("", Vec::new()),
        }
    }
}

pub(super) fn split_statements(src: &str, origin: &str) -> Result<Vec<Stmt>, ModelError> {
    let mut out = Vec::new();
    let mut cur = Stmt {
        text: String::new(),
        map: Vec::new(),
    };
    let mut depth: i64 = 0;
    let mut open_at = 0;
    let mut offset = 0;
    for raw in src.split_inclusive('\n') {
        let line_start = offset;
        offset += raw.len();
        let line = raw.trim_end_matches(['\n', '\r']);
        let code = line.split('#').next().unwrap_or("");
        for (i, ch) in code.char_indices() {
            match ch {
                '(' => {
                    if depth == 0 {
                        open_at = line_start + i;
                    }
                    depth += 1
                }
                ')' => depth -= 1,
                _ => {}
            }
            let pos = line_start + i;
            cur.text.push(ch);
            cur.map.extend(std::iter::repeat_n(pos, ch.len_utf8()));
        }
        let trimmed = code.trim_end();
        // A description is free text: one line, whatever its brackets.
        let free_text = {
            let t = cur.text.trim_start();
            t.starts_with("description ") || t == "description"
        };
        if free_text {
            depth = 0;
        }
        let continues =
            !free_text && (depth > 0 || trimmed.ends_with(['+', '-', '*', '/', '^', ',']));
        if continues && !cur.text.trim().is_empty() {
            cur.text.push(' ');
            cur.map.push(line_start + code.len());
            continue;
        }
        if !cur.text.trim().is_empty() {
            out.push(std::mem::replace(
                &mut cur,
                Stmt {
                    text: String::new(),
                    map: Vec::new(),
                },
            ));
        } else {
            cur = Stmt {
                text: String::new(),
                map: Vec::new(),
            };
        }
        depth = 0;
    }
    if depth > 0 {
        return Err(ModelError::at(
            origin,
            src,
            open_at,
            open_at + 1,
            "this '(' is never closed",
        ));
    }
    if !cur.text.trim().is_empty() {
        // A file that ends inside a continued statement: drop the joining
        // space, so an error at its end points just after its last character.
        let keep = cur.text.trim_end().len();
        cur.text.truncate(keep);
        cur.map.truncate(keep);
        out.push(cur);
    }
    Ok(out)
}

/// A name: an ASCII letter or '_', then ASCII letters, digits or '_'.
pub(super) fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// Split `text` at commas outside parentheses: (start, end) byte ranges.
pub(super) fn split_commas(text: &str) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i64, 0);
    for (i, ch) in text.char_indices() {
        match ch {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push((start, i));
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push((start, text.len()));
    out
}

/// Trimmed sub-range.
pub(super) fn trim_range(text: &str, (a, b): (usize, usize)) -> (usize, usize) {
    let s = &text[a..b];
    let lead = s.len() - s.trim_start().len();
    let trail = s.len() - s.trim_end().len();
    (a + lead, (b - trail).max(a + lead))
}

pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for i in 1..=a.len() {
        let mut cur = vec![i; b.len() + 1];
        for j in 1..=b.len() {
            let sub = prev[j - 1] + usize::from(a[i - 1] != b[j - 1]);
            cur[j] = sub.min(prev[j] + 1).min(cur[j - 1] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

pub(super) const KEYWORDS: [&str; 15] = [
    "system",
    "delay",
    "description",
    "state",
    "states",
    "param",
    "params",
    "const",
    "consts",
    "input",
    "inputs",
    "output",
    "restrict",
    "unknown",
    "varying",
];

/// Source range of `span` of an expression whose text has the source map `map`.
pub(super) fn span_in(map: &[usize], s: Span) -> (usize, usize) {
    let last = map.len().saturating_sub(1);
    let a = map.get(s.start.min(last)).copied().unwrap_or(0);
    let b = map
        .get(s.end.saturating_sub(1).min(last))
        .map_or(a, |x| x + 1);
    (a, b.max(a + 1))
}
