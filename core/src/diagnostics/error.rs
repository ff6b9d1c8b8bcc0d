//! Error types of the layer: one small enum per failure domain.
//!
//! Every type here is `Copy`, has one sentence per variant (`message`) and implements
//! [`core::error::Error`]. `message` is the one text of a variant: [`Display`](core::fmt::Display)
//! prints it as it is for a variant without fields, and with the fields worked into the
//! sentence otherwise; `defmt` prints it followed by the fields; the C API's status
//! strings are checked against it (`ffi/tests/same_bits.rs`). None of them carries a
//! postcard error: the wire library is an implementation detail.

use core::fmt;

/// Which of the two heads of a table an error refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Head {
    /// The maximum-likelihood head (histogram likelihood only).
    Ml,
    /// The maximum a-posteriori head (histogram likelihood times Gaussian prior).
    Map,
    /// The Bayes head (a posterior over every logit, docs/DESIGN.md §1.6).
    Bayes,
    /// The open head (the detector's softmax at a temperature, times the probability
    /// that the object is of a known class, docs/DESIGN.md §1.8).
    Open,
}

impl fmt::Display for Head {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Ml => "ML",
            Self::Map => "MAP",
            Self::Bayes => "Bayes",
            Self::Open => "open",
        })
    }
}

/// A broken table invariant (DESIGN §1.3, invariant 5).
///
/// Returned when a table is built from parts or decoded from bytes whose contents
/// violate one of the rules every table obeys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum TableError {
    /// The outer edges are not finite, not increasing, or give inner edges that are not
    /// strictly increasing in `f32`.
    Edges {
        /// Head of the histogram.
        head: Head,
        /// Class index of the histogram.
        class: u16,
    },
    /// A frequency is negative or not finite, or the frequencies do not sum to 1 within
    /// [`FREQUENCY_SUM_TOLERANCE`](crate::FREQUENCY_SUM_TOLERANCE).
    Frequencies {
        /// Head of the histogram.
        head: Head,
        /// Class index of the histogram.
        class: u16,
    },
    /// The histogram has a bin count other than the one the table declares.
    BinCount {
        /// Head of the histogram.
        head: Head,
        /// Class index of the histogram.
        class: u16,
    },
    /// The prior's mean is not finite.
    Mean {
        /// Class index.
        class: u16,
    },
    /// The prior's variance is not finite and positive, or so small that `1 / (2 var)`
    /// overflows `f32`.
    Variance {
        /// Class index.
        class: u16,
    },
    /// A smoothing lambda is not in `(0, MAX_LAMBDA]` (`(0, MAX_LAMBDA_BAYES]` for the
    /// Bayes head).
    Lambda {
        /// Head of the lambda.
        head: Head,
    },
    /// A class name breaks the rule of DESIGN §6.15 (see
    /// [`check_class_name`](crate::check_class_name)): it is empty, longer than
    /// [`NAME_MAX`](crate::NAME_MAX) bytes, the reserved label `background`, or (in a
    /// table built now, or decoded from format version
    /// [`NAME_RULE_VERSION`](crate::NAME_RULE_VERSION) on) not printable or padded.
    Name {
        /// Class index.
        class: u16,
        /// The rule broken.
        error: crate::NameError,
    },
    /// Two classes have the same name.
    DuplicateName {
        /// Index of the second occurrence.
        class: u16,
    },
    /// The number of classes is below 2 or above `u16::MAX`.
    ClassCount,
    /// A category of the Bayes head has no training rows, or the rows overflow `u64`.
    CategoryRows {
        /// Category index (K is `background`).
        class: u16,
    },
    /// The Bayes head's shape is inconsistent: categories other than K or K + 1, or
    /// a stored sequence of the wrong length.
    BayesShape,
    /// The open head's temperature is not in
    /// `[MIN_TEMPERATURE, MAX_TEMPERATURE]` (DESIGN §1.8).
    Temperature,
    /// The open head's `epsilon` is not 0 and not in
    /// `[f32::MIN_POSITIVE, MAX_EPSILON]` (DESIGN §1.8).
    Epsilon,
    /// A head's recalibration map breaks the rule of DESIGN §1.9, or is stored for a
    /// head the table does not have.
    Map {
        /// The head the map is for.
        head: Head,
        /// The rule broken.
        error: MapError,
    },
}

impl TableError {
    /// The one sentence describing the variant, without its fields.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Edges { .. } => "histogram edges are not finite and strictly increasing",
            Self::Frequencies { .. } => {
                "histogram frequencies are not finite, non-negative and summing to 1"
            }
            Self::BinCount { .. } => "histogram bin count differs from the table's",
            Self::Mean { .. } => "prior mean is not finite",
            Self::Variance { .. } => {
                "prior variance is not finite and positive (or 1/(2 var) overflows)"
            }
            Self::Lambda { .. } => "a smoothing lambda is out of range",
            Self::Name { .. } => "a class name breaks the naming rule",
            Self::DuplicateName { .. } => "a class name repeats an earlier class name",
            Self::ClassCount => "a table needs between 2 and 65535 classes",
            Self::CategoryRows { .. } => {
                "a Bayes category has no training rows (or the row counts overflow)"
            }
            Self::BayesShape => {
                "Bayes head: categories are not K or K + 1, or a sequence has the wrong length"
            }
            // The bounds as `{:e}` prints them (checked by a test).
            Self::Temperature => "open head: the temperature is not in [1e-6, 1e6]",
            Self::Epsilon => "open head: epsilon is neither 0 nor in [1.1754944e-38, 1e30]",
            Self::Map { .. } => {
                "a recalibration map breaks its rule or is for a head the table does not have"
            }
        }
    }
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Edges { head, class } => write!(
                f,
                "{head} histogram of class {class}: edges are not finite and strictly increasing"
            ),
            Self::Frequencies { head, class } => write!(
                f,
                "{head} histogram of class {class}: frequencies are not finite, non-negative and summing to 1"
            ),
            Self::BinCount { head, class } => write!(
                f,
                "{head} histogram of class {class}: bin count differs from the table's"
            ),
            Self::Mean { class } => write!(f, "prior of class {class}: mean is not finite"),
            Self::Variance { class } => write!(
                f,
                "prior of class {class}: variance is not finite and positive (or 1/(2 var) overflows)"
            ),
            Self::Lambda { head } => write!(
                f,
                "{head} lambda is not in (0, {}]",
                match head {
                    Head::Bayes | Head::Open => crate::MAX_LAMBDA_BAYES,
                    Head::Ml | Head::Map => crate::MAX_LAMBDA,
                }
            ),
            Self::Name { class, error } => write!(f, "name of class {class}: {error}"),
            Self::DuplicateName { class } => {
                write!(f, "name of class {class} repeats an earlier class name")
            }
            Self::CategoryRows { class } => write!(
                f,
                "Bayes category {class} has no training rows (or the row counts overflow)"
            ),
            Self::ClassCount | Self::BayesShape | Self::Temperature | Self::Epsilon => {
                f.write_str(self.message())
            }
            Self::Map { head, error } => write!(f, "recalibration map of the {head} head: {error}"),
        }
    }
}

impl core::error::Error for TableError {}

/// Why a recalibration map's knots break the rule of DESIGN §1.9.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MapError {
    /// Fewer than 2 or more than [`MAX_KNOTS`](crate::MAX_KNOTS) knots.
    KnotCount,
    /// The first knot is not at `x = 0` or the last not at `x = 1`.
    Ends,
    /// The knots' `x` are not strictly increasing (or one is NaN).
    Order,
    /// A `y` is outside `(0, 1]` (or NaN), or the `y` decrease.
    Values,
    /// The table has no such head.
    NoHead,
}

impl MapError {
    /// The variant's message: what `Display` says (with the variant's values where it
    /// has any) and what `defmt` prints.
    pub const fn message(self) -> &'static str {
        match self {
            Self::KnotCount => "it needs between 2 and 32 knots",
            Self::Ends => "its first knot is not at 0 or its last not at 1",
            Self::Order => "its knots are not strictly increasing in x",
            Self::Values => "its values are not in (0, 1] and non-decreasing",
            Self::NoHead => "the table has no such head",
        }
    }
}

impl fmt::Display for MapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.message())
    }
}

impl core::error::Error for MapError {}

/// Why a byte string could not become a table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DecodeError {
    /// The input is shorter than the smallest possible table.
    Truncated,
    /// The bytes do not start with the mlmap magic `MLMP`.
    NotATable,
    /// The stored CRC-32 does not match the contents.
    Corrupted,
    /// The table was written in a format version this build does not read.
    UnsupportedVersion {
        /// Version stored in the bytes.
        found: u16,
    },
    /// The table has another shape than the type it is decoded into.
    ShapeMismatch {
        /// `(K, ML bins, MAP bins)` of the destination type.
        expected: (u16, u16, u16),
        /// `(K, ML bins, MAP bins)` stored in the table.
        found: (u16, u16, u16),
    },
    /// The table has another Bayes head shape than the type it is decoded into (one
    /// has a Bayes head and the other not, or the bins or categories differ).
    BayesShapeMismatch {
        /// `(Bayes bins, categories)` of the destination type, `(0, 0)` for none.
        expected: (u16, u16),
        /// `(Bayes bins, categories)` stored in the table, `(0, 0)` for none.
        found: (u16, u16),
    },
    /// The table holds a recalibration map with more knots than the type it is decoded
    /// into has room for (its `M` parameter; 0 for a type without maps).
    MapCapacity {
        /// The head the map is for.
        head: Head,
        /// Knots per map the destination type holds.
        capacity: u16,
        /// Knots stored in the table.
        found: u16,
    },
    /// The table has the objectness feature (DESIGN §1.6) and the type it is decoded
    /// into has no room for it, or the type requires the feature and the table lacks it.
    ObjectnessMismatch {
        /// Whether the table has the feature.
        found: bool,
    },
    /// The checksum matched, but the body does not follow the format (a field is
    /// missing, an enum tag is unknown, a name is not UTF-8, bytes are left over, a
    /// varint is not in its shortest form).
    Malformed,
    /// The body parsed, but a table invariant does not hold.
    Invalid(TableError),
}

/// The part of a table a decode that gave [`DecodeError::Malformed`] was reading when
/// the bytes stopped following the format ([`locate_malformed`](crate::locate_malformed)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum BodyPart {
    /// The header (the Bayes head's shape, stored after the fixed fields).
    Header,
    /// The body is shorter than the frequencies and terms the header announces.
    Length,
    /// The settings (lambdas, the edge mode and upper tail codes).
    Settings,
    /// The record of one class (name, rows, prior, histograms), or a class record
    /// beyond the header's number of classes.
    Class {
        /// Index of the class.
        index: u16,
    },
    /// The Bayes head (lambda, category rows, axes, log-terms).
    Bayes,
    /// The objectness feature (DESIGN §1.6).
    Objectness,
    /// The open head's temperature and epsilon.
    Open,
    /// The recalibration maps (DESIGN §1.9).
    Maps,
    /// Bytes left over after the last part.
    Trailing,
}

impl BodyPart {
    /// A few words naming the part, shared by `Display` users and `defmt`.
    pub const fn describe(self) -> &'static str {
        match self {
            Self::Header => "header (Bayes shape)",
            Self::Length => "body length (shorter than the header's shape)",
            Self::Settings => "settings",
            Self::Class { .. } => "class record",
            Self::Bayes => "Bayes head",
            Self::Objectness => "objectness feature",
            Self::Open => "open head parameters",
            Self::Maps => "recalibration maps",
            Self::Trailing => "bytes after the last part",
        }
    }
}

impl fmt::Display for BodyPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Class { index } => write!(f, "class record {index}"),
            _ => f.write_str(self.describe()),
        }
    }
}

impl DecodeError {
    /// The one sentence describing the variant, without its fields.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Truncated => "input is too short to be an mlmap table",
            Self::NotATable => "input does not start with the mlmap magic `MLMP`",
            Self::Corrupted => "table checksum does not match its contents",
            Self::UnsupportedVersion { .. } => "table format version is not supported",
            Self::ShapeMismatch { .. } => "table shape differs from the destination type's",
            Self::BayesShapeMismatch { .. } => {
                "table's Bayes head shape differs from the destination type's"
            }
            Self::MapCapacity { .. } => {
                "table's recalibration map has more knots than the destination type holds"
            }
            Self::ObjectnessMismatch { .. } => {
                "table's objectness feature differs from the destination type's"
            }
            Self::Malformed => "table body does not follow the mlmap format",
            Self::Invalid(_) => "table breaks an invariant",
        }
    }
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Truncated | Self::NotATable | Self::Corrupted | Self::Malformed => {
                f.write_str(self.message())
            }
            Self::UnsupportedVersion { found } => write!(
                f,
                "table format version {found} is not supported (this build reads versions 1 to {})",
                crate::FORMAT_VERSION
            ),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "table has {} classes, {} ML bins and {} MAP bins; expected {}, {} and {}",
                found.0, found.1, found.2, expected.0, expected.1, expected.2
            ),
            Self::BayesShapeMismatch { expected, found } => write!(
                f,
                "table has a Bayes head of {} bins and {} categories; expected {} and {} (0 and 0: none)",
                found.0, found.1, expected.0, expected.1
            ),
            Self::MapCapacity { head, capacity, found } => write!(
                f,
                "table has a recalibration map of {found} knots for the {head} head; the table type holds {capacity}"
            ),
            Self::ObjectnessMismatch { found: true } => f.write_str(
                "table has the objectness feature; the table type has no room for it"
            ),
            Self::ObjectnessMismatch { found: false } => f.write_str(
                "table has no objectness feature; the table type requires one"
            ),
            Self::Invalid(e) => write!(f, "invalid table: {e}"),
        }
    }
}

impl core::error::Error for DecodeError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Invalid(e) => Some(e),
            _ => None,
        }
    }
}

impl From<TableError> for DecodeError {
    fn from(e: TableError) -> Self {
        Self::Invalid(e)
    }
}

/// Why a table could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EncodeError {
    /// The output buffer is too small; `MAX_ENCODED_LEN` bytes always suffice.
    BufferTooSmall,
}

impl EncodeError {
    /// The one sentence describing the variant.
    pub const fn message(self) -> &'static str {
        match self {
            Self::BufferTooSmall => "output buffer is too small for the table",
        }
    }
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.message())
    }
}

impl core::error::Error for EncodeError {}

/// Why one detection could not be scored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum InferError {
    /// A logit is NaN.
    NanLogit {
        /// Index of the first NaN logit.
        class: u16,
    },
    /// The objectness is NaN or outside `[0, 1]`.
    Objectness,
    /// The logit slice or the output slice does not have one entry per class.
    Length,
    /// Evidence or lambda given to `scores_from_evidence` is out of range.
    Evidence,
    /// The Bayes head was asked for, and the table has none (it was fitted with
    /// `--no-bayes`, or is a version-1 table).
    NoBayesHead,
    /// The open head was asked for, and the table has none (it has no Bayes head, or is
    /// a version-1 or version-2 table).
    NoOpenHead,
    /// A quantized logit is outside the code range of the quantized table (an int8
    /// section given a code above 127 or below -128).
    CodeRange {
        /// Index of the first such code.
        class: u16,
    },
    /// A score given to a conformal set is NaN.
    NanScore {
        /// Index of the first NaN score.
        class: u16,
    },
    /// Quantized codes of another width than the section's (`i16` codes given to an
    /// 8-bit section, or `i8` codes to a 16-bit one).
    CodeWidth {
        /// Bits per code of the section.
        expected: u8,
        /// Bits per code given.
        found: u8,
    },
}

impl InferError {
    /// The one sentence describing the variant, without its fields.
    pub const fn message(self) -> &'static str {
        match self {
            Self::NanLogit { .. } => "a logit is NaN",
            Self::Objectness => "objectness is NaN or outside [0, 1]",
            Self::Length => "logits or output do not have one entry per class",
            Self::Evidence => "evidence is not finite and >= 0, or lambda is out of range",
            Self::NoBayesHead => "the table has no Bayes head",
            Self::NoOpenHead => "the table has no open head",
            Self::CodeRange { .. } => "a quantized logit is outside the section's code range",
            Self::NanScore { .. } => "a score is NaN",
            Self::CodeWidth { .. } => "the codes' width is not the quantized section's",
        }
    }
}

impl fmt::Display for InferError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::NanLogit { class } => write!(f, "logit of class {class} is NaN"),
            Self::Objectness
            | Self::Length
            | Self::Evidence
            | Self::NoBayesHead
            | Self::NoOpenHead => f.write_str(self.message()),
            Self::CodeRange { class } => write!(
                f,
                "quantized logit of class {class} is outside the section's code range"
            ),
            Self::NanScore { class } => write!(f, "score of class {class} is NaN"),
            Self::CodeWidth { expected, found } => write!(
                f,
                "the codes are {found}-bit and the quantized section's are {expected}-bit"
            ),
        }
    }
}

impl core::error::Error for InferError {}

/// Why a batch could not be scored completely.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BatchError {
    /// The input and output slices have different lengths; nothing was written.
    LengthMismatch,
    /// Row `index` is invalid. Rows before it were written, rows from it on were not.
    Row {
        /// Index of the first invalid row.
        index: usize,
        /// What is wrong with it.
        error: InferError,
    },
}

impl BatchError {
    /// The one sentence describing the variant, without its fields.
    pub const fn message(self) -> &'static str {
        match self {
            Self::LengthMismatch => "logits, objectness and output slices differ in length",
            Self::Row { .. } => "a row of the batch is invalid",
        }
    }
}

impl fmt::Display for BatchError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::LengthMismatch => f.write_str(self.message()),
            Self::Row { index, error } => write!(f, "row {index}: {error}"),
        }
    }
}

impl core::error::Error for BatchError {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Row { error, .. } => Some(error),
            Self::LengthMismatch => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::format;
    use std::string::ToString;

    use super::*;

    /// The messages that spell out constants as `Display` would format them.
    #[test]
    fn messages_quote_the_constants_they_name() {
        let t = format!(
            "open head: the temperature is not in [{:e}, {:e}]",
            crate::MIN_TEMPERATURE,
            crate::MAX_TEMPERATURE
        );
        assert_eq!(TableError::Temperature.message(), t);
        let e = format!(
            "open head: epsilon is neither 0 nor in [{:e}, {:e}]",
            f32::MIN_POSITIVE,
            crate::MAX_EPSILON
        );
        assert_eq!(TableError::Epsilon.message(), e);
    }

    /// A variant without fields displays exactly its message.
    #[test]
    fn display_of_a_variant_without_fields_is_its_message() {
        for e in [
            TableError::ClassCount,
            TableError::BayesShape,
            TableError::Temperature,
            TableError::Epsilon,
        ] {
            assert_eq!(e.to_string(), e.message());
        }
        for e in [
            DecodeError::Truncated,
            DecodeError::NotATable,
            DecodeError::Corrupted,
            DecodeError::Malformed,
        ] {
            assert_eq!(e.to_string(), e.message());
        }
        for e in [
            InferError::Objectness,
            InferError::Length,
            InferError::Evidence,
            InferError::NoBayesHead,
            InferError::NoOpenHead,
        ] {
            assert_eq!(e.to_string(), e.message());
        }
        assert_eq!(
            EncodeError::BufferTooSmall.to_string(),
            EncodeError::BufferTooSmall.message()
        );
        assert_eq!(
            BatchError::LengthMismatch.to_string(),
            BatchError::LengthMismatch.message()
        );
    }
}
