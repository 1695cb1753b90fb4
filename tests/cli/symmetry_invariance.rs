//! Every symmetry `obsan symmetries` prints is checked here by the test's own
//! arithmetic, not the engine's: the `.sys` text is read by a small reader
//! below, each expression is parsed to a syntax tree (`parse_ast`, syntax only)
//! and evaluated with forward-mode dual numbers written here. At random points,
//! with `W` the span of the printed vectors and the free directions `d/dx`:
//!
//! - every output is invariant along each of them: `grad h . w = 0`;
//! - `W` is invariant under the dynamics: `[w, f] = Dw f - Df w` lies in `W`,
//!   with `f` the whole field `f0 + sum_i f_i u_i` at several random input
//!   values (the bracket is linear in `u`, so the drift and every input field
//!   are covered).
//!
//! Together these say `W` lies in the kernel of the observable codistribution
//! (it contains every `dh` and is closed under Lie derivatives along the
//! fields): moving along `W` changes no output, the paper's continuous
//! symmetries (Section III). A single vector need not commute with `f` (SEIR's
//! `d/dR` has `[d/dR, f] = -mu d/dR`); the span must be kept. The vectors must
//! also be independent at a random point, and their number must be `n - rank`.

use crate::util::obsan;
use obsan_expr::{parse_ast, Ast, AstKind, BinOp, SplitMix};
use serde_json::Value;
use std::collections::HashMap;

/// Relative size of a residual, against the sum of the magnitudes of its
/// terms, that counts as zero: the expressions take at most a few hundred
/// floating-point operations, each adding a relative error of about 1e-16, so
/// a true zero lands many orders below this; a wrong vector leaves a residual
/// of the order of its terms.
const ZERO_REL: f64 = 1e-8;
/// Pivot, relative to the largest entry, below which vectors count as dependent.
const PIVOT_REL: f64 = 1e-9;
/// Random points per system (a point where something is not finite is skipped).
const POINTS: usize = 4;

/// A value with its gradient in the analysed variables.
#[derive(Clone, Debug)]
struct D {
    v: f64,
    g: Vec<f64>,
}

impl D {
    fn c(v: f64, n: usize) -> D {
        D { v, g: vec![0.0; n] }
    }
    /// `f(self)` with `f'(self.v) = d`.
    fn chain(&self, v: f64, d: f64) -> D {
        D {
            v,
            g: self.g.iter().map(|x| x * d).collect(),
        }
    }
    fn lin(&self, a: f64, o: &D, b: f64, v: f64) -> D {
        D {
            v,
            g: self
                .g
                .iter()
                .zip(&o.g)
                .map(|(x, y)| a * x + b * y)
                .collect(),
        }
    }
}

/// Evaluates a syntax tree at `vals` (name -> value with gradient).
fn eval(a: &Ast, vals: &HashMap<String, D>, n: usize) -> D {
    match &a.kind {
        AstKind::Num(q) => D::c(q.to_f64(), n),
        AstKind::Pi => D::c(std::f64::consts::PI, n),
        AstKind::Ident(s) => vals
            .get(s)
            .cloned()
            .unwrap_or_else(|| panic!("no value for {s}")),
        AstKind::Neg(x) => {
            let x = eval(x, vals, n);
            x.chain(-x.v, -1.0)
        }
        AstKind::Bin(op, l, r) => {
            let (x, y) = (eval(l, vals, n), eval(r, vals, n));
            match op {
                BinOp::Add => x.lin(1.0, &y, 1.0, x.v + y.v),
                BinOp::Sub => x.lin(1.0, &y, -1.0, x.v - y.v),
                BinOp::Mul => x.lin(y.v, &y, x.v, x.v * y.v),
                BinOp::Div => x.lin(1.0 / y.v, &y, -x.v / (y.v * y.v), x.v / y.v),
                BinOp::Pow => {
                    let int = y.g.iter().all(|g| *g == 0.0) && y.v.fract() == 0.0;
                    if int {
                        let k = y.v as i32;
                        x.chain(x.v.powi(k), k as f64 * x.v.powi(k - 1))
                    } else {
                        // x^y = exp(y log x), on x > 0.
                        let p = x.v.powf(y.v);
                        x.lin(y.v * x.v.powf(y.v - 1.0), &y, p * x.v.ln(), p)
                    }
                }
            }
        }
        AstKind::Call(f, args) => {
            let x = eval(&args[0], vals, n);
            match f.as_str() {
                "sin" => x.chain(x.v.sin(), x.v.cos()),
                "cos" => x.chain(x.v.cos(), -x.v.sin()),
                "tan" => x.chain(x.v.tan(), 1.0 + x.v.tan().powi(2)),
                "atan" => x.chain(x.v.atan(), 1.0 / (1.0 + x.v * x.v)),
                "exp" => x.chain(x.v.exp(), x.v.exp()),
                "log" => x.chain(x.v.ln(), 1.0 / x.v),
                "sqrt" => x.chain(x.v.sqrt(), 0.5 / x.v.sqrt()),
                "atan2" => {
                    // atan2(y, x): d = (x dy - y dx) / (x^2 + y^2).
                    let (y, xx) = (x, eval(&args[1], vals, n));
                    let r2 = xx.v * xx.v + y.v * y.v;
                    y.lin(xx.v / r2, &xx, -y.v / r2, y.v.atan2(xx.v))
                }
                other => panic!("function {other} unknown to the test's evaluator"),
            }
        }
    }
}

/// A `.sys` model as this test reads it.
#[derive(Default)]
struct Model {
    state: Vec<String>,
    params: Vec<String>,
    consts: Vec<String>,
    inputs: Vec<String>,
    fields: HashMap<String, Ast>,
    outputs: Vec<Ast>,
    /// restriction name -> (input, expression in new inputs and consts).
    restricts: HashMap<String, Vec<(String, Ast)>>,
}

fn names(s: &str) -> Vec<String> {
    s.split(',').map(|x| x.trim().to_string()).collect()
}

/// Reads the statements the shipped systems use; a line that starts with
/// white space continues the previous statement.
fn read_sys(text: &str) -> Model {
    let mut stmts: Vec<String> = Vec::new();
    for raw in text.lines() {
        let line = raw.split('#').next().unwrap();
        if line.trim().is_empty() {
            continue;
        }
        if line.starts_with([' ', '\t']) && !stmts.is_empty() {
            stmts.last_mut().unwrap().push_str(line);
        } else {
            stmts.push(line.to_string());
        }
    }
    let mut m = Model::default();
    let ast = |s: &str| parse_ast(s.trim()).unwrap_or_else(|e| panic!("{s}: {e:?}"));
    for s in stmts {
        let (kw, rest) = s.split_once(char::is_whitespace).unwrap_or((&s, ""));
        match kw {
            "system" | "description" => {}
            "state" => m.state.extend(names(rest)),
            "param" => m.params.extend(names(rest)),
            "const" => m.consts.extend(names(rest)),
            "input" => m.inputs.extend(names(rest)),
            "output" => m.outputs.push(ast(rest.split_once('=').unwrap().1)),
            "restrict" => {
                let (name, eqs) = rest.split_once(':').unwrap();
                let subs = eqs
                    .split(',')
                    .map(|e| {
                        let (u, x) = e.split_once('=').unwrap();
                        (u.trim().to_string(), ast(x))
                    })
                    .collect();
                m.restricts.insert(name.trim().to_string(), subs);
            }
            _ => {
                let (lhs, rhs) = s.split_once('=').expect("an equation");
                let x = lhs.trim().strip_suffix('\'').expect("x' = ...").trim();
                m.fields.insert(x.to_string(), ast(rhs));
            }
        }
    }
    m
}

fn text_of(v: &Value) -> &str {
    v["text"].as_str().expect("a component's text")
}

/// Runs `obsan symmetries` and checks every vector as the module doc says.
/// Returns the number of directions checked.
fn check_system(path: &str, input: Option<&str>, seed: u64) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    let m = read_sys(&text);
    let mut args = vec!["symmetries", path, "--json"];
    if let Some(q) = input {
        args.extend(["--input", q]);
    }
    let r = obsan(&args);
    assert_eq!(r.code, 0, "{path}: {}{}", r.stdout, r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    let vars: Vec<String> = v["state"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect();
    let all: Vec<String> = m.state.iter().chain(&m.params).cloned().collect();
    assert_eq!(
        {
            let mut a = vars.clone();
            a.sort();
            a
        },
        {
            let mut a = all.clone();
            a.sort();
            a
        },
        "{path}: the analysed variables are the states and params"
    );
    let n = vars.len();
    // The directions: printed vectors, then each free direction d/dx.
    let mut dirs: Vec<Vec<Ast>> = Vec::new();
    for w in v["symmetries"].as_array().unwrap() {
        dirs.push(
            vars.iter()
                .map(|x| parse_ast(w.get(x).map(text_of).unwrap_or("0")).unwrap())
                .collect(),
        );
    }
    for x in v["free_directions"].as_array().unwrap() {
        let x = x.as_str().unwrap();
        dirs.push(
            vars.iter()
                .map(|y| parse_ast(if y == x { "1" } else { "0" }).unwrap())
                .collect(),
        );
    }
    let rank = v["rank"].as_u64().unwrap() as usize;
    assert_eq!(
        dirs.len(),
        n - rank,
        "{path}: {} directions for n - rank = {}",
        dirs.len(),
        n - rank
    );
    // The inputs the fields see: a restriction's expressions, or the inputs.
    let subs: Vec<(String, Ast)> = match input {
        Some(q) => m.restricts[q].clone(),
        None => m
            .inputs
            .iter()
            .map(|u| (u.clone(), parse_ast(u).unwrap()))
            .collect(),
    };
    let mut rng = SplitMix(seed);
    let mut uniform =
        |lo: f64, hi: f64| lo + (hi - lo) * (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut checked_points = 0;
    for _ in 0..POINTS {
        // Variables carry their unit gradient; consts and inputs none.
        let mut vals: HashMap<String, D> = HashMap::new();
        for (i, x) in vars.iter().enumerate() {
            let mut d = D::c(uniform(0.3, 1.3), n);
            d.g[i] = 1.0;
            vals.insert(x.clone(), d);
        }
        for c in &m.consts {
            vals.insert(c.clone(), D::c(uniform(0.3, 1.3), n));
        }
        let comps: Vec<Vec<D>> = dirs
            .iter()
            .map(|w| w.iter().map(|a| eval(a, &vals, n)).collect())
            .collect();
        let outs: Vec<D> = m.outputs.iter().map(|h| eval(h, &vals, n)).collect();
        let finite = |d: &D| d.v.is_finite() && d.g.iter().all(|x| x.is_finite());
        if !comps.iter().flatten().chain(&outs).all(finite) {
            continue;
        }
        // Independence of the directions at this point.
        let mut mat: Vec<Vec<f64>> = comps
            .iter()
            .map(|w| w.iter().map(|c| c.v).collect())
            .collect();
        assert_eq!(
            numeric_rank(&mut mat),
            dirs.len(),
            "{path}: dependent directions"
        );
        for (k, w) in comps.iter().enumerate() {
            for (j, h) in outs.iter().enumerate() {
                let terms: Vec<f64> = (0..n).map(|i| h.g[i] * w[i].v).collect();
                assert_zero(&terms, || {
                    format!("{path}: output {j} not invariant along direction {k}")
                });
            }
        }
        // The whole field at a few random input values (more draws than
        // inputs, so the drift and each input field are all exercised).
        for _ in 0..subs.len() + 2 {
            let mut uvals = vals.clone();
            let new_inputs: Vec<String> = subs
                .iter()
                .flat_map(|(_, a)| a.idents().into_iter().map(|(s, _)| s.to_string()))
                .filter(|s| !vals.contains_key(s))
                .collect();
            for s in new_inputs {
                let u = uniform(-1.0, 1.0);
                uvals.insert(s, D::c(u, n));
            }
            let mut ivals = vals.clone();
            for (u, a) in &subs {
                let x = eval(a, &uvals, n);
                ivals.insert(u.clone(), D::c(x.v, n));
            }
            for u in &m.inputs {
                ivals.entry(u.clone()).or_insert_with(|| D::c(0.0, n));
            }
            let f: Vec<D> = vars
                .iter()
                .map(|x| match m.fields.get(x) {
                    Some(a) => eval(a, &ivals, n),
                    None => D::c(0.0, n),
                })
                .collect();
            if !f.iter().all(finite) {
                continue;
            }
            let basis = orthonormal(
                &comps
                    .iter()
                    .map(|w| w.iter().map(|c| c.v).collect())
                    .collect::<Vec<Vec<f64>>>(),
            );
            for (k, w) in comps.iter().enumerate() {
                // [w, f]_i = sum_j (dw_i/dx_j f_j - df_i/dx_j w_j), with the
                // size of its terms per component.
                let (b, scale): (Vec<f64>, Vec<f64>) = (0..n)
                    .map(|i| {
                        let t: Vec<f64> = (0..n)
                            .flat_map(|j| [w[i].g[j] * f[j].v, -f[i].g[j] * w[j].v])
                            .collect();
                        (
                            t.iter().sum::<f64>(),
                            t.iter().map(|x| x.abs()).sum::<f64>(),
                        )
                    })
                    .unzip();
                let r = outside(&basis, &b);
                let size = scale.iter().fold(0f64, |a, x| a.max(*x));
                for i in 0..n {
                    assert!(
                        r[i].abs() <= ZERO_REL * size,
                        "{path}: [w{k}, f] leaves the symmetries' span in {} by {:e} (terms of size {size:e})",
                        vars[i],
                        r[i]
                    );
                }
            }
        }
        checked_points += 1;
    }
    assert!(
        checked_points >= POINTS / 2,
        "{path}: only {checked_points} usable points"
    );
    dirs.len()
}

fn assert_zero(terms: &[f64], what: impl Fn() -> String) {
    let sum: f64 = terms.iter().sum();
    let scale: f64 = terms.iter().map(|t| t.abs()).sum();
    assert!(
        sum.abs() <= ZERO_REL * scale,
        "{}: residual {sum:e} against terms of size {scale:e}",
        what()
    );
}

/// An orthonormal basis of the rows' span (modified Gram-Schmidt; the rows
/// are independent, checked before).
fn orthonormal(rows: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out: Vec<Vec<f64>> = Vec::new();
    for r in rows {
        let mut v = r.clone();
        for e in &out {
            let d: f64 = v.iter().zip(e).map(|(a, b)| a * b).sum();
            v.iter_mut().zip(e).for_each(|(a, b)| *a -= d * b);
        }
        let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        out.push(v.iter().map(|a| a / norm).collect());
    }
    out
}

/// The part of `b` outside the span of the orthonormal `basis`.
fn outside(basis: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let mut r = b.to_vec();
    for e in basis {
        let d: f64 = r.iter().zip(e).map(|(a, b)| a * b).sum();
        r.iter_mut().zip(e).for_each(|(a, b)| *a -= d * b);
    }
    r
}

/// Rank by Gaussian elimination with partial pivoting (the rows are few).
fn numeric_rank(m: &mut [Vec<f64>]) -> usize {
    let big = m.iter().flatten().fold(0f64, |a, x| a.max(x.abs()));
    if m.is_empty() || big == 0.0 {
        return 0;
    }
    let cols = m[0].len();
    let mut rank = 0;
    for c in 0..cols {
        let Some(p) = (rank..m.len()).max_by(|&a, &b| m[a][c].abs().total_cmp(&m[b][c].abs()))
        else {
            break;
        };
        if m[p][c].abs() <= PIVOT_REL * big {
            continue;
        }
        m.swap(rank, p);
        let pivot = m[rank].clone();
        for row in m.iter_mut().skip(rank + 1) {
            let t = row[c] / pivot[c];
            for (x, p) in row[c..].iter_mut().zip(&pivot[c..]) {
                *x -= t * p;
            }
        }
        rank += 1;
    }
    rank
}

fn sys_files(dir: &str) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path().to_string_lossy().into_owned())
        .filter(|p| p.ends_with(".sys"))
        .collect();
    v.sort();
    v
}

fn root(p: &str) -> String {
    format!("{}/{p}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn every_printed_symmetry_of_the_shipped_systems_is_one_by_the_tests_own_arithmetic() {
    let mut with = 0;
    for dir in ["systems", "systems/classic", "systems/benchmarks"] {
        for (i, path) in sys_files(&root(dir)).iter().enumerate() {
            if check_system(path, None, 1000 + i as u64) > 0 {
                with += 1;
            }
        }
    }
    // The paper's systems alone (eq. 3 localization, the psi system, vins)
    // have symmetries, so an empty answer everywhere must fail.
    assert!(with >= 10, "only {with} systems had a symmetry to check");
}

#[test]
fn the_calibration_system_on_circles_has_checked_symmetries() {
    // Under q (wR = nu, wL = q nu) the calibration is not identifiable
    // from one circle (the paper, Section V): a symmetry must be printed.
    let n = check_system(&root("systems/calib.sys"), Some("q"), 7);
    assert!(n >= 1, "no symmetry under q");
}

/// Regression (session 30): the Monod community with one output has a basis
/// of order 25, whose random certificate built graphs of gigabytes and timed
/// out; its symmetries were then proven by the span certificate, and since
/// session 31 (enough random points for the cheap route's candidates) by
/// invariance: its 7 symmetries are translations and scalings. Either way
/// exact; they must still pass this file's own arithmetic (outputs
/// invariant, span invariant under the fields, independent, n - rank of
/// them), with the rank of the file's independent symident verdict (27 of 34).
/// The span certificate itself is exercised on SI.jl's SEAIJRC (its basis of
/// order >= 10 is no cheap structure), rank 13 of 14 by the file's verdict
/// from SI.jl's identifiable functions.
#[test]
fn a_deep_monod_community_gets_span_certified_symmetries() {
    let path = root("systems/benchmarks/strike-goldd/msmi_2x2m_hx1.sys");
    let r = obsan(&["symmetries", &path, "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["certificate"], "invariance", "{}", r.stdout);
    assert_eq!(v["exact"], true);
    assert_eq!(v["rank"], 27);
    assert_eq!(check_system(&path, None, 30), 34 - 27);
    let path = root("systems/benchmarks/si-jl/SEAIJRC.sys");
    let r = obsan(&["symmetries", &path, "--json"]);
    assert_eq!(r.code, 0, "{}", r.stderr);
    let v: Value = serde_json::from_str(&r.stdout).unwrap();
    assert_eq!(v["certificate"], "span", "{}", r.stdout);
    assert_eq!(v["exact"], true);
    assert_eq!(v["rank"], 13);
    assert_eq!(check_system(&path, None, 31), 14 - 13);
}
