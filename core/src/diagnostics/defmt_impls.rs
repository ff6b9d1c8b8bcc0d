//! `defmt::Format` for every public type (feature `defmt`), kept in one place so the
//! modules shared with `build.rs` stay free of target-only derives.

use defmt::{write, Format, Formatter};

use crate::{
    BatchError, CharKind, ClassName, DecodeError, EdgeMode, EncodeError, Gaussian, GaussianError,
    Head, Histogram, HistogramError, InferError, NameError, Scores, Settings, TableError,
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

// Errors: each variant's `message()` (the text `Display` is built from), then its fields.

impl Format for TableError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::Edges { head, class }
            | Self::Frequencies { head, class }
            | Self::BinCount { head, class } => {
                write!(f, "{=str} ({} histogram of class {})", m, head, class)
            }
            Self::Mean { class } | Self::Variance { class } | Self::DuplicateName { class } => {
                write!(f, "{=str} (class {})", m, class)
            }
            Self::CategoryRows { class } => write!(f, "{=str} (category {})", m, class),
            Self::Lambda { head } => write!(f, "{=str} ({})", m, head),
            Self::Name { class, error } => write!(f, "{=str} (class {}: {})", m, class, error),
            Self::ClassCount | Self::BayesShape | Self::Temperature | Self::Epsilon => {
                write!(f, "{=str}", m)
            }
            Self::Map { head, error } => write!(f, "{=str} ({} head: {})", m, head, error),
        }
    }
}

impl Format for crate::MapError {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.message())
    }
}

impl Format for crate::Knot {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "({}, {})", self.x, self.y)
    }
}

impl Format for crate::RecalMap<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "RecalMap {{ knots: {=[?]} }}", self.knots())
    }
}

impl Format for NameError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::Char { ch, at, kind } => {
                write!(
                    f,
                    "{=str} ({} U+{:04X} at byte {})",
                    m,
                    kind,
                    u32::from(ch),
                    at
                )
            }
            Self::Repeated { first } => write!(f, "{=str} (class {})", m, first),
            Self::Empty | Self::TooLong | Self::Reserved | Self::Padded => write!(f, "{=str}", m),
        }
    }
}

impl Format for CharKind {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.message())
    }
}

impl Format for crate::BodyPart {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::Class { index } => write!(f, "{=str} {}", self.describe(), index),
            _ => write!(f, "{=str}", self.describe()),
        }
    }
}

impl Format for DecodeError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::UnsupportedVersion { found } => write!(f, "{=str} (version {})", m, found),
            Self::ShapeMismatch { expected, found } => {
                write!(f, "{=str} (expected {}, found {})", m, expected, found)
            }
            Self::BayesShapeMismatch { expected, found } => {
                write!(f, "{=str} (expected {}, found {})", m, expected, found)
            }
            Self::Invalid(e) => write!(f, "{=str}: {}", m, e),
            Self::Truncated | Self::NotATable | Self::Corrupted | Self::Malformed => {
                write!(f, "{=str}", m)
            }
            Self::MapCapacity {
                head,
                capacity,
                found,
            } => write!(
                f,
                "{=str} ({} head: {} knots, room for {})",
                m, head, found, capacity
            ),
            Self::ObjectnessMismatch { found } => write!(f, "{=str} (found {})", m, found),
        }
    }
}

impl Format for EncodeError {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "{=str}", self.message())
    }
}

impl Format for InferError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::NanLogit { class } | Self::CodeRange { class } | Self::NanScore { class } => {
                write!(f, "{=str} (class {})", m, class)
            }
            Self::Objectness
            | Self::Length
            | Self::Evidence
            | Self::NoBayesHead
            | Self::NoOpenHead => write!(f, "{=str}", m),
            Self::CodeWidth { expected, found } => {
                write!(
                    f,
                    "{=str} ({}-bit codes, section {}-bit)",
                    m, found, expected
                )
            }
        }
    }
}

impl Format for BatchError {
    fn format(&self, f: Formatter<'_>) {
        match *self {
            Self::LengthMismatch => write!(f, "{=str}", self.message()),
            Self::Row { index, error } => write!(f, "row {}: {}", index, error),
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
        let m = self.message();
        match *self {
            Self::UnsupportedVersion { found } => write!(f, "{=str} (found {})", m, found),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "{=str} (found {} classes of int{}, expected {} of int{})",
                m, found.0, found.1, expected.0, expected.1
            ),
            Self::Invalid { field, class } => {
                write!(f, "{=str} (class {}: {})", m, class, field)
            }
            _ => write!(f, "{=str}", m),
        }
    }
}

impl Format for crate::QuantizeError {
    fn format(&self, f: Formatter<'_>) {
        let m = self.message();
        match *self {
            Self::Scale { class } | Self::ZeroPoint { class } => {
                write!(f, "{=str} (class {})", m, class)
            }
            _ => write!(f, "{=str}", m),
        }
    }
}

impl<'a, C, L, Q> Format for crate::QTableInner<'a, C, L, Q>
where
    C: AsRef<[crate::lent::QClass<'a>]>,
    L: AsRef<[crate::lent::QLogit<'a>]>,
{
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "QTable {{ K: {}, bits: {}, bytes: {}, categories: {} }}",
            self.k(),
            self.bits(),
            self.section_len(),
            self.categories()
        )
    }
}

impl Format for crate::AnyCode {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "AnyCode")
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

impl Format for crate::OpenParams {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "OpenParams {{ temperature: {}, epsilon: {} }}",
            self.temperature(),
            self.epsilon()
        )
    }
}

impl Format for crate::Axis {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "Axis {{ [{}, {}], {} bins }}",
            self.lo(),
            self.hi(),
            self.bins()
        )
    }
}

impl Format for crate::BayesView<'_> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "BayesView {{ {} logits, {} categories, {} bins, lambda: {}, open: {} }}",
            self.logits(),
            self.categories(),
            self.bins(),
            self.lambda(),
            self.open()
        )
    }
}

impl<F: AsRef<[f32]>, G: AsRef<[f32]>> Format for crate::TableView<'_, F, G> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "TableView {{ {} classes, {} ML bins, {} MAP bins, {}, bayes: {} }}",
            self.k(),
            self.bins_ml(),
            self.bins_map(),
            self.settings(),
            self.bayes()
        )
    }
}

impl<F: AsRef<[f32]>, G: AsRef<[f32]>> Format for crate::ClassSpec<'_, F, G> {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "ClassSpec {{ name: {=str}, rows: {}, mean: {}, variance: {}, ML: [{}, {}] {=[?]}, \
             MAP: [{}, {}] {=[?]} }}",
            self.name,
            self.rows,
            self.mean,
            self.variance,
            self.ml_range.0,
            self.ml_range.1,
            self.ml_freqs.as_ref(),
            self.map_range.0,
            self.map_range.1,
            self.map_freqs.as_ref()
        )
    }
}

impl<const N: usize> Format for crate::Bounded<N> {
    fn format(&self, f: Formatter<'_>) {
        write!(f, "Bounded<{}>({=[?]})", N, self.as_ref())
    }
}

#[cfg(feature = "alloc")]
impl Format for crate::BayesSpec {
    fn format(&self, f: Formatter<'_>) {
        write!(
            f,
            "BayesSpec {{ lambda: {}, rows: {=[?]}, {} ranges, {} terms }}",
            self.lambda,
            &self.rows[..],
            self.ranges.len(),
            self.terms.len()
        )
    }
}
