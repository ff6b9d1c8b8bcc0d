//! Error details of a decode: the field, head and class a failure is about, written
//! into a caller's `mlmap_error_t` (no global state).

use core::ffi::c_char;
use core::mem::size_of;

use mlmap::{BodyPart, DecodeError, Head, TableError};

use super::arena::Failure;
use super::mlmap_status_t::{self, *};
use super::{check_ptr, overlap};

/// What part of a table a decode failure is about (`mlmap_error_t.field`).
///
/// Values are stable; `mlmap_field_str()` names each.
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum mlmap_field_t {
    /// No field: success, or a failure of the whole input (magic, CRC, version, a body
    /// whose parts all parse but one is not in its shortest encoding) or of an
    /// argument.
    MLMAP_FIELD_NONE = 0,
    /// A histogram's edges (`head`, `class_index`).
    MLMAP_FIELD_EDGES = 1,
    /// A histogram's frequencies (`head`, `class_index`).
    MLMAP_FIELD_FREQUENCIES = 2,
    /// A histogram's bin count (`head`, `class_index`).
    MLMAP_FIELD_BIN_COUNT = 3,
    /// A prior's mean (`class_index`).
    MLMAP_FIELD_MEAN = 4,
    /// A prior's variance (`class_index`).
    MLMAP_FIELD_VARIANCE = 5,
    /// A head's smoothing lambda (`head`).
    MLMAP_FIELD_LAMBDA = 6,
    /// A class name breaks the naming rule (`class_index`).
    MLMAP_FIELD_NAME = 7,
    /// A class name repeats an earlier one (`class_index`).
    MLMAP_FIELD_DUPLICATE_NAME = 8,
    /// The number of classes.
    MLMAP_FIELD_CLASS_COUNT = 9,
    /// A Bayes category without training rows (`class_index` is the category).
    MLMAP_FIELD_CATEGORY_ROWS = 10,
    /// The Bayes head's shape (categories, sequence lengths, or above the build's
    /// maximum).
    MLMAP_FIELD_BAYES_SHAPE = 11,
    /// The open head's temperature.
    MLMAP_FIELD_TEMPERATURE = 12,
    /// The open head's epsilon.
    MLMAP_FIELD_EPSILON = 13,
    /// A recalibration map (`head`).
    MLMAP_FIELD_MAP = 14,
    /// The shape (classes, bins) is above what the storage or the build holds.
    MLMAP_FIELD_SHAPE = 15,
    /// The objectness feature.
    MLMAP_FIELD_OBJECTNESS = 16,
    /// The storage is smaller than the table needs (`needed`).
    MLMAP_FIELD_STORAGE = 17,
    /// A quantized class's scale (`class_index`).
    MLMAP_FIELD_SCALE = 18,
    /// A quantized class's zero point (`class_index`).
    MLMAP_FIELD_ZERO_POINT = 19,
    /// A quantized class's (or logit's) window of codes (`class_index`).
    MLMAP_FIELD_CODE_WINDOW = 20,
    /// A quantized code's bin index (`class_index`: the class or logit).
    MLMAP_FIELD_BIN_INDEX = 21,
    /// A quantized mass (`class_index`).
    MLMAP_FIELD_MASS = 22,
    /// A quantized Bayes log-term, log prior or log lambda (`class_index`: the logit or
    /// category, 0 for the header's).
    MLMAP_FIELD_LOG_TERM = 23,
    /// A quantized open head's unknown log-score.
    MLMAP_FIELD_LOG_UNKNOWN = 24,
    /// The checksum of the table a quantized section follows is not the one it was
    /// computed from.
    MLMAP_FIELD_TABLE_CRC = 25,
    /// Malformed: the table body ends inside, or breaks the syntax of, the settings.
    MLMAP_FIELD_SETTINGS = 26,
    /// Malformed: a class record (`class_index`; K when a record follows the K
    /// announced).
    MLMAP_FIELD_CLASS_RECORD = 27,
    /// Malformed: the Bayes head's data (lambda, rows, axes, log-terms).
    MLMAP_FIELD_BAYES_DATA = 28,
    /// Malformed: the open head's parameters.
    MLMAP_FIELD_OPEN_PARAMS = 29,
    /// Malformed: bytes left over after the last part.
    MLMAP_FIELD_TRAILING_BYTES = 30,
    /// Malformed: the header (the Bayes shape after the fixed fields), or a body
    /// shorter than the header's shape.
    MLMAP_FIELD_HEADER = 31,
}

use mlmap_field_t::*;

/// The details of a status: which field, head and class a decode failure is about.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct mlmap_error_t {
    /// The status the call returned.
    pub status: mlmap_status_t,
    /// The field the failure is about (`MLMAP_FIELD_NONE` for none).
    pub field: mlmap_field_t,
    /// The head: 0 ML, 1 MAP, 2 Bayes, 3 open; -1 for none.
    pub head: i32,
    /// The class (for `MLMAP_FIELD_CATEGORY_ROWS` the Bayes category); -1 for none.
    pub class_index: i32,
    /// Bytes of arena the table needs, when known (0 otherwise): set on success and
    /// with `MLMAP_ERR_STORAGE_TOO_SMALL`.
    pub needed: usize,
}

/// The code of a head in `mlmap_error_t.head`.
fn head_code(h: Head) -> i32 {
    match h {
        Head::Ml => 0,
        Head::Map => 1,
        Head::Bayes => 2,
        Head::Open => 3,
    }
}

/// The field, head and class of the part where a malformed table stops following the
/// format.
pub(crate) fn locate_part(part: BodyPart) -> (mlmap_field_t, i32, i32) {
    match part {
        BodyPart::Header | BodyPart::Length => (MLMAP_FIELD_HEADER, -1, -1),
        BodyPart::Settings => (MLMAP_FIELD_SETTINGS, -1, -1),
        BodyPart::Class { index } => (MLMAP_FIELD_CLASS_RECORD, -1, i32::from(index)),
        BodyPart::Bayes => (MLMAP_FIELD_BAYES_DATA, 2, -1),
        BodyPart::Objectness => (MLMAP_FIELD_OBJECTNESS, 2, -1),
        BodyPart::Open => (MLMAP_FIELD_OPEN_PARAMS, 3, -1),
        BodyPart::Maps => (MLMAP_FIELD_MAP, -1, -1),
        BodyPart::Trailing => (MLMAP_FIELD_TRAILING_BYTES, -1, -1),
        _ => (MLMAP_FIELD_NONE, -1, -1),
    }
}

/// The field, head and class of a decode error.
pub(crate) fn locate(e: DecodeError) -> (mlmap_field_t, i32, i32) {
    let c = i32::from;
    match e {
        DecodeError::ShapeMismatch { .. } => (MLMAP_FIELD_SHAPE, -1, -1),
        DecodeError::BayesShapeMismatch { .. } => (MLMAP_FIELD_BAYES_SHAPE, -1, -1),
        DecodeError::MapCapacity { head, .. } => (MLMAP_FIELD_MAP, head_code(head), -1),
        DecodeError::ObjectnessMismatch { .. } => (MLMAP_FIELD_OBJECTNESS, -1, -1),
        DecodeError::Invalid(t) => match t {
            TableError::Edges { head, class } => (MLMAP_FIELD_EDGES, head_code(head), c(class)),
            TableError::Frequencies { head, class } => {
                (MLMAP_FIELD_FREQUENCIES, head_code(head), c(class))
            }
            TableError::BinCount { head, class } => {
                (MLMAP_FIELD_BIN_COUNT, head_code(head), c(class))
            }
            TableError::Mean { class } => (MLMAP_FIELD_MEAN, -1, c(class)),
            TableError::Variance { class } => (MLMAP_FIELD_VARIANCE, -1, c(class)),
            TableError::Lambda { head } => (MLMAP_FIELD_LAMBDA, head_code(head), -1),
            TableError::Name { class, .. } => (MLMAP_FIELD_NAME, -1, c(class)),
            TableError::DuplicateName { class } => (MLMAP_FIELD_DUPLICATE_NAME, -1, c(class)),
            TableError::ClassCount => (MLMAP_FIELD_CLASS_COUNT, -1, -1),
            TableError::CategoryRows { class } => (MLMAP_FIELD_CATEGORY_ROWS, -1, c(class)),
            TableError::BayesShape => (MLMAP_FIELD_BAYES_SHAPE, -1, -1),
            TableError::Temperature => (MLMAP_FIELD_TEMPERATURE, 3, -1),
            TableError::Epsilon => (MLMAP_FIELD_EPSILON, 3, -1),
            TableError::Map { head, .. } => (MLMAP_FIELD_MAP, head_code(head), -1),
            _ => (MLMAP_FIELD_NONE, -1, -1),
        },
        _ => (MLMAP_FIELD_NONE, -1, -1),
    }
}

/// The status of `r`, written with its details into `detail` when it is not NULL
/// (`MLMAP_ERR_MISALIGNED` for a misaligned one, `MLMAP_ERR_OVERLAP` for one that
/// overlaps a region of the call, and nothing written).
///
/// # Safety
///
/// `detail` is NULL or points to a writable `mlmap_error_t`.
pub(crate) unsafe fn report(
    detail: *mut mlmap_error_t,
    regions: &[(usize, usize)],
    r: Result<usize, Failure>,
) -> mlmap_status_t {
    let value = match r {
        Ok(needed) => mlmap_error_t {
            status: MLMAP_OK,
            field: MLMAP_FIELD_NONE,
            head: -1,
            class_index: -1,
            needed,
        },
        Err(f) => {
            let (field, head, class_index) = f.at;
            mlmap_error_t {
                status: f.status,
                field,
                head,
                class_index,
                needed: f.needed,
            }
        }
    };
    if detail.is_null() {
        return value.status;
    }
    if let Err(s) = check_ptr(detail) {
        return s;
    }
    let d = (detail as usize, size_of::<mlmap_error_t>());
    if regions.iter().any(|&(a, n)| overlap(d.0, d.1, a, n)) {
        return MLMAP_ERR_OVERLAP;
    }
    // SAFETY: non-NULL, aligned, the caller's, disjoint from the call's other memory.
    unsafe { detail.write(value) };
    value.status
}

/// The name of a field of ::mlmap_error_t, as a static NUL-terminated string (never
/// NULL; an unknown value gives "unknown field").
///
/// @param field A `mlmap_error_t.field`.
/// @return The name, e.g. "histogram edges".
#[no_mangle]
pub extern "C" fn mlmap_field_str(field: i32) -> *const c_char {
    let s: &'static core::ffi::CStr = match field {
        0 => c"none",
        1 => c"histogram edges",
        2 => c"histogram frequencies",
        3 => c"histogram bin count",
        4 => c"prior mean",
        5 => c"prior variance",
        6 => c"smoothing lambda",
        7 => c"class name",
        8 => c"duplicate class name",
        9 => c"number of classes",
        10 => c"Bayes category rows",
        11 => c"Bayes head shape",
        12 => c"open head temperature",
        13 => c"open head epsilon",
        14 => c"recalibration map",
        15 => c"table shape",
        16 => c"objectness feature",
        17 => c"storage size",
        18 => c"quantized scale",
        19 => c"quantized zero point",
        20 => c"quantized window of codes",
        21 => c"quantized bin index",
        22 => c"quantized mass",
        23 => c"quantized Bayes log-term",
        24 => c"quantized open head unknown log-score",
        25 => c"checksum of the table a section follows",
        26 => c"settings (malformed)",
        27 => c"class record (malformed)",
        28 => c"Bayes head data (malformed)",
        29 => c"open head parameters (malformed)",
        30 => c"bytes after the last part (malformed)",
        31 => c"header (malformed)",
        _ => c"unknown field",
    };
    s.as_ptr()
}
