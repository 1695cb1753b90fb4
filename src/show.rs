//! `obsan show`, and loading a system from the command line (shared by the
//! commands that take a SYSTEM argument).

use crate::cli::{ShowArgs, SystemArgs};
use crate::Failure;
use obsan_expr::{Ctx, Id, Q};
use obsan_model::{Experiment, Kind, NormalForm, System};
use std::process::ExitCode;

/// Read and check a .sys file.
pub fn load_system(path: &str) -> Result<System, Failure> {
    let src = crate::fsio::read_text(path)?;
    let sys = System::parse(&src, path).map_err(|e| Failure(e.to_string()))?;
    crate::clock::refuse_time(&sys)?;
    crate::clock::refuse_measured(&sys)?;
    Ok(sys)
}

/// Parse `--set NAME=VALUE` flags (values are exact: `0.9` is 9/10).
pub fn parse_sets(sets: &[String]) -> Result<Vec<(String, Q)>, Failure> {
    let mut out = Vec::new();
    for s in sets {
        let Some((n, v)) = s.split_once('=') else {
            return Err(Failure(format!(
                "--set {s}: expected NAME=VALUE, e.g. --set q=0.9"
            )));
        };
        let mut ctx = Ctx::new();
        let id = ctx
            .parse(v.trim())
            .map_err(|e| Failure(format!("--set {s}: {e}")))?;
        let r = ctx
            .try_canon(id)
            .map_err(|l| Failure(format!("--set {s}: {l}")))?;
        let Some(q) = r.as_q() else {
            return Err(Failure(format!(
                "--set {s}: the value must be a rational number"
            )));
        };
        out.push((n.trim().to_string(), q));
    }
    Ok(out)
}

/// Load a system and bring it to normal form as the flags say.
pub fn load_normal_form(a: &SystemArgs) -> Result<(System, NormalForm), Failure> {
    let sys = load_system(&a.system)?;
    if let Some(exps) = experiments_of(a)? {
        let nf = sys
            .stacked_normal_form(&exps)
            .map_err(|e| Failure(e.to_string()))?;
        return Ok((sys, nf));
    }
    let sets = parse_sets(&a.set)?;
    let nf = sys
        .normal_form(a.restriction.as_deref(), &sets)
        .map_err(|e| Failure(e.to_string()))?;
    Ok((sys, nf))
}

fn expr_json(ctx: &mut Ctx, id: Id) -> crate::json::Formula {
    let c = ctx.canon(id);
    crate::json::Formula {
        latex: ctx.ratfun_latex(&c),
        text: ctx.ratfun_text(&c),
    }
}

pub fn run(a: &ShowArgs) -> Result<ExitCode, Failure> {
    let (sys, mut nf) = load_normal_form(&a.sys)?;
    let params: Vec<String> = sys.decls_of(Kind::Param).map(|d| d.name.clone()).collect();
    // The user's states: the clock of explicit time and the measured inputs
    // are the analysis' own.
    let clock = nf.clock();
    let states: Vec<String> = nf.state[..nf.n_dynamic]
        .iter()
        .enumerate()
        .filter(|(k, s)| Some(*k) != clock && !nf.measured_inputs.contains(s))
        .map(|(_, s)| s.clone())
        .collect();
    if a.out.json {
        use std::collections::BTreeMap;
        let field = |nf: &mut NormalForm, f: &[Id]| {
            let mut m = BTreeMap::new();
            for (k, &c) in f.iter().enumerate() {
                m.insert(nf.state[k].clone(), expr_json(&mut nf.ctx, c));
            }
            m
        };
        let f0 = nf.f0.clone();
        let f0j = field(&mut nf, &f0);
        let mut fields = BTreeMap::new();
        for (i, f) in nf.fields.clone().iter().enumerate() {
            let fj = field(&mut nf, f);
            fields.insert(nf.inputs[i].clone(), fj);
        }
        let mut outputs = BTreeMap::new();
        for (n, h) in nf.outputs.clone() {
            outputs.insert(n, expr_json(&mut nf.ctx, h));
        }
        let consts = nf
            .consts
            .iter()
            .map(|(n, v)| crate::json::Constant {
                name: n.clone(),
                value: v.as_ref().map(|q| q.to_string()),
            })
            .collect();
        crate::json::print(&crate::json::Show {
            consts,
            description: nf.description.clone(),
            exact: true,
            f0: f0j,
            fields,
            file: a.sys.system.clone(),
            inputs: nf.inputs.clone(),
            outputs,
            params,
            restriction: nf.restriction.clone(),
            states,
            system: nf.name.clone(),
        })?;
        return Ok(ExitCode::SUCCESS);
    }
    let fmt = |nf: &mut NormalForm, id: Id| -> String {
        let c = nf.ctx.canon(id);
        if a.out.latex {
            nf.ctx.ratfun_latex(&c)
        } else {
            nf.ctx.ratfun_text(&c)
        }
    };
    let mut out = String::new();
    out.push_str(&format!("system {}", nf.name));
    if let Some(r) = &nf.restriction {
        out.push_str(&format!(" with restriction {r}"));
    }
    out.push('\n');
    if !nf.description.is_empty() {
        out.push_str(&format!("  {}\n", nf.description));
    }
    let list = |v: &[String]| {
        if v.is_empty() {
            "(none)".to_string()
        } else {
            v.join(", ")
        }
    };
    out.push_str(&format!("states: {}\n", list(&states)));
    out.push_str(&format!("params: {}\n", list(&params)));
    let consts: Vec<String> = nf
        .consts
        .iter()
        .map(|(n, v)| match v {
            Some(q) => format!("{n} = {q}"),
            None => format!("{n} (generic)"),
        })
        .collect();
    out.push_str(&format!("consts: {}\n", list(&consts)));
    out.push_str(&format!("inputs: {}\n", list(&nf.inputs)));
    if !nf.unknown_inputs.is_empty() {
        out.push_str(&format!("unknown inputs: {}\n", list(&nf.unknown_inputs)));
    }
    if clock.is_some() {
        out.push_str("time: the fields or outputs use t explicitly; analysed with the clock t' = 1 and the known output t (not a state of the model)\n");
    }
    if let Some(note) = crate::clock::measured_note(&nf) {
        out.push_str(&format!("{note}\n"));
    }
    out.push_str(&format!("analysed state S = [{}]\n", nf.state.join(", ")));
    let mut fields: Vec<(String, Vec<Id>)> = vec![("f0".to_string(), nf.f0.clone())];
    for (i, f) in nf.fields.iter().enumerate() {
        fields.push((
            format!("f_{} (coefficient of {})", nf.inputs[i], nf.inputs[i]),
            f.clone(),
        ));
    }
    for (j, g) in nf.unknown_fields.iter().enumerate() {
        let w = &nf.unknown_inputs[j];
        fields.push((format!("g_{w} (coefficient of the unknown {w})"), g.clone()));
    }
    for (name, f) in fields {
        let nonzero: Vec<(usize, Id)> = f
            .iter()
            .copied()
            .enumerate()
            .filter(|(_, c)| !nf.ctx.is_identically_zero(*c))
            .collect();
        if nonzero.is_empty() {
            out.push_str(&format!("{name}: 0\n"));
            continue;
        }
        out.push_str(&format!("{name}:\n"));
        let w = nonzero
            .iter()
            .map(|(k, _)| nf.state[*k].len())
            .max()
            .unwrap_or(0);
        for (k, c) in nonzero {
            let s = fmt(&mut nf, c);
            out.push_str(&format!("  {:w$} : {s}\n", nf.state[k]));
        }
        let zeros: Vec<String> = f
            .iter()
            .enumerate()
            .filter(|(_, c)| nf.ctx.is_identically_zero(**c))
            .map(|(k, _)| nf.state[k].clone())
            .collect();
        if !zeros.is_empty() {
            out.push_str(&format!("  (0 for {})\n", zeros.join(", ")));
        }
    }
    for (n, h) in nf.outputs.clone() {
        let s = fmt(&mut nf, h);
        out.push_str(&format!("output {n} = {s}\n"));
    }
    out!("{out}");
    Ok(ExitCode::SUCCESS)
}

/// An exact rational from text (`0.9` is 9/10).
pub(crate) fn rational(v: &str) -> Result<Q, String> {
    let mut ctx = Ctx::new();
    let id = ctx.parse(v).map_err(|e| e.to_string())?;
    ctx.canon(id)
        .as_q()
        .ok_or_else(|| format!("'{v}' is not a rational number"))
}

/// The experiments the flags ask for (`None`: one ordinary experiment).
/// `--set` values apply to every experiment (an experiment's own win).
pub fn experiments_of(a: &SystemArgs) -> Result<Option<Vec<Experiment>>, Failure> {
    let mut exps = Vec::new();
    if let Some(f) = &a.experiments {
        if f == "auto" {
            return Err(Failure(
                "--experiments auto is a question for `obsan rank`; here give the experiments (--experiment SPEC or --experiments FILE)".into(),
            ));
        }
        let text = crate::fsio::read_text(f)?;
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let e = Experiment::parse(line, &rational)
                .map_err(|m| Failure(format!("{f}:{}: {m}", i + 1)))?;
            exps.push(e);
        }
        if exps.is_empty() {
            return Err(Failure(format!("{f}: no experiments in the file")));
        }
    }
    for s in &a.experiment {
        let e = Experiment::parse(s, &rational)
            .map_err(|m| Failure(format!("--experiment '{s}': {m}")))?;
        exps.push(e);
    }
    if exps.is_empty() {
        return Ok(None);
    }
    let sets = parse_sets(&a.set)?;
    for e in exps.iter_mut() {
        let mut all = sets.clone();
        all.append(&mut e.set);
        e.set = all;
    }
    Ok(Some(exps))
}
