//! The names shadelab writes beside an output while it is being written (temporaries, old
//! versions kept aside, locks) and the process that owns them: one home for what the atomic
//! writes ([`super::atomic`]) and the output sets ([`super::output_set`]) share.

use crate::error::{Error, Result};
use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// This process: its id and its start time (clock ticks after boot, field 22 of
/// `/proc/self/stat`; 0 where there is no `/proc`). The pair names this run in temporary names
/// and locks, so that a later run can tell whether their owner is still running.
pub(crate) fn identity() -> (u32, u64) {
    static ID: OnceLock<(u32, u64)> = OnceLock::new();
    *ID.get_or_init(|| {
        let pid = std::process::id();
        (pid, proc_stat(pid).map_or(0, |(_, start)| start))
    })
}

/// A process's state letter and start time from `/proc/PID/stat`.
fn proc_stat(pid: u32) -> Option<(String, u64)> {
    let stat = fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: count from after it.
    let rest = stat.get(stat.rfind(')')? + 1..)?;
    let mut fields = rest.split_whitespace();
    let state = fields.next()?.to_string();
    let start = fields.nth(18)?.parse().ok()?;
    Some((state, start))
}

/// Whether the process `pid` that started at `start` still runs: `Some(false)` when it is gone,
/// a zombie, or its id now names another process; `None` when this system cannot tell (no
/// `/proc`).
pub(crate) fn running(pid: u32, start: u64) -> Option<bool> {
    proc_stat(std::process::id())?;
    match proc_stat(pid) {
        None => Some(false),
        Some((state, s)) => Some(s == start && state != "Z"),
    }
}

/// The owner (pid, start) that a temporary's name `….tmp-PID-START-N` records, if it is one.
pub(crate) fn temporary_owner(name: &OsStr) -> Option<(u32, u64)> {
    let name = name.to_str()?;
    if !name.starts_with('.') {
        return None;
    }
    let tag = Tag::Temporary.text();
    let at = name.rfind(tag)?;
    let mut parts = name[at + tag.len()..].split('-');
    let pid = parts.next()?.parse().ok()?;
    let start = parts.next()?.parse().ok()?;
    parts.next()?.parse::<u64>().ok()?;
    parts.next().is_none().then_some((pid, start))
}

/// The longest file name part kept as written in a temporary's name; a longer name is cut and
/// followed by a hash of the whole, so that any legal final name (up to 255 bytes) has a
/// temporary name that is legal too.
const TEMP_STEM_BYTES: usize = 100;

/// What a name made beside an output is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Tag {
    /// A file or folder being written: `.NAME.tmp-PID-START-N`.
    Temporary,
    /// An old version moved aside during a commit: `.NAME.old-PID-START-N`.
    Backup,
    /// The lock of an output: `.NAME.lock`.
    Lock,
    /// The lock of a run that is gone, moved aside to be recovered: `.NAME.stale-PID-START-N`.
    Stale,
}

impl Tag {
    /// The text before the owner in the name.
    pub(crate) fn text(self) -> &'static str {
        match self {
            Tag::Temporary => ".tmp-",
            Tag::Backup => ".old-",
            Tag::Lock => ".lock",
            Tag::Stale => ".stale-",
        }
    }
}

/// A hidden name beside `target` for `tag`: `.NAME.tmp-PID-START-N` (and the like, see
/// [`Tag`]), with NAME cut to [`TEMP_STEM_BYTES`] (at a character boundary) plus 12 hex digits
/// of the whole name's MD5 when longer. PID and START (the process's start time) name the run,
/// so that a later run can tell a temporary of a run that is gone (see
/// [`super::output_set::remove_dead_temporaries`]).
pub(crate) fn temp_name(target: &Path, tag: Tag) -> Result<PathBuf> {
    let name = target
        .file_name()
        .ok_or_else(|| Error::invalid(format!("{}: not a file name", target.display())))?
        .to_string_lossy();
    let stem = if name.len() <= TEMP_STEM_BYTES {
        name.to_string()
    } else {
        let mut cut = TEMP_STEM_BYTES;
        while !name.is_char_boundary(cut) {
            cut -= 1;
        }
        use md5::{Digest, Md5};
        let hash: String = Md5::digest(name.as_bytes())
            .iter()
            .take(6)
            .map(|b| format!("{b:02x}"))
            .collect();
        format!("{}~{hash}", &name[..cut])
    };
    let name = if tag == Tag::Lock {
        format!(".{stem}{}", tag.text())
    } else {
        let (pid, start) = identity();
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        format!(".{stem}{}{pid}-{start}-{n}", tag.text())
    };
    Ok(target.with_file_name(name))
}

pub(crate) fn parent_of(target: &Path) -> &Path {
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The folder that will hold `target` must exist and be a folder; a path under a regular file
/// gets its own message rather than "does not exist".
pub(crate) fn check_parent(target: &Path) -> Result<()> {
    let parent = parent_of(target);
    if parent.is_dir() {
        Ok(())
    } else if parent.exists() {
        Err(Error::format(
            parent,
            "is not a folder, so it cannot hold the output",
        ))
    } else {
        Err(Error::format(parent, "output folder does not exist"))
    }
}
