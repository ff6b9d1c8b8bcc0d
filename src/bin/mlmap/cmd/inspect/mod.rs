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

mod heads;
mod sections;

use heads::{bayes_json, bayes_text};
use sections::{conformal_info, monitor_info, quantized_json, quantized_text};

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
    match t.bayes_head() {
        Some(b) => bayes_text(&mut s, &b, &names, bins),
        None => {
            let _ = writeln!(s, "\nBayes head  none");
        }
    }
    match t.open_params() {
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
    let feature = t
        .bayes_head()
        .is_some_and(|b| b.objectness_axis().is_some());
    if feature || HEADS.iter().any(|&h| t.recal_map(h).is_some()) {
        return 4;
    }
    match (t.bayes_head().is_some(), t.open_params().is_some()) {
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
        "bayes": t.bayes_head().map(|b| bayes_json(&b, &names)),
        "open": t.open_params().map(|o| serde_json::json!({
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
