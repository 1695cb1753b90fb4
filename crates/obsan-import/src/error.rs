use std::fmt;

/// A refusal of foreign text, at a 1-based line and column of it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImportError {
    pub line: usize,
    pub col: usize,
    pub message: String,
}

impl ImportError {
    pub(crate) fn at(line: usize, col: usize, message: impl Into<String>) -> ImportError {
        ImportError {
            line,
            col,
            message: message.into(),
        }
    }
}

/// `LINE:COL: MESSAGE`; the caller prefixes the file name.
impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}: {}", self.line, self.col, self.message)
    }
}

impl std::error::Error for ImportError {}
