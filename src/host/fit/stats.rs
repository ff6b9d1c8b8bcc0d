//! Per-class statistics of a fit: moments (pass 1) and histogram counts (pass 2).

use std::string::String;
use std::vec::Vec;

use crate::{Axis, EdgeMode, VARIANCE_FLOOR};

use super::binpicker;

/// Count, extremes, mean and variance of one class's training logits `v_c`
/// (DESIGN §1.1), accumulated in `f64` one value at a time.
///
/// The mean and variance are updated with Welford's method, which stays accurate
/// when the mean is large compared with the spread (no `sum x^2 - n mean^2`
/// cancellation).
#[derive(Debug, Clone, PartialEq)]
pub struct ClassMoments {
    name: String,
    count: u64,
    min: f64,
    max: f64,
    mean: f64,
    /// Sum of squared deviations from the running mean.
    m2: f64,
}

impl ClassMoments {
    /// Empty statistics of the class `name`.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            count: 0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            mean: 0.0,
            m2: 0.0,
        }
    }

    /// Adds one value (finite, as every logit of a [`DataSource`](crate::host::dataset::DataSource)).
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        self.min = self.min.min(x);
        self.max = self.max.max(x);
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// The class name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of values `|v_c|` (training rows of the class).
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Smallest value (`+inf` when empty).
    pub fn min(&self) -> f64 {
        self.min
    }

    /// Largest value (`-inf` when empty).
    pub fn max(&self) -> f64 {
        self.max
    }

    /// Mean of the values (0 when empty).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Sample variance (`ddof = 1`, as MATLAB's `fitdist(x, 'Normal')`); 0 with fewer
    /// than 2 values.
    pub fn sample_variance(&self) -> f64 {
        if self.count < 2 {
            0.0
        } else {
            self.m2 / (self.count - 1) as f64
        }
    }

    /// The variance written to the table: [`sample_variance`](Self::sample_variance)
    /// floored to [`VARIANCE_FLOOR`], so that a constant class, or a class with a single
    /// row, still has a valid (very narrow) prior.
    pub fn prior_variance(&self) -> f64 {
        self.sample_variance().max(VARIANCE_FLOOR)
    }

    /// The outer edges `(e_0, e_B)` of this class's histogram with `bins` bins, as
    /// stored in the table (`f32`).
    ///
    /// * [`EdgeMode::Linspace`]: `[min, max]`. When the range is empty in `f32` (all
    ///   values equal, or equal after rounding to `f32`), it is widened to
    ///   `[min - 0.5, max + 0.5]`, so the values sit in the middle of the range.
    /// * [`EdgeMode::Matlab`]: the first and last edges of MATLAB's bin picker (see
    ///   the `binpicker` rule in [`crate::host::fit`]).
    ///
    /// Rounding to `f32` is monotonic, so every training value, rounded to `f32`,
    /// lies in the returned range.
    pub fn range(&self, bins: usize, edges: EdgeMode) -> (f32, f32) {
        match edges {
            EdgeMode::Linspace => {
                let (lo, hi) = (self.min as f32, self.max as f32);
                if lo < hi {
                    (lo, hi)
                } else {
                    ((self.min - 0.5) as f32, (self.max + 0.5) as f32)
                }
            }
            EdgeMode::Matlab => {
                let p = binpicker::pick(self.min, self.max, bins);
                (p.left as f32, p.right as f32)
            }
        }
    }
}

/// The histogram of one class: outer edges and bin counts.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassHistogram {
    lo: f32,
    hi: f32,
    counts: Vec<u64>,
}

impl ClassHistogram {
    /// First edge `e_0`.
    pub fn lo(&self) -> f32 {
        self.lo
    }

    /// Last edge `e_B`.
    pub fn hi(&self) -> f32 {
        self.hi
    }

    /// Number of values in each bin.
    pub fn counts(&self) -> &[u64] {
        &self.counts
    }

    /// Number of bins `B`.
    pub fn bins(&self) -> usize {
        self.counts.len()
    }

    /// Number of values counted.
    pub fn total(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Frequencies `count_k / total` (they sum to 1; all 0 when empty), computed in
    /// `f64` and rounded to `f32`.
    pub fn frequencies(&self) -> Vec<f32> {
        let n = self.total() as f64;
        self.counts
            .iter()
            .map(|&c| if n > 0.0 { (c as f64 / n) as f32 } else { 0.0 })
            .collect()
    }
}

/// Counts values into the bins of a table histogram, with the layer's own `f32` edges
/// and bin rule ([`Histogram::bin`]), so that every training value is counted in the
/// bin the device will look it up in.
///
#[derive(Debug, Clone)]
pub(crate) struct BinCounter {
    shape: Axis,
    counts: Vec<u64>,
}

impl BinCounter {
    /// A counter over `[lo, hi]` with `bins` bins, or `None` when those edges are not
    /// valid for a table (not finite, or inner edges not strictly increasing in `f32`).
    pub(crate) fn new(lo: f32, hi: f32, bins: usize) -> Option<Self> {
        Some(Self {
            shape: Axis::new(lo, hi, bins).ok()?,
            counts: std::vec![0; bins],
        })
    }

    /// Number of bins.
    pub(crate) fn bins(&self) -> usize {
        self.counts.len()
    }

    /// Counts `x`; `false` when it is outside `[lo, hi]`.
    ///
    /// The bin is the one the layer looks `x` up in ([`Axis::bin`], the lookup of
    /// [`Histogram::bin`](crate::Histogram::bin)).
    #[inline]
    pub(crate) fn add(&mut self, x: f32) -> bool {
        let Some(k) = self.shape.bin(x) else {
            return false;
        };
        match self.counts.get_mut(k) {
            Some(c) => {
                *c += 1;
                true
            }
            None => false,
        }
    }

    /// Counts a slice sorted in ascending order (by `f32::total_cmp`) with one binary
    /// search per edge: the same counts as [`BinCounter::add`] on every value, in
    /// `O(B log n)`. Returns `false` if a value is outside `[lo, hi]`.
    pub(crate) fn add_sorted(&mut self, sorted: &[f32]) -> bool {
        let below = |e: f32| sorted.partition_point(|&v| v < e);
        let n = sorted.len();
        if below(self.shape.lo()) != 0 || sorted.partition_point(|&v| v <= self.shape.hi()) != n {
            return false;
        }
        let bins = self.counts.len();
        let mut start = 0;
        for (k, c) in self.counts.iter_mut().enumerate() {
            // Bin k is [e_k, e_{k+1}); the last one is closed, and ends after every value.
            let end = if k + 1 == bins {
                n
            } else {
                below(self.shape.edge(k + 1))
            };
            *c += (end - start) as u64;
            start = end;
        }
        true
    }

    pub(crate) fn finish(self) -> ClassHistogram {
        ClassHistogram {
            lo: self.shape.lo(),
            hi: self.shape.hi(),
            counts: self.counts,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moments_match_numpy() {
        // numpy 2.4: v = [4.3536, 2.4027, 5.1, -0.25, 3.0]
        // v.mean() = 2.9212599999999997, v.var(ddof=1) = 4.282625077999999
        let mut m = ClassMoments::new("car");
        for x in [4.3536, 2.4027, 5.1, -0.25, 3.0] {
            m.push(x);
        }
        assert_eq!(m.count(), 5);
        assert_eq!((m.min(), m.max()), (-0.25, 5.1));
        assert!((m.mean() - 2.92126).abs() < 1e-14, "{}", m.mean());
        let var = 4.282_625_077_999_999;
        assert!((m.sample_variance() - var).abs() < 1e-13 * var);
    }

    #[test]
    fn variance_floor_for_constant_and_single_values() {
        let mut m = ClassMoments::new("a");
        m.push(2.0);
        assert_eq!(m.sample_variance(), 0.0);
        assert_eq!(m.prior_variance(), VARIANCE_FLOOR);
        m.push(2.0);
        assert_eq!(m.sample_variance(), 0.0);
        assert_eq!(m.prior_variance(), VARIANCE_FLOOR);
    }

    #[test]
    fn welford_is_stable_far_from_zero() {
        // Values 1e9 + {0, 1, 2}: sample variance exactly 1.
        let mut m = ClassMoments::new("a");
        for x in [1e9, 1e9 + 1.0, 1e9 + 2.0] {
            m.push(x);
        }
        assert_eq!(m.sample_variance(), 1.0);
    }

    #[test]
    fn linspace_range_widens_empty_ranges() {
        let mut m = ClassMoments::new("a");
        m.push(2.0);
        assert_eq!(m.range(5, EdgeMode::Linspace), (1.5, 2.5));
        // Distinct in f64, equal in f32.
        m.push(2.0 + 1e-12);
        assert_eq!(m.range(5, EdgeMode::Linspace), (1.5, 2.5));
        m.push(-1.25);
        assert_eq!(m.range(5, EdgeMode::Linspace), (-1.25, 2.0));
    }

    #[test]
    fn sorted_counting_equals_bin_by_bin_counting() {
        // A deterministic spread of values including every edge of the histogram.
        let (lo, hi, bins) = (-3.7f32, 9.1f32, 22usize);
        let mut values: Vec<f32> = (0..5000)
            .map(|i| lo + (hi - lo) * ((i as f32 * 0.618_034) % 1.0))
            .collect();
        let probe = BinCounter::new(lo, hi, bins).unwrap();
        for k in 0..=bins {
            values.push(probe.shape.edge(k));
            values.push(probe.shape.edge(k).next_up().min(hi));
            values.push(probe.shape.edge(k).next_down().max(lo));
        }
        let mut one_by_one = BinCounter::new(lo, hi, bins).unwrap();
        for &v in &values {
            assert!(one_by_one.add(v), "{v}");
        }
        values.sort_unstable_by(f32::total_cmp);
        let mut sorted = BinCounter::new(lo, hi, bins).unwrap();
        assert!(sorted.add_sorted(&values));
        assert_eq!(sorted.finish(), one_by_one.finish());
    }

    #[test]
    fn values_outside_the_range_are_refused() {
        let mut c = BinCounter::new(0.0, 1.0, 4).unwrap();
        assert!(!c.add(1.5));
        assert!(!c.add(-0.1));
        assert!(!c.add_sorted(&[0.5, 2.0]));
        assert!(BinCounter::new(1.0, 1.0, 4).is_none());
        assert!(BinCounter::new(0.0, 1.0, 0).is_none());
    }

    #[test]
    fn frequencies_are_counts_over_total() {
        let h = ClassHistogram {
            lo: 0.0,
            hi: 1.0,
            counts: std::vec![1, 0, 3],
        };
        assert_eq!(h.frequencies(), std::vec![0.25, 0.0, 0.75]);
        assert_eq!(h.total(), 4);
    }
}
