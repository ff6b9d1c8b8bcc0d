//! Ranking metrics (DESIGN §1.5): `auroc` of the confidence, true against false
//! positives, and the precision-recall curve and average precision of each class.

use super::accumulate::Sum;
use super::outcome::{check, Outcome};
use super::MetricsError;

/// A point of a precision-recall curve (one distinct score threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrPoint {
    /// Rows with a score `>= threshold` are predicted positive.
    pub threshold: f64,
    /// True positives over predicted positives.
    pub precision: f64,
    /// True positives over all positives.
    pub recall: f64,
}

/// Sort key of a checked score in `[0, 1]` with a flag: the score's bits shifted left
/// by one, the flag in bit 0.
///
/// For non-negative floats the bit pattern orders as the value, and `[0, 1]` uses only
/// the low 62 bits, so sorting these integers sorts by score (`-0.0` is mapped to
/// `0.0` first), and `key >> 1` groups equal scores. Sorting plain integers is several
/// times faster than sorting `(f64, bool)` pairs with a float comparator.
fn key(score: f64, flag: bool) -> u64 {
    ((score + 0.0).to_bits() << 1) | u64::from(flag)
}

/// The score of a [`key`].
fn unkey(key: u64) -> f64 {
    f64::from_bits(key >> 1)
}

/// AUROC of `conf`, true against false positives, ties 1/2; `None` without both.
///
/// Sorts once and counts, per group of equal `conf`, the false positives below it: the
/// Mann-Whitney statistic, kept exact in integers until the final division.
pub(super) fn auroc(outcomes: &[Outcome]) -> Option<f64> {
    let mut v: Vec<u64> = outcomes.iter().map(|o| key(o.conf, o.correct)).collect();
    let tp = v.iter().filter(|&&x| x & 1 == 1).count() as u128;
    let fp = v.len() as u128 - tp;
    if tp == 0 || fp == 0 {
        return None;
    }
    v.sort_unstable();
    let (mut twice_u, mut fp_below) = (0u128, 0u128);
    for group in v.chunk_by(|a, b| a >> 1 == b >> 1) {
        let tp_g = group.iter().filter(|&&x| x & 1 == 1).count() as u128;
        let fp_g = group.len() as u128 - tp_g;
        twice_u += tp_g * (2 * fp_below + fp_g);
        fp_below += fp_g;
    }
    Some(twice_u as f64 / (2 * tp * fp) as f64)
}

/// The order of any non-NaN `f64` as a `u64` (`-0.0` as `0.0`): the sign bit flipped
/// for non-negative values, every bit flipped for negative ones.
fn signed_key(v: f64) -> u64 {
    let bits = (v + 0.0).to_bits();
    if bits >> 63 == 1 {
        !bits
    } else {
        bits | (1 << 63)
    }
}

/// AUROC of `positive` against `negative` values: the probability that a positive
/// exceeds a negative, ties counting 1/2 (the Mann-Whitney statistic, exact in
/// integers until the final division); `None` when either side is empty. Values are
/// any non-NaN numbers (NaN values are left out).
pub fn separation_auroc(positive: &[f64], negative: &[f64]) -> Option<f64> {
    let mut v: Vec<(u64, bool)> = positive
        .iter()
        .filter(|x| !x.is_nan())
        .map(|&x| (signed_key(x), true))
        .chain(
            negative
                .iter()
                .filter(|x| !x.is_nan())
                .map(|&x| (signed_key(x), false)),
        )
        .collect();
    let p = v.iter().filter(|x| x.1).count() as u128;
    let n = v.len() as u128 - p;
    if p == 0 || n == 0 {
        return None;
    }
    v.sort_unstable();
    let (mut twice_u, mut neg_below) = (0u128, 0u128);
    for group in v.chunk_by(|a, b| a.0 == b.0) {
        let p_g = group.iter().filter(|x| x.1).count() as u128;
        let n_g = group.len() as u128 - p_g;
        twice_u += p_g * (2 * neg_below + n_g);
        neg_below += n_g;
    }
    Some(twice_u as f64 / (2 * p * n) as f64)
}

/// The share of `negative` values at or above the threshold that keeps 95 % of the
/// `positive` ones: the threshold is the largest value `t` with at least
/// `ceil(0.95 * P)` positives `>= t` (the `m`-th largest positive), as
/// `sklearn.metrics.roc_curve` gives the false-positive rate at the first point whose
/// true-positive rate reaches 0.95. `None` when either side is empty. NaN values are
/// left out.
pub fn fpr_at_95_tpr(positive: &[f64], negative: &[f64]) -> Option<f64> {
    let mut pos: Vec<u64> = positive
        .iter()
        .filter(|x| !x.is_nan())
        .map(|&x| signed_key(x))
        .collect();
    let neg: Vec<u64> = negative
        .iter()
        .filter(|x| !x.is_nan())
        .map(|&x| signed_key(x))
        .collect();
    if pos.is_empty() || neg.is_empty() {
        return None;
    }
    // m = ceil(95 P / 100), in integers.
    let m = (95 * pos.len()).div_ceil(100).max(1);
    pos.sort_unstable_by(|a, b| b.cmp(a));
    let threshold = *pos.get(m - 1)?;
    let above = neg.iter().filter(|&&x| x >= threshold).count();
    Some(above as f64 / neg.len() as f64)
}

/// Precision-recall points of one class, thresholds in decreasing order, after
/// checking; empty when the class has no positive row.
pub(super) fn pr_points(
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
    class: usize,
) -> Vec<PrPoint> {
    let v: Vec<u64> = scores
        .chunks_exact(k)
        .zip(labels)
        .map(|(row, l)| key(row.get(class).copied().unwrap_or(0.0), *l == Some(class)))
        .collect();
    pr_points_of_keys(v)
}

/// The sort key of one row's score of a class and whether the row is a positive of it,
/// for [`pr_points_of_keys`].
pub(super) fn pr_key(score: f64, positive: bool) -> u64 {
    key(score, positive)
}

/// Precision-recall points from the [`pr_key`]s of every row (in any order).
pub(super) fn pr_points_of_keys(mut v: Vec<u64>) -> Vec<PrPoint> {
    let positives = v.iter().filter(|&&x| x & 1 == 1).count();
    if positives == 0 {
        return Vec::new();
    }
    v.sort_unstable();
    let (mut tp, mut seen) = (0usize, 0usize);
    v.chunk_by(|a, b| a >> 1 == b >> 1)
        .rev()
        .map(|group| {
            tp += group.iter().filter(|&&x| x & 1 == 1).count();
            seen += group.len();
            PrPoint {
                threshold: group.first().map_or(0.0, |&x| unkey(x)),
                precision: tp as f64 / seen as f64,
                recall: tp as f64 / positives as f64,
            }
        })
        .collect()
}

/// Average precision from the points of [`precision_recall_curve`]:
/// `sum_n (R_n - R_{n-1}) P_n`, `R_0 = 0`, as
/// `sklearn.metrics.average_precision_score`; `None` for no points (no positives).
///
/// # Examples
///
/// ```
/// use mlmap_host::metrics::{average_precision, precision_recall_curve};
///
/// // scikit-learn's example: labels [0, 0, 1, 1], scores [0.1, 0.4, 0.35, 0.8].
/// let scores = [0.1, 0.4, 0.35, 0.8];
/// let labels = [None, None, Some(0), Some(0)];
/// let pr = precision_recall_curve(&scores, 1, &labels, 0)?;
/// let ap = average_precision(&pr).unwrap();
/// assert!((ap - 5.0 / 6.0).abs() < 1e-12);
/// # Ok::<(), mlmap_host::metrics::MetricsError>(())
/// ```
pub fn average_precision(points: &[PrPoint]) -> Option<f64> {
    if points.is_empty() {
        return None;
    }
    let (mut ap, mut prev) = (Sum::default(), 0.0);
    for p in points {
        ap.add((p.recall - prev) * p.precision);
        prev = p.recall;
    }
    Some(ap.value())
}

/// The precision-recall curve of one class's score, positives being the rows labelled
/// with that class: one point per distinct score, in decreasing order of threshold, as
/// `sklearn.metrics.precision_recall_curve` (without its final `(1, 0)` point). Empty
/// when no row is labelled with the class.
///
/// # Errors
///
/// As [`outcomes`](super::outcomes), and [`MetricsError::Class`] for `class >= k`.
///
/// # Panics
///
/// Never.
pub fn precision_recall_curve(
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
    class: usize,
) -> Result<Vec<PrPoint>, MetricsError> {
    check(scores, &[], k, labels)?;
    if class >= k {
        return Err(MetricsError::Class);
    }
    Ok(pr_points(scores, k, labels, class))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::lcg;

    #[test]
    fn separation_by_hand() {
        // Positives 3, 1, -1; negatives 1, -2: pairs 3>1, 3>-2, 1=1 (1/2), 1>-2, -1>-2,
        // -1<1: 4.5 of 6.
        assert_eq!(
            separation_auroc(&[3.0, 1.0, -1.0], &[1.0, -2.0]),
            Some(0.75)
        );
        assert_eq!(separation_auroc(&[-0.0], &[0.0]), Some(0.5));
        assert_eq!(separation_auroc(&[], &[1.0]), None);
        assert_eq!(separation_auroc(&[f64::NEG_INFINITY], &[-1e300]), Some(0.0));
        // 20 positives 1..=20: m = 19, threshold 2; negatives >= 2: 2 and 5 of 4.
        let pos: Vec<f64> = (1..=20).map(f64::from).collect();
        assert_eq!(fpr_at_95_tpr(&pos, &[0.0, 2.0, 5.0, 1.5]), Some(0.5));
        // 21 positives: m = ceil(19.95) = 20, threshold 2 again.
        let pos: Vec<f64> = (1..=21).map(f64::from).collect();
        assert_eq!(fpr_at_95_tpr(&pos, &[0.0, 2.0, 5.0, 1.5]), Some(0.5));
        // One positive: its own value is the threshold.
        assert_eq!(fpr_at_95_tpr(&[-3.0], &[-3.0, -4.0]), Some(0.5));
        assert_eq!(fpr_at_95_tpr(&[1.0], &[]), None);
    }

    fn ap(scores: &[f64], labels: &[Option<usize>]) -> Option<f64> {
        average_precision(&precision_recall_curve(scores, 1, labels, 0).unwrap())
    }

    #[test]
    fn average_precision_with_a_tie_at_the_top() {
        // [1, 0, 1] with [0.5, 0.5, 0.2]: 0.5 * 0.5 + 0.5 * 2/3.
        let got = ap(&[0.5, 0.5, 0.2], &[Some(0), None, Some(0)]).unwrap();
        assert!((got - (0.25 + 1.0 / 3.0)).abs() < 1e-12, "{got}");
        assert_eq!(ap(&[0.3], &[None]), None);
    }

    #[test]
    fn average_precision_agrees_with_a_direct_count_under_ties() {
        // Scores rounded to 0.05 give many ties; the reference recounts precision and
        // recall over every row at each distinct threshold.
        let mut rnd = lcg(7);
        let n = 300;
        let scores: Vec<f64> = (0..n).map(|_| (rnd() * 20.0).round() / 20.0).collect();
        let labels: Vec<Option<usize>> = (0..n)
            .map(|i| (rnd() < 0.3 + 0.5 * scores[i]).then_some(0))
            .collect();
        let positives = labels.iter().filter(|l| l.is_some()).count() as f64;
        let mut thresholds = scores.clone();
        thresholds.sort_by(|a, b| b.total_cmp(a));
        thresholds.dedup();
        let (mut want, mut prev_recall) = (0.0, 0.0);
        for t in thresholds {
            let picked = || (0..n).filter(|&i| scores[i] >= t);
            let tp = picked().filter(|&i| labels[i].is_some()).count() as f64;
            let recall = tp / positives;
            want += (recall - prev_recall) * tp / picked().count() as f64;
            prev_recall = recall;
        }
        let got = ap(&scores, &labels).unwrap();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}
