//! One `@ODEmodel` (or `linear_compartment_model`) to `.sys` text.

use super::lex::{err, ident, is_punct, items, tokenize, Token};
use super::parse::{rename_bare, walk, P};
use super::{Lincomp, SiJlModel};
use crate::ex::{show, sys_identifier, Ex, RESERVED};
use crate::{Converted, ImportError};
use std::collections::BTreeMap;

/// Translate one model of `text` (found by [`super::si_jl_models`]) into
/// `.sys` text. `origin` names the file in the header comment.
pub fn si_jl_convert(
    text: &str,
    model: &SiJlModel,
    origin: &str,
) -> Result<Converted, ImportError> {
    if let Some(lc) = &model.lincomp {
        return Ok(lincomp_sys(lc, model, origin));
    }
    let toks = tokenize(text)?;
    let mut eqs = equations(&toks, model)?;
    let split = split_bare_names(&mut eqs);
    let states: Vec<&str> = eqs
        .iter()
        .filter(|q| q.state)
        .map(|q| q.name.as_str())
        .collect();
    let outputs: Vec<&str> = eqs
        .iter()
        .filter(|q| !q.state)
        .map(|q| q.name.as_str())
        .collect();
    let values = parameter_values(&toks, model, &states, &outputs)?;
    let (params, inputs) = params_and_inputs(&eqs, &states, &outputs, &values)?;
    // .sys names: reserved words get a trailing '_' (unique).
    let mut taken: Vec<String> = states
        .iter()
        .chain(&outputs)
        .map(|s| s.to_string())
        .chain(params.iter().cloned())
        .chain(inputs.iter().cloned())
        .collect();
    let mut renamed: BTreeMap<String, String> = split
        .iter()
        .map(|(a, b)| (format!("{a} (bare)"), b.clone()))
        .collect();
    for n in taken.clone() {
        if RESERVED.contains(&n.as_str()) {
            let mut m = format!("{n}_");
            while taken.contains(&m) {
                m.push('_');
            }
            taken.push(m.clone());
            renamed.insert(n, m);
        }
    }
    let mut value_text: BTreeMap<String, String> = BTreeMap::new();
    for (p, v) in &values {
        let mut s = String::new();
        show(v, &mut s, &|n| n.to_string());
        value_text.insert(p.clone(), s);
    }
    let names = SysNames {
        states: &states,
        params: &params,
        inputs: &inputs,
        renamed: &renamed,
        value_text: &value_text,
    };
    Ok(write_sys(model, origin, &eqs, &names))
}

/// One equation of the model: `x'(t) = rhs` (a state) or `y(t) = rhs`.
struct Equation {
    name: String,
    state: bool,
    /// The token of its left-hand side, for the line map and errors.
    at: Token,
    rhs: Ex,
}

/// The equations inside the macro's parentheses, each checked for shape.
fn equations(toks: &[Token], model: &SiJlModel) -> Result<Vec<Equation>, ImportError> {
    let (a, b) = model.args;
    if b > toks.len() || a > b || a == 0 {
        return Err(ImportError::at(
            model.line,
            model.col,
            "model not found in this text",
        ));
    }
    let mut eqs: Vec<Equation> = Vec::new();
    for (s, e) in items(toks, a - 1, b) {
        let t0 = &toks[s];
        let Some(name) = ident(Some(t0)) else {
            return Err(err(
                t0,
                "expected an equation 'x'(t) = ...' or 'y(t) = ...'",
            ));
        };
        let mut k = s + 1;
        let state = is_punct(toks.get(k), "'");
        if state {
            k += 1;
        }
        if !(is_punct(toks.get(k), "(")
            && ident(toks.get(k + 1)) == Some("t")
            && is_punct(toks.get(k + 2), ")")
            && is_punct(toks.get(k + 3), "="))
            || k + 4 >= e
        {
            return Err(err(
                t0,
                format!("expected '{name}'(t) = EXPR' (a state) or '{name}(t) = EXPR' (an output)"),
            ));
        }
        let mut p = P {
            toks,
            i: k + 4,
            end: e,
            depth: 0,
        };
        let rhs = p.whole()?;
        if eqs.iter().any(|q| q.name == name) {
            return Err(err(t0, format!("'{name}' has two equations")));
        }
        eqs.push(Equation {
            name: name.to_string(),
            state,
            at: t0.clone(),
            rhs,
        });
    }
    if !eqs.iter().any(|q| q.state) {
        return Err(ImportError::at(
            model.line,
            model.col,
            "the model has no state equation",
        ));
    }
    if !eqs.iter().any(|q| !q.state) {
        return Err(ImportError::at(
            model.line,
            model.col,
            "the model has no output",
        ));
    }
    Ok(eqs)
}

/// SI.jl reads `q(t)` (a state or an input) and a bare `q` (a parameter) as
/// two variables: the bare one is renamed `q_p`. Returns the renames.
fn split_bare_names(eqs: &mut [Equation]) -> BTreeMap<String, String> {
    let mut timed_names: Vec<String> = eqs
        .iter()
        .filter(|q| q.state)
        .map(|q| q.name.clone())
        .collect();
    for q in eqs.iter() {
        walk(&q.rhs, &mut |n, timed, _| {
            if timed && !timed_names.iter().any(|x| x == n) {
                timed_names.push(n.to_string());
            }
        });
    }
    let mut all_names = timed_names.clone();
    for q in eqs.iter() {
        all_names.push(q.name.clone());
    }
    for q in eqs.iter() {
        walk(&q.rhs, &mut |n, _, _| all_names.push(n.to_string()));
    }
    let mut split: BTreeMap<String, String> = BTreeMap::new();
    for q in eqs.iter_mut() {
        rename_bare(&mut q.rhs, &timed_names, &all_names, &mut split);
    }
    split
}

/// The values `set_parameter_values` gives (numbers only, on parameters).
fn parameter_values(
    toks: &[Token],
    model: &SiJlModel,
    states: &[&str],
    outputs: &[&str],
) -> Result<BTreeMap<String, Ex>, ImportError> {
    let mut values: BTreeMap<String, Ex> = BTreeMap::new();
    for (p, (l, c), (va, vb)) in &model.values {
        let mut pp = P {
            toks,
            i: *va,
            end: *vb,
            depth: 0,
        };
        let v = pp.whole()?;
        let mut bad = None;
        walk(&v, &mut |n, _, at| {
            if bad.is_none() {
                bad = Some((n.to_string(), at));
            }
        });
        if let Some((n, (l2, c2))) = bad {
            return Err(ImportError::at(
                l2,
                c2,
                format!("the value of '{p}' uses '{n}': values must be numbers"),
            ));
        }
        if states.contains(&p.as_str()) || outputs.contains(&p.as_str()) {
            return Err(ImportError::at(
                *l,
                *c,
                format!("'{p}' is a state or an output, not a parameter"),
            ));
        }
        values.insert(p.clone(), v);
    }
    Ok(values)
}

/// The names the right-hand sides use, as SI.jl reads them: `u(t)` that is
/// not a state is an input, a bare name without a value a parameter.
fn params_and_inputs(
    eqs: &[Equation],
    states: &[&str],
    outputs: &[&str],
    values: &BTreeMap<String, Ex>,
) -> Result<(Vec<String>, Vec<String>), ImportError> {
    let mut params: Vec<String> = Vec::new();
    let mut inputs: Vec<String> = Vec::new();
    for q in eqs {
        let mut bad: Option<ImportError> = None;
        walk(&q.rhs, &mut |n, timed, (l, c)| {
            if bad.is_some() {
                return;
            }
            let is_state = states.contains(&n);
            if outputs.contains(&n) {
                bad = Some(ImportError::at(
                    l,
                    c,
                    format!("the output '{n}' is used in an equation"),
                ));
            } else if timed && !is_state {
                if !inputs.iter().any(|x| x == n) {
                    inputs.push(n.to_string());
                }
            } else if !timed && n == "t" {
                bad = Some(ImportError::at(l, c, "time 't' itself is not supported (non-autonomous models are outside obsan's class; add a clock state t'(t) = 1)"));
            } else if !timed && values.contains_key(n) {
                // substituted by write_sys
            } else if !timed && !params.iter().any(|x| x == n) {
                params.push(n.to_string());
            }
        });
        if let Some(e) = bad {
            return Err(e);
        }
    }
    Ok((params, inputs))
}

/// The declarations and how names are written in the `.sys` text.
struct SysNames<'a> {
    states: &'a [&'a str],
    params: &'a [String],
    inputs: &'a [String],
    /// Reserved words and split names, renamed.
    renamed: &'a BTreeMap<String, String>,
    /// Parameter values, substituted.
    value_text: &'a BTreeMap<String, String>,
}

impl SysNames<'_> {
    fn map(&self, n: &str) -> String {
        if let Some(v) = self.value_text.get(n) {
            if v.chars().all(|c| c.is_ascii_digit() || c == '.') {
                v.clone()
            } else {
                format!("({v})")
            }
        } else {
            self.renamed
                .get(n)
                .cloned()
                .unwrap_or_else(|| n.to_string())
        }
    }
}

/// The `.sys` text: header comments, declarations, one line per equation
/// (each mapped back to its place in the source).
fn write_sys(model: &SiJlModel, origin: &str, eqs: &[Equation], nm: &SysNames) -> Converted {
    let map = |n: &str| nm.map(n);
    let sysname = sys_name(&model.key);
    let one_line = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut lines = header(model, origin, "");
    let mut line_map = Vec::new();
    if !nm.renamed.is_empty() {
        let r: Vec<String> = nm
            .renamed
            .iter()
            .map(|(a, b)| format!("{a} -> {b}"))
            .collect();
        lines.push(format!(
            "# renamed (reserved in .sys, or one name used both with and without (t)): {}",
            r.join(", ")
        ));
    }
    if !nm.value_text.is_empty() {
        let r: Vec<String> = nm
            .value_text
            .iter()
            .map(|(a, b)| format!("{a} = {b}"))
            .collect();
        lines.push(format!(
            "# parameter values set in the source (substituted): {}",
            r.join(", ")
        ));
    }
    lines.push(format!("system {sysname}"));
    if let Some(n) = &model.name {
        let n = one_line(n);
        if !n.is_empty() {
            lines.push(format!("description {n}"));
        }
    }
    let list = |v: Vec<String>| v.join(", ");
    lines.push(format!(
        "state {}",
        list(nm.states.iter().map(|s| map(s)).collect())
    ));
    if !nm.params.is_empty() {
        lines.push(format!(
            "param {}",
            list(nm.params.iter().map(|s| map(s)).collect())
        ));
    }
    if !nm.inputs.is_empty() {
        lines.push(format!(
            "input {}",
            list(nm.inputs.iter().map(|s| map(s)).collect())
        ));
    }
    for q in eqs {
        let mut s = String::new();
        show(&q.rhs, &mut s, &map);
        lines.push(if q.state {
            format!("{}' = {s}", map(&q.name))
        } else {
            format!("output {} = {s}", map(&q.name))
        });
        line_map.push((lines.len(), q.at.line, q.at.col));
    }
    let mut sys_text = lines.join("\n");
    sys_text.push('\n');
    Converted {
        name: sysname,
        sys_text,
        line_map,
        table_lines: Vec::new(),
    }
}

fn header(model: &SiJlModel, origin: &str, what: &str) -> Vec<String> {
    let one_line = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    let mut lines = vec![format!(
        "# Imported by `obsan import si-jl` from {}, model :{} (line {}){}.",
        one_line(origin),
        model.key,
        model.line,
        model
            .name
            .as_ref()
            .map_or(String::new(), |n| format!(", \"{}\"", one_line(n)))
    )];
    if let Some(c) = &model.cite {
        lines.push(format!("# cite: {}", one_line(c)));
    }
    if !what.is_empty() {
        lines.push(format!("# {what}"));
    }
    lines
}

fn sys_name(key: &str) -> String {
    sys_identifier(key)
}

fn lincomp_sys(lc: &Lincomp, model: &SiJlModel, origin: &str) -> Converted {
    let n = lc.graph.len();
    let mut lines = header(
        model,
        origin,
        "linear_compartment_model expanded as SI.jl's src/lincomp.jl does: x_j' gains a_j_i*x_i, x_i' loses it.",
    );
    let name = sys_name(&model.key);
    lines.push(format!("system {name}"));
    if let Some(d) = &model.name {
        lines.push(format!(
            "description {}",
            d.split_whitespace().collect::<Vec<_>>().join(" ")
        ));
    }
    let mut rhs: Vec<Vec<String>> = vec![Vec::new(); n];
    let mut params = Vec::new();
    for (i, outs) in lc.graph.iter().enumerate() {
        for &j in outs {
            let a = format!("a_{j}_{}", i + 1);
            rhs[j - 1].push(format!("+ {a}*x{}", i + 1));
            rhs[i].push(format!("- {a}*x{}", i + 1));
            params.push(a);
        }
    }
    for &l in &lc.leaks {
        let a = format!("a_0_{l}");
        rhs[l - 1].push(format!("- {a}*x{l}"));
        params.push(a);
    }
    for &u in &lc.inputs {
        rhs[u - 1].push(format!("+ u{u}"));
    }
    params.dedup();
    let states: Vec<String> = (1..=n).map(|i| format!("x{i}")).collect();
    lines.push(format!("state {}", states.join(", ")));
    if !params.is_empty() {
        lines.push(format!("param {}", params.join(", ")));
    }
    if !lc.inputs.is_empty() {
        let u: Vec<String> = lc.inputs.iter().map(|i| format!("u{i}")).collect();
        lines.push(format!("input {}", u.join(", ")));
    }
    let mut line_map = Vec::new();
    for (i, terms) in rhs.iter().enumerate() {
        let mut t = terms.join(" ");
        if let Some(r) = t.strip_prefix("+ ") {
            t = r.to_string();
        } else if let Some(r) = t.strip_prefix("- ") {
            t = format!("-{r}");
        }
        if t.is_empty() {
            t = "0".into();
        }
        lines.push(format!("x{}' = {t}", i + 1));
        line_map.push((lines.len(), model.line, model.col));
    }
    for &o in &lc.outputs {
        lines.push(format!("output y{o} = x{o}"));
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
