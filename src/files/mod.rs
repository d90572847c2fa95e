//! The rules for the files lanterna reads and writes, in one place, because careless and
//! hostile paths reach every command:
//!
//! * reads are bounded ([`read_input`]): a file larger than [`max_input_bytes`] or an
//!   endless stream (`/dev/zero`, a FIFO) is refused instead of growing memory without
//!   bound, and the first bytes are checked before the rest is read;
//! * writes are atomic ([`write_atomically`]): a temporary `.NAME.PID.tmp` next to the
//!   target, renamed over it. A symlink is written through (its target is replaced, the
//!   link stays); a FIFO, device, socket or directory is refused, never replaced.
//!   Temporary files that dead processes left behind are removed on the way;
//! * a run never writes over its own inputs or twice to one file ([`FilePlan`]): paths
//!   are compared canonically and, where files exist, by device and inode, so hard links
//!   and symlinks are caught too.

mod identity;
mod read;
mod write;

pub use identity::{FileId, FilePlan};
pub use read::{max_input_bytes, read_input, Start, MAX_INPUT_ENV};
pub use write::{remove_stale_temps, write_all_atomically, write_atomically};

use std::path::PathBuf;

/// What went wrong with a file; every variant names it.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    #[error("{}: file not found", path.display())]
    NotFound { path: PathBuf },
    // `error` is not a `source`: the message already includes it, once.
    #[error("{}: {error}", path.display())]
    Io {
        path: PathBuf,
        error: std::io::Error,
    },
    #[error(
        "{}: is {kind}, not a regular file; lanterna writes only regular files (and \
         through symlinks to them) and never replaces anything else",
        path.display()
    )]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error(
        "{}: larger than {limit} bytes, the most lanterna reads from one file (an endless \
         stream?); raise the limit with {}=MIB if the file is genuine",
        path.display(),
        MAX_INPUT_ENV
    )]
    TooLarge { path: PathBuf, limit: u64 },
    #[error("{}: is a directory, not a file", path.display())]
    IsDirectory { path: PathBuf },
    /// The first bytes say the file is not of the kind expected.
    #[error("{}: {reason}", path.display())]
    Format { path: PathBuf, reason: String },
    #[error(
        "{what} {} is the same file as {other_what} {}: refusing to overwrite it",
        path.display(),
        other.display()
    )]
    SameFile {
        what: String,
        path: PathBuf,
        other_what: String,
        other: PathBuf,
    },
}

impl FileError {
    pub(crate) fn io(path: &std::path::Path, error: std::io::Error) -> FileError {
        if error.kind() == std::io::ErrorKind::NotFound {
            FileError::NotFound {
                path: path.to_path_buf(),
            }
        } else {
            FileError::Io {
                path: path.to_path_buf(),
                error,
            }
        }
    }
}

/// A description of a file type that is not a regular file, for messages.
pub(crate) fn kind_name(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_dir() {
        "a directory"
    } else if ft.is_symlink() {
        "a symbolic link"
    } else if ft.is_file() {
        "a regular file"
    } else {
        "a special file"
    }
}
