//! Several experiments and known initial conditions: the
//! multi-experiment rank of calib.sys with three circles (target < 0.05 s),
//! `--experiments auto` on every suite model (target < 1 s each), and the
//! known-initial-condition test. Run: `cargo bench --bench experiments`
//! (`-- quick` for fewer runs).

use obsan_analysis::{
    multi_experiment::experiments_auto, multi_experiment::rank_known,
    multi_experiment::AutoOptions, multi_experiment::Known, multi_experiment::KnownOptions, rank,
    RankOptions,
};
use obsan_expr::Q;
use obsan_model::{Experiment, System};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn load(path: &str) -> System {
    let src = std::fs::read_to_string(format!("{ROOT}/{path}")).expect("system file");
    System::parse(&src, path).expect("parses")
}

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

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let reps = if quick { 3 } else { 11 };
    println!("== median (min) of {reps} runs, library calls (stacking included)");
    let calib = load("systems/calib.sys");
    let circle = |n: i64, d: i64| Experiment {
        restriction: Some("q".into()),
        set: vec![("q".into(), Q::new(n.into(), d.into()))],
    };
    let three = [circle(9, 10), circle(0, 1), circle(-1, 1)];
    let (med, min) = time(reps, || {
        let mut nf = calib.stacked_normal_form(&three).expect("stack");
        let r = rank(&mut nf, RankOptions::default()).expect("rank");
        assert_eq!(r.rank, 11);
    });
    println!(
        "rank, calib.sys, 3 circles (q = 0.9, 0, -1): {:.2} ms ({:.2})",
        ms(med),
        ms(min)
    );
    let (med, min) = time(reps, || {
        let r = experiments_auto(&calib, Some("q"), &[], AutoOptions::default()).expect("auto");
        assert_eq!(r.experiments, 3);
    });
    println!(
        "--experiments auto, calib.sys --input q (with 7 special values): {:.2} ms ({:.2})",
        ms(med),
        ms(min)
    );
    let ric = System::parse(
        "system riccati\nstate S\nparam a\nS' = 1 + a*S^2\noutput y = S\n",
        "riccati.sys",
    )
    .expect("parses");
    let (med, min) = time(reps, || {
        let mut nf = ric.normal_form(None, &[]).expect("nf");
        let k = [Known {
            index: 0,
            value: Some(Q::zero()),
        }];
        rank_known(&mut nf, &k, KnownOptions::default()).expect("known");
    });
    println!("--known S=0, riccati: {:.2} ms ({:.2})", ms(med), ms(min));

    println!("\n== --experiments auto on every suite model (systems/benchmarks), median of {reps}");
    let mut paths: Vec<String> = std::fs::read_dir(format!("{ROOT}/systems/benchmarks"))
        .expect("dir")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".sys"))
        .collect();
    paths.sort();
    let mut worst = (Duration::ZERO, String::new());
    let mut total = Duration::ZERO;
    for p in &paths {
        let sys = load(&format!("systems/benchmarks/{p}"));
        let mut k = 0;
        let (med, _) = time(reps, || {
            k = experiments_auto(&sys, None, &[], AutoOptions::default())
                .expect("auto")
                .experiments;
        });
        total += med;
        if med > worst.0 {
            worst = (med, p.clone());
        }
        println!("  {p:32} {:8.2} ms  ({k} experiment(s))", ms(med));
    }
    println!(
        "{} models: {:.1} ms in all, slowest {} {:.2} ms",
        paths.len(),
        ms(total),
        worst.1,
        ms(worst.0)
    );
}
