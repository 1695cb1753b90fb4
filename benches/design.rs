//! `obsan design`: minimal sets among 10 candidate sensors
//! (1,024 subsets) on vins.sys, a suite model (target < 5 s), and the input
//! families of calib.sys. Run: `cargo bench --bench design` (`-- quick`).

use obsan_analysis::{
    sensor_design::design_inputs, sensor_design::design_outputs, sensor_design::Candidate,
    sensor_design::DesignOptions,
};
use obsan_model::System;
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// Ten single-output candidates for vins.sys: position, velocity and
/// landmark coordinates, two attitude entries (R(q) rows over |q|^2).
const CANDIDATES: [(&str, &str); 10] = [
    ("gx", "rx"),
    ("gy", "ry"),
    ("gz", "rz"),
    ("dvx", "vx"),
    ("dvy", "vy"),
    ("lx", "pfx"),
    ("ly", "pfy"),
    ("lz", "pfz"),
    (
        "mx",
        "(qw^2 + qx^2 - qy^2 - qz^2)/(qw^2 + qx^2 + qy^2 + qz^2)",
    ),
    ("my", "2*(qx*qy + qw*qz)/(qw^2 + qx^2 + qy^2 + qz^2)"),
];

fn time<F: FnMut()>(reps: usize, mut f: F) -> (Duration, Duration) {
    let mut v: Vec<Duration> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed()
        })
        .collect();
    v.sort();
    (v[v.len() / 2], v[0])
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let reps = if quick { 3 } else { 7 };
    let src = std::fs::read_to_string(format!("{ROOT}/systems/vins.sys")).expect("vins.sys");
    let base = System::parse(&src, "vins.sys")
        .expect("parses")
        .output_names()
        .len();
    let mut text = src.clone();
    for (n, e) in CANDIDATES {
        text.push_str(&format!("\noutput {n} = {e}\n"));
    }
    let sys = System::parse(&text, "vins.sys").expect("parses");
    let nf = sys.normal_form(None, &[]).expect("normal form");
    let cands: Vec<Candidate> = CANDIDATES
        .iter()
        .enumerate()
        .map(|(i, (n, _))| Candidate {
            name: n.to_string(),
            cost: 1.0,
            outputs: vec![base + i],
        })
        .collect();
    println!("== median (min) of {reps} runs, library calls");
    let mut screened = 0;
    let mut found = 0;
    let (med, min) = time(reps, || {
        let r = design_outputs(&nf, base, &cands, None, &DesignOptions::default()).expect("design");
        screened = r.subsets_screened;
        found = r.sets.len();
    });
    println!(
        "design, vins.sys, 10 candidates (1,024 subsets; {screened} screened, the rest supersets of the {found} minimal sets found), symmetries included: {:.1} ms ({:.1})",
        med.as_secs_f64() * 1e3,
        min.as_secs_f64() * 1e3
    );
    let no_sym = DesignOptions {
        symmetries: false,
        ..Default::default()
    };
    let (med, min) = time(reps, || {
        design_outputs(&nf, base, &cands, None, &no_sym).expect("design");
    });
    println!(
        "  the same without the model's symmetries: {:.1} ms ({:.1})",
        med.as_secs_f64() * 1e3,
        min.as_secs_f64() * 1e3
    );
    let calib = System::parse(
        &std::fs::read_to_string(format!("{ROOT}/systems/calib.sys")).expect("calib.sys"),
        "calib.sys",
    )
    .expect("parses");
    let (med, min) = time(reps, || {
        design_inputs(&calib, &[], &DesignOptions::default()).expect("families");
    });
    println!(
        "design (input families), calib.sys: {:.1} ms ({:.1})",
        med.as_secs_f64() * 1e3,
        min.as_secs_f64() * 1e3
    );
}
