//! [`Violation`]: which invariant broke, where, and the values; its one-sentence `Display`.

use super::*;

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
    /// DESIGN §1.8: the open head's decided class is not the detector's (the largest
    /// logit, the lower index among equal ones).
    NotDetectorDecision {
        /// The largest logit's class.
        expected: usize,
        /// The decided class.
        found: usize,
    },
    /// DESIGN §1.8: the open head's temperature or epsilon is out of range.
    OpenParams {
        /// The stored temperature.
        temperature: f32,
        /// The stored epsilon.
        epsilon: f32,
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
            Self::NotDetectorDecision { expected, found } => write!(
                f,
                "DESIGN §1.8: the open head decided class {found}, not the largest logit's class {expected}"
            ),
            Self::OpenParams {
                temperature,
                epsilon,
            } => write!(
                f,
                "DESIGN §1.8: open head temperature {temperature:e} or epsilon {epsilon:e} out of range"
            ),
        }
    }
}

impl core::error::Error for Violation {}
