//! A table whose shape is known only at run time (feature `alloc`), for the host
//! (fitting, tuning, the CLI) and for `mlmap`'s build script: the one
//! [`TableInner`] over vectors ([`VecStorage`]), so that host and device accept the
//! same bytes, through the same decoder, and compute identical scores through the same
//! [`TableView`].

use alloc::vec;
use alloc::vec::Vec;

use crate::diagnostics::error::{DecodeError, EncodeError, Head, MapError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{ClassSpec, Settings};
use crate::heads::bayes;
use crate::heads::open::OpenParams;
use crate::heads::recal::{self, head_slot, Knot, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::storage::inner::{private::Sealed, InUse, Storage, TableInner};
use crate::storage::lent::StorageShape;
use crate::storage::view::{self, TableView};

/// A validated table with a run-time number of classes and bins: the one
/// [`TableInner`] over vectors.
///
/// Same invariants, same wire format and same scores as
/// [`Table`](crate::Table); convert with [`DynTable::from_table`] and
/// [`Table::try_from`](crate::Table).
pub type DynTable = TableInner<VecStorage>;

/// The storage of a [`DynTable`]: vectors of exactly the table's shape (a table
/// without a Bayes head has no axes, terms or categories; one without the objectness
/// feature no objectness axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VecStorage;

impl Sealed for VecStorage {}

impl Storage for VecStorage {
    type Names = Vec<ClassName>;
    type Rows = Vec<u64>;
    type Priors = Vec<Gaussian>;
    type MlFreqs = Vec<f32>;
    type MapFreqs = Vec<f32>;
    type Ml = Vec<Histogram<Vec<f32>>>;
    type Map = Vec<Histogram<Vec<f32>>>;
    type Settings = Settings;
    type Axes = Vec<Axis>;
    type Terms = Vec<f32>;
    type Categories = Vec<u64>;
    type LogPrior = Vec<f32>;
    type Knots = Vec<Knot>;
    type ObjectnessAxis = Vec<Axis>;
    type ObjectnessTerms = Vec<f32>;
    type Extent = ();
    type View<'a> = TableView<'a, Vec<f32>, Vec<f32>>;

    const NAME: &'static str = "DynTable";
    const OBJECTNESS_REQUIRED: bool = false;

    /// All of it: the vectors have the table's shape.
    #[inline]
    fn in_use(t: &DynTable) -> InUse {
        InUse {
            classes: t.names.len(),
            bayes: !t.bayes_axes.is_empty(),
            categories: t.bayes_rows.len(),
            terms: t.bayes_terms.len(),
            objectness: !t.bayes_os_axis.is_empty(),
            objectness_terms: t.bayes_os_terms.len(),
            maps: true,
        }
    }

    /// Allocates for the shape, after refusing a header announcing more floats than the
    /// body holds.
    fn prepare(
        t: &mut DynTable,
        s: &StorageShape,
        _: ((u16, u16, u16), (u16, u16)),
        body: usize,
    ) -> Result<(), DecodeError> {
        // Every frequency and term takes 4 bytes of the body: refuse a header announcing
        // more than the body holds before allocating for it.
        if s.floats().checked_mul(4).is_none_or(|n| n > body) {
            return Err(DecodeError::Malformed);
        }
        let (k, bins, cats) = (s.classes, s.bins_bayes, s.categories);
        let hist = |bins: usize| crate::lent::empty_histogram(vec![0.0; bins]);
        t.names = vec![ClassName::EMPTY; k];
        t.rows = vec![0; k];
        t.priors = vec![Gaussian::ZERO; k];
        t.ml = vec![hist(s.bins_ml); k];
        t.map = vec![hist(s.bins_map); k];
        if bins > 0 {
            t.bayes_axes = vec![Axis::ZERO; k];
            t.bayes_terms = vec![0.0; cats * k * bins];
            t.bayes_rows = vec![0; cats];
            t.bayes_log_prior = vec![0.0; cats];
            // Room for the objectness feature, whose B * C terms a table with K >= 1
            // logits' terms (counted in the check above) bounds; a header with K = 0
            // (invalid: refused after parsing) gets none, so that it cannot ask for an
            // allocation the body does not back.
            t.bayes_os_axis = vec![Axis::ZERO];
            t.bayes_os_terms = vec![0.0; cats * bins * k.min(1)];
        }
        t.recal = core::array::from_fn(|_| vec![Knot::ZERO; MAX_KNOTS]);
        Ok(())
    }

    /// Keeps the knots in use, and the objectness feature's room only when the table
    /// has it.
    fn finish(t: &mut DynTable, _: &StorageShape, objectness: bool, knots: [usize; 4]) {
        for (map, n) in t.recal.iter_mut().zip(knots) {
            map.truncate(n);
        }
        if !objectness {
            t.bayes_os_axis = Vec::new();
            t.bayes_os_terms = Vec::new();
        }
    }

    #[inline]
    fn wrap<'a>(_: &'a DynTable, view: TableView<'a, Vec<f32>, Vec<f32>>) -> Self::View<'a> {
        view
    }
}

/// A fitted Bayes head before validation (docs/DESIGN.md §1.6), for
/// [`DynTable::with_bayes`].
#[derive(Debug, Clone, PartialEq)]
pub struct BayesSpec {
    /// Additive smoothing inside the logarithm, in `(0, MAX_LAMBDA_BAYES]`.
    pub lambda: f32,
    /// Training rows per category: the K classes, then `background` if present.
    pub rows: Vec<u64>,
    /// First and last edge of each logit's bins (K pairs).
    pub ranges: Vec<(f32, f32)>,
    /// `ln(h + lambda)` per logit, bin and category, logit-major (see [`BayesView`](crate::BayesView)).
    pub terms: Vec<f32>,
    /// The objectness feature (DESIGN §1.6), when fitted: the first and last edge of
    /// its axis over the objectness logit, and its `ln(h + lambda)` per bin and
    /// category (bin-major).
    pub objectness: Option<((f32, f32), Vec<f32>)>,
}

impl DynTable {
    /// Builds a table without a Bayes head from fitted statistics, checking every
    /// invariant; all classes must have the bin counts of the first.
    ///
    /// # Errors
    ///
    /// The first broken invariant.
    pub fn new(
        settings: Settings,
        classes: Vec<ClassSpec<'_, Vec<f32>, Vec<f32>>>,
    ) -> Result<Self, TableError> {
        settings.validate()?;
        if classes.len() < 2 || classes.len() >= usize::from(u16::MAX) {
            return Err(TableError::ClassCount);
        }
        let bins_ml = classes.first().map_or(0, |c| c.ml_freqs.len());
        let bins_map = classes.first().map_or(0, |c| c.map_freqs.len());
        let mut t = Self::empty(settings);
        t.names.reserve(classes.len());
        for (i, spec) in classes.into_iter().enumerate() {
            let c = spec.validate(i, bins_ml, bins_map)?;
            t.names.push(c.name);
            t.rows.push(c.rows);
            t.priors.push(c.prior);
            t.ml.push(c.ml);
            t.map.push(c.map);
        }
        view::check_unique_names(&t.names)?;
        Ok(t)
    }

    /// Adds (or replaces) the Bayes head, checking every invariant of §1.6.
    ///
    /// # Errors
    ///
    /// [`TableError::BayesShape`] when the lengths do not fit K (categories K or K + 1,
    /// K ranges, categories * K * bins terms); otherwise the first broken invariant.
    pub fn with_bayes(mut self, spec: BayesSpec) -> Result<Self, TableError> {
        let k = self.k();
        let categories = spec.rows.len();
        let bins = match categories.checked_mul(k) {
            Some(n) if n > 0 && spec.terms.len().is_multiple_of(n) => spec.terms.len() / n,
            _ => return Err(TableError::BayesShape),
        };
        if spec.ranges.len() != k || bins > usize::from(u16::MAX) {
            return Err(TableError::BayesShape);
        }
        let mut axes: Vec<Axis> = spec
            .ranges
            .iter()
            .map(|&(lo, hi)| Axis {
                lo,
                hi,
                ..Axis::ZERO
            })
            .collect();
        let mut log_prior = vec![0.0; categories];
        let mut objectness = spec.objectness.map(|((lo, hi), terms)| {
            (
                Axis {
                    lo,
                    hi,
                    ..Axis::ZERO
                },
                terms,
            )
        });
        let log_lambda = bayes::validate(
            k,
            bins,
            spec.lambda,
            &mut axes,
            &spec.terms,
            &spec.rows,
            &mut log_prior,
            objectness.as_mut().map(|(a, t)| (a, t.as_slice())),
        )?;
        if objectness.is_some() {
            // Format version 4 holds only names of the rule of DESIGN §6.15.
            self.check_names()?;
        }
        self.bayes_axes = axes;
        self.bayes_terms = spec.terms;
        self.bayes_rows = spec.rows;
        self.bayes_log_prior = log_prior;
        (self.bayes_lambda, self.bayes_log_lambda) = (spec.lambda, log_lambda);
        self.bayes_open = None;
        (self.bayes_os_axis, self.bayes_os_terms) = match objectness {
            Some((axis, terms)) => (vec![axis], terms),
            None => (Vec::new(), Vec::new()),
        };
        Ok(self)
    }

    /// The table without its Bayes head (and without the maps of the Bayes and open
    /// heads).
    pub fn without_bayes(mut self) -> Self {
        let empty = Self::empty(self.settings);
        self.bayes_axes = empty.bayes_axes;
        self.bayes_terms = empty.bayes_terms;
        self.bayes_rows = empty.bayes_rows;
        self.bayes_log_prior = empty.bayes_log_prior;
        (self.bayes_lambda, self.bayes_log_lambda) = (0.0, 0.0);
        self.bayes_open = None;
        self.bayes_os_axis = empty.bayes_os_axis;
        self.bayes_os_terms = empty.bayes_os_terms;
        self.clear_map(Head::Bayes);
        self.clear_map(Head::Open);
        self
    }

    /// The table with `knots` as the recalibration map of `head` (DESIGN §1.9), in place
    /// of any map it had. The table is then written as format version 4.
    ///
    /// # Errors
    ///
    /// [`TableError::Map`] when the knots break the rule of §1.9 or the table has no
    /// such head; [`TableError::Name`] when a class name breaks the rule of DESIGN §6.15
    /// (a table decoded from a version-1 or version-2 file may hold one).
    pub fn with_map(mut self, head: Head, knots: Vec<Knot>) -> Result<Self, TableError> {
        let map_err = |error| TableError::Map { head, error };
        if !self.view().has_head(head) {
            return Err(map_err(MapError::NoHead));
        }
        recal::check(knots.as_slice()).map_err(map_err)?;
        self.check_names()?;
        let slot = head_slot(head);
        if let (Some(map), Some(len)) = (self.recal.get_mut(slot), self.recal_len.get_mut(slot)) {
            // At most MAX_KNOTS (checked above).
            *len = u8::try_from(knots.len()).unwrap_or(0);
            *map = knots;
        }
        Ok(self)
    }

    /// The table without the recalibration map of `head`.
    pub fn without_map(mut self, head: Head) -> Self {
        self.clear_map(head);
        self
    }

    /// The table without any recalibration map: the heads' own scores.
    pub fn without_maps(mut self) -> Self {
        self.recal = Default::default();
        self.recal_len = [0; 4];
        self
    }

    fn clear_map(&mut self, head: Head) {
        let slot = head_slot(head);
        if let (Some(map), Some(len)) = (self.recal.get_mut(slot), self.recal_len.get_mut(slot)) {
            map.clear();
            *len = 0;
        }
    }

    /// Checks every class name against the whole rule of DESIGN §6.15, which format
    /// versions 3 and 4 require.
    fn check_names(&self) -> Result<(), TableError> {
        crate::format::name::check_class_names(self.names.iter().map(ClassName::as_str)).map_err(
            |(i, error)| TableError::Name {
                class: u16::try_from(i).unwrap_or(u16::MAX),
                error,
            },
        )
    }

    /// The table with the open head (DESIGN §1.8): its temperature `T` and the prior
    /// weight `epsilon` of the unknown category. The table is then written as format
    /// version 3.
    ///
    /// # Errors
    ///
    /// [`TableError::Name`] when a class name breaks the rule of DESIGN §6.15 (a table
    /// decoded from a version-1 or version-2 file may hold one);
    /// [`TableError::BayesShape`] for a table without a Bayes head (the open head is
    /// built on it); [`TableError::Temperature`] or [`TableError::Epsilon`] for a
    /// parameter out of range.
    pub fn with_open(mut self, temperature: f32, epsilon: f32) -> Result<Self, TableError> {
        // A version-3 file holds only names of the rule of DESIGN §6.15: a table decoded
        // from an older file with another name cannot become one.
        self.check_names()?;
        let k = self.k();
        let bins = self
            .bayes_axes
            .first()
            .map(Axis::bins)
            .ok_or(TableError::BayesShape)?;
        let features = k + self.bayes_os_axis.len();
        self.bayes_open = Some(OpenParams::new(
            temperature,
            epsilon,
            features,
            bins,
            self.bayes_lambda,
        )?);
        Ok(self)
    }

    /// The table without its open head (a version-2 table if it has a Bayes head and no
    /// map), and without that head's map.
    pub fn without_open(mut self) -> Self {
        self.bayes_open = None;
        self.clear_map(Head::Open);
        self
    }

    /// Decodes and validates a table of any shape.
    ///
    /// # Errors
    ///
    /// As [`Table::from_bytes`](crate::Table::from_bytes), except that there is no
    /// shape to mismatch.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DecodeError> {
        let mut t = Self::empty(Settings::ZERO);
        t.decode_with(bytes, |k| (vec![""; k], vec![(0, 0); k]))?;
        Ok(t)
    }

    /// Encodes the table (the same bytes [`Table::to_slice`](crate::Table::to_slice)
    /// writes for an equal table).
    ///
    /// # Errors
    ///
    /// Never in practice: the buffer is sized from the table.
    pub fn to_vec(&self) -> Result<Vec<u8>, EncodeError> {
        let view = self.view();
        let mut buf = vec![0u8; view.encoded_len()];
        let len = view.encode(&mut buf)?.len();
        buf.truncate(len);
        Ok(buf)
    }

    /// A table of no class and no part, with `settings` (it does not satisfy the
    /// invariants: every constructor fills it before it escapes).
    fn empty(settings: Settings) -> Self {
        Self {
            names: Vec::new(),
            rows: Vec::new(),
            priors: Vec::new(),
            ml: Vec::new(),
            map: Vec::new(),
            settings,
            bayes_axes: Vec::new(),
            bayes_terms: Vec::new(),
            bayes_rows: Vec::new(),
            bayes_log_prior: Vec::new(),
            bayes_lambda: 0.0,
            bayes_log_lambda: 0.0,
            bayes_open: None,
            recal: Default::default(),
            recal_len: [0; 4],
            bayes_os_axis: Vec::new(),
            bayes_os_terms: Vec::new(),
            extent: (),
        }
    }

    /// The run-time shaped copy of a fixed-size table.
    pub fn from_table<
        const K: usize,
        const B_ML: usize,
        const B_MAP: usize,
        const B_BAYES: usize,
        const C: usize,
        const N: usize,
        const F: usize,
    >(
        t: &crate::Table<K, B_ML, B_MAP, B_BAYES, C, N, F>,
    ) -> Self {
        let v = t.view();
        let mut d = Self::empty(*v.settings);
        d.names = v.names.to_vec();
        d.rows = v.rows.to_vec();
        d.priors = v.priors.to_vec();
        d.ml = v.ml.iter().map(to_vec_hist).collect();
        d.map = v.map.iter().map(to_vec_hist).collect();
        if let Some(b) = v.bayes {
            d.bayes_axes = b.axes.to_vec();
            d.bayes_terms = b.terms.to_vec();
            d.bayes_rows = b.rows.to_vec();
            d.bayes_log_prior = b.log_prior.to_vec();
            (d.bayes_lambda, d.bayes_log_lambda) = (b.lambda, b.log_lambda);
            d.bayes_open = b.open;
            if let Some((axis, terms)) = b.objectness {
                (d.bayes_os_axis, d.bayes_os_terms) = (vec![axis], terms.to_vec());
            }
        }
        d.recal = v.maps.0.map(<[Knot]>::to_vec);
        d.recal_len = t.recal_len;
        d
    }
}

fn to_vec_hist<const B: usize>(h: &Histogram<[f32; B]>) -> Histogram<Vec<f32>> {
    Histogram {
        lo: h.lo,
        hi: h.hi,
        width: h.width,
        inv_width: h.inv_width,
        freqs: h.freqs.to_vec(),
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
    > TryFrom<&DynTable> for crate::Table<K, B_ML, B_MAP, B_BAYES, C, N, F>
{
    type Error = DecodeError;

    /// Converts through the wire format, so every check of
    /// [`Table::from_bytes`](crate::Table::from_bytes) applies.
    fn try_from(t: &DynTable) -> Result<Self, DecodeError> {
        let bytes = t.to_vec().map_err(|_| DecodeError::Malformed)?;
        Self::from_bytes(&bytes)
    }
}
