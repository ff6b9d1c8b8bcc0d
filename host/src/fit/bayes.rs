//! Fitting the Bayes head (docs/DESIGN.md §1.6): per-logit axes over every training
//! row, and per category and logit the histogram counts of that category's rows.
//!
//! Categories are the K classes, then `background` when the training data has rows so
//! labelled (rows without a label are skipped). The counts are exact integers, so they
//! are the part a fit can accumulate and merge; the smoothing `lambda` enters only when
//! the log-terms `ln(count / n_c + lambda)` are written ([`BayesCounts::spec`]).

use crate::dataset::{Label, Row};
use crate::BayesSpec;
use mlmap_core::{Axis, EdgeMode, MAX_LAMBDA_BAYES};

use super::shards::FitLogit;
use super::stats::{lower, upper, BinCounter};
use super::{FitError, MAX_BINS};

/// The hyper-parameters of the Bayes head.
///
/// # Parameters
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `bins` | 22 | bins per logit | `1..=65535` |
/// | `lambda` | 0.001 | additive smoothing inside the logarithm | `(0, 1]` |
/// | `objectness` | false | the objectness feature: a histogram of the objectness logit per category (DESIGN §1.6) | |
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BayesParams {
    /// Bins per logit.
    pub bins: usize,
    /// Additive smoothing inside the logarithm.
    pub lambda: f32,
    /// Whether the categories also model the objectness logit.
    pub objectness: bool,
}

impl Default for BayesParams {
    fn default() -> Self {
        Self {
            bins: 22,
            lambda: 1e-3,
            objectness: false,
        }
    }
}

impl BayesParams {
    /// Checks both parameters against their ranges.
    ///
    /// # Errors
    ///
    /// [`FitError::Param`] naming the first parameter out of range.
    pub fn validate(&self) -> Result<(), FitError> {
        if !(1..=MAX_BINS).contains(&self.bins) {
            return Err(FitError::Param {
                name: "bins_bayes",
                value: self.bins.to_string(),
                expected: "an integer from 1 to 65535",
            });
        }
        if !(self.lambda > 0.0 && self.lambda <= MAX_LAMBDA_BAYES) {
            return Err(FitError::Param {
                name: "lambda_bayes",
                value: self.lambda.to_string(),
                expected: "a number in (0, 1]",
            });
        }
        Ok(())
    }
}

/// The category of a training row: its class, `K` for background, `None` unlabelled.
pub(crate) fn category(row: &Row<'_>, k: usize) -> Option<usize> {
    match row.label {
        Label::Class(c) => Some(c),
        Label::Background => Some(k),
        Label::Missing => None,
    }
}

/// Pass 1 of the Bayes fit: the extremes of every logit over all labelled rows, and the
/// rows per category. Exact and mergeable: [`merge`](Self::merge) of the statistics of
/// any split of the rows equals one pass over all of them.
#[derive(Debug, Clone, PartialEq)]
pub struct BayesMoments {
    /// The K class names (logit `j` is named after class `j` in messages).
    names: Vec<String>,
    /// Smallest value of logit `j` over every labelled row.
    min: Vec<f64>,
    /// Largest value of logit `j` over every labelled row.
    max: Vec<f64>,
    /// Rows per category: K classes, then background.
    rows: Vec<u64>,
}

impl BayesMoments {
    /// Empty statistics for `names` (the K class names).
    pub fn new<S: AsRef<str>>(names: &[S]) -> Self {
        Self {
            names: names.iter().map(|n| n.as_ref().to_string()).collect(),
            min: vec![f64::INFINITY; names.len()],
            max: vec![f64::NEG_INFINITY; names.len()],
            rows: vec![0; names.len() + 1],
        }
    }

    /// Adds one row.
    #[inline]
    pub fn push(&mut self, row: &Row<'_>) {
        let k = self.names.len();
        if let Some(c) = category(row, k) {
            if let Some(n) = self.rows.get_mut(c) {
                *n += 1;
            }
            for ((lo, hi), &x) in self.min.iter_mut().zip(&mut self.max).zip(row.logits) {
                *lo = lower(*lo, x);
                *hi = upper(*hi, x);
            }
        }
    }

    /// Adds one row of category `c` (a class, or K for background) with the logits
    /// `x`: the same as [`push`](Self::push) of such a row.
    #[inline]
    pub(crate) fn push_values<T: FitLogit>(&mut self, c: usize, x: &[T]) {
        if let Some(n) = self.rows.get_mut(c) {
            *n += 1;
        }
        for ((lo, hi), &v) in self.min.iter_mut().zip(&mut self.max).zip(x) {
            let v = v.to_f64();
            *lo = lower(*lo, v);
            *hi = upper(*hi, v);
        }
    }

    /// Adds the rows of `other`, statistics of the same classes.
    ///
    /// # Errors
    ///
    /// [`FitError::ClassesDiffer`] when `other` has other class names.
    pub fn merge(&mut self, other: &Self) -> Result<(), FitError> {
        if self.names != other.names {
            return Err(FitError::ClassesDiffer {
                ours: self.names.clone(),
                theirs: other.names.clone(),
            });
        }
        for (a, &b) in self.min.iter_mut().zip(&other.min) {
            *a = lower(*a, b);
        }
        for (a, &b) in self.max.iter_mut().zip(&other.max) {
            *a = upper(*a, b);
        }
        for (a, &b) in self.rows.iter_mut().zip(&other.rows) {
            *a = a.saturating_add(b);
        }
        Ok(())
    }

    /// Rows per category, with the background category only when it has rows.
    pub fn category_rows(&self) -> &[u64] {
        let k = self.names.len();
        match self.rows.get(k) {
            Some(0) => self.rows.get(..k).unwrap_or(&[]),
            _ => &self.rows,
        }
    }

    /// Smallest and largest value of each logit over the labelled rows (`+inf`,
    /// `-inf` when there are none).
    pub fn extremes(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.min.iter().copied().zip(self.max.iter().copied())
    }

    /// The axis of each logit with `bins` linspace bins.
    ///
    /// # Errors
    ///
    /// [`FitError::OutOfF32`] or [`FitError::Edges`] for a logit whose range a table
    /// cannot hold.
    pub(crate) fn axes(&self, bins: usize) -> Result<Vec<Axis>, FitError> {
        self.names
            .iter()
            .zip(self.extremes())
            .map(|(name, (lo, hi))| super::checked_axis(name, lo, hi, bins, EdgeMode::Linspace))
            .collect()
    }

    /// The counters of pass 2, one per category and logit, over the axes of `bins`
    /// linspace bins.
    ///
    /// # Errors
    ///
    /// As [`axes`](Self::axes).
    pub(crate) fn counters(&self, bins: usize) -> Result<BayesCounters, FitError> {
        Ok(BayesCounters::new(
            self.category_rows().len(),
            &self.axes(bins)?,
        ))
    }

    /// The serialized form: `(min, max, rows)`.
    pub(crate) fn to_parts(&self) -> (Vec<f64>, Vec<f64>, Vec<u64>) {
        (self.min.clone(), self.max.clone(), self.rows.clone())
    }

    /// The statistics of `names` from [`to_parts`](Self::to_parts); `None` when the
    /// parts do not fit the names.
    pub(crate) fn from_parts(
        names: &[String],
        min: Vec<f64>,
        max: Vec<f64>,
        rows: Vec<u64>,
    ) -> Option<Self> {
        let k = names.len();
        let ok = min.len() == k
            && max.len() == k
            && rows.len() == k + 1
            && min.iter().zip(&max).all(|(a, b)| {
                (a.is_finite() && b.is_finite() && a <= b)
                    || (*a == f64::INFINITY && *b == f64::NEG_INFINITY)
            });
        ok.then(|| Self {
            names: names.to_vec(),
            min,
            max,
            rows,
        })
    }
}

/// Pass 2 of the Bayes fit: the bin counts of every category and logit.
#[derive(Debug, Clone)]
pub(crate) struct BayesCounters {
    k: usize,
    categories: usize,
    /// Category-major: counter `c * K + j`.
    counters: Vec<BinCounter>,
}

impl BayesCounters {
    /// Counters for `categories` categories over `axes` (one per logit).
    pub(crate) fn new(categories: usize, axes: &[Axis]) -> Self {
        let mut counters = Vec::with_capacity(categories * axes.len());
        for _ in 0..categories {
            counters.extend(axes.iter().map(|&a| BinCounter::from_axis(a)));
        }
        Self {
            k: axes.len(),
            categories,
            counters,
        }
    }

    /// Counts one row; `false` when a value falls outside its axis, or the row is
    /// background and the axes were made without a background category.
    #[inline]
    pub(crate) fn add(&mut self, row: &Row<'_>) -> bool {
        let Some(c) = category(row, self.k) else {
            return true;
        };
        if c >= self.categories {
            return false;
        }
        let start = c * self.k;
        let mut inside = true;
        for (counter, &x) in self.counters.iter_mut().skip(start).zip(row.logits) {
            inside &= counter.add(x as f32);
        }
        inside
    }

    /// Counts one row of category `c` (a class, or K for background) with the logits
    /// `x`: the same as [`add`](Self::add) of such a row.
    #[inline]
    pub(crate) fn add_values<T: FitLogit>(&mut self, c: usize, x: &[T]) -> bool {
        if c >= self.categories {
            return false;
        }
        let start = c * self.k;
        let mut inside = true;
        for (counter, &v) in self.counters.iter_mut().skip(start).zip(x) {
            inside &= counter.add(v.to_f32());
        }
        inside
    }

    /// The counts of every counter, category-major.
    pub(crate) fn counts(&self) -> Vec<u64> {
        self.counters
            .iter()
            .flat_map(|c| c.counts().iter().copied())
            .collect()
    }

    /// Adds counts laid out as [`counts`](Self::counts); `false` when their number
    /// differs.
    pub(crate) fn add_counts(&mut self, counts: &[u64]) -> bool {
        let bins = self.counters.first().map_or(0, BinCounter::bins);
        if counts.len() != bins * self.counters.len() {
            return false;
        }
        self.counters
            .iter_mut()
            .zip(counts.chunks(bins.max(1)))
            .all(|(c, o)| c.add_counts(o))
    }

    /// The counts, checked against `rows`, the rows per category of pass 1.
    pub(crate) fn finish(self, rows: &[u64]) -> Option<BayesCounts> {
        if rows.len() != self.categories {
            return None;
        }
        let bins = self.counters.first().map_or(0, BinCounter::bins);
        let mut ranges = Vec::with_capacity(self.k);
        let mut counts = Vec::with_capacity(self.counters.len() * bins);
        for (i, counter) in self.counters.into_iter().enumerate() {
            let h = counter.finish();
            if i < self.k {
                ranges.push((h.lo(), h.hi()));
            }
            if h.total() != *rows.get(i / self.k.max(1))? {
                return None;
            }
            counts.extend_from_slice(h.counts());
        }
        Some(BayesCounts {
            k: self.k,
            bins,
            ranges,
            rows: rows.to_vec(),
            counts,
            objectness: None,
        })
    }
}

/// The fitted counts of a Bayes head: everything but the smoothing.
#[derive(Debug, Clone, PartialEq)]
pub struct BayesCounts {
    k: usize,
    bins: usize,
    ranges: Vec<(f32, f32)>,
    rows: Vec<u64>,
    /// Category-major: the `B` counts of category `c`, logit `j` start at `(c K + j) B`.
    counts: Vec<u64>,
    /// The objectness feature: its axis's first and last edge, and the `B` counts of
    /// each category (category-major).
    objectness: Option<((f32, f32), Vec<u64>)>,
}

impl BayesCounts {
    /// Bins per logit.
    pub fn bins(&self) -> usize {
        self.bins
    }

    /// Rows per category (K classes, then background if present).
    pub fn rows(&self) -> &[u64] {
        &self.rows
    }

    /// First and last edge of each logit's bins.
    pub fn ranges(&self) -> &[(f32, f32)] {
        &self.ranges
    }

    /// The counts, category-major.
    pub fn counts(&self) -> &[u64] {
        &self.counts
    }

    /// The objectness feature's axis range and counts (category-major), when fitted.
    pub fn objectness(&self) -> Option<((f32, f32), &[u64])> {
        self.objectness.as_ref().map(|(r, c)| (*r, c.as_slice()))
    }

    /// The same counts with the objectness feature's.
    pub(crate) fn with_objectness(mut self, range: (f32, f32), counts: Vec<u64>) -> Self {
        self.objectness = Some((range, counts));
        self
    }

    /// The head with smoothing `lambda`: log-terms `ln(count / n_c + lambda)` computed
    /// in `f64` and rounded to `f32`, in the table's logit-major order (logit, bin,
    /// category).
    pub fn spec(&self, lambda: f32) -> BayesSpec {
        let lambda64 = f64::from(lambda);
        let (k, bins, cats) = (self.k, self.bins, self.rows.len());
        let mut terms = Vec::with_capacity(self.counts.len());
        for j in 0..k {
            for b in 0..bins {
                for (c, &n) in self.rows.iter().enumerate() {
                    let count = self
                        .counts
                        .get((c * k + j) * bins + b)
                        .copied()
                        .unwrap_or(0);
                    terms.push((count as f64 / n.max(1) as f64 + lambda64).ln() as f32);
                }
            }
        }
        debug_assert_eq!(terms.len(), k * bins * cats);
        // The objectness feature: bin-major, then category.
        let objectness = self.objectness.as_ref().map(|(range, counts)| {
            let mut t = Vec::with_capacity(bins * cats);
            for b in 0..bins {
                for (c, &n) in self.rows.iter().enumerate() {
                    let count = counts.get(c * bins + b).copied().unwrap_or(0);
                    t.push((count as f64 / n.max(1) as f64 + lambda64).ln() as f32);
                }
            }
            (*range, t)
        });
        BayesSpec {
            lambda,
            rows: self.rows.clone(),
            ranges: self.ranges.clone(),
            terms,
            objectness,
        }
    }
}
