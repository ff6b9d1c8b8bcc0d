//! The drift monitor (docs/DESIGN.md §7): a fixed-memory check, run on the device next
//! to the layer, that the detections it scores still look like the training data.
//!
//! Over each window of `W` detections (tumbling: a window starts where the previous one
//! ended) it counts, per logit `j`, the detections in each bin of the Bayes head's axis
//! `j`, plus one count below the first edge and one above the last. At the end of the
//! window it reports, per logit, the population stability index of those counts
//! against the training distribution of logit `j`, and
//!
//! * `psi_max`: the largest of them;
//! * `oos_rate`: the share of the window's detections with at least one logit out of
//!   support (in a bin, or below or above the axis, where no training row fell);
//! * `q_mean`: the mean known-probability `q` of the open head (DESIGN §1.8), when the
//!   table has that head;
//!
//! and one alarm per metric against the thresholds stored in the table file's monitor
//! section (`psi_max` and `oos_rate` above theirs, `q_mean` below its).
//!
//! The training distribution of logit `j` (bin `b`) is `e[j][b] = sum_c pi[c] h[c][j][b]`,
//! derived by the host from the table's log-terms and training rows and stored in the
//! section ([`MonitorSpec`]); the section names its table by the table's CRC.
//!
//! Memory: the counts are `K (B + 2)` words, plus a reference to the spec and four words
//! of running sums ([`Monitor`]: `K (B + 2) + 5` words on a 32-bit target). The slice
//! functions ([`MonitorSpec::push`], [`MonitorState`]) run the same code on storage the
//! caller owns (the C API).

use crate::diagnostics::error::InferError;
use crate::heads::bayes::BayesView;
use crate::heads::layer::{self, Scores};
use crate::heads::open::{self, OpenParams};
use crate::math::Backend;
use crate::sections::{self, Missing, Reader, Writer, TRAILER_LEN};
use crate::storage::view::{OpenBackend, TableView};

mod spec;
pub use spec::{write_monitor_section, MonitorSpec};

/// The four bytes a monitor section starts with.
pub const MONITOR_MAGIC: [u8; 4] = sections::MONITOR;

/// The monitor section's format version this build reads and writes.
pub const MONITOR_VERSION: u8 = 1;

/// Bytes of the section's fixed header.
const HEADER_LEN: usize = 36;

/// Largest distance of a logit's reference shares' sum from 1 that a section may hold
/// (the host writes shares that sum to 1 in `f64`, each rounded once to `f32`).
pub const REFERENCE_SUM_TOLERANCE: f32 = 1e-4;

/// Bytes of a monitor section for `k` logits of `bins` bins each.
pub const fn monitor_section_len(k: usize, bins: usize) -> usize {
    HEADER_LEN + 4 * k * bins + TRAILER_LEN
}

/// Why a monitor section was refused, or a monitor could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MonitorError {
    /// The bytes hold no monitor section (magic `MLMW`).
    Absent,
    /// The section's CRC does not match its contents.
    Corrupted,
    /// A section version this build does not read.
    UnsupportedVersion {
        /// The version found.
        found: u8,
    },
    /// The section's bytes do not follow the layout (a reserved field that is not 0, a
    /// length that is not the one its shape implies).
    Malformed,
    /// The table has no Bayes head: the monitor bins on its axes (DESIGN §7).
    NoBayesHead,
    /// The section is for another shape `(K, B)` than the table or the monitor type.
    ShapeMismatch {
        /// The shape expected.
        expected: (u16, u16),
        /// The shape found.
        found: (u16, u16),
    },
    /// The section follows another table than the one it was written for (its stored
    /// table CRC differs).
    TableMismatch,
    /// The window is 0.
    Window,
    /// `alpha` is not in `[0, 1)`.
    Alpha,
    /// A threshold is NaN or out of its range.
    Threshold,
    /// A logit's reference shares are not in `[0, 1]` or do not sum to 1.
    Reference {
        /// The logit.
        logit: u16,
    },
    /// The output buffer is too small (encoding).
    BufferTooSmall,
}

impl MonitorError {
    /// The variant's message: what `Display` says (with the variant's values where it
    /// has any) and what `defmt` prints.
    pub const fn message(self) -> &'static str {
        match self {
            Self::Absent => "input holds no monitor section (magic `MLMW`)",
            Self::Corrupted => "monitor section checksum does not match its contents",
            Self::UnsupportedVersion { .. } => "monitor section version is not supported",
            Self::Malformed => "monitor section is malformed",
            Self::NoBayesHead => {
                "the table has no Bayes head, which the monitor bins on (DESIGN §7)"
            }
            Self::ShapeMismatch { .. } => {
                "monitor section shape differs from the table's or the monitor's"
            }
            Self::TableMismatch => {
                "monitor section was written for another table (table CRC differs)"
            }
            Self::Window => "monitor window must be at least 1 detection",
            Self::Alpha => "monitor alpha must be in [0, 1)",
            Self::Threshold => "a monitor threshold is NaN or out of range",
            Self::Reference { .. } => {
                "reference shares of a logit are not in [0, 1] or do not sum to 1"
            }
            Self::BufferTooSmall => "buffer too small for the monitor section",
        }
    }
}

impl core::fmt::Display for MonitorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Absent
            | Self::Corrupted
            | Self::Malformed
            | Self::NoBayesHead
            | Self::TableMismatch
            | Self::Window
            | Self::Alpha
            | Self::Threshold
            | Self::BufferTooSmall => f.write_str(self.message()),
            Self::UnsupportedVersion { found } => write!(
                f,
                "monitor section version {found} is not supported (this build reads {MONITOR_VERSION})"
            ),
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "monitor section is for {} logits of {} bins, expected {} of {}",
                found.0, found.1, expected.0, expected.1
            ),
            Self::Reference { logit } => write!(
                f,
                "reference shares of logit {logit} are not in [0, 1] or do not sum to 1"
            ),
        }
    }
}

impl core::error::Error for MonitorError {}

/// The alarm thresholds of the three window metrics (DESIGN §7): an alarm is raised
/// when `psi_max > psi`, `oos_rate > oos` or `q_mean < q`. [`Thresholds::NONE`] never
/// alarms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Threshold of `psi_max` (`>= 0`, `+inf` for none).
    pub psi: f32,
    /// Threshold of `oos_rate` (`>= 0`, `+inf` for none).
    pub oos: f32,
    /// Threshold of `q_mean` (`<= 1`, `-inf` for none).
    pub q: f32,
}

impl Thresholds {
    /// Thresholds that never alarm.
    pub const NONE: Self = Self {
        psi: f32::INFINITY,
        oos: f32::INFINITY,
        q: f32::NEG_INFINITY,
    };

    fn valid(&self) -> bool {
        self.psi >= 0.0 && self.oos >= 0.0 && self.q <= 1.0
    }
}

/// What a monitor section stores besides the reference: the window `W`, the false-alarm
/// rate `alpha` the thresholds were fitted for (0 when they were not fitted), and the
/// thresholds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MonitorParams {
    /// Detections per window.
    pub window: u32,
    /// The false-alarm rate the thresholds were chosen for, in `[0, 1)`.
    pub alpha: f32,
    /// The thresholds.
    pub thresholds: Thresholds,
}

/// The alarms of one window.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Alarms {
    /// `psi_max` passed its threshold.
    pub psi: bool,
    /// `oos_rate` passed its threshold.
    pub oos: bool,
    /// `q_mean` passed (fell below) its threshold.
    pub q: bool,
}

impl Alarms {
    /// Whether any metric passed its threshold.
    #[inline]
    pub fn any(&self) -> bool {
        self.psi || self.oos || self.q
    }
}

/// The metrics of one window (the per-logit PSI are written to a slice, or held by
/// [`WindowReport`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowSummary {
    /// Index of the window, from 0.
    pub window: u32,
    /// Detections in the window: `W`, or fewer for the last, partial window.
    pub rows: u32,
    /// The largest per-logit PSI.
    pub psi_max: f32,
    /// The logit of the largest PSI (the lowest on ties).
    pub psi_logit: u16,
    /// Share of the window's detections with a logit out of support.
    pub oos_rate: f32,
    /// Mean known-probability `q` of the open head; `None` without that head.
    pub q_mean: Option<f32>,
    /// The alarms; none for a partial window (the thresholds hold for `W` detections).
    pub alarms: Alarms,
}

/// The running sums of the current window.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[repr(C)]
pub struct Accumulators {
    /// Detections pushed into the current window.
    pub rows: u32,
    /// Of those, the ones with a logit out of support.
    pub outside: u32,
    /// Sum of their `q` (0 without the open head).
    pub q_sum: f32,
    /// Index of the current window.
    pub window: u32,
}

/// A monitor's counts and sums, in storage the caller owns: `tails` holds 2 counts per
/// logit (below, above), `bins` `B` per logit, logit after logit.
#[derive(Debug)]
pub struct MonitorState<'m> {
    tails: &'m mut [u32],
    bins: &'m mut [u32],
    acc: &'m mut Accumulators,
}

impl<'m> MonitorState<'m> {
    /// A state over the caller's storage, cleared (`tails`: 2 K counts, `bins`: K B).
    /// The lengths are checked against the spec by every call that uses it.
    pub fn new(tails: &'m mut [u32], bins: &'m mut [u32], acc: &'m mut Accumulators) -> Self {
        tails.fill(0);
        bins.fill(0);
        *acc = Accumulators::default();
        Self { tails, bins, acc }
    }

    /// A state over storage that holds a window in progress (as the calls left it):
    /// nothing is cleared. Whatever the storage holds, no call panics; counts that no
    /// call wrote give meaningless metrics.
    pub fn resume(tails: &'m mut [u32], bins: &'m mut [u32], acc: &'m mut Accumulators) -> Self {
        Self { tails, bins, acc }
    }

    /// The running sums of the current window.
    #[inline]
    pub fn accumulators(&self) -> &Accumulators {
        self.acc
    }

    /// The current window's counts of logit `j` in `bins` bins: (below, per bin, above).
    pub fn counts(&self, j: usize, bins: usize) -> Option<(u32, &[u32], u32)> {
        let t = self.tails.get(2 * j..2 * j + 2)?;
        let b = self.bins.get(j * bins..(j + 1) * bins)?;
        Some((*t.first()?, b, *t.get(1)?))
    }
}

/// The metrics of one window with its per-logit PSI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowReport<const K: usize> {
    /// The window's metrics and alarms.
    pub summary: WindowSummary,
    /// The PSI of each logit.
    pub psi: [f32; K],
}

/// A drift monitor of fixed size: `K` logits, `B` bins per logit (the Bayes head's),
/// `C` Bayes categories (K, or K + 1 with `background`), as the table's
/// [`Table`](crate::Table) type. It owns its counts and borrows its spec.
///
/// # Examples
///
/// ```
/// # use mlmap_core as mlmap;
/// use mlmap::{Monitor, MonitorSpec, Table};
///
/// // A table file with a monitor section (written by `mlmap monitor fit`).
/// let bytes = include_bytes!("../../../../tests/golden/monitor_small.mlmap");
/// let table: Table<3, 22, 17, 22, 4> = Table::from_bytes(bytes)?;
/// let spec = MonitorSpec::from_bytes(bytes, &table.view())?;
/// let mut monitor: Monitor<'_, 3, 22, 4> = Monitor::new(&spec)?;
/// let window = spec.params().window;
/// let mut reports = 0;
/// for i in 0..2 * window {
///     let x = (i % 7) as f32 * 0.5;
///     if let Some(report) = monitor.push(&[x, -x, 0.0], 1.0)? {
///         assert_eq!(report.summary.rows, window);
///         reports += 1;
///     }
/// }
/// assert_eq!(reports, 2);
/// # Ok::<(), Box<dyn core::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct Monitor<'s, const K: usize, const B: usize, const C: usize> {
    spec: &'s MonitorSpec<'s>,
    acc: Accumulators,
    tails: [[u32; 2]; K],
    bins: [[u32; B]; K],
}

impl<'s, const K: usize, const B: usize, const C: usize> Monitor<'s, K, B, C> {
    /// A monitor for `spec`, its first window empty.
    ///
    /// # Errors
    ///
    /// [`MonitorError::ShapeMismatch`] when the spec is not for `K` logits of `B` bins
    /// with `C` categories.
    pub fn new(spec: &'s MonitorSpec<'s>) -> Result<Self, MonitorError> {
        if spec.k() != K || spec.bins() != B || spec.categories() != C {
            return Err(MonitorError::ShapeMismatch {
                expected: (
                    u16::try_from(K).unwrap_or(u16::MAX),
                    u16::try_from(B).unwrap_or(u16::MAX),
                ),
                found: (
                    u16::try_from(spec.k()).unwrap_or(u16::MAX),
                    u16::try_from(spec.bins()).unwrap_or(u16::MAX),
                ),
            });
        }
        Ok(Self {
            spec,
            acc: Accumulators::default(),
            tails: [[0; 2]; K],
            bins: [[0; B]; K],
        })
    }

    fn state(&mut self) -> MonitorState<'_> {
        MonitorState {
            tails: self.tails.as_flattened_mut(),
            bins: self.bins.as_flattened_mut(),
            acc: &mut self.acc,
        }
    }

    /// Pushes one detection; returns the window's report when it completes it.
    ///
    /// # Errors
    ///
    /// [`InferError::NanLogit`] and [`InferError::Objectness`]; nothing is counted then.
    ///
    /// # Panics
    ///
    /// Never.
    #[inline]
    pub fn push(
        &mut self,
        logits: &[f32; K],
        objectness: f32,
    ) -> Result<Option<WindowReport<K>>, InferError> {
        let spec = self.spec;
        let mut scratch = [0.0f32; C];
        let mut psi = [0.0f32; K];
        let summary = spec.push(
            &mut self.state(),
            logits,
            objectness,
            &mut scratch,
            &mut psi,
        )?;
        Ok(summary.map(|summary| WindowReport { summary, psi }))
    }

    /// Scores one detection with the open head (its default backend, as
    /// [`Table::open`](crate::Table::open)) and pushes it: one pass for both.
    ///
    /// # Errors
    ///
    /// As [`Monitor::push`], and [`InferError::NoOpenHead`] without that head.
    #[inline]
    pub fn push_open(
        &mut self,
        logits: &[f32; K],
        objectness: f32,
    ) -> Result<(Scores<K>, Option<WindowReport<K>>), InferError> {
        let spec = self.spec;
        let mut scratch = [0.0f32; C];
        let mut psi = [0.0f32; K];
        let mut out = [0.0f32; K];
        let summary = spec.push_open::<OpenBackend>(
            &mut self.state(),
            logits,
            objectness,
            &mut out,
            &mut scratch,
            &mut psi,
        )?;
        Ok((
            Scores(out),
            summary.map(|summary| WindowReport { summary, psi }),
        ))
    }

    /// Ends the current window early (the end of a log): its report, `None` when it is
    /// empty. A partial window raises no alarm.
    pub fn flush(&mut self) -> Option<WindowReport<K>> {
        let spec = self.spec;
        let mut psi = [0.0f32; K];
        let summary = spec.finish(&mut self.state(), &mut psi)?;
        Some(WindowReport { summary, psi })
    }

    /// The running sums of the current window.
    #[inline]
    pub fn accumulators(&self) -> &Accumulators {
        &self.acc
    }

    /// The current window's counts of logit `j`: (below, per bin, above).
    pub fn counts(&self, j: usize) -> Option<(u32, &[u32; B], u32)> {
        let [below, above] = *self.tails.get(j)?;
        Some((below, self.bins.get(j)?, above))
    }
}
