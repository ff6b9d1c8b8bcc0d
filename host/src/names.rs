//! The names of every closed set of settings: how reports print them, how the command
//! line spells them, and a one-line description of each (shown by `--help`).
//!
//! Each set has one table ([`Named::NAMES`]); printing ([`Named::name`]) and parsing
//! ([`Named::from_name`]) both read it, so a name is written once. The host enums
//! ([`Binning`](super::metrics::Binning), [`Objective`](super::tune::Objective),
//! [`Method`](super::eval::Method)) keep their table next to their definition and
//! implement `Display` and `FromStr` through it; the tables of the layer's enums
//! ([`EdgeMode`], [`UpperTail`], [`Head`]) are here.

use core::fmt;

use mlmap_core::{EdgeMode, Head, UpperTail};

/// One value of a [`Named`] set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Name<T: 'static> {
    /// The value.
    pub value: T,
    /// Its name in reports (text, JSON, markdown).
    pub name: &'static str,
    /// Its spelling on the command line (usually the same as `name`).
    pub flag: &'static str,
    /// A one-line description.
    pub help: &'static str,
}

impl<T> Name<T> {
    /// A value whose command-line spelling is its name.
    pub const fn new(value: T, name: &'static str, help: &'static str) -> Self {
        Self {
            value,
            name,
            flag: name,
            help,
        }
    }
}

/// A closed set of values with stable names.
///
/// # Examples
///
/// ```
/// use mlmap_host::names::Named;
/// use mlmap_core::EdgeMode;
///
/// assert_eq!(EdgeMode::Matlab.name(), "matlab");
/// assert_eq!(EdgeMode::from_name("linspace"), Ok(EdgeMode::Linspace));
/// assert!(EdgeMode::from_name("log").is_err());
/// ```
pub trait Named: Copy + PartialEq + Sized + 'static {
    /// What the set is called in error messages (`edge mode`, `binning`, ...).
    const WHAT: &'static str;
    /// Every value with its names, in the order they are listed.
    const NAMES: &'static [Name<Self>];

    /// The value's entry of [`NAMES`](Self::NAMES).
    fn entry(self) -> Option<&'static Name<Self>> {
        Self::NAMES.iter().find(|n| n.value == self)
    }

    /// The name in reports.
    fn name(self) -> &'static str {
        self.entry().map_or("", |n| n.name)
    }

    /// The spelling on the command line.
    fn flag(self) -> &'static str {
        self.entry().map_or("", |n| n.flag)
    }

    /// The value whose name or command-line spelling is `s` (exact, case-sensitive).
    ///
    /// # Errors
    ///
    /// [`UnknownName`] listing the accepted names.
    fn from_name(s: &str) -> Result<Self, UnknownName> {
        Self::NAMES
            .iter()
            .find(|n| n.name == s || n.flag == s)
            .map(|n| n.value)
            .ok_or_else(|| UnknownName {
                what: Self::WHAT,
                given: String::from(s),
                expected: Self::NAMES.iter().map(|n| n.flag).collect(),
            })
    }
}

/// A name that is not in a [`Named`] set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownName {
    what: &'static str,
    given: String,
    expected: Vec<&'static str>,
}

impl fmt::Display for UnknownName {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown {} `{}`: expected one of {}",
            self.what,
            self.given,
            self.expected.join(", ")
        )
    }
}

impl core::error::Error for UnknownName {}

/// Implements `Display` (the name) and `FromStr` (a name or flag, else
/// [`UnknownName`]) of host enums through their [`Named`] table.
macro_rules! display_and_parse {
    ($($t:ty),+) => {$(
        impl core::fmt::Display for $t {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                f.write_str($crate::names::Named::name(*self))
            }
        }

        impl core::str::FromStr for $t {
            type Err = $crate::names::UnknownName;

            fn from_str(s: &str) -> Result<Self, Self::Err> {
                <Self as $crate::names::Named>::from_name(s)
            }
        }
    )+};
}
pub(crate) use display_and_parse;

// The layer's enums. These tables belong next to the enums; they are kept here while
// the layer stays free of host code.

impl Named for EdgeMode {
    const WHAT: &'static str = "edge mode";
    const NAMES: &'static [Name<Self>] = &[
        Name::new(
            Self::Linspace,
            "linspace",
            "B equal bins over [min, max] of the training logits (numpy.histogram)",
        ),
        Name::new(
            Self::Matlab,
            "matlab",
            "The edges MATLAB's histogram(x, nbins) picks (the paper's tables)",
        ),
    ];
}

impl Named for UpperTail {
    const WHAT: &'static str = "upper tail";
    const NAMES: &'static [Name<Self>] = &[
        Name::new(
            Self::Zero,
            "zero",
            "No likelihood above the training support (the paper's behaviour)",
        ),
        Name::new(
            Self::Clamp,
            "clamp",
            "Logits above the last edge use the last bin",
        ),
    ];
}

/// The heads by their keys in reports (`ml`, `map`); `Head`'s `Display` gives the
/// titles (`ML`, `MAP`).
impl Named for Head {
    const WHAT: &'static str = "head";
    const NAMES: &'static [Name<Self>] = &[
        Name::new(Self::Ml, "ml", "The maximum-likelihood head"),
        Name::new(Self::Map, "map", "The maximum a-posteriori head"),
        Name::new(Self::Bayes, "bayes", "The Bayes head over every logit"),
        Name::new(
            Self::Open,
            "open",
            "The detector's softmax at a temperature, times the probability of a known object",
        ),
    ];
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    fn round_trip<T: Named + fmt::Debug>() {
        for n in T::NAMES {
            assert_eq!(n.value.name(), n.name);
            assert_eq!(T::from_name(n.name), Ok(n.value));
            assert_eq!(T::from_name(n.flag), Ok(n.value));
        }
        let names: Vec<_> = T::NAMES.iter().map(|n| n.name).collect();
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "{names:?}");
    }

    #[test]
    fn names_round_trip() {
        round_trip::<EdgeMode>();
        round_trip::<UpperTail>();
        round_trip::<Head>();
        let e = UpperTail::from_name("Zero").unwrap_err();
        assert_eq!(
            e.to_string(),
            "unknown upper tail `Zero`: expected one of zero, clamp"
        );
    }
}
