//! Errors with a place: file, line, column, and the offending line with a caret.

use obsan_expr::line_col;
use std::fmt;

/// A mistake in a system description or in what was asked of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelError {
    /// File name (or a flag such as `--set`) the error is about.
    pub origin: String,
    /// 1-based line and column, when the error has a place in the file.
    pub line: Option<usize>,
    pub col: Option<usize>,
    pub message: String,
    /// The source line and the length of the underlined part.
    snippet: Option<(String, usize)>,
}

impl ModelError {
    /// An error at byte range `start..end` of `src`.
    pub fn at(
        origin: &str,
        src: &str,
        start: usize,
        end: usize,
        message: impl Into<String>,
    ) -> ModelError {
        let (line, col) = line_col(src, start);
        let text = src.lines().nth(line - 1).unwrap_or("").to_string();
        let width = src[start.min(src.len())..end.clamp(start, src.len())]
            .split('\n')
            .next()
            .map_or(1, |s| s.chars().count().max(1));
        ModelError {
            origin: origin.into(),
            line: Some(line),
            col: Some(col),
            message: message.into(),
            snippet: Some((text, width)),
        }
    }

    /// An error without a place in a file (a flag, a whole-file problem).
    pub fn general(origin: &str, message: impl Into<String>) -> ModelError {
        ModelError {
            origin: origin.into(),
            line: None,
            col: None,
            message: message.into(),
            snippet: None,
        }
    }
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.col) {
            (Some(l), Some(c)) => write!(f, "{}:{l}:{c}: {}", self.origin, self.message)?,
            _ => write!(f, "{}: {}", self.origin, self.message)?,
        }
        if let (Some((text, width)), Some(l), Some(c)) = (&self.snippet, self.line, self.col) {
            let gutter = l.to_string().len();
            write!(
                f,
                "\n{:gutter$} |\n{l} | {text}\n{:gutter$} | {}{}",
                "",
                "",
                " ".repeat(c - 1),
                "^".repeat(*width)
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for ModelError {}
