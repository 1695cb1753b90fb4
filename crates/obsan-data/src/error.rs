//! The dataset readers' typed errors. `Display` is the exact text the CLI
//! prints (its tests compare the texts): `file[:row][ (column c)]: message`.

use crate::limits::{MAX_ABS_VALUE, MIN_OUTPUT_SAMPLES};
use std::fmt;

/// A rejected file, with the place. A plain record: any combination of
/// place and kind is a valid error, so the fields are public.
#[derive(Clone, Debug, PartialEq)]
pub struct DataError {
    pub file: String,
    /// 1-based line number in the file (the header is line 1).
    pub row: Option<usize>,
    /// A column's name (CSV), a key (JSON), a 1-based column number (MRCLAM
    /// logs) or serde_json's 1-based character column.
    pub column: Option<String>,
    pub kind: DataErrorKind,
}

impl DataError {
    pub(crate) fn new(
        file: impl Into<String>,
        row: Option<usize>,
        column: Option<String>,
        kind: DataErrorKind,
    ) -> DataError {
        DataError {
            file: file.into(),
            row,
            column,
            kind,
        }
    }

    /// The message after the place.
    pub fn message(&self) -> String {
        self.kind.to_string()
    }
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
        write!(f, ": {}", self.kind)
    }
}

impl std::error::Error for DataError {}

/// What is wrong at a [`DataError`]'s place.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum DataErrorKind {
    /// No header line.
    EmptyFile,
    /// The header's first column is not `t`.
    FirstColumn { found: String },
    /// A header field is empty (1-based position).
    UnnamedColumn { index: usize },
    /// A header name appears twice.
    DuplicateColumn,
    /// A column the model needs is absent.
    MissingColumn { name: String, header: String },
    /// A quoted field runs to the end of its line.
    UnclosedQuote,
    /// Text after a field's closing quote.
    AfterQuote(char),
    /// A row has a different number of fields than the header.
    FieldCount { found: usize, expected: usize },
    /// An empty cell where a value is required.
    EmptyValue,
    /// NaN or infinite.
    NotFinite(String),
    /// Beyond [`crate::MAX_ABS_TIME`] (`time`) or [`MAX_ABS_VALUE`].
    OutOfRange {
        cell: String,
        time: bool,
        bound: f64,
    },
    /// Not a number.
    NotANumber(String),
    /// A CSV row's time is before the previous row's.
    TimeBackwards { t: f64, prev: f64 },
    /// Invalid UTF-8 at this 1-based byte.
    InvalidUtf8 { byte: usize },
    /// A JSON file not understood: serde_json's message and a hint.
    Json(String),
    /// A JSON number beyond [`MAX_ABS_VALUE`].
    JsonOutOfRange(f64),
    /// A trajectory folder lacks a file.
    MissingFile { trajectory: String, which: String },
    /// Fewer than [`MIN_OUTPUT_SAMPLES`] output samples.
    TooFewOutputs { measured: usize },
    /// Fewer than 2 input rows.
    TooFewInputs,
    /// An output time before the first input time (`inputs`: that file).
    OutputBeforeInputs { t: f64, t0: f64, inputs: String },
    /// An output time beyond the inputs' end plus their span.
    OutputAfterInputs {
        t: f64,
        late: f64,
        t1: f64,
        inputs: String,
    },
    /// No trajectory folder.
    NoTrajectory,
    /// A MRCLAM log row has fewer columns than its kind.
    ColumnCount { expected: usize, found: usize },
    /// `--window` is not a positive number of seconds.
    BadWindow,
    /// A MRCLAM log's time goes backwards.
    LogTimeBackwards { t: f64, prev: f64 },
    /// A MRCLAM odometry log with fewer than two rows.
    TooFewOdometryRows,
    /// `--window` would cut the log into more than `max` windows.
    TooManyWindows { window: f64, span: f64, max: f64 },
    /// Vicon poses as outputs without the ground-truth file.
    NeedsGroundTruth,
    /// `Landmark_Groundtruth.dat` lists no landmark.
    NoLandmarks,
    /// No window holds enough landmark measurements.
    NoWindow {
        window: f64,
        min_measurements: usize,
    },
}

/// The most characters of a cell (or header) a message echoes: a 10 MB
/// cell must not make a 10 MB message.
pub const MAX_ECHO_CHARS: usize = 80;

/// `text` as echoed in a message: whole if short, else its start and its
/// length.
fn cut(text: &str) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(MAX_ECHO_CHARS) {
        None => text.into(),
        Some((end, _)) => format!("{}... ({} bytes in all)", &text[..end], text.len()).into(),
    }
}

impl fmt::Display for DataErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use DataErrorKind::*;
        match self {
            EmptyFile => f.write_str("the file is empty: expected a header line t,..."),
            FirstColumn { found } => {
                write!(f, "the first column must be 't', found '{}'", cut(found))
            }
            UnnamedColumn { index } => write!(f, "column {index} of the header has no name"),
            DuplicateColumn => f.write_str("this column appears twice"),
            MissingColumn { name, header } => {
                write!(
                    f,
                    "missing column '{}' (the header is '{}')",
                    cut(name),
                    cut(header)
                )
            }
            UnclosedQuote => f.write_str("a quoted field is not closed on its line"),
            AfterQuote(c) => write!(f, "'{c}' after the closing quote of a field"),
            FieldCount { found, expected } => {
                write!(f, "{found} fields, the header has {expected}")
            }
            EmptyValue => f.write_str("empty value"),
            NotFinite(cell) => write!(f, "'{}' is not a finite number", cut(cell)),
            OutOfRange { cell, time, bound } => write!(
                f,
                "'{}' is outside the accepted range |{}| <= {bound:e}",
                cut(cell),
                if *time { "t" } else { "value" }
            ),
            NotANumber(cell) => write!(f, "'{}' is not a number", cut(cell)),
            TimeBackwards { t, prev } => write!(f, "time goes backwards: {t} after {prev}"),
            InvalidUtf8 { byte } => write!(f, "invalid UTF-8 (byte {byte} of the file)"),
            Json(m) => f.write_str(m),
            JsonOutOfRange(v) => write!(
                f,
                "{v} is outside the accepted range |value| <= {MAX_ABS_VALUE:e}"
            ),
            MissingFile { trajectory, which } => {
                write!(f, "trajectory '{trajectory}' has no {which}")
            }
            TooFewOutputs { measured } => write!(
                f,
                "only {measured} output samples: a trajectory needs at least {MIN_OUTPUT_SAMPLES}"
            ),
            TooFewInputs => f.write_str("fewer than 2 input rows"),
            OutputBeforeInputs { t, t0, inputs } => write!(
                f,
                "output time {t} is before the first input time {t0} ({inputs})"
            ),
            OutputAfterInputs {
                t,
                late,
                t1,
                inputs,
            } => write!(
                f,
                "output time {t} is after {late}, the inputs' end {t1} plus their span ({inputs})"
            ),
            NoTrajectory => f.write_str("no trajectory folder (with inputs.csv and outputs.csv)"),
            ColumnCount { expected, found } => {
                write!(f, "expected {expected} columns, found {found}")
            }
            BadWindow => f.write_str("the window must be a positive number of seconds"),
            LogTimeBackwards { t, prev } => write!(f, "time goes backwards ({t} after {prev})"),
            TooFewOdometryRows => f.write_str("fewer than two odometry rows"),
            TooManyWindows { window, span, max } => write!(
                f,
                "{window} s cuts the log's {span:.0} s into more than {max:e} windows"
            ),
            NeedsGroundTruth => {
                f.write_str("Vicon poses as outputs need the robot's ground-truth file")
            }
            NoLandmarks => f.write_str("no landmark (expected rows: barcode x y ...)"),
            NoWindow {
                window,
                min_measurements,
            } => write!(
                f,
                "no window of {window} s has {min_measurements} landmark measurements"
            ),
        }
    }
}

/// Why a derived input (`input dwR = rate(wR)`) cannot be computed. It
/// belongs to a model's definition, not to a file: no place.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum DerivedInputError {
    /// `rate(u)` of a column that is absent.
    NoColumn {
        name: String,
        def: String,
        column: String,
    },
    /// The definition does not parse.
    Parse {
        name: String,
        def: String,
        message: String,
    },
    /// A name in the definition is neither a column nor a constant.
    Unknown {
        name: String,
        def: String,
        ident: String,
    },
}

impl fmt::Display for DerivedInputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DerivedInputError::NoColumn { name, def, column } => {
                write!(f, "derived input {name} = {def}: no input column '{column}'")
            }
            DerivedInputError::Parse { name, def, message } => {
                write!(f, "derived input {name} = {def}: {message}")
            }
            DerivedInputError::Unknown { name, def, ident } => write!(
                f,
                "derived input {name} = {def}: '{ident}' is neither an input column nor a known constant"
            ),
        }
    }
}

impl std::error::Error for DerivedInputError {}

#[cfg(test)]
mod tests {
    use super::{DataErrorKind as K, DerivedInputError};
    use crate::{add_derived_inputs, Series};
    use std::collections::BTreeMap;

    fn kind(text: &str) -> (Option<usize>, Option<String>, K) {
        let e = Series::parse_csv(text, "in.csv", &["wR"], false).unwrap_err();
        (e.row, e.column, e.kind)
    }

    /// A 10 MB cell made a 10 MB message. The echo is cut to
    /// MAX_ECHO_CHARS characters plus the cell's length in bytes.
    #[test]
    fn a_huge_cell_is_cut_in_the_message() {
        let cell = "x".repeat(10 << 20);
        for text in [
            format!("t,wR\n0,{cell}\n"),
            format!("{cell},wR\n"),
            format!("t,{cell}\n"),
        ] {
            let e = Series::parse_csv(&text, "in.csv", &["wR"], false).unwrap_err();
            let m = e.to_string();
            assert!(m.len() < 400, "{} bytes: {}", m.len(), &m[..400]);
            // The whole cell is 10 MiB (the third case's header 2 more).
            assert!(m.contains(" bytes in all)"), "{m}");
            assert!(m.contains(&format!("{}", 10 << 20)[..6]), "{m}");
        }
        // A short cell is echoed whole.
        let e = Series::parse_csv("t,wR\n0,abc\n", "in.csv", &["wR"], false).unwrap_err();
        assert!(e.to_string().contains("'abc' is not a number"), "{e}");
    }

    #[test]
    fn csv_rejections_give_their_variant_and_place() {
        assert_eq!(kind(""), (None, None, K::EmptyFile));
        assert_eq!(kind("x,wR\n").2, K::FirstColumn { found: "x".into() });
        assert_eq!(kind("t,,wR\n").2, K::UnnamedColumn { index: 2 });
        assert_eq!(
            kind("t,wR,wR\n"),
            (Some(1), Some("wR".into()), K::DuplicateColumn)
        );
        assert_eq!(
            kind("t,wL\n").2,
            K::MissingColumn {
                name: "wR".into(),
                header: "t,wL".into()
            }
        );
        assert_eq!(kind("t,\"wR\n").2, K::UnclosedQuote);
        assert_eq!(kind("t,\"wR\"x\n").2, K::AfterQuote('x'));
        assert_eq!(
            kind("t,wR\n0,1,2,3\n"),
            (
                Some(2),
                None,
                K::FieldCount {
                    found: 4,
                    expected: 2
                }
            )
        );
        assert_eq!(kind("t,wR\n0,\n").2, K::EmptyValue);
        assert_eq!(kind("t,wR\n0,NaN\n").2, K::NotFinite("NaN".into()));
        assert_eq!(kind("t,wR\n0,abc\n").2, K::NotANumber("abc".into()));
        assert_eq!(
            kind("t,wR\n1e11,1\n").2,
            K::OutOfRange {
                cell: "1e11".into(),
                time: true,
                bound: crate::MAX_ABS_TIME
            }
        );
        assert_eq!(
            kind("t,wR\n1,1\n# c\n0.5,1\n"),
            (
                Some(4),
                Some("t".into()),
                K::TimeBackwards { t: 0.5, prev: 1.0 }
            )
        );
        let e = Series::parse_csv_bytes(b"t,wR\n0,\xff\n", "in.csv", &["wR"], false).unwrap_err();
        assert_eq!((e.row, e.kind), (Some(2), K::InvalidUtf8 { byte: 8 }));
    }

    #[test]
    fn display_is_the_place_then_the_message() {
        let e = Series::parse_csv("t,wR\n0,1e10\n", "a/in.csv", &["wR"], false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "a/in.csv:2 (column wR): '1e10' is outside the accepted range |value| <= 1e9"
        );
        assert_eq!(e.message(), e.kind.to_string());
        let e = Series::parse_csv("", "in.csv", &[], false).unwrap_err();
        assert_eq!(
            e.to_string(),
            "in.csv: the file is empty: expected a header line t,..."
        );
    }

    #[test]
    fn derived_input_errors() {
        let mut s = Series::new(vec!["wR".into()]);
        s.push(0.0, &[Some(1.0)]);
        s.push(1.0, &[Some(2.0)]);
        let none = BTreeMap::new();
        let d = |def: &str| vec![("d".to_string(), def.to_string())];
        let e = add_derived_inputs(&mut s, &d("rate(wL)"), &none).unwrap_err();
        assert_eq!(
            e,
            DerivedInputError::NoColumn {
                name: "d".into(),
                def: "rate(wL)".into(),
                column: "wL".into()
            }
        );
        assert_eq!(
            e.to_string(),
            "derived input d = rate(wL): no input column 'wL'"
        );
        let e = add_derived_inputs(&mut s, &d("wR * k"), &none).unwrap_err();
        assert!(matches!(&e, DerivedInputError::Unknown { ident, .. } if ident == "k"));
        let e = add_derived_inputs(&mut s, &d("wR +"), &none).unwrap_err();
        assert!(matches!(e, DerivedInputError::Parse { .. }));
        assert!(s.column("d").is_none());
    }
}
