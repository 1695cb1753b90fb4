//! The numbers an SBML file gives, named as `sbml_to_sys` writes the `.sys`
//! model: global and kinetic-law parameter values, compartment sizes, and each species'
//! initial value as its state is written (a concentration, amount / size,
//! unless `hasOnlySubstanceUnits`, then an amount, concentration * size).
//! Initial assignments are not evaluated here: an id they set is left out,
//! so a simulation asks for it by name instead of using a wrong number.

use crate::ex::RESERVED;
use crate::ImportError;
use roxmltree::{Document, Node};
use std::collections::BTreeMap;

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
    if RESERVED.contains(&s.as_str()) {
        s.push('_');
    }
    s
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
    let set_later: Vec<&str> = list(model, "listOfInitialAssignments", "initialAssignment")
        .iter()
        .filter_map(|n| n.attribute("symbol"))
        .collect();
    let mut out = BTreeMap::new();
    let mut sizes = BTreeMap::new();
    for c in list(model, "listOfCompartments", "compartment") {
        if let (Some(id), Some(v)) = (c.attribute("id"), num(c, "size")) {
            // A size an initial assignment replaces is stale: a species
            // amount is not divided by it (its concentration is left out).
            if !set_later.contains(&id) {
                sizes.insert(id.to_string(), v);
            }
            out.insert(id.to_string(), v);
        }
    }
    for p in list(model, "listOfParameters", "parameter") {
        if let (Some(id), Some(v)) = (p.attribute("id"), num(p, "value")) {
            out.insert(id.to_string(), v);
        }
    }
    // Kinetic-law parameters, named `REACTION_ID` as the `.sys` names them.
    for r in list(model, "listOfReactions", "reaction") {
        let (Some(rid), Some(law)) = (
            r.attribute("id"),
            r.children()
                .find(|c| c.is_element() && c.tag_name().name() == "kineticLaw"),
        ) else {
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
    for s in list(model, "listOfSpecies", "species") {
        let Some(id) = s.attribute("id") else {
            continue;
        };
        let size = s
            .attribute("compartment")
            .and_then(|c| sizes.get(c))
            .copied();
        let amount_units = s.attribute("hasOnlySubstanceUnits") == Some("true");
        let v = match (num(s, "initialAmount"), num(s, "initialConcentration")) {
            (Some(a), _) if amount_units => Some(a),
            (_, Some(c)) if amount_units => size.map(|z| c * z),
            (_, Some(c)) => Some(c),
            (Some(a), None) => size.filter(|z| *z != 0.0).map(|z| a / z),
            (None, None) => None,
        };
        if let Some(v) = v {
            out.insert(id.to_string(), v);
        }
    }
    Ok(out
        .into_iter()
        .filter(|(id, _)| !set_later.contains(&id.as_str()))
        .map(|(id, v)| (sys_id(&id), v))
        .collect())
}
