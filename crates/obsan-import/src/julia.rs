//! StructuralIdentifiability.jl's `@ODEmodel` text (SciML, MIT): a Julia
//! file holding one or more models, e.g. its `benchmarking/benchmarks.jl`.
//!
//! Only the Julia needed to find and read models is understood: the macro
//! `@ODEmodel(eq, eq, ...)`; a model named by a `:KEY => Dict(:name => "...",
//! :cite => "...", :ode => MODEL)` entry or `NAME[:KEY] = Dict(...)`;
//! `VAR = @ODEmodel(...)` and `VAR = set_parameter_values(VAR, Dict(p =>
//! VALUE, ...))`, whose values (numbers, `QQ(a, b)`, `a // b`) are
//! substituted. Everything else in the file is skipped token by token.
//!
//! In a model, `x'(t) = EXPR` makes `x` a state, `y(t) = EXPR` an output,
//! another `u(t)` an input and a bare name a parameter, as SI.jl does.

use crate::{Converted, ImportError};
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    Num(String),
    Str(String),
    /// Operators and punctuation, multi-character ones (`=>`, `//`) whole.
    Punct(String),
    /// Any other character (non-ASCII letters): an error only inside a model.
    Other(char),
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    line: usize,
    col: usize,
    /// Whitespace or a comment precedes it.
    spaced: bool,
}

fn err(t: &Token, msg: impl Into<String>) -> ImportError {
    ImportError::at(t.line, t.col, msg)
}

/// Split Julia text into tokens; comments (`#`, nested `#= =#`) dropped.
fn tokenize(text: &str) -> Result<Vec<Token>, ImportError> {
    let chars: Vec<char> = text.chars().collect();
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    let mut out = Vec::new();
    let mut spaced = true;
    // Advance over chars[i..j], keeping line and column.
    let step = |i: &mut usize, line: &mut usize, col: &mut usize, j: usize| {
        while *i < j {
            if chars[*i] == '\n' {
                *line += 1;
                *col = 1;
            } else {
                *col += 1;
            }
            *i += 1;
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let (l0, c0) = (line, col);
        if c.is_whitespace() {
            let next = i + 1;
            step(&mut i, &mut line, &mut col, next);
            spaced = true;
            continue;
        }
        if c == '#' {
            if chars.get(i + 1) == Some(&'=') {
                let mut depth = 0usize;
                let mut j = i;
                loop {
                    if j >= chars.len() {
                        return Err(ImportError::at(l0, c0, "unterminated '#=' comment"));
                    }
                    if chars[j] == '#' && chars.get(j + 1) == Some(&'=') {
                        depth += 1;
                        j += 2;
                    } else if chars[j] == '=' && chars.get(j + 1) == Some(&'#') {
                        depth -= 1;
                        j += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        j += 1;
                    }
                }
                step(&mut i, &mut line, &mut col, j);
            } else {
                let mut j = i;
                while j < chars.len() && chars[j] != '\n' {
                    j += 1;
                }
                step(&mut i, &mut line, &mut col, j);
            }
            spaced = true;
            continue;
        }
        let mut j = i + 1;
        let tok = if c.is_ascii_alphabetic() || c == '_' {
            while j < chars.len() && (chars[j].is_ascii_alphanumeric() || chars[j] == '_') {
                j += 1;
            }
            // Julia names may go on with `!` or Unicode letters: keep them in
            // the token so that the name is refused whole, not misread.
            while j < chars.len()
                && (chars[j] == '!' && chars.get(j + 1) != Some(&'=')
                    || !chars[j].is_ascii() && chars[j].is_alphanumeric())
            {
                j += 1;
            }
            Tok::Ident(chars[i..j].iter().collect())
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            j = i;
            while j < chars.len() && chars[j].is_ascii_digit() {
                j += 1;
            }
            if chars.get(j) == Some(&'.') && chars.get(j + 1).is_none_or(|d| d.is_ascii_digit()) {
                j += 1;
                while j < chars.len() && chars[j].is_ascii_digit() {
                    j += 1;
                }
            }
            if matches!(chars.get(j), Some('e' | 'E')) {
                let mut k = j + 1;
                if matches!(chars.get(k), Some('+' | '-')) {
                    k += 1;
                }
                if chars.get(k).is_some_and(char::is_ascii_digit) {
                    while k < chars.len() && chars[k].is_ascii_digit() {
                        k += 1;
                    }
                    j = k;
                }
            }
            Tok::Num(chars[i..j].iter().collect())
        } else if c == '"' {
            let mut s = String::new();
            loop {
                match chars.get(j) {
                    None => return Err(ImportError::at(l0, c0, "unterminated string")),
                    Some('"') => {
                        j += 1;
                        break;
                    }
                    Some('\\') => {
                        if let Some(&e) = chars.get(j + 1) {
                            s.push(e);
                        }
                        j += 2;
                    }
                    Some(&x) => {
                        s.push(x);
                        j += 1;
                    }
                }
            }
            j = j.min(chars.len());
            Tok::Str(s)
        } else if c.is_ascii_punctuation() {
            let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
            if ["=>", "//", "==", "!=", "<=", ">=", "&&", "||", "::"].contains(&two.as_str()) {
                j = i + 2;
                Tok::Punct(two)
            } else {
                Tok::Punct(c.to_string())
            }
        } else {
            Tok::Other(c)
        };
        out.push(Token {
            tok,
            line: l0,
            col: c0,
            spaced,
        });
        step(&mut i, &mut line, &mut col, j);
        spaced = false;
    }
    Ok(out)
}

/// One model found in a file: where its `@ODEmodel(...)` is, its key and the
/// name and citation its Dict gives, and any parameter values set on it.
#[derive(Clone, Debug)]
pub struct SiJlModel {
    /// The Dict key (`:Goodwin`), the variable it was bound to, or `model_N`.
    pub key: String,
    pub name: Option<String>,
    pub cite: Option<String>,
    /// 1-based line and column of `@ODEmodel`.
    pub line: usize,
    pub col: usize,
    /// Token range of the macro's arguments (inside its parentheses).
    args: (usize, usize),
    /// `set_parameter_values`: name -> value tokens range.
    values: Vec<SetValue>,
    /// A `linear_compartment_model(graph; inputs, outputs, leaks)` call.
    lincomp: Option<Lincomp>,
}

/// One `p => VALUE` of `set_parameter_values`: the name, its place, the value's token range.
type SetValue = (String, (usize, usize), (usize, usize));

/// SI.jl's `linear_compartment_model`: `graph[i]` lists the compartments
/// that compartment i flows into (rate `a_j_i`); leaks `a_0_i`, inputs `u_i`
/// added to `x_i'`, outputs `y_i = x_i` (SI.jl's src/lincomp.jl).
#[derive(Clone, Debug, Default)]
struct Lincomp {
    graph: Vec<Vec<usize>>,
    inputs: Vec<usize>,
    outputs: Vec<usize>,
    leaks: Vec<usize>,
}

/// A Julia vector of integers `[1, 2]` at `toks[open]` (`[`).
fn int_list(toks: &[Token], open: usize, close: usize) -> Result<Vec<usize>, ImportError> {
    let mut out = Vec::new();
    for (a, b) in items(toks, open, close) {
        match (&toks[a].tok, b == a + 1) {
            (Tok::Num(n), true) => out.push(
                n.parse()
                    .map_err(|_| err(&toks[a], format!("'{n}' is not a compartment number")))?,
            ),
            _ => return Err(err(&toks[a], "expected a compartment number")),
        }
    }
    Ok(out)
}

fn lincomp_at(toks: &[Token], k: usize) -> Result<Option<(Lincomp, usize)>, ImportError> {
    if !(ident(toks.get(k)) == Some("linear_compartment_model") && is_punct(toks.get(k + 1), "(")) {
        return Ok(None);
    }
    let close = closing(toks, k + 1)?;
    let mut lc = Lincomp::default();
    for (n, (a, b)) in items(toks, k + 1, close).into_iter().enumerate() {
        if n == 0 {
            if !is_punct(toks.get(a), "[") || closing(toks, a)? + 1 != b {
                return Err(err(&toks[a], "expected the graph, a vector of vectors"));
            }
            for (ia, ib) in items(toks, a, b - 1) {
                if !is_punct(toks.get(ia), "[") || closing(toks, ia)? + 1 != ib {
                    return Err(err(&toks[ia], "expected a vector of compartment numbers"));
                }
                lc.graph.push(int_list(toks, ia, ib - 1)?);
            }
            continue;
        }
        let key = ident(toks.get(a));
        if !(is_punct(toks.get(a + 1), "=") && is_punct(toks.get(a + 2), "[")) {
            return Err(err(
                &toks[a],
                "expected 'inputs = [...]', 'outputs = [...]' or 'leaks = [...]'",
            ));
        }
        let l = int_list(toks, a + 2, b.saturating_sub(1))?;
        match key {
            Some("inputs") => lc.inputs = l,
            Some("outputs") => lc.outputs = l,
            Some("leaks") => lc.leaks = l,
            _ => return Err(err(&toks[a], "expected inputs, outputs or leaks")),
        }
    }
    let n = lc.graph.len();
    for (i, t) in lc
        .graph
        .iter()
        .flatten()
        .chain(&lc.inputs)
        .chain(&lc.outputs)
        .chain(&lc.leaks)
        .map(|i| (*i, &toks[k]))
    {
        if i == 0 || i > n {
            return Err(err(t, format!("compartment {i} is not among 1..{n}")));
        }
    }
    Ok(Some((lc, close + 1)))
}

fn is_punct(t: Option<&Token>, p: &str) -> bool {
    matches!(t, Some(Token { tok: Tok::Punct(q), .. }) if q == p)
}

fn ident(t: Option<&Token>) -> Option<&str> {
    match t {
        Some(Token {
            tok: Tok::Ident(s), ..
        }) => Some(s.as_str()),
        _ => None,
    }
}

/// Index of the `)` (or `]`) closing the bracket at `open`.
fn closing(toks: &[Token], open: usize) -> Result<usize, ImportError> {
    let mut depth = 0usize;
    for (k, t) in toks.iter().enumerate().skip(open) {
        if let Tok::Punct(p) = &t.tok {
            match p.as_str() {
                "(" | "[" | "{" => depth += 1,
                ")" | "]" | "}" => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        return Ok(k);
                    }
                }
                _ => {}
            }
        }
    }
    Err(err(&toks[open], "this bracket is never closed"))
}

/// Top-level items (depth 0) of the bracket `open..close`, split at commas.
fn items(toks: &[Token], open: usize, close: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0usize, open + 1);
    for (k, t) in toks.iter().enumerate().take(close).skip(open + 1) {
        if let Tok::Punct(p) = &t.tok {
            match p.as_str() {
                "(" | "[" | "{" => depth += 1,
                ")" | "]" | "}" => depth = depth.saturating_sub(1),
                "," if depth == 0 => {
                    out.push((start, k));
                    start = k + 1;
                }
                _ => {}
            }
        }
    }
    if start < close {
        out.push((start, close));
    }
    out
}

/// Every model in `text`, in order of appearance. Fails only when the file
/// cannot be tokenized or a model's brackets do not close.
pub fn si_jl_models(text: &str) -> Result<Vec<SiJlModel>, ImportError> {
    let toks = tokenize(text)?;
    let mut out: Vec<SiJlModel> = Vec::new();
    let mut bound: BTreeMap<String, SiJlModel> = BTreeMap::new();
    let mut anon = 0usize;
    let mut i = 0usize;
    // `@ODEmodel(` at k: the model (args range), and the index after it.
    let macro_at = |k: usize| -> Result<Option<(SiJlModel, usize)>, ImportError> {
        if is_punct(toks.get(k), "@")
            && ident(toks.get(k + 1)) == Some("ODEmodel")
            && is_punct(toks.get(k + 2), "(")
        {
            let close = closing(&toks, k + 2)?;
            Ok(Some((
                SiJlModel {
                    key: String::new(),
                    name: None,
                    cite: None,
                    line: toks[k].line,
                    col: toks[k].col,
                    args: (k + 3, close),
                    values: Vec::new(),
                    lincomp: None,
                },
                close + 1,
            )))
        } else {
            Ok(None)
        }
    };
    while i < toks.len() {
        // `:KEY => Dict(` or `NAME[:KEY] = Dict(`
        let dict = if is_punct(toks.get(i), ":")
            && ident(toks.get(i + 1)).is_some()
            && is_punct(toks.get(i + 2), "=>")
            && ident(toks.get(i + 3)) == Some("Dict")
            && is_punct(toks.get(i + 4), "(")
        {
            Some((
                ident(toks.get(i + 1)).unwrap_or_default().to_string(),
                i + 4,
            ))
        } else if ident(toks.get(i)).is_some()
            && is_punct(toks.get(i + 1), "[")
            && is_punct(toks.get(i + 2), ":")
            && ident(toks.get(i + 3)).is_some()
            && is_punct(toks.get(i + 4), "]")
            && is_punct(toks.get(i + 5), "=")
            && ident(toks.get(i + 6)) == Some("Dict")
            && is_punct(toks.get(i + 7), "(")
        {
            Some((
                ident(toks.get(i + 3)).unwrap_or_default().to_string(),
                i + 7,
            ))
        } else {
            None
        };
        if let Some((key, open)) = dict {
            let close = closing(&toks, open)?;
            let (mut name, mut cite, mut model) = (None, None, None);
            for (a, b) in items(&toks, open, close) {
                if !(is_punct(toks.get(a), ":") && is_punct(toks.get(a + 2), "=>")) {
                    continue;
                }
                let v = a + 3;
                match (ident(toks.get(a + 1)), toks.get(v).map(|t| &t.tok)) {
                    (Some("name"), Some(Tok::Str(s))) => name = Some(s.clone()),
                    (Some("cite"), Some(Tok::Str(s))) => cite = Some(s.clone()),
                    (Some("ode"), _) => {
                        if let Some((m, _)) = macro_at(v)? {
                            model = Some(m);
                        } else if let Some((lc, _)) = lincomp_at(&toks, v)? {
                            model = Some(SiJlModel {
                                key: String::new(),
                                name: None,
                                cite: None,
                                line: toks[v].line,
                                col: toks[v].col,
                                args: (v, v),
                                values: Vec::new(),
                                lincomp: Some(lc),
                            });
                        } else if let (Some(var), true) = (ident(toks.get(v)), v + 1 == b) {
                            model = bound.get(var).cloned();
                        }
                    }
                    _ => {}
                }
            }
            if let Some(mut m) = model {
                if cite.as_deref() == Some("") {
                    cite = None;
                }
                m.key = key;
                m.name = name;
                m.cite = cite;
                out.push(m);
                i = close + 1;
                continue;
            }
        }
        // `VAR = @ODEmodel(...)` and `VAR = set_parameter_values(SRC, Dict(...))`
        if let (Some(var), true) = (ident(toks.get(i)), is_punct(toks.get(i + 1), "=")) {
            if let Some((mut m, next)) = macro_at(i + 2)? {
                m.key = var.to_string();
                bound.insert(var.to_string(), m);
                i = next;
                continue;
            }
            if ident(toks.get(i + 2)) == Some("set_parameter_values")
                && is_punct(toks.get(i + 3), "(")
            {
                let close = closing(&toks, i + 3)?;
                let args = items(&toks, i + 3, close);
                if let (Some(&(a0, b0)), Some(&(a1, _))) = (args.first(), args.get(1)) {
                    let src = ident(toks.get(a0)).filter(|_| b0 == a0 + 1);
                    if let (Some(mut m), true, true) = (
                        src.and_then(|s| bound.get(s).cloned()),
                        ident(toks.get(a1)) == Some("Dict"),
                        is_punct(toks.get(a1 + 1), "("),
                    ) {
                        let dclose = closing(&toks, a1 + 1)?;
                        for (a, b) in items(&toks, a1 + 1, dclose) {
                            let Some(p) = ident(toks.get(a)) else {
                                return Err(err(&toks[a], "expected 'parameter => value'"));
                            };
                            if !is_punct(toks.get(a + 1), "=>") || a + 2 >= b {
                                return Err(err(&toks[a], "expected 'parameter => value'"));
                            }
                            m.values
                                .push((p.to_string(), (toks[a].line, toks[a].col), (a + 2, b)));
                        }
                        m.key = var.to_string();
                        bound.insert(var.to_string(), m);
                        i = close + 1;
                        continue;
                    }
                }
            }
        }
        if let Some((mut m, next)) = macro_at(i)? {
            anon += 1;
            m.key = format!("model_{anon}");
            out.push(m);
            i = next;
            continue;
        }
        i += 1;
    }
    // Models bound to a variable and never put in a Dict are models too.
    for (var, mut m) in bound {
        if !out.iter().any(|o| o.args == m.args) {
            m.key = var;
            out.push(m);
        }
    }
    out.sort_by_key(|m| (m.line, m.col, m.key.clone()));
    out.dedup_by(|a, b| a.key == b.key && a.args == b.args);
    Ok(out)
}

// ---- expressions ----

#[derive(Clone, Debug)]
pub(crate) enum Ex {
    Num(String),
    /// A name; `timed` when written `name(t)`.
    Name {
        name: String,
        timed: bool,
        at: (usize, usize),
    },
    Neg(Box<Ex>),
    Bin(char, Box<Ex>, Box<Ex>),
    Call(String, Vec<Ex>),
}

const FUNCS: [&str; 7] = ["exp", "log", "sin", "cos", "tan", "atan", "sqrt"];
const MAX_DEPTH: usize = 200;

struct P<'a> {
    toks: &'a [Token],
    i: usize,
    end: usize,
    depth: usize,
}

impl P<'_> {
    fn peek(&self) -> Option<&Token> {
        if self.i < self.end {
            self.toks.get(self.i)
        } else {
            None
        }
    }
    /// The token at the cursor (the delimiter after the expression when it ran out).
    fn here(&self) -> &Token {
        let k = self.i.min(self.toks.len().saturating_sub(1));
        &self.toks[k]
    }
    fn eat(&mut self, p: &str) -> bool {
        if is_punct(self.peek(), p) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    fn deeper(&mut self) -> Result<(), ImportError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(err(self.here(), "expression nested too deeply"));
        }
        Ok(())
    }
    fn sum(&mut self) -> Result<Ex, ImportError> {
        self.deeper()?;
        let mut a = self.product()?;
        loop {
            let op = if self.eat("+") {
                '+'
            } else if self.eat("-") {
                '-'
            } else {
                break;
            };
            let b = self.product()?;
            a = Ex::Bin(op, Box::new(a), Box::new(b));
        }
        self.depth -= 1;
        Ok(a)
    }
    fn product(&mut self) -> Result<Ex, ImportError> {
        let mut a = self.rational()?;
        loop {
            let op = if self.eat("*") {
                '*'
            } else if self.eat("/") {
                '/'
            } else {
                break;
            };
            let b = self.rational()?;
            a = Ex::Bin(op, Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    /// Julia's `//` binds tighter than `*` and `/`.
    fn rational(&mut self) -> Result<Ex, ImportError> {
        let mut a = self.unary()?;
        while self.eat("//") {
            let b = self.unary()?;
            a = Ex::Bin('/', Box::new(a), Box::new(b));
        }
        Ok(a)
    }
    /// Unary minus binds looser than `^` (`-x^2` is `-(x^2)`), as in Julia.
    fn unary(&mut self) -> Result<Ex, ImportError> {
        if self.eat("-") {
            self.deeper()?;
            let a = self.unary()?;
            self.depth -= 1;
            return Ok(Ex::Neg(Box::new(a)));
        }
        if self.eat("+") {
            self.deeper()?;
            let a = self.unary();
            self.depth -= 1;
            return a;
        }
        self.power()
    }
    fn power(&mut self) -> Result<Ex, ImportError> {
        let base = self.atom()?;
        if self.eat("^") {
            self.deeper()?;
            let e = self.unary()?;
            self.depth -= 1;
            return Ok(Ex::Bin('^', Box::new(base), Box::new(e)));
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<Ex, ImportError> {
        let Some(t) = self.peek().cloned() else {
            return Err(err(self.here(), "expected an expression"));
        };
        self.i += 1;
        let a = match &t.tok {
            Tok::Num(n) => Ex::Num(n.clone()),
            Tok::Punct(p) if p == "(" => {
                let e = self.sum()?;
                if !self.eat(")") {
                    return Err(err(self.here(), "expected ')'"));
                }
                e
            }
            Tok::Ident(name) => {
                if !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                    return Err(err(
                        &t,
                        format!("'{name}' is not an ASCII name: .sys names are ASCII (rename it)"),
                    ));
                }
                if is_punct(self.peek(), "(") && !self.peek().is_some_and(|x| x.spaced) {
                    self.i += 1;
                    let open = self.i - 1;
                    let close = closing(self.toks, open)?;
                    if close >= self.end {
                        return Err(err(&self.toks[open], "this '(' is never closed"));
                    }
                    let is_t = close == open + 2 && ident(self.toks.get(open + 1)) == Some("t");
                    if (FUNCS.contains(&name.as_str()) || name == "QQ") && !is_t {
                        let mut args = Vec::new();
                        for (a, b) in items(self.toks, open, close) {
                            let mut sub = P {
                                toks: self.toks,
                                i: a,
                                end: b,
                                depth: self.depth,
                            };
                            args.push(sub.whole()?);
                        }
                        self.i = close + 1;
                        if name == "QQ" {
                            // Nemo's rational constructor: QQ(a) or QQ(a, b).
                            let mut it = args.into_iter();
                            match (it.next(), it.next(), it.next()) {
                                (Some(a), None, None) => a,
                                (Some(a), Some(b), None) => Ex::Bin('/', Box::new(a), Box::new(b)),
                                _ => return Err(err(&t, "QQ takes one or two arguments")),
                            }
                        } else if args.len() != 1 {
                            return Err(err(&t, format!("{name} takes one argument")));
                        } else {
                            Ex::Call(name.clone(), args)
                        }
                    } else if is_t {
                        self.i = close + 1;
                        Ex::Name {
                            name: name.clone(),
                            timed: true,
                            at: (t.line, t.col),
                        }
                    } else {
                        return Err(err(
                            &t,
                            format!(
                                "'{name}(...)': a function of time is written '{name}(t)'; \
                                 the functions read are {}",
                                FUNCS.join(", ")
                            ),
                        ));
                    }
                } else if name == "pi" || name == "π" {
                    Ex::Num("pi".into())
                } else {
                    Ex::Name {
                        name: name.clone(),
                        timed: false,
                        at: (t.line, t.col),
                    }
                }
            }
            Tok::Other(c) => return Err(err(&t, format!("unexpected character '{c}'"))),
            _ => return Err(err(&t, "expected an expression")),
        };
        // Julia's juxtaposition `2x`, `2(x + 1)`: a number followed directly by a name or '('.
        if let (Ex::Num(_), Some(n)) = (&a, self.peek()) {
            if !n.spaced && (matches!(&n.tok, Tok::Ident(_)) || is_punct(Some(n), "(")) {
                let b = self.power()?;
                return Ok(Ex::Bin('*', Box::new(a), Box::new(b)));
            }
        }
        Ok(a)
    }
    /// An expression that must use every token up to `end`.
    fn whole(&mut self) -> Result<Ex, ImportError> {
        let e = self.sum()?;
        if let Some(t) = self.peek() {
            return Err(err(t, "unexpected text after the expression"));
        }
        Ok(e)
    }
}

fn prec(e: &Ex) -> u8 {
    match e {
        Ex::Bin('+' | '-', ..) => 1,
        Ex::Bin('*' | '/', ..) => 2,
        // Wrapped wherever it is not the first term of a sum: `a - (-b)`, `(-a)*b`.
        Ex::Neg(_) => 1,
        Ex::Bin(..) => 4,
        _ => 5,
    }
}

/// `.sys` text of `e`; names mapped by `name`, values substituted by `value`.
pub(crate) fn show(e: &Ex, out: &mut String, map: &dyn Fn(&str) -> String) {
    let wrap = |x: &Ex, min: u8, out: &mut String| {
        if prec(x) < min {
            out.push('(');
            show(x, out, map);
            out.push(')');
        } else {
            show(x, out, map);
        }
    };
    match e {
        Ex::Num(n) => out.push_str(n),
        Ex::Name { name, .. } => out.push_str(&map(name)),
        Ex::Neg(a) => {
            out.push('-');
            wrap(a, 3, out);
        }
        Ex::Bin(op, a, b) => {
            let (l, r) = match op {
                '+' => (1, 2),
                '-' => (1, 2),
                '*' => (2, 3),
                '/' => (2, 4),
                _ => (5, 4),
            };
            // -a*b reads as -(a*b): the same value, so a negated left factor needs no parentheses.
            if matches!((op, &**a), ('*' | '/', Ex::Neg(_))) {
                show(a, out, map);
            } else {
                wrap(a, l, out);
            }
            match op {
                '+' => out.push_str(" + "),
                '-' => out.push_str(" - "),
                c => out.push(*c),
            }
            wrap(b, r, out);
        }
        Ex::Call(f, args) => {
            out.push_str(f);
            out.push('(');
            for (k, a) in args.iter().enumerate() {
                if k > 0 {
                    out.push_str(", ");
                }
                show(a, out, map);
            }
            out.push(')');
        }
    }
}

/// Names a `.sys` file cannot use: its keywords, functions and constants.
pub(crate) const RESERVED: [&str; 23] = [
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
    "sin",
    "cos",
    "tan",
    "atan",
    "atan2",
    "exp",
    "log",
    "sqrt",
    "pi",
    "rate",
];

/// Rename bare uses of a name that is also written `name(t)`: `name_p`.
fn rename_bare(
    e: &mut Ex,
    timed_names: &[String],
    all: &[String],
    split: &mut BTreeMap<String, String>,
) {
    match e {
        Ex::Name { name, timed, .. } => {
            if !*timed && timed_names.iter().any(|x| x == name) {
                let new = split.entry(name.clone()).or_insert_with(|| {
                    let mut m = format!("{name}_p");
                    while all.contains(&m) {
                        m.push('_');
                    }
                    m
                });
                *name = new.clone();
            }
        }
        Ex::Neg(a) => rename_bare(a, timed_names, all, split),
        Ex::Bin(_, a, b) => {
            rename_bare(a, timed_names, all, split);
            rename_bare(b, timed_names, all, split);
        }
        Ex::Call(_, args) => args
            .iter_mut()
            .for_each(|a| rename_bare(a, timed_names, all, split)),
        Ex::Num(_) => {}
    }
}

fn walk<'a>(e: &'a Ex, f: &mut dyn FnMut(&'a str, bool, (usize, usize))) {
    match e {
        Ex::Name { name, timed, at } => f(name, *timed, *at),
        Ex::Neg(a) => walk(a, f),
        Ex::Bin(_, a, b) => {
            walk(a, f);
            walk(b, f);
        }
        Ex::Call(_, args) => args.iter().for_each(|a| walk(a, f)),
        Ex::Num(_) => {}
    }
}

/// Translate one model of `text` (found by [`si_jl_models`]) into `.sys`
/// text. `origin` names the file in the header comment.
pub fn si_jl_convert(
    text: &str,
    model: &SiJlModel,
    origin: &str,
) -> Result<Converted, ImportError> {
    if let Some(lc) = &model.lincomp {
        return Ok(lincomp_sys(lc, model, origin));
    }
    let toks = tokenize(text)?;
    let (a, b) = model.args;
    if b > toks.len() || a > b || a == 0 {
        return Err(ImportError::at(
            model.line,
            model.col,
            "model not found in this text",
        ));
    }
    // Equations: (lhs name, is state, lhs token, rhs).
    let mut eqs: Vec<(String, bool, Token, Ex)> = Vec::new();
    for (s, e) in items(&toks, a - 1, b) {
        let t0 = &toks[s];
        let Some(name) = ident(Some(t0)) else {
            return Err(err(
                t0,
                "expected an equation 'x'(t) = ...' or 'y(t) = ...'",
            ));
        };
        let mut k = s + 1;
        let state = is_punct(toks.get(k), "'");
        if state {
            k += 1;
        }
        if !(is_punct(toks.get(k), "(")
            && ident(toks.get(k + 1)) == Some("t")
            && is_punct(toks.get(k + 2), ")")
            && is_punct(toks.get(k + 3), "="))
            || k + 4 >= e
        {
            return Err(err(
                t0,
                format!("expected '{name}'(t) = EXPR' (a state) or '{name}(t) = EXPR' (an output)"),
            ));
        }
        let mut p = P {
            toks: &toks,
            i: k + 4,
            end: e,
            depth: 0,
        };
        let rhs = p.whole()?;
        if eqs.iter().any(|(n, _, _, _)| n == name) {
            return Err(err(t0, format!("'{name}' has two equations")));
        }
        eqs.push((name.to_string(), state, t0.clone(), rhs));
    }
    if !eqs.iter().any(|q| q.1) {
        return Err(ImportError::at(
            model.line,
            model.col,
            "the model has no state equation",
        ));
    }
    if !eqs.iter().any(|q| !q.1) {
        return Err(ImportError::at(
            model.line,
            model.col,
            "the model has no output",
        ));
    }
    // SI.jl reads `q(t)` (a state or an input) and a bare `q` (a parameter)
    // as two variables: the bare one is renamed `q_p` here.
    let mut timed_names: Vec<String> = eqs.iter().filter(|q| q.1).map(|q| q.0.clone()).collect();
    for (_, _, _, rhs) in &eqs {
        walk(rhs, &mut |n, timed, _| {
            if timed && !timed_names.iter().any(|x| x == n) {
                timed_names.push(n.to_string());
            }
        });
    }
    let all_names: Vec<String> = {
        let mut v = timed_names.clone();
        for (n, ..) in &eqs {
            v.push(n.clone());
        }
        for (_, _, _, rhs) in &eqs {
            walk(rhs, &mut |n, _, _| v.push(n.to_string()));
        }
        v
    };
    let mut split: BTreeMap<String, String> = BTreeMap::new();
    for (_, _, _, rhs) in eqs.iter_mut() {
        rename_bare(rhs, &timed_names, &all_names, &mut split);
    }
    let eqs = eqs;
    let states: Vec<&str> = eqs.iter().filter(|q| q.1).map(|q| q.0.as_str()).collect();
    let outputs: Vec<&str> = eqs.iter().filter(|q| !q.1).map(|q| q.0.as_str()).collect();
    // Parameter values set on the model.
    let mut values: BTreeMap<String, Ex> = BTreeMap::new();
    for (p, (l, c), (va, vb)) in &model.values {
        let mut pp = P {
            toks: &toks,
            i: *va,
            end: *vb,
            depth: 0,
        };
        let v = pp.whole()?;
        let mut bad = None;
        walk(&v, &mut |n, _, at| {
            if bad.is_none() {
                bad = Some((n.to_string(), at));
            }
        });
        if let Some((n, (l2, c2))) = bad {
            return Err(ImportError::at(
                l2,
                c2,
                format!("the value of '{p}' uses '{n}': values must be numbers"),
            ));
        }
        if states.contains(&p.as_str()) || outputs.contains(&p.as_str()) {
            return Err(ImportError::at(
                *l,
                *c,
                format!("'{p}' is a state or an output, not a parameter"),
            ));
        }
        values.insert(p.clone(), v);
    }
    let mut params: Vec<String> = Vec::new();
    let mut inputs: Vec<String> = Vec::new();
    for (_, _, _, rhs) in &eqs {
        let mut bad: Option<ImportError> = None;
        walk(rhs, &mut |n, timed, (l, c)| {
            if bad.is_some() {
                return;
            }
            let is_state = states.contains(&n);
            if outputs.contains(&n) {
                bad = Some(ImportError::at(
                    l,
                    c,
                    format!("the output '{n}' is used in an equation"),
                ));
            } else if timed && !is_state {
                if !inputs.iter().any(|x| x == n) {
                    inputs.push(n.to_string());
                }
            } else if !timed && n == "t" {
                bad = Some(ImportError::at(l, c, "time 't' itself is not supported (non-autonomous models are outside obsan's class; add a clock state t'(t) = 1)"));
            } else if !timed && values.contains_key(n) {
                // substituted below
            } else if !timed && !params.iter().any(|x| x == n) {
                params.push(n.to_string());
            }
        });
        if let Some(e) = bad {
            return Err(e);
        }
    }
    // .sys names: reserved words get a trailing '_' (unique).
    let mut taken: Vec<String> = states
        .iter()
        .chain(&outputs)
        .map(|s| s.to_string())
        .chain(params.iter().cloned())
        .chain(inputs.iter().cloned())
        .collect();
    let mut renamed: BTreeMap<String, String> = split
        .iter()
        .map(|(a, b)| (format!("{a} (bare)"), b.clone()))
        .collect();
    for n in taken.clone() {
        if RESERVED.contains(&n.as_str()) {
            let mut m = format!("{n}_");
            while taken.contains(&m) {
                m.push('_');
            }
            taken.push(m.clone());
            renamed.insert(n, m);
        }
    }
    let mut value_text: BTreeMap<String, String> = BTreeMap::new();
    for (p, v) in &values {
        let mut s = String::new();
        show(v, &mut s, &|n| n.to_string());
        value_text.insert(p.clone(), s);
    }
    let map = |n: &str| -> String {
        if let Some(v) = value_text.get(n) {
            if v.chars().all(|c| c.is_ascii_digit() || c == '.') {
                v.clone()
            } else {
                format!("({v})")
            }
        } else {
            renamed.get(n).cloned().unwrap_or_else(|| n.to_string())
        }
    };
    let sysname = sys_name(&model.key);
    let one_line = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut lines = header(model, origin, "");
    let mut line_map = Vec::new();
    if !renamed.is_empty() {
        let r: Vec<String> = renamed.iter().map(|(a, b)| format!("{a} -> {b}")).collect();
        lines.push(format!(
            "# renamed (reserved in .sys, or one name used both with and without (t)): {}",
            r.join(", ")
        ));
    }
    if !value_text.is_empty() {
        let r: Vec<String> = value_text
            .iter()
            .map(|(a, b)| format!("{a} = {b}"))
            .collect();
        lines.push(format!(
            "# parameter values set in the source (substituted): {}",
            r.join(", ")
        ));
    }
    lines.push(format!("system {sysname}"));
    if let Some(n) = &model.name {
        let n = one_line(n);
        if !n.is_empty() {
            lines.push(format!("description {n}"));
        }
    }
    let list = |v: Vec<String>| v.join(", ");
    lines.push(format!(
        "state {}",
        list(states.iter().map(|s| map(s)).collect())
    ));
    if !params.is_empty() {
        lines.push(format!(
            "param {}",
            list(params.iter().map(|s| map(s)).collect())
        ));
    }
    if !inputs.is_empty() {
        lines.push(format!(
            "input {}",
            list(inputs.iter().map(|s| map(s)).collect())
        ));
    }
    for (name, state, t0, rhs) in &eqs {
        let mut s = String::new();
        show(rhs, &mut s, &map);
        lines.push(if *state {
            format!("{}' = {s}", map(name))
        } else {
            format!("output {} = {s}", map(name))
        });
        line_map.push((lines.len(), t0.line, t0.col));
    }
    let mut sys_text = lines.join("\n");
    sys_text.push('\n');
    Ok(Converted {
        name: sysname,
        sys_text,
        line_map,
        table_lines: Vec::new(),
    })
}

fn header(model: &SiJlModel, origin: &str, what: &str) -> Vec<String> {
    let one_line = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut lines = vec![format!(
        "# Imported by `obsan import si-jl` from {}, model :{} (line {}){}.",
        one_line(origin),
        model.key,
        model.line,
        model
            .name
            .as_ref()
            .map_or(String::new(), |n| format!(", \"{}\"", one_line(n)))
    )];
    if let Some(c) = &model.cite {
        lines.push(format!("# cite: {}", one_line(c)));
    }
    if !what.is_empty() {
        lines.push(format!("# {what}"));
    }
    lines
}

fn sys_name(key: &str) -> String {
    let mut s: String = key
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if !s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        s.insert(0, '_');
    }
    if RESERVED.contains(&s.as_str()) {
        s.push('_');
    }
    s
}

fn lincomp_sys(lc: &Lincomp, model: &SiJlModel, origin: &str) -> Converted {
    let n = lc.graph.len();
    let mut lines = header(
        model,
        origin,
        "linear_compartment_model expanded as SI.jl's src/lincomp.jl does: x_j' gains a_j_i*x_i, x_i' loses it.",
    );
    let name = sys_name(&model.key);
    lines.push(format!("system {name}"));
    if let Some(d) = &model.name {
        lines.push(format!(
            "description {}",
            d.split_whitespace().collect::<Vec<_>>().join(" ")
        ));
    }
    let mut rhs: Vec<Vec<String>> = vec![Vec::new(); n];
    let mut params = Vec::new();
    for (i, outs) in lc.graph.iter().enumerate() {
        for &j in outs {
            let a = format!("a_{j}_{}", i + 1);
            rhs[j - 1].push(format!("+ {a}*x{}", i + 1));
            rhs[i].push(format!("- {a}*x{}", i + 1));
            params.push(a);
        }
    }
    for &l in &lc.leaks {
        let a = format!("a_0_{l}");
        rhs[l - 1].push(format!("- {a}*x{l}"));
        params.push(a);
    }
    for &u in &lc.inputs {
        rhs[u - 1].push(format!("+ u{u}"));
    }
    params.dedup();
    let states: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    lines.push(format!("state {}", states.join(", ")));
    if !params.is_empty() {
        lines.push(format!("param {}", params.join(", ")));
    }
    if !lc.inputs.is_empty() {
        let u: Vec<String> = lc.inputs.iter().map(|i| format!("u{i}")).collect();
        lines.push(format!("input {}", u.join(", ")));
    }
    let mut line_map = Vec::new();
    for (i, terms) in rhs.iter().enumerate() {
        let mut t = terms.join(" ");
        if let Some(r) = t.strip_prefix("+ ") {
            t = r.to_string();
        } else if let Some(r) = t.strip_prefix("- ") {
            t = format!("-{r}");
        }
        if t.is_empty() {
            t = "0".into();
        }
        lines.push(format!("x{}' = {t}", i + 1));
        line_map.push((lines.len(), model.line, model.col));
    }
    for &o in &lc.outputs {
        lines.push(format!("output y{o} = x{o}"));
    }
    let mut sys_text = lines.join("\n");
    sys_text.push('\n');
    Converted {
        name,
        sys_text,
        line_map,
        table_lines: Vec::new(),
    }
}
