//! SBML (Level 2 and 3 core) to `.sys`: species changed by reactions become
//! states with `d[S]/dt = sum(stoichiometry * rate) / compartment size` (the
//! kinetic law is in substance per time; a species with
//! `hasOnlySubstanceUnits` is an amount and is not divided), rate rules give
//! their variable's equation, assignment rules are substituted, function
//! definitions inlined, compartments with a size folded in as numbers, global
//! and kinetic-law parameters become unknown params (local ones prefixed with
//! their reaction id). SBML has no outputs: `observe` names them (species or
//! parameter ids), or every state is measured. Refused with the element and its
//! line: events, algebraic rules, delays, avogadro, piecewise, `fast`
//! reactions, compartments that vary. A Level 3 speciesReference id is its
//! stoichiometry (a value, or a state under a rate rule); a conversion factor
//! multiplies the species' reaction terms.

use crate::ex::{show, sys_identifier, Ex, RESERVED};
use crate::sbml_math::{
    bin, child, elems, id_of, list, math_of, name, number, read_functions, subst, uses_time, Ctx,
    TIME,
};
use crate::sbml_pw::{extract, replace, PwInput};
use crate::{Converted, ImportError};
use roxmltree::{Document, Node};
use std::collections::BTreeMap;

type At = (usize, usize);
type Rules = BTreeMap<String, (Ex, At)>;

/// An SBML model read into equations (assignment rules and sizes already
/// substituted, every name checked), before outputs are chosen: shared by
/// `sbml_to_sys` and the PEtab importer, which adds its own outputs and fixes
/// some parameters.
pub(crate) struct Sbml {
    pub name: String,
    pub description: Option<String>,
    /// `(state, rhs, place of its species or rule)`, resolved.
    pub eqs: Vec<(String, Ex, At)>,
    /// Unknown constants in declaration order (global and local parameters,
    /// fixed species); may hold unused ones, which `emit` drops.
    pub params: Vec<String>,
    /// The `value` attribute of each global parameter that has one.
    pub values: BTreeMap<String, Ex>,
    /// Compartments without a size (known constants).
    pub consts: Vec<String>,
    /// Compartment sizes folded in.
    pub sizes: BTreeMap<String, Ex>,
    pub assign: Rules,
    pub model_at: At,
    /// Piecewise of time and constants, each a known input (see `sbml_pw`).
    pub inputs: Vec<PwInput>,
}

/// Translate an SBML document into `.sys` text. `observe`: the ids measured
/// (each an output `y_ID = ID`); empty: every state.
pub fn sbml_to_sys(text: &str, origin: &str, observe: &[String]) -> Result<Converted, ImportError> {
    let m = Sbml::read(text)?;
    let mut outputs: Vec<(String, Ex, Option<At>)> = Vec::new();
    if observe.is_empty() {
        for (v, _, at) in &m.eqs {
            outputs.push((format!("y_{v}"), name(v, *at), None));
        }
    } else {
        for o in observe {
            let e = if let Some((x, _)) = m.assign.get(o) {
                m.resolve(x)?
            } else if m.known().contains(&o.as_str()) {
                name(o, (1, 1))
            } else {
                return Err(ImportError::at(
                    m.model_at.0,
                    m.model_at.1,
                    format!("--observe '{o}' is not an id of this model"),
                ));
            };
            outputs.push((format!("y_{o}"), e, None));
        }
    }
    let mut header = vec![format!(
        "# Imported by `obsan import sbml` from {}.",
        one_line(origin)
    )];
    if observe.is_empty() {
        header.push(
            "# SBML has no outputs: every state is measured here (choose with --observe).".into(),
        );
    }
    let consts: Vec<(String, Option<Ex>)> = m.consts.iter().map(|c| (c.clone(), None)).collect();
    Ok(m.emit(header, &m.params, &consts, &outputs))
}

impl Sbml {
    /// Read the document: functions, rules, compartments, species,
    /// parameters, reactions, then the equations (resolved and checked).
    pub fn read(text: &str) -> Result<Sbml, ImportError> {
        let doc = Document::parse(text).map_err(|e| {
            let p = e.pos();
            ImportError::at(
                p.row as usize,
                p.col as usize,
                format!("not well-formed XML: {e}"),
            )
        })?;
        let mut cx = Ctx {
            doc: &doc,
            funcs: BTreeMap::new(),
        };
        let root = doc.root_element();
        if root.tag_name().name() != "sbml" {
            return Err(cx.err(root, "the root element is not <sbml>"));
        }
        let model = child(root, "model").ok_or_else(|| cx.err(root, "no <model>"))?;
        if let Some(e) = list(model, "listOfEvents", "event").first() {
            let id = e.attribute("id").unwrap_or("?");
            return Err(cx.err(
                *e,
                format!("<event> '{id}': events are not supported (discontinuous dynamics)"),
            ));
        }
        read_functions(&mut cx, model)?;
        let (assign, rate) = read_rules(&cx, model)?;
        let (mut consts, mut sizes) = read_compartments(&cx, model, &assign, &rate)?;
        let mut assign = assign;
        let stoich_states = stoichiometry_ids(&cx, model, &rate, &mut assign)?;
        constant_initial_assignments(&cx, model, &rate, &mut assign)?;
        consts.retain(|c| !assign.contains_key(c));
        sizes.retain(|c, _| !assign.contains_key(c));
        let species = read_species(&cx, model)?;
        let (mut params, mut param_states, mut values) =
            read_parameters(&cx, model, &assign, &rate)?;
        param_states.extend(stoich_states);
        let flux = read_reactions(&cx, model, &mut params, &mut values)?;
        let eqs = equations(
            &species,
            &param_states,
            (&assign, &rate),
            &flux,
            &mut params,
        )?;
        if eqs.is_empty() {
            return Err(cx.err(
                model,
                "the model has no dynamics (no species changed by a reaction or rate rule)",
            ));
        }
        let mut m = Sbml {
            name: sys_name(model),
            description: model
                .attribute("name")
                .map(one_line)
                .filter(|n| !n.is_empty()),
            eqs: Vec::new(),
            params,
            values,
            consts,
            sizes,
            assign,
            model_at: cx.pos(model),
            inputs: Vec::new(),
        };
        m.params.retain(|p| !eqs.iter().any(|e| &e.0 == p));
        let mut body = Vec::new();
        let mut known: Vec<String> = eqs
            .iter()
            .map(|e| e.0.clone())
            .chain(m.params.iter().cloned())
            .chain(m.consts.iter().cloned())
            .collect();
        let states: Vec<String> = eqs.iter().map(|e| e.0.clone()).collect();
        let mut inputs = Vec::new();
        let mut resolved = Vec::new();
        for (_, e, _) in &eqs {
            resolved.push(extract(&m.substitute(e)?, &states, &known, &mut inputs)?);
        }
        known.extend(inputs.iter().map(|i| i.name.clone()));
        m.inputs = inputs;
        for ((v, _, at), r) in eqs.iter().zip(resolved) {
            check_names(
                &r,
                &known,
                "a species, parameter or compartment of the model",
            )?;
            body.push((v.clone(), r, *at));
        }
        m.eqs = body;
        Ok(m)
    }

    /// The ids an output may use: states, parameters, known constants.
    pub fn known(&self) -> Vec<&str> {
        self.eqs
            .iter()
            .map(|e| e.0.as_str())
            .chain(self.params.iter().map(String::as_str))
            .chain(self.consts.iter().map(String::as_str))
            .collect()
    }

    /// Substitute assignment rules (they may use each other) and compartment
    /// sizes, and name each piecewise by its input.
    pub fn resolve(&self, e: &Ex) -> Result<Ex, ImportError> {
        replace(&self.substitute(e)?, &self.inputs)
    }

    /// Substitute assignment rules (they may use each other) and compartment sizes.
    fn substitute(&self, e: &Ex) -> Result<Ex, ImportError> {
        let mut cur = e.clone();
        // Each round removes one level of rule nesting; more rounds than rules means a cycle.
        for _ in 0..self.assign.len() + 2 {
            let mut hit = false;
            walk_names(&cur, &mut |n| {
                hit |= self.assign.contains_key(n) || self.sizes.contains_key(n)
            });
            if !hit {
                return Ok(cur);
            }
            cur = subst(&cur, &|n| {
                self.assign
                    .get(n)
                    .map(|(x, _)| x.clone())
                    .or_else(|| self.sizes.get(n).cloned())
            });
        }
        let at = self.assign.values().next().map_or((1, 1), |a| a.1);
        Err(ImportError::at(
            at.0,
            at.1,
            "assignment rules refer to each other in a cycle",
        ))
    }

    /// The `.sys` text: `header` comment lines, then the declarations (only
    /// the `params` and `consts` the equations and outputs use, in their
    /// order; a const with a value is written `const k = VALUE`), equations
    /// and outputs. An output's place, when given, goes in the line map.
    pub fn emit(
        &self,
        mut lines: Vec<String>,
        params: &[String],
        consts: &[(String, Option<Ex>)],
        outputs: &[(String, Ex, Option<At>)],
    ) -> Converted {
        let mut used: Vec<String> = Vec::new();
        for e in self
            .eqs
            .iter()
            .map(|b| &b.1)
            .chain(outputs.iter().map(|o| &o.1))
        {
            walk_names(e, &mut |n| {
                if !used.iter().any(|u| u == n) {
                    used.push(n.to_string());
                }
            });
        }
        let mut params: Vec<&String> = params.iter().filter(|p| used.contains(p)).collect();
        params.dedup();
        let rename = |n: &str| -> String {
            if RESERVED.contains(&n) || n == TIME {
                format!("{n}_")
            } else {
                n.to_string()
            }
        };
        let text = |e: &Ex| {
            let mut s = String::new();
            show(e, &mut s, &rename);
            s
        };
        if !self.sizes.is_empty() {
            let v: Vec<String> = self
                .sizes
                .iter()
                .map(|(k, e)| format!("{k} = {}", text(e)))
                .collect();
            lines.push(format!("# compartment sizes folded in: {}", v.join(", ")));
        }
        for i in self.inputs.iter().filter(|i| used.contains(&i.name)) {
            lines.push(format!(
                "# input {}: the <piecewise> at line {}, a known function of time (its course: \
                 obsan import sbml MODEL.xml --inputs-out FILE.csv --until T)",
                i.name, i.at.0
            ));
        }
        lines.push(format!("system {}", self.name));
        if let Some(d) = &self.description {
            lines.push(format!("description {d}"));
        }
        let names = |v: Vec<&String>| {
            v.into_iter()
                .map(|s| rename(s))
                .collect::<Vec<_>>()
                .join(", ")
        };
        lines.push(format!(
            "state {}",
            names(self.eqs.iter().map(|b| &b.0).collect())
        ));
        if !params.is_empty() {
            lines.push(format!("param {}", names(params)));
        }
        let generic: Vec<&String> = consts
            .iter()
            .filter(|c| c.1.is_none() && used.contains(&c.0))
            .map(|c| &c.0)
            .collect();
        if !generic.is_empty() {
            lines.push(format!("const {}", names(generic)));
        }
        let inputs: Vec<&String> = self
            .inputs
            .iter()
            .map(|i| &i.name)
            .filter(|n| used.contains(n))
            .collect();
        if !inputs.is_empty() {
            lines.push(format!("input {}", names(inputs)));
        }
        for (c, v) in consts {
            if let (Some(v), true) = (v, used.contains(c)) {
                lines.push(format!("const {} = {}", rename(c), text(v)));
            }
        }
        let mut line_map = Vec::new();
        for (v, e, at) in &self.eqs {
            lines.push(format!("{}' = {}", rename(v), text(e)));
            line_map.push((lines.len(), at.0, at.1));
        }
        let mut line_file = Vec::new();
        for (o, e, at) in outputs {
            lines.push(format!("output {} = {}", rename(o), text(e)));
            if let Some(at) = at {
                line_map.push((lines.len(), at.0, at.1));
                line_file.push(lines.len());
            }
        }
        let mut sys_text = lines.join("\n");
        sys_text.push('\n');
        Converted {
            name: self.name.clone(),
            sys_text,
            line_map,
            table_lines: line_file,
        }
    }
}

pub(crate) fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Every name of `e` must be in `known`, else an error at the name.
pub(crate) fn check_names(e: &Ex, known: &[String], what: &str) -> Result<(), ImportError> {
    let mut bad = None;
    walk_names_at(e, &mut |n, p| {
        if bad.is_none() && !known.iter().any(|k| k == n) {
            bad = Some((n.to_string(), p));
        }
    });
    match bad {
        Some((n, p)) => Err(ImportError::at(p.0, p.1, format!("'{n}' is not {what}"))),
        None => Ok(()),
    }
}

/// The model's id (or name) as a `.sys` system name.
fn sys_name(model: Node) -> String {
    let mid = model
        .attribute("id")
        .or(model.attribute("name"))
        .unwrap_or("sbml_model");
    sys_identifier(mid)
}

fn read_rules(cx: &Ctx, model: Node) -> Result<(Rules, Rules), ImportError> {
    let mut assign = Rules::new();
    let mut rate = Rules::new();
    if let Some(rules) = child(model, "listOfRules") {
        for r in elems(rules) {
            match r.tag_name().name() {
                "assignmentRule" => {
                    let v = id_of(cx, r, "variable")?;
                    assign.insert(v, (math_of(cx, r)?, cx.pos(r)));
                }
                "rateRule" => {
                    let v = id_of(cx, r, "variable")?;
                    rate.insert(v, (math_of(cx, r)?, cx.pos(r)));
                }
                "algebraicRule" => {
                    return Err(cx.err(
                        r,
                        "<algebraicRule>: algebraic rules (DAEs) are not supported",
                    ))
                }
                // SBML Level 1 rule names and anything else.
                other => return Err(cx.err(r, format!("<{other}> is not supported"))),
            }
        }
    }
    Ok((assign, rate))
}

/// Compartments: sizes folded in as numbers; without a size, a known constant.
fn read_compartments(
    cx: &Ctx,
    model: Node,
    assign: &Rules,
    rate: &Rules,
) -> Result<(Vec<String>, BTreeMap<String, Ex>), ImportError> {
    let mut consts = Vec::new();
    let mut sizes = BTreeMap::new();
    for c in list(model, "listOfCompartments", "compartment") {
        let id = id_of(cx, c, "id")?;
        if rate.contains_key(&id)
            || assign.contains_key(&id)
            || c.attribute("constant") == Some("false")
        {
            return Err(cx.err(
                c,
                format!("compartment '{id}' varies: only constant compartments are supported"),
            ));
        }
        match c.attribute("size").or(c.attribute("volume")) {
            Some(s) => {
                sizes.insert(id, number(cx, c, s)?);
            }
            None => consts.push(id),
        }
    }
    Ok((consts, sizes))
}

/// An initial assignment to a constant parameter or compartment holds at all
/// times: it is substituted like an assignment rule. (One to a species is an
/// initial value, which the analysis does not use.)
fn constant_initial_assignments(
    cx: &Ctx,
    model: Node,
    rate: &Rules,
    assign: &mut Rules,
) -> Result<(), ImportError> {
    let constant: Vec<String> = list(model, "listOfParameters", "parameter")
        .into_iter()
        .chain(list(model, "listOfCompartments", "compartment"))
        .filter(|p| p.attribute("constant") != Some("false"))
        .filter_map(|p| p.attribute("id").map(str::to_string))
        .collect();
    for ia in list(model, "listOfInitialAssignments", "initialAssignment") {
        let v = id_of(cx, ia, "symbol")?;
        if constant.contains(&v) && !rate.contains_key(&v) && !assign.contains_key(&v) {
            let e = at_time_zero(&math_of(cx, ia)?, assign);
            assign.insert(v, (e, cx.pos(ia)));
        }
    }
    Ok(())
}

/// An initial assignment's value: taken at time 0, so where its math uses
/// time (itself or through assignment rules) those rules are expanded and
/// `t` set to 0; otherwise the math as written.
fn at_time_zero(e: &Ex, assign: &Rules) -> Ex {
    let mut cur = e.clone();
    // Each round expands one level of rules; a chain is at most every rule
    // long (a cycle is refused where the rules are substituted).
    for _ in 0..=assign.len() {
        let mut more = false;
        walk_names(&cur, &mut |n| more |= assign.contains_key(n));
        if !more {
            break;
        }
        cur = subst(&cur, &|n| assign.get(n).map(|r| r.0.clone()));
    }
    if !uses_time(&cur) {
        return e.clone();
    }
    fn zero(e: &Ex) -> Ex {
        match e {
            Ex::Num(n) if n == TIME => Ex::Num("0".into()),
            Ex::Num(_) | Ex::Name { .. } => e.clone(),
            Ex::Neg(a) => Ex::Neg(Box::new(zero(a))),
            Ex::Bin(op, a, b) => bin(*op, zero(a), zero(b)),
            Ex::Call(f, args) => Ex::Call(f.clone(), args.iter().map(zero).collect()),
        }
    }
    zero(&cur)
}

/// A speciesReference with an id (SBML Level 3) names its stoichiometry, a
/// value kinetic laws and rules may use. Driven by a rate rule it is a state
/// (returned, with its place); set by an assignment rule it is that rule;
/// otherwise it is constant (events are refused): its initial assignment, or
/// its `stoichiometry` attribute, substituted like an assignment rule.
fn stoichiometry_ids(
    cx: &Ctx,
    model: Node,
    rate: &Rules,
    assign: &mut Rules,
) -> Result<Vec<(String, At)>, ImportError> {
    let initial: Vec<Node> = list(model, "listOfInitialAssignments", "initialAssignment");
    let mut states = Vec::new();
    for r in list(model, "listOfReactions", "reaction") {
        for sr in list(r, "listOfReactants", "speciesReference")
            .into_iter()
            .chain(list(r, "listOfProducts", "speciesReference"))
        {
            if sr.attribute("id").is_none() {
                continue;
            }
            let id = id_of(cx, sr, "id")?;
            if assign.contains_key(&id) {
                continue;
            }
            if rate.contains_key(&id) {
                states.push((id, cx.pos(sr)));
                continue;
            }
            let value = match initial
                .iter()
                .find(|ia| ia.attribute("symbol") == Some(&id))
            {
                Some(ia) => (at_time_zero(&math_of(cx, *ia)?, assign), cx.pos(*ia)),
                None => (stoichiometry_attr(cx, sr)?, cx.pos(sr)),
            };
            assign.insert(id, value);
        }
    }
    Ok(states)
}

/// The `stoichiometry` attribute; 1 when absent (SBML Level 2's default).
fn stoichiometry_attr(cx: &Ctx, sr: Node) -> Result<Ex, ImportError> {
    match sr.attribute("stoichiometry") {
        Some(s) => number(cx, sr, s),
        None => Ok(Ex::Num("1".into())),
    }
}

struct Sp {
    id: String,
    comp: String,
    amount: bool,
    /// SBML Level 3 `conversionFactor` (the species' own, else the model's):
    /// the reactions' extent is multiplied by it.
    conv: Option<String>,
    fixed: bool,
    at: At,
}

fn read_species(cx: &Ctx, model: Node) -> Result<Vec<Sp>, ImportError> {
    let mut species = Vec::new();
    let model_conv = match model.attribute("conversionFactor") {
        Some(_) => Some(id_of(cx, model, "conversionFactor")?),
        None => None,
    };
    for s in list(model, "listOfSpecies", "species") {
        let conv = match s.attribute("conversionFactor") {
            Some(_) => Some(id_of(cx, s, "conversionFactor")?),
            None => model_conv.clone(),
        };
        species.push(Sp {
            id: id_of(cx, s, "id")?,
            comp: id_of(cx, s, "compartment")?,
            amount: s.attribute("hasOnlySubstanceUnits") == Some("true"),
            conv,
            fixed: s.attribute("boundaryCondition") == Some("true")
                || s.attribute("constant") == Some("true"),
            at: cx.pos(s),
        });
    }
    Ok(species)
}

/// Global parameters: unknown constants, or states when a rate rule drives
/// them (those with an assignment rule are substituted). Values are kept for
/// the PEtab importer.
#[allow(clippy::type_complexity)]
fn read_parameters(
    cx: &Ctx,
    model: Node,
    assign: &Rules,
    rate: &Rules,
) -> Result<(Vec<String>, Vec<(String, At)>, BTreeMap<String, Ex>), ImportError> {
    let mut params = Vec::new();
    let mut param_states = Vec::new();
    let mut values = BTreeMap::new();
    for p in list(model, "listOfParameters", "parameter") {
        let id = id_of(cx, p, "id")?;
        if assign.contains_key(&id) {
            continue;
        }
        if let Some(v) = p.attribute("value") {
            // A value that is not a finite number (NaN, INF) is left out.
            if let Ok(x) = number(cx, p, v) {
                values.insert(id.clone(), x);
            }
        }
        if rate.contains_key(&id) {
            param_states.push((id, cx.pos(p)));
        } else {
            params.push(id);
        }
    }
    Ok((params, param_states, values))
}

/// Reactions: for each species, the terms `±stoichiometry * rate`; local
/// parameters become params `REACTION_ID` (their values kept).
fn read_reactions(
    cx: &Ctx,
    model: Node,
    params: &mut Vec<String>,
    values: &mut BTreeMap<String, Ex>,
) -> Result<BTreeMap<String, Vec<Ex>>, ImportError> {
    let mut flux: BTreeMap<String, Vec<Ex>> = BTreeMap::new();
    for r in list(model, "listOfReactions", "reaction") {
        let rid = id_of(cx, r, "id")?;
        if r.attribute("fast") == Some("true") {
            // Rapid equilibrium makes the reaction an algebraic constraint
            // (a DAE), which a .sys model cannot state.
            return Err(cx.err(
                r,
                format!(
                    "reaction '{rid}' is fast: SBML's rapid-equilibrium semantics (an algebraic \
                     constraint) is not supported"
                ),
            ));
        }
        let law = child(r, "kineticLaw")
            .ok_or_else(|| cx.err(r, format!("reaction '{rid}' has no <kineticLaw>")))?;
        let mut local: BTreeMap<String, Ex> = BTreeMap::new();
        for lp in list(law, "listOfParameters", "parameter")
            .into_iter()
            .chain(list(law, "listOfLocalParameters", "localParameter"))
        {
            let id = id_of(cx, lp, "id")?;
            let g = format!("{rid}_{id}");
            local.insert(id, name(&g, cx.pos(lp)));
            if let Some(x) = lp.attribute("value").and_then(|v| number(cx, lp, v).ok()) {
                values.insert(g.clone(), x);
            }
            params.push(g);
        }
        let v = subst(&math_of(cx, law)?, &|n| local.get(n).cloned());
        for (listname, sign) in [("listOfReactants", -1), ("listOfProducts", 1)] {
            for sr in list(r, listname, "speciesReference") {
                let sid = id_of(cx, sr, "species")?;
                // SBML Level 2's stoichiometryMath, or a Level 3 id (its
                // value substituted or a state, see `stoichiometry_ids`).
                let st = if let Some(m) = child(sr, "stoichiometryMath") {
                    math_of(cx, m)?
                } else if let Some(id) = sr.attribute("id") {
                    name(id, cx.pos(sr))
                } else {
                    stoichiometry_attr(cx, sr)?
                };
                let term = match &st {
                    Ex::Num(s) if s == "1" => v.clone(),
                    _ => bin('*', st, v.clone()),
                };
                flux.entry(sid).or_default().push(if sign < 0 {
                    Ex::Neg(Box::new(term))
                } else {
                    term
                });
            }
        }
    }
    Ok(flux)
}

/// States and their equations: a rate rule, or the reactions' sum over the
/// compartment size (not for amounts); a species no reaction changes, or a
/// boundary or constant one, is a param.
fn equations(
    species: &[Sp],
    param_states: &[(String, At)],
    (assign, rate): (&Rules, &Rules),
    flux: &BTreeMap<String, Vec<Ex>>,
    params: &mut Vec<String>,
) -> Result<Vec<(String, Ex, At)>, ImportError> {
    let mut eqs: Vec<(String, Ex, At)> = Vec::new();
    for s in species {
        if assign.contains_key(&s.id) {
            continue;
        }
        if let Some((e, at)) = rate.get(&s.id) {
            eqs.push((s.id.clone(), e.clone(), *at));
        } else if s.fixed || !flux.contains_key(&s.id) {
            params.push(s.id.clone());
        } else {
            let terms = flux.get(&s.id).cloned().unwrap_or_default();
            let sum = terms
                .into_iter()
                .reduce(|a, b| match b {
                    Ex::Neg(x) => bin('-', a, *x),
                    b => bin('+', a, b),
                })
                .unwrap_or(Ex::Num("0".into()));
            let sum = match &s.conv {
                Some(c) => bin('*', name(c, s.at), sum),
                None => sum,
            };
            let rhs = if s.amount {
                sum
            } else {
                bin('/', sum, name(&s.comp, s.at))
            };
            eqs.push((s.id.clone(), rhs, s.at));
        }
    }
    for (p, at) in param_states {
        if let Some((e, _)) = rate.get(p) {
            eqs.push((p.clone(), e.clone(), *at));
        }
    }
    for (v, (_, at)) in rate {
        if !eqs.iter().any(|(n, _, _)| n == v) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("rate rule for '{v}', which is not a species or parameter"),
            ));
        }
    }
    Ok(eqs)
}

pub(crate) fn walk_names(e: &Ex, f: &mut dyn FnMut(&str)) {
    walk_names_at(e, &mut |n, _| f(n));
}

pub(crate) fn walk_names_at(e: &Ex, f: &mut dyn FnMut(&str, (usize, usize))) {
    match e {
        Ex::Name { name, at, .. } => f(name, *at),
        Ex::Neg(a) => walk_names_at(a, f),
        Ex::Bin(_, a, b) => {
            walk_names_at(a, f);
            walk_names_at(b, f);
        }
        Ex::Call(_, args) => args.iter().for_each(|a| walk_names_at(a, f)),
        Ex::Num(_) => {}
    }
}
