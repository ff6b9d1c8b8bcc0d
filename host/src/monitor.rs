//! The host side of the drift monitor (DESIGN §7): the training distribution of every
//! logit derived from a table, the monitor section written into a table file, a monitor
//! over vectors for replaying logs, and thresholds fitted from in-distribution rows.
//!
//! Every window metric comes from the layer's own [`MonitorSpec`], so what the host
//! fits and replays is what the device computes.

use mlmap_core::{
    monitor_section_len, section_of, table_of, write_monitor_section, Accumulators, DynTable,
    InferError, MonitorError, MonitorParams, MonitorSpec, MonitorState, Thresholds, WindowSummary,
    MONITOR_MAGIC, QUANTIZED_MAGIC,
};

/// The magic of the conformal section (DESIGN §8), kept when a monitor is written.
const CONFORMAL_MAGIC: [u8; 4] = *b"MLMS";

/// The training share `e[j][b]` of every logit's bins (logit-major), from the table's
/// Bayes head (DESIGN §7): per category `c`, the count of training rows in the bin is
/// recovered from the stored log-term `t` as `round(n_c (e^t - lambda))` (in `f64`),
/// and `e[j][b]` is the sum of those counts over the categories divided by all
/// training rows, `sum_c pi[c] h[c][j][b]`. `None` without a Bayes head.
pub fn reference(table: &DynTable) -> Option<Vec<f64>> {
    let bayes = table.bayes_head()?;
    let (k, bins, cats) = (bayes.logits(), bayes.bins(), bayes.categories());
    let lambda = f64::from(bayes.lambda());
    let total: f64 = bayes.all_rows().iter().map(|&n| n as f64).sum();
    let mut out = Vec::with_capacity(k * bins);
    for j in 0..k {
        for b in 0..bins {
            let mut count = 0.0f64;
            for c in 0..cats {
                let n_c = bayes.rows(c)? as f64;
                let t = f64::from(bayes.term(c, j, b)?);
                count += (n_c * (t.exp() - lambda)).round().max(0.0);
            }
            out.push(count / total);
        }
    }
    Some(out)
}

/// The file `bytes` (a table, with or without sections) with a monitor section for
/// `params` in place of any it had: the table, then its quantized section, the new
/// monitor section and its conformal section, in that order, when it has them.
///
/// # Errors
///
/// [`MonitorError::NoBayesHead`] for a table without a Bayes head; the errors of
/// [`write_monitor_section`].
pub fn with_monitor(
    bytes: &[u8],
    table: &DynTable,
    params: &MonitorParams,
) -> Result<Vec<u8>, MonitorError> {
    let bayes = table.bayes_head().ok_or(MonitorError::NoBayesHead)?;
    let (k, bins) = (bayes.logits(), bayes.bins());
    let shares: Vec<f32> = reference(table)
        .ok_or(MonitorError::NoBayesHead)?
        .into_iter()
        .map(|e| e as f32)
        .collect();
    let table_bytes = table_of(bytes);
    let crc = table_bytes
        .len()
        .checked_sub(4)
        .and_then(|at| table_bytes.get(at..))
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes);
    let mut section = vec![0u8; monitor_section_len(k, bins)];
    write_monitor_section(
        &mut section,
        crc,
        k,
        bins,
        table.open_params().is_some(),
        params,
        &shares,
    )?;
    let mut out = table_bytes.to_vec();
    if let Some(q) = section_of(bytes, QUANTIZED_MAGIC) {
        out.extend_from_slice(q);
    }
    out.extend_from_slice(&section);
    if let Some(s) = section_of(bytes, CONFORMAL_MAGIC) {
        out.extend_from_slice(s);
    }
    Ok(out)
}

/// Whether `bytes` has a monitor section (of any content).
pub fn has_monitor(bytes: &[u8]) -> bool {
    section_of(bytes, MONITOR_MAGIC).is_some()
}

/// A monitor over vectors: the storage of [`MonitorState`] for any shape.
#[derive(Debug, Clone)]
pub struct DynMonitor {
    tails: Vec<u32>,
    bins: Vec<u32>,
    acc: Accumulators,
    scratch: Vec<f32>,
    psi: Vec<f32>,
}

impl DynMonitor {
    /// An empty monitor for `spec`.
    pub fn new(spec: &MonitorSpec<'_>) -> Self {
        let (k, b) = (spec.k(), spec.bins());
        Self {
            tails: vec![0; 2 * k],
            bins: vec![0; k * b],
            acc: Accumulators::default(),
            scratch: vec![0.0; spec.categories()],
            psi: vec![0.0; k],
        }
    }

    fn state(&mut self) -> MonitorState<'_> {
        MonitorState::resume(&mut self.tails, &mut self.bins, &mut self.acc)
    }

    /// Pushes one detection; returns the window's metrics and per-logit PSI when it
    /// completes one.
    ///
    /// # Errors
    ///
    /// As [`MonitorSpec::push`].
    pub fn push(
        &mut self,
        spec: &MonitorSpec<'_>,
        logits: &[f32],
        objectness: f32,
    ) -> Result<Option<(WindowSummary, Vec<f32>)>, InferError> {
        let mut scratch = std::mem::take(&mut self.scratch);
        let mut psi = std::mem::take(&mut self.psi);
        let r = spec.push(
            &mut self.state(),
            logits,
            objectness,
            &mut scratch,
            &mut psi,
        );
        let out = r.map(|s| s.map(|s| (s, psi.clone())));
        self.scratch = scratch;
        self.psi = psi;
        out
    }

    /// Ends the current window (the end of a log): its metrics, `None` when empty.
    pub fn finish(&mut self, spec: &MonitorSpec<'_>) -> Option<(WindowSummary, Vec<f32>)> {
        let mut psi = std::mem::take(&mut self.psi);
        let s = spec.finish(&mut self.state(), &mut psi);
        let out = s.map(|s| (s, psi.clone()));
        self.psi = psi;
        out
    }

    /// The running sums of the current window.
    pub fn accumulators(&self) -> &Accumulators {
        &self.acc
    }
}

/// The generator of the resampled windows: SplitMix64 from `seed`, so that any
/// implementation draws the same rows (DESIGN §7).
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// The generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64-bit value.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A row index below `n`: `floor(next * n / 2^64)`.
    pub fn index(&mut self, n: usize) -> usize {
        ((u128::from(self.next_u64()) * n as u128) >> 64) as usize
    }
}

/// The metrics of the resampled in-distribution windows and the thresholds chosen
/// from them.
#[derive(Debug, Clone)]
pub struct FittedThresholds {
    /// The thresholds.
    pub thresholds: Thresholds,
    /// The per-metric level `beta <= alpha` the thresholds are quantiles at.
    pub level: f64,
    /// Share of the resampled windows with any alarm at these thresholds (`<= alpha`).
    pub alarm_rate: f64,
    /// Every resampled window's metrics.
    pub windows: Vec<WindowSummary>,
}

/// Fits the thresholds of DESIGN §7: `windows` windows of `spec`'s `W` rows, each
/// drawn uniformly with replacement from the `n` rows (`logits`: n x K, row-major;
/// `objectness`: n) by [`SplitMix64`] from `seed`, scored by the layer's monitor; each
/// metric's threshold is its quantile at level `1 - beta` (the lower `beta` quantile
/// for `q_mean`), with `beta` the largest of `alpha * i / 100` (`i` = 100 down to 1)
/// at which at most a share `alpha` of the windows has any alarm.
///
/// # Errors
///
/// The first row the layer refuses, as its index and the error.
pub fn fit_thresholds(
    spec: &MonitorSpec<'_>,
    logits: &[f32],
    objectness: &[f32],
    alpha: f64,
    windows: usize,
    seed: u64,
) -> Result<FittedThresholds, (usize, InferError)> {
    let k = spec.k();
    let n = objectness.len();
    let window = spec.params().window as usize;
    let mut rng = SplitMix64::new(seed);
    let mut mon = DynMonitor::new(spec);
    let mut summaries = Vec::with_capacity(windows);
    if n > 0 {
        for _ in 0..windows {
            for _ in 0..window {
                let i = rng.index(n);
                let x = logits.get(i * k..(i + 1) * k).unwrap_or_default();
                let os = objectness.get(i).copied().unwrap_or(1.0);
                if let Some((s, _)) = mon.push(spec, x, os).map_err(|e| (i, e))? {
                    summaries.push(s);
                }
            }
        }
    }
    let mut psi: Vec<f32> = summaries.iter().map(|s| s.psi_max).collect();
    let mut oos: Vec<f32> = summaries.iter().map(|s| s.oos_rate).collect();
    let mut q: Vec<f32> = summaries.iter().filter_map(|s| s.q_mean).collect();
    psi.sort_by(f32::total_cmp);
    oos.sort_by(f32::total_cmp);
    q.sort_by(f32::total_cmp);
    let r = summaries.len();
    let at = |beta: f64| -> Thresholds {
        // Upper quantile: the ceil((1 - beta) R)-th smallest; lower: the (floor(beta R) + 1)-th.
        let upper = ((1.0 - beta) * r as f64).ceil() as usize;
        let lower = (beta * r as f64).floor() as usize;
        let up = |v: &[f32]| {
            upper
                .checked_sub(1)
                .and_then(|i| v.get(i))
                .copied()
                .unwrap_or(f32::INFINITY)
        };
        Thresholds {
            psi: up(&psi),
            oos: up(&oos),
            q: if spec.has_q() {
                q.get(lower).copied().unwrap_or(f32::NEG_INFINITY)
            } else {
                f32::NEG_INFINITY
            },
        }
    };
    let rate = |t: &Thresholds| -> f64 {
        let alarms = summaries
            .iter()
            .filter(|s| {
                s.psi_max > t.psi || s.oos_rate > t.oos || s.q_mean.is_some_and(|q| q < t.q)
            })
            .count();
        if r == 0 {
            0.0
        } else {
            alarms as f64 / r as f64
        }
    };
    let mut chosen = (alpha / 100.0, at(alpha / 100.0));
    for i in (1..=100).rev() {
        let beta = alpha * f64::from(i) / 100.0;
        let t = at(beta);
        if rate(&t) <= alpha {
            chosen = (beta, t);
            break;
        }
    }
    let alarm_rate = rate(&chosen.1);
    Ok(FittedThresholds {
        thresholds: chosen.1,
        level: chosen.0,
        alarm_rate,
        windows: summaries,
    })
}
