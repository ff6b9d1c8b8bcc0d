//! The quantized scoring calls: one detection and batches of int8 and int16 codes, and
//! the dequantized logits.

use core::mem::size_of;
use core::ptr;

use mlmap::{Code, Head};

use super::super::limits::{FAST_CLASSES, MAX_CLASSES};
use super::super::mlmap_status_t::{self, *};
use super::super::{batch_memory, batch_pointers, batch_rows, check_ptr, status};
use super::{handle, mlmap_qtable_t, outside, Control};

/// The head of a `head` argument.
fn head_of(head: i32) -> Result<Head, mlmap_status_t> {
    match head {
        0 => Ok(Head::Ml),
        1 => Ok(Head::Map),
        2 => Ok(Head::Bayes),
        3 => Ok(Head::Open),
        _ => Err(MLMAP_ERR_UNKNOWN_HEAD),
    }
}

/// The checks shared by every quantized call on K codes of type `Q`: the handle, the
/// head, the code width and the count.
#[inline(always)]
unsafe fn checked<'a, Q: Code>(
    qtable: *const mlmap_qtable_t,
    n_codes: usize,
) -> Result<&'a Control, mlmap_status_t> {
    // SAFETY: forwarded contract.
    let c = unsafe { handle(qtable) }?;
    if c.q.bits() != Q::BITS {
        return Err(MLMAP_ERR_CODE_WIDTH);
    }
    if n_codes != c.q.k() {
        return Err(MLMAP_ERR_LENGTH);
    }
    Ok(c)
}

/// Scores one detection: the checks, then the layer.
#[inline(always)]
unsafe fn detection<Q: Code + Default>(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const Q,
    n_codes: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let c = unsafe { checked::<Q>(qtable, n_codes) }?;
    let head = head_of(head)?;
    check_ptr(codes)?;
    check_ptr(out)?;
    let k = c.q.k();
    if out_len < k {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    outside(c, out as usize, k * size_of::<f32>())?;
    // The class counts of FAST_CLASSES (MLMAP_FAST_CLASSES) copy their codes and clear
    // their scratch at their own size.
    macro_rules! dispatch {
        ($($k:literal)*) => {
            match k {
                $($k if FAST_CLASSES.contains(&$k) => {
                    // SAFETY: forwarded contract, `k` codes and floats.
                    unsafe { one::<Q, $k, { 2 * $k + 1 }>(c, head, codes, k, objectness, out) }
                })*
                // SAFETY: as above.
                _ => unsafe {
                    one::<Q, MAX_CLASSES, { 2 * MAX_CLASSES + 1 }>(c, head, codes, k, objectness, out)
                },
            }
        };
    }
    dispatch!(2 3 4 5 6 7 8 9 10 11 12 13 14 15 16)
}

/// One detection of `k <= N` codes with a scratch of `S >= 2 k + 1` floats.
///
/// # Safety
///
/// `k` readable codes at `codes` and `k` writable floats at `out`, non-NULL and aligned,
/// `out` overlapping neither the arena nor the section's bytes.
#[inline(always)]
unsafe fn one<Q: Code + Default, const N: usize, const S: usize>(
    c: &Control,
    head: Head,
    codes: *const Q,
    k: usize,
    objectness: f32,
    out: *mut f32,
) -> Result<(), mlmap_status_t> {
    // The codes are copied first, so the scores may overlap them in any way.
    let mut x = [Q::default(); N];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    for (i, d) in x.iter_mut().enumerate() {
        // SAFETY: `i < k` (the caller's promise).
        *d = unsafe { codes.add(i).read() };
    }
    let mut scratch = [0.0f32; S];
    // SAFETY: the codes are read whole; `out` is the caller's (see above).
    let out = unsafe { core::slice::from_raw_parts_mut(out, k) };
    Ok(c.q.score_into(head, x, objectness, out, &mut scratch)?)
}

/// Scores a batch: the checks, then one row at a time.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
unsafe fn batch<Q: Code>(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const Q,
    rows: usize,
    n_codes: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let c = unsafe { checked::<Q>(qtable, n_codes) }?;
    let h = head_of(head)?;
    batch_pointers(codes, out, objectness, done)?;
    let q = &c.q;
    match h {
        Head::Bayes if !q.has_bayes() => return Err(MLMAP_ERR_NO_BAYES_HEAD),
        Head::Open if q.open_params().is_none() => return Err(MLMAP_ERR_NO_OPEN_HEAD),
        _ => {}
    }
    let k = q.k();
    // A batch does not copy its inputs, and a row of scores is wider than a row of
    // codes: the scores must not overlap the codes at all.
    let (bytes, done_bytes) = batch_memory(
        rows,
        k,
        (codes as usize, size_of::<Q>()),
        false,
        objectness,
        out,
        out_len,
        done,
    )?;
    let (o, d) = (out as usize, done as usize);
    outside(c, o, bytes)?;
    outside(c, d, done_bytes)?;
    let mut scratch = [0.0f32; 2 * MAX_CLASSES + 1];
    // SAFETY: the checks above (the output overlaps none of the inputs, `done`, the
    // arena or the bytes).
    unsafe {
        batch_rows(rows, k, codes, objectness, out, done, None, |row, os, o| {
            q.score_into(h, row, os, o, &mut scratch)
        })
    }
}

/// Scores one detection of int8 codes with `head` (an ::mlmap_head_t value): the
/// scores of the float table's head on the dequantized logits `(q - zero_point) *
/// scale`, bit for bit those of the Rust `QTable` and of `mlmap apply --quantized`.
/// ML and MAP are K lookups and the normalisation (no `exp`); Bayes and open keep the
/// softmax's `exp`.
///
/// @param qtable A handle from mlmap_qtable_init() of an 8-bit section.
/// @param head `MLMAP_HEAD_ML`, `_MAP`, `_BAYES` or `_OPEN`.
/// @param codes The detection's K codes.
/// @param n_codes Number of codes; must be K.
/// @param objectness The detection's objectness, in [0, 1].
/// @param[out] out Receives the K scores; may overlap `codes` in any way (they are
///   copied first), must not overlap the arena or the section's bytes.
/// @param out_len Number of floats at `out`, at least K.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_QTABLE`, `MLMAP_ERR_MOVED`, `MLMAP_ERR_CODE_WIDTH` (a 16-bit
///   section), `MLMAP_ERR_UNKNOWN_HEAD`, `MLMAP_ERR_LENGTH`,
///   `MLMAP_ERR_BUFFER_TOO_SMALL`, `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_OBJECTNESS`,
///   `MLMAP_ERR_NO_BAYES_HEAD`, `MLMAP_ERR_NO_OPEN_HEAD`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_qscore_i8(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const i8,
    n_codes: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes `n_codes` codes at `codes`, `out_len` floats at `out`.
    status(unsafe { detection(qtable, head, codes, n_codes, objectness, out, out_len) })
}

/// Scores one detection of int16 codes: as mlmap_qscore_i8() for a 16-bit section.
///
/// @param qtable A handle from mlmap_qtable_init() of a 16-bit section.
/// @param head `MLMAP_HEAD_ML`, `_MAP`, `_BAYES` or `_OPEN`.
/// @param codes The detection's K codes.
/// @param n_codes Number of codes; must be K.
/// @param objectness The detection's objectness, in [0, 1].
/// @param[out] out Receives the K scores.
/// @param out_len Number of floats at `out`, at least K.
/// @return As mlmap_qscore_i8() (`MLMAP_ERR_CODE_WIDTH` for an 8-bit section).
#[no_mangle]
pub unsafe extern "C" fn mlmap_qscore_i16(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const i16,
    n_codes: usize,
    objectness: f32,
    out: *mut f32,
    out_len: usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_qscore_i8`.
    status(unsafe { detection(qtable, head, codes, n_codes, objectness, out, out_len) })
}

/// Scores a batch of int8 codes: row `r` of `codes` (row-major, `rows` x K) and
/// `objectness[r]` into row `r` of `out`, each row as mlmap_qscore_i8().
///
/// Every argument is checked before anything is written (nothing is written on a
/// failed check, `*done` included). On a row that cannot be scored (bad objectness)
/// the rows before it are written, its status is returned and `*done` is its index.
/// The scores must not overlap the codes, the objectness, `done`, the arena or the
/// section's bytes (`MLMAP_ERR_OVERLAP`): a batch does not copy its inputs.
///
/// @param qtable A handle from mlmap_qtable_init() of an 8-bit section.
/// @param head `MLMAP_HEAD_ML`, `_MAP`, `_BAYES` or `_OPEN`.
/// @param codes `rows * n_codes` codes, row-major.
/// @param rows Number of detections (0 is allowed).
/// @param n_codes Codes per row; must be K.
/// @param objectness `rows` floats, or NULL for an objectness of 1 everywhere.
/// @param[out] out Receives `rows * K` scores.
/// @param out_len Number of floats at `out`, at least `rows * K`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As mlmap_qscore_i8(), and `MLMAP_ERR_TOO_LARGE`.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_qscore_i8_batch(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const i8,
    rows: usize,
    n_codes: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes the buffers described above.
    status(unsafe {
        batch(
            qtable, head, codes, rows, n_codes, objectness, out, out_len, done,
        )
    })
}

/// Scores a batch of int16 codes: as mlmap_qscore_i8_batch() for a 16-bit section.
///
/// @param qtable A handle from mlmap_qtable_init() of a 16-bit section.
/// @param head `MLMAP_HEAD_ML`, `_MAP`, `_BAYES` or `_OPEN`.
/// @param codes `rows * n_codes` codes, row-major.
/// @param rows Number of detections.
/// @param n_codes Codes per row; must be K.
/// @param objectness `rows` floats, or NULL for 1 everywhere.
/// @param[out] out Receives `rows * K` scores.
/// @param out_len Number of floats at `out`.
/// @param[out] done If not NULL, receives the number of rows written.
/// @return As mlmap_qscore_i8_batch().
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_qscore_i16_batch(
    qtable: *const mlmap_qtable_t,
    head: i32,
    codes: *const i16,
    rows: usize,
    n_codes: usize,
    objectness: *const f32,
    out: *mut f32,
    out_len: usize,
    done: *mut usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_qscore_i8_batch`.
    status(unsafe {
        batch(
            qtable, head, codes, rows, n_codes, objectness, out, out_len, done,
        )
    })
}

/// The dequantized logits of K codes (what the scores are exact for): pass them with
/// the scores to mlmap_decide(), whose tie rule compares logits, since classes may have
/// different scales.
///
/// @param qtable A handle from mlmap_qtable_init() of an 8-bit section.
/// @param codes The detection's K codes.
/// @param n_codes Number of codes; must be K.
/// @param[out] logits Receives the K logits; may overlap `codes` (copied first), must
///   not overlap the arena or the section's bytes.
/// @param logits_len Number of floats at `logits`, at least K.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_QTABLE`, `MLMAP_ERR_MOVED`, `MLMAP_ERR_CODE_WIDTH`,
///   `MLMAP_ERR_LENGTH`, `MLMAP_ERR_BUFFER_TOO_SMALL`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_qlogits_i8(
    qtable: *const mlmap_qtable_t,
    codes: *const i8,
    n_codes: usize,
    logits: *mut f32,
    logits_len: usize,
) -> mlmap_status_t {
    // SAFETY: the caller passes `n_codes` codes and `logits_len` floats.
    status(unsafe { dequantize(qtable, codes, n_codes, logits, logits_len) })
}

/// The dequantized logits of K int16 codes: as mlmap_qlogits_i8() for a 16-bit section.
///
/// @param qtable A handle from mlmap_qtable_init() of a 16-bit section.
/// @param codes The detection's K codes.
/// @param n_codes Number of codes; must be K.
/// @param[out] logits Receives the K logits.
/// @param logits_len Number of floats at `logits`, at least K.
/// @return As mlmap_qlogits_i8().
#[no_mangle]
pub unsafe extern "C" fn mlmap_qlogits_i16(
    qtable: *const mlmap_qtable_t,
    codes: *const i16,
    n_codes: usize,
    logits: *mut f32,
    logits_len: usize,
) -> mlmap_status_t {
    // SAFETY: as for `mlmap_qlogits_i8`.
    status(unsafe { dequantize(qtable, codes, n_codes, logits, logits_len) })
}

unsafe fn dequantize<Q: Code + Default>(
    qtable: *const mlmap_qtable_t,
    codes: *const Q,
    n_codes: usize,
    logits: *mut f32,
    logits_len: usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let c = unsafe { checked::<Q>(qtable, n_codes) }?;
    check_ptr(codes)?;
    check_ptr(logits)?;
    let k = c.q.k();
    if logits_len < k {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    outside(c, logits as usize, k * size_of::<f32>())?;
    let mut x = [Q::default(); MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: `k` readable codes, `k <= logits_len` writable floats (the caller's
    // promise), checked for NULL and alignment; the codes are copied first.
    unsafe {
        ptr::copy_nonoverlapping(codes, x.as_mut_ptr(), k);
        let out = core::slice::from_raw_parts_mut(logits, k);
        Ok(c.q.logits_into(x, out)?)
    }
}
