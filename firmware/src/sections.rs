//! The runtime-safety sections after the table: the drift monitor (DESIGN §7) replayed
//! window by window, and the conformal class sets (DESIGN §8).

use super::*;

/// One window report against the host's values.
fn check_window(r: &mut Report, name: &str, got: &WindowReport<K>, want: &WindowCase<K>) -> f64 {
    let s = &got.summary;
    let close = |g: f32, w: f64| (f64::from(g) - w).abs() <= MONITOR_TOLERANCE * (1.0 + w.abs());
    let mut max_err = 0.0f64;
    #[allow(unused_mut)]
    let mut want_psi_max = want.psi_max;
    #[cfg(feature = "canary")]
    if want.window == 1 {
        want_psi_max += 1e-2;
    }
    for (&g, &w) in got.psi.iter().zip(want.psi.iter()) {
        max_err = max_err.max((f64::from(g) - w).abs());
    }
    let q = s.q_mean.unwrap_or(f32::NAN);
    let ok = s.window == want.window
        && s.rows == want.rows
        && got
            .psi
            .iter()
            .zip(want.psi.iter())
            .all(|(&g, &w)| close(g, w))
        && close(s.psi_max, want_psi_max)
        && want.psi_logit.is_none_or(|l| l == s.psi_logit)
        && close(s.oos_rate, want.oos_rate)
        && close(q, want.q_mean);
    r.check(
        ok,
        "monitor window",
        format_args!(
            "{name} monitor: got window {} rows {} psi {:?} (max {} at {}) oos {} q {:?}, want \
             window {} rows {} psi {:?} (max {want_psi_max}) oos {} q {}",
            s.window,
            s.rows,
            got.psi,
            s.psi_max,
            s.psi_logit,
            s.oos_rate,
            s.q_mean,
            want.window,
            want.rows,
            want.psi,
            want.oos_rate,
            want.q_mean
        ),
    );
    let alarms = (s.alarms.psi, s.alarms.oos, s.alarms.q);
    r.check(
        alarms == want.alarms,
        "monitor window",
        format_args!(
            "{name} monitor window {}: alarms {alarms:?}, want {:?}",
            s.window, want.alarms
        ),
    );
    max_err
}

/// The drift monitor (DESIGN §7) of `MONITOR_FILE` on `t`: the stored window and
/// thresholds, a damaged section refused, and the replay of `MONITOR_ROWS` through `push`
/// and `push_open` against the host's windows. Returns the largest PSI deviation.
pub(crate) fn check_monitor(r: &mut Report, name: &str, t: &EmbeddedTable) -> f64 {
    let view = t.view();
    let bytes = black_box(MONITOR_FILE);
    // A flipped bit in the section fails its CRC.
    let mut copy = [0u8; MONITOR_FILE.len()];
    copy.copy_from_slice(bytes);
    if let Some(b) = copy.get_mut(MONITOR_FILE.len() - 20) {
        *b ^= 1;
    }
    let damaged = MonitorSpec::from_bytes(black_box(&copy[..]), &view).err();
    r.check(
        damaged == Some(MonitorError::Corrupted),
        "monitor section",
        format_args!("{name}: a damaged section gave {damaged:?}"),
    );
    let spec = match MonitorSpec::from_bytes(bytes, &view) {
        Ok(s) => s,
        Err(e) => {
            r.check(false, "monitor section", format_args!("{name}: {e:?}"));
            return 0.0;
        }
    };
    let p = spec.params();
    let th = (p.thresholds.psi, p.thresholds.oos, p.thresholds.q);
    let bits = |t: (f32, f32, f32)| (t.0.to_bits(), t.1.to_bits(), t.2.to_bits());
    r.check(
        p.window == MONITOR_WINDOW && bits(th) == bits(MONITOR_THRESHOLDS) && spec.has_q(),
        "monitor section",
        format_args!(
            "{name}: window {} thresholds {th:?}, want {MONITOR_WINDOW} {MONITOR_THRESHOLDS:?}",
            p.window
        ),
    );
    let (mut plain, mut open) = match (EmbeddedMonitor::new(&spec), EmbeddedMonitor::new(&spec)) {
        (Ok(a), Ok(b)) => (a, b),
        (a, _) => {
            r.check(false, "monitor", format_args!("{name}: {:?}", a.err()));
            return 0.0;
        }
    };
    // A rejected detection counts nothing.
    let mut bad = [0.0f32; K];
    bad[1] = f32::NAN;
    let refused = plain.push(black_box(&bad), 1.0).err();
    r.check(
        refused == Some(InferError::NanLogit { class: 1 }) && plain.accumulators().rows == 0,
        "monitor",
        format_args!("{name}: a NaN logit gave {refused:?}"),
    );
    let mut windows = MONITOR_WINDOWS.iter();
    let mut max_err = 0.0f64;
    let mut seen = 0usize;
    let mut scores_same = true;
    let mut ended =
        |r: &mut Report, a: Option<WindowReport<K>>, b: Option<WindowReport<K>>| match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                seen += 1;
                r.check(
                    a.summary == b.summary && a.psi.map(f32::to_bits) == b.psi.map(f32::to_bits),
                    "monitor",
                    format_args!("{name}: push and push_open report other windows"),
                );
                match windows.next() {
                    Some(want) => max_err = max_err.max(check_window(r, name, &a, want)),
                    None => r.check(false, "monitor", format_args!("{name}: an extra window")),
                }
            }
            _ => r.check(
                false,
                "monitor",
                format_args!("{name}: push and push_open end windows apart"),
            ),
        };
    for (x, os) in MONITOR_ROWS {
        let (x, os) = (black_box(*x), black_box(*os));
        let a = plain.push(&x, os);
        let b = open.push_open(&x, os);
        match (a, b) {
            (Ok(a), Ok((scores, b))) => {
                scores_same &= t.open(&x, os).is_ok_and(|s| s.0 == scores.0);
                ended(r, a, b);
            }
            (a, b) => r.check(
                false,
                "monitor",
                format_args!("{name}: push {:?}, push_open {:?}", a.err(), b.err()),
            ),
        }
    }
    ended(r, plain.flush(), open.flush());
    r.check(
        scores_same,
        "monitor",
        format_args!("{name}: push_open's scores are not the open head's"),
    );
    r.check(
        seen == MONITOR_WINDOWS.len() && plain.flush().is_none(),
        "monitor",
        format_args!("{name}: {seen} windows, want {}", MONITOR_WINDOWS.len()),
    );
    max_err
}

/// The conformal class sets (DESIGN §8) of `CONFORMAL_FILE` on `t`: the stored alpha,
/// head and thresholds, a damaged section refused, and the sets of `SET_CASES`.
pub(crate) fn check_conformal(r: &mut Report, name: &str, t: &EmbeddedTable) {
    let view = t.view();
    let bytes = black_box(CONFORMAL_FILE);
    let mut copy = [0u8; CONFORMAL_FILE.len()];
    copy.copy_from_slice(bytes);
    if let Some(b) = copy.get_mut(CONFORMAL_FILE.len() - 20) {
        *b ^= 1;
    }
    let damaged = ConformalSpec::from_bytes(black_box(&copy[..]), &view).err();
    r.check(
        damaged == Some(ConformalError::Corrupted),
        "conformal section",
        format_args!("{name}: a damaged section gave {damaged:?}"),
    );
    let spec = match ConformalSpec::from_bytes(bytes, &view) {
        Ok(s) => s,
        Err(e) => {
            r.check(false, "conformal section", format_args!("{name}: {e:?}"));
            return;
        }
    };
    let thresholds_ok = (0..K).all(|c| {
        spec.threshold(c)
            .is_some_and(|v| (f64::from(v) - CONFORMAL_THRESHOLDS[c]).abs() <= TOLERANCE)
    });
    r.check(
        spec.alpha().to_bits() == CONFORMAL_ALPHA.to_bits()
            && spec.head() == Head::Open
            && thresholds_ok,
        "conformal section",
        format_args!(
            "{name}: alpha {} head {:?} thresholds {:?}, want {CONFORMAL_ALPHA} open \
             {CONFORMAL_THRESHOLDS:?}",
            spec.alpha(),
            spec.head(),
            [spec.threshold(0), spec.threshold(1), spec.threshold(2)]
        ),
    );
    let mut scratch = [0.0f32; mlmap::embedded::CATEGORIES];
    let mut compared = 0;
    for case in SET_CASES {
        let (x, os) = (black_box(case.logits), black_box(case.objectness));
        let mut scores = [0.0f32; K];
        let got = spec.set64(&view, &x, os, &mut scores, &mut scratch);
        #[allow(unused_mut)]
        let mut want = case.mask;
        #[cfg(feature = "canary")]
        if case.label == SET_CASES[0].label {
            want ^= 1;
        }
        let Ok(mask) = got else {
            r.check(false, case.label, format_args!("{name} set: {got:?}"));
            continue;
        };
        // The set is the classes whose open-head score reaches their threshold.
        let own = t.open(&x, os).is_ok_and(|s| {
            s.0 == scores
                && (0..K).all(|c| {
                    let inside = spec.threshold(c).is_some_and(|v| scores[c] >= v);
                    ((mask >> c) & 1 == 1) == inside
                })
        });
        let same = !case.compared || mask == want;
        compared += usize::from(case.compared);
        r.check(
            own && same && mask < 1 << K,
            case.label,
            format_args!("{name} set: got mask {mask:#b} (scores {scores:?}), want {want:#b}"),
        );
    }
    let mut bad = [1.0f32; K];
    bad[2] = f32::NAN;
    let mut scores = [0.0f32; K];
    let refused = spec
        .set64(&view, &bad, 1.0, &mut scores, &mut scratch)
        .err();
    r.check(
        refused == Some(InferError::NanLogit { class: 2 }) && compared >= 10,
        "conformal",
        format_args!("{name}: a NaN logit gave {refused:?}; {compared} sets compared"),
    );
}
