//! PEtab v1 problems (the YAML file, its SBML model and its tables) to one
//! `.sys`: the structural question the problem asks. The model's equations
//! come from the SBML reader; the observables' formulas are the outputs; the
//! parameter table says which parameters are estimated (`param`) and which
//! are fixed (`const p = nominalValue`); SBML parameters the table does not
//! list keep their SBML value (`const`). Each simulation condition used by
//! the measurement table is one experiment: with several, the states and
//! outputs are copied per condition (`x_COND`) and the parameters shared, so
//! condition-specific values (numbers or estimated parameters) are exact.
//! Placeholders `observableParameterN_OBS` take the measurement table's
//! overrides; an observable measured with several different overrides gives
//! one output per override. Noise formulas, transformations (bijections of
//! the output), initial values set by conditions and preequilibration do not
//! change the structure and are not read (a header comment says so).

use crate::ex::Ex;
use crate::infix::{self, Dialect};
use crate::sbml::{check_names, one_line, Sbml};
use crate::yaml::{self, Y};
use crate::{Converted, ImportError};
use std::collections::BTreeMap;

/// The files a PEtab problem names (relative to the YAML file's folder).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PetabFiles {
    pub sbml: String,
    pub parameters: String,
    pub observables: String,
    pub conditions: String,
    /// Zero or more measurement tables (their rows are read together).
    pub measurements: Vec<String>,
}

/// Which file of the problem an error is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PetabFile {
    Yaml,
    Sbml,
    Parameters,
    Observables,
    Conditions,
    /// The k-th measurement table (0-based).
    Measurements(usize),
}

/// An error at a line and column of one of the problem's files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PetabError {
    pub file: PetabFile,
    pub error: ImportError,
}

/// The texts of a problem's files.
pub struct PetabTexts<'a> {
    pub sbml: &'a str,
    pub parameters: &'a str,
    pub observables: &'a str,
    pub conditions: &'a str,
    pub measurements: Vec<&'a str>,
}

/// Read a PEtab v1 problem file: the one problem's file names.
pub fn petab_files(text: &str) -> Result<PetabFiles, ImportError> {
    let y = yaml::parse(text)?;
    let top = match &y {
        Y::Map(_) => &y,
        _ => {
            return Err(ImportError::at(
                1,
                1,
                "a PEtab problem file is a YAML mapping",
            ))
        }
    };
    let at_of = |k: &str| match top {
        Y::Map(m) => m.iter().find(|e| e.0 == k).map_or((1, 1), |e| e.2),
        _ => (1, 1),
    };
    if let Some(Y::Str(v, at)) = top.get("format_version") {
        if !(v == "1" || v.starts_with("1.")) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("format_version {v}: only PEtab v1 is read"),
            ));
        }
    }
    let one =
        |y: Option<&Y>, key: &str, at: (usize, usize)| -> Result<Option<String>, ImportError> {
            match y {
                None => Ok(None),
                Some(Y::Str(s, _)) if !s.is_empty() => Ok(Some(s.clone())),
                Some(Y::List(v)) if v.is_empty() => Ok(None),
                Some(Y::List(v)) => match v.as_slice() {
                    [Y::Str(s, _)] => Ok(Some(s.clone())),
                    _ => Err(ImportError::at(
                        at.0,
                        at.1,
                        format!("'{key}' names {} files: obsan reads one", v.len()),
                    )),
                },
                Some(_) => Err(ImportError::at(
                    at.0,
                    at.1,
                    format!("'{key}' is not a file name"),
                )),
            }
        };
    let parameters = one(
        top.get("parameter_file"),
        "parameter_file",
        at_of("parameter_file"),
    )?
    .ok_or_else(|| ImportError::at(1, 1, "no 'parameter_file' (a PEtab v1 problem names one)"))?;
    let pat = at_of("problems");
    let problem = match top.get("problems") {
        Some(Y::List(v)) if v.len() == 1 => &v[0],
        Some(Y::List(v)) => {
            return Err(ImportError::at(
                pat.0,
                pat.1,
                format!("{} problems: obsan reads a file with one", v.len()),
            ))
        }
        _ => return Err(ImportError::at(pat.0, pat.1, "no 'problems' list")),
    };
    let key_at = |k: &str| match problem {
        Y::Map(m) => m.iter().find(|e| e.0 == k).map_or(pat, |e| e.2),
        _ => pat,
    };
    let need = |k: &str| -> Result<String, ImportError> {
        one(problem.get(k), k, key_at(k))?
            .ok_or_else(|| ImportError::at(pat.0, pat.1, format!("the problem has no '{k}'")))
    };
    Ok(PetabFiles {
        sbml: need("sbml_files")?,
        parameters,
        observables: need("observable_files")?,
        conditions: need("condition_files")?,
        measurements: match problem.get("measurement_files") {
            None => Vec::new(),
            Some(Y::Str(s, _)) => vec![s.clone()],
            Some(Y::List(v)) => v
                .iter()
                .map(|x| match x {
                    Y::Str(s, _) => Ok(s.clone()),
                    _ => {
                        let at = key_at("measurement_files");
                        Err(ImportError::at(
                            at.0,
                            at.1,
                            "'measurement_files' lists a non-name",
                        ))
                    }
                })
                .collect::<Result<_, _>>()?,
            Some(_) => {
                let at = key_at("measurement_files");
                return Err(ImportError::at(
                    at.0,
                    at.1,
                    "'measurement_files' is not a list",
                ));
            }
        },
    })
}

/// A tab-separated table: its header and its rows (1-based line, cells).
struct Table {
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Table {
    fn read(text: &str) -> Result<Table, ImportError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(k, l)| (k + 1, l.strip_prefix('\u{feff}').unwrap_or(l)))
            .filter(|(_, l)| !l.trim().is_empty());
        let header: Vec<String> = match lines.next() {
            Some((_, h)) => h.split('\t').map(|c| c.trim().to_string()).collect(),
            None => return Err(ImportError::at(1, 1, "the table is empty (no header row)")),
        };
        let rows = lines
            .map(|(n, l)| (n, l.split('\t').map(str::to_string).collect()))
            .collect();
        Ok(Table { header, rows })
    }
    fn col(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
    fn need(&self, name: &str) -> Result<usize, ImportError> {
        self.col(name)
            .ok_or_else(|| ImportError::at(1, 1, format!("the table has no column '{name}'")))
    }
    /// A cell's trimmed text and its place (line, column of its first character).
    /// The id in column `k` of `row` with its place; an error unless it is
    /// a valid id (`what`: the table's entries, for the message).
    fn id<'a>(
        &self,
        row: &'a (usize, Vec<String>),
        k: usize,
        what: &str,
    ) -> Result<(&'a str, (usize, usize)), ImportError> {
        let (id, at) = self.cell(row, k);
        if !is_id(id) {
            return Err(ImportError::at(
                at.0,
                at.1,
                format!("'{id}' is not a valid {what} id"),
            ));
        }
        Ok((id, at))
    }
    fn cell<'a>(&self, row: &'a (usize, Vec<String>), k: usize) -> (&'a str, (usize, usize)) {
        let before: usize = row.1.iter().take(k).map(|c| c.chars().count() + 1).sum();
        match row.1.get(k) {
            Some(c) => {
                let lead = c.chars().take_while(|x| x.is_whitespace()).count();
                (c.trim(), (row.0, before + lead + 1))
            }
            None => ("", (row.0, before + 1)),
        }
    }
}

fn is_id(s: &str) -> bool {
    s.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_')
        && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

fn nan(s: &str) -> bool {
    s.is_empty() || s.eq_ignore_ascii_case("nan")
}

/// A table value: a number or a parameter id.
fn value(s: &str, at: (usize, usize)) -> Result<Ex, ImportError> {
    if let Some(n) = infix::normal_number(s.trim_start_matches('+')) {
        return Ok(Ex::Num(n));
    }
    if let Some(n) = s.strip_prefix('-').and_then(infix::normal_number) {
        return Ok(Ex::Neg(Box::new(Ex::Num(n))));
    }
    if is_id(s) {
        return Ok(Ex::Name {
            name: s.to_string(),
            timed: false,
            at,
        });
    }
    Err(ImportError::at(
        at.0,
        at.1,
        format!("'{s}' is neither a finite number nor a parameter id"),
    ))
}

fn subst_names(e: &Ex, f: &dyn Fn(&str) -> Option<Ex>) -> Ex {
    match e {
        Ex::Name { name, .. } => f(name).unwrap_or_else(|| e.clone()),
        Ex::Neg(a) => Ex::Neg(Box::new(subst_names(a, f))),
        Ex::Bin(op, a, b) => Ex::Bin(
            *op,
            Box::new(subst_names(a, f)),
            Box::new(subst_names(b, f)),
        ),
        Ex::Call(g, args) => Ex::Call(g.clone(), args.iter().map(|a| subst_names(a, f)).collect()),
        Ex::Num(_) => e.clone(),
    }
}

/// The error of an id met a second time in its table.
fn listed_twice(what: &str, id: &str, at: (usize, usize)) -> ImportError {
    ImportError::at(at.0, at.1, format!("{what} '{id}' is listed twice"))
}

/// The parameter table: id -> `None` estimated, `Some(value)` fixed.
type ParamTable = Vec<(String, Option<Ex>)>;

fn read_parameters(text: &str) -> Result<ParamTable, ImportError> {
    let t = Table::read(text)?;
    let (ci, ce) = (t.need("parameterId")?, t.need("estimate")?);
    let cn = t.col("nominalValue");
    let mut out: ParamTable = Vec::new();
    for row in &t.rows {
        let (id, at) = t.id(row, ci, "parameter")?;
        if out.iter().any(|p| p.0 == id) {
            return Err(listed_twice("parameter", id, at));
        }
        let (est, eat) = t.cell(row, ce);
        let fixed = match est {
            "1" => None,
            "0" => {
                let (v, vat) = match cn {
                    Some(k) => t.cell(row, k),
                    None => ("", at),
                };
                let x = value(v, vat).ok().filter(|x| !matches!(x, Ex::Name { .. }));
                Some(x.ok_or_else(|| {
                    ImportError::at(
                        vat.0,
                        vat.1,
                        format!("fixed parameter '{id}' has no finite nominalValue ('{v}')"),
                    )
                })?)
            }
            _ => {
                return Err(ImportError::at(
                    eat.0,
                    eat.1,
                    format!("estimate is '{est}': it must be 0 or 1"),
                ))
            }
        };
        out.push((id.to_string(), fixed));
    }
    Ok(out)
}

/// An id, an expression and its place (if any).
type Placed<A> = (String, Ex, A);

/// Observables: id, formula and the formula's place.
fn read_observables(text: &str) -> Result<Vec<Placed<(usize, usize)>>, ImportError> {
    let t = Table::read(text)?;
    let (ci, cf) = (t.need("observableId")?, t.need("observableFormula")?);
    let mut out: Vec<Placed<(usize, usize)>> = Vec::new();
    for row in &t.rows {
        let (id, at) = t.id(row, ci, "observable")?;
        if out.iter().any(|o| o.0 == id) {
            return Err(listed_twice("observable", id, at));
        }
        let (f, fat) = t.cell(row, cf);
        if f.is_empty() {
            return Err(ImportError::at(
                fat.0,
                fat.1,
                format!("observable '{id}' has no formula"),
            ));
        }
        out.push((id.to_string(), infix::parse(f, fat, Dialect::Petab)?, fat));
    }
    Ok(out)
}

/// Conditions: id -> [(column id, value text, place)], and each column's header place.
/// A condition's id and the values it sets: (column id, value, place).
type Condition = (String, Vec<(String, String, (usize, usize))>);
type Conditions = Vec<Condition>;

fn read_conditions(text: &str) -> Result<Conditions, ImportError> {
    let t = Table::read(text)?;
    let ci = t.need("conditionId")?;
    let mut out: Conditions = Vec::new();
    for row in &t.rows {
        let (id, _) = t.id(row, ci, "condition")?;
        let mut vals = Vec::new();
        for (k, h) in t.header.iter().enumerate() {
            if k == ci || h == "conditionName" {
                continue;
            }
            let (v, vat) = t.cell(row, k);
            vals.push((h.clone(), v.to_string(), vat));
        }
        out.push((id.to_string(), vals));
    }
    Ok(out)
}

/// Overrides: per (condition, observable) the distinct override lists, each
/// with its table and the line of its first row.
type Overrides = BTreeMap<(String, String), Vec<(Vec<String>, usize, usize)>>;

/// Measurements: the conditions used in order, the overrides, and whether
/// some row asks for preequilibration.
fn read_measurements(texts: &[&str]) -> Result<(Vec<String>, Overrides, bool), PetabError> {
    let mut conds: Vec<String> = Vec::new();
    let mut over = Overrides::new();
    let mut preeq = false;
    for (k, text) in texts.iter().enumerate() {
        read_measurement_table(text, k, &mut conds, &mut over, &mut preeq)
            .map_err(in_file(PetabFile::Measurements(k)))?;
    }
    Ok((conds, over, preeq))
}

fn read_measurement_table(
    text: &str,
    file: usize,
    conds: &mut Vec<String>,
    over: &mut Overrides,
    preeq: &mut bool,
) -> Result<(), ImportError> {
    let t = Table::read(text)?;
    let (co, cc) = (t.need("observableId")?, t.need("simulationConditionId")?);
    let cp = t.col("observableParameters");
    let cpre = t.col("preequilibrationConditionId");
    for row in &t.rows {
        let (o, oat) = t.cell(row, co);
        let (c, cat) = t.cell(row, cc);
        for (s, at) in [(o, oat), (c, cat)] {
            if !is_id(s) {
                return Err(ImportError::at(
                    at.0,
                    at.1,
                    format!("'{s}' is not a valid id"),
                ));
            }
        }
        *preeq |= cpre.is_some_and(|k| !nan(t.cell(row, k).0));
        if !conds.iter().any(|x| x == c) {
            conds.push(c.to_string());
        }
        let ps: Vec<String> = match cp.map(|k| t.cell(row, k).0) {
            Some(s) if !nan(s) => s.split(';').map(|x| x.trim().to_string()).collect(),
            _ => Vec::new(),
        };
        let e = over.entry((c.to_string(), o.to_string())).or_default();
        if !e.iter().any(|x| x.0 == ps) {
            e.push((ps, file, row.0));
        }
    }
    Ok(())
}

fn in_file(file: PetabFile) -> impl Fn(ImportError) -> PetabError {
    move |error| PetabError { file, error }
}

/// The conditions to copy the model for, the measurement table's overrides,
/// and whether any measurement asks for preequilibration: the conditions the
/// measurements use (all of the table without measurements), narrowed to
/// `condition` if given; one unnamed condition when there is none.
fn used_conditions(
    t: &PetabTexts,
    conditions: &Conditions,
    condition: Option<&str>,
) -> Result<(Vec<String>, Overrides, bool), PetabError> {
    let (mut used, over, preeq) = match t.measurements.is_empty() {
        false => read_measurements(&t.measurements)?,
        true => (
            conditions.iter().map(|c| c.0.clone()).collect(),
            BTreeMap::new(),
            false,
        ),
    };
    if let Some(c) = condition {
        if !conditions.iter().any(|x| x.0 == c) {
            return Err(PetabError {
                file: PetabFile::Conditions,
                error: ImportError::at(1, 1, format!("no condition '{c}' in the condition table")),
            });
        }
        used.retain(|x| x == c);
        if used.is_empty() {
            used.push(c.to_string());
        }
    }
    if used.is_empty() {
        used.push(String::new());
    }
    Ok((used, over, preeq))
}

/// The observables' formulas, with assignment rules and sizes substituted;
/// their names checked first, at their place.
fn observable_formulas(
    m: &Sbml,
    table: &ParamTable,
    observables: &[Placed<(usize, usize)>],
) -> Result<Vec<Placed<(usize, usize)>>, PetabError> {
    let mut known: Vec<String> = m.known().iter().map(|s| s.to_string()).collect();
    known.extend(table.iter().map(|p| p.0.clone()));
    let mut formulas = Vec::new();
    for (o, f, at) in observables {
        let mut k = known.clone();
        let prefix = "observableParameter";
        let mut ph = Vec::new();
        crate::sbml::walk_names(f, &mut |n| {
            if n.starts_with(prefix) && n.ends_with(&format!("_{o}")) {
                ph.push(n.to_string());
            }
        });
        k.extend(ph);
        // Names are checked before the rules are substituted, at their place.
        let rules: Vec<String> = m.assign.keys().cloned().collect();
        k.extend(rules);
        check_names(
            f,
            &k,
            "an id of the model, the parameter table or this observable's parameters",
        )
        .map_err(in_file(PetabFile::Observables))?;
        let r = m.resolve(f).map_err(|e| PetabError {
            file: PetabFile::Observables,
            error: ImportError::at(at.0, at.1, e.message),
        })?;
        formulas.push((o.clone(), r, *at));
    }
    Ok(formulas)
}

/// The values condition `c` sets (its `row` of the condition table):
/// parameters and compartments without a size, each a number or a
/// parameter of the table or the model. Initial values of states are not
/// read: their ids are added to `ignored_init`.
fn condition_values(
    m: &Sbml,
    table: &ParamTable,
    c: &str,
    row: Option<&Condition>,
    ignored_init: &mut Vec<String>,
) -> Result<BTreeMap<String, Ex>, PetabError> {
    let mut set: BTreeMap<String, Ex> = BTreeMap::new();
    for (id, v, at) in row.map_or(&[][..], |r| r.1.as_slice()) {
        if nan(v) {
            continue;
        }
        let err = |msg: String| PetabError {
            file: PetabFile::Conditions,
            error: ImportError::at(at.0, at.1, msg),
        };
        if m.eqs.iter().any(|e| &e.0 == id) {
            if !ignored_init.contains(id) {
                ignored_init.push(id.clone());
            }
            continue;
        }
        if m.sizes.contains_key(id) {
            return Err(err(format!(
                "condition '{c}' sets the size of compartment '{id}', which is folded in as a \
                 number: not supported"
            )));
        }
        if !(m.params.contains(id) || m.consts.contains(id)) {
            return Err(err(format!(
                "column '{id}' is not a parameter, species or compartment of the model"
            )));
        }
        let x = value(v, *at).map_err(|e| PetabError {
            file: PetabFile::Conditions,
            error: e,
        })?;
        if let Ex::Name { name, .. } = &x {
            if !table.iter().any(|p| &p.0 == name) && !m.params.contains(name) {
                return Err(err(format!(
                    "'{name}' is not in the parameter table (condition '{c}', column '{id}')"
                )));
            }
        }
        set.insert(id.clone(), x);
    }
    Ok(set)
}

/// Condition `c`'s outputs, pushed onto `outputs`: each observable measured
/// in it, once per distinct list of placeholder overrides (all observables,
/// unoverridden, when the problem has no measurements), renamed by `ren`.
fn condition_outputs(
    formulas: &[Placed<(usize, usize)>],
    over: &Overrides,
    c: &str,
    measured_all: bool,
    suffix: &str,
    ren: &dyn Fn(&str) -> Option<Ex>,
    outputs: &mut Vec<Placed<Option<(usize, usize)>>>,
) -> Result<(), PetabError> {
    for (o, f, at) in formulas {
        let lists = over.get(&(c.to_string(), o.clone()));
        let lists: Vec<(Vec<String>, usize, usize)> = match lists {
            Some(l) => l.clone(),
            None if measured_all => vec![(Vec::new(), 0, 0)],
            None => continue,
        };
        for (j, (ps, file, line)) in lists.iter().enumerate() {
            let mut vals: BTreeMap<String, Ex> = BTreeMap::new();
            for (n, p) in ps.iter().enumerate() {
                let x = value(p, (*line, 1)).map_err(in_file(PetabFile::Measurements(*file)))?;
                vals.insert(format!("observableParameter{}_{o}", n + 1), x);
            }
            let g = subst_names(f, &|n| vals.get(n).cloned());
            let mut missing = None;
            crate::sbml::walk_names(&g, &mut |n| {
                if n.starts_with("observableParameter") && missing.is_none() && !ps.is_empty() {
                    missing = Some(n.to_string());
                }
            });
            if let Some(n) = missing {
                return Err(PetabError {
                    file: PetabFile::Measurements(*file),
                    error: ImportError::at(
                        *line,
                        1,
                        format!("observable '{o}' needs '{n}', which this row does not give"),
                    ),
                });
            }
            let name = if lists.len() > 1 {
                format!("{o}{suffix}_{}", j + 1)
            } else {
                format!("{o}{suffix}")
            };
            outputs.push((name, subst_names(&g, ren), Some(*at)));
        }
    }
    Ok(())
}

/// Declarations: estimated -> param; fixed -> const with its value; SBML
/// parameters the table does not list keep their SBML value; placeholders
/// no measurement overrides are unknown params.
fn declarations(
    m: &Sbml,
    table: &ParamTable,
    outputs: &[Placed<Option<(usize, usize)>>],
) -> (Vec<String>, Vec<(String, Option<Ex>)>) {
    let mut params: Vec<String> = Vec::new();
    let mut consts: Vec<(String, Option<Ex>)> = Vec::new();
    for p in m.params.iter().chain(table.iter().map(|p| &p.0)) {
        if params.contains(p) || consts.iter().any(|c| &c.0 == p) {
            continue;
        }
        match table.iter().find(|x| &x.0 == p) {
            Some((_, None)) => params.push(p.clone()),
            Some((_, Some(v))) => consts.push((p.clone(), Some(v.clone()))),
            None => consts.push((p.clone(), m.values.get(p).cloned())),
        }
    }
    for (_, e, _) in outputs {
        crate::sbml::walk_names(e, &mut |n| {
            if n.starts_with("observableParameter") && !params.iter().any(|p| p == n) {
                params.push(n.to_string());
            }
        });
    }
    consts.extend(m.consts.iter().map(|c| (c.clone(), None)));
    (params, consts)
}

/// The `.sys` header: where it came from, the conditions, what was not read.
fn header(origin: &str, used: &[String], ignored_init: bool, preeq: bool) -> Vec<String> {
    let mut header = vec![format!(
        "# Imported by `obsan import petab` from {}.",
        one_line(origin)
    )];
    if used.len() > 1 {
        header.push(format!(
            "# One copy of the model per simulation condition (states and outputs suffixed \
             _CONDITION), parameters shared: {}.",
            used.join(", ")
        ));
    } else if !used[0].is_empty() {
        header.push(format!("# Simulation condition {}.", used[0]));
    }
    header.push(
        "# Estimated parameters are params; fixed ones and SBML parameters the table does not \
         list are consts at their values; SBML parameters without a value are generic consts."
            .into(),
    );
    let mut not_read = vec!["noise formulas", "observable transformations"];
    if ignored_init {
        not_read.push("initial values set by conditions");
    }
    if preeq {
        not_read.push("preequilibration");
    }
    header.push(format!(
        "# Not read (the analysis is at a generic initial state; a transformation is a \
         bijection of the output): {}.",
        not_read.join(", ")
    ));
    header
}

/// Translate a PEtab problem into `.sys` text. `condition`: only this
/// simulation condition (default: every condition the measurements use).
pub fn petab_to_sys(
    t: &PetabTexts,
    origin: &str,
    condition: Option<&str>,
) -> Result<Converted, PetabError> {
    use PetabFile as F;
    let m = Sbml::read(t.sbml).map_err(in_file(F::Sbml))?;
    let table = read_parameters(t.parameters).map_err(in_file(F::Parameters))?;
    let observables = read_observables(t.observables).map_err(in_file(F::Observables))?;
    let conditions = read_conditions(t.conditions).map_err(in_file(F::Conditions))?;
    let (used, over, preeq) = used_conditions(t, &conditions, condition)?;
    let measured_all = t.measurements.is_empty();
    let states: Vec<String> = m.eqs.iter().map(|e| e.0.clone()).collect();
    let formulas = observable_formulas(&m, &table, &observables)?;
    let many = used.len() > 1;
    let mut eqs = Vec::new();
    let mut outputs: Vec<Placed<Option<(usize, usize)>>> = Vec::new();
    let mut ignored_init: Vec<String> = Vec::new();
    for c in &used {
        let suffix = if many { format!("_{c}") } else { String::new() };
        let row = conditions.iter().find(|x| &x.0 == c);
        let set = condition_values(&m, &table, c, row, &mut ignored_init)?;
        let ren = |n: &str| -> Option<Ex> {
            // A piecewise input's course may use values the condition sets: one per condition.
            if states.iter().any(|s| s == n) || m.inputs.iter().any(|i| i.name == n) {
                Some(Ex::Name {
                    name: format!("{n}{suffix}"),
                    timed: false,
                    at: (1, 1),
                })
            } else {
                set.get(n).cloned()
            }
        };
        for (v, e, at) in &m.eqs {
            eqs.push((format!("{v}{suffix}"), subst_names(e, &ren), *at));
        }
        condition_outputs(
            &formulas,
            &over,
            c,
            measured_all,
            &suffix,
            &ren,
            &mut outputs,
        )?;
    }
    if outputs.is_empty() {
        return Err(PetabError {
            file: F::Measurements(0),
            error: ImportError::at(1, 1, "no observable is measured in the conditions read"),
        });
    }
    let (params, consts) = declarations(&m, &table, &outputs);
    let header = header(origin, &used, !ignored_init.is_empty(), preeq);
    let mut out = m;
    out.eqs = eqs;
    if many {
        out.inputs = used
            .iter()
            .flat_map(|c| {
                out.inputs.iter().map(move |i| {
                    let mut i = i.clone();
                    i.name = format!("{}_{c}", i.name);
                    i
                })
            })
            .collect();
    }
    Ok(out.emit(header, &params, &consts, &outputs))
}
