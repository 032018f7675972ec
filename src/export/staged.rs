//! Files of an export written into a folder of their own beside their destination and moved into place only
//! once every one is whole, so that an export that is cancelled or fails leaves the destination exactly as it
//! found it: an earlier export of the same names keeps every file, none overwritten and none removed.

use std::path::{Path, PathBuf};

use crate::output::OutputError;

/// A staging folder beside the destination and the files staged in it, each with where it goes. Dropped
/// without `commit` (a failure on the way, a panic), it removes its folder: nothing is left behind.
pub struct Staged {
    dir: PathBuf,
    files: Vec<(PathBuf, PathBuf)>,
}

impl Staged {
    /// A new, empty staging folder in `destination`'s folder (hidden, named for this process and moment, so that
    /// two exports never share one), on the destination's file system so that moving a file in is a rename.
    pub fn beside(destination: &Path) -> Result<Staged, OutputError> {
        let parent = crate::output::parent_dir(destination);
        let stamp = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        let dir = parent.join(format!(
            ".energywave-export-{}-{stamp}.partial",
            std::process::id()
        ));
        std::fs::create_dir(&dir).map_err(|source| OutputError::Io {
            path: dir.clone(),
            source,
        })?;
        Ok(Staged {
            dir,
            files: Vec::new(),
        })
    }

    /// Where to write the file bound for `destination`; it is moved there by `commit`.
    pub fn stage(&mut self, destination: &Path) -> PathBuf {
        let name = destination.file_name().unwrap_or_default();
        let staged = self.dir.join(name);
        self.files.push((staged.clone(), destination.to_owned()));
        staged
    }

    /// Moves every staged file to its destination, returning the destinations. Each file the move replaces is
    /// set aside first; should a move fail, the files already moved go back and those set aside are restored,
    /// and the staging folder is removed, so that a failure leaves the destination as it was.
    pub fn commit(mut self) -> Result<Vec<PathBuf>, OutputError> {
        let files = std::mem::take(&mut self.files);
        let aside = self.dir.join("replaced");
        let mut done: Vec<(&Path, &Path, Option<PathBuf>)> = Vec::new();
        let mut result = Ok(());
        for (k, (staged, destination)) in files.iter().enumerate() {
            let io = |source| OutputError::Io {
                path: destination.clone(),
                source,
            };
            if destination.is_dir() {
                result = Err(io(std::io::Error::new(
                    std::io::ErrorKind::IsADirectory,
                    "a folder stands where the file goes",
                )));
                break;
            }
            let kept = if destination.exists() {
                if let Err(e) = std::fs::create_dir_all(&aside) {
                    result = Err(io(e));
                    break;
                }
                let to = aside.join(format!("{k}"));
                if let Err(e) = std::fs::rename(destination, &to) {
                    result = Err(io(e));
                    break;
                }
                Some(to)
            } else {
                None
            };
            if let Err(e) = std::fs::rename(staged, destination) {
                if let Some(to) = &kept {
                    let _ = std::fs::rename(to, destination);
                }
                result = Err(io(e));
                break;
            }
            done.push((staged, destination, kept));
        }
        if result.is_err() {
            for (staged, destination, kept) in done.into_iter().rev() {
                let _ = std::fs::rename(destination, staged);
                if let Some(to) = kept {
                    let _ = std::fs::rename(to, destination);
                }
            }
        }
        // The staging folder (with what was set aside) goes when `self` is dropped.
        result.map(|()| files.into_iter().map(|(_, d)| d).collect())
    }

    /// Removes the staging folder and what it holds; the destination is untouched.
    pub fn discard(self) {}
}

impl Drop for Staged {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[cfg(test)]
mod tests {
    use super::Staged;

    fn folder(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("energywave-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn listing(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
        let mut out: Vec<_> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| {
                let p = e.unwrap().path();
                let bytes = std::fs::read(&p).unwrap_or_default();
                (p.file_name().unwrap().to_string_lossy().into_owned(), bytes)
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn a_commit_replaces_and_adds_and_a_discard_leaves_the_folder_as_it_was() {
        let dir = folder("staged");
        std::fs::write(dir.join("a.txt"), b"old a").unwrap();
        std::fs::write(dir.join("keep.txt"), b"untouched").unwrap();
        let before = listing(&dir);
        let mut staged = Staged::beside(&dir.join("a.txt")).unwrap();
        std::fs::write(staged.stage(&dir.join("a.txt")), b"new a").unwrap();
        std::fs::write(staged.stage(&dir.join("b.txt")), b"new b").unwrap();
        staged.discard();
        assert_eq!(listing(&dir), before, "a discard changes nothing");
        let mut staged = Staged::beside(&dir.join("a.txt")).unwrap();
        std::fs::write(staged.stage(&dir.join("a.txt")), b"new a").unwrap();
        std::fs::write(staged.stage(&dir.join("b.txt")), b"new b").unwrap();
        let moved = staged.commit().unwrap();
        assert_eq!(moved, vec![dir.join("a.txt"), dir.join("b.txt")]);
        assert_eq!(
            listing(&dir),
            vec![
                ("a.txt".into(), b"new a".to_vec()),
                ("b.txt".into(), b"new b".to_vec()),
                ("keep.txt".into(), b"untouched".to_vec()),
            ]
        );
    }

    #[test]
    fn a_commit_that_fails_midway_puts_everything_back() {
        let dir = folder("staged-fail");
        std::fs::write(dir.join("a.txt"), b"old a").unwrap();
        std::fs::write(dir.join("b.txt"), b"old b").unwrap();
        let before = listing(&dir);
        let mut staged = Staged::beside(&dir.join("a.txt")).unwrap();
        std::fs::write(staged.stage(&dir.join("a.txt")), b"new a").unwrap();
        std::fs::write(staged.stage(&dir.join("c.txt")), b"new c").unwrap();
        // The third file never written (a disk that filled up): its move fails after two have moved.
        staged.stage(&dir.join("b.txt"));
        assert!(staged.commit().is_err());
        assert_eq!(
            listing(&dir),
            before,
            "the old a and b are back, c is gone, nothing staged is left"
        );
        // A folder where a file goes is refused, and nothing moves.
        std::fs::create_dir(dir.join("d.txt")).unwrap();
        let before = listing(&dir);
        let mut staged = Staged::beside(&dir.join("a.txt")).unwrap();
        std::fs::write(staged.stage(&dir.join("a.txt")), b"new a").unwrap();
        std::fs::write(staged.stage(&dir.join("d.txt")), b"new d").unwrap();
        assert!(staged.commit().is_err());
        assert_eq!(listing(&dir), before);
    }
}
