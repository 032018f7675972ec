//! The recently opened and saved scene files, newest first, kept between runs in the user's configuration
//! folder (`$XDG_CONFIG_HOME/energywave/recent.txt`, else `~/.config/energywave/recent.txt`), one path a line.

use std::path::{Path, PathBuf};

/// How many files the list keeps.
pub const RECENT_FILES: usize = 8;

/// The list, and where it is kept (nowhere for a viewer under test).
#[derive(Clone, Debug, Default)]
pub struct RecentFiles {
    files: Vec<PathBuf>,
    store: Option<PathBuf>,
}

impl RecentFiles {
    /// The list kept in `store` (empty if the file is missing or unreadable).
    pub fn load(store: PathBuf) -> Self {
        let files = std::fs::read_to_string(&store)
            .map(|t| {
                t.lines()
                    .filter(|l| !l.trim().is_empty())
                    .map(PathBuf::from)
                    .take(RECENT_FILES)
                    .collect()
            })
            .unwrap_or_default();
        Self {
            files,
            store: Some(store),
        }
    }

    /// The user's list: `$XDG_CONFIG_HOME/energywave/recent.txt`, else `$HOME/.config/...`; a list kept nowhere
    /// when neither is set.
    pub fn for_user() -> Self {
        let base = std::env::var_os("XDG_CONFIG_HOME")
            .filter(|v| !v.is_empty())
            .map(PathBuf::from)
            .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")));
        match base {
            Some(b) => Self::load(b.join("energywave").join("recent.txt")),
            None => Self::default(),
        }
    }

    /// The files, newest first.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// `path` to the front (once), the list cut to `RECENT_FILES`, and kept (a failure to keep it costs only
    /// the list).
    pub fn add(&mut self, path: &Path) {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        self.files.retain(|p| *p != path);
        self.files.insert(0, path);
        self.files.truncate(RECENT_FILES);
        if let Some(store) = &self.store {
            let text: String = self
                .files
                .iter()
                .map(|p| format!("{}\n", p.display()))
                .collect();
            if let Some(dir) = store.parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let _ = crate::output::write_atomically(store, text.as_bytes());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn newest_first_once_each_and_kept_between_runs() {
        let dir = std::env::temp_dir().join(format!("energywave-recent-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let store = dir.join("cfg/recent.txt");
        let mut r = RecentFiles::load(store.clone());
        assert!(r.files().is_empty());
        for k in 0..10 {
            r.add(&dir.join(format!("s{k}.toml")));
        }
        r.add(&dir.join("s5.toml"));
        let again = RecentFiles::load(store);
        assert_eq!(again.files().len(), RECENT_FILES);
        assert_eq!(again.files()[0], dir.join("s5.toml"));
        assert_eq!(again.files()[1], dir.join("s9.toml"));
        assert_eq!(
            again
                .files()
                .iter()
                .filter(|p| p.ends_with("s5.toml"))
                .count(),
            1
        );
    }
}
