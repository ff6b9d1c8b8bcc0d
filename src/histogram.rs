//! The likelihood: a normalised histogram of one class's training logits (DESIGN §1.1,
//! §1.2; paper §III-B).
//!
//! A histogram with `B` bins stores its two outer edges `lo = e_0` and `hi = e_B` and the
//! `B` bin frequencies. Both edge modes of DESIGN §1.1 (numpy's `linspace` and MATLAB's
//! bin picker) give equal-width bins, so the inner edges are defined, exactly and in
//! `f32`, by
//!
//! ```text
//! w   = (hi - lo) / B                    (one f32 division)
//! e_k = lo + k * w        for 0 < k < B  (one f32 multiplication, one f32 addition)
//! ```
//!
//! (no fused multiply-add). Bin `k` is `[e_k, e_{k+1})`, the last bin is closed
//! (`[e_{B-1}, e_B]`), as in `numpy.histogram`. Lookup is O(1): an index estimated by one
//! multiplication and corrected against the true edges, so values on an edge land in the
//! bin the edge opens, whatever the rounding of the estimate.

/// Largest allowed deviation of a histogram's frequency sum from 1.
pub const FREQUENCY_SUM_TOLERANCE: f32 = 1e-4;

/// What a histogram answers for a logit above its last edge `e_B` (DESIGN §1.2).
///
/// Logits below the first edge always get likelihood 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum UpperTail {
    /// The paper's behaviour: a logit never seen in training carries no likelihood.
    #[default]
    Zero,
    /// Logits above `e_B` (`+inf` included) use the last bin's frequency.
    Clamp,
}

/// How the fit placed the bin edges (recorded in the table, informational for the layer).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum EdgeMode {
    /// `B` equal bins over `[min, max]` of the training logits, as `numpy.histogram`.
    #[default]
    Linspace,
    /// The edges MATLAB's `histogram(x, nbins)` picks (round bin width and left edge).
    Matlab,
}

/// A histogram that does not satisfy the table invariants.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HistogramError {
    /// Edges not finite, `lo >= hi`, or inner edges not strictly increasing in `f32`;
    /// also a bin count of 0 or above `u16::MAX`.
    Edges,
    /// A frequency is negative or not finite, or the sum is not 1 within
    /// [`FREQUENCY_SUM_TOLERANCE`].
    Frequencies,
}

/// A validated normalised histogram over equal-width bins.
///
/// `F` holds the `B` frequencies: `[f32; B]` in a [`Table`](crate::Table), `Vec<f32>` on
/// the host. Fields are private and only set after validation, so every `Histogram`
/// satisfies DESIGN §1.3 (5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Histogram<F> {
    pub(crate) lo: f32,
    pub(crate) hi: f32,
    /// `(hi - lo) / B`, the `w` of the module docs.
    pub(crate) width: f32,
    /// `B / (hi - lo)`, used only to estimate a bin index.
    pub(crate) inv_width: f32,
    pub(crate) freqs: F,
}

impl<F: AsRef<[f32]>> Histogram<F> {
    /// Validates and builds a histogram from its outer edges and frequencies.
    ///
    /// # Errors
    ///
    /// [`HistogramError::Edges`] when the edges are not finite or give inner edges that
    /// are not strictly increasing; [`HistogramError::Frequencies`] when a frequency is
    /// negative or not finite or they do not sum to 1 within
    /// [`FREQUENCY_SUM_TOLERANCE`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn new(lo: f32, hi: f32, freqs: F) -> Result<Self, HistogramError> {
        let n = freqs.as_ref().len();
        if n == 0 || n > usize::from(u16::MAX) {
            return Err(HistogramError::Edges);
        }
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(HistogramError::Edges);
        }
        let span = hi - lo;
        let bins = n as f32;
        let width = span / bins;
        let inv_width = bins / span;
        let finite_positive = |v: f32| v.is_finite() && v > 0.0;
        if !(finite_positive(span) && finite_positive(width) && finite_positive(inv_width)) {
            return Err(HistogramError::Edges);
        }
        let h = Self {
            lo,
            hi,
            width,
            inv_width,
            freqs,
        };
        let mut prev = lo;
        for k in 1..=n {
            let e = h.edge(k);
            if !(e > prev) {
                return Err(HistogramError::Edges);
            }
            prev = e;
        }
        let mut sum = 0.0f32;
        for &f in h.freqs.as_ref() {
            if !(f.is_finite() && f >= 0.0) {
                return Err(HistogramError::Frequencies);
            }
            sum += f;
        }
        if !((sum - 1.0).abs() <= FREQUENCY_SUM_TOLERANCE) {
            return Err(HistogramError::Frequencies);
        }
        Ok(h)
    }

    /// Number of bins `B`.
    #[inline]
    pub fn bins(&self) -> usize {
        self.freqs.as_ref().len()
    }

    /// The first edge `e_0`.
    #[inline]
    pub fn lo(&self) -> f32 {
        self.lo
    }

    /// The last edge `e_B` (the last bin is closed on it).
    #[inline]
    pub fn hi(&self) -> f32 {
        self.hi
    }

    /// The bin frequencies (they sum to 1).
    #[inline]
    pub fn frequencies(&self) -> &[f32] {
        self.freqs.as_ref()
    }

    /// Edge `e_k` as defined in the module docs; `k >= B` gives `e_B`.
    #[inline]
    pub fn edge(&self, k: usize) -> f32 {
        if k == 0 {
            self.lo
        } else if k >= self.bins() {
            self.hi
        } else {
            self.lo + (k as f32) * self.width
        }
    }

    /// The bin containing `x` under numpy's rule, or `None` outside `[e_0, e_B]`
    /// (`±inf` and NaN included).
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn bin(&self, x: f32) -> Option<usize> {
        if !(x >= self.lo && x <= self.hi) {
            return None;
        }
        let last = self.bins() - 1;
        // Estimate, then correct against the true edges. The estimate is off by at most
        // one bin for validated tables; the loops make the result exact regardless.
        let t = (x - self.lo) * self.inv_width;
        let mut k = if t < last as f32 { t as usize } else { last };
        while k > 0 && x < self.edge(k) {
            k -= 1;
        }
        while k < last && x >= self.edge(k + 1) {
            k += 1;
        }
        Some(k)
    }

    /// The likelihood `L` of `x`: the frequency of its bin, 0 outside the support, with
    /// the upper tail handled by `tail`.
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn likelihood(&self, x: f32, tail: UpperTail) -> f32 {
        let bin = if x > self.hi && tail == UpperTail::Clamp {
            Some(self.bins() - 1)
        } else {
            self.bin(x)
        };
        match bin {
            Some(k) => self.freqs.as_ref().get(k).copied().unwrap_or(0.0),
            None => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn h4() -> Histogram<[f32; 4]> {
        // Edges 0, 0.5, 1, 1.5, 2 (all exact in f32).
        Histogram::new(0.0, 2.0, [0.1, 0.2, 0.3, 0.4]).unwrap()
    }

    #[test]
    fn numpy_bin_rule() {
        let h = h4();
        let cases: &[(f32, Option<usize>)] = &[
            (0.0, Some(0)),
            (0.25, Some(0)),
            (0.5, Some(1)), // an inner edge opens the bin to its right
            (1.0, Some(2)),
            (1.5, Some(3)),
            (2.0, Some(3)), // the last edge is closed
            (-0.0001, None),
            (2.0001, None),
            (f32::INFINITY, None),
            (f32::NEG_INFINITY, None),
            (f32::NAN, None),
        ];
        for &(x, want) in cases {
            assert_eq!(h.bin(x), want, "bin({x})");
        }
    }

    #[test]
    fn upper_tail_policies() {
        let h = h4();
        assert_eq!(h.likelihood(3.0, UpperTail::Zero), 0.0);
        assert_eq!(h.likelihood(3.0, UpperTail::Clamp), 0.4);
        assert_eq!(h.likelihood(f32::INFINITY, UpperTail::Clamp), 0.4);
        assert_eq!(h.likelihood(-3.0, UpperTail::Clamp), 0.0);
        assert_eq!(h.likelihood(0.7, UpperTail::Zero), 0.2);
    }

    #[test]
    fn every_edge_opens_its_bin_for_awkward_widths() {
        // Widths that are not representable make the estimate land on either side.
        for &(lo, hi, n) in &[
            (-3.7f32, 9.1f32, 22usize),
            (0.1, 0.7, 17),
            (-1e3, 1e3 + 0.3, 97),
        ] {
            let freqs = std::vec![1.0 / n as f32; n];
            let h = Histogram::new(lo, hi, freqs).unwrap();
            for k in 0..n {
                let e = h.edge(k);
                assert_eq!(h.bin(e), Some(k), "edge {k} = {e}");
                let below = h.edge(k + 1).next_down();
                if k + 1 < n {
                    assert_eq!(h.bin(below), Some(k), "just below edge {}", k + 1);
                }
            }
            assert_eq!(h.bin(hi), Some(n - 1));
        }
    }

    #[test]
    fn rejects_broken_invariants() {
        use HistogramError::*;
        let ok = [0.5f32, 0.5];
        assert_eq!(Histogram::new(1.0, 1.0, ok).unwrap_err(), Edges);
        assert_eq!(Histogram::new(2.0, 1.0, ok).unwrap_err(), Edges);
        assert_eq!(Histogram::new(f32::NAN, 1.0, ok).unwrap_err(), Edges);
        assert_eq!(Histogram::new(0.0, f32::INFINITY, ok).unwrap_err(), Edges);
        assert_eq!(Histogram::new(-3e38, 3e38, ok).unwrap_err(), Edges);
        // Inner edges collapse: 1e6 + k * 1e-3 is not strictly increasing in f32.
        let many = std::vec![1.0 / 100.0; 100];
        assert_eq!(Histogram::new(1e6, 1e6 + 0.1, many).unwrap_err(), Edges);
        let empty: [f32; 0] = [];
        assert_eq!(Histogram::new(0.0, 1.0, empty).unwrap_err(), Edges);
        assert_eq!(
            Histogram::new(0.0, 1.0, [0.5, 0.4]).unwrap_err(),
            Frequencies
        );
        assert_eq!(
            Histogram::new(0.0, 1.0, [1.5, -0.5]).unwrap_err(),
            Frequencies
        );
        assert_eq!(
            Histogram::new(0.0, 1.0, [f32::NAN, 1.0]).unwrap_err(),
            Frequencies
        );
        assert!(Histogram::new(0.0, 1.0, [0.50004, 0.5]).is_ok());
    }
}
