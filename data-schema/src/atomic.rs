//! Atomic file output: write to a temporary file beside the target, then rename.
//!
//! A rename within one folder is atomic on POSIX file systems, so readers see
//! either the old complete file or the new complete file, never a partial one.

use crate::error::{Result, SchemaError};
use crate::unstage::Unstage;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Temporary path used while `target` is being written (same folder, hidden, `.tmp` suffix).
pub fn temp_path(target: &Path) -> PathBuf {
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let tmp = format!(".{name}.{}.tmp", std::process::id());
    match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// Write `target` atomically: `fill` writes the whole content into a temporary
/// file, which is flushed, synced and renamed onto `target` only if `fill` succeeds.
/// On error the temporary file is removed and `target` is left untouched.
pub fn write_atomic<F>(target: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut std::io::BufWriter<std::fs::File>) -> Result<()>,
{
    if let Some(parent) = target.parent() {
        if !parent.as_os_str().is_empty() {
            std::fs::create_dir_all(parent).map_err(|e| SchemaError::io(parent, e))?;
        }
    }
    let tmp = temp_path(target);
    let result: Result<()> = (|| {
        let file = std::fs::File::create(&tmp).map_err(|e| SchemaError::io(&tmp, e))?;
        let mut w = std::io::BufWriter::new(file);
        fill(&mut w)?;
        w.flush().map_err(|e| SchemaError::io(target, e))?;
        w.get_ref().sync_all().map_err(|e| SchemaError::io(target, e))?;
        Ok(())
    })();
    match result {
        Ok(()) => commit(&tmp, target),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e.unstaged(&tmp, target))
        }
    }
}

/// Write `target` atomically through a file written by another library (e.g. HDF5): `fill`
/// writes the whole content at the temporary path it is given (a leftover of an earlier attempt
/// is removed first) and closes it; on success the file is renamed onto `target`, on error it is
/// removed and `target` is left untouched.
pub fn write_via<T>(target: &Path, fill: impl FnOnce(&Path) -> Result<T>) -> Result<T> {
    let tmp = temp_path(target);
    let _ = std::fs::remove_file(&tmp);
    match fill(&tmp) {
        Ok(v) => {
            commit(&tmp, target)?;
            Ok(v)
        }
        // the user asked for `target`; the temporary name is ours
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e.unstaged(&tmp, target))
        }
    }
}

/// Move an already complete temporary file into place (used for outputs written by other
/// libraries, e.g. HDF5 or images). If the rename fails (say `target` is a folder), the
/// temporary file is removed: the error names `target`, and nothing of ours is left beside it.
pub fn commit(tmp: &Path, target: &Path) -> Result<()> {
    std::fs::rename(tmp, target).map_err(|e| {
        let _ = std::fs::remove_file(tmp);
        SchemaError::io(target, e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_old_file_untouched() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.csv");
        std::fs::write(&target, "old").unwrap();
        let err = write_atomic(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(SchemaError::Invalid { path: target.clone(), message: "boom".into() })
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "temporary file removed");
    }

    /// An error while the temporary file is written names the file the user asked for, in its
    /// path and in its message, never the temporary name.
    #[test]
    fn a_failed_write_names_the_target_not_the_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("merged.h5");
        let err = write_via(&target, |tmp| std::fs::read(tmp).map(|_| ()).map_err(|e| SchemaError::io(tmp, e))).unwrap_err().to_string();
        assert!(err.starts_with(&target.display().to_string()) && !err.contains(&temp_path(&target).display().to_string()), "{err}");
        let err = write_via(&target, |tmp| -> Result<()> { Err(SchemaError::Hdf5 { path: tmp.to_path_buf(), message: format!("unable to extend {} (disk full)", tmp.display()) }) }).unwrap_err().to_string();
        assert_eq!(err, format!("{0}: HDF5: unable to extend {0} (disk full)", target.display()));
        let err = write_atomic(&target, |_| Err(SchemaError::io(temp_path(&target), std::io::Error::other("no space")))).unwrap_err().to_string();
        assert_eq!(err, format!("{}: no space", target.display()));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing left behind");
    }

    /// A rename that fails (the target is a folder holding a file) names the target and leaves
    /// neither a temporary file nor a changed folder, through both writers.
    #[test]
    fn a_failed_rename_removes_the_temporary_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.h5");
        std::fs::create_dir(&target).unwrap();
        std::fs::write(target.join("kept.txt"), "kept").unwrap();
        let err = write_atomic(&target, |w| w.write_all(b"new").map_err(|e| SchemaError::io("x", e))).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: ", target.display())), "{err}");
        let err = write_via(&target, |tmp| std::fs::write(tmp, b"new").map_err(|e| SchemaError::io(tmp, e))).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: ", target.display())), "{err}");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("out.h5")], "only the folder is left");
        assert_eq!(std::fs::read_to_string(target.join("kept.txt")).unwrap(), "kept");
    }

    #[test]
    fn successful_write_replaces_file() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("sub/out.csv");
        write_atomic(&target, |w| w.write_all(b"new").map_err(|e| SchemaError::io("x", e))).unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "new");
    }
}
