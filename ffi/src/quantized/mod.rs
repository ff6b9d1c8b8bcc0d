//! Quantized tables (int8 and int16 logits, docs/DESIGN.md and docs/FORMAT.md, "The
//! quantized section"): a section validated once and read in place from its bytes (in
//! flash), with a handle of K class records in an arena the caller owns, sized by
//! `MLMAP_QTABLE_ARENA_SIZE(k)` or `mlmap_qtable_arena_size`. Scoring runs the Rust
//! layer's `LentQTable`, the quantized heads of `QTable`, so the scores are the Rust
//! layer's bit for bit.

use core::ffi::c_void;
use core::mem::{align_of, size_of};
use core::ptr;

use mlmap::lent::{LentQTable, QClass, QLogit, EMPTY_QCLASS, EMPTY_QLOGIT};
use mlmap::{QField, QTableError};

use super::arena::Failure;
use super::decode::{describes_memory, size_query};
use super::detail::{mlmap_error_t, mlmap_field_t, report};
use super::limits::MAX_CLASSES;
use super::mlmap_status_t::{self, *};
use super::{check_ptr, overlap, put, status};

/// A quantized table: an arena initialised by `mlmap_qtable_init`, used through a
/// pointer to it. Only the library reads or writes its contents.
pub struct mlmap_qtable_t {
    _opaque: [u64; 0],
}

/// The heads, as the `head` argument of the quantized scoring calls (and the `head`
/// of ::mlmap_error_t).
#[repr(i32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum mlmap_head_t {
    /// The ML head (docs/DESIGN.md §1.2).
    MLMAP_HEAD_ML = 0,
    /// The MAP head (docs/DESIGN.md §1.2).
    MLMAP_HEAD_MAP = 1,
    /// The Bayes head (docs/DESIGN.md §1.6).
    MLMAP_HEAD_BAYES = 2,
    /// The open head (docs/DESIGN.md §1.8).
    MLMAP_HEAD_OPEN = 3,
}

/// What a quantized table holds (`mlmap_qtable_info`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct mlmap_qtable_info_t {
    /// Number of classes K (codes and scores per detection).
    pub classes: usize,
    /// Bits per code: 8 (call the `_i8` functions) or 16 (the `_i16` ones).
    pub bits: u32,
    /// Categories of the Bayes head (K, or K + 1 with `background`); 0 without it.
    pub categories: usize,
    /// 1 when the section has the open head, else 0.
    pub has_open: u32,
    /// The open head's temperature; 0 without it.
    pub temperature: f32,
    /// The open head's epsilon; 0 without it (or with epsilon 0: see `temperature`).
    pub epsilon: f32,
    /// CRC-32 of the table the section was computed from.
    pub table_crc: u32,
    /// Bytes of the section, trailer included (the bytes that must stay in place).
    pub section_len: usize,
}

/// Bytes of a pointer on this target.
const P: usize = size_of::<usize>();

/// Bytes of the control block at the start of a quantized arena (`96 + 24 P`); the
/// header's `MLMAP_QTABLE_ARENA_SIZE` computes the same.
const CONTROL: usize = 96 + 24 * P;
/// Bytes of one class record and of one logit record (`16 + 6 P` and `5 P`).
const PER_CLASS: usize = 16 + 11 * P;

/// The start of every quantized arena: a tag saying a section was validated into it,
/// the arena's own address then (the handle holds pointers into the arena), the bytes
/// the handle uses, where the section's bytes are, and the handle.
#[repr(C)]
struct Control {
    tag: u64,
    addr: usize,
    used: usize,
    bytes: (usize, usize),
    q: LentQTable<'static, 'static>,
}

const _: () = assert!(size_of::<Control>() <= CONTROL && CONTROL.is_multiple_of(8));
const _: () = assert!(size_of::<QClass<'static>>() == 16 + 6 * P);
const _: () = assert!(size_of::<QLogit<'static>>() == 5 * P);
const _: () = assert!(
    align_of::<Control>() <= 8 && align_of::<QClass<'static>>() <= 8 && align_of::<QLogit>() <= 8
);
// The logit records follow K class records: a multiple of 8 bytes for any K.
const _: () = assert!(size_of::<QClass<'static>>().is_multiple_of(8));

/// Written into [`Control::tag`] when a section is validated.
const TAG: u64 = u64::from_le_bytes(*b"MLMPqtb1");

/// Bytes of arena for a section of `k` classes.
fn arena_bytes(k: usize) -> usize {
    CONTROL + k * PER_CLASS
}

impl From<QTableError> for mlmap_status_t {
    fn from(e: QTableError) -> Self {
        match e {
            QTableError::NotQuantized => MLMAP_ERR_NO_SECTION,
            QTableError::Corrupted => MLMAP_ERR_CORRUPTED,
            QTableError::UnsupportedVersion { .. } => MLMAP_ERR_UNSUPPORTED_VERSION,
            // The arena is sized before the section is read: only a shape above the
            // build's maximum gets here.
            QTableError::ShapeMismatch { .. } => MLMAP_ERR_SHAPE_TOO_LARGE,
            _ => MLMAP_ERR_INVALID_SECTION,
        }
    }
}

/// The field, head and class of a quantized section's error.
pub(crate) fn locate(e: QTableError) -> (mlmap_field_t, i32, i32) {
    use mlmap_field_t::*;
    match e {
        QTableError::ShapeMismatch { .. } => (MLMAP_FIELD_SHAPE, -1, -1),
        QTableError::TableMismatch => (MLMAP_FIELD_TABLE_CRC, -1, -1),
        QTableError::Invalid { field, class } => {
            let c = i32::from(class);
            match field {
                QField::Shape => (MLMAP_FIELD_SHAPE, -1, -1),
                QField::Lambda => (MLMAP_FIELD_LAMBDA, -1, -1),
                QField::Scale => (MLMAP_FIELD_SCALE, -1, c),
                QField::ZeroPoint => (MLMAP_FIELD_ZERO_POINT, -1, c),
                QField::Window => (MLMAP_FIELD_CODE_WINDOW, -1, c),
                QField::Index => (MLMAP_FIELD_BIN_INDEX, -1, c),
                QField::Mass => (MLMAP_FIELD_MASS, -1, c),
                QField::LogTerm => (MLMAP_FIELD_LOG_TERM, 2, c),
                QField::Temperature => (MLMAP_FIELD_TEMPERATURE, 3, -1),
                QField::Epsilon => (MLMAP_FIELD_EPSILON, 3, -1),
                QField::LogUnknown => (MLMAP_FIELD_LOG_UNKNOWN, 3, -1),
                QField::Map => (MLMAP_FIELD_MAP, c, -1),
                QField::Objectness => (MLMAP_FIELD_OBJECTNESS, 2, -1),
                _ => (MLMAP_FIELD_NONE, -1, -1),
            }
        }
        _ => (MLMAP_FIELD_NONE, -1, -1),
    }
}

/// K of the section in `bytes`, checked against the build's maximum.
fn classes(bytes: &[u8]) -> Result<usize, Failure> {
    let k = LentQTable::classes_of(bytes).map_err(Failure::from)?;
    if k > MAX_CLASSES {
        return Err(Failure::from(QTableError::ShapeMismatch {
            expected: (u16::try_from(MAX_CLASSES).unwrap_or(u16::MAX), 0),
            found: (u16::try_from(k).unwrap_or(u16::MAX), 0),
        }));
    }
    Ok(k)
}

/// Gives the bytes of arena mlmap_qtable_init() needs for the quantized section in
/// `bytes` on this target: `MLMAP_QTABLE_ARENA_SIZE(k)` for its K classes.
///
/// Checks the section's trailer, magic, CRC-32 and version, and K against
/// `MLMAP_MAX_CLASSES`; the rest is checked by mlmap_qtable_init().
///
/// @param bytes The section, alone or after its table (a file `mlmap quantize` wrote).
/// @param len Number of bytes.
/// @param[out] size Receives the bytes; must not overlap `bytes`.
/// @param[out] detail As for mlmap_qtable_init(); may be NULL.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_TOO_LARGE`, `MLMAP_ERR_NO_SECTION`,
///   `MLMAP_ERR_CORRUPTED`, `MLMAP_ERR_UNSUPPORTED_VERSION`,
///   `MLMAP_ERR_SHAPE_TOO_LARGE`, `MLMAP_ERR_INVALID_SECTION`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_qtable_arena_size(
    bytes: *const u8,
    len: usize,
    size: *mut usize,
    detail: *mut mlmap_error_t,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    unsafe { size_query(bytes, len, size, detail, |b| Ok(arena_bytes(classes(b)?))) }
}

/// Validates the quantized section in `bytes` (as written by `mlmap quantize`: the
/// section alone or after its table) once, and gives its handle: K class records in
/// `arena`, the masses and terms read in place from `bytes` on every call.
///
/// Checks, in order, those of the Rust `QTable::from_bytes`: the trailer and magic
/// `MLMQ`, the section's CRC-32, the version, the header's fields (K at most
/// `MLMAP_MAX_CLASSES`), the checksum of the table it follows (when it follows one),
/// then every class's and logit's values, and that no byte is left over. On failure the
/// arena holds no quantized table and `*qtable` is NULL.
///
/// Lifetime: the handle reads `bytes` on every call: they must stay in place and
/// unchanged while it is used (a section in flash, or a buffer not reused). The arena
/// holds pointers into itself: do not copy or move it (a copy is refused with
/// `MLMAP_ERR_MOVED`).
///
/// Work: the CRC-32 over the section, then one pass over it; the arena's bytes beyond
/// `MLMAP_QTABLE_ARENA_SIZE(k)` are never touched.
///
/// @param[out] arena The storage, aligned to 8 (`static MLMAP_ALIGN8 uint8_t
///   arena[MLMAP_QTABLE_ARENA_SIZE(3)]`), or `MLMAP_ERR_MISALIGNED`.
/// @param arena_size Bytes of the arena: at least `MLMAP_QTABLE_ARENA_SIZE(k)`
///   (`MLMAP_ERR_STORAGE_TOO_SMALL`, and `detail->needed` says how many).
/// @param bytes The section's bytes; must not overlap the arena (`MLMAP_ERR_OVERLAP`).
/// @param len Number of bytes.
/// @param[out] qtable Receives the handle (the arena's address) on success, NULL on
///   failure; may be NULL.
/// @param[out] detail If not NULL, receives the status and, for an invalid section, the
///   field (`MLMAP_FIELD_SCALE`, `_ZERO_POINT`, `_CODE_WINDOW`, `_BIN_INDEX`, `_MASS`,
///   `_LOG_TERM`, `_LOG_UNKNOWN`, `_TABLE_CRC`, `_SHAPE`, `_LAMBDA`, `_TEMPERATURE`,
///   `_EPSILON`, `_MAP`, `_OBJECTNESS`) and the class or logit it is about.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_STORAGE_TOO_SMALL`, `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_TOO_LARGE`,
///   `MLMAP_ERR_NO_SECTION`, `MLMAP_ERR_CORRUPTED`, `MLMAP_ERR_UNSUPPORTED_VERSION`,
///   `MLMAP_ERR_SHAPE_TOO_LARGE`, `MLMAP_ERR_INVALID_SECTION` (a value, the layout, or
///   another table's checksum).
#[no_mangle]
pub unsafe extern "C" fn mlmap_qtable_init(
    arena: *mut c_void,
    arena_size: usize,
    bytes: *const u8,
    len: usize,
    qtable: *mut *mut mlmap_qtable_t,
    detail: *mut mlmap_error_t,
) -> mlmap_status_t {
    if !qtable.is_null() {
        if let Err(s) = check_ptr(qtable) {
            return s;
        }
        let t = qtable as usize;
        if describes_memory(arena as usize, arena_size)
            && describes_memory(bytes as usize, len)
            && (overlap(t, P, arena as usize, arena_size) || overlap(t, P, bytes as usize, len))
        {
            return MLMAP_ERR_OVERLAP;
        }
        // SAFETY: non-NULL, aligned, the caller's `mlmap_qtable_t *`.
        unsafe { qtable.write(ptr::null_mut()) };
    }
    let regions = [(arena as usize, arena_size), (bytes as usize, len)];
    // SAFETY: forwarded contract (`detail` is checked by `report`).
    let r = unsafe { init(arena.cast::<u8>(), arena_size, bytes, len) };
    // SAFETY: `detail` is NULL or the caller's `mlmap_error_t`.
    let s = unsafe { report(detail, &regions, r) };
    if s == MLMAP_OK && !qtable.is_null() {
        // SAFETY: checked above.
        unsafe { qtable.write(arena.cast::<mlmap_qtable_t>()) };
    }
    s
}

unsafe fn init(
    arena: *mut u8,
    size: usize,
    bytes: *const u8,
    len: usize,
) -> Result<usize, Failure> {
    check_ptr(arena.cast::<u64>())?;
    check_ptr(bytes)?;
    if size < 8 {
        return Err(Failure::too_small(CONTROL));
    }
    let (a, b) = (arena as usize, bytes as usize);
    if !describes_memory(a, size) || !describes_memory(b, len) {
        return Err(MLMAP_ERR_TOO_LARGE.into());
    }
    if overlap(a, size, b, len) {
        return Err(MLMAP_ERR_OVERLAP.into());
    }
    // SAFETY: non-NULL, aligned to 8, at least 8 bytes: no handle until the end.
    unsafe { arena.cast::<u64>().write(0) };
    // SAFETY: the caller promises `len` readable bytes, disjoint from the arena, left
    // in place and unchanged while the handle is used (the `'static` stands for that).
    let b: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
    let k = classes(b)?;
    let need = arena_bytes(k);
    if need > size {
        return Err(Failure::too_small(need));
    }
    // SAFETY: the records lie at `CONTROL` and `CONTROL + k * size_of::<QClass>()`,
    // inside the `need <= size` bytes of the arena, aligned to 8 (checked at compile
    // time), each slot written before the slice is made; the arena is the caller's
    // for as long as the handle is used (`'static` stands for that).
    let (cls, lgs): (
        &'static mut [QClass<'static>],
        &'static mut [QLogit<'static>],
    ) = unsafe {
        let c = arena.add(CONTROL).cast::<QClass<'static>>();
        let l = arena
            .add(CONTROL + k * size_of::<QClass<'static>>())
            .cast::<QLogit<'static>>();
        for i in 0..k {
            c.add(i).write(EMPTY_QCLASS);
            l.add(i).write(EMPTY_QLOGIT);
        }
        (
            core::slice::from_raw_parts_mut(c, k),
            core::slice::from_raw_parts_mut(l, k),
        )
    };
    let q = LentQTable::from_bytes(b, cls, lgs).map_err(Failure::from)?;
    let control = arena.cast::<Control>();
    // SAFETY: the control block is the first `CONTROL` bytes, disjoint from the
    // records, aligned (checked at compile time).
    unsafe {
        ptr::addr_of_mut!((*control).addr).write(a);
        ptr::addr_of_mut!((*control).used).write(need);
        ptr::addr_of_mut!((*control).bytes).write((b.as_ptr() as usize, len));
        ptr::addr_of_mut!((*control).q).write(q);
        ptr::addr_of_mut!((*control).tag).write(TAG);
    }
    Ok(need)
}

/// The handle in `qtable`.
///
/// # Safety
///
/// `qtable` is NULL or points to an arena that is zeroed or was passed to
/// `mlmap_qtable_init`.
#[inline(always)]
unsafe fn handle<'a>(qtable: *const mlmap_qtable_t) -> Result<&'a Control, mlmap_status_t> {
    let control = qtable.cast::<Control>();
    check_ptr(control)?;
    // SAFETY: non-NULL and aligned; every arena has at least the tag.
    if unsafe { ptr::addr_of!((*control).tag).read() } != TAG {
        return Err(MLMAP_ERR_NO_QTABLE);
    }
    // SAFETY: the tag is written only after a successful init wrote the control block.
    let c = unsafe { &*control };
    if c.addr != control as usize {
        return Err(MLMAP_ERR_MOVED);
    }
    Ok(c)
}

/// Refuses an output of `n` bytes at `out` that overlaps the arena the handle uses or
/// the section's bytes.
#[inline(always)]
fn outside(c: &Control, out: usize, n: usize) -> Result<(), mlmap_status_t> {
    if overlap(out, n, c.addr, c.used) || overlap(out, n, c.bytes.0, c.bytes.1) {
        Err(MLMAP_ERR_OVERLAP)
    } else {
        Ok(())
    }
}

/// Reports what a quantized table holds.
///
/// @param qtable A handle from mlmap_qtable_init().
/// @param[out] info Receives the description; must not overlap the arena or the bytes.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_QTABLE`, `MLMAP_ERR_MOVED`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_qtable_info(
    qtable: *const mlmap_qtable_t,
    info: *mut mlmap_qtable_info_t,
) -> mlmap_status_t {
    status((|| {
        // SAFETY: forwarded contract.
        let c = unsafe { handle(qtable) }?;
        check_ptr(info)?;
        outside(c, info as usize, size_of::<mlmap_qtable_info_t>())?;
        let q = &c.q;
        let open = q.open_params();
        let value = mlmap_qtable_info_t {
            classes: q.k(),
            bits: u32::from(q.bits()),
            categories: q.categories(),
            has_open: u32::from(open.is_some()),
            temperature: open.map_or(0.0, |o| o.temperature()),
            epsilon: open.map_or(0.0, |o| o.epsilon()),
            table_crc: q.table_crc(),
            section_len: q.section_len(),
        };
        // SAFETY: checked above.
        unsafe { put(info, value) }
    })())
}

/// The quantization of one class: a code `q` stands for the logit `(q - zero_point) *
/// scale` (in `float`: `(float)(q - zero_point) * scale`).
///
/// @param qtable A handle from mlmap_qtable_init().
/// @param class_index The class, below K.
/// @param[out] scale Receives the class's scale.
/// @param[out] zero_point Receives the class's zero point.
/// @return `MLMAP_OK`; `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_QTABLE`, `MLMAP_ERR_MOVED`, `MLMAP_ERR_CLASS_INDEX`,
///   `MLMAP_ERR_OVERLAP` (the outputs overlap each other, the arena or the bytes).
#[no_mangle]
pub unsafe extern "C" fn mlmap_qtable_params(
    qtable: *const mlmap_qtable_t,
    class_index: usize,
    scale: *mut f32,
    zero_point: *mut i32,
) -> mlmap_status_t {
    status((|| {
        // SAFETY: forwarded contract.
        let c = unsafe { handle(qtable) }?;
        check_ptr(scale)?;
        check_ptr(zero_point)?;
        outside(c, scale as usize, 4)?;
        outside(c, zero_point as usize, 4)?;
        if overlap(scale as usize, 4, zero_point as usize, 4) {
            return Err(MLMAP_ERR_OVERLAP);
        }
        let (s, z) = c.q.params(class_index).ok_or(MLMAP_ERR_CLASS_INDEX)?;
        // SAFETY: checked above.
        unsafe {
            put(scale, s)?;
            put(zero_point, z)
        }
    })())
}

mod score;
pub use score::*;
