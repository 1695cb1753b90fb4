//! SBML's XML and MathML read into expressions: element helpers, located
//! errors, exact decimal numbers, the MathML content subset obsan reads, and
//! function definitions (inlined at each call).

use crate::ex::Ex;
use crate::ImportError;
use roxmltree::{Document, Node};
use std::collections::BTreeMap;

pub(crate) struct Ctx<'a> {
    pub doc: &'a Document<'a>,
    pub funcs: BTreeMap<String, (Vec<String>, Ex)>,
}

impl Ctx<'_> {
    pub fn pos(&self, n: Node) -> (usize, usize) {
        let p = self.doc.text_pos_at(n.range().start);
        (p.row as usize, p.col as usize)
    }
    pub fn err(&self, n: Node, msg: impl Into<String>) -> ImportError {
        let (l, c) = self.pos(n);
        ImportError::at(l, c, msg)
    }
}

pub(crate) fn elems<'a, 'i>(n: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    n.children().filter(|c| c.is_element())
}

pub(crate) fn child<'a, 'i>(n: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    elems(n).find(|c| c.tag_name().name() == name)
}

pub(crate) fn list<'a, 'i>(n: Node<'a, 'i>, list: &str, item: &str) -> Vec<Node<'a, 'i>> {
    child(n, list).map_or(Vec::new(), |l| {
        elems(l).filter(|c| c.tag_name().name() == item).collect()
    })
}

pub(crate) fn id_of(cx: &Ctx, n: Node, attr: &str) -> Result<String, ImportError> {
    let id = n
        .attribute(attr)
        .ok_or_else(|| cx.err(n, format!("<{}> has no '{attr}'", n.tag_name().name())))?;
    if id.is_empty()
        || !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        || !id.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
    {
        return Err(cx.err(n, format!("'{id}' is not a valid SBML id")));
    }
    Ok(id.to_string())
}

/// A number as `.sys` reads it (exact decimal), from SBML text.
pub(crate) fn number(cx: &Ctx, n: Node, text: &str) -> Result<Ex, ImportError> {
    let t = text.trim().to_ascii_lowercase();
    let (neg, body) = match t.strip_prefix('-') {
        Some(b) => (true, b.to_string()),
        None => (false, t.trim_start_matches('+').to_string()),
    };
    let mut parts = body.splitn(2, 'e');
    let mant = parts.next().unwrap_or("");
    let exp = parts.next();
    let mant_ok = !mant.is_empty()
        && mant.chars().all(|c| c.is_ascii_digit() || c == '.')
        && mant.chars().filter(|&c| c == '.').count() <= 1
        && mant.chars().any(|c| c.is_ascii_digit());
    let exp_ok = exp.is_none_or(|e| {
        let d = e.trim_start_matches(['+', '-']);
        !d.is_empty() && d.len() <= 4 && d.chars().all(|c| c.is_ascii_digit())
    });
    if !mant_ok || !exp_ok {
        return Err(cx.err(n, format!("'{}' is not a finite number", text.trim())));
    }
    let mut s = mant.to_string();
    if s.starts_with('.') {
        s.insert(0, '0');
    }
    if s.ends_with('.') {
        s.push('0');
    }
    if let Some(e) = exp {
        s = format!("{s}e{e}");
    }
    let e = Ex::Num(s);
    Ok(if neg { Ex::Neg(Box::new(e)) } else { e })
}

pub(crate) fn name(s: &str, n: (usize, usize)) -> Ex {
    Ex::Name {
        name: s.to_string(),
        timed: false,
        at: n,
    }
}

pub(crate) fn bin(op: char, a: Ex, b: Ex) -> Ex {
    Ex::Bin(op, Box::new(a), Box::new(b))
}

/// Replace names by expressions.
pub(crate) fn subst(e: &Ex, f: &dyn Fn(&str) -> Option<Ex>) -> Ex {
    match e {
        Ex::Name { name, .. } => f(name).unwrap_or_else(|| e.clone()),
        Ex::Neg(a) => Ex::Neg(Box::new(subst(a, f))),
        Ex::Bin(op, a, b) => bin(*op, subst(a, f), subst(b, f)),
        Ex::Call(g, args) => Ex::Call(g.clone(), args.iter().map(|a| subst(a, f)).collect()),
        Ex::Num(_) => e.clone(),
    }
}

pub(crate) const MAX_DEPTH: usize = 200;

/// Explicit time in the `.sys` text (an SBML id `t` is written `t_`).
pub(crate) const TIME: &str = "t";

/// A MathML content element as an expression.
pub(crate) fn mathml(cx: &Ctx, n: Node, depth: usize) -> Result<Ex, ImportError> {
    if depth > MAX_DEPTH {
        return Err(cx.err(n, "MathML nested too deeply"));
    }
    let tag = n.tag_name().name();
    match tag {
        "math" | "semantics" => {
            let first = elems(n)
                .next()
                .ok_or_else(|| cx.err(n, format!("empty <{tag}>")))?;
            mathml(cx, first, depth + 1)
        }
        "cn" => {
            let kind = n.attribute("type").unwrap_or("real");
            let texts: Vec<&str> = n
                .children()
                .filter(|c| c.is_text())
                .filter_map(|c| c.text())
                .map(str::trim)
                .filter(|t| !t.is_empty())
                .collect();
            match (kind, texts.as_slice()) {
                ("integer" | "real" | "double", [t]) => number(cx, n, t),
                ("e-notation", [m, e]) => number(cx, n, &format!("{m}e{e}")),
                ("rational", [a, b]) => Ok(bin('/', number(cx, n, a)?, number(cx, n, b)?)),
                _ => Err(cx.err(n, format!("cannot read this <cn type=\"{kind}\">"))),
            }
        }
        "ci" => {
            let t = n.text().unwrap_or("").trim();
            Ok(name(t, cx.pos(n)))
        }
        "pi" => Ok(Ex::Num("pi".into())),
        "exponentiale" => Ok(Ex::Call("exp".into(), vec![Ex::Num("1".into())])),
        "csymbol" => {
            let url = n.attribute("definitionURL").unwrap_or("");
            let what = url.rsplit('/').next().unwrap_or(url);
            if what == "time" {
                // Explicit time is `t` in a `.sys` file; written as a number
                // token so that no renaming of SBML ids touches it.
                return Ok(Ex::Num(TIME.into()));
            }
            Err(cx.err(
                n,
                format!(
                    "<csymbol> '{what}' is not supported (time is; delay and avogadro are not: \
                     the model must be without delays)"
                ),
            ))
        }
        "apply" => {
            let mut it = elems(n);
            let op = it.next().ok_or_else(|| cx.err(n, "empty <apply>"))?;
            let rest: Vec<Node> = it.collect();
            let qual = |q: &str| rest.iter().find(|c| c.tag_name().name() == q).copied();
            let args: Vec<Ex> = rest
                .iter()
                .filter(|c| !matches!(c.tag_name().name(), "degree" | "logbase"))
                .map(|c| mathml(cx, *c, depth + 1))
                .collect::<Result<_, _>>()?;
            let opname = op.tag_name().name();
            let arity = |k: usize| -> Result<(), ImportError> {
                if args.len() == k {
                    Ok(())
                } else {
                    Err(cx.err(op, format!("<{opname}> takes {k} argument(s), not {}", args.len())))
                }
            };
            let call = |f: &str, a: Ex| Ex::Call(f.to_string(), vec![a]);
            match opname {
                "plus" => Ok(args
                    .into_iter()
                    .reduce(|a, b| bin('+', a, b))
                    .unwrap_or(Ex::Num("0".into()))),
                "times" => Ok(args
                    .into_iter()
                    .reduce(|a, b| bin('*', a, b))
                    .unwrap_or(Ex::Num("1".into()))),
                "minus" => {
                    let mut a = args.into_iter();
                    match (a.next(), a.next(), a.next()) {
                        (Some(x), None, None) => Ok(Ex::Neg(Box::new(x))),
                        (Some(x), Some(y), None) => Ok(bin('-', x, y)),
                        _ => Err(cx.err(op, "<minus> takes one or two arguments")),
                    }
                }
                "divide" | "power" => {
                    arity(2)?;
                    let mut a = args.into_iter();
                    let (x, y) = (a.next(), a.next());
                    match (x, y) {
                        (Some(x), Some(y)) => Ok(bin(if opname == "divide" { '/' } else { '^' }, x, y)),
                        _ => Err(cx.err(op, "missing argument")),
                    }
                }
                "root" => {
                    arity(1)?;
                    let x = args.into_iter().next().ok_or_else(|| cx.err(op, "missing argument"))?;
                    match qual("degree") {
                        None => Ok(call("sqrt", x)),
                        Some(d) => {
                            let dn = elems(d).next().ok_or_else(|| cx.err(d, "empty <degree>"))?;
                            let deg = mathml(cx, dn, depth + 1)?;
                            Ok(bin('^', x, bin('/', Ex::Num("1".into()), deg)))
                        }
                    }
                }
                "exp" | "ln" | "sin" | "cos" | "tan" | "arctan" => {
                    arity(1)?;
                    let x = args.into_iter().next().ok_or_else(|| cx.err(op, "missing argument"))?;
                    let f = match opname {
                        "ln" => "log",
                        "arctan" => "atan",
                        f => f,
                    };
                    Ok(call(f, x))
                }
                "log" => {
                    arity(1)?;
                    let x = args.into_iter().next().ok_or_else(|| cx.err(op, "missing argument"))?;
                    let base = match qual("logbase") {
                        Some(b) => {
                            let bn = elems(b).next().ok_or_else(|| cx.err(b, "empty <logbase>"))?;
                            mathml(cx, bn, depth + 1)?
                        }
                        None => Ex::Num("10".into()),
                    };
                    Ok(bin('/', call("log", x), call("log", base)))
                }
                "ci" => {
                    let f = op.text().unwrap_or("").trim();
                    let (params, body) = cx.funcs.get(f).ok_or_else(|| {
                        cx.err(op, format!("'{f}' is called but is not a function definition"))
                    })?;
                    if params.len() != args.len() {
                        return Err(cx.err(
                            op,
                            format!("'{f}' takes {} argument(s), not {}", params.len(), args.len()),
                        ));
                    }
                    let map: BTreeMap<&str, &Ex> =
                        params.iter().map(String::as_str).zip(args.iter()).collect();
                    Ok(subst(body, &|nm| map.get(nm).map(|e| (*e).clone())))
                }
                "csymbol" => mathml(cx, op, depth + 1),
                other => Err(cx.err(
                    op,
                    format!("MathML <{other}> is not supported (obsan reads + - * / ^, root, exp, ln, log, sin, cos, tan, arctan)"),
                )),
            }
        }
        "piecewise" => piecewise(cx, n, depth),
        other => Err(cx.err(
            n,
            format!("MathML <{other}> is not supported (relations and logic only in a <piecewise> condition)"),
        )),
    }
}

/// The call name of a `<piecewise>` read from MathML: `piecewise@LINE:COL`
/// (its place, so that an error and the input it becomes can name it), to
/// which `math_of` appends `@OWNER`, the id of the element holding the math.
/// Arguments: value, condition, value, condition, ..., then the
/// `<otherwise>` value if there is one (an odd count).
pub(crate) const PIECEWISE: &str = "piecewise@";

/// `<piecewise>`: its pieces' values and conditions (relations and logic,
/// read only here), as `Call(PIECEWISE..., args)`.
fn piecewise(cx: &Ctx, n: Node, depth: usize) -> Result<Ex, ImportError> {
    let mut args = Vec::new();
    let mut otherwise = None;
    for c in elems(n) {
        match c.tag_name().name() {
            "piece" => {
                let parts: Vec<Node> = elems(c).collect();
                let [v, cond] = parts.as_slice() else {
                    return Err(cx.err(c, "<piece> takes a value and a condition"));
                };
                args.push(mathml(cx, *v, depth + 1)?);
                args.push(condition(cx, *cond, depth + 1)?);
            }
            "otherwise" => {
                let v = elems(c)
                    .next()
                    .ok_or_else(|| cx.err(c, "empty <otherwise>"))?;
                otherwise = Some(mathml(cx, v, depth + 1)?);
            }
            other => return Err(cx.err(c, format!("<{other}> in a <piecewise>"))),
        }
    }
    if args.is_empty() && otherwise.is_none() {
        return Err(cx.err(n, "empty <piecewise>"));
    }
    args.extend(otherwise);
    let (l, col) = cx.pos(n);
    Ok(Ex::Call(format!("{PIECEWISE}{l}:{col}"), args))
}

/// Relations (`lt gt leq geq eq neq`, a chain `a < b < c` read pairwise),
/// logic (`and or xor not`) and `true`/`false`: `Call(op, args)`,
/// `Num("true")`. Anything else is a value, refused as a condition.
fn condition(cx: &Ctx, n: Node, depth: usize) -> Result<Ex, ImportError> {
    if depth > MAX_DEPTH {
        return Err(cx.err(n, "MathML nested too deeply"));
    }
    match n.tag_name().name() {
        "true" | "false" => return Ok(Ex::Num(n.tag_name().name().into())),
        "apply" => {}
        other => return Err(cx.err(n, format!("<{other}> is not a condition"))),
    }
    let mut it = elems(n);
    let op = it.next().ok_or_else(|| cx.err(n, "empty <apply>"))?;
    let rest: Vec<Node> = it.collect();
    let opname = op.tag_name().name();
    match opname {
        "lt" | "gt" | "leq" | "geq" | "eq" | "neq" => {
            let a: Vec<Ex> = rest
                .iter()
                .map(|c| mathml(cx, *c, depth + 1))
                .collect::<Result<_, _>>()?;
            if a.len() < 2 || (opname == "neq" && a.len() != 2) {
                return Err(cx.err(op, format!("<{opname}> with {} argument(s)", a.len())));
            }
            let pairs: Vec<Ex> = a
                .windows(2)
                .map(|w| Ex::Call(opname.into(), w.to_vec()))
                .collect();
            Ok(if pairs.len() == 1 {
                pairs.into_iter().next().unwrap_or(Ex::Num("true".into()))
            } else {
                Ex::Call("and".into(), pairs)
            })
        }
        "and" | "or" | "xor" | "not" => {
            let a: Vec<Ex> = rest
                .iter()
                .map(|c| condition(cx, *c, depth + 1))
                .collect::<Result<_, _>>()?;
            // An empty <and/> is true, an empty <or/> or <xor/> false (MathML's n-ary forms).
            if opname == "not" && a.len() != 1 {
                return Err(cx.err(op, format!("<{opname}> with {} argument(s)", a.len())));
            }
            Ok(Ex::Call(opname.into(), a))
        }
        other => Err(cx.err(
            op,
            format!(
                "<{other}> is not a condition (relations lt gt leq geq eq neq, and or xor not)"
            ),
        )),
    }
}

/// Append the owner's id to each `<piecewise>` call name in `e`.
fn own(e: &Ex, owner: &str) -> Ex {
    match e {
        Ex::Call(f, args) => {
            let args = args.iter().map(|a| own(a, owner)).collect();
            if f.starts_with(PIECEWISE) && f.matches('@').count() == 1 {
                Ex::Call(format!("{f}@{owner}"), args)
            } else {
                Ex::Call(f.clone(), args)
            }
        }
        Ex::Neg(a) => Ex::Neg(Box::new(own(a, owner))),
        Ex::Bin(op, a, b) => bin(*op, own(a, owner), own(b, owner)),
        Ex::Num(_) | Ex::Name { .. } => e.clone(),
    }
}

pub(crate) fn math_of(cx: &Ctx, n: Node) -> Result<Ex, ImportError> {
    let m = child(n, "math")
        .ok_or_else(|| cx.err(n, format!("<{}> has no <math>", n.tag_name().name())))?;
    let e = mathml(cx, m, 0)?;
    // The id a piecewise here is named after: the rule's variable, the
    // initial assignment's symbol, or the reaction of a kinetic law.
    let owner = n
        .attribute("variable")
        .or(n.attribute("symbol"))
        .or(n.attribute("id"))
        .or_else(|| n.parent_element().and_then(|p| p.attribute("id")))
        .unwrap_or("pw");
    Ok(own(&e, owner))
}

/// Function definitions, each body read with the ones defined before it.
pub(crate) fn read_functions(cx: &mut Ctx, model: Node) -> Result<(), ImportError> {
    for f in list(model, "listOfFunctionDefinitions", "functionDefinition") {
        let id = id_of(cx, f, "id")?;
        let lambda = child(f, "math")
            .and_then(|m| {
                child(m, "lambda")
                    .or_else(|| child(m, "semantics").and_then(|s| child(s, "lambda")))
            })
            .ok_or_else(|| cx.err(f, format!("function '{id}' has no <lambda>")))?;
        let mut params = Vec::new();
        let mut body = None;
        for c in elems(lambda) {
            if c.tag_name().name() == "bvar" {
                let ci = child(c, "ci").ok_or_else(|| cx.err(c, "<bvar> without <ci>"))?;
                params.push(ci.text().unwrap_or("").trim().to_string());
            } else {
                body = Some(mathml(cx, c, 0)?);
            }
        }
        let body = body.ok_or_else(|| cx.err(lambda, format!("function '{id}' has no body")))?;
        cx.funcs.insert(id, (params, body));
    }
    Ok(())
}

/// Whether an expression reads SBML's `time`.
pub(crate) fn uses_time(e: &Ex) -> bool {
    match e {
        Ex::Num(n) => n == TIME,
        Ex::Name { .. } => false,
        Ex::Neg(a) => uses_time(a),
        Ex::Bin(_, a, b) => uses_time(a) || uses_time(b),
        Ex::Call(_, args) => args.iter().any(uses_time),
    }
}
