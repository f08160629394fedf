//! The store's writer lock: one process at a time may write a store.
//!
//! [`StoreLock::acquire`] takes an exclusive advisory lock (`flock`, the standard library's
//! `File::try_lock`) on `STORE/.lock` and writes the holder's pid and command into it; a
//! second writer is refused at once with a message naming the holder. The operating
//! system releases the lock when the process ends, however it ends (a `kill -9` leaves no
//! stale lock; the file itself stays); a normal release unlocks explicitly on drop.
//! Re-entrant within one process (a repair that re-runs the build holds it once). Readers
//! do not lock: every file is replaced atomically and the manifest is written last.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::error::{Error, Result};

/// Directories this process holds the lock of, with their nesting depth.
static HELD: Mutex<Vec<(PathBuf, usize)>> = Mutex::new(Vec::new());

/// Held while this process writes the store; released on drop.
#[derive(Debug)]
pub struct StoreLock {
    dir: PathBuf,
    /// The locked file (only the outermost acquisition holds it).
    _file: Option<std::fs::File>,
}

impl StoreLock {
    /// Locks the store directory `dir` (which must exist) for writing by `command`, or
    /// fails naming the process that holds it.
    pub fn acquire(dir: &Path, command: &str) -> Result<StoreLock> {
        if !dir.is_dir() {
            return Err(Error::store(
                dir,
                "not a directory (expected a cliffmap store made by `cliffmap build`)",
            ));
        }
        let key = dir.canonicalize().map_err(|e| Error::io(dir, e))?;
        let mut held = HELD.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(h) = held.iter_mut().find(|h| h.0 == key) {
            h.1 += 1;
            return Ok(StoreLock {
                dir: key,
                _file: None,
            });
        }
        let path = key.join(".lock");
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&path)
            .map_err(|e| Error::io(&path, e))?;
        match file.try_lock() {
            Ok(()) => {}
            Err(std::fs::TryLockError::WouldBlock) => {
                let holder = std::fs::read_to_string(&path).unwrap_or_default();
                let holder = holder.trim();
                return Err(Error::StoreLocked {
                    path: dir.to_path_buf(),
                    holder: if holder.is_empty() {
                        "holder unknown".to_string()
                    } else {
                        holder.to_string()
                    },
                    command: command.to_string(),
                });
            }
            Err(std::fs::TryLockError::Error(e)) => return Err(Error::io(&path, e)),
        }
        let _ = file.set_len(0);
        let _ = write!(file, "pid {} running `{command}`", std::process::id());
        held.push((key.clone(), 1));
        Ok(StoreLock {
            dir: key,
            _file: Some(file),
        })
    }
}

impl Drop for StoreLock {
    fn drop(&mut self) {
        let mut held = HELD.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(i) = held.iter().position(|h| h.0 == self.dir) {
            held[i].1 -= 1;
            if held[i].1 == 0 {
                held.remove(i);
            }
        }
        // Unlock explicitly rather than on close: `flock` belongs to the open file
        // description, which a child process forked by another thread shares until it
        // execs; closing only our descriptor would leave the lock held for that moment and
        // refuse this process's next writer (seen in CI while a test spawned `python3`).
        if let Some(file) = &self._file {
            let _ = file.unlock();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_holder_is_refused_and_nesting_is_allowed() {
        let tmp = tempfile::tempdir().unwrap();
        let a = StoreLock::acquire(tmp.path(), "cliffmap build").unwrap();
        let b = StoreLock::acquire(tmp.path(), "cliffmap reparam").unwrap(); // same process: nested
        drop(b);
        // A different open file description (as another process would have) is refused.
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(tmp.path().join(".lock"))
            .unwrap();
        assert!(matches!(
            f.try_lock(),
            Err(std::fs::TryLockError::WouldBlock)
        ));
        drop(a);
        assert!(f.try_lock().is_ok());
        let text = std::fs::read_to_string(tmp.path().join(".lock")).unwrap();
        assert!(text.contains("cliffmap build"), "{text}");
        // Held through another file description, the store is refused with a typed error.
        let e = StoreLock::acquire(tmp.path(), "cliffmap project").unwrap_err();
        match &e {
            Error::StoreLocked {
                holder, command, ..
            } => {
                assert!(holder.contains("cliffmap build"), "{holder}");
                assert_eq!(command, "cliffmap project");
            }
            other => panic!("expected StoreLocked, got {other:?}"),
        }
        assert!(
            e.to_string()
                .contains("another cliffmap process is writing this store"),
            "{e}"
        );
    }
}
