//! The normal form `S' = f0(S) + sum_i f_i(S) u_i`, `y = h(S)` (eq. 6 of the paper).

use crate::error::ModelError;
use crate::sys::{Kind, System, TIME};
use obsan_expr::{parse_ast, Ast, Ctx, Id, ParseError, Span, Symbol, Var, Q};

/// A substitution: each variable and the expression that replaces it.
type Subst = Vec<(Var, Id)>;
/// `f0`, the input fields and the unknown-input fields, one entry per state each.
type SplitFields = (Vec<Id>, Vec<Vec<Id>>, Vec<Vec<Id>>);

/// Resolves names beyond the system's own first: `None` to fall through.
pub type ExtraNames<'a> = dyn Fn(&str, Span) -> Option<Result<Id, ParseError>> + 'a;

/// A system in input-affine normal form, ready for analysis.
///
/// The analysed state `S` is the dynamic states followed by the params
/// (whose derivative is 0); every vector field has one entry per element of `S`.
#[derive(Clone, Debug)]
pub struct NormalForm {
    pub ctx: Ctx,
    pub name: String,
    pub description: String,
    /// Names of the analysed state: dynamic states, then params.
    pub state: Vec<String>,
    pub state_vars: Vec<Var>,
    /// How many of `state` are dynamic states (the rest are params).
    pub n_dynamic: usize,
    /// Known constants: name and the value given to it, if any (else generic).
    pub consts: Vec<(String, Option<Q>)>,
    pub inputs: Vec<String>,
    pub input_vars: Vec<Var>,
    /// Drift `f0`, one entry per state element.
    pub f0: Vec<Id>,
    /// `fields[i]` is the field multiplying input `i`.
    pub fields: Vec<Vec<Id>>,
    pub outputs: Vec<(String, Id)>,
    /// The restriction applied, if any.
    pub restriction: Option<String>,
    /// Index in `state` of the delay param (`delay tau`): the dynamics see
    /// `u(t - tau)`. The predictor applies it exactly; the analysis to first
    /// order (`u - tau du/dt`, with `du/dt` as further free inputs).
    pub delay: Option<usize>,
    /// Unknown inputs `w_j` (`unknown input w`, `varying k`): unmeasured
    /// functions of time, `S' = f0 + sum f_i u_i + sum g_j w_j`. Empty for a
    /// model whose inputs are all known.
    pub unknown_inputs: Vec<String>,
    pub unknown_input_vars: Vec<Var>,
    /// `unknown_fields[j]` is the field `g_j` multiplying unknown input `j`.
    /// The outputs may contain the `w_j` (direct feedthrough).
    pub unknown_fields: Vec<Vec<Id>>,
    /// The right-hand sides and outputs as written (after constants and the
    /// restriction), before they are expanded: their sub-expressions
    /// (`N - A - I - H`) are candidate blocks of invariants. May be empty.
    pub written: Vec<Id>,
    /// The known inputs some output reads, made measured coordinates
    /// (`measured.rs`): each is a dynamic state and an output of its own
    /// name, and the input of that index is now its derivative `u'`.
    pub measured_inputs: Vec<String>,
}

impl NormalForm {
    /// Index in `state` of the clock `t` (`t' = 1`, known through its own
    /// output `t`), present when the fields or outputs use time explicitly.
    /// It is the analysis' coordinate, never a state of the user's: reports
    /// leave it out.
    pub fn clock(&self) -> Option<usize> {
        self.state.iter().position(|s| s == TIME)
    }

    /// Time as a known coordinate (Martinelli's route for time-varying
    /// systems): the last dynamic state `t` with `t' = 1` in the drift and no
    /// input or unknown input moving it, and the output `t` (first), so its
    /// differential is in the codistribution from order 0.
    fn append_clock(&mut self) {
        let t = self.ctx.symbol(TIME);
        let (zero, one) = (self.ctx.int(0), self.ctx.int(1));
        let k = self.n_dynamic;
        self.state.insert(k, TIME.to_string());
        self.state_vars.insert(k, t.var);
        self.f0.insert(k, one);
        for f in self.fields.iter_mut().chain(self.unknown_fields.iter_mut()) {
            f.insert(k, zero);
        }
        self.n_dynamic += 1;
        if let Some(d) = self.delay.as_mut() {
            // The delay is a param, after every dynamic state.
            *d += 1;
        }
        // First among the outputs: its row `dt` then always opens the basis
        // (order 0), so reports can set it aside.
        self.outputs.insert(0, (TIME.to_string(), t.id));
    }

    /// `true` if the drift is identically zero.
    pub fn drift_is_zero(&mut self) -> bool {
        let f0 = self.f0.clone();
        f0.iter().all(|&f| self.ctx.is_identically_zero(f))
    }
}

impl System {
    /// The normal form, after the named input restriction (if any) and with
    /// the given known constants set to values (others stay generic).
    pub fn normal_form(
        &self,
        restriction: Option<&str>,
        set: &[(String, Q)],
    ) -> Result<NormalForm, ModelError> {
        self.normal_form_with(restriction, set, true)
    }

    /// The normal form with outputs that read known inputs kept as written
    /// (`h(S, u)`, no input measured): for evaluating the model along given
    /// inputs (`obsan simulate` substitutes `u(t)` in the outputs too), never
    /// for an analysis.
    pub fn normal_form_as_written(
        &self,
        restriction: Option<&str>,
        set: &[(String, Q)],
    ) -> Result<NormalForm, ModelError> {
        self.normal_form_with(restriction, set, false)
    }

    fn normal_form_with(
        &self,
        restriction: Option<&str>,
        set: &[(String, Q)],
        measure: bool,
    ) -> Result<NormalForm, ModelError> {
        self.check_set(set)?;
        self.check_measured()?;
        let mut ctx = self.ctx.clone();
        // Constant values: from the file, then from --set.
        let (mut subst, consts) = self.const_values(&mut ctx, set);
        let inputs = match restriction {
            Some(rn) => self.restricted_inputs(&mut ctx, rn, &mut subst)?,
            None => self.decls_of(Kind::Input).map(|d| d.name.clone()).collect(),
        };
        let input_syms: Vec<Symbol> = inputs.iter().map(|n| ctx.symbol(n)).collect();
        let input_vars: Vec<Var> = input_syms.iter().map(|s| s.var).collect();
        let state_decls: Vec<_> = self
            .decls
            .iter()
            .filter(|d| d.kind == Kind::State)
            .chain(self.decls_of(Kind::Param))
            .collect();
        let n_dynamic = self.dynamics.len();
        let unknown_inputs: Vec<String> = self
            .decls_of(Kind::Unknown)
            .map(|d| d.name.clone())
            .collect();
        let unknown_syms: Vec<Symbol> = self.decls_of(Kind::Unknown).map(|d| d.sym).collect();
        let (f0, fields, unknown_fields) = self.split_fields(
            &mut ctx,
            &subst,
            &input_syms,
            &unknown_syms,
            state_decls.len(),
        )?;
        let mut written = Vec::new();
        for loc in &self.dynamics {
            if let Ok(e) = ctx.substitute(loc.id, &subst) {
                written.push(e);
            }
        }
        let mut outputs = Vec::new();
        for (n, loc) in &self.outputs {
            let h = ctx
                .substitute(loc.id, &subst)
                .map_err(|e| self.err_at(loc, &e.0))?;
            outputs.push((n.clone(), h));
            written.push(h);
        }
        let mut nf = NormalForm {
            ctx,
            name: self.name.clone(),
            description: self.description.clone(),
            state: state_decls.iter().map(|d| d.name.clone()).collect(),
            state_vars: state_decls.iter().map(|d| d.sym.var).collect(),
            n_dynamic,
            consts,
            inputs,
            input_vars,
            f0,
            fields,
            outputs,
            restriction: restriction.map(str::to_string),
            delay: self
                .delay
                .as_ref()
                .and_then(|d| state_decls.iter().position(|s| &s.name == d)),
            unknown_inputs,
            unknown_input_vars: unknown_syms.iter().map(|s| s.var).collect(),
            unknown_fields,
            written,
            measured_inputs: Vec::new(),
        };
        if measure {
            nf.measure_inputs();
        }
        if self.uses_time() {
            nf.append_clock();
        }
        Ok(nf)
    }

    /// Every `--set` name must be a known constant of the system.
    fn check_set(&self, set: &[(String, Q)]) -> Result<(), ModelError> {
        for (n, _) in set {
            match self.decls.iter().find(|d| &d.name == n) {
                Some(d) if d.kind == Kind::Const => {}
                Some(d) => {
                    return Err(ModelError::general(
                        "--set",
                        format!(
                            "'{n}' is a {} of {}, not a known constant",
                            d.kind.word(),
                            self.name
                        ),
                    ))
                }
                None => {
                    let names: Vec<&str> = self
                        .decls_of(Kind::Const)
                        .map(|d| d.name.as_str())
                        .collect();
                    let known = if names.is_empty() {
                        "it has none".to_string()
                    } else {
                        format!("its constants: {}", names.join(", "))
                    };
                    return Err(ModelError::general(
                        "--set",
                        format!("'{n}' is not a constant of {} ({known})", self.name),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Each constant's value (the last `--set`, else the file's, else none: generic),
    /// and the substitution of the valued ones.
    fn const_values(
        &self,
        ctx: &mut Ctx,
        set: &[(String, Q)],
    ) -> (Subst, Vec<(String, Option<Q>)>) {
        let mut subst: Vec<(Var, Id)> = Vec::new();
        let mut consts: Vec<(String, Option<Q>)> = Vec::new();
        for d in self.decls_of(Kind::Const) {
            let v = set
                .iter()
                .rev()
                .find(|(n, _)| n == &d.name)
                .map(|(_, q)| q.clone())
                .or_else(|| d.value.clone());
            if let Some(q) = &v {
                subst.push((d.sym.var, ctx.num(q.clone())));
            }
            consts.push((d.name.clone(), v));
        }
        (subst, consts)
    }

    /// The inputs under restriction `rn`; `subst` gains each replaced input's expression.
    fn restricted_inputs(
        &self,
        ctx: &mut Ctx,
        rn: &str,
        subst: &mut Vec<(Var, Id)>,
    ) -> Result<Vec<String>, ModelError> {
        let Some(r) = self.restriction(rn) else {
            let names: Vec<&str> = self.restrictions.iter().map(|r| r.name.as_str()).collect();
            let known = if names.is_empty() {
                "it declares none".to_string()
            } else {
                format!("it declares: {}", names.join(", "))
            };
            return Err(ModelError::general(
                "--input",
                format!("{} has no restriction named '{rn}' ({known})", self.origin),
            ));
        };
        let input_decls: Vec<_> = self.decls_of(Kind::Input).collect();
        for (ii, loc) in &r.subs {
            let rhs = ctx
                .substitute(loc.id, subst)
                .map_err(|e| self.err_at(loc, &e.0))?;
            // `ii` indexes the inputs (made so by the reader).
            if let Some(d) = input_decls.get(*ii) {
                subst.push((d.sym.var, rhs));
            }
        }
        Ok(r.inputs.clone())
    }

    /// `f0`, the input fields `f_i = d rhs / d u_i` and the unknown-input fields
    /// `g_j = d rhs / d w_j` of each of the `n_states` states (zero for the params),
    /// after `subst`.
    fn split_fields(
        &self,
        ctx: &mut Ctx,
        subst: &[(Var, Id)],
        input_syms: &[Symbol],
        unknown_syms: &[Symbol],
        n_states: usize,
    ) -> Result<SplitFields, ModelError> {
        let n_dynamic = self.dynamics.len();
        let input_vars: Vec<Var> = input_syms.iter().map(|s| s.var).collect();
        let mut unknown_fields = vec![Vec::new(); unknown_syms.len()];
        let mut f0 = Vec::new();
        let mut fields = vec![Vec::new(); input_syms.len()];
        let zero = ctx.int(0);
        // The written forms of f0 and of each field (written.rs in
        // obsan-expr): each right-hand side with every input and unknown
        // input set to 0, and its derivatives likewise; it is affine in them
        // jointly, so these are the same functions as the canonical forms.
        let zeros: Vec<(Var, Id)> = input_vars
            .iter()
            .chain(unknown_syms.iter().map(|w| &w.var))
            .map(|&v| (v, zero))
            .collect();
        for k in 0..n_states {
            if k >= n_dynamic {
                f0.push(zero);
                for f in fields.iter_mut().chain(unknown_fields.iter_mut()) {
                    f.push(zero);
                }
                continue;
            }
            let loc = &self.dynamics[k];
            let e = ctx
                .substitute(loc.id, subst)
                .map_err(|er| self.err_at(loc, &er.0))?;
            // Budgeted, so that a form past the term budget (a sum of rate laws
            // over distinct denominators expands their product) is an error at
            // its equation, not an unbounded allocation.
            let canon_at = |ctx: &mut Ctx, id| {
                ctx.try_canon(id)
                    .map_err(|l| self.err_at(loc, &l.to_string()))
            };
            let written_at_zero = |ctx: &mut Ctx, id: Id| ctx.substitute(id, &zeros).ok();
            // e is affine in the inputs (checked when read; restrictions are affine too).
            let mut rest = e;
            for (i, &u) in input_vars.iter().enumerate() {
                let fi = ctx.diff(e, u);
                let c = canon_at(ctx, fi)?;
                debug_assert!(
                    input_vars.iter().all(|&w| {
                        let d = ctx.diff(fi, w);
                        ctx.is_identically_zero(d)
                    }),
                    "affine"
                );
                let fi_written = written_at_zero(ctx, fi);
                let fi = ctx.from_canonical(&c);
                if let Some(w) = fi_written {
                    ctx.note_written_form(fi, w);
                }
                let term = ctx.mul(&[fi, input_syms[i].id]);
                rest = ctx.sub(rest, term);
                fields[i].push(fi);
            }
            // g_j = d rhs / d w_j (affine in the inputs and the w_j jointly,
            // checked when read).
            for (j, w) in unknown_syms.iter().enumerate() {
                let gj = ctx.diff(e, w.var);
                let c = canon_at(ctx, gj)?;
                let gj_written = written_at_zero(ctx, gj);
                let gj = ctx.from_canonical(&c);
                if let Some(w) = gj_written {
                    ctx.note_written_form(gj, w);
                }
                let term = ctx.mul(&[gj, w.id]);
                rest = ctx.sub(rest, term);
                unknown_fields[j].push(gj);
            }
            let c = canon_at(ctx, rest)?;
            let f0k = ctx.from_canonical(&c);
            if let Some(w) = written_at_zero(ctx, e) {
                ctx.note_written_form(f0k, w);
            }
            f0.push(f0k);
        }
        Ok((f0, fields, unknown_fields))
    }

    pub(crate) fn err_at(&self, loc: &crate::sys::Located, msg: &str) -> ModelError {
        let (a, b) = loc.src_span(loc.ast.span);
        ModelError::at(&self.origin, &self.src, a, b, msg.to_string())
    }
}

impl NormalForm {
    /// Parse an expression over the analysed state and the known constants
    /// (constants with a value are replaced by it), and the inputs if `inputs`.
    pub fn parse_expr(&mut self, text: &str, inputs: bool) -> Result<Id, ParseError> {
        let ast = parse_ast(text)?;
        self.build_expr(&ast, inputs, &|_, _| None)
    }

    /// Build a syntax tree over the state, constants and (if `inputs`) inputs;
    /// `extra` resolves other names first (or refuses one with an error).
    pub fn build_expr(
        &mut self,
        ast: &Ast,
        inputs: bool,
        extra: &ExtraNames,
    ) -> Result<Id, ParseError> {
        let state = self.state.clone();
        let consts = self.consts.clone();
        let ins = if inputs { self.inputs.clone() } else { vec![] };
        let all_inputs = self.inputs.clone();
        let mut resolve = |c: &mut Ctx, n: &str, s: Span| -> Result<Id, ParseError> {
            if let Some(r) = extra(n, s) {
                return r;
            }
            if state.iter().any(|x| x == n) || ins.iter().any(|x| x == n) {
                return Ok(c.symbol(n).id);
            }
            if let Some((_, v)) = consts.iter().find(|(x, _)| x == n) {
                return Ok(match v {
                    Some(q) => c.num(q.clone()),
                    None => c.symbol(n).id,
                });
            }
            if all_inputs.iter().any(|x| x == n) {
                return Err(ParseError::new(
                    format!("'{n}' is an input; only states, params and constants may appear here"),
                    s,
                ));
            }
            let mut known = state.clone();
            known.extend(consts.iter().map(|c| c.0.clone()));
            known.extend(ins.iter().cloned());
            Err(ParseError::new(
                format!("unknown symbol '{n}' (known here: {})", known.join(", ")),
                s,
            ))
        };
        self.ctx.build(ast, &mut resolve)
    }
}
