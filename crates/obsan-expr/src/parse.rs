//! Infix expressions: a hand-written lexer and a Pratt parser producing a
//! spanned syntax tree, then a builder that lowers it into a [`Ctx`].
//!
//! Grammar: numbers (integers and decimals, read as exact rationals, with an
//! optional exponent `1.5e-3`), identifiers, `+ - * / ^`, unary minus,
//! parentheses, `pi`, and the functions `sin cos tan atan atan2 exp log sqrt`.
//! `^` is right-associative and binds tighter than unary minus: `-x^2 = -(x^2)`.
//!
//! Depth: parentheses, unary signs, powers and calls nest at most
//! [`MAX_DEPTH`] deep (the parser recurses once per level), and a long flat
//! chain such as a sum of 100,000 terms is read in a loop and stored as a
//! balanced tree, so the tree is at most [`MAX_HEIGHT`] high and every
//! recursive pass over it (building, dropping, evaluating) stays shallow.

use crate::budget::Limit;
use crate::graph::Id;
use crate::memo::Ctx;
use crate::num::{int, Int, Q};
use std::fmt;

/// Byte range in the source text (use [`line_col`] for a line and a column in characters).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl Span {
    pub fn new(start: usize, end: usize) -> Span {
        Span { start, end }
    }
    pub fn join(self, o: Span) -> Span {
        Span {
            start: self.start.min(o.start),
            end: self.end.max(o.end),
        }
    }
    pub fn shift(self, by: usize) -> Span {
        Span {
            start: self.start + by,
            end: self.end + by,
        }
    }
}

/// An error at a place in the source.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ParseError {
    pub message: String,
    pub span: Span,
    /// Set when the text is well formed but building it reached a limit of
    /// the budget (size, degree, deadline): the input is not wrong, only
    /// larger than the engine was allowed to go.
    pub limit: Option<Limit>,
}

impl ParseError {
    pub fn new(message: impl Into<String>, span: Span) -> ParseError {
        ParseError {
            message: message.into(),
            span,
            limit: None,
        }
    }

    /// A budget limit reached while building well-formed text.
    pub fn from_limit(limit: Limit, span: Span) -> ParseError {
        ParseError {
            message: limit.to_string(),
            span,
            limit: Some(limit),
        }
    }
}

impl fmt::Display for ParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}
impl std::error::Error for ParseError {}

/// 1-based line and column (in characters) of a byte offset.
/// An offset inside a multi-byte character counts as that character's start.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(src.len());
    while !src.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &src[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Binary operators.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
}

/// The functions the language knows, with their arity.
pub const FUNCTIONS: [(&str, usize); 8] = [
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("atan", 1),
    ("atan2", 2),
    ("exp", 1),
    ("log", 1),
    ("sqrt", 1),
];

/// A syntax tree node with its span.
#[derive(Clone, Debug, PartialEq)]
pub struct Ast {
    pub kind: AstKind,
    pub span: Span,
}

#[derive(Clone, Debug, PartialEq)]
pub enum AstKind {
    Num(Q),
    Pi,
    Ident(String),
    Neg(Box<Ast>),
    Bin(BinOp, Box<Ast>, Box<Ast>),
    Call(String, Vec<Ast>),
}

impl Ast {
    /// Every identifier (not function names), with its span.
    pub fn idents(&self) -> Vec<(&str, Span)> {
        let mut out = Vec::new();
        let mut stack = vec![self];
        while let Some(a) = stack.pop() {
            match &a.kind {
                AstKind::Ident(n) => out.push((n.as_str(), a.span)),
                AstKind::Neg(x) => stack.push(x),
                AstKind::Bin(_, l, r) => {
                    stack.push(r);
                    stack.push(l);
                }
                AstKind::Call(_, args) => stack.extend(args.iter().rev()),
                AstKind::Num(_) | AstKind::Pi => {}
            }
        }
        out
    }

    /// The top-level additive terms, each with its sign (`a - b*c` gives `+a`, `-b*c`).
    pub fn additive_terms(&self) -> Vec<(bool, &Ast)> {
        let mut out = Vec::new();
        fn walk<'a>(a: &'a Ast, neg: bool, out: &mut Vec<(bool, &'a Ast)>) {
            match &a.kind {
                AstKind::Bin(BinOp::Add, l, r) => {
                    walk(l, neg, out);
                    walk(r, neg, out);
                }
                AstKind::Bin(BinOp::Sub, l, r) => {
                    walk(l, neg, out);
                    walk(r, !neg, out);
                }
                AstKind::Neg(x) => walk(x, !neg, out),
                _ => out.push((neg, a)),
            }
        }
        walk(self, false, &mut out);
        out
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(Q),
    Ident(String),
    Op(char),
    LParen,
    RParen,
    Comma,
    End,
}

struct Lexer<'a> {
    src: &'a str,
    pos: usize,
}

impl<'a> Lexer<'a> {
    fn next(&mut self) -> Result<(Tok, Span), ParseError> {
        let b = self.src.as_bytes();
        while self.pos < b.len() && (b[self.pos] as char).is_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        if self.pos >= b.len() {
            return Ok((Tok::End, Span::new(start, start)));
        }
        let c = b[self.pos] as char;
        if c.is_ascii_digit()
            || (c == '.' && b.get(self.pos + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            return self.number(start);
        }
        if c.is_ascii_alphabetic() || c == '_' {
            while self.pos < b.len()
                && ((b[self.pos] as char).is_ascii_alphanumeric() || b[self.pos] == b'_')
            {
                self.pos += 1;
            }
            return Ok((
                Tok::Ident(self.src[start..self.pos].to_string()),
                Span::new(start, self.pos),
            ));
        }
        self.pos += 1;
        let t = match c {
            '+' | '-' | '*' | '/' | '^' => Tok::Op(c),
            '(' => Tok::LParen,
            ')' => Tok::RParen,
            ',' => Tok::Comma,
            _ => {
                let ch = self.src[start..].chars().next().unwrap_or('?');
                self.pos = start + ch.len_utf8();
                let hint = if ch == '=' {
                    " (an equation is not an expression)"
                } else {
                    ""
                };
                return Err(ParseError::new(
                    format!("unexpected character '{ch}'{hint}"),
                    Span::new(start, self.pos),
                ));
            }
        };
        Ok((t, Span::new(start, self.pos)))
    }

    fn number(&mut self, start: usize) -> Result<(Tok, Span), ParseError> {
        let b = self.src.as_bytes();
        let digits = |p: &mut usize| {
            let s = *p;
            while *p < b.len() && b[*p].is_ascii_digit() {
                *p += 1;
            }
            *p - s
        };
        let mut p = self.pos;
        digits(&mut p);
        let int_end = p;
        let mut frac = "";
        if p < b.len() && b[p] == b'.' {
            p += 1;
            let fs = p;
            digits(&mut p);
            frac = &self.src[fs..p];
        }
        let mut exp: i64 = 0;
        if p < b.len() && (b[p] == b'e' || b[p] == b'E') {
            let mut q = p + 1;
            let neg = q < b.len() && b[q] == b'-';
            if q < b.len() && (b[q] == b'-' || b[q] == b'+') {
                q += 1;
            }
            let es = q;
            if digits(&mut q) == 0 {
                return Err(ParseError::new(
                    "malformed number: exponent has no digits",
                    Span::new(start, q),
                ));
            }
            let e: i64 = self.src[es..q].parse().unwrap_or(i64::MAX);
            if e > 400 {
                return Err(ParseError::new(
                    "number exponent out of range",
                    Span::new(start, q),
                ));
            }
            exp = if neg { -e } else { e };
            p = q;
        }
        self.pos = p;
        let span = Span::new(start, p);
        if p < b.len() && ((b[p] as char).is_ascii_alphabetic() || b[p] == b'_') {
            return Err(ParseError::new(
                "a number cannot be followed by a letter (use '*')",
                Span::new(start, p + 1),
            ));
        }
        // Printed canonical forms carry their exact coefficients, which can be
        // long; they must read back (see print.rs), so only absurd lengths are refused.
        if int_end - start + frac.len() > MAX_DIGITS {
            return Err(ParseError::new("number has too many digits", span));
        }
        let mantissa: Int = format!("{}{}", &self.src[start..int_end], frac)
            .parse::<Int>()
            .unwrap_or(int(0));
        let e = exp - frac.len() as i64;
        let ten = int(10);
        let q = if e >= 0 {
            Q::from_int(mantissa * ten.pow(e as usize))
        } else {
            Q::new(mantissa, ten.pow((-e) as usize))
        };
        Ok((Tok::Num(q), span))
    }
}

struct Parser<'a> {
    lex: Lexer<'a>,
    tok: Tok,
    span: Span,
    depth: usize,
}

/// Most digits of a number literal.
pub const MAX_DIGITS: usize = 1_000_000;

/// Deepest nesting of parentheses, signs, powers and calls.
pub const MAX_DEPTH: usize = 500;

/// Highest syntax tree [`parse_ast`] returns (flat chains count log2 of their length).
pub const MAX_HEIGHT: usize = 1000;

/// Chains of `+ -` or `* /` longer than this are stored as balanced trees.
const CHAIN_BALANCE: usize = 32;

/// Whether two operators bind equally tightly (one flat chain).
fn same_level(a: BinOp, b: BinOp) -> bool {
    matches!(
        (a, b),
        (BinOp::Add | BinOp::Sub, BinOp::Add | BinOp::Sub)
            | (BinOp::Mul | BinOp::Div, BinOp::Mul | BinOp::Div)
    )
}

/// A chain `x0 op1 x1 op2 x2 ...` as a tree. Short chains associate to the
/// left as written; long ones become `x0 + (-x1) + ...` or `x0 * (1/x1) * ...`
/// summed pairwise, which the context folds to the same value.
fn fold_chain(first: Ast, rest: Vec<(BinOp, Ast)>) -> Ast {
    if rest.len() < CHAIN_BALANCE {
        let mut lhs = first;
        for (op, rhs) in rest {
            let span = lhs.span.join(rhs.span);
            lhs = Ast {
                kind: AstKind::Bin(op, Box::new(lhs), Box::new(rhs)),
                span,
            };
        }
        return lhs;
    }
    let additive = matches!(rest[0].0, BinOp::Add | BinOp::Sub);
    let join = if additive { BinOp::Add } else { BinOp::Mul };
    let mut level: Vec<Ast> = Vec::with_capacity(rest.len() + 1);
    level.push(first);
    for (op, x) in rest {
        let span = x.span;
        level.push(match op {
            BinOp::Sub => Ast {
                kind: AstKind::Neg(Box::new(x)),
                span,
            },
            BinOp::Div => Ast {
                kind: AstKind::Bin(
                    BinOp::Div,
                    Box::new(Ast {
                        kind: AstKind::Num(Q::one()),
                        span: Span::new(span.start, span.start),
                    }),
                    Box::new(x),
                ),
                span,
            },
            _ => x,
        });
    }
    while level.len() > 1 {
        let mut next = Vec::with_capacity(level.len().div_ceil(2));
        let mut it = level.into_iter();
        while let Some(a) = it.next() {
            next.push(match it.next() {
                Some(b) => {
                    let span = a.span.join(b.span);
                    Ast {
                        kind: AstKind::Bin(join, Box::new(a), Box::new(b)),
                        span,
                    }
                }
                None => a,
            });
        }
        level = next;
    }
    // `level` started non-empty and pairing never empties it.
    level.pop().unwrap_or(Ast {
        kind: AstKind::Num(Q::zero()),
        span: Span::default(),
    })
}

/// Height of a tree, and the span of its deepest node (no recursion).
fn height(a: &Ast) -> (usize, Span) {
    let mut best = (0, a.span);
    let mut stack = vec![(a, 1usize)];
    while let Some((n, h)) = stack.pop() {
        if h > best.0 {
            best = (h, n.span);
        }
        match &n.kind {
            AstKind::Neg(x) => stack.push((x, h + 1)),
            AstKind::Bin(_, l, r) => {
                stack.push((l, h + 1));
                stack.push((r, h + 1));
            }
            AstKind::Call(_, args) => stack.extend(args.iter().map(|x| (x, h + 1))),
            AstKind::Num(_) | AstKind::Pi | AstKind::Ident(_) => {}
        }
    }
    best
}

impl<'a> Parser<'a> {
    fn bump(&mut self) -> Result<(), ParseError> {
        let (t, s) = self.lex.next()?;
        self.tok = t;
        self.span = s;
        Ok(())
    }

    fn expr(&mut self, min_bp: u8) -> Result<Ast, ParseError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(ParseError::new(
                format!("expression nested too deeply (more than {MAX_DEPTH} levels)"),
                self.span,
            ));
        }
        let mut lhs = self.prefix()?;
        while let Some((op, l_bp, r_bp)) = self.infix() {
            if l_bp < min_bp {
                break;
            }
            self.bump()?;
            let rhs = self.expr(r_bp)?;
            if op == BinOp::Pow {
                let span = lhs.span.join(rhs.span);
                lhs = Ast {
                    kind: AstKind::Bin(op, Box::new(lhs), Box::new(rhs)),
                    span,
                };
                continue;
            }
            // The rest of a flat chain at this level, in a loop (no recursion per term).
            let mut rest = vec![(op, rhs)];
            while let Some((op2, _, r_bp2)) = self.infix().filter(|t| same_level(t.0, op)) {
                self.bump()?;
                rest.push((op2, self.expr(r_bp2)?));
            }
            lhs = fold_chain(lhs, rest);
        }
        self.depth -= 1;
        Ok(lhs)
    }

    /// The current token as an infix operator with its binding powers.
    fn infix(&self) -> Option<(BinOp, u8, u8)> {
        Some(match self.tok {
            Tok::Op('+') => (BinOp::Add, 1, 2),
            Tok::Op('-') => (BinOp::Sub, 1, 2),
            Tok::Op('*') => (BinOp::Mul, 3, 4),
            Tok::Op('/') => (BinOp::Div, 3, 4),
            Tok::Op('^') => (BinOp::Pow, 8, 7),
            _ => return None,
        })
    }

    fn prefix(&mut self) -> Result<Ast, ParseError> {
        let span = self.span;
        match self.tok.clone() {
            Tok::Num(q) => {
                self.bump()?;
                Ok(Ast {
                    kind: AstKind::Num(q),
                    span,
                })
            }
            Tok::Op('-') => {
                self.bump()?;
                let x = self.expr(5)?;
                let s = span.join(x.span);
                Ok(Ast {
                    kind: AstKind::Neg(Box::new(x)),
                    span: s,
                })
            }
            Tok::Op('+') => {
                self.bump()?;
                self.expr(5)
            }
            Tok::LParen => {
                self.bump()?;
                let inner = self.expr(0)?;
                if self.tok != Tok::RParen {
                    return Err(ParseError::new(
                        "expected ')' to close this '('",
                        span.join(self.span),
                    ));
                }
                let end = self.span;
                self.bump()?;
                Ok(Ast {
                    kind: inner.kind,
                    span: span.join(end),
                })
            }
            Tok::Ident(name) => {
                self.bump()?;
                if self.tok == Tok::LParen {
                    return self.call(name, span);
                }
                if name == "pi" {
                    return Ok(Ast {
                        kind: AstKind::Pi,
                        span,
                    });
                }
                if FUNCTIONS.iter().any(|(f, _)| *f == name) {
                    return Err(ParseError::new(
                        format!("function '{name}' needs an argument list: {name}(...)"),
                        span,
                    ));
                }
                Ok(Ast {
                    kind: AstKind::Ident(name),
                    span,
                })
            }
            Tok::End => Err(ParseError::new("unexpected end of expression", span)),
            Tok::RParen => Err(ParseError::new("unexpected ')'", span)),
            Tok::Comma => Err(ParseError::new("unexpected ','", span)),
            Tok::Op(c) => Err(ParseError::new(format!("unexpected operator '{c}'"), span)),
        }
    }

    fn call(&mut self, name: String, name_span: Span) -> Result<Ast, ParseError> {
        let Some(&(_, arity)) = FUNCTIONS.iter().find(|(f, _)| *f == name) else {
            let known: Vec<&str> = FUNCTIONS.iter().map(|f| f.0).collect();
            return Err(ParseError::new(
                format!("unknown function '{name}' (known: {})", known.join(", ")),
                name_span,
            ));
        };
        self.bump()?; // '('
        let mut args = Vec::new();
        if self.tok != Tok::RParen {
            loop {
                args.push(self.expr(0)?);
                if self.tok == Tok::Comma {
                    self.bump()?;
                    continue;
                }
                break;
            }
        }
        if self.tok != Tok::RParen {
            return Err(ParseError::new(
                format!("expected ',' or ')' in the arguments of '{name}'"),
                self.span,
            ));
        }
        let span = name_span.join(self.span);
        self.bump()?;
        if args.len() != arity {
            let plural = if arity == 1 { "" } else { "s" };
            return Err(ParseError::new(
                format!(
                    "'{name}' takes {arity} argument{plural}, got {}",
                    args.len()
                ),
                span,
            ));
        }
        Ok(Ast {
            kind: AstKind::Call(name, args),
            span,
        })
    }
}

/// Parse an expression to a syntax tree.
pub fn parse_ast(src: &str) -> Result<Ast, ParseError> {
    let mut p = Parser {
        lex: Lexer { src, pos: 0 },
        tok: Tok::End,
        span: Span::default(),
        depth: 0,
    };
    p.bump()?;
    let a = p.expr(0)?;
    if p.tok != Tok::End {
        let what = match &p.tok {
            Tok::RParen => "unmatched ')'".to_string(),
            Tok::Num(_) | Tok::Ident(_) | Tok::LParen => "missing operator before this".to_string(),
            _ => "unexpected token".to_string(),
        };
        return Err(ParseError::new(what, p.span));
    }
    let (h, at) = height(&a);
    if h > MAX_HEIGHT {
        return Err(ParseError::new(
            format!("expression nested too deeply (more than {MAX_HEIGHT} levels)"),
            at,
        ));
    }
    Ok(a)
}

impl Ctx {
    /// Build a syntax tree; `resolve` maps each identifier to a node. Runs
    /// under the context's budget ([`Ctx::set_budget`](Ctx#method.set_budget)): a limit is reported
    /// at the innermost subexpression that reached it.
    pub fn build(
        &mut self,
        ast: &Ast,
        resolve: &mut dyn FnMut(&mut Ctx, &str, Span) -> Result<Id, ParseError>,
    ) -> Result<Id, ParseError> {
        match self.budgeted(|ctx| ctx.build_node(ast, resolve)) {
            (Err(e), _) => Err(e),
            (Ok(_), Some(l)) => Err(ParseError::from_limit(l, ast.span)),
            (Ok(id), None) => Ok(id),
        }
    }

    /// [`Ctx::build`] without arming the budget (the tree is at most
    /// [`MAX_HEIGHT`] high, so the recursion is shallow).
    fn build_node(
        &mut self,
        ast: &Ast,
        resolve: &mut dyn FnMut(&mut Ctx, &str, Span) -> Result<Id, ParseError>,
    ) -> Result<Id, ParseError> {
        let id = self.build_one(ast, resolve)?;
        // poll, not just tripped: building a long printed form is all
        // hash-consing, which nothing else times (fuzz timeout-5952913f).
        if !crate::budget::poll() {
            return Err(match crate::budget::reason() {
                Some(l) => ParseError::from_limit(l, ast.span),
                None => ParseError::new("", ast.span),
            });
        }
        Ok(id)
    }

    fn build_one(
        &mut self,
        ast: &Ast,
        resolve: &mut dyn FnMut(&mut Ctx, &str, Span) -> Result<Id, ParseError>,
    ) -> Result<Id, ParseError> {
        // An engine error after the budget tripped is that limit.
        let at = |e: crate::lower::EngineError, s: Span| match crate::budget::tripped() {
            true => match crate::budget::reason() {
                Some(l) => ParseError::from_limit(l, s),
                None => ParseError::new(e.0, s),
            },
            false => ParseError::new(e.0, s),
        };
        Ok(match &ast.kind {
            AstKind::Num(q) => self.num(q.clone()),
            AstKind::Pi => self.pi(),
            AstKind::Ident(n) => resolve(self, n, ast.span)?,
            AstKind::Neg(x) => {
                let v = self.build_node(x, resolve)?;
                self.neg(v)
            }
            AstKind::Bin(op, l, r) => {
                let a = self.build_node(l, resolve)?;
                let b = self.build_node(r, resolve)?;
                match op {
                    BinOp::Add => self.add(&[a, b]),
                    BinOp::Sub => self.sub(a, b),
                    BinOp::Mul => self.mul(&[a, b]),
                    BinOp::Div => self.checked_div(a, b).map_err(|e| at(e, r.span))?,
                    BinOp::Pow => self.pow_expr(a, b).map_err(|e| at(e, ast.span))?,
                }
            }
            AstKind::Call(f, args) => {
                let mut v = Vec::with_capacity(args.len());
                for a in args {
                    v.push(self.build_node(a, resolve)?);
                }
                let r = match (f.as_str(), v.as_slice()) {
                    ("sin", &[u]) => self.sin(u),
                    ("cos", &[u]) => self.cos(u),
                    ("tan", &[u]) => self.tan(u),
                    ("atan", &[u]) => self.atan(u),
                    ("atan2", &[y, x]) => self.atan2(y, x),
                    ("exp", &[u]) => self.exp(u),
                    ("log", &[u]) => self.log(u),
                    ("sqrt", &[u]) => self.sqrt(u),
                    _ => Err(crate::lower::EngineError(format!(
                        "unknown function '{f}' with {} arguments",
                        v.len()
                    ))),
                };
                r.map_err(|e| at(e, ast.span))?
            }
        })
    }

    /// Parse and build, treating every identifier as a symbol.
    pub fn parse(&mut self, src: &str) -> Result<Id, ParseError> {
        let ast = parse_ast(src)?;
        self.build(&ast, &mut |ctx, name, _| Ok(ctx.symbol(name).id))
    }
}
