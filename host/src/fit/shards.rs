//! The fit as two exact, mergeable passes over shards of the data: see the
//! "Sharded fitting" section of [`crate::fit`].

mod block;
mod wire;

use wire::{
    check_names, decode, encode, format_error, CountsWire, EdgesWire, ParamsWire, StatsWire,
};

pub use block::{FitLabel, FitLogit};

use std::path::Path;

use super::bayes::{BayesCounters, BayesMoments};
use super::stats::{BinCounter, ClassHistogram, ClassMoments};
use super::{
    build_table, checked_axis, class_value, require_rows, with_bayes, FitError, FitParams,
};
use crate::dataset::Row;
use crate::DynTable;
use mlmap_core::Axis;

/// The format version of serialized [`FitStats`], [`FitEdges`] and [`FitCounts`].
pub const STATS_FORMAT_VERSION: u16 = 1;

const MAGIC_STATS: &[u8; 8] = b"MLMAPFST";
const MAGIC_EDGES: &[u8; 8] = b"MLMAPFED";
const MAGIC_COUNTS: &[u8; 8] = b"MLMAPFCT";
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// What [`FitStats::edges`] names in an error about classes without rows.
const STATS: &str = "the statistics";

/// Pass (a) of a fit: the exact, mergeable statistics of some rows (see the
/// [sharded fitting](crate::fit#sharded-fitting)).
///
/// The fit settings can be recorded with them ([`with_params`](Self::with_params)), so
/// that shards fitted with other settings cannot be merged by mistake.
#[derive(Debug, Clone, PartialEq)]
pub struct FitStats {
    classes: Vec<String>,
    params: Option<FitParams>,
    rows: u64,
    moments: Vec<ClassMoments>,
    bayes: BayesMoments,
}

impl FitStats {
    /// Empty statistics of the classes `classes` (in column order).
    pub fn new<S: AsRef<str>>(classes: &[S]) -> Self {
        Self {
            classes: classes.iter().map(|c| c.as_ref().to_string()).collect(),
            params: None,
            rows: 0,
            moments: classes
                .iter()
                .map(|c| ClassMoments::new(c.as_ref()))
                .collect(),
            bayes: BayesMoments::new(classes),
        }
    }

    /// The same statistics with the fit settings `params` recorded.
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] for parameters out of range.
    pub fn with_params(mut self, params: FitParams) -> Result<Self, FitError> {
        params.validate()?;
        self.params = Some(params);
        Ok(self)
    }

    /// The recorded fit settings, if any.
    pub fn params(&self) -> Option<&FitParams> {
        self.params.as_ref()
    }

    /// The class names.
    pub fn classes(&self) -> &[String] {
        &self.classes
    }

    /// Rows pushed (labelled or not).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// The statistics of every class's training values, in class order.
    pub fn moments(&self) -> &[ClassMoments] {
        &self.moments
    }

    /// The Bayes head's pass-(a) statistics.
    pub fn bayes(&self) -> &BayesMoments {
        &self.bayes
    }

    /// Adds one row (with one logit per class, as every [`RowSource`](crate::dataset::RowSource)
    /// gives).
    #[inline]
    pub fn push(&mut self, row: &Row<'_>) {
        self.rows += 1;
        if let Some((c, x)) = class_value(row) {
            if let Some(m) = self.moments.get_mut(c) {
                m.push(x);
            }
        }
        self.bayes.push(row);
    }

    /// Adds the statistics of other rows: the result is the same as pushing them here.
    ///
    /// # Errors
    ///
    /// [`FitError::ClassesDiffer`] for statistics of other classes,
    /// [`FitError::ParamsDiffer`] when both recorded settings and they differ (or only
    /// one did). Nothing is changed on error.
    pub fn merge(&mut self, other: &FitStats) -> Result<(), FitError> {
        if self.classes != other.classes {
            return Err(FitError::ClassesDiffer {
                ours: self.classes.clone(),
                theirs: other.classes.clone(),
            });
        }
        if self.params != other.params {
            return Err(FitError::ParamsDiffer);
        }
        self.bayes.merge(&other.bayes)?;
        self.rows = self.rows.saturating_add(other.rows);
        for (m, o) in self.moments.iter_mut().zip(&other.moments) {
            m.merge(o);
        }
        Ok(())
    }

    /// The edges of every histogram for a fit with `params`.
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] for parameters out of range; [`FitError::Objectness`] for the
    /// objectness feature, which needs the rows; [`FitError::ParamsDiffer`] when
    /// the statistics recorded other settings; [`FitError::EmptyClasses`] (naming "the
    /// statistics") when a class has no rows; [`FitError::Edges`] or
    /// [`FitError::OutOfF32`] for classes whose range a table cannot hold.
    pub fn edges(&self, params: &FitParams) -> Result<FitEdges, FitError> {
        params.validate()?;
        if params.bayes.is_some_and(|b| b.objectness) {
            return Err(FitError::Objectness {
                reason: "statistics do not hold the objectness of the rows: fit from the \
                         rows themselves",
            });
        }
        if self.params.is_some_and(|p| p != *params) {
            return Err(FitError::ParamsDiffer);
        }
        require_rows(Path::new(STATS), &self.moments)?;
        let axes = |bins| {
            self.moments
                .iter()
                .map(|m| checked_axis(m.name(), m.min(), m.max(), bins, params.edges))
                .collect::<Result<Vec<Axis>, FitError>>()
        };
        let bayes = match params.bayes {
            Some(p) => Some((self.bayes.category_rows().len(), self.bayes.axes(p.bins)?)),
            None => None,
        };
        Ok(FitEdges {
            params: *params,
            classes: self.classes.clone(),
            ml: axes(params.bins_ml)?,
            map: axes(params.bins_map)?,
            bayes,
        })
    }

    /// The serialized statistics (see the [sharded fitting](crate::fit#sharded-fitting)).
    pub fn to_bytes(&self) -> Vec<u8> {
        let (bayes_min, bayes_max, bayes_rows) = self.bayes.to_parts();
        let wire = StatsWire {
            classes: self.classes.clone(),
            params: self.params.as_ref().map(ParamsWire::from),
            rows: self.rows,
            moments: self.moments.iter().map(ClassMoments::to_parts).collect(),
            bayes_min,
            bayes_max,
            bayes_rows,
        };
        encode(MAGIC_STATS, &wire)
    }

    /// Statistics from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    ///
    /// [`FitError::Format`] for bytes that are not statistics of this format version,
    /// or that are truncated or corrupt.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FitError> {
        let w: StatsWire = decode(MAGIC_STATS, bytes)?;
        check_names(&w.classes, "statistics")?;
        let bad = |what: &str| format_error(format!("inconsistent statistics: {what}"));
        let params = w.params.map(ParamsWire::into_params).transpose()?;
        if w.moments.len() != w.classes.len() {
            return Err(bad("one entry per class expected"));
        }
        let moments = w
            .classes
            .iter()
            .zip(&w.moments)
            .map(|(name, p)| ClassMoments::from_parts(name.clone(), p))
            .collect::<Option<Vec<_>>>()
            .ok_or_else(|| bad("class moments"))?;
        let bayes = BayesMoments::from_parts(&w.classes, w.bayes_min, w.bayes_max, w.bayes_rows)
            .ok_or_else(|| bad("Bayes head statistics"))?;
        let class_rows = moments.iter().map(ClassMoments::count);
        let labelled = class_rows
            .clone()
            .zip(bayes.category_rows())
            .all(|(a, &b)| a == b);
        let total = bayes
            .category_rows()
            .iter()
            .try_fold(0u64, |acc, &n| acc.checked_add(n));
        if !labelled || total.is_none_or(|t| t > w.rows) {
            return Err(bad("row counts"));
        }
        Ok(Self {
            classes: w.classes,
            params,
            rows: w.rows,
            moments,
            bayes,
        })
    }
}

/// What pass (b) needs: the fit settings and the axis of every histogram (ML and MAP
/// per class, Bayes per logit), from [`FitStats::edges`].
///
/// Edges are a function of the (merged) statistics and the settings, so they can be
/// recomputed wherever those are; they also serialize ([`to_bytes`](Self::to_bytes)),
/// to ship them to the machines that run pass (b).
#[derive(Debug, Clone, PartialEq)]
pub struct FitEdges {
    params: FitParams,
    classes: Vec<String>,
    ml: Vec<Axis>,
    map: Vec<Axis>,
    /// Categories (K, or K + 1 with background rows) and the axis of every logit.
    bayes: Option<(usize, Vec<Axis>)>,
}

impl FitEdges {
    /// The fit settings.
    pub fn params(&self) -> &FitParams {
        &self.params
    }

    /// The class names.
    pub fn classes(&self) -> &[String] {
        &self.classes
    }

    /// The ML head's axis of every class.
    pub fn ml(&self) -> &[Axis] {
        &self.ml
    }

    /// The MAP head's axis of every class.
    pub fn map(&self) -> &[Axis] {
        &self.map
    }

    /// The Bayes head's axis of every logit (`None` without that head).
    pub fn bayes(&self) -> Option<&[Axis]> {
        self.bayes.as_ref().map(|(_, a)| a.as_slice())
    }

    fn to_wire(&self) -> EdgesWire {
        let ranges = |axes: &[Axis]| axes.iter().map(|a| (a.lo(), a.hi())).collect();
        EdgesWire {
            params: ParamsWire::from(&self.params),
            classes: self.classes.clone(),
            ml: ranges(&self.ml),
            map: ranges(&self.map),
            bayes: self
                .bayes
                .as_ref()
                .map(|(c, axes)| (*c as u64, ranges(axes))),
        }
    }

    fn from_wire(w: EdgesWire) -> Result<Self, FitError> {
        check_names(&w.classes, "edges")?;
        let params = w.params.into_params()?;
        let k = w.classes.len();
        let bad = |what: &str| format_error(format!("inconsistent edges: {what}"));
        let axes = |ranges: &[(f32, f32)], bins| {
            if ranges.len() != k {
                return Err(bad("one axis per class expected"));
            }
            ranges
                .iter()
                .map(|&(lo, hi)| Axis::new(lo, hi, bins).map_err(|_| bad("invalid axis")))
                .collect::<Result<Vec<Axis>, FitError>>()
        };
        let bayes = match (params.bayes, &w.bayes) {
            (Some(p), Some((c, ranges))) if *c == k as u64 || *c == k as u64 + 1 => {
                Some((*c as usize, axes(ranges, p.bins)?))
            }
            (None, None) => None,
            _ => return Err(bad("Bayes head")),
        };
        Ok(Self {
            ml: axes(&w.ml, params.bins_ml)?,
            map: axes(&w.map, params.bins_map)?,
            params,
            classes: w.classes,
            bayes,
        })
    }

    /// The serialized edges (see the [sharded fitting](crate::fit#sharded-fitting)).
    pub fn to_bytes(&self) -> Vec<u8> {
        encode(MAGIC_EDGES, &self.to_wire())
    }

    /// Edges from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    ///
    /// [`FitError::Format`] for bytes that are not edges of this format version, or
    /// that are truncated or corrupt.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FitError> {
        Self::from_wire(decode(MAGIC_EDGES, bytes)?)
    }
}

/// Pass (b) of a fit: the bin counts of every head over given [`FitEdges`] (see the
/// [sharded fitting](crate::fit#sharded-fitting)).
#[derive(Debug, Clone)]
pub struct FitCounts {
    edges: FitEdges,
    rows: u64,
    ml: Vec<BinCounter>,
    map: Vec<BinCounter>,
    bayes: Option<BayesCounters>,
}

impl PartialEq for FitCounts {
    fn eq(&self, other: &Self) -> bool {
        self.to_bytes() == other.to_bytes()
    }
}

impl FitCounts {
    /// Empty counts over `edges`.
    pub fn new(edges: &FitEdges) -> Self {
        let counters = |axes: &[Axis]| axes.iter().map(|&a| BinCounter::from_axis(a)).collect();
        Self {
            edges: edges.clone(),
            rows: 0,
            ml: counters(&edges.ml),
            map: counters(&edges.map),
            bayes: edges
                .bayes
                .as_ref()
                .map(|(c, axes)| BayesCounters::new(*c, axes)),
        }
    }

    /// The edges counted over.
    pub fn edges(&self) -> &FitEdges {
        &self.edges
    }

    /// Rows pushed (labelled or not).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Counts one row; `false` when a value falls outside its axis (or a background
    /// row comes where pass (a) saw none): the edges are not those of statistics that
    /// include this row.
    #[inline]
    pub fn push(&mut self, row: &Row<'_>) -> bool {
        self.rows += 1;
        let mut inside = true;
        if let Some((c, x)) = class_value(row) {
            if let (Some(a), Some(b)) = (self.ml.get_mut(c), self.map.get_mut(c)) {
                let x = x as f32;
                inside &= a.add(x) & b.add(x);
            }
        }
        if let Some(b) = &mut self.bayes {
            inside &= b.add(row);
        }
        inside
    }

    /// Adds the counts of other rows over the same edges.
    ///
    /// # Errors
    ///
    /// [`FitError::EdgesDiffer`] when `other` counted over other edges; nothing is
    /// changed then.
    pub fn merge(&mut self, other: &FitCounts) -> Result<(), FitError> {
        if self.edges != other.edges {
            return Err(FitError::EdgesDiffer);
        }
        let mut merged = self.clone();
        let ok = merged
            .ml
            .iter_mut()
            .zip(&other.ml)
            .chain(merged.map.iter_mut().zip(&other.map))
            .all(|(a, b)| a.add_counts(b.counts()))
            && match (&mut merged.bayes, &other.bayes) {
                (Some(a), Some(b)) => a.add_counts(&b.counts()),
                (None, None) => true,
                _ => false,
            };
        if !ok {
            return Err(FitError::EdgesDiffer);
        }
        merged.rows = merged.rows.saturating_add(other.rows);
        *self = merged;
        Ok(())
    }

    /// The serialized counts, with their edges (see the [sharded fitting](crate::fit#sharded-fitting)).
    pub fn to_bytes(&self) -> Vec<u8> {
        let counts = |c: &[BinCounter]| c.iter().map(|b| b.counts().to_vec()).collect();
        let wire = CountsWire {
            edges: self.edges.to_wire(),
            rows: self.rows,
            ml: counts(&self.ml),
            map: counts(&self.map),
            bayes: self.bayes.as_ref().map(BayesCounters::counts),
        };
        encode(MAGIC_COUNTS, &wire)
    }

    /// Counts from [`to_bytes`](Self::to_bytes).
    ///
    /// # Errors
    ///
    /// [`FitError::Format`] for bytes that are not counts of this format version, or
    /// that are truncated or corrupt.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FitError> {
        let w: CountsWire = decode(MAGIC_COUNTS, bytes)?;
        let edges = FitEdges::from_wire(w.edges)?;
        let mut counts = Self::new(&edges);
        counts.rows = w.rows;
        let bad = || format_error("inconsistent counts: they do not fit their edges".to_string());
        let ok = w.ml.len() == counts.ml.len()
            && w.map.len() == counts.map.len()
            && counts
                .ml
                .iter_mut()
                .zip(&w.ml)
                .chain(counts.map.iter_mut().zip(&w.map))
                .all(|(a, b)| a.add_counts(b))
            && match (&mut counts.bayes, &w.bayes) {
                (Some(a), Some(b)) => a.add_counts(b),
                (None, None) => true,
                _ => false,
            };
        if !ok {
            return Err(bad());
        }
        Ok(counts)
    }
}

/// Serialized pass-(a) statistics or pass-(b) counts, told apart by their magic bytes.
#[derive(Debug, Clone, PartialEq)]
pub enum FitFile {
    /// Pass-(a) statistics ([`FitStats::to_bytes`]).
    Stats(FitStats),
    /// Pass-(b) counts ([`FitCounts::to_bytes`]).
    Counts(FitCounts),
}

impl FitFile {
    /// Decodes statistics or counts, whichever the bytes hold.
    ///
    /// # Errors
    ///
    /// [`FitError::Format`] as [`FitStats::from_bytes`] and [`FitCounts::from_bytes`]
    /// (edges and other bytes are refused).
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FitError> {
        if bytes.starts_with(MAGIC_COUNTS) {
            FitCounts::from_bytes(bytes).map(Self::Counts)
        } else {
            FitStats::from_bytes(bytes).map(Self::Stats)
        }
    }
}

/// Builds the table from pass (a) statistics and pass (b) counts of the same rows.
///
/// # Errors
///
/// [`FitError::ClassesDiffer`] for counts of other classes;
/// [`FitError::EdgesDiffer`] when the counts were not made over the edges of `stats`
/// (with the settings they record); [`FitError::RowsDiffer`] when the counts cover
/// other rows than the statistics; [`FitError::OutOfF32`] or [`FitError::Table`] as
/// [`build_table`].
pub fn finish(stats: &FitStats, counts: &FitCounts) -> Result<DynTable, FitError> {
    if stats.classes != counts.edges.classes {
        return Err(FitError::ClassesDiffer {
            ours: stats.classes.clone(),
            theirs: counts.edges.classes.clone(),
        });
    }
    let params = counts.edges.params;
    if stats.edges(&params)? != counts.edges {
        return Err(FitError::EdgesDiffer);
    }
    let rows_differ = || FitError::RowsDiffer {
        stats: stats.rows,
        counts: counts.rows,
    };
    if stats.rows != counts.rows {
        return Err(rows_differ());
    }
    let histograms = |c: &[BinCounter]| -> Vec<ClassHistogram> {
        c.iter().cloned().map(BinCounter::finish).collect()
    };
    let (ml, map) = (histograms(&counts.ml), histograms(&counts.map));
    for ((m, a), b) in stats.moments.iter().zip(&ml).zip(&map) {
        let counted = if a.total() == m.count() {
            b.total()
        } else {
            a.total()
        };
        if counted != m.count() {
            return Err(FitError::ClassRowsDiffer {
                class: m.name().to_string(),
                stats: m.count(),
                counts: counted,
            });
        }
    }
    let table = build_table(&stats.moments, &ml, &map, params.settings())?;
    match (&counts.bayes, params.bayes) {
        (Some(b), Some(p)) => {
            let bayes = b
                .clone()
                .finish(stats.bayes.category_rows())
                .ok_or_else(rows_differ)?;
            with_bayes(table, &bayes, p.lambda)
        }
        _ => Ok(table),
    }
}
