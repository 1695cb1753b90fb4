//! Writing output folders: atomically, and never over what obsan did not write.
//!
//! Every folder obsan writes (a dataset, a report, figures) holds a manifest,
//! [`MANIFEST`], listing the files it wrote. `--force` replaces a folder only
//! when everything in it is listed there: a folder holding anything else
//! (the user's files, a symlink), the working directory or one of its
//! parents is refused, so `--force` cannot delete what obsan did not write.

use crate::Failure;
use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// The manifest's file name inside each folder obsan writes.
pub const MANIFEST: &str = ".obsan-manifest";
/// The manifest's first line; the rest is one relative path per line.
const MANIFEST_HEADER: &str = "# written by obsan: these files may be replaced by --force";

/// A text held in memory under a name that stands for a file (e.g.
/// `<string>`): [`read_text`] of that name reads it, so messages read
/// `<string>:3:7: ...`. Used by the Python package's `obsan.loads`.
#[derive(Clone, Debug)]
pub struct Overlay {
    pub name: String,
    pub text: String,
}

thread_local! {
    /// The overlay of the command running on this thread.
    static OVERLAY: std::cell::RefCell<Option<Overlay>> = const { std::cell::RefCell::new(None) };
}

/// Make `o` the overlay of this thread's commands.
pub(crate) fn set_overlay(o: Option<Overlay>) {
    OVERLAY.with(|x| *x.borrow_mut() = o);
}

/// Read a text file the user wrote (.sys, .eff, .dec): a BOM is dropped,
/// line endings normalised, and invalid UTF-8 is an error at its line and
/// column.
pub fn read_text(path: &str) -> Result<String, Failure> {
    let held = OVERLAY.with(|x| {
        x.borrow()
            .as_ref()
            .filter(|o| o.name == path)
            .map(|o| o.text.clone().into_bytes())
    });
    let bytes = match held {
        Some(b) => b,
        None => std::fs::read(path).map_err(|e| Failure(format!("cannot read {path}: {e}")))?,
    };
    obsan_model::decode_text(&bytes, path).map_err(|e| Failure(e.to_string()))
}

/// Temporary files and folders being written now (removed if the process
/// ends early: a signal, `--timeout`).
static WRITING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
/// Set once the process is ending: writers stop and commit nothing.
static ENDING: AtomicBool = AtomicBool::new(false);

/// Remove every temporary file or folder being written and keep any writer
/// from committing its output: called just before the process ends early
/// (SIGINT, SIGTERM, `--timeout`), so nothing partial is left behind. The
/// lock on the list is kept until the process exits.
pub fn abandon_writes() {
    ENDING.store(true, Ordering::SeqCst);
    let guard = WRITING.lock().unwrap_or_else(|p| p.into_inner());
    for p in guard.iter() {
        // A writer may be creating a file at this moment (it checks ENDING
        // before each one): retry briefly until the folder is gone.
        for _ in 0..200 {
            let gone = match std::fs::symlink_metadata(p) {
                Err(_) => true,
                Ok(m) if m.is_dir() => std::fs::remove_dir_all(p).is_ok(),
                Ok(_) => std::fs::remove_file(p).is_ok(),
            };
            if gone {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        }
    }
    std::mem::forget(guard);
}

/// Whether a write must stop: the process is ending, or the command was
/// cancelled (the Python package's Ctrl-C or `timeout`).
fn must_stop() -> bool {
    ENDING.load(Ordering::SeqCst) || obsan_expr::cancel_requested()
}

/// Note `p` as being written (see [`abandon_writes`]).
fn register(p: &Path) {
    let mut w = WRITING.lock().unwrap_or_else(|p| p.into_inner());
    w.push(p.to_path_buf());
}

/// Run `commit` (renames into place) unless the process is ending, then
/// forget `temps`: under the list's lock, so [`abandon_writes`] sees either
/// the temporaries or the committed output, never half of it.
pub(crate) fn commit_writes(
    temps: &[PathBuf],
    commit: impl FnOnce() -> Result<(), Failure>,
) -> Result<(), Failure> {
    let mut w = WRITING.lock().unwrap_or_else(|p| p.into_inner());
    let r = if must_stop() {
        Err(Failure("interrupted".into()))
    } else {
        commit()
    };
    w.retain(|p| !temps.contains(p));
    r
}

/// Write each (temporary file, bytes), then run `commit` (renaming them into
/// place) under the lock of [`commit_writes`]; the temporaries are
/// registered, so a signal or `--timeout` removes them. On an error the
/// caller removes them.
pub(crate) fn write_files_then(
    temps: &[(PathBuf, &[u8])],
    commit: impl FnOnce() -> Result<(), Failure>,
) -> Result<(), Failure> {
    let paths: Vec<PathBuf> = temps.iter().map(|(p, _)| p.clone()).collect();
    for (p, bytes) in temps {
        register(p);
        if let Err(e) = write_file(p, bytes) {
            let _ = commit_writes(&paths, || Ok(()));
            return Err(match e.kind() {
                std::io::ErrorKind::Interrupted => Failure("interrupted".into()),
                _ => Failure(format!("cannot write {}: {e}", p.display())),
            });
        }
    }
    commit_writes(&paths, commit)
}

/// Write `bytes` to a new file `p` in pieces, stopping (an error) once the
/// process is ending: a 100 MB file does not delay a signal's clean-up.
fn write_file(p: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut f = std::fs::File::create(p)?;
    for chunk in bytes.chunks(1 << 20) {
        if must_stop() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "interrupted",
            ));
        }
        f.write_all(chunk)?;
    }
    Ok(())
}

/// A path made absolute with symlinks resolved as far as it exists (the
/// rest appended, `.` and `..` applied by name), so two spellings of one
/// place compare equal.
fn resolved(p: &Path) -> PathBuf {
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    // Walk up to the deepest part that exists; `None` stands for `..`.
    let mut head = abs.clone();
    let mut tail: Vec<Option<std::ffi::OsString>> = Vec::new();
    loop {
        if let Ok(mut r) = head.canonicalize() {
            for part in tail.iter().rev() {
                match part {
                    Some(n) => r.push(n),
                    None => {
                        r.pop();
                    }
                }
            }
            return r;
        }
        match head.components().next_back() {
            Some(Component::Normal(n)) => tail.push(Some(n.to_os_string())),
            Some(Component::ParentDir) => tail.push(None),
            Some(Component::CurDir) => {}
            _ => return abs,
        }
        if !head.pop() {
            return abs;
        }
    }
}

/// Refuse an output (`out`, a folder or file the command writes) that is,
/// holds or lies inside something the same command reads (`reads`: its
/// input files and folders), compared by canonical path: `--force` must
/// never replace a command's own input, and an output inside an
/// input folder would change that input. Checked before any work is done.
pub fn check_outside(out: &str, reads: &[&str]) -> Result<(), Failure> {
    let o = resolved(Path::new(out));
    for r in reads {
        let i = resolved(Path::new(r));
        let why = if o == i {
            "it is"
        } else if i.starts_with(&o) {
            "it holds"
        } else if o.starts_with(&i) {
            "it lies inside"
        } else {
            continue;
        };
        return Err(Failure(format!(
            "refusing to write {out}: {why} {r}, which this command reads; choose another place"
        )));
    }
    Ok(())
}

/// Whether process `pid` is running; `None` where it cannot be told (no
/// /proc).
fn alive(pid: u32) -> Option<bool> {
    if !Path::new("/proc/self").exists() {
        return None;
    }
    Some(Path::new("/proc").join(pid.to_string()).exists())
}

/// Remove what an earlier run that ended without cleaning up (killed, power
/// lost) left in `parent`: `.NAME.obsan-tmp-PID` and `.NAME.obsan-old-PID`
/// folders of a process no longer running, each removal said on stderr.
fn remove_stale(parent: &Path) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let me = std::process::id();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = name.strip_prefix('.') else {
            continue;
        };
        let found = [".obsan-tmp-", ".obsan-old-"]
            .iter()
            .find_map(|k| rest.rsplit_once(k).map(|(_, pid)| (*k, pid)));
        let Some((kind, pid)) = found else { continue };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        let path = e.path();
        let ours_now = WRITING.lock().map(|w| w.contains(&path)).unwrap_or(true);
        if ours_now || !e.file_type().is_ok_and(|t| t.is_dir()) {
            continue;
        }
        if pid != me && alive(pid) != Some(false) {
            continue;
        }
        if kind == ".obsan-tmp-" {
            let _ = std::fs::remove_dir_all(&path);
        } else {
            remove_ours(&path);
        }
        if !path.exists() {
            eprintln!(
                "note: removed {}, left by an earlier obsan run (process {pid}) that did not finish",
                path.display()
            );
        }
    }
}

/// Write all files into a temporary sibling folder, then rename it into
/// place: a failure, a signal or `--timeout` leaves nothing behind. Missing
/// parent folders are created (as `mkdir -p` does). `reads` are the
/// command's inputs: `out` may not be, hold or lie inside one of them.
pub fn write_folder_atomically(
    out: &str,
    force: bool,
    reads: &[&str],
    files: &[(PathBuf, impl AsRef<[u8]>)],
) -> Result<(), Failure> {
    check_outside(out, reads)?;
    let target = Path::new(out);
    for (rel, _) in files {
        if !is_plain_relative(rel) || rel.as_os_str() == MANIFEST {
            return Err(Failure(format!(
                "internal: refusing to write {} into {out}",
                rel.display()
            )));
        }
    }
    // symlink_metadata: a symlink named like the target is not followed.
    let existing = std::fs::symlink_metadata(target).ok();
    if let Some(meta) = &existing {
        if !force {
            return Err(Failure(format!(
                "{out} already exists (use --force to replace a folder obsan wrote)"
            )));
        }
        if !meta.is_dir() {
            return Err(Failure(format!(
                "{out} exists and is not a folder: --force only replaces a folder obsan wrote"
            )));
        }
        replaceable(out, target)?;
    }
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(|e| {
        let why = if parent.exists() && !parent.is_dir() {
            format!("{} exists and is not a folder", parent.display())
        } else {
            e.to_string()
        };
        Failure(format!("cannot create {out}: {why}"))
    })?;
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().to_string())
        .ok_or_else(|| Failure(format!("cannot write {out}: it names no folder")))?;
    remove_stale(&parent);
    let pid = std::process::id();
    let tmp = parent.join(format!(".{name}.obsan-tmp-{pid}"));
    let old = parent.join(format!(".{name}.obsan-old-{pid}"));
    // create_dir fails if the name is taken, so what is removed below on
    // failure is only ever the folder made here. (A signal before it is
    // registered leaves it empty, for the next run's remove_stale.)
    if let Err(e) = std::fs::create_dir(&tmp) {
        return Err(Failure(format!("cannot create {}: {e}", tmp.display())));
    }
    register(&tmp);
    let written = (|| -> std::io::Result<()> {
        let mut manifest = String::from(MANIFEST_HEADER);
        manifest.push('\n');
        for (rel, content) in files {
            let p = tmp.join(rel);
            if let Some(d) = p.parent() {
                std::fs::create_dir_all(d)?;
            }
            write_file(&p, content.as_ref())?;
            manifest.push_str(&rel.to_string_lossy());
            manifest.push('\n');
        }
        write_file(&tmp.join(MANIFEST), manifest.as_bytes())
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(&tmp);
        let _ = commit_writes(std::slice::from_ref(&tmp), || Ok(()));
        return Err(match e.kind() {
            std::io::ErrorKind::Interrupted => Failure("interrupted".into()),
            _ => Failure(format!("cannot write {out}: {e}")),
        });
    }
    let replaced = existing.is_some();
    let r = commit_writes(std::slice::from_ref(&tmp), || {
        if replaced {
            std::fs::rename(target, &old)
                .map_err(|e| Failure(format!("cannot replace {out}: {e}")))?;
        }
        if let Err(e) = std::fs::rename(&tmp, target) {
            if replaced {
                let _ = std::fs::rename(&old, target);
            }
            return Err(Failure(format!("cannot write {out}: {e}")));
        }
        Ok(())
    });
    if let Err(e) = r {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    if replaced {
        remove_ours(&old);
    }
    Ok(())
}

/// Whether `--force` may replace the existing folder `target`: not the
/// working directory nor one of its parents, and holding only the files its
/// manifest lists (and the folders they sit in).
fn replaceable(out: &str, target: &Path) -> Result<(), Failure> {
    let refuse = |why: String| Failure(format!("refusing to replace {out} with --force: {why}"));
    let full = target
        .canonicalize()
        .map_err(|e| refuse(format!("cannot resolve it ({e})")))?;
    if let Ok(cwd) = std::env::current_dir().and_then(|c| c.canonicalize()) {
        if cwd.starts_with(&full) {
            return Err(refuse(
                "it is the working directory or one of its parents".into(),
            ));
        }
    }
    let listed = read_manifest(target).ok_or_else(|| {
        refuse(format!(
            "it was not written by obsan (no {MANIFEST}); move it away or choose another folder"
        ))
    })?;
    let mut dirs = BTreeSet::new();
    for f in &listed {
        let mut p = f.as_path();
        while let Some(d) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            dirs.insert(d.to_path_buf());
            p = d;
        }
    }
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let entries = std::fs::read_dir(target.join(&rel))
            .map_err(|e| refuse(format!("cannot list {}: {e}", rel.display())))?;
        for entry in entries {
            let entry = entry.map_err(|e| refuse(e.to_string()))?;
            let r = rel.join(entry.file_name());
            let kind = entry.file_type().map_err(|e| refuse(e.to_string()))?;
            let known = if kind.is_dir() {
                dirs.contains(&r)
            } else {
                kind.is_file() && (listed.contains(&r) || r.as_os_str() == MANIFEST)
            };
            if !known {
                return Err(refuse(format!(
                    "it holds {}, which obsan did not write; move it away or choose another folder",
                    Path::new(out).join(&r).display()
                )));
            }
            if kind.is_dir() {
                stack.push(r);
            }
        }
    }
    Ok(())
}

/// The files a folder's manifest lists, if it has a well-formed one.
fn read_manifest(dir: &Path) -> Option<BTreeSet<PathBuf>> {
    let text = std::fs::read_to_string(dir.join(MANIFEST)).ok()?;
    let mut lines = text.lines();
    if lines.next()? != MANIFEST_HEADER {
        return None;
    }
    let mut files = BTreeSet::new();
    for l in lines.filter(|l| !l.is_empty()) {
        let p = PathBuf::from(l);
        if !is_plain_relative(&p) {
            return None;
        }
        files.insert(p);
    }
    Some(files)
}

/// Remove a replaced folder: only the files its manifest lists, then the folders left empty; anything else
/// stays where it is.
fn remove_ours(dir: &Path) {
    let mut listed: Vec<PathBuf> = read_manifest(dir).into_iter().flatten().collect();
    listed.push(PathBuf::from(MANIFEST));
    let mut dirs = BTreeSet::new();
    for f in &listed {
        let _ = std::fs::remove_file(dir.join(f));
        let mut p = f.as_path();
        while let Some(d) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            dirs.insert(d.to_path_buf());
            p = d;
        }
    }
    // Deepest first; remove_dir fails on a folder that is not empty.
    let mut dirs: Vec<_> = dirs.into_iter().collect();
    dirs.sort_by_key(|d| std::cmp::Reverse(d.components().count()));
    for d in dirs {
        let _ = std::fs::remove_dir(dir.join(d));
    }
    let _ = std::fs::remove_dir(dir);
}

/// A relative path of plain names (no `..`, no root, not empty).
fn is_plain_relative(p: &Path) -> bool {
    p.components().count() > 0 && p.components().all(|c| matches!(c, Component::Normal(_)))
}
