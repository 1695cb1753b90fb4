//! The dataset reader: benign variations of valid
//! files are read to the same numbers; mutated files never panic and every
//! rejection names a file of the dataset and a line within it.

use obsan_calib::{simulate, SimOptions};
use obsan_data::{
    read_dataset, DataError, DataFile, DatasetFiles, Series, TrajectoryFiles, MAX_ABS_VALUE,
};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;

const INPUTS: [&str; 2] = ["wR", "wL"];
const OUTPUTS: [&str; 1] = ["beta"];

fn file(path: &str, text: impl Into<Vec<u8>>) -> Option<DataFile> {
    Some(DataFile {
        path: path.into(),
        bytes: text.into(),
    })
}

fn one(inputs: impl Into<Vec<u8>>, outputs: impl Into<Vec<u8>>) -> DatasetFiles {
    DatasetFiles {
        meta: None,
        trajectories: vec![TrajectoryFiles {
            name: "a".into(),
            inputs: file("a/inputs.csv", inputs),
            outputs: file("a/outputs.csv", outputs),
            meta: None,
        }],
    }
}

fn read(f: &DatasetFiles) -> Result<obsan_data::ReadDataset, DataError> {
    read_dataset(f, &INPUTS, &OUTPUTS)
}

/// Plain inputs: 0..n rows of two wheel speeds; outputs: ten bearings.
fn plain_inputs() -> String {
    let mut s = String::from("t,wR,wL\n");
    for k in 0..20 {
        s.push_str(&format!(
            "{},{},{}\n",
            k as f64 * 0.5,
            0.1 + k as f64,
            -0.25
        ));
    }
    s
}
fn plain_outputs() -> String {
    let mut s = String::from("t,beta\n");
    for k in 0..12 {
        s.push_str(&format!("{},{}\n", k as f64 * 0.75, 0.01 * k as f64));
    }
    s
}

#[test]
fn benign_variations_read_to_the_same_numbers() {
    let base = read(&one(plain_inputs(), plain_outputs())).unwrap();
    assert!(base.warnings.is_empty());
    let crlf = |s: &str| s.replace('\n', "\r\n");
    let cr = |s: &str| s.replace('\n', "\r");
    let bom = |s: &str| format!("\u{feff}{s}");
    let quoted = |s: &str| {
        let (h, rest) = s.split_once('\n').unwrap();
        let h: Vec<String> = h.split(',').map(|c| format!("\"{c}\"")).collect();
        format!("{}\n{rest}", h.join(","))
    };
    let trailing = |s: &str| s.replace('\n', ",\n");
    let comments = |s: &str| format!("# logged by hand\n\n{}\n# end\n\n", s.replace('\n', "\n\n"));
    type Vary = Box<dyn Fn(&str) -> String>;
    let variants: Vec<(&str, Vary)> = vec![
        ("crlf", Box::new(crlf)),
        ("cr", Box::new(cr)),
        ("bom", Box::new(bom)),
        ("quoted header", Box::new(quoted)),
        ("trailing comma", Box::new(trailing)),
        ("comments and blank lines", Box::new(comments)),
        ("all", Box::new(move |s| bom(&cr(&trailing(&quoted(s)))))),
    ];
    for (name, v) in &variants {
        let r = read(&one(v(&plain_inputs()), v(&plain_outputs())))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(r.dataset, base.dataset, "{name}");
        assert!(r.warnings.is_empty(), "{name}");
    }
    // A JSON file with a byte-order mark.
    let mut f = one(plain_inputs(), plain_outputs());
    f.meta = file("dataset.json", "\u{feff}{\"d0\": 1.2}");
    assert_eq!(read(&f).unwrap().dataset.meta.d0, Some(1.2));
}

#[test]
fn a_text_column_is_ignored_once_with_a_warning() {
    let with_note: String = plain_inputs()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            let note = match i {
                0 => "note",
                3 => "\"turning, fast\"",
                _ => "ok",
            };
            format!("{l},{note}\n")
        })
        .collect();
    let r = read(&one(with_note, plain_outputs())).unwrap();
    let base = read(&one(plain_inputs(), plain_outputs())).unwrap();
    assert_eq!(r.dataset, base.dataset);
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    let w = r.warnings[0].to_string();
    assert!(w.starts_with("a/inputs.csv") && w.contains("'note'"), "{w}");
    // A required column holding text is still an error, located.
    let bad = plain_inputs().replace("5.1,-0.25", "fast,-0.25");
    let e = read(&one(bad, plain_outputs())).unwrap_err();
    assert_eq!((e.row, e.column.as_deref()), (Some(7), Some("wR")), "{e}");
}

#[test]
fn real_errors_stay_located() {
    // (inputs, outputs, file, row, column, message part)
    let ins = plain_inputs();
    let outs = plain_outputs();
    type Case<'a> = (
        String,
        String,
        &'a str,
        Option<usize>,
        Option<&'a str>,
        &'a str,
    );
    let cases: Vec<Case> = vec![
        // The value that hung calibrate.
        (
            ins.clone(),
            outs.replace("\n1.5,0.02\n", "\n1.5,1e308\n"),
            "a/outputs.csv",
            Some(4),
            Some("beta"),
            "outside the accepted range",
        ),
        (
            ins.replace("\n1,2.1,", "\n1,2e9,"),
            outs.clone(),
            "a/inputs.csv",
            Some(4),
            Some("wR"),
            "outside the accepted range",
        ),
        // Item 9: an output before the inputs start names the file and row.
        (
            ins.clone(),
            outs.replace("t,beta\n0,", "t,beta\n-5,"),
            "a/outputs.csv",
            Some(2),
            Some("t"),
            "output time -5 is before the first input time 0",
        ),
        // Outputs long after the inputs end (the integration would run on).
        (
            ins.clone(),
            format!("{outs}1e9,0.1\n"),
            "a/outputs.csv",
            Some(14),
            Some("t"),
            "after",
        ),
        // A control character is not a number.
        (
            ins.replace("\n2,", "\n\u{fffd}2,")
                .replace('\u{fffd}', "\u{1}"),
            outs.clone(),
            "a/inputs.csv",
            Some(6),
            Some("t"),
            "not a number",
        ),
        (
            ins.replace("t,wR,wL", "t,\"wR,wL"),
            outs.clone(),
            "a/inputs.csv",
            Some(1),
            Some("2"),
            "quoted field is not closed",
        ),
        (
            ins.clone(),
            "t,beta\n0,1\n".into(),
            "a/outputs.csv",
            None,
            None,
            "only 1 output samples",
        ),
    ];
    for (i, o, f, row, col, msg) in cases {
        let e = read(&one(i, o)).unwrap_err();
        assert_eq!(e.file, f, "{e}");
        assert_eq!(e.row, row, "{e}");
        assert_eq!(e.column.as_deref(), col, "{e}");
        assert!(e.message().contains(msg), "{e}");
    }
    let mut bytes = ins.into_bytes();
    let at = bytes.iter().position(|&b| b == b'\n').unwrap() + 1;
    bytes.splice(at..at, [b'\n', b'\r', 0xff, 0xfe]);
    let e = read(&one(bytes, outs.clone())).unwrap_err();
    assert_eq!((e.file.as_str(), e.row), ("a/inputs.csv", Some(4)), "{e}");
    assert!(e.message().contains("invalid UTF-8"), "{e}");
    let mut f = one(plain_inputs(), outs);
    f.meta = file("dataset.json", "{\"d0\": 1e308}");
    let e = read(&f).unwrap_err();
    assert_eq!(
        (e.file.as_str(), e.column.as_deref()),
        ("dataset.json", Some("d0"))
    );
}

/// A simulated dataset round-trips through its CSV text and the reader.
#[test]
fn simulated_files_read_back_exactly() {
    let (data, _) = simulate(&SimOptions::default()).unwrap();
    let files = DatasetFiles {
        meta: file("dataset.json", serde_json::to_string(&data.meta).unwrap()),
        trajectories: data
            .trajectories
            .iter()
            .map(|t| TrajectoryFiles {
                name: t.name.clone(),
                inputs: file(&format!("{}/inputs.csv", t.name), t.inputs.to_csv()),
                outputs: file(&format!("{}/outputs.csv", t.name), t.outputs.to_csv()),
                meta: file(
                    &format!("{}/meta.json", t.name),
                    serde_json::to_string(&t.meta).unwrap(),
                ),
            })
            .collect(),
    };
    assert_eq!(read(&files).unwrap().dataset, data);
}

/// Lines in the file, counted as the reader counts them.
fn lines(bytes: &[u8]) -> usize {
    1 + bytes
        .iter()
        .enumerate()
        .filter(|&(i, &c)| c == b'\n' || (c == b'\r' && bytes.get(i + 1) != Some(&b'\n')))
        .count()
}

fn series_text(t: &[f64], cols: &[&str], v: &[Vec<f64>]) -> String {
    let mut s = Series::new(cols.iter().map(|c| c.to_string()).collect());
    for (k, &tk) in t.iter().enumerate() {
        let row: Vec<Option<f64>> = v.iter().map(|c| Some(c[k])).collect();
        s.push(tk, &row);
    }
    s.to_csv()
}

prop_compose! {
    /// A valid trajectory's two CSV texts and their numbers.
    fn valid()(n_in in 2usize..25, n_out in 10usize..25)
        (steps in prop::collection::vec(0.0f64..2.0, n_in),
         wr in prop::collection::vec(-50.0f64..50.0, n_in),
         wl in prop::collection::vec(-50.0f64..50.0, n_in),
         frac in prop::collection::vec(0.0f64..1.0, n_out),
         beta in prop::collection::vec(-3.2f64..3.2, n_out))
        -> (String, String, Vec<f64>, Vec<f64>)
    {
        let mut t = vec![0.0];
        for s in &steps[1..] { t.push(t[t.len() - 1] + s); }
        let end = t[t.len() - 1];
        let mut to: Vec<f64> = frac.iter().map(|f| f * end).collect();
        to.sort_by(f64::total_cmp);
        (series_text(&t, &INPUTS, &[wr.clone(), wl]), series_text(&to, &OUTPUTS, &[beta]), wr, to)
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Insert(usize, u8),
    Delete(usize),
    Replace(usize, u8),
    Duplicate(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    // Bytes that matter to the reader, and any byte.
    let byte = prop_oneof![
        prop::sample::select(b",\n\r\"#-.e0123456789 tabinf".to_vec()),
        any::<u8>()
    ];
    prop_oneof![
        (any::<usize>(), byte.clone()).prop_map(|(i, b)| Mutation::Insert(i, b)),
        any::<usize>().prop_map(Mutation::Delete),
        (any::<usize>(), byte).prop_map(|(i, b)| Mutation::Replace(i, b)),
        (any::<usize>(), 1usize..40).prop_map(|(i, n)| Mutation::Duplicate(i, n)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let n = bytes.len();
    match *m {
        Mutation::Insert(i, b) => bytes.insert(i % (n + 1), b),
        Mutation::Delete(i) => {
            bytes.remove(i % n);
        }
        Mutation::Replace(i, b) => bytes[i % n] = b,
        Mutation::Duplicate(i, len) => {
            let a = i % n;
            let piece: Vec<u8> = bytes[a..(a + len).min(n)].to_vec();
            bytes.splice(a..a, piece);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 300,
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "tests/reader.proptest-regressions",
        ))),
        ..ProptestConfig::default()
    })]

    /// Valid files are read to their numbers, through every benign variation.
    #[test]
    fn valid_files_read_to_their_numbers(
        (ins, outs, wr, to) in valid(),
        crlf in any::<bool>(), cr in any::<bool>(), bom in any::<bool>(),
        trailing in any::<bool>(), comment in any::<bool>(),
    ) {
        let vary = |s: &str| {
            let mut s = s.to_string();
            if trailing { s = s.replace('\n', ",\n"); }
            if comment { s = format!("# a comment\n{}", s.replace('\n', "\n\n")); }
            if crlf { s = s.replace('\n', "\r\n"); } else if cr { s = s.replace('\n', "\r"); }
            if bom { s = format!("\u{feff}{s}"); }
            s
        };
        let r = read(&one(vary(&ins), vary(&outs))).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let tr = &r.dataset.trajectories[0];
        let got_wr: Vec<f64> = tr.inputs.column("wR").unwrap().iter().map(|v| v.unwrap()).collect();
        prop_assert_eq!(got_wr, wr);
        prop_assert_eq!(tr.outputs.t(), &to);
        prop_assert!(r.warnings.is_empty());
    }

    /// Mutated files never panic; a rejection names one of the files and a
    /// line inside it; an accepted file holds only finite bounded values.
    #[test]
    fn mutated_files_are_read_or_rejected_with_a_place(
        (ins, outs, _, _) in valid(),
        which in 0usize..3,
        muts in prop::collection::vec(mutation(), 1..6),
    ) {
        let mut files = [ins.into_bytes(), outs.into_bytes(), b"{\"d0\": 1.2, \"noise\": {\"beta\": 0.01}}".to_vec()];
        for m in &muts { apply(&mut files[which], m); }
        let mut f = one(files[0].clone(), files[1].clone());
        f.meta = file("dataset.json", files[2].clone());
        match read(&f) {
            Ok(r) => {
                for tr in &r.dataset.trajectories {
                    for s in [&tr.inputs, &tr.outputs] {
                        prop_assert!(s.t().windows(2).all(|w| w[0] <= w[1]));
                        for v in s.values().iter().flatten().flatten() {
                            prop_assert!(v.is_finite() && v.abs() <= MAX_ABS_VALUE);
                        }
                    }
                }
            }
            Err(e) => {
                let k = ["a/inputs.csv", "a/outputs.csv", "dataset.json"]
                    .iter()
                    .position(|p| *p == e.file);
                prop_assert!(k.is_some(), "unknown file in {}", e);
                if let Some(row) = e.row {
                    prop_assert!(row >= 1 && row <= lines(&files[k.unwrap()]), "{} (lines {})", e, lines(&files[k.unwrap()]));
                }
                prop_assert!(!e.message().is_empty());
            }
        }
    }
}

/// One bearing of 1e308 made calibrate run for minutes (an
/// SVD that never converged). The reader now refuses it; the estimators,
/// given it anyway (or a large value within the bound), return.
#[test]
fn extreme_values_do_not_hang_the_estimators() {
    use obsan_calib::{calib_predictor, calibrate, CalibrateOptions, Method};
    let p = calib_predictor();
    for v in [1e308, MAX_ABS_VALUE, f64::NAN] {
        let (mut data, _) = simulate(&SimOptions::default()).unwrap();
        data.trajectories[1].outputs.values_mut(0)[2] = Some(v);
        for m in [Method::Det, Method::Ls, Method::Ml] {
            let o = CalibrateOptions::for_dataset(&data, m);
            // Either answer is acceptable; returning is the point.
            if let Ok(r) = calibrate(&data, Some(&p), &o) {
                let _ = r.calibration.sd();
            }
        }
    }
}
