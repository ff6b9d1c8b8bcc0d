//! Confidence binning of `ece` and `mce` (DESIGN §1.5): the conventions, their edges,
//! and the reliability bins.

use core::fmt;
use core::str::FromStr;

use super::accumulate::Sum;
use super::MetricsError;
use crate::names::{Name, Named};

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

impl Named for Binning {
    const WHAT: &'static str = "binning";
    const NAMES: &'static [Name<Self>] = &[
        Name {
            value: Self::Design,
            name: "design",
            flag: "default",
            help: "`((m-1)/M, m/M]`, conf = 0 in the first bin (DESIGN §1.5)",
        },
        Name::new(Self::Netcal, "netcal", "`[lo, hi)` bins, as netcal"),
        Name::new(
            Self::Torchmetrics,
            "torchmetrics",
            "`[lo, hi)` bins with conf = 1 in an extra bin, as torchmetrics",
        ),
    ];
}

impl Binning {
    /// Every convention, default first.
    pub const ALL: [Self; 3] = [Self::Design, Self::Netcal, Self::Torchmetrics];

    /// The name used in reports: `design`, `netcal` or `torchmetrics` (the command
    /// line also accepts `default` for `design`).
    pub fn name(self) -> &'static str {
        Named::name(self)
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
        Self::from_name(s).map_err(|_| MetricsError::UnknownBinning)
    }
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

/// The bin edges of a convention, and the rule that maps a confidence to a bin.
#[derive(Debug, Clone)]
pub(super) enum Edges {
    /// `e_0 .. e_M`; bin = number of `e_1 .. e_M` below `conf`, at most `M - 1`.
    Design(Vec<f64>),
    /// `e_0 .. e_M`; bin = number of `e_i <= clip(conf)` minus 1, at most `M - 1`.
    Netcal(Vec<f64>),
    /// `e_0 .. e_M` in `f32`; bin = number of `e_i <= f32(conf)` minus 1, up to `M`.
    Torch(Vec<f32>),
}

impl Edges {
    pub(super) fn new(binning: Binning, m: usize) -> Self {
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

    /// Number of bins.
    pub(super) fn len(&self) -> usize {
        match self {
            Self::Design(e) | Self::Netcal(e) => e.len().saturating_sub(1),
            Self::Torch(e) => e.len(),
        }
    }

    /// The bin of a confidence in `[0, 1]`.
    pub(super) fn bin(&self, conf: f64) -> usize {
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

/// The running sums of one confidence bin.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct BinSum {
    pub(super) count: usize,
    pub(super) correct: usize,
    pub(super) conf: Sum,
}

/// Reliability bins, `ece` and `mce` from the sums of every bin over `n` rows.
pub(super) fn calibration(
    edges: &Edges,
    sums: &[BinSum],
    n: usize,
) -> (Vec<CalibrationBin>, f64, f64) {
    let n = n as f64;
    let (mut ece, mut mce) = (Sum::default(), 0.0f64);
    let bins = sums
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (lo, hi) = edges.range(i);
            let (mut accuracy, mut confidence) = (None, None);
            if s.count > 0 {
                let count = s.count as f64;
                let (a, c) = (s.correct as f64 / count, s.conf.value() / count);
                let gap = (a - c).abs();
                ece.add(count / n * gap);
                mce = mce.max(gap);
                (accuracy, confidence) = (Some(a), Some(c));
            }
            CalibrationBin {
                lo,
                hi,
                count: s.count,
                accuracy,
                confidence,
            }
        })
        .collect();
    (bins, ece.value(), mce)
}

#[cfg(test)]
mod tests {
    use super::*;

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
        for binning in Binning::ALL {
            for m in [1, 3, 10] {
                assert_eq!(Edges::new(binning, m).len(), binning.bin_count(m));
            }
        }
    }

    #[test]
    fn design_bins_of_other_counts() {
        // (conf, M, bin): edges are m / M in f64; 0 and below join the first bin, above
        // 1 the last.
        const VECTORS: &[(f64, usize, usize)] = &[
            (-0.5, 10, 0),
            (0.100_000_000_000_001, 10, 1),
            (0.6, 10, 5),
            (1.5, 10, 9),
            (0.5, 1, 0),
            (1.0 / 3.0, 3, 0),
            (2.0 / 3.0, 3, 1),
        ];
        for &(conf, m, want) in VECTORS {
            assert_eq!(Edges::new(Binning::Design, m).bin(conf), want, "{conf} {m}");
        }
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
    fn names_parse() {
        assert_eq!("netcal".parse(), Ok(Binning::Netcal));
        assert_eq!("default".parse(), Ok(Binning::Design));
        assert_eq!(format!("{}", Binning::Design), "design");
        assert_eq!(Binning::Design.flag(), "default");
        assert_eq!(
            "NetCal".parse::<Binning>(),
            Err(MetricsError::UnknownBinning)
        );
    }
}
