//! The drift monitor of docs/DESIGN.md section 7 for C: storage the caller owns, sized
//! by `MLMAP_MONITOR_SIZE(k, bins)`, running the Rust layer's `MonitorSpec`.

use core::ffi::c_void;
use core::mem::{align_of, size_of};
use core::ptr;

use mlmap::{Accumulators, MonitorError, MonitorSpec, MonitorState, WindowSummary};

use super::limits::{MAX_CATEGORIES, MAX_CLASSES};
use super::mlmap_status_t::{self, *};
use super::{check_ptr, mlmap_table_t, overlap, put, status, table_ref};

/// Bytes of the fixed part of a monitor's storage (its spec and running sums); the
/// counts follow it. `MLMAP_MONITOR_SIZE(k, bins)` adds `4 k (bins + 2)` bytes.
pub const MLMAP_MONITOR_HEADER: usize = 256;

/// Alignment of a monitor's storage in bytes.
pub const MLMAP_MONITOR_ALIGN: usize = 8;

/// The fixed part of a monitor's storage.
#[repr(C)]
struct Header {
    tag: u64,
    spec: MonitorSpec<'static>,
    acc: Accumulators,
    k: usize,
    bins: usize,
}

const _: () = assert!(size_of::<Header>() <= MLMAP_MONITOR_HEADER);
const _: () = assert!(align_of::<Header>() <= MLMAP_MONITOR_ALIGN);

/// Written into [`Header::tag`] once a monitor is initialised.
const TAG: u64 = u64::from_le_bytes(*b"MLMPmon1");

/// The metrics of one window (docs/DESIGN.md section 7).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct mlmap_window_t {
    /// Index of the window, from 0.
    pub window: u32,
    /// Detections in the window (`W`, or fewer for a window ended by mlmap_monitor_finish()).
    pub rows: u32,
    /// The largest per-logit population stability index.
    pub psi_max: f32,
    /// The logit (class index) of `psi_max`.
    pub psi_logit: u32,
    /// Share of the detections with a logit out of support.
    pub oos_rate: f32,
    /// Mean known-probability q of the open head; NaN when the table has no open head.
    pub q_mean: f32,
    /// 1 when any metric passed its threshold, else 0.
    pub alarm: u32,
    /// 1 when `psi_max` passed its threshold.
    pub alarm_psi: u32,
    /// 1 when `oos_rate` passed its threshold.
    pub alarm_oos: u32,
    /// 1 when `q_mean` fell below its threshold.
    pub alarm_q: u32,
}

impl From<WindowSummary> for mlmap_window_t {
    fn from(s: WindowSummary) -> Self {
        Self {
            window: s.window,
            rows: s.rows,
            psi_max: s.psi_max,
            psi_logit: u32::from(s.psi_logit),
            oos_rate: s.oos_rate,
            q_mean: s.q_mean.unwrap_or(f32::NAN),
            alarm: u32::from(s.alarms.any()),
            alarm_psi: u32::from(s.alarms.psi),
            alarm_oos: u32::from(s.alarms.oos),
            alarm_q: u32::from(s.alarms.q),
        }
    }
}

impl From<MonitorError> for mlmap_status_t {
    fn from(e: MonitorError) -> Self {
        match e {
            MonitorError::Absent => MLMAP_ERR_NO_SECTION,
            MonitorError::Corrupted => MLMAP_ERR_CORRUPTED,
            MonitorError::UnsupportedVersion { .. } => MLMAP_ERR_UNSUPPORTED_VERSION,
            MonitorError::NoBayesHead => MLMAP_ERR_NO_BAYES_HEAD,
            _ => MLMAP_ERR_INVALID_SECTION,
        }
    }
}

/// Bytes of a monitor's storage for `k` logits of `bins` bins (`MLMAP_MONITOR_SIZE`).
const fn storage_bytes(k: usize, bins: usize) -> Option<usize> {
    match bins.checked_add(2) {
        Some(b2) => match k.checked_mul(b2) {
            Some(n) => match n.checked_mul(4) {
                Some(n) => n.checked_add(MLMAP_MONITOR_HEADER),
                None => None,
            },
            None => None,
        },
        None => None,
    }
}

/// Initialises a drift monitor in `monitor` for `table` from the monitor section in
/// `bytes` (a table file with the section, as written by `mlmap monitor fit`, or the
/// section alone), its first window empty.
///
/// Checks the section as the Rust `MonitorSpec::from_bytes` does: the magic, the CRC,
/// the version, the shape against the table's Bayes head, the table's CRC when the
/// table precedes the section, the window, alpha, the thresholds and every share.
///
/// Lifetime: the monitor keeps pointers into `table` and `bytes`: both must stay in
/// place and unchanged while the monitor is used (a table decoded again, or bytes
/// rewritten, need mlmap_monitor_init() again). On failure the storage holds no
/// monitor.
///
/// @param[out] monitor Storage of `MLMAP_MONITOR_SIZE(k, bins)` bytes aligned to
///   `MLMAP_MONITOR_ALIGN`, `k` the table's classes and `bins` its Bayes bins.
/// @param monitor_size Its size in bytes (`MLMAP_ERR_STORAGE_TOO_SMALL` when too small).
/// @param table A decoded table with the Bayes head (`MLMAP_ERR_NO_BAYES_HEAD`).
/// @param bytes The bytes holding the monitor section; they must not overlap the monitor.
/// @param len Number of bytes.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_TABLE`, `MLMAP_ERR_NO_BAYES_HEAD`, `MLMAP_ERR_STORAGE_TOO_SMALL`,
///   `MLMAP_ERR_TOO_LARGE`, `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NO_SECTION`,
///   `MLMAP_ERR_CORRUPTED`, `MLMAP_ERR_UNSUPPORTED_VERSION`, `MLMAP_ERR_INVALID_SECTION`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_monitor_init(
    monitor: *mut c_void,
    monitor_size: usize,
    table: *const mlmap_table_t,
    bytes: *const u8,
    len: usize,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe { init(monitor, monitor_size, table, bytes, len) })
}

unsafe fn init(
    monitor: *mut c_void,
    monitor_size: usize,
    table: *const mlmap_table_t,
    bytes: *const u8,
    len: usize,
) -> Result<(), mlmap_status_t> {
    let header = monitor.cast::<Header>();
    check_ptr(header)?;
    check_ptr(bytes)?;
    // SAFETY: forwarded contract.
    let (view, used) = unsafe { table_ref(table) }?;
    let bayes = view.bayes().ok_or(MLMAP_ERR_NO_BAYES_HEAD)?;
    let (k, bins) = (bayes.logits(), bayes.bins());
    let need = storage_bytes(k, bins).ok_or(MLMAP_ERR_TOO_LARGE)?;
    let describes_memory =
        |at: usize, n: usize| n <= isize::MAX as usize && at.checked_add(n).is_some();
    let (m, b) = (monitor as usize, bytes as usize);
    if !describes_memory(m, monitor_size) || !describes_memory(b, len) {
        return Err(MLMAP_ERR_TOO_LARGE);
    }
    if monitor_size < need {
        return Err(MLMAP_ERR_STORAGE_TOO_SMALL);
    }
    if overlap(m, need, b, len) || overlap(m, need, table as usize, used) {
        return Err(MLMAP_ERR_OVERLAP);
    }
    // SAFETY: `len` readable bytes (the caller's promise), disjoint from the monitor.
    // The caller keeps them and the table in place while the monitor is used (the
    // documented contract), which is what the `'static` borrow stands for.
    let section: &'static [u8] = unsafe { core::slice::from_raw_parts(bytes, len) };
    // SAFETY: `header` is non-NULL, aligned, and `need >= size_of::<Header>()` writable
    // bytes; the tag is cleared before anything else so a failure leaves no monitor.
    unsafe { ptr::addr_of_mut!((*header).tag).write(0) };
    let spec = MonitorSpec::from_bytes(section, view)?;
    // SAFETY: as above; the counts follow the header inside the `need` bytes.
    unsafe {
        ptr::addr_of_mut!((*header).spec).write(spec);
        ptr::addr_of_mut!((*header).acc).write(Accumulators::default());
        ptr::addr_of_mut!((*header).k).write(k);
        ptr::addr_of_mut!((*header).bins).write(bins);
        let counts = monitor.cast::<u8>().add(MLMAP_MONITOR_HEADER);
        ptr::write_bytes(counts, 0, need - MLMAP_MONITOR_HEADER);
        ptr::addr_of_mut!((*header).tag).write(TAG);
    }
    Ok(())
}

/// The initialised monitor in `monitor` and its counts.
///
/// # Safety
///
/// `monitor` is NULL or points to storage passed to [`mlmap_monitor_init`] (or zeroed).
unsafe fn open<'a>(
    monitor: *mut c_void,
) -> Result<(&'a MonitorSpec<'static>, MonitorState<'a>, usize), mlmap_status_t> {
    let header = monitor.cast::<Header>();
    check_ptr(header)?;
    // SAFETY: non-NULL and aligned; storage of at least the tag's size.
    if unsafe { ptr::addr_of!((*header).tag).read() } != TAG {
        return Err(MLMAP_ERR_NO_MONITOR);
    }
    // SAFETY: the tag is written only after a successful init into storage of
    // `MLMAP_MONITOR_SIZE(k, bins)` bytes, which then holds a valid header and counts.
    unsafe {
        let h = &mut *header;
        let (k, bins) = (h.k, h.bins);
        let counts = monitor.cast::<u8>().add(MLMAP_MONITOR_HEADER).cast::<u32>();
        let tails = core::slice::from_raw_parts_mut(counts, 2 * k);
        let per_bin = core::slice::from_raw_parts_mut(counts.add(2 * k), k * bins);
        let state = MonitorState::resume(tails, per_bin, &mut h.acc);
        Ok((&h.spec, state, k))
    }
}

/// Writes a window's metrics and per-logit PSI.
unsafe fn report(
    monitor: *mut c_void,
    summary: Option<WindowSummary>,
    psi: &[f32],
    window: *mut mlmap_window_t,
    psi_out: *mut f32,
    completed: *mut u32,
) -> Result<(), mlmap_status_t> {
    if let Some(s) = summary {
        // SAFETY: checked by the caller of `report`: outputs non-NULL (psi_out when
        // psi is non-empty), aligned, large enough and disjoint from the monitor.
        unsafe {
            put(window, mlmap_window_t::from(s))?;
            if !psi.is_empty() {
                ptr::copy_nonoverlapping(psi.as_ptr(), psi_out, psi.len());
            }
        }
    }
    let _ = monitor;
    // SAFETY: as above.
    unsafe { put(completed, u32::from(summary.is_some())) }
}

/// Checks the outputs of a push or a finish against the monitor's storage and each other.
fn check_outputs(
    monitor: *mut c_void,
    k: usize,
    bins: usize,
    window: *mut mlmap_window_t,
    psi: *mut f32,
    psi_len: usize,
    completed: *mut u32,
) -> Result<usize, mlmap_status_t> {
    check_ptr(window)?;
    check_ptr(completed)?;
    let psi_n = if psi.is_null() && psi_len == 0 {
        0
    } else {
        check_ptr(psi)?;
        if psi_len < k {
            return Err(MLMAP_ERR_BUFFER_TOO_SMALL);
        }
        k
    };
    let size = storage_bytes(k, bins).unwrap_or(usize::MAX);
    let regions = [
        (monitor as usize, size),
        (window as usize, size_of::<mlmap_window_t>()),
        (psi as usize, 4 * psi_n),
        (completed as usize, size_of::<u32>()),
    ];
    for (i, &(a, an)) in regions.iter().enumerate() {
        for &(b, bn) in regions.iter().skip(i + 1) {
            if overlap(a, an, b, bn) {
                return Err(MLMAP_ERR_OVERLAP);
            }
        }
    }
    Ok(psi_n)
}

/// Pushes one detection into the monitor's current window. When it completes the
/// window (its `W`-th detection), writes the window's metrics into `*window`, its K
/// per-logit PSI into `psi` (when given), `*completed = 1`, and starts the next window;
/// otherwise writes `*completed = 0` only.
///
/// Work: K bin lookups (and the Bayes log-scores for q when the table has the open
/// head); the end of a window adds `K (B + 2)` terms. No allocation, bounded time.
///
/// @param monitor A monitor from mlmap_monitor_init().
/// @param logits K logits; they may lie anywhere (copied first).
/// @param n_logits K (`MLMAP_ERR_LENGTH` otherwise).
/// @param objectness In [0, 1] (`MLMAP_ERR_OBJECTNESS`).
/// @param[out] window Receives a completed window's metrics.
/// @param[out] psi NULL (with `psi_len` 0), or at least K floats for the per-logit PSI.
/// @param psi_len Floats at `psi`.
/// @param[out] completed 1 when a window was completed, else 0.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_MONITOR`, `MLMAP_ERR_LENGTH`, `MLMAP_ERR_BUFFER_TOO_SMALL`,
///   `MLMAP_ERR_OVERLAP`, `MLMAP_ERR_NAN_LOGIT`, `MLMAP_ERR_OBJECTNESS` (nothing is
///   counted or written then).
#[no_mangle]
pub unsafe extern "C" fn mlmap_monitor_push(
    monitor: *mut c_void,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    window: *mut mlmap_window_t,
    psi: *mut f32,
    psi_len: usize,
    completed: *mut u32,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe {
        push(
            monitor, logits, n_logits, objectness, window, psi, psi_len, completed,
        )
    })
}

#[allow(clippy::too_many_arguments)]
unsafe fn push(
    monitor: *mut c_void,
    logits: *const f32,
    n_logits: usize,
    objectness: f32,
    window: *mut mlmap_window_t,
    psi: *mut f32,
    psi_len: usize,
    completed: *mut u32,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let (spec, mut state, k) = unsafe { open(monitor) }?;
    check_ptr(logits)?;
    if n_logits != k {
        return Err(MLMAP_ERR_LENGTH);
    }
    let psi_n = check_outputs(monitor, k, spec.bins(), window, psi, psi_len, completed)?;
    let mut x = [0.0f32; MAX_CLASSES];
    let x = x.get_mut(..k).ok_or(MLMAP_ERR_LENGTH)?;
    // SAFETY: `k` readable floats at `logits` (the caller's promise), copied before
    // anything is written.
    unsafe { ptr::copy_nonoverlapping(logits, x.as_mut_ptr(), k) };
    let mut scratch = [0.0f32; MAX_CATEGORIES];
    let mut per = [0.0f32; MAX_CLASSES];
    let per = per.get_mut(..psi_n).ok_or(MLMAP_ERR_LENGTH)?;
    let summary = spec.push(&mut state, x, objectness, &mut scratch, per)?;
    // SAFETY: outputs checked above.
    unsafe { report(monitor, summary, per, window, psi, completed) }
}

/// Ends the current window early (the end of a log): writes its metrics and
/// `*completed = 1` when it holds any detection (a window of fewer than `W` detections
/// raises no alarm), else `*completed = 0`; the next window starts empty.
///
/// @param monitor A monitor from mlmap_monitor_init().
/// @param[out] window Receives the window's metrics.
/// @param[out] psi NULL (with `psi_len` 0), or at least K floats.
/// @param psi_len Floats at `psi`.
/// @param[out] completed 1 when a window was reported, else 0.
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_MONITOR`, `MLMAP_ERR_BUFFER_TOO_SMALL`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_monitor_finish(
    monitor: *mut c_void,
    window: *mut mlmap_window_t,
    psi: *mut f32,
    psi_len: usize,
    completed: *mut u32,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe { finish(monitor, window, psi, psi_len, completed) })
}

unsafe fn finish(
    monitor: *mut c_void,
    window: *mut mlmap_window_t,
    psi: *mut f32,
    psi_len: usize,
    completed: *mut u32,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let (spec, mut state, k) = unsafe { open(monitor) }?;
    let psi_n = check_outputs(monitor, k, spec.bins(), window, psi, psi_len, completed)?;
    let mut per = [0.0f32; MAX_CLASSES];
    let per = per.get_mut(..psi_n).ok_or(MLMAP_ERR_LENGTH)?;
    let summary = spec.finish(&mut state, per);
    // SAFETY: outputs checked above.
    unsafe { report(monitor, summary, per, window, psi, completed) }
}

/// The monitor's window `W`, false-alarm rate and thresholds (`psi_max > t_psi`,
/// `oos_rate > t_oos`, `q_mean < t_q` alarm; infinite thresholds never do).
///
/// @param monitor A monitor from mlmap_monitor_init().
/// @param[out] window Receives `W`.
/// @param[out] alpha Receives the false-alarm rate the thresholds were fitted for (0: none).
/// @param[out] thresholds Receives `t_psi`, `t_oos`, `t_q` (3 floats).
/// @return `MLMAP_OK`, or `MLMAP_ERR_NULL_POINTER`, `MLMAP_ERR_MISALIGNED`,
///   `MLMAP_ERR_NO_MONITOR`, `MLMAP_ERR_OVERLAP`.
#[no_mangle]
pub unsafe extern "C" fn mlmap_monitor_params(
    monitor: *mut c_void,
    window: *mut u32,
    alpha: *mut f32,
    thresholds: *mut f32,
) -> mlmap_status_t {
    // SAFETY: forwarded contract.
    status(unsafe { params(monitor, window, alpha, thresholds) })
}

unsafe fn params(
    monitor: *mut c_void,
    window: *mut u32,
    alpha: *mut f32,
    thresholds: *mut f32,
) -> Result<(), mlmap_status_t> {
    // SAFETY: forwarded contract.
    let (spec, _, k) = unsafe { open(monitor) }?;
    check_ptr(window)?;
    check_ptr(alpha)?;
    check_ptr(thresholds)?;
    let size = storage_bytes(k, spec.bins()).unwrap_or(usize::MAX);
    let regions = [
        (monitor as usize, size),
        (window as usize, 4),
        (alpha as usize, 4),
        (thresholds as usize, 12),
    ];
    for (i, &(a, an)) in regions.iter().enumerate() {
        for &(b, bn) in regions.iter().skip(i + 1) {
            if overlap(a, an, b, bn) {
                return Err(MLMAP_ERR_OVERLAP);
            }
        }
    }
    let p = spec.params();
    let t = [p.thresholds.psi, p.thresholds.oos, p.thresholds.q];
    // SAFETY: checked non-NULL, aligned, disjoint; 3 floats at `thresholds` (contract).
    unsafe {
        put(window, p.window)?;
        put(alpha, p.alpha)?;
        ptr::copy_nonoverlapping(t.as_ptr(), thresholds, 3);
    }
    Ok(())
}
