//! Running sums: compensated summation, and the [`Accumulator`] of the metrics that
//! can be computed in one pass without storing scores (`ece`, `mce`, `nll`, `brier`,
//! `accuracy`), and optionally the average precision of each class (which keeps one
//! sort key per row and class).

use super::binning::{calibration, BinSum, CalibrationBin, Edges};
use super::outcome::{outcome, Outcome};
use super::ranking::{average_precision, pr_key, pr_points_of_keys};
use super::{MetricsConfig, MetricsError, NLL_FLOOR};

/// Neumaier's compensated sum: the error does not grow with the number of terms.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Sum {
    sum: f64,
    carry: f64,
}

impl Sum {
    pub(super) fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.carry += (self.sum - t) + x;
        } else {
            self.carry += (x - t) + self.sum;
        }
        self.sum = t;
    }

    pub(super) fn value(self) -> f64 {
        self.sum + self.carry
    }

    /// Adds another sum (its value and its carry).
    pub(super) fn merge(&mut self, other: Self) {
        self.add(other.sum);
        self.add(other.carry);
    }

    /// `(sum, carry)`, for serialization.
    pub(super) fn parts(self) -> (f64, f64) {
        (self.sum, self.carry)
    }

    /// A sum from [`parts`](Self::parts).
    pub(super) fn from_parts((sum, carry): (f64, f64)) -> Self {
        Self { sum, carry }
    }
}

/// One confidence bin as serialized: count, correct, and the sum of confidences.
type BinWire = (u64, u64, (f64, f64));

/// The serialized state of an [`Accumulator`] (its edges follow from the config).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct AccumulatorWire {
    /// Per bin: count, correct, and the sum of confidences.
    bins: Option<Vec<BinWire>>,
    nll: Option<((f64, f64), u64)>,
    brier: Option<(f64, f64)>,
    rows: u64,
    labelled: u64,
    correct: u64,
}

/// Mean and population variance (two passes); `None` for no values.
pub(super) fn mean_var(values: impl Iterator<Item = f64> + Clone) -> Option<(f64, f64)> {
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

/// Which metrics an [`Accumulator`] keeps (each costs time per row).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Parts {
    /// `ece`, `mce` and `accuracy`: the decision and the confidence bin of every row.
    pub calibration: bool,
    /// `nll`: a logarithm per labelled row.
    pub nll: bool,
    /// `brier`: a square per score.
    pub brier: bool,
    /// `ap_<class>` and their mean: a sort key per row and class, sorted at the end.
    pub ranking: bool,
}

impl Parts {
    /// Every metric.
    pub const ALL: Self = Self {
        calibration: true,
        nll: true,
        brier: true,
        ranking: true,
    };
}

/// One pass over the rows of one method: the sums behind `ece`, `mce`, `nll`,
/// `brier` and `accuracy` (DESIGN §1.5), without storing scores. The tuner scores each candidate with
/// one, and [`evaluate`](super::evaluate) computes those metrics with one.
///
/// Rows are not checked: give scores in `[0, 1]` and labels below `K` (as
/// [`evaluate`](super::evaluate) checks), or the sums mean nothing (but never panic).
///
/// # Examples
///
/// ```
/// use mlmap_host::metrics::{Accumulator, MetricsConfig, Parts};
///
/// let mut acc = Accumulator::new(&MetricsConfig::default(), Parts::ALL)?;
/// acc.add(&[0.9f32, 0.1], &[2.0f32, -1.0], Some(0));
/// acc.add(&[0.3f32, 0.6], &[0.0f32, 1.0], None);
/// assert_eq!(acc.rows(), 2);
/// let brier = (0.01 + 0.01 + 0.09 + 0.36) / 2.0;
/// assert!((acc.brier().unwrap() - brier).abs() < 1e-7);
/// assert_eq!(acc.accuracy(), Some(1.0));
/// # Ok::<(), mlmap_host::metrics::MetricsError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Accumulator {
    edges: Edges,
    bins: Option<Vec<BinSum>>,
    nll: Option<(Sum, usize)>,
    brier: Option<Sum>,
    /// Per class, the precision-recall sort key of every row (with `ranking`).
    ranking: Option<Vec<Vec<u64>>>,
    rows: usize,
    labelled: usize,
    correct: usize,
}

impl Accumulator {
    /// An empty accumulator keeping `parts`, binning as `cfg` says.
    ///
    /// # Errors
    ///
    /// [`MetricsError::Bins`] when `cfg.bins` is 0 or above [`MAX_BINS`](super::MAX_BINS).
    pub fn new(cfg: &MetricsConfig, parts: Parts) -> Result<Self, MetricsError> {
        if cfg.bins == 0 || cfg.bins > super::MAX_BINS {
            return Err(MetricsError::Bins);
        }
        let edges = Edges::new(cfg.binning, cfg.bins);
        let bins = parts
            .calibration
            .then(|| vec![BinSum::default(); edges.len()]);
        Ok(Self {
            edges,
            bins,
            nll: parts.nll.then(|| (Sum::default(), 0)),
            brier: parts.brier.then(Sum::default),
            ranking: parts.ranking.then(Vec::new),
            rows: 0,
            labelled: 0,
            correct: 0,
        })
    }

    /// Adds one row: its `K` scores, its logits (for the decision, DESIGN §1.7; may be
    /// empty) and its label (`None` for background).
    pub fn add<S, L>(&mut self, scores: &[S], logits: &[L], label: Option<usize>)
    where
        S: Copy + PartialOrd + Into<f64>,
        L: Copy + PartialOrd,
    {
        let o = self.bins.is_some().then(|| outcome(scores, logits, label));
        self.add_row(scores, label, o.as_ref());
    }

    /// Adds a row whose outcome is known (needed only when calibration is kept).
    pub(super) fn add_row<S: Copy + Into<f64>>(
        &mut self,
        scores: &[S],
        label: Option<usize>,
        o: Option<&Outcome>,
    ) {
        self.rows += 1;
        self.labelled += usize::from(label.is_some());
        if let (Some(bins), Some(o)) = (&mut self.bins, o) {
            self.correct += usize::from(o.correct);
            if let Some(b) = bins.get_mut(self.edges.bin(o.conf)) {
                b.count += 1;
                b.correct += usize::from(o.correct);
                b.conf.add(o.conf);
            }
        }
        if let Some((sum, n)) = &mut self.nll {
            if let Some(l) = label {
                let s: f64 = scores.get(l).map_or(0.0, |&s| s.into());
                sum.add(-s.max(NLL_FLOOR).ln());
                *n += 1;
            }
        }
        if let Some(keys) = &mut self.ranking {
            if keys.len() < scores.len() {
                keys.resize_with(scores.len(), Vec::new);
            }
            for (i, (class_keys, &s)) in keys.iter_mut().zip(scores).enumerate() {
                class_keys.push(pr_key(s.into(), label == Some(i)));
            }
        }
        if let Some(sum) = &mut self.brier {
            for (i, &s) in scores.iter().enumerate() {
                let y = if label == Some(i) { 1.0 } else { 0.0 };
                let d = s.into() - y;
                sum.add(d * d);
            }
        }
    }

    /// Adds the rows of `other`, an accumulator of the same configuration and parts
    /// without ranking: the sums are added (compensated), the counts exactly.
    ///
    /// # Errors
    ///
    /// [`MetricsError::Shape`] when the two keep different bins or parts, or either
    /// keeps the ranking.
    pub fn merge(&mut self, other: &Self) -> Result<(), MetricsError> {
        let same_bins = match (&self.bins, &other.bins) {
            (Some(a), Some(b)) => a.len() == b.len(),
            (None, None) => true,
            _ => false,
        };
        if !same_bins
            || self.nll.is_some() != other.nll.is_some()
            || self.brier.is_some() != other.brier.is_some()
            || self.ranking.is_some()
            || other.ranking.is_some()
        {
            return Err(MetricsError::Shape);
        }
        if let (Some(a), Some(b)) = (&mut self.bins, &other.bins) {
            for (x, y) in a.iter_mut().zip(b) {
                x.count += y.count;
                x.correct += y.correct;
                x.conf.merge(y.conf);
            }
        }
        if let (Some((s, n)), Some((t, m))) = (&mut self.nll, other.nll) {
            s.merge(t);
            *n += m;
        }
        if let (Some(s), Some(t)) = (&mut self.brier, other.brier) {
            s.merge(t);
        }
        self.rows += other.rows;
        self.labelled += other.labelled;
        self.correct += other.correct;
        Ok(())
    }

    /// The state as plain numbers (without the ranking part).
    pub(super) fn to_wire(&self) -> AccumulatorWire {
        AccumulatorWire {
            bins: self.bins.as_ref().map(|b| {
                b.iter()
                    .map(|x| (x.count as u64, x.correct as u64, x.conf.parts()))
                    .collect()
            }),
            nll: self.nll.map(|(s, n)| (s.parts(), n as u64)),
            brier: self.brier.map(Sum::parts),
            rows: self.rows as u64,
            labelled: self.labelled as u64,
            correct: self.correct as u64,
        }
    }

    /// An accumulator of `cfg` from [`to_wire`](Self::to_wire)'s state; `None` when
    /// the state does not fit the configuration (another number of bins, counts that
    /// contradict each other).
    pub(super) fn from_wire(cfg: &MetricsConfig, w: &AccumulatorWire) -> Option<Self> {
        let parts = Parts {
            calibration: w.bins.is_some(),
            nll: w.nll.is_some(),
            brier: w.brier.is_some(),
            ranking: false,
        };
        let mut acc = Self::new(cfg, parts).ok()?;
        let size = |v: u64| usize::try_from(v).ok();
        if let (Some(bins), Some(wb)) = (&mut acc.bins, &w.bins) {
            if bins.len() != wb.len() {
                return None;
            }
            for (b, &(count, correct, conf)) in bins.iter_mut().zip(wb) {
                if correct > count {
                    return None;
                }
                *b = BinSum {
                    count: size(count)?,
                    correct: size(correct)?,
                    conf: Sum::from_parts(conf),
                };
            }
        }
        acc.nll = match w.nll {
            Some((s, n)) => Some((Sum::from_parts(s), size(n)?)),
            None => None,
        };
        acc.brier = w.brier.map(Sum::from_parts);
        acc.rows = size(w.rows)?;
        acc.labelled = size(w.labelled)?;
        acc.correct = size(w.correct)?;
        if acc.labelled > acc.rows || acc.correct > acc.labelled {
            return None;
        }
        Some(acc)
    }

    /// Rows added.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Rows added with a class label.
    pub fn labelled(&self) -> usize {
        self.labelled
    }

    /// `accuracy`, the fraction of labelled rows whose decision is their label
    /// (DESIGN §1.5, §1.7); `None` unless calibration is kept or without a labelled row.
    pub fn accuracy(&self) -> Option<f64> {
        self.bins.as_ref()?;
        (self.labelled > 0).then(|| self.correct as f64 / self.labelled as f64)
    }

    /// The reliability bins, `ece` and `mce`; `None` unless calibration is kept.
    pub fn calibration(&self) -> Option<(Vec<CalibrationBin>, f64, f64)> {
        let bins = self.bins.as_ref()?;
        Some(calibration(&self.edges, bins, self.rows.max(1)))
    }

    /// `ece` (0 without rows); `None` unless calibration is kept.
    pub fn ece(&self) -> Option<f64> {
        self.calibration().map(|c| c.1)
    }

    /// `nll`, the mean `-ln(max(s_label, 1e-12))` over labelled rows; `None` unless
    /// kept or without a labelled row.
    pub fn nll(&self) -> Option<f64> {
        self.nll
            .filter(|&(_, n)| n > 0)
            .map(|(sum, n)| sum.value() / n as f64)
    }

    /// `ap_<class>` of every class seen, as [`average_precision`] of the metrics core
    /// (`None` for a class without positives); `None` unless ranking is kept.
    pub fn average_precisions(&self) -> Option<Vec<Option<f64>>> {
        let keys = self.ranking.as_ref()?;
        Some(
            keys.iter()
                .map(|k| average_precision(&pr_points_of_keys(k.clone())))
                .collect(),
        )
    }

    /// `mAP`, the mean of the defined `ap_<class>` ([`Metrics::mean_ap`](super::Metrics::mean_ap));
    /// `None` unless ranking is kept or when no class has a positive row.
    pub fn mean_ap(&self) -> Option<f64> {
        super::mean_of_defined(&self.average_precisions()?)
    }

    /// `brier`, the mean over rows of `sum_i (s_i - y_i)^2` (0 without rows); `None`
    /// unless kept.
    pub fn brier(&self) -> Option<f64> {
        self.brier.map(|sum| sum.value() / self.rows.max(1) as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn average_precision_by_hand() {
        // Class 0: positives at scores 0.8 and 0.35, negatives at 0.4 and 0.1:
        // precision 1 at recall 1/2, then 2/3 at recall 1: AP = 1/2 + 1/3.
        // Class 1: its only positive ranks first: AP = 1.
        let rows: [([f64; 2], Option<usize>); 4] = [
            ([0.8, 0.1], Some(0)),
            ([0.4, 0.3], None),
            ([0.35, 0.6], Some(0)),
            ([0.1, 0.9], Some(1)),
        ];
        let mut acc = Accumulator::new(&MetricsConfig::default(), Parts::ALL).unwrap();
        for (s, l) in &rows {
            acc.add(s, &[] as &[f64], *l);
        }
        let ap = acc.average_precisions().unwrap();
        assert!((ap[0].unwrap() - (0.5 + 1.0 / 3.0)).abs() < 1e-12, "{ap:?}");
        assert_eq!(ap[1], Some(1.0));
        let want = (0.5 + 1.0 / 3.0 + 1.0) / 2.0;
        assert!((acc.mean_ap().unwrap() - want).abs() < 1e-12);
        // Without the ranking part there is no mAP.
        let parts = Parts {
            ranking: false,
            ..Parts::ALL
        };
        let acc = Accumulator::new(&MetricsConfig::default(), parts).unwrap();
        assert_eq!(acc.mean_ap(), None);
    }
}
