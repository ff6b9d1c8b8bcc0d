//! A table whose shape is known only at run time (feature `alloc`), for the host
//! (fitting, tuning, the CLI) and for `mlmap`'s build script. It owns vectors and lends
//! them to the same [`TableView`] and decoder as [`Table`](crate::Table), so host and
//! device accept the same bytes and compute identical scores.

use alloc::vec;
use alloc::vec::Vec;

use crate::diagnostics::error::{DecodeError, EncodeError, Head, InferError, MapError, TableError};
use crate::format::name::ClassName;
use crate::format::wire::{self, ClassSpec, Settings};
use crate::heads::bayes::{self, BayesView};
use crate::heads::open::OpenParams;
use crate::heads::recal::{self, head_slot, Knot, Maps, RecalMap, MAX_KNOTS};
use crate::math::gaussian::Gaussian;
use crate::math::histogram::{Axis, Histogram};
use crate::math::Backend;
use crate::storage::view::{self, BayesStorage, Slots, TableView};

/// A validated table with a run-time number of classes and bins.
///
/// Same invariants, same wire format and same scores as
/// [`Table`](crate::Table); convert with [`DynTable::from_table`] and
/// [`Table::try_from`](crate::Table).
#[derive(Debug, Clone, PartialEq)]
pub struct DynTable {
    names: Vec<ClassName>,
    rows: Vec<u64>,
    priors: Vec<Gaussian>,
    ml: Vec<Histogram<Vec<f32>>>,
    map: Vec<Histogram<Vec<f32>>>,
    settings: Settings,
    bayes: Option<DynBayes>,
    /// Each head's recalibration map (DESIGN §1.9), ML, MAP, Bayes, open; empty: none.
    maps: [Vec<Knot>; 4],
}

/// The Bayes head's storage.
#[derive(Debug, Clone, PartialEq)]
struct DynBayes {
    axes: Vec<Axis>,
    terms: Vec<f32>,
    rows: Vec<u64>,
    log_prior: Vec<f32>,
    lambda: f32,
    log_lambda: f32,
    open: Option<OpenParams>,
    /// The objectness feature's axis and terms (bin-major, then category).
    objectness: Option<(Axis, Vec<f32>)>,
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
    /// `ln(h + lambda)` per logit, bin and category, logit-major (see [`BayesView`]).
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
        let mut t = Self {
            names: Vec::with_capacity(classes.len()),
            rows: Vec::with_capacity(classes.len()),
            priors: Vec::with_capacity(classes.len()),
            ml: Vec::with_capacity(classes.len()),
            map: Vec::with_capacity(classes.len()),
            settings,
            bayes: None,
            maps: Default::default(),
        };
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
        self.bayes = Some(DynBayes {
            axes,
            terms: spec.terms,
            rows: spec.rows,
            log_prior,
            lambda: spec.lambda,
            log_lambda,
            open: None,
            objectness,
        });
        Ok(self)
    }

    /// The table without its Bayes head (and without the maps of the Bayes and open
    /// heads).
    pub fn without_bayes(mut self) -> Self {
        self.bayes = None;
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
        if let Some(slot) = self.maps.get_mut(head_slot(head)) {
            *slot = knots;
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
        self.maps = Default::default();
        self
    }

    /// The recalibration map of `head`, if the table holds one.
    pub fn recal_map(&self, head: Head) -> Option<RecalMap<'_>> {
        self.view().recal_map(head)
    }

    fn clear_map(&mut self, head: Head) {
        if let Some(slot) = self.maps.get_mut(head_slot(head)) {
            slot.clear();
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
        let b = self.bayes.as_mut().ok_or(TableError::BayesShape)?;
        let bins = b.axes.first().map_or(0, Axis::bins);
        let features = k + usize::from(b.objectness.is_some());
        b.open = Some(OpenParams::new(
            temperature,
            epsilon,
            features,
            bins,
            b.lambda,
        )?);
        Ok(self)
    }

    /// The table without its open head (a version-2 table if it has a Bayes head and no
    /// map), and without that head's map.
    pub fn without_open(mut self) -> Self {
        if let Some(b) = self.bayes.as_mut() {
            b.open = None;
        }
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
        // A quantized section appended to the table is not part of it.
        let bytes = crate::quantized::qtable::table_part(bytes);
        let (header, body) = wire::open(bytes)?;
        let k = usize::from(header.k);
        let (bins_ml, bins_map) = (usize::from(header.bins_ml), usize::from(header.bins_map));
        let (bins_bayes, categories) = (
            usize::from(header.bins_bayes),
            usize::from(header.categories),
        );
        // Every frequency and term takes 4 bytes of the body: refuse a header announcing
        // more than the body holds before allocating for it.
        let floats = k * (bins_ml + bins_map) + categories * k * bins_bayes;
        if floats.checked_mul(4).is_none_or(|n| n > body.len()) {
            return Err(DecodeError::Malformed);
        }
        let hist = |bins: usize| Histogram {
            lo: 0.0,
            hi: 0.0,
            width: 0.0,
            inv_width: 0.0,
            freqs: vec![0.0; bins],
        };
        let mut t = Self {
            names: vec![ClassName::EMPTY; k],
            rows: vec![0; k],
            priors: vec![Gaussian::ZERO; k],
            ml: vec![hist(bins_ml); k],
            map: vec![hist(bins_map); k],
            settings: Settings::ZERO,
            bayes: (bins_bayes > 0).then(|| DynBayes {
                axes: vec![Axis::ZERO; k],
                terms: vec![0.0; categories * k * bins_bayes],
                rows: vec![0; categories],
                log_prior: vec![0.0; categories],
                lambda: 0.0,
                log_lambda: 0.0,
                open: None,
                // Room for the objectness feature, whose B * C terms a table with K >= 1
                // logits' terms (counted in the check above) bounds; a header with K = 0
                // (invalid: refused after parsing) gets none, so that it cannot ask for
                // an allocation the body does not back.
                objectness: Some((Axis::ZERO, vec![0.0; categories * bins_bayes * k.min(1)])),
            }),
            maps: core::array::from_fn(|_| vec![Knot::ZERO; MAX_KNOTS]),
        };
        let mut has_objectness = false;
        let mut raw_names = vec![""; k];
        let mut lens = vec![(0, 0); k];
        let [r0, r1, r2, r3] = &mut t.maps;
        let knots = Slots {
            names: &mut t.names,
            raw_names: &mut raw_names,
            lens: &mut lens,
            rows: &mut t.rows,
            priors: &mut t.priors,
            ml: &mut t.ml,
            map: &mut t.map,
            settings: &mut t.settings,
            bayes: t.bayes.as_mut().map(|b| {
                let (axis, terms) = match &mut b.objectness {
                    Some((a, t)) => (core::slice::from_mut(a), t.as_mut_slice()),
                    None => (&mut [][..], &mut [][..]),
                };
                BayesStorage {
                    axes: &mut b.axes,
                    terms: &mut b.terms,
                    rows: &mut b.rows,
                    log_prior: &mut b.log_prior,
                    lambda: &mut b.lambda,
                    log_lambda: &mut b.log_lambda,
                    open: &mut b.open,
                    objectness_axis: axis,
                    objectness_terms: terms,
                    objectness_required: false,
                    has_objectness: &mut has_objectness,
                }
            }),
            recal: [r0, r1, r2, r3],
        }
        .decode(&header, body)?;
        for (map, n) in t.maps.iter_mut().zip(knots) {
            map.truncate(n);
        }
        if !has_objectness {
            if let Some(b) = t.bayes.as_mut() {
                b.objectness = None;
            }
        }
        if k < 2 {
            return Err(TableError::ClassCount.into());
        }
        wire::check_canonical(bytes.len(), &t.view())?;
        Ok(t)
    }

    /// The table as a [`TableView`], the implementation every kind of table shares.
    #[inline]
    pub fn view(&self) -> TableView<'_, Vec<f32>, Vec<f32>> {
        TableView {
            names: &self.names,
            rows: &self.rows,
            priors: &self.priors,
            ml: &self.ml,
            map: &self.map,
            bayes: self.bayes.as_ref().map(|b| BayesView {
                axes: &b.axes,
                terms: &b.terms,
                rows: &b.rows,
                log_prior: &b.log_prior,
                lambda: b.lambda,
                log_lambda: b.log_lambda,
                open: b.open,
                objectness: b.objectness.as_ref().map(|(a, t)| (*a, t.as_slice())),
            }),
            settings: &self.settings,
            maps: Maps(core::array::from_fn(|h| {
                self.maps.get(h).map_or(&[][..], Vec::as_slice)
            })),
        }
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

    /// The statistics of class `i` (ML and MAP heads), as slices.
    pub fn spec(&self, i: usize) -> Option<ClassSpec<'_, &[f32], &[f32]>> {
        self.view().spec(i)
    }

    /// Number of classes K.
    pub fn k(&self) -> usize {
        self.names.len()
    }

    /// Bins of the ML head.
    pub fn bins_ml(&self) -> usize {
        self.view().bins_ml()
    }

    /// Bins of the MAP head.
    pub fn bins_map(&self) -> usize {
        self.view().bins_map()
    }

    /// Class names in order.
    pub fn class_names(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        self.names.iter().map(ClassName::as_str)
    }

    /// Hyper-parameters and policies of the ML and MAP heads.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// Training rows per class.
    pub fn rows(&self) -> &[u64] {
        &self.rows
    }

    /// The ML histograms, one per class.
    pub fn ml_histograms(&self) -> &[Histogram<Vec<f32>>] {
        &self.ml
    }

    /// The MAP histograms, one per class.
    pub fn map_histograms(&self) -> &[Histogram<Vec<f32>>] {
        &self.map
    }

    /// The Gaussian priors, one per class.
    pub fn priors(&self) -> &[Gaussian] {
        &self.priors
    }

    /// The Bayes head, if the table has one.
    pub fn bayes(&self) -> Option<BayesView<'_>> {
        self.view().bayes()
    }

    /// The open head's parameters, if the table has that head.
    pub fn open(&self) -> Option<OpenParams> {
        self.view().open()
    }

    /// ML scores of one detection into `out` (length K); `scratch` is any K floats.
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
        self.view().ml_into(logits, objectness, out, scratch)
    }

    /// MAP scores of one detection with backend `M` into `out` (length K).
    ///
    /// # Errors
    ///
    /// As [`DynTable::ml_into`].
    pub fn map_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.view().map_into::<M>(logits, objectness, out, scratch)
    }

    /// Bayes scores of one detection with backend `M` into `out` (length K);
    /// `scratch` holds one float per Bayes category (K or K + 1). `M = FastMath` gives
    /// the bits of [`Table::bayes`](crate::Table::bayes).
    ///
    /// # Errors
    ///
    /// [`InferError::NoBayesHead`] without that head; otherwise as
    /// [`DynTable::ml_into`].
    pub fn bayes_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.view()
            .bayes_into::<M>(logits, objectness, out, scratch)
    }

    /// Open-head scores of one detection with backend `M` into `out` (length K);
    /// `scratch` holds one float per Bayes category. `M = FastMath` gives the bits of
    /// [`Table::open`](crate::Table::open).
    ///
    /// # Errors
    ///
    /// [`InferError::NoOpenHead`] without that head; otherwise as
    /// [`DynTable::ml_into`].
    pub fn open_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        self.view().open_into::<M>(logits, objectness, out, scratch)
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
        Self {
            names: v.names.to_vec(),
            rows: v.rows.to_vec(),
            priors: v.priors.to_vec(),
            ml: v.ml.iter().map(to_vec_hist).collect(),
            map: v.map.iter().map(to_vec_hist).collect(),
            settings: *v.settings,
            bayes: v.bayes.map(|b| DynBayes {
                axes: b.axes.to_vec(),
                terms: b.terms.to_vec(),
                rows: b.rows.to_vec(),
                log_prior: b.log_prior.to_vec(),
                lambda: b.lambda,
                log_lambda: b.log_lambda,
                open: b.open,
                objectness: b.objectness.map(|(a, t)| (a, t.to_vec())),
            }),
            maps: v.maps.0.map(<[Knot]>::to_vec),
        }
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
