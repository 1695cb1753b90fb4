//! Errors with a place: file, line, column, and the offending line with a caret.
//!
//! Places are byte offsets into the text read; lines and columns are counted
//! in characters, so a non-ASCII character before the place moves the column
//! by one. Offsets that are past the end or inside a character are clamped,
//! never trusted: building a message must not panic whatever offsets it is
//! given.

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
    /// The source line, the text before the caret (tabs kept, every other
    /// character a space, so the caret aligns under the character), and the
    /// length of the underlined part in characters.
    snippet: Option<Box<Snippet>>,
}

#[derive(Clone, Debug, PartialEq, Eq)]
struct Snippet {
    text: String,
    pad: String,
    width: usize,
}

/// The largest char boundary of `s` at or below `i`.
fn floor_boundary(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

/// The smallest char boundary of `s` at or above `i` (at most its length).
fn ceil_boundary(s: &str, i: usize) -> usize {
    let mut i = i.min(s.len());
    while !s.is_char_boundary(i) {
        i += 1;
    }
    i
}

/// 1-based line and column (in characters) of byte `offset` of `src`, with
/// the byte range of that line (without its line break).
fn locate(src: &str, offset: usize) -> (usize, usize, usize, usize) {
    let offset = floor_boundary(src, offset);
    let line_start = src[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = src[..line_start].matches('\n').count() + 1;
    let col = src[line_start..offset].chars().count() + 1;
    let line_end = src[offset..].find('\n').map_or(src.len(), |i| offset + i);
    (line, col, line_start, line_end)
}

impl ModelError {
    /// An error at byte range `start..end` of `src` (clamped to the text and
    /// to its characters).
    pub fn at(
        origin: &str,
        src: &str,
        start: usize,
        end: usize,
        message: impl Into<String>,
    ) -> ModelError {
        let (line, col, line_start, line_end) = locate(src, start);
        let start = floor_boundary(src, start);
        // An end inside a character takes the whole character.
        let end = ceil_boundary(src, end.max(start)).min(line_end);
        let raw = src[line_start..line_end].trim_end_matches('\r');
        let before = &src[line_start..start];
        let pad = before
            .chars()
            .map(|c| if c == '\t' { '\t' } else { ' ' })
            .collect();
        let width = src[start..end.max(start)].chars().count().max(1);
        ModelError {
            origin: origin.into(),
            line: Some(line),
            col: Some(col),
            message: message.into(),
            snippet: Some(Box::new(Snippet {
                text: raw.to_string(),
                pad,
                width,
            })),
        }
    }

    /// An error at a known line and column, without the line's text.
    pub(crate) fn placed(
        origin: &str,
        line: usize,
        col: usize,
        message: impl Into<String>,
    ) -> ModelError {
        ModelError {
            origin: origin.into(),
            line: Some(line),
            col: Some(col),
            message: message.into(),
            snippet: None,
        }
    }

    /// Its line and column (1, 1 without a place).
    pub(crate) fn place(&self) -> (usize, usize) {
        (self.line.unwrap_or(1), self.col.unwrap_or(1))
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
        if let (Some(s), Some(l)) = (&self.snippet, self.line) {
            let gutter = l.to_string().len();
            write!(
                f,
                "\n{:gutter$} |\n{l} | {}\n{:gutter$} | {}{}",
                "",
                s.text,
                "",
                s.pad,
                "^".repeat(s.width)
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for ModelError {}

/// The text of a file as the readers want it: a leading UTF-8 byte-order
/// mark dropped, and CRLF and CR-only line ends read as `\n` (a CR-only file
/// is not one long line). Lines and columns of the result are those of the
/// original text.
pub fn normalize_text(src: &str) -> std::borrow::Cow<'_, str> {
    let s = src.strip_prefix('\u{feff}').unwrap_or(src);
    if s.contains('\r') {
        std::borrow::Cow::Owned(s.replace("\r\n", "\n").replace('\r', "\n"))
    } else {
        std::borrow::Cow::Borrowed(s)
    }
}

/// Decode a file's bytes as UTF-8 text for [`crate::System::parse`] and
/// [`crate::EffectLibrary::parse`], normalized as [`normalize_text`] does.
/// Invalid UTF-8 is an error at the line and column (in characters) of the
/// first bad byte; `origin` names the file.
pub fn decode_text(bytes: &[u8], origin: &str) -> Result<String, ModelError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) => Ok(normalize_text(s).into_owned()),
        Err(e) => {
            let at = e.valid_up_to();
            // Lossy decoding keeps the valid prefix as it is and turns the
            // bad byte into U+FFFD: the caret lands under it.
            let good = normalize_text(&String::from_utf8_lossy(&bytes[..at])).len();
            let full = String::from_utf8_lossy(bytes);
            let full = normalize_text(&full);
            let byte = bytes.get(at).copied().unwrap_or(0);
            Err(ModelError::at(
                origin,
                &full,
                good,
                good + 1,
                format!(
                    "invalid UTF-8 (byte 0x{byte:02X}): the file must be UTF-8 text \
                     (re-save it as UTF-8)"
                ),
            ))
        }
    }
}
