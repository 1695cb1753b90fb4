//! The MRCLAM importer (obsan_data::mrclam_convert) on framed logs.
//!
//! Framing: the first byte picks the window (1 + b/4 s) and the outputs
//! (odd: Vicon poses); the rest is split on NUL bytes into the odometry,
//! measurement, landmark and ground-truth texts (a missing fourth part is an
//! absent ground-truth file). Oracles: no panic; a rejection names one of the
//! four files or --window; an accepted dataset has windows of at least two
//! input rows whose meta gives every landmark's lx/ly, and finite values.
#![no_main]

use libfuzzer_sys::fuzz_target;
use obsan_data::{mrclam_convert, MrclamOutputs, MrclamText};

const NAMES: [&str; 4] = ["odo.txt", "meas.txt", "lms.dat", "gt.txt"];

fuzz_target!(|data: &[u8]| {
    let Some((&head, rest)) = data.split_first() else {
        return;
    };
    let parts: Vec<String> = rest
        .split(|&b| b == 0)
        .take(4)
        .map(|p| String::from_utf8_lossy(p).into_owned())
        .collect();
    let get = |i: usize| parts.get(i).map(String::as_str).unwrap_or("");
    let t = MrclamText {
        odometry: (get(0), NAMES[0]),
        measurements: (get(1), NAMES[1]),
        landmarks: (get(2), NAMES[2]),
        groundtruth: parts.get(3).map(|g| (g.as_str(), NAMES[3])),
    };
    let window = 1.0 + f64::from(head / 2) / 4.0;
    let what = if head % 2 == 1 {
        MrclamOutputs::ViconPoses
    } else {
        MrclamOutputs::Landmarks
    };
    match mrclam_convert(&t, window, 1, what) {
        Err(e) => assert!(
            NAMES.contains(&e.file.as_str()) || e.file == "--window",
            "{e}"
        ),
        Ok((d, _truth)) => {
            assert!(!d.trajectories.is_empty());
            for tr in &d.trajectories {
                assert!(tr.inputs.len() >= 2, "{}", tr.name);
                for v in tr.inputs.values().iter().chain(tr.outputs.values()) {
                    assert!(v.iter().flatten().all(|x| x.is_finite()), "{}", tr.name);
                }
                if what == MrclamOutputs::Landmarks {
                    for c in tr
                        .outputs
                        .columns()
                        .iter()
                        .filter_map(|n| n.strip_prefix('r'))
                    {
                        assert!(tr.meta.contains_key(&format!("lx{c}")), "{} lx{c}", tr.name);
                        assert!(tr.meta.contains_key(&format!("ly{c}")), "{} ly{c}", tr.name);
                    }
                }
            }
        }
    }
});
