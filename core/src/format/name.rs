//! Class names stored inline, so a table needs no allocation and can be a `const`, and
//! the one rule every class name of a new table obeys (DESIGN §6.15):
//! [`check_class_name`] for one name, [`check_class_names`] for a table's list.

use core::fmt;

/// Longest class name a table stores, in UTF-8 bytes.
pub const NAME_MAX: usize = 31;

/// The first table format version whose decoder enforces the whole name rule
/// ([`check_class_name`]). Tables of older versions only need names of 1 to
/// [`NAME_MAX`] bytes other than `background`, unique (they keep decoding as written).
pub const NAME_RULE_VERSION: u16 = 3;

/// The label of rows without an object, which no class may take.
const RESERVED: &str = "background";

/// What kind of character a name may not hold (DESIGN §6.15).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CharKind {
    /// A control character: C0 (U+0000 to U+001F), DEL (U+007F) or C1 (U+0080 to
    /// U+009F), e.g. NUL, ESC, tab, CR or LF.
    Control,
    /// A character that is not drawn: a format character (Unicode category Cf: the
    /// bidirectional controls U+202A to U+202E and U+2066 to U+2069, the zero-width
    /// characters U+200B to U+200D, U+FEFF, the soft hyphen, the tags) or any other
    /// default-ignorable code point (variation selectors, Hangul fillers, ...).
    Invisible,
    /// White space other than U+0020 SPACE: no-break and wide spaces, the line and
    /// paragraph separators U+2028 and U+2029.
    Separator,
    /// A private-use code point (no standard glyph).
    PrivateUse,
    /// A noncharacter (U+FDD0 to U+FDEF, and the last two code points of every plane).
    Noncharacter,
}

impl CharKind {
    /// The words naming the kind, shared by `Display` and `defmt`.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Control => "a control character",
            Self::Invisible => "an invisible or bidirectional formatting character",
            Self::Separator => "a separator other than the space",
            Self::PrivateUse => "a private-use character",
            Self::Noncharacter => "a noncharacter",
        }
    }
}

impl fmt::Display for CharKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.message())
    }
}

/// Which rule of DESIGN §6.15 a class name breaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum NameError {
    /// The name is empty.
    Empty,
    /// The name is longer than [`NAME_MAX`] bytes.
    TooLong,
    /// The name is `background`, the label of rows without an object.
    Reserved,
    /// The name holds a character it may not hold.
    Char {
        /// The character.
        ch: char,
        /// Its byte offset in the name (below [`NAME_MAX`]).
        at: u8,
        /// Why it is refused.
        kind: CharKind,
    },
    /// The name starts or ends with a space.
    Padded,
    /// The name repeats the name of an earlier class (only from
    /// [`check_class_names`]).
    Repeated {
        /// Index of the earlier class.
        first: u16,
    },
}

impl NameError {
    /// The one sentence describing the variant, without its fields (`TooLong` quotes
    /// [`NAME_MAX`], checked by a test).
    pub const fn message(self) -> &'static str {
        match self {
            Self::Empty => "the name is empty",
            Self::TooLong => "the name is longer than 31 bytes",
            Self::Reserved => "`background` is reserved (the label of rows without an object)",
            Self::Char { .. } => "the name holds a character it may not hold",
            Self::Padded => "the name starts or ends with a space",
            Self::Repeated { .. } => "the name repeats the name of an earlier class",
        }
    }
}

impl fmt::Display for NameError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Empty | Self::TooLong | Self::Reserved | Self::Padded => {
                f.write_str(self.message())
            }
            Self::Char { ch, at, kind } => write!(
                f,
                "the name holds {kind}, U+{:04X}, at byte {at}",
                u32::from(ch)
            ),
            Self::Repeated { first } => {
                write!(f, "the name repeats the name of class {first}")
            }
        }
    }
}

impl core::error::Error for NameError {}

/// Code points that are not drawn: Unicode's format characters (category Cf) and the
/// other default-ignorable code points (Unicode 15.1), as inclusive ranges, sorted.
const INVISIBLE: &[(u32, u32)] = &[
    (0x00AD, 0x00AD),
    (0x034F, 0x034F),
    (0x0600, 0x0605),
    (0x061C, 0x061C),
    (0x06DD, 0x06DD),
    (0x070F, 0x070F),
    (0x0890, 0x0891),
    (0x08E2, 0x08E2),
    (0x115F, 0x1160),
    (0x17B4, 0x17B5),
    (0x180B, 0x180F),
    (0x200B, 0x200F),
    (0x202A, 0x202E),
    (0x2060, 0x206F),
    (0x3164, 0x3164),
    (0xFE00, 0xFE0F),
    (0xFEFF, 0xFEFF),
    (0xFFA0, 0xFFA0),
    (0xFFF0, 0xFFFB),
    (0x110BD, 0x110BD),
    (0x110CD, 0x110CD),
    (0x13430, 0x1343F),
    (0x1BCA0, 0x1BCA3),
    (0x1D173, 0x1D17A),
    (0xE0000, 0xE0FFF),
];

/// Why `c` may not appear in a class name, or `None` when it may.
pub fn refused_char(c: char) -> Option<CharKind> {
    let u = u32::from(c);
    if c.is_control() {
        Some(CharKind::Control)
    } else if INVISIBLE.iter().any(|&(lo, hi)| (lo..=hi).contains(&u)) {
        Some(CharKind::Invisible)
    } else if c.is_whitespace() && c != ' ' {
        Some(CharKind::Separator)
    } else if (0xE000..=0xF8FF).contains(&u) || u >= 0xF_0000 && u & 0xFFFE != 0xFFFE {
        Some(CharKind::PrivateUse)
    } else if (0xFDD0..=0xFDEF).contains(&u) || u & 0xFFFE == 0xFFFE {
        Some(CharKind::Noncharacter)
    } else {
        None
    }
}

/// Checks one class name against the rule of DESIGN §6.15: 1 to [`NAME_MAX`] bytes,
/// not `background`, every character printable (no control, invisible or formatting
/// character, no separator but U+0020 SPACE, no private-use character or
/// noncharacter), and no space at either end. Uniqueness is a rule of a list: see
/// [`check_class_names`].
///
/// # Errors
///
/// The first rule broken, in the order above.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{check_class_name, CharKind, NameError};
/// assert_eq!(check_class_name("traffic light"), Ok(()));
/// assert_eq!(check_class_name("Fußgänger"), Ok(()));
/// assert_eq!(check_class_name("background"), Err(NameError::Reserved));
/// assert_eq!(check_class_name(" car"), Err(NameError::Padded));
/// assert_eq!(
///     check_class_name("car\u{202E}"),
///     Err(NameError::Char { ch: '\u{202E}', at: 3, kind: CharKind::Invisible })
/// );
/// ```
pub fn check_class_name(name: &str) -> Result<(), NameError> {
    check_stored(name)?;
    for (at, ch) in name.char_indices() {
        if let Some(kind) = refused_char(ch) {
            let at = u8::try_from(at).unwrap_or(u8::MAX);
            return Err(NameError::Char { ch, at, kind });
        }
    }
    if name.starts_with(' ') || name.ends_with(' ') {
        return Err(NameError::Padded);
    }
    Ok(())
}

/// Checks a table's list of class names: [`check_class_name`] of each, and no name
/// twice (O(K²), no allocation).
///
/// # Errors
///
/// The index of the first name at fault, and the rule it breaks
/// ([`NameError::Repeated`] for the second of two equal names).
pub fn check_class_names<'a, I>(names: I) -> Result<(), (usize, NameError)>
where
    I: IntoIterator<Item = &'a str>,
    I::IntoIter: Clone,
{
    let names = names.into_iter();
    for (i, name) in names.clone().enumerate() {
        check_class_name(name).map_err(|e| (i, e))?;
        if let Some(first) = names.clone().take(i).position(|n| n == name) {
            let first = u16::try_from(first).unwrap_or(u16::MAX);
            return Err((i, NameError::Repeated { first }));
        }
    }
    Ok(())
}

/// The part of the rule every table of every version obeys: 1 to [`NAME_MAX`] bytes,
/// not `background` (what a table of a version before [`NAME_RULE_VERSION`] may hold).
fn check_stored(name: &str) -> Result<(), NameError> {
    if name.is_empty() {
        Err(NameError::Empty)
    } else if name.len() > NAME_MAX {
        Err(NameError::TooLong)
    } else if name == RESERVED {
        Err(NameError::Reserved)
    } else {
        Ok(())
    }
}

/// A class name of at most [`NAME_MAX`] UTF-8 bytes, stored inline.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct ClassName {
    pub(crate) len: u8,
    pub(crate) bytes: [u8; NAME_MAX],
}

impl ClassName {
    /// The empty name (invalid), for storage that is filled before use.
    pub(crate) const EMPTY: Self = Self {
        len: 0,
        bytes: [0; NAME_MAX],
    };

    /// Stores `name`; `None` if it breaks the rule of [`check_class_name`] (e.g. it is
    /// empty, longer than [`NAME_MAX`] bytes, the reserved label `background`, or holds
    /// a control character).
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// use mlmap::ClassName;
    /// assert_eq!(ClassName::new("cyclist").unwrap().as_str(), "cyclist");
    /// assert!(ClassName::new("").is_none());
    /// assert!(ClassName::new("background").is_none());
    /// assert!(ClassName::new("car\n").is_none());
    /// ```
    pub fn new(name: &str) -> Option<Self> {
        Self::checked(name).ok()
    }

    /// Stores `name` if it passes [`check_class_name`].
    pub(crate) fn checked(name: &str) -> Result<Self, NameError> {
        check_class_name(name)?;
        Ok(Self::store(name))
    }

    /// Stores `name` as a table of a version before [`NAME_RULE_VERSION`] may hold it:
    /// 1 to [`NAME_MAX`] bytes, not `background`.
    pub(crate) fn stored(name: &str) -> Result<Self, NameError> {
        check_stored(name)?;
        Ok(Self::store(name))
    }

    /// Copies at most [`NAME_MAX`] bytes of `name` (checked by the caller).
    fn store(name: &str) -> Self {
        let src = name.as_bytes();
        let mut bytes = [0u8; NAME_MAX];
        for (d, s) in bytes.iter_mut().zip(src) {
            *d = *s;
        }
        Self {
            len: u8::try_from(src.len().min(NAME_MAX)).unwrap_or(0),
            bytes,
        }
    }

    /// The name as a string slice.
    pub fn as_str(&self) -> &str {
        let used = self.bytes.get(..usize::from(self.len)).unwrap_or(&[]);
        core::str::from_utf8(used).unwrap_or("")
    }
}

impl fmt::Debug for ClassName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(self.as_str(), f)
    }
}

impl fmt::Display for ClassName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_too_long_message_quotes_name_max() {
        let want = std::format!("the name is longer than {NAME_MAX} bytes");
        assert_eq!(NameError::TooLong.message(), want);
    }

    /// Each range of refused characters by its first and last code point and the
    /// allowed neighbours just outside it, from the Unicode 15.1 character database
    /// (UnicodeData.txt categories Cc, Cf, Zs, Zl, Zp, Co, and
    /// DerivedCoreProperties.txt's Default_Ignorable_Code_Point), written out by hand.
    #[test]
    fn refused_characters_by_range() {
        use CharKind::*;
        let refused: &[(u32, u32, CharKind)] = &[
            (0x00, 0x1F, Control),
            (0x7F, 0x9F, Control),
            (0xAD, 0xAD, Invisible),
            (0x34F, 0x34F, Invisible),
            (0x600, 0x605, Invisible),
            (0x61C, 0x61C, Invisible),
            (0x6DD, 0x6DD, Invisible),
            (0x70F, 0x70F, Invisible),
            (0x890, 0x891, Invisible),
            (0x8E2, 0x8E2, Invisible),
            (0x115F, 0x1160, Invisible),
            (0x17B4, 0x17B5, Invisible),
            (0x180B, 0x180F, Invisible),
            (0x200B, 0x200F, Invisible),
            (0x202A, 0x202E, Invisible),
            (0x2060, 0x206F, Invisible),
            (0x3164, 0x3164, Invisible),
            (0xFE00, 0xFE0F, Invisible),
            (0xFEFF, 0xFEFF, Invisible),
            (0xFFA0, 0xFFA0, Invisible),
            (0xFFF0, 0xFFFB, Invisible),
            (0x110BD, 0x110BD, Invisible),
            (0x110CD, 0x110CD, Invisible),
            (0x13430, 0x1343F, Invisible),
            (0x1BCA0, 0x1BCA3, Invisible),
            (0x1D173, 0x1D17A, Invisible),
            (0xE0000, 0xE0FFF, Invisible),
            (0xA0, 0xA0, Separator),
            (0x1680, 0x1680, Separator),
            (0x2000, 0x200A, Separator),
            (0x2028, 0x2029, Separator),
            (0x202F, 0x202F, Separator),
            (0x205F, 0x205F, Separator),
            (0x3000, 0x3000, Separator),
            (0xE000, 0xF8FF, PrivateUse),
            (0xF0000, 0xFFFFD, PrivateUse),
            (0x100000, 0x10FFFD, PrivateUse),
            (0xFDD0, 0xFDEF, Noncharacter),
        ];
        // The last two code points of each of the 17 planes.
        let planes: std::vec::Vec<_> = (0..=0x10)
            .map(|p: u32| (p << 16 | 0xFFFE, p << 16 | 0xFFFF, Noncharacter))
            .collect();
        let refused = &[refused, &planes[..]].concat()[..];
        let in_any = |u: u32| refused.iter().any(|&(lo, hi, _)| (lo..=hi).contains(&u));
        for &(lo, hi, kind) in refused {
            for u in [lo, hi, lo + (hi - lo) / 2] {
                let c = char::from_u32(u).unwrap();
                assert_eq!(refused_char(c), Some(kind), "U+{u:04X}");
            }
            for u in [lo.wrapping_sub(1), hi + 1] {
                if let Some(c) = char::from_u32(u).filter(|_| !in_any(u)) {
                    assert_eq!(refused_char(c), None, "U+{u:04X}");
                }
            }
        }
        for c in [
            ' ', 'a', 'Z', '0', '~', 'é', 'ß', 'Ω', 'ж', '中', '日', '😀', '\u{FFFD}',
        ] {
            assert_eq!(refused_char(c), None, "{c:?}");
        }
    }

    #[test]
    fn the_rules_in_order() {
        assert_eq!(check_class_name(""), Err(NameError::Empty));
        assert_eq!(check_class_name(&"x".repeat(32)), Err(NameError::TooLong));
        assert_eq!(check_class_name(&"x".repeat(31)), Ok(()));
        // 10 characters of 3 bytes: 30 bytes, then 33.
        assert_eq!(check_class_name(&"中".repeat(10)), Ok(()));
        assert_eq!(check_class_name(&"中".repeat(11)), Err(NameError::TooLong));
        assert_eq!(check_class_name("background"), Err(NameError::Reserved));
        assert_eq!(check_class_name("Background"), Ok(()));
        assert_eq!(check_class_name("traffic light"), Ok(()));
        assert_eq!(check_class_name("car "), Err(NameError::Padded));
        assert_eq!(check_class_name(" "), Err(NameError::Padded));
        let ch = |ch, at, kind| Err(NameError::Char { ch, at, kind });
        assert_eq!(check_class_name("a\0b"), ch('\0', 1, CharKind::Control));
        assert_eq!(
            check_class_name("\x1b[31mred"),
            ch('\x1b', 0, CharKind::Control)
        );
        assert_eq!(check_class_name("car\n"), ch('\n', 3, CharKind::Control));
        assert_eq!(check_class_name("\tcar"), ch('\t', 0, CharKind::Control));
        assert_eq!(
            check_class_name("é\u{85}"),
            ch('\u{85}', 2, CharKind::Control)
        );
        assert_eq!(
            check_class_name("abc\u{202E}cba"),
            ch('\u{202E}', 3, CharKind::Invisible)
        );
        assert_eq!(
            check_class_name("a\u{200B}b"),
            ch('\u{200B}', 1, CharKind::Invisible)
        );
        assert_eq!(
            check_class_name("a\u{2028}b"),
            ch('\u{2028}', 1, CharKind::Separator)
        );
        assert_eq!(
            check_class_name("a\u{a0}b"),
            ch('\u{a0}', 1, CharKind::Separator)
        );
        // The injection a C comment would suffer is printable: the writers escape it.
        assert_eq!(check_class_name("*/ int pwn = 1; /*"), Ok(()));
    }

    #[test]
    fn lists_are_unique() {
        assert_eq!(check_class_names(["car", "cyclist"]), Ok(()));
        assert_eq!(
            check_class_names(["car", "bus", "car"]),
            Err((2, NameError::Repeated { first: 0 }))
        );
        assert_eq!(
            check_class_names(["car", "bus\r"]),
            Err((
                1,
                NameError::Char {
                    ch: '\r',
                    at: 3,
                    kind: CharKind::Control
                }
            ))
        );
    }

    #[test]
    fn stored_names_of_older_tables() {
        assert!(ClassName::stored("car\n").is_ok());
        assert_eq!(ClassName::stored(""), Err(NameError::Empty));
        assert_eq!(ClassName::stored("background"), Err(NameError::Reserved));
        assert!(ClassName::new("car\n").is_none());
        assert_eq!(ClassName::checked("car").map(|n| n.len), Ok(3));
    }
}
