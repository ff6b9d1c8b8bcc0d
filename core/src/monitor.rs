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

use crate::bayes::BayesView;
use crate::error::InferError;
use crate::layer::{self, Scores};
use crate::math::Backend;
use crate::open::{self, OpenParams};
use crate::sections::{self, Missing, Reader, Writer, TRAILER_LEN};
use crate::view::{OpenBackend, TableView};

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

impl core::fmt::Display for MonitorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::Absent => f.write_str("input holds no monitor section (magic `MLMW`)"),
            Self::Corrupted => f.write_str("monitor section checksum does not match its contents"),
            Self::UnsupportedVersion { found } => write!(
                f,
                "monitor section version {found} is not supported (this build reads {MONITOR_VERSION})"
            ),
            Self::Malformed => f.write_str("monitor section is malformed"),
            Self::NoBayesHead => {
                f.write_str("the table has no Bayes head, which the monitor bins on (DESIGN §7)")
            }
            Self::ShapeMismatch { expected, found } => write!(
                f,
                "monitor section is for {} logits of {} bins, expected {} of {}",
                found.0, found.1, expected.0, expected.1
            ),
            Self::TableMismatch => {
                f.write_str("monitor section was written for another table (table CRC differs)")
            }
            Self::Window => f.write_str("monitor window must be at least 1 detection"),
            Self::Alpha => f.write_str("monitor alpha must be in [0, 1)"),
            Self::Threshold => f.write_str("a monitor threshold is NaN or out of range"),
            Self::Reference { logit } => write!(
                f,
                "reference shares of logit {logit} are not in [0, 1] or do not sum to 1"
            ),
            Self::BufferTooSmall => f.write_str("buffer too small for the monitor section"),
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

/// A validated monitor section, with the table's Bayes head it bins on.
#[derive(Debug, Clone, Copy)]
pub struct MonitorSpec<'a> {
    bayes: BayesView<'a>,
    /// The open head's recalibration map (DESIGN §1.9), applied by `push_open` as the
    /// table's `open` does.
    open_map: Option<crate::RecalMap<'a>>,
    /// `e[j][b]` as little-endian `f32`, logit-major.
    reference: &'a [u8],
    params: MonitorParams,
}

impl<'a> MonitorSpec<'a> {
    /// Reads the monitor section of `bytes` (the section alone, or a table file with it
    /// among its appended sections) for `table`: checks the magic, the CRC, the version,
    /// the shape against the table's Bayes head, that the section names the table before
    /// it (when there is one) by its CRC, the window, alpha, the thresholds and every
    /// reference share.
    ///
    /// # Errors
    ///
    /// A [`MonitorError`] naming the first failed check.
    ///
    /// # Panics
    ///
    /// Never, whatever the bytes.
    pub fn from_bytes<F: AsRef<[f32]>, G: AsRef<[f32]>>(
        bytes: &'a [u8],
        table: &TableView<'a, F, G>,
    ) -> Result<Self, MonitorError> {
        let (section, before) = sections::find(bytes, MONITOR_MAGIC).map_err(|m| match m {
            Missing::Absent => MonitorError::Absent,
            Missing::Corrupted => MonitorError::Corrupted,
        })?;
        let bayes = table.bayes().ok_or(MonitorError::NoBayesHead)?;
        let body = section
            .get(..section.len().saturating_sub(TRAILER_LEN))
            .unwrap_or_default();
        let mut r = Reader(body);
        let malformed = MonitorError::Malformed;
        let _magic = r.take(4).ok_or(malformed)?;
        let version = r.u8().ok_or(malformed)?;
        if version != MONITOR_VERSION {
            return Err(MonitorError::UnsupportedVersion { found: version });
        }
        let (flags, reserved) = (r.u8().ok_or(malformed)?, r.u16().ok_or(malformed)?);
        let (k, bins) = (r.u16().ok_or(malformed)?, r.u16().ok_or(malformed)?);
        let window = r.u32().ok_or(malformed)?;
        let table_crc = r.u32().ok_or(malformed)?;
        let alpha = r.f32().ok_or(malformed)?;
        let thresholds = Thresholds {
            psi: r.f32().ok_or(malformed)?,
            oos: r.f32().ok_or(malformed)?,
            q: r.f32().ok_or(malformed)?,
        };
        let has_q = table.open().is_some();
        if reserved != 0 || flags != u8::from(has_q) {
            return Err(malformed);
        }
        let expected = (
            u16::try_from(bayes.logits()).unwrap_or(u16::MAX),
            u16::try_from(bayes.bins()).unwrap_or(u16::MAX),
        );
        if (k, bins) != expected {
            return Err(MonitorError::ShapeMismatch {
                expected,
                found: (k, bins),
            });
        }
        if sections::table_crc(before).is_some_and(|crc| crc != table_crc) {
            return Err(MonitorError::TableMismatch);
        }
        if window == 0 {
            return Err(MonitorError::Window);
        }
        if !(0.0..1.0).contains(&alpha) {
            return Err(MonitorError::Alpha);
        }
        if !thresholds.valid() || (!has_q && thresholds.q != f32::NEG_INFINITY) {
            return Err(MonitorError::Threshold);
        }
        let (k, bins) = (usize::from(k), usize::from(bins));
        let reference = r.take(4 * k * bins).ok_or(malformed)?;
        if !r.is_empty() {
            return Err(malformed);
        }
        let spec = Self {
            bayes,
            open_map: table.recal_map(crate::Head::Open),
            reference,
            params: MonitorParams {
                window,
                alpha,
                thresholds,
            },
        };
        for j in 0..k {
            let logit = u16::try_from(j).unwrap_or(u16::MAX);
            let mut sum = 0.0f32;
            for b in 0..bins {
                let e = spec.share(j * bins + b);
                if !(0.0..=1.0).contains(&e) {
                    return Err(MonitorError::Reference { logit });
                }
                sum += e;
            }
            if !((sum - 1.0).abs() <= REFERENCE_SUM_TOLERANCE) {
                return Err(MonitorError::Reference { logit });
            }
        }
        Ok(spec)
    }

    /// Number of logits K.
    #[inline]
    pub fn k(&self) -> usize {
        self.bayes.logits()
    }

    /// Bins per logit B (the Bayes head's).
    #[inline]
    pub fn bins(&self) -> usize {
        self.bayes.bins()
    }

    /// Number of Bayes categories (K, or K + 1 with `background`): the scratch a push
    /// needs.
    #[inline]
    pub fn categories(&self) -> usize {
        self.bayes.categories()
    }

    /// Window, alpha and thresholds.
    #[inline]
    pub fn params(&self) -> MonitorParams {
        self.params
    }

    /// Whether the windows report `q_mean` (the table has the open head).
    #[inline]
    pub fn has_q(&self) -> bool {
        self.bayes.open().is_some()
    }

    /// The training share `e[j][b]` of logit `j`'s bin `b`.
    pub fn reference(&self, j: usize, b: usize) -> Option<f32> {
        (j < self.k() && b < self.bins()).then(|| self.share(j * self.bins() + b))
    }

    #[inline(always)]
    fn share(&self, i: usize) -> f32 {
        self.reference
            .get(4 * i..4 * i + 4)
            .and_then(|b| <[u8; 4]>::try_from(b).ok())
            .map_or(0.0, f32::from_le_bytes)
    }

    fn check_state(&self, st: &MonitorState<'_>) -> Result<(), InferError> {
        let (k, b) = (self.k(), self.bins());
        if st.tails.len() != 2 * k || st.bins.len() != k * b {
            return Err(InferError::Length);
        }
        Ok(())
    }

    /// Adds one detection's bins to the window; `q` is its known-probability (when the
    /// spec has the open head). Inputs are checked.
    #[inline(always)]
    fn count(&self, st: &mut MonitorState<'_>, logits: &[f32], q: f32) {
        let b = self.bins();
        let mut outside = false;
        for (j, (axis, &x)) in self.bayes.axes().iter().zip(logits).enumerate() {
            match axis.bin(x) {
                Some(bin) => {
                    let i = j * b + bin;
                    if let Some(n) = st.bins.get_mut(i) {
                        *n = n.wrapping_add(1);
                    }
                    outside |= self.share(i) == 0.0;
                }
                None => {
                    let tail = 2 * j + usize::from(!(x < axis.lo()));
                    if let Some(n) = st.tails.get_mut(tail) {
                        *n = n.wrapping_add(1);
                    }
                    outside = true;
                }
            }
        }
        st.acc.rows = st.acc.rows.wrapping_add(1);
        st.acc.outside = st.acc.outside.wrapping_add(u32::from(outside));
        st.acc.q_sum += q;
    }

    /// Pushes one detection into the window of `st`; `scratch` holds one float per
    /// Bayes category ([`MonitorSpec::categories`]). When the window is full, its
    /// metrics are returned, its per-logit PSI written to `psi` (K entries, or empty to
    /// skip them), and the state starts the next window.
    ///
    /// # Errors
    ///
    /// [`InferError::NanLogit`], [`InferError::Objectness`] and [`InferError::Length`]
    /// (a slice or the state of another shape); nothing is counted then.
    #[inline]
    pub fn push(
        &self,
        st: &mut MonitorState<'_>,
        logits: &[f32],
        objectness: f32,
        scratch: &mut [f32],
        psi: &mut [f32],
    ) -> Result<Option<WindowSummary>, InferError> {
        self.check_state(st)?;
        layer::check(logits, objectness, self.k(), self.k())?;
        if !(psi.is_empty() || psi.len() == self.k()) {
            return Err(InferError::Length);
        }
        let q = match self.bayes.open() {
            Some(open) => {
                let l = scratch
                    .get_mut(..self.categories())
                    .ok_or(InferError::Length)?;
                self.bayes.log_scores_into(logits, objectness, l)?;
                open::known_share::<OpenBackend>(l, self.k(), open.log_unknown())
            }
            None => 0.0,
        };
        self.count(st, logits, q);
        Ok(self.end_if_full(st, psi))
    }

    /// Scores one detection with the open head (backend `M`) into `out` and pushes it,
    /// its log-scores computed once for both: the scores are bit for bit
    /// [`TableView::open_into`]'s with the same backend, and the window's `q` is the one
    /// that scored it.
    ///
    /// # Errors
    ///
    /// As [`MonitorSpec::push`], and [`InferError::NoOpenHead`] without that head.
    #[inline]
    pub fn push_open<M: Backend>(
        &self,
        st: &mut MonitorState<'_>,
        logits: &[f32],
        objectness: f32,
        out: &mut [f32],
        scratch: &mut [f32],
        psi: &mut [f32],
    ) -> Result<Option<WindowSummary>, InferError> {
        let open: OpenParams = self.bayes.open().ok_or(InferError::NoOpenHead)?;
        self.check_state(st)?;
        layer::check(logits, objectness, self.k(), out.len())?;
        if !(psi.is_empty() || psi.len() == self.k()) {
            return Err(InferError::Length);
        }
        let l = scratch
            .get_mut(..self.categories())
            .ok_or(InferError::Length)?;
        self.bayes.log_scores_into(logits, objectness, l)?;
        let q = open::score_from_log_scores::<M>(l, &open, logits, objectness, out);
        if let Some(g) = &self.open_map {
            g.apply(out);
        }
        self.count(st, logits, q);
        Ok(self.end_if_full(st, psi))
    }

    fn end_if_full(&self, st: &mut MonitorState<'_>, psi: &mut [f32]) -> Option<WindowSummary> {
        if st.acc.rows >= self.params.window {
            self.finish(st, psi)
        } else {
            None
        }
    }

    /// Ends the current window, however many detections it holds: its metrics (`None`
    /// for an empty window), its per-logit PSI into `psi` (K entries, or empty), and the
    /// state cleared for the next window. A window of fewer than `W` detections raises
    /// no alarm.
    pub fn finish(&self, st: &mut MonitorState<'_>, psi: &mut [f32]) -> Option<WindowSummary> {
        let n = st.acc.rows;
        if n == 0 || self.check_state(st).is_err() {
            return None;
        }
        let b = self.bins();
        let inv_n = 1.0 / n as f32;
        // The floor of an empty share: half a detection.
        let floor = 0.5 * inv_n;
        let mut psi_max = 0.0f32;
        let mut psi_logit = 0u16;
        let mut psi_out = psi.iter_mut();
        for (j, (tails, bins)) in st
            .tails
            .chunks_exact(2)
            .zip(st.bins.chunks_exact(b.max(1)))
            .enumerate()
        {
            // Below and above: no training row lies outside the axis (share 0).
            let mut sum = 0.0f32;
            for &count in tails {
                sum += term(count, 0.0, inv_n, floor);
            }
            let shares = self
                .reference
                .get(4 * j * b..4 * (j + 1) * b)
                .unwrap_or_default();
            for (&count, e) in bins.iter().zip(shares.chunks_exact(4)) {
                let e = <[u8; 4]>::try_from(e).map_or(0.0, f32::from_le_bytes);
                sum += term(count, e, inv_n, floor);
            }
            if sum > psi_max {
                psi_max = sum;
                psi_logit = u16::try_from(j).unwrap_or(u16::MAX);
            }
            if let Some(p) = psi_out.next() {
                *p = sum;
            }
        }
        let oos_rate = st.acc.outside as f32 * inv_n;
        let q_mean = self.has_q().then_some(st.acc.q_sum * inv_n);
        let t = self.params.thresholds;
        let alarms = if n >= self.params.window {
            Alarms {
                psi: psi_max > t.psi,
                oos: oos_rate > t.oos,
                q: q_mean.is_some_and(|q| q < t.q),
            }
        } else {
            Alarms::default()
        };
        let summary = WindowSummary {
            window: st.acc.window,
            rows: n,
            psi_max,
            psi_logit,
            oos_rate,
            q_mean,
            alarms,
        };
        st.tails.fill(0);
        st.bins.fill(0);
        *st.acc = Accumulators {
            window: st.acc.window.wrapping_add(1),
            ..Accumulators::default()
        };
        Some(summary)
    }
}

/// One bin's PSI term `(o - e') ln(o / e')`, with `o = max(count, 1/2) / n` and
/// `e' = max(e, floor)`, `floor = 1 / (2n)`; 0 when both are at the floor.
#[inline(always)]
fn term(count: u32, e: f32, inv_n: f32, floor: f32) -> f32 {
    let e = if e > floor { e } else { floor };
    let o = if count == 0 {
        if e == floor {
            return 0.0;
        }
        floor
    } else {
        count as f32 * inv_n
    };
    (o - e) * (ln(o) - ln(e))
}

/// Natural logarithm of a positive normal `f32` (a relative error below `2e-7` for the
/// shares the monitor takes it of): `x = 2^k m` with `m` in `[sqrt(1/2), sqrt(2))`,
/// `ln m = 2 atanh(s)`, `s = (m - 1) / (m + 1)`, by its series to `s^9`.
#[inline(always)]
fn ln(x: f32) -> f32 {
    let bits = x.to_bits();
    // Subtract the exponent of sqrt(1/2) so that the mantissa lands in [sqrt(1/2), sqrt(2)).
    let shifted = bits.wrapping_sub(0x3f35_04f3);
    let k = (shifted as i32) >> 23;
    let m = f32::from_bits((shifted & 0x007f_ffff).wrapping_add(0x3f35_04f3));
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    let series = s2 * (1.0 / 3.0 + s2 * (1.0 / 5.0 + s2 * (1.0 / 7.0 + s2 * (1.0 / 9.0))));
    let ln_m = 2.0 * s + 2.0 * s * series;
    k as f32 * core::f32::consts::LN_2 + ln_m
}

/// Writes a monitor section into `out` (exactly [`monitor_section_len`] bytes) for a
/// table whose CRC is `table_crc` and whose Bayes head has `k` logits of `bins` bins:
/// `reference` holds `e[j][b]`, logit-major; `has_q` says whether the table has the open
/// head. The section is read back by [`MonitorSpec::from_bytes`], which checks it.
///
/// # Errors
///
/// [`MonitorError::BufferTooSmall`] for a buffer of another length, and
/// [`MonitorError::Malformed`] for a reference of another length or a shape beyond
/// `u16`.
pub fn write_monitor_section(
    out: &mut [u8],
    table_crc: u32,
    k: usize,
    bins: usize,
    has_q: bool,
    params: &MonitorParams,
    reference: &[f32],
) -> Result<(), MonitorError> {
    if out.len() != monitor_section_len(k, bins) {
        return Err(MonitorError::BufferTooSmall);
    }
    let (Ok(k16), Ok(b16)) = (u16::try_from(k), u16::try_from(bins)) else {
        return Err(MonitorError::Malformed);
    };
    if reference.len() != k * bins {
        return Err(MonitorError::Malformed);
    }
    let mut w = Writer { buf: out, at: 0 };
    let t = params.thresholds;
    (|| {
        w.put(&MONITOR_MAGIC)?;
        w.u8(MONITOR_VERSION)?;
        w.u8(u8::from(has_q))?;
        w.u16(0)?;
        w.u16(k16)?;
        w.u16(b16)?;
        w.u32(params.window)?;
        w.u32(table_crc)?;
        w.f32(params.alpha)?;
        w.f32(t.psi)?;
        w.f32(t.oos)?;
        w.f32(t.q)?;
        for &e in reference {
            w.f32(e)?;
        }
        Some(())
    })()
    .ok_or(MonitorError::BufferTooSmall)?;
    sections::seal(out).ok_or(MonitorError::BufferTooSmall)
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
/// let bytes = include_bytes!("../../tests/golden/monitor_small.mlmap");
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ln_matches_libm() {
        let mut worst = 0.0f64;
        let mut x = 1.0e-10f32;
        while x < 4.0 {
            let exact = (x as f64).ln();
            let got = ln(x) as f64;
            let err = if exact.abs() > 1e-3 {
                ((got - exact) / exact).abs()
            } else {
                (got - exact).abs()
            };
            worst = worst.max(err);
            x *= 1.000_37;
        }
        assert!(worst < 2e-7, "worst error {worst}");
        assert_eq!(ln(1.0), 0.0);
    }

    #[test]
    fn term_is_zero_at_the_floor_and_positive_elsewhere() {
        let n = 200u32;
        let inv = 1.0 / n as f32;
        let floor = 0.5 * inv;
        assert_eq!(term(0, 0.0, inv, floor), 0.0);
        assert_eq!(term(0, floor * 0.5, inv, floor), 0.0);
        assert!(term(0, 0.1, inv, floor) > 0.0);
        assert!(term(20, 0.1, inv, floor).abs() < 1e-7);
        assert!(term(40, 0.1, inv, floor) > 0.0);
    }
}
