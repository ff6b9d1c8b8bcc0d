//! `defmt::Format` for every public type (feature `defmt`), kept in one place so the
//! modules shared with `build.rs` stay free of target-only derives.

use defmt::{write, Format, Formatter};

use crate::{
    BatchError, CharKind, ClassName, DecodeError, EdgeMode, EncodeError, Gaussian, GaussianError,
    Head, Histogram, HistogramError, InferError, NameError, Scores, Settings, Table, TableError,
    UpperTail,
};

impl Format for Head {
    fn format(&self, f: Formatter<'_>) {
        match self {
            Self::Ml => write!(f, "ML"),
            Self::Map => write!(f, "MAP"),
            Self::Bayes => write!(f, "Bayes"),
            Self::Open => write!(f, "open"),
        }
    }
}

impl Format for TableError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::Edges { head, class } => {
                write!(f, "{} histogram of class {}: bad edges", head, class)
            }
            Self::Frequencies { head, class } => {
                write!(f, "{} histogram of class {}: bad frequencies", head, class)
            }
            Self::BinCount { head, class } => {
                write!(f, "{} histogram of class {}: wrong bin count", head, class)
            }
            Self::Mean { class } => write!(f, "prior of class {}: bad mean", class),
            Self::Variance { class } => write!(f, "prior of class {}: bad variance", class),
            Self::Lambda { head } => write!(f, "{} lambda out of range", head),
            Self::Name { class, error } => write!(f, "name of class {}: {}", class, error),
            Self::DuplicateName { class } => write!(f, "name of class {} repeated", class),
            Self::ClassCount => write!(f, "class count out of range"),
            Self::CategoryRows { class } => write!(f, "Bayes category {} has no rows", class),
            Self::BayesShape => write!(f, "Bayes head shape inconsistent"),
            Self::Temperature => write!(f, "open head: temperature out of range"),
            Self::Epsilon => write!(f, "open head: epsilon out of range"),
        }
    }
}

impl Format for NameError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::Empty => write!(f, "empty"),
            Self::TooLong => write!(f, "too long"),
            Self::Reserved => write!(f, "reserved"),
            Self::Char { ch, at, kind } => {
                write!(f, "{} U+{:04X} at byte {}", kind, u32::from(ch), at)
            }
            Self::Padded => write!(f, "starts or ends with a space"),
            Self::Repeated { first } => write!(f, "repeats class {}", first),
        }
    }
}

impl Format for CharKind {
    fn format(&self, f: Formatter<'_>) {
        match self {
            Self::Control => write!(f, "control character"),
            Self::Invisible => write!(f, "invisible character"),
            Self::Separator => write!(f, "separator"),
            Self::PrivateUse => write!(f, "private-use character"),
            Self::Noncharacter => write!(f, "noncharacter"),
        }
    }
}

impl Format for DecodeError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::Truncated => write!(f, "Truncated"),
            Self::NotATable => write!(f, "NotATable"),
            Self::Corrupted => write!(f, "Corrupted"),
            Self::UnsupportedVersion { found } => write!(f, "UnsupportedVersion({})", found),
            Self::ShapeMismatch { expected, found } => {
                write!(f, "ShapeMismatch(expected {}, found {})", expected, found)
            }
            Self::BayesShapeMismatch { expected, found } => {
                write!(
                    f,
                    "BayesShapeMismatch(expected {}, found {})",
                    expected, found
                )
            }
            Self::Malformed => write!(f, "Malformed"),
            Self::Invalid(e) => write!(f, "Invalid({})", e),
        }
    }
}

impl Format for EncodeError {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "BufferTooSmall")
    }
}

impl Format for InferError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::NanLogit { class } => write!(f, "NanLogit({})", class),
            Self::Objectness => write!(f, "Objectness"),
            Self::Length => write!(f, "Length"),
            Self::Evidence => write!(f, "Evidence"),
            Self::NoBayesHead => write!(f, "NoBayesHead"),
            Self::NoOpenHead => write!(f, "NoOpenHead"),
            Self::CodeRange { class } => write!(f, "CodeRange({})", class),
            Self::NanScore { class } => write!(f, "NanScore({})", class),
        }
    }
}

impl Format for BatchError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::LengthMismatch => write!(f, "LengthMismatch"),
            Self::Row { index, error } => write!(f, "Row({}, {})", index, error),
        }
    }
}

impl Format for EdgeMode {
    fn format(&self, f: Formatter<'_>) {
        match self {
            Self::Linspace => write!(f, "linspace"),
            Self::Matlab => write!(f, "matlab"),
        }
    }
}

impl Format for UpperTail {
    fn format(&self, f: Formatter<'_>) {
        match self {
            Self::Zero => write!(f, "zero"),
            Self::Clamp => write!(f, "clamp"),
        }
    }
}

impl Format for ClassName {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.as_str())
    }
}

impl Format for Settings {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Settings {{ lambda_ml: {}, lambda_map: {}, edges: {}, upper_tail: {} }}",
            self.lambda_ml, self.lambda_map, self.edge_mode, self.upper_tail
        )
    }
}

impl Format for Gaussian {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "N(mean {}, var {})", self.mean, self.var)
    }
}

impl<F: AsRef<[f32]>> Format for Histogram<F> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Histogram {{ [{}, {}], {=[?]} }}",
            self.lo,
            self.hi,
            self.freqs.as_ref()
        )
    }
}

impl<const K: usize> Format for Scores<K> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Scores({=[?]})", &self.0[..])
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
    > Format for Table<K, B_ML, B_MAP, B_BAYES, C>
{
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Table<{}, {}, {}, {}, {}> {{ classes: {=[?]}, {} }}",
            K,
            B_ML,
            B_MAP,
            B_BAYES,
            C,
            &self.names[..],
            self.settings
        )
    }
}

impl Format for crate::Libm {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Libm")
    }
}

impl Format for crate::FastMath {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "FastMath")
    }
}

#[cfg(feature = "micromath")]
impl Format for crate::Micromath {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Micromath")
    }
}

impl Format for HistogramError {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.message())
    }
}

impl Format for GaussianError {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.message())
    }
}

impl Format for crate::QField {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.describe())
    }
}

impl Format for crate::QTableError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::NotQuantized => write!(f, "NotQuantized"),
            Self::Corrupted => write!(f, "Corrupted"),
            Self::UnsupportedVersion { found } => write!(f, "UnsupportedVersion({})", found),
            Self::ShapeMismatch { expected, found } => {
                write!(f, "ShapeMismatch({}, {})", expected, found)
            }
            Self::TableMismatch => write!(f, "TableMismatch"),
            Self::Malformed => write!(f, "Malformed"),
            Self::Invalid { field, class } => write!(f, "Invalid({}, class {})", field, class),
        }
    }
}

impl Format for crate::QuantizeError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::Bits => write!(f, "Bits"),
            Self::Length => write!(f, "Length"),
            Self::Scale { class } => write!(f, "Scale({})", class),
            Self::ZeroPoint { class } => write!(f, "ZeroPoint({})", class),
            Self::NoBayesHead => write!(f, "NoBayesHead"),
            Self::BufferTooSmall => write!(f, "BufferTooSmall"),
            Self::TooLarge => write!(f, "TooLarge"),
        }
    }
}

impl<const K: usize, Q: crate::Code> Format for crate::QTable<'_, K, Q> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "QTable(K = {}, int{}, {} bytes, Bayes {})",
            K,
            Q::BITS,
            self.section_len(),
            self.has_bayes()
        )
    }
}

impl Format for crate::QParams<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "QParams(int{}, scales {=[?]}, zero points {=[?]}, Bayes {})",
            self.bits, self.scales, self.zero_points, self.bayes
        )
    }
}
