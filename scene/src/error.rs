//! Scene errors: the file, the line and a message naming the key; byte offset to line.

use std::fmt;
use std::path::PathBuf;

/// A scene-file (or record-file) error: the file, the line (1-based) and a message naming the key.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    /// The file the error is in (as given, e.g. `scenes/x.toml`).
    pub file: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What is wrong, starting with the key (e.g. `[structure] damping_ratio = 1.2 is out of ...`).
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{}: {}", self.file.display(), line, self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

impl std::error::Error for SceneError {}

/// 1-based line of byte `offset` in `src`.
pub(crate) fn line_of(src: &str, offset: usize) -> usize {
    let end = offset.min(src.len());
    src.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}
