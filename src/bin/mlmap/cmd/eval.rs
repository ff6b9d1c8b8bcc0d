//! `mlmap eval`: the baselines and the layer's heads on labelled data, on the whole
//! test set and per group (DESIGN §1.4, §1.5, §4).

use std::fmt::Write as _;

use mlmap::host::conformal::{evaluate, has_conformal, ConformalEval, Coverage, Rows, Which};
use mlmap::host::data::{self, Loaded};
use mlmap::host::eval::{self, Inputs};
use mlmap::host::metrics::{self, MetricsConfig};
use mlmap::host::names::Named as _;
use mlmap::host::DynTable;
use mlmap::ConformalSpec;

use crate::args::{EvalArgs, Format};
use crate::error::{CliError, Result};
use crate::output;
use crate::report;
use crate::shared::{read_table, write_plots};

/// The conformal sets of the table and the LAC baseline (DESIGN §8) on the eval's rows.
fn conformal_eval(
    a: &EvalArgs,
    table: &DynTable,
    spec: &ConformalSpec<'_>,
    test: &Loaded,
    val: Option<&Loaded>,
    ood: Option<&Loaded>,
) -> Result<ConformalEval> {
    let test_labels = test.class_labels(&a.test)?;
    let val_labels = match (val, a.val.as_deref()) {
        (Some(v), Some(p)) => Some(v.class_labels(p)?),
        _ => None,
    };
    let ood_labels = ood.map(|o| vec![None; o.len()]);
    fn rows<'d>(d: &'d Loaded, labels: &'d [Option<usize>]) -> Rows<'d> {
        Rows {
            logits: &d.logits,
            objectness: &d.objectness,
            labels,
        }
    }
    let val_rows = val.zip(val_labels.as_deref()).map(|(v, l)| rows(v, l));
    let ood_rows = ood.zip(ood_labels.as_deref()).map(|(o, l)| rows(o, l));
    evaluate(table, spec, rows(test, &test_labels), val_rows, ood_rows).map_err(|(w, i, e)| {
        let (d, p) = match w {
            Which::Test => (Some(test), Some(a.test.as_path())),
            Which::Calibration => (val, a.val.as_deref()),
            Which::Unseen => (ood, a.ood.as_deref()),
        };
        let loc = d.and_then(|d| d.locations.get(i).copied());
        match (p, loc) {
            (Some(p), Some(loc)) => CliError::Input(format!("{}: {e}", data::at(p, loc))),
            _ => CliError::Input(format!("row {i}: {e}")),
        }
    })
}

fn conformal_report(out: &mut String, format: Format, ce: &ConformalEval, table: &DynTable) {
    let names: Vec<&str> = table.class_names().collect();
    let methods: Vec<(String, &Coverage)> =
        std::iter::once((format!("sets ({})", ce.head.name()), &ce.sets))
            .chain(ce.lac.as_ref().map(|(_, c)| ("LAC softmax".to_string(), c)))
            .collect();
    let pct = |v: f64| {
        if v.is_nan() {
            "-".to_string()
        } else {
            format!("{v:.4}")
        }
    };
    match format {
        Format::Json => {
            let cov = |c: &Coverage| {
                let per: serde_json::Map<String, serde_json::Value> = names
                    .iter()
                    .zip(&c.per_class)
                    .map(|(n, &(rows, v))| {
                        (
                            (*n).to_string(),
                            serde_json::json!({"rows": rows, "coverage": finite(v)}),
                        )
                    })
                    .collect();
                serde_json::json!({
                    "coverage": per,
                    "mean_size": finite(c.mean_size),
                    "empty_known": finite(c.empty_known),
                    "empty_unseen": c.empty_unseen.map(finite),
                })
            };
            let v = serde_json::json!({
                "head": ce.head.name(),
                "alpha": ce.alpha,
                "sets": cov(&ce.sets),
                "lac": ce.lac.as_ref().map(|(l, c)| {
                    let mut v = cov(c);
                    if let Some(o) = v.as_object_mut() {
                        o.insert("qhat".into(), finite(l.qhat));
                        o.insert("calibration_rows".into(), serde_json::json!(l.rows));
                    }
                    v
                }),
            });
            if let Ok(mut doc) = serde_json::from_str::<serde_json::Value>(out) {
                if let Some(o) = doc.as_object_mut() {
                    o.insert("conformal".into(), v);
                    *out = serde_json::to_string_pretty(&doc).unwrap_or_default();
                    out.push('\n');
                }
            }
        }
        Format::Text | Format::Markdown => {
            let md = format == Format::Markdown;
            let _ = writeln!(
                out,
                "\nconformal class sets (DESIGN §8) at alpha {}{}",
                ce.alpha,
                match &ce.lac {
                    Some((l, _)) => format!(
                        "; LAC baseline on OS * softmax, qhat {:.6} from {} calibration rows of --val",
                        l.qhat, l.rows
                    ),
                    None => "; give --val for the LAC baseline".to_string(),
                }
            );
            let mut rows: Vec<(String, Vec<String>)> = Vec::new();
            for (i, n) in names.iter().enumerate() {
                rows.push((
                    format!("coverage {n}"),
                    methods
                        .iter()
                        .map(|(_, c)| c.per_class.get(i).map_or("-".into(), |&(_, v)| pct(v)))
                        .collect(),
                ));
            }
            rows.push((
                "mean set size".into(),
                methods.iter().map(|(_, c)| pct(c.mean_size)).collect(),
            ));
            rows.push((
                "empty sets (known)".into(),
                methods.iter().map(|(_, c)| pct(c.empty_known)).collect(),
            ));
            if methods.iter().any(|(_, c)| c.empty_unseen.is_some()) {
                rows.push((
                    "empty sets (--ood)".into(),
                    methods
                        .iter()
                        .map(|(_, c)| c.empty_unseen.map_or("-".into(), pct))
                        .collect(),
                ));
            }
            let width = rows.iter().map(|r| r.0.len()).max().unwrap_or(8).max(8);
            if md {
                let _ = write!(out, "\n| metric |");
                for (m, _) in &methods {
                    let _ = write!(out, " {m} |");
                }
                let _ = write!(out, "\n|---|");
                for _ in &methods {
                    let _ = write!(out, "---:|");
                }
                out.push('\n');
                for (k, v) in &rows {
                    let _ = writeln!(out, "| {k} | {} |", v.join(" | "));
                }
            } else {
                let _ = write!(out, "{:<width$}", "metric");
                for (m, _) in &methods {
                    let _ = write!(out, "  {m:>14}");
                }
                out.push('\n');
                for (k, v) in &rows {
                    let _ = write!(out, "{k:<width$}");
                    for x in v {
                        let _ = write!(out, "  {x:>14}");
                    }
                    out.push('\n');
                }
            }
        }
    }
}

fn finite(v: f64) -> serde_json::Value {
    serde_json::Number::from_f64(v).map_or(serde_json::Value::Null, serde_json::Value::Number)
}

pub fn run(a: &EvalArgs) -> Result<()> {
    if a.ece_bins == 0 || a.ece_bins > metrics::MAX_BINS {
        return Err(CliError::Input(format!(
            "--ece-bins must be in 1..={}",
            metrics::MAX_BINS
        )));
    }
    let config = MetricsConfig {
        bins: a.ece_bins,
        binning: a.ece_binning,
    };
    if let Some(c) = a.group_by.as_deref() {
        if matches!(c, "label" | "objectness" | "id") || c.trim() != c || c.is_empty() {
            return Err(CliError::Input(format!(
                "--group-by {c:?}: name a column other than label, objectness and id, \
                 as written in the header"
            )));
        }
    }
    let (table, bytes) = read_table(&a.table)?;
    // With --group-by the column is not a class in any file; only the test file must
    // have it.
    let read = |p: &std::path::Path, required: bool| match a.group_by.as_deref() {
        Some(c) => Loaded::read_with_column(p, c, required),
        None => Loaded::read(p).map(|d| (d, None)),
    };
    let (test, groups) = read(&a.test, true)?;
    let val = a.val.as_deref().map(|p| read(p, false)).transpose()?;
    let ood = a.ood.as_deref().map(|p| read(p, false)).transpose()?;
    let ev = eval::evaluate(&Inputs {
        table: &table,
        test: (&test, &a.test),
        val: val.as_ref().map(|v| &v.0).zip(a.val.as_deref()),
        ood: ood.as_ref().map(|o| &o.0).zip(a.ood.as_deref()),
        config,
        groups: groups.as_deref(),
    })?;
    let mut text = report::evaluation(&ev, a.format, a.group_by.as_deref());
    if has_conformal(&bytes) {
        let spec = ConformalSpec::from_bytes(&bytes, &table.view())
            .map_err(|e| CliError::input(&a.table, e))?;
        let ce = conformal_eval(
            a,
            &table,
            &spec,
            &test,
            val.as_ref().map(|v| &v.0),
            ood.as_ref().map(|o| &o.0),
        )?;
        conformal_report(&mut text, a.format, &ce, &table);
    }
    if let Some(dir) = &a.plots {
        let n = write_plots(&ev, dir, &table)?;
        if a.format == Format::Text {
            let _ = writeln!(text, "\nwrote {n} plots into {}", dir.display());
        }
    }
    output::print(&text)
}
