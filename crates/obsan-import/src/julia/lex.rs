//! Julia tokens: enough of the lexer to find models and read their text.

use crate::ImportError;

#[derive(Clone, Debug, PartialEq)]
pub(super) enum Tok {
    Ident(String),
    Num(String),
    Str(String),
    /// Operators and punctuation, multi-character ones (`=>`, `//`) whole.
    Punct(String),
    /// Any other character (non-ASCII letters): an error only inside a model.
    Other(char),
}

#[derive(Clone, Debug)]
pub(super) struct Token {
    pub(super) tok: Tok,
    pub(super) line: usize,
    pub(super) col: usize,
    /// Whitespace or a comment precedes it.
    pub(super) spaced: bool,
}

pub(super) fn err(t: &Token, msg: impl Into<String>) -> ImportError {
    ImportError::at(t.line, t.col, msg)
}

/// Split Julia text into tokens; comments (`#`, nested `#= =#`) dropped.
pub(super) fn tokenize(text: &str) -> Result<Vec<Token>, ImportError> {
    let chars: Vec<char> = text.chars().collect();
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    let mut out = Vec::new();
    let mut spaced = true;
    // Advance over chars[i..j], keeping line and column.
    let step = |i: &mut usize, line: &mut usize, col: &mut usize, j: usize| {
        while *i < j {
            if chars[*i] == '\n' {
                *line += 1;
                *col = 1;
            } else {
                *col += 1;
            }
            *i += 1;
        }
    };
    while i < chars.len() {
        let c = chars[i];
        let (l0, c0) = (line, col);
        if c.is_whitespace() {
            let next = i + 1;
            step(&mut i, &mut line, &mut col, next);
            spaced = true;
            continue;
        }
        if c == '#' {
            if chars.get(i + 1) == Some(&'=') {
                let mut depth = 0usize;
                let mut j = i;
                loop {
                    if j >= chars.len() {
                        return Err(ImportError::at(l0, c0, "unterminated '#=' comment"));
                    }
                    if chars[j] == '#' && chars.get(j + 1) == Some(&'=') {
                        depth += 1;
                        j += 2;
                    } else if chars[j] == '=' && chars.get(j + 1) == Some(&'#') {
                        depth -= 1;
                        j += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        j += 1;
                    }
                }
                step(&mut i, &mut line, &mut col, j);
            } else {
                let mut j = i;
                while j < chars.len() && chars[j] != '\n' {
                    j += 1;
                }
                step(&mut i, &mut line, &mut col, j);
            }
            spaced = true;
            continue;
        }
        let mut j = i + 1;
        let tok = if c.is_ascii_alphabetic() || c == '_' {
            while j < chars.len() && (chars[j].is_ascii_alphanumeric() || chars[j] == '_') {
                j += 1;
            }
            // Julia names may go on with `!` or Unicode letters: keep them in
            // the token so that the name is refused whole, not misread.
            while j < chars.len()
                && (chars[j] == '!' && chars.get(j + 1) != Some(&'=')
                    || !chars[j].is_ascii() && chars[j].is_alphanumeric())
            {
                j += 1;
            }
            Tok::Ident(chars[i..j].iter().collect())
        } else if c.is_ascii_digit()
            || (c == '.' && chars.get(i + 1).is_some_and(char::is_ascii_digit))
        {
            j = i;
            while j < chars.len() && chars[j].is_ascii_digit() {
                j += 1;
            }
            if chars.get(j) == Some(&'.') && chars.get(j + 1).is_none_or(|d| d.is_ascii_digit()) {
                j += 1;
                while j < chars.len() && chars[j].is_ascii_digit() {
                    j += 1;
                }
            }
            if matches!(chars.get(j), Some('e' | 'E')) {
                let mut k = j + 1;
                if matches!(chars.get(k), Some('+' | '-')) {
                    k += 1;
                }
                if chars.get(k).is_some_and(char::is_ascii_digit) {
                    while k < chars.len() && chars[k].is_ascii_digit() {
                        k += 1;
                    }
                    j = k;
                }
            }
            Tok::Num(chars[i..j].iter().collect())
        } else if c == '"' {
            let mut s = String::new();
            loop {
                match chars.get(j) {
                    None => return Err(ImportError::at(l0, c0, "unterminated string")),
                    Some('"') => {
                        j += 1;
                        break;
                    }
                    Some('\\') => {
                        if let Some(&e) = chars.get(j + 1) {
                            s.push(e);
                        }
                        j += 2;
                    }
                    Some(&x) => {
                        s.push(x);
                        j += 1;
                    }
                }
            }
            j = j.min(chars.len());
            Tok::Str(s)
        } else if c.is_ascii_punctuation() {
            let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
            if ["=>", "//", "==", "!=", "<=", ">=", "&&", "||", "::"].contains(&two.as_str()) {
                j = i + 2;
                Tok::Punct(two)
            } else {
                Tok::Punct(c.to_string())
            }
        } else {
            Tok::Other(c)
        };
        out.push(Token {
            tok,
            line: l0,
            col: c0,
            spaced,
        });
        step(&mut i, &mut line, &mut col, j);
        spaced = false;
    }
    Ok(out)
}

pub(super) fn is_punct(t: Option<&Token>, p: &str) -> bool {
    matches!(t, Some(Token { tok: Tok::Punct(q), .. }) if q == p)
}

pub(super) fn ident(t: Option<&Token>) -> Option<&str> {
    match t {
        Some(Token {
            tok: Tok::Ident(s), ..
        }) => Some(s.as_str()),
        _ => None,
    }
}

/// Index of the `)` (or `]`) closing the bracket at `open`.
pub(super) fn closing(toks: &[Token], open: usize) -> Result<usize, ImportError> {
    let mut depth = 0usize;
    for (k, t) in toks.iter().enumerate().skip(open) {
        if let Tok::Punct(p) = &t.tok {
            match p.as_str() {
                "(" | "[" | "{" => depth += 1,
                ")" | "]" | "}" => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        return Ok(k);
                    }
                }
                _ => {}
            }
        }
    }
    Err(err(&toks[open], "this bracket is never closed"))
}

/// Top-level items (depth 0) of the bracket `open..close`, split at commas.
pub(super) fn items(toks: &[Token], open: usize, close: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let (mut depth, mut start) = (0usize, open + 1);
    for (k, t) in toks.iter().enumerate().take(close).skip(open + 1) {
        if let Tok::Punct(p) = &t.tok {
            match p.as_str() {
                "(" | "[" | "{" => depth += 1,
                ")" | "]" | "}" => depth = depth.saturating_sub(1),
                "," if depth == 0 => {
                    out.push((start, k));
                    start = k + 1;
                }
                _ => {}
            }
        }
    }
    if start < close {
        out.push((start, close));
    }
    out
}
