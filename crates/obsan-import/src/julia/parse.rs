//! Julia expressions inside `@ODEmodel` and `set_parameter_values`, read
//! into the shared [`Ex`] tree (precedence as Julia's).

use super::lex::{closing, err, ident, is_punct, items, Tok, Token};
use crate::ex::Ex;
use crate::ImportError;
use std::collections::BTreeMap;

const FUNCS: [&str; 7] = ["exp", "log", "sin", "cos", "tan", "atan", "sqrt"];
const MAX_DEPTH: usize = 200;

pub(super) struct P<'a> {
    pub(super) toks: &'a [Token],
    pub(super) i: usize,
    pub(super) end: usize,
    pub(super) depth: usize,
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
    // Parallel to infix.rs's descent but apart: it reads julia/lex.rs's
    // tokens, not characters, and has Julia's levels (`//` above `*`).
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
    pub(super) fn whole(&mut self) -> Result<Ex, ImportError> {
        let e = self.sum()?;
        if let Some(t) = self.peek() {
            return Err(err(t, "unexpected text after the expression"));
        }
        Ok(e)
    }
}

/// Rename bare uses of a name that is also written `name(t)`: `name_p`.
pub(super) fn rename_bare(
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

pub(super) fn walk<'a>(e: &'a Ex, f: &mut dyn FnMut(&'a str, bool, (usize, usize))) {
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
