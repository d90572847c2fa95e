//! Bounded reads of input files (scenes, buffers, images, EXRs, SD-trees): the first
//! bytes are checked by the caller before the rest is read, and nothing larger than the
//! input limit is read at all.

use super::FileError;
use std::io::Read;
use std::path::Path;

/// Environment variable overriding the input size limit, in MiB.
pub const MAX_INPUT_ENV: &str = "LANTERNA_MAX_INPUT_MIB";

/// The default limit: 4 GiB, the largest file GLB can describe.
const DEFAULT_MAX_INPUT_BYTES: u64 = 4 << 30;

/// The most bytes lanterna reads from one input file: `LANTERNA_MAX_INPUT_MIB` MiB, or
/// 4 GiB.
pub fn max_input_bytes() -> u64 {
    std::env::var(MAX_INPUT_ENV)
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .filter(|&mib| mib > 0)
        .map_or(DEFAULT_MAX_INPUT_BYTES, |mib| mib.saturating_mul(1 << 20))
}

/// What the caller concluded from a file's first bytes.
pub enum Start {
    /// Read on, up to the limit.
    Continue,
    /// The format declares its total length: read at most this many bytes (what follows
    /// is not read; a shorter file is the format parser's to report).
    Length(u64),
}

/// How many bytes `check_start` sees (fewer when the file is shorter).
const START_BYTES: usize = 64;

/// Reads `path` whole, refusing more than `limit` bytes. `check_start` sees the first
/// bytes (up to 64) and rejects a file that is not of the expected kind before anything
/// more is read (so `/dev/zero` given as a scene costs 64 bytes, not gigabytes).
pub fn read_input(
    path: &Path,
    limit: u64,
    check_start: &dyn Fn(&[u8]) -> Result<Start, String>,
) -> Result<Vec<u8>, FileError> {
    let io = |e| FileError::io(path, e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if meta.is_dir() {
        return Err(FileError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    if meta.is_file() && meta.len() > limit {
        return Err(FileError::TooLarge {
            path: path.to_path_buf(),
            limit,
        });
    }
    let mut data = Vec::with_capacity(if meta.is_file() {
        meta.len() as usize
    } else {
        START_BYTES
    });
    (&mut file)
        .take(START_BYTES as u64)
        .read_to_end(&mut data)
        .map_err(io)?;
    let start = check_start(&data).map_err(|reason| FileError::Format {
        path: path.to_path_buf(),
        reason,
    })?;
    match start {
        Start::Length(n) if n > limit => Err(FileError::TooLarge {
            path: path.to_path_buf(),
            limit,
        }),
        Start::Length(n) => {
            if data.len() as u64 >= n {
                data.truncate(n as usize);
            } else {
                file.take(n - data.len() as u64)
                    .read_to_end(&mut data)
                    .map_err(io)?;
            }
            Ok(data)
        }
        Start::Continue => {
            // One byte past the limit tells "exactly at the limit" from "more".
            file.take((limit + 1).saturating_sub(data.len() as u64))
                .read_to_end(&mut data)
                .map_err(io)?;
            if data.len() as u64 > limit {
                return Err(FileError::TooLarge {
                    path: path.to_path_buf(),
                    limit,
                });
            }
            Ok(data)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_stream_is_refused_at_the_limit() {
        let e = read_input(Path::new("/dev/zero"), 1000, &|_| Ok(Start::Continue)).unwrap_err();
        assert!(matches!(e, FileError::TooLarge { limit: 1000, .. }), "{e}");
    }

    #[test]
    fn start_check_runs_before_the_rest_is_read() {
        let e = read_input(Path::new("/dev/zero"), u64::MAX / 2, &|start| {
            assert!(start.len() <= START_BYTES);
            Err("zeros".into())
        })
        .unwrap_err();
        assert!(e.to_string().contains("zeros"), "{e}");
    }

    #[test]
    fn declared_length_bounds_the_read() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("f");
        std::fs::write(&p, [7u8; 100]).unwrap();
        let d = read_input(&p, 1000, &|_| Ok(Start::Length(80))).unwrap();
        assert_eq!(d.len(), 80);
        let d = read_input(&p, 1000, &|_| Ok(Start::Continue)).unwrap();
        assert_eq!(d.len(), 100);
        assert!(read_input(&p, 99, &|_| Ok(Start::Continue)).is_err());
        assert!(read_input(&p, 100, &|_| Ok(Start::Continue)).is_ok());
        let e = read_input(dir.path(), 1000, &|_| Ok(Start::Continue)).unwrap_err();
        assert!(e.to_string().contains("directory"), "{e}");
    }
}
