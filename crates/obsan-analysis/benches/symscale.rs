//! Scaling of the symmetries with the number of parts:
//! k copies of the paper's calibration system (eq. 16 under the circular
//! restriction (17), `--input q`), stacked into one system with renamed
//! states and params (independent copies, n = 7k) or with the five params
//! shared (several experiments of one robot, n = 2k + 5). Prints the time of
//! the rank test (by blocks, as `obsan symmetries` runs it) and of the
//! symmetries, their ratio per doubling, and the peak resident memory.
//! Run: `cargo bench -p obsan-analysis --bench symscale` (`-- quick`: up to n = 56).

use obsan_analysis::{rank_by_blocks, symmetries_with, Certificate, RankOptions, SymmetryOptions};
use obsan_model::System;
use std::time::Instant;

/// k copies of calib.sys (written from eq. 16 and 17 of the paper, as
/// systems/calib.sys); `shared`: one set of params for all copies.
pub fn stack(k: usize, shared: bool) -> String {
    let mut states = Vec::new();
    let mut params = Vec::new();
    let mut inputs = Vec::new();
    let mut body = String::new();
    let mut restrict = Vec::new();
    for i in 1..=k {
        let p = |s: &str| {
            if shared {
                s.to_string()
            } else {
                format!("{s}{i}")
            }
        };
        let (mu, g) = (format!("mu{i}"), format!("gamma{i}"));
        let (phi, psi, eta, delta, xi) = (p("phi"), p("psi"), p("eta"), p("delta"), p("xi"));
        let (wr, wl) = (format!("wR{i}"), format!("wL{i}"));
        states.extend([mu.clone(), g.clone()]);
        if !shared {
            params.extend([
                phi.clone(),
                psi.clone(),
                eta.clone(),
                delta.clone(),
                xi.clone(),
            ]);
        }
        inputs.extend([wr.clone(), wl.clone()]);
        body.push_str(&format!(
            "{mu}' = -{mu}^2*{eta}*({wr} + {delta}*{wl})*cos({g} - {phi})\n\
             {g}' = {xi}*({wr} - {delta}*{wl}) - {mu}*{eta}*({wr} + {delta}*{wl})*sin({g} - {phi})\n\
             output beta{i} = atan2(sin({g}), -{mu} - cos({g})) - {psi}\n"
        ));
        restrict.push(format!("{wr} = nu, {wl} = q*nu"));
    }
    if shared {
        params = ["phi", "psi", "eta", "delta", "xi"]
            .map(String::from)
            .to_vec();
    }
    format!(
        "system stack{k}\nstate {}\nparam {}\nconst q\ninput {}\n{body}restrict q: {}\n",
        states.join(", "),
        params.join(", "),
        inputs.join(", "),
        restrict.join(", ")
    )
}

/// Peak resident set of this process (VmHWM), in MB; 0 where /proc is absent.
fn peak_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

/// CPU time of this process (user + system) in seconds, from /proc/self/stat
/// in clock ticks (USER_HZ, 100 on Linux); 0 where /proc is absent. On a
/// loaded machine this is the figure to compare, not the wall time.
fn cpu_secs() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // Fields after the parenthesised command name; utime, stime are 14, 15.
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) / 100.0)
        })
        .unwrap_or(0.0)
}

fn run(k: usize, shared: bool) -> (usize, usize, usize, f64, f64, f64, String) {
    let src = stack(k, shared);
    let sys = System::parse(&src, "stack.sys").expect("parses");
    let mut nf = sys.normal_form(Some("q"), &[]).expect("normal form");
    let t = Instant::now();
    let r = rank_by_blocks(&mut nf, RankOptions::default()).expect("rank");
    let t_rank = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let c = cpu_secs();
    let s = symmetries_with(&mut nf, &r, &SymmetryOptions::default()).expect("symmetries");
    let t_sym = t.elapsed().as_secs_f64();
    let c_sym = cpu_secs() - c;
    let cert = match &s.certificate {
        Certificate::Random(c) => format!("random, error <= {:.0e}", c.error_bound),
        Certificate::Invariance(_) => "invariance".into(),
        Certificate::Closure => "closure".into(),
        Certificate::Span => "span".into(),
    };
    (
        r.n,
        s.rank,
        s.vectors.len(),
        t_rank,
        t_sym,
        c_sym,
        format!("{cert}; {} blocks", s.blocks),
    )
}

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let ks: &[usize] = if quick {
        &[1, 2, 4, 8]
    } else {
        &[1, 2, 4, 8, 16, 32]
    };
    for shared in [false, true] {
        println!(
            "\n{} copies of calib.sys, --input q",
            if shared {
                "shared-param"
            } else {
                "independent"
            }
        );
        println!("copies     n  rank  syms   rank s    syms s  syms cpu s  cpu ratio  certificate");
        let mut prev: Option<f64> = None;
        for &k in ks {
            let (n, rank, syms, tr, ts, cs, cert) = run(k, shared);
            let ratio = prev.map_or("        -".to_string(), |p| format!("{:9.2}", cs / p));
            println!("{k:6} {n:5} {rank:5} {syms:5} {tr:8.3} {ts:9.3} {cs:11.2} {ratio}  {cert}");
            prev = Some(cs);
        }
    }
    println!(
        "\npeak resident memory of the whole run: {:.0} MB",
        peak_mb()
    );
}
