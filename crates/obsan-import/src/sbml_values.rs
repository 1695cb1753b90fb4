//! The numbers an SBML file gives, named as `sbml_to_sys` writes the `.sys`
//! model: global and kinetic-law parameter values, compartment sizes,
//! speciesReference stoichiometries, and each species' initial value as its
//! state is written (a concentration, amount / size, unless
//! `hasOnlySubstanceUnits`, then an amount, concentration * size).
//! Initial assignments (and assignment rules, at time 0) are evaluated in
//! floating point from those numbers; one whose math obsan cannot read or
//! whose inputs have no value is left out, so a simulation asks for its id
//! by name instead of using a wrong number.

use crate::ex::{apply_fn, Ex, RESERVED};
use crate::sbml_math::{child, mathml, read_functions, Ctx};
use crate::ImportError;
use roxmltree::{Document, Node};
use std::collections::{BTreeMap, BTreeSet};

fn list<'a, 'i>(model: Node<'a, 'i>, outer: &str, inner: &'a str) -> Vec<Node<'a, 'i>> {
    model
        .children()
        .filter(|c| c.is_element() && c.tag_name().name() == outer)
        .flat_map(|l| l.children())
        .filter(move |c| c.is_element() && c.tag_name().name() == inner)
        .collect()
}

fn num(n: Node, attr: &str) -> Option<f64> {
    n.attribute(attr)
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|v| v.is_finite())
}

fn sys_id(id: &str) -> String {
    let mut s = id.to_string();
    if RESERVED.contains(&s.as_str()) || s == crate::sbml_math::TIME {
        s.push('_');
    }
    s
}

/// Numeric value of `e` from `vals`; `None` when a name has no value or the
/// result is not finite.
fn eval(e: &Ex, vals: &BTreeMap<String, f64>) -> Option<f64> {
    let v = match e {
        Ex::Num(s) if s == "pi" => std::f64::consts::PI,
        // Initial values are at time 0.
        Ex::Num(s) if s == crate::sbml_math::TIME => 0.0,
        Ex::Num(s) => s.parse().ok()?,
        Ex::Name { name, .. } => *vals.get(name)?,
        Ex::Neg(a) => -eval(a, vals)?,
        Ex::Bin(op, a, b) => {
            let (x, y) = (eval(a, vals)?, eval(b, vals)?);
            match op {
                '+' => x + y,
                '-' => x - y,
                '*' => x * y,
                '/' => x / y,
                '^' => x.powf(y),
                _ => return None,
            }
        }
        Ex::Call(f, args) => {
            let [a] = args.as_slice() else {
                return None;
            };
            apply_fn(f, eval(a, vals)?)?
        }
    };
    v.is_finite().then_some(v)
}

/// Each species' initial value as its state is written, where the file and
/// the compartment sizes known so far give it.
fn species_value(s: Node, sizes: &BTreeMap<String, f64>) -> Option<f64> {
    let size = s
        .attribute("compartment")
        .and_then(|c| sizes.get(c))
        .copied();
    let amount_units = s.attribute("hasOnlySubstanceUnits") == Some("true");
    match (num(s, "initialAmount"), num(s, "initialConcentration")) {
        (Some(a), _) if amount_units => Some(a),
        (_, Some(c)) if amount_units => size.map(|z| c * z),
        (_, Some(c)) => Some(c),
        (Some(a), None) => size.filter(|z| *z != 0.0).map(|z| a / z),
        (None, None) => None,
    }
}

/// `(name, value)` of every number the file gives, sorted by name.
pub fn sbml_values(text: &str) -> Result<Vec<(String, f64)>, ImportError> {
    let doc = Document::parse(text).map_err(|e| {
        let p = e.pos();
        ImportError::at(p.row as usize, p.col as usize, e.to_string())
    })?;
    let Some(model) = doc
        .root_element()
        .children()
        .find(|c| c.is_element() && c.tag_name().name() == "model")
    else {
        return Err(ImportError::at(1, 1, "no <model> element"));
    };
    let mut cx = Ctx {
        doc: &doc,
        funcs: BTreeMap::new(),
    };
    // A function definition obsan cannot read only leaves out the values
    // that call it.
    let _ = read_functions(&mut cx, model);
    // `(symbol, math)` of initial assignments, then of assignment rules
    // (their value at time 0, which other initial values may use).
    let mut formulas: Vec<(String, Option<Ex>)> = Vec::new();
    for n in list(model, "listOfInitialAssignments", "initialAssignment")
        .into_iter()
        .chain(list(model, "listOfRules", "assignmentRule"))
    {
        let sym = n.attribute("symbol").or(n.attribute("variable"));
        if let Some(sym) = sym {
            let e = child(n, "math").and_then(|m| mathml(&cx, m, 0).ok());
            formulas.push((sym.to_string(), e));
        }
    }
    let set_later: BTreeSet<&str> = formulas.iter().map(|f| f.0.as_str()).collect();
    let mut out = BTreeMap::new();
    let mut sizes = BTreeMap::new();
    for c in list(model, "listOfCompartments", "compartment") {
        if let (Some(id), Some(v)) = (c.attribute("id"), num(c, "size")) {
            // A size a formula replaces is stale: no species amount is
            // divided by it until the formula has its value.
            if !set_later.contains(id) {
                sizes.insert(id.to_string(), v);
                out.insert(id.to_string(), v);
            }
        }
    }
    for p in list(model, "listOfParameters", "parameter") {
        if let (Some(id), Some(v)) = (p.attribute("id"), num(p, "value")) {
            if !set_later.contains(id) {
                out.insert(id.to_string(), v);
            }
        }
    }
    // Kinetic-law parameters, named `REACTION_ID` as the `.sys` names them,
    // and the stoichiometry a speciesReference id names.
    for r in list(model, "listOfReactions", "reaction") {
        for sr in list(r, "listOfReactants", "speciesReference")
            .into_iter()
            .chain(list(r, "listOfProducts", "speciesReference"))
        {
            if let Some(id) = sr.attribute("id").filter(|id| !set_later.contains(id)) {
                out.insert(id.to_string(), num(sr, "stoichiometry").unwrap_or(1.0));
            }
        }
        let (Some(rid), Some(law)) = (r.attribute("id"), child(r, "kineticLaw")) else {
            continue;
        };
        for lp in list(law, "listOfParameters", "parameter")
            .into_iter()
            .chain(list(law, "listOfLocalParameters", "localParameter"))
        {
            if let (Some(id), Some(v)) = (lp.attribute("id"), num(lp, "value")) {
                out.insert(format!("{rid}_{id}"), v);
            }
        }
    }
    let species = list(model, "listOfSpecies", "species");
    // Each round adds the values whose inputs are known; a round that adds
    // none ends it (what is left refers to itself or to a missing value).
    loop {
        let mut added = false;
        for s in &species {
            let Some(id) = s.attribute("id").filter(|id| !set_later.contains(id)) else {
                continue;
            };
            if !out.contains_key(id) {
                if let Some(v) = species_value(*s, &sizes) {
                    out.insert(id.to_string(), v);
                    added = true;
                }
            }
        }
        for (sym, e) in &formulas {
            if out.contains_key(sym) {
                continue;
            }
            if let Some(v) = e.as_ref().and_then(|e| eval(e, &out)) {
                out.insert(sym.clone(), v);
                sizes.insert(sym.clone(), v);
                added = true;
            }
        }
        if !added {
            break;
        }
    }
    Ok(out.into_iter().map(|(id, v)| (sys_id(&id), v)).collect())
}
