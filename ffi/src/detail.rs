//! Error details of a decode: the field, head and class a failure is about, written
//! into a caller's `mlmap_error_t` (no global state).

use core::ffi::c_char;
use core::mem::size_of;

use mlmap::{DecodeError, Head, TableError};

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
    /// that does not parse: the parser reports no position) or of an argument.
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

/// The field, head and class of a decode error.
fn locate(e: DecodeError) -> (mlmap_field_t, i32, i32) {
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
            let (field, head, class_index) = match f.error {
                Some(e) => locate(e),
                None if f.status == MLMAP_ERR_STORAGE_TOO_SMALL => (MLMAP_FIELD_STORAGE, -1, -1),
                None => (MLMAP_FIELD_NONE, -1, -1),
            };
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
        _ => c"unknown field",
    };
    s.as_ptr()
}
