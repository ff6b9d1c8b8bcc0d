//! Decoding a table into storage its caller lends, slice by slice, each of exactly the
//! table's size: for a program that sizes its memory to the one table it runs (the C
//! API's arena) rather than to a maximum shape ([`BoundedTable`](crate::BoundedTable)).
//!
//! [`StorageShape::of`] reads how many of each item a table needs (from its header and,
//! for a version-4 table, the lengths of its maps and of its objectness feature);
//! [`LentTable`] lends that storage to the one decoder (`Slots`), which fills and
//! validates it, and the result is a [`TableView`], the one implementation of scoring.
//! The same bytes give the same result as `DynTable::from_bytes`, error included.
//!
//! [`LentQTable`] does the same for a quantized section: its per-class records in lent
//! storage, its masses and terms read in place from the section's bytes.

use core::marker::PhantomData;

use crate::diagnostics::error::DecodeError;
use crate::format::name::ClassName;
use crate::format::wire::Settings;
use crate::heads::recal::Knot;
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::storage::inner::{maps_of, private::Sealed, view_of, InUse, Parts, Storage, TableInner};
use crate::storage::view::TableView;

mod arena;
mod shape;
pub use arena::{
    ArenaLayout, ARENA_LAYOUT, AXIS_BYTES, KNOT_BYTES, NAME_BYTES, PRIOR_BYTES, SETTINGS_BYTES,
};
pub use shape::StorageShape;

pub use crate::quantized::qtable::{LentQTable, QClass, QLogit, EMPTY_QCLASS, EMPTY_QLOGIT};

/// A placeholder class name (empty, invalid) for storage the decoder fills.
pub const EMPTY_NAME: ClassName = ClassName::EMPTY;
/// A placeholder prior (all zeros, invalid) for storage the decoder fills.
pub const EMPTY_PRIOR: Gaussian = Gaussian::ZERO;
/// A placeholder axis (all zeros, invalid) for storage the decoder fills.
pub const EMPTY_AXIS: Axis = Axis::ZERO;
/// Placeholder settings (all zeros, invalid) for storage the decoder fills.
pub const EMPTY_SETTINGS: Settings = Settings::ZERO;
/// A placeholder knot for storage the decoder fills.
pub const EMPTY_KNOT: Knot = Knot { x: 0.0, y: 0.0 };

/// A placeholder histogram (all zeros, invalid) over the frequency storage `freqs`,
/// which the decoder fills.
pub const fn empty_histogram<F>(freqs: F) -> Histogram<F> {
    Histogram {
        lo: 0.0,
        hi: 0.0,
        width: 0.0,
        inv_width: 0.0,
        freqs,
    }
}

/// A table in storage lent slice by slice (`'t`), each slice holding exactly the items
/// of a [`StorageShape`]: the one [`TableInner`] over [`LentStorage`]. Lend the slices
/// with [`LentTable::lend`] (each filled with the placeholders of this module) and
/// decode into them with [`LentTable::decode`].
pub type LentTable<'t> = TableInner<LentStorage<'t>>;

/// The storage of a [`LentTable`]: slices lent by the caller, of exactly the table's
/// shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LentStorage<'t>(PhantomData<&'t mut ()>);

/// Which optional parts a [`LentTable`] has room for, and holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LentParts {
    /// Whether the storage was lent with a Bayes head's.
    pub(crate) bayes: bool,
    /// Whether the decoded table has the objectness feature.
    pub(crate) objectness: bool,
}

impl Sealed for LentStorage<'_> {}

impl<'t> Storage for LentStorage<'t> {
    type Names = &'t mut [ClassName];
    type Rows = &'t mut [u64];
    type Priors = &'t mut [Gaussian];
    type MlFreqs = &'t mut [f32];
    type MapFreqs = &'t mut [f32];
    type Ml = &'t mut [Histogram<&'t mut [f32]>];
    type Map = &'t mut [Histogram<&'t mut [f32]>];
    type Settings = &'t mut Settings;
    type Axes = &'t mut [Axis];
    type Terms = &'t mut [f32];
    type Categories = &'t mut [u64];
    type LogPrior = &'t mut [f32];
    type Knots = &'t mut [Knot];
    type ObjectnessAxis = &'t mut [Axis];
    type ObjectnessTerms = &'t mut [f32];
    type Extent = LentParts;
    type View<'a>
        = TableView<'a, &'t mut [f32], &'t mut [f32]>
    where
        Self: 'a;

    const NAME: &'static str = "LentTable";
    const OBJECTNESS_REQUIRED: bool = false;

    #[inline]
    fn in_use(t: &LentTable<'t>) -> InUse {
        InUse {
            classes: t.names.len(),
            bayes: t.extent.bayes,
            categories: t.bayes_rows.len(),
            terms: t.bayes_terms.len(),
            objectness: t.extent.objectness,
            objectness_terms: t.bayes_os_terms.len(),
            maps: true,
        }
    }

    /// [`DecodeError::ShapeMismatch`] or [`DecodeError::BayesShapeMismatch`] unless the
    /// header's shape is exactly the storage's; then, as every decoder, a body too short
    /// for the announced floats is malformed.
    fn prepare(
        t: &mut LentTable<'t>,
        s: &StorageShape,
        (shape, bayes_shape): ((u16, u16, u16), (u16, u16)),
        body: usize,
    ) -> Result<(), DecodeError> {
        let k = s.classes;
        let lens_ok = |h: &[Histogram<&'t mut [f32]>], b: usize| {
            h.len() == k && h.iter().all(|h| h.freqs.len() == b)
        };
        let held = |h: &[Histogram<&'t mut [f32]>]| {
            u16::try_from(h.first().map_or(0, |h| h.freqs.len())).unwrap_or(u16::MAX)
        };
        if [t.names.len(), t.rows.len(), t.priors.len()]
            .iter()
            .any(|&n| n != k)
            || !lens_ok(t.ml, s.bins_ml)
            || !lens_ok(t.map, s.bins_map)
        {
            return Err(DecodeError::ShapeMismatch {
                expected: (
                    u16::try_from(t.names.len()).unwrap_or(u16::MAX),
                    held(t.ml),
                    held(t.map),
                ),
                found: shape,
            });
        }
        let (bins, cats) = (s.bins_bayes, s.categories);
        let bayes_ok = if t.extent.bayes {
            t.bayes_axes.len() == k
                && t.bayes_rows.len() == cats
                && t.bayes_log_prior.len() == cats
                && Some(t.bayes_terms.len())
                    == cats.checked_mul(k).and_then(|n| n.checked_mul(bins))
        } else {
            bins == 0
        };
        if !bayes_ok {
            let held = if t.extent.bayes {
                let c = t.bayes_rows.len();
                let bins = t.bayes_terms.len().checked_div(c * k).unwrap_or(0);
                (
                    u16::try_from(bins).unwrap_or(u16::MAX),
                    u16::try_from(c).unwrap_or(u16::MAX),
                )
            } else {
                (0, 0)
            };
            return Err(DecodeError::BayesShapeMismatch {
                expected: held,
                found: bayes_shape,
            });
        }
        // Storage lent for a Bayes head, for a table without one, is malformed.
        if s.floats().saturating_mul(4) > body || t.extent.bayes != (bins > 0) {
            return Err(DecodeError::Malformed);
        }
        Ok(())
    }

    fn finish(t: &mut LentTable<'t>, _: &StorageShape, objectness: bool, _: [usize; 4]) {
        t.extent.objectness = objectness;
    }

    #[inline]
    fn wrap<'a>(
        _: &'a LentTable<'t>,
        view: TableView<'a, &'t mut [f32], &'t mut [f32]>,
    ) -> Self::View<'a> {
        view
    }
}

/// A Bayes head's storage, lent slice by slice.
#[derive(Debug)]
pub struct LentBayes<'t> {
    /// K axes.
    pub axes: &'t mut [Axis],
    /// `categories K bins` log-terms.
    pub terms: &'t mut [f32],
    /// `categories` row counts.
    pub rows: &'t mut [u64],
    /// `categories` log-priors.
    pub log_prior: &'t mut [f32],
    /// The objectness feature's axis: 1 entry with the feature, none without.
    pub objectness_axis: &'t mut [Axis],
    /// The objectness feature's `bins categories` terms (none without the feature).
    pub objectness_terms: &'t mut [f32],
}

impl<'t> LentTable<'t> {
    /// Storage lent for one table: K class names, row counts and priors, K ML and K MAP
    /// histograms each over its own `bins_ml` (`bins_map`) frequencies, the settings,
    /// the Bayes head's storage for a table with one, and each head's map (ML, MAP,
    /// Bayes, open): `knots[h]` knots. Fill every slice with the placeholders of this
    /// module before lending it.
    #[allow(clippy::too_many_arguments)]
    pub fn lend(
        names: &'t mut [ClassName],
        rows: &'t mut [u64],
        priors: &'t mut [Gaussian],
        ml: &'t mut [Histogram<&'t mut [f32]>],
        map: &'t mut [Histogram<&'t mut [f32]>],
        settings: &'t mut Settings,
        bayes: Option<LentBayes<'t>>,
        knots: [&'t mut [Knot]; 4],
    ) -> Self {
        let has_bayes = bayes.is_some();
        let b = bayes.unwrap_or(LentBayes {
            axes: &mut [],
            terms: &mut [],
            rows: &mut [],
            log_prior: &mut [],
            objectness_axis: &mut [],
            objectness_terms: &mut [],
        });
        Self {
            names,
            rows,
            priors,
            ml,
            map,
            settings,
            bayes_axes: b.axes,
            bayes_terms: b.terms,
            bayes_rows: b.rows,
            bayes_log_prior: b.log_prior,
            bayes_lambda: 0.0,
            bayes_log_lambda: 0.0,
            bayes_open: None,
            recal: knots,
            recal_len: [0; 4],
            bayes_os_axis: b.objectness_axis,
            bayes_os_terms: b.objectness_terms,
            extent: LentParts {
                bayes: has_bayes,
                objectness: false,
            },
        }
    }

    /// Decodes and validates `bytes` into the lent storage, which must have exactly the
    /// table's shape ([`StorageShape::of`]), and returns the table as a [`TableView`]
    /// borrowing it for `'t`. Runs the decoder of every table ([`Table`](crate::Table),
    /// [`BoundedTable`](crate::BoundedTable), `DynTable`): the same checks in the same
    /// order. `scratch_names` and `scratch_lens` are the decoder's scratch, K entries
    /// each, used only while it runs.
    ///
    /// # Errors
    ///
    /// As [`Table::from_bytes`](crate::Table::from_bytes); a shape mismatch means
    /// storage of another shape than the table's; [`DecodeError::MapCapacity`] a map
    /// longer than its slice in `knots` (and at most [`MAX_KNOTS`](crate::MAX_KNOTS)),
    /// [`DecodeError::ObjectnessMismatch`] an objectness feature without room for it,
    /// [`DecodeError::Malformed`] scratch of fewer than K entries.
    pub fn decode<'a>(
        mut self,
        bytes: &'a [u8],
        scratch_names: &mut [&'a str],
        scratch_lens: &mut [(usize, usize)],
    ) -> Result<TableView<'t, &'t mut [f32], &'t mut [f32]>, DecodeError> {
        self.decode_with(bytes, |_| (scratch_names, scratch_lens))?;
        let in_use = LentStorage::in_use(&self);
        let recal: [&'t [Knot]; 4] = self.recal.map(|k| &*k);
        let parts = Parts {
            names: self.names,
            rows: self.rows,
            priors: self.priors,
            ml: self.ml,
            map: self.map,
            settings: self.settings,
            axes: self.bayes_axes,
            terms: self.bayes_terms,
            categories: self.bayes_rows,
            log_prior: self.bayes_log_prior,
            lambda: self.bayes_lambda,
            log_lambda: self.bayes_log_lambda,
            open: self.bayes_open,
            os_axis: self.bayes_os_axis,
            os_terms: self.bayes_os_terms,
            maps: maps_of(in_use.maps, &self.recal_len, |h| recal.get(h).copied()),
        };
        Ok(view_of(parts, in_use))
    }
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use super::*;
    use crate::{DynTable, FastMath, Libm};
    use std::vec;
    use std::vec::Vec;

    /// Owned storage of one shape, lent as a [`LentTable`].
    struct Owned<'a> {
        names: Vec<ClassName>,
        rows: Vec<u64>,
        priors: Vec<Gaussian>,
        freqs_ml: Vec<f32>,
        freqs_map: Vec<f32>,
        settings: Settings,
        raw: Vec<&'a str>,
        lens: Vec<(usize, usize)>,
        axes: Vec<Axis>,
        terms: Vec<f32>,
        brows: Vec<u64>,
        log_prior: Vec<f32>,
        os_axis: Vec<Axis>,
        os_terms: Vec<f32>,
        knots: [Vec<Knot>; 4],
        s: StorageShape,
    }

    impl<'a> Owned<'a> {
        fn new(s: StorageShape) -> Self {
            let k = s.classes;
            let os = usize::from(s.objectness);
            Self {
                names: vec![EMPTY_NAME; k],
                rows: vec![0; k],
                priors: vec![EMPTY_PRIOR; k],
                freqs_ml: vec![0.0; k * s.bins_ml],
                freqs_map: vec![0.0; k * s.bins_map],
                settings: EMPTY_SETTINGS,
                raw: vec![""; k],
                lens: vec![(0, 0); k],
                axes: vec![EMPTY_AXIS; if s.bins_bayes > 0 { k } else { 0 }],
                terms: vec![0.0; s.categories * k * s.bins_bayes],
                brows: vec![0; s.categories],
                log_prior: vec![0.0; s.categories],
                os_axis: vec![EMPTY_AXIS; os],
                os_terms: vec![0.0; os * s.categories * s.bins_bayes],
                knots: s.knots.map(|n| vec![EMPTY_KNOT; n]),
                s,
            }
        }

        fn decode<'t>(
            &'t mut self,
            bytes: &'a [u8],
            ml: &'t mut Vec<Histogram<&'t mut [f32]>>,
            map: &'t mut Vec<Histogram<&'t mut [f32]>>,
        ) -> Result<TableView<'t, &'t mut [f32], &'t mut [f32]>, DecodeError> {
            let s = self.s;
            split(&mut self.freqs_ml, s.classes, s.bins_ml, ml);
            split(&mut self.freqs_map, s.classes, s.bins_map, map);
            let [k0, k1, k2, k3] = &mut self.knots;
            LentTable::lend(
                &mut self.names,
                &mut self.rows,
                &mut self.priors,
                ml,
                map,
                &mut self.settings,
                (s.bins_bayes > 0).then_some(LentBayes {
                    axes: &mut self.axes,
                    terms: &mut self.terms,
                    rows: &mut self.brows,
                    log_prior: &mut self.log_prior,
                    objectness_axis: &mut self.os_axis,
                    objectness_terms: &mut self.os_terms,
                }),
                [k0, k1, k2, k3],
            )
            .decode(bytes, &mut self.raw, &mut self.lens)
        }
    }

    /// `k` histograms over consecutive runs of `b` floats (`b` may be 0).
    fn split<'t>(
        mut f: &'t mut [f32],
        k: usize,
        b: usize,
        out: &mut Vec<Histogram<&'t mut [f32]>>,
    ) {
        for _ in 0..k {
            let (head, tail) = core::mem::take(&mut f).split_at_mut(b);
            out.push(empty_histogram(head));
            f = tail;
        }
    }

    fn lent_decode(bytes: &[u8]) -> Result<Vec<u8>, DecodeError> {
        let s = StorageShape::of(bytes, |_| Ok(()))?;
        let mut owned = Owned::new(s);
        let (mut ml, mut map) = (Vec::new(), Vec::new());
        let v = owned.decode(bytes, &mut ml, &mut map)?;
        let mut buf = vec![0u8; v.encoded_len()];
        Ok(v.encode(&mut buf).unwrap().to_vec())
    }

    const TABLES: [&[u8]; 5] = [
        include_bytes!("../../../../tables/default.mlmap"),
        include_bytes!("../../../../tests/golden/layer/small.mlmap"),
        include_bytes!("../../../../tests/golden/layer/small_maps.mlmap"),
        include_bytes!("../../../../tests/golden/layer/small_osf.mlmap"),
        include_bytes!("../../../../tests/golden/layer/small_open.mlmap"),
    ];

    fn with_crc(mut bytes: Vec<u8>) -> Vec<u8> {
        let n = bytes.len() - 4;
        let crc = crate::format::wire::CRC.checksum(&bytes[..n]);
        bytes[n..].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    /// Every single-byte change (with and without a valid CRC) and every truncation of
    /// tables of each version and part: the same outcome as `DynTable::from_bytes`, and
    /// the same bytes back on success.
    #[test]
    fn accepts_exactly_what_dyn_table_accepts() {
        let mut checked = 0;
        for original in TABLES {
            let mut inputs = Vec::new();
            for i in 0..original.len() {
                for v in [0x00u8, original[i] ^ 0x01, original[i] ^ 0x80, 0xff] {
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
                let want = DynTable::from_bytes(&bytes).map(|d| d.to_vec().unwrap());
                assert_eq!(lent_decode(&bytes), want, "{bytes:02x?}");
                checked += 1;
            }
        }
        assert!(checked > 10_000);
    }

    #[test]
    fn shapes_are_exact_and_scores_equal_the_dyn_tables() {
        for bytes in TABLES {
            let s = StorageShape::of(bytes, |_| Ok(())).unwrap();
            let d = DynTable::from_bytes(bytes).unwrap();
            let dv = d.view();
            assert_eq!(
                (s.classes, s.bins_ml, s.bins_map),
                (dv.k(), dv.bins_ml(), dv.bins_map())
            );
            for (h, n) in crate::heads::recal::HEADS.iter().zip(s.knots) {
                assert_eq!(dv.recal_map(*h).map_or(0, |m| m.knots().len()), n);
            }
            assert_eq!(
                s.objectness,
                dv.bayes().is_some_and(|b| b.objectness.is_some())
            );
            let mut owned = Owned::new(s);
            let (mut ml, mut map) = (Vec::new(), Vec::new());
            let v = owned.decode(bytes, &mut ml, &mut map).unwrap();
            let k = v.k();
            let (mut a, mut b, mut scratch) = (vec![0.0; k], vec![0.0; k], vec![0.0; k + 1]);
            for i in 0..500 {
                let x: Vec<f32> = (0..k)
                    .map(|c| ((i * 37 + c * 101) % 200) as f32 / 25.0 - 4.0)
                    .collect();
                let os = (i % 11) as f32 / 10.0;
                for head in crate::heads::recal::HEADS {
                    let r1 = v.score_into(head, &x, os, &mut a, &mut scratch);
                    let r2 = dv.score_into(head, &x, os, &mut b, &mut scratch);
                    assert_eq!(r1, r2);
                    assert_eq!(
                        a.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                        b.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                    );
                }
            }
            let _ = (Libm, FastMath);
        }
    }

    #[test]
    fn storage_of_another_shape_is_refused() {
        let bytes = TABLES[0];
        let mut s = StorageShape::of(bytes, |_| Ok(())).unwrap();
        s.bins_ml -= 1;
        let mut owned = Owned::new(s);
        let (mut ml, mut map) = (Vec::new(), Vec::new());
        assert!(matches!(
            owned.decode(bytes, &mut ml, &mut map),
            Err(DecodeError::ShapeMismatch { .. })
        ));
        let limit = StorageShape::of(bytes, |s| {
            if s.classes > 2 {
                Err(DecodeError::Malformed)
            } else {
                Ok(())
            }
        });
        assert_eq!(limit, Err(DecodeError::Malformed));
    }
}
