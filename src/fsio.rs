//! Writing output folders: atomically, and never over what obsan did not write.
//!
//! Every folder obsan writes (a dataset, a report, figures) holds a manifest,
//! [`MANIFEST`], listing the files it wrote. `--force` replaces a folder only
//! when everything in it is listed there: a folder holding anything else
//! (the user's files, a symlink), the working directory or one of its
//! parents is refused, so `--force` cannot delete what obsan did not write.

use crate::Failure;
use std::collections::BTreeSet;
use std::path::{Component, Path, PathBuf};

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

/// Write all files into a temporary sibling folder, then rename it into
/// place: a failure leaves nothing behind. Missing parent folders are
/// created (as `mkdir -p` does).
pub fn write_folder_atomically(
    out: &str,
    force: bool,
    files: &[(PathBuf, impl AsRef<[u8]>)],
) -> Result<(), Failure> {
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
    let pid = std::process::id();
    let tmp = parent.join(format!(".{name}.obsan-tmp-{pid}"));
    let old = parent.join(format!(".{name}.obsan-old-{pid}"));
    // create_dir fails if the name is taken, so what is removed below on
    // failure is only ever the folder made here.
    if let Err(e) = std::fs::create_dir(&tmp) {
        return Err(Failure(format!("cannot create {}: {e}", tmp.display())));
    }
    let written = (|| -> std::io::Result<()> {
        let mut manifest = String::from(MANIFEST_HEADER);
        manifest.push('\n');
        for (rel, content) in files {
            let p = tmp.join(rel);
            if let Some(d) = p.parent() {
                std::fs::create_dir_all(d)?;
            }
            std::fs::write(p, content.as_ref())?;
            manifest.push_str(&rel.to_string_lossy());
            manifest.push('\n');
        }
        std::fs::write(tmp.join(MANIFEST), manifest)
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(Failure(format!("cannot write {out}: {e}")));
    }
    if existing.is_some() {
        if let Err(e) = std::fs::rename(target, &old) {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(Failure(format!("cannot replace {out}: {e}")));
        }
    }
    if let Err(e) = std::fs::rename(&tmp, target) {
        if existing.is_some() {
            let _ = std::fs::rename(&old, target);
        }
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(Failure(format!("cannot write {out}: {e}")));
    }
    if existing.is_some() {
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
