//! Atomic writes: a temporary `.NAME.PID.tmp` in the target's directory, synced and
//! renamed over the target, so a crash never leaves a half-written file under the final
//! name. What the target may be: nothing yet, a regular file (replaced), or a symlink to
//! a regular file (written through: the file it points to is replaced and the link
//! stays). Anything else is refused. Temporary files of processes that no longer run
//! are removed on the way (a killed run cannot clean up after itself).

use super::{kind_name, FileError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Writes `bytes` to `path` atomically (see the module comment).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), FileError> {
    write_all_atomically(&[(path, bytes)])
}

/// Writes several files so that either all are replaced or none is: every temporary file
/// is written and synced before the first rename.
pub fn write_all_atomically(files: &[(&Path, &[u8])]) -> Result<(), FileError> {
    let mut staged: Vec<(PathBuf, PathBuf)> = Vec::new();
    let result = (|| {
        for (path, bytes) in files {
            let target = resolve_target(path)?;
            let tmp = temp_name(&target);
            remove_stale_temps(&target);
            write_temp(&tmp, bytes).map_err(|e| FileError::io(path, e))?;
            staged.push((tmp, target));
        }
        for (i, (tmp, target)) in staged.iter().enumerate() {
            std::fs::rename(tmp, target).map_err(|e| FileError::io(files[i].0, e))?;
        }
        Ok(())
    })();
    if result.is_err() {
        for (tmp, _) in &staged {
            let _ = std::fs::remove_file(tmp);
        }
    }
    result
}

/// The file a write to `path` replaces: `path` itself, or the regular file a symlink at
/// `path` points to. Refuses directories, FIFOs, devices, sockets and dangling links.
pub(super) fn resolve_target(path: &Path) -> Result<PathBuf, FileError> {
    if path.file_name().is_none() {
        return Err(FileError::IsDirectory {
            path: path.to_path_buf(),
        });
    }
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(path.to_path_buf()),
        Err(e) => return Err(FileError::io(path, e)),
    };
    let ft = meta.file_type();
    if ft.is_file() {
        return Ok(path.to_path_buf());
    }
    if !ft.is_symlink() {
        return Err(FileError::NotRegular {
            path: path.to_path_buf(),
            kind: kind_name(&ft),
        });
    }
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => std::fs::canonicalize(path).map_err(|e| FileError::io(path, e)),
        Ok(m) => Err(FileError::NotRegular {
            path: path.to_path_buf(),
            kind: match kind_name(&m.file_type()) {
                "a directory" => "a symbolic link to a directory",
                "a FIFO" => "a symbolic link to a FIFO",
                "a character device" => "a symbolic link to a character device",
                "a block device" => "a symbolic link to a block device",
                _ => "a symbolic link to a special file",
            },
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(FileError::NotRegular {
            path: path.to_path_buf(),
            kind: "a dangling symbolic link",
        }),
        Err(e) => Err(FileError::io(path, e)),
    }
}

fn dir_and_name(target: &Path) -> (PathBuf, String) {
    let dir = match target.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    (dir, name)
}

fn temp_name(target: &Path) -> PathBuf {
    let (dir, name) = dir_and_name(target);
    dir.join(format!(".{name}.{}.tmp", std::process::id()))
}

/// Creates the temporary file anew (never following a link planted at its name).
fn write_temp(tmp: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let open = || {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(tmp)
    };
    let mut file = match open() {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
            // Ours (this process id) from an earlier failed attempt: replace it.
            std::fs::remove_file(tmp)?;
            open()?
        }
        Err(e) => return Err(e),
    };
    let result = file.write_all(bytes).and_then(|()| file.sync_all());
    if result.is_err() {
        let _ = std::fs::remove_file(tmp);
    }
    result
}

/// Whether process `pid` is running. Only Linux's `/proc` answers reliably; elsewhere,
/// or without `/proc`, every process counts as running (nothing is removed).
fn process_alive(pid: u32) -> bool {
    let proc = Path::new("/proc");
    if !cfg!(target_os = "linux") || !proc.join("self").exists() {
        return true;
    }
    proc.join(pid.to_string()).exists()
}

/// Removes `.NAME.PID.tmp` files next to `target` whose process is gone (left by a run
/// that was killed while writing). Returns how many were removed.
pub fn remove_stale_temps(target: &Path) -> usize {
    let (dir, name) = dir_and_name(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return 0;
    };
    let prefix = format!(".{name}.");
    let mut removed = 0;
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(pid) = file_name
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|pid| pid.parse::<u32>().ok())
        else {
            continue;
        };
        if pid == std::process::id() || process_alive(pid) {
            continue;
        }
        let path = entry.path();
        let regular = std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_file());
        if regular && std::fs::remove_file(&path).is_ok() {
            log::info!(
                "removed {}, left behind by process {pid} which no longer runs",
                path.display()
            );
            removed += 1;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temps(dir: &Path) -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".tmp"))
            .collect()
    }

    #[test]
    fn replaces_a_regular_file_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.txt");
        write_atomically(&p, b"one").unwrap();
        write_atomically(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert!(temps(dir.path()).is_empty());
    }

    #[cfg(unix)]
    #[test]
    fn writes_through_a_symlink_and_keeps_it() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.txt");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_atomically(&link, b"new").unwrap();
        assert!(std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
    }

    #[cfg(unix)]
    #[test]
    fn refuses_special_files() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_atomically(dir.path(), b"x").unwrap_err();
        assert!(matches!(e, FileError::NotRegular { .. }), "{e}");
        let e = write_atomically(Path::new("/dev/null"), b"x").unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let dangling = dir.path().join("dangling");
        std::os::unix::fs::symlink(dir.path().join("nowhere"), &dangling).unwrap();
        assert!(write_atomically(&dangling, b"x").is_err());
        assert!(!dir.path().join("nowhere").exists());
    }

    #[test]
    fn removes_temps_of_dead_processes_only() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.exr");
        // No process has id u32::MAX - 1 (pid_max is at most 2^22 on Linux).
        let dead = dir.path().join(format!(".out.exr.{}.tmp", u32::MAX - 1));
        let alive = dir.path().join(".out.exr.1.tmp");
        let other = dir.path().join(format!(".other.exr.{}.tmp", u32::MAX - 1));
        for p in [&dead, &alive, &other] {
            std::fs::write(p, b"x").unwrap();
        }
        write_atomically(&target, b"data").unwrap();
        if cfg!(target_os = "linux") {
            assert!(!dead.exists(), "the dead process's temp file stays");
        }
        assert!(alive.exists(), "pid 1 runs: its file must stay");
        assert!(other.exists(), "another output's temp file must stay");
    }
}
