//! Outputs made of several files, committed as a set: a render's image, mask, layers and
//! sidecar, or an output folder. Whatever stops a run (an error, a full disk, Ctrl-C, SIGKILL,
//! a power cut after the renames reached the disk), the user finds either the complete old set
//! or the complete new set under the final names, never a mix.
//!
//! How:
//! 1. [`OutputSet::begin`] takes the output's lock, `.NAME.lock` beside the set's last file (its
//!    commit record: the sidecar, or the folder), created whole and exclusively. The lock holds
//!    a journal: the process (id and start time, which together name a process even after its
//!    id is reused), the state (`staging` or `committing`) and, for each file, its final name,
//!    its temporary and the name its old version is moved aside to. A second run on the same
//!    output finds the lock and fails with [`Error::Locked`].
//! 2. Every file is written under its temporary ([`OutputSet::staged`]).
//! 3. [`OutputSet::commit`] marks the journal `committing`, then for each file in order keeps
//!    the old version aside (a second link to a file; a folder is swapped with the new one in
//!    one step) and moves the new one in, so that no final name is ever missing; the commit
//!    record goes last, so once it is in place the set is whole. Only then are the old versions deleted and the lock removed. A rename
//!    that fails undoes the ones before it from the journal.
//! 4. A run that finds a lock whose process is gone takes it over and finishes that run's work
//!    from its journal: a run stopped while `staging` loses its temporaries; one stopped while
//!    `committing` is completed when its commit record was in place (the old versions are
//!    deleted) and undone otherwise (the old versions come back). The same run removes the
//!    temporaries that dead runs left in the folder (names ending in `.tmp-PID-START-N`).
//!
//! Nothing here ever deletes a file that already replaced the user's: a new file is removed
//! only while its old version (if any) is still kept aside to be put back.
//!
//! ```
//! use shadelab_io::{self as io, OutputSet};
//! let dir = std::env::temp_dir().join(format!("shadelab-doc-set-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let (picture, sidecar) = (dir.join("a.txt"), dir.join("a.json"));
//! let set = OutputSet::begin(&[picture.clone(), sidecar.clone()])?;
//! io::write_text(set.staged(&picture)?, "new picture")?;
//! io::write_text(set.staged(&sidecar)?, "{}")?;
//! assert!(!picture.exists()); // nothing is visible before the commit
//! set.commit()?;
//! assert_eq!(std::fs::read_to_string(&picture)?, "new picture");
//! assert_eq!(std::fs::read_dir(&dir)?.count(), 2); // no lock, no temporary left
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::temp::{check_parent, identity, parent_of, running, temp_name, temporary_owner, Tag};
use crate::error::{Error, Result};
use std::ffi::{OsStr, OsString};
use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Removes the temporaries that runs no longer running left in `dir` (hidden names ending in
/// `.tmp-PID-START-N`, files or folders); returns what was removed. Temporaries of a running
/// run, or whose owner this system cannot check, are left alone.
pub fn remove_dead_temporaries(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    let me = identity();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let dead = temporary_owner(&name)
            .is_some_and(|owner| owner != me && running(owner.0, owner.1) == Some(false));
        if dead && remove_any(&entry.path()).is_ok() {
            removed.push(entry.path());
        }
    }
    removed
}

/// Removes a file, link or folder; a missing one is fine.
fn remove_any(path: &Path) -> std::io::Result<()> {
    let result = match fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => fs::remove_dir_all(path),
        Ok(_) => fs::remove_file(path),
        Err(e) => Err(e),
    };
    match result {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(e),
        _ => Ok(()),
    }
}

/// Whether anything (a file, folder or link, even a broken one) has this name.
fn present(path: &Path) -> bool {
    fs::symlink_metadata(path).is_ok()
}

/// One file of a set: its final name, the temporary it is written to, and where its old version
/// waits while the set is committed (all in the set's folder).
#[derive(Debug, Clone)]
struct Entry {
    target: PathBuf,
    staged: PathBuf,
    backup: PathBuf,
}

/// The lock's journal.
#[derive(Debug)]
struct Journal {
    pid: u32,
    start: u64,
    committing: bool,
    entries: Vec<Entry>,
}

const JOURNAL_HEADER: &str = "shadelab output lock";

fn hex(name: &OsStr) -> String {
    name.as_encoded_bytes()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

fn unhex(text: &str) -> Option<OsString> {
    let bytes = (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(text.get(i..i + 2)?, 16).ok())
        .collect::<Option<Vec<u8>>>()?;
    #[cfg(unix)]
    {
        use std::os::unix::ffi::OsStringExt;
        Some(OsString::from_vec(bytes))
    }
    #[cfg(not(unix))]
    {
        String::from_utf8(bytes).ok().map(OsString::from)
    }
}

impl Journal {
    fn text(&self) -> String {
        let mut text = format!(
            "{JOURNAL_HEADER}\nprocess {} {}\nstate {}\n",
            self.pid,
            self.start,
            if self.committing {
                "committing"
            } else {
                "staging"
            }
        );
        let name = |p: &Path| hex(p.file_name().unwrap_or_default());
        for e in &self.entries {
            text.push_str(&format!(
                "entry {} {} {}\n",
                name(&e.target),
                name(&e.staged),
                name(&e.backup)
            ));
        }
        text
    }

    /// The journal in `text`, with its entries in `dir`; `None` when it is not one.
    fn parse(text: &str, dir: &Path) -> Option<Journal> {
        let mut lines = text.lines();
        if lines.next()? != JOURNAL_HEADER {
            return None;
        }
        let mut process = lines.next()?.strip_prefix("process ")?.split(' ');
        let pid = process.next()?.parse().ok()?;
        let start = process.next()?.parse().ok()?;
        let committing = match lines.next()? {
            "state committing" => true,
            "state staging" => false,
            _ => return None,
        };
        let entries = lines
            .map(|line| {
                let mut names = line.strip_prefix("entry ")?.split(' ');
                let mut next = || Some(dir.join(unhex(names.next()?)?));
                Some(Entry {
                    target: next()?,
                    staged: next()?,
                    backup: next()?,
                })
            })
            .collect::<Option<Vec<_>>>()?;
        Some(Journal {
            pid,
            start,
            committing,
            entries,
        })
    }

    /// The owner recorded at the start of a lock's text, even when the rest is cut short.
    fn owner(text: &str) -> Option<(u32, u64)> {
        let line = text.lines().nth(1)?.strip_prefix("process ")?;
        let mut parts = line.split(' ');
        Some((parts.next()?.parse().ok()?, parts.next()?.parse().ok()?))
    }

    /// Finishes what a stopped run left: a run stopped before its commit loses its temporaries;
    /// a run stopped while committing is completed if its commit record (the last file) was in
    /// place, and undone otherwise. Returns whether everything was put in order.
    fn recover(&self) -> bool {
        if !self.committing {
            return self.entries.iter().all(|e| remove_any(&e.staged).is_ok());
        }
        match self.entries.last() {
            Some(record) if !present(&record.staged) => {
                // The commit record is in place: the new set is whole; drop the old versions
                // (a folder's files that the new one does not hold are moved over first).
                self.entries.iter().all(|e| {
                    rescue_into(e);
                    remove_any(&e.backup).is_ok()
                })
            }
            _ => undo(&self.entries),
        }
    }
}

/// Before an old folder is deleted: what appeared in it after its files to keep were linked
/// into the new one is moved over (see [`super::keep`]).
fn rescue_into(e: &Entry) {
    if fs::symlink_metadata(&e.backup).is_ok_and(|m| m.is_dir())
        && fs::symlink_metadata(&e.target).is_ok_and(|m| m.is_dir())
    {
        super::keep::rescue(&e.backup, &e.target);
    }
}

/// Undoes a commit that stopped part way: every file whose new version came in gets its old
/// version back (or is removed when it had none), and every temporary is removed. Returns
/// whether it all worked.
fn undo(entries: &[Entry]) -> bool {
    let mut ok = true;
    for e in entries.iter().rev() {
        let moved_in = !present(&e.staged);
        if present(&e.backup) {
            ok &= put_back(e, moved_in).is_ok();
        } else if moved_in {
            ok &= remove_any(&e.target).is_ok();
        }
        ok &= remove_any(&e.staged).is_ok();
    }
    ok
}

/// Puts the old version kept in `e.backup` back under `e.target`, replacing what is there.
fn put_back(e: &Entry, moved_in: bool) -> std::io::Result<()> {
    if moved_in && fs::symlink_metadata(&e.target).is_ok_and(|m| m.is_dir()) {
        // A folder is swapped back in one step where the system can, else removed first.
        if exchange(&e.backup, &e.target).is_err() {
            remove_any(&e.target)?;
            return fs::rename(&e.backup, &e.target);
        }
        return remove_any(&e.backup);
    }
    // A file replaces the new one in one step. When the backup is a second link to the very
    // file under the target name (stopped before the new one came in), rename does nothing
    // and the backup is simply removed.
    fs::rename(&e.backup, &e.target)?;
    remove_any(&e.backup)
}

/// Swaps two names in one step (Linux `renameat2` with `RENAME_EXCHANGE`), so that a folder is
/// replaced without a moment in which its name is missing.
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    use std::ffi::{c_char, c_int, c_uint, CString};
    use std::os::unix::ffi::OsStrExt;
    const AT_FDCWD: c_int = -100;
    const RENAME_EXCHANGE: c_uint = 2;
    extern "C" {
        fn renameat2(
            olddirfd: c_int,
            oldpath: *const c_char,
            newdirfd: c_int,
            newpath: *const c_char,
            flags: c_uint,
        ) -> c_int;
    }
    let (a, b) = (
        CString::new(a.as_os_str().as_bytes())?,
        CString::new(b.as_os_str().as_bytes())?,
    );
    // SAFETY: both arguments are NUL-terminated strings that outlive the call, which only
    // reads them; the directory descriptors are AT_FDCWD.
    let status = unsafe { renameat2(AT_FDCWD, a.as_ptr(), AT_FDCWD, b.as_ptr(), RENAME_EXCHANGE) };
    if status == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// Swapping two names in one step is not available here: the caller falls back to two renames.
#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Moves the new version of `e` in, its old version (if any) kept at `e.backup`, without a
/// moment in which `e.target` is missing: a file's old version is kept as a second link and the
/// new one renamed over it; a folder is swapped with its new version in one step. Where the
/// system can do neither, the old version is renamed aside first.
fn move_in(e: &Entry) -> std::io::Result<()> {
    let Ok(meta) = fs::symlink_metadata(&e.target) else {
        return fs::rename(&e.staged, &e.target);
    };
    if meta.is_dir() {
        if exchange(&e.staged, &e.target).is_ok() {
            // The old folder is now under the temporary name: keep it as the backup.
            return fs::rename(&e.staged, &e.backup);
        }
    } else if fs::hard_link(&e.target, &e.backup).is_ok() {
        return fs::rename(&e.staged, &e.target);
    }
    fs::rename(&e.target, &e.backup)?;
    fs::rename(&e.staged, &e.target)
}

/// A set of output files (or one folder) in one folder, written under temporary names and made
/// visible together by [`OutputSet::commit`]; dropped uncommitted, it removes its temporaries
/// and its lock and leaves the old set as it was (crates/io/src/output_set.rs says how).
#[derive(Debug)]
pub struct OutputSet {
    lock: PathBuf,
    journal: Journal,
    /// Done with: committed, or (after a failed undo) left for the next run to recover.
    done: bool,
}

impl OutputSet {
    /// Locks the output whose files are `files` (all in one folder; the last is the commit
    /// record, e.g. the sidecar) and plans their temporaries. Fails with [`Error::Locked`] when
    /// another run holds the lock; a lock left by a run that is gone is taken over and that
    /// run's leftovers are put in order first. Temporaries of dead runs in the folder are
    /// removed.
    pub fn begin(files: &[PathBuf]) -> Result<OutputSet> {
        let record = files
            .last()
            .ok_or_else(|| Error::Compute("internal: an output set of no files".into()))?;
        check_parent(record)?;
        let dir = parent_of(record).to_path_buf();
        if let Some(other) = files.iter().find(|f| parent_of(f) != dir) {
            return Err(Error::Compute(format!(
                "internal: {} is not in the folder of {}",
                other.display(),
                record.display()
            )));
        }
        let (pid, start) = identity();
        let entries = files
            .iter()
            .map(|target| {
                Ok(Entry {
                    target: target.clone(),
                    staged: temp_name(target, Tag::Temporary)?,
                    backup: temp_name(target, Tag::Backup)?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let journal = Journal {
            pid,
            start,
            committing: false,
            entries,
        };
        let lock = temp_name(record, Tag::Lock)?;
        acquire(&lock, record, &journal.text())?;
        remove_dead_temporaries(&dir);
        Ok(OutputSet {
            lock,
            journal,
            done: false,
        })
    }

    /// Where to write `target` (one of the set's files) until the commit.
    pub fn staged(&self, target: &Path) -> Result<&Path> {
        self.journal
            .entries
            .iter()
            .find(|e| e.target == target)
            .map(|e| e.staged.as_path())
            .ok_or_else(|| {
                Error::Compute(format!(
                    "internal: {} is not one of the output's files",
                    target.display()
                ))
            })
    }

    /// `error` with the final name of a file in place of its temporary's, so that a message
    /// names the file the user asked for.
    pub fn final_names(&self, error: Error) -> Error {
        let target_of = |path: &Path| {
            self.journal
                .entries
                .iter()
                .find(|e| e.staged == path)
                .map(|e| e.target.clone())
        };
        match error {
            Error::Io { path, source } => Error::Io {
                path: target_of(&path).unwrap_or(path),
                source,
            },
            Error::Format { path, message } => Error::Format {
                path: target_of(&path).unwrap_or(path),
                message,
            },
            other => other,
        }
    }

    /// The lock file (it exists while the set is being written).
    pub fn lock_path(&self) -> &Path {
        &self.lock
    }

    /// Makes the new set visible, its commit record last, replacing the old set (see
    /// crates/io/src/output_set.rs). Every file must have been written. Fails with [`Error::Cancelled`],
    /// changing nothing, when a stop was requested before the commit began; once begun, it
    /// completes (or is undone when a rename fails).
    pub fn commit(mut self) -> Result<()> {
        crate::cancel::check()?;
        if let Some(e) = self.journal.entries.iter().find(|e| !present(&e.staged)) {
            return Err(Error::Compute(format!(
                "internal: {} was not written",
                e.target.display()
            )));
        }
        self.journal.committing = true;
        rewrite(&self.lock, &self.journal.text())?;
        let mut failure = None;
        for e in &self.journal.entries {
            if let Err(err) = move_in(e) {
                failure = Some(Error::io(&e.target, err));
                break;
            }
        }
        if let Some(err) = failure {
            if !undo(&self.journal.entries) {
                // Keep the lock and its journal: the next run puts the old set back.
                self.done = true;
            }
            return Err(err);
        }
        for e in &self.journal.entries {
            rescue_into(e);
            let _ = remove_any(&e.backup);
        }
        let _ = fs::remove_file(&self.lock);
        self.done = true;
        Ok(())
    }
}

impl Drop for OutputSet {
    fn drop(&mut self) {
        if !self.done {
            for e in &self.journal.entries {
                let _ = remove_any(&e.staged);
            }
            let _ = fs::remove_file(&self.lock);
        }
    }
}

/// Creates `lock` holding `text`, whole and only if no lock is there (a temporary file linked
/// to the lock's name; exclusive creation where links are not supported). A lock of a run that
/// is gone is taken over after its journal is recovered.
fn acquire(lock: &Path, output: &Path, text: &str) -> Result<()> {
    for _ in 0..8 {
        let tmp = temp_name(lock, Tag::Temporary)?;
        fs::write(&tmp, text).map_err(|e| Error::io(&tmp, e))?;
        let linked = fs::hard_link(&tmp, lock);
        let _ = fs::remove_file(&tmp);
        match linked {
            Ok(()) => return Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
            Err(_) => match fs::OpenOptions::new()
                .write(true)
                .create_new(true)
                .open(lock)
            {
                Ok(mut file) => {
                    file.write_all(text.as_bytes())
                        .and_then(|_| file.sync_all())
                        .map_err(|e| Error::io(lock, e))?;
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(Error::io(lock, e)),
            },
        }
        // Someone holds it: a running run, or one that is gone.
        let held = match fs::read_to_string(lock) {
            Ok(held) => held,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e) => return Err(Error::io(lock, e)),
        };
        let owner = Journal::owner(&held);
        match owner.map(|(pid, start)| (pid, running(pid, start))) {
            Some((_, Some(false))) => take_over(lock, parent_of(output))?,
            Some((pid, Some(true))) => {
                return Err(Error::Locked {
                    path: output.to_path_buf(),
                    message: format!(
                        "another shadelab run (process {pid}) is writing this output; try again when it has finished"
                    ),
                })
            }
            other => {
                let who = match other {
                    Some((pid, _)) => format!("process {pid}"),
                    None => "an unknown process".into(),
                };
                return Err(Error::Locked {
                    path: output.to_path_buf(),
                    message: format!(
                        "locked by {who}, which this system cannot check; if no shadelab run is writing it, remove {}",
                        lock.display()
                    ),
                });
            }
        }
    }
    Err(Error::Locked {
        path: output.to_path_buf(),
        message: "other shadelab runs keep taking this output's lock; try again".into(),
    })
}

/// Takes over the lock of a run that is gone: moves it aside (only one taker succeeds), puts
/// that run's leftovers in order from its journal, and removes it.
fn take_over(lock: &Path, dir: &Path) -> Result<()> {
    let aside = temp_name(lock, Tag::Stale)?;
    match fs::rename(lock, &aside) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(lock, e)),
    }
    let text = fs::read_to_string(&aside).unwrap_or_default();
    let recovered = Journal::parse(&text, dir).map_or(true, |j| j.recover());
    if recovered {
        let _ = fs::remove_file(&aside);
        Ok(())
    } else {
        let _ = fs::rename(&aside, lock);
        Err(Error::format(
            lock,
            "an earlier run stopped while replacing this output and what it left cannot be put back; see the names in this file",
        ))
    }
}

/// Replaces the lock's journal (the lock is this run's).
fn rewrite(lock: &Path, text: &str) -> Result<()> {
    let tmp = temp_name(lock, Tag::Temporary)?;
    let result = fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(text.as_bytes()).and_then(|_| f.sync_all()))
        .and_then(|_| fs::rename(&tmp, lock));
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result.map_err(|e| Error::io(lock, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::atomic::tests::scratch;
    use crate::write_text;

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn contents(files: &[PathBuf]) -> Vec<Option<String>> {
        files.iter().map(|f| fs::read_to_string(f).ok()).collect()
    }

    /// Writes the set `files` with `text` + the file's index, failing at the `fail_at`th file
    /// (a full disk) when given.
    fn write_set(files: &[PathBuf], text: &str, fail_at: Option<usize>) -> Result<()> {
        let set = OutputSet::begin(files)?;
        for (i, f) in files.iter().enumerate() {
            let staged = set.staged(f)?;
            crate::write_atomic(staged, |out| {
                out.write_all(format!("{text}{i}").as_bytes())
                    .map_err(|e| Error::io(staged, e))?;
                if Some(i) == fail_at {
                    return Err(Error::io(
                        staged,
                        std::io::Error::new(std::io::ErrorKind::StorageFull, "No space left"),
                    ));
                }
                Ok(())
            })
            .map_err(|e| set.final_names(e))?;
        }
        set.commit()
    }

    fn render_set(d: &Path) -> Vec<PathBuf> {
        ["a.png", "a_mask.png", "a_depth.npy", "a.json"]
            .iter()
            .map(|n| d.join(n))
            .collect()
    }

    #[test]
    fn a_full_disk_at_any_file_leaves_the_old_set_whole() {
        let d = scratch("full");
        let files = render_set(&d);
        write_set(&files, "old", None).unwrap();
        let old = contents(&files);
        for fail_at in 0..files.len() {
            let e = write_set(&files, "new", Some(fail_at)).unwrap_err();
            assert!(e.to_string().contains("No space left"), "{e}");
            assert!(!e.to_string().contains(".tmp-"), "{e}");
            assert_eq!(contents(&files), old, "failing at file {fail_at}");
            assert_eq!(names(&d), ["a.json", "a.png", "a_depth.npy", "a_mask.png"]);
        }
        // A first set that fails leaves nothing at all.
        let e = scratch("full-first");
        let fresh = render_set(&e);
        assert!(write_set(&fresh, "new", Some(2)).is_err());
        assert!(names(&e).is_empty(), "{:?}", names(&e));
        write_set(&files, "new", None).unwrap();
        assert_eq!(contents(&files)[3].as_deref(), Some("new3"));
        assert_eq!(names(&d).len(), 4);
    }

    #[test]
    fn a_second_writer_is_refused_while_the_first_holds_the_lock() {
        let d = scratch("locked");
        let files = render_set(&d);
        let first = OutputSet::begin(&files).unwrap();
        let e = OutputSet::begin(&files).unwrap_err();
        assert!(matches!(e, Error::Locked { .. }), "{e}");
        let text = e.to_string();
        assert!(
            text.contains(&format!(
                "another shadelab run (process {})",
                std::process::id()
            )),
            "{text}"
        );
        assert!(!text.contains('\n'));
        drop(first);
        assert!(names(&d).is_empty());
        assert!(OutputSet::begin(&files).is_ok());
    }

    /// A pid that no process has (above the kernel's pid_max of 2^22).
    const GONE: u32 = 4_194_999;

    /// A run stopped by SIGKILL while committing, after `moved` of the files came in: its lock,
    /// its backups and its temporaries, as it would have left them.
    fn killed_commit(d: &Path, files: &[PathBuf], moved: usize) {
        let entries: Vec<Entry> = files
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let name = f.file_name().unwrap().to_string_lossy();
                Entry {
                    target: f.clone(),
                    staged: d.join(format!(".{name}.tmp-{GONE}-7-{i}")),
                    backup: d.join(format!(".{name}.old-{GONE}-7-{i}")),
                }
            })
            .collect();
        for (i, e) in entries.iter().enumerate() {
            fs::write(&e.staged, format!("dead{i}")).unwrap();
            if i < moved {
                move_in(e).unwrap();
            } else if i == moved {
                // Stopped between keeping the old version and moving the new one in.
                fs::hard_link(&e.target, &e.backup).unwrap();
            }
        }
        let journal = Journal {
            pid: GONE,
            start: 7,
            committing: true,
            entries,
        };
        let lock = temp_name(files.last().unwrap(), Tag::Lock).unwrap();
        fs::write(lock, journal.text()).unwrap();
        // A temporary of the dead run's that is not in the journal (a write under way).
        fs::write(d.join(format!(".a.png.tmp-{GONE}-7-99")), "x").unwrap();
    }

    #[test]
    fn the_next_run_puts_in_order_what_a_killed_commit_left() {
        if running(1, 0).is_none() {
            eprintln!("skipped: no /proc, so a dead run's lock cannot be recognised here");
            return;
        }
        for moved in 0..=4 {
            let d = scratch(&format!("killed-{moved}"));
            let files = render_set(&d);
            write_set(&files, "old", None).unwrap();
            killed_commit(&d, &files, moved);
            // While the lock is there, the set is whole as of the last commit record...
            // ...and the next run puts it in order before writing its own.
            let set = OutputSet::begin(&files).unwrap();
            let expected: Vec<Option<String>> = (0..4)
                .map(|i| {
                    Some(if moved == 4 {
                        format!("dead{i}")
                    } else {
                        format!("old{i}")
                    })
                })
                .collect();
            assert_eq!(contents(&files), expected, "{moved} moved");
            let mut left = names(&d);
            left.retain(|n| !n.ends_with(".lock"));
            assert_eq!(
                left,
                ["a.json", "a.png", "a_depth.npy", "a_mask.png"],
                "{moved}"
            );
            drop(set);
        }
    }

    #[test]
    fn folders_and_names_that_are_not_utf8_go_through_the_journal() {
        let d = scratch("journal");
        let j = Journal {
            pid: 12,
            start: 34,
            committing: true,
            entries: vec![Entry {
                target: d.join("é x"),
                staged: d.join(".é x.tmp-12-34-0"),
                backup: d.join(".é x.old-12-34-1"),
            }],
        };
        let back = Journal::parse(&j.text(), &d).unwrap();
        assert_eq!((back.pid, back.start, back.committing), (12, 34, true));
        assert_eq!(back.entries[0].target, d.join("é x"));
        assert_eq!(back.entries[0].backup, d.join(".é x.old-12-34-1"));
        assert!(Journal::parse("something else", &d).is_none());
        assert_eq!(Journal::owner(&j.text()[..40]), Some((12, 34)));
        // temporary names are recognised, others are not.
        assert_eq!(
            temporary_owner(OsStr::new(".a.png.tmp-12-34-5")),
            Some((12, 34))
        );
        for name in [
            "a.png.tmp-12-34-5",
            ".a.png.tmp-12-34",
            ".a.tmp-x-1-2",
            ".a.old-1-2-3",
        ] {
            assert_eq!(temporary_owner(OsStr::new(name)), None, "{name}");
        }
        write_text(&d.join(format!(".b.tmp-{GONE}-1-2")), "x").unwrap();
        let mine = temp_name(&d.join("c"), Tag::Temporary).unwrap();
        write_text(&mine, "x").unwrap();
        assert_eq!(
            remove_dead_temporaries(&d).len(),
            usize::from(running(1, 0).is_some())
        );
        assert!(mine.exists());
    }
}
