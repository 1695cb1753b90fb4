//! The dataset format (docs/data-format.md), as text in and text out: the
//! binary does the file I/O. Every rejection names the file, the row and the
//! column.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;

/// A rejected file, with the place.
#[derive(Clone, Debug, PartialEq)]
pub struct DataError {
    pub file: String,
    /// 1-based line number in the file (the header is line 1).
    pub row: Option<usize>,
    pub column: Option<String>,
    pub message: String,
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(r) = self.row {
            write!(f, ":{r}")?;
        }
        if let Some(c) = &self.column {
            write!(f, " (column {c})")?;
        }
        write!(f, ": {}", self.message)
    }
}
impl std::error::Error for DataError {}

/// A time series: a time column and named value columns (`None` = not measured).
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub columns: Vec<String>,
    pub t: Vec<f64>,
    /// `values[c][k]`: column c at row k.
    pub values: Vec<Vec<Option<f64>>>,
}

impl Series {
    pub fn new(columns: Vec<String>) -> Series {
        let n = columns.len();
        Series {
            columns,
            t: Vec::new(),
            values: vec![Vec::new(); n],
        }
    }
    pub fn push(&mut self, t: f64, row: &[Option<f64>]) {
        self.t.push(t);
        for (c, v) in self.values.iter_mut().zip(row) {
            c.push(*v);
        }
    }
    pub fn len(&self) -> usize {
        self.t.len()
    }
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    pub fn column(&self, name: &str) -> Option<&[Option<f64>]> {
        self.columns
            .iter()
            .position(|c| c == name)
            .map(|i| self.values[i].as_slice())
    }

    /// CSV text: header `t,<columns>`, full precision, empty cells for `None`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t");
        for c in &self.columns {
            s.push(',');
            s.push_str(c);
        }
        s.push('\n');
        for k in 0..self.t.len() {
            s.push_str(&format!("{}", self.t[k]));
            for c in &self.values {
                s.push(',');
                if let Some(v) = c[k] {
                    s.push_str(&format!("{v}"));
                }
            }
            s.push('\n');
        }
        s
    }

    /// Parse CSV text. `required` columns must be present (others are kept);
    /// empty cells are allowed only if `allow_empty`.
    pub fn parse_csv(
        text: &str,
        file: &str,
        required: &[&str],
        allow_empty: bool,
    ) -> Result<Series, DataError> {
        let err = |row: Option<usize>, column: Option<String>, message: String| DataError {
            file: file.to_string(),
            row,
            column,
            message,
        };
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((_, header)) = lines.next() else {
            return Err(err(
                None,
                None,
                "the file is empty: expected a header line t,...".into(),
            ));
        };
        let cols: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        if cols.first().map(String::as_str) != Some("t") {
            return Err(err(
                Some(1),
                None,
                format!(
                    "the first column must be 't', found '{}'",
                    cols.first().map_or("", |s| s.as_str())
                ),
            ));
        }
        for (i, c) in cols.iter().enumerate() {
            if c.is_empty() {
                return Err(err(
                    Some(1),
                    None,
                    format!("column {} of the header has no name", i + 1),
                ));
            }
            if cols[..i].contains(c) {
                return Err(err(
                    Some(1),
                    Some(c.clone()),
                    "this column appears twice".into(),
                ));
            }
        }
        for r in required {
            if !cols.iter().any(|c| c == r) {
                return Err(err(
                    Some(1),
                    Some(r.to_string()),
                    format!("missing column '{r}' (the header is '{header}')"),
                ));
            }
        }
        let mut s = Series::new(cols[1..].to_vec());
        for (i, line) in lines {
            let row = i + 1;
            let cells: Vec<&str> = line.split(',').map(|c| c.trim()).collect();
            if cells.len() != cols.len() {
                return Err(err(
                    Some(row),
                    None,
                    format!("{} fields, the header has {}", cells.len(), cols.len()),
                ));
            }
            let mut vals = Vec::with_capacity(cols.len() - 1);
            let mut t = 0.0;
            for (j, cell) in cells.iter().enumerate() {
                let v = if cell.is_empty() {
                    if j == 0 || !allow_empty {
                        return Err(err(Some(row), Some(cols[j].clone()), "empty value".into()));
                    }
                    None
                } else {
                    match cell.parse::<f64>() {
                        Ok(x) if x.is_finite() => Some(x),
                        Ok(_) => {
                            return Err(err(
                                Some(row),
                                Some(cols[j].clone()),
                                format!("'{cell}' is not a finite number"),
                            ))
                        }
                        Err(_) => {
                            return Err(err(
                                Some(row),
                                Some(cols[j].clone()),
                                format!("'{cell}' is not a number"),
                            ))
                        }
                    }
                };
                if j == 0 {
                    t = v.expect("t present");
                } else {
                    vals.push(v);
                }
            }
            if let Some(&prev) = s.t.last() {
                if t < prev {
                    return Err(err(
                        Some(row),
                        Some("t".into()),
                        format!("time goes backwards: {t} after {prev}"),
                    ));
                }
            }
            s.push(t, &vals);
        }
        Ok(s)
    }
}

/// `dataset.json`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DatasetMeta {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// Nominal values (e.g. wheel radii) known before calibration.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub nominal: BTreeMap<String, f64>,
    /// One metric measurement: the initial distance to the feature (section V-C).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d0: Option<f64>,
    /// Noise levels of the sensors, when known (e.g. "beta": 0.01745).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub noise: BTreeMap<String, f64>,
}

/// One trajectory: its inputs, outputs and known constants (`meta.json`).
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    pub name: String,
    pub inputs: Series,
    pub outputs: Series,
    pub meta: BTreeMap<String, f64>,
}

/// The fewest output samples a trajectory may have.
pub const MIN_OUTPUT_SAMPLES: usize = 10;

impl Trajectory {
    /// Check a trajectory read from files named in `origin`.
    pub fn check(&self, origin: &str) -> Result<(), DataError> {
        let measured = self
            .outputs
            .values
            .iter()
            .map(|c| c.iter().filter(|v| v.is_some()).count())
            .sum::<usize>();
        if measured < MIN_OUTPUT_SAMPLES {
            return Err(DataError {
                file: format!("{origin}/outputs.csv"),
                row: None,
                column: None,
                message: format!("only {measured} output samples: a trajectory needs at least {MIN_OUTPUT_SAMPLES}"),
            });
        }
        if self.inputs.len() < 2 {
            return Err(DataError {
                file: format!("{origin}/inputs.csv"),
                row: None,
                column: None,
                message: "fewer than 2 input rows".into(),
            });
        }
        Ok(())
    }
}

/// A dataset: metadata and trajectories (in name order).
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    pub meta: DatasetMeta,
    pub trajectories: Vec<Trajectory>,
}

/// Add a model's derived inputs (`input dwR = rate(wR)`, see
/// docs/sys-format.md) to `series` as columns computed from the measured
/// ones. `rate(u)` on row k is `(u[k+1] - u[k]) / (t[k+1] - t[k])` (0 on the
/// last row), so its integral over any rows telescopes exactly to the change
/// of `u`; other definitions are evaluated row by row, with `consts` known.
/// A column already present (measured) is kept.
pub fn add_derived_inputs(
    series: &mut Series,
    derived: &[(String, String)],
    consts: &BTreeMap<String, f64>,
) -> Result<(), String> {
    for (name, def) in derived {
        if series.columns.iter().any(|c| c == name) {
            continue;
        }
        let def = def.trim();
        let col: Vec<Option<f64>> = if let Some(inner) =
            def.strip_prefix("rate(").and_then(|r| r.strip_suffix(')'))
        {
            let src = series.column(inner.trim()).ok_or_else(|| {
                format!(
                    "derived input {name} = {def}: no input column '{}'",
                    inner.trim()
                )
            })?;
            let n = series.t.len();
            (0..n)
                .map(|k| {
                    if k + 1 >= n {
                        return Some(0.0);
                    }
                    let dt = series.t[k + 1] - series.t[k];
                    match (src[k], src[k + 1]) {
                        (Some(a), Some(b)) if dt > 0.0 => Some((b - a) / dt),
                        _ => Some(0.0),
                    }
                })
                .collect()
        } else {
            // Evaluated in floating point from the syntax tree (not the exact
            // engine): `sqrt(x^2)` is |x| here, which is what a derivation wants.
            let ast = obsan_expr::parse_ast(def)
                .map_err(|e| format!("derived input {name} = {def}: {}", e.message))?;
            let mut names: Vec<String> = Vec::new();
            for (n, _) in ast.idents() {
                if !names.iter().any(|x| x == n) {
                    names.push(n.to_string());
                }
            }
            enum Src<'a> {
                Col(&'a [Option<f64>]),
                Const(f64),
            }
            let srcs: Vec<Src> = names
                .iter()
                .map(|n| match series.column(n) {
                    Some(c) => Ok(Src::Col(c)),
                    None => consts
                        .get(n)
                        .map(|v| Src::Const(*v))
                        .ok_or_else(|| format!("derived input {name} = {def}: '{n}' is neither an input column nor a known constant")),
                })
                .collect::<Result<_, String>>()?;
            let mut x = vec![0.0; names.len()];
            (0..series.t.len())
                .map(|k| {
                    for (xi, s) in x.iter_mut().zip(&srcs) {
                        *xi = match s {
                            Src::Col(c) => c[k]?,
                            Src::Const(v) => *v,
                        };
                    }
                    let v = eval_ast(&ast, &names, &x);
                    v.is_finite().then_some(v)
                })
                .collect()
        };
        series.columns.push(name.clone());
        series.values.push(col);
    }
    Ok(())
}

fn eval_ast(a: &obsan_expr::Ast, names: &[String], x: &[f64]) -> f64 {
    use obsan_expr::{AstKind, BinOp};
    let ev = |b: &obsan_expr::Ast| eval_ast(b, names, x);
    match &a.kind {
        AstKind::Num(q) => q.to_f64(),
        AstKind::Pi => std::f64::consts::PI,
        AstKind::Ident(n) => names.iter().position(|m| m == n).map_or(f64::NAN, |i| x[i]),
        AstKind::Neg(b) => -ev(b),
        AstKind::Bin(op, l, r) => {
            let (l, r) = (ev(l), ev(r));
            match op {
                BinOp::Add => l + r,
                BinOp::Sub => l - r,
                BinOp::Mul => l * r,
                BinOp::Div => l / r,
                BinOp::Pow => l.powf(r),
            }
        }
        AstKind::Call(f, args) => {
            let v: Vec<f64> = args.iter().map(ev).collect();
            match (f.as_str(), v.as_slice()) {
                ("sin", [a]) => a.sin(),
                ("cos", [a]) => a.cos(),
                ("tan", [a]) => a.tan(),
                ("atan", [a]) => a.atan(),
                ("atan2", [y, x]) => y.atan2(*x),
                ("exp", [a]) => a.exp(),
                ("log", [a]) => a.ln(),
                ("sqrt", [a]) => a.sqrt(),
                _ => f64::NAN,
            }
        }
    }
}
