//! The numbers behind the plots: reliability bins and ECE (DESIGN §1.5), score
//! histograms, precision-recall curves and average precision (DESIGN §1.5, as
//! `sklearn.metrics.average_precision_score`).

use std::format;
use std::string::{String, ToString};
use std::vec;
use std::vec::Vec;

use super::SCORE_BINS;

/// One bin of a reliability diagram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct CalBin {
    pub(super) lo: f64,
    pub(super) hi: f64,
    pub(super) count: usize,
    /// Fraction of correct rows (0 when empty).
    pub(super) acc: f64,
    /// Mean confidence (0 when empty).
    pub(super) conf: f64,
}

/// Index of the bin `((m-1)/M, m/M]` holding `conf`, with edges `m / M` in `f64`;
/// `conf <= 1/M` (0 and below included) is bin 0 and `conf > 1` the last bin.
pub(super) fn calibration_bin(conf: f64, bins: usize) -> usize {
    let m = bins as f64;
    let est = (conf * m).ceil();
    // 1-based estimate, then corrected against the true edges m / M.
    let mut k = if est >= 1.0 { (est.min(m)) as usize } else { 1 };
    while k > 1 && conf <= (k - 1) as f64 / m {
        k -= 1;
    }
    while k < bins && conf > k as f64 / m {
        k += 1;
    }
    k - 1
}

pub(super) fn reliability_bins(conf: &[f64], correct: &[bool], bins: usize) -> Vec<CalBin> {
    let m = bins as f64;
    let mut out: Vec<CalBin> = (0..bins)
        .map(|i| CalBin {
            lo: i as f64 / m,
            hi: (i + 1) as f64 / m,
            count: 0,
            acc: 0.0,
            conf: 0.0,
        })
        .collect();
    for (&c, &ok) in conf.iter().zip(correct) {
        if let Some(b) = out.get_mut(calibration_bin(c, bins)) {
            b.count += 1;
            b.conf += c;
            if ok {
                b.acc += 1.0;
            }
        }
    }
    for b in &mut out {
        if b.count > 0 {
            b.acc /= b.count as f64;
            b.conf /= b.count as f64;
        }
    }
    out
}

/// `sum_m |B_m| / n * |acc(B_m) - conf(B_m)|`, or `None` without rows.
pub(super) fn ece(bins: &[CalBin]) -> Option<f64> {
    let n: usize = bins.iter().map(|b| b.count).sum();
    if n == 0 {
        return None;
    }
    let sum: f64 = bins
        .iter()
        .map(|b| b.count as f64 * (b.acc - b.conf).abs())
        .sum();
    Some(sum / n as f64)
}

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

/// The precision-recall curve of one class: `scores` are the class's scores of every
/// row, the positives are the rows labelled `class`.
pub(super) fn pr_curve(
    scores: impl Iterator<Item = f64>,
    labels: &[Option<usize>],
    class: usize,
) -> PrCurve {
    let mut ranked: Vec<(f64, bool)> = scores
        .zip(labels)
        .map(|(s, l)| (s, *l == Some(class)))
        .collect();
    let positives = ranked.iter().filter(|(_, p)| *p).count();
    if positives == 0 {
        return PrCurve {
            points: Vec::new(),
            ap: None,
        };
    }
    ranked.sort_by(|a, b| b.0.total_cmp(&a.0));
    // (recall, precision) at every distinct score, highest first.
    let mut steps: Vec<(f64, f64)> = Vec::new();
    let (mut tp, mut fp) = (0usize, 0usize);
    let mut iter = ranked.iter().peekable();
    while let Some(&(s, pos)) = iter.next() {
        if pos {
            tp += 1;
        } else {
            fp += 1;
        }
        let last_of_group = iter.peek().is_none_or(|next| next.0 != s);
        if last_of_group {
            steps.push((tp as f64 / positives as f64, tp as f64 / (tp + fp) as f64));
        }
    }
    let mut ap = 0.0;
    let mut prev_recall = 0.0;
    for &(r, p) in &steps {
        ap += (r - prev_recall) * p;
        prev_recall = r;
    }
    // Steps whose area is the AP: precision P_n over recall (R_{n-1}, R_n].
    let mut points: Vec<(f64, f64)> = Vec::with_capacity(2 * steps.len());
    let mut prev_recall = 0.0;
    for &(r, p) in &steps {
        push_thinned(&mut points, (prev_recall, p));
        push_thinned(&mut points, (r, p));
        prev_recall = r;
    }
    if let (Some(last), Some(&end)) = (points.last(), steps.last()) {
        if *last != end {
            points.push(end);
        }
    }
    PrCurve {
        points,
        ap: Some(ap),
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

/// Column `c` of an N x K row-major matrix.
pub(super) fn column(scores: &[f64], k: usize, c: usize) -> impl Iterator<Item = f64> + '_ {
    scores
        .chunks(k.max(1))
        .map(move |row| row.get(c).copied().unwrap_or(0.0))
}

/// DESIGN §1.5: `conf` is the row's largest score; the row is correct when its label
/// is a class and equals the argmax (lowest index on ties).
pub(super) fn confidence_and_correct(
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
) -> (Vec<f64>, Vec<bool>) {
    scores
        .chunks(k.max(1))
        .zip(labels)
        .map(|(row, label)| {
            let mut best = 0usize;
            let mut conf = f64::NEG_INFINITY;
            for (i, &s) in row.iter().enumerate() {
                if s > conf {
                    conf = s;
                    best = i;
                }
            }
            (conf, *label == Some(best))
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_bins_close_on_the_right_edge() {
        // (conf, M, bin): edges are m / M in f64; 0 joins the first bin.
        const VECTORS: &[(f64, usize, usize)] = &[
            (0.0, 10, 0),
            (-0.5, 10, 0),
            (0.05, 10, 0),
            (0.1, 10, 0),
            (0.100_000_000_000_001, 10, 1),
            (0.3, 10, 2),
            (0.6, 10, 5),
            (0.95, 10, 9),
            (1.0, 10, 9),
            (1.5, 10, 9),
            (0.5, 1, 0),
            (1.0 / 3.0, 3, 0),
            (2.0 / 3.0, 3, 1),
        ];
        for &(conf, m, want) in VECTORS {
            assert_eq!(calibration_bin(conf, m), want, "conf {conf}, M {m}");
        }
    }

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

    #[test]
    fn average_precision_matches_sklearn() {
        // sklearn's docs: average_precision_score([0, 0, 1, 1], [0.1, 0.4, 0.35, 0.8])
        // = 0.8333...; a tie at the top: [1, 0, 1] with [0.5, 0.5, 0.2] gives
        // 0.5 * 0.5 + 0.5 * 2/3 = 0.58333...
        const MAX_ABS_ERR: f64 = 1e-12;
        let labels = [None, None, Some(0), Some(0)];
        let curve = pr_curve([0.1, 0.4, 0.35, 0.8].into_iter(), &labels, 0);
        let ap = curve.ap.unwrap();
        assert!((ap - 5.0 / 6.0).abs() < MAX_ABS_ERR, "{ap}");
        assert_eq!(curve.points.first(), Some(&(0.0, 1.0)));
        assert_eq!(curve.points.last(), Some(&(1.0, 0.5)));

        let labels = [Some(0), Some(1), Some(0)];
        let ap = pr_curve([0.5, 0.5, 0.2].into_iter(), &labels, 0)
            .ap
            .unwrap();
        assert!((ap - (0.25 + 1.0 / 3.0)).abs() < MAX_ABS_ERR, "{ap}");

        assert_eq!(pr_curve([0.3].into_iter(), &[None], 0).ap, None);
    }

    #[test]
    fn confidence_is_max_and_ties_go_to_the_lowest_index() {
        let scores = [0.2, 0.7, 0.1, 0.4, 0.4, 0.2, 0.3, 0.3, 0.3];
        let labels = [Some(1), Some(1), None];
        let (conf, correct) = confidence_and_correct(&scores, 3, &labels);
        assert_eq!(conf, vec![0.7, 0.4, 0.3]);
        assert_eq!(correct, vec![true, false, false]);
    }

    /// A pseudo-random sequence in [0, 1) (64-bit LCG), for reproducible test data.
    fn lcg(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
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
        let got = pr_curve(scores.iter().copied(), &labels, 0).ap.unwrap();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }

    #[test]
    fn long_curves_are_thinned_for_drawing() {
        let mut rnd = lcg(11);
        let n = 50_000;
        let scores: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let labels: Vec<Option<usize>> = scores.iter().map(|&s| (rnd() < s).then_some(0)).collect();
        let curve = pr_curve(scores.iter().copied(), &labels, 0);
        assert!(curve.points.len() < n / 5, "{} points", curve.points.len());
        for &(r, p) in &curve.points {
            assert!((0.0..=1.0).contains(&r) && (0.0..=1.0).contains(&p));
        }
        assert_eq!(curve.points.last().map(|p| p.0), Some(1.0));
        // A perfect ranking: AP 1 whatever the thinning.
        let ranked: Vec<f64> = labels
            .iter()
            .enumerate()
            .map(|(i, l)| if l.is_some() { 2.0 } else { 0.0 } + i as f64 * 1e-9)
            .collect();
        assert_eq!(pr_curve(ranked.into_iter(), &labels, 0).ap, Some(1.0));
    }
}
