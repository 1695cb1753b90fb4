//! The statements of a STRIKE-GOLDD model file run in order, `for` loops
//! over numeric ranges unrolled: the body runs once per value with the loop
//! variable assigned that number (as MATLAB does, so `xdot(i)` and
//! `x(2*i-1)` index with it, and it keeps its last value after `end`).
//! Limits on iterations, on the statements run from loop bodies, on nesting
//! and on the expression nodes a file builds are errors at their place,
//! never a silent truncation. Also here: whole-number evaluation (indices,
//! bounds, `numel(v)`) and the vectors `zeros(n,1)`, `sym('x', [n 1])` and
//! `v([5 4 3])`.

use crate::ex::Ex;
use crate::infix::{self, Dialect, Placed};
use crate::ImportError;

type At = (usize, usize);
/// A variable's entries, if assigned (what index and bound evaluation look up).
type Entries<'a> = Option<&'a [(Ex, At)]>;

/// Most iterations of one loop (the library's one loop runs 26 times).
pub(crate) const MAX_ITERATIONS: i64 = 10_000;
/// Most statements run from loop bodies in one file, nested loops counted
/// once per enclosing iteration.
pub(crate) const MAX_UNROLLED: usize = 100_000;
/// Most loops nested in one another (recursion depth of the runner).
pub(crate) const MAX_DEPTH: usize = 16;
/// Most expression nodes one file's assignments may build in all: each
/// assignment copies what it substitutes, so `a = [a; a]` or `a = a*a` in a
/// loop doubles; this bounds time and memory (the library's largest file
/// builds 1.4 * 10^4; a vector at the limit takes some 130 MB).
pub(crate) const MAX_NODES: usize = 2_000_000;
/// Longest vector of `zeros(n,1)` (as `sym('x', [n 1])`).
const MAX_LEN: i64 = 100_000;

/// The statement runner's view of the reader's state.
pub(crate) trait Exec {
    /// Run one statement (neither a loop's head nor its `end`).
    fn statement(&mut self, st: &[(char, At)]) -> Result<(), ImportError>;
    /// The entries of a variable assigned before.
    fn value(&self, name: &str) -> Option<&[(Ex, At)]>;
    /// Assign a variable (the loop variable).
    fn assign(&mut self, name: &str, items: Vec<(Ex, At)>, at: At);
}

pub(crate) fn trim(s: &[(char, At)]) -> &[(char, At)] {
    let a = s
        .iter()
        .position(|c| !c.0.is_whitespace())
        .unwrap_or(s.len());
    let b = s
        .iter()
        .rposition(|c| !c.0.is_whitespace())
        .map_or(a, |k| k + 1);
    &s[a..b.max(a)]
}

pub(crate) fn string(s: &[(char, At)]) -> String {
    s.iter().map(|c| c.0).collect()
}

fn err(at: At, m: impl Into<String>) -> ImportError {
    ImportError::at(at.0, at.1, m)
}

/// The statement's first word, and its place.
fn keyword(st: &[(char, At)]) -> (String, At) {
    let t = string(st);
    let w = t
        .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .next()
        .unwrap_or("")
        .to_string();
    (w, st.first().map_or((1, 1), |c| c.1))
}

/// Words that open a block closed by `end`.
const OPENERS: [&str; 7] = ["for", "parfor", "while", "if", "switch", "try", "function"];

/// Run the statements in order, unrolling loops.
pub(crate) fn run(stmts: &[Placed], ex: &mut impl Exec) -> Result<(), ImportError> {
    let mut budget = MAX_UNROLLED;
    block(stmts, ex, &mut budget, 0)
}

fn block(
    stmts: &[Placed],
    ex: &mut impl Exec,
    budget: &mut usize,
    depth: usize,
) -> Result<(), ImportError> {
    let mut k = 0;
    while k < stmts.len() {
        let st = trim(&stmts[k]);
        let (w, at) = keyword(st);
        let whole = string(st);
        if whole == "end" {
            return Err(err(at, "this 'end' closes no loop"));
        }
        if w != "for" {
            ex.statement(st)?;
            k += 1;
            continue;
        }
        let close =
            matching_end(stmts, k).ok_or_else(|| err(at, "this 'for' has no matching 'end'"))?;
        if depth >= MAX_DEPTH {
            return Err(err(
                at,
                format!("loops nested more than {MAX_DEPTH} deep: a limit of this reader"),
            ));
        }
        let (var, values) = head(st, at, ex)?;
        let body = &stmts[k + 1..close];
        let runs = values.len().saturating_mul(body.len());
        if runs > *budget {
            return Err(err(
                at,
                format!(
                    "unrolling this loop runs {runs} statements, past the limit of {MAX_UNROLLED} \
                     statements run from loops in one file"
                ),
            ));
        }
        *budget -= runs;
        if values.is_empty() {
            // MATLAB leaves the variable of a loop that never runs empty.
            ex.assign(&var, Vec::new(), at);
        }
        for v in values {
            ex.assign(&var, vec![(Ex::Num(v.to_string()), at)], at);
            block(body, ex, budget, depth + 1)?;
        }
        k = close + 1;
    }
    Ok(())
}

/// The index of the `end` closing the block opened at `k`.
fn matching_end(stmts: &[Placed], k: usize) -> Option<usize> {
    let mut open = 0usize;
    for (j, st) in stmts.iter().enumerate().skip(k) {
        let st = trim(st);
        if string(st) == "end" {
            open -= 1;
            if open == 0 {
                return Some(j);
            }
        } else if OPENERS.contains(&keyword(st).0.as_str()) {
            open += 1;
        }
    }
    None
}

/// `for NAME = a:b` (or `a:s:b`, or in parentheses): the name and its values.
fn head(st: &[(char, At)], at: At, ex: &impl Exec) -> Result<(String, Vec<i64>), ImportError> {
    let mut rest = trim(&st[3..]);
    if rest.first().map(|c| c.0) == Some('(') && rest.last().map(|c| c.0) == Some(')') {
        rest = trim(&rest[1..rest.len() - 1]);
    }
    let bad = || {
        err(
            at,
            "only loops 'for NAME = a:b' or 'for NAME = a:s:b' over whole numbers are read",
        )
    };
    let eq = rest.iter().position(|c| c.0 == '=').ok_or_else(bad)?;
    let var = string(trim(&rest[..eq]));
    if !(var.starts_with(|c: char| c.is_ascii_alphabetic())
        && var.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
    {
        return Err(bad());
    }
    let range = trim(&rest[eq + 1..]);
    // The range's parts: split at ':' outside brackets.
    let mut parts = Vec::new();
    let (mut d, mut start) = (0i32, 0usize);
    for (j, c) in range.iter().enumerate() {
        match c.0 {
            '(' | '[' => d += 1,
            ')' | ']' => d -= 1,
            ':' if d == 0 => {
                parts.push(&range[start..j]);
                start = j + 1;
            }
            _ => {}
        }
    }
    parts.push(&range[start..]);
    let mut nums = Vec::new();
    for p in &parts {
        let p = trim(p);
        let pat = p.first().map_or(at, |c| c.1);
        let e = infix::parse_placed(p, Dialect::Matlab)?;
        let n = integer(&e, &|n| ex.value(n)).ok_or_else(|| {
            err(
                pat,
                format!(
                    "'{}': a loop's bounds and step must be whole numbers (numbers, names \
                     assigned one, numel(v), + - * /)",
                    string(p)
                ),
            )
        })?;
        nums.push(n);
    }
    let (a, s, b) = match nums.as_slice() {
        [a, b] => (*a, 1, *b),
        [a, s, b] => (*a, *s, *b),
        _ => return Err(bad()),
    };
    if s == 0 {
        return Err(err(at, "this loop's step is 0: it would never end"));
    }
    // Bounds are at most 10^12 (integer()), so this does not overflow.
    let count = if (s > 0 && b >= a) || (s < 0 && b <= a) {
        (b - a) / s + 1
    } else {
        0
    };
    if count > MAX_ITERATIONS {
        return Err(err(
            at,
            format!("this loop runs {count} times, past the limit of {MAX_ITERATIONS}"),
        ));
    }
    Ok((var, (0..count).map(|j| a + j * s).collect()))
}

/// `e` as a whole number of magnitude at most 10^12: numbers, names whose
/// value is one, `numel(v)` of a vector, and + - * / of them.
pub(crate) fn integer<'a>(e: &Ex, value: &dyn Fn(&str) -> Entries<'a>) -> Option<i64> {
    let v = number(e, value, 0)?;
    (v.fract() == 0.0 && v.abs() <= 1e12).then_some(v as i64)
}

fn number<'a>(e: &Ex, value: &dyn Fn(&str) -> Entries<'a>, depth: usize) -> Option<f64> {
    // A bound on recursion: values are substituted, but `a = a` of a symbol names itself.
    if depth > 64 {
        return None;
    }
    let r = match e {
        Ex::Num(s) => s.parse::<f64>().ok()?,
        Ex::Name { name, .. } => match value(name)? {
            [(x, _)] => number(x, value, depth + 1)?,
            _ => return None,
        },
        Ex::Neg(a) => -number(a, value, depth + 1)?,
        Ex::Bin(op, a, b) => {
            let (a, b) = (number(a, value, depth + 1)?, number(b, value, depth + 1)?);
            match op {
                '+' => a + b,
                '-' => a - b,
                '*' => a * b,
                '/' => a / b,
                _ => return None,
            }
        }
        Ex::Call(g, args) => match (g.strip_prefix(infix::INDEX), args.as_slice()) {
            (Some("numel"), [Ex::Name { name, .. }]) => value(name)?.len() as f64,
            _ => return None,
        },
    };
    r.is_finite().then_some(r)
}

/// `zeros(n,1)` or `zeros(1,n)`, alone or in `sym(...)`: `n` zeros; `None`
/// when `t` is no such call.
pub(crate) fn zeros<'a>(
    t: &str,
    at: At,
    value: &dyn Fn(&str) -> Entries<'a>,
) -> Result<Option<Vec<(Ex, At)>>, ImportError> {
    let t = t.trim();
    let t = t
        .strip_prefix("sym(")
        .and_then(|r| r.strip_suffix(')'))
        .map_or(t, str::trim);
    let Some(inner) = t.strip_prefix("zeros(").and_then(|r| r.strip_suffix(')')) else {
        return Ok(None);
    };
    let bad = || {
        err(
            at,
            format!("'{t}': only vectors of zeros, zeros(n,1) or zeros(1,n), are read"),
        )
    };
    let mut dims = Vec::new();
    let (mut d, mut start) = (0i32, 0usize);
    let cs: Vec<char> = inner.chars().collect();
    for j in 0..=cs.len() {
        match cs.get(j) {
            Some('(' | '[') => d += 1,
            Some(')' | ']') => d -= 1,
            Some(',') | None if d == 0 => {
                let part: String = cs[start..j].iter().collect();
                let e = infix::parse(&part, at, Dialect::Matlab).map_err(|_| bad())?;
                dims.push(integer(&e, value).ok_or_else(bad)?);
                start = j + 1;
            }
            _ => {}
        }
    }
    let n = match dims.as_slice() {
        [n, 1] | [1, n] => *n,
        _ => return Err(bad()),
    };
    if !(0..=MAX_LEN).contains(&n) {
        return Err(bad());
    }
    Ok(Some(vec![(Ex::Num("0".into()), at); n as usize]))
}

/// The nodes of `items`, counted up to `cap` (then `cap + 1`).
pub(crate) fn nodes(items: &[(Ex, At)], cap: usize) -> usize {
    let mut n = 0usize;
    let mut stack: Vec<&Ex> = items.iter().map(|x| &x.0).collect();
    while let Some(e) = stack.pop() {
        n += 1;
        if n > cap {
            break;
        }
        match e {
            Ex::Neg(a) => stack.push(a),
            Ex::Bin(_, a, b) => {
                stack.push(a);
                stack.push(b);
            }
            Ex::Call(_, args) => stack.extend(args),
            Ex::Num(_) | Ex::Name { .. } => {}
        }
    }
    n
}

pub(crate) fn is_name(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// The names of `sym('x', [n 1])` (or `[1 n]`, or `n`): `x1`..`xn`, as MATLAB
/// names them.
pub(crate) fn sym_array(t: &str, at: At) -> Result<Vec<String>, ImportError> {
    let bad = || {
        ImportError::at(
            at.0,
            at.1,
            format!("'{t}': only vectors of symbols, sym('x', [n 1]), are read"),
        )
    };
    let inner = t
        .strip_prefix("sym(")
        .and_then(|r| r.trim_end().strip_suffix(')'))
        .ok_or_else(bad)?;
    let (name, size) = inner.split_once(',').unwrap_or((inner, "1"));
    // The name quoted, or `char(x)` of a symbol `x` (its own name).
    let name = name.trim();
    let name = name
        .strip_prefix('\'')
        .and_then(|n| n.strip_suffix('\''))
        .or_else(|| name.strip_prefix("char(").and_then(|n| n.strip_suffix(')')))
        .map(str::trim)
        .filter(|n| is_name(n))
        .ok_or_else(bad)?;
    let dims: Vec<usize> = size
        .trim()
        .trim_start_matches('[')
        .trim_end_matches(']')
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|w| !w.is_empty())
        .map(|w| w.parse::<usize>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let n = match dims.as_slice() {
        [n] | [n, 1] | [1, n] => *n,
        _ => return Err(bad()),
    };
    // A bound well above the library's largest (117): an error, never a huge allocation.
    if n == 0 || n > 100_000 {
        return Err(bad());
    }
    Ok((1..=n).map(|k| format!("{name}{k}")).collect())
}

/// `v([5 4 3])` (blank- or comma-separated numbers, ranges `a:b`, `end` and `a:end`): the
/// vector's name and its indices, `len` standing for `end`.
pub(crate) fn index_list(t: &str, len: impl Fn(&str) -> usize) -> Option<(String, Vec<usize>)> {
    let (v, rest) = t.split_once("([")?;
    let list = rest.trim_end().strip_suffix("])")?;
    let v = v.trim();
    if !is_name(v) {
        return None;
    }
    let end = len(v);
    let num = |x: &str| match x {
        "end" => Some(end),
        _ => x.parse::<usize>().ok(),
    };
    let mut ks: Vec<usize> = Vec::new();
    for w in list
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|w| !w.is_empty())
    {
        match w.split_once(':') {
            // A range past the library's sizes is no index list (then refused as a formula).
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if a > b || b - a > 100_000 {
                    return None;
                }
                ks.extend(a..=b);
            }
            None => ks.push(num(w)?),
        }
    }
    (!ks.is_empty()).then(|| (v.to_string(), ks))
}
