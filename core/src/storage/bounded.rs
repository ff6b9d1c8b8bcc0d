//! Storage whose shape is known only at run time but bounded at compile time:
//! [`Bounded`] (up to `N` floats) and [`BoundedTable`] (a table of any shape up to a
//! maximum). For firmware that receives its table at run time (a calibration sector, a
//! C program through the C API) and must reserve its memory statically.
//!
//! A `BoundedTable` is the one [`TableInner`] over fixed arrays ([`BoundedStorage`])
//! of which it records the prefix in use: the same decoder, [`TableView`] (encoding,
//! scoring) and accessors as [`Table`](crate::Table) and `DynTable`. It accepts exactly
//! the bytes `DynTable::from_bytes` accepts, as long as their shape fits, and gives
//! bit-identical scores.

use crate::diagnostics::error::DecodeError;
use crate::format::name::ClassName;
use crate::format::wire::{self, Settings};
use crate::heads::recal::{Knot, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::storage::inner::{private::Sealed, InUse, Storage, TableInner};
use crate::storage::lent::StorageShape;
use crate::storage::view::TableView;

/// Up to `N` floats, the number in use known at run time: the frequency storage of a
/// [`BoundedTable`]'s histograms (`Histogram<Bounded<N>>`).
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::Bounded;
///
/// let mut b = Bounded::<4>::from_slice(&[0.25, 0.75]).ok_or("too long")?;
/// assert_eq!(b.as_ref(), &[0.25, 0.75]);
/// b.as_mut()[0] = 0.5;
/// assert_eq!(b.as_ref(), &[0.5, 0.75]);
/// assert!(Bounded::<1>::from_slice(&[0.5, 0.5]).is_none());
/// # Ok::<(), &str>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounded<const N: usize> {
    /// Floats in use, at most `N`.
    len: usize,
    data: [f32; N],
}

impl<const N: usize> Bounded<N> {
    /// No float in use.
    pub const EMPTY: Self = Self {
        len: 0,
        data: [0.0; N],
    };

    /// The floats of `values`; `None` when there are more than `N`.
    pub fn from_slice(values: &[f32]) -> Option<Self> {
        let mut b = Self::EMPTY;
        if !b.set_len(values.len()) {
            return None;
        }
        for (d, &v) in b.data.iter_mut().zip(values) {
            *d = v;
        }
        Some(b)
    }

    /// Number of floats in use.
    #[inline]
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether no float is in use.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Uses the first `len` floats (their values are kept); `false`, and nothing
    /// changed, when `len > N`.
    pub(crate) fn set_len(&mut self, len: usize) -> bool {
        if len > N {
            return false;
        }
        self.len = len;
        true
    }
}

impl<const N: usize> Default for Bounded<N> {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl<const N: usize> AsRef<[f32]> for Bounded<N> {
    #[inline]
    fn as_ref(&self) -> &[f32] {
        // `len <= N` always holds; the fallback is never taken.
        self.data.get(..self.len).unwrap_or(&[])
    }
}

impl<const N: usize> AsMut<[f32]> for Bounded<N> {
    #[inline]
    fn as_mut(&mut self) -> &mut [f32] {
        self.data.get_mut(..self.len).unwrap_or(&mut [])
    }
}

/// A table of any shape up to `K` classes, `B_ML` and `B_MAP` bins in the ML and MAP
/// heads, and a Bayes head of up to `B_BAYES` bins and `C` categories (`C = K + 1`
/// holds every Bayes head of up to `K` classes; `B_BAYES = C = 0` accepts only tables
/// without one). The shape is read from the bytes when they are decoded.
///
/// The table is either empty (as built by [`BoundedTable::new`], or after a failed
/// decode) or holds a table that satisfies every invariant; [`BoundedTable::view`]
/// lends the latter to [`TableView`], which encodes and scores it.
///
/// It is as large as its maximum shape: put it in a `static` (or decode into one with
/// [`BoundedTable::decode`]) rather than on a small stack. Every field of an empty
/// table is zero, so an all-zero block of memory of its size is an empty table.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{BoundedTable, Libm};
///
/// // Up to 8 classes and 32 bins per head, with or without a Bayes head.
/// let mut table = BoundedTable::<8, 32, 32, 32, 9>::new();
/// assert!(table.view().is_none());
///
/// table.decode(include_bytes!("../../../tables/default.mlmap"))?;
/// let view = table.view().ok_or("empty")?;
/// assert_eq!((view.k(), view.bins_ml(), view.bins_map()), (3, 22, 17));
///
/// let (mut out, mut scratch) = ([0.0; 3], [0.0; 3]);
/// view.map_into::<Libm>(&[5.1, -2.0, -1.3], 0.93, &mut out, &mut scratch)?;
/// assert_eq!(mlmap::decide(&out, &[5.1, -2.0, -1.3]), 0);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
pub type BoundedTable<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
    const N: usize = 0,
    const F: usize = 0,
> = TableInner<BoundedStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>>;

/// The storage of a [`BoundedTable`]: arrays of its maximum shape, of which a prefix is
/// in use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundedStorage<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
    const N: usize,
    const F: usize,
>;

/// The shape in use of a [`BoundedTable`] (all zeros: empty).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BoundedExtent {
    /// Classes in use; 0 for an empty table.
    pub(crate) classes: usize,
    /// Bayes bins per logit in use; 0 without a Bayes head.
    pub(crate) bins_bayes: usize,
    /// Bayes categories in use; 0 without a Bayes head.
    pub(crate) categories: usize,
    /// Whether the table in use has the objectness feature.
    pub(crate) objectness: bool,
}

impl BoundedExtent {
    const EMPTY: Self = Self {
        classes: 0,
        bins_bayes: 0,
        categories: 0,
        objectness: false,
    };
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Sealed for BoundedStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Storage for BoundedStorage<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    type Names = [ClassName; K];
    type Rows = [u64; K];
    type Priors = [Gaussian; K];
    type MlFreqs = Bounded<B_ML>;
    type MapFreqs = Bounded<B_MAP>;
    type Ml = [Histogram<Bounded<B_ML>>; K];
    type Map = [Histogram<Bounded<B_MAP>>; K];
    type Settings = Settings;
    type Axes = [Axis; K];
    /// The log-terms as one flat buffer (the array's shape only bounds its length): the
    /// first `categories * k * bins` floats hold them logit-major (logit, bin, category),
    /// as [`BayesView`](crate::BayesView) reads them.
    type Terms = [[[f32; B_BAYES]; K]; C];
    type Categories = [u64; C];
    type LogPrior = [f32; C];
    type Knots = [Knot; N];
    type ObjectnessAxis = [Axis; F];
    type ObjectnessTerms = [[[f32; B_BAYES]; C]; F];
    type Extent = BoundedExtent;
    type View<'a> = Option<TableView<'a, Bounded<B_ML>, Bounded<B_MAP>>>;

    const NAME: &'static str = "BoundedTable";
    const OBJECTNESS_REQUIRED: bool = false;

    #[inline]
    fn in_use(t: &BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>) -> InUse {
        let e = t.extent;
        InUse {
            classes: e.classes,
            bayes: e.bins_bayes > 0,
            categories: e.categories,
            terms: e
                .categories
                .saturating_mul(e.classes)
                .saturating_mul(e.bins_bayes),
            objectness: e.objectness,
            objectness_terms: e.categories.saturating_mul(e.bins_bayes),
            maps: N > 0,
        }
    }

    /// Refuses a shape above the maximum and a body too short for the shape; sets the
    /// number of frequencies of each histogram in use.
    fn prepare(
        t: &mut BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        s: &StorageShape,
        (shape, bayes_shape): ((u16, u16, u16), (u16, u16)),
        body: usize,
    ) -> Result<(), DecodeError> {
        if s.classes > K || s.bins_ml > B_ML || s.bins_map > B_MAP {
            return Err(DecodeError::ShapeMismatch {
                expected: BoundedTable::<K, B_ML, B_MAP, B_BAYES, C, N, F>::MAX_SHAPE,
                found: shape,
            });
        }
        if s.bins_bayes > B_BAYES || s.categories > C {
            return Err(DecodeError::BayesShapeMismatch {
                expected: BoundedTable::<K, B_ML, B_MAP, B_BAYES, C, N, F>::MAX_BAYES_SHAPE,
                found: bayes_shape,
            });
        }
        // As `DynTable::from_bytes`: every frequency and term takes 4 bytes of the body, so
        // a header announcing more than the body holds is malformed (the same error for
        // the same bytes on the host and here).
        if s.floats().saturating_mul(4) > body {
            return Err(DecodeError::Malformed);
        }
        // Each histogram of a class in use holds the announced number of frequencies
        // (a longer sequence is malformed, a shorter one has the wrong bin count).
        let malformed = DecodeError::Malformed;
        for h in t.ml.get_mut(..s.classes).ok_or(malformed)? {
            h.freqs.set_len(s.bins_ml);
        }
        for h in t.map.get_mut(..s.classes).ok_or(malformed)? {
            h.freqs.set_len(s.bins_map);
        }
        Ok(())
    }

    fn finish(
        t: &mut BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        s: &StorageShape,
        objectness: bool,
        _: [usize; 4],
    ) {
        t.extent = BoundedExtent {
            classes: s.classes,
            bins_bayes: s.bins_bayes,
            categories: s.categories,
            objectness,
        };
    }

    #[inline]
    fn wrap<'a>(
        t: &'a BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>,
        view: TableView<'a, Bounded<B_ML>, Bounded<B_MAP>>,
    ) -> Option<TableView<'a, Bounded<B_ML>, Bounded<B_MAP>>> {
        (t.extent.classes > 0).then_some(view)
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    const SHAPE_OK: () = assert!(
        K >= 2
            && K < u16::MAX as usize
            && B_ML >= 1
            && B_ML <= u16::MAX as usize
            && B_MAP >= 1
            && B_MAP <= u16::MAX as usize
            && B_BAYES <= u16::MAX as usize
            && C <= u16::MAX as usize
            && ((B_BAYES == 0) == (C == 0))
            && N <= MAX_KNOTS
            && F <= 1,
        "a BoundedTable holds up to 2..65535 classes and 1..=65535 bins per head; \
         B_BAYES and C are both 0 (no Bayes head) or both positive; at most MAX_KNOTS \
         knots per map"
    );

    /// The largest `(K, ML bins, MAP bins)` this type holds, as reported by
    /// [`DecodeError::ShapeMismatch`].
    pub const MAX_SHAPE: (u16, u16, u16) = (K as u16, B_ML as u16, B_MAP as u16);

    /// The largest `(Bayes bins, categories)` this type holds, as reported by
    /// [`DecodeError::BayesShapeMismatch`].
    pub const MAX_BAYES_SHAPE: (u16, u16) = (B_BAYES as u16, C as u16);

    /// Largest number of bytes the encoding of a table of this type takes.
    pub const MAX_ENCODED_LEN: usize = wire::max_encoded_len(K, B_ML, B_MAP, B_BAYES, C, N, F);

    /// An empty table (all zeros).
    pub const fn new() -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        const fn hist<const B: usize>() -> Histogram<Bounded<B>> {
            Histogram {
                lo: 0.0,
                hi: 0.0,
                width: 0.0,
                inv_width: 0.0,
                freqs: Bounded::EMPTY,
            }
        }
        Self {
            names: [ClassName::EMPTY; K],
            rows: [0; K],
            priors: [Gaussian::ZERO; K],
            ml: [hist::<B_ML>(); K],
            map: [hist::<B_MAP>(); K],
            settings: Settings::ZERO,
            bayes_axes: [Axis::ZERO; K],
            bayes_terms: [[[0.0; B_BAYES]; K]; C],
            bayes_rows: [0; C],
            bayes_log_prior: [0.0; C],
            bayes_lambda: 0.0,
            bayes_log_lambda: 0.0,
            bayes_open: None,
            recal: [[Knot::ZERO; N]; 4],
            recal_len: [0; 4],
            bayes_os_axis: [Axis::ZERO; F],
            bayes_os_terms: [[[0.0; B_BAYES]; C]; F],
            extent: BoundedExtent::EMPTY,
        }
    }

    /// Decodes and validates a table into this storage, in place (nothing the size of
    /// the table is built on the stack), replacing what it held. On error the table is
    /// empty.
    ///
    /// # Errors
    ///
    /// As [`Table::from_bytes`](crate::Table::from_bytes), where a shape mismatch means
    /// a shape above the maximum: [`DecodeError::ShapeMismatch`] (with
    /// [`Self::MAX_SHAPE`] as `expected`) for more classes or bins than `K`, `B_ML`,
    /// `B_MAP`; [`DecodeError::BayesShapeMismatch`] (with [`Self::MAX_BAYES_SHAPE`])
    /// for a Bayes head above `B_BAYES` bins or `C` categories.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn decode(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        #[allow(clippy::let_unit_value)]
        let () = Self::SHAPE_OK;
        self.clear();
        let result = self.decode_with(bytes, |_| ([""; K], [(0, 0); K]));
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Decodes a table into a new `BoundedTable` (which the caller then moves: prefer
    /// [`BoundedTable::decode`] into a `static` on a small stack).
    ///
    /// # Errors
    ///
    /// As [`BoundedTable::decode`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DecodeError> {
        let mut t = Self::new();
        t.decode(bytes)?;
        Ok(t)
    }

    /// Empties the table.
    pub fn clear(&mut self) {
        self.extent = BoundedExtent::EMPTY;
        self.recal_len = [0; 4];
    }

    /// Whether the table holds no table.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.extent.classes == 0
    }
}

impl<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    > Default for BoundedTable<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Libm, Table};
    use std::boxed::Box;
    use std::vec::Vec;

    const SHIPPED: &[u8] = include_bytes!("../../../tables/default.mlmap");
    const SMALL: &[u8] = include_bytes!("../../../tests/golden/layer/small.mlmap");

    /// The C API's default maximum shape.
    type Big = BoundedTable<16, 64, 64, 64, 17>;

    fn big() -> Box<Big> {
        Box::new(Big::new())
    }

    /// `bytes` with its CRC recomputed.
    #[cfg(feature = "alloc")]
    fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
        let n = bytes.len() - 4;
        let crc = wire::CRC.checksum(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    /// Detections that reach every branch: inside, on and outside the supports,
    /// infinities, objectness 0 and 1.
    fn detections() -> Vec<([f32; 3], f32)> {
        let mut v = Vec::new();
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..2000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = |s: u64| ((s % 4000) as f32 - 2000.0) / 150.0;
            let os = (i % 11) as f32 / 10.0;
            v.push(([x(state), x(state >> 16), x(state >> 32)], os));
        }
        v.push(([f32::INFINITY, f32::NEG_INFINITY, 0.0], 1.0));
        v.push(([1e30, -1e30, 3.0], 0.5));
        v
    }

    #[test]
    fn bounded_holds_at_most_n() {
        let b = Bounded::<3>::from_slice(&[1.0, 2.0, 3.0]).unwrap();
        assert_eq!((b.len(), b.as_ref()), (3, &[1.0, 2.0, 3.0][..]));
        assert!(Bounded::<3>::from_slice(&[0.0; 4]).is_none());
        let mut e = Bounded::<3>::default();
        assert!(e.is_empty() && e.as_ref().is_empty() && e.as_mut().is_empty());
        assert!(!e.set_len(4));
        assert!(e.is_empty());
        assert!(e.set_len(2));
        assert_eq!(e.as_ref(), &[0.0, 0.0]);
    }

    #[test]
    fn histogram_over_bounded_storage() {
        let freqs = Bounded::<8>::from_slice(&[0.5, 0.25, 0.25]).unwrap();
        let h = Histogram::new(0.0, 3.0, freqs).unwrap();
        assert_eq!(h.bins(), 3);
        assert_eq!(h.likelihood(1.5, crate::UpperTail::Zero), 0.25);
        assert_eq!(h.bin(3.0), Some(2));
        let bad = Bounded::<8>::from_slice(&[0.5, 0.25]).unwrap();
        assert!(Histogram::new(0.0, 3.0, bad).is_err());
    }

    #[test]
    fn shipped_table_scores_bit_for_bit_like_the_fixed_table() {
        let fixed = Table::<3, 22, 17, 22, 4>::from_bytes(SHIPPED).unwrap();
        let mut t = big();
        t.decode(SHIPPED).unwrap();
        let v = t.view().unwrap();
        assert_eq!((v.k(), v.bins_ml(), v.bins_map()), (3, 22, 17));
        let b = v.bayes().unwrap();
        assert_eq!((b.bins(), b.categories()), (22, 4));
        let mut buf = [0u8; Big::MAX_ENCODED_LEN];
        assert_eq!(v.encode(&mut buf).unwrap(), SHIPPED);
        for i in 0..3 {
            assert_eq!(v.class_name(i), fixed.class_name(i));
            assert_eq!(v.spec(i), fixed.spec(i));
        }
        let (mut out, mut scratch, mut cats) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 4]);
        let bits = |s: &[f32]| s.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for (x, os) in detections() {
            v.ml_into(&x, os, &mut out, &mut scratch).unwrap();
            assert_eq!(bits(&out), bits(&fixed.ml(&x, os).unwrap().0), "ML {x:?}");
            v.map_into::<Libm>(&x, os, &mut out, &mut scratch).unwrap();
            assert_eq!(bits(&out), bits(&fixed.map(&x, os).unwrap().0), "MAP {x:?}");
            v.bayes_into::<crate::FastMath>(&x, os, &mut out, &mut cats)
                .unwrap();
            assert_eq!(
                bits(&out),
                bits(&fixed.bayes(&x, os).unwrap().0),
                "Bayes {x:?}"
            );
        }
    }

    #[test]
    fn a_table_without_bayes_head_has_none() {
        let mut t = big();
        t.decode(SMALL).unwrap();
        let v = t.view().unwrap();
        assert!(v.bayes().is_none());
        let mut out = [0.0; 3];
        assert_eq!(
            v.bayes_into::<Libm>(&[0.0; 3], 1.0, &mut out, &mut [0.0; 3]),
            Err(crate::InferError::NoBayesHead)
        );
        // A type without Bayes storage takes it, and refuses the shipped table.
        let mut plain = BoundedTable::<4, 4, 4, 0, 0>::new();
        plain.decode(SMALL).unwrap();
        assert_eq!(
            plain.decode(SHIPPED),
            Err(DecodeError::ShapeMismatch {
                expected: (4, 4, 4),
                found: (3, 22, 17)
            })
        );
        let mut no_bayes = BoundedTable::<4, 32, 32, 0, 0>::new();
        assert_eq!(
            no_bayes.decode(SHIPPED),
            Err(DecodeError::BayesShapeMismatch {
                expected: (0, 0),
                found: (22, 4)
            })
        );
        assert!(no_bayes.is_empty());
    }

    #[test]
    fn shapes_above_the_maximum_are_refused_and_leave_it_empty() {
        let mut t = BoundedTable::<3, 22, 17, 21, 4>::new();
        assert_eq!(
            t.decode(SHIPPED),
            Err(DecodeError::BayesShapeMismatch {
                expected: (21, 4),
                found: (22, 4)
            })
        );
        let mut t = BoundedTable::<3, 22, 17, 22, 3>::new();
        assert!(matches!(
            t.decode(SHIPPED),
            Err(DecodeError::BayesShapeMismatch { .. })
        ));
        // Exactly the shape fits.
        let mut t = BoundedTable::<3, 22, 17, 22, 4>::new();
        t.decode(SHIPPED).unwrap();
        assert!(!t.is_empty());
        // A failed decode empties a table that held one.
        let mut corrupt = SHIPPED.to_vec();
        corrupt[40] ^= 1;
        assert_eq!(t.decode(&corrupt), Err(DecodeError::Corrupted));
        assert!(t.is_empty() && t.view().is_none());
        for max in [(2, 22, 17), (3, 21, 17), (3, 22, 16)] {
            let r = match max {
                (2, ..) => BoundedTable::<2, 22, 17, 22, 4>::from_bytes(SHIPPED).map(|_| ()),
                (_, 21, _) => BoundedTable::<3, 21, 17, 22, 4>::from_bytes(SHIPPED).map(|_| ()),
                _ => BoundedTable::<3, 22, 16, 22, 4>::from_bytes(SHIPPED).map(|_| ()),
            };
            assert_eq!(
                r,
                Err(DecodeError::ShapeMismatch {
                    expected: max,
                    found: (3, 22, 17)
                })
            );
        }
    }

    #[test]
    fn decoding_twice_replaces_the_table() {
        let mut t = big();
        t.decode(SHIPPED).unwrap();
        t.decode(SMALL).unwrap();
        let v = t.view().unwrap();
        assert_eq!((v.k(), v.bins_ml(), v.bins_map()), (3, 4, 2));
        assert!(v.bayes().is_none());
        let mut buf = [0u8; Big::MAX_ENCODED_LEN];
        assert_eq!(v.encode(&mut buf).unwrap(), SMALL);
    }

    /// Every single-byte change of both tables (with and without a valid CRC), every
    /// truncation: the bounded table gives the result of the run-time shaped one.
    #[cfg(feature = "alloc")]
    #[test]
    fn accepts_exactly_what_dyn_table_accepts() {
        use crate::DynTable;
        let mut t = big();
        let mut buf = [0u8; Big::MAX_ENCODED_LEN];
        let mut checked = 0;
        for original in [SHIPPED, SMALL] {
            let mut inputs = Vec::new();
            for i in 0..original.len() {
                for v in [0x00u8, original[i] ^ 0x01, original[i] ^ 0x80] {
                    let mut b = original.to_vec();
                    b[i] = v;
                    inputs.push(b.clone());
                    if i + 4 < original.len() {
                        inputs.push(with_crc(b));
                    }
                }
            }
            for len in 0..original.len() {
                inputs.push(original[..len].to_vec());
            }
            for bytes in inputs {
                let dynt = DynTable::from_bytes(&bytes);
                let r = t.decode(&bytes);
                match (&r, &dynt) {
                    (
                        Err(
                            DecodeError::ShapeMismatch { .. }
                            | DecodeError::BayesShapeMismatch { .. },
                        ),
                        _,
                    ) => {
                        // Only a shape above the maximum may be refused for its shape.
                        assert!(dynt.is_err(), "{bytes:02x?}");
                    }
                    (Ok(()), Ok(d)) => {
                        let v = t.view().unwrap();
                        assert_eq!(v.encode(&mut buf).unwrap(), &d.to_vec().unwrap()[..]);
                        assert_eq!(&d.to_vec().unwrap()[..], &bytes[..]);
                    }
                    (r, d) => {
                        assert_eq!(*r, d.as_ref().map(|_| ()).map_err(|e| *e), "{bytes:02x?}")
                    }
                }
                assert_eq!(t.is_empty(), r.is_err());
                checked += 1;
            }
        }
        assert!(checked > 5_000);
    }
}
