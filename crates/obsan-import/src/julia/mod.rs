//! StructuralIdentifiability.jl's `@ODEmodel` text (SciML, MIT): a Julia
//! file holding one or more models, e.g. its `benchmarking/benchmarks.jl`.
//!
//! Only the Julia needed to find and read models is understood: the macro
//! `@ODEmodel(eq, eq, ...)`; a model named by a `:KEY => Dict(:name => "...",
//! :cite => "...", :ode => MODEL)` entry or `NAME[:KEY] = Dict(...)`;
//! `VAR = @ODEmodel(...)` and `VAR = set_parameter_values(VAR, Dict(p =>
//! VALUE, ...))`, whose values (numbers, `QQ(a, b)`, `a // b`) are
//! substituted. Everything else in the file is skipped token by token.
//!
//! In a model, `x'(t) = EXPR` makes `x` a state, `y(t) = EXPR` an output,
//! another `u(t)` an input and a bare name a parameter, as SI.jl does.

mod convert;
mod lex;
mod parse;

pub use convert::si_jl_convert;
use lex::{closing, err, ident, is_punct, items, tokenize, Tok, Token};

use crate::ImportError;
use std::collections::BTreeMap;

/// One model found in a file: where its `@ODEmodel(...)` is, its key and the
/// name and citation its Dict gives, and any parameter values set on it.
#[derive(Clone, Debug)]
pub struct SiJlModel {
    /// The Dict key (`:Goodwin`), the variable it was bound to, or `model_N`.
    pub key: String,
    pub name: Option<String>,
    pub cite: Option<String>,
    /// 1-based line and column of `@ODEmodel`.
    pub line: usize,
    pub col: usize,
    /// Token range of the macro's arguments (inside its parentheses).
    args: (usize, usize),
    /// `set_parameter_values`: name -> value tokens range.
    values: Vec<SetValue>,
    /// A `linear_compartment_model(graph; inputs, outputs, leaks)` call.
    lincomp: Option<Lincomp>,
}

/// One `p => VALUE` of `set_parameter_values`: the name, its place, the value's token range.
type SetValue = (String, (usize, usize), (usize, usize));

/// SI.jl's `linear_compartment_model`: `graph[i]` lists the compartments
/// that compartment i flows into (rate `a_j_i`); leaks `a_0_i`, inputs `u_i`
/// added to `x_i'`, outputs `y_i = x_i` (SI.jl's src/lincomp.jl).
#[derive(Clone, Debug, Default)]
struct Lincomp {
    graph: Vec<Vec<usize>>,
    inputs: Vec<usize>,
    outputs: Vec<usize>,
    leaks: Vec<usize>,
}

/// A Julia vector of integers `[1, 2]` at `toks[open]` (`[`).
fn int_list(toks: &[Token], open: usize, close: usize) -> Result<Vec<usize>, ImportError> {
    let mut out = Vec::new();
    for (a, b) in items(toks, open, close) {
        match (&toks[a].tok, b == a + 1) {
            (Tok::Num(n), true) => out.push(
                n.parse()
                    .map_err(|_| err(&toks[a], format!("'{n}' is not a compartment number")))?,
            ),
            _ => return Err(err(&toks[a], "expected a compartment number")),
        }
    }
    Ok(out)
}

fn lincomp_at(toks: &[Token], k: usize) -> Result<Option<(Lincomp, usize)>, ImportError> {
    if !(ident(toks.get(k)) == Some("linear_compartment_model") && is_punct(toks.get(k + 1), "(")) {
        return Ok(None);
    }
    let close = closing(toks, k + 1)?;
    let mut lc = Lincomp::default();
    for (n, (a, b)) in items(toks, k + 1, close).into_iter().enumerate() {
        if n == 0 {
            if !is_punct(toks.get(a), "[") || closing(toks, a)? + 1 != b {
                return Err(err(&toks[a], "expected the graph, a vector of vectors"));
            }
            for (ia, ib) in items(toks, a, b - 1) {
                if !is_punct(toks.get(ia), "[") || closing(toks, ia)? + 1 != ib {
                    return Err(err(&toks[ia], "expected a vector of compartment numbers"));
                }
                lc.graph.push(int_list(toks, ia, ib - 1)?);
            }
            continue;
        }
        let key = ident(toks.get(a));
        if !(is_punct(toks.get(a + 1), "=") && is_punct(toks.get(a + 2), "[")) {
            return Err(err(
                &toks[a],
                "expected 'inputs = [...]', 'outputs = [...]' or 'leaks = [...]'",
            ));
        }
        let l = int_list(toks, a + 2, b.saturating_sub(1))?;
        match key {
            Some("inputs") => lc.inputs = l,
            Some("outputs") => lc.outputs = l,
            Some("leaks") => lc.leaks = l,
            _ => return Err(err(&toks[a], "expected inputs, outputs or leaks")),
        }
    }
    let n = lc.graph.len();
    for (i, t) in lc
        .graph
        .iter()
        .flatten()
        .chain(&lc.inputs)
        .chain(&lc.outputs)
        .chain(&lc.leaks)
        .map(|i| (*i, &toks[k]))
    {
        if i == 0 || i > n {
            return Err(err(t, format!("compartment {i} is not among 1..{n}")));
        }
    }
    Ok(Some((lc, close + 1)))
}

/// Every model in `text`, in order of appearance. Fails only when the file
/// cannot be tokenized or a model's brackets do not close.
pub fn si_jl_models(text: &str) -> Result<Vec<SiJlModel>, ImportError> {
    let toks = tokenize(text)?;
    let mut out: Vec<SiJlModel> = Vec::new();
    let mut bound: BTreeMap<String, SiJlModel> = BTreeMap::new();
    let mut anon = 0usize;
    let mut i = 0usize;
    // `@ODEmodel(` at k: the model (args range), and the index after it.
    let macro_at = |k: usize| -> Result<Option<(SiJlModel, usize)>, ImportError> {
        if is_punct(toks.get(k), "@")
            && ident(toks.get(k + 1)) == Some("ODEmodel")
            && is_punct(toks.get(k + 2), "(")
        {
            let close = closing(&toks, k + 2)?;
            Ok(Some((
                SiJlModel {
                    key: String::new(),
                    name: None,
                    cite: None,
                    line: toks[k].line,
                    col: toks[k].col,
                    args: (k + 3, close),
                    values: Vec::new(),
                    lincomp: None,
                },
                close + 1,
            )))
        } else {
            Ok(None)
        }
    };
    while i < toks.len() {
        // `:KEY => Dict(` or `NAME[:KEY] = Dict(`
        let dict = if is_punct(toks.get(i), ":")
            && ident(toks.get(i + 1)).is_some()
            && is_punct(toks.get(i + 2), "=>")
            && ident(toks.get(i + 3)) == Some("Dict")
            && is_punct(toks.get(i + 4), "(")
        {
            Some((
                ident(toks.get(i + 1)).unwrap_or_default().to_string(),
                i + 4,
            ))
        } else if ident(toks.get(i)).is_some()
            && is_punct(toks.get(i + 1), "[")
            && is_punct(toks.get(i + 2), ":")
            && ident(toks.get(i + 3)).is_some()
            && is_punct(toks.get(i + 4), "]")
            && is_punct(toks.get(i + 5), "=")
            && ident(toks.get(i + 6)) == Some("Dict")
            && is_punct(toks.get(i + 7), "(")
        {
            Some((
                ident(toks.get(i + 3)).unwrap_or_default().to_string(),
                i + 7,
            ))
        } else {
            None
        };
        if let Some((key, open)) = dict {
            let close = closing(&toks, open)?;
            let (mut name, mut cite, mut model) = (None, None, None);
            for (a, b) in items(&toks, open, close) {
                if !(is_punct(toks.get(a), ":") && is_punct(toks.get(a + 2), "=>")) {
                    continue;
                }
                let v = a + 3;
                match (ident(toks.get(a + 1)), toks.get(v).map(|t| &t.tok)) {
                    (Some("name"), Some(Tok::Str(s))) => name = Some(s.clone()),
                    (Some("cite"), Some(Tok::Str(s))) => cite = Some(s.clone()),
                    (Some("ode"), _) => {
                        if let Some((m, _)) = macro_at(v)? {
                            model = Some(m);
                        } else if let Some((lc, _)) = lincomp_at(&toks, v)? {
                            model = Some(SiJlModel {
                                key: String::new(),
                                name: None,
                                cite: None,
                                line: toks[v].line,
                                col: toks[v].col,
                                args: (v, v),
                                values: Vec::new(),
                                lincomp: Some(lc),
                            });
                        } else if let (Some(var), true) = (ident(toks.get(v)), v + 1 == b) {
                            model = bound.get(var).cloned();
                        }
                    }
                    _ => {}
                }
            }
            if let Some(mut m) = model {
                if cite.as_deref() == Some("") {
                    cite = None;
                }
                m.key = key;
                m.name = name;
                m.cite = cite;
                out.push(m);
                i = close + 1;
                continue;
            }
        }
        // `VAR = @ODEmodel(...)` and `VAR = set_parameter_values(SRC, Dict(...))`
        if let (Some(var), true) = (ident(toks.get(i)), is_punct(toks.get(i + 1), "=")) {
            if let Some((mut m, next)) = macro_at(i + 2)? {
                m.key = var.to_string();
                bound.insert(var.to_string(), m);
                i = next;
                continue;
            }
            if ident(toks.get(i + 2)) == Some("set_parameter_values")
                && is_punct(toks.get(i + 3), "(")
            {
                let close = closing(&toks, i + 3)?;
                let args = items(&toks, i + 3, close);
                if let (Some(&(a0, b0)), Some(&(a1, _))) = (args.first(), args.get(1)) {
                    let src = ident(toks.get(a0)).filter(|_| b0 == a0 + 1);
                    if let (Some(mut m), true, true) = (
                        src.and_then(|s| bound.get(s).cloned()),
                        ident(toks.get(a1)) == Some("Dict"),
                        is_punct(toks.get(a1 + 1), "("),
                    ) {
                        let dclose = closing(&toks, a1 + 1)?;
                        for (a, b) in items(&toks, a1 + 1, dclose) {
                            let Some(p) = ident(toks.get(a)) else {
                                return Err(err(&toks[a], "expected 'parameter => value'"));
                            };
                            if !is_punct(toks.get(a + 1), "=>") || a + 2 >= b {
                                return Err(err(&toks[a], "expected 'parameter => value'"));
                            }
                            m.values
                                .push((p.to_string(), (toks[a].line, toks[a].col), (a + 2, b)));
                        }
                        m.key = var.to_string();
                        bound.insert(var.to_string(), m);
                        i = close + 1;
                        continue;
                    }
                }
            }
        }
        if let Some((mut m, next)) = macro_at(i)? {
            anon += 1;
            m.key = format!("model_{anon}");
            out.push(m);
            i = next;
            continue;
        }
        i += 1;
    }
    // Models bound to a variable and never put in a Dict are models too.
    for (var, mut m) in bound {
        if !out.iter().any(|o| o.args == m.args) {
            m.key = var;
            out.push(m);
        }
    }
    out.sort_by_key(|m| (m.line, m.col, m.key.clone()));
    out.dedup_by(|a, b| a.key == b.key && a.args == b.args);
    Ok(out)
}
