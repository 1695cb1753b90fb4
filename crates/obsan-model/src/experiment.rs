//! Several experiments stacked into one normal form (multi-experiment
//! identifiability): each experiment runs its own copy of the dynamic states
//! from its own initial condition, under its own input restriction and its own
//! values of the known constants; the params are shared. Observability of the
//! stacked state `[x@1, ..., x@k, params]` is identifiability of the params
//! (and of every experiment's initial state) from all the experiments'
//! outputs together.

use crate::error::ModelError;
use crate::normal::NormalForm;
use crate::sys::{Kind, System};
use obsan_expr::{Ctx, Id, Symbol, Var, Q};

/// One experiment: an input restriction (or none: every input free) and
/// values of known constants (the others, if they vary between experiments,
/// stay generic and distinct per experiment).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Experiment {
    pub restriction: Option<String>,
    pub set: Vec<(String, Q)>,
}

impl Experiment {
    /// `q: q=0.9, k=2` reads as restriction `q` with `q = 9/10`, `k = 2`;
    /// `: q=0` or `q=0` as no restriction; `q` alone as restriction `q`.
    /// Values are exact rationals (`0.9` is 9/10); `parse_value` reads one.
    pub fn parse(
        text: &str,
        parse_value: &dyn Fn(&str) -> Result<Q, String>,
    ) -> Result<Experiment, String> {
        let (r, sets) = match text.split_once(':') {
            Some((r, s)) => (r.trim(), s.trim()),
            None if text.contains('=') => ("", text.trim()),
            None => (text.trim(), ""),
        };
        if !r.is_empty() && !r.chars().all(|c| c.is_alphanumeric() || c == '_') {
            return Err(format!(
                "'{r}' is not a restriction name (expected `NAME: c=VALUE, ...`)"
            ));
        }
        let mut set = Vec::new();
        for item in sets.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((n, v)) = item.split_once('=') else {
                return Err(format!(
                    "'{item}': expected NAME=VALUE, e.g. `q: q=0.9, k=2`"
                ));
            };
            let q = parse_value(v.trim()).map_err(|e| format!("'{item}': {e}"))?;
            set.push((n.trim().to_string(), q));
        }
        Ok(Experiment {
            restriction: (!r.is_empty()).then(|| r.to_string()),
            set,
        })
    }
}

/// The name of a copy of `name` in experiment `e` (1-based).
pub fn experiment_name(name: &str, e: usize) -> String {
    format!("{name}@{e}")
}

impl System {
    /// The constants that differ between experiments: those some experiment
    /// sets, and those a used restriction mentions.
    fn experiment_consts(&self, exps: &[Experiment]) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for d in self.decls_of(Kind::Const) {
            let set = exps.iter().any(|x| x.set.iter().any(|(n, _)| n == &d.name));
            let in_restriction = exps.iter().any(|x| {
                x.restriction
                    .as_deref()
                    .and_then(|r| self.restriction(r))
                    .is_some_and(|r| {
                        r.subs
                            .iter()
                            .any(|(_, loc)| self.ctx.reachable(&[loc.id]).contains(&d.sym.id))
                    })
            });
            if set || in_restriction {
                out.push(d.name.clone());
            }
        }
        out
    }

    /// The stacked normal form of several experiments. Dynamic states, inputs
    /// and outputs of experiment `e` (1-based) are renamed `x@e`, `u@e`,
    /// `y@e`; a constant that varies between experiments becomes `c@e`
    /// (its value in experiment `e`, or generic there when not given: the
    /// file's value is not used for it); other constants are shared (their
    /// file value or generic). Params are shared and come last.
    pub fn stacked_normal_form(&self, exps: &[Experiment]) -> Result<NormalForm, ModelError> {
        self.refuse_stacking(exps)?;
        let varying = self.experiment_consts(exps);
        let mut ctx = self.ctx.clone();
        let params: Vec<_> = self.decls_of(Kind::Param).cloned().collect();
        let nd = self.dynamics.len();
        let k = exps.len();
        let n = k * nd + params.len();
        let zero = ctx.int(0);
        let mut st = Stacked {
            ctx,
            state: Vec::with_capacity(n),
            state_vars: Vec::with_capacity(n),
            consts: Vec::new(),
            inputs: Vec::new(),
            input_vars: Vec::new(),
            input_block: Vec::new(),
            f0: Vec::with_capacity(n),
            field_rows: Vec::new(),
            outputs: Vec::new(),
        };
        let mut shared: Vec<(Var, Id)> = Vec::new();
        for d in self.decls_of(Kind::Const) {
            if varying.contains(&d.name) {
                continue;
            }
            if let Some(q) = &d.value {
                shared.push((d.sym.var, st.ctx.num(q.clone())));
            }
            st.consts.push((d.name.clone(), d.value.clone()));
        }
        for (e, x) in exps.iter().enumerate() {
            self.stack_experiment(&mut st, e, x, &shared, &varying)?;
        }
        for d in &params {
            st.state.push(d.name.clone());
            st.state_vars.push(d.sym.var);
            st.f0.push(zero);
        }
        // Each input's field lives in its own experiment's block.
        let fields: Vec<Vec<Id>> = st
            .field_rows
            .into_iter()
            .zip(&st.input_block)
            .map(|(rows, &e)| {
                let mut v = vec![zero; n];
                v[e * nd..(e + 1) * nd].copy_from_slice(&rows);
                v
            })
            .collect();
        let delay = self
            .delay
            .as_ref()
            .and_then(|d| st.state.iter().position(|s| s == d));
        Ok(NormalForm {
            ctx: st.ctx,
            name: self.name.clone(),
            description: self.description.clone(),
            state: st.state,
            state_vars: st.state_vars,
            n_dynamic: k * nd,
            consts: st.consts,
            inputs: st.inputs,
            input_vars: st.input_vars,
            f0: st.f0,
            fields,
            unknown_inputs: Vec::new(),
            unknown_input_vars: Vec::new(),
            unknown_fields: Vec::new(),
            outputs: st.outputs,
            restriction: None,
            delay,
            // Stacked copies: sub-expressions per copy are not tracked.
            written: Vec::new(),
            // Refused by `refuse_stacking`.
            measured_inputs: Vec::new(),
        })
    }

    /// The experiments that cannot be stacked: none, a model with unknown inputs or time,
    /// or an experiment `normal_form` refuses (same messages).
    fn refuse_stacking(&self, exps: &[Experiment]) -> Result<(), ModelError> {
        if exps.is_empty() {
            return Err(ModelError::general(
                "--experiment",
                "no experiments given".to_string(),
            ));
        }
        // Unknown inputs of several experiments (each its own unmeasured signal) are not
        // stacked yet: refuse rather than analyse them as if they were absent.
        if let Some(w) = self.decls_of(Kind::Unknown).next() {
            return Err(ModelError::general(
                "--experiment",
                format!(
                    "'{}' is an unknown input: several experiments of a model with unknown \
                     inputs are not supported yet",
                    w.name
                ),
            ));
        }
        if let Some(e) = self.time_refusal("several experiments (`--experiment`)") {
            return Err(e);
        }
        if let Some(e) = self.input_output_refusal("several experiments (`--experiment`)") {
            return Err(e);
        }
        for x in exps {
            self.normal_form(x.restriction.as_deref(), &x.set)?;
        }
        Ok(())
    }

    /// Add experiment `e` (0-based; its names carry `@{e + 1}`) to the stack: its
    /// varying constants and states renamed, its inputs (restricted as it says), its
    /// dynamics split into drift and input fields, its outputs. `shared` sets the
    /// constants common to every experiment.
    fn stack_experiment(
        &self,
        st: &mut Stacked,
        e: usize,
        x: &Experiment,
        shared: &[(Var, Id)],
        varying: &[String],
    ) -> Result<(), ModelError> {
        let tag = e + 1;
        let nd = self.dynamics.len();
        let mut map: Vec<(Var, Id)> = shared.to_vec();
        for d in self.decls_of(Kind::Const) {
            if !varying.contains(&d.name) {
                continue;
            }
            let name = experiment_name(&d.name, tag);
            let v = x
                .set
                .iter()
                .rev()
                .find(|(m, _)| m == &d.name)
                .map(|s| s.1.clone());
            let id = match &v {
                Some(q) => st.ctx.num(q.clone()),
                None => st.ctx.symbol(&name).id,
            };
            map.push((d.sym.var, id));
            st.consts.push((name, v));
        }
        for d in self.decls_of(Kind::State) {
            let s = st.ctx.symbol(&experiment_name(&d.name, tag));
            map.push((d.sym.var, s.id));
            st.state.push(experiment_name(&d.name, tag));
            st.state_vars.push(s.var);
        }
        let (exp_inputs, syms) = self.experiment_inputs(&mut st.ctx, tag, x, &mut map)?;
        let first = st.field_rows.len();
        for (name, s) in exp_inputs.iter().zip(&syms) {
            st.inputs.push(experiment_name(name, tag));
            st.input_vars.push(s.var);
            st.input_block.push(e);
            st.field_rows.push(Vec::with_capacity(nd));
        }
        let ctx = &mut st.ctx;
        for loc in &self.dynamics {
            let ex = ctx
                .substitute(loc.id, &map)
                .map_err(|er| self.err_at(loc, &er.0))?;
            let mut rest = ex;
            for (j, s) in syms.iter().enumerate() {
                let fi = ctx.diff(ex, s.var);
                let c = ctx.canon(fi);
                let fi = ctx.from_canonical(&c);
                let term = ctx.mul(&[fi, s.id]);
                rest = ctx.sub(rest, term);
                st.field_rows[first + j].push(fi);
            }
            let c = ctx.canon(rest);
            st.f0.push(ctx.from_canonical(&c));
        }
        for (name, loc) in &self.outputs {
            let h = ctx
                .substitute(loc.id, &map)
                .map_err(|er| self.err_at(loc, &er.0))?;
            st.outputs.push((experiment_name(name, tag), h));
        }
        Ok(())
    }

    /// Experiment `tag`'s inputs, renamed `u@tag` (the restricted system's inputs under
    /// its restriction), and their symbols; `map` gains the renaming and each restricted
    /// input's replacement.
    fn experiment_inputs(
        &self,
        ctx: &mut Ctx,
        tag: usize,
        x: &Experiment,
        map: &mut Vec<(Var, Id)>,
    ) -> Result<(Vec<String>, Vec<Symbol>), ModelError> {
        let all_inputs: Vec<_> = self.decls_of(Kind::Input).collect();
        let mut exp_inputs: Vec<String> = all_inputs.iter().map(|d| d.name.clone()).collect();
        let mut in_map: Vec<(Var, Id)> = Vec::new();
        let restriction = match x.restriction.as_deref() {
            Some(r) => self.restriction(r),
            None => None,
        };
        if let Some(r) = restriction {
            exp_inputs = r.inputs.clone();
        }
        let mut syms: Vec<Symbol> = Vec::new();
        for name in &exp_inputs {
            let orig = ctx.symbol(name);
            let renamed = ctx.symbol(&experiment_name(name, tag));
            in_map.push((orig.var, renamed.id));
            syms.push(renamed);
        }
        if let Some(r) = restriction {
            let mut rmap = map.clone();
            rmap.extend(in_map.iter().cloned());
            for (ii, loc) in &r.subs {
                let rhs = ctx
                    .substitute(loc.id, &rmap)
                    .map_err(|er| self.err_at(loc, &er.0))?;
                if let Some(d) = all_inputs.get(*ii) {
                    map.push((d.sym.var, rhs));
                }
            }
        }
        map.extend(in_map);
        Ok((exp_inputs, syms))
    }
}

/// The stacked normal form's parts, filled experiment by experiment.
struct Stacked {
    ctx: Ctx,
    state: Vec<String>,
    state_vars: Vec<Var>,
    consts: Vec<(String, Option<Q>)>,
    inputs: Vec<String>,
    input_vars: Vec<Var>,
    /// The experiment of each stacked input.
    input_block: Vec<usize>,
    f0: Vec<Id>,
    /// Per stacked input, its field's entries in its experiment's block.
    field_rows: Vec<Vec<Id>>,
    outputs: Vec<(String, Id)>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn q(s: &str) -> Result<Q, String> {
        let mut c = obsan_expr::Ctx::new();
        let id = c.parse(s).map_err(|e| e.to_string())?;
        c.canon(id).as_q().ok_or_else(|| "not rational".to_string())
    }

    #[test]
    fn parses_experiment_specs() {
        let e = Experiment::parse("q: q=0.9, k=2", &q).unwrap();
        assert_eq!(e.restriction.as_deref(), Some("q"));
        assert_eq!(e.set.len(), 2);
        assert_eq!(e.set[0].1, q("9/10").unwrap());
        assert_eq!(Experiment::parse(": q=0", &q).unwrap().restriction, None);
        assert_eq!(Experiment::parse("q=0", &q).unwrap().restriction, None);
        assert_eq!(Experiment::parse("q", &q).unwrap().set, vec![]);
        assert!(Experiment::parse("q: q", &q).is_err());
        assert!(Experiment::parse("a b: q=1", &q).is_err());
    }

    #[test]
    fn stacks_blocks_with_shared_params() {
        // x' = -a x + u, y = x; two experiments: unrestricted and u = c*v.
        let src = "system s\nstate x\nparam a\nconst c\ninput u\nx' = -a*x + u\noutput y = x\nrestrict r: u = c*v\n";
        let sys = System::parse(src, "s.sys").unwrap();
        let exps = vec![
            Experiment::default(),
            Experiment {
                restriction: Some("r".into()),
                set: vec![("c".into(), Q::from_i64(2))],
            },
        ];
        let mut nf = sys.stacked_normal_form(&exps).unwrap();
        assert_eq!(nf.state, vec!["x@1", "x@2", "a"]);
        assert_eq!(nf.n_dynamic, 2);
        assert_eq!(nf.inputs, vec!["u@1", "v@2"]);
        assert_eq!(nf.ctx.to_text(nf.f0[0]), "-a*x@1");
        assert_eq!(nf.ctx.to_text(nf.f0[1]), "-a*x@2");
        // u@1 moves only x@1; v@2 moves x@2 by c = 2.
        assert_eq!(nf.ctx.to_text(nf.fields[0][0]), "1");
        assert!(nf.ctx.is_zero(nf.fields[0][1]));
        assert!(nf.ctx.is_zero(nf.fields[1][0]));
        assert_eq!(nf.ctx.to_text(nf.fields[1][1]), "2");
        assert_eq!(nf.outputs[1].0, "y@2");
        assert_eq!(
            nf.consts,
            vec![
                ("c@1".to_string(), None),
                ("c@2".to_string(), Some(Q::from_i64(2)))
            ]
        );
    }

    #[test]
    fn unknown_restriction_is_an_error() {
        let src = "system s\nstate x\ninput u\nx' = u\noutput y = x\n";
        let sys = System::parse(src, "s.sys").unwrap();
        let e = sys
            .stacked_normal_form(&[Experiment {
                restriction: Some("nope".into()),
                set: vec![],
            }])
            .unwrap_err();
        assert!(e.to_string().contains("nope"), "{e}");
    }
}
