//! Checksummed cell files: write atomically and record a [`FileRef`]; read and verify.

use std::path::Path;

use super::manifest::FileRef;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

/// CRC-32 of `bytes` as 8 lowercase hex digits.
pub fn crc32_hex(bytes: &[u8]) -> String {
    format!("{:08x}", crc32fast::hash(bytes))
}

/// Writes `bytes` atomically to `store/rel` and returns its [`FileRef`].
pub fn write_file(store: &Path, rel: &str, bytes: &[u8]) -> Result<FileRef> {
    write_atomic(&store.join(rel), bytes)?;
    Ok(file_ref(rel, bytes))
}

/// The record of `bytes` stored at `rel` (size and checksum).
pub(crate) fn file_ref(rel: &str, bytes: &[u8]) -> FileRef {
    FileRef {
        path: rel.to_string(),
        bytes: bytes.len() as u64,
        crc32: crc32_hex(bytes),
    }
}

/// Reads `store/file.path` and checks its size and checksum.
pub fn read_verified(store: &Path, file: &FileRef) -> Result<Vec<u8>> {
    let path = store.join(&file.path);
    let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
    if bytes.len() as u64 != file.bytes || crc32_hex(&bytes) != file.crc32 {
        return Err(Error::store(
            &path,
            format!(
                "checksum mismatch (expected {} bytes crc {}, found {} bytes crc {}): the file is corrupt; rebuild the store",
                file.bytes,
                file.crc32,
                bytes.len(),
                crc32_hex(&bytes)
            ),
        ));
    }
    Ok(bytes)
}

/// True if the file exists with the recorded size and checksum.
pub fn is_intact(store: &Path, file: &FileRef) -> bool {
    read_verified(store, file).is_ok()
}
