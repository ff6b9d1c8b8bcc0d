//! The layout of the C API's arena ([`ArenaLayout`]): where each item of a table of a
//! given [`StorageShape`] lives, on a target of a given pointer size.

use super::StorageShape;
use crate::format::name::ClassName;
use crate::format::wire::Settings;
use crate::heads::recal::Knot;
use crate::math::gaussian::Gaussian;
use crate::math::histogram::Axis;

/// The layout of the C API's arena (`mlmap_table_init`) for a table of a given
/// [`StorageShape`] on a target of a given pointer size: the offset of each region,
/// every one a multiple of 8, and the total. The arena starts with a control block of
/// [`ArenaLayout::control`] bytes; every item is stored at its type's size on that
/// target, which the C API checks at compile time against this model. The total is
/// `a + b * pointer` for two integers of the shape (`mlmap export-c` writes it so, with
/// `sizeof(void *)`), and [`ARENA_LAYOUT`] names this layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ArenaLayout {
    /// K class names of [`NAME_BYTES`] each.
    pub names: usize,
    /// K row counts (`u64`).
    pub rows: usize,
    /// K priors of [`PRIOR_BYTES`] each.
    pub priors: usize,
    /// K ML histograms of [`ArenaLayout::histogram`] bytes each.
    pub ml: usize,
    /// K MAP histograms.
    pub map: usize,
    /// The settings ([`SETTINGS_BYTES`]).
    pub settings: usize,
    /// The Bayes head's K axes of [`AXIS_BYTES`] each (none without the head).
    pub axes: usize,
    /// The Bayes head's row counts (`u64`, one per category).
    pub bayes_rows: usize,
    /// The Bayes head's log-priors (`f32`, one per category).
    pub log_prior: usize,
    /// The objectness feature's axis (one with the feature, none without).
    pub objectness_axis: usize,
    /// Every map's knots, the ML head's first ([`KNOT_BYTES`] each).
    pub knots: usize,
    /// Every float: the ML frequencies (class-major), the MAP frequencies, the Bayes
    /// log-terms, the objectness feature's terms.
    pub floats: usize,
    /// Decoder scratch: K names as parsed (two pointers each).
    pub scratch_names: usize,
    /// Decoder scratch: K pairs of counts (two pointers each).
    pub scratch_lens: usize,
    /// Bytes of the whole arena.
    pub size: usize,
}

/// The version of [`ArenaLayout`]: a change of layout changes it, so that a size
/// written for one layout is never taken for another's.
pub const ARENA_LAYOUT: u32 = 1;
/// Bytes of a class name in the arena.
pub const NAME_BYTES: usize = core::mem::size_of::<ClassName>();
/// Bytes of a prior in the arena.
pub const PRIOR_BYTES: usize = core::mem::size_of::<Gaussian>();
/// Bytes of an axis in the arena.
pub const AXIS_BYTES: usize = core::mem::size_of::<Axis>();
/// Bytes of a knot in the arena.
pub const KNOT_BYTES: usize = core::mem::size_of::<Knot>();
/// Bytes reserved for the settings in the arena.
pub const SETTINGS_BYTES: usize = 16;

// The model holds on every target: these types hold no pointer.
const _: () = assert!(NAME_BYTES == 32 && PRIOR_BYTES == 16 && AXIS_BYTES == 24);
const _: () = assert!(KNOT_BYTES == 8 && core::mem::size_of::<Settings>() <= SETTINGS_BYTES);

impl ArenaLayout {
    /// Bytes of the control block on a target of `pointer`-byte pointers.
    pub const fn control(pointer: usize) -> usize {
        64 + 32 * pointer
    }

    /// Bytes of a histogram over a borrowed slice of frequencies.
    pub const fn histogram(pointer: usize) -> usize {
        16 + 2 * pointer
    }

    /// The layout of `shape` on a target of `pointer`-byte pointers; `None` when a
    /// size overflows `usize`.
    pub fn new(shape: &StorageShape, pointer: usize) -> Option<Self> {
        let k = shape.classes;
        let bayes = shape.bins_bayes > 0;
        let cats = if bayes { shape.categories } else { 0 };
        let os = usize::from(bayes && shape.objectness);
        let round8 = |n: usize| n.checked_add(7).map(|n| n & !7);
        let mut at = Self::control(pointer);
        let mut next = |bytes: Option<usize>| -> Option<usize> {
            let start = at;
            at = at.checked_add(round8(bytes?)?)?;
            Some(start)
        };
        let knots: usize = shape
            .knots
            .iter()
            .try_fold(0usize, |a, &n| a.checked_add(n))?;
        let floats = shape.floats();
        let os_terms = os.checked_mul(cats)?.checked_mul(shape.bins_bayes)?;
        let names = next(k.checked_mul(NAME_BYTES))?;
        let rows = next(k.checked_mul(8))?;
        let priors = next(k.checked_mul(PRIOR_BYTES))?;
        let ml = next(k.checked_mul(Self::histogram(pointer)))?;
        let map = next(k.checked_mul(Self::histogram(pointer)))?;
        let settings = next(Some(SETTINGS_BYTES))?;
        let axes = next(if bayes {
            k.checked_mul(AXIS_BYTES)
        } else {
            Some(0)
        })?;
        let bayes_rows = next(cats.checked_mul(8))?;
        let log_prior = next(cats.checked_mul(4))?;
        let objectness_axis = next(os.checked_mul(AXIS_BYTES))?;
        let knots = next(knots.checked_mul(KNOT_BYTES))?;
        let floats = next(floats.checked_add(os_terms)?.checked_mul(4))?;
        let scratch_names = next(k.checked_mul(2 * pointer))?;
        let scratch_lens = next(k.checked_mul(2 * pointer))?;
        Some(Self {
            names,
            rows,
            priors,
            ml,
            map,
            settings,
            axes,
            bayes_rows,
            log_prior,
            objectness_axis,
            knots,
            floats,
            scratch_names,
            scratch_lens,
            size: at,
        })
    }

    /// The arena's size as `(a, b)`, `a + b * pointer` bytes for any pointer size of 4
    /// or 8 (what `mlmap export-c` writes, with `sizeof(void *)`); `None` on overflow.
    pub fn size_terms(shape: &StorageShape) -> Option<(usize, usize)> {
        let (s4, s8) = (Self::new(shape, 4)?.size, Self::new(shape, 8)?.size);
        let b = (s8.checked_sub(s4)?) / 4;
        Some((s4.checked_sub(4 * b)?, b))
    }
}
