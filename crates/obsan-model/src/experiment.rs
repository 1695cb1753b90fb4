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
use obsan_expr::{Id, Symbol, Var, Q};

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
        // Validate names as normal_form does (same messages).
        for x in exps {
            self.normal_form(x.restriction.as_deref(), &x.set)?;
        }
        let varying = self.experiment_consts(exps);
        let mut ctx = self.ctx.clone();
        let states: Vec<_> = self.decls_of(Kind::State).cloned().collect();
        let params: Vec<_> = self.decls_of(Kind::Param).cloned().collect();
        let all_inputs: Vec<_> = self.decls_of(Kind::Input).cloned().collect();
        let nd = self.dynamics.len();
        let k = exps.len();
        let n = k * nd + params.len();
        let zero = ctx.int(0);

        let mut state = Vec::with_capacity(n);
        let mut state_vars = Vec::with_capacity(n);
        let mut consts: Vec<(String, Option<Q>)> = Vec::new();
        let mut shared: Vec<(Var, Id)> = Vec::new();
        for d in self.decls_of(Kind::Const) {
            if varying.contains(&d.name) {
                continue;
            }
            if let Some(q) = &d.value {
                shared.push((d.sym.var, ctx.num(q.clone())));
            }
            consts.push((d.name.clone(), d.value.clone()));
        }
        let mut inputs = Vec::new();
        let mut input_vars = Vec::new();
        let mut input_block = Vec::new(); // experiment of each stacked input
        let mut f0 = Vec::with_capacity(n);
        let mut field_rows: Vec<Vec<Id>> = Vec::new(); // per stacked input, its block entries
        let mut outputs = Vec::new();

        for (e, x) in exps.iter().enumerate() {
            let tag = e + 1;
            let mut map: Vec<(Var, Id)> = shared.clone();
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
                    Some(q) => ctx.num(q.clone()),
                    None => ctx.symbol(&name).id,
                };
                map.push((d.sym.var, id));
                consts.push((name, v));
            }
            let mut block_vars = Vec::new();
            for d in &states {
                let s = ctx.symbol(&experiment_name(&d.name, tag));
                map.push((d.sym.var, s.id));
                state.push(experiment_name(&d.name, tag));
                state_vars.push(s.var);
                block_vars.push(s.var);
            }
            // Inputs of this experiment, renamed; restricted inputs replaced.
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
            let first = field_rows.len();
            for (name, s) in exp_inputs.iter().zip(&syms) {
                inputs.push(experiment_name(name, tag));
                input_vars.push(s.var);
                input_block.push(e);
                field_rows.push(Vec::with_capacity(nd));
            }
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
                    field_rows[first + j].push(fi);
                }
                let c = ctx.canon(rest);
                f0.push(ctx.from_canonical(&c));
            }
            for (name, loc) in &self.outputs {
                let h = ctx
                    .substitute(loc.id, &map)
                    .map_err(|er| self.err_at(loc, &er.0))?;
                outputs.push((experiment_name(name, tag), h));
            }
            debug_assert_eq!(block_vars.len(), nd);
        }
        for d in &params {
            state.push(d.name.clone());
            state_vars.push(d.sym.var);
            f0.push(zero);
        }
        // Each input's field lives in its own experiment's block.
        let fields: Vec<Vec<Id>> = field_rows
            .into_iter()
            .zip(&input_block)
            .map(|(rows, &e)| {
                let mut v = vec![zero; n];
                v[e * nd..(e + 1) * nd].copy_from_slice(&rows);
                v
            })
            .collect();
        let delay = self
            .delay
            .as_ref()
            .and_then(|d| state.iter().position(|s| s == d));
        Ok(NormalForm {
            ctx,
            name: self.name.clone(),
            description: self.description.clone(),
            state,
            state_vars,
            n_dynamic: k * nd,
            consts,
            inputs,
            input_vars,
            f0,
            fields,
            unknown_inputs: Vec::new(),
            unknown_input_vars: Vec::new(),
            unknown_fields: Vec::new(),
            outputs,
            restriction: None,
            delay,
        })
    }
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
