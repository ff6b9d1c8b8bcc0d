//! Per-class statistics of a fit: moments (pass 1) and histogram counts (pass 2).

use mlmap_core::{Axis, EdgeMode, VARIANCE_FLOOR};

use super::binpicker;
use super::exact::{self, F32Sums, Fixed, Sums};

/// The exact state of a [`ClassMoments`] in canonical form (the serialized form).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub(crate) struct MomentParts {
    pub(crate) count: u64,
    pub(crate) min: f64,
    pub(crate) max: f64,
    pub(crate) non_finite: bool,
    pub(crate) sum: (u32, Vec<i64>),
    pub(crate) squares: (u32, Vec<i64>),
}

/// The smaller of two logits in IEEE 754's total order (`-0.0 < +0.0`), so that the
/// extremes, and the edges and table bytes they give, do not depend on the order in which
/// rows or shards arrive (`f64::min` may return either zero).
#[inline]
pub(crate) fn lower(a: f64, b: f64) -> f64 {
    if b.total_cmp(&a).is_lt() {
        b
    } else {
        a
    }
}

/// The larger of two logits in IEEE 754's total order (see [`lower`]).
#[inline]
pub(crate) fn upper(a: f64, b: f64) -> f64 {
    if b.total_cmp(&a).is_gt() {
        b
    } else {
        a
    }
}

/// Count, extremes, mean and variance of one class's training logits `v_c`
/// (DESIGN §1.1), accumulated one value at a time, and mergeable.
///
/// The state is exact: the count, the extremes, and the **exact** sum and sum of
/// squares of the values (fixed-point accumulators, no rounding). So it does not depend
/// on the order of the values, [`merge`](Self::merge) of the statistics of any split of
/// the values gives the same state as one pass over all of them, and the mean and
/// variance are a deterministic function of it: each the exact rational
/// (`S1 / n`, `(n S2 - S1^2) / (n (n - 1))`) rounded once to `f64`, so no cancellation
/// however large the mean is compared with the spread.
///
/// ```
/// use mlmap_host::fit::ClassMoments;
///
/// let (mut all, mut a, mut b) = (ClassMoments::new("car"), ClassMoments::new("car"), ClassMoments::new("car"));
/// for x in [1e9, 1e9 + 1.0, 1e9 + 2.0] {
///     all.push(x);
/// }
/// a.push(1e9 + 2.0);
/// b.push(1e9);
/// b.push(1e9 + 1.0);
/// a.merge(&b);
/// assert_eq!(a, all);
/// assert_eq!((all.mean(), all.sample_variance()), (1e9 + 1.0, 1.0));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ClassMoments {
    name: String,
    count: u64,
    min: f64,
    max: f64,
    /// Whether a NaN or infinite value was pushed (the mean and variance are then NaN).
    non_finite: bool,
    /// Exact sums of the values and of their squares.
    sums: std::boxed::Box<Sums>,
}

impl ClassMoments {
    /// Empty statistics of the class `name`.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            count: 0,
            min: f64::INFINITY,
            max: f64::NEG_INFINITY,
            non_finite: false,
            sums: std::boxed::Box::default(),
        }
    }

    /// Adds one value (finite, as every logit of a [`DataSource`](crate::dataset::DataSource);
    /// a NaN or infinite value makes the mean and variance NaN).
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        self.min = lower(self.min, x);
        self.max = upper(self.max, x);
        match exact::split(x) {
            Some((negative, m, pos)) => self.sums.add(negative, m, pos),
            None => self.non_finite = true,
        }
    }

    /// Adds a value that is an `f32`: the same state as [`push`](Self::push) of it as
    /// an `f64` once `sums` is flushed into these statistics
    /// ([`flush_f32`](Self::flush_f32)).
    #[inline]
    pub(crate) fn push_f32(&mut self, x: f32, sums: &mut F32Sums) {
        let wide = f64::from(x);
        self.count += 1;
        self.min = lower(self.min, wide);
        self.max = upper(self.max, wide);
        if !sums.add(x) {
            self.non_finite = true;
        }
    }

    /// Moves the sums of values pushed by [`push_f32`](Self::push_f32) here.
    pub(crate) fn flush_f32(&mut self, sums: &mut F32Sums) {
        sums.flush_into(&mut self.sums);
    }

    /// Adds the values of `other` (its name is not checked): the same state as pushing
    /// them one by one.
    pub fn merge(&mut self, other: &Self) {
        self.count = self.count.saturating_add(other.count);
        self.min = lower(self.min, other.min);
        self.max = upper(self.max, other.max);
        self.non_finite |= other.non_finite;
        self.sums.merge(&other.sums);
    }

    /// The exact state in canonical form, for serialization.
    pub(crate) fn to_parts(&self) -> MomentParts {
        let (sum, squares) = self.sums.exact();
        MomentParts {
            count: self.count,
            min: self.min,
            max: self.max,
            non_finite: self.non_finite,
            sum: sum.to_words(),
            squares: squares.to_words(),
        }
    }

    /// The statistics of class `name` from [`to_parts`](Self::to_parts); `None` when
    /// the parts are inconsistent.
    pub(crate) fn from_parts(name: String, p: &MomentParts) -> Option<Self> {
        let empty = p.count == 0;
        let extremes_ok = if empty {
            p.min == f64::INFINITY && p.max == f64::NEG_INFINITY
        } else {
            !(p.min.is_nan() || p.max.is_nan()) && p.min <= p.max
        };
        if !extremes_ok || (empty && (!p.sum.1.is_empty() || !p.squares.1.is_empty())) {
            return None;
        }
        Some(Self {
            name,
            count: p.count,
            min: p.min,
            max: p.max,
            non_finite: p.non_finite,
            sums: std::boxed::Box::new(Sums::from_exact(
                Fixed::from_words(p.sum.0, &p.sum.1)?,
                Fixed::from_words(p.squares.0, &p.squares.1)?,
            )),
        })
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

    /// Mean of the values (0 when empty): the exact mean rounded to `f64`.
    pub fn mean(&self) -> f64 {
        if self.non_finite {
            return f64::NAN;
        }
        exact::mean(self.count, &self.sums.exact().0)
    }

    /// Sample variance (`ddof = 1`, as MATLAB's `fitdist(x, 'Normal')`); 0 with fewer
    /// than 2 values. The exact variance of the values rounded to `f64`.
    pub fn sample_variance(&self) -> f64 {
        if self.non_finite {
            return f64::NAN;
        }
        let (sum, squares) = self.sums.exact();
        exact::sample_variance(self.count, &sum, &squares)
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
    ///   the `binpicker` rule in [`crate::fit`]).
    ///
    /// Rounding to `f32` is monotonic, so every training value, rounded to `f32`,
    /// lies in the returned range.
    pub fn range(&self, bins: usize, edges: EdgeMode) -> (f32, f32) {
        range(self.min, self.max, bins, edges)
    }
}

/// The outer edges of a histogram of values in `[min, max]` (see
/// [`ClassMoments::range`]).
pub(crate) fn range(min: f64, max: f64, bins: usize, edges: EdgeMode) -> (f32, f32) {
    match edges {
        EdgeMode::Linspace => {
            let (lo, hi) = (min as f32, max as f32);
            if lo < hi {
                (lo, hi)
            } else {
                ((min - 0.5) as f32, (max + 0.5) as f32)
            }
        }
        EdgeMode::Matlab => {
            let p = binpicker::pick(min, max, bins);
            (p.left as f32, p.right as f32)
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
    #[cfg(test)]
    pub(crate) fn new(lo: f32, hi: f32, bins: usize) -> Option<Self> {
        Some(Self::from_axis(Axis::new(lo, hi, bins).ok()?))
    }

    /// A counter over the bins of `axis`.
    pub(crate) fn from_axis(axis: Axis) -> Self {
        Self {
            shape: axis,
            counts: vec![0; axis.bins()],
        }
    }

    /// Number of bins.
    pub(crate) fn bins(&self) -> usize {
        self.counts.len()
    }

    /// The counts so far.
    pub(crate) fn counts(&self) -> &[u64] {
        &self.counts
    }

    /// Adds counts of the same bins; `false` (and nothing added) when their number
    /// differs.
    pub(crate) fn add_counts(&mut self, counts: &[u64]) -> bool {
        if counts.len() != self.counts.len() {
            return false;
        }
        for (c, &o) in self.counts.iter_mut().zip(counts) {
            *c = c.saturating_add(o);
        }
        true
    }

    /// Counts `x`; `false` when it is outside `[lo, hi]`.
    ///
    /// The bin is the one the layer looks `x` up in ([`Axis::bin`], the lookup of
    /// [`Histogram::bin`](mlmap_core::Histogram::bin)).
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
    fn variance_is_exact_far_from_zero() {
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
            counts: vec![1, 0, 3],
        };
        assert_eq!(h.frequencies(), vec![0.25, 0.0, 0.75]);
        assert_eq!(h.total(), 4);
    }
}
