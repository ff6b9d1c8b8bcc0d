//! Checkers for the invariants of DESIGN §1.3, written against the public API only.
//!
//! The property tests and the fuzz targets of this crate check every score and every
//! table they meet with these functions, so that both test the very same rules; an
//! application can run them too, e.g. on a table received over the air before it is
//! trusted, or on the scores of a new head during development. Each checker returns
//! `Ok(())` or the first [`Violation`] it finds, whose message names the invariant (its
//! number in DESIGN §1.3), the class and the values. They never allocate and never panic.
//!
//! | invariant | checker |
//! |---|---|
//! | 1, scores in `[0, OS]` summing to `OS` | [`check_scores`] with [`Sum::Equal`] |
//! | 2, "I don't know" is exactly `OS / K` | [`check_unknown`] |
//! | 3, more evidence never lowers a score | [`check_monotone`] |
//! | 4, bad input is an error | [`check_error`] (and [`expected_error`]) |
//! | 5, table invariants | [`check_table`], `check_dyn_table` (feature `std`), and the parts: [`check_settings`], [`check_names`], [`check_prior`], [`check_histogram`], [`check_bins`] |
//! | §1.6, the Bayes head's table invariants | [`check_bayes`] (called by [`check_table`] and `check_dyn_table`), and the parts: [`check_bayes_axis`], [`check_bayes_terms`] |
//! | §1.6, its scores | [`check_scores`] with [`Sum::Equal`] (no background) or [`Sum::AtMost`] ([`bayes_sum`] picks), [`check_prior_share`] without evidence, [`check_error`] |
//!
//! The Bayes head's violations cite DESIGN §1.6 instead of §1.3.
//!
//! ```
//! use mlmap::invariants::{
//!     bayes_sum, check_prior_share, check_scores, check_table, check_unknown, Sum,
//! };
//! use mlmap::Table;
//!
//! let table = Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../tables/default.mlmap"))?;
//! check_table(&table)?;
//! let scores = table.map(&[5.1, -2.0, -1.3], 0.93)?;
//! check_scores(&scores.0, 0.93, Sum::Equal)?;
//! // Far outside every histogram: the "I don't know" answer.
//! let unknown = table.ml(&[1e30, 1e30, 1e30], 0.93)?;
//! check_unknown(&unknown.0, 0.93)?;
//! // The Bayes head: its sum rule, and the prior's shares without evidence.
//! let head = table.bayes_head().ok_or("the shipped table has a Bayes head")?;
//! let scores = table.bayes(&[5.1, -2.0, -1.3], 0.93)?;
//! check_scores(&scores.0, 0.93, bayes_sum(&head))?;
//! let unknown = table.bayes(&[1e30, 1e30, 1e30], 0.93)?;
//! check_prior_share(&unknown.0, 0.93, &head)?;
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use core::fmt;

use crate::{
    BayesView, Head, Histogram, InferError, Settings, Table, FAST_MATH_MAX_REL_ERROR,
    FREQUENCY_SUM_TOLERANCE, MAX_LAMBDA, MAX_LAMBDA_BAYES, NAME_MAX,
};

/// Relative tolerance of the sum of the scores against `OS` (DESIGN §1.3 (1)).
pub const SUM_RELATIVE_TOLERANCE: f64 = 1e-5;

/// The smallest positive `f32` (a subnormal), `2^-149`. A score below `f32::MIN_POSITIVE`
/// has no relative precision left and carries up to this much absolute rounding, so
/// [`check_scores`] allows `K` times this on top of the relative tolerance (it matters
/// only for `OS` below about `1e-38`).
pub const SUBNORMAL_STEP: f64 = 1.401_298_464_324_817e-45;

/// How the scores of a head must add up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sum {
    /// The scores sum to `OS` within [`SUM_RELATIVE_TOLERANCE`]: the ML and MAP heads,
    /// whose categories are exactly the `K` classes.
    Equal,
    /// The scores sum to at most `OS` (within the same tolerance): a head with a
    /// background category, whose share of `OS` is not a class score.
    AtMost,
}

/// A broken invariant of DESIGN §1.3 (or of the Bayes head, §1.6): which one, where, and
/// the values.
///
/// `Display` gives one sentence that starts with the invariant's citation, e.g.
/// `DESIGN §1.3 (1): score of class 2 = 1.2e0 is outside [0, OS = 1e0]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Violation {
    /// Invariant 1: a score is NaN or outside `[0, OS]`.
    ScoreOutOfRange {
        /// Class index.
        class: usize,
        /// The score.
        score: f32,
        /// The objectness it must not exceed.
        objectness: f32,
    },
    /// Invariant 1: the scores do not sum to `OS` ([`Sum::Equal`]).
    SumNotObjectness {
        /// Sum of the scores, in `f64`.
        sum: f64,
        /// The objectness.
        objectness: f32,
    },
    /// Invariant 1: the scores sum to more than `OS` ([`Sum::AtMost`]).
    SumAboveObjectness {
        /// Sum of the scores, in `f64`.
        sum: f64,
        /// The objectness.
        objectness: f32,
    },
    /// Invariant 2: without evidence, a score is not exactly `OS / K`.
    NotUnknown {
        /// Class index.
        class: usize,
        /// The score.
        score: f32,
        /// `OS / K` in `f32`.
        expected: f32,
    },
    /// Invariant 3: more evidence for a class lowered its score.
    ScoreLowered {
        /// Class index.
        class: usize,
        /// The score with less evidence.
        before: f32,
        /// The score with more evidence.
        after: f32,
    },
    /// Invariant 4: a bad input was scored instead of refused.
    MissingError {
        /// The error the input calls for.
        expected: InferError,
    },
    /// Invariant 4: an error other than the one the input calls for (`expected` is
    /// `None` when the input is valid).
    WrongError {
        /// The error the input calls for, if any.
        expected: Option<InferError>,
        /// The error returned.
        found: InferError,
    },
    /// Invariant 5: fewer classes than the table's shape declares, or fewer than 2.
    ClassCount {
        /// Classes the table should have (at least 2).
        expected: usize,
        /// Classes found.
        found: usize,
    },
    /// Invariant 5: a lambda is not in `(0, MAX_LAMBDA]`.
    Lambda {
        /// Head of the lambda.
        head: Head,
        /// The lambda.
        lambda: f32,
    },
    /// Invariant 5: a class name is empty, longer than [`NAME_MAX`] bytes, or
    /// `background`.
    Name {
        /// Class index.
        class: usize,
        /// Length of the name in bytes.
        len: usize,
    },
    /// Invariant 5: a class name repeats an earlier one.
    DuplicateName {
        /// Index of the repetition.
        class: usize,
        /// Index of the first class with that name.
        first: usize,
    },
    /// Invariant 5: a prior's mean is not finite.
    Mean {
        /// Class index.
        class: usize,
        /// The mean.
        mean: f32,
    },
    /// Invariant 5: a prior's variance is not finite and positive.
    Variance {
        /// Class index.
        class: usize,
        /// The variance.
        variance: f32,
    },
    /// Invariant 5: a histogram has another bin count than the table's shape.
    BinCount {
        /// Head of the histogram.
        head: Head,
        /// Class index.
        class: usize,
        /// Bin count of the shape.
        expected: usize,
        /// Frequencies found.
        found: usize,
    },
    /// Invariant 5: an edge is not finite.
    EdgeNotFinite {
        /// Head of the histogram.
        head: Head,
        /// Class index.
        class: usize,
        /// Edge index `k` of `e_k`.
        edge: usize,
        /// The edge.
        value: f32,
    },
    /// Invariant 5: an edge is not above the one before it.
    EdgesNotIncreasing {
        /// Head of the histogram.
        head: Head,
        /// Class index.
        class: usize,
        /// Edge index `k` of `e_k`.
        edge: usize,
        /// `e_{k-1}`.
        previous: f32,
        /// `e_k`.
        value: f32,
    },
    /// Invariant 5: a frequency is negative or not finite.
    Frequency {
        /// Head of the histogram.
        head: Head,
        /// Class index.
        class: usize,
        /// Bin index.
        bin: usize,
        /// The frequency.
        value: f32,
    },
    /// Invariant 5: the frequencies do not sum to 1 within
    /// [`FREQUENCY_SUM_TOLERANCE`].
    FrequencySum {
        /// Head of the histogram.
        head: Head,
        /// Class index.
        class: usize,
        /// The sum that is out of tolerance (the `f32` sum in bin order, or the exact sum).
        sum: f64,
    },
    /// DESIGN §1.6: the Bayes lambda is not in `(0, MAX_LAMBDA_BAYES]`.
    BayesLambda {
        /// The lambda.
        lambda: f32,
    },
    /// DESIGN §1.6: the Bayes head has another number of logits than the table's K, or
    /// its categories are neither K nor K + 1.
    BayesCategories {
        /// The table's K.
        classes: usize,
        /// Logits (axes) of the head.
        logits: usize,
        /// Categories of the head.
        categories: usize,
    },
    /// DESIGN §1.6: a category has no training row (or the rows overflow `u64`).
    CategoryRows {
        /// Category index (`K` is `background`).
        category: usize,
        /// Its rows.
        rows: u64,
    },
    /// DESIGN §1.6: a logit's axis has another bin count than the head (or than the
    /// table's shape), or none, or a term of it is missing.
    BayesBins {
        /// Logit index.
        logit: usize,
        /// Bins of the head (or of the shape).
        expected: usize,
        /// Bins found.
        found: usize,
    },
    /// DESIGN §1.6: an edge of a logit's axis is not finite, or not above the one before.
    BayesEdge {
        /// Logit index.
        logit: usize,
        /// Edge index `k` of `e_k`.
        edge: usize,
        /// `e_{k-1}` (`-inf` for `e_0`).
        previous: f32,
        /// `e_k`.
        value: f32,
    },
    /// DESIGN §1.6: a stored log-term `ln(h + lambda)` is not finite.
    BayesTerm {
        /// Category index.
        category: usize,
        /// Logit index.
        logit: usize,
        /// Bin index.
        bin: usize,
        /// The term.
        term: f32,
    },
    /// DESIGN §1.6: the frequency `exp(t) - lambda` implied by a term is negative beyond
    /// [`BAYES_FREQUENCY_TOLERANCE`].
    BayesFrequency {
        /// Category index.
        category: usize,
        /// Logit index.
        logit: usize,
        /// Bin index.
        bin: usize,
        /// The implied frequency, in `f64`.
        frequency: f64,
    },
    /// DESIGN §1.6: the implied frequencies of a (category, logit) do not sum to 1
    /// within [`bayes_frequency_sum_tolerance`].
    BayesFrequencySum {
        /// Category index.
        category: usize,
        /// Logit index.
        logit: usize,
        /// Their sum, in `f64`.
        sum: f64,
    },
    /// DESIGN §1.6: without evidence (every logit outside its axis), a score is not
    /// `OS * pi[c]` within [`bayes_score_tolerance`].
    NotPriorShare {
        /// Class index.
        class: usize,
        /// The score.
        score: f32,
        /// `OS * pi[c]`, in `f64`.
        expected: f64,
    },
}

impl fmt::Display for Violation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::ScoreOutOfRange {
                class,
                score,
                objectness,
            } => write!(
                f,
                "DESIGN §1.3 (1): score of class {class} = {score:e} is outside [0, OS = {objectness:e}]"
            ),
            Self::SumNotObjectness { sum, objectness } => write!(
                f,
                "DESIGN §1.3 (1): the scores sum to {sum:e}, not to OS = {objectness:e} (relative tolerance {SUM_RELATIVE_TOLERANCE:e})"
            ),
            Self::SumAboveObjectness { sum, objectness } => write!(
                f,
                "DESIGN §1.3 (1): the scores sum to {sum:e}, above OS = {objectness:e}"
            ),
            Self::NotUnknown {
                class,
                score,
                expected,
            } => write!(
                f,
                "DESIGN §1.3 (2): without evidence, score of class {class} = {score:e} is not OS / K = {expected:e}"
            ),
            Self::ScoreLowered {
                class,
                before,
                after,
            } => write!(
                f,
                "DESIGN §1.3 (3): more evidence lowered the score of class {class} from {before:e} to {after:e}"
            ),
            Self::MissingError { expected } => write!(
                f,
                "DESIGN §1.3 (4): the input was scored instead of refused with \"{expected}\""
            ),
            Self::WrongError {
                expected: Some(expected),
                found,
            } => write!(
                f,
                "DESIGN §1.3 (4): error \"{found}\" instead of \"{expected}\""
            ),
            Self::WrongError {
                expected: None,
                found,
            } => write!(f, "DESIGN §1.3 (4): a valid input was refused: \"{found}\""),
            Self::ClassCount { expected, found } => write!(
                f,
                "DESIGN §1.3 (5): {found} classes, the table needs {expected}"
            ),
            Self::Lambda { head, lambda } => write!(
                f,
                "DESIGN §1.3 (5): {head} lambda = {lambda:e} is not in (0, {MAX_LAMBDA:e}]"
            ),
            Self::Name { class, len } => write!(
                f,
                "DESIGN §1.3 (5): name of class {class} ({len} bytes) is empty, longer than {NAME_MAX} bytes, or `background`"
            ),
            Self::DuplicateName { class, first } => write!(
                f,
                "DESIGN §1.3 (5): name of class {class} repeats the name of class {first}"
            ),
            Self::Mean { class, mean } => write!(
                f,
                "DESIGN §1.3 (5): prior mean of class {class} = {mean:e} is not finite"
            ),
            Self::Variance { class, variance } => write!(
                f,
                "DESIGN §1.3 (5): prior variance of class {class} = {variance:e} is not finite and positive"
            ),
            Self::BinCount {
                head,
                class,
                expected,
                found,
            } => write!(
                f,
                "DESIGN §1.3 (5): {head} histogram of class {class} has {found} bins, the shape {expected}"
            ),
            Self::EdgeNotFinite {
                head,
                class,
                edge,
                value,
            } => write!(
                f,
                "DESIGN §1.3 (5): {head} histogram of class {class}: edge {edge} = {value:e} is not finite"
            ),
            Self::EdgesNotIncreasing {
                head,
                class,
                edge,
                previous,
                value,
            } => write!(
                f,
                "DESIGN §1.3 (5): {head} histogram of class {class}: edge {edge} = {value:e} is not above edge {} = {previous:e}",
                edge.saturating_sub(1)
            ),
            Self::Frequency {
                head,
                class,
                bin,
                value,
            } => write!(
                f,
                "DESIGN §1.3 (5): {head} histogram of class {class}: frequency {bin} = {value:e} is not finite and >= 0"
            ),
            Self::FrequencySum { head, class, sum } => write!(
                f,
                "DESIGN §1.3 (5): {head} histogram of class {class}: frequencies sum to {sum:e}, not 1 within {FREQUENCY_SUM_TOLERANCE:e}"
            ),
            Self::BayesLambda { lambda } => write!(
                f,
                "DESIGN §1.6: Bayes lambda = {lambda:e} is not in (0, {MAX_LAMBDA_BAYES:e}]"
            ),
            Self::BayesCategories {
                classes,
                logits,
                categories,
            } => write!(
                f,
                "DESIGN §1.6: Bayes head with {logits} logits and {categories} categories in a table of {classes} classes (needs K logits and K or K + 1 categories)"
            ),
            Self::CategoryRows { category, rows } => write!(
                f,
                "DESIGN §1.6: Bayes category {category} has {rows} training rows (none, or the total overflows)"
            ),
            Self::BayesBins {
                logit,
                expected,
                found,
            } => write!(
                f,
                "DESIGN §1.6: Bayes axis of logit {logit} has {found} bins (or terms), the head {expected}"
            ),
            Self::BayesEdge {
                logit,
                edge,
                previous,
                value,
            } => write!(
                f,
                "DESIGN §1.6: Bayes axis of logit {logit}: edge {edge} = {value:e} is not finite or not above {previous:e}"
            ),
            Self::BayesTerm {
                category,
                logit,
                bin,
                term,
            } => write!(
                f,
                "DESIGN §1.6: Bayes term of category {category}, logit {logit}, bin {bin} = {term:e} is not finite"
            ),
            Self::BayesFrequency {
                category,
                logit,
                bin,
                frequency,
            } => write!(
                f,
                "DESIGN §1.6: Bayes frequency of category {category}, logit {logit}, bin {bin} = {frequency:e} is below 0 (tolerance {BAYES_FREQUENCY_TOLERANCE:e})"
            ),
            Self::BayesFrequencySum {
                category,
                logit,
                sum,
            } => write!(
                f,
                "DESIGN §1.6: Bayes frequencies of category {category}, logit {logit} sum to {sum:e}, not 1"
            ),
            Self::NotPriorShare {
                class,
                score,
                expected,
            } => write!(
                f,
                "DESIGN §1.6: without evidence, score of class {class} = {score:e} is not OS * pi = {expected:e}"
            ),
        }
    }
}

impl core::error::Error for Violation {}

/// Invariant 1: every score is in `[0, OS]`, and the scores sum to `OS` ([`Sum::Equal`])
/// or to at most `OS` ([`Sum::AtMost`]), within [`SUM_RELATIVE_TOLERANCE`] of `OS` plus
/// `K` times [`SUBNORMAL_STEP`]. The sum is taken in `f64`.
///
/// # Errors
///
/// [`Violation::ScoreOutOfRange`] for the first score that is NaN or outside `[0, OS]`,
/// then [`Violation::SumNotObjectness`] or [`Violation::SumAboveObjectness`].
pub fn check_scores(scores: &[f32], objectness: f32, sum: Sum) -> Result<(), Violation> {
    let mut total = 0.0f64;
    for (class, &score) in scores.iter().enumerate() {
        if !(score >= 0.0 && score <= objectness) {
            return Err(Violation::ScoreOutOfRange {
                class,
                score,
                objectness,
            });
        }
        total += f64::from(score);
    }
    let os = f64::from(objectness);
    let tolerance = SUM_RELATIVE_TOLERANCE * os + scores.len() as f64 * SUBNORMAL_STEP;
    match sum {
        Sum::Equal if !((total - os).abs() <= tolerance) => Err(Violation::SumNotObjectness {
            sum: total,
            objectness,
        }),
        Sum::AtMost if !(total <= os + tolerance) => Err(Violation::SumAboveObjectness {
            sum: total,
            objectness,
        }),
        _ => Ok(()),
    }
}

/// Invariant 2: every score is exactly `OS / K` (computed in `f32`), bit for bit: the
/// answer of the ML and MAP heads when no class has evidence.
///
/// # Errors
///
/// [`Violation::NotUnknown`] for the first other score.
pub fn check_unknown(scores: &[f32], objectness: f32) -> Result<(), Violation> {
    let expected = objectness / scores.len() as f32;
    match scores
        .iter()
        .position(|s| s.to_bits() != expected.to_bits())
    {
        Some(class) => Err(Violation::NotUnknown {
            class,
            score: scores.get(class).copied().unwrap_or(f32::NAN),
            expected,
        }),
        None => Ok(()),
    }
}

/// Invariant 3: the score of `class` with more evidence (`after`) is not below its
/// score with less (`before`), everything else being the same.
///
/// # Errors
///
/// [`Violation::ScoreLowered`] when `after < before` or either is NaN.
pub fn check_monotone(class: usize, before: f32, after: f32) -> Result<(), Violation> {
    if after >= before {
        Ok(())
    } else {
        Err(Violation::ScoreLowered {
            class,
            before,
            after,
        })
    }
}

/// The error that invariant 4 demands for these inputs: the first NaN logit, else an
/// objectness that is NaN or outside `[0, 1]`; `None` for valid inputs.
#[must_use]
pub fn expected_error(logits: &[f32], objectness: f32) -> Option<InferError> {
    if let Some(i) = logits.iter().position(|x| x.is_nan()) {
        return Some(InferError::NanLogit {
            class: u16::try_from(i).unwrap_or(u16::MAX),
        });
    }
    if !(0.0..=1.0).contains(&objectness) {
        return Some(InferError::Objectness);
    }
    None
}

/// Invariant 4: `found`, the error (if any) that scoring `logits` with `objectness`
/// returned, is exactly [`expected_error`]`(logits, objectness)`.
///
/// # Errors
///
/// [`Violation::MissingError`] when a bad input was scored, [`Violation::WrongError`]
/// when the error differs or a valid input was refused.
pub fn check_error(
    logits: &[f32],
    objectness: f32,
    found: Option<InferError>,
) -> Result<(), Violation> {
    let expected = expected_error(logits, objectness);
    match (expected, found) {
        (Some(expected), None) => Err(Violation::MissingError { expected }),
        (expected, Some(found)) if expected != Some(found) => {
            Err(Violation::WrongError { expected, found })
        }
        _ => Ok(()),
    }
}

/// Invariant 5: both lambdas are in `(0, MAX_LAMBDA]`.
///
/// # Errors
///
/// [`Violation::Lambda`] for the first lambda out of range.
pub fn check_settings(settings: &Settings) -> Result<(), Violation> {
    for (head, lambda) in [
        (Head::Ml, settings.lambda_ml),
        (Head::Map, settings.lambda_map),
    ] {
        if !(lambda > 0.0 && lambda <= MAX_LAMBDA) {
            return Err(Violation::Lambda { head, lambda });
        }
    }
    Ok(())
}

/// Invariant 5: at least two names, each non-empty, at most [`NAME_MAX`] bytes, not
/// `background`, and no name twice.
///
/// # Errors
///
/// [`Violation::ClassCount`], [`Violation::Name`] or [`Violation::DuplicateName`].
pub fn check_names<'a, I>(names: I) -> Result<(), Violation>
where
    I: IntoIterator<Item = &'a str>,
    I::IntoIter: Clone,
{
    let names = names.into_iter();
    let mut count = 0;
    for (class, name) in names.clone().enumerate() {
        count += 1;
        if name.is_empty() || name.len() > NAME_MAX || name == "background" {
            return Err(Violation::Name {
                class,
                len: name.len(),
            });
        }
        if let Some(first) = names.clone().take(class).position(|n| n == name) {
            return Err(Violation::DuplicateName { class, first });
        }
    }
    if count < 2 {
        return Err(Violation::ClassCount {
            expected: 2,
            found: count,
        });
    }
    Ok(())
}

/// Invariant 5: the prior of `class` has a finite mean and a finite positive variance
/// (e.g. `check_prior(i, g.mean(), g.variance())` for a [`Gaussian`](crate::Gaussian)).
///
/// # Errors
///
/// [`Violation::Mean`] or [`Violation::Variance`].
pub fn check_prior(class: usize, mean: f32, variance: f32) -> Result<(), Violation> {
    if !mean.is_finite() {
        return Err(Violation::Mean { class, mean });
    }
    if !(variance.is_finite() && variance > 0.0) {
        return Err(Violation::Variance { class, variance });
    }
    Ok(())
}

/// Invariant 5 for a [`Histogram`]: [`check_bins`] of its edges `e_0 ..= e_B` and its
/// frequencies.
///
/// # Errors
///
/// As [`check_bins`].
pub fn check_histogram<F: AsRef<[f32]>>(
    head: Head,
    class: usize,
    histogram: &Histogram<F>,
    bins: usize,
) -> Result<(), Violation> {
    let edges = (0..=histogram.bins()).map(|k| histogram.edge(k));
    check_bins(head, class, edges, histogram.frequencies(), bins)
}

/// Invariant 5 for the `head` histogram of `class`, given as its edges and frequencies
/// (so that any storage of a histogram can be checked): `bins + 1` edges, finite and
/// strictly increasing; `bins` frequencies, finite and `>= 0`, summing to 1 within
/// [`FREQUENCY_SUM_TOLERANCE`]. The sum is checked twice: in `f32` in bin order (the
/// format's rule), and exactly, where it may differ from the `f32` sum by the rounding
/// of `bins` additions (allowed: `bins * f32::EPSILON`).
///
/// # Errors
///
/// [`Violation::BinCount`] (of the frequencies, or of the edges as `edges - 1`),
/// [`Violation::EdgeNotFinite`], [`Violation::EdgesNotIncreasing`],
/// [`Violation::Frequency`] or [`Violation::FrequencySum`]: the first problem found, in
/// that order.
pub fn check_bins<E: IntoIterator<Item = f32>>(
    head: Head,
    class: usize,
    edges: E,
    frequencies: &[f32],
    bins: usize,
) -> Result<(), Violation> {
    let wrong_count = |found| Violation::BinCount {
        head,
        class,
        expected: bins,
        found,
    };
    if frequencies.len() != bins {
        return Err(wrong_count(frequencies.len()));
    }
    let mut previous = f32::NEG_INFINITY;
    let mut count = 0;
    for (edge, value) in edges.into_iter().enumerate() {
        count += 1;
        if !value.is_finite() {
            return Err(Violation::EdgeNotFinite {
                head,
                class,
                edge,
                value,
            });
        }
        if !(value > previous) {
            return Err(Violation::EdgesNotIncreasing {
                head,
                class,
                edge,
                previous,
                value,
            });
        }
        previous = value;
    }
    if count != bins + 1 {
        return Err(wrong_count(count.saturating_sub(1)));
    }
    let (mut sum32, mut sum64) = (0.0f32, 0.0f64);
    for (bin, &value) in frequencies.iter().enumerate() {
        if !(value.is_finite() && value >= 0.0) {
            return Err(Violation::Frequency {
                head,
                class,
                bin,
                value,
            });
        }
        sum32 += value;
        sum64 += f64::from(value);
    }
    let slack = bins as f64 * f64::from(f32::EPSILON);
    let sum = if !((sum32 - 1.0).abs() <= FREQUENCY_SUM_TOLERANCE) {
        f64::from(sum32)
    } else if !((sum64 - 1.0).abs() <= f64::from(FREQUENCY_SUM_TOLERANCE) + slack) {
        sum64
    } else {
        return Ok(());
    };
    Err(Violation::FrequencySum { head, class, sum })
}

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
/// [`Violation::BayesTerm`], [`Violation::BayesFrequency`] or
/// [`Violation::BayesFrequencySum`], in that order.
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
    Ok(())
}

/// Invariant 5 for a fixed-size table: settings, names, and every class's prior and
/// histograms (of `B_ML` and `B_MAP` bins), through the public accessors; and, when the
/// table has a Bayes head, [`check_bayes`] with its shape `B_BAYES` bins and `C`
/// categories.
///
/// # Errors
///
/// The first [`Violation`] of [`check_settings`], [`check_names`], [`check_prior`],
/// [`check_histogram`] or [`check_bayes`]; [`Violation::ClassCount`] when an accessor has
/// no class `i < K`; [`Violation::BayesBins`] or [`Violation::BayesCategories`] when the
/// Bayes head has another shape than `B_BAYES` and `C`.
pub fn check_table<
    const K: usize,
    const B_ML: usize,
    const B_MAP: usize,
    const B_BAYES: usize,
    const C: usize,
>(
    table: &Table<K, B_ML, B_MAP, B_BAYES, C>,
) -> Result<(), Violation> {
    check_settings(table.settings())?;
    let missing = |found| Violation::ClassCount { expected: K, found };
    let names = (0..K).map(|i| table.class_name(i).unwrap_or(""));
    if let Some(found) = (0..K).position(|i| table.class_name(i).is_none()) {
        return Err(missing(found));
    }
    check_names(names)?;
    for class in 0..K {
        let (Some(prior), Some(ml), Some(map)) = (
            table.prior(class),
            table.ml_histogram(class),
            table.map_histogram(class),
        ) else {
            return Err(missing(class));
        };
        check_prior(class, prior.mean(), prior.variance())?;
        check_histogram(Head::Ml, class, ml, B_ML)?;
        check_histogram(Head::Map, class, map, B_MAP)?;
    }
    if let Some(head) = table.bayes_head() {
        check_bayes(&head, K)?;
        if head.bins() != B_BAYES {
            return Err(Violation::BayesBins {
                logit: 0,
                expected: B_BAYES,
                found: head.bins(),
            });
        }
        if head.categories() != C {
            return Err(Violation::BayesCategories {
                classes: K,
                logits: head.logits(),
                categories: head.categories(),
            });
        }
    }
    Ok(())
}

/// Invariant 5 for a run-time shaped table, as [`check_table`] does for a fixed one.
///
/// # Errors
///
/// As [`check_table`]; [`Violation::ClassCount`] when the names, priors or histograms
/// are fewer than [`DynTable::k`](crate::host::DynTable::k).
#[cfg(feature = "std")]
#[cfg_attr(docsrs, doc(cfg(feature = "std")))]
pub fn check_dyn_table(table: &crate::host::DynTable) -> Result<(), Violation> {
    let k = table.k();
    check_settings(table.settings())?;
    for found in [
        table.class_names().len(),
        table.priors().len(),
        table.ml_histograms().len(),
        table.map_histograms().len(),
    ] {
        if found != k {
            return Err(Violation::ClassCount { expected: k, found });
        }
    }
    // `class_names()` cannot be replayed; the names again, through `spec`.
    check_names((0..k).map(|i| table.spec(i).map_or("", |s| s.name)))?;
    let classes = table
        .priors()
        .iter()
        .zip(table.ml_histograms())
        .zip(table.map_histograms());
    for (class, ((prior, ml), map)) in classes.enumerate() {
        check_prior(class, prior.mean(), prior.variance())?;
        check_histogram(Head::Ml, class, ml, table.bins_ml())?;
        check_histogram(Head::Map, class, map, table.bins_map())?;
    }
    if let Some(head) = table.bayes() {
        check_bayes(&head, k)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use std::string::ToString;

    use super::*;
    use crate::{ClassSpec, EdgeMode, UpperTail};

    fn settings(lambda_ml: f32, lambda_map: f32) -> Settings {
        Settings {
            lambda_ml,
            lambda_map,
            edge_mode: EdgeMode::Linspace,
            upper_tail: UpperTail::Zero,
        }
    }

    fn spec(name: &str) -> ClassSpec<'_, [f32; 2], [f32; 1]> {
        ClassSpec {
            name,
            rows: 10,
            mean: 0.5,
            variance: 0.25,
            ml_range: (0.0, 1.0),
            ml_freqs: [0.25, 0.75],
            map_range: (-1.0, 1.0),
            map_freqs: [1.0],
        }
    }

    /// Asserts that `got` is `Err(want)` and that its message cites invariant `n` and
    /// holds `needle`.
    fn fails(got: Result<(), Violation>, want: Violation, n: u8, needle: &str) {
        assert_eq!(got, Err(want));
        let msg = want.to_string();
        let cite = std::format!("DESIGN §1.3 ({n}): ");
        assert!(msg.starts_with(&cite), "{msg}");
        assert!(msg.contains(needle), "{msg}");
    }

    #[test]
    fn scores_in_range_summing_to_objectness_pass() {
        assert_eq!(check_scores(&[0.25, 0.5, 0.15], 0.9, Sum::Equal), Ok(()));
        // 1e-5 relative of 0.9 is 9e-6: a sum 8.1e-6 above passes.
        assert_eq!(check_scores(&[0.45, 0.450_008_1], 0.9, Sum::Equal), Ok(()));
        assert_eq!(check_scores(&[0.2, 0.3], 0.9, Sum::AtMost), Ok(()));
        assert_eq!(check_scores(&[0.0, -0.0], 0.0, Sum::Equal), Ok(()));
        // A subnormal objectness: one rounding step per score is allowed.
        let step = f32::from_bits(1);
        assert_eq!(
            check_scores(&[step, step], f32::from_bits(3), Sum::Equal),
            Ok(())
        );
        assert_eq!(check_scores(&[], 0.5, Sum::AtMost), Ok(()));
    }

    #[test]
    fn each_score_violation_is_reported() {
        fails(
            check_scores(&[0.5, 0.6], 0.5, Sum::Equal),
            Violation::ScoreOutOfRange {
                class: 1,
                score: 0.6,
                objectness: 0.5,
            },
            1,
            "score of class 1 = 6e-1 is outside [0, OS = 5e-1]",
        );
        fails(
            check_scores(&[0.0, -1e-30], 1.0, Sum::AtMost),
            Violation::ScoreOutOfRange {
                class: 1,
                score: -1e-30,
                objectness: 1.0,
            },
            1,
            "class 1",
        );
        let nan = check_scores(&[f32::NAN, 1.0], 1.0, Sum::Equal);
        assert!(
            matches!(nan, Err(Violation::ScoreOutOfRange { class: 0, score, .. }) if score.is_nan()),
            "{nan:?}"
        );
        // 1.8e-5 above 0.9: out of the 9e-6 tolerance.
        fails(
            check_scores(&[0.45, 0.450_018], 0.9, Sum::Equal),
            Violation::SumNotObjectness {
                sum: f64::from(0.45f32) + f64::from(0.450_018f32),
                objectness: 0.9,
            },
            1,
            "not to OS = 9e-1",
        );
        fails(
            check_scores(&[0.2, 0.3], 0.9, Sum::Equal),
            Violation::SumNotObjectness {
                sum: f64::from(0.2f32) + f64::from(0.3f32),
                objectness: 0.9,
            },
            1,
            "the scores sum to 5",
        );
        fails(
            check_scores(&[0.45, 0.46], 0.9, Sum::AtMost),
            Violation::SumAboveObjectness {
                sum: f64::from(0.45f32) + f64::from(0.46f32),
                objectness: 0.9,
            },
            1,
            "above OS = 9e-1",
        );
    }

    #[test]
    fn unknown_must_be_exactly_os_over_k() {
        let third = 0.9f32 / 3.0;
        assert_eq!(check_unknown(&[third; 3], 0.9), Ok(()));
        let quarter = 0.25f32;
        let off = quarter.next_up();
        fails(
            check_unknown(&[quarter, quarter, off, quarter], 1.0),
            Violation::NotUnknown {
                class: 2,
                score: off,
                expected: quarter,
            },
            2,
            "score of class 2 = 2.5000003e-1 is not OS / K = 2.5e-1",
        );
        let off = third.next_up();
        fails(
            check_unknown(&[third, off, third], 0.9),
            Violation::NotUnknown {
                class: 1,
                score: off,
                expected: third,
            },
            2,
            "without evidence, score of class 1",
        );
    }

    #[test]
    fn monotone_allows_equal_and_higher_scores_only() {
        assert_eq!(check_monotone(2, 0.25, 0.25), Ok(()));
        assert_eq!(check_monotone(2, 0.25, 0.5), Ok(()));
        let lower = 0.25f32.next_down();
        fails(
            check_monotone(2, 0.25, lower),
            Violation::ScoreLowered {
                class: 2,
                before: 0.25,
                after: lower,
            },
            3,
            "lowered the score of class 2 from 2.5e-1 to 2.4999999e-1",
        );
        assert!(check_monotone(0, 0.25, f32::NAN).is_err());
        assert!(check_monotone(0, f32::NAN, 0.25).is_err());
    }

    #[test]
    fn bad_input_must_be_the_right_error() {
        let nan_logit = InferError::NanLogit { class: 1 };
        // The first NaN logit comes before a bad objectness.
        assert_eq!(
            expected_error(&[0.0, f32::NAN, f32::NAN], 2.0),
            Some(nan_logit)
        );
        // ±inf logits and a -0 objectness are valid.
        assert_eq!(
            expected_error(&[f32::INFINITY, f32::NEG_INFINITY], -0.0),
            None
        );
        for os in [f32::NAN, -1e-45, 1.0f32.next_up(), f32::INFINITY] {
            assert_eq!(
                expected_error(&[0.0, 1.0], os),
                Some(InferError::Objectness)
            );
        }
        assert_eq!(check_error(&[0.0, 1.0], 1.0, None), Ok(()));
        assert_eq!(check_error(&[0.0, f32::NAN], 1.0, Some(nan_logit)), Ok(()));
        fails(
            check_error(&[0.0, f32::NAN], 1.0, None),
            Violation::MissingError {
                expected: nan_logit,
            },
            4,
            "scored instead of refused",
        );
        fails(
            check_error(&[0.0, f32::NAN], 1.5, Some(InferError::Objectness)),
            Violation::WrongError {
                expected: Some(nan_logit),
                found: InferError::Objectness,
            },
            4,
            "instead of",
        );
        fails(
            check_error(&[0.0, 1.0], 1.0, Some(InferError::Objectness)),
            Violation::WrongError {
                expected: None,
                found: InferError::Objectness,
            },
            4,
            "a valid input was refused",
        );
    }

    #[test]
    fn valid_tables_pass() {
        let t =
            Table::<2, 2, 1>::from_parts(settings(1e-3, 1e-6), [spec("car"), spec("bus")]).unwrap();
        assert_eq!(check_table(&t), Ok(()));
        let shipped =
            Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../tables/default.mlmap"))
                .unwrap();
        assert_eq!(check_table(&shipped), Ok(()));
        #[cfg(feature = "std")]
        assert_eq!(
            check_dyn_table(&crate::host::DynTable::from_table(&shipped)),
            Ok(())
        );
        let h = Histogram::new(-1.0, 1.0, [0.5f32, 0.0, 0.5]).unwrap();
        assert_eq!(check_histogram(Head::Ml, 0, &h, 3), Ok(()));
    }

    #[test]
    fn each_settings_names_and_prior_violation_is_reported() {
        fails(
            check_settings(&settings(0.0, 1.0)),
            Violation::Lambda {
                head: Head::Ml,
                lambda: 0.0,
            },
            5,
            "ML lambda = 0e0 is not in (0, 1e6]",
        );
        fails(
            check_settings(&settings(1.0, 2e6)),
            Violation::Lambda {
                head: Head::Map,
                lambda: 2e6,
            },
            5,
            "MAP lambda = 2e6",
        );
        let nan = check_settings(&settings(1.0, f32::NAN));
        assert!(
            matches!(nan, Err(Violation::Lambda { head: Head::Map, lambda }) if lambda.is_nan()),
            "{nan:?}"
        );
        assert_eq!(check_settings(&settings(MAX_LAMBDA, 1e-30)), Ok(()));

        assert_eq!(check_names(["car", "bus"]), Ok(()));
        fails(
            check_names(["car", "", "bus"]),
            Violation::Name { class: 1, len: 0 },
            5,
            "name of class 1 (0 bytes)",
        );
        fails(
            check_names(["car", "background"]),
            Violation::Name { class: 1, len: 10 },
            5,
            "or `background`",
        );
        let long = "x".repeat(NAME_MAX + 1);
        fails(
            check_names(["car", long.as_str()]),
            Violation::Name { class: 1, len: 32 },
            5,
            "longer than 31 bytes",
        );
        assert_eq!(check_names(["car", &long[1..]]), Ok(()));
        fails(
            check_names(["car", "bus", "car"]),
            Violation::DuplicateName { class: 2, first: 0 },
            5,
            "name of class 2 repeats the name of class 0",
        );
        fails(
            check_names(["car"]),
            Violation::ClassCount {
                expected: 2,
                found: 1,
            },
            5,
            "1 classes, the table needs 2",
        );

        assert_eq!(check_prior(3, -1e30, f32::MIN_POSITIVE), Ok(()));
        fails(
            check_prior(3, f32::INFINITY, 1.0),
            Violation::Mean {
                class: 3,
                mean: f32::INFINITY,
            },
            5,
            "prior mean of class 3 = inf is not finite",
        );
        for variance in [0.0, -1.0, f32::INFINITY] {
            fails(
                check_prior(3, 0.0, variance),
                Violation::Variance { class: 3, variance },
                5,
                "prior variance of class 3",
            );
        }
        assert!(check_prior(0, f32::NAN, 1.0).is_err());
        assert!(check_prior(0, 0.0, f32::NAN).is_err());
    }

    #[test]
    fn each_histogram_violation_is_reported() {
        let ok = check_bins(Head::Ml, 1, [0.0, 0.5, 1.0], &[0.25, 0.75], 2);
        assert_eq!(ok, Ok(()));
        fails(
            check_bins(Head::Map, 4, [0.0, 0.5, 1.0], &[0.25, 0.75], 3),
            Violation::BinCount {
                head: Head::Map,
                class: 4,
                expected: 3,
                found: 2,
            },
            5,
            "MAP histogram of class 4 has 2 bins, the shape 3",
        );
        fails(
            check_bins(Head::Ml, 1, [0.0, 1.0], &[0.25, 0.75], 2),
            Violation::BinCount {
                head: Head::Ml,
                class: 1,
                expected: 2,
                found: 1,
            },
            5,
            "has 1 bins",
        );
        fails(
            check_bins(Head::Ml, 1, [0.0, f32::INFINITY, 1.0], &[0.25, 0.75], 2),
            Violation::EdgeNotFinite {
                head: Head::Ml,
                class: 1,
                edge: 1,
                value: f32::INFINITY,
            },
            5,
            "ML histogram of class 1: edge 1 = inf is not finite",
        );
        fails(
            check_bins(Head::Map, 0, [0.0, 1.0, 1.0], &[0.25, 0.75], 2),
            Violation::EdgesNotIncreasing {
                head: Head::Map,
                class: 0,
                edge: 2,
                previous: 1.0,
                value: 1.0,
            },
            5,
            "MAP histogram of class 0: edge 2 = 1e0 is not above edge 1 = 1e0",
        );
        fails(
            check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[1.5, -0.5], 2),
            Violation::Frequency {
                head: Head::Ml,
                class: 2,
                bin: 1,
                value: -0.5,
            },
            5,
            "frequency 1 = -5e-1 is not finite and >= 0",
        );
        assert!(check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[f32::NAN, 1.0], 2).is_err());
        // 1e-4 is the tolerance: 0.25 + 0.7502 is out, 0.25 + 0.75009 in.
        fails(
            check_bins(Head::Ml, 2, [0.0, 0.5, 1.0], &[0.25, 0.7502], 2),
            Violation::FrequencySum {
                head: Head::Ml,
                class: 2,
                sum: f64::from(0.25f32 + 0.7502f32),
            },
            5,
            "ML histogram of class 2: frequencies sum to 1.0002",
        );
        let edges = [0.0, 0.5, 1.0];
        assert_eq!(check_bins(Head::Ml, 2, edges, &[0.25, 0.750_09], 2), Ok(()));
    }

    /// Asserts that `got` is `Err(want)` and that its message cites DESIGN §1.6 and holds
    /// `needle`.
    fn fails_bayes(got: Result<(), Violation>, want: Violation, needle: &str) {
        assert_eq!(got, Err(want));
        let msg = want.to_string();
        assert!(msg.starts_with("DESIGN §1.6: "), "{msg}");
        assert!(msg.contains(needle), "{msg}");
    }

    fn shipped() -> Table<3, 22, 17, 22, 4> {
        Table::from_bytes(include_bytes!("../tables/default.mlmap")).unwrap()
    }

    #[test]
    fn shipped_bayes_head_passes_and_needs_its_k() {
        let t = shipped();
        let head = t.bayes_head().unwrap();
        assert_eq!(check_bayes(&head, 3), Ok(()));
        assert_eq!(bayes_sum(&head), Sum::AtMost);
        fails_bayes(
            check_bayes(&head, 2),
            Violation::BayesCategories {
                classes: 2,
                logits: 3,
                categories: 4,
            },
            "Bayes head with 3 logits and 4 categories in a table of 2 classes",
        );
        assert!(check_bayes(&head, 4).is_err());
        // Scores: at most OS (the background takes a share), and the prior's shares
        // without evidence.
        let s = t.bayes(&[5.1, -2.0, -1.3], 0.93).unwrap();
        assert_eq!(check_scores(&s.0, 0.93, bayes_sum(&head)), Ok(()));
        let unknown = t.bayes(&[1e30, -1e30, f32::INFINITY], 0.93).unwrap();
        assert_eq!(check_prior_share(&unknown.0, 0.93, &head), Ok(()));
        let mut off = unknown.0;
        off[1] *= 1.001;
        assert!(matches!(
            check_prior_share(&off, 0.93, &head),
            Err(Violation::NotPriorShare { class: 1, .. })
        ));
        assert_eq!(
            check_prior_share(&off[..2], 0.93, &head),
            Err(Violation::ClassCount {
                expected: 3,
                found: 2
            })
        );
    }

    #[test]
    fn each_bayes_axis_and_term_violation_is_reported() {
        assert_eq!(check_bayes_axis(0, [-1.0, 0.0, 2.0], 2), Ok(()));
        fails_bayes(
            check_bayes_axis(1, [-1.0, f32::INFINITY, 2.0], 2),
            Violation::BayesEdge {
                logit: 1,
                edge: 1,
                previous: -1.0,
                value: f32::INFINITY,
            },
            "Bayes axis of logit 1: edge 1 = inf is not finite or not above -1e0",
        );
        fails_bayes(
            check_bayes_axis(2, [-1.0, 0.0, 0.0], 2),
            Violation::BayesEdge {
                logit: 2,
                edge: 2,
                previous: 0.0,
                value: 0.0,
            },
            "edge 2 = 0e0",
        );
        fails_bayes(
            check_bayes_axis(0, [-1.0, 0.0], 2),
            Violation::BayesBins {
                logit: 0,
                expected: 2,
                found: 1,
            },
            "Bayes axis of logit 0 has 1 bins (or terms), the head 2",
        );
        // lambda = 0.5, frequencies 0.25 and 0.75: terms ln 0.75 and ln 1.25.
        let ok = [0.75f64.ln() as f32, 1.25f64.ln() as f32];
        assert_eq!(check_bayes_terms(1, 2, 0.5, ok, 2), Ok(()));
        fails_bayes(
            check_bayes_terms(1, 2, 0.5, [f32::INFINITY, 0.0], 2),
            Violation::BayesTerm {
                category: 1,
                logit: 2,
                bin: 0,
                term: f32::INFINITY,
            },
            "Bayes term of category 1, logit 2, bin 0 = inf is not finite",
        );
        let nan = check_bayes_terms(1, 2, 0.5, [0.0, f32::NAN], 2);
        assert!(
            matches!(nan, Err(Violation::BayesTerm { bin: 1, term, .. }) if term.is_nan()),
            "{nan:?}"
        );
        // Frequency -0.1 (term ln 0.4), then 1.1 (ln 1.6).
        let negative = check_bayes_terms(0, 0, 0.5, [0.4f32.ln(), 1.6f32.ln()], 2);
        assert!(
            matches!(negative, Err(Violation::BayesFrequency { category: 0, logit: 0, bin: 0, frequency })
                if (frequency + 0.1).abs() < 1e-6),
            "{negative:?}"
        );
        // Within the stated tolerance: -1.5e-5 and 1 + 1.5e-5 pass.
        let edge = [(0.5f64 - 1.5e-5).ln() as f32, (1.5f64 + 1.5e-5).ln() as f32];
        assert_eq!(check_bayes_terms(0, 0, 0.5, edge, 2), Ok(()));
        // Sum 0.9: out of 1e-4 + 2 * 2e-5.
        let low = check_bayes_terms(3, 1, 0.5, [0.75f32.ln(), 1.15f32.ln()], 2);
        assert!(
            matches!(low, Err(Violation::BayesFrequencySum { category: 3, logit: 1, sum })
                if (sum - 0.9).abs() < 1e-6),
            "{low:?}"
        );
        assert!(low
            .unwrap_err()
            .to_string()
            .contains("frequencies of category 3, logit 1 sum to "));
        // Two bins: a sum of 1.00015 is out (tolerance 1.4e-4), 1.00013 in.
        let near = |d: f64| [0.75f64.ln() as f32, (1.25f64 + d).ln() as f32];
        assert!(check_bayes_terms(0, 0, 0.5, near(1.5e-4), 2).is_err());
        assert_eq!(check_bayes_terms(0, 0, 0.5, near(1.3e-4), 2), Ok(()));
        assert!((bayes_frequency_sum_tolerance(3) - 1.6e-4).abs() < 1e-10);
        fails_bayes(
            check_bayes_terms(0, 4, 0.5, ok, 3),
            Violation::BayesBins {
                logit: 4,
                expected: 3,
                found: 2,
            },
            "logit 4 has 2 bins",
        );
        for (v, needle) in [
            (
                Violation::BayesLambda { lambda: 2.0 },
                "Bayes lambda = 2e0 is not in (0, 1e0]",
            ),
            (
                Violation::CategoryRows {
                    category: 3,
                    rows: 0,
                },
                "Bayes category 3 has 0 training rows",
            ),
            (
                Violation::NotPriorShare {
                    class: 1,
                    score: 0.5,
                    expected: 0.25,
                },
                "score of class 1 = 5e-1 is not OS * pi = 2.5e-1",
            ),
            (
                Violation::BayesFrequency {
                    category: 1,
                    logit: 0,
                    bin: 2,
                    frequency: -0.5,
                },
                "category 1, logit 0, bin 2 = -5e-1 is below 0",
            ),
        ] {
            let msg = v.to_string();
            assert!(
                msg.starts_with("DESIGN §1.6: ") && msg.contains(needle),
                "{msg}"
            );
        }
    }

    /// A K = 2 table whose Bayes head has 2 bins over [0, 2] per logit, lambda 0.5, rows
    /// 1 and 3 (and 4 background rows with `background`); class 0 puts logit 0 in bin 0
    /// and logit 1 in bin 1, class 1 (and background) half and half.
    #[cfg(feature = "std")]
    fn hand_table(background: bool) -> crate::host::DynTable {
        use std::vec;
        use std::vec::Vec;
        let class = |name| ClassSpec {
            name,
            rows: 10,
            mean: 0.5,
            variance: 0.25,
            ml_range: (0.0, 1.0),
            ml_freqs: vec![0.25, 0.75],
            map_range: (-1.0, 1.0),
            map_freqs: vec![1.0],
        };
        let t = crate::host::DynTable::new(settings(1e-3, 1e-3), vec![class("car"), class("bus")])
            .unwrap();
        let mut rows = vec![1, 3];
        // h per category for (logit 0, bin 0), (0, 1), (1, 0), (1, 1).
        let mut h: Vec<[f64; 4]> = vec![[1.0, 0.0, 0.0, 1.0], [0.5; 4]];
        if background {
            rows.push(4);
            h.push([0.5; 4]);
        }
        let mut terms = Vec::new();
        for i in 0..4 {
            for hc in &h {
                terms.push(libm::log(hc[i] + 0.5) as f32);
            }
        }
        t.with_bayes(crate::host::BayesSpec {
            lambda: 0.5,
            rows,
            ranges: vec![(0.0, 2.0); 2],
            terms,
        })
        .unwrap()
    }

    #[cfg(feature = "std")]
    #[test]
    fn bayes_checks_by_hand() {
        for background in [false, true] {
            let t = hand_table(background);
            assert_eq!(check_dyn_table(&t), Ok(()));
            let head = t.bayes().unwrap();
            let sum = bayes_sum(&head);
            assert_eq!(sum, if background { Sum::AtMost } else { Sum::Equal });
            // Outside both axes: OS * pi = 0.8 * [1/4, 3/4] or 0.8 * [1/8, 3/8].
            let (mut out, mut scratch) = ([0.0f32; 2], [0.0f32; 3]);
            let scratch = &mut scratch[..head.categories()];
            t.bayes_into::<crate::Libm>(&[-1.0, 3.0], 0.8, &mut out, scratch)
                .unwrap();
            let want: [f32; 2] = if background { [0.1, 0.3] } else { [0.2, 0.6] };
            for (o, w) in out.iter().zip(want) {
                assert!((o - w).abs() < 1e-7, "{out:?}");
            }
            assert_eq!(check_prior_share(&out, 0.8, &head), Ok(()));
            assert_eq!(check_scores(&out, 0.8, sum), Ok(()));
            // Logit 0 in bin 0, logit 1 in bin 1: masses 1/4 * 1.5 * 1.5 = 0.5625 for
            // class 0, 3/4 * 1 * 1 = 0.75 for class 1 (and 1 for background): scores
            // 0.8 * [3/7, 4/7], or 0.8 * [0.5625, 0.75] / 2.3125 with background.
            let x = [0.5f32, 1.5];
            t.bayes_into::<crate::Libm>(&x, 0.8, &mut out, scratch)
                .unwrap();
            let want = if background {
                [0.8 * 0.5625 / 2.3125, 0.8 * 0.75 / 2.3125]
            } else {
                [0.8 * 3.0 / 7.0, 0.8 * 4.0 / 7.0]
            };
            let mut reference = [0.0f64; 2];
            let mut s64 = [0.0f64; 3];
            assert!(bayes_reference(
                &head,
                &x,
                0.8,
                &mut reference,
                &mut s64[..head.categories()]
            ));
            for i in 0..2 {
                // The stored terms are f32: about 1e-8 from the exact values.
                assert!((reference[i] - want[i]).abs() < 1e-7, "{reference:?}");
                assert!((f64::from(out[i]) - want[i]).abs() < 1e-7, "{out:?}");
            }
            assert_eq!(bayes_mismatch(&head, &out, &reference, 0.8), None);
            assert_eq!(check_scores(&out, 0.8, sum), Ok(()));
            // Without evidence the rule is the prior, not these scores.
            assert!(check_prior_share(&out, 0.8, &head).is_err());
            let mut off = out;
            off[1] *= 1.01;
            assert_eq!(bayes_mismatch(&head, &off, &reference, 0.8), Some(1));
            assert!(!bayes_reference(
                &head,
                &x[..1],
                0.8,
                &mut reference,
                &mut s64
            ));
            // The tolerance: K = 2, lambda = 0.5, |ln(1/8)| = 2.08 with background.
            let tol = bayes_score_tolerance(&head);
            assert!(tol > 1e-5 && tol < 1e-4, "{tol:e}");
        }
    }
}
