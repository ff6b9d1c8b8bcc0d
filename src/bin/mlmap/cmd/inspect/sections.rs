//! The sections after the table: the quantized heads, the drift monitor and the conformal
//! class sets, as text and as JSON.

use super::*;

/// A window of stored codes as text: `[first, last]`, or `none`.
fn window_text(w: Option<(i32, usize)>) -> String {
    match w {
        Some((first, n)) if n > 0 => format!("[{first}, {}]", i64::from(first) + n as i64 - 1),
        Some(_) => "none".into(),
        None => "-".into(),
    }
}

/// The quantized section in text.
pub(super) fn quantized_text(s: &mut String, q: &DynQTable<'_>, names: &[&str]) {
    let _ = writeln!(s);
    let open = q.open_params();
    let _ = writeln!(
        s,
        "quantized  int{} codes, section {} bytes (CRC-32 verified), heads ML, MAP{}{}",
        q.bits(),
        q.section_len(),
        if q.has_bayes() { ", Bayes" } else { "" },
        if open.is_some() { ", open" } else { "" }
    );
    if let Some(o) = open {
        let _ = writeln!(
            s,
            "  open head: temperature {}, epsilon {}, ln unknown {}",
            o.temperature(),
            o.epsilon(),
            o.log_unknown()
        );
    }
    let _ = writeln!(
        s,
        "  codes stored per class (outside them: lambda, or ln lambda for Bayes)"
    );
    for (c, name) in names.iter().enumerate() {
        let (scale, zp) = q.params(c).unwrap_or((0.0, 0));
        let [ml, map, bayes] = q.windows(c).unwrap_or([None; 3]);
        let _ = writeln!(
            s,
            "  {name:<12} scale {scale}, zero point {zp}; ML {}, MAP {}, Bayes {}",
            window_text(ml),
            window_text(map),
            window_text(bayes)
        );
    }
}

/// The quantized section in JSON.
pub(super) fn quantized_json(q: &DynQTable<'_>, names: &[&str]) -> serde_json::Value {
    let classes: Vec<serde_json::Value> = names
        .iter()
        .enumerate()
        .map(|(c, name)| {
            let (scale, zp) = q.params(c).unwrap_or((0.0, 0));
            let [ml, map, bayes] = q.windows(c).unwrap_or([None; 3]);
            serde_json::json!({
                "name": name,
                "scale": scale,
                "zero_point": zp,
                "ml_codes": ml,
                "map_codes": map,
                "bayes_codes": bayes,
            })
        })
        .collect();
    // `log_unknown` is -inf for epsilon = 0, which JSON cannot hold: null then.
    let open = q.open_params().map(|o| {
        serde_json::json!({
            "temperature": o.temperature(),
            "epsilon": o.epsilon(),
            "log_unknown": o.log_unknown().is_finite().then_some(o.log_unknown()),
        })
    });
    serde_json::json!({
        "bits": q.bits(),
        "bytes": q.section_len(),
        "bayes": q.has_bayes(),
        "open": open,
        "classes": classes,
    })
}

/// The monitor section (DESIGN §7): its settings as text and JSON (`null` without one).
pub(super) fn monitor_info(file: &[u8], table: &DynTable) -> (Option<String>, serde_json::Value) {
    let Some(section) = mlmap::section_of(file, mlmap::MONITOR_MAGIC) else {
        return (None, serde_json::Value::Null);
    };
    match mlmap::MonitorSpec::from_bytes(file, &table.view()) {
        Ok(spec) => {
            let p = spec.params();
            let t = p.thresholds;
            let q = spec.has_q().then_some(t.q);
            let text = format!(
                "monitor    section {} bytes (CRC-32 verified): windows of {} detections, \
                 alpha {}; alarm when psi_max > {}, oos_rate > {}{}\n",
                section.len(),
                p.window,
                p.alpha,
                t.psi,
                t.oos,
                q.map_or_else(String::new, |q| format!(", q_mean < {q}"))
            );
            let num = |v: f32| {
                if v.is_finite() {
                    serde_json::json!(v)
                } else {
                    serde_json::Value::Null
                }
            };
            let json = serde_json::json!({
                "bytes": section.len(),
                "window": p.window,
                "alpha": p.alpha,
                "thresholds": {"psi": num(t.psi), "oos": num(t.oos), "q": q.map(num)},
            });
            (Some(text), json)
        }
        Err(e) => (
            Some(format!("monitor    section refused: {e}\n")),
            serde_json::json!({ "error": e.to_string() }),
        ),
    }
}

/// The conformal section (DESIGN §8): its head, alpha and thresholds as text and JSON
/// (`null` without one). A class whose rank `floor((n_c + 1) alpha)` is 0 has no
/// threshold (`-inf`, JSON `null`): every set holds it.
pub(super) fn conformal_info(file: &[u8], table: &DynTable) -> (Option<String>, serde_json::Value) {
    let Some(section) = mlmap::section_of(file, mlmap::CONFORMAL_MAGIC) else {
        return (None, serde_json::Value::Null);
    };
    match mlmap::ConformalSpec::from_bytes(file, &table.view()) {
        Ok(spec) => {
            let mut text = format!(
                "conformal  section {} bytes (CRC-32 verified): sets of the {} head at alpha {} \
                 (class c in the set when its score >= t_c)\n",
                section.len(),
                spec.head().name(),
                spec.alpha()
            );
            let mut classes = Vec::new();
            for (c, name) in table.class_names().enumerate() {
                let (n, t) = (
                    spec.calibration_rows(c).unwrap_or(0),
                    spec.threshold(c).unwrap_or(f32::NEG_INFINITY),
                );
                let _ = writeln!(
                    text,
                    "{}",
                    crate::shared::threshold_line(&visible(name), n, t, spec.alpha())
                );
                let rank = mlmap::threshold_rank(n, spec.alpha());
                classes.push(serde_json::json!({
                    "name": name,
                    "calibration_rows": n,
                    "rank": rank,
                    "threshold": if rank == 0 { serde_json::Value::Null } else { serde_json::json!(t) },
                }));
            }
            let json = serde_json::json!({
                "bytes": section.len(),
                "head": spec.head().name(),
                "alpha": spec.alpha(),
                "classes": classes,
            });
            (Some(text), json)
        }
        Err(e) => (
            Some(format!("conformal  section refused: {e}\n")),
            serde_json::json!({ "error": e.to_string() }),
        ),
    }
}
