//! STRIKE-GOLDD's model files (`z_create_NAME.m`, MATLAB symbolic text):
//! `syms` declarations and the assignments `x = [..]` (states), `p = [..]`
//! (unknown parameters), `u = [..]` (known inputs), `w = [..]` (unknown
//! inputs), `f = [..]` (the dynamics, one entry per state), `h = [..]` (the
//! outputs). Other assignments are intermediate quantities, substituted where
//! later used; `ics`, `known_ics` and every other statement (`clear`, `save`)
//! are skipped. Vectors are `[a; b]`, `[a, b]` or `[a b]` (elements split at
//! blanks only when every element is a name or number), a trailing `'`
//! (transpose) is ignored. `%` starts a comment, `...` continues a line.
//! Vectors may start as `zeros(n,1)` (or `sym(zeros(numel(x),1))`) or `[]`
//! and grow element by element (`xdot(3) = ...`, `f = [f; xdot(i)]`); `for`
//! loops over whole-number ranges are unrolled (matlab_exec.rs). A role
//! re-assigned later (`u = [x(1); x(2)]` after `f` was written in `x(1)`)
//! takes its last value: MATLAB's `save` stores the last one.
//! The format is read from its description in STRIKE-GOLDD's documentation;
//! no STRIKE-GOLDD text (GPL-3) is used.

use crate::ex::{show, sys_identifier, Ex, RESERVED};
use crate::infix::{self, Dialect, Placed};
use crate::matlab_exec::{
    index_list, integer, is_name, nodes, run, string, sym_array, trim, zeros, Exec, MAX_NODES,
};
use crate::sbml::{one_line, walk_names_at};
use crate::{Converted, ImportError};
use std::collections::BTreeMap;

type At = (usize, usize);
/// A vector's entries with their places, and the place of its assignment.
type Vector = (Vec<(Ex, At)>, At);

/// Split the text into statements (comments and continuations blanked,
/// newlines inside brackets kept as row separators).
/// MATLAB's bracket pairs (opening, closing).
const BRACKETS: [(char, char); 3] = [('[', ']'), ('(', ')'), ('{', '}')];

fn statements(text: &str) -> Result<Vec<Placed>, ImportError> {
    let src = infix::placed(text.strip_prefix('\u{feff}').unwrap_or(text), (1, 1));
    let mut out = Vec::new();
    let mut cur: Placed = Vec::new();
    let mut depth: Vec<(char, At)> = Vec::new();
    let mut i = 0;
    let prev_sig = |cur: &Placed| cur.iter().rev().find(|c| !c.0.is_whitespace()).map(|c| c.0);
    while i < src.len() {
        let (ch, at) = src[i];
        if ch == '%' {
            while i < src.len() && src[i].0 != '\n' {
                i += 1;
            }
            continue;
        }
        if ch == '.' && src[i..].iter().take(3).all(|c| c.0 == '.') && src.len() >= i + 3 {
            // A continuation: skip to the end of the line and join the next one.
            while i < src.len() && src[i].0 != '\n' {
                i += 1;
            }
            if let Some(&(_, nat)) = src.get(i) {
                cur.push((' ', nat));
            }
            i += 1;
            continue;
        }
        if ch == '\'' {
            // A transpose after a value; otherwise a string, kept whole.
            let transpose = prev_sig(&cur).is_some_and(|p| {
                p.is_ascii_alphanumeric() || matches!(p, '_' | ']' | ')' | '\'' | '.')
            }) && cur.last().is_some_and(|c| !c.0.is_whitespace());
            if !transpose {
                cur.push(src[i]);
                i += 1;
                while i < src.len() && src[i].0 != '\'' && src[i].0 != '\n' {
                    cur.push(src[i]);
                    i += 1;
                }
                if src.get(i).map(|c| c.0) != Some('\'') {
                    return Err(ImportError::at(
                        at.0,
                        at.1,
                        "this string is not closed on its line",
                    ));
                }
            }
            cur.push(src[i]);
            i += 1;
            continue;
        }
        let opens = BRACKETS.iter().any(|b| b.0 == ch);
        let closes = BRACKETS.iter().find(|b| b.1 == ch).map(|b| b.0);
        match ch {
            _ if opens => depth.push((ch, at)),
            _ if closes.is_some() => {
                let want = closes;
                match depth.pop() {
                    Some((o, _)) if Some(o) == want => {}
                    _ => return Err(ImportError::at(at.0, at.1, format!("unmatched '{ch}'"))),
                }
            }
            _ => {}
        }
        let ends = depth.is_empty() && matches!(ch, ';' | ',' | '\n');
        if ends {
            if cur.iter().any(|c| !c.0.is_whitespace()) {
                out.push(std::mem::take(&mut cur));
            } else {
                cur.clear();
            }
        } else {
            cur.push(src[i]);
        }
        i += 1;
    }
    if let Some((o, at)) = depth.pop() {
        return Err(ImportError::at(
            at.0,
            at.1,
            format!("this '{o}' is never closed"),
        ));
    }
    if cur.iter().any(|c| !c.0.is_whitespace()) {
        out.push(cur);
    }
    Ok(out)
}

/// The elements of a right-hand side: `[a; b]` as a list, otherwise one.
fn elements(rhs: &[(char, At)]) -> Vec<&[(char, At)]> {
    let mut r = trim(rhs);
    // A trailing transpose.
    while let Some(((c, _), rest)) = r.split_last() {
        if *c == '\''
            || (*c == '.'
                && rest
                    .last()
                    .is_some_and(|x| x.0 == ']' || x.0.is_ascii_alphanumeric()))
        {
            r = trim(rest);
        } else {
            break;
        }
    }
    if r.first().map(|c| c.0) != Some('[') || r.last().map(|c| c.0) != Some(']') {
        return vec![r];
    }
    // The brackets must enclose the whole: `[a] * [b]` is not a vector.
    let mut d = 0i32;
    for (k, c) in r.iter().enumerate() {
        match c.0 {
            '[' | '(' => d += 1,
            ']' | ')' => d -= 1,
            _ => {}
        }
        if d == 0 && k + 1 < r.len() {
            return vec![r];
        }
    }
    let inner = &r[1..r.len() - 1];
    let mut parts = Vec::new();
    let (mut d, mut start) = (0i32, 0usize);
    for (k, c) in inner.iter().enumerate() {
        match c.0 {
            '[' | '(' => d += 1,
            ']' | ')' => d -= 1,
            ';' | ',' | '\n' if d == 0 => {
                parts.push(&inner[start..k]);
                start = k + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    let mut out = Vec::new();
    for p in parts {
        let p = trim(p);
        if p.is_empty() {
            continue;
        }
        // `[x1 x2 x3]`: blanks separate elements when each is a name or number
        // (or a function of time, `[C(t) theta(t)]`).
        let words: Vec<&[(char, At)]> = p
            .split(|c| c.0.is_whitespace())
            .filter(|w| !w.is_empty())
            .collect();
        let simple = |w: &[(char, At)]| {
            let w = string(w);
            let w = w.strip_suffix("(t)").unwrap_or(&w);
            w.chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.'))
        };
        if words.len() > 1 && words.iter().all(|w| simple(w)) {
            out.extend(words);
        } else {
            out.push(p);
        }
    }
    out
}

/// What the statements so far have defined: assignments, and the symbolic
/// functions of time (`syms C(t)`), each with the input name it becomes.
#[derive(Default)]
struct Scope {
    vars: BTreeMap<String, Vector>,
    /// MATLAB name -> (the input's `.sys` name, its declaration's place).
    funcs: BTreeMap<String, (String, At)>,
}

/// The input standing for a function of time `name`, written at `at`.
fn timed(name: &str, at: At) -> Ex {
    Ex::Name {
        name: name.to_string(),
        timed: true,
        at,
    }
}

/// Substitute the single-valued assignments made so far, indexing `v(k)`
/// into an assigned vector, and `C(t)` (or bare `C`) of a function of time.
fn subst(e: &Ex, sc: &Scope, at: At) -> Result<Ex, ImportError> {
    let vars = &sc.vars;
    Ok(match e {
        Ex::Call(g, args) if g.starts_with(infix::INDEX) => {
            let v = &g[infix::INDEX.len()..];
            if let Some((input, _)) = sc.funcs.get(v) {
                return match args.as_slice() {
                    [Ex::Name { name, .. }] if name == "t" => Ok(timed(input, at)),
                    _ => Err(ImportError::at(
                        at.0,
                        at.1,
                        format!("'{v}' is a function of time (syms {v}(t)): write {v}(t)"),
                    )),
                };
            }
            // A whole number: `x(3)`, or the loop variable's `x(i)`, `x(2*i - 1)`.
            let k = match args.as_slice() {
                [k] => integer(k, &|n| vars.get(n).map(|v| v.0.as_slice()))
                    .and_then(|k| usize::try_from(k).ok()),
                _ => None,
            };
            match (vars.get(v), k) {
                (Some((items, _)), Some(k)) if k >= 1 && k <= items.len() => items[k - 1].0.clone(),
                (Some((items, _)), _) => {
                    return Err(ImportError::at(
                        at.0,
                        at.1,
                        format!(
                            "'{v}(...)': the index must be a number from 1 to {}",
                            items.len()
                        ),
                    ))
                }
                (None, _) => {
                    return Err(ImportError::at(
                        at.0,
                        at.1,
                        format!(
                            "'{v}(...)' is neither a function obsan reads (exp, log, log10, sqrt, \
                             sin, cos, tan, atan) nor a vector assigned before"
                        ),
                    ))
                }
            }
        }
        e => subst_plain(e, sc, at)?,
    })
}

fn subst_plain(e: &Ex, sc: &Scope, at: At) -> Result<Ex, ImportError> {
    Ok(match e {
        Ex::Name { name, at: nat, .. } => match sc.vars.get(name).map(|v| v.0.as_slice()) {
            Some([x]) => x.0.clone(),
            // A bare symbolic function is its value at t, as MATLAB computes with it.
            _ => match sc.funcs.get(name) {
                Some((input, _)) => timed(input, *nat),
                None => e.clone(),
            },
        },
        Ex::Neg(a) => Ex::Neg(Box::new(subst(a, sc, at)?)),
        Ex::Bin(op, a, b) => Ex::Bin(
            *op,
            Box::new(subst(a, sc, at)?),
            Box::new(subst(b, sc, at)?),
        ),
        Ex::Call(g, args) => Ex::Call(
            g.clone(),
            args.iter()
                .map(|a| subst(a, sc, at))
                .collect::<Result<_, _>>()?,
        ),
        Ex::Num(_) => e.clone(),
    })
}

/// Translate a STRIKE-GOLDD model file into `.sys` text. `origin` names the
/// file (its stem, less `z_create_`, names the system unless the file saves
/// under another name with `save('NAME', ...)`).
pub fn strike_goldd_to_sys(text: &str, origin: &str) -> Result<Converted, ImportError> {
    // Every assignment, in order; a later one replaces an earlier one.
    let mut state = State {
        work: MAX_NODES,
        ..State::default()
    };
    run(&statements(text)?, &mut state)?;
    let State {
        sc, syms, saved, ..
    } = state;
    let mut roles: BTreeMap<&str, Vector> = BTreeMap::new();
    for r in ["x", "p", "u", "w", "f", "h"] {
        if let Some(v) = sc.vars.get(r) {
            roles.insert(r, v.clone());
        } else if let Some((_, at)) = syms.iter().find(|s| s.0 == r) {
            let e = Ex::Name {
                name: r.to_string(),
                timed: false,
                at: *at,
            };
            roles.insert(r, (vec![(e, *at)], *at));
        }
    }
    let syms: Vec<String> = syms.into_iter().map(|s| s.0).collect();
    convert(roles, &syms, &sc.funcs, saved, origin)
}

/// The reader's state as the statements run.
#[derive(Default)]
struct State {
    sc: Scope,
    syms: Vec<(String, At)>,
    saved: Option<String>,
    /// Expression nodes the assignments may still build (MAX_NODES in all).
    work: usize,
}

impl Exec for State {
    fn value(&self, name: &str) -> Option<&[(Ex, At)]> {
        self.sc.vars.get(name).map(|v| v.0.as_slice())
    }

    fn assign(&mut self, name: &str, items: Vec<(Ex, At)>, at: At) {
        self.sc.funcs.remove(name);
        self.sc.vars.insert(name.to_string(), (items, at));
    }

    fn statement(&mut self, st: &[(char, At)]) -> Result<(), ImportError> {
        let State {
            sc,
            syms,
            saved,
            work,
        } = self;
        let t = string(st);
        // `syms a b real`: a role (x, u, ...) declared and never assigned is that one symbol.
        if let Some(rest) = t.strip_prefix("syms") {
            if rest.is_empty() || rest.starts_with(char::is_whitespace) {
                for (w, at) in words(&st[4..]) {
                    declare(sc, syms, w, at)?;
                }
                return Ok(());
            }
        }
        if let Some(rest) = t.strip_prefix("save(") {
            let name = rest
                .trim_start()
                .strip_prefix('\'')
                .and_then(|r| r.split('\'').next());
            if let Some(n) = name.filter(|n| is_name(n)) {
                *saved = Some(n.to_string());
            }
            return Ok(());
        }
        refuse_unread(st, &t)?;
        // An assignment NAME = RHS (not ==).
        let Some(eq) = st.iter().position(|c| c.0 == '=') else {
            return Ok(());
        };
        if st.get(eq + 1).map(|c| c.0) == Some('=') {
            return Ok(());
        }
        let lhs = string(trim(&st[..eq]));
        if let Some((v, k)) = lhs.split_once('(').filter(|(v, _)| is_name(v.trim_end())) {
            let (v, at) = (v.trim_end(), st[0].1);
            // `f(3) = ...`, `xdot(i) = ...`: one element of a vector assigned before,
            // replaced or appended.
            let k = k
                .strip_suffix(')')
                .and_then(|k| infix::parse(k, at, Dialect::Matlab).ok())
                .and_then(|k| integer(&k, &|n| sc.vars.get(n).map(|v| v.0.as_slice())));
            if let (Some(k), Some(len)) = (k, sc.vars.get(v).map(|x| x.0.len())) {
                let rhs = elements(&st[eq + 1..]);
                let [el] = rhs.as_slice() else {
                    return Err(ImportError::at(
                        at.0,
                        at.1,
                        format!("'{lhs} = ...' sets one element to several"),
                    ));
                };
                let e = infix::parse_placed(el, Dialect::Matlab)?;
                let el_at = el.first().map_or(at, |c| c.1);
                let e = (subst(&e, sc, el_at)?, el_at);
                spend(work, std::slice::from_ref(&e), at)?;
                let Some((items, _)) = sc.vars.get_mut(v) else {
                    return Ok(());
                };
                match k {
                    _ if k >= 1 && k <= len as i64 => items[k as usize - 1] = e,
                    _ if k == len as i64 + 1 => items.push(e),
                    _ => {
                        return Err(ImportError::at(
                            at.0,
                            at.1,
                            format!(
                        "'{lhs} = ...': element {k} of a vector of {len} (set them in order)"
                    ),
                        ))
                    }
                }
                return Ok(());
            }
            // `M(i,j) = ...`: an element set by the script, which this reader does not follow.
            if !matches!(v, "ics" | "known_ics") {
                let at = st[0].1;
                return Err(ImportError::at(
                    at.0,
                    at.1,
                    format!("'{lhs} = ...' sets an element: not read (assign whole vectors)"),
                ));
            }
        }
        if !is_name(&lhs) || matches!(lhs.as_str(), "ics" | "known_ics") {
            return Ok(());
        }
        let mut items = Vec::new();
        for el in elements(&st[eq + 1..]) {
            // An empty element (`x = [a;;b]`, `x = `) is the parser's error, at the '='.
            let Some(&(_, at)) = el.first() else {
                let at = st[eq].1;
                return Err(ImportError::at(at.0, at.1, "nothing to read after '='"));
            };
            // `zeros(n,1)`, `sym(zeros(numel(x),1))`: n zeros, set element by element later.
            if let Some(z) = zeros(&string(el), at, &|n| sc.vars.get(n).map(|v| v.0.as_slice()))? {
                items.extend(z);
                continue;
            }
            if string(el).starts_with("sym(") {
                // `sym('x', [34 1])`: the symbols x1..x34, indexed later (`x(3)`).
                for name in sym_array(&string(el), at)? {
                    declare(sc, syms, name.clone(), at)?;
                    let e = Ex::Name {
                        name,
                        timed: false,
                        at,
                    };
                    items.push((e, at));
                }
                continue;
            }
            // `x([5 4 3])`: elements of a vector assigned before, in that order.
            let len = |v: &str| sc.vars.get(v).map_or(0, |x| x.0.len());
            if let Some((v, ks)) = index_list(&string(el), len) {
                for k in ks {
                    let e = Ex::Call(format!("{}{v}", infix::INDEX), vec![Ex::Num(k.to_string())]);
                    items.push((subst(&e, sc, at)?, at));
                }
                continue;
            }
            let e = infix::parse_placed(el, Dialect::Matlab)?;
            // A name standing for a whole vector (`h = x`) is that vector.
            if let Ex::Name { name, .. } = &e {
                if let Some((v, _)) = sc.vars.get(name).filter(|v| v.0.len() != 1) {
                    items.extend(v.iter().cloned());
                    continue;
                }
            }
            items.push((subst(&e, sc, el[0].1)?, el[0].1));
        }
        spend(work, &items, st[0].1)?;
        sc.funcs.remove(&lhs);
        sc.vars.insert(lhs, (items, st[0].1));
        Ok(())
    }
}

/// The blank-separated words of a `syms` line, with their places.
fn words(s: &[(char, At)]) -> Vec<(String, At)> {
    s.split(|c| c.0.is_whitespace())
        .filter(|w| !w.is_empty())
        .map(|w| (string(w), w[0].1))
        .collect()
}

/// One word of `syms`: a plain symbol, or `C(t)`, a symbolic function of
/// time: a known input, named `C` if the name is free, else `C_t` (a `syms
/// theta` or an assignment to `theta` came first and keeps that name).
fn declare(
    sc: &mut Scope,
    syms: &mut Vec<(String, At)>,
    w: String,
    at: At,
) -> Result<(), ImportError> {
    let Some((name, args)) = w.strip_suffix(')').and_then(|r| r.split_once('(')) else {
        if !is_name(&w) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("'{w}' in syms: not read (declare plain names, or functions NAME(t))"),
            ));
        }
        // A plain re-declaration ends the function of that name.
        sc.funcs.remove(&w);
        syms.push((w, at));
        return Ok(());
    };
    if !is_name(name) || args.trim() != "t" {
        return Err(ImportError::at(
            at.0,
            at.1,
            format!("'{w}' in syms: only functions of time alone, NAME(t), are read"),
        ));
    }
    let taken = |n: &str, sc: &Scope| {
        syms.iter().any(|s| s.0 == n)
            || sc.vars.contains_key(n)
            || sc.funcs.iter().any(|(k, v)| k != name && v.0 == n)
    };
    let mut input = name.to_string();
    while taken(&input, sc) {
        input.push_str("_t");
    }
    sc.vars.remove(name);
    sc.funcs.insert(name.to_string(), (input, at));
    Ok(())
}

/// MATLAB this reader does not follow (loops, branches, functions) is
/// refused at its place rather than skipped: skipping a loop that fills `f`
/// would convert a different model.
fn refuse_unread(st: &[(char, At)], t: &str) -> Result<(), ImportError> {
    let first = t
        .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .next();
    if let Some(k) = first.filter(|k| {
        matches!(
            *k,
            "for" | "while" | "if" | "switch" | "function" | "parfor" | "try"
        )
    }) {
        let at = st.first().map_or((1, 1), |c| c.1);
        return Err(ImportError::at(
            at.0,
            at.1,
            format!(
                "'{k}' (MATLAB control flow) is not read: write the model's vectors out (loops \
                 'for i = a:b' are read)"
            ),
        ));
    }
    Ok(())
}

fn names_of(
    roles: &BTreeMap<&str, Vector>,
    key: &str,
    what: &str,
) -> Result<Vec<(String, At)>, ImportError> {
    let mut out = Vec::new();
    if let Some((items, _)) = roles.get(key) {
        for (e, at) in items {
            match e {
                Ex::Name { name, .. } => out.push((name.clone(), *at)),
                _ => {
                    return Err(ImportError::at(
                        at.0,
                        at.1,
                        format!("each entry of '{key}' ({what}) must be a name"),
                    ))
                }
            }
        }
    }
    Ok(out)
}

/// A model's roles, checked: the names declared as states, parameters,
/// known and unknown inputs, and the entries of `f` and `h`.
struct Model {
    states: Vec<(String, At)>,
    params: Vec<(String, At)>,
    inputs: Vec<(String, At)>,
    unknown: Vec<(String, At)>,
    f: Vec<(Ex, At)>,
    h: Vec<(Ex, At)>,
}

impl Model {
    /// Every declared name (x, p, u, w).
    fn declared(&self) -> Vec<&str> {
        self.states
            .iter()
            .chain(&self.params)
            .chain(&self.inputs)
            .chain(&self.unknown)
            .map(|n| n.0.as_str())
            .collect()
    }
}

/// Step 1: the roles present (x, f, h required), each list of names made
/// of names, one entry of `f` per state, no name declared twice.
fn checked_roles(roles: &BTreeMap<&str, Vector>) -> Result<Model, ImportError> {
    for (k, what) in [
        ("x", "the states"),
        ("f", "the dynamics"),
        ("h", "the outputs"),
    ] {
        if !roles.contains_key(k) {
            return Err(ImportError::at(
                1,
                1,
                format!("no '{k} = [...]' ({what}) in the file"),
            ));
        }
    }
    let m = Model {
        states: names_of(roles, "x", "the states")?,
        params: names_of(roles, "p", "the parameters")?,
        inputs: names_of(roles, "u", "the known inputs")?,
        unknown: names_of(roles, "w", "the unknown inputs")?,
        f: roles.get("f").cloned().unwrap_or_default().0,
        h: roles.get("h").cloned().unwrap_or_default().0,
    };
    if m.f.len() != m.states.len() {
        let fat = roles.get("f").map_or((1, 1), |v| v.1);
        return Err(ImportError::at(
            fat.0,
            fat.1,
            format!("f has {} entries for {} states", m.f.len(), m.states.len()),
        ));
    }
    let mut all: Vec<&str> = Vec::new();
    for (n, at) in m
        .states
        .iter()
        .chain(&m.params)
        .chain(&m.inputs)
        .chain(&m.unknown)
    {
        if all.contains(&n.as_str()) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("'{n}' is declared twice (x, p, u, w)"),
            ));
        }
        all.push(n);
    }
    Ok(m)
}

/// Step 2: the known constants. A symbol declared with `syms` but in none
/// of x, p, u, w is a known constant, as STRIKE-GOLDD reads it; any other
/// name in `f` or `h` is refused at its place.
fn constants(m: &Model, syms: &[String]) -> Result<Vec<String>, ImportError> {
    let all = m.declared();
    let mut consts: Vec<String> = Vec::new();
    for (e, _) in m.f.iter().chain(&m.h) {
        let mut bad = None;
        walk_names_at(e, &mut |n, p| {
            if all.contains(&n) || consts.iter().any(|c| c == n) {
            } else if syms.iter().any(|s| s == n) {
                consts.push(n.to_string());
            } else if bad.is_none() {
                bad = Some((n.to_string(), p));
            }
        });
        if let Some((n, p)) = bad {
            let why = if n == "t" {
                " (time: the model must be autonomous)"
            } else {
                ""
            };
            return Err(ImportError::at(
                p.0,
                p.1,
                format!(
                    "'{n}' is not a state, parameter or input of the model (x, p, u, w) nor \
                     declared with syms{why}"
                ),
            ));
        }
    }
    Ok(consts)
}

/// Step 3: the system's name: `save('NAME', ...)`'s, else the file's stem
/// less `z_create_`, made a valid `.sys` name.
fn system_name(saved: Option<String>, origin: &str) -> String {
    let stem = origin
        .rsplit(['/', '\\'])
        .next()
        .unwrap_or(origin)
        .trim_end_matches(".m");
    let name = saved.unwrap_or_else(|| stem.strip_prefix("z_create_").unwrap_or(stem).to_string());
    sys_identifier(&name)
}

/// `.sys` names: a reserved word gets a trailing `_`.
fn rename(n: &str) -> String {
    if RESERVED.contains(&n) {
        format!("{n}_")
    } else {
        n.to_string()
    }
}

/// Step 4: the `.sys` text, with the source place of each equation and
/// output line.
fn write_sys(m: &Model, consts: &[String], name: String, origin: &str) -> Converted {
    let list = |v: &[(String, At)]| {
        v.iter()
            .map(|x| rename(&x.0))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let mut lines = vec![
        format!(
            "# Imported by `obsan import strike-goldd` from {}.",
            one_line(origin)
        ),
        format!("system {name}"),
        format!("state {}", list(&m.states)),
    ];
    for (kw, v) in [
        ("param", &m.params),
        ("input", &m.inputs),
        ("unknown input", &m.unknown),
    ] {
        if !v.is_empty() {
            lines.push(format!("{kw} {}", list(v)));
        }
    }
    if !consts.is_empty() {
        let c: Vec<String> = consts.iter().map(|c| rename(c)).collect();
        lines.push(format!("const {}", c.join(", ")));
    }
    let mut line_map = Vec::new();
    for ((s, _), (e, at)) in m.states.iter().zip(&m.f) {
        let mut t = String::new();
        show(e, &mut t, &rename);
        lines.push(format!("{}' = {t}", rename(s)));
        line_map.push((lines.len(), at.0, at.1));
    }
    // Outputs y1, y2, ... unless a declared name has that form.
    let clash = m.declared().iter().any(|n| {
        n.strip_prefix('y')
            .is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()))
    });
    let base = if clash { "y_out" } else { "y" };
    for (k, (e, at)) in m.h.iter().enumerate() {
        let mut t = String::new();
        show(e, &mut t, &rename);
        lines.push(format!("output {base}{} = {t}", k + 1));
        line_map.push((lines.len(), at.0, at.1));
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

fn convert(
    roles: BTreeMap<&str, Vector>,
    syms: &[String],
    funcs: &BTreeMap<String, (String, At)>,
    saved: Option<String>,
    origin: &str,
) -> Result<Converted, ImportError> {
    let mut m = checked_roles(&roles)?;
    timed_inputs(&roles, &mut m, funcs)?;
    let consts = constants(&m, syms)?;
    Ok(write_sys(&m, &consts, system_name(saved, origin), origin))
}

/// Functions of time (`syms C(t)`) are known inputs: refused as states or
/// parameters, and added to the inputs when used in `f` or `h` but listed in
/// neither `u` nor `w`.
fn timed_inputs(
    roles: &BTreeMap<&str, Vector>,
    m: &mut Model,
    funcs: &BTreeMap<String, (String, At)>,
) -> Result<(), ImportError> {
    for (key, what) in [("x", "state"), ("p", "parameter")] {
        let items = roles.get(key).map_or(&[][..], |v| v.0.as_slice());
        if let Some((Ex::Name { name, .. }, at)) = items
            .iter()
            .find(|(e, _)| matches!(e, Ex::Name { timed: true, .. }))
        {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("'{name}' is a function of time (syms ...(t)): an input, not a {what}"),
            ));
        }
    }
    let inputs: Vec<&str> = funcs.values().map(|v| v.0.as_str()).collect();
    let mut extra = Vec::new();
    for (e, _) in m.f.iter().chain(&m.h) {
        walk_names_at(e, &mut |n, at| {
            if inputs.contains(&n)
                && !m.declared().contains(&n)
                && !extra.iter().any(|x: &(String, At)| x.0 == n)
            {
                extra.push((n.to_string(), at));
            }
        });
    }
    m.inputs.extend(extra);
    Ok(())
}

/// Take an assignment's nodes from the file's budget (MAX_NODES).
fn spend(work: &mut usize, items: &[(Ex, At)], at: At) -> Result<(), ImportError> {
    let n = nodes(items, *work);
    if n > *work {
        return Err(ImportError::at(
            at.0,
            at.1,
            format!(
                "the assignments up to here build more than {MAX_NODES} expression nodes: \
                 a limit of this reader (each assignment copies what it substitutes)"
            ),
        ));
    }
    *work -= n;
    Ok(())
}
