//! Errors of loading a scene: each names the file, the place (line and column where known) and the field.

use std::fmt;
use std::path::PathBuf;

/// One thing wrong in a scene file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// 1-based line and column of the offending key or value, where the parser knows them.
    pub location: Option<(usize, usize)>,
    /// The field's path, as `curves[1].control_points` or `camera.fov_y`; empty for a syntax error.
    pub field: String,
    /// What is wrong and what would be valid.
    pub message: String,
}

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The path could not be read (missing, unreadable, ...).
    #[error("{}: cannot read the scene file: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The path is a directory.
    #[error("{}: is a directory, not a scene file (a scene is a TOML file such as assets/scenes/torus_r0.9.toml)", path.display())]
    Directory { path: PathBuf },
    /// The bytes are not UTF-8 text.
    #[error("{}: not a text file (invalid UTF-8 at byte {offset}); a scene is a TOML text file", path.display())]
    NotText { path: PathBuf, offset: usize },
    /// Nothing but whitespace and comments.
    #[error("{}: the file is empty; a scene needs at least one source, for example:\n  [[points]]\n  position = [0.0, 0.0, 0.0]\n  coefficient = 1.0", path.display())]
    Empty { path: PathBuf },
    /// Syntax errors, wrong types, unknown keys, out-of-range values.
    #[error("{}", render_invalid(path, problems))]
    Invalid {
        path: PathBuf,
        problems: Vec<Problem>,
    },
}

impl SceneError {
    /// The problems of an `Invalid` error (empty for the others).
    pub fn problems(&self) -> &[Problem] {
        match self {
            SceneError::Invalid { problems, .. } => problems,
            _ => &[],
        }
    }
}

fn render_invalid(path: &std::path::Path, problems: &[Problem]) -> String {
    let mut out = String::new();
    for (i, p) in problems.iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        out.push_str(&p.to_string_with(path));
    }
    out
}

impl Problem {
    fn to_string_with(&self, path: &std::path::Path) -> String {
        let mut s = path.display().to_string();
        if let Some((line, column)) = self.location {
            s.push_str(&format!(":{line}:{column}"));
        }
        s.push_str(": ");
        if !self.field.is_empty() {
            s.push_str(&self.field);
            s.push_str(": ");
        }
        s.push_str(&self.message);
        s
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some((line, column)) = self.location {
            write!(f, "line {line}, column {column}: ")?;
        }
        if !self.field.is_empty() {
            write!(f, "{}: ", self.field)?;
        }
        f.write_str(&self.message)
    }
}
