//! An error of a temporary file or a staging folder reported as its target's: the user asked for
//! the target (`atomic::write_via`, `output_set::write_set`), the temporary name is ours.

use std::path::{Path, PathBuf};

/// An error that can name `to` wherever it named `from` or a path under it (a staging folder's
/// or a temporary file's error reported as its output's).
pub trait Unstage {
    fn unstaged(self, from: &Path, to: &Path) -> Self;
}

/// `path` with its leading `from` replaced by `to` (unchanged when it does not start with `from`).
pub fn rebased(path: &Path, from: &Path, to: &Path) -> PathBuf {
    match path.strip_prefix(from) {
        Ok(rest) if rest.as_os_str().is_empty() => to.to_path_buf(),
        Ok(rest) => to.join(rest),
        Err(_) => path.to_path_buf(),
    }
}

/// `text` with every mention of `from` replaced by `to` (paths under `from` included).
pub fn renamed_in(text: &str, from: &Path, to: &Path) -> String {
    text.replace(&from.display().to_string(), &to.display().to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_path_is_rebased_only_under_the_folder_itself() {
        assert_eq!(rebased(Path::new("/a/b"), Path::new("/a/b"), Path::new("/c")), PathBuf::from("/c"));
        assert_eq!(rebased(Path::new("/a/b/f.png"), Path::new("/a/b"), Path::new("/c")), PathBuf::from("/c/f.png"));
        assert_eq!(rebased(Path::new("/a/bc"), Path::new("/a/b"), Path::new("/c")), PathBuf::from("/a/bc"));
        assert_eq!(renamed_in("cannot write /a/b/f.png", Path::new("/a/b"), Path::new("/c")), "cannot write /c/f.png");
    }
}
