//! Effect libraries (`.eff` files): named extensions of a model, each a patch
//! of its `.sys` text, for the discrepancy workflow (`docs/effects-format.md`).
//!
//! ```text
//! model calib
//! effect bearing_scale
//! description Bearing sensor scale error: beta_meas = (1 + kb) beta
//! param kb
//! output beta = (1 + kb)*atan2(sin(beta), cos(beta))
//! ```
//!
//! In `output y = EXPR` the name `y` stands for the nominal expression of `y`;
//! `subst u = EXPR` replaces the input `u` in every dynamics right-hand side
//! (where `u` in `EXPR` is the measured input); `x' = EXPR` replaces a state's
//! dynamics. `param`, `const` and `input` declare new names (a new input is
//! usually derived, e.g. `input dwR = rate(wR)`).

use crate::error::{normalize_text, ModelError};
use crate::sys::{Kind, System};
use crate::unit::{Unit, UnitDecl};

/// One named model extension.
#[derive(Clone, Debug, PartialEq)]
pub struct Effect {
    pub name: String,
    pub description: String,
    /// New unknown params (started at 0 by the workflow unless `starts`
    /// gives a value).
    pub params: Vec<String>,
    /// New dynamic states (`state va = v`); each needs an `x' = EXPR`.
    pub states: Vec<String>,
    /// Start values written with the declaration: `param T = 0.2` (a
    /// number), `state va = v` (an expression of the inputs' first row).
    pub starts: Vec<(String, String)>,
    /// New known constants (e.g. `later`, supplied by the workflow).
    pub consts: Vec<String>,
    /// New inputs and their derivation (`None`: the data must hold a column).
    pub inputs: Vec<(String, Option<String>)>,
    /// `subst u = EXPR`.
    pub substs: Vec<(String, String)>,
    /// `output y = EXPR` (y in EXPR is the nominal y).
    pub outputs: Vec<(String, String)>,
    /// `x' = EXPR`.
    pub dynamics: Vec<(String, String)>,
    /// `compare u = EXPR`: a relation the measured inputs should satisfy
    /// (an input-side effect: it changes no dynamics or output, and its
    /// params are fitted to the inputs alone).
    pub compares: Vec<(String, String)>,
    /// `delay tau`: the extended dynamics see `u(t - tau)`.
    pub delay: Option<String>,
    /// 1-based line of the `effect` statement.
    pub line: usize,
}

/// The effects of one file.
#[derive(Clone, Debug, PartialEq)]
pub struct EffectLibrary {
    /// The system name the effects are written for (`model NAME`), if given.
    pub model: Option<String>,
    pub effects: Vec<Effect>,
    /// `unit NAME = UNIT` declarations (anywhere in the file; they name the
    /// model's outputs, inputs and params or the effects' new names).
    pub units: Vec<UnitDecl>,
    pub origin: String,
}

fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    matches!(c.next(), Some(ch) if ch.is_ascii_alphabetic() || ch == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

/// Split `a = x, b = f(y, z)` at top-level commas.
fn split_top(body: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0i32, 0);
    for (i, c) in body.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&body[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&body[start..]);
    out
}

/// Replace whole identifiers of `text` by `(replacement)`, simultaneously;
/// number literals such as `1.5e-3` are left alone.
pub fn substitute(text: &str, map: &[(String, String)]) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_digit() || c == b'.' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                let mut j = i + 1;
                if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                    j += 1;
                }
                if j < b.len() && b[j].is_ascii_digit() {
                    i = j;
                    while i < b.len() && b[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
            out.push_str(&text[start..i]);
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            let word = &text[start..i];
            match map.iter().find(|(k, _)| k == word) {
                Some((_, r)) => {
                    out.push('(');
                    out.push_str(r);
                    out.push(')');
                }
                None => out.push_str(word),
            }
        } else {
            // Copy one whole character (non-ASCII text stays intact).
            let ch = text[i..].chars().next().unwrap_or('\u{fffd}');
            out.push(ch);
            i += ch.len_utf8().max(1);
        }
    }
    out
}

impl EffectLibrary {
    /// Read an effects file; `origin` names it in messages. A leading
    /// byte-order mark is ignored and CRLF or CR line ends read as lines.
    /// Errors point at the statement (line, column, caret).
    pub fn parse(src: &str, origin: &str) -> Result<EffectLibrary, ModelError> {
        let src = normalize_text(src);
        let src: &str = &src;
        let mut model = None;
        let mut effects: Vec<Effect> = Vec::new();
        let mut units: Vec<UnitDecl> = Vec::new();
        let mut line_start = 0;
        for (ln, raw) in src.split('\n').enumerate() {
            let line_no = ln + 1;
            let here = line_start;
            line_start += raw.len() + 1;
            let line = raw.split('#').next().unwrap_or("");
            let t = line.trim();
            if t.is_empty() {
                continue;
            }
            let lead = here + (line.len() - line.trim_start().len());
            let err = |msg: String| ModelError::at(origin, src, lead, lead + t.len(), msg);
            let (word, rest) = match t.find(|c: char| c.is_whitespace() || c == '=') {
                Some(i) => (&t[..i], t[i..].trim()),
                None => (t, ""),
            };
            if word == "model" {
                if !is_ident(rest) {
                    return Err(err("'model' needs one system name: model NAME".into()));
                }
                model = Some(rest.to_string());
                continue;
            }
            if word == "unit" || word == "units" {
                units_statement(origin, src, lead + word.len(), &t[word.len()..], &mut units)?;
                continue;
            }
            if word == "effect" {
                if !is_ident(rest) {
                    return Err(err("'effect' needs one name: effect NAME".into()));
                }
                if effects.iter().any(|e| e.name == rest) {
                    return Err(err(format!("effect '{rest}' is defined twice")));
                }
                effects.push(Effect {
                    name: rest.to_string(),
                    description: String::new(),
                    params: vec![],
                    states: vec![],
                    starts: vec![],
                    consts: vec![],
                    inputs: vec![],
                    substs: vec![],
                    outputs: vec![],
                    dynamics: vec![],
                    compares: vec![],
                    delay: None,
                    line: line_no,
                });
                continue;
            }
            let Some(e) = effects.last_mut() else {
                return Err(err(format!(
                    "'{word}' before any 'effect NAME' line (a file is: [model NAME] then effect blocks)"
                )));
            };
            let assignment = |item: &str| -> Result<(String, String), ModelError> {
                let Some((n, v)) = item.split_once('=') else {
                    return Err(err(format!(
                        "expected NAME = EXPR, found '{}'",
                        item.trim()
                    )));
                };
                let (n, v) = (n.trim(), v.trim());
                if !is_ident(n) || v.is_empty() {
                    return Err(err(format!(
                        "expected NAME = EXPR, found '{}'",
                        item.trim()
                    )));
                }
                Ok((n.to_string(), v.to_string()))
            };
            match word {
                "description" => {
                    if !e.description.is_empty() {
                        e.description.push(' ');
                    }
                    e.description.push_str(rest);
                }
                "param" | "params" | "state" | "states" => {
                    for item in split_top(rest) {
                        let n = match item.split_once('=') {
                            Some(_) => {
                                let (n, v) = assignment(item)?;
                                e.starts.push((n.clone(), v));
                                n
                            }
                            None => item.trim().to_string(),
                        };
                        if !is_ident(&n) {
                            return Err(err(format!("'{n}' is not a valid name in a '{word}' list")));
                        }
                        if word.starts_with("param") {
                            e.params.push(n);
                        } else {
                            e.states.push(n);
                        }
                    }
                }
                "const" | "consts" => {
                    for n in rest.split(',').map(str::trim) {
                        if !is_ident(n) {
                            return Err(err(format!("'{n}' is not a valid name in a '{word}' list")));
                        }
                        e.consts.push(n.into());
                    }
                }
                "input" | "inputs" => {
                    for item in split_top(rest) {
                        match item.split_once('=') {
                            Some(_) => {
                                let (n, v) = assignment(item)?;
                                e.inputs.push((n, Some(v)));
                            }
                            None if is_ident(item.trim()) => e.inputs.push((item.trim().into(), None)),
                            None => return Err(err(format!("'{}' is not a valid input name", item.trim()))),
                        }
                    }
                }
                "subst" => {
                    for item in split_top(rest) {
                        e.substs.push(assignment(item)?);
                    }
                }
                "output" => e.outputs.push(assignment(rest)?),
                "compare" => e.compares.push(assignment(rest)?),
                "delay" => {
                    if !is_ident(rest) {
                        return Err(err("'delay' needs one param name: delay NAME".into()));
                    }
                    e.delay = Some(rest.to_string());
                }
                w if w.ends_with('\'') || t[w.len()..].trim_start().starts_with('\'') => {
                    let (lhs, rhs) = t.split_once('=').ok_or_else(|| err("an equation needs '=': x' = EXPR".into()))?;
                    let n = lhs.trim().trim_end_matches('\'').trim();
                    if !is_ident(n) || rhs.trim().is_empty() {
                        return Err(err("expected x' = EXPR".into()));
                    }
                    e.dynamics.push((n.into(), rhs.trim().into()));
                }
                _ => {
                    return Err(err(format!(
                        "expected one of model, effect, unit, description, param, state, const, input, subst, output, compare, delay, x' = ..., found '{word}'"
                    )))
                }
            }
        }
        if effects.is_empty() {
            return Err(ModelError::general(
                origin,
                "no 'effect NAME' block in the file",
            ));
        }
        Ok(EffectLibrary {
            model,
            effects,
            units,
            origin: origin.to_string(),
        })
    }

    pub fn get(&self, name: &str) -> Option<&Effect> {
        self.effects.iter().find(|e| e.name == name)
    }

    /// Check that every effect extends `sys` into a valid system; the error
    /// names this file's line of the faulty effect.
    pub fn check(&self, sys: &System) -> Result<(), ModelError> {
        if let Some(m) = &self.model {
            if m != &sys.name {
                return Err(ModelError::general(
                    &self.origin,
                    format!(
                        "these effects are written for system '{m}', not '{}'",
                        sys.name
                    ),
                ));
            }
        }
        for e in &self.effects {
            if e.is_input_side() {
                let fail = |msg: String| {
                    ModelError::general(
                        &format!("{}:{}", self.origin, e.line),
                        format!("effect '{}': {msg}", e.name),
                    )
                };
                if !(e.substs.is_empty() && e.outputs.is_empty() && e.dynamics.is_empty()) {
                    return Err(fail("an effect with 'compare' changes only the inputs' relation: it cannot also subst, replace outputs or dynamics".into()));
                }
                for (u, _) in &e.compares {
                    if !sys
                        .decls
                        .iter()
                        .any(|d| &d.name == u && d.kind == Kind::Input)
                    {
                        return Err(fail(format!(
                            "compare of '{u}', which is not an input of {}",
                            sys.name
                        )));
                    }
                }
                continue;
            }
            sys.extend(&[e], &self.origin)?;
        }
        self.check_units(sys)
    }

    /// Every `unit` declaration names an output, input, param, state or
    /// constant of `sys` or of one of the effects.
    fn check_units(&self, sys: &System) -> Result<(), ModelError> {
        for u in &self.units {
            let n = u.name.as_str();
            let known = sys.decls.iter().any(|d| d.name == n)
                || sys.outputs.iter().any(|o| o.0 == n)
                || self.effects.iter().any(|e| {
                    (e.params.iter().chain(&e.states).chain(&e.consts)).any(|x| x == n)
                        || e.inputs.iter().any(|i| i.0 == n)
                });
            if !known {
                return Err(ModelError::placed(
                    &self.origin,
                    u.line,
                    u.col,
                    format!(
                        "unit of '{n}', which is no output, input, param, state or constant of {} or of these effects",
                        sys.name
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// `unit r = m, wR = rad/s` (after the word, `body` starting at byte `at`
/// of `src`): each name once in the file, each unit readable.
fn units_statement(
    origin: &str,
    src: &str,
    at: usize,
    body: &str,
    units: &mut Vec<UnitDecl>,
) -> Result<(), ModelError> {
    let mut off = at;
    for item in body.split(',') {
        let here = off;
        off += item.len() + 1;
        let lead = here + (item.len() - item.trim_start().len());
        let at = |a: usize, b: usize, m: String| ModelError::at(origin, src, a, b, m);
        let err = |a: usize, b: usize, m: String| Err(at(a, b, m));
        let Some((n, v)) = item.split_once('=') else {
            return err(
                lead,
                here + item.len(),
                "expected NAME = UNIT, e.g. unit r = m".into(),
            );
        };
        let name = n.trim();
        if !is_ident(name) {
            return err(
                lead,
                lead + n.len(),
                format!("'{name}' is not a valid name in a 'unit' list"),
            );
        }
        if units.iter().any(|u| u.name == name) {
            return err(
                lead,
                lead + name.len(),
                format!("the unit of '{name}' is declared twice"),
            );
        }
        let v_at = here + n.len() + 1;
        let v_lead = v_at + (v.len() - v.trim_start().len());
        let unit = Unit::parse(v.trim())
            .map_err(|(k, m)| at(v_lead + k, v_lead + k + 1, format!("unit of '{name}': {m}")))?;
        let (line, col) = ModelError::at(origin, src, lead, lead, "").place();
        units.push(UnitDecl {
            name: name.to_string(),
            unit,
            line,
            col,
        });
    }
    Ok(())
}

impl Effect {
    /// An effect on the measured inputs (`compare`), not on the model.
    pub fn is_input_side(&self) -> bool {
        !self.compares.is_empty()
    }
}

impl System {
    /// The system extended by `effects`, applied in order. `origin` (the
    /// effects file) is used in error messages.
    pub fn extend(&self, effects: &[&Effect], origin: &str) -> Result<System, ModelError> {
        let mut cur = self.clone();
        for e in effects {
            if e.is_input_side() {
                continue;
            }
            let fail = |msg: String| {
                ModelError::general(
                    &format!("{origin}:{}", e.line),
                    format!("effect '{}': {msg}", e.name),
                )
            };
            let taken = |n: &str| {
                cur.decls.iter().any(|d| d.name == n) || cur.outputs.iter().any(|o| o.0 == n)
            };
            for n in e
                .params
                .iter()
                .chain(&e.states)
                .chain(&e.consts)
                .chain(e.inputs.iter().map(|i| &i.0))
            {
                if taken(n) {
                    return Err(fail(format!("'{n}' is already a name of {}", cur.name)));
                }
            }
            let mut s = cur.clone();
            for (u, _) in &e.substs {
                if !cur
                    .decls
                    .iter()
                    .any(|d| &d.name == u && d.kind == Kind::Input)
                {
                    return Err(fail(format!(
                        "subst of '{u}', which is not an input of {}",
                        cur.name
                    )));
                }
            }
            let states: Vec<String> = cur.decls_of(Kind::State).map(|d| d.name.clone()).collect();
            for (k, name) in states.iter().enumerate() {
                let base = match e.dynamics.iter().find(|d| &d.0 == name) {
                    Some((_, rhs)) => rhs.clone(),
                    None => cur.texts.dynamics.get(k).cloned().unwrap_or_default(),
                };
                if let Some(slot) = s.texts.dynamics.get_mut(k) {
                    *slot = if e.substs.is_empty() {
                        base
                    } else {
                        substitute(&base, &e.substs)
                    };
                }
            }
            for (x, _) in &e.dynamics {
                if !states.contains(x) && !e.states.contains(x) {
                    return Err(fail(format!(
                        "an equation for '{x}', which is neither a state of {} nor a new state",
                        cur.name
                    )));
                }
            }
            for x in &e.states {
                if !e.dynamics.iter().any(|d| &d.0 == x) {
                    return Err(fail(format!(
                        "the new state '{x}' needs an equation {x}' = ..."
                    )));
                }
            }
            for (y, rhs) in &e.outputs {
                let Some(k) = cur.outputs.iter().position(|o| &o.0 == y) else {
                    return Err(fail(format!(
                        "output '{y}' is not an output of {}",
                        cur.name
                    )));
                };
                let nominal = cur.texts.outputs.get(k).cloned().unwrap_or_default();
                if let Some(slot) = s.texts.outputs.get_mut(k) {
                    *slot = substitute(rhs, &[(y.clone(), nominal)]);
                }
            }
            if let Some(d) = &e.delay {
                if cur.delay.is_some() {
                    return Err(fail(format!("{} already has a delay", cur.name)));
                }
                s.delay = Some(d.clone());
            }
            let mut text = s.to_sys_text();
            // New declarations after the old ones keep the old params first.
            let mut extra = String::new();
            let declared = |names: &[String]| -> String {
                let items: Vec<String> = names
                    .iter()
                    .map(|n| match e.starts.iter().find(|s| &s.0 == n) {
                        Some((_, v)) => format!("{n} = {v}"),
                        None => n.clone(),
                    })
                    .collect();
                items.join(", ")
            };
            if !e.states.is_empty() {
                extra.push_str(&format!("state {}\n", declared(&e.states)));
            }
            if !e.params.is_empty() {
                extra.push_str(&format!("param {}\n", declared(&e.params)));
            }
            if !e.consts.is_empty() {
                extra.push_str(&format!("const {}\n", e.consts.join(", ")));
            }
            for (n, d) in &e.inputs {
                match d {
                    Some(d) => extra.push_str(&format!("input {n} = {d}\n")),
                    None => extra.push_str(&format!("input {n}\n")),
                }
            }
            let cut = text.find("\n\n").map_or(text.len(), |i| i + 1);
            text.insert_str(cut, &extra);
            // The new states' equations, untouched by `subst` (they see the
            // measured inputs).
            for x in &e.states {
                if let Some((_, rhs)) = e.dynamics.iter().find(|d| &d.0 == x) {
                    text.push_str(&format!("{x}' = {rhs}\n"));
                }
            }
            let mut next = System::parse(&text, &format!("{}+{}", cur.name, e.name))
                .map_err(|err| fail(format!("the extended model is not valid: {err}")))?;
            // Fitting and diagnosis have no clock: time stays out of effects.
            if let Some(err) = next.time_refusal("an effect's extended model") {
                return Err(fail(format!("{err}")));
            }
            next.description = if cur.description.is_empty() {
                format!("with {}", e.name)
            } else {
                format!("{} With {}: {}", cur.description, e.name, e.description)
            };
            cur = next;
        }
        Ok(cur)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substitution_is_whole_word_and_simultaneous() {
        let m = vec![
            ("u".to_string(), "u - t*du".to_string()),
            ("x".to_string(), "y".to_string()),
        ];
        assert_eq!(
            substitute("u*x + ux + 1.5e-3*u", &m),
            "(u - t*du)*(y) + ux + 1.5e-3*(u - t*du)"
        );
    }

    /// Each bad `unit` statement is an error at its file:line:col.
    #[test]
    fn unit_declarations_read_and_bad_ones_are_placed_errors() {
        let head = "effect b\nparam b\noutput beta = beta + b\n";
        let lib = EffectLibrary::parse(
            &format!("unit beta = rad\n{head}unit b = rad, wR = rad/s\n"),
            "u.eff",
        )
        .expect("valid units");
        let shown: Vec<String> = lib
            .units
            .iter()
            .map(|u| format!("{}={}@{}:{}", u.name, u.unit, u.line, u.col))
            .collect();
        assert_eq!(shown, ["beta=rad@1:6", "b=rad@5:6", "wR=rad/s@5:15"]);
        for (text, place, what) in [
            ("unit beta\n", "u.eff:1:6", "expected NAME = UNIT"),
            ("unit 2x = m\n", "u.eff:1:6", "not a valid name"),
            ("unit r = m\nunit r = m\n", "u.eff:2:6", "declared twice"),
            ("unit r = m/\n", "u.eff:1:12", "expected a unit symbol"),
            ("unit r = m^x\n", "u.eff:1:12", "nonzero integer exponent"),
            ("unit r = m s\n", "u.eff:1:12", "expected '*', '/'"),
        ] {
            let e = EffectLibrary::parse(&format!("{text}{head}"), "u.eff")
                .expect_err(text)
                .to_string();
            assert!(e.starts_with(place) && e.contains(what), "{text}: {e}");
        }
        // A name of neither the model nor the effects: placed by `check`.
        let sys = System::parse(
            "system s\nstate x\ninput u\nx' = u\noutput beta = atan(x)\n",
            "s.sys",
        )
        .expect("valid system");
        let lib = EffectLibrary::parse(&format!("{head}unit b = rad, u = m/s\n"), "u.eff")
            .expect("valid");
        assert_eq!(lib.check(&sys), Ok(()));
        let lib =
            EffectLibrary::parse(&format!("{head}\n  unit zz = m\n"), "u.eff").expect("valid");
        let e = lib.check(&sys).expect_err("zz is no name").to_string();
        assert!(e.starts_with("u.eff:5:8: unit of 'zz'"), "{e}");
    }
}
