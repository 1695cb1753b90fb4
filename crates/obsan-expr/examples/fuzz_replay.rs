//! Replays the `expr` fuzz target's work (fuzz/fuzz_targets/expr.rs: parse,
//! canon, print, re-read, F_p evaluation) on every file of a corpus folder and
//! lists the slowest, to profile without libFuzzer:
//! `cargo run --release -p obsan-expr --example fuzz_replay -- fuzz/corpus/expr [N]`.

use obsan_expr::{Budget, Ctx, SplitMix};
use std::time::{Duration, Instant};

/// The target's body without its oracles' assertions (timing only).
fn replay(data: &[u8]) {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let budget = || Budget {
        max_terms: 2_000,
        max_nodes: 200_000,
        max_degree: 300,
        deadline: Some(Instant::now() + Duration::from_secs(2)),
    };
    let mut ctx = Ctx::new();
    ctx.set_budget(budget());
    let Ok(id) = ctx.parse(src) else { return };
    let Ok(r) = ctx.try_canon(id) else { return };
    let Ok(back) = ctx.within_budget(|c| c.from_canonical(&r)) else {
        return;
    };
    let Ok(text) = ctx.try_ratfun_text(&r, 1 << 20) else {
        return;
    };
    ctx.set_budget(budget());
    if let Ok(t) = ctx.parse(&text) {
        let _ = ctx.try_canon(t);
    }
    let mut rng = SplitMix(data.len() as u64);
    for _ in 0..4 {
        if let Ok(pt) = ctx.random_fp_point(&mut rng, &|_| None) {
            let _ = ctx.eval_fp(&[id, back], &pt);
        }
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let dir = args.next().unwrap_or_else(|| "fuzz/corpus/expr".into());
    let n: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(10);
    let mut times = Vec::new();
    let mut paths: Vec<_> = match std::fs::read_dir(&dir) {
        Ok(d) => d.filter_map(|e| e.ok().map(|e| e.path())).collect(),
        Err(e) => {
            eprintln!("{dir}: {e}");
            std::process::exit(2);
        }
    };
    paths.sort();
    let all = Instant::now();
    for p in &paths {
        let Ok(data) = std::fs::read(p) else { continue };
        let t = Instant::now();
        replay(&data);
        times.push((t.elapsed().as_secs_f64(), p.display().to_string()));
    }
    let total = all.elapsed().as_secs_f64();
    times.sort_by(|a, b| b.0.total_cmp(&a.0));
    let slow = times.iter().filter(|t| t.0 > 0.2).count();
    println!(
        "{} files, {total:.2} s, {slow} over 200 ms; slowest {n}:",
        times.len()
    );
    for (t, p) in times.iter().take(n) {
        println!("{t:>8.3} s  {p}");
    }
}
