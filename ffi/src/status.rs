//! The statuses every function returns, and their descriptions.

use core::ffi::c_char;

use mlmap::{DecodeError, InferError, TableError};

/// The result of every function: `MLMAP_OK` or the reason for the failure.
///
/// Values are stable; `mlmap_status_str()` gives a one-line description of each.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum mlmap_status_t {
    /// Success.
    MLMAP_OK = 0,
    /// A pointer argument that must not be NULL is NULL.
    MLMAP_ERR_NULL_POINTER = 1,
    /// A pointer is not aligned for its type (`mlmap_table_t`: `MLMAP_TABLE_ALIGN`,
    /// `float`: 4, `size_t`: its own size).
    MLMAP_ERR_MISALIGNED = 2,
    /// The table storage is smaller than the library needs: the header's `MLMAP_MAX_*`
    /// macros differ from the library's build (see `mlmap_limits`).
    MLMAP_ERR_STORAGE_TOO_SMALL = 3,
    /// The table storage holds no table: never decoded into, or the last decode failed.
    MLMAP_ERR_NO_TABLE = 4,
    /// Memory that must be disjoint overlaps: an output (or the bytes to decode) and
    /// the table storage; two outputs; or a batch's scores and its inputs, other than
    /// scores written exactly over the logits (`out == logits`).
    MLMAP_ERR_OVERLAP = 5,
    /// Decode: the input is shorter than the smallest table.
    MLMAP_ERR_TRUNCATED = 6,
    /// Decode: the input does not start with the magic `MLMP`.
    MLMAP_ERR_NOT_A_TABLE = 7,
    /// Decode: the CRC-32 does not match the contents.
    MLMAP_ERR_CORRUPTED = 8,
    /// Decode: a format version this library does not read.
    MLMAP_ERR_UNSUPPORTED_VERSION = 9,
    /// Decode: more classes, ML bins or MAP bins than `MLMAP_MAX_CLASSES` and
    /// `MLMAP_MAX_BINS` allow. (A recalibration map with more knots than the storage
    /// holds would be this status too, but cannot occur: the storage holds a map of
    /// the format's maximum, 32 knots, for every head.)
    MLMAP_ERR_SHAPE_TOO_LARGE = 10,
    /// Decode: a Bayes head with more bins than `MLMAP_MAX_BINS_BAYES`.
    MLMAP_ERR_BAYES_SHAPE_TOO_LARGE = 11,
    /// Decode: the body does not follow the format.
    MLMAP_ERR_MALFORMED = 12,
    /// Decode: the body parsed, but a table invariant does not hold; this includes a
    /// recalibration map (docs/DESIGN.md §1.9) that breaks the knots' rule (2 to 32
    /// knots, from x = 0 to x = 1, x increasing, y in (0, 1] non-decreasing) or is for
    /// a head the table does not have.
    MLMAP_ERR_INVALID_TABLE = 13,
    /// Scoring or decision: a logit is NaN.
    MLMAP_ERR_NAN_LOGIT = 14,
    /// Scoring: the objectness is NaN or outside [0, 1].
    MLMAP_ERR_OBJECTNESS = 15,
    /// A count does not match: logits per detection other than the table's K, or a
    /// count of 0 where one is needed.
    MLMAP_ERR_LENGTH = 16,
    /// An output buffer is too short (scores: K per detection; names: the name and
    /// its NUL).
    MLMAP_ERR_BUFFER_TOO_SMALL = 17,
    /// The Bayes head was asked for and the table has none.
    MLMAP_ERR_NO_BAYES_HEAD = 18,
    /// A class index is not below K.
    MLMAP_ERR_CLASS_INDEX = 19,
    /// No class has the given name.
    MLMAP_ERR_NOT_FOUND = 20,
    /// A length is so large that it cannot describe memory (above `PTRDIFF_MAX`
    /// bytes).
    MLMAP_ERR_TOO_LARGE = 21,
    /// Decision: a score is NaN.
    MLMAP_ERR_NAN_SCORE = 22,
    /// The open head was asked for and the table has none (a version-1 or version-2
    /// table, or one without a Bayes head).
    MLMAP_ERR_NO_OPEN_HEAD = 23,
    /// Decode: the open head's temperature is not in [1e-6, 1e6] (a broken table
    /// invariant, reported on its own).
    MLMAP_ERR_OPEN_TEMPERATURE = 24,
    /// Decode: the open head's epsilon is neither 0 nor in [2^-126, 1e30] (a broken
    /// table invariant, reported on its own).
    MLMAP_ERR_OPEN_EPSILON = 25,
    /// The monitor storage holds no monitor (mlmap_monitor_init() did not succeed on it).
    MLMAP_ERR_NO_MONITOR = 26,
    /// The bytes hold no section of the kind asked for (a monitor section: magic MLMW;
    /// a conformal section: magic MLMS; a quantized section: magic MLMQ).
    MLMAP_ERR_NO_SECTION = 27,
    /// A section breaks its format or does not belong to the table (another shape or
    /// table CRC, a window of 0, a threshold or share out of range).
    MLMAP_ERR_INVALID_SECTION = 28,
    /// The conformal storage holds no conformal handle (mlmap_conformal_init() did not
    /// succeed on it).
    MLMAP_ERR_NO_CONFORMAL = 29,
    /// The table storage (or a quantized arena) was copied or moved after its decode:
    /// it holds pointers into itself, so only the storage decoded into is a table
    /// (decode again instead).
    MLMAP_ERR_MOVED = 30,
    /// Quantized scoring: codes of another width than the section's (an `_i8` call on
    /// a 16-bit section, or an `_i16` call on an 8-bit one).
    MLMAP_ERR_CODE_WIDTH = 31,
    /// A `head` argument is not one of the ::mlmap_head_t values.
    MLMAP_ERR_UNKNOWN_HEAD = 32,
    /// The quantized arena holds no quantized table (mlmap_qtable_init() did not
    /// succeed on it).
    MLMAP_ERR_NO_QTABLE = 33,
}

/// Statuses in code order (tests and `mlmap_status_str`).
#[doc(hidden)]
pub const ALL_STATUSES: [mlmap_status_t; 34] = [
    MLMAP_OK,
    MLMAP_ERR_NULL_POINTER,
    MLMAP_ERR_MISALIGNED,
    MLMAP_ERR_STORAGE_TOO_SMALL,
    MLMAP_ERR_NO_TABLE,
    MLMAP_ERR_OVERLAP,
    MLMAP_ERR_TRUNCATED,
    MLMAP_ERR_NOT_A_TABLE,
    MLMAP_ERR_CORRUPTED,
    MLMAP_ERR_UNSUPPORTED_VERSION,
    MLMAP_ERR_SHAPE_TOO_LARGE,
    MLMAP_ERR_BAYES_SHAPE_TOO_LARGE,
    MLMAP_ERR_MALFORMED,
    MLMAP_ERR_INVALID_TABLE,
    MLMAP_ERR_NAN_LOGIT,
    MLMAP_ERR_OBJECTNESS,
    MLMAP_ERR_LENGTH,
    MLMAP_ERR_BUFFER_TOO_SMALL,
    MLMAP_ERR_NO_BAYES_HEAD,
    MLMAP_ERR_CLASS_INDEX,
    MLMAP_ERR_NOT_FOUND,
    MLMAP_ERR_TOO_LARGE,
    MLMAP_ERR_NAN_SCORE,
    MLMAP_ERR_NO_OPEN_HEAD,
    MLMAP_ERR_OPEN_TEMPERATURE,
    MLMAP_ERR_OPEN_EPSILON,
    MLMAP_ERR_NO_MONITOR,
    MLMAP_ERR_NO_SECTION,
    MLMAP_ERR_INVALID_SECTION,
    MLMAP_ERR_NO_CONFORMAL,
    MLMAP_ERR_MOVED,
    MLMAP_ERR_CODE_WIDTH,
    MLMAP_ERR_UNKNOWN_HEAD,
    MLMAP_ERR_NO_QTABLE,
];

impl From<DecodeError> for mlmap_status_t {
    fn from(e: DecodeError) -> Self {
        match e {
            DecodeError::Truncated => MLMAP_ERR_TRUNCATED,
            DecodeError::NotATable => MLMAP_ERR_NOT_A_TABLE,
            DecodeError::Corrupted => MLMAP_ERR_CORRUPTED,
            DecodeError::UnsupportedVersion { .. } => MLMAP_ERR_UNSUPPORTED_VERSION,
            DecodeError::ShapeMismatch { .. } => MLMAP_ERR_SHAPE_TOO_LARGE,
            DecodeError::BayesShapeMismatch { .. } => MLMAP_ERR_BAYES_SHAPE_TOO_LARGE,
            DecodeError::Invalid(TableError::Temperature) => MLMAP_ERR_OPEN_TEMPERATURE,
            DecodeError::Invalid(TableError::Epsilon) => MLMAP_ERR_OPEN_EPSILON,
            DecodeError::Invalid(_) => MLMAP_ERR_INVALID_TABLE,
            // The storage has room for `MAX_KNOTS` knots per map, the most a valid map
            // has (more are `Invalid`), so this never happens in this library; were
            // it built with less room, the table would be too large for it.
            DecodeError::MapCapacity { .. } => MLMAP_ERR_SHAPE_TOO_LARGE,
            _ => MLMAP_ERR_MALFORMED,
        }
    }
}

impl From<InferError> for mlmap_status_t {
    fn from(e: InferError) -> Self {
        match e {
            InferError::NanLogit { .. } => MLMAP_ERR_NAN_LOGIT,
            InferError::Objectness => MLMAP_ERR_OBJECTNESS,
            InferError::NoBayesHead => MLMAP_ERR_NO_BAYES_HEAD,
            InferError::NoOpenHead => MLMAP_ERR_NO_OPEN_HEAD,
            InferError::NanScore { .. } => MLMAP_ERR_NAN_SCORE,
            InferError::CodeWidth { .. } => MLMAP_ERR_CODE_WIDTH,
            _ => MLMAP_ERR_LENGTH,
        }
    }
}

use mlmap_status_t::*;

/// A one-line English description of a status, as a static NUL-terminated string
/// (never NULL; an unknown value gives "unknown mlmap status").
///
/// @param status A value returned by any function of this API.
/// @return The description.
// A status that stands for one error of the layer is described by that error's
// `message()` (checked by `status_strings_are_the_layers_messages` in tests/same_bits.rs).
#[no_mangle]
pub extern "C" fn mlmap_status_str(status: i32) -> *const c_char {
    let s: &'static core::ffi::CStr = match status {
        0 => c"success",
        1 => c"a pointer argument is NULL",
        2 => c"a pointer is not aligned for its type",
        3 => c"the table storage is smaller than the library needs (MLMAP_MAX_* differ from the library's build)",
        4 => c"the table storage holds no decoded table",
        5 => c"memory that must be disjoint overlaps (an output and the table storage, two outputs, or a batch's scores and its inputs)",
        6 => c"input is too short to be an mlmap table",
        7 => c"input does not start with the mlmap magic `MLMP`",
        8 => c"table checksum does not match its contents",
        9 => c"table format version is not supported",
        10 => c"table has more classes or bins than MLMAP_MAX_CLASSES and MLMAP_MAX_BINS allow",
        11 => c"table's Bayes head has more bins than MLMAP_MAX_BINS_BAYES allows",
        12 => c"table body does not follow the mlmap format",
        13 => c"table breaks an invariant",
        14 => c"a logit is NaN",
        15 => c"objectness is NaN or outside [0, 1]",
        16 => c"a count does not match the table's number of classes, or is 0",
        17 => c"an output buffer is too short",
        18 => c"the table has no Bayes head",
        19 => c"class index is not below the number of classes",
        20 => c"no class has this name",
        21 => c"a length is too large to describe memory",
        22 => c"a score is NaN",
        23 => c"the table has no open head",
        24 => c"open head: the temperature is not in [1e-6, 1e6]",
        25 => c"open head: epsilon is neither 0 nor in [1.1754944e-38, 1e30]",
        26 => c"the monitor storage holds no monitor",
        27 => c"input holds no section of this kind (monitor: magic MLMW; conformal: magic MLMS; quantized: magic MLMQ)",
        28 => c"a section breaks its format or belongs to another table",
        29 => c"the conformal storage holds no conformal handle",
        30 => c"the table storage was copied or moved after its decode (decode it again)",
        31 => c"the codes' width is not the quantized section's",
        32 => c"head is not one of the MLMAP_HEAD_* values",
        33 => c"the quantized arena holds no quantized table",
        _ => c"unknown mlmap status",
    };
    s.as_ptr()
}
