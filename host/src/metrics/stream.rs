//! [`StreamMetrics`]: the metrics of one method over rows given in any number of pieces,
//! in memory that does not grow with the rows, merged exactly across shards.

use serde::{Deserialize, Serialize};

use super::accumulate::AccumulatorWire;
use super::outcome::outcome;
use super::ranking::{average_precision, PrPoint};
use super::{Accumulator, Metrics, MetricsConfig, MetricsError, Parts};

/// Score levels of the rank counts unless configured otherwise: `2^16`, so scores
/// closer than about `1.5e-5` count as tied in `auroc` and `ap_<class>`.
pub const DEFAULT_RANK_LEVELS: u32 = 1 << 16;

/// Largest accepted number of score levels, `2^20`: the counts then take 16 MB per
/// class and method.
pub const MAX_RANK_LEVELS: u32 = 1 << 20;

const MAGIC: &[u8; 8] = b"MLMAPEVS";
const WIRE_VERSION: u16 = 1;
const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Count, mean and sum of squared deviations (Welford), merged as Chan et al.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
struct Moments {
    n: u64,
    mean: f64,
    m2: f64,
}

impl Moments {
    fn add(&mut self, x: f64) {
        self.n += 1;
        let d = x - self.mean;
        self.mean += d / self.n as f64;
        self.m2 += d * (x - self.mean);
    }

    fn merge(&mut self, o: &Self) {
        if o.n == 0 {
            return;
        }
        let n = self.n + o.n;
        let d = o.mean - self.mean;
        self.mean += d * o.n as f64 / n as f64;
        self.m2 += o.m2 + d * d * self.n as f64 * o.n as f64 / n as f64;
        self.n = n;
    }

    fn mean_var(&self) -> Option<(f64, f64)> {
        (self.n > 0).then(|| (self.mean, self.m2.max(0.0) / self.n as f64))
    }
}

/// Per score level `0 ..= levels`, `[positives, negatives]`.
type Counts = Vec<[u64; 2]>;

fn merge_counts(a: &mut Counts, b: &Counts) {
    for (x, y) in a.iter_mut().zip(b) {
        x[0] += y[0];
        x[1] += y[1];
    }
}

/// The level of a score: `round(s * levels)`, the score clamped to `[0, 1]` (the
/// callers check scores; a score outside cannot index outside).
fn level(s: f64, levels: u32) -> u32 {
    (s.clamp(0.0, 1.0) * f64::from(levels)).round() as u32
}

fn bump(counts: &mut Counts, level: u32, side: usize) {
    if let Some(c) = counts
        .get_mut(level as usize)
        .and_then(|pair| pair.get_mut(side))
    {
        *c += 1;
    }
}

/// The metrics of DESIGN §1.5 for one method, accumulated row by row: the confidence
/// bins, sums and counts of `ece`, `mce`, `nll`, `brier` and `accuracy` (as
/// [`evaluate`](super::evaluate) computes them, up to the order of floating-point
/// additions), the moments of `tp_*` and `fp_*`, and for `auroc` and `ap_<class>`
/// exact counts of positives and negatives per score level (`levels + 1` levels on
/// `[0, 1]`): those two metrics are exact for scores on the levels, and otherwise
/// count scores of one level as tied. Memory is `(K + 1) * (levels + 1)` pairs of
/// counts (16 bytes each), whatever the number of rows; [`merge`](Self::merge) is exact for the counts
/// and compensated for the sums, so shards merge in any order.
///
/// # Examples
///
/// ```
/// use mlmap_host::metrics::{MetricsConfig, StreamMetrics};
///
/// let cfg = MetricsConfig::default();
/// let mut a = StreamMetrics::new(2, &cfg, 1 << 16)?;
/// let mut b = a.clone();
/// a.add(&[0.9, 0.1], &[2.0, -1.0], Some(0));
/// b.add(&[0.3, 0.6], &[0.0, 1.0], None);
/// a.merge(&b)?;
/// let m = a.report()?;
/// assert_eq!((m.rows, m.labelled, m.tp), (2, 1, 1));
/// assert_eq!(m.auroc, Some(1.0));
/// # Ok::<(), mlmap_host::metrics::MetricsError>(())
/// ```
#[derive(Debug, Clone)]
pub struct StreamMetrics {
    k: usize,
    cfg: MetricsConfig,
    levels: u32,
    acc: Accumulator,
    tp: Moments,
    fp: Moments,
    /// `conf` per level: `[true positives, false positives]`.
    conf: Counts,
    /// Per class, its score per level: `[rows of the class, other rows]`.
    classes: Vec<Counts>,
}

/// The serialized state of a [`StreamMetrics`].
#[derive(Debug, Clone, Serialize, Deserialize)]
struct StreamWire {
    k: u64,
    bins: u64,
    binning: u8,
    levels: u32,
    acc: AccumulatorWire,
    tp: Moments,
    fp: Moments,
    conf: Vec<(u32, [u64; 2])>,
    classes: Vec<Vec<(u32, [u64; 2])>>,
}

impl StreamMetrics {
    /// No rows yet, for `k` classes.
    ///
    /// # Errors
    ///
    /// [`MetricsError::Shape`] for `k = 0` or `levels` outside `1..=MAX_RANK_LEVELS`;
    /// [`MetricsError::Bins`] for a bad number of bins.
    pub fn new(k: usize, cfg: &MetricsConfig, levels: u32) -> Result<Self, MetricsError> {
        if k == 0 || !(1..=MAX_RANK_LEVELS).contains(&levels) {
            return Err(MetricsError::Shape);
        }
        let parts = Parts {
            ranking: false,
            ..Parts::ALL
        };
        Ok(Self {
            k,
            cfg: *cfg,
            levels,
            acc: Accumulator::new(cfg, parts)?,
            tp: Moments::default(),
            fp: Moments::default(),
            conf: vec![[0, 0]; levels as usize + 1],
            classes: vec![vec![[0, 0]; levels as usize + 1]; k],
        })
    }

    fn level(&self, s: f64) -> u32 {
        level(s, self.levels)
    }

    /// Adds one row: its `K` scores in `[0, 1]`, its logits (the decision's ties,
    /// DESIGN §1.7; may be empty) and its label (`None` for background). A row of
    /// another length is ignored.
    pub fn add(&mut self, scores: &[f64], logits: &[f64], label: Option<usize>) {
        if scores.len() != self.k {
            return;
        }
        let o = outcome(scores, logits, label);
        self.acc.add(scores, logits, label);
        let conf_level = self.level(o.conf);
        let side = usize::from(!o.correct);
        if o.correct {
            self.tp.add(o.conf);
        } else {
            self.fp.add(o.conf);
        }
        bump(&mut self.conf, conf_level, side);
        let levels = self.levels;
        for (i, (&s, counts)) in scores.iter().zip(&mut self.classes).enumerate() {
            bump(counts, level(s, levels), usize::from(label != Some(i)));
        }
    }

    /// Adds the rows of `other`.
    ///
    /// # Errors
    ///
    /// [`MetricsError::Shape`] when `other` has another number of classes, bins,
    /// binning or levels.
    pub fn merge(&mut self, other: &Self) -> Result<(), MetricsError> {
        if (self.k, self.cfg, self.levels) != (other.k, other.cfg, other.levels) {
            return Err(MetricsError::Shape);
        }
        self.acc.merge(&other.acc)?;
        self.tp.merge(&other.tp);
        self.fp.merge(&other.fp);
        merge_counts(&mut self.conf, &other.conf);
        for (a, b) in self.classes.iter_mut().zip(&other.classes) {
            merge_counts(a, b);
        }
        Ok(())
    }

    /// `K`, the number of classes.
    pub fn k(&self) -> usize {
        self.k
    }

    /// The binning settings and the number of score levels.
    pub fn config(&self) -> (MetricsConfig, u32) {
        (self.cfg, self.levels)
    }

    /// Rows added.
    pub fn rows(&self) -> usize {
        self.acc.rows()
    }

    /// The metrics of the rows added (no out-of-distribution part).
    ///
    /// # Errors
    ///
    /// [`MetricsError::Empty`] without rows.
    pub fn report(&self) -> Result<Metrics, MetricsError> {
        let n = self.acc.rows();
        if n == 0 {
            return Err(MetricsError::Empty);
        }
        let (reliability, ece, mce) = self.acc.calibration().unwrap_or_default();
        let tp = self.tp.mean_var();
        let fp = self.fp.mean_var();
        Ok(Metrics {
            ece,
            mce,
            nll: self.acc.nll(),
            brier: self.acc.brier().unwrap_or_default(),
            tp_mean: tp.map(|s| s.0),
            tp_var: tp.map(|s| s.1),
            fp_mean: fp.map(|s| s.0),
            fp_var: fp.map(|s| s.1),
            auroc: auroc(&self.conf),
            accuracy: self.acc.accuracy(),
            ap: self
                .classes
                .iter()
                .map(|c| average_precision(&pr_points(c, self.levels)))
                .collect(),
            ood: None,
            rows: n,
            labelled: self.acc.labelled(),
            tp: self.tp.n as usize,
            fp: self.fp.n as usize,
            reliability,
        })
    }

    /// The state as bytes: `MLMAPEVS`, a format version, the postcard body and a
    /// CRC-32 ([`from_bytes`](Self::from_bytes) reads them back).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::from(&MAGIC[..]);
        out.extend_from_slice(&WIRE_VERSION.to_le_bytes());
        // Serializing numbers and vectors into a Vec cannot fail.
        out.extend(postcard::to_allocvec(&self.to_wire()).unwrap_or_default());
        let crc = CRC.checksum(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// The metrics state of [`to_bytes`](Self::to_bytes); `None` for bytes that are
    /// not such a state of this format version, truncated, corrupt or inconsistent.
    pub fn from_bytes(bytes: &[u8]) -> Option<Self> {
        let split = bytes.len().checked_sub(4).filter(|&n| n >= 10)?;
        let (body, crc) = bytes.split_at(split);
        let want = u32::from_le_bytes(crc.try_into().ok()?);
        if body.get(..8)? != &MAGIC[..]
            || body.get(8..10)? != &WIRE_VERSION.to_le_bytes()[..]
            || CRC.checksum(body) != want
        {
            return None;
        }
        let w: StreamWire = postcard::from_bytes(body.get(10..)?).ok()?;
        Self::from_wire(&w)
    }

    fn to_wire(&self) -> StreamWire {
        // Only the levels that hold rows.
        let flat = |c: &Counts| {
            (0u32..)
                .zip(c)
                .filter(|(_, v)| v[0] + v[1] > 0)
                .map(|(l, &v)| (l, v))
                .collect()
        };
        StreamWire {
            k: self.k as u64,
            bins: self.cfg.bins as u64,
            binning: super::Binning::ALL
                .iter()
                .position(|&b| b == self.cfg.binning)
                .unwrap_or(0) as u8,
            levels: self.levels,
            acc: self.acc.to_wire(),
            tp: self.tp,
            fp: self.fp,
            conf: flat(&self.conf),
            classes: self.classes.iter().map(flat).collect(),
        }
    }

    fn from_wire(w: &StreamWire) -> Option<Self> {
        let cfg = MetricsConfig {
            bins: usize::try_from(w.bins).ok()?,
            binning: *super::Binning::ALL.get(usize::from(w.binning))?,
        };
        let k = usize::try_from(w.k).ok()?;
        let mut s = Self::new(k, &cfg, w.levels).ok()?;
        if w.classes.len() != k {
            return None;
        }
        s.acc = Accumulator::from_wire(&cfg, &w.acc)?;
        s.tp = w.tp;
        s.fp = w.fp;
        let read = |v: &[(u32, [u64; 2])]| -> Option<Counts> {
            let mut c: Counts = vec![[0, 0]; w.levels as usize + 1];
            let mut total = 0u64;
            // Levels strictly increasing, each inside.
            let mut next = 0u32;
            for &(level, pair) in v {
                if level < next {
                    return None;
                }
                *c.get_mut(level as usize)? = pair;
                total = total.checked_add(pair[0])?.checked_add(pair[1])?;
                next = level.checked_add(1)?;
            }
            (total == w.tp.n.checked_add(w.fp.n)?).then_some(c)
        };
        s.conf = read(&w.conf)?;
        s.classes = w.classes.iter().map(|c| read(c)).collect::<Option<_>>()?;
        let rows = s.acc.rows() as u64;
        (rows == w.tp.n + w.fp.n && s.acc.labelled() as u64 >= w.tp.n).then_some(s)
    }
}

/// AUROC of the level counts, positives against negatives, ties 1/2: the
/// Mann-Whitney statistic in integers until the final division.
fn auroc(counts: &Counts) -> Option<f64> {
    let p: u128 = counts.iter().map(|c| u128::from(c[0])).sum();
    let n: u128 = counts.iter().map(|c| u128::from(c[1])).sum();
    if p == 0 || n == 0 {
        return None;
    }
    let (mut twice_u, mut below) = (0u128, 0u128);
    for c in counts {
        let (pg, ng) = (u128::from(c[0]), u128::from(c[1]));
        twice_u += pg * (2 * below + ng);
        below += ng;
    }
    Some(twice_u as f64 / (2 * p * n) as f64)
}

/// The precision-recall curve of level counts: a point per level, highest first;
/// empty without positives.
fn pr_points(counts: &Counts, levels: u32) -> Vec<PrPoint> {
    let total: u64 = counts.iter().map(|c| c[0]).sum();
    if total == 0 {
        return Vec::new();
    }
    let (mut tp, mut fp) = (0u64, 0u64);
    counts
        .iter()
        .enumerate()
        .rev()
        .filter(|(_, c)| c[0] + c[1] > 0)
        .map(|(level, c)| {
            tp += c[0];
            fp += c[1];
            PrPoint {
                threshold: level as f64 / f64::from(levels),
                precision: tp as f64 / (tp + fp) as f64,
                recall: tp as f64 / total as f64,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows with repeated scores (so levels and exact values rank alike): 3 classes.
    fn rows() -> Vec<([f64; 3], Option<usize>)> {
        let values = [0.0, 0.125, 0.25, 0.5, 0.75, 1.0];
        (0..200usize)
            .map(|i| {
                let s = [
                    values[i % 6] / 2.0,
                    values[(i / 6) % 6] / 4.0,
                    values[(i * 7) % 6] / 4.0,
                ];
                let label = match i % 5 {
                    4 => None,
                    c => Some(c % 3),
                };
                (s, label)
            })
            .collect()
    }

    #[test]
    fn shards_merged_equal_evaluate() {
        let cfg = MetricsConfig::default();
        let rows = rows();
        let scores: Vec<f64> = rows.iter().flat_map(|r| r.0).collect();
        let labels: Vec<Option<usize>> = rows.iter().map(|r| r.1).collect();
        let want = super::super::evaluate(&scores, 3, &labels, &cfg).unwrap();
        let mut total = StreamMetrics::new(3, &cfg, 1 << 10).unwrap();
        for shard in rows.chunks(37) {
            let mut s = StreamMetrics::new(3, &cfg, 1 << 10).unwrap();
            for (x, l) in shard {
                s.add(x, &[], *l);
            }
            let s = StreamMetrics::from_bytes(&s.to_bytes()).unwrap();
            total.merge(&s).unwrap();
        }
        let got = total.report().unwrap();
        // Scores are multiples of 1/32, on the levels: ranks are exact.
        assert_eq!(got.auroc, want.auroc);
        for (g, w) in got.ap.iter().zip(&want.ap) {
            assert!((g.unwrap() - w.unwrap()).abs() < 1e-12, "{g:?} {w:?}");
        }
        assert_eq!(
            (got.rows, got.labelled, got.tp, got.fp),
            (200, 160, want.tp, want.fp)
        );
        for (g, w) in [
            (got.ece, want.ece),
            (got.mce, want.mce),
            (got.brier, want.brier),
            (got.nll.unwrap(), want.nll.unwrap()),
            (got.tp_var.unwrap(), want.tp_var.unwrap()),
            (got.fp_mean.unwrap(), want.fp_mean.unwrap()),
        ] {
            assert!((g - w).abs() < 1e-12, "{g} {w}");
        }
    }

    #[test]
    fn bad_bytes_and_mismatched_merges_are_refused() {
        let cfg = MetricsConfig::default();
        let mut s = StreamMetrics::new(3, &cfg, 64).unwrap();
        s.add(&[0.5, 0.25, 0.25], &[], Some(0));
        let bytes = s.to_bytes();
        for cut in [0, 5, 10, bytes.len() - 1] {
            assert!(StreamMetrics::from_bytes(&bytes[..cut]).is_none());
        }
        let mut flipped = bytes.clone();
        flipped[12] ^= 1;
        assert!(StreamMetrics::from_bytes(&flipped).is_none());
        let other = StreamMetrics::new(3, &cfg, 128).unwrap();
        assert_eq!(s.merge(&other), Err(MetricsError::Shape));
        assert!(StreamMetrics::new(0, &cfg, 64).is_err());
        assert!(StreamMetrics::new(3, &cfg, 0).is_err());
        assert_eq!(
            StreamMetrics::new(3, &cfg, 8).unwrap().report(),
            Err(MetricsError::Empty)
        );
    }
}
