//! Scene errors that name the file, line and column, and what was expected.

use std::fmt;
use std::ops::Range;

/// A problem in a scene file, located at a line and column (1-based; 0 for
/// the file as a whole).
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
    /// 1-based line (0: the file as a whole).
    pub line: usize,
    /// 1-based column, in characters (0: the file as a whole).
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

    /// An error about the file as a whole (it could not be read, it is too
    /// large, there is no such file): line and column 0, shown as
    /// `file: message` without a position.
    pub fn whole_file(file: &str, message: impl Into<String>) -> Self {
        SceneError {
            file: file.to_string(),
            line: 0,
            column: 0,
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

/// Characters of the source line shown before the error's column, at most.
const EXCERPT_BEFORE: usize = 40;
/// Characters of the source line shown in all, at most.
const EXCERPT_WIDTH: usize = 100;

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            return write!(
                f,
                "{}: {}",
                escape_controls(&self.file),
                escape_controls(&self.message)
            );
        }
        write!(
            f,
            "{}:{}:{}: {}",
            escape_controls(&self.file),
            self.line,
            self.column,
            escape_controls(&self.message)
        )?;
        if !self.source_line.is_empty() {
            let gutter = self.line.to_string().len();
            let (excerpt, caret) = excerpt(&self.source_line, self.column);
            write!(
                f,
                "\n {:>gutter$} | {excerpt}\n {:>gutter$} | {}^",
                self.line,
                "",
                " ".repeat(caret - 1)
            )?;
        }
        Ok(())
    }
}

/// Text from a scene file made safe to print: control characters (ANSI
/// escapes, NUL, …) are written as `\u{…}` escapes, never sent raw to a
/// terminal.
pub fn escape_controls(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() && c != '\n' {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    out
}

/// The part of `line` around 1-based character `column`, at most
/// [`EXCERPT_WIDTH`] characters with `…` where it was clipped and control
/// characters shown as `�` (one column each, so the caret stays aligned),
/// and the caret's 1-based column in the excerpt.
fn excerpt(line: &str, column: usize) -> (String, usize) {
    let n = line.chars().count();
    let column = column.clamp(1, n + 1);
    let start = column.saturating_sub(EXCERPT_BEFORE + 1);
    let end = (start + EXCERPT_WIDTH).min(n);
    let mut out = String::new();
    let mut caret = column - start;
    if start > 0 {
        out.push('…');
        caret += 1;
    }
    for c in line.chars().skip(start).take(end - start) {
        out.push(if c.is_control() { '\u{fffd}' } else { c });
    }
    if end < n {
        out.push('…');
    }
    (out, caret)
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
    fn long_lines_print_a_clipped_excerpt_with_the_caret_on_the_column() {
        // Column 70 001: the old printer panicked (width argument out of range).
        let mut text = "x = [".to_string();
        text.push_str(&"1, ".repeat(23_332));
        let at = text.len();
        text.push_str("oops]\n");
        let e = SceneError::at("s.toml", &text, at..at + 1, "not a number");
        assert_eq!(e.column, at + 1);
        let shown = e.to_string();
        let lines: Vec<&str> = shown.lines().collect();
        assert_eq!(lines[0], format!("s.toml:1:{}: not a number", at + 1));
        let code = lines[1].split_once(" | ").unwrap().1;
        let caret = lines[2].split_once(" | ").unwrap().1;
        assert!(code.chars().count() <= EXCERPT_WIDTH + 2, "{code}");
        assert!(code.starts_with('…') && code.contains("oops]"), "{code}");
        // The caret sits under the `o` of `oops`.
        let under = code.chars().nth(caret.chars().count() - 1).unwrap();
        assert_eq!(under, 'o', "{code}\n{caret}");
    }

    #[test]
    fn control_characters_are_never_printed_raw() {
        let text = "name = \"\u{1b}[31mred\u{0}\"\n";
        let e = SceneError::at(
            "s\u{7}.toml",
            text,
            0..1,
            "unknown body `\u{1b}[31mred\u{0}`",
        );
        let shown = e.to_string();
        assert!(
            !shown.chars().any(|c| c.is_control() && c != '\n'),
            "{shown:?}"
        );
        assert!(shown.contains("\\u{1b}[31mred\\u{0}"), "{shown}");
        assert!(shown.starts_with("s\\u{7}.toml:1:1:"), "{shown}");
    }

    #[test]
    fn whole_file_errors_have_no_position() {
        let e = SceneError::whole_file("nosuchscene", "no such file");
        assert_eq!(e.to_string(), "nosuchscene: no such file");
    }

    #[test]
    fn offsets_past_the_end_clamp() {
        let e = SceneError::at("s.toml", "a = 1", 99..100, "eof");
        assert_eq!((e.line, e.column), (1, 6));
    }
}
