//! `mlmap inspect TABLE`: a readable summary of a table file.

use std::borrow::Cow;
use std::fmt::Write as _;

use mlmap::host::escape::visible;
use mlmap::host::names::Named;
use mlmap::host::{DynQTable, DynTable};
use mlmap::{BayesView, Head, Histogram};

use crate::args::{Format, InspectArgs};
use crate::error::Result;
use crate::output;
use crate::shared::read_table;

/// Eight-level bar characters, lowest first.
const BARS: [char; 8] = ['▁', '▂', '▃', '▄', '▅', '▆', '▇', '█'];

/// A text sparkline of the frequencies, scaled to the largest.
fn sparkline(freqs: &[f32]) -> String {
    let max = freqs.iter().copied().fold(0.0f32, f32::max);
    freqs
        .iter()
        .map(|&f| {
            if f <= 0.0 || max <= 0.0 {
                ' '
            } else {
                let level = ((f / max) * 7.0).round() as usize;
                BARS.get(level.min(7)).copied().unwrap_or('█')
            }
        })
        .collect()
}

fn histogram_lines(s: &mut String, head: &str, name: &str, h: &Histogram<Vec<f32>>, bins: bool) {
    let _ = writeln!(
        s,
        "  {head:<4} {name:<12} [{:>9.4}, {:>9.4}]  |{}|",
        h.lo(),
        h.hi(),
        sparkline(h.frequencies())
    );
    if bins {
        for (k, f) in h.frequencies().iter().enumerate() {
            let close = if k + 1 == h.bins() { ']' } else { ')' };
            let _ = writeln!(
                s,
                "         bin {k:>3}  [{:>10.5}, {:>10.5}{close}  {f:.6}",
                h.edge(k),
                h.edge(k + 1)
            );
        }
    }
}

/// The name of Bayes category `c`: a class name, or `background` (index K).
fn category_name<'a>(names: &[&'a str], c: usize) -> &'a str {
    names.get(c).copied().unwrap_or("background")
}

/// The frequencies of category `c`, logit `j` recovered from the stored log-terms:
/// `exp(t) - lambda`, never below 0.
fn bayes_frequencies(b: &BayesView<'_>, c: usize, j: usize) -> Vec<f32> {
    let lambda = f64::from(b.lambda());
    (0..b.bins())
        .map(|bin| {
            b.term(c, j, bin)
                .map_or(0.0, |t| (f64::from(t).exp() - lambda).max(0.0) as f32)
        })
        .collect()
}

/// The share of the training rows in each Bayes category.
fn prior_shares(b: &BayesView<'_>) -> Vec<f64> {
    let total: u64 = b.all_rows().iter().sum();
    b.all_rows()
        .iter()
        .map(|&n| n as f64 / total.max(1) as f64)
        .collect()
}

/// The Bayes head in text: settings, categories, axes, and a sparkline per category
/// and logit.
fn bayes_text(s: &mut String, b: &BayesView<'_>, names: &[&str], bins: bool) {
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "Bayes head  {} bins per logit, lambda {:e}, {} categories{}",
        b.bins(),
        b.lambda(),
        b.categories(),
        if b.has_background() {
            " (the classes and background)"
        } else {
            ""
        }
    );
    let _ = writeln!(s, "{:<12} {:>10} {:>11}", "category", "rows", "prior");
    for (c, (rows, share)) in b.all_rows().iter().zip(prior_shares(b)).enumerate() {
        let _ = writeln!(
            s,
            "{:<12} {rows:>10} {share:>11.5}",
            category_name(names, c)
        );
    }
    let _ = writeln!(s, "axes (bins of each logit over every training row)");
    for (j, axis) in b.axes().iter().enumerate() {
        let _ = writeln!(
            s,
            "  logit {:<12} [{:>9.4}, {:>9.4}]",
            category_name(names, j),
            axis.lo(),
            axis.hi()
        );
    }
    let _ = writeln!(s, "frequencies per category and logit (sparkline)");
    for c in 0..b.categories() {
        for (j, axis) in b.axes().iter().enumerate() {
            let freqs = bayes_frequencies(b, c, j);
            let _ = writeln!(
                s,
                "  {:<12} {:<12} |{}|",
                category_name(names, c),
                category_name(names, j),
                sparkline(&freqs)
            );
            if bins {
                for (k, f) in freqs.iter().enumerate() {
                    let close = if k + 1 == axis.bins() { ']' } else { ')' };
                    let _ = writeln!(
                        s,
                        "         bin {k:>3}  [{:>10.5}, {:>10.5}{close}  {f:.6}",
                        axis.edge(k),
                        axis.edge(k + 1)
                    );
                }
            }
        }
    }
    if let Some(axis) = b.objectness_axis() {
        let _ = writeln!(
            s,
            "objectness feature (DESIGN §1.6): the objectness logit ln(OS) - ln(1 - OS), \
             clamped into [{:.4}, {:.4}]",
            axis.lo(),
            axis.hi()
        );
        for c in 0..b.categories() {
            let freqs = objectness_frequencies(b, c);
            let _ = writeln!(
                s,
                "  {:<12} {:<12} |{}|",
                category_name(names, c),
                "objectness",
                sparkline(&freqs)
            );
        }
    }
}

/// The frequencies of category `c`'s histogram of the objectness logit:
/// `exp(term) - lambda` of each bin (the feature's terms are bin-major, then category).
fn objectness_frequencies(b: &BayesView<'_>, c: usize) -> Vec<f32> {
    let cats = b.categories();
    b.objectness_terms()
        .iter()
        .skip(c)
        .step_by(cats.max(1))
        .map(|&t| (t.exp() - b.lambda()).max(0.0))
        .collect()
}

/// The Bayes head in JSON.
fn bayes_json(b: &BayesView<'_>, names: &[&str]) -> serde_json::Value {
    let axes: Vec<serde_json::Value> = b
        .axes()
        .iter()
        .enumerate()
        .map(|(j, a)| {
            let edges: Vec<f32> = (0..=a.bins()).map(|k| a.edge(k)).collect();
            serde_json::json!({ "logit": category_name(names, j), "edges": edges })
        })
        .collect();
    let categories: Vec<serde_json::Value> = b
        .all_rows()
        .iter()
        .zip(prior_shares(b))
        .enumerate()
        .map(|(c, (rows, share))| {
            let freqs: Vec<Vec<f32>> = (0..b.logits())
                .map(|j| bayes_frequencies(b, c, j))
                .collect();
            serde_json::json!({
                "name": category_name(names, c),
                "rows": rows,
                "prior": share,
                "frequencies": freqs,
            })
        })
        .collect();
    serde_json::json!({
        "bins": b.bins(),
        "lambda": b.lambda(),
        "background": b.has_background(),
        "axes": axes,
        "categories": categories,
        "objectness_feature": b.objectness_axis().map(|a| {
            let edges: Vec<f32> = (0..=a.bins()).map(|k| a.edge(k)).collect();
            let freqs: Vec<Vec<f32>> = (0..b.categories())
                .map(|c| objectness_frequencies(b, c))
                .collect();
            serde_json::json!({ "edges": edges, "frequencies": freqs })
        }),
    })
}

/// A window of stored codes as text: `[first, last]`, or `none`.
fn window_text(w: Option<(i32, usize)>) -> String {
    match w {
        Some((first, n)) if n > 0 => format!("[{first}, {}]", i64::from(first) + n as i64 - 1),
        Some(_) => "none".into(),
        None => "-".into(),
    }
}

/// The quantized section in text.
fn quantized_text(s: &mut String, q: &DynQTable<'_>, names: &[&str]) {
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
fn quantized_json(q: &DynQTable<'_>, names: &[&str]) -> serde_json::Value {
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

/// The text report.
fn render_text(path: &std::path::Path, t: &DynTable, bytes: &[u8], bins: bool) -> String {
    let st = t.settings();
    let crc = bytes
        .get(bytes.len().saturating_sub(4)..)
        .and_then(|b| <[u8; 4]>::try_from(b).ok())
        .map_or(0, u32::from_le_bytes);
    let mut s = String::new();
    let _ = writeln!(s, "table       {}", path.display());
    let _ = writeln!(
        s,
        "format      version {}, {} bytes, CRC-32 {crc:08x} (verified)",
        file_version(t),
        bytes.len()
    );
    // A table of an older format version may hold names with control characters.
    let shown: Vec<Cow<'_, str>> = t.class_names().map(visible).collect();
    let names: Vec<&str> = shown.iter().map(AsRef::as_ref).collect();
    let _ = writeln!(s, "classes     {}: {}", t.k(), names.join(", "));
    let _ = writeln!(
        s,
        "edges       {}, upper tail {}",
        st.edge_mode.name(),
        st.upper_tail.name()
    );
    let _ = writeln!(
        s,
        "ML head     {} bins, lambda {:e}",
        t.bins_ml(),
        st.lambda_ml
    );
    let _ = writeln!(
        s,
        "MAP head    {} bins, lambda {:e}",
        t.bins_map(),
        st.lambda_map
    );
    let _ = writeln!(s);
    let _ = writeln!(
        s,
        "{:<12} {:>10} {:>11} {:>11}",
        "class", "rows", "prior mean", "prior var"
    );
    for ((name, rows), g) in names.iter().zip(t.rows()).zip(t.priors()) {
        let _ = writeln!(
            s,
            "{name:<12} {rows:>10} {:>11.5} {:>11.5}",
            g.mean(),
            g.variance()
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "histograms (support, then frequencies as a sparkline)");
    for (name, h) in names.iter().zip(t.ml_histograms()) {
        histogram_lines(&mut s, "ML", name, h, bins);
    }
    for (name, h) in names.iter().zip(t.map_histograms()) {
        histogram_lines(&mut s, "MAP", name, h, bins);
    }
    match t.bayes() {
        Some(b) => bayes_text(&mut s, &b, &names, bins),
        None => {
            let _ = writeln!(s, "\nBayes head  none");
        }
    }
    match t.open() {
        Some(o) => {
            let _ = writeln!(
                s,
                "\nopen head   temperature {}, epsilon {:e} (unknown log-score {:e}), on the Bayes head",
                o.temperature(),
                o.epsilon(),
                o.log_unknown()
            );
        }
        None => {
            let _ = writeln!(s, "\nopen head   none");
        }
    }
    let _ = writeln!(s, "\nrecalibration maps (DESIGN §1.9: top score -> g(top))");
    let mut any = false;
    for head in HEADS {
        if let Some(m) = t.recal_map(head) {
            any = true;
            let knots: Vec<String> = m
                .knots()
                .iter()
                .map(|k| format!("{:.4}->{:.4}", k.x, k.y))
                .collect();
            let _ = writeln!(
                s,
                "  {:<6} {} knots: {}",
                head.name(),
                knots.len(),
                knots.join(" ")
            );
        }
    }
    if !any {
        let _ = writeln!(s, "  none");
    }
    s
}

/// Every head, in the order of a table's maps.
const HEADS: [Head; 4] = [Head::Ml, Head::Map, Head::Bayes, Head::Open];

/// The format version the table is written in (DESIGN §3): 4 with a recalibration
/// map, 3 with the open head, 2 with the Bayes head only, 1 otherwise.
fn file_version(t: &DynTable) -> u16 {
    let feature = t.bayes().is_some_and(|b| b.objectness_axis().is_some());
    if feature || HEADS.iter().any(|&h| t.recal_map(h).is_some()) {
        return 4;
    }
    match (t.bayes().is_some(), t.open().is_some()) {
        (_, true) => 3,
        (true, false) => 2,
        (false, false) => 1,
    }
}

/// The file's table bytes (before every section) and its quantized section, if it has
/// one.
fn split(bytes: &[u8]) -> (&[u8], Option<DynQTable<'_>>) {
    (mlmap::table_of(bytes), DynQTable::from_bytes(bytes).ok())
}

/// The JSON report.
fn render_json(
    path: &std::path::Path,
    t: &DynTable,
    bytes: &[u8],
    quantized: Option<&DynQTable<'_>>,
    monitor: serde_json::Value,
    conformal: serde_json::Value,
) -> String {
    let st = t.settings();
    let names: Vec<&str> = t.class_names().collect();
    let hist = |h: &Histogram<Vec<f32>>| {
        let edges: Vec<f32> = (0..=h.bins()).map(|k| h.edge(k)).collect();
        serde_json::json!({ "edges": edges, "frequencies": h.frequencies() })
    };
    let classes: Vec<serde_json::Value> = t
        .class_names()
        .zip(t.rows())
        .zip(t.priors())
        .zip(t.ml_histograms().iter().zip(t.map_histograms()))
        .map(|(((name, rows), g), (ml, map))| {
            serde_json::json!({
                "name": name,
                "rows": rows,
                "prior": { "mean": g.mean(), "variance": g.variance() },
                "ml": hist(ml),
                "map": hist(map),
            })
        })
        .collect();
    let v = serde_json::json!({
        "path": path.display().to_string(),
        "format_version": file_version(t),
        "bytes": bytes.len(),
        "crc_ok": true,
        "edge_mode": st.edge_mode.name(),
        "upper_tail": st.upper_tail.name(),
        "bins_ml": t.bins_ml(),
        "bins_map": t.bins_map(),
        "lambda_ml": st.lambda_ml,
        "lambda_map": st.lambda_map,
        "classes": classes,
        "bayes": t.bayes().map(|b| bayes_json(&b, &names)),
        "open": t.open().map(|o| serde_json::json!({
            "temperature": o.temperature(),
            "epsilon": o.epsilon(),
            "log_unknown": o.log_unknown(),
        })),
        "maps": HEADS
            .iter()
            .filter_map(|&h| {
                t.recal_map(h).map(|m| {
                    let knots: Vec<[f32; 2]> = m.knots().iter().map(|k| [k.x, k.y]).collect();
                    (h.name().to_string(), serde_json::json!(knots))
                })
            })
            .collect::<serde_json::Map<String, serde_json::Value>>(),
        "quantized": quantized.map(|q| quantized_json(q, &names)),
        "monitor": monitor,
        "conformal": conformal,
    });
    let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
    s.push('\n');
    s
}

/// The monitor section (DESIGN §7): its settings as text and JSON (`null` without one).
fn monitor_info(file: &[u8], table: &DynTable) -> (Option<String>, serde_json::Value) {
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
fn conformal_info(file: &[u8], table: &DynTable) -> (Option<String>, serde_json::Value) {
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

pub fn run(args: &InspectArgs) -> Result<()> {
    let (table, file) = read_table(&args.table)?;
    let (bytes, quantized) = split(&file);
    let (monitor_text, monitor_json) = monitor_info(&file, &table);
    let (conformal_text, conformal_json) = conformal_info(&file, &table);
    let text = match args.format {
        Format::Json => render_json(
            &args.table,
            &table,
            bytes,
            quantized.as_ref(),
            monitor_json,
            conformal_json,
        ),
        Format::Text | Format::Markdown => {
            let mut s = render_text(&args.table, &table, bytes, args.bins);
            if let Some(q) = &quantized {
                let shown: Vec<Cow<'_, str>> = table.class_names().map(visible).collect();
                let names: Vec<&str> = shown.iter().map(AsRef::as_ref).collect();
                quantized_text(&mut s, q, &names);
            }
            if let Some(m) = monitor_text {
                s.push_str(&m);
            }
            if let Some(c) = conformal_text {
                s.push_str(&c);
            }
            s
        }
    };
    output::print(&text)
}
