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
//!
//! ```
//! use mlmap::invariants::{check_scores, check_table, check_unknown, Sum};
//! use mlmap::Table;
//!
//! let table = Table::<3, 22, 17, 22, 4>::from_bytes(include_bytes!("../tables/default.mlmap"))?;
//! check_table(&table)?;
//! let scores = table.map(&[5.1, -2.0, -1.3], 0.93)?;
//! check_scores(&scores.0, 0.93, Sum::Equal)?;
//! // Far outside every histogram: the "I don't know" answer.
//! let unknown = table.ml(&[1e30, 1e30, 1e30], 0.93)?;
//! check_unknown(&unknown.0, 0.93)?;
//! # Ok::<(), Box<dyn core::error::Error>>(())
//! ```

use core::fmt;

use crate::{
    Head, Histogram, InferError, Settings, Table, FREQUENCY_SUM_TOLERANCE, MAX_LAMBDA, NAME_MAX,
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

/// A broken invariant of DESIGN §1.3: which one, where, and the values.
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

/// Invariant 5 for a fixed-size table: settings, names, and every class's prior and
/// histograms (of `B_ML` and `B_MAP` bins), through the public accessors.
///
/// # Errors
///
/// The first [`Violation`] of [`check_settings`], [`check_names`], [`check_prior`] or
/// [`check_histogram`]; [`Violation::ClassCount`] when an accessor has no class `i < K`.
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
}
