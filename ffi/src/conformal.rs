//! The conformal class sets of docs/DESIGN.md section 8 for C: a fixed-size handle
//! (`MLMAP_CONFORMAL_SIZE` bytes) over the table and its conformal section, running the
//! Rust layer's `ConformalSpec`.

use core::ffi::c_void;
use core::mem::{align_of, size_of};
use core::ptr;

use mlmap::{set_words, ConformalError, ConformalSpec, Head};

use super::limits::{MAX_CATEGORIES, MAX_CLASSES};
use super::mlmap_status_t::{self, *};
use super::{check_ptr, mlmap_table_t, overlap, put, status, table_ref};

/// Bytes of a conformal handle's storage.
pub const MLMAP_CONFORMAL_SIZE: usize = 64;

/// Alignment of a conformal handle's storage in bytes.
pub const MLMAP_CONFORMAL_ALIGN: usize = 8;

/// Most 32-bit words of a set's bitmask: `(MLMAP_MAX_CLASSES + 31) / 32`.
const MAX_WORDS: usize = MAX_CLASSES.div_ceil(32);

#[repr(C)]
struct Header {
    tag: u64,
    spec: ConformalSpec<'static>,
    table: *const mlmap_table_t,
}

const _: () = assert!(size_of::<Header>() <= MLMAP_CONFORMAL_SIZE);
const _: () = assert!(align_of::<Header>() <= MLMAP_CONFORMAL_ALIGN);

/// Written into [`Header::tag`] once a handle is initialised.
const TAG: u64 = u64::from_le_bytes(*b"MLMPset1");

impl From<ConformalError> for mlmap_status_t {
    fn from(e: ConformalError) -> Self {
        match e {
            ConformalError::Absent => MLMAP_ERR_NO_SECTION,
            ConformalError::Corrupted => MLMAP_ERR_CORRUPTED,
            ConformalError::UnsupportedVersion { .. } => MLMAP_ERR_UNSUPPORTED_VERSION,
            ConformalError::MissingHead { head: Head::Open } => MLMAP_ERR_NO_OPEN_HEAD,
            ConformalError::MissingHead { .. } => MLMAP_ERR_NO_BAYES_HEAD,
            _ => MLMAP_ERR_INVALID_SECTION,
        }
    }
}

/// Initialises a conformal handle in `conformal` for `table` from the conformal section
/// in `bytes` (a table file with the section, as written by `mlmap conformal`, or the
/// section alone).
///
/// Checks the section as the Rust `ConformalSpec::from_bytes` does: the magic, the CRC,
/// the version, that the table has the section's head, K, the table's CRC when the
/// table precedes the section, alpha, and every threshold against its calibration rows.
///
/// Lifetime: the handle keeps pointers into `table` and `bytes`: both must stay in place
/// and unchanged while it is used. On failure the storage holds no handle.
///
/// @param[out] conformal Storage of `MLMAP_CONFORMAL_SIZE` bytes aligned to
///   `MLMAP_CONFORMAL_ALIGN`.
/// @param conformal_size Its size in bytes (`MLMAP_ERR_STORAGE_TOO_SMALL` when too small).
/// @param table A decoded table.
/// @param bytes The bytes holding the conformal section; they must not overlap the handle.
/// @param len Number of bytes.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_STORAGE_TOO_SMALL`, `MLMAP_ERR_TOO_LARGE`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NO_SECTION`, `MLMAP_ERR_CORRUPTED`,
///   `MLMAP_ERR_UNSUPPORTED_VERSION`, `MLMAP_ERR_NO_BAYES_HEAD`, `MLMAP_ERR_NO_OPEN_HEAD`
///   (the section's head is not in the table), `MLMAP_ERR_INVALID_SECTION`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_conformal_init(
    conformal: *mut c_void,
    conformal_size: usize,
    table: *const mlmap_table_t,
    bytes: *const u8,
    len: usize,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe { init(conformal, conformal_size, table, bytes, len) })
}

unsafe fn init(
    conformal: *mut c_void,
    conformal_size: usize,
    table: *const mlmap_table_t,
    bytes: *const u8,
    len: usize,
) -> Result<(), mlmap_status_t> {
    let header = conformal.cast::<Header>();
    check_ptr(header)?;
    check_ptr(bytes)?;
    // SAFETY: forwarded contract.
    let (view, used) = unsafe { table_ref(table) }?;
    let describes_memory =
        |at: usize, n: usize| n <= isize::MAX as usize && at.checked_add(n).is_some();
    let (c, b) = (conformal as usize, bytes as usize);
    if !describes_memory(c, conformal_size) || !describes_memory(b, len) {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    if conformal_size < MLMAP_CONFORMAL_SIZE {
        return Err(MLMAP_ERR_STORAGE_TOO_SMALL);
    }
    let need = MLMAP_CONFORMAL_SIZE;
    if overlap(c, need, b, len) || overlap(c, need, table as usize, used) {
        return Err(MLMAP_ERR_OVERLAP);
    }
    // SAFETY: `len` readable bytes (the caller's promise), disjoint from the handle,
    // kept in place while the handle is used (the documented contract).
    let section: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
    // SAFETY: `header` is non-NULL, aligned, and `need` writable bytes; the tag is
    // cleared first so that a failure leaves no handle.
    unsafe { ptr::addr_of_mut!((*header).tag).write(0) };
    let spec = ConformalSpec::from_bytes(section, view)?;
    // SAFETY: as above.
    unsafe {
        ptr::addr_of_mut!((*header).spec).write(spec);
        ptr::addr_of_mut!((*header).table).write(table);
        ptr::addr_of_mut!((*header).tag).write(TAG);
    }
    Ok(())
}

/// The initialised handle in `conformal`.
///
/// # Safety
///
/// `conformal` is NULL or points to storage passed to [`mlmap_conformal_init`] (or
/// zeroed).
unsafe fn open<'a>(
    conformal: *const c_void,
) -> Result<(&'a ConformalSpec<'static>, *const mlmap_table_t), mlmap_status_t> {
    let header = conformal.cast::<Header>();
    check_ptr(header)?;
    // SAFETY: non-NULL and aligned; storage of at least the tag's size.
    if unsafe { ptr::addr_of!((*header).tag).read() } != TAG {
        return Err(MLMAP_ERR_NO_CONFORMAL);
    }
    // SAFETY: the tag is written only after a successful init, which wrote the spec and
    // the table pointer (kept valid by the caller's contract).
    unsafe {
        let h = &*header;
        Ok((&h.spec, h.table))
    }
}

/// Scores one detection with the section's head (the library's default backend for it,
/// as mlmap_score() and the Rust `Table` methods) into `scores` and writes its conformal
/// set into `mask`: bit `c % 32` of `mask[c / 32]` is 1 when class `c` is in the set
/// (its score at or above its threshold). An empty set with the open head, or a table
/// with a background category, means "not a known object".
///
/// Work: the head's scoring, then K comparisons. No allocation, bounded time.
///
/// @param conformal A handle from mlmap_conformal_init().
/// @param logits K logits; they may lie anywhere (copied first).
/// @param n_logits K (`MLMAP_ERR_LENGTH` otherwise).
/// @param objectness In [0, 1] (`MLMAP_ERR_OBJECTNESS`).
/// @param[out] scores K floats: the head's scores.
/// @param scores_len Floats at `scores` (`MLMAP_ERR_BUFFER_TOO_SMALL` below K).
/// @param[out] mask `(K + 31) / 32` words: the set.
/// @param mask_len Words at `mask` (`MLMAP_ERR_BUFFER_TOO_SMALL` below `(K + 31) / 32`).
/// @param[out] size The number of classes in the set.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_CONFORMAL`, `MLMAP_ERR_LENGTH`, `MLMAP_ERR_BUFFER_TOO_SMALL`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NAN_LOGIT`, `MLMAP_ERR_OBJECTNESS` (nothing is
///   written then).
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlmap_conformal_set(
    conformal: *const c_void,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    scores: *mut f32,
    scores_len: usize,
    mask: *mut u32,
    mask_len: usize,
    size: *mut u32,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe {
        set(
            conformal, logits, n_logits, objectness, scores, scores_len, mask, mask_len, size,
        )
    })
}

#[allow(clippy::too_many_arguments)]
unsafe fn set(
    conformal: *const c_void,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    scores: *mut f32,
    scores_len: usize,
    mask: *mut u32,
    mask_len: usize,
    size: *mut u32,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let (spec, table) = unsafe { open(conformal) }?;
    // SAFETY: the table the handle was initialised with, kept in place by the caller.
    let (view, used) = unsafe { table_ref(table) }?;
    let k = spec.k();
    check_ptr(logits)?;
    check_ptr(scores)?;
    check_ptr(mask)?;
    check_ptr(size)?;
    if n_logits != k {
        return Err(MLMAP_ERR_LENGTH);
    }
    let words = set_words(k);
    if scores_len < k || mask_len < words {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    let regions = [
        (conformal as usize, MLMAP_CONFORMAL_SIZE),
        (table as usize, used),
        (scores as usize, 4 * k),
        (mask as usize, 4 * words),
        (size as usize, 4),
    ];
    for (i, &(a, an)) in regions.iter().enumerate() {
        for &(b, bn) in regions.iter().skip(i + 1) {
            if overlap(a, an, b, bn) {
                return Err(MLMAP_ERR_OVERLAP);
            }
        }
    }
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: `k` readable floats at `logits` (the caller's promise), copied before
    // anything is written.
    unsafe { ptr::copy_nonoverlapping(logits, x.as_mut_ptr(), k) };
    let mut out = [0.0f32; MAX_CLASSES];
    let out = out.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    let mut scratch = [0.0f32; MAX_CATEGORIES];
    let mut m = [0u32; MAX_WORDS];
    let n = spec.score_set(view, x, objectness, out, &mut scratch, &mut m)?;
    let m = m.get(..words).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: outputs checked above: non-NULL, aligned, large enough, disjoint.
    unsafe {
        ptr::copy_nonoverlapping(out.as_ptr(), scores, k);
        ptr::copy_nonoverlapping(m.as_ptr(), mask, words);
        put(size, n)
    }
}

/// The handle's level, head and thresholds.
///
/// @param conformal A handle from mlmap_conformal_init().
/// @param[out] alpha Receives alpha.
/// @param[out] head Receives the head: 0 ML, 1 MAP, 2 Bayes, 3 open.
/// @param[out] thresholds Receives K thresholds (`-INFINITY`: the class is in every set).
/// @param thresholds_len Floats at `thresholds` (`MLMAP_ERR_BUFFER_TOO_SMALL` below K).
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_CONFORMAL`, `MLMAP_ERR_BUFFER_TOO_SMALL`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_conformal_params(
    conformal: *const c_void,
    alpha: *mut f32,
    head: *mut u32,
    thresholds: *mut f32,
    thresholds_len: usize,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe { params(conformal, alpha, head, thresholds, thresholds_len) })
}

unsafe fn params(
    conformal: *const c_void,
    alpha: *mut f32,
    head: *mut u32,
    thresholds: *mut f32,
    thresholds_len: usize,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let (spec, _) = unsafe { open(conformal) }?;
    check_ptr(alpha)?;
    check_ptr(head)?;
    check_ptr(thresholds)?;
    let k = spec.k();
    if thresholds_len < k {
        return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
    }
    let regions = [
        (conformal as usize, MLMAP_CONFORMAL_SIZE),
        (alpha as usize, 4),
        (head as usize, 4),
        (thresholds as usize, 4 * k),
    ];
    for (i, &(a, an)) in regions.iter().enumerate() {
        for &(b, bn) in regions.iter().skip(i + 1) {
            if overlap(a, an, b, bn) {
                return Err(MLMAP_ERR_OVERLAP);
            }
        }
    }
    let code = match spec.head() {
        Head::Ml => 0,
        Head::Map => 1,
        Head::Bayes => 2,
        Head::Open => 3,
    };
    // SAFETY: checked non-NULL, aligned, disjoint; K floats at `thresholds`.
    unsafe {
        put(alpha, spec.alpha())?;
        put(head, code)?;
        for c in 0..k {
            thresholds
                .add(c)
                .write(spec.threshold(c).unwrap_or(f32::NEG_INFINITY));
        }
    }
    Ok(())
}
