//! A table whose shape is known only at run time, for the host (fitting, tuning, the
//! CLI) and for `build.rs`. It shares the wire format, the validation and the scoring
//! code with [`Table`](crate::Table), so host and device compute identical scores.

use std::vec::Vec;

use crate::error::{DecodeError, EncodeError, InferError, TableError};
use crate::gaussian::Gaussian;
use crate::histogram::Histogram;
use crate::layer;
use crate::math::Backend;
use crate::name::ClassName;
use crate::wire::{self, ClassSpec, ClassWire, Settings};

/// A validated table with a run-time number of classes and bins.
///
/// Same invariants, same wire format and same scores as
/// [`Table`](crate::Table); convert with [`DynTable::from_table`] and
/// [`Table::try_from`](crate::Table).
#[derive(Debug, Clone, PartialEq)]
pub struct DynTable {
    pub(crate) names: Vec<ClassName>,
    pub(crate) rows: Vec<u64>,
    pub(crate) priors: Vec<Gaussian>,
    pub(crate) ml: Vec<Histogram<Vec<f32>>>,
    pub(crate) map: Vec<Histogram<Vec<f32>>>,
    pub(crate) settings: Settings,
}

impl DynTable {
    /// Builds a table from fitted statistics, checking every invariant; all classes
    /// must have the bin counts of the first.
    ///
    /// # Errors
    ///
    /// The first broken invariant.
    pub fn new(
        settings: Settings,
        classes: Vec<ClassSpec<'_, Vec<f32>, Vec<f32>>>,
    ) -> Result<Self, TableError> {
        settings.validate()?;
        if classes.len() < 2 || classes.len() > usize::from(u16::MAX) {
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
        };
        for (i, spec) in classes.into_iter().enumerate() {
            let c = spec.validate(i, bins_ml, bins_map)?;
            t.names.push(c.name);
            t.rows.push(c.rows);
            t.priors.push(c.prior);
            t.ml.push(c.ml);
            t.map.push(c.map);
        }
        wire::check_unique_names(&t.names)?;
        Ok(t)
    }

    /// Decodes and validates a table of any shape.
    ///
    /// # Errors
    ///
    /// As [`Table::from_bytes`](crate::Table::from_bytes), except that there is no
    /// shape to mismatch.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, DecodeError> {
        let (header, body) = wire::open(bytes)?;
        let (settings, classes) = wire::parse_body::<Vec<ClassWire<'_, Vec<f32>, Vec<f32>>>>(body)?;
        if classes.len() != usize::from(header.k) {
            return Err(DecodeError::Malformed);
        }
        let specs = classes.into_iter().map(ClassWire::into_spec).collect();
        let t = Self::new(settings, specs)?;
        if t.bins_ml() != usize::from(header.bins_ml)
            || t.bins_map() != usize::from(header.bins_map)
        {
            return Err(DecodeError::Malformed);
        }
        let shape = (header.k, header.bins_ml, header.bins_map);
        wire::check_canonical(bytes.len(), shape, &t.settings, |i| t.spec(i))?;
        Ok(t)
    }

    /// Encodes the table (the same bytes [`Table::to_slice`](crate::Table::to_slice)
    /// writes for an equal table).
    ///
    /// # Errors
    ///
    /// Never in practice: the buffer is sized from the shape.
    pub fn to_vec(&self) -> Result<Vec<u8>, EncodeError> {
        let mut buf =
            std::vec![0u8; wire::max_encoded_len(self.k(), self.bins_ml(), self.bins_map())];
        let shape = (
            u16::try_from(self.k()).unwrap_or(u16::MAX),
            u16::try_from(self.bins_ml()).unwrap_or(u16::MAX),
            u16::try_from(self.bins_map()).unwrap_or(u16::MAX),
        );
        let len = wire::encode(shape, &self.settings, |i| self.spec(i), &mut buf)?.len();
        buf.truncate(len);
        Ok(buf)
    }

    /// The statistics of class `i`, as slices.
    pub fn spec(&self, i: usize) -> Option<ClassSpec<'_, &[f32], &[f32]>> {
        let (ml, map, prior) = (self.ml.get(i)?, self.map.get(i)?, self.priors.get(i)?);
        Some(ClassSpec {
            name: self.names.get(i)?.as_str(),
            rows: *self.rows.get(i)?,
            mean: prior.mean,
            variance: prior.var,
            ml_range: (ml.lo, ml.hi),
            ml_freqs: &ml.freqs,
            map_range: (map.lo, map.hi),
            map_freqs: &map.freqs,
        })
    }

    /// Number of classes K.
    pub fn k(&self) -> usize {
        self.names.len()
    }

    /// Bins of the ML head.
    pub fn bins_ml(&self) -> usize {
        self.ml.first().map_or(0, Histogram::bins)
    }

    /// Bins of the MAP head.
    pub fn bins_map(&self) -> usize {
        self.map.first().map_or(0, Histogram::bins)
    }

    /// Class names in order.
    pub fn class_names(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        self.names.iter().map(ClassName::as_str)
    }

    /// Hyper-parameters and policies.
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
        if scratch.len() != self.k() {
            return Err(InferError::Length);
        }
        layer::ml_into(
            &self.ml,
            self.settings.lambda_ml,
            self.settings.upper_tail,
            logits,
            objectness,
            out,
            scratch,
        )
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
        if scratch.len() != self.k() {
            return Err(InferError::Length);
        }
        layer::map_into::<_, M>(
            &self.map,
            &self.priors,
            self.settings.lambda_map,
            self.settings.upper_tail,
            logits,
            objectness,
            out,
            scratch,
        )
    }
}

impl DynTable {
    /// The run-time shaped copy of a fixed-size table.
    pub fn from_table<const K: usize, const B_ML: usize, const B_MAP: usize>(
        t: &crate::Table<K, B_ML, B_MAP>,
    ) -> Self {
        Self {
            names: t.names.to_vec(),
            rows: t.rows.to_vec(),
            priors: t.priors.to_vec(),
            ml: t.ml.iter().map(to_vec_hist).collect(),
            map: t.map.iter().map(to_vec_hist).collect(),
            settings: t.settings,
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

impl<const K: usize, const B_ML: usize, const B_MAP: usize> TryFrom<&DynTable>
    for crate::Table<K, B_ML, B_MAP>
{
    type Error = DecodeError;

    /// Converts through the wire format, so every check of
    /// [`Table::from_bytes`](crate::Table::from_bytes) applies.
    fn try_from(t: &DynTable) -> Result<Self, DecodeError> {
        let bytes = t.to_vec().map_err(|_| DecodeError::Malformed)?;
        Self::from_bytes(&bytes)
    }
}
