//! How `obsan simulate MODEL.sys` drives a model's known inputs: each input
//! becomes an expression of time substituted into the drift,
//! `f0 + sum_i f_i u_i(t)`, with time the clock state `t' = 1`. RK4 then
//! evaluates every input at its stage times, exactly as it evaluates `t`:
//! `--input u=EXPR` is an expression of `t` (and the model's params and
//! constants); a column of `--inputs FILE.csv` is, on each piece between
//! two rows, `level + slope (t - from)` with the three held as constants
//! set per piece, the integrator stopping at every row's time.

use crate::input_table::InputTable;
use crate::Failure;
use obsan_expr::{parse_ast, Ctx, Id, ParseError, Span};
use obsan_fit::Predictor;
use obsan_model::{NormalForm, TIME};

/// The constant holding the start of the current piece (a name no `.sys`
/// file can declare, so it never meets a user's).
const FROM: &str = "@from";

/// The drive of one simulation, after [`drive`] rewrote the normal form.
pub struct Drive {
    /// The clock's index among the dynamic states.
    pub clock: usize,
    table: Option<InputTable>,
    /// Per table column used: its column and the constants `level`, `slope`.
    columns: Vec<(usize, String, String)>,
    /// The inputs given no value.
    pub missing: Vec<String>,
}

/// Index in `state` of a clock `t' = 1`, appended after the dynamic states
/// when the model has none (the normal form adds it when the model uses
/// `t`, with its known output, which simulating does not print).
fn ensure_clock(nf: &mut NormalForm) -> usize {
    if let Some(k) = nf.clock() {
        nf.outputs.retain(|o| o.0 != TIME);
        return k;
    }
    let t = nf.ctx.symbol(TIME);
    let (zero, one) = (nf.ctx.int(0), nf.ctx.int(1));
    let k = nf.n_dynamic;
    nf.state.insert(k, TIME.to_string());
    nf.state_vars.insert(k, t.var);
    nf.f0.insert(k, one);
    for f in nf.fields.iter_mut().chain(nf.unknown_fields.iter_mut()) {
        f.insert(k, zero);
    }
    nf.n_dynamic += 1;
    if let Some(d) = nf.delay.as_mut() {
        *d += 1;
    }
    k
}

/// `--input NAME=EXPR` as an expression in `nf.ctx`: `t`, numbers, the
/// model's params and constants; anything else is refused with its column.
fn input_expr(nf: &mut NormalForm, flag: &str, text: &str, at: usize) -> Result<Id, Failure> {
    let located = |e: ParseError| {
        let col = flag[..(at + e.span.start).min(flag.len())].chars().count() + 1;
        let width = flag[(at + e.span.start).min(flag.len())..(at + e.span.end).min(flag.len())]
            .chars()
            .count()
            .max(1);
        Failure(format!(
            "--input {flag}: column {col}: {}\n  |\n  | {flag}\n  | {}{}",
            e.message,
            " ".repeat(col - 1),
            "^".repeat(width)
        ))
    };
    let ast = parse_ast(text).map_err(located)?;
    let params: Vec<String> = nf.state[nf.n_dynamic..].to_vec();
    let consts = nf.consts.clone();
    let mut resolve = |ctx: &mut Ctx, name: &str, span: Span| -> Result<Id, ParseError> {
        if let Some((_, v)) = consts.iter().find(|c| c.0 == name) {
            return Ok(match v {
                Some(q) => ctx.num(q.clone()),
                None => ctx.symbol(name).id,
            });
        }
        if name == TIME || params.iter().any(|p| p == name) {
            return Ok(ctx.symbol(name).id);
        }
        Err(ParseError::new(
            format!(
                "'{name}' is not t, a param or a constant of the model (an input is a finite \
                 number or an expression of t)"
            ),
            span,
        ))
    };
    nf.ctx.build(&ast, &mut resolve).map_err(located)
}

/// Rewrite `nf` so that its known inputs are driven as `flags` (each
/// `NAME=EXPR`, the last for a name wins) and `table` say; an input in both
/// is refused, one in neither is listed in [`Drive::missing`].
pub fn drive(
    nf: &mut NormalForm,
    flags: &[String],
    table: Option<InputTable>,
) -> Result<Drive, Failure> {
    let clock = ensure_clock(nf);
    let n = nf.inputs.len();
    let mut value: Vec<Option<Id>> = vec![None; n];
    let mut varying = false;
    for flag in flags {
        let Some((name, text)) = flag.split_once('=') else {
            return Err(Failure(format!(
                "--input {flag}: expected NAME=VALUE or NAME=EXPR"
            )));
        };
        let name = name.trim();
        let Some(i) = nf.inputs.iter().position(|u| u == name) else {
            return Err(Failure(format!(
                "--input {flag}: the model has no input '{name}'"
            )));
        };
        // A later --input wins, as a later --set does.
        let e = input_expr(nf, flag, text, flag.len() - text.len())?;
        varying |= parse_ast(text).is_ok_and(|a| a.idents().iter().any(|(n, _)| *n == TIME));
        value[i] = Some(e);
    }
    let mut columns = Vec::new();
    if let Some(tb) = &table {
        let t = nf.ctx.symbol(TIME).id;
        let from = nf.ctx.symbol(FROM).id;
        nf.consts.push((FROM.to_string(), None));
        for (c, name) in tb.names.iter().enumerate() {
            let here = format!("{}:{}:{}", tb.file, tb.header_line, tb.name_cols[c]);
            let Some(i) = nf.inputs.iter().position(|u| u == name) else {
                return Err(Failure(format!(
                    "{here}: the model has no input '{name}' (its inputs: {})",
                    nf.inputs.join(", ")
                )));
            };
            if value[i].is_some() {
                return Err(Failure(format!(
                    "{here}: input '{name}' is also given by --input"
                )));
            }
            let (level, slope) = (format!("{name}@level"), format!("{name}@slope"));
            let l = nf.ctx.symbol(&level).id;
            let s = nf.ctx.symbol(&slope).id;
            nf.consts.push((level.clone(), None));
            nf.consts.push((slope.clone(), None));
            let since = nf.ctx.sub(t, from);
            let ramp = nf.ctx.mul(&[s, since]);
            value[i] = Some(nf.ctx.add(&[l, ramp]));
            columns.push((c, level, slope));
            varying = true;
        }
    }
    // Reported with the missing values of the states and params (`start`).
    let missing: Vec<String> = (0..n)
        .filter(|&i| value[i].is_none())
        .map(|i| nf.inputs[i].clone())
        .collect();
    let zero = nf.ctx.int(0);
    if varying && nf.delay.is_some() {
        return Err(Failure(
            "the model delays its inputs (`delay`): simulating it takes constant inputs only"
                .into(),
        ));
    }
    substitute(
        nf,
        &value
            .into_iter()
            .map(|v| v.unwrap_or(zero))
            .collect::<Vec<Id>>(),
    )?;
    Ok(Drive {
        clock,
        table,
        columns,
        missing,
    })
}

/// `f0 += sum_i f_i u_i`, and `u_i(t)` in the outputs that read inputs
/// (`h(x, u(t))`, the input at each output time); then the model has no
/// known inputs left.
fn substitute(nf: &mut NormalForm, value: &[Id]) -> Result<(), Failure> {
    for k in 0..nf.f0.len() {
        let mut terms = vec![nf.f0[k]];
        for (f, &u) in nf.fields.iter().zip(value) {
            terms.push(nf.ctx.mul(&[f[k], u]));
        }
        nf.f0[k] = nf.ctx.add(&terms);
    }
    let map: Vec<_> = nf
        .input_vars
        .iter()
        .copied()
        .zip(value.iter().copied())
        .collect();
    for o in nf.outputs.iter_mut() {
        o.1 = nf
            .ctx
            .substitute(o.1, &map)
            .map_err(|e| Failure(format!("output {}: {}", o.0, e.0)))?;
    }
    nf.inputs.clear();
    nf.input_vars.clear();
    nf.fields.clear();
    Ok(())
}

impl Drive {
    /// `true` for a constant this module added (the caller gives it no value).
    pub fn is_internal(name: &str) -> bool {
        name.contains('@')
    }

    /// The times the integrator must stop at besides the output times.
    pub fn breakpoints(&self, until: f64) -> Result<Vec<f64>, Failure> {
        match &self.table {
            None => Ok(Vec::new()),
            Some(t) => {
                t.check_covers(until)?;
                Ok(t.breakpoints(until))
            }
        }
    }

    /// Set the table's constants in `consts` (the predictor's order) for the
    /// step `[t0, t1]`, which lies inside one piece.
    pub fn set_piece(&self, p: &Predictor, consts: &mut [f64], t0: f64, t1: f64) {
        let Some(tb) = &self.table else { return };
        let at = |n: &str| p.consts.iter().position(|c| c == n);
        let piece = tb.piece(t0, t1);
        if let Some(k) = at(FROM) {
            consts[k] = t0;
        }
        for (c, level, slope) in &self.columns {
            if let (Some(a), Some(b)) = (at(level), at(slope)) {
                consts[a] = piece[*c].0;
                consts[b] = piece[*c].1;
            }
        }
    }
}
