//! Atomic file saves, and the removal of what interrupted ones leave behind: one piece of
//! code for the layout library (`haunts-affordance`) and the CLI's day artifacts.
//!
//! [`save`] writes `bytes` to a temporary file `.<name>.tmp-<pid>-<n>` beside the target
//! (`<pid>` the saving process, `<n>` a counter within it), fsyncs it, renames it over the
//! target and fsyncs the directory (on Unix). A crash at any point leaves either the previous
//! file or the new one, never a mixture, plus perhaps the temporary file.
//!
//! **Stale temporaries.** Before writing, [`save`] removes the temporaries of the *same
//! target* that no save in progress can own ([`remove_stale_temporaries`], which loaders call
//! too): a temporary is stale when its process is not running (on Linux, no
//! `/proc/<pid>`; elsewhere, where that cannot be asked, this test is skipped), or when it was
//! last written more than a day ago, whatever its process (a process id reused by
//! an unrelated program does not keep an orphan forever). The saving process's own
//! temporaries are left alone (another thread may be writing one). Files of other names are
//! never touched.
//!
//! **Writers one at a time.** An atomic save keeps a file whole, not a read-modify-write
//! whole: two processes that each load a library, add a day and save it lose one of the days.
//! [`lock`] takes an advisory exclusive lock on a sidecar `.<name>.lock` beside the target
//! (the target itself is replaced by every save, so a lock on it would lock a file that is
//! about to be unlinked); hold the [`Lock`] from before the load until after the save. The
//! sidecar is created on first use and never removed (removing it would let a third writer
//! lock a new file while a second still holds the old one). The lock is the operating
//! system's (`flock` on Unix, `LockFileEx` on Windows, through the `fs4` crate), so it
//! is released when the process ends, however it ends: a `kill -9` leaves no stale lock.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

/// A temporary file older than this is stale even if its process id is running: one day.
const STALE_AFTER: Duration = Duration::from_secs(24 * 3600);

/// Saves `bytes` to `path` atomically (see the [module docs](self)), after removing the stale
/// temporaries of `path`. `error` builds the caller's error from the path concerned, the step
/// that failed and the I/O error.
///
/// # Errors
/// `error(path, step, source)` for the first step that fails; the previous file is then
/// untouched and this save's temporary file removed.
///
/// ```
/// use haunts_occupancy::atomic;
/// let dir = std::env::temp_dir().join(format!("haunts-atomic-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let target = dir.join("library.bin");
/// // What a save killed before its rename leaves, from a process that no longer runs.
/// let orphan = dir.join(".library.bin.tmp-4000000000-0");
/// std::fs::write(&orphan, b"half").unwrap();
/// atomic::save(&target, b"whole", |p, step, e| format!("{}: {step}: {e}", p.display())).unwrap();
/// assert_eq!(std::fs::read(&target).unwrap(), b"whole");
/// assert!(!orphan.exists());
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn save<E>(
    path: &Path,
    bytes: &[u8],
    error: impl Fn(&Path, &'static str, std::io::Error) -> E,
) -> Result<(), E> {
    remove_stale_temporaries(path);
    let tmp = write_temporary(path, bytes, &error)?;
    if let Err(source) = fs::rename(&tmp, path) {
        let _ = fs::remove_file(&tmp);
        return Err(error(path, "rename the temporary file over it", source));
    }
    #[cfg(unix)]
    {
        let dir = directory_of(path);
        fs::File::open(dir)
            .and_then(|d| d.sync_all())
            .map_err(|e| error(dir, "fsync the directory", e))?;
    }
    Ok(())
}

/// An exclusive advisory lock on a file's sidecar (see the [module docs](self)); released when
/// dropped or when the process ends.
#[derive(Debug)]
pub struct Lock {
    /// The locked sidecar (the lock lives as long as this handle).
    _file: fs::File,
    path: PathBuf,
}

impl Lock {
    /// The sidecar file that is locked.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The error for a path without a file name (a root, `..`), through the caller's `error`.
fn no_file_name<E>(path: &Path, error: impl Fn(&Path, &'static str, std::io::Error) -> E) -> E {
    error(
        path,
        "take the file name",
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the path has no file name",
        ),
    )
}

/// The sidecar whose lock stands for `path`'s: `.<name>.lock` beside it, or `None` when
/// `path` has no file name.
pub fn lock_path(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?;
    Some(directory_of(path).join(format!(".{}.lock", name.to_string_lossy())))
}

/// Takes the exclusive lock standing for `path` (its sidecar [`lock_path`]), waiting up to
/// `wait` for another holder to release it (polled every 50 ms; `Duration::ZERO` tries once).
///
/// # Errors
/// `error(sidecar, step, source)`: the sidecar cannot be created or locked, or (with
/// `std::io::ErrorKind::TimedOut`) another process still holds it after `wait`.
///
/// ```
/// use std::time::Duration;
/// use haunts_occupancy::atomic;
/// let dir = std::env::temp_dir().join(format!("haunts-lock-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let target = dir.join("library.bin");
/// let error = |p: &std::path::Path, step: &str, e: std::io::Error| format!("{}: {step}: {e}", p.display());
/// let held = atomic::lock(&target, Duration::ZERO, error).unwrap();
/// // A second writer (here the same process, through another handle) waits, then gives up.
/// let refused = atomic::lock(&target, Duration::from_millis(120), error).unwrap_err();
/// assert!(refused.contains("still held"), "{refused}");
/// drop(held);
/// assert!(atomic::lock(&target, Duration::ZERO, error).is_ok());
/// # std::fs::remove_dir_all(&dir).unwrap();
/// ```
pub fn lock<E>(
    path: &Path,
    wait: Duration,
    error: impl Fn(&Path, &'static str, std::io::Error) -> E,
) -> Result<Lock, E> {
    let Some(sidecar) = lock_path(path) else {
        return Err(no_file_name(path, error));
    };
    let file = fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&sidecar)
        .map_err(|e| error(&sidecar, "open the lock file", e))?;
    let start = std::time::Instant::now();
    loop {
        // The trait's method by name: `File::try_lock` of the standard library (Rust 1.89)
        // would shadow it.
        match fs4::FileExt::try_lock(&file) {
            Ok(()) => {
                return Ok(Lock {
                    _file: file,
                    path: sidecar,
                });
            }
            Err(fs4::TryLockError::WouldBlock) => {}
            Err(fs4::TryLockError::Error(e)) => return Err(error(&sidecar, "lock", e)),
        }
        let waited = start.elapsed();
        if waited >= wait {
            return Err(error(
                &sidecar,
                "lock",
                std::io::Error::new(
                    std::io::ErrorKind::TimedOut,
                    format!(
                        "still held by another writer after {:.1} s",
                        waited.as_secs_f64()
                    ),
                ),
            ));
        }
        std::thread::sleep(Duration::from_millis(50).min(wait - waited));
    }
}

/// Writes `bytes` to a new temporary file beside `path` and fsyncs it; returns its path. The
/// first half of [`save`]: a crash after it leaves the temporary file and the untouched
/// target.
///
/// # Errors
/// `error(path, step, source)` naming the temporary file (or `path` when it has no file
/// name); the temporary file is then removed.
pub fn write_temporary<E>(
    path: &Path,
    bytes: &[u8],
    error: impl Fn(&Path, &'static str, std::io::Error) -> E,
) -> Result<PathBuf, E> {
    static SAVES: AtomicU64 = AtomicU64::new(0);
    let Some(name) = path.file_name() else {
        return Err(no_file_name(path, error));
    };
    let n = SAVES.fetch_add(1, Ordering::Relaxed);
    let tmp = directory_of(path).join(format!(
        "{}{}-{n}",
        prefix(&name.to_string_lossy()),
        std::process::id()
    ));
    let written = (|| {
        let mut file = fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| ("create the temporary file", e))?;
        file.write_all(bytes)
            .map_err(|e| ("write the temporary file", e))?;
        file.sync_all().map_err(|e| ("fsync the temporary file", e))
    })();
    match written {
        Ok(()) => Ok(tmp),
        Err((operation, source)) => {
            let _ = fs::remove_file(&tmp);
            Err(error(&tmp, operation, source))
        }
    }
}

/// Removes the stale temporary files of `path` (the rule is in the [module docs](self)) and
/// returns those removed. Best effort: a directory that cannot be listed or a file that
/// cannot be removed is left as it is (the save or load that follows reports its own
/// errors).
pub fn remove_stale_temporaries(path: &Path) -> Vec<PathBuf> {
    let Some(name) = path.file_name() else {
        return Vec::new();
    };
    let prefix = prefix(&name.to_string_lossy());
    let Ok(entries) = fs::read_dir(directory_of(path)) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|n| n.strip_prefix(&prefix))
            .and_then(temporary_pid)
        else {
            continue;
        };
        let old = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age > STALE_AFTER);
        let own = pid == std::process::id();
        if (old || (!own && !running(pid))) && fs::remove_file(entry.path()).is_ok() {
            removed.push(entry.path());
        }
    }
    removed
}

/// `.<name>.tmp-`: what every temporary file of the target `name` starts with.
fn prefix(name: &str) -> String {
    format!(".{name}.tmp-")
}

/// The process id of a temporary file's name after its prefix: `<pid>-<n>`, both decimal.
fn temporary_pid(rest: &str) -> Option<u32> {
    let (pid, n) = rest.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (digits(pid) && digits(n)).then(|| pid.parse().ok())?
}

/// Whether process `pid` may be running: on Linux, whether `/proc/<pid>` exists; where
/// `/proc` is absent, always (only the age rule applies there).
fn running(pid: u32) -> bool {
    let proc = Path::new("/proc");
    !proc.join("self").exists() || proc.join(pid.to_string()).exists()
}

fn directory_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    #[test]
    fn only_temporaries_of_the_target_from_dead_processes_are_removed() {
        let dir = std::env::temp_dir().join(format!("haunts-atomic-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let target = dir.join("lib.bin");
        let own = std::process::id();
        // Process 1 (init) always runs; 4 000 000 000 is above any Linux pid_max.
        let names = [
            format!(".lib.bin.tmp-{own}-7"),
            ".lib.bin.tmp-1-0".to_owned(),
            ".lib.bin.tmp-4000000000-3".to_owned(),
            ".other.bin.tmp-4000000000-3".to_owned(),
            ".lib.bin.tmp-4000000000-x".to_owned(),
            "lib.bin".to_owned(),
        ];
        for n in &names {
            fs::write(dir.join(n), b"x").unwrap();
        }
        let removed = remove_stale_temporaries(&target);
        let linux = Path::new("/proc/self").exists();
        let expected: Vec<PathBuf> = if linux {
            vec![dir.join(&names[2])]
        } else {
            Vec::new()
        };
        assert_eq!(removed, expected);
        for n in &names {
            assert_eq!(
                dir.join(n).exists(),
                !expected.contains(&dir.join(n)),
                "{n}"
            );
        }
        assert_eq!(temporary_pid("12-0"), Some(12));
        assert_eq!(temporary_pid("12-"), None);
        assert_eq!(temporary_pid("99999999999-0"), None);
        fs::remove_dir_all(&dir).unwrap();
    }
}
