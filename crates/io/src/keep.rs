//! What an output folder keeps when shadelab writes it again. The folder is the user's too: a
//! run replaces only the files it writes and the files that the folder's previous shadelab run
//! wrote (listed in that run's manifest, [`MANIFEST`]); every other file, link and folder in it
//! (a participant's responses, the user's notes, an input the run read) is carried into the new
//! folder unchanged, byte for byte.
//!
//! The new folder is built beside the old one and swapped in whole (see [`super::AtomicDir`]):
//! before the swap every file to keep gets a second link inside the new folder ([`carry`] with
//! [`Carry::Link`]: the same file, not a copy, so a file someone is still appending to keeps
//! growing under its name), so at no moment is a kept file missing from its name; after the swap
//! anything that appeared in the old folder meanwhile is moved over ([`Carry::Move`]) before the
//! old folder is deleted.
//!
//! ```
//! use shadelab_io::AtomicDir;
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-keep-{}", std::process::id()));
//! # let _ = std::fs::remove_dir_all(&dir);
//! for run in 0..2 {
//!     let folder = AtomicDir::create(&dir, "report.json", false)?;
//!     std::fs::write(folder.path().join("report.json"), r#"{"program": "shadelab"}"#)?;
//!     std::fs::write(folder.path().join(format!("run-{run}.txt")), "shadelab's")?;
//!     folder.commit()?;
//!     std::fs::write(dir.join("my notes.txt"), format!("the user's, after run {run}"))?;
//! }
//! // The second run replaced the first run's files (run-0.txt is gone) and kept the user's.
//! assert!(!dir.join("run-0.txt").exists() && dir.join("run-1.txt").exists());
//! assert_eq!(std::fs::read_to_string(dir.join("my notes.txt"))?, "the user's, after run 1");
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::temp::temporary_owner;
use crate::error::{Error, Result};
use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The manifest of an output folder: the files (paths relative to the folder) that the run
/// which wrote it wrote, so that the next run knows which files are shadelab's to replace.
pub const MANIFEST: &str = ".shadelab-files.json";

/// What the manifest says of itself.
const MANIFEST_NOTE: &str = "the files this shadelab run wrote; a later run into this folder \
replaces these and keeps every other file";

/// Every file, link and empty folder under `dir`, as paths relative to it, sorted; the
/// manifest itself is left out.
pub(crate) fn files_under(dir: &Path) -> Result<BTreeSet<PathBuf>> {
    fn walk(root: &Path, rel: &Path, out: &mut BTreeSet<PathBuf>) -> Result<()> {
        let here = root.join(rel);
        let mut empty = true;
        for entry in fs::read_dir(&here).map_err(|e| Error::io(&here, e))? {
            let entry = entry.map_err(|e| Error::io(&here, e))?;
            empty = false;
            let path = rel.join(entry.file_name());
            let kind = entry.file_type().map_err(|e| Error::io(entry.path(), e))?;
            if kind.is_dir() {
                walk(root, &path, out)?;
            } else if path != Path::new(MANIFEST) {
                out.insert(path);
            }
        }
        if empty && !rel.as_os_str().is_empty() {
            out.insert(rel.to_path_buf());
        }
        Ok(())
    }
    let mut out = BTreeSet::new();
    walk(dir, Path::new(""), &mut out)?;
    Ok(out)
}

/// Whether `rel` lies under one of the `tools` entries (see [`super::AtomicDir::leaves_to`]).
pub(crate) fn under_any(rel: &Path, tools: &[String]) -> bool {
    tools.iter().any(|t| rel.starts_with(t))
}

/// Writes the manifest of `dir`: every file in it now, but those under the `tools` entries
/// (another program's, such as npm's `node_modules/`).
pub(crate) fn write_manifest(dir: &Path, tools: &[String]) -> Result<BTreeSet<PathBuf>> {
    let mut files = files_under(dir)?;
    files.retain(|f| !under_any(f, tools));
    let listed: Vec<String> = files
        .iter()
        .map(|p| p.to_string_lossy().replace('\\', "/"))
        .collect();
    let json = serde_json::json!({
        "program": "shadelab",
        "version": super::PROGRAM_VERSION,
        "note": MANIFEST_NOTE,
        "files": listed,
    });
    super::write_json(&dir.join(MANIFEST), &json)?;
    Ok(files)
}

/// The files the manifest in `dir` lists; empty when there is none, or when it is not a
/// shadelab manifest (a folder written before manifests, or by someone else): every file of
/// such a folder that the new run does not write is then kept.
pub(crate) fn read_manifest(dir: &Path) -> BTreeSet<PathBuf> {
    let Ok(bytes) = fs::read(dir.join(MANIFEST)) else {
        return BTreeSet::new();
    };
    let Ok(value) = serde_json::from_slice::<serde_json::Value>(&bytes) else {
        return BTreeSet::new();
    };
    if value.get("program").and_then(|p| p.as_str()) != Some("shadelab") {
        return BTreeSet::new();
    }
    value
        .get("files")
        .and_then(|f| f.as_array())
        .map(|files| {
            files
                .iter()
                .filter_map(|f| f.as_str())
                // Only plain relative paths: a manifest never names anything outside its folder.
                .filter(|f| {
                    Path::new(f)
                        .components()
                        .all(|c| matches!(c, std::path::Component::Normal(_)))
                })
                .map(PathBuf::from)
                .collect()
        })
        .unwrap_or_default()
}

/// How [`carry`] brings a kept entry into the new folder.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Carry {
    /// A second link to the same file (a copy where the file system has no links; a link is
    /// made again), the old one left in place.
    Link,
    /// Moved (renamed) from the old folder.
    Move,
}

/// Whether a name is one of shadelab's own passing names (a temporary, old version or lock of
/// a run writing beside it): never carried.
fn passing(name: &std::ffi::OsStr) -> bool {
    let text = name.to_string_lossy();
    temporary_owner(name).is_some() || (text.starts_with('.') && text.ends_with(".lock"))
}

/// Brings every entry of `old` that is neither in `new` nor listed in `ours` (the old run's
/// manifest) into `new` at the same relative path; returns what it brought, relative to the
/// folders. An entry that cannot be kept because the new folder has a file where the kept entry's
/// folder would go is an error naming both, and nothing of the new folder is then used.
pub(crate) fn carry(
    old: &Path,
    new: &Path,
    ours: &BTreeSet<PathBuf>,
    how: Carry,
) -> Result<Vec<PathBuf>> {
    let mut kept = Vec::new();
    for rel in files_under(old)? {
        if ours.contains(&rel) || rel.iter().any(passing) {
            continue;
        }
        let (from, to) = (old.join(&rel), new.join(&rel));
        if fs::symlink_metadata(&to).is_ok() {
            continue; // the new run writes this name: it is replaced
        }
        if let Some(parent) = to.parent() {
            fs::create_dir_all(parent).map_err(|e| {
                Error::format(
                    &from,
                    format!(
                        "cannot be kept: the new output has a file where its folder goes ({e})"
                    ),
                )
            })?;
        }
        bring(&from, &to, how).map_err(|e| Error::io(&from, e))?;
        kept.push(rel);
    }
    Ok(kept)
}

fn bring(from: &Path, to: &Path, how: Carry) -> std::io::Result<()> {
    let meta = fs::symlink_metadata(from)?;
    if how == Carry::Move {
        return fs::rename(from, to);
    }
    if meta.is_dir() {
        fs::create_dir(to)
    } else if meta.file_type().is_symlink() {
        link_again(from, to)
    } else {
        fs::hard_link(from, to).or_else(|_| fs::copy(from, to).map(|_| ()))
    }
}

#[cfg(unix)]
fn link_again(from: &Path, to: &Path) -> std::io::Result<()> {
    std::os::unix::fs::symlink(fs::read_link(from)?, to)
}

#[cfg(not(unix))]
fn link_again(from: &Path, to: &Path) -> std::io::Result<()> {
    fs::copy(from, to).map(|_| ())
}

/// Moves into `new` what changed in `old` (a folder just swapped out) after its files were
/// linked into `new`, before `old` is deleted: a file that appeared meanwhile (see [`carry`]),
/// and a kept file that was replaced meanwhile by a new file under its name (an editor saving
/// by rename), which replaces the stale link. Files the new run wrote are never touched.
pub(crate) fn rescue(old: &Path, new: &Path) {
    let ours = read_manifest(old);
    let written = read_manifest(new);
    let _ = carry(old, new, &ours, Carry::Move);
    let Ok(entries) = files_under(old) else {
        return;
    };
    for rel in entries {
        if ours.contains(&rel) || written.contains(&rel) || rel.iter().any(passing) {
            continue;
        }
        let (from, to) = (old.join(&rel), new.join(&rel));
        if !same_file(&from, &to) && fs::symlink_metadata(&from).is_ok_and(|m| m.is_file()) {
            let _ = fs::rename(&from, &to);
        }
    }
}

/// Whether two names are links to one file (false where this cannot be told).
#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (fs::symlink_metadata(a), fs::symlink_metadata(b)) {
        (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_a: &Path, _b: &Path) -> bool {
    true // without inode numbers, a kept copy is left as it was carried
}

/// Whether two paths inside one folder name the same entry, or one holds the other.
pub(crate) fn overlaps(a: &Path, b: &Path) -> bool {
    a.starts_with(b) || b.starts_with(a)
}

/// Whether `input` (a file or folder a run reads) lies inside the output folder `out` or is
/// it; the path inside (empty for `out` itself) when it does. Both are resolved (links
/// followed) where they exist.
pub(crate) fn inside(input: &Path, out: &Path) -> Option<PathBuf> {
    let input = fs::canonicalize(input).ok()?;
    let out = fs::canonicalize(out).ok()?;
    input.strip_prefix(&out).ok().map(Path::to_path_buf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atomic::tests::scratch;

    #[test]
    fn a_folder_lists_its_files_links_and_empty_folders_but_not_its_manifest() {
        let d = scratch("keep-list");
        fs::create_dir_all(d.join("a/b")).unwrap();
        fs::create_dir_all(d.join("empty")).unwrap();
        fs::write(d.join("a/b/x.txt"), "x").unwrap();
        fs::write(d.join("top.txt"), "t").unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink("top.txt", d.join("link")).unwrap();
        let written = write_manifest(&d, &[]).unwrap();
        let mut expected: BTreeSet<PathBuf> =
            ["a/b/x.txt", "empty", "top.txt"].map(PathBuf::from).into();
        #[cfg(unix)]
        expected.insert(PathBuf::from("link"));
        assert_eq!(written, expected);
        assert_eq!(read_manifest(&d), expected);
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_manifest_naming_paths_outside_its_folder_is_not_followed() {
        let d = scratch("keep-outside");
        let text = r#"{"program": "shadelab", "files": ["../escape", "/etc/passwd", "ok.txt"]}"#;
        fs::write(d.join(MANIFEST), text).unwrap();
        assert_eq!(read_manifest(&d), [PathBuf::from("ok.txt")].into());
        fs::write(
            d.join(MANIFEST),
            r#"{"program": "other", "files": ["ok.txt"]}"#,
        )
        .unwrap();
        assert!(read_manifest(&d).is_empty());
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn carrying_links_what_is_neither_new_nor_listed_and_keeps_its_bytes() {
        let d = scratch("keep-carry");
        let (old, new) = (d.join("old"), d.join("new"));
        fs::create_dir_all(old.join("images")).unwrap();
        fs::create_dir_all(new.join("images")).unwrap();
        fs::write(old.join("report.json"), "old report").unwrap();
        fs::write(old.join("images/a.png"), "old a").unwrap();
        fs::write(old.join("images/mine.png"), [0u8, 1, 2, 255]).unwrap();
        fs::write(old.join("notes.txt"), "user").unwrap();
        fs::write(old.join(".hidden"), "user").unwrap();
        fs::write(old.join(".x.png.tmp-1-2-3"), "a dead run's").unwrap();
        fs::write(new.join("report.json"), "new report").unwrap();
        let ours: BTreeSet<PathBuf> = ["report.json", "images/a.png"].map(PathBuf::from).into();
        let kept = carry(&old, &new, &ours, Carry::Link).unwrap();
        assert_eq!(
            kept,
            [".hidden", "images/mine.png", "notes.txt"].map(PathBuf::from)
        );
        assert_eq!(
            fs::read(new.join("images/mine.png")).unwrap(),
            [0, 1, 2, 255]
        );
        assert_eq!(
            fs::read_to_string(new.join("report.json")).unwrap(),
            "new report"
        );
        assert!(!new.join("images/a.png").exists());
        assert!(!new.join(".x.png.tmp-1-2-3").exists());
        // A link, not a copy: what is appended to the old name shows under the new one.
        use std::io::Write;
        let mut f = fs::OpenOptions::new()
            .append(true)
            .open(old.join("notes.txt"))
            .unwrap();
        f.write_all(b" more").unwrap();
        assert_eq!(
            fs::read_to_string(new.join("notes.txt")).unwrap(),
            "user more"
        );
        // The old folder is left as it was.
        assert_eq!(
            fs::read_to_string(old.join("images/a.png")).unwrap(),
            "old a"
        );
        fs::remove_dir_all(&d).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn rescue_brings_what_appeared_or_was_replaced_after_the_links() {
        let d = scratch("keep-rescue");
        let (old, new) = (d.join("old"), d.join("new"));
        fs::create_dir_all(&old).unwrap();
        fs::create_dir_all(&new).unwrap();
        fs::write(old.join("notes.txt"), "v1").unwrap();
        fs::write(old.join("report.json"), "old report").unwrap();
        fs::write(
            old.join(MANIFEST),
            r#"{"program": "shadelab", "files": ["report.json"]}"#,
        )
        .unwrap();
        fs::write(new.join("report.json"), "new report").unwrap();
        write_manifest(&new, &[]).unwrap();
        carry(&old, &new, &read_manifest(&old), Carry::Link).unwrap();
        // Meanwhile the user saves notes.txt by rename (a new file) and adds another.
        fs::write(old.join(".notes.swp"), "v2").unwrap();
        fs::rename(old.join(".notes.swp"), old.join("notes.txt")).unwrap();
        fs::write(old.join("late.txt"), "late").unwrap();
        rescue(&old, &new);
        assert_eq!(fs::read_to_string(new.join("notes.txt")).unwrap(), "v2");
        assert_eq!(fs::read_to_string(new.join("late.txt")).unwrap(), "late");
        assert_eq!(
            fs::read_to_string(new.join("report.json")).unwrap(),
            "new report"
        );
        fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_kept_file_whose_folder_the_new_output_fills_with_a_file_is_an_error() {
        let d = scratch("keep-clash");
        let (old, new) = (d.join("old"), d.join("new"));
        fs::create_dir_all(old.join("plots")).unwrap();
        fs::create_dir_all(&new).unwrap();
        fs::write(old.join("plots/mine.txt"), "user").unwrap();
        fs::write(new.join("plots"), "a file now").unwrap();
        let e = carry(&old, &new, &BTreeSet::new(), Carry::Link).unwrap_err();
        assert!(e.to_string().contains("mine.txt"), "{e}");
        assert!(e.to_string().contains("cannot be kept"), "{e}");
        fs::remove_dir_all(&d).unwrap();
    }
}
