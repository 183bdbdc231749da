//! Atomic output: write to a temporary name beside the target, then rename.

use super::output_set::OutputSet;
use super::temp::{check_parent, parent_of, temp_name, Tag};
use crate::error::{Error, Result};
use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The temporary folders of the [`AtomicDir`]s being written. A file written (by
/// [`write_atomic`]) straight into one of them is not synced on its own: its write-back to the
/// disk is started and the folder's commit waits for all its files together, before the
/// folder becomes visible. Either way no output appears under its final name before its data
/// is on the disk.
static STAGED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Whether `target` is a file straight inside a staged folder (see [`STAGED`]).
fn in_staged_folder(target: &Path) -> bool {
    let dir = parent_of(target);
    STAGED
        .lock()
        .map(|staged| staged.iter().any(|d| d.as_path() == dir))
        .unwrap_or(false)
}

/// Registers a staged folder for as long as it lives (see [`STAGED`]).
#[derive(Debug)]
struct Staged(PathBuf);

impl Staged {
    fn new(dir: &Path) -> Staged {
        if let Ok(mut staged) = STAGED.lock() {
            staged.push(dir.to_path_buf());
        }
        Staged(dir.to_path_buf())
    }
}

impl Drop for Staged {
    fn drop(&mut self) {
        if let Ok(mut staged) = STAGED.lock() {
            staged.retain(|d| *d != self.0);
        }
    }
}

/// Starts writing `file`'s data to the disk without waiting for it (Linux `sync_file_range`),
/// so that the wait at the commit overlaps the work done meanwhile. Only a hint: errors are
/// left to the `fsync` at the commit.
#[cfg(target_os = "linux")]
fn start_write_back(file: &fs::File) {
    use std::ffi::{c_int, c_uint};
    use std::os::unix::io::AsRawFd;
    const SYNC_FILE_RANGE_WRITE: c_uint = 2;
    extern "C" {
        fn sync_file_range(fd: c_int, offset: i64, nbytes: i64, flags: c_uint) -> c_int;
    }
    // SAFETY: the descriptor belongs to `file`, open for the whole call; offset 0 and
    // length 0 mean the whole file; the call only schedules write-back.
    let _ = unsafe { sync_file_range(file.as_raw_fd(), 0, 0, SYNC_FILE_RANGE_WRITE) };
}

/// No early write-back here: the commit's `fsync` does all of it.
#[cfg(not(target_os = "linux"))]
fn start_write_back(_file: &fs::File) {}

/// Syncs every file straight inside `dir` and then `dir` itself. Their write-back was started
/// as each was written, so this mostly waits for what is still under way; on this thread, as
/// more threads would each keep an allocator arena of their own and raise the peak memory.
fn sync_folder(dir: &Path) -> Result<()> {
    let sync = |path: &Path| -> Result<()> {
        fs::File::open(path)
            .and_then(|f| f.sync_all())
            .map_err(|e| Error::io(path, e))
    };
    for entry in fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        if entry.file_type().map_err(|e| Error::io(dir, e))?.is_file() {
            sync(&entry.path())?;
        }
    }
    sync(dir)
}

/// Writes `target` atomically: `write` fills a temporary file in the same folder, which is
/// renamed over `target` only when everything succeeded. On failure the temporary file is
/// removed and `target` is untouched. A stop requested meanwhile ([`crate::cancel`]) ends the
/// write with [`Error::Cancelled`] at the next buffer written.
pub fn write_atomic(target: &Path, write: impl FnOnce(&mut dyn Write) -> Result<()>) -> Result<()> {
    check_parent(target)?;
    if target.is_dir() {
        return Err(Error::format(
            target,
            "is a directory; expected a file name",
        ));
    }
    crate::cancel::check()?;
    let tmp = temp_name(target, Tag::Temporary)?;
    let mut result = (|| {
        let file = fs::File::create(&tmp).map_err(|e| Error::io(target, e))?;
        let mut out = BufWriter::new(StopOnCancel(file));
        write(&mut out)?;
        let StopOnCancel(file) = out
            .into_inner()
            .map_err(|e| Error::io(target, e.into_error()))?;
        if in_staged_folder(target) {
            // The folder's commit syncs it (see `STAGED`).
            start_write_back(&file);
        } else {
            file.sync_all().map_err(|e| Error::io(target, e))?;
        }
        crate::cancel::check()?;
        fs::rename(&tmp, target).map_err(|e| Error::io(target, e))
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
        if crate::cancel::requested() {
            result = Err(Error::Cancelled);
        }
    }
    result
}

/// A writer that fails once a stop is requested, so that a long write ends early.
struct StopOnCancel<W>(W);

impl<W: Write> Write for StopOnCancel<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if crate::cancel::requested() {
            return Err(std::io::Error::other("interrupted"));
        }
        self.0.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}

/// Writes `text` to `target` atomically (see [`write_atomic`]).
pub fn write_text(target: &Path, text: &str) -> Result<()> {
    if super::extension(target) == "csv" {
        super::check_csv_finite(target, text)?;
    }
    write_atomic(target, |out| {
        out.write_all(text.as_bytes())
            .map_err(|e| Error::io(target, e))
    })
}

/// Whether `marker` is a sidecar or report that shadelab wrote: a JSON object whose `program`
/// is `shadelab`, or (an `index.html`) a page that names shadelab. A user's own `photo.json`
/// beside their `photo.png` must not license replacing either.
fn written_by_shadelab(marker: &Path) -> bool {
    if !marker.is_file() {
        return false;
    }
    let Ok(bytes) = fs::read(marker) else {
        return false;
    };
    if super::extension(marker) == "json" {
        serde_json::from_slice::<serde_json::Value>(&bytes)
            .is_ok_and(|v| v.get("program").and_then(|p| p.as_str()) == Some("shadelab"))
    } else {
        bytes.windows(8).any(|w| w == b"shadelab")
    }
}

/// The last part of `path`, lossily as text (for messages).
pub fn file_name_of(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Refuses to replace an existing file that shadelab did not write: a file is shadelab's when
/// `marker` (its sidecar or report) beside it was written by shadelab. The marker itself may be
/// given as `target`: it is then replaced only when it is shadelab's own. `force` overrides.
pub fn check_overwrite(target: &Path, marker: &Path, force: bool) -> Result<()> {
    if force || !target.exists() {
        return Ok(());
    }
    if target.is_dir() {
        return Err(Error::format(
            target,
            "is a directory; expected a file name",
        ));
    }
    if written_by_shadelab(marker) {
        return Ok(());
    }
    let why = if target == marker {
        "it is not a shadelab sidecar".to_string()
    } else if marker.exists() {
        format!(
            "{} beside it is not a shadelab sidecar",
            file_name_of(marker)
        )
    } else {
        format!("no {} beside it", file_name_of(marker))
    };
    Err(Error::NotOurs {
        path: target.to_path_buf(),
        message: format!("exists and was not written by shadelab ({why})"),
    })
}

/// An output folder filled under a temporary name and moved into place by
/// [`AtomicDir::commit`], which never leaves a moment without a folder under the final name
/// (the old one is moved aside, the new one in, then the old one deleted: an
/// [`OutputSet`] of one folder). The output is locked from [`AtomicDir::create`] on, so a second
/// run writing the same folder fails with [`Error::Locked`]; dropped uncommitted, the temporary
/// folder and the lock are removed.
///
/// The folder is the user's too (see crates/io/src/keep.rs): the new folder replaces only the files
/// this run writes and those the previous run's manifest lists; every other file in the old
/// folder is carried over unchanged, with or without `force`. An input the run reads
/// ([`AtomicDir::reads`]) is never replaced.
#[derive(Debug)]
pub struct AtomicDir {
    set: OutputSet,
    temp: PathBuf,
    target: PathBuf,
    /// The path as the user gave it (a link to a folder is followed to `target`).
    shown: PathBuf,
    marker: String,
    force: bool,
    /// The run's inputs inside the output folder: as given, and their path inside it.
    inputs: Vec<(PathBuf, PathBuf)>,
    /// Files in the folder that the last run did not write are refused without `force`
    /// (kept with it): the name of what they would be, e.g. "the experiment's design".
    refuse_collected: Option<String>,
    /// Entries of the folder that another program keeps (npm's `node_modules/`): see
    /// [`AtomicDir::leaves_to`].
    tools: Vec<String>,
    /// Files written straight into `temp` are synced at the commit (see [`STAGED`]).
    staged: Staged,
}

/// The folder an output path names: itself, or where a link to a folder leads.
fn resolve_folder(target: &Path) -> Result<PathBuf> {
    let Ok(meta) = fs::symlink_metadata(target) else {
        return Ok(target.to_path_buf());
    };
    if !meta.file_type().is_symlink() {
        return Ok(target.to_path_buf());
    }
    match fs::canonicalize(target) {
        Ok(real) if real.is_dir() => Ok(real),
        Ok(real) => Err(Error::format(
            target,
            format!(
                "is a link to {}, which is not a folder, so it cannot be the output folder",
                real.display()
            ),
        )),
        Err(_) => Err(Error::format(
            target,
            format!(
                "is a link to {}, which does not exist: make that folder or give another output folder",
                fs::read_link(target).unwrap_or_default().display()
            ),
        )),
    }
}

/// A short list of paths for a message: the first few, then how many more.
fn some_names(paths: &[PathBuf]) -> String {
    let mut names: Vec<String> = paths
        .iter()
        .take(3)
        .map(|p| p.display().to_string())
        .collect();
    if paths.len() > 3 {
        names.push(format!("and {} more", paths.len() - 3));
    }
    names.join(", ")
}

impl AtomicDir {
    /// Starts an output folder for `target` (a link to a folder is followed). `marker` names
    /// the file (e.g. `report.json`) that identifies a folder shadelab wrote: an existing
    /// `target` is written into only when it is empty or holds that file, or when `force` is
    /// set (and it is then still never a file). Either way the files in it that this run does
    /// not write are kept (see crates/io/src/keep.rs).
    pub fn create(target: &Path, marker: &str, force: bool) -> Result<AtomicDir> {
        let shown = target.to_path_buf();
        let target = resolve_folder(target)?;
        check_parent(&target)?;
        let set = OutputSet::begin(std::slice::from_ref(&target))?;
        if target.exists() {
            if !target.is_dir() {
                return Err(Error::format(&shown, "exists and is not a folder"));
            }
            let empty = fs::read_dir(&target)
                .map_err(|e| Error::io(&shown, e))?
                .next()
                .is_none();
            if !empty && !force && !written_by_shadelab(&target.join(marker)) {
                let why = if target.join(marker).exists() {
                    format!("its {marker} is not shadelab's")
                } else {
                    format!("no {marker} in it")
                };
                return Err(Error::NotOurs {
                    path: shown,
                    message: format!("folder exists and was not written by shadelab ({why})"),
                });
            }
        }
        let temp = set.staged(&target)?.to_path_buf();
        fs::create_dir(&temp).map_err(|e| Error::io(&shown, e))?;
        Ok(AtomicDir {
            set,
            staged: Staged::new(&temp),
            temp,
            target,
            shown,
            marker: marker.to_string(),
            force,
            inputs: Vec::new(),
            refuse_collected: None,
            tools: Vec::new(),
        })
    }

    /// Names the files and folders this run reads, so that none is ever replaced: an input
    /// that is the output folder itself, or a file in it that the previous run wrote (which
    /// this run replaces), is refused now, before any work, naming both; any other input inside
    /// the folder is kept like every file of the user's, and the commit is refused should the
    /// run write a file under its name.
    pub fn reads<P: AsRef<Path>>(mut self, inputs: &[P]) -> Result<AtomicDir> {
        let ours = super::keep::read_manifest(&self.target);
        for input in inputs {
            let input = input.as_ref();
            let Some(rel) = super::keep::inside(input, &self.target) else {
                continue;
            };
            let replaced = rel.as_os_str().is_empty()
                || rel == Path::new(&self.marker)
                || ours.iter().any(|f| super::keep::overlaps(f, &rel));
            if replaced {
                return Err(Error::format(
                    input,
                    format!(
                        "is an input of this run and lies in its output folder {}, which the \
                         run replaces: move the input out of the folder or choose another \
                         output folder",
                        self.shown.display()
                    ),
                ));
            }
            self.inputs.push((input.to_path_buf(), rel));
        }
        Ok(self)
    }

    /// Refuses to write into a folder that holds files the previous run did not write (a
    /// participant's responses beside an experiment's design) unless `force` was given; with
    /// it they are kept as always. `what` names what this run writes, for the message.
    pub fn refusing_collected(mut self, what: &str) -> AtomicDir {
        self.refuse_collected = Some(what.to_string());
        self
    }

    /// Leaves the entries `names` of the folder (top-level names, e.g. npm's `node_modules`
    /// and `package-lock.json`) to the program that keeps them: they are never shadelab's (not
    /// in the manifest, even where an earlier version's manifest listed them), always carried
    /// over as they are, neither "collected data" nor listed among the kept files. The run may
    /// still have that program fill them once the folder is committed.
    pub fn leaves_to(mut self, names: &[&str]) -> AtomicDir {
        self.tools = names.iter().map(|n| n.to_string()).collect();
        self
    }

    /// Where to write the folder's files until it is committed.
    pub fn path(&self) -> &Path {
        &self.temp
    }

    /// The folder's final name.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Moves the finished folder into place, replacing an earlier shadelab output there and
    /// keeping every file this run did not write. Fails with [`Error::Cancelled`], writing
    /// nothing, when a stop was requested.
    pub fn commit(self) -> Result<PathBuf> {
        self.commit_keeping().map(|(path, _)| path)
    }

    /// [`AtomicDir::commit`], also returning the files of the old folder that were kept (paths
    /// inside the folder).
    pub fn commit_keeping(self) -> Result<(PathBuf, Vec<PathBuf>)> {
        if !self.temp.join(&self.marker).exists() {
            return Err(Error::Compute(format!(
                "internal: output folder lacks its {}",
                self.marker
            )));
        }
        let written = super::keep::write_manifest(&self.temp, &self.tools)?;
        if let Some((input, rel)) = self
            .inputs
            .iter()
            .find(|(_, rel)| written.iter().any(|f| super::keep::overlaps(f, rel)))
        {
            return Err(Error::format(
                input,
                format!(
                    "is an input of this run, and the run would write {} over it: move the \
                     input out of the folder or choose another output folder (nothing was written)",
                    self.shown.join(rel).display()
                ),
            ));
        }
        let mut kept = if self.target.is_dir() {
            let mut ours = super::keep::read_manifest(&self.target);
            ours.retain(|f| !super::keep::under_any(f, &self.tools));
            super::keep::carry(&self.target, &self.temp, &ours, super::keep::Carry::Link)?
        } else {
            Vec::new()
        };
        kept.retain(|f| !super::keep::under_any(f, &self.tools));
        if let Some(what) = &self.refuse_collected {
            let collected: Vec<PathBuf> = kept
                .iter()
                .filter(|p| !p.to_string_lossy().starts_with('.'))
                .cloned()
                .collect();
            if !collected.is_empty() && !self.force {
                return Err(Error::NotOurs {
                    path: self.shown.clone(),
                    message: format!(
                        "holds {} file{} that {what} did not write ({}): collected data? \
                         Nothing was written; forced, the new files go beside them",
                        collected.len(),
                        if collected.len() == 1 { "" } else { "s" },
                        some_names(&collected)
                    ),
                });
            }
        }
        sync_folder(&self.temp)?;
        drop(self.staged);
        self.set.commit()?;
        Ok((self.shown, kept))
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::temp::{temp_name, Tag};
    use std::sync::atomic::Ordering;

    /// A fresh scratch folder for one test of `io`.
    pub(crate) fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("shadelab-atomic-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn any_legal_final_name_has_a_legal_temporary_name() {
        let d = scratch("long-names");
        // 255 bytes is the usual limit of one name; the temporary's prefix and suffix must
        // not push it over (names of 240–248 bytes failed before).
        for len in [1, 100, 101, 240, 248, 251] {
            let name = format!("{}.png", "a".repeat(len));
            let target = d.join(&name);
            write_text(&target, "x").unwrap();
            assert_eq!(fs::read_to_string(&target).unwrap(), "x", "{len}");
            let temp = temp_name(&target, Tag::Temporary).unwrap();
            let temp_len = temp.file_name().unwrap().len();
            assert!(temp_len <= 160, "{len}: {temp_len}");
        }
        // Two long names that share their first 100 bytes get different temporaries.
        let (a, b) = (
            d.join(format!("{}a.png", "x".repeat(150))),
            d.join(format!("{}b.png", "x".repeat(150))),
        );
        let stem = |p: &Path| {
            let n = temp_name(p, Tag::Temporary)
                .unwrap()
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned();
            n[..n.find(".tmp-").unwrap()].to_string()
        };
        assert_ne!(stem(&a), stem(&b));
        // A multi-byte name is cut at a character boundary.
        let wide = d.join("é".repeat(120));
        assert!(temp_name(&wide, Tag::Temporary).is_ok());
        let _ = fs::remove_dir_all(&d);
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let d = scratch("fail");
        let target = d.join("out.bin");
        let r = write_atomic(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(Error::invalid("boom"))
        });
        assert!(r.is_err());
        assert_eq!(fs::read_dir(&d).unwrap().count(), 0);
        write_atomic(&target, |w| {
            w.write_all(b"ok").map_err(|e| Error::io(&target, e))
        })
        .unwrap();
        assert_eq!(fs::read(&target).unwrap(), b"ok");
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
    }

    const OURS: &str = r#"{"program": "shadelab"}"#;

    #[test]
    fn dir_is_removed_unless_committed_and_foreign_dirs_are_kept() {
        let d = scratch("dir");
        let target = d.join("result");
        {
            let a = AtomicDir::create(&target, "report.json", false).unwrap();
            fs::write(a.path().join("x"), "1").unwrap();
        }
        assert_eq!(fs::read_dir(&d).unwrap().count(), 0);
        let a = AtomicDir::create(&target, "report.json", false).unwrap();
        fs::write(a.path().join("report.json"), OURS).unwrap();
        a.commit().unwrap();
        assert!(target.join("report.json").exists());
        // Replacing our own output is fine; a folder of someone else's is refused.
        let a = AtomicDir::create(&target, "report.json", false).unwrap();
        fs::write(a.path().join("report.json"), OURS).unwrap();
        a.commit().unwrap();
        let foreign = d.join("photos");
        fs::create_dir(&foreign).unwrap();
        fs::write(foreign.join("holiday.jpg"), "x").unwrap();
        assert!(AtomicDir::create(&foreign, "report.json", false).is_err());
        assert!(foreign.join("holiday.jpg").exists());
        // A report.json of someone else's does not make the folder shadelab's.
        fs::write(foreign.join("report.json"), r#"{"program": "darktable"}"#).unwrap();
        let e = AtomicDir::create(&foreign, "report.json", false).unwrap_err();
        assert!(e.to_string().contains("not shadelab's"), "{e}");
        // A path under a regular file is named as such.
        let e = AtomicDir::create(&foreign.join("holiday.jpg/out"), "report.json", false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("holiday.jpg: is not a folder"), "{e}");
    }

    #[test]
    fn a_folder_is_never_missing_while_it_is_replaced() {
        let d = scratch("no-gap");
        let target = d.join("result");
        let commit = |n: usize| {
            let a = AtomicDir::create(&target, "report.json", false).unwrap();
            fs::write(a.path().join("report.json"), OURS).unwrap();
            fs::write(a.path().join("n"), n.to_string()).unwrap();
            a.commit().unwrap();
        };
        commit(0);
        // A reader polls the final name while the folder is replaced 200 times: it must always
        // find a whole folder (the old one or the new one).
        let done = std::sync::atomic::AtomicBool::new(false);
        let (looks, misses) = std::thread::scope(|s| {
            let reader = s.spawn(|| {
                let (mut looks, mut misses) = (0u64, 0u64);
                while !done.load(Ordering::Relaxed) {
                    looks += 1;
                    if !target.join("report.json").exists() {
                        misses += 1;
                    }
                }
                (looks, misses)
            });
            for n in 1..=200 {
                commit(n);
            }
            done.store(true, Ordering::Relaxed);
            reader.join().unwrap()
        });
        assert!(looks > 200, "{looks}");
        assert_eq!(misses, 0, "{misses} of {looks} looks found no folder");
        assert_eq!(fs::read_to_string(target.join("n")).unwrap(), "200");
        // Only the folder is left: no lock, no backup, no temporary.
        assert_eq!(fs::read_dir(&d).unwrap().count(), 1);
    }

    #[test]
    fn a_folder_being_written_is_locked() {
        let d = scratch("dir-lock");
        let target = d.join("result");
        let first = AtomicDir::create(&target, "report.json", false).unwrap();
        let e = AtomicDir::create(&target, "report.json", false).unwrap_err();
        assert!(matches!(e, Error::Locked { .. }), "{e}");
        fs::write(first.path().join("report.json"), OURS).unwrap();
        first.commit().unwrap();
        assert!(target.join("report.json").exists());
    }

    #[test]
    fn overwrite_needs_a_marker_or_force() {
        let d = scratch("overwrite");
        let target = d.join("img.png");
        fs::write(&target, "not ours").unwrap();
        let marker = d.join("img.json");
        assert!(check_overwrite(&target, &marker, false).is_err());
        assert!(check_overwrite(&target, &marker, true).is_ok());
        // A JSON file of the user's beside it is not a sidecar, and is itself protected.
        fs::write(&marker, "{}").unwrap();
        assert!(check_overwrite(&target, &marker, false).is_err());
        assert!(check_overwrite(&marker, &marker, false).is_err());
        fs::write(&marker, OURS).unwrap();
        assert!(check_overwrite(&target, &marker, false).is_ok());
        assert!(check_overwrite(&marker, &marker, false).is_ok());
    }
}
