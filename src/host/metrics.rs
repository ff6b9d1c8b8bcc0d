//! Evaluation metrics of DESIGN §1.5, on final scores (objectness included).
//!
//! Input is always the same: `N x K` scores, row-major `f64`, each in `[0, 1]`, and one
//! label per row (`Some(class)` or `None` for background). From them:
//!
//! * `conf = max_i s_i`; a row is **correct** (a true positive) when its label is a
//!   class and the argmax of its scores (lowest index on ties, as
//!   [`argmax`](crate::argmax)) equals it. Every other row is a false positive.
//! * `ece`, `mce`: the calibration gap over equal-width confidence bins, with the bin
//!   convention a parameter ([`Binning`]).
//! * `nll`, `brier`, the mean and population variance of `conf` over true and false
//!   positives, `auroc` (true against false positives), `ap_<class>` as
//!   `sklearn.metrics.average_precision_score`, and `ood_mean`, `ood_over_0_9` on an
//!   out-of-distribution set.
//!
//! A metric with nothing to average (no labelled row, no true or false positive, no
//! positive of a class) is `None`, which reports write as `null`. Sums use
//! compensated (Neumaier) summation, and each metric that ranks rows sorts once, so a
//! million rows take a fraction of a second.
//!
//! The values are checked against an independent numpy / scikit-learn implementation
//! (`tools/metrics_reference.py`, golden files in `tests/golden/metrics/`).

use core::fmt;
use core::str::FromStr;
use std::string::String;
use std::vec::Vec;

use super::baselines::NLL_FLOOR;

/// Number of confidence bins of `ece` and `mce` unless configured otherwise (DESIGN §1.5).
pub const DEFAULT_BINS: usize = 10;

/// Largest accepted number of confidence bins.
pub const MAX_BINS: usize = 1 << 20;

/// `ood_over_0_9` counts the out-of-distribution rows whose `conf` exceeds this.
pub const OOD_THRESHOLD: f64 = 0.9;

/// Which confidence falls in which bin of `ece` and `mce`.
///
/// All three split `[0, 1]` into `M` equal-width bins; they differ on the bin that
/// holds a confidence lying exactly on an edge, which matters because scores such as
/// `OS / K` or `1.0` sit on edges often.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Binning {
    /// DESIGN §1.5 (the default): bins `((m-1)/M, m/M]` with edges `m / M` computed
    /// in `f64`, and `conf = 0` in the first bin.
    #[default]
    Design,
    /// netcal's rule (`netcal.metrics.ECE`): the confidence is clipped to
    /// `[eps, 1 - eps]` (`eps` = `f64::EPSILON`), then binned `[lo, hi)` on the edges
    /// `numpy.linspace(0, 1, M + 1)`, i.e. `m * (1 / M)`; so `conf = 1` is in the last bin.
    Netcal,
    /// torchmetrics' rule (`multiclass_calibration_error`): `M + 1` bins from
    /// `torch.bucketize(conf, edges, right=True) - 1`, i.e. `[lo, hi)`, with
    /// `conf = 1` alone in the extra bin `M`. As in torchmetrics, the comparison is in
    /// `f32`: the confidence is rounded to `f32` and the edges are those
    /// `torch.linspace(0, 1, M + 1)` computes in `f32` (`i / M` on the lower half,
    /// `1 - (M - i) / M` on the upper half, with the step `1 / M` in `f32`). For
    /// `M = 10` these are the `f32` values nearest `m / 10`; for some other `M`,
    /// torch's vectorised or FMA-contracted kernels may round an edge one `f32` ulp
    /// differently, which matters only for a confidence within that ulp of the edge.
    /// Bin means use the unrounded `f64` confidences.
    Torchmetrics,
}

impl Binning {
    /// Every convention, default first.
    pub const ALL: [Self; 3] = [Self::Design, Self::Netcal, Self::Torchmetrics];

    /// The name used on the command line and in reports: `design`, `netcal` or
    /// `torchmetrics`.
    pub const fn name(self) -> &'static str {
        match self {
            Self::Design => "design",
            Self::Netcal => "netcal",
            Self::Torchmetrics => "torchmetrics",
        }
    }

    /// Number of bins this convention uses for `m` requested bins (`m + 1` for
    /// torchmetrics' extra bin).
    pub const fn bin_count(self, m: usize) -> usize {
        match self {
            Self::Torchmetrics => m.saturating_add(1),
            Self::Design | Self::Netcal => m,
        }
    }
}

impl fmt::Display for Binning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Binning {
    type Err = MetricsError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|b| b.name() == s)
            .ok_or(MetricsError::UnknownBinning)
    }
}

/// Settings of [`evaluate`].
///
/// # Parameters
///
/// | Name | Default | Purpose | Range |
/// |---|---|---|---|
/// | `bins` | [`DEFAULT_BINS`] (10) | `M`, equal-width confidence bins of `ece`/`mce` | `1..=MAX_BINS` |
/// | `binning` | [`Binning::Design`] | which bin holds a confidence on an edge | any |
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MetricsConfig {
    /// `M`, the number of equal-width confidence bins.
    pub bins: usize,
    /// The bin convention.
    pub binning: Binning,
}

impl Default for MetricsConfig {
    fn default() -> Self {
        Self {
            bins: DEFAULT_BINS,
            binning: Binning::Design,
        }
    }
}

/// Why metrics could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MetricsError {
    /// There are no rows.
    Empty,
    /// `K` is 0, the score count is not a multiple of `K`, or there is not one label
    /// per row.
    Shape,
    /// A score is NaN, infinite or outside `[0, 1]`.
    Score {
        /// Row of the first bad score.
        row: usize,
        /// Class (column) of the first bad score.
        class: usize,
    },
    /// A label is a class index `>= K`.
    Label {
        /// Row of the first bad label.
        row: usize,
    },
    /// The number of confidence bins is 0 or above [`MAX_BINS`].
    Bins,
    /// A class index `>= K` was asked for.
    Class,
    /// A binning name other than `design`, `netcal` and `torchmetrics`.
    UnknownBinning,
}

impl fmt::Display for MetricsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Empty => f.write_str("no rows to evaluate"),
            Self::Shape => {
                f.write_str("scores and labels do not describe the same rows of K > 0 classes")
            }
            Self::Score { row, class } => write!(
                f,
                "row {row}, class {class}: score is not a number in [0, 1]"
            ),
            Self::Label { row } => write!(f, "row {row}: label is not a class index"),
            Self::Bins => write!(f, "the number of bins must be in 1..={MAX_BINS}"),
            Self::Class => f.write_str("class index out of range"),
            Self::UnknownBinning => {
                f.write_str("binning must be one of design, netcal, torchmetrics")
            }
        }
    }
}

impl core::error::Error for MetricsError {}

/// What one row contributes to the confidence metrics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outcome {
    /// `conf = max_i s_i`.
    pub conf: f64,
    /// The predicted class: the argmax, lowest index on ties.
    pub pred: usize,
    /// Whether the row is a true positive (labelled `pred`).
    pub correct: bool,
}

/// One confidence bin of `ece` and `mce` (a point of a reliability diagram).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationBin {
    /// Lower edge.
    pub lo: f64,
    /// Upper edge (equal to `lo` for torchmetrics' extra bin at 1).
    pub hi: f64,
    /// Number of rows in the bin.
    pub count: usize,
    /// Fraction of correct rows, `acc(B)`; `None` for an empty bin.
    pub accuracy: Option<f64>,
    /// Mean `conf`, `conf(B)`; `None` for an empty bin.
    pub confidence: Option<f64>,
}

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

/// Metrics of an out-of-distribution set (DESIGN §1.5), from [`ood_metrics`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OodMetrics {
    /// `ood_mean`: mean `conf` over the set.
    pub ood_mean: f64,
    /// `ood_over_0_9`: fraction of rows with `conf > 0.9`.
    pub ood_over_0_9: f64,
    /// Number of rows.
    pub rows: usize,
}

/// Every metric of DESIGN §1.5 for one method on one set, from [`evaluate`].
///
/// Each field is named after its DESIGN key; `None` means undefined (nothing to
/// average), never "not a number".
#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    /// `ece`: `sum_m |B_m| / n * |acc(B_m) - conf(B_m)|`.
    pub ece: f64,
    /// `mce`: the largest `|acc(B_m) - conf(B_m)|` over non-empty bins.
    pub mce: f64,
    /// `nll`: mean `-ln(max(s_label, 1e-12))` over labelled rows; `None` without any.
    pub nll: Option<f64>,
    /// `brier`: mean over all rows of `sum_i (s_i - y_i)^2`, `y` one-hot (all zeros for
    /// background).
    pub brier: f64,
    /// `tp_mean`: mean `conf` of the true positives; `None` without any.
    pub tp_mean: Option<f64>,
    /// `tp_var`: population variance of `conf` of the true positives; `None` without any.
    pub tp_var: Option<f64>,
    /// `fp_mean`: mean `conf` of the false positives; `None` without any.
    pub fp_mean: Option<f64>,
    /// `fp_var`: population variance of `conf` of the false positives; `None` without any.
    pub fp_var: Option<f64>,
    /// `auroc`: probability that a true positive's `conf` exceeds a false positive's,
    /// ties counting 1/2; `None` without both.
    pub auroc: Option<f64>,
    /// `ap_<class>`, in class order: average precision of the class's score with its
    /// labelled rows as positives; `None` for a class without positives.
    pub ap: Vec<Option<f64>>,
    /// `ood_mean` and `ood_over_0_9`, when an out-of-distribution set was evaluated
    /// (attach with [`Metrics::with_ood`]).
    pub ood: Option<OodMetrics>,
    /// Number of rows.
    pub rows: usize,
    /// Number of rows labelled with a class.
    pub labelled: usize,
    /// Number of true positives.
    pub tp: usize,
    /// Number of false positives (`rows - tp`).
    pub fp: usize,
    /// The confidence bins behind `ece` and `mce`, in order.
    pub reliability: Vec<CalibrationBin>,
}

impl Metrics {
    /// The keys of [`Metrics::entries`] that come before the `ap_<class>` ones.
    pub const LEADING_KEYS: [&'static str; 9] = [
        "ece", "mce", "nll", "brier", "tp_mean", "tp_var", "fp_mean", "fp_var", "auroc",
    ];

    /// Attaches the metrics of an out-of-distribution set.
    pub fn with_ood(mut self, ood: OodMetrics) -> Self {
        self.ood = Some(ood);
        self
    }

    /// Every metric as `(key, value)`, in a stable order, with the DESIGN §1.5 keys:
    /// [`LEADING_KEYS`](Self::LEADING_KEYS), then `ap_<class>` per class, then
    /// `ood_mean` and `ood_over_0_9` when an out-of-distribution set is attached.
    ///
    /// `class_names[i]` names class `i`; a class without a name is called `class<i>`
    /// (the default of DESIGN §2). `None` values are undefined metrics (`null` in JSON).
    pub fn entries<S: AsRef<str>>(&self, class_names: &[S]) -> Vec<(String, Option<f64>)> {
        let leading = [
            Some(self.ece),
            Some(self.mce),
            self.nll,
            Some(self.brier),
            self.tp_mean,
            self.tp_var,
            self.fp_mean,
            self.fp_var,
            self.auroc,
        ];
        let mut out: Vec<(String, Option<f64>)> = Self::LEADING_KEYS
            .iter()
            .zip(leading)
            .map(|(k, v)| (String::from(*k), v))
            .collect();
        for (i, ap) in self.ap.iter().enumerate() {
            let key = match class_names.get(i) {
                Some(name) => std::format!("ap_{}", name.as_ref()),
                None => std::format!("ap_class{i}"),
            };
            out.push((key, *ap));
        }
        if let Some(ood) = self.ood {
            out.push((String::from("ood_mean"), Some(ood.ood_mean)));
            out.push((String::from("ood_over_0_9"), Some(ood.ood_over_0_9)));
        }
        out
    }
}

/// Neumaier's compensated sum: the error does not grow with the number of terms.
#[derive(Debug, Clone, Copy, Default)]
struct Sum {
    sum: f64,
    carry: f64,
}

impl Sum {
    fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.carry += (self.sum - t) + x;
        } else {
            self.carry += (x - t) + self.sum;
        }
        self.sum = t;
    }

    fn value(self) -> f64 {
        self.sum + self.carry
    }
}

/// Mean and population variance (two passes); `None` for no values.
fn mean_var(values: impl Iterator<Item = f64> + Clone) -> Option<(f64, f64)> {
    let (mut sum, mut n) = (Sum::default(), 0usize);
    for x in values.clone() {
        sum.add(x);
        n += 1;
    }
    if n == 0 {
        return None;
    }
    let mean = sum.value() / n as f64;
    let mut sq = Sum::default();
    for x in values {
        sq.add((x - mean) * (x - mean));
    }
    Some((mean, sq.value() / n as f64))
}

/// Checks the shape and every score; returns `N`.
fn check_scores(scores: &[f64], k: usize) -> Result<usize, MetricsError> {
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

/// Checks scores and labels; returns `N`.
fn check(scores: &[f64], k: usize, labels: &[Option<usize>]) -> Result<usize, MetricsError> {
    if k == 0 || !scores.len().is_multiple_of(k) || scores.len() / k != labels.len() {
        return Err(MetricsError::Shape);
    }
    let n = check_scores(scores, k)?;
    match labels.iter().position(|l| l.is_some_and(|c| c >= k)) {
        Some(row) => Err(MetricsError::Label { row }),
        None => Ok(n),
    }
}

/// `conf` and argmax (lowest index on ties) of one row of checked scores.
fn conf_pred(row: &[f64]) -> (f64, usize) {
    let mut best = (f64::NEG_INFINITY, 0);
    for (i, &s) in row.iter().enumerate() {
        if s > best.0 {
            best = (s, i);
        }
    }
    // `+ 0.0` turns -0.0 into 0.0, so equal confidences have equal bits.
    (best.0 + 0.0, best.1)
}

/// The [`Outcome`] of every row: `conf`, predicted class, correctness.
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
    check(scores, k, labels)?;
    Ok(scores
        .chunks_exact(k)
        .zip(labels)
        .map(|(row, label)| {
            let (conf, pred) = conf_pred(row);
            Outcome {
                conf,
                pred,
                correct: *label == Some(pred),
            }
        })
        .collect())
}

/// The bin edges of a convention, and the rule that maps a confidence to a bin (also
/// the binner of the tuner's ECE objective).
pub(crate) enum Edges {
    /// `e_0 .. e_M`; bin = number of `e_1 .. e_M` below `conf`, at most `M - 1`.
    Design(Vec<f64>),
    /// `e_0 .. e_M`; bin = number of `e_i <= clip(conf)` minus 1, at most `M - 1`.
    Netcal(Vec<f64>),
    /// `e_0 .. e_M` in `f32`; bin = number of `e_i <= f32(conf)` minus 1, up to `M`.
    Torch(Vec<f32>),
}

impl Edges {
    pub(crate) fn new(binning: Binning, m: usize) -> Self {
        match binning {
            Binning::Design => Self::Design((0..=m).map(|i| i as f64 / m as f64).collect()),
            Binning::Netcal => {
                // numpy.linspace(0, 1, m + 1): i * step, the last edge set to 1.
                let step = 1.0 / m as f64;
                Self::Netcal(
                    (0..=m)
                        .map(|i| if i == m { 1.0 } else { i as f64 * step })
                        .collect(),
                )
            }
            Binning::Torchmetrics => {
                // torch.linspace(0, 1, m + 1) in f32: start + step * i below halfway,
                // end - step * (steps - 1 - i) from there on.
                let step = 1.0f32 / m as f32;
                // torch's halfway = steps / 2 with steps = m + 1.
                let half = m.div_ceil(2);
                Self::Torch(
                    (0..=m)
                        .map(|i| {
                            if i < half {
                                step * i as f32
                            } else {
                                1.0 - step * (m - i) as f32
                            }
                        })
                        .collect(),
                )
            }
        }
    }

    /// The bin of a confidence in `[0, 1]`.
    pub(crate) fn bin(&self, conf: f64) -> usize {
        match self {
            Self::Design(e) => {
                let inner = e.get(1..).unwrap_or_default();
                inner
                    .partition_point(|&x| x < conf)
                    .min(inner.len().saturating_sub(1))
            }
            Self::Netcal(e) => {
                let c = conf.clamp(f64::EPSILON, 1.0 - f64::EPSILON);
                e.partition_point(|&x| x <= c)
                    .saturating_sub(1)
                    .min(e.len().saturating_sub(2))
            }
            Self::Torch(e) => e.partition_point(|&x| x <= conf as f32).saturating_sub(1),
        }
    }

    /// `(lo, hi)` of bin `i`.
    fn range(&self, i: usize) -> (f64, f64) {
        let pair = |lo: Option<f64>, hi: Option<f64>| {
            let lo = lo.unwrap_or(1.0);
            (lo, hi.unwrap_or(lo))
        };
        match self {
            Self::Design(e) | Self::Netcal(e) => pair(e.get(i).copied(), e.get(i + 1).copied()),
            Self::Torch(e) => pair(
                e.get(i).map(|&x| f64::from(x)),
                e.get(i + 1).map(|&x| f64::from(x)),
            ),
        }
    }
}

/// Reliability bins, `ece` and `mce` of checked outcomes (at least one).
fn calibration(outcomes: &[Outcome], cfg: &MetricsConfig) -> (Vec<CalibrationBin>, f64, f64) {
    let edges = Edges::new(cfg.binning, cfg.bins);
    let nb = cfg.binning.bin_count(cfg.bins);
    let mut acc = std::vec![(0usize, 0usize, Sum::default()); nb];
    for o in outcomes {
        if let Some((count, correct, conf)) = acc.get_mut(edges.bin(o.conf)) {
            *count += 1;
            *correct += usize::from(o.correct);
            conf.add(o.conf);
        }
    }
    let n = outcomes.len() as f64;
    let (mut ece, mut mce) = (Sum::default(), 0.0f64);
    let bins = acc
        .into_iter()
        .enumerate()
        .map(|(i, (count, correct, conf))| {
            let (lo, hi) = edges.range(i);
            let (mut accuracy, mut confidence) = (None, None);
            if count > 0 {
                let (a, c) = (correct as f64 / count as f64, conf.value() / count as f64);
                let gap = (a - c).abs();
                ece.add(count as f64 / n * gap);
                mce = mce.max(gap);
                (accuracy, confidence) = (Some(a), Some(c));
            }
            CalibrationBin {
                lo,
                hi,
                count,
                accuracy,
                confidence,
            }
        })
        .collect();
    (bins, ece.value(), mce)
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

/// The score and the flag of a [`key`].
fn unkey(key: u64) -> (f64, bool) {
    (f64::from_bits(key >> 1), key & 1 == 1)
}

/// AUROC of `conf`, true against false positives, ties 1/2; `None` without both.
///
/// Sorts once and counts, per group of equal `conf`, the false positives below it: the
/// Mann-Whitney statistic, kept exact in integers until the final division.
fn auroc(outcomes: &[Outcome]) -> Option<f64> {
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

/// Precision-recall points of one class, thresholds in decreasing order, after
/// checking; empty when the class has no positive row.
fn pr_points(scores: &[f64], k: usize, labels: &[Option<usize>], class: usize) -> Vec<PrPoint> {
    let mut v: Vec<u64> = scores
        .chunks_exact(k)
        .zip(labels)
        .map(|(row, l)| key(row.get(class).copied().unwrap_or(0.0), *l == Some(class)))
        .collect();
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
                threshold: group.first().map_or(0.0, |&x| unkey(x).0),
                precision: tp as f64 / seen as f64,
                recall: tp as f64 / positives as f64,
            }
        })
        .collect()
}

/// Average precision from the points: `sum_n (R_n - R_{n-1}) P_n`, `R_0 = 0`.
fn average_precision(points: &[PrPoint]) -> Option<f64> {
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
/// As [`outcomes`], and [`MetricsError::Class`] for `class >= k`.
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
    check(scores, k, labels)?;
    if class >= k {
        return Err(MetricsError::Class);
    }
    Ok(pr_points(scores, k, labels, class))
}

/// Every metric of DESIGN §1.5 except the out-of-distribution ones.
///
/// `scores` holds `N x K` final scores (row-major, objectness included), `labels` one
/// label per row (`None` for background).
///
/// # Examples
///
/// ```
/// use mlmap::host::metrics::{evaluate, MetricsConfig};
///
/// let scores = [0.9, 0.1, 0.3, 0.6, 0.8, 0.0];
/// let labels = [Some(0), Some(0), None];
/// let m = evaluate(&scores, 2, &labels, &MetricsConfig::default())?;
/// assert_eq!((m.tp, m.fp), (1, 2));
/// assert_eq!(m.auroc, Some(1.0));
/// assert_eq!(m.entries(&["car", "person"])[9].0, "ap_car");
/// # Ok::<(), mlmap::host::metrics::MetricsError>(())
/// ```
///
/// # Errors
///
/// * [`MetricsError::Shape`]: `k` is 0 or `scores.len()` is not `labels.len() * k`.
/// * [`MetricsError::Empty`]: no rows.
/// * [`MetricsError::Score`]: a score is NaN, infinite or outside `[0, 1]`.
/// * [`MetricsError::Label`]: a label is not a class index.
/// * [`MetricsError::Bins`]: `cfg.bins` is 0 or above [`MAX_BINS`].
///
/// # Panics
///
/// Never.
pub fn evaluate(
    scores: &[f64],
    k: usize,
    labels: &[Option<usize>],
    cfg: &MetricsConfig,
) -> Result<Metrics, MetricsError> {
    if cfg.bins == 0 || cfg.bins > MAX_BINS {
        return Err(MetricsError::Bins);
    }
    let outcomes = outcomes(scores, k, labels)?;
    let (reliability, ece, mce) = calibration(&outcomes, cfg);

    let (mut nll, mut brier, mut labelled) = (Sum::default(), Sum::default(), 0usize);
    for (row, label) in scores.chunks_exact(k).zip(labels) {
        if let Some(s) = label.and_then(|c| row.get(c)) {
            nll.add(-s.max(NLL_FLOOR).ln());
            labelled += 1;
        }
        for (i, &s) in row.iter().enumerate() {
            let y = if *label == Some(i) { 1.0 } else { 0.0 };
            brier.add((s - y) * (s - y));
        }
    }
    let n = outcomes.len();

    let tp_conf = outcomes.iter().filter(|o| o.correct).map(|o| o.conf);
    let fp_conf = outcomes.iter().filter(|o| !o.correct).map(|o| o.conf);
    let tp_stats = mean_var(tp_conf);
    let fp_stats = mean_var(fp_conf);
    let tp = outcomes.iter().filter(|o| o.correct).count();

    Ok(Metrics {
        ece,
        mce,
        nll: (labelled > 0).then(|| nll.value() / labelled as f64),
        brier: brier.value() / n as f64,
        tp_mean: tp_stats.map(|s| s.0),
        tp_var: tp_stats.map(|s| s.1),
        fp_mean: fp_stats.map(|s| s.0),
        fp_var: fp_stats.map(|s| s.1),
        auroc: auroc(&outcomes),
        ap: (0..k)
            .map(|c| average_precision(&pr_points(scores, k, labels, c)))
            .collect(),
        ood: None,
        rows: n,
        labelled,
        tp,
        fp: n - tp,
        reliability,
    })
}

/// `ood_mean` and `ood_over_0_9` of an out-of-distribution set (labels are not used).
///
/// # Errors
///
/// * [`MetricsError::Shape`]: `k` is 0 or `scores.len()` is not a multiple of `k`.
/// * [`MetricsError::Empty`]: no rows.
/// * [`MetricsError::Score`]: a score is NaN, infinite or outside `[0, 1]`.
///
/// # Panics
///
/// Never.
pub fn ood_metrics(scores: &[f64], k: usize) -> Result<OodMetrics, MetricsError> {
    let n = check_scores(scores, k)?;
    let (mut sum, mut over) = (Sum::default(), 0usize);
    for row in scores.chunks_exact(k) {
        let conf = conf_pred(row).0;
        sum.add(conf);
        over += usize::from(conf > OOD_THRESHOLD);
    }
    Ok(OodMetrics {
        ood_mean: sum.value() / n as f64,
        ood_over_0_9: over as f64 / n as f64,
        rows: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(binning: Binning) -> MetricsConfig {
        MetricsConfig { bins: 10, binning }
    }

    fn bin_of(binning: Binning, conf: f64) -> usize {
        Edges::new(binning, 10).bin(conf)
    }

    #[test]
    fn bin_conventions_on_edges() {
        // (conf, design, netcal, torchmetrics)
        let cases = [
            (0.0, 0, 0, 0),
            (1e-300, 0, 0, 0),
            (0.1, 0, 1, 1),
            (0.3, 2, 2, 3), // numpy.linspace's 3 * 0.1 = 0.30000000000000004 > 0.3
            (0.30000000000000004, 3, 3, 3),
            (0.5, 4, 5, 5),
            (0.7, 6, 6, 7), // 7 * 0.1 = 0.7000000000000001 > 0.7; f32(0.7) is an edge
            (f64::from(0.7f32), 6, 6, 7),
            (0.95, 9, 9, 9),
            (1.0 - 1e-17, 9, 9, 10),  // rounds to 1.0 in f64 already
            (0.999_999_99, 9, 9, 10), // rounds to 1.0 in f32
            (1.0, 9, 9, 10),
        ];
        for (conf, d, n, t) in cases {
            assert_eq!(bin_of(Binning::Design, conf), d, "design {conf}");
            assert_eq!(bin_of(Binning::Netcal, conf), n, "netcal {conf}");
            assert_eq!(
                bin_of(Binning::Torchmetrics, conf),
                t,
                "torchmetrics {conf}"
            );
        }
        // Edges m / M close their bin under the DESIGN rule (also the tuner's binner).
        assert_eq!(bin_of(Binning::Design, 0.1000001), 1);
        assert_eq!(bin_of(Binning::Design, 0.9), 8);
        assert_eq!(bin_of(Binning::Design, 0.05), 0);
        assert_eq!(Edges::new(Binning::Design, 1).bin(0.0), 0);
        assert_eq!(Edges::new(Binning::Netcal, 1).bin(1.0), 0);
        assert_eq!(Edges::new(Binning::Torchmetrics, 1).bin(1.0), 1);
    }

    #[test]
    fn torch_edges_for_ten_bins_are_the_nearest_f32() {
        let Edges::Torch(e) = Edges::new(Binning::Torchmetrics, 10) else {
            unreachable!()
        };
        for (i, x) in e.iter().enumerate() {
            assert_eq!(*x, (i as f64 / 10.0) as f32, "edge {i}");
        }
    }

    #[test]
    fn ece_by_hand() {
        // Rows: conf 0.95 correct, 0.95 wrong, 0.25 wrong, 0.0 (background).
        let scores = [0.95, 0.05, 0.95, 0.0, 0.25, 0.2, 0.0, 0.0];
        let labels = [Some(0), Some(1), Some(1), None];
        let m = evaluate(&scores, 2, &labels, &cfg(Binning::Design)).unwrap();
        // bin 9: acc 0.5, conf 0.95 -> gap 0.45, weight 2/4; bin 2: gap 0.25, 1/4;
        // bin 0: gap 0, 1/4.
        assert!(
            (m.ece - (0.5 * 0.45 + 0.25 * 0.25)).abs() < 1e-15,
            "{}",
            m.ece
        );
        assert!((m.mce - 0.45).abs() < 1e-15);
        assert_eq!((m.rows, m.labelled, m.tp, m.fp), (4, 3, 1, 3));
        assert_eq!(m.reliability.len(), 10);
        assert_eq!(m.reliability[0].count, 1);
        assert_eq!(m.reliability[1].accuracy, None);
        let t = evaluate(&scores, 2, &labels, &cfg(Binning::Torchmetrics)).unwrap();
        assert_eq!(t.reliability.len(), 11);
        assert_eq!((t.reliability[10].lo, t.reliability[10].hi), (1.0, 1.0));
    }

    #[test]
    fn undefined_metrics_are_none() {
        // All background: no labelled row, no true positive.
        let scores = [0.2, 0.7, 0.5, 0.5];
        let m = evaluate(&scores, 2, &[None, None], &MetricsConfig::default()).unwrap();
        assert_eq!(
            (m.nll, m.tp_mean, m.tp_var, m.auroc),
            (None, None, None, None)
        );
        assert_eq!(m.ap, [None, None]);
        assert!(m.fp_mean.is_some());
        let keys: Vec<_> = m.entries(&["a"]).into_iter().map(|e| e.0).collect();
        assert_eq!(
            keys,
            [
                "ece",
                "mce",
                "nll",
                "brier",
                "tp_mean",
                "tp_var",
                "fp_mean",
                "fp_var",
                "auroc",
                "ap_a",
                "ap_class1"
            ]
        );
        // All correct: no false positive.
        let m = evaluate(&scores, 2, &[Some(1), Some(0)], &MetricsConfig::default()).unwrap();
        assert_eq!((m.fp_mean, m.fp_var, m.auroc), (None, None, None));
        assert_eq!(m.tp_mean, Some(0.6));
    }

    #[test]
    fn auroc_and_ap_ties() {
        // conf: TP 0.8, FP 0.8, TP 0.6, FP 0.4: pairs (TP > FP): 0.8>0.4, 0.6>0.4, tie
        // 0.8=0.8 -> 1/2; 0.6 < 0.8 -> 0. AUROC = 2.5 / 4.
        let scores = [0.8, 0.2, 0.8, 0.2, 0.6, 0.4, 0.4, 0.1];
        let labels = [Some(0), Some(1), Some(0), None];
        let m = evaluate(&scores, 2, &labels, &MetricsConfig::default()).unwrap();
        assert_eq!(m.auroc, Some(0.625));
        // Class 0 scores 0.8 (+), 0.8 (-), 0.6 (+), 0.4 (-): thresholds 0.8: P 1/2 R 1/2;
        // 0.6: P 2/3, R 1; AP = 0.5 * 0.5 + 0.5 * 2/3.
        let ap0 = m.ap[0].unwrap();
        assert!((ap0 - (0.25 + 1.0 / 3.0)).abs() < 1e-15, "{ap0}");
        // Class 1 scores 0.4 (-), 0.2 (-), 0.2 (+), 0.1 (-): the positive first counts
        // at threshold 0.2 with precision 1/3 and recall 1.
        let ap1 = m.ap[1].unwrap();
        assert!((ap1 - 1.0 / 3.0).abs() < 1e-15, "{ap1}");
        let pr = precision_recall_curve(&scores, 2, &labels, 0).unwrap();
        assert_eq!(pr.len(), 3);
        assert_eq!(pr[0].threshold, 0.8);
        assert_eq!(pr[2].recall, 1.0);
        assert_eq!(
            precision_recall_curve(&scores, 2, &labels, 2),
            Err(MetricsError::Class)
        );
    }

    #[test]
    fn nll_brier_and_ood() {
        let scores = [0.0, 1.0, 0.5, 0.25];
        let m = evaluate(&scores, 2, &[Some(0), None], &MetricsConfig::default()).unwrap();
        assert!((m.nll.unwrap() + 1e-12f64.ln()).abs() < 1e-12);
        assert!((m.brier - (2.0 + 0.25 + 0.0625) / 2.0).abs() < 1e-15);
        let ood = ood_metrics(&[0.95, 0.0, 0.9, 0.05, 0.3, 0.2], 2).unwrap();
        assert!((ood.ood_mean - (0.95 + 0.9 + 0.3) / 3.0).abs() < 1e-15);
        assert_eq!(ood.ood_over_0_9, 1.0 / 3.0);
        let keys = m.with_ood(ood).entries::<&str>(&[]);
        assert_eq!(keys[keys.len() - 2].0, "ood_mean");
        assert_eq!(
            keys[keys.len() - 1],
            (String::from("ood_over_0_9"), Some(1.0 / 3.0))
        );
    }

    #[test]
    fn bad_inputs_are_errors() {
        let c = MetricsConfig::default();
        assert_eq!(evaluate(&[], 2, &[], &c), Err(MetricsError::Empty));
        assert_eq!(evaluate(&[0.5], 0, &[], &c), Err(MetricsError::Shape));
        assert_eq!(
            evaluate(&[0.5; 3], 2, &[None], &c),
            Err(MetricsError::Shape)
        );
        assert_eq!(
            evaluate(&[0.5; 4], 2, &[None], &c),
            Err(MetricsError::Shape)
        );
        for bad in [f64::NAN, f64::INFINITY, -0.1, 1.0 + 1e-12] {
            assert_eq!(
                evaluate(&[0.5, 0.5, 0.5, bad], 2, &[None, None], &c),
                Err(MetricsError::Score { row: 1, class: 1 })
            );
        }
        assert_eq!(
            evaluate(&[0.5; 4], 2, &[None, Some(2)], &c),
            Err(MetricsError::Label { row: 1 })
        );
        for bins in [0, MAX_BINS + 1] {
            let c = MetricsConfig { bins, ..c };
            assert_eq!(evaluate(&[0.5; 2], 2, &[None], &c), Err(MetricsError::Bins));
        }
        assert_eq!(ood_metrics(&[], 3), Err(MetricsError::Empty));
        assert_eq!(
            ood_metrics(&[0.5, f64::NAN], 2),
            Err(MetricsError::Score { row: 0, class: 1 })
        );
        assert_eq!("netcal".parse(), Ok(Binning::Netcal));
        assert_eq!(
            "NetCal".parse::<Binning>(),
            Err(MetricsError::UnknownBinning)
        );
    }

    #[test]
    fn one_bin_and_many_bins() {
        let scores = [0.0, 0.0, 1.0, 0.0, 0.5, 0.5];
        let labels = [Some(0), Some(1), None];
        for binning in Binning::ALL {
            for bins in [1, 3, 1000] {
                let m = evaluate(&scores, 2, &labels, &MetricsConfig { bins, binning }).unwrap();
                let counted: usize = m.reliability.iter().map(|b| b.count).sum();
                assert_eq!(counted, 3, "{binning} {bins}");
                assert!(m.ece >= 0.0 && m.ece <= m.mce + 1e-15);
            }
        }
    }
}
