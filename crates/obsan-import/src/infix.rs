//! Infix formulas of two foreign dialects, read into the importers' `Ex`:
//! PEtab's (SymPy's syntax: `+ - * / ^ **`, `exp log ln log10 log2 sqrt sin
//! cos tan atan arctan pow`) and MATLAB's symbolic text of STRIKE-GOLDD
//! models (`.* ./ .^` as `* / ^`, `...` continues a line, `^` is
//! left-associative). Unary minus binds looser than a power in both
//! (`-x^2` is `-(x^2)`). Positions are 1-based line and column of the text
//! as placed in its file (`at`: where the text starts).

use crate::ex::Ex;
use crate::ImportError;

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Dialect {
    Petab,
    Matlab,
}

#[derive(Clone, Debug, PartialEq)]
enum T {
    Num(String),
    Id(String),
    Op(&'static str),
}

struct Tok {
    t: T,
    at: (usize, usize),
}

const MAX_DEPTH: usize = 200;

/// The prefix of a call that is MATLAB indexing (`[]u` for `u(k)`).
pub(crate) const INDEX: &str = "[]";

/// Each character with its place in the file.
pub(crate) type Placed = Vec<(char, (usize, usize))>;

/// `text` placed from `at` on (a newline starts column 1 of the next line).
pub(crate) fn placed(text: &str, at: (usize, usize)) -> Placed {
    let (mut line, mut col) = at;
    let mut out = Vec::with_capacity(text.len());
    for ch in text.chars() {
        out.push((ch, (line, col)));
        if ch == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    out
}

fn tokenize(src: &[(char, (usize, usize))], d: Dialect) -> Result<Vec<Tok>, ImportError> {
    let c: Vec<char> = src.iter().map(|x| x.0).collect();
    let mut i = 0;
    let mut out = Vec::new();
    while i < c.len() {
        let here = src[i].1;
        let ch = c[i];
        let mut take = 1;
        if ch.is_whitespace() {
        } else if d == Dialect::Matlab && c[i..].starts_with(&['.', '.', '.']) {
            // A continuation: the rest of the line is a comment.
            while i + take < c.len() && c[i + take] != '\n' {
                take += 1;
            }
        } else if ch.is_ascii_digit()
            || (ch == '.' && c.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            let digits = |mut j: usize| {
                while j < c.len() && c[j].is_ascii_digit() {
                    j += 1;
                }
                j
            };
            let mut j = digits(i);
            // MATLAB's `2.*x` is 2 .* x.
            let dot_op = d == Dialect::Matlab && matches!(c.get(j + 1), Some('*' | '/' | '^'));
            if c.get(j) == Some(&'.') && !dot_op {
                j = digits(j + 1);
            }
            // MATLAB also takes Fortran's `d`/`D` exponent marker (`1.5D-3`).
            let marker = match d {
                Dialect::Matlab => &['e', 'E', 'd', 'D'][..],
                Dialect::Petab => &['e', 'E'][..],
            };
            if c.get(j).is_some_and(|m| marker.contains(m)) {
                let k = if matches!(c.get(j + 1), Some('+' | '-')) {
                    j + 2
                } else {
                    j + 1
                };
                if c.get(k).is_some_and(char::is_ascii_digit) {
                    j = digits(k);
                }
            }
            take = j - i;
            let s: String = c[i..j].iter().collect();
            let e = s.replace(['d', 'D'], "e");
            out.push(Tok {
                t: T::Num(normal_number(&e).ok_or_else(|| {
                    ImportError::at(here.0, here.1, format!("'{s}' is not a number"))
                })?),
                at: here,
            });
        } else if ch.is_ascii_alphabetic() || ch == '_' {
            while i + take < c.len() && (c[i + take].is_ascii_alphanumeric() || c[i + take] == '_')
            {
                take += 1;
            }
            out.push(Tok {
                t: T::Id(c[i..i + take].iter().collect()),
                at: here,
            });
        } else {
            let next = c.get(i + 1).copied();
            let (op, len): (&'static str, usize) = match (ch, next, d) {
                ('*', Some('*'), Dialect::Petab) => ("^", 2),
                ('.', Some('*'), Dialect::Matlab) => ("*", 2),
                ('.', Some('/'), Dialect::Matlab) => ("/", 2),
                ('.', Some('^'), Dialect::Matlab) => ("^", 2),
                ('+', ..) => ("+", 1),
                ('-', ..) => ("-", 1),
                ('*', ..) => ("*", 1),
                ('/', ..) => ("/", 1),
                ('^', ..) => ("^", 1),
                ('(', ..) => ("(", 1),
                (')', ..) => (")", 1),
                (',', ..) => (",", 1),
                _ => {
                    return Err(ImportError::at(
                        here.0,
                        here.1,
                        format!("unexpected character '{ch}' in a formula"),
                    ))
                }
            };
            take = len;
            out.push(Tok {
                t: T::Op(op),
                at: here,
            });
        }
        i += take;
    }
    Ok(out)
}

/// A decimal as `.sys` reads it: `.5` -> `0.5`, `1.` -> `1.0`, `1E+05` -> `1e05`.
pub(crate) fn normal_number(s: &str) -> Option<String> {
    let t = s.trim().to_ascii_lowercase();
    let mut parts = t.splitn(2, 'e');
    let mant = parts.next().unwrap_or("");
    let exp = parts.next();
    let ok = !mant.is_empty()
        && mant.chars().all(|c| c.is_ascii_digit() || c == '.')
        && mant.chars().filter(|&c| c == '.').count() <= 1
        && mant.chars().any(|c| c.is_ascii_digit());
    let mut m = mant.to_string();
    if m.starts_with('.') {
        m.insert(0, '0');
    }
    if m.ends_with('.') {
        m.push('0');
    }
    match exp {
        None if ok => Some(m),
        Some(e) if ok => {
            let (neg, d) = match e.strip_prefix('-') {
                Some(d) => (true, d),
                None => (false, e.trim_start_matches('+')),
            };
            if d.is_empty() || d.len() > 4 || !d.chars().all(|c| c.is_ascii_digit()) {
                return None;
            }
            Some(format!("{m}e{}{d}", if neg { "-" } else { "" }))
        }
        _ => None,
    }
}

struct P<'a> {
    toks: &'a [Tok],
    i: usize,
    depth: usize,
    d: Dialect,
    end: (usize, usize),
}

fn bin(op: char, a: Ex, b: Ex) -> Ex {
    Ex::Bin(op, Box::new(a), Box::new(b))
}

impl P<'_> {
    fn here(&self) -> (usize, usize) {
        self.toks.get(self.i).map_or(self.end, |t| t.at)
    }
    fn err(&self, msg: impl Into<String>) -> ImportError {
        let (l, c) = self.here();
        ImportError::at(l, c, msg)
    }
    fn eat(&mut self, op: &str) -> bool {
        if matches!(self.toks.get(self.i), Some(Tok { t: T::Op(o), .. }) if *o == op) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    fn deeper(&mut self) -> Result<(), ImportError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.err("formula nested too deeply"));
        }
        Ok(())
    }
    // julia/parse.rs has a parallel descent over its own tokens and levels.
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
            a = bin(op, a, self.product()?);
        }
        self.depth -= 1;
        Ok(a)
    }
    fn product(&mut self) -> Result<Ex, ImportError> {
        let mut a = self.unary()?;
        loop {
            let op = if self.eat("*") {
                '*'
            } else if self.eat("/") {
                '/'
            } else {
                break;
            };
            a = bin(op, a, self.unary()?);
        }
        Ok(a)
    }
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
    /// SymPy's `^` is right-associative, MATLAB's left-associative; the
    /// exponent may carry a sign (`x^-1`).
    fn power(&mut self) -> Result<Ex, ImportError> {
        let mut base = self.atom()?;
        while self.eat("^") {
            self.deeper()?;
            let e = if self.d == Dialect::Petab {
                self.unary()?
            } else if self.eat("-") {
                Ex::Neg(Box::new(self.atom()?))
            } else {
                self.eat("+");
                self.atom()?
            };
            self.depth -= 1;
            base = bin('^', base, e);
            if self.d == Dialect::Petab {
                break;
            }
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<Ex, ImportError> {
        let Some(tok) = self.toks.get(self.i) else {
            return Err(self.err("expected an expression, found the end of the formula"));
        };
        let at = tok.at;
        self.i += 1;
        match &tok.t {
            T::Num(n) => Ok(Ex::Num(n.clone())),
            T::Op("(") => {
                let e = self.sum()?;
                if !self.eat(")") {
                    return Err(self.err("expected ')'"));
                }
                Ok(e)
            }
            T::Op(o) => Err(ImportError::at(
                at.0,
                at.1,
                format!("expected an expression, found '{o}'"),
            )),
            T::Id(name) => {
                if !self.eat("(") {
                    return Ok(match name.as_str() {
                        "pi" => Ex::Num("pi".into()),
                        _ => Ex::Name {
                            name: name.clone(),
                            timed: false,
                            at,
                        },
                    });
                }
                let mut args = Vec::new();
                if !self.eat(")") {
                    loop {
                        args.push(self.sum()?);
                        if self.eat(")") {
                            break;
                        }
                        if !self.eat(",") {
                            return Err(self.err("expected ',' or ')'"));
                        }
                    }
                }
                self.call(name, args, at)
            }
        }
    }
    fn call(&self, f: &str, mut args: Vec<Ex>, at: (usize, usize)) -> Result<Ex, ImportError> {
        let err = |m: String| ImportError::at(at.0, at.1, m);
        let one = |args: &mut Vec<Ex>| -> Result<Ex, ImportError> {
            match (args.pop(), args.is_empty()) {
                (Some(a), true) => Ok(a),
                _ => Err(err(format!("{f} takes one argument"))),
            }
        };
        let log = |x: Ex| Ex::Call("log".into(), vec![x]);
        let num = |s: &str| Ex::Num(s.into());
        Ok(match f {
            "exp" | "sin" | "cos" | "tan" | "atan" | "sqrt" => {
                Ex::Call(f.into(), vec![one(&mut args)?])
            }
            "arctan" if self.d == Dialect::Petab => Ex::Call("atan".into(), vec![one(&mut args)?]),
            "ln" if self.d == Dialect::Petab => log(one(&mut args)?),
            "log" if args.len() == 2 && self.d == Dialect::Petab => {
                let b = args.pop().map(log);
                let x = args.pop().map(log);
                match (x, b) {
                    (Some(x), Some(b)) => bin('/', x, b),
                    _ => return Err(err("log takes one or two arguments".into())),
                }
            }
            "log" => log(one(&mut args)?),
            "log10" => bin('/', log(one(&mut args)?), log(num("10"))),
            "log2" => bin('/', log(one(&mut args)?), log(num("2"))),
            "pow" | "power" if args.len() == 2 => {
                let e = args.pop();
                let b = args.pop();
                match (b, e) {
                    (Some(b), Some(e)) => bin('^', b, e),
                    _ => return Err(err(format!("{f} takes two arguments"))),
                }
            }
            // MATLAB indexing `u(2)`: resolved by the caller, which knows the vectors.
            _ if self.d == Dialect::Matlab && args.len() == 1 => {
                Ex::Call(format!("{INDEX}{f}"), args)
            }
            _ => {
                return Err(err(format!(
                    "function '{f}' is not supported (read: exp, log, ln, log10, log2, sqrt, \
                     sin, cos, tan, atan, pow)"
                )))
            }
        })
    }
}

/// Read one formula placed at `at` in its file.
pub(crate) fn parse(text: &str, at: (usize, usize), d: Dialect) -> Result<Ex, ImportError> {
    parse_placed(&placed(text, at), d)
}

/// Read one formula whose characters carry their own places.
pub(crate) fn parse_placed(src: &[(char, (usize, usize))], d: Dialect) -> Result<Ex, ImportError> {
    let toks = tokenize(src, d)?;
    let end = src.last().map_or((1, 1), |&(_, (l, c))| (l, c + 1));
    let mut p = P {
        toks: &toks,
        i: 0,
        depth: 0,
        d,
        end,
    };
    let e = p.sum()?;
    if p.i < toks.len() {
        return Err(p.err("unexpected text after the formula"));
    }
    Ok(e)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ex::show;

    fn text(s: &str, d: Dialect) -> String {
        let e = parse(s, (1, 1), d).unwrap();
        let mut o = String::new();
        show(&e, &mut o, &|n| n.to_string());
        o
    }

    #[test]
    fn dialects() {
        assert_eq!(text("a**2*b", Dialect::Petab), "a^2*b");
        assert_eq!(text("2^3^2", Dialect::Petab), "2^3^2");
        // MATLAB: 2^3^2 = (2^3)^2 = 64.
        assert_eq!(text("2^3^2", Dialect::Matlab), "(2^3)^2");
        assert_eq!(text("x.^2./y.*z", Dialect::Matlab), "x^2/y*z");
        assert_eq!(
            text("-x^2 + 1.E+05*.5", Dialect::Petab),
            "-x^2 + 1.0e05*0.5"
        );
        assert_eq!(text("a*(b - ...\n c)", Dialect::Matlab), "a*(b - c)");
        assert_eq!(text("log10(x)", Dialect::Petab), "log(x)/log(10)");
        assert_eq!(text("x^-1", Dialect::Matlab), "x^(-1)");
        assert_eq!(
            text("1.5D-3*x + 2d2 + .5D+1", Dialect::Matlab),
            "1.5e-3*x + 2e2 + 0.5e1"
        );
        let e = parse("a + b)", (3, 5), Dialect::Petab).unwrap_err();
        assert_eq!((e.line, e.col), (3, 10));
        let e = parse("a +\n  #", (3, 5), Dialect::Matlab).unwrap_err();
        assert_eq!((e.line, e.col), (4, 3));
        let e = parse("a +", (3, 5), Dialect::Petab).unwrap_err();
        assert_eq!((e.line, e.col), (3, 8));
    }
}
