//! `mlmap eval`: sigmoid, softmax, temperature, ML and MAP on labelled data
//! (DESIGN §1.4, §1.5, §4).

use std::fmt::Write as _;
use std::path::Path;

use mlmap::host::baselines::{self, Baseline, Rows};
use mlmap::host::metrics::{self, Binning, MetricsConfig};
use mlmap::host::{plots, DynTable};
use mlmap::Libm;

use crate::args::{self, EvalArgs, Format};
use crate::cmd::inspect::read_table;
use crate::error::{CliError, Result};
use crate::load::{self, Loaded};
use crate::output;
use crate::report::{self, MethodReport};

/// Scores of one method on one set: N x K, row-major.
pub struct MethodScores {
    pub method: &'static str,
    pub test: Vec<f64>,
    pub ood: Option<Vec<f64>>,
}

/// Everything `eval` computes.
pub struct Evaluation {
    pub class_names: Vec<String>,
    pub labels: Vec<Option<usize>>,
    pub scores: Vec<MethodScores>,
    pub reports: Vec<MethodReport>,
    /// Fitted temperature and its validation NLL.
    pub temperature: Option<(f64, f64)>,
    pub rows: usize,
    pub ood_rows: Option<usize>,
}

/// ML and MAP scores of every row through the layer (f32, as on the device).
pub fn layer_scores(table: &DynTable, data: &Loaded, path: &Path) -> Result<(Vec<f64>, Vec<f64>)> {
    let k = table.k();
    let mut ml = Vec::with_capacity(data.logits.len());
    let mut map = Vec::with_capacity(data.logits.len());
    let (mut x, mut s, mut scratch) = (vec![0f32; k], vec![0f32; k], vec![0f32; k]);
    for (row, (xs, &os)) in data
        .logits
        .chunks_exact(k)
        .zip(&data.objectness)
        .enumerate()
    {
        for (d, &v) in x.iter_mut().zip(xs) {
            *d = v as f32;
        }
        let at = |e| CliError::input(path, format!("data row {}: {e}", row + 1));
        table
            .ml_into(&x, os as f32, &mut s, &mut scratch)
            .map_err(at)?;
        ml.extend(s.iter().map(|&v| f64::from(v)));
        table
            .map_into::<Libm>(&x, os as f32, &mut s, &mut scratch)
            .map_err(at)?;
        map.extend(s.iter().map(|&v| f64::from(v)));
    }
    Ok((ml, map))
}

fn baseline(b: Baseline, d: &Loaded, k: usize, path: &Path) -> Result<Vec<f64>> {
    let rows = Rows::new(&d.logits, k, &[], &d.objectness).map_err(|e| CliError::input(path, e))?;
    baselines::score_rows(b, &rows).map_err(|e| CliError::input(path, e))
}

/// Inputs of an evaluation.
pub struct Inputs<'a> {
    pub table: &'a DynTable,
    pub test: &'a Loaded,
    pub test_path: &'a Path,
    pub val: Option<(&'a Loaded, &'a Path)>,
    pub ood: Option<(&'a Loaded, &'a Path)>,
    pub config: MetricsConfig,
}

/// Scores every method and computes every metric.
pub fn evaluate(inp: &Inputs<'_>) -> Result<Evaluation> {
    let table = inp.table;
    let k = table.k();
    let names: Vec<String> = table.class_names().map(str::to_string).collect();
    load::check_classes(inp.test_path, &inp.test.classes, table.class_names())?;
    let labels = inp.test.class_labels(inp.test_path)?;
    let mut temperature = None;
    if let Some((val, path)) = inp.val {
        load::check_classes(path, &val.classes, table.class_names())?;
        let vlabels = val.class_labels(path)?;
        let rows = Rows::new(&val.logits, k, &vlabels, &val.objectness)
            .map_err(|e| CliError::input(path, e))?;
        let fit =
            baselines::fit_temperature_detailed(&rows).map_err(|e| CliError::input(path, e))?;
        temperature = Some((fit.t, fit.nll));
    }
    if let Some((ood, path)) = inp.ood {
        load::check_classes(path, &ood.classes, table.class_names())?;
    }
    let mut methods: Vec<(&'static str, Option<Baseline>)> = vec![
        ("sigmoid", Some(Baseline::Sigmoid)),
        ("softmax", Some(Baseline::Softmax)),
    ];
    if let Some((t, _)) = temperature {
        methods.push(("temperature", Some(Baseline::Temperature(t))));
    }
    let mut scores = Vec::new();
    for (method, b) in methods.iter().filter_map(|(m, b)| b.map(|b| (*m, b))) {
        let ood = match inp.ood {
            Some((d, p)) => Some(baseline(b, d, k, p)?),
            None => None,
        };
        scores.push(MethodScores {
            method,
            test: baseline(b, inp.test, k, inp.test_path)?,
            ood,
        });
    }
    let (ml, map) = layer_scores(table, inp.test, inp.test_path)?;
    let (ml_ood, map_ood) = match inp.ood {
        Some((d, p)) => {
            let (a, b) = layer_scores(table, d, p)?;
            (Some(a), Some(b))
        }
        None => (None, None),
    };
    scores.push(MethodScores {
        method: "ml",
        test: ml,
        ood: ml_ood,
    });
    scores.push(MethodScores {
        method: "map",
        test: map,
        ood: map_ood,
    });
    let mut reports = Vec::new();
    for s in &scores {
        let mut m = metrics::evaluate(&s.test, k, &labels, &inp.config)
            .map_err(|e| CliError::input(inp.test_path, format!("{}: {e}", s.method)))?;
        if let (Some(o), Some((_, path))) = (&s.ood, inp.ood) {
            m = m.with_ood(
                metrics::ood_metrics(o, k)
                    .map_err(|e| CliError::input(path, format!("{}: {e}", s.method)))?,
            );
        }
        let mut entries = m.entries(&names);
        if s.method == "temperature" {
            if let Some((t, _)) = temperature {
                entries.push(("T".into(), Some(t)));
            }
        }
        reports.push(MethodReport {
            method: s.method,
            metrics: entries,
        });
    }
    Ok(Evaluation {
        class_names: names,
        labels,
        rows: inp.test.len(),
        ood_rows: inp.ood.map(|(d, _)| d.len()),
        scores,
        reports,
        temperature,
    })
}

impl Evaluation {
    /// The report in `format`.
    pub fn render(&self, format: Format, config: &MetricsConfig) -> String {
        match format {
            Format::Text => {
                let mut s = String::new();
                let tp = self.labels.iter().filter(|l| l.is_some()).count();
                let _ = writeln!(
                    s,
                    "{} test rows ({} labelled with a class, {} background){}; ECE: {} bins, {} binning",
                    self.rows,
                    tp,
                    self.rows - tp,
                    self.ood_rows.map_or(String::new(), |n| format!(", {n} out-of-distribution rows")),
                    config.bins,
                    config.binning.name(),
                );
                if let Some((t, nll)) = self.temperature {
                    let _ = writeln!(s, "temperature T = {t:.4} (validation NLL {nll:.4})");
                }
                s.push('\n');
                s.push_str(&report::text(&self.reports));
                s
            }
            Format::Markdown => report::markdown(&self.reports),
            Format::Json => {
                let extra = serde_json::json!({
                    "rows": self.rows,
                    "ood_rows": self.ood_rows,
                    "classes": self.class_names,
                    "ece_bins": config.bins,
                    "ece_binning": config.binning.name(),
                });
                let v = report::json(&self.reports, extra);
                let mut s = serde_json::to_string_pretty(&v).unwrap_or_default();
                s.push('\n');
                s
            }
        }
    }

    /// Writes every plot into `dir`; returns how many files were written.
    pub fn plot(&self, dir: &Path, table: &DynTable, bins: usize) -> Result<usize> {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::input(dir, format!("cannot create: {e}")))?;
        let methods: Vec<(&str, &[f64])> = self
            .scores
            .iter()
            .map(|s| (s.method, s.test.as_slice()))
            .collect();
        let written = plots::plot_all(
            dir,
            &self.class_names,
            &methods,
            &self.labels,
            bins,
            Some(table),
        )
        .map_err(|e| match &e {
            plots::PlotError::Io { source, .. } if output::location_refused(source) => {
                CliError::Input(e.to_string())
            }
            _ => CliError::Internal(e.to_string()),
        })?;
        Ok(written.len())
    }
}

/// The ECE binning of a flag value.
pub fn binning(b: args::Binning) -> Binning {
    match b {
        args::Binning::Default => Binning::Design,
        args::Binning::Netcal => Binning::Netcal,
        args::Binning::Torchmetrics => Binning::Torchmetrics,
    }
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
        binning: binning(a.ece_binning),
    };
    let (table, _) = read_table(&a.table)?;
    let test = load::load(&a.test)?;
    let val = a.val.as_deref().map(load::load).transpose()?;
    let ood = a.ood.as_deref().map(load::load).transpose()?;
    let ev = evaluate(&Inputs {
        table: &table,
        test: &test,
        test_path: &a.test,
        val: val.as_ref().zip(a.val.as_deref()),
        ood: ood.as_ref().zip(a.ood.as_deref()),
        config,
    })?;
    let mut text = ev.render(a.format, &config);
    if let Some(dir) = &a.plots {
        let n = ev.plot(dir, &table, config.bins)?;
        if a.format == Format::Text {
            let _ = writeln!(text, "\nwrote {n} plots into {}", dir.display());
        }
    }
    output::print(&text)
}
