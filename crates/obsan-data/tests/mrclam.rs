//! The MRCLAM converter on small synthetic logs (the real files are read by
//! tests/cli/diagnose.rs when present).

use obsan_data::{mrclam_convert, mrclam_model_text, MrclamOutputs, MrclamText};

const LMS: &str = " 18 \t 0.5 \t -1.0 \t 0.0001 \t 0.001\n 45 \t 2.0 \t 1.0 \t 0.0001 \t 0.001\n";

fn odometry(n: usize) -> String {
    (0..n)
        .map(|k| format!("{:.2} 0.1 0.05\n", k as f64 * 0.02))
        .collect()
}

#[test]
fn windows_hold_measurements_landmarks_and_skip_other_robots() {
    let odo = odometry(1000); // 20 s
    let meas: String = (0..40)
        .map(|k| {
            format!(
                "{:.1} {} 1.5 0.1\n",
                k as f64 * 0.5,
                if k % 4 == 0 { 5 } else { 18 }
            )
        })
        .collect();
    let t = MrclamText {
        odometry: (&odo, "o.txt"),
        measurements: (&meas, "m.txt"),
        landmarks: (LMS, "l.dat"),
        groundtruth: None,
    };
    let (d, truth) = mrclam_convert(&t, 10.0, 5, MrclamOutputs::Landmarks).unwrap();
    assert_eq!(d.trajectories.len(), 2);
    assert!(truth.is_empty());
    let w = &d.trajectories[0];
    assert_eq!(w.meta["lx45"], 2.0);
    // Barcode 5 is a robot: 3 of every 4 measurements are kept, 15 in 10 s.
    assert_eq!(
        w.outputs.column("r18").unwrap().iter().flatten().count(),
        15
    );
    assert!(w.outputs.column("r45").unwrap().iter().all(Option::is_none));
    assert_eq!(w.inputs.columns(), ["v", "omega"]);
}

#[test]
fn malformed_lines_name_file_row_and_column() {
    let odo = "0.0 0.1 0.0\n0.02 x 0.0\n";
    let t = MrclamText {
        odometry: (odo, "o.txt"),
        measurements: ("", "m.txt"),
        landmarks: (LMS, "l.dat"),
        groundtruth: None,
    };
    let e = mrclam_convert(&t, 10.0, 1, MrclamOutputs::Landmarks)
        .unwrap_err()
        .to_string();
    assert!(e.contains("o.txt:2 (column 2)") && e.contains("'x'"), "{e}");
    let odo = "0.5 0.1 0.0\n0.2 0.1 0.0\n";
    let t = MrclamText {
        odometry: (odo, "o.txt"),
        ..t
    };
    let e = mrclam_convert(&t, 10.0, 1, MrclamOutputs::Landmarks)
        .unwrap_err()
        .to_string();
    assert!(e.contains("o.txt:2") && e.contains("backwards"), "{e}");
    let odo = odometry(100);
    let t = MrclamText {
        odometry: (&odo, "o.txt"),
        measurements: ("1.0 18 nan 0.1\n", "m.txt"),
        ..t
    };
    let e = mrclam_convert(&t, 10.0, 1, MrclamOutputs::Landmarks)
        .unwrap_err()
        .to_string();
    assert!(e.contains("m.txt:1 (column 3)"), "{e}");
}

#[test]
fn the_shipped_model_is_the_generated_one() {
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../systems/mrclam.sys"
    ))
    .unwrap();
    let codes = [18, 45, 7, 63, 16, 90, 61, 81, 9, 25, 36, 70, 54, 72, 27];
    assert_eq!(shipped, mrclam_model_text(&codes));
}

#[test]
fn vicon_poses_replace_the_landmark_outputs_in_the_same_windows() {
    let odo = odometry(1000); // 20 s
    let meas: String = (0..40)
        .map(|k| format!("{:.1} 18 1.5 0.1\n", k as f64 * 0.5))
        .collect();
    // Vicon at 100 Hz: x = t, y = -t, theta = 0.1 t.
    let gt: String = (0..2000)
        .map(|k| {
            let t = k as f64 * 0.01;
            format!("{t:.2} {t} {} {}\n", -t, 0.1 * t)
        })
        .collect();
    let t = MrclamText {
        odometry: (&odo, "o.txt"),
        measurements: (&meas, "m.txt"),
        landmarks: (LMS, "l.dat"),
        groundtruth: Some((&gt, "g.txt")),
    };
    let (lm, _) = mrclam_convert(&t, 10.0, 5, MrclamOutputs::Landmarks).unwrap();
    let (vp, truth) = mrclam_convert(&t, 10.0, 5, MrclamOutputs::ViconPoses).unwrap();
    let names = |d: &obsan_data::Dataset| -> Vec<String> {
        d.trajectories.iter().map(|w| w.name.clone()).collect()
    };
    assert_eq!(names(&lm), names(&vp));
    assert_eq!(truth.len(), 2);
    let w = &vp.trajectories[1];
    assert_eq!(w.outputs.columns(), ["px", "py", "pth"]);
    // One pose every POSE_INTERVAL s over the window's input span.
    let n = w.outputs.len() as f64;
    let span = w.inputs.t().last().unwrap() - w.inputs.t()[0];
    assert!(
        (n - 1.0 - span / obsan_data::POSE_INTERVAL).abs() <= 1.0,
        "{n}"
    );
    for (k, tk) in w.outputs.t().iter().enumerate() {
        let row: Vec<f64> = (0..3).map(|c| w.outputs.values()[c][k].unwrap()).collect();
        assert!((row[0] - tk).abs() < 1e-9 && (row[1] + tk).abs() < 1e-9);
        assert!((row[2] - 0.1 * tk).abs() < 1e-9);
    }
    // Without ground truth there is nothing to write.
    let t = MrclamText {
        groundtruth: None,
        ..t
    };
    let e = mrclam_convert(&t, 10.0, 5, MrclamOutputs::ViconPoses).unwrap_err();
    assert!(e.to_string().contains("ground-truth"), "{e}");
}

/// An empty landmark file was blamed on the measurement file (no
/// measurement could match a landmark); the error now names the landmark file.
#[test]
fn an_empty_landmark_file_is_named() {
    let odo = odometry(100);
    let meas = "0.5 18 1.5 0.1\n";
    for lms in ["", "# only a comment\n"] {
        let t = MrclamText {
            odometry: (&odo, "o.txt"),
            measurements: (meas, "m.txt"),
            landmarks: (lms, "l.dat"),
            groundtruth: None,
        };
        let e = mrclam_convert(&t, 10.0, 1, MrclamOutputs::Landmarks).unwrap_err();
        assert_eq!(e.file, "l.dat", "{e}");
        assert!(e.to_string().contains("no landmark"), "{e}");
    }
}
