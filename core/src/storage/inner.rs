//! [`TableInner<S>`]: the one table type, generic over where its items live (a
//! [`Storage`]), as `heapless` has one `VecInner<S>` behind `Vec` and `VecView`. It has
//! the one [`view`](TableInner::view), the one decoder (filling the storage through
//! `Slots`) and the one set of accessors; [`Table`](crate::Table),
//! [`BoundedTable`](crate::BoundedTable), `DynTable` and
//! [`LentTable`](crate::lent::LentTable) are aliases of it over their storage, which
//! add their constructors only.

use core::borrow::{Borrow, BorrowMut};

use crate::diagnostics::error::{DecodeError, Head, InferError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{self, ClassSpec, Settings};
use crate::heads::bayes::BayesView;
use crate::heads::open::OpenParams;
use crate::heads::recal::{Knot, Maps, RecalMap};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::math::Backend;
use crate::storage::lent::StorageShape;
use crate::storage::view::{BayesStorage, Slots, TableView};

/// A container of a table's items, read and written as one slice: an array, an array
/// of arrays (flattened), a vector or a lent slice.
pub trait Items<T> {
    /// Every item, in order.
    fn items(&self) -> &[T];
    /// Every item, in order, mutably.
    fn items_mut(&mut self) -> &mut [T];
}

impl<T, const N: usize> Items<T> for [T; N] {
    #[inline(always)]
    fn items(&self) -> &[T] {
        self
    }
    #[inline(always)]
    fn items_mut(&mut self) -> &mut [T] {
        self
    }
}

impl<T, const A: usize, const B: usize> Items<T> for [[T; A]; B] {
    #[inline(always)]
    fn items(&self) -> &[T] {
        self.as_flattened()
    }
    #[inline(always)]
    fn items_mut(&mut self) -> &mut [T] {
        self.as_flattened_mut()
    }
}

impl<T, const A: usize, const B: usize, const C: usize> Items<T> for [[[T; A]; B]; C] {
    #[inline(always)]
    fn items(&self) -> &[T] {
        self.as_flattened().as_flattened()
    }
    #[inline(always)]
    fn items_mut(&mut self) -> &mut [T] {
        self.as_flattened_mut().as_flattened_mut()
    }
}

impl<T> Items<T> for &mut [T] {
    #[inline(always)]
    fn items(&self) -> &[T] {
        self
    }
    #[inline(always)]
    fn items_mut(&mut self) -> &mut [T] {
        self
    }
}

#[cfg(feature = "alloc")]
impl<T> Items<T> for alloc::vec::Vec<T> {
    #[inline(always)]
    fn items(&self) -> &[T] {
        self
    }
    #[inline(always)]
    fn items_mut(&mut self) -> &mut [T] {
        self
    }
}

/// Where a [`TableInner`] keeps its items: one container type per kind of item, and
/// what [`TableInner::view`] returns. Implemented by the crate's four storages only:
/// [`ArrayStorage`](crate::ArrayStorage) (fixed arrays), [`BoundedStorage`](crate::BoundedStorage)
/// (arrays of a maximum shape, a prefix in use), `VecStorage` (vectors, feature
/// `alloc`) and [`LentStorage`](crate::lent::LentStorage) (slices lent by the caller).
pub trait Storage: private::Sealed + Sized {
    /// The class names (K).
    type Names: Items<ClassName>;
    /// The training rows per class (K).
    type Rows: Items<u64>;
    /// The Gaussian priors (K).
    type Priors: Items<Gaussian>;
    /// One ML histogram's frequencies.
    type MlFreqs: AsRef<[f32]> + AsMut<[f32]>;
    /// One MAP histogram's frequencies.
    type MapFreqs: AsRef<[f32]> + AsMut<[f32]>;
    /// The ML histograms (K).
    type Ml: Items<Histogram<Self::MlFreqs>>;
    /// The MAP histograms (K).
    type Map: Items<Histogram<Self::MapFreqs>>;
    /// The settings (owned, or lent).
    type Settings: Borrow<Settings> + BorrowMut<Settings>;
    /// The Bayes head's axes (K).
    type Axes: Items<Axis>;
    /// The Bayes head's log-terms (categories K bins, logit-major).
    type Terms: Items<f32>;
    /// The Bayes head's training rows per category.
    type Categories: Items<u64>;
    /// The Bayes head's log-priors per category.
    type LogPrior: Items<f32>;
    /// Room for one head's recalibration map.
    type Knots: Items<Knot>;
    /// The objectness feature's axis (0 or 1).
    type ObjectnessAxis: Items<Axis>;
    /// The objectness feature's terms (bins categories).
    type ObjectnessTerms: Items<f32>;
    /// What the storage records besides the items: the shape in use for storage of a
    /// maximum shape, nothing otherwise.
    type Extent: Copy + core::fmt::Debug + PartialEq;
    /// What [`TableInner::view`] returns: a [`TableView`], or `Option<TableView>` for
    /// storage that may hold no table ([`BoundedStorage`](crate::BoundedStorage)).
    type View<'a>
    where
        Self: 'a;

    /// The type name `defmt` prints.
    #[doc(hidden)]
    const NAME: &'static str;
    /// Whether a table without the objectness feature is refused.
    #[doc(hidden)]
    const OBJECTNESS_REQUIRED: bool;
    /// How much of `t` is in use.
    #[doc(hidden)]
    fn in_use(t: &TableInner<Self>) -> InUse;
    /// Makes room in `t` for a table of `shape` (its header's; `found` as the errors
    /// report it) and a body of `body` bytes, or refuses the shape.
    #[doc(hidden)]
    fn prepare(
        t: &mut TableInner<Self>,
        shape: &StorageShape,
        found: ((u16, u16, u16), (u16, u16)),
        body: usize,
    ) -> Result<(), DecodeError>;
    /// Records what a successful parse found: the shape, the objectness feature, the
    /// maps' knots.
    #[doc(hidden)]
    fn finish(t: &mut TableInner<Self>, shape: &StorageShape, objectness: bool, knots: [usize; 4]);
    /// The view as [`TableInner::view`] returns it.
    #[doc(hidden)]
    fn wrap<'a>(
        t: &'a TableInner<Self>,
        view: TableView<'a, Self::MlFreqs, Self::MapFreqs>,
    ) -> Self::View<'a>;
}

/// How much of a storage is in use, and which parts the table has.
#[derive(Debug, Clone, Copy)]
pub struct InUse {
    /// Classes K.
    pub classes: usize,
    /// Whether the table has a Bayes head.
    pub bayes: bool,
    /// The Bayes head's categories.
    pub categories: usize,
    /// The Bayes head's log-terms.
    pub terms: usize,
    /// Whether the Bayes head has the objectness feature.
    pub objectness: bool,
    /// The objectness feature's terms.
    pub objectness_terms: usize,
    /// Whether the storage has room for maps (`false`: none, known at compile time).
    pub maps: bool,
}

pub(crate) mod private {
    /// Seals [`Storage`](super::Storage): only this crate's storages implement it.
    pub trait Sealed {}
}

/// A validated table over the storage `S`; use it through its aliases
/// [`Table`](crate::Table), [`BoundedTable`](crate::BoundedTable), `DynTable` and
/// [`LentTable`](crate::lent::LentTable). Every accessor reads the table in use (none
/// for an empty [`BoundedTable`](crate::BoundedTable)).
#[derive(Debug, Clone, PartialEq)]
pub struct TableInner<S: Storage> {
    pub(crate) names: S::Names,
    pub(crate) rows: S::Rows,
    pub(crate) priors: S::Priors,
    pub(crate) ml: S::Ml,
    pub(crate) map: S::Map,
    pub(crate) settings: S::Settings,
    /// The Bayes head's bins per logit (see [`Storage::Axes`]).
    pub(crate) bayes_axes: S::Axes,
    /// `ln(h + lambda)` per logit, bin and category (logit-major, see [`BayesView`]).
    pub(crate) bayes_terms: S::Terms,
    pub(crate) bayes_rows: S::Categories,
    pub(crate) bayes_log_prior: S::LogPrior,
    pub(crate) bayes_lambda: f32,
    pub(crate) bayes_log_lambda: f32,
    /// The open head's parameters (DESIGN §1.8), `None` without that head.
    pub(crate) bayes_open: Option<OpenParams>,
    /// Room for each head's recalibration map (DESIGN §1.9), ML, MAP, Bayes, open.
    pub(crate) recal: [S::Knots; 4],
    /// Knots in use in each of `recal` (0: no map).
    pub(crate) recal_len: [u8; 4],
    /// The objectness feature's axis (DESIGN §1.6), when the table has it.
    pub(crate) bayes_os_axis: S::ObjectnessAxis,
    /// The objectness feature's terms, bin-major then category.
    pub(crate) bayes_os_terms: S::ObjectnessTerms,
    /// The storage's own record (the shape in use of bounded storage).
    pub(crate) extent: S::Extent,
}

/// The first `n` of `items` (all of them when `n` is their number, which the compiler
/// sees for arrays).
#[inline(always)]
fn first<T>(items: &[T], n: usize) -> &[T] {
    items.get(..n).unwrap_or_default()
}

/// The first `n` of `items`, mutably, or [`DecodeError::Malformed`].
#[inline(always)]
fn first_mut<T>(items: &mut [T], n: usize) -> Result<&mut [T], DecodeError> {
    items.get_mut(..n).ok_or(DecodeError::Malformed)
}

/// A table's items as shared slices, as long as `'a`: what [`view_of`] builds a view of.
pub(crate) struct Parts<'a, F, G> {
    pub(crate) names: &'a [ClassName],
    pub(crate) rows: &'a [u64],
    pub(crate) priors: &'a [Gaussian],
    pub(crate) ml: &'a [Histogram<F>],
    pub(crate) map: &'a [Histogram<G>],
    pub(crate) settings: &'a Settings,
    pub(crate) axes: &'a [Axis],
    pub(crate) terms: &'a [f32],
    pub(crate) categories: &'a [u64],
    pub(crate) log_prior: &'a [f32],
    pub(crate) lambda: f32,
    pub(crate) log_lambda: f32,
    pub(crate) open: Option<OpenParams>,
    /// The heads' maps ([`maps_of`]).
    pub(crate) maps: Maps<'a>,
    pub(crate) os_axis: &'a [Axis],
    pub(crate) os_terms: &'a [f32],
}

/// The view of the parts `p` of which `u` is in use (`p.maps` already cut to it): the one construction of a
/// [`TableView`], for every storage.
#[inline(always)]
pub(crate) fn view_of<'a, F, G>(p: Parts<'a, F, G>, u: InUse) -> TableView<'a, F, G> {
    let k = u.classes;
    TableView {
        names: first(p.names, k),
        rows: first(p.rows, k),
        priors: first(p.priors, k),
        ml: first(p.ml, k),
        map: first(p.map, k),
        bayes: u.bayes.then(|| BayesView {
            axes: first(p.axes, k),
            terms: first(p.terms, u.terms),
            rows: first(p.categories, u.categories),
            log_prior: first(p.log_prior, u.categories),
            lambda: p.lambda,
            log_lambda: p.log_lambda,
            open: p.open,
            objectness: if u.objectness {
                p.os_axis
                    .first()
                    .map(|&a| (a, first(p.os_terms, u.objectness_terms)))
            } else {
                None
            },
        }),
        settings: p.settings,
        maps: p.maps,
    }
}

/// The maps of a table: the first `len[h]` knots of `knots(h)` for each head, when the
/// storage has room for maps (`any`; none otherwise, known at compile time for arrays).
#[inline(always)]
pub(crate) fn maps_of<'a>(
    any: bool,
    len: &[u8; 4],
    knots: impl Fn(usize) -> Option<&'a [Knot]>,
) -> Maps<'a> {
    if !any {
        return Maps::NONE;
    }
    Maps(core::array::from_fn(|h| {
        let len = len.get(h).map_or(0, |&n| usize::from(n));
        knots(h).and_then(|k| k.get(..len)).unwrap_or_default()
    }))
}

impl<S: Storage> TableInner<S> {
    /// The table as a [`TableView`]: the one implementation of encoding and scoring
    /// every storage shares (`Option<TableView>` for a [`BoundedTable`](crate::BoundedTable),
    /// `None` when it is empty).
    #[inline]
    pub fn view(&self) -> S::View<'_> {
        S::wrap(self, self.in_use_view())
    }

    /// The table in use as a [`TableView`] (no classes for an empty bounded table).
    #[inline(always)]
    pub(crate) fn in_use_view(&self) -> TableView<'_, S::MlFreqs, S::MapFreqs> {
        let in_use = S::in_use(self);
        view_of(
            Parts {
                names: self.names.items(),
                rows: self.rows.items(),
                priors: self.priors.items(),
                ml: self.ml.items(),
                map: self.map.items(),
                settings: self.settings.borrow(),
                axes: self.bayes_axes.items(),
                terms: self.bayes_terms.items(),
                categories: self.bayes_rows.items(),
                log_prior: self.bayes_log_prior.items(),
                lambda: self.bayes_lambda,
                log_lambda: self.bayes_log_lambda,
                open: self.bayes_open,
                os_axis: self.bayes_os_axis.items(),
                os_terms: self.bayes_os_terms.items(),
                maps: maps_of(in_use.maps, &self.recal_len, |h| {
                    self.recal.get(h).map(Items::items)
                }),
            },
            in_use,
        )
    }

    /// The one decoder: decodes and validates `bytes` into this storage (which
    /// `Storage::prepare` sizes or checks), with `scratch`
    /// giving room for K names and K pairs of lengths as parsed.
    pub(crate) fn decode_with<'a, N, L>(
        &mut self,
        bytes: &'a [u8],
        scratch: impl FnOnce(usize) -> (N, L),
    ) -> Result<(), DecodeError>
    where
        N: AsMut<[&'a str]>,
        L: AsMut<[(usize, usize)]>,
    {
        // A section appended to the table (quantized, monitor...) is not part of it.
        let bytes = crate::quantized::qtable::table_part(bytes);
        let (header, body) = wire::open(bytes)?;
        let shape = StorageShape {
            classes: usize::from(header.k),
            bins_ml: usize::from(header.bins_ml),
            bins_map: usize::from(header.bins_map),
            bins_bayes: usize::from(header.bins_bayes),
            categories: usize::from(header.categories),
            ..StorageShape::default()
        };
        let found = (header.shape(), header.bayes_shape());
        S::prepare(self, &shape, found, body.len())?;
        let (k, cats, bins) = (shape.classes, shape.categories, shape.bins_bayes);
        let (mut raw_names, mut lens) = scratch(k);
        let mut has_os = false;
        let [r0, r1, r2, r3] = &mut self.recal;
        let bayes = if bins > 0 {
            let terms = cats.saturating_mul(k).saturating_mul(bins);
            Some(BayesStorage {
                axes: first_mut(self.bayes_axes.items_mut(), k)?,
                terms: first_mut(self.bayes_terms.items_mut(), terms)?,
                rows: first_mut(self.bayes_rows.items_mut(), cats)?,
                log_prior: first_mut(self.bayes_log_prior.items_mut(), cats)?,
                lambda: &mut self.bayes_lambda,
                log_lambda: &mut self.bayes_log_lambda,
                open: &mut self.bayes_open,
                objectness_axis: self.bayes_os_axis.items_mut(),
                objectness_terms: self.bayes_os_terms.items_mut(),
                objectness_required: S::OBJECTNESS_REQUIRED,
                has_objectness: &mut has_os,
            })
        } else {
            None
        };
        let knots = Slots {
            names: first_mut(self.names.items_mut(), k)?,
            raw_names: first_mut(raw_names.as_mut(), k)?,
            lens: first_mut(lens.as_mut(), k)?,
            rows: first_mut(self.rows.items_mut(), k)?,
            priors: first_mut(self.priors.items_mut(), k)?,
            ml: first_mut(self.ml.items_mut(), k)?,
            map: first_mut(self.map.items_mut(), k)?,
            settings: self.settings.borrow_mut(),
            bayes,
            recal: [
                r0.items_mut(),
                r1.items_mut(),
                r2.items_mut(),
                r3.items_mut(),
            ],
        }
        .decode(&header, body)?;
        if k < 2 {
            return Err(TableError::ClassCount.into());
        }
        for (len, &n) in self.recal_len.iter_mut().zip(&knots) {
            // At most MAX_KNOTS (checked by the decoder).
            *len = u8::try_from(n).unwrap_or(0);
        }
        S::finish(self, &shape, has_os, knots);
        wire::check_canonical(bytes.len(), &self.in_use_view())
    }

    /// Number of classes K (0 for an empty bounded table).
    #[inline]
    pub fn k(&self) -> usize {
        S::in_use(self).classes
    }

    /// Bins of the ML head.
    #[inline]
    pub fn bins_ml(&self) -> usize {
        self.in_use_view().bins_ml()
    }

    /// Bins of the MAP head.
    #[inline]
    pub fn bins_map(&self) -> usize {
        self.in_use_view().bins_map()
    }

    /// The statistics of class `i` (ML and MAP heads), as slices.
    pub fn spec(&self, i: usize) -> Option<ClassSpec<'_, &[f32], &[f32]>> {
        self.in_use_view().spec(i)
    }

    /// Name of class `i`.
    pub fn class_name(&self, i: usize) -> Option<&str> {
        self.in_use_view().class_name(i)
    }

    /// Index of the class called `name`.
    pub fn class_index(&self, name: &str) -> Option<usize> {
        self.in_use_view().class_index(name)
    }

    /// Class names in order.
    pub fn class_names(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        self.in_use_view().names.iter().map(ClassName::as_str)
    }

    /// Hyper-parameters and policies of the ML and MAP heads.
    pub fn settings(&self) -> &Settings {
        self.settings.borrow()
    }

    /// Training rows per class.
    pub fn rows(&self) -> &[u64] {
        self.in_use_view().rows
    }

    /// The Gaussian priors, one per class.
    pub fn priors(&self) -> &[Gaussian] {
        self.in_use_view().priors
    }

    /// The ML histograms, one per class.
    pub fn ml_histograms(&self) -> &[Histogram<S::MlFreqs>] {
        self.in_use_view().ml
    }

    /// The MAP histograms, one per class.
    pub fn map_histograms(&self) -> &[Histogram<S::MapFreqs>] {
        self.in_use_view().map
    }

    /// The Bayes head, if the table has one.
    pub fn bayes_head(&self) -> Option<BayesView<'_>> {
        self.in_use_view().bayes()
    }

    /// The open head's parameters (DESIGN §1.8), if the table has that head.
    pub fn open_params(&self) -> Option<OpenParams> {
        self.in_use_view().open()
    }

    /// The recalibration map of `head` (DESIGN §1.9), when the table holds one; the
    /// scoring calls apply it.
    pub fn recal_map(&self, head: Head) -> Option<RecalMap<'_>> {
        self.in_use_view().recal_map(head)
    }

    /// Number of bytes the encoding of the table takes.
    pub fn encoded_len(&self) -> usize {
        self.in_use_view().encoded_len()
    }

    /// ML scores of one detection into `out` (K entries); `scratch` is any K floats.
    ///
    /// # Errors
    ///
    /// As [`Table::ml`](crate::Table::ml), plus [`InferError::Length`] when a slice
    /// does not have K entries.
    pub fn ml_into(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.in_use_view().ml_into(logits, objectness, out, scratch)
    }

    /// MAP scores of one detection with backend `M` into `out` (K entries).
    ///
    /// # Errors
    ///
    /// As [`TableInner::ml_into`].
    pub fn map_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.in_use_view()
            .map_into::<M>(logits, objectness, out, scratch)
    }

    /// Bayes scores of one detection with backend `M` into `out` (K entries);
    /// `scratch` holds one float per Bayes category (K or K + 1). `M = FastMath` gives
    /// the bits of [`Table::bayes`](crate::Table::bayes).
    ///
    /// # Errors
    ///
    /// [`InferError::NoBayesHead`] without that head; otherwise as
    /// [`TableInner::ml_into`].
    pub fn bayes_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.in_use_view()
            .bayes_into::<M>(logits, objectness, out, scratch)
    }

    /// Open-head scores of one detection with backend `M` into `out` (K entries);
    /// `scratch` holds one float per Bayes category. `M = FastMath` gives the bits of
    /// [`Table::open`](crate::Table::open).
    ///
    /// # Errors
    ///
    /// [`InferError::NoOpenHead`] without that head; otherwise as
    /// [`TableInner::ml_into`].
    pub fn open_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.in_use_view()
            .open_into::<M>(logits, objectness, out, scratch)
    }
}

#[cfg(all(test, feature = "alloc"))]
mod tests {
    use super::*;
    use crate::heads::recal::HEADS;
    use crate::{BoundedTable, DynTable, Table, MAX_KNOTS};
    use std::boxed::Box;
    use std::vec::Vec;

    const SHIPPED: &[u8] = include_bytes!("../../../tables/default.mlmap");
    const SMALL: &[u8] = include_bytes!("../../../tests/golden/layer/small.mlmap");
    const SMALL_MAPS: &[u8] = include_bytes!("../../../tests/golden/layer/small_maps.mlmap");
    const SMALL_OSF: &[u8] = include_bytes!("../../../tests/golden/layer/small_osf.mlmap");
    const SMALL_OPEN: &[u8] = include_bytes!("../../../tests/golden/layer/small_open.mlmap");

    type Big = BoundedTable<16, 64, 64, 64, 17, MAX_KNOTS, 1>;

    fn hists<F: AsRef<[f32]>>(h: &[Histogram<F>]) -> Vec<(f32, f32, f32, f32, Vec<f32>)> {
        h.iter()
            .map(|h| (h.lo, h.hi, h.width, h.inv_width, h.freqs.as_ref().to_vec()))
            .collect()
    }

    /// Every accessor of `a` answers as `b`'s does.
    fn same<S: Storage, T: Storage>(a: &TableInner<S>, b: &TableInner<T>) {
        assert_eq!(
            (a.k(), a.bins_ml(), a.bins_map()),
            (b.k(), b.bins_ml(), b.bins_map())
        );
        assert_eq!(
            a.class_names().collect::<Vec<_>>(),
            b.class_names().collect::<Vec<_>>()
        );
        for i in 0..=a.k() {
            assert_eq!(a.class_name(i), b.class_name(i));
            assert_eq!(a.spec(i), b.spec(i));
        }
        assert_eq!(a.class_index("car"), b.class_index("car"));
        assert_eq!(a.settings(), b.settings());
        assert_eq!(a.rows(), b.rows());
        assert_eq!(a.priors(), b.priors());
        assert_eq!(hists(a.ml_histograms()), hists(b.ml_histograms()));
        assert_eq!(hists(a.map_histograms()), hists(b.map_histograms()));
        assert_eq!(a.bayes_head(), b.bayes_head());
        assert_eq!(a.open_params(), b.open_params());
        for head in HEADS {
            assert_eq!(a.recal_map(head), b.recal_map(head));
        }
        assert_eq!(a.encoded_len(), b.encoded_len());
    }

    /// The accessors of every storage agree, table by table, with the run-time shaped
    /// one's; an empty bounded table has none.
    #[test]
    fn every_storage_answers_alike() {
        let mut bounded = Box::new(Big::new());
        assert_eq!((bounded.k(), bounded.rows().len()), (0, 0));
        assert!(bounded.bayes_head().is_none() && bounded.class_name(0).is_none());
        for bytes in [SHIPPED, SMALL, SMALL_MAPS, SMALL_OSF, SMALL_OPEN] {
            let d = DynTable::from_bytes(bytes).unwrap();
            bounded.decode(bytes).unwrap();
            same(&d, &*bounded);
            assert_eq!(d.encoded_len(), bytes.len());
        }
        let shipped = Table::<3, 22, 17, 22, 4>::from_bytes(SHIPPED).unwrap();
        same(&shipped, &DynTable::from_bytes(SHIPPED).unwrap());
        let small = Table::<3, 4, 2>::from_bytes(SMALL).unwrap();
        same(&small, &DynTable::from_bytes(SMALL).unwrap());
        let maps = Table::<3, 4, 2, 4, 4, MAX_KNOTS>::from_bytes(SMALL_MAPS).unwrap();
        same(&maps, &DynTable::from_bytes(SMALL_MAPS).unwrap());
        // A copy of a fixed-size table is the same table.
        same(&DynTable::from_table(&maps), &maps);
    }
}
