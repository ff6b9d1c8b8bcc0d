//! The reports of a search: its candidates, the comparison of the heads, `tune --format
//! json` and the recalibration maps' verdicts.

use super::*;
use mlmap::host::tune::{compared_keys, compared_value, energy_value, report, ReportValue};

/// The best `top` candidates of each head as an aligned table; `searched(head)` is the
/// number of candidates searched. Candidates beyond the guards are marked `*`.
pub fn candidates(
    result: &TuneResult,
    objective: Objective,
    top: usize,
    searched: impl Fn(mlmap::Head) -> usize,
) -> String {
    let mut s = String::new();
    for h in &result.heads {
        let cands = &h.candidates;
        let _ = writeln!(
            s,
            "{} head: best {} of {} candidates by {objective}, within the guards first",
            h.head,
            top.min(cands.len()),
            searched(h.head),
        );
        if cands.first().is_some_and(|c| !c.eligible()) {
            let _ = writeln!(
                s,
                "  no candidate is within the accuracy and mAP guards: chose the one that loses least"
            );
        }
        // The open head: its Bayes head (bins, lambda) is the chosen one, the search is
        // over epsilon at one temperature.
        let open = h.head == mlmap::Head::Open;
        if let Some(t) = cands.first().and_then(|c| c.temperature) {
            let _ = writeln!(
                s,
                "  temperature {t} (fitted by NLL on the validation rows), on the chosen Bayes head"
            );
        }
        let epsilon_header = if open {
            format!(" {:>11}", "epsilon")
        } else {
            String::new()
        };
        let _ = writeln!(
            s,
            "  {:>4} {:>5} {:>11}{epsilon_header} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "rank", "bins", "lambda", "ece", "nll", "brier", "accuracy", "mAP"
        );
        for (i, c) in cands.iter().take(top).enumerate() {
            let epsilon = match (open, c.epsilon) {
                (true, Some(e)) => format!(" {e:>11.3e}"),
                _ => String::new(),
            };
            let _ = writeln!(
                s,
                "  {:>4} {:>5} {:>11.3e}{epsilon} {:>9} {:>9} {:>9} {:>9} {:>9}{}",
                i + 1,
                c.bins,
                c.lambda,
                fmt_opt(c.ece),
                fmt_opt(c.nll),
                fmt_opt(c.brier),
                fmt_opt(c.accuracy),
                fmt_opt(c.mean_ap),
                if c.eligible() { "" } else { " *" }
            );
        }
    }
    s
}

/// The sentence naming the head to ship.
fn best_sentence(c: &Comparison, objective: Objective) -> String {
    match c.best {
        Some(m) => format!(
            "best head by {objective} within the accuracy and mAP guards: {}",
            m.title()
        ),
        None => "no head is within the accuracy and mAP guards against softmax".into(),
    }
}

/// Every head at its chosen settings, softmax and temperature scaling on the
/// validation rows, as an aligned table and the sentence naming the best head.
pub fn comparison(c: &Comparison, objective: Objective) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "validation metrics at the chosen settings: {} rows{}; {}",
        c.rows,
        c.ood_rows.map_or(String::new(), |n| format!(
            " ({n} never-seen, as background)"
        )),
        c.temperature.map_or_else(
            || "no temperature (no row labelled with a class)".into(),
            |t| format!("temperature T = {t:.4}")
        )
    );
    // The energy score's column comes after the baselines, before the heads.
    let heads_from = c
        .methods
        .iter()
        .position(|m| m.method.head().is_some())
        .unwrap_or(c.methods.len());
    let (baselines, heads) = c.methods.split_at(heads_from);
    let _ = write!(s, "{:<9}", "metric");
    for m in baselines {
        let _ = write!(s, " {:>12}", m.method.name());
    }
    let _ = write!(s, " {:>12}", Method::Energy.name());
    for m in heads {
        let _ = write!(s, " {:>12}", m.method.name());
    }
    s.push('\n');
    for key in compared_keys(c) {
        let label = if key == "mean_ap" { "mAP" } else { key };
        let _ = write!(s, "{label:<9}");
        for m in baselines {
            let _ = write!(s, " {:>12}", fmt_value(compared_value(&m.metrics, key)));
        }
        let _ = write!(s, " {:>12}", fmt_value(energy_value(&c.energy, key)));
        for m in heads {
            let _ = write!(s, " {:>12}", fmt_value(compared_value(&m.metrics, key)));
        }
        s.push('\n');
    }
    let _ = write!(s, "{:<9}", "guards");
    for _ in 0..=baselines.len() {
        let _ = write!(s, " {:>12}", "");
    }
    for m in heads {
        let mark = if m.excess == 0.0 { "ok" } else { "loses" };
        let _ = write!(s, " {mark:>12}");
    }
    s.push('\n');
    let _ = writeln!(s, "{}", best_sentence(c, objective));
    s
}

/// A value of the report in JSON (a non-finite number is `null`).
fn report_json(v: &ReportValue) -> serde_json::Value {
    match v {
        ReportValue::Null => serde_json::Value::Null,
        ReportValue::Bool(b) => serde_json::json!(b),
        ReportValue::Int(n) => serde_json::json!(n),
        ReportValue::Float(x) => serde_json::json!(x),
        ReportValue::Single(x) => serde_json::json!(x),
        ReportValue::Text(t) => serde_json::json!(t),
        ReportValue::List(items) => {
            serde_json::Value::Array(items.iter().map(report_json).collect())
        }
        ReportValue::Map(entries) => serde_json::Value::Object(
            entries
                .iter()
                .map(|(k, v)| (k.clone(), report_json(v)))
                .collect(),
        ),
    }
}

/// The result of `tune` as one JSON object: the library's report (per head the best
/// `top` candidates, the comparison on the validation rows, the maps) and the written
/// table.
pub fn tune_json(
    tuned: &Tuned,
    params: &TuneParams,
    top: usize,
    table_path: &Path,
    table_bytes: usize,
) -> String {
    let mut v = report_json(&report(tuned, params, top));
    if let Some(o) = v.as_object_mut() {
        o.insert(
            "table".into(),
            serde_json::json!({ "path": table_path.display().to_string(), "bytes": table_bytes }),
        );
    }
    pretty(&v)
}

/// What `tune` decided for each head's recalibration map (DESIGN §1.9).
pub fn maps_text(maps: &[mlmap::host::tune::MapChoice]) -> String {
    let mut s = String::from(
        "recalibration maps (ECE of two-fold cross-fitting on the validation rows):\n",
    );
    if maps.is_empty() {
        s.push_str("  none could be fitted\n");
    }
    for m in maps {
        let verdict = if m.kept {
            format!("kept, {} knots", m.knots.len())
        } else if m.excess > m.excess_without {
            "not kept: it would lose accuracy or mAP beyond the guards".to_string()
        } else {
            "not kept: no lower ECE".to_string()
        };
        let _ = writeln!(
            s,
            "  {:<6} ECE {:.4} -> {:.4}  {verdict}",
            m.head.name(),
            m.ece_without,
            m.ece_with
        );
    }
    s
}
