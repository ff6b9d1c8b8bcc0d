//! Fitting the Bayes head (docs/DESIGN.md §1.6): per-logit axes over every training
//! row, and per category and logit the histogram counts of that category's rows.
//!
//! Categories are the K classes, then `background` when the training data has rows so
//! labelled (rows without a label are skipped). The counts are exact integers, so they
//! are the part a fit can accumulate and merge; the smoothing `lambda` enters only when
//! the log-terms `ln(count / n_c + lambda)` are written ([`BayesCounts::spec`]).

use std::string::ToString;
use std::vec::Vec;

use crate::host::dataset::{Label, Row};
use crate::host::BayesSpec;
use crate::{EdgeMode, MAX_LAMBDA_BAYES};

use super::stats::{BinCounter, ClassMoments};
use super::{FitError, MAX_BINS};

/// The hyper-parameters of the Bayes head.
///
/// # Parameters
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `bins` | 22 | bins per logit | `1..=65535` |
/// | `lambda` | 0.001 | additive smoothing inside the logarithm | `(0, 1]` |
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BayesParams {
    /// Bins per logit.
    pub bins: usize,
    /// Additive smoothing inside the logarithm.
    pub lambda: f32,
}

impl Default for BayesParams {
    fn default() -> Self {
        Self {
            bins: 22,
            lambda: 1e-3,
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
/// rows per category.
#[derive(Debug, Clone, PartialEq)]
pub struct BayesMoments {
    /// Moments of logit `j` over every labelled row (only the extremes are used).
    logits: Vec<ClassMoments>,
    /// Rows per category: K classes, then background.
    rows: Vec<u64>,
}

impl BayesMoments {
    /// Empty statistics for `names` (the K class names).
    pub fn new<S: AsRef<str>>(names: &[S]) -> Self {
        Self {
            logits: names
                .iter()
                .map(|n| ClassMoments::new(n.as_ref()))
                .collect(),
            rows: std::vec![0; names.len() + 1],
        }
    }

    /// Adds one row.
    pub fn push(&mut self, row: &Row<'_>) {
        let k = self.logits.len();
        if let Some(c) = category(row, k) {
            if let Some(n) = self.rows.get_mut(c) {
                *n += 1;
            }
            for (m, &x) in self.logits.iter_mut().zip(row.logits) {
                m.push(x);
            }
        }
    }

    /// Rows per category, with the background category only when it has rows.
    pub fn category_rows(&self) -> &[u64] {
        let k = self.logits.len();
        match self.rows.get(k) {
            Some(0) => self.rows.get(..k).unwrap_or(&[]),
            _ => &self.rows,
        }
    }

    /// The counters of pass 2, one per category and logit, over the axes of `bins`
    /// linspace bins.
    ///
    /// # Errors
    ///
    /// [`FitError::OutOfF32`] or [`FitError::Edges`] for a logit whose range a table
    /// cannot hold.
    pub(crate) fn counters(&self, bins: usize) -> Result<BayesCounters, FitError> {
        let mut axes = Vec::with_capacity(self.logits.len());
        for m in &self.logits {
            axes.push(super::counter_for(m, bins, EdgeMode::Linspace)?);
        }
        let categories = self.category_rows().len();
        let mut counters = Vec::with_capacity(categories * axes.len());
        for _ in 0..categories {
            counters.extend(axes.iter().cloned());
        }
        Ok(BayesCounters {
            k: self.logits.len(),
            rows: self.category_rows().to_vec(),
            counters,
        })
    }
}

/// Pass 2 of the Bayes fit: the bin counts of every category and logit.
#[derive(Debug, Clone)]
pub(crate) struct BayesCounters {
    k: usize,
    rows: Vec<u64>,
    /// Category-major: counter `c * K + j`.
    counters: Vec<BinCounter>,
}

impl BayesCounters {
    /// Counts one row; `false` when a value falls outside its axis (the data changed
    /// since pass 1).
    pub(crate) fn add(&mut self, row: &Row<'_>) -> bool {
        let Some(c) = category(row, self.k) else {
            return true;
        };
        if c >= self.rows.len() {
            // A background row that pass 1 did not see.
            return false;
        }
        let start = c * self.k;
        let mut inside = true;
        for (counter, &x) in self.counters.iter_mut().skip(start).zip(row.logits) {
            inside &= counter.add(x as f32);
        }
        inside
    }

    /// The counts, checked against the rows of pass 1.
    pub(crate) fn finish(self) -> Option<BayesCounts> {
        let bins = self.counters.first().map_or(0, BinCounter::bins);
        let mut ranges = Vec::with_capacity(self.k);
        let mut counts = Vec::with_capacity(self.counters.len() * bins);
        for (i, counter) in self.counters.into_iter().enumerate() {
            let h = counter.finish();
            if i < self.k {
                ranges.push((h.lo(), h.hi()));
            }
            if h.total() != *self.rows.get(i / self.k)? {
                return None;
            }
            counts.extend_from_slice(h.counts());
        }
        Some(BayesCounts {
            k: self.k,
            bins,
            ranges,
            rows: self.rows,
            counts,
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
        BayesSpec {
            lambda,
            rows: self.rows.clone(),
            ranges: self.ranges.clone(),
            terms,
        }
    }
}
