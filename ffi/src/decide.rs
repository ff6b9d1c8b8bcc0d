//! The tie-safe decision (docs/DESIGN.md §1.7), one detection and a batch.

use core::mem::{align_of, size_of};

use mlmap::decide;

use super::mlmap_status_t::{self, *};
use super::{check_ptr, put, status};

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
