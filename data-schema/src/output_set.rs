//! A command's outputs replaced as a set: all the old ones or all the new ones, never a mix.
//!
//! [`write_set`] hands the command a staging folder `.<name>.staging-<pid>` beside the output
//! folder `<name>` (same parent, so the same file system; inside `<name>` when the parent is not
//! writable) and, only when everything was written there, moves the entries into place: each
//! file by one rename, each sub-folder (e.g. `figures/`) as a whole by one rename. The entries of the output folder the command owns
//! (`owns`) but did not write this time (e.g. the figure of a start shape no longer present)
//! are removed with the same moves. If writing fails, the output folder is not touched; if a
//! move fails, the moves already made are undone, so the previous outputs are back. Staging
//! folders of processes that no longer exist (killed mid-run) are removed by the next command
//! writing to the same folder. Files of the output folder the command does not own are left
//! alone.

use crate::error::{Result, SchemaError};
use crate::unstage::Unstage;
use std::path::{Path, PathBuf};

/// Write a set of outputs into `out` (a folder, created when missing): `fill` writes them into
/// the folder it is given, under the names they get in `out`; then they replace the entries of
/// `out` of the same names, and the entries of `out` for which `owns(name)` holds are removed
/// when `fill` did not write them again. Returns `fill`'s value and every file now in place
/// (paths under `out`, sorted). On error `out` holds exactly what it held before and no
/// temporary folder is left behind.
///
/// An error of `fill` names the output folder where it named the staging folder or a file in it
/// ([`Unstage`]): the user asked for `out`, the staging name is ours.
pub fn write_set<T, E>(
    out: &Path,
    owns: impl Fn(&str) -> bool,
    fill: impl FnOnce(&Path) -> std::result::Result<T, E>,
) -> std::result::Result<(T, Vec<PathBuf>), E>
where
    E: From<SchemaError> + Unstage,
{
    write_set_with(out, owns, fill, E::unstaged)
}

/// [`write_set`] for an error type that does not implement [`Unstage`] (a binary's
/// `anyhow::Error`): `unstage(error, staging, out)` rewrites an error of `fill`.
pub fn write_set_with<T, E>(
    out: &Path,
    owns: impl Fn(&str) -> bool,
    fill: impl FnOnce(&Path) -> std::result::Result<T, E>,
    unstage: impl FnOnce(E, &Path, &Path) -> E,
) -> std::result::Result<(T, Vec<PathBuf>), E>
where
    E: From<SchemaError>,
{
    let set = Staging::begin(out)?;
    let value = fill(&set.dir).map_err(|e| unstage(e, &set.dir, out))?;
    let written = set.commit(&owns, &mut |from, to| std::fs::rename(from, to))?;
    Ok((value, written))
}

/// The staging folder of one [`write_set`] and the folder where replaced entries wait until the
/// set is in place; both are removed when dropped.
struct Staging {
    out: PathBuf,
    dir: PathBuf,
    replaced: PathBuf,
}

impl Staging {
    /// Stage beside `out`; where its parent is not writable (e.g. `--out .` in a home folder),
    /// inside `out` (the same file system either way).
    fn begin(out: &Path) -> Result<Staging> {
        let (parent, name) = home(out)?;
        Staging::begin_in(out, &parent, &name).or_else(|beside| {
            if std::fs::create_dir_all(out).is_err() {
                return Err(beside);
            }
            Staging::begin_in(out, out, &name).map_err(|_| beside)
        })
    }

    fn begin_in(out: &Path, parent: &Path, name: &str) -> Result<Staging> {
        remove_dead_leftovers(parent, name);
        let pid = std::process::id();
        let dir = parent.join(format!(".{name}.staging-{pid}"));
        let replaced = parent.join(format!(".{name}.replaced-{pid}"));
        for d in [&dir, &replaced] {
            if d.exists() {
                std::fs::remove_dir_all(d).map_err(|e| SchemaError::io(d, e))?;
            }
        }
        std::fs::create_dir(&dir).map_err(|e| SchemaError::io(&dir, e))?;
        Ok(Staging { out: out.to_path_buf(), dir, replaced })
    }

    /// Whether `name` in `out` is this set's own staging or replaced folder (staged inside `out`).
    fn is_own(&self, name: &str) -> bool {
        [&self.dir, &self.replaced].iter().any(|d| d.file_name().is_some_and(|n| n == name) && d.parent() == Some(self.out.as_path()))
    }

    /// Move the staged entries into `out` with `rename`, undoing every move made if one fails.
    fn commit(
        &self,
        owns: &dyn Fn(&str) -> bool,
        rename: &mut dyn FnMut(&Path, &Path) -> std::io::Result<()>,
    ) -> Result<Vec<PathBuf>> {
        let staged = entry_names(&self.dir)?;
        let mut files = Vec::new();
        for name in &staged {
            list_files(&self.dir.join(name), &self.out.join(name), &mut files)?;
        }
        std::fs::create_dir_all(&self.out).map_err(|e| SchemaError::io(&self.out, e))?;
        let stale: Vec<String> = entry_names(&self.out)?
            .into_iter()
            .filter(|n| owns(n) && !staged.contains(n) && !self.is_own(n))
            .collect();
        std::fs::create_dir(&self.replaced).map_err(|e| SchemaError::io(&self.replaced, e))?;

        // one log of the moves made, undone in reverse order on failure
        let mut done: Vec<(PathBuf, PathBuf)> = Vec::new();
        let mut step = |from: PathBuf, to: PathBuf, done: &mut Vec<(PathBuf, PathBuf)>| -> Result<()> {
            rename(&from, &to).map_err(|e| SchemaError::io(&to, e))?;
            done.push((from, to));
            Ok(())
        };
        let result = (|| -> Result<()> {
            for name in &staged {
                let target = self.out.join(name);
                if std::fs::symlink_metadata(&target).is_ok() {
                    step(target.clone(), self.replaced.join(name), &mut done)?;
                }
                step(self.dir.join(name), target, &mut done)?;
            }
            for name in &stale {
                step(self.out.join(name), self.replaced.join(name), &mut done)?;
            }
            Ok(())
        })();
        if let Err(e) = result {
            for (from, to) in done.iter().rev() {
                let _ = std::fs::rename(to, from);
            }
            return Err(e);
        }
        files.sort();
        Ok(files)
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
        let _ = std::fs::remove_dir_all(&self.replaced);
    }
}

/// The folder that holds `out` and `out`'s name in it (the parent is created when missing). An
/// existing `out` is resolved first, so that a symlink to a folder on another disk is staged
/// beside the folder itself (a rename cannot cross file systems).
fn home(out: &Path) -> Result<(PathBuf, String)> {
    if let Ok(abs) = out.canonicalize() {
        return Ok(match (abs.parent(), abs.file_name()) {
            (Some(p), Some(n)) => (p.to_path_buf(), n.to_string_lossy().into_owned()),
            _ => (abs.clone(), "output".into()),
        });
    }
    if let (Some(parent), Some(name)) = (out.parent(), out.file_name()) {
        let parent = if parent.as_os_str().is_empty() { Path::new(".") } else { parent };
        std::fs::create_dir_all(parent).map_err(|e| SchemaError::io(parent, e))?;
        return Ok((parent.to_path_buf(), name.to_string_lossy().into_owned()));
    }
    // `..` or `a/..` of a folder that does not exist
    Err(SchemaError::io(out, std::io::Error::new(std::io::ErrorKind::NotFound, "no such folder")))
}

/// Remove `.<name>.staging-<pid>` and `.<name>.replaced-<pid>` folders in `parent` whose process
/// has ended (Linux: no `/proc/<pid>`; elsewhere nothing is removed).
fn remove_dead_leftovers(parent: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(parent) else { return };
    for e in entries.flatten() {
        let file_name = e.file_name().to_string_lossy().into_owned();
        let pid = [".staging-", ".replaced-"].iter().find_map(|kind| {
            file_name.strip_prefix(&format!(".{name}{kind}")).and_then(|p| p.parse::<u32>().ok())
        });
        if let Some(pid) = pid {
            if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_dir_all(e.path());
            }
        }
    }
}

/// Names of the entries of `dir`, sorted.
fn entry_names(dir: &Path) -> Result<Vec<String>> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).map_err(|e| SchemaError::io(dir, e))? {
        let e = e.map_err(|e| SchemaError::io(dir, e))?;
        names.push(e.file_name().to_string_lossy().into_owned());
    }
    names.sort();
    Ok(names)
}

/// Every file under `src` (a file or a folder), as the path it gets under `dst`.
fn list_files(src: &Path, dst: &Path, files: &mut Vec<PathBuf>) -> Result<()> {
    let meta = std::fs::symlink_metadata(src).map_err(|e| SchemaError::io(src, e))?;
    if meta.is_dir() {
        for name in entry_names(src)? {
            list_files(&src.join(&name), &dst.join(&name), files)?;
        }
    } else {
        files.push(dst.to_path_buf());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Every file under `dir` with its bytes (relative paths).
    fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
        let mut files = Vec::new();
        list_files(dir, Path::new(""), &mut files).unwrap();
        files.into_iter().map(|p| (p.display().to_string(), std::fs::read(dir.join(&p)).unwrap())).collect()
    }

    fn write(path: &Path, text: &str) -> Result<()> {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).map_err(|e| SchemaError::io(path, e))
    }

    /// An error while the set is staged names the output folder and the file in it, in its path
    /// and its message, never the hidden staging folder; `out` stays as it was.
    #[test]
    fn a_failed_fill_names_the_output_not_the_staging_folder() {
        let root = tempfile::tempdir().unwrap();
        let out = previous(root.path());
        let before = snapshot(&out);
        let err = write_set(&out, |_| true, |dir| -> Result<()> {
            write(&dir.join("a.csv"), "new a")?;
            Err(SchemaError::Invalid { path: dir.join("figures/f1.png"), message: format!("cannot write {}", dir.join("figures").display()) })
        })
        .unwrap_err()
        .to_string();
        assert_eq!(err, format!("{}: cannot write {}", out.join("figures/f1.png").display(), out.join("figures").display()));
        assert_eq!(snapshot(&out), before);
    }

    /// `out` with two tables, a figure folder, a stale owned figure table and a file of the user's.
    fn previous(root: &Path) -> PathBuf {
        let out = root.join("out");
        for (p, t) in [("a.csv", "old a"), ("b.csv", "old b"), ("figures/f1.png", "old f1"), ("extra_owned.csv", "old extra"), ("notes.txt", "user")] {
            write(&out.join(p), t).unwrap();
        }
        out
    }

    fn owns(name: &str) -> bool {
        name.ends_with(".csv") || name == "figures"
    }

    fn fill_new(dir: &Path) -> Result<()> {
        write(&dir.join("a.csv"), "new a")?;
        write(&dir.join("b.csv"), "new b")?;
        write(&dir.join("figures/f2.png"), "new f2")
    }

    /// Only `out` is left in the root: no staging or replaced folder.
    fn assert_no_leftovers(root: &Path) {
        let names = entry_names(root).unwrap();
        assert_eq!(names, ["out"], "temporary folders left behind");
    }

    #[test]
    fn a_successful_set_replaces_every_owned_entry_and_keeps_the_rest() {
        let root = tempfile::tempdir().unwrap();
        let out = previous(root.path());
        let ((), written) = write_set(&out, owns, fill_new).unwrap();
        let expected: BTreeMap<String, Vec<u8>> =
            [("a.csv", "new a"), ("b.csv", "new b"), ("figures/f2.png", "new f2"), ("notes.txt", "user")]
                .into_iter()
                .map(|(p, t)| (p.to_string(), t.as_bytes().to_vec()))
                .collect();
        assert_eq!(snapshot(&out), expected);
        assert_eq!(written, [out.join("a.csv"), out.join("b.csv"), out.join("figures/f2.png")]);
        assert_no_leftovers(root.path());
    }

    #[test]
    fn a_failure_after_some_outputs_leaves_the_previous_ones_byte_identical() {
        let root = tempfile::tempdir().unwrap();
        let out = previous(root.path());
        let before = snapshot(&out);
        let err = write_set(&out, owns, |dir| -> Result<()> {
            write(&dir.join("a.csv"), "new a")?;
            write(&dir.join("figures/f2.png"), "new f2")?;
            Err(SchemaError::Invalid { path: dir.join("b.csv"), message: "a figure failed".into() })
        })
        .unwrap_err();
        assert!(err.to_string().contains("a figure failed"), "{err}");
        assert_eq!(snapshot(&out), before);
        assert_no_leftovers(root.path());
    }

    #[test]
    fn a_failed_move_undoes_the_moves_already_made() {
        // every failure point of the commit (7 renames: 3 entries aside and in, 1 stale aside)
        for fail_at in 0..7 {
            let root = tempfile::tempdir().unwrap();
            let out = previous(root.path());
            let before = snapshot(&out);
            let set = Staging::begin(&out).unwrap();
            fill_new(&set.dir).unwrap();
            let mut calls = 0;
            let r = set.commit(&owns, &mut |from, to| {
                calls += 1;
                if calls > fail_at {
                    Err(std::io::Error::other("disk gone"))
                } else {
                    std::fs::rename(from, to)
                }
            });
            assert!(r.is_err(), "fail at {fail_at}");
            drop(set);
            assert_eq!(snapshot(&out), before, "fail at {fail_at}");
            assert_no_leftovers(root.path());
        }
    }

    #[test]
    fn leftovers_of_a_killed_process_are_removed_and_a_new_folder_is_made() {
        let root = tempfile::tempdir().unwrap();
        // pid_max is at most 2^22 on Linux: no process has this id
        let dead = root.path().join(".out.staging-99999999");
        write(&dead.join("a.csv"), "half").unwrap();
        let other = root.path().join(".other.staging-99999999");
        write(&other.join("x"), "not ours").unwrap();
        let out = root.path().join("out");
        write_set(&out, owns, fill_new).unwrap();
        assert!(!dead.exists());
        assert!(other.exists(), "another output folder's staging is not ours to remove");
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new a");
    }

    #[test]
    fn an_output_folder_whose_parent_is_not_writable_stages_inside_itself() {
        let root = tempfile::tempdir().unwrap();
        let out = previous(root.path());
        // the parent is "not writable" when the staging name is taken by a file
        let blocker = root.path().join(format!(".out.staging-{}", std::process::id()));
        std::fs::write(&blocker, "").unwrap();
        let ((), written) = write_set(&out, |n| n.starts_with('.') || owns(n), fill_new).unwrap();
        assert_eq!(written.len(), 3);
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new a");
        assert!(!out.join("extra_owned.csv").exists());
        let names = entry_names(&out).unwrap();
        assert_eq!(names, ["a.csv", "b.csv", "figures", "notes.txt"], "no staging folder left inside");
    }

    #[test]
    fn a_symlinked_output_folder_is_staged_beside_the_folder_it_points_to() {
        let root = tempfile::tempdir().unwrap();
        let out = previous(root.path());
        let elsewhere = root.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        let link = elsewhere.join("link");
        std::os::unix::fs::symlink(&out, &link).unwrap();
        let real_parent = root.path().canonicalize().unwrap();
        write_set(&link, owns, |dir| {
            assert_eq!(dir.parent(), Some(real_parent.as_path()), "staged beside the real folder");
            fill_new(dir)
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(out.join("a.csv")).unwrap(), "new a");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays a link");
        assert_eq!(entry_names(&elsewhere).unwrap(), ["link"]);
        assert_eq!(entry_names(root.path()).unwrap(), ["elsewhere", "out"]);
    }

    #[test]
    fn the_current_folder_can_be_the_output() {
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("out");
        std::fs::create_dir_all(out.join("sub")).unwrap();
        let dot = out.join("sub/..");
        assert!(dot.file_name().is_none());
        write_set(&dot, owns, fill_new).unwrap();
        assert_eq!(std::fs::read_to_string(out.join("b.csv")).unwrap(), "new b");
        assert!(out.join("sub").is_dir());
        assert_no_leftovers(root.path());
    }
}
