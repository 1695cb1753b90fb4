//! The dataset reader (obsan_data::read_dataset) on framed files.
//!
//! Framing: the input is split on NUL bytes into dataset.json, then groups of
//! three per trajectory: inputs.csv, outputs.csv, meta.json (an empty part is
//! an absent file). Oracles: no panic; a rejection names one of the files and
//! a line inside it; an accepted dataset holds finite values within the bound,
//! non-decreasing times, and reads back identically from its own CSV text.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_data::{read_dataset, DataFile, DatasetFiles, TrajectoryFiles, MAX_ABS_VALUE};

fn part(path: String, bytes: &[u8]) -> Option<DataFile> {
    (!bytes.is_empty()).then(|| DataFile {
        path,
        bytes: bytes.to_vec(),
    })
}

fn lines(bytes: &[u8]) -> usize {
    1 + bytes
        .iter()
        .enumerate()
        .filter(|&(i, &c)| c == b'\n' || (c == b'\r' && bytes.get(i + 1) != Some(&b'\n')))
        .count()
}

const INPUTS: [&str; 2] = ["wR", "wL"];
const OUTPUTS: [&str; 1] = ["beta"];

fuzz_target!(|data: &[u8]| {
    let parts: Vec<&[u8]> = data.split(|&b| b == 0).collect();
    let mut files = DatasetFiles {
        meta: part("dataset.json".into(), parts[0]),
        trajectories: Vec::new(),
    };
    for (k, g) in parts[1..].chunks(3).take(4).enumerate() {
        let name = format!("q{k}");
        let get = |i: usize, f: &str| g.get(i).and_then(|b| part(format!("{name}/{f}"), b));
        files.trajectories.push(TrajectoryFiles {
            name: name.clone(),
            inputs: get(0, "inputs.csv"),
            outputs: get(1, "outputs.csv"),
            meta: get(2, "meta.json"),
        });
    }
    let all: Vec<&DataFile> = files
        .meta
        .iter()
        .chain(
            files
                .trajectories
                .iter()
                .flat_map(|t| t.inputs.iter().chain(t.outputs.iter()).chain(t.meta.iter())),
        )
        .collect();
    match read_dataset(&files, &INPUTS, &OUTPUTS) {
        Ok(r) => {
            for t in &r.dataset.trajectories {
                for s in [&t.inputs, &t.outputs] {
                    assert!(s.t().windows(2).all(|w| w[0] <= w[1]), "time goes backwards");
                    for v in s.values().iter().flatten().flatten() {
                        assert!(v.is_finite() && v.abs() <= MAX_ABS_VALUE, "value {v}");
                    }
                }
            }
            // The accepted numbers read back from their own CSV text.
            let back = DatasetFiles {
                meta: None,
                trajectories: r
                    .dataset
                    .trajectories
                    .iter()
                    .map(|t| TrajectoryFiles {
                        name: t.name.clone(),
                        inputs: part("i".into(), t.inputs.to_csv().as_bytes()),
                        outputs: part("o".into(), t.outputs.to_csv().as_bytes()),
                        meta: None,
                    })
                    .collect(),
            };
            let again = read_dataset(&back, &INPUTS, &OUTPUTS).expect("re-read");
            for (a, b) in again
                .dataset
                .trajectories
                .iter()
                .zip(&r.dataset.trajectories)
            {
                assert_eq!((&a.inputs, &a.outputs), (&b.inputs, &b.outputs));
            }
        }
        Err(e) => {
            assert!(!e.message().is_empty());
            if let Some(f) = all.iter().find(|f| f.path == e.file) {
                if let Some(row) = e.row {
                    assert!(row >= 1 && row <= lines(&f.bytes), "{e}: beyond the file");
                }
            } else {
                // An absent file or the dataset as a whole: no line.
                assert!(e.row.is_none(), "{e}: a line in no file");
            }
        }
    }
});
