//! The time course of the known inputs an SBML model's piecewise of time
//! become (`sbml_pw`), in the `--inputs FILE.csv` format `obsan simulate`
//! reads: header `t,<inputs>`, the value linear between rows, two rows at
//! one time a step. The course is exact, not sampled: every condition must
//! compare time with a constant expression (its threshold, a breakpoint,
//! is that expression's value from the file's numbers), so between
//! breakpoints the piece that holds is fixed, and every piece must be
//! affine in time, so two rows per interval give it exactly. Anything else
//! is refused at the `<piecewise>`.

use crate::ex::{apply_fn, Ex, RESERVED};
use crate::sbml::Sbml;
use crate::sbml_math::{uses_time, TIME};
use crate::sbml_pw::place;
use crate::ImportError;
use std::collections::BTreeMap;

/// The known inputs of an SBML model and, for a horizon, their course.
#[derive(Clone, Debug)]
pub struct SbmlInputs {
    /// Input names as the `.sys` declares them.
    pub names: Vec<String>,
    /// The line and column of each input's `<piecewise>`.
    pub places: Vec<(usize, usize)>,
    /// `(t, value of each input)`, increasing `t` from 0 to the horizon,
    /// a repeated `t` at a step (the value before, then after).
    pub rows: Vec<(f64, Vec<f64>)>,
}

impl SbmlInputs {
    /// The course as CSV text (`{:?}` numbers: each reads back to its f64).
    pub fn csv(&self) -> String {
        let mut s = format!("t,{}\n", self.names.join(","));
        for (t, v) in &self.rows {
            let cells: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
            s.push_str(&format!("{t:?},{}\n", cells.join(",")));
        }
        s
    }
}

/// The inputs `sbml_to_sys` declares for the piecewise of time in `text`
/// and, with `until`, their exact course over `[0, until]` from the file's
/// numbers (`sbml_values`).
pub fn sbml_inputs(text: &str, until: Option<f64>) -> Result<SbmlInputs, ImportError> {
    let m = Sbml::read(text)?;
    let names: Vec<String> = m.inputs.iter().map(|i| i.name.clone()).collect();
    let places: Vec<(usize, usize)> = m.inputs.iter().map(|i| i.at).collect();
    let mut out = SbmlInputs {
        names,
        places,
        rows: Vec::new(),
    };
    let Some(until) = until else {
        return Ok(out);
    };
    if !(until.is_finite() && until > 0.0) {
        return Err(ImportError::at(
            m.model_at.0,
            m.model_at.1,
            format!("the horizon must be a positive number, not {until}"),
        ));
    }
    if m.inputs.is_empty() {
        return Ok(out);
    }
    let vals: BTreeMap<String, f64> = crate::sbml_values(text)?.into_iter().collect();
    let mut cuts = vec![0.0, until];
    for i in &m.inputs {
        affine(&i.expr, i.at)?;
        breakpoints(&i.expr, i.at, &vals, &mut cuts).map_err(|e| match (e.line, e.col) {
            (1, 1) => ImportError::at(i.at.0, i.at.1, e.message),
            _ => e,
        })?;
    }
    cuts.retain(|c| (0.0..=until).contains(c));
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1]);
        // No threshold lies inside (a, b): the conditions hold at its
        // midpoint as everywhere in it.
        let mid = a + (b - a) / 2.0;
        let mut left = Vec::new();
        let mut right = Vec::new();
        for i in &m.inputs {
            // An evaluation error without a place of its own is the piecewise's.
            let here = |e: ImportError| match (e.line, e.col) {
                (1, 1) => ImportError::at(i.at.0, i.at.1, e.message),
                _ => e,
            };
            left.push(eval(&i.expr, a, mid, &vals).map_err(here)?);
            right.push(eval(&i.expr, b, mid, &vals).map_err(here)?);
        }
        match out.rows.last() {
            Some((t, v)) if *t == a && *v == left => {}
            _ => out.rows.push((a, left)),
        }
        out.rows.push((b, right));
    }
    Ok(out)
}

/// The degree of `e` in time when at most 1 (affine), else `None`.
fn degree(e: &Ex) -> Option<u8> {
    Some(match e {
        Ex::Num(n) if n == TIME => 1,
        Ex::Num(_) | Ex::Name { .. } => 0,
        Ex::Neg(a) => degree(a)?,
        Ex::Bin('+' | '-', a, b) => degree(a)?.max(degree(b)?),
        Ex::Bin('*', a, b) => match degree(a)? + degree(b)? {
            d @ (0 | 1) => d,
            _ => return None,
        },
        Ex::Bin('/', a, b) if degree(b)? == 0 => degree(a)?,
        Ex::Call(f, args) if place(f).is_some() => {
            // Values at even places (and the last, <otherwise>); conditions
            // are checked by `breakpoints`.
            let mut d = 0;
            for (k, a) in args.iter().enumerate() {
                if k % 2 == 0 {
                    d = d.max(degree(a)?);
                }
            }
            d
        }
        _ if !uses_time(e) => 0,
        _ => return None,
    })
}

fn affine(e: &Ex, at: (usize, usize)) -> Result<(), ImportError> {
    match degree(e) {
        Some(_) => Ok(()),
        None => Err(ImportError::at(
            at.0,
            at.1,
            "a piece of this <piecewise> is not affine in time: its course is written exactly \
             only for pieces linear in time (supply the input's course yourself)",
        )),
    }
}

/// Thresholds of the time comparisons in the conditions of `e` (and of any
/// piecewise inside it), added to `cuts`.
fn breakpoints(
    e: &Ex,
    at: (usize, usize),
    vals: &BTreeMap<String, f64>,
    cuts: &mut Vec<f64>,
) -> Result<(), ImportError> {
    match e {
        Ex::Call(f, args) if place(f).is_some() => {
            for (k, a) in args.iter().enumerate() {
                if k % 2 == 1 {
                    atoms(a, at, vals, cuts)?;
                } else {
                    breakpoints(a, at, vals, cuts)?;
                }
            }
        }
        Ex::Call(_, args) => {
            for a in args {
                breakpoints(a, at, vals, cuts)?;
            }
        }
        Ex::Neg(a) => breakpoints(a, at, vals, cuts)?,
        Ex::Bin(_, a, b) => {
            breakpoints(a, at, vals, cuts)?;
            breakpoints(b, at, vals, cuts)?;
        }
        Ex::Num(_) | Ex::Name { .. } => {}
    }
    Ok(())
}

/// A condition's comparisons: each is of constants (no threshold) or of
/// time itself with a constant expression (its value is a threshold).
fn atoms(
    c: &Ex,
    at: (usize, usize),
    vals: &BTreeMap<String, f64>,
    cuts: &mut Vec<f64>,
) -> Result<(), ImportError> {
    let Ex::Call(op, args) = c else {
        return Ok(());
    };
    if matches!(op.as_str(), "and" | "or" | "xor" | "not") {
        for a in args {
            atoms(a, at, vals, cuts)?;
        }
        return Ok(());
    }
    let is_t = |e: &Ex| matches!(e, Ex::Num(n) if n == TIME);
    match args.as_slice() {
        [a, b] if !uses_time(a) && !uses_time(b) => {
            breakpoints(a, at, vals, cuts)?;
            breakpoints(b, at, vals, cuts)
        }
        [a, b] if is_t(a) && !uses_time(b) => {
            cuts.push(eval(b, 0.0, 0.0, vals)?);
            Ok(())
        }
        [a, b] if is_t(b) && !uses_time(a) => {
            cuts.push(eval(a, 0.0, 0.0, vals)?);
            Ok(())
        }
        _ => Err(ImportError::at(
            at.0,
            at.1,
            format!(
                "a condition of this <piecewise> ({op}) is not a comparison of time with a \
                 constant expression: its switching times cannot be solved exactly"
            ),
        )),
    }
}

fn lookup(n: &str, vals: &BTreeMap<String, f64>) -> Option<f64> {
    let mut s = n.to_string();
    if RESERVED.contains(&n) || n == TIME {
        s.push('_');
    }
    vals.get(&s).copied()
}

/// The value of `e` with time `t` in its arithmetic and `tc` in its
/// conditions (the interval's midpoint: which piece holds there).
fn eval(e: &Ex, t: f64, tc: f64, vals: &BTreeMap<String, f64>) -> Result<f64, ImportError> {
    let v = match e {
        Ex::Num(s) if s == TIME => t,
        Ex::Num(s) if s == "pi" => std::f64::consts::PI,
        Ex::Num(s) => s
            .parse()
            .map_err(|_| ImportError::at(1, 1, format!("'{s}' is not a number")))?,
        Ex::Name { name, at, .. } => lookup(name, vals).ok_or_else(|| {
            ImportError::at(
                at.0,
                at.1,
                format!("'{name}' has no value in the file: the input's course needs it"),
            )
        })?,
        Ex::Neg(a) => -eval(a, t, tc, vals)?,
        Ex::Bin(op, a, b) => {
            let (x, y) = (eval(a, t, tc, vals)?, eval(b, t, tc, vals)?);
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => x / y,
                _ => x.powf(y),
            }
        }
        Ex::Call(f, args) => match place(f) {
            Some((at, _)) => return piece(args, at, t, tc, vals),
            None => {
                let [a] = args.as_slice() else {
                    return Err(ImportError::at(1, 1, format!("cannot evaluate '{f}'")));
                };
                let x = eval(a, t, tc, vals)?;
                apply_fn(f, x)
                    .ok_or_else(|| ImportError::at(1, 1, format!("cannot evaluate '{f}'")))?
            }
        },
    };
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ImportError::at(
            1,
            1,
            format!("an input's value at time {t} is not finite"),
        ))
    }
}

/// The value of the first piece whose condition holds at `tc`, else the
/// `<otherwise>`.
fn piece(
    args: &[Ex],
    at: (usize, usize),
    t: f64,
    tc: f64,
    vals: &BTreeMap<String, f64>,
) -> Result<f64, ImportError> {
    for pair in args.chunks(2) {
        match pair {
            [v, c] if holds(c, tc, vals)? => return eval(v, t, tc, vals),
            [v] => return eval(v, t, tc, vals),
            _ => {}
        }
    }
    Err(ImportError::at(
        at.0,
        at.1,
        format!("no piece of this <piecewise> holds at time {tc} and it has no <otherwise>"),
    ))
}

fn holds(c: &Ex, tc: f64, vals: &BTreeMap<String, f64>) -> Result<bool, ImportError> {
    let Ex::Call(op, args) = c else {
        return Ok(matches!(c, Ex::Num(s) if s == "true"));
    };
    let all = |f: &dyn Fn(&[bool]) -> bool| -> Result<bool, ImportError> {
        let b: Vec<bool> = args
            .iter()
            .map(|a| holds(a, tc, vals))
            .collect::<Result<_, _>>()?;
        Ok(f(&b))
    };
    match op.as_str() {
        "and" => all(&|b| b.iter().all(|x| *x)),
        "or" => all(&|b| b.iter().any(|x| *x)),
        "xor" => all(&|b| b.iter().filter(|x| **x).count() % 2 == 1),
        "not" => all(&|b| !b.first().copied().unwrap_or(false)),
        rel => {
            let [a, b] = args.as_slice() else {
                return Ok(false);
            };
            let (x, y) = (eval(a, tc, tc, vals)?, eval(b, tc, tc, vals)?);
            Ok(match rel {
                "lt" => x < y,
                "gt" => x > y,
                "leq" => x <= y,
                "geq" => x >= y,
                "eq" => x == y,
                _ => x != y,
            })
        }
    }
}
