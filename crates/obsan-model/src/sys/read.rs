//! Pass 1 of reading `.sys`: sort each statement by what it is and collect
//! its names and unbuilt expressions ([`Statements`]); nothing is built yet.

use super::lex::{is_ident, split_commas, trim_range, Stmt};
use super::Kind;
use crate::error::ModelError;
use obsan_expr::ParseError;

pub(super) struct Reader<'a> {
    pub(super) src: &'a str,
    pub(super) origin: &'a str,
}

impl<'a> Reader<'a> {
    pub(super) fn err(
        &self,
        stmt: &Stmt,
        a: usize,
        b: usize,
        msg: impl Into<String>,
    ) -> ModelError {
        let (s, e) = (stmt.src(a), stmt.src(b.saturating_sub(1)) + 1);
        ModelError::at(self.origin, self.src, s, e.max(s + 1), msg)
    }
    pub(super) fn err_src(&self, a: usize, b: usize, msg: impl Into<String>) -> ModelError {
        ModelError::at(self.origin, self.src, a, b.max(a + 1), msg)
    }
    pub(super) fn parse_err(&self, map: &[usize], e: ParseError) -> ModelError {
        let a = map
            .get(e.span.start)
            .copied()
            .unwrap_or_else(|| map.last().map_or(0, |x| x + 1));
        let b = map
            .get(e.span.end.saturating_sub(1))
            .map_or(a + 1, |x| x + 1);
        // The expression language's names are ASCII: say so at a letter
        // it does not know.
        let mut msg = e.message;
        if msg.starts_with("unexpected character") && !msg.is_ascii() {
            msg.push_str(" (names are ASCII: letters a-z A-Z, digits and '_')");
        }
        self.err_src(a, b, msg)
    }
}

/// A declared name before the symbols exist.
pub(super) struct PendingDecl {
    pub(super) name: String,
    pub(super) kind: Kind,
    /// Source offset of the name.
    pub(super) at: usize,
    /// The text after `=` and its source map.
    pub(super) value: Option<(String, Vec<usize>)>,
}

/// `x' = EXPR` as read: its statement, the offset of `x`, the right side.
pub(super) struct RawEquation {
    pub(super) stmt: usize,
    pub(super) at: usize,
    pub(super) rhs: String,
    pub(super) map: Vec<usize>,
}

/// `output y = EXPR` as read.
pub(super) struct RawOutput {
    pub(super) name: String,
    pub(super) at: usize,
    pub(super) rhs: String,
    pub(super) map: Vec<usize>,
}

/// `restrict NAME: ...` as read: its statement, name, the name's source
/// offset and the offset of the colon in the statement.
pub(super) struct RawRestrict {
    pub(super) stmt: usize,
    pub(super) name: String,
    pub(super) at: usize,
    pub(super) colon: usize,
}

/// Pass 1: every statement sorted by what it is, nothing built yet.
#[derive(Default)]
pub(super) struct Statements {
    pub(super) name: Option<String>,
    pub(super) description: Vec<String>,
    pub(super) pending: Vec<PendingDecl>,
    pub(super) equations: Vec<RawEquation>,
    pub(super) outputs: Vec<RawOutput>,
    pub(super) restricts: Vec<RawRestrict>,
    pub(super) delay: Option<(String, usize)>,
}

/// Why a name is refused; non-ASCII letters get said so (the expression
/// language's names are ASCII, see docs/sys-format.md).
pub(super) fn not_a_name(nm: &str) -> &'static str {
    if nm.is_ascii() {
        ""
    } else {
        " (names are ASCII: letters a-z A-Z, digits and '_')"
    }
}

impl Reader<'_> {
    /// Pass 1, one statement: which it is, its names and unbuilt expressions.
    pub(super) fn statement(
        &self,
        raw: &mut Statements,
        si: usize,
        st: &Stmt,
    ) -> Result<(), ModelError> {
        let t = st.text.as_str();
        let lead = t.len() - t.trim_start().len();
        let word_end = t[lead..]
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '\''))
            .map_or(t.len(), |i| lead + i);
        let word = &t[lead..word_end];
        let rest_start = word_end;
        let kind = match word {
            "state" | "states" => Some(Kind::State),
            "param" | "params" => Some(Kind::Param),
            "const" | "consts" => Some(Kind::Const),
            "input" | "inputs" => Some(Kind::Input),
            "varying" => Some(Kind::Unknown),
            _ => None,
        };
        if let Some(kind) = kind {
            return self.declaration_list(raw, st, kind, (lead, word_end));
        }
        if word == "unknown" {
            // `unknown input w, v`: the list starts after the second word.
            let rest = &t[word_end..];
            let gap = rest.len() - rest.trim_start().len();
            let second = rest[gap..]
                .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                .next()
                .unwrap_or("");
            if second != "input" && second != "inputs" {
                return Err(self.err(
                    st,
                    lead,
                    word_end,
                    "'unknown' must be followed by 'input': unknown input w1, w2",
                ));
            }
            let end = word_end + gap + second.len();
            return self.declaration_list(raw, st, Kind::Unknown, (lead, end));
        }
        match word {
            "system" => {
                let n = single_name(
                    self,
                    st,
                    (lead, word_end, rest_start),
                    raw.name.is_some(),
                    "'system' needs one name (letters, digits, '_'): system NAME",
                    "a second 'system' line: a file describes one system",
                )?;
                raw.name = Some(n.to_string());
            }
            "description" => raw.description.push(t[rest_start..].trim().to_string()),
            "delay" => {
                let n = single_name(
                    self,
                    st,
                    (lead, word_end, rest_start),
                    raw.delay.is_some(),
                    "'delay' needs one param name: delay NAME",
                    "a second 'delay': a system has at most one",
                )?;
                raw.delay = Some((
                    n.to_string(),
                    st.src(rest_start + t[rest_start..].find(n).unwrap_or(0)),
                ));
            }
            "output" => {
                let (nm, a, eq) = named_head(
                    self,
                    st,
                    lead,
                    rest_start,
                    '=',
                    "an output",
                    "output y = EXPR",
                )?;
                let (rhs, map) = st.slice(rest_start + eq + 1, t.len());
                raw.outputs.push(RawOutput {
                    name: nm,
                    at: st.src(rest_start + a),
                    rhs: rhs.to_string(),
                    map,
                });
            }
            "restrict" => {
                let (nm, a, colon) = named_head(
                    self,
                    st,
                    lead,
                    rest_start,
                    ':',
                    "a restriction",
                    "restrict NAME: u1 = EXPR, ...",
                )?;
                if raw.restricts.iter().any(|r| r.name == nm) {
                    return Err(self.err(
                        st,
                        rest_start + a,
                        rest_start + a + nm.len(),
                        format!("restriction '{nm}' is defined twice"),
                    ));
                }
                raw.restricts.push(RawRestrict {
                    stmt: si,
                    at: st.src(rest_start + a),
                    name: nm,
                    colon: rest_start + colon,
                });
            }
            w if t[word_end..].starts_with('\'') || w.ends_with('\'') => {
                self.equation(raw, si, st, (lead, word_end))?
            }
            _ => {
                let first = t[lead..].chars().next().unwrap_or(' ');
                let hint = if !first.is_ascii() && first.is_alphabetic() {
                    format!(" ('{first}': names are ASCII: letters a-z A-Z, digits and '_')")
                } else if t.contains('=') && is_ident(word) {
                    format!(" (for the dynamics of {word} write {word}' = ..., for an output write output {word} = ...)")
                } else {
                    String::new()
                };
                return Err(self.err(
                    st,
                    lead,
                    word_end.max(lead + first.len_utf8()),
                    format!("expected a declaration (system, description, state, param, const, input, unknown input, varying, output, restrict) or an equation x' = ...{hint}"),
                ));
            }
        }
        Ok(())
    }

    /// `state a, b = EXPR, ...` (and param, const, input): the names and the
    /// text after each `=`.
    fn declaration_list(
        &self,
        raw: &mut Statements,
        st: &Stmt,
        kind: Kind,
        (lead, word_end): (usize, usize),
    ) -> Result<(), ModelError> {
        let t = st.text.as_str();
        let word = &t[lead..word_end];
        let body = &t[word_end..];
        if body.trim().is_empty() {
            return Err(self.err(
                st,
                lead,
                word_end,
                format!("'{word}' needs a list of names"),
            ));
        }
        for r in split_commas(body) {
            let (a, b) = trim_range(body, r);
            let item = &body[a..b];
            let (nm, val) = match item.split_once('=') {
                Some((n, v)) => (n.trim_end(), Some(v)),
                None => (item, None),
            };
            let na = word_end + a;
            if !is_ident(nm) {
                let shown = if nm.is_empty() {
                    "an empty name".to_string()
                } else {
                    format!("'{nm}'")
                };
                return Err(self.err(
                    st,
                    na,
                    na + nm.len().max(1),
                    format!(
                        "{shown} is not a valid name in a '{word}' list{}",
                        not_a_name(nm)
                    ),
                ));
            }
            let value = match val {
                Some(v) if v.trim().is_empty() => {
                    return Err(self.err(
                        st,
                        na,
                        na + nm.len(),
                        format!("'{nm} =' needs a value after '='"),
                    ))
                }
                Some(v) => {
                    // `v` is the tail of `item` after its first '='.
                    let off = na + (item.len() - v.len());
                    Some((
                        v.to_string(),
                        (off..off + v.len()).map(|i| st.src(i)).collect(),
                    ))
                }
                None => None,
            };
            raw.pending.push(PendingDecl {
                name: nm.to_string(),
                kind,
                at: st.src(na),
                value,
            });
        }
        Ok(())
    }

    /// `x' = EXPR`.
    fn equation(
        &self,
        raw: &mut Statements,
        si: usize,
        st: &Stmt,
        (lead, word_end): (usize, usize),
    ) -> Result<(), ModelError> {
        let t = st.text.as_str();
        let w = &t[lead..word_end];
        let nm = w.trim_end_matches('\'');
        let after = if w.ends_with('\'') {
            word_end
        } else {
            word_end + 1
        };
        let rest = &t[after..];
        let Some(eq) = rest.find('=') else {
            return Err(self.err(
                st,
                lead,
                t.len(),
                format!("an equation needs '=': {nm}' = EXPR"),
            ));
        };
        if !rest[..eq].trim().is_empty() {
            return Err(self.err(st, after, after + eq, format!("expected '=' after {nm}'")));
        }
        let (rhs, map) = st.slice(after + eq + 1, t.len());
        raw.equations.push(RawEquation {
            stmt: si,
            at: st.src(lead),
            rhs: rhs.to_string(),
            map,
        });
        Ok(())
    }
}

/// The one name of `KEYWORD NAME` (`system`, `delay`), refused when it is
/// not a name or when the statement was already given.
fn single_name<'s>(
    rd: &Reader,
    st: &'s Stmt,
    (lead, word_end, rest_start): (usize, usize, usize),
    again: bool,
    usage: &str,
    twice: &str,
) -> Result<&'s str, ModelError> {
    let n = st.text[rest_start..].trim();
    if !is_ident(n) {
        return Err(rd.err(st, lead, st.text.len(), usage));
    }
    if again {
        return Err(rd.err(st, lead, word_end, twice));
    }
    Ok(n)
}

/// The name before `sep` in `KEYWORD NAME sep ...`: (name, its offset in the
/// body, the offset of `sep` in the body).
fn named_head(
    rd: &Reader,
    st: &Stmt,
    lead: usize,
    rest_start: usize,
    sep: char,
    what: &str,
    usage: &str,
) -> Result<(String, usize, usize), ModelError> {
    let t = &st.text;
    let body = &t[rest_start..];
    let Some(pos) = body.find(sep) else {
        let sep_word = if sep == '=' {
            "an expression"
        } else {
            "a colon"
        };
        return Err(rd.err(
            st,
            lead,
            t.len(),
            format!("{what} needs a name and {sep_word}: {usage}"),
        ));
    };
    let (a, b) = trim_range(body, (0, pos));
    let nm = &body[a..b];
    if !is_ident(nm) {
        return Err(rd.err(
            st,
            rest_start + a,
            rest_start + b.max(a + 1),
            format!("{what} needs a name: {usage}"),
        ));
    }
    Ok((nm.to_string(), a, pos))
}
