//! Reading the `.sys` format.
//!
//! A file is a list of statements, one per line; a statement continues on the
//! next line while a parenthesis is open or the line ends with an operator or a
//! comma. `#` starts a comment. Declarations may come in any order: all names
//! are collected first, then every expression is built and checked.

use crate::error::{normalize_text, ModelError};
use std::collections::HashMap;

use obsan_expr::{parse_ast, Ast, Ctx, Id, ParseError, Span, Symbol, FUNCTIONS, Q};

/// What a declared name is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A dynamic state (has an equation `x' = ...`).
    State,
    /// An unknown constant parameter: part of the analysed state, derivative 0.
    Param,
    /// A known constant (such as `q`): neither state nor input.
    Const,
    Input,
}

impl Kind {
    pub fn word(self) -> &'static str {
        match self {
            Kind::State => "state",
            Kind::Param => "param",
            Kind::Const => "const",
            Kind::Input => "input",
        }
    }
}

/// A declared name.
#[derive(Clone, Debug)]
pub struct Decl {
    pub name: String,
    pub kind: Kind,
    pub sym: Symbol,
    /// For constants declared with a value (`const g = 9.81`).
    pub value: Option<Q>,
    /// For derived inputs (`input dwR = rate(wR)`): the defining text, which
    /// the data layer evaluates from the measured inputs. To the analysis a
    /// derived input is an input like any other.
    pub derived: Option<String>,
    /// A start value for fitting, never used by the analysis: for a param a
    /// number (`param T = 0.2`), for a state an expression of the constants
    /// and the inputs' first row of each trajectory (`state va = v`).
    pub start: Option<Start>,
    /// Byte offset of the name in the source.
    pub(crate) at: usize,
}

/// Where fitting starts a param or a state (`Decl::start`).
#[derive(Clone, Debug, PartialEq)]
pub enum Start {
    /// A param's start value (exact as written).
    Number(Q),
    /// A state's start in each trajectory: an expression of the constants
    /// and of the inputs at the trajectory's first row.
    Inputs(String),
}

impl Start {
    /// The `.sys` text after `=`.
    pub fn text(&self) -> String {
        match self {
            Start::Number(q) => q.to_string(),
            Start::Inputs(t) => t.clone(),
        }
    }
}

/// An expression with the map from its text offsets to source offsets.
#[derive(Clone, Debug)]
pub(crate) struct Located {
    pub ast: Ast,
    pub id: Id,
    pub map: Vec<usize>,
}

impl Located {
    pub(crate) fn src_span(&self, s: Span) -> (usize, usize) {
        span_in(&self.map, s)
    }
}

/// A named input restriction, e.g. `restrict q: wR = nu, wL = q*nu`.
#[derive(Clone, Debug)]
pub struct Restriction {
    pub name: String,
    /// Original input index, and its replacement.
    pub(crate) subs: Vec<(usize, Located)>,
    /// The inputs of the restricted system, in order: the original inputs not
    /// replaced, then the new ones in order of appearance.
    pub inputs: Vec<String>,
}

/// A parsed, checked system description.
#[derive(Clone, Debug)]
pub struct System {
    pub name: String,
    pub description: String,
    pub(crate) ctx: Ctx,
    pub decls: Vec<Decl>,
    /// Right-hand side per dynamic state, in the order of `states()`.
    pub(crate) dynamics: Vec<Located>,
    pub(crate) outputs: Vec<(String, Located)>,
    pub restrictions: Vec<Restriction>,
    /// `delay tau`: the dynamics see the inputs `u(t - tau)`, tau a param
    /// (a clock offset between input and output stamps, or an actuation lag).
    pub delay: Option<String>,
    pub(crate) origin: String,
    pub(crate) src: String,
    /// Source text of each dynamics right-hand side, output expression and
    /// restriction statement (for [`System::to_sys_text`]).
    pub(crate) texts: Texts,
}

#[derive(Clone, Debug, Default)]
pub(crate) struct Texts {
    pub dynamics: Vec<String>,
    pub outputs: Vec<String>,
    pub restrictions: Vec<String>,
}

/// A logical statement: its text and, per byte, the source offset.
struct Stmt {
    text: String,
    map: Vec<usize>,
}

impl Stmt {
    fn src(&self, i: usize) -> usize {
        self.map
            .get(i)
            .copied()
            .unwrap_or_else(|| self.map.last().map_or(0, |x| x + 1))
    }
    /// Text and source map of `a..b` (clamped; empty if not on characters).
    fn slice(&self, a: usize, b: usize) -> (&str, Vec<usize>) {
        let b = b.min(self.text.len());
        let a = a.min(b);
        match (self.text.get(a..b), self.map.get(a..b)) {
            (Some(t), Some(m)) => (t, m.to_vec()),
            _ => ("", Vec::new()),
        }
    }
}

fn split_statements(src: &str, origin: &str) -> Result<Vec<Stmt>, ModelError> {
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
fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// Split `text` at commas outside parentheses: (start, end) byte ranges.
fn split_commas(text: &str) -> Vec<(usize, usize)> {
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
fn trim_range(text: &str, (a, b): (usize, usize)) -> (usize, usize) {
    let s = &text[a..b];
    let lead = s.len() - s.trim_start().len();
    let trail = s.len() - s.trim_end().len();
    (a + lead, (b - trail).max(a + lead))
}

fn edit_distance(a: &str, b: &str) -> usize {
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

const KEYWORDS: [&str; 13] = [
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
];

struct Reader<'a> {
    src: &'a str,
    origin: &'a str,
}

impl<'a> Reader<'a> {
    fn err(&self, stmt: &Stmt, a: usize, b: usize, msg: impl Into<String>) -> ModelError {
        let (s, e) = (stmt.src(a), stmt.src(b.saturating_sub(1)) + 1);
        ModelError::at(self.origin, self.src, s, e.max(s + 1), msg)
    }
    fn err_src(&self, a: usize, b: usize, msg: impl Into<String>) -> ModelError {
        ModelError::at(self.origin, self.src, a, b.max(a + 1), msg)
    }
    fn parse_err(&self, map: &[usize], e: ParseError) -> ModelError {
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
struct PendingDecl {
    name: String,
    kind: Kind,
    /// Source offset of the name.
    at: usize,
    /// The text after `=` and its source map.
    value: Option<(String, Vec<usize>)>,
}

/// `x' = EXPR` as read: its statement, the offset of `x`, the right side.
struct RawEquation {
    stmt: usize,
    at: usize,
    rhs: String,
    map: Vec<usize>,
}

/// `output y = EXPR` as read.
struct RawOutput {
    name: String,
    at: usize,
    rhs: String,
    map: Vec<usize>,
}

/// `restrict NAME: ...` as read: its statement, name, the name's source
/// offset and the offset of the colon in the statement.
struct RawRestrict {
    stmt: usize,
    name: String,
    at: usize,
    colon: usize,
}

/// Pass 1: every statement sorted by what it is, nothing built yet.
#[derive(Default)]
struct Statements {
    name: Option<String>,
    description: Vec<String>,
    pending: Vec<PendingDecl>,
    equations: Vec<RawEquation>,
    outputs: Vec<RawOutput>,
    restricts: Vec<RawRestrict>,
    delay: Option<(String, usize)>,
}

/// Why a name is refused; non-ASCII letters get said so (the expression
/// language's names are ASCII, see docs/sys-format.md).
fn not_a_name(nm: &str) -> &'static str {
    if nm.is_ascii() {
        ""
    } else {
        " (names are ASCII: letters a-z A-Z, digits and '_')"
    }
}

impl System {
    /// Read a system from `.sys` text; `origin` names the file in messages.
    /// A leading byte-order mark is ignored and CRLF or CR line ends read as
    /// lines ([`crate::normalize_text`]).
    pub fn parse(src: &str, origin: &str) -> Result<System, ModelError> {
        let src = normalize_text(src);
        let src: &str = &src;
        let rd = Reader { src, origin };
        let stmts = split_statements(src, origin)?;
        let mut raw = Statements::default();
        for (si, st) in stmts.iter().enumerate() {
            rd.statement(&mut raw, si, st)?;
        }
        let Some(name) = raw.name.take() else {
            return Err(ModelError::general(
                origin,
                "no 'system NAME' line: every .sys file starts by naming its system",
            ));
        };
        let mut ctx = Ctx::new();
        let decls = rd.declarations(&mut ctx, &raw.pending)?;
        let (dynamics, dyn_text) = rd.dynamics(&mut ctx, &stmts, &raw.equations, &decls)?;
        let outputs = rd.outputs(&mut ctx, &raw.outputs, &decls)?;
        let restrictions = rd.restrictions(&mut ctx, &stmts, &raw.restricts, &decls, &outputs)?;
        if let Some((n, at)) = &raw.delay {
            if !decls.iter().any(|d| &d.name == n && d.kind == Kind::Param) {
                return Err(rd.err_src(
                    *at,
                    at + n.len(),
                    format!("delay '{n}': it must be a declared param (an unknown constant)"),
                ));
            }
        }
        Ok(System {
            name,
            description: raw.description.join(" ").trim().to_string(),
            ctx,
            decls,
            dynamics,
            outputs,
            restrictions,
            delay: raw.delay.map(|d| d.0),
            origin: origin.to_string(),
            src: src.to_string(),
            texts: Texts {
                dynamics: dyn_text,
                outputs: raw
                    .outputs
                    .iter()
                    .map(|o| o.rhs.trim().to_string())
                    .collect(),
                restrictions: raw
                    .restricts
                    .iter()
                    .filter_map(|r| stmts.get(r.stmt))
                    .map(|s| s.text.trim().to_string())
                    .collect(),
            },
        })
    }
}

impl Reader<'_> {
    /// Pass 1, one statement: which it is, its names and unbuilt expressions.
    fn statement(&self, raw: &mut Statements, si: usize, st: &Stmt) -> Result<(), ModelError> {
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
            _ => None,
        };
        if let Some(kind) = kind {
            return self.declaration_list(raw, st, kind, (lead, word_end));
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
                    format!("expected a declaration (system, description, state, param, const, input, output, restrict) or an equation x' = ...{hint}"),
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

    /// Declarations: duplicates, reserved names, the symbols (states, params,
    /// consts, inputs in that order), values, starts and derived inputs.
    fn declarations(
        &self,
        ctx: &mut Ctx,
        pending: &[PendingDecl],
    ) -> Result<Vec<Decl>, ModelError> {
        // First declaration of each name (a map: files with many names stay
        // linear).
        let mut first: HashMap<&str, &PendingDecl> = HashMap::new();
        for p in pending {
            let prev = *first.entry(p.name.as_str()).or_insert(p);
            if prev.at < p.at {
                let e = ModelError::at(self.origin, self.src, prev.at, prev.at + 1, "");
                let (l, c) = (e.line.unwrap_or(0), e.col.unwrap_or(0));
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    format!(
                        "'{}' is declared twice (first as a {} at line {l}, column {c})",
                        p.name,
                        prev.kind.word()
                    ),
                ));
            }
            if p.name == "pi"
                || FUNCTIONS.iter().any(|f| f.0 == p.name)
                || KEYWORDS.contains(&p.name.as_str())
            {
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    format!("'{}' is a reserved word and cannot be a name", p.name),
                ));
            }
        }
        let mut order: Vec<&PendingDecl> = pending.iter().collect();
        order.sort_by_key(|p| match p.kind {
            Kind::State => 0,
            Kind::Param => 1,
            Kind::Const => 2,
            Kind::Input => 3,
        });
        let mut decls: Vec<Decl> = Vec::new();
        for p in order {
            let sym = ctx.symbol(&p.name);
            let value = match (&p.value, p.kind) {
                (Some((text, map)), Kind::Const) => {
                    Some(self.number(text, map, "a constant's value")?)
                }
                _ => None,
            };
            let start = match (&p.value, p.kind) {
                (Some((text, map)), Kind::Param) => Some(Start::Number(self.number(
                    text,
                    map,
                    "a param's start value",
                )?)),
                (Some((text, _)), Kind::State) => Some(Start::Inputs(text.trim().to_string())),
                _ => None,
            };
            decls.push(Decl {
                name: p.name.clone(),
                kind: p.kind,
                sym,
                value,
                derived: match (&p.value, p.kind) {
                    (Some((text, _)), Kind::Input) => Some(text.trim().to_string()),
                    _ => None,
                },
                start,
                at: p.at,
            });
        }
        for p in pending {
            if let (Some((text, map)), Kind::Input | Kind::State) = (&p.value, p.kind) {
                check_derived(self, text, map, &decls, p.kind)?;
            }
        }
        if !decls
            .iter()
            .any(|d| matches!(d.kind, Kind::State | Kind::Param))
        {
            return Err(ModelError::general(
                self.origin,
                "the system has no state and no param: declare them with 'state' and 'param'",
            ));
        }
        Ok(decls)
    }

    /// A number: a constant's value or a param's start.
    fn number(&self, text: &str, map: &[usize], what: &str) -> Result<Q, ModelError> {
        let ast = parse_ast(text).map_err(|e| self.parse_err(map, e))?;
        let mut tmp = Ctx::new();
        let id = tmp
            .build(&ast, &mut |_, n, s| {
                Err(ParseError::new(
                    format!("{what} must be a number, not '{n}'"),
                    s,
                ))
            })
            .map_err(|e| self.parse_err(map, e))?;
        tmp.canon(id).as_q().ok_or_else(|| {
            self.parse_err(
                map,
                ParseError::new(format!("{what} must be a rational number"), ast.span),
            )
        })
    }

    /// Did-you-mean for an unknown name.
    fn suggest(decls: &[Decl], n: &str) -> String {
        let best = decls
            .iter()
            .map(|d| (edit_distance(n, &d.name), &d.name))
            .filter(|(k, _)| *k <= 2)
            .min();
        best.map_or(String::new(), |(_, m)| format!(" (did you mean '{m}'?)"))
    }

    /// The equations: one per state, built over every declared name and
    /// affine in the inputs. Returns them in state order with their text.
    fn dynamics(
        &self,
        ctx: &mut Ctx,
        stmts: &[Stmt],
        equations: &[RawEquation],
        decls: &[Decl],
    ) -> Result<(Vec<Located>, Vec<String>), ModelError> {
        let states: Vec<&Decl> = decls.iter().filter(|d| d.kind == Kind::State).collect();
        let mut dynamics: Vec<Option<Located>> = vec![None; states.len()];
        let mut dyn_text: Vec<String> = vec![String::new(); states.len()];
        for eqn in equations {
            let at = eqn.at;
            let t = stmts.get(eqn.stmt).map_or("", |s| s.text.trim_start());
            let nm = t[..t.find('\'').unwrap_or(0)].trim();
            let width = nm.len() + 1;
            let idx = match decls.iter().find(|d| d.name == nm) {
                None => {
                    return Err(self.err_src(
                        at,
                        at + width,
                        format!(
                        "equation for '{nm}', which is not declared{} (declare it with 'state')",
                        Self::suggest(decls, nm)
                    ),
                    ))
                }
                Some(d) if d.kind == Kind::Param => {
                    return Err(self.err_src(
                        at,
                        at + width,
                        format!("'{nm}' is a param: params are constant and take no equation"),
                    ))
                }
                Some(d) => match states.iter().position(|s| s.name == nm) {
                    Some(i) => i,
                    None => {
                        return Err(self.err_src(
                            at,
                            at + width,
                            format!("'{nm}' is a {}: only states have equations", d.kind.word()),
                        ))
                    }
                },
            };
            if dynamics[idx].is_some() {
                return Err(self.err_src(at, at + width, format!("a second equation for '{nm}'")));
            }
            if eqn.rhs.trim().is_empty() {
                return Err(self.err_src(
                    at,
                    at + width,
                    format!("the equation for '{nm}' has no right-hand side"),
                ));
            }
            let ast = parse_ast(&eqn.rhs).map_err(|e| self.parse_err(&eqn.map, e))?;
            let id = build_checked(
                ctx,
                &ast,
                &eqn.map,
                self,
                decls,
                &[Kind::State, Kind::Param, Kind::Const, Kind::Input],
                &format!("the dynamics of {nm}"),
            )?;
            let loc = Located {
                ast,
                id,
                map: eqn.map.clone(),
            };
            check_affine(ctx, &loc, decls, self, nm)?;
            dynamics[idx] = Some(loc);
            dyn_text[idx] = eqn.rhs.trim().to_string();
        }
        let mut out = Vec::with_capacity(states.len());
        for (s, d) in states.iter().zip(dynamics) {
            match d {
                Some(d) => out.push(d),
                None => {
                    return Err(self.err_src(s.at, s.at + s.name.len(), format!("state '{}' has no equation: add {}' = ... (or declare it as a param if it is constant)", s.name, s.name)))
                }
            }
        }
        Ok((out, dyn_text))
    }

    /// The outputs: at least one, fresh names, functions of states, params
    /// and constants only.
    fn outputs(
        &self,
        ctx: &mut Ctx,
        raw: &[RawOutput],
        decls: &[Decl],
    ) -> Result<Vec<(String, Located)>, ModelError> {
        if raw.is_empty() {
            return Err(ModelError::general(
                self.origin,
                "the system has no output: add at least one 'output y = EXPR'",
            ));
        }
        let find = |n: &str| decls.iter().find(|d| d.name == n);
        let mut outputs: Vec<(String, Located)> = Vec::new();
        for o in raw {
            let (nm, at, map) = (&o.name, o.at, &o.map);
            if find(nm).is_some() || outputs.iter().any(|(p, _)| p == nm) {
                return Err(self.err_src(
                    at,
                    at + nm.len(),
                    format!("output name '{nm}' is already used"),
                ));
            }
            if o.rhs.trim().is_empty() {
                return Err(self.err_src(
                    at,
                    at + nm.len(),
                    format!("output '{nm}' has no expression"),
                ));
            }
            let ast = parse_ast(&o.rhs).map_err(|e| self.parse_err(map, e))?;
            for (id_name, span) in ast.idents() {
                if find(id_name).is_some_and(|d| d.kind == Kind::Input) {
                    let (a, b) = span_in(map, span);
                    return Err(self.err_src(a, b, format!("output '{nm}' uses the input '{id_name}': outputs must be functions of states, params and constants")));
                }
            }
            let id = build_checked(
                ctx,
                &ast,
                map,
                self,
                decls,
                &[Kind::State, Kind::Param, Kind::Const],
                &format!("output {nm}"),
            )?;
            outputs.push((
                nm.clone(),
                Located {
                    ast,
                    id,
                    map: map.clone(),
                },
            ));
        }
        Ok(outputs)
    }

    fn restrictions(
        &self,
        ctx: &mut Ctx,
        stmts: &[Stmt],
        raw: &[RawRestrict],
        decls: &[Decl],
        outputs: &[(String, Located)],
    ) -> Result<Vec<Restriction>, ModelError> {
        let mut out = Vec::new();
        for r in raw {
            if let Some(st) = stmts.get(r.stmt) {
                out.push(self.restriction(ctx, st, r, decls, outputs)?);
            }
        }
        Ok(out)
    }

    /// `restrict NAME: u1 = EXPR, ...`: each left side an input set once;
    /// right sides of constants, inputs not replaced and new names (the new
    /// inputs), affine in the new inputs.
    fn restriction(
        &self,
        ctx: &mut Ctx,
        st: &Stmt,
        r: &RawRestrict,
        decls: &[Decl],
        outputs: &[(String, Located)],
    ) -> Result<Restriction, ModelError> {
        let (rname, at) = (&r.name, r.at);
        let find = |n: &str| decls.iter().find(|d| d.name == n);
        let inputs: Vec<&Decl> = decls.iter().filter(|d| d.kind == Kind::Input).collect();
        let t = &st.text;
        let colon = r.colon + 1;
        let body = t.get(colon..).unwrap_or("");
        if body.trim().is_empty() {
            return Err(self.err_src(
                at,
                at + rname.len(),
                format!(
                    "restriction '{rname}' substitutes nothing: restrict {rname}: u1 = EXPR, ..."
                ),
            ));
        }
        let mut raw: Vec<(usize, Ast, Vec<usize>)> = Vec::new();
        for part in split_commas(body) {
            let (a, b) = trim_range(body, part);
            let item = &body[a..b];
            let Some(eq) = item.find('=') else {
                return Err(self.err(
                    st,
                    colon + a,
                    colon + b.max(a + 1),
                    "each part of a restriction is INPUT = EXPR",
                ));
            };
            let lhs = item[..eq].trim();
            let la = colon + a;
            let Some(ii) = inputs.iter().position(|d| d.name == lhs) else {
                let what = match find(lhs) {
                    Some(d) => format!("'{lhs}' is a {}, not an input", d.kind.word()),
                    None => format!(
                        "'{lhs}' is not a declared input{}{}",
                        Self::suggest(decls, lhs),
                        not_a_name(lhs)
                    ),
                };
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len().max(1),
                    format!("restriction '{rname}': {what}"),
                ));
            };
            if raw.iter().any(|(k, _, _)| *k == ii) {
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len(),
                    format!("restriction '{rname}' sets '{lhs}' twice"),
                ));
            }
            let (rhs, map) = st.slice(colon + a + eq + 1, colon + b);
            if rhs.trim().is_empty() {
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len(),
                    format!("restriction '{rname}': '{lhs} =' needs an expression"),
                ));
            }
            let ast = parse_ast(rhs).map_err(|e| self.parse_err(&map, e))?;
            raw.push((ii, ast, map));
        }
        let replaced: Vec<usize> = raw.iter().map(|r| r.0).collect();
        let mut fresh: Vec<String> = Vec::new();
        for (_, ast, map) in &raw {
            for (n, span) in ast.idents() {
                let (a, b) = span_in(map, span);
                match find(n) {
                    Some(d) if d.kind == Kind::Const => {}
                    Some(d) if d.kind == Kind::Input => {
                        if inputs
                            .iter()
                            .position(|x| x.name == n)
                            .is_some_and(|ii| replaced.contains(&ii))
                        {
                            return Err(self.err_src(a, b, format!("restriction '{rname}' replaces '{n}' and also uses it on a right side")));
                        }
                    }
                    Some(d) => {
                        return Err(self.err_src(a, b, format!("restriction '{rname}': the right side may use known constants and inputs only, not the {} '{n}'", d.kind.word())));
                    }
                    None if outputs.iter().any(|(o, _)| o == n) => {
                        return Err(self.err_src(
                            a,
                            b,
                            format!("restriction '{rname}': '{n}' is an output, not an input"),
                        ));
                    }
                    None => {
                        if !fresh.iter().any(|f| f == n) {
                            fresh.push(n.to_string());
                        }
                    }
                }
            }
        }
        let mut new_inputs: Vec<String> = inputs
            .iter()
            .enumerate()
            .filter(|(i, _)| !replaced.contains(i))
            .map(|(_, d)| d.name.clone())
            .collect();
        new_inputs.extend(fresh.iter().cloned());
        let mut subs: Vec<(usize, Located)> = Vec::new();
        for (ii, ast, map) in raw {
            let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
                if fresh.iter().any(|f| f == n) || decls.iter().any(|d| d.name == n) {
                    Ok(c.symbol(n).id)
                } else {
                    // Every identifier was classified above.
                    Err(ParseError::new(format!("unknown symbol '{n}'"), s))
                }
            };
            let id = ctx
                .build(&ast, &mut resolve)
                .map_err(|e| self.parse_err(&map, e))?;
            let loc = Located { ast, id, map };
            // Affine in the new inputs.
            let vars: Vec<_> = new_inputs.iter().map(|n| ctx.symbol(n).var).collect();
            for &v in &vars {
                let d = ctx.diff(id, v);
                for &w in &vars {
                    let dd = ctx.diff(d, w);
                    if !ctx.is_identically_zero(dd) {
                        let (a, b) = loc.src_span(loc.ast.span);
                        let u = inputs.get(ii).map_or("", |d| d.name.as_str());
                        return Err(self.err_src(
                            a,
                            b,
                            format!(
                                "restriction '{rname}': {u} = ... is not affine in the inputs ({})",
                                new_inputs.join(", ")
                            ),
                        ));
                    }
                }
            }
            subs.push((ii, loc));
        }
        Ok(Restriction {
            name: rname.clone(),
            subs,
            inputs: new_inputs,
        })
    }
}

/// Source range of `span` of an expression whose text has the source map `map`.
fn span_in(map: &[usize], s: Span) -> (usize, usize) {
    let last = map.len().saturating_sub(1);
    let a = map.get(s.start.min(last)).copied().unwrap_or(0);
    let b = map
        .get(s.end.saturating_sub(1).min(last))
        .map_or(a, |x| x + 1);
    (a, b.max(a + 1))
}

impl System {
    /// The system as `.sys` text (declarations, dynamics, outputs,
    /// restrictions; comments dropped): what `obsan diagnose` writes for an
    /// extended model, and what [`System::parse`] reads back.
    pub fn to_sys_text(&self) -> String {
        let mut out = format!("system {}\n", self.name);
        if !self.description.is_empty() {
            out.push_str(&format!("description {}\n", self.description));
        }
        for kind in [Kind::State, Kind::Param, Kind::Const, Kind::Input] {
            let items: Vec<String> = self
                .decls_of(kind)
                .map(|d| match (&d.value, &d.derived, &d.start) {
                    (Some(v), _, _) => format!("{} = {}", d.name, v),
                    (_, Some(t), _) => format!("{} = {}", d.name, t),
                    (_, _, Some(s)) => format!("{} = {}", d.name, s.text()),
                    _ => d.name.clone(),
                })
                .collect();
            if items.is_empty() {
                continue;
            }
            // Derived inputs one per line: their definitions contain commas.
            if kind == Kind::Input {
                for it in items {
                    out.push_str(&format!("input {it}\n"));
                }
            } else {
                out.push_str(&format!("{} {}\n", kind.word(), items.join(", ")));
            }
        }
        if let Some(d) = &self.delay {
            out.push_str(&format!("delay {d}\n"));
        }
        out.push('\n');
        for (d, rhs) in self.decls_of(Kind::State).zip(&self.texts.dynamics) {
            out.push_str(&format!("{}' = {}\n", d.name, rhs));
        }
        out.push('\n');
        for ((name, _), rhs) in self.outputs.iter().zip(&self.texts.outputs) {
            out.push_str(&format!("output {name} = {rhs}\n"));
        }
        if !self.texts.restrictions.is_empty() {
            out.push('\n');
            for r in &self.texts.restrictions {
                out.push_str(r);
                out.push('\n');
            }
        }
        out
    }

    /// The source text of a state's right-hand side or an output's expression.
    pub fn rhs_text(&self, name: &str) -> Option<&str> {
        if let Some(i) = self.decls_of(Kind::State).position(|d| d.name == name) {
            return self.texts.dynamics.get(i).map(String::as_str);
        }
        let i = self.outputs.iter().position(|o| o.0 == name)?;
        self.texts.outputs.get(i).map(String::as_str)
    }

    pub fn decls_of(&self, kind: Kind) -> impl Iterator<Item = &Decl> {
        self.decls.iter().filter(move |d| d.kind == kind)
    }

    pub fn origin(&self) -> &str {
        &self.origin
    }

    pub fn restriction(&self, name: &str) -> Option<&Restriction> {
        self.restrictions.iter().find(|r| r.name == name)
    }

    /// Output names in declaration order.
    pub fn output_names(&self) -> Vec<&str> {
        self.outputs.iter().map(|o| o.0.as_str()).collect()
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

/// A derived input is `rate(u)` (the time derivative of a measured input) or
/// an expression of measured inputs and constants (e.g. `sqrt((wR - wL)^2)*wR`).
/// A derived input's definition, or a state's start (`kind` says which):
/// measured inputs and constants only.
fn check_derived(
    rd: &Reader,
    text: &str,
    map: &[usize],
    decls: &[Decl],
    kind: Kind,
) -> Result<(), ModelError> {
    let what = if kind == Kind::State {
        "a state's start value"
    } else {
        "a derived input"
    };
    let measured = |n: &str| {
        decls
            .iter()
            .any(|d| d.name == n && d.kind == Kind::Input && d.derived.is_none())
    };
    let t = text.trim();
    if let Some(inner) = t.strip_prefix("rate(").and_then(|r| r.strip_suffix(')')) {
        if measured(inner.trim()) {
            return Ok(());
        }
        let lead = text.len() - text.trim_start().len();
        let (a, b) = span_in(map, Span::new(lead, lead + t.len()));
        return Err(rd.err_src(
            a,
            b,
            format!("rate(...) takes one measured input, not '{}'", inner.trim()),
        ));
    }
    let ast = parse_ast(text).map_err(|e| rd.parse_err(map, e))?;
    for (n, span) in ast.idents() {
        let ok = measured(n) || decls.iter().any(|d| d.name == n && d.kind == Kind::Const);
        if !ok {
            let (a, b) = span_in(map, span);
            return Err(rd.err_src(
                a,
                b,
                format!("{what} may use measured inputs and constants, not '{n}'"),
            ));
        }
    }
    Ok(())
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

/// Build an expression, allowing only identifiers of the given kinds.
fn build_checked(
    ctx: &mut Ctx,
    ast: &Ast,
    map: &[usize],
    rd: &Reader,
    decls: &[Decl],
    allowed: &[Kind],
    what: &str,
) -> Result<Id, ModelError> {
    let index: HashMap<&str, &Decl> = decls.iter().map(|d| (d.name.as_str(), d)).collect();
    let mut resolve = |_c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
        match index.get(n).copied() {
            // The declaration's symbol was made in this context.
            Some(d) if allowed.contains(&d.kind) => Ok(d.sym.id),
            Some(d) => Err(ParseError::new(
                format!("{what} cannot use the {} '{n}'", d.kind.word()),
                s,
            )),
            None => {
                let best = decls
                    .iter()
                    .map(|d| (edit_distance(n, &d.name), &d.name))
                    .filter(|(k, _)| *k <= 2)
                    .min();
                let hint = best.map_or(String::new(), |(_, m)| format!(" (did you mean '{m}'?)"));
                Err(ParseError::new(
                    format!("unknown symbol '{n}' in {what}{hint}"),
                    s,
                ))
            }
        }
    };
    ctx.build(ast, &mut resolve)
        .map_err(|e| rd.parse_err(map, e))
}

/// The dynamics must be affine in the inputs: otherwise name the first
/// top-level term that is not.
fn check_affine(
    ctx: &mut Ctx,
    loc: &Located,
    decls: &[Decl],
    rd: &Reader,
    state: &str,
) -> Result<(), ModelError> {
    let inputs: Vec<_> = decls
        .iter()
        .filter(|d| d.kind == Kind::Input)
        .map(|d| d.sym.var)
        .collect();
    let affine = |ctx: &mut Ctx, id: Id| -> bool {
        for &u in &inputs {
            let d = ctx.diff(id, u);
            for &w in &inputs {
                let dd = ctx.diff(d, w);
                if !ctx.is_identically_zero(dd) {
                    return false;
                }
            }
        }
        true
    };
    if affine(ctx, loc.id) {
        return Ok(());
    }
    let names: Vec<&str> = decls
        .iter()
        .filter(|d| d.kind == Kind::Input)
        .map(|d| d.name.as_str())
        .collect();
    for (_, term) in loc.ast.additive_terms() {
        let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
            c.lookup(n)
                .map(|x| x.id)
                .ok_or_else(|| ParseError::new(format!("unknown symbol '{n}'"), s))
        };
        let Ok(tid) = ctx.build(term, &mut resolve) else {
            continue;
        };
        if !affine(ctx, tid) {
            let (a, b) = loc.src_span(term.span);
            let text = rd.src.get(a..b).unwrap_or("");
            return Err(rd.err_src(a, b, format!("the dynamics of {state} are not affine in the inputs ({}): the term '{text}' is not", names.join(", "))));
        }
    }
    let (a, b) = loc.src_span(loc.ast.span);
    Err(rd.err_src(
        a,
        b,
        format!(
            "the dynamics of {state} are not affine in the inputs ({})",
            names.join(", ")
        ),
    ))
}
