//! Evaluation metrics of DESIGN §1.5, on final scores (objectness included).
//!
//! Input is always the same: `N x K` scores, row-major `f64`, each in `[0, 1]`, and one
//! label per row (`Some(class)` or `None` for background). From them:
//!
//! * `conf = max_i s_i`; a row is **correct** (a true positive) when its label is a
//!   class and the row's [`decision`] equals it. Every other row is a false positive.
//! * `ece`, `mce`: the calibration gap over equal-width confidence bins, with the bin
//!   convention a parameter ([`Binning`]).
//! * `nll`, `brier`, the mean and population variance of `conf` over true and false
//!   positives, `auroc` (true against false positives), `accuracy` (the fraction of
//!   labelled rows that are correct), `ap_<class>` as
//!   `sklearn.metrics.average_precision_score`, and `ood_mean`, `ood_over_0_9`,
//!   `ood_auroc` and `ood_fpr95` (known rows against unseen ones) on an
//!   out-of-distribution set.
//!
//! A metric with nothing to average (no labelled row, no true or false positive, no
//! positive of a class) is `None`, which reports write as `null`. Sums use
//! compensated (Neumaier) summation, and each metric that ranks rows sorts once, so a
//! million rows take a fraction of a second.
//!
//! The module is the one home of these computations: [`crate::plots`] draws
//! from its bins and curves, and [`crate::tune`] scores candidates with its
//! [`Accumulator`].
//!
//! The values are checked against an independent numpy / scikit-learn implementation
//! (`tools/metrics_reference.py`, golden files in `tests/golden/metrics/`).

mod accumulate;
mod binning;
mod outcome;
mod ranking;
mod stream;

use core::fmt;

pub use self::accumulate::{Accumulator, Parts};
pub use self::binning::{Binning, CalibrationBin};
pub use self::outcome::{decision, outcomes, outcomes_with_logits, Outcome};
pub use self::ranking::{
    average_precision, fpr_at_95_tpr, precision_recall_curve, separation_auroc, PrPoint,
};
pub use self::stream::{StreamMetrics, DEFAULT_RANK_LEVELS, MAX_RANK_LEVELS};

use self::accumulate::{mean_var, Sum};
use self::outcome::{check_scores, outcome};
use self::ranking::{auroc, pr_points};
use super::baselines::NLL_FLOOR;

/// Number of confidence bins of `ece` and `mce` unless configured otherwise (DESIGN §1.5).
pub const DEFAULT_BINS: usize = 10;

/// Largest accepted number of confidence bins.
pub const MAX_BINS: usize = 1 << 20;

/// `ood_over_0_9` counts the out-of-distribution rows whose `conf` exceeds this.
pub const OOD_THRESHOLD: f64 = 0.9;

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

/// Metrics of an out-of-distribution set (DESIGN §1.5), from [`ood_metrics`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OodMetrics {
    /// `ood_mean`: mean `conf` over the set.
    pub ood_mean: f64,
    /// `ood_over_0_9`: fraction of rows with `conf > 0.9`.
    pub ood_over_0_9: f64,
    /// `ood_auroc`: the probability that a known row's `conf` (a row labelled with a
    /// class) exceeds an unseen row's, ties 1/2 ([`separation_auroc`]); `None` without
    /// known rows, or from [`ood_metrics`] alone.
    pub auroc: Option<f64>,
    /// `ood_fpr95`: the share of unseen rows whose `conf` reaches the threshold that
    /// keeps 95 % of the known rows ([`fpr_at_95_tpr`]); `None` as `auroc`.
    pub fpr95: Option<f64>,
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
    /// `accuracy`: fraction of the labelled rows whose [`decision`] is their label;
    /// `None` without any.
    pub accuracy: Option<f64>,
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
    pub const LEADING_KEYS: [&'static str; 10] = [
        "ece", "mce", "nll", "brier", "tp_mean", "tp_var", "fp_mean", "fp_var", "auroc", "accuracy",
    ];

    /// `mAP`: the mean of the defined `ap_<class>`; `None` when no class has a
    /// positive row.
    pub fn mean_ap(&self) -> Option<f64> {
        mean_of_defined(&self.ap)
    }

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
            self.accuracy,
        ];
        let mut out: Vec<(String, Option<f64>)> = Self::LEADING_KEYS
            .iter()
            .zip(leading)
            .map(|(k, v)| (String::from(*k), v))
            .collect();
        for (i, ap) in self.ap.iter().enumerate() {
            let key = match class_names.get(i) {
                Some(name) => format!("ap_{}", name.as_ref()),
                None => format!("ap_class{i}"),
            };
            out.push((key, *ap));
        }
        if let Some(ood) = self.ood {
            out.push((String::from("ood_mean"), Some(ood.ood_mean)));
            out.push((String::from("ood_over_0_9"), Some(ood.ood_over_0_9)));
            out.push((String::from("ood_auroc"), ood.auroc));
            out.push((String::from("ood_fpr95"), ood.fpr95));
        }
        out
    }
}

/// The reliability bins, `ece` and `mce` of a set of outcomes, from [`reliability`].
#[derive(Debug, Clone, PartialEq)]
pub struct Reliability {
    /// The confidence bins, in order ([`Binning::bin_count`] of them).
    pub bins: Vec<CalibrationBin>,
    /// `ece`; `None` without rows.
    pub ece: Option<f64>,
    /// `mce`; `None` without rows.
    pub mce: Option<f64>,
}

/// The reliability bins, `ece` and `mce` of `outcomes` (from [`outcomes`] or
/// [`outcomes_with_logits`]), binned as `cfg` says: the data of a reliability diagram.
///
/// # Errors
///
/// [`MetricsError::Bins`]: `cfg.bins` is 0 or above [`MAX_BINS`].
///
/// # Panics
///
/// Never.
pub fn reliability(outcomes: &[Outcome], cfg: &MetricsConfig) -> Result<Reliability, MetricsError> {
    let parts = Parts {
        calibration: true,
        nll: false,
        brier: false,
        ranking: false,
    };
    let mut acc = Accumulator::new(cfg, parts)?;
    for o in outcomes {
        acc.add_row::<f64>(&[], None, Some(o));
    }
    let (bins, ece, mce) = acc.calibration().unwrap_or_default();
    let some = !outcomes.is_empty();
    Ok(Reliability {
        bins,
        ece: some.then_some(ece),
        mce: some.then_some(mce),
    })
}

/// Every metric of DESIGN §1.5 except the out-of-distribution ones.
///
/// `scores` holds `N x K` final scores (row-major, objectness included), `labels` one
/// label per row (`None` for background).
///
/// # Examples
///
/// ```
/// use mlmap_host::metrics::{evaluate, MetricsConfig};
///
/// let scores = [0.9, 0.1, 0.3, 0.6, 0.8, 0.0];
/// let labels = [Some(0), Some(0), None];
/// let m = evaluate(&scores, 2, &labels, &MetricsConfig::default())?;
/// assert_eq!((m.tp, m.fp), (1, 2));
/// assert_eq!(m.auroc, Some(1.0));
/// assert_eq!(m.accuracy, Some(0.5));
/// assert_eq!(m.entries(&["car", "person"])[10].0, "ap_car");
/// # Ok::<(), mlmap_host::metrics::MetricsError>(())
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
    evaluate_with_logits(scores, &[], k, labels, cfg)
}

/// [`evaluate`] with each row decided by [`decision`] from its scores and its logits
/// (`logits`: `N x K`, row-major, or empty).
///
/// # Errors
///
/// As [`evaluate`]; [`MetricsError::Shape`] also when `logits` is neither empty nor as
/// long as `scores`.
///
/// # Panics
///
/// Never.
pub fn evaluate_with_logits(
    scores: &[f64],
    logits: &[f64],
    k: usize,
    labels: &[Option<usize>],
    cfg: &MetricsConfig,
) -> Result<Metrics, MetricsError> {
    let mut acc = Accumulator::new(cfg, Parts::ALL)?;
    let outcomes = outcomes_with_logits(scores, logits, k, labels)?;
    for ((row, label), o) in scores.chunks_exact(k).zip(labels).zip(&outcomes) {
        acc.add_row(row, *label, Some(o));
    }
    let (reliability, ece, mce) = acc.calibration().unwrap_or_default();
    let n = outcomes.len();

    let tp_conf = outcomes.iter().filter(|o| o.correct).map(|o| o.conf);
    let fp_conf = outcomes.iter().filter(|o| !o.correct).map(|o| o.conf);
    let tp_stats = mean_var(tp_conf);
    let fp_stats = mean_var(fp_conf);
    let tp = outcomes.iter().filter(|o| o.correct).count();

    Ok(Metrics {
        ece,
        mce,
        nll: acc.nll(),
        brier: acc.brier().unwrap_or_default(),
        tp_mean: tp_stats.map(|s| s.0),
        tp_var: tp_stats.map(|s| s.1),
        fp_mean: fp_stats.map(|s| s.0),
        fp_var: fp_stats.map(|s| s.1),
        auroc: auroc(&outcomes),
        accuracy: acc.accuracy(),
        ap: (0..k)
            .map(|c| average_precision(&pr_points(scores, k, labels, c)))
            .collect(),
        ood: None,
        rows: n,
        labelled: acc.labelled(),
        tp,
        fp: n - tp,
        reliability,
    })
}

/// The mean of the defined values; `None` when none is.
fn mean_of_defined(values: &[Option<f64>]) -> Option<f64> {
    let defined: Vec<f64> = values.iter().flatten().copied().collect();
    (!defined.is_empty()).then(|| defined.iter().sum::<f64>() / defined.len() as f64)
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
        let conf = outcome::<f64, f64>(row, &[], None).conf;
        sum.add(conf);
        over += usize::from(conf > OOD_THRESHOLD);
    }
    Ok(OodMetrics {
        ood_mean: sum.value() / n as f64,
        ood_over_0_9: over as f64 / n as f64,
        auroc: None,
        fpr95: None,
        rows: n,
    })
}

/// [`ood_metrics`] of the unseen rows' `scores`, with `ood_auroc` and `ood_fpr95` of
/// the known rows' confidences `known` (from [`known_confidences`]) against theirs.
///
/// # Errors
///
/// As [`ood_metrics`].
///
/// # Panics
///
/// Never.
pub fn ood_metrics_against(
    scores: &[f64],
    k: usize,
    known: &[f64],
) -> Result<OodMetrics, MetricsError> {
    let mut m = ood_metrics(scores, k)?;
    let unseen: Vec<f64> = scores
        .chunks_exact(k)
        .map(|row| outcome::<f64, f64>(row, &[], None).conf)
        .collect();
    m.auroc = separation_auroc(known, &unseen);
    m.fpr95 = fpr_at_95_tpr(known, &unseen);
    Ok(m)
}

/// The `conf` (largest score) of every row labelled with a class: the known rows of
/// `ood_auroc` and `ood_fpr95`. Rows beyond the shorter of `scores` and `labels` are
/// left out.
pub fn known_confidences(scores: &[f64], k: usize, labels: &[Option<usize>]) -> Vec<f64> {
    if k == 0 {
        return Vec::new();
    }
    scores
        .chunks_exact(k)
        .zip(labels)
        .filter(|(_, l)| l.is_some())
        .map(|(row, _)| outcome::<f64, f64>(row, &[], None).conf)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(binning: Binning) -> MetricsConfig {
        MetricsConfig { bins: 10, binning }
    }

    #[test]
    fn ties_are_decided_by_the_logits() {
        // Row 0 scores OS / K for both classes (no histogram knew its logits) and is
        // labelled 1, whose logit is the larger: correct with the logits, wrong without.
        let scores = [0.25, 0.25, 0.9, 0.1];
        let logits = [-3.0, 2.0, 1.0, 0.0];
        let labels = [Some(1), Some(0)];
        let c = MetricsConfig::default();
        let plain = evaluate(&scores, 2, &labels, &c).unwrap();
        assert_eq!((plain.tp, plain.accuracy), (1, Some(0.5)));
        let decided = evaluate_with_logits(&scores, &logits, 2, &labels, &c).unwrap();
        assert_eq!((decided.tp, decided.accuracy), (2, Some(1.0)));
        assert_eq!((decided.fp_mean, decided.tp_mean), (None, Some(0.575)));
        assert_eq!(
            evaluate_with_logits(&scores, &logits[..3], 2, &labels, &c),
            Err(MetricsError::Shape)
        );
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
        assert_eq!(m.accuracy, Some(1.0 / 3.0));
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
            (m.nll, m.tp_mean, m.tp_var, m.auroc, m.accuracy),
            (None, None, None, None, None)
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
                "accuracy",
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
        let keys = m.clone().with_ood(ood).entries::<&str>(&[]);
        assert_eq!(keys[keys.len() - 4].0, "ood_mean");
        assert_eq!(
            keys[keys.len() - 3],
            (String::from("ood_over_0_9"), Some(1.0 / 3.0))
        );
        assert_eq!(keys[keys.len() - 1], (String::from("ood_fpr95"), None));
        // Known confidences 1.0 (row 0, labelled) against unseen 0.95, 0.9, 0.3.
        let known = known_confidences(&scores, 2, &[Some(0), None]);
        assert_eq!(known, [1.0]);
        let against = ood_metrics_against(&[0.95, 0.0, 0.9, 0.05, 0.3, 0.2], 2, &known).unwrap();
        assert_eq!((against.auroc, against.fpr95), (Some(1.0), Some(0.0)));
        assert_eq!(against.ood_mean, ood.ood_mean);
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
