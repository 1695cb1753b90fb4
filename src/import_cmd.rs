//! `obsan import si-jl`, `sbml`, `petab` and `strike-goldd`: foreign model text to .sys (docs/import.md). The
//! translation is obsan-import's; this reads the file, checks the produced
//! .sys with obsan-model (so a model outside obsan's class is refused at its
//! line in the source) and writes the result.

use crate::cli::{PetabArgs, SbmlArgs, SiJlArgs, StrikeGolddArgs};
use crate::{json, Failure};
use obsan_import::{Converted, ImportError};
use std::path::Path;
use std::process::ExitCode;

fn located(path: &str, e: &ImportError) -> String {
    format!("{path}:{e}")
}

/// Read the produced .sys back (parse and normal form): an error is reported
/// at the source line its equation came from.
fn check(path: &str, c: &Converted, at: (usize, usize), key: &str) -> Result<(), String> {
    let origin = format!("{}.sys", c.name);
    let res = obsan_model::System::parse(&c.sys_text, &origin)
        .and_then(|s| s.normal_form(None, &[]).map(|_| ()));
    match res {
        Ok(()) => Ok(()),
        Err(e) => {
            let (l, col) = e.line.and_then(|l| c.source_of(l)).unwrap_or(at);
            Err(format!(
                "{path}:{l}:{col}: model :{key} is outside obsan's .sys class: {}",
                e.message
            ))
        }
    }
}

/// Refuse a target that exists (without --force) or is a folder: checked for
/// every file a command writes before it writes the first, so that a refusal
/// leaves nothing partial behind.
fn writable(out: &str, force: bool) -> Result<(), Failure> {
    let p = Path::new(out);
    if p.exists() && !force {
        return Err(Failure(format!("{out} exists (--force replaces it)")));
    }
    if p.is_dir() {
        return Err(Failure(format!("{out} is a folder")));
    }
    Ok(())
}

/// Write `text` to `out` whole (a sibling temporary file renamed into place).
fn write_whole(out: &str, text: &str, force: bool) -> Result<(), Failure> {
    writable(out, force)?;
    let p = Path::new(out);
    if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| Failure(format!("cannot create {}: {e}", dir.display())))?;
    }
    let tmp = format!("{out}.tmp-{}", std::process::id());
    std::fs::write(&tmp, text).map_err(|e| Failure(format!("cannot write {tmp}: {e}")))?;
    std::fs::rename(&tmp, out).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Failure(format!("cannot write {out}: {e}"))
    })
}

/// What `--json` prints: the models converted and the files written.
fn report(format: &str, source: &str) -> json::Import {
    json::Import {
        format: format.into(),
        inputs_out: None,
        known_inputs: Vec::new(),
        models: Vec::new(),
        refused: Vec::new(),
        source: source.into(),
        values: None,
    }
}

/// One converted model: written to `out`, or its text kept for stdout.
fn model(key: Option<&str>, c: &Converted, out: Option<&str>) -> json::ImportedModel {
    json::ImportedModel {
        key: key.map(str::to_string),
        path: out.map(str::to_string),
        system: c.name.clone(),
        text: if out.is_none() {
            Some(c.sys_text.clone())
        } else {
            None
        },
    }
}

/// Write the converted model to `out`, or print it; with `--json` print the report
/// instead of the text and the summary line.
fn finish(
    mut r: json::Import,
    key: Option<&str>,
    c: &Converted,
    out: Option<&str>,
    as_json: bool,
) -> Result<(), Failure> {
    r.models.push(model(key, c, out));
    if as_json {
        return json::print(&r);
    }
    match out {
        Some(out) => match key {
            Some(k) => outln!("model :{k} written to {out}"),
            None => outln!("{} written to {out}", r.source),
        },
        None => out!("{}", c.sys_text),
    }
    Ok(())
}

pub fn si_jl(a: &SiJlArgs) -> Result<ExitCode, Failure> {
    let path = a.source.as_str();
    let text = crate::fsio::read_text(path)?;
    let models = obsan_import::si_jl_models(&text).map_err(|e| Failure(located(path, &e)))?;
    if models.is_empty() {
        return Err(Failure(format!("{path}: no @ODEmodel(...) found")));
    }
    if a.list {
        for m in &models {
            outln!(
                "{}\t{}:{}\t{}",
                m.key,
                path,
                m.line,
                m.name.as_deref().unwrap_or("")
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let convert = |m: &obsan_import::SiJlModel| -> Result<Converted, String> {
        let c = obsan_import::si_jl_convert(&text, m, path).map_err(|e| located(path, &e))?;
        check(path, &c, (m.line, m.col), &m.key)?;
        Ok(c)
    };
    if let Some(dir) = &a.all {
        let mut r = report("si-jl", path);
        for m in &models {
            match convert(m) {
                Ok(c) => {
                    let out = Path::new(dir).join(format!("{}.sys", c.name));
                    let out = out.to_string_lossy();
                    write_whole(&out, &c.sys_text, a.force)?;
                    r.models.push(model(Some(&m.key), &c, Some(&out)));
                }
                Err(msg) => {
                    eprintln!("{msg}");
                    r.refused.push(msg);
                }
            }
        }
        let refused = r.refused.len();
        if a.json {
            json::print(&r)?;
        } else {
            outln!(
                "{} of {} models written to {dir}, {refused} refused",
                r.models.len(),
                models.len()
            );
        }
        if refused > 0 {
            return Err(Failure(format!(
                "{refused} model(s) of {path} refused (messages above)"
            )));
        }
        return Ok(ExitCode::SUCCESS);
    }
    let m = match &a.model {
        Some(k) => models.iter().find(|m| &m.key == k).ok_or_else(|| {
            let keys: Vec<&str> = models.iter().map(|m| m.key.as_str()).collect();
            Failure(format!(
                "{path}: no model '{k}' (models: {})",
                keys.join(", ")
            ))
        })?,
        None if models.len() == 1 => &models[0],
        None => {
            let keys: Vec<&str> = models.iter().map(|m| m.key.as_str()).collect();
            return Err(Failure(format!(
                "{path} holds {} models: choose one with --model ({}) or use --all DIR",
                models.len(),
                keys.join(", ")
            )));
        }
    };
    let c = convert(m).map_err(Failure)?;
    if let Some(out) = &a.out {
        write_whole(out, &c.sys_text, a.force)?;
    }
    let r = report("si-jl", path);
    finish(r, Some(&m.key), &c, a.out.as_deref(), a.json)?;
    Ok(ExitCode::SUCCESS)
}

pub fn sbml(a: &SbmlArgs) -> Result<ExitCode, Failure> {
    let path = a.source.as_str();
    let text = crate::fsio::read_text(path)?;
    let c = obsan_import::sbml_to_sys(&text, path, &a.observe)
        .map_err(|e| Failure(located(path, &e)))?;
    // Everything is computed and every target checked before anything is
    // written: a refusal writes nothing.
    let inputs =
        obsan_import::sbml_inputs(&text, a.until).map_err(|e| Failure(located(path, &e)))?;
    check_sys(path, &c)?;
    let values = match &a.values {
        Some(_) => {
            let values =
                obsan_import::sbml_values(&text).map_err(|e| Failure(located(path, &e)))?;
            // `{:?}` is the shortest text that reads back to the same f64.
            Some(
                values
                    .iter()
                    .map(|(n, v)| format!("{n} = {v:?}\n"))
                    .collect::<String>(),
            )
        }
        None => None,
    };
    let course = a.inputs_out.as_ref().filter(|_| !inputs.names.is_empty());
    for out in [&a.out, &a.values].into_iter().flatten().chain(course) {
        writable(out, a.force)?;
    }
    if let Some(out) = &a.out {
        write_whole(out, &c.sys_text, a.force)?;
    }
    let mut r = report("sbml", path);
    if let (Some(out), Some(values)) = (&a.values, &values) {
        write_whole(out, values, a.force)?;
        r.values = Some(out.clone());
    }
    r.known_inputs = inputs.names.clone();
    match (&a.inputs_out, inputs.names.is_empty()) {
        (Some(out), true) => {
            eprintln!("note: {path} has no <piecewise> of time: no known input, {out} not written");
        }
        (Some(out), false) => {
            write_whole(out, &inputs.csv(), a.force)?;
            r.inputs_out = Some(out.clone());
            eprintln!(
                "{} input(s) ({}): course over [0, {}] written to {out}",
                inputs.names.len(),
                inputs.names.join(", "),
                a.until.unwrap_or(0.0)
            );
        }
        (None, _) => {
            for (n, (l, c)) in inputs.names.iter().zip(&inputs.places) {
                eprintln!(
                    "note: {path}:{l}:{c}: the <piecewise> here is the known input {n}: \
                     supply its course to simulate (--inputs FILE.csv, as --inputs-out FILE.csv \
                     --until T writes it)"
                );
            }
        }
    }
    finish(r, None, &c, a.out.as_deref(), a.json)?;
    Ok(ExitCode::SUCCESS)
}

pub fn strike_goldd(a: &StrikeGolddArgs) -> Result<ExitCode, Failure> {
    let path = a.source.as_str();
    // MATLAB files are often Latin-1 (accents in comments): read as such when not UTF-8.
    let text = match crate::fsio::read_text(path) {
        Ok(t) => t,
        Err(e) => match std::fs::read(path) {
            Ok(b) if std::str::from_utf8(&b).is_err() => b.iter().map(|&c| c as char).collect(),
            _ => return Err(e),
        },
    };
    let c =
        obsan_import::strike_goldd_to_sys(&text, path).map_err(|e| Failure(located(path, &e)))?;
    check_sys(path, &c)?;
    if let Some(out) = &a.out {
        write_whole(out, &c.sys_text, a.force)?;
    }
    finish(
        report("strike-goldd", path),
        None,
        &c,
        a.out.as_deref(),
        a.json,
    )?;
    Ok(ExitCode::SUCCESS)
}

/// Read the produced .sys back: an error is reported at its source line.
fn check_sys(path: &str, c: &Converted) -> Result<(), Failure> {
    let origin = format!("{}.sys", c.name);
    obsan_model::System::parse(&c.sys_text, &origin)
        .and_then(|s| s.normal_form(None, &[]).map(|_| ()))
        .map_err(|e| {
            let (l, col) = e.line.and_then(|l| c.source_of(l)).unwrap_or((1, 1));
            Failure(format!(
                "{path}:{l}:{col}: the model is outside obsan's .sys class: {}",
                e.message
            ))
        })
}

pub fn petab(a: &PetabArgs) -> Result<ExitCode, Failure> {
    use obsan_import::PetabFile as F;
    let yaml = a.source.as_str();
    let files = obsan_import::petab_files(&crate::fsio::read_text(yaml)?)
        .map_err(|e| Failure(located(yaml, &e)))?;
    // The tables and the model are named relative to the problem file's folder.
    let dir = Path::new(yaml).parent().unwrap_or(Path::new(""));
    let path_of = |f: &str| dir.join(f).to_string_lossy().into_owned();
    let (sbml, params, obs, conds) = (
        path_of(&files.sbml),
        path_of(&files.parameters),
        path_of(&files.observables),
        path_of(&files.conditions),
    );
    let meas: Vec<String> = files.measurements.iter().map(|m| path_of(m)).collect();
    let texts = (
        crate::fsio::read_text(&sbml)?,
        crate::fsio::read_text(&params)?,
        crate::fsio::read_text(&obs)?,
        crate::fsio::read_text(&conds)?,
        meas.iter()
            .map(|m| crate::fsio::read_text(m))
            .collect::<Result<Vec<String>, Failure>>()?,
    );
    let t = obsan_import::PetabTexts {
        sbml: &texts.0,
        parameters: &texts.1,
        observables: &texts.2,
        conditions: &texts.3,
        measurements: texts.4.iter().map(String::as_str).collect(),
    };
    let file = |f: F| -> &str {
        match f {
            F::Yaml => yaml,
            F::Sbml => &sbml,
            F::Parameters => &params,
            F::Observables => &obs,
            F::Conditions => &conds,
            F::Measurements(k) => meas.get(k).map_or(yaml, String::as_str),
        }
    };
    let c = obsan_import::petab_to_sys(&t, yaml, a.condition.as_deref())
        .map_err(|e| Failure(located(file(e.file), &e.error)))?;
    let origin = format!("{}.sys", c.name);
    obsan_model::System::parse(&c.sys_text, &origin)
        .and_then(|s| s.normal_form(None, &[]).map(|_| ()))
        .map_err(|e| {
            let line = e.line.unwrap_or(0);
            let (l, col) = c.source_of(line).unwrap_or((1, 1));
            let f = if c.table_lines.contains(&line) {
                &obs
            } else {
                &sbml
            };
            Failure(format!(
                "{f}:{l}:{col}: the problem is outside obsan's .sys class: {}",
                e.message
            ))
        })?;
    if let Some(out) = &a.out {
        write_whole(out, &c.sys_text, a.force)?;
    }
    finish(report("petab", yaml), None, &c, a.out.as_deref(), a.json)?;
    Ok(ExitCode::SUCCESS)
}
