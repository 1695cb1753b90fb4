//! `obsan modes`: observable modes and the reduced system, derived and proven.

use crate::cli::ModesArgs;
use crate::json;
use crate::show::load_normal_form;
use crate::Failure;
use obsan_analysis::{
    derive_modes, rank as rank_test, symmetries_with, verify_derivation, Certificate,
    DeriveOptions, RankOptions, Route, SymmetryOptions,
};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

pub fn run(a: &ModesArgs) -> Result<ExitCode, Failure> {
    if let Some(prefix) = &a.out_prefix {
        for ext in ["sys", "dec"] {
            crate::fsio::check_outside(&format!("{prefix}.{ext}"), &[&a.sys.system])?;
        }
    }
    let (_, mut nf) = load_normal_form(&a.sys)?;
    if !nf.unknown_inputs.is_empty() {
        return crate::unknown_input_cmd::modes(a, &mut nf, write_pair);
    }
    if nf.outputs.is_empty() {
        return Err(Failure(format!(
            "{}: the system has no output, so nothing is observable",
            a.sys.system
        )));
    }
    // The whole --timeout, shared by every stage (rank, symmetries,
    // derivation): a run stopped inside the derivation says how far it got
    // (modes found, stage); the watchdog waits a second more.
    let deadline = crate::cli::deadline_after(Instant::now(), a.timeout);
    let r = rank_test(
        &mut nf,
        RankOptions {
            seed: a.seed,
            deadline,
            progress: None,
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    // With explicit time the clock `t` is an analysed state and a mode
    // (src/clock.rs): counted out of every rank, n and mode list shown.
    let clk = usize::from(nf.clock().is_some());
    let title = match &nf.restriction {
        Some(q) => format!("{} (input {q})", nf.name),
        None => nf.name.clone(),
    };
    if r.rank == r.n {
        // The full rank is a nonzero minor: a proof only over decided atoms
        // (else the true rank may be lower, as `obsan rank` says too).
        let undecided = obsan_analysis::certify::undecided_atoms_of(&mut nf, &[]);
        let decided = undecided.is_empty();
        let certificate = if decided {
            "rank equals the dimension: a non-zero minor at a point proves it (exact)".to_string()
        } else {
            not_decided_text(&undecided, r.rank)
        };
        if a.out.json {
            let modes = nf
                .state
                .iter()
                .filter(|s| clk == 0 || s.as_str() != obsan_model::TIME)
                .map(|s| json::VariableMode {
                    expr: s.clone(),
                    kind: "variable".into(),
                    name: s.clone(),
                })
                .collect();
            crate::json::print(&json::Modes::FullRank(json::ModesFullRank {
                certificate,
                decided,
                full_rank: decided.then_some(true),
                modes,
                n: r.n - clk,
                rank: r.rank - clk,
                reduced: None,
                restriction: nf.restriction.clone(),
                system: nf.name.clone(),
                undecided_atoms: undecided,
            }))?;
        } else if decided {
            outln!(
                "{title}: rank {} of {}: every variable is observable; the modes are the variables",
                r.rank - clk,
                r.n - clk
            );
        } else {
            outln!(
                "{title}: rank {} of {} with the atoms independent\n{certificate}",
                r.rank - clk,
                r.n - clk
            );
        }
        // Nothing to reduce: the reduced system would be the system itself.
        if let Some(prefix) = &a.out_prefix {
            eprintln!(
                "note: nothing written to {prefix}.sys or {prefix}.dec: the system has full rank, so its reduced system is {} itself",
                a.sys.system
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    // Variables no output reaches are unobservable, each its own symmetry
    // d/dx, and in no mode: the modes are derived on the subsystem of the
    // reached ones (same rank, same modes), so that unused params cost
    // nothing.
    let n_full = r.n;
    let mut unreached: Vec<String> = Vec::new();
    let (mut nf, r) = match obsan_analysis::restrict_to_reached(&mut nf) {
        Some(red) => {
            unreached = red.unreached.iter().map(|&j| nf.state[j].clone()).collect();
            let mut sub = red.nf;
            let r = rank_test(
                &mut sub,
                RankOptions {
                    seed: a.seed,
                    deadline,
                    progress: None,
                },
            )
            .map_err(|e| Failure(e.to_string()))?;
            (sub, r)
        }
        None => (nf, r),
    };
    // The symmetries only guide the search (and give the PDE (11) check):
    // cheap structure, or reconstruction certified at random points. The
    // exact certificate of the modes is the closure of the reduced system.
    let sym = symmetries_with(
        &mut nf,
        &r,
        &SymmetryOptions {
            deadline,
            route: Route::Auto,
        },
    )
    .map_err(|e| Failure(e.to_string()))?;
    let opts = DeriveOptions {
        seed: a.seed,
        deadline,
        ..DeriveOptions::default()
    };
    let d = derive_modes(&mut nf, &r, &sym, &opts).map_err(|e| Failure(e.to_string()))?;
    let (sys_path, sets) = crate::reduced_text::dec_source(&a.sys);
    let dec = d.decomposition_text(&sys_path, nf.restriction.as_deref(), &sets);
    let sys_text = d.sys_text(&nf.name, &format!("observable modes of {title}"));
    let checks = match &dec {
        Some(t) => Some(
            verify_derivation(&mut nf, t, "derived decomposition", a.seed, (&r, &sym))
                .map_err(|e| Failure(format!("internal: the derived decomposition: {e}")))?,
        ),
        None => None,
    };
    let verified = checks.as_ref().is_some_and(|c| c.iter().all(|c| c.pass));
    // Everything resting on a nonzero form (the rank, the modes'
    // independence, a check's minor, a failed residual) is proven only over
    // decided atoms; zero residuals and substitutions are proofs regardless.
    let mut undecided: Vec<String> = sym.undecided.clone();
    undecided.extend(d.mode_report.undecided.iter().cloned());
    for c in checks.iter().flatten() {
        undecided.extend(c.undecided.iter().cloned());
    }
    undecided.sort();
    undecided.dedup();
    let decided = undecided.is_empty();
    let failure_certain = checks
        .iter()
        .flatten()
        .any(|c| !c.pass && c.undecided.is_empty());
    let modes_ok = d.mode_report.checks.iter().all(|c| c.is_mode)
        && d.mode_report.independent
        && d.mode_report.complete;
    let plural = |k: usize| if k == 1 { "y" } else { "ies" };
    let nsym = sym.count() + unreached.len();
    let sym_cert = match &sym.certificate {
        Certificate::Random(c) => format!(
            "reconstructed, certified at {} random points with error below {:.0e}",
            c.points, c.error_bound
        ),
        Certificate::Invariance(_) => "cheap structure, proven exactly by invariance".into(),
        Certificate::Closure => "exact Gauss-Jordan, proven by the exact closure check".into(),
        Certificate::Span => "reconstructed, proven exactly by the span certificate".into(),
    };
    let closure = checks.as_ref().is_some_and(|c| d.closure_proves(c));
    let certificate = if closure {
        format!(
            "exact by closure: {} modes with independent gradients (a non-zero minor at a point); their dynamics along every field and every output written in the modes and proven by exact substitution ({} decomposition checks); so the observable codistribution is their span, the rank is exactly {} and each mode satisfies eq. (11) for every symmetry (the PDE also checked exactly against the {nsym} symmetr{}: {sym_cert}){}",
            d.shown().len(),
            checks.as_ref().map_or(0, |c| c.len()),
            d.rank - clk,
            plural(nsym),
            if clk == 1 { "; with the clock t, a mode of every system with explicit time, in the checks" } else { "" },
        )
    } else if !decided {
        format!(
            "{} mode(s), each satisfies eq. (11) exactly (canonical forms) for the {nsym} symmetr{} found ({sym_cert}); {}; {}",
            d.shown().len(),
            plural(nsym),
            match &checks {
                Some(_) if verified => "the reduced system writes every output and field in the modes (exact substitution)".to_string(),
                Some(_) => "reduced system: a decomposition check did not pass".to_string(),
                None => format!("reduced system not closed: no form in the modes found for {}", d.missing().join(", ")),
            },
            not_decided_text(&undecided, d.rank)
        )
    } else {
        format!(
            "{} mode(s), each satisfies eq. (11) exactly (canonical forms) for the {nsym} symmetr{} ({sym_cert}); gradients independent (a non-zero minor at a point, exact); {} = rank{}{}",
            d.shown().len(),
            plural(nsym),
            d.mode_report.independent_count.saturating_sub(clk),
            if sym.exact { " (exact)" } else { " (the rank test's, exact only as a lower bound)" },
            match &checks {
                Some(_) => "; reduced system: a decomposition check FAILED".to_string(),
                None if d.reduced_timed_out => format!("; reduced system not closed within --timeout (the time limit stopped the search): no form yet for {}", d.missing().join(", ")),
                None => format!("; reduced system not closed: no form in the modes found for {}", d.missing().join(", ")),
            }
        )
    };
    if let (Some(prefix), Some(dec), Some(sys_text)) = (&a.out_prefix, &dec, &sys_text) {
        write_pair(prefix, a.force, sys_text, dec)?;
    }
    if a.out.json {
        let modes = d
            .shown()
            .into_iter()
            .map(|k| &d.modes[k])
            .map(|m| json::DerivedMode {
                angle: m.angle,
                domain: m.domain.clone(),
                expr: m.text.clone(),
                kind: m.kind.word().to_string(),
                name: m.name.clone(),
            })
            .collect();
        let dynamics = d
            .shown()
            .into_iter()
            .map(|k| json::ReducedDynamics {
                name: d.modes[k].name.clone(),
                rhs: d.dynamics(k),
            })
            .collect();
        let outputs = d
            .shown_outputs()
            .map(|(n, e)| json::ReducedOutput {
                expr: e.clone(),
                name: n.clone(),
            })
            .collect();
        let checks = checks.as_ref().map(|cs| {
            cs.iter()
                .map(|c| json::PassCheck {
                    check: c.name.clone(),
                    detail: c.detail.clone(),
                    pass: c.pass,
                })
                .collect()
        });
        let certificate = json::ModesCertificate {
            checks,
            complete: decided.then_some(d.mode_report.complete),
            exact: closure || (modes_ok && sym.exact && decided),
            independent: (decided || !d.mode_report.independent)
                .then_some(d.mode_report.independent),
            method: if closure { "closure" } else { "symmetries" }.into(),
            modes_exact: decided.then_some(modes_ok),
            symmetries: sym_cert,
            text: certificate,
            verified: (decided || failure_certain).then_some(verified),
        };
        crate::json::print(&json::Modes::Derived(Box::new(json::ModesDerived {
            certificate,
            dec: dec.clone(),
            decided,
            full_rank: false,
            modes,
            n: n_full - clk,
            rank: d.rank - clk,
            reduced: json::Reduced {
                closed: d.closed(),
                dynamics,
                inputs: d.inputs(),
                missing: d.missing(),
                outputs,
            },
            restriction: nf.restriction.clone(),
            symmetries: nsym,
            sys: sys_text,
            system: nf.name.clone(),
            undecided_atoms: undecided,
            unreached,
        })))?;
    } else {
        let mut o = format!(
            "{title}: rank {} of {}, {} symmetr{}; {} observable modes:\n",
            d.rank - clk,
            n_full - clk,
            nsym,
            plural(nsym),
            d.shown().len()
        );
        if !unreached.is_empty() {
            o.push_str(&format!(
                "  ({} variable{} no output reaches, unobservable, each its own symmetry d/dx and in no mode: {})\n",
                unreached.len(),
                if unreached.len() == 1 { "" } else { "s" },
                unreached.join(", ")
            ));
        }
        for m in d.shown().into_iter().map(|k| &d.modes[k]) {
            let e = if a.out.latex {
                nf.ctx.to_latex(m.expr)
            } else {
                m.text.clone()
            };
            crate::reduced_text::push_mode(&mut o, m, &e);
        }
        crate::reduced_text::push_reduced(&mut o, &d);
        o.push_str(&format!("certificate: {certificate}\n"));
        if let Some(p) = &a.out_prefix {
            if dec.is_some() {
                o.push_str(&format!("wrote {p}.sys and {p}.dec\n"));
            }
        }
        out!("{o}");
    }
    if !modes_ok || !verified {
        if a.out_prefix.is_some() && dec.is_none() {
            eprintln!("error: the reduced system is not closed; nothing written");
        }
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}

/// What stays unproven over undecided atoms (the rank and every nonzero
/// form built on it), and what is still proven.
fn not_decided_text(atoms: &[String], rank: usize) -> String {
    format!(
        "not decided: the atoms {} may be related in ways the engine does not detect; the rank {rank} is that of the system with them independent, an upper bound on the true rank, so there may be more symmetries, fewer observable modes and a smaller reduced system than shown (zero residuals and exact substitutions above are proofs; nonzero minors and pivots over these atoms are not)",
        atoms.join(", ")
    )
}

/// The first line of every file `obsan modes --out` writes: `--force`
/// replaces a file only when it starts with it.
const WRITTEN_BY: &str = "# written by obsan modes (--force may replace this file)";

/// Write PREFIX.sys and PREFIX.dec: each to a temporary sibling, then renamed;
/// an existing file is replaced only with --force, and only if obsan wrote it.
fn write_pair(prefix: &str, force: bool, sys: &str, dec: &str) -> Result<(), Failure> {
    // After a limit (terms, time, a form too long to print) the texts are
    // placeholders or cut short: write nothing; the caller reports the limit.
    if obsan_expr::limits::budget_tripped() {
        return Err(Failure("an engine limit was reached".into()));
    }
    let (sys, dec) = (
        format!("{WRITTEN_BY}\n{sys}"),
        format!("{WRITTEN_BY}\n{dec}"),
    );
    let targets = [
        (PathBuf::from(format!("{prefix}.sys")), sys.as_str()),
        (PathBuf::from(format!("{prefix}.dec")), dec.as_str()),
    ];
    for (p, _) in &targets {
        let Ok(meta) = std::fs::symlink_metadata(p) else {
            continue;
        };
        if !force {
            return Err(Failure(format!(
                "{} already exists (use --force to replace a file obsan wrote)",
                p.display()
            )));
        }
        let ours = meta.is_file()
            && std::fs::read_to_string(p).is_ok_and(|t| t.lines().next() == Some(WRITTEN_BY));
        if !ours {
            return Err(Failure(format!(
                "refusing to replace {} with --force: obsan did not write it",
                p.display()
            )));
        }
    }
    if let Some(parent) = Path::new(prefix).parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent)
                .map_err(|e| Failure(format!("cannot create {}: {e}", parent.display())))?;
        }
    }
    let temps: Vec<PathBuf> = targets
        .iter()
        .map(|(p, _)| PathBuf::from(format!("{}.tmp-{}", p.display(), std::process::id())))
        .collect();
    let remove = || {
        for t in &temps {
            let _ = std::fs::remove_file(t);
        }
    };
    let r = crate::fsio::write_files_then(
        &temps
            .iter()
            .zip(&targets)
            .map(|(t, (_, text))| (t.clone(), text.as_bytes()))
            .collect::<Vec<_>>(),
        || {
            for (tmp, (p, _)) in temps.iter().zip(&targets) {
                std::fs::rename(tmp, p)
                    .map_err(|e| Failure(format!("cannot write {}: {e}", p.display())))?;
            }
            Ok(())
        },
    );
    if r.is_err() {
        remove();
    }
    r
}
