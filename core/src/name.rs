//! Class names stored inline, so a table needs no allocation and can be a `const`.

use core::fmt;

/// Longest class name a table stores, in UTF-8 bytes.
pub const NAME_MAX: usize = 31;

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

    /// Stores `name`; `None` if it is empty, longer than [`NAME_MAX`] bytes, or the
    /// reserved label `background`.
    ///
    /// # Examples
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// use mlmap::ClassName;
    /// assert_eq!(ClassName::new("cyclist").unwrap().as_str(), "cyclist");
    /// assert!(ClassName::new("").is_none());
    /// assert!(ClassName::new("background").is_none());
    /// ```
    pub fn new(name: &str) -> Option<Self> {
        let src = name.as_bytes();
        if src.is_empty() || src.len() > NAME_MAX || name == "background" {
            return None;
        }
        let mut bytes = [0u8; NAME_MAX];
        for (d, s) in bytes.iter_mut().zip(src) {
            *d = *s;
        }
        Some(Self {
            len: src.len() as u8,
            bytes,
        })
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
