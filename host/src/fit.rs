//! Fitting a table from labelled training logits (DESIGN §1.1; paper §III-B).
//!
//! For each class `c` the fit takes `v_c`, the logit of column `c` of the rows labelled
//! `c` (rows labelled `background` or unlabelled are skipped), and computes:
//!
//! * the **likelihood** of each head: a histogram of `v_c` with `B` equal bins,
//!   normalised to frequencies `count_k / |v_c|`; the edges are placed by
//!   [`EdgeMode::Linspace`] (`[min, max]`) or [`EdgeMode::Matlab`] (MATLAB's bin
//!   picker, below); see [`ClassMoments::range`];
//! * the **prior**: the mean and the sample variance (`ddof = 1`) of `v_c`, the
//!   variance floored to [`VARIANCE_FLOOR`](mlmap_core::VARIANCE_FLOOR).
//!
//! The moments are exact: the sum and sum of squares of `v_c` are accumulated without
//! rounding ([`ClassMoments`]), so the mean and variance do not depend on the order of
//! the rows, and statistics of shards merge exactly ([`FitStats`]). The histogram counts
//! use the values rounded to `f32` and the table's own `f32` edges and bin rule
//! ([`Histogram::bin`](mlmap_core::Histogram::bin)), so each training value is counted in
//! exactly the bin the device looks it up in.
//!
//! # Two ways to fit
//!
//! * [`fit`] streams the data twice (pass (a): [`FitStats`]; pass (b): [`FitCounts`]
//!   over the [`FitEdges`] of pass (a); then [`finish`]). Memory is `O(K B)`, whatever
//!   the number of rows. The same steps run over shards of the data, on any machines,
//!   and merge exactly ([`FitStats::merge`], [`FitCounts::merge`]): any split gives the
//!   table of one fit.
//! * [`TrainingSet::read`] streams the data once and keeps `v_c` of every class in
//!   memory (4 bytes per labelled row, sorted). Histograms for any bin count are then
//!   computed without reading the data again, in `O(K B log n)`
//!   ([`TrainingSet::histograms`]), and [`build_table`] assembles tables for any
//!   lambdas: this is what hyper-parameter tuning needs. Both give identical tables.
//!
//! # Sharded fitting
//!
//! * Pass (a), [`FitStats`]: per class the exact [`ClassMoments`] (count, extremes,
//!   exact sums), and the Bayes head's [`BayesMoments`] (extremes of every logit and
//!   rows per category). Shards' statistics [`merge`](FitStats::merge) exactly.
//! * [`FitStats::edges`] turns the merged statistics and the [`FitParams`] into
//!   [`FitEdges`]: the axes of every histogram.
//! * Pass (b), [`FitCounts`]: the bin counts of every head over those edges, per shard,
//!   merged by addition.
//! * [`finish`] builds the table from the merged statistics and counts.
//!
//! Every step is exact (integer counts, exact sums, extremes), so any split of the rows
//! into shards, merged in any order and grouping, gives the same table bytes as
//! [`fit`](fit()) over all rows; `fit` itself runs these steps over one source.
//!
//! ## Serialized form
//!
//! [`FitStats::to_bytes`], [`FitEdges::to_bytes`] and [`FitCounts::to_bytes`] write
//! `magic (8 bytes) | format version (u16 LE) | postcard body | CRC-32 (u32 LE)`, the
//! CRC (zlib's) covering every byte before it. The magics are `MLMAPFST` (statistics),
//! `MLMAPFED` (edges) and `MLMAPFCT` (counts); the format version is
//! [`STATS_FORMAT_VERSION`]. Floats are stored as their IEEE bits, so a round trip is
//! exact; equal statistics have equal bytes (the exact sums are stored in canonical
//! form). A file of a newer format version, of another kind, truncated or corrupt is
//! refused with a [`FitError::Format`] that says which.
//!
//! ```
//! use mlmap_host::dataset::{Label, Row};
//! use mlmap_host::fit::{finish, FitCounts, FitParams, FitStats};
//!
//! fn row((c, x): &(usize, [f64; 2])) -> Row<'_> {
//!     Row { index: 0, line: None, id: None, label: Label::Class(*c), objectness: 1.0, logits: x }
//! }
//! let rows = [(0, [2.0, -1.0]), (1, [0.5, 1.5]), (0, [3.0, 0.0]), (1, [-0.5, 2.5])];
//! let params = FitParams::default();
//! // Pass (a) on two shards, merged through bytes.
//! let (mut a, mut b) = (FitStats::new(&["car", "person"]), FitStats::new(&["car", "person"]));
//! rows[..1].iter().for_each(|r| a.push(&row(r)));
//! rows[1..].iter().for_each(|r| b.push(&row(r)));
//! let mut stats = FitStats::from_bytes(&b.to_bytes())?;
//! stats.merge(&a)?;
//! // Pass (b) over the edges of the merged statistics.
//! let edges = stats.edges(&params)?;
//! let mut counts = FitCounts::new(&edges);
//! for r in &rows {
//!     assert!(counts.push(&row(r)));
//! }
//! let table = finish(&stats, &counts)?;
//! assert_eq!(table.rows(), &[2, 2]);
//! # Ok::<(), mlmap_host::fit::FitError>(())
//! ```
//!
//! # MATLAB's bin picker
//!
//! The `matlab` edge mode reproduces the edges of MATLAB's `histogram(x, nbins)`, with
//! which the paper's authors built their tables. With `xmin`, `xmax` the extremes of
//! `v_c`, `r = xmax - xmin` and `eps(s)` the spacing of doubles at
//! `s = max(|xmin|, |xmax|)`:
//!
//! 1. Nearly constant data (`r <= sqrt(eps(s))`): the edges are half-integers around
//!    the data with at least a quarter unit of margin, `floor(2 (xmin - u/4)) / 2` and
//!    `ceil(2 (xmax + u/4)) / 2` with `u = max(1, ceil(B eps(s)))`.
//! 2. Otherwise `raw = r / B` is truncated to its leading decimal digit, `w0`, and the
//!    first edge is the multiple of `w0` at or below `xmin`, `left`.
//! 3. For `B > 1` the bin width is the smallest multiple of
//!    `q = 10^floor(log10(hi - lo))` that is at least `lo`, where `lo = (xmax - left)/B`
//!    and `hi = (xmax - left)/(B - 1)` bound the widths that keep `xmax` in the last
//!    bin; for `B = 1` it is `w0`.
//! 4. The last edge is `max(left + B width, xmax)`.
//!
//! Example (MathWorks' `histcounts` documentation): `[2 3 5 7 11 13 17 19 23 29]` with
//! 6 bins gives the edges `0, 4.9, 9.8, ..., 29.4`. MATLAB then counts doubles against
//! double edges; the table counts `f32` values against `f32` edges, which can differ
//! only for a value within an `f32` rounding of an edge.

mod bayes;
mod binpicker;
mod error;
mod exact;
pub mod parts;
mod shards;
mod stats;

use std::path::{Path, PathBuf};

use crate::dataset::{Label, Row, RowSource};
use crate::DynTable;
use mlmap_core::{Axis, ClassSpec, EdgeMode, Settings, TableError, UpperTail, MAX_LAMBDA};

pub use bayes::{BayesCounts, BayesMoments, BayesParams};
pub use error::{warnings, FitError, FitWarning};
pub use shards::{
    finish, FitCounts, FitEdges, FitFile, FitLabel, FitLogit, FitStats, STATS_FORMAT_VERSION,
};
pub use stats::{ClassHistogram, ClassMoments};

use stats::BinCounter;

/// Largest bin count of a head (the table stores bin counts as `u16`).
pub const MAX_BINS: usize = u16::MAX as usize;

/// The hyper-parameters of a fit.
///
/// # Parameters
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `bins_ml` | 22 | bins of the ML head's histograms | `1..=65535` |
/// | `lambda_ml` | 0.0055 | additive smoothing of the ML head | `(0, 1e6]` |
/// | `bins_map` | 17 | bins of the MAP head's histograms | `1..=65535` |
/// | `lambda_map` | 0.00012 | additive smoothing of the MAP head | `(0, 1e6]` |
/// | `edges` | `Linspace` | how bin edges are placed | `Linspace`, `Matlab` |
/// | `upper_tail` | `Zero` | likelihood above the last edge (recorded in the table) | `Zero`, `Clamp` |
/// | `bayes` | `Some(BayesParams::default())` | the Bayes head's bins and lambda; `None` fits none | see [`BayesParams`] |
///
/// The defaults are the authors' detection settings (DESIGN §1.1). Very large bin
/// counts may make the `f32` frequencies miss the table's sum tolerance, and are
/// refused by [`DynTable::new`]; they are far beyond any useful histogram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitParams {
    /// Bins of the ML histograms.
    pub bins_ml: usize,
    /// Smoothing lambda of the ML head.
    pub lambda_ml: f32,
    /// Bins of the MAP histograms.
    pub bins_map: usize,
    /// Smoothing lambda of the MAP head.
    pub lambda_map: f32,
    /// Edge placement.
    pub edges: EdgeMode,
    /// Upper-tail policy, recorded in the table's settings.
    pub upper_tail: UpperTail,
    /// The Bayes head's parameters, or `None` for a table without that head.
    pub bayes: Option<BayesParams>,
}

impl Default for FitParams {
    fn default() -> Self {
        Self {
            bins_ml: 22,
            lambda_ml: 0.0055,
            bins_map: 17,
            lambda_map: 0.00012,
            edges: EdgeMode::Linspace,
            upper_tail: UpperTail::Zero,
            bayes: Some(BayesParams::default()),
        }
    }
}

impl FitParams {
    /// Checks every parameter against its range.
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), FitError> {
        let bins = |name, v: usize| {
            if (1..=MAX_BINS).contains(&v) {
                Ok(())
            } else {
                Err(FitError::Param {
                    name,
                    value: v.to_string(),
                    expected: "an integer from 1 to 65535",
                })
            }
        };
        let lambda = |name, v: f32| {
            if v > 0.0 && v <= MAX_LAMBDA {
                Ok(())
            } else {
                Err(FitError::Param {
                    name,
                    value: v.to_string(),
                    expected: "a number in (0, 1e6]",
                })
            }
        };
        bins("bins_ml", self.bins_ml)?;
        bins("bins_map", self.bins_map)?;
        lambda("lambda_ml", self.lambda_ml)?;
        lambda("lambda_map", self.lambda_map)?;
        self.bayes.as_ref().map_or(Ok(()), BayesParams::validate)
    }

    /// The table settings these parameters give.
    pub fn settings(&self) -> Settings {
        Settings {
            lambda_ml: self.lambda_ml,
            lambda_map: self.lambda_map,
            edge_mode: self.edges,
            upper_tail: self.upper_tail,
        }
    }
}

/// The value `v_c` a row contributes, with its class: `x_c` of a row labelled `c`.
#[inline]
fn class_value(row: &Row<'_>) -> Option<(usize, f64)> {
    match row.label {
        Label::Class(c) => row.logits.get(c).map(|&x| (c, x)),
        Label::Background | Label::Missing => None,
    }
}

/// Refuses unlabelled sources.
fn require_labels(source: &impl RowSource) -> Result<(), FitError> {
    if source.has_labels() {
        Ok(())
    } else {
        Err(FitError::NoLabels {
            path: source.path().to_path_buf(),
        })
    }
}

/// Refuses classes without rows.
fn require_rows(path: &Path, moments: &[ClassMoments]) -> Result<(), FitError> {
    let empty: Vec<String> = moments
        .iter()
        .filter(|m| m.count() == 0)
        .map(|m| m.name().to_string())
        .collect();
    if empty.is_empty() {
        Ok(())
    } else {
        Err(FitError::EmptyClasses {
            path: path.to_path_buf(),
            classes: empty,
        })
    }
}

/// Pass (a) over a whole source: its [`FitStats`], checked for labels and rows.
fn pass_a(source: &impl RowSource) -> Result<FitStats, FitError> {
    require_labels(source)?;
    let mut stats = FitStats::new(source.classes());
    source.for_each_row(|row| {
        stats.push(&row);
        Ok::<(), FitError>(())
    })?;
    require_rows(source.path(), stats.moments())?;
    Ok(stats)
}

/// Pass 1 of [`fit`]: the moments of every class, in one streaming pass.
///
/// # Errors
///
/// [`FitError::Data`] for unreadable data, [`FitError::NoLabels`] for unlabelled data,
/// [`FitError::EmptyClasses`] when a class has no training rows.
pub fn class_moments(source: &impl RowSource) -> Result<Vec<ClassMoments>, FitError> {
    Ok(pass_a(source)?.moments().to_vec())
}

/// The axis of a histogram of `bins` bins over values in `[min, max]` (named `name` in
/// errors), placed by `edges`.
pub(crate) fn checked_axis(
    name: &str,
    min: f64,
    max: f64,
    bins: usize,
    edges: EdgeMode,
) -> Result<Axis, FitError> {
    if !((min as f32).is_finite() && (max as f32).is_finite()) {
        return Err(FitError::OutOfF32 {
            class: name.to_string(),
        });
    }
    let (lo, hi) = stats::range(min, max, bins, edges);
    Axis::new(lo, hi, bins).map_err(|_| FitError::Edges {
        class: name.to_string(),
        bins,
        lo,
        hi,
    })
}

/// A counter over the histogram range of class `m`.
fn counter_for(m: &ClassMoments, bins: usize, edges: EdgeMode) -> Result<BinCounter, FitError> {
    checked_axis(m.name(), m.min(), m.max(), bins, edges).map(BinCounter::from_axis)
}

/// Fits a table from `source` (a file, or rows in memory) in two streaming passes
/// (memory independent of the row count): pass (a) [`FitStats`], their
/// [`FitEdges`], pass (b) [`FitCounts`], and [`finish`], the code path of a fit
/// merged from shards.
///
/// # Errors
///
/// [`FitError::Param`] for parameters out of range; [`FitError::Data`],
/// [`FitError::NoLabels`] and [`FitError::EmptyClasses`] as [`class_moments`];
/// [`FitError::Edges`] or [`FitError::OutOfF32`] for classes whose statistics a table
/// cannot hold; [`FitError::Changed`] if the input changes between the passes.
pub fn fit(source: &impl RowSource, params: &FitParams) -> Result<DynTable, FitError> {
    params.validate()?;
    // The objectness feature is fitted from the rows held in memory (the statistics of
    // the two streaming passes do not hold the objectness).
    if params.bayes.is_some_and(|b| b.objectness) {
        return TrainingSet::read(source)?.fit(params);
    }
    let stats = pass_a(source)?;
    let edges = stats.edges(params)?;
    let mut counts = FitCounts::new(&edges);
    let mut outside = false;
    source.for_each_row(|row| {
        outside |= !counts.push(&row);
        Ok::<(), FitError>(())
    })?;
    let changed = || FitError::Changed {
        path: source.path().to_path_buf(),
    };
    if outside {
        return Err(changed());
    }
    finish(&stats, &counts).map_err(|e| match e {
        FitError::RowsDiffer { .. } | FitError::ClassRowsDiffer { .. } | FitError::EdgesDiffer => {
            changed()
        }
        e => e,
    })
}

/// The open head's temperature of a table no validation data has tuned (DESIGN §1.8).
pub const UNTUNED_TEMPERATURE: f32 = 1.0;
/// The open head's `epsilon` of a table no validation data has tuned: no unknown
/// category (DESIGN §1.8).
pub const UNTUNED_EPSILON: f32 = 0.0;

/// `table` with the Bayes head of `counts` smoothed by `lambda`, and the open head built
/// on it with the untuned parameters ([`UNTUNED_TEMPERATURE`], [`UNTUNED_EPSILON`]):
/// `tune` sets them from validation data.
///
/// # Errors
///
/// [`FitError::ClassTable`] (or [`FitError::Table`]) when the head breaks an invariant of §1.6 (e.g. a lambda out of
/// range, or counts for another number of classes).
pub fn with_bayes(
    table: DynTable,
    counts: &BayesCounts,
    lambda: f32,
) -> Result<DynTable, FitError> {
    let names: Vec<String> = table.class_names().map(str::to_string).collect();
    table
        .with_bayes(counts.spec(lambda))
        .and_then(|t| t.with_open(UNTUNED_TEMPERATURE, UNTUNED_EPSILON))
        .map_err(|e| table_error(e, |i| names.get(i).map_or("background", String::as_str)))
}

/// A table error, naming the class (`name` of its index) when it concerns one.
fn table_error<'a>(e: TableError, name: impl Fn(usize) -> &'a str) -> FitError {
    match error::class_index(&e) {
        Some(i) => FitError::ClassTable {
            class: name(usize::from(i)).to_string(),
            error: e,
        },
        None => FitError::Table(e),
    }
}

/// Assembles a table from per-class moments and the histograms of both heads (one of
/// each per class, in class order); provenance rows are the class counts.
///
/// # Errors
///
/// [`FitError::OutOfF32`] when a mean or variance does not fit in `f32`;
/// [`FitError::ClassTable`] (or [`FitError::Table`]) when the parts break another table invariant (mismatched bin
/// counts or class counts, invalid lambdas, ...).
pub fn build_table(
    moments: &[ClassMoments],
    ml: &[ClassHistogram],
    map: &[ClassHistogram],
    settings: Settings,
) -> Result<DynTable, FitError> {
    if ml.len() != moments.len() || map.len() != moments.len() {
        return Err(FitError::Table(TableError::ClassCount));
    }
    let mut specs = Vec::with_capacity(moments.len());
    for ((m, a), b) in moments.iter().zip(ml).zip(map) {
        let (mean, variance) = (m.mean() as f32, m.prior_variance() as f32);
        if !(mean.is_finite() && variance.is_finite()) {
            return Err(FitError::OutOfF32 {
                class: m.name().to_string(),
            });
        }
        specs.push(ClassSpec {
            name: m.name(),
            rows: m.count(),
            mean,
            variance,
            ml_range: (a.lo(), a.hi()),
            ml_freqs: a.frequencies(),
            map_range: (b.lo(), b.hi()),
            map_freqs: b.frequencies(),
        });
    }
    DynTable::new(settings, specs)
        .map_err(|e| table_error(e, |i| moments.get(i).map_or("", |m| m.name())))
}

/// The training values of every class, held in memory, for fitting many tables from
/// one read of the data (hyper-parameter tuning).
///
/// Memory: 4 bytes per labelled row (the values `v_c` as `f32`, sorted), plus the
/// moments. Histograms for a bin count cost `O(K B log n)` and never read the data.
#[derive(Debug, Clone)]
pub struct TrainingSet {
    path: PathBuf,
    moments: Vec<ClassMoments>,
    /// `v_c` of each class as `f32`, sorted ascending.
    values: Vec<Vec<f32>>,
    /// Extremes and category rows of the Bayes head.
    bayes: BayesMoments,
    /// Every labelled row's K logits as `f32`, row-major, and its category (K is
    /// background), for Bayes counts at any bin count.
    logits: Vec<f32>,
    categories: Vec<usize>,
    /// Every labelled row's objectness as `f32`, for the objectness feature.
    objectness: Vec<f32>,
}

impl TrainingSet {
    /// Reads `source` once: moments and values of every class.
    ///
    /// # Errors
    ///
    /// As [`class_moments`].
    pub fn read(source: &impl RowSource) -> Result<Self, FitError> {
        require_labels(source)?;
        let mut moments: Vec<ClassMoments> = source
            .classes()
            .iter()
            .map(|c| ClassMoments::new(c.as_str()))
            .collect();
        let mut values: Vec<Vec<f32>> = vec![Vec::new(); moments.len()];
        let mut bayes = BayesMoments::new(source.classes());
        let (mut logits, mut categories, mut objectness) = (Vec::new(), Vec::new(), Vec::new());
        let k = moments.len();
        source.for_each_row(|row| {
            if let Some((c, x)) = class_value(&row) {
                if let (Some(m), Some(v)) = (moments.get_mut(c), values.get_mut(c)) {
                    m.push(x);
                    v.push(x as f32);
                }
            }
            if let Some(c) = bayes::category(&row, k) {
                bayes.push(&row);
                categories.push(c);
                logits.extend(row.logits.iter().map(|&x| x as f32));
                objectness.push(row.objectness as f32);
            }
            Ok::<(), FitError>(())
        })?;
        require_rows(source.path(), &moments)?;
        for v in &mut values {
            v.sort_unstable_by(f32::total_cmp);
        }
        Ok(Self {
            path: source.path().to_path_buf(),
            moments,
            values,
            bayes,
            logits,
            categories,
            objectness,
        })
    }

    /// The Bayes head's counts with `bins` bins per logit (the same counts [`fit`]
    /// makes).
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] for a bin count out of `1..=65535`; [`FitError::Edges`] or
    /// [`FitError::OutOfF32`] for a logit whose range a table cannot hold.
    pub fn bayes_counts(&self, bins: usize) -> Result<BayesCounts, FitError> {
        BayesParams {
            bins,
            lambda: 1.0,
            objectness: false,
        }
        .validate()?;
        let mut counters = self.bayes.counters(bins)?;
        let k = self.moments.len();
        let no_id = None;
        for (logits, &c) in self.logits.chunks_exact(k.max(1)).zip(&self.categories) {
            let x: Vec<f64> = logits.iter().map(|&v| f64::from(v)).collect();
            let row = Row {
                index: 0,
                line: None,
                id: no_id,
                label: if c < k {
                    Label::Class(c)
                } else {
                    Label::Background
                },
                objectness: 1.0,
                logits: &x,
            };
            counters.add(&row);
        }
        counters
            .finish(self.bayes.category_rows())
            .ok_or(FitError::Changed {
                path: self.path.clone(),
            })
    }

    /// The Bayes head's counts with `bins` bins per logit and, with `objectness`, the
    /// objectness feature's (DESIGN §1.6): linspace bins over the finite objectness
    /// logits of every labelled row, each row counted in the bin of its objectness
    /// logit clamped into the axis (so objectness 0 and 1 count in the first and last
    /// bin), with the layer's own `objectness_logit`.
    ///
    /// # Errors
    ///
    /// As [`bayes_counts`](Self::bayes_counts); [`FitError::Objectness`] when no
    /// labelled row has an objectness strictly between 0 and 1.
    pub fn bayes_counts_with(
        &self,
        bins: usize,
        objectness: bool,
    ) -> Result<BayesCounts, FitError> {
        let counts = self.bayes_counts(bins)?;
        if !objectness {
            return Ok(counts);
        }
        let z: Vec<f32> = self
            .objectness
            .iter()
            .map(|&os| mlmap_core::objectness_logit(os))
            .collect();
        let finite = || z.iter().copied().filter(|v| v.is_finite());
        let (lo, hi) = (
            finite().fold(f32::INFINITY, f32::min),
            finite().fold(f32::NEG_INFINITY, f32::max),
        );
        if !(lo <= hi) {
            return Err(FitError::Objectness {
                reason: "every labelled row has an objectness of 0 or 1",
            });
        }
        let axis = checked_axis(
            "objectness",
            f64::from(lo),
            f64::from(hi),
            bins,
            EdgeMode::Linspace,
        )?;
        let rows = counts.rows().to_vec();
        let mut counters: Vec<BinCounter> =
            rows.iter().map(|_| BinCounter::from_axis(axis)).collect();
        for (&v, &c) in z.iter().zip(&self.categories) {
            if let Some(counter) = counters.get_mut(c) {
                counter.add(v.clamp(axis.lo(), axis.hi()));
            }
        }
        let mut all = Vec::with_capacity(rows.len() * bins);
        for (counter, &n) in counters.into_iter().zip(&rows) {
            let h = counter.finish();
            if h.total() != n {
                return Err(FitError::Changed {
                    path: self.path.clone(),
                });
            }
            all.extend_from_slice(h.counts());
        }
        Ok(counts.with_objectness((axis.lo(), axis.hi()), all))
    }

    /// The training input this set was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The moments of every class, in class order.
    pub fn moments(&self) -> &[ClassMoments] {
        &self.moments
    }

    /// The values `v_c` of class `class` as `f32`, sorted ascending.
    pub fn values(&self, class: usize) -> Option<&[f32]> {
        self.values.get(class).map(Vec::as_slice)
    }

    /// The histogram of every class with `bins` bins placed by `edges`.
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] for a bin count out of `1..=65535`; [`FitError::Edges`] or
    /// [`FitError::OutOfF32`] for a class whose range a table cannot hold.
    pub fn histograms(
        &self,
        bins: usize,
        edges: EdgeMode,
    ) -> Result<Vec<ClassHistogram>, FitError> {
        if !(1..=MAX_BINS).contains(&bins) {
            return Err(FitError::Param {
                name: "bins",
                value: bins.to_string(),
                expected: "an integer from 1 to 65535",
            });
        }
        self.moments
            .iter()
            .zip(&self.values)
            .map(|(m, v)| {
                let mut counter = counter_for(m, bins, edges)?;
                if counter.add_sorted(v) {
                    Ok(counter.finish())
                } else {
                    // Unreachable: the range covers every value by construction.
                    Err(FitError::Edges {
                        class: m.name().to_string(),
                        bins,
                        lo: m.min() as f32,
                        hi: m.max() as f32,
                    })
                }
            })
            .collect()
    }

    /// Fits a table with `params`; the same table as [`fit`] on the same data.
    ///
    /// # Errors
    ///
    /// As [`fit`], except for data errors (the data was read by
    /// [`TrainingSet::read`]).
    pub fn fit(&self, params: &FitParams) -> Result<DynTable, FitError> {
        params.validate()?;
        let ml = self.histograms(params.bins_ml, params.edges)?;
        let map = self.histograms(params.bins_map, params.edges)?;
        let table = build_table(&self.moments, &ml, &map, params.settings())?;
        match params.bayes {
            Some(p) => with_bayes(
                table,
                &self.bayes_counts_with(p.bins, p.objectness)?,
                p.lambda,
            ),
            None => Ok(table),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_authors_detection_settings() {
        let p = FitParams::default();
        assert_eq!((p.bins_ml, p.bins_map), (22, 17));
        assert_eq!((p.lambda_ml, p.lambda_map), (0.0055, 0.00012));
        assert_eq!(p.edges, EdgeMode::Linspace);
        assert_eq!(p.upper_tail, UpperTail::Zero);
        assert_eq!(p.validate(), Ok(()));
    }

    #[test]
    fn parameters_out_of_range_are_refused() {
        let bad = [
            FitParams {
                bins_ml: 0,
                ..FitParams::default()
            },
            FitParams {
                bins_map: 65536,
                ..FitParams::default()
            },
            FitParams {
                lambda_ml: 0.0,
                ..FitParams::default()
            },
            FitParams {
                lambda_map: f32::NAN,
                ..FitParams::default()
            },
            FitParams {
                lambda_map: 2e6,
                ..FitParams::default()
            },
        ];
        let names = [
            "bins_ml",
            "bins_map",
            "lambda_ml",
            "lambda_map",
            "lambda_map",
        ];
        for (p, want) in bad.iter().zip(names) {
            match p.validate() {
                Err(FitError::Param { name, .. }) => assert_eq!(name, want),
                other => panic!("{p:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn empty_classes_message_names_every_class_and_the_file() {
        let e = FitError::EmptyClasses {
            path: "t.csv".into(),
            classes: vec!["cyclist".into()],
        };
        assert_eq!(
            e.to_string(),
            "t.csv: class \"cyclist\" has no training rows (rows labelled with the class); \
             every class needs at least one"
        );
        let e = FitError::EmptyClasses {
            path: "t.csv".into(),
            classes: vec!["a".into(), "b".into()],
        };
        assert!(e
            .to_string()
            .contains("classes \"a\", \"b\" have no training rows"));
        assert!(e.is_bad_input());
    }
}
