//! SBML `<piecewise>` of time and constants (dosing switches) as known
//! inputs: each such piecewise in the resolved equations becomes an input
//! `u_OWNER` of the `.sys` (OWNER the rule variable or reaction holding it),
//! its course a function of time that `sbml_inputs` writes out. A
//! piecewise that reads a state is dynamics a `.sys` cannot state: refused
//! at the state's name.

use crate::ex::{show, Ex};
use crate::sbml_math::PIECEWISE;
use crate::ImportError;

type At = (usize, usize);

/// A piecewise made a known input.
#[derive(Clone, Debug)]
pub(crate) struct PwInput {
    /// Its `.sys` name, `u_OWNER` (`_2`, ... when one owner holds several).
    pub name: String,
    /// The piecewise's text: the same piecewise (through assignment rules)
    /// is one input.
    pub key: String,
    /// The piecewise, assignment rules and sizes substituted.
    pub expr: Ex,
    /// Its `<piecewise>` element.
    pub at: At,
}

/// The place and owner encoded in a piecewise call name.
pub(crate) fn place(f: &str) -> Option<(At, &str)> {
    let rest = f.strip_prefix(PIECEWISE)?;
    let mut parts = rest.splitn(2, '@');
    let lc = parts.next()?;
    let owner = parts.next().unwrap_or("pw");
    let (l, c) = lc.split_once(':')?;
    Some(((l.parse().ok()?, c.parse().ok()?), owner))
}

fn key_of(e: &Ex) -> String {
    let mut s = String::new();
    show(e, &mut s, &|n: &str| n.to_string());
    s
}

/// `e` with each outermost piecewise replaced by its input, new ones added
/// to `inputs`. `states`: the names a piecewise may not read; `taken`: the
/// model's ids, which an input name must avoid.
pub(crate) fn extract(
    e: &Ex,
    states: &[String],
    taken: &[String],
    inputs: &mut Vec<PwInput>,
) -> Result<Ex, ImportError> {
    Ok(match e {
        Ex::Call(f, args) => match place(f) {
            Some((at, owner)) => {
                let mut bad = None;
                names_at(e, &mut |n, p| {
                    if bad.is_none() && states.iter().any(|s| s == n) {
                        bad = Some((n.to_string(), p));
                    }
                });
                if let Some((n, p)) = bad {
                    return Err(ImportError::at(
                        p.0,
                        p.1,
                        format!(
                            "the <piecewise> at line {} reads the state '{n}': only a piecewise of \
                             time and constants is read (as a known input)",
                            at.0
                        ),
                    ));
                }
                let key = key_of(e);
                if let Some(i) = inputs.iter().find(|i| i.key == key) {
                    return Ok(input_name(&i.name));
                }
                let base = format!("u_{owner}");
                let mut name = base.clone();
                let mut k = 1;
                while taken.contains(&name) || inputs.iter().any(|i| i.name == name) {
                    k += 1;
                    name = format!("{base}_{k}");
                }
                inputs.push(PwInput {
                    name: name.clone(),
                    key,
                    expr: e.clone(),
                    at,
                });
                input_name(&name)
            }
            None => Ex::Call(
                f.clone(),
                args.iter()
                    .map(|a| extract(a, states, taken, inputs))
                    .collect::<Result<_, _>>()?,
            ),
        },
        Ex::Neg(a) => Ex::Neg(Box::new(extract(a, states, taken, inputs)?)),
        Ex::Bin(op, a, b) => Ex::Bin(
            *op,
            Box::new(extract(a, states, taken, inputs)?),
            Box::new(extract(b, states, taken, inputs)?),
        ),
        Ex::Num(_) | Ex::Name { .. } => e.clone(),
    })
}

/// `e` with each piecewise that is one of `inputs` replaced by its name; any
/// other piecewise (one only an output or observable uses) is refused.
pub(crate) fn replace(e: &Ex, inputs: &[PwInput]) -> Result<Ex, ImportError> {
    Ok(match e {
        Ex::Call(f, args) => match place(f) {
            Some((at, _)) => {
                let key = key_of(e);
                match inputs.iter().find(|i| i.key == key) {
                    Some(i) => input_name(&i.name),
                    None => {
                        return Err(ImportError::at(
                            at.0,
                            at.1,
                            "a <piecewise> that no equation uses (only an output) is not \
                             supported: a known input must drive the dynamics",
                        ))
                    }
                }
            }
            None => Ex::Call(
                f.clone(),
                args.iter()
                    .map(|a| replace(a, inputs))
                    .collect::<Result<_, _>>()?,
            ),
        },
        Ex::Neg(a) => Ex::Neg(Box::new(replace(a, inputs)?)),
        Ex::Bin(op, a, b) => Ex::Bin(
            *op,
            Box::new(replace(a, inputs)?),
            Box::new(replace(b, inputs)?),
        ),
        Ex::Num(_) | Ex::Name { .. } => e.clone(),
    })
}

fn names_at(e: &Ex, f: &mut dyn FnMut(&str, At)) {
    match e {
        Ex::Name { name, at, .. } => f(name, *at),
        Ex::Neg(a) => names_at(a, f),
        Ex::Bin(_, a, b) => {
            names_at(a, f);
            names_at(b, f);
        }
        Ex::Call(_, args) => args.iter().for_each(|a| names_at(a, f)),
        Ex::Num(_) => {}
    }
}

fn input_name(n: &str) -> Ex {
    Ex::Name {
        name: n.to_string(),
        timed: false,
        at: (1, 1),
    }
}
