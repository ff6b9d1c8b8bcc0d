//! The Bayes head (docs/DESIGN.md §1.6): a naive-Bayes posterior over every logit of
//! the detection, with a `background` category when the training data has one.
//!
//! Categories `c` are the K classes, plus `background` (index K) when the table was
//! fitted from data with background rows. Logit `j` has one set of equal-width bins
//! (an [`Axis`]) over all training rows; category `c` has a histogram of logit `j` over
//! its own rows, with frequencies `h[c][j][b]`. The table stores, per category, logit
//! and bin, the log-term `t[c][j][b] = ln(h[c][j][b] + lambda)` in `f32`, and per
//! category its number of training rows, from which the prior `ln pi[c]` is computed
//! once, at decode. For a detection with logits `x`:
//!
//! ```text
//! l[c] = ln pi[c] + sum_j t[c][j][bin_j(x_j)]      (ln(lambda) when x_j is outside axis j)
//! p[c] = exp(l[c] - max l) / sum_c' exp(l[c'] - max l)
//! s_i  = OS * p[i]                                   for the K classes only
//! ```
//!
//! With the objectness feature (`fit --objectness-feature`, §1.6) one more axis, over
//! the objectness logit `z = ln(OS) - ln(1 - OS)` clamped into the axis, adds its row
//! of terms after the K logits' (so `OS = 0` and `OS = 1` fall in the first and last
//! bin).
//!
//! So inference is `K * |C|` lookups and additions and one softmax over `|C|` values.
//! The background share is not a class score: the K scores sum to `OS` without a
//! background category and to at most `OS` with one. A detection whose every logit is
//! outside its axis gets the same log-term sum in every category, so its scores are
//! `OS * pi[i]`.
//!
//! Storage is borrowed ([`BayesView`]): the fixed-size [`Table`](crate::Table) and the
//! host's [`DynTable`](crate::DynTable) hold their arrays and lend them here, so both
//! run this one implementation.

use crate::diagnostics::error::{Head, InferError, TableError};
use crate::heads::open::OpenParams;
use crate::math::histogram::{Axis, FREQUENCY_SUM_TOLERANCE};
use crate::math::{self, Backend};

/// The Bayes head's backend when none is named ([`Table::bayes`](crate::Table::bayes),
/// `score_into`, the quantized head, the C API): the crate's own
/// [`FastMath`](crate::FastMath) `exp` for the softmax.
pub type BayesBackend = crate::FastMath;

/// The Bayes head of a table, borrowed from its storage.
///
/// `terms` is laid out logit-major: the log-terms of logit `j` and bin `b` for the `C`
/// categories are contiguous, starting at `(j * B + b) * C`, so a detection adds one
/// contiguous row of `C` terms per logit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BayesView<'a> {
    pub(crate) axes: &'a [Axis],
    pub(crate) terms: &'a [f32],
    pub(crate) rows: &'a [u64],
    pub(crate) log_prior: &'a [f32],
    pub(crate) lambda: f32,
    pub(crate) log_lambda: f32,
    /// The open head's parameters (§1.8), when the table has them (format version 3).
    pub(crate) open: Option<OpenParams>,
    /// The objectness feature: its axis over the objectness logit and its `B * C`
    /// terms (bin-major, then category), when the table has it (format version 4).
    pub(crate) objectness: Option<(Axis, &'a [f32])>,
}

/// The objectness logit `ln(OS) - ln(1 - OS)` of the objectness feature (DESIGN §1.6),
/// in `f32` with libm's `logf`: `-inf` for `OS = 0`, `+inf` for `OS = 1`. The fit bins
/// training rows with this very function.
#[inline]
pub fn objectness_logit(objectness: f32) -> f32 {
    math::ln(objectness) - math::ln(1.0 - objectness)
}

impl<'a> BayesView<'a> {
    /// The open head's parameters (DESIGN §1.8), when the table has that head.
    #[inline]
    pub fn open(&self) -> Option<OpenParams> {
        self.open
    }

    /// Number of logits (the table's K).
    #[inline]
    pub fn logits(&self) -> usize {
        self.axes.len()
    }

    /// Number of categories: K, or K + 1 with `background`.
    #[inline]
    pub fn categories(&self) -> usize {
        self.rows.len()
    }

    /// Whether the last category is `background`.
    #[inline]
    pub fn has_background(&self) -> bool {
        self.categories() > self.logits()
    }

    /// Bins per logit.
    #[inline]
    pub fn bins(&self) -> usize {
        self.axes.first().map_or(0, Axis::bins)
    }

    /// The additive smoothing inside the logarithm.
    #[inline]
    pub fn lambda(&self) -> f32 {
        self.lambda
    }

    /// The bins of logit `j`.
    #[inline]
    pub fn axis(&self, j: usize) -> Option<&'a Axis> {
        self.axes.get(j)
    }

    /// Training rows of category `c` (`c = K` is `background`).
    #[inline]
    pub fn rows(&self, c: usize) -> Option<u64> {
        self.rows.get(c).copied()
    }

    /// `ln pi[c]`, the log prior of category `c`, as computed at decode.
    #[inline]
    pub fn log_prior(&self, c: usize) -> Option<f32> {
        self.log_prior.get(c).copied()
    }

    /// The stored log-term `ln(h + lambda)` of category `c`, logit `j` and bin `bin`.
    #[inline]
    pub fn term(&self, c: usize, j: usize, bin: usize) -> Option<f32> {
        let (b, cats) = (self.bins(), self.categories());
        if c >= cats || j >= self.logits() || bin >= b {
            return None;
        }
        self.terms.get((j * b + bin) * cats + c).copied()
    }

    /// Every stored log-term, logit-major (see the type docs).
    #[inline]
    pub fn all_terms(&self) -> &'a [f32] {
        self.terms
    }

    /// Every category's training rows.
    #[inline]
    pub fn all_rows(&self) -> &'a [u64] {
        self.rows
    }

    /// Every logit's axis.
    #[inline]
    pub fn axes(&self) -> &'a [Axis] {
        self.axes
    }

    /// The objectness feature's axis, over the objectness logit, when the table has it.
    #[inline]
    pub fn objectness_axis(&self) -> Option<Axis> {
        self.objectness.map(|(a, _)| a)
    }

    /// The objectness feature's `B * C` terms (bin-major, then category; empty without
    /// the feature).
    #[inline]
    pub fn objectness_terms(&self) -> &'a [f32] {
        self.objectness.map_or(&[], |(_, t)| t)
    }

    /// Number of axes a detection adds terms from: K, plus 1 with the objectness
    /// feature (the open head's unknown category has a flat share on each).
    #[inline]
    pub fn features(&self) -> usize {
        self.logits() + usize::from(self.objectness.is_some())
    }

    /// Scores of one detection into `out` (length K); `scratch` holds one value per
    /// category. Inputs must already be checked (no NaN logit, objectness in `[0, 1]`).
    /// Inlined into each table's entry point, so that a fixed-size table's lengths are
    /// constants there.
    #[inline(always)]
    pub(crate) fn score_into<M: Backend>(
        &self,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
    ) -> Result<(), InferError> {
        if out.len() != self.logits() {
            return Err(InferError::Length);
        }
        self.log_scores_into(logits, objectness, scratch)?;
        softmax::<M>(scratch, objectness, out);
        Ok(())
    }

    /// The log-scores `l[c] = ln pi[c] + sum_j t[c][j][bin_j(x_j)]` of one detection
    /// into `l` (one per category), plus the objectness feature's term when the table
    /// has it; shared by this head and the open head (§1.8). Inlined into each head, so
    /// that a fixed-size table's lengths are constants there.
    #[inline(always)]
    pub(crate) fn log_scores_into(
        &self,
        logits: &[f32],
        objectness: f32,
        l: &mut [f32],
    ) -> Result<(), InferError> {
        let b = self.bins();
        if logits.len() != self.logits() || l.len() != self.categories() {
            return Err(InferError::Length);
        }
        // Each logit's bin is looked up once, and its row of C terms added to the
        // log-scores (left to right over the logits, after the prior).
        for (l, &prior) in l.iter_mut().zip(self.log_prior) {
            *l = prior;
        }
        let cats = l.len();
        let terms = self.terms;
        let mut offset = 0usize;
        let rows = self.axes.iter().zip(logits).map(|(axis, &x)| {
            let row = axis
                .bin(x)
                .and_then(|bin| terms.get((offset + bin) * cats..(offset + bin + 1) * cats));
            offset += b;
            row
        });
        add_rows(l, rows, self.log_lambda);
        if let Some((axis, terms)) = &self.objectness {
            add_objectness_row(axis, terms, objectness, l);
        }
        Ok(())
    }
}

/// A stored Bayes log-term: an `f32` of a decoded table, or the four little-endian
/// bytes of one in a quantized section (read in place).
pub(crate) trait Term: Copy {
    /// The term's value.
    fn value(self) -> f32;
}

impl Term for f32 {
    #[inline(always)]
    fn value(self) -> f32 {
        self
    }
}

impl Term for [u8; 4] {
    #[inline(always)]
    fn value(self) -> f32 {
        f32::from_le_bytes(self)
    }
}

/// Adds one row of C terms per logit to the log-scores `l` (C of them, starting from the
/// log priors), left to right over the logits; a logit outside its axis (no row) adds
/// `ln(lambda)` to every category. The one sum of the Bayes head's log-scores, for the
/// `f32` head ([`BayesView`]) and the quantized one.
#[inline(always)]
pub(crate) fn add_rows<'t, T: Term + 't>(
    l: &mut [f32],
    rows: impl Iterator<Item = Option<&'t [T]>>,
    log_lambda: f32,
) {
    for row in rows {
        match row {
            Some(row) => {
                for (l, &t) in l.iter_mut().zip(row) {
                    *l += t.value();
                }
            }
            None => {
                for l in l.iter_mut() {
                    *l += log_lambda;
                }
            }
        }
    }
}

/// `z` clamped into `[axis.lo, axis.hi]` (`max` then `min`: no panic path, unlike
/// `f32::clamp`, and an axis always has `lo < hi`).
#[inline(always)]
pub(crate) fn clamp_to_axis(z: f32, axis: &Axis) -> f32 {
    z.max(axis.lo).min(axis.hi)
}

/// Adds the objectness feature's row of terms for `objectness` to the log-scores `l`:
/// the bin of the objectness logit clamped into `axis` (every objectness in `[0, 1]`
/// has one). Shared by [`BayesView`] and the quantized table.
#[inline(always)]
pub(crate) fn add_objectness_row<T: Term>(
    axis: &Axis,
    terms: &[T],
    objectness: f32,
    l: &mut [f32],
) {
    let cats = l.len();
    let z = clamp_to_axis(objectness_logit(objectness), axis);
    let row = axis
        .bin(z)
        .and_then(|bin| terms.get(bin * cats..(bin + 1) * cats));
    if let Some(row) = row {
        for (l, &t) in l.iter_mut().zip(row) {
            *l += t.value();
        }
    }
}

/// The Bayes head's normalisation: the log-scores `l` (one per category, each finite)
/// become `OS * exp(l[c] - max l) / sum_c' exp(l[c'] - max l)` for the first `out.len()`
/// categories; `l` is overwritten. Shared by [`BayesView`] and the quantized table.
#[inline(always)]
pub(crate) fn softmax<M: Backend>(l: &mut [f32], objectness: f32, out: &mut [f32]) {
    // Every log-score is finite (the terms and priors are), so `max` is too.
    let max = l.iter().copied().fold(f32::NEG_INFINITY, f32::max);
    let mut total = 0.0f32;
    for l in l.iter_mut() {
        // exp(0) = 1 exactly for the largest: one `exp` saved.
        *l = if *l == max { 1.0 } else { M::exp(*l - max) };
        total += *l;
    }
    // `total >= 1`: the largest category contributes exp(0) = 1.
    let scale = objectness / total;
    for (o, &e) in out.iter_mut().zip(l.iter()) {
        *o = e * scale;
    }
}

/// Largest smoothing lambda of the Bayes head. Frequencies are at most 1, so a larger
/// lambda would drown every histogram in the prior; and with `lambda <= 1` every stored
/// term `ln(h + lambda)` is at most `ln 2`, which keeps the decode-time check of the
/// frequencies (through `exp`) accurate.
pub const MAX_LAMBDA_BAYES: f32 = 1.0;

/// How far `exp(t) - lambda` may be from the frequency `h` a stored term
/// `t = f32(ln(h + lambda))` came from, per bin: the rounding of `t` to `f32` (relative
/// `2^-24` of `|t|`, and `|t| <= 64` for any `lambda >= 1e-27`) and the error of `exp`
/// (a few ulp), relative to `h + lambda <= 2`.
const TERM_TOLERANCE: f32 = 2.0 * 80.0 * f32::EPSILON;

/// Checks a Bayes head's stored fields (every table invariant of §1.6) and computes the
/// derived ones: fills `axes[j]`'s widths (from their `lo`, `hi` as stored), writes
/// `log_prior` and returns `ln(lambda)`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn validate(
    k: usize,
    bins: usize,
    lambda: f32,
    axes: &mut [Axis],
    terms: &[f32],
    rows: &[u64],
    log_prior: &mut [f32],
    objectness: Option<(&mut Axis, &[f32])>,
) -> Result<f32, TableError> {
    let head = Head::Bayes;
    if !(lambda > 0.0 && lambda <= MAX_LAMBDA_BAYES) {
        return Err(TableError::Lambda { head });
    }
    let categories = rows.len();
    if axes.len() != k
        || !(categories == k || categories == k + 1)
        || log_prior.len() != categories
        || Some(terms.len()) != categories.checked_mul(k).and_then(|n| n.checked_mul(bins))
        || bins == 0
    {
        return Err(TableError::BayesShape);
    }
    for (j, axis) in axes.iter_mut().enumerate() {
        let class = u16::try_from(j).unwrap_or(u16::MAX);
        *axis = Axis::new(axis.lo, axis.hi, bins).map_err(|_| TableError::Edges { head, class })?;
    }
    // The prior: shares of the training rows, each category non-empty.
    let mut total = 0u64;
    for (c, &n) in rows.iter().enumerate() {
        let class = u16::try_from(c).unwrap_or(u16::MAX);
        total = match total.checked_add(n) {
            Some(t) if n > 0 => t,
            _ => return Err(TableError::CategoryRows { class }),
        };
    }
    for (lp, &n) in log_prior.iter_mut().zip(rows) {
        *lp = math::ln(n as f32 / total as f32);
    }
    // Each (category, logit) histogram: ln(h + lambda) with h >= 0 and sum h = 1. The
    // terms of logit j, bin b, category c are at (j * B + b) * C + c.
    let log_lambda = math::ln(lambda);
    for i in 0..categories * k {
        // `max(1)`: no division by zero, whatever the compiler can prove of the loop.
        let (c, j) = (i % categories.max(1), i / categories.max(1));
        let hist = terms
            .get(j * bins * categories..)
            .unwrap_or(&[])
            .iter()
            .skip(c)
            .step_by(categories.max(1))
            .take(bins);
        check_histogram(hist, lambda, bins, c)?;
    }
    // The objectness feature: its axis (named as logit K in errors) and, per category, a
    // histogram of the same rule; its terms are bin-major, then category.
    if let Some((axis, terms)) = objectness {
        let class = u16::try_from(k).unwrap_or(u16::MAX);
        *axis = Axis::new(axis.lo, axis.hi, bins).map_err(|_| TableError::Edges { head, class })?;
        if Some(terms.len()) != bins.checked_mul(categories) {
            return Err(TableError::BayesShape);
        }
        for c in 0..categories {
            let hist = terms.iter().skip(c).step_by(categories.max(1)).take(bins);
            check_histogram(hist, lambda, bins, c)?;
        }
    }
    Ok(log_lambda)
}

/// Checks one category's histogram of stored terms `ln(h + lambda)`: every term finite,
/// `h >= 0` and `sum h = 1` within the tolerances.
fn check_histogram<'t>(
    terms: impl Iterator<Item = &'t f32>,
    lambda: f32,
    bins: usize,
    category: usize,
) -> Result<(), TableError> {
    let head = Head::Bayes;
    let class = u16::try_from(category).unwrap_or(u16::MAX);
    let mut sum = 0.0f32;
    for &t in terms {
        if !t.is_finite() {
            return Err(TableError::Frequencies { head, class });
        }
        let h = math::exp(t) - lambda;
        if !(h >= -TERM_TOLERANCE) {
            return Err(TableError::Frequencies { head, class });
        }
        sum += h;
    }
    // The rounding of each term adds up over the bins.
    let tolerance = FREQUENCY_SUM_TOLERANCE + bins as f32 * TERM_TOLERANCE;
    if !((sum - 1.0).abs() <= tolerance) {
        return Err(TableError::Frequencies { head, class });
    }
    Ok(())
}
