//! The open head (docs/DESIGN.md §1.8): the detector's own ranking, calibrated by a
//! temperature, times the probability that the detection is an object of a known class.
//!
//! It reuses the Bayes head's log-scores `l[c]` (§1.6: the categories `C` are the K
//! classes, plus `background` when the table has it) and adds an `unknown` category with
//! a flat share `1/B` in every bin of every logit and prior weight `epsilon`:
//!
//! ```text
//! l_u  = ln(epsilon) + K ln(1/B + lambda)          (stored at decode as `log_unknown`)
//! m    = max_c l[c]                                 (over C, not over the unknown)
//! q    = sum_{c < K} e^(l[c] - m) / (sum_{c in C} e^(l[c] - m) + e^(l_u - m))
//! s_i  = (OS * q) * softmax(z / T)_i
//! ```
//!
//! The softmax is the temperature layer's ([`crate::math::baseline::temperature`]), given
//! `OS * q` as its objectness; with `epsilon = 0` and no background category `q` is
//! exactly 1 and the scores are bit for bit that layer's.
//!
//! Why `m` leaves the unknown out: for one detection, `e^(l_u - m)` then depends on
//! `epsilon` alone, through libm's `logf` and `expf`, both non-decreasing (checked for
//! every `f32`; the unknown's term uses libm whatever the backend of the rest), so
//! raising `epsilon` never raises a score, not even by a rounding step; an `e^(l_u - m)` that overflows is
//! `+inf`, and `q` is then 0, which is what its true value (below `K / 3.4e38`) rounds to.

use crate::diagnostics::error::{InferError, TableError};
use crate::math::baseline;
use crate::math::{self, Backend};

/// The open head's backend when none is named ([`Table::open`](crate::Table::open),
/// `score_into`, the quantized head, the C API): the Bayes head's, whose log-scores it
/// shares.
pub type OpenBackend = super::bayes::BayesBackend;

/// Largest temperature a table may hold (the temperature baseline's search bound,
/// DESIGN §1.4).
pub const MAX_TEMPERATURE: f32 = 1.0e6;
/// Smallest temperature a table may hold (the same bound).
pub const MIN_TEMPERATURE: f32 = 1.0e-6;
/// Largest prior weight of the unknown category. Beyond it every known object would
/// already score about `OS / epsilon`; the bound keeps `ln(epsilon)` far from overflow.
pub const MAX_EPSILON: f32 = 1.0e30;

/// The open head's two parameters, and the one value derived from them at decode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenParams {
    pub(crate) temperature: f32,
    pub(crate) epsilon: f32,
    /// `ln(epsilon) + K ln(1/B + lambda)`, `-inf` when `epsilon = 0`.
    pub(crate) log_unknown: f32,
}

impl OpenParams {
    /// Checks `temperature` (finite, in `[MIN_TEMPERATURE, MAX_TEMPERATURE]`) and
    /// `epsilon` (`0` or in `[f32::MIN_POSITIVE, MAX_EPSILON]`), and derives the unknown
    /// category's log-score for a Bayes head with `k` logits, `bins` bins per logit and
    /// smoothing `lambda`.
    pub(crate) fn new(
        temperature: f32,
        epsilon: f32,
        k: usize,
        bins: usize,
        lambda: f32,
    ) -> Result<Self, TableError> {
        if !(MIN_TEMPERATURE..=MAX_TEMPERATURE).contains(&temperature) {
            return Err(TableError::Temperature);
        }
        if !(epsilon == 0.0 || (f32::MIN_POSITIVE..=MAX_EPSILON).contains(&epsilon))
            || epsilon.is_sign_negative()
        {
            return Err(TableError::Epsilon);
        }
        let log_unknown = if epsilon == 0.0 {
            f32::NEG_INFINITY
        } else {
            // K <= 65535, bins >= 1, lambda in (0, 1]: the flat term is finite.
            let flat = k as f32 * math::ln(1.0 / bins.max(1) as f32 + lambda);
            math::ln(epsilon) + flat
        };
        Ok(Self {
            temperature,
            epsilon,
            log_unknown,
        })
    }

    /// The temperature `T > 0` that divides the logits before the softmax.
    #[inline]
    pub fn temperature(&self) -> f32 {
        self.temperature
    }

    /// The prior weight `epsilon >= 0` of the unknown category (0: no unknown).
    #[inline]
    pub fn epsilon(&self) -> f32 {
        self.epsilon
    }

    /// The unknown category's log-score `ln(epsilon) + K ln(1/B + lambda)`, as computed
    /// at decode (`-inf` when `epsilon = 0`).
    #[inline]
    pub fn log_unknown(&self) -> f32 {
        self.log_unknown
    }
}

/// The open head from the Bayes log-scores `l` (one per category, each finite, the K
/// classes first) and the detection's logits: writes `OS * q * softmax(z / T)` into
/// `out` (K entries) and returns `q`. `l` is overwritten. Inputs must already be
/// checked (no NaN logit, objectness in `[0, 1]`, lengths). Shared by the f32 table and
/// the quantized table, so both give the same bits on the same log-scores.
#[inline(always)]
pub(crate) fn score_from_log_scores<M: Backend>(
    l: &mut [f32],
    open: &OpenParams,
    logits: &[f32],
    objectness: f32,
    out: &mut [f32],
) -> f32 {
    let k = out.len();
    let q = known_share::<M>(l, k, open.log_unknown);
    baseline::temperature_into::<M>(logits, open.temperature, objectness * q, out);
    q
}

/// `q`: the share of the K classes in the posterior over the categories and the unknown.
#[inline(always)]
pub(crate) fn known_share<M: Backend>(l: &[f32], k: usize, log_unknown: f32) -> f32 {
    // Every log-score is finite (the terms and priors are), so `max` is too.
    let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mut known = 0.0f32;
    let mut rest = 0.0f32;
    for (c, &lc) in l.iter().enumerate() {
        // exp(0) = 1 exactly for the largest, as in the Bayes head's softmax.
        let e = if lc == max { 1.0 } else { M::exp(lc - max) };
        if c < k {
            known += e;
        } else {
            rest += e;
        }
    }
    // No unknown category when epsilon = 0 (`log_unknown = -inf`): its term is 0, which
    // is what exp(-inf) gives, without the call. Otherwise libm's `expf` whatever `M`:
    // it never decreases (checked for every f32), so neither does this term in epsilon;
    // `FastMath`'s `exp` steps down by an ulp at a few arguments.
    let unknown = if log_unknown == f32::NEG_INFINITY {
        0.0
    } else {
        math::exp(log_unknown - max)
    };
    // `known + rest >= 1` (the largest category contributes 1), so the denominator is
    // never 0, and `known <= known + rest <= denominator` keeps q in [0, 1].
    known / ((known + rest) + unknown)
}

/// Open-head scores of one detection from a Bayes head's log-scores: the entry of
/// [`BayesView`](crate::BayesView)-backed tables.
#[inline(always)]
pub(crate) fn score_into<M: Backend>(
    bayes: &crate::BayesView<'_>,
    open: &OpenParams,
    logits: &[f32],
    objectness: f32,
    out: &mut [f32],
    scratch: &mut [f32],
) -> Result<(), InferError> {
    bayes.log_scores_into(logits, objectness, scratch)?;
    score_from_log_scores::<M>(scratch, open, logits, objectness, out);
    Ok(())
}
