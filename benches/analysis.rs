//! Analysis benchmark: the paper's computations, as library calls and as
//! whole `obsan` processes, and the scaling of the rank test with the state
//! dimension. Run: `cargo bench --bench analysis` (`-- quick` for fewer runs).

use obsan_analysis::{
    rank, rank_symbolic, symmetries, verify_decomposition, Decomposition, RankOptions,
};
use obsan_model::System;
use std::process::Command;
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn median(mut v: Vec<Duration>) -> (Duration, Duration) {
    v.sort();
    (v[v.len() / 2], v[0])
}

fn load(path: &str) -> System {
    let src = std::fs::read_to_string(format!("{ROOT}/{path}")).expect("system file");
    System::parse(&src, path).expect("parses")
}

fn time<F: FnMut()>(reps: usize, mut f: F) -> (Duration, Duration) {
    median(
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed()
            })
            .collect(),
    )
}

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// A unicycle with odometry (v, omega) observing n landmarks of unknown
/// position by bearing: 3 + 2n states, rank 2n (translation and rotation of
/// the whole scene are the symmetries).
fn bearing_slam(n: usize) -> String {
    let mut s = String::from("system bearing_slam\nstate x, y, theta\ninput v, omega\n");
    let ps: Vec<String> = (1..=n)
        .flat_map(|i| [format!("lx{i}"), format!("ly{i}")])
        .collect();
    s.push_str(&format!("param {}\n", ps.join(", ")));
    s.push_str("x' = v*cos(theta)\ny' = v*sin(theta)\ntheta' = omega\n");
    for i in 1..=n {
        s.push_str(&format!(
            "output b{i} = atan2(ly{i} - y, lx{i} - x) - theta\n"
        ));
    }
    s
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let reps = if quick { 3 } else { 11 };
    println!("== library calls, median (min) of {reps} runs");
    let cases: [(&str, Option<&str>, bool); 5] = [
        ("systems/calib.sys", None, false),
        ("systems/calib.sys", Some("q"), false),
        ("systems/calib_q_nopsi.sys", None, true),
        ("systems/psi.sys", None, true),
        ("systems/calib.sys", Some("q"), true),
    ];
    for (path, input, sym) in cases {
        let sys = load(path);
        let (med, min) = time(reps, || {
            let mut nf = sys.normal_form(input, &[]).expect("normal form");
            let r = rank(&mut nf, RankOptions::default()).expect("rank");
            if sym {
                symmetries(&mut nf, &r).expect("symmetries");
            }
        });
        let what = if sym { "rank + symmetries" } else { "rank" };
        let inp = input.map(|i| format!(" --input {i}")).unwrap_or_default();
        println!("{what:18} {path}{inp}: {:.2} ms ({:.2})", ms(med), ms(min));
    }
    // Rank by jets against the older graph route: the paper's
    // systems and the order-10 pharmacokinetic model (the graph route takes
    // tens of seconds there, so it runs once, and not with `quick`).
    println!("\n== rank: jets vs the graph route (rank_symbolic), median (min)");
    let pk = "crates/obsan-analysis/tests/data/pharmacokinetics.sys";
    for (path, input) in [
        ("systems/calib.sys", None),
        ("systems/calib.sys", Some("q")),
        ("systems/psi.sys", None),
        ("systems/classic/hiv.sys", None),
        (pk, None),
    ] {
        let sys = load(path);
        let mut order = 0;
        let (med, min) = time(reps, || {
            let mut nf = sys.normal_form(input, &[]).expect("normal form");
            order = rank(&mut nf, RankOptions::default())
                .expect("rank")
                .max_order;
        });
        let slow = path == pk;
        let sym = if slow && quick {
            "(skipped with quick)".to_string()
        } else {
            let (smed, smin) = time(if slow { 1 } else { reps }, || {
                let mut nf = sys.normal_form(input, &[]).expect("normal form");
                rank_symbolic(&mut nf, RankOptions::default()).expect("rank");
            });
            format!("{:.2} ms ({:.2})", ms(smed), ms(smin))
        };
        let inp = input.map(|i| format!(" --input {i}")).unwrap_or_default();
        println!(
            "{path}{inp} (order {order}): jets {:.2} ms ({:.2}), graph {sym}",
            ms(med),
            ms(min)
        );
    }
    // Cheap structure (free variable, scaling) before the general route.
    let seir = load("crates/obsan-analysis/tests/data/seir.sys");
    let (med, min) = time(reps, || {
        let mut nf = seir.normal_form(None, &[]).expect("nf");
        let r = rank(&mut nf, RankOptions::default()).expect("rank");
        symmetries(&mut nf, &r).expect("symmetries");
    });
    println!(
        "rank + symmetries seir (free R, scaling N, beta): {:.2} ms ({:.2})\n",
        ms(med),
        ms(min)
    );
    for dec in [
        "systems/decomp_localization.dec",
        "systems/decomp_21_22.dec",
        "systems/decomp_23_24.dec",
    ] {
        let src = std::fs::read_to_string(format!("{ROOT}/{dec}")).expect("dec");
        let d = Decomposition::parse(&src, dec).expect("parses");
        let sys = load(&format!("systems/{}", d.system));
        let (med, min) = time(reps, || {
            let mut nf = sys
                .normal_form(d.restriction.as_deref(), &d.set)
                .expect("nf");
            verify_decomposition(&mut nf, &d, 1).expect("verify");
        });
        println!("verify {dec}: {:.2} ms ({:.2})", ms(med), ms(min));
    }

    println!("\n== whole processes (target/release/obsan), wall time, median (min) of {reps} runs");
    let bin = format!("{ROOT}/target/release/obsan");
    if std::path::Path::new(&bin).exists() {
        for args in [
            vec!["rank", "systems/calib.sys"],
            vec![
                "rank",
                "crates/obsan-analysis/tests/data/pharmacokinetics.sys",
            ],
            vec!["symmetries", "crates/obsan-analysis/tests/data/seir.sys"],
            vec!["symmetries", "systems/calib_q_nopsi.sys"],
            vec!["verify", "systems/decomp_21_22.dec"],
            vec!["verify", "systems/decomp_23_24.dec"],
            vec!["symmetries", "systems/calib.sys", "--input", "q"],
        ] {
            let (med, min) = time(reps, || {
                let st = Command::new(&bin)
                    .args(&args)
                    .current_dir(ROOT)
                    .output()
                    .expect("runs");
                assert!(st.status.success());
            });
            println!(
                "obsan {}: {:.2} ms ({:.2})",
                args.join(" "),
                ms(med),
                ms(min)
            );
        }
    } else {
        println!("(build the release binary first: cargo build --release)");
    }

    println!("\n== scaling: bearing-only observation of n landmarks, 3 + 2n states");
    println!("landmarks | states | rank | Lie derivs evaluated | rank ms median (min)");
    let max_n = if quick { 8 } else { 18 };
    for n in (1..=max_n).filter(|n| *n <= 4 || n % 2 == 0 || *n == max_n) {
        let src = bearing_slam(n);
        let sys = System::parse(&src, "bearing_slam").expect("parses");
        let mut last = None;
        let (med, min) = time(if n > 10 { 3 } else { reps }, || {
            let mut nf = sys.normal_form(None, &[]).expect("nf");
            last = Some(rank(&mut nf, RankOptions::default()).expect("rank"));
        });
        let r = last.expect("ran");
        println!(
            "{n:9} | {:6} | {:4} | {:20} | {:.2} ({:.2})",
            r.n,
            r.rank,
            r.evaluated,
            ms(med),
            ms(min)
        );
    }
}
