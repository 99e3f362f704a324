//! Bounded echoes of user input in error messages: a value is cut at
//! [`MAX_ECHO_CHARS`] characters with an ellipsis, a list at [`MAX_ECHO_ITEMS`] items
//! with a count of the rest, and control characters are escaped, so that an error
//! stays one short line whatever a file or a flag holds.
//!
//! ```
//! use fathom_core::echo::{echo, echo_list};
//!
//! assert_eq!(echo("hull").to_string(), "hull");
//! let long = "x".repeat(100_000);
//! assert!(echo(&long).to_string().chars().count() < 120);
//! assert_eq!(echo("a\nb").to_string(), "a\\nb");
//! let ids: Vec<u32> = (0..200_000).collect();
//! assert!(echo_list(&ids).to_string().ends_with("... (199990 more)"));
//! ```

use std::fmt::{self, Display, Write};
use std::path::Path;

/// Characters of one echoed value shown before the ellipsis.
pub const MAX_ECHO_CHARS: usize = 80;

/// Items of an echoed list shown before the count of the rest.
pub const MAX_ECHO_ITEMS: usize = 10;

/// Characters shown of a message that may quote the input itself (a TOML, CSV or OBJ
/// parser's, a reason built around a value): longer than a value, still one line.
pub const MAX_MESSAGE_CHARS: usize = 400;

/// Characters shown of a file path: the start and, as it names the file, most of
/// the end, with `...` between.
pub const MAX_PATH_CHARS: usize = 160;

/// A user string as an error message shows it: see [`echo`].
#[derive(Debug, Clone, Copy)]
pub struct Echo<'a> {
    text: &'a str,
    max: usize,
    /// Characters shown of a span quoted in backticks (a parser quoting the input).
    quoted_max: usize,
}

/// `text` bounded for an error message: at most [`MAX_ECHO_CHARS`] characters, then
/// `...` and the total length; control characters (a newline, a tab) escaped.
pub fn echo(text: &str) -> Echo<'_> {
    Echo {
        text,
        max: MAX_ECHO_CHARS,
        quoted_max: usize::MAX,
    }
}

/// Characters of one printed error line before it is cut: the guard of a front end
/// over messages of crates that do not bound their echoes themselves.
pub const MAX_LINE_CHARS: usize = 1000;

/// Each line of `text` bounded at [`MAX_LINE_CHARS`], its backtick-quoted spans as
/// [`echo_message`] bounds them; line breaks are kept.
pub fn echo_lines(text: &str) -> String {
    text.lines()
        .map(|line| {
            Echo {
                text: line,
                max: MAX_LINE_CHARS,
                quoted_max: MAX_PATH_CHARS,
            }
            .to_string()
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// A message bounded at [`MAX_MESSAGE_CHARS`], each span it quotes in backticks (a
/// parser's echo of the input) at [`MAX_PATH_CHARS`] as [`echo_file`] bounds a path
/// (so that a value or path echoed already is left as it is).
pub fn echo_message(text: &str) -> Echo<'_> {
    Echo {
        text: text.trim_end(),
        max: MAX_MESSAGE_CHARS,
        quoted_max: MAX_PATH_CHARS,
    }
}

/// A path bounded as [`echo_file`] bounds a file label (lossy for non-UTF-8 names).
pub fn echo_path(path: &Path) -> String {
    echo_file(&path.to_string_lossy())
}

/// A file name or path as an error message shows it: at most [`MAX_PATH_CHARS`]
/// characters, the middle left out (`...`), control characters escaped.
pub fn echo_file(label: &str) -> String {
    let chars: Vec<char> = label.chars().collect();
    echo_whole(&cut_middle(&chars, MAX_PATH_CHARS))
}

/// `text` with its control characters escaped, not cut.
fn echo_whole(text: &str) -> String {
    Echo {
        text,
        max: usize::MAX,
        quoted_max: usize::MAX,
    }
    .to_string()
}

/// `chars` cut to `max` characters: the first quarter and the rest from the end, with
/// `...` between (the end of a path names its file).
fn cut_middle(chars: &[char], max: usize) -> String {
    if chars.len() <= max {
        return chars.iter().collect();
    }
    let head = max / 4;
    let tail = &chars[chars.len() - (max - head)..];
    chars[..head]
        .iter()
        .chain("...".chars().collect::<Vec<_>>().iter())
        .chain(tail)
        .collect()
}

impl Echo<'_> {
    /// The text with its quoted spans bounded (before the bound of the whole).
    fn spans_bounded(&self) -> String {
        if self.quoted_max == usize::MAX {
            return self.text.to_string();
        }
        // a message: its numbers written out in full shortened first
        let text = compact_numbers(self.text);
        let parts: Vec<&str> = text.split('`').collect();
        let last = parts.len() - 1;
        let mut out = String::new();
        for (i, part) in parts.iter().enumerate() {
            if i > 0 {
                out.push('`');
            }
            let chars: Vec<char> = part.chars().collect();
            let quoted = i % 2 == 1;
            if quoted && i < last {
                out.push_str(&cut_middle(&chars, self.quoted_max));
            } else if quoted && chars.len() > self.quoted_max {
                // An unclosed quote: its start.
                out.extend(&chars[..self.quoted_max]);
                out.push_str("...");
            } else {
                out.push_str(part);
            }
        }
        out
    }
}

impl Display for Echo<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = self.spans_bounded();
        for (shown, c) in text.chars().enumerate() {
            if shown == self.max {
                return write!(f, "... ({} characters)", self.text.chars().count());
            }
            if c.is_control() {
                for e in c.escape_default() {
                    f.write_char(e)?;
                }
            } else {
                f.write_char(c)?;
            }
        }
        Ok(())
    }
}

/// Digits of a number written out in full beyond which [`compact_numbers`] writes it
/// in scientific notation.
pub const MAX_NUMBER_CHARS: usize = 20;

/// `text` with every number written out in more than [`MAX_NUMBER_CHARS`] characters
/// with a run of zeros (Rust prints `1e300` as 301 digits and `1e-300` as 302) in
/// scientific notation
/// (`1e300`, `1e-300`, `5.2e294`): the same value, read back exactly, in a message a
/// person can read.
///
/// ```
/// use fathom_core::echo::compact_numbers;
///
/// let m = format!("rate {} Hz, step {} s, 0.25 m", 1e300, 1e-300);
/// assert_eq!(compact_numbers(&m), "rate 1e300 Hz, step 1e-300 s, 0.25 m");
/// ```
pub fn compact_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let number = &rest[start..];
        let len = number
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(number.len());
        // a sentence's full stop after a number is not part of it
        let digits = number[..len].trim_end_matches('.');
        let after = &number[digits.len()..];
        // (a long run of digits without zeros is an identifier, not a float written out)
        let written_out = digits.len() > MAX_NUMBER_CHARS && digits.contains("00000");
        match digits.parse::<f64>() {
            Ok(x) if written_out && x.is_finite() => {
                out.push_str(&format!("{x:e}"));
            }
            _ => out.push_str(digits),
        }
        rest = after;
    }
    out.push_str(rest);
    out
}

/// A list as an error message shows it: see [`echo_list`].
#[derive(Debug, Clone, Copy)]
pub struct EchoList<'a, T>(&'a [T]);

/// `items` joined by `, `, each bounded as by [`echo`]; after [`MAX_ECHO_ITEMS`]
/// items, `...` and the count of the rest.
pub fn echo_list<T: Display>(items: &[T]) -> EchoList<'_, T> {
    EchoList(items)
}

impl<T: Display> Display for EchoList<'_, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, item) in self.0.iter().take(MAX_ECHO_ITEMS).enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{}", echo(&item.to_string()))?;
        }
        if self.0.len() > MAX_ECHO_ITEMS {
            write!(f, ", ... ({} more)", self.0.len() - MAX_ECHO_ITEMS)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_written_in_scientific_notation() {
        let m = format!("a {} b {} c -{}.", 1e300, 1e-300, 123_456.5);
        assert_eq!(compact_numbers(&m), "a 1e300 b 1e-300 c -123456.5.");
        assert_eq!(compact_numbers("index 12, v1.2.3"), "index 12, v1.2.3");
        let derived = format!("{}", 5.2e294_f64);
        assert_eq!(compact_numbers(&derived), "5.2e294");
        // the negative control: a 20-character number is kept as it is
        let kept = "12345678901234567890";
        assert_eq!(compact_numbers(kept), kept);
        let id = "123456789123456789123456789";
        assert_eq!(compact_numbers(id), id);
    }

    #[test]
    fn short_values_are_unchanged() {
        assert_eq!(echo("").to_string(), "");
        let exact = "é".repeat(MAX_ECHO_CHARS);
        assert_eq!(echo(&exact).to_string(), exact);
        assert_eq!(echo_list(&["a", "b"]).to_string(), "a, b");
        assert_eq!(echo_path(Path::new("w/x.obj")), "w/x.obj");
    }

    #[test]
    fn long_paths_keep_their_start_and_file_name() {
        let path = format!("/tmp/{}/world.obj", "d".repeat(20_000));
        let shown = echo_file(&path);
        assert!(shown.starts_with("/tmp/ddd"), "{shown}");
        assert!(shown.ends_with("ddd/world.obj"), "{shown}");
        assert_eq!(shown.chars().count(), MAX_PATH_CHARS + 3);
    }

    #[test]
    fn long_values_are_cut_at_a_character_boundary() {
        let long = "é".repeat(MAX_ECHO_CHARS + 1);
        let shown = echo(&long).to_string();
        assert_eq!(
            shown,
            format!("{}... (81 characters)", "é".repeat(MAX_ECHO_CHARS))
        );
    }

    #[test]
    fn control_characters_are_escaped() {
        assert_eq!(echo("a\r\n\tb").to_string(), "a\\r\\n\\tb");
    }

    #[test]
    fn messages_keep_more_and_lose_trailing_space() {
        let m = format!("{}\n", "m".repeat(150));
        assert_eq!(echo_message(&m).to_string(), "m".repeat(150));
        let long = "m".repeat(5000);
        assert!(
            echo_message(&long)
                .to_string()
                .starts_with(&"m".repeat(MAX_MESSAGE_CHARS))
        );
        assert!(
            echo_message(&long)
                .to_string()
                .ends_with("... (5000 characters)")
        );
    }

    #[test]
    fn quoted_spans_of_messages_are_bounded_as_values() {
        let key = "k".repeat(1000);
        let m = format!("unknown field `{key}`, expected `name`");
        let shown = echo_message(&m).to_string();
        assert_eq!(
            shown,
            format!(
                "unknown field `{}...{}`, expected `name`",
                "k".repeat(MAX_PATH_CHARS / 4),
                "k".repeat(MAX_PATH_CHARS - MAX_PATH_CHARS / 4)
            )
        );
        // An unclosed quote is cut as well, and the message as a whole.
        let open = format!("bad `{}", "k".repeat(100_000));
        assert!(echo_message(&open).to_string().chars().count() < MAX_PATH_CHARS + 10);
        // A value echoed already is not cut again.
        let echoed = format!("got `{}`", echo(&key));
        assert_eq!(echo_message(&echoed).to_string(), echoed);
        // A plain value keeps its backticks as they are.
        assert_eq!(echo("a`b`c").to_string(), "a`b`c");
    }

    #[test]
    fn printed_lines_are_bounded_each() {
        let text = format!("cannot write `{}`\nsecond", "p".repeat(20_000));
        let shown = echo_lines(&text);
        assert_eq!(shown.lines().count(), 2);
        assert!(
            shown.lines().all(|l| l.len() <= MAX_LINE_CHARS + 30),
            "{shown}"
        );
        assert_eq!(echo_lines("a\nb"), "a\nb");
    }

    #[test]
    fn lists_and_their_items_are_bounded() {
        let items: Vec<String> = (0..1000)
            .map(|i| format!("{i}{}", "y".repeat(1000)))
            .collect();
        let shown = echo_list(&items).to_string();
        assert!(shown.len() < 1200, "{} bytes", shown.len());
        assert!(shown.ends_with(", ... (990 more)"), "{shown}");
        assert_eq!(shown.matches("(1001 characters)").count(), 10);
    }
}
