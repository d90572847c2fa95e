//! Which files are the same file: by device and inode where a file exists (hard links,
//! symlinks, `./a` vs `a`), else by canonical path. A [`FilePlan`] lists what a run will
//! read and write and refuses, before anything is rendered, an output that is one of its
//! inputs or another of its outputs, or that no write could replace.

use super::FileError;
use std::path::{Path, PathBuf};

/// A file's identity: (device, inode) on Unix.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct FileId {
    dev: u64,
    ino: u64,
}

impl FileId {
    /// The identity of the file at `path` (links followed); `None` when there is none.
    pub fn of(path: &Path) -> Option<FileId> {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            std::fs::metadata(path).ok().map(|m| FileId {
                dev: m.dev(),
                ino: m.ino(),
            })
        }
        #[cfg(not(unix))]
        {
            let _ = path;
            None
        }
    }
}

/// Where `path` leads: its canonical form if it exists, else its canonical directory
/// joined with its name, else its absolute form.
fn canonical(path: &Path) -> PathBuf {
    if let Ok(p) = std::fs::canonicalize(path) {
        return p;
    }
    if let (Some(dir), Some(name)) = (path.parent(), path.file_name()) {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = std::fs::canonicalize(dir) {
            return d.join(name);
        }
    }
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf())
}

struct Entry {
    what: String,
    path: PathBuf,
    canonical: PathBuf,
    id: Option<FileId>,
}

impl Entry {
    fn new(what: &str, path: &Path) -> Entry {
        Entry {
            what: what.to_string(),
            path: path.to_path_buf(),
            canonical: canonical(path),
            id: FileId::of(path),
        }
    }

    fn same(&self, other: &Entry) -> bool {
        self.canonical == other.canonical
            || matches!((self.id, other.id), (Some(a), Some(b)) if a == b)
    }
}

/// The files one run reads and writes (see the module comment).
#[derive(Default)]
pub struct FilePlan {
    inputs: Vec<Entry>,
    outputs: Vec<Entry>,
}

impl FilePlan {
    pub fn new() -> FilePlan {
        FilePlan::default()
    }

    /// A file the run reads; `what` names it in messages ("the scene", "--reference").
    pub fn input(&mut self, what: &str, path: &Path) -> &mut Self {
        self.inputs.push(Entry::new(what, path));
        self
    }

    /// Several inputs of one kind.
    pub fn inputs<'a>(
        &mut self,
        what: &str,
        paths: impl IntoIterator<Item = &'a PathBuf>,
    ) -> &mut Self {
        for p in paths {
            self.input(what, p);
        }
        self
    }

    /// A file the run writes.
    pub fn output(&mut self, what: &str, path: &Path) -> &mut Self {
        self.outputs.push(Entry::new(what, path));
        self
    }

    /// Refuses an output that is an input or an earlier output, or that a write would
    /// refuse (a directory, FIFO, device: so the run fails before its work, not after).
    pub fn check(&self) -> Result<(), FileError> {
        for (i, out) in self.outputs.iter().enumerate() {
            super::write::resolve_target(&out.path)?;
            let clash = self
                .inputs
                .iter()
                .chain(&self.outputs[..i])
                .find(|other| out.same(other));
            if let Some(other) = clash {
                return Err(FileError::SameFile {
                    what: out.what.clone(),
                    path: out.path.clone(),
                    other_what: other.what.clone(),
                    other: other.path.clone(),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn catches_the_same_file_under_other_names() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let scene = d.join("scene.gltf");
        std::fs::write(&scene, b"{}").unwrap();
        std::fs::create_dir(d.join("sub")).unwrap();

        let dotted = d.join("sub").join("..").join("scene.gltf");
        let mut plan = FilePlan::new();
        plan.input("the scene", &scene).output("-o", &dotted);
        let e = plan.check().unwrap_err();
        assert!(e.to_string().contains("same file as the scene"), "{e}");

        #[cfg(unix)]
        {
            let hard = d.join("hard.gltf");
            std::fs::hard_link(&scene, &hard).unwrap();
            let mut plan = FilePlan::new();
            plan.input("the scene", &scene).output("-o", &hard);
            assert!(plan.check().is_err(), "hard link not caught");

            let soft = d.join("soft.gltf");
            std::os::unix::fs::symlink(&scene, &soft).unwrap();
            let mut plan = FilePlan::new();
            plan.input("the scene", &scene).output("-o", &soft);
            assert!(plan.check().is_err(), "symlink not caught");
        }

        let mut plan = FilePlan::new();
        plan.output("-o", &d.join("new.exr"))
            .output("--png", &d.join("sub/../new.exr"));
        assert!(plan.check().is_err(), "two outputs to one new file");

        let mut plan = FilePlan::new();
        plan.input("the scene", &scene)
            .output("-o", &d.join("a.exr"))
            .output("--png", &d.join("a.png"));
        plan.check().unwrap();
    }
}
