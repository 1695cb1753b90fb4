//! The expression tree every importer builds (Julia, MathML, MATLAB, PEtab
//! formulas) and its `.sys` text, with the names a `.sys` file reserves.

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

/// A name from another tool (a model key, an SBML id, a file stem) as a `.sys`
/// identifier: other characters become `_`, a leading digit gets a `_` before
/// it, and a reserved word a `_` after it.
pub(crate) fn sys_identifier(raw: &str) -> String {
    let mut s: String = raw
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

/// A one-argument function of the `.sys` grammar at a number, `None` for any
/// other name (the importers' numeric evaluators share it).
pub(crate) fn apply_fn(f: &str, x: f64) -> Option<f64> {
    Some(match f {
        "exp" => x.exp(),
        "log" => x.ln(),
        "sqrt" => x.sqrt(),
        "sin" => x.sin(),
        "cos" => x.cos(),
        "tan" => x.tan(),
        "atan" => x.atan(),
        _ => return None,
    })
}
