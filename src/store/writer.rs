//! Store files written atomically on a thread of their own ([`BackgroundWriter`]).

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;

use super::files::file_ref;
use super::manifest::FileRef;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

/// Writes store files atomically (temporary file, `fsync`, rename: as [`super::write_file`])
/// on a thread of its own, so the threads that compute the files do not wait for the disk.
/// [`BackgroundWriter::submit`] returns a file's [`FileRef`] at once;
/// [`BackgroundWriter::finish`] waits until every submitted file is written and reports the
/// first failure. Dropping the writer without `finish` also waits for the writes.
pub struct BackgroundWriter {
    dir: PathBuf,
    tx: Option<mpsc::Sender<(PathBuf, Vec<u8>)>>,
    thread: Option<JoinHandle<Result<()>>>,
}

impl BackgroundWriter {
    /// A writer for files of the store at `dir`.
    pub fn new(dir: &Path) -> BackgroundWriter {
        let (tx, rx) = mpsc::channel::<(PathBuf, Vec<u8>)>();
        let thread = std::thread::spawn(move || {
            let mut first = Ok(());
            for (path, bytes) in rx {
                // after a failure the remaining files are not written
                if first.is_ok() {
                    first = write_atomic(&path, &bytes);
                }
            }
            first
        });
        BackgroundWriter {
            dir: dir.to_path_buf(),
            tx: Some(tx),
            thread: Some(thread),
        }
    }

    /// Queues `bytes` for `dir/rel` and returns the file's record (size and checksum of
    /// `bytes`).
    pub fn submit(&self, rel: &str, bytes: Vec<u8>) -> Result<FileRef> {
        let file = file_ref(rel, &bytes);
        let path = self.dir.join(rel);
        let sent = self.tx.as_ref().map(|tx| tx.send((path.clone(), bytes)));
        match sent {
            Some(Ok(())) => Ok(file),
            _ => Err(Error::store(
                path,
                "the file writer stopped before this file",
            )),
        }
    }

    /// Waits until every submitted file is written; the first write error, if any.
    pub fn finish(mut self) -> Result<()> {
        self.wait()
    }

    fn wait(&mut self) -> Result<()> {
        self.tx = None;
        match self.thread.take().map(JoinHandle::join) {
            None => Ok(()),
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(Error::store(&self.dir, "the file writer thread panicked")),
        }
    }
}

impl Drop for BackgroundWriter {
    fn drop(&mut self) {
        let _ = self.wait();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::crc32_hex;

    #[test]
    fn writes_every_file_and_reports_failures() {
        let dir = tempfile::tempdir().unwrap();
        let w = BackgroundWriter::new(dir.path());
        let refs: Vec<FileRef> = (0..20)
            .map(|i| {
                w.submit(&format!("cells/{i}.bin"), vec![i as u8; 100 + i])
                    .unwrap()
            })
            .collect();
        w.finish().unwrap();
        for (i, r) in refs.iter().enumerate() {
            let bytes = std::fs::read(dir.path().join(&r.path)).unwrap();
            assert_eq!(
                (bytes.len() as u64, crc32_hex(&bytes)),
                (r.bytes, r.crc32.clone()),
                "file {i}"
            );
        }
        // a path under a regular file cannot be created: finish reports it
        std::fs::write(dir.path().join("plain"), b"x").unwrap();
        let w = BackgroundWriter::new(dir.path());
        w.submit("plain/sub.bin", vec![1, 2, 3]).unwrap();
        let err = w.finish().unwrap_err().to_string();
        assert!(err.contains("plain"), "{err}");
    }
}
