//! Typed errors. Every scene error names its place: a JSON path with line
//! and column for parse errors, the JSON path and the block or object name
//! for semantic ones.

use std::path::PathBuf;

/// Why a scene file was rejected.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// The text is not valid JSON or does not match the format.
    #[error("{}line {line}, column {column}: {message}", path_prefix(path))]
    Parse {
        /// JSON path of the offending value, e.g. `blocks[1].objects[0]`.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// The JSON is well-formed but means nothing valid.
    #[error("{place}{}: {message}", position_suffix(position))]
    Semantic {
        /// JSON path (and block/object name in `message`).
        place: String,
        /// 1-based line and column of the value at `place` (or of its
        /// nearest enclosing value, when `place` is a member left out),
        /// when known.
        position: Option<(usize, usize)>,
        /// What is wrong.
        message: String,
    },
}

fn position_suffix(position: &Option<(usize, usize)>) -> String {
    position.map(|(l, c)| format!(", line {l}, column {c}")).unwrap_or_default()
}

fn path_prefix(path: &str) -> String {
    if path.is_empty() || path == "." {
        String::new()
    } else {
        format!("{path}, ")
    }
}

impl SceneError {
    /// A semantic error at `place`.
    pub fn semantic(place: &str, message: impl Into<String>) -> Self {
        SceneError::Semantic { place: place.to_string(), position: None, message: message.into() }
    }

    /// Prefixes the message of a semantic error with the owner (`block "x", object 2`).
    pub(crate) fn with_owner(self, owner: &str) -> Self {
        match self {
            SceneError::Semantic { place, position, message } => {
                SceneError::Semantic { place, position, message: format!("{owner}: {message}") }
            }
            other => other,
        }
    }

    /// Adds the line and column of a semantic error's place in `text`, or
    /// of its nearest enclosing value if the place is a member left out.
    pub(crate) fn located(self, text: &str) -> Self {
        match self {
            SceneError::Semantic { place, position: None, message } => {
                let position = crate::locate::locate(text, &place);
                SceneError::Semantic { place, position, message }
            }
            other => other,
        }
    }

    pub(crate) fn from_json(e: serde_path_to_error::Error<serde_json::Error>) -> Self {
        // serde_path_to_error writes `?` for a place it could not name
        // (inside a syntax error); the line and column still say where.
        let path = e.path().to_string();
        let path = abbreviated(path.trim_end_matches('?').trim_end_matches('.'));
        let inner = e.inner();
        let (line, column) = (inner.line(), inner.column());
        let raw = inner.to_string();
        // serde_json appends " at line L column C"; we print the place ourselves.
        let message = match raw.rfind(" at line ") {
            Some(i) => raw[..i].to_string(),
            None => raw,
        };
        let message = if message == "recursion limit exceeded" {
            "nested too deeply: at most 128 levels of brackets (about 60 nested groups) are supported".to_string()
        } else {
            message
        };
        let message = with_suggestion(message);
        SceneError::Parse { path, line, column, message }
    }
}

/// A JSON path short enough to read: a path more than 12 steps deep (only
/// deeply nested groups get there) keeps its first and last 4 steps.
fn abbreviated(path: &str) -> String {
    let steps: Vec<&str> = path.split('.').collect();
    if steps.len() <= 12 {
        return path.to_string();
    }
    let n = steps.len();
    format!("{}.(… {} more levels …).{}", steps[..4].join("."), n - 8, steps[n - 4..].join("."))
}

/// Adds "did you mean" to serde's unknown field/variant messages.
fn with_suggestion(message: String) -> String {
    let Some(rest) = message.strip_prefix("unknown field `").or_else(|| message.strip_prefix("unknown variant `"))
    else {
        return message;
    };
    let Some(end) = rest.find('`') else { return message };
    let given = &rest[..end];
    let expected = &rest[end..];
    let candidates: Vec<&str> = expected.split('`').skip(2).step_by(2).collect();
    match nearest(given, candidates.iter().copied()) {
        Some(n) => format!("{message} (did you mean `{n}`?)"),
        None => message,
    }
}

/// The candidate closest to `given` by edit distance, if it is close enough
/// to be a plausible typo.
pub fn nearest<'a>(given: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let given_lc = given.to_lowercase();
    candidates
        .map(|c| (levenshtein(&given_lc, &c.to_lowercase()), c))
        .filter(|(d, c)| {
            let len = c.chars().count().max(given.chars().count());
            *d < len && *d <= (len / 2).max(2)
        })
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

fn levenshtein(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = if ca == *cb { prev } else { 1 + prev.min(cur).min(row[j]) };
            prev = cur;
        }
    }
    row[b.len()]
}

/// Any failure of the library's top-level operations.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene is invalid.
    #[error("{file}: {source}", file = .file.display())]
    Scene {
        /// The scene file.
        file: PathBuf,
        /// What is wrong and where.
        source: SceneError,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// Encoding an image failed.
    #[error("{}: {message}", .path.display())]
    Encode {
        /// The file being written.
        path: PathBuf,
        /// The encoder's message.
        message: String,
    },
    /// Bad options (image size, thread count, ray).
    #[error("{0}")]
    Options(String),
    /// A data file other than the scene (the rays of `trace --rays`) is
    /// invalid.
    #[error("{}: {message}", .file.display())]
    Data {
        /// The file.
        file: PathBuf,
        /// What is wrong and where (line and column, or the ray).
        message: String,
    },
    /// The render was cancelled (Ctrl-C) before it finished.
    #[error("interrupted; no output was written")]
    Interrupted,
}

impl Error {
    /// Whether the error is the user's input (scene or options) rather than
    /// the environment (files, encoders).
    pub fn is_input_error(&self) -> bool {
        matches!(self, Error::Scene { .. } | Error::Options(_) | Error::Data { .. })
    }
}
