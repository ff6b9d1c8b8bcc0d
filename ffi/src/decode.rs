//! Decoding a table: into an arena of exactly the table's size (`mlmap_table_init`,
//! sized by `mlmap_table_arena_size` or by `mlmap export-c`'s macro), or into a
//! `mlmap_table_t` of the build's maximum shape (`mlmap_table_decode`). Both run the one
//! decoder into the same arena layout; every other function takes either.

use core::ffi::c_void;
use core::mem::size_of;

use mlmap::lent::StorageShape;
use mlmap::DecodeError;

use super::arena::{self, Failure, ARENA_ALIGN};
use super::detail::{mlmap_error_t, report};
use super::limits::{MAX_BINS, MAX_BINS_BAYES, MAX_CATEGORIES, MAX_CLASSES};
use super::mlmap_status_t::{self, *};
use super::{check_ptr, max_table_bytes, mlmap_table_t, overlap, status};

/// Whether `n` bytes at `at` can describe memory: at most `PTRDIFF_MAX` bytes, not past
/// the end of the address space.
pub(crate) fn describes_memory(at: usize, n: usize) -> bool {
    n <= isize::MAX as usize && at.checked_add(n).is_some()
}

/// The largest shape a build scores: every call keeps K logits and K + 1 categories
/// of scratch on the stack, so K is at most `MLMAP_MAX_CLASSES` whatever the storage.
fn scoring_limit(s: &StorageShape) -> Result<(), DecodeError> {
    if s.classes > MAX_CLASSES {
        return Err(DecodeError::ShapeMismatch {
            expected: (
                u16::try_from(MAX_CLASSES).unwrap_or(u16::MAX),
                u16::MAX,
                u16::MAX,
            ),
            found: (
                u16::try_from(s.classes).unwrap_or(u16::MAX),
                u16::try_from(s.bins_ml).unwrap_or(u16::MAX),
                u16::try_from(s.bins_map).unwrap_or(u16::MAX),
            ),
        });
    }
    Ok(())
}

/// The shape of a `mlmap_table_t`: at most `MLMAP_MAX_CLASSES` classes, `MLMAP_MAX_BINS`
/// bins in the ML and MAP heads, `MLMAP_MAX_BINS_BAYES` in the Bayes head.
fn fixed_limit(s: &StorageShape) -> Result<(), DecodeError> {
    let u = |n: usize| u16::try_from(n).unwrap_or(u16::MAX);
    if s.classes > MAX_CLASSES || s.bins_ml > MAX_BINS || s.bins_map > MAX_BINS {
        return Err(DecodeError::ShapeMismatch {
            expected: (u(MAX_CLASSES), u(MAX_BINS), u(MAX_BINS)),
            found: (u(s.classes), u(s.bins_ml), u(s.bins_map)),
        });
    }
    if s.bins_bayes > MAX_BINS_BAYES || s.categories > MAX_CATEGORIES {
        return Err(DecodeError::BayesShapeMismatch {
            expected: (u(MAX_BINS_BAYES), u(MAX_CATEGORIES)),
            found: (u(s.bins_bayes), u(s.categories)),
        });
    }
    Ok(())
}

/// The checks of every decode, then the decode: `need` is the least storage accepted
/// before the table is read (the whole `mlmap_table_t`, or the tag of an arena), and
/// the least the table then occupies (outputs may not overlap it).
unsafe fn decode(
    storage: *mut u8,
    size: usize,
    need: usize,
    bytes: *const u8,
    len: usize,
    limit: fn(&StorageShape) -> Result<(), DecodeError>,
) -> Result<usize, Failure> {
    check_ptr(storage.cast::<u64>())?;
    check_ptr(bytes)?;
    if size < need {
        return Err(Failure::too_small(need));
    }
    let (s, b) = (storage as usize, bytes as usize);
    if !describes_memory(s, size) || !describes_memory(b, len) {
        return Err(MLMAP_ERR_TOO_LARGE.into());
    }
    // The bytes must lie outside the whole storage the caller declared.
    if overlap(s, size, b, len) {
        return Err(MLMAP_ERR_OVERLAP.into());
    }
    // SAFETY: non-NULL, aligned to 8 (checked as a `u64` pointer) and at least 8 bytes
    // (`need >= 8`): the tag, cleared first so that a failure leaves no table.
    unsafe { arena::clear(storage) };
    // SAFETY: the caller promises `len` readable bytes, disjoint from the storage.
    let bytes = unsafe { core::slice::from_raw_parts(bytes, len) };
    let shape = StorageShape::of(bytes, limit).map_err(|e| Failure::decoding(e, bytes))?;
    // SAFETY: aligned, `size` bytes of the caller's, disjoint from the bytes (checked).
    unsafe { arena::decode_into(storage, size, bytes, &shape, need) }?;
    Ok(arena::layout(&shape).map_or(0, |l| l.size))
}

/// Decodes and validates a table (a `.mlmap` file's bytes) into `table`, a
/// `mlmap_table_t` (room for any table of the build's maximum shape).
///
/// Prefer mlmap_table_init(), which takes an arena of exactly the table's size (a
/// `mlmap_table_t` is about 87 KB in the default build, whatever the table); this
/// function is kept for programs written against it and decodes into the same layout.
///
/// Checks, in order: the magic, the CRC-32, the format version, the shape against the
/// library's maximum, the body's syntax and every table invariant; the same checks,
/// with the same outcome, as the Rust `Table::from_bytes`. Any table the storage held
/// before is discarded first: on failure the storage holds no table, and every
/// function given it returns `MLMAP_ERR_NO_TABLE`. The bytes are not used after the
/// call returns.
///
/// The storage holds pointers into itself once decoded: do not copy or move it (a copy
/// is refused with `MLMAP_ERR_MOVED`; decode again instead).
///
/// Work: computes the CRC-32 over the input, measures the table (for a format-4 table,
/// one parse that stores nothing), then parses it once into the storage and checks the
/// invariants: time linear in `len` and in the table's size.
///
/// @param[out] table Storage for the table: a `mlmap_table_t`, aligned to
///   `MLMAP_TABLE_ALIGN` (a `static mlmap_table_t` is).
/// @param table_size The size of the storage in bytes (`sizeof` it): at least
///   `mlmap_limits().table_size` (`MLMAP_ERR_STORAGE_TOO_SMALL`), at most
///   `PTRDIFF_MAX` and not past the end of the address space (`MLMAP_ERR_TOO_LARGE`).
/// @param bytes The table's bytes; must not overlap the `table_size` bytes of the
///   storage (`MLMAP_ERR_OVERLAP`).
/// @param len Number of bytes, at most `PTRDIFF_MAX` (`MLMAP_ERR_TOO_LARGE`).
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_STORAGE_TOO_SMALL`, `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_TOO_LARGE`, and
///   each decode error: `MLMAP_ERR_TRUNCATED`, `MLMAP_ERR_NOT_A_TABLE`,
///   `MLMAP_ERR_CORRUPTED`, `MLMAP_ERR_UNSUPPORTED_VERSION`,
///   `MLMAP_ERR_SHAPE_TOO_LARGE`, `MLMAP_ERR_BAYES_SHAPE_TOO_LARGE`,
///   `MLMAP_ERR_MALFORMED`, `MLMAP_ERR_INVALID_TABLE`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_table_decode(
    table: *mut mlmap_table_t,
    table_size: usize,
    bytes: *const u8,
    len: usize,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    let r = unsafe {
        decode(
            table.cast::<u8>(),
            table_size,
            max_table_bytes(),
            bytes,
            len,
            fixed_limit,
        )
    };
    status(r.map(|_| ()).map_err(|f| f.status))
}

/// Decodes and validates a table into `arena`, storage of at least the bytes this
/// table needs (`mlmap_table_arena_size`, or the `NAME_ARENA_SIZE` macro `mlmap
/// export-c` writes), and gives the table's handle. The arena is carved into the
/// table's own items (names, histograms over their frequencies, the Bayes head's terms,
/// the maps), so a table costs its size, whatever the library's `MLMAP_MAX_*`, which
/// only bound K (at most `MLMAP_MAX_CLASSES`: each scoring call keeps K logits of
/// scratch on its stack).
///
/// The checks and their order are mlmap_table_decode()'s, with the same outcome as the
/// Rust `Table::from_bytes`; on failure the arena holds no table and `*table` is NULL.
/// The bytes are not used after the call returns (the quantized calls read theirs in
/// place, see mlmap_qtable_init()).
///
/// The arena holds pointers into itself once decoded: do not copy or move it (a copy
/// is refused with `MLMAP_ERR_MOVED`; decode again where it is to be used).
///
/// Work: as mlmap_table_decode(); the arena's bytes beyond the table's are never
/// touched.
///
/// @param[out] arena The storage, aligned to 8 (`static MLMAP_ALIGN8 uint8_t
///   arena[N]`), or `MLMAP_ERR_MISALIGNED`.
/// @param arena_size Bytes of the arena: at least the table's
///   (`MLMAP_ERR_STORAGE_TOO_SMALL`, and `detail->needed` says how many), at most
///   `PTRDIFF_MAX` (`MLMAP_ERR_TOO_LARGE`).
/// @param bytes The table's bytes (a table file, sections appended allowed); must not
///   overlap the arena (`MLMAP_ERR_OVERLAP`).
/// @param len Number of bytes.
/// @param[out] table Receives the handle (the arena's address) on success, NULL on
///   failure; may be NULL.
/// @param[out] detail If not NULL, receives the status and, for a decode failure, the
///   field, head and class it is about, and the bytes the table needs when known (see
///   ::mlmap_error_t); must not overlap the arena or the bytes.
/// @return As mlmap_table_decode(); `MLMAP_ERR_SHAPE_TOO_LARGE` only for more than
///   `MLMAP_MAX_CLASSES` classes.
#[no_mangle]
pub unsafe extern "C" fn mlmap_table_init(
    arena: *mut c_void,
    arena_size: usize,
    bytes: *const u8,
    len: usize,
    table: *mut *mut mlmap_table_t,
    detail: *mut mlmap_error_t,
) -> mlmap_status_t {
    if !table.is_null() {
        if let Err(s) = check_ptr(table) {
            return s;
        }
        let t = table as usize;
        // (An arena size that cannot describe memory is refused by the decode.)
        if describes_memory(arena as usize, arena_size)
            && describes_memory(bytes as usize, len)
            && overlap(t, size_of::<usize>(), arena as usize, arena_size)
            || overlap(t, size_of::<usize>(), bytes as usize, len)
        {
            return MLMAP_ERR_OVERLAP;
        }
        // SAFETY: non-NULL, aligned, the caller's `mlmap_table_t *`.
        unsafe { table.write(core::ptr::null_mut()) };
    }
    let regions = [(arena as usize, arena_size), (bytes as usize, len)];
    // SAFETY: forwarded contract (`detail` is checked by `report`).
    let r = unsafe { decode(arena.cast::<u8>(), arena_size, 8, bytes, len, scoring_limit) };
    // SAFETY: `detail` is NULL or the caller's `mlmap_error_t`.
    let s = unsafe { report(detail, &regions, r) };
    if s == MLMAP_OK && !table.is_null() {
        // SAFETY: checked above.
        unsafe { table.write(arena.cast::<mlmap_table_t>()) };
    }
    s
}

/// Gives the bytes of arena mlmap_table_init() needs for `bytes` on this target: the
/// table's exact size, from its header (for a format-4 table, also from the lengths of
/// its maps and objectness feature, read without storing anything). `mlmap export-c`
/// writes the same number as a macro, for a `static` arena sized at compile time.
///
/// Checks the magic, the CRC-32, the version, K against `MLMAP_MAX_CLASSES`, and that
/// the body is long enough for the announced shape (a format-4 body: that it parses);
/// the invariants are checked by the decode.
///
/// @param bytes The table's bytes.
/// @param len Number of bytes.
/// @param[out] size Receives the bytes; must not overlap `bytes`.
/// @param[out] detail As for mlmap_table_init(); may be NULL.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_TOO_LARGE`, `MLMAP_ERR_TRUNCATED`,
///   `MLMAP_ERR_NOT_A_TABLE`, `MLMAP_ERR_CORRUPTED`, `MLMAP_ERR_UNSUPPORTED_VERSION`,
///   `MLMAP_ERR_SHAPE_TOO_LARGE`, `MLMAP_ERR_MALFORMED`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_table_arena_size(
    bytes: *const u8,
    len: usize,
    size: *mut usize,
    detail: *mut mlmap_error_t,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    unsafe {
        size_query(bytes, len, size, detail, |b| {
            let shape = StorageShape::of(b, scoring_limit).map_err(|e| Failure::decoding(e, b))?;
            Ok(arena::layout(&shape)?.size)
        })
    }
}

/// The arena-size queries of tables and quantized sections: `measure` the `len` bytes
/// at `bytes`, after the checks of the arguments, into `*size`, with the details into
/// `detail`.
///
/// # Safety
///
/// `len` readable bytes at `bytes`; `size` and `detail` NULL or the caller's.
pub(crate) unsafe fn size_query(
    bytes: *const u8,
    len: usize,
    size: *mut usize,
    detail: *mut mlmap_error_t,
    measure: impl FnOnce(&[u8]) -> Result<usize, Failure>,
) -> mlmap_status_t {
    let regions = [(bytes as usize, len), (size as usize, size_of::<usize>())];
    let r = (|| {
        check_ptr(bytes)?;
        check_ptr(size)?;
        if !describes_memory(bytes as usize, len) {
            return Err(MLMAP_ERR_TOO_LARGE.into());
        }
        if overlap(size as usize, size_of::<usize>(), bytes as usize, len) {
            return Err(MLMAP_ERR_OVERLAP.into());
        }
        // SAFETY: `len` readable bytes (the caller's promise).
        let n = measure(unsafe { core::slice::from_raw_parts(bytes, len) })?;
        // SAFETY: non-NULL, aligned, disjoint from the bytes (checked).
        unsafe { size.write(n) };
        Ok(n)
    })();
    // SAFETY: `detail` is NULL or the caller's `mlmap_error_t`.
    unsafe { report(detail, &regions, r) }
}

const _: () = assert!(ARENA_ALIGN == 8);
