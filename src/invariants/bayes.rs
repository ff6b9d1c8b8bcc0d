//! The Bayes head's invariants (DESIGN §1.6): its table, its scores, and an `f64` reference.

use super::*;

/// Largest amount by which a frequency `h = exp(t) - lambda` implied by a stored Bayes
/// term `t` may be negative, per bin (DESIGN §1.6), computed in `f64` from the `f32`
/// term.
///
/// A fit stores `t = f32(ln(h + lambda))` with `h >= 0` and `h + lambda <= 2`; the
/// rounding of `t` is at most `2^-24 |t|`, with `|t| <= max(ln 2, |ln lambda|) <= 103.3`
/// for any positive `f32` lambda, so `exp(t)` is within `2 * 103.3 * 2^-24 = 1.2e-5` of
/// `h + lambda`. The decoder checks the same rule in `f32` with a per-bin tolerance of
/// `160 * f32::EPSILON = 1.9e-5`; this one is `9e-7` wider, which covers the decoder's
/// own `f32` rounding (`exp` and the subtraction, under `1e-6`), so every table the
/// decoder accepts passes.
pub const BAYES_FREQUENCY_TOLERANCE: f64 = 2e-5;

/// How far the implied frequencies of one (category, logit) of a Bayes head with `bins`
/// bins may sum from 1: [`FREQUENCY_SUM_TOLERANCE`] plus [`BAYES_FREQUENCY_TOLERANCE`]
/// per bin (each bin's term carries its own rounding).
#[must_use]
pub fn bayes_frequency_sum_tolerance(bins: usize) -> f64 {
    f64::from(FREQUENCY_SUM_TOLERANCE) + bins as f64 * BAYES_FREQUENCY_TOLERANCE
}

/// How the Bayes scores of `head` must add up: to `OS` ([`Sum::Equal`]) when its
/// categories are the K classes, to at most `OS` ([`Sum::AtMost`]) with `background`.
#[must_use]
pub fn bayes_sum(head: &BayesView<'_>) -> Sum {
    if head.has_background() {
        Sum::AtMost
    } else {
        Sum::Equal
    }
}

/// `pi[c]`, the share of the training rows of category `c`, in `f64` (`None` when `c`
/// is not a category or there are no rows).
fn prior_share(head: &BayesView<'_>, c: usize) -> Option<f64> {
    let total: f64 = head.all_rows().iter().map(|&n| n as f64).sum();
    let n = head.rows(c)? as f64;
    (total > 0.0).then(|| n / total)
}

/// Relative tolerance of a Bayes score of `head` against the formula of DESIGN §1.6
/// evaluated exactly (in `f64`) from the stored terms and the rows; at least
/// [`SUM_RELATIVE_TOLERANCE`].
///
/// # Derivation
///
/// Let `M = max_c |ln pi[c]| + K T`, `T = max(1, |ln lambda|, max |t|)` over the stored
/// terms: no partial sum of a log-score exceeds `M` in magnitude. The decoder's
/// `f32` `ln pi[c]` is within `3 u + u |ln pi[c]|` of the exact (`u = 2^-24`: rounding
/// of the two counts, the quotient and the logarithm), each of the `K` additions
/// rounds by at most `u M`, and the subtraction of the largest by `2 u M`: each
/// argument of `exp` is within `d = (K + 5) u (M + 1)` of the exact difference (`d`
/// counts the errors of both log-scores). `exp` adds a relative
/// [`FAST_MATH_MAX_REL_ERROR`] (FastMath; `Libm` is within `8e-8`), and the
/// normalisation (`C - 1` additions, the quotient and the product) `(C + 1) u`. To first
/// order, a score is within a relative `2 (2 d + e) + (C + 1) u`; the bound doubles
/// that for the second-order terms. (For the shipped table, K = 3, lambda = 1e-3: about
/// `9.4e-5`; measured on its test split: `2.2e-6`.) Intermediates below
/// `f32::MIN_POSITIVE` carry an absolute rounding instead, allowed for separately by the
/// checkers (`OS * f32::MIN_POSITIVE` plus four [`SUBNORMAL_STEP`]s).
#[must_use]
pub fn bayes_score_tolerance(head: &BayesView<'_>) -> f64 {
    const U: f64 = 1.0 / 16_777_216.0;
    let k = head.logits() as f64;
    let c = head.categories() as f64;
    let mut t = libm::log(f64::from(head.lambda())).abs().max(1.0);
    for &term in head.all_terms() {
        t = t.max(f64::from(term).abs());
    }
    let mut prior = 0.0f64;
    for cat in 0..head.categories() {
        if let Some(pi) = prior_share(head, cat) {
            prior = prior.max(libm::log(pi).abs());
        }
    }
    let m = prior + k * t;
    let d = (k + 5.0) * U * (m + 1.0);
    let e = f64::from(FAST_MATH_MAX_REL_ERROR);
    let first_order = 2.0 * (2.0 * d + e) + (c + 1.0) * U;
    (2.0 * first_order).max(SUM_RELATIVE_TOLERANCE)
}

/// The absolute slack of the Bayes score checks for `OS = objectness`: intermediates
/// below `f32::MIN_POSITIVE` (absolute rounding of `2^-149` each, on a total of at least
/// 1) and subnormal scores.
fn bayes_absolute_slack(objectness: f32) -> f64 {
    f64::from(objectness) * f64::from(f32::MIN_POSITIVE) + 4.0 * SUBNORMAL_STEP
}

/// DESIGN §1.6, the rule without evidence: when every logit is outside its axis, every
/// category gets the same `K ln(lambda)`, so score `i` is `OS * pi[i]` (`pi` the share of
/// the training rows of category `i`, computed here in `f64` from
/// [`BayesView::rows`]), within a relative [`bayes_score_tolerance`] plus the absolute
/// slack of subnormal values.
///
/// # Errors
///
/// [`Violation::ClassCount`] when there are not K scores; [`Violation::NotPriorShare`]
/// for the first score out of tolerance (or NaN).
pub fn check_prior_share(
    scores: &[f32],
    objectness: f32,
    head: &BayesView<'_>,
) -> Result<(), Violation> {
    if scores.len() != head.logits() {
        return Err(Violation::ClassCount {
            expected: head.logits(),
            found: scores.len(),
        });
    }
    let relative = bayes_score_tolerance(head);
    let slack = bayes_absolute_slack(objectness);
    for (class, &score) in scores.iter().enumerate() {
        let expected = f64::from(objectness) * prior_share(head, class).unwrap_or(f64::NAN);
        if !((f64::from(score) - expected).abs() <= relative * expected + slack) {
            return Err(Violation::NotPriorShare {
                class,
                score,
                expected,
            });
        }
    }
    Ok(())
}

/// The Bayes scores of DESIGN §1.6 evaluated in `f64` from the head's stored terms and
/// rows (`ln pi[c]` from the rows, `ln(lambda)` for a logit outside its axis, then the
/// softmax, times `OS`), into `out` (length K): a reference for the head's `f32`
/// inference, which must be within [`bayes_score_tolerance`] of it. Inputs must be valid
/// (no NaN logit, objectness in `[0, 1]`); `scratch` holds one value per category.
///
/// Returns `false` (and writes nothing) when a length does not fit the head.
pub fn bayes_reference(
    head: &BayesView<'_>,
    logits: &[f32],
    objectness: f32,
    out: &mut [f64],
    scratch: &mut [f64],
) -> bool {
    let (k, cats) = (head.logits(), head.categories());
    if logits.len() != k || out.len() != k || scratch.len() != cats {
        return false;
    }
    let log_lambda = libm::log(f64::from(head.lambda()));
    for (c, l) in scratch.iter_mut().enumerate() {
        *l = libm::log(prior_share(head, c).unwrap_or(f64::NAN));
        for (j, &x) in logits.iter().enumerate() {
            let term = head
                .axis(j)
                .and_then(|a| a.bin(x))
                .and_then(|b| head.term(c, j, b));
            *l += term.map_or(log_lambda, f64::from);
        }
    }
    let max = scratch.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut total = 0.0;
    for l in scratch.iter_mut() {
        *l = libm::exp(*l - max);
        total += *l;
    }
    for (o, &e) in out.iter_mut().zip(scratch.iter()) {
        *o = f64::from(objectness) * e / total;
    }
    true
}

/// Whether Bayes `scores` are within [`bayes_score_tolerance`] (relative, plus the
/// absolute slack of subnormal values) of the `f64` reference `want`
/// ([`bayes_reference`]); the index of the first that is not.
#[must_use]
pub fn bayes_mismatch(
    head: &BayesView<'_>,
    scores: &[f32],
    want: &[f64],
    objectness: f32,
) -> Option<usize> {
    let relative = bayes_score_tolerance(head);
    let slack = bayes_absolute_slack(objectness);
    if scores.len() != want.len() {
        return Some(scores.len().min(want.len()));
    }
    scores
        .iter()
        .zip(want)
        .position(|(&s, &w)| !((f64::from(s) - w).abs() <= relative * w + slack))
}

/// DESIGN §1.6 for the axis of logit `logit` of a Bayes head, given as its edges (so
/// that any storage can be checked): `bins + 1` edges, finite and strictly increasing.
///
/// # Errors
///
/// [`Violation::BayesEdge`] for the first bad edge, [`Violation::BayesBins`] when there
/// are not `bins + 1` edges.
pub fn check_bayes_axis<E: IntoIterator<Item = f32>>(
    logit: usize,
    edges: E,
    bins: usize,
) -> Result<(), Violation> {
    let mut previous = f32::NEG_INFINITY;
    let mut count = 0usize;
    for (edge, value) in edges.into_iter().enumerate() {
        count += 1;
        if !(value.is_finite() && value > previous) {
            return Err(Violation::BayesEdge {
                logit,
                edge,
                previous,
                value,
            });
        }
        previous = value;
    }
    if count != bins + 1 || bins == 0 {
        return Err(Violation::BayesBins {
            logit,
            expected: bins,
            found: count.saturating_sub(1),
        });
    }
    Ok(())
}

/// DESIGN §1.6 for the stored terms `t = ln(h + lambda)` of one (category, logit) of a
/// Bayes head, in bin order (so that any storage can be checked, e.g. a
/// [`BayesSpec`](crate::host::BayesSpec) before it is attached): `bins` terms, each
/// finite, each implied frequency `exp(t) - lambda` (in `f64`) at least
/// `-`[`BAYES_FREQUENCY_TOLERANCE`], summing to 1 within
/// [`bayes_frequency_sum_tolerance`].
///
/// # Errors
///
/// [`Violation::BayesTerm`], [`Violation::BayesFrequency`],
/// [`Violation::BayesBins`] (not `bins` terms) or [`Violation::BayesFrequencySum`], the
/// first found.
pub fn check_bayes_terms<T: IntoIterator<Item = f32>>(
    category: usize,
    logit: usize,
    lambda: f32,
    terms: T,
    bins: usize,
) -> Result<(), Violation> {
    let lambda = f64::from(lambda);
    let mut sum = 0.0f64;
    let mut count = 0usize;
    for (bin, term) in terms.into_iter().enumerate() {
        count += 1;
        if !term.is_finite() {
            return Err(Violation::BayesTerm {
                category,
                logit,
                bin,
                term,
            });
        }
        let frequency = libm::exp(f64::from(term)) - lambda;
        if !(frequency >= -BAYES_FREQUENCY_TOLERANCE) {
            return Err(Violation::BayesFrequency {
                category,
                logit,
                bin,
                frequency,
            });
        }
        sum += frequency;
    }
    if count != bins {
        return Err(Violation::BayesBins {
            logit,
            expected: bins,
            found: count,
        });
    }
    if !((sum - 1.0).abs() <= bayes_frequency_sum_tolerance(bins)) {
        return Err(Violation::BayesFrequencySum {
            category,
            logit,
            sum,
        });
    }
    Ok(())
}

/// The table invariants of DESIGN §1.6 for the Bayes head of a table of `classes`
/// classes, through the public [`BayesView`] API: lambda in
/// `(0, MAX_LAMBDA_BAYES]`; `classes` logits and `classes` or `classes + 1` categories,
/// each with training rows (whose total fits `u64`); every logit's axis with the head's
/// bin count, its edges ([`Axis::edge`](crate::Axis::edge)) finite and strictly
/// increasing; every term finite; and per (category, logit) the implied frequencies
/// `exp(t) - lambda` (in `f64`) at least `-`[`BAYES_FREQUENCY_TOLERANCE`] and summing to
/// 1 within [`bayes_frequency_sum_tolerance`].
///
/// # Errors
///
/// The first of [`Violation::BayesLambda`], [`Violation::BayesCategories`],
/// [`Violation::CategoryRows`], [`Violation::BayesBins`], [`Violation::BayesEdge`],
/// [`Violation::BayesTerm`], [`Violation::BayesFrequency`],
/// [`Violation::BayesFrequencySum`] or, with the open head, [`Violation::OpenParams`],
/// in that order.
pub fn check_bayes(head: &BayesView<'_>, classes: usize) -> Result<(), Violation> {
    let lambda = head.lambda();
    if !(lambda > 0.0 && lambda <= MAX_LAMBDA_BAYES) {
        return Err(Violation::BayesLambda { lambda });
    }
    let (logits, categories) = (head.logits(), head.categories());
    if logits != classes || !(categories == classes || categories == classes + 1) {
        return Err(Violation::BayesCategories {
            classes,
            logits,
            categories,
        });
    }
    let mut total = 0u64;
    for (category, &rows) in head.all_rows().iter().enumerate() {
        total = match total.checked_add(rows) {
            Some(t) if rows > 0 => t,
            _ => return Err(Violation::CategoryRows { category, rows }),
        };
    }
    let bins = head.bins();
    for logit in 0..logits {
        let found = head.axis(logit).map_or(0, |a| a.bins());
        if found != bins || bins == 0 {
            return Err(Violation::BayesBins {
                logit,
                expected: bins,
                found,
            });
        }
        if let Some(axis) = head.axis(logit) {
            check_bayes_axis(logit, (0..=bins).map(|e| axis.edge(e)), bins)?;
        }
    }
    for category in 0..categories {
        for logit in 0..logits {
            let terms = (0..bins).map(|bin| head.term(category, logit, bin).unwrap_or(f32::NAN));
            check_bayes_terms(category, logit, head.lambda(), terms, bins)?;
        }
    }
    if let Some(open) = head.open() {
        check_open_params(open.temperature(), open.epsilon())?;
    }
    Ok(())
}

/// DESIGN §1.8, the open head's stored parameters: a temperature in
/// `[MIN_TEMPERATURE, MAX_TEMPERATURE]`, and an `epsilon` that is `+0` or in
/// `[f32::MIN_POSITIVE, MAX_EPSILON]`.
///
/// # Errors
///
/// [`Violation::OpenParams`] when either is out of range.
pub fn check_open_params(temperature: f32, epsilon: f32) -> Result<(), Violation> {
    let t_ok = (crate::MIN_TEMPERATURE..=crate::MAX_TEMPERATURE).contains(&temperature);
    let e_ok = (epsilon == 0.0 && epsilon.is_sign_positive())
        || (f32::MIN_POSITIVE..=crate::MAX_EPSILON).contains(&epsilon);
    if t_ok && e_ok {
        Ok(())
    } else {
        Err(Violation::OpenParams {
            temperature,
            epsilon,
        })
    }
}
