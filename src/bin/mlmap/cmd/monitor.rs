//! `mlmap monitor`: the drift monitor of DESIGN §7 on the host. `monitor fit` chooses the
//! alarm thresholds from in-distribution rows and writes them, with the window and the
//! false-alarm rate, into the table file's monitor section; `monitor --input LOG`
//! replays a log through the layer's monitor and prints every window.

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, Subcommand, ValueEnum};
use mlmap::host::data::{self, check_classes, Loaded};
use mlmap::host::monitor::{fit_thresholds, has_monitor, with_monitor, DynMonitor};
use mlmap::host::DynTable;
use mlmap::{MonitorParams, MonitorSpec, Thresholds, WindowSummary};

use crate::error::{CliError, Result};
use crate::output;
use crate::shared::read_table;

/// Flags of `monitor`: replay a log, or `monitor fit`.
#[derive(Debug, Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct MonitorArgs {
    /// Fit the thresholds instead of replaying a log.
    #[command(subcommand)]
    pub fit: Option<MonitorCommand>,
    /// The table (with a monitor section from `monitor fit` for alarms).
    #[arg(long, value_name = "TABLE", required = true)]
    pub table: Option<PathBuf>,
    /// The log to replay, in order (CSV file or NPY directory).
    #[arg(long, value_name = "FILE", required = true)]
    pub input: Option<PathBuf>,
    /// Detections per window: the section's by default; required without a section.
    #[arg(long, value_name = "W")]
    pub window: Option<u32>,
    /// Output format: text lines and a summary, or one JSON object per window.
    #[arg(long, value_enum, default_value_t = LogFormat::Text)]
    pub format: LogFormat,
}

/// Output format of `monitor`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LogFormat {
    /// One line per window, then a summary.
    Text,
    /// One JSON object per window (JSON lines).
    Jsonl,
}

/// The subcommand of `monitor`.
#[derive(Debug, Subcommand)]
pub enum MonitorCommand {
    /// Choose the alarm thresholds from in-distribution rows and write them into the table.
    Fit(MonitorFitArgs),
}

/// Flags of `monitor fit`.
#[derive(Debug, Args)]
pub struct MonitorFitArgs {
    /// The table (it needs the Bayes head).
    #[arg(long, value_name = "TABLE")]
    pub table: PathBuf,
    /// In-distribution rows (CSV file or NPY directory; labels are not needed), never the
    /// training rows.
    #[arg(long, value_name = "FILE")]
    pub val: PathBuf,
    /// Detections per window.
    #[arg(long, value_name = "W")]
    pub window: u32,
    /// The false-alarm rate on in-distribution windows, in (0, 0.5].
    #[arg(long, value_name = "ALPHA")]
    pub false_alarm: f64,
    /// Resampled windows the quantiles are taken over.
    #[arg(long, default_value_t = 2000, value_name = "R")]
    pub windows: usize,
    /// Seed of the resampling.
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub seed: u64,
    /// The file to write: the table with its monitor section.
    #[arg(long, short, value_name = "FILE")]
    pub output: PathBuf,
}

/// Largest window: a window's counts stay exact in `f32` (2^24).
const MAX_WINDOW: u32 = 1 << 24;

pub fn run(args: &MonitorArgs) -> Result<()> {
    match (&args.fit, &args.table, &args.input) {
        (Some(MonitorCommand::Fit(f)), _, _) => fit(f),
        (None, Some(table), Some(input)) => replay(args, table, input),
        _ => Err(CliError::Input(
            "monitor needs --table and --input (or `monitor fit`)".into(),
        )),
    }
}

fn check_window(w: u32) -> Result<()> {
    if !(1..=MAX_WINDOW).contains(&w) {
        return Err(CliError::Input(format!(
            "--window {w} is out of range: 1 to {MAX_WINDOW} detections"
        )));
    }
    Ok(())
}

fn fit(args: &MonitorFitArgs) -> Result<()> {
    output::check_outputs(&args.output, &[&args.table, &args.val])?;
    check_window(args.window)?;
    if !(args.false_alarm > 0.0 && args.false_alarm <= 0.5) {
        return Err(CliError::Input(format!(
            "--false-alarm {} is out of range: (0, 0.5]",
            args.false_alarm
        )));
    }
    if !(100..=1_000_000).contains(&args.windows) {
        return Err(CliError::Input(format!(
            "--windows {} is out of range: 100 to 1000000",
            args.windows
        )));
    }
    let (table, bytes) = read_table(&args.table)?;
    let no_thresholds = MonitorParams {
        window: args.window,
        alpha: 0.0,
        thresholds: Thresholds::NONE,
    };
    let draft = section_file(&args.table, &bytes, &table, &no_thresholds)?;
    let spec = spec_of(&args.table, &draft, &table)?;
    let val = Loaded::read(&args.val)?;
    check_classes(&args.val, &val.classes, table.class_names())?;
    let (x, os) = (val.logits_f32(), val.objectness_f32());
    let fitted = fit_thresholds(&spec, &x, &os, args.false_alarm, args.windows, args.seed)
        .map_err(|(i, e)| {
            let at = val.locations.get(i).copied();
            CliError::Input(match at {
                Some(loc) => format!("{}: {e}", data::at(&args.val, loc)),
                None => format!("{}: {e}", args.val.display()),
            })
        })?;
    let params = MonitorParams {
        window: args.window,
        alpha: args.false_alarm as f32,
        thresholds: fitted.thresholds,
    };
    let out = section_file(&args.table, &bytes, &table, &params)?;
    // What is written reads back with the device's checks.
    spec_of(&args.output, &out, &table)?;
    output::write_bytes_atomic(&args.output, &out)?;
    let t = fitted.thresholds;
    let mut text = format!(
        "wrote {}: monitor section for windows of {} detections, fitted on {} resampled \
         windows of {} rows of {}\n",
        args.output.display(),
        args.window,
        fitted.windows.len(),
        val.len(),
        args.val.display()
    );
    let _ = writeln!(
        text,
        "thresholds: psi_max > {}, oos_rate > {}{}",
        t.psi,
        t.oos,
        if spec.has_q() {
            format!(", q_mean < {}", t.q)
        } else {
            String::new()
        }
    );
    let _ = writeln!(
        text,
        "each at level {:.6}; share of the resampled windows with an alarm: {:.4} (alpha {})",
        fitted.level, fitted.alarm_rate, args.false_alarm
    );
    output::print(&text)
}

/// The file with a monitor section for `params`.
fn section_file(
    path: &std::path::Path,
    bytes: &[u8],
    table: &DynTable,
    params: &MonitorParams,
) -> Result<Vec<u8>> {
    with_monitor(bytes, table, params).map_err(|e| CliError::input(path, e))
}

fn spec_of<'a>(
    path: &std::path::Path,
    bytes: &'a [u8],
    table: &'a DynTable,
) -> Result<MonitorSpec<'a>> {
    MonitorSpec::from_bytes(bytes, &table.view()).map_err(|e| CliError::input(path, e))
}

fn replay(args: &MonitorArgs, table_path: &std::path::Path, input: &std::path::Path) -> Result<()> {
    let (table, bytes) = read_table(table_path)?;
    if table.bayes_head().is_none() {
        return Err(CliError::input(
            table_path,
            "the table has no Bayes head, which the monitor bins on (DESIGN §7)",
        ));
    }
    let file = if has_monitor(&bytes) {
        let spec = spec_of(table_path, &bytes, &table)?;
        let w = spec.params().window;
        if let Some(given) = args.window.filter(|&g| g != w) {
            return Err(CliError::input(
                table_path,
                format!(
                    "its monitor thresholds are for windows of {w} detections, not {given}: \
                     leave out --window, or fit the thresholds for {given} with `monitor fit`"
                ),
            ));
        }
        bytes.clone()
    } else {
        let Some(w) = args.window else {
            return Err(CliError::input(
                table_path,
                "has no monitor section (`mlmap monitor fit`): give --window",
            ));
        };
        check_window(w)?;
        let params = MonitorParams {
            window: w,
            alpha: 0.0,
            thresholds: Thresholds::NONE,
        };
        section_file(table_path, &bytes, &table, &params)?
    };
    let spec = spec_of(table_path, &file, &table)?;
    let fitted = has_monitor(&bytes);
    let src = data::open(input)?;
    check_classes(input, src.classes(), table.class_names())?;
    let names: Vec<&str> = table.class_names().collect();
    let mut mon = DynMonitor::new(&spec);
    let mut out = String::new();
    let mut tally = Tally::default();
    let mut x = vec![0.0f32; names.len()];
    src.for_each_row(|row| -> Result<()> {
        for (d, &s) in x.iter_mut().zip(row.logits) {
            *d = s as f32;
        }
        let report = mon
            .push(&spec, &x, row.objectness as f32)
            .map_err(|e| CliError::Input(format!("{}: {e}", data::at(input, row.location()))))?;
        if let Some((s, psi)) = report {
            line(&mut out, args.format, &s, &psi, &names);
            tally.add(&s);
        }
        Ok(())
    })?;
    if let Some((s, psi)) = mon.finish(&spec) {
        line(&mut out, args.format, &s, &psi, &names);
        tally.add(&s);
    }
    if args.format == LogFormat::Text {
        summary(&mut out, &tally, &spec, fitted);
    }
    output::print(&out)
}

#[derive(Default)]
struct Tally {
    windows: u32,
    rows: u64,
    alarms: u32,
    psi: u32,
    oos: u32,
    q: u32,
    first: Option<u32>,
}

impl Tally {
    fn add(&mut self, s: &WindowSummary) {
        self.windows += 1;
        self.rows += u64::from(s.rows);
        let a = s.alarms;
        self.psi += u32::from(a.psi);
        self.oos += u32::from(a.oos);
        self.q += u32::from(a.q);
        if a.any() {
            self.alarms += 1;
            self.first.get_or_insert(s.window);
        }
    }
}

/// An `f32` as the JSON number of its shortest decimal.
fn num(v: f32) -> serde_json::Value {
    v.to_string()
        .parse::<f64>()
        .ok()
        .and_then(serde_json::Number::from_f64)
        .map_or(serde_json::Value::Null, serde_json::Value::Number)
}

fn line(out: &mut String, format: LogFormat, s: &WindowSummary, psi: &[f32], names: &[&str]) {
    let name = names.get(usize::from(s.psi_logit)).copied().unwrap_or("");
    match format {
        LogFormat::Jsonl => {
            let per: serde_json::Map<String, serde_json::Value> = names
                .iter()
                .zip(psi)
                .map(|(n, &p)| ((*n).to_string(), num(p)))
                .collect();
            let v = serde_json::json!({
                "window": s.window,
                "rows": s.rows,
                "alarm": s.alarms.any(),
                "psi_max": num(s.psi_max),
                "psi_logit": name,
                "oos_rate": num(s.oos_rate),
                "q_mean": s.q_mean.map(num),
                "psi": per,
                "alarms": {"psi": s.alarms.psi, "oos": s.alarms.oos, "q": s.alarms.q},
            });
            let _ = writeln!(out, "{v}");
        }
        LogFormat::Text => {
            let q = s
                .q_mean
                .map_or_else(|| "-".to_string(), |q| format!("{q:.4}"));
            let mut alarms: Vec<&str> = Vec::new();
            if s.alarms.psi {
                alarms.push("psi");
            }
            if s.alarms.oos {
                alarms.push("oos");
            }
            if s.alarms.q {
                alarms.push("q");
            }
            let _ = writeln!(
                out,
                "window {:>5}  rows {:>6}  psi_max {:>9.5} ({name})  oos_rate {:.4}  q_mean {q}  alarm {}",
                s.window,
                s.rows,
                s.psi_max,
                s.oos_rate,
                if alarms.is_empty() {
                    "-".to_string()
                } else {
                    alarms.join(",")
                }
            );
        }
    }
}

fn summary(out: &mut String, t: &Tally, spec: &MonitorSpec<'_>, fitted: bool) {
    let p = spec.params();
    let _ = writeln!(
        out,
        "{} windows ({} rows), {} with an alarm (psi {}, oos {}, q {}){}",
        t.windows,
        t.rows,
        t.alarms,
        t.psi,
        t.oos,
        t.q,
        t.first
            .map_or_else(String::new, |w| format!("; first alarm in window {w}"))
    );
    if fitted {
        let _ = writeln!(
            out,
            "thresholds of the table: windows of {} detections, false-alarm rate {}",
            p.window, p.alpha
        );
    } else {
        let _ = writeln!(
            out,
            "no thresholds: the table has no monitor section (`mlmap monitor fit`), so no window alarms"
        );
    }
}
