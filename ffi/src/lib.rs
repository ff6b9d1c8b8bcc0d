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
use core::mem::size_of;
use core::ptr;

mod limits {
    include!(concat!(env!("OUT_DIR"), "/limits.rs"));
}
mod arena;
mod conformal;
mod decide;
mod decode;
mod detail;
mod monitor;
mod quantized;
mod score;
mod status;
pub use conformal::*;
pub use decide::*;
pub use decode::*;
pub use detail::*;
pub use monitor::*;
pub use quantized::*;
pub use score::*;

use arena::{table_ref, View};
use limits::{MAX_BINS, MAX_BINS_BAYES, MAX_CATEGORIES, MAX_CLASSES};

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

use mlmap_status_t::*;
pub use status::*;

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

/// The memory of a batch of `rows` rows of K values, checked before anything is
/// written: `rows * k` scores at `out` (of `out_len` floats), inputs of `input_size`
/// bytes each at `input`, one objectness per row (or NULL), a `done` counter (or
/// NULL). The scores may be written exactly over the inputs only when `in_place`
/// (row `r` is read before row `r` is written, and no other row's inputs are
/// touched); any other overlap of the scores with an input would feed scores back in
/// as inputs of later rows. Returns the bytes of the scores and of `done`.
#[allow(clippy::too_many_arguments)]
fn batch_memory(
    rows: usize,
    k: usize,
    input: (usize, usize),
    in_place: bool,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> Result<(usize, usize), mlmap_status_t> {
    let total = rows.checked_mul(k).ok_or(MLMAP_ERR_TOO_LARGE)?;
    if total > isize::MAX as usize / size_of::<f32>() {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    if out_len < total {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    let bytes = total * size_of::<f32>();
    let (x, in_bytes) = (input.0, total * input.1);
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
    let (o, d, os) = (out as usize, done as usize, objectness as usize);
    if (!in_place && overlap(o, bytes, x, in_bytes))
        || overlap(o, bytes, os, os_bytes)
        || overlap(d, done_bytes, o, bytes)
        || overlap(d, done_bytes, x, in_bytes)
        || overlap(d, done_bytes, os, os_bytes)
    {
        return Err(MLMAP_ERR_OVERLAP);
    }
    Ok((bytes, done_bytes))
}

/// The pointers of a batch call: the inputs and the scores non-NULL and aligned, the
/// objectness and the `done` counter aligned when given (NULL: none).
#[inline(always)]
fn batch_pointers<T>(
    input: *const T,
    out: *mut f32,
    objectness: *const f32,
    done: *mut usize,
) -> Result<(), mlmap_status_t> {
    check_ptr(input)?;
    check_ptr(out)?;
    if !objectness.is_null() {
        check_ptr(objectness)?;
    }
    if !done.is_null() {
        check_ptr(done)?;
    }
    Ok(())
}

/// The row loop of every batch call: row `r` of the `rows * k` inputs at `input`, with
/// `objectness[r]` (1 when NULL), through `score` into row `r` of `out`; `*done` (when
/// not NULL) is 0 first and `r + 1` after row `r`. With `row_copy` (K values), each row
/// is copied there before it is scored: a batch written exactly over its inputs.
///
/// # Safety
///
/// `batch_pointers` and `batch_memory` accepted these arguments: `rows * k` readable
/// inputs, as many writable floats at `out`, one readable float per row at
/// `objectness` (or NULL), a writable `done` (or NULL), the scores overlapping no input
/// but, with `row_copy`, exactly the inputs.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn batch_rows<T: Copy>(
    rows: usize,
    k: usize,
    input: *const T,
    objectness: *const f32,
    out: *mut f32,
    done: *mut usize,
    mut row_copy: Option<&mut [T]>,
    mut score: impl FnMut(&[T], f32, &mut [f32]) -> Result<(), mlmap::InferError>,
) -> Result<(), mlmap_status_t> {
    if row_copy.as_ref().is_some_and(|copy| copy.len() != k) {
        return Err(MLMAP_ERR_LENGTH);
    }
    if !done.is_null() {
        // SAFETY: non-NULL, aligned, the caller's `size_t`, overlapping nothing else.
        unsafe { done.write(0) };
    }
    for r in 0..rows {
        let at = r * k;
        // SAFETY: row `r < rows` of the `rows * k` inputs and scores, one objectness per
        // row (the contract); a row copy holds K values and is the caller's own memory.
        unsafe {
            let os = if objectness.is_null() {
                1.0
            } else {
                objectness.add(r).read()
            };
            let row: &[T] = match row_copy.as_deref_mut() {
                // K values (checked before the loop).
                Some(copy) => {
                    core::ptr::copy_nonoverlapping(input.add(at), copy.as_mut_ptr(), k);
                    copy
                }
                None => core::slice::from_raw_parts(input.add(at), k),
            };
            score(row, os, core::slice::from_raw_parts_mut(out.add(at), k))?;
            if !done.is_null() {
                done.write(r + 1);
            }
        }
    }
    Ok(())
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
                    upper_tail: i32::from(s.upper_tail.code()),
                    edge_mode: i32::from(s.edge_mode.code()),
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

/// Whether the byte ranges `[a, a + a_len)` and `[b, b + b_len)` share a byte (an empty
/// range shares none).
#[inline(always)]
fn overlap(a: usize, a_len: usize, b: usize, b_len: usize) -> bool {
    // Both non-empty, and `a` in `[b, b + b_len)` or `b` in `[a, a + a_len)`, without
    // overflow.
    a_len != 0 && b_len != 0 && (a.wrapping_sub(b) < b_len || b.wrapping_sub(a) < a_len)
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
