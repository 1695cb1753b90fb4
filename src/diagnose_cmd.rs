//! `obsan diagnose`: reading the model, effects and data, printing the
//! diagnosis, writing the report folder.

use crate::cli::{DiagnoseArgs, MrclamArgs};
use crate::diagnose_units::Units;
use crate::estimate_cmds::read_dataset;
use crate::fsio::write_folder_atomically;
use crate::show::load_system;
use crate::Failure;
use obsan_diagnose::{
    diagnose, start_values, statistics::Combination, CandidateResult, DiagnoseOptions, Diagnosis,
    InputNoise, ModelFit, Named,
};
use obsan_model::{EffectLibrary, Kind};
use std::collections::BTreeMap;
use std::fmt::Write;
use std::path::PathBuf;
use std::process::ExitCode;

/// The effects file diagnose reads: --effects, else the model's `.eff` if there is one.
fn effects_path(a: &DiagnoseArgs) -> Option<String> {
    match &a.effects {
        Some(p) => Some(p.clone()),
        None => {
            let p = PathBuf::from(a.model()).with_extension("eff");
            p.exists().then(|| p.display().to_string())
        }
    }
}

fn load_effects(a: &DiagnoseArgs) -> Result<Option<EffectLibrary>, Failure> {
    let Some(path) = effects_path(a) else {
        return Ok(None);
    };
    let src = crate::fsio::read_text(&path)?;
    Ok(Some(EffectLibrary::parse(&src, &path)?))
}

fn parse_init(v: &[String]) -> Result<BTreeMap<String, f64>, Failure> {
    let mut out = BTreeMap::new();
    for s in v {
        let Some((n, x)) = s.split_once('=') else {
            return Err(Failure(format!("--init {s}: expected NAME=VALUE")));
        };
        let x: f64 = x
            .trim()
            .parse()
            .map_err(|_| Failure(format!("--init {s}: '{}' is not a number", x.trim())))?;
        if !x.is_finite() {
            return Err(Failure(format!("--init {s}: the value must be finite")));
        }
        out.insert(n.trim().to_string(), x);
    }
    Ok(out)
}

pub fn run(a: &DiagnoseArgs) -> Result<ExitCode, Failure> {
    if !(a.alpha > 0.0 && a.alpha < 1.0) {
        return Err(Failure(format!("--alpha {}: must be in (0, 1)", a.alpha)));
    }
    let eff = effects_path(a);
    let mut reads = vec![a.model(), a.data()];
    reads.extend(eff.as_deref());
    if let Some(dir) = &a.report {
        crate::fsio::check_outside(dir, &reads)?;
    }
    let sys = load_system(a.model())?;
    let lib = load_effects(a)?;
    if let Some(l) = &lib {
        l.check(&sys)?;
    }
    let inputs: Vec<&str> = sys
        .decls_of(Kind::Input)
        .filter(|d| d.derived.is_none())
        .map(|d| d.name.as_str())
        .collect();
    let outputs = sys.output_names();
    let data = read_dataset(a.data(), &inputs, &outputs)?;
    // A constant the model declares without a value comes from each
    // trajectory's meta.json: a missing one is an error, never a silent 0
    // (a window of MRCLAM without lx9 named other effects).
    for t in &data.trajectories {
        if let Some(c) = sys
            .decls_of(Kind::Const)
            .find(|c| c.value.is_none() && !t.meta.contains_key(&c.name))
        {
            let file = std::path::Path::new(a.data())
                .join(&t.name)
                .join("meta.json");
            return Err(Failure(format!(
                "{}: no value for the constant {} that {} declares (each trajectory's meta.json gives the model's constants)",
                file.display(),
                c.name,
                a.model()
            )));
        }
    }
    let init = parse_init(&a.init)?;
    let start = start_values(&sys, &data, &init)?;
    let opts = DiagnoseOptions {
        alpha: a.alpha,
        max_rounds: a.max_effects.unwrap_or(usize::MAX),
        input_noise: match a.input_noise.as_str() {
            "auto" => InputNoise::Auto,
            "stated" => InputNoise::Stated,
            "estimate" => InputNoise::Estimate,
            "none" => InputNoise::None,
            s => {
                return Err(Failure(format!(
                    "--input-noise {s}: expected stated, estimate or none (or auto)"
                )))
            }
        },
        generate: a.generated && !a.no_generated,
        ..DiagnoseOptions::default()
    };
    let bar = crate::progress::Progress::new("diagnose", 0, "");
    let progress = |m: &str| bar.set_message(m);
    let d = diagnose(&sys, lib.as_ref(), &data, &start, &opts, &progress)?;
    drop(bar);
    let units = Units::new(&sys, lib.as_ref(), opts.generate, &d);
    let text = render_text(&d, a.data(), &units);
    if a.json {
        crate::json::print(&crate::json::diagnose(&d, &units))?;
    } else {
        out!("{text}");
    }
    if let Some(dir) = &a.report {
        write_folder_atomically(
            dir,
            a.force,
            &reads,
            &crate::diagnose_report::report_files(&d, &text, &units),
        )?;
        if !a.json {
            outln!("report written to {dir}/report.md");
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn white_rms(f: &ModelFit) -> f64 {
    (f.cost / f.n.max(1) as f64).sqrt()
}

fn rms_text(f: &ModelFit, d: &Diagnosis) -> String {
    f.rms
        .iter()
        .zip(&d.sigma)
        .map(|((n, r), (_, s))| format!("{n} {r:.4e} ({:.2} sigma)", r / s))
        .collect::<Vec<_>>()
        .join(", ")
}

fn structure_text(f: &ModelFit, out: &mut String) {
    let st = f.residuals.structure();
    if st.is_empty() {
        let _ = writeln!(
            out,
            "  consistent with noise (no test above z = {})",
            obsan_diagnose::Z_STRUCTURE
        );
    }
    for s in st {
        let _ = writeln!(out, "  {:<10} z = {:>6.2}  {}", s.test, s.z, s.description);
    }
}

/// A candidate's name, with `*` when it was generated.
fn mark(c: &CandidateResult) -> String {
    if c.origin == obsan_diagnose::ORIGIN_GENERATED {
        format!("{}*", c.effect)
    } else {
        c.effect.clone()
    }
}

/// A named effect's name, with `*` when it was generated.
fn named_mark(n: &Named) -> String {
    if n.origin == obsan_diagnose::ORIGIN_GENERATED {
        format!("{}*", n.effect)
    } else {
        n.effect.clone()
    }
}

fn hidden_text(c: &CandidateResult) -> String {
    let vector: Vec<String> = c
        .symmetry
        .iter()
        .map(|(n, v)| format!("{v:+.3} d/d{n}"))
        .collect();
    // Other params in the null vector absorb the effect; entries with
    // [k] are trajectory k's initial state.
    let absorbers: Vec<&str> = c
        .symmetry
        .iter()
        .map(|t| t.0.as_str())
        .filter(|n| !n.contains('[') && !c.params.iter().any(|p| p == n))
        .collect();
    if c.symmetry.is_empty() {
        "the rank test finds it not identifiable (no null vector could be evaluated at the fit)"
            .into()
    } else if c.symmetry.len() == 1 {
        "these data leave it without effect on the outputs (its inputs vanish here, e.g. at constant speed)".into()
    } else if absorbers.is_empty() {
        format!(
            "absorbed by the initial states (null vector {})",
            vector.join(" ")
        )
    } else {
        format!(
            "absorbed by {} (null vector {})",
            absorbers.join(", "),
            vector.join(" ")
        )
    }
}

/// `name = value ± sd unit [± robust]`: the robust sd (trajectories as
/// clusters) where there is one.
fn with_robust(est: &[(String, f64, f64)], robust: &[f64], u: &Units) -> Vec<String> {
    est.iter()
        .enumerate()
        .map(
            |(i, (n, v, sd))| match robust.get(i).filter(|r| r.is_finite()) {
                Some(r) => format!("{n} = {} [± {r:.1e}]", u.pm(n, *v, *sd)),
                None => format!("{n} = {}", u.pm(n, *v, *sd)),
            },
        )
        .collect()
}

pub fn render_text(d: &Diagnosis, data: &str, u: &Units) -> String {
    let mut s = String::new();
    let n_traj = d.nominal.initial_states.len();
    let _ = writeln!(
        s,
        "obsan diagnose: model {} on {data} ({n_traj} trajectories, {} output samples)",
        d.model, d.nominal.n
    );
    verdict(d, &mut s, u);
    let _ = writeln!(s, "\nstart: {}", d.start);
    let sig: Vec<String> = d
        .sigma
        .iter()
        .map(|(n, v)| format!("{n} {v:.4e}"))
        .collect();
    let _ = writeln!(
        s,
        "output noise: {} ({}); input class: {}",
        sig.join(", "),
        if d.sigma_estimated {
            match d.relevels.iter().any(|r| r.replaced) {
                true => "estimated from the residuals, again after each naming (these are the last): the level test is void",
                false => "estimated from the residuals: the level test is void",
            }
        } else {
            "stated"
        },
        d.input_class
    );
    if !d.input_noise.is_empty() {
        let c: Vec<String> = d
            .input_noise
            .iter()
            .map(|(n, v)| format!("{n} {v:.3e}"))
            .collect();
        let how = match (d.input_noise_source.as_str(), d.input_noise_lr.last()) {
            ("estimated", Some(lr)) => format!(
                "estimated by restricted maximum likelihood, linearised about the fit; \
                 likelihood ratio against white output noise {lr:.0}"
            ),
            (src, _) => src.to_string(),
        };
        let _ = writeln!(
            s,
            "input noise c (spectral density c|u|): {} ({how}); residuals weighed by \
             generalised least squares",
            c.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "\nnominal fit: residual RMS {}; whitened RMS {:.3} (white noise: 1)",
        rms_text(&d.nominal, d),
        white_rms(&d.nominal)
    );
    structure_text(&d.nominal, &mut s);
    rounds_text(d, &mut s, u);
    let _ = writeln!(s);
    let unseparated: Vec<_> = d
        .competing
        .iter()
        .filter(|c| c.established.is_none() && c.named_form.is_none())
        .collect();
    if d.named.is_empty() && unseparated.is_empty() {
        let _ = writeln!(s, "named: none: no candidate effect is significant");
    } else if d.named.is_empty() {
        let _ = writeln!(
            s,
            "named: none: the best candidates compete, not separated by these data"
        );
    }
    named_text(d, &mut s, u);
    combinations_text(d, &mut s, u);
    for c in &unseparated {
        let _ = writeln!(
            s,
            "competing explanations, not separated by these data (round {}, neither named): {}",
            c.round,
            obsan_diagnose::statistics::competing_text(c)
        );
    }
    for c in d.competing.iter().filter(|c| c.established.is_none()) {
        if let Some(n) = &c.named_form {
            let _ = writeln!(
                s,
                "one effect in two forms, not separated by these data (round {}, {n} named, the \
                 stronger together): {}",
                c.round,
                obsan_diagnose::statistics::competing_text(c)
            );
        }
    }
    for c in &d.suggested {
        let _ = writeln!(
            s,
            "suggested, not established: {}: {} (LR {:.1} above its critical value, but {:.1} sds \
             from 0 with the larger of the model's and the cluster-robust sd: not named)",
            mark(c),
            with_robust(&c.estimates, &c.robust_sd, u).join(", "),
            c.lr,
            c.wald_z
        );
    }
    // A candidate the heading-free check vetoed, once (its last round).
    let mut vetoed: Vec<&CandidateResult> = Vec::new();
    for c in d.rounds.iter().rev().flat_map(|r| r.iter().rev()) {
        if c.common_mode.as_ref().is_some_and(|v| v.vetoed)
            && !vetoed.iter().any(|x| x.effect == c.effect)
        {
            vetoed.push(c);
        }
    }
    for c in vetoed.iter().rev() {
        if let Some(v) = &c.common_mode {
            let _ = writeln!(s, "caution: {}", v.veto_text(&mark(c)));
        }
    }
    for c in &d.input_checks {
        let est: Vec<String> = c
            .estimates
            .iter()
            .map(|(p, v, sd)| format!("{p} = {}", u.pm(p, *v, *sd)))
            .collect();
        let _ = writeln!(
            s,
            "input check {}: {} (z {:.1}, {}): {}",
            c.effect,
            if est.is_empty() {
                c.note.clone()
            } else {
                est.join(", ")
            },
            c.z,
            c.note,
            if c.significant {
                "the measured inputs disagree with the commanded relation"
            } else {
                "consistent"
            }
        );
        if c.significant {
            for t in &c.per_trajectory {
                let est: Vec<String> = t
                    .estimates
                    .iter()
                    .map(|(p, v, sd)| format!("{p} = {}", u.pm(p, *v, *sd)))
                    .collect();
                let _ = writeln!(
                    s,
                    "  trajectory {}: {} (z {:.1})",
                    t.trajectory,
                    est.join(", "),
                    t.z
                );
            }
        }
    }
    let _ = writeln!(
        s,
        "\nfinal fit: residual RMS {}; whitened RMS {:.3}",
        rms_text(&d.final_fit, d),
        white_rms(&d.final_fit)
    );
    structure_text(&d.final_fit, &mut s);
    if !d.final_fit.residuals.consistent_with_noise() && d.named.len() < d.rounds.len().max(1) {
        let unfitted = unfitted_file_candidates(d);
        if unfitted.is_empty() {
            let _ = writeln!(s, "  no candidate explains this structure: the model misses something not in the effects file");
        } else {
            let _ = writeln!(
                s,
                "  no candidate explains this structure; not really fitted in the last round: {} \
                 (failed, not fitted, or its estimate never left its start), so the effects \
                 file is not ruled out",
                unfitted.join(", ")
            );
        }
    }
    if !d.hidden.is_empty() {
        let _ = writeln!(s, "\nthese data cannot reveal:");
        for c in &d.hidden {
            let _ = writeln!(s, "  {}: {}", mark(c), hidden_text(c));
        }
    }
    if !d.generated_dropped.is_empty() {
        let _ = writeln!(s, "\ngenerated candidates left out:");
        for (n, why) in &d.generated_dropped {
            let _ = writeln!(s, "  {n}: {why}");
        }
    }
    s
}

/// Every named effect with its residuals and cautions.
fn named_text(d: &Diagnosis, s: &mut String, u: &Units) {
    for (k, n) in d.named.iter().enumerate() {
        let est = with_robust(&n.estimates, &n.robust_sd, u);
        if n.origin == obsan_diagnose::ORIGIN_RELATION {
            let _ = writeln!(
                s,
                "named: {}: {} ({}; an input relation: the measured inputs contradict the \
                 declared restriction, z {:.1}, p {:.1e}; the fit uses the measured inputs, so \
                 the extended model carries it in its restriction)",
                n.effect,
                est.join(", "),
                n.description,
                n.lr.sqrt(),
                n.p_value
            );
            continue;
        }
        let before: Vec<String> = n
            .rms_before
            .iter()
            .map(|r| format!("{:.4e}", r.1))
            .collect();
        let after: Vec<String> = n.rms_after.iter().map(|r| format!("{:.4e}", r.1)).collect();
        if n.origin == obsan_diagnose::ORIGIN_GENERATED {
            let _ = writeln!(
                s,
                "named: {} (generated from the model's structure, not in the effects file): {}, {}",
                n.effect,
                n.description,
                est.join(", ")
            );
        } else {
            let _ = writeln!(
                s,
                "named: {}: {} ({})",
                n.effect,
                est.join(", "),
                n.description
            );
        }
        let _ = writeln!(
            s,
            "  residual RMS {} -> {} (LR {:.1}, p {:.1e})",
            before.join(", "),
            after.join(", "),
            n.lr,
            n.p_value
        );
        // The LR test reads the residuals as independent within a
        // trajectory (up to the inflation); the spread across trajectories
        // does not need that.
        let crit = d.lr_critical.sqrt();
        for ((p, v, _), r) in n.estimates.iter().zip(&n.robust_sd) {
            if r.is_finite() && *r > 0.0 && (v / r).abs() < crit {
                let _ = writeln!(
                    s,
                    "  caution: across trajectories {p} is only {:.1} sd from 0 (critical {crit:.1}): \
                     the residuals are correlated within trajectories and the LR overstates the evidence",
                    (v / r).abs()
                );
            }
        }
        for rv in &n.rivals {
            let why = match rv.jointly_identifiable {
                Some(false) => "together they are not identifiable on these data, so which one acts cannot be told from them",
                Some(true) => "both stay identifiable together, but these data favour neither strongly",
                None => "not tested together",
            };
            let _ = writeln!(
                s,
                "  caution: {} fits almost as well (BIC {:+.1} against it): {why}",
                rv.effect, rv.delta_bic
            );
        }
        if let Some(c) = n.curvature.as_ref().filter(|_| n.stand_in) {
            let _ = writeln!(
                s,
                "  stand-in: {} over [{:.4e}, {:.4e}]; {} is what this form absorbs of an effect \
                 of another form",
                curvature_text(c),
                c.span[0],
                c.span[1],
                n.effect
            );
        }
        // Once per pair, under the later of the two named effects; the
        // user's model's params are in --json only.
        for (c, other) in d.correlated_with_earlier(k) {
            let text = c.caution_text(&named_mark(n), &named_mark(other));
            let _ = writeln!(s, "  caution: {text}");
        }
    }
}

/// The curvature left in the outputs a stand-in rewrites, in words.
fn curvature_text(c: &obsan_diagnose::Curvature) -> String {
    let outs = match c.outputs.as_slice() {
        [a] => a.clone(),
        [a, b] => format!("{a}, {b}"),
        [a, b, ..] => format!("{a}, {b}, ... ({} outputs)", c.outputs.len()),
        [] => "its outputs".into(),
    };
    format!(
        "the residuals of {outs} still curve in the predicted value ({:.2e} ± {:.1e} at the \
         span's ends, z {:.1}, critical {:.1})",
        c.coefficient,
        c.sd,
        c.z,
        obsan_diagnose::Z_STAND_IN
    )
}

/// The pairs fixed only in combination, with the combination the data fix.
fn combinations_text(d: &Diagnosis, s: &mut String, u: &Units) {
    for c in &d.combinations {
        let _ = writeln!(s, "{}", combination_line(c, u));
    }
}

/// One pair fixed only in combination, as one line.
fn combination_line(c: &Combination, u: &Units) -> String {
    let (head, tail) = match (c.named, c.established) {
        (true, true) => ("fixed in combination", "each alone is an extrapolation"),
        (true, false) => (
            "fixed in combination, not established",
            "each alone is an extrapolation",
        ),
        (false, true) => (
            "fixed in combination (suggested effects fitted together; not in the extended model)",
            "neither alone is established",
        ),
        (false, false) => (
            "suggested in combination, not established (fitted together; not in the extended model)",
            "neither alone is established",
        ),
    };
    format!(
        "{head}: {} and {}: {}; Wald z {:.1} (alone {:.1} and {:.1}): {tail}",
        c.effects[0],
        c.effects[1],
        u.combination(c),
        c.wald_z,
        c.wald_z_alone[0],
        c.wald_z_alone[1]
    )
}

/// The refit notes and every round's table of candidates.
fn rounds_text(d: &Diagnosis, s: &mut String, u: &Units) {
    for r in &d.refits {
        let _ = writeln!(
            s,
            "  note: {} fit had not converged: refitted from {}'s point with its params at 0, \
             -2 log L {:.1} -> {:.1}; round {}'s candidates are compared with the refit{}",
            if r.round == 1 {
                "the nominal"
            } else {
                "the current"
            },
            r.from,
            r.m2ll_before,
            r.m2ll_after,
            r.round,
            if r.round == 1 { " (shown above)" } else { "" }
        );
    }
    for (i, round) in d.rounds.iter().enumerate() {
        let _ = writeln!(
            s,
            "\ncandidates, round {} (named when LR > {:.2}: p < alpha / candidates, and BIC falls; [± sd across trajectories], cluster-robust):",
            i + 1,
            d.lr_critical
        );
        if d.lr_critical_generated.is_finite() {
            let _ = writeln!(
                s,
                "  (candidates marked * are generated from the model's structure: named when LR > {:.2}, their share of alpha split over them)",
                d.lr_critical_generated
            );
        }
        let mut hidden: Vec<String> = Vec::new();
        for c in round {
            if let Some(e) = &c.error {
                let _ = writeln!(s, "  {:<20} failed: {e}", mark(c));
            } else if let Some(v) = c
                .common_mode
                .as_ref()
                .filter(|v| c.screened_out && v.predicted && v.vetoed)
            {
                let sc = c.score.unwrap_or(0.0);
                let _ = writeln!(
                    s,
                    "  {:<20} not fitted: score {sc:.2}; the heading-free check, predicted, vetoes it",
                    mark(c)
                );
                let _ = writeln!(s, "    not named: {}", v.veto_text(&mark(c)));
            } else if c.screened_out {
                let sc = c.score.unwrap_or(0.0);
                let why = if sc < d.screen_threshold {
                    format!("below the screen's {:.2}", d.screen_threshold)
                } else {
                    format!(
                        "x {} below this round's best LR: it cannot win the round",
                        obsan_diagnose::SCREEN_SAFETY
                    )
                };
                let _ = writeln!(s, "  {:<20} not fitted: score {sc:.2} {why}", mark(c));
            } else if !c.identifiable {
                hidden.push(mark(c));
            } else {
                let est = with_robust(&c.estimates, &c.robust_sd, u);
                let _ = writeln!(
                    s,
                    "  {:<20} {:<28} LR {:>8.2}  p {:.1e}  dBIC {:>8.1}{}",
                    mark(c),
                    est.join(", "),
                    c.lr,
                    c.p_value,
                    c.delta_bic,
                    if c.significant {
                        "  significant"
                    } else if c.suggested {
                        "  suggested (Wald z below critical)"
                    } else {
                        ""
                    }
                );
                match c.common_mode.as_ref().filter(|v| v.applies) {
                    Some(v) if v.vetoed => {
                        let _ = writeln!(s, "    not named: {}", v.veto_text(&mark(c)));
                    }
                    Some(v) => {
                        let _ = writeln!(
                            s,
                            "    supported by simultaneous differences: {} = {:.4} ± {:.4} ({:.1} combined robust sds from the full fit, limit {:.2})",
                            v.param, v.differences, v.differences_robust_sd, v.z, v.limit
                        );
                    }
                    None => {}
                }
            }
        }
        if !hidden.is_empty() {
            let _ = writeln!(
                s,
                "  not identifiable on these data: {} (see \"these data cannot reveal\")",
                hidden.join(", ")
            );
        }
        for r in d.relevels.iter().filter(|r| r.round == i + 1) {
            crate::diagnose_levels::after_round(r)
                .iter()
                .for_each(|l| s.push_str(&format!("{l}\n")));
        }
    }
}

/// The effects file's candidates of the last round that were identifiable
/// but not really fitted: failed, screened out, or a fit that never moved its
/// params (LR 0 included).
fn unfitted_file_candidates(d: &Diagnosis) -> Vec<String> {
    d.rounds
        .last()
        .map(|r| {
            r.iter()
                .filter(|c| c.origin != obsan_diagnose::ORIGIN_GENERATED)
                // A fit that never moved its params from their start
                // (`moved`) weighed nothing: the effect is not ruled out.
                .filter(|c| {
                    c.error.is_some()
                        || c.screened_out
                        || (c.identifiable && (!c.moved || c.lr == 0.0))
                })
                .map(|c| c.effect.clone())
                .collect()
        })
        .unwrap_or_default()
}

/// The one-paragraph verdict that leads the text: what is named with its
/// magnitude, what is only suggested, whether the nominal fit had to be
/// refitted, and what remains unexplained: a reader sees the answer before
/// the tables.
fn verdict(d: &Diagnosis, s: &mut String, u: &Units) {
    let mut parts: Vec<String> = Vec::new();
    if d.named.is_empty() {
        parts.push("nothing named".into());
    } else {
        let named: Vec<String> = d
            .named
            .iter()
            .map(|n| {
                format!(
                    "{} ({})",
                    named_mark(n),
                    with_robust(&n.estimates, &n.robust_sd, u).join(", ")
                )
            })
            .collect();
        parts.push(format!("named {}", named.join("; ")));
    }
    // Named effects whose outputs still curve: stand-ins, grouped by the
    // outputs they rewrite (a scale and a bias of one sensor share them).
    let mut stand_ins: Vec<(Vec<&str>, &obsan_diagnose::Curvature)> = Vec::new();
    for n in d.named.iter().filter(|n| n.stand_in) {
        let Some(c) = &n.curvature else { continue };
        match stand_ins.iter_mut().find(|g| g.1.outputs == c.outputs) {
            Some(g) => g.0.push(&n.effect),
            None => stand_ins.push((vec![&n.effect], c)),
        }
    }
    for (names, c) in stand_ins {
        let verb = if names.len() == 1 {
            "is a stand-in"
        } else {
            "are stand-ins"
        };
        parts.push(format!(
            "{} {verb} for an effect of another form: {}",
            names.join(" and "),
            curvature_text(c)
        ));
    }
    if !d.suggested.is_empty() {
        let sug: Vec<String> = d
            .suggested
            .iter()
            .map(|c| format!("{} (Wald z {:.1})", mark(c), c.wald_z))
            .collect();
        parts.push(format!("suggested, not established: {}", sug.join(", ")));
    }
    for c in &d.combinations {
        let what = if c.established {
            "fixed in combination"
        } else {
            "not established even in combination"
        };
        parts.push(format!(
            "{} and {} {what}: {}",
            c.effects[0],
            c.effects[1],
            u.combination(c)
        ));
    }
    for c in d.competing.iter().filter(|c| c.established.is_none()) {
        parts.push(match &c.named_form {
            None => format!(
                "competing explanations, not separated by these data: {}; what they explain \
                 remains unexplained (neither is in the final model)",
                obsan_diagnose::statistics::competing_text(c)
            ),
            Some(n) => format!(
                "one effect in two forms, not separated by these data: {}; {n} is named (the \
                 stronger together), its form not established",
                obsan_diagnose::statistics::competing_text(c)
            ),
        });
    }
    parts.extend(crate::diagnose_levels::weak_part(d));
    if !d.nominal_converged {
        parts.push("the nominal fit from the start had not converged and was refitted".into());
    }
    let st = d.final_fit.residuals.structure();
    if st.is_empty() {
        parts.push("the final fit is consistent with noise".into());
    } else {
        let what: Vec<String> = st
            .iter()
            .map(|x| format!("{} (z {:.1})", x.test, x.z))
            .collect();
        parts.push(format!("unexplained: {}", what.join(", ")));
    }
    if !d.hidden.is_empty() {
        let h: Vec<String> = d.hidden.iter().map(mark).collect();
        parts.push(format!("these data cannot reveal {}", h.join(", ")));
    }
    let _ = writeln!(s, "verdict: {}.", parts.join("; "));
}

/// `obsan import mrclam`: read one robot's files, write a dataset folder.
pub fn import_mrclam(a: &MrclamArgs) -> Result<ExitCode, Failure> {
    crate::fsio::check_outside(&a.out, &[&a.source])?;
    let dir = std::path::Path::new(&a.source);
    // Invalid UTF-8 is an error at its line and column (read_text).
    let read = |name: &str| -> Result<(String, String), Failure> {
        let p = dir.join(name).display().to_string();
        Ok((crate::fsio::read_text(&p)?, p))
    };
    let odo = read(&format!("robot{}_Odometry.txt", a.robot))?;
    let meas = read(&format!("robot{}_Measurement.txt", a.robot))?;
    let lms = read("Landmark_Groundtruth.dat")?;
    // The ground truth only fills truth.json (and the outputs of
    // --vicon-poses): a missing file is said, an unreadable one an error.
    let gt_path = dir.join(format!("robot{}_Groundtruth.txt", a.robot));
    let gt = if gt_path.exists() {
        Some(read(&format!("robot{}_Groundtruth.txt", a.robot))?)
    } else {
        if !a.vicon_poses {
            eprintln!(
                "warning: no {}: truth.json will list no window's ground truth",
                gt_path.display()
            );
        }
        None
    };
    let text = obsan_data::MrclamText {
        odometry: (&odo.0, &odo.1),
        measurements: (&meas.0, &meas.1),
        landmarks: (&lms.0, &lms.1),
        groundtruth: gt.as_ref().map(|g| (g.0.as_str(), g.1.as_str())),
    };
    let what = if a.vicon_poses {
        obsan_data::MrclamOutputs::ViconPoses
    } else {
        obsan_data::MrclamOutputs::Landmarks
    };
    let bar = crate::progress::Progress::new("import mrclam", 0, "");
    bar.set_message(&format!("converting robot {}'s logs", a.robot));
    let (mut data, mut truth) =
        obsan_data::mrclam_convert(&text, a.window, a.min_measurements, what)?;
    drop(bar);
    if a.max_windows > 0 {
        data.trajectories.truncate(a.max_windows);
        truth.retain(|t| data.trajectories.iter().any(|d| d.name == t.name));
    }
    let truth_json = serde_json::json!({
        "source": "UTIAS MRCLAM (Leung, Halpern, Barfoot, Liu, IJRR 2011): Vicon ground truth per window; estimators never read it",
        "robot": a.robot,
        "windows": truth,
    });
    let files = crate::simulate::dataset_files(
        &data,
        &[("truth.json", serde_json::to_string_pretty(&truth_json)?)],
    )?;
    write_folder_atomically(&a.out, a.force, &[&a.source], &files)?;
    let n: usize = data.trajectories.iter().map(|t| t.outputs.len()).sum();
    outln!(
        "wrote {}: robot {}, {} windows of {} s, {} {}",
        a.out,
        a.robot,
        data.trajectories.len(),
        a.window,
        n,
        if a.vicon_poses {
            "Vicon poses"
        } else {
            "landmark measurements"
        }
    );
    Ok(ExitCode::SUCCESS)
}
