//! The dataset format (docs/data-format.md), as text in and text out: the
//! binary does the file I/O. Every rejection names the file, the row and the
//! column.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;

use crate::error::{DataError, DataErrorKind as K, DerivedInputError};
use crate::limits::{MAX_ABS_TIME, MAX_ABS_VALUE, MIN_OUTPUT_SAMPLES};

/// A time series: a time column and named value columns (`None` = not measured).
///
/// Invariants (kept by every constructor and mutator): one value column per
/// name, each as long as the time column; times finite and non-decreasing
/// (equal times are two samples at one instant). Readers index
/// `values()[c][k]` for every `k < len()` and the integrators walk the rows
/// in time order, so neither is re-checked downstream.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    columns: Vec<String>,
    t: Vec<f64>,
    /// `values[c][k]`: column c at row k.
    values: Vec<Vec<Option<f64>>>,
}

impl Series {
    /// An empty series with these value columns.
    pub fn new(columns: Vec<String>) -> Series {
        let n = columns.len();
        Series {
            columns,
            t: Vec::new(),
            values: vec![Vec::new(); n],
        }
    }
    /// Append a row: `row[c]` for column c.
    ///
    /// # Panics
    /// If `row` does not have one value per column, or `t` is not finite or
    /// before the last row's time. Readers of user files check both first
    /// (with the file's line); a violation here is a bug in the caller.
    pub fn push(&mut self, t: f64, row: &[Option<f64>]) {
        assert_eq!(row.len(), self.columns.len(), "one value per column");
        assert!(
            t.is_finite() && self.t.last().is_none_or(|&l| l <= t),
            "time {t} after {:?}: times must be finite and non-decreasing",
            self.t.last()
        );
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
    /// The value columns' names.
    pub fn columns(&self) -> &[String] {
        &self.columns
    }
    /// The time column.
    pub fn t(&self) -> &[f64] {
        &self.t
    }
    /// `values()[c][k]`: column c at row k.
    pub fn values(&self) -> &[Vec<Option<f64>>] {
        &self.values
    }
    /// Column c's values, to change in place (its length is fixed).
    pub fn values_mut(&mut self, c: usize) -> &mut [Option<f64>] {
        &mut self.values[c]
    }
    pub fn column(&self, name: &str) -> Option<&[Option<f64>]> {
        self.columns
            .iter()
            .position(|c| c == name)
            .map(|i| self.values[i].as_slice())
    }
    /// Keep the first `n` rows.
    pub fn truncate(&mut self, n: usize) {
        self.t.truncate(n);
        for c in &mut self.values {
            c.truncate(n);
        }
    }

    /// CSV text: header `t,<columns>`, full precision, empty cells for `None`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from("t");
        for c in &self.columns {
            s.push(',');
            // Quoted when the reader would otherwise split it.
            if c.contains([',', '"']) {
                s.push('"');
                s.push_str(&c.replace('"', "\"\""));
                s.push('"');
            } else {
                s.push_str(c);
            }
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

    /// Parse CSV text. `required` columns must be present (other numeric
    /// columns are kept, text columns dropped); empty cells are allowed only
    /// if `allow_empty`. Warnings (dropped columns) are discarded: see
    /// [`Series::parse_csv_warn`].
    pub fn parse_csv(
        text: &str,
        file: &str,
        required: &[&str],
        allow_empty: bool,
    ) -> Result<Series, DataError> {
        Series::parse_csv_warn(text, file, required, allow_empty).map(|(s, _)| s)
    }

    /// [`Series::parse_csv`] of raw bytes: invalid UTF-8 is an error naming
    /// the line.
    pub fn parse_csv_bytes(
        bytes: &[u8],
        file: &str,
        required: &[&str],
        allow_empty: bool,
    ) -> Result<(Series, Vec<DataWarning>), DataError> {
        Series::parse_csv_warn(utf8(bytes, file)?, file, required, allow_empty)
    }

    /// [`Series::parse_csv`], with a warning for each ignored column. Accepted
    /// besides plain CSV (docs/data-format.md): a UTF-8 byte-order mark, LF,
    /// CRLF or CR line endings, blank lines and `#` comment lines, quoted
    /// fields (`"t","wR"`, `""` inside for a quote), a trailing comma, and
    /// columns outside `required` that hold text (ignored, one warning each).
    pub fn parse_csv_warn(
        text: &str,
        file: &str,
        required: &[&str],
        allow_empty: bool,
    ) -> Result<(Series, Vec<DataWarning>), DataError> {
        parse_rows(text, file, required, allow_empty)
    }
}

/// The body of [`Series::parse_csv_warn`]. Two passes over the text, neither
/// keeping the cells: the first checks each row's shape and finds the text
/// columns (as a whole-file scan must, before any value is taken), the
/// second parses the values straight into the series. A file's rows are
/// never held as strings: they cost several times the file's own size.
fn parse_rows(
    text: &str,
    file: &str,
    required: &[&str],
    allow_empty: bool,
) -> Result<(Series, Vec<DataWarning>), DataError> {
    let err = |row: Option<usize>, column: Option<String>, kind: K| {
        DataError::new(file, row, column, kind)
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (hrow, cols) = header(text, file, required)?;
    // Pass 1: field counts, and the first text cell of each column the
    // caller does not need.
    let mut first_text: Vec<Option<(usize, String)>> = vec![None; cols.len()];
    let mut n_rows = 0;
    for (row, line) in data_lines(text, hrow) {
        let cells = row_cells(line, row, &cols, file)?;
        n_rows += 1;
        for (j, cell) in cells.iter().enumerate().skip(1) {
            if first_text[j].is_none()
                && !required.contains(&cols[j].as_str())
                && !cell.is_empty()
                && cell.parse::<f64>().is_err()
            {
                first_text[j] = Some((row, cell.clone()));
            }
        }
    }
    // A column the caller does not need that holds text is ignored.
    let mut keep = vec![true; cols.len()];
    let mut warnings = Vec::new();
    for (j, c) in cols.iter().enumerate().skip(1) {
        if let Some((row, cell)) = &first_text[j] {
            keep[j] = false;
            warnings.push(DataWarning {
                file: file.to_string(),
                message: format!(
                    "column '{c}' holds text (line {row}: '{cell}') and is not needed: ignored"
                ),
            });
        }
    }
    let kept: Vec<String> = cols
        .iter()
        .zip(&keep)
        .skip(1)
        .filter(|(_, k)| **k)
        .map(|(c, _)| c.clone())
        .collect();
    let mut s = Series::new(kept);
    s.t.reserve_exact(n_rows);
    for c in &mut s.values {
        c.reserve_exact(n_rows);
    }
    // Pass 2: the values (the shapes were checked by pass 1).
    let mut vals = Vec::with_capacity(cols.len());
    for (row, line) in data_lines(text, hrow) {
        let cells = row_cells(line, row, &cols, file)?;
        vals.clear();
        let mut t = 0.0;
        for (j, cell) in cells.iter().enumerate() {
            if !keep[j] {
                continue;
            }
            let bound = if j == 0 { MAX_ABS_TIME } else { MAX_ABS_VALUE };
            let v = if cell.is_empty() {
                if j == 0 || !allow_empty {
                    return Err(err(Some(row), Some(cols[j].clone()), K::EmptyValue));
                }
                None
            } else {
                Some(
                    cell_value(cell, bound, j == 0)
                        .map_err(|k| err(Some(row), Some(cols[j].clone()), k))?,
                )
            };
            match (j, v) {
                (0, Some(x)) => t = x,
                (0, None) => {}
                _ => vals.push(v),
            }
        }
        if let Some(&prev) = s.t.last() {
            if t < prev {
                return Err(err(
                    Some(row),
                    Some("t".into()),
                    K::TimeBackwards { t, prev },
                ));
            }
        }
        s.push(t, &vals);
    }
    Ok((s, warnings))
}

/// The header of a CSV file: its line and its column names, checked (`t`
/// first, no empty or repeated name, every `required` column present).
fn header(text: &str, file: &str, required: &[&str]) -> Result<(usize, Vec<String>), DataError> {
    let err = |row: Option<usize>, column: Option<String>, kind: K| {
        DataError::new(file, row, column, kind)
    };
    let Some((hrow, header)) = data_lines(text, 0).next() else {
        return Err(err(None, None, K::EmptyFile));
    };
    let mut cols =
        split_fields(header).map_err(|(c, m)| err(Some(hrow), Some(format!("{c}")), m))?;
    // A trailing comma ends the header with an empty name.
    if cols.len() > 1 && cols.last().is_some_and(String::is_empty) {
        cols.pop();
    }
    if cols.first().map(String::as_str) != Some("t") {
        return Err(err(
            Some(hrow),
            None,
            K::FirstColumn {
                found: cols.first().cloned().unwrap_or_default(),
            },
        ));
    }
    for (i, c) in cols.iter().enumerate() {
        if c.is_empty() {
            return Err(err(Some(hrow), None, K::UnnamedColumn { index: i + 1 }));
        }
        if cols[..i].contains(c) {
            return Err(err(Some(hrow), Some(c.clone()), K::DuplicateColumn));
        }
    }
    for r in required {
        if !cols.iter().any(|c| c == r) {
            return Err(err(
                Some(hrow),
                Some(r.to_string()),
                K::MissingColumn {
                    name: r.to_string(),
                    header: cols.join(","),
                },
            ));
        }
    }
    Ok((hrow, cols))
}

/// The lines after line `after` that are neither blank nor `#` comments.
fn data_lines(text: &str, after: usize) -> impl Iterator<Item = (usize, &str)> {
    split_lines(text).filter(move |(row, l)| {
        let l = l.trim();
        *row > after && !l.is_empty() && !l.starts_with('#')
    })
}

/// The cells of one data row, as many as the header's columns (a trailing
/// comma allowed).
fn row_cells(
    line: &str,
    row: usize,
    cols: &[String],
    file: &str,
) -> Result<Vec<String>, DataError> {
    let mut cells = split_fields(line)
        .map_err(|(c, m)| DataError::new(file, Some(row), cols.get(c - 1).cloned(), m))?;
    if cells.len() == cols.len() + 1 && cells.last().is_some_and(String::is_empty) {
        cells.pop();
    }
    if cells.len() != cols.len() {
        return Err(DataError::new(
            file,
            Some(row),
            None,
            K::FieldCount {
                found: cells.len(),
                expected: cols.len(),
            },
        ));
    }
    Ok(cells)
}

/// One non-empty cell's value: a finite number within `bound`.
fn cell_value(cell: &str, bound: f64, time: bool) -> Result<f64, K> {
    match cell.parse::<f64>() {
        Ok(x) if !x.is_finite() => Err(K::NotFinite(cell.to_string())),
        Ok(x) if x.abs() > bound => Err(K::OutOfRange {
            cell: cell.to_string(),
            time,
            bound,
        }),
        Ok(x) => Ok(x),
        Err(_) => Err(K::NotANumber(cell.to_string())),
    }
}

/// The 1-based line of data row `k` (0-based, header excluded) of a CSV
/// text, for a message about that row.
fn line_of_row(text: &str, k: usize) -> Option<usize> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let (hrow, _) = data_lines(text, 0).next()?;
    data_lines(text, hrow).nth(k).map(|(row, _)| row)
}

/// Something accepted but worth saying once (e.g. an ignored column).
#[derive(Clone, Debug, PartialEq)]
pub struct DataWarning {
    pub file: String,
    pub message: String,
}

impl fmt::Display for DataWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.file, self.message)
    }
}

/// Lines with their 1-based numbers; `\n`, `\r\n` and a lone `\r` each end one.
fn split_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    let b = text.as_bytes();
    let (mut start, mut line) = (0, 0);
    std::iter::from_fn(move || {
        if start >= b.len() {
            return None;
        }
        let end = b[start..]
            .iter()
            .position(|&c| c == b'\n' || c == b'\r')
            .map_or(b.len(), |p| start + p);
        let out = (line + 1, &text[start..end]);
        line += 1;
        start = if b.get(end) == Some(&b'\r') && b.get(end + 1) == Some(&b'\n') {
            end + 2
        } else {
            end + 1
        };
        Some(out)
    })
}

/// The fields of one CSV line, trimmed; a field may be quoted (`"a,b"`, with
/// `""` for a quote inside). An error gives the 1-based field number.
///
/// Hand-written rather than the `csv` crate: the format is one row per line (a quote
/// never spans lines, so a row number is a line number), and every rejection names the
/// field; `csv` reads quoted newlines, accepts text after a closing quote (`"a"b`) and
/// reports a byte and record position, not the field.
fn split_fields(line: &str) -> Result<Vec<String>, (usize, K)> {
    let mut out = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        let n = out.len() + 1;
        let mut field = String::new();
        while chars.peek().is_some_and(|c| *c == ' ' || *c == '\t') {
            chars.next();
        }
        if chars.peek() == Some(&'"') {
            chars.next();
            loop {
                match chars.next() {
                    None => return Err((n, K::UnclosedQuote)),
                    Some('"') if chars.peek() == Some(&'"') => {
                        chars.next();
                        field.push('"');
                    }
                    Some('"') => break,
                    Some(c) => field.push(c),
                }
            }
            let field = field.trim().to_string();
            while chars.peek().is_some_and(|c| *c == ' ' || *c == '\t') {
                chars.next();
            }
            match chars.next() {
                None => {
                    out.push(field);
                    return Ok(out);
                }
                Some(',') => out.push(field),
                Some(c) => {
                    return Err((n, K::AfterQuote(c)));
                }
            }
        } else {
            loop {
                match chars.next() {
                    None => {
                        out.push(field.trim().to_string());
                        return Ok(out);
                    }
                    Some(',') => break,
                    Some(c) => field.push(c),
                }
            }
            out.push(field.trim().to_string());
        }
    }
}

/// The text of a file's bytes (a byte-order mark dropped); invalid UTF-8 is
/// an error naming the line.
fn utf8<'a>(bytes: &'a [u8], file: &str) -> Result<&'a str, DataError> {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let ok = &bytes[..e.valid_up_to()];
        let line = 1 + ok
            .iter()
            .enumerate()
            .filter(|&(i, &c)| c == b'\n' || (c == b'\r' && ok.get(i + 1) != Some(&b'\n')))
            .count();
        DataError::new(
            file,
            Some(line),
            None,
            K::InvalidUtf8 {
                byte: e.valid_up_to() + 1,
            },
        )
    })
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

impl Trajectory {
    /// Check a trajectory read from files named in `origin`.
    pub fn check(&self, origin: &str) -> Result<(), DataError> {
        check_counts(
            &self.outputs,
            &self.inputs,
            || format!("{origin}/outputs.csv"),
            || format!("{origin}/inputs.csv"),
        )?;
        Ok(())
    }
}

/// The minimum sizes of one trajectory: enough measured output samples,
/// and two input rows (one interval). The file names are for the message.
fn check_counts(
    outputs: &Series,
    inputs: &Series,
    outputs_file: impl FnOnce() -> String,
    inputs_file: impl FnOnce() -> String,
) -> Result<(), DataError> {
    let measured = outputs
        .values
        .iter()
        .map(|c| c.iter().filter(|v| v.is_some()).count())
        .sum::<usize>();
    if measured < MIN_OUTPUT_SAMPLES {
        return Err(DataError {
            file: outputs_file(),
            row: None,
            column: None,
            kind: K::TooFewOutputs { measured },
        });
    }
    if inputs.len() < 2 {
        return Err(DataError {
            file: inputs_file(),
            row: None,
            column: None,
            kind: K::TooFewInputs,
        });
    }
    Ok(())
}

/// A dataset: metadata and trajectories (in name order).
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    pub meta: DatasetMeta,
    pub trajectories: Vec<Trajectory>,
}

/// One file of a dataset: its path (for messages) and its bytes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DataFile {
    pub path: String,
    pub bytes: Vec<u8>,
}

/// The files of one trajectory folder (`None`: the file is absent).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrajectoryFiles {
    /// The folder's name, the trajectory's name.
    pub name: String,
    pub inputs: Option<DataFile>,
    pub outputs: Option<DataFile>,
    pub meta: Option<DataFile>,
}

/// The files of a dataset folder, trajectories in name order. `truth.json`
/// is not among them: estimators never read it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DatasetFiles {
    pub meta: Option<DataFile>,
    pub trajectories: Vec<TrajectoryFiles>,
}

/// A dataset read, with what was accepted but worth saying.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadDataset {
    pub dataset: Dataset,
    pub warnings: Vec<DataWarning>,
}

/// Read a dataset from its files (docs/data-format.md): `inputs` and
/// `outputs` are the columns the model needs. Every rejection names the file
/// and, where there is one, the line and the column.
pub fn read_dataset(
    files: &DatasetFiles,
    inputs: &[&str],
    outputs: &[&str],
) -> Result<ReadDataset, DataError> {
    let mut reader = DatasetReader::new(files.meta.as_ref(), inputs, outputs)?;
    for tf in &files.trajectories {
        reader.add(tf)?;
    }
    reader.finish()
}

/// [`read_dataset`] one trajectory at a time: a caller that reads the files
/// of a trajectory, adds them and drops them holds one trajectory's file
/// bytes at most, never the whole dataset's beside the parsed series.
pub struct DatasetReader<'c> {
    inputs: &'c [&'c str],
    outputs: &'c [&'c str],
    meta: DatasetMeta,
    warnings: Vec<DataWarning>,
    trajectories: Vec<Trajectory>,
}

fn located(f: &DataFile, e: serde_json::Error, hint: &str) -> DataError {
    DataError::new(
        f.path.clone(),
        // serde_json counts lines from 1; 0 means no position.
        (e.line() > 0).then_some(e.line()),
        (e.line() > 0).then(|| e.column().to_string()),
        K::Json(format!("{e}{hint}")),
    )
}

impl<'c> DatasetReader<'c> {
    /// Start with `dataset.json` (`None`: absent); `inputs` and `outputs`
    /// are the columns the model needs.
    pub fn new(
        meta: Option<&DataFile>,
        inputs: &'c [&'c str],
        outputs: &'c [&'c str],
    ) -> Result<DatasetReader<'c>, DataError> {
        let meta: DatasetMeta = match meta {
            Some(f) => {
                let m: DatasetMeta = serde_json::from_str(utf8(&f.bytes, &f.path)?)
                    .map_err(|e| located(f, e, ""))?;
                let values = m
                    .nominal
                    .iter()
                    .chain(&m.noise)
                    .map(|(k, v)| (k.as_str(), *v))
                    .chain(m.d0.map(|v| ("d0", v)));
                check_json_values(f, values)?;
                m
            }
            None => DatasetMeta::default(),
        };
        Ok(DatasetReader {
            inputs,
            outputs,
            meta,
            warnings: Vec::new(),
            trajectories: Vec::new(),
        })
    }

    /// Parse and check one trajectory's files (trajectories in name order).
    pub fn add(&mut self, tf: &TrajectoryFiles) -> Result<(), DataError> {
        let missing = |which: &str| {
            DataError::new(
                format!("{}/{which}", tf.name),
                None,
                None,
                K::MissingFile {
                    trajectory: tf.name.clone(),
                    which: which.to_string(),
                },
            )
        };
        let fi = tf.inputs.as_ref().ok_or_else(|| missing("inputs.csv"))?;
        let fo = tf.outputs.as_ref().ok_or_else(|| missing("outputs.csv"))?;
        let (ins, w) = parse_rows(utf8(&fi.bytes, &fi.path)?, &fi.path, self.inputs, false)?;
        self.warnings.extend(w);
        let out_text = utf8(&fo.bytes, &fo.path)?;
        let (outs, w) = parse_rows(out_text, &fo.path, self.outputs, true)?;
        self.warnings.extend(w);
        let meta: BTreeMap<String, f64> = match &tf.meta {
            Some(f) => {
                let m: BTreeMap<String, f64> = serde_json::from_str(utf8(&f.bytes, &f.path)?)
                    .map_err(|e| located(f, e, " (expected {\"name\": number})"))?;
                check_json_values(f, m.iter().map(|(k, v)| (k.as_str(), *v)))?;
                m
            }
            None => BTreeMap::new(),
        };
        check_counts(&outs, &ins, || fo.path.clone(), || fi.path.clone())?;
        // Outputs are predicted from the inputs on: none may come before
        // them, nor after their end by more than their span (which bounds
        // the integration's work by the data's own size).
        let (t0, t1) = (ins.t[0], ins.t[ins.len() - 1]);
        let late = t1 + (t1 - t0);
        if let Some(k) = outs.t.iter().position(|&t| t < t0 || t > late) {
            let t = outs.t[k];
            return Err(DataError {
                file: fo.path.clone(),
                row: line_of_row(out_text, k),
                column: Some("t".into()),
                kind: if t < t0 {
                    K::OutputBeforeInputs {
                        t,
                        t0,
                        inputs: fi.path.clone(),
                    }
                } else {
                    K::OutputAfterInputs {
                        t,
                        late,
                        t1,
                        inputs: fi.path.clone(),
                    }
                },
            });
        }
        self.trajectories.push(Trajectory {
            name: tf.name.clone(),
            inputs: ins,
            outputs: outs,
            meta,
        });
        Ok(())
    }

    /// The dataset, with its warnings; at least one trajectory.
    pub fn finish(self) -> Result<ReadDataset, DataError> {
        if self.trajectories.is_empty() {
            return Err(DataError {
                file: "the dataset".into(),
                row: None,
                column: None,
                kind: K::NoTrajectory,
            });
        }
        Ok(ReadDataset {
            dataset: Dataset {
                meta: self.meta,
                trajectories: self.trajectories,
            },
            warnings: self.warnings,
        })
    }
}

/// Numbers from a JSON file obey the CSV bound ([`MAX_ABS_VALUE`]).
fn check_json_values<'a>(
    f: &DataFile,
    values: impl Iterator<Item = (&'a str, f64)>,
) -> Result<(), DataError> {
    for (k, v) in values {
        if !(v.is_finite() && v.abs() <= MAX_ABS_VALUE) {
            return Err(DataError {
                file: f.path.clone(),
                row: None,
                column: Some(k.to_string()),
                kind: K::JsonOutOfRange(v),
            });
        }
    }
    Ok(())
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
) -> Result<(), DerivedInputError> {
    for (name, def) in derived {
        if series.columns.iter().any(|c| c == name) {
            continue;
        }
        let def = def.trim();
        let col: Vec<Option<f64>> = if let Some(inner) =
            def.strip_prefix("rate(").and_then(|r| r.strip_suffix(')'))
        {
            let src = series
                .column(inner.trim())
                .ok_or_else(|| DerivedInputError::NoColumn {
                    name: name.clone(),
                    def: def.to_string(),
                    column: inner.trim().to_string(),
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
            let ast = obsan_expr::parse_ast(def).map_err(|e| DerivedInputError::Parse {
                name: name.clone(),
                def: def.to_string(),
                message: e.message,
            })?;
            let expr = obsan_expr::FloatExpr::new(ast);
            enum Src<'a> {
                Col(&'a [Option<f64>]),
                Const(f64),
            }
            let srcs: Vec<Src> = expr
                .names()
                .iter()
                .map(|n| match series.column(n) {
                    Some(c) => Ok(Src::Col(c)),
                    None => consts.get(n).map(|v| Src::Const(*v)).ok_or_else(|| {
                        DerivedInputError::Unknown {
                            name: name.clone(),
                            def: def.to_string(),
                            ident: n.clone(),
                        }
                    }),
                })
                .collect::<Result<_, DerivedInputError>>()?;
            let mut x = vec![0.0; srcs.len()];
            (0..series.t.len())
                .map(|k| {
                    for (xi, s) in x.iter_mut().zip(&srcs) {
                        *xi = match s {
                            Src::Col(c) => c[k]?,
                            Src::Const(v) => *v,
                        };
                    }
                    let v = expr.eval(&x);
                    v.is_finite().then_some(v)
                })
                .collect()
        };
        debug_assert_eq!(col.len(), series.t.len());
        series.columns.push(name.clone());
        series.values.push(col);
    }
    Ok(())
}

#[cfg(test)]
mod tests;
