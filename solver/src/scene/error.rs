//! Scene errors that name the file, line and column, and what was expected.

use std::fmt;
use std::ops::Range;

/// A problem in a scene file, located at a line and column (1-based).
///
/// Displays as `file:line:column: message`, followed by the offending source
/// line with a caret, e.g.
///
/// ```text
/// scenes/four-bar.toml:12:9: joint `j3` names unknown body `cranck` (bodies: ground, crank)
///    12 | bodies = ["ground", "cranck"]
///       |         ^
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SceneError {
    /// The file as the user named it (or `scenes/<name>.toml` for built-ins).
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    /// What is wrong and what was expected.
    pub message: String,
    /// The source line the error points into (without its newline).
    pub source_line: String,
}

impl SceneError {
    /// An error at byte offset `span.start` of `text` (clamped into the text).
    pub fn at(file: &str, text: &str, span: Range<usize>, message: impl Into<String>) -> Self {
        let offset = span.start.min(text.len());
        let before = &text[..floor_char_boundary(text, offset)];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        let source_line = text[line_start..].lines().next().unwrap_or("").to_string();
        SceneError {
            file: file.to_string(),
            line,
            column,
            message: message.into(),
            source_line,
        }
    }

    /// An error about the file as a whole (it could not be read), at 1:1.
    pub fn whole_file(file: &str, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            line: 1,
            column: 1,
            message: message.into(),
            source_line: String::new(),
        }
    }
}

fn floor_char_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.column, self.message
        )?;
        if !self.source_line.is_empty() {
            let gutter = self.line.to_string().len();
            write!(
                f,
                "\n {:>gutter$} | {}\n {:>gutter$} | {:>col$}",
                self.line,
                self.source_line,
                "",
                "^",
                col = self.column
            )?;
        }
        Ok(())
    }
}

impl std::error::Error for SceneError {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_line_and_column_from_a_byte_offset() {
        let text = "[scene]\nname = \"x\"\n[[body]]\nnamé = 1\n";
        let at = text.find("= 1").unwrap();
        let e = SceneError::at("s.toml", text, at..at + 1, "bad");
        assert_eq!((e.line, e.column), (4, 6));
        assert_eq!(e.source_line, "namé = 1");
        let shown = e.to_string();
        assert!(
            shown.starts_with("s.toml:4:6: bad\n 4 | namé = 1\n   |      ^"),
            "{shown}"
        );
    }

    #[test]
    fn offsets_past_the_end_clamp() {
        let e = SceneError::at("s.toml", "a = 1", 99..100, "eof");
        assert_eq!((e.line, e.column), (1, 6));
    }
}
