//! What each row contributes: its confidence, its decision and whether it is correct
//! (DESIGN §1.5), and the checks of the inputs.

use super::MetricsError;

/// What one row contributes to the confidence metrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// `conf = max_i s_i`.
    pub conf: f64,
    /// The predicted class, from [`decision`].
    pub pred: usize,
    /// Whether the row is a true positive (labelled `pred`).
    pub correct: bool,
}

/// The predicted class of a row from its scores and its logits (DESIGN §1.7): the
/// index of the largest score; a tie of the largest scores goes to the larger logit
/// among the tied classes, then to the lowest index (as [`mlmap_core::decide`]).
///
/// Every decision of the host (metrics, plots, the tuner, `apply`'s `*_pred`) is made
/// here. `logits` are the row's logits in class order; without them (empty) ties go to
/// the lowest index.
///
/// # Examples
///
/// ```
/// use mlmap_host::metrics::decision;
///
/// assert_eq!(decision(&[0.2, 0.7, 0.1], &[0.0, 1.0, -1.0]), 1);
/// // Every histogram said "I don't know": OS / K each, the logits decide.
/// assert_eq!(decision(&[0.25, 0.25, 0.25], &[-1.0, 3.0, 2.0]), 1);
/// assert_eq!(decision::<f64, f64>(&[0.25, 0.25], &[]), 0);
/// assert_eq!(decision::<f64, f64>(&[], &[]), 0);
/// ```
pub fn decision<S, L>(scores: &[S], logits: &[L]) -> usize
where
    S: Copy + PartialOrd,
    L: Copy + PartialOrd,
{
    mlmap_core::decide(scores, logits)
}

/// The [`Outcome`] of one row (not checked; see [`outcomes`]).
pub(super) fn outcome<S, L>(scores: &[S], logits: &[L], label: Option<usize>) -> Outcome
where
    S: Copy + PartialOrd + Into<f64>,
    L: Copy + PartialOrd,
{
    let pred = decision(scores, logits);
    // The decision's score is the largest; `+ 0.0` turns -0.0 into 0.0, so equal
    // confidences have equal bits.
    let conf = scores.get(pred).map_or(0.0, |&s| s.into()) + 0.0;
    Outcome {
        conf,
        pred,
        correct: label == Some(pred),
    }
}

/// Checks the shape and every score; returns `N`.
pub(super) fn check_scores(scores: &[f64], k: usize) -> Result<usize, MetricsError> {
    if k == 0 || !scores.len().is_multiple_of(k) {
        return Err(MetricsError::Shape);
    }
    if scores.is_empty() {
        return Err(MetricsError::Empty);
    }
    match scores.iter().position(|s| !(0.0..=1.0).contains(s)) {
        Some(i) => Err(MetricsError::Score {
            row: i / k,
            class: i % k,
        }),
        None => Ok(scores.len() / k),
    }
}

/// Checks scores, logits (`N x K` or empty) and labels; returns `N`.
pub(super) fn check(
    scores: &[f64],
    logits: &[f64],
    k: usize,
    labels: &[Option<usize>],
) -> Result<usize, MetricsError> {
    if k == 0
        || !scores.len().is_multiple_of(k)
        || scores.len() / k != labels.len()
        || !(logits.is_empty() || logits.len() == scores.len())
    {
        return Err(MetricsError::Shape);
    }
    let n = check_scores(scores, k)?;
    match labels.iter().position(|l| l.is_some_and(|c| c >= k)) {
        Some(row) => Err(MetricsError::Label { row }),
        None => Ok(n),
    }
}

/// The rows of checked logits: `N` rows of `K`, or `N` empty rows.
pub(super) fn logit_rows(logits: &[f64], k: usize, n: usize) -> impl Iterator<Item = &[f64]> {
    let empty: &[f64] = &[];
    logits.chunks_exact(k).chain(core::iter::repeat_n(
        empty,
        if logits.is_empty() { n } else { 0 },
    ))
}

/// The [`Outcome`] of every row: `conf`, predicted class, correctness, deciding
/// without logits (ties of the largest score go to the lowest index); see
/// [`outcomes_with_logits`].
///
/// # Errors
///
/// * [`MetricsError::Shape`]: `k` is 0, `scores.len()` is not `labels.len() * k`.
/// * [`MetricsError::Empty`]: no rows.
/// * [`MetricsError::Score`]: a score is not a number in `[0, 1]`.
/// * [`MetricsError::Label`]: a label is not a class index.
///
/// # Panics
///
/// Never.
pub fn outcomes(
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
) -> Result<Vec<Outcome>, MetricsError> {
    outcomes_with_logits(scores, &[], k, labels)
}

/// The [`Outcome`] of every row, each decided by [`decision`] from its scores and its
/// logits (`N x K`, row-major, or empty).
///
/// # Errors
///
/// As [`outcomes`]; [`MetricsError::Shape`] also when `logits` is neither empty nor
/// as long as `scores`.
///
/// # Panics
///
/// Never.
pub fn outcomes_with_logits(
    scores: &[f64],
    logits: &[f64],
    k: usize,
    labels: &[Option<usize>],
) -> Result<Vec<Outcome>, MetricsError> {
    let n = check(scores, logits, k, labels)?;
    Ok(scores
        .chunks_exact(k)
        .zip(logit_rows(logits, k, n))
        .zip(labels)
        .map(|((row, x), &label)| outcome(row, x, label))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn confidence_is_the_max_and_ties_go_to_the_larger_logit() {
        let scores = [0.2, 0.7, 0.1, 0.4, 0.4, 0.2, 0.3, 0.3, 0.3];
        let labels = [Some(1), Some(1), None];
        let o = outcomes(&scores, 3, &labels).unwrap();
        let conf: Vec<f64> = o.iter().map(|o| o.conf).collect();
        let correct: Vec<bool> = o.iter().map(|o| o.correct).collect();
        assert_eq!(conf, [0.7, 0.4, 0.3]);
        assert_eq!(correct, [true, false, false]);
        // Without logits the lowest index; with them the larger logit (row 1: 0.4 ties
        // between classes 0 and 1, logit 2 > 1; row 2: a three-way tie, logit 5 wins).
        let logits = [0.0, 1.0, 0.0, 1.0, 2.0, 9.0, 4.0, 5.0, 3.0];
        let o = outcomes_with_logits(&scores, &logits, 3, &labels).unwrap();
        let pred: Vec<usize> = o.iter().map(|o| o.pred).collect();
        assert_eq!(pred, [1, 1, 1]);
        assert!(o[1].correct);
        assert_eq!(o[1].conf, 0.4);
        assert_eq!(decision(&[0.5f32, 0.5], &[0.0f32, 1.0]), 1);
        assert_eq!(decision(&[0.5f32, 0.5], &[1.0f32, 1.0]), 0);
        assert_eq!(
            outcomes_with_logits(&scores, &[0.0; 3], 3, &labels),
            Err(MetricsError::Shape)
        );
    }
}
