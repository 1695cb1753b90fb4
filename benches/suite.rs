//! The public benchmark suite (docs/benchmarks.md): `obsan rank` and `obsan symmetries` on
//! every model of systems/benchmarks/, on systems/vins.sys, on the systems listed in
//! systems/benchmarks/paper.list and on StructuralIdentifiability.jl's models
//! (systems/benchmarks/si-jl/, beside SI.jl's published local times where it gives them), through
//! the built binary, one child process per run. `cargo bench --bench suite -- si-jl` runs those
//! alone and ends with their median and max rank time.
//!
//! `cargo bench --bench suite [-- FILTER]` prints one Markdown table: n (states + params), rank,
//! the verdict against the cited one, the symmetries found and their certificate, wall time and
//! peak memory of each run. Peak memory is the child's maximum resident set size as reported by
//! GNU time (`/usr/bin/time -f %M`, from wait4) when it is installed, otherwise the largest
//! VmHWM read from /proc/PID/status while the child runs (polled every 2 ms, so a run shorter
//! than that may show less). The column header says which was used.
//!
//! Environment: OBSAN_SUITE_SYM_TIMEOUT (seconds for `symmetries --timeout`, default 10),
//! OBSAN_SUITE_RANK_TIMEOUT (default 60), OBSAN_SUITE_MODES_TIMEOUT (seconds for
//! `modes --timeout`, default 10). The modes column: the number of modes, `proven` when the
//! reduced system closed and every exact check passed, `open` when it did not close (exit 1),
//! `all` for a full-rank model (the modes are the variables), `none` without an answer.
//! The global column (`obsan global --timeout`, OBSAN_SUITE_GLOBAL_TIMEOUT, default 10):
//! counts of globally / locally (k values) / not identifiable variables, `none in T s` when it
//! did not finish within the budget, `refused` for models it does not count (trig leaves, delay).

use serde_json::Value;
use std::collections::BTreeSet;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GNU_TIME: &str = "/usr/bin/time";

#[path = "suite_entries.rs"]
mod suite_entries;
use suite_entries::{entries, si_jl_entries, si_jl_published, unknown_input_entries, Verdict};

/// One child run: exit code, stdout, wall time, peak resident memory in KiB.
struct Run {
    code: i32,
    stdout: String,
    secs: f64,
    peak_kib: Option<u64>,
}

fn run(root: &Path, args: &[&str], gnu_time: bool) -> Run {
    let obsan = env!("CARGO_BIN_EXE_obsan");
    let tmp = std::env::temp_dir().join(format!("obsan-suite-time-{}", std::process::id()));
    let mut cmd = if gnu_time {
        let mut c = Command::new(GNU_TIME);
        c.arg("-f").arg("%M").arg("-o").arg(&tmp).arg(obsan);
        c
    } else {
        Command::new(obsan)
    };
    cmd.args(args)
        .current_dir(root)
        .stdout(Stdio::piped())
        .stderr(Stdio::null());
    let start = Instant::now();
    let Ok(mut child) = cmd.spawn() else {
        return Run {
            code: -1,
            stdout: String::new(),
            secs: 0.0,
            peak_kib: None,
        };
    };
    // Drain stdout on a thread so a large answer cannot block the child.
    let mut pipe = child.stdout.take();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(p) = pipe.as_mut() {
            let _ = std::io::Read::read_to_string(p, &mut s);
        }
        s
    });
    let mut hwm = 0;
    let pid = child.id();
    let status = loop {
        if !gnu_time {
            if let Some(k) = vm_hwm(pid) {
                hwm = hwm.max(k);
            }
        }
        match child.try_wait() {
            Ok(Some(s)) => break Some(s),
            Ok(None) => std::thread::sleep(Duration::from_millis(2)),
            Err(_) => break None,
        }
    };
    let secs = start.elapsed().as_secs_f64();
    let stdout = reader.join().unwrap_or_default();
    let peak_kib = if gnu_time {
        std::fs::read_to_string(&tmp)
            .ok()
            .and_then(|s| s.lines().last().and_then(|l| l.trim().parse().ok()))
    } else {
        Some(hwm).filter(|&k| k > 0)
    };
    Run {
        code: status.and_then(|s| s.code()).unwrap_or(-1),
        stdout,
        secs,
        peak_kib,
    }
}

fn vm_hwm(pid: u32) -> Option<u64> {
    let s = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn mem(k: Option<u64>) -> String {
    k.map_or("-".into(), |k| format!("{:.1}", k as f64 / 1024.0))
}

fn env_secs(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// The rank run against the cited verdict: "agrees" or what differs.
fn judge(v: &Value, cited: &Verdict) -> String {
    if *cited == Verdict::default() {
        return "none cited".into();
    }
    let (Some(rank), Some(n)) = (v["rank"].as_u64(), v["n"].as_u64()) else {
        return "no answer".into();
    };
    let un: BTreeSet<String> = v["unobservable_variables"]
        .as_array()
        .map(|a| {
            a.iter()
                .filter_map(|x| x.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default();
    let mut diffs = Vec::new();
    if let Some(r) = cited.rank {
        if r != rank {
            diffs.push(format!("cited rank {r}"));
        }
    }
    if let Some(want) = &cited.unobservable {
        if want.is_empty() && rank != n {
            diffs.push("cited observable".into());
        } else if *want != un {
            let extra: Vec<&String> = un.difference(want).collect();
            let missing: Vec<&String> = want.difference(&un).collect();
            diffs.push(format!("unobservable also {extra:?}, not {missing:?}"));
        }
    }
    if let Some(want) = &cited.reconstructable {
        // `obsan rank` on a model with unknown inputs: each reconstructable one with its order.
        let got: BTreeSet<String> = v["reconstructable_inputs"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x["name"].as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default();
        if *want != got {
            diffs.push(format!("reconstructable {got:?}, cited {want:?}"));
        }
    }
    if diffs.is_empty() {
        "agrees".into()
    } else {
        format!("DIFFERS: {}", diffs.join("; "))
    }
}

fn main() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    // `cargo bench` passes `--bench`; any other argument filters the entries by path.
    let filter: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let all = (|| {
        let mut e = entries(root)?;
        e.extend(si_jl_entries(root)?);
        e.extend(unknown_input_entries(root)?);
        Ok::<_, String>((e, si_jl_published(root)?))
    })();
    let (entries, published) = all.unwrap_or_else(|e| {
        eprintln!("suite: {e}");
        std::process::exit(2);
    });
    // Rank times of the SI.jl models, for the summary (median, max).
    let mut si_rank_secs: Vec<(f64, String)> = Vec::new();
    let mut si_sym: (usize, usize) = (0, 0);
    let sym_timeout = env_secs("OBSAN_SUITE_SYM_TIMEOUT", 10).to_string();
    let rank_timeout = env_secs("OBSAN_SUITE_RANK_TIMEOUT", 60).to_string();
    let modes_timeout = env_secs("OBSAN_SUITE_MODES_TIMEOUT", 10).to_string();
    let global_timeout = env_secs("OBSAN_SUITE_GLOBAL_TIMEOUT", 10);
    let gnu_time = Path::new(GNU_TIME).exists();
    let how = if gnu_time {
        "GNU time %M"
    } else {
        "VmHWM polled"
    };
    println!(
        "| model | n | rank | verdict vs cited | rank s | rank MB | symmetries | certificate | sym s | sym MB | modes | modes s | SI.jl local s | global | global s | SI.jl global s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let (mut agree, mut differ, mut total, mut uncited) = (0, 0, 0, 0);
    for e in &entries {
        if !filter.is_empty() && !filter.iter().any(|f| e.path.contains(f.as_str())) {
            continue;
        }
        let mut extra: Vec<&str> = Vec::new();
        if let Some(name) = &e.input {
            extra.extend(["--input", name.as_str()]);
        }
        let label = match &e.input {
            Some(name) => format!("{} --input {name}", e.path),
            None => e.path.clone(),
        };
        let mut args = vec![
            "rank",
            e.path.as_str(),
            "--json",
            "--timeout",
            &rank_timeout,
        ];
        args.extend(&extra);
        let r = run(root, &args, gnu_time);
        let rv: Value = serde_json::from_str(&r.stdout).unwrap_or(Value::Null);
        let (n, rank, verdict) = if r.code == 0 {
            (
                rv["n"].to_string(),
                rv["rank"].to_string(),
                judge(&rv, &e.verdict),
            )
        } else {
            ("-".into(), "-".into(), format!("rank exit {}", r.code))
        };
        total += 1;
        if verdict == "agrees" {
            agree += 1;
        } else if verdict.starts_with("DIFFERS") {
            differ += 1;
        } else if verdict == "none cited" {
            uncited += 1;
        }
        let mut args = vec![
            "symmetries",
            e.path.as_str(),
            "--json",
            "--timeout",
            &sym_timeout,
        ];
        args.extend(&extra);
        let s = run(root, &args, gnu_time);
        let sv: Value = serde_json::from_str(&s.stdout).unwrap_or(Value::Null);
        let (found, cert) = if s.code == 0 {
            // A variable no output reaches is a symmetry too (`d/dx`), listed
            // apart in `free_directions`: counted here, marked "free".
            let structured = sv["symmetries"].as_array().map_or(0, |a| a.len());
            let free = sv["free_directions"].as_array().map_or(0, |a| a.len());
            let cert = match (&sv["certificate"], &sv["exact"]) {
                (Value::String(c), _) => c.clone(),
                (_, Value::Bool(true)) => "exact".into(),
                _ => "-".into(),
            };
            let found = match (structured, free) {
                (k, 0) => k.to_string(),
                (k, f) => format!("{} ({f} free)", k + f),
            };
            (found, cert)
        } else {
            (format!("none (exit {})", s.code), "-".into())
        };
        let mut args = vec![
            "modes",
            e.path.as_str(),
            "--json",
            "--timeout",
            &modes_timeout,
        ];
        args.extend(&extra);
        let m = run(root, &args, gnu_time);
        let mv: Value = serde_json::from_str(&m.stdout).unwrap_or(Value::Null);
        let count = mv["modes"].as_array().map_or(0, |a| a.len());
        let modes = match (m.code, &mv["full_rank"]) {
            (0, Value::Bool(true)) => format!("{count} all"),
            (0, _) => format!("{count} proven"),
            (1, _) => format!("{count} open"),
            (c, _) => format!("none (exit {c})"),
        };
        let gt = global_timeout.to_string();
        let mut args = vec!["global", e.path.as_str(), "--json", "--timeout", &gt];
        args.extend(&extra);
        let g = run(root, &args, gnu_time);
        let gv: Value = serde_json::from_str(&g.stdout).unwrap_or(Value::Null);
        let global = match (g.code, gv["variables"].as_array()) {
            (0, Some(vars)) => {
                let n = |t: &str| vars.iter().filter(|v| v["verdict"] == t).count();
                let ks: BTreeSet<u64> = vars
                    .iter()
                    .filter_map(|v| v["values"].as_u64())
                    .filter(|&k| k > 1)
                    .collect();
                format!(
                    "{} global, {} local {ks:?}, {} not",
                    n("global"),
                    n("local"),
                    n("not identifiable")
                )
            }
            _ if g.secs >= global_timeout as f64 => format!("none in {global_timeout} s"),
            (c, _) => format!("refused (exit {c})"),
        };
        let key = e
            .path
            .strip_prefix("systems/benchmarks/si-jl/")
            .and_then(|k| k.strip_suffix(".sys"));
        let sijl = key
            .and_then(|k| published.iter().find(|p| p.0 == k))
            .map_or("-".to_string(), |p| p.1.clone());
        let sijl_glob = key
            .and_then(|k| published.iter().find(|p| p.0 == k))
            .map_or("-".to_string(), |p| p.2.clone());
        if let Some(k) = key {
            if r.code == 0 {
                si_rank_secs.push((r.secs, k.to_string()));
            }
            if rv["rank"].as_u64().is_some() && rv["rank"] != rv["n"] {
                si_sym.0 += 1;
                if s.code == 0 && found != "0" {
                    si_sym.1 += 1;
                }
            }
        }
        println!(
            "| {label} | {n} | {rank} | {verdict} | {:.2} | {} | {found} | {cert} | {:.2} | {} | {modes} | {:.2} | {sijl} | {global} | {:.2} | {sijl_glob} |",
            r.secs,
            mem(r.peak_kib),
            s.secs,
            mem(s.peak_kib),
            m.secs,
            g.secs
        );
    }
    println!();
    println!(
        "{total} runs: {agree} verdicts agree with the cited ones, {differ} differ, {uncited} cite \
         none, {} gave no answer; memory: {how}; symmetries --timeout {sym_timeout} s; rank --timeout {rank_timeout} s; \
         modes --timeout {modes_timeout} s",
        total - agree - differ - uncited
    );
    if !si_rank_secs.is_empty() {
        si_rank_secs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let med = si_rank_secs[si_rank_secs.len() / 2].0;
        let (max, at) = si_rank_secs[si_rank_secs.len() - 1].clone();
        println!(
            "SI.jl models: {} ranks, median {med:.2} s, max {max:.2} s ({at}); {} of {} rank-deficient \
             ones have symmetries (SI.jl local times: its benchmarking/benchmark_result.md, machine \
             in published_times.list)",
            si_rank_secs.len(),
            si_sym.1,
            si_sym.0,
        );
    }
}
