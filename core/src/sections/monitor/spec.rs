//! The monitor section read and written in place ([`MonitorSpec`],
//! [`write_monitor_section`]): the per-detection counting and the window's metrics over
//! storage the caller owns.

use super::*;

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
