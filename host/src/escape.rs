//! Class names written into other text: a terminal or an SVG file ([`visible`]) and a
//! C comment ([`c_comment`]). CSV and JSON are written through the `csv` crate and
//! `serde_json`, which quote and escape for their own languages.
//!
//! A table built now holds only printable names (DESIGN §6.15), but a table file of an
//! older format version may hold any UTF-8, control characters included; these
//! functions make such a name harmless and visible wherever it is written.

use std::borrow::Cow;
use std::fmt::Write as _;

use mlmap_core::refused_char;

/// `name` with every character the name rule refuses
/// ([`refused_char`]: control, invisible and bidirectional
/// formatting characters, separators other than the space, private-use characters and
/// noncharacters) written as a Rust escape: `\n`, `\r`, `\t`, `\0`, or `\u{..}` with
/// the code point in hexadecimal. When anything is escaped, a backslash of the name is
/// written `\\`, so the escapes can be told from the name's own text. A name that
/// passes the rule is returned unchanged.
///
/// # Examples
///
/// ```
/// use mlmap_host::escape::visible;
/// assert_eq!(visible("traffic light"), "traffic light");
/// assert_eq!(visible("a\nb\u{1b}[2J"), "a\\nb\\u{1b}[2J");
/// assert_eq!(visible("x\\y\u{202e}"), "x\\\\y\\u{202e}");
/// ```
pub fn visible(name: &str) -> Cow<'_, str> {
    if !name.chars().any(|c| refused_char(c).is_some()) {
        return Cow::Borrowed(name);
    }
    let mut out = String::with_capacity(name.len() + 16);
    for c in name.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\0' => out.push_str("\\0"),
            c if refused_char(c).is_some() => {
                // Writing to a String cannot fail.
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// `text` for the inside of a C block comment (`/* ... */`), in printable ASCII: the
/// characters that could end the comment, open a nested one, form a trigraph or a
/// line splice (`*`, `/`, `?`, `\`), and every character outside printable ASCII are
/// written as escapes the reader can decode: `\xHH` for ASCII, `\uXXXX` or
/// `\UXXXXXXXX` (C's universal character names) for the others. No byte of the result
/// can change what the compiler reads around the comment.
///
/// # Examples
///
/// ```
/// use mlmap_host::escape::c_comment;
/// assert_eq!(c_comment("pedestrian"), "pedestrian");
/// assert_eq!(c_comment("*/ int pwn; /*"), "\\x2a\\x2f int pwn; \\x2f\\x2a");
/// assert_eq!(c_comment("vélo??/"), "v\\u00e9lo\\x3f\\x3f\\x2f");
/// ```
pub fn c_comment(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 16);
    for c in text.chars() {
        let u = u32::from(c);
        // Writing to a String cannot fail.
        let _ = match c {
            '*' | '/' | '?' | '\\' => write!(out, "\\x{u:02x}"),
            ' '..='~' => {
                out.push(c);
                Ok(())
            }
            _ if u < 0x80 => write!(out, "\\x{u:02x}"),
            _ if u <= 0xFFFF => write!(out, "\\u{u:04x}"),
            _ => write!(out, "\\U{u:08x}"),
        };
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn visible_escapes_what_the_rule_refuses() {
        assert!(matches!(visible("Fußgänger"), Cow::Borrowed("Fußgänger")));
        assert_eq!(visible("a\\b"), "a\\b");
        assert_eq!(visible("\0\t\r\n"), "\\0\\t\\r\\n");
        assert_eq!(visible("\u{7f}\u{85}\u{a0}"), "\\u{7f}\\u{85}\\u{a0}");
        assert_eq!(visible("\u{2028}\u{feff}"), "\\u{2028}\\u{feff}");
        assert_eq!(visible("\u{e000}\u{fffe}"), "\\u{e000}\\u{fffe}");
        // Nothing refused remains.
        let hostile = "\u{1b}]0;x\u{7}\u{202e}\u{2066}\u{200b}\n";
        assert!(!visible(hostile).chars().any(|c| refused_char(c).is_some()));
    }

    #[test]
    fn c_comment_is_printable_ascii_without_comment_or_trigraph_syntax() {
        let hostile = "*/ int pwn = 1; /* ??/\n\\\u{0}é中😀";
        let out = c_comment(hostile);
        assert!(out.chars().all(|c| (' '..='~').contains(&c)), "{out}");
        for bad in ["*/", "/*", "//", "??", "*", "/", "?"] {
            assert!(!out.contains(bad), "{out}");
        }
        assert_eq!(
            out,
            "\\x2a\\x2f int pwn = 1; \\x2f\\x2a \\x3f\\x3f\\x2f\\x0a\\x5c\\x00\\u00e9\\u4e2d\\U0001f600"
        );
    }
}
