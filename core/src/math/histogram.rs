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

impl UpperTail {
    /// The policy's code in a table file's settings and in the C API's
    /// `mlmap_settings_t` (docs/FORMAT.md): `Zero` 0, `Clamp` 1.
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// use mlmap::UpperTail;
    /// assert_eq!(UpperTail::from_code(UpperTail::Clamp.code()), Some(UpperTail::Clamp));
    /// assert_eq!(UpperTail::from_code(2), None);
    /// ```
    pub const fn code(self) -> u8 {
        match self {
            Self::Zero => 0,
            Self::Clamp => 1,
        }
    }

    /// The policy of a code, `None` for a code no policy has.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Self::Zero),
            1 => Some(Self::Clamp),
            _ => None,
        }
    }
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

impl EdgeMode {
    /// The mode's code in a table file's settings and in the C API's `mlmap_settings_t`
    /// (docs/FORMAT.md): `Linspace` 0, `Matlab` 1.
    ///
    /// ```
    /// # use mlmap_core as mlmap;
    /// use mlmap::EdgeMode;
    /// assert_eq!(EdgeMode::from_code(EdgeMode::Matlab.code()), Some(EdgeMode::Matlab));
    /// assert_eq!(EdgeMode::from_code(2), None);
    /// ```
    pub const fn code(self) -> u8 {
        match self {
            Self::Linspace => 0,
            Self::Matlab => 1,
        }
    }

    /// The mode of a code, `None` for a code no mode has.
    pub const fn from_code(code: u8) -> Option<Self> {
        match code {
            0 => Some(Self::Linspace),
            1 => Some(Self::Matlab),
            _ => None,
        }
    }
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

impl HistogramError {
    /// The one sentence describing the error, shared by `Display` and `defmt`.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Edges => "histogram edges are not finite, or not strictly increasing in f32",
            Self::Frequencies => {
                "histogram frequencies are not finite, non-negative and summing to 1"
            }
        }
    }
}

impl core::fmt::Display for HistogramError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.message())
    }
}

impl core::error::Error for HistogramError {}

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
        let (width, inv_width) = equal_bins(lo, hi, freqs.as_ref().len())?;
        let h = Self {
            lo,
            hi,
            width,
            inv_width,
            freqs,
        };
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
            self.inner_edge(k)
        }
    }

    #[inline(always)]
    fn inner_edge(&self, k: usize) -> f32 {
        inner_edge(self.lo, self.width, k)
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
        Some(self.bin_in_support(x))
    }

    /// The bin of `x`, for `lo <= x <= hi`.
    #[inline(always)]
    fn bin_in_support(&self, x: f32) -> usize {
        let last = self.bins() - 1;
        locate(self.lo, self.width, self.inv_width, last, cap(last), x)
    }

    /// The likelihood `L` of `x`: the frequency of its bin, 0 outside the support, with
    /// the upper tail handled by `tail`.
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn likelihood(&self, x: f32, tail: UpperTail) -> f32 {
        let k = if x >= self.lo && x <= self.hi {
            self.bin_in_support(x)
        } else if x > self.hi && tail == UpperTail::Clamp {
            self.bins() - 1
        } else {
            return 0.0;
        };
        self.freqs.as_ref().get(k).copied().unwrap_or(0.0)
    }
}

impl<F: AsRef<[f32]>> Histogram<F> {
    /// The bin whose frequency [`Histogram::likelihood`] returns for `x` (the last bin
    /// above `e_B` under [`UpperTail::Clamp`]), or `None` where it returns 0 without a
    /// bin. The quantized table stores these bins per code.
    pub(crate) fn likelihood_bin(&self, x: f32, tail: UpperTail) -> Option<usize> {
        if x >= self.lo && x <= self.hi {
            Some(self.bin_in_support(x))
        } else if x > self.hi && tail == UpperTail::Clamp {
            Some(self.bins().saturating_sub(1))
        } else {
            None
        }
    }
}

/// Width and reciprocal width of `n` equal bins over `[lo, hi]`, after checking that
/// the edges are finite and that every inner edge `lo + k * w` is strictly above the
/// previous one in `f32`.
fn equal_bins(lo: f32, hi: f32, n: usize) -> Result<(f32, f32), HistogramError> {
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
    let mut prev = lo;
    for k in 1..n {
        let e = inner_edge(lo, width, k);
        if !(e > prev) {
            return Err(HistogramError::Edges);
        }
        prev = e;
    }
    if !(hi > prev) {
        return Err(HistogramError::Edges);
    }
    Ok((width, inv_width))
}

/// `lo + k * w`: edge `e_k` for `0 < k < B` (one rounded product, one rounded sum).
/// `k < B <= u16::MAX`, so the conversion through `u32` is exact and cheaper than one
/// from `usize`.
#[inline(always)]
fn inner_edge(lo: f32, width: f32, k: usize) -> f32 {
    lo + (k as u32 as f32) * width
}

/// `1.5 * 2^23`: sums with it in `[2^23, 2^24)` are rounded to integers.
const ROUNDER: f32 = 12_582_912.0;

/// `ROUNDER + last`, the largest estimate [`locate`] may return, as its exact `f32`.
#[inline(always)]
fn cap(last: usize) -> f32 {
    ROUNDER + last as u32 as f32
}

/// The bin of `x` among `last + 1` equal-width bins starting at `lo`, for `x` inside
/// the support (`lo <= x <= e_B`): the O(1) lookup of the module docs, shared by
/// [`Histogram`] and [`Axis`].
#[inline(always)]
fn locate(lo: f32, width: f32, inv_width: f32, last: usize, cap: f32, x: f32) -> usize {
    // Estimate `floor(t)`, then correct against the true edges. The estimate is off
    // by at most one bin for validated tables; the corrections make the result exact
    // regardless. `0 <= t <= B (1 + eps)`, far below 2^22, so `t - 0.5 + ROUNDER`
    // is an integer-valued f32 equal to `ROUNDER + round(t - 0.5)`: `kf` is the
    // estimate as an exact f32 and `k` as an integer, without float-int conversions.
    let t = (x - lo) * inv_width;
    let r = t - 0.5 + ROUNDER;
    let r = if r < cap { r } else { cap };
    let kf = r - ROUNDER;
    let mut k = r.to_bits().saturating_sub(ROUNDER.to_bits()) as usize;
    // `kf` is `k as f32` and `lo + kf * w` is `edge(k)` for 1 <= k <= last (and
    // compares equal to it for k = 0). After a step down `x < e_(k+1)` holds, so at
    // most one direction ever moves.
    if x < lo + kf * width {
        k = k.saturating_sub(1);
        while k > 0 && x < inner_edge(lo, width, k) {
            k -= 1;
        }
    } else if k < last && x >= lo + (kf + 1.0) * width {
        k += 1;
        while k < last && x >= inner_edge(lo, width, k + 1) {
            k += 1;
        }
    }
    k
}

/// The equal-width bins of one logit, without frequencies: the support of a Bayes head's
/// per-logit histograms ([`crate::BayesView`]), with the same edges and the same lookup
/// rule as a [`Histogram`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Axis {
    pub(crate) lo: f32,
    pub(crate) hi: f32,
    pub(crate) width: f32,
    pub(crate) inv_width: f32,
    pub(crate) bins: u16,
    /// `ROUNDER + (bins - 1)`, precomputed for the lookup (0 for the placeholder).
    pub(crate) cap: f32,
}

impl Axis {
    /// An axis of all zeros (invalid), for storage that is filled before use.
    pub(crate) const ZERO: Self = Self {
        lo: 0.0,
        hi: 0.0,
        width: 0.0,
        inv_width: 0.0,
        bins: 0,
        cap: 0.0,
    };

    /// Validates and builds `bins` equal bins over `[lo, hi]`.
    ///
    /// # Errors
    ///
    /// [`HistogramError::Edges`] as for [`Histogram::new`].
    ///
    /// # Panics
    ///
    /// Never.
    pub fn new(lo: f32, hi: f32, bins: usize) -> Result<Self, HistogramError> {
        let (width, inv_width) = equal_bins(lo, hi, bins)?;
        Ok(Self {
            lo,
            hi,
            width,
            inv_width,
            bins: u16::try_from(bins).map_err(|_| HistogramError::Edges)?,
            cap: cap(bins - 1),
        })
    }

    /// The first edge `e_0`.
    #[inline]
    pub fn lo(&self) -> f32 {
        self.lo
    }

    /// The last edge `e_B`.
    #[inline]
    pub fn hi(&self) -> f32 {
        self.hi
    }

    /// Number of bins `B`.
    #[inline]
    pub fn bins(&self) -> usize {
        usize::from(self.bins)
    }

    /// Edge `e_k`, exactly as [`Histogram::edge`] computes it; `k >= B` gives `e_B`.
    #[inline]
    pub fn edge(&self, k: usize) -> f32 {
        if k == 0 {
            self.lo
        } else if k >= self.bins() {
            self.hi
        } else {
            inner_edge(self.lo, self.width, k)
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
        // A validated axis has `bins >= 1`; the placeholder's empty range holds nothing.
        if !(x >= self.lo && x <= self.hi) {
            return None;
        }
        let last = usize::from(self.bins).saturating_sub(1);
        Some(locate(
            self.lo,
            self.width,
            self.inv_width,
            last,
            self.cap,
            x,
        ))
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

    /// The bin by definition: the last `k` with `e_k <= x`, the last bin closed.
    fn bin_by_scan<F: AsRef<[f32]>>(h: &Histogram<F>, x: f32) -> Option<usize> {
        if !(x >= h.lo() && x <= h.hi()) {
            return None;
        }
        (0..h.bins()).rev().find(|&k| x >= h.edge(k))
    }

    #[test]
    fn bin_matches_the_definition_near_every_edge() {
        // Bins of one or two ulps (the estimate is then often off), wide and narrow
        // supports, supports straddling 0, and negative ones.
        let cases: &[(f32, f32, usize)] = &[
            (1.0e6, 1.0e6 + 22.0 * 0.0625, 22),
            (1.0e6, 1.0e6 + 17.0 * 0.125 - 0.0625, 17),
            (-1.0e6 - 1.5, -1.0e6, 22),
            (-3.7, 9.1, 22),
            (-0.123_2, 9.392_4, 22),
            (-7.064_5, 6.911_1, 17),
            (-1.0e-30, 1.0e-30, 17),
            (0.0, 1.0, 1),
            (-2.0, 65_534.0, 65_535),
        ];
        for &(lo, hi, n) in cases {
            let h = Histogram::new(lo, hi, std::vec![1.0 / n as f32; n]).unwrap();
            let step = (n / 200).max(1);
            for k in (0..=n).step_by(step).chain([n]) {
                let mut x = h.edge(k);
                for _ in 0..4 {
                    x = x.next_down();
                }
                for _ in 0..9 {
                    assert_eq!(h.bin(x), bin_by_scan(&h, x), "{lo}..{hi} / {n}: x = {x}");
                    x = x.next_up();
                }
            }
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
