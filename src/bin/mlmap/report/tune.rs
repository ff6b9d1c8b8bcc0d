//! The reports of a search: its candidates, the comparison of the heads, `tune --format
//! json` and the recalibration maps' verdicts.

use super::*;

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

/// The keys of the comparison of `tune`, in print order.
const COMPARED: [&str; 6] = ["ece", "nll", "brier", "accuracy", "mAP", "auroc"];

/// The comparison's value of `key` for one method.
fn compared_value(m: &mlmap::host::metrics::Metrics, key: &str) -> Option<f64> {
    match key {
        "ece" => Some(m.ece),
        "nll" => m.nll,
        "brier" => Some(m.brier),
        "accuracy" => m.accuracy,
        "mAP" => m.mean_ap(),
        "auroc" => m.auroc,
        "ood_mean" => m.ood.map(|o| o.ood_mean),
        "ood_auroc" => m.ood.and_then(|o| o.auroc),
        "ood_fpr95" => m.ood.and_then(|o| o.fpr95),
        _ => None,
    }
}

/// The keys of the comparison, `ood_mean`, `ood_auroc` and `ood_fpr95` with
/// never-seen objects.
fn compared_keys(c: &Comparison) -> Vec<&'static str> {
    let mut keys = COMPARED.to_vec();
    if c.ood_rows.is_some() {
        keys.extend(["ood_mean", "ood_auroc", "ood_fpr95"]);
    }
    keys
}

/// The energy score's value of `key` in the comparison: its ranking metrics only.
fn energy_value(r: &mlmap::host::eval::Ranking, key: &str) -> Option<f64> {
    match key {
        "auroc" => r.auroc,
        "ood_auroc" => r.ood_auroc,
        "ood_fpr95" => r.ood_fpr95,
        _ => None,
    }
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
        let _ = write!(s, "{key:<9}");
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

/// One candidate in JSON, values at full precision.
fn candidate_json(c: &Candidate) -> serde_json::Value {
    let mut v = serde_json::json!({
        "bins": c.bins,
        "lambda": c.lambda,
        "objective": finite(c.objective),
        "ece": c.ece,
        "nll": c.nll,
        "brier": c.brier,
        "accuracy": c.accuracy,
        "mean_ap": c.mean_ap,
        "within_guards": c.eligible(),
    });
    if let (Some(o), Some(t), Some(e)) = (v.as_object_mut(), c.temperature, c.epsilon) {
        o.insert("temperature".into(), serde_json::json!(t));
        o.insert("epsilon".into(), serde_json::json!(e));
    }
    v
}

/// A finite number, or null.
fn finite(v: f64) -> serde_json::Value {
    if v.is_finite() {
        serde_json::json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// The result of `tune` as one JSON object: per head the best `top` candidates, the
/// comparison on the validation rows, and the written table.
pub fn tune_json(
    tuned: &Tuned,
    params: &TuneParams,
    top: usize,
    table_path: &Path,
    table_bytes: usize,
) -> String {
    let result = &tuned.result;
    let mut v = serde_json::Map::new();
    v.insert("objective".into(), params.objective.name().into());
    let counts: serde_json::Map<String, serde_json::Value> = result
        .heads
        .iter()
        .map(|h| (h.head.name().to_string(), params.candidates(h.head).into()))
        .collect();
    v.insert("candidates".into(), counts.into());
    for h in &result.heads {
        let list: Vec<serde_json::Value> = h
            .candidates
            .iter()
            .take(top)
            .enumerate()
            .map(|(i, c)| {
                let mut j = candidate_json(c);
                if let Some(o) = j.as_object_mut() {
                    o.insert("rank".into(), (i + 1).into());
                }
                j
            })
            .collect();
        v.insert(h.head.name().to_string(), list.into());
    }
    let c = &tuned.comparison;
    let mut methods = serde_json::Map::new();
    for m in &c.methods {
        let mut o = serde_json::Map::new();
        for key in compared_keys(c) {
            let name = if key == "mAP" { "mean_ap" } else { key };
            let value = compared_value(&m.metrics, key)
                .filter(|x| x.is_finite())
                .map_or(serde_json::Value::Null, |x| serde_json::json!(x));
            o.insert(name.into(), value);
        }
        if let Some(ch) = &m.chosen {
            o.insert("bins".into(), ch.bins.into());
            o.insert("lambda".into(), serde_json::json!(ch.lambda));
            if let (Some(t), Some(e)) = (ch.temperature, ch.epsilon) {
                o.insert("temperature".into(), serde_json::json!(t));
                o.insert("epsilon".into(), serde_json::json!(e));
            }
            o.insert("within_guards".into(), (m.excess == 0.0).into());
        }
        methods.insert(m.method.name().to_string(), o.into());
    }
    let energy: serde_json::Map<String, serde_json::Value> = compared_keys(c)
        .into_iter()
        .map(|key| {
            let name = if key == "mAP" { "mean_ap" } else { key };
            let value = energy_value(&c.energy, key)
                .filter(|x| x.is_finite())
                .map_or(serde_json::Value::Null, |x| serde_json::json!(x));
            (name.to_string(), value)
        })
        .collect();
    methods.insert(Method::Energy.name().to_string(), energy.into());
    v.insert(
        "validation".into(),
        serde_json::json!({
            "rows": c.rows,
            "ood_rows": c.ood_rows,
            "temperature": c.temperature,
            "max_accuracy_loss": params.guards.max_accuracy_loss,
            "max_map_loss": params.guards.max_map_loss,
            "methods": methods,
            "best": c.best.map(|m| m.name()),
        }),
    );
    if params.maps {
        let maps: serde_json::Map<String, serde_json::Value> = tuned
            .maps
            .iter()
            .map(|m| {
                let finite = |x: f64| x.is_finite().then(|| serde_json::json!(x));
                let knots: Vec<[f32; 2]> = m.knots.iter().map(|k| [k.x, k.y]).collect();
                (
                    m.head.name().to_string(),
                    serde_json::json!({
                        "kept": m.kept,
                        "cv_ece_without": finite(m.ece_without),
                        "cv_ece_with": finite(m.ece_with),
                        "within_guards": m.excess == 0.0,
                        "adds_no_loss": m.excess <= m.excess_without,
                        "knots": knots,
                    }),
                )
            })
            .collect();
        v.insert("maps".into(), maps.into());
    }
    v.insert(
        "table".into(),
        serde_json::json!({ "path": table_path.display().to_string(), "bytes": table_bytes }),
    );
    pretty(&serde_json::Value::Object(v))
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
