//! Scoring: one detection and batches of each head (ML, MAP, Bayes, open) through
//! `TableView`, the one scoring path of every table.

use core::mem::size_of;
use core::ptr;

use mlmap::{Head, InferError, MapBackend};

use super::limits::{FAST_CLASSES, MAX_CLASSES};
use super::mlmap_status_t::{self, *};
use super::{
    batch_memory, batch_pointers, batch_rows, check_ptr, mlmap_table_t, outside_table, overlap,
    status, table_len, view, View,
};

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
        Head::Map => v.map_into::<MapBackend>(x, objectness, out, &mut scratch),
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
                        Head::Map => v.map_into::<MapBackend>(x, objectness, out, s),
                        Head::Bayes | Head::Open => score_categories(v, head, x, objectness, out),
                    }
                }
            }
        };
    }
    dispatch!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
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
        return Ok(score(v, head, x, objectness, o)?);
    }
    // In place: the logits are copied first.
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: as above; `x` is a local array, and `out` no longer overlaps an input.
    unsafe {
        ptr::copy_nonoverlapping(logits, x.as_mut_ptr(), k);
        Ok(score(
            v,
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
    batch_pointers(logits, out, objectness, done)?;
    let k = v.k();
    if n_logits != k {
        return Err(MLMAP_ERR_LENGTH);
    }
    match head {
        Head::Bayes if v.bayes().is_none() => return Err(MLMAP_ERR_NO_BAYES_HEAD),
        Head::Open if v.open().is_none() => return Err(MLMAP_ERR_NO_OPEN_HEAD),
        _ => {}
    }
    let in_place = out.cast_const() == logits;
    let (bytes, done_bytes) = batch_memory(
        rows,
        k,
        (logits as usize, size_of::<f32>()),
        in_place,
        objectness,
        out,
        out_len,
        done,
    )?;
    outside_table(out, bytes, table)?;
    outside_table(done, done_bytes, table)?;
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: the checks above (the output overlaps neither the table, nor `done`, nor
    // the objectness, and the logits only when it is exactly them: then each row is
    // copied to `x` first).
    unsafe {
        batch_rows(
            rows,
            k,
            logits,
            objectness,
            out,
            done,
            in_place.then_some(x),
            |row, os, o| score(v, head, row, os, o),
        )
    }
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
