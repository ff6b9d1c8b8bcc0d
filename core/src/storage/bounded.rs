//! Storage whose shape is known only at run time but bounded at compile time:
//! [`Bounded`] (up to `N` floats) and [`BoundedTable`] (a table of any shape up to a
//! maximum). For firmware that receives its table at run time (a calibration sector, a
//! C program through the C API) and must reserve its memory statically.
//!
//! A `BoundedTable` owns fixed arrays and lends their used prefixes to the same
//! [`TableView`] (encoding, scoring) and the same decoder as [`Table`](crate::Table) and
//! `DynTable`: it accepts exactly the bytes `DynTable::from_bytes` accepts, as long as
//! their shape fits, and gives bit-identical scores.

use crate::diagnostics::error::{DecodeError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{self, Settings};
use crate::heads::bayes::BayesView;
use crate::heads::open::OpenParams;
use crate::heads::recal::{Knot, Maps, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::storage::view::{BayesStorage, Slots, TableView};

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
#[derive(Debug, Clone, PartialEq)]
pub struct BoundedTable<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
    const N: usize = 0,
    const F: usize = 0,
> {
    /// Classes in use; 0 for an empty table.
    k: usize,
    names: [ClassName; K],
    rows: [u64; K],
    priors: [Gaussian; K],
    ml: [Histogram<Bounded<B_ML>>; K],
    map: [Histogram<Bounded<B_MAP>>; K],
    settings: Settings,
    /// Bayes bins per logit in use; 0 without a Bayes head.
    bayes_bins: usize,
    /// Bayes categories in use; 0 without a Bayes head.
    bayes_categories: usize,
    /// Log-terms in use: `bayes_categories * k * bayes_bins`.
    bayes_terms_len: usize,
    bayes_axes: [Axis; K],
    /// The log-terms as one flat buffer (the array's shape only bounds its length): the
    /// first `categories * k * bins` floats hold them logit-major (logit, bin, category),
    /// as [`BayesView`] reads them.
    bayes_terms: [[[f32; B_BAYES]; K]; C],
    bayes_rows: [u64; C],
    bayes_log_prior: [f32; C],
    bayes_lambda: f32,
    bayes_log_lambda: f32,
    bayes_open: Option<OpenParams>,
    /// Room for each head's recalibration map (DESIGN §1.9): ML, MAP, Bayes, open.
    recal: [[Knot; N]; 4],
    /// Knots in use in each of `recal` (0: no map).
    recal_len: [u8; 4],
    /// Room for the objectness feature (DESIGN §1.6) when `F = 1`: its axis and its
    /// terms (the first `bayes_categories * bayes_bins` in use).
    bayes_os_axis: [Axis; F],
    bayes_os_terms: [[[f32; B_BAYES]; C]; F],
    /// Whether the table in use has the feature.
    bayes_has_os: bool,
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
            k: 0,
            names: [ClassName::EMPTY; K],
            rows: [0; K],
            priors: [Gaussian::ZERO; K],
            ml: [hist::<B_ML>(); K],
            map: [hist::<B_MAP>(); K],
            settings: Settings::ZERO,
            bayes_bins: 0,
            bayes_categories: 0,
            bayes_terms_len: 0,
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
            bayes_has_os: false,
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
        let result = self.decode_inner(bytes);
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
        self.k = 0;
        self.bayes_bins = 0;
        self.bayes_categories = 0;
        self.bayes_terms_len = 0;
        self.recal_len = [0; 4];
        self.bayes_has_os = false;
    }

    /// Whether the table holds no table.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.k == 0
    }

    /// The table as a [`TableView`] (the implementation every kind of table shares),
    /// or `None` when it is empty.
    #[inline]
    pub fn view(&self) -> Option<TableView<'_, Bounded<B_ML>, Bounded<B_MAP>>> {
        let k = self.k;
        if k == 0 {
            return None;
        }
        let bayes = if self.bayes_bins > 0 {
            let c = self.bayes_categories;
            let terms = c.checked_mul(k)?.checked_mul(self.bayes_bins)?;
            Some(BayesView {
                axes: self.bayes_axes.get(..k)?,
                terms: self
                    .bayes_terms
                    .as_flattened()
                    .as_flattened()
                    .get(..terms)?,
                rows: self.bayes_rows.get(..c)?,
                log_prior: self.bayes_log_prior.get(..c)?,
                lambda: self.bayes_lambda,
                log_lambda: self.bayes_log_lambda,
                open: self.bayes_open,
                objectness: if self.bayes_has_os {
                    let n = c.checked_mul(self.bayes_bins)?;
                    Some((
                        *self.bayes_os_axis.first()?,
                        self.bayes_os_terms.as_flattened().as_flattened().get(..n)?,
                    ))
                } else {
                    None
                },
            })
        } else {
            None
        };
        Some(TableView {
            names: self.names.get(..k)?,
            rows: self.rows.get(..k)?,
            priors: self.priors.get(..k)?,
            ml: self.ml.get(..k)?,
            map: self.map.get(..k)?,
            bayes,
            settings: &self.settings,
            maps: Maps([
                self.recal_slice(0),
                self.recal_slice(1),
                self.recal_slice(2),
                self.recal_slice(3),
            ]),
        })
    }

    /// The knots in use in map slot `slot`.
    fn recal_slice(&self, slot: usize) -> &[Knot] {
        let len = self.recal_len.get(slot).map_or(0, |&n| usize::from(n));
        self.recal
            .get(slot)
            .and_then(|k| k.get(..len))
            .unwrap_or_default()
    }

    /// [`BoundedTable::decode`] on a cleared table.
    fn decode_inner(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        // A quantized section appended to the table is not part of it.
        let bytes = crate::quantized::qtable::table_part(bytes);
        let (header, body) = wire::open(bytes)?;
        let k = usize::from(header.k);
        let (bins_ml, bins_map) = (usize::from(header.bins_ml), usize::from(header.bins_map));
        let (bins_bayes, categories) = (
            usize::from(header.bins_bayes),
            usize::from(header.categories),
        );
        if k > K || bins_ml > B_ML || bins_map > B_MAP {
            return Err(DecodeError::ShapeMismatch {
                expected: Self::MAX_SHAPE,
                found: header.shape(),
            });
        }
        if bins_bayes > B_BAYES || categories > C {
            return Err(DecodeError::BayesShapeMismatch {
                expected: Self::MAX_BAYES_SHAPE,
                found: header.bayes_shape(),
            });
        }
        // As `DynTable::from_bytes`: every frequency and term takes 4 bytes of the body, so
        // a header announcing more than the body holds is malformed (the same error for
        // the same bytes on the host and here).
        let terms = categories.saturating_mul(k).saturating_mul(bins_bayes);
        let floats = k
            .saturating_mul(bins_ml.saturating_add(bins_map))
            .saturating_add(terms);
        if floats.saturating_mul(4) > body.len() {
            return Err(DecodeError::Malformed);
        }
        // Each histogram of a class in use holds the announced number of frequencies
        // (a longer sequence is malformed, a shorter one has the wrong bin count).
        let malformed = DecodeError::Malformed;
        let ml = self.ml.get_mut(..k).ok_or(malformed)?;
        let map = self.map.get_mut(..k).ok_or(malformed)?;
        for h in ml.iter_mut() {
            h.freqs.set_len(bins_ml);
        }
        for h in map.iter_mut() {
            h.freqs.set_len(bins_map);
        }
        let mut raw_names = [""; K];
        let mut lens = [(0, 0); K];
        let [r0, r1, r2, r3] = &mut self.recal;
        let mut has_os = false;
        let knots = Slots {
            names: self.names.get_mut(..k).ok_or(malformed)?,
            raw_names: raw_names.get_mut(..k).ok_or(malformed)?,
            lens: lens.get_mut(..k).ok_or(malformed)?,
            rows: self.rows.get_mut(..k).ok_or(malformed)?,
            priors: self.priors.get_mut(..k).ok_or(malformed)?,
            ml,
            map,
            settings: &mut self.settings,
            bayes: if bins_bayes > 0 {
                Some(BayesStorage {
                    axes: self.bayes_axes.get_mut(..k).ok_or(malformed)?,
                    terms: self
                        .bayes_terms
                        .as_flattened_mut()
                        .as_flattened_mut()
                        .get_mut(..terms)
                        .ok_or(malformed)?,
                    rows: self.bayes_rows.get_mut(..categories).ok_or(malformed)?,
                    log_prior: self
                        .bayes_log_prior
                        .get_mut(..categories)
                        .ok_or(malformed)?,
                    lambda: &mut self.bayes_lambda,
                    log_lambda: &mut self.bayes_log_lambda,
                    open: &mut self.bayes_open,
                    objectness_axis: &mut self.bayes_os_axis,
                    objectness_terms: self.bayes_os_terms.as_flattened_mut().as_flattened_mut(),
                    objectness_required: false,
                    has_objectness: &mut has_os,
                })
            } else {
                None
            },
            recal: [r0, r1, r2, r3],
        }
        .decode(&header, body)?;
        if k < 2 {
            return Err(TableError::ClassCount.into());
        }
        for (len, n) in self.recal_len.iter_mut().zip(knots) {
            // At most MAX_KNOTS (checked by the decoder).
            *len = u8::try_from(n).unwrap_or(0);
        }
        self.bayes_has_os = has_os;
        (self.k, self.bayes_bins, self.bayes_categories) = (k, bins_bayes, categories);
        self.bayes_terms_len = terms;
        let view = self.view().ok_or(malformed)?;
        wire::check_canonical(bytes.len(), &view)
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
