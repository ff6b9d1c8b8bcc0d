//! The C API of mlmap: decode a table into storage the caller owns, score detections with
//! the ML, MAP, Bayes and open heads, and take the tie-safe decision. `include/mlmap.h` is
//! generated from this file by cbindgen; every doc comment here is a Doxygen comment
//! there.
//!
//! Rules every function keeps: it never allocates, never panics and never aborts; it
//! checks every pointer (NULL, alignment) and every length before touching memory, and
//! returns an [`mlmap_status_t`]; it writes its outputs only on success (batches: the rows
//! before a failing row).
//!
//! Aliasing (docs/DESIGN.md §5.1): no output may overlap the table storage the library
//! uses, and no two outputs may overlap each other (`MLMAP_ERR_OVERLAP`, nothing
//! written). A single-detection call copies its K logits before writing, so its scores
//! may overlap the logits in any way; a batch cannot copy all of its rows, so its scores
//! must either be exactly the logits (`out == logits`: each row is read before it is
//! overwritten) or not overlap them, and must not overlap the objectness
//! (`MLMAP_ERR_OVERLAP` otherwise). Every other call reads its inputs whole before it
//! writes its one output.
#![cfg_attr(not(feature = "std"), no_std)]
#![deny(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]
#![allow(non_camel_case_types)]
// The doc comments are the header's Doxygen comments: `@param[out]` is not a Rust link.
#![allow(rustdoc::broken_intra_doc_links)]
#![allow(clippy::missing_safety_doc)] // every entry point documents its contract in prose
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

use core::ffi::c_char;
use core::mem::{align_of, size_of};
use core::ptr;

use mlmap::{decide, DecodeError, EdgeMode, Head, InferError, Libm, TableError, UpperTail};

mod limits {
    include!(concat!(env!("OUT_DIR"), "/limits.rs"));
}
mod arena;
mod conformal;
mod decode;
mod detail;
mod monitor;
pub use conformal::*;
pub use decode::*;
pub use detail::*;
pub use monitor::*;

use arena::{table_ref, View};
use limits::{FAST_CLASSES, MAX_BINS, MAX_BINS_BAYES, MAX_CATEGORIES, MAX_CLASSES};

/// `MLMAP_TABLE_SIZE` of the header: bytes of a `mlmap_table_t`, an arena with room
/// for any table of the build's maximum shape (`classes`, `bins` in the ML and MAP heads,
/// `bins_bayes` per logit in the Bayes head, 0 for none) with every part at its largest:
/// a map of 32 knots per head and the objectness feature. The header computes the same
/// formula; the assertion below checks that it bounds the arena's layout.
#[cfg_attr(not(test), allow(dead_code))]
const fn table_bytes(classes: usize, bins: usize, bins_bayes: usize) -> usize {
    let p = size_of::<usize>();
    (1136
        + 32 * p
        + classes * (112 + 8 * p + 8 * bins)
        + (classes + 1) * (12 + 4 * (classes + 1) * bins_bayes))
        .div_ceil(8)
        * 8
}

/// The shape of the largest table a `mlmap_table_t` holds.
const MAX_SHAPE: mlmap::lent::StorageShape = mlmap::lent::StorageShape {
    classes: MAX_CLASSES,
    bins_ml: MAX_BINS,
    bins_map: MAX_BINS,
    bins_bayes: MAX_BINS_BAYES,
    categories: MAX_CATEGORIES,
    knots: [mlmap::MAX_KNOTS; 4],
    objectness: MAX_BINS_BAYES > 0,
};

/// Bytes of a `mlmap_table_t` the library uses: the arena of [`MAX_SHAPE`].
fn max_table_bytes() -> usize {
    arena::layout(&MAX_SHAPE).map_or(usize::MAX, |l| l.size)
}

/// Alignment of `mlmap_table_t` in bytes.
pub const MLMAP_TABLE_ALIGN: usize = 8;

/// Longest class name in bytes, without the terminating NUL.
pub const MLMAP_NAME_MAX: usize = 31;
const _: () = assert!(MLMAP_NAME_MAX == mlmap::NAME_MAX);

/// A decoded table: an arena (a `mlmap_table_t`, or exactly the bytes the table needs,
/// see `mlmap_table_init`), used through a pointer to it. Only the library reads or
/// writes its contents.
pub struct mlmap_table_t {
    _opaque: [u64; 0],
}

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
    /// a conformal section: magic MLMS).
    MLMAP_ERR_NO_SECTION = 27,
    /// A section breaks its format or does not belong to the table (another shape or
    /// table CRC, a window of 0, a threshold or share out of range).
    MLMAP_ERR_INVALID_SECTION = 28,
    /// The conformal storage holds no conformal handle (mlmap_conformal_init() did not
    /// succeed on it).
    MLMAP_ERR_NO_CONFORMAL = 29,
    /// The table storage was copied or moved after its decode: it holds pointers into
    /// itself, so only the storage decoded into is a table (decode again instead).
    MLMAP_ERR_MOVED = 30,
}

use mlmap_status_t::*;

/// Statuses in code order (tests and `mlmap_status_str`).
#[doc(hidden)]
pub const ALL_STATUSES: [mlmap_status_t; 31] = [
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
            _ => MLMAP_ERR_LENGTH,
        }
    }
}

/// The maximum shape this library was built for, and the storage it needs.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct mlmap_limits_t {
    /// `MLMAP_MAX_CLASSES` of the library's build.
    pub max_classes: usize,
    /// `MLMAP_MAX_BINS` of the library's build (ML and MAP heads).
    pub max_bins: usize,
    /// `MLMAP_MAX_BINS_BAYES` of the library's build (0: no Bayes head).
    pub max_bins_bayes: usize,
    /// Bytes of table storage the library uses (at most `MLMAP_TABLE_SIZE`).
    pub table_size: usize,
}

/// The shape of a decoded table.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct mlmap_shape_t {
    /// Number of classes K (the length of every logit and score vector).
    pub classes: usize,
    /// Bins of the ML head's histograms.
    pub bins_ml: usize,
    /// Bins of the MAP head's histograms.
    pub bins_map: usize,
    /// Bins per logit of the Bayes head; 0 when the table has none.
    pub bins_bayes: usize,
    /// Categories of the Bayes head: K, or K + 1 with `background`; 0 without a head.
    pub categories: usize,
}

/// The hyper-parameters and policies of a decoded table.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct mlmap_settings_t {
    /// Additive smoothing of the ML head.
    pub lambda_ml: f32,
    /// Additive smoothing of the MAP head.
    pub lambda_map: f32,
    /// Smoothing of the Bayes head; 0 when the table has none.
    pub lambda_bayes: f32,
    /// Above the last edge: 0 = likelihood 0 (the paper's), 1 = the last bin's.
    pub upper_tail: i32,
    /// How the fit placed the edges: 0 = numpy's linspace, 1 = MATLAB's (informational).
    pub edge_mode: i32,
    /// The open head's temperature `T` (docs/DESIGN.md §1.8), in [1e-6, 1e6]; 0 when
    /// the table has no open head.
    pub temperature: f32,
    /// The open head's prior weight `epsilon` of the unknown category: 0 (no unknown
    /// category) or in [2^-126, 1e30]; 0 also when the table has no open head (tell
    /// the two apart by `temperature`).
    pub epsilon: f32,
}

/// Checks a pointer for NULL and alignment.
#[inline(always)]
fn check_ptr<T>(p: *const T) -> Result<(), mlmap_status_t> {
    if p.is_null() {
        Err(MLMAP_ERR_NULL_POINTER)
    } else if !p.is_aligned() {
        Err(MLMAP_ERR_MISALIGNED)
    } else {
        Ok(())
    }
}

/// The view of a decoded table.
///
/// # Safety
///
/// `table` is NULL or points to an arena that is zeroed or was passed to a decode.
#[inline(always)]
unsafe fn view<'a>(table: *const mlmap_table_t) -> Result<&'a View<'a>, mlmap_status_t> {
    // SAFETY: forwarded contract.
    unsafe { table_ref(table) }.map(|(v, _)| v)
}

/// Bytes of the arena at `table` that its table uses (the tag's 8 when it holds none).
#[inline(always)]
fn table_len(table: *const mlmap_table_t) -> usize {
    // SAFETY: every caller passes a table pointer it was given, checked by `view` first.
    unsafe { table_ref(table) }.map_or(8, |(_, used)| used)
}

/// Writes `value` through an output pointer that has no table storage to overlap.
#[inline(always)]
unsafe fn put<T>(out: *mut T, value: T) -> Result<(), mlmap_status_t> {
    check_ptr(out)?;
    // SAFETY: non-NULL and aligned; the caller promises it points to a `T`.
    unsafe { out.write(value) };
    Ok(())
}

/// Refuses an output of `len` bytes at `out` that overlaps the part of the table
/// storage the library uses.
#[inline(always)]
fn outside_table<T>(
    out: *const T,
    len: usize,
    table: *const mlmap_table_t,
) -> Result<(), mlmap_status_t> {
    if overlap(out as usize, len, table as usize, table_len(table)) {
        Err(MLMAP_ERR_OVERLAP)
    } else {
        Ok(())
    }
}

/// Writes `value` through an output pointer, refusing one inside the table storage.
#[inline(always)]
unsafe fn put_outside<T>(
    out: *mut T,
    value: T,
    table: *const mlmap_table_t,
) -> Result<(), mlmap_status_t> {
    check_ptr(out)?;
    outside_table(out, size_of::<T>(), table)?;
    // SAFETY: forwarded contract.
    unsafe { put(out, value) }
}

/// The status of a result.
#[inline(always)]
fn status(r: Result<(), mlmap_status_t>) -> mlmap_status_t {
    match r {
        Ok(()) => MLMAP_OK,
        Err(s) => s,
    }
}

/// Reports the maximum table shape the library was built for and the storage it uses.
///
/// A program built with other `MLMAP_MAX_*` macros than the library can detect it
/// here at start-up (`mlmap_table_decode` also refuses storage that is too small).
///
/// @param[out] limits Receives the limits.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_limits(limits: *mut mlmap_limits_t) -> mlmap_status_t {
    #[cfg(feature = "canary")]
    #[allow(clippy::panic)] // the canary's one reachable panic, on purpose
    if core::hint::black_box(limits as usize) == 1 {
        panic!("canary");
    }
    let value = mlmap_limits_t {
        max_classes: MAX_CLASSES,
        max_bins: MAX_BINS,
        max_bins_bayes: MAX_BINS_BAYES,
        table_size: max_table_bytes(),
    };
    // SAFETY: the caller passes a pointer to a `mlmap_limits_t` or NULL.
    status(unsafe { put(limits, value) })
}

/// Gives the number of classes K of a decoded table.
///
/// @param table A decoded table.
/// @param[out] classes Receives K; must not lie in the table storage.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_class_count(
    table: *const mlmap_table_t,
    classes: *mut usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes a table storage and a `size_t` pointer (or NULL).
    status(unsafe { view(table).and_then(|v| put_outside(classes, v.k(), table)) })
}

/// Gives the shape of a decoded table.
///
/// @param table A decoded table.
/// @param[out] shape Receives the shape; must not overlap the table storage.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_shape(
    table: *const mlmap_table_t,
    shape: *mut mlmap_shape_t,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_class_count`.
    status(unsafe {
        view(table).and_then(|v| {
            let bayes = v.bayes();
            put_outside(
                shape,
                mlmap_shape_t {
                    classes: v.k(),
                    bins_ml: v.bins_ml(),
                    bins_map: v.bins_map(),
                    bins_bayes: bayes.map_or(0, |b| b.bins()),
                    categories: bayes.map_or(0, |b| b.categories()),
                },
                table,
            )
        })
    })
}

/// Gives the settings of a decoded table.
///
/// @param table A decoded table.
/// @param[out] settings Receives the settings; must not overlap the table storage.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_settings(
    table: *const mlmap_table_t,
    settings: *mut mlmap_settings_t,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_class_count`.
    status(unsafe {
        view(table).and_then(|v| {
            let s = v.settings();
            let open = v.open();
            put_outside(
                settings,
                mlmap_settings_t {
                    lambda_ml: s.lambda_ml,
                    lambda_map: s.lambda_map,
                    lambda_bayes: v.bayes().map_or(0.0, |b| b.lambda()),
                    upper_tail: match s.upper_tail {
                        UpperTail::Zero => 0,
                        UpperTail::Clamp => 1,
                    },
                    edge_mode: match s.edge_mode {
                        EdgeMode::Linspace => 0,
                        EdgeMode::Matlab => 1,
                    },
                    temperature: open.map_or(0.0, |o| o.temperature()),
                    epsilon: open.map_or(0.0, |o| o.epsilon()),
                },
                table,
            )
        })
    })
}

/// Copies the name of class `class_index` into `buf` as a NUL-terminated UTF-8 string.
///
/// A buffer of `MLMAP_NAME_MAX + 1` bytes always suffices.
///
/// @param table A decoded table.
/// @param class_index The class, below K.
/// @param[out] buf Receives the name and a NUL; untouched on failure. The bytes it
///   would receive must not overlap the table storage.
/// @param buf_len Size of `buf` in bytes.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_CLASS_INDEX`, `MLMAP_ERR_BUFFER_TOO_SMALL`,
///   `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_class_name(
    table: *const mlmap_table_t,
    class_index: usize,
    buf: *mut c_char,
    buf_len: usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes a table storage and `buf_len` writable bytes at `buf`.
    status(unsafe { class_name(table, class_index, buf, buf_len) })
}

unsafe fn class_name(
    table: *const mlmap_table_t,
    class_index: usize,
    buf: *mut c_char,
    buf_len: usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let v = unsafe { view(table) }?;
    check_ptr(buf)?;
    let mut name = [0u8; MLMAP_NAME_MAX + 1];
    let src = v
        .class_name(class_index)
        .ok_or(MLMAP_ERR_CLASS_INDEX)?
        .as_bytes();
    let n = src.len();
    if n >= buf_len {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    outside_table(buf, n + 1, table)?;
    for (d, s) in name.iter_mut().zip(src) {
        *d = *s;
    }
    // SAFETY: `n + 1 <= buf_len` bytes are writable at `buf` and lie outside the table
    // storage (checked); `name` is a local array holding the name and at least one NUL
    // after it (`n <= MLMAP_NAME_MAX`).
    unsafe { ptr::copy_nonoverlapping(name.as_ptr(), buf.cast::<u8>(), n + 1) };
    Ok(())
}

/// Finds the class called `name` (`name_len` bytes, no NUL needed).
///
/// @param table A decoded table.
/// @param name The name's bytes.
/// @param name_len Number of bytes of the name.
/// @param[out] class_index Receives the class index; must not lie in the table
///   storage (it may overlap the name, which is read whole first).
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_TOO_LARGE`,
///   `MLMAP_ERR_NOT_FOUND`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_class_index(
    table: *const mlmap_table_t,
    name: *const c_char,
    name_len: usize,
    class_index: *mut usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes `name_len` readable bytes at `name`.
    status(unsafe { class_index_of(table, name, name_len, class_index) })
}

unsafe fn class_index_of(
    table: *const mlmap_table_t,
    name: *const c_char,
    name_len: usize,
    class_index: *mut usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let v = unsafe { view(table) }?;
    check_ptr(name)?;
    check_ptr(class_index)?;
    outside_table(class_index, size_of::<usize>(), table)?;
    if name_len > isize::MAX as usize {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    // SAFETY: non-NULL, `name_len` readable bytes (the caller's promise).
    let bytes = unsafe { core::slice::from_raw_parts(name.cast::<u8>(), name_len) };
    let found = core::str::from_utf8(bytes)
        .ok()
        .and_then(|s| v.class_index(s))
        .ok_or(MLMAP_ERR_NOT_FOUND)?;
    // SAFETY: checked above (outside the table too); the name was read whole, so it
    // may overlap the output.
    unsafe { put(class_index, found) }
}

/// Scores one detection with `K`, the table's class count, known at compile time: the
/// layer's loops then have constant trip counts, as for the fixed-size Rust `Table`.
#[inline(always)]
fn score_k<const K: usize>(
    v: &View<'_>,
    head: Head,
    x: &[f32],
    objectness: f32,
    out: &mut [f32],
) -> Result<(), InferError> {
    let (Some(x), Some(out)) = (x.get(..K), out.get_mut(..K)) else {
        return Err(InferError::Length);
    };
    let mut scratch = [0.0f32; K];
    match head {
        Head::Ml => v.ml_into(x, objectness, out, &mut scratch),
        Head::Map => v.map_into::<Libm>(x, objectness, out, &mut scratch),
        Head::Bayes | Head::Open => score_categories(v, head, x, objectness, out),
    }
}

/// The Bayes or the open head, with a scratch of one float per category, through
/// `TableView::score_into`: the backend `Table::bayes` and `Table::open` use
/// (`FastMath`), so C, Rust and `mlmap apply` give the same bits.
#[inline(always)]
fn score_categories(
    v: &View<'_>,
    head: Head,
    x: &[f32],
    objectness: f32,
    out: &mut [f32],
) -> Result<(), InferError> {
    let mut cats = [0.0f32; MAX_CLASSES + 1];
    v.score_into(head, x, objectness, out, &mut cats)
}

/// Scores one detection: logits `x` (K entries) into `out` (K entries).
#[inline(always)]
fn score(
    v: &View<'_>,
    head: Head,
    x: &[f32],
    objectness: f32,
    out: &mut [f32],
) -> Result<(), InferError> {
    // The class counts of FAST_CLASSES (MLMAP_FAST_CLASSES) run specialised code.
    macro_rules! dispatch {
        ($($k:literal)*) => {
            match x.len() {
                $($k if FAST_CLASSES.contains(&$k) => score_k::<$k>(v, head, x, objectness, out),)*
                _ => {
                    let mut scratch = [0.0f32; MAX_CLASSES];
                    let s = scratch.get_mut(..x.len()).unwrap_or(&mut []);
                    match head {
                        Head::Ml => v.ml_into(x, objectness, out, s),
                        Head::Map => v.map_into::<Libm>(x, objectness, out, s),
                        Head::Bayes | Head::Open => score_categories(v, head, x, objectness, out),
                    }
                }
            }
        };
    }
    dispatch!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// Whether the byte ranges `[a, a + a_len)` and `[b, b + b_len)` share a byte (an empty
/// range shares none).
#[inline(always)]
fn overlap(a: usize, a_len: usize, b: usize, b_len: usize) -> bool {
    // Both non-empty, and `a` in `[b, b + b_len)` or `b` in `[a, a + a_len)`, without
    // overflow.
    a_len != 0 && b_len != 0 && (a.wrapping_sub(b) < b_len || b.wrapping_sub(a) < a_len)
}

/// One detection through `head`: the checks of the C API around [`score`].
#[inline(always)]
unsafe fn detection(
    head: Head,
    table: *const mlmap_table_t,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let v = unsafe { view(table) }?;
    check_ptr(logits)?;
    check_ptr(out)?;
    let k = v.k();
    if n_logits != k {
        return Err(MLMAP_ERR_LENGTH);
    }
    if out_len < k {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    let bytes = k * size_of::<f32>();
    if overlap(out as usize, bytes, table as usize, table_len(table)) {
        return Err(MLMAP_ERR_OVERLAP);
    }
    if !overlap(out as usize, bytes, logits as usize, bytes) {
        // SAFETY: `k` readable floats at `logits` and `k <= out_len` writable ones at
        // `out` (the caller's promise), non-NULL and aligned (checked), disjoint from
        // each other and from the table (checked).
        let (x, o) = unsafe {
            (
                core::slice::from_raw_parts(logits, k),
                core::slice::from_raw_parts_mut(out, k),
            )
        };
        return Ok(score(&v, head, x, objectness, o)?);
    }
    // In place: the logits are copied first.
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: as above; `x` is a local array, and `out` no longer overlaps an input.
    unsafe {
        ptr::copy_nonoverlapping(logits, x.as_mut_ptr(), k);
        Ok(score(
            &v,
            head,
            x,
            objectness,
            core::slice::from_raw_parts_mut(out, k),
        )?)
    }
}

/// Rows of a batch through `head`.
#[allow(clippy::too_many_arguments)]
unsafe fn batch(
    head: Head,
    table: *const mlmap_table_t,
    logits: *const f32,
    rows: usize,
    n_logits: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let v = unsafe { view(table) }?;
    check_ptr(logits)?;
    check_ptr(out)?;
    if !objectness.is_null() {
        check_ptr(objectness)?;
    }
    if !done.is_null() {
        check_ptr(done)?;
    }
    let k = v.k();
    if n_logits != k {
        return Err(MLMAP_ERR_LENGTH);
    }
    match head {
        Head::Bayes if v.bayes().is_none() => return Err(MLMAP_ERR_NO_BAYES_HEAD),
        Head::Open if v.open().is_none() => return Err(MLMAP_ERR_NO_OPEN_HEAD),
        _ => {}
    }
    let total = rows.checked_mul(k).ok_or(MLMAP_ERR_TOO_LARGE)?;
    if total > isize::MAX as usize / size_of::<f32>() {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    if out_len < total {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    // Every pair that could alias, before anything is written. The scores may be
    // written exactly over the logits (row `r` is read before row `r` is written, and
    // no other row's logits are touched); any other overlap of the scores with an
    // input would feed scores back in as inputs of later rows.
    let bytes = total * size_of::<f32>();
    let os_bytes = if objectness.is_null() {
        0
    } else {
        rows * size_of::<f32>()
    };
    let done_bytes = if done.is_null() {
        0
    } else {
        size_of::<usize>()
    };
    let (o, d) = (out as usize, done as usize);
    let in_place = out.cast_const() == logits;
    if (!in_place && overlap(o, bytes, logits as usize, bytes))
        || overlap(o, bytes, objectness as usize, os_bytes)
        || overlap(d, done_bytes, o, bytes)
        || overlap(d, done_bytes, logits as usize, bytes)
        || overlap(d, done_bytes, objectness as usize, os_bytes)
    {
        return Err(MLMAP_ERR_OVERLAP);
    }
    outside_table(out, bytes, table)?;
    outside_table(done, done_bytes, table)?;
    if !done.is_null() {
        // SAFETY: non-NULL, aligned, the caller's `size_t`, overlapping nothing else.
        unsafe { done.write(0) };
    }
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    for r in 0..rows {
        let at = r * k;
        // SAFETY: row `r < rows` of `rows * k` readable floats at `logits`, and of as
        // many writable ones at `out`; one readable float per row at `objectness`. The
        // output overlaps neither the table, nor `done`, nor the objectness, and the
        // logits only when it is exactly them: then the row is copied out first.
        unsafe {
            let os = if objectness.is_null() {
                1.0
            } else {
                objectness.add(r).read()
            };
            let input: &[f32] = if in_place {
                ptr::copy_nonoverlapping(logits.add(at), x.as_mut_ptr(), k);
                x
            } else {
                core::slice::from_raw_parts(logits.add(at), k)
            };
            score(
                &v,
                head,
                input,
                os,
                core::slice::from_raw_parts_mut(out.add(at), k),
            )?;
            if !done.is_null() {
                done.write(r + 1);
            }
        }
    }
    Ok(())
}

/// Scores one detection with the ML head: `out[i] = OS (L_i + lambda) / sum_j (L_j +
/// lambda)` (docs/DESIGN.md §1.2); the scores sum to the objectness.
///
/// When the table holds a recalibration map for this head (docs/DESIGN.md §1.9), the
/// scores are those after it: the top score `t` becomes `g(t)`, the others keep their
/// ratio to it, and the sum is no longer bound to the objectness.
///
/// Bit for bit the scores of the Rust layer and of `mlmap apply` for the same table.
///
/// @param table A decoded table.
/// @param logits The detection's K logits (`±inf` allowed, NaN not).
/// @param n_logits Number of logits; must be K.
/// @param objectness The detection's objectness, in [0, 1] (1 if the detector has
///   none).
/// @param[out] out Receives the K scores; may overlap `logits` in any way (the K
///   logits are copied before any score is written), must not overlap the table
///   storage.
/// @param out_len Number of floats at `out`, at least K.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_LENGTH`, `MLMAP_ERR_BUFFER_TOO_SMALL`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NAN_LOGIT`, `MLMAP_ERR_OBJECTNESS`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_ml(
    table: *const mlmap_table_t,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes `n_logits` floats at `logits`, `out_len` at `out`.
    status(unsafe { detection(Head::Ml, table, logits, n_logits, objectness, out, out_len) })
}

/// Scores one detection with the MAP head: `out[i] = OS (L_i P_i + lambda) / sum_j
/// (L_j P_j + lambda)`, with the Gaussian prior `P` (docs/DESIGN.md §1.2).
///
/// When the table holds a recalibration map for this head (docs/DESIGN.md §1.9), the
/// scores are those after it: the top score `t` becomes `g(t)`, the others keep their
/// ratio to it, and the sum is no longer bound to the objectness.
///
/// Parameters and statuses as for `mlmap_ml`.
///
/// @param table A decoded table.
/// @param logits The detection's K logits.
/// @param n_logits Number of logits; must be K.
/// @param objectness The detection's objectness, in [0, 1].
/// @param[out] out Receives the K scores.
/// @param out_len Number of floats at `out`, at least K.
/// @return As `mlmap_ml`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_map(
    table: *const mlmap_table_t,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml`.
    status(unsafe { detection(Head::Map, table, logits, n_logits, objectness, out, out_len) })
}

/// Scores one detection with the Bayes head: `out[i] = OS p_i`, with `p` the
/// posterior over the categories given every logit (docs/DESIGN.md §1.6). With a
/// `background` category the scores sum to at most the objectness.
///
/// When the table holds a recalibration map for this head (docs/DESIGN.md §1.9), the
/// scores are those after it: the top score `t` becomes `g(t)`, the others keep their
/// ratio to it, and the sum is no longer bound to the objectness.
///
/// @param table A decoded table with a Bayes head.
/// @param logits The detection's K logits.
/// @param n_logits Number of logits; must be K.
/// @param objectness The detection's objectness, in [0, 1].
/// @param[out] out Receives the K scores.
/// @param out_len Number of floats at `out`, at least K.
/// @return As `mlmap_ml`, and `MLMAP_ERR_NO_BAYES_HEAD`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_bayes(
    table: *const mlmap_table_t,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml`.
    status(unsafe {
        detection(
            Head::Bayes,
            table,
            logits,
            n_logits,
            objectness,
            out,
            out_len,
        )
    })
}

/// Scores one detection with the open head (docs/DESIGN.md §1.8): `out[i] = OS q
/// softmax(z / T)_i`, the detector's own softmax at the table's temperature `T`, times
/// `q`, the probability that the detection is an object of a known class (the Bayes
/// head's categories against an `unknown` category of prior weight `epsilon`; see
/// `mlmap_settings` for `T` and `epsilon`). The scores sum to at most the objectness;
/// they order the classes as the logits do, so `mlmap_decide` on them answers the
/// largest logit (ties: the lowest index). With `epsilon = 0` and no `background`
/// category, `q = 1` and the scores are `OS softmax(z / T)`.
///
/// When the table holds a recalibration map for this head (docs/DESIGN.md §1.9), the
/// scores are those after it: the top score `t` becomes `g(t)`, the others keep their
/// ratio to it, and the sum is no longer bound to the objectness.
///
/// Bit for bit the scores of the Rust layer (`Table::open`) and of `mlmap apply`'s
/// `open_*` columns for the same table.
///
/// @param table A decoded table with an open head (format version 3 with a Bayes
///   head).
/// @param logits The detection's K logits (`±inf` allowed, NaN not).
/// @param n_logits Number of logits; must be K.
/// @param objectness The detection's objectness, in [0, 1].
/// @param[out] out Receives the K scores; may overlap `logits` in any way (the K
///   logits are copied before any score is written), must not overlap the table
///   storage.
/// @param out_len Number of floats at `out`, at least K.
/// @return As `mlmap_ml`, and `MLMAP_ERR_NO_OPEN_HEAD`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_open(
    table: *const mlmap_table_t,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml`.
    status(unsafe {
        detection(
            Head::Open,
            table,
            logits,
            n_logits,
            objectness,
            out,
            out_len,
        )
    })
}

/// Scores a batch with the ML head: row `r` of `logits` (row-major, `rows` x K) and
/// `objectness[r]` into row `r` of `out`, the head's recalibration map applied as in
/// `mlmap_ml` (every batch call gives the bits of its single-detection call).
///
/// Every argument is checked before anything is written: on a failed check nothing
/// is written, `*done` included. On a row that cannot be scored (NaN logit, bad
/// objectness) the rows before it are written, the others untouched, its status is
/// returned and `*done` is its index: resume at `*done + 1`.
///
/// Aliasing: the `rows * K` scores are either written exactly over the logits (`out
/// == logits`: each row is read before it is overwritten) or must not overlap them at
/// all; a batch does not copy its inputs, so a partial overlap (e.g. `out == logits +
/// K`) is refused with `MLMAP_ERR_OVERLAP`. The scores must not overlap `objectness`
/// nor the table storage, and `done` must not overlap the scores, the logits, the
/// objectness nor the table storage (`MLMAP_ERR_OVERLAP`).
///
/// @param table A decoded table.
/// @param logits `rows * n_logits` floats, row-major.
/// @param rows Number of detections (0 is allowed).
/// @param n_logits Logits per row; must be K.
/// @param objectness `rows` floats, or NULL for an objectness of 1 everywhere.
/// @param[out] out Receives `rows * K` scores; exactly `logits`, or disjoint from it.
/// @param out_len Number of floats at `out`, at least `rows * K`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As `mlmap_ml`, and `MLMAP_ERR_TOO_LARGE`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_ml_batch(
    table: *const mlmap_table_t,
    logits: *const f32,
    rows: usize,
    n_logits: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes the buffers described above.
    status(unsafe {
        batch(
            Head::Ml,
            table,
            logits,
            rows,
            n_logits,
            objectness,
            out,
            out_len,
            done,
        )
    })
}

/// Scores a batch with the MAP head; see `mlmap_ml_batch` (aliasing rules included).
///
/// @param table A decoded table.
/// @param logits `rows * n_logits` floats, row-major.
/// @param rows Number of detections.
/// @param n_logits Logits per row; must be K.
/// @param objectness `rows` floats, or NULL for 1 everywhere.
/// @param[out] out Receives `rows * K` scores.
/// @param out_len Number of floats at `out`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As `mlmap_ml_batch`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_map_batch(
    table: *const mlmap_table_t,
    logits: *const f32,
    rows: usize,
    n_logits: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml_batch`.
    status(unsafe {
        batch(
            Head::Map,
            table,
            logits,
            rows,
            n_logits,
            objectness,
            out,
            out_len,
            done,
        )
    })
}

/// Scores a batch with the Bayes head; see `mlmap_ml_batch` (aliasing rules included).
///
/// @param table A decoded table with a Bayes head.
/// @param logits `rows * n_logits` floats, row-major.
/// @param rows Number of detections.
/// @param n_logits Logits per row; must be K.
/// @param objectness `rows` floats, or NULL for 1 everywhere.
/// @param[out] out Receives `rows * K` scores.
/// @param out_len Number of floats at `out`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As `mlmap_ml_batch`, and `MLMAP_ERR_NO_BAYES_HEAD`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_bayes_batch(
    table: *const mlmap_table_t,
    logits: *const f32,
    rows: usize,
    n_logits: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml_batch`.
    status(unsafe {
        batch(
            Head::Bayes,
            table,
            logits,
            rows,
            n_logits,
            objectness,
            out,
            out_len,
            done,
        )
    })
}

/// Scores a batch with the open head; see `mlmap_ml_batch` (aliasing rules included).
///
/// @param table A decoded table with an open head.
/// @param logits `rows * n_logits` floats, row-major.
/// @param rows Number of detections.
/// @param n_logits Logits per row; must be K.
/// @param objectness `rows` floats, or NULL for 1 everywhere.
/// @param[out] out Receives `rows * K` scores.
/// @param out_len Number of floats at `out`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As `mlmap_ml_batch`, and `MLMAP_ERR_NO_OPEN_HEAD` (checked with the
///   arguments, before any row, even for 0 rows).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_open_batch(
    table: *const mlmap_table_t,
    logits: *const f32,
    rows: usize,
    n_logits: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_ml_batch`.
    status(unsafe {
        batch(
            Head::Open,
            table,
            logits,
            rows,
            n_logits,
            objectness,
            out,
            out_len,
            done,
        )
    })
}

/// The tie-safe decision (docs/DESIGN.md §1.7): the index of the largest score;
/// among equal largest scores, the one with the largest logit; among those, the
/// lowest index. Use it instead of a plain argmax: a detection that every histogram
/// calls "I don't know" gets equal scores, and the logits then keep the detector's
/// ranking.
///
/// A NaN anywhere in the scores (`MLMAP_ERR_NAN_SCORE`) or in the logits
/// (`MLMAP_ERR_NAN_LOGIT`) is an error, not a decision (docs/DESIGN.md §5.1); `±inf`
/// is compared as any other value.
///
/// @param scores The K scores of one detection.
/// @param logits The same detection's K logits.
/// @param k Number of scores and logits, at least 1.
/// @param[out] class_index Receives the decided class; may overlap the inputs (they
///   are read whole first).
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_LENGTH` (k = 0), `MLMAP_ERR_TOO_LARGE`, `MLMAP_ERR_NAN_SCORE`,
///   `MLMAP_ERR_NAN_LOGIT`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_decide(
    scores: *const f32,
    logits: *const f32,
    k: usize,
    class_index: *mut usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes `k` floats at `scores` and at `logits`.
    status(unsafe { decide_c(scores, logits, k, class_index) })
}

unsafe fn decide_c(
    scores: *const f32,
    logits: *const f32,
    k: usize,
    class_index: *mut usize,
) -> Result<(), mlmap_status_t> {
    check_ptr(scores)?;
    check_ptr(logits)?;
    check_ptr(class_index)?;
    if k == 0 {
        return Err(MLMAP_ERR_LENGTH);
    }
    if k > isize::MAX as usize / size_of::<f32>() {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    // SAFETY: `k` readable floats each (the caller's promise), non-NULL and aligned;
    // both are only read.
    let (s, l) = unsafe {
        (
            core::slice::from_raw_parts(scores, k),
            core::slice::from_raw_parts(logits, k),
        )
    };
    // No decision on NaN: the rule of §1.7 would answer a class (class 0 when every
    // score is NaN) that nothing supports.
    if s.iter().any(|v| v.is_nan()) {
        return Err(MLMAP_ERR_NAN_SCORE);
    }
    if l.iter().any(|v| v.is_nan()) {
        return Err(MLMAP_ERR_NAN_LOGIT);
    }
    let i = decide(s, l);
    // SAFETY: checked above; the inputs were read whole, so they may overlap the
    // output.
    unsafe { put(class_index, i) }
}

/// Decides a batch: `mlmap_decide` on each of `n` rows of K scores and K logits,
/// row-major (row `r` at `scores + r * k` and `logits + r * k`), the class of row `r`
/// into `classes[r]`. Stops at the first row with a NaN score or logit; the rows before
/// it are written.
///
/// @param scores `n * k` scores.
/// @param logits `n * k` logits.
/// @param n Number of rows (0: nothing to do).
/// @param k Classes per row, at least 1.
/// @param[out] classes Receives `n` class indexes; must not overlap the inputs.
/// @param classes_len Entries available at `classes`, at least `n`.
/// @param[out] done Receives the number of rows decided; may be NULL.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_LENGTH` (k = 0), `MLMAP_ERR_BUFFER_TOO_SMALL`, `MLMAP_ERR_TOO_LARGE`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NAN_SCORE`, `MLMAP_ERR_NAN_LOGIT` (row `*done`).
#[no_mangle]
pub unsafe extern "C" fn mlmap_decide_batch(
    scores: *const f32,
    logits: *const f32,
    n: usize,
    k: usize,
    classes: *mut usize,
    classes_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    if !done.is_null() {
        if !(done as usize).is_multiple_of(align_of::<usize>()) {
            return MLMAP_ERR_MISALIGNED;
        }
        // SAFETY: non-NULL and aligned; the caller passes a writable `size_t`.
        unsafe { *done = 0 };
    }
    // SAFETY: the caller passes `n * k` floats at `scores` and `logits` and
    // `classes_len` writable entries at `classes`.
    status(unsafe { decide_batch_c(scores, logits, n, k, classes, classes_len, done) })
}

unsafe fn decide_batch_c(
    scores: *const f32,
    logits: *const f32,
    n: usize,
    k: usize,
    classes: *mut usize,
    classes_len: usize,
    done: *mut usize,
) -> Result<(), mlmap_status_t> {
    check_ptr(scores)?;
    check_ptr(logits)?;
    check_ptr(classes)?;
    if k == 0 {
        return Err(MLMAP_ERR_LENGTH);
    }
    let total = n.checked_mul(k).ok_or(MLMAP_ERR_TOO_LARGE)?;
    if total > isize::MAX as usize / size_of::<f32>()
        || n > isize::MAX as usize / size_of::<usize>()
    {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    if classes_len < n {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    // The output is written row by row while the inputs are read: it must not overlap
    // them.
    let out_bytes = (classes as usize, n * size_of::<usize>());
    for input in [
        (scores as usize, total * size_of::<f32>()),
        (logits as usize, total * size_of::<f32>()),
    ] {
        if overlaps(out_bytes, input) {
            return Err(MLMAP_ERR_OVERLAP);
        }
    }
    for r in 0..n {
        // SAFETY: row `r` is inside the `n * k` floats of each input and entry `r` inside
        // `classes` (checked above).
        unsafe { decide_c(scores.add(r * k), logits.add(r * k), k, classes.add(r))? };
        if !done.is_null() {
            // SAFETY: checked by the caller's entry point (non-NULL, aligned).
            unsafe { *done = r + 1 };
        }
    }
    Ok(())
}

/// Whether two byte ranges `(start, len)` share a byte.
fn overlaps(a: (usize, usize), b: (usize, usize)) -> bool {
    a.1 > 0 && b.1 > 0 && a.0 < b.0.saturating_add(b.1) && b.0 < a.0.saturating_add(a.1)
}

/// The library's version, `"MAJOR.MINOR.PATCH"` (a static NUL-terminated string):
/// equal to the header's `MLMAP_VERSION_STRING` when header and library come from one
/// build.
#[no_mangle]
pub extern "C" fn mlmap_version() -> *const c_char {
    VERSION.as_ptr()
}

/// The crate's version as a C string.
const VERSION: &core::ffi::CStr =
    match core::ffi::CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes())
    {
        Ok(v) => v,
        Err(_) => c"unknown",
    };

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
        27 => c"input holds no section of this kind (monitor: magic MLMW; conformal: magic MLMS)",
        28 => c"a section breaks its format or belongs to another table",
        29 => c"the conformal storage holds no conformal handle",
        30 => c"the table storage was copied or moved after its decode (decode it again)",
        _ => c"unknown mlmap status",
    };
    s.as_ptr()
}

#[cfg(not(feature = "std"))]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    extern "C" {
        /// Defined nowhere: a panic path that survives optimisation makes the link of
        /// any program using the library fail on this symbol.
        fn mlmap_panic_path_reachable() -> !;
    }
    // SAFETY: never executed; a reachable call fails the link.
    unsafe { mlmap_panic_path_reachable() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `MLMAP_TABLE_SIZE` bounds the arena of the largest table of the build's shape,
    /// and of the default build's.
    #[test]
    fn the_table_type_holds_the_largest_arena() {
        let need = max_table_bytes();
        assert!(need <= table_bytes(MAX_CLASSES, MAX_BINS, MAX_BINS_BAYES));
        let default = mlmap::lent::StorageShape {
            classes: 16,
            bins_ml: 64,
            bins_map: 64,
            bins_bayes: 64,
            categories: 17,
            knots: [32; 4],
            objectness: true,
        };
        assert!(arena::layout(&default).unwrap().size <= table_bytes(16, 64, 64));
    }
}
