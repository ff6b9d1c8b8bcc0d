//! The table storage: an arena the caller owns, carved into the typed slices of one
//! table's exact shape ([`mlmap::lent::ArenaLayout`]) and filled by the one decoder
//! ([`mlmap::lent::LentTable`]). A `mlmap_table_t` is the same arena at the largest
//! shape of the build.
//!
//! This module holds the crate's only code that types raw memory: [`carve`] writes a
//! valid value into every slot of a region before it makes a slice of it, and every
//! region lies inside the arena (checked against its size), is aligned for its type
//! (the arena is aligned to 8, every region starts at a multiple of 8, and no type
//! needs more: checked at compile time) and is disjoint from every other region (the
//! layout places them one after the other).

use core::mem::{align_of, size_of};
use core::ptr;

use mlmap::lent::{
    empty_histogram, ArenaLayout, LentBayes, LentTable, StorageShape, EMPTY_AXIS, EMPTY_KNOT,
    EMPTY_NAME, EMPTY_PRIOR, EMPTY_SETTINGS,
};
use mlmap::{
    Axis, ClassName, DecodeError, Gaussian, Histogram, Knot, QTableError, Settings, TableView,
};

use super::detail::{self, mlmap_field_t};
use super::mlmap_status_t::{self, *};
use super::{check_ptr, mlmap_table_t};

/// The view every scoring call runs on: histograms over frequencies in the arena.
pub(crate) type View<'a> = TableView<'a, &'a mut [f32], &'a mut [f32]>;

/// Bytes of a pointer on this target.
const P: usize = size_of::<usize>();

/// The start of every arena: a tag saying a table was decoded into it, the arena's own
/// address at that time (the view holds pointers into the arena, so a copy of it is not
/// a table), the bytes the table uses, and the view.
#[repr(C)]
pub(crate) struct Control {
    tag: u64,
    addr: usize,
    used: usize,
    view: View<'static>,
}

/// Written into [`Control::tag`] when a decode succeeds.
const TAG: u64 = u64::from_le_bytes(*b"MLMParn1");

// The layout model of `mlmap::lent::ArenaLayout` is this target's: each item takes the
// bytes the model gives it, and no type needs more than the 8-byte alignment of the
// arena and of every region.
const _: () = assert!(size_of::<Control>() <= ArenaLayout::control(P));
const _: () = assert!(size_of::<Histogram<&mut [f32]>>() == ArenaLayout::histogram(P));
const _: () = assert!(size_of::<ClassName>() == mlmap::lent::NAME_BYTES);
const _: () = assert!(size_of::<Gaussian>() == mlmap::lent::PRIOR_BYTES);
const _: () = assert!(size_of::<Axis>() == mlmap::lent::AXIS_BYTES);
const _: () = assert!(size_of::<Knot>() == mlmap::lent::KNOT_BYTES);
const _: () = assert!(size_of::<Settings>() <= mlmap::lent::SETTINGS_BYTES);
const _: () = assert!(size_of::<&str>() == 2 * P && size_of::<(usize, usize)>() == 2 * P);
const _: () = assert!(
    align_of::<Control>() <= ARENA_ALIGN
        && align_of::<Histogram<&mut [f32]>>() <= ARENA_ALIGN
        && align_of::<ClassName>() <= ARENA_ALIGN
        && align_of::<Gaussian>() <= ARENA_ALIGN
        && align_of::<Axis>() <= ARENA_ALIGN
        && align_of::<Knot>() <= ARENA_ALIGN
        && align_of::<Settings>() <= ARENA_ALIGN
        && align_of::<u64>() <= ARENA_ALIGN
        && align_of::<&str>() <= ARENA_ALIGN
        && align_of::<(usize, usize)>() <= ARENA_ALIGN
);

/// Alignment of an arena in bytes.
pub(crate) const ARENA_ALIGN: usize = 8;

/// Where a decode failed: the status, the field, head and class it is about
/// (`mlmap_error_t`), and the bytes the table needs when known.
pub(crate) struct Failure {
    pub(crate) status: mlmap_status_t,
    pub(crate) at: (mlmap_field_t, i32, i32),
    /// Bytes the table needs, when known.
    pub(crate) needed: usize,
}

impl Failure {
    /// Storage smaller than the `needed` bytes.
    pub(crate) fn too_small(needed: usize) -> Self {
        Self {
            status: MLMAP_ERR_STORAGE_TOO_SMALL,
            at: (mlmap_field_t::MLMAP_FIELD_STORAGE, -1, -1),
            needed,
        }
    }

    /// A decode error of `bytes`; a malformed body is located by a second parse.
    pub(crate) fn decoding(e: DecodeError, bytes: &[u8]) -> Self {
        let mut f = Self::from(e);
        if e == DecodeError::Malformed {
            if let Some(part) = mlmap::locate_malformed(bytes) {
                f.at = detail::locate_part(part);
            }
        }
        f
    }
}

impl From<mlmap_status_t> for Failure {
    fn from(status: mlmap_status_t) -> Self {
        Self {
            status,
            at: (mlmap_field_t::MLMAP_FIELD_NONE, -1, -1),
            needed: 0,
        }
    }
}

impl From<DecodeError> for Failure {
    fn from(e: DecodeError) -> Self {
        Self {
            status: e.into(),
            at: detail::locate(e),
            needed: 0,
        }
    }
}

impl From<QTableError> for Failure {
    fn from(e: QTableError) -> Self {
        Self {
            status: e.into(),
            at: crate::quantized::locate(e),
            needed: 0,
        }
    }
}

/// The layout of `shape` on this target.
pub(crate) fn layout(shape: &StorageShape) -> Result<ArenaLayout, mlmap_status_t> {
    ArenaLayout::new(shape, P).ok_or(MLMAP_ERR_TOO_LARGE)
}

/// `n` items of `T` at `at` bytes into the arena, each first set to `init(i)`.
///
/// # Safety
///
/// `base` is aligned to [`ARENA_ALIGN`]; `at` is a multiple of 8 and `at + n *
/// size_of::<T>()` bytes from `base` lie in memory the caller owns, used by nothing else
/// for `'t`; `align_of::<T>() <= ARENA_ALIGN`.
unsafe fn carve<'t, T>(
    base: *mut u8,
    at: usize,
    n: usize,
    mut init: impl FnMut(usize) -> T,
) -> &'t mut [T] {
    // SAFETY: inside the caller's memory, aligned for `T` (see above).
    let first = unsafe { base.add(at) }.cast::<T>();
    for i in 0..n {
        // SAFETY: slot `i` of the region, written before the slice is made, so every
        // element of the slice is a valid `T`.
        unsafe { first.add(i).write(init(i)) };
    }
    // SAFETY: `n` initialised, aligned, exclusively owned `T`s.
    unsafe { core::slice::from_raw_parts_mut(first, n) }
}

/// Splits the front `n` floats off `rest`.
fn take<'t>(rest: &mut &'t mut [f32], n: usize) -> &'t mut [f32] {
    let all = core::mem::take(rest);
    let (head, tail) = all.split_at_mut(n.min(all.len()));
    *rest = tail;
    head
}

/// Decodes `bytes`, whose shape is `shape`, into the arena at `arena` of `size` bytes,
/// and marks it as holding a table of `max(reserve, its size)` bytes (the bytes no
/// output may overlap); the caller has cleared the tag.
///
/// # Safety
///
/// `arena` is aligned to [`ARENA_ALIGN`] and `size` bytes there are the caller's,
/// disjoint from `bytes`.
pub(crate) unsafe fn decode_into(
    arena: *mut u8,
    size: usize,
    bytes: &[u8],
    shape: &StorageShape,
    reserve: usize,
) -> Result<(), Failure> {
    let l = layout(shape)?;
    if l.size > size {
        return Err(Failure::too_small(l.size));
    }
    let k = shape.classes;
    let bayes = shape.bins_bayes > 0;
    let cats = if bayes { shape.categories } else { 0 };
    let os = usize::from(bayes && shape.objectness);
    let terms = cats * k * shape.bins_bayes;
    let os_terms = os * cats * shape.bins_bayes;
    let floats = shape.floats() + os_terms;
    // SAFETY (every `carve` below): `ArenaLayout::new` placed the regions one after the
    // other inside `l.size <= size` bytes, each at a multiple of 8 and with room for its
    // items at the sizes checked at compile time above.
    let (names, rows, priors, settings, knots, raw, lens) = unsafe {
        (
            carve::<ClassName>(arena, l.names, k, |_| EMPTY_NAME),
            carve::<u64>(arena, l.rows, k, |_| 0),
            carve::<Gaussian>(arena, l.priors, k, |_| EMPTY_PRIOR),
            carve::<Settings>(arena, l.settings, 1, |_| EMPTY_SETTINGS),
            carve::<Knot>(arena, l.knots, shape.knots.iter().sum(), |_| EMPTY_KNOT),
            carve::<&str>(arena, l.scratch_names, k, |_| ""),
            carve::<(usize, usize)>(arena, l.scratch_lens, k, |_| (0, 0)),
        )
    };
    // SAFETY: as above.
    let mut all = unsafe { carve::<f32>(arena, l.floats, floats, |_| 0.0) };
    let mut ml_f = take(&mut all, k * shape.bins_ml);
    let mut map_f = take(&mut all, k * shape.bins_map);
    let terms = take(&mut all, terms);
    let os_terms = take(&mut all, os_terms);
    // SAFETY: as above.
    let (ml, map) = unsafe {
        (
            carve::<Histogram<&mut [f32]>>(arena, l.ml, k, |_| {
                empty_histogram(take(&mut ml_f, shape.bins_ml))
            }),
            carve::<Histogram<&mut [f32]>>(arena, l.map, k, |_| {
                empty_histogram(take(&mut map_f, shape.bins_map))
            }),
        )
    };
    let bayes = if bayes {
        // SAFETY: as above.
        Some(unsafe {
            LentBayes {
                axes: carve::<Axis>(arena, l.axes, k, |_| EMPTY_AXIS),
                terms,
                rows: carve::<u64>(arena, l.bayes_rows, cats, |_| 0),
                log_prior: carve::<f32>(arena, l.log_prior, cats, |_| 0.0),
                objectness_axis: carve::<Axis>(arena, l.objectness_axis, os, |_| EMPTY_AXIS),
                objectness_terms: os_terms,
            }
        })
    } else {
        None
    };
    let mut knots: &mut [Knot] = knots;
    let mut lent_knots: [&mut [Knot]; 4] = [&mut [], &mut [], &mut [], &mut []];
    for (slot, &n) in lent_knots.iter_mut().zip(&shape.knots) {
        let all = core::mem::take(&mut knots);
        let (head, tail) = all.split_at_mut(n.min(all.len()));
        *slot = head;
        knots = tail;
    }
    let view = LentTable::lend(
        names,
        rows,
        priors,
        ml,
        map,
        settings.first_mut().ok_or(MLMAP_ERR_TOO_LARGE)?,
        bayes,
        lent_knots,
    )
    .decode(bytes, raw, lens)
    .map_err(|e| Failure::decoding(e, bytes))?;
    let control = arena.cast::<Control>();
    // SAFETY: the control block is the first `ArenaLayout::control(P)` bytes, disjoint
    // from every region, aligned (checked above); the view borrows the regions for as
    // long as the table is in the arena, which the tag stands for.
    unsafe {
        ptr::addr_of_mut!((*control).addr).write(arena as usize);
        ptr::addr_of_mut!((*control).used).write(l.size.max(reserve));
        ptr::addr_of_mut!((*control).view).write(view);
        ptr::addr_of_mut!((*control).tag).write(TAG);
    }
    Ok(())
}

/// Marks the arena as holding no table.
///
/// # Safety
///
/// `arena` is aligned to [`ARENA_ALIGN`] with at least 8 writable bytes.
pub(crate) unsafe fn clear(arena: *mut u8) {
    // SAFETY: the caller's promise.
    unsafe { arena.cast::<u64>().write(0) };
}

/// The decoded table in `table`, and the bytes of the arena it uses.
///
/// # Safety
///
/// `table` is NULL or points to an arena that is zeroed or was passed to a decode.
#[inline(always)]
pub(crate) unsafe fn table_ref<'a>(
    table: *const mlmap_table_t,
) -> Result<(&'a View<'a>, usize), mlmap_status_t> {
    let control = table.cast::<Control>();
    check_ptr(control)?;
    // SAFETY: non-NULL and aligned; every arena has at least the tag.
    if unsafe { ptr::addr_of!((*control).tag).read() } != TAG {
        return Err(MLMAP_ERR_NO_TABLE);
    }
    // SAFETY: the tag is written only after a successful decode wrote the control block.
    let c = unsafe { &*control };
    if c.addr != control as usize {
        return Err(MLMAP_ERR_MOVED);
    }
    Ok((&c.view, c.used))
}
