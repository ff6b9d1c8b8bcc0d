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

use crate::diagnostics::error::{DecodeError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{self, Header, Settings};
use crate::heads::bayes::BayesView;
use crate::heads::recal::{Knot, Maps};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::storage::view::{BayesStorage, Slots, TableView};

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

/// Storage for one table, lent slice by slice (`'t`), each slice holding exactly the
/// items of a [`StorageShape`]; `'s` and `'a` are the decoder's scratch and the bytes,
/// used only while [`LentTable::decode`] runs. Fill every slice with the placeholders
/// of this module before lending it.
#[derive(Debug)]
pub struct LentTable<'t, 's, 'a> {
    /// K class names.
    pub names: &'t mut [ClassName],
    /// K training row counts.
    pub rows: &'t mut [u64],
    /// K priors.
    pub priors: &'t mut [Gaussian],
    /// K ML histograms, each over its own `bins_ml` frequencies.
    pub ml: &'t mut [Histogram<&'t mut [f32]>],
    /// K MAP histograms, each over its own `bins_map` frequencies.
    pub map: &'t mut [Histogram<&'t mut [f32]>],
    /// The settings.
    pub settings: &'t mut Settings,
    /// Scratch: K names as parsed.
    pub scratch_names: &'s mut [&'a str],
    /// Scratch: K pairs of frequency counts as parsed.
    pub scratch_lens: &'s mut [(usize, usize)],
    /// The Bayes head's storage, for a table with one.
    pub bayes: Option<LentBayes<'t>>,
    /// Each head's map (ML, MAP, Bayes, open): `knots[h]` knots.
    pub knots: [&'t mut [Knot]; 4],
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

impl<'t, 'a> LentTable<'t, '_, 'a> {
    /// The shape this storage has room for: [`DecodeError::ShapeMismatch`] or
    /// [`DecodeError::BayesShapeMismatch`] unless the header's shape is exactly it.
    fn check_shape(&self, header: &Header) -> Result<(), DecodeError> {
        let k = usize::from(header.k);
        let (bml, bmap) = (usize::from(header.bins_ml), usize::from(header.bins_map));
        let lens_ok = |h: &[Histogram<&'t mut [f32]>], b: usize| {
            h.len() == k && h.iter().all(|h| h.freqs.len() == b)
        };
        let held = |h: &[Histogram<&'t mut [f32]>]| {
            u16::try_from(h.first().map_or(0, |h| h.freqs.len())).unwrap_or(u16::MAX)
        };
        if [
            self.names.len(),
            self.rows.len(),
            self.priors.len(),
            self.scratch_names.len(),
            self.scratch_lens.len(),
        ]
        .iter()
        .any(|&n| n != k)
            || !lens_ok(self.ml, bml)
            || !lens_ok(self.map, bmap)
        {
            return Err(DecodeError::ShapeMismatch {
                expected: (
                    u16::try_from(self.names.len()).unwrap_or(u16::MAX),
                    held(self.ml),
                    held(self.map),
                ),
                found: header.shape(),
            });
        }
        let (bins, cats) = (
            usize::from(header.bins_bayes),
            usize::from(header.categories),
        );
        let bayes_ok = match &self.bayes {
            None => bins == 0,
            Some(b) => {
                b.axes.len() == k
                    && b.rows.len() == cats
                    && b.log_prior.len() == cats
                    && Some(b.terms.len()) == cats.checked_mul(k).and_then(|n| n.checked_mul(bins))
            }
        };
        if !bayes_ok {
            let held = self.bayes.as_ref().map_or((0, 0), |b| {
                let c = b.rows.len();
                let bins = b.terms.len().checked_div(c * k).unwrap_or(0);
                (
                    u16::try_from(bins).unwrap_or(u16::MAX),
                    u16::try_from(c).unwrap_or(u16::MAX),
                )
            });
            return Err(DecodeError::BayesShapeMismatch {
                expected: held,
                found: header.bayes_shape(),
            });
        }
        Ok(())
    }

    /// Decodes and validates `bytes` into the lent storage, which must have exactly the
    /// table's shape ([`StorageShape::of`]), and returns the table as a [`TableView`]
    /// borrowing it. Runs the decoder of every table ([`Table`](crate::Table),
    /// [`BoundedTable`](crate::BoundedTable), `DynTable`): the same checks in the same
    /// order.
    ///
    /// # Errors
    ///
    /// As [`Table::from_bytes`](crate::Table::from_bytes); a shape mismatch means
    /// storage of another shape than the table's; [`DecodeError::MapCapacity`] a map
    /// longer than its slice in `knots` (and at most [`MAX_KNOTS`](crate::MAX_KNOTS)),
    /// [`DecodeError::ObjectnessMismatch`] an objectness feature without room for it.
    pub fn decode(
        self,
        bytes: &'a [u8],
    ) -> Result<TableView<'t, &'t mut [f32], &'t mut [f32]>, DecodeError> {
        let bytes = crate::sections::table_part(bytes);
        let (header, body) = wire::open(bytes)?;
        self.check_shape(&header)?;
        let shape = StorageShape {
            classes: usize::from(header.k),
            bins_ml: usize::from(header.bins_ml),
            bins_map: usize::from(header.bins_map),
            bins_bayes: usize::from(header.bins_bayes),
            categories: usize::from(header.categories),
            ..StorageShape::default()
        };
        if shape.floats().saturating_mul(4) > body.len() {
            return Err(DecodeError::Malformed);
        }
        let LentTable {
            names,
            rows,
            priors,
            ml,
            map,
            settings,
            scratch_names,
            scratch_lens,
            mut bayes,
            knots: [k0, k1, k2, k3],
        } = self;
        let (mut lambda, mut log_lambda, mut open, mut has_os) = (0.0f32, 0.0f32, None, false);
        let counts = Slots {
            names: &mut *names,
            raw_names: scratch_names,
            lens: scratch_lens,
            rows: &mut *rows,
            priors: &mut *priors,
            ml: &mut *ml,
            map: &mut *map,
            settings: &mut *settings,
            bayes: bayes.as_mut().map(|b| BayesStorage {
                axes: &mut *b.axes,
                terms: &mut *b.terms,
                rows: &mut *b.rows,
                log_prior: &mut *b.log_prior,
                lambda: &mut lambda,
                log_lambda: &mut log_lambda,
                open: &mut open,
                objectness_axis: &mut *b.objectness_axis,
                objectness_terms: &mut *b.objectness_terms,
                objectness_required: false,
                has_objectness: &mut has_os,
            }),
            recal: [&mut *k0, &mut *k1, &mut *k2, &mut *k3],
        }
        .decode(&header, body)?;
        if shape.classes < 2 {
            return Err(TableError::ClassCount.into());
        }
        let knots: [&'t [Knot]; 4] = [k0, k1, k2, k3];
        let mut maps = Maps::NONE;
        for ((slot, all), n) in maps.0.iter_mut().zip(knots).zip(counts) {
            *slot = all.get(..n).unwrap_or_default();
        }
        let bayes = match bayes {
            Some(b) => {
                let objectness = if has_os {
                    let axis = *b.objectness_axis.first().ok_or(DecodeError::Malformed)?;
                    let terms: &'t [f32] = b.objectness_terms;
                    Some((axis, terms))
                } else {
                    None
                };
                Some(BayesView {
                    axes: b.axes,
                    terms: b.terms,
                    rows: b.rows,
                    log_prior: b.log_prior,
                    lambda,
                    log_lambda,
                    open,
                    objectness,
                })
            }
            None => None,
        };
        let view = TableView {
            names,
            rows,
            priors,
            ml,
            map,
            bayes,
            settings,
            maps,
        };
        wire::check_canonical(bytes.len(), &view)?;
        Ok(view)
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
            LentTable {
                names: &mut self.names,
                rows: &mut self.rows,
                priors: &mut self.priors,
                ml,
                map,
                settings: &mut self.settings,
                scratch_names: &mut self.raw,
                scratch_lens: &mut self.lens,
                bayes: (s.bins_bayes > 0).then_some(LentBayes {
                    axes: &mut self.axes,
                    terms: &mut self.terms,
                    rows: &mut self.brows,
                    log_prior: &mut self.log_prior,
                    objectness_axis: &mut self.os_axis,
                    objectness_terms: &mut self.os_terms,
                }),
                knots: [k0, k1, k2, k3],
            }
            .decode(bytes)
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
        let crc = wire::CRC.checksum(&bytes[..n]);
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
