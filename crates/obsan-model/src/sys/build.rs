//! Pass 2 of reading `.sys`: make the symbols, build every expression and
//! check it (kinds of names used, derived inputs, affinity in the inputs,
//! restrictions).

use super::lex::{edit_distance, span_in, split_commas, trim_range, Stmt, KEYWORDS};
use super::read::{not_a_name, PendingDecl, RawEquation, RawOutput, RawRestrict, Reader};
use super::{Decl, Kind, Located, Restriction, Start};
use crate::error::ModelError;
use std::collections::HashMap;

use obsan_expr::{parse_ast, Ast, Ctx, Id, ParseError, Span, FUNCTIONS, Q};

impl Reader<'_> {
    /// Declarations: duplicates, reserved names, the symbols (states, params,
    /// consts, inputs in that order), values, starts and derived inputs.
    pub(super) fn declarations(
        &self,
        ctx: &mut Ctx,
        pending: &[PendingDecl],
    ) -> Result<Vec<Decl>, ModelError> {
        // First declaration of each name (a map: files with many names stay
        // linear).
        let mut first: HashMap<&str, &PendingDecl> = HashMap::new();
        for p in pending {
            let prev = *first.entry(p.name.as_str()).or_insert(p);
            if prev.at < p.at {
                let e = ModelError::at(self.origin, self.src, prev.at, prev.at + 1, "");
                let (l, c) = (e.line.unwrap_or(0), e.col.unwrap_or(0));
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    format!(
                        "'{}' is declared twice (first as a {} at line {l}, column {c})",
                        p.name,
                        prev.kind.word()
                    ),
                ));
            }
            if p.name == super::TIME {
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    "'t' is time, known to every model (its clock t' = 1): it cannot be declared; \
                     use it in right-hand sides and outputs as it is",
                ));
            }
            if p.name == "pi"
                || FUNCTIONS.iter().any(|f| f.0 == p.name)
                || KEYWORDS.contains(&p.name.as_str())
            {
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    format!("'{}' is a reserved word and cannot be a name", p.name),
                ));
            }
        }
        let mut order: Vec<&PendingDecl> = pending.iter().collect();
        order.sort_by_key(|p| match p.kind {
            Kind::State => 0,
            Kind::Param => 1,
            Kind::Const => 2,
            Kind::Input => 3,
            Kind::Unknown => 4,
        });
        let mut decls: Vec<Decl> = Vec::new();
        for p in order {
            let sym = ctx.symbol(&p.name);
            let value = match (&p.value, p.kind) {
                (Some((text, map)), Kind::Const) => {
                    Some(self.number(text, map, "a constant's value")?)
                }
                _ => None,
            };
            let start = match (&p.value, p.kind) {
                (Some((text, map)), Kind::Param) => Some(Start::Number(self.number(
                    text,
                    map,
                    "a param's start value",
                )?)),
                (Some((text, _)), Kind::State) => Some(Start::Inputs(text.trim().to_string())),
                _ => None,
            };
            decls.push(Decl {
                name: p.name.clone(),
                kind: p.kind,
                sym,
                value,
                derived: match (&p.value, p.kind) {
                    (Some((text, _)), Kind::Input) => Some(text.trim().to_string()),
                    _ => None,
                },
                start,
                at: p.at,
            });
        }
        for p in pending {
            if let (Some(_), Kind::Unknown) = (&p.value, p.kind) {
                return Err(self.err_src(
                    p.at,
                    p.at + p.name.len(),
                    format!(
                        "'{}' is an unknown input: it takes no value (nobody measures it)",
                        p.name
                    ),
                ));
            }
            if let (Some((text, map)), Kind::Input | Kind::State) = (&p.value, p.kind) {
                check_derived(self, text, map, &decls, (p.kind, p.at))?;
            }
        }
        if !decls
            .iter()
            .any(|d| matches!(d.kind, Kind::State | Kind::Param))
        {
            return Err(ModelError::general(
                self.origin,
                "the system has no state and no param: declare them with 'state' and 'param'",
            ));
        }
        Ok(decls)
    }

    /// A number: a constant's value or a param's start.
    fn number(&self, text: &str, map: &[usize], what: &str) -> Result<Q, ModelError> {
        let ast = parse_ast(text).map_err(|e| self.parse_err(map, e))?;
        let mut tmp = Ctx::new();
        let id = tmp
            .build(&ast, &mut |_, n, s| {
                Err(ParseError::new(
                    format!("{what} must be a number, not '{n}'"),
                    s,
                ))
            })
            .map_err(|e| self.parse_err(map, e))?;
        // Budgeted: a number past the engine's limits is an error at its place.
        let r = tmp
            .try_canon(id)
            .map_err(|l| self.parse_err(map, ParseError::new(format!("{what}: {l}"), ast.span)))?;
        r.as_q().ok_or_else(|| {
            self.parse_err(
                map,
                ParseError::new(format!("{what} must be a rational number"), ast.span),
            )
        })
    }

    /// Did-you-mean for an unknown name.
    fn suggest(decls: &[Decl], n: &str) -> String {
        let best = decls
            .iter()
            .map(|d| (edit_distance(n, &d.name), &d.name))
            .filter(|(k, _)| *k <= 2)
            .min();
        best.map_or(String::new(), |(_, m)| format!(" (did you mean '{m}'?)"))
    }

    /// The equations: one per state, built over every declared name and
    /// affine in the inputs. Returns them in state order with their text.
    pub(super) fn dynamics(
        &self,
        ctx: &mut Ctx,
        stmts: &[Stmt],
        equations: &[RawEquation],
        decls: &[Decl],
    ) -> Result<(Vec<Located>, Vec<String>), ModelError> {
        let states: Vec<&Decl> = decls.iter().filter(|d| d.kind == Kind::State).collect();
        let mut dynamics: Vec<Option<Located>> = vec![None; states.len()];
        let mut dyn_text: Vec<String> = vec![String::new(); states.len()];
        for eqn in equations {
            let at = eqn.at;
            let t = stmts.get(eqn.stmt).map_or("", |s| s.text.trim_start());
            let nm = t[..t.find('\'').unwrap_or(0)].trim();
            let width = nm.len() + 1;
            let idx = match decls.iter().find(|d| d.name == nm) {
                None => {
                    return Err(self.err_src(
                        at,
                        at + width,
                        format!(
                        "equation for '{nm}', which is not declared{} (declare it with 'state')",
                        Self::suggest(decls, nm)
                    ),
                    ))
                }
                Some(d) if d.kind == Kind::Param => {
                    return Err(self.err_src(
                        at,
                        at + width,
                        format!("'{nm}' is a param: params are constant and take no equation"),
                    ))
                }
                Some(d) => match states.iter().position(|s| s.name == nm) {
                    Some(i) => i,
                    None => {
                        return Err(self.err_src(
                            at,
                            at + width,
                            format!("'{nm}' is a {}: only states have equations", d.kind.word()),
                        ))
                    }
                },
            };
            if dynamics[idx].is_some() {
                return Err(self.err_src(at, at + width, format!("a second equation for '{nm}'")));
            }
            if eqn.rhs.trim().is_empty() {
                return Err(self.err_src(
                    at,
                    at + width,
                    format!("the equation for '{nm}' has no right-hand side"),
                ));
            }
            let ast = parse_ast(&eqn.rhs).map_err(|e| self.parse_err(&eqn.map, e))?;
            let id = build_checked(
                ctx,
                &ast,
                &eqn.map,
                self,
                decls,
                &[
                    Kind::State,
                    Kind::Param,
                    Kind::Const,
                    Kind::Input,
                    Kind::Unknown,
                ],
                &format!("the dynamics of {nm}"),
            )?;
            let loc = Located {
                ast,
                id,
                map: eqn.map.clone(),
            };
            check_affine(ctx, &loc, decls, self, nm)?;
            dynamics[idx] = Some(loc);
            dyn_text[idx] = eqn.rhs.trim().to_string();
        }
        let mut out = Vec::with_capacity(states.len());
        for (s, d) in states.iter().zip(dynamics) {
            match d {
                Some(d) => out.push(d),
                None => {
                    return Err(self.err_src(s.at, s.at + s.name.len(), format!("state '{}' has no equation: add {}' = ... (or declare it as a param if it is constant)", s.name, s.name)))
                }
            }
        }
        Ok((out, dyn_text))
    }

    /// The outputs: at least one, fresh names, functions of states, params
    /// and constants only.
    pub(super) fn outputs(
        &self,
        ctx: &mut Ctx,
        raw: &[RawOutput],
        decls: &[Decl],
    ) -> Result<Vec<(String, Located)>, ModelError> {
        if raw.is_empty() {
            return Err(ModelError::general(
                self.origin,
                "the system has no output: add at least one 'output y = EXPR'",
            ));
        }
        let find = |n: &str| decls.iter().find(|d| d.name == n);
        let mut outputs: Vec<(String, Located)> = Vec::new();
        for o in raw {
            let (nm, at, map) = (&o.name, o.at, &o.map);
            if nm == super::TIME {
                return Err(self.err_src(
                    at,
                    at + nm.len(),
                    "'t' is time: an output cannot be named 't' (the clock is already a known output)",
                ));
            }
            if find(nm).is_some() || outputs.iter().any(|(p, _)| p == nm) {
                return Err(self.err_src(
                    at,
                    at + nm.len(),
                    format!("output name '{nm}' is already used"),
                ));
            }
            if o.rhs.trim().is_empty() {
                return Err(self.err_src(
                    at,
                    at + nm.len(),
                    format!("output '{nm}' has no expression"),
                ));
            }
            let ast = parse_ast(&o.rhs).map_err(|e| self.parse_err(map, e))?;
            let id = build_checked(
                ctx,
                &ast,
                map,
                self,
                decls,
                // Known inputs too: the normal form measures them (measured.rs).
                &[
                    Kind::State,
                    Kind::Param,
                    Kind::Const,
                    Kind::Unknown,
                    Kind::Input,
                ],
                &format!("output {nm}"),
            )?;
            outputs.push((
                nm.clone(),
                Located {
                    ast,
                    id,
                    map: map.clone(),
                },
            ));
        }
        Ok(outputs)
    }

    pub(super) fn restrictions(
        &self,
        ctx: &mut Ctx,
        stmts: &[Stmt],
        raw: &[RawRestrict],
        decls: &[Decl],
        outputs: &[(String, Located)],
    ) -> Result<Vec<Restriction>, ModelError> {
        let mut out = Vec::new();
        for r in raw {
            if let Some(st) = stmts.get(r.stmt) {
                out.push(self.restriction(ctx, st, r, decls, outputs)?);
            }
        }
        Ok(out)
    }

    /// `restrict NAME: u1 = EXPR, ...`: each left side an input set once;
    /// right sides of constants, inputs not replaced and new names (the new
    /// inputs), affine in the new inputs.
    fn restriction(
        &self,
        ctx: &mut Ctx,
        st: &Stmt,
        r: &RawRestrict,
        decls: &[Decl],
        outputs: &[(String, Located)],
    ) -> Result<Restriction, ModelError> {
        let (rname, at) = (&r.name, r.at);
        let find = |n: &str| decls.iter().find(|d| d.name == n);
        let inputs: Vec<&Decl> = decls.iter().filter(|d| d.kind == Kind::Input).collect();
        let t = &st.text;
        let colon = r.colon + 1;
        let body = t.get(colon..).unwrap_or("");
        if body.trim().is_empty() {
            return Err(self.err_src(
                at,
                at + rname.len(),
                format!(
                    "restriction '{rname}' substitutes nothing: restrict {rname}: u1 = EXPR, ..."
                ),
            ));
        }
        let mut raw: Vec<(usize, Ast, Vec<usize>)> = Vec::new();
        for part in split_commas(body) {
            let (a, b) = trim_range(body, part);
            let item = &body[a..b];
            let Some(eq) = item.find('=') else {
                return Err(self.err(
                    st,
                    colon + a,
                    colon + b.max(a + 1),
                    "each part of a restriction is INPUT = EXPR",
                ));
            };
            let lhs = item[..eq].trim();
            let la = colon + a;
            let Some(ii) = inputs.iter().position(|d| d.name == lhs) else {
                let what = match find(lhs) {
                    Some(d) => format!("'{lhs}' is a {}, not an input", d.kind.word()),
                    None => format!(
                        "'{lhs}' is not a declared input{}{}",
                        Self::suggest(decls, lhs),
                        not_a_name(lhs)
                    ),
                };
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len().max(1),
                    format!("restriction '{rname}': {what}"),
                ));
            };
            if raw.iter().any(|(k, _, _)| *k == ii) {
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len(),
                    format!("restriction '{rname}' sets '{lhs}' twice"),
                ));
            }
            let (rhs, map) = st.slice(colon + a + eq + 1, colon + b);
            if rhs.trim().is_empty() {
                return Err(self.err(
                    st,
                    la,
                    la + lhs.len(),
                    format!("restriction '{rname}': '{lhs} =' needs an expression"),
                ));
            }
            let ast = parse_ast(rhs).map_err(|e| self.parse_err(&map, e))?;
            raw.push((ii, ast, map));
        }
        let replaced: Vec<usize> = raw.iter().map(|r| r.0).collect();
        let mut fresh: Vec<String> = Vec::new();
        for (_, ast, map) in &raw {
            for (n, span) in ast.idents() {
                let (a, b) = span_in(map, span);
                if n == super::TIME {
                    return Err(self.err_src(a, b, format!("restriction '{rname}': time 't' cannot be substituted for an input (a restriction's new names are inputs; explicit time belongs in the dynamics and outputs)")));
                }
                match find(n) {
                    Some(d) if d.kind == Kind::Const => {}
                    Some(d) if d.kind == Kind::Input => {
                        if inputs
                            .iter()
                            .position(|x| x.name == n)
                            .is_some_and(|ii| replaced.contains(&ii))
                        {
                            return Err(self.err_src(a, b, format!("restriction '{rname}' replaces '{n}' and also uses it on a right side")));
                        }
                    }
                    Some(d) => {
                        return Err(self.err_src(a, b, format!("restriction '{rname}': the right side may use known constants and inputs only, not the {} '{n}'", d.kind.word())));
                    }
                    None if outputs.iter().any(|(o, _)| o == n) => {
                        return Err(self.err_src(
                            a,
                            b,
                            format!("restriction '{rname}': '{n}' is an output, not an input"),
                        ));
                    }
                    None => {
                        if !fresh.iter().any(|f| f == n) {
                            fresh.push(n.to_string());
                        }
                    }
                }
            }
        }
        let mut new_inputs: Vec<String> = inputs
            .iter()
            .enumerate()
            .filter(|(i, _)| !replaced.contains(i))
            .map(|(_, d)| d.name.clone())
            .collect();
        new_inputs.extend(fresh.iter().cloned());
        let mut subs: Vec<(usize, Located)> = Vec::new();
        for (ii, ast, map) in raw {
            let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
                if fresh.iter().any(|f| f == n) || decls.iter().any(|d| d.name == n) {
                    Ok(c.symbol(n).id)
                } else {
                    // Every identifier was classified above.
                    Err(ParseError::new(format!("unknown symbol '{n}'"), s))
                }
            };
            let id = ctx
                .build(&ast, &mut resolve)
                .map_err(|e| self.parse_err(&map, e))?;
            let loc = Located { ast, id, map };
            // Affine in the new inputs.
            let vars: Vec<_> = new_inputs.iter().map(|n| ctx.symbol(n).var).collect();
            for &v in &vars {
                let d = ctx.diff(id, v);
                for &w in &vars {
                    let dd = ctx.diff(d, w);
                    if !ctx.is_identically_zero(dd) {
                        let (a, b) = loc.src_span(loc.ast.span);
                        let u = inputs.get(ii).map_or("", |d| d.name.as_str());
                        return Err(self.err_src(
                            a,
                            b,
                            format!(
                                "restriction '{rname}': {u} = ... is not affine in the inputs ({})",
                                new_inputs.join(", ")
                            ),
                        ));
                    }
                }
            }
            subs.push((ii, loc));
        }
        Ok(Restriction {
            name: rname.clone(),
            subs,
            inputs: new_inputs,
        })
    }
}

/// A derived input is `rate(u)` (the time derivative of a measured input) or
/// an expression of measured inputs and constants (e.g. `sqrt((wR - wL)^2)*wR`).
/// A derived input's definition, or a state's start (`kind` says which):
/// measured inputs and constants only.
fn check_derived(
    rd: &Reader,
    text: &str,
    map: &[usize],
    decls: &[Decl],
    (kind, at): (Kind, usize),
) -> Result<(), ModelError> {
    let what = if kind == Kind::State {
        "a state's start value"
    } else {
        "a derived input"
    };
    let measured = |n: &str| {
        decls
            .iter()
            .any(|d| d.name == n && d.kind == Kind::Input && d.derived.is_none())
    };
    let t = text.trim();
    // A rate of an earlier rate is a higher derivative (`input u_d2 =
    // rate(u_d1)`, as `obsan modes --out` declares them): the data layer
    // computes the derived inputs in order.
    let earlier_rate = |n: &str| {
        decls.iter().any(|d| {
            d.name == n
                && d.kind == Kind::Input
                && d.at < at
                && d.derived
                    .as_deref()
                    .is_some_and(|x| x.trim().starts_with("rate("))
        })
    };
    if let Some(inner) = t.strip_prefix("rate(").and_then(|r| r.strip_suffix(')')) {
        if measured(inner.trim()) || (kind == Kind::Input && earlier_rate(inner.trim())) {
            return Ok(());
        }
        let lead = text.len() - text.trim_start().len();
        let (a, b) = span_in(map, Span::new(lead, lead + t.len()));
        return Err(rd.err_src(
            a,
            b,
            format!(
                "rate(...) takes one measured input or an earlier rate(...), not '{}'",
                inner.trim()
            ),
        ));
    }
    let ast = parse_ast(text).map_err(|e| rd.parse_err(map, e))?;
    for (n, span) in ast.idents() {
        let ok = measured(n) || decls.iter().any(|d| d.name == n && d.kind == Kind::Const);
        if !ok {
            let (a, b) = span_in(map, span);
            return Err(rd.err_src(
                a,
                b,
                format!("{what} may use measured inputs and constants, not '{n}'"),
            ));
        }
    }
    Ok(())
}

/// Build an expression, allowing only identifiers of the given kinds.
fn build_checked(
    ctx: &mut Ctx,
    ast: &Ast,
    map: &[usize],
    rd: &Reader,
    decls: &[Decl],
    allowed: &[Kind],
    what: &str,
) -> Result<Id, ModelError> {
    let index: HashMap<&str, &Decl> = decls.iter().map(|d| (d.name.as_str(), d)).collect();
    let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
        match index.get(n).copied() {
            // Explicit time: never declared (refused above), a known coordinate.
            None if n == super::TIME => Ok(c.symbol(n).id),
            // The declaration's symbol was made in this context.
            Some(d) if allowed.contains(&d.kind) => Ok(d.sym.id),
            Some(d) => Err(ParseError::new(
                format!("{what} cannot use the {} '{n}'", d.kind.word()),
                s,
            )),
            None => {
                let best = decls
                    .iter()
                    .map(|d| (edit_distance(n, &d.name), &d.name))
                    .filter(|(k, _)| *k <= 2)
                    .min();
                let hint = best.map_or(String::new(), |(_, m)| format!(" (did you mean '{m}'?)"));
                Err(ParseError::new(
                    format!("unknown symbol '{n}' in {what}{hint}"),
                    s,
                ))
            }
        }
    };
    ctx.build(ast, &mut resolve)
        .map_err(|e| rd.parse_err(map, e))
}

/// The dynamics must be affine in the inputs: otherwise name the first
/// top-level term that is not.
fn check_affine(
    ctx: &mut Ctx,
    loc: &Located,
    decls: &[Decl],
    rd: &Reader,
    state: &str,
) -> Result<(), ModelError> {
    // Known and unknown inputs together: x' = f0 + sum f_i u_i + sum g_j w_j
    // (no products u*w, no powers of w: Martinelli's input-affine form).
    let is_input = |d: &&Decl| matches!(d.kind, Kind::Input | Kind::Unknown);
    let inputs: Vec<_> = decls.iter().filter(is_input).map(|d| d.sym.var).collect();
    let affine = |ctx: &mut Ctx, id: Id| -> bool {
        for &u in &inputs {
            let d = ctx.diff(id, u);
            for &w in &inputs {
                let dd = ctx.diff(d, w);
                if !ctx.is_identically_zero(dd) {
                    return false;
                }
            }
        }
        true
    };
    if affine(ctx, loc.id) {
        return Ok(());
    }
    let names: Vec<&str> = decls
        .iter()
        .filter(is_input)
        .map(|d| d.name.as_str())
        .collect();
    for (_, term) in loc.ast.additive_terms() {
        let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
            c.lookup(n)
                .map(|x| x.id)
                .ok_or_else(|| ParseError::new(format!("unknown symbol '{n}'"), s))
        };
        let Ok(tid) = ctx.build(term, &mut resolve) else {
            continue;
        };
        if !affine(ctx, tid) {
            let (a, b) = loc.src_span(term.span);
            let text = rd.src.get(a..b).unwrap_or("");
            return Err(rd.err_src(a, b, format!("the dynamics of {state} are not affine in the inputs ({}): the term '{text}' is not", names.join(", "))));
        }
    }
    let (a, b) = loc.src_span(loc.ast.span);
    Err(rd.err_src(
        a,
        b,
        format!(
            "the dynamics of {state} are not affine in the inputs ({})",
            names.join(", ")
        ),
    ))
}
