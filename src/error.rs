//! The crate's error type. Every error that comes from user input names the file
//! (or option) and the problem, so the CLI can print it and exit non-zero.

use std::path::{Path, PathBuf};

/// Result alias used across cliffmap.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong in cliffmap. Input errors carry the offending path.
///
/// Callers tell apart the cases they must act on by variant: a bad input file
/// ([`Error::BadInput`], [`Error::Io`], [`Error::TooLarge`]), a bad option
/// ([`Error::BadOption`]), a store another process is writing ([`Error::StoreLocked`]), a
/// store of another version ([`Error::StoreVersion`]), a damaged store ([`Error::Store`]) and
/// the GPU ([`Error::Gpu`]). New variants may be added.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An I/O error while reading or writing `path`.
    #[error("{path}: {error}")]
    Io {
        /// The file involved.
        path: PathBuf,
        /// The underlying error (already part of the message, so not a separate source).
        error: std::io::Error,
    },
    /// The file exists but its content is not acceptable (truncated, NaN heights, bad tags...).
    #[error("{path}: {msg}")]
    BadInput {
        /// The file involved.
        path: PathBuf,
        /// What is wrong, in words a user can act on.
        msg: String,
    },
    /// An option or combination of options is invalid (no file involved).
    #[error("invalid option: {0}")]
    BadOption(String),
    /// The inputs are well-formed but do not allow the computation asked for (e.g. too few
    /// usable ground control points for the free parameters); the message says why.
    #[error("{0}")]
    Unusable(String),
    /// The input would need more memory than the configured limit.
    #[error(
        "{path}: would need {needed} bytes, over the memory limit of {limit} bytes (raise --max-memory if this is intended)"
    )]
    TooLarge {
        /// The file involved.
        path: PathBuf,
        /// Bytes the input would need.
        needed: u64,
        /// The configured limit in bytes.
        limit: u64,
    },
    /// A store on disk is corrupt or of an unknown version.
    #[error("store {path}: {msg}")]
    Store {
        /// The store file involved.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// Another process holds the store's writer lock (`STORE/.lock`).
    #[error(
        "store {path}: another cliffmap process is writing this store ({holder}); wait for it to finish, then run `{command}` again"
    )]
    StoreLocked {
        /// The store directory.
        path: PathBuf,
        /// What the lock file says of its holder (process id and command), or "holder unknown".
        holder: String,
        /// The command that was refused.
        command: String,
    },
    /// The store's manifest has a version this cliffmap does not read.
    #[error(
        "store {path}: store version {found} is not supported (this cliffmap reads version {supported})"
    )]
    StoreVersion {
        /// The manifest file.
        path: PathBuf,
        /// The version the manifest records.
        found: u32,
        /// The version this cliffmap reads.
        supported: u32,
    },
    /// The GPU (wgpu adapter, device or a GPU operation) failed or is unavailable.
    #[error("GPU: {0}")]
    Gpu(String),
}

impl Error {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().to_path_buf(),
            error: source,
        }
    }
    /// A content problem in `path`.
    pub fn bad_input(path: impl AsRef<Path>, msg: impl Into<String>) -> Self {
        Error::BadInput {
            path: path.as_ref().to_path_buf(),
            msg: msg.into(),
        }
    }
    /// A problem in the store file `path`.
    pub fn store(path: impl AsRef<Path>, msg: impl Into<String>) -> Self {
        Error::Store {
            path: path.as_ref().to_path_buf(),
            msg: msg.into(),
        }
    }
}
