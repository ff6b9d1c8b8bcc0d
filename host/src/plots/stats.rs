//! The numbers behind the plots that the metrics module does not compute: score
//! histograms, and precision-recall curves thinned for drawing. Reliability bins,
//! the ECE, the curves' points and average precision come from
//! [`metrics`](crate::metrics).

use super::SCORE_BINS;
use crate::metrics::{average_precision, PrPoint};

/// The ECE as the reliability diagram's title writes it.
pub(super) fn ece_label(ece: Option<f64>) -> String {
    match ece {
        Some(e) => format!("ECE = {e:.4}"),
        None => "ECE = n/a".to_string(),
    }
}

/// Counts of scores in [`SCORE_BINS`] bins on `[0, 1]`, and their mean.
pub(super) struct ScoreHist {
    pub(super) counts: Vec<usize>,
    pub(super) n: usize,
    pub(super) mean: Option<f64>,
}

impl ScoreHist {
    pub(super) fn new(scores: &[f64]) -> Self {
        let mut counts = vec![0usize; SCORE_BINS];
        for &s in scores {
            if let Some(c) = counts.get_mut(score_bin(s, SCORE_BINS)) {
                *c += 1;
            }
        }
        let n = scores.len();
        let mean = (n > 0).then(|| scores.iter().sum::<f64>() / n as f64);
        Self { counts, n, mean }
    }
}

/// numpy's rule on `bins` equal bins of `[0, 1]`: `[k/M, (k+1)/M)`, the last closed;
/// values outside go to the nearest bin.
pub(super) fn score_bin(x: f64, bins: usize) -> usize {
    let m = bins as f64;
    let est = (x * m).floor();
    let mut k = if est >= 0.0 {
        (est.min(m - 1.0)) as usize
    } else {
        0
    };
    while k > 0 && x < k as f64 / m {
        k -= 1;
    }
    while k + 1 < bins && x >= (k + 1) as f64 / m {
        k += 1;
    }
    k
}

/// A precision-recall curve drawn as steps, and its average precision.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct PrCurve {
    /// `(recall, precision)` vertices of the step curve, thinned for drawing.
    pub(super) points: Vec<(f64, f64)>,
    /// `None` when the class has no positives.
    pub(super) ap: Option<f64>,
}

/// Smallest change of recall or precision kept between two drawn vertices (well below
/// a pixel); the AP is always computed from every threshold.
const PR_RESOLUTION: f64 = 5e-4;

/// The drawing of a precision-recall curve from its points (thresholds in decreasing
/// order, as [`precision_recall_curve`](crate::metrics::precision_recall_curve)
/// gives them), with its average precision.
pub(super) fn pr_curve(steps: &[PrPoint]) -> PrCurve {
    // Steps whose area is the AP: precision P_n over recall (R_{n-1}, R_n].
    let mut points: Vec<(f64, f64)> = Vec::with_capacity(2 * steps.len());
    let mut prev_recall = 0.0;
    for p in steps {
        push_thinned(&mut points, (prev_recall, p.precision));
        push_thinned(&mut points, (p.recall, p.precision));
        prev_recall = p.recall;
    }
    if let (Some(last), Some(end)) = (points.last(), steps.last()) {
        let end = (end.recall, end.precision);
        if *last != end {
            points.push(end);
        }
    }
    PrCurve {
        points,
        ap: average_precision(steps),
    }
}

fn push_thinned(points: &mut Vec<(f64, f64)>, p: (f64, f64)) {
    let keep = points.last().is_none_or(|last| {
        (last.0 - p.0).abs() > PR_RESOLUTION || (last.1 - p.1).abs() > PR_RESOLUTION
    });
    if keep {
        points.push(p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::lcg;

    #[test]
    fn score_bins_follow_numpy() {
        const VECTORS: &[(f64, usize)] = &[
            (0.0, 0),
            (0.049, 0),
            (0.05, 1),
            (0.5, 10),
            (0.95, 19),
            (1.0, 19),
            (-1.0, 0),
            (2.0, 19),
        ];
        for &(x, want) in VECTORS {
            assert_eq!(score_bin(x, SCORE_BINS), want, "x {x}");
        }
    }

    fn drawn(scores: &[f64], labels: &[Option<usize>]) -> PrCurve {
        let points = crate::metrics::precision_recall_curve(scores, 1, labels, 0).unwrap();
        pr_curve(&points)
    }

    #[test]
    fn average_precision_matches_sklearn() {
        // sklearn's docs: average_precision_score([0, 0, 1, 1], [0.1, 0.4, 0.35, 0.8])
        // = 0.8333...; a tie at the top: [1, 0, 1] with [0.5, 0.5, 0.2] gives
        // 0.5 * 0.5 + 0.5 * 2/3 = 0.58333...
        const MAX_ABS_ERR: f64 = 1e-12;
        let labels = [None, None, Some(0), Some(0)];
        let curve = drawn(&[0.1, 0.4, 0.35, 0.8], &labels);
        let ap = curve.ap.unwrap();
        assert!((ap - 5.0 / 6.0).abs() < MAX_ABS_ERR, "{ap}");
        assert_eq!(curve.points.first(), Some(&(0.0, 1.0)));
        assert_eq!(curve.points.last(), Some(&(1.0, 0.5)));

        let labels = [Some(0), None, Some(0)];
        let ap = drawn(&[0.5, 0.5, 0.2], &labels).ap.unwrap();
        assert!((ap - (0.25 + 1.0 / 3.0)).abs() < MAX_ABS_ERR, "{ap}");

        assert_eq!(drawn(&[0.3], &[None]).ap, None);
    }

    #[test]
    fn long_curves_are_thinned_for_drawing() {
        let mut rnd = lcg(11);
        let n = 50_000;
        let scores: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let labels: Vec<Option<usize>> = scores.iter().map(|&s| (rnd() < s).then_some(0)).collect();
        let curve = drawn(&scores, &labels);
        assert!(curve.points.len() < n / 5, "{} points", curve.points.len());
        for &(r, p) in &curve.points {
            assert!((0.0..=1.0).contains(&r) && (0.0..=1.0).contains(&p));
        }
        assert_eq!(curve.points.last().map(|p| p.0), Some(1.0));
        // A perfect ranking: AP 1 whatever the thinning.
        let ranked: Vec<f64> = labels
            .iter()
            .enumerate()
            .map(|(i, l)| if l.is_some() { 0.5 } else { 0.0 } + i as f64 * 1e-9)
            .collect();
        assert_eq!(drawn(&ranked, &labels).ap, Some(1.0));
    }
}
