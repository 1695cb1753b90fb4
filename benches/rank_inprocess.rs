//! `obsan rank` timed in-process: the CPU time of the command itself (argument parsing, reading
//! and parsing the model, its normal form, the rank test, the JSON), without the process start
//! that `obsan rank` as a child process pays (about 1.6 ms here: `obsan --version` alone). This
//! is what symident's `detect()` time measures on its side (benches/peers/symident_suite.py
//! times `detect()` inside an interpreter already running, SymPy imported): the like-for-like
//! comparison (docs/benchmarks.md, "Side by side with symident on the SI.jl models").
//!
//! `cargo bench --bench rank_inprocess [-- FILTER] [--repeat K] [--tsv FILE]`: every suite model
//! whose path contains FILTER (default `si-jl`), K runs each (default 20, after one warm-up run),
//! through `obsan_cli::run_json` (the entry point the Python package uses). Prints one Markdown
//! row per model with the least and the median CPU time of the K runs (the process's CPU clock,
//! `CLOCK_PROCESS_CPUTIME_ID`: every thread, nothing else; the bench thread waits blocked while
//! the command's thread runs) and the least wall time, and the least CPU time of the computation
//! alone on a model parsed beforehand (normal form, rank, undecided atoms: what symident's
//! `detect()` does with its `Model` built); `--tsv FILE` also writes `path<TAB>command
//! seconds<TAB>computation seconds` lines, which `symident_suite.py --inprocess FILE` divides
//! symident's time by.

use std::path::Path;
use std::time::Instant;

/// The process's CPU time (all threads), in seconds: CLOCK_PROCESS_CPUTIME_ID.
fn cpu_seconds() -> f64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ProcessCPUTime);
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

/// The rank test's computation alone, on a model parsed beforehand (as symident's `detect()`
/// gets its `Model` built): the normal form, `obsan_analysis::rank` and the undecided-atoms
/// check, no argument parsing, file reading or JSON.
fn compute_once(sys: &obsan_model::System) -> Option<usize> {
    let mut nf = sys.normal_form(None, &[]).ok()?;
    let r = obsan_analysis::rank(&mut nf, obsan_analysis::RankOptions::default()).ok()?;
    std::hint::black_box(obsan_analysis::certify::undecided_atoms_of(&mut nf, &[]));
    Some(r.rank)
}

/// The least CPU time of `repeat` runs of `f`.
fn least_cpu(repeat: usize, mut f: impl FnMut()) -> f64 {
    (0..repeat)
        .map(|_| {
            let c0 = cpu_seconds();
            f();
            cpu_seconds() - c0
        })
        .fold(f64::INFINITY, f64::min)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::env::set_current_dir(root).expect("cd to the repository");
    let mut args = std::env::args().skip(1).filter(|a| a != "--bench");
    let (mut filter, mut repeat, mut tsv) = ("si-jl".to_string(), 20usize, None::<String>);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--repeat" => {
                repeat = args
                    .next()
                    .and_then(|k| k.parse().ok())
                    .expect("--repeat K")
            }
            "--tsv" => tsv = args.next(),
            _ => filter = a,
        }
    }
    let mut files: Vec<String> = Vec::new();
    for dir in [
        "systems/benchmarks",
        "systems/benchmarks/si-jl",
        "systems/benchmarks/unknown-inputs",
    ] {
        let mut fs: Vec<String> = std::fs::read_dir(dir)
            .expect("the suite's folders")
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".sys"))
            .map(|n| format!("{dir}/{n}"))
            .filter(|p| p.contains(filter.as_str()))
            .collect();
        fs.sort();
        files.extend(fs);
    }
    println!("| model | least CPU ms | median CPU ms | least wall ms | computation alone, least CPU ms |");
    println!("|---|---|---|---|---|");
    let mut compute_all = Vec::new();
    let mut lines = String::new();
    let mut least_all = Vec::new();
    for f in &files {
        let argv: Vec<String> = ["rank", f.as_str(), "--json"].map(String::from).to_vec();
        // One warm-up run: the file in the page cache, the allocator's arenas grown.
        if obsan_cli::run_json(&argv, None).is_err() {
            println!("| {f} | refused | | |");
            continue;
        }
        let (mut cpu, mut wall) = (Vec::new(), Vec::new());
        for _ in 0..repeat {
            let (c0, w0) = (cpu_seconds(), Instant::now());
            let out = obsan_cli::run_json(&argv, None).expect("ran once already");
            std::hint::black_box(out.json);
            cpu.push(cpu_seconds() - c0);
            wall.push(w0.elapsed().as_secs_f64());
        }
        let least = cpu.iter().copied().fold(f64::INFINITY, f64::min);
        let least_wall = wall.iter().copied().fold(f64::INFINITY, f64::min);
        let text = std::fs::read_to_string(f).expect("read once already");
        let sys = obsan_model::System::parse(&text, f).expect("parsed once already");
        let compute = least_cpu(repeat, || {
            std::hint::black_box(compute_once(&sys));
        });
        println!(
            "| {f} | {:.3} | {:.3} | {:.3} | {:.3} |",
            least * 1e3,
            median(&mut cpu) * 1e3,
            least_wall * 1e3,
            compute * 1e3
        );
        lines.push_str(&format!("{f}\t{least:.9}\t{compute:.9}\n"));
        least_all.push(least);
        compute_all.push(compute);
    }
    if !least_all.is_empty() {
        println!(
            "\n{} models, {repeat} runs each: median of the least CPU times {:.3} ms",
            least_all.len(),
            median(&mut least_all) * 1e3
        );
        println!(
            "the computation alone (model parsed beforehand, no JSON): median of the least CPU times {:.3} ms",
            median(&mut compute_all) * 1e3
        );
    }
    if let Some(p) = tsv {
        std::fs::write(&p, lines).expect("write --tsv");
    }
}
