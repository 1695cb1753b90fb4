//! `obsan montecarlo`: the paper's Tables IV-VII, optionally one shard of the
//! runs at a time (`--shard K/N --json`), and `montecarlo merge` of the parts.

use crate::cli::{MergeArgs, MontecarloArgs, MontecarloCommand};
use crate::json::{self, Partial, PartialCell, PartialOutcome, PartialRun, PartialTable};
use crate::progress::Progress;
use crate::Failure;
use obsan_calib::{
    calib_predictor, merge_runs, run_runs, shard_runs, summarize, table, RunOutcome, RunRecord,
    Table,
};
use obsan_fit::Predictor;
use serde_json::Value;
use std::process::ExitCode;

/// The most runs per cell (`--runs`): each run's values are kept for the
/// summary, so memory grows with it.
pub const MAX_RUNS: usize = 100_000;
/// The most worker threads (`--threads`).
pub const MAX_THREADS: usize = 1024;

/// A selection of `obsan montecarlo`: per table, its cells (indices) and
/// runs per cell (Table IV reports single runs).
struct Plan {
    tables: Vec<(Table, Vec<usize>, usize)>,
}

fn plan(a: &MontecarloArgs) -> Result<Plan, Failure> {
    let numbers: Vec<u8> = match a.table.as_str() {
        "all" => vec![4, 5, 6, 7],
        t => vec![t
            .parse::<u8>()
            .ok()
            .filter(|n| (4..=7).contains(n))
            .ok_or_else(|| Failure(format!("--table {t}: expected 4, 5, 6, 7 or all")))?],
    };
    if a.runs == 0 {
        return Err(Failure("--runs must be at least 1".into()));
    }
    if a.runs > MAX_RUNS {
        return Err(Failure(format!(
            "--runs {}: at most {MAX_RUNS} per cell (obsan's limit)",
            a.runs
        )));
    }
    if let Some(n) = a.threads.filter(|n| *n > MAX_THREADS) {
        return Err(Failure(format!(
            "--threads {n}: at most {MAX_THREADS} (obsan's limit)"
        )));
    }
    if a.cell.is_some() && numbers.len() != 1 {
        return Err(Failure(
            "--cell needs a single --table (4, 5, 6 or 7)".into(),
        ));
    }
    let mut tables = Vec::new();
    for tn in numbers {
        let t = table(tn).ok_or_else(|| Failure(format!("--table {tn}: no such table")))?;
        let cells = match a.cell {
            None => (0..t.cells.len()).collect(),
            Some(c) if (1..=t.cells.len()).contains(&c) => vec![c - 1],
            Some(c) => {
                let list: Vec<String> = t
                    .cells
                    .iter()
                    .enumerate()
                    .map(|(i, c)| format!("  {} {}", i + 1, c.label))
                    .collect();
                return Err(Failure(format!(
                    "--cell {c}: table {tn} has cells 1 to {}:\n{}",
                    t.cells.len(),
                    list.join("\n")
                )));
            }
        };
        let runs = if t.estimates { 1 } else { a.runs };
        tables.push((t, cells, runs));
    }
    Ok(Plan { tables })
}

/// `--shard K/N` as (K, N), 1 <= K <= N.
fn parse_shard(s: &str) -> Result<(usize, usize), Failure> {
    let bad = || {
        Failure(format!(
            "--shard {s}: expected K/N with 1 <= K <= N, e.g. 2/8"
        ))
    };
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n) = (
        k.trim().parse::<usize>().map_err(|_| bad())?,
        n.trim().parse::<usize>().map_err(|_| bad())?,
    );
    if k == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

/// The marker and version of a partial result; a merge refuses any other.
const PARTIAL: &str = "obsan montecarlo --shard K/N --json";
const PARTIAL_VERSION: u32 = 1;

fn to_hex(v: &[f64]) -> Vec<String> {
    v.iter().map(|x| format!("{:016x}", x.to_bits())).collect()
}

fn from_hex(v: &[String]) -> Option<Vec<f64>> {
    v.iter()
        .map(|h| {
            (h.len() == 16)
                .then(|| u64::from_str_radix(h, 16).ok())
                .flatten()
                .map(f64::from_bits)
        })
        .collect()
}

impl PartialRun {
    fn of(r: &RunRecord) -> PartialRun {
        PartialRun {
            run: r.run,
            outcomes: r
                .outcomes
                .iter()
                .map(|o| match o {
                    Ok((e, v)) => PartialOutcome::Ok {
                        errors: to_hex(e),
                        estimates: to_hex(v),
                    },
                    Err(m) => PartialOutcome::Failed { failed: m.clone() },
                })
                .collect(),
        }
    }

    fn record(&self) -> Option<RunRecord> {
        let outcomes = self
            .outcomes
            .iter()
            .map(|o| match o {
                PartialOutcome::Ok { errors, estimates } => {
                    Some(Ok((from_hex(errors)?, from_hex(estimates)?)))
                }
                PartialOutcome::Failed { failed } => Some(Err(failed.clone())),
            })
            .collect::<Option<Vec<RunOutcome>>>()?;
        Some(RunRecord {
            run: self.run,
            outcomes,
        })
    }
}

pub fn montecarlo_cmd(a: &MontecarloArgs) -> Result<ExitCode, Failure> {
    if let Some(MontecarloCommand::Merge(m)) = &a.merge {
        return merge_cmd(m);
    }
    let plan = plan(a)?;
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    // A pool of its own, not the global one: that can be set once per
    // process, and the Python package runs many commands in one.
    let pool = match a.threads {
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Failure(format!("--threads {n}: {e}")))?,
        ),
        None => None,
    };
    let range = |runs: usize| match shard {
        Some((k, n)) => shard_runs(runs, k, n).unwrap_or(0..0),
        None => 0..runs,
    };
    let total: usize = plan
        .tables
        .iter()
        .map(|(_, cells, runs)| cells.len() * range(*runs).len())
        .sum();
    let p = calib_predictor();
    let progress = Progress::new("montecarlo", total as u64, "runs");
    // Per table, per selected cell: the records of its runs in this shard.
    let compute = || -> Result<Vec<Vec<Vec<RunRecord>>>, Failure> {
        let mut computed: Vec<Vec<Vec<RunRecord>>> = Vec::new();
        for (t, cells, runs) in &plan.tables {
            progress.set_message(&format!("table {}", t.number));
            let start = std::time::Instant::now();
            let recs = cells
                .iter()
                .map(|&c| {
                    run_runs(&t.cells[c], t.modes, range(*runs), a.seed, &p, &|| {
                        progress.inc()
                    })
                })
                .collect::<Result<_, _>>()?;
            computed.push(recs);
            progress.println(&format!(
                "montecarlo: table {}: {} cell{} in {:.1} s",
                t.number,
                cells.len(),
                if cells.len() == 1 { "" } else { "s" },
                start.elapsed().as_secs_f64()
            ));
        }
        Ok(computed)
    };
    let computed = match &pool {
        // The cancel flag is this thread's: hand it to the pool's.
        Some(pool) => {
            let flag = obsan_expr::cancel_flag();
            pool.install(|| obsan_expr::with_cancel(flag, compute))?
        }
        None => compute()?,
    };
    drop(progress);
    if let (Some(shard), true) = (shard, a.json) {
        let part = Partial {
            partial: PARTIAL.into(),
            version: PARTIAL_VERSION,
            seed: a.seed,
            shard,
            tables: plan
                .tables
                .iter()
                .zip(&computed)
                .map(|((t, cells, runs), recs)| PartialTable {
                    table: t.number,
                    runs: *runs,
                    cells: cells
                        .iter()
                        .zip(recs)
                        .map(|(&c, r)| {
                            let rr = range(*runs);
                            PartialCell {
                                cell: c + 1,
                                label: t.cells[c].label.clone(),
                                methods: t.cells[c]
                                    .methods
                                    .iter()
                                    .map(|m| m.name().into())
                                    .collect(),
                                run_range: (rr.start, rr.end),
                                records: r.iter().map(PartialRun::of).collect(),
                            }
                        })
                        .collect(),
                })
                .collect(),
        };
        outln!("{}", serde_json::to_string_pretty(&part)?);
        return Ok(ExitCode::SUCCESS);
    }
    let note = shard.map(|(k, n)| (k, n, a.runs));
    report_tables(&plan, computed, a.seed, a.json, note, &p)
}

/// The tables from the records of their runs: text or JSON, identical
/// whether the records were computed here or merged from shards.
fn report_tables(
    plan: &Plan,
    computed: Vec<Vec<Vec<RunRecord>>>,
    seed: u64,
    json: bool,
    shard: Option<(usize, usize, usize)>,
    p: &Predictor,
) -> Result<ExitCode, Failure> {
    let mut all = Vec::new();
    for ((t, cells, runs), recs) in plan.tables.iter().zip(computed) {
        let results = cells
            .iter()
            .zip(&recs)
            .map(|(&c, r)| {
                let cell = &t.cells[c];
                summarize(cell, t.modes, r, cell.bounds(t.modes, p))
                    .map_err(|e| Failure(format!("table {} cell {}: {e}", t.number, c + 1)))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let shown: Vec<(usize, &obsan_calib::Cell, &obsan_calib::CellResult)> = cells
            .iter()
            .zip(&results)
            .map(|(&c, r)| (c, &t.cells[c], r))
            .collect();
        if !json {
            let runs_text = match shard {
                Some((k, n, _)) => {
                    let r = shard_runs(*runs, k, n).unwrap_or(0..0);
                    format!(
                        "shard {k}/{n}: runs {}..{} of {runs} per cell, seed {seed}; merge the --json parts for the table",
                        r.start, r.end
                    )
                }
                None => format!(
                    "{runs} run{} per cell, seed {seed}",
                    if *runs == 1 { "" } else { "s" }
                ),
            };
            print_table(t, &shown, &runs_text);
        }
        all.push(json::McTable {
            cells: shown.iter().map(|(i, c, r)| mc_cell(*i, c, r)).collect(),
            columns: t.columns.iter().map(|c| c.to_string()).collect(),
            runs: *runs,
            seed,
            table: t.number,
            title: t.title.clone(),
        });
    }
    if json {
        json::print(&all)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// One cell of a table as `--json` prints it (a non-finite figure as null).
fn mc_cell(i: usize, c: &obsan_calib::Cell, r: &obsan_calib::CellResult) -> json::McCell {
    let fin = |v: &[f64]| v.iter().map(|&x| json::finite(x)).collect::<Vec<_>>();
    json::McCell {
        cell: i + 1,
        crlb_sd: r.crlb_sd.as_deref().map(fin),
        crlb_sd_with_encoder_noise: r.crlb_sd_encoders.as_deref().map(fin),
        label: r.label.clone(),
        methods: r
            .methods
            .iter()
            .map(|m| json::McMethod {
                failures: m.failures,
                first_failure: m.first_failure.clone(),
                mean_abs_error: fin(&m.mean_abs),
                mean_estimate: fin(&m.mean_estimate),
                method: m.method.name().to_string(),
                rms_error: fin(&m.rms),
            })
            .collect(),
        paper: c
            .paper
            .iter()
            .map(|(m, v)| json::McPaper {
                method: m.name().to_string(),
                values: fin(v),
            })
            .collect(),
    }
}

/// `obsan montecarlo merge`: check that the parts are every shard of one
/// sweep, once each, then report the tables from their runs in run order.
fn merge_cmd(m: &MergeArgs) -> Result<ExitCode, Failure> {
    let mut parts: Vec<(String, Partial)> = Vec::new();
    for path in &m.parts {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Failure(format!("cannot read {path}: {e}")))?;
        // A BOM (an editor's, PowerShell's `>`) is accepted, as by every other reader.
        let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
        let v: Value = serde_json::from_str(text)
            .map_err(|e| Failure(format!("{path}:{}:{}: not JSON: {e}", e.line(), e.column())))?;
        if v.get("partial").and_then(Value::as_str) != Some(PARTIAL) {
            return Err(Failure(format!(
                "{path}: not a partial result of `{PARTIAL}`"
            )));
        }
        if v.get("version").and_then(Value::as_u64) != Some(PARTIAL_VERSION as u64) {
            return Err(Failure(format!(
                "{path}: partial result of another version (this obsan reads version {PARTIAL_VERSION})"
            )));
        }
        let p: Partial = serde_json::from_str(text)
            .map_err(|e| Failure(format!("{path}:{}:{}: {e}", e.line(), e.column())))?;
        parts.push((path.clone(), p));
    }
    let (first_path, first) = &parts[0];
    let n = first.shard.1;
    // What the sweep is: the same in every part.
    let sweep = |p: &Partial| -> Vec<(u8, usize, Vec<usize>)> {
        p.tables
            .iter()
            .map(|t| (t.table, t.runs, t.cells.iter().map(|c| c.cell).collect()))
            .collect()
    };
    let describe = |s: &[(u8, usize, Vec<usize>)]| -> String {
        s.iter()
            .map(|(t, r, c)| {
                let c: Vec<String> = c.iter().map(|c| c.to_string()).collect();
                let cells = if c.len() == 1 { "cell" } else { "cells" };
                format!("table {t} {cells} {} with {r} runs", c.join(","))
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    for (path, p) in &parts[1..] {
        let differ = |what: &str, a: String, b: String| {
            Failure(format!(
                "{path} and {first_path} are not shards of one sweep: {what} {a} vs {b}"
            ))
        };
        if p.seed != first.seed {
            return Err(differ("seed", p.seed.to_string(), first.seed.to_string()));
        }
        if p.shard.1 != n {
            return Err(differ("shard count", p.shard.1.to_string(), n.to_string()));
        }
        if sweep(p) != sweep(first) {
            return Err(differ(
                "sweep",
                describe(&sweep(p)),
                describe(&sweep(first)),
            ));
        }
    }
    // Every shard 1..=n exactly once.
    let mut by_shard: Vec<Option<&(String, Partial)>> = vec![None; n];
    for part in &parts {
        let (k, _) = part.1.shard;
        if k == 0 || k > n {
            return Err(Failure(format!("{}: shard {k}/{n} does not exist", part.0)));
        }
        if let Some(other) = by_shard[k - 1] {
            return Err(Failure(format!(
                "{} and {} are both shard {k}/{n}",
                other.0, part.0
            )));
        }
        by_shard[k - 1] = Some(part);
    }
    let missing: Vec<String> = (1..=n)
        .filter(|k| by_shard[k - 1].is_none())
        .map(|k| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(Failure(format!(
            "missing shard{} {} of the sweep ({} given)",
            if missing.len() == 1 { "" } else { "s" },
            missing.join(", "),
            describe(&sweep(first))
        )));
    }
    let ordered: Vec<&(String, Partial)> = by_shard.into_iter().flatten().collect();
    let mut plan = Plan { tables: Vec::new() };
    let mut computed = Vec::new();
    for (ti, pt) in first.tables.iter().enumerate() {
        let t = table(pt.table)
            .ok_or_else(|| Failure(format!("{first_path}: no table {}", pt.table)))?;
        let mut cells = Vec::new();
        let mut recs = Vec::new();
        for (ci, pc) in pt.cells.iter().enumerate() {
            let c = pc
                .cell
                .checked_sub(1)
                .filter(|&c| c < t.cells.len())
                .ok_or_else(|| {
                    Failure(format!(
                        "{first_path}: table {} has no cell {}",
                        t.number, pc.cell
                    ))
                })?;
            let cell = &t.cells[c];
            let names: Vec<String> = cell.methods.iter().map(|m| m.name().to_string()).collect();
            let mut shards = Vec::new();
            for (path, p) in &ordered {
                let sc = &p.tables[ti].cells[ci];
                if sc.label != cell.label || sc.methods != names {
                    return Err(Failure(format!(
                        "{path}: table {} cell {} is '{}' ({}) in the part but '{}' ({}) in this obsan",
                        t.number, pc.cell, sc.label, sc.methods.join(", "), cell.label, names.join(", ")
                    )));
                }
                let want = shard_runs(pt.runs, p.shard.0, n).unwrap_or(0..0);
                if (sc.run_range.0..sc.run_range.1) != want {
                    return Err(Failure(format!(
                        "{path}: table {} cell {}: runs {}..{}, shard {}/{n} of {} runs is {}..{}",
                        t.number,
                        pc.cell,
                        sc.run_range.0,
                        sc.run_range.1,
                        p.shard.0,
                        pt.runs,
                        want.start,
                        want.end
                    )));
                }
                let r = sc
                    .records
                    .iter()
                    .map(|r| {
                        r.record().ok_or_else(|| {
                            Failure(format!(
                                "{path}: table {} cell {} run {}: a value is not 16 hex digits",
                                t.number, pc.cell, r.run
                            ))
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                // The runs of this part in order, each once: checked here so
                // that the error names the part (merge_runs cannot).
                if let Some((i, rec)) = r
                    .iter()
                    .enumerate()
                    .find(|(i, rec)| rec.run != want.start + i)
                {
                    return Err(Failure(format!(
                        "{path}: table {} cell {}: run {} expected, run {} found in its place",
                        t.number,
                        pc.cell,
                        want.start + i,
                        rec.run
                    )));
                }
                if r.len() != want.len() {
                    return Err(Failure(format!(
                        "{path}: table {} cell {}: {} runs given, shard {}/{n} has {}",
                        t.number,
                        pc.cell,
                        r.len(),
                        p.shard.0,
                        want.len()
                    )));
                }
                report_odd_values(path, t.number, pc.cell, &r);
                shards.push(r);
            }
            let all = merge_runs(shards, pt.runs)
                .map_err(|e| Failure(format!("table {} cell {}: {e}", t.number, pc.cell)))?;
            cells.push(c);
            recs.push(all);
        }
        plan.tables.push((t, cells, pt.runs));
        computed.push(recs);
    }
    let p = calib_predictor();
    report_tables(&plan, computed, first.seed, m.json, None, &p)
}

/// Say on stderr which values of a part are infinite or a NaN other than the
/// quiet NaN a shard writes for a value a method does not estimate (an
/// edited or damaged part, or a diverged estimate). They are merged as
/// they are (the summary shows what they do), but never without a word.
fn report_odd_values(path: &str, table: u8, cell: usize, runs: &[RunRecord]) {
    let quiet = f64::NAN.to_bits();
    let odd = |x: &f64| x.is_infinite() || (x.is_nan() && x.to_bits() & !(1 << 63) != quiet);
    let hits: Vec<usize> = runs
        .iter()
        .filter(|r| {
            r.outcomes
                .iter()
                .any(|o| o.as_ref().is_ok_and(|(e, v)| e.iter().chain(v).any(odd)))
        })
        .map(|r| r.run)
        .collect();
    if let Some(first) = hits.first() {
        eprintln!(
            "warning: {path}: table {table} cell {cell}: {} run(s) hold an infinite value or an unusual NaN bit pattern (first: run {first}); merged as given",
            hits.len()
        );
    }
}

fn print_table(
    t: &Table,
    shown: &[(usize, &obsan_calib::Cell, &obsan_calib::CellResult)],
    runs_text: &str,
) {
    outln!("{} ({runs_text})", t.title);
    let head: String = t.columns.iter().map(|c| format!("{c:>11}")).collect();
    outln!("{:<32} {:<22}{head}", "set-up", "row");
    for &(_, cell, r) in shown {
        for (m, v) in &cell.paper {
            let vals: String = v.iter().map(|x| format!("{x:>11.4}")).collect();
            outln!(
                "{:<32} {:<22}{vals}",
                r.label,
                format!("paper {}", m.name())
            );
        }
        for ms in &r.methods {
            let fail = if ms.failures > 0 {
                format!(
                    "  ({} failed: {})",
                    ms.failures,
                    ms.first_failure.clone().unwrap_or_default()
                )
            } else {
                String::new()
            };
            let (name, vals) = if t.estimates {
                ("estimate", &ms.mean_estimate)
            } else {
                ("mean |err|", &ms.mean_abs)
            };
            let row: String = vals
                .iter()
                .map(|x| {
                    if x.is_nan() {
                        format!("{:>11}", "-")
                    } else {
                        format!("{x:>11.4}")
                    }
                })
                .collect();
            outln!(
                "{:<32} {:<22}{row}{fail}",
                r.label,
                format!("{} {name}", ms.method.name())
            );
            if !t.estimates && !t.modes {
                let row: String = ms.rms.iter().map(|x| format!("{x:>11.4}")).collect();
                outln!(
                    "{:<32} {:<22}{row}",
                    r.label,
                    format!("{} rms err", ms.method.name())
                );
            }
        }
        for (sd, label) in [
            (&r.crlb_sd, "CRLB sd (bearings)"),
            (&r.crlb_sd_encoders, "CRLB sd (+encoders)"),
        ] {
            if let Some(sd) = sd {
                let row: String = sd.iter().map(|x| format!("{x:>11.4}")).collect();
                outln!("{:<32} {:<22}{row}", r.label, label);
            }
        }
        for ms in &r.methods {
            let Some((sd, which)) = r.bound_for(ms.method) else {
                continue;
            };
            let row: String = ms
                .rms
                .iter()
                .zip(sd)
                .map(|(e, s)| format!("{:>11.2}", e / s))
                .collect();
            outln!(
                "{:<32} {:<22}{row}",
                r.label,
                format!("{} rms/{which}", ms.method.name())
            );
        }
    }
    if let Some(note) = paper_below_bound_note(t, shown) {
        outln!("{note}");
    }
    outln!();
}

/// A reader who sees the paper's mean errors beside larger ones of ours concludes we are worse;
/// where the paper's figure is under the Cramér–Rao sd of its own set-up, say so beside the
/// table. An efficient unbiased Gaussian estimator's mean |error| is sqrt(2/pi) = 0.80 sd.
fn paper_below_bound_note(
    t: &Table,
    shown: &[(usize, &obsan_calib::Cell, &obsan_calib::CellResult)],
) -> Option<String> {
    if t.estimates {
        return None;
    }
    let mean_abs_at_bound = (2.0 / std::f64::consts::PI).sqrt();
    let mut below = std::collections::BTreeSet::new();
    for &(_, cell, r) in shown {
        let Some(sd) = &r.crlb_sd else { continue };
        for (_, v) in &cell.paper {
            for (c, (x, s)) in v.iter().zip(sd).enumerate() {
                if x.abs() < mean_abs_at_bound * s {
                    below.insert(c);
                }
            }
        }
    }
    if below.is_empty() {
        return None;
    }
    let cols: Vec<&str> = below.iter().map(|&c| t.columns[c]).collect();
    Some(format!(
        "note: the paper's mean errors on {} are below what an efficient unbiased estimator \
         reaches under the paper's own set-up (mean |error| = 0.80 x the `CRLB sd` row): \
         compare ours with the bound, the paper's rows for their trend (docs/accuracy.md, item 3).",
        cols.join(", ")
    ))
}
